/* POM's codels in C: the same fusion as descriptions/dala/codels/POM.py, against POM_c_types.h.
 *
 * Generate DALA with them: genom2bip descriptions/dala -o OUT --c-codels descriptions/dala/codels_c
 * (docs/codels.md, *DALA with C codels*).
 */
#include "acPOM.h"

#include <math.h>

#include "POM_c_types.h"

static dala_pose anchor;          /* world pose of the odometry frame */
static dala_pose last;            /* last odometry pose used */
static int has_last;

static double wrap(double a) { return atan2(sin(a), cos(a)); }

static dala_pose compose(dala_pose a, dala_pose b)
{
  double c = cos(a.theta), s = sin(a.theta);
  dala_pose r;
  r.x = a.x + c * b.x - s * b.y;
  r.y = a.y + s * b.x + c * b.y;
  r.theta = wrap(a.theta + b.theta);
  return r;
}

static dala_pose between(dala_pose a, dala_pose b)
{
  double c = cos(a.theta), s = sin(a.theta), dx = b.x - a.x, dy = b.y - a.y;
  dala_pose r;
  r.x = c * dx + s * dy;
  r.y = -s * dx + c * dy;
  r.theta = wrap(b.theta - a.theta);
  return r;
}

/* The position for one odometry sample: its pose in the world frame, the covariance grown by the motion. */
static void fuse(dala_position *out, const dala_odometry *odo, const dala_pose *previous, const double cov[3])
{
  double c0 = cov[0], c1 = cov[1], c2 = cov[2];
  if (previous) {
    dala_pose step = between(*previous, odo->position);
    double distance = pow(step.x * step.x + step.y * step.y, 0.5);
    c0 += 0.01 * distance;
    c1 += 0.01 * distance;
    c2 += 0.005 * fabs(step.theta);
  }
  out->estimate = compose(anchor, odo->position);
  out->covariance[0] = c0;
  out->covariance[1] = c1;
  out->covariance[2] = c2;
  out->stamp = odo->stamp;
}

genom_event
pomInitTask(bool *initialised, const genom_context self)
{
  (void)self;
  *initialised = false;
  return POM_update;
}

genom_event
pomUpdate(bool initialised, const POM_Odo *Odo, dala_position *estimate, const POM_Pos *Pos,
          const genom_context self)
{
  if (initialised && Odo->read(self) == genom_ok) {
    const dala_odometry *odo = Odo->data(self);
    double cov[3];
    cov[0] = estimate->covariance[0];
    cov[1] = estimate->covariance[1];
    cov[2] = estimate->covariance[2];
    fuse(estimate, odo, has_last ? &last : NULL, cov);
    last = odo->position;
    has_last = 1;
    *Pos->data(self) = *estimate;
    Pos->write(self);
  }
  return POM_pause_update;
}

genom_event
pomEnd(const genom_context self)
{
  (void)self;
  return POM_ether;
}

genom_event
pomWaitOdometry(const POM_Odo *Odo, const genom_context self)
{
  return Odo->read(self) == genom_ok ? POM_fix : POM_pause_start;
}

genom_event
pomFix(const dala_pose *origin, const POM_Odo *Odo, dala_position *estimate, bool *initialised,
       const POM_Pos *Pos, const genom_context self)
{
  static const dala_pose zero = {0.0, 0.0, 0.0};
  static const double none[3] = {0.0, 0.0, 0.0};
  const dala_odometry *odo;

  if (Odo->read(self) != genom_ok) return POM_e_no_odometry(self);
  odo = Odo->data(self);
  anchor = compose(*origin, between(odo->position, zero));
  last = odo->position;
  has_last = 1;
  fuse(estimate, odo, NULL, none);
  *initialised = true;
  *Pos->data(self) = *estimate;
  Pos->write(self);
  return POM_ether;
}

genom_event
pomReset(bool *initialised, const genom_context self)
{
  (void)self;
  *initialised = false;
  return POM_ether;
}
