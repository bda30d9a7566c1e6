/*
 * unmodelled.c - touches registers the emulated chip does not model: the DMA controller's
 * MAR0AR (written), the flash memory's FLMCR1 (read), a reserved I/O address (read), and the
 * DMAC again (not reported twice). Each access behaves as on a chip where nothing answers (a
 * read gives 0, a write is ignored); the emulator reports the first access to each address
 * with the instruction and its function. Exit status 0.
 */
#include "chip.h"

UNUSED_ISR(isr_irq0)
UNUSED_ISR(isr_wovi)
UNUSED_ISR(isr_imia0)

NOINLINE void start_dma(void)
{
    REG8(0xFFFF20) = 0x12u; /* MAR0AR */
}

NOINLINE u8 flash_status(void)
{
    return REG8(0xFFFF40); /* FLMCR1 */
}

NOINLINE u8 reserved(void)
{
    return REG8(0xFFFF1C); /* reserved */
}

int main(void)
{
    con_init();
    start_dma();
    check(flash_status() == 0u, "an unmodelled register reads 0");
    check(reserved() == 0u, "a reserved address reads 0");
    start_dma();
    con_puts("done\n");
    return finish();
}
