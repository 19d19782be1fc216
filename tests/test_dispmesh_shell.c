/* test_dispmesh_shell.c - dispmesh.h part 3: the bounding shell and paper 000's simplification
   constraints (dm_shell_grow, dm_shell_constraint). Generated meshes (a bumpy sphere, a fat
   torus with a narrow hole, a box with grooves) and, when glmark2-data is installed, the bunny at 500 faces.
   Checked by brute force, independently of the constraint's own bookkeeping:
   - the shell: offsets within [0, thickness], shell point = vertex + offset * unit normal, no
     shell point closer to the original than 85% of its offset (of the distance its adjacent faces
     allow, where the surface is concave: the offset surface does not run into the original),
     vertices stopped where the torus's hole closes;
   - the constrained base: every original vertex on the inner side of the base (signed distance
     with the angle-weighted pseudonormal at its closest base feature <= 1e-4 of the diagonal;
     vertices whose closest feature is on a boundary are excluded and counted), every sampled
     base point inside the shell, the bake rays' first hits front-facing, no bake ray (153 per
     triangle) going out and in again (the bunny: at most 1 in 10000); the face count reached;
   - a fan of K long thin triangles around a cone's apex (K = 20k, 40k, 80k): the growth's
     proximity steps (DM_COUNT_OPS: nodes and triangles visited) at 80k are at most 6 times those
     at 20k, and at 20k every vertex's offsets agree with a brute-force distance to all triangles;
   - the enclosure's exact projection against brute force (every independent set of at most three
     planes), consistent and inconsistent plane sets, nearly parallel ones;
   - bad input, allocation failure at every point, cancel, determinism. */
static unsigned long long g_ops; /* proximity and queue steps (DM_COUNT_OPS) */
#define DM_COUNT_OPS(n) (g_ops += (unsigned long long)(n))
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#include "test.h"
#include "testmesh.h"

static const dm_distance_options dist_100000 = {100000, NULL, NULL, NULL};
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void load(const float *p, uint32_t v, double o[3]) { o[0] = p[3 * v]; o[1] = p[3 * v + 1]; o[2] = p[3 * v + 2]; }
static void unit_normal(const float *p, const uint32_t *t, double n[3])
{
    double a[3], b[3], c[3], e1[3], e2[3], l;
    int k;
    load(p, t[0], a); load(p, t[1], b); load(p, t[2], c);
    for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    l = sqrt(dot3(n, n));
    if (l > 0) { n[0] /= l; n[1] /= l; n[2] /= l; }
}

/* closest point on triangle (Ericson 5.1.5, written again here so the test does not lean on the
   header's): returns d^2, barycentrics of b and c */
static double tri_closest(const double p[3], const double a[3], const double b[3], const double c[3], double *u, double *v)
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], d1, d2, d3, d4, d5, d6, va, vb, vc, q[3], r = 0;
    int k;
    for (k = 0; k < 3; k++) { ab[k] = b[k] - a[k]; ac[k] = c[k] - a[k]; ap[k] = p[k] - a[k]; bp[k] = p[k] - b[k]; cp[k] = p[k] - c[k]; }
    d1 = dot3(ab, ap); d2 = dot3(ac, ap); d3 = dot3(ab, bp); d4 = dot3(ac, bp); d5 = dot3(ab, cp); d6 = dot3(ac, cp);
    vc = d1 * d4 - d3 * d2; vb = d5 * d2 - d1 * d6; va = d3 * d6 - d5 * d4;
    if (d1 <= 0 && d2 <= 0) { *u = 0; *v = 0; }
    else if (d3 >= 0 && d4 <= d3) { *u = 1; *v = 0; }
    else if (vc <= 0 && d1 >= 0 && d3 <= 0) { *u = d1 / (d1 - d3); *v = 0; }
    else if (d6 >= 0 && d5 <= d6) { *u = 0; *v = 1; }
    else if (vb <= 0 && d2 >= 0 && d6 <= 0) { *u = 0; *v = d2 / (d2 - d6); }
    else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) { *v = (d4 - d3) / ((d4 - d3) + (d5 - d6)); *u = 1 - *v; }
    else { double s = va + vb + vc; *u = vb / s; *v = vc / s; }
    for (k = 0; k < 3; k++) { q[k] = a[k] + *u * ab[k] + *v * ac[k]; r += (p[k] - q[k]) * (p[k] - q[k]); }
    return r;
}

/* Inner-side check of every original vertex against the base, by brute force over the base. */
typedef struct side_report { size_t outside, boundary, checked; double worst; } side_report;
static side_report inner_side(const mesh *orig, const float *bp, const uint32_t *bi, size_t bnt, double diag)
{
    side_report r = {0, 0, 0, -1e300};
    size_t v, t, s;
    unsigned char *bvert;
    uint32_t maxv = 0;
    for (t = 0; t < 3 * bnt; t++) if (bi[t] > maxv) maxv = bi[t];
    bvert = (unsigned char *)calloc((size_t)maxv + 1, 1);
    for (t = 0; t < bnt; t++) /* boundary vertices: an edge of theirs with one triangle */
        for (s = 0; s < 3; s++) {
            uint32_t a = bi[3 * t + s], b = bi[3 * t + (s + 1) % 3];
            size_t u, cnt = 0;
            for (u = 0; u < bnt; u++) {
                int ha = 0, hb = 0, k;
                for (k = 0; k < 3; k++) { ha |= bi[3 * u + k] == a; hb |= bi[3 * u + k] == b; }
                cnt += ha && hb;
            }
            if (cnt == 1) bvert[a] = bvert[b] = 1;
        }
    for (v = 0; v < orig->nv; v++) {
        double p[3], best = 1e300, bu = 0, bv = 0, w[3], q[3] = {0, 0, 0}, N[3] = {0, 0, 0}, d[3], sd;
        size_t bt = 0;
        uint32_t fv[3];
        int nf = 0, j, k, faces = 0;
        load(orig->p, (uint32_t)v, p);
        for (t = 0; t < bnt; t++) {
            double a[3], b[3], c[3], u, vv, d2;
            load(bp, bi[3 * t], a); load(bp, bi[3 * t + 1], b); load(bp, bi[3 * t + 2], c);
            d2 = tri_closest(p, a, b, c, &u, &vv);
            if (d2 < best) { best = d2; bt = t; bu = u; bv = vv; }
        }
        w[0] = 1 - bu - bv; w[1] = bu; w[2] = bv;
        for (j = 0; j < 3; j++) {
            double c[3];
            load(bp, bi[3 * bt + j], c);
            for (k = 0; k < 3; k++) q[k] += w[j] * c[k];
            if (w[j] > 1e-7) fv[nf++] = bi[3 * bt + j];
        }
        for (s = 0; s < bnt; s++) { /* pseudonormal of the feature: faces that contain it */
            const uint32_t *tr = bi + 3 * s;
            int has = 0, corner = 0;
            double n[3], ang = 1;
            for (j = 0; j < nf; j++)
                for (k = 0; k < 3; k++)
                    if (tr[k] == fv[j]) { has++; corner = k; }
            if (has < nf) continue;
            faces++;
            unit_normal(bp, tr, n);
            if (nf == 1) {
                double a[3], b[3], c[3], e1[3], e2[3], cs;
                load(bp, tr[corner], a); load(bp, tr[(corner + 1) % 3], b); load(bp, tr[(corner + 2) % 3], c);
                for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
                cs = dot3(e1, e2) / sqrt(dot3(e1, e1) * dot3(e2, e2));
                ang = acos(cs < -1 ? -1 : cs > 1 ? 1 : cs);
            }
            for (k = 0; k < 3; k++) N[k] += ang * n[k];
        }
        if ((nf == 2 && faces < 2) || (nf == 1 && bvert[fv[0]])) { r.boundary++; continue; } /* on a boundary */
        for (k = 0; k < 3; k++) d[k] = p[k] - q[k];
        sd = dot3(d, N) > 0 ? sqrt(best) : -sqrt(best);
        r.checked++;
        if (sd > 1e-4 * diag) r.outside++;
        if (sd / diag > r.worst) r.worst = sd / diag;
    }
    free(bvert);
    return r;
}

