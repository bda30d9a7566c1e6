/*
 * arith.c - integer arithmetic at every width.
 *
 * 8/16/32-bit signed and unsigned add, subtract, multiply, divide, modulo,
 * negate and compare over a table of edge values and pseudo-random pairs.
 * Overflow is only ever produced in unsigned arithmetic (defined wrap-around);
 * narrowing back to a signed type relies on GCC's documented modulo
 * conversion, the same on host and target. Division skips zero divisors and
 * I32_MIN / -1 (undefined in C). Each (width, operation) prints a hash of all
 * its results; a few named cases print their values.
 */
#include "testlib.h"

static const u32 edge32[] = {
    0u, 1u, 2u, 3u, 7u, 10u, 0x7Fu, 0x80u, 0xFFu, 0x100u, 0x7FFFu, 0x8000u,
    0xFFFFu, 0x10000u, 0x12345678u, 0x7FFFFFFFu, 0x80000000u, 0x80000001u,
    0xFFFFFFFEu, 0xFFFFFFFFu, 0xDEADBEEFu, 0x00FF00FFu, 0xFFFF0001u, 0x55555555u,
};
#define N_EDGE (sizeof(edge32) / sizeof(edge32[0]))
#define N_RANDOM 48

/* Operand pairs: every edge value with every edge value, then random pairs. */
static u32 pair_a(u32 k)
{
    return edge32[k / N_EDGE];
}
static u32 pair_b(u32 k)
{
    return edge32[k % N_EDGE];
}

/* The operations are out of line so their operands stay unknown to GCC. */
static NOINLINE i8 add_i8(i8 a, i8 b) { return (i8)(u8)((u8)a + (u8)b); }
static NOINLINE i8 sub_i8(i8 a, i8 b) { return (i8)(u8)((u8)a - (u8)b); }
static NOINLINE i8 mul_i8(i8 a, i8 b) { return (i8)(a * b); }
static NOINLINE i8 div_i8(i8 a, i8 b) { return (i8)(a / b); }
static NOINLINE i8 mod_i8(i8 a, i8 b) { return (i8)(a % b); }
static NOINLINE u8 add_u8(u8 a, u8 b) { return (u8)(a + b); }
static NOINLINE u8 sub_u8(u8 a, u8 b) { return (u8)(a - b); }
static NOINLINE u8 mul_u8(u8 a, u8 b) { return (u8)(a * b); }
static NOINLINE u8 div_u8(u8 a, u8 b) { return (u8)(a / b); }
static NOINLINE u8 mod_u8(u8 a, u8 b) { return (u8)(a % b); }

static NOINLINE i16 add_i16(i16 a, i16 b) { return (i16)(u16)((u16)a + (u16)b); }
static NOINLINE i16 sub_i16(i16 a, i16 b) { return (i16)(u16)((u16)a - (u16)b); }
static NOINLINE i16 mul_i16(i16 a, i16 b) { return (i16)(a * b); }
static NOINLINE i16 div_i16(i16 a, i16 b) { return (i16)(a / b); }
static NOINLINE i16 mod_i16(i16 a, i16 b) { return (i16)(a % b); }
static NOINLINE u16 add_u16(u16 a, u16 b) { return (u16)(a + b); }
static NOINLINE u16 sub_u16(u16 a, u16 b) { return (u16)(a - b); }
static NOINLINE u16 mul_u16(u16 a, u16 b) { return (u16)((u32)a * b); }
static NOINLINE u16 div_u16(u16 a, u16 b) { return (u16)(a / b); }
static NOINLINE u16 mod_u16(u16 a, u16 b) { return (u16)(a % b); }

static NOINLINE i32 add_i32(i32 a, i32 b) { return (i32)((u32)a + (u32)b); }
static NOINLINE i32 sub_i32(i32 a, i32 b) { return (i32)((u32)a - (u32)b); }
static NOINLINE i32 mul_i32(i32 a, i32 b) { return (i32)((u32)a * (u32)b); }
static NOINLINE i32 div_i32(i32 a, i32 b) { return a / b; }
static NOINLINE i32 mod_i32(i32 a, i32 b) { return a % b; }
static NOINLINE u32 add_u32(u32 a, u32 b) { return a + b; }
static NOINLINE u32 sub_u32(u32 a, u32 b) { return a - b; }
static NOINLINE u32 mul_u32(u32 a, u32 b) { return a * b; }
static NOINLINE u32 div_u32(u32 a, u32 b) { return a / b; }
static NOINLINE u32 mod_u32(u32 a, u32 b) { return a % b; }

