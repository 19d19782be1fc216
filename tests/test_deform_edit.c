/* test_deform_edit - deform.h part 2: Laplacian, transformation-fitting and LRI editing.
   Properties from issue 18: zero motion reproduces the mesh, translating every constrained vertex
   translates the result, a rigid motion of the constraints is reproduced by LRI and not by the
   plain Laplacian, origin independence, soft -> hard convergence, when the frame choice matters;
   then bad input, allocation failure and cancellation. Meshes are generated (a noisy open tube). */
#define DFM_IMPLEMENTATION
#include "deform.h"

#include "test.h"
#include "hashrand.h"

#include <stdlib.h>
#include <string.h>
#include <math.h>

static const double PI = 3.14159265358979323846;

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

/* ---- the test mesh: an open tube along z, radius 1, height h, rings x segs vertices, radial
   noise of `noise` (deterministic); ROI = z > 0.25 h, handle = z > 0.85 h ------------------- */
typedef struct tube {
    size_t nv, nt;
    double *pos;
    uint32_t *idx;
    unsigned char *roi, *handle, *fixed;
    double h, diag;
} tube;

static tube make_tube(size_t rings, size_t segs, double h, double noise)
{
    tube m;
    size_t r, s, t = 0;
    m.nv = rings * segs;
    m.nt = 2 * (rings - 1) * segs;
    m.h = h;
    m.pos = (double *)malloc(3 * m.nv * sizeof(double));
    m.idx = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t));
    m.roi = (unsigned char *)malloc(m.nv);
    m.handle = (unsigned char *)malloc(m.nv);
    m.fixed = (unsigned char *)malloc(m.nv);
    for (r = 0; r < rings; r++)
        for (s = 0; s < segs; s++) {
            size_t v = r * segs + s;
            double a = 2.0 * PI * ((double)s + 0.5 * (double)(r & 1)) / (double)segs;
            double rad = 1.0 + noise * (2.0 * unit_random(v, 1) - 1.0), z = h * (double)r / (double)(rings - 1);
            m.pos[3 * v] = rad * cos(a);
            m.pos[3 * v + 1] = rad * sin(a);
            m.pos[3 * v + 2] = z;
            m.roi[v] = z > 0.25 * h;
            m.handle[v] = z > 0.85 * h;
            m.fixed[v] = !m.roi[v] || m.handle[v];
        }
    for (r = 0; r + 1 < rings; r++)
        for (s = 0; s < segs; s++) {
            uint32_t a = (uint32_t)(r * segs + s), b = (uint32_t)(r * segs + (s + 1) % segs);
            uint32_t c = (uint32_t)((r + 1) * segs + s), d = (uint32_t)((r + 1) * segs + (s + 1) % segs);
            uint32_t *f = m.idx + 6 * t++;
            if (r & 1) {
                f[0] = a; f[1] = b; f[2] = d; f[3] = a; f[4] = d; f[5] = c;
            } else {
                f[0] = a; f[1] = b; f[2] = c; f[3] = b; f[4] = d; f[5] = c;
            }
        }
    m.diag = sqrt(8.0 + h * h);
    return m;
}

static void free_tube(tube *m)
{
    free(m->pos);
    free(m->idx);
    free(m->roi);
    free(m->handle);
    free(m->fixed);
}

static double max_dist(const double *a, const double *b, size_t nv)
{
    size_t i;
    double m = 0.0;
    for (i = 0; i < 3 * nv; i++) m = fmax(m, fabs(a[i] - b[i]));
    return m;
}

static dfm_deform_options method_options(int method, int ortho)
{
    dfm_deform_options o = dfm_deform_default_options();
    o.method = method;
    o.orthonormalize = ortho;
    return o;
}

/* setup + one solve; returns the result (malloc'd) or NULL, with the setup's code in *err */
static double *deform(const tube *m, const dfm_deform_options *o, const double *targets, const double *rot,
                      dfm_result *err)
{
    dfm_deform *d = NULL;
    double *out = (double *)malloc(3 * m->nv * sizeof(double));
    *err = dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, o, &d);
    if (*err == DFM_OK) *err = dfm_deform_solve(d, targets, rot, out);
    dfm_deform_free(d);
    if (*err != DFM_OK) {
        free(out);
        return NULL;
    }
    return out;
}

/* the configurations every property is checked on */
#define NCONF 9
static dfm_deform_options conf(int k)
{
    dfm_deform_options o = dfm_deform_default_options();
    static const int method[NCONF] = {DFM_METHOD_LAPLACIAN, DFM_METHOD_LAPLACIAN, DFM_METHOD_FITTING,
                                      DFM_METHOD_LRI,       DFM_METHOD_LRI,       DFM_METHOD_LRI,
                                      DFM_METHOD_LRI,       DFM_METHOD_LRI,       DFM_METHOD_LRI};
    o.method = method[k];
    o.weights = k == 1 || k == 6 || k == 7 ? DFM_WEIGHTS_COTAN : DFM_WEIGHTS_UNIFORM;
    o.orthonormalize = k == 4 || k == 7 ? DFM_ORTHO_POLAR : k == 5 ? DFM_ORTHO_GRAM_SCHMIDT : DFM_ORTHO_NONE;
    o.handle_constraint = k == 6 || k == 8 ? DFM_HANDLE_SOFT : DFM_HANDLE_HARD;
    o.rigid_steps = k >= 7 ? 3 : 0;
    return o;
}
static const char *conf_name[NCONF] = {"laplacian", "laplacian-cotan", "fitting",     "lri",       "lri-polar",
                                       "lri-gs",    "lri-cotan-soft",  "lri-rigid3", "lri-soft-rigid3"};

/* a 90-degree bend of the tube's ROI towards +x */
static void bend_pose(const tube *m, double angle, double *targets, double *rot)
{
    double base[3] = {0, 0, 0.25 * m->h}, axis[3] = {0, 0, 1}, toward[3] = {1, 0, 0};
    base[2] = 0.25 * m->h;
    dfm_pose_identity(m->pos, m->nv, targets, rot);
    dfm_pose_bend(m->pos, m->nv, m->handle, base, axis, toward, 0.6 * m->h, angle, targets, rot);
}

/* ---- the properties --------------------------------------------------------------------------- */

/* Zero handle motion: the displacement form has a zero right-hand side, so the result is the
   mesh up to the orthonormalization's rounding (1e-8 of the diagonal is the bar). */
