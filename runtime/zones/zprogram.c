/* Discrete states' programs (zsearch.c's header) written in C: ZoneExplorer.program() line for line, on the
 * words of the compiled step (runtime/native), whose c_successors gives each state's successors.
 *
 * The model's clock side comes as one table of int64 (runtime/zones/ctables.py writes it): expressions as
 * postfix code, atoms with their places (time passing there, invariants, clocks read), clock guards and resets
 * of transitions, compound priorities with their guards and chains, observers and response clocks.  What an
 * interaction number stands for (its engine index, ports and priorities) is asked of Python once per number.
 * Whatever this file does not take (an expression outside the code, a marking of two places, a priority cycle,
 * an error of the step) sends the state back to Python's program(), the reference, which computes it or
 * raises the error it would raise anyway.
 */
#include <stdint.h>

typedef int (*succ_fn)(const int64_t *s, int64_t *out, int64_t *via, int max, int64_t budget, int *ecode,
                       int64_t *earg);
typedef int (*inter_fn)(int64_t number);

enum { OP_END, OP_CONST, OP_SLOT, OP_NEG, OP_ADD, OP_SUB, OP_MUL, OP_LT, OP_LE, OP_GT, OP_GE, OP_EQ, OP_NE,
       OP_AND, OP_OR, OP_NOT };
#define BACK 1  /* "send this state back to Python" */
#define NO_BOUND -2  /* model.py's NO_BOUND: the L or U of a side no guard ahead bounds (minus infinity) */

/* The step's successors of one state: words, interactions, room for cap; ``state``: whose, -1 none. */
typedef struct { int64_t *words, *via; int cap, n; } SuccBuf;

/* A growable list of int64 (lpush, lcat below). */
typedef struct { int64_t *a; int64_t n, cap; } L;

typedef struct {
    const int64_t *code;
    int W, n, natoms, ntimed, nrules, ntick, nobs, nmeas, nsteps, local;
    const int64_t *atom_offset, *atom_nplaces;
    const int64_t **place;   /* per atom, per place: ticks, discrete, natoms, atoms (clock op expr)..., nactive, ... */
    int64_t *place_base;
    const int64_t *clock_atom, *timed, *tick, *obs, *meas;
    const int64_t *goal;     /* ngroups (-1: none), per group: n, (offset, mask)... */
    const int64_t **step;    /* natoms, (clock op expr)..., nresets, (clock expr)... */
    const int64_t **rule;    /* kind, [ndiag triples | expr], nedges, edges... */
    int64_t *blob;
    succ_fn succ;
    int64_t budget;
    SuccBuf wbuf;            /* the step's successors of the state whose program is being written */
    int64_t *top_gen, *top_idx, gen;  /* per rule: its region at the state being written (memo entry), if top_gen
                                       * is that program's generation: the memo's common case found at once */
    int64_t *chain_gen, *chain_head;  /* per rule: its last memo entry in program chain_gen's memo (memo_prev on) */
    int64_t *high_gen, *high_head;    /* per rule: the first of its high side's interactions in program high_gen's
                                       * list (Prog's high) */
    inter_fn ask_inter;
    /* The lists a program's writing works in, kept from one program to the next so that they are not grown again
     * from nothing for each state (write_program empties the memo's).  The memo of regions: rule, acc, result (each
     * result: a list of [n, triples...]). */
    L memo_key;              /* per memo entry: r, nacc, acc... */
    L memo_off;              /* per memo entry: where its result starts in pool */
    L memo_at;               /* per memo entry: where its key starts in memo_key */
    L memo_prev;             /* per memo entry: the entry of the same rule before it, -1 for none */
    L pool;                  /* results: count (-1: everywhere), then per region: n, triples... */
    L high;                  /* pairs (enabled interaction, next pair of the same rule or -1): index_highs */
    L path;                  /* the rules region is within (rule_region empties it) */
    L **deep;                /* per depth of region's recursion: its three lists (depth_lists) */
    int64_t ndeep;
} Tables;

/* -- the table ------------------------------------------------------------------------------------ */
static void tables_free(Tables *t)
{
    if (!t)
        return;
    free(t->place), free(t->place_base), free(t->step), free(t->rule), free(t->blob);
    free(t->wbuf.words), free(t->wbuf.via), free(t->top_gen), free(t->top_idx);
    free(t->chain_gen), free(t->chain_head), free(t->high_gen), free(t->high_head);
    free(t->memo_key.a), free(t->memo_off.a), free(t->memo_at.a), free(t->memo_prev.a), free(t->pool.a);
    free(t->high.a), free(t->path.a);
    for (int64_t k = 0; k < t->ndeep; k++)
        if (t->deep[k])
            free(t->deep[k][0].a), free(t->deep[k][1].a), free(t->deep[k][2].a), free(t->deep[k]);
    free(t->deep);
    free(t);
}

