/*
 * stack_after.c - a deep recursion that fits, then a frame that does not (for the stack
 * guard).
 *
 * descend() goes 60 levels deep (about 3.5 KB of stack: well inside the room between the
 * end of the data and the top of RAM) and comes back; the guard must let all of it through.
 * Then fill() asks for an 8 180-byte buffer on the stack, more than the room that is left
 * under main's frame: the instruction that allocates it (SP moved below the end of the
 * data) is where the guard stops the program, before the buffer is written through the
 * frame pointer.
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

static NOINLINE u32 fill(u32 seed)
{
    volatile u8 buffer[8180];
    u32 i, sum = 0u;
    for (i = 0u; i < sizeof buffer; i++) {
        buffer[i] = (u8)(seed + i);
    }
    for (i = 0u; i < sizeof buffer; i += 97u) {
        sum += buffer[i];
    }
    return sum;
}

int main(void)
{
    con_init();
    sink = descend(60u);
    con_kv_u32("descend", sink);
    sink = fill(sink);
    con_kv_u32("fill", sink);
    return finish();
}
