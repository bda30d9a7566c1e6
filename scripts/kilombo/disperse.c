/* disperse: the kilobotics.com Lab 3 behaviour, written for Kilombo.
 *
 * Every bot broadcasts an empty message. About once a second
 * (kilo_ticks > last decision + 32) a bot that heard any message since
 * its last decision picks a random motion: forward (p = 1/2, green),
 * turn left (1/4, red) or turn right (1/4, blue). A bot that heard
 * nothing stops (white). So bots within communication range of others
 * keep moving and isolated bots stand still: the swarm spreads out.
 *
 * Differences from the lab's code: state in mydata (Kilombo runs all bots
 * in one process), and in the simulator build two extra hooks for the
 * measurement (measure.c): bot 0 counts the simulator's steps, and optional
 * square walls through Kilombo's obstacle callback.
 */
#include <kilombo.h>
#include "disperse.h"

REGISTER_USERDATA(USERDATA)

static void set_motion(motion_t m)
{
  if (mydata->current_motion == m)
    return;
  mydata->current_motion = m;
  switch (m) {
  case STOP:    set_motors(0, 0); break;
  case FORWARD: spinup_motors(); set_motors(kilo_straight_left, kilo_straight_right); break;
  case LEFT:    spinup_motors(); set_motors(kilo_turn_left, 0); break;
  case RIGHT:   spinup_motors(); set_motors(0, kilo_turn_right); break;
  }
}

static void setup(void)
{
  mydata->current_motion = STOP;
  mydata->new_message = 0;
  mydata->last_motion_update = 0;
  mydata->message.type = NORMAL;
  mydata->message.crc = message_crc(&mydata->message);
}

static void loop(void)
{
#ifdef SIMULATOR
  if (kilo_uid == 0)
    measure_count_step();   /* Kilombo calls every bot's loop once per step */
#endif
  if (kilo_ticks > mydata->last_motion_update + 32) {
    mydata->last_motion_update = kilo_ticks;
    if (mydata->new_message) {
      mydata->new_message = 0;
      uint8_t r = rand_hard() % 4;
      if (r < 2) {
        set_color(RGB(0, 1, 0));
        set_motion(FORWARD);
      } else if (r == 2) {
        set_color(RGB(1, 0, 0));
        set_motion(LEFT);
      } else {
        set_color(RGB(0, 0, 1));
        set_motion(RIGHT);
      }
    } else {
      set_color(RGB(1, 1, 1));
      set_motion(STOP);
    }
  }
}

static void message_rx(message_t *m, distance_measurement_t *d)
{
  (void) m; (void) d;
  mydata->new_message = 1;
}

static message_t *message_tx(void)
{
  return &mydata->message;
}

int main(void)
{
  kilo_init();
  kilo_message_rx = message_rx;
  kilo_message_tx = message_tx;
#ifdef SIMULATOR
  SET_CALLBACK(global_setup, measure_global_setup);
#endif
  kilo_start(setup, loop);
  return 0;
}
