/*
 * shifts.c - variable and constant shifts and rotates at every width.
 *
 * Each H8/300H shift instruction moves one bit, so GCC turns a shift by a
 * run-time count into a loop of SHLL/SHLR/SHAR and a shift by a constant
 * into unrolled sequences, byte and word moves and EXTS/EXTU. Every width (8/16/32), signedness and direction is run for
 * every count 0..width-1. Left shifts are done on unsigned values (shifting a
 * negative signed value left is undefined in C); right shifts of negative
 * signed values are arithmetic in GCC on both host and target.
 */
#include "testlib.h"

static NOINLINE u8 shl_u8(u8 v, int n) { return (u8)(v << n); }
static NOINLINE u8 shr_u8(u8 v, int n) { return (u8)(v >> n); }
static NOINLINE i8 sar_i8(i8 v, int n) { return (i8)(v >> n); }
static NOINLINE i8 shl_i8(i8 v, int n) { return (i8)(u8)((u8)v << n); }
static NOINLINE u16 shl_u16(u16 v, int n) { return (u16)(v << n); }
static NOINLINE u16 shr_u16(u16 v, int n) { return (u16)(v >> n); }
static NOINLINE i16 sar_i16(i16 v, int n) { return (i16)(v >> n); }
static NOINLINE i16 shl_i16(i16 v, int n) { return (i16)(u16)((u16)v << n); }
static NOINLINE u32 shl_u32(u32 v, int n) { return v << n; }
static NOINLINE u32 shr_u32(u32 v, int n) { return v >> n; }
static NOINLINE i32 sar_i32(i32 v, int n) { return v >> n; }
static NOINLINE i32 shl_i32(i32 v, int n) { return (i32)((u32)v << n); }

/* Rotates by a run-time count (n in 1..width-1). */
static NOINLINE u8 rotl_u8(u8 v, int n) { return (u8)((v << n) | (v >> (8 - n))); }
static NOINLINE u16 rotr_u16(u16 v, int n) { return (u16)((v >> n) | (v << (16 - n))); }
static NOINLINE u32 rotl_u32(u32 v, int n) { return (v << n) | (v >> (32 - n)); }

/* Constant shifts: GCC picks special sequences per count (byte/word moves,
 * EXTS/EXTU, rotate-through-carry tricks), so test a spread of them. */
static NOINLINE u32 const_shifts_u32(u32 v)
{
    u32 h = 0;
    h = fold(h, v << 1);
    h = fold(h, v << 2);
    h = fold(h, v << 7);
    h = fold(h, v << 8);
    h = fold(h, v << 15);
    h = fold(h, v << 16);
    h = fold(h, v << 24);
    h = fold(h, v << 31);
    h = fold(h, v >> 1);
    h = fold(h, v >> 3);
    h = fold(h, v >> 8);
    h = fold(h, v >> 16);
    h = fold(h, v >> 17);
    h = fold(h, v >> 24);
    h = fold(h, v >> 31);
    return h;
}

static NOINLINE u32 const_shifts_i32(i32 v)
{
    u32 h = 0;
    h = fold(h, (u32)(v >> 1));
    h = fold(h, (u32)(v >> 5));
    h = fold(h, (u32)(v >> 8));
    h = fold(h, (u32)(v >> 15));
    h = fold(h, (u32)(v >> 16));
    h = fold(h, (u32)(v >> 23));
    h = fold(h, (u32)(v >> 24));
    h = fold(h, (u32)(v >> 30));
    h = fold(h, (u32)(v >> 31));
    return h;
}

static NOINLINE u32 const_shifts_16_8(u16 w, i16 s, u8 b, i8 c)
{
    u32 h = 0;
    h = fold(h, (u16)(w << 3));
    h = fold(h, (u16)(w << 8));
    h = fold(h, (u16)(w << 12));
    h = fold(h, (u16)(w >> 4));
    h = fold(h, (u16)(w >> 8));
    h = fold(h, (u16)(w >> 15));
    h = fold(h, (u32)(i32)(i16)(s >> 2));
    h = fold(h, (u32)(i32)(i16)(s >> 8));
    h = fold(h, (u32)(i32)(i16)(s >> 15));
    h = fold(h, (u8)(b << 1));
    h = fold(h, (u8)(b << 5));
    h = fold(h, (u8)(b >> 3));
    h = fold(h, (u8)(b >> 7));
    h = fold(h, (u32)(i32)(i8)(c >> 1));
    h = fold(h, (u32)(i32)(i8)(c >> 6));
    h = fold(h, (u32)(i32)(i8)(c >> 7));
    return h;
}

/* Leading zeros by a shift loop; bit length as used by the learner. */
static NOINLINE int clz32(u32 v)
{
    int n = 0;
    if (v == 0u) {
        return 32;
    }
    while ((v & 0x80000000u) == 0u) {
        v <<= 1;
        n++;
    }
    return n;
}

static const u32 values[] = {
    0x00000000u, 0x00000001u, 0x80000000u, 0xFFFFFFFFu, 0x12345678u,
    0x87654321u, 0x7FFFFFFFu, 0x0000FF80u, 0x00800080u, 0xA5A5A5A5u,
};
#define N_VALUES (sizeof(values) / sizeof(values[0]))

