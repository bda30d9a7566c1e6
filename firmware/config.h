/*
 * config.h - the configuration block (docs/design.md §8): one image for every setting.
 *
 * 32 bytes at H'000400 in flash, big-endian (the H8's byte order), written by the emulator
 * into the image at load as a production line writes calibration data:
 *
 *   0  magic "H8SW"           4  version (1)        5  outputs M (2..4)
 *   6  history H (0..8)       7  flags: bit 0 bias input, bit 1 random walk (the motors run
 *                                a behaviour drawn from xorshift32, the learner still runs)
 *   8  spare inputs (u16)     10 eta (Q15, 0..32767)   12 threshold T (du, 0..32767)
 *   14 save every S steps (1..65535; 0 = never save)
 *   16 ticks per step K (1..65535)
 *   18 tick counts: ITU0 counts of phi/8 per 10 ms tick, GRA0 + 1 (2..65535)
 *   20 A/D channels of the front, rear, left and right sensors (0..7, distinct, one scan group)
 *   24 weight seed (u32; ORed with 1 for xorshift32)
 *   28 reserved (0)           30 CRC-16/CCITT-FALSE of bytes 0..29
 *
 * At boot the firmware checks the block; absent (no magic) or corrupt (bad CRC) -> the compiled
 * defaults (the arena); a well-formed block with a value the firmware cannot run is rejected:
 * defaults, and cfg_status names the field for the emulator to report.
 */
#ifndef CONFIG_H
#define CONFIG_H

#include "h8.h"

#define CFG_VERSION 1
#define CFG_FLAG_BIAS 0x01
#define CFG_FLAG_RANDOM_WALK 0x02

struct config {
    u8 magic[4];
    u8 version;
    u8 outputs;
    u8 history;
    u8 flags;
    u16 spare;
    i16 eta;
    i16 threshold;
    u16 save_every;
    u16 ticks_per_step;
    u16 tick_counts;
    u8 channels[4];
    u32 seed;
    u16 reserved;
    u16 crc;
};

/* cfg_status after boot. */
#define CFG_OK 0x00          /* the block was used */
#define CFG_ABSENT 0x01      /* no block: compiled defaults */
#define CFG_CORRUPT 0x02     /* bad CRC: compiled defaults */
#define CFG_REJECT 0x10      /* + field code: a value the firmware cannot run; defaults */
#define CFG_R_VERSION 0x10
#define CFG_R_OUTPUTS 0x11
#define CFG_R_HISTORY 0x12
#define CFG_R_FLAGS 0x13
#define CFG_R_INPUTS 0x14    /* N = 4 (1 + H) + M + 1 + bias + spare above 256 */
#define CFG_R_ETA 0x15
#define CFG_R_THRESHOLD 0x16
#define CFG_R_TICKS 0x18
#define CFG_R_TICK_COUNTS 0x19
#define CFG_R_CHANNELS 0x1A
#define CFG_R_RESERVED 0x1B
#define CFG_R_RAM 0x1C       /* the network and the stack do not fit the 8 KB RAM */

extern const struct config config_block; /* at H'000400 (crt0.S) */
extern struct config cfg;                /* the settings in use */
extern u8 cfg_status;

/* Loads cfg from the block or the defaults and sets cfg_status. */
void config_load(void);
/* Falls back to the compiled defaults with this status (a block rejected after loading, e.g.
 * a network too large for the RAM). */
void config_load_defaults(u8 status);
/* The network's input count for cfg. */
u16 config_inputs(const struct config *c);
/* CRC-16/CCITT-FALSE (poly H'1021, init H'FFFF) of n bytes, continuing from crc. */
u16 crc16(u16 crc, const u8 *p, u16 n);

#endif
