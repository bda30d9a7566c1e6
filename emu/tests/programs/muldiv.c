/*
 * muldiv.c - multiply and divide, with negative operands and edge cases.
 *
 * 32 x 32 multiply goes through __mulsi3 (MULXU.W x 3), 32-bit division and
 * modulo through __divsi3/__udivsi3/__modsi3/__umodsi3 (DIVXU.W for divisors
 * below 2^16, a shift-subtract loop above). 16 x 16 -> 32 and 8 x 8 -> 16
 * products compile to MULXS/MULXU directly, unsigned 16- and 8-bit division
 * to DIVXU.W/DIVXU.B. GCC never emits DIVXS (C's signed division by a narrow
 * type can overflow), so the signed hardware divides are reached through
 * inline assembly on the target and computed in C on the host.
 *
 * Each helper result is also checked on the target itself against a
 * shift-and-add multiply and a restoring division written in plain C, which
 * use no helper at all, and against n == q * d + r with |r| < |d|.
 */
#include "testlib.h"

static NOINLINE u32 mul_u32(u32 a, u32 b) { return a * b; }
static NOINLINE i32 mul_i32(i32 a, i32 b) { return (i32)((u32)a * (u32)b); }
static NOINLINE u32 div_u32(u32 a, u32 b) { return a / b; }
static NOINLINE u32 mod_u32(u32 a, u32 b) { return a % b; }
static NOINLINE i32 div_i32(i32 a, i32 b) { return a / b; }
static NOINLINE i32 mod_i32(i32 a, i32 b) { return a % b; }

/* Widening products: MULXS.W / MULXU.W / MULXS.B / MULXU.B. */
static NOINLINE i32 mulw_i16(i16 a, i16 b) { return (i32)a * b; }
static NOINLINE u32 mulw_u16(u16 a, u16 b) { return (u32)a * b; }
static NOINLINE i16 mulw_i8(i8 a, i8 b) { return (i16)(a * b); }
static NOINLINE u16 mulw_u8(u8 a, u8 b) { return (u16)(a * b); }

/* Narrow unsigned division: DIVXU.W / DIVXU.B. */
static NOINLINE u16 div_u16(u16 a, u16 b) { return (u16)(a / b); }
static NOINLINE u16 mod_u16(u16 a, u16 b) { return (u16)(a % b); }
static NOINLINE u8 div_u8(u8 a, u8 b) { return (u8)(a / b); }
static NOINLINE u8 mod_u8(u8 a, u8 b) { return (u8)(a % b); }

/* DIVXS.W Rs,ERd: ERd (32 bits) / Rs (16 bits) -> quotient in Rd (low word),
 * remainder in Ed (high word), both signed; the quotient truncates toward
 * zero and the remainder takes the dividend's sign. Callers keep the
 * quotient within 16 bits (the hardware result is not defined otherwise). */
static NOINLINE u32 hw_divxs_w(i32 dividend, i16 divisor)
{
#ifdef __H8300H__
    i32 r = dividend;
    __asm__("divxs.w %1,%0" : "+r"(r) : "r"(divisor));
    return (u32)r;
#else
    i16 q = (i16)(dividend / divisor);
    i16 rem = (i16)(dividend % divisor);
    return ((u32)(u16)rem << 16) | (u16)q;
#endif
}

/* DIVXS.B Rs,Rd: Rd (16 bits) / Rs (8 bits) -> quotient in RdL, remainder in
 * RdH, both signed. */
static NOINLINE u16 hw_divxs_b(i16 dividend, i8 divisor)
{
#ifdef __H8300H__
    i16 r = dividend;
    __asm__("divxs.b %X1,%0" : "+r"(r) : "r"(divisor));
    return (u16)r;
#else
    i8 q = (i8)(dividend / divisor);
    i8 rem = (i8)(dividend % divisor);
    return (u16)(((u16)(u8)rem << 8) | (u8)q);
#endif
}

/* Reference multiply: shift and add, no helper. */
static NOINLINE u32 ref_mul(u32 a, u32 b)
{
    u32 p = 0;
    while (b != 0u) {
        if (b & 1u) {
            p += a;
        }
        a <<= 1;
        b >>= 1;
    }
    return p;
}

/* Reference unsigned division: restoring, one bit at a time, no helper.
 * Returns the quotient, stores the remainder. */
static NOINLINE u32 ref_divmod(u32 n, u32 d, u32 *rem)
{
    u32 q = 0, r = 0;
    int i;
    for (i = 31; i >= 0; i--) {
        u32 top = r >> 31;
        r = (r << 1) | ((n >> i) & 1u);
        if (top != 0u || r >= d) {
            r -= d;
            q |= 1u << i;
        }
    }
    *rem = r;
    return q;
}

static u32 h_mul32, h_div32, h_mulw, h_div16, h_divxs;

