/* The zone graph search of runtime/zones/search.py in C: the passed/waiting store, the zones and every
 * operation on them.  dbm.c's functions are compiled in front of this file.
 *
 * The search knows discrete states by number only.  What it needs of one (its successors with their clock
 * guards, resets and the regions where priorities block them; where time may pass there; the clocks nobody
 * reads there; the observers and response clocks it watches) is its *program*, a flat array of int64 that
 * ZoneExplorer.program() writes once per discrete state, asked for through a callback the first time the
 * search needs it.  The order of every loop is search.py's, so both searches number the same nodes the same
 * way (tests compare them).
 *
 * Program layout (every bound is a triple i, j, c: xi - xj <= c):
 *   n_idle, idle clocks...
 *   n_ceilings, (clock, L, U)...: the clocks whose ceilings here are their place's, not the model's
 *   passes (0: time cannot pass here), [n_before, bounds..., n_after, bounds..., n_waits,
 *       per wait: n, bounds..., kind (1: the lower bound k, c follow; 0: none), k, c, rule]
 *   n_checks, per check: kind (0 observer, 1 response clock), slot, clock, bound
 *   n_succ, per successor: next state, interaction, n_need, bounds..., n_resets, (clock, value)...,
 *       n_blocks, per block: n, bounds...
 */
#include <stdint.h>
#include <stdio.h>
#ifdef __AVX2__
#include <immintrin.h>
#endif

typedef int (*program_fn)(int64_t state);
typedef int (*ample_fn)(int64_t state, int64_t zone);  /* a node's discrete state and zone slot */
typedef int (*progress_fn)(int64_t nodes, int64_t transitions, int64_t waiting, int64_t memory, int64_t depth);

/* A growable array of a plain type. */
#define VEC(T) struct { T *a; int64_t n, cap; }

/* *a (cap items of size bytes) grown to twice as many; -9 without memory, *a and *cap as they were. */
static int grow_vec(void **a, int64_t *cap, size_t size)
{
    int64_t more = *cap ? 2 * *cap : 64;
    void *b = realloc(*a, more * size);
    if (!b)
        return -9;
    *a = b, *cap = more;
    return 0;
}

/* x appended to v; without memory, v is kept and ``fail`` runs (a return, or a jump to where locals are freed). */
#define PUSH_OR(v, x, fail) do { if ((v).n == (v).cap && grow_vec((void **)&(v).a, &(v).cap, sizeof(*(v).a))) fail; \
    (v).a[(v).n++] = (x); } while (0)
#define PUSH(v, x) PUSH_OR(v, x, return -9)

typedef struct {  /* 56 bytes: the 64-bit field first, the bytes last */
    int64_t guard;  /* offset of the step's bounds in the guard pool; their count is guard_len */
    int32_t state, parent, via, by, zone, own, members;  /* zone, own: slots; members: first of a chain, -1 */
    int32_t guard_len;
    int32_t child, sibling;  /* its first child in the tree and its next sibling, -1 for none (pruning's walks) */
    uint8_t grown, covered, expanded;
    uint8_t dead, skipped, covers;  /* pruned below a covered node; popped while dead; covered a newcomer */
} Node;
_Static_assert(sizeof(Node) == 56, "a Node is 56 bytes: millions are kept");

/* A step into a zone another node covers: what a trace and a lasso read of it (a Node's row without a zone, members
 * or flags of its own), in 32 bytes instead of a Node's 56.  A search keeps several times more of them than nodes. */
typedef struct {
    int32_t state, parent, via, by;
    int64_t guard;
    int32_t guard_len;
    uint8_t grown;
} Step;

typedef VEC(double) Doubles;
typedef VEC(int64_t) Longs;

/* n numbers appended to v at once (src NULL: left unwritten); -9: no memory. */
static int append(Doubles *v, const double *src, int64_t n)
{
    if (v->n + n > v->cap) {
        int64_t cap = v->cap ? v->cap : 64;
        while (cap < v->n + n)
            cap *= 2;
        double *a = realloc(v->a, cap * sizeof(double));
        if (!a)
            return -9;
        v->a = a, v->cap = cap;
    }
    if (src)  /* NULL: room only (append_active writes it) */
        memcpy(v->a + v->n, src, n * sizeof(double));
    v->n += n;
    return 0;
}

typedef struct { int32_t from, target, ref; } Edge;  /* ref >= 0: a node; ref < 0: step -ref-1 */
typedef struct { int32_t member, next; } Member;
/* A discrete state's zones not covered (node numbers); past SIG_FROM of them, each one's signature beside it. */
typedef struct { int32_t *a; int16_t *sig; int32_t n, cap; uint8_t seen; } Kept;

/* What a discrete state's stored zones keep (see layout_for). */
typedef struct {
    int nr, nc;         /* rows and columns kept */
    int *rows, *cols;   /* the clock of each, 0 first */
    int *rat;           /* per clock: the place of its row, -1 for an idle clock (no bound) */
    int *from;          /* per clock: the place its column is read from (0, column 0's, where it is left out) */
    int *zat;           /* per number stored: its index in the full matrix */
    int *idle, nidle;   /* the clocks freed */
    int64_t rlen;       /* numbers stored: nr * nc */
    int sigk;           /* numbers in a signature: row 0 and column 0 as stored, in whole blocks of 16 */
    uint64_t key;       /* hash of the idle clocks */
} Layout;

/* Zone slots of one precision, each as long as its layout says, one after the other in ``a``. */
typedef struct {
    char *a;
    int64_t used, cap;            /* bytes of a written, and allocated */
    int64_t *off;                 /* per slot: where it starts in a */
    int32_t *refs, *lay;          /* per slot: its users, its layout */
    int64_t n, ncap;              /* slots numbered, and room for */
    VEC(int64_t) free;            /* slot numbers let go */
    VEC(int64_t) *spare;          /* per count of numbers (d * d + 1 of them): places in a let go */
    int64_t held;                 /* bytes of the slots in use */
    int width;                    /* bytes per number */
} Pool;

typedef struct {
    int d, nobs, merge;
    double *ceiling;
    int *grow_only, ngrow;  /* clocks whose zones keep their upper bounds only (model.py's grow_only) */
    Pool shorts, floats;    /* zone slots (see slot_new) */
    int64_t *zkey, zcap, zused;  /* the zones stored once each: open addressing on slot + 1, 0 empty, -1 gone */
    VEC(Node) nodes;
    VEC(Step) steps;        /* steps into a zone another node covers */
    VEC(Edge) edges;
    VEC(Member) members;
    VEC(int64_t) guards;    /* bound triples */
    VEC(int32_t) waiting;
    int64_t head;
    /* per discrete state */
    VEC(int64_t *) prog;
    VEC(Kept) kept;
    int64_t discrete, transitions, merged, dropped;
    int32_t *violation;     /* per observer slot: first node, -1 */
    double *max_value;
    int32_t *max_node;      /* per clock: node of the largest value, -1 */
    int64_t err_arg;
    int failed;             /* why program() last gave NULL: -9 no memory, -1 the callback's error */
    double *tmp;            /* scratch zones */
    int ntmp;
    /* with the compiled step: programs written in C (zprogram.c), states kept as its words */
    Tables *tables;
    VEC(uint8_t) bytes;     /* states' words, each as it differs from the first state's (see encode) */
    VEC(int64_t) ends;      /* per state: where its bytes end */
    uint8_t *enc;           /* scratch: one state encoded */
    int64_t *ref;           /* the first state's words, which the others are written against (NULL before it) */
    int64_t *hash;          /* open addressing: state + 1, 0 empty */
    int64_t hcap;
    int64_t *inter_key, **inter_val, icap, icount;
    int64_t prog_words;     /* words held by programs */
    int told;               /* violations found when zs_run last looked */
    /* partial-order reduction where time cannot pass (runtime/zones/reduction.py computes the sets) */
    ample_fn ask_ample;     /* NULL: off */
    L amp;                  /* the set the last call answered: interactions to fire first; amp_all: all */
    int amp_all;
    int old_hit;            /* a step reached a zone already stored (add), since zs_run last cleared it */
    int64_t reduced;        /* expansions that left steps out */
    /* programs let go (see let_go): per state, its nodes waiting and whether C wrote its program */
    int32_t *pending, *plen;  /* grown with prog (grow_states); plen: words held, successors included */
    int32_t *body;          /* per state: where the successors kept after a program written in C begin (program) */
    uint8_t *in_c;
    VEC(int64_t) finished;  /* states whose nodes were all expanded, oldest first, from finished_head on */
    int64_t finished_head;
    int64_t budget;         /* bytes of programs held before finished states' are let go; 0: never */
    int64_t pinned;         /* the state being expanded: its program is read while its successors arrive */
    int64_t let_go, rewritten;
    int64_t level_end, depth;  /* breadth-first levels: the waiting list's end when the current one began */
    int prune;              /* the subtrees of covered nodes pruned (zs_set_prune) */
    int64_t pruned, revived;  /* nodes left unexpanded for it, and dead nodes brought back */
    int invariants;         /* points past an invariant are no state (search.py's ZoneExplorer.invariants) */
    int16_t *z16own;        /* scratch: slot_new's own stored 16-bit form of a zone (z16r may hold its caller's) */
    int32_t *past;          /* scratch: d * d numbers (union16, z_union) */
    int16_t *sig;           /* scratch: the signature of a zone being stored */
    int16_t *z16r;          /* scratch: a zone's stored 16-bit form */
    VEC(Layout) lays;       /* what stored zones keep, one layout per set of idle clocks (layout_for) */
    int32_t *lkey;          /* open addressing on a layout's key: its number + 1, 0 empty */
    int64_t lcap;
    int32_t *lay_of;        /* per state: its layout, -1 before its first zone (grown with prog) */
    int64_t kept_bytes;     /* the states' lists of zones kept, with their signatures */
    int64_t current;        /* the node being expanded (-1 before the first): those before it are expanded */
    VEC(int32_t) walk;      /* scratch: the nodes a pruning or a revival walks through */
    VEC(int32_t) back;      /* scratch: the nodes a revival queues again */
    VEC(int32_t) under;     /* scratch: the state's zones it includes (positions in its list) */
    Doubles out;            /* scratch: arrive's pieces after time passes, kept from call to call */
    Longs grown;            /* scratch: each piece's grown flag */
} Ctx;



static double *T(Ctx *x, int k) { return x->tmp + (int64_t)k * x->d * x->d; }

/* -- working zones: their active clocks (active.c) ---------------------------------------------------- */
/* The clocks a working zone keeps bounds between, ascending, 0 first; in[k]: whether clock k is one. */
typedef struct { int n; int c[256]; uint8_t in[256]; } Act;

/* The active clocks of a state's zones: its layout's rows. */
static void act_of(Act *a, const Layout *L, int d)
{
    memset(a->in, 0, d);
    a->n = L->nr;
    for (int r = 0; r < L->nr; r++)
        a->c[r] = L->rows[r], a->in[L->rows[r]] = 1;
}

static void act_copy(Act *to, const Act *from, int d)
{
    to->n = from->n;
    memcpy(to->c, from->c, from->n * sizeof(int));
    memcpy(to->in, from->in, d);
}

/* Clock k active, in its place; 1 when it was not (then its bounds are still to be written). */
static int act_add(Act *a, int k)
{
    if (a->in[k])
        return 0;
    int p = a->n++;
    for (; p > 0 && a->c[p - 1] > k; p--)
        a->c[p] = a->c[p - 1];
    a->c[p] = k, a->in[k] = 1;
    return 1;
}

/* The clocks the n bounds b read made active; those that were not appended to fr[*nf..] (no clock twice). */
static void act_reads(Act *a, const int64_t *b, int64_t n, int *fr, int *nf)
{
    for (int64_t k = 0; k < 3 * n; k += 3)
        for (int e = 0; e < 2; e++)
            if (act_add(a, (int)b[k + e]))
                fr[(*nf)++] = (int)b[k + e];
}

