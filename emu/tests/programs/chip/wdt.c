/*
 * wdt.c - the watchdog timer (H8/3052F hardware manual, section 12) from a program's side.
 *
 * At power-on (RSTCSR.WRST = 0) it checks the registers' reset values and the password
 * writes, runs the interval timer mode twice (OVF polled and cleared by reading it as 1 and
 * writing 0; then the WOVI interrupt, vector 20, woken from SLEEP), keeps the watchdog timer
 * mode from overflowing by writing TCNT in time, and then stops writing it and spins: the
 * overflow resets the chip. It starts again from the reset vector, sees WRST = 1, clears it,
 * checks that the reset returned TCSR and TCNT to their reset values, and exits 0.
 *
 * crt0 clears .bss and copies .data at every start, but the watchdog's reset keeps the RAM:
 * the count of starts lives in a RAM word above the program's data and below its stack
 * (BOOT_CELL; the test checks that __bss_end lies below it).
 */
#include "chip.h"

UNUSED_ISR(isr_irq0)
UNUSED_ISR(isr_imia0)

#define BOOT_CELL REG16(0xFFE800)
#define BOOT_MAGIC REG16(0xFFE802)
#define MAGIC 0xB007u

static volatile u32 wovi_count;

void isr_wovi(void) __attribute__((interrupt_handler));
void isr_wovi(void)
{
    u8 tcsr = WDT_TCSR_R; /* OVF read as 1 ... */
    WDT_TCSR(tcsr & (u8)~TCSR_OVF); /* ... then 0 written: cleared */
    wovi_count++;
}

static NOINLINE u16 starts(void)
{
    if (BOOT_MAGIC != MAGIC) {
        BOOT_MAGIC = MAGIC;
        BOOT_CELL = 0;
    }
    BOOT_CELL = (u16)(BOOT_CELL + 1u);
    return BOOT_CELL;
}

static NOINLINE void power_on(void)
{
    u32 polls = 0;
    int n;
    check(WDT_TCSR_R == 0x18u, "TCSR resets to H'18");
    check(WDT_TCNT_R == 0u, "TCNT resets to 0");
    check(WDT_RSTCSR_R == 0x3Fu, "RSTCSR resets to H'3F");

    /* Byte writes and a wrong password change nothing. */
    REG8(0xFFFFA8) = TCSR_TME;
    WDT_WRITE = 0x1234u;
    check(WDT_TCSR_R == 0x18u, "byte and wrong-password writes are ignored");
    WDT_TCNT(0x40); /* TCNT is held at 0 while TME = 0 */
    check(WDT_TCNT_R == 0u, "TCNT stays 0 while stopped");

    /* Interval timer mode, phi/2: an overflow every 512 states, polled. */
    WDT_TCSR(TCSR_TME | 0);
    for (n = 0; n < 3; n++) {
        while ((WDT_TCSR_R & TCSR_OVF) == 0u) {
            polls++;
        }
        WDT_TCSR(TCSR_TME | 0);
        check((WDT_TCSR_R & TCSR_OVF) == 0u, "OVF cleared by reading 1 then writing 0");
    }
    con_kv_u32("interval_polled", 3u);
    check(polls > 10u, "the counter took time to overflow");

    /* Interval timer mode, phi/32, with the WOVI interrupt. */
    WDT_TCSR(TCSR_TME | 1);
    ENABLE_INTERRUPTS();
    while (wovi_count < 4u) {
        SLEEP();
    }
    DISABLE_INTERRUPTS();
    WDT_TCSR(0);
    con_kv_u32("wovi", wovi_count);
    check(WDT_TCNT_R == 0u, "clearing TME clears TCNT");

    /* Watchdog timer mode, phi/4096 (an overflow after 1 048 576 states): written in time,
     * it never overflows. */
    WDT_TCSR(TCSR_WT | TCSR_TME | 7);
    for (n = 0; n < 5; n++) {
        while (WDT_TCNT_R < 200u) {
        }
        WDT_TCNT(0);
    }
    con_kv_u32("kicked", 5u);
    check((WDT_RSTCSR_R & RSTCSR_WRST) == 0u, "no reset while written in time");
    con_puts("spinning\n");
    for (;;) {
    }
}

int main(void)
{
    u16 boot;
    u8 rstcsr;
    con_init();
    rstcsr = WDT_RSTCSR_R;
    boot = starts();
    con_kv_u32("boot", boot);
    con_kv_u32("wrst", (rstcsr & RSTCSR_WRST) ? 1u : 0u);
    if (boot == 1u) {
        check((rstcsr & RSTCSR_WRST) == 0u, "no WRST at power-on");
        power_on();
    }
    check(boot == 2u, "one watchdog reset");
    check((rstcsr & RSTCSR_WRST) != 0u, "WRST after the watchdog's reset");
    check(WDT_TCSR_R == 0x18u, "the reset returned TCSR to H'18");
    check(WDT_TCNT_R == 0u, "the reset returned TCNT to 0");
    WDT_RSTCSR_WRITE = 0xA500u; /* H'A5 with WRST = 0: cleared */
    check(WDT_RSTCSR_R == 0x3Fu, "WRST cleared by the password write");
    return finish();
}
