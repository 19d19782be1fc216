/* test_dispmesh_catch.c - dispmesh.h: two checks with tight, derived bounds on generated meshes, no
   package needed (issue 21 point 8), for bugs that were caught only on the bunny or by the Embree
   reference:
   1. Placement: every collapse of dm_simplify, replayed from the progressive-mesh records, puts keep
      where the test's own double-precision solve of the summed quadrics (or, where the library's rule
      takes its fallback, the best point of the edge) puts it, to within float rounding. A simplified
      box keeps its eight corners bit for bit. (Planted bug: the collapsed vertex at the edge's
      midpoint instead of the solved position.)
   2. Bake depth: the original is the box [-1,1]^3, whose triangles lie exactly in its face planes
      (no interpolation error), so the depth along each valid texel's line p - t n (p, n the map's own
      pos and nrm) is the ray/box slab entry in closed form; every baked depth matches it to within
      float rounding. Two bases: a coarse box at 1.25 and a simplified sphere of radius 2.5. (Planted
      bug: a constant 1e-3 x search distance added to every depth.) */
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#include "test.h"
#include "testmesh.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>

#define U_D 1.1102230246251565e-16 /* 2^-53, the unit roundoff of double */
#define U_F 5.9604644775390625e-08 /* 2^-24, float's: |fl(x) - x| <= U_F |x| (normal range) */

/* A box: the cube-sphere's topology with every vertex pushed from the sphere to the cube of
   half-side h along its ray (s / max|s_i|). The largest coordinate divides to exactly 1, so each
   face's vertices have that coordinate exactly +-h: the faces are exactly planar and the eight
   corners are exactly (+-h, +-h, +-h). */
static mesh make_box(int n, float h)
{
    mesh m = make_sphere(n, 0.0, 1.0);
    size_t v;
    for (v = 0; v < m.nv; v++) {
        float *p = m.p + 3 * v, mx = fabsf(p[0]);
        int k;
        if (fabsf(p[1]) > mx) mx = fabsf(p[1]);
        if (fabsf(p[2]) > mx) mx = fabsf(p[2]);
        for (k = 0; k < 3; k++) p[k] = p[k] / mx * h;
    }
    return m;
}

/* ---- 1. placement ---------------------------------------------------------------------------- */

/* Q(x) = x^T A x + 2 b^T x + c as dispmesh.h defines it (A = a00 a01 a02 a11 a12 a22), in world
   coordinates, with the number of planes summed into it. */
typedef struct quad { double a[6], b[3], c; double n; } quad;

static void quad_sum(quad *r, const quad *x, const quad *y)
{
    int k;
    for (k = 0; k < 6; k++) r->a[k] = x->a[k] + y->a[k];
    for (k = 0; k < 3; k++) r->b[k] = x->b[k] + y->b[k];
    r->c = x->c + y->c;
    r->n = x->n + y->n;
}

static void quad_mul(const quad *q, const double e[3], double o[3])
{
    o[0] = q->a[0] * e[0] + q->a[1] * e[1] + q->a[2] * e[2];
    o[1] = q->a[1] * e[0] + q->a[3] * e[1] + q->a[4] * e[2];
    o[2] = q->a[2] * e[0] + q->a[4] * e[1] + q->a[5] * e[2];
}

static double quad_eval(const quad *q, const double x[3])
{
    double ax[3];
    quad_mul(q, x, ax);
    return x[0] * (ax[0] + 2.0 * q->b[0]) + x[1] * (ax[1] + 2.0 * q->b[1]) + x[2] * (ax[2] + 2.0 * q->b[2]) + q->c;
}

/* Per input vertex: the area-weighted planes of its triangles (PART 2's quadrics). The library
   computes them in a frame centred and scaled by the box's largest side; the weights there are
   these over scale^2, which changes neither the minimiser nor any test below (det / trace^3 and
   the distance ratio are scale-free). */