/* n numbers (a d x d matrix) appended to v, of which src's active entries are written; -9: no memory. */
static int append_active(Doubles *v, const double *src, int64_t n, int d, const Act *a)
{
    if (append(v, NULL, n))
        return -9;
    a_copy(v->a + v->n - n, src, d, a->c, a->n);
    return 0;
}

/* -- programs let go ----------------------------------------------------------------------------------
 * A discrete state's program is read when its nodes arrive and when they are expanded.  Once every node of a
 * state was expanded, its program is needed again only if a new zone of that state arrives; a program written
 * in C can then be written again from the state's words.  Past the budget, the programs of the states that
 * finished first are let go (breadth-first, a state's zones mostly arrive within a few levels of each other). */
static void let_go(Ctx *x)
{
    while (x->budget > 0 && x->prog_words * 8 > x->budget && x->finished_head < x->finished.n) {
        int64_t s = x->finished.a[x->finished_head++];
        if (s == x->pinned || x->pending[s] || !x->in_c[s] || !x->prog.a[s])
            continue;
        free(x->prog.a[s]);
        x->prog.a[s] = NULL;
        x->prog_words -= x->plen[s];
        x->let_go++;
    }
    if (x->finished_head > 4096 && x->finished_head * 2 > x->finished.n) {
        memmove(x->finished.a, x->finished.a + x->finished_head,
                (x->finished.n - x->finished_head) * sizeof(int64_t));
        x->finished.n -= x->finished_head;
        x->finished_head = 0;
    }
}

/* A node of ``state`` leaves the waiting list (expanded or covered); -9: no memory. */
static int node_done(Ctx *x, int64_t state)
{
    if (--x->pending[state] == 0 && x->budget > 0) {
        PUSH(x->finished, state);
    }
    return 0;
}

void zs_set_budget(void *p, int64_t bytes)
{
    ((Ctx *)p)->budget = bytes;
}

/* Programs let go, programs written again after being let go, and programs written in C held now. */
void zs_program_counts(void *p, int64_t *out)
{
    Ctx *x = p;
    out[0] = x->let_go, out[1] = x->rewritten, out[2] = 0;
    for (int64_t s = 0; s < x->prog.n; s++)
        out[2] += x->prog.a[s] && x->in_c[s];
}

/* -- what a stored zone keeps -------------------------------------------------------------------------
 * The zones of a discrete state all free the same clocks, the idle ones (add frees them once extrapolated, so their
 * rows and columns are the same function of the rest in every zone), and the clocks read only for how large they
 * grow keep their upper bounds only (forget_below: their column is column 0).  A layout says which numbers are
 * stored: the rows of 0 and of the active clocks, the columns of 0 and of the active clocks that are not grow-only.
 * The others follow: an idle clock's row has no bound, a column left out is column 0's, 0 on the diagonal.  Whole
 * DALA then stores 103 numbers of a zone instead of 629 on average, RobNav at two cores 137 instead of 276; a
 * merge's hull keeps the form.  Comparisons, signatures and the hash read the stored form, which two zones of
 * one state share; a zone is spread back whole when it is loaded. */
static uint64_t idle_key(const int64_t *idle, int64_t n)
{
    uint64_t h = 1469598103934665603ull ^ (uint64_t)n;
    for (int64_t k = 0; k < n; k++)
        h = (h ^ (uint64_t)idle[k]) * 1099511628211ull;
    return h | 1;
}

static int same_idle(const Layout *L, const int64_t *idle, int64_t n)
{
    if (L->nidle != n)
        return 0;
    for (int64_t k = 0; k < n; k++)
        if (L->idle[k] != idle[k])
            return 0;
    return 1;
}

/* The layout of the zones of a state whose idle clocks are idle[0..n) (ascending): its number, -9 without memory. */
static int32_t layout_for(Ctx *x, const int64_t *idle, int64_t n)
{
    uint64_t key = idle_key(idle, n);
    for (int64_t h = (int64_t)(key & (uint64_t)(x->lcap - 1)); x->lcap && x->lkey[h]; h = (h + 1) & (x->lcap - 1)) {
        const Layout *L = &x->lays.a[x->lkey[h] - 1];
        if (L->key == key && same_idle(L, idle, n))
            return x->lkey[h] - 1;
    }
    if (2 * (x->lays.n + 1) > x->lcap) {  /* the table grows first: nothing is half made without memory */
        int64_t cap = x->lcap ? 2 * x->lcap : 64;
        int32_t *t = calloc(cap, sizeof(int32_t));
        if (!t)
            return -9;
        for (int64_t i = 0; i < x->lays.n; i++) {
            int64_t h = (int64_t)(x->lays.a[i].key & (uint64_t)(cap - 1));
            while (t[h])
                h = (h + 1) & (cap - 1);
            t[h] = (int32_t)i + 1;
        }
        free(x->lkey);
        x->lkey = t, x->lcap = cap;
    }
    int d = x->d;
    Layout L = {0};
    unsigned char row_kept[256], col_kept[256];  /* per clock (d <= 256, as arrive's bounds) */
    memset(row_kept, 1, d), memset(col_kept, 1, d);
    for (int64_t k = 0; k < n; k++)
        row_kept[idle[k]] = col_kept[idle[k]] = 0;
    for (int g = 0; g < x->ngrow; g++)
        col_kept[x->grow_only[g]] = 0;
    for (int j = 0; j < d; j++)
        L.nr += row_kept[j], L.nc += col_kept[j];
    L.rlen = (int64_t)L.nr * L.nc;
    L.sigk = (L.nc - 1 + L.nr - 1 + 15) / 16 * 16;
    L.nidle = (int)n, L.key = key;
    int *block = malloc((L.nr + L.nc + 2 * d + L.rlen + n + 1) * sizeof(int));
    if (!block)
        return -9;
    L.rows = block, L.cols = L.rows + L.nr, L.rat = L.cols + L.nc, L.from = L.rat + d, L.zat = L.from + d;
    L.idle = L.zat + L.rlen;
    int r = 0, c = 0;
    for (int j = 0; j < d; j++) {
        L.rat[j] = row_kept[j] ? r : -1;
        L.from[j] = col_kept[j] ? c : 0;
        if (row_kept[j])
            L.rows[r++] = j;
        if (col_kept[j])
            L.cols[c++] = j;
    }
    for (int a = 0; a < L.nr; a++)
        for (int q = 0; q < L.nc; q++)
            L.zat[(int64_t)a * L.nc + q] = L.rows[a] * d + L.cols[q];
    for (int64_t k = 0; k < n; k++)
        L.idle[k] = (int)idle[k];
    PUSH_OR(x->lays, L, { free(block); return -9; });
    int64_t h = (int64_t)(key & (uint64_t)(x->lcap - 1));
    while (x->lkey[h])
        h = (h + 1) & (x->lcap - 1);
    x->lkey[h] = (int32_t)x->lays.n;
    return (int32_t)x->lays.n - 1;
}

/* The clocks read only for how large they grow (model.py's grow_only); before the search stores a zone. */
int zs_set_grow_only(void *p, const int *clocks, int n)
{
    Ctx *x = p;
    if (x->lays.n)
        return -2;
    free(x->grow_only);
    x->grow_only = malloc((n ? n : 1) * sizeof(int));
    if (!x->grow_only)
        return -9;
    memcpy(x->grow_only, clocks, n * sizeof(int));
    x->ngrow = n;
    return 0;
}

void zs_free(void *p);
static void pool_free(Pool *p, int d);

void *zs_new(int d, const double *ceiling, int nobs, int merge)
{
    Ctx *x = calloc(1, sizeof(Ctx));
    if (!x)
        return NULL;
    x->d = d, x->nobs = nobs, x->merge = merge;
    x->ntmp = 9;
    x->pinned = -1;
    x->depth = -1;
    x->current = -1;
    x->ceiling = malloc(d * sizeof(double));
    x->violation = malloc((nobs + 1) * sizeof(int32_t));
    x->max_value = calloc(d, sizeof(double));
    x->max_node = malloc(d * sizeof(int32_t));
    x->tmp = malloc((int64_t)x->ntmp * d * d * sizeof(double));
    x->z16own = malloc((int64_t)d * d * sizeof(int16_t));
    x->z16r = malloc((int64_t)d * d * sizeof(int16_t));
    x->past = malloc((int64_t)d * d * sizeof(int32_t));
    x->sig = malloc((2 * (int64_t)d + 16) * sizeof(int16_t));
    x->shorts.width = 2, x->floats.width = 4;
    x->shorts.spare = calloc((int64_t)d * d + 1, sizeof(*x->shorts.spare));
    x->floats.spare = calloc((int64_t)d * d + 1, sizeof(*x->floats.spare));
    if (!x->ceiling || !x->violation || !x->max_value || !x->max_node || !x->tmp || !x->z16own || !x->z16r || !x->past
        || !x->sig || !x->shorts.spare || !x->floats.spare) {
        zs_free(x);
        return NULL;
    }
    memcpy(x->ceiling, ceiling, d * sizeof(double));
    for (int i = 0; i <= nobs; i++)
        x->violation[i] = -1;
    for (int i = 0; i < d; i++)
        x->max_node[i] = -1;
    return x;
}

void zs_free(void *p)
{
    Ctx *x = p;
    if (!x)
        return;
    for (int64_t i = 0; i < x->prog.n; i++)
        free(x->prog.a[i]);
    for (int64_t i = 0; i < x->kept.n; i++)
        free(x->kept.a[i].a), free(x->kept.a[i].sig);
    free(x->amp.a);
    pool_free(&x->shorts, x->d), pool_free(&x->floats, x->d);
    for (int64_t i = 0; i < x->lays.n; i++)
        free(x->lays.a[i].rows);  /* the layout's one block */
    free(x->lays.a), free(x->lkey), free(x->lay_of);
    free(x->prog.a), free(x->kept.a), free(x->zkey), free(x->nodes.a), free(x->steps.a);
    free(x->edges.a), free(x->members.a), free(x->guards.a), free(x->waiting.a), free(x->ceiling), free(x->grow_only);
    free(x->walk.a), free(x->back.a);
    free(x->violation), free(x->max_value), free(x->max_node), free(x->tmp), free(x->z16own), free(x->past), free(x->sig);
    free(x->under.a), free(x->z16r);
    free(x->out.a), free(x->grown.a);
    free(x->pending), free(x->plen), free(x->in_c), free(x->body), free(x->finished.a);
    tables_free(x->tables);
    for (int64_t i = 0; i < x->icap; i++)
        free(x->inter_val ? x->inter_val[i] : NULL);
    free(x->inter_key), free(x->inter_val), free(x->bytes.a), free(x->ends.a), free(x->enc), free(x->ref), free(x->hash);
    free(x);
}

/* -- states as the compiled step's words, kept as they differ from the first state ---------------------- */
static uint64_t hash_bytes(const uint8_t *b, int64_t n)
{
    uint64_t h = 0x9e3779b97f4a7c15ull ^ (uint64_t)n;
    int64_t i = 0;
    if (n >= 64) {  /* four lanes at a time: one lane's multiplications wait on each other (a state's words, a zone) */
        uint64_t lane[4] = {h, 0xc2b2ae3d27d4eb4full, 0x165667b19e3779f9ull, 0x27d4eb2f165667c5ull};
        for (; i + 32 <= n; i += 32)
            for (int l = 0; l < 4; l++) {
                uint64_t v;
                memcpy(&v, b + i + 8 * l, 8);
                lane[l] = (lane[l] ^ v) * 0xff51afd7ed558ccdull;
                lane[l] ^= lane[l] >> 32;
            }
        h = lane[0] ^ (lane[1] << 17 | lane[1] >> 47) ^ (lane[2] << 31 | lane[2] >> 33) ^ (lane[3] << 47 | lane[3] >> 17);
    }
    for (; i + 8 <= n; i += 8) {
        uint64_t v;
        memcpy(&v, b + i, 8);
        h = (h ^ v) * 0xff51afd7ed558ccdull;
        h ^= h >> 32;
    }
    for (; i < n; i++)
        h = (h ^ b[i]) * 0x100000001b3ull;
    h ^= h >> 29;
    h *= 0xc4ceb9fe1a85ec53ull;
    return h ^ (h >> 32);
}

