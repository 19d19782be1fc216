/* test_erosion.c - erosion.h's properties (issue 17 "Done when"):
   a flat windward patch erodes uniformly; a leeward patch changes by the ambient term only; a pit
   fills and a ridge wears; harder materials erode less, monotonically in eps; on a closed torus
   (dispmesh.h's map) the change across seams stays within the 99th percentile of interior
   neighbours' and the reported volume matches the reconstructed torus's enclosed volume within 2%;
   a height field eroded at 512^2 and 2048^2 agrees (RMS <= 5% of the change); a wrapped tile
   commutes with circular shifts bit for bit; a stopped and resumed run gives the same bits; bad
   input gets its named error with the map untouched; no allocation failure leaks; on a cylinder
   with bosses the windward side wears more than the leeward (Fig 5.2.2), and raised letters of a
   hard material lose less than those of a soft one (Fig 5.2.3).
   --digest: prints a hash of the maps and reports of height fields eroded under varied options
   (the ring with and without wrap, materials, flags, force, bound, radii; the walk with a valid map), for
   tests/erosion_simd_same.sh to compare the portable build with the ERO_USE_AVX2 one. */
#define ERO_IMPLEMENTATION
#include "erosion.h"
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#include "test.h"
#include "testmesh.h"
#include "failalloc.h"
#include <stdlib.h>

/* ---- helpers ---------------------------------------------------------------------------------- */

typedef struct plane_grid { /* a flat surface grid: a plane in 3D as a surface sample grid */
    int w, h;
    float *pos, *nrm, *disp, *area;
    uint32_t *nbr;
    uint8_t *rot;
} plane_grid;

static plane_grid make_plane(int w, int h, float s, const float u[3], const float v[3], float d0)
{
    plane_grid p;
    int x, y, k;
    float n[3];
    size_t nt = (size_t)w * h;
    p.w = w; p.h = h;
    p.pos = (float *)malloc(3 * nt * sizeof(float));
    p.nrm = (float *)malloc(3 * nt * sizeof(float));
    p.disp = (float *)malloc(nt * sizeof(float));
    p.area = (float *)malloc(nt * sizeof(float));
    p.nbr = (uint32_t *)malloc(4 * nt * sizeof(uint32_t));
    p.rot = (uint8_t *)calloc(4 * nt, 1);
    n[0] = u[1] * v[2] - u[2] * v[1]; n[1] = u[2] * v[0] - u[0] * v[2]; n[2] = u[0] * v[1] - u[1] * v[0];
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            for (k = 0; k < 3; k++) { p.pos[3 * i + k] = s * (x * u[k] + y * v[k]); p.nrm[3 * i + k] = n[k]; }
            p.disp[i] = d0;
            p.area[i] = s * s;
            p.nbr[4 * i + 0] = x + 1 < w ? (uint32_t)(i + 1) : UINT32_MAX;
            p.nbr[4 * i + 1] = x > 0 ? (uint32_t)(i - 1) : UINT32_MAX;
            p.nbr[4 * i + 2] = y + 1 < h ? (uint32_t)(i + w) : UINT32_MAX;
            p.nbr[4 * i + 3] = y > 0 ? (uint32_t)(i - w) : UINT32_MAX;
        }
    return p;
}
static void plane_free(plane_grid *p)
{
    free(p->pos); free(p->nrm); free(p->disp); free(p->area); free(p->nbr); free(p->rot);
}
static ero_grid plane_ero(plane_grid *p)
{
    return ero_surface_grid(p->w, p->h, p->pos, p->nrm, p->disp, p->area, NULL, p->nbr, p->rot);
}

/* min and max of a[i] - b[i] over the texels at least margin from the border */
static void interior_range(const float *a, const float *b, int w, int h, int margin, double *lo, double *hi)
{
    int x, y;
    *lo = 1e300; *hi = -1e300;
    for (y = margin; y < h - margin; y++)
        for (x = margin; x < w - margin; x++) {
            double d = (double)a[(size_t)y * w + x] - (b ? b[(size_t)y * w + x] : 0.0);
            if (d < *lo) *lo = d;
            if (d > *hi) *hi = d;
        }
}

static float *copy_floats(const float *a, size_t n)
{
    float *c = (float *)malloc(n * sizeof(float));
    memcpy(c, a, n * sizeof(float));
    return c;
}

static int dcmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* ---- 1, 2: flat patches, windward and leeward ------------------------------------------------ */

static void test_flat_patches(void)
{
    const float u[3] = {1, 0, 0}, v[3] = {0, 0.8f, 0.6f}; /* normal (0, -0.6, 0.8) */
    const float s = 0.01f;
    plane_grid p = make_plane(96, 96, s, u, v, 0.05f);
    ero_grid g = plane_ero(&p);
    ero_options o = ero_default_options();
    ero_material m = {1, 4, 0, 0}, r;
    ero_report rep;
    double lo, hi, want, amb;
    float *d0 = copy_floats(p.disp, 96 * 96);
    ero_resolve_material(&m, &r);
    amb = r.ambient;
    o.normal_radius = 2 * s; o.filter_sigma = s; o.rate = 1e-3f;
    /* windward: the wind blows into the face at exposure e = 0.6 */
    o.wind[0] = 0.8f; o.wind[1] = 0.6f * 0.6f; o.wind[2] = -0.6f * 0.8f;
    T_CHECK(ero_erode(&g, NULL, &m, 1, 3, &o, NULL, &rep) == ERO_OK);
    interior_range(p.disp, d0, 96, 96, 8, &lo, &hi);
    want = 3 * 1e-3 * (0.6 + amb) / 4.0; /* flat: c = 0, R = eps_max */
    printf("  note: windward flat patch: change %.9g..%.9g, expected %.9g\n", lo, hi, want);
    T_CHECK_MSG(hi - lo <= 1e-4 * want, "windward patch not uniform: spread %g of %g", hi - lo, want);
    T_CHECK_MSG(fabs(lo - want) <= 1e-3 * want, "windward change %g, expected %g", lo, want);
    /* leeward: the wind blows along the normal, away from the face: ambient / R only */
    memcpy(p.disp, d0, 96 * 96 * sizeof(float));
    o.wind[0] = 0.0f; o.wind[1] = -0.6f; o.wind[2] = 0.8f;
    T_CHECK(ero_erode(&g, NULL, &m, 1, 3, &o, NULL, &rep) == ERO_OK);
    interior_range(p.disp, d0, 96, 96, 0, &lo, &hi);
    want = 3 * 1e-3 * amb / 4.0;
    printf("  note: leeward flat patch: change %.9g..%.9g, expected ambient/eps_max %.9g\n", lo, hi, want);
    T_CHECK_MSG(fabs(lo - want) <= 1e-3 * want && fabs(hi - want) <= 1e-3 * want, "leeward %g..%g vs %g", lo, hi, want);
    memcpy(p.disp, d0, 96 * 96 * sizeof(float));
    o.flags = ERO_LEEWARD_LITERAL; /* the paper's literal H = ambientW */
    T_CHECK(ero_erode(&g, NULL, &m, 1, 3, &o, NULL, &rep) == ERO_OK);
    interior_range(p.disp, d0, 96, 96, 0, &lo, &hi);
    want = 3 * 1e-3 * amb;
    T_CHECK_MSG(fabs(lo - want) <= 1e-3 * want && fabs(hi - want) <= 1e-3 * want, "literal leeward %g..%g vs %g", lo, hi, want);
    free(d0);
    plane_free(&p);
}