static const int64_t *skip_atoms(const int64_t *p) { return p + 1 + 3 * p[0]; }

static Tables *tables_read(const int64_t *words, int64_t len)
{
    Tables *t = calloc(1, sizeof(Tables));
    if (!t)
        return NULL;
    t->blob = malloc(len * sizeof(int64_t));
    if (!t->blob)
        goto nomem;
    memcpy(t->blob, words, len * sizeof(int64_t));
    const int64_t *p = t->blob;
    t->W = (int)*p++, t->n = (int)*p++, t->natoms = (int)*p++, t->ntimed = (int)*p++, t->nrules = (int)*p++;
    t->ntick = (int)*p++, t->nobs = (int)*p++, t->nmeas = (int)*p++, t->nsteps = (int)*p++, t->local = (int)*p++;
    int64_t ncode = *p++;
    t->code = p;
    p += ncode;
    t->atom_offset = p;
    p += t->natoms;
    t->atom_nplaces = p;
    p += t->natoms;
    t->place_base = malloc((t->natoms + 1) * sizeof(int64_t));
    if (!t->place_base)
        goto nomem;
    int64_t total = 0;
    for (int a = 0; a < t->natoms; a++)
        t->place_base[a] = total, total += t->atom_nplaces[a];
    t->place = malloc((total + 1) * sizeof(int64_t *));
    if (!t->place)
        goto nomem;
    for (int64_t k = 0; k < total; k++) {
        t->place[k] = p;
        p += 2;  /* ticks, discrete */
        p = skip_atoms(p);
        p += 1 + p[0];  /* active clocks */
        p += 1 + 3 * p[0];  /* (clock, L, U) of the place */
    }
    t->clock_atom = p;
    p += t->n + 1;
    t->timed = p;
    p += t->ntimed;
    t->step = malloc((t->nsteps + 1) * sizeof(int64_t *));
    if (!t->step)
        goto nomem;
    for (int k = 0; k < t->nsteps; k++) {
        t->step[k] = p;
        p = skip_atoms(p);
        p += 1 + 2 * p[0];
    }
    t->rule = malloc((t->nrules + 1) * sizeof(int64_t *));
    t->top_gen = calloc(t->nrules + 1, sizeof(int64_t));
    t->top_idx = calloc(t->nrules + 1, sizeof(int64_t));
    t->chain_gen = calloc(t->nrules + 1, sizeof(int64_t));
    t->chain_head = calloc(t->nrules + 1, sizeof(int64_t));
    t->high_gen = calloc(t->nrules + 1, sizeof(int64_t));
    t->high_head = calloc(t->nrules + 1, sizeof(int64_t));
    if (!t->rule || !t->top_gen || !t->top_idx || !t->chain_gen || !t->chain_head || !t->high_gen || !t->high_head)
        goto nomem;
    for (int r = 0; r < t->nrules; r++) {
        t->rule[r] = p;
        int64_t kind = *p++;
        if (kind == 1)
            p += 1 + 3 * p[0];
        else if (kind == 2)
            p++;
        p += 1 + p[0];
    }
    t->tick = p;
    p += t->ntick;
    t->obs = p;
    p += 5 * t->nobs;
    t->meas = p;
    p += 3 * t->nmeas;
    t->goal = p;
    return t;
nomem:
    tables_free(t);
    return NULL;
}

int zs_set_interaction(void *p, int64_t number, const int64_t *words, int64_t n);

/* -- expressions -------------------------------------------------------------------------------- */
static int ev(const Tables *t, int64_t at, const int64_t *s, int64_t *out)
{
    if (at < 0)
        return BACK;
    int64_t st[64];
    int sp = 0;
    for (const int64_t *c = t->code + at;; ) {
        int64_t op = *c++;
        if (op == OP_END)
            break;
        if (op == OP_CONST || op == OP_SLOT) {
            if (sp == 64)
                return BACK;
            st[sp++] = op == OP_CONST ? *c : s[*c];
            c++;
            continue;
        }
        if (op == OP_NEG || op == OP_NOT) {
            if (sp < 1)
                return BACK;
            st[sp - 1] = op == OP_NEG ? -st[sp - 1] : !st[sp - 1];
            continue;
        }
        if (sp < 2)
            return BACK;
        int64_t a = st[sp - 2], b = st[sp - 1], v;
        switch (op) {
        case OP_ADD: v = a + b; break;
        case OP_SUB: v = a - b; break;
        case OP_MUL: v = a * b; break;
        case OP_LT: v = a < b; break;
        case OP_LE: v = a <= b; break;
        case OP_GT: v = a > b; break;
        case OP_GE: v = a >= b; break;
        case OP_EQ: v = a == b; break;
        case OP_NE: v = a != b; break;
        case OP_AND: v = a && b; break;
        case OP_OR: v = a || b; break;
        default: return BACK;
        }
        st[--sp - 1] = v;
    }
    if (sp != 1)
        return BACK;
    *out = st[0];
    return 0;
}

