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

typedef struct {
    int32_t state, parent, via, by, zone, own, members;  /* zone, own: slots; members: first of a chain, -1 */
    int64_t guard;  /* offset of the step's bounds in the guard pool; their count is guard_len */
    int32_t guard_len;
    uint8_t grown, covered, expanded;
} Node;

typedef VEC(double) Doubles;
typedef VEC(int64_t) Longs;

/* n numbers appended to v at once; -9: no memory. */
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
    memcpy(v->a + v->n, src, n * sizeof(double));
    v->n += n;
    return 0;
}

typedef struct { int32_t from, target, ref; } Edge;  /* ref >= 0: a node; ref < 0: step -ref-1 */
typedef struct { int32_t member, next; } Member;
/* A discrete state's zones not covered (node numbers); past SIG_FROM of them, each one's signature beside it. */
typedef struct { int32_t *a; int16_t *sig; int32_t n, cap; uint8_t seen; } Kept;
typedef struct { char *a; int32_t *refs; int64_t n, size; VEC(int64_t) free; } Pool;  /* zone slots of one width */

typedef struct {
    int d, nobs, merge;
    double *ceiling;
    int *grow_only, ngrow;  /* clocks whose zones keep their upper bounds only (model.py's grow_only) */
    Pool shorts, floats;    /* zone slots (see slot_new) */
    int64_t *zkey, zcap, zused;  /* the zones stored once each: open addressing on slot + 1, 0 empty, -1 gone */
    VEC(Node) nodes;
    VEC(Node) steps;        /* steps into a zone another node covers */
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
    VEC(uint8_t) bytes;     /* states' words, zigzag varints (most slots are small) */
    VEC(int64_t) ends;      /* per state: where its bytes end */
    uint8_t *enc;           /* scratch: one state encoded */
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
    int32_t *pending, *plen;  /* grown with prog (grow_states) */
    uint8_t *in_c;
    VEC(int64_t) finished;  /* states whose nodes were all expanded, oldest first, from finished_head on */
    int64_t finished_head;
    int64_t budget;         /* bytes of programs held before finished states' are let go; 0: never */
    int64_t pinned;         /* the state being expanded: its program is read while its successors arrive */
    int64_t let_go, rewritten;
    int64_t level_end, depth;  /* breadth-first levels: the waiting list's end when the current one began */
    int invariants;         /* points past an invariant are no state (search.py's ZoneExplorer.invariants) */
    int16_t *z16;           /* scratch: a zone being stored, in 16 bits */
    int16_t *z16own;        /* scratch: slot_new's own 16-bit form of a zone (z16 may hold its caller's) */
    int32_t *past;          /* scratch: d * d numbers (union16) */
    int16_t *sig;           /* scratch: the signature of a zone being stored */
    /* what a stored zone keeps: columns x->cols[0..w) of each row (see zs_set_grow_only), rlen numbers in all */
    int w, *cols, *at;      /* at[j]: column j's place in a stored row, -1 where it is column 0's */
    int *from;              /* from[j]: the place column j is read from (at[j], or 0) */
    int64_t rlen;
    int16_t *z16r;          /* scratch: a zone's stored 16-bit form */
    int sigk;               /* numbers in a signature (see sig_of) */
    int64_t current;        /* the node being expanded (-1 before the first): those before it are expanded */
    VEC(int32_t) under;     /* scratch: the state's zones it includes (positions in its list) */
    Doubles out;            /* scratch: arrive's pieces after time passes, kept from call to call */
    Longs grown;            /* scratch: each piece's grown flag */
} Ctx;



static double *T(Ctx *x, int k) { return x->tmp + (int64_t)k * x->d * x->d; }

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

void zs_program_counts(void *p, int64_t *out)
{
    Ctx *x = p;
    out[0] = x->let_go, out[1] = x->rewritten;
}

/* What a stored zone keeps: every column but those of the clocks read only for how large they grow, which are
 * column 0 (forget_below makes them so before a zone is stored, and a merge's hull keeps it) with 0 on the diagonal.
 * Comparisons, signatures and the hash read the stored form; a zone is spread back whole when it is loaded. */
static int set_layout(Ctx *x)
{
    int d = x->d, w = 0;
    free(x->cols), free(x->at), free(x->from), free(x->z16r), free(x->sig);
    x->z16r = NULL, x->sig = NULL;
    x->cols = malloc(d * sizeof(int)), x->at = malloc(d * sizeof(int)), x->from = malloc(d * sizeof(int));
    if (!x->cols || !x->at || !x->from)
        return -9;
    for (int j = 0; j < d; j++) {
        int grows = 0;
        for (int c = 0; c < x->ngrow; c++)
            grows |= x->grow_only[c] == j;
        x->at[j] = grows ? -1 : w;
        x->from[j] = grows ? 0 : w;
        if (!grows)
            x->cols[w++] = j;
    }
    x->w = w, x->rlen = (int64_t)d * w;
    x->shorts.size = x->rlen * sizeof(int16_t);
    x->floats.size = x->rlen * sizeof(float);
    x->sigk = (w - 1 + d - 1 + 15) / 16 * 16;
    x->z16r = malloc(x->rlen * sizeof(int16_t));
    x->sig = malloc((x->sigk + 1) * sizeof(int16_t));
    return x->z16r && x->sig ? 0 : -9;
}

