/* Random runs of a tick model in C, on the compiled step (c_successors): the loop of runtime/smc/simulate.py's
 * Simulator.run, its stochastic policy and its leaps over time, without a Python call per step.
 *
 * The model is read through the compiled step only; what the policy needs of an interaction (is it the tick,
 * which codels it starts or ends, which waits it ends, which response times it opens or closes, the weight and
 * the duration law of each of its successors) is asked of Python once per interaction (and again when the
 * number of its successors changes), through the `define` callback, which answers with sr_define.
 * The random numbers are xoshiro256** seeded by Python per run: a run depends on its seed words alone.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef int (*succ_fn)(int64_t *, int64_t *, int64_t *, int, int64_t, int *, int64_t *);
typedef int (*define_fn)(int64_t number, int64_t count, const int64_t *state);

enum { L_EXECS, L_DONES, L_ENDS, L_OPENS, L_CLOSES, L_HITS, L_CANCELS, NLISTS };
enum { END_HORIZON, END_GOALS, END_DEADLOCK, END_ZENO };
enum { ERR_STEP = -1, ERR_CAP = -2, ERR_DEFINE = -3, ERR_MEMORY = -4 };
#define FAR ((int64_t)1 << 62)
#define NORMAL_TRIES 32

typedef struct { double w; int kind; double a, b, c; } Rank;  /* weight; law: 0 uniform, 1 triangular, 2 normal */

typedef struct {
    int64_t number;
    int tick;
    int at[NLISTS], n[NLISTS];  /* into the pool */
    int64_t count;              /* successors the ranks were given for (-1: none) */
    int rank_at, rank_cap;      /* into ranks; room there (a count that comes back smaller reuses it) */
} Info;

typedef struct {
    succ_fn succ; define_fn define;
    int w, cap; int64_t budget;
    int64_t *cur, *out, *via;
    /* the model: schedulers (mark, busy bit, x, lo, hi), windows (mark, bit, clock, lo slot or -1, lo, hi slot or
       -1, hi), goals (slot, bit), leaps: clocks, (clock, const), (clock, slot), gaps (i or -1, j or -1, k) */
    int nsched; int64_t *sched;
    int nwin; int64_t *win;
    int ngoal; int64_t *goal;
    int nwatch;
    int nclock; int64_t *clocks;
    int ncons; int64_t *cons;
    int ndyn; int64_t *dyn;
    int ngap; int64_t *gaps;
    int leap; double tick_us; int keep_going;
    /* interactions known */
    Info *infos; int ninfo, cinfo;
    int64_t *keys; int *vals; int hcap;
    int *pool; int npool, cpool;
    Rank *ranks; int nrank, crank;
    /* the run */
    uint64_t s[4];
    int64_t *drawn, *waits, *since, *rates, *slot_rate; /* slot_rate: per slot, 0 but for clocks */
    int *gstart, *gcount, *ginfo, *allowed; int gcap;
    /* results */
    int64_t *reached, *at_step, ticks, steps, err_code, err_arg;
    int64_t *resp; int64_t nresp, cresp;       /* (watch, ticks) pairs */
    int64_t *choices; int64_t nchoice, cchoice; /* (number, rank) pairs, when recording */
} Ctx;

