/* fuzz_deform.c - fuzz target for deform.h: CSC building and checks, normal matrices, block
   expansion, analysis (AMD, natural, given, blocks, nested dissection), factorization, solves
   (plain, refined, constrained), mesh Laplacians, deformation setup and solve, ROI and pose helpers.
   libFuzzer: clang -g -O1 -I. -Itests -fsanitize=fuzzer,address,undefined tests/fuzz_deform.c -o fuzz_deform -lm
   plain:     gcc -std=c99 -g -O1 -I. -Itests tests/fuzz_deform.c tests/fuzz_main.c -o fuzz_deform -lm
              && ./fuzz_deform tests/fuzz/corpus/deform
   Byte 0 picks the entry point (bits 0-1) and whether numbers are raw 8-byte doubles (bit 7: any
   bits, NaN, Inf, 1e308, subnormals) or small values (else); byte 1 the allocation to fail (low
   nibble, 0 = none) and the progress call that cancels (high nibble, 0 = never). Every call must
   return DFM_OK with a sound result or a named code with nothing held: on DFM_OK the outputs are
   finite, a factor solves its matrix (relative residual bounded), a constrained solve keeps the
   fixed values bit for bit, a deformation puts every known vertex exactly on its target and the
   ROI masks stay masks. Allocations are limited to 64 MB in all. A broken rule calls abort().

   The first part (up to FZ_HELPERS_ONLY) is the byte reader and failing allocator that the other
   fuzz targets of this series (texel, relief, dispmesh) include. */
#ifndef FUZZ_HELPERS_C
#define FUZZ_HELPERS_C
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* the helpers a target does not call draw no warning */
#if defined(__GNUC__) || defined(__clang__)
#define FZ_UNUSED __attribute__((unused))
#else
#define FZ_UNUSED
#endif

/* the input: bytes read front to back, zero when used up; raw: numbers as their bit patterns */
typedef struct fz_in { const uint8_t *p; size_t n; int raw; } fz_in;

static FZ_UNUSED unsigned fz_u8(fz_in *in)
{
    unsigned b;
    if (!in->n) return 0;
    b = *in->p++;
    in->n--;
    return b;
}

/* a raw double, or (b - 128) / 16 */
static FZ_UNUSED double fz_f64(fz_in *in)
{
    double d;
    if (in->raw && in->n >= 8) {
        memcpy(&d, in->p, 8);
        in->p += 8;
        in->n -= 8;
        return d;
    }
    return ((double)fz_u8(in) - 128.0) / 16.0;
}

/* a raw float, or (b - 128) / 16 */
static FZ_UNUSED float fz_f32(fz_in *in)
{
    float f;
    if (in->raw && in->n >= 4) {
        memcpy(&f, in->p, 4);
        in->p += 4;
        in->n -= 4;
        return f;
    }
    return ((float)fz_u8(in) - 128.0f) / 16.0f;
}

/* The allocator under test: fails its fail_at-th call (0 = none) and whatever would take the
   blocks held above 64 MB; counts what is live so that a leak is caught at the end. */
typedef struct fz_heap { size_t bytes; long live, calls, fail_at; } fz_heap;

static FZ_UNUSED void *fz_heap_alloc(void *user, size_t n)
{
    fz_heap *h = (fz_heap *)user;
    size_t *p;
    h->calls++;
    if (h->calls == h->fail_at || n > ((size_t)64 << 20) - h->bytes) return NULL;
    p = (size_t *)malloc(n + 2 * sizeof(size_t));
    if (!p) return NULL;
    p[0] = n;
    h->bytes += n;
    h->live++;
    return p + 2;
}

static FZ_UNUSED void fz_heap_free(void *user, void *q)
{
    fz_heap *h = (fz_heap *)user;
    size_t *p;
    if (!q) return;
    p = (size_t *)q - 2;
    h->bytes -= p[0];
    h->live--;
    free(p);
}

/* points a library's allocator struct (alloc, free, user) at the heap */
#define FZ_HEAP_ALLOCATOR(a, h) ((a).alloc = fz_heap_alloc, (a).free = fz_heap_free, (a).user = (h))

