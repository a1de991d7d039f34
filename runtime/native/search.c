/* The search over packed states, included after a model's generated step (runtime.native.cstep).

   States are bit-packed into NW 64-bit words by the generated pack/unpack (runtime.explore.codec's fields:
   markings, bools, declared domains, other ints zig-zag coded in a field the caller widens), numbered in
   order of discovery, with a parent and the interaction that first reached them.  The visited set is an
   open-addressing table of state numbers.  Breadth-first numbering makes the parent links shortest paths. */

typedef int (*progress_fn)(int64_t states, int64_t transitions, int64_t depth, int64_t frontier, int64_t memory);

typedef struct {
    int64_t states, transitions, depth, error_state, deadlocks, memory;
    int32_t status, ecode;
    int64_t earg;
} Result;

enum { S_COMPLETE, S_MAX_STATES, S_MAX_DEPTH, S_ERROR, S_DEADLOCK, S_INTERRUPTED, S_MAX_MEMORY, S_WIDEN, S_VIOLATED };

static uint64_t *STORE;
static uint32_t *PARENT, *VIA;
static int64_t NSTATES, CAP;
static uint32_t *TABLE;
static uint64_t TSIZE;
static int64_t *DEAD;
static int64_t NDEAD, DCAP;
static V *SUCC;
static uint32_t *SVIA;
static uint8_t *SBAD; /* successor i violates an observer */
static int64_t VIOL = -1;
static uint64_t *PK;
static int SCAP;
static int64_t EXTRA; /* bytes of the depth-first stack and marks */
static int POR;             /* reduce: expand an ample set where one is proper */
static int PROPER;          /* the last expansion was of a proper ample set */
static int64_t NREDUCED;    /* states expanded with a proper ample set */

static inline int same(const uint64_t *a, const uint64_t *b) {
    for (int i = 0; i < NW; i++) if (a[i] != b[i]) return 0;
    return 1;
}

static uint64_t hash(const uint64_t *w) {
    uint64_t h = UINT64_C(0x9E3779B97F4A7C15);
    for (int i = 0; i < NW; i++) {
        h ^= w[i];
        h *= UINT64_C(0xff51afd7ed558ccd);
        h ^= h >> 32;
    }
    /* murmur3's finaliser: every input bit reaches the low bits the table uses */
    h ^= h >> 33;
    h *= UINT64_C(0xc4ceb9fe1a85ec53);
    h ^= h >> 33;
    return h;
}

static int64_t memory(void) {
    return CAP * (NW * 8 + 8) + (int64_t)TSIZE * 4 + DCAP * 8 + EXTRA;
}

static void c_release(void) {
    free(STORE); free(PARENT); free(VIA); free(TABLE); free(DEAD); free(SUCC); free(SVIA); free(PK); free(SBAD);
    STORE = 0; PARENT = VIA = TABLE = 0; DEAD = 0; SUCC = 0; SVIA = 0; PK = 0; SBAD = 0; VIOL = -1;
    NSTATES = CAP = NDEAD = DCAP = NREDUCED = 0; TSIZE = 0; SCAP = 0; EXTRA = 0;
}

static void rehash(uint64_t size) {
    free(TABLE);
    TABLE = calloc(size, sizeof *TABLE);
    TSIZE = size;
    for (int64_t id = 0; id < NSTATES; id++) {
        uint64_t h = hash(STORE + id * NW) & (size - 1);
        while (TABLE[h]) h = (h + 1) & (size - 1);
        TABLE[h] = (uint32_t)(id + 1);
    }
}