/* ------------------------------------------------------------------------------------------------ random */
static inline uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
static uint64_t next64(Ctx *c) {
    uint64_t *s = c->s, r = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0]; s[3] ^= s[1]; s[1] ^= s[2]; s[0] ^= s[3]; s[2] ^= t; s[3] = rotl(s[3], 45);
    return r;
}
static double unit(Ctx *c) { return (next64(c) >> 11) * 0x1.0p-53; } /* [0, 1) */
static int64_t below(Ctx *c, int64_t n) {                                 /* uniform in [0, n) */
    uint64_t limit = UINT64_MAX - UINT64_MAX % (uint64_t)n, x;
    do x = next64(c); while (x >= limit);
    return (int64_t)(x % (uint64_t)n);
}
static int64_t geometric(Ctx *c, double q) { /* P(G >= j) = q^j */
    double u = 1.0 - unit(c);
    return (int64_t)(log(u) / log(q));
}
static double gauss(Ctx *c, double mean, double sd) {
    double u = 1.0 - unit(c), v = unit(c);
    return mean + sd * sqrt(-2.0 * log(u)) * cos(2.0 * M_PI * v);
}
static double draw_us(Ctx *c, const Rank *law, double lo, double hi) {
    if (hi <= lo) return lo;
    int kind = law ? law->kind : 0;
    if (kind == 1) {
        double mode = isnan(law->a) ? (lo + hi) / 2 : fmin(fmax(law->a, lo), hi);
        double u = unit(c), k = (mode - lo) / (hi - lo), low = lo, high = hi;
        if (u > k) { u = 1.0 - u; k = 1.0 - k; low = hi; high = lo; }
        return low + (high - low) * sqrt(u * k);
    }
    if (kind == 2) {
        double mean = isnan(law->b) ? (lo + hi) / 2 : law->b;
        double sd = (isnan(law->c) || law->c == 0) ? (hi - lo) / 6 : law->c;
        for (int t = 0; t < NORMAL_TRIES; t++) {
            double v = gauss(c, mean, sd);
            if (lo <= v && v <= hi) return v;
        }
        return fmin(fmax(mean, lo), hi);
    }
    return lo + (hi - lo) * unit(c);
}
static int64_t draw_ticks(Ctx *c, const Rank *law, int64_t lo, int64_t hi) { /* rounded up to a tick */
    double v = draw_us(c, law, lo * c->tick_us, hi * c->tick_us);
    int64_t t = (int64_t)ceil(v / c->tick_us - 1e-9);
    return t < lo ? lo : t > hi ? hi : t;
}

/* ------------------------------------------------------------------------------------------------ tables */
static int grow(void **p, int *cap, int need, size_t size) {
    if (need <= *cap) return 0;
    int n = *cap ? *cap : 16;
    while (n < need) n *= 2;
    void *q = realloc(*p, (size_t)n * size);
    if (!q) return -1;
    *p = q; *cap = n;
    return 0;
}
static int grow64(void **p, int64_t *cap, int64_t need, size_t size) {
    if (need <= *cap) return 0;
    int64_t n = *cap ? *cap : 1024;
    while (n < need) n *= 2;
    void *q = realloc(*p, (size_t)n * size);
    if (!q) return -1;
    *p = q; *cap = n;
    return 0;
}
static uint64_t mix(int64_t k) {
    uint64_t x = (uint64_t)k * 0x9E3779B97F4A7C15ull;
    return x ^ (x >> 29);
}
static int lookup(Ctx *c, int64_t number) {
    if (!c->hcap) return -1;
    for (uint64_t h = mix(number) & (c->hcap - 1);; h = (h + 1) & (c->hcap - 1)) {
        if (c->vals[h] < 0) return -1;
        if (c->keys[h] == number) return c->vals[h];
    }
}
static int insert(Ctx *c, int64_t number, int v) {
    if (2 * (c->ninfo + 1) > c->hcap) {
        int n = c->hcap ? 2 * c->hcap : 256;
        int64_t *keys = malloc(n * sizeof *keys); int *vals = malloc(n * sizeof *vals);
        if (!keys || !vals) { free(keys); free(vals); return -1; }
        for (int i = 0; i < n; i++) vals[i] = -1;
        for (int i = 0; i < c->hcap; i++) if (c->vals[i] >= 0) {
            uint64_t h = mix(c->keys[i]) & (n - 1);
            while (vals[h] >= 0) h = (h + 1) & (n - 1);
            keys[h] = c->keys[i]; vals[h] = c->vals[i];
        }
        free(c->keys); free(c->vals);
        c->keys = keys; c->vals = vals; c->hcap = n;
    }
    uint64_t h = mix(number) & (c->hcap - 1);
    while (c->vals[h] >= 0) h = (h + 1) & (c->hcap - 1);
    c->keys[h] = number; c->vals[h] = v;
    return 0;
}

static int64_t *copy64(const int64_t *src, int64_t n) {
    int64_t *p = malloc((n ? n : 1) * sizeof *p);
    if (p && n) memcpy(p, src, n * sizeof *p);
    return p;
}

void sr_free(Ctx *c);

