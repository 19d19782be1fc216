/* test_dispmesh_simplify - unit tests of dispmesh.h's QEM simplifier and progressive meshes.

   - guarantees on a bumpy icosphere and the bunny (skipped with a reason if glmark2-data is
     missing): the target is reached; the output is a closed, consistently oriented 2-manifold
     (every edge in exactly two triangles, once each way) with Euler characteristic 2; no
     degenerate triangle (2 area > 1e-6 longest edge^2); no flipped triangle (its normal against
     the input's normal at the closest point of its centroid, found with dm_bvh_closest_point);
     determinism (two runs give the same bytes);
   - progressive mesh: the simplifier stopped after k collapses (max_collapses) gives exactly
     level (splits - k) of the full run, positions bit for bit and the same triangles; the top
     level is the input; levels visited in a scrambled order; every vertex split record is
     consistent; the merged-vertex sets partition the input vertices;
   - open meshes: boundary vertices stay on the boundary, within 1e-5 (a wavy unit square sheet); with
     DM_SIMPLIFY_LOCK_BOUNDARY they do not move and are not removed; per-vertex locks;
   - target error: no collapse above it, the reported error is at most the bound;
   - the constraint: veto all (DM_OK, no collapse, target not reached), veto a half space
     (no vertex of the result came from there... checked through the merged sets), and a
     corrected position (every vertex stays at its own input position);
   - bad input: NULL arrays, no triangles, bad index, NaN (referenced: error; unreferenced:
     fine), NaN target error, duplicate vertices (a seam), zero-area triangles, repeated-index
     triangles (dropped and counted), an edge with three triangles (its vertices' triangles are
     left alone), isolated vertices, a lone triangle and a tetrahedron (nothing to collapse);
   - progress and cancel; allocation-failure injection at every allocation (returns
     DM_ERR_OUT_OF_MEMORY, leaks nothing);
   - white box: the two-at-a-time placement gives the one-at-a-time solve's bits, and refuses
     exactly where that one falls back to the edge; on flat grids of 20k and 80k triangles (every
     interior collapse costs 0, so the queue holds long runs of equal keys) the queue's front
     comparisons (DM_COUNT_OPS) grow at most 6 times for the 4 times larger grid (a scan of the
     equal keys grew them with the square). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

#include "test.h"
#include "hashrand.h"
#include "../bench/sphere.h"
static unsigned long long g_ops; /* the queue's front comparisons (DM_COUNT_OPS) */
#define DM_COUNT_OPS(n) (g_ops += (unsigned long long)(n))
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

#define BUNNY "/usr/share/glmark2/models/bunny.obj"

typedef struct mesh {
    float *pos;
    size_t nv;
    uint32_t *idx;
    size_t nt;
} mesh;

/* the current level of a progressive mesh, compact */
static mesh pm_mesh(dm_pm *pm, uint32_t **ids)
{
    mesh m;
    dm_pm_counts(pm, &m.nv, &m.nt);
    m.pos = (float *)malloc(3 * m.nv * sizeof(float) + 4);
    m.idx = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t) + 4);
    *ids = (uint32_t *)malloc(m.nv * sizeof(uint32_t) + 4);
    dm_pm_get_mesh(pm, m.pos, m.idx, *ids);
    return m;
}

static void mesh_free(mesh *m)
{
    free(m->pos);
    free(m->idx);
}

static double tri_normal(const float *pos, const uint32_t *t, double n[3], double *longest2)
{
    double e[3], f[3], g[3], a, b, c;
    int k;
    for (k = 0; k < 3; k++) {
        e[k] = (double)pos[3 * t[1] + k] - pos[3 * t[0] + k];
        f[k] = (double)pos[3 * t[2] + k] - pos[3 * t[0] + k];
        g[k] = (double)pos[3 * t[2] + k] - pos[3 * t[1] + k];
    }
    n[0] = e[1] * f[2] - e[2] * f[1];
    n[1] = e[2] * f[0] - e[0] * f[2];
    n[2] = e[0] * f[1] - e[1] * f[0];
    a = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    b = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    c = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    *longest2 = fmax(a, fmax(b, c));
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* edges not in exactly two triangles once each way (bad), boundary edges (in one triangle only,
   counted apart), degenerate triangles, and V - E + F */
static void topology(const mesh *m, size_t *bad_edges, size_t *boundary_edges, size_t *degenerate, long *euler)
{
    uint64_t *e = (uint64_t *)malloc(3 * m->nt * sizeof(uint64_t) + 8);
    uint64_t *r = (uint64_t *)malloc(3 * m->nt * sizeof(uint64_t) + 8);
    size_t i, n = 3 * m->nt, bad = 0, bnd = 0, deg = 0, edges = 0, j;
    for (i = 0; i < m->nt; i++) {
        int k;
        double nn[3], l2;
        for (k = 0; k < 3; k++) {
            uint64_t a = m->idx[3 * i + k], b = m->idx[3 * i + (k + 1) % 3];
            e[3 * i + k] = (a << 32) | b;
            r[3 * i + k] = (b << 32) | a;
        }
        if (!(tri_normal(m->pos, m->idx + 3 * i, nn, &l2) > 1e-6 * l2)) deg++;
    }
    qsort(e, n, sizeof(uint64_t), cmp_u64);
    qsort(r, n, sizeof(uint64_t), cmp_u64);
    for (i = 0; i < n; i++) {
        uint64_t key = e[i], rev = (key << 32) | (key >> 32);
        size_t lo = 0, hi = n, cnt = 0;
        if (i > 0 && e[i - 1] == key) bad++; /* the same directed edge twice */
        while (lo < hi) { /* how many reversed copies */
            size_t mid = (lo + hi) / 2;
            if (r[mid] < key) lo = mid + 1;
            else hi = mid;
        }
        for (j = lo; j < n && r[j] == key; j++) cnt++;
        (void)rev;
        /* r holds reversed edges: r == key means some triangle has the edge the other way */
        if (cnt == 0) bnd++;
        else if (cnt > 1) bad++;
        edges += 1;
    }
    /* undirected edges: interior ones were counted twice */
    *bad_edges = bad;
    *boundary_edges = bnd;
    *degenerate = deg;
    {
        size_t v, used = 0;
        char *u = (char *)calloc(m->nv + 1, 1);
        for (i = 0; i < n; i++) u[m->idx[i]] = 1;
        for (v = 0; v < m->nv; v++) used += (size_t)u[v];
        free(u);
        *euler = (long)used - (long)((edges - bnd) / 2 + bnd) + (long)m->nt;
    }
    free(e);
    free(r);
}

/* triangles whose normal points against the input's normal at the closest point of the centroid */
static size_t flipped(const mesh *in, const dm_bvh *bvh, const mesh *out)
{
    size_t i, count = 0;
    for (i = 0; i < out->nt; i++) {
        double n[3], l2, n0[3];
        float c[3];
        dm_closest cl;
        int k;
        tri_normal(out->pos, out->idx + 3 * i, n, &l2);
        for (k = 0; k < 3; k++)
            c[k] = (out->pos[3 * out->idx[3 * i] + k] + out->pos[3 * out->idx[3 * i + 1] + k] +
                    out->pos[3 * out->idx[3 * i + 2] + k]) / 3.0f;
        if (!dm_bvh_closest_point(bvh, c, INFINITY, &cl)) {
            count++;
            continue;
        }
        tri_normal(in->pos, in->idx + 3 * cl.triangle, n0, &l2);
        if (n[0] * n0[0] + n[1] * n0[1] + n[2] * n0[2] < 0.0) count++;
    }
    return count;
}

static int same_mesh(const mesh *a, const uint32_t *ida, const mesh *b, const uint32_t *idb)
{
    if (a->nv != b->nv || a->nt != b->nt) return 0;
    if (memcmp(ida, idb, a->nv * sizeof(uint32_t)) != 0) return 0;
    if (memcmp(a->pos, b->pos, 3 * a->nv * sizeof(float)) != 0) return 0;
    return memcmp(a->idx, b->idx, 3 * a->nt * sizeof(uint32_t)) == 0;
}

/* ---- guarantees on a closed mesh ------------------------------------------------------------ */

static void closed_mesh_checks(const char *name, const mesh *in, double fraction)
{
    dm_simplify_options o;
    dm_simplify_report rep, rep2;
    dm_pm *pm = NULL, *pm2 = NULL;
    dm_bvh *bvh = NULL;
    mesh out, out2;
    uint32_t *ids, *ids2;
    size_t bad, bnd, deg, flips;
    long euler;
    memset(&o, 0, sizeof o);
    o.target_triangles = (size_t)(fraction * (double)in->nt);
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm2, &rep2), DM_OK);
    if (!pm || !pm2) return;
    out = pm_mesh(pm, &ids);
    out2 = pm_mesh(pm2, &ids2);
    T_CHECK_MSG(rep.triangle_count <= o.target_triangles && rep.triangle_count + 2 > o.target_triangles,
                "%s: %zu triangles for target %zu", name, rep.triangle_count, o.target_triangles);
    T_CHECK(rep.reached_target == 1);
    T_EQ_SIZE(out.nt, rep.triangle_count);
    T_EQ_SIZE(out.nv, rep.vertex_count);
    T_EQ_SIZE(rep.collapse_count, dm_pm_split_count(pm));
    topology(&out, &bad, &bnd, &deg, &euler);
    T_CHECK_MSG(bad == 0 && bnd == 0, "%s: %zu non-manifold, %zu boundary edges", name, bad, bnd);
    T_CHECK_MSG(deg == 0, "%s: %zu degenerate triangles", name, deg);
    T_EQ_INT(euler, 2);
    T_EQ_INT(dm_bvh_build(in->pos, in->nv, in->idx, in->nt, NULL, &bvh), DM_OK);
    flips = bvh ? flipped(in, bvh, &out) : out.nt;
    T_CHECK_MSG(flips == 0, "%s: %zu of %zu triangles face against the input", name, flips, out.nt);
    dm_bvh_free(bvh);
    T_CHECK_MSG(same_mesh(&out, ids, &out2, ids2) && memcmp(&rep, &rep2, sizeof rep) == 0, "%s: not deterministic",
                name);
    printf("  %s: %zu -> %zu triangles, error %.3g, %zu refused\n", name, in->nt, out.nt, rep.error, rep.rejected);
    mesh_free(&out);
    mesh_free(&out2);
    free(ids);
    free(ids2);
    dm_pm_free(pm);
    dm_pm_free(pm2);
}