static void test_zero_motion(const tube *m)
{
    int k;
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    dfm_pose_identity(m->pos, m->nv, tg, rot);
    for (k = 0; k < NCONF; k++) {
        dfm_deform_options o = conf(k);
        dfm_result err;
        double *out = deform(m, &o, tg, rot, &err);
        T_EQ_INT(err, DFM_OK);
        if (out) {
            double e = max_dist(out, m->pos, m->nv) / m->diag;
            T_CHECK_MSG(e <= 1e-8, "%s: zero motion moved by %.3g diagonals", conf_name[k], e);
        }
        free(out);
    }
    free(tg);
    free(rot);
}

/* Translating every constrained vertex by t translates the result by t (L has zero row sums,
   the fit is centred, LRI's frames do not change): checked on a bent pose, not only the rest. */
static void test_translation(const tube *m)
{
    int k;
    size_t v;
    double t[3] = {0.3, -1.7, 2.2};
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    double *tg2 = (double *)malloc(3 * m->nv * sizeof(double));
    bend_pose(m, 0.5 * PI, tg, rot);
    for (v = 0; v < m->nv; v++)
        for (k = 0; k < 3; k++) tg2[3 * v + k] = tg[3 * v + k] + t[k];
    for (k = 0; k < NCONF; k++) {
        dfm_deform_options o = conf(k);
        dfm_result e1, e2;
        double *a = deform(m, &o, tg, rot, &e1), *b = deform(m, &o, tg2, rot, &e2), e = 0.0;
        T_CHECK(e1 == DFM_OK && e2 == DFM_OK);
        if (a && b) {
            for (v = 0; v < m->nv; v++) {
                int c;
                for (c = 0; c < 3; c++) e = fmax(e, fabs(b[3 * v + c] - a[3 * v + c] - t[c]));
            }
            e /= m->diag;
            T_CHECK_MSG(e <= 1e-9, "%s: translated constraints, result off by %.3g diagonals", conf_name[k], e);
        }
        free(a);
        free(b);
    }
    free(tg);
    free(tg2);
    free(rot);
}

/* The same rigid motion (rotation R about a point, then a shift) of the handle and the fixed set,
   positions and frames: LRI reproduces the moved mesh (its coordinates are rotation invariant),
   the plain Laplacian does not (its delta_i keep their directions). */
static void test_rigid_motion(const tube *m)
{
    int k;
    double axis[3] = {1, 2, 0.5}, R[9], c[3] = {0.5, 0.2, 1.0}, t[3] = {1, 0, -2};
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    double *moved = (double *)malloc(3 * m->nv * sizeof(double));
    unsigned char *all = (unsigned char *)malloc(m->nv);
    memset(all, 1, m->nv);
    dfm_rotation(axis, 1.2, R);
    dfm_pose_identity(m->pos, m->nv, tg, rot);
    dfm_pose_rigid(m->pos, m->nv, m->fixed, R, c, t, tg, rot);
    dfm_pose_rigid(m->pos, m->nv, all, R, c, t, moved, NULL);
    for (k = 0; k < NCONF; k++) {
        dfm_deform_options o = conf(k);
        dfm_result err;
        double *out = deform(m, &o, tg, rot, &err), e;
        T_EQ_INT(err, DFM_OK);
        if (!out) continue;
        e = max_dist(out, moved, m->nv) / m->diag;
        printf("rigid motion (69 degrees): %-15s max error %.3g diagonals\n", conf_name[k], e);
        if (o.method == DFM_METHOD_LRI)
            T_CHECK_MSG(e <= 1e-6, "%s: rigid motion reproduced to %.3g", conf_name[k], e);
        if (o.method == DFM_METHOD_LAPLACIAN) /* a visible failure, not rounding */
            T_CHECK_MSG(e >= 1e-2, "%s: rigid motion error only %.3g", conf_name[k], e);
        free(out);
    }
    free(tg);
    free(rot);
    free(moved);
    free(all);
}

/* Shift the mesh and its pose by 10 diagonals, deform, shift back: the same result (the
   transformation fit is on centred coordinates; the thesis's uncentred fit fails this). */
static void test_origin_independence(tube *m)
{
    int k;
    size_t v;
    double s[3], *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    s[0] = 10.0 * m->diag;
    s[1] = -7.0 * m->diag;
    s[2] = 4.0 * m->diag;
    for (k = 0; k < NCONF; k++) {
        dfm_deform_options o = conf(k);
        dfm_result e1, e2;
        double *a, *b, e = 0.0;
        int c;
        bend_pose(m, 0.5 * PI, tg, rot);
        a = deform(m, &o, tg, rot, &e1);
        for (v = 0; v < m->nv; v++)
            for (c = 0; c < 3; c++) {
                m->pos[3 * v + c] += s[c];
                tg[3 * v + c] += s[c];
            }
        b = deform(m, &o, tg, rot, &e2);
        for (v = 0; v < m->nv; v++)
            for (c = 0; c < 3; c++) m->pos[3 * v + c] -= s[c];
        T_CHECK(e1 == DFM_OK && e2 == DFM_OK);
        if (a && b) {
            for (v = 0; v < m->nv; v++)
                for (c = 0; c < 3; c++) e = fmax(e, fabs(b[3 * v + c] - s[c] - a[3 * v + c]));
            e /= m->diag;
            T_CHECK_MSG(e <= 1e-6, "%s: shifted by 10 diagonals, result off by %.3g", conf_name[k], e);
        }
        free(a);
        free(b);
    }
    free(tg);
    free(rot);
}

/* Soft handle constraints with growing weight converge to the hard-constraint result: the error
   falls with the weight and is small at w = 1000 (the soft solution is O(1 / w^2) from the hard). */
static void test_soft_to_hard(const tube *m)
{
    int meth;
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    bend_pose(m, 0.5 * PI, tg, rot);
    for (meth = 0; meth < 3; meth++) {
        dfm_deform_options o = method_options(meth, DFM_ORTHO_NONE);
        dfm_result err;
        double *hard = deform(m, &o, tg, rot, &err), prev = HUGE_VAL, first = 0.0, e = 0.0, w;
        int monotone = 1;
        T_EQ_INT(err, DFM_OK);
        o.handle_constraint = DFM_HANDLE_SOFT;
        for (w = 1.0; w <= 1000.0 && hard; w *= 10.0) {
            double *soft;
            o.handle_weight = w;
            soft = deform(m, &o, tg, rot, &err);
            T_EQ_INT(err, DFM_OK);
            if (!soft) break;
            e = max_dist(soft, hard, m->nv) / m->diag;
            if (w == 1.0) first = e;
            monotone &= e < prev;
            prev = e;
            free(soft);
        }
        printf("soft -> hard, method %d: error %.3g at w = 1, %.3g at w = 1000\n", meth, first, e);
        T_CHECK(monotone);
        T_CHECK_MSG(e <= 1e-4 * first + 1e-12 && e <= 1e-5, "method %d: soft w=1000 off by %.3g", meth, e);
        free(hard);
    }
    free(tg);
    free(rot);
}

