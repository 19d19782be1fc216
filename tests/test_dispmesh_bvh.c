/* test_dispmesh_bvh - unit tests of dispmesh.h's BVH ray caster (no reference library needed).

   - brute force: on small generated meshes (bumpy icospheres, a triangle soup with degenerate
     triangles) every query equals a loop over all triangles with the same watertight test, bit
     for bit, and agrees with an independent double-precision Moller-Trumbore under the
     reference test's mismatch rule (hit/miss or |dt| > 1e-5 max(t, 1e-3 diagonal));
   - watertightness: rays aimed at every vertex and edge midpoint of closed meshes, from the
     point plus a small offset along its angle-weighted pseudonormal, back along minus it, all hit;
   - closest point on 10k random points against an independent brute force, to 1e-6 diagonal;
   - the line query (both directions), occlusion, batches;
   - bad input returns codes; allocation-failure injection returns DM_ERR_OUT_OF_MEMORY and
     leaks nothing; progress and cancel; determinism (identical trees and hits on a rebuild and
     with the HIGH quality option and every leaf size); refit after the vertices move;
   - `--digest` prints a hash of every query's answer on a fixed set of rays (random, aimed at
     vertices, axis-aligned, limited) instead of testing: tests/simd_same.sh builds this file
     with the portable path, DM_USE_SSE2 and DM_USE_AVX2 and requires the same digest. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <float.h>

#include "test.h"
#include "../bench/sphere.h"
#define DM_IMPLEMENTATION
#include "dispmesh.h"

/* ---- deterministic numbers ------------------------------------------------------------------ */

#include "hashrand.h"

/* ---- meshes --------------------------------------------------------------------------------- */

typedef struct mesh {
    float *pos;
    size_t nv;
    uint32_t *idx;
    size_t nt;
    float lo[3], hi[3];
    double diag;
} mesh;

static void mesh_bounds(mesh *m)
{
    size_t v;
    int k;
    m->diag = 0.0;
    for (k = 0; k < 3; k++) m->lo[k] = m->hi[k] = m->pos[k];
    for (v = 0; v < m->nv; v++)
        for (k = 0; k < 3; k++) {
            m->lo[k] = fminf(m->lo[k], m->pos[3 * v + k]);
            m->hi[k] = fmaxf(m->hi[k], m->pos[3 * v + k]);
        }
    for (k = 0; k < 3; k++) m->diag += (double)(m->hi[k] - m->lo[k]) * (m->hi[k] - m->lo[k]);
    m->diag = sqrt(m->diag);
}

static int sphere_mesh(int freq, mesh *m)
{
    gsph_mesh g;
    if (gsph_generate(freq, &g) != 0) return 0;
    m->pos = g.positions;
    m->nv = g.vertex_count;
    m->idx = g.indices;
    m->nt = g.triangle_count;
    mesh_bounds(m);
    return 1;
}

/* 400 random triangles in the unit cube, one in 10 degenerate (a repeated corner, collinear
   corners, or all corners equal) */
static int soup_mesh(mesh *m)
{
    size_t t, k;
    m->nt = 400;
    m->nv = 3 * m->nt;
    m->pos = (float *)malloc(3 * m->nv * sizeof(float));
    m->idx = (uint32_t *)malloc(3 * m->nt * sizeof(uint32_t));
    if (!m->pos || !m->idx) return 0;
    for (t = 0; t < m->nt; t++) {
        float c[3];
        for (k = 0; k < 3; k++) c[k] = (float)unit_random(t, k);
        for (k = 0; k < 9; k++) m->pos[9 * t + k] = c[k % 3] + (float)(0.3 * (unit_random(t, 3 + k) - 0.5));
        for (k = 0; k < 3; k++) m->idx[3 * t + k] = (uint32_t)(3 * t + k);
        if (t % 10 == 1) m->idx[3 * t + 2] = m->idx[3 * t]; /* repeated corner */
        if (t % 10 == 3)                                    /* collinear corners */
            for (k = 0; k < 3; k++) m->pos[9 * t + 6 + k] = 2.0f * m->pos[9 * t + 3 + k] - m->pos[9 * t + k];
        if (t % 10 == 5) /* a point */
            for (k = 0; k < 3; k++) m->pos[9 * t + 3 + k] = m->pos[9 * t + 6 + k] = m->pos[9 * t + k];
    }
    mesh_bounds(m);
    return 1;
}

static void mesh_free(mesh *m)
{
    free(m->pos);
    free(m->idx);
    memset(m, 0, sizeof *m);
}

/* ---- brute force ---------------------------------------------------------------------------- */

/* every triangle with the library's own watertight test (nearest, then lowest index) */
static int brute_same_test(const mesh *m, const dm_ray *ray, dm_hit *hit)
{
    dm__ray_pre r;
    size_t i;
    int found = 0;
    hit->triangle = DM_NO_HIT;
    if (!dm__prepare_ray(ray->org, ray->dir, 1.0f, &r)) return 0;
    for (i = 0; i < m->nt; i++) {
        float p[9], t, u, v;
        int c, k;
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) p[3 * c + k] = m->pos[3 * (size_t)m->idx[3 * i + c] + k];
        if (!dm__triangle(&r, p, ray->tmin, found ? hit->t : ray->tmax, &t, &u, &v)) continue;
        if (found && t == hit->t && i > hit->triangle) continue;
        found = 1;
        hit->t = t;
        hit->u = u;
        hit->v = v;
        hit->triangle = (uint32_t)i;
    }
    return found;
}

