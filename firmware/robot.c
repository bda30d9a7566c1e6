/*
 * robot.c - the robot controller (docs/design.md §3.5, 8): boot, the 10 ms tick, and the step.
 *
 * Boot: the configuration block (or the compiled defaults), ports and pull-ups, ITU0 as the
 * 10 ms tick interrupt, ITU1/ITU2 as the motors' PWM, the network's arrays after .bss, the
 * newest valid A/B record or fresh xorshift32 weights, interrupts on. Then SLEEP between
 * ticks; every K ticks one step: A/D scan -> du -> learner (D, E, update, input, forward) ->
 * motors -> a record every S steps.
 */
#include "config.h"
#include "i2c.h"
#include "learner.h"
#include "record.h"

/* PWM: ITU1 (left) and ITU2 (right) at phi/8 with GRA = 1249, a 400 us period (2.5 kHz at
 * 25 MHz). Full speed is GRB = 1250, above GRA: the compare match B never comes and the
 * output stays high (the hardware manual's 100 % setting; GRB = GRA would hold the output
 * low). 0.3 v is 375 counts high, GRB = 374. */
#define PWM_GRA 1249
#define PWM_FULL 1250
#define PWM_SLOW 374
/* Port B: IN1/IN2 of the left H-bridge on PB0/PB1, of the right on PB2/PB3 (H/L forward,
 * L/H reverse, L/L coast). */
#define LEFT_FWD 0x01
#define LEFT_REV 0x02
#define RIGHT_FWD 0x04
#define RIGHT_REV 0x08
/* Room the stack needs below the top of RAM (the measured high-water mark is about half). */
#define STACK_RESERVE 256

/* From the linker script. */
extern u8 _heap_start[];
extern u8 _stack_top[];
extern const u8 du_table[256];

/* One row per behaviour (docs/design.md §3.5): forward (v, v), backward (-v, -v), turn-left-forward
 * (0.3 v, v), turn-right-forward (v, 0.3 v). */
struct motor_row {
    u16 left;
    u16 right;
    u8 dir;
};
static const struct motor_row motor_table[4] = {
    {PWM_FULL, PWM_FULL, LEFT_FWD | RIGHT_FWD},
    {PWM_FULL, PWM_FULL, LEFT_REV | RIGHT_REV},
    {PWM_SLOW, PWM_FULL, LEFT_FWD | RIGHT_FWD},
    {PWM_FULL, PWM_SLOW, LEFT_FWD | RIGHT_FWD},
};

volatile u32 ticks;  /* 10 ms ticks since boot (the interrupt counts them) */
u32 next_step;       /* the tick of the next step */
u32 steps;           /* steps run since boot */
u8 behaviour;        /* the behaviour the motors run */
u8 restored;         /* 1: the weights came from a record */
u8 *heap_end;        /* the first byte after the network's arrays */
static u16 save_count;
static u32 rng;      /* xorshift32 state */

void tick_isr(void) __attribute__((interrupt_handler));
void boot(void);
void ad_scan(u8 *p);
void motors_set(u8 b);
void robot_step(void);
void weights_random(void);
void tick_isr(void)
{
    TSR0 &= (u8)~IMA; /* read with IMFA = 1, write 0: the flag clears */
    ticks++;
}

static u32 xorshift32(void)
{
    u32 x = rng;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    rng = x;
    return x;
}

/* Fresh weights: the top 15 bits of xorshift32 less 2^14, uniform in [-0.5, 0.5). */
void weights_random(void)
{
    i16 *w = net_w;
    u16 n = (u16)(net_n_in * net_n_out);
    do {
        *w++ = (i16)((u16)(xorshift32() >> 17) - 16384);
    } while (--n);
}

static void hw_init(void)
{
    /* I2C lines released (DR = 0, DDR = 0) with their pull-ups; bumper pull-ups on P2.0-3;
     * the H-bridges coasting on PB0-3. */
    P4DR = 0;
    P4DDR = 0;
    P4PCR = SDA_BIT | SCL_BIT;
    P2PCR = 0x0F;
    PBDR = 0;
    PBDDR = 0x0F;
    /* ITU0: the tick; ITU1/ITU2: PWM at full duty, coasting until the first step. */
    TCR0 = TCR_CLEAR_ON_GRA_PHI8;
    TCR1 = TCR_CLEAR_ON_GRA_PHI8;
    TCR2 = TCR_CLEAR_ON_GRA_PHI8;
    GRA0 = cfg.tick_counts - 1;
    GRA1 = PWM_GRA;
    GRA2 = PWM_GRA;
    GRB1 = PWM_FULL;
    GRB2 = PWM_FULL;
    TIER0 = IMA;
    TMDR = TMDR_PWM12;
    TSTR = TSTR_CH012;
}

/* Boot up to the first SLEEP: everything that runs once. */
void boot(void)
{
    u16 n_in;
    config_load();
    n_in = config_inputs(&cfg);
    if (_heap_start + learner_bytes(n_in, cfg.outputs) + STACK_RESERVE > _stack_top) {
        config_load_defaults(CFG_R_RAM);
        n_in = config_inputs(&cfg);
    }
    hw_init();
    heap_end = learner_setup(_heap_start, n_in, cfg.outputs);
    net_history = cfg.history;
    net_bias = cfg.flags & CFG_FLAG_BIAS;
    net_eta = cfg.eta;
    net_threshold = cfg.threshold;
    rng = cfg.seed | 1;
    i2c_bus_clear();
    restored = record_restore();
    if (!restored) {
        weights_random();
    }
    next_step = 1; /* the first step comes with the first tick */
}

/* A/D: one scan of the sensors' group (AN0-3 or AN4-7), ADF polled, then the four codes
 * through the du table. ADDRA..D hold AN0/4..AN3/7, the 8-bit code in the upper byte. */
void ad_scan(u8 *p)
{
    u8 group = (cfg.channels[0] & 4) | 3;
    u8 k;
    ADCSR = ADCSR_ADST | ADCSR_SCAN | ADCSR_CKS | group;
    while ((ADCSR & ADCSR_ADF) == 0) {
    }
    ADCSR = ADCSR_SCAN | ADCSR_CKS | group; /* ADF read as 1, written 0; ADST off */
    for (k = 0; k < 4; k++) {
        p[k] = du_table[REG8(ADDRAH_ADDR + 2 * (cfg.channels[k] & 3))];
    }
}

/* The behaviour's row into GRB1, GRB2 and the H-bridge inputs. */
void motors_set(u8 b)
{
    const struct motor_row *r = &motor_table[b];
    GRB1 = r->left;
    GRB2 = r->right;
    PBDR = r->dir;
}

void robot_step(void)
{
    u8 p[4];
    u8 b;
    ad_scan(p);
    b = learner_step(p);
    if (cfg.flags & CFG_FLAG_RANDOM_WALK) {
        /* The random-walk control: the learner runs, its choice is not obeyed. */
        b = (u8)(((u32)(u16)(xorshift32() >> 16) * net_n_out) >> 16);
    }
    behaviour = b;
    motors_set(b);
    if (cfg.save_every != 0 && ++save_count >= cfg.save_every) {
        save_count = 0;
        record_save();
    }
    steps++;
}

int main(void)
{
    boot();
    __asm__ __volatile__("andc #0x7f,ccr"); /* interrupts on */
    for (;;) {
        while ((i32)(ticks - next_step) < 0) {
            __asm__ __volatile__("sleep");
        }
        next_step += cfg.ticks_per_step;
        robot_step();
    }
    return 0;
}
