/* The hot operations of runtime/zones/dbm.py in C: the same functions on the same row-major
 * (n+1) x (n+1) matrices of doubles (INFINITY absorbs sums), in place.  dbm.py keeps the numpy
 * versions as the reference and uses these when a compiler is there. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Every allocation of the zone library and its search goes through these, so that tests can make the n-th one from
 * now fail (zs_fail_allocation) and reach each out-of-memory path: the search must then say so, never go on with
 * less than it was given. */
static int64_t alloc_left = -1, alloc_count = 0;

static int alloc_fails(void)
{
    alloc_count++;
    return alloc_left >= 0 && alloc_left-- == 0;
}

static void *z_malloc(size_t n) { return alloc_fails() ? NULL : malloc(n); }
static void *z_calloc(size_t n, size_t size) { return alloc_fails() ? NULL : calloc(n, size); }
static void *z_realloc(void *p, size_t n) { return alloc_fails() ? NULL : realloc(p, n); }
#define malloc z_malloc
#define calloc z_calloc
#define realloc z_realloc

/* The n-th allocation from now fails (n >= 0; -1: none); allocations made since the library was loaded. */
void zs_fail_allocation(int64_t n) { alloc_left = n; }
int64_t zs_allocations(void) { return alloc_count; }

/* The zone library's loops over whole matrices (to_short, the inclusion tests) are worth vectorising even where
 * that needs a scalar tail, which -O2's cheap cost model refuses.  Other compilers ignore the pragma. */
#pragma GCC optimize("vect-cost-model=dynamic")

/* Floyd-Warshall: tightest bounds; an empty zone ends with a negative diagonal. */
void z_close(double *m, int d)
{
    for (int k = 0; k < d; k++) {
        const double *rk = m + (long)k * d;
        for (int i = 0; i < d; i++) {
            double *ri = m + (long)i * d;
            double ik = ri[k];
            if (ik == INFINITY)
                continue;
            for (int j = 0; j < d; j++) {
                double v = ik + rk[j];
                if (v < ri[j])
                    ri[j] = v;
            }
        }
    }
}

/* xi - xj <= c added to a canonical zone; 0 when nothing is left (m then unchanged). */
int z_constrain(double *m, int d, int i, int j, double c)
{
    if (m[(long)i * d + j] <= c)
        return 1;
    if (m[(long)j * d + i] + c < 0)
        return 0;
    double col[256], row[256];
    for (int a = 0; a < d; a++) {
        col[a] = m[(long)a * d + i];
        row[a] = m[(long)j * d + a];
    }
    for (int a = 0; a < d; a++) {
        double head = col[a] + c;
        if (head == INFINITY)
            continue;
        double *ra = m + (long)a * d;
        for (int b = 0; b < d; b++) {
            double v = head + row[b];
            if (v < ra[b])
                ra[b] = v;
        }
    }
    return 1;
}

/* Several operations below run on a sub-matrix: the bounds between the clocks act[0..na) (0 among them, ascending)
 * of the full row-major d x d matrix, the others neither read nor written.  The zone search works so on the active
 * clocks of a state (active.c); dbm.py's whole matrices are the case act = every clock (every_clock). */
static int every_clock(int d, int *act)
{
    for (int k = 0; k < d; k++)
        act[k] = k;
    return d;
}

/* Floyd-Warshall over the clocks of act. */
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

/* m was closed, then the entries at idx[0..n) (places in the full matrix) were raised: closed again.  Only those
 * entries can change (a path through a raised entry is no shorter than it was), so Floyd-Warshall over them alone is
 * the whole closure: na * n steps instead of na^3. */
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

/* Extra_LU on integers: a bound of row i past lower[i] forgotten, one of column j below -upper[j] - 1 raised to it
 * (dbm.py's extrapolate_np), then closed; 1 when something changed.  Extra_M is lower = upper = the ceilings. */
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