/* A state's words as stored: a bitmap of the words that differ from ref (the first state's), ceil(n / 8) bytes,
 * then those words' values as zigzag varints, in order.  A state of whole DALA has 324 words of which about 26
 * differ from the first one's: 70 bytes instead of 327 as varints alone.  One encoding per state, so equal words
 * are equal bytes (intern compares and hashes the bytes). */
/* Bit l set where w[l] differs from ref[l], for l < n (at most 8): no branch per word (most are equal). */
static inline unsigned differ8(const int64_t *w, const int64_t *ref, int n)
{
#ifdef __AVX2__  /* eight words compared in two instructions (-march=native on x86-64 machines of the last decade) */
    if (n == 8) {
        __m256i a0 = _mm256_loadu_si256((const __m256i *)w), a1 = _mm256_loadu_si256((const __m256i *)(w + 4));
        __m256i r0 = _mm256_loadu_si256((const __m256i *)ref), r1 = _mm256_loadu_si256((const __m256i *)(ref + 4));
        unsigned eq = (unsigned)_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(a0, r0)))
                      | (unsigned)_mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(a1, r1))) << 4;
        return ~eq & 0xffu;
    }
#endif
    unsigned bits = 0;
    for (int l = 0; l < n; l++)
        bits |= (unsigned)(w[l] != ref[l]) << l;
    return bits;
}

static int64_t encode(const int64_t *w, int n, const int64_t *ref, uint8_t *out)
{
    int64_t nb = (n + 7) / 8, k = nb;
    for (int64_t byte = 0; byte < nb; byte++) {  /* a byte of the bitmap, then its words' values */
        int base = (int)byte * 8;
        unsigned bits = differ8(w + base, ref + base, n - base < 8 ? n - base : 8);
        out[byte] = (uint8_t)bits;
        for (; bits; bits &= bits - 1) {
            int i = base + __builtin_ctz(bits);
            uint64_t v = ((uint64_t)w[i] << 1) ^ (uint64_t)(w[i] >> 63);
            while (v >= 0x80) {
                out[k++] = (uint8_t)(v | 0x80);
                v >>= 7;
            }
            out[k++] = (uint8_t)v;
        }
    }
    return k;
}

static const uint8_t *varint(const uint8_t *b, int64_t *w)
{
    uint64_t v = 0;
    int shift = 0;
    while (*b & 0x80) {
        v |= (uint64_t)(*b++ & 0x7f) << shift;
        shift += 7;
    }
    v |= (uint64_t)*b++ << shift;
    *w = (int64_t)(v >> 1) ^ -(int64_t)(v & 1);
    return b;
}

static void decode(const uint8_t *b, int n, const int64_t *ref, int64_t *w)
{
    const uint8_t *v = b + (n + 7) / 8;
    memcpy(w, ref, n * sizeof(int64_t));
    for (int byte = 0; byte < (n + 7) / 8; byte++)
        for (unsigned bits = b[byte]; bits; bits &= bits - 1)
            v = varint(v, w + 8 * byte + __builtin_ctz(bits));
}

static const uint8_t *state_bytes(const Ctx *x, int64_t s, int64_t *len)
{
    int64_t start = s ? x->ends.a[s - 1] : 0;
    *len = x->ends.a[s] - start;
    return x->bytes.a + start;
}

static void state_words(const Ctx *x, int64_t s, int64_t *w)
{
    int64_t len;
    decode(state_bytes(x, s, &len), x->tables->W, x->ref, w);
}

static int grow_states(Ctx *x, int64_t n)
{
    while (x->prog.n < n) {
        if (x->prog.n == x->prog.cap) {
            int64_t cap = x->prog.cap ? 2 * x->prog.cap : 1024;
            int64_t **a = realloc(x->prog.a, cap * sizeof(int64_t *));
            Kept *k = realloc(x->kept.a, cap * sizeof(Kept));
            int32_t *pe = realloc(x->pending, cap * sizeof(int32_t));
            int32_t *pl = realloc(x->plen, cap * sizeof(int32_t));
            uint8_t *c = realloc(x->in_c, cap);
            int32_t *lo = realloc(x->lay_of, cap * sizeof(int32_t));
            int32_t *bo = realloc(x->body, cap * sizeof(int32_t));
            x->prog.a = a ? a : x->prog.a, x->kept.a = k ? k : x->kept.a;  /* what moved is kept, to be freed */
            x->pending = pe ? pe : x->pending, x->plen = pl ? pl : x->plen, x->in_c = c ? c : x->in_c;
            x->lay_of = lo ? lo : x->lay_of, x->body = bo ? bo : x->body;
            if (!a || !k || !pe || !pl || !c || !lo || !bo)
                return -9;  /* the capacity stays what every array has */
            x->prog.cap = x->kept.cap = cap;
        }
        Kept none = {0};
        x->pending[x->prog.n] = 0, x->plen[x->prog.n] = 0, x->in_c[x->prog.n] = 0, x->lay_of[x->prog.n] = -1;
        x->body[x->prog.n] = 0;
        x->prog.a[x->prog.n++] = NULL;
        x->kept.a[x->kept.n++] = none;
    }
    return 0;
}

/* The number of the state stored as enc[0..k) (encode's form), given on first sight. */
static int64_t intern_encoded(Ctx *x, const uint8_t *enc, int64_t k)
{
    int64_t n = x->ends.n, len;
    if (2 * (n + 1) > x->hcap) {
        int64_t cap = x->hcap ? 2 * x->hcap : 4096;
        int64_t *h = calloc(cap, sizeof(int64_t));
        if (!h)
            return -9;
        for (int64_t s = 0; s < n; s++) {
            const uint8_t *b = state_bytes(x, s, &len);
            uint64_t i = hash_bytes(b, len) & (cap - 1);
            while (h[i])
                i = (i + 1) & (cap - 1);
            h[i] = s + 1;
        }
        free(x->hash);
        x->hash = h, x->hcap = cap;
    }
    uint64_t i = hash_bytes(enc, k) & (x->hcap - 1);
    while (x->hash[i]) {
        int64_t s = x->hash[i] - 1;
        const uint8_t *b = state_bytes(x, s, &len);
        if (len == k && !memcmp(b, enc, k))
            return s;
        i = (i + 1) & (x->hcap - 1);
    }
    if (x->bytes.n + k > x->bytes.cap) {
        int64_t cap = x->bytes.cap ? x->bytes.cap : 4096;
        while (cap < x->bytes.n + k)
            cap *= 2;
        uint8_t *a = realloc(x->bytes.a, cap);
        if (!a)
            return -9;
        x->bytes.a = a, x->bytes.cap = cap;
    }
    memcpy(x->bytes.a + x->bytes.n, enc, k);
    x->bytes.n += k;
    PUSH(x->ends, x->bytes.n);
    x->hash[i] = n + 1;
    if (grow_states(x, n + 1))
        return -9;
    return n;
}

/* The number of the state with these words, given on first sight. */
static int64_t intern(void *p, const int64_t *w)
{
    Ctx *x = p;
    int W = x->tables->W;
    if (!x->enc && !(x->enc = malloc(11 * (size_t)W + 1)))
        return -9;
    if (!x->ref) {  /* the first state: the others are written as they differ from it */
        if (!(x->ref = malloc(W * sizeof(int64_t))))
            return -9;
        memcpy(x->ref, w, W * sizeof(int64_t));
    }
    return intern_encoded(x, x->enc, encode(w, W, x->ref, x->enc));
}

int64_t zs_intern(void *p, const int64_t *w) { return intern(p, w); }

void zs_state_words(void *p, int64_t state, int64_t *out)
{
    Ctx *x = p;
    state_words(x, state, out);
}

int64_t zs_nstates(void *p)
{
    Ctx *x = p;
    return x->tables ? x->ends.n : x->prog.n;
}

int zs_set_tables(void *p, const int64_t *words, int64_t n, void *succ, int64_t budget, inter_fn ask_inter)
{
    Ctx *x = p;
    x->tables = tables_read(words, n);
    if (!x->tables)
        return -9;
    x->tables->succ = (succ_fn)succ, x->tables->budget = budget, x->tables->ask_inter = ask_inter;
    return 0;
}

void zs_set_step(void *p, void *succ)
{
    Ctx *x = p;
    x->tables->succ = (succ_fn)succ;
}

/* interaction rows by number (open addressing on the number) */
static int64_t *inter_find(Ctx *x, int64_t number)
{
    if (!x->icap)
        return NULL;
    uint64_t i = ((uint64_t)number * 11400714819323198485ull) & (x->icap - 1);
    while (x->inter_val[i]) {
        if (x->inter_key[i] == number)
            return x->inter_val[i];
        i = (i + 1) & (x->icap - 1);
    }
    return NULL;
}

int zs_set_interaction(void *p, int64_t number, const int64_t *words, int64_t n)
{
    Ctx *x = p;
    if (2 * (x->icount + 1) > x->icap) {
        int64_t cap = x->icap ? 2 * x->icap : 256;
        int64_t *k = calloc(cap, sizeof(int64_t));
        int64_t **v = calloc(cap, sizeof(int64_t *));
        if (!k || !v) {
            free(k), free(v);
            return -9;
        }
        for (int64_t j = 0; j < x->icap; j++)
            if (x->inter_val[j]) {
                uint64_t i = ((uint64_t)x->inter_key[j] * 11400714819323198485ull) & (cap - 1);
                while (v[i])
                    i = (i + 1) & (cap - 1);
                k[i] = x->inter_key[j], v[i] = x->inter_val[j];
            }
        free(x->inter_key), free(x->inter_val);
        x->inter_key = k, x->inter_val = v, x->icap = cap;
    }
    int64_t *row = malloc((n ? n : 1) * sizeof(int64_t));
    if (!row)
        return -9;
    memcpy(row, words, n * sizeof(int64_t));
    uint64_t i = ((uint64_t)number * 11400714819323198485ull) & (x->icap - 1);
    while (x->inter_val[i])
        i = (i + 1) & (x->icap - 1);
    x->inter_key[i] = number, x->inter_val[i] = row, x->icount++;
    return 0;
}

static int64_t *inter_row(void *p, Tables *t, int64_t number)
{
    Ctx *x = p;
    int64_t *row = inter_find(x, number);
    if (!row && t->ask_inter(number) == 0)
        row = inter_find(x, number);
    return row;
}

/* -- zone slots ------------------------------------------------------------------------------------
 * A zone whose every finite bound lies within +-32766 is kept in 16 bits (infinity as 32767): a quarter of a
 * double matrix.  Others are kept in single precision (every bound an integer far below 2^24).  A slot number
 * says which: even numbers are 16-bit slots (number / 2), odd ones single precision ((number - 1) / 2). */
#define SHORT_INF 32767

/* A slot of len numbers with layout lay: its number in p, -1 without memory (then nothing is taken). */
static int64_t pool_take(Pool *p, int64_t len, int32_t lay)
{
    int64_t size = len * p->width;
    if (!p->free.n && p->n == p->ncap) {
        int64_t cap = p->ncap ? 2 * p->ncap : 1024;
        int64_t *off = realloc(p->off, cap * sizeof(int64_t));
        if (!off)
            return -1;
        p->off = off;  /* at once: realloc may have moved it */
        int32_t *refs = realloc(p->refs, cap * sizeof(int32_t));
        if (!refs)
            return -1;
        p->refs = refs;
        int32_t *lays = realloc(p->lay, cap * sizeof(int32_t));
        if (!lays)
            return -1;
        p->lay = lays, p->ncap = cap;
    }
    if (!p->spare[len].n && p->used + size > p->cap) {
        int64_t cap = p->cap ? 2 * p->cap : 1 << 16;
        while (cap < p->used + size)
            cap *= 2;
        char *a = realloc(p->a, cap);
        if (!a)
            return -1;
        p->a = a, p->cap = cap;
    }
    int64_t at;
    if (p->spare[len].n) {
        at = p->spare[len].a[--p->spare[len].n];
    } else {
        at = p->used;
        p->used += size;
    }
    int64_t id = p->free.n ? p->free.a[--p->free.n] : p->n++;
    p->off[id] = at, p->lay[id] = lay, p->held += size;
    return id;
}