/* ---- progressive mesh ----------------------------------------------------------------------- */

static void pm_checks(const char *name, const mesh *in, size_t target)
{
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    size_t splits, i, cover = 0, bad_sets = 0, bad_levels = 0, bad_records = 0;
    size_t ks[6];
    uint32_t *seen;
    memset(&o, 0, sizeof o);
    o.target_triangles = target;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    if (!pm) return;
    splits = dm_pm_split_count(pm);
    T_CHECK(splits > 10);
    /* partial runs against the levels of the full one */
    ks[0] = 1;
    ks[1] = 2;
    ks[2] = splits / 3;
    ks[3] = splits / 2;
    ks[4] = splits - 1;
    ks[5] = splits;
    for (i = 0; i < 6; i++) {
        dm_pm *part = NULL;
        mesh a, b;
        uint32_t *ida, *idb;
        o.max_collapses = ks[i];
        if (dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &part, NULL) != DM_OK) {
            bad_levels++;
            continue;
        }
        dm_pm_set_level(pm, splits - ks[i]);
        a = pm_mesh(pm, &ida);
        b = pm_mesh(part, &idb);
        if (dm_pm_split_count(part) != ks[i] || !same_mesh(&a, ida, &b, idb)) {
            printf("  level %zu (after %zu collapses) differs\n", splits - ks[i], ks[i]);
            bad_levels++;
        }
        mesh_free(&a);
        mesh_free(&b);
        free(ida);
        free(idb);
        dm_pm_free(part);
    }
    T_CHECK_MSG(bad_levels == 0, "%s: %zu partial runs differ from their level", name, bad_levels);
    /* the top level is the input */
    {
        mesh a;
        uint32_t *ida;
        int same;
        dm_pm_set_level(pm, splits + 5); /* clamped */
        T_EQ_SIZE(dm_pm_level(pm), splits);
        a = pm_mesh(pm, &ida);
        same = a.nt == in->nt && a.nv == in->nv;
        for (i = 0; same && i < a.nv; i++) same = ida[i] == i;
        same = same && memcmp(a.pos, in->pos, 3 * in->nv * sizeof(float)) == 0 &&
               memcmp(a.idx, in->idx, 3 * in->nt * sizeof(uint32_t)) == 0;
        T_CHECK_MSG(same, "%s: the finest level is not the input", name);
        mesh_free(&a);
        free(ida);
    }
    /* scrambled walk, then back to the base: the same base */
    {
        mesh a, b;
        uint32_t *ida, *idb;
        dm_pm *fresh = NULL;
        for (i = 0; i < 20; i++) dm_pm_set_level(pm, (size_t)(unit_random(i, 7) * (double)(splits + 1)));
        dm_pm_set_level(pm, 0);
        o.max_collapses = 0;
        T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &fresh, NULL), DM_OK);
        a = pm_mesh(pm, &ida);
        if (fresh) {
            b = pm_mesh(fresh, &idb);
            T_CHECK_MSG(same_mesh(&a, ida, &b, idb), "%s: base after a walk differs", name);
            mesh_free(&b);
            free(idb);
        }
        dm_pm_free(fresh);
        mesh_free(&a);
        free(ida);
    }
    /* vertex split records: one more vertex and 1 or 2 more triangles per level */
    for (i = 0; i + 1 <= splits; i++) {
        dm_vsplit vs;
        if (!dm_pm_get_vsplit(pm, i, &vs) || vs.keep == vs.remove || vs.keep >= in->nv || vs.remove >= in->nv ||
            vs.restored_triangles < 1 || vs.restored_triangles > 2)
            bad_records++;
    }
    {
        dm_vsplit vs;
        T_CHECK(!dm_pm_get_vsplit(pm, splits, &vs));
    }
    T_CHECK_MSG(bad_records == 0, "%s: %zu bad split records", name, bad_records);
    {
        size_t nv0, nt0, nv1, nt1;
        dm_vsplit vs;
        dm_pm_set_level(pm, 0);
        dm_pm_counts(pm, &nv0, &nt0);
        dm_pm_get_vsplit(pm, 0, &vs);
        dm_pm_set_level(pm, 1);
        dm_pm_counts(pm, &nv1, &nt1);
        T_CHECK(nv1 == nv0 + 1 && nt1 == nt0 + vs.restored_triangles);
        T_CHECK(memcmp(dm_pm_positions(pm) + 3 * vs.keep, vs.keep_position, sizeof vs.keep_position) == 0);
        dm_pm_set_level(pm, 0);
        T_CHECK(memcmp(dm_pm_positions(pm) + 3 * vs.keep, vs.merged_position, sizeof vs.merged_position) == 0);
    }
    /* merged sets: a partition of the input vertices, each base vertex in its own set */
    seen = (uint32_t *)calloc(in->nv, sizeof(uint32_t));
    {
        mesh base;
        uint32_t *ids;
        dm_pm_set_level(pm, 0);
        base = pm_mesh(pm, &ids);
        for (i = 0; i < in->nv; i++) {
            const uint32_t *list;
            size_t n = dm_pm_merged_vertices(pm, (uint32_t)i, &list), j;
            for (j = 0; j < n; j++) {
                if (list[j] >= in->nv || seen[list[j]]++ || (j && list[j] <= list[j - 1])) bad_sets++;
            }
            cover += n;
        }
        for (i = 0; i < base.nv; i++) {
            const uint32_t *list;
            size_t n = dm_pm_merged_vertices(pm, ids[i], &list), j, self = 0;
            for (j = 0; j < n; j++) self += list[j] == ids[i];
            if (self != 1) bad_sets++;
        }
        T_EQ_SIZE(cover, in->nv);
        T_CHECK_MSG(bad_sets == 0, "%s: %zu bad merged sets", name, bad_sets);
        mesh_free(&base);
        free(ids);
    }
    free(seen);
    dm_pm_free(pm);
}

/* ---- open meshes, locks, error bound, constraint -------------------------------------------- */