/* ---- 3: a pit fills, a ridge wears ----------------------------------------------------------- */

static void test_pit_ridge(void)
{
    enum { N = 128 };
    float *h = (float *)malloc(N * N * sizeof(float)), *h0;
    float s = 1.0f / N;
    int x, y;
    ero_grid g;
    ero_options o = ero_default_options();
    ero_report rep;
    double pit, ridge, flat;
    for (y = 0; y < N; y++)
        for (x = 0; x < N; x++) {
            double px = (x + 0.5) * s, py = (y + 0.5) * s;
            double rp = (px - 0.3) * (px - 0.3) + (py - 0.5) * (py - 0.5), rr = (px - 0.75) * (px - 0.75);
            h[y * N + x] = (float)(-0.04 * exp(-rp / (2 * 0.05 * 0.05)) + 0.04 * exp(-rr / (2 * 0.05 * 0.05)));
        }
    h0 = copy_floats(h, N * N);
    g = ero_heightfield_grid(N, N, h, s, 1);
    o.wind[2] = -1.0f; /* straight down: every part faces it */
    o.normal_radius = 2 * s; o.filter_sigma = s;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 5, &o, NULL, &rep) == ERO_OK);
    pit = h[(N / 2) * N + (int)(0.3 * N)] - h0[(N / 2) * N + (int)(0.3 * N)];
    ridge = h[(N / 2) * N + (int)(0.75 * N)] - h0[(N / 2) * N + (int)(0.75 * N)];
    flat = h[(N / 2) * N + (int)(0.52 * N)] - h0[(N / 2) * N + (int)(0.52 * N)];
    printf("  note: pit centre %+.3g, ridge crest %+.3g, flat %+.3g; deposited %.3g eroded %.3g\n", pit, ridge, flat,
           rep.deposited, rep.eroded);
    T_CHECK_MSG(pit > 0.0, "the pit does not fill: %g", pit);
    T_CHECK_MSG(ridge < flat && flat < 0.0, "the ridge does not wear more than the flat: %g vs %g", ridge, flat);
    T_CHECK(rep.deposited > 0.0 && rep.eroded > 0.0);
    free(h); free(h0);
}

/* ---- the deposition bound: disp >= 0 on a surface; a texel above the base erodes, never rises ---- */

static void test_bound(void)
{
    const float u[3] = {1, 0, 0}, v[3] = {0, 1, 0};
    const float s = 1.0f / 64;
    plane_grid p = make_plane(64, 64, s, u, v, 0.0f);
    ero_grid g = plane_ero(&p);
    ero_options o = ero_default_options();
    float mn = 1e30f, *d0;
    int x, y, i;
    for (y = 0; y < 64; y++) /* a pit, 0.02 deep, in a surface at the base (disp 0) */
        for (x = 0; x < 64; x++) {
            double r2 = ((x - 32) * (x - 32) + (y - 32) * (y - 32)) * (double)s * s;
            p.disp[y * 64 + x] = (float)(0.02 * exp(-r2 / (2 * 0.08 * 0.08)));
        }
    d0 = copy_floats(p.disp, 64 * 64);
    o.wind[2] = 1.0f; /* leeward everywhere: ambient wear on the flat, strong deposition in the pit */
    o.normal_radius = 2 * s; o.filter_sigma = s; o.rate = 0.05f; o.deposit_ratio = 3.0f; o.curvature_length = 0.5f;
    o.bound = ERO_BOUND_NONE;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 20, &o, NULL, NULL) == ERO_OK);
    for (i = 0; i < 64 * 64; i++) mn = p.disp[i] < mn ? p.disp[i] : mn;
    T_CHECK_MSG(mn < 0.0f, "unbounded, the pit should overfill above the base: smallest disp %g", mn);
    printf("  note: deposition bound: smallest disp after 20 steps unbounded %.3g", mn);
    memcpy(p.disp, d0, 64 * 64 * sizeof(float));
    free(d0);
    o.bound = ERO_BOUND_DEFAULT;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 20, &o, NULL, NULL) == ERO_OK);
    for (mn = 1e30f, i = 0; i < 64 * 64; i++) mn = p.disp[i] < mn ? p.disp[i] : mn;
    printf(", bounded %.3g (bound 0)\n", mn);
    T_CHECK(mn >= 0.0f);
    o.wind[2] = -1.0f; o.deposit_ratio = 0.0f; o.curvature_length = 0.0f;
    /* a flat surface 0.01 above its base (disp < 0), facing the wind: erodes as if unbounded */
    for (i = 0; i < 64 * 64; i++) p.disp[i] = -0.01f;
    d0 = copy_floats(p.disp, 64 * 64);
    o.rate = 1e-3f;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 2, &o, NULL, NULL) == ERO_OK);
    T_CHECK(p.disp[32 * 64 + 32] > d0[32 * 64 + 32] && p.disp[32 * 64 + 32] < 0.0f);
    free(d0);
    plane_free(&p);
}

/* ---- 4: harder erodes less, monotone in eps (four bands painted from a mask) ------------------ */

