/* test_deform_chol - deform.h part 1: CSC assembly, AMD, symbolic analysis, supernodal Cholesky,
   solves, constraints, errors. Cross-checks against a dense Cholesky and brute-force symbolic
   elimination; real-mesh checks on the Stanford bunny when glmark2-data is installed. */
#include <stdint.h>
/* test-only hooks into AMD (test_amd_degrees): called before each pivot and after each step's
   degree update, with the quotient graph */
struct dfm__amd;
static void amd_audit_pivot(const struct dfm__amd *s, int32_t p);
static void amd_audit_step(const struct dfm__amd *s, int32_t p);
#define DFM_TEST_AMD_PIVOT(s, p) amd_audit_pivot(s, p)
#define DFM_TEST_AMD_STEP(s, p) amd_audit_step(s, p)
#define DFM_IMPLEMENTATION
#include "deform.h"

#include "test.h"
#include "hashrand.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

#include <stdlib.h>
#include <string.h>
#include <math.h>

static int sanitize_mode(void) { return getenv("TEST_SANITIZE") != NULL; }

/* ---- a counting allocator that can fail the k-th allocation -------------------------------- */
typedef struct counting {
    long allocs, frees, fail_at; /* fail_at < 0: never */
} counting;
static void *counting_alloc(void *user, size_t size)
{
    counting *c = (counting *)user;
    if (c->fail_at >= 0 && c->allocs >= c->fail_at) return NULL;
    c->allocs++;
    return malloc(size);
}
static void counting_free(void *user, void *p)
{
    counting *c = (counting *)user;
    if (p) {
        c->frees++;
        free(p);
    }
}

/* ---- matrices ---------------------------------------------------------------------------------- */

/* random sparse symmetric positive definite matrix, lower stored: random off-diagonal pattern
   with density about avg entries per column, diagonal = sum |row| + shift */
static dfm_csc random_spd(size_t n, double avg, uint64_t seed, double shift)
{
    dfm_csc m;
    size_t j, i, nnz = 0, cap = n * (size_t)(avg * 3 + 4) + n;
    double *dense_rowsum = (double *)calloc(n, sizeof(double));
    dfm_csc_alloc(n, n, cap, DFM_CSC_SYMMETRIC_LOWER, NULL, &m);
    for (j = 0; j < n; j++) {
        size_t start = nnz;
        m.row_index[nnz] = (int32_t)j;
        m.values[nnz++] = 0.0;
        for (i = j + 1; i < n; i++) {
            double u = unit_random(seed * 1000003u + j * n + i, 1);
            if (u < avg / (double)n && nnz < cap) {
                double v = 2.0 * unit_random(seed * 1000003u + j * n + i, 2) - 1.0;
                m.row_index[nnz] = (int32_t)i;
                m.values[nnz++] = v;
                dense_rowsum[i] += fabs(v);
                dense_rowsum[j] += fabs(v);
            }
        }
        (void)start;
        m.col_start[j + 1] = nnz;
    }
    for (j = 0; j < n; j++) m.values[m.col_start[j]] = dense_rowsum[j] + shift;
    free(dense_rowsum);
    return m;
}

static double *to_dense(const dfm_csc *a)
{
    size_t n = a->n_rows, j, p;
    double *d = (double *)calloc(n * a->n_cols, sizeof(double));
    for (j = 0; j < a->n_cols; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            size_t i = (size_t)a->row_index[p];
            d[i + j * n] += a->values[p];
            if (a->kind == DFM_CSC_SYMMETRIC_LOWER && i != j) d[j + i * n] += a->values[p];
        }
    return d;
}

/* dense Cholesky solve (reference); returns 0 if not positive definite */
static int dense_solve(size_t n, const double *a, const double *b, double *x)
{
    double *l = (double *)malloc(n * n * sizeof(double));
    size_t i, j, k;
    memcpy(l, a, n * n * sizeof(double));
    for (j = 0; j < n; j++) {
        double d = l[j + j * n];
        for (k = 0; k < j; k++) d -= l[j + k * n] * l[j + k * n];
        if (!(d > 0)) {
            free(l);
            return 0;
        }
        d = sqrt(d);
        l[j + j * n] = d;
        for (i = j + 1; i < n; i++) {
            double s = l[i + j * n];
            for (k = 0; k < j; k++) s -= l[i + k * n] * l[j + k * n];
            l[i + j * n] = s / d;
        }
    }
    for (i = 0; i < n; i++) {
        double s = b[i];
        for (k = 0; k < i; k++) s -= l[i + k * n] * x[k];
        x[i] = s / l[i + i * n];
    }
    for (i = n; i-- > 0;) {
        double s = x[i];
        for (k = i + 1; k < n; k++) s -= l[k + i * n] * x[k];
        x[i] = s / l[i + i * n];
    }
    free(l);
    return 1;
}

static double norm_inf_matrix(const dfm_csc *a)
{
    size_t n = a->n_cols, j, p;
    double *rs = (double *)calloc(n, sizeof(double)), m = 0;
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            size_t i = (size_t)a->row_index[p];
            rs[i] += fabs(a->values[p]);
            if (i != j) rs[j] += fabs(a->values[p]);
        }
    for (j = 0; j < n; j++)
        if (rs[j] > m) m = rs[j];
    free(rs);
    return m;
}

/* ||b - Ax||inf / (||A||inf ||x||inf + ||b||inf), worst over nrhs */
static double residual(const dfm_csc *a, const double *x, const double *b, size_t nrhs)
{
    size_t n = a->n_cols, q, i;
    double *y = (double *)malloc(n * nrhs * sizeof(double)), worst = 0, an = norm_inf_matrix(a);
    dfm_csc_multiply(a, x, y, nrhs);
    for (q = 0; q < nrhs; q++) {
        double r = 0, xn = 0, bn = 0, v;
        for (i = 0; i < n; i++) {
            r = fmax(r, fabs(b[q * n + i] - y[q * n + i]));
            xn = fmax(xn, fabs(x[q * n + i]));
            bn = fmax(bn, fabs(b[q * n + i]));
        }
        v = r / (an * xn + bn);
        if (!(v <= worst)) worst = v;
    }
    free(y);
    return worst;
}

static double *random_vector(size_t n, uint64_t seed)
{
    double *v = (double *)malloc(n * sizeof(double));
    size_t i;
    for (i = 0; i < n; i++) v[i] = 2.0 * unit_random(seed * 7919 + i, 3) - 1.0;
    return v;
}

/* factor + solve with default options; returns residual, or -1 on failure */
static double solve_residual(const dfm_csc *a, const double *b, size_t nrhs, double *x, const dfm_chol_options *o)
{
    dfm_chol *c = NULL;
    double r = -1;
    size_t n = a->n_cols;
    if (dfm_chol_analyze(a, o, &c) != DFM_OK) return -1;
    if (dfm_chol_factor(c, a) == DFM_OK) {
        memcpy(x, b, n * nrhs * sizeof(double));
        if (dfm_chol_solve(c, x, nrhs) == DFM_OK) r = residual(a, x, b, nrhs);
    }
    dfm_chol_free(c);
    return r;
}

/* ---- meshes -------------------------------------------------------------------------------- */

/* a w x h grid of vertices over [0,1]^2 with a bumpy z, two triangles per cell, diagonals
   alternating */
static void grid_mesh(size_t w, size_t h, float **pos, uint32_t **idx, size_t *nv, size_t *nt)
{
    size_t x, y, t = 0;
    *nv = w * h;
    *nt = 2 * (w - 1) * (h - 1);
    *pos = (float *)malloc(*nv * 3 * sizeof(float));
    *idx = (uint32_t *)malloc(*nt * 3 * sizeof(uint32_t));
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            float *p = *pos + 3 * (y * w + x);
            p[0] = (float)x / (float)(w - 1) + 0.2f * (float)unit_random(y * w + x, 4) / (float)w;
            p[1] = (float)y / (float)(h - 1) + 0.2f * (float)unit_random(y * w + x, 5) / (float)h;
            p[2] = 0.1f * (float)sin(3.0 * p[0]) * (float)cos(2.0 * p[1]);
        }
    for (y = 0; y + 1 < h; y++)
        for (x = 0; x + 1 < w; x++) {
            uint32_t a = (uint32_t)(y * w + x), b = a + 1, c = a + (uint32_t)w, d = c + 1;
            uint32_t *f = *idx + 6 * t++;
            if ((x + y) & 1) {
                f[0] = a; f[1] = b; f[2] = d; f[3] = a; f[4] = d; f[5] = c;
            } else {
                f[0] = a; f[1] = b; f[2] = c; f[3] = b; f[4] = d; f[5] = c;
            }
        }
}

/* adds d to the diagonal entries of the listed rows (every diagonal entry is stored) */
static void add_diagonal(dfm_csc *a, const unsigned char *which, double d)
{
    size_t j, p;
    for (j = 0; j < a->n_cols; j++)
        if (which[j])
            for (p = a->col_start[j]; p < a->col_start[j + 1]; p++)
                if ((size_t)a->row_index[p] == j) a->values[p] += d;
}

static unsigned char *every_kth(size_t n, size_t k)
{
    unsigned char *m = (unsigned char *)calloc(n, 1);
    size_t i;
    for (i = 0; i < n; i += k) m[i] = 1;
    return m;
}

/* ---- brute-force symbolic elimination ------------------------------------------------------ */
static void brute_counts(const dfm_csc *a, const int32_t *perm, size_t *counts)
{
    size_t n = a->n_cols, j, p, i, k;
    unsigned char *s = (unsigned char *)calloc(n * n, 1);
    int32_t *ip = (int32_t *)malloc(n * sizeof(int32_t));
    for (k = 0; k < n; k++) ip[perm[k]] = (int32_t)k;
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            size_t I = (size_t)ip[a->row_index[p]], J = (size_t)ip[j];
            s[I + J * n] = s[J + I * n] = 1;
        }
    for (k = 0; k < n; k++) {
        s[k + k * n] = 1;
        for (i = k + 1; i < n; i++)
            if (s[i + k * n])
                for (j = k + 1; j <= i; j++)
                    if (s[j + k * n]) s[i + j * n] = s[j + i * n] = 1;
    }
    for (k = 0; k < n; k++) {
        counts[k] = 0;
        for (i = k; i < n; i++) counts[k] += s[i + k * n];
    }
    free(s);
    free(ip);
}

/* ---- tests ------------------------------------------------------------------------------------- */