/* the number of a packed state; a new one is numbered unless the limit is reached (-1) or memory is out (-2) */
static int64_t add(const uint64_t *w, uint32_t parent, uint32_t via, int64_t max_states, int *added) {
    uint64_t h = hash(w) & (TSIZE - 1);
    while (TABLE[h]) {
        int64_t id = TABLE[h] - 1;
        if (same(STORE + id * NW, w)) { *added = 0; return id; }
        h = (h + 1) & (TSIZE - 1);
    }
    if (max_states >= 0 && NSTATES >= max_states) return -1;
    if (NSTATES >= (int64_t)UINT32_MAX - 1) return -2;
    if (NSTATES == CAP) {
        int64_t cap = CAP ? CAP * 2 : 1024;
        uint64_t *s = realloc(STORE, cap * NW * 8);
        uint32_t *p = realloc(PARENT, cap * 4), *v = realloc(VIA, cap * 4);
        if (!s || !p || !v) { if (s) STORE = s; if (p) PARENT = p; if (v) VIA = v; return -2; }
        STORE = s; PARENT = p; VIA = v; CAP = cap;
    }
    memcpy(STORE + NSTATES * NW, w, NW * 8);
    PARENT[NSTATES] = parent;
    VIA[NSTATES] = via;
    TABLE[h] = (uint32_t)(NSTATES + 1);
    *added = 1;
    NSTATES++;
    if ((uint64_t)NSTATES * 2 > TSIZE) rehash(TSIZE * 2);
    return NSTATES - 1;
}

static void ensure_succ(int n) {
    if (n <= SCAP) return;
    int cap = SCAP ? SCAP : 64;
    while (cap < n) cap *= 2;
    SUCC = realloc(SUCC, (size_t)cap * W * sizeof *SUCC);
    SVIA = realloc(SVIA, (size_t)cap * sizeof *SVIA);
    PK = realloc(PK, (size_t)cap * NW * sizeof *PK);
    SBAD = realloc(SBAD, (size_t)cap);
    SCAP = cap;
}

#define MAXSUCC 65536

/* ---- partial-order reduction (tables from runtime.native.por) ---- */

static inline int has(const uint64_t *b, int i) { return (int)(b[i >> 6] >> (i & 63) & 1); }

/* T |= B, pushing the new members on the work list */
static inline void join(uint64_t *T, const uint64_t *B, int *work, int *nw) {
    for (int k = 0; k < SW; k++) {
        uint64_t add = B[k] & ~T[k];
        T[k] |= add;
        while (add) { int b = __builtin_ctzll(add); add &= add - 1; work[(*nw)++] = k * 64 + b; }
    }
}

/* the enabled interactions of the smallest invisible strong stubborn set seeded by one enabled source;
   n unchanged when none is smaller than the whole (PROPER says which) */
static int ample(int n, uint32_t *isrc, uint32_t *imask) {
    static uint64_t en[SW], T[SW], best[SW];
    static int work[NSRC + 1];
    PROPER = 0;
    memset(en, 0, sizeof en);
    int nen = 0;
    for (int i = 0; i < n; i++) if (!has(en, (int)isrc[i])) { en[isrc[i] >> 6] |= UINT64_C(1) << (isrc[i] & 63); nen++; }
    if (nen < 2) return n;
    int bestn = nen;
    for (int i = 0; i < n && bestn > 1; i++) {
        int e = (int)isrc[i];
        if (VISIBLE[e] || (i && isrc[i - 1] == isrc[i])) continue;
        memset(T, 0, sizeof T);
        T[e >> 6] |= UINT64_C(1) << (e & 63);
        int nw = 0, cnt = 0, ok = 1;
        work[nw++] = e;
        while (nw && ok) {
            int t = work[--nw];
            if (has(en, t)) {
                if (VISIBLE[t] || ++cnt >= bestn) { ok = 0; break; }
                join(T, DEP[t], work, &nw);
            } else {
                int k = RZOFF[t], found = 0;
                for (; k < RZOFF[t + 1]; k++) if (!PEN[RZPORT[k]]) { found = 1; break; }
                join(T, found ? WRITERS[RZATOM[k]] : NESALL[t], work, &nw);
            }
        }
        if (ok) { bestn = cnt; memcpy(best, T, sizeof T); }
    }
    if (bestn == nen) return n;
    int k = 0;
    for (int i = 0; i < n; i++) if (has(best, (int)isrc[i])) { isrc[k] = isrc[i]; imask[k] = imask[i]; k++; }
    PROPER = 1;
    return k;
}

