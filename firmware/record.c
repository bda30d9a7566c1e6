/*
 * record.c - save and restore the network as A/B records (eeprom/src/persist.rs's format).
 */
#include "record.h"
#include "config.h"
#include "i2c.h"
#include "learner.h"

#define CHIP_A 0x50
#define PAGE_BYTES 64
#define SLOT_ADDR 0x0000
#define BODY_ADDR 0x0040
#define COMMIT_BYTES 14
#define BODY_HEADER_BYTES 6

u32 rec_sequence;
u16 rec_failures;

/* The page being sent (body pages are gathered here from the header, the weights and the
 * CRC) and the commit block. */
static u8 page[PAGE_BYTES];

static void put_u32(u8 *p, u32 v)
{
    p[0] = (u8)(v >> 24);
    p[1] = (u8)(v >> 16);
    p[2] = (u8)(v >> 8);
    p[3] = (u8)v;
}

static u32 get_u32(const u8 *p)
{
    return ((u32)p[0] << 24) | ((u32)p[1] << 16) | ((u32)p[2] << 8) | p[3];
}

static u16 get_u16(const u8 *p)
{
    return (u16)(((u16)p[0] << 8) | p[1]);
}

static u16 payload_bytes(void)
{
    return (u16)(2 * net_n_in * net_n_out);
}

/* Writes one page and waits for its write cycle. */
static u8 write_page(u8 chip, u16 addr, const u8 *src, u8 n)
{
    if (i2c_write(chip, addr, src, n)) {
        return 1;
    }
    return i2c_ack_poll(chip) == 0;
}

u8 record_save(void)
{
    u8 hdr[BODY_HEADER_BYTES];
    u8 crc_be[2];
    u8 chip = (u8)(CHIP_A | (rec_sequence & 1));
    u16 len = payload_bytes();
    u16 crc, total, sent, addr;
    const u8 *w = (const u8 *)net_w;
    u16 at; /* position in the body stream: header, payload, CRC */

    put_u32(hdr, rec_sequence);
    hdr[4] = (u8)(len >> 8);
    hdr[5] = (u8)len;
    crc = crc16(0xFFFF, hdr, BODY_HEADER_BYTES);
    crc = crc16(crc, w, len);
    crc_be[0] = (u8)(crc >> 8);
    crc_be[1] = (u8)crc;

    total = BODY_HEADER_BYTES + len + 2;
    at = 0;
    addr = BODY_ADDR;
    while (at < total) {
        u8 n = 0;
        sent = at;
        while (n < PAGE_BYTES && at < total) {
            u8 b;
            if (at < BODY_HEADER_BYTES) {
                b = hdr[at];
            } else if (at < BODY_HEADER_BYTES + len) {
                b = w[at - BODY_HEADER_BYTES];
            } else {
                b = crc_be[at - BODY_HEADER_BYTES - len];
            }
            page[n++] = b;
            at++;
        }
        if (write_page(chip, (u16)(addr + sent), page, n)) {
            rec_failures++;
            return 1;
        }
    }

    page[0] = 'H';
    page[1] = 'K';
    page[2] = 1;
    page[3] = 0;
    put_u32(page + 4, rec_sequence);
    page[8] = (u8)(len >> 8);
    page[9] = (u8)len;
    page[10] = crc_be[0];
    page[11] = crc_be[1];
    crc = crc16(0xFFFF, page, 12);
    page[12] = (u8)(crc >> 8);
    page[13] = (u8)crc;
    if (write_page(chip, SLOT_ADDR, page, COMMIT_BYTES)) {
        rec_failures++;
        return 1;
    }
    rec_sequence++;
    return 0;
}

/* A commit block read from a chip and checked. */
struct commit {
    u8 ok;
    u32 sequence;
    u16 len;
    u16 body_crc;
};

static void read_commit(u8 chip, struct commit *c)
{
    u8 *b = page;
    c->ok = 0;
    if (i2c_read(chip, SLOT_ADDR, b, COMMIT_BYTES)) {
        return;
    }
    if (b[0] != 'H' || b[1] != 'K') {
        return;
    }
    if (crc16(0xFFFF, b, 12) != get_u16(b + 12)) {
        return;
    }
    if (b[2] != 1 || b[3] != 0) {
        return;
    }
    c->sequence = get_u32(b + 4);
    c->len = get_u16(b + 8);
    c->body_crc = get_u16(b + 10);
    /* Longer than this network's weights: not a record of ours. The chip's parity. */
    if (c->len > payload_bytes() || (u8)(CHIP_A | (c->sequence & 1)) != chip) {
        return;
    }
    c->ok = 1;
}

/* Reads the body c describes: header into hdr, payload into the weights, then the CRC.
 * Returns 1 when it checks out. */
static u8 read_body(u8 chip, const struct commit *c)
{
    u8 *hdr = page;
    u8 *crc_be = page + BODY_HEADER_BYTES;
    u16 crc;
    if (i2c_read(chip, BODY_ADDR, hdr, BODY_HEADER_BYTES) ||
        i2c_read(chip, BODY_ADDR + BODY_HEADER_BYTES, (u8 *)net_w, c->len) ||
        i2c_read(chip, (u16)(BODY_ADDR + BODY_HEADER_BYTES + c->len), crc_be, 2)) {
        return 0;
    }
    crc = crc16(0xFFFF, hdr, BODY_HEADER_BYTES);
    crc = crc16(crc, (const u8 *)net_w, c->len);
    return crc == get_u16(crc_be) && get_u32(hdr) == c->sequence && get_u16(hdr + 4) == c->len &&
           crc == c->body_crc;
}

u8 record_restore(void)
{
    struct commit c[2];
    u8 first, k, found = 0;
    u32 seq = 0;
    u16 len = 0;

    read_commit(CHIP_A, &c[0]);
    read_commit(CHIP_A + 1, &c[1]);
    /* Newest first, in serial-number arithmetic. */
    first = (c[0].ok && c[1].ok && c[1].sequence != c[0].sequence &&
             c[1].sequence - c[0].sequence < 0x80000000u)
                ? 1
                : 0;
    for (k = 0; k < 2 && !found; k++) {
        u8 i = first ^ k;
        if (c[i].ok && read_body((u8)(CHIP_A + i), &c[i])) {
            found = 1;
            seq = c[i].sequence;
            len = c[i].len;
        }
    }
    rec_sequence = found ? seq + 1 : 0;
    return found && len == payload_bytes();
}