static void test_random_vs_dense(void)
{
    static const size_t sizes[] = {1, 2, 3, 7, 30, 100, 250, 500};
    static const double dens[] = {0.0, 1.0, 3.0, 8.0};
    size_t si, di, i;
    int all_ok = 1, counts_ok = 1, nocount = 1;
    double worst = 0, worst_dx = 0;
    for (si = 0; si < sizeof sizes / sizeof *sizes; si++)
        for (di = 0; di < sizeof dens / sizeof *dens; di++) {
            size_t n = sizes[si];
            dfm_csc a = random_spd(n, dens[di], si * 10 + di, 0.1);
            double *b = random_vector(n * 2, si + 100 * di), *x = (double *)malloc(2 * n * sizeof(double));
            double *d = to_dense(&a), *xd = (double *)malloc(n * sizeof(double)), r, scale = 0;
            dfm_chol *c = NULL;
            r = solve_residual(&a, b, 2, x, NULL);
            if (r < 0) all_ok = 0;
            if (r > worst) worst = r;
            if (dense_solve(n, d, b, xd)) {
                for (i = 0; i < n; i++) scale = fmax(scale, fabs(xd[i]));
                for (i = 0; i < n; i++) worst_dx = fmax(worst_dx, fabs(x[i] - xd[i]) / scale);
            } else {
                all_ok = 0;
            }
            /* column counts against brute-force symbolic elimination with the same permutation */
            if (dfm_chol_analyze(&a, NULL, &c) == DFM_OK) {
                size_t *bc = (size_t *)malloc(n * sizeof(size_t)), total = 0;
                dfm_chol_info info;
                brute_counts(&a, dfm_chol_permutation(c), bc);
                for (i = 0; i < n; i++) {
                    if (bc[i] != dfm_chol_column_counts(c)[i]) counts_ok = 0;
                    total += bc[i];
                }
                dfm_chol_get_info(c, &info);
                if (info.nnz_l != total || info.stored_entries < total) counts_ok = 0;
                nocount = 0;
                free(bc);
            } else {
                counts_ok = 0;
            }
            dfm_chol_free(c);
            free(b);
            free(x);
            free(d);
            free(xd);
            dfm_csc_free(&a);
        }
    T_CHECK(all_ok);
    T_CHECK_MSG(worst <= 1e-14, "worst residual %.3g", worst);
    T_CHECK_MSG(worst_dx <= 1e-10, "worst |x - x_dense| / |x_dense| %.3g", worst_dx);
    T_CHECK(counts_ok && !nocount);
}

/* natural order and a given order on the same matrix also match brute force */
static void test_orderings(void)
{
    size_t n = 200, i;
    dfm_csc a = random_spd(n, 4.0, 77, 0.5);
    double *b = random_vector(n, 5), *x = (double *)malloc(n * sizeof(double));
    int32_t *perm = (int32_t *)malloc(n * sizeof(int32_t));
    dfm_chol_options o = dfm_chol_default_options();
    dfm_chol *c = NULL;
    size_t *bc = (size_t *)malloc(n * sizeof(size_t));
    int ok = 1;
    for (i = 0; i < n; i++) perm[i] = (int32_t)(n - 1 - i);
    o.ordering = DFM_ORDER_NATURAL;
    T_CHECK(solve_residual(&a, b, 1, x, &o) <= 1e-14);
    T_EQ_INT(dfm_chol_analyze(&a, &o, &c), DFM_OK);
    brute_counts(&a, dfm_chol_permutation(c), bc);
    for (i = 0; i < n; i++) ok &= bc[i] == dfm_chol_column_counts(c)[i];
    T_CHECK(ok);
    dfm_chol_free(c);
    o.ordering = DFM_ORDER_GIVEN;
    o.perm = perm;
    T_CHECK(solve_residual(&a, b, 1, x, &o) <= 1e-14);
    perm[3] = perm[4]; /* not a permutation */
    T_EQ_INT(dfm_chol_analyze(&a, &o, &c), DFM_ERR_BAD_INDEX);
    T_CHECK(c == NULL);
    free(bc);
    free(perm);
    free(b);
    free(x);
    dfm_csc_free(&a);
}

static void test_not_spd(void)
{
    size_t n = 300, cols[] = {0, 17, 150, 299}, k, p;
    for (k = 0; k < 4; k++) {
        dfm_csc a = random_spd(n, 3.0, 9 + k, 0.2);
        dfm_chol *c = NULL;
        dfm_chol_info info;
        size_t j = cols[k];
        for (p = a.col_start[j]; p < a.col_start[j + 1]; p++)
            if ((size_t)a.row_index[p] == j) a.values[p] = -1.0;
        T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_OK);
        T_EQ_INT(dfm_chol_factor(c, &a), DFM_ERR_NOT_POSITIVE_DEFINITE);
        dfm_chol_get_info(c, &info);
        T_EQ_INT(info.failed_column, (long long)j);
        T_EQ_INT(info.factored, 0);
        {
            double x = 0;
            T_EQ_INT(dfm_chol_solve(c, &x, 1), DFM_ERR_INVALID_ARGUMENT); /* not factored */
        }
        /* fix the value: the same object refactors */
        for (p = a.col_start[j]; p < a.col_start[j + 1]; p++)
            if ((size_t)a.row_index[p] == j) a.values[p] = 100.0;
        T_EQ_INT(dfm_chol_factor(c, &a), DFM_OK);
        dfm_chol_get_info(c, &info);
        T_EQ_INT(info.failed_column, -1);
        dfm_chol_free(c);
        dfm_csc_free(&a);
    }
    /* a NaN pivot is reported as not positive definite too (values are checked first: NaN in A
       is BAD_VALUE) */
    {
        dfm_csc a = random_spd(10, 2.0, 3, 0.1);
        dfm_chol *c = NULL;
        T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_OK);
        a.values[0] = NAN;
        T_EQ_INT(dfm_chol_factor(c, &a), DFM_ERR_BAD_VALUE);
        a.values[0] = 0.0; /* zero pivot in column 0 (or a later one): not positive definite */
        a.values[a.col_start[1]] = 0.0;
        T_EQ_INT(dfm_chol_factor(c, &a), DFM_ERR_NOT_POSITIVE_DEFINITE);
        dfm_chol_free(c);
        dfm_csc_free(&a);
    }
}

/* P A P^T with a random permutation gives the same solution */
static void test_permutation_invariance(void)
{
    size_t n = 400, i, j, p;
    dfm_csc a = random_spd(n, 5.0, 21, 0.05), pa;
    int32_t *perm = (int32_t *)malloc(n * sizeof(int32_t)), *ip = (int32_t *)malloc(n * sizeof(int32_t));
    int32_t *ti = (int32_t *)malloc(a.col_start[n] * sizeof(int32_t)), *tj = (int32_t *)malloc(a.col_start[n] * sizeof(int32_t));
    double *b = random_vector(3 * n, 8), *pb = (double *)malloc(3 * n * sizeof(double));
    double *x = (double *)malloc(3 * n * sizeof(double)), *px = (double *)malloc(3 * n * sizeof(double)), diff = 0;
    size_t cnt = 0, q;
    for (i = 0; i < n; i++) perm[i] = (int32_t)i;
    for (i = n; i-- > 1;) {
        size_t k = (size_t)(unit_random(i, 6) * (double)(i + 1));
        int32_t t = perm[i];
        perm[i] = perm[k];
        perm[k] = t;
    }
    for (i = 0; i < n; i++) ip[perm[i]] = (int32_t)i;
    /* pa(ip[i], ip[j]) = a(i, j), kept lower */
    for (j = 0; j < n; j++)
        for (p = a.col_start[j]; p < a.col_start[j + 1]; p++) {
            int32_t I = ip[a.row_index[p]], J = ip[j];
            ti[cnt] = I > J ? I : J;
            tj[cnt++] = I > J ? J : I;
        }
    {
        double *tv = (double *)malloc(cnt * sizeof(double));
        for (i = 0; i < cnt; i++) tv[i] = a.values[i];
        dfm_allocator al = dfm__resolve_allocator(NULL);
        T_EQ_INT(dfm__from_triplets(n, n, cnt, ti, tj, tv, DFM_CSC_SYMMETRIC_LOWER, &al, &pa), DFM_OK);
        free(tv);
    }
    for (q = 0; q < 3; q++)
        for (i = 0; i < n; i++) pb[q * n + (size_t)ip[i]] = b[q * n + i];
    T_CHECK(solve_residual(&a, b, 3, x, NULL) <= 1e-14);
    T_CHECK(solve_residual(&pa, pb, 3, px, NULL) <= 1e-14);
    for (q = 0; q < 3; q++)
        for (i = 0; i < n; i++) diff = fmax(diff, fabs(x[q * n + i] - px[q * n + (size_t)ip[i]]));
    T_CHECK_MSG(diff <= 1e-10, "diff %.3g", diff);
    free(perm);
    free(ip);
    free(ti);
    free(tj);
    free(b);
    free(pb);
    free(x);
    free(px);
    dfm_csc_free(&a);
    dfm_csc_free(&pa);
}

/* L^T L + D from dfm_normal_matrix against the explicit product, for all Laplacian kinds */
static void test_normal_matrix(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt, kind, i, j, k, p;
    grid_mesh(14, 11, &pos, &idx, &nv, &nt);
    for (kind = 0; kind < 3; kind++) {
        dfm_csc l, m;
        double *ld, *md, *dg = random_vector(nv, 12), maxdiff = 0, maxval = 0;
        int pattern_ok = 1, sym_ok = 1;
        for (i = 0; i < nv; i++) dg[i] = fabs(dg[i]);
        T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, (int)kind, NULL, &l), DFM_OK);
        T_EQ_INT(dfm_normal_matrix(&l, dg, NULL, &m), DFM_OK);
        T_EQ_INT(m.kind, DFM_CSC_SYMMETRIC_LOWER);
        ld = to_dense(&l);
        md = (double *)calloc(nv * nv, sizeof(double));
        /* explicit product: (L^T L)_jk = sum_i L_ij L_ik */
        for (j = 0; j < nv; j++)
            for (k = 0; k < nv; k++) {
                double s = j == k ? dg[j] : 0.0;
                for (i = 0; i < nv; i++) s += ld[i + j * nv] * ld[i + k * nv];
                md[j + k * nv] = s;
            }
        for (j = 0; j < nv; j++)
            for (p = m.col_start[j]; p < m.col_start[j + 1]; p++) {
                size_t r = (size_t)m.row_index[p];
                maxdiff = fmax(maxdiff, fabs(m.values[p] - md[r + j * nv]));
                md[r + j * nv] = 0.0; /* consumed */
                md[j + r * nv] = 0.0;
                if (p > m.col_start[j] && m.row_index[p - 1] >= m.row_index[p]) pattern_ok = 0;
            }
        /* every nonzero of the explicit product is stored */
        for (i = 0; i < nv * nv; i++) maxval = fmax(maxval, fabs(md[i]));
        if (kind != DFM_LAPLACIAN_UNIFORM_NORMALIZED)
            for (j = 0; j < nv; j++) /* symmetric kinds: L is symmetric, row sums zero */
                for (p = l.col_start[j]; p < l.col_start[j + 1]; p++)
                    if (l.row_index[p] < (int32_t)j) sym_ok = 0;
        T_CHECK_MSG(maxdiff <= 1e-12, "kind %d: |M - L^T L - D| = %.3g", (int)kind, maxdiff);
        T_CHECK_MSG(maxval <= 1e-12, "kind %d: product entry %.3g missing from the pattern", (int)kind, maxval);
        T_CHECK(pattern_ok && sym_ok);
        free(ld);
        free(md);
        free(dg);
        dfm_csc_free(&l);
        dfm_csc_free(&m);
    }
    /* a rectangular general A: A^T A */
    {
        size_t r = 40, c = 25, q;
        dfm_csc a, m;
        double *ad, maxdiff = 0;
        dfm_csc_alloc(r, c, r * c, DFM_CSC_GENERAL, NULL, &a);
        q = 0;
        for (j = 0; j < c; j++) {
            for (i = 0; i < r; i++)
                if (unit_random(i * c + j, 7) < 0.15) {
                    a.row_index[q] = (int32_t)i;
                    a.values[q++] = unit_random(i * c + j, 8) - 0.5;
                }
            a.col_start[j + 1] = q;
        }
        T_EQ_INT(dfm_normal_matrix(&a, NULL, NULL, &m), DFM_OK);
        ad = to_dense(&a);
        for (j = 0; j < c; j++)
            for (k = 0; k < c; k++) {
                double s = 0, v = 0;
                for (i = 0; i < r; i++) s += ad[i + j * r] * ad[i + k * r];
                if (k >= j)
                    for (p = m.col_start[j]; p < m.col_start[j + 1]; p++)
                        if ((size_t)m.row_index[p] == k) v = m.values[p];
                if (k >= j) maxdiff = fmax(maxdiff, fabs(s - v));
            }
        T_CHECK(maxdiff <= 1e-14);
        free(ad);
        dfm_csc_free(&a);
        dfm_csc_free(&m);
    }
    free(pos);
    free(idx);
}