static double diagonal(const mesh *m)
{
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, d = 0;
    size_t v;
    int k;
    for (v = 0; v < m->nv; v++)
        for (k = 0; k < 3; k++) {
            if (m->p[3 * v + k] < lo[k]) lo[k] = m->p[3 * v + k];
            if (m->p[3 * v + k] > hi[k]) hi[k] = m->p[3 * v + k];
        }
    for (k = 0; k < 3; k++) d += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d);
}

/* the shell's own properties; returns the number of stopped vertices seen. Where the surface is
   concave at a vertex, its own adjacent faces' planes lie nearer the offset point than the offset
   (by the cosine between the vertex normal and the face's normal, taken at least 0.75 as the
   header does): the 85% bound applies to that local distance. */
static void check_shell(const char *what, const mesh *m, const dm_shell *sh, const dm_bvh *bvh)
{
    size_t v, t, bad_range = 0, bad_pos = 0, bad_norm = 0, collide = 0, full = 0;
    double *local = (double *)malloc((m->nv + 1) * sizeof(double));
    if (!local) { T_CHECK_MSG(0, "%s: out of memory", what); return; }
    for (v = 0; v < m->nv; v++) local[v] = 1.0;
    for (t = 0; t < m->nt; t++) {
        const uint32_t *tv = m->t + 3 * t;
        double fn[3], c[3][3];
        int j, k;
        unit_normal(m->p, tv, fn);
        for (j = 0; j < 3; j++) load(m->p, tv[j], c[j]);
        for (j = 0; j < 3; j++) {
            const float *n = sh->normals + 3 * (size_t)tv[j];
            double rise = 0.0, cs = 0.0;
            for (k = 0; k < 3; k++) {
                rise += (c[(j + 1) % 3][k] + c[(j + 2) % 3][k] - 2.0 * c[j][k]) * n[k];
                cs += fn[k] * n[k];
            }
            if (rise > 0.0 && (cs < 0.75 ? 0.75 : cs) < local[tv[j]]) local[tv[j]] = cs < 0.75 ? 0.75 : cs;
        }
    }
    for (v = 0; v < m->nv; v++) {
        const float *n = sh->normals + 3 * v, *p = m->p + 3 * v, *s = sh->positions + 3 * v;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        float o = sh->offset[v];
        int k;
        dm_closest cl;
        if (!(o >= 0.0f && o <= sh->thickness)) bad_range++;
        if (fabs(len - 1.0) > 1e-5) bad_norm++;
        for (k = 0; k < 3; k++)
            if (s[k] != p[k] + o * n[k]) bad_pos++;
        if (o == sh->thickness) full++;
        if (o > 0.0f && dm_bvh_closest_point(bvh, s, INFINITY, &cl) && cl.distance < 0.85 * local[v] * o) collide++;
    }
    free(local);
    T_CHECK_MSG(bad_range == 0 && bad_pos == 0 && bad_norm == 0, "%s: %zu offsets out of range, %zu positions, %zu normals", what,
                bad_range, bad_pos, bad_norm);
    T_CHECK_MSG(collide == 0, "%s: %zu shell points closer to the original than 85%% of their offset", what, collide);
    T_CHECK_MSG(full + sh->stopped_vertices == m->nv, "%s: %zu at full thickness + %zu stopped != %zu", what, full,
                sh->stopped_vertices, m->nv);
}

/* the base's vertex normals as the bake takes them (dm_base_normals), as doubles */
static void vertex_normals(const float *p, size_t nv, const uint32_t *t, size_t nt, double *vn)
{
    float *f = (float *)malloc(3 * nv * sizeof(float) + 4);
    size_t i;
    if (!T_CHECK(f && dm_base_normals(p, nv, t, nt, NULL, f) == DM_OK)) {
        memset(vn, 0, 3 * nv * sizeof(double));
        free(f);
        return;
    }
    for (i = 0; i < 3 * nv; i++) vn[i] = f[i];
    free(f);
}

/* Base points (a barycentric grid of 15 per triangle): how many lie outside the shell (farther
   from the original than the thickness), and how many bake rays (along the inverted interpolated
   normal, from a quarter thickness outside, up to 2.25 thicknesses) first meet a back face or
   nothing. Then the bake rays of a finer grid (153 per triangle, FOLD_GRID subdivisions): how
   many go out and in again (a back face, then a front face more than 1e-4 of the diagonal
   deeper, within 2.25 thicknesses: a fold; a front face right after a front face is a pleat of
   the original, not counted). */
#define FOLD_GRID 16
typedef struct base_report { size_t samples, outside_shell, back_first, missed, fold_rays, folds; } base_report;

