/* The search over packed states, included after a model's generated step (runtime.native.cstep).

   States are bit-packed into NW 64-bit words by the generated pack/unpack (runtime.explore.codec's fields:
   markings, bools, declared domains, other ints zig-zag coded in a field the caller widens), numbered in
   order of discovery, with a parent and the interaction that first reached them.  Breadth-first numbering
   makes the parent links shortest paths.

   The visited set is one of three stores:
   - exact: an open-addressing table of state numbers over every packed state;
   - compact (hash compaction, SPIN's -DHC): a table of 64-bit fingerprints; only the current and next
     breadth-first levels keep their packed states (a window), so two states with the same fingerprint are
     taken as one (lossy, the probability is reported);
   - bitstate (SPIN's -DBITSTATE): BITK bits per state in a fixed bit array, lossier still.
   Lossy stores keep each state's parent, interaction and outcome index: a trace is rebuilt by replaying
   the step from an initial state.

   Built with PARALLEL, the breadth-first search runs on NWORK threads level by level: states of a level are
   claimed by an atomic counter, the table is filled lock-free (a slot is claimed, the state written, then
   the slot published), and the threads meet at a barrier at the end of a level, to grow the arrays, or to
   stop.  Levels stay levels, so traces stay shortest; numbers within a level depend on the interleaving. */

typedef int (*progress_fn)(int64_t states, int64_t transitions, int64_t depth, int64_t frontier, int64_t memory);

typedef struct {
    int64_t states, transitions, depth, error_state, deadlocks, memory;
    int32_t status, ecode;
    int64_t earg;
} Result;

enum { S_COMPLETE, S_MAX_STATES, S_MAX_DEPTH, S_ERROR, S_DEADLOCK, S_INTERRUPTED, S_MAX_MEMORY, S_WIDEN, S_VIOLATED };
enum { ST_EXACT, ST_COMPACT, ST_BITSTATE };

#define BUSY UINT32_MAX     /* a table slot claimed by a thread that is writing its state */
#define SEEN (-3)           /* add(): a lossy store already holds the state, which has no number here */
#define BITK 3              /* bits per state in the bitstate store (SPIN's -k3) */

static TL V *SUCC;
static TL VIA_T *SVIA;              /* successor i: the number of its interaction */
static TL uint32_t *SSRC;           /* successor i: its interaction's source */
static TL uint8_t *SBAD; /* successor i violates an observer */
static TL uint64_t *PK;
static TL int SCAP;
static TL int PROPER;       /* the last expansion was of a proper ample set */

#ifdef PARALLEL
static pthread_mutex_t LOCKM = PTHREAD_MUTEX_INITIALIZER;
static pthread_barrier_t BAR;
#define LOCK() pthread_mutex_lock(&LOCKM)
#define UNLOCK() pthread_mutex_unlock(&LOCKM)
#define RELAX() __builtin_ia32_pause()
#else
#define LOCK() ((void)0)
#define UNLOCK() ((void)0)
#define RELAX() ((void)0)
#endif

static void free_scratch(void) {
    free(SUCC); free(SVIA); free(SSRC); free(PK); free(SBAD);
    SUCC = 0; SVIA = 0; SSRC = 0; PK = 0; SBAD = 0; SCAP = 0;
}

static void ensure_succ(int n) {
    if (n <= SCAP) return;
    int cap = SCAP ? SCAP : 64;
    while (cap < n) cap *= 2;
    SUCC = realloc(SUCC, (size_t)cap * W * sizeof *SUCC);
    SVIA = realloc(SVIA, (size_t)cap * sizeof *SVIA);
    SSRC = realloc(SSRC, (size_t)cap * sizeof *SSRC);
    PK = realloc(PK, (size_t)cap * NW * sizeof *PK);
    SBAD = realloc(SBAD, (size_t)cap);
    SCAP = cap;
}

#define MAXSUCC 65536

/* ---- what the search adds: its store and bounds, hashing, partial-order reduction (not in a STEP_ONLY build) ---- */

#ifndef STEP_ONLY
static int KIND;                    /* the store: ST_EXACT, ST_COMPACT or ST_BITSTATE */
static int NWORK = 1;               /* threads of the breadth-first search */
static uint64_t *STORE;             /* packed states numbered WBASE.. (exact: all of them, WBASE 0) */
static int64_t WBASE, WCAP;         /* first number in STORE, room in states */
static uint32_t *PARENT;
static VIA_T *VIA;                  /* the interaction that first reached each state (numbering.py) */
static uint16_t *OUTK;              /* lossy: rank among the parent's successors by the same interaction */
static int64_t NSTATES, CAP;        /* numbered states, room of PARENT and VIA */
static int64_t RES, LIMIT;          /* numbers promised to pending steps (NSTATES <= RES <= LIMIT); the room */
static uint32_t *TABLE;             /* exact: numbers + 1 (0 free) */
static uint64_t *FTAB;              /* compact: fingerprints (0 free); bitstate: the bits */
static uint64_t TSIZE;              /* slots of TABLE or FTAB; bits of the bitstate array */
static int64_t *DEAD;
static int64_t NDEAD, DCAP;
static int64_t VIOL = -1;
static int64_t EXTRA; /* bytes of the depth-first stack and marks */
static int POR;             /* reduce: expand an ample set where one is proper */
static TL int64_t NREDUCED; /* states expanded with a proper ample set, by this thread */
static int64_t REDUCED_ALL, TRANS_ALL;
static int64_t LEVEL_END;  /* breadth-first: the first number past the current level */
static TL uint64_t AMPLE[SW]; /* the sources of the last proper ample set */