/* The frame choice (first edge or the thesis's largest elevation) changes nothing with no or
   polar orthonormalization (the problem is the same up to per-vertex rotations of the frames),
   and does change the result with Gram-Schmidt (not equivariant). */
static void test_frame_choice(const tube *m)
{
    int ortho;
    size_t v, differ = 0;
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    dfm_deform *d1 = NULL, *d2 = NULL;
    dfm_deform_options o = method_options(DFM_METHOD_LRI, DFM_ORTHO_NONE);
    bend_pose(m, 2.0 * PI / 3.0, tg, rot);
    /* the two choices really pick different tangent axes */
    T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d1), DFM_OK);
    o.frames = DFM_FRAMES_MAX_ELEVATION;
    T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d2), DFM_OK);
    if (d1 && d2)
        for (v = 0; v < m->nv; v++) differ += fabs(d1->frame[9 * v] - d2->frame[9 * v]) > 1e-3;
    T_CHECK_MSG(differ > m->nv / 2, "frames differ at %d of %d vertices", (int)differ, (int)m->nv);
    dfm_deform_free(d1);
    dfm_deform_free(d2);
    for (ortho = DFM_ORTHO_NONE; ortho <= DFM_ORTHO_GRAM_SCHMIDT + 1; ortho++) { /* last: polar + rigid steps */
        dfm_result e1, e2;
        double *a, *b, e;
        o = method_options(DFM_METHOD_LRI, ortho > DFM_ORTHO_GRAM_SCHMIDT ? DFM_ORTHO_POLAR : ortho);
        o.rigid_steps = ortho > DFM_ORTHO_GRAM_SCHMIDT ? 4 : 0;
        a = deform(m, &o, tg, rot, &e1);
        o.frames = DFM_FRAMES_MAX_ELEVATION;
        b = deform(m, &o, tg, rot, &e2);
        T_CHECK(e1 == DFM_OK && e2 == DFM_OK);
        if (a && b) {
            e = max_dist(a, b, m->nv) / m->diag;
            printf("frame choice, orthonormalization %d: results differ by %.3g diagonals\n", ortho, e);
            if (ortho == DFM_ORTHO_GRAM_SCHMIDT) T_CHECK_MSG(e >= 1e-4, "Gram-Schmidt: only %.3g", e);
            else T_CHECK_MSG(e <= 1e-9, "ortho %d: frame choice changed the result by %.3g", ortho, e);
        }
        free(a);
        free(b);
    }
    free(tg);
    free(rot);
}

/* RMS of |e'| / |e| - 1 over the edges with a free end */
static double edge_distortion(const tube *m, const double *out)
{
    size_t t, k, n = 0;
    double s = 0.0;
    for (t = 0; t < m->nt; t++)
        for (k = 0; k < 3; k++) {
            uint32_t a = m->idx[3 * t + k], b = m->idx[3 * t + (k + 1) % 3];
            double l0 = 0, l1 = 0, r;
            int c;
            if (!(m->roi[a] && !m->handle[a]) && !(m->roi[b] && !m->handle[b])) continue;
            for (c = 0; c < 3; c++) {
                l0 += (m->pos[3 * a + c] - m->pos[3 * b + c]) * (m->pos[3 * a + c] - m->pos[3 * b + c]);
                l1 += (out[3 * a + c] - out[3 * b + c]) * (out[3 * a + c] - out[3 * b + c]);
            }
            r = sqrt(l1 / l0) - 1.0;
            s += r * r;
            n++;
        }
    return sqrt(s / (double)n);
}

/* The ideal 90-degree bend of the tube's free part (z in [base, base + len]): the axis follows
   the arc of the same length and each cross-section turns with it, rigidly. */
static void ideal_bend(const tube *m, double angle, const double *p, double *q)
{
    double base = 0.25 * m->h, len = 0.6 * m->h, s = p[2] - base, phi = angle * s / len, r = len / angle;
    q[0] = r * (1.0 - cos(phi)) + p[0] * cos(phi);
    q[1] = p[1];
    q[2] = base + r * sin(phi) - p[0] * sin(phi);
}

/* The point of LRI: the 90-degree bend comes out close to the ideal bend, while plain Laplacian
   editing (whose delta_i do not turn) is far from it. RMS over the free vertices. */
static void test_bend_quality(void)
{
    tube m = make_tube(60, 16, 8.0, 0.02);
    double *tg = (double *)malloc(3 * m.nv * sizeof(double)), *rot = (double *)malloc(9 * m.nv * sizeof(double));
    double err[3], ed[3];
    int meth;
    bend_pose(&m, 0.5 * PI, tg, rot);
    for (meth = 0; meth < 3; meth++) {
        dfm_deform_options o = method_options(meth, DFM_ORTHO_POLAR);
        dfm_result e;
        double *out = deform(&m, &o, tg, rot, &e), sum = 0.0, q[3];
        size_t v, n = 0;
        T_EQ_INT(e, DFM_OK);
        for (v = 0; v < m.nv && out; v++) {
            int c;
            if (!m.roi[v] || m.handle[v]) continue;
            ideal_bend(&m, 0.5 * PI, m.pos + 3 * v, q);
            for (c = 0; c < 3; c++) sum += (out[3 * v + c] - q[c]) * (out[3 * v + c] - q[c]);
            n++;
        }
        err[meth] = out ? sqrt(sum / (double)n) / m.diag : HUGE_VAL;
        ed[meth] = out ? edge_distortion(&m, out) : HUGE_VAL;
        free(out);
    }
    printf("bend 90, RMS distance to the ideal bend (diagonals): laplacian %.4f fitting %.4f lri %.4f\n", err[0],
           err[1], err[2]);
    printf("bend 90, edge distortion (the ideal bend has its own): laplacian %.4f fitting %.4f lri %.4f\n", ed[0],
           ed[1], ed[2]);
    T_CHECK_MSG(err[2] <= err[0] / 3.0, "lri %.4f vs laplacian %.4f", err[2], err[0]);
    free(tg);
    free(rot);
    free_tube(&m);
}

/* The as-rigid-as-possible energy sum_i sum_j w_ij |e'_ij - R_i e_ij|^2 of a result over the
   setup's mesh graph, with R_i the best rotation (the polar factor of sum_j w_ij e'_ij e_ij^T) at
   the unknowns and the given rotation at the known vertices. */