static void test_materials(void)
{
    enum { N = 128 };
    float *h = (float *)calloc(N * N, sizeof(float)), mask[4];
    uint8_t *mat = (uint8_t *)calloc(N * N, 1);
    ero_material ms[4];
    ero_grid g = ero_heightfield_grid(N, N, h, 1.0f / N, 1);
    ero_options o = ero_default_options();
    double ch[4];
    int k, ok = 1;
    for (k = 0; k < 4; k++) {
        float e = (float)(1 << k);
        ms[k].eps_min = e; ms[k].eps_max = 4 * e; ms[k].eps_medium = 0; ms[k].ambient = 0;
        mask[k] = (k + 0.5f) / 4.0f;
    }
    for (k = 1; k < 4; k++) T_CHECK(ero_paint_mask(mat, N, N, mask, 4, 1, 1, k / 4.0f, (uint8_t)k) == ERO_OK);
    o.wind[0] = 0.3f; o.wind[2] = -1.0f;
    T_CHECK(ero_erode(&g, mat, ms, 4, 4, &o, NULL, NULL) == ERO_OK);
    for (k = 0; k < 4; k++) ch[k] = -h[(N / 2) * N + k * N / 4 + N / 8];
    printf("  note: erosion in bands eps_min 1, 2, 4, 8: %.4g %.4g %.4g %.4g\n", ch[0], ch[1], ch[2], ch[3]);
    for (k = 0; k < 3; k++) ok &= ch[k + 1] < ch[k] && ch[k + 1] > 0.0;
    T_CHECK_MSG(ok, "erosion not decreasing in eps");
    T_NEAR(ch[0] / ch[1], 2.0, 1e-3); /* eps scaled by 2: W_f / R halves */
    { /* a region: a sphere of radius 0.25 around the flat field's point (0.5, 0.5, h) paints pi r^2 / s^2 texels */
        const float c[3] = {0.5f, 0.5f, h[(N / 2) * N + N / 2]};
        size_t painted = 0, k2;
        memset(mat, 0, N * N);
        T_CHECK(ero_paint_sphere(&g, mat, c, 0.25f, 3) == ERO_OK);
        for (k2 = 0; k2 < (size_t)N * N; k2++) painted += mat[k2] == 3;
        T_NEAR((double)painted, 3.14159265 * 0.25 * 0.25 * N * N, 0.02 * 3.14159265 * 0.25 * 0.25 * N * N);
        T_CHECK(mat[(N / 2) * N + N / 2] == 3 && mat[0] == 0);
    }
    free(h); free(mat);
}

/* ---- 5, 6: the torus through dispmesh.h: seams and volume ------------------------------------- */

typedef struct torus_map {
    dm_pm *pm;
    dm_param *param;
    dm_dispmap *map;
    float *bp;
    uint32_t *bi;
    size_t bnv, bnt;
} torus_map;

static int make_torus_map(torus_map *t, int res)
{
    mesh m = make_torus(192, 80, 0.3, 0.06);
    dm_simplify_options so;
    dm_param_options po;
    int ok = 0;
    memset(t, 0, sizeof *t);
    memset(&so, 0, sizeof so);
    so.target_triangles = 500;
    so.min_quality = 0.1f;
    memset(&po, 0, sizeof po);
    po.width = po.height = res;
    if (dm_simplify(m.p, m.nv, m.t, m.nt, &so, &t->pm, NULL) != DM_OK) goto done;
    dm_pm_counts(t->pm, &t->bnv, &t->bnt);
    t->bp = (float *)malloc(3 * t->bnv * sizeof(float));
    t->bi = (uint32_t *)malloc(3 * t->bnt * sizeof(uint32_t));
    dm_pm_get_mesh(t->pm, t->bp, t->bi, NULL);
    if (dm_parameterize(t->bp, t->bnv, t->bi, t->bnt, &po, &t->param) != DM_OK) goto done;
    if (dm_bake(t->param, t->bp, t->bnv, t->bi, t->bnt, m.p, m.nv, m.t, m.nt, NULL, &t->map) != DM_OK) goto done;
    ok = 1;
done:
    mesh_free(&m);
    return ok;
}
static void torus_free(torus_map *t)
{
    dm_dispmap_free(t->map); dm_param_free(t->param); dm_pm_free(t->pm); free(t->bp); free(t->bi);
}
static ero_grid torus_ero(torus_map *t)
{
    dm_dispmap *m = t->map;
    return ero_surface_grid(m->width, m->height, m->pos, m->nrm, m->disp, m->area, m->valid, m->nbr, m->nbr_rot);
}

static double enclosed_volume(torus_map *t)
{
    dm_trimesh *rec = NULL;
    double v = 0.0;
    size_t f;
    if (dm_reconstruct(t->map, t->param, t->bp, t->bnv, t->bi, t->bnt, NULL, &rec) != DM_OK) return -1.0;
    for (f = 0; f < rec->triangle_count; f++) {
        const float *a = rec->positions + 3 * rec->indices[3 * f], *b = rec->positions + 3 * rec->indices[3 * f + 1],
                    *c = rec->positions + 3 * rec->indices[3 * f + 2];
        v += ((double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) +
              (double)a[1] * ((double)b[2] * c[0] - (double)b[0] * c[2]) +
              (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6.0;
    }
    dm_trimesh_free(rec);
    return v;
}

static ero_options torus_options(void)
{
    ero_options o = ero_default_options();
    o.wind[0] = -1.0f; o.wind[2] = -0.3f; /* the source at +x, a little above */
    o.normal_radius = 0.044f; o.filter_sigma = 0.022f; /* 2 and 1 texels at 256^2 */
    return o;
}

/* a seam pair: texels of two charts that are neighbours across their seam */
typedef struct seam_pair { uint64_t seam; double diff, dist; } seam_pair;
static int seam_cmp(const void *a, const void *b)
{
    const seam_pair *x = (const seam_pair *)a, *y = (const seam_pair *)b;
    return x->seam < y->seam ? -1 : x->seam > y->seam;
}
static double dist3(const float *a, const float *b)
{
    return sqrt(((double)a[0] - b[0]) * ((double)a[0] - b[0]) + ((double)a[1] - b[1]) * ((double)a[1] - b[1]) +
                ((double)a[2] - b[2]) * ((double)a[2] - b[2]));
}

/* Seams after 10 steps. A seam is the boundary between two charts; the change across it is the mean,
   over its pairs of neighbours, of the difference of their changes, divided by the number of
   texel spacings the pair spans when more than one (dispmesh's neighbour across a seam is the
   nearest texel there, up to ~3 spacings away). Every seam's must be within the 99th percentile of
   the differences between interior neighbours. Single pairs are reported: under the same
   distribution as the interior, 1% of them would exceed its 99th percentile. */
static void check_seams(torus_map *t, const float *d0)
{
    dm_dispmap *m = t->map;
    size_t n = (size_t)m->width * m->height, i, ni = 0, ns = 0, over = 0, seams = 0, k;
    double *inner = (double *)malloc(4 * n * sizeof(double)), *idist = (double *)malloc(4 * n * sizeof(double));
    seam_pair *sp = (seam_pair *)malloc(4 * n * sizeof(seam_pair));
    double spacing, p99, worst = 0.0, worst_pair = 0.0;
    int d;
    for (i = 0; i < n; i++) {
        if (!m->valid[i]) continue;
        for (d = 0; d < 4; d++) {
            uint32_t j = m->nbr[4 * i + d];
            size_t adj = d == 0 ? i + 1 : d == 1 ? i - 1 : d == 2 ? i + m->width : i - m->width;
            double diff;
            if (j == UINT32_MAX || j == i || !m->valid[j]) continue;
            diff = fabs(((double)m->disp[i] - d0[i]) - ((double)m->disp[j] - d0[j]));
            if (j == adj && m->nbr_rot[4 * i + d] == 0) {
                idist[ni] = dist3(m->pos + 3 * i, m->pos + 3 * (size_t)j);
                inner[ni++] = diff;
            } else {
                uint32_t ca = t->param->chart[t->param->texel_triangle[i]], cb = t->param->chart[t->param->texel_triangle[j]];
                sp[ns].seam = ca < cb ? (uint64_t)ca << 32 | cb : (uint64_t)cb << 32 | ca;
                sp[ns].dist = dist3(m->pos + 3 * i, m->pos + 3 * (size_t)j);
                sp[ns++].diff = diff;
            }
        }
    }
    qsort(inner, ni, sizeof(double), dcmp);
    qsort(idist, ni, sizeof(double), dcmp);
    p99 = inner[(size_t)(0.99 * (ni - 1))];
    spacing = idist[ni / 2];
    qsort(sp, ns, sizeof(seam_pair), seam_cmp);
    for (i = 0; i < ns; i = k) {
        double sum = 0.0;
        for (k = i; k < ns && sp[k].seam == sp[i].seam; k++) {
            double v = sp[k].diff / (sp[k].dist > spacing ? sp[k].dist / spacing : 1.0);
            sum += v;
            if (v > worst_pair) worst_pair = v;
            if (v > p99) over++;
        }
        if (sum / (double)(k - i) > worst) worst = sum / (double)(k - i);
        seams++;
    }
    printf("  note: torus seams: %zu seams (%zu pairs); largest mean change difference across a seam %.4g, interior p99 %.4g "
           "(%zu pairs, spacing %.4g): %.0f%% of it; single pairs: largest %.4g, %.1f%% over p99\n", seams, ns, worst, p99, ni,
           spacing, 100 * worst / p99, worst_pair, 100.0 * over / ns);
    T_CHECK(seams > 20);
    T_CHECK_MSG(worst <= p99, "a seam's change differs by %g > interior p99 %g", worst, p99);
    free(inner); free(idist); free(sp);
}
static void test_torus(torus_map *t)
{
    dm_dispmap *m = t->map;
    size_t n = (size_t)m->width * m->height;
    float *d0 = copy_floats(m->disp, n);
    double v0 = enclosed_volume(t), v1, rel;
    ero_grid g = torus_ero(t);
    ero_options o = torus_options();
    ero_report rep;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 10, &o, NULL, &rep) == ERO_OK);
    v1 = enclosed_volume(t);
    check_seams(t, d0);
    rel = fabs((v0 - v1) - (rep.eroded - rep.deposited)) / fabs(v0 - v1);
    printf("  note: torus volume %.6g -> %.6g: change %.6g, reported eroded - deposited %.6g (%.6g - %.6g): %.2f%% off\n",
           v0, v1, v0 - v1, rep.eroded - rep.deposited, rep.eroded, rep.deposited, 100 * rel);
    T_CHECK_MSG(rel <= 0.02, "volume off by %.2f%%", 100 * rel);
    memcpy(m->disp, d0, n * sizeof(float));
    free(d0);
}