/* Comparisons compile to the signed (BLT/BGT/...) or unsigned (BCS/BHI/...)
 * branch family; pack six outcomes into one value. */
static NOINLINE u32 cmp_i8(i8 a, i8 b)
{
    return (u32)((a < b) | (a <= b) << 1 | (a > b) << 2 | (a >= b) << 3 | (a == b) << 4 | (a != b) << 5);
}
static NOINLINE u32 cmp_u8(u8 a, u8 b)
{
    return (u32)((a < b) | (a <= b) << 1 | (a > b) << 2 | (a >= b) << 3 | (a == b) << 4 | (a != b) << 5);
}
static NOINLINE u32 cmp_i16(i16 a, i16 b)
{
    return (u32)((a < b) | (a <= b) << 1 | (a > b) << 2 | (a >= b) << 3 | (a == b) << 4 | (a != b) << 5);
}
static NOINLINE u32 cmp_u16(u16 a, u16 b)
{
    return (u32)((a < b) | (a <= b) << 1 | (a > b) << 2 | (a >= b) << 3 | (a == b) << 4 | (a != b) << 5);
}
static NOINLINE u32 cmp_i32(i32 a, i32 b)
{
    return (u32)((a < b) | (a <= b) << 1 | (a > b) << 2 | (a >= b) << 3 | (a == b) << 4 | (a != b) << 5);
}
static NOINLINE u32 cmp_u32(u32 a, u32 b)
{
    return (u32)((a < b) | (a <= b) << 1 | (a > b) << 2 | (a >= b) << 3 | (a == b) << 4 | (a != b) << 5);
}

/* Negation and absolute value through unsigned arithmetic. */
static NOINLINE i32 neg_i32(i32 a) { return (i32)(0u - (u32)a); }
static NOINLINE i16 neg_i16(i16 a) { return (i16)(u16)(0u - (u16)a); }
static NOINLINE i8 neg_i8(i8 a) { return (i8)(u8)(0u - (u8)a); }
static NOINLINE u32 abs_i32(i32 a) { return (a < 0) ? 0u - (u32)a : (u32)a; }

enum { OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_MOD, OP_CMP, OP_NEG, N_OPS };
static const char *const op_names[N_OPS] = { "add", "sub", "mul", "div", "mod", "cmp", "neg" };

static u32 hashes[6][N_OPS];