static double arap_energy(const dfm_deform *d, const double *out, const double *rot)
{
    size_t i, p, k;
    double E = 0.0;
    for (i = 0; i < d->nv; i++) {
        double S[9] = {0}, R[9];
        for (k = 0; k < 9; k++) R[k] = rot[9 * i + k];
        if (d->unk[i] >= 0) {
            for (p = d->g.start[i]; p < d->g.start[i + 1]; p++) {
                size_t j = (size_t)d->g.adj[p];
                for (k = 0; k < 9; k++)
                    S[k] += d->g.w[p] * (out[3 * j + k / 3] - out[3 * i + k / 3]) *
                            (d->pos[3 * j + k % 3] - d->pos[3 * i + k % 3]);
            }
            memcpy(R, S, sizeof S);
            dfm__polar(R);
        }
        for (p = d->g.start[i]; p < d->g.start[i + 1]; p++) {
            size_t j = (size_t)d->g.adj[p];
            double e[3], r;
            int c;
            for (c = 0; c < 3; c++) e[c] = d->pos[3 * j + c] - d->pos[3 * i + c];
            for (c = 0; c < 3; c++) {
                r = out[3 * j + c] - out[3 * i + c] - (R[3 * c] * e[0] + R[3 * c + 1] * e[1] + R[3 * c + 2] * e[2]);
                E += d->g.w[p] * r * r;
            }
        }
    }
    return E;
}

/* LRI's rigid steps are local-global steps on the ARAP energy started from LRI's result: the
   energy (each unknown's rotation the best one) never rises from one step count to the next
   (block descent; 1e-9 relative for rounding and the local fit's last iteration) and falls in all.
   Uniform and cotangent weights. */
static void test_rigid_steps(void)
{
    tube m = make_tube(40, 16, 8.0, 0.02);
    double *tg = (double *)malloc(3 * m.nv * sizeof(double)), *rot = (double *)malloc(9 * m.nv * sizeof(double));
    int weights;
    bend_pose(&m, 0.5 * PI, tg, rot);
    for (weights = DFM_WEIGHTS_UNIFORM; weights <= DFM_WEIGHTS_COTAN; weights++) {
        dfm_deform_options o = method_options(DFM_METHOD_LRI, DFM_ORTHO_POLAR);
        dfm_deform *d = NULL;
        double E[6], ed[6], *out = (double *)malloc(3 * m.nv * sizeof(double));
        int k, monotone = 1;
        o.weights = weights;
        for (k = 0; k < 6; k++) {
            o.rigid_steps = k == 0 ? 0 : 1 << (k - 1); /* 0 1 2 4 8 16 */
            T_EQ_INT(dfm_deform_setup(m.pos, m.nv, m.idx, m.nt, m.roi, m.handle, &o, &d), DFM_OK);
            E[k] = ed[k] = HUGE_VAL;
            if (d && dfm_deform_solve(d, tg, rot, out) == DFM_OK) {
                E[k] = arap_energy(d, out, rot);
                ed[k] = edge_distortion(&m, out);
            }
            dfm_deform_free(d);
            if (k > 0) monotone &= E[k] <= E[k - 1] * (1.0 + 1e-9);
        }
        printf("rigid steps 0 1 2 4 8 16 (%s weights): ARAP energy %.4g %.4g %.4g %.4g %.4g %.4g, edge distortion "
               "%.4f -> %.4f\n",
               weights ? "cotangent" : "uniform", E[0], E[1], E[2], E[3], E[4], E[5], ed[0], ed[5]);
        T_CHECK_MSG(monotone, "the ARAP energy rose with more steps");
        T_CHECK_MSG(E[5] < E[0], "16 steps: energy %.4g, none: %.4g", E[5], E[0]);
        free(out);
    }
    free(tg);
    free(rot);
    free_tube(&m);
}

/* Iterative refinement keeps the normal matrices and changes the result only by rounding; a
   vertex in no triangle, even inside the ROI, stays at its target. */
static void test_refine_and_lone_vertex(const tube *m)
{
    double *tg = (double *)malloc(3 * (m->nv + 1) * sizeof(double)), *rot = (double *)malloc(9 * (m->nv + 1) * sizeof(double));
    int meth;
    bend_pose(m, 0.5 * PI, tg, rot);
    for (meth = 0; meth < 3; meth++) {
        dfm_deform_options o = method_options(meth, DFM_ORTHO_POLAR);
        dfm_result e1, e2;
        double *a = deform(m, &o, tg, rot, &e1), *b;
        o.refine_steps = 2;
        b = deform(m, &o, tg, rot, &e2);
        T_CHECK(e1 == DFM_OK && e2 == DFM_OK);
        if (a && b) T_CHECK_MSG(max_dist(a, b, m->nv) <= 1e-9 * m->diag, "refined: %.3g", max_dist(a, b, m->nv));
        free(a);
        free(b);
    }
    {
        tube m2 = *m;
        dfm_deform *d = NULL;
        double *out = (double *)malloc(3 * (m->nv + 1) * sizeof(double));
        dfm_deform_options o = method_options(DFM_METHOD_LRI, DFM_ORTHO_POLAR);
        m2.nv = m->nv + 1;
        m2.pos = (double *)malloc(3 * m2.nv * sizeof(double));
        m2.roi = (unsigned char *)malloc(m2.nv);
        m2.handle = (unsigned char *)malloc(m2.nv);
        memcpy(m2.pos, m->pos, 3 * m->nv * sizeof(double));
        memcpy(m2.roi, m->roi, m->nv);
        memcpy(m2.handle, m->handle, m->nv);
        m2.pos[3 * m->nv] = 7.0;
        m2.pos[3 * m->nv + 1] = 7.0;
        m2.pos[3 * m->nv + 2] = 7.0;
        m2.roi[m->nv] = 1;
        m2.handle[m->nv] = 0;
        tg[3 * m->nv] = tg[3 * m->nv + 1] = tg[3 * m->nv + 2] = 7.0;
        memcpy(rot + 9 * m->nv, rot, 9 * sizeof(double));
        T_EQ_INT(dfm_deform_setup(m2.pos, m2.nv, m2.idx, m2.nt, m2.roi, m2.handle, &o, &d), DFM_OK);
        if (d) {
            T_EQ_INT(dfm_deform_solve(d, tg, rot, out), DFM_OK);
            T_CHECK(out[3 * m->nv] == 7.0 && out[3 * m->nv + 2] == 7.0);
        }
        dfm_deform_free(d);
        free(out);
        free(m2.pos);
        free(m2.roi);
        free(m2.handle);
    }
    free(tg);
    free(rot);
}

/* ---- helpers ------------------------------------------------------------------------------------ */