/* Slot id of p (len numbers) let go: its number and its place are taken again; -9 without memory to remember
 * them (they are then lost, not reused). */
static int pool_give(Pool *p, int64_t id, int64_t len)
{
    p->held -= len * p->width;
    PUSH(p->free, id);
    PUSH(p->spare[len], p->off[id]);
    return 0;
}

static void pool_free(Pool *p, int d)
{
    if (p->spare)
        for (int64_t len = 0; len <= (int64_t)d * d; len++)
            free(p->spare[len].a);
    free(p->spare), free(p->a), free(p->off), free(p->refs), free(p->lay), free(p->free.a);
}

/* -- zones stored once each ------------------------------------------------------------------------
 * Most symbolic states share their zone with others (whole DALA on two cores: 76,423 stored zones, 1,847
 * different), so a zone slot is shared and counted: slot_new finds an equal zone of the same layout through a hash
 * table and slot_drop lets a slot go with its last user.  Slots are never changed once written. */
static const Pool *pool_of(const Ctx *x, int64_t s)
{
    return s & 1 ? &x->floats : &x->shorts;
}

static const Layout *slot_layout(const Ctx *x, int64_t s)
{
    return &x->lays.a[pool_of(x, s)->lay[s >> 1]];
}

static const char *slot_bytes(const Ctx *x, int64_t s)
{
    const Pool *p = pool_of(x, s);
    return p->a + p->off[s >> 1];
}

static int32_t *slot_refs(Ctx *x, int64_t s)
{
    return s & 1 ? &x->floats.refs[s >> 1] : &x->shorts.refs[s >> 1];
}

static int64_t slot_size(const Ctx *x, int64_t s)
{
    return slot_layout(x, s)->rlen * pool_of(x, s)->width;
}

static uint64_t slot_hash(const Ctx *x, int64_t s)
{
    uint64_t lay = (uint64_t)pool_of(x, s)->lay[s >> 1];
    return hash_bytes((const uint8_t *)slot_bytes(x, s), slot_size(x, s)) ^ (uint64_t)(s & 1)
           ^ (lay * 0x9E3779B97F4A7C15ull);
}

static int zkey_grow(Ctx *x)
{
    int64_t cap = x->zcap ? 2 * x->zcap : 4096, *old = x->zkey, ocap = x->zcap;
    int64_t *key = calloc(cap, sizeof(int64_t));
    if (!key)
        return -1;
    x->zkey = key, x->zcap = cap, x->zused = 0;
    for (int64_t i = 0; i < ocap; i++)
        if (old[i] > 0) {
            int64_t h = (int64_t)(slot_hash(x, old[i] - 1) & (uint64_t)(cap - 1));
            while (key[h])
                h = (h + 1) & (cap - 1);
            key[h] = old[i], x->zused++;
        }
    free(old);
    return 0;
}

/* The stored form of full zone z in 16 bits (infinity as SHORT_INF) into out; 1 when every number fits, else out is
 * not z's.  Without branches, so that the compiler vectorises the conversion (dbm.c's pragma). */
static int gather_short(const Layout *L, const double *restrict z, int16_t *restrict out)
{
    int bad = 0;
    for (int64_t q = 0; q < L->rlen; q++) {
        double v = z[L->zat[q]];
        bad |= (v < -(SHORT_INF - 1)) | ((v > SHORT_INF - 1) & (v != INFINITY));
        double c = v > SHORT_INF ? SHORT_INF : v;
        c = c < -SHORT_INF ? -SHORT_INF : c;
        out[q] = (int16_t)(int32_t)c;
    }
    return !bad;
}

/* The slot of zone z of a state of layout lay: an equal stored zone's (one more user), or a new one; -1 without
 * memory.  ``r16``: z's stored 16-bit form if the caller has it (gather_short said it fits), else NULL. */
static int64_t slot_new(Ctx *x, int32_t lay, const double *z, const int16_t *r16)
{
    const Layout *L = &x->lays.a[lay];
    int64_t rlen = L->rlen;
    if (!r16 && gather_short(L, z, x->z16own))
        r16 = x->z16own;
    Pool *p = r16 ? &x->shorts : &x->floats;
    if (2 * (x->zused + 1) > x->zcap && zkey_grow(x))
        return -1;
    int64_t id = pool_take(p, rlen, lay);
    if (id < 0)
        return -1;
    if (r16) {
        memcpy(p->a + p->off[id], r16, rlen * sizeof(int16_t));
    } else {
        float *dst = (float *)(p->a + p->off[id]);
        for (int64_t q = 0; q < rlen; q++)
            dst[q] = (float)z[L->zat[q]];
    }
    int64_t s = 2 * id + !r16, size = rlen * p->width, mask = x->zcap - 1;
    int64_t h = (int64_t)(slot_hash(x, s) & (uint64_t)mask), hole = -1;
    for (; x->zkey[h]; h = (h + 1) & mask) {
        int64_t t = x->zkey[h] - 1;
        if (t < 0) {
            if (hole < 0)
                hole = h;
            continue;
        }
        if ((t & 1) == (s & 1) && pool_of(x, t)->lay[t >> 1] == lay
            && !memcmp(slot_bytes(x, t), slot_bytes(x, s), size)) {
            if (pool_give(p, id, rlen))  /* the copy just written goes back */
                return -1;
            (*slot_refs(x, t))++;
            return t;
        }
    }
    if (hole < 0)
        hole = h, x->zused++;
    x->zkey[hole] = s + 1;
    *slot_refs(x, s) = 1;
    return s;
}

/* Stored number q of slot s. */
static double stored(const Ctx *x, int64_t s, int64_t q)
{
    if (s & 1)
        return ((const float *)slot_bytes(x, s))[q];
    int16_t v = ((const int16_t *)slot_bytes(x, s))[q];
    return v == SHORT_INF ? INFINITY : v;
}

/* Entry (i, j) of slot s's full matrix. */
static double entry(const Ctx *x, int64_t s, int i, int j)
{
    const Layout *L = slot_layout(x, s);
    if (i == j)
        return 0;
    if (L->rat[i] < 0)
        return INFINITY;
    return stored(x, s, (int64_t)L->rat[i] * L->nc + L->from[j]);
}

/* Slot s's stored rows spread into z, each at the columns cols[0..nc); 0 on the diagonal. */
static void slot_rows(Ctx *x, int64_t s, double *z, const int *cols, int nc)
{
    const Layout *L = slot_layout(x, s);
    int d = x->d;
    const char *b = slot_bytes(x, s);
    for (int r = 0; r < L->nr; r++) {  /* a column left out is column 0's */
        int a = L->rows[r];
        double *za = z + (int64_t)a * d;
        if (s & 1) {
            const float *ra = (const float *)b + (int64_t)r * L->nc;
            for (int q = 0; q < nc; q++)
                za[cols[q]] = ra[L->from[cols[q]]];
        } else {
            const int16_t *ra = (const int16_t *)b + (int64_t)r * L->nc;
            for (int q = 0; q < nc; q++) {
                int16_t v = ra[L->from[cols[q]]];
                za[cols[q]] = v == SHORT_INF ? INFINITY : v;
            }
        }
        za[a] = 0;
    }
}

/* Slot s's whole matrix into z: an idle clock's row has no bound. */
static void slot_load(Ctx *x, int64_t s, double *z)
{
    const Layout *L = slot_layout(x, s);
    int d = x->d, all[256];
    for (int j = 0; j < d; j++) {
        all[j] = j;
        if (L->rat[j] < 0) {
            double *zj = z + (int64_t)j * d;
            for (int k = 0; k < d; k++)
                zj[k] = INFINITY;
            zj[j] = 0;
        }
    }
    slot_rows(x, s, z, all, d);
}

/* Slot s's bounds between its state's active clocks (its layout's rows) into z, the rest of z left as it was. */
static void slot_load_active(Ctx *x, int64_t s, double *z)
{
    const Layout *L = slot_layout(x, s);
    slot_rows(x, s, z, L->rows, L->nr);
}

static int slot_geq(Ctx *x, int64_t s, const double *z)  /* the stored zone includes z (of its state) */
{
    const Layout *L = slot_layout(x, s);
    for (int64_t q = 0; q < L->rlen; q++)
        if (stored(x, s, q) < z[L->zat[q]])
            return 0;
    return 1;
}

static int slot_leq(Ctx *x, int64_t s, const double *z)  /* z (of its state) includes the stored zone */
{
    const Layout *L = slot_layout(x, s);
    for (int64_t q = 0; q < L->rlen; q++)
        if (stored(x, s, q) > z[L->zat[q]])
            return 0;
    return 1;
}

/* Both inclusions between two 16-bit zones at once (SHORT_INF, the largest value, stands for infinity): *ge when a
 * includes b, *le when b includes a; it stops as soon as neither can hold. */
static void compare16(const int16_t *a, const int16_t *b, int64_t len, int *ge, int *le)
{
    int g = 1, l = 1;
    int64_t k = 0;
    for (; k + 16 <= len && (g | l); k += 16)
        for (int j = 0; j < 16; j++) {
            g &= a[k + j] >= b[k + j];
            l &= a[k + j] <= b[k + j];
        }
    for (; k < len && (g | l); k++) {
        g &= a[k] >= b[k];
        l &= a[k] <= b[k];
    }
    *ge = g, *le = l;
}

static int slot_drop(Ctx *x, int64_t s)
{
    if (--*slot_refs(x, s) > 0)
        return 0;
    int64_t mask = x->zcap - 1, h = (int64_t)(slot_hash(x, s) & (uint64_t)mask);
    while (x->zkey[h] != s + 1)
        h = (h + 1) & mask;
    x->zkey[h] = -1;
    return pool_give(s & 1 ? &x->floats : &x->shorts, s >> 1, slot_layout(x, s)->rlen);
}

static int64_t zone_bytes(const Ctx *x)
{
    return x->shorts.held + x->floats.held + x->zcap * 8 + (x->shorts.ncap + x->floats.ncap) * 16;
}

/* -- zone operations that dbm.c does not have --------------------------------------------------------- */
/* Pieces of m minus other (integer complements), as dbm.py's subtract_bounds, on the active clocks of A (both are
 * zones on them): each piece appended to *out (d*d numbers each, A's entries written), with the cut bounds that made
 * it appended to *cuts and their count to *ncut; -9: no memory. */
static int subtract(const double *m, const double *other, int d, const Act *A, double *rest, double *piece,
                    Doubles *out, Longs *cuts, Longs *ncut)
{
    int64_t len = (int64_t)d * d;
    const int *act = A->c;
    int na = A->n;
    a_copy(rest, m, d, act, na);
    Longs kept = {0};  /* the bounds kept so far: each piece copies them, then its cut */
    for (int a = 0; a < na; a++)
        for (int b = 0; b < na; b++) {
            int i = act[a], j = act[b];
            double c = other[(int64_t)i * d + j];
            if (i == j || c == INFINITY || rest[(int64_t)i * d + j] <= c)
                continue;
            a_copy(piece, rest, d, act, na);
            if (a_constrain(piece, d, act, na, j, i, -c - 1)) {
                if (append_active(out, piece, len, d, A))
                    goto nomem;
                for (int64_t k = 0; k < kept.n; k++)
                    PUSH_OR(*cuts, kept.a[k], goto nomem);
                PUSH_OR(*cuts, j, goto nomem); PUSH_OR(*cuts, i, goto nomem);
                PUSH_OR(*cuts, (int64_t)(-c - 1), goto nomem);
                PUSH_OR(*ncut, kept.n / 3 + 1, goto nomem);
            }
            if (!a_constrain(rest, d, act, na, i, j, c))
                goto done;
            PUSH_OR(kept, i, goto nomem); PUSH_OR(kept, j, goto nomem); PUSH_OR(kept, (int64_t)c, goto nomem);
        }
done:
    free(kept.a);
    return 0;
nomem:
    free(kept.a);
    return -9;
}