static int ray_folds(const dm_shell *sh, const dm_bvh *orig_bvh, const mesh *orig, const double y[3], const double n[3])
{
    double l = sqrt(dot3(n, n)), fn[3], out_t = -1.0;
    dm_ray ray;
    dm_hit hit;
    int k, crossings;
    for (k = 0; k < 3; k++) {
        ray.dir[k] = (float)(-n[k] / l);
        ray.org[k] = (float)(y[k] + 0.25 * sh->thickness * n[k] / l);
    }
    ray.tmin = 0.0f;
    ray.tmax = 2.25f * sh->thickness;
    if (!dm_bvh_intersect(orig_bvh, &ray, &hit)) return 0;
    for (crossings = 0; crossings < 16; crossings++) {
        ray.tmin = hit.t + 1e-6f * sh->diagonal;
        if (!(ray.tmin < ray.tmax) || !dm_bvh_intersect(orig_bvh, &ray, &hit)) break;
        unit_normal(orig->p, orig->t + 3 * hit.triangle, fn);
        if (dot3(fn, n) <= 0) {
            out_t = hit.t;
        } else {
            if (out_t >= 0 && hit.t - out_t > 1e-4 * sh->diagonal) return 1;
            out_t = -1.0;
        }
    }
    return 0;
}
static base_report check_base(const dm_shell *sh, const dm_bvh *orig_bvh, const mesh *orig, const float *bp, size_t bnv,
                              const uint32_t *bi, size_t bnt)
{
    base_report r = {0, 0, 0, 0, 0, 0};
    double *vn = (double *)malloc(3 * bnv * sizeof(double));
    size_t t;
    int i, j, k;
    vertex_normals(bp, bnv, bi, bnt, vn);
    for (t = 0; t < bnt; t++)
        for (i = 0; i <= 4; i++)
            for (j = 0; i + j <= 4; j++) {
                double w[3] = {(4 - i - j) / 4.0, i / 4.0, j / 4.0}, y[3] = {0, 0, 0}, n[3] = {0, 0, 0}, l, fn[3];
                float q[3];
                dm_closest cl;
                dm_ray ray;
                dm_hit hit;
                int c;
                for (c = 0; c < 3; c++)
                    for (k = 0; k < 3; k++) {
                        y[k] += w[c] * bp[3 * bi[3 * t + c] + k];
                        n[k] += w[c] * vn[3 * bi[3 * t + c] + k];
                    }
                for (k = 0; k < 3; k++) q[k] = (float)y[k];
                r.samples++;
                if (!dm_bvh_closest_point(orig_bvh, q, INFINITY, &cl) || cl.distance > sh->thickness * 1.001f + 1e-6f * sh->diagonal)
                    r.outside_shell++;
                l = sqrt(dot3(n, n));
                for (k = 0; k < 3; k++) {
                    ray.dir[k] = (float)(-n[k] / l);
                    ray.org[k] = (float)(y[k] + 0.25 * sh->thickness * n[k] / l);
                }
                ray.tmin = 0.0f;
                ray.tmax = 2.25f * sh->thickness;
                if (!dm_bvh_intersect(orig_bvh, &ray, &hit)) { r.missed++; continue; }
                unit_normal(orig->p, orig->t + 3 * hit.triangle, fn);
                if (dot3(fn, n) <= 0) r.back_first++;
            }
    for (t = 0; t < bnt; t++)
        for (i = 0; i <= FOLD_GRID; i++)
            for (j = 0; i + j <= FOLD_GRID; j++) {
                double w[3] = {(double)(FOLD_GRID - i - j) / FOLD_GRID, (double)i / FOLD_GRID, (double)j / FOLD_GRID};
                double y[3] = {0, 0, 0}, n[3] = {0, 0, 0};
                int c;
                for (c = 0; c < 3; c++)
                    for (k = 0; k < 3; k++) {
                        y[k] += w[c] * bp[3 * bi[3 * t + c] + k];
                        n[k] += w[c] * vn[3 * bi[3 * t + c] + k];
                    }
                r.fold_rays++;
                r.folds += ray_folds(sh, orig_bvh, orig, y, n);
            }
    free(vn);
    return r;
}

typedef struct run { dm_pm *pm; dm_simplify_report rep; float *bp; uint32_t *bi; size_t bnv, bnt; } run;
static dm_result simplify(const mesh *m, dm_shell *sh, size_t target, run *r)
{
    dm_simplify_options o;
    dm_result res;
    memset(&o, 0, sizeof o);
    memset(r, 0, sizeof *r);
    o.target_triangles = target;
    if (sh) {
        o.constraint = dm_shell_constraint;
        o.on_collapse = dm_shell_collapsed;
        o.constraint_user = sh;
    }
    res = dm_simplify(m->p, m->nv, m->t, m->nt, &o, &r->pm, &r->rep);
    if (res != DM_OK) return res;
    dm_pm_counts(r->pm, &r->bnv, &r->bnt);
    r->bp = (float *)malloc(3 * r->bnv * sizeof(float) + 1);
    r->bi = (uint32_t *)malloc(3 * r->bnt * sizeof(uint32_t) + 1);
    dm_pm_get_mesh(r->pm, r->bp, r->bi, NULL);
    return DM_OK;
}
static void run_free(run *r) { dm_pm_free(r->pm); free(r->bp); free(r->bi); memset(r, 0, sizeof *r); }

/* the whole chain on one mesh: shell, constrained and unconstrained bases, checks; folds_per_10k:
   folded bake rays tolerated per 10000 */