/* ---- 7: resolution independence -------------------------------------------------------------- */

static float *analytic_field(int n)
{
    float *h = (float *)malloc((size_t)n * n * sizeof(float));
    int x, y;
    const double tau = 6.283185307179586;
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            double px = (x + 0.5) / n, py = (y + 0.5) / n; /* wavelengths 1/2 .. 1/16: >= 32 texels at 512 */
            h[(size_t)y * n + x] = (float)(0.02 * sin(tau * 2 * px) * cos(tau * 3 * py) + 0.006 * sin(tau * (8 * px + 5 * py)) +
                                          0.004 * cos(tau * 16 * py + 1.0));
        }
    return h;
}

static void test_resolution(void)
{
    float *a = analytic_field(512), *b = analytic_field(2048), *a0 = copy_floats(a, 512 * 512), *b0 = copy_floats(b, 2048 * 2048);
    ero_options o = ero_default_options();
    ero_grid ga = ero_heightfield_grid(512, 512, a, 1.0f / 512, 1), gb = ero_heightfield_grid(2048, 2048, b, 1.0f / 2048, 1);
    double se = 0.0, sc = 0.0, rel;
    int x, y, i, j;
    o.wind[0] = 1.0f; o.wind[1] = 0.3f; o.wind[2] = -1.0f;
    /* the change resolved at 512^2: sigma 2 texels, normals averaged over 4 */
    o.normal_radius = 4.0f / 512; o.filter_sigma = 2.0f / 512; o.rate = 2e-3f; o.curvature_length = 1.0f / 32;
    T_CHECK(ero_erode(&ga, NULL, NULL, 0, 10, &o, NULL, NULL) == ERO_OK);
    T_CHECK(ero_erode(&gb, NULL, NULL, 0, 10, &o, NULL, NULL) == ERO_OK);
    for (y = 0; y < 512; y++)
        for (x = 0; x < 512; x++) {
            double cb = 0.0, ca = (double)a[y * 512 + x] - a0[y * 512 + x];
            for (j = 0; j < 4; j++)
                for (i = 0; i < 4; i++) {
                    size_t k = (size_t)(4 * y + j) * 2048 + 4 * x + i;
                    cb += ((double)b[k] - b0[k]) / 16.0;
                }
            se += (ca - cb) * (ca - cb);
            sc += ca * ca;
        }
    rel = sqrt(se / sc);
    printf("  note: 512^2 vs 2048^2 (box-filtered): RMS difference %.3f%% of the 512^2 RMS change %.4g\n", 100 * rel,
           sqrt(sc / (512.0 * 512)));
    T_CHECK_MSG(rel <= 0.05, "resolution dependence %.2f%% > 5%%", 100 * rel);
    free(a); free(b); free(a0); free(b0);
}

/* ---- 8: tiling: erode then shift == shift then erode ------------------------------------------ */

static void test_tiling(void)
{
    enum { N = 128, SX = 37, SY = 11 };
    float *a = analytic_field(N), *b = (float *)malloc(N * N * sizeof(float)), *c = (float *)malloc(N * N * sizeof(float));
    ero_options o = ero_default_options();
    ero_grid ga = ero_heightfield_grid(N, N, a, 1.0f / N, 1), gb = ero_heightfield_grid(N, N, b, 1.0f / N, 1);
    int x, y;
    for (y = 0; y < N; y++)
        for (x = 0; x < N; x++) b[((y + SY) % N) * N + (x + SX) % N] = a[y * N + x];
    o.wind[0] = 1.0f; o.wind[1] = 0.3f; o.wind[2] = -1.0f;
    o.normal_radius = 3.0f / N; o.filter_sigma = 1.5f / N;
    T_CHECK(ero_erode(&ga, NULL, NULL, 0, 5, &o, NULL, NULL) == ERO_OK);
    T_CHECK(ero_erode(&gb, NULL, NULL, 0, 5, &o, NULL, NULL) == ERO_OK);
    for (y = 0; y < N; y++)
        for (x = 0; x < N; x++) c[((y + SY) % N) * N + (x + SX) % N] = a[y * N + x];
    T_CHECK_MSG(memcmp(b, c, N * N * sizeof(float)) == 0, "erode-then-shift differs from shift-then-erode");
    free(a); free(b); free(c);
}