static void test_u32(u32 a, u32 b)
{
    u32 p = mul_u32(a, b);
    check(p == ref_mul(a, b), "mulsi3");
    h_mul32 = fold(h_mul32, p);
    if (b != 0u) {
        u32 r_ref;
        u32 q_ref = ref_divmod(a, b, &r_ref);
        u32 q = div_u32(a, b);
        u32 r = mod_u32(a, b);
        check(q == q_ref, "udivsi3");
        check(r == r_ref, "umodsi3");
        h_div32 = fold(h_div32, q);
        h_div32 = fold(h_div32, r);
    }
}

static void test_i32(i32 a, i32 b)
{
    i32 p = mul_i32(a, b);
    check((u32)p == ref_mul((u32)a, (u32)b), "mulsi3 signed");
    h_mul32 = fold(h_mul32, (u32)p);
    if (b != 0 && !(a == I32_MIN && b == -1)) {
        i32 q = div_i32(a, b);
        i32 r = mod_i32(a, b);
        u32 mag_a = (a < 0) ? 0u - (u32)a : (u32)a;
        u32 mag_b = (b < 0) ? 0u - (u32)b : (u32)b;
        u32 mag_r = (r < 0) ? 0u - (u32)r : (u32)r;
        u32 r_ref;
        u32 q_ref = ref_divmod(mag_a, mag_b, &r_ref);
        if ((a < 0) != (b < 0)) {
            q_ref = 0u - q_ref;
        }
        if (a < 0) {
            r_ref = 0u - r_ref;
        }
        check((u32)q == q_ref, "divsi3");
        check((u32)r == r_ref, "modsi3");
        check((u32)a == ref_mul((u32)q, (u32)b) + (u32)r, "n == q*d + r");
        check(mag_r < mag_b, "|r| < |d|");
        check(r == 0 || ((r < 0) == (a < 0)), "sign of r");
        h_div32 = fold(h_div32, (u32)q);
        h_div32 = fold(h_div32, (u32)r);
    }
}

static void test_narrow(u32 v, u32 w)
{
    i16 a16 = (i16)v, b16 = (i16)w;
    u16 ua16 = (u16)v, ub16 = (u16)w;
    i8 a8 = (i8)v, b8 = (i8)w;
    u8 ua8 = (u8)v, ub8 = (u8)w;

    h_mulw = fold(h_mulw, (u32)mulw_i16(a16, b16));
    h_mulw = fold(h_mulw, mulw_u16(ua16, ub16));
    h_mulw = fold(h_mulw, (u32)mulw_i8(a8, b8));
    h_mulw = fold(h_mulw, mulw_u8(ua8, ub8));
    check(mulw_u16(ua16, ub16) == ref_mul(ua16, ub16), "mulxu.w");
    check((u32)mulw_i16(a16, b16) == ref_mul((u32)(i32)a16, (u32)(i32)b16), "mulxs.w");
    if (ub16 != 0u) {
        h_div16 = fold(h_div16, div_u16(ua16, ub16));
        h_div16 = fold(h_div16, mod_u16(ua16, ub16));
    }
    if (ub8 != 0u) {
        h_div16 = fold(h_div16, div_u8(ua8, ub8));
        h_div16 = fold(h_div16, mod_u8(ua8, ub8));
    }
    /* DIVXS.W with a quotient that fits in 16 bits: dividend = a16 * k + r0
     * with |r0| < |b16|. */
    if (b16 != 0 && b16 != I16_MIN) {
        i32 dividend = (i32)a16 * (i32)((i8)(w >> 8) | 1) / 2;
        i32 q = dividend / b16;
        if (q >= -32767 && q <= 32767) {
            h_divxs = fold(h_divxs, hw_divxs_w(dividend, b16));
        }
    }
    if (b8 != 0 && b8 != I8_MIN) {
        i16 dividend = (i16)((i16)a8 * (i16)((i8)(w >> 16) >> 1));
        i32 q = dividend / b8;
        if (q >= -127 && q <= 127) {
            h_divxs = fold(h_divxs, hw_divxs_b(dividend, b8));
        }
    }
}

static const i32 edge[] = {
    0, 1, -1, 2, -2, 3, -3, 7, -7, 10, -10, 255, -256, 32767, -32768, 65535,
    65536, -65536, 65537, 100000, -100000, 0x12345678, -0x12345678,
    I32_MAX, I32_MIN, I32_MIN + 1, I32_MAX - 1, 0x40000000, -0x40000000,
};
#define N_EDGE (sizeof(edge) / sizeof(edge[0]))

static void show_divxs_w(i32 n, i16 d)
{
    u32 r = hw_divxs_w(n, d);
    con_puts("divxs.w ");
    con_dec_i32(n);
    con_putchar('/');
    con_dec_i16(d);
    con_puts(" q=");
    con_dec_i16((i16)(u16)r);
    con_puts(" r=");
    con_dec_i16((i16)(u16)(r >> 16));
    con_nl();
}