static void check_mesh(const char *what, const mesh *m, size_t target, size_t max_faces, int closed, size_t folds_per_10k)
{
    dm_shell *sh = NULL;
    dm_bvh *bvh = NULL;
    run con, unc;
    double diag = diagonal(m);
    dm_distance_report dc, du;
    side_report sr;
    base_report br;
    T_CHECK(dm_bvh_build(m->p, m->nv, m->t, m->nt, NULL, &bvh) == DM_OK);
    T_CHECK(dm_shell_grow(m->p, m->nv, m->t, m->nt, NULL, &sh) == DM_OK);
    if (!sh || !bvh) { dm_bvh_free(bvh); dm_shell_free(sh); return; }
    T_NEAR(sh->thickness, 0.02 * diag, 1e-6 * diag);
    check_shell(what, m, sh, bvh);
    T_CHECK(simplify(m, sh, target, &con) == DM_OK);
    T_CHECK(simplify(m, NULL, con.bnt, &unc) == DM_OK);
    T_CHECK_MSG(con.bnt <= max_faces, "%s: %zu faces reached (target %zu)", what, con.bnt, target);
    sr = inner_side(m, con.bp, con.bi, con.bnt, diag);
    T_CHECK_MSG(sr.outside == 0, "%s: %zu of %zu original vertices outside the base (worst %.3g of the diagonal)", what,
                sr.outside, sr.checked, sr.worst);
    if (closed) T_EQ_SIZE(sr.boundary, 0);
    br = check_base(sh, bvh, m, con.bp, con.bnv, con.bi, con.bnt);
    T_CHECK_MSG(br.outside_shell == 0, "%s: %zu of %zu base samples outside the shell", what, br.outside_shell, br.samples);
    T_CHECK_MSG(br.back_first == 0, "%s: %zu of %zu bake rays meet a back face first", what, br.back_first, br.samples);
    if (closed) T_CHECK_MSG(br.missed == 0, "%s: %zu of %zu bake rays miss a closed original", what, br.missed, br.samples);
    T_CHECK_MSG(br.folds <= br.fold_rays * folds_per_10k / 10000, "%s: %zu of %zu bake rays go out and in again", what,
                br.folds, br.fold_rays);
    T_CHECK(dm_surface_distance(m->p, m->nv, m->t, m->nt, con.bp, con.bnv, con.bi, con.bnt, &dist_100000, &dc) == DM_OK);
    T_CHECK(dm_surface_distance(m->p, m->nv, m->t, m->nt, unc.bp, unc.bnv, unc.bi, unc.bnt, &dist_100000, &du) == DM_OK);
    printf("  %s: %zu -> %zu faces (unconstrained %zu); rms %.3e (unconstrained %.3e, ratio %.2f), max %.3e; "
           "%zu vertices checked, %zu on a boundary, worst side %.2e; shell: %zu stopped; constraint: %zu moved, "
           "%zu/%zu/%zu vetoed (enclose/shell/overlap); rays missed %zu of %zu, folded %zu of %zu\n",
           what, m->nt, con.bnt, unc.bnt, dc.rms, du.rms, dc.rms / du.rms, dc.max, sr.checked, sr.boundary, sr.worst,
           sh->stopped_vertices, sh->moved, sh->vetoed_enclose, sh->vetoed_shell, sh->vetoed_overlap, br.missed, br.samples, br.folds, br.fold_rays);
    run_free(&con);
    run_free(&unc);
    dm_bvh_free(bvh);
    dm_shell_free(sh);
}

/* The fallback (dm_shell_relax): on the torus with a narrow hole, a target below what the paper's
   constraints reach is reached once relaxed; the relaxed collapses' keeps are marked and turn into
   the flagged base triangles; the bake takes the nearest crossing either way on exactly those
   (their texels equal a both-ways bake's, the others an inward bake's). */
static void test_fallback(const mesh *m, size_t target)
{
    dm_shell *sh = NULL;
    dm_simplify_options o;
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    run strict;
    uint32_t *ids = NULL;
    uint8_t *flags = NULL;
    float *bp = NULL;
    uint32_t *bi = NULL;
    size_t bnv, bnt, nflag, t, n, k, bad_in = 0, bad_out = 0, in_flagged = 0;
    dm_param *param = NULL;
    dm_param_options po;
    dm_bake_options bo;
    dm_dispmap *mix = NULL, *inw = NULL, *both = NULL;
    if (!T_CHECK(dm_shell_grow(m->p, m->nv, m->t, m->nt, NULL, &sh) == DM_OK)) return;
    T_CHECK(simplify(m, sh, target, &strict) == DM_OK);
    T_CHECK_MSG(strict.bnt > target, "the paper's constraints reach %zu faces, target %zu: no fallback needed", strict.bnt,
                target);
    T_CHECK(sh->fallback == 0 && sh->fallback_collapses == 0);
    run_free(&strict);
    memset(&o, 0, sizeof o);
    o.target_triangles = target;
    o.constraint = dm_shell_constraint;
    o.on_collapse = dm_shell_collapsed;
    o.relax = dm_shell_relax;
    o.constraint_user = sh;
    if (!T_CHECK(dm_simplify(m->p, m->nv, m->t, m->nt, &o, &pm, &rep) == DM_OK)) goto done;
    T_CHECK_MSG(rep.reached_target && sh->fallback_collapses > 0, /* relaxed per candidate, or everywhere */
                "relaxed: %zu faces (target %zu), relaxed %zu, level %d, %zu relaxed collapses", rep.triangle_count,
                target, rep.relaxed, sh->fallback, sh->fallback_collapses);
    dm_pm_counts(pm, &bnv, &bnt);
    bp = (float *)malloc(3 * bnv * sizeof(float));
    bi = (uint32_t *)malloc(3 * bnt * sizeof(uint32_t));
    ids = (uint32_t *)malloc(bnv * sizeof(uint32_t));
    flags = (uint8_t *)malloc(bnt);
    dm_pm_get_mesh(pm, bp, bi, ids);
    nflag = dm_shell_fallback_triangles(sh, bi, bnt, ids, flags);
    for (t = 0, k = 0; t < bnt; t++) k += flags[t];
    T_CHECK_MSG(nflag > 0 && nflag == k, "%zu of %zu base triangles flagged (%zu counted)", nflag, bnt, k);
    printf("  fallback: %zu -> %zu faces (paper's constraints alone: more than %zu); %zu relaxed collapses, %zu of %zu "
           "triangles flagged\n", m->nt, bnt, target, sh->fallback_collapses, nflag, bnt);
    memset(&po, 0, sizeof po);
    po.width = po.height = 128;
    if (!T_CHECK(dm_parameterize(bp, bnv, bi, bnt, &po, &param) == DM_OK)) goto done;
    memset(&bo, 0, sizeof bo);
    bo.inward = 1;
    bo.both_ways = flags;
    T_CHECK(dm_bake(param, bp, bnv, bi, bnt, m->p, m->nv, m->t, m->nt, &bo, &mix) == DM_OK);
    bo.both_ways = NULL;
    T_CHECK(dm_bake(param, bp, bnv, bi, bnt, m->p, m->nv, m->t, m->nt, &bo, &inw) == DM_OK);
    bo.inward = 0;
    T_CHECK(dm_bake(param, bp, bnv, bi, bnt, m->p, m->nv, m->t, m->nt, &bo, &both) == DM_OK);
    if (mix && inw && both) {
        n = (size_t)po.width * (size_t)po.height;
        for (k = 0; k < n; k++) {
            uint32_t tt = param->texel_triangle[k];
            if (tt == DM_NO_HIT) continue;
            if (flags[tt]) {
                in_flagged++;
                bad_in += mix->disp[k] != both->disp[k];
            } else {
                bad_out += mix->disp[k] != inw->disp[k];
            }
        }
        T_CHECK_MSG(in_flagged > 0 && bad_in == 0 && bad_out == 0,
                    "%zu texels in flagged triangles, %zu differ from the both-ways bake; %zu others differ from the inward one",
                    in_flagged, bad_in, bad_out);
    }
done:
    dm_dispmap_free(mix);
    dm_dispmap_free(inw);
    dm_dispmap_free(both);
    dm_param_free(param);
    free(bp);
    free(bi);
    free(ids);
    free(flags);
    dm_pm_free(pm);
    dm_shell_free(sh);
}

