/*
 * i2c.h - the bit-banged I2C master on port 4 (docs/design.md §3.6): SDA = P4.7, SCL = P4.6, open drain
 * through the DDR (pull = DDR bit 1 with DR = 0, release = DDR bit 0; the on-chip pull-ups
 * take a released line high).
 */
#ifndef I2C_H
#define I2C_H

#include "h8.h"

/* Most ACK polls after a page write before the save gives up (a poll and the pause after it
 * take about 250 us: 200 are 50 ms, ten times the 24LC256's 5 ms write cycle). */
#define I2C_MAX_POLLS 200

/* Releases both lines, clocks SCL until a slave holding SDA lets go (at most 9 clocks), and
 * sends a STOP. Returns 0, or 1 when SDA stays low. */
u8 i2c_bus_clear(void);
/* A page write: START, control (W), address, n (1..64) bytes from src, STOP.
 * Returns 0 on ACKs throughout, 1 on a NACK (the transfer ends with a STOP). */
u8 i2c_write(u8 chip, u16 addr, const u8 *src, u8 n);
/* ACK polling (DS21203 Figure 7-1) until the chip answers or I2C_MAX_POLLS. Returns the
 * number of polls, or 0 on a time-out. */
u16 i2c_ack_poll(u8 chip);
/* A random read of n bytes at addr into dst. Returns 0, or 1 on a NACK. */
u8 i2c_read(u8 chip, u16 addr, u8 *dst, u16 n);

#endif