static quad *initial_quadrics(const mesh *m)
{
    quad *q = (quad *)calloc(m->nv, sizeof(quad));
    size_t t;
    for (t = 0; t < m->nt; t++) {
        const uint32_t *tr = m->t + 3 * t;
        const float *p0 = m->p + 3 * tr[0], *p1 = m->p + 3 * tr[1], *p2 = m->p + 3 * tr[2];
        double e[3], f[3], nr[3], len, d, w;
        int k, j;
        for (k = 0; k < 3; k++) {
            e[k] = (double)p1[k] - p0[k];
            f[k] = (double)p2[k] - p0[k];
        }
        nr[0] = e[1] * f[2] - e[2] * f[1];
        nr[1] = e[2] * f[0] - e[0] * f[2];
        nr[2] = e[0] * f[1] - e[1] * f[0];
        len = sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
        if (!(len > 0.0)) continue;
        for (k = 0; k < 3; k++) nr[k] /= len;
        d = -(nr[0] * p0[0] + nr[1] * p0[1] + nr[2] * p0[2]);
        w = 0.5 * len;
        for (j = 0; j < 3; j++) {
            quad *o = q + tr[j];
            o->a[0] += w * nr[0] * nr[0]; o->a[1] += w * nr[0] * nr[1]; o->a[2] += w * nr[0] * nr[2];
            o->a[3] += w * nr[1] * nr[1]; o->a[4] += w * nr[1] * nr[2]; o->a[5] += w * nr[2] * nr[2];
            for (k = 0; k < 3; k++) o->b[k] += w * d * nr[k];
            o->c += w * d * d;
            o->n += 1.0;
        }
    }
    return q;
}

typedef struct place_stats {
    size_t collapses, solved, edge, skipped, bad, keep_mismatch;
    double worst_ratio;  /* largest |library - test| / bound over all checked coordinates */
    double worst_dev;    /* the deviation there (world units) */
    double mid_gap;      /* largest |solve - midpoint| of the solved collapses: what the bug would move */
    double max_tol;      /* the largest bound of a checked coordinate */
} place_stats;

/* Replays the records of pm (made from m with no constraint, closed manifold m: no boundary, locked
   or frozen vertex, so every collapse is PART 2's free placement) and checks each position. */