/* an n x n square sheet over [0,1]^2, wavy with amplitude amp (0: flat) */
static mesh sheet_amp(int n, float amp)
{
    mesh m;
    int i, j;
    m.nv = (size_t)(n + 1) * (size_t)(n + 1);
    m.nt = 2 * (size_t)n * (size_t)n;
    m.pos = (float *)malloc(3 * m.nv * sizeof(float));
    m.idx = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t));
    for (j = 0; j <= n; j++)
        for (i = 0; i <= n; i++) {
            float *p = m.pos + 3 * ((size_t)j * (n + 1) + i);
            p[0] = (float)i / n;
            p[1] = (float)j / n;
            p[2] = amp != 0.0f ? amp * sinf(6.0f * p[0]) * cosf(5.0f * p[1]) : 0.0f;
        }
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)n + 1, d = c + 1;
            uint32_t *t = m.idx + 6 * ((size_t)j * n + i);
            t[0] = a; t[1] = b; t[2] = d;
            t[3] = a; t[4] = d; t[5] = c;
        }
    return m;
}

static mesh sheet(int n) { return sheet_amp(n, 0.05f); }

/* Frames: a tilted plane must simplify with no error (the quadrics are exact on planes up to
   rounding: a float quadric, or one in unnormalised coordinates, would show a noise floor here),
   also when it sits far from the origin (then the input's own float rounding, 7.6e-6 at 100, is
   the limit); and the same sheet at another scale must give the same result relative to its
   size (the greedy order is chaotic under rounding, so "the same" is to within 10%). */
static double frame_run(const mesh *in, double sx, double tx, size_t target, double *plane_dev, size_t *nt)
{
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    mesh m = *in, out;
    uint32_t *ids;
    size_t i;
    m.pos = (float *)malloc(3 * in->nv * sizeof(float));
    for (i = 0; i < 3 * in->nv; i++) m.pos[i] = (float)(in->pos[i] * sx + tx);
    memset(&o, 0, sizeof o);
    o.target_triangles = target;
    memset(&rep, 0, sizeof rep);
    T_EQ_INT(dm_simplify(m.pos, m.nv, m.idx, m.nt, &o, &pm, &rep), DM_OK);
    *plane_dev = 0.0;
    *nt = rep.triangle_count;
    if (pm) {
        out = pm_mesh(pm, &ids);
        for (i = 0; i < out.nv; i++) { /* the tilted plane z = 0.3 x + 0.2 y, in the input's frame */
            const float *q = out.pos + 3 * i;
            double x = (q[0] - tx) / sx, y = (q[1] - tx) / sx, z = (q[2] - tx) / sx;
            double d = fabs(z - 0.3 * x - 0.2 * y);
            if (d > *plane_dev) *plane_dev = d;
        }
        mesh_free(&out);
        free(ids);
        dm_pm_free(pm);
    }
    free(m.pos);
    return rep.error / sx;
}

static void frame_checks(void)
{
    mesh flat = sheet(120), wavy = sheet(120);
    size_t i, nt0, nt1, nt2;
    double dev, dev1, dev2, e0, e1, e2;
    for (i = 0; i < flat.nv; i++) flat.pos[3 * i + 2] = 0.3f * flat.pos[3 * i] + 0.2f * flat.pos[3 * i + 1];
    e0 = frame_run(&flat, 1.0, 0.0, flat.nt / 50, &dev, &nt0);
    T_CHECK_MSG(e0 <= 1e-7 && dev <= 1e-6, "tilted plane: error %.3g, off the plane by %.3g", e0, dev);
    e1 = frame_run(&flat, 1.0, 100.0, flat.nt / 50, &dev1, &nt1);
    T_CHECK_MSG(e1 <= 4.0 * 7.6e-6 && dev1 <= 2.0 * 7.6e-6, "tilted plane moved by 100: error %.3g, off the plane by %.3g", e1, dev1);
    T_CHECK(nt0 <= flat.nt / 50 && nt1 <= flat.nt / 50);
    printf("  frames: tilted plane error %.2g off %.2g (moved: %.2g off %.2g), %zu %zu\n", e0, dev, e1, dev1, nt0, nt1);
    e0 = frame_run(&wavy, 1.0, 0.0, wavy.nt / 50, &dev, &nt0);
    e1 = frame_run(&wavy, 1e-3, 0.0, wavy.nt / 50, &dev1, &nt1);
    e2 = frame_run(&wavy, 1e3, 0.0, wavy.nt / 50, &dev2, &nt2);
    T_CHECK_MSG(nt0 <= nt1 + 1 && nt1 <= nt0 + 1 && nt0 <= nt2 + 1 && nt2 <= nt0 + 1, "wavy sheet: %zu / %zu / %zu triangles",
                nt0, nt1, nt2);
    T_CHECK_MSG(e0 > 0.0 && fabs(e1 / e0 - 1.0) < 0.1 && fabs(e2 / e0 - 1.0) < 0.1,
                "wavy sheet: error %.4g at size 1, %.4g at 1e-3, %.4g at 1e3 (relative)", e0, e1, e2);
    printf("  frames: wavy sheet error %.4g / %.4g / %.4g, %zu %zu %zu triangles\n", e0, e1, e2, nt0, nt1, nt2);
    mesh_free(&flat);
    mesh_free(&wavy);
}

static int on_square_boundary(const float *p) { return p[0] == 0.0f || p[0] == 1.0f || p[1] == 0.0f || p[1] == 1.0f; }

/* within 1e-5 of an edge of the square: a corner may slide along one edge by the quadric's balance */
static int near_square_boundary(const float *p)
{
    return fabsf(p[0]) < 1e-5f || fabsf(p[0] - 1.0f) < 1e-5f || fabsf(p[1]) < 1e-5f || fabsf(p[1] - 1.0f) < 1e-5f;
}

static void open_mesh_checks(void)
{
    mesh in = sheet(40), out;
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    uint32_t *ids;
    size_t i, off = 0, moved = 0, missing = 0, bad, bnd, deg;
    long euler;
    uint8_t *locked;
    memset(&o, 0, sizeof o);
    o.target_triangles = 200;
    T_EQ_INT(dm_simplify(in.pos, in.nv, in.idx, in.nt, &o, &pm, &rep), DM_OK);
    if (pm) {
        out = pm_mesh(pm, &ids);
        T_CHECK(rep.reached_target);
        /* boundary vertices of the result stay on the square's edges */
        topology(&out, &bad, &bnd, &deg, &euler);
        T_CHECK_MSG(bad == 0 && deg == 0, "sheet: %zu bad edges, %zu degenerate", bad, deg);
        T_EQ_INT(euler, 1);
        for (i = 0; i < out.nv; i++)
            if (on_square_boundary(in.pos + 3 * ids[i]) && !near_square_boundary(out.pos + 3 * i)) off++;
        T_CHECK_MSG(off == 0, "sheet: %zu boundary vertices left the boundary", off);
        mesh_free(&out);
        free(ids);
        dm_pm_free(pm);
        pm = NULL;
    }
    /* locked boundary: every boundary vertex present, unmoved */
    o.flags = DM_SIMPLIFY_LOCK_BOUNDARY;
    T_EQ_INT(dm_simplify(in.pos, in.nv, in.idx, in.nt, &o, &pm, &rep), DM_OK);
    if (pm) {
        const float *p = dm_pm_positions(pm);
        char *present = (char *)calloc(in.nv, 1);
        out = pm_mesh(pm, &ids);
        for (i = 0; i < out.nv; i++) present[ids[i]] = 1;
        for (i = 0; i < in.nv; i++)
            if (on_square_boundary(in.pos + 3 * i)) {
                if (!present[i]) missing++;
                else if (memcmp(p + 3 * i, in.pos + 3 * i, 3 * sizeof(float)) != 0) moved++;
            }
        T_CHECK_MSG(missing == 0 && moved == 0, "locked boundary: %zu removed, %zu moved", missing, moved);
        T_EQ_SIZE(out.nt, 200);
        free(present);
        mesh_free(&out);
        free(ids);
        dm_pm_free(pm);
        pm = NULL;
    }
    /* per-vertex locks */
    o.flags = 0;
    locked = (uint8_t *)calloc(in.nv, 1);
    for (i = 0; i < in.nv; i++) locked[i] = unit_random(i, 3) < 0.1;
    o.locked = locked;
    missing = moved = 0;
    T_EQ_INT(dm_simplify(in.pos, in.nv, in.idx, in.nt, &o, &pm, &rep), DM_OK);
    if (pm) {
        const float *p = dm_pm_positions(pm);
        char *present = (char *)calloc(in.nv, 1);
        out = pm_mesh(pm, &ids);
        for (i = 0; i < out.nv; i++) present[ids[i]] = 1;
        for (i = 0; i < in.nv; i++)
            if (locked[i]) {
                if (!present[i]) missing++;
                else if (memcmp(p + 3 * i, in.pos + 3 * i, 3 * sizeof(float)) != 0) moved++;
            }
        T_CHECK_MSG(missing == 0 && moved == 0, "locks: %zu removed, %zu moved", missing, moved);
        free(present);
        mesh_free(&out);
        free(ids);
        dm_pm_free(pm);
        pm = NULL;
    }
    free(locked);
    mesh_free(&in);
}

