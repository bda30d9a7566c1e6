/*
 * irq_board.c - IRQ0 driven from outside: P8.0 an input, IRQ0 on its falling edges, the CPU
 * asleep between them. Run on a board that drives P8.0 (emu/tests/chip_programs.rs); on a
 * board that drives nothing the pin floats low, no edge comes, and the program sleeps for ever.
 * After three interrupts it prints their count and exits 0.
 */
#include "chip.h"

UNUSED_ISR(isr_wovi)
UNUSED_ISR(isr_imia0)

static volatile u32 irqs;

void isr_irq0(void) __attribute__((interrupt_handler));
void isr_irq0(void)
{
    irqs++;
}

int main(void)
{
    con_init();
    ISCR = 0x01u; /* IRQ0: falling edge */
    {
        u8 isr = ISR;
        ISR = (u8)(isr & 0xFEu);
    }
    IER = 0x01u;
    ENABLE_INTERRUPTS();
    while (irqs < 3u) {
        SLEEP();
    }
    DISABLE_INTERRUPTS();
    con_kv_u32("irqs", irqs);
    return finish();
}