/* ---- 9: resume and repeatability -------------------------------------------------------------- */

static int stop_after_3(void *user, float done)
{
    int *calls = (int *)user;
    (void)done;
    return ++*calls > 3;
}

static void test_resume(torus_map *t)
{
    dm_dispmap *m = t->map;
    size_t n = (size_t)m->width * m->height;
    float *d0 = copy_floats(m->disp, n), *once, *again;
    ero_grid g = torus_ero(t);
    ero_options o = torus_options();
    ero_report steps[10], total, part;
    double sum = 0.0;
    int calls = 0, k;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 10, &o, steps, &total) == ERO_OK);
    for (k = 0; k < 10; k++) sum += steps[k].eroded;
    T_NEAR(sum, total.eroded, 1e-12 * total.eroded);
    once = copy_floats(m->disp, n);
    memcpy(m->disp, d0, n * sizeof(float));
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 10, &o, NULL, NULL) == ERO_OK);
    T_CHECK_MSG(memcmp(once, m->disp, n * sizeof(float)) == 0, "two runs differ");
    memcpy(m->disp, d0, n * sizeof(float));
    o.progress = stop_after_3; o.user = &calls;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 10, &o, NULL, &part), ERO_CANCELLED);
    T_EQ_INT(part.steps, 3);
    o.progress = NULL;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 4, &o, NULL, NULL) == ERO_OK);
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 3, &o, NULL, NULL) == ERO_OK);
    again = m->disp;
    T_CHECK_MSG(memcmp(once, again, n * sizeof(float)) == 0, "stopped after 3, resumed 4 + 3: differs from 10 at once");
    memcpy(m->disp, d0, n * sizeof(float));
    free(d0); free(once);
}

/* ---- bad input and allocation failure --------------------------------------------------------- */

static void test_bad_input(torus_map *t)
{
    enum { N = 32 };
    float h[N * N], h0[N * N];
    uint8_t mat[N * N];
    ero_grid g = ero_heightfield_grid(N, N, h, 0.1f, 0), b;
    ero_options o = ero_default_options();
    ero_material bad = {4, 4, 0, 0}, ok = {1, 4, 0, 0}, fixed, odd = {1, 4, 9, 0.01f};
    dm_dispmap *m = t->map;
    size_t n = (size_t)m->width * m->height;
    float *d0 = copy_floats(m->disp, n), nk[3];
    uint32_t keep;
    int k, f;
    for (k = 0; k < N * N; k++) h[k] = h0[k] = 0.01f * (float)sin(k * 0.1);
    memset(mat, 0, sizeof mat);
    o.wind[2] = -1.0f;
    T_EQ_INT(ero_erode(NULL, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 0, &o, NULL, NULL), ERO_ERR_BAD_STEPS);
    b = g; b.spacing = 0.0f;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_SPACING);
    b.spacing = -1.0f;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_SPACING);
    b = g; b.width = 0;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_SIZE);
    b = g; b.width = 0x7fffffff; b.height = 0x7fffffff;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_TOO_LARGE);
    b = g; b.domain = 7;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    h[N * N - 1] = NAN;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_MAP);
    h[N * N - 1] = INFINITY;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_MAP);
    h[N * N - 1] = h0[N * N - 1];
    o.wind[2] = 0.0f;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_WIND);
    o.wind[2] = NAN;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_WIND);
    o.wind[2] = -1.0f;
    T_EQ_INT(ero_erode(&g, NULL, &bad, 1, 1, &o, NULL, NULL), ERO_ERR_BAD_MATERIAL);
    bad.eps_max = 2.0f;
    T_EQ_INT(ero_erode(&g, NULL, &bad, 1, 1, &o, NULL, NULL), ERO_ERR_BAD_MATERIAL);
    mat[5] = 1;
    T_EQ_INT(ero_erode(&g, mat, &ok, 1, 1, &o, NULL, NULL), ERO_ERR_BAD_MATERIAL);
    o.rate = -1.0f;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_PARAMETER);
    o.rate = 0.0f; o.filter_sigma = 1e6f;
    T_EQ_INT(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_PARAMETER);
    o.filter_sigma = 0.0f;
    T_CHECK(memcmp(h, h0, sizeof h) == 0);
    /* the paper's corrections: eps_medium clamped into [eps_min, eps_max], ambientW above its bound */
    f = ero_resolve_material(&odd, &fixed);
    T_EQ_INT(f, ERO_CORRECTED_MEDIUM | ERO_CORRECTED_AMBIENT);
    T_NEAR(fixed.eps_medium, 4.0, 0);
    T_CHECK(fixed.ambient > 1.0f / 3.0f);
    {
        ero_report rep;
        T_EQ_INT(ero_erode(&g, NULL, &odd, 1, 1, &o, NULL, &rep), ERO_OK);
        T_EQ_SIZE(rep.corrected, 1);
        memcpy(h, h0, sizeof h);
    }
    /* surface grid: a neighbour out of range, a rotation > 3, a NaN normal, a missing array */
    b = torus_ero(t);
    for (k = 0; !m->valid[k]; k++) {}
    keep = m->nbr[4 * k];
    ((uint32_t *)m->nbr)[4 * k] = (uint32_t)n;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_INDEX);
    ((uint32_t *)m->nbr)[4 * k] = keep;
    ((uint8_t *)m->nbr_rot)[4 * k] = 4;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_INDEX);
    ((uint8_t *)m->nbr_rot)[4 * k] = 0;
    memcpy(nk, m->nrm + 3 * k, sizeof nk);
    m->nrm[3 * k] = NAN;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_MAP);
    m->nrm[3 * k] = m->nrm[3 * k + 1] = m->nrm[3 * k + 2] = 0.0f;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_MAP);
    memcpy(m->nrm + 3 * k, nk, sizeof nk);
    b.nbr = NULL;
    T_EQ_INT(ero_erode(&b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    T_CHECK_MSG(memcmp(d0, m->disp, n * sizeof(float)) == 0, "a failed call changed the map");
    free(d0);
}

static void test_alloc_failure(torus_map *t)
{
    dm_dispmap *m = t->map;
    size_t n = (size_t)m->width * m->height;
    float *d0 = copy_floats(m->disp, n);
    fail_alloc fa = {0, 0, 0};
    ero_allocator al = {fa_alloc, fa_free, &fa};
    ero_grid g = torus_ero(t);
    ero_options o = torus_options();
    long calls, k;
    int all = 1;
    o.allocator = &al;
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 1, &o, NULL, NULL) == ERO_OK);
    calls = fa.calls;
    T_CHECK(calls >= 1 && fa.live == 0);
    memcpy(m->disp, d0, n * sizeof(float));
    for (k = 1; k <= calls; k++) {
        fa.calls = 0; fa.fail_at = k; fa.live = 0;
        all &= ero_erode(&g, NULL, NULL, 0, 2, &o, NULL, NULL) == ERO_ERR_OUT_OF_MEMORY;
        all &= fa.live == 0 && memcmp(d0, m->disp, n * sizeof(float)) == 0;
    }
    T_CHECK_MSG(all, "allocation failure: %ld calls failed in turn: not all reported, or leaked, or changed the map", calls);
    free(d0);
}

