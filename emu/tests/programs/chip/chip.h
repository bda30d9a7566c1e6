/*
 * chip.h - the H8/3052F registers the chip test programs use (H8/3052F hardware manual,
 * appendix B.1), and helpers for interrupts and sleep.
 */
#ifndef CHIP_H
#define CHIP_H

#include "testlib.h"

#define REG8(a) (*(volatile u8 *)(a))
#define REG16(a) (*(volatile u16 *)(a))

/* Watchdog timer (section 12): password words at H'FFA8 (TCSR, TCNT) and H'FFAA (RSTCSR). */
#define WDT_TCSR_R REG8(0xFFFFA8)
#define WDT_TCNT_R REG8(0xFFFFA9)
#define WDT_RSTCSR_R REG8(0xFFFFAB)
#define WDT_WRITE REG16(0xFFFFA8)
#define WDT_RSTCSR_WRITE REG16(0xFFFFAA)
#define WDT_TCSR(v) (WDT_WRITE = (u16)(0xA500u | (u8)(v)))
#define WDT_TCNT(v) (WDT_WRITE = (u16)(0x5A00u | (u8)(v)))
#define TCSR_OVF 0x80u
#define TCSR_WT 0x40u
#define TCSR_TME 0x20u
#define RSTCSR_WRST 0x80u

/* ITU channel 0 (section 10). */
#define ITU_TSTR REG8(0xFFFF60)
#define ITU_TCR0 REG8(0xFFFF64)
#define ITU_TIER0 REG8(0xFFFF66)
#define ITU_TSR0 REG8(0xFFFF67)
#define ITU_GRA0 REG16(0xFFFF6A)

/* IRQ inputs (section 5) and port 8, whose P8.0 is IRQ0. */
#define ISCR REG8(0xFFFFF4)
#define IER REG8(0xFFFFF5)
#define ISR REG8(0xFFFFF6)
#define P8DDR REG8(0xFFFFCD)
#define P8DR REG8(0xFFFFCF)

/* CCR.I = 0 / 1, and SLEEP. */
#define ENABLE_INTERRUPTS() __asm__ volatile("andc #0x7f,ccr")
#define DISABLE_INTERRUPTS() __asm__ volatile("orc #0x80,ccr")
#define SLEEP() __asm__ volatile("sleep")

/* A handler crt0.S's table points at that the program does not use: it must never run
 * (exit status 0xEE if it does). */
void __exit(void);
#define UNUSED_ISR(name)                                                                     \
    void name(void) __attribute__((interrupt_handler));                                      \
    void name(void)                                                                          \
    {                                                                                        \
        __asm__ volatile("mov.b #0xee,r0l\n\tjmp @__exit");                                  \
    }

#endif