/* independent double-precision Moller-Trumbore, two-sided, nearest t > tmin (t only) */
static int brute_double(const mesh *m, const dm_ray *ray, double *t_out)
{
    size_t i;
    int found = 0;
    for (i = 0; i < m->nt; i++) {
        const float *a = m->pos + 3 * (size_t)m->idx[3 * i], *b = m->pos + 3 * (size_t)m->idx[3 * i + 1],
                    *c = m->pos + 3 * (size_t)m->idx[3 * i + 2];
        double e1[3], e2[3], s[3], p[3], q[3], det, u, v, t;
        int k;
        for (k = 0; k < 3; k++) {
            e1[k] = (double)b[k] - a[k];
            e2[k] = (double)c[k] - a[k];
            s[k] = (double)ray->org[k] - a[k];
        }
        p[0] = ray->dir[1] * e2[2] - ray->dir[2] * e2[1];
        p[1] = ray->dir[2] * e2[0] - ray->dir[0] * e2[2];
        p[2] = ray->dir[0] * e2[1] - ray->dir[1] * e2[0];
        det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
        if (det == 0.0) continue;
        q[0] = s[1] * e1[2] - s[2] * e1[1];
        q[1] = s[2] * e1[0] - s[0] * e1[2];
        q[2] = s[0] * e1[1] - s[1] * e1[0];
        u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
        v = (ray->dir[0] * q[0] + ray->dir[1] * q[1] + ray->dir[2] * q[2]) / det;
        t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0 || t < ray->tmin || t > ray->tmax) continue;
        if (!found || t < *t_out) *t_out = t;
        found = 1;
    }
    return found;
}

/* squared distance from p to segment ab */
static double seg_d2(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], len2 = 0, s = 0, d2 = 0;
    int k;
    for (k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ap[k] = p[k] - a[k];
        len2 += ab[k] * ab[k];
        s += ap[k] * ab[k];
    }
    s = len2 > 0 ? fmin(1.0, fmax(0.0, s / len2)) : 0.0;
    for (k = 0; k < 3; k++) d2 += (ap[k] - s * ab[k]) * (ap[k] - s * ab[k]);
    return d2;
}

/* independent closest distance: projection onto the plane when it falls inside, else edges */
static double brute_closest(const mesh *m, const float pf[3])
{
    double best = INFINITY, p[3] = {pf[0], pf[1], pf[2]};
    size_t i;
    for (i = 0; i < m->nt; i++) {
        double a[3], b[3], c[3], n[3], nn, d, e;
        int k;
        for (k = 0; k < 3; k++) {
            a[k] = m->pos[3 * (size_t)m->idx[3 * i] + k];
            b[k] = m->pos[3 * (size_t)m->idx[3 * i + 1] + k];
            c[k] = m->pos[3 * (size_t)m->idx[3 * i + 2] + k];
        }
        n[0] = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
        n[1] = (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]);
        n[2] = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (nn > 0) {
            double h = ((p[0] - a[0]) * n[0] + (p[1] - a[1]) * n[1] + (p[2] - a[2]) * n[2]) / nn, q[3], w[3];
            const double *v0[3] = {a, b, c}, *v1[3] = {b, c, a};
            int inside = 1;
            for (k = 0; k < 3; k++) q[k] = p[k] - h * n[k];
            for (k = 0; k < 3; k++) { /* q on the inner side of each edge */
                double ex[3], qx[3];
                int j;
                for (j = 0; j < 3; j++) {
                    ex[j] = v1[k][j] - v0[k][j];
                    qx[j] = q[j] - v0[k][j];
                }
                w[k] = n[0] * (ex[1] * qx[2] - ex[2] * qx[1]) + n[1] * (ex[2] * qx[0] - ex[0] * qx[2]) +
                       n[2] * (ex[0] * qx[1] - ex[1] * qx[0]);
                if (w[k] < 0) inside = 0;
            }
            if (inside) {
                d = h * h * nn;
                if (d < best) best = d;
                continue;
            }
        }
        d = seg_d2(p, a, b);
        e = seg_d2(p, b, c);
        d = e < d ? e : d;
        e = seg_d2(p, c, a);
        d = e < d ? e : d;
        if (d < best) best = d;
    }
    return sqrt(best);
}

/* ---- counting allocator with failure injection ---------------------------------------------- */

typedef struct counting {
    long live, calls, fail_at; /* fail_at: the 1-based call that fails, 0 = never */
} counting;

static void *counting_alloc(void *user, size_t size)
{
    counting *c = (counting *)user;
    void *p;
    c->calls++;
    if (c->fail_at && c->calls == c->fail_at) return NULL;
    p = malloc(size);
    if (p) c->live++;
    return p;
}

static void counting_free(void *user, void *ptr)
{
    counting *c = (counting *)user;
    if (ptr) c->live--;
    free(ptr);
}

/* ---- ray sets ------------------------------------------------------------------------------- */

/* rays from a sphere of 1.5 diagonals around the box toward random points inside it, and
   rays from inside the box in random directions */