/* -- small growable lists of int64 ---------------------------------------------------------------- */

/* A push found no memory since write_program began: the program it writes is then incomplete, and it says -9.
 * A list keeps what it held.  region checks each push itself (it reads back what it pushed). */
static _Thread_local int list_failed;

/* Room for ``more`` numbers after l's; -9 (list_failed set) without memory.  Out of line, so that the pushes below,
 * inlined (gcc leaves them out of line otherwise: a program's millions of calls cost a tenth of whole DALA's
 * search), stay a compare and a store. */
static __attribute__((noinline)) int lgrow(L *l, int64_t more)
{
    int64_t cap = l->cap ? 2 * l->cap : 32;
    while (cap < l->n + more)
        cap *= 2;
    int64_t *a = realloc(l->a, cap * sizeof(int64_t));
    if (!a) {
        list_failed = 1;
        return -9;
    }
    l->a = a, l->cap = cap;
    return 0;
}

static inline __attribute__((always_inline)) int lpush(L *l, int64_t v)
{
    if (l->n == l->cap && lgrow(l, 1))
        return -9;
    l->a[l->n++] = v;
    return 0;
}

/* n numbers appended to l (v not within l); -9 without memory, l as it was. */
static inline __attribute__((always_inline)) int lcat(L *l, const int64_t *v, int64_t n)
{
    if (n <= 0)
        return 0;
    if (l->n + n > l->cap && lgrow(l, n))
        return -9;
    memcpy(l->a + l->n, v, n * sizeof(int64_t));
    l->n += n;
    return 0;
}

/* clock atoms (clock, op, expr) as bounds i j c appended to out (search.py's bounds) */
static int bounds(const Tables *t, const int64_t *atoms, const int64_t *s, L *out)
{
    for (int64_t k = 0; k < atoms[0]; k++) {
        int64_t clock = atoms[1 + 3 * k], op = atoms[2 + 3 * k], v;
        if (ev(t, atoms[3 + 3 * k], s, &v))
            return BACK;
        switch (op) {
        case 0: lpush(out, clock), lpush(out, 0), lpush(out, v - 1); break;
        case 1: lpush(out, clock), lpush(out, 0), lpush(out, v); break;
        case 2: lpush(out, 0), lpush(out, clock), lpush(out, -(v + 1)); break;
        case 3: lpush(out, 0), lpush(out, clock), lpush(out, -v); break;
        default:
            lpush(out, clock), lpush(out, 0), lpush(out, v);
            lpush(out, 0), lpush(out, clock), lpush(out, -v);
        }
    }
    return 0;
}

/* the index of the one place marked in a marking, -1 when it is not exactly one */
static int one_place(int64_t bits)
{
    if (bits <= 0 || (bits & (bits - 1)))
        return -1;
    return __builtin_ctzll((uint64_t)bits);
}

/* -- one state's program ------------------------------------------------------------------------ */
typedef struct {
    Tables *t;             /* with the lists the program is written in (memo, high, path, deep) */
    const int64_t *s;
    int d;
    double *scratch;
    /* enabled interactions: engine index and their table rows, in engine order */
    int64_t *index;
    int64_t **row;
    int64_t nen;
    int64_t gen;           /* this program's number (Tables' top_gen) */
    int highs;             /* Tables' high built for this program (index_highs, at the first region) */
} Prog;

/* Some clock values meet every bound (i, j, c: x_i - x_j <= c, clock 0 the zero): no negative cycle among the
 * clocks the bounds name, every clock being at least 0.  Only those clocks are looked at, so that a check of
 * two or three bounds costs a few dozen operations whatever the number of clocks. */
/* Some clock values meet every bound (i, j, c: x_i - x_j <= c, clock 0 the zero), every clock being at least 0:
 * no negative cycle among the clocks the bounds name.  Only those clocks are looked at, so that two or three
 * bounds cost a few dozen operations whatever the number of clocks. */
