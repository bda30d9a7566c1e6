/*
 * console.h - a tiny console for the differential test programs.
 *
 * On the H8/3052F target the bytes go out through SCI1, polled exactly as on
 * the real chip (wait for SSR.TDRE = 1, write TDR, clear TDRE). On the host the
 * same API writes to stdout. Everything above the single byte output is shared
 * code, so host and target print the same text for the same values.
 *
 * Number formatting uses no division (powers of ten are subtracted), so the
 * console works even if the 32-bit divide helpers were broken, and a failing
 * program shows which values differ instead of printing garbage.
 *
 * Every byte written is folded into a running CRC-32 (IEEE 802.3, reflected,
 * polynomial 0xEDB88320); con_checksum_line() prints it.
 */
#ifndef CONSOLE_H
#define CONSOLE_H

#include "h8types.h"

/* Initialise SCI1 (8N1, 38400 bit/s at 25 MHz) for transmission. */
void con_init(void);
/* Write one byte. */
void con_putchar(u8 c);
/* Write a NUL-terminated string (no newline added). */
void con_puts(const char *s);
/* Write a newline. */
void con_nl(void);

/* Decimal, no padding, '-' for negative values. */
void con_dec_u8(u8 v);
void con_dec_i8(i8 v);
void con_dec_u16(u16 v);
void con_dec_i16(i16 v);
void con_dec_u32(u32 v);
void con_dec_i32(i32 v);

/* Hexadecimal, fixed width (2, 4 or 8 digits), upper case, no prefix.
 * Signed values print their two's-complement bits: con_hex16((u16)-1) -> FFFF. */
void con_hex8(u8 v);
void con_hex16(u16 v);
void con_hex32(u32 v);

/* "label=" followed by the value and a newline. */
void con_kv_i32(const char *label, i32 v);
void con_kv_u32(const char *label, u32 v);
void con_kv_hex32(const char *label, u32 v);

/* CRC-32 of every byte written so far. */
u32 con_crc(void);
/* Print "checksum XXXXXXXX\n" with the CRC-32 of everything written before it. */
void con_checksum_line(void);

#endif