/* no successor of the last expansion is stored yet: the cycle proviso's test (see c_search) */
static int all_new(int n) {
    for (int i = 0; i < n; i++) {
        const uint64_t *w = PK + (size_t)i * NW;
        uint64_t h = hash(w) & (TSIZE - 1);
        while (TABLE[h]) {
            if (same(STORE + (int64_t)(TABLE[h] - 1) * NW, w)) return 0;
            h = (h + 1) & (TSIZE - 1);
        }
    }
    return 1;
}

/* every successor of s (engine slots, then request counts): interactions, then the odometer over outcomes */
static int expand(const V *s, int reduce) {
    uint32_t isrc[MAXI], imask[MAXI];
    CUR = s;
    int ni = enabled(s, isrc, imask);
    PROPER = 0;
    if (reduce && POR_ON) ni = ample(ni, isrc, imask);
    int cnt = 0;
    for (int i = 0; i < ni; i++) {
        SL = 0;
        do {
            NC = 0;
            memset(TAKEN, 0, sizeof TAKEN);
            if (cnt >= MAXSUCC) fail(E_FULL, 0);
            ensure_succ(cnt + 1);
            V *L = SUCC + (size_t)cnt * W;
            memcpy(L, s, W * sizeof *L);
            FIRE[isrc[i]](L, imask[i]);
            for (int k = 0; k < NSERV; k++) L[E + k] = s[E + k] + TAKEN[k];
            SVIA[cnt] = imask[i] * NSRC + isrc[i];
            SBAD[cnt] = (uint8_t)observe(s, L, SVIA[cnt]);
            cnt++;
        } while (odometer_next());
    }
    return cnt;
}

static int initials(void) {
    int cnt = 0;
    SL = 0;
    do {
        NC = 0;
        memset(TAKEN, 0, sizeof TAKEN);
        ensure_succ(cnt + 1);
        V *L = SUCC + (size_t)cnt * W;
        memset(L, 0, W * sizeof *L);
        initial(L);
        for (int k = 0; k < NSERV; k++) L[E + k] = TAKEN[k];
        SVIA[cnt] = UINT32_MAX;
        SBAD[cnt] = (uint8_t)observe_initial(L);
        cnt++;
    } while (odometer_next());
    return cnt;
}

/* successors of s packed into PK (or initial states when s is NULL); -1 on a model error (ECODE, EARG) */
static int step_packed(const V *s) {
    if (setjmp(JB)) return -1;
    int n = s ? expand(s, 0) : initials();
    for (int i = 0; i < n; i++) pack(SUCC + (size_t)i * W, PK + (size_t)i * NW);
    return n;
}

/* the successors the search follows: an ample set's when it is proper, else all of them.  With observers,
   only when every ample successor is also new (so a reduced state only leads to states numbered after it
   and every cycle of the reduced graph has a fully expanded state: the cycle proviso safety needs);
   deadlocks need no proviso (stubborn sets preserve every reachable deadlock) */
static int step_search(const V *s) {
    if (!POR) return step_packed(s);
    if (setjmp(JB)) return -1;
    int n = expand(s, 1);
    for (int i = 0; i < n; i++) pack(SUCC + (size_t)i * W, PK + (size_t)i * NW);
    if (!PROPER) return n;
    if (!NMON || all_new(n)) { NREDUCED++; return n; }
    return step_packed(s);
}

static int label_of(uint32_t via) {
    uint32_t src = via % NSRC, mask = via / NSRC;
    if (LABELS[src].fixed || mask == LABELS[src].full) return LABELS[src].label;
    return NLABELS + (int)via;
}

/* ---- entry points called from Python ---- */

