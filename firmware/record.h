/*
 * record.h - the A/B persistence record on the two 24LC256 (docs/design.md §3.6), the format of the
 * Rust crate eeprom (eeprom/src/persist.rs):
 *
 *   commit page at H'0000 (14 bytes): 'H' 'K', version 1, 0, sequence (u32), payload length
 *     (u16), body CRC (u16), CRC of bytes 0..11 (u16), all big-endian;
 *   body from H'0040: sequence (u32), length (u16), payload, CRC of the 6 + length bytes.
 *
 * Record n goes to chip 0x50 when n is even and 0x51 when odd; a save writes the body pages
 * in address order, ACK-polling each write cycle, and the commit page last. The payload is
 * the weight matrix as the H8 holds it: row by row, big-endian i16.
 */
#ifndef RECORD_H
#define RECORD_H

#include "h8.h"

extern u32 rec_sequence;  /* the sequence number the next save uses */
extern u16 rec_failures;  /* saves that failed on the bus (NACK or poll time-out) */

/* Writes the weights as the next record. Returns 0, or 1 when the bus failed. */
u8 record_save(void);
/* Loads the newest valid record into the weights. Returns 1 when one of this network's size
 * was restored, 0 otherwise (the caller draws fresh weights); sets rec_sequence either way. */
u8 record_restore(void);

#endif