static void error_bound_checks(const mesh *in)
{
    dm_simplify_options o;
    dm_simplify_report rep, rep_all;
    dm_pm *pm = NULL;
    memset(&o, 0, sizeof o);
    o.target_error = 0.002;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK_MSG(rep.error <= 0.002 && rep.error > 0.0, "error %g for bound 0.002", rep.error);
    T_CHECK(rep.triangle_count < in->nt / 2);
    dm_pm_free(pm);
    pm = NULL;
    o.target_error = 0.0; /* no bound, no target: as far as the checks allow */
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep_all), DM_OK);
    T_CHECK(rep_all.triangle_count < rep.triangle_count && rep_all.error > rep.error);
    T_CHECK(rep_all.triangle_count >= 4);
    dm_pm_free(pm);
}

static int veto_all(void *user, const dm_collapse *c, float corrected[3])
{
    (void)corrected;
    (void)c;
    (*(size_t *)user)++;
    return DM_COLLAPSE_VETO;
}

typedef struct half_state {
    size_t calls, bad_ring;
    const float *input;
} half_state;

/* vetoes every collapse that touches x > 0 (either vertex or the proposed position); checks the ring */
static int veto_half(void *user, const dm_collapse *c, float corrected[3])
{
    half_state *h = (half_state *)user;
    size_t i, has_keep = 0;
    (void)corrected;
    h->calls++;
    for (i = 0; i < 3 * c->triangle_count; i++) {
        if (c->triangles[i] == c->remove) h->bad_ring++;
        has_keep += c->triangles[i] == c->keep;
    }
    if (has_keep != c->triangle_count) h->bad_ring++;
    if (c->position[0] > 0.0f || c->positions[3 * c->remove] > 0.0f || c->positions[3 * c->keep] > 0.0f)
        return DM_COLLAPSE_VETO;
    return DM_COLLAPSE_ALLOW;
}

/* keep stays where it is */
static int stay(void *user, const dm_collapse *c, float corrected[3])
{
    (void)user;
    memcpy(corrected, c->positions + 3 * c->keep, 3 * sizeof(float));
    return DM_COLLAPSE_MOVE;
}

/* a constraint with a strictness: at level 0 it vetoes the half x > 0, at level 1 nothing;
   relax moves it up once */
typedef struct levels {
    int level, honour_relaxed;
    size_t relax_calls, vetoes_at_0, relaxed_asks, relaxed_unmatched, nlog;
    struct { uint32_t a, b; double error; } log[65536]; /* the vetoes: edge, error */
} levels;
static int veto_by_level(void *user, const dm_collapse *c, float corrected[3])
{
    levels *l = (levels *)user;
    (void)corrected;
    if (c->relaxed) { /* a candidate vetoed before, unchanged since: the same edge and error */
        size_t i;
        uint32_t a = c->keep < c->remove ? c->keep : c->remove, b = c->keep ^ c->remove ^ a;
        l->relaxed_asks++;
        for (i = 0; i < l->nlog && !(l->log[i].a == a && l->log[i].b == b && l->log[i].error == c->error); i++) {}
        if (i == l->nlog) l->relaxed_unmatched++;
        if (l->honour_relaxed) return DM_COLLAPSE_ALLOW;
    }
    if (l->level == 0 && (c->positions[3 * c->keep] > 0.0f || c->positions[3 * c->remove] > 0.0f)) {
        l->vetoes_at_0++;
        if (l->nlog < sizeof l->log / sizeof l->log[0]) {
            l->log[l->nlog].a = c->keep < c->remove ? c->keep : c->remove;
            l->log[l->nlog].b = c->keep < c->remove ? c->remove : c->keep;
            l->log[l->nlog++].error = c->error;
        }
        return DM_COLLAPSE_VETO;
    }
    return DM_COLLAPSE_ALLOW;
}
static int relax_once(void *user)
{
    levels *l = (levels *)user;
    l->relax_calls++;
    if (l->level > 0) return 0;
    l->level = 1;
    return 1;
}

/* dm_simplify_options.relax: called only when the queue runs dry above the target with vetoes,
   then every vetoed edge is tried again; without it the run stops there. With it, a vetoed
   candidate also comes back at relax_cost times its cost, asked with dm_collapse.relaxed. */
static void relax_checks(const mesh *in)
{
    dm_simplify_options o;
    dm_simplify_report rep, rep_strict;
    dm_pm *pm = NULL;
    static levels l;
    memset(&o, 0, sizeof o);
    memset(&l, 0, sizeof l);
    o.target_triangles = in->nt / 20;
    o.constraint = veto_by_level;
    o.constraint_user = &l;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep_strict), DM_OK);
    T_CHECK(!rep_strict.reached_target && rep_strict.relaxed == 0 && rep_strict.vetoed > 0);
    dm_pm_free(pm);
    pm = NULL;
    memset(&l, 0, sizeof l);
    o.relax = relax_once;
    o.relax_cost = -1.0; /* no retries: relaxed only once stuck */
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK(l.relaxed_asks == 0);
    T_CHECK_MSG(rep.reached_target && rep.relaxed == 1 && l.relax_calls == 1 && l.level == 1,
                "relaxed %zu times (%zu calls), reached %zu of target %zu", rep.relaxed, l.relax_calls,
                rep.triangle_count, o.target_triangles);
    /* the strict part of the run is the strict run: the same collapses first */
    T_CHECK(rep.collapse_count > rep_strict.collapse_count && l.vetoes_at_0 == rep_strict.vetoed);
    dm_pm_free(pm);
    pm = NULL;
    /* a target the strict run reaches: relax is never called */
    memset(&l, 0, sizeof l);
    o.target_triangles = rep_strict.triangle_count + 2;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK(rep.reached_target && rep.relaxed == 0 && l.relax_calls == 0);
    dm_pm_free(pm);
    pm = NULL;
    /* retries (relax_cost 0 = 16): the vetoed candidates come back asked relaxed, each one the
       same edge with the same error as a veto before it; a constraint that lets them go reaches
       the target without ever being stuck */
    o.target_triangles = in->nt / 20;
    o.relax_cost = 0.0;
    memset(&l, 0, sizeof l);
    l.honour_relaxed = 1;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK_MSG(rep.reached_target && rep.relaxed == 0 && l.relax_calls == 0 && l.relaxed_asks > 0 &&
                    l.relaxed_unmatched == 0 && l.nlog < sizeof l.log / sizeof l.log[0],
                "reached %zu of %zu, relax called %zu times, %zu relaxed asks (%zu matching no veto of %zu)",
                rep.triangle_count, o.target_triangles, l.relax_calls, l.relaxed_asks, l.relaxed_unmatched, l.nlog);
    dm_pm_free(pm);
    pm = NULL;
    /* ... and a constraint that vetoes them again: back to the relax call once stuck */
    memset(&l, 0, sizeof l);
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK(rep.reached_target && rep.relaxed == 1 && l.relax_calls == 1 && l.relaxed_asks > 0 && l.relaxed_unmatched == 0);
    dm_pm_free(pm);
    pm = NULL;
    o.relax_cost = 0.0 / (in->nt ? 0.0 : 1.0); /* NaN */
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_ERR_INVALID_ARGUMENT);
    T_CHECK(pm == NULL);
}

