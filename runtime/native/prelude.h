/* Shared by every generated step: value type, error exit, checked arithmetic, the request environment.
   Included by the C text runtime.native.cstep generates, after E, W, NSRC, MAXF, NSLOTS, NSERV are defined. */
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* PARALLEL (the two-worker build): the step's scratch globals are per thread, shared counters atomic */
#ifdef PARALLEL
#include <pthread.h>
#define TL __thread
#define ALOAD(p) __atomic_load_n(p, __ATOMIC_ACQUIRE)
#define ASTORE(p, v) __atomic_store_n(p, v, __ATOMIC_RELEASE)
#define ACAS(p, e, d) __atomic_compare_exchange_n(p, e, d, 0, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)
#define AADD(p, v) __atomic_fetch_add(p, v, __ATOMIC_ACQ_REL)
#define AOR(p, v) __atomic_fetch_or(p, v, __ATOMIC_ACQ_REL)
#else
#define TL
#define ALOAD(p) (*(p))
#define ASTORE(p, v) (*(p) = (v))
#define ACAS(p, e, d) (*(p) == *(e) ? (*(p) = (d), 1) : (*(e) = *(p), 0))
#define AADD(p, v) ((*(p) += (v)) - (v))
#define AOR(p, v) aor_plain(p, v)
static inline uint64_t aor_plain(uint64_t *p, uint64_t v) { uint64_t o = *p; *p = o | v; return o; }
#endif

typedef int64_t V;
typedef struct { int label, fixed; uint32_t full; } LabelDesc;

enum { E_NONDET = 1, E_UNSAFE, E_STUCK, E_NOTENABLED, E_ARITH, E_CYCLE, E_DOMAIN, E_WIDEN, E_CHOICES, E_FULL };

static TL jmp_buf JB;
static TL int ECODE;
static TL int64_t EARG;

static void fail(int code, int64_t arg) { ECODE = code; EARG = arg; longjmp(JB, 1); }

static inline V ADD(V a, V b) { V r; if (__builtin_add_overflow(a, b, &r)) fail(E_ARITH, 0); return r; }
static inline V SUB(V a, V b) { V r; if (__builtin_sub_overflow(a, b, &r)) fail(E_ARITH, 0); return r; }
static inline V MUL(V a, V b) { V r; if (__builtin_mul_overflow(a, b, &r)) fail(E_ARITH, 0); return r; }
static inline V NEG(V a) { if (a == INT64_MIN) fail(E_ARITH, 0); return -a; }
static inline V IDIV(V a, V b) { if (b == 0 || (a == INT64_MIN && b == -1)) fail(E_ARITH, 1); return a / b; }
static inline V IMOD(V a, V b) { if (b == 0) fail(E_ARITH, 1); if (b == -1) return 0; return a % b; }
static inline V SHL(V a, V b) {
    if (b < 0 || b > 62) fail(E_ARITH, 2);
    V r = (V)((uint64_t)a << b);
    if ((r >> b) != a) fail(E_ARITH, 2);
    return r;
}
static inline V SHR(V a, V b) { if (b < 0) fail(E_ARITH, 2); if (b > 63) return a < 0 ? -1 : 0; return a >> b; }

/* the environment's requests: counts per service follow the engine's slots */
static TL const V *CUR;
static TL int TAKEN[NSERV > 0 ? NSERV : 1];
static int64_t BUDGET = -1;
static inline int PENDING(int k) { return CUR[E + k] < BUDGET; }
static inline V TAKE(int k) { TAKEN[k]++; return 0; }
