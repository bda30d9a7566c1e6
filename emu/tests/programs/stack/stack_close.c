/*
 * stack_close.c - a recursion that comes close to the end of the data but stays out of it
 * (for the stack guard: it must not be stopped).
 *
 * approach() reads SP and goes one level deeper while SP is more than 96 bytes above the end
 * of the program's data (the linker's __bss_end); one level takes less than 48 bytes, so the
 * deepest frame ends within a few dozen bytes of the data, never in it. Exit status 0.
 */
#include "testlib.h"

extern u8 _bss_end[];

static volatile u32 levels;

static NOINLINE u32 approach(u32 n)
{
    volatile u8 frame[16];
    u32 sp;
    __asm__ volatile("mov.l er7,%0" : "=r"(sp));
    frame[0] = (u8)n;
    levels = n;
    if (sp <= (u32)_bss_end + 96u) {
        return frame[0];
    }
    return approach(n + 1u) + frame[0];
}

int main(void)
{
    u32 r;
    con_init();
    r = approach(0u);
    con_kv_u32("levels", levels);
    check(levels > 100u, "the recursion went deep");
    con_kv_u32("sum", r);
    return finish();
}
