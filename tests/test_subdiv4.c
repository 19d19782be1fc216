/* test_subdiv4.c - unit tests of subdiv4.h: four-point curves and grids (interpolation, polynomial
   reproduction, commutation, closed curves, the basis function of paper note 001), the terrain
   pipeline (epsilon, conformity, determinism) and butterfly (counts, kept vertices, planes,
   non-manifold input, errors, allocation failures, cancel). OpenMesh comparison: ref_openmesh_butterfly.
   Hardening (issue 21): finite input whose result overflows (curve w 1e308, two grid nodes at
   1e308, random heights 1e308 smoothed, terrain w 1e308, butterfly w 1e300) gives
   SD4_ERR_NOT_FINITE; a divergent terrain (mountain6, w 0.5) is refused with SD4_ERR_TOO_LARGE
   and max_triangles is the exact count; butterfly's search and stencil steps (the SD4_COUNT_OPS
   hook) on fans of 20k / 40k / 80k triangles grow at most 6x; the ZSS stencils reproduce
   quadratics at the spoke midpoints of regular planar fans of valence 3..200 within 1e-6; every
   new point of a flipped icosphere with valences 3..12 matches the DLG / ZSS formulas written out
   here within 1e-6. */
#include <stdlib.h>
#include <string.h>
#include <math.h>
static unsigned long long g_ops; /* subdiv4.h's test hook: steps of its searches and stencils */
#define SD4_COUNT_OPS(n) (g_ops += (unsigned long long)(n))
#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#include "test.h"
#include "hashrand.h"

static double cubic(double t) { return 0.3 * t * t * t - 1.7 * t * t + 2.0 * t - 5.0; }

/* refine a curve, allocating the output */
static double *refine_curve(const double *p, size_t n, int dim, double w, int levels, const sd4_options *o, size_t *m)
{
    double *out;
    int closed = o && o->end_rule == SD4_END_PERIODIC;
    if (sd4_curve_size(n, closed, levels, m) != SD4_OK) return NULL;
    out = (double *)malloc(*m * (size_t)dim * sizeof(double));
    if (out && sd4_curve_refine(p, n, dim, w, levels, o, out, *m) != SD4_OK) { free(out); return NULL; }
    return out;
}

static void test_curves(void)
{
    double p[3 * 12], *r, w;
    size_t n = 12, m, i;
    int k, levels = 4, rule;
    sd4_options o;
    memset(&o, 0, sizeof o);
    /* old points are kept exactly: open and closed, 2D and 3D, several w */
    for (i = 0; i < 3 * n; i++) p[i] = 10.0 * unit_random(i, 0) - 5.0;
    for (rule = 0; rule < 3; rule++)
        for (k = 2; k <= 3; k++) {
            int exact = 1;
            o.end_rule = rule;
            w = 0.05 + 0.1 * rule;
            r = refine_curve(p, n, k, w, levels, &o, &m);
            T_CHECK(r != NULL);
            if (!r) continue;
            T_EQ_SIZE(m, rule == SD4_END_PERIODIC ? n << levels : ((n - 1) << levels) + 1);
            for (i = 0; i < n; i++)
                if (memcmp(r + (i << levels) * (size_t)k, p + i * (size_t)k, (size_t)k * sizeof(double)) != 0) exact = 0;
            T_CHECK_MSG(exact, "old points kept, rule %d dim %d", rule, k);
            free(r);
        }
    /* w = 1/16 reproduces cubics at interior points (linear end rule) and everywhere (cubic rule) */
    for (i = 0; i < n; i++) { p[2 * i] = (double)i; p[2 * i + 1] = cubic((double)i); }
    for (rule = 0; rule < 2; rule++) {
        double worst = 0.0;
        o.end_rule = rule;
        r = refine_curve(p, n, 2, 1.0 / 16.0, levels, &o, &m);
        T_CHECK(r != NULL);
        if (!r) continue;
        for (i = 0; i < m; i++) {
            double t = (double)i / (double)(1 << levels), e;
            if (rule == SD4_END_LINEAR && (t < 2.0 || t > (double)n - 3.0)) continue; /* near the ends */
            e = fabs(r[2 * i + 1] - cubic(t)) / fmax(1.0, fabs(cubic(t)));
            if (fabs(r[2 * i] - t) > worst) worst = fabs(r[2 * i] - t);
            if (e > worst) worst = e;
        }
        T_CHECK_MSG(worst <= 1e-12, "cubic reproduction rule %d: %g", rule, worst);
        free(r);
    }
    /* any w reproduces linear functions, with either end rule, everywhere */
    for (k = 0; k < 6; k++) {
        double worst = 0.0;
        w = -0.2 + 0.1 * k;
        for (i = 0; i < n; i++) { p[3 * i] = 2.0 * (double)i - 1.0; p[3 * i + 1] = -0.5 * (double)i + 3.0; p[3 * i + 2] = 7.0; }
        o.end_rule = k % 2;
        r = refine_curve(p, n, 3, w, levels, &o, &m);
        T_CHECK(r != NULL);
        if (!r) continue;
        for (i = 0; i < m; i++) {
            double t = (double)i / (double)(1 << levels);
            worst = fmax(worst, fabs(r[3 * i] - (2.0 * t - 1.0)));
            worst = fmax(worst, fabs(r[3 * i + 1] - (-0.5 * t + 3.0)));
            worst = fmax(worst, fabs(r[3 * i + 2] - 7.0));
        }
        T_CHECK_MSG(worst <= 1e-12, "linear reproduction w=%g: %g", w, worst);
        free(r);
    }
    /* closed curves stay closed: starting the polygon at another point rotates the result */
    {
        double q[2 * 12], *r2, worst = 0.0;
        o.end_rule = SD4_END_PERIODIC;
        for (i = 0; i < n; i++) {
            p[2 * i] = cos(6.283185307179586 * (double)i / (double)n) * (1.0 + 0.3 * unit_random(i, 1));
            p[2 * i + 1] = sin(6.283185307179586 * (double)i / (double)n);
        }
        for (i = 0; i < n; i++) { q[2 * i] = p[2 * ((i + 5) % n)]; q[2 * i + 1] = p[2 * ((i + 5) % n) + 1]; }
        r = refine_curve(p, n, 2, 0.1, levels, &o, &m);
        r2 = refine_curve(q, n, 2, 0.1, levels, &o, &m);
        T_CHECK(r && r2);
        if (r && r2) {
            for (i = 0; i < m; i++) {
                size_t j = (i + (5u << levels)) % m;
                worst = fmax(worst, fabs(r2[2 * i] - r[2 * j]) + fabs(r2[2 * i + 1] - r[2 * j + 1]));
            }
            T_CHECK_MSG(worst <= 1e-12, "closed curve rotation: %g", worst);
            /* the closing segment was refined too: the point after the last old one is the rule's */
            {
                size_t last = (n - 1) << levels, half = (size_t)1 << (levels - 1);
                T_CHECK(fabs(r[2 * (last + half)] - r[2 * ((last + half) % m)]) == 0.0 && last + half < m);
            }
        }
        free(r);
        free(r2);
    }
    /* omega_per_level: two levels with (a, b) = one level with a, then one with b */
    {
        double per[2] = {0.12, -0.03}, *one, *two, *both, worst = 0.0;
        size_t m1, m2, m3;
        for (i = 0; i < n; i++) p[i] = unit_random(i, 3);
        memset(&o, 0, sizeof o);
        one = refine_curve(p, n, 1, per[0], 1, &o, &m1);
        two = one ? refine_curve(one, m1, 1, per[1], 1, &o, &m2) : NULL;
        o.omega_per_level = per;
        both = refine_curve(p, n, 1, 99.0, 2, &o, &m3);
        T_CHECK(two && both && m2 == m3);
        if (two && both)
            for (i = 0; i < m3; i++) worst = fmax(worst, fabs(two[i] - both[i]));
        T_CHECK_MSG(worst <= 1e-14, "per-level w: %g", worst);
        free(one); free(two); free(both);
        /* the OCR reading halves w */
        memset(&o, 0, sizeof o);
        one = refine_curve(p, n, 1, 0.2, 3, &o, &m1);
        o.omega_convention = SD4_OMEGA_HALF;
        two = refine_curve(p, n, 1, 0.4, 3, &o, &m2);
        T_CHECK(one && two && m1 == m2 && memcmp(one, two, m1 * sizeof(double)) == 0);
        free(one); free(two);
    }
}