static int feasible(Prog *g, const int64_t *b, int64_t n)
{
    if (n > 31) {  /* more than the small matrix takes: the whole zone */
        int d = g->d;
        double *z = g->scratch;
        for (int i = 0; i < d; i++)
            for (int j = 0; j < d; j++)
                z[(int64_t)i * d + j] = i == 0 || i == j ? 0 : INFINITY;
        for (int64_t k = 0; k < n; k++)
            if (!z_constrain(z, d, (int)b[3 * k], (int)b[3 * k + 1], (double)b[3 * k + 2]))
                return 0;
        return 1;
    }
    int ids[64], at[64], m = 1;
    double w[64 * 64];
    ids[0] = 0;
    for (int64_t k = 0; k < n; k++)
        for (int e = 0; e < 2; e++) {
            int c = (int)b[3 * k + e], f = -1;
            for (int q = 0; q < m && f < 0; q++)
                if (ids[q] == c)
                    f = q;
            if (f < 0)
                ids[f = m++] = c;
            at[2 * k + e] = f;
        }
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++)
            w[i * m + j] = i == 0 || i == j ? 0 : INFINITY;
    for (int64_t k = 0; k < n; k++) {
        double c = (double)b[3 * k + 2];
        int i = at[2 * k], j = at[2 * k + 1];
        if (c < w[i * m + j])
            w[i * m + j] = c;
    }
    for (int k = 0; k < m; k++)
        for (int i = 0; i < m; i++) {
            double ik = w[i * m + k];
            if (ik == INFINITY)
                continue;
            for (int j = 0; j < m; j++)
                if (ik + w[k * m + j] < w[i * m + j])
                    w[i * m + j] = ik + w[k * m + j];
        }
    for (int i = 0; i < m; i++)
        if (w[i * m + i] < 0)
            return 0;
    return 1;
}

/* the need bounds of enabled interaction e (its guard at this state, search.py's guard) */
static int need_of(Prog *g, const int64_t *row, L *need, L *resets)
{
    const Tables *t = g->t;
    const int64_t *p = row + 1;
    int64_t nports = *p++;
    for (int64_t k = 0; k < nports; k++) {
        int64_t atom = p[0], nplaces = p[1];
        const int64_t *steps = p + 2;
        p += 2 + nplaces;
        int pi = one_place(g->s[t->atom_offset[atom]]);
        if (pi < 0 || pi >= nplaces || steps[pi] < 0)
            continue;
        const int64_t *st = t->step[steps[pi]];
        if (bounds(t, st, g->s, need))
            return BACK;
        if (resets) {
            const int64_t *rs = skip_atoms(st);
            for (int64_t r = 0; r < rs[0]; r++) {
                int64_t v;
                if (ev(t, rs[2 + 2 * r], g->s, &v))
                    return BACK;
                lpush(resets, rs[1 + 2 * r]), lpush(resets, v);
            }
        }
    }
    return 0;
}

static const int64_t *lows(const int64_t *row)
{
    const int64_t *p = row + 1;
    int64_t nports = *p++;
    for (int64_t k = 0; k < nports; k++)
        p += 2 + p[1];
    return p;  /* nlow, lows..., nhigh, highs... */
}