Ctx *sr_new(int w, int nsched, const int64_t *sched, int nwin, const int64_t *win, int ngoal, const int64_t *goal,
            int nwatch, int nclock, const int64_t *clocks, int ncons, const int64_t *cons, int ndyn,
            const int64_t *dyn, int ngap, const int64_t *gaps, int leap, double tick_us, int keep_going) {
    Ctx *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->w = w; c->cap = 64;
    c->nsched = nsched; c->sched = copy64(sched, 5 * nsched);
    c->nwin = nwin; c->win = copy64(win, 7 * nwin);
    c->ngoal = ngoal; c->goal = copy64(goal, 2 * ngoal);
    c->nwatch = nwatch;
    c->nclock = nclock; c->clocks = copy64(clocks, nclock);
    c->ncons = ncons; c->cons = copy64(cons, 2 * ncons);
    c->ndyn = ndyn; c->dyn = copy64(dyn, 2 * ndyn);
    c->ngap = ngap; c->gaps = copy64(gaps, 3 * ngap);
    c->leap = leap; c->tick_us = tick_us; c->keep_going = keep_going;
    c->cur = malloc(w * sizeof(int64_t));
    c->slot_rate = calloc(w, sizeof(int64_t));
    c->out = malloc((size_t)w * c->cap * sizeof(int64_t));
    c->via = malloc(c->cap * sizeof(int64_t));
    c->drawn = malloc((nsched + 1) * sizeof(int64_t)); c->waits = malloc((nwin + 1) * sizeof(int64_t));
    c->since = malloc((nwatch + 1) * sizeof(int64_t)); c->rates = malloc((nclock + 1) * sizeof(int64_t));
    c->reached = malloc((ngoal + 1) * sizeof(int64_t)); c->at_step = malloc((ngoal + 1) * sizeof(int64_t));
    if (!c->sched || !c->win || !c->goal || !c->clocks || !c->cons || !c->dyn || !c->gaps || !c->cur || !c->out
        || !c->via || !c->slot_rate || !c->drawn || !c->waits || !c->since || !c->rates || !c->reached || !c->at_step) {
        sr_free(c);
        return NULL;
    }
    return c;
}

void sr_free(Ctx *c) {
    if (!c) return;
    void *ps[] = {c->sched, c->win, c->goal, c->clocks, c->cons, c->dyn, c->gaps, c->cur, c->slot_rate, c->out,
                  c->via, c->drawn,
                  c->waits, c->since, c->rates, c->reached, c->at_step, c->infos, c->keys, c->vals, c->pool,
                  c->ranks, c->gstart, c->gcount, c->ginfo, c->allowed, c->resp, c->choices};
    for (size_t i = 0; i < sizeof ps / sizeof *ps; i++) free(ps[i]);
    free(c);
}

/* Forget every interaction (the step was rebuilt: its numbers may differ). */
void sr_forget(Ctx *c) {
    c->ninfo = 0; c->npool = 0; c->nrank = 0;
    for (int i = 0; i < c->hcap; i++) c->vals[i] = -1;
}

/* What the policy needs of interaction `number` with `count` successors: tick or not, seven lists (execs,
 * dones, ends, opens, closes, hits, cancels: lens[7], then their items in `items`), per successor its weight and duration law
 * (kinds[count], params[3 * count]: mode, mean, sd in us, NaN for none).  Answered from the define callback. */