/* Peak and trough of the basis function (a unit impulse refined 12 levels), paper note 001 §3.3. */
static void test_basis(void)
{
    static const struct { double w, max1, min1; } tab[] = {
        {0.0625, 1.0000, -0.0734}, {0.10, 1.0052, -0.1298}, {0.18, 1.0925, -0.2932}, {0.20, 1.1246, -0.3461},
        {0.25, 1.2098, -0.5072}};
    size_t t, i, m;
    double p[16];
    sd4_options o;
    memset(&o, 0, sizeof o);
    o.end_rule = SD4_END_PERIODIC;
    for (t = 0; t < sizeof tab / sizeof tab[0]; t++) {
        double *r, hi = -1e9, lo = 1e9;
        memset(p, 0, sizeof p);
        p[8] = 1.0;
        r = refine_curve(p, 16, 1, tab[t].w, 12, &o, &m);
        T_CHECK(r != NULL);
        if (!r) continue;
        for (i = 0; i < m; i++) { hi = fmax(hi, r[i]); lo = fmin(lo, r[i]); }
        T_NEAR(hi, tab[t].max1, 6e-4);
        T_NEAR(lo, tab[t].min1, 6e-4);
        if (tab[t].w == 0.25) { /* 2D: phi(x) phi(y) */
            T_NEAR(hi * hi, 1.4635, 1e-3);
            T_NEAR(hi * lo, -0.6136, 1e-3);
        }
        free(r);
    }
}

static int cancel_at_half(void *user, float done) { (void)user; return done >= 0.5f; }

static void test_grids(void)
{
    enum { NX = 7, NY = 5, DIM = 3, LV = 3 };
    double g[NX * NY * DIM], *a, *b, per[LV] = {0.1, 0.2, 0.0625};
    size_t W, H, i, j, total;
    sd4_options o;
    int rx, ry, exact;
    for (i = 0; i < NX * NY * DIM; i++) g[i] = 100.0 * unit_random(i, 4) - 50.0;
    /* rows-then-columns equals columns-then-rows, for every pair of border rules */
    for (rx = 0; rx < 3; rx++)
        for (ry = 0; ry < 3; ry++) {
            double worst = 0.0, scale = 0.0;
            memset(&o, 0, sizeof o);
            o.end_rule = rx;
            o.end_rule_y = ry;
            o.omega_per_level = (rx + ry) % 2 ? per : NULL;
            T_CHECK(sd4_grid_size(NX, NY, LV, &o, &W, &H) == SD4_OK);
            T_EQ_SIZE(W, rx == 2 ? NX << LV : ((NX - 1) << LV) + 1);
            T_EQ_SIZE(H, ry == 2 ? NY << LV : ((NY - 1) << LV) + 1);
            total = W * H * DIM;
            a = (double *)malloc(total * sizeof(double));
            b = (double *)malloc(total * sizeof(double));
            if (!a || !b) { T_CHECK(0); free(a); free(b); continue; }
            T_CHECK(sd4_grid_refine(g, NX, NY, DIM, 0.15, LV, &o, a, total) == SD4_OK);
            T_CHECK(sd4_grid_refine_columns_first(g, NX, NY, DIM, 0.15, LV, &o, b, total) == SD4_OK);
            for (i = 0; i < total; i++) { worst = fmax(worst, fabs(a[i] - b[i])); scale = fmax(scale, fabs(a[i])); }
            T_CHECK_MSG(worst <= 1e-13 * scale, "commutation rx %d ry %d: %g", rx, ry, worst);
            exact = 1;
            for (j = 0; j < NY; j++)
                for (i = 0; i < NX; i++)
                    if (memcmp(a + ((j << LV) * W + (i << LV)) * DIM, g + (j * NX + i) * DIM, DIM * sizeof(double))) exact = 0;
            T_CHECK(exact);
            free(a);
            free(b);
        }
    /* the cubic end rule at w = 1/16 reproduces products of cubics on the whole grid */
    {
        double h[NX * NY], worst = 0.0;
        memset(&o, 0, sizeof o);
        o.end_rule = o.end_rule_y = SD4_END_CUBIC;
        for (j = 0; j < NY; j++)
            for (i = 0; i < NX; i++) h[j * NX + i] = cubic((double)i) * cubic(0.5 * (double)j);
        sd4_grid_size(NX, NY, LV, &o, &W, &H);
        a = (double *)malloc(W * H * sizeof(double));
        T_CHECK(a && sd4_grid_refine(h, NX, NY, 1, 1.0 / 16.0, LV, &o, a, W * H) == SD4_OK);
        if (a)
            for (j = 0; j < H; j++)
                for (i = 0; i < W; i++) {
                    double x = (double)i / (1 << LV), y = (double)j / (1 << LV), f = cubic(x) * cubic(0.5 * y);
                    worst = fmax(worst, fabs(a[j * W + i] - f) / fmax(1.0, fabs(f)));
                }
        T_CHECK_MSG(worst <= 1e-12, "bicubic reproduction: %g", worst);
        free(a);
    }
    /* errors */
    {
        double out[1000], bad[4] = {0, 1, NAN, 3};
        memset(&o, 0, sizeof o);
        T_EQ_INT(sd4_grid_refine(g, NX, NY, DIM, 0.1, 2, NULL, out, 10), SD4_ERR_BUFFER_TOO_SMALL);
        T_EQ_INT(sd4_grid_refine(g, NX, NY, 0, 0.1, 2, NULL, out, 1000), SD4_ERR_INVALID_ARGUMENT);
        T_EQ_INT(sd4_grid_refine(NULL, NX, NY, 1, 0.1, 2, NULL, out, 1000), SD4_ERR_INVALID_ARGUMENT);
        T_EQ_INT(sd4_curve_refine(bad, 4, 1, 0.1, 2, NULL, out, 1000), SD4_ERR_BAD_POSITION);
        T_EQ_INT(sd4_curve_refine(g, 4, 1, NAN, 2, NULL, out, 1000), SD4_ERR_INVALID_ARGUMENT);
        T_EQ_INT(sd4_curve_size((size_t)-1 / 4, 0, 30, &W), SD4_ERR_TOO_LARGE);
        T_EQ_INT(sd4_curve_size(0, 0, 3, &W), SD4_ERR_INVALID_ARGUMENT);
        T_EQ_INT(sd4_curve_size(5, 0, 31, &W), SD4_ERR_INVALID_ARGUMENT);
        o.end_rule = 7;
        T_EQ_INT(sd4_grid_refine(g, NX, NY, 1, 0.1, 2, &o, out, 1000), SD4_ERR_INVALID_ARGUMENT);
        /* a single point and a two-point line */
        T_EQ_INT(sd4_curve_refine(g, 1, 2, 0.1, 3, NULL, out, 1000), SD4_OK);
        T_CHECK(out[0] == g[0] && out[1] == g[1]);
        T_EQ_INT(sd4_curve_refine(g, 2, 1, 0.3, 2, NULL, out, 5), SD4_OK);
        T_NEAR(out[2], 0.5 * (g[0] + g[1]), 1e-12); /* linear ghosts on both sides: the midpoint */
        T_CHECK(strcmp(sd4_result_string(SD4_ERR_TOO_LARGE), "SD4_ERR_TOO_LARGE") == 0);
        /* the progress callback cancels */
        o.end_rule = SD4_END_LINEAR;
        o.progress = cancel_at_half;
        T_EQ_INT(sd4_grid_refine(g, 3, 3, 1, 0.1, 3, &o, out, 1000), SD4_CANCELLED);
    }
}