static void random_ray(const mesh *m, size_t i, dm_ray *r)
{
    double c[3];
    int k;
    for (k = 0; k < 3; k++) c[k] = 0.5 * ((double)m->lo[k] + m->hi[k]);
    if (i % 2 == 0) {
        float d[3], target[3];
        double len = 0;
        random_direction(i, 1, d);
        for (k = 0; k < 3; k++) {
            r->org[k] = (float)(c[k] + 1.5 * m->diag * d[k]);
            target[k] = (float)(m->lo[k] + (m->hi[k] - m->lo[k]) * unit_random(i, 4 + (uint64_t)k));
            r->dir[k] = target[k] - r->org[k];
            len += (double)r->dir[k] * r->dir[k];
        }
        for (k = 0; k < 3; k++) r->dir[k] = (float)(r->dir[k] / sqrt(len));
    } else {
        for (k = 0; k < 3; k++) r->org[k] = (float)(m->lo[k] + (m->hi[k] - m->lo[k]) * unit_random(i, 4 + (uint64_t)k));
        random_direction(i, 8, r->dir);
    }
    r->tmin = 0.0f;
    r->tmax = INFINITY;
}

static int mismatch(int hit_a, double ta, int hit_b, double tb, double diag)
{
    if (hit_a != hit_b) return 1;
    return hit_a && fabs(ta - tb) > 1e-5 * fmax(tb, 1e-3 * diag);
}

/* ---- tests ---------------------------------------------------------------------------------- */

static void test_brute_force(const char *name, const mesh *m, size_t rays)
{
    dm_bvh *bvh = NULL;
    size_t i, differs = 0, bad_double = 0, occl_bad = 0, batch_bad = 0, hits = 0, nan_hits = 0, line_bad = 0;
    dm_ray *all = (dm_ray *)calloc(rays, sizeof(dm_ray));
    dm_hit *batch = (dm_hit *)calloc(rays, sizeof(dm_hit));
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, NULL, &bvh), DM_OK);
    T_CHECK(all != NULL && batch != NULL);
    if (!bvh || !all || !batch) {
        dm_bvh_free(bvh);
        free(all);
        free(batch);
        T_SKIP_N(7, name, "no BVH or no memory (counted above)");
        return;
    }
    for (i = 0; i < rays; i++) {
        dm_hit h, bf, line;
        double td = 0;
        int hit, bhit, dhit;
        random_ray(m, i, &all[i]);
        if (i % 5 == 4) all[i].tmax = (float)(0.5 * m->diag); /* bounded rays too */
        hit = dm_bvh_intersect(bvh, &all[i], &h);
        bhit = brute_same_test(m, &all[i], &bf);
        dhit = brute_double(m, &all[i], &td);
        hits += (size_t)hit;
        if (hit && !(h.t == h.t && h.u == h.u && h.v == h.v)) nan_hits++;
        if (hit != bhit || (hit && (h.t != bf.t || h.triangle != bf.triangle || h.u != bf.u || h.v != bf.v))) {
            if (differs++ < 5)
                printf("  %s ray %zu: bvh %d t=%.9g tri=%u, brute %d t=%.9g tri=%u\n", name, i, hit, h.t, h.triangle,
                       bhit, bf.t, bf.triangle);
        }
        if (mismatch(hit, h.t, dhit, td, m->diag)) {
            if (bad_double++ < 5)
                printf("  %s ray %zu: bvh %d t=%.9g, double MT %d t=%.9g\n", name, i, hit, h.t, dhit, td);
        }
        if (dm_bvh_occluded(bvh, &all[i]) != hit) occl_bad++;
        /* the line query equals the better of a forward and a backward brute force */
        {
            dm_ray fwd = all[i], back = all[i];
            dm_hit hf, hb;
            int k, f, b;
            fwd.tmin = 0.0f;
            back.tmin = 0.0f;
            for (k = 0; k < 3; k++) back.dir[k] = -back.dir[k];
            f = brute_same_test(m, &fwd, &hf);
            b = brute_same_test(m, &back, &hb);
            line = h;
            {
                dm_ray lr = all[i];
                lr.tmin = -lr.tmax;
                int lh = dm_bvh_intersect_line(bvh, &lr, &line);
                int expect = f || b;
                double expect_t = 0;
                if (b && (!f || hb.t < hf.t || (hb.t == hf.t && hb.triangle < hf.triangle))) expect_t = -hb.t;
                else if (f) expect_t = hf.t;
                if (lh != expect || (lh && fabs(line.t - expect_t) > 1e-6 * m->diag)) {
                    if (line_bad++ < 5)
                        printf("  %s line %zu: got %d t=%.9g, expected %d t=%.9g\n", name, i, lh, line.t, expect, expect_t);
                }
            }
        }
    }
    T_EQ_SIZE(dm_bvh_intersect_batch(bvh, all, rays, batch), hits);
    for (i = 0; i < rays; i++) {
        dm_hit h;
        dm_bvh_intersect(bvh, &all[i], &h);
        if (memcmp(&h, &batch[i], sizeof h) != 0) batch_bad++;
    }
    printf("%s: %zu triangles, %zu rays, %zu hits\n", name, m->nt, rays, hits);
    T_CHECK_MSG(hits > rays / 10 && hits < rays, "%zu hits of %zu", hits, rays);
    T_EQ_SIZE(differs, 0);
    T_EQ_SIZE(bad_double, 0);
    T_EQ_SIZE(nan_hits, 0);
    T_EQ_SIZE(occl_bad + batch_bad, 0);
    T_EQ_SIZE(line_bad, 0);
    dm_bvh_free(bvh);
    free(all);
    free(batch);
}

/* rays at every vertex and edge midpoint of a closed mesh, from the point plus offset times the
   angle-weighted pseudonormal, pointing back along minus it */
typedef struct edge_key {
    uint32_t lo, hi, tri;
} edge_key;