static void test_helpers(const tube *m)
{
    double base[3] = {0, 0, 0}, axis[3] = {0, 0, 3}, toward[3] = {2, 0, 1}, p[3] = {0.5, 0.0, 2.0}, tg[3], r[9];
    double pt[3] = {1, 1, 0}, ax[3] = {0, 0, 1}, q[6] = {1, 1, 5, 2, 1, 5}, tq[6];
    unsigned char one = 1, two[2] = {1, 1}, *mask = (unsigned char *)calloc(m->nv, 1);
    double rr = 4.0 / PI, e;
    size_t v, cnt = 0, deg;
    /* bend by 90 degrees over length 2 towards +x: the point base + 2 axis goes to the arc's end
       (r (1 - cos), 0, r sin) with r = 2 / (pi / 2); a point 0.5 beside it turns with the handle */
    dfm_pose_bend(p, 1, &one, base, axis, toward, 2.0, 0.5 * PI, tg, r);
    T_NEAR(tg[0], rr + 0.0, 1e-12);
    T_NEAR(tg[1], 0.0, 1e-12);
    T_NEAR(tg[2], rr - 0.5, 1e-12);
    T_NEAR(r[2], 1.0, 1e-12); /* R maps z to x */
    /* a twist about the line through (1,1,0) along z keeps points on it and turns the others */
    dfm_pose_twist(q, 2, two, pt, ax, 0.5 * PI, tq, NULL);
    T_NEAR(max_dist(tq, q, 1), 0.0, 1e-12);
    T_NEAR(tq[3], 1.0, 1e-12);
    T_NEAR(tq[4], 2.0, 1e-12);
    /* rings: one ring around a vertex is the vertex and its neighbours (6 on this tube) */
    mask[3 * 16 + 5] = 1;
    T_EQ_INT(dfm_roi_rings(m->idx, m->nt, m->nv, 1, mask, NULL), DFM_OK);
    for (v = 0; v < m->nv; v++) cnt += mask[v];
    T_EQ_SIZE(cnt, 7);
    T_EQ_INT(dfm_roi_rings(m->idx, m->nt, m->nv, 2, mask, NULL), DFM_OK);
    for (v = 0, deg = 0; v < m->nv; v++) deg += mask[v];
    T_EQ_SIZE(deg, 37); /* three rings of a regular valence-6 triangulation: 1 + 6 + 12 + 18 */
    /* geodesic: the edge-path distance is >= the Euclidean one, and <= 1.5x on this mesh */
    memset(mask, 0, m->nv);
    {
        unsigned char *seed = (unsigned char *)calloc(m->nv, 1);
        size_t s0 = 20 * 16 + 3;
        int bad = 0, missed = 0;
        seed[s0] = 1;
        T_EQ_INT(dfm_roi_geodesic(m->pos, m->nv, m->idx, m->nt, seed, 1.0, mask, NULL), DFM_OK);
        for (v = 0; v < m->nv; v++) {
            double dd[3];
            int c;
            for (c = 0; c < 3; c++) dd[c] = m->pos[3 * v + c] - m->pos[3 * s0 + c];
            e = sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
            bad += mask[v] && e > 1.0 + 1e-12;
            missed += !mask[v] && e < 1.0 / 1.5;
        }
        T_EQ_INT(bad, 0);
        T_EQ_INT(missed, 0);
        free(seed);
    }
    free(mask);
}

/* LRI's single-rotation shortcut (one scalar solve when every known rotation is I or the same R)
   agrees with the general nine-right-hand-side solve, taken when one handle rotation differs in
   its last bit. */
static void test_single_rotation_path(const tube *m)
{
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    double *a = (double *)malloc(3 * m->nv * sizeof(double)), *b = (double *)malloc(3 * m->nv * sizeof(double));
    dfm_deform_options o = method_options(DFM_METHOD_LRI, DFM_ORTHO_POLAR);
    dfm_deform *d = NULL;
    size_t v;
    bend_pose(m, 0.5 * PI, tg, rot);
    T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d), DFM_OK);
    T_EQ_INT(dfm_deform_solve(d, tg, rot, a), DFM_OK);
    for (v = 0; v < m->nv && !m->handle[v]; v++) {
    }
    rot[9 * v + 1] = nextafter(rot[9 * v + 1], 1.0);
    T_EQ_INT(dfm_deform_solve(d, tg, rot, b), DFM_OK);
    T_CHECK_MSG(max_dist(a, b, m->nv) <= 1e-10 * m->diag, "shortcut vs general: %.3g", max_dist(a, b, m->nv));
    T_CHECK(max_dist(a, m->pos, m->nv) > 0.1 * m->diag); /* and the pose did move the mesh */
    dfm_deform_free(d);
    free(tg);
    free(rot);
    free(a);
    free(b);
}

/* The polar factor: orthogonal, and R^T X symmetric positive definite (the polar decomposition
   X = R P), for random well- and badly-scaled matrices. */
static void test_polar(void)
{
    int t, bad = 0;
    for (t = 0; t < 200; t++) {
        double X[9], R[9], P[9], e = 0.0, sym = 0.0, sc = t % 2 ? 1e-3 : 50.0;
        int i, j, k;
        for (k = 0; k < 9; k++) X[k] = sc * (2.0 * unit_random((uint64_t)(9 * t + k), 3) - 1.0) + (k % 4 == 0 ? 1.5 * sc : 0.0);
        memcpy(R, X, sizeof X);
        dfm__polar(R);
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) {
                double rr = 0.0, rp = 0.0;
                for (k = 0; k < 3; k++) {
                    rr += R[3 * i + k] * R[3 * j + k];
                    rp += R[3 * k + i] * X[3 * k + j];
                }
                e = fmax(e, fabs(rr - (i == j)));
                P[3 * i + j] = rp;
            }
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) sym = fmax(sym, fabs(P[3 * i + j] - P[3 * j + i]) / sc);
        bad += !(e <= 1e-12 && sym <= 1e-10 && P[0] > 0 && P[4] > 0 && P[8] > 0);
    }
    T_EQ_INT(bad, 0);
}

/* ---- bad input ---------------------------------------------------------------------------------- */

static dfm_result setup_code(const tube *m, const double *pos, const uint32_t *idx, size_t nv, size_t nt,
                             const unsigned char *roi, const unsigned char *handle, const dfm_deform_options *o)
{
    dfm_deform *d = (dfm_deform *)m; /* any non-NULL value: must be reset to NULL on failure */
    dfm_result err = dfm_deform_setup(pos, nv, idx, nt, roi, handle, o, &d);
    if (err != DFM_OK && d != NULL) return (dfm_result)-1;
    dfm_deform_free(d);
    return err;
}

