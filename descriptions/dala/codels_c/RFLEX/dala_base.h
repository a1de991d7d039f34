/* dala_base.h: the simulated base as RFLEX's C codels see it (genom2bip_device("dala_base")).
 *
 * The table is made by descriptions/dala/codels/base_device.py over the ir-sim world; a real base would be
 * a serial line with the same three operations.
 */
#ifndef H_DALA_BASE
#define H_DALA_BASE

struct dala_base {
  void (*command)(double v, double w);        /* the wheel command (m/s, rad/s), applied from the next step */
  double (*advance)(double seconds);          /* the base moves on by seconds; returns the simulation's time */
  double (*measure)(double *v, double *w);    /* the speeds the base measures; returns the simulation's time */
};

#endif /* H_DALA_BASE */