/* The paper's inward rule where the base does not enclose the original (a relaxed collapse's
   neighbourhood): a base plane inside a thin slab, 2 mm under its top face and 11 mm over its
   bottom one. The inward ray's first hit is the bottom face seen from inside (a back face: the
   slab's far side); the bake must take the nearest crossing either way, the top face, instead. */
static void test_inside_start(void)
{
    static const float sp[8 * 3] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 0.02f, 1, 0, 0.02f, 1, 1, 0.02f, 0, 1, 0.02f};
    static const uint32_t st[12 * 3] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                        1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
    static const float bp[4 * 3] = {0.1f, 0.1f, 0.011f, 0.9f, 0.1f, 0.011f, 0.9f, 0.9f, 0.011f, 0.1f, 0.9f, 0.011f};
    static const uint32_t bi[2 * 3] = {0, 1, 2, 0, 2, 3};
    dm_param *param = NULL;
    dm_param_options po;
    dm_bake_options bo;
    dm_dispmap *map = NULL;
    size_t k, n, hits = 0, off = 0;
    memset(&po, 0, sizeof po);
    po.width = po.height = 64;
    if (!T_CHECK(dm_parameterize(bp, 4, bi, 2, &po, &param) == DM_OK)) return;
    memset(&bo, 0, sizeof bo);
    bo.inward = 1; /* max_distance: 5% of the slab's diagonal, 71 mm; the inward search starts 7 mm out */
    if (T_CHECK(dm_bake(param, bp, 4, bi, 2, sp, 8, st, 12, &bo, &map) == DM_OK)) {
        n = (size_t)po.width * (size_t)po.height;
        for (k = 0; k < n; k++) {
            if (map->status[k] != DM_TEXEL_HIT) continue;
            hits++;
            off += !(fabsf(map->disp[k] + 0.009f) < 1e-5f);
        }
        T_CHECK_MSG(hits > n / 4 && off == 0, "%zu of %zu texels hit, %zu not on the top face (9 mm out)", hits, n, off);
    }
    dm_dispmap_free(map);
    dm_param_free(param);
}

static void test_bad_input(const mesh *m)
{
    dm_shell *sh = (dm_shell *)1;
    dm_shell_options so;
    float bad[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t tri[3] = {0, 1, 2}, badtri[3] = {0, 1, 3};
    dm_collapse c;
    float corr[3];
    memset(&so, 0, sizeof so);
    T_EQ_INT(dm_shell_grow(m->p, m->nv, m->t, m->nt, NULL, NULL), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_shell_grow(NULL, 3, tri, 1, NULL, &sh), DM_ERR_INVALID_ARGUMENT);
    T_CHECK(sh == NULL);
    T_EQ_INT(dm_shell_grow(bad, 3, tri, 0, NULL, &sh), DM_ERR_NO_TRIANGLES);
    T_EQ_INT(dm_shell_grow(bad, 3, badtri, 1, NULL, &sh), DM_ERR_BAD_INDEX);
    bad[4] = NAN;
    T_EQ_INT(dm_shell_grow(bad, 3, tri, 1, NULL, &sh), DM_ERR_BAD_POSITION);
    bad[4] = 0.0f;
    so.thickness = NAN;
    T_EQ_INT(dm_shell_grow(bad, 3, tri, 1, &so, &sh), DM_ERR_INVALID_ARGUMENT);
    so.thickness = -1.0f;
    T_EQ_INT(dm_shell_grow(bad, 3, tri, 1, &so, &sh), DM_ERR_INVALID_ARGUMENT);
    so.thickness = 0.0f;
    so.steps = -2;
    T_EQ_INT(dm_shell_grow(bad, 3, tri, 1, &so, &sh), DM_ERR_INVALID_ARGUMENT);
    so.steps = 0;
    /* one triangle: an open mesh; the shell still grows (along the normal, full thickness) */
    T_EQ_INT(dm_shell_grow(bad, 3, tri, 1, &so, &sh), DM_OK);
    if (sh) {
        T_EQ_SIZE(sh->stopped_vertices, 0);
        T_NEAR(sh->positions[2], sh->thickness, 1e-7);
    }
    memset(&c, 0, sizeof c);
    T_EQ_INT(dm_shell_constraint(NULL, &c, corr), DM_COLLAPSE_VETO);
    T_EQ_INT(dm_shell_constraint(sh, NULL, corr), DM_COLLAPSE_VETO);
    T_EQ_INT(dm_shell_constraint(sh, &c, corr), DM_COLLAPSE_VETO); /* no arrays */
    dm_shell_free(sh);
    dm_shell_free(NULL);
}


/* allocation failure at every point of dm_shell_grow; then a shell whose allocator fails inside
   the constraint: every candidate is vetoed, nothing leaks */
static void test_alloc_fail(void)
{
    mesh m = make_sphere(6, 0.05, 1.0);
    counting cnt;
    dm_allocator al = {c_alloc, c_free, &cnt};
    dm_shell_options so;
    long k, total = 0, bad = 0;
    memset(&so, 0, sizeof so);
    so.allocator = &al;
    for (k = 0;; k++) {
        dm_shell *sh = NULL;
        dm_result r;
        cnt.calls = 0;
        cnt.fail_at = k;
        cnt.live = 0;
        r = dm_shell_grow(m.p, m.nv, m.t, m.nt, &so, &sh);
        if (r == DM_OK) {
            total = k;
            dm_shell_free(sh);
            if (cnt.live != 0) bad++;
            break;
        }
        if (r != DM_ERR_OUT_OF_MEMORY || sh != NULL || cnt.live != 0) bad++;
    }
    T_CHECK_MSG(bad == 0 && total > 5, "%ld failures mishandled over %ld allocation points", bad, total);
    {
        dm_shell *sh = NULL;
        run r;
        cnt.calls = 0;
        cnt.fail_at = 1L << 40;
        cnt.live = 0;
        T_CHECK(dm_shell_grow(m.p, m.nv, m.t, m.nt, &so, &sh) == DM_OK);
        cnt.fail_at = cnt.calls; /* from now on the constraint's scratch cannot grow */
        if (sh && simplify(&m, sh, 20, &r) == DM_OK) {
            T_EQ_SIZE(r.rep.collapse_count, 0);
            T_CHECK(r.rep.vetoed > 0);
            run_free(&r);
        }
        dm_shell_free(sh);
        T_EQ_INT(cnt.live, 0);
    }
    mesh_free(&m);
}

static int cancel_now(void *u, float done) { (void)done; return ++*(int *)u >= 2; }

/* squared distance from q to the nearest triangle of m, by brute force in double */
static double brute_d2(const mesh *m, const float q[3])
{
    double best = DBL_MAX, p[3];
    size_t t;
    int k;
    for (k = 0; k < 3; k++) p[k] = q[k];
    for (t = 0; t < m->nt; t++) {
        double tri[9], u, v, d2;
        for (k = 0; k < 9; k++) tri[k] = m->p[3 * m->t[3 * t + (size_t)(k / 3)] + (size_t)(k % 3)];
        d2 = dm__triangle_d2(p, tri, &u, &v);
        if (d2 < best) best = d2;
    }
    return best;
}

/* A fan of K triangles around the apex of a flat cone (the rim on the unit circle in z = 0, the
   apex at z = 0.2): every box of a long thin triangle reaches from the apex to the rim, so a
   box hierarchy alone visits a share of all K triangles for each rim vertex (quadratic). */
static mesh make_fan(int K)
{
    mesh m;
    int i;
    m.nv = (size_t)K + 1;
    m.nt = (size_t)K;
    m.p = (float *)malloc(3 * m.nv * sizeof(float));
    m.t = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t));
    if (!m.p || !m.t) { free(m.p); free(m.t); m.p = NULL; m.t = NULL; m.nv = m.nt = 0; return m; }
    m.p[0] = 0.0f; m.p[1] = 0.0f; m.p[2] = 0.2f;
    for (i = 0; i < K; i++) {
        double a = 6.283185307179586 * i / K;
        m.p[3 + 3 * i] = (float)cos(a); m.p[4 + 3 * i] = (float)sin(a); m.p[5 + 3 * i] = 0.0f;
        m.t[3 * i] = 0; m.t[3 * i + 1] = (uint32_t)(1 + i); m.t[3 * i + 2] = (uint32_t)(1 + (i + 1) % K);
    }
    return m;
}