static void test_laplacian_values(void)
{
    /* a right isosceles triangle pair (unit square split on the diagonal 0-2): cot 45 = 1 */
    float pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 5, 5, 5};
    uint32_t idx[] = {0, 1, 2, 0, 2, 3};
    dfm_csc l;
    double *d;
    T_EQ_INT(dfm_mesh_laplacian(pos, 5, idx, 2, DFM_LAPLACIAN_COTAN, NULL, &l), DFM_OK);
    d = to_dense(&l);
    T_NEAR(d[0 + 1 * 5], -0.5, 1e-12); /* edge 0-1: opposite angle at 2 is 45 deg: cot/2 */
    T_NEAR(d[0 + 2 * 5], 0.0, 1e-12);  /* diagonal: both opposite angles 90 deg */
    T_NEAR(d[0 + 0 * 5], 1.0, 1e-12);
    T_NEAR(d[4 + 4 * 5], 0.0, 0.0);    /* unused vertex: zero row, diagonal stored */
    T_EQ_SIZE(l.col_start[5] - l.col_start[4], 1);
    free(d);
    dfm_csc_free(&l);
    T_EQ_INT(dfm_mesh_laplacian(pos, 5, idx, 2, DFM_LAPLACIAN_UNIFORM_NORMALIZED, NULL, &l), DFM_OK);
    d = to_dense(&l);
    T_NEAR(d[0 + 0 * 5], 1.0, 0);
    T_NEAR(d[0 + 1 * 5], -1.0 / 3.0, 1e-15); /* vertex 0 has neighbours 1, 2, 3 */
    T_NEAR(d[1 + 0 * 5], -0.5, 1e-15);       /* vertex 1 has neighbours 0, 2 */
    free(d);
    dfm_csc_free(&l);
}

/* mesh systems: cotan Laplacian + 1% constraints, bi-Laplacian, against dense */
static void test_mesh_systems(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt, i;
    dfm_csc l, m;
    unsigned char *fixed;
    double *b, *x, *xd, *d, r, dx = 0, sc = 0;
    grid_mesh(20, 21, &pos, &idx, &nv, &nt);
    fixed = every_kth(nv, 100);
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, NULL, &l), DFM_OK);
    add_diagonal(&l, fixed, 1.0);
    b = random_vector(3 * nv, 31);
    x = (double *)malloc(3 * nv * sizeof(double));
    xd = (double *)malloc(nv * sizeof(double));
    r = solve_residual(&l, b, 3, x, NULL);
    T_CHECK_MSG(r >= 0 && r <= 1e-14, "laplacian residual %.3g", r);
    d = to_dense(&l);
    T_CHECK(dense_solve(nv, d, b, xd));
    for (i = 0; i < nv; i++) sc = fmax(sc, fabs(xd[i]));
    for (i = 0; i < nv; i++) dx = fmax(dx, fabs(xd[i] - x[i]) / sc);
    T_CHECK_MSG(dx <= 1e-10, "laplacian vs dense %.3g", dx);
    free(d);
    {
        double *dg = (double *)calloc(nv, sizeof(double));
        dfm_csc lu;
        for (i = 0; i < nv; i++) dg[i] = fixed[i] ? 1.0 : 0.0;
        T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, NULL, &lu), DFM_OK);
        T_EQ_INT(dfm_normal_matrix(&lu, dg, NULL, &m), DFM_OK);
        r = solve_residual(&m, b, 3, x, NULL);
        T_CHECK_MSG(r >= 0 && r <= 1e-14, "bilaplacian residual %.3g", r);
        d = to_dense(&m);
        T_CHECK(dense_solve(nv, d, b, xd));
        sc = 0;
        dx = 0;
        for (i = 0; i < nv; i++) sc = fmax(sc, fabs(xd[i]));
        for (i = 0; i < nv; i++) dx = fmax(dx, fabs(xd[i] - x[i]) / sc);
        /* the bi-Laplacian is ill-conditioned: the two solutions agree to about cond * eps */
        T_CHECK_MSG(dx <= 1e-6, "bilaplacian vs dense %.3g", dx);
        /* iterative refinement does not make the residual worse */
        {
            dfm_chol *c = NULL;
            double *xr = (double *)malloc(3 * nv * sizeof(double)), r0, r1;
            T_EQ_INT(dfm_chol_analyze(&m, NULL, &c), DFM_OK);
            T_EQ_INT(dfm_chol_factor(c, &m), DFM_OK);
            T_EQ_INT(dfm_chol_solve_refined(c, &m, b, xr, 3, 0), DFM_OK);
            r0 = residual(&m, xr, b, 3);
            T_EQ_INT(dfm_chol_solve_refined(c, &m, b, xr, 3, 3), DFM_OK);
            r1 = residual(&m, xr, b, 3);
            T_CHECK_MSG(r1 <= r0 * 1.0000001 && r1 <= 1e-15, "refined %.3g vs %.3g", r1, r0);
            free(xr);
            dfm_chol_free(c);
        }
        free(d);
        free(dg);
        dfm_csc_free(&lu);
        dfm_csc_free(&m);
    }
    free(b);
    free(x);
    free(xd);
    free(fixed);
    dfm_csc_free(&l);
    free(pos);
    free(idx);
}

/* refactorization with new values, multiple right-hand sides, determinism */
static void test_refactor_multi_rhs(void)
{
    size_t n = 350, q, i;
    dfm_csc a = random_spd(n, 6.0, 41, 0.3);
    dfm_chol *c = NULL, *c2 = NULL;
    double *b = random_vector(7 * n, 2), *x = (double *)malloc(7 * n * sizeof(double)), *x1 = (double *)malloc(n * sizeof(double));
    double worst = 0;
    int same = 1;
    T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_OK);
    T_EQ_INT(dfm_chol_factor(c, &a), DFM_OK);
    memcpy(x, b, 7 * n * sizeof(double));
    T_EQ_INT(dfm_chol_solve(c, x, 7), DFM_OK);
    for (q = 0; q < 7; q++) {
        memcpy(x1, b + q * n, n * sizeof(double));
        dfm_chol_solve(c, x1, 1);
        for (i = 0; i < n; i++) worst = fmax(worst, fabs(x1[i] - x[q * n + i]));
    }
    T_CHECK_MSG(worst <= 1e-13, "multi-rhs vs single %.3g", worst);
    T_CHECK(residual(&a, x, b, 7) <= 1e-14);
    /* new values, same pattern */
    for (i = 0; i < a.col_start[n]; i++) a.values[i] *= 1.0 + 0.5 * unit_random(i, 9);
    for (i = 0; i < n; i++) a.values[a.col_start[i]] += 3.0;
    T_EQ_INT(dfm_chol_factor(c, &a), DFM_OK);
    memcpy(x, b, 7 * n * sizeof(double));
    T_EQ_INT(dfm_chol_solve(c, x, 7), DFM_OK);
    T_CHECK(residual(&a, x, b, 7) <= 1e-14);
    /* determinism: a second analysis and factorization gives the same bits */
    T_EQ_INT(dfm_chol_analyze(&a, NULL, &c2), DFM_OK);
    T_EQ_INT(dfm_chol_factor(c2, &a), DFM_OK);
    same &= memcmp(dfm_chol_permutation(c), dfm_chol_permutation(c2), n * sizeof(int32_t)) == 0;
    memcpy(x1, b, n * sizeof(double));
    dfm_chol_solve(c2, x1, 1);
    same &= memcmp(x1, x, n * sizeof(double)) == 0;
    T_CHECK(same);
    /* a different pattern is refused */
    {
        dfm_csc a2 = random_spd(n, 6.0, 42, 0.3);
        T_EQ_INT(dfm_chol_factor(c, &a2), DFM_ERR_PATTERN_MISMATCH);
        dfm_csc_free(&a2);
    }
    dfm_chol_free(c);
    dfm_chol_free(c2);
    free(b);
    free(x);
    free(x1);
    dfm_csc_free(&a);
}

/* hard constraints by elimination: the solution satisfies the free rows and the fixed values */
static void test_constraints(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt, i, q;
    dfm_csc l, m;
    unsigned char *fixed;
    dfm_constrained *c = NULL;
    double *b, *fv, *x, *y, worst = 0, fixed_err = 0;
    grid_mesh(25, 18, &pos, &idx, &nv, &nt);
    fixed = every_kth(nv, 37);
    for (i = 0; i < 25; i++) fixed[i] = 1; /* a whole boundary row too */
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, NULL, &l), DFM_OK);
    T_EQ_INT(dfm_normal_matrix(&l, NULL, NULL, &m), DFM_OK); /* singular without the constraints */
    b = random_vector(3 * nv, 51);
    fv = random_vector(3 * nv, 52);
    x = (double *)malloc(3 * nv * sizeof(double));
    y = (double *)malloc(3 * nv * sizeof(double));
    {
        /* with coordinates (nested dissection of the free block) the same solution */
        dfm_constrained *cc = NULL;
        dfm_chol_options o = dfm_chol_default_options();
        double *co = (double *)malloc(3 * nv * sizeof(double)), d = 0;
        for (i = 0; i < 3 * nv; i++) co[i] = pos[i];
        o.coords = co;
        T_EQ_INT(dfm_constrained_analyze(&m, fixed, &o, &cc), DFM_OK);
        T_EQ_INT(dfm_constrained_factor(cc, &m), DFM_OK);
        T_EQ_INT(dfm_constrained_solve(cc, b, fv, y, 3), DFM_OK);
        T_EQ_INT(dfm_constrained_analyze(&m, fixed, NULL, &c), DFM_OK);
        T_EQ_INT(dfm_constrained_factor(c, &m), DFM_OK);
        T_EQ_INT(dfm_constrained_solve(c, b, fv, x, 3), DFM_OK);
        for (i = 0; i < 3 * nv; i++) d = fmax(d, fabs(x[i] - y[i]));
        T_CHECK_MSG(d <= 1e-9, "constrained with and without coordinates %.3g", d);
        dfm_constrained_free(cc);
        free(co);
    }
    dfm_csc_multiply(&m, x, y, 3);
    for (q = 0; q < 3; q++)
        for (i = 0; i < nv; i++) {
            if (fixed[i]) fixed_err = fmax(fixed_err, fabs(x[q * nv + i] - fv[q * nv + i]));
            else worst = fmax(worst, fabs(y[q * nv + i] - b[q * nv + i]));
        }
    T_NEAR(fixed_err, 0.0, 0.0);
    T_CHECK_MSG(worst <= 1e-9, "free rows residual %.3g", worst);
    /* new weights, same pattern: refactor; the failing column is reported in input numbering */
    {
        size_t j, p, bad = 0;
        for (j = 0; j < nv && !bad; j++)
            if (!fixed[j]) bad = j + 200 < nv && !fixed[j + 200] ? j + 200 : 0;
        for (p = m.col_start[bad]; p < m.col_start[bad + 1]; p++)
            if ((size_t)m.row_index[p] == bad) m.values[p] = -5.0;
        T_EQ_INT(dfm_constrained_factor(c, &m), DFM_ERR_NOT_POSITIVE_DEFINITE);
        T_EQ_INT(dfm_constrained_chol(c) ? 1 : 0, 1);
        {
            dfm_chol_info info;
            dfm_chol_get_info(dfm_constrained_chol(c), &info);
            T_EQ_INT(info.failed_column, (long long)bad);
        }
    }
    /* fixed everything: refused */
    {
        unsigned char *all = (unsigned char *)malloc(nv);
        dfm_constrained *c2 = NULL;
        memset(all, 1, nv);
        T_EQ_INT(dfm_constrained_analyze(&m, all, NULL, &c2), DFM_ERR_INVALID_ARGUMENT);
        T_CHECK(c2 == NULL);
        free(all);
    }
    dfm_constrained_free(c);
    free(b);
    free(fv);
    free(x);
    free(y);
    free(fixed);
    dfm_csc_free(&l);
    dfm_csc_free(&m);
    free(pos);
    free(idx);
}

