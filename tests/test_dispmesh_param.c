/* test_dispmesh_param.c - dispmesh.h part 3: parameterization, bake, sample grid, reconstruction.
   Generated meshes only: a bumpy sphere (closed, genus 0) over a coarse enclosing sphere, a bumpy
   torus (genus 1) over a coarse torus, an open bumpy sheet with a hole over a flat sheet. */
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#include "test.h"
#include "hashrand.h"
#include "testmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

static const dm_distance_options dist_20000 = {20000, NULL, NULL, NULL};
#include <stdlib.h>
#include <math.h>

/* edges of a triangle mesh: how many have one triangle (boundary), more than two, or two that
   run them the same way (inconsistent orientation) */
typedef struct edge_stats { size_t boundary, over, same_way, edges; } edge_stats;
static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}
static edge_stats edge_count(const uint32_t *idx, size_t nt)
{
    edge_stats r = {0, 0, 0, 0};
    uint64_t *e = (uint64_t *)malloc(3 * nt * sizeof(uint64_t) + 8);
    size_t i, j;
    for (i = 0; i < 3 * nt; i++) {
        uint32_t a = idx[i], b = idx[i - i % 3 + (i % 3 + 1) % 3];
        /* key: min, max, and the direction in the lowest bit of a third field packed in */
        e[i] = ((uint64_t)(a < b ? a : b) << 33) | ((uint64_t)(a < b ? b : a) << 1) | (uint64_t)(a < b);
    }
    qsort(e, 3 * nt, sizeof(uint64_t), cmp_u64);
    for (i = 0; i < 3 * nt; i = j) {
        size_t fwd = 0;
        for (j = i; j < 3 * nt && (e[j] >> 1) == (e[i] >> 1); j++) fwd += e[j] & 1;
        r.edges++;
        if (j - i == 1) r.boundary++;
        else if (j - i > 2) r.over++;
        else if (fwd != 1) r.same_way++;
    }
    free(e);
    return r;
}

static double uv_area(const dm_param *pm, size_t t)
{
    const float *u = pm->uv + 6 * t;
    return 0.5 * (((double)u[2] - u[0]) * ((double)u[5] - u[1]) - ((double)u[4] - u[0]) * ((double)u[3] - u[1]));
}

