/* Codel outcomes as branching: every choice call answers from a script and records its domain; the
   odometer gives the next script (runtime.explore.choices.Oracle, the same order). Needs DOMV, DOMN. */
#define MAXCALLS 256
static TL int NC, SL;
static TL int CPOS[MAXCALLS], CDOM[MAXCALLS], SCR[MAXCALLS];

static inline V choice(int d) {
    if (NC >= MAXCALLS) fail(E_CHOICES, 0);
    int k = NC++;
    int pos = k < SL ? SCR[k] : 0;
    CPOS[k] = pos;
    CDOM[k] = d;
    return DOMV[d][pos];
}

static int odometer_next(void) {
    int k = NC - 1;
    while (k >= 0 && CPOS[k] + 1 >= DOMN[CDOM[k]]) k--;
    if (k < 0) return 0;
    for (int j = 0; j < k; j++) SCR[j] = CPOS[j];
    SCR[k] = CPOS[k] + 1;
    SL = k + 1;
    return 1;
}

#define MAXI (NSRC * 8 + 64)

/* defines.maximal_enabled: maximal interactions within em whose guard holds, starting from the largest */
static int maximal_enabled(uint32_t (*maxa)(uint32_t), uint32_t em, int np, V pv[][MAXF],
                           int (*blocked)(uint32_t, V[][MAXF]), int src, uint32_t *isrc, uint32_t *imask, int n) {
    uint32_t top = maxa(em);
    (void)np;
    if (!top) return n;
    if (!blocked(top, pv)) { isrc[n] = src; imask[n] = top; return n + 1; }
    int cap = 64, ns = 0, nf = 0, nk = 0;
    uint32_t *seen = malloc(cap * sizeof *seen), *found = malloc(cap * sizeof *found), *stack = malloc(cap * sizeof *stack);
    int fcap = cap, kcap = cap;
    seen[ns++] = top;
    stack[nk++] = top;
    while (nk) {
        uint32_t x = stack[--nk], rest = x;
        while (rest) {
            uint32_t low = rest & -rest;
            rest ^= low;
            uint32_t y = maxa(x & ~low);
            if (!y) continue;
            int dup = 0;
            for (int i = 0; i < ns; i++) if (seen[i] == y) { dup = 1; break; }
            if (dup) continue;
            if (ns == cap) { cap *= 2; seen = realloc(seen, cap * sizeof *seen); }
            seen[ns++] = y;
            if (blocked(y, pv)) {
                if (nk == kcap) { kcap *= 2; stack = realloc(stack, kcap * sizeof *stack); }
                stack[nk++] = y;
            } else {
                if (nf == fcap) { fcap *= 2; found = realloc(found, fcap * sizeof *found); }
                found[nf++] = y;
            }
        }
    }
    /* keep the maximal ones, in increasing order */
    uint32_t keep[64];
    int nkeep = 0;
    for (int i = 0; i < nf; i++) {
        int sub = 0;
        for (int j = 0; j < nf; j++) if (found[j] != found[i] && (found[j] & found[i]) == found[i]) { sub = 1; break; }
        if (!sub) {
            if (nkeep == 64) { free(seen); free(found); free(stack); fail(E_FULL, 0); }
            keep[nkeep++] = found[i];
        }
    }
    free(seen); free(found); free(stack);
    for (int i = 1; i < nkeep; i++)
        for (int j = i; j > 0 && keep[j - 1] > keep[j]; j--) { uint32_t t = keep[j]; keep[j] = keep[j - 1]; keep[j - 1] = t; }
    for (int i = 0; i < nkeep; i++) {
        if (n >= MAXI) fail(E_FULL, 0);
        isrc[n] = src; imask[n] = keep[i]; n++;
    }
    return n;
}