static int edge_compare(const void *pa, const void *pb)
{
    const edge_key *a = (const edge_key *)pa, *b = (const edge_key *)pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return a->tri < b->tri ? -1 : (a->tri > b->tri);
}

static void test_watertight(const char *name, const mesh *m)
{
    dm_bvh *bvh = NULL;
    double *vn = (double *)calloc(3 * m->nv, sizeof(double)), *fn = NULL;
    size_t *first = NULL;
    edge_key *edges = NULL;
    size_t t, v, misses = 0, rays = 0, through = 0, early = 0;
    int side;
    const double offset = 1e-3 * m->diag;
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, NULL, &bvh), DM_OK);
    if (!bvh || !vn) {
        free(vn);
        dm_bvh_free(bvh);
        T_SKIP_N(1, name, "no BVH or no memory (counted above)");
        return;
    }
    for (t = 0; t < m->nt; t++) { /* vertex pseudonormals: sum of angle * unit face normal */
        int c, k;
        double p[3][3], n[3], len;
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) p[c][k] = m->pos[3 * (size_t)m->idx[3 * t + c] + k];
        n[0] = (p[1][1] - p[0][1]) * (p[2][2] - p[0][2]) - (p[1][2] - p[0][2]) * (p[2][1] - p[0][1]);
        n[1] = (p[1][2] - p[0][2]) * (p[2][0] - p[0][0]) - (p[1][0] - p[0][0]) * (p[2][2] - p[0][2]);
        n[2] = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (c = 0; c < 3; c++) {
            double e1[3], e2[3], l1 = 0, l2 = 0, dot = 0, angle;
            for (k = 0; k < 3; k++) {
                e1[k] = p[(c + 1) % 3][k] - p[c][k];
                e2[k] = p[(c + 2) % 3][k] - p[c][k];
                l1 += e1[k] * e1[k];
                l2 += e2[k] * e2[k];
                dot += e1[k] * e2[k];
            }
            angle = acos(fmax(-1.0, fmin(1.0, dot / sqrt(l1 * l2))));
            for (k = 0; k < 3; k++) vn[3 * (size_t)m->idx[3 * t + c] + k] += angle * n[k] / len;
        }
    }
    /* unit face normals, the first corner of each vertex, and the edges sorted by (min, max) so
       that the two faces of an edge are neighbours */
    fn = (double *)malloc(3 * m->nt * sizeof(double));
    first = (size_t *)malloc(m->nv * sizeof(size_t));
    edges = (edge_key *)malloc(3 * m->nt * sizeof(edge_key));
    if (!fn || !first || !edges) {
        T_SKIP_N(1, name, "no memory");
        goto done;
    }
    for (t = 0; t < m->nt; t++) {
        double p[3][3], len;
        int c, k;
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) p[c][k] = m->pos[3 * (size_t)m->idx[3 * t + c] + k];
        fn[3 * t] = (p[1][1] - p[0][1]) * (p[2][2] - p[0][2]) - (p[1][2] - p[0][2]) * (p[2][1] - p[0][1]);
        fn[3 * t + 1] = (p[1][2] - p[0][2]) * (p[2][0] - p[0][0]) - (p[1][0] - p[0][0]) * (p[2][2] - p[0][2]);
        fn[3 * t + 2] = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        len = sqrt(fn[3 * t] * fn[3 * t] + fn[3 * t + 1] * fn[3 * t + 1] + fn[3 * t + 2] * fn[3 * t + 2]);
        for (k = 0; k < 3; k++) fn[3 * t + k] /= len;
        for (c = 0; c < 3; c++) {
            uint32_t a = m->idx[3 * t + c], b = m->idx[3 * t + (c + 1) % 3];
            edges[3 * t + c].lo = a < b ? a : b;
            edges[3 * t + c].hi = a < b ? b : a;
            edges[3 * t + c].tri = (uint32_t)t;
        }
    }
    for (v = 0; v < m->nv; v++) first[v] = (size_t)-1;
    for (v = 3 * m->nt; v-- > 0;) first[m->idx[v]] = v;
    qsort(edges, 3 * m->nt, sizeof(edge_key), edge_compare);
    for (v = 0; v < m->nv + 3 * m->nt; v++) {
        double point[3], n[3], len = 0;
        dm_ray r;
        dm_hit h;
        int k, is_edge = v >= m->nv;
        if (!is_edge) {
            if (first[v] == (size_t)-1) continue;
            for (k = 0; k < 3; k++) {
                point[k] = m->pos[3 * v + k];
                n[k] = vn[3 * v + k];
            }
        } else { /* edge pseudonormal: sum of the two faces' unit normals */
            size_t e = v - m->nv;
            if (e + 1 >= 3 * m->nt || edges[e].lo != edges[e + 1].lo || edges[e].hi != edges[e + 1].hi ||
                (e > 0 && edges[e - 1].lo == edges[e].lo && edges[e - 1].hi == edges[e].hi))
                continue; /* each edge once, from the first of its pair */
            for (k = 0; k < 3; k++) {
                point[k] = 0.5 * ((double)m->pos[3 * (size_t)edges[e].lo + k] + m->pos[3 * (size_t)edges[e].hi + k]);
                n[k] = fn[3 * (size_t)edges[e].tri + k] + fn[3 * (size_t)edges[e + 1].tri + k];
            }
        }
        for (k = 0; k < 3; k++) len += n[k] * n[k];
        len = sqrt(len);
        for (side = 1; side >= -1; side -= 2) { /* from outside (front faces), then from inside (back faces) */
            for (k = 0; k < 3; k++) {
                r.org[k] = (float)(point[k] + side * offset * n[k] / len);
                r.dir[k] = (float)(-side * n[k] / len);
            }
            r.tmin = 0.0f;
            r.tmax = INFINITY;
            rays++;
            /* the aimed point lies on the mesh at t = offset: a ray that slips through the crack
               there hits farther (the far side); before it is fine (a saddle's other sheet) */
            if (!dm_bvh_intersect(bvh, &r, &h)) {
                if (misses++ < 5) printf("  %s: %s ray %zu missed\n", name, is_edge ? "edge" : "vertex", rays);
            } else if (h.t > offset + 1e-3 * offset + 1e-5 * m->diag) {
                if (through++ < 5) printf("  %s: %s ray %zu passed its point (t %.6g, offset %.6g)\n", name,
                                          is_edge ? "edge" : "vertex", rays, h.t, offset);
            } else if (h.t < offset - 1e-3 * offset - 1e-5 * m->diag) {
                early++;
            }
        }
    }
    printf("%s: %zu rays at vertices and edge midpoints from both sides, %zu missed, %zu passed their point, %zu hit "
           "the mesh before it\n", name, rays, misses, through, early);
    T_CHECK_MSG(misses == 0 && through == 0 && rays == 2 * (m->nv + 3 * m->nt / 2), "%zu misses, %zu through, of %zu rays",
                misses, through, rays);
