/* Shared by every generated step: value type, error exit, checked arithmetic, the request environment.
   Included by the C text runtime.native.cstep generates, after E, W, NSRC, MAXF, NSLOTS, NSERV, VIA_BITS are
   defined. */
#include <math.h>
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

/* the number of an interaction (runtime.native.numbering): OFF[src] + mask, or OFF[src] for a source with one
   interaction; stored with every state as the link to its parent, in 32 bits when the model's numbers fit */
#if VIA_BITS == 64
typedef uint64_t VIA_T;
#define VIA_NONE UINT64_MAX
#else
typedef uint32_t VIA_T;
#define VIA_NONE UINT32_MAX
#endif

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
/* floats: stored as the bits of a double; computed as Python computes them, stopping where Python raises */
static inline double F(V bits) { double d; memcpy(&d, &bits, sizeof d); return d; }
static inline V B(double d) { V bits; if (d == 0) d = 0.0; memcpy(&bits, &d, sizeof bits); return bits; }
static inline double FDIV(double a, double b) { if (b == 0) fail(E_ARITH, 1); return a / b; }
static inline double FMOD(double a, double b) { if (b == 0 || (isinf(a) && !isnan(b))) fail(E_ARITH, 1); return fmod(a, b); }
static inline V F2I(double d) {
    if (!(d >= -9223372036854775808.0 && d < 9223372036854775808.0)) fail(E_ARITH, 3); /* NaN, inf, past 64 bits */
    return (V)d;
}
/* an int compared with a double exactly, as Python compares them (op: == != < <= > >=) */
static inline int ICMPF(V a, double b, int op) {
    int c;
    if (isnan(b)) return op == 1;
    if (b >= 9223372036854775808.0) c = -1;
    else if (b < -9223372036854775808.0) c = 1;
    else {
        V t = (V)b;
        double frac = b - (double)t;
        c = a < t ? -1 : a > t ? 1 : frac > 0 ? -1 : frac < 0 ? 1 : 0;
    }
    switch (op) {
    case 0: return c == 0;
    case 1: return c != 0;
    case 2: return c < 0;
    case 3: return c <= 0;
    case 4: return c > 0;
    default: return c >= 0;
    }
}
static inline V SHR(V a, V b) { if (b < 0) fail(E_ARITH, 2); if (b > 63) return a < 0 ? -1 : 0; return a >> b; }

/* the environment's requests: counts per service follow the engine's slots */
static TL const V *CUR;
static TL int TAKEN[NSERV > 0 ? NSERV : 1];
static int64_t BUDGET = -1;
static inline int PENDING(int k) { return CUR[E + k] < BUDGET; }
static inline V TAKE(int k) { TAKEN[k]++; return 0; }

/* an interaction a node of a nested connector offers: its leaf mask and the values of its exported port */
typedef struct { uint32_t m; V v[MAXF]; } Offer;

/* defines.maximal: the distinct masks of which no other is a strict superset, in increasing order */
static int maximal_offers(const Offer *g, int n, uint32_t *out) {
    int k = 0;
    for (int i = 0; i < n; i++) {
        uint32_t m = g[i].m;
        int drop = 0;
        for (int j = 0; j < n && !drop; j++) if (g[j].m != m && (g[j].m & m) == m) drop = 1;
        for (int j = 0; j < k && !drop; j++) if (out[j] == m) drop = 1;
        if (!drop) out[k++] = m;
    }
    for (int i = 1; i < k; i++)
        for (int j = i; j > 0 && out[j - 1] > out[j]; j--) { uint32_t t = out[j]; out[j] = out[j - 1]; out[j - 1] = t; }
    return k;
}
