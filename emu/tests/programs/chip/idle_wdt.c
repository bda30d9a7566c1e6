/*
 * idle_wdt.c - the watchdog counting while the CPU idles: ITU0 ticks every 2 000 states
 * (vector 24: the handler counts), main sleeps between ticks (`while (ticks < N) sleep();`, the
 * robot firmware's idle loop), and the watchdog, in watchdog timer mode at phi/4096 and never
 * written, overflows after 1 048 576 states, in the middle of the idle stretch: the chip is
 * reset. After the reset (RSTCSR.WRST = 1) the program prints how it started and exits 0.
 * The emulator advances proven idle cycles at once (`Cpu::run_idle`); the watchdog's overflow
 * must still reset the chip at its own state.
 */
#include "chip.h"

UNUSED_ISR(isr_irq0)
UNUSED_ISR(isr_wovi)

static volatile u32 ticks;

void isr_imia0(void) __attribute__((interrupt_handler));
void isr_imia0(void)
{
    u8 tsr = ITU_TSR0;
    ITU_TSR0 = (u8)(tsr & 0xFEu);
    ticks++;
}

int main(void)
{
    u8 rstcsr = WDT_RSTCSR_R;
    con_init();
    if (rstcsr & RSTCSR_WRST) {
        con_puts("reset by the watchdog\n");
        WDT_RSTCSR_WRITE = 0xA500u;
        return finish();
    }
    con_puts("idling\n");
    ITU_TCR0 = 0x23u; /* phi/8, cleared by GRA */
    ITU_GRA0 = 249u;  /* 2 000 states */
    ITU_TIER0 = 0x01u;
    ITU_TSTR = 0x01u;
    WDT_TCSR(TCSR_WT | TCSR_TME | 7);
    ENABLE_INTERRUPTS();
    while (ticks < 100000u) {
        SLEEP();
    }
    /* Never reached: the watchdog resets the chip after about 524 ticks. */
    DISABLE_INTERRUPTS();
    check(0, "the watchdog reset the chip");
    return finish();
}