done:
    free(vn);
    free(fn);
    free(first);
    free(edges);
    dm_bvh_free(bvh);
}

static void test_closest_point(const char *name, const mesh *m, size_t points)
{
    dm_bvh *bvh = NULL;
    size_t i, bad = 0, bad_point = 0;
    double worst = 0;
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, NULL, &bvh), DM_OK);
    if (!bvh) {
        T_SKIP_N(2, name, "no BVH (counted above)");
        return;
    }
    for (i = 0; i < points; i++) {
        float p[3];
        dm_closest c;
        double expect, err, back = 0;
        int k;
        for (k = 0; k < 3; k++)
            p[k] = (float)(m->lo[k] + (m->hi[k] - m->lo[k]) * (1.4 * unit_random(i, 11 + (uint64_t)k) - 0.2));
        expect = brute_closest(m, p);
        if (!dm_bvh_closest_point(bvh, p, INFINITY, &c)) {
            bad++;
            continue;
        }
        err = fabs((double)c.distance - expect);
        if (err > worst) worst = err;
        if (err > 1e-6 * m->diag) {
            if (bad++ < 5) printf("  %s point %zu: %.9g vs brute force %.9g\n", name, i, c.distance, expect);
        }
        for (k = 0; k < 3; k++) back += ((double)c.point[k] - p[k]) * ((double)c.point[k] - p[k]);
        if (fabs(sqrt(back) - expect) > 1e-6 * m->diag) bad_point++;
    }
    printf("%s: %zu closest points, worst error %.3g of the diagonal\n", name, points, worst / m->diag);
    T_EQ_SIZE(bad, 0);
    T_EQ_SIZE(bad_point, 0);
    dm_bvh_free(bvh);
}