static void run_pair(u32 a, u32 b)
{
    i8 sa8 = (i8)a, sb8 = (i8)b;
    u8 ua8 = (u8)a, ub8 = (u8)b;
    i16 sa16 = (i16)a, sb16 = (i16)b;
    u16 ua16 = (u16)a, ub16 = (u16)b;
    i32 sa32 = (i32)a, sb32 = (i32)b;

    hashes[0][OP_ADD] = fold(hashes[0][OP_ADD], (u32)add_i8(sa8, sb8));
    hashes[0][OP_SUB] = fold(hashes[0][OP_SUB], (u32)sub_i8(sa8, sb8));
    hashes[0][OP_MUL] = fold(hashes[0][OP_MUL], (u32)mul_i8(sa8, sb8));
    hashes[0][OP_CMP] = fold(hashes[0][OP_CMP], cmp_i8(sa8, sb8));
    hashes[0][OP_NEG] = fold(hashes[0][OP_NEG], (u32)neg_i8(sa8));
    if (sb8 != 0) {
        hashes[0][OP_DIV] = fold(hashes[0][OP_DIV], (u32)div_i8(sa8, sb8));
        hashes[0][OP_MOD] = fold(hashes[0][OP_MOD], (u32)mod_i8(sa8, sb8));
    }
    hashes[1][OP_ADD] = fold(hashes[1][OP_ADD], add_u8(ua8, ub8));
    hashes[1][OP_SUB] = fold(hashes[1][OP_SUB], sub_u8(ua8, ub8));
    hashes[1][OP_MUL] = fold(hashes[1][OP_MUL], mul_u8(ua8, ub8));
    hashes[1][OP_CMP] = fold(hashes[1][OP_CMP], cmp_u8(ua8, ub8));
    if (ub8 != 0) {
        hashes[1][OP_DIV] = fold(hashes[1][OP_DIV], div_u8(ua8, ub8));
        hashes[1][OP_MOD] = fold(hashes[1][OP_MOD], mod_u8(ua8, ub8));
    }
    hashes[2][OP_ADD] = fold(hashes[2][OP_ADD], (u32)add_i16(sa16, sb16));
    hashes[2][OP_SUB] = fold(hashes[2][OP_SUB], (u32)sub_i16(sa16, sb16));
    hashes[2][OP_MUL] = fold(hashes[2][OP_MUL], (u32)mul_i16(sa16, sb16));
    hashes[2][OP_CMP] = fold(hashes[2][OP_CMP], cmp_i16(sa16, sb16));
    hashes[2][OP_NEG] = fold(hashes[2][OP_NEG], (u32)neg_i16(sa16));
    if (sb16 != 0) {
        hashes[2][OP_DIV] = fold(hashes[2][OP_DIV], (u32)div_i16(sa16, sb16));
        hashes[2][OP_MOD] = fold(hashes[2][OP_MOD], (u32)mod_i16(sa16, sb16));
    }
    hashes[3][OP_ADD] = fold(hashes[3][OP_ADD], add_u16(ua16, ub16));
    hashes[3][OP_SUB] = fold(hashes[3][OP_SUB], sub_u16(ua16, ub16));
    hashes[3][OP_MUL] = fold(hashes[3][OP_MUL], mul_u16(ua16, ub16));
    hashes[3][OP_CMP] = fold(hashes[3][OP_CMP], cmp_u16(ua16, ub16));
    if (ub16 != 0) {
        hashes[3][OP_DIV] = fold(hashes[3][OP_DIV], div_u16(ua16, ub16));
        hashes[3][OP_MOD] = fold(hashes[3][OP_MOD], mod_u16(ua16, ub16));
    }
    hashes[4][OP_ADD] = fold(hashes[4][OP_ADD], (u32)add_i32(sa32, sb32));
    hashes[4][OP_SUB] = fold(hashes[4][OP_SUB], (u32)sub_i32(sa32, sb32));
    hashes[4][OP_MUL] = fold(hashes[4][OP_MUL], (u32)mul_i32(sa32, sb32));
    hashes[4][OP_CMP] = fold(hashes[4][OP_CMP], cmp_i32(sa32, sb32));
    hashes[4][OP_NEG] = fold(hashes[4][OP_NEG], (u32)neg_i32(sa32) ^ abs_i32(sb32));
    if (sb32 != 0 && !(sa32 == I32_MIN && sb32 == -1)) {
        hashes[4][OP_DIV] = fold(hashes[4][OP_DIV], (u32)div_i32(sa32, sb32));
        hashes[4][OP_MOD] = fold(hashes[4][OP_MOD], (u32)mod_i32(sa32, sb32));
    }
    hashes[5][OP_ADD] = fold(hashes[5][OP_ADD], add_u32(a, b));
    hashes[5][OP_SUB] = fold(hashes[5][OP_SUB], sub_u32(a, b));
    hashes[5][OP_MUL] = fold(hashes[5][OP_MUL], mul_u32(a, b));
    hashes[5][OP_CMP] = fold(hashes[5][OP_CMP], cmp_u32(a, b));
    if (b != 0) {
        hashes[5][OP_DIV] = fold(hashes[5][OP_DIV], div_u32(a, b));
        hashes[5][OP_MOD] = fold(hashes[5][OP_MOD], mod_u32(a, b));
    }
}

static const char *const width_names[6] = { "i8", "u8", "i16", "u16", "i32", "u32" };

