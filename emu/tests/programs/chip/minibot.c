/*
 * minibot.c - the least a robot image does for `h8swarm run --firmware`: a 10 ms tick
 * (ITU0 compare match A, vector 24), and every 45 ticks a step: start the A/D converter
 * (which is when the swarm takes the robot's sensing), wait for the result, sleep again. It
 * drives no motor. At boot it also writes the DMA controller's MAR0AR, and every step it reads
 * the flash memory's FLMCR1: registers the emulated chip does not model, which `run` reports
 * once per robot (and `--strict-io` stops at).
 */
#include "chip.h"

UNUSED_ISR(isr_irq0)
UNUSED_ISR(isr_wovi)

#define ADCSR REG8(0xFFFFE8)
#define ADDRAH REG8(0xFFFFE0)

static volatile u32 ticks;
static volatile u8 last;

void isr_imia0(void) __attribute__((interrupt_handler));
void isr_imia0(void)
{
    u8 tsr = ITU_TSR0;
    ITU_TSR0 = (u8)(tsr & 0xFEu);
    ticks++;
}

NOINLINE void boot_dma(void)
{
    REG8(0xFFFF20) = 0u; /* MAR0AR */
}

NOINLINE u8 flash_busy(void)
{
    return REG8(0xFFFF40); /* FLMCR1 */
}

NOINLINE void sense(void)
{
    u8 csr;
    ADCSR = 0x20u; /* ADST: single mode, AN0 */
    while (((csr = ADCSR) & 0x80u) == 0u) {
    }
    ADCSR = (u8)(csr & 0x7Fu); /* ADF read as 1, cleared */
    last = ADDRAH;
}

int main(void)
{
    u32 next = 45u;
    boot_dma();
    ITU_TCR0 = 0x23u;  /* phi/8, cleared by GRA */
    ITU_GRA0 = 31249u; /* 10 ms at 25 MHz */
    ITU_TIER0 = 0x01u;
    ITU_TSTR = 0x01u;
    ENABLE_INTERRUPTS();
    for (;;) {
        while ((i32)(ticks - next) < 0) {
            SLEEP();
        }
        next += 45u;
        sense();
        last = (u8)(last + flash_busy());
    }
    return 0;
}