/* ---- terrain ------------------------------------------------------------------------------- */

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

/* Every undirected edge is used by exactly two triangles in opposite directions, or by one
   triangle when both ends lie on the border x in {0, xmax} or z in {0, zmax} (same side).
   Returns the number of offending edges. */
static size_t nonconforming_edges(const sd4_mesh *m, double xmax, double zmax)
{
    size_t e = 3 * m->triangle_count, i = 0, bad = 0;
    uint64_t *keys = (uint64_t *)malloc(e * sizeof(uint64_t) + 1);
    if (!keys) return (size_t)-1;
    for (i = 0; i < e; i++) {
        uint64_t a = m->indices[i], b = m->indices[i % 3 == 2 ? i - 2 : i + 1];
        keys[i] = a < b ? (a << 33 | b << 1) : (b << 33 | a << 1 | 1);
    }
    qsort(keys, e, sizeof(uint64_t), cmp_u64);
    for (i = 0; i < e;) {
        size_t j = i;
        while (j < e && keys[j] >> 1 == keys[i] >> 1) j++;
        if (j - i == 2) {
            if ((keys[i] & 1) == (keys[i + 1] & 1)) bad++;
        } else if (j - i == 1) {
            const float *p = m->positions + 3 * (keys[i] >> 33), *q = m->positions + 3 * ((keys[i] >> 1) & 0xffffffffu);
            int onx = (p[0] == 0.0f && q[0] == 0.0f) || (p[0] == (float)xmax && q[0] == (float)xmax);
            int onz = (p[2] == 0.0f && q[2] == 0.0f) || (p[2] == (float)zmax && q[2] == (float)zmax);
            if (!onx && !onz) bad++;
        } else
            bad++;
        i = j;
    }
    free(keys);
    return bad;
}

static void test_terrain(void)
{
    const char *names[4] = {"desert", "vegetation", "mountain5", "mountain6"};
    sd4_terrain_desc d;
    sd4_mesh m, m2;
    size_t i, k;
    int p;
    /* a flat square of side 8 with epsilon 3: depth 2, 16 small quads, 25 vertices */
    {
        double h[4] = {0, 0, 0, 0};
        memset(&d, 0, sizeof d);
        d.heights = h; d.nx = d.ny = 2; d.spacing = 8.0; d.levels = 0; d.epsilon = 3.0; d.omega = 0.1;
        T_EQ_INT(sd4_terrain_build(&d, &m), SD4_OK);
        T_EQ_SIZE(m.triangle_count, 32);
        T_EQ_SIZE(m.vertex_count, 25);
        sd4_free_mesh(&m);
    }
    /* one steep cell beside flat ones: different depths meet, and no T-junction is left */
    {
        double h[8] = {0, 0, 0, 0, 0, 0, 30, 0};
        memset(&d, 0, sizeof d);
        d.heights = h; d.nx = 4; d.ny = 2; d.spacing = 8.0; d.levels = 0; d.epsilon = 3.0; d.omega = 0.1;
        T_EQ_INT(sd4_terrain_build(&d, &m), SD4_OK);
        T_EQ_SIZE(nonconforming_edges(&m, 24.0, 8.0), 0);
        T_CHECK(m.triangle_count > 32 * 3); /* the steep cells went deeper */
        sd4_free_mesh(&m);
    }
    for (p = 0; p < 4; p++) {
        double worst_edge = 0.0, min_ny = 1.0, normal_err = 0.0;
        T_EQ_INT(sd4_terrain_preset(names[p], &d), SD4_OK);
        d.levels = 3; /* smaller than the demo, same pipeline */
        T_EQ_INT(sd4_terrain_build(&d, &m), SD4_OK);
        T_CHECK(m.triangle_count > 0 && m.face_normals != NULL);
        T_EQ_SIZE(nonconforming_edges(&m, 512.0, 512.0), 0);
        for (i = 0; i < m.triangle_count; i++) {
            const uint32_t *t = m.indices + 3 * i;
            const float *n = m.face_normals + 3 * i;
            double e1[3], e2[3], cy;
            for (k = 0; k < 3; k++) {
                const float *a = m.positions + 3 * (size_t)t[k], *b = m.positions + 3 * (size_t)t[(k + 1) % 3];
                if (a[0] == b[0] || a[2] == b[2]) { /* a side of a small quad, not a half-diagonal */
                    double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
                    worst_edge = fmax(worst_edge, sqrt(dx * dx + dy * dy + dz * dz));
                }
            }
            for (k = 0; k < 3; k++) {
                e1[k] = (double)m.positions[3 * (size_t)t[1] + k] - m.positions[3 * (size_t)t[0] + k];
                e2[k] = (double)m.positions[3 * (size_t)t[2] + k] - m.positions[3 * (size_t)t[0] + k];
            }
            cy = e1[2] * e2[0] - e1[0] * e2[2]; /* y of e1 x e2: counter-clockwise seen from +y */
            min_ny = fmin(min_ny, cy);
            normal_err = fmax(normal_err, fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1.0));
        }
        T_CHECK_MSG(worst_edge <= d.epsilon * (1.0 + 1e-5), "%s: longest small-quad edge %g > epsilon %g", names[p],
                    worst_edge, d.epsilon);
        T_CHECK_MSG(min_ny > 0.0, "%s: a triangle faces down", names[p]);
        T_CHECK(normal_err < 1e-5);
        /* deterministic */
        T_EQ_INT(sd4_terrain_build(&d, &m2), SD4_OK);
        T_CHECK(m2.vertex_count == m.vertex_count && m2.triangle_count == m.triangle_count &&
                memcmp(m.positions, m2.positions, 12 * m.vertex_count) == 0 &&
                memcmp(m.face_normals, m2.face_normals, 12 * m.triangle_count) == 0);
        sd4_free_mesh(&m2);
        sd4_free_mesh(&m);
    }
    /* sigma 0 leaves the geometric normal; a larger sigma tilts normals more on average */
    {
        double tilt[2] = {0, 0};
        int s;
        for (s = 0; s < 2; s++) {
            sd4_terrain_preset("vegetation", &d);
            d.levels = 2;
            d.sigma = s ? 0.35 : 0.0;
            T_EQ_INT(sd4_terrain_build(&d, &m), SD4_OK);
            for (i = 0; i < m.triangle_count; i += 2) tilt[s] += acos(fmin(1.0, (double)m.face_normals[3 * i + 1]));
            tilt[s] /= (double)(m.triangle_count / 2 + 1);
            sd4_free_mesh(&m);
        }
        T_CHECK_MSG(tilt[1] > tilt[0] + 0.1, "mean tilt %g (sigma 0) vs %g (sigma 0.35)", tilt[0], tilt[1]);
    }
    {
        double h[4] = {0, NAN, 0, 0};
        memset(&d, 0, sizeof d);
        d.heights = h; d.nx = d.ny = 2; d.levels = 2; d.epsilon = 3.0; d.omega = 0.1;
        T_EQ_INT(sd4_terrain_build(&d, &m), SD4_ERR_BAD_POSITION);
        T_CHECK(m.positions == NULL && m.triangle_count == 0);
    }
    T_EQ_INT(sd4_terrain_preset("moon", &d), SD4_ERR_INVALID_ARGUMENT);
    sd4_terrain_preset("desert", &d);
    d.levels = 11;
    T_EQ_INT(sd4_terrain_build(&d, &m), SD4_ERR_INVALID_ARGUMENT);
    T_CHECK(m.positions == NULL);
}

