/*
 * console.c - see console.h.
 */
#include "console.h"

#ifdef __H8300H__

/* SCI1 registers (H8/3052F hardware manual, section 13 "Serial Communication
 * Interface"; addresses as in docs/design.md §4.1: SCI1 at H'FFFFB8-H'FFFFBD). */
#define SCI1_SMR (*(volatile u8 *)0xFFFFB8) /* serial mode register */
#define SCI1_BRR (*(volatile u8 *)0xFFFFB9) /* bit rate register */
#define SCI1_SCR (*(volatile u8 *)0xFFFFBA) /* serial control register */
#define SCI1_TDR (*(volatile u8 *)0xFFFFBB) /* transmit data register */
#define SCI1_SSR (*(volatile u8 *)0xFFFFBC) /* serial status register */

/* SMR = 0: asynchronous, 8 data bits, no parity, 1 stop bit, clock = phi. */
#define SMR_ASYNC_8N1_PHI 0x00
/* BRR = phi / (32 * 2^(2n) * B) - 1 with n = 0, phi = 25 MHz, B = 38400 bit/s:
 * 25e6 / 1228800 - 1 = 19.3 -> 19 (error +1.7 %), from the manual's BRR formula. */
#define BRR_38400_AT_25MHZ 19
/* SCR bit 5: TE, transmit enable. */
#define SCR_TE 0x20
/* SSR bit 7: TDRE, transmit data register empty. */
#define SSR_TDRE 0x80

/* The manual asks for at least one bit period (26 us = 651 states at 38400
 * bit/s and 25 MHz) between writing BRR and enabling TE. Each pass of the
 * loop below costs well over 2 states, so 400 passes are plenty. */
#define BIT_PERIOD_WAIT_LOOPS 400

static void hw_init(void)
{
    volatile u16 i;
    SCI1_SCR = 0x00;              /* TE = RE = 0 while configuring */
    SCI1_SMR = SMR_ASYNC_8N1_PHI;
    SCI1_BRR = BRR_38400_AT_25MHZ;
    for (i = 0; i < BIT_PERIOD_WAIT_LOOPS; i++) {
    }
    SCI1_SCR = SCR_TE;
}

static void hw_putchar(u8 c)
{
    while ((SCI1_SSR & SSR_TDRE) == 0) {
    }
    SCI1_TDR = c;
    /* Writing 0 to TDRE clears it; writing 1 to the other flags leaves them. */
    SCI1_SSR = (u8)(SCI1_SSR & (u8)~SSR_TDRE);
}

#else /* host */

#include <stdio.h>

static void hw_init(void)
{
}

static void hw_putchar(u8 c)
{
    putchar(c);
}

#endif

/* CRC-32 (IEEE), reflected, polynomial 0xEDB88320, initial value and final
 * XOR 0xFFFFFFFF. Computed bit by bit: no table, shifts and XOR only. */
#define CRC32_POLY_REFLECTED 0xEDB88320u

static u32 crc_state = 0xFFFFFFFFu;

void con_init(void)
{
    crc_state = 0xFFFFFFFFu;
    hw_init();
}

void con_putchar(u8 c)
{
    u32 crc = crc_state ^ c;
    int bit;
    for (bit = 0; bit < 8; bit++) {
        if (crc & 1u) {
            crc = (crc >> 1) ^ CRC32_POLY_REFLECTED;
        } else {
            crc >>= 1;
        }
    }
    crc_state = crc;
    hw_putchar(c);
}

void con_puts(const char *s)
{
    while (*s != '\0') {
        con_putchar((u8)*s);
        s++;
    }
}

void con_nl(void)
{
    con_putchar('\n');
}

/* Powers of ten for division-free decimal conversion. */
static const u32 pow10_table[10] = {
    1000000000u, 100000000u, 10000000u, 1000000u, 100000u,
    10000u, 1000u, 100u, 10u, 1u,
};

void con_dec_u32(u32 v)
{
    int i;
    int started = 0;
    for (i = 0; i < 10; i++) {
        u8 digit = 0;
        while (v >= pow10_table[i]) {
            v -= pow10_table[i];
            digit++;
        }
        if (digit != 0 || started || i == 9) {
            con_putchar((u8)('0' + digit));
            started = 1;
        }
    }
}

void con_dec_i32(i32 v)
{
    if (v < 0) {
        con_putchar('-');
        /* 0 - (u32)v is the magnitude, also for I32_MIN. */
        con_dec_u32(0u - (u32)v);
    } else {
        con_dec_u32((u32)v);
    }
}

void con_dec_u8(u8 v)
{
    con_dec_u32(v);
}

void con_dec_i8(i8 v)
{
    con_dec_i32(v);
}

void con_dec_u16(u16 v)
{
    con_dec_u32(v);
}

void con_dec_i16(i16 v)
{
    con_dec_i32(v);
}

static const char hex_digits[16] = {
    '0', '1', '2', '3', '4', '5', '6', '7',
    '8', '9', 'A', 'B', 'C', 'D', 'E', 'F',
};

static void hex_n(u32 v, int digits)
{
    int shift;
    for (shift = (digits - 1) * 4; shift >= 0; shift -= 4) {
        con_putchar((u8)hex_digits[(v >> shift) & 0xFu]);
    }
}

void con_hex8(u8 v)
{
    hex_n(v, 2);
}

void con_hex16(u16 v)
{
    hex_n(v, 4);
}

void con_hex32(u32 v)
{
    hex_n(v, 8);
}

void con_kv_i32(const char *label, i32 v)
{
    con_puts(label);
    con_putchar('=');
    con_dec_i32(v);
    con_nl();
}

void con_kv_u32(const char *label, u32 v)
{
    con_puts(label);
    con_putchar('=');
    con_dec_u32(v);
    con_nl();
}

void con_kv_hex32(const char *label, u32 v)
{
    con_puts(label);
    con_putchar('=');
    con_hex32(v);
    con_nl();
}

u32 con_crc(void)
{
    return crc_state ^ 0xFFFFFFFFu;
}

void con_checksum_line(void)
{
    u32 crc = con_crc();
    con_puts("checksum ");
    con_hex32(crc);
    con_nl();
}