static place_stats check_placements(const mesh *m, dm_pm *pm)
{
    place_stats st;
    size_t S = dm_pm_split_count(pm), i, v;
    quad *q = initial_quadrics(m);
    float *pos = (float *)malloc(m->nv * 3 * sizeof(float));
    double scale = 0.0, lo[3], hi[3];
    int k;
    memset(&st, 0, sizeof st);
    memcpy(pos, m->p, m->nv * 3 * sizeof(float));
    for (k = 0; k < 3; k++) lo[k] = hi[k] = m->p[k];
    for (v = 0; v < m->nv; v++)
        for (k = 0; k < 3; k++) {
            if (m->p[3 * v + k] < lo[k]) lo[k] = m->p[3 * v + k];
            if (m->p[3 * v + k] > hi[k]) hi[k] = m->p[3 * v + k];
        }
    for (k = 0; k < 3; k++) if (hi[k] - lo[k] > scale) scale = hi[k] - lo[k];
    for (i = 0; i < S; i++) {
        dm_vsplit vs;
        quad Q;
        double p0[3], p1[3], e[3], x[3], tol[3], len2 = 0.0, tr, det, c[6];
        double na, nb, mag = 0.0;
        int have = 0, skip = 0, j;
        uint32_t lo_id, hi_id;
        if (!dm_pm_get_vsplit(pm, S - 1 - i, &vs) || vs.keep >= m->nv || vs.remove >= m->nv) { st.bad++; break; }
        st.collapses++;
        if (memcmp(vs.keep_position, pos + 3 * (size_t)vs.keep, sizeof vs.keep_position) != 0) st.keep_mismatch++;
        quad_sum(&Q, q + vs.keep, q + vs.remove);
        /* the library's edge (a, b) has a < b */
        lo_id = vs.keep < vs.remove ? vs.keep : vs.remove;
        hi_id = vs.keep < vs.remove ? vs.remove : vs.keep;
        for (k = 0; k < 3; k++) {
            p0[k] = pos[3 * (size_t)lo_id + k];
            p1[k] = pos[3 * (size_t)hi_id + k];
            e[k] = p1[k] - p0[k];
            len2 += e[k] * e[k];
            if (fabs(p0[k]) > mag) mag = fabs(p0[k]);
            if (fabs(p1[k]) > mag) mag = fabs(p1[k]);
        }
        mag += scale; /* the library works relative to the box centre, scaled by `scale` */
        c[0] = Q.a[3] * Q.a[5] - Q.a[4] * Q.a[4];
        c[1] = Q.a[2] * Q.a[4] - Q.a[1] * Q.a[5];
        c[2] = Q.a[1] * Q.a[4] - Q.a[2] * Q.a[3];
        c[3] = Q.a[0] * Q.a[5] - Q.a[2] * Q.a[2];
        c[4] = Q.a[1] * Q.a[2] - Q.a[0] * Q.a[4];
        c[5] = Q.a[0] * Q.a[3] - Q.a[1] * Q.a[1];
        det = Q.a[0] * c[0] + Q.a[1] * c[1] + Q.a[2] * c[2];
        tr = Q.a[0] + Q.a[3] + Q.a[5];
        /* The library solves when det > 1e-7 tr^3 and the solution lies within two edge lengths of
           the midpoint; otherwise it takes the best point of the edge. Candidates within a factor
           2 of the first threshold or 10% of the second could go either way under rounding: skipped. */
        if (tr > 0.0 && det > 2e-7 * tr * tr * tr) {
            double o[3], d2 = 0.0, fa = 0.0, fi = 0.0, kappa, ob = 0.0;
            o[0] = -(c[0] * Q.b[0] + c[1] * Q.b[1] + c[2] * Q.b[2]) / det;
            o[1] = -(c[1] * Q.b[0] + c[3] * Q.b[1] + c[4] * Q.b[2]) / det;
            o[2] = -(c[2] * Q.b[0] + c[4] * Q.b[1] + c[5] * Q.b[2]) / det;
            for (k = 0; k < 3; k++) {
                double mk = o[k] - 0.5 * (p0[k] + p1[k]);
                d2 += mk * mk;
            }
            if (d2 <= 3.6 * len2) {
                /* Bound per coordinate: the library rounds its double result to float (at most
                   U_F |x_k|), plus the double-precision difference of two solves of the same system
                   summed in another order and frame. Each entry of A and b is a sum of Q.n terms
                   with |terms| summing to at most tr (A is positive semi-definite with unit normals)
                   and tr * mag (b; |d| <= mag): perturbations dA <= 2 n u tr, db <= 2 n u tr mag
                   per side. First-order perturbation of A x = -b: |dx| <= kappa (|dA|/|A| |x| +
                   |db|/|A|), kappa = |A|_F |A^-1|_F >= the 2-norm condition number, |A| >= tr / 3.
                   Times 4 for the two sides and the frame's own rounding (centre, scale). */
                for (j = 0; j < 6; j++) {
                    double w = (j == 1 || j == 2 || j == 4) ? 2.0 : 1.0;
                    fa += w * Q.a[j] * Q.a[j];
                    fi += w * c[j] * c[j];
                }
                kappa = sqrt(fa) * sqrt(fi) / fabs(det);
                for (k = 0; k < 3; k++) if (fabs(o[k]) > ob) ob = fabs(o[k]);
                for (k = 0; k < 3; k++) {
                    x[k] = o[k];
                    tol[k] = U_F * fabs(o[k]) + 4.0 * kappa * 3.0 * 2.0 * Q.n * U_D * (ob + mag) + 1e-30;
                }
                {
                    double g = 0.0;
                    for (k = 0; k < 3; k++) {
                        double mk = o[k] - 0.5 * (p0[k] + p1[k]);
                        g += mk * mk;
                    }
                    if (sqrt(g) > st.mid_gap) st.mid_gap = sqrt(g);
                }
                have = 1;
                st.solved++;
            } else if (d2 < 4.4 * len2) {
                skip = 1;
            }
        } else if (tr > 0.0 && det > 0.5e-7 * tr * tr * tr) {
            skip = 1;
        }
        if (!have && !skip) {
            /* the best point of the edge: t = num / den clamped to [0, 1], the 1-D minimiser of
               Q(p0 + t e). Bound: fl(x) as above, plus t's double error (num and den are sums of
               Q.n-term entries times |p| <= mag and |e|: relative 2 n u each, 4 for both sides),
               moved by |e|. A den at rounding level (e in A's null space: an edge along a flat
               face or a crease) makes every point of the edge as good: then either end is right
               (the library compares the two ends' values, which tie there). */
            double ae[3], num, den, t, nabs, l = sqrt(len2);
            quad_mul(&Q, e, ae);
            den = e[0] * ae[0] + e[1] * ae[1] + e[2] * ae[2];
            num = -(ae[0] * p0[0] + ae[1] * p0[1] + ae[2] * p0[2] + Q.b[0] * e[0] + Q.b[1] * e[1] + Q.b[2] * e[2]);
            nabs = 2.0 * Q.n * U_D * 4.0 * tr * l * (mag + l) * 3.0;
            if (!(den > nabs)) {
                /* either end: pick the nearer to what the library did */
                double dk0 = 0.0, dk1 = 0.0;
                for (k = 0; k < 3; k++) {
                    dk0 += fabs((double)vs.merged_position[k] - p0[k]);
                    dk1 += fabs((double)vs.merged_position[k] - p1[k]);
                }
                t = dk0 <= dk1 ? 0.0 : 1.0;
                na = 0.0;
                nb = fabs(quad_eval(&Q, p0) - quad_eval(&Q, p1)) > 1e3 * Q.n * U_D * tr * mag * mag ? 1.0 : 0.0;
                if (nb) skip = 1; /* the ends differ but den is tiny: not a case the test can call */
            } else {
                t = num > 0.0 ? (num < den ? num / den : 1.0) : 0.0;
                na = nabs / den + (fabs(num) + nabs) * nabs / (den * den); /* |dt| */
                nb = 0.0;
            }
            if (!skip) {
                for (k = 0; k < 3; k++) {
                    x[k] = p0[k] + t * e[k];
                    tol[k] = U_F * fabs(x[k]) + na * l + 2.0 * U_D * mag + 1e-30;
                }
                have = 1;
                st.edge++;
            }
        }
        if (skip) st.skipped++;
        if (have) {
            for (k = 0; k < 3; k++) {
                double dev = fabs((double)vs.merged_position[k] - x[k]), ratio = dev / tol[k];
                if (ratio > st.worst_ratio) { st.worst_ratio = ratio; st.worst_dev = dev; }
                if (tol[k] > st.max_tol) st.max_tol = tol[k];
            }
        }
        /* apply the collapse as the library did */
        quad_sum(q + vs.keep, q + vs.keep, q + vs.remove);
        memcpy(pos + 3 * (size_t)vs.keep, vs.merged_position, sizeof vs.merged_position);
    }
    free(q);
    free(pos);
    return st;
}