static void test_bad_input(const tube *m)
{
    dfm_deform_options o = dfm_deform_default_options();
    unsigned char *roi = (unsigned char *)malloc(m->nv), *h = (unsigned char *)malloc(m->nv);
    double *pos = (double *)malloc(3 * m->nv * sizeof(double)), *tg = (double *)malloc(3 * m->nv * sizeof(double));
    uint32_t *idx = (uint32_t *)malloc(3 * m->nt * sizeof(uint32_t));
    size_t v;
    int meth;
    T_EQ_INT(setup_code(m, NULL, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, NULL), DFM_ERR_INVALID_ARGUMENT);
    o.method = 3;
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_INVALID_ARGUMENT);
    o = dfm_deform_default_options();
    o.rigid_steps = -1;
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_INVALID_ARGUMENT);
    o.rigid_steps = 101;
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_INVALID_ARGUMENT);
    o = dfm_deform_default_options();
    o.handle_weight = -1.0;
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_BAD_VALUE);
    o = dfm_deform_default_options();
    /* empty ROI, and an ROI that is all handle */
    memset(roi, 0, m->nv);
    memset(h, 0, m->nv);
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, roi, h, &o), DFM_ERR_EMPTY_ROI);
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, m->handle, m->handle, &o), DFM_ERR_EMPTY_ROI);
    /* a handle vertex outside the ROI */
    memcpy(h, m->handle, m->nv);
    h[0] = 1;
    T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, m->roi, h, &o), DFM_ERR_HANDLE_OUTSIDE_ROI);
    /* the whole mesh free and no handle: nothing holds it */
    memset(roi, 1, m->nv);
    memset(h, 0, m->nv);
    for (meth = 0; meth < 3; meth++) {
        o.method = meth;
        T_EQ_INT(setup_code(m, m->pos, m->idx, m->nv, m->nt, roi, h, &o), DFM_ERR_UNCONSTRAINED);
    }
    o = dfm_deform_default_options();
    /* two components: the second, a shifted copy of the tube, entirely in the ROI and without a
       handle, floats free (the first is fine) */
    {
        size_t nv2 = 2 * m->nv, nt2 = 2 * m->nt, t;
        double *pos2 = (double *)malloc(3 * nv2 * sizeof(double));
        uint32_t *idx2 = (uint32_t *)malloc(3 * nt2 * sizeof(uint32_t));
        unsigned char *roi2 = (unsigned char *)malloc(nv2), *h2 = (unsigned char *)calloc(nv2, 1);
        memcpy(pos2, m->pos, 3 * m->nv * sizeof(double));
        for (v = 0; v < 3 * m->nv; v++) pos2[3 * m->nv + v] = m->pos[v] + (v % 3 == 0 ? 5.0 : 0.0);
        memcpy(idx2, m->idx, 3 * m->nt * sizeof(uint32_t));
        for (t = 0; t < 3 * m->nt; t++) idx2[3 * m->nt + t] = m->idx[t] + (uint32_t)m->nv;
        memcpy(roi2, m->roi, m->nv);
        memset(roi2 + m->nv, 1, m->nv);
        memcpy(h2, m->handle, m->nv);
        for (meth = 0; meth < 3; meth++) {
            o.method = meth;
            T_EQ_INT(setup_code(m, pos2, idx2, nv2, nt2, roi2, h2, &o), DFM_ERR_UNCONSTRAINED);
        }
        memcpy(roi2 + m->nv, m->roi, m->nv); /* the second held like the first: fine */
        memcpy(h2 + m->nv, m->handle, m->nv);
        T_EQ_INT(setup_code(m, pos2, idx2, nv2, nt2, roi2, h2, &o), DFM_OK);
        free(pos2);
        free(idx2);
        free(roi2);
        free(h2);
    }
    o = dfm_deform_default_options();
    /* bad index, NaN position */
    memcpy(idx, m->idx, 3 * m->nt * sizeof(uint32_t));
    idx[7] = (uint32_t)m->nv;
    T_EQ_INT(setup_code(m, m->pos, idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_BAD_INDEX);
    memcpy(pos, m->pos, 3 * m->nv * sizeof(double));
    pos[3 * 40 + 1] = NAN;
    T_EQ_INT(setup_code(m, pos, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_BAD_VALUE);
    /* a zero-area triangle in the ROI: one corner moved onto the middle of the opposite edge */
    memcpy(pos, m->pos, 3 * m->nv * sizeof(double));
    {
        const uint32_t *f = m->idx + 3 * (m->nt / 2);
        int c;
        for (c = 0; c < 3; c++) pos[3 * f[0] + c] = 0.5 * (pos[3 * f[1] + c] + pos[3 * f[2] + c]);
    }
    for (meth = 0; meth < 3; meth++) {
        o.method = meth;
        o.weights = DFM_WEIGHTS_COTAN;
        T_EQ_INT(setup_code(m, pos, m->idx, m->nv, m->nt, m->roi, m->handle, &o), DFM_ERR_DEGENERATE_TRIANGLE);
    }
    o = dfm_deform_default_options();
    /* a non-manifold edge: a third triangle on an edge, to a new vertex */
    {
        uint32_t *idx2 = (uint32_t *)malloc(3 * (m->nt + 1) * sizeof(uint32_t));
        double *pos2 = (double *)malloc(3 * (m->nv + 1) * sizeof(double));
        unsigned char *roi2 = (unsigned char *)calloc(m->nv + 1, 1), *h2 = (unsigned char *)calloc(m->nv + 1, 1);
        memcpy(idx2, m->idx, 3 * m->nt * sizeof(uint32_t));
        memcpy(pos2, m->pos, 3 * m->nv * sizeof(double));
        memcpy(roi2, m->roi, m->nv);
        memcpy(h2, m->handle, m->nv);
        pos2[3 * m->nv] = 5.0;
        pos2[3 * m->nv + 1] = 5.0;
        pos2[3 * m->nv + 2] = 5.0;
        idx2[3 * m->nt] = m->idx[3 * (m->nt / 2)]; /* an interior edge (two triangles already) */
        idx2[3 * m->nt + 1] = m->idx[3 * (m->nt / 2) + 1];
        idx2[3 * m->nt + 2] = (uint32_t)m->nv;
        T_EQ_INT(setup_code(m, pos2, idx2, m->nv + 1, m->nt + 1, roi2, h2, &o), DFM_ERR_NON_MANIFOLD);
        free(idx2);
        free(pos2);
        free(roi2);
        free(h2);
    }
    /* unwelded: every triangle its own three vertices */
    {
        size_t n3 = 3 * m->nt, t;
        uint32_t *idx2 = (uint32_t *)malloc(n3 * sizeof(uint32_t));
        double *pos2 = (double *)malloc(3 * n3 * sizeof(double));
        unsigned char *roi2 = (unsigned char *)malloc(n3), *h2 = (unsigned char *)malloc(n3);
        for (t = 0; t < n3; t++) {
            idx2[t] = (uint32_t)t;
            memcpy(pos2 + 3 * t, m->pos + 3 * m->idx[t], 3 * sizeof(double));
            roi2[t] = m->roi[m->idx[t]];
            h2[t] = m->handle[m->idx[t]];
        }
        T_EQ_INT(setup_code(m, pos2, idx2, n3, m->nt, roi2, h2, &o), DFM_ERR_UNWELDED);
        /* welded by dfm_weld, the soup deforms as the mesh does (copies moved with remap) */
        {
            uint32_t *remap = (uint32_t *)malloc(n3 * sizeof(uint32_t));
            double *tg2 = (double *)malloc(3 * n3 * sizeof(double)), *out2 = (double *)malloc(3 * n3 * sizeof(double));
            double *tgm = (double *)malloc(3 * m->nv * sizeof(double)), *rotm = (double *)malloc(9 * m->nv * sizeof(double));
            double *rot2 = (double *)malloc(9 * n3 * sizeof(double)), *ref, e = 0.0;
            dfm_deform *d = NULL;
            dfm_result er;
            T_EQ_INT(dfm_weld(pos2, n3, idx2, m->nt, remap, idx2, NULL), DFM_OK);
            bend_pose(m, 0.5 * PI, tgm, rotm);
            for (t = 0; t < n3; t++) {
                memcpy(tg2 + 3 * t, tgm + 3 * m->idx[t], 3 * sizeof(double));
                memcpy(rot2 + 9 * t, rotm + 9 * m->idx[t], 9 * sizeof(double));
            }
            ref = deform(m, &o, tgm, rotm, &er);
            T_EQ_INT(dfm_deform_setup(pos2, n3, idx2, m->nt, roi2, h2, &o, &d), DFM_OK);
            if (d && ref && dfm_deform_solve(d, tg2, rot2, out2) == DFM_OK) {
                for (t = 0; t < n3; t++) {
                    int c;
                    for (c = 0; c < 3; c++) e = fmax(e, fabs(out2[3 * remap[t] + c] - ref[3 * m->idx[t] + c]));
                }
                T_CHECK_MSG(e <= 1e-9 * m->diag, "welded soup vs mesh: %.3g", e);
            } else {
                T_CHECK(0);
            }
            dfm_deform_free(d);
            free(ref);
            free(remap);
            free(tg2);
            free(out2);
            free(tgm);
            free(rotm);
            free(rot2);
        }
        free(idx2);
        free(pos2);
        free(roi2);
        free(h2);
    }
    /* NaN targets at a handle vertex: the solve refuses them, and the object stays usable */
    {
        dfm_deform *d = NULL;
        double *out = (double *)malloc(3 * m->nv * sizeof(double));
        for (meth = 0; meth < 3; meth++) {
            o.method = meth;
            T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d), DFM_OK);
            dfm_pose_identity(m->pos, m->nv, tg, NULL);
            for (v = 0; v < m->nv && !m->handle[v]; v++) {
            }
            tg[3 * v] = NAN;
            T_EQ_INT(dfm_deform_solve(d, tg, NULL, out), DFM_ERR_BAD_VALUE);
            tg[3 * v] = m->pos[3 * v];
            T_EQ_INT(dfm_deform_solve(d, tg, NULL, out), DFM_OK);
            T_CHECK(max_dist(out, m->pos, m->nv) <= 1e-8 * m->diag);
            T_EQ_INT(dfm_deform_solve(NULL, tg, NULL, out), DFM_ERR_INVALID_ARGUMENT);
            T_EQ_INT(dfm_deform_solve(d, NULL, NULL, out), DFM_ERR_INVALID_ARGUMENT);
            dfm_deform_free(d);
            d = NULL;
        }
        free(out);
    }
    free(roi);
    free(h);
    free(pos);
    free(tg);
    free(idx);
}