int sr_define(Ctx *c, int64_t number, int tick, const int *lens, const int *items, int64_t count,
              const double *weights, const int *kinds, const double *params) {
    int k = lookup(c, number), known = k >= 0;
    if (!known) {
        if (grow((void **)&c->infos, &c->cinfo, c->ninfo + 1, sizeof(Info))) return ERR_MEMORY;
        k = c->ninfo;
        if (insert(c, number, k)) return ERR_MEMORY;
        c->ninfo++;
        memset(&c->infos[k], 0, sizeof(Info));
    }
    Info *in = &c->infos[k];
    if (known) { /* known: new ranks only (the lists do not change) */
        if (count > in->rank_cap) {
            if (grow((void **)&c->ranks, &c->crank, c->nrank + (int)count, sizeof(Rank))) return ERR_MEMORY;
            in->rank_at = c->nrank; in->rank_cap = (int)count; c->nrank += (int)count;
        }
        in->count = count;
        for (int64_t r = 0; r < count; r++) {
            Rank *x = &c->ranks[in->rank_at + r];
            x->w = weights[r]; x->kind = kinds[r];
            x->a = params[3 * r]; x->b = params[3 * r + 1]; x->c = params[3 * r + 2];
        }
        return 0;
    }
    in->number = number; in->tick = tick;
    int total = 0;
    for (int l = 0; l < NLISTS; l++) total += lens[l];
    if (grow((void **)&c->pool, &c->cpool, c->npool + total, sizeof(int))) return ERR_MEMORY;
    for (int l = 0, at = 0; l < NLISTS; l++) {
        in->at[l] = c->npool; in->n[l] = lens[l];
        for (int i = 0; i < lens[l]; i++) c->pool[c->npool++] = items[at++];
    }
    if (grow((void **)&c->ranks, &c->crank, c->nrank + (int)count, sizeof(Rank))) return ERR_MEMORY;
    in->count = count; in->rank_at = c->nrank; in->rank_cap = count > 0 ? (int)count : 1;
    for (int64_t r = 0; r < count; r++) {
        Rank *x = &c->ranks[c->nrank++];
        x->w = weights[r]; x->kind = kinds[r];
        x->a = params[3 * r]; x->b = params[3 * r + 1]; x->c = params[3 * r + 2];
    }
    return 0;
}

static Info *info_of(Ctx *c, int64_t number, int64_t count) {
    int k = lookup(c, number);
    if (k >= 0) {
        Info *in = &c->infos[k];
        if (in->count == count || (count == 1 && in->n[L_EXECS] == 0)) return in;
    }
    if (c->define(number, count, c->cur)) return NULL;
    k = lookup(c, number);
    return k < 0 ? NULL : &c->infos[k];
}

/* ------------------------------------------------------------------------------------------------ a run */
static int early(Ctx *c, const Info *in, int list, const int64_t *at, const int64_t *table, int width, int col) {
    for (int i = 0; i < in->n[list]; i++) {
        int k = c->pool[in->at[list] + i];
        if (at[k] >= 0 && c->cur[table[width * k + col]] < at[k]) return 1;
    }
    return 0;
}
static void enter(Ctx *c) { /* draw the end of every window just entered; forget those left */
    for (int k = 0; k < c->nwin; k++) {
        const int64_t *v = &c->win[7 * k];
        int inside = (c->cur[v[0]] & v[1]) != 0;
        if (inside && c->waits[k] < 0) {
            int64_t lo = v[3] >= 0 ? c->cur[v[3]] : v[4], hi = v[5] >= 0 ? c->cur[v[5]] : v[6];
            c->waits[k] = draw_ticks(c, NULL, lo, hi);
        } else if (!inside && c->waits[k] >= 0) {
            c->waits[k] = -1;
        }
    }
}
static int64_t nearer(int64_t best, int64_t gap) {
    if (0 < gap && gap < best) best = gap;
    if (0 < gap + 1 && gap + 1 < best) best = gap + 1;
    return best;
}
static inline int64_t rate_of(Ctx *c, int64_t slot) { return c->slot_rate[slot]; }
/* runtime/smc/leaps.py's Leaps.length, the drawn ends included; rates read on the tick successor `t`. */
static int64_t span_of(Ctx *c, const int64_t *t) {
    int64_t best = FAR;
    for (int i = 0; i < c->nclock; i++) {
        c->rates[i] = t[c->clocks[i]] - c->cur[c->clocks[i]];
        c->slot_rate[c->clocks[i]] = c->rates[i];
    }
    for (int i = 0; i < c->ncons; i++)
        if (rate_of(c, c->cons[2 * i])) best = nearer(best, c->cons[2 * i + 1] - c->cur[c->cons[2 * i]]);
    for (int i = 0; i < c->ndyn; i++)
        if (rate_of(c, c->dyn[2 * i])) best = nearer(best, c->cur[c->dyn[2 * i + 1]] - c->cur[c->dyn[2 * i]]);
    for (int i = 0; i < c->ngap; i++) {
        int64_t gi = c->gaps[3 * i], gj = c->gaps[3 * i + 1], k = c->gaps[3 * i + 2];
        int64_t r = (gi >= 0 ? rate_of(c, gi) : 0) - (gj >= 0 ? rate_of(c, gj) : 0);
        if (r) {
            int64_t d = (gi >= 0 ? c->cur[gi] : 0) - (gj >= 0 ? c->cur[gj] : 0);
            best = nearer(best, (k - d) * r);
            best = nearer(best, (k - d) * r - 1);
        }
    }
    for (int k = 0; k < c->nsched; k++)
        if (c->drawn[k] >= 0 && rate_of(c, c->sched[5 * k + 2]))
            best = nearer(best, c->drawn[k] - c->cur[c->sched[5 * k + 2]]);
    for (int k = 0; k < c->nwin; k++)
        if (c->waits[k] >= 0 && rate_of(c, c->win[7 * k + 2]))
            best = nearer(best, c->waits[k] - c->cur[c->win[7 * k + 2]]);
    return best;
}
static void advance(Ctx *c, int64_t times) {
    for (int i = 0; i < c->nclock; i++) c->cur[c->clocks[i]] += c->rates[i] * times;
}
static int record(Ctx *c, int64_t number, int64_t rank, int64_t times) {
    if (grow64((void **)&c->choices, &c->cchoice, 2 * (c->nchoice + times), sizeof(int64_t))) return ERR_MEMORY;
    for (int64_t i = 0; i < times; i++) {
        c->choices[2 * c->nchoice] = number; c->choices[2 * c->nchoice + 1] = rank; c->nchoice++;
    }
    return 0;
}
/* Goals reached by a place (slot >= 0); those of an until (slot -1) by the interactions that hit them, before
 * those that cancel them (reached -2 until the run ends). */