static inline int same(const uint64_t *a, const uint64_t *b) {
    for (int i = 0; i < NW; i++) if (a[i] != b[i]) return 0;
    return 1;
}

static inline uint64_t mix(uint64_t h) {
    /* murmur3's finaliser: every input bit reaches the low bits the table uses */
    h ^= h >> 33;
    h *= UINT64_C(0xc4ceb9fe1a85ec53);
    h ^= h >> 33;
    return h;
}

static uint64_t hash(const uint64_t *w) {
    uint64_t h = UINT64_C(0x9E3779B97F4A7C15);
    for (int i = 0; i < NW; i++) {
        h ^= w[i];
        h *= UINT64_C(0xff51afd7ed558ccd);
        h ^= h >> 32;
    }
    return mix(h);
}

/* a second hash, independent of the first: the fingerprint of hash compaction, the bitstate stride */
static uint64_t hash2(const uint64_t *w) {
    uint64_t h = UINT64_C(0x2545F4914F6CDD1D);
    for (int i = 0; i < NW; i++) {
        h = (h ^ w[i]) * UINT64_C(0x9FB21C651E98DF25);
        h ^= h >> 29;
    }
    h ^= h >> 32;
    h *= UINT64_C(0xD6E8FEB86659FD93);
    h ^= h >> 32;
    return h;
}

static inline uint64_t *at(int64_t id) { return STORE + (id - WBASE) * NW; }

static int64_t memory(void) {
    int64_t table = KIND == ST_EXACT ? (int64_t)TSIZE * 4 : KIND == ST_COMPACT ? (int64_t)TSIZE * 8 : (int64_t)(TSIZE / 8);
    return CAP * (4 + (int64_t)sizeof(VIA_T) + (OUTK ? 2 : 0)) + WCAP * NW * 8 + table + DCAP * 8 + EXTRA;
}

static void c_release(void) {
    free(STORE); free(PARENT); free(VIA); free(OUTK); free(TABLE); free(FTAB); free(DEAD);
    free_scratch();
    STORE = 0; PARENT = TABLE = 0; VIA = 0; OUTK = 0; FTAB = 0; DEAD = 0; VIOL = -1;
    NSTATES = CAP = NDEAD = DCAP = NREDUCED = REDUCED_ALL = TRANS_ALL = WBASE = WCAP = RES = LIMIT = 0;
    TSIZE = 0; EXTRA = 0;
}

/* the numbers the arrays and the table have room for */
static void set_limit(void) {
    int64_t l = CAP < WBASE + WCAP ? CAP : WBASE + WCAP;
    if (KIND == ST_EXACT && (int64_t)(TSIZE / 2) < l) l = (int64_t)(TSIZE / 2);
    if (KIND == ST_COMPACT && (int64_t)(TSIZE * 7 / 10) < l) l = (int64_t)(TSIZE * 7 / 10);
    LIMIT = l;
}

static int rehash(uint64_t size) {
    if (KIND == ST_EXACT) {
        uint32_t *t = calloc(size, sizeof *t);
        if (!t) return 0;
        for (int64_t id = 0; id < NSTATES; id++) {
            uint64_t h = hash(at(id)) & (size - 1);
            while (t[h]) h = (h + 1) & (size - 1);
            t[h] = (uint32_t)(id + 1);
        }
        free(TABLE);
        TABLE = t;
    } else {
        uint64_t *t = calloc(size, sizeof *t);
        if (!t) return 0;
        for (uint64_t i = 0; i < TSIZE; i++) {
            uint64_t f = FTAB[i];
            if (!f) continue;
            uint64_t h = f & (size - 1);
            while (t[h]) h = (h + 1) & (size - 1);
            t[h] = f;
        }
        free(FTAB);
        FTAB = t;
    }
    TSIZE = size;
    return 1;
}

/* room for `need` numbers (run by one thread while the others wait); 0 when memory is out */
static int grow(int64_t need) {
    if (need > CAP) {
        int64_t cap = CAP ? CAP : 1024;
        while (cap < need) cap *= 2;
        uint32_t *p = realloc(PARENT, cap * 4);
        if (p) PARENT = p;
        VIA_T *v = realloc(VIA, cap * sizeof *VIA);
        if (v) VIA = v;
        uint16_t *k = KIND == ST_EXACT ? OUTK : realloc(OUTK, cap * 2);
        if (k) OUTK = k;
        if (!p || !v || (KIND != ST_EXACT && !k)) return 0;
        CAP = cap;
    }
    if (need - WBASE > WCAP) {
        int64_t cap = WCAP ? WCAP : 1024;
        while (cap < need - WBASE) cap *= 2;
        uint64_t *s = realloc(STORE, cap * NW * 8);
        if (!s) return 0;
        STORE = s;
        WCAP = cap;
    }
    if (KIND == ST_EXACT && (uint64_t)need * 2 > TSIZE) {
        uint64_t size = TSIZE;
        while ((uint64_t)need * 2 > size) size *= 2;
        if (!rehash(size)) return 0;
    }
    if (KIND == ST_COMPACT && (uint64_t)need * 10 > TSIZE * 7) {
        uint64_t size = TSIZE;
        while ((uint64_t)need * 10 > size * 7) size *= 2;
        if (!rehash(size)) return 0;
    }
    set_limit();
    return 1;
}

