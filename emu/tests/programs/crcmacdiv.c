/*
 * crcmacdiv.c - the core-speed benchmark's workload (emu/benches/core_speed.rs):
 * three compute kernels with no I/O, repeated for ROUNDS rounds, then the
 * results printed.
 *
 *   CRC-32   bitwise, reflected (polynomial H'EDB88320), over a 256-byte
 *            buffer that changes every round: 32-bit shifts, AND, NEG, XOR,
 *            a counted inner loop.
 *   Q15 MAC  y_j = sum_i w_ij * x_i for 4 outputs of 64 Q15 weights times Q7
 *            inputs, exact in 32 bits: the firmware learner's MULXS.W
 *            multiply-accumulate loop (firmware/learner.c, learner_forward).
 *   DIVXS.W  q = (a * 32767) / d with |a| < |d|, so the quotient fits in 16
 *            bits: the learner's normalising division, through inline
 *            assembly as firmware/learner.c's divxs_w (host: C's / and %).
 *
 * The console is set up only after the rounds, so the benchmark's window (the
 * first states after reset) runs compute only: no I/O register is touched
 * before the results are printed. Each round's three results are folded into
 * hashes; the crc, the outputs of the last round and the hashes are printed.
 */
#include "testlib.h"

#define ROUNDS 48
#define CRC_BYTES 256
#define N_IN 64
#define N_OUT 4
#define N_DIV 96

static u8 crc_buf[CRC_BYTES];
static i16 weights[N_OUT * N_IN];
static i8 inputs[N_IN];
static i32 y_out[N_OUT];
static i16 div_a[N_DIV];
static i16 div_d[N_DIV];

static NOINLINE u32 crc32_update(u32 crc, const u8 *p, int n)
{
    int i, k;
    crc = ~crc;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        for (k = 0; k < 8; k++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

/* The learner's loop shape: pointers walked with post-increment, counted
 * do-while loops, MULXS.W products summed in 32 bits. */
static NOINLINE void mac_forward(void)
{
    const i16 *w = weights;
    i32 *y = y_out;
    int j = N_OUT;
    do {
        const i8 *x = inputs;
        int n = N_IN;
        i32 acc = 0;
        do {
            i16 a = *w++;
            i16 b = *x++;
            acc += (i32)a * b;
        } while (--n);
        *y++ = acc;
    } while (--j);
}

/* DIVXS.W Rs,ERd: the remainder (high word) and the quotient (low word). */
static __inline__ u32 divxs_w(i32 num, i16 den)
{
#ifdef __H8300H__
    __asm__("divxs.w %1,%0" : "+r"(num) : "r"(den));
    return (u32)num;
#else
    i16 q = (i16)(num / den);
    i16 rem = (i16)(num % den);
    return ((u32)(u16)rem << 16) | (u16)q;
#endif
}

static NOINLINE u32 div_all(u32 h)
{
    int i;
    for (i = 0; i < N_DIV; i++) {
        h = fold(h, divxs_w((i32)div_a[i] * 32767, div_d[i]));
    }
    return h;
}

int main(void)
{
    int r, i;
    u32 crc = 0u, h_mac = 0u, h_div = 0u;

    rng_seed(0xC0DE5EEDu);
    for (i = 0; i < CRC_BYTES; i++) {
        crc_buf[i] = (u8)rng_next();
    }
    for (i = 0; i < N_OUT * N_IN; i++) {
        weights[i] = (i16)rng_next();
    }
    for (i = 0; i < N_DIV; i++) {
        u32 v = rng_next();
        i16 a = (i16)(v & 0x3FFFu) - 0x2000;
        /* |d| > |a| keeps the quotient within 16 bits; both signs. */
        i16 m = (i16)((a < 0 ? -a : a) + 1 + (i16)((v >> 16) & 0x1FFFu));
        div_a[i] = a;
        div_d[i] = (v & 0x80000000u) ? (i16)-m : m;
    }

    for (r = 0; r < ROUNDS; r++) {
        crc = crc32_update(crc, crc_buf, CRC_BYTES);
        crc_buf[r & (CRC_BYTES - 1)] ^= (u8)crc;
        for (i = 0; i < N_IN; i++) {
            inputs[i] = (i8)(crc_buf[(i + r) & (CRC_BYTES - 1)] ^ (u8)r);
        }
        mac_forward();
        for (i = 0; i < N_OUT; i++) {
            h_mac = fold(h_mac, (u32)y_out[i]);
        }
        h_div = div_all(h_div);
    }

    con_init();
    con_puts("crcmacdiv: CRC-32, Q15 MAC and DIVXS.W kernels\n");
    con_kv_u32("rounds", ROUNDS);
    con_kv_hex32("crc32", crc);
    for (i = 0; i < N_OUT; i++) {
        con_kv_hex32("y", (u32)y_out[i]);
    }
    con_kv_hex32("hash mac", h_mac);
    con_kv_hex32("hash divxs", h_div);
    check(crc32_update(0u, (const u8 *)"123456789", 9) == 0xCBF43926u, "crc32 check value");
    return finish();
}