static void constraint_checks(const mesh *in)
{
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    size_t calls = 0, i, bad = 0;
    half_state h;
    memset(&o, 0, sizeof o);
    o.target_triangles = in->nt / 10;
    o.constraint = veto_all;
    o.constraint_user = &calls;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK(pm != NULL && rep.collapse_count == 0 && !rep.reached_target && rep.triangle_count == in->nt);
    T_CHECK(calls > 0 && rep.vetoed == calls);
    dm_pm_free(pm);
    pm = NULL;
    memset(&h, 0, sizeof h);
    o.constraint = veto_half;
    o.constraint_user = &h;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    T_CHECK(h.calls > 0 && h.bad_ring == 0);
    if (pm) { /* every input vertex with x > 0 is still there, unmoved */
        const float *p = dm_pm_positions(pm);
        for (i = 0; i < in->nv; i++)
            if (in->pos[3 * i] > 0.0f) {
                const uint32_t *list;
                if (dm_pm_merged_vertices(pm, (uint32_t)i, &list) != 1 || memcmp(p + 3 * i, in->pos + 3 * i, 12) != 0)
                    bad++;
            }
        T_CHECK_MSG(bad == 0, "veto x > 0: %zu vertices there merged or moved", bad);
        T_CHECK(rep.vetoed > 0 && rep.collapse_count > 0);
        dm_pm_free(pm);
        pm = NULL;
    }
    o.constraint = stay;
    o.constraint_user = NULL;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, &rep), DM_OK);
    if (pm) {
        mesh out;
        uint32_t *ids;
        out = pm_mesh(pm, &ids);
        bad = 0;
        for (i = 0; i < out.nv; i++)
            if (memcmp(out.pos + 3 * i, in->pos + 3 * ids[i], 12) != 0) bad++;
        T_CHECK_MSG(bad == 0 && rep.reached_target, "corrected positions: %zu vertices moved", bad);
        mesh_free(&out);
        free(ids);
        dm_pm_free(pm);
    }
}

/* ---- bad input ------------------------------------------------------------------------------ */

static void bad_input_checks(void)
{
    float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    uint32_t tet[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    uint32_t bad_idx[] = {0, 1, 7};
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = (dm_pm *)&o;
    memset(&o, 0, sizeof o);
    T_EQ_INT(dm_simplify(NULL, 4, tet, 4, NULL, &pm, NULL), DM_ERR_INVALID_ARGUMENT);
    T_CHECK(pm == NULL);
    T_EQ_INT(dm_simplify(p, 4, NULL, 4, NULL, &pm, NULL), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_simplify(p, 4, tet, 4, NULL, NULL, NULL), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_simplify(p, 4, tet, 0, NULL, &pm, NULL), DM_ERR_NO_TRIANGLES);
    T_EQ_INT(dm_simplify(p, 4, bad_idx, 1, NULL, &pm, NULL), DM_ERR_BAD_INDEX);
    o.target_error = NAN;
    T_EQ_INT(dm_simplify(p, 4, tet, 4, &o, &pm, NULL), DM_ERR_INVALID_ARGUMENT);
    o.target_error = -1.0;
    T_EQ_INT(dm_simplify(p, 4, tet, 4, &o, &pm, NULL), DM_ERR_INVALID_ARGUMENT);
    o.target_error = 0.0;
    {
        float q[15];
        memcpy(q, p, sizeof q);
        q[4] = NAN;
        T_EQ_INT(dm_simplify(q, 4, tet, 4, NULL, &pm, NULL), DM_ERR_BAD_POSITION);
        q[4] = 0.0f;
        q[13] = NAN; /* vertex 4, not referenced */
        T_EQ_INT(dm_simplify(q, 5, tet, 4, NULL, &pm, &rep), DM_OK);
        T_CHECK(rep.vertex_count == 4 && rep.triangle_count == 4); /* a tetrahedron cannot shrink */
        dm_pm_free(pm);
        pm = NULL;
        q[13] = INFINITY;
        q[0] = 1e30f;
        T_EQ_INT(dm_simplify(q, 5, tet, 4, NULL, &pm, NULL), DM_ERR_BAD_POSITION);
    }
    /* a lone triangle, and one with a repeated index */
    {
        uint32_t t[] = {0, 1, 2, 1, 1, 2};
        T_EQ_INT(dm_simplify(p, 3, t, 2, NULL, &pm, &rep), DM_OK);
        T_CHECK(rep.triangle_count == 1 && rep.dropped_triangles == 1 && rep.input_triangles == 1);
        dm_pm_free(pm);
        pm = NULL;
        T_EQ_INT(dm_simplify(p, 3, t + 3, 1, NULL, &pm, &rep), DM_OK);
        T_CHECK(rep.triangle_count == 0 && rep.vertex_count == 0);
        dm_pm_free(pm);
        pm = NULL;
    }
    dm_pm_free(NULL);
    T_EQ_SIZE(dm_pm_split_count(NULL), 0);
}

/* A sheet with a seam of duplicate vertices, zero-area triangles, a fin on an interior edge (an
   edge with three triangles) and isolated vertices. */
static void messy_checks(void)
{
    mesh s = sheet(24), m, out;
    size_t extra_v = 30, i, n = 24, fin_tri, kept_fin = 0, bad, bnd, deg0 = 0, deg, zero_tris;
    long euler;
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    uint32_t *ids, a, b;
    m.nv = s.nv + extra_v;
    m.nt = s.nt + 3;
    m.pos = (float *)malloc(3 * m.nv * sizeof(float));
    m.idx = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t));
    memcpy(m.pos, s.pos, 3 * s.nv * sizeof(float));
    memcpy(m.idx, s.idx, 3 * s.nt * sizeof(uint32_t));
    /* duplicate the column x = 12/24 for the triangles right of it: a seam of twin vertices */
    for (i = 0; i <= n; i++) {
        uint32_t v = (uint32_t)(i * (n + 1) + 12), twin = (uint32_t)(s.nv + i);
        size_t t;
        memcpy(m.pos + 3 * twin, s.pos + 3 * v, 12);
        for (t = 0; t < s.nt; t++) {
            int k, right = 0;
            for (k = 0; k < 3; k++) right |= (m.idx[3 * t + k] % (n + 1)) > 12 && m.idx[3 * t + k] < s.nv;
            for (k = 0; k < 3; k++)
                if (right && m.idx[3 * t + k] == v) m.idx[3 * t + k] = twin;
        }
    }
    /* isolated vertices s.nv + 25 .. s.nv + 29 (one far away) */
    for (i = s.nv + 25; i < m.nv; i++) {
        m.pos[3 * i] = 5.0f + (float)i;
        m.pos[3 * i + 1] = m.pos[3 * i + 2] = 0.0f;
    }
    /* zero-area: flatten one quad's triangle onto a line (three collinear points on row 3) */
    m.pos[3 * (3 * (n + 1) + 5) + 2] = 0.0f;
    /* a fin on the interior edge (a, b) of row 6: a third triangle with a new apex */
    a = (uint32_t)(6 * (n + 1) + 4);
    b = a + 1;
    m.pos[3 * (s.nv + 25)] = m.pos[3 * a];
    m.pos[3 * (s.nv + 25) + 1] = m.pos[3 * a + 1] + 0.02f;
    m.pos[3 * (s.nv + 25) + 2] = 0.3f;
    fin_tri = s.nt;
    m.idx[3 * fin_tri] = a;
    m.idx[3 * fin_tri + 1] = b;
    m.idx[3 * fin_tri + 2] = (uint32_t)(s.nv + 25);
    /* a degenerate triangle with three distinct collinear vertices on the seam column */
    m.idx[3 * (fin_tri + 1)] = (uint32_t)(2 * (n + 1) + 12);
    m.idx[3 * (fin_tri + 1) + 1] = (uint32_t)(3 * (n + 1) + 12);
    m.idx[3 * (fin_tri + 1) + 2] = (uint32_t)(4 * (n + 1) + 12);
    /* and one with a repeated index */
    m.idx[3 * (fin_tri + 2)] = 7;
    m.idx[3 * (fin_tri + 2) + 1] = 8;
    m.idx[3 * (fin_tri + 2) + 2] = 7;
    {
        mesh in_view = m;
        in_view.nt = m.nt - 1;
        topology(&in_view, &bad, &bnd, &deg0, &euler);
    }
    memset(&o, 0, sizeof o);
    o.target_triangles = 100;
    T_EQ_INT(dm_simplify(m.pos, m.nv, m.idx, m.nt, &o, &pm, &rep), DM_OK);
    if (pm) {
        const uint32_t *idx_all;
        T_EQ_SIZE(rep.dropped_triangles, 1);
        T_CHECK(rep.frozen_vertices >= 3);
        T_CHECK(rep.triangle_count <= 140); /* the frozen fan around the fin stays */
        out = pm_mesh(pm, &ids);
        topology(&out, &bad, &bnd, &deg, &euler);
        zero_tris = deg;
        T_CHECK_MSG(deg <= deg0, "messy: %zu degenerate triangles out of %zu in", deg, deg0);
        /* the triangles around the fin's edge are untouched: find the fin, same vertices */
        for (i = 0; i < out.nt; i++) {
            uint32_t x = ids[out.idx[3 * i]], y = ids[out.idx[3 * i + 1]], z = ids[out.idx[3 * i + 2]];
            if (x == a && y == b && z == (uint32_t)(s.nv + 25)) kept_fin++;
        }
        T_EQ_SIZE(kept_fin, 1);
        idx_all = NULL;
        (void)idx_all;
        T_CHECK(memcmp(dm_pm_positions(pm) + 3 * a, m.pos + 3 * a, 12) == 0);
        /* seam twins never merge with each other across the crack: both sides keep a boundary */
        T_CHECK(bnd > 0 && zero_tris <= 1);
        mesh_free(&out);
        free(ids);
        dm_pm_free(pm);
    }
    mesh_free(&s);
    mesh_free(&m);
}