/* promise room for m more numbers; 0 when the arrays must grow first */
static int room(int m) {
    int64_t r = AADD(&RES, (int64_t)m) + m;
    if (r <= LIMIT) return 1;
    AADD(&RES, -(int64_t)m);
    return 0;
}

/* a new number for w: -1 at the state limit, -2 past 32-bit numbers */
static int64_t number(const uint64_t *w, uint32_t parent, VIA_T via, int k, int64_t max_states) {
    int64_t n = ALOAD(&NSTATES);
    do {
        if (max_states >= 0 && n >= max_states) return -1;
        if (n >= (int64_t)UINT32_MAX - 2) return -2;
    } while (!ACAS(&NSTATES, &n, n + 1));
    memcpy(at(n), w, NW * 8);
    PARENT[n] = parent;
    VIA[n] = via;
    if (OUTK) OUTK[n] = (uint16_t)k;
    return n;
}

/* the number of a packed state, numbering it when new (*added); SEEN when a lossy store holds it already;
   -1 at the state limit, -2 when memory is out.  *key names the state in the step's transition count */
static int64_t add(const uint64_t *w, uint32_t parent, VIA_T via, int k, int64_t max_states, int *added,
                   uint64_t *key) {
    *added = 0;
    if (KIND == ST_EXACT) {
        uint64_t mask = TSIZE - 1, h = hash(w) & mask;
        for (;;) {
            uint32_t v = ALOAD(&TABLE[h]);
            if (v == 0) {
                uint32_t e = 0;
                if (!ACAS(&TABLE[h], &e, BUSY)) continue;
                int64_t n = number(w, parent, via, k, max_states);
                if (n < 0) { ASTORE(&TABLE[h], 0); return n; }
                ASTORE(&TABLE[h], (uint32_t)(n + 1));
                *added = 1;
                *key = (uint64_t)n;
                return n;
            }
            if (v == BUSY) { RELAX(); continue; }
            if (same(at(v - 1), w)) { *key = v - 1; return v - 1; }
            h = (h + 1) & mask;
        }
    }
    if (KIND == ST_COMPACT) {
        uint64_t f = hash2(w), mask = TSIZE - 1;
        f = f ? f : 1;
        *key = f;
        for (uint64_t h = f & mask;; h = (h + 1) & mask) {
            uint64_t v = ALOAD(&FTAB[h]);
            if (v == f) return SEEN;
            if (v == 0) {
                uint64_t e = 0;
                if (!ACAS(&FTAB[h], &e, f)) { h = (h - 1) & mask; continue; }
                int64_t n = number(w, parent, via, k, max_states);
                if (n >= 0) *added = 1;
                return n;
            }
        }
    }
    uint64_t h1 = hash(w), h2 = hash2(w) | 1, mask = TSIZE - 1;
    int fresh = 0;
    for (int j = 0; j < BITK; j++) {
        uint64_t b = (h1 + (uint64_t)j * h2) & mask, bit = UINT64_C(1) << (b & 63);
        if (!(AOR(&FTAB[b >> 6], bit) & bit)) fresh = 1;
    }
    *key = h1;
    if (!fresh) return SEEN;
    int64_t n = number(w, parent, via, k, max_states);
    if (n >= 0) *added = 1;
    return n;
}

/* whether the store holds w (a slot being written counts as held: the cycle proviso's safe side) */
static int held(const uint64_t *w) {
    if (KIND == ST_EXACT) {
        uint64_t mask = TSIZE - 1, h = hash(w) & mask;
        for (uint32_t v; (v = ALOAD(&TABLE[h])); h = (h + 1) & mask)
            if (v == BUSY || same(at(v - 1), w)) return 1;
        return 0;
    }
    if (KIND == ST_COMPACT) {
        uint64_t f = hash2(w), mask = TSIZE - 1;
        f = f ? f : 1;
        for (uint64_t h = f & mask, v; (v = ALOAD(&FTAB[h])); h = (h + 1) & mask)
            if (v == f) return 1;
        return 0;
    }
    uint64_t h1 = hash(w), h2 = hash2(w) | 1, mask = TSIZE - 1;
    for (int j = 0; j < BITK; j++) {
        uint64_t b = (h1 + (uint64_t)j * h2) & mask;
        if (!(ALOAD(&FTAB[b >> 6]) >> (b & 63) & 1)) return 0;
    }
    return 1;
}

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

/* a necessary enabling set of the disabled source t: the writers of the atom of one of its ports that is not
   enabled (the one adding the fewest sources to T), or the writers of everything it reads */
static const uint64_t *enabling(int t, const uint64_t *T) {
    const uint64_t *best = NESALL[t];
    int fewest = NSRC + 1;
    for (int k = RZOFF[t]; k < RZOFF[t + 1]; k++) {
        if (PEN[RZPORT[k]]) continue;
        const uint64_t *w = WRITERS[RZATOM[k]];
        int c = 0;
        for (int j = 0; j < SW; j++) c += __builtin_popcountll(w[j] & ~T[j]);
        if (c < fewest) { fewest = c; best = w; if (!c) break; }
    }
    return best;
}

/* the enabled interactions of the smallest invisible strong stubborn set seeded by one enabled source;
   n unchanged when none is smaller than the whole (PROPER says which, AMPLE holds its sources).  Sources in
   `bad` (some successor of theirs breaks the cycle proviso) may not be in it, as visible ones may not */