static void placement_case(const char *name, mesh *m, size_t target, size_t min_solved)
{
    dm_simplify_options so;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    memset(&so, 0, sizeof so);
    so.target_triangles = target;
    T_EQ_INT(dm_simplify(m->p, m->nv, m->t, m->nt, &so, &pm, &rep), DM_OK);
    if (!pm) return;
    {
        place_stats st = check_placements(m, pm);
        printf("placement %s: %zu triangles -> %zu, %zu collapses: %zu solved, %zu on the edge, %zu skipped "
               "(threshold); worst |library - test| = %.3g = %.3g x its bound (bounds up to %.3g); largest |solve - "
               "midpoint| %.3g\n",
               name, m->nt, rep.triangle_count, st.collapses, st.solved, st.edge, st.skipped, st.worst_dev,
               st.worst_ratio, st.max_tol, st.mid_gap);
        T_EQ_SIZE(st.bad, 0);
        T_EQ_SIZE(st.collapses, rep.collapse_count);
        T_EQ_SIZE(st.keep_mismatch, 0);
        /* not vacuous: most collapses are checked, and enough of them in the solved branch */
        T_CHECK_MSG(st.skipped * 20 <= st.collapses, "%s: %zu of %zu skipped", name, st.skipped, st.collapses);
        T_CHECK_MSG(st.solved >= min_solved, "%s: %zu solved collapses", name, st.solved);
        T_CHECK_MSG(st.worst_ratio <= 1.0, "%s: a position %.3g off the test's solve, %.3g x its bound", name,
                    st.worst_dev, st.worst_ratio);
    }
    dm_pm_free(pm);
}

/* The simplified box: its eight corners are vertices of the base, bit for bit (three planes meet
   there at one point; every collapse into a corner solves to it), and every base vertex lies on the
   box (one coordinate exactly +-1: a collapse inside a face or along an edge stays in its planes). */