static void test_bad_input(void)
{
    float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3}, bad_idx[6] = {0, 1, 2, 0, 2, 4};
    dm_bvh *bvh = (dm_bvh *)&pos; /* must be overwritten with NULL on failure */
    dm_ray r = {{0.2f, 0.2f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    dm_hit h;
    dm_closest c;
    T_EQ_INT(dm_bvh_build(pos, 4, idx, 0, NULL, &bvh), DM_ERR_NO_TRIANGLES);
    T_CHECK(bvh == NULL);
    T_EQ_INT(dm_bvh_build(NULL, 4, idx, 2, NULL, &bvh), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_bvh_build(pos, 4, NULL, 2, NULL, &bvh), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_bvh_build(pos, 4, idx, 2, NULL, NULL), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_bvh_build(pos, 4, bad_idx, 2, NULL, &bvh), DM_ERR_BAD_INDEX);
    T_EQ_INT(dm_bvh_build(pos, 0, idx, 2, NULL, &bvh), DM_ERR_BAD_INDEX);
    T_EQ_INT(dm_bvh_build(pos, 4, idx, (size_t)-1 / 4, NULL, &bvh), DM_ERR_TOO_LARGE);
    T_EQ_INT(dm_bvh_build(pos, (size_t)-1 / 2, idx, 2, NULL, &bvh), DM_ERR_TOO_LARGE);
    T_EQ_INT(dm_bvh_build(pos, 4, idx, (size_t)0x80000000u, NULL, &bvh), DM_ERR_TOO_LARGE);
    pos[4] = NAN;
    T_EQ_INT(dm_bvh_build(pos, 4, idx, 2, NULL, &bvh), DM_ERR_BAD_POSITION);
    pos[4] = INFINITY;
    T_EQ_INT(dm_bvh_build(pos, 4, idx, 2, NULL, &bvh), DM_ERR_BAD_POSITION);
    pos[4] = 1e30f;
    T_EQ_INT(dm_bvh_build(pos, 4, idx, 2, NULL, &bvh), DM_ERR_BAD_POSITION);
    T_CHECK(bvh == NULL);
    /* NaN in a vertex no triangle uses is fine */
    pos[4] = 0.0f;
    pos[11] = NAN;
    T_EQ_INT(dm_bvh_build(pos, 4, idx, 1, NULL, &bvh), DM_OK);
    T_EQ_INT(dm_bvh_intersect(bvh, &r, &h), 1);
    T_EQ_INT(h.triangle, 0);
    /* bad rays miss; NULL arguments are harmless */
    r.dir[2] = 0.0f;
    T_EQ_INT(dm_bvh_intersect(bvh, &r, &h), 0);
    T_EQ_INT(h.triangle, DM_NO_HIT);
    r.dir[2] = NAN;
    T_EQ_INT(dm_bvh_intersect(bvh, &r, &h) + dm_bvh_occluded(bvh, &r) + dm_bvh_intersect_line(bvh, &r, &h), 0);
    r.dir[2] = -1.0f;
    r.tmin = 2.0f;
    r.tmax = 1.0f;
    T_EQ_INT(dm_bvh_intersect(bvh, &r, &h), 0);
    T_EQ_INT(dm_bvh_intersect(NULL, &r, &h) + dm_bvh_occluded(NULL, &r) + dm_bvh_intersect(bvh, NULL, &h), 0);
    T_EQ_INT(dm_bvh_closest_point(bvh, pos, -1.0f, &c), 0);
    T_EQ_INT(dm_bvh_closest_point(bvh, pos, INFINITY, &c), 1);
    T_NEAR(c.distance, 0.0, 0.0);
    /* refit with bad input leaves the BVH unchanged */
    T_EQ_INT(dm_bvh_refit(bvh, pos, 4, idx, 2), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_bvh_refit(bvh, pos, 4, bad_idx + 3, 1), DM_ERR_BAD_INDEX);
    pos[0] = NAN;
    T_EQ_INT(dm_bvh_refit(bvh, pos, 4, idx, 1), DM_ERR_BAD_POSITION);
    pos[0] = 0.0f;
    r.tmin = 0.0f;
    r.tmax = INFINITY;
    T_EQ_INT(dm_bvh_intersect(bvh, &r, &h), 1);
    dm_bvh_free(bvh);
    dm_bvh_free(NULL);
    T_EQ_STR(dm_result_string(DM_OK), "DM_OK");
    T_EQ_STR(dm_result_string(DM_ERR_OUT_OF_MEMORY), "DM_ERR_OUT_OF_MEMORY");
    T_EQ_STR(dm_result_string((dm_result)99), "DM_ERR_?");
}

static void test_alloc_failure(const mesh *m)
{
    counting cnt;
    dm_allocator a;
    dm_bvh_options o;
    dm_bvh *bvh = NULL;
    long k, calls, wrong = 0, leaks = 0;
    memset(&o, 0, sizeof o);
    a.alloc = counting_alloc;
    a.free = counting_free;
    a.user = &cnt;
    o.allocator = &a;
    memset(&cnt, 0, sizeof cnt);
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &bvh), DM_OK);
    calls = cnt.calls;
    T_CHECK(cnt.live > 0);
    dm_bvh_free(bvh);
    T_EQ_INT(cnt.live, 0);
    for (k = 1; k <= calls; k++) {
        dm_result r;
        memset(&cnt, 0, sizeof cnt);
        cnt.fail_at = k;
        r = dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &bvh);
        if (r != DM_ERR_OUT_OF_MEMORY || bvh != NULL) wrong++;
        if (cnt.live != 0) leaks++;
        if (r == DM_OK) dm_bvh_free(bvh);
    }
    printf("allocation failure injected at each of %ld allocations\n", calls);
    T_CHECK(calls >= 3);
    T_EQ_INT(wrong, 0);
    T_EQ_INT(leaks, 0);
}

typedef struct progress_log {
    int calls, cancel_at;
    float last;
    int decreasing;
} progress_log;

static int progress_cb(void *user, float done)
{
    progress_log *p = (progress_log *)user;
    if (done < p->last) p->decreasing = 1;
    p->last = done;
    p->calls++;
    return p->cancel_at && p->calls >= p->cancel_at;
}

static void test_progress_cancel(const mesh *m)
{
    counting cnt;
    dm_allocator a;
    dm_bvh_options o;
    progress_log log;
    dm_bvh *bvh = NULL;
    int k, wrong = 0;
    memset(&o, 0, sizeof o);
    memset(&cnt, 0, sizeof cnt);
    memset(&log, 0, sizeof log);
    a.alloc = counting_alloc;
    a.free = counting_free;
    a.user = &cnt;
    o.allocator = &a;
    o.progress = progress_cb;
    o.progress_user = &log;
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &bvh), DM_OK);
    T_CHECK_MSG(log.calls >= 3 && log.last == 1.0f && !log.decreasing, "%d calls, last %g", log.calls, log.last);
    dm_bvh_free(bvh);
    for (k = 1; k <= log.calls; k++) {
        progress_log l2;
        memset(&l2, 0, sizeof l2);
        l2.cancel_at = k;
        o.progress_user = &l2;
        if (dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &bvh) != DM_CANCELLED || bvh != NULL) wrong++;
    }
    T_EQ_INT(wrong, 0);
    T_EQ_INT(cnt.live, 0);
}