/* ---- progress, cancel, allocation failure --------------------------------------------------- */

/* Non-manifold input: sheets with fins (a third triangle on an edge) and bowties (a lone
   triangle on a vertex). Only the non-manifold vertices are frozen; at every level of the
   progressive mesh no triangle repeats a vertex or another triangle's vertices, no edge is
   non-manifold that was not before, and the levels come back bit for bit. The fins' neighbours
   collapse: some vertex in a triangle with a fin's edge (not on it) is merged away. */
static uint32_t nm_rand(unsigned long long *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (uint32_t)(*s >> 11);
}

static int cmp_tri(const void *a, const void *b) { return memcmp(a, b, 3 * sizeof(uint32_t)); }

/* triangles that repeat a vertex or another's vertex set, and edges in more than two triangles */
static void nm_counts(const uint32_t *idx, size_t nt, size_t *bad_tris, size_t *nm_edges)
{
    uint32_t *t = (uint32_t *)malloc(3 * nt * sizeof(uint32_t) + 4);
    uint64_t *e = (uint64_t *)malloc(3 * nt * sizeof(uint64_t) + 8);
    size_t i, k, n = 0;
    *bad_tris = *nm_edges = 0;
    for (i = 0; i < nt; i++) {
        uint32_t a = idx[3 * i], b = idx[3 * i + 1], c = idx[3 * i + 2], x;
        if (a == b || b == c || a == c) (*bad_tris)++;
        if (a > b) { x = a; a = b; b = x; }
        if (b > c) { x = b; b = c; c = x; }
        if (a > b) { x = a; a = b; b = x; }
        t[3 * i] = a; t[3 * i + 1] = b; t[3 * i + 2] = c;
        e[n++] = (uint64_t)a << 32 | b;
        e[n++] = (uint64_t)b << 32 | c;
        e[n++] = (uint64_t)a << 32 | c;
    }
    qsort(t, nt, 3 * sizeof(uint32_t), cmp_tri);
    for (i = 1; i < nt; i++) *bad_tris += memcmp(t + 3 * i, t + 3 * (i - 1), 3 * sizeof(uint32_t)) == 0;
    qsort(e, n, sizeof(uint64_t), cmp_u64);
    for (i = 0; i < n; i = k) {
        for (k = i; k < n && e[k] == e[i]; k++) {}
        *nm_edges += k - i > 2;
    }
    free(t);
    free(e);
}

static void nonmanifold_checks(void)
{
    unsigned long long seed = 88172645463325252ull;
    int iter, bad_levels = 0, round_trips = 0, frozen_ok = 0, neighbour_gone = 0;
    for (iter = 0; iter < 100; iter++) {
        int n = 4 + (int)(nm_rand(&seed) % 8), x, y, f, nf = 1 + (int)(nm_rand(&seed) % 8);
        size_t nv = (size_t)(n + 1) * (size_t)(n + 1), nt = 0, nsplit, lev, bad, nm0, nm1, i, nfrozen = 0;
        float *P = (float *)malloc(3 * sizeof(float) * (nv + 2 * (size_t)nf));
        uint32_t *T = (uint32_t *)malloc(3 * sizeof(uint32_t) * (2 * (size_t)n * (size_t)n + (size_t)nf)), *ids;
        uint8_t *is_nm = (uint8_t *)calloc(nv + 2 * (size_t)nf, 1), *near_fin = (uint8_t *)calloc(nv + 2 * (size_t)nf, 1);
        dm_simplify_options o;
        dm_simplify_report rep;
        dm_pm *pm = NULL;
        mesh lo, again;
        for (y = 0; y <= n; y++)
            for (x = 0; x <= n; x++) {
                float *p = P + 3 * ((size_t)y * (size_t)(n + 1) + (size_t)x);
                p[0] = (float)x + 0.001f * (float)(nm_rand(&seed) % 100);
                p[1] = (float)y;
                p[2] = 0.0005f * (float)(nm_rand(&seed) % 100);
            }
        for (y = 0; y < n; y++)
            for (x = 0; x < n; x++) {
                uint32_t a = (uint32_t)(y * (n + 1) + x), b = a + 1, c = a + (uint32_t)n + 1, d = c + 1;
                T[3 * nt] = a; T[3 * nt + 1] = b; T[3 * nt + 2] = d; nt++;
                T[3 * nt] = a; T[3 * nt + 1] = d; T[3 * nt + 2] = c; nt++;
            }
        for (f = 0; f < nf; f++) {
            uint32_t t = nm_rand(&seed) % (uint32_t)(2 * n * n), c = nm_rand(&seed) % 3, a = T[3 * t + c],
                     b = T[3 * t + (c + 1) % 3], ap = (uint32_t)nv++;
            P[3 * ap] = P[3 * a] + 0.3f; P[3 * ap + 1] = P[3 * a + 1] + 0.2f; P[3 * ap + 2] = 1.0f + (float)f;
            if (nm_rand(&seed) % 2) { /* a fin on edge a b */
                T[3 * nt] = a; T[3 * nt + 1] = b; T[3 * nt + 2] = ap; nt++;
                is_nm[a] = is_nm[b] = 1;
            } else { /* a bowtie at a */
                uint32_t q = (uint32_t)nv++;
                P[3 * q] = P[3 * a] - 0.3f; P[3 * q + 1] = P[3 * a + 1]; P[3 * q + 2] = 1.5f + (float)f;
                T[3 * nt] = a; T[3 * nt + 1] = ap; T[3 * nt + 2] = q; nt++;
                is_nm[a] = 1;
            }
        }
        for (i = 0; i < 2 * (size_t)n * (size_t)n; i++) /* grid vertices in a triangle with a frozen one */
            if (is_nm[T[3 * i]] | is_nm[T[3 * i + 1]] | is_nm[T[3 * i + 2]])
                near_fin[T[3 * i]] = near_fin[T[3 * i + 1]] = near_fin[T[3 * i + 2]] = 1;
        for (i = 0; i < nv; i++) {
            nfrozen += is_nm[i];
            if (is_nm[i]) near_fin[i] = 0;
        }
        nm_counts(T, nt, &bad, &nm0);
        memset(&o, 0, sizeof o);
        o.target_triangles = 4;
        T_EQ_INT(dm_simplify(P, nv, T, nt, &o, &pm, &rep), DM_OK);
        if (!pm) continue;
        frozen_ok += rep.frozen_vertices == nfrozen;
        nsplit = dm_pm_split_count(pm);
        for (lev = 0; lev <= nsplit; lev++) {
            dm_pm_set_level(pm, lev);
            lo = pm_mesh(pm, &ids);
            nm_counts(lo.idx, lo.nt, &bad, &nm1);
            free(ids);
            mesh_free(&lo);
            if (bad || nm1 > nm0) { bad_levels++; break; }
        }
        dm_pm_set_level(pm, 0);
        lo = pm_mesh(pm, &ids);
        for (i = 0; i < lo.nv; i++) near_fin[ids[i]] = 0; /* what is left is gone */
        for (i = 0; i < nv && !near_fin[i]; i++) {}
        neighbour_gone += i < nv;
        free(ids);
        dm_pm_set_level(pm, nsplit);
        dm_pm_set_level(pm, 0);
        again = pm_mesh(pm, &ids);
        round_trips += lo.nt == again.nt && lo.nv == again.nv && memcmp(lo.pos, again.pos, 3 * lo.nv * sizeof(float)) == 0 &&
                       memcmp(lo.idx, again.idx, 3 * lo.nt * sizeof(uint32_t)) == 0;
        free(ids);
        mesh_free(&lo);
        mesh_free(&again);
        dm_pm_free(pm);
        free(P); free(T); free(is_nm); free(near_fin);
    }
    T_CHECK_MSG(bad_levels == 0, "non-manifold sheets: %d runs with a repeated or doubled triangle or a new non-manifold edge", bad_levels);
    T_CHECK_MSG(round_trips == 100, "non-manifold sheets: %d of 100 round trips bit for bit", round_trips);
    T_CHECK_MSG(frozen_ok == 100, "non-manifold sheets: %d of 100 froze exactly their non-manifold vertices", frozen_ok);
    T_CHECK_MSG(neighbour_gone >= 90, "non-manifold sheets: %d of 100 merged a neighbour of a frozen vertex", neighbour_gone);
    printf("  non-manifold sheets: 100 runs, %d froze exactly their non-manifold vertices, %d merged a neighbour of one\n",
           frozen_ok, neighbour_gone);
}