int c_width(int slot) { return WIDTHS[slot]; }
int c_words(void) { return NW; }
int c_state_width(void) { return W; }
int64_t c_nstates(void) { return NSTATES; }
int64_t c_parent(int64_t id) { return PARENT[id] == UINT32_MAX ? -1 : (int64_t)PARENT[id]; }
int64_t c_via(int64_t id) { return VIA[id] == UINT32_MAX ? -1 : (int64_t)VIA[id]; }
int64_t c_deadlock(int64_t i) { return DEAD[i]; }
void c_state(int64_t id, V *out) { unpack(STORE + id * NW, out); }
void c_free(void) { c_release(); }
void c_set_por(int on) { POR = on && POR_ON; }
int c_por_available(void) { return POR_ON; }
int64_t c_reduced(void) { return NREDUCED; }

/* successors of one explorer state, packed then unpacked (dead variables reset): the agreement tests' view */
int c_successors(const V *s, V *out, uint32_t *via, int max, int64_t budget, int *ecode, int64_t *earg) {
    BUDGET = budget;
    ensure_succ(1);
    int n = step_packed(s);
    if (n < 0) { *ecode = ECODE; *earg = EARG; return -1; }
    if (n > max) { *ecode = E_FULL; return -1; }
    for (int i = 0; i < n; i++) {
        unpack(PK + (size_t)i * NW, out + (size_t)i * W);
        if (via) via[i] = SVIA[i];
    }
    return n;
}

static void push_dead(int64_t id) {
    if (NDEAD == DCAP) { DCAP = DCAP ? DCAP * 2 : 64; DEAD = realloc(DEAD, DCAP * 8); }
    DEAD[NDEAD++] = id;
}

/* the (label, target) pairs of state `sid`'s successors, numbering new targets; transitions counted */
static int record(int64_t sid, int n, int64_t max_states, int64_t *targets, Result *r) {
    int distinct = 0;
    for (int i = 0; i < n; i++) {
        int added;
        int64_t t = add(PK + (size_t)i * NW, (uint32_t)sid, SVIA[i], max_states, &added);
        if (t == -1) { r->status = S_MAX_STATES; return -1; }
        if (t == -2) { r->status = S_MAX_MEMORY; return -1; }
        if (SBAD[i] && VIOL < 0) VIOL = t;
        int lab = label_of(SVIA[i]), dup = 0;
        for (int j = 0; j < distinct; j++)
            if (targets[2 * j] == lab && targets[2 * j + 1] == t) { dup = 1; break; }
        if (!dup) { targets[2 * distinct] = lab; targets[2 * distinct + 1] = t; distinct++; }
    }
    r->transitions += distinct;
    return distinct;
}