/* -- programs --------------------------------------------------------------------------------------- */
/* The step's successors of the state whose program was just written (b), appended to it as intern keeps states
 * (encode's form: about 70 bytes each on whole DALA), so that its expansion interns them without stepping the state
 * again: their count, then each one's length in bytes and its bytes, eight to a word.  0, or -9 without memory. */
static int keep_successors(Ctx *x, const SuccBuf *b, L *prog)
{
    int W = x->tables->W;
    if (lpush(prog, b->n))
        return -9;
    for (int64_t j = 0; j < b->n; j++) {
        int64_t k = encode(b->words + j * W, W, x->ref, x->enc), at = prog->n + 1;
        for (int64_t w = 0; w < 1 + (k + 7) / 8; w++)
            if (lpush(prog, 0))
                return -9;
        prog->a[at - 1] = k;
        memcpy(prog->a + at, x->enc, k);
    }
    return 0;
}

/* Successor k (from 0) of those keep_successors appended to a program: its bytes, and their length in *len; NULL
 * when the step gave fewer. */
static const uint8_t *kept_successor(const int64_t *kept, int64_t k, int64_t *len)
{
    if (k >= kept[0])
        return NULL;
    const int64_t *at = kept + 1;
    for (int64_t j = 0; j < k; j++)
        at += 1 + (at[0] + 7) / 8;
    *len = at[0];
    return (const uint8_t *)(at + 1);
}

/* The program of a state, written now if the search has none; NULL with x->failed -9 (no memory) or -1 (the
 * callback's error, kept by csearch.py). */
static int64_t *program(Ctx *x, int64_t state, program_fn ask)
{
    x->failed = -9;
    if (grow_states(x, state + 1))
        return NULL;
    if (x->prog.a[state])
        return x->prog.a[state];
    if (x->tables) {
        int W = x->tables->W;
        int64_t *s = malloc(W * sizeof(int64_t));  /* interning successors may move the words */
        if (!s)
            return NULL;
        state_words(x, state, s);
        L prog = {0};
        int status = write_program(x, x->tables, s, x->d, T(x, 8), &prog);
        free(s);
        int64_t body = prog.n;
        if (!status)
            status = keep_successors(x, &x->tables->wbuf, &prog);
        if (!status) {
            let_go(x);  /* first: a state finished twice may still be queued, and this one must stay */
            x->rewritten += x->in_c[state];
            x->in_c[state] = 1, x->plen[state] = (int32_t)prog.n, x->body[state] = (int32_t)body;
            x->prog_words += prog.n;
            x->prog.a[state] = prog.a ? prog.a : calloc(1, sizeof(int64_t));
            /* a state with no node waiting may be let go again once its zone has arrived: one let go before and
             * written again for a zone that something covers would otherwise be held to the end (a state that
             * gets a node waiting is skipped by let_go, and queued again when its last node leaves) */
            if (x->budget > 0 && !x->pending[state])
                PUSH_OR(x->finished, state, return NULL);
            return x->prog.a[state];
        }
        free(prog.a);
        if (status != BACK) {
            x->failed = status == -9 ? -9 : -1;
            return NULL;
        }
    }
    x->failed = -1;
    if (!ask || ask(state) != 0)
        return NULL;
    return x->prog.a[state];
}

int zs_set_program(void *p, int64_t state, const int64_t *words, int64_t n)
{
    Ctx *x = p;
    if (state >= x->prog.n)
        return -1;
    int64_t *copy = malloc((n ? n : 1) * sizeof(int64_t));
    if (!copy)
        return -9;
    memcpy(copy, words, n * sizeof(int64_t));
    x->prog.a[state] = copy;
    x->in_c[state] = 0, x->plen[state] = (int32_t)n;  /* names its successors by number: none kept after it */
    x->prog_words += n;
    return 0;
}

/* The subtree of a node that a larger zone covers once it was expanded is not expanded further (1, search.py's
 * ZoneExplorer.prune) or it is (0). */
void zs_set_prune(void *p, int on)
{
    ((Ctx *)p)->prune = on;
}

/* Points past an invariant are no state (1) or a piece where time cannot pass (0, the default). */
void zs_set_invariants(void *p, int on)
{
    ((Ctx *)p)->invariants = on;
}

/* The partial-order reduction on (``ask``: called with a node whose state lets no time pass, it answers with
 * zs_set_ample) or off (NULL). */
void zs_set_por(void *p, ample_fn ask)
{
    ((Ctx *)p)->ask_ample = ask;
}

/* The interactions to fire first at the node asked about; n < 0: all of them. */
int zs_set_ample(void *p, const int64_t *vias, int64_t n)
{
    Ctx *x = p;
    x->amp.n = 0;
    x->amp_all = n < 0;
    if (lpush(&x->amp, n < 0 ? 0 : n) || (n > 0 && lcat(&x->amp, vias, n)))
        return -9;
    return 0;
}

static int in_list(const int64_t *list, int64_t v)
{
    for (int64_t i = 1; i <= list[0]; i++)
        if (list[i] == v)
            return 1;
    return 0;
}

/* Where the parts of a program start (the layout above). */
typedef struct { const int64_t *idle, *ceil, *pass, *checks, *succ; int64_t nidle, nceil; } Parts;

static const int64_t *skip_bounds(const int64_t *p) { return p + 1 + 3 * p[0]; }

static Parts parts(const int64_t *p)
{
    Parts q;
    q.nidle = p[0], q.idle = p + 1;
    p += 1 + p[0];
    q.nceil = p[0], q.ceil = p + 1;
    p += 1 + 3 * p[0];
    q.pass = p;
    if (*p++) {
        p = skip_bounds(p);
        p = skip_bounds(p);
        int64_t nw = *p++;
        for (int64_t w = 0; w < nw; w++)
            p = skip_bounds(p) + 4;
    }
    q.checks = p;
    p += 1 + 4 * p[0];
    q.succ = p;
    return q;
}

/* One successor of a program (the header's layout, after next state and interaction): its guard's bounds (need: n,
 * triples), its resets (n, pairs) and the regions where priorities block it (nblocks of them, each n, triples). */
typedef struct { const int64_t *need, *resets, *blocks; int64_t nblocks; } SuccEntry;

/* Successor entry s read into e; the entry after it. */
static const int64_t *succ_entry(const int64_t *s, SuccEntry *e)
{
    e->need = s + 2, e->resets = skip_bounds(e->need);
    const int64_t *bl = e->resets + 1 + 2 * e->resets[0];
    e->nblocks = *bl++;
    e->blocks = bl;
    for (int64_t k = 0; k < e->nblocks; k++)
        bl = skip_bounds(bl);
    return bl;
}

/* -- time passing (search.py's limits and elapse) --------------------------------------------------- */
/* The pieces of z (a zone on A's clocks) after time passes at a state where it can (``pass``: that part of the
 * state's program), appended to out with their grown flags; returns the number of pieces, -2 for a wait that is not
 * one lower bound (err_arg: the rule), or -9 without memory. */
static int64_t elapse(Ctx *x, const int64_t *pass, double *z, const Act *A, Doubles *out, Longs *grown)
{
    int d = x->d, na = A->n;
    const int *act = A->c;
    int64_t len = (int64_t)d * d;
    const int64_t *before = pass + 1, *after = skip_bounds(before), *w = skip_bounds(after);
    if (x->invariants && !a_constrain_all(z, d, act, na, after + 1, after[0]))
        return 0;  /* z (the caller's scratch) is past an invariant everywhere: no state */
    int64_t nw = *w++;
    Longs extra = {0};  /* a wait's lower bound: time passes up to it */
    if (nw) {
        double *reach = T(x, 4), *probe = T(x, 5);
        a_copy(reach, z, d, act, na);
        a_up(reach, d, act, na);
        int live = a_constrain_all(reach, d, act, na, before + 1, before[0]);
        for (int64_t k = 0; k < nw; k++) {
            const int64_t *b = w;
            w = skip_bounds(w);
            int64_t kind = w[0], clock = w[1], c = w[2], rule = w[3];
            w += 4;
            if (!live)
                continue;
            a_copy(probe, reach, d, act, na);
            if (!a_constrain_all(probe, d, act, na, b + 1, b[0]))
                continue;
            if (!kind) {
                x->err_arg = rule;
                free(extra.a);
                return -2;
            }
            PUSH_OR(extra, clock, goto nomem); PUSH_OR(extra, 0, goto nomem); PUSH_OR(extra, -c, goto nomem);
        }
    }
    double *start = T(x, 4), *piece = T(x, 5);
    a_copy(start, z, d, act, na);
    int ok = a_constrain_all(start, d, act, na, after + 1, after[0])
             && a_constrain_all(start, d, act, na, extra.a, extra.n / 3);
    int64_t count = 1;
    if (!ok) {
        if (append_active(out, z, len, d, A))
            goto nomem;
        PUSH_OR(*grown, 0, goto nomem);
    } else {
        a_up(start, d, act, na);
        a_constrain_all(start, d, act, na, after + 1, after[0]);
        a_constrain_all(start, d, act, na, extra.a, extra.n / 3);
        if (append_active(out, start, len, d, A))
            goto nomem;
        PUSH_OR(*grown, 1, goto nomem);
        Longs cuts = {0}, ncut = {0};
        int64_t before_n = out->n;
        int cut = subtract(z, start, d, A, T(x, 6), piece, out, &cuts, &ncut);
        free(cuts.a), free(ncut.a);
        if (cut)
            goto nomem;
        count = 1 + (out->n - before_n) / len;
        for (int64_t k = 1; k < count; k++)
            PUSH_OR(*grown, 0, goto nomem);
    }
    free(extra.a);
    return count;
nomem:
    free(extra.a);
    return -9;
}

/* -- the store (search.py's add and merge_into) ----------------------------------------------------- */
static int add_member(Ctx *x, Node *step, int32_t k)
{
    Member m = {k, -1};
    if (step->members < 0) {
        step->members = (int32_t)x->members.n;
    } else {
        int32_t t = step->members;
        while (x->members.a[t].next >= 0)
            t = x->members.a[t].next;
        x->members.a[t].next = (int32_t)x->members.n;
    }
    PUSH(x->members, m);
    return 0;
}

/* -- signatures -------------------------------------------------------------------------------------
 * A state with many zones compares each new zone with every one of them, most in vain, and each comparison loads
 * a zone from anywhere in the pools.  Past SIG_FROM zones, the state keeps beside each one its row 0 and column 0
 * as stored (every active clock's lower and upper bound, padded with zeros to the layout's sigk, a whole number of
 * blocks of 16 that vectorise without a scalar tail), side by side: a zone that neither includes nor is
 * included in the new one there is passed over without being loaded (on RobNav at three cores, 94 % of the pairs
 * of a state's zones).  The full comparison decides the others, so the search stores the same nodes.  A zone
 * whose bounds do not fit in 16 bits has SIG_NONE as its first number: it is always compared in full. */
#define SIG_FROM 16
#define SIG_NONE INT16_MIN

/* The signature of a zone from its stored 16-bit form (NULL: it has none, SIG_NONE): row 0, column 0, zeros
 * after. */
static void sig_of(const Layout *L, const int16_t *z16, int16_t *out)
{
    int k = 0;
    if (!z16) {
        out[0] = SIG_NONE;
        return;
    }
    for (int q = 1; q < L->nc; q++)  /* row 0 (its columns left out are 0, the same for every zone) */
        out[k++] = z16[q];
    for (int a = 1; a < L->nr; a++)  /* column 0 (an idle clock's row has no bound in every zone) */
        out[k++] = z16[(int64_t)a * L->nc];
    while (k < L->sigk)
        out[k++] = 0;
}

static void sig_of_slot(const Ctx *x, const Layout *L, int64_t slot, int16_t *out)
{
    sig_of(L, slot & 1 ? NULL : (const int16_t *)slot_bytes(x, slot), out);
}

