/* RFLEX's codels in C: the same servo loop as descriptions/dala/codels/RFLEX.py, against RFLEX_c_types.h.
 *
 * The base is the simulated one, reached as a device (dala_base.h): the servo task advances it by one
 * period and integrates the speeds it measures into the odometry; TrackSpeed applies NDD's Speed poster
 * under the acceleration limit.  Generate DALA with them: genom2bip descriptions/dala -o OUT --c-codels
 * descriptions/dala/codels_c (docs/codels.md, *DALA with C codels*).
 */
#include "acRFLEX.h"

#include <math.h>
#include <stdio.h>

#include "RFLEX_c_types.h"
#include "dala_base.h"
#include "genom2bip/device.h"

#define PERIOD 0.025                 /* s, the servo task's period */

static dala_pose pose;               /* the odometry pose, from zero when the base is initialised */
static dala_twist applied;           /* the speed last applied to the wheels */

static struct dala_base *base(void)
{
  return (struct dala_base *)genom2bip_device("dala_base");
}

static double wrap(double a) { return atan2(sin(a), cos(a)); }

/* Unicycle dead reckoning over dt (exact on an arc), as odometry.integrate. */
static void integrate(dala_pose *p, double v, double w, double dt)
{
  double th = p->theta, dx, dy;
  if (fabs(w) < 1e-9) {
    dx = v * dt * cos(th);
    dy = v * dt * sin(th);
  } else {
    dx = v / w * (sin(th + w * dt) - sin(th));
    dy = -v / w * (cos(th + w * dt) - cos(th));
  }
  p->x += dx;
  p->y += dy;
  p->theta = wrap(th + w * dt);
}

/* The stamp as the Python codels publish it: the simulation's time to the microsecond. */
static double stamp(double t) { return nearbyint(t * 1e6) / 1e6; }

static void publish(const RFLEX_Odo *Odo, struct dala_base *b, const genom_context self)
{
  dala_odometry *odo = Odo->data(self);
  double v = 0., w = 0., t = b->measure(&v, &w);
  odo->position = pose;
  odo->velocity.v = v;
  odo->velocity.w = w;
  odo->stamp = stamp(t);
  Odo->write(self);
}

static void apply(dala_twist speed)
{
  struct dala_base *b = base();
  applied = speed;
  if (b) b->command(speed.v, speed.w);
}

genom_event
rflexInitOdometry(const RFLEX_Odo *Odo, const genom_context self)
{
  struct dala_base *b = base();
  pose.x = pose.y = pose.theta = 0.;
  applied.v = applied.w = 0.;
  if (b) {
    b->command(0., 0.);
    publish(Odo, b, self);
  }
  return RFLEX_odometry;
}

genom_event
rflexOdometry(const RFLEX_Odo *Odo, const genom_context self)
{
  struct dala_base *b = base();
  if (b) {
    double v = 0., w = 0.;
    b->advance(PERIOD);
    b->measure(&v, &w);
    integrate(&pose, v, w, PERIOD);
    publish(Odo, b, self);
  }
  return RFLEX_pause_odometry;
}

genom_event
rflexClose(const genom_context self)
{
  (void)self;
  return RFLEX_ether;
}

genom_event
rflexOpen(const char device[64], char opened[64], const genom_context self)
{
  if (!base()) {
    RFLEX_e_base_detail d;
    snprintf(d.what, sizeof(d.what), "no base device dala_base for %s", device);
    return RFLEX_e_base(&d, self);
  }
  snprintf(opened, 64, "%s", device);
  return RFLEX_ether;
}

genom_event
rflexStartTracking(dala_drive_mode *mode, const genom_context self)
{
  (void)self;
  *mode = dala_drive_tracking;
  return RFLEX_track;
}

/* The speed one period closer to wanted: speeding up by at most acceleration_max * dt; braking at once. */
static dala_twist limited(dala_twist current, dala_twist wanted, double acceleration_max, double dt)
{
  dala_twist out;
  double v = current.v, target = wanted.v;
  if (fabs(target) > fabs(v) && target * v >= 0) {
    double step = acceleration_max * dt, d = target - v;
    v += d > step ? step : d < -step ? -step : d;
  } else {
    v = target;
  }
  out.v = v;
  out.w = wanted.w;
  return out;
}

genom_event
rflexTrack(const RFLEX_Speed *Speed, double acceleration_max, dala_twist *command, const genom_context self)
{
  dala_twist wanted = { 0., 0. };
  if (Speed->read(self) == genom_ok) wanted = *Speed->data(self);
  apply(limited(applied, wanted, acceleration_max ? acceleration_max : 0.5, PERIOD));
  *command = applied;
  return RFLEX_pause_track;
}

genom_event
rflexBrake(dala_drive_mode *mode, dala_twist *command, const genom_context self)
{
  dala_twist still = { 0., 0. };
  (void)self;
  *mode = dala_drive_braking;
  apply(still);
  *command = still;
  return RFLEX_ether;
}

genom_event
rflexStop(dala_twist *command, const genom_context self)
{
  dala_twist still = { 0., 0. };
  (void)self;
  apply(still);
  *command = still;
  return RFLEX_ether;
}
