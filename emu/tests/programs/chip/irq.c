/*
 * irq.c - the IRQ0 input (section 5) driven by the program's own port pin: P8.0 is IRQ0, and
 * as an output it drives the IRQ input with its latch. Falling-edge sensing: each 1 -> 0 of
 * P8DR bit 0 sets IRQ0F and interrupts (vector 12); 0 -> 1 does not. Low-level sensing: the
 * flag is set while the pin is low; the handler ends it by driving the pin high. The IRQ
 * flags are cleared by their exception handling (edge sensing) and by reading 1 then writing
 * 0. Exit status 0.
 */
#include "chip.h"

UNUSED_ISR(isr_wovi)
UNUSED_ISR(isr_imia0)

static volatile u32 irqs;

void isr_irq0(void) __attribute__((interrupt_handler));
void isr_irq0(void)
{
    u8 isr;
    irqs++;
    P8DR = 0x01u; /* the pin high: a low level no longer requests */
    isr = ISR;    /* ... and the flag, read as 1, cleared (a level-sensed flag is not cleared */
    ISR = (u8)(isr & 0xFEu); /* by the exception handling while the pin was still low) */
}

int main(void)
{
    int n;
    con_init();
    P8DR = 0x01u;
    P8DDR = 0x01u; /* P8.0 an output, high */
    ISCR = 0x01u;  /* IRQ0: falling edge */
    {
        u8 isr = ISR;
        ISR = (u8)(isr & 0xFEu); /* no stale flag */
    }
    IER = 0x01u;
    ENABLE_INTERRUPTS();
    for (n = 0; n < 5; n++) {
        P8DR = 0x00u; /* falling edge: one interrupt */
        P8DR = 0x01u; /* rising: none */
    }
    con_kv_u32("edges", irqs);
    check(irqs == 5u, "one interrupt per falling edge");

    /* Masked: the flag waits; unmasked, one interrupt. */
    DISABLE_INTERRUPTS();
    P8DR = 0x00u;
    P8DR = 0x01u;
    check((ISR & 0x01u) != 0u, "the flag is set while masked");
    ENABLE_INTERRUPTS();
    check(irqs == 6u, "taken once unmasked, the flag cleared by its handling");
    check((ISR & 0x01u) == 0u, "edge flag cleared by the exception handling");

    /* Low level: the handler raises the pin, so each low request is taken once. */
    ISCR = 0x00u;
    for (n = 0; n < 3; n++) {
        P8DR = 0x00u;
    }
    con_kv_u32("levels", irqs);
    check(irqs == 9u, "one interrupt per low level");

    /* Disabled: no interrupt, but the flag is set. */
    IER = 0x00u;
    P8DR = 0x00u;
    check(irqs == 9u, "no interrupt while IER = 0");
    check((ISR & 0x01u) != 0u, "the flag is set while disabled");
    P8DR = 0x01u;
    {
        u8 isr = ISR;
        ISR = (u8)(isr & 0xFEu);
    }
    check((ISR & 0x01u) == 0u, "cleared by reading 1 then writing 0 with the pin high");
    DISABLE_INTERRUPTS();
    return finish();
}
