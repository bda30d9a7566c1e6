/*
 * learner.c - the learner of docs/design.md §2 in Q15/Q7, written for the H8/300H.
 *
 * Written as an H8 engineer writes it: 16 x 16 -> 32 products from int16_t operands (GCC emits
 * MULXS.W), 32-bit sums, pointers walked with post-increment, counted do-while loops (DEC and
 * BNE), the division of docs/design.md §2.3 as one DIVXS.W (32 / 16), no division in an inner loop.
 * Every data-dependent path is one the Rust cost model (nn_q15's H8 meter) counts.
 */
#include "learner.h"

u16 net_n_in;
u8 net_n_out;
u8 net_history;
u8 net_bias;
i16 net_eta;
i16 net_threshold;
i16 *net_w;
i8 *net_x;
i32 *net_y;
i16 *net_o;
i16 *net_delta;
u8 net_win;
u8 net_started;
i16 net_d_prev;

u32 learner_bytes(u16 n_in, u8 n_out)
{
    u32 n = n_in, m = n_out;
    /* w, delta, y, o, x (x rounded up to a whole word) */
    return 2 * n * m + 2 * n + 4 * m + 2 * m + ((n + 1) & ~1u);
}

u8 *learner_setup(u8 *heap, u16 n_in, u8 n_out)
{
    u16 i;
    net_n_in = n_in;
    net_n_out = n_out;
    net_w = (i16 *)heap;
    heap += 2 * (u32)n_in * n_out;
    net_delta = (i16 *)heap;
    heap += 2 * (u32)n_in;
    net_y = (i32 *)heap;
    heap += 4 * (u32)n_out;
    net_o = (i16 *)heap;
    heap += 2 * (u32)n_out;
    net_x = (i8 *)heap;
    heap += (n_in + 1) & ~1u;
    for (i = 0; i < n_in; i++) {
        net_x[i] = 0;
    }
    for (i = 0; i < n_out; i++) {
        net_o[i] = 0;
    }
    net_win = 0;
    net_started = 0;
    net_d_prev = 0;
    return heap;
}

/* The low 16 bits of v >> 7 (bits 7..22 of v): SHLL.L puts them at bits 8..23, which are
 * the low byte of E and the high byte of R; the E half goes through a scratch register (E
 * has no byte halves) and two byte moves gather them in R. GCC would shift seven times. */
static __inline__ i16 lo16_shr7(i32 v)
{
    i16 t;
    __asm__("shll.l %S0\n\tmov.w %e0,%1\n\tmov.b %t0,%s0\n\tmov.b %s1,%t0"
            : "+r"(v), "=&r"(t)
            :
            : "cc");
    return (i16)v;
}

/* DIVXS.W: ER0 (32 bits) / R1 (16 bits) -> quotient in R0, truncated toward zero. The
 * operands always give a quotient that fits (|y'| < m' <= 32767). */
static __inline__ i16 divxs_w(i32 num, i16 den)
{
    __asm__("divxs.w %1,%0" : "+r"(num) : "r"(den));
    return (i16)num;
}

void learner_forward(void)
{
    const i16 *w = net_w;
    i32 *y = net_y;
    i16 *o = net_o;
    u8 m_out = net_n_out;
    u8 j;
    i32 max;
    u8 win;

    /* y_j = sum_i w_ij x_i, exact in 32 bits (Q22). */
    j = m_out;
    do {
        const i8 *x = net_x;
        u16 n = net_n_in;
        i32 acc = 0;
        do {
            i16 a = *w++;
            i16 b = *x++;
            acc += (i32)a * b;
        } while (--n);
        *y++ = acc;
    } while (--j);

    /* The maximum and the winner, ties to the lowest index. */
    y = net_y;
    max = *y++;
    win = 0;
    for (j = 1; j < m_out; j++) {
        i32 v = *y++;
        if (v > max) {
            max = v;
            win = j;
        }
    }
    net_win = win;

    y = net_y;
    j = m_out;
    if (max < (1L << 22)) {
        /* Below 1.0: O_j = sat16(y_j >> 7). Every y_j <= max < 2^22, so only the bottom can
         * clamp; otherwise bits 7..22 of y_j are O_j, taken as (y << 1) >> 8 (a one-bit
         * shift and byte moves instead of seven shifts). */
        do {
            i32 v = *y++;
            if (v < -(1L << 22)) {
                *o++ = -32768;
            } else {
                *o++ = lo16_shr7(v);
            }
        } while (--j);
    } else {
        /* Eq. 2's division by the largest sum: m' = m >> s in [2^14, 2^15), s = bitlen(m) - 15,
         * which is 8 to 16 here: one byte shift, then s - 8 single shifts. */
        u8 s8 = 0;
        i16 ms;
        max >>= 8;
        while (max >= 32768) {
            max >>= 1;
            s8++;
        }
        ms = (i16)max;
        do {
            i32 v = *y++ >> 8;
            u8 k = s8;
            while (k != 0) {
                v >>= 1;
                k--;
            }
            if (v <= -(i32)ms) {
                *o++ = -32768;
            } else if (v >= ms) {
                /* (m' << 15) / m' = 32768 does not fit a 16-bit quotient. */
                *o++ = 32767;
            } else {
                *o++ = divxs_w(v << 15, ms);
            }
        } while (--j);
    }
}

