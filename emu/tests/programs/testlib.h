/*
 * testlib.h - small helpers shared by the differential test programs:
 * a deterministic pseudo-random generator, a hash fold, and self-checks.
 * Everything here is plain C with defined behaviour on host and target.
 */
#ifndef TESTLIB_H
#define TESTLIB_H

#include "h8types.h"
#include "console.h"

/* GCC 3.4 and later understand this; keeps small test functions out of line
 * so the compiler cannot fold their operands into constants. */
#define NOINLINE __attribute__((noinline))
/* Not every program uses every helper below. */
#define MAYBE_UNUSED __attribute__((unused))

/* xorshift32 (Marsaglia 2003, shifts 13/17/5): shifts and XOR only, so it
 * does not depend on the multiply or divide helpers. Never returns 0 for a
 * nonzero state. */
static MAYBE_UNUSED u32 rng_state = 0x2545F491u;

static MAYBE_UNUSED void rng_seed(u32 seed)
{
    rng_state = (seed != 0u) ? seed : 0x2545F491u;
}

static MAYBE_UNUSED u32 rng_next(void)
{
    u32 x = rng_state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    rng_state = x;
    return x;
}

/* Fold a 32-bit value into a running hash: rotate left by 5, XOR, add a
 * constant. Order-sensitive, so a swapped result changes the hash. */
static MAYBE_UNUSED u32 fold(u32 h, u32 v)
{
    h = (h << 5) | (h >> 27);
    return (h ^ v) + 0x9E3779B9u;
}

/* Self-checks: count failures, print the first few. main returns the count
 * (capped) so a wrong result also shows in the exit status. */
static MAYBE_UNUSED u32 check_failures = 0;

static MAYBE_UNUSED void check(int ok, const char *what)
{
    if (!ok) {
        check_failures++;
        if (check_failures <= 8u) {
            con_puts("FAIL ");
            con_puts(what);
            con_nl();
        }
    }
}

/* Print the summary and checksum lines; return the exit status. */
static MAYBE_UNUSED int finish(void)
{
    con_kv_u32("failures", check_failures);
    con_checksum_line();
    return (check_failures > 100u) ? 100 : (int)check_failures;
}

#endif
