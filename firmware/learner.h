/*
 * learner.h - the Hartono-Kakita learner of docs/design.md §2 in Q15/Q7 on the H8/300H.
 *
 * Bit-exact to the Rust crate nn_q15 (forward pass docs/design.md §2.3, update docs/design.md §2.4, input vector
 * docs/design.md §2.2, step order docs/design.md §3.5). The network's arrays live in RAM after .bss, carved by
 * learner_setup at boot from the configuration block; nothing is allocated after boot.
 *
 * The routines work on the globals below rather than on arguments, so that the emulator can
 * call them by their symbols with the operands placed in RAM (h8swarm learn --on-core).
 */
#ifndef LEARNER_H
#define LEARNER_H

#include "h8.h"

/* Largest network the routines take: 256 inputs (the no-overflow bound of the i32 sum,
 * docs/design.md §2.1) and 8 outputs (the robot enables 2 or 4 behaviours; up to 8 for what-if shapes). */
#define NET_MAX_INPUTS 256
#define NET_MAX_OUTPUTS 8

extern u16 net_n_in;      /* N */
extern u8 net_n_out;      /* M */
extern u8 net_history;    /* H: delayed copies of the proximities */
extern u8 net_bias;       /* 1: bias input +127 after E */
extern i16 net_eta;       /* eta, Q15, >= 0 */
extern i16 net_threshold; /* T, du, >= 0 */
extern i16 *net_w;        /* M rows of N Q15 weights, row j = output j */
extern i8 *net_x;         /* N Q7 inputs */
extern i32 *net_y;        /* M Q22 sums */
extern i16 *net_o;        /* M Q15 outputs */
extern i16 *net_delta;    /* N Q15 update deltas */
extern u8 net_win;        /* winner of the last forward pass */
extern u8 net_started;    /* a step has run: E and the update are defined */
extern i16 net_d_prev;    /* D(t-1) */

/* Carves the arrays for N inputs and M outputs from `heap` and zeroes x, outputs and the
 * carried state. Returns the first byte after them. */
u8 *learner_setup(u8 *heap, u16 n_in, u8 n_out);
/* Bytes learner_setup takes for N x M. */
u32 learner_bytes(u16 n_in, u8 n_out);
/* One step (docs/design.md §3.5): D(t) and E(t-1), the update on x(t-1), x(t), the forward pass.
 * Returns the winner. Phase "input" (its callees learner_update and learner_forward are
 * phases of their own). */
u8 learner_step(const u8 *p);
/* The update of docs/design.md §2.4 on net_x with evaluation e and winner net_win. */
void learner_update(i16 e);
/* The forward pass of docs/design.md §2.3 on net_x: net_y, net_o, net_win. */
void learner_forward(void);

#endif