static void test_determinism_refit(const mesh *m)
{
    dm_bvh *a = NULL, *b = NULL, *high = NULL, *fresh = NULL;
    dm_bvh_options o;
    dm_bvh_info ia, ih;
    float *moved = (float *)malloc(3 * m->nv * sizeof(float));
    size_t i, differ = 0, high_differ = 0, refit_bad = 0;
    memset(&o, 0, sizeof o);
    o.quality = DM_BVH_QUALITY_HIGH;
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, NULL, &a), DM_OK);
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, NULL, &b), DM_OK);
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &high), DM_OK);
    if (!a || !b || !high || !moved) {
        T_SKIP_N(7, "determinism and refit", "build failed (counted above)");
        dm_bvh_free(a);
        dm_bvh_free(b);
        dm_bvh_free(high);
        free(moved);
        return;
    }
    T_CHECK(a->node_slots == b->node_slots && memcmp(a->nodes, b->nodes, a->node_slots * sizeof(dm__node)) == 0 &&
            a->block_count == b->block_count && memcmp(a->blocks, b->blocks, a->block_count * sizeof(dm__tri4)) == 0);
    dm_bvh_get_info(a, &ia);
    dm_bvh_get_info(high, &ih);
    printf("default build: %zu nodes, %zu leaves, depth %zu, SAH %.3f, %zu bytes; high: %zu nodes, SAH %.3f\n",
           ia.node_count, ia.leaf_count, ia.max_depth, ia.sah_cost, ia.memory_bytes, ih.node_count, ih.sah_cost);
    T_CHECK(ia.memory_bytes >= m->nt * 9 * sizeof(float) && ia.leaf_count * 2 == ia.node_count + 1);
    for (i = 0; i < 2000; i++) {
        dm_ray r;
        dm_hit ha, hh;
        random_ray(m, i, &r);
        dm_bvh_intersect(a, &r, &ha);
        dm_bvh_intersect(high, &r, &hh);
        if (memcmp(&ha, &hh, sizeof ha) != 0) high_differ++;
    }
    T_EQ_SIZE(high_differ, 0);
    /* move every vertex (a shear and a bulge), refit, compare with a fresh build */
    for (i = 0; i < m->nv; i++) {
        const float *p = m->pos + 3 * i;
        moved[3 * i] = p[0] + 0.3f * p[1];
        moved[3 * i + 1] = p[1] * (1.0f + 0.2f * p[2] * p[2]);
        moved[3 * i + 2] = p[2] - 0.1f * p[0];
    }
    T_EQ_INT(dm_bvh_refit(a, moved, m->nv, m->idx, m->nt), DM_OK);
    T_EQ_INT(dm_bvh_build(moved, m->nv, m->idx, m->nt, NULL, &fresh), DM_OK);
    for (i = 0; fresh && i < 4000; i++) {
        dm_ray r;
        dm_hit ha, hf;
        dm_closest ca, cf;
        random_ray(m, i, &r);
        dm_bvh_intersect(a, &r, &ha);
        dm_bvh_intersect(fresh, &r, &hf);
        if (memcmp(&ha, &hf, sizeof ha) != 0) refit_bad++;
        dm_bvh_closest_point(a, r.org, INFINITY, &ca);
        dm_bvh_closest_point(fresh, r.org, INFINITY, &cf);
        if (ca.distance != cf.distance) refit_bad++;
        if (dm_bvh_occluded(a, &r) != (ha.triangle != DM_NO_HIT)) differ++;
    }
    T_EQ_SIZE(refit_bad, 0);
    T_EQ_SIZE(differ, 0);
    dm_bvh_free(a);
    dm_bvh_free(b);
    dm_bvh_free(high);
    dm_bvh_free(fresh);
    free(moved);
}

/* all triangles in one spot (identical centroids): the build must still make small leaves */
/* Leaves of 1 to 16 triangles change the tree, never the answers. */
static void test_leaf_sizes(const mesh *m)
{
    static const int sizes[] = {1, 3, 5, 8, 12, 16};
    dm_bvh *ref = NULL;
    size_t s;
    T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, NULL, &ref), DM_OK);
    for (s = 0; ref && s < sizeof sizes / sizeof sizes[0]; s++) {
        dm_bvh_options o;
        dm_bvh *b = NULL;
        size_t i, differ = 0;
        memset(&o, 0, sizeof o);
        o.max_leaf_size = sizes[s];
        T_EQ_INT(dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &b), DM_OK);
        if (!b) continue;
        for (i = 0; i < 3000; i++) {
            dm_ray r;
            dm_hit ha, hb;
            random_ray(m, i, &r);
            dm_bvh_intersect(ref, &r, &ha);
            dm_bvh_intersect(b, &r, &hb);
            differ += memcmp(&ha, &hb, sizeof ha) != 0 || dm_bvh_occluded(ref, &r) != dm_bvh_occluded(b, &r);
        }
        T_CHECK_MSG(differ == 0, "max_leaf_size %d: %zu of 3000 rays answered differently", sizes[s], differ);
        dm_bvh_free(b);
    }
    dm_bvh_free(ref);
}

/* FNV-1a over the bytes of every answer */
static uint64_t digest_bytes(uint64_t h, const void *p, size_t n)
{
    const unsigned char *c = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; i++) h = (h ^ c[i]) * 0x100000001b3ull;
    return h;
}

