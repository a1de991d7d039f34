/* The search's working zones, which keep bounds between their active clocks alone: the operations dbm.c does not
 * already run on a sub-matrix (its a_ functions: closure, extrapolation, forgetting lower bounds).
 *
 * A zone of a discrete state needs no bound on the clocks idle there (no guard reads them before their next reset:
 * their row has none, their column is column 0's), so the search works on act[0..na) alone: the clock 0, the state's
 * active clocks, and any other clock the step at hand reads or resets.  Entries of the full row-major d x d matrix
 * outside act x act are never read, nor written here; a clock joins act with its bounds written (a_free, a_reset).
 * Whole DALA's zones have 37 rows of which about 15 are active: each operation costs what one on a matrix of that
 * size would, not d * d.  act is ascending, so that loops over pairs meet them in the full matrix's order.  The
 * results on act x act are those on the whole matrix: an idle clock's row has no bound but its diagonal, so no path
 * through it is shorter than one around it, and no bound of the others depends on it. */

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
