/*
 * config.c - the configuration block: defaults, checks, CRC-16.
 */
#include "config.h"
#include "learner.h"

struct config cfg;
u8 cfg_status;

/* The compiled defaults: the arena (paper env. 2; docs/design.md §5): four behaviours, history 1, no
 * bias, eta 0.001 (33), T 10, a record every 20 steps, 0.45 s = 45 ticks of 10 ms at
 * phi = 25 MHz (31 250 counts of phi/8), sensors on AN0-AN3, seed 1. */
static const struct config defaults = {
    {'H', '8', 'S', 'W'}, CFG_VERSION, 4, 1, 0, 0, 33, 10, 20, 45, 31250, {0, 1, 2, 3}, 1, 0, 0};

u16 crc16(u16 crc, const u8 *p, u16 n)
{
    while (n != 0) {
        u8 b;
        crc ^= (u16)*p++ << 8;
        b = 8;
        do {
            if (crc & 0x8000) {
                crc = (crc << 1) ^ 0x1021;
            } else {
                crc <<= 1;
            }
        } while (--b);
        n--;
    }
    return crc;
}

u16 config_inputs(const struct config *c)
{
    return 4 * (1 + (u16)c->history) + c->outputs + 1 + (c->flags & CFG_FLAG_BIAS) + c->spare;
}

/* The first field of c the firmware cannot run, as a CFG_R_ code, or CFG_OK. */
static u8 check(const struct config *c)
{
    u8 k, group;
    if (c->version != CFG_VERSION) {
        return CFG_R_VERSION;
    }
    if (c->outputs < 2 || c->outputs > 4) {
        return CFG_R_OUTPUTS;
    }
    if (c->history > 8) {
        return CFG_R_HISTORY;
    }
    if (c->flags & ~(CFG_FLAG_BIAS | CFG_FLAG_RANDOM_WALK)) {
        return CFG_R_FLAGS;
    }
    if (c->spare > NET_MAX_INPUTS || config_inputs(c) > NET_MAX_INPUTS) {
        return CFG_R_INPUTS;
    }
    if (c->eta < 0) {
        return CFG_R_ETA;
    }
    if (c->threshold < 0) {
        return CFG_R_THRESHOLD;
    }
    if (c->ticks_per_step == 0) {
        return CFG_R_TICKS;
    }
    if (c->tick_counts < 2) {
        return CFG_R_TICK_COUNTS;
    }
    group = c->channels[0] & 4;
    for (k = 0; k < 4; k++) {
        u8 i;
        if (c->channels[k] > 7 || (c->channels[k] & 4) != group) {
            return CFG_R_CHANNELS;
        }
        for (i = 0; i < k; i++) {
            if (c->channels[i] == c->channels[k]) {
                return CFG_R_CHANNELS;
            }
        }
    }
    if (c->reserved != 0) {
        return CFG_R_RESERVED;
    }
    return CFG_OK;
}

void config_load_defaults(u8 status)
{
    cfg = defaults;
    cfg_status = status;
}

void config_load(void)
{
    const struct config *b = &config_block;
    if (b->magic[0] != 'H' || b->magic[1] != '8' || b->magic[2] != 'S' || b->magic[3] != 'W') {
        cfg = defaults;
        cfg_status = CFG_ABSENT;
        return;
    }
    if (crc16(0xFFFF, (const u8 *)b, 30) != b->crc) {
        cfg = defaults;
        cfg_status = CFG_CORRUPT;
        return;
    }
    cfg_status = check(b);
    cfg = (cfg_status == CFG_OK) ? *b : defaults;
}