static int cmp3(const void *a, const void *b)
{
    const int64_t *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* regions of rule r under acc (search.py's Blocking._region) appended to out as [n, triples...] each;
 * *everywhere set when the result is [[]]. */
static int region(Prog *g, int64_t r, const int64_t *acc0, int64_t nacc0, L *path, L *out, int *everywhere);

static int memo_find(Prog *g, int64_t r, const int64_t *acc, int64_t nacc)
{
    const Tables *t = g->t;
    if (!nacc)
        return t->top_gen[r] == g->gen ? (int)t->top_idx[r] : -1;
    if (t->chain_gen[r] != g->gen)
        return -1;
    for (int64_t k = t->chain_head[r]; k >= 0; k = t->memo_prev.a[k]) {  /* the rule's entries alone */
        const int64_t *key = t->memo_key.a + t->memo_at.a[k];
        if (key[1] == nacc && !memcmp(key + 2, acc, 3 * nacc * sizeof(int64_t)))
            return (int)k;
    }
    return -1;
}

/* For each rule, the enabled interactions whose high side names it, in engine order: a chain of Tables' high pairs
 * from its high_head, valid where high_gen is this program's (a rule's region is asked for once per acc:
 * scanning every enabled interaction each time cost a tenth of whole DALA's search; a table over every rule, cleared
 * for each program, cost 3 % more).  0, or -9 without memory. */
static int index_highs(Prog *g)
{
    Tables *t = g->t;
    t->high.n = 0;
    for (int64_t e = g->nen - 1; e >= 0; e--) {  /* each pushed in front of its rule's chain: engine order */
        const int64_t *hl = lows(g->row[e]);
        hl += 1 + hl[0];
        for (int64_t k = 0; k < hl[0]; k++) {
            int64_t r = hl[1 + k], seen = r < 0 || r >= t->nrules;
            for (int64_t j = 0; j < k && !seen; j++)
                seen = hl[1 + j] == r;  /* an interaction once per rule */
            if (seen)
                continue;
            if (lpush(&t->high, e) || lpush(&t->high, t->high_gen[r] == g->gen ? t->high_head[r] : -1))
                return -9;
            t->high_gen[r] = g->gen, t->high_head[r] = t->high.n / 2 - 1;
        }
    }
    g->highs = 1;
    return 0;
}

/* The three lists (acc, mine, kept) of region at this depth of its recursion, emptied; NULL without memory.  Each
 * depth's are allocated once and kept from program to program (Tables' deep), at addresses that do not move. */
static L *depth_lists(Prog *g, int64_t depth)
{
    Tables *t = g->t;
    if (depth >= t->ndeep) {
        int64_t n = t->ndeep ? 2 * t->ndeep : 8;
        while (n <= depth)
            n *= 2;
        L **a = realloc(t->deep, n * sizeof(L *));
        if (!a)
            return NULL;
        for (int64_t k = t->ndeep; k < n; k++)
            a[k] = NULL;
        t->deep = a, t->ndeep = n;
    }
    if (!t->deep[depth] && !(t->deep[depth] = calloc(3, sizeof(L))))
        return NULL;
    L *l = t->deep[depth];
    l[0].n = l[1].n = l[2].n = 0;
    return l;
}

static int region(Prog *g, int64_t r, const int64_t *acc0, int64_t nacc0, L *path, L *out, int *everywhere)
{
    Tables *t = g->t;
    *everywhere = 0;
    int hit = memo_find(g, r, acc0, nacc0);
    if (hit >= 0) {
        const int64_t *v = t->pool.a + t->memo_off.a[hit];
        if (v[0] < 0) {
            *everywhere = 1;
            return 0;
        }
        int64_t at = 1;
        for (int64_t k = 0; k < v[0]; k++) {
            if (lcat(out, v + at, 1 + 3 * v[at]))
                return -9;
            at += 1 + 3 * v[at];
        }
        return 0;
    }
    const int64_t *rule = t->rule[r];
    L *lists = depth_lists(g, path->n);
    if (!lists)
        return -9;
    L acc = lists[0], mine = lists[1];  /* written back at the end (their arrays may grow) */
    int status = 0, all = 0;
    int64_t kind = rule[0];
    const int64_t *edges;
    if (lcat(&acc, acc0, 3 * nacc0) || (kind == 1 && lcat(&acc, rule + 2, 3 * rule[1]))) {
        status = -9;
        goto done;
    }
    if (kind == 1) {
        qsort(acc.a, acc.n / 3, 3 * sizeof(int64_t), cmp3);
        int64_t w = 0;
        for (int64_t k = 0; k < acc.n / 3; k++)
            if (!w || cmp3(acc.a + 3 * k, acc.a + 3 * (w - 1))) {
                memmove(acc.a + 3 * w, acc.a + 3 * k, 3 * sizeof(int64_t));
                w++;
            }
        acc.n = 3 * w;
        edges = rule + 2 + 3 * rule[1];
        if (!feasible(g, acc.a, w))
            goto store;
    } else if (kind == 2) {
        int64_t v;
        if (ev(t, rule[1], g->s, &v)) {
            status = BACK;
            goto done;
        }
        edges = rule + 2;
        if (!v)
            goto store;
    } else if (kind == 0) {
        edges = rule + 1;
    } else {
        status = BACK;
        goto done;
    }
    for (int64_t k = 0; k < path->n; k++)
        if (path->a[k] == r) {
            status = BACK;  /* a priority cycle: Python names it */
            goto done;
        }
    if (!g->highs && index_highs(g)) {
        status = -9;
        goto done;
    }
    for (int64_t h = t->high_gen[r] == g->gen ? t->high_head[r] : -1; h >= 0; h = t->high.a[2 * h + 1]) {
        int64_t e = t->high.a[2 * h];
        int64_t at = mine.n;  /* the high side's need, written in place after its count */
        if (lpush(&mine, 0) || lcat(&mine, acc.a, acc.n)) {
            status = -9;
            goto done;
        }
        if (need_of(g, g->row[e], &mine, NULL)) {
            status = BACK;
            goto done;
        }
        if (mine.n == at + 1) {
            mine.n = at;
            all = 1;
            goto store;
        }
        mine.a[at] = (mine.n - at - 1) / 3;
    }
    if (lpush(path, r)) {
        status = -9;
        goto done;
    }
    for (int64_t k = 0; k < edges[0] && !all; k++) {
        int64_t at = mine.n;  /* the lower rule's regions, appended in place */
        int every;
        status = region(g, edges[1 + k], acc.a, acc.n / 3, path, &mine, &every);
        if (status) {
            path->n--;
            goto done;
        }
        if (every) {
            mine.n = at;
            all = 1;
        } else {
            for (int64_t q = at; q < mine.n; q += 1 + 3 * mine.a[q])
                if (!mine.a[q]) {  /* an empty region: everywhere */
                    mine.n = at;
                    all = 1;
                    break;
                }
        }
    }
    path->n--;
store:
    {
        /* keep the feasible ones, then remember: the memo's lists grow together or not at all (memo_find follows
         * a rule's chain from chain_head through memo_prev, and reads each entry's key at memo_at) */
        L kept = lists[2];
        int64_t count = 0, key_n = t->memo_key.n, pool_n = t->pool.n, entries = t->memo_at.n;
        int64_t prev = t->chain_gen[r] == g->gen ? t->chain_head[r] : -1;
        if (!all)
            for (int64_t at = 0; at < mine.n && !status; at += 1 + 3 * mine.a[at])
                if (feasible(g, mine.a + at + 1, mine.a[at])) {
                    status = lcat(&kept, mine.a + at, 1 + 3 * mine.a[at]);
                    count++;
                }
        if (status || lpush(&t->memo_key, r) || lpush(&t->memo_key, nacc0) || lcat(&t->memo_key, acc0, 3 * nacc0)
            || lpush(&t->pool, all ? -1 : count) || lcat(&t->pool, kept.a, kept.n) || lpush(&t->memo_at, key_n)
            || lpush(&t->memo_prev, prev) || lpush(&t->memo_off, pool_n)) {
            t->memo_key.n = key_n, t->pool.n = pool_n, t->memo_at.n = t->memo_prev.n = entries;
            status = -9;
        } else {
            t->chain_gen[r] = g->gen, t->chain_head[r] = entries;
            if (!nacc0)
                t->top_gen[r] = g->gen, t->top_idx[r] = t->memo_off.n - 1;
            if (all)
                *everywhere = 1;
            else if (lcat(out, kept.a, kept.n))
                status = -9;
        }
        lists[2] = kept;
    }
done:
    lists[0] = acc, lists[1] = mine;
    return status;
}

static int rule_region(Prog *g, int64_t r, L *out, int *everywhere)
{
    g->t->path.n = 0;  /* a rule asked for at the top: within no other */
    return region(g, r, NULL, 0, &g->t->path, out, everywhere);
}

/* The step's successors of state s into b, grown as needed: their number, or < 0 (-9 memory; else the step's
 * error, which Python's successors handle). */
static int step_successors(Tables *t, const int64_t *s, SuccBuf *b)
{
    int ecode;
    int64_t earg;
    if (!b->cap) {
        b->cap = 64;
        b->words = malloc((size_t)b->cap * t->W * sizeof(int64_t));
        b->via = malloc((size_t)b->cap * sizeof(int64_t));
    }
    for (;;) {
        if (!b->words || !b->via)
            return -9;
        int n = t->succ(s, b->words, b->via, b->cap, t->budget, &ecode, &earg);
        if (n >= 0 || b->cap >= 65536 || ecode != 10)
            return b->n = n == -9 ? -10 : n;
        b->cap *= 4;
        free(b->words), free(b->via);
        b->words = malloc((size_t)b->cap * t->W * sizeof(int64_t));
        b->via = malloc((size_t)b->cap * sizeof(int64_t));
    }
}

/* Write the program of state s (words) into prog; BACK: let Python write it.  A successor goes into the program
 * as -(its index among the step's successors) - 1, interned only when a step first takes it (zsearch.c). */

static int64_t *inter_row(void *ctx, Tables *t, int64_t number);

static int write_program(void *ctx, Tables *t, const int64_t *s, int d, double *scratch, L *prog)
{
    int n = step_successors(t, s, &t->wbuf);
    int64_t *via = t->wbuf.via;
    if (n == -9)
        return -9;
    int status = 0;
    list_failed = 0;
    Prog g = {t, s, d, scratch, NULL, NULL, 0, ++t->gen, 0};
    t->memo_key.n = t->memo_off.n = t->memo_at.n = t->memo_prev.n = t->pool.n = 0;
    int64_t *sidx = NULL;
    int64_t **srow = NULL;
    if (n < 0) {
        status = BACK;  /* the step's own error, or a field to widen: Python's successors handle it */
        goto out;
    }
    sidx = malloc((n + 1) * sizeof(int64_t));
    srow = malloc((n + 1) * sizeof(int64_t *));
    g.index = malloc((n + 1) * sizeof(int64_t));
    g.row = malloc((n + 1) * sizeof(int64_t *));
    if (!sidx || !srow || !g.index || !g.row) {
        status = -9;
        goto out;
    }
    for (int i = 0; i < n; i++) {
        srow[i] = inter_row(ctx, t, via[i]);
        if (!srow[i]) {
            status = -1;
            goto out;
        }
        sidx[i] = srow[i][0];
    }
    /* enabled: distinct engine indices, ascending (insertion sort: a state has few) */
    for (int i = 0; i < n; i++) {
        int64_t e = 0;
        while (e < g.nen && g.index[e] < sidx[i])
            e++;
        if (e < g.nen && g.index[e] == sidx[i])
            continue;
        memmove(g.index + e + 1, g.index + e, (g.nen - e) * sizeof(int64_t));
        memmove(g.row + e + 1, g.row + e, (g.nen - e) * sizeof(int64_t *));
        g.index[e] = sidx[i], g.row[e] = srow[i], g.nen++;
    }
    /* idle clocks */
    L idle = {0};
    for (int k = 1; k <= t->n; k++) {
        int64_t atom = t->clock_atom[k];
        int pi = one_place(s[t->atom_offset[atom]]);
        if (pi < 0 || pi >= t->atom_nplaces[atom]) {
            free(idle.a);
            status = BACK;
            goto out;
        }
        const int64_t *pl = t->place[t->place_base[atom] + pi];
        const int64_t *act = skip_atoms(pl + 2);
        int on = 0;
        for (int64_t a = 0; a < act[0]; a++)
            on |= act[1 + a] == k;
        if (!on)
            lpush(&idle, k);
    }
    lpush(prog, idle.n), lcat(prog, idle.a, idle.n);
    /* clocks whose ceiling here is their place's; an idle one has no bound on either side (search.py's ceilings) */
    {
        L over = {0};
        for (int k = 1; k <= t->n && t->local; k++) {
            int is_idle = 0;
            for (int64_t a = 0; a < idle.n; a++)
                is_idle |= idle.a[a] == k;
            if (is_idle) {
                lpush(&over, k), lpush(&over, NO_BOUND), lpush(&over, NO_BOUND);
                continue;
            }
            int64_t atom = t->clock_atom[k];
            int pi = one_place(s[t->atom_offset[atom]]);
            const int64_t *pl = t->place[t->place_base[atom] + pi];
            const int64_t *act = skip_atoms(pl + 2);
            const int64_t *loc = act + 1 + act[0];
            for (int64_t a = 0; a < loc[0]; a++)
                if (loc[1 + 3 * a] == k) {
                    lpush(&over, k), lpush(&over, loc[2 + 3 * a]), lpush(&over, loc[3 + 3 * a]);
                    break;
                }
        }
        lpush(prog, over.n / 3), lcat(prog, over.a, over.n);
        free(over.a), free(idle.a);
    }
    /* time passing (search.py's _passing_at) */
    {
        L before = {0}, after = {0}, waits = {0};
        int passes = 1;
        for (int a = 0; a < t->ntimed && passes; a++) {
            int64_t atom = t->timed[a];
            int pi = one_place(s[t->atom_offset[atom]]);
            if (pi < 0 || pi >= t->atom_nplaces[atom]) {
                status = BACK;
                break;
            }
            const int64_t *pl = t->place[t->place_base[atom] + pi];
            if (!pl[0]) {
                passes = 0;
                break;
            }
            if (pl[1] != -1) {
                int64_t v;
                if (ev(t, pl[1], s, &v)) {
                    status = BACK;
                    break;
                }
                if (!v) {
                    passes = 0;
                    break;
                }
            }
            L b = {0};
            if (bounds(t, pl + 2, s, &b)) {
                free(b.a);
                status = BACK;
                break;
            }
            for (int64_t k = 0; k < b.n / 3; k++) {
                if (b.a[3 * k + 1] != 0) {
                    status = BACK;  /* time bounded from below: Python says where */
                    break;
                }
                lpush(&before, b.a[3 * k]), lpush(&before, 0), lpush(&before, b.a[3 * k + 2]);
                lpush(&after, b.a[3 * k]), lpush(&after, 0), lpush(&after, b.a[3 * k + 2] + 1);
            }
            free(b.a);
            if (status)
                break;
        }
        int64_t nwaits = 0;
        for (int r = 0; r < t->ntick && passes && !status; r++) {
            L reg = {0};
            int every;
            status = rule_region(&g, t->tick[r], &reg, &every);
            if (!status && every)
                passes = 0;
            for (int64_t at = 0; !status && passes && at < reg.n; at += 1 + 3 * reg.a[at]) {
                int64_t nb = reg.a[at];
                const int64_t *b = reg.a + at + 1;
                if (!nb) {
                    passes = 0;
                    break;
                }
                int64_t lower = -1;
                for (int64_t k = 0; k < nb && lower < 0; k++)
                    if (b[3 * k] == 0)
                        lower = k;
                lpush(&waits, nb), lcat(&waits, b, 3 * nb);
                if (nb == 1 && lower >= 0) {
                    lpush(&waits, 1), lpush(&waits, b[1]), lpush(&waits, b[2]);
                } else {
                    lpush(&waits, 0), lpush(&waits, 0), lpush(&waits, 0);
                }
                lpush(&waits, t->tick[r]);
                nwaits++;
            }
            free(reg.a);
        }
        if (!status) {
            if (!passes) {
                lpush(prog, 0);
            } else {
                lpush(prog, 1);
                lpush(prog, before.n / 3), lcat(prog, before.a, before.n);
                lpush(prog, after.n / 3), lcat(prog, after.a, after.n);
                lpush(prog, nwaits), lcat(prog, waits.a, waits.n);
            }
        }
        free(before.a), free(after.a), free(waits.a);
        if (status)
            goto out;
    }
    /* observers and response clocks watched here */
    {
        L checks = {0};
        for (int o = 0; o < t->nobs; o++) {
            const int64_t *ob = t->obs + 5 * o;  /* atom, place, clock, bound, slot */
            if (s[t->atom_offset[ob[0]]] != ((int64_t)1 << ob[1]))
                continue;
            int64_t v;
            if (ev(t, ob[3], s, &v)) {
                status = BACK;
                break;
            }
            lpush(&checks, 0), lpush(&checks, ob[4]), lpush(&checks, ob[2]), lpush(&checks, v);
        }
        for (int o = 0; o < t->nmeas && !status; o++) {
            const int64_t *m = t->meas + 3 * o;  /* atom, place, clock */
            if (s[t->atom_offset[m[0]]] == ((int64_t)1 << m[1])) {
                lpush(&checks, 1), lpush(&checks, 0), lpush(&checks, m[2]), lpush(&checks, 0);
            }
        }
        if (t->goal[0] >= 0 && !status) {  /* every group has a place marked */
            const int64_t *q = t->goal + 1;
            int all = 1;
            for (int64_t gi = 0; gi < t->goal[0]; gi++) {
                int any = 0;
                for (int64_t a = 0; a < q[0]; a++)
                    any |= s[q[1 + 2 * a]] == q[2 + 2 * a];
                all &= any;
                q += 1 + 2 * q[0];
            }
            if (all) {
                lpush(&checks, 2), lpush(&checks, 0), lpush(&checks, 0), lpush(&checks, 0);
            }
        }
        if (!status)
            lpush(prog, checks.n / 4), lcat(prog, checks.a, checks.n);
        free(checks.a);
        if (status)
            goto out;
    }
    /* successors */
    {
        int64_t count_at = prog->n, count = 0;
        lpush(prog, 0);
        L regions = {0}, need = {0}, resets = {0}, reg = {0};  /* each successor's, emptied for the next */
        for (int i = 0; i < n && !status; i++) {
            regions.n = need.n = resets.n = 0;
            int64_t nreg = 0;
            int blocked = 0;
            const int64_t *lw = lows(srow[i]);
            for (int64_t k = 0; k < lw[0] && !blocked && !status; k++) {
                reg.n = 0;
                int every;
                status = rule_region(&g, lw[1 + k], &reg, &every);
                if (!status && every)
                    blocked = 1;
                for (int64_t at = 0; !status && !blocked && at < reg.n; at += 1 + 3 * reg.a[at]) {
                    if (!reg.a[at]) {
                        blocked = 1;
                        break;
                    }
                    lcat(&regions, reg.a + at, 1 + 3 * reg.a[at]);
                    nreg++;
                }
            }
            if (!status && !blocked) {
                if (need_of(&g, srow[i], &need, &resets)) {
                    status = BACK;
                } else {
                    /* the successor is interned when a step first takes it (zsearch.c's resolve): most are
                     * timers' and overruns' steps whose clock guard no zone of this state meets */
                    int64_t id = -(int64_t)i - 1;
                    {
                        lpush(prog, id), lpush(prog, sidx[i]);
                        lpush(prog, need.n / 3), lcat(prog, need.a, need.n);
                        lpush(prog, resets.n / 2), lcat(prog, resets.a, resets.n);
                        lpush(prog, nreg), lcat(prog, regions.a, regions.n);
                        count++;
                    }
                }
            }
        }
        free(regions.a), free(need.a), free(resets.a), free(reg.a);
        if (!list_failed)
            prog->a[count_at] = count;
    }
out:
    if (list_failed && !status)
        status = -9;  /* the program lacks what a push could not add */
    free(sidx), free(srow), free(g.index), free(g.row);
    return status;
}