static void test_valence(void)
{
    static const int Ks[3] = {20000, 40000, 80000};
    unsigned long long ops[3];
    int k;
    for (k = 0; k < 3; k++) {
        mesh m = make_fan(Ks[k]);
        dm_shell *sh = NULL;
        ops[k] = 0;
        if (!T_CHECK(m.p != NULL)) return;
        g_ops = 0;
        T_CHECK(dm_shell_grow(m.p, m.nv, m.t, m.nt, NULL, &sh) == DM_OK);
        ops[k] = g_ops;
        if (sh && k == 0) { /* each vertex's offsets against the brute-force distance, every 50th vertex */
            size_t v, wrong = 0, checked = 0;
            for (v = 0; v < m.nv; v += 50) {
                int step, kk;
                for (step = 1; step <= 8; step++) {
                    float h = sh->thickness * (float)step / 8.0f, q[3];
                    int near;
                    for (kk = 0; kk < 3; kk++) q[kk] = m.p[3 * v + (size_t)kk] + h * sh->normals[3 * v + (size_t)kk];
                    near = (float)sqrt(brute_d2(&m, q)) < 0.9f * h;
                    checked++;
                    if (near) { wrong += sh->offset[v] >= h; break; } /* stopped before this step */
                    wrong += sh->offset[v] < h; /* not stopped: grown at least this far */
                }
            }
            printf("  fan of 20000: %zu of %zu offset steps differ from the brute force\n", wrong, checked);
            T_CHECK(checked > 1000 && wrong == 0);
        }
        dm_shell_free(sh);
        mesh_free(&m);
    }
    printf("  fan of 20k / 40k / 80k triangles: %llu / %llu / %llu proximity steps (80k / 20k = %.2f)\n", ops[0], ops[1],
           ops[2], (double)ops[2] / (double)(ops[0] ? ops[0] : 1));
    T_CHECK(ops[0] >= 20000);
    T_CHECK_MSG(ops[2] <= 6 * ops[0], "%llu steps at 80k, %llu at 20k", ops[2], ops[0]);
}

static void test_cancel_and_determinism(const mesh *m)
{
    dm_shell_options so;
    dm_shell *a = NULL, *b = NULL;
    int calls = 0;
    run ra, rb;
    memset(&so, 0, sizeof so);
    so.progress = cancel_now;
    so.progress_user = &calls;
    T_EQ_INT(dm_shell_grow(m->p, m->nv, m->t, m->nt, &so, &a), DM_CANCELLED);
    T_CHECK(a == NULL);
    T_CHECK(dm_shell_grow(m->p, m->nv, m->t, m->nt, NULL, &a) == DM_OK);
    T_CHECK(dm_shell_grow(m->p, m->nv, m->t, m->nt, NULL, &b) == DM_OK);
    if (!a || !b) { dm_shell_free(a); dm_shell_free(b); return; }
    T_CHECK(memcmp(a->positions, b->positions, 3 * m->nv * sizeof(float)) == 0);
    T_CHECK(simplify(m, a, 300, &ra) == DM_OK);
    T_CHECK(simplify(m, b, 300, &rb) == DM_OK);
    T_CHECK(ra.bnv == rb.bnv && ra.bnt == rb.bnt && ra.bp && rb.bp &&
            memcmp(ra.bp, rb.bp, 3 * ra.bnv * sizeof(float)) == 0 && memcmp(ra.bi, rb.bi, 3 * ra.bnt * sizeof(uint32_t)) == 0);
    run_free(&rb);
    { /* one shell, several runs: the second run on shell a (which followed the first run's mesh)
         and a run at another target in between give the same base as a fresh shell */
        size_t moved = a->moved, vetoed = a->vetoed_enclose + a->vetoed_shell + a->vetoed_overlap;
        run rc, rd;
        T_CHECK(simplify(m, a, 500, &rc) == DM_OK);
        T_CHECK(simplify(m, a, 300, &rd) == DM_OK);
        T_CHECK_MSG(ra.bnv == rd.bnv && ra.bnt == rd.bnt && ra.bp && rd.bp &&
                        memcmp(ra.bp, rd.bp, 3 * ra.bnv * sizeof(float)) == 0 &&
                        memcmp(ra.bi, rd.bi, 3 * ra.bnt * sizeof(uint32_t)) == 0,
                    "a shell used for a third run gives another base (%zu vs %zu faces)", rd.bnt, ra.bnt);
        T_CHECK_MSG(a->moved == moved && a->vetoed_enclose + a->vetoed_shell + a->vetoed_overlap == vetoed,
                    "verdicts of the last run: moved %zu vs %zu, vetoed %zu vs %zu", a->moved, moved,
                    a->vetoed_enclose + a->vetoed_shell + a->vetoed_overlap, vetoed);
        run_free(&rc);
        run_free(&rd);
    }
    run_free(&ra);
    dm_shell_free(a);
    dm_shell_free(b);
}