static int ample(int n, uint32_t *isrc, uint32_t *imask, const uint64_t *bad) {
    static TL uint64_t en[SW], T[SW];
    uint64_t *best = AMPLE;
    static TL int work[NSRC + 1];
    PROPER = 0;
    memset(en, 0, sizeof en);
    int nen = 0;
    for (int i = 0; i < n; i++) if (!has(en, (int)isrc[i])) { en[isrc[i] >> 6] |= UINT64_C(1) << (isrc[i] & 63); nen++; }
    if (nen < 2) return n;
    int bestn = nen;
    for (int i = 0; i < n && bestn > 1; i++) {
        int e = (int)isrc[i];
        if (VISIBLE[e] || (i && isrc[i - 1] == isrc[i]) || (bad && has(bad, e))) continue;
        memset(T, 0, sizeof T);
        T[e >> 6] |= UINT64_C(1) << (e & 63);
        int nw = 0, cnt = 0, ok = 1;
        work[nw++] = e;
        while (nw && ok) {
            int t = work[--nw];
            if (has(en, t)) {
                if (VISIBLE[t] || (bad && has(bad, t)) || ++cnt >= bestn) { ok = 0; break; }
                join(T, DEP[t], work, &nw);
            } else {
                join(T, enabling(t, T), work, &nw);
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

#endif

/* every successor of s (engine slots, then request counts): interactions, then the odometer over outcomes */
static int expand(const V *s, int reduce) {
    uint32_t isrc[MAXI], imask[MAXI];
    CUR = s;
    int ni = enabled(s, isrc, imask);
    PROPER = 0;
#ifndef STEP_ONLY
    if (reduce && POR_ON) ni = ample(ni, isrc, imask, 0);
#endif
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
            SVIA[cnt] = OFF[isrc[i]] + imask[i];  /* imask is 0 for a source of one interaction */
            SSRC[cnt] = isrc[i];
            SBAD[cnt] = (uint8_t)observe(s, L, isrc[i], imask[i]);
            cnt++;
        } while (odometer_next());
    }
    return cnt;
}

#ifndef STEP_ONLY
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
        SVIA[cnt] = VIA_NONE;
        SSRC[cnt] = 0;
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

/* a successor breaks the breadth-first cycle proviso: stored, and not in the next level (lossy stores: stored) */
static int backward(const uint64_t *w) {
    if (KIND != ST_EXACT) return held(w);
    int64_t next = ALOAD(&LEVEL_END);
    uint64_t mask = TSIZE - 1, h = hash(w) & mask;
    for (uint32_t v; (v = ALOAD(&TABLE[h])); h = (h + 1) & mask) {
        if (v == BUSY) return 1;
        if (same(at(v - 1), w)) return (int64_t)v - 1 < next;
    }
    return 0;
}

/* every successor of s, then only those of the smallest ample set none of whose successors `closes` says
   breaks the cycle proviso (every successor when there is none) */
static int step_proviso(const V *s, int (*closes)(const uint64_t *w)) {
    static TL uint64_t bad[SW];
    static TL uint32_t isrc[MAXSUCC], imask[MAXSUCC];
    int n = step_packed(s);
    if (n <= 1) return n;
    memset(bad, 0, sizeof bad);
    for (int i = 0; i < n; i++) {
        int src = (int)SSRC[i];
        isrc[i] = (uint32_t)src;
        imask[i] = 0;
        if (!has(bad, src) && closes(PK + (size_t)i * NW)) bad[src >> 6] |= UINT64_C(1) << (src & 63);
    }
    ample(n, isrc, imask, bad);
    if (!PROPER) return n;
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (!has(AMPLE, (int)SSRC[i])) continue;
        if (k != i) {
            memcpy(SUCC + (size_t)k * W, SUCC + (size_t)i * W, W * sizeof *SUCC);
            memcpy(PK + (size_t)k * NW, PK + (size_t)i * NW, NW * sizeof *PK);
            SVIA[k] = SVIA[i];
            SSRC[k] = SSRC[i];
            SBAD[k] = SBAD[i];
        }
        k++;
    }
    NREDUCED++;
    return k;
}

/* the successors the search follows: an ample set's when it is proper, else all of them.  With observers,
   only when every ample successor is new or already in the next level (lossy stores: new), so a reduced
   state only leads one level down, even with several threads, and every cycle of the reduced graph has a
   fully expanded state: the cycle proviso safety needs.  An ample set that fails it gives way to the next
   smallest one of another seed before the state is fully expanded.
   Deadlocks need no proviso (stubborn sets preserve every reachable deadlock) */
static int step_search(const V *s) {
    if (!POR) return step_packed(s);
    if (!NMON) {
        if (setjmp(JB)) return -1;
        int n = expand(s, 1);
        for (int i = 0; i < n; i++) pack(SUCC + (size_t)i * W, PK + (size_t)i * NW);
        NREDUCED += PROPER;
        return n;
    }
    return step_proviso(s, backward);
}

/* the label of interaction `via` of source `src` when it does not depend on the mask, else one of its own */
static int64_t label_of(uint32_t src, VIA_T via) {
    if (LABELS[src].fixed || via - OFF[src] == LABELS[src].full) return LABELS[src].label;
    return NLABELS + (int64_t)via;
}

#endif

/* ---- entry points called from Python: a step's (every build), then the search's (not in a STEP_ONLY build,
   which the zone search and the traces call one state at a time, and which compiles in about half the time) ---- */

int c_width(int slot) { return WIDTHS[slot]; }
int c_words(void) { return NW; }
int c_state_width(void) { return W; }
int c_via_bits(void) { return VIA_BITS; }
int c_por_available(void) { return POR_ON; }

/* successors of one explorer state as packing then unpacking them leaves them (dead variables reset, every field
   checked; canon writes that without the packed words): the agreement tests' view, and the zone search's step */
int c_successors(const V *s, V *out, int64_t *via, int max, int64_t budget, int *ecode, int64_t *earg) {
    BUDGET = budget;
    ensure_succ(1);
    if (setjmp(JB)) { *ecode = ECODE; *earg = EARG; return -1; }
    int n = expand(s, 0);
    if (n > max) { *ecode = E_FULL; return -1; }
    for (int i = 0; i < n; i++) {
        canon(SUCC + (size_t)i * W, out + (size_t)i * W);
        if (via) via[i] = (int64_t)SVIA[i];
    }
    return n;
}

#ifdef STEP_ONLY
void c_free(void) { free_scratch(); }
#else
int64_t c_nstates(void) { return NSTATES; }
int64_t c_parent(int64_t id) { return PARENT[id] == UINT32_MAX ? -1 : (int64_t)PARENT[id]; }
int64_t c_via(int64_t id) { return VIA[id] == VIA_NONE ? -1 : (int64_t)VIA[id]; }
int64_t c_deadlock(int64_t i) { return DEAD[i]; }
void c_free(void) { c_release(); }
void c_set_por(int on) { POR = on && POR_ON; }
int64_t c_reduced(void) { return REDUCED_ALL; }
uint64_t c_table_size(void) { return TSIZE; }
int c_bits_per_state(void) { return BITK; }
#ifdef PARALLEL
int c_parallel(void) { return 1; }
#else
int c_parallel(void) { return 0; }
#endif

/* state `id`: from the store, or (a lossy store past the window) replayed from an initial state along the
   parent links, taking at each step the successor by the recorded interaction and outcome rank */
void c_state(int64_t id, V *out) {
    if (id >= WBASE) { unpack(at(id), out); return; }
    int64_t n = 0, cap = 64, *path = malloc(cap * sizeof *path);
    for (int64_t k = id; k >= 0; k = PARENT[k] == UINT32_MAX ? -1 : (int64_t)PARENT[k]) {
        if (n == cap) { cap *= 2; path = realloc(path, cap * sizeof *path); }
        path[n++] = k;
    }
    uint64_t cur[NW];
    V *S = malloc(W * sizeof *S);
    for (int64_t j = n - 1; j >= 0; j--) {
        int m = step_packed(j == n - 1 ? NULL : S), rank = 0;
        for (int i = 0; i < m; i++) {
            if (SVIA[i] != VIA[path[j]]) continue;
            if (rank++ == OUTK[path[j]]) { memcpy(cur, PK + (size_t)i * NW, sizeof cur); break; }
        }
        unpack(cur, S);
    }
    memcpy(out, S, W * sizeof *S);
    free(S);
    free(path);
}

static void push_dead(int64_t id) {
    LOCK();
    if (NDEAD == DCAP) { DCAP = DCAP ? DCAP * 2 : 64; DEAD = realloc(DEAD, DCAP * 8); }
    DEAD[NDEAD++] = id;
    UNLOCK();
}

/* ---- the search's shared state: its bounds, how it stopped ---- */

static int64_t MAX_STATES, MAX_DEPTH, MAX_BYTES;
static int STOP_AT_DEADLOCK;
static Result *RES_OUT;
static int STOP, DONE, SYNC, MID;   /* stop asked; threads leave; threads meet at the barrier; one mid-step */
static int64_t NEXT, DEPTH, GROWTO;
static double PERIOD_S;
static progress_fn CB;

/* end the search with `status` (the first one asked wins) */
static void stop_with(int status, int64_t state) {
    LOCK();
    if (!STOP) {
        RES_OUT->status = status;
        if (status == S_ERROR || status == S_WIDEN) {
            RES_OUT->ecode = ECODE;
            RES_OUT->earg = EARG;
        }
        if (state >= -1) RES_OUT->error_state = state;
        ASTORE(&STOP, 1);
    }
    ASTORE(&SYNC, 1);
    UNLOCK();
}

/* numbers the successors of state `sid`, within the room room() promised for them (the unused part is given
   back); counts its distinct (label, target) transitions; -1 if it stopped */
static int record(int64_t sid, int n, int64_t *targets) {
    int distinct = 0, rank = 0, fresh = 0;
    for (int i = 0; i < n; i++) {
        int added;
        uint64_t key = 0;
        rank = i && SVIA[i] == SVIA[i - 1] ? rank + 1 : 0;
        int64_t t = add(PK + (size_t)i * NW, sid < 0 ? UINT32_MAX : (uint32_t)sid, SVIA[i], rank, MAX_STATES, &added,
                        &key);
        if (t == SEEN && SBAD[i]) {  /* a lossy store took a violating state for a visited one: number it anyway */
            t = number(PK + (size_t)i * NW, sid < 0 ? UINT32_MAX : (uint32_t)sid, SVIA[i], rank, MAX_STATES);
            added = t >= 0;
        }
        if (t == -1) { stop_with(S_MAX_STATES, -2); return -1; }
        if (t == -2) { stop_with(S_MAX_MEMORY, -2); return -1; }
        fresh += added;
        if (SBAD[i]) { int64_t none = -1; ACAS(&VIOL, &none, t); }
        int64_t lab = sid < 0 ? -1 : label_of(SSRC[i], SVIA[i]);
        int dup = 0;
        for (int j = 0; j < distinct; j++)
            if (targets[2 * j] == lab && (uint64_t)targets[2 * j + 1] == key) { dup = 1; break; }
        if (!dup) { targets[2 * distinct] = lab; targets[2 * distinct + 1] = (int64_t)key; distinct++; }
    }
    AADD(&RES, (int64_t)fresh - n);
    return distinct;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void barrier(void) {
#ifdef PARALLEL
    if (NWORK > 1) pthread_barrier_wait(&BAR);
#endif
}

/* the threads meet: one grows the arrays, moves to the next level or ends the search; 1 when it ends */
static int sync_point(int tid, int mid) {
    if (mid) ASTORE(&MID, 1);
    barrier();
    if (tid == 0) {
        if (GROWTO > 0 && !STOP && !grow(GROWTO)) stop_with(S_MAX_MEMORY, -2);
        GROWTO = 0;
        RES = NSTATES;
        if (NEXT > LEVEL_END) NEXT = LEVEL_END;
        if (STOP) DONE = 1;
        else if (!MID && NEXT >= LEVEL_END) {
            if (LEVEL_END == NSTATES) DONE = 1;  /* complete */
            else if (MAX_DEPTH >= 0 && DEPTH + 1 >= MAX_DEPTH) { DEPTH++; stop_with(S_MAX_DEPTH, -2); DONE = 1; }
            else {
                DEPTH++;
                if (KIND != ST_EXACT) {  /* the window keeps the new level only */
                    memmove(STORE, at(LEVEL_END), (size_t)(NSTATES - LEVEL_END) * NW * 8);
                    WBASE = LEVEL_END;
                    set_limit();
                }
                LEVEL_END = NSTATES;
            }
        }
        MID = 0;
        SYNC = STOP;
    }
    barrier();
    return DONE;
}

/* one thread of the breadth-first search: claim a state of the level, expand it, number its successors */
static void *bfs_worker(void *arg) {
    int tid = (int)(intptr_t)arg;
    V *S = malloc(W * sizeof *S);
    int64_t *targets = malloc(2 * MAXSUCC * sizeof *targets), trans = 0, ticks = 0;
    double next = now() + PERIOD_S;
    for (;;) {
        if (ALOAD(&SYNC)) { if (sync_point(tid, 0)) break; continue; }
        int64_t sid = AADD(&NEXT, 1);
        if (sid >= LEVEL_END) { ASTORE(&SYNC, 1); continue; }
        unpack(at(sid), S);
        int m = step_search(S);
        if (m < 0) { stop_with(ECODE == E_WIDEN ? S_WIDEN : S_ERROR, sid); continue; }
        while (!room(m)) {
            if (NWORK == 1) {
                if (!grow(RES + m)) { stop_with(S_MAX_MEMORY, -2); break; }
                continue;
            }
            LOCK();
            if (RES + m > GROWTO) GROWTO = RES + m;
            UNLOCK();
            ASTORE(&SYNC, 1);
            if (sync_point(tid, 1)) goto out;
        }
        if (ALOAD(&STOP)) continue;
        int d = record(sid, m, targets);
        if (d < 0) continue;
        trans += d;
        if (ALOAD(&VIOL) >= 0) stop_with(S_VIOLATED, ALOAD(&VIOL));
        if (m == 0) { push_dead(sid); if (STOP_AT_DEADLOCK) stop_with(S_DEADLOCK, -2); }
        if (tid == 0 && MAX_BYTES >= 0 && memory() > MAX_BYTES) stop_with(S_MAX_MEMORY, -2);
        if ((++ticks & 255) == 0) {
            AADD(&TRANS_ALL, trans);
            trans = 0;
            if (tid == 0 && now() >= next) {
                next = now() + PERIOD_S;
                if (CB && CB(ALOAD(&NSTATES), ALOAD(&TRANS_ALL), DEPTH, ALOAD(&NSTATES) - ALOAD(&NEXT), memory()))
                    stop_with(S_INTERRUPTED, -2);
            }
        }
    }
out:
    AADD(&TRANS_ALL, trans);
    AADD(&REDUCED_ALL, NREDUCED);
    NREDUCED = 0;
    free(S);
    free(targets);
    if (tid) free_scratch();
    return 0;
}

/* one thread's depth-first step at sid, m successors (-1: a model error): numbered and recorded; the
   distinct transitions, or -1 when the search stops (error, limit, violation, deadlock asked for) */
static int settle(int64_t sid, int m, int64_t *targets) {
    if (m < 0) { stop_with(ECODE == E_WIDEN ? S_WIDEN : S_ERROR, sid); return -1; }
    if (!room(m)) {
        if (!grow(RES + m)) { stop_with(S_MAX_MEMORY, -2); return -1; }
        room(m);
    }
    int d = record(sid, m, targets);
    if (d < 0) return -1;
    TRANS_ALL += d;
    if (VIOL >= 0) { stop_with(S_VIOLATED, VIOL); return -1; }
    if (m == 0) { push_dead(sid); if (STOP_AT_DEADLOCK) { stop_with(S_DEADLOCK, -2); return -1; } }
    return d;
}

/* a byte per numbered state (zeroed as it grows): the depth-first searches' marks */
static uint8_t *marks_for_all(uint8_t *marks, int64_t *cap) {
    if (NSTATES <= *cap) return marks;
    int64_t c = *cap ? *cap : 1024;
    while (c < NSTATES) c *= 2;
    marks = realloc(marks, c);
    memset(marks + *cap, 0, c - *cap);
    *cap = c;
    return marks;
}

/* depth-first over the exact store, one thread: a stack of (state, depth), a mark per expanded state */
static void dfs(int64_t *init_ids, int64_t ninit, Result *r) {
    int64_t scap = 1024, ns = 0, mcap = 0, ticks = 0;
    int64_t *stack = malloc(scap * 2 * sizeof *stack), *targets = malloc(2 * MAXSUCC * sizeof *targets);
    uint8_t *expanded = 0;
    V *S = malloc(W * sizeof *S);
    double next = now() + PERIOD_S;
    for (int64_t i = ninit - 1; i >= 0; i--) { stack[2 * ns] = init_ids[i]; stack[2 * ns + 1] = 0; ns++; }
    while (ns && !STOP) {
        ns--;
        int64_t sid = stack[2 * ns], depth = stack[2 * ns + 1];
        expanded = marks_for_all(expanded, &mcap);
        if (expanded[sid]) continue;
        expanded[sid] = 1;
        if (depth > r->depth) r->depth = depth;
        if (MAX_DEPTH >= 0 && depth >= MAX_DEPTH) { r->status = S_MAX_DEPTH; continue; }
        unpack(at(sid), S);
        int d = settle(sid, step_search(S), targets);
        if (d < 0) break;
        expanded = marks_for_all(expanded, &mcap);
        for (int k = d - 1; k >= 0; k--) {
            int64_t t = targets[2 * k + 1];
            if (expanded[t]) continue;
            if (ns == scap) { scap *= 2; stack = realloc(stack, scap * 2 * sizeof *stack); }
            stack[2 * ns] = t; stack[2 * ns + 1] = depth + 1; ns++;
        }
        EXTRA = scap * 16 + mcap;
        if (MAX_BYTES >= 0 && memory() > MAX_BYTES) { stop_with(S_MAX_MEMORY, -2); break; }
        if ((++ticks & 255) == 0 && now() >= next) {
            next = now() + PERIOD_S;
            if (CB && CB(NSTATES, TRANS_ALL, r->depth, ns, memory())) { stop_with(S_INTERRUPTED, -2); break; }
        }
    }
    REDUCED_ALL += NREDUCED;
    NREDUCED = 0;
    free(stack);
    free(expanded);
    free(targets);
    free(S);
}

/* the number of a stored state, or -1 (exact store) */
static int64_t lookup(const uint64_t *w) {
    uint64_t mask = TSIZE - 1, h = hash(w) & mask;
    for (uint32_t v; (v = TABLE[h]); h = (h + 1) & mask)
        if (same(at(v - 1), w)) return v - 1;
    return -1;
}

/* the successors the depth-first search with the stack proviso follows: an ample set's, unless one of its
   successors is on the search stack (SPIN's cycle proviso): then the ample set of another seed, and every
   successor when none is left */
static TL const uint8_t *ONSTACK;

static int on_stack(const uint64_t *w) {
    int64_t id = lookup(w);
    return id >= 0 && (ONSTACK[id] & 2);
}

static int step_stack(const V *s, const uint8_t *onstack) {
    ONSTACK = onstack;
    return step_proviso(s, on_stack);
}

/* depth-first over a path stack, for the reduction with observers: a frame per state on the current path
   with the successors still to visit; a state is on the stack from its expansion until its frame is done */
static void dfs_stack(int64_t *init_ids, int64_t ninit, Result *r) {
    int64_t fcap = 1024, nf = 0, kcap = 4096, nk = 0, mcap = 0, ticks = 0;
    int64_t *fsid = malloc(fcap * 8), *fdepth = malloc(fcap * 8), *fnext = malloc(fcap * 8), *fend = malloc(fcap * 8);
    int64_t *kids = malloc(kcap * 8), *targets = malloc(2 * MAXSUCC * sizeof *targets);
    uint8_t *mark = 0; /* bit 0: expanded, bit 1: on the stack */
    V *S = malloc(W * sizeof *S);
    double next = now() + PERIOD_S;
    for (int64_t i = 0; i < ninit && !STOP; i++) {
        int64_t push = init_ids[i], depth = 0;
        for (;;) {
            if (push >= 0) {  /* expand `push` and open its frame */
                mark = marks_for_all(mark, &mcap);
                if (mark[push] & 1) { push = -1; continue; }
                mark[push] |= 3;
                if (depth > r->depth) r->depth = depth;
                if (nf == fcap) {
                    fcap *= 2;
                    fsid = realloc(fsid, fcap * 8); fdepth = realloc(fdepth, fcap * 8);
                    fnext = realloc(fnext, fcap * 8); fend = realloc(fend, fcap * 8);
                }
                fsid[nf] = push; fdepth[nf] = depth; fnext[nf] = fend[nf] = nk; nf++;
                if (MAX_DEPTH >= 0 && depth >= MAX_DEPTH) r->status = S_MAX_DEPTH;
                else {
                    unpack(at(push), S);
                    int d = settle(push, step_stack(S, mark), targets);
                    if (d < 0) break;
                    mark = marks_for_all(mark, &mcap);
                    for (int k = 0; k < d; k++) {
                        if (mark[targets[2 * k + 1]] & 1) continue;
                        if (nk == kcap) { kcap *= 2; kids = realloc(kids, kcap * 8); }
                        kids[nk++] = targets[2 * k + 1];
                    }
                    fend[nf - 1] = nk;
                }
                EXTRA = fcap * 32 + kcap * 8 + mcap;
                if (MAX_BYTES >= 0 && memory() > MAX_BYTES) { stop_with(S_MAX_MEMORY, -2); break; }
                if ((++ticks & 255) == 0 && now() >= next) {
                    next = now() + PERIOD_S;
                    if (CB && CB(NSTATES, TRANS_ALL, r->depth, nf, memory())) { stop_with(S_INTERRUPTED, -2); break; }
                }
                push = -1;
            }
            if (!nf) break;
            int64_t f = nf - 1;
            if (fnext[f] < fend[f]) { push = kids[fnext[f]++]; depth = fdepth[f] + 1; continue; }
            mark[fsid[f]] &= 1;  /* leaves the stack */
            nk = f ? fend[f - 1] : 0;
            nf--;
        }
    }
    REDUCED_ALL += NREDUCED;
    NREDUCED = 0;
    free(fsid); free(fdepth); free(fnext); free(fend); free(kids); free(targets); free(mark); free(S);
}

/* the whole search.  store: ST_EXACT, ST_COMPACT or ST_BITSTATE (2^bits bits); workers > 1 needs PARALLEL
   and breadth-first order; lossy stores search breadth-first */
int c_search(int dfs_order, int64_t max_states, int64_t max_depth, int64_t max_bytes, int stop_at_deadlock,
             int64_t budget, double period, progress_fn cb, Result *r, int workers, int store, int bits) {
    c_release();
    BUDGET = budget;
    memset(r, 0, sizeof *r);
    r->error_state = -1;
    RES_OUT = r;
    MAX_STATES = max_states; MAX_DEPTH = max_depth; MAX_BYTES = max_bytes; STOP_AT_DEADLOCK = stop_at_deadlock;
    PERIOD_S = period; CB = cb;
    STOP = DONE = SYNC = MID = 0;
    NEXT = LEVEL_END = DEPTH = GROWTO = 0;
    KIND = store;
#ifdef PARALLEL
    NWORK = workers < 1 ? 1 : workers;
#else
    NWORK = 1;
#endif
    if (KIND != ST_EXACT || NWORK > 1) dfs_order = 0;
    if (KIND == ST_BITSTATE) {
        TSIZE = UINT64_C(1) << (bits < 9 ? 9 : bits > 40 ? 40 : bits);
        FTAB = calloc(TSIZE / 64, 8);
    } else if (KIND == ST_COMPACT) {
        TSIZE = 1 << 12;
        FTAB = calloc(TSIZE, 8);
    } else {
        TSIZE = 1 << 12;
        TABLE = calloc(TSIZE, 4);
    }
    if ((KIND == ST_EXACT && !TABLE) || (KIND != ST_EXACT && !FTAB)) { r->status = S_MAX_MEMORY; return r->status; }
    set_limit();
    int n = step_packed(NULL);
    if (n < 0) {
        stop_with(ECODE == E_WIDEN ? S_WIDEN : S_ERROR, -1);
        goto done;
    }
    if (!grow(n)) { stop_with(S_MAX_MEMORY, -2); goto done; }
    int64_t ninit = 0, init_ids[64];
    for (int i = 0; i < n && !STOP; i++) {
        int added;
        uint64_t key;
        int64_t id = add(PK + (size_t)i * NW, UINT32_MAX, VIA_NONE, i, max_states, &added, &key);
        if (id == SEEN && SBAD[i]) id = number(PK + (size_t)i * NW, UINT32_MAX, VIA_NONE, i, max_states);
        if (id == -1 || id == -2) { stop_with(id == -1 ? S_MAX_STATES : S_MAX_MEMORY, -2); break; }
        if (added && ninit < 64) init_ids[ninit++] = id;
        if (SBAD[i] && VIOL < 0) { VIOL = id; stop_with(S_VIOLATED, id); }
    }
    if (STOP) goto done;
    RES = NSTATES;
    if (dfs_order) {
        if (POR && NMON) dfs_stack(init_ids, ninit, r);
        else dfs(init_ids, ninit, r);
        goto done;
    }
    LEVEL_END = NSTATES;
    if (max_depth == 0) { stop_with(S_MAX_DEPTH, -2); goto done; }
#ifdef PARALLEL
    pthread_t threads[64];
    if (NWORK > 64) NWORK = 64;
    if (NWORK > 1) {
        pthread_barrier_init(&BAR, 0, NWORK);
        for (int t = 1; t < NWORK; t++) pthread_create(&threads[t - 1], 0, bfs_worker, (void *)(intptr_t)t);
    }
    bfs_worker((void *)(intptr_t)0);
    if (NWORK > 1) {
        for (int t = 1; t < NWORK; t++) pthread_join(threads[t - 1], 0);
        pthread_barrier_destroy(&BAR);
    }
#else
    bfs_worker((void *)(intptr_t)0);
#endif
    r->depth = DEPTH;
done:
    r->states = NSTATES;
    r->transitions = TRANS_ALL;
    r->deadlocks = NDEAD;
    r->memory = memory();
    return r->status;
}
#endif  /* STEP_ONLY */