static void box_corners(void)
{
    mesh m = make_box(8, 1.0f);
    dm_simplify_options so;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    memset(&so, 0, sizeof so);
    so.target_triangles = 12; /* a box's fewest: every zero-cost collapse (flat faces, straight edges) is
                                 done before any at a corner costs something */
    T_EQ_INT(dm_simplify(m.p, m.nv, m.t, m.nt, &so, &pm, &rep), DM_OK);
    if (pm) {
        size_t bnv, bnt, v, corners = 0, off_box = 0;
        float *bp;
        uint32_t *bt;
        int c;
        dm_pm_counts(pm, &bnv, &bnt);
        bp = (float *)malloc((bnv + 1) * 3 * sizeof(float));
        bt = (uint32_t *)malloc((bnt + 1) * 3 * sizeof(uint32_t));
        dm_pm_get_mesh(pm, bp, bt, NULL);
        for (c = 0; c < 8; c++) {
            float want[3];
            want[0] = (c & 1) ? 1.0f : -1.0f;
            want[1] = (c & 2) ? 1.0f : -1.0f;
            want[2] = (c & 4) ? 1.0f : -1.0f;
            for (v = 0; v < bnv; v++)
                if (bp[3 * v] == want[0] && bp[3 * v + 1] == want[1] && bp[3 * v + 2] == want[2]) { corners++; break; }
        }
        for (v = 0; v < bnv; v++)
            off_box += !(fabsf(bp[3 * v]) == 1.0f || fabsf(bp[3 * v + 1]) == 1.0f || fabsf(bp[3 * v + 2]) == 1.0f) ||
                       fabsf(bp[3 * v]) > 1.0f || fabsf(bp[3 * v + 1]) > 1.0f || fabsf(bp[3 * v + 2]) > 1.0f;
        printf("box corners: %zu triangles -> %zu (%zu vertices): %zu of 8 corners kept exactly, %zu vertices off "
               "the box\n", m.nt, bnt, bnv, corners, off_box);
        T_EQ_SIZE(corners, 8);
        T_EQ_SIZE(off_box, 0);
        T_EQ_SIZE(bnt, 12);
        free(bp);
        free(bt);
        dm_pm_free(pm);
    }
    mesh_free(&m);
}

/* ---- 2. bake depth --------------------------------------------------------------------------- */

/* The line o + s d, d = -nrm, enters the box [-1,1]^3 at s = max over axes of the slab's nearer
   crossing (the base is outside the box, so s > 0 and it is the crossing nearest to o either
   way). Returns the entry s and the axis it is on; -1 when the line misses the box. */
static double slab_entry(const double o[3], const double d[3], int *axis)
{
    double tn = -INFINITY, tf = INFINITY;
    int k;
    *axis = -1;
    for (k = 0; k < 3; k++) {
        double t1, t2;
        if (d[k] == 0.0) {
            if (o[k] < -1.0 || o[k] > 1.0) return -1.0;
            continue;
        }
        t1 = (-1.0 - o[k]) / d[k];
        t2 = (1.0 - o[k]) / d[k];
        if (t1 > t2) { double s = t1; t1 = t2; t2 = s; }
        if (t1 > tn) { tn = t1; *axis = k; }
        if (t2 < tf) tf = t2;
    }
    return tn <= tf && tn > 0.0 ? tn : -1.0;
}