/* ---- butterfly ----------------------------------------------------------------------------- */

/* a (cols x rows) torus: every vertex has valence 6 */
static void torus(int cols, int rows, float *pos, uint32_t *tri)
{
    int i, j;
    for (j = 0; j < rows; j++)
        for (i = 0; i < cols; i++) {
            double u = 6.283185307179586 * i / cols, v = 6.283185307179586 * j / rows;
            float *p = pos + 3 * (j * cols + i);
            p[0] = (float)((2.0 + cos(v)) * cos(u));
            p[1] = (float)((2.0 + cos(v)) * sin(u));
            p[2] = (float)sin(v);
        }
    for (j = 0; j < rows; j++)
        for (i = 0; i < cols; i++) {
            uint32_t a = (uint32_t)(j * cols + i), b = (uint32_t)(j * cols + (i + 1) % cols);
            uint32_t c = (uint32_t)(((j + 1) % rows) * cols + i), d = (uint32_t)(((j + 1) % rows) * cols + (i + 1) % cols);
            uint32_t *t = tri + 6 * (j * cols + i);
            t[0] = a; t[1] = b; t[2] = d; t[3] = a; t[4] = d; t[5] = c;
        }
}

static long g_allocs, g_frees, g_fail_at;
static void *count_alloc(void *user, size_t size)
{
    (void)user;
    if (g_fail_at >= 0 && g_allocs >= g_fail_at) return NULL;
    g_allocs++;
    return malloc(size);
}
static void count_free(void *user, void *p)
{
    (void)user;
    if (p) g_frees++;
    free(p);
}