/* 3x3 blocks: identity blocks give three independent solves; random SPD blocks match dense */
static void test_blocks(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt, i, q, p;
    dfm_csc l, m, e, e2;
    unsigned char *fixed;
    double *b, *x, *x3, diff = 0, r;
    dfm_chol_options o = dfm_chol_default_options();
    grid_mesh(12, 13, &pos, &idx, &nv, &nt);
    fixed = every_kth(nv, 20);
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_UNIFORM, NULL, &l), DFM_OK);
    T_EQ_INT(dfm_normal_matrix(&l, NULL, NULL, &m), DFM_OK);
    add_diagonal(&m, fixed, 2.0);
    T_EQ_INT(dfm_block_expand(&m, 3, NULL, NULL, &e), DFM_OK);
    T_EQ_SIZE(e.n_cols, 3 * nv);
    b = random_vector(3 * nv, 61);
    x = (double *)malloc(3 * nv * sizeof(double));
    x3 = (double *)malloc(3 * nv * sizeof(double));
    T_CHECK(solve_residual(&m, b, 3, x, NULL) <= 1e-14);
    {
        /* b interleaved: unknown r of vertex i is row 3i + r */
        double *bi = (double *)malloc(3 * nv * sizeof(double));
        for (q = 0; q < 3; q++)
            for (i = 0; i < nv; i++) bi[3 * i + q] = b[q * nv + i];
        o.block_size = 3;
        r = solve_residual(&e, bi, 1, x3, &o);
        T_CHECK_MSG(r >= 0 && r <= 1e-14, "block residual %.3g", r);
        for (q = 0; q < 3; q++)
            for (i = 0; i < nv; i++) diff = fmax(diff, fabs(x3[3 * i + q] - x[q * nv + i]));
        T_CHECK_MSG(diff <= 1e-9, "block vs scalar %.3g", diff);
        free(bi);
    }
    /* random coupled blocks: diagonal blocks m_ii I + s S_i (S_i symmetric), off-diagonal m_ij R */
    {
        size_t nnz = m.col_start[nv], j;
        double *blk = (double *)malloc(nnz * 9 * sizeof(double)), *d, *xd = (double *)malloc(3 * nv * sizeof(double)), sc = 0;
        for (j = 0; j < nv; j++)
            for (p = m.col_start[j]; p < m.col_start[j + 1]; p++) {
                double *B = blk + 9 * p;
                size_t r2, c2;
                for (r2 = 0; r2 < 3; r2++)
                    for (c2 = 0; c2 < 3; c2++) B[r2 * 3 + c2] = m.values[p] * (r2 == c2 ? 1.0 : 0.0);
                if ((size_t)m.row_index[p] == j) {
                    double s = 0.1 * fabs(m.values[p]);
                    B[1] = B[3] = s * unit_random(p, 10);
                    B[2] = B[6] = s * unit_random(p, 11);
                    B[5] = B[7] = s * unit_random(p, 12);
                } else {
                    for (r2 = 0; r2 < 9; r2++) B[r2] += 0.05 * m.values[p] * (unit_random(p * 9 + r2, 13) - 0.5);
                }
            }
        /* make it safely SPD: add to the diagonal blocks */
        for (j = 0; j < nv; j++) {
            double *B = blk + 9 * m.col_start[j];
            B[0] += 5;
            B[4] += 5;
            B[8] += 5;
        }
        T_EQ_INT(dfm_block_expand(&m, 3, blk, NULL, &e2), DFM_OK);
        r = solve_residual(&e2, b, 1, x3, &o);
        T_CHECK_MSG(r >= 0 && r <= 1e-14, "coupled block residual %.3g", r);
        d = to_dense(&e2);
        T_CHECK(dense_solve(3 * nv, d, b, xd));
        diff = 0;
        for (i = 0; i < 3 * nv; i++) sc = fmax(sc, fabs(xd[i]));
        for (i = 0; i < 3 * nv; i++) diff = fmax(diff, fabs(xd[i] - x3[i]) / sc);
        T_CHECK_MSG(diff <= 1e-10, "coupled block vs dense %.3g", diff);
        /* block ordering keeps a vertex's three unknowns together */
        {
            dfm_chol *c = NULL;
            int together = 1;
            T_EQ_INT(dfm_chol_analyze(&e2, &o, &c), DFM_OK);
            for (i = 0; i < 3 * nv; i += 3) {
                const int32_t *pm = dfm_chol_permutation(c);
                together &= pm[i] % 3 == 0 && pm[i + 1] == pm[i] + 1 && pm[i + 2] == pm[i] + 2;
            }
            T_CHECK(together);
            dfm_chol_free(c);
        }
        o.block_size = 4; /* 3 nv is not a multiple of 4 (nv = 156: it is; use 5) */
        o.block_size = 5;
        {
            dfm_chol *c = NULL;
            T_EQ_INT(dfm_chol_analyze(&e2, &o, &c), (3 * nv) % 5 ? DFM_ERR_INVALID_ARGUMENT : DFM_OK);
            dfm_chol_free(c);
        }
        free(blk);
        free(d);
        free(xd);
        dfm_csc_free(&e2);
    }
    free(b);
    free(x);
    free(x3);
    free(fixed);
    dfm_csc_free(&l);
    dfm_csc_free(&m);
    dfm_csc_free(&e);
    free(pos);
    free(idx);
}

static void test_bad_input(void)
{
    dfm_csc a = random_spd(20, 3.0, 5, 0.1), m;
    dfm_chol *c = NULL;
    float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[] = {0, 1, 2}, bad_idx[] = {0, 1, 3};
    int32_t saved;
    double x[20] = {0};
    T_EQ_INT(dfm_chol_analyze(NULL, NULL, &c), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_chol_analyze(&a, NULL, NULL), DFM_ERR_INVALID_ARGUMENT);
    /* an upper-triangle entry in a lower matrix */
    saved = a.row_index[a.col_start[5]];
    a.row_index[a.col_start[5]] = 2;
    T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_ERR_BAD_INDEX);
    a.row_index[a.col_start[5]] = 99;
    T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_ERR_BAD_INDEX);
    a.row_index[a.col_start[5]] = -1;
    T_EQ_INT(dfm_csc_validate(&a), DFM_ERR_BAD_INDEX);
    a.row_index[a.col_start[5]] = saved;
    T_EQ_INT(dfm_csc_validate(&a), DFM_OK);
    /* missing diagonal: structurally singular */
    {
        dfm_csc b2 = random_spd(20, 3.0, 5, 0.1);
        b2.row_index[b2.col_start[7]] = b2.col_start[8] - b2.col_start[7] > 1 ? b2.row_index[b2.col_start[7] + 1] : 19;
        T_EQ_INT(dfm_chol_analyze(&b2, NULL, &c), DFM_ERR_STRUCTURALLY_SINGULAR);
        T_CHECK(c == NULL);
        dfm_csc_free(&b2);
    }
    /* a general matrix is not accepted by the factorization */
    a.kind = DFM_CSC_GENERAL;
    T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_ERR_INVALID_ARGUMENT);
    a.kind = DFM_CSC_SYMMETRIC_LOWER;
    /* decreasing column starts */
    {
        size_t s = a.col_start[3];
        a.col_start[3] = a.col_start[4] + 1;
        T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_ERR_INVALID_ARGUMENT);
        a.col_start[3] = s;
    }
    /* NaN values */
    T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_OK);
    a.values[4] = INFINITY;
    T_EQ_INT(dfm_chol_factor(c, &a), DFM_ERR_BAD_VALUE);
    T_EQ_INT(dfm_csc_multiply(&a, x, x, 1), DFM_ERR_BAD_VALUE);
    a.values[4] = 0.25;
    T_EQ_INT(dfm_chol_solve(NULL, x, 1), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_chol_factor(NULL, &a), DFM_ERR_INVALID_ARGUMENT);
    dfm_chol_free(c);
    dfm_chol_free(NULL);
    dfm_constrained_free(NULL);
    dfm_csc_free(NULL);
    /* meshes */
    T_EQ_INT(dfm_mesh_laplacian(pos, 3, bad_idx, 1, DFM_LAPLACIAN_COTAN, NULL, &m), DFM_ERR_BAD_INDEX);
    T_CHECK(m.col_start == NULL);
    T_EQ_INT(dfm_mesh_laplacian(pos, 0, idx, 1, DFM_LAPLACIAN_COTAN, NULL, &m), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_mesh_laplacian(pos, 3, idx, 1, 7, NULL, &m), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_mesh_laplacian(NULL, 3, idx, 1, 0, NULL, &m), DFM_ERR_INVALID_ARGUMENT);
    pos[4] = NAN;
    T_EQ_INT(dfm_mesh_laplacian(pos, 3, idx, 1, DFM_LAPLACIAN_COTAN, NULL, &m), DFM_ERR_BAD_VALUE);
    pos[4] = 0;
    /* degenerate triangles give finite weights */
    {
        float flat[] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
        uint32_t dup[] = {0, 1, 2, 0, 0, 1};
        size_t p;
        int finite = 1;
        T_EQ_INT(dfm_mesh_laplacian(flat, 3, dup, 2, DFM_LAPLACIAN_COTAN, NULL, &m), DFM_OK);
        for (p = 0; p < m.col_start[3]; p++) finite &= isfinite(m.values[p]) != 0;
        T_CHECK(finite);
        dfm_csc_free(&m);
    }
    T_EQ_INT(dfm_normal_matrix(NULL, NULL, NULL, &m), DFM_ERR_INVALID_ARGUMENT);
    {
        double dg[20];
        size_t i;
        for (i = 0; i < 20; i++) dg[i] = i == 3 ? NAN : 1.0;
        T_EQ_INT(dfm_normal_matrix(&a, dg, NULL, &m), DFM_ERR_BAD_VALUE);
    }
    T_EQ_INT(dfm_block_expand(&a, 0, NULL, NULL, &m), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_csc_alloc(3, 4, 1, DFM_CSC_SYMMETRIC_LOWER, NULL, &m), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_csc_alloc((size_t)1 << 40, 4, 1, DFM_CSC_GENERAL, NULL, &m), DFM_ERR_TOO_LARGE);
    T_EQ_STR(dfm_result_string(DFM_ERR_NOT_POSITIVE_DEFINITE), "DFM_ERR_NOT_POSITIVE_DEFINITE");
    T_EQ_STR(dfm_result_string((dfm_result)99), "DFM_ERR_?");
    dfm_csc_free(&a);
}