/* Extra_LU+ (Behrmann, Bouyer, Larsen, Pelanek) where plus[k]: a clock above its lower-bound constant has no
 * bound left in its row, one above its upper-bound constant none in its column (its lower bound raised to it);
 * only between clocks both marked (no priority compares them), Extra_LU elsewhere (dbm.py's extrapolate_lu_plus).
 * A lower bound raised above 0 (NO_BOUND's -U - 1 = 1, or dropped) is put back to x >= 0: clocks are never negative,
 * so the zone is the same, and its matrix is the one every other path to it gives (inclusion is then exact). */
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

/* Each clock of idx keeps its upper bounds only: its column set to column 0 (dbm.py's forget_below), in the rows of
 * act (a clock of idx outside act has its entries there written, and never read).  Row by row (column 0 is never one
 * of idx), so each row is read from memory once. */
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

int z_extrapolate_lu(double *m, int d, const double *lower, const double *upper)
{
    int act[256];
    return a_extrapolate_lu(m, d, act, every_clock(d, act), lower, upper);
}

int z_extrapolate(double *m, int d, const double *ceiling)
{
    return z_extrapolate_lu(m, d, ceiling, ceiling);
}

int z_extrapolate_lu_plus(double *m, int d, const double *lower, const double *upper, const unsigned char *plus)
{
    int act[256];
    return a_extrapolate_lu_plus(m, d, act, every_clock(d, act), lower, upper, plus);
}

void z_forget_below(double *m, int d, const int *idx, int count)
{
    int act[256];
    a_forget_below(m, d, act, every_clock(d, act), idx, count);
}

/* Every bound of big at least small's. */
int z_includes(const double *big, const double *small, int len)
{
    for (int k = 0; k < len; k++)
        if (big[k] < small[k])
            return 0;
    return 1;
}

/* src's zone with the clocks idx[0..count) forgotten (any value >= 0, as dbm.py's free_many), into m.  src may be
 * m itself: each row is read before it is written, and the rows of forgotten clocks are written over at the end.
 * Row by row, so that the columns' writes stay within the row being read. */
void z_free(double *m, const double *src, int d, const int *idx, int count)
{
    for (int a = 0; a < d; a++) {
        double *ra = m + (long)a * d, first = src[(long)a * d];
        if (ra != src + (long)a * d)
            memcpy(ra, src + (long)a * d, d * sizeof(double));
        for (int c = 0; c < count; c++)
            ra[idx[c]] = first;
    }
    for (int c = 0; c < count; c++) {
        double *ri = m + (long)idx[c] * d;
        for (int b = 0; b < d; b++)
            ri[b] = INFINITY;
        ri[idx[c]] = 0;
    }
}

/* The hull of a and b (the least zone holding both) into h; 1 when it holds nothing else (their union is
 * that zone), as dbm.py's union_np.  A point of the hull in neither is past a bound (i, j) of a that b goes
 * beyond and past a bound (k, l) of b that a goes beyond; on integer points the hull (closed) has one iff
 * h[i][l] + h[k][j] >= a[i][j] + b[k][l] + 2 (the only cycle through both negated bounds). */
int z_union(double *h, const double *a, const double *b, int d, int *past)
{
    long len = (long)d * d;
    for (long k = 0; k < len; k++)
        h[k] = a[k] > b[k] ? a[k] : b[k];
    int n = 0;  /* past[0..n): the bounds of b that a goes beyond (d * d numbers of scratch) */
    for (long k = 0; k < len; k++)
        if (a[k] > b[k])
            past[n++] = (int)k;
    int ok = 1;
    for (int i = 0; i < d && ok && n; i++)
        for (int j = 0; j < d && ok; j++) {
            double c = a[(long)i * d + j];
            if (b[(long)i * d + j] <= c)
                continue;
            for (int q = 0; q < n; q++) {
                int k = past[q] / d, l = past[q] % d;
                if (h[(long)i * d + l] + h[(long)k * d + j] >= c + b[past[q]] + 2) {
                    ok = 0;
                    break;
                }
            }
        }
    return ok;
}