/* The enclosure's exact projection (dm__sh_project) against brute force: the nearest point in the
   metric on the outer side of all planes lies in the relative interior of one face, the point
   nearest x0 on the affine hull of some independent set of at most three of the planes; so the
   nearest feasible point over all such sets (each solved as a small equality problem) is the
   answer, and no feasible one means the planes are inconsistent (and then the at most four
   planes dm__sh_project names as the proof have no common point by themselves). Random metrics (the quadric
   part of rank 0 to 3), plane sets around a point (consistent), with opposite pairs (not),
   fans of nearly parallel planes (where Dykstra's sweeps crawl). */
static unsigned rnd_state = 12345u;
static double rnd(void) { rnd_state = rnd_state * 1664525u + 1013904223u; return (rnd_state >> 8) / 16777216.0; }

static int solve_small(double A[3][4], int n, double *out) /* Gauss with pivoting, n <= 3 */
{
    int i, j, k;
    for (i = 0; i < n; i++) {
        int pv = i;
        for (j = i + 1; j < n; j++) if (fabs(A[j][i]) > fabs(A[pv][i])) pv = j;
        if (fabs(A[pv][i]) < 1e-12) return 0;
        for (k = 0; k < 4; k++) { double t = A[i][k]; A[i][k] = A[pv][k]; A[pv][k] = t; }
        for (j = 0; j < n; j++) {
            double f;
            if (j == i) continue;
            f = A[j][i] / A[i][i];
            for (k = i; k < 4; k++) A[j][k] -= f * A[i][k];
        }
    }
    for (i = 0; i < n; i++) out[i] = A[i][3] / A[i][i];
    return 1;
}

/* brute force: 1 and *best at the answer, 0 when no point meets every plane */
static int project_brute(double Mf[3][3], const double *pl, size_t np, const double x0[3], double best[3])
{
    double Mi[3][3], det, bd = 1e300;
    size_t s[3], i;
    int found = 0, k, j;
    Mi[0][0] = Mf[1][1] * Mf[2][2] - Mf[1][2] * Mf[2][1];
    Mi[0][1] = Mf[0][2] * Mf[2][1] - Mf[0][1] * Mf[2][2];
    Mi[0][2] = Mf[0][1] * Mf[1][2] - Mf[0][2] * Mf[1][1];
    Mi[1][1] = Mf[0][0] * Mf[2][2] - Mf[0][2] * Mf[2][0];
    Mi[1][2] = Mf[0][2] * Mf[1][0] - Mf[0][0] * Mf[1][2];
    Mi[2][2] = Mf[0][0] * Mf[1][1] - Mf[0][1] * Mf[1][0];
    Mi[1][0] = Mi[0][1]; Mi[2][0] = Mi[0][2]; Mi[2][1] = Mi[1][2];
    det = Mf[0][0] * Mi[0][0] + Mf[0][1] * Mi[1][0] + Mf[0][2] * Mi[2][0];
    for (j = 0; j < 3; j++) for (k = 0; k < 3; k++) Mi[j][k] /= det;
    for (s[0] = 0; s[0] <= np; s[0]++)
        for (s[1] = s[0] < np ? s[0] + 1 : np; s[1] <= np; s[1]++)
            for (s[2] = s[1] < np ? s[1] + 1 : np; s[2] <= np; s[2]++) {
                /* x = x0 + Mi N lambda, with N^T x = d on the chosen planes */
                size_t set[3];
                int n = 0, a, b;
                double A[3][4], lam[3] = {0, 0, 0}, x[3], md = 0, w[3];
                for (k = 0; k < 3; k++) if (s[k] < np) set[n++] = s[k];
                for (a = 0; a < n; a++) {
                    const double *na = pl + 4 * set[a];
                    for (b = 0; b < n; b++) {
                        const double *nb = pl + 4 * set[b];
                        double v = 0;
                        for (j = 0; j < 3; j++) for (k = 0; k < 3; k++) v += na[j] * Mi[j][k] * nb[k];
                        A[a][b] = v;
                    }
                    A[a][3] = na[3] - dot3(na, x0);
                }
                if (n && !solve_small(A, n, lam)) continue;
                for (j = 0; j < 3; j++) {
                    x[j] = x0[j];
                    for (a = 0; a < n; a++) for (k = 0; k < 3; k++) x[j] += Mi[j][k] * pl[4 * set[a] + k] * lam[a];
                }
                for (i = 0; i < np; i++) if (dot3(pl + 4 * i, x) < pl[4 * i + 3] - 1e-9) break;
                if (i < np) continue;
                for (j = 0; j < 3; j++) w[j] = x[j] - x0[j];
                for (j = 0; j < 3; j++) for (k = 0; k < 3; k++) md += w[j] * Mf[j][k] * w[k];
                if (md < bd) { bd = md; for (j = 0; j < 3; j++) best[j] = x[j]; }
                found = 1;
            }
    return found;
}