int main(void)
{
    u32 k;
    int w, op;

    con_init();
    con_puts("arith: add/sub/mul/div/mod/cmp/neg at 8/16/32 bits\n");

    /* Named cases: wrap-around, truncating division, remainder signs. */
    con_kv_i32("i8 127+1", add_i8(127, 1));
    con_kv_i32("i8 -128-1", sub_i8(-128, 1));
    con_kv_i32("i8 -128/-1", div_i8(-128, -1));
    con_kv_i32("i8 -7/2", div_i8(-7, 2));
    con_kv_i32("i8 -7%2", mod_i8(-7, 2));
    con_kv_i32("i8 7%-2", mod_i8(7, -2));
    con_kv_i32("i8 -100*3", mul_i8(-100, 3));
    con_kv_u32("u8 200+100", add_u8(200, 100));
    con_kv_u32("u8 3-5", sub_u8(3, 5));
    con_kv_u32("u8 255/7", div_u8(255, 7));
    con_kv_u32("u8 255%7", mod_u8(255, 7));
    con_kv_i32("i16 32767+1", add_i16(32767, 1));
    con_kv_i32("i16 -32768/-1", div_i16(I16_MIN, -1));
    con_kv_i32("i16 -30000%7", mod_i16(-30000, 7));
    con_kv_i32("i16 300*-300", mul_i16(300, -300));
    con_kv_u32("u16 65535+2", add_u16(65535u, 2u));
    con_kv_u32("u16 65535*65535", mul_u16(65535u, 65535u));
    con_kv_u32("u16 65535/255", div_u16(65535u, 255u));
    con_kv_i32("i32 max+1", add_i32(I32_MAX, 1));
    con_kv_i32("i32 min-1", sub_i32(I32_MIN, 1));
    con_kv_i32("i32 min/1", div_i32(I32_MIN, 1));
    con_kv_i32("i32 min/2", div_i32(I32_MIN, 2));
    con_kv_i32("i32 min%3", mod_i32(I32_MIN, 3));
    con_kv_i32("i32 min/max", div_i32(I32_MIN, I32_MAX));
    con_kv_i32("i32 -1/max", div_i32(-1, I32_MAX));
    con_kv_i32("i32 -1000000007/-3", div_i32(-1000000007, -3));
    con_kv_i32("i32 -1000000007%-3", mod_i32(-1000000007, -3));
    con_kv_i32("i32 123456*-654321", mul_i32(123456, -654321));
    con_kv_i32("i32 -min", neg_i32(I32_MIN));
    con_kv_u32("u32 max*max", mul_u32(U32_MAX, U32_MAX));
    con_kv_u32("u32 max/65537", div_u32(U32_MAX, 65537u));
    con_kv_u32("u32 max%65537", mod_u32(U32_MAX, 65537u));
    con_kv_u32("u32 max/7", div_u32(U32_MAX, 7u));
    con_kv_u32("u32 0xDEADBEEF%0x10001", mod_u32(0xDEADBEEFu, 0x10001u));
    con_kv_u32("u32 cmp(1,max)", cmp_u32(1u, U32_MAX));
    con_kv_u32("i32 cmp(1,-1)", cmp_i32(1, -1));

    check(add_i32(I32_MAX, 1) == I32_MIN, "i32 wrap");
    check(div_i32(-7, 2) == -3 && mod_i32(-7, 2) == -1, "i32 -7/2");
    check(mul_u32(0x10001u, 0x10001u) == 0x00020001u, "u32 0x10001^2");

    for (k = 0; k < N_EDGE * N_EDGE; k++) {
        run_pair(pair_a(k), pair_b(k));
    }
    rng_seed(0xA5A5F00Du);
    for (k = 0; k < N_RANDOM; k++) {
        u32 a = rng_next();
        u32 b = rng_next();
        /* Mix in small operands: shift right by a random amount. */
        b >>= (a & 31u);
        run_pair(a, b);
        run_pair(b, a);
    }

    for (w = 0; w < 6; w++) {
        con_puts(width_names[w]);
        for (op = 0; op < N_OPS; op++) {
            if (op == OP_NEG && (w == 1 || w == 3 || w == 5)) {
                continue;
            }
            con_putchar(' ');
            con_puts(op_names[op]);
            con_putchar('=');
            con_hex32(hashes[w][op]);
        }
        con_nl();
    }
    return finish();
}