static double tri_area(const mesh *m, size_t t)
{
    const float *a = m->p + 3 * m->t[3 * t], *b = m->p + 3 * m->t[3 * t + 1], *c = m->p + 3 * m->t[3 * t + 2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(x * x + y * y + z * z);
}

/* The parameterization properties of issue 8: no flipped UV triangle, UVs inside the map, 95% of
   the area ratios (map area / weight, over the mean) in [0.8, 1.25], seam walks come back. */
static void check_param(const char *what, const mesh *base, const dm_param *pm, const float *weight)
{
    size_t t, flipped = 0, outside = 0, ok = 0, n = (size_t)pm->width * pm->height, i, walks = 0, back = 0, across = 0;
    double su = 0.0, sw = 0.0;
    int dir;
    for (t = 0; t < base->nt; t++) {
        int c;
        if (!(uv_area(pm, t) > 0.0)) flipped++;
        for (c = 0; c < 6; c++)
            if (!(pm->uv[6 * t + c] >= 0.0f && pm->uv[6 * t + c] <= 1.0f)) outside++;
        su += uv_area(pm, t);
        sw += weight ? weight[t] : tri_area(base, t);
    }
    for (t = 0; t < base->nt; t++) {
        double r = uv_area(pm, t) / (weight ? weight[t] : tri_area(base, t)) / (su / sw);
        ok += r >= 0.8 && r <= 1.25;
    }
    T_CHECK_MSG(flipped == 0, "%s: %zu flipped UV triangles", what, flipped);
    T_CHECK_MSG(outside == 0, "%s: %zu UVs outside [0,1]", what, outside);
    T_CHECK_MSG(ok >= 0.95 * base->nt, "%s: %zu of %zu area ratios in [0.8,1.25]", what, ok, base->nt);
    T_NEAR(pm->area_ratio_ok, (double)ok / base->nt, 1e-6);
    T_CHECK_MSG(pm->utilization > 0.25f, "%s: utilization %.3f", what, pm->utilization);
    /* seam walks: step across, then step back the opposite way in the neighbour's axes */
    for (i = 0; i < n; i++) {
        if (pm->texel_triangle[i] == DM_NO_HIT) continue;
        for (dir = 0; dir < 4; dir++) {
            static const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
            uint32_t j = pm->nbr[4 * i + dir], k;
            int r, ex, ey, bx, by, bd, xi, yi, xk, yk;
            if (j == UINT32_MAX) continue;
            if (pm->chart[pm->texel_triangle[j]] == pm->chart[pm->texel_triangle[i]] && pm->nbr_rot[4 * i + dir] == 0) {
                /* inside one chart: plain neighbours, both ways */
                int back_dir = dir ^ 1;
                walks++;
                back += pm->nbr[4 * (size_t)j + back_dir] == i;
                continue;
            }
            across++;
            r = pm->nbr_rot[4 * i + dir];
            ex = dx[dir]; ey = dy[dir];
            for (; r > 0; r--) { int tmp = ex; ex = -ey; ey = tmp; }
            bx = -ex; by = -ey;
            bd = bx == 1 ? 0 : bx == -1 ? 1 : by == 1 ? 2 : 3;
            k = pm->nbr[4 * (size_t)j + bd];
            walks++;
            if (k == UINT32_MAX) continue;
            xi = (int)(i % pm->width); yi = (int)(i / pm->width);
            xk = (int)(k % pm->width); yk = (int)(k / pm->width);
            back += abs(xi - xk) <= 1 && abs(yi - yk) <= 1;
        }
    }
    T_CHECK_MSG(across > 0, "%s: no seam crossings", what);
    T_CHECK_MSG(walks == back, "%s: %zu of %zu walks came back (%zu across seams)", what, back, walks, across);
    /* the mirror fallback (the texel itself, half turn) stays rare: chart corners only */
    {
        size_t mirrors = 0;
        for (i = 0; i < n; i++)
            for (dir = 0; dir < 4; dir++) mirrors += pm->nbr[4 * i + dir] == i && pm->nbr_rot[4 * i + dir] == 2;
        T_CHECK_MSG(mirrors <= across / 1000, "%s: %zu mirror links of %zu seam crossings", what, mirrors, across);
        printf("  note: %s: %zu mirror links\n", what, mirrors);
    }
    printf("  note: %s: %zu charts, utilization %.3f, stretch L2 %.3f max %.3f, area ratios ok %.3f, "
           "%zu seam crossings, %zu of them not walking back\n", what, pm->chart_count, pm->utilization,
           pm->stretch_l2, pm->stretch_max, pm->area_ratio_ok, across, walks - back);
}

static int cancel_at;
static int cancel_progress(void *user, float done)
{
    int *calls = (int *)user;
    (void)done;
    return ++*calls >= cancel_at;
}


/* dm_surface_distance: two spheres of radius 1 and 1.02 on the same cube-sphere grid are 0.02
   apart along every ray from the centre; progress, cancel, allocation failure, determinism. */
typedef struct dist_prog { int calls, bad; float last; int cancel_at; } dist_prog;
static int dist_progress(void *user, float done)
{
    dist_prog *d = (dist_prog *)user;
    if (!(done >= d->last && done <= 1.0f)) d->bad++;
    d->last = done;
    return d->cancel_at > 0 && ++d->calls >= d->cancel_at;
}

/* A 500-face base of the bunny (a shell-constrained dm_simplify run) with one grown chart that
   curls: laid out with its boundary on a convex polygon it was squeezed (stretch_l2 4.88, one
   triangle 177, area ratios ok 0.890 at 1024^2). Such a chart must fall apart rather than be
   kept: issue 16's packing bars hold on it. */
static void test_curled_chart(void)
{
    const char *path = "tests/fixtures/curled_chart_base.off";
    mio_mesh m;
    mio_error err;
    dm_param_options po;
    dm_param *pm = NULL;
    if (!T_CHECK_MSG(mio_read_file(path, NULL, &m, &err) == MIO_OK, "%s: could not read it (the tests run from the "
                     "repository's top)", path))
        return;
    memset(&po, 0, sizeof po);
    po.width = po.height = 1024;
    if (T_CHECK(dm_parameterize(m.positions, m.vertex_count, m.indices, m.triangle_count, &po, &pm) == DM_OK)) {
        printf("  note: curled chart base: %zu charts, utilization %.3f, stretch_l2 %.4f (max %.3f), area ok %.3f\n",
               pm->chart_count, pm->utilization, pm->stretch_l2, pm->stretch_max, pm->area_ratio_ok);
        T_CHECK_MSG(pm->stretch_l2 <= 1.05f && pm->stretch_max <= 2.0f, "stretch_l2 %.4f, max %.3f", pm->stretch_l2,
                    pm->stretch_max);
        T_CHECK_MSG(pm->area_ratio_ok >= 0.95f, "area ratios ok %.3f", pm->area_ratio_ok);
        T_CHECK_MSG(pm->utilization >= 0.6f, "utilization %.3f", pm->utilization);
    }
    dm_param_free(pm);
    mio_free_mesh(&m);
}

/* A sliver given a floor weight (as dm_coverage_weights gives a base triangle over little of the
   original): scaled to its target as a whole triangle it would be a needle 28 times the side of
   the sheet beside it, and the map would shrink to fit it. Its target is cut, so the sheet keeps
   its texels. */
static void test_needle(void)
{
    enum { N = 8 };
    float p[3 * ((N + 1) * (N + 1) + 3)], w[2 * N * N + 1];
    uint32_t t[3 * (2 * N * N + 1)];
    size_t nv = 0, nt = 0, i, covered_grid = 0;
    int x, y;
    dm_param_options po;
    dm_param *pm = NULL;
    for (y = 0; y <= N; y++)
        for (x = 0; x <= N; x++) {
            p[3 * nv] = (float)x / N; p[3 * nv + 1] = (float)y / N; p[3 * nv + 2] = 0.0f;
            nv++;
        }
    for (y = 0; y < N; y++)
        for (x = 0; x < N; x++) {
            uint32_t a = (uint32_t)(y * (N + 1) + x), b = a + 1, c = a + N + 1, d = c + 1;
            t[3 * nt] = a; t[3 * nt + 1] = b; t[3 * nt + 2] = d; w[nt++] = 0.5f / (N * N);
            t[3 * nt] = a; t[3 * nt + 1] = d; t[3 * nt + 2] = c; w[nt++] = 0.5f / (N * N);
        }
    p[3 * nv] = 2.0f; p[3 * nv + 1] = 0.0f; p[3 * nv + 2] = 0.0f;
    p[3 * nv + 3] = 3.0f; p[3 * nv + 4] = 0.0f; p[3 * nv + 5] = 0.0f;
    p[3 * nv + 6] = 2.5f; p[3 * nv + 7] = 1e-6f; p[3 * nv + 8] = 0.0f;
    t[3 * nt] = (uint32_t)nv; t[3 * nt + 1] = (uint32_t)nv + 1; t[3 * nt + 2] = (uint32_t)nv + 2;
    w[nt++] = 0.05f / (2 * N * N); /* 5% of the mean, the coverage weights' floor */
    nv += 3;
    memset(&po, 0, sizeof po);
    po.width = po.height = 256;
    po.triangle_weight = w;
    if (T_CHECK(dm_parameterize(p, nv, t, nt, &po, &pm) == DM_OK)) {
        for (i = 0; i < (size_t)po.width * po.height; i++) covered_grid += pm->texel_triangle[i] < 2 * N * N;
        printf("  note: grid beside a needle: utilization %.3f, grid texels %zu\n", pm->utilization, covered_grid);
        T_CHECK_MSG(covered_grid >= (size_t)(0.2 * po.width * po.height), "the grid got %zu of %d texels", covered_grid,
                    po.width * po.height);
    }
    dm_param_free(pm);
}

/* the unit normal of triangle t of (p, idx) */
static void unit_face_normal(const float *p, const uint32_t *idx, size_t t, double n[3])
{
    const float *a = p + 3 * idx[3 * t], *b = p + 3 * idx[3 * t + 1], *c = p + 3 * idx[3 * t + 2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]}, l;
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    n[0] /= l;
    n[1] /= l;
    n[2] /= l;
}

