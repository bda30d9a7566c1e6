/*
 * i2c.c - bit-banged I2C master for the two 24LC256 (DS21203) on port 4.
 *
 * Timing at phi = 25 MHz (40 ns a state), the 400 kHz-class minima of DS21203 Table 1-2:
 * SCL low >= 1.3 us and a bit >= 2.5 us, SCL high >= 0.6 us, START hold/setup >= 0.6 us,
 * data setup >= 0.1 us, STOP setup >= 0.6 us, bus free >= 1.3 us. The pin writes themselves
 * take time (a MOV.B to P4DDR is 5 states, the shadow update a few more); the delay loops
 * below add what is missing, counted from the listing. At a slower phi every interval is
 * longer, never shorter, so the minima hold at any clock of the H8/3052F.
 *
 * The DDR is write-only: a shadow keeps its value. Port 4's other pins are not used.
 */
#include "i2c.h"

static u8 ddr; /* P4DDR shadow */

/* n iterations of ADD.B #-1 and BNE: 6 states each. */
static __inline__ void delay(u8 n)
{
    __asm__ __volatile__("1:\n\tadd.b #-1,%s0\n\tbne 1b" : "+r"(n) : : "cc");
}

/* Delay loop counts (6 states an iteration), beside the states of the pin writes around
 * them; checked against the EEPROM model's timing monitor (emu's firmware tests). */
#define D_LOW 6   /* SCL low before a repeated START or a STOP's rising edge: >= 48 states */
#define D_HIGH 2  /* SCL high: >= 15 states */
#define D_HOLD 2  /* START hold, START setup, STOP setup: >= 15 states */
#define D_BUF 5   /* bus free after STOP: >= 33 states */

/* Between two ACK polls the master leaves the bus alone for about 200 us: the chip's write
 * cycle takes 3-5 ms (DS21203 t_WC), so polling back to back would spend the whole cycle on
 * the bus (about 250 polls a page); with the pause a page takes 15-25 polls and ends at most
 * 0.2 ms later. 833 iterations of DEC.W and BNE (6 states each) are 4 998 states at 25 MHz. */
#define POLL_GAP 833

/* n iterations of DEC.W #1 and BNE: 6 states each (n >= 1). */
static __inline__ void delay16(u16 n)
{
    __asm__ __volatile__("1:\n\tdec.w #1,%0\n\tbne 1b" : "+r"(n) : : "cc");
}

static __inline__ void scl_low(void)
{
    ddr |= SCL_BIT;
    P4DDR = ddr;
}

static __inline__ void scl_release(void)
{
    ddr &= (u8)~SCL_BIT;
    P4DDR = ddr;
}

static __inline__ void sda_low(void)
{
    ddr |= SDA_BIT;
    P4DDR = ddr;
}

static __inline__ void sda_release(void)
{
    ddr &= (u8)~SDA_BIT;
    P4DDR = ddr;
}

/* START from idle: SDA falls while SCL is high. */
static void start_condition(void)
{
    sda_low();
    delay(D_HOLD);
    scl_low();
}

/* Repeated START with SCL low. */
static void repeated_start(void)
{
    sda_release();
    delay(D_LOW);
    scl_release();
    delay(D_HOLD);
    sda_low();
    delay(D_HOLD);
    scl_low();
}

/* STOP with SCL low: SDA rises while SCL is high. */
static void stop_condition(void)
{
    sda_low();
    delay(D_LOW);
    scl_release();
    delay(D_HOLD);
    sda_release();
    delay(D_BUF);
}

/* One clock pulse with SCL low at entry and exit; returns SDA sampled while SCL is high. The
 * SCL low time needs no delay here: from the previous falling edge, the return, the loop, the
 * SDA write and the call take more than the 48 states of T_LOW (about 80, from the listing). */
static u8 clock(void)
{
    u8 sda;
    scl_release();
    delay(D_HIGH);
    sda = P4DR & SDA_BIT;
    scl_low();
    return sda;
}

/* Sends a byte MSB first (SCL low at entry and exit); returns 1 on ACK. */
static u8 write_byte(u8 b)
{
    u8 n = 8;
    do {
        if (b & 0x80) {
            sda_release();
        } else {
            sda_low();
        }
        b <<= 1;
        clock();
    } while (--n);
    sda_release();
    return clock() == 0;
}

/* Receives a byte MSB first and answers ACK (ack = 1) or NACK. */
static u8 read_byte(u8 ack)
{
    u8 n = 8, b = 0;
    sda_release();
    do {
        b <<= 1;
        if (clock()) {
            b |= 1;
        }
    } while (--n);
    if (ack) {
        sda_low();
    }
    clock();
    sda_release();
    return b;
}

static u8 control(u8 chip, u8 read)
{
    return (u8)(0xA0 | ((chip & 7) << 1) | read);
}

u8 i2c_bus_clear(void)
{
    u8 clocks = 0;
    ddr = 0;
    P4DR = 0;
    P4DDR = 0;
    delay(D_BUF);
    while ((P4DR & SDA_BIT) == 0) {
        if (clocks == 9) {
            return 1;
        }
        scl_low();
        clock();
        scl_release();
        clocks++;
    }
    delay(D_HIGH);
    scl_low();
    stop_condition();
    return 0;
}

/* START, control (W), address high and low: returns 1 when all three are ACKed. */
static u8 address(u8 chip, u16 addr)
{
    start_condition();
    return write_byte(control(chip, 0)) && write_byte((u8)(addr >> 8)) && write_byte((u8)addr);
}

u8 i2c_write(u8 chip, u16 addr, const u8 *src, u8 n)
{
    if (!address(chip, addr)) {
        stop_condition();
        return 1;
    }
    do {
        if (!write_byte(*src++)) {
            stop_condition();
            return 1;
        }
    } while (--n);
    stop_condition();
    return 0;
}

u16 i2c_ack_poll(u8 chip)
{
    u16 polls = 0;
    start_condition();
    for (;;) {
        polls++;
        if (write_byte(control(chip, 0))) {
            stop_condition();
            return polls;
        }
        if (polls == I2C_MAX_POLLS) {
            stop_condition();
            return 0;
        }
        delay16(POLL_GAP);
        repeated_start();
    }
}

u8 i2c_read(u8 chip, u16 addr, u8 *dst, u16 n)
{
    if (!address(chip, addr)) {
        stop_condition();
        return 1;
    }
    repeated_start();
    if (!write_byte(control(chip, 1))) {
        stop_condition();
        return 1;
    }
    while (n != 0) {
        n--;
        *dst++ = read_byte(n != 0);
    }
    stop_condition();
    return 0;
}