/* Issue 21 point 2: finite input whose result overflows is DFM_ERR_NOT_FINITE, never DFM_OK with
   Inf or NaN in the output; a NaN/Inf right-hand side or vector is DFM_ERR_BAD_VALUE (and the
   solve leaves x as it was). Every case below returned DFM_OK with Inf before. */
static void test_not_finite(void)
{
    dfm_csc a = random_spd(20, 3.0, 7, 0.1), m, d;
    dfm_chol *c = NULL;
    dfm_constrained *k = NULL;
    unsigned char fixed[20] = {0};
    double x[20], y[20], b[20], fv[20];
    size_t i, p;
    int unchanged;
    /* a 1e200 entry squared by the normal matrix */
    a.values[a.col_start[4]] = 1e200;
    T_EQ_INT(dfm_normal_matrix(&a, NULL, NULL, &m), DFM_ERR_NOT_FINITE);
    T_CHECK(m.col_start == NULL && m.values == NULL); /* freed */
    a.values[a.col_start[4]] = 1e150; /* 1e300: still finite */
    T_EQ_INT(dfm_normal_matrix(&a, NULL, NULL, &m), DFM_OK);
    dfm_csc_free(&m);
    /* a finite diagonal that overflows the sum */
    {
        double dg[20];
        for (i = 0; i < 20; i++) dg[i] = 1.7e308;
        a.values[a.col_start[4]] = 1e154;
        T_EQ_INT(dfm_normal_matrix(&a, dg, NULL, &m), DFM_ERR_NOT_FINITE);
    }
    a.values[a.col_start[4]] = 10.0;
    /* the product overflows; a NaN vector is bad input */
    for (i = 0; i < 20; i++) x[i] = 1e308;
    T_EQ_INT(dfm_csc_multiply(&a, x, y, 1), DFM_ERR_NOT_FINITE);
    x[3] = NAN;
    T_EQ_INT(dfm_csc_multiply(&a, x, y, 1), DFM_ERR_BAD_VALUE);
    /* a tiny pivot: the diagonal 1e-300, b = 1e300 gives x = 1e600 */
    T_EQ_INT(dfm_csc_alloc(20, 20, 20, DFM_CSC_SYMMETRIC_LOWER, NULL, &d), DFM_OK);
    for (i = 0; i < 20; i++) {
        d.row_index[i] = (int32_t)i;
        d.values[i] = i == 5 ? 1e-300 : 2.0;
        d.col_start[i + 1] = i + 1;
    }
    T_EQ_INT(dfm_chol_analyze(&d, NULL, &c), DFM_OK);
    T_EQ_INT(dfm_chol_factor(c, &d), DFM_OK);
    for (i = 0; i < 20; i++) b[i] = 1e300;
    memcpy(x, b, sizeof x);
    T_EQ_INT(dfm_chol_solve(c, x, 1), DFM_ERR_NOT_FINITE);
    T_EQ_INT(dfm_chol_solve_refined(c, &d, b, x, 1, 0), DFM_ERR_NOT_FINITE);
    T_EQ_INT(dfm_chol_solve_refined(c, &d, b, x, 1, 3), DFM_ERR_NOT_FINITE);
    b[5] = 1e-10; /* x_5 = 1e290: finite */
    T_EQ_INT(dfm_chol_solve_refined(c, &d, b, x, 1, 3), DFM_OK);
    for (i = 0; i < 20; i++) x[i] = i == 9 ? INFINITY : 1.0;
    T_EQ_INT(dfm_chol_solve(c, x, 1), DFM_ERR_BAD_VALUE);
    for (i = 0, unchanged = 1; i < 20; i++) unchanged &= x[i] == (i == 9 ? INFINITY : 1.0);
    T_CHECK(unchanged);
    dfm_chol_free(c);
    /* constrained: finite fixed values whose coupling overflows the right-hand side */
    fixed[0] = fixed[1] = 1;
    T_EQ_INT(dfm_constrained_analyze(&a, fixed, NULL, &k), DFM_OK);
    T_EQ_INT(dfm_constrained_factor(k, &a), DFM_OK);
    for (i = 0; i < 20; i++) {
        b[i] = 1.0;
        fv[i] = 1.0;
    }
    T_EQ_INT(dfm_constrained_solve(k, b, fv, x, 1), DFM_OK);
    for (p = a.col_start[0]; p < a.col_start[2]; p++) /* the fixed columns' couplings to 1e300 */
        if ((size_t)a.row_index[p] > 1) a.values[p] = -1e300;
    T_EQ_INT(dfm_constrained_factor(k, &a), DFM_OK);
    fv[0] = fv[1] = 1e300;
    T_EQ_INT(dfm_constrained_solve(k, b, fv, x, 1), DFM_ERR_NOT_FINITE);
    fv[0] = NAN;
    T_EQ_INT(dfm_constrained_solve(k, b, fv, x, 1), DFM_ERR_BAD_VALUE);
    dfm_constrained_free(k);
    T_EQ_STR(dfm_result_string(DFM_ERR_NOT_FINITE), "DFM_ERR_NOT_FINITE");
    dfm_csc_free(&d);
    dfm_csc_free(&a);
}

/* every allocation failure is reported as OUT_OF_MEMORY and leaks nothing */
static int run_pipeline(const dfm_allocator *al, const float *pos, size_t nv, const uint32_t *idx, size_t nt)
{
    dfm_csc l, m;
    dfm_chol *c = NULL;
    dfm_constrained *k = NULL;
    dfm_chol_options o = dfm_chol_default_options();
    dfm_result r;
    double *dg = (double *)calloc(nv, sizeof(double)), *b = (double *)calloc(3 * nv, sizeof(double));
    double *x = (double *)malloc(3 * nv * sizeof(double)), *co = (double *)malloc(3 * nv * sizeof(double));
    unsigned char *fixed = every_kth(nv, 10);
    size_t i;
    memset(&l, 0, sizeof l);
    memset(&m, 0, sizeof m);
    for (i = 0; i < nv; i++) {
        dg[i] = fixed[i] ? 1.0 : 0.0;
        b[i] = 1.0;
    }
    o.allocator = al;
    r = dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, al, &l);
    if (r == DFM_OK) r = dfm_normal_matrix(&l, dg, al, &m);
    for (i = 0; i < 3 * nv; i++) co[i] = pos[i];
    if (r == DFM_OK) {
        dfm_chol *cn = NULL;
        o.coords = co;
        r = dfm_chol_analyze(&m, &o, &cn);
        o.coords = NULL;
        dfm_chol_free(cn);
    }
    if (r == DFM_OK) r = dfm_chol_analyze(&m, &o, &c);
    if (r == DFM_OK) r = dfm_chol_factor(c, &m);
    if (r == DFM_OK) {
        memcpy(x, b, 3 * nv * sizeof(double));
        r = dfm_chol_solve(c, x, 3);
    }
    if (r == DFM_OK) r = dfm_chol_solve_refined(c, &m, b, x, 3, 2);
    o.coords = co;
    if (r == DFM_OK) r = dfm_constrained_analyze(&m, fixed, &o, &k);
    o.coords = NULL;
    if (r == DFM_OK) r = dfm_constrained_factor(k, &m);
    if (r == DFM_OK) r = dfm_constrained_solve(k, b, b, x, 3);
    if (r == DFM_OK) {
        dfm_csc e;
        o.block_size = 3;
        r = dfm_block_expand(&m, 3, NULL, al, &e);
        if (r == DFM_OK) {
            dfm_chol *c3 = NULL;
            r = dfm_chol_analyze(&e, &o, &c3);
            dfm_chol_free(c3);
            dfm_csc_free(&e);
        }
    }
    dfm_constrained_free(k);
    dfm_chol_free(c);
    dfm_csc_free(&l);
    dfm_csc_free(&m);
    free(dg);
    free(b);
    free(x);
    free(co);
    free(fixed);
    return (int)r;
}

static void test_alloc_failures(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt;
    long k;
    int all_oom = 1, no_leaks = 1, finished = 0;
    grid_mesh(20, 15, &pos, &idx, &nv, &nt); /* 300 vertices: nested dissection splits */
    for (k = 0; k < 5000 && !finished; k++) {
        counting cnt = {0, 0, k};
        dfm_allocator al = {counting_alloc, counting_free, &cnt};
        int r = run_pipeline(&al, pos, nv, idx, nt);
        if (r == DFM_OK) finished = 1;
        else if (r != DFM_ERR_OUT_OF_MEMORY) all_oom = 0;
        if (cnt.allocs != cnt.frees) no_leaks = 0;
    }
    T_CHECK(finished);
    T_CHECK(all_oom);
    T_CHECK(no_leaks);
    T_CHECK_MSG(k > 20, "%ld allocation points", k);
    free(pos);
    free(idx);
}

static int cancel_after(void *user, float done)
{
    int *calls = (int *)user;
    (void)done;
    return ++*calls >= 2;
}

static void test_cancel(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt;
    dfm_csc l;
    dfm_chol *c = NULL;
    int calls = 0;
    counting cnt = {0, 0, -1};
    dfm_allocator al = {counting_alloc, counting_free, &cnt};
    dfm_chol_options o = dfm_chol_default_options();
    grid_mesh(60, 60, &pos, &idx, &nv, &nt);
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_UNIFORM, NULL, &l), DFM_OK);
    l.values[0] += 1.0;
    o.allocator = &al;
    o.progress = cancel_after;
    o.progress_user = &calls;
    T_EQ_INT(dfm_chol_analyze(&l, &o, &c), DFM_CANCELLED);
    T_CHECK(c == NULL);
    T_EQ_INT(cnt.allocs, cnt.frees);
    o.progress = NULL;
    T_EQ_INT(dfm_chol_analyze(&l, &o, &c), DFM_OK);
    c->progress = cancel_after;
    c->progress_user = &calls;
    calls = 0;
    T_EQ_INT(dfm_chol_factor(c, &l), DFM_CANCELLED);
    dfm_chol_free(c);
    T_EQ_INT(cnt.allocs, cnt.frees);
    dfm_csc_free(&l);
    free(pos);
    free(idx);
}

