/*
 * q15learn.c - the fixed-point learner step of docs/design.md §2.3-2.4 on a toy world.
 *
 * N = 13 Q7 inputs (4 proximities - 128, the same 4 from the previous step,
 * the 4 previous outputs >> 8, sat_i8(E(t-1) >> 3)), M = 4 outputs with Q15
 * weights, eta = 0.1 (3277 in Q15), T = 10 du:
 *   y_j = sum_i w_ij * x_i            (Q22, exact, a MULXS.W multiply-accumulate)
 *   m = max_j y_j; if m < 2^22: O_j = sat16(y_j >> 7)
 *   else s = bitlen(m) - 15, m' = m >> s, y'_j = y_j >> s,
 *        O_j = -32768 if y'_j <= -m', else min(32767, (y'_j * 2^15) / m')
 *   win = argmax_j y_j (ties to the lowest index)
 *   if |E| > T: delta_i = round_half_away(eta * x_i / 2^7),
 *        w_i,win += sign(E) * delta_i, w_i,j -= sign(E) * delta_i (saturating)
 * The toy world moves four proximity readings (0..255 du) by the chosen
 * behaviour plus pseudo-random noise (a reading that comes too close jumps
 * back to far away); E(t) = D(t+1) - D(t) with D the sum.
 * Printed: a few steps in full, then the final weights and hashes.
 */
#include "testlib.h"

#define N_IN 13
#define N_OUT 4
#define K_PROX 4
#define ETA_Q15 3277 /* 0.1 in Q15 (docs/design.md §2.1) */
#define THRESHOLD_DU 10 /* T (docs/design.md §2.1) */
#define STEPS 160

static i16 weights[N_OUT][N_IN];
static i8 x_in[N_IN];
static i32 y_sum[N_OUT];
static i16 o_out[N_OUT];
static u8 prox[K_PROX];
static u8 prox_prev[K_PROX];

static i16 sat16(i32 v)
{
    if (v > I16_MAX) {
        return I16_MAX;
    }
    if (v < I16_MIN) {
        return I16_MIN;
    }
    return (i16)v;
}

static i8 sat8(i32 v)
{
    if (v > I8_MAX) {
        return I8_MAX;
    }
    if (v < I8_MIN) {
        return I8_MIN;
    }
    return (i8)v;
}

static int bitlen(u32 v)
{
    int n = 0;
    while (v != 0u) {
        v >>= 1;
        n++;
    }
    return n;
}

/* The multiply-accumulate loop: Q15 x Q7 -> Q22, summed exactly in 32 bits. */
static NOINLINE i32 mac(const i16 *w, const i8 *x, int n)
{
    i32 acc = 0;
    int i;
    for (i = 0; i < n; i++) {
        acc += (i32)w[i] * x[i];
    }
    return acc;
}

static NOINLINE int forward(void)
{
    int j, win = 0;
    i32 m;
    for (j = 0; j < N_OUT; j++) {
        y_sum[j] = mac(weights[j], x_in, N_IN);
    }
    m = y_sum[0];
    for (j = 1; j < N_OUT; j++) {
        if (y_sum[j] > m) {
            m = y_sum[j];
            win = j;
        }
    }
    if (m < (1 << 22)) {
        for (j = 0; j < N_OUT; j++) {
            o_out[j] = sat16(y_sum[j] >> 7);
        }
    } else {
        int s = bitlen((u32)m) - 15;
        i32 m_s = m >> s;
        for (j = 0; j < N_OUT; j++) {
            i32 y_s = y_sum[j] >> s;
            if (y_s <= -m_s) {
                o_out[j] = I16_MIN;
            } else {
                i32 q = (y_s * 32768) / m_s;
                o_out[j] = (i16)((q > I16_MAX) ? I16_MAX : q);
            }
        }
    }
    return win;
}

static i16 round_delta(i32 eta, i8 x)
{
    i32 p = eta * x;
    if (p >= 0) {
        return (i16)((p + 64) >> 7);
    }
    return (i16)(-((-p + 64) >> 7));
}

static NOINLINE u32 update(int win, i32 e)
{
    int i, j;
    i32 sigma;
    u32 changed = 0;
    if (e <= THRESHOLD_DU && e >= -THRESHOLD_DU) {
        return 0u;
    }
    sigma = (e > 0) ? 1 : -1;
    for (i = 0; i < N_IN; i++) {
        i32 d = sigma * round_delta(ETA_Q15, x_in[i]);
        for (j = 0; j < N_OUT; j++) {
            i16 before = weights[j][i];
            weights[j][i] = sat16((j == win) ? before + d : before - d);
            changed += (weights[j][i] != before);
        }
    }
    return changed;
}

static u32 prox_sum(void)
{
    u32 d = 0;
    int k;
    for (k = 0; k < K_PROX; k++) {
        d += prox[k];
    }
    return d;
}