/* Every allocation of setup and solve failed in turn: DFM_ERR_OUT_OF_MEMORY, nothing leaked. */
static void test_alloc_failures(void)
{
    tube m = make_tube(14, 10, 3.0, 0.05);
    int meth;
    double *tg = (double *)malloc(3 * m.nv * sizeof(double)), *rot = (double *)malloc(9 * m.nv * sizeof(double));
    double *out = (double *)malloc(3 * m.nv * sizeof(double));
    bend_pose(&m, 0.5 * PI, tg, rot);
    for (meth = 0; meth < 4; meth++) { /* 3: LRI with rigid steps (their sums' array) */
        long k;
        int leaks = 0, wrong = 0, ok = 0;
        for (k = 0; k < 100000 && !ok; k++) {
            counting c = {0, 0, 0};
            dfm_allocator al = {counting_alloc, counting_free, NULL};
            dfm_deform_options o = method_options(meth < 3 ? meth : DFM_METHOD_LRI, DFM_ORTHO_POLAR);
            dfm_deform *d = NULL;
            dfm_result err;
            c.fail_at = k;
            al.user = &c;
            o.allocator = &al;
            o.rigid_steps = meth == 3 ? 2 : 0;
            err = dfm_deform_setup(m.pos, m.nv, m.idx, m.nt, m.roi, m.handle, &o, &d);
            if (err == DFM_OK) err = dfm_deform_solve(d, tg, rot, out);
            if (err == DFM_OK) ok = 1;
            else wrong += err != DFM_ERR_OUT_OF_MEMORY;
            dfm_deform_free(d);
            leaks += c.allocs != c.frees;
        }
        printf("allocation failures, method %d: %ld allocations checked\n", meth, k);
        T_CHECK(ok);
        T_EQ_INT(leaks, 0);
        T_EQ_INT(wrong, 0);
    }
    free(tg);
    free(rot);
    free(out);
    free_tube(&m);
}

static int cancel_after(void *user, float done)
{
    int *n = (int *)user;
    (void)done;
    return --(*n) < 0;
}

static int record_progress(void *user, float done)
{
    float *last = (float *)user;
    if (done < last[0] || done > 1.0f) { /* not monotone, or out of range */
        printf("  progress %.9g after %.9g\n", done, last[0]);
        last[1] = 1.0f;
    }
    last[0] = done;
    return 0;
}

static void test_progress(const tube *m)
{
    int meth, calls;
    for (meth = 0; meth < 3; meth++) {
        counting c = {0, 0, -1};
        dfm_allocator al = {counting_alloc, counting_free, NULL};
        dfm_deform_options o = method_options(meth, DFM_ORTHO_NONE);
        dfm_deform *d = NULL;
        float rec[2] = {0.0f, 0.0f};
        al.user = &c;
        o.allocator = &al;
        o.progress = record_progress;
        o.progress_user = rec;
        T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d), DFM_OK);
        T_CHECK_MSG(rec[1] == 0.0f && rec[0] == 1.0f, "progress monotone %d, last %g", rec[1] == 0.0f, rec[0]);
        dfm_deform_free(d);
        for (calls = 0; calls < 6; calls++) {
            int n = calls;
            d = NULL;
            o.progress = cancel_after;
            o.progress_user = &n;
            T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d), DFM_CANCELLED);
            T_CHECK(d == NULL);
        }
        T_EQ_INT(c.allocs, c.frees);
    }
}