static uint64_t digest_rays(uint64_t h, const mesh *m, int leaf)
{
    dm_bvh_options o;
    dm_bvh *b = NULL;
    size_t i;
    int k;
    memset(&o, 0, sizeof o);
    o.max_leaf_size = leaf;
    if (dm_bvh_build(m->pos, m->nv, m->idx, m->nt, &o, &b) != DM_OK) return 0;
    for (i = 0; i < 20000 + 4 * m->nv; i++) {
        dm_ray r;
        dm_hit hit, line;
        unsigned char occ;
        if (i < 20000) {
            random_ray(m, i, &r);
            if (i % 5 == 1) { /* axis-aligned: zero direction components */
                for (k = 0; k < 3; k++) r.dir[k] = k == (int)(i / 5 % 3) ? (i % 2 ? 1.0f : -1.0f) : 0.0f;
            }
            if (i % 7 == 3) { /* limited */
                r.tmin = (float)(0.2 * m->diag * unit_random(i, 20));
                r.tmax = r.tmin + (float)(0.5 * m->diag * unit_random(i, 21));
            }
        } else { /* at a vertex, or at the middle of an edge of triangle (i / 4) */
            size_t t = (i - 20000) / 4 % m->nt;
            const float *a = m->pos + 3 * m->idx[3 * t], *c = m->pos + 3 * m->idx[3 * t + (i % 4 == 0 ? 0 : 1)];
            float d[3];
            random_direction(i, 30, d);
            for (k = 0; k < 3; k++) {
                float target = 0.5f * (a[k] + c[k]);
                r.org[k] = target + (float)(0.3 * m->diag) * d[k];
                r.dir[k] = target - r.org[k];
            }
            r.tmin = 0.0f;
            r.tmax = INFINITY;
        }
        dm_bvh_intersect(b, &r, &hit);
        occ = (unsigned char)dm_bvh_occluded(b, &r);
        r.tmin = -r.tmax;
        dm_bvh_intersect_line(b, &r, &line);
        h = digest_bytes(h, &hit, sizeof hit);
        h = digest_bytes(h, &line, sizeof line);
        h = digest_bytes(h, &occ, 1);
    }
    dm_bvh_free(b);
    return h;
}

static int print_digest(const mesh *s7, const mesh *s16, const mesh *soup)
{
    uint64_t h = 0xcbf29ce484222325ull;
    int leaf;
    for (leaf = 4; leaf <= 16; leaf += 4) {
        h = digest_rays(h, s7, leaf);
        h = digest_rays(h, s16, leaf);
        h = digest_rays(h, soup, leaf);
    }
#if defined(DM_USE_AVX2)
    printf("path avx2\n");
#elif defined(DM_USE_SSE2)
    printf("path sse2\n");
#else
    printf("path portable\n");
#endif
    printf("digest %016llx\n", (unsigned long long)h);
    return 0;
}

static void test_coincident(void)
{
    enum { N = 1000 };
    static float pos[9];
    static uint32_t idx[3 * N];
    dm_bvh *bvh = NULL;
    dm_bvh_info info;
    dm_ray r = {{0.2f, 0.2f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
    dm_hit h;
    size_t i;
    pos[3] = 1.0f;
    pos[7] = 1.0f;
    for (i = 0; i < 3 * N; i++) idx[i] = (uint32_t)(i % 3);
    T_EQ_INT(dm_bvh_build(pos, 3, idx, N, NULL, &bvh), DM_OK);
    dm_bvh_get_info(bvh, &info);
    T_CHECK_MSG(info.max_depth < DM__STACK, "depth %zu", info.max_depth);
    T_EQ_INT(dm_bvh_intersect(bvh, &r, &h), 1);
    T_EQ_INT(h.triangle, 0); /* all tie: the lowest index wins */
    T_NEAR(h.t, 1.0, 1e-6);
    dm_bvh_free(bvh);
}

int main(int argc, char **argv)
{
    mesh s3, s7, s16, soup;
    const int sanitize = getenv("TEST_SANITIZE") != NULL;
    T_BEGIN(argc, argv);
    memset(&s3, 0, sizeof s3);
    memset(&s7, 0, sizeof s7);
    memset(&s16, 0, sizeof s16);
    memset(&soup, 0, sizeof soup);
    T_CHECK(sphere_mesh(3, &s3) && sphere_mesh(7, &s7) && sphere_mesh(16, &s16) && soup_mesh(&soup));
    if (!s3.pos || !s7.pos || !s16.pos || !soup.pos) return T_END();
    if (argc > 1 && strcmp(argv[1], "--digest") == 0) {
        int rc = print_digest(&s7, &s16, &soup);
        mesh_free(&s3);
        mesh_free(&s7);
        mesh_free(&s16);
        mesh_free(&soup);
        return rc;
    }
    if (argc > 1 && strcmp(argv[1], "--watertight") == 0) { /* only that (tests/fp_contract.sh) */
        test_watertight("sphere f3", &s3);
        test_watertight("sphere f16", &s16);
        mesh_free(&s3);
        mesh_free(&s7);
        mesh_free(&s16);
        mesh_free(&soup);
        return T_END();
    }
    if (sanitize) printf("note: TEST_SANITIZE is set: 2,000 brute-force rays per mesh instead of 10,000\n");
    test_brute_force("sphere f7", &s7, sanitize ? 2000 : 10000);
    test_brute_force("soup", &soup, sanitize ? 2000 : 10000);
    test_watertight("sphere f3", &s3);
    test_watertight("sphere f16", &s16);
    test_closest_point("sphere f16", &s16, 10000);
    test_closest_point("soup", &soup, 10000);
    test_bad_input();
    test_alloc_failure(&s7);
    test_progress_cancel(&s16);
    test_determinism_refit(&s16);
    test_leaf_sizes(&s16);
    test_leaf_sizes(&soup);
    test_coincident();
    mesh_free(&s3);
    mesh_free(&s7);
    mesh_free(&s16);
    mesh_free(&soup);
    return T_END();
}