/* Saturating 16-bit add and subtract: ADD.W/SUB.W, and on overflow (V) the bound the carry
 * points to. MOV.W leaves C alone. (Signed overflow of an add of two negatives carries out;
 * of two positives does not. A subtract overflows with a borrow when a >= 0 > b.) */
static __inline__ i16 sat_add16(i16 a, i16 b)
{
    __asm__("add.w %1,%0\n\tbvc 1f\n\tmov.w #32767,%0\n\tbcc 1f\n\tmov.w #-32768,%0\n1:"
            : "+r"(a)
            : "r"(b)
            : "cc");
    return a;
}

static __inline__ i16 sat_sub16(i16 a, i16 b)
{
    __asm__("sub.w %1,%0\n\tbvc 1f\n\tmov.w #32767,%0\n\tbcs 1f\n\tmov.w #-32768,%0\n1:"
            : "+r"(a)
            : "r"(b)
            : "cc");
    return a;
}

void learner_update(i16 e)
{
    i16 t = net_threshold;
    i16 nt = -t; /* T <= 32767: -T fits */
    i16 seta;
    const i8 *x;
    i16 *d;
    i16 *w;
    u16 n;
    u8 j, win, m_out;

    if (e <= t && e >= nt) {
        return; /* dead zone: weights bit-identical */
    }
    seta = (e > 0) ? net_eta : -net_eta;

    /* delta_i = round_half_away(sigma eta x_i / 2^7): |sigma eta x_i| <= 32767 * 128. */
    x = net_x;
    d = net_delta;
    n = net_n_in;
    do {
        i16 b = *x++;
        i32 p = (i32)seta * b;
        if (p >= 0) {
            *d++ = lo16_shr7(p + 64);
        } else {
            *d++ = -lo16_shr7(64 - p);
        }
    } while (--n);

    /* w_i,win += delta_i; w_i,j -= delta_i for the others; saturating in 16 bits. */
    w = net_w;
    win = net_win;
    m_out = net_n_out;
    j = 0;
    do {
        d = net_delta;
        n = net_n_in;
        if (j == win) {
            do {
                *w = sat_add16(*w, *d++);
                w++;
            } while (--n);
        } else {
            do {
                *w = sat_sub16(*w, *d++);
                w++;
            } while (--n);
        }
    } while (++j < m_out);
}

u8 learner_step(const u8 *p)
{
    i16 dsum = (i16)(p[0] + p[1] + p[2] + p[3]);
    i16 e = 0;
    i8 *x = net_x;
    u8 k, j;
    u8 at;

    if (net_started) {
        e = dsum - net_d_prev;
        learner_update(e);
    }

    /* x(t): the history one block deeper, newest first (4 bytes a block). */
    k = net_history;
    if (k != 0) {
        i8 *dst = x + 4 * (u16)k + 3;
        const i8 *src = dst - 4;
        u16 n = 4 * (u16)k;
        do {
            *dst-- = *src--;
        } while (--n);
    }
    /* The new readings p_k - 128. */
    x[0] = (i8)(p[0] ^ 0x80);
    x[1] = (i8)(p[1] ^ 0x80);
    x[2] = (i8)(p[2] ^ 0x80);
    x[3] = (i8)(p[3] ^ 0x80);
    /* The previous outputs O_j >> 8 (their high bytes), then sat_i8(E >> 3), then the bias. */
    at = 4 + 4 * net_history;
    {
        const i16 *o = net_o;
        i8 *xo = x + at;
        j = net_n_out;
        do {
            *xo++ = (i8)(*o++ >> 8);
        } while (--j);
        {
            i16 e3 = e >> 3;
            if (e3 > 127) {
                e3 = 127;
            } else if (e3 < -128) {
                e3 = -128;
            }
            *xo++ = (i8)e3;
        }
        if (net_bias) {
            *xo = 127;
        }
    }

    learner_forward();
    net_d_prev = dsum;
    net_started = 1;
    return net_win;
}