/* the test's own angle-weighted vertex normals (Thurmer and Wuthrich), unit, 3 doubles each */
static void angle_weighted(const float *p, size_t nv, const uint32_t *idx, size_t nt, double *vn)
{
    size_t t, v;
    int c, k;
    memset(vn, 0, 3 * nv * sizeof(double));
    for (t = 0; t < nt; t++) {
        double n[3];
        unit_face_normal(p, idx, t, n);
        for (c = 0; c < 3; c++) {
            const float *a = p + 3 * idx[3 * t + c], *b = p + 3 * idx[3 * t + (c + 1) % 3], *d = p + 3 * idx[3 * t + (c + 2) % 3];
            double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
            double cs = (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) /
                        sqrt((u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]));
            double ang = acos(cs < -1.0 ? -1.0 : cs > 1.0 ? 1.0 : cs);
            for (k = 0; k < 3; k++) vn[3 * idx[3 * t + c] + k] += ang * n[k];
        }
    }
    for (v = 0; v < nv; v++) {
        double l = sqrt(vn[3 * v] * vn[3 * v] + vn[3 * v + 1] * vn[3 * v + 1] + vn[3 * v + 2] * vn[3 * v + 2]);
        for (k = 0; k < 3; k++) vn[3 * v + k] /= l;
    }
}

/* vertex v's smallest dot product with its triangles' normals, for normal n */
static double worst_face(const float *p, const uint32_t *idx, size_t nt, uint32_t v, const double n[3])
{
    double m = 2.0;
    size_t t;
    for (t = 0; t < nt; t++)
        if (idx[3 * t] == v || idx[3 * t + 1] == v || idx[3 * t + 2] == v) {
            double f[3], d;
            unit_face_normal(p, idx, t, f);
            d = f[0] * n[0] + f[1] * n[1] + f[2] * n[2];
            if (d < m) m = d;
        }
    return m;
}

/* dm_base_normals, the directions of the bake and the reconstruction: the angle-weighted normals
   where each vertex sees its triangles within 60 degrees (the bumpy sphere); at a crease between a
   wide flat fan and a thin wall, where the angle-weighted normal lies along the wall, the least
   turn that sees the wall at 60 degrees; where no direction sees all its triangles that well (a
   thin wedge), toward the one that sees them best, by at most 30 degrees; the errors. */