static int count_progress(void *user, float done)
{
    float *last = (float *)user;
    if (done < last[0] || done > 1.0f) last[1] = 1.0f; /* not monotone */
    last[0] = done;
    last[2] += 1.0f;
    return 0;
}

static int cancel_now(void *user, float done)
{
    (void)user;
    (void)done;
    return 1;
}

typedef struct counting {
    long allocs, frees, fail_at;
} counting;

static void *c_alloc(void *user, size_t size)
{
    counting *c = (counting *)user;
    if (c->fail_at >= 0 && c->allocs >= c->fail_at) return NULL;
    c->allocs++;
    return malloc(size);
}

static void c_free(void *user, void *p)
{
    counting *c = (counting *)user;
    if (p) c->frees++;
    free(p);
}

static void resource_checks(const mesh *in)
{
    dm_simplify_options o;
    dm_pm *pm = NULL;
    float state[3] = {0, 0, 0};
    counting c;
    dm_allocator al;
    long k, total, bad = 0;
    memset(&o, 0, sizeof o);
    o.target_triangles = in->nt / 20;
    o.progress = count_progress;
    o.progress_user = state;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, NULL), DM_OK);
    T_CHECK(state[2] >= 2.0f && state[1] == 0.0f && state[0] == 1.0f);
    dm_pm_free(pm);
    o.progress = cancel_now;
    pm = (dm_pm *)&o;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, NULL), DM_CANCELLED);
    T_CHECK(pm == NULL);
    o.progress = NULL;
    memset(&c, 0, sizeof c);
    c.fail_at = -1;
    al.alloc = c_alloc;
    al.free = c_free;
    al.user = &c;
    o.allocator = &al;
    T_EQ_INT(dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, NULL), DM_OK);
    dm_pm_free(pm);
    T_EQ_INT(c.allocs, c.frees);
    total = c.allocs;
    for (k = 0; k < total; k++) {
        dm_result r;
        c.allocs = c.frees = 0;
        c.fail_at = k;
        pm = NULL;
        r = dm_simplify(in->pos, in->nv, in->idx, in->nt, &o, &pm, NULL);
        if (r != DM_ERR_OUT_OF_MEMORY || pm != NULL || c.allocs != c.frees) bad++;
    }
    T_CHECK_MSG(bad == 0 && total > 10, "allocation failure: %ld of %ld runs wrong", bad, total);
    /* bad input, as the doc says: a bad index before anything is allocated; a bad position
       (checked once per used vertex, after the working arrays) leaves nothing allocated */
    {
        uint32_t *idx = (uint32_t *)malloc(3 * in->nt * sizeof(uint32_t));
        float *pos = (float *)malloc(3 * in->nv * sizeof(float));
        T_CHECK(idx && pos);
        if (idx && pos) {
            memcpy(idx, in->idx, 3 * in->nt * sizeof(uint32_t));
            memcpy(pos, in->pos, 3 * in->nv * sizeof(float));
            idx[3 * in->nt - 1] = (uint32_t)in->nv; /* the last corner */
            c.allocs = c.frees = 0;
            c.fail_at = -1;
            pm = (dm_pm *)&o;
            T_EQ_INT(dm_simplify(pos, in->nv, idx, in->nt, &o, &pm, NULL), DM_ERR_BAD_INDEX);
            T_CHECK(pm == NULL && c.allocs == 0);
            idx[3 * in->nt - 1] = in->idx[3 * in->nt - 1];
            pos[3 * (size_t)idx[3 * in->nt - 1] + 1] = NAN; /* a vertex of the last triangle */
            pm = (dm_pm *)&o;
            T_EQ_INT(dm_simplify(pos, in->nv, idx, in->nt, &o, &pm, NULL), DM_ERR_BAD_POSITION);
            T_CHECK(pm == NULL && c.allocs == c.frees);
        }
        free(idx);
        free(pos);
    }
}

/* on_collapse: once per collapse done, in order, before it is applied (positions still the old
   ones), with the position keep goes to; the old triangles are keep's and remove's. And a
   constraint that moves keep far away (its cost goes up): the candidate waits in the queue at
   that cost; the result is still deterministic and level k is still the k-th collapse. */
typedef struct seen {
    size_t n, bad;
    uint32_t keep[8192], remove[8192];
    float pos[8192][3];
} seen;
static void on_collapse_rec(void *user, const dm_collapse *d)
{
    seen *s = (seen *)user;
    size_t i;
    int has_keep = 0, has_remove = 0;
    if (s->n < 8192) {
        s->keep[s->n] = d->keep;
        s->remove[s->n] = d->remove;
        memcpy(s->pos[s->n], d->position, sizeof s->pos[0]);
    }
    s->n++;
    for (i = 0; i < d->old_triangle_count; i++) {
        const uint32_t *t = d->old_triangles + 3 * i;
        int k;
        for (k = 0; k < 3; k++) {
            has_keep |= t[k] == d->keep;
            has_remove |= t[k] == d->remove;
        }
        if (!(t[0] == d->keep || t[1] == d->keep || t[2] == d->keep || t[0] == d->remove || t[1] == d->remove ||
              t[2] == d->remove))
            s->bad++;
    }
    for (i = 0; i < d->triangle_count; i++) {
        const uint32_t *t = d->triangles + 3 * i;
        if (t[0] == d->remove || t[1] == d->remove || t[2] == d->remove) s->bad++;
    }
    if (!has_keep || !has_remove) s->bad++;
}
static int push_up(void *user, const dm_collapse *c, float corrected[3])
{
    (void)user;
    if ((c->keep + c->remove) % 3) return DM_COLLAPSE_ALLOW;
    corrected[0] = c->position[0] * 1.001f; /* a little outward on the unit sphere: costs more */
    corrected[1] = c->position[1] * 1.001f;
    corrected[2] = c->position[2] * 1.001f;
    return DM_COLLAPSE_MOVE;
}
static void on_collapse_checks(const mesh *m)
{
    static seen a, b;
    dm_simplify_options o;
    dm_simplify_report ra, rb;
    dm_pm *pa = NULL, *pb = NULL;
    size_t i, mismatch = 0;
    memset(&o, 0, sizeof o);
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    o.target_triangles = m->nt / 10;
    o.on_collapse = on_collapse_rec;
    o.constraint = push_up;
    o.constraint_user = &a;
    T_EQ_INT(dm_simplify(m->pos, m->nv, m->idx, m->nt, &o, &pa, &ra), DM_OK);
    o.constraint_user = &b;
    T_EQ_INT(dm_simplify(m->pos, m->nv, m->idx, m->nt, &o, &pb, &rb), DM_OK);
    if (!pa || !pb) { dm_pm_free(pa); dm_pm_free(pb); return; }
    T_EQ_SIZE(a.n, ra.collapse_count);
    T_EQ_SIZE(a.bad, 0);
    T_CHECK(a.n == b.n && memcmp(a.keep, b.keep, sizeof a.keep) == 0 && memcmp(a.pos, b.pos, sizeof a.pos) == 0);
    for (i = 0; i < a.n && i < 8192; i++) { /* collapse i undoes as split (n - 1 - i) */
        dm_vsplit v;
        if (!dm_pm_get_vsplit(pa, a.n - 1 - i, &v) || v.keep != a.keep[i] || v.remove != a.remove[i] ||
            memcmp(v.merged_position, a.pos[i], sizeof v.merged_position) != 0)
            mismatch++;
    }
    T_CHECK_MSG(mismatch == 0, "%zu of %zu on_collapse calls differ from the recorded splits", mismatch, a.n);
    T_CHECK(ra.triangle_count <= m->nt / 10);
    dm_pm_free(pa);
    dm_pm_free(pb);
}

