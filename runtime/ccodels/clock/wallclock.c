/* The controller's clock for the codels' wall clock (linked into every codel library with -Wl,--wrap).
 *
 * gettimeofday(), clock_gettime(CLOCK_REALTIME or CLOCK_MONOTONIC) and time() called by the codels come
 * here.  While genom2bip_now is NULL (the controller runs on the real clock) they are the system's; once
 * the controller sets it (a virtual clock, faster than real time), they answer its time: realtime != 0 asks
 * for seconds since the epoch, 0 for the monotonic clock.
 */
#define _GNU_SOURCE
#include <stddef.h>
#include <sys/time.h>
#include <time.h>

double (*genom2bip_now)(int realtime) = NULL;

int __real_gettimeofday(struct timeval *tv, void *tz);
int __real_clock_gettime(clockid_t id, struct timespec *ts);
time_t __real_time(time_t *t);

int __wrap_gettimeofday(struct timeval *tv, void *tz)
{
  double now;

  if (!genom2bip_now || !tv) return __real_gettimeofday(tv, tz);
  now = genom2bip_now(1);
  tv->tv_sec = (time_t)now;
  tv->tv_usec = (suseconds_t)((now - (double)tv->tv_sec) * 1e6);
  return 0;
}

int __wrap_clock_gettime(clockid_t id, struct timespec *ts)
{
  double now;

  if (!genom2bip_now || !ts || (id != CLOCK_REALTIME && id != CLOCK_MONOTONIC))
    return __real_clock_gettime(id, ts);
  now = genom2bip_now(id == CLOCK_REALTIME);
  ts->tv_sec = (time_t)now;
  ts->tv_nsec = (long)((now - (double)ts->tv_sec) * 1e9);
  return 0;
}

time_t __wrap_time(time_t *t)
{
  time_t now;

  if (!genom2bip_now) return __real_time(t);
  now = (time_t)genom2bip_now(1);
  if (t) *t = now;
  return now;
}