/* Node v (its zone in ``slot``) joins the state's list. */
static int kept_push(Ctx *x, const Layout *L, Kept *k, int32_t v, int64_t slot)
{
    int K = L->sigk;
    if (k->n == k->cap) {
        int32_t cap = k->cap ? 2 * k->cap : 4;
        int32_t *a = realloc(k->a, cap * sizeof(int32_t));
        if (!a)
            return -9;
        k->a = a;
        if (k->sig) {
            int16_t *g = realloc(k->sig, (int64_t)cap * K * sizeof(int16_t));
            if (!g)
                return -9;
            k->sig = g;
        }
        x->kept_bytes += (int64_t)(cap - k->cap) * ((int64_t)sizeof(int32_t) + (k->sig ? K * 2 : 0));
        k->cap = cap;
    }
    k->a[k->n++] = v;
    if (k->sig) {
        sig_of_slot(x, L, slot, k->sig + (int64_t)(k->n - 1) * K);
    } else if (k->n >= SIG_FROM && K > 0) {  /* from now on: the signatures of those kept so far */
        if (!(k->sig = malloc((int64_t)k->cap * K * sizeof(int16_t))))
            return -9;
        x->kept_bytes += (int64_t)k->cap * K * 2;
        for (int32_t i = 0; i < k->n - 1; i++)
            sig_of_slot(x, L, x->nodes.a[k->a[i]].zone, k->sig + (int64_t)i * K);
        sig_of_slot(x, L, slot, k->sig + (int64_t)(k->n - 1) * K);
    }
    return 0;
}

/* The entries at positions pos[0..n) (ascending) leave the state's list, which keeps its order. */
static void kept_remove(const Layout *L, Kept *kept, const int32_t *pos, int64_t n)
{
    int K = L->sigk;
    int32_t w = pos[0];
    for (int32_t i = pos[0], q = 0; i < kept->n; i++) {
        if (q < n && pos[q] == i) {
            q++;
            continue;
        }
        if (kept->sig)
            memcpy(kept->sig + (int64_t)w * K, kept->sig + (int64_t)i * K, K * sizeof(int16_t));
        kept->a[w++] = kept->a[i];
    }
    kept->n = w;
}

/* The first position of the state's list whose node was not expanded yet: nodes are expanded in the order they
 * are stored, and a list holds its nodes in that order, so those after the node being expanded. */
