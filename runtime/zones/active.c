/* dbm.c's operations on the search's working zones, which keep bounds between their active clocks alone.
 *
 * A zone of a discrete state needs no bound on the clocks idle there (no guard reads them before their next reset:
 * their row has none, their column is column 0's), so the search works on act[0..na) alone: the clock 0, the state's
 * active clocks, and any other clock the step at hand reads or resets.  Entries of the full row-major d x d matrix
 * outside act x act are never read, nor written here; a clock joins act with its bounds written (a_free, a_reset).
 * Whole DALA's zones have 38 rows of which about 10 are active: each operation below costs what one on a
 * matrix of that size would, not d * d.  act is ascending, so that loops over pairs meet them in the full matrix's
 * order.  The results on act x act are dbm.c's on the whole matrix: an idle clock's row has no bound but its
 * diagonal, so no path through it is shorter than one around it, and no bound of the others depends on it. */

/* The active entries of src into dst. */
static void a_copy(double *restrict dst, const double *restrict src, int d, const int *act, int na)
{
    for (int a = 0; a < na; a++) {
        const double *s = src + (int64_t)act[a] * d;
        double *t = dst + (int64_t)act[a] * d;
        for (int b = 0; b < na; b++)
            t[act[b]] = s[act[b]];
    }
}

/* xi - xj <= c added (i and j active); 0 when nothing is left (m then unchanged), as z_constrain. */
static int a_constrain(double *m, int d, const int *act, int na, int i, int j, double c)
{
    if (m[(int64_t)i * d + j] <= c)
        return 1;
    if (m[(int64_t)j * d + i] + c < 0)
        return 0;
    double col[256], row[256];
    for (int a = 0; a < na; a++) {
        col[a] = m[(int64_t)act[a] * d + i];
        row[a] = m[(int64_t)j * d + act[a]];
    }
    for (int a = 0; a < na; a++) {
        double head = col[a] + c;
        if (head == INFINITY)
            continue;
        double *ra = m + (int64_t)act[a] * d;
        for (int b = 0; b < na; b++) {
            double v = head + row[b];
            if (v < ra[act[b]])
                ra[act[b]] = v;
        }
    }
    return 1;
}

/* The n bounds b (triples i, j, c) added in turn; 0 as soon as nothing is left. */
static int a_constrain_all(double *m, int d, const int *act, int na, const int64_t *b, int64_t n)
{
    for (int64_t k = 0; k < n; k++)
        if (!a_constrain(m, d, act, na, (int)b[3 * k], (int)b[3 * k + 1], (double)b[3 * k + 2]))
            return 0;
    return 1;
}

/* Time passes: no clock keeps an upper bound. */
static void a_up(double *m, int d, const int *act, int na)
{
    for (int a = 0; a < na; a++)
        if (act[a])
            m[(int64_t)act[a] * d] = INFINITY;
}

/* Clock i (active) set to v. */
static void a_reset(double *m, int d, const int *act, int na, int i, double v)
{
    double *ri = m + (int64_t)i * d;
    for (int a = 0; a < na; a++) {
        int k = act[a];
        ri[k] = v + m[k];
        m[(int64_t)k * d + i] = m[(int64_t)k * d] - v;
    }
    ri[i] = 0;
}

/* The clocks fr[0..nf) of act forgotten (any value >= 0), as z_free: their rows have no bound, their columns are
 * column 0's.  The other active clocks' bounds must be m's already. */
static void a_free(double *m, int d, const int *act, int na, const int *fr, int nf)
{
    for (int f = 0; f < nf; f++) {
        double *r = m + (int64_t)fr[f] * d;
        for (int b = 0; b < na; b++)
            r[act[b]] = INFINITY;
    }
    for (int a = 0; a < na; a++) {  /* row 0 first: column 0 of a forgotten row is infinity already */
        double *ra = m + (int64_t)act[a] * d, first = ra[0];
        for (int f = 0; f < nf; f++)
            ra[fr[f]] = first;
    }
    for (int f = 0; f < nf; f++)
        m[(int64_t)fr[f] * d + fr[f]] = 0;
}

