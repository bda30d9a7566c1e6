/*
 * h8.h - fixed-width types and the H8/3052F registers the robot firmware uses.
 *
 * Addresses and bits: docs/design.md §3.2 and 4.1, from the H8/3052F hardware manual's register
 * tables (A/D converter, ITU, I/O ports). The registers sit at H'FFFF1C-H'FFFFFF, so GCC
 * reaches the byte registers with @aa:8 and the word registers with @aa:16.
 */
#ifndef H8_H
#define H8_H

typedef signed char i8;
typedef unsigned char u8;
typedef short i16;
typedef unsigned short u16;
typedef int i32; /* -mint32: int is 32 bits; long would be too, but stay with one spelling */
typedef unsigned int u32;

#define REG8(a) (*(volatile u8 *)(a))
#define REG16(a) (*(volatile u16 *)(a))

/* ITU (hardware manual section 10): TSTR, TMDR, and channels 0-2 at their bases. */
#define TSTR REG8(0xFFFF60)
#define TMDR REG8(0xFFFF62)
#define TCR0 REG8(0xFFFF64)
#define TIER0 REG8(0xFFFF66)
#define TSR0 REG8(0xFFFF67)
#define GRA0 REG16(0xFFFF6A)
#define TCR1 REG8(0xFFFF6E)
#define GRA1 REG16(0xFFFF74)
#define GRB1 REG16(0xFFFF76)
#define TCR2 REG8(0xFFFF78)
#define GRA2 REG16(0xFFFF7E)
#define GRB2 REG16(0xFFFF80)
/* TCR: counter cleared by compare match A (CCLR = 01), phi/8 (TPSC = 011). */
#define TCR_CLEAR_ON_GRA_PHI8 0x23
/* TIER/TSR bit 0: compare match A (IMIEA / IMFA). */
#define IMA 0x01
/* TMDR: PWM mode on channels 1 and 2 (PWM1, PWM2). */
#define TMDR_PWM12 0x06
/* TSTR: start channels 0, 1 and 2. */
#define TSTR_CH012 0x07

/* Ports (section 9). DDRs are write-only: keep shadows. */
#define P2PCR REG8(0xFFFFD8)
#define P4DDR REG8(0xFFFFC5)
#define P4DR REG8(0xFFFFC7)
#define P4PCR REG8(0xFFFFDA)
#define PBDDR REG8(0xFFFFD4)
#define PBDR REG8(0xFFFFD6)
/* I2C on port 4 (docs/design.md §3.6): SDA = P4.7, SCL = P4.6. */
#define SDA_BIT 0x80
#define SCL_BIT 0x40

/* A/D converter (section 15, docs/design.md §3.2): results left-justified, upper byte first. */
#define ADDRAH_ADDR 0xFFFFE0
#define ADCSR REG8(0xFFFFE8)
#define ADCSR_ADF 0x80
#define ADCSR_ADST 0x20
#define ADCSR_SCAN 0x10
#define ADCSR_CKS 0x08 /* 134 states per conversion */

#endif
