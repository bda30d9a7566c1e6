/* Kilombo port of the kilobotics.com Lab 3 "disperse" behaviour.
 * Per-bot state lives in USERDATA (Kilombo runs every bot in one process).
 */
#ifndef DISPERSE_H
#define DISPERSE_H

#include <stdint.h>

typedef enum { STOP, FORWARD, LEFT, RIGHT } motion_t;

typedef struct {
  motion_t current_motion;
  uint8_t new_message;          /* a message arrived since the last decision */
  uint32_t last_motion_update;  /* kilo_ticks of the last decision */
  message_t message;            /* the (empty) message this bot broadcasts */
} USERDATA;

#ifdef SIMULATOR
/* measurement hooks, in measure.c (simulator only) */
void measure_global_setup(void);
void measure_count_step(void);
int16_t measure_walls(double x, double y, double *dx, double *dy);
#endif

#endif
