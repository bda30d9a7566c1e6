/*
 * stack_deep.c - a recursion that does not stop in time (for the stack guard).
 *
 * Each level of descend() keeps a 48-byte frame of its own (through the frame pointer ER6)
 * besides the saved ER6 and the return address; 400 levels need about 24 KB, three times
 * the 8 KB of on-chip RAM. The stack runs down into .bss and off the RAM. Under the
 * emulator's stack guard the program stops at the first instruction that takes the stack
 * below the end of its data (the symbol __bss_end): the frame allocation or the push of one
 * level of descend(). Without a guard it would overwrite its variables and, much later, fetch
 * an instruction from outside ROM and RAM.
 */
#include "testlib.h"

static volatile u32 sink;

static NOINLINE u32 descend(u32 n)
{
    volatile u8 frame[48];
    frame[0] = (u8)n;
    frame[47] = (u8)(n >> 8);
    if (n == 0u) {
        return frame[0];
    }
    return descend(n - 1u) + frame[47];
}

int main(void)
{
    con_init();
    con_puts("descending 400 levels\n");
    sink = descend(400u);
    con_kv_u32("sum", sink);
    return finish();
}