/* Floyd-Warshall over the active clocks. */
static void a_close(double *m, int d, const int *act, int na)
{
    for (int k = 0; k < na; k++) {
        const double *rk = m + (int64_t)act[k] * d;
        for (int i = 0; i < na; i++) {
            double *ri = m + (int64_t)act[i] * d, ik = ri[act[k]];
            if (ik == INFINITY)
                continue;
            for (int j = 0; j < na; j++) {
                double v = ik + rk[act[j]];
                if (v < ri[act[j]])
                    ri[act[j]] = v;
            }
        }
    }
}

/* m was closed, then the entries at idx[0..n) (places in the full matrix) were raised: closed again, as
 * z_close_raised, through the active clocks. */
static void a_close_raised(double *m, int d, const int *act, int na, const int *idx, int n)
{
    int row[4096], col[4096];
    for (int e = 0; e < n; e++)
        row[e] = idx[e] / d * d, col[e] = idx[e] % d;
    for (int k = 0; k < na; k++) {
        const double *rk = m + (int64_t)act[k] * d;
        for (int e = 0; e < n; e++) {
            double v = m[row[e] + act[k]] + rk[col[e]];
            if (v < m[idx[e]])
                m[idx[e]] = v;
        }
    }
}

/* z_extrapolate_lu on the active clocks. */
static int a_extrapolate_lu(double *m, int d, const int *act, int na, const double *lower, const double *upper)
{
    int raised[4096], n = 0, all = na * na > 4096;
    double floor_[256];
    for (int b = 0; b < na; b++)
        floor_[b] = -upper[act[b]] - 1;
    for (int a = 0; a < na; a++) {
        int i = act[a];
        double *w = m + (int64_t)i * d, li = lower[i];
        int hit = 0;  /* most rows keep every bound: told first, without a branch per entry (the diagonal may count) */
        for (int b = 0; b < na; b++) {
            double v = w[act[b]];
            hit |= ((v > li) & (v != INFINITY)) | (v < floor_[b]);
        }
        if (!hit)
            continue;
        for (int b = 0; b < na; b++) {
            int j = act[b];
            double v = w[j], to = v > li ? INFINITY : v < floor_[b] ? floor_[b] : v;
            if (i == j || to == v)
                continue;
            raised[all ? 0 : n] = i * d + j;
            n++;
            w[j] = to;
        }
    }
    if (n && all)
        a_close(m, d, act, na);
    else if (n)
        a_close_raised(m, d, act, na, raised, n);
    return n > 0;
}

/* z_extrapolate_lu_plus on the active clocks. */
static int a_extrapolate_lu_plus(double *m, int d, const int *act, int na, const double *lower, const double *upper,
                                 const unsigned char *plus)
{
    double first[256];
    for (int a = 0; a < na; a++)
        first[a] = -m[act[a]];  /* row 0: each clock's lower bound, before anything changes */
    int changed = 0;
    for (int a = 0; a < na; a++)
        for (int b = 0; b < na; b++) {
            int i = act[a], j = act[b];
            if (i == j)
                continue;
            double *v = m + (int64_t)i * d + j, to = *v;
            int li = i && plus[i] && first[a] > lower[i] + 1, uj = j && plus[j] && first[b] > upper[j] + 1;
            if (li && (j == 0 || plus[j]))
                to = INFINITY;
            else if (uj && i && plus[i])
                to = INFINITY;
            else if (uj && !i)
                to = -upper[j] - 1;
            else if (*v > lower[i])
                to = INFINITY;
            else if (*v < -upper[j] - 1)
                to = -upper[j] - 1;
            if (to != *v) {
                *v = to;
                changed = 1;
            }
        }
    for (int b = 0; b < na; b++)  /* row 0: clocks are >= 0 */
        if (act[b] && m[act[b]] > 0) {
            m[act[b]] = 0;
            changed = 1;
        }
    if (changed)
        a_close(m, d, act, na);
    return changed;
}

/* Each clock of idx keeps its upper bounds only, as z_forget_below (idle ones' entries are written and never read). */
static void a_forget_below(double *m, int d, const int *act, int na, const int *idx, int count)
{
    for (int a = 0; a < na; a++) {
        double *ra = m + (int64_t)act[a] * d, first = ra[0];
        for (int c = 0; c < count; c++)
            ra[idx[c]] = first;
    }
    for (int c = 0; c < count; c++)
        m[(int64_t)idx[c] * d + idx[c]] = 0;
}