/* AMD quality: on a 2D grid Laplacian, fill within a sane factor of nested-dissection theory
   and much below the natural order's band */
/* ---- AMD's degrees against the quotient graph (issue 21 point 8) ----------------------------
   While on, every pivot and every degree update of AMD is audited from the quotient graph's lists
   alone (brute force, independent of AMD's w[] bookkeeping):
   - before a pivot: each live variable in a degree list is in the list of its degree, the lists
     hold exactly the live variables that are listed, and the pivot has the smallest degree;
   - after a step, for each variable v of the new element L_p (weights nv):
       ext(v)  = |(A_v u L_p u U_{e in E_v} L_e) \ v|, the exact external degree,
       d1(v)   = |A_v \ L_p \ v| + |L_p \ v| + sum_{e in E_v, e != p} |L_e \ L_p|   (ADD 1996 eq. 4.1),
       d2(v)   = the degree before the step + |L_p \ v|, rest(v) = n - eliminated - nv(v);
     degree(v) must equal max(0, min(d1, d2, rest)) exactly and be >= ext(v) (the bound). */
typedef struct amd_audit {
    int on;
    size_t cap;
    int32_t *prev;
    int64_t *mark, *inlp, stamp;
    long pivots, updates, bound_exact, list_bad, min_bad, formula_bad, bound_bad;
} amd_audit;
static amd_audit audit;

static int32_t audit_w(const dfm__amd *s, int32_t u) { return s->status[u] == DFM__VAR && s->nv[u] > 0 ? s->nv[u] : 0; }

static void amd_audit_pivot(const struct dfm__amd *s, int32_t p)
{
    int32_t n = s->n, d, v, listed = 0, walked = 0, dmin = -1;
    if (!audit.on) return;
    if (audit.cap < (size_t)n) {
        audit.cap = (size_t)n;
        audit.prev = (int32_t *)realloc(audit.prev, audit.cap * sizeof(int32_t));
        audit.mark = (int64_t *)realloc(audit.mark, audit.cap * sizeof(int64_t));
        audit.inlp = (int64_t *)realloc(audit.inlp, audit.cap * sizeof(int64_t));
        memset(audit.mark, 0, audit.cap * sizeof(int64_t));
        memset(audit.inlp, 0, audit.cap * sizeof(int64_t));
    }
    memcpy(audit.prev, s->degree, (size_t)n * sizeof(int32_t));
    audit.pivots++;
    for (v = 0; v < n; v++) listed += s->inlist[v] != 0;
    for (d = 0; d < n; d++)
        for (v = s->head[d]; v >= 0 && walked <= n; v = s->next[v]) {
            walked++;
            if (!s->inlist[v] || s->degree[v] != d || !audit_w(s, v)) audit.list_bad++;
            if (dmin < 0) dmin = d;
        }
    if (walked != listed) audit.list_bad++;
    if (s->degree[p] != dmin) audit.min_bad++;
}

static void amd_audit_step(const struct dfm__amd *s, int32_t p)
{
    int64_t q, r, t, lp = 0, st;
    if (!audit.on) return;
    st = ++audit.stamp;
    for (q = s->pe[p]; q < s->pe[p] + s->len[p]; q++)
        if (audit_w(s, s->iw[q])) {
            audit.inlp[s->iw[q]] = st;
            lp += audit_w(s, s->iw[q]);
        }
    for (q = s->pe[p]; q < s->pe[p] + s->len[p]; q++) {
        int32_t v = s->iw[q], nvv = audit_w(s, v);
        int64_t ext = 0, d1 = 0, d2, rest, want, mk;
        if (!nvv) continue;
        mk = ++audit.stamp;
        audit.mark[v] = mk;
        for (r = s->pe[v]; r < s->pe[v] + s->len[v]; r++) {
            int32_t e = s->iw[r];
            int elem = r < s->pe[v] + s->elen[v];
            int64_t a = elem ? s->pe[e] : r, b = elem ? s->pe[e] + s->len[e] : r + 1;
            if (elem && s->status[e] != DFM__ELEM) continue;
            for (t = a; t < b; t++) {
                int32_t u = s->iw[t], wu = audit_w(s, u);
                if (!wu || u == v) continue;
                if (audit.mark[u] != mk) { /* the union: each variable once */
                    audit.mark[u] = mk;
                    ext += wu;
                }
                if (audit.inlp[u] != st && (!elem || e != p)) d1 += wu; /* |A_v \ L_p|, |L_e \ L_p| */
            }
        }
        d1 += lp - nvv;
        d2 = (int64_t)audit.prev[v] + lp - nvv;
        rest = (int64_t)(s->n - s->nel) - nvv;
        want = d1 < d2 ? d1 : d2;
        if (rest < want) want = rest;
        if (want < 0) want = 0;
        audit.updates++;
        if (s->degree[v] != want) audit.formula_bad++;
        if (s->degree[v] < ext) audit.bound_bad++;
        audit.bound_exact += s->degree[v] == ext;
    }
}

/* AMD audited on generated meshes: grids with both diagonal patterns, a tube (periodic), their
   3x3-block expansions (supervariables of 3 from the start) and random sparse matrices with a
   wide range of degrees. Planted, one at a time: step 6's d = w + |L_p| without "- nv(v)"; the
   same in step 3's first visit of an element; step 6's min with d2 dropped; step 4's |A_v|
   counted unweighted (deg += 1); step 4's |L_e \ L_p| one too large. Each makes formula_bad
   nonzero here. Elsewhere the first two were caught only by the bunny's fill bound (and the
   dissection comparison), the fourth and fifth only by the factor digests, the third by nothing. */
static void test_amd_degrees(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt, k;
    long graphs = 0;
    memset(&audit, 0, sizeof audit);
    audit.on = 1;
    for (k = 0; k < 8; k++) {
        dfm_csc l, a, b;
        dfm_chol *c = NULL;
        size_t w = 6 + 5 * k, h = 5 + 3 * k;
        grid_mesh(w, h, &pos, &idx, &nv, &nt);
        if (k & 1) /* the other diagonal in every third quad */
            for (nt = 0; nt < 2 * (w - 1) * (h - 1); nt += 6) {
                uint32_t *f = idx + 3 * nt, a0 = f[0], b0 = f[1], c0 = f[2], d0 = f[4];
                if (f[2] == f[4]) continue;
                f[0] = a0, f[1] = b0, f[2] = d0, f[3] = a0, f[4] = d0, f[5] = c0;
            }
        nt = 2 * (w - 1) * (h - 1);
        T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_UNIFORM, NULL, &l), DFM_OK);
        T_EQ_INT(dfm_chol_analyze(&l, NULL, &c), DFM_OK);
        dfm_chol_free(c);
        T_EQ_INT(dfm_block_expand(&l, 3, NULL, NULL, &b), DFM_OK);
        T_EQ_INT(dfm_chol_analyze(&b, NULL, &c), DFM_OK);
        dfm_chol_free(c);
        a = random_spd(40 + 60 * k, 2.0 + (double)k, 100 + k, 1.0);
        T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_OK);
        dfm_chol_free(c);
        graphs += 3;
        dfm_csc_free(&l);
        dfm_csc_free(&b);
        dfm_csc_free(&a);
        free(pos);
        free(idx);
    }
    audit.on = 0;
    printf("AMD audit: %ld graphs, %ld pivots, %ld degree updates (%ld equal to the exact external degree)\n", graphs,
           audit.pivots, audit.updates, audit.bound_exact);
    T_CHECK(audit.pivots > 1000 && audit.updates > 1000);
    T_EQ_INT(audit.list_bad, 0);
    T_EQ_INT(audit.min_bad, 0);
    T_EQ_INT(audit.formula_bad, 0);
    T_EQ_INT(audit.bound_bad, 0);
    free(audit.prev);
    free(audit.mark);
    free(audit.inlp);
    memset(&audit, 0, sizeof audit);
}

static void test_amd_quality(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt;
    dfm_csc l;
    dfm_chol *c = NULL, *cn = NULL;
    dfm_chol_options o = dfm_chol_default_options();
    dfm_chol_info ia, in;
    grid_mesh(100, 100, &pos, &idx, &nv, &nt);
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_UNIFORM, NULL, &l), DFM_OK);
    l.values[0] += 1.0;
    T_EQ_INT(dfm_chol_analyze(&l, NULL, &c), DFM_OK);
    o.ordering = DFM_ORDER_NATURAL;
    T_EQ_INT(dfm_chol_analyze(&l, &o, &cn), DFM_OK);
    dfm_chol_get_info(c, &ia);
    dfm_chol_get_info(cn, &in);
    T_CHECK_MSG(ia.nnz_l * 3 < in.nnz_l, "amd %zu natural %zu", ia.nnz_l, in.nnz_l);
    T_CHECK_MSG(ia.nnz_l < 30 * nv, "amd nnz(L) %zu for n %zu", ia.nnz_l, nv);
    T_EQ_INT(dfm_chol_factor(c, &l), DFM_OK);
    dfm_chol_free(c);
    dfm_chol_free(cn);
    dfm_csc_free(&l);
    free(pos);
    free(idx);
}


/* nested dissection with vertex coordinates: correct solves, brute-force counts, never more fill
   than AMD alone, bad coordinates refused, deterministic */