/* the step stopped at state sid (-1: the initial states): a model error, or a field to widen */
static void stopped_by_error(int64_t sid, Result *r) {
    r->status = ECODE == E_WIDEN ? S_WIDEN : S_ERROR;
    r->ecode = ECODE;
    r->earg = EARG;
    r->error_state = sid;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

int c_search(int dfs, int64_t max_states, int64_t max_depth, int64_t max_bytes, int stop_at_deadlock,
             int64_t budget, double period, progress_fn cb, Result *r) {
    c_release();
    BUDGET = budget;
    memset(r, 0, sizeof *r);
    r->error_state = -1;
    rehash(1 << 12);
    V *S = malloc(W * sizeof *S);
    int64_t *targets = malloc(2 * MAXSUCC * sizeof *targets);
    int n = step_packed(NULL);
    if (n < 0) {
        stopped_by_error(-1, r);
        free(S); free(targets); return r->status;
    }
    int64_t ninit = 0;
    int64_t init_ids[64];
    for (int i = 0; i < n; i++) {
        int added;
        int64_t id = add(PK + (size_t)i * NW, UINT32_MAX, UINT32_MAX, max_states, &added);
        if (id < 0) { r->status = id == -1 ? S_MAX_STATES : S_MAX_MEMORY; break; }
        if (added && ninit < 64) init_ids[ninit++] = id;
        if (SBAD[i] && VIOL < 0) { VIOL = id; r->status = S_VIOLATED; r->error_state = id; }
    }
    double next = now() + period;
    int64_t ticks = 0;
    if (r->status) goto done;
    if (!dfs) {
        int64_t sid = 0, level_end = NSTATES, depth = 0;
        while (sid < NSTATES) {
            if (sid == level_end) { depth++; level_end = NSTATES; }
            r->depth = depth;
            if (max_depth >= 0 && depth >= max_depth) { r->status = S_MAX_DEPTH; break; }
            unpack(STORE + sid * NW, S);
            int m = step_search(S);
            if (m < 0) { stopped_by_error(sid, r); break; }
            if (record(sid, m, max_states, targets, r) < 0) break;
            if (VIOL >= 0) { r->status = S_VIOLATED; r->error_state = VIOL; break; }
            if (m == 0) { push_dead(sid); if (stop_at_deadlock) { r->status = S_DEADLOCK; break; } }
            sid++;
            if (max_bytes >= 0 && memory() > max_bytes) { r->status = S_MAX_MEMORY; break; }
            if ((++ticks & 255) == 0 && now() >= next) {
                next = now() + period;
                if (cb && cb(NSTATES, r->transitions, depth, NSTATES - sid, memory())) { r->status = S_INTERRUPTED; break; }
            }
        }
    } else {
        int64_t scap = 1024, ns = 0, mcap = 0;
        int64_t *stack = malloc(scap * 2 * sizeof *stack);
        uint8_t *expanded = 0;
        for (int64_t i = ninit - 1; i >= 0; i--) { stack[2 * ns] = init_ids[i]; stack[2 * ns + 1] = 0; ns++; }
        while (ns) {
            ns--;
            int64_t sid = stack[2 * ns], depth = stack[2 * ns + 1];
            if (NSTATES > mcap) {
                int64_t cap = mcap ? mcap : 1024;
                while (cap < NSTATES) cap *= 2;
                expanded = realloc(expanded, cap);
                memset(expanded + mcap, 0, cap - mcap);
                mcap = cap;
            }
            if (expanded[sid]) continue;
            expanded[sid] = 1;
            if (depth > r->depth) r->depth = depth;
            if (max_depth >= 0 && depth >= max_depth) { r->status = S_MAX_DEPTH; continue; }
            unpack(STORE + sid * NW, S);
            int m = step_search(S);
            if (m < 0) { stopped_by_error(sid, r); break; }
            int d = record(sid, m, max_states, targets, r);
            if (d < 0) break;
            if (VIOL >= 0) { r->status = S_VIOLATED; r->error_state = VIOL; break; }
            if (m == 0) { push_dead(sid); if (stop_at_deadlock) { r->status = S_DEADLOCK; break; } }
            if (NSTATES > mcap) {
                int64_t cap = mcap;
                while (cap < NSTATES) cap *= 2;
                expanded = realloc(expanded, cap);
                memset(expanded + mcap, 0, cap - mcap);
                mcap = cap;
            }
            for (int k = d - 1; k >= 0; k--) {
                int64_t t = targets[2 * k + 1];
                if (expanded[t]) continue;
                if (ns == scap) { scap *= 2; stack = realloc(stack, scap * 2 * sizeof *stack); }
                stack[2 * ns] = t; stack[2 * ns + 1] = depth + 1; ns++;
            }
            EXTRA = scap * 16 + mcap;
            if (max_bytes >= 0 && memory() > max_bytes) { r->status = S_MAX_MEMORY; break; }
            if ((++ticks & 255) == 0 && now() >= next) {
                next = now() + period;
                if (cb && cb(NSTATES, r->transitions, r->depth, ns, memory())) { r->status = S_INTERRUPTED; break; }
            }
        }
        free(stack);
        free(expanded);
    }
done:
    r->states = NSTATES;
    r->deadlocks = NDEAD;
    r->memory = memory();
    free(S);
    free(targets);
    return r->status;
}