/* White box: the placement run two edges at a time (dm__qem_optimal_lanes) gives the bits of
   the one-at-a-time solve (dm__qem_optimal) where it accepts a lane, and refuses exactly the
   lanes where dm__qem_optimal falls back to the segment: random quadrics from 1 to 6 planes
   (1 or 2 planes: A singular, always refused), minimisers near and far from the edge. */
static void lanes_checks(void)
{
    size_t trial, accepted = 0, refused = 0, mismatched = 0;
    for (trial = 0; trial < 20000; trial++) {
        dm__qem_quadric q[DM__QEM_LANES];
        double pa[DM__QEM_LANES][3], pb[DM__QEM_LANES][3], cost[DM__QEM_LANES];
        const double *p0[DM__QEM_LANES], *p1[DM__QEM_LANES];
        int ok[DM__QEM_LANES], l, k;
        for (l = 0; l < DM__QEM_LANES; l++) { /* planes through a point near the edge or far from it */
            uint64_t id = (uint64_t)trial * DM__QEM_LANES + (uint64_t)l;
            int planes = 1 + (int)(unit_random(id, 1) * 6.0), j;
            double far = unit_random(id, 2) < 0.5 ? 0.03 : 0.2, t[3];
            for (k = 0; k < 3; k++) {
                pa[l][k] = unit_random(id, 10 + (uint64_t)k) - 0.5;
                pb[l][k] = pa[l][k] + 0.05 * (unit_random(id, 20 + (uint64_t)k) - 0.5);
                t[k] = 0.5 * (pa[l][k] + pb[l][k]) + far * (unit_random(id, 30 + (uint64_t)k) - 0.5);
            }
            p0[l] = pa[l];
            p1[l] = pb[l];
            memset(&q[l], 0, sizeof q[l]);
            for (j = 0; j < planes; j++) {
                float d[3];
                double n[3];
                random_direction(id * 8 + (uint64_t)j, 3, d);
                for (k = 0; k < 3; k++) n[k] = d[k];
                dm__qem_quadric_add_plane(&q[l], n, -(n[0] * t[0] + n[1] * t[1] + n[2] * t[2]) + 1e-3 * (unit_random(id * 8 + (uint64_t)j, 4) - 0.5),
                                          0.1 + unit_random(id * 8 + (uint64_t)j, 5));
            }
        }
        dm__qem_optimal_lanes(q, p0, p1, cost, ok);
        for (l = 0; l < DM__QEM_LANES; l++) {
            double x[3], xs[3], c = dm__qem_optimal(&q[l], p0[l], p1[l], x);
            dm__qem_segment_min(&q[l], p0[l], p1[l], xs);
            if (ok[l]) { /* solved: the same cost, bit for bit */
                accepted++;
                mismatched += memcmp(&c, &cost[l], sizeof c) != 0;
            } else { /* refused: dm__qem_optimal took the segment too */
                refused++;
                mismatched += memcmp(x, xs, sizeof x) != 0;
            }
        }
    }
    printf("  lanes: %zu accepted, %zu refused, %zu differ from the one-at-a-time solve\n", accepted, refused, mismatched);
    T_CHECK(accepted > 1000 && refused > 1000);
    T_CHECK(mismatched == 0);
}

/* m simplified to target (it must reach it): the DM_COUNT_OPS steps it took; frees m */
static unsigned long long counted_simplify(mesh *m, size_t target)
{
    dm_simplify_options o = dm_simplify_default_options();
    dm_pm *pm = NULL;
    dm_simplify_report rep;
    o.target_triangles = target;
    g_ops = 0;
    T_CHECK(dm_simplify(m->pos, m->nv, m->idx, m->nt, &o, &pm, &rep) == DM_OK);
    T_CHECK(rep.reached_target);
    dm_pm_free(pm);
    free(m->pos);
    free(m->idx);
    return g_ops;
}

static void queue_checks(void)
{
    unsigned long long ops[2];
    int g;
    for (g = 0; g < 2; g++) {
        mesh m = sheet_amp(g ? 200 : 100, 0.0f);
        ops[g] = counted_simplify(&m, m.nt / 50);
    }
    printf("  flat grids 20000 / 80000 triangles: %llu / %llu queue and list steps (%.2f x)\n", ops[0], ops[1],
           (double)ops[1] / (double)(ops[0] ? ops[0] : 1));
    T_CHECK_MSG(ops[1] <= 6 * ops[0], "queue and list steps %llu for 80k triangles, %llu for 20k", ops[1], ops[0]);
}

/* A fan of K triangles around vertex 0 (a cone: the rim on the unit circle in z = 0, the centre
   at z = 0.2), closed or open (one sector missing, the centre on the boundary), simplified to
   100 triangles: the queue and corner-list steps (DM_COUNT_OPS) at K = 80k are at most 6 times
   those at 20k (linear, 4x, up to a logarithm; dropping each dead triangle from the centre's
   list at once, or looking for the centre's boundary neighbour through its whole list once per
   corner, grew them with K squared). */
static void valence_checks(void)
{
    static const int Ks[3] = {20000, 40000, 80000};
    unsigned long long ops[3];
    int closed, k, i;
    for (closed = 0; closed < 2; closed++) {
        for (k = 0; k < 3; k++) {
            int K = Ks[k];
            mesh m;
            m.nv = (size_t)K + 1;
            m.nt = closed ? (size_t)K : (size_t)K - 1;
            m.pos = (float *)malloc(3 * m.nv * sizeof(float));
            m.idx = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t));
            ops[k] = 0;
            if (!T_CHECK(m.pos && m.idx)) { free(m.pos); free(m.idx); return; }
            m.pos[0] = 0.0f; m.pos[1] = 0.0f; m.pos[2] = 0.2f;
            for (i = 0; i < K; i++) {
                double a = 6.283185307179586 * i / K;
                m.pos[3 + 3 * i] = (float)cos(a); m.pos[4 + 3 * i] = (float)sin(a); m.pos[5 + 3 * i] = 0.0f;
            }
            for (i = 0; i < (int)m.nt; i++) {
                m.idx[3 * i] = 0; m.idx[3 * i + 1] = (uint32_t)(1 + i); m.idx[3 * i + 2] = (uint32_t)(1 + (i + 1) % K);
            }
            ops[k] = counted_simplify(&m, 100);
        }
        printf("  %s fan of 20k / 40k / 80k triangles: %llu / %llu / %llu queue and list steps (80k / 20k = %.2f)\n",
               closed ? "closed" : "open", ops[0], ops[1], ops[2], (double)ops[2] / (double)(ops[0] ? ops[0] : 1));
        T_CHECK(ops[0] >= 20000); /* the hook counts: at least a step a triangle */
        T_CHECK_MSG(ops[2] <= 6 * ops[0], "%s fan: %llu steps at 80k, %llu at 20k", closed ? "closed" : "open", ops[2], ops[0]);
    }
}

int main(int argc, char **argv)
{
    gsph_mesh g;
    mesh sph;
    mio_mesh bunny;
    mio_error err;
    T_BEGIN(argc, argv);
    T_CHECK(gsph_generate(16, &g) == 0);
    sph.pos = g.positions;
    sph.nv = g.vertex_count;
    sph.idx = g.indices;
    sph.nt = g.triangle_count;
    closed_mesh_checks("sphere 5120", &sph, 0.05);
    closed_mesh_checks("sphere 5120 to 12", &sph, 0.0025);
    pm_checks("sphere 5120", &sph, 500);
    open_mesh_checks();
    frame_checks();
    lanes_checks();
    queue_checks();
    valence_checks();
    error_bound_checks(&sph);
    constraint_checks(&sph);
    relax_checks(&sph);
    on_collapse_checks(&sph);
    bad_input_checks();
    messy_checks();
    nonmanifold_checks();
    resource_checks(&sph);
    if (mio_read_file(BUNNY, NULL, &bunny, &err) == MIO_OK) {
        mesh b;
        b.pos = bunny.positions;
        b.nv = bunny.vertex_count;
        b.idx = bunny.indices;
        b.nt = bunny.triangle_count;
        closed_mesh_checks("bunny 1%", &b, 0.01);
        closed_mesh_checks("bunny 10%", &b, 0.10);
        pm_checks("bunny", &b, 700);
        mio_free_mesh(&bunny);
    } else {
        T_SKIP_N(28, "bunny checks", BUNNY " missing: apt-get install glmark2-data");
    }
    gsph_free(&g);
    return T_END();
}