static void test_nested_dissection(void)
{
    float *pos;
    uint32_t *idx;
    size_t nv, nt, i;
    dfm_csc l;
    double *co, *b, *x;
    dfm_chol_options o = dfm_chol_default_options();
    dfm_chol *c = NULL, *ca = NULL, *c2 = NULL;
    dfm_chol_info info, info_amd;
    unsigned char *fixed;
    int counts_ok = 1;
    /* small: brute-force counts under the dissection ordering */
    grid_mesh(21, 22, &pos, &idx, &nv, &nt);
    co = (double *)malloc(3 * nv * sizeof(double));
    for (i = 0; i < 3 * nv; i++) co[i] = pos[i];
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, NULL, &l), DFM_OK);
    fixed = every_kth(nv, 50);
    add_diagonal(&l, fixed, 1.0);
    o.coords = co;
    T_EQ_INT(dfm_chol_analyze(&l, &o, &c), DFM_OK);
    {
        size_t *bc = (size_t *)malloc(nv * sizeof(size_t));
        brute_counts(&l, dfm_chol_permutation(c), bc);
        for (i = 0; i < nv; i++) counts_ok &= bc[i] == dfm_chol_column_counts(c)[i];
        free(bc);
    }
    T_CHECK(counts_ok);
    dfm_chol_free(c);
    free(fixed);
    dfm_csc_free(&l);
    free(pos);
    free(idx);
    free(co);
    /* larger: fill and solve */
    grid_mesh(150, 140, &pos, &idx, &nv, &nt);
    co = (double *)malloc(3 * nv * sizeof(double));
    for (i = 0; i < 3 * nv; i++) co[i] = pos[i];
    T_EQ_INT(dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, NULL, &l), DFM_OK);
    fixed = every_kth(nv, 100);
    add_diagonal(&l, fixed, 1.0);
    o.coords = co;
    T_EQ_INT(dfm_chol_analyze(&l, &o, &c), DFM_OK);
    T_EQ_INT(dfm_chol_analyze(&l, NULL, &ca), DFM_OK);
    dfm_chol_get_info(c, &info);
    dfm_chol_get_info(ca, &info_amd);
    T_CHECK_MSG(info.nnz_l <= info_amd.nnz_l, "with coordinates %zu, AMD %zu", info.nnz_l, info_amd.nnz_l);
    /* the dissection ordering itself: a permutation, with fill close to AMD's on this grid */
    {
        dfm_allocator al = dfm__resolve_allocator(NULL);
        size_t *st;
        int32_t *adj, *pnd = (int32_t *)malloc(nv * sizeof(int32_t)), *pamd = (int32_t *)malloc(nv * sizeof(int32_t));
        unsigned char *seen = (unsigned char *)calloc(nv, 1);
        double fnd = 0, famd = 0;
        int is_perm = 1;
        T_EQ_INT(dfm__adjacency(&l, 1, &al, &st, &adj), DFM_OK);
        dfm__fill fill_nd, fill_amd;
        int32_t *cnd = (int32_t *)malloc(nv * sizeof(int32_t)), *camd = (int32_t *)malloc(nv * sizeof(int32_t));
        T_EQ_INT(dfm__nd_order((int32_t)nv, st, adj, co, &al, NULL, NULL, pnd, &fill_nd, cnd), DFM_OK);
        T_EQ_INT(dfm__amd_order((int32_t)nv, st, adj, NULL, &al, NULL, NULL, pamd, &fill_amd, camd), DFM_OK);
        for (i = 0; i < nv; i++) {
            if (pnd[i] < 0 || (size_t)pnd[i] >= nv || seen[pnd[i]]) is_perm = 0;
            else seen[pnd[i]] = 1;
        }
        T_CHECK(is_perm);
        dfm__graph_fill(nv, st, adj, pnd, &al, &fnd);
        dfm__graph_fill(nv, st, adj, pamd, &al, &famd);
        T_CHECK_MSG(famd == (double)info_amd.nnz_l, "graph fill %.0f vs symbolic %zu", famd, info_amd.nnz_l);
        T_CHECK_MSG(fnd < 1.3 * famd, "dissection %.0f AMD %.0f", fnd, famd);
        /* without dense rows the fill AMD counts as it eliminates is exact (the analysis picks
           an ordering by it), for plain and constrained minimum degree alike */
        T_CHECK(fill_amd.exact && fill_nd.exact);
        T_CHECK_MSG(fill_amd.lnz == famd, "AMD's count %.0f, symbolic %.0f", fill_amd.lnz, famd);
        T_CHECK_MSG(fill_nd.lnz == fnd, "constrained AMD's count %.0f, symbolic %.0f", fill_nd.lnz, fnd);
        /* and so is each column's count (the analysis takes them instead of counting again):
           the same as the row-subtree counts of the analysis given that ordering */
        {
            int pass;
            for (pass = 0; pass < 2; pass++) {
                dfm_chol *cg = NULL;
                dfm_chol_options og = dfm_chol_default_options();
                size_t bad = 0;
                og.ordering = DFM_ORDER_GIVEN;
                og.perm = pass ? pnd : pamd;
                T_EQ_INT(dfm_chol_analyze(&l, &og, &cg), DFM_OK);
                for (i = 0; cg && i < nv; i++)
                    bad += dfm_chol_column_counts(cg)[i] != (size_t)(pass ? cnd : camd)[dfm_chol_permutation(cg)[i]];
                T_CHECK_MSG(bad == 0, "%s: %zu column counts differ from the symbolic ones", pass ? "ND" : "AMD", bad);
                dfm_chol_free(cg);
            }
        }
        free(cnd);
        free(camd);
        free(st);
        free(adj);
        free(pnd);
        free(pamd);
        free(seen);
    }
    b = random_vector(3 * nv, 71);
    x = (double *)malloc(3 * nv * sizeof(double));
    T_EQ_INT(dfm_chol_factor(c, &l), DFM_OK);
    memcpy(x, b, 3 * nv * sizeof(double));
    T_EQ_INT(dfm_chol_solve(c, x, 3), DFM_OK);
    T_CHECK(residual(&l, x, b, 3) <= 1e-14);
    T_EQ_INT(dfm_chol_analyze(&l, &o, &c2), DFM_OK);
    T_CHECK(memcmp(dfm_chol_permutation(c), dfm_chol_permutation(c2), nv * sizeof(int32_t)) == 0);
    dfm_chol_free(c2);
    c2 = NULL;
    co[5] = NAN;
    T_EQ_INT(dfm_chol_analyze(&l, &o, &c2), DFM_ERR_BAD_VALUE);
    T_CHECK(c2 == NULL);
    dfm_chol_free(c);
    dfm_chol_free(ca);
    free(b);
    free(x);
    free(fixed);
    dfm_csc_free(&l);
    free(pos);
    free(idx);
    free(co);
}

/* the Stanford bunny (glmark2-data): cotangent Laplacian + 1% constraints and the bi-Laplacian,
   three right-hand sides, with and without coordinates, refactored with new weights */
static void test_bunny(void)
{
    const char *path = "/usr/share/glmark2/models/bunny.obj";
    mio_mesh mesh;
    mio_error merr;
    size_t nv, i, sys;
    FILE *f = fopen(path, "rb");
    if (!f) {
        T_SKIP_N(18, "bunny checks", "/usr/share/glmark2/models/bunny.obj missing: apt-get install glmark2-data");
        return;
    }
    fclose(f);
    T_EQ_INT(mio_read_file(path, NULL, &mesh, &merr), MIO_OK);
    nv = mesh.vertex_count;
    for (sys = 0; sys < 2; sys++) {
        dfm_csc l, a;
        double *dg = (double *)calloc(nv, sizeof(double)), *b = random_vector(3 * nv, 90 + sys);
        double *x = (double *)malloc(3 * nv * sizeof(double)), *co = (double *)malloc(3 * nv * sizeof(double)), r;
        dfm_chol_options o = dfm_chol_default_options();
        dfm_chol *c = NULL;
        dfm_chol_info info;
        for (i = 0; i < nv; i += 100) dg[i] = 1.0;
        for (i = 0; i < 3 * nv; i++) co[i] = mesh.positions[i];
        T_EQ_INT(dfm_mesh_laplacian(mesh.positions, nv, mesh.indices, mesh.triangle_count, DFM_LAPLACIAN_COTAN, NULL, &l), DFM_OK);
        if (sys == 0) {
            unsigned char *fx = every_kth(nv, 100);
            add_diagonal(&l, fx, 1.0);
            free(fx);
            a = l;
            memset(&l, 0, sizeof l);
        } else {
            T_EQ_INT(dfm_normal_matrix(&l, dg, NULL, &a), DFM_OK);
        }
        r = solve_residual(&a, b, 3, x, NULL);
        T_CHECK_MSG(r >= 0 && r <= 1e-14, "bunny system %zu residual %.3g", sys, r);
        o.coords = co;
        r = solve_residual(&a, b, 3, x, &o);
        T_CHECK_MSG(r >= 0 && r <= 1e-14, "bunny system %zu residual with coordinates %.3g", sys, r);
        T_EQ_INT(dfm_chol_analyze(&a, NULL, &c), DFM_OK);
        dfm_chol_get_info(c, &info);
        /* AMD's fill on these systems, as CHOLMOD's AMD reports it (1363788 and 4628409) */
        T_CHECK_MSG(info.nnz_l < (sys == 0 ? 1400000u : 4750000u), "nnz(L) %zu", info.nnz_l);
        /* new constraint weights: refactor without a new analysis */
        for (i = 0; i < nv; i += 100) a.values[a.col_start[i]] += 9.0; /* the diagonal comes first */
        T_EQ_INT(dfm_chol_factor(c, &a), DFM_OK);
        memcpy(x, b, 3 * nv * sizeof(double));
        T_EQ_INT(dfm_chol_solve(c, x, 3), DFM_OK);
        r = residual(&a, x, b, 3);
        T_CHECK_MSG(r <= 1e-14, "bunny refactor residual %.3g", r);
        dfm_chol_free(c);
        dfm_csc_free(&l);
        dfm_csc_free(&a);
        free(dg);
        free(b);
        free(x);
        free(co);
    }
    mio_free_mesh(&mesh);
}

/* ---- dense kernels: every tile path gives the reference's bits ----------------------------------
   The factor's bits must not depend on which tiles run (AVX-512, AVX, two-lane, plain C, edge
   tiles): dfm__gemm and dfm__trsm_rows are compared bit for bit with a one-entry-at-a-time
   reference that spells out the order of operations the header documents, over shapes that
   exercise every tile width and remainder. */
static void ref_gemm(size_t m, size_t k, size_t p, const double *A, size_t lda, const double *B, size_t ldb, double *C,
                     size_t ldc, int assign)
{
    size_t i, j, t, k4 = k & ~(size_t)3;
    for (j = 0; j < k; j++)
        for (i = 0; i < m; i++) {
            double *c = C + i + j * ldc;
            if (j < k4) { /* 4-column tiles: the products summed in order, then subtracted */
                double sum = 0.0;
                for (t = 0; t < p; t++) sum += A[i + t * lda] * B[j + t * ldb];
                *c = assign ? -sum : *c - sum;
            } else { /* the last k % 4 columns: each product subtracted in turn */
                if (assign) *c = 0.0;
                for (t = 0; t < p; t++) *c -= A[i + t * lda] * B[j + t * ldb];
            }
        }
}

/* the analysis's row sort equals qsort on distinct keys, sizes 0 .. 600, shuffled and sorted-run
   inputs (the supernode rows are a union of sorted lists) */
static void test_sort_rows(void)
{
    size_t n, i, bad = 0;
    int32_t *a = (int32_t *)malloc(600 * sizeof(int32_t)), *b = (int32_t *)malloc(600 * sizeof(int32_t));
    uint64_t h = 12345;
    for (n = 0; n <= 600; n += (n < 40 ? 1 : 37)) {
        int runs;
        for (runs = 0; runs < 2; runs++) {
            for (i = 0; i < n; i++) a[i] = (int32_t)(3 * i + 7);
            for (i = n; i > 1; i--) { /* Fisher-Yates, or 4 sorted runs interleaved by blocks */
                size_t k;
                int32_t t;
                h = h * 6364136223846793005ull + 1442695040888963407ull;
                k = runs ? (i - 1) - (i - 1) % 4 : (size_t)(h >> 33) % i;
                t = a[i - 1];
                a[i - 1] = a[k];
                a[k] = t;
            }
            memcpy(b, a, n * sizeof(int32_t));
            dfm__sort_rows(a, n);
            qsort(b, n, sizeof(int32_t), dfm__cmp_i32);
            bad += n > 0 && memcmp(a, b, n * sizeof(int32_t)) != 0;
        }
    }
    T_CHECK_MSG(bad == 0, "%zu inputs sorted differently from qsort", bad);
    free(a);
    free(b);
}