static void test_base_normals(void)
{
    mesh s = make_sphere(16, 0.03, 1.0);
    float pos[3 * 9], *nrm = (float *)malloc(3 * s.nv * sizeof(float));
    uint32_t idx[3 * 8];
    double *vn = (double *)malloc(3 * s.nv * sizeof(double)), n[3], aw[3 * 9];
    size_t v, off = 0, i, nt = 0;
    if (!T_CHECK(nrm && vn)) goto done;
    T_EQ_INT(dm_base_normals(s.p, s.nv, s.t, s.nt, NULL, nrm), DM_OK);
    angle_weighted(s.p, s.nv, s.t, s.nt, vn);
    for (v = 0; v < s.nv; v++) {
        int k;
        for (k = 0; k < 3; k++) off += fabs(nrm[3 * v + k] - vn[3 * v + k]) > 1e-6;
    }
    T_CHECK_MSG(off == 0, "bumpy sphere: %zu normal components differ from the angle-weighted ones", off);
    { /* a crease: O at the origin, a fan of 270 degrees in the plane y = 0 facing -y, and one wall
         triangle of a 3-degree corner facing -x */
        pos[0] = pos[1] = pos[2] = 0.0f;
        for (i = 0; i < 7; i++) {
            double a = 1.5 * 3.14159265358979 * (double)i / 6.0;
            pos[3 * (1 + i)] = (float)cos(a);
            pos[3 * (1 + i) + 1] = 0.0f;
            pos[3 * (1 + i) + 2] = (float)sin(a);
        }
        for (i = 0; i < 6; i++) {
            idx[3 * nt] = 0;
            idx[3 * nt + 1] = (uint32_t)(1 + i);
            idx[3 * nt + 2] = (uint32_t)(2 + i);
            nt++;
        }
        pos[24] = 0.0f; pos[25] = 0.05f; pos[26] = -1.0f; /* the wall: O, (0 0 -1), (0 .05 -1) */
        pos[21] = 0.0f; pos[22] = 0.0f; pos[23] = -1.0f;
        /* vertex 7 was the fan's last point at 270 degrees: (0, 0, -1), the wall's foot */
        idx[3 * nt] = 0;
        idx[3 * nt + 1] = 8;
        idx[3 * nt + 2] = 7;
        nt++;
        {
            float out[3 * 9];
            double wall[3], worst_aw, worst;
            unit_face_normal(pos, idx, 6, wall);
            angle_weighted(pos, 9, idx, nt, aw);
            worst_aw = worst_face(pos, idx, nt, 0, aw);
            T_CHECK_MSG(worst_aw < 0.1, "the crease is not one: the angle-weighted normal sees the wall at %.3f", worst_aw);
            if (T_EQ_INT(dm_base_normals(pos, 9, idx, nt, NULL, out), DM_OK)) {
                for (i = 0; i < 3; i++) n[i] = out[i];
                worst = worst_face(pos, idx, nt, 0, n);
                printf("  note: crease: the angle-weighted normal sees the wall at %.4f, the base normal at %.4f\n",
                       wall[0] * aw[0] + wall[1] * aw[1] + wall[2] * aw[2], wall[0] * n[0] + wall[1] * n[1] + wall[2] * n[2]);
                T_CHECK_MSG(worst >= 0.5 - 1e-5 && worst <= 0.5 + 1e-3, "crease: the base normal sees its worst "
                            "triangle at %.6f (the least turn reaching 0.5)", worst);
                for (v = 1; v < 9; v++) { /* the others see their triangles within 60 degrees: unchanged */
                    double d = 0.0;
                    int k;
                    for (k = 0; k < 3; k++) d += fabs(out[3 * v + k] - aw[3 * v + k]);
                    T_CHECK_MSG(d < 1e-6, "crease: vertex %zu turned by %.3g", v, d);
                }
            }
        }
    }
    { /* a thin wedge: O's two triangles face (0, 0.2, 1) and (0, 0.2, -1) nearly apart, and a third
         (0, -1, 0); no direction sees all three at 60 degrees */
        static const float wp[3 * 5] = {0, 0, 0, 1, 0, 0, -1, 1, 0.2f, -1, 1, -0.2f, -1, -1, 0};
        static const uint32_t wi[3 * 3] = {0, 1, 2, 0, 3, 1, 0, 1, 4};
        float out[3 * 5];
        double waw[3 * 5], worst_aw, worst, turn;
        angle_weighted(wp, 5, wi, 3, waw);
        worst_aw = worst_face(wp, wi, 3, 0, waw);
        if (T_EQ_INT(dm_base_normals(wp, 5, wi, 3, NULL, out), DM_OK)) {
            for (i = 0; i < 3; i++) n[i] = out[i];
            worst = worst_face(wp, wi, 3, 0, n);
            turn = acos(n[0] * waw[0] + n[1] * waw[1] + n[2] * waw[2]) * 180.0 / 3.14159265358979;
            printf("  note: wedge: worst triangle seen at %.4f (angle-weighted %.4f), turned %.2f degrees\n", worst,
                   worst_aw, turn);
            T_CHECK_MSG(worst >= worst_aw - 1e-6 && worst < 0.5, "wedge: worst %.4f, angle-weighted %.4f", worst, worst_aw);
            T_CHECK_MSG(turn <= 30.0 + 1e-3, "wedge: turned by %.3f degrees", turn);
        }
    }
    { /* errors, and nothing held after an allocation fails */
        uint32_t bad[3] = {0, 1, 99};
        float nanp[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        counting c = {0, 0, 0};
        dm_allocator al;
        long k;
        int ok_seen = 0;
        nanp[4] = (float)NAN;
        T_EQ_INT(dm_base_normals(pos, 9, idx, nt, NULL, NULL), DM_ERR_INVALID_ARGUMENT);
        T_EQ_INT(dm_base_normals(pos, 9, bad, 1, NULL, nrm), DM_ERR_BAD_INDEX);
        T_EQ_INT(dm_base_normals(nanp, 3, idx, 1, NULL, nrm), DM_ERR_BAD_POSITION);
        T_EQ_INT(dm_base_normals(pos, 9, idx, 0, NULL, nrm), DM_ERR_NO_TRIANGLES);
        al.alloc = c_alloc;
        al.free = c_free;
        al.user = &c;
        for (k = 0; k < 8 && !ok_seen; k++) { /* the crease needs the work space: fail each allocation */
            float out[3 * 9];
            dm_result r;
            c.calls = 0;
            c.fail_at = k;
            r = dm_base_normals(pos, 9, idx, nt, &al, out);
            T_CHECK_MSG(r == DM_OK || r == DM_ERR_OUT_OF_MEMORY, "allocation %ld failed: result %d", k, (int)r);
            T_CHECK_MSG(c.live == 0, "allocation %ld failed: %ld blocks held", k, c.live);
            ok_seen = r == DM_OK;
        }
        T_CHECK_MSG(ok_seen && k > 1, "dm_base_normals: never done, or done without its work space (%ld)", k);
    }
done:
    free(nrm);
    free(vn);
    mesh_free(&s);
}

static void test_surface_distance(void)
{
    mesh a = make_sphere(24, 0.0, 1.0), b = make_sphere(24, 0.0, 1.02);
    dm_distance_options o;
    dm_distance_report r1, r2;
    dist_prog dp;
    counting cnt;
    dm_allocator al;
    long k;
    int oom_ok = 1, leak = 0;
    dm_result r;
    memset(&o, 0, sizeof o);
    memset(&dp, 0, sizeof dp);
    o.samples_per_side = 50000;
    o.progress = dist_progress;
    o.progress_user = &dp;
    T_EQ_INT(dm_surface_distance(a.p, a.nv, a.t, a.nt, b.p, b.nv, b.t, b.nt, &o, &r1), DM_OK);
    /* the two meshes are the same grid scaled: every point of one is 0.02 r from the other
       along its ray, and the closest point is nearer by the facets' tilt only (< 2%) */
    T_CHECK_MSG(fabs(r1.rms * r1.diagonal - 0.02) < 0.02 * 0.02 && fabs(r1.max * r1.diagonal - 0.02) < 0.02 * 0.03,
                "spheres 1 and 1.02: rms %.5f max %.5f (world units)", r1.rms * r1.diagonal, r1.max * r1.diagonal);
    T_CHECK_MSG(fabs(r1.diagonal - 2.0 * sqrt(3.0)) < 1e-5, "diagonal %.6f", r1.diagonal);
    T_EQ_SIZE(r1.samples, 50000);
    T_CHECK_MSG(dp.bad == 0 && dp.last == 1.0f, "progress: %d out of order, last %g", dp.bad, dp.last);
    dp.calls = 0; dp.last = 0.0f; dp.cancel_at = 3;
    T_EQ_INT(dm_surface_distance(a.p, a.nv, a.t, a.nt, b.p, b.nv, b.t, b.nt, &o, &r2), DM_CANCELLED);
    T_CHECK(r2.rms == 0.0 && r2.max == 0.0 && r2.samples == 0);
    o.progress = NULL;
    T_EQ_INT(dm_surface_distance(a.p, a.nv, a.t, a.nt, b.p, b.nv, b.t, b.nt, &o, &r2), DM_OK);
    T_CHECK_MSG(memcmp(&r1, &r2, sizeof r1) == 0, "not deterministic");
    T_EQ_INT(dm_surface_distance(a.p, a.nv, a.t, a.nt, b.p, b.nv, b.t, b.nt, &o, NULL), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_surface_distance(a.p, a.nv, a.t, 0, b.p, b.nv, b.t, b.nt, &o, &r2), DM_ERR_NO_TRIANGLES);
    al.alloc = c_alloc;
    al.free = c_free;
    al.user = &cnt;
    o.allocator = &al;
    o.samples_per_side = 2000;
    for (k = 0;; k++) {
        cnt.calls = 0; cnt.fail_at = k; cnt.live = 0;
        r = dm_surface_distance(a.p, a.nv, a.t, a.nt, b.p, b.nv, b.t, b.nt, &o, &r2);
        leak |= cnt.live != 0;
        if (r == DM_OK) break;
        oom_ok &= r == DM_ERR_OUT_OF_MEMORY;
    }
    T_CHECK_MSG(oom_ok && !leak && k >= 3, "surface distance: %ld failure points, oom_ok %d leak %d", k, oom_ok, leak);
    T_EQ_INT(dm_surface_distance(a.p, a.nv, a.t, a.nt, b.p, b.nv, b.t, b.nt, NULL, &r2), DM_OK);
    T_EQ_SIZE(r2.samples, 200000);
    mesh_free(&a);
    mesh_free(&b);
}

/* dm_coverage_weights: the original's area over each base triangle */
static void test_coverage_weights(void)
{
    mesh base = make_sphere(6, 0.0, 1.06), orig = make_sphere(48, 0.03, 1.0);
    mesh sheet = make_sheet(4, 0.0, 0.0, 0.0), holed = make_sheet(40, 0.0, 0.05, 0.5);
    float *w = (float *)malloc(base.nt * sizeof(float)), *ws = (float *)malloc(sheet.nt * sizeof(float));
    double total = 0.0, sum = 0.0, worst = 0.0, mean, wmin = 1e30;
    size_t t, low = 0;
    dm_param_options po;
    dm_param *pm = NULL;
    if (!w || !ws) {
        T_SKIP_N(13, "coverage weights", "out of memory");
        free(w);
        free(ws);
        return;
    }
    /* every original triangle lands somewhere: the weights add up to the original's area */
    T_EQ_INT(dm_coverage_weights(base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, NULL, w), DM_OK);
    for (t = 0; t < orig.nt; t++) total += tri_area(&orig, t);
    for (t = 0; t < base.nt; t++) sum += w[t];
    T_CHECK_MSG(fabs(sum - total) <= 1e-4 * total, "weights add to %.6f, the original's area is %.6f", sum, total);
    { /* the explicit defaults give the zero ones' bits */
        dm_coverage_options co = dm_coverage_default_options();
        float *w2 = (float *)malloc(base.nt * sizeof(float));
        T_CHECK(co.floor == 0.05f && co.allocator == NULL && co.progress == NULL);
        if (w2) {
            T_EQ_INT(dm_coverage_weights(base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, &co, w2), DM_OK);
            T_CHECK(memcmp(w, w2, base.nt * sizeof(float)) == 0);
            free(w2);
        }
        T_CHECK(dm_distance_default_options().samples_per_side == 200000);
    }
    /* the map made with them meets the area targets */
    memset(&po, 0, sizeof po);
    po.width = po.height = 256;
    po.triangle_weight = w;
    T_EQ_INT(dm_parameterize(base.p, base.nv, base.t, base.nt, &po, &pm), DM_OK);
    if (pm) check_param("sphere, coverage weights", &base, pm, w);
    dm_param_free(pm);
    /* a mesh over itself: each triangle's own area */
    T_EQ_INT(dm_coverage_weights(base.p, base.nv, base.t, base.nt, base.p, base.nv, base.t, base.nt, NULL, w), DM_OK);
    for (t = 0; t < base.nt; t++) {
        double a = tri_area(&base, t), e = fabs(w[t] - a) / a;
        if (e > worst) worst = e;
    }
    T_CHECK_MSG(worst <= 1e-5, "a mesh over itself: weight differs from the area by %.3g (relative)", worst);
    /* a sheet with a hole over a flat sheet: the triangles under the hole get the floor */
    T_EQ_INT(dm_coverage_weights(sheet.p, sheet.nv, sheet.t, sheet.nt, holed.p, holed.nv, holed.t, holed.nt, NULL, ws), DM_OK);
    sum = 0.0;
    for (t = 0; t < sheet.nt; t++) {
        sum += ws[t];
        if (ws[t] < wmin) wmin = ws[t];
    }
    mean = sum / (double)sheet.nt;
    for (t = 0; t < sheet.nt; t++) low += ws[t] < 0.5 * mean;
    T_CHECK_MSG(wmin >= 0.049 * mean && low > 0, "floor: smallest weight %.4g of mean %.4g, %zu below half the mean",
                wmin, mean, low);
    { /* the floor is an option (a fraction of the mean of the unfloored weights: 0.3 is 6 times
         the default 0.05), progress ends at 1, a nonzero return cancels */
        dm_coverage_options co;
        dist_prog dp;
        double wmin2 = 1e30;
        memset(&co, 0, sizeof co);
        memset(&dp, 0, sizeof dp);
        co.floor = 0.3f;
        co.progress = dist_progress;
        co.progress_user = &dp;
        T_EQ_INT(dm_coverage_weights(sheet.p, sheet.nv, sheet.t, sheet.nt, holed.p, holed.nv, holed.t, holed.nt, &co, ws),
                 DM_OK);
        for (t = 0; t < sheet.nt; t++)
            if (ws[t] < wmin2) wmin2 = ws[t];
        T_CHECK_MSG(fabs(wmin2 / wmin - 6.0) < 1e-4, "floor 0.3: smallest weight %.5g, with the default %.5g", wmin2, wmin);
        T_CHECK_MSG(dp.bad == 0 && dp.last == 1.0f, "progress: %d out of order, last %g", dp.bad, dp.last);
        dp.cancel_at = 1;
        T_EQ_INT(dm_coverage_weights(sheet.p, sheet.nv, sheet.t, sheet.nt, holed.p, holed.nv, holed.t, holed.nt, &co, ws),
                 DM_CANCELLED);
        co.progress = NULL;
        co.floor = 2.0f;
        T_EQ_INT(dm_coverage_weights(sheet.p, sheet.nv, sheet.t, sheet.nt, holed.p, holed.nv, holed.t, holed.nt, &co, ws),
                 DM_ERR_INVALID_ARGUMENT);
        co.floor = NAN;
        T_EQ_INT(dm_coverage_weights(sheet.p, sheet.nv, sheet.t, sheet.nt, holed.p, holed.nv, holed.t, holed.nt, &co, ws),
                 DM_ERR_INVALID_ARGUMENT);
    }
    /* bad input */
    T_EQ_INT(dm_coverage_weights(base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, NULL, NULL), DM_ERR_INVALID_ARGUMENT);
    orig.t[5] = (uint32_t)orig.nv;
    T_EQ_INT(dm_coverage_weights(base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, NULL, w), DM_ERR_BAD_INDEX);
    free(w);
    free(ws);
    mesh_free(&base);
    mesh_free(&orig);
    mesh_free(&sheet);
    mesh_free(&holed);
}

int main(int argc, char **argv)
{
    int san = getenv("TEST_SANITIZE") != NULL;
    mesh orig = make_sphere(san ? 32 : 64, 0.03, 1.0), base = make_sphere(6, 0.0, 1.06);
    dm_param_options po;
    dm_param *pm = NULL, *pm2 = NULL;
    dm_dispmap *map = NULL, *map2 = NULL;
    dm_trimesh *rec = NULL;
    dm_result r;
    int res = san ? 256 : 512;
    T_BEGIN(argc, argv);

    /* ---- sphere: parameterization */
    memset(&po, 0, sizeof po);
    po.width = po.height = res;
    r = dm_parameterize(base.p, base.nv, base.t, base.nt, &po, &pm);
    T_EQ_INT(r, DM_OK);
    if (r == DM_OK) check_param("sphere", &base, pm, NULL);

    /* ---- sphere: bake, grid, reconstruction */
    if (pm) {
        dm_distance_report rep, base_rep;
        size_t i, n = (size_t)res * res, bad = 0, covered = 0;
        double area = 0.0, base_area = 0.0;
        r = dm_bake(pm, base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, NULL, &map);
        T_EQ_INT(r, DM_OK);
        if (map) {
            T_EQ_SIZE(map->miss_count, 0);
            for (i = 0; i < n; i++) {
                covered += pm->texel_triangle[i] != DM_NO_HIT;
                area += map->area[i];
                if (map->valid[i]) {
                    double q[3], l, d[3];
                    int k;
                    for (k = 0; k < 3; k++) q[k] = map->pos[3 * i + k] - map->disp[i] * map->nrm[3 * i + k];
                    l = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
                    for (k = 0; k < 3; k++) d[k] = q[k] / l;
                    /* the hit lies on the bumpy sphere (up to its tessellation), the depth is inward */
                    if (fabs(l - bump_sphere(d, 0.03)) > 2e-3 || !(map->disp[i] > 0.0f)) bad++;
                }
            }
            T_EQ_SIZE(map->hit_count, covered);
            T_CHECK_MSG(bad == 0, "%zu texels off the original or not inward", bad);
            for (i = 0; i < base.nt; i++) base_area += tri_area(&base, i);
            T_CHECK_MSG(fabs(area / base_area - 1.0) < 0.02, "texel areas sum to %.4f of the base area", area / base_area);
            /* bit-identical rerun */
            r = dm_bake(pm, base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, NULL, &map2);
            T_EQ_INT(r, DM_OK);
            if (map2) {
                T_CHECK(memcmp(map->disp, map2->disp, n * sizeof(float)) == 0);
                T_CHECK(memcmp(map->normal, map2->normal, 3 * n * sizeof(float)) == 0);
                T_CHECK(memcmp(map->pos, map2->pos, 3 * n * sizeof(float)) == 0);
                dm_dispmap_free(map2);
                map2 = NULL;
            }
            r = dm_parameterize(base.p, base.nv, base.t, base.nt, &po, &pm2);
            T_EQ_INT(r, DM_OK);
            if (pm2) {
                T_CHECK(memcmp(pm->uv, pm2->uv, 6 * base.nt * sizeof(float)) == 0);
                T_CHECK(memcmp(pm->nbr, pm2->nbr, 4 * n * sizeof(uint32_t)) == 0);
                dm_param_free(pm2);
                pm2 = NULL;
            }
            r = dm_reconstruct(map, pm, base.p, base.nv, base.t, base.nt, NULL, &rec);
            T_EQ_INT(r, DM_OK);
            if (rec) {
                size_t i, wrong = 0, bad_normal = 0, bad_face = 0, *per_base = (size_t *)calloc(base.nt, sizeof(size_t));
                /* vertex v < base.nv is base vertex v moved by at most the search distance */
                T_CHECK(rec->vertex_count > base.nv);
                for (i = 0; i < base.nv && i < rec->vertex_count; i++) {
                    double d2 = 0.0;
                    int c;
                    for (c = 0; c < 3; c++) {
                        double e = (double)rec->positions[3 * i + (size_t)c] - base.p[3 * i + (size_t)c];
                        d2 += e * e;
                    }
                    wrong += !(sqrt(d2) <= map->max_distance);
                }
                for (i = 0; i < rec->vertex_count; i++) {
                    double l = sqrt((double)rec->normals[3 * i] * rec->normals[3 * i] + (double)rec->normals[3 * i + 1] * rec->normals[3 * i + 1] +
                                    (double)rec->normals[3 * i + 2] * rec->normals[3 * i + 2]);
                    bad_normal += !(fabs(l - 1.0) < 1e-5);
                }
                for (i = 0; i < rec->triangle_count; i++) {
                    if (rec->face_base[i] >= base.nt) { bad_face++; continue; }
                    per_base[rec->face_base[i]]++;
                }
                for (i = 0; i < base.nt; i++) bad_face += per_base[i] == 0;
                free(per_base);
                T_CHECK_MSG(wrong == 0, "%zu base vertices moved beyond the search distance", wrong);
                T_CHECK_MSG(bad_normal == 0, "%zu reconstruction normals not unit", bad_normal);
                T_CHECK_MSG(bad_face == 0, "%zu face_base entries out of range or base triangles without a face", bad_face);
                r = dm_surface_distance(orig.p, orig.nv, orig.t, orig.nt, rec->positions, rec->vertex_count,
                                        rec->indices, rec->triangle_count, &dist_20000, &rep);
                T_EQ_INT(r, DM_OK);
                r = dm_surface_distance(orig.p, orig.nv, orig.t, orig.nt, base.p, base.nv, base.t, base.nt, &dist_20000, &base_rep);
                T_EQ_INT(r, DM_OK);
                T_CHECK_MSG(rep.rms <= 0.1 * base_rep.rms, "recon rms %.3g vs base-only %.3g", rep.rms, base_rep.rms);
                T_CHECK_MSG(rep.max <= 0.25 * base_rep.max, "recon max %.3g vs base-only %.3g", rep.max, base_rep.max);
                printf("  note: sphere %dx%d: recon %zu tris rms %.2e max %.2e; base only rms %.2e max %.2e\n", res, res,
                       rec->triangle_count, rep.rms, rep.max, base_rep.rms, base_rep.max);
                {
                    edge_stats es = edge_count(rec->indices, rec->triangle_count);
                    T_CHECK_MSG(es.boundary == 0 && es.over == 0 && es.same_way == 0, "recon: %zu edges on a boundary, %zu "
                                "with more than two triangles, %zu run the same way by both", es.boundary, es.over, es.same_way);
                    printf("  note: sphere recon: %zu edges, %zu on a boundary (cracks), %zu with more than two "
                           "triangles, %zu run the same way by both\n", es.edges, es.boundary, es.over, es.same_way);
                }
                { /* the flips along the map's depth: the same points, the same count, closer to the original */
                    dm_reconstruct_options ro = dm_reconstruct_default_options();
                    dm_trimesh *plain = NULL;
                    dm_distance_report prep;
                    ro.depth_flips = -1;
                    if (T_EQ_INT(dm_reconstruct(map, pm, base.p, base.nv, base.t, base.nt, &ro, &plain), DM_OK)) {
                        T_EQ_SIZE(plain->triangle_count, rec->triangle_count);
                        T_CHECK(plain->vertex_count == rec->vertex_count &&
                                memcmp(plain->positions, rec->positions, 3 * rec->vertex_count * sizeof(float)) == 0);
                        T_CHECK(memcmp(plain->indices, rec->indices, 3 * rec->triangle_count * sizeof(uint32_t)) != 0);
                        T_EQ_INT(dm_surface_distance(orig.p, orig.nv, orig.t, orig.nt, plain->positions, plain->vertex_count,
                                                     plain->indices, plain->triangle_count, &dist_20000, &prep), DM_OK);
                        printf("  note: sphere recon rms %.4e with the depth flips, %.4e without\n", rep.rms, prep.rms);
                        T_CHECK_MSG(rep.rms < 0.985 * prep.rms, "depth flips: rms %.4e, without %.4e", rep.rms, prep.rms);
                    }
                    dm_trimesh_free(plain);
                }
                dm_trimesh_free(rec);
                rec = NULL;
            }
        }
    }

    /* ---- sphere with caller weights: map area follows them */
    {
        float *w = (float *)malloc(base.nt * sizeof(float));
        size_t t;
        dm_param *pw = NULL;
        for (t = 0; t < base.nt; t++) w[t] = (float)(tri_area(&base, t) * (1.0 + 0.6 * unit_random(t / 2, 3)));
        r = dm_parameterize(base.p, base.nv, base.t, base.nt, &po, &pw);
        T_EQ_INT(r, DM_OK);
        dm_param_free(pw);
        pw = NULL;
        po.triangle_weight = w;
        r = dm_parameterize(base.p, base.nv, base.t, base.nt, &po, &pw);
        T_EQ_INT(r, DM_OK);
        if (pw) check_param("sphere, weighted", &base, pw, w);
        po.triangle_weight = NULL;
        dm_param_free(pw);
        free(w);
    }

    /* ---- torus (genus 1) */
    {
        mesh tb = make_torus(24, 10, 0.36, 0.0), to = make_torus(san ? 120 : 240, san ? 48 : 96, 0.3, 0.08);
        dm_param *pt = NULL;
        dm_dispmap *mt = NULL;
        r = dm_parameterize(tb.p, tb.nv, tb.t, tb.nt, &po, &pt);
        T_EQ_INT(r, DM_OK);
        if (pt) {
            check_param("torus", &tb, pt, NULL);
            r = dm_bake(pt, tb.p, tb.nv, tb.t, tb.nt, to.p, to.nv, to.t, to.nt, NULL, &mt);
            T_EQ_INT(r, DM_OK);
            if (mt) {
                dm_distance_report rep, base_rep;
                T_EQ_SIZE(mt->miss_count, 0);
                r = dm_reconstruct(mt, pt, tb.p, tb.nv, tb.t, tb.nt, NULL, &rec);
                T_EQ_INT(r, DM_OK);
                if (rec) {
                    dm_surface_distance(to.p, to.nv, to.t, to.nt, rec->positions, rec->vertex_count, rec->indices,
                                        rec->triangle_count, &dist_20000, &rep);
                    dm_surface_distance(to.p, to.nv, to.t, to.nt, tb.p, tb.nv, tb.t, tb.nt, &dist_20000, &base_rep);
                    T_CHECK_MSG(rep.rms <= 0.1 * base_rep.rms, "torus recon rms %.3g vs base-only %.3g", rep.rms, base_rep.rms);
                    printf("  note: torus: recon rms %.2e max %.2e; base only rms %.2e max %.2e\n", rep.rms, rep.max,
                           base_rep.rms, base_rep.max);
                    dm_trimesh_free(rec);
                    rec = NULL;
                }
                dm_dispmap_free(mt);
            }
            dm_param_free(pt);
        }
        mesh_free(&tb);
        mesh_free(&to);
    }

    /* ---- open original with a hole: texels over the hole miss, are flagged and filled */
    {
        mesh sb = make_sheet(4, 0.2, 0.0, 0.0), so = make_sheet(80, 0.0, 0.05, 0.3);
        dm_param *ps = NULL;
        dm_dispmap *ms = NULL;
        dm_param_options sp = po;
        dm_bake_options bo;
        memset(&bo, 0, sizeof bo);
        bo.max_distance = 0.5f;
        sp.width = sp.height = 128;
        r = dm_parameterize(sb.p, sb.nv, sb.t, sb.nt, &sp, &ps);
        T_EQ_INT(r, DM_OK);
        if (ps) {
            T_EQ_SIZE(ps->chart_count, 1);
            r = dm_bake(ps, sb.p, sb.nv, sb.t, sb.nt, so.p, so.nv, so.t, so.nt, &bo, &ms);
            T_EQ_INT(r, DM_OK);
            if (ms) {
                size_t i, wrong = 0, finite = 0, misses = 0;
                for (i = 0; i < (size_t)128 * 128; i++) {
                    double x = ms->pos[3 * i], y = ms->pos[3 * i + 1], rr = sqrt(x * x + y * y);
                    if (ms->status[i] == DM_TEXEL_EMPTY || ms->status[i] == DM_TEXEL_BORDER) continue;
                    if (ms->status[i] == DM_TEXEL_MISS) { misses++; if (rr > 0.35) wrong++; }
                    else if (rr < 0.25) wrong++;
                    finite += isfinite(ms->disp[i]) && isfinite(ms->normal[3 * i]);
                }
                T_CHECK(misses > 0);
                T_EQ_SIZE(misses, ms->miss_count);
                T_CHECK_MSG(wrong == 0, "%zu texels flagged where the original is, or hit over the hole", wrong);
                T_EQ_SIZE(finite, ms->hit_count + ms->miss_count);
                r = dm_reconstruct(ms, ps, sb.p, sb.nv, sb.t, sb.nt, NULL, &rec);
                T_EQ_INT(r, DM_OK);
                if (rec) { /* open, but only along the sheet's own boundary: 4 x 4 base edges of 32 texels or less */
                    edge_stats es = edge_count(rec->indices, rec->triangle_count);
                    T_CHECK_MSG(es.boundary >= 16 && es.boundary <= 16 * 33, "sheet recon: %zu boundary edges", es.boundary);
                    T_CHECK(es.over == 0 && es.same_way == 0);
                    dm_trimesh_free(rec);
                    rec = NULL;
                }
                dm_dispmap_free(ms);
            }
            dm_param_free(ps);
        }
        mesh_free(&sb);
        mesh_free(&so);
    }

    /* ---- cancel, bad input, allocation failure */
    {
        int calls = 0;
        dm_param *px = NULL;
        dm_dispmap *mx = NULL;
        dm_bake_options bo;
        uint32_t badidx[3] = {0, 1, 999};
        float nanp[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        dm_param_options tiny = po;
        counting cnt;
        dm_allocator al;
        long k;
        int oom_ok = 1, leak = 0;
        cancel_at = 2;
        po.progress = cancel_progress;
        po.progress_user = &calls;
        T_EQ_INT(dm_parameterize(base.p, base.nv, base.t, base.nt, &po, &px), DM_CANCELLED);
        T_CHECK(px == NULL);
        po.progress = NULL;
        memset(&bo, 0, sizeof bo);
        bo.progress = cancel_progress;
        bo.progress_user = &calls;
        calls = 0;
        if (pm) {
            T_EQ_INT(dm_bake(pm, base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, &bo, &mx), DM_CANCELLED);
            T_CHECK(mx == NULL);
        }
        T_EQ_INT(dm_parameterize(NULL, 3, base.t, 1, NULL, &px), DM_ERR_INVALID_ARGUMENT);
        T_EQ_INT(dm_parameterize(base.p, base.nv, base.t, 0, NULL, &px), DM_ERR_NO_TRIANGLES);
        T_EQ_INT(dm_parameterize(nanp, 3, badidx, 1, NULL, &px), DM_ERR_BAD_INDEX);
        nanp[4] = NAN;
        badidx[2] = 2;
        T_EQ_INT(dm_parameterize(nanp, 3, badidx, 1, NULL, &px), DM_ERR_BAD_POSITION);
        tiny.width = tiny.height = 4;
        T_EQ_INT(dm_parameterize(base.p, base.nv, base.t, base.nt, &tiny, &px), DM_ERR_MAP_TOO_SMALL);
        T_CHECK(px == NULL);
        T_EQ_STR(dm_result_string(DM_ERR_MAP_TOO_SMALL), "DM_ERR_MAP_TOO_SMALL");
        if (pm) T_EQ_INT(dm_bake(pm, base.p, base.nv, base.t, base.nt - 1, orig.p, orig.nv, orig.t, orig.nt, NULL, &mx),
                         DM_ERR_INVALID_ARGUMENT);
        /* every allocation failing in turn: an error, nothing leaked */
        al.alloc = c_alloc;
        al.free = c_free;
        al.user = &cnt;
        tiny.width = tiny.height = 64;
        tiny.allocator = &al;
        for (k = 0;; k++) {
            cnt.calls = 0; cnt.fail_at = k; cnt.live = 0;
            r = dm_parameterize(base.p, base.nv, base.t, base.nt, &tiny, &px);
            if (r == DM_OK) { dm_param_free(px); px = NULL; leak |= cnt.live != 0; break; }
            oom_ok &= r == DM_ERR_OUT_OF_MEMORY && px == NULL;
            leak |= cnt.live != 0;
        }
        T_CHECK_MSG(oom_ok && !leak && k > 5, "parameterize: %ld failure points, oom_ok %d leak %d", k, oom_ok, leak);
        tiny.allocator = NULL;
        r = dm_parameterize(base.p, base.nv, base.t, base.nt, &tiny, &px);
        T_EQ_INT(r, DM_OK);
        if (px) {
            bo.progress = NULL;
            bo.allocator = &al;
            oom_ok = 1;
            leak = 0;
            for (k = 0;; k++) {
                cnt.calls = 0; cnt.fail_at = k; cnt.live = 0;
                r = dm_bake(px, base.p, base.nv, base.t, base.nt, orig.p, orig.nv, orig.t, orig.nt, &bo, &mx);
                if (r == DM_OK) { dm_dispmap_free(mx); mx = NULL; leak |= cnt.live != 0; break; }
                oom_ok &= r == DM_ERR_OUT_OF_MEMORY && mx == NULL;
                leak |= cnt.live != 0;
            }
            T_CHECK_MSG(oom_ok && !leak && k > 5, "bake: %ld failure points, oom_ok %d leak %d", k, oom_ok, leak);
            dm_param_free(px);
        }
    }

    dm_dispmap_free(map);
    dm_param_free(pm);
    mesh_free(&orig);
    mesh_free(&base);
    test_coverage_weights();
    test_surface_distance();
    test_base_normals();
    test_curled_chart();
    test_needle();
    return T_END();
}