/* The clocks read only for how large they grow (model.py's grow_only); before the search stores a zone. */
int zs_set_grow_only(void *p, const int *clocks, int n)
{
    Ctx *x = p;
    if (x->shorts.n || x->floats.n)
        return -2;
    free(x->grow_only);
    x->grow_only = malloc((n ? n : 1) * sizeof(int));
    if (!x->grow_only)
        return -9;
    memcpy(x->grow_only, clocks, n * sizeof(int));
    x->ngrow = n;
    return set_layout(x);
}

void zs_free(void *p);

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
    x->z16 = malloc((int64_t)d * d * sizeof(int16_t));
    x->z16own = malloc((int64_t)d * d * sizeof(int16_t));
    x->past = malloc((int64_t)d * d * sizeof(int32_t));
    if (!x->ceiling || !x->violation || !x->max_value || !x->max_node || !x->tmp || !x->z16 || !x->z16own || !x->past
        || set_layout(x)) {  /* every column kept until zs_set_grow_only */
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
    free(x->prog.a), free(x->kept.a), free(x->shorts.a), free(x->shorts.free.a), free(x->floats.a),
    free(x->floats.free.a), free(x->shorts.refs), free(x->floats.refs), free(x->zkey), free(x->nodes.a), free(x->steps.a);
    free(x->edges.a), free(x->members.a), free(x->guards.a), free(x->waiting.a), free(x->ceiling), free(x->grow_only);
    free(x->violation), free(x->max_value), free(x->max_node), free(x->tmp), free(x->z16), free(x->z16own), free(x->past), free(x->sig), free(x->under.a);
    free(x->cols), free(x->at), free(x->from), free(x->z16r);
    free(x->out.a), free(x->grown.a);
    free(x->pending), free(x->plen), free(x->in_c), free(x->finished.a);
    tables_free(x->tables);
    for (int64_t i = 0; i < x->icap; i++)
        free(x->inter_val ? x->inter_val[i] : NULL);
    free(x->inter_key), free(x->inter_val), free(x->bytes.a), free(x->ends.a), free(x->enc), free(x->hash), free(x);
}

/* -- states as the compiled step's words, kept as zigzag varints ------------------------------------- */
static uint64_t hash_bytes(const uint8_t *b, int64_t n)
{
    uint64_t h = 0x9e3779b97f4a7c15ull ^ (uint64_t)n;
    int64_t i = 0;
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

static int64_t encode(const int64_t *w, int n, uint8_t *out)
{
    int64_t k = 0;
    for (int i = 0; i < n; i++) {
        uint64_t v = ((uint64_t)w[i] << 1) ^ (uint64_t)(w[i] >> 63);
        while (v >= 0x80) {
            out[k++] = (uint8_t)(v | 0x80);
            v >>= 7;
        }
        out[k++] = (uint8_t)v;
    }
    return k;
}

static void decode(const uint8_t *b, int n, int64_t *w)
{
    for (int i = 0; i < n; i++) {
        uint64_t v = 0;
        int shift = 0;
        while (*b & 0x80) {
            v |= (uint64_t)(*b++ & 0x7f) << shift;
            shift += 7;
        }
        v |= (uint64_t)*b++ << shift;
        w[i] = (int64_t)(v >> 1) ^ -(int64_t)(v & 1);
    }
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
    decode(state_bytes(x, s, &len), x->tables->W, w);
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
            x->prog.a = a ? a : x->prog.a, x->kept.a = k ? k : x->kept.a;  /* what moved is kept, to be freed */
            x->pending = pe ? pe : x->pending, x->plen = pl ? pl : x->plen, x->in_c = c ? c : x->in_c;
            if (!a || !k || !pe || !pl || !c)
                return -9;  /* the capacity stays what every array has */
            x->prog.cap = x->kept.cap = cap;
        }
        Kept none = {0};
        x->pending[x->prog.n] = 0, x->plen[x->prog.n] = 0, x->in_c[x->prog.n] = 0;
        x->prog.a[x->prog.n++] = NULL;
        x->kept.a[x->kept.n++] = none;
    }
    return 0;
}