/* The cotangent floor: the weights a thin, obtuse triangulation makes negative are clamped, and
   editing still reproduces the mesh at rest. */
static void test_cotan_floor(void)
{
    tube m = make_tube(40, 8, 6.0, 0.0); /* long thin triangles: many obtuse angles */
    dfm_deform_options o = method_options(DFM_METHOD_LAPLACIAN, DFM_ORTHO_NONE);
    dfm_deform *d = NULL;
    size_t p, floored = 0;
    o.weights = DFM_WEIGHTS_COTAN;
    T_EQ_INT(dfm_deform_setup(m.pos, m.nv, m.idx, m.nt, m.roi, m.handle, &o, &d), DFM_OK);
    if (d) {
        int pos_ok = 1;
        for (p = 0; p < d->g.start[d->nv]; p++) {
            pos_ok &= d->g.w[p] >= DFM__COTAN_FLOOR;
            floored += d->g.w[p] == DFM__COTAN_FLOOR;
        }
        T_CHECK(pos_ok);
        printf("cotan floor: %d of %d directed edges clamped\n", (int)floored, (int)d->g.start[d->nv]);
        T_CHECK(floored > 0);
    }
    dfm_deform_free(d);
    free_tube(&m);
}

/* Issue 21 point 2: the methods are scale-free, so a mesh and pose scaled by 2^k (exact) give the
   result scaled by 2^k. At 2^400 (2.6e120) and 2^-400 the plain sums of squares overflow or
   underflow (|u x v|^2 in the cotangents and the degenerate-triangle check, LRI's normals and
   ARAP sums, FITTING's 3x3 inverse of the sixth power of a ring's size); at 2^90 they do not and
   the mesh is not rescaled. Without the setup's power-of-two rescaling, 2^400 gave DFM_OK with
   LRI 0.1 diagonals off (3.6e3 with soft handle and rigid steps), 2^-400 Gram-Schmidt LRI 0.035
   off, and FITTING refused both. The bound: the same operations on exactly scaled numbers, so
   the same bits but for rounding of the scaled targets; 1e-12 of the diagonal. A pose near 1e308
   overflows the displacements: DFM_ERR_NOT_FINITE and out not written. */
static void test_scale(tube *m)
{
    static const int expo[3] = {400, -400, 90};
    size_t v, i;
    int k, j;
    double *tg = (double *)malloc(3 * m->nv * sizeof(double)), *rot = (double *)malloc(9 * m->nv * sizeof(double));
    double *spos = (double *)malloc(3 * m->nv * sizeof(double)), *stg = (double *)malloc(3 * m->nv * sizeof(double));
    for (k = 0; k < NCONF; k++) {
        dfm_deform_options o = conf(k);
        dfm_result e1, e2;
        double *a, *b, *saved = m->pos;
        bend_pose(m, 0.5 * PI, tg, rot);
        a = deform(m, &o, tg, rot, &e1);
        T_CHECK(e1 == DFM_OK);
        for (j = 0; j < 3; j++) {
            double e = 0.0;
            for (i = 0; i < 3 * m->nv; i++) {
                spos[i] = ldexp(m->pos[i], expo[j]);
                stg[i] = ldexp(tg[i], expo[j]);
            }
            m->pos = spos;
            b = deform(m, &o, stg, rot, &e2);
            m->pos = saved;
            T_CHECK_MSG(e2 == DFM_OK, "%s at 2^%d: %s", conf_name[k], expo[j], dfm_result_string(e2));
            if (a && b) {
                for (i = 0; i < 3 * m->nv; i++) e = fmax(e, fabs(ldexp(b[i], -expo[j]) - a[i]));
                T_CHECK_MSG(e / m->diag <= 1e-12, "%s at 2^%d: result off by %.3g diagonals", conf_name[k], expo[j],
                            e / m->diag);
            }
            free(b);
        }
        free(a);
    }
    /* a finite pose whose displacement overflows */
    {
        dfm_deform_options o = conf(0);
        dfm_deform *d = NULL;
        double *out = (double *)malloc(3 * m->nv * sizeof(double));
        T_EQ_INT(dfm_deform_setup(m->pos, m->nv, m->idx, m->nt, m->roi, m->handle, &o, &d), DFM_OK);
        dfm_pose_identity(m->pos, m->nv, tg, rot);
        for (v = 0; v < m->nv; v++)
            if (m->handle[v]) tg[3 * v] = 1.7e308;
            else if (!m->roi[v]) tg[3 * v] = -1.7e308;
        for (i = 0; i < 3 * m->nv; i++) out[i] = 7.0;
        T_EQ_INT(dfm_deform_solve(d, tg, rot, out), DFM_ERR_NOT_FINITE);
        for (i = 0; i < 3 * m->nv && out[i] == 7.0; i++) continue;
        T_EQ_SIZE(i, 3 * m->nv); /* not written */
        dfm_deform_free(d);
        free(out);
    }
    /* an edge longer than a double holds */
    {
        unsigned char *seeds = (unsigned char *)calloc(m->nv, 1), *mask = (unsigned char *)malloc(m->nv);
        memcpy(spos, m->pos, 3 * m->nv * sizeof(double));
        for (v = 0; v < m->nv; v++) spos[3 * v] = (v & 1) ? 1.5e308 : -1.5e308;
        seeds[0] = 1;
        T_EQ_INT(dfm_roi_geodesic(spos, m->nv, m->idx, m->nt, seeds, 1e308, mask, NULL), DFM_ERR_NOT_FINITE);
        free(seeds);
        free(mask);
    }
    free(tg);
    free(rot);
    free(spos);
    free(stg);
}

int main(int argc, char **argv)
{
    tube m;
    T_BEGIN(argc, argv);
    m = make_tube(30, 16, 4.0, 0.05);
    test_zero_motion(&m);
    test_translation(&m);
    test_rigid_motion(&m);
    test_origin_independence(&m);
    test_scale(&m);
    test_soft_to_hard(&m);
    test_frame_choice(&m);
    test_bend_quality();
    test_rigid_steps();
    test_refine_and_lone_vertex(&m);
    test_polar();
    test_single_rotation_path(&m);
    test_helpers(&m);
    test_bad_input(&m);
    test_progress(&m);
    test_alloc_failures();
    test_cotan_floor();
    free_tube(&m);
    return T_END();
}
