/*
 * recursion.c - recursive calls: Fibonacci, Ackermann (small), quicksort,
 * Towers of Hanoi, N-queens, mutual recursion, permutations and a recursive
 * GCD.
 *
 * Exercises JSR/BSR/RTS, pushing and popping the callee-saved ER4-ER6,
 * stack frames through ER6, and arguments beyond the three in registers
 * (pushed on the stack). The deepest recursion (Ackermann(3, 3), quicksort
 * on sorted input) stays well inside the 8 KB of on-chip RAM.
 */
#include "testlib.h"

static NOINLINE u32 fib(u32 n)
{
    return (n < 2u) ? n : fib(n - 1u) + fib(n - 2u);
}

static u32 ack_calls;

static NOINLINE u32 ack(u32 m, u32 n)
{
    ack_calls++;
    if (m == 0u) {
        return n + 1u;
    }
    if (n == 0u) {
        return ack(m - 1u, 1u);
    }
    return ack(m - 1u, ack(m, n - 1u));
}

static NOINLINE u32 gcd(u32 a, u32 b)
{
    return (b == 0u) ? a : gcd(b, a % b);
}

/* Mutual recursion. */
static NOINLINE int is_odd(u32 n);
static NOINLINE int is_even(u32 n)
{
    return (n == 0u) ? 1 : is_odd(n - 1u);
}
static NOINLINE int is_odd(u32 n)
{
    return (n == 0u) ? 0 : is_even(n - 1u);
}

/* Quicksort (Lomuto partition), recursing into both halves. */
static u32 qs_depth, qs_max_depth;

static NOINLINE void quicksort(i32 *a, int lo, int hi)
{
    i32 pivot, t;
    int i, j;
    if (lo >= hi) {
        return;
    }
    qs_depth++;
    if (qs_depth > qs_max_depth) {
        qs_max_depth = qs_depth;
    }
    pivot = a[hi];
    i = lo;
    for (j = lo; j < hi; j++) {
        if (a[j] < pivot) {
            t = a[i];
            a[i] = a[j];
            a[j] = t;
            i++;
        }
    }
    t = a[i];
    a[i] = a[hi];
    a[hi] = t;
    quicksort(a, lo, i - 1);
    quicksort(a, i + 1, hi);
    qs_depth--;
}

/* Towers of Hanoi: six arguments, so three go on the stack. */
static u32 hanoi_moves, hanoi_hash;

static NOINLINE void hanoi(int n, int from, int to, int via, u32 depth, u32 salt)
{
    if (n == 0) {
        return;
    }
    hanoi(n - 1, from, via, to, depth + 1u, salt);
    hanoi_moves++;
    hanoi_hash = fold(hanoi_hash, (u32)n << 24 | (u32)from << 16 | (u32)to << 8 | (depth ^ salt));
    hanoi(n - 1, via, to, from, depth + 1u, salt);
}

/* N-queens by backtracking, counting solutions. */
static NOINLINE u32 queens(int n, int row, u32 cols, u32 diag1, u32 diag2)
{
    u32 count = 0;
    int c;
    if (row == n) {
        return 1u;
    }
    for (c = 0; c < n; c++) {
        u32 bit = 1u << c;
        u32 d1 = 1u << (row + c);
        u32 d2 = 1u << (row - c + n - 1);
        if ((cols & bit) == 0u && (diag1 & d1) == 0u && (diag2 & d2) == 0u) {
            count += queens(n, row + 1, cols | bit, diag1 | d1, diag2 | d2);
        }
    }
    return count;
}

/* All permutations of 5 items by recursive swapping. */
static u8 perm[5];
static u32 perm_count, perm_hash;

static NOINLINE void permute(int k, int n)
{
    int i;
    u8 t;
    if (k == n) {
        u32 v = 0;
        for (i = 0; i < n; i++) {
            v = v * 10u + perm[i];
        }
        perm_count++;
        perm_hash = fold(perm_hash, v);
        return;
    }
    for (i = k; i < n; i++) {
        t = perm[k];
        perm[k] = perm[i];
        perm[i] = t;
        permute(k + 1, n);
        t = perm[k];
        perm[k] = perm[i];
        perm[i] = t;
    }
}

#define QS_N 64
static i32 data[QS_N];

int main(void)
{
    u32 n, i;
    u32 h;

    con_init();
    con_puts("recursion: fib, ackermann, quicksort, hanoi, queens, permutations\n");

    for (n = 0; n <= 20; n += 4) {
        con_puts("fib(");
        con_dec_u32(n);
        con_puts(")=");
        con_dec_u32(fib(n));
        con_nl();
    }
    check(fib(20) == 6765u, "fib(20)");

    for (n = 0; n <= 3; n++) {
        ack_calls = 0;
        con_puts("ack(2,");
        con_dec_u32(n);
        con_puts(")=");
        con_dec_u32(ack(2u, n));
        con_puts(" calls=");
        con_dec_u32(ack_calls);
        con_nl();
    }
    ack_calls = 0;
    con_kv_u32("ack(3,3)", ack(3u, 3u));
    con_kv_u32("ack(3,3) calls", ack_calls);
    check(ack(3u, 3u) == 61u, "ack(3,3)");

    con_kv_u32("gcd(1071,462)", gcd(1071u, 462u));
    con_kv_u32("gcd(2^31,3*2^20)", gcd(0x80000000u, 3u << 20));
    con_kv_u32("gcd(fib19,fib20)", gcd(fib(19), fib(20)));
    con_kv_i32("is_even(77)", is_even(77u));
    con_kv_i32("is_odd(77)", is_odd(77u));

    /* Quicksort random data, then already sorted data (deep recursion). */
    rng_seed(0x0BADCAFEu);
    for (i = 0; i < QS_N; i++) {
        data[i] = (i32)(rng_next() >> 12) - 0x80000;
    }
    quicksort(data, 0, QS_N - 1);
    h = 0;
    for (i = 0; i < QS_N; i++) {
        h = fold(h, (u32)data[i]);
        if (i > 0u) {
            check(data[i - 1u] <= data[i], "sorted");
        }
    }
    con_kv_i32("qs min", data[0]);
    con_kv_i32("qs median", data[QS_N / 2]);
    con_kv_i32("qs max", data[QS_N - 1]);
    con_kv_hex32("qs hash", h);
    con_kv_u32("qs max depth random", qs_max_depth);
    qs_max_depth = 0;
    quicksort(data, 0, QS_N - 1);
    con_kv_u32("qs max depth sorted", qs_max_depth);

    hanoi(10, 1, 3, 2, 0u, 0x5A5A5A5Au);
    con_kv_u32("hanoi(10) moves", hanoi_moves);
    con_kv_hex32("hanoi hash", hanoi_hash);
    check(hanoi_moves == 1023u, "hanoi moves");

    for (n = 4; n <= 7; n++) {
        con_puts("queens(");
        con_dec_u32(n);
        con_puts(")=");
        con_dec_u32(queens((int)n, 0, 0u, 0u, 0u));
        con_nl();
    }
    check(queens(6, 0, 0u, 0u, 0u) == 4u, "queens(6)");

    for (i = 0; i < 5; i++) {
        perm[i] = (u8)(i + 1u);
    }
    permute(0, 5);
    con_kv_u32("permutations", perm_count);
    con_kv_hex32("perm hash", perm_hash);
    return finish();
}