static void bake_case(const char *name, const mesh *base, const mesh *orig, float max_distance, int res)
{
    dm_param_options po;
    dm_bake_options bo;
    dm_param *pm = NULL;
    dm_dispmap *map = NULL;
    memset(&po, 0, sizeof po);
    po.width = po.height = res;
    T_EQ_INT(dm_parameterize(base->p, base->nv, base->t, base->nt, &po, &pm), DM_OK);
    if (!pm) return;
    memset(&bo, 0, sizeof bo);
    bo.max_distance = max_distance;
    T_EQ_INT(dm_bake(pm, base->p, base->nv, base->t, base->nt, orig->p, orig->nv, orig->t, orig->nt, &bo, &map), DM_OK);
    if (map) {
        size_t i, n = (size_t)res * res, covered = 0, checked = 0, no_entry = 0;
        double worst_ratio = 0.0, worst_dev = 0.0, worst_signed = 0.0, max_dev = 0.0, tmin = INFINITY, tmax = 0.0;
        for (i = 0; i < n; i++) {
            double o[3], d[3], t, tol, dev;
            int k, axis;
            covered += pm->texel_triangle[i] != DM_NO_HIT;
            if (!map->valid[i]) continue;
            for (k = 0; k < 3; k++) {
                o[k] = map->pos[3 * i + k];
                d[k] = -(double)map->nrm[3 * i + k];
            }
            t = slab_entry(o, d, &axis);
            if (t < 0.0) { no_entry++; continue; }
            /* Bound: the library's t is the crossing of its float ray (these same o, d) with the
               hit triangle's plane, exactly the face plane (the face's vertices share that
               coordinate exactly, so the plane's normal has two exact zeros), computed in double
               (a few ulps of the operands: 8 u (|o| + |t|) / |d_axis|, as the slab's one division
               and subtraction are here too) and rounded to float (U_F |t|). */
            tol = U_F * fabs(t) + 8.0 * U_D * (fabs(o[axis]) + 1.0 + fabs(t)) / fabs(d[axis]) * 2.0;
            dev = fabs((double)map->disp[i] - t);
            if (dev / tol > worst_ratio) { worst_ratio = dev / tol; worst_dev = dev; worst_signed = map->disp[i] - t; }
            if (dev > max_dev) max_dev = dev;
            if (t < tmin) tmin = t;
            if (t > tmax) tmax = t;
            checked++;
        }
        printf("bake %s: %zu base triangles, %dx%d map, search %.4g: %zu of %zu covered texels valid and checked, "
               "depths %.4g..%.4g; worst |disp - analytic| = %.3g (signed %.3g) = %.3g x its bound (max %.3g); "
               "the planted offset would be %.3g\n",
               name, base->nt, res, res, (double)map->max_distance, checked, covered, tmin, tmax, worst_dev, worst_signed,
               worst_ratio, max_dev, 1e-3 * map->max_distance);
        T_EQ_SIZE(no_entry, 0);
        T_EQ_SIZE(map->miss_count, 0);
        /* not vacuous: every covered texel is a hit (the base encloses the box, and every line meets it) */
        T_CHECK_MSG(checked == covered && covered > n / 4, "%s: %zu checked of %zu covered", name, checked, covered);
        T_CHECK_MSG(worst_ratio <= 1.0, "%s: a depth %.3g off the analytic one, %.3g x its bound", name, worst_dev,
                    worst_ratio);
        dm_dispmap_free(map);
    }
    dm_param_free(pm);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    {
        mesh s = make_sphere(12, 0.1, 1.0), t = make_torus(48, 16, 0.35, 0.1), b = make_box(8, 1.0f);
        placement_case("bumpy sphere", &s, 60, 100);
        placement_case("bumpy torus", &t, 80, 100);
        placement_case("box", &b, 0, 8);
        mesh_free(&s);
        mesh_free(&t);
        mesh_free(&b);
    }
    box_corners();
    {
        mesh orig = make_box(16, 1.0f), coarse = make_box(2, 1.25f), sph = make_sphere(16, 0.0, 2.5);
        dm_simplify_options so;
        dm_pm *pm = NULL;
        bake_case("box 1.25 over box 1", &coarse, &orig, 0.5f, 256);
        memset(&so, 0, sizeof so);
        so.target_triangles = 120;
        T_EQ_INT(dm_simplify(sph.p, sph.nv, sph.t, sph.nt, &so, &pm, NULL), DM_OK);
        if (pm) {
            mesh base;
            dm_pm_counts(pm, &base.nv, &base.nt);
            base.p = (float *)malloc(base.nv * 3 * sizeof(float));
            base.t = (uint32_t *)malloc(base.nt * 3 * sizeof(uint32_t));
            dm_pm_get_mesh(pm, base.p, base.t, NULL);
            bake_case("simplified sphere 2.5 over box 1", &base, &orig, 2.0f, 256);
            mesh_free(&base);
            dm_pm_free(pm);
        }
        mesh_free(&orig);
        mesh_free(&coarse);
        mesh_free(&sph);
    }
    return T_END();
}