static void show_divxs_b(i16 n, i8 d)
{
    u16 r = hw_divxs_b(n, d);
    con_puts("divxs.b ");
    con_dec_i16(n);
    con_putchar('/');
    con_dec_i8(d);
    con_puts(" q=");
    con_dec_i8((i8)(u8)r);
    con_puts(" r=");
    con_dec_i8((i8)(u8)(r >> 8));
    con_nl();
}

int main(void)
{
    u32 i, j;

    con_init();
    con_puts("muldiv: multiply and divide helpers and instructions\n");

    con_kv_i32("-7*6", mul_i32(-7, 6));
    con_kv_i32("-46341*46341", mul_i32(-46341, 46341));
    con_kv_hex32("0xFFFF*0xFFFF", mul_u32(0xFFFFu, 0xFFFFu));
    con_kv_hex32("0x12345678*0x9ABCDEF0", mul_u32(0x12345678u, 0x9ABCDEF0u));
    con_kv_i32("min*-1", mul_i32(I32_MIN, -1));
    con_kv_i32("-7/2", div_i32(-7, 2));
    con_kv_i32("-7%2", mod_i32(-7, 2));
    con_kv_i32("7/-2", div_i32(7, -2));
    con_kv_i32("7%-2", mod_i32(7, -2));
    con_kv_i32("-7/-2", div_i32(-7, -2));
    con_kv_i32("-7%-2", mod_i32(-7, -2));
    con_kv_i32("min/-2", div_i32(I32_MIN, -2));
    con_kv_i32("min%-2", mod_i32(I32_MIN, -2));
    con_kv_i32("min/65536", div_i32(I32_MIN, 65536));
    con_kv_i32("min%100000", mod_i32(I32_MIN, 100000));
    con_kv_i32("max/-65537", div_i32(I32_MAX, -65537));
    con_kv_u32("0xFFFFFFFF/0xFFFF", div_u32(0xFFFFFFFFu, 0xFFFFu));
    con_kv_u32("0xFFFFFFFF/0x10000", div_u32(0xFFFFFFFFu, 0x10000u));
    con_kv_u32("0xFFFFFFFF/0x80000000", div_u32(0xFFFFFFFFu, 0x80000000u));
    con_kv_u32("0xFFFFFFFF%0x80000001", mod_u32(0xFFFFFFFFu, 0x80000001u));
    con_kv_u32("0xFFFFFFFE/0xFFFFFFFF", div_u32(0xFFFFFFFEu, 0xFFFFFFFFu));
    con_kv_u32("1000000000/3", div_u32(1000000000u, 3u));
    con_kv_i32("i16 -300*-300 (mulxs.w)", mulw_i16(-300, -300));
    con_kv_i32("i16 -32768*-32768 (mulxs.w)", mulw_i16(I16_MIN, I16_MIN));
    con_kv_u32("u16 65535*65535 (mulxu.w)", mulw_u16(65535u, 65535u));
    con_kv_i32("i8 -128*-128 (mulxs.b)", mulw_i8(-128, -128));
    con_kv_i32("i8 -128*127 (mulxs.b)", mulw_i8(-128, 127));
    con_kv_u32("u8 255*255 (mulxu.b)", mulw_u8(255, 255));
    con_kv_u32("u16 65535/7 (divxu.w)", div_u16(65535u, 7u));
    con_kv_u32("u16 65535%7 (divxu.w)", mod_u16(65535u, 7u));
    con_kv_u32("u8 250/3 (divxu.b)", div_u8(250, 3));
    con_kv_u32("u8 250%3 (divxu.b)", mod_u8(250, 3));
    show_divxs_w(-100000, 7);
    show_divxs_w(100000, -7);
    show_divxs_w(-100000, -7);
    show_divxs_w(1048575, 32767);
    show_divxs_w(-32767, 1);
    show_divxs_w(5, -7);
    show_divxs_b(-1000, 9);
    show_divxs_b(1000, -9);
    show_divxs_b(-1000, -9);
    show_divxs_b(-127, 1);
    show_divxs_b(-5, 7);

    for (i = 0; i < N_EDGE; i++) {
        for (j = 0; j < N_EDGE; j++) {
            test_i32(edge[i], edge[j]);
            test_u32((u32)edge[i], (u32)edge[j]);
            test_narrow((u32)edge[i], (u32)edge[j]);
        }
    }
    rng_seed(0xD1B54A32u);
    for (i = 0; i < 200; i++) {
        u32 a = rng_next();
        u32 b = rng_next();
        u32 c = rng_next();
        /* Vary the divisor's size: shift by 0..31 bits. */
        u32 bs = b >> (c & 31u);
        test_u32(a, bs);
        test_i32((i32)a, (i32)bs);
        test_i32((i32)a, -(i32)(bs >> 1));
        test_narrow(a, c);
    }

    con_kv_hex32("hash mul32", h_mul32);
    con_kv_hex32("hash div32", h_div32);
    con_kv_hex32("hash mulx", h_mulw);
    con_kv_hex32("hash divxu", h_div16);
    con_kv_hex32("hash divxs", h_divxs);
    return finish();
}