/* ---- a workspace reused across calls: the same bits as ero_erode ------------------------------ */

/* steps of ero_erode_ws on a reused workspace, split as `parts` says, equal ero_erode's one call */
static int ws_matches(ero_grid *g, const ero_options *o, int steps, const int *parts, int nparts)
{
    size_t n = (size_t)g->width * g->height;
    float *d0 = copy_floats(g->disp, n), *once;
    ero_report a[16], b[16], ta, tb;
    ero_workspace *ws = NULL;
    int k, done = 0, same;
    if (ero_erode(g, NULL, NULL, 0, steps, o, a, &ta) != ERO_OK) return 0;
    once = copy_floats(g->disp, n);
    memcpy(g->disp, d0, n * sizeof(float));
    same = ero_workspace_create(g, o, &ws) == ERO_OK;
    for (k = 0; k < 2 && same; k++) { /* twice: a used workspace gives the same bits as a new one */
        int p;
        for (p = 0, done = 0; p < nparts && same; done += parts[p++])
            same = ero_erode_ws(ws, g, NULL, NULL, 0, parts[p], o, b + done, &tb) == ERO_OK;
        same = same && done == steps && memcmp(once, g->disp, n * sizeof(float)) == 0;
        for (p = 0; p < steps && same; p++)
            same = memcmp(&a[p].eroded, &b[p].eroded, sizeof(double)) == 0 &&
                   memcmp(&a[p].deposited, &b[p].deposited, sizeof(double)) == 0 && a[p].max_change == b[p].max_change;
        memcpy(g->disp, d0, n * sizeof(float));
    }
    ero_workspace_destroy(ws);
    free(d0); free(once);
    return same;
}