static int32_t first_open(const Ctx *x, const Kept *kept)
{
    int32_t lo = 0, hi = kept->n;
    while (lo < hi) {
        int32_t mid = (lo + hi) / 2;
        if (kept->a[mid] <= x->current)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Whether two signatures leave room for an inclusion either way: a's bounds all at least b's, or all at most.
 * Each of the 16 lanes keeps its own verdicts over the blocks, told apart once at the end (a verdict folded into
 * one number after every block cost more than the comparisons: a state with many zones runs this for each). */
static int sig_may(const int16_t *a, const int16_t *b, int K)
{
    if (a[0] == SIG_NONE)
        return 1;
    int16_t g[16], l[16];
    for (int j = 0; j < 16; j++)
        g[j] = l[j] = -1;
    for (int k = 0; k < K; k += 16)  /* K is a whole number of blocks of 16 */
        for (int j = 0; j < 16; j++) {
            g[j] &= (int16_t)-(a[k + j] >= b[k + j]);
            l[j] &= (int16_t)-(a[k + j] <= b[k + j]);
        }
    int16_t all_g = -1, all_l = -1;
    for (int j = 0; j < 16; j++)
        all_g &= g[j], all_l &= l[j];
    return (all_g | all_l) != 0;
}

/* Entry (i, j) of a zone's full matrix from its stored 16-bit form. */
static int32_t full16(const Layout *L, const int16_t *r, int i, int j)
{
    if (i == j)
        return 0;
    return L->rat[i] < 0 ? SHORT_INF : r[(int64_t)L->rat[i] * L->nc + L->from[j]];
}

/* Whether bound (i, j) of a, beyond which b goes (a[i][j] = c), and bound (k, l) of b, beyond which a goes, leave
 * a point of the hull in neither (z_union's test, on stored forms; SHORT_INF: no bound). */
static int apart16(const Layout *L, const int16_t *a, const int16_t *b, int i, int j, int32_t c, int k, int l)
{
    int32_t ail = full16(L, a, i, l), bil = full16(L, b, i, l), akj = full16(L, a, k, j), bkj = full16(L, b, k, j);
    int32_t il = ail > bil ? ail : bil, kj = akj > bkj ? akj : bkj;
    return il == SHORT_INF || kj == SHORT_INF || il + kj >= c + full16(L, b, k, l) + 2;
}

/* dbm.c's z_union on two zones' stored 16-bit forms, without the hull, as a first test: 0 when a pair of their
 * bounds shows a point of the hull in neither (exact for that pair), 1 when none of the pairs of stored bounds
 * does (z_union then decides on the whole matrices).  The first bound of a that b goes beyond is tested against
 * each bound of b that a goes beyond as the scan meets it, which tells most pairs apart before the scan ends; the
 * others are tested pair by pair after.  past: room for d * d numbers. */
static int union16(const Layout *L, const int16_t *a, const int16_t *b, int32_t *past)
{
    int64_t len = L->rlen;
    int nc = L->nc, n = 0, i0 = -1, j0 = -1;
    const int *rows = L->rows, *cols = L->cols;
    int32_t c0 = 0;
    for (int64_t q = 0; q < len; q++) {
        if (i0 < 0 && b[q] > a[q]) {
            i0 = rows[q / nc], j0 = cols[q % nc], c0 = a[q];
            for (int p = 0; p < n; p++)
                if (apart16(L, a, b, i0, j0, c0, rows[past[p] / nc], cols[past[p] % nc]))
                    return 0;
        }
        if (a[q] > b[q]) {
            if (i0 >= 0 && apart16(L, a, b, i0, j0, c0, rows[q / nc], cols[q % nc]))
                return 0;
            past[n++] = (int32_t)q;
        }
    }
    if (!n || i0 < 0)
        return 1;
    for (int64_t q = 0; q < len; q++) {
        if (b[q] <= a[q])
            continue;
        int i = rows[q / nc], j = cols[q % nc];
        for (int p = 0; p < n; p++)
            if (apart16(L, a, b, i, j, a[q], rows[past[p] / nc], cols[past[p] % nc]))
                return 0;
    }
    return 1;
}

/* ``small``: whether x->z16r holds zone's stored 16-bit form (the caller's comparisons wrote it); ``own``: where the
 * zone as it came is copied before its first merge.  L: the state's layout. */
static int merge_into(Ctx *x, const Layout *L, Node *step, double *zone, Kept *kept, int small, double *own)
{
    int d = x->d;
    int64_t len = (int64_t)d * d;
    int32_t index = (int32_t)x->nodes.n;
    double *other = T(x, 6), *hull = T(x, 7);
    int grew = 1, count = 0;
    while (grew) {  /* most pairs are told apart on their 16-bit forms (x->z16r kept the zone's as it grows) */
        grew = 0;
        x->under.n = 0;  /* the positions merged in this pass */
        for (int32_t i = first_open(x, kept); i < kept->n; i++) {
            Node *o = &x->nodes.a[kept->a[i]];
            if (small && !(o->zone & 1) && !union16(L, x->z16r, (const int16_t *)slot_bytes(x, o->zone), x->past))
                continue;
            slot_load(x, o->zone, other);
            if (z_union(hull, zone, other, d, (int *)x->past)) {  /* union16 is done with x->past */
                if (!count)
                    memcpy(own, zone, len * sizeof(double));
                memcpy(zone, hull, len * sizeof(double));
                small = gather_short(L, zone, x->z16r);
                if (add_member(x, step, kept->a[i]))
                    return -9;
                o->covered = 1, o->by = index;
                grew = 1, count++;
                PUSH(x->under, i);
            }
        }
        if (x->under.n)
            kept_remove(L, kept, x->under.a, x->under.n);
    }
    return count;
}

/* Node k was expanded and a larger zone now covers it: the nodes below it are marked dead, down through those
 * expanded, and those not expanded yet will not be; a node that covered a newcomer stays, with what is below it
 * (the newcomer's successors are its).  docs/verification/platform.md, *What lies below a covered node is pruned*,
 * says why the answers stay the same. */
static int prune_below(Ctx *x, int32_t k)
{
    x->walk.n = 0;
    PUSH(x->walk, k);
    while (x->walk.n) {
        int32_t u = x->walk.a[--x->walk.n];
        for (int32_t c = x->nodes.a[u].child; c >= 0; c = x->nodes.a[c].sibling) {
            Node *n = &x->nodes.a[c];
            if (n->dead || n->covered || n->covers)
                continue;
            n->dead = 1;
            if (n->expanded)
                PUSH(x->walk, c);
        }
    }
    return 0;
}

static int ascending(const void *a, const void *b)
{
    int32_t p = *(const int32_t *)a, q = *(const int32_t *)b;
    return (p > q) - (p < q);
}

/* Node k is dead and covers a newcomer: it and the dead nodes below it, down through those expanded, live again;
 * those passed over while dead are queued again, in the order they were stored. */
static int revive(Ctx *x, int32_t k)
{
    x->walk.n = x->back.n = 0;
    PUSH(x->walk, k);
    while (x->walk.n) {
        int32_t u = x->walk.a[--x->walk.n];
        Node *n = &x->nodes.a[u];
        n->dead = 0;
        x->revived++;
        if (n->skipped) {
            n->skipped = 0;
            PUSH(x->back, u);
        }
        if (n->expanded)
            for (int32_t c = n->child; c >= 0; c = x->nodes.a[c].sibling)
                if (x->nodes.a[c].dead)
                    PUSH(x->walk, c);
    }
    qsort(x->back.a, (size_t)x->back.n, sizeof(int32_t), ascending);
    for (int64_t q = 0; q < x->back.n; q++) {
        PUSH(x->waiting, x->back.a[q]);
        x->pending[x->nodes.a[x->back.a[q]].state]++;
    }
    return 0;
}

/* Store (state, zone) reached from node parent by interaction via: zone's bounds are those between A's clocks (the
 * state's active ones, and any idle one its program reads); zone is changed (extrapolated; its idle clocks freed only
 * where whole matrices meet, in merging: the stored form and every comparison leave their rows and columns out, see
 * layout_for). */
static int add(Ctx *x, int64_t state, double *zone, const Act *A, int32_t parent, int32_t via, const int64_t *guard,
               int64_t nguard, int grown, const double *lower, const double *upper, const unsigned char *plus)
{
    int d = x->d;
    int32_t lay = x->lay_of[state];
    const Layout *L = &x->lays.a[lay];
    if (plus)
        a_extrapolate_lu_plus(zone, d, A->c, A->n, lower, upper, plus);
    else
        a_extrapolate_lu(zone, d, A->c, A->n, x->ceiling, x->ceiling);
    int grow[256], ngrow = 0;  /* the grow-only clocks of A: the others' entries are never read */
    for (int g = 0; g < x->ngrow; g++)
        if (A->in[x->grow_only[g]])
            grow[ngrow++] = x->grow_only[g];
    a_forget_below(zone, d, A->c, A->n, grow, ngrow);
    Kept *kept = &x->kept.a[state];
    if (!kept->seen)
        kept->seen = 1, x->discrete++;
    Node step = {.state = (int32_t)state, .parent = parent, .via = via, .by = -1, .zone = -1, .own = -1, .members = -1,
                 .guard = x->guards.n, .guard_len = (int32_t)nguard, .grown = (uint8_t)grown, .child = -1,
                 .sibling = -1};
    const int16_t *ready = NULL;  /* the zone's stored 16-bit form, once computed and while it is the zone's */
    for (int64_t k = 0; k < 3 * nguard; k++)
        PUSH(x->guards, guard[k]);
    if (kept->n) {
        /* one pass over the state's zones: the first that includes the new one covers it; those it includes are
         * covered by it once no zone covers it (the order of search.py's two passes, which give the same) */
        int16_t *mine = x->z16r;  /* its stored form, as the state's zones are */
        int small = gather_short(L, zone, mine);
        ready = small ? mine : NULL;
        x->under.n = 0;
        int K = L->sigk;
        int16_t *sig = kept->sig && small ? x->sig : NULL;  /* signatures first, where the state keeps them */
        if (sig)
            sig_of(L, mine, sig);
        for (int32_t i = 0; i < kept->n; i++) {
            if (sig) {
                if (!sig_may(kept->sig + (int64_t)i * K, sig, K))
                    continue;
            } else {
                /* the state's zones lie anywhere in the pools: ask for the next ones' first bytes while this one is
                 * compared (most comparisons end there) */
                if (i + 8 < kept->n)
                    __builtin_prefetch(&x->nodes.a[kept->a[i + 8]]);
                if (i + 4 < kept->n) {
                    const char *at = slot_bytes(x, x->nodes.a[kept->a[i + 4]].zone);
                    __builtin_prefetch(at), __builtin_prefetch(at + 64);
                }
            }
            int64_t slot = x->nodes.a[kept->a[i]].zone;
            int ge, le;
            if (small && !(slot & 1)) {
                compare16((const int16_t *)slot_bytes(x, slot), mine, L->rlen, &ge, &le);
            } else {
                ge = slot_geq(x, slot, zone);
                le = !ge && slot_leq(x, slot, zone);
            }
            if (ge && x->nodes.a[kept->a[i]].dead && revive(x, kept->a[i]))
                return -9;
            if (ge) {
                x->old_hit = 1;
                x->nodes.a[kept->a[i]].covers = 1;
                if (parent >= 0) {
                    Step into = {step.state, step.parent, step.via, kept->a[i], step.guard, step.guard_len, step.grown};
                    Edge e = {parent, kept->a[i], (int32_t)(-x->steps.n - 1)};
                    PUSH(x->steps, into);
                    PUSH(x->edges, e);
                }
                return 0;
            }
            if (le)
                PUSH(x->under, i);
        }
        for (int64_t u = 0; u < x->under.n; u++) {
            Node *old = &x->nodes.a[kept->a[x->under.a[u]]];
            old->covered = 1, old->by = (int32_t)x->nodes.n;
            if (old->expanded && x->prune && prune_below(x, kept->a[x->under.a[u]]))
                return -9;
            if (!old->expanded) {
                if (slot_drop(x, old->zone))
                    return -9;
                old->zone = -1;
                x->dropped++;
            }
        }
        if (x->under.n)
            kept_remove(L, kept, x->under.a, x->under.n);
    }
    if (x->merge && kept->n) {
        /* merging takes hulls of whole matrices: the idle clocks' rows and columns as stored ones', every other entry
         * of zone written (the active clocks' are all the state's others) */
        z_free(zone, zone, d, L->idle, L->nidle);  /* in place: see z_free */
        double *own = T(x, 3);  /* the zone as it came, if it merges */
        int got = merge_into(x, L, &step, zone, kept, ready != NULL, own);
        if (got < 0)
            return got;
        if (got)
            ready = NULL;  /* the zone is now the hull */
        x->merged += got;
        if (step.members >= 0 && (step.own = (int32_t)slot_new(x, lay, own, NULL)) < 0)
            return -9;
    }
    if ((step.zone = (int32_t)slot_new(x, lay, zone, ready)) < 0)
        return -9;
    int32_t index = (int32_t)x->nodes.n;
    PUSH(x->nodes, step);
    if (parent >= 0) {
        Edge e = {parent, index, index};
        PUSH(x->edges, e);
        if (x->prune) {
            x->nodes.a[index].sibling = x->nodes.a[parent].child;
            x->nodes.a[parent].child = index;
        }
    }
    if (kept_push(x, L, kept, index, step.zone))
        return -9;
    PUSH(x->waiting, index);
    x->pending[step.state]++;
    return 0;
}

/* -- observers and response clocks (search.py's check) ------------------------------------------------ */
static void check(Ctx *x, int32_t k, const int64_t *pr)
{
    Parts q = parts(pr);
    const int64_t *c = q.checks;
    int64_t n = *c++;
    int64_t slot = x->nodes.a[k].zone;
    for (int64_t i = 0; i < n; i++, c += 4) {
        double top = entry(x, slot, (int)c[2], 0);
        if (c[0] == 2) {
            if (x->violation[x->nobs] < 0)
                x->violation[x->nobs] = k;  /* the goal */
        } else if (c[0] == 0) {
            if (top > (double)c[3] && x->violation[c[1]] < 0)
                x->violation[c[1]] = k;
        } else if (x->max_node[c[2]] < 0 || top > x->max_value[c[2]]) {
            x->max_value[c[2]] = top;
            x->max_node[c[2]] = k;
        }
    }
}

/* The clocks time passing at a state reads (``pass``, that part of its program) made active. */
static void act_pass(Act *a, const int64_t *pass)
{
    if (!*pass)
        return;
    int fr[256], nf = 0;
    const int64_t *w = pass + 1;
    for (int part = 0; part < 2; part++) {  /* before, after */
        act_reads(a, w + 1, w[0], fr, &nf);
        w = skip_bounds(w);
    }
    for (int64_t k = 0, nw = *w++; k < nw; k++) {
        act_reads(a, w + 1, w[0], fr, &nf);
        w = skip_bounds(w) + 4;
    }
}

/* The clocks the steps of a state read (``succ``, that part of its program: guards and priorities' blocks) made
 * active; those that were not appended to fr, nf set to their count. */
static void act_steps(Act *a, const int64_t *succ, int *fr, int *nf)
{
    *nf = 0;
    const int64_t *s = succ + 1;
    for (int64_t t = 0; t < succ[0]; t++) {
        SuccEntry e;
        s = succ_entry(s, &e);
        act_reads(a, e.need + 1, e.need[0], fr, nf);
        const int64_t *b = e.blocks;
        for (int64_t k = 0; k < e.nblocks; k++, b = skip_bounds(b))
            act_reads(a, b + 1, b[0], fr, nf);
    }
}

/* Time passing at ``state`` from zone z (reset: a zone on zin's clocks), every piece stored.  The state's idle
 * clocks are forgotten: they leave the working zone, but for those the state's program reads, which stay free. */
static int arrive(Ctx *x, int64_t state, double *z, const Act *zin, int32_t parent, int32_t via, const int64_t *guard,
                  int64_t nguard, program_fn ask)
{
    const int64_t *pr = program(x, state, ask);
    if (!pr)
        return x->failed;
    Parts q = parts(pr);
    if (x->lay_of[state] < 0 && (x->lay_of[state] = layout_for(x, q.idle, q.nidle)) < 0)
        return -9;
    const Layout *L = &x->lays.a[x->lay_of[state]];  /* its idle clocks are the program's, as ints */
    Act A;
    act_of(&A, L, x->d);
    act_pass(&A, q.pass);
    int fr[256], nf = 0;  /* free here: the idle clocks read, and the active ones z has no bounds of */
    for (int a = 1; a < A.n; a++)
        if (L->rat[A.c[a]] < 0 || !zin->in[A.c[a]])
            fr[nf++] = A.c[a];
    if (nf)
        a_free(z, x->d, A.c, A.n, fr, nf);
    const double *lower = x->ceiling, *upper = x->ceiling;
    const unsigned char *plus = NULL;
    double lo[256], up[256];
    unsigned char marked[256];
    if (q.nceil) {
        memcpy(lo, x->ceiling, x->d * sizeof(double));
        memcpy(up, x->ceiling, x->d * sizeof(double));
        memset(marked, 0, x->d);
        for (int64_t k = 0; k < q.nceil; k++) {
            lo[q.ceil[3 * k]] = (double)q.ceil[3 * k + 1];
            up[q.ceil[3 * k]] = (double)q.ceil[3 * k + 2];
            marked[q.ceil[3 * k]] = 1;
        }
        lower = lo, upper = up, plus = marked;
    }
    if (!*q.pass)  /* time cannot pass here: z is the state's one piece */
        return add(x, state, z, &A, parent, via, guard, nguard, 0, lower, upper, plus);
    x->out.n = x->grown.n = 0;
    int64_t n = elapse(x, q.pass, z, &A, &x->out, &x->grown);
    int status = n < 0 ? (int)n : 0;
    for (int64_t k = 0; k < n && !status; k++)
        status = add(x, state, x->out.a + k * x->d * x->d, &A, parent, via, guard, nguard, (int)x->grown.a[k],
                     lower, upper, plus);
    return status;
}

int zs_initial(void *p, int64_t state, const double *zone, program_fn ask)
{
    Ctx *x = p;
    double *z = T(x, 1);
    memcpy(z, zone, (int64_t)x->d * x->d * sizeof(double));
    Act all;  /* the zone given has bounds on every clock */
    all.n = x->d;
    for (int k = 0; k < x->d; k++)
        all.c[k] = k, all.in[k] = 1;
    return arrive(x, state, z, &all, -1, -1, NULL, 0, ask);
}

/* The number of successor entry ``*id`` of state ``state``'s program, interned now if it was not yet (a program
 * written in C names its successors by their index among the step's successors until a step takes them); the
 * entry is then rewritten with it.  < 0: no memory (-9), or the step gave fewer successors (-1). */
static int64_t resolve(Ctx *x, int64_t state, int64_t *id)
{
    if (*id >= 0)
        return *id;
    /* only a program written in C names successors by their index, and it keeps them after it (keep_successors) */
    int64_t len;
    const uint8_t *bytes = kept_successor(x->prog.a[state] + x->body[state], -*id - 1, &len);
    int64_t got = bytes ? intern_encoded(x, bytes, len) : -1;
    if (got >= 0)
        *id = got;
    return got;
}

/* Bytes the search holds: zones, states (words, tables, lists of zones kept with their signatures), programs, nodes,
 * steps, edges, the waiting list; counted as they grow (the budget of --max-memory reads it). */
int64_t zs_memory(Ctx *x)
{
    return zone_bytes(x) + x->bytes.n + x->ends.n * 16 + x->prog_words * 8 + x->nodes.n * (int64_t)sizeof(Node)
           + x->steps.n * (int64_t)sizeof(Step) + x->edges.n * (int64_t)sizeof(Edge) + x->guards.n * 8
           + x->kept_bytes + x->waiting.n * 4 + x->members.n * (int64_t)sizeof(Member)
           + x->prog.cap * (int64_t)(sizeof(int64_t *) + sizeof(Kept) + 13) + x->hcap * 8;
}

/* The search, resumable: it goes on from where a previous call stopped.  Returns 0 complete, 1 max-states,
 * 2 violated (stop_at_violation), 3 stopped by the progress callback, 4 a violation newly found (``notify``:
 * after the node where it was seen is expanded, so that a next call goes on), -1 the program callback failed
 * (its exception is on the Python side), -2 an unsupported wait (err_arg), -9 memory. */
int zs_run(void *p, int64_t max_states, int stop_at_violation, program_fn ask, progress_fn progress,
           int64_t every, int notify)
{
    Ctx *x = p;
    int d = x->d;
    int64_t len = (int64_t)d * d;
    Doubles pieces = {0}, next = {0};  /* the allowed pieces of a step's zone, and the next block's */
    Longs cuts = {0}, ncut = {0}, need = {0}, ncuts = {0}, nn = {0}, pc = {0}, pn = {0};
    int status = 0;
    int64_t count = 0;
    Act ha, za;  /* the clocks of the zone being expanded, and of a successor's once reset */
    int fr[256], nf;
    while (x->head < x->waiting.n) {
        if (x->head >= x->level_end)  /* the nodes before level_end are at depth, those after at depth + 1 */
            x->depth++, x->level_end = x->waiting.n;
        int32_t k = x->waiting.a[x->head++];
        if (node_done(x, x->nodes.a[k].state)) {  /* its program stays while it is pinned */
            status = -9;
            break;
        }
        if (x->nodes.a[k].covered)
            continue;
        if (x->nodes.a[k].dead) {
            x->nodes.a[k].skipped = 1;
            x->pruned++;
            continue;
        }
        x->nodes.a[k].expanded = 1;
        if (k > x->current)
            x->current = k;
        x->pinned = x->nodes.a[k].state;
        const int64_t *pr = program(x, x->nodes.a[k].state, ask);
        if (!pr) {
            status = x->failed;
            break;
        }
        check(x, k, pr);
        int found = 0;
        for (int i = 0; i <= x->nobs; i++)  /* the observers, then the goal */
            found += x->violation[i] >= 0;
        if (stop_at_violation && found) {
            status = 2;
            break;
        }
        int fresh = notify && found > x->told;
        x->told = found;
        double *here = T(x, 0), *met = T(x, 1), *block = T(x, 2);
        /* the zone on the state's active clocks, and on the idle ones its steps read (free) */
        slot_load_active(x, x->nodes.a[k].zone, here);
        act_of(&ha, slot_layout(x, x->nodes.a[k].zone), d);
        act_steps(&ha, parts(pr).succ, fr, &nf);
        if (nf)
            a_free(here, d, ha.c, ha.n, fr, nf);
        const int64_t *keep = NULL;  /* the reduction's set first; the rest if it reached a stored zone */
        if (x->ask_ample && !*parts(pr).pass) {
            if (x->ask_ample(x->nodes.a[k].state, x->nodes.a[k].zone) != 0) {
                status = -1;
                break;
            }
            keep = x->amp_all ? NULL : x->amp.a;
        }
        x->old_hit = 0;
        int64_t fired = x->transitions;  /* none of the set fires in this zone: the others must */
        for (int round = 0; round < (keep ? 2 : 1) && !status; round++) {
            if (round == 1 && !x->old_hit && x->transitions > fired) {
                x->reduced++;
                break;
            }
            const int64_t *s = parts(pr).succ;
            int64_t nsucc = *s++;
            for (int64_t t = 0; t < nsucc && !status; t++) {
                const int64_t *entry = s;
                int64_t nxt = s[0], via = s[1];
                SuccEntry e;
                s = succ_entry(s, &e);
                const int64_t *nb = e.need, *rs = e.resets, *blocks = e.blocks;
                int64_t nblocks = e.nblocks;
                if (keep && in_list(keep, via) != (round == 0))
                    continue;
                a_copy(met, here, d, ha.c, ha.n);
                if (!a_constrain_all(met, d, ha.c, ha.n, nb + 1, nb[0]))
                    continue;
                /* allowed: the pieces of met outside every block, each with its cut bounds; while no block meets
                 * met (``whole``), met itself is the one piece, not copied */
                int whole = 1;
                pieces.n = cuts.n = ncut.n = 0;
                const int64_t *b = blocks;
                for (int64_t bi = 0; bi < nblocks && (whole || pieces.n); bi++) {
                    a_copy(block, met, d, ha.c, ha.n);
                    int live = a_constrain_all(block, d, ha.c, ha.n, b + 1, b[0]);
                    b = skip_bounds(b);
                    if (!live)
                        continue;
                    if (whole) {
                        whole = 0;
                        if (append_active(&pieces, met, len, d, &ha))
                            goto nomem;
                        PUSH_OR(ncut, 0, goto nomem);
                    }
                    next.n = ncuts.n = nn.n = 0;
                    int64_t off = 0;
                    for (int64_t pi = 0; pi * len < pieces.n; pi++) {
                        pc.n = pn.n = 0;
                        if (subtract(pieces.a + pi * len, block, d, &ha, T(x, 6), T(x, 7), &next, &pc, &pn))
                            goto nomem;
                        int64_t o2 = 0;
                        for (int64_t q = 0; q < pn.n; q++) {
                            for (int64_t w = 0; w < 3 * ncut.a[pi]; w++)
                                PUSH_OR(ncuts, cuts.a[off + w], goto nomem);
                            for (int64_t w = 0; w < 3 * pn.a[q]; w++)
                                PUSH_OR(ncuts, pc.a[o2 + w], goto nomem);
                            o2 += 3 * pn.a[q];
                            PUSH_OR(nn, ncut.a[pi] + pn.a[q], goto nomem);
                        }
                        off += 3 * ncut.a[pi];
                    }
                    Doubles dt = pieces;  /* the pieces left become the ones to cut by the next block */
                    Longs ct = cuts, nt = ncut;
                    pieces = next, cuts = ncuts, ncut = nn;
                    next = dt, ncuts = ct, nn = nt;
                }
                if (whole)  /* met as it is, with no cut */
                    PUSH_OR(ncut, 0, goto nomem);
                int64_t off = 0, npieces = whole ? 1 : pieces.n / len;
                for (int64_t pi = 0; pi < npieces && !status; pi++) {
                    double *z = T(x, 1);  /* met, where the piece is met itself */
                    if (!whole)
                        a_copy(z, pieces.a + pi * len, d, ha.c, ha.n);
                    act_copy(&za, &ha, d);  /* a clock reset joins the zone's */
                    for (int64_t r = 0; r < rs[0]; r++) {
                        act_add(&za, (int)rs[1 + 2 * r]);
                        a_reset(z, d, za.c, za.n, (int)rs[1 + 2 * r], (double)rs[2 + 2 * r]);
                    }
                    need.n = 0;
                    for (int64_t w = 0; w < 3 * nb[0]; w++)
                        PUSH_OR(need, nb[1 + w], goto nomem);
                    for (int64_t w = 0; w < 3 * ncut.a[pi]; w++)
                        PUSH_OR(need, cuts.a[off + w], goto nomem);
                    off += 3 * ncut.a[pi];
                    x->transitions++;
                    if (nxt < 0 && (nxt = resolve(x, x->nodes.a[k].state, (int64_t *)entry)) < 0) {
                        status = nxt == -9 ? -9 : -1;
                        break;
                    }
                    status = arrive(x, nxt, z, &za, k, (int32_t)via, need.a, need.n / 3, ask);
                    /* arrive may move the program array: re-read nothing from it after this point */
                }
                /* T(x, 0) (here) is never used by arrive, so the next successor starts from the same zone */
            }
        }
        if (status)
            break;
        /* the state's program may go once it is expanded: node_done queued it, but let_go passes over the pinned
         * state, which it may have met while its successors arrived */
        if (x->budget > 0 && !x->pending[x->pinned])
            PUSH_OR(x->finished, x->pinned, goto nomem);
        if (max_states >= 0 && x->nodes.n >= max_states) {
            status = 1;
            break;
        }
        if (fresh) {
            status = 4;
            break;
        }
        if (progress && ++count % every == 0 &&
            progress(x->nodes.n, x->transitions, x->waiting.n - x->head, zs_memory(x), x->depth)) {
            status = 3;
            break;
        }
    }
    goto done;
nomem:
    status = -9;
done:
    free(pieces.a), free(cuts.a), free(ncut.a), free(need.a), free(next.a), free(ncuts.a), free(nn.a), free(pc.a),
         free(pn.a);
    return status;
}

/* -- reading the result ---------------------------------------------------------------------------- */
void zs_counts(void *p, int64_t *out)
{
    Ctx *x = p;
    out[0] = x->nodes.n, out[1] = x->discrete, out[2] = x->transitions, out[3] = x->merged;
    out[4] = x->dropped, out[5] = x->steps.n, out[6] = x->edges.n, out[7] = x->members.n, out[8] = x->guards.n;
    out[9] = x->waiting.n - x->head, out[10] = x->err_arg, out[11] = zs_memory(x);
    out[12] = zone_bytes(x), out[13] = x->bytes.n + x->ends.n * 16, out[14] = x->prog_words * 8;
    out[15] = x->reduced, out[16] = x->pruned, out[17] = x->revived;
}

/* A node's (or a step's) fields as an int64 row of 10: state parent via by zone own members guard guard_len
 * grown|covered<<1|expanded<<2|dead<<3. */
static void node_row(const Node *a, int64_t *r)
{
    r[0] = a->state, r[1] = a->parent, r[2] = a->via, r[3] = a->by, r[4] = a->zone;
    r[5] = a->own, r[6] = a->members, r[7] = a->guard, r[8] = a->guard_len;
    r[9] = a->grown | a->covered << 1 | a->expanded << 2 | a->dead << 3;
}

/* Column ``col`` of every node's row (node_row): a search of millions of nodes is read back a column at a time. */
void zs_node_column(void *p, int col, int64_t *out)
{
    Ctx *x = p;
    int64_t r[10];
    for (int64_t i = 0; i < x->nodes.n; i++) {
        node_row(x->nodes.a + i, r);
        out[i] = r[col];
    }
}

void zs_node_row(void *p, int64_t k, int64_t *out)
{
    node_row(((Ctx *)p)->nodes.a + k, out);
}

/* The row of step k into a covered zone (steps are many, and a trace reads a few). */
void zs_step_row(void *p, int64_t k, int64_t *out)
{
    const Step *a = ((Ctx *)p)->steps.a + k;
    Node as = {.state = a->state, .parent = a->parent, .via = a->via, .by = a->by, .zone = -1, .own = -1, .members = -1,
               .guard = a->guard, .guard_len = a->guard_len, .grown = a->grown, .child = -1, .sibling = -1};
    node_row(&as, out);
}

/* Whether time passed in each step into a covered zone, one byte each. */
void zs_step_grown(void *p, uint8_t *out)
{
    Ctx *x = p;
    for (int64_t i = 0; i < x->steps.n; i++)
        out[i] = x->steps.a[i].grown;
}

void zs_edges(void *p, int32_t *out)
{
    Ctx *x = p;
    memcpy(out, x->edges.a, x->edges.n * sizeof(Edge));
}

void zs_members(void *p, int32_t *out)
{
    Ctx *x = p;
    memcpy(out, x->members.a, x->members.n * sizeof(Member));
}

void zs_guards(void *p, int64_t *out)
{
    Ctx *x = p;
    memcpy(out, x->guards.a, x->guards.n * sizeof(int64_t));
}

void zs_zone(void *p, int64_t slot, double *out)
{
    slot_load(p, slot, out);
}

void zs_results(void *p, int32_t *violation, double *max_value, int32_t *max_node)
{
    Ctx *x = p;
    memcpy(violation, x->violation, (x->nobs + 1) * sizeof(int32_t));
    memcpy(max_value, x->max_value, x->d * sizeof(double));
    memcpy(max_node, x->max_node, x->d * sizeof(int32_t));
}

/* The program of a state as the search used it (its length; copied when it fits in cap), -1 if none, -9 without
 * memory to write it again. */
int64_t zs_program(void *p, int64_t state, int64_t *out, int64_t cap)
{
    Ctx *x = p;
    if (state >= x->prog.n)
        return -1;
    if (!x->prog.a[state] && !x->in_c[state])
        return -1;  /* none */
    if (!x->prog.a[state] && !program(x, state, NULL))  /* let go: written again here (C writes it alike) */
        return x->failed;
    const int64_t *pr = x->prog.a[state];
    Parts q = parts(pr);
    const int64_t *s = q.succ;
    int64_t n = *s++;
    for (int64_t t = 0; t < n; t++) {
        if (s[0] < 0 && resolve(x, state, (int64_t *)s) < 0)
            return -2;
        SuccEntry e;
        s = succ_entry(s, &e);
    }
    int64_t len = s - pr;
    if (len <= cap)
        memcpy(out, pr, len * sizeof(int64_t));
    return len;
}

/* Word ``offset`` of a state stored as b: ref's, or the value after those of the differing words before it. */
static int64_t word_at(const uint8_t *b, int n, const int64_t *ref, int offset)
{
    if (!(b[offset >> 3] >> (offset & 7) & 1))
        return ref[offset];
    int before = 0;
    for (int byte = 0; byte < offset >> 3; byte++)
        before += __builtin_popcount(b[byte]);
    before += __builtin_popcount(b[offset >> 3] & ((1u << (offset & 7)) - 1));
    const uint8_t *v = b + (n + 7) / 8;
    for (; before > 0; v++)
        before -= !(*v & 0x80);
    int64_t w;
    varint(v, &w);
    return w;
}

/* Word ``offset`` of each of the states ids[0..n) into out (the words before it skipped, not decoded). */
void zs_node_words(void *p, const int64_t *ids, int64_t n, int offset, int64_t *out)
{
    Ctx *x = p;
    int64_t len;
    for (int64_t i = 0; i < n; i++)
        out[i] = word_at(state_bytes(x, ids[i], &len), x->tables->W, x->ref, offset);
}