static void test_butterfly(void)
{
    enum { C = 8, R = 6 };
    float pos[3 * C * R];
    uint32_t tri[6 * C * R];
    sd4_mesh m;
    size_t i;
    torus(C, R, pos, tri);
    /* closed mesh: V + E vertices, 4 T triangles per level, old vertices kept exactly */
    T_EQ_INT(sd4_butterfly(pos, C * R, tri, 2 * C * R, 2, 1.0 / 16.0, NULL, &m), SD4_OK);
    T_EQ_SIZE(m.triangle_count, 16 * 2 * C * R);
    T_EQ_SIZE(m.vertex_count, C * R + 3 * C * R + 4 * 3 * C * R); /* level 1: V + E; level 2: + 2 E1 ... */
    T_CHECK(memcmp(m.positions, pos, sizeof pos) == 0);
    sd4_free_mesh(&m);
    /* w = 0 on a regular mesh: new points are edge midpoints */
    T_EQ_INT(sd4_butterfly(pos, C * R, tri, 2 * C * R, 1, 0.0, NULL, &m), SD4_OK);
    {
        double worst = 0.0;
        for (i = 0; i < m.triangle_count; i += 4) { /* first child (v0, m0, m2) */
            const uint32_t *t = m.indices + 3 * i;
            int k;
            for (k = 0; k < 3; k++)
                worst = fmax(worst, fabs(m.positions[3 * (size_t)t[1] + k] -
                                         0.5f * (pos[3 * (size_t)tri[3 * (i / 4)] + k] + pos[3 * (size_t)tri[3 * (i / 4) + 1] + k])));
        }
        T_CHECK_MSG(worst < 1e-6, "midpoints at w = 0: %g", worst);
    }
    sd4_free_mesh(&m);
    /* a plane with a boundary and irregular vertices is reproduced (the scheme is affine) */
    {
        enum { N = 6 };
        float pp[3 * N * N];
        uint32_t tt[6 * (N - 1) * (N - 1)];
        int a, b, nt = 0;
        double worst = 0.0;
        for (b = 0; b < N; b++)
            for (a = 0; a < N; a++) {
                float x = (float)a + 0.3f * (float)unit_random((uint64_t)(b * N + a), 5), y = (float)b + 0.3f * (float)unit_random((uint64_t)(b * N + a), 6);
                pp[3 * (b * N + a)] = x; pp[3 * (b * N + a) + 1] = y; pp[3 * (b * N + a) + 2] = 0.5f * x - 0.25f * y + 1.0f;
            }
        for (b = 0; b + 1 < N; b++)
            for (a = 0; a + 1 < N; a++) { /* alternate diagonals: valences 4 and 8 inside */
                uint32_t v00 = (uint32_t)(b * N + a), v10 = v00 + 1, v01 = v00 + N, v11 = v01 + 1;
                if ((a + b) % 2) { uint32_t q[6] = {v00, v10, v11, v00, v11, v01}; memcpy(tt + 3 * nt, q, sizeof q); }
                else { uint32_t q[6] = {v00, v10, v01, v10, v11, v01}; memcpy(tt + 3 * nt, q, sizeof q); }
                nt += 2;
            }
        T_EQ_INT(sd4_butterfly(pp, N * N, tt, (size_t)nt, 2, 1.0 / 16.0, NULL, &m), SD4_OK);
        for (i = 0; i < m.vertex_count; i++) {
            const float *q = m.positions + 3 * i;
            worst = fmax(worst, fabs((double)q[2] - (0.5 * q[0] - 0.25 * q[1] + 1.0)));
        }
        T_CHECK_MSG(worst < 1e-5, "plane reproduction: %g", worst);
        T_EQ_SIZE(m.triangle_count, 16 * (size_t)nt);
        sd4_free_mesh(&m);
    }
    /* non-manifold: three triangles on one edge pass through, their neighbours stay conforming */
    {
        float pp[3 * 6] = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1, 1.5f, 1, 0};
        uint32_t tt[3 * 4] = {0, 1, 2, 1, 0, 3, 0, 1, 4, 1, 5, 2};
        size_t kept = 0;
        T_EQ_INT(sd4_butterfly(pp, 6, tt, 4, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
        for (i = 0; i < m.triangle_count; i++) {
            const uint32_t *t = m.indices + 3 * i;
            if ((t[0] == 0 && t[1] == 1) || (t[1] == 0 && t[2] == 1) || (t[2] == 0 && t[0] == 1) ||
                (t[0] == 1 && t[1] == 0) || (t[1] == 1 && t[2] == 0) || (t[2] == 1 && t[0] == 0))
                kept++;
        }
        T_EQ_SIZE(kept, 3);
        /* the fourth triangle touches vertex 1 of the non-manifold edge: frozen as well */
        T_EQ_SIZE(m.triangle_count, 4);
        T_EQ_SIZE(m.vertex_count, 6);
        sd4_free_mesh(&m);
    }
    /* a bowtie vertex (two fans at vertex 0): its triangles pass through; the triangle beside
       one of them has one unsplit edge and is split 1 -> 3 */
    {
        float pp[3 * 6] = {0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0, 1, 1, 0};
        uint32_t tt[3 * 3] = {0, 1, 2, 0, 3, 4, 2, 1, 5};
        T_EQ_INT(sd4_butterfly(pp, 6, tt, 3, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
        T_EQ_SIZE(m.triangle_count, 2 + 3);
        T_EQ_SIZE(m.vertex_count, 6 + 2);
        T_CHECK(memcmp(m.indices, tt, 6 * sizeof(uint32_t)) == 0);
        sd4_free_mesh(&m);
    }
    /* random soup on few vertices (non-manifold everywhere, degenerate triangles): never fails,
       indices stay in range, triangles that are not frozen are split */
    {
        float pp[3 * 12];
        uint32_t tt[3 * 40];
        int trial, bad = 0;
        for (trial = 0; trial < 200; trial++) {
            size_t nt = 1 + (size_t)(unit_random((uint64_t)trial, 7) * 40), nv = 3 + (size_t)(unit_random((uint64_t)trial, 8) * 9);
            for (i = 0; i < 3 * nv; i++) pp[i] = (float)unit_random((uint64_t)(trial * 100) + i, 9);
            for (i = 0; i < 3 * nt; i++) tt[i] = (uint32_t)(unit_random((uint64_t)(trial * 1000) + i, 10) * (double)nv);
            if (sd4_butterfly(pp, nv, tt, nt, 2, 1.0 / 16.0, NULL, &m) != SD4_OK) { bad++; continue; }
            for (i = 0; i < 3 * m.triangle_count; i++)
                if (m.indices[i] >= m.vertex_count) bad++;
            for (i = 0; i < 3 * m.vertex_count; i++)
                if (!isfinite(m.positions[i])) bad++;
            sd4_free_mesh(&m);
        }
        T_CHECK_MSG(bad == 0, "random soups: %d problems", bad);
    }
    /* a closed pillow (two triangles, valence 2) and a lone triangle (boundary only) */
    {
        float pp[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        uint32_t tt[6] = {0, 1, 2, 0, 2, 1};
        T_EQ_INT(sd4_butterfly(pp, 3, tt, 2, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
        T_EQ_SIZE(m.triangle_count, 8);
        sd4_free_mesh(&m);
        T_EQ_INT(sd4_butterfly(pp, 3, tt, 1, 3, 1.0 / 16.0, NULL, &m), SD4_OK);
        T_EQ_SIZE(m.triangle_count, 64);
        sd4_free_mesh(&m);
    }
    /* errors, allocation failures, cancellation */
    {
        sd4_allocator al = {count_alloc, count_free, NULL};
        sd4_options o;
        uint32_t badtri[3] = {0, 1, 999};
        float nanpos[9] = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
        uint32_t t1[3] = {0, 1, 2};
        long n;
        int fails = 0, leaks = 0;
        T_EQ_INT(sd4_butterfly(pos, C * R, badtri, 1, 1, 0.0625, NULL, &m), SD4_ERR_BAD_INDEX);
        T_EQ_INT(sd4_butterfly(nanpos, 3, t1, 1, 1, 0.0625, NULL, &m), SD4_ERR_BAD_POSITION);
        T_EQ_INT(sd4_butterfly(pos, C * R, tri, 2 * C * R, 0, 0.0625, NULL, &m), SD4_ERR_INVALID_ARGUMENT);
        T_CHECK(m.positions == NULL && m.triangle_count == 0);
        memset(&o, 0, sizeof o);
        o.allocator = &al;
        for (n = 0; n < 40; n++) {
            sd4_result r;
            g_allocs = g_frees = 0;
            g_fail_at = n;
            r = sd4_butterfly(pos, C * R, tri, 2 * C * R, 2, 0.0625, &o, &m);
            if (r == SD4_OK) sd4_free_mesh(&m);
            else if (r != SD4_ERR_OUT_OF_MEMORY) fails++;
            if (g_allocs != g_frees) leaks++;
        }
        T_CHECK_MSG(fails == 0 && leaks == 0, "allocation failures: %d wrong codes, %d leaks", fails, leaks);
        g_fail_at = -1;
        g_allocs = g_frees = 0;
        o.progress = cancel_at_half;
        T_EQ_INT(sd4_butterfly(pos, C * R, tri, 2 * C * R, 2, 0.0625, &o, &m), SD4_CANCELLED);
        T_CHECK(g_allocs == g_frees);
        /* terrain under failing allocation: no leak either */
        {
            sd4_terrain_desc d;
            sd4_mesh tm;
            leaks = 0;
            for (n = 0; n < 16; n++) {
                sd4_terrain_preset("mountain5", &d);
                d.levels = 1;
                d.allocator = &al;
                g_allocs = g_frees = 0;
                g_fail_at = n;
                if (sd4_terrain_build(&d, &tm) == SD4_OK) sd4_free_mesh(&tm);
                if (g_allocs != g_frees) leaks++;
            }
            g_fail_at = -1;
            T_CHECK(leaks == 0);
        }
    }
}

/* ---- finite input, results that are not: SD4_ERR_NOT_FINITE; bounded terrain ----------------- */

static void test_not_finite(void)
{
    double pts[2 * 5] = {0, 0, 1, 1, 2, -1, 3, 1, 4, 0}, out2[2 * 65], grid[16], fine[25 * 25], h[16];
    float pos[3 * 9];
    uint32_t tri[3 * 8];
    sd4_terrain_desc d;
    sd4_mesh m;
    int i, j;
    /* curve: w = 1e308 overflows (1/2 + w)(...) */
    T_EQ_INT(sd4_curve_refine(pts, 5, 2, 1e308, 4, NULL, out2, 65), SD4_ERR_NOT_FINITE);
    T_EQ_INT(sd4_curve_refine(pts, 5, 2, 0.0625, 4, NULL, out2, 65), SD4_OK);
    /* grid: two neighbouring nodes at 1e308 (their sum in the rule overflows) */
    for (i = 0; i < 16; i++) grid[i] = (double)(i % 5);
    grid[5] = grid[6] = 1e308;
    T_EQ_INT(sd4_grid_refine(grid, 4, 4, 1, 0.0625, 3, NULL, fine, 25 * 25), SD4_ERR_NOT_FINITE);
    grid[5] = grid[6] = 1e300;
    T_EQ_INT(sd4_grid_refine(grid, 4, 4, 1, 0.0625, 3, NULL, fine, 25 * 25), SD4_OK);
    /* random heights: amplitude 1e308 is finite, their 3x3 sums are not */
    T_EQ_INT(sd4_random_heights(4, 4, 1e308, 0, 7, NULL, h), SD4_OK);
    T_EQ_INT(sd4_random_heights(4, 4, 1e308, 1, 7, NULL, h), SD4_ERR_NOT_FINITE);
    /* terrain: omega = 1e308 */
    T_EQ_INT(sd4_terrain_preset("desert", &d), SD4_OK);
    d.omega = 1e308;
    T_EQ_INT(sd4_terrain_build(&d, &m), SD4_ERR_NOT_FINITE);
    T_CHECK(m.positions == NULL && m.indices == NULL);
    /* butterfly: w = 1e300 on a 3x3 grid of triangles (its boundary edges use w): floats overflow */
    for (j = 0; j < 3; j++)
        for (i = 0; i < 3; i++) { pos[3 * (j * 3 + i)] = (float)i; pos[3 * (j * 3 + i) + 1] = (float)j; pos[3 * (j * 3 + i) + 2] = 0.1f * (float)(i * j); }
    for (j = 0; j < 2; j++)
        for (i = 0; i < 2; i++) {
            uint32_t a = (uint32_t)(j * 3 + i), *t = tri + 6 * (j * 2 + i);
            t[0] = a; t[1] = a + 1; t[2] = a + 4; t[3] = a; t[4] = a + 4; t[5] = a + 3;
        }
    T_EQ_INT(sd4_butterfly(pos, 9, tri, 8, 1, 1e300, NULL, &m), SD4_ERR_NOT_FINITE);
    T_CHECK(m.positions == NULL);
    T_EQ_INT(sd4_butterfly(pos, 9, tri, 8, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
    sd4_free_mesh(&m);
    T_EQ_STR(sd4_result_string(SD4_ERR_NOT_FINITE), "SD4_ERR_NOT_FINITE");
}

static void test_terrain_bounded(void)
{
    sd4_terrain_desc d;
    sd4_mesh m;
    size_t count;
    /* a divergent w (0.5: the heights grow level by level, every quad is split to the cap, 16384
       quads x 4^10 x 2 triangles) is refused before anything is made */
    T_EQ_INT(sd4_terrain_preset("mountain6", &d), SD4_OK);
    d.omega = 0.5;
    T_EQ_INT(sd4_terrain_build(&d, &m), SD4_ERR_TOO_LARGE);
    T_CHECK(m.positions == NULL);
    /* the limit is the exact triangle count: desert's count passes, one less does not */
    T_EQ_INT(sd4_terrain_preset("desert", &d), SD4_OK);
    T_EQ_INT(sd4_terrain_build(&d, &m), SD4_OK);
    count = m.triangle_count;
    sd4_free_mesh(&m);
    d.max_triangles = count;
    T_EQ_INT(sd4_terrain_build(&d, &m), SD4_OK);
    T_EQ_SIZE(m.triangle_count, count);
    sd4_free_mesh(&m);
    d.max_triangles = count - 1;
    T_EQ_INT(sd4_terrain_build(&d, &m), SD4_ERR_TOO_LARGE);
    printf("terrain: mountain6 with w 0.5 refused; desert's %lu triangles pass max_triangles = %lu, not %lu\n",
           (unsigned long)count, (unsigned long)count, (unsigned long)count - 1);
}

/* ---- butterfly at a vertex of high valence ---------------------------------------------------- */

/* a closed (centre interior) or open fan of K triangles around vertex 0, the rim on the unit
   circle in z = 0, the centre at height zc */
static void fan(int K, int closed, float zc, float *pos, uint32_t *tri, size_t *nt)
{
    int i;
    pos[0] = 0.0f; pos[1] = 0.0f; pos[2] = zc;
    for (i = 0; i < K; i++) {
        double a = 6.283185307179586 * i / K;
        pos[3 + 3 * i] = (float)cos(a); pos[4 + 3 * i] = (float)sin(a); pos[5 + 3 * i] = 0.0f;
    }
    *nt = (size_t)(closed ? K : K - 1);
    for (i = 0; i < (int)*nt; i++) { tri[3 * i] = 0; tri[3 * i + 1] = (uint32_t)(1 + i); tri[3 * i + 2] = (uint32_t)(1 + (i + 1) % K); }
}

static void test_butterfly_valence(void)
{
    static const int Ks[3] = {20000, 40000, 80000};
    unsigned long long ops[2][3];
    int closed, k;
    for (closed = 0; closed < 2; closed++)
        for (k = 0; k < 3; k++) {
            int K = Ks[k];
            float *pos = (float *)malloc(sizeof(float) * 3 * (size_t)(K + 1));
            uint32_t *tri = (uint32_t *)malloc(sizeof(uint32_t) * 3 * (size_t)K);
            size_t nt;
            sd4_mesh m;
            if (!pos || !tri) { T_CHECK(0); free(pos); free(tri); return; }
            fan(K, closed, 0.2f, pos, tri, &nt);
            g_ops = 0;
            T_EQ_INT(sd4_butterfly(pos, (size_t)K + 1, tri, nt, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
            ops[closed][k] = g_ops;
            sd4_free_mesh(&m);
            free(pos);
            free(tri);
        }
    for (closed = 0; closed < 2; closed++) {
        printf("butterfly on a %s fan: %llu / %llu / %llu search and stencil steps at K = 20k / 40k / 80k (80k / 20k = %.2f)\n",
               closed ? "closed" : "open", ops[closed][0], ops[closed][1], ops[closed][2],
               ops[closed][0] ? (double)ops[closed][2] / (double)ops[closed][0] : 0.0);
        T_CHECK(ops[closed][0] >= 20000);                  /* the hook counts: at least a step a spoke */
        T_CHECK(ops[closed][2] <= 6 * ops[closed][0]);     /* linear (4x) up to a log factor, not quadratic (16x) */
    }
}

/* Zorin-Schroeder-Sweldens' stencil of a valence-K vertex reproduces quadratics: on a regular
   planar K-gon fan with heights z = q(x, y) the new point of each spoke is its midpoint with
   z = q(midpoint) (K >= 5 and K = 4 for every quadratic; K = 3 for x^2 + y^2 and linear ones).
   The fan's float positions are regular to 2^-24, so with |s_j| summing to at most 1.75 and
   coordinates of at most 2, the point is within 1e-6 (a wrong weight moves it by 1e-3 or more).
   Valences 32 and 64 on, the tabled and the Fourier forms, are included. */
static void test_butterfly_stencil(void)
{
    static const int Ks[] = {3, 4, 5, 7, 8, 12, 31, 32, 33, 63, 64, 65, 200};
    double worst = 0.0;
    size_t t;
    for (t = 0; t < sizeof Ks / sizeof Ks[0]; t++) {
        int K = Ks[t], i, checked = 0;
        unsigned char spoke[201 + 400];
        float pos[3 * 201];
        uint32_t tri[3 * 200];
        size_t nt, v;
        sd4_mesh m;
        double a = 0.6, b = K == 3 ? 0.0 : -0.4, c = K == 3 ? 0.6 : 0.35;
        fan(K, 1, 0.3f, pos, tri, &nt);
        for (i = 0; i <= K; i++) {
            double x = pos[3 * i], y = pos[3 * i + 1];
            pos[3 * i + 2] = (float)(0.3 + 0.5 * x - 0.25 * y + a * x * x + b * x * y + c * y * y);
        }
        T_EQ_INT(sd4_butterfly(pos, (size_t)K + 1, tri, nt, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
        memset(spoke, 0, m.vertex_count);
        for (v = 0; v < m.triangle_count; v++) /* the spokes' new points: the centre's new neighbours */
            if (m.indices[3 * v] == 0 || m.indices[3 * v + 1] == 0 || m.indices[3 * v + 2] == 0)
                for (i = 0; i < 3; i++) spoke[m.indices[3 * v + i]] = m.indices[3 * v + i] > (uint32_t)K;
        for (v = (size_t)K + 1; v < m.vertex_count; v++) {
            const float *p = m.positions + 3 * v;
            double best = 1e30, err;
            int j, bj = 0;
            if (!spoke[v]) continue; /* a rim edge's point (the boundary rule) */
            for (j = 0; j < K; j++) {
                double dx = p[0] - 0.5 * (pos[0] + pos[3 + 3 * j]), dy = p[1] - 0.5 * (pos[1] + pos[4 + 3 * j]);
                if (dx * dx + dy * dy < best) { best = dx * dx + dy * dy; bj = j; }
            }
            {
                double mx = 0.5 * ((double)pos[0] + pos[3 + 3 * bj]), my = 0.5 * ((double)pos[1] + pos[4 + 3 * bj]);
                double mz = 0.3 + 0.5 * mx - 0.25 * my + a * mx * mx + b * mx * my + c * my * my;
                err = fabs(p[0] - mx) + fabs(p[1] - my) + fabs(p[2] - mz);
            }
            worst = err > worst ? err : worst;
            T_CHECK_MSG(err <= 1e-6, "K = %d: spoke %d's point off its quadratic midpoint by %g", K, bj, err);
            checked++;
        }
        T_EQ_INT(checked, K);
        sd4_free_mesh(&m);
    }
    printf("butterfly ZSS stencils, K = 3..200: spoke points within %.2g of the quadratic's midpoints (bound 1e-6)\n", worst);
}

/* ---- butterfly against the formulas, written out independently --------------------------------
   A closed mesh with valences 3..12: an icosahedron split twice (162 vertices, valences 5 and 6)
   on the unit sphere with noise, then 150 random edge flips (valences kept in 3..12, no repeated
   edge, half of them raising high valences), leaving every valence 3..12. Each new point of one butterfly level is recomputed in double from the papers' rules,
   with each vertex's neighbour ring built here by walking its triangles:
     both ends of valence 6: 1/2 (a + b) + 1/8 (c + d) - 1/16 (the four wings)   (DLG 1990, w = 1/16)
     one end v of valence K != 6: 3/4 v + sum_j s_j e_j, e_0 the other end, j counted around v
       (s_j is symmetric in j and K - j, so the direction does not matter),
       s_j = (1/4 + cos(2 pi j / K) + 1/2 cos(4 pi j / K)) / K for K >= 5, (5/12, -1/12, -1/12) for
       K = 3, (3/8, 0, -1/8, 0) for K = 4                                            (ZSS 1996)
     both ends of valence != 6: the average of the two.
   Positions are within 2 of the origin and the weights' magnitudes sum to at most 2.6, so the
   float output is within 2.6 * 2 * 2^-24 + 2^-23 < 5e-7 of the double value; 1e-6 is the bound,
   while a wrong weight of 1/48 moves a point by about 1e-2. Planted, one at a time in subdiv4.h:
   K = 3's -1/12 -> -1/8; K = 4's -1/8 -> -1/16; the K >= 5 term 1/2 cos(4 pi j/K) -> cos; the
   average of two extraordinary ends dropped (p *= 0.5 removed); valence 7 taken as the regular
   one (!= 6 -> != 7); the regular butterfly's 2w on d -> 2w + 1/64: each fails here, with 15 to
   432 of the 480 points off. The regular-fan test above misses the dropped average and the 1/64
   (the plane tests catch those two, with one point each). */
static uint32_t ring_next(const uint32_t *tri, size_t nt, uint32_t v, uint32_t x)
{
    size_t t;
    int k;
    for (t = 0; t < nt; t++)
        for (k = 0; k < 3; k++)
            if (tri[3 * t + k] == v && tri[3 * t + (k + 1) % 3] == x) return tri[3 * t + (k + 2) % 3];
    return UINT32_MAX;
}

static int valence_of(const uint32_t *tri, size_t nt, uint32_t v)
{
    size_t t;
    int k, n = 0;
    for (t = 0; t < nt; t++)
        for (k = 0; k < 3; k++) n += tri[3 * t + k] == v;
    return n;
}

static int has_edge(const uint32_t *tri, size_t nt, uint32_t a, uint32_t b)
{
    return ring_next(tri, nt, a, b) != UINT32_MAX || ring_next(tri, nt, b, a) != UINT32_MAX;
}

/* the ZSS stencil of v (valence K) for the edge to b, added to p with weight f */
static void zss_point(const float *pos, const uint32_t *tri, size_t nt, uint32_t v, uint32_t b, double f, double *p)
{
    int K = valence_of(tri, nt, v), j, k;
    uint32_t e = b;
    double sum = 0.0;
    for (j = 0; j < K; j++) {
        double s, x = 2.0 * 3.14159265358979323846 * j / K;
        if (K == 3) s = j == 0 ? 5.0 / 12.0 : -1.0 / 12.0;
        else if (K == 4) s = j == 0 ? 3.0 / 8.0 : j == 2 ? -1.0 / 8.0 : 0.0;
        else s = (0.25 + cos(x) + 0.5 * cos(2.0 * x)) / K;
        for (k = 0; k < 3; k++) p[k] += f * s * pos[3 * e + k];
        sum += s;
        e = ring_next(tri, nt, v, e); /* the next neighbour around v */
    }
    for (k = 0; k < 3; k++) p[k] += f * (1.0 - sum) * pos[3 * v + k];
}

/* the vertex beyond edge (x, y) from the triangle (x, y, z): the third vertex of (y, x, ?) */
static uint32_t wing(const uint32_t *tri, size_t nt, uint32_t x, uint32_t y) { return ring_next(tri, nt, y, x); }

static void test_butterfly_formula(void)
{
    enum { NV = 162, NT = 320, FLIPS = 150 };
    float pos[3 * NV];
    uint32_t tri[3 * NT * 4], *t2;
    size_t nt = 20, nv = 12, i, flips = 0, cases[3] = {0, 0, 0};
    int lvl, k, kmax, missing, hist[13] = {0};
    double worst = 0.0;
    sd4_mesh m;
    static const uint32_t ico[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2,
                                     10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11,
                                     6, 2, 10, 8, 6, 7, 9, 8, 1};
    const double g = 1.6180339887498949;
    const double iv[36] = {-1, g, 0, 1, g, 0, -1, -g, 0, 1, -g, 0, 0, -1, g, 0, 1, g,
                           0, -1, -g, 0, 1, -g, g, 0, -1, g, 0, 1, -g, 0, -1, -g, 0, 1};
    for (i = 0; i < 36; i++) pos[i] = (float)iv[i];
    memcpy(tri, ico, sizeof ico);
    for (lvl = 0; lvl < 2; lvl++) { /* midpoint 4-split, new vertices shared through a search */
        size_t t, n0 = nt;
        t2 = (uint32_t *)malloc(sizeof(uint32_t) * 12 * nt);
        for (t = 0; t < n0; t++) {
            uint32_t c[3], mid[3];
            for (k = 0; k < 3; k++) c[k] = tri[3 * t + k];
            for (k = 0; k < 3; k++) {
                uint32_t a = c[k], b = c[(k + 1) % 3], v;
                for (v = 12; v < nv; v++) /* an existing midpoint of (a, b)? */
                    if (fabsf(pos[3 * v] - 0.5f * (pos[3 * a] + pos[3 * b])) + fabsf(pos[3 * v + 1] - 0.5f * (pos[3 * a + 1] + pos[3 * b + 1])) +
                            fabsf(pos[3 * v + 2] - 0.5f * (pos[3 * a + 2] + pos[3 * b + 2])) == 0.0f)
                        break;
                if (v == nv) {
                    int q;
                    for (q = 0; q < 3; q++) pos[3 * nv + q] = 0.5f * (pos[3 * a + q] + pos[3 * b + q]);
                    nv++;
                }
                mid[k] = v;
            }
            {
                uint32_t f[12] = {c[0], mid[0], mid[2], c[1], mid[1], mid[0], c[2], mid[2], mid[1], mid[0], mid[1], mid[2]};
                memcpy(t2 + 12 * t, f, sizeof f);
            }
        }
        nt *= 4;
        memcpy(tri, t2, sizeof(uint32_t) * 3 * nt);
        free(t2);
    }
    T_EQ_SIZE(nv, NV);
    T_EQ_SIZE(nt, NT);
    for (i = 0; i < nv; i++) { /* onto the unit sphere, with noise */
        double x = pos[3 * i], y = pos[3 * i + 1], z = pos[3 * i + 2], r = sqrt(x * x + y * y + z * z);
        double s = (1.0 + 0.08 * (unit_random(i, 11) - 0.5)) / r;
        pos[3 * i] = (float)(x * s), pos[3 * i + 1] = (float)(y * s), pos[3 * i + 2] = (float)(z * s);
    }
    for (i = 0; i < 4000 && flips < FLIPS; i++) { /* random flips: triangle (a, b, c) and (b, a, d) -> (a, d, c), (d, b, c) */
        size_t t = (size_t)(unit_random(i, 12) * (double)nt) % nt, u;
        int e = (int)(unit_random(i, 13) * 3.0) % 3;
        uint32_t a = tri[3 * t + e], b = tri[3 * t + (e + 1) % 3], c = tri[3 * t + (e + 2) % 3], d = wing(tri, nt, a, b);
        if (d == UINT32_MAX || d == c || has_edge(tri, nt, c, d)) continue;
        if (valence_of(tri, nt, a) <= 3 || valence_of(tri, nt, b) <= 3 || valence_of(tri, nt, c) >= 12 ||
            valence_of(tri, nt, d) >= 12)
            continue;
        if (valence_of(tri, nt, c) + valence_of(tri, nt, d) < valence_of(tri, nt, a) + valence_of(tri, nt, b) - 1 &&
            (i & 1)) /* half the flips make high valences higher */
            continue;
        for (u = 0; u < nt; u++)
            if (tri[3 * u] == b && tri[3 * u + 1] == a && tri[3 * u + 2] == d) break;
        if (u == nt)
            for (u = 0; u < nt; u++)
                if ((tri[3 * u] == a && tri[3 * u + 1] == d && tri[3 * u + 2] == b) ||
                    (tri[3 * u] == d && tri[3 * u + 1] == b && tri[3 * u + 2] == a))
                    break;
        if (u == nt) continue;
        tri[3 * t] = a, tri[3 * t + 1] = d, tri[3 * t + 2] = c;
        tri[3 * u] = d, tri[3 * u + 1] = b, tri[3 * u + 2] = c;
        flips++;
    }
    for (i = 0; i < nv; i++) hist[valence_of(tri, nt, (uint32_t)i)]++;
    for (k = 3, kmax = 0, missing = 0; k <= 12; k++) {
        if (hist[k]) kmax = k;
        missing += hist[k] == 0;
    }
    T_CHECK_MSG(missing == 0, "valences 3..12 present after %zu flips (%d missing)", flips, missing);
    T_EQ_INT(sd4_butterfly(pos, nv, tri, nt, 1, 1.0 / 16.0, NULL, &m), SD4_OK);
    T_EQ_SIZE(m.vertex_count, nv + nt * 3 / 2);
    for (i = nv; i < m.vertex_count; i++) {
        uint32_t ends[2], a, b, c, d;
        int ne = 0, Ka, Kb, q;
        size_t t;
        double p[3] = {0, 0, 0}, err = 0.0;
        for (t = 0; t < m.triangle_count && ne < 2; t++) /* the edge's ends: the old vertices of its corner triangles */
            for (k = 0; k < 3; k++)
                if (m.indices[3 * t + k] == i) {
                    for (q = 0; q < 3; q++) {
                        uint32_t o = m.indices[3 * t + q];
                        if (o < nv && ne < 2 && (ne == 0 || ends[0] != o)) ends[ne++] = o;
                    }
                }
        if (!T_CHECK(ne == 2)) continue;
        a = ends[0], b = ends[1];
        if (ring_next(tri, nt, a, b) == UINT32_MAX) a = ends[1], b = ends[0]; /* (a, b, c) a triangle */
        c = ring_next(tri, nt, a, b);
        d = ring_next(tri, nt, b, a);
        Ka = valence_of(tri, nt, a), Kb = valence_of(tri, nt, b);
        if (Ka == 6 && Kb == 6) {
            uint32_t w4[4];
            w4[0] = wing(tri, nt, b, c), w4[1] = wing(tri, nt, c, a), w4[2] = wing(tri, nt, a, d), w4[3] = wing(tri, nt, d, b);
            for (q = 0; q < 3; q++) {
                p[q] = 0.5 * ((double)pos[3 * a + q] + pos[3 * b + q]) + 0.125 * ((double)pos[3 * c + q] + pos[3 * d + q]);
                for (k = 0; k < 4; k++) p[q] -= pos[3 * w4[k] + q] / 16.0;
            }
            cases[0]++;
        } else if (Ka != 6 && Kb != 6) {
            zss_point(pos, tri, nt, a, b, 0.5, p);
            zss_point(pos, tri, nt, b, a, 0.5, p);
            cases[2]++;
        } else {
            if (Ka != 6) zss_point(pos, tri, nt, a, b, 1.0, p);
            else zss_point(pos, tri, nt, b, a, 1.0, p);
            cases[1]++;
        }
        for (q = 0; q < 3; q++) err = fmax(err, fabs(m.positions[3 * i + q] - p[q]));
        worst = fmax(worst, err);
        T_CHECK_MSG(err <= 1e-6, "edge (%u, %u), valences %d and %d: off the formula by %.3g", a, b, Ka, Kb, err);
    }
    T_CHECK(cases[0] >= 10 && cases[1] >= 100 && cases[2] >= 100);
    printf("butterfly formulas on a flipped icosphere (%zu flips, valences 3..%d): %zu regular, %zu one-sided, %zu "
           "two-sided edges, worst %.2g (bound 1e-6)\n", flips, kmax, cases[0], cases[1], cases[2], worst);
    sd4_free_mesh(&m);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    test_not_finite();
    test_terrain_bounded();
    test_butterfly_valence();
    test_butterfly_stencil();
    test_butterfly_formula();
    test_curves();
    test_basis();
    test_grids();
    test_terrain();
    test_butterfly();
    return T_END();
}
