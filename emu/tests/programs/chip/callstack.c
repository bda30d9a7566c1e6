/*
 * callstack.c - a program of known call structure for the profile (folded stacks):
 * main -> top -> mid -> leaf (mid calls leaf twice), while ITU0's compare match A interrupts
 * every 2 000 states (vector 24: isr_imia0 -> tick_work); main sleeps until 30 ticks have
 * passed, then stops the timer. Exit status 0.
 */
#include "chip.h"

UNUSED_ISR(isr_irq0)
UNUSED_ISR(isr_wovi)

static volatile u32 ticks;

NOINLINE void tick_work(void)
{
    ticks++;
}

void isr_imia0(void) __attribute__((interrupt_handler));
void isr_imia0(void)
{
    u8 tsr = ITU_TSR0; /* IMFA read as 1 ... */
    ITU_TSR0 = (u8)(tsr & 0xFEu); /* ... then cleared */
    tick_work();
}

NOINLINE u32 leaf(u32 x)
{
    return (x << 1) + x + 1u;
}

NOINLINE u32 mid(u32 x)
{
    return leaf(x) + leaf(x + 1u);
}

NOINLINE u32 top(u32 n)
{
    u32 s = 0;
    u32 i;
    for (i = 0; i < n; i++) {
        s += mid(i);
    }
    return s;
}

int main(void)
{
    u32 s = 0;
    con_init();
    /* ITU0: phi/8, cleared by GRA, compare match A every 250 counts (2 000 states). */
    ITU_TCR0 = 0x23u;
    ITU_GRA0 = 249u;
    ITU_TIER0 = 0x01u;
    ITU_TSTR = 0x01u;
    ENABLE_INTERRUPTS();
    while (ticks < 30u) {
        s += top(40u);
        SLEEP();
    }
    DISABLE_INTERRUPTS();
    ITU_TSTR = 0u;
    con_kv_u32("sum", s);
    check(s != 0u, "top ran");
    return finish();
}