/* The number of the state with these words, given on first sight. */
static int64_t intern(void *p, const int64_t *w)
{
    Ctx *x = p;
    int W = x->tables->W;
    int64_t n = x->ends.n, len;
    if (!x->enc && !(x->enc = malloc(10 * (size_t)W + 1)))
        return -9;
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
    int64_t k = encode(w, W, x->enc);
    uint64_t i = hash_bytes(x->enc, k) & (x->hcap - 1);
    while (x->hash[i]) {
        int64_t s = x->hash[i] - 1;
        const uint8_t *b = state_bytes(x, s, &len);
        if (len == k && !memcmp(b, x->enc, k))
            return s;
        i = (i + 1) & (x->hcap - 1);
    }
    for (int64_t j = 0; j < k; j++)
        PUSH(x->bytes, x->enc[j]);
    PUSH(x->ends, x->bytes.n);
    x->hash[i] = n + 1;
    if (grow_states(x, n + 1))
        return -9;
    return n;
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

static int64_t pool_take(Pool *p)
{
    if (p->free.n)
        return p->free.a[--p->free.n];
    if (p->n % 1024 == 0) {
        char *a = realloc(p->a, (p->n + 1024) * p->size);
        if (!a)
            return -1;
        p->a = a;  /* at once: realloc may have moved it */
        int32_t *r = realloc(p->refs, (p->n + 1024) * sizeof(int32_t));
        if (!r)
            return -1;
        p->refs = r;
    }
    return p->n++;
}

/* -- zones stored once each ------------------------------------------------------------------------
 * Most symbolic states share their zone with others (whole DALA on two cores: 76,423 stored zones, 1,847
 * different), so a zone slot is shared and counted: slot_new finds an equal zone through a hash table and
 * slot_drop lets a slot go with its last user.  Slots are never changed once written. */
static const char *slot_bytes(const Ctx *x, int64_t s)
{
    return s & 1 ? x->floats.a + (s >> 1) * x->floats.size : x->shorts.a + (s >> 1) * x->shorts.size;
}

static int32_t *slot_refs(Ctx *x, int64_t s)
{
    return s & 1 ? &x->floats.refs[s >> 1] : &x->shorts.refs[s >> 1];
}

static uint64_t slot_hash(const Ctx *x, int64_t s)
{
    return hash_bytes((const uint8_t *)slot_bytes(x, s), s & 1 ? x->floats.size : x->shorts.size) ^ (uint64_t)(s & 1);
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

/* z's 16-bit form into out (infinity as SHORT_INF); 1 when every entry fits, else out is not z.  Without
 * branches, so that the compiler vectorises it (dbm.c's pragma). */
static int to_short(const double *restrict z, int64_t len, int16_t *restrict out)
{
    int bad = 0;
    for (int64_t k = 0; k < len; k++) {
        double v = z[k];
        bad |= (v < -(SHORT_INF - 1)) | ((v > SHORT_INF - 1) & (v != INFINITY));
        double c = v > SHORT_INF ? SHORT_INF : v;
        c = c < -SHORT_INF ? -SHORT_INF : c;
        out[k] = (int16_t)(int32_t)c;
    }
    return !bad;
}

/* A full 16-bit matrix's stored form: its columns x->cols, row by row. */
static void gather16(const Ctx *x, const int16_t *full, int16_t *out)
{
    int d = x->d, w = x->w;
    if (w == d) {  /* every column kept */
        memcpy(out, full, (int64_t)d * d * sizeof(int16_t));
        return;
    }
    for (int a = 0; a < d; a++)
        for (int q = 0; q < w; q++)
            out[(int64_t)a * w + q] = full[(int64_t)a * d + x->cols[q]];
}


/* The slot of zone z: an equal stored zone's (one more user), or a new one; -1 without memory.  ``r16``: z's
 * stored 16-bit form if the caller has it (to_short said it fits), else NULL. */
static int64_t slot_new(Ctx *x, const double *z, const int16_t *r16)
{
    int64_t len = (int64_t)x->d * x->d, rlen = x->rlen;
    int64_t s;
    if (!r16 && to_short(z, len, x->z16own)) {
        gather16(x, x->z16own, x->z16r);
        r16 = x->z16r;
    }
    if (r16) {
        if ((s = pool_take(&x->shorts)) < 0)
            return -1;
        memcpy((int16_t *)x->shorts.a + s * rlen, r16, rlen * sizeof(int16_t));
        s = 2 * s;
    } else {
        if ((s = pool_take(&x->floats)) < 0)
            return -1;
        float *dst = (float *)x->floats.a + s * rlen;
        for (int a = 0; a < x->d; a++)
            for (int q = 0; q < x->w; q++)
                dst[(int64_t)a * x->w + q] = (float)z[(int64_t)a * x->d + x->cols[q]];
        s = 2 * s + 1;
    }
    if (2 * (x->zused + 1) > x->zcap && zkey_grow(x))
        return -1;
    int64_t size = s & 1 ? x->floats.size : x->shorts.size, mask = x->zcap - 1;
    int64_t h = (int64_t)(slot_hash(x, s) & (uint64_t)mask), hole = -1;
    for (; x->zkey[h]; h = (h + 1) & mask) {
        int64_t t = x->zkey[h] - 1;
        if (t < 0) {
            if (hole < 0)
                hole = h;
            continue;
        }
        if ((t & 1) == (s & 1) && !memcmp(slot_bytes(x, t), slot_bytes(x, s), size)) {
            Pool *p = s & 1 ? &x->floats : &x->shorts;  /* the copy just written goes back */
            PUSH(p->free, s >> 1);
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

/* Stored number q of slot s (an index into its stored form). */
static double stored(const Ctx *x, int64_t s, int64_t q)
{
    if (s & 1)
        return ((const float *)x->floats.a)[(s >> 1) * x->rlen + q];
    int16_t v = ((const int16_t *)x->shorts.a)[(s >> 1) * x->rlen + q];
    return v == SHORT_INF ? INFINITY : v;
}

/* Where entry (i, j) of a full matrix is in the stored form; -1 for the diagonal of a column left out (0). */
static int64_t place(const Ctx *x, int i, int j)
{
    return x->at[j] < 0 && i == j ? -1 : (int64_t)i * x->w + x->from[j];
}

/* Entry k of slot s's full matrix. */
static double entry(const Ctx *x, int64_t s, int64_t k)
{
    int64_t q = place(x, (int)(k / x->d), (int)(k % x->d));
    return q < 0 ? 0 : stored(x, s, q);
}

static void slot_load(Ctx *x, int64_t s, double *z)
{
    int64_t len = (int64_t)x->d * x->d;
    if (s & 1) {
        for (int64_t k = 0; k < len; k++)
            z[k] = entry(x, s, k);
    } else {  /* row by row: a column left out is column 0, with 0 on the diagonal */
        const int16_t *r = (const int16_t *)slot_bytes(x, s);
        for (int a = 0; a < x->d; a++) {
            const int16_t *ra = r + (int64_t)a * x->w;
            double *za = z + (int64_t)a * x->d;
            for (int j = 0; j < x->d; j++) {
                int16_t v = ra[x->from[j]];
                za[j] = v == SHORT_INF ? INFINITY : v;
            }
        }
        for (int c = 0; c < x->ngrow; c++)
            z[(int64_t)x->grow_only[c] * (x->d + 1)] = 0;
    }
}

/* z's entries at the stored places (a zone that went through forget_below: those left out are column 0's). */
static double at_stored(const Ctx *x, const double *z, int64_t q)
{
    return z[q / x->w * x->d + x->cols[q % x->w]];
}

static int slot_geq(Ctx *x, int64_t s, const double *z)  /* the stored zone includes z */
{
    for (int64_t q = 0; q < x->rlen; q++)
        if (stored(x, s, q) < at_stored(x, z, q))
            return 0;
    return 1;
}

static int slot_leq(Ctx *x, int64_t s, const double *z)  /* z includes the stored zone */
{
    for (int64_t q = 0; q < x->rlen; q++)
        if (stored(x, s, q) > at_stored(x, z, q))
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
    if (s & 1)
        PUSH(x->floats.free, s >> 1);
    else
        PUSH(x->shorts.free, s >> 1);
    return 0;
}

static int64_t zone_bytes(const Ctx *x)
{
    int64_t len = x->rlen;
    return (x->shorts.n - x->shorts.free.n) * len * 2 + (x->floats.n - x->floats.free.n) * len * 4
           + x->zcap * 8 + (x->shorts.n + x->floats.n) * 4;
}

/* -- zone operations that dbm.c does not have --------------------------------------------------------- */
static int constrain_all(double *m, int d, const int64_t *b, int64_t n)
{
    for (int64_t k = 0; k < n; k++)
        if (!z_constrain(m, d, (int)b[3 * k], (int)b[3 * k + 1], (double)b[3 * k + 2]))
            return 0;
    return 1;
}

static void z_up(double *m, int d)
{
    for (int i = 1; i < d; i++)
        m[(int64_t)i * d] = INFINITY;
}

static void z_reset(double *m, int d, int i, double v)
{
    for (int a = 0; a < d; a++) {
        m[(int64_t)i * d + a] = v + m[a];
        m[(int64_t)a * d + i] = m[(int64_t)a * d] - v;
    }
    m[(int64_t)i * d + i] = 0;
}

/* Pieces of m minus other (integer complements), as dbm.py's subtract_bounds: each piece appended to *out
 * (d*d doubles each), with the cut bounds that made it appended to *cuts and their count to *ncut; -9: no memory. */
static int subtract(const double *m, const double *other, int d, double *rest, double *piece,
                    Doubles *out, Longs *cuts, Longs *ncut)
{
    int64_t len = (int64_t)d * d;
    memcpy(rest, m, len * sizeof(double));
    Longs kept = {0};  /* the bounds kept so far: each piece copies them, then its cut */
    for (int i = 0; i < d; i++)
        for (int j = 0; j < d; j++) {
            double c = other[(int64_t)i * d + j];
            if (i == j || c == INFINITY || rest[(int64_t)i * d + j] <= c)
                continue;
            memcpy(piece, rest, len * sizeof(double));
            if (z_constrain(piece, d, j, i, -c - 1)) {
                if (append(out, piece, len))
                    goto nomem;
                for (int64_t k = 0; k < kept.n; k++)
                    PUSH_OR(*cuts, kept.a[k], goto nomem);
                PUSH_OR(*cuts, j, goto nomem); PUSH_OR(*cuts, i, goto nomem);
                PUSH_OR(*cuts, (int64_t)(-c - 1), goto nomem);
                PUSH_OR(*ncut, kept.n / 3 + 1, goto nomem);
            }
            if (!z_constrain(rest, d, i, j, c))
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
        if (!status) {
            let_go(x);  /* first: a state finished twice may still be queued, and this one must stay */
            x->rewritten += x->in_c[state];
            x->in_c[state] = 1, x->plen[state] = (int32_t)prog.n;
            x->prog_words += prog.n;
            x->prog.a[state] = prog.a ? prog.a : calloc(1, sizeof(int64_t));
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
    x->prog_words += n;
    return 0;
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

/* -- time passing (search.py's limits and elapse) --------------------------------------------------- */
/* The pieces of z after time passes at a state where it can (``pass``: that part of the state's program), appended
 * to out with their grown flags; returns the number of pieces, -2 for a wait that is not one lower bound (err_arg:
 * the rule), or -9 without memory. */
static int64_t elapse(Ctx *x, const int64_t *pass, double *z, Doubles *out, Longs *grown)
{
    int d = x->d;
    int64_t len = (int64_t)d * d;
    const int64_t *before = pass + 1, *after = skip_bounds(before), *w = skip_bounds(after);
    if (x->invariants && !constrain_all(z, d, after + 1, after[0]))
        return 0;  /* z (the caller's scratch) is past an invariant everywhere: no state */
    int64_t nw = *w++;
    Longs extra = {0};  /* a wait's lower bound: time passes up to it */
    if (nw) {
        double *reach = T(x, 4), *probe = T(x, 5);
        memcpy(reach, z, len * sizeof(double));
        z_up(reach, d);
        int live = constrain_all(reach, d, before + 1, before[0]);
        for (int64_t k = 0; k < nw; k++) {
            const int64_t *b = w;
            w = skip_bounds(w);
            int64_t kind = w[0], clock = w[1], c = w[2], rule = w[3];
            w += 4;
            if (!live)
                continue;
            memcpy(probe, reach, len * sizeof(double));
            if (!constrain_all(probe, d, b + 1, b[0]))
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
    memcpy(start, z, len * sizeof(double));
    int ok = constrain_all(start, d, after + 1, after[0]) && constrain_all(start, d, extra.a, extra.n / 3);
    int64_t count = 1;
    if (!ok) {
        if (append(out, z, len))
            goto nomem;
        PUSH_OR(*grown, 0, goto nomem);
    } else {
        z_up(start, d);
        constrain_all(start, d, after + 1, after[0]);
        constrain_all(start, d, extra.a, extra.n / 3);
        if (append(out, start, len))
            goto nomem;
        PUSH_OR(*grown, 1, goto nomem);
        Longs cuts = {0}, ncut = {0};
        int64_t before_n = out->n;
        int cut = subtract(z, start, d, T(x, 6), piece, out, &cuts, &ncut);
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
 * (every clock's lower and upper bound: 2(d - 1) numbers, padded with zeros to x->sigk, a whole number of blocks of
 * 16 that vectorise without a scalar tail), side by side: a zone that neither includes nor is
 * included in the new one there is passed over without being loaded (on RobNav at three cores, 94 % of the pairs
 * of a state's zones).  The full comparison decides the others, so the search stores the same nodes.  A zone
 * whose bounds do not fit in 16 bits has SIG_NONE as its first number: it is always compared in full. */
#define SIG_FROM 16
#define SIG_NONE INT16_MIN

/* The signature of a zone from its stored 16-bit form (NULL: it has none, SIG_NONE): row 0, column 0, zeros
 * after. */
static void sig_of(const Ctx *x, const int16_t *z16, int16_t *out)
{
    int d = x->d, w = x->w, k = 0;
    if (!z16) {
        out[0] = SIG_NONE;
        return;
    }
    for (int q = 1; q < w; q++)  /* row 0 (its columns left out are 0, the same for every zone) */
        out[k++] = z16[q];
    for (int a = 1; a < d; a++)  /* column 0 */
        out[k++] = z16[(int64_t)a * w];
    while (k < x->sigk)
        out[k++] = 0;
}

static void sig_of_slot(const Ctx *x, int64_t slot, int16_t *out)
{
    sig_of(x, slot & 1 ? NULL : (const int16_t *)slot_bytes(x, slot), out);
}

/* Node v (its zone in ``slot``) joins the state's list. */
static int kept_push(Ctx *x, Kept *k, int32_t v, int64_t slot)
{
    int K = x->sigk;
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
        k->cap = cap;
    }
    k->a[k->n++] = v;
    if (k->sig) {
        sig_of_slot(x, slot, k->sig + (int64_t)(k->n - 1) * K);
    } else if (k->n >= SIG_FROM && K > 0) {  /* from now on: the signatures of those kept so far */
        if (!(k->sig = malloc((int64_t)k->cap * K * sizeof(int16_t))))
            return -9;
        for (int32_t i = 0; i < k->n - 1; i++)
            sig_of_slot(x, x->nodes.a[k->a[i]].zone, k->sig + (int64_t)i * K);
        sig_of_slot(x, slot, k->sig + (int64_t)(k->n - 1) * K);
    }
    return 0;
}

/* The entries at positions pos[0..n) (ascending) leave the state's list, which keeps its order. */
static void kept_remove(Ctx *x, Kept *kept, const int32_t *pos, int64_t n)
{
    int K = x->sigk;
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

/* Whether two signatures leave room for an inclusion either way: a's bounds all at least b's, or all at most. */
static int sig_may(const int16_t *a, const int16_t *b, int K)
{
    if (a[0] == SIG_NONE)
        return 1;
    int g = 1, l = 1;
    for (int k = 0; k < K; k += 16)  /* K is a whole number of blocks of 16 */
        for (int j = 0; j < 16; j++) {
            g &= a[k + j] >= b[k + j];
            l &= a[k + j] <= b[k + j];
        }
    return g | l;
}

/* Entry (i, j) of a zone's full matrix from its stored 16-bit form. */
static int32_t full16(const Ctx *x, const int16_t *r, int i, int j)
{
    int64_t q = place(x, i, j);
    return q < 0 ? 0 : r[q];
}

/* Whether bound (i, j) of a, beyond which b goes (a[i][j] = c), and bound (k, l) of b, beyond which a goes, leave
 * a point of the hull in neither (z_union's test, on stored forms; SHORT_INF: no bound). */
static int apart16(const Ctx *x, const int16_t *a, const int16_t *b, int i, int j, int32_t c, int k, int l)
{
    int32_t ail = full16(x, a, i, l), bil = full16(x, b, i, l), akj = full16(x, a, k, j), bkj = full16(x, b, k, j);
    int32_t il = ail > bil ? ail : bil, kj = akj > bkj ? akj : bkj;
    return il == SHORT_INF || kj == SHORT_INF || il + kj >= c + full16(x, b, k, l) + 2;
}

/* dbm.c's z_union on two zones' stored 16-bit forms, without the hull, as a first test: 0 when a pair of their
 * bounds shows a point of the hull in neither (exact for that pair), 1 when none of the pairs of stored bounds
 * does (z_union then decides on the whole matrices).  The first bound of a that b goes beyond is tested against
 * each bound of b that a goes beyond as the scan meets it, which tells most pairs apart before the scan ends; the
 * others are tested pair by pair after.  past: room for d * d numbers. */
static int union16(const Ctx *x, const int16_t *a, const int16_t *b, int32_t *past)
{
    int64_t len = x->rlen;
    int w = x->w, n = 0, i0 = -1, j0 = -1;
    int32_t c0 = 0;
    for (int64_t q = 0; q < len; q++) {
        if (i0 < 0 && b[q] > a[q]) {
            i0 = (int)(q / w), j0 = x->cols[q % w], c0 = a[q];
            for (int p = 0; p < n; p++)
                if (apart16(x, a, b, i0, j0, c0, past[p] / w, x->cols[past[p] % w]))
                    return 0;
        }
        if (a[q] > b[q]) {
            if (i0 >= 0 && apart16(x, a, b, i0, j0, c0, (int)(q / w), x->cols[q % w]))
                return 0;
            past[n++] = (int32_t)q;
        }
    }
    if (!n || i0 < 0)
        return 1;
    for (int64_t q = 0; q < len; q++) {
        if (b[q] <= a[q])
            continue;
        int i = (int)(q / w), j = x->cols[q % w];
        for (int p = 0; p < n; p++)
            if (apart16(x, a, b, i, j, a[q], past[p] / w, x->cols[past[p] % w]))
                return 0;
    }
    return 1;
}

/* ``small``: whether x->z16 and x->z16r hold zone's 16-bit form and its stored form (the caller's comparisons wrote
 * them); ``own``: where the zone as it came is copied before its first merge. */
static int merge_into(Ctx *x, Node *step, double *zone, Kept *kept, int small, double *own)
{
    int d = x->d;
    int64_t len = (int64_t)d * d;
    int32_t index = (int32_t)x->nodes.n;
    double *other = T(x, 6), *hull = T(x, 7);
    int grew = 1, count = 0;
    while (grew) {  /* most pairs are told apart on their 16-bit forms (x->z16 kept the zone's as it grows) */
        grew = 0;
        x->under.n = 0;  /* the positions merged in this pass */
        for (int32_t i = first_open(x, kept); i < kept->n; i++) {
            Node *o = &x->nodes.a[kept->a[i]];
            if (small && !(o->zone & 1) && !union16(x, x->z16r, (const int16_t *)slot_bytes(x, o->zone), x->past))
                continue;
            slot_load(x, o->zone, other);
            if (z_union(hull, zone, other, d, (int *)x->past)) {  /* union16 is done with x->past */
                if (!count)
                    memcpy(own, zone, len * sizeof(double));
                memcpy(zone, hull, len * sizeof(double));
                if ((small = to_short(zone, len, x->z16)))
                    gather16(x, x->z16, x->z16r);
                if (add_member(x, step, kept->a[i]))
                    return -9;
                o->covered = 1, o->by = index;
                grew = 1, count++;
                PUSH(x->under, i);
            }
        }
        if (x->under.n)
            kept_remove(x, kept, x->under.a, x->under.n);
    }
    return count;
}

/* Store (state, zone) reached from node parent by interaction via; zone is changed (extrapolated). */
static int add(Ctx *x, int64_t state, double *zone, int32_t parent, int32_t via, const int64_t *guard,
               int64_t nguard, int grown, const double *lower, const double *upper, const unsigned char *plus)
{
    int d = x->d;
    if (plus)
        z_extrapolate_lu_plus(zone, d, lower, upper, plus);
    else
        z_extrapolate(zone, d, x->ceiling);
    z_forget_below(zone, d, x->grow_only, x->ngrow);
    Kept *kept = &x->kept.a[state];
    if (!kept->seen)
        kept->seen = 1, x->discrete++;
    Node step = {(int32_t)state, parent, via, -1, -1, -1, -1, x->guards.n, (int32_t)nguard, (uint8_t)grown, 0, 0};
    const int16_t *ready = NULL;  /* the zone's stored 16-bit form, once computed and while it is the zone's */
    for (int64_t k = 0; k < 3 * nguard; k++)
        PUSH(x->guards, guard[k]);
    if (kept->n) {
        /* one pass over the state's zones: the first that includes the new one covers it; those it includes are
         * covered by it once no zone covers it (the order of search.py's two passes, which give the same) */
        int64_t len = (int64_t)d * d;
        int16_t *mine = x->z16r;  /* its stored form, as the state's zones are */
        int small = to_short(zone, len, x->z16);
        if (small)
            gather16(x, x->z16, mine);
        ready = small ? mine : NULL;
        x->under.n = 0;
        int K = x->sigk;
        int16_t *sig = kept->sig && small ? x->sig : NULL;  /* signatures first, where the state keeps them */
        if (sig)
            sig_of(x, mine, sig);
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
                compare16((const int16_t *)x->shorts.a + (slot >> 1) * x->rlen, mine, x->rlen, &ge, &le);
            } else {
                ge = slot_geq(x, slot, zone);
                le = !ge && slot_leq(x, slot, zone);
            }
            if (ge) {
                x->old_hit = 1;
                if (parent >= 0) {
                    step.by = kept->a[i];
                    Edge e = {parent, kept->a[i], (int32_t)(-x->steps.n - 1)};
                    PUSH(x->steps, step);
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
            if (!old->expanded) {
                slot_drop(x, old->zone);
                old->zone = -1;
                x->dropped++;
            }
        }
        if (x->under.n)
            kept_remove(x, kept, x->under.a, x->under.n);
    }
    if (x->merge && kept->n) {
        double *own = T(x, 3);  /* the zone as it came, if it merges */
        int got = merge_into(x, &step, zone, kept, ready != NULL, own);
        if (got < 0)
            return got;
        if (got)
            ready = NULL;  /* the zone is now the hull */
        x->merged += got;
        if (step.members >= 0 && (step.own = (int32_t)slot_new(x, own, NULL)) < 0)
            return -9;
    }
    if ((step.zone = (int32_t)slot_new(x, zone, ready)) < 0)
        return -9;
    int32_t index = (int32_t)x->nodes.n;
    PUSH(x->nodes, step);
    if (parent >= 0) {
        Edge e = {parent, index, index};
        PUSH(x->edges, e);
    }
    if (kept_push(x, kept, index, step.zone))
        return -9;
    PUSH(x->waiting, index);
    x->pending[step.state]++;
    return 0;
}

/* -- observers and response clocks (search.py's check) ------------------------------------------------ */
static void check(Ctx *x, int32_t k, const int64_t *pr)
{
    int d = x->d;
    Parts q = parts(pr);
    const int64_t *c = q.checks;
    int64_t n = *c++;
    int64_t slot = x->nodes.a[k].zone;
    for (int64_t i = 0; i < n; i++, c += 4) {
        double top = entry(x, slot, (int64_t)c[2] * d);
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

/* Time passing at ``state`` from zone z (already reset and forgotten), every piece stored. */
static int arrive(Ctx *x, int64_t state, double *z, int32_t parent, int32_t via, const int64_t *guard,
                  int64_t nguard, program_fn ask)
{
    const int64_t *pr = program(x, state, ask);
    if (!pr)
        return x->failed;
    Parts q = parts(pr);
    if (q.nidle) {
        int idx[256];
        for (int64_t k = 0; k < q.nidle; k++)
            idx[k] = (int)q.idle[k];
        z_free(z, z, x->d, idx, (int)q.nidle);  /* in place: see z_free */
    }
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
        return add(x, state, z, parent, via, guard, nguard, 0, lower, upper, plus);
    x->out.n = x->grown.n = 0;
    int64_t n = elapse(x, q.pass, z, &x->out, &x->grown);
    int status = n < 0 ? (int)n : 0;
    for (int64_t k = 0; k < n && !status; k++)
        status = add(x, state, x->out.a + k * x->d * x->d, parent, via, guard, nguard, (int)x->grown.a[k], lower,
                     upper, plus);
    return status;
}

int zs_initial(void *p, int64_t state, const double *zone, program_fn ask)
{
    Ctx *x = p;
    double *z = T(x, 1);
    memcpy(z, zone, (int64_t)x->d * x->d * sizeof(double));
    return arrive(x, state, z, -1, -1, NULL, 0, ask);
}

/* The number of successor entry ``*id`` of state ``state``'s program, interned now if it was not yet (a program
 * written in C names its successors by their index among the step's successors until a step takes them); the
 * entry is then rewritten with it.  < 0: no memory (-9), or the step no longer gives that successor. */
static int64_t resolve(Ctx *x, int64_t state, int64_t *id)
{
    if (*id >= 0)
        return *id;
    Tables *t = x->tables;
    SuccBuf *b = &t->rbuf;
    if (b->state != state || !b->cap) {  /* one expansion takes several successors of the same state */
        int64_t *w = malloc(t->W * sizeof(int64_t));
        if (!w)
            return -9;
        state_words(x, state, w);
        int n = step_successors(t, w, b);
        free(w);
        if (n == -9)
            return -9;  /* no memory for the successors (b->state stays -1: none held) */
        b->state = state;
    }
    int64_t k = -*id - 1;
    if (b->n <= k) {
        b->state = -1;
        return b->n == -9 ? -9 : -1;
    }
    int64_t got = intern(x, b->words + k * t->W);
    if (got >= 0)
        *id = got;
    return got;
}

/* Bytes the search holds: zones, states' words, programs' words are counted as they are kept. */
int64_t zs_memory(Ctx *x)
{
    return zone_bytes(x) + x->bytes.n + x->ends.n * 16 + x->prog_words * 8 + x->nodes.n * (int64_t)sizeof(Node)
           + x->steps.n * (int64_t)sizeof(Node) + x->edges.n * (int64_t)sizeof(Edge) + x->guards.n * 8;
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
        x->nodes.a[k].expanded = 1;
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
        slot_load(x, x->nodes.a[k].zone, here);
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
                const int64_t *nb = s + 2, *rs = skip_bounds(nb), *bl = rs + 1 + 2 * rs[0];
                int64_t nblocks = *bl++;
                const int64_t *blocks = bl;
                for (int64_t b = 0; b < nblocks; b++)
                    bl = skip_bounds(bl);
                s = bl;
                if (keep && in_list(keep, via) != (round == 0))
                    continue;
                memcpy(met, here, len * sizeof(double));
                if (!constrain_all(met, d, nb + 1, nb[0]))
                    continue;
                /* allowed: the pieces of met outside every block, each with its cut bounds; while no block meets
                 * met (``whole``), met itself is the one piece, not copied */
                int whole = 1;
                pieces.n = cuts.n = ncut.n = 0;
                const int64_t *b = blocks;
                for (int64_t bi = 0; bi < nblocks && (whole || pieces.n); bi++) {
                    memcpy(block, met, len * sizeof(double));
                    int live = constrain_all(block, d, b + 1, b[0]);
                    b = skip_bounds(b);
                    if (!live)
                        continue;
                    if (whole) {
                        whole = 0;
                        if (append(&pieces, met, len))
                            goto nomem;
                        PUSH_OR(ncut, 0, goto nomem);
                    }
                    next.n = ncuts.n = nn.n = 0;
                    int64_t off = 0;
                    for (int64_t pi = 0; pi * len < pieces.n; pi++) {
                        pc.n = pn.n = 0;
                        if (subtract(pieces.a + pi * len, block, d, T(x, 6), T(x, 7), &next, &pc, &pn))
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
                        memcpy(z, pieces.a + pi * len, len * sizeof(double));
                    for (int64_t r = 0; r < rs[0]; r++)
                        z_reset(z, d, (int)rs[1 + 2 * r], (double)rs[2 + 2 * r]);
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
                    status = arrive(x, nxt, z, k, (int32_t)via, need.a, need.n / 3, ask);
                    /* arrive may move the program array: re-read nothing from it after this point */
                }
                /* T(x, 0) (here) is never used by arrive, so the next successor starts from the same zone */
            }
        }
        if (status)
            break;
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
    out[15] = x->reduced;
}

/* A node's (or a step's) fields as an int64 row of 10: state parent via by zone own members guard guard_len
 * grown|covered<<1|expanded<<2. */
static void node_row(const Node *a, int64_t *r)
{
    r[0] = a->state, r[1] = a->parent, r[2] = a->via, r[3] = a->by, r[4] = a->zone;
    r[5] = a->own, r[6] = a->members, r[7] = a->guard, r[8] = a->guard_len;
    r[9] = a->grown | a->covered << 1 | a->expanded << 2;
}

/* Every node's row. */
void zs_nodes(void *p, int64_t *out)
{
    Ctx *x = p;
    for (int64_t i = 0; i < x->nodes.n; i++)
        node_row(x->nodes.a + i, out + 10 * i);
}

/* The row of step k into a covered zone (steps are many, and a trace reads a few). */
void zs_step_row(void *p, int64_t k, int64_t *out)
{
    node_row(((Ctx *)p)->steps.a + k, out);
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
        const int64_t *rs = skip_bounds(s + 2), *bl = rs + 1 + 2 * rs[0];
        int64_t nb = *bl++;
        for (int64_t b = 0; b < nb; b++)
            bl = skip_bounds(bl);
        s = bl;
    }
    int64_t len = s - pr;
    if (len <= cap)
        memcpy(out, pr, len * sizeof(int64_t));
    return len;
}

/* Where the number after the first ``n`` of b[0..len) starts: eight bytes at a time while they hold no more ends
 * than are left to skip (a byte with its high bit clear ends a number). */
static const uint8_t *skip_words(const uint8_t *b, int64_t len, int n)
{
    const uint8_t *end = b + len;
    while (n > 0 && b + 8 <= end) {
        uint64_t v;
        memcpy(&v, b, 8);
        int ends = __builtin_popcountll(~v & 0x8080808080808080ull);
        if (ends > n)
            break;
        b += 8, n -= ends;
    }
    for (; n > 0; b++)
        n -= !(*b & 0x80);
    return b;
}

/* Word ``offset`` of each of the states ids[0..n) into out (the words before it skipped, not decoded). */
void zs_node_words(void *p, const int64_t *ids, int64_t n, int offset, int64_t *out)
{
    Ctx *x = p;
    int64_t len;
    for (int64_t i = 0; i < n; i++) {
        const uint8_t *b = state_bytes(x, ids[i], &len);
        decode(skip_words(b, len, offset), 1, out + i);
    }
}