/* progress: done must stay in [0, 1]; the cancel_at-th call (0 = never) cancels */
typedef struct fz_cancel { long calls, cancel_at; float last; } fz_cancel;

static FZ_UNUSED int fz_progress(void *user, float done)
{
    fz_cancel *c = (fz_cancel *)user;
    if (!(done >= 0.0f && done <= 1.0f)) abort();
    c->last = done;
    return ++c->calls == c->cancel_at;
}

static FZ_UNUSED void fz_check(int ok)
{
    if (!ok) abort();
}

static FZ_UNUSED int fz_all_finite_d(const double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

static FZ_UNUSED int fz_all_finite_f(const float *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* Reads the two header bytes: returns the op byte; sets raw, the failing allocation, the cancel */
static FZ_UNUSED unsigned fz_begin(fz_in *in, const uint8_t *data, size_t size, fz_heap *h, fz_cancel *c)
{
    unsigned op, k;
    in->p = data;
    in->n = size;
    in->raw = 0;
    op = fz_u8(in);
    k = fz_u8(in);
    in->raw = (op & 0x80) != 0;
    memset(h, 0, sizeof *h);
    memset(c, 0, sizeof *c);
    h->fail_at = (long)(k & 15);
    c->cancel_at = (long)(k >> 4);
    return op;
}

/* A small triangle mesh from the bytes: nv <= max_v vertices, nt <= max_t triangles, indices
   mostly in range (some up to nv + 1, out of range); positions as float or double. */
static FZ_UNUSED void fz_mesh(fz_in *in, size_t max_v, size_t max_t, float *fpos, double *dpos, uint32_t *idx, size_t *nv,
                    size_t *nt)
{
    size_t i;
    *nv = fz_u8(in) % (max_v + 1);
    *nt = fz_u8(in) % (max_t + 1);
    for (i = 0; i < 3 * *nv; i++) {
        double v = fz_f64(in);
        if (fpos) fpos[i] = (float)v;
        if (dpos) dpos[i] = v;
    }
    for (i = 0; i < 3 * *nt; i++) idx[i] = (uint32_t)(fz_u8(in) % (*nv + 2));
}
#endif /* FUZZ_HELPERS_C */

#ifndef FZ_HELPERS_ONLY
#define DFM_IMPLEMENTATION
#include "deform.h"

#define FZ_N 24 /* matrix size and mesh vertices at most */
#define FZ_T 32 /* triangles at most */

static int fz_known(dfm_result r) { return strcmp(dfm_result_string(r), "DFM_ERR_?") != 0; }

/* An n x n (or n x m) matrix from triplets in the bytes, through dfm_csc_alloc: rows sorted or
   not, duplicates, upper entries in a lower matrix, rows out of range are all possible. *dominant
   is set when the decoder made it symmetric, in range and strictly diagonally dominant with a
   positive diagonal (so SPD: its factor must say DFM_OK unless something overflows). */
static dfm_result fz_matrix(fz_in *in, const dfm_allocator *al, int kind, dfm_csc *m, int *dominant)
{
    size_t nr = 1 + fz_u8(in) % FZ_N, nc = kind == DFM_CSC_SYMMETRIC_LOWER ? nr : 1 + fz_u8(in) % FZ_N;
    size_t per = fz_u8(in) % 5, j, k, w = 0;
    unsigned flags = fz_u8(in);
    dfm_result r = dfm_csc_alloc(nr, nc, nc * (per + 1), kind, al, m);
    if (r != DFM_OK) return r;
    for (j = 0; j < nc; j++) {
        if (kind == DFM_CSC_SYMMETRIC_LOWER && !(flags & 1 && j == nc / 2)) { /* diagonal, dominant */
            m->row_index[w] = (int32_t)j;
            m->values[w++] = (flags & 2) ? fz_f64(in) : 4.0 + fabs(fz_f64(in)) * (double)per;
        }
        for (k = 0; k < per; k++) {
            unsigned b = fz_u8(in);
            size_t i = kind == DFM_CSC_SYMMETRIC_LOWER && !(flags & 4) ? j + b % (nr - j) : b % (nr + 1);
            m->row_index[w] = (int32_t)(i == nr && (flags & 8) ? -1 : (int32_t)i); /* maybe out of range */
            m->values[w++] = fz_f64(in) / (double)(per + 1);
        }
        m->col_start[j + 1] = w;
    }
    *dominant = kind == DFM_CSC_SYMMETRIC_LOWER && !(flags & 15);
    if (*dominant) {
        double off[FZ_N] = {0};
        size_t p;
        for (j = 0; j < nc; j++)
            for (p = m->col_start[j]; p < m->col_start[j + 1]; p++)
                if ((size_t)m->row_index[p] != j) {
                    off[j] += fabs(m->values[p]);
                    off[m->row_index[p]] += fabs(m->values[p]);
                }
        for (j = 0; j < nc; j++) /* the column's first entry is its diagonal; duplicates of it zeroed */
            for (p = m->col_start[j]; p < m->col_start[j + 1]; p++)
                if ((size_t)m->row_index[p] == j) m->values[p] = p == m->col_start[j] ? 1.0 + 2.0 * off[j] : 0.0;
        for (j = 0; j < nc; j++) *dominant &= isfinite(m->values[m->col_start[j]]) != 0;
    }
    return DFM_OK;
}

/* Cholesky is backward stable on an SPD matrix: |b - A x|inf <= c n^2 eps (|A|inf |x|inf + |b|inf)
   (Higham, Accuracy and Stability, thm 10.4 with | |L| |L^T| | <= n |A|); c = 8 here */
static void fz_residual(const dfm_csc *a, const double *x, const double *b)
{
    double y[FZ_N * 3], an = 0.0, xn = 0.0, bn = 0.0, rn = 0.0, row[FZ_N] = {0};
    size_t n = a->n_cols, j, p, i;
    if (dfm_csc_multiply(a, x, y, 1) != DFM_OK) return; /* the product may overflow: no bound then */
    for (j = 0; j < n; j++)
        for (p = a->col_start[j]; p < a->col_start[j + 1]; p++) {
            row[a->row_index[p]] += fabs(a->values[p]);
            if ((size_t)a->row_index[p] != j) row[j] += fabs(a->values[p]);
        }
    for (i = 0; i < n; i++) {
        an = fmax(an, row[i]);
        xn = fmax(xn, fabs(x[i]));
        bn = fmax(bn, fabs(b[i]));
        rn = fmax(rn, fabs(b[i] - y[i]));
    }
    if (isfinite(an * xn + bn)) fz_check(rn <= 8.0 * (double)(n * n) * 2.2e-16 * (an * xn + bn) + 1e-300);
}

static void fz_chol(fz_in *in, const dfm_allocator *al, fz_cancel *cc)
{
    dfm_csc a, g, nm, ex;
    dfm_chol_options o = dfm_chol_default_options();
    dfm_chol *c = NULL;
    dfm_constrained *k = NULL;
    int32_t perm[FZ_N];
    double coords[3 * FZ_N], x[3 * FZ_N], b[3 * FZ_N], fv[3 * FZ_N], diag[FZ_N];
    unsigned char fixed[FZ_N];
    unsigned f;
    size_t n, i, nrhs, bs;
    int dominant = 0;
    dfm_result r;
    memset(&a, 0, sizeof a);
    memset(&g, 0, sizeof g);
    memset(&nm, 0, sizeof nm);
    memset(&ex, 0, sizeof ex);
    f = fz_u8(in);
    /* a general matrix: validate, multiply, its normal matrix (the factor's input below) */
    if (f & 1) {
        r = fz_matrix(in, al, DFM_CSC_GENERAL, &g, &dominant);
        dominant = 0;
        fz_check(fz_known(r));
        if (r != DFM_OK) return;
        for (i = 0; i < g.n_cols; i++) diag[i] = (f & 2) ? fz_f64(in) : 1.0;
        r = dfm_normal_matrix(&g, diag, al, &a);
        fz_check(fz_known(r));
        if (r == DFM_OK) fz_check(dfm_csc_validate(&a) == DFM_OK);
        else fz_check(a.col_start == NULL && a.values == NULL);
        dfm_csc_free(&g);
        if (r != DFM_OK) return;
    } else {
        r = fz_matrix(in, al, DFM_CSC_SYMMETRIC_LOWER, &a, &dominant);
        fz_check(fz_known(r));
        if (r != DFM_OK) return;
    }
    n = a.n_cols;
    /* block expansion (value times identity, or blocks from the bytes) */
    bs = 1 + fz_u8(in) % 3;
    if (f & 4) {
        double blocks[FZ_N * 5 * 9];
        size_t nb = a.col_start[n] * bs * bs;
        int use = nb <= sizeof blocks / sizeof blocks[0];
        for (i = 0; use && i < nb; i++) blocks[i] = fz_f64(in);
        r = dfm_block_expand(&a, bs, (f & 8) && use ? blocks : NULL, al, &ex);
        fz_check(fz_known(r));
        if (r == DFM_OK) fz_check(ex.n_cols == n * bs && dfm_csc_validate(&ex) == DFM_OK);
        dfm_csc_free(&ex);
    }
    /* analysis options */
    o.ordering = (int)(fz_u8(in) % 4); /* 3: invalid */
    for (i = 0; i < n; i++) perm[i] = (int32_t)i;
    for (i = n; i > 1; i--) { /* a shuffle, sometimes broken */
        size_t j = fz_u8(in) % i;
        int32_t t = perm[i - 1];
        perm[i - 1] = perm[j];
        perm[j] = t;
    }
    if (f & 16) perm[0] = perm[n - 1];
    o.perm = (f & 32) ? NULL : perm;
    o.block_size = fz_u8(in) % 4;
    for (i = 0; i < 3 * n; i++) coords[i] = fz_f64(in);
    o.coords = (f & 64) ? coords : NULL;
    o.allocator = al;
    o.progress = (f & 128) ? fz_progress : NULL;
    o.progress_user = cc;
    r = dfm_chol_analyze(&a, &o, &c);
    fz_check(fz_known(r));
    if (r == DFM_OK) {
        dfm_chol_info info;
        const int32_t *pm = dfm_chol_permutation(c);
        unsigned char seen[FZ_N] = {0};
        for (i = 0; i < n; i++) {
            fz_check(pm[i] >= 0 && (size_t)pm[i] < n && !seen[pm[i]]);
            seen[pm[i]] = 1;
        }
        r = dfm_chol_factor(c, &a);
        fz_check(fz_known(r));
        if (dominant && !cc->cancel_at && !((fz_heap *)al->user)->fail_at) fz_check(r == DFM_OK);
        dfm_chol_get_info(c, &info);
        fz_check(info.n == n && info.nnz_l >= n);
        if (r == DFM_OK) {
            nrhs = 1 + fz_u8(in) % 3;
            for (i = 0; i < n * nrhs; i++) b[i] = fz_f64(in);
            memcpy(x, b, n * nrhs * sizeof(double));
            r = dfm_chol_solve(c, x, nrhs);
            fz_check(fz_known(r));
            if (r == DFM_OK) {
                fz_check(fz_all_finite_d(x, n * nrhs));
                if (dominant) fz_residual(&a, x, b);
            }
            r = dfm_chol_solve_refined(c, &a, b, x, nrhs, (int)(fz_u8(in) % 4));
            fz_check(fz_known(r));
            if (r == DFM_OK) fz_check(fz_all_finite_d(x, n * nrhs));
        }
    } else {
        fz_check(c == NULL);
    }
    dfm_chol_free(c);
    /* hard constraints by elimination */
    for (i = 0; i < n; i++) fixed[i] = (unsigned char)(fz_u8(in) & 1);
    r = dfm_constrained_analyze(&a, fixed, &o, &k);
    fz_check(fz_known(r));
    if (r == DFM_OK) r = dfm_constrained_factor(k, &a);
    fz_check(fz_known(r));
    if (r == DFM_OK) {
        for (i = 0; i < n; i++) {
            b[i] = fz_f64(in);
            fv[i] = fz_f64(in);
        }
        r = dfm_constrained_solve(k, b, fv, x, 1);
        fz_check(fz_known(r));
        if (r == DFM_OK) {
            fz_check(fz_all_finite_d(x, n));
            for (i = 0; i < n; i++)
                if (fixed[i]) fz_check(memcmp(x + i, fv + i, sizeof(double)) == 0);
        }
    }
    dfm_constrained_free(k);
    dfm_csc_free(&a);
}

static void fz_laplacian(fz_in *in, const dfm_allocator *al)
{
    float pos[3 * FZ_N];
    uint32_t idx[3 * FZ_T];
    size_t nv, nt;
    int kind = (int)(fz_u8(in) % 4); /* 3: invalid */
    dfm_csc l, m;
    dfm_result r;
    fz_mesh(in, FZ_N, FZ_T, pos, NULL, idx, &nv, &nt);
    r = dfm_mesh_laplacian(pos, nv, idx, nt, kind, al, &l);
    fz_check(fz_known(r));
    if (r != DFM_OK) {
        fz_check(l.col_start == NULL);
        return;
    }
    fz_check(l.n_rows == nv && dfm_csc_validate(&l) == DFM_OK);
    r = dfm_normal_matrix(&l, NULL, al, &m);
    fz_check(fz_known(r));
    if (r == DFM_OK) fz_check(dfm_csc_validate(&m) == DFM_OK);
    dfm_csc_free(&m);
    dfm_csc_free(&l);
}

static void fz_deform(fz_in *in, const dfm_allocator *al, fz_cancel *cc)
{
    double pos[3 * FZ_N], tg[3 * FZ_N], rot[9 * FZ_N], out[3 * FZ_N], R[9], p3[3], ax[3], to[3];
    uint32_t idx[3 * FZ_T];
    unsigned char roi[FZ_N], handle[FZ_N];
    size_t nv, nt, v;
    unsigned f = fz_u8(in), g = fz_u8(in);
    dfm_deform_options o = dfm_deform_default_options();
    dfm_deform *d = NULL;
    dfm_result r;
    int frame;
    fz_mesh(in, FZ_N, FZ_T, NULL, pos, idx, &nv, &nt);
    for (v = 0; v < nv; v++) {
        unsigned b = fz_u8(in);
        roi[v] = (unsigned char)(b & 1);
        handle[v] = (unsigned char)((b >> 1) & 1 && ((b & 1) || (f & 1)));
    }
    o.method = (int)(f >> 1) % 3;
    o.weights = (int)(f >> 3) & 1;
    o.handle_constraint = (int)(f >> 4) & 1;
    o.handle_weight = (f & 32) ? fz_f64(in) : 0.0;
    o.frames = (int)(g & 1);
    o.orthonormalize = (int)((g >> 1) & 3); /* 3: invalid */
    o.refine_steps = (int)((g >> 3) & 3);
    o.rigid_steps = (g & 32) ? (int)(fz_u8(in) % 4) : 0;
    o.allocator = al;
    o.progress = (f & 64) ? fz_progress : NULL;
    o.progress_user = cc;
    r = dfm_deform_setup(pos, nv, idx, nt, roi, handle, &o, &d);
    fz_check(fz_known(r));
    if (r != DFM_OK) {
        fz_check(d == NULL);
        return;
    }
    for (frame = 0; frame < 2; frame++) {
        unsigned k = fz_u8(in);
        for (v = 0; v < 3; v++) {
            p3[v] = fz_f64(in);
            ax[v] = fz_f64(in);
            to[v] = fz_f64(in);
        }
        dfm_pose_identity(pos, nv, tg, rot);
        if ((k & 3) == 1) {
            dfm_rotation(ax, fz_f64(in), R);
            dfm_pose_rigid(pos, nv, handle, R, p3, to, tg, rot);
        } else if ((k & 3) == 2) {
            dfm_pose_twist(pos, nv, handle, p3, ax, fz_f64(in), tg, rot);
        } else if ((k & 3) == 3) {
            dfm_pose_bend(pos, nv, handle, p3, ax, to, fz_f64(in), fz_f64(in), tg, rot);
        }
        r = dfm_deform_solve(d, tg, (k & 4) ? NULL : rot, out);
        fz_check(fz_known(r));
        if (r == DFM_OK) {
            /* fixed and hard-handle vertices land exactly on their targets (a pose helper may
               have put NaN at a vertex no row reads: it is copied as it is); every vertex solved
               for is finite */
            for (v = 0; v < nv; v++)
                if (!roi[v] || (handle[v] && o.handle_constraint == DFM_HANDLE_HARD))
                    fz_check(memcmp(out + 3 * v, tg + 3 * v, 3 * sizeof(double)) == 0);
                else if (memcmp(out + 3 * v, tg + 3 * v, 3 * sizeof(double)) != 0)
                    fz_check(fz_all_finite_d(out + 3 * v, 3));
        }
    }
    dfm_deform_free(d);
}

static void fz_helpers(fz_in *in, const dfm_allocator *al)
{
    double pos[3 * FZ_N];
    uint32_t idx[3 * FZ_T], remap[FZ_N], out_idx[3 * FZ_T];
    unsigned char mask[FZ_N], seeds[FZ_N], before[FZ_N];
    size_t nv, nt, v;
    double radius;
    unsigned k = fz_u8(in);
    dfm_result r;
    fz_mesh(in, FZ_N, FZ_T, NULL, pos, idx, &nv, &nt);
    if (k & 8) /* some copies of vertices, for the weld */
        for (v = 1; v < nv; v++)
            if (fz_u8(in) & 1) memcpy(pos + 3 * v, pos + 3 * (v - 1), 3 * sizeof(double));
    for (v = 0; v < nv; v++) {
        unsigned b = fz_u8(in);
        mask[v] = (unsigned char)(b & 1);
        seeds[v] = (unsigned char)((b >> 1) & 1);
    }
    memcpy(before, mask, nv);
    r = dfm_roi_rings(idx, nt, nv, k & 7, mask, al);
    fz_check(fz_known(r));
    if (r == DFM_OK)
        for (v = 0; v < nv; v++) fz_check(!before[v] || mask[v]); /* a ring only grows the mask */
    radius = fz_f64(in);
    r = dfm_roi_geodesic(pos, nv, idx, nt, seeds, radius, mask, al);
    fz_check(fz_known(r));
    if (r == DFM_OK)
        for (v = 0; v < nv; v++) fz_check(mask[v] <= 1 && (!seeds[v] || !(radius >= 0.0) || mask[v]));
    r = dfm_weld(pos, nv, idx, nt, remap, (k & 16) ? idx : out_idx, al);
    fz_check(fz_known(r));
    if (r == DFM_OK) {
        const uint32_t *oi = (k & 16) ? idx : out_idx;
        for (v = 0; v < nv; v++)
            fz_check(remap[v] <= v && memcmp(pos + 3 * remap[v], pos + 3 * v, 3 * sizeof(double)) == 0);
        for (v = 0; v < 3 * nt; v++) fz_check(oi[v] < nv && remap[oi[v]] == oi[v]);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fz_heap h;
    fz_cancel c;
    dfm_allocator a;
    unsigned op = fz_begin(&in, data, size, &h, &c);
    FZ_HEAP_ALLOCATOR(a, &h);
    switch (op & 3) {
    case 0: fz_chol(&in, &a, &c); break;
    case 1: fz_laplacian(&in, &a); break;
    case 2: fz_deform(&in, &a, &c); break;
    default: fz_helpers(&in, &a); break;
    }
    fz_check(h.live == 0 && h.bytes == 0); /* nothing held after any result */
    return 0;
}
#endif /* FZ_HELPERS_ONLY */