/* Behaviour effect on each of the four sensors (front, back, left, right):
 * 0 forward, 1 backward, 2 turn-left-forward, 3 turn-right-forward. */
static const i8 effect[N_OUT][K_PROX] = {
    { -18, 12, -2, -2 },
    { 12, -18, -2, -2 },
    { -8, 6, 10, -14 },
    { -8, 6, -14, 10 },
};

static void world_step(int behaviour)
{
    int k;
    for (k = 0; k < K_PROX; k++) {
        i32 noise = (i32)(rng_next() % 7u) - 3;
        i32 p = (i32)prox[k] + effect[behaviour][k] + noise;
        prox_prev[k] = prox[k];
        /* Too close: the obstacle is bumped away and reappears far off. */
        prox[k] = (u8)((p < 8) ? 230 : (p > 255) ? 255 : p);
    }
}

static void build_inputs(i32 e_prev)
{
    int k, j;
    for (k = 0; k < K_PROX; k++) {
        x_in[k] = (i8)((i32)prox[k] - 128);
        x_in[K_PROX + k] = (i8)((i32)prox_prev[k] - 128);
    }
    for (j = 0; j < N_OUT; j++) {
        x_in[2 * K_PROX + j] = (i8)(o_out[j] >> 8);
    }
    x_in[2 * K_PROX + N_OUT] = sat8(e_prev >> 3);
}

int main(void)
{
    int i, j, t;
    i32 e = 0;
    u32 h_y = 0, h_o = 0, h_w = 0, changed_total = 0;
    u32 wins[N_OUT] = { 0u, 0u, 0u, 0u };

    con_init();
    con_puts("q15learn: Q15 forward pass and update (docs/design.md §2.3-2.4), 13 inputs, 4 outputs\n");

    rng_seed(0x51A4F00Du);
    for (j = 0; j < N_OUT; j++) {
        for (i = 0; i < N_IN; i++) {
            weights[j][i] = (i16)((i32)(rng_next() & 0x1FFFu) - 0x1000);
        }
    }
    for (i = 0; i < K_PROX; i++) {
        prox[i] = (u8)(60u + (rng_next() & 127u));
        prox_prev[i] = prox[i];
    }
    for (j = 0; j < N_OUT; j++) {
        o_out[j] = 0;
    }

    for (t = 0; t < STEPS; t++) {
        u32 d_before, changed;
        int win;
        build_inputs(e);
        win = forward();
        wins[win]++;
        d_before = prox_sum();
        world_step(win);
        e = (i32)prox_sum() - (i32)d_before;
        changed = update(win, e);
        changed_total += changed;
        for (j = 0; j < N_OUT; j++) {
            h_y = fold(h_y, (u32)y_sum[j]);
            h_o = fold(h_o, (u32)(u16)o_out[j]);
        }
        if (t < 4 || t % 40 == 39) {
            con_puts("t=");
            con_dec_i32(t);
            con_puts(" y=");
            for (j = 0; j < N_OUT; j++) {
                con_dec_i32(y_sum[j]);
                con_putchar(j + 1 < N_OUT ? ',' : ' ');
            }
            con_puts("o=");
            for (j = 0; j < N_OUT; j++) {
                con_dec_i16(o_out[j]);
                con_putchar(j + 1 < N_OUT ? ',' : ' ');
            }
            con_puts("win=");
            con_dec_i32(win);
            con_puts(" e=");
            con_dec_i32(e);
            con_puts(" changed=");
            con_dec_u32(changed);
            con_nl();
        }
    }

    for (j = 0; j < N_OUT; j++) {
        con_puts("w[");
        con_dec_i32(j);
        con_puts("]=");
        for (i = 0; i < N_IN; i++) {
            con_dec_i16(weights[j][i]);
            con_putchar(i + 1 < N_IN ? ',' : '\n');
            h_w = fold(h_w, (u32)(u16)weights[j][i]);
        }
    }
    con_puts("wins=");
    for (j = 0; j < N_OUT; j++) {
        con_dec_u32(wins[j]);
        con_putchar(j + 1 < N_OUT ? ',' : '\n');
    }
    con_kv_u32("weights changed", changed_total);
    con_kv_hex32("hash y", h_y);
    con_kv_hex32("hash o", h_o);
    con_kv_hex32("hash w", h_w);

    /* Fixed checks of the arithmetic. */
    check(round_delta(ETA_Q15, 127) == 3251, "delta(127)");
    check(round_delta(ETA_Q15, -128) == -3277, "delta(-128)");
    check(round_delta(ETA_Q15, 1) == 26, "delta(1)");
    check(round_delta(ETA_Q15, -1) == -26, "delta(-1)");
    check(sat16(40000) == I16_MAX && sat16(-40000) == I16_MIN, "sat16");
    check(bitlen(1u << 22) == 23, "bitlen");
    return finish();
}