static int goals(Ctx *c, int64_t now, int *left) {
    for (int g = 0; g < c->ngoal; g++)
        if (c->reached[g] == -1 && c->goal[2 * g] >= 0 && (c->cur[c->goal[2 * g]] & c->goal[2 * g + 1])) {
            c->reached[g] = now;
            c->at_step[g] = c->choices ? c->nchoice : c->steps;
            (*left)--;
        }
    return *left == 0 && !c->keep_going;
}

void sr_set_step(Ctx *c, void *succ, int64_t budget, void *define) {
    c->succ = (succ_fn)succ; c->budget = budget; c->define = (define_fn)define;
}

/* One run from `init` (w words) with random words `seed`, up to `horizon` ticks (or every goal reached), at
 * most `limit` steps.  Returns the end (END_*) or an error (ERR_*: err_code and err_arg say the step's). */
int sr_run(Ctx *c, const int64_t *init, const uint64_t *seed, int64_t horizon, int64_t limit, int recording) {
    int w = c->w;
    memcpy(c->cur, init, w * sizeof(int64_t));
    memcpy(c->s, seed, sizeof c->s);
    for (int k = 0; k < c->nsched; k++) c->drawn[k] = -1;
    for (int k = 0; k < c->nwin; k++) c->waits[k] = -1;
    for (int k = 0; k < c->nwatch; k++) c->since[k] = -1;
    for (int g = 0; g < c->ngoal; g++) c->reached[g] = c->at_step[g] = -1;
    c->nresp = 0; c->nchoice = 0; c->steps = 0; c->ticks = 0;
    if (!recording) { free(c->choices); c->choices = NULL; c->cchoice = 0; }
    else if (!c->choices && grow64((void **)&c->choices, &c->cchoice, 2, sizeof(int64_t))) return ERR_MEMORY;
    int left = c->ngoal, forced = 0, end = END_HORIZON;
    int64_t now = 0;
    enter(c);
    for (;;) {
        int code = 0; int64_t arg = 0;
        int n = c->succ(c->cur, c->out, c->via, c->cap, c->budget, &code, &arg);
        if (n < 0) {
            if (code == 10 && c->cap < 65536) { /* more successors than room: a larger buffer, the same state */
                int cap = c->cap * 16;
                int64_t *out = realloc(c->out, (size_t)w * cap * sizeof(int64_t));
                if (!out) return ERR_MEMORY;
                c->out = out;
                int64_t *via = realloc(c->via, cap * sizeof(int64_t));
                if (!via) return ERR_MEMORY;
                c->via = via; c->cap = cap;
                continue;
            }
            c->err_code = code; c->err_arg = arg;
            return ERR_STEP;
        }
        if (n == 0) { end = END_DEADLOCK; break; }
        if (n > c->gcap) {
            int cap = c->cap > n ? c->cap : n;
            int *a = realloc(c->gstart, cap * sizeof(int)), *b = a ? realloc(c->gcount, cap * sizeof(int)) : NULL;
            if (a) c->gstart = a;
            if (b) c->gcount = b;
            int *d = b ? realloc(c->ginfo, cap * sizeof(int)) : NULL;
            if (d) c->ginfo = d;
            int *e = d ? realloc(c->allowed, cap * sizeof(int)) : NULL;
            if (!e) return ERR_MEMORY;
            c->allowed = e; c->gcap = cap;
        }
        int ng = 0;
        for (int i = 0; i < n; i++) {
            if (ng && c->via[i] == c->via[c->gstart[ng - 1]]) { c->gcount[ng - 1]++; continue; }
            c->gstart[ng] = i; c->gcount[ng] = 1; ng++;
        }
        for (int g = 0; g < ng; g++) {
            Info *in = info_of(c, c->via[c->gstart[g]], c->gcount[g]);
            if (!in) return ERR_DEFINE;
            c->ginfo[g] = (int)(in - c->infos);
        }
        int na = 0;
        int any = 0;
        for (int k = 0; k < c->nsched && !any; k++) any = c->drawn[k] >= 0;
        for (int k = 0; k < c->nwin && !any; k++) any = c->waits[k] >= 0;
        if (any) {
            int due = 0;
            for (int k = 0; k < c->nsched && !due; k++)
                due = c->drawn[k] >= 0 && c->cur[c->sched[5 * k + 2]] >= c->drawn[k];
            for (int k = 0; k < c->nwin && !due; k++)
                due = c->waits[k] >= 0 && c->cur[c->win[7 * k + 2]] >= c->waits[k];
            for (int g = 0; g < ng; g++) {
                Info *in = &c->infos[c->ginfo[g]];
                if (in->tick) { if (due) continue; }
                else if (early(c, in, L_DONES, c->drawn, c->sched, 5, 2)) continue;
                if (early(c, in, L_ENDS, c->waits, c->win, 7, 2)) continue;
                c->allowed[na++] = g;
            }
        }
        if (!na) { for (int g = 0; g < ng; g++) c->allowed[g] = g; na = ng; }
        if (c->leap) {
            int tick = -1;
            for (int a = 0; a < na; a++) if (c->infos[c->ginfo[c->allowed[a]]].tick) { tick = a; break; }
            if (tick >= 0) {
                int others = na - 1;
                int64_t passing = forced ? 0 : others == 0 ? FAR : geometric(c, 1.0 / (others + 1));
                forced = 0;
                if (passing) {
                    if (now >= horizon) break;
                    int g = c->allowed[tick];
                    const int64_t *t = c->out + (size_t)c->gstart[g] * w;
                    int64_t span = span_of(c, t), m = passing < span ? passing : span;
                    if (horizon - now < m) m = horizon - now;
                    if (m == span && m > 1) { /* the tick ending the span may do more than add to clocks */
                        m--;
                        advance(c, m);
                    } else {
                        memcpy(c->cur, t, w * sizeof(int64_t));
                        if (m > 1) advance(c, m - 1);
                        forced = m == passing && m < span;
                    }
                    now += m;
                    c->steps++;
                    if (recording && record(c, c->infos[c->ginfo[g]].number, 0, m)) return ERR_MEMORY;
                    if (left && goals(c, now, &left)) { end = END_GOALS; break; }
                    if (c->steps >= limit) { end = END_ZENO; break; }
                    continue;
                }
                for (int a = tick; a + 1 < na; a++) c->allowed[a] = c->allowed[a + 1];
                na--;
            }
            forced = 0;
        }
        int g = c->allowed[na > 1 ? below(c, na) : 0];
        Info *in = &c->infos[c->ginfo[g]];
        if (in->tick && now >= horizon) break;
        int64_t count = c->gcount[g], rank = 0;
        const Rank *ranks = in->count == count ? &c->ranks[in->rank_at] : NULL;
        if (count > 1) {
            double sum = 0;
            if (ranks) for (int64_t r = 0; r < count; r++) sum += ranks[r].w;
            if (sum > 0) {
                double u = unit(c) * sum, acc = 0;
                rank = count - 1;
                for (int64_t r = 0; r < count; r++) {
                    acc += ranks[r].w;
                    if (u < acc) { rank = r; break; }
                }
                while (ranks[rank].w <= 0 && rank > 0) rank--; /* rounding at the top: never a weight of 0 */
            } else {
                rank = below(c, count);
            }
        }
        memcpy(c->cur, c->out + (size_t)(c->gstart[g] + rank) * w, w * sizeof(int64_t));
        c->steps++;
        if (recording && record(c, in->number, rank, 1)) return ERR_MEMORY;
        if (in->tick) now++;
        for (int i = 0; i < in->n[L_DONES]; i++) c->drawn[c->pool[in->at[L_DONES] + i]] = -1;
        for (int i = 0; i < in->n[L_EXECS]; i++) {
            int k = c->pool[in->at[L_EXECS] + i];
            const int64_t *s = &c->sched[5 * k];
            if (c->cur[s[0]] & s[1])
                c->drawn[k] = draw_ticks(c, ranks ? &ranks[rank] : NULL, c->cur[s[3]], c->cur[s[4]]);
        }
        if (c->nwin) enter(c);
        for (int i = 0; i < in->n[L_OPENS]; i++) {
            int k = c->pool[in->at[L_OPENS] + i];
            if (c->since[k] < 0) c->since[k] = now;
        }
        for (int i = 0; i < in->n[L_CLOSES]; i++) {
            int k = c->pool[in->at[L_CLOSES] + i];
            if (c->since[k] >= 0) {
                if (grow64((void **)&c->resp, &c->cresp, 2 * (c->nresp + 1), sizeof(int64_t))) return ERR_MEMORY;
                c->resp[2 * c->nresp] = k; c->resp[2 * c->nresp + 1] = now - c->since[k]; c->nresp++;
                c->since[k] = -1;
            }
        }
        for (int i = 0; i < in->n[L_CANCELS]; i++) {
            int k = c->pool[in->at[L_CANCELS] + i];
            if (c->reached[k] == -1) { c->reached[k] = -2; left--; }
        }
        for (int i = 0; i < in->n[L_HITS]; i++) {
            int k = c->pool[in->at[L_HITS] + i];
            if (c->reached[k] == -1) {
                c->reached[k] = now; c->at_step[k] = c->choices ? c->nchoice : c->steps; left--;
            }
        }
        if (left && goals(c, now, &left)) { end = END_GOALS; break; }
        if (!left && !c->keep_going && c->ngoal) { end = END_GOALS; break; }
        if (c->steps >= limit) { end = END_ZENO; break; }
    }
    for (int g = 0; g < c->ngoal; g++) if (c->reached[g] == -2) c->reached[g] = -1;
    c->ticks = now;
    return end;
}

/* Results of the last run. */
void sr_results(Ctx *c, int64_t *out) { /* ticks, steps, nresp, nchoice, err_code, err_arg */
    out[0] = c->ticks; out[1] = c->steps; out[2] = c->nresp; out[3] = c->nchoice; out[4] = c->err_code;
    out[5] = c->err_arg;
}
void sr_goals(Ctx *c, int64_t *reached, int64_t *at_step) {
    memcpy(reached, c->reached, c->ngoal * sizeof(int64_t));
    memcpy(at_step, c->at_step, c->ngoal * sizeof(int64_t));
}
void sr_responses(Ctx *c, int64_t *out) { memcpy(out, c->resp, 2 * c->nresp * sizeof(int64_t)); }
void sr_choices(Ctx *c, int64_t *out) { memcpy(out, c->choices, 2 * c->nchoice * sizeof(int64_t)); }