static void test_projection(void)
{
    int trial, agree = 0, inconsistent = 0, consistent = 0, proved = 0;
    double worst = 0.0;
    for (trial = 0; trial < 3000; trial++) {
        double metric[6], Mf[3][3], pl[4 * 12], work[3 * 12], x0[3], x[3], xb[3];
        size_t np = 1 + (size_t)(rnd() * 11), i, proof[4], nproof;
        int kind = trial % 3, rank = trial % 4, j, k, r1, r2;
        for (j = 0; j < 6; j++) metric[j] = 0.0;
        for (j = 0; j < rank; j++) { /* a quadric of rank `rank`: sum of outer products */
            double v[3], l;
            for (k = 0; k < 3; k++) v[k] = rnd() - 0.5;
            l = sqrt(dot3(v, v));
            for (k = 0; k < 3; k++) v[k] /= l;
            metric[0] += v[0] * v[0]; metric[1] += v[0] * v[1]; metric[2] += v[0] * v[2];
            metric[3] += v[1] * v[1]; metric[4] += v[1] * v[2]; metric[5] += v[2] * v[2];
        }
        for (i = 0; i < np; i++) {
            double *n = pl + 4 * i, l;
            if (kind == 2) { /* nearly parallel: normals within a few degrees of +z */
                n[0] = 0.05 * (rnd() - 0.5); n[1] = 0.05 * (rnd() - 0.5); n[2] = 1.0;
            } else {
                for (k = 0; k < 3; k++) n[k] = rnd() - 0.5;
            }
            l = sqrt(dot3(n, n));
            for (k = 0; k < 3; k++) n[k] /= l;
            n[3] = kind == 1 ? 0.2 * rnd() : -0.3 * rnd(); /* around the origin, or pushed apart */
            if (kind == 1 && i + 1 < np && rnd() < 0.3) { /* an opposite pair: inconsistent */
                double *m = pl + 4 * (i + 1);
                for (k = 0; k < 3; k++) m[k] = -n[k];
                m[3] = 0.1 * rnd() - n[3] + 1e-3;
                i++;
            }
        }
        for (k = 0; k < 3; k++) x0[k] = 2.0 * (rnd() - 0.5);
        if (kind == 2) x0[2] = -1.0 - rnd();
        dm__sh_metric(metric, Mf);
        for (k = 0; k < 3; k++) x[k] = x0[k];
        r1 = project_brute(Mf, pl, np, x0, xb);
        r2 = dm__sh_project(metric, pl, np, 1e-12, work, x, proof, &nproof);
        if (r1) consistent++;
        else inconsistent++;
        if (r1 != r2) {
            T_CHECK_MSG(0, "projection %d: brute force %s, dm__sh_project %s", trial, r1 ? "consistent" : "inconsistent",
                        r2 ? "consistent" : "inconsistent");
            continue;
        }
        if (!r1) { /* x as it was; the planes it names have no common point by themselves */
            double sub[4 * 4], xs[3];
            agree += x[0] == x0[0] && x[1] == x0[1] && x[2] == x0[2];
            for (i = 0; i < nproof; i++)
                for (k = 0; k < 4; k++) sub[4 * i + (size_t)k] = pl[4 * proof[i] + (size_t)k];
            proved += nproof >= 1 && nproof <= 4 && !project_brute(Mf, sub, nproof, x0, xs);
            continue;
        }
        {
            double d = sqrt((x[0] - xb[0]) * (x[0] - xb[0]) + (x[1] - xb[1]) * (x[1] - xb[1]) + (x[2] - xb[2]) * (x[2] - xb[2]));
            if (d > worst) worst = d;
            agree += d < 1e-7;
        }
    }
    T_CHECK_MSG(agree == 3000 && consistent > 1000 && inconsistent > 300,
                "exact projection: %d of 3000 agree with brute force (worst %.2g), %d consistent, %d not", agree, worst,
                consistent, inconsistent);
    T_CHECK_MSG(proved == inconsistent, "exact projection: %d of %d inconsistent sets proved by the planes it names",
                proved, inconsistent);
}

int main(int argc, char **argv)
{
    mesh sphere, torus;
    T_BEGIN(argc, argv);
    test_projection();
    sphere = make_sphere(24, 0.08, 1.0);
    check_mesh("bumpy sphere", &sphere, 200, 200, 1, 0);
    torus = make_torus(96, 48, 0.9, 0.05);
    {
        dm_shell *sh = NULL;
        dm_bvh *bvh = NULL;
        dm_shell_options so;
        memset(&so, 0, sizeof so);
        so.thickness = 0.3f; /* the hole is about 0.2 wide: the inner side must stop */
        T_CHECK(dm_bvh_build(torus.p, torus.nv, torus.t, torus.nt, NULL, &bvh) == DM_OK);
        T_CHECK(dm_shell_grow(torus.p, torus.nv, torus.t, torus.nt, &so, &sh) == DM_OK);
        if (sh && bvh) {
            check_shell("torus, thick shell", &torus, sh, bvh);
            T_CHECK_MSG(sh->stopped_vertices > torus.nv / 10, "%zu stopped", sh->stopped_vertices);
        }
        dm_shell_free(sh);
        dm_bvh_free(bvh);
    }
    check_mesh("fat torus", &torus, 400, 400, 1, 0);
    test_fallback(&torus, 120);
    test_inside_start();
    {   /* sharp edges and narrow grooves: the QEM position of an edge collapse lands far from
           keep, which the enclosure's old triangles must not follow */
        mesh box = make_grooved_box(12, 0.03);
        check_mesh("grooved box", &box, 12, 12, 1, 0);
        mesh_free(&box);
        box = make_grooved_box(4, 0.03); /* left 3 vertices out by 2e-3 of the diagonal before */
        check_mesh("coarse grooved box", &box, 12, 40, 1, 0);
        mesh_free(&box);
    }
    test_bad_input(&sphere);
    test_alloc_fail();
    test_cancel_and_determinism(&sphere);
    test_valence();
    {
        const char *bunny = "/usr/share/glmark2/models/bunny.obj";
        mio_mesh mm;
        mio_error err;
        FILE *f = fopen(bunny, "rb");
        if (!f) {
            T_SKIP_N(15, "bunny", "glmark2-data is not installed");
        } else if (getenv("TEST_SANITIZE")) {
            fclose(f);
            T_SKIP_N(15, "bunny", "70k triangles under the sanitizers: about a minute");
        } else {
            fclose(f);
            if (mio_read_file(bunny, NULL, &mm, &err) == MIO_OK) {
                mesh b;
                b.p = mm.positions;
                b.t = mm.indices;
                b.nv = mm.vertex_count;
                b.nt = mm.triangle_count;
                /* the overlap check samples 4 rays per triangle of a collapse's one-ring: fold
                   patches between them, or on the triangles next to the one-ring, are not seen
                   (1 ray of 76500 here) */
                check_mesh("bunny", &b, 500, 510, 0, 1);
                mio_free_mesh(&mm);
            } else {
                T_CHECK_MSG(0, "bunny: %s", err.message);
            }
        }
    }
    mesh_free(&sphere);
    mesh_free(&torus);
    return T_END();
}