static void test_workspace(torus_map *t)
{
    enum { N = 96 };
    dm_dispmap *m = t->map;
    size_t n = (size_t)m->width * m->height, k;
    float *d0 = copy_floats(m->disp, n), *h = analytic_field(N), *mid;
    uint8_t *valid = (uint8_t *)malloc(N * N), mat[N * N];
    ero_grid g = torus_ero(t), b, hg = ero_heightfield_grid(N, N, h, 1.0f / N, 1);
    ero_options o = torus_options(), p, ho = ero_default_options();
    ero_material hard = {3, 5, 0, 0};
    ero_workspace *ws = NULL;
    fail_alloc fa = {0, 0, 0};
    ero_allocator al = {fa_alloc, fa_free, &fa};
    const int split[3] = {4, 3, 3}, one[1] = {10}, hsplit[2] = {2, 3}, hone[1] = {5};
    long calls;
    int all = 1;
    T_CHECK_MSG(ws_matches(&g, &o, 10, one, 1), "torus: a workspace's 10 steps differ from ero_erode's");
    T_CHECK_MSG(ws_matches(&g, &o, 10, split, 3), "torus: 4 + 3 + 3 steps on a workspace differ from 10 at once");
    ho.wind[0] = 1.0f; ho.wind[1] = 0.3f; ho.wind[2] = -1.0f;
    ho.normal_radius = 3.0f / N; ho.filter_sigma = 1.5f / N;
    T_CHECK_MSG(ws_matches(&hg, &ho, 5, hone, 1) && ws_matches(&hg, &ho, 5, hsplit, 2),
                "wrapped height field: a workspace differs from ero_erode");
    hg.wrap = 0;
    T_CHECK_MSG(ws_matches(&hg, &ho, 5, hsplit, 2), "height field: a workspace differs from ero_erode");
    for (k = 0; k < N * N; k++) valid[k] = (k % N - 40.0) * (k % N - 40.0) + (k / N - 50.0) * (k / N - 50.0) < 35.0 * 35.0;
    hg.valid = valid;
    T_CHECK_MSG(ws_matches(&hg, &ho, 5, hsplit, 2), "height field with a valid map: a workspace differs from ero_erode");
    /* what may change between calls: the wind, the rate, the materials */
    T_CHECK(ero_workspace_create(&g, &o, &ws) == ERO_OK && ws);
    p = o; p.wind[0] = -o.wind[1]; p.wind[1] = o.wind[0]; p.rate = 0.5f * o.rate;
    memset(mat, 0, sizeof mat);
    T_CHECK(ero_erode(&g, NULL, NULL, 0, 2, &o, NULL, NULL) == ERO_OK && ero_erode(&g, NULL, &hard, 1, 2, &p, NULL, NULL) == ERO_OK);
    mid = copy_floats(m->disp, n);
    memcpy(m->disp, d0, n * sizeof(float));
    T_CHECK(ero_erode_ws(ws, &g, NULL, NULL, 0, 2, &o, NULL, NULL) == ERO_OK &&
            ero_erode_ws(ws, &g, NULL, &hard, 1, 2, &p, NULL, NULL) == ERO_OK);
    T_CHECK_MSG(memcmp(mid, m->disp, n * sizeof(float)) == 0, "a workspace with the wind changed between calls differs");
    memcpy(m->disp, d0, n * sizeof(float));
    /* what may not: another grid, other kernels; and the per-call checks, the map untouched */
    T_EQ_INT(ero_erode_ws(NULL, &g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    T_EQ_INT(ero_erode_ws(ws, NULL, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    b = g; b.nbr = NULL;
    T_EQ_INT(ero_erode_ws(ws, &b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    b = g; b.height = g.height - 1;
    T_EQ_INT(ero_erode_ws(ws, &b, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    T_EQ_INT(ero_erode_ws(ws, &hg, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_INVALID_ARGUMENT);
    p = o; p.filter_sigma = 1.5f * (o.filter_sigma > 0 ? o.filter_sigma : 0.01f);
    T_EQ_INT(ero_erode_ws(ws, &g, NULL, NULL, 0, 1, &p, NULL, NULL), ERO_ERR_BAD_PARAMETER);
    p = o; p.flags ^= ERO_KEEP_INVALID;
    T_EQ_INT(ero_erode_ws(ws, &g, NULL, NULL, 0, 1, &p, NULL, NULL), ERO_ERR_BAD_PARAMETER);
    p = o; p.wind[0] = p.wind[1] = p.wind[2] = 0.0f;
    T_EQ_INT(ero_erode_ws(ws, &g, NULL, NULL, 0, 1, &p, NULL, NULL), ERO_ERR_BAD_WIND);
    T_EQ_INT(ero_erode_ws(ws, &g, NULL, NULL, 0, 0, &o, NULL, NULL), ERO_ERR_BAD_STEPS);
    hard.eps_min = 6.0f;
    T_EQ_INT(ero_erode_ws(ws, &g, NULL, &hard, 1, 1, &o, NULL, NULL), ERO_ERR_BAD_MATERIAL);
    m->disp[n / 2] = NAN;
    T_EQ_INT(ero_erode_ws(ws, &g, NULL, NULL, 0, 1, &o, NULL, NULL), ERO_ERR_BAD_MAP);
    m->disp[n / 2] = d0[n / 2];
    T_CHECK_MSG(memcmp(d0, m->disp, n * sizeof(float)) == 0, "a failed workspace call changed the map");
    ero_workspace_destroy(ws);
    ero_workspace_destroy(NULL);
    T_EQ_INT(ero_workspace_create(&g, &o, NULL), ERO_ERR_INVALID_ARGUMENT);
    b = g; b.nbr = NULL; ws = (ero_workspace *)&b; /* not NULL: the call sets it */
    T_EQ_INT(ero_workspace_create(&b, &o, &ws), ERO_ERR_INVALID_ARGUMENT);
    T_CHECK(ws == NULL);
    /* allocation failure: every allocation of the workspace in turn; a call allocates nothing */
    o.allocator = &al;
    T_CHECK(ero_workspace_create(&g, &o, &ws) == ERO_OK);
    calls = fa.calls;
    T_CHECK(ero_erode_ws(ws, &g, NULL, NULL, 0, 2, &o, NULL, NULL) == ERO_OK);
    T_CHECK_MSG(fa.calls == calls, "ero_erode_ws allocated %ld blocks", fa.calls - calls);
    ero_workspace_destroy(ws);
    T_CHECK(calls >= 2 && fa.live == 0);
    memcpy(m->disp, d0, n * sizeof(float));
    for (k = 1; k <= (size_t)calls; k++) {
        fa.calls = 0; fa.fail_at = (long)k; fa.live = 0;
        ws = NULL;
        all &= ero_workspace_create(&g, &o, &ws) == ERO_ERR_OUT_OF_MEMORY && ws == NULL && fa.live == 0;
    }
    T_CHECK_MSG(all, "workspace allocation failure: %ld calls failed in turn: not all reported, or leaked", calls);
    T_CHECK(memcmp(d0, m->disp, n * sizeof(float)) == 0);
    free(d0); free(h); free(valid); free(mid);
}

/* ---- Figs 5.2.2 and 5.2.3: cylinders with reliefs ---------------------------------------------- */

/* a cylinder of radius 0.5 and height 1.2 as a surface grid (u around, wrapping; v along the axis)
   whose base encloses the reliefs: disp = 0.06 - relief */
typedef struct cyl_grid {
    int w, h;
    float *pos, *nrm, *disp, *area;
    uint32_t *nbr;
    uint8_t *rot, *mat;
} cyl_grid;

static const char *const cyl_font[7] = { /* "CGGM", 5 x 7 letters, a column between */
    ".###.. .###.. .###.. #...#", "#...#. #...#. #...#. ##.##", "#..... #..... #..... #.#.#",
    "#..... #.###. #.###. #.#.#", "#..... #...#. #...#. #...#", "#...#. #...#. #...#. #...#",
    ".###.. .###.. .###.. #...#"};

/* the letter (0..3) whose stroke covers arc length s from the text's centre (which faces -x) and
   height z, or -1; cells of 0.05 */
static int cyl_letter(double s, double z)
{
    int col = (int)floor((s + 0.575) / 0.05), row = (int)floor((0.175 - z) / 0.05);
    if (col < 0 || col >= 23 || row < 0 || row >= 7 || cyl_font[row][col + col / 6] != '#') return -1;
    return col / 6;
}

static void make_cylinder(cyl_grid *c, int w, int letters)
{
    int x, y, h = (int)(w * 1.2 / 3.14159265 + 0.5);
    size_t n = (size_t)w * h, i;
    c->w = w; c->h = h;
    c->pos = (float *)malloc(3 * n * sizeof(float)); c->nrm = (float *)malloc(3 * n * sizeof(float));
    c->disp = (float *)malloc(n * sizeof(float)); c->area = (float *)malloc(n * sizeof(float));
    c->nbr = (uint32_t *)malloc(4 * n * sizeof(uint32_t)); c->rot = (uint8_t *)calloc(4 * n, 1);
    c->mat = (uint8_t *)calloc(n, 1);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            double th = 6.283185307 * (x + 0.5) / w, z = -0.6 + 1.2 * (y + 0.5) / h, relief = 0.0;
            i = (size_t)y * w + x;
            if (letters) {
                int l = cyl_letter(0.5 * (th - 3.14159265), z);
                if (l >= 0) relief = 0.04;
                if (l >= 0 && l < 2) c->mat[i] = 1; /* C, G hard */
            } else { /* bosses, 12 around by 3 along */
                int b, j;
                for (b = 0; b < 12; b++)
                    for (j = -1; j <= 1; j++) {
                        double dth = th - 6.283185307 * (b + 0.5) / 12, ds, dz = z - 0.35 * j, q;
                        dth -= 6.283185307 * floor(dth / 6.283185307 + 0.5);
                        ds = 0.5 * dth;
                        q = (ds * ds + dz * dz) / (0.11 * 0.11);
                        if (q < 1 && 0.045 * (1 - q) * (1 - q) > relief) relief = 0.045 * (1 - q) * (1 - q);
                    }
            }
            c->pos[3 * i] = (float)(0.5 * cos(th)); c->pos[3 * i + 1] = (float)(0.5 * sin(th)); c->pos[3 * i + 2] = (float)z;
            c->nrm[3 * i] = (float)cos(th); c->nrm[3 * i + 1] = (float)sin(th); c->nrm[3 * i + 2] = 0.0f;
            c->disp[i] = (float)(0.06 - relief);
            c->area[i] = (float)((3.14159265 / w) * (1.2 / h));
            c->nbr[4 * i + 0] = (uint32_t)(y * w + (x + 1) % w);
            c->nbr[4 * i + 1] = (uint32_t)(y * w + (x + w - 1) % w);
            c->nbr[4 * i + 2] = y + 1 < h ? (uint32_t)((y + 1) * w + x) : UINT32_MAX;
            c->nbr[4 * i + 3] = y > 0 ? (uint32_t)((y - 1) * w + x) : UINT32_MAX;
        }
}

static void cyl_free(cyl_grid *c)
{
    free(c->pos); free(c->nrm); free(c->disp); free(c->area); free(c->nbr); free(c->rot); free(c->mat);
}

/* the wind blows toward +x: windward texels face -x */
static ero_result cyl_erode(cyl_grid *c, const ero_material *mats, size_t count, int steps)
{
    ero_grid g = ero_surface_grid(c->w, c->h, c->pos, c->nrm, c->disp, c->area, NULL, c->nbr, c->rot);
    ero_options o = ero_default_options();
    o.wind[0] = 1.0f;
    o.rate = 0.006f;
    return ero_erode(&g, count ? c->mat : NULL, mats, count, steps, &o, NULL, NULL);
}

static void test_cylinder_reliefs(void)
{
    cyl_grid c;
    float *d0;
    size_t n, i;
    double wind = 0, lee = 0;
    long nw = 0, nl = 0;
    make_cylinder(&c, 128, 0);
    n = (size_t)c.w * c.h;
    d0 = copy_floats(c.disp, n);
    T_CHECK(cyl_erode(&c, NULL, 0, 10) == ERO_OK);
    for (i = 0; i < n; i++) { /* the wear (disp grows inward) on each side, away from the open ends */
        size_t y = i / (size_t)c.w;
        if (y < 4 || y + 4 >= (size_t)c.h) continue;
        if (c.nrm[3 * i] < -0.2f) { wind += c.disp[i] - d0[i]; nw++; }
        else if (c.nrm[3 * i] > 0.2f) { lee += c.disp[i] - d0[i]; nl++; }
    }
    wind /= (double)nw; lee /= (double)nl;
    printf("  note: Fig 5.2.2 cylinder with bosses, 10 steps: mean wear windward %.4g, leeward %.4g (x%.2f)\n", wind, lee, wind / lee);
    T_CHECK_MSG(wind > 1.5 * lee && lee > 0, "windward wear %g not above 1.5 x leeward %g", wind, lee);
    free(d0);
    cyl_free(&c);
}

static void test_cylinder_letters(void)
{
    cyl_grid c;
    float *d0;
    size_t n;
    int x, y;
    double loss[2] = {0, 0};
    long cnt[2] = {0, 0};
    ero_material mats[2] = {{1, 4, 0, 0}, {4, 16, 0, 0}}; /* soft, hard */
    make_cylinder(&c, 192, 1);
    n = (size_t)c.w * c.h;
    d0 = copy_floats(c.disp, n);
    T_CHECK(cyl_erode(&c, mats, 2, 10) == ERO_OK);
    for (y = 0; y < c.h; y++)
        for (x = 0; x < c.w; x++) {
            size_t i = (size_t)y * c.w + x;
            double th = 6.283185307 * (x + 0.5) / c.w, z = -0.6 + 1.2 * (y + 0.5) / c.h;
            int l = cyl_letter(0.5 * (th - 3.14159265), z);
            if (l < 0) continue;
            loss[l < 2] += c.disp[i] - d0[i]; /* [1]: C, G (hard); [0]: G, M (soft) */
            cnt[l < 2]++;
        }
    loss[0] /= (double)cnt[0]; loss[1] /= (double)cnt[1];
    printf("  note: Fig 5.2.3 letters CGGM, 10 steps: mean loss of hard CG %.4g, soft GM %.4g\n", loss[1], loss[0]);
    T_CHECK_MSG(loss[1] < 0.5 * loss[0] && loss[1] > 0, "hard letters lost %g, soft %g", loss[1], loss[0]);
    free(d0);
    cyl_free(&c);
}

/* ---- --digest: the bits of varied runs ------------------------------------------------------ */

static uint64_t fnv_bytes(const void *p, size_t n, uint64_t h)
{
    const unsigned char *c = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; i++) { h ^= c[i]; h *= 1099511628211ull; }
    return h;
}

static int print_digest(void)
{
    static const ero_material mats[3] = {{1, 4, 0, 0}, {2, 5, 3, 0.5f}, {0.5f, 8, 0, 0}};
    uint64_t hash = 1469598103934665603ull;
    int cfg;
    for (cfg = 0; cfg < 10; cfg++) {
        int W = cfg < 4 ? 256 : 133 + 17 * cfg, H = cfg < 4 ? 256 : 61 + 9 * cfg, wrap = cfg & 1, k;
        size_t n = (size_t)W * H, i;
        float *h = analytic_field(W > H ? W : H);
        uint8_t *mat = (uint8_t *)malloc(n), *valid = (uint8_t *)malloc(n);
        ero_grid g;
        ero_options o = ero_default_options();
        ero_report per[3], total;
        ero_result e;
        for (i = 0; i < n; i++) {
            h[i] += (i * 2654435761u >> 27) % 7 == 0 ? 0.01f : 0.0f; /* texel-scale bumps */
            mat[i] = (uint8_t)((i * 2654435761u >> 28) % 3);
            valid[i] = (i * 40503u >> 9) % 11 != 0;
        }
        g = ero_heightfield_grid(W, H, h, 1.0f / (float)W, wrap);
        if (cfg == 8) g.valid = valid; /* the walk */
        o.wind[0] = 1.0f; o.wind[1] = 0.3f; o.wind[2] = -1.0f;
        if (cfg % 3 == 0) { o.normal_radius = 2.0f / (float)W; o.filter_sigma = 1.0f / (float)W; }
        if (cfg == 2) o.flags = ERO_CONSTANT_WINDWARD;
        if (cfg == 5) { o.bound = ERO_BOUND_VALUE; o.bound_value = 0.015f; o.flags = ERO_LEEWARD_LITERAL; }
        if (cfg == 7) { o.deposit_ratio = -1.0f; o.normal_radius = 3.7f / (float)W; o.filter_sigma = 2.3f / (float)W; o.force = 1.7f; }
        if (cfg == 9) { o.normal_radius = 0.4f / (float)W; o.filter_sigma = 0.5f / (float)W; o.wind[2] = 1.0f; }
        e = ero_erode(&g, (cfg & 2) ? mat : NULL, mats, (cfg & 2) ? 3 : 1, 3, &o, per, &total);
        hash = fnv_bytes(&e, sizeof e, hash);
        hash = fnv_bytes(h, n * sizeof(float), hash);
        for (k = 0; k < 3; k++) {
            hash = fnv_bytes(&per[k].eroded, sizeof per[k].eroded, hash);
            hash = fnv_bytes(&per[k].deposited, sizeof per[k].deposited, hash);
            hash = fnv_bytes(&per[k].max_change, sizeof per[k].max_change, hash);
        }
        free(h); free(mat); free(valid);
    }
    printf("digest %016llx\n", (unsigned long long)hash);
    return 0;
}

int main(int argc, char **argv)
{
    torus_map t;
    if (argc > 1 && strcmp(argv[1], "--digest") == 0) return print_digest();
    T_BEGIN(argc, argv);
    test_flat_patches();
    test_pit_ridge();
    test_bound();
    test_materials();
    test_tiling();
    test_cylinder_reliefs();
    test_cylinder_letters();
    if (T_CHECK(make_torus_map(&t, 256))) {
        test_torus(&t);
        test_resume(&t);
        test_bad_input(&t);
        test_alloc_failure(&t);
        test_workspace(&t);
    }
    torus_free(&t);
    test_resolution();
    return T_END();
}