int main(void)
{
    u32 vi;
    int n;
    u32 h_var8 = 0, h_var16 = 0, h_var32 = 0, h_rot = 0, h_const = 0, h_clz = 0;

    con_init();
    con_puts("shifts: variable and constant shifts, rotates\n");

    /* A few shown in full. */
    con_kv_hex32("u8 0x81<<3", shl_u8(0x81, 3));
    con_kv_hex32("u8 0x81>>7", shr_u8(0x81, 7));
    con_kv_i32("i8 -128>>7", sar_i8(-128, 7));
    con_kv_i32("i8 -1>>5", sar_i8(-1, 5));
    con_kv_i32("i8 0x41<<1", shl_i8(0x41, 1));
    con_kv_hex32("u16 0x8001<<15", shl_u16(0x8001u, 15));
    con_kv_hex32("u16 0x8001>>15", shr_u16(0x8001u, 15));
    con_kv_i32("i16 -32768>>15", sar_i16(I16_MIN, 15));
    con_kv_i32("i16 -12345>>4", sar_i16(-12345, 4));
    con_kv_hex32("u32 1<<31", shl_u32(1u, 31));
    con_kv_hex32("u32 0x80000000>>31", shr_u32(0x80000000u, 31));
    con_kv_i32("i32 min>>31", sar_i32(I32_MIN, 31));
    con_kv_i32("i32 -1000000>>10", sar_i32(-1000000, 10));
    con_kv_i32("i32 3<<30", shl_i32(3, 30));
    con_kv_hex32("rotl8 0x96,3", rotl_u8(0x96, 3));
    con_kv_hex32("rotr16 0x1234,4", rotr_u16(0x1234u, 4));
    con_kv_hex32("rotl32 0x12345678,12", rotl_u32(0x12345678u, 12));

    check(shl_u32(1u, 31) == 0x80000000u, "1<<31");
    check(sar_i32(-1, 31) == -1, "-1>>31");
    check(shr_u16(0xFFFFu, 15) == 1u, "u16 >>15");
    check(sar_i8(-128, 7) == -1, "i8 >>7");

    for (vi = 0; vi < N_VALUES; vi++) {
        u32 v = values[vi];
        for (n = 0; n < 8; n++) {
            h_var8 = fold(h_var8, shl_u8((u8)v, n));
            h_var8 = fold(h_var8, shr_u8((u8)v, n));
            h_var8 = fold(h_var8, (u32)sar_i8((i8)v, n));
            h_var8 = fold(h_var8, (u32)shl_i8((i8)v, n));
        }
        for (n = 0; n < 16; n++) {
            h_var16 = fold(h_var16, shl_u16((u16)v, n));
            h_var16 = fold(h_var16, shr_u16((u16)v, n));
            h_var16 = fold(h_var16, (u32)sar_i16((i16)v, n));
            h_var16 = fold(h_var16, (u32)shl_i16((i16)v, n));
        }
        for (n = 0; n < 32; n++) {
            h_var32 = fold(h_var32, shl_u32(v, n));
            h_var32 = fold(h_var32, shr_u32(v, n));
            h_var32 = fold(h_var32, (u32)sar_i32((i32)v, n));
            h_var32 = fold(h_var32, (u32)shl_i32((i32)v, n));
        }
        for (n = 1; n < 8; n++) {
            h_rot = fold(h_rot, rotl_u8((u8)v, n));
        }
        for (n = 1; n < 16; n++) {
            h_rot = fold(h_rot, rotr_u16((u16)v, n));
        }
        for (n = 1; n < 32; n++) {
            h_rot = fold(h_rot, rotl_u32(v, n));
        }
        h_const = fold(h_const, const_shifts_u32(v));
        h_const = fold(h_const, const_shifts_i32((i32)v));
        h_const = fold(h_const, const_shifts_16_8((u16)v, (i16)(v >> 16), (u8)(v >> 8), (i8)v));
        h_clz = fold(h_clz, (u32)clz32(v));
        /* Identities that must hold for every value. */
        check(rotl_u32(rotl_u32(v | 1u, 7), 25) == (v | 1u), "rotl 7+25");
        check(shr_u32(shl_u32(v, 8), 8) == (v & 0x00FFFFFFu), "shl/shr 8");
    }
    /* Pseudo-random values and counts. */
    rng_seed(0x5EED0001u);
    for (vi = 0; vi < 64; vi++) {
        u32 v = rng_next();
        int c = (int)(rng_next() & 31u);
        h_var32 = fold(h_var32, shl_u32(v, c) ^ shr_u32(v, c) ^ (u32)sar_i32((i32)v, c));
        h_var16 = fold(h_var16, (u32)shl_u16((u16)v, c & 15) ^ (u32)(u16)sar_i16((i16)v, c & 15));
        h_var8 = fold(h_var8, (u32)shr_u8((u8)v, c & 7) ^ (u32)(u8)sar_i8((i8)v, c & 7));
        h_clz = fold(h_clz, (u32)clz32(v >> c));
    }

    con_kv_hex32("hash var8", h_var8);
    con_kv_hex32("hash var16", h_var16);
    con_kv_hex32("hash var32", h_var32);
    con_kv_hex32("hash rotate", h_rot);
    con_kv_hex32("hash const", h_const);
    con_kv_hex32("hash clz", h_clz);
    return finish();
}
