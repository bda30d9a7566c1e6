/* Measurement hooks for the disperse example (simulator build only).
 *
 * Kept in a file of its own because it includes Kilombo's internal header
 * skilobot.h, whose `extern void *mydata` clashes with REGISTER_USERDATA.
 *
 * - measure_count_step(): called by bot 0's loop. Kilombo's main loop
 *   (src/runsim.c) calls every bot's loop exactly once per step and then
 *   does `time += simparams->timeStep; kilo_ticks = time * TICKS_PER_SEC`.
 *   Repeating that same double += float sum here gives, at exit, exactly
 *   the simulated time Kilombo reached.
 * - measure_walls(): optional square walls (JSON "arenaWalls": 1) at the
 *   edges of the box the "random" formation fills:
 *   side = (int)(distributePercent * displayWidth) mm, as in distribution.c.
 * - at exit: one KILOMBO_REPORT line; every "sampleEvery" simulated seconds
 *   one KILOMBO_SAMPLE line (0 = off).
 */
#define _POSIX_C_SOURCE 199309L  /* clock_gettime under -std=c99 */
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <time.h>
#include "kilombo/kilolib.h"
#include "kilombo/params.h"
#include "kilombo/skilobot.h"
#include "disperse.h"

static long steps = 0;
static double sim_time = 0;          /* same sum as runsim.c's `time` */
static double next_sample = 0;
static double sample_every = 0;
static double half_x = 0, half_y = 0;
static struct timespec t_first;

static double now(struct timespec *t)
{
  clock_gettime(CLOCK_MONOTONIC, t);
  return t->tv_sec + 1e-9 * t->tv_nsec;
}

static int is_moving(const kilobot *b)
{
  return b->left_motor_power || b->right_motor_power;
}

/* Contacts (pairs closer than two radii) and bots with no other bot within
 * the communication radius, from the neighbour lists of the last step. */
static void neighbour_counts(long *contacts, int *isolated)
{
  double d2 = 4.0 * allbots[0]->radius * allbots[0]->radius;
  *contacts = 0;
  *isolated = 0;
  for (int i = 0; i < n_bots; i++) {
    kilobot *a = allbots[i];
    if (a->n_in_range == 0)
      (*isolated)++;
    for (int k = 0; k < a->n_in_range; k++) {
      kilobot *b = allbots[a->in_range[k]];
      if (b->ID > a->ID) {
        double dx = a->x - b->x, dy = a->y - b->y;
        if (dx * dx + dy * dy < d2)
          (*contacts)++;
      }
    }
  }
}

static void sample(void)
{
  int moving = 0, isolated;
  long contacts;
  for (int i = 0; i < n_bots; i++)
    moving += is_moving(allbots[i]);
  neighbour_counts(&contacts, &isolated);
  printf("KILOMBO_SAMPLE t=%.3f steps=%ld moving=%d contacts=%ld isolated=%d\n",
         sim_time, steps, moving, contacts, isolated);
}

static void report(void)
{
  struct timespec t_end;
  double wall = steps ? now(&t_end) - (t_first.tv_sec + 1e-9 * t_first.tv_nsec) : 0;
  int moving = 0, isolated;
  long contacts;
  double minx = allbots[0]->x, maxx = minx, miny = allbots[0]->y, maxy = miny;
  for (int i = 0; i < n_bots; i++) {
    kilobot *b = allbots[i];
    moving += is_moving(b);
    if (b->x < minx) minx = b->x;
    if (b->x > maxx) maxx = b->x;
    if (b->y < miny) miny = b->y;
    if (b->y > maxy) maxy = b->y;
  }
  neighbour_counts(&contacts, &isolated);
  printf("KILOMBO_REPORT bots=%d steps=%ld timeStep=%.10g sim_seconds=%.6f "
         "kilo_ticks=%u kilo_ticks_check=%u loop_to_exit_wall=%.3f "
         "moving=%d contacts=%ld isolated=%d bbox_mm=%.0fx%.0f\n",
         n_bots, steps, (double) simparams->timeStep, sim_time,
         (unsigned) kilo_ticks, (unsigned) (uint32_t) (sim_time * TICKS_PER_SEC), wall,
         moving, contacts, isolated, maxx - minx, maxy - miny);
  fflush(stdout);
}

int16_t measure_walls(double x, double y, double *dx, double *dy)
{
  double r = allbots[0]->radius;
  double lx = half_x - r, ly = half_y - r;
  *dx = x > lx ? lx - x : (x < -lx ? -lx - x : 0);
  *dy = y > ly ? ly - y : (y < -ly ? -ly - y : 0);
  return *dx != 0 || *dy != 0;
}

void measure_global_setup(void)
{
  sample_every = get_float_param("sampleEvery", 0);
  if (get_int_param("arenaWalls", 0)) {
    float f = get_float_param("distributePercent", 0.2);
    int w = get_int_param("displayWidth", 500);
    int h = get_int_param("displayHeight", 500);
    half_x = (int) (f * w) / 2.0;
    half_y = (int) (f * h) / 2.0;
    SET_CALLBACK(obstacles, measure_walls);
    printf("KILOMBO_WALLS square %.0f mm x %.0f mm\n", 2 * half_x, 2 * half_y);
  }
  atexit(report);
}

void measure_count_step(void)
{
  if (steps == 0)
    now(&t_first);
  if (sample_every > 0 && sim_time >= next_sample) {
    sample();
    next_sample += sample_every;
  }
  steps++;
  sim_time += simparams->timeStep;   /* runsim.c: time += simparams->timeStep */
}