static void test_dense_kernel_bits(void)
{
    static const size_t ms[] = {1, 3, 4, 7, 8, 9, 15, 16, 17, 24, 31, 33, 40, 64, 70};
    static const size_t ks[] = {1, 3, 4, 5, 8, 11, 16, 36};
    static const size_t ps[] = {0, 1, 2, 5, 17, 48};
    size_t a, b, c, i, j, mism = 0, cases = 0, tmism = 0;
    const size_t N = 128 * 128;
    double *A = random_vector(N, 301), *B = random_vector(N, 302), *C0 = random_vector(N, 303);
    double *C1 = (double *)malloc(N * sizeof(double)), *C2 = (double *)malloc(N * sizeof(double));
    double *ws = (double *)malloc((dfm__gemm_ws(64) + 1) * sizeof(double));
    int packed;
    /* without the workspace, and with it (packed tiles where the shape has the reuse) */
    for (packed = 0; packed < 2; packed++)
    for (a = 0; a < sizeof ms / sizeof *ms; a++)
        for (b = 0; b < sizeof ks / sizeof *ks; b++)
            for (c = 0; c < sizeof ps / sizeof *ps; c++) {
                int assign;
                for (assign = 0; assign < 2; assign++) {
                    memcpy(C1, C0, N * sizeof(double));
                    memcpy(C2, C0, N * sizeof(double));
                    dfm__gemm(ms[a], ks[b], ps[c], A + 1, 75, B + 2, 57, C1 + 3, 80, assign, packed ? ws : NULL);
                    ref_gemm(ms[a], ks[b], ps[c], A + 1, 75, B + 2, 57, C2 + 3, 80, assign);
                    if (assign) /* only row >= column is the product's: the rest is copied */
                        for (i = 0; i < ms[a]; i++)
                            for (j = i + 1; j < ks[b]; j++) C1[3 + i + j * 80] = C2[3 + i + j * 80];
                    mism += memcmp(C1, C2, N * sizeof(double)) != 0;
                    cases++;
                }
            }
    T_CHECK_MSG(mism == 0, "%zu of %zu gemm shapes differ from the reference's bits", mism, cases);
    /* the triangular solve by row tiles against the column order, for 1..40 rows and 1..9 columns;
       D's diagonal is kept away from zero */
    for (a = 1; a <= 40; a++)
        for (b = 1; b <= 9; b++) {
            size_t r, q, t;
            double *D = C1, *X = C2, *Y = A + 2048;
            for (i = 0; i < N; i++) D[i] = B[i];
            for (q = 0; q < b; q++) D[q + q * 64] = 2.0 + B[q];
            for (i = 0; i < 64 * 16; i++) X[i] = Y[i] = C0[i];
            dfm__trsm_rows(a, b, D, X, 64);
            for (r = 0; r < a; r++)
                for (q = 0; q < b; q++) {
                    for (t = 0; t < q; t++) Y[r + q * 64] -= Y[r + t * 64] * D[q + t * 64];
                    Y[r + q * 64] *= 1.0 / D[q + q * 64];
                }
            tmism += memcmp(X, Y, 64 * 16 * sizeof(double)) != 0;
        }
    T_CHECK_MSG(tmism == 0, "%zu of 360 row-tile solves differ from the column order's bits", tmism);
    free(A);
    free(B);
    free(C0);
    free(C1);
    free(C2);
    free(ws);
}

/* ---- digests (issue 16: "digests first") ---------------------------------------------------------
   FNV-1a 64 over the bits of what dfm_chol_factor leaves in the factor object: the permutation,
   the column counts, the supernode partition, each supernode's rows and every value of L. The
   expected figures were recorded on the code before dfm_chol_analyze was split into its named
   steps (commit 7ca88e6); a restructuring that keeps them keeps the factor bit for bit. A change
   of behaviour must update them in the same commit and say why. */
static uint64_t fnv1a(uint64_t h, const void *data, size_t bytes)
{
    const unsigned char *c = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < bytes; i++) h = (h ^ c[i]) * 1099511628211ull;
    return h;
}

static uint64_t factor_digest(const dfm_chol *c)
{
    uint64_t h = 1469598103934665603ull;
    size_t n = c->n, ns = c->nsuper;
    h = fnv1a(h, &n, sizeof n);
    h = fnv1a(h, &ns, sizeof ns);
    h = fnv1a(h, c->perm, n * sizeof(int32_t));
    h = fnv1a(h, c->colcount, n * sizeof(size_t));
    h = fnv1a(h, c->sup_first, (ns + 1) * sizeof(int32_t));
    h = fnv1a(h, c->sup_rowptr, (ns + 1) * sizeof(size_t));
    h = fnv1a(h, c->sup_valptr, (ns + 1) * sizeof(size_t));
    h = fnv1a(h, c->rows, c->sup_rowptr[ns] * sizeof(int32_t));
    h = fnv1a(h, c->values, c->sup_valptr[ns] * sizeof(double));
    return h;
}

static uint64_t digest_of(const dfm_csc *a, const dfm_chol_options *o)
{
    dfm_chol *c = NULL;
    uint64_t h = 0;
    if (dfm_chol_analyze(a, o, &c) == DFM_OK && dfm_chol_factor(c, a) == DFM_OK) h = factor_digest(c);
    dfm_chol_free(c);
    return h;
}

/* the bits of dfm_chol_solve's output for nrhs hashed right-hand sides (3: the x, y, z path) */
static uint64_t solve_digest(const dfm_csc *a, size_t nrhs)
{
    dfm_chol *c = NULL;
    uint64_t h = 0;
    double *x = random_vector(a->n_cols * nrhs, 91);
    if (dfm_chol_analyze(a, NULL, &c) == DFM_OK && dfm_chol_factor(c, a) == DFM_OK &&
        dfm_chol_solve(c, x, nrhs) == DFM_OK)
        h = fnv1a(1469598103934665603ull, x, a->n_cols * nrhs * sizeof(double));
    dfm_chol_free(c);
    free(x);
    return h;
}

static void test_factor_digests(void)
{
    /* recorded at 7ca88e6 (see above); the same with gcc and clang, -O1 and -O2, and with
       DFM_NO_VECTOR_EXTENSIONS */
    static const uint64_t expect[5] = {0xa917f7a31f7d6327ull, 0xc6781e36ba21c6dcull, 0x23e6f27f24450ed4ull,
                                       0x87e4e3bfc27f1049ull, 0xcdba1408c543f30eull};
    uint64_t got[5];
    float *pos;
    uint32_t *idx;
    size_t nv, nt, i;
    dfm_csc lap, bil, blk, rnd;
    dfm_chol_options o = dfm_chol_default_options();
    double *dg, *co;
    unsigned char *fixed;
    grid_mesh(40, 37, &pos, &idx, &nv, &nt);
    fixed = every_kth(nv, 50);
    dg = (double *)calloc(nv, sizeof(double));
    co = (double *)malloc(3 * nv * sizeof(double));
    for (i = 0; i < nv; i++) dg[i] = fixed[i] ? 1.0 : 0.0;
    for (i = 0; i < 3 * nv; i++) co[i] = pos[i];
    dfm_mesh_laplacian(pos, nv, idx, nt, DFM_LAPLACIAN_COTAN, NULL, &lap);
    dfm_normal_matrix(&lap, dg, NULL, &bil); /* the bi-Laplacian of Laplacian editing */
    add_diagonal(&lap, fixed, 1.0);
    dfm_block_expand(&bil, 3, NULL, NULL, &blk);
    rnd = random_spd(700, 6.0, 77, 0.5);
    got[0] = digest_of(&lap, &o);  /* grid cotangent Laplacian, AMD */
    got[1] = digest_of(&bil, &o);  /* its normal matrix, AMD */
    {
        /* the same under the nested dissection ordering (given: on this small grid AMD's fill is
           below the analysis's threshold for trying dissection; before that threshold existed
           dissection won here, and this digest is the one recorded then) */
        dfm_allocator al = dfm__resolve_allocator(NULL);
        size_t *st = NULL;
        int32_t *adj = NULL, *pnd = (int32_t *)malloc(nv * sizeof(int32_t));
        dfm__fill fill;
        T_EQ_INT(dfm__adjacency(&bil, 1, &al, &st, &adj), DFM_OK);
        T_EQ_INT(dfm__nd_order((int32_t)nv, st, adj, co, &al, NULL, NULL, pnd, &fill, NULL), DFM_OK);
        o.ordering = DFM_ORDER_GIVEN;
        o.perm = pnd;
        got[2] = digest_of(&bil, &o);
        o = dfm_chol_default_options();
        o.coords = co;
        T_CHECK(digest_of(&bil, &o) == got[1]); /* with coordinates: AMD alone, as CHOLMOD would */
        o.coords = NULL;
        free(st);
        free(adj);
        free(pnd);
    }
    o.block_size = 3;
    got[3] = digest_of(&blk, &o);  /* 3x3-block expansion, vertex-graph ordering */
    o = dfm_chol_default_options();
    got[4] = digest_of(&rnd, &o);  /* random SPD matrix */
    for (i = 0; i < 5; i++) {
        printf("DIGEST dfm_chol_factor case=%d fnv1a=%016llx\n", (int)i, (unsigned long long)got[i]);
        T_CHECK_MSG(got[i] == expect[i], "case %d digest %016llx, recorded %016llx", (int)i,
                    (unsigned long long)got[i], (unsigned long long)expect[i]);
    }
    /* the solves (recorded at c7fa4cb, before the solve was split into steps; the vector paths
       SSE2 / AVX give these bits, the plain C build's solve differs in the last bits by design) */
    {
        static const uint64_t expect_solve[3] = {0xa6bb74ecc70ef25bull, 0xa04a6170e6a17ab4ull, 0x43d503b2e31ae4d8ull};
        uint64_t s3 = solve_digest(&bil, 3), s1 = solve_digest(&bil, 1), s5 = solve_digest(&rnd, 5);
        printf("DIGEST dfm_chol_solve nrhs=3 %016llx nrhs=1 %016llx nrhs=5 %016llx\n", (unsigned long long)s3,
               (unsigned long long)s1, (unsigned long long)s5);
#if (defined(__GNUC__) || defined(__clang__)) && !defined(DFM_NO_VECTOR_EXTENSIONS)
        T_CHECK(s3 == expect_solve[0]);
        T_CHECK(s1 == expect_solve[1]);
        T_CHECK(s5 == expect_solve[2]);
#else
        T_SKIP_N(3, "solve digests", "recorded for the vector build");
#endif
    }
    free(pos);
    free(idx);
    free(fixed);
    free(dg);
    free(co);
    dfm_csc_free(&lap);
    dfm_csc_free(&bil);
    dfm_csc_free(&blk);
    dfm_csc_free(&rnd);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    (void)sanitize_mode;
    if (argc > 1 && strcmp(argv[1], "--digests") == 0) { /* only those (tests/fp_contract.sh) */
        test_factor_digests();
        return T_END();
    }
    test_laplacian_values();
    test_random_vs_dense();
    test_orderings();
    test_not_spd();
    test_permutation_invariance();
    test_normal_matrix();
    test_mesh_systems();
    test_refactor_multi_rhs();
    test_constraints();
    test_blocks();
    test_bad_input();
    test_not_finite();
    test_alloc_failures();
    test_cancel();
    test_amd_quality();
    test_amd_degrees();
    test_nested_dissection();
    test_bunny();
    test_sort_rows();
    test_dense_kernel_bits();
    test_factor_digests();
    return T_END();
}
