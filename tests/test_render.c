/* test_render.c - tests for examples/render.h: coverage (watertightness, fill rule), near-plane
   clipping, depth, perspective-correct interpolation, volume vs mesh silhouettes, relief mapping
   against analytic intersections, PNG round trip through independent decoders, determinism.
   test_render --png-msd FILE prints a PNG's adjacent-pixel statistic for tests/terrain_cli.sh. */
#define _POSIX_C_SOURCE 200809L
#define SR_IMPLEMENTATION
#include "render.h"
#include "test.h"

#include <stdlib.h>
#include <unistd.h>

static int g_small; /* TEST_SANITIZE: smaller images */

/* ---- helpers ------------------------------------------------------------------------------ */

static uint32_t lcg(uint32_t *s) { *s = *s * 1664525u + 1013904223u; return *s >> 8; }
static float frand(uint32_t *s) { return (float)(lcg(s) & 0xFFFFFF) / 16777216.0f; }

typedef struct mesh { float *p; uint32_t *i; size_t nv, nt; } mesh;

/* closed UV sphere (convex): poles + rings x segs */
static mesh uv_sphere(int rings, int segs, float r)
{
    mesh m;
    int a, b;
    size_t v = 0, t = 0;
    m.nv = (size_t)(rings - 1) * (size_t)segs + 2;
    m.nt = 2 * (size_t)segs * (size_t)(rings - 1);
    m.p = (float *)malloc(m.nv * 3 * sizeof(float));
    m.i = (uint32_t *)malloc(m.nt * 3 * sizeof(uint32_t));
    m.p[v * 3] = 0; m.p[v * 3 + 1] = r; m.p[v * 3 + 2] = 0; v++;
    for (a = 1; a < rings; a++)
        for (b = 0; b < segs; b++) {
            double th = 3.14159265358979 * a / rings, ph = 2 * 3.14159265358979 * b / segs;
            m.p[v * 3] = (float)(r * sin(th) * cos(ph));
            m.p[v * 3 + 1] = (float)(r * cos(th));
            m.p[v * 3 + 2] = (float)(-r * sin(th) * sin(ph));
            v++;
        }
    m.p[v * 3] = 0; m.p[v * 3 + 1] = -r; m.p[v * 3 + 2] = 0; v++;
#define RV(a, b) ((uint32_t)(1 + ((a) - 1) * segs + ((b) % segs)))
    for (b = 0; b < segs; b++) { /* counter-clockwise from outside */
        m.i[t * 3] = 0; m.i[t * 3 + 1] = RV(1, b); m.i[t * 3 + 2] = RV(1, b + 1); t++;
    }
    for (a = 1; a < rings - 1; a++)
        for (b = 0; b < segs; b++) {
            m.i[t * 3] = RV(a, b); m.i[t * 3 + 1] = RV(a + 1, b); m.i[t * 3 + 2] = RV(a + 1, b + 1); t++;
            m.i[t * 3] = RV(a, b); m.i[t * 3 + 1] = RV(a + 1, b + 1); m.i[t * 3 + 2] = RV(a, b + 1); t++;
        }
    for (b = 0; b < segs; b++) {
        m.i[t * 3] = (uint32_t)(v - 1); m.i[t * 3 + 1] = RV(rings - 1, b + 1); m.i[t * 3 + 2] = RV(rings - 1, b); t++;
    }
#undef RV
    m.nt = t;
    return m;
}

/* closed torus (not convex) */
static mesh torus(int nu, int nv, float R, float r)
{
    mesh m;
    int a, b;
    size_t t = 0;
    m.nv = (size_t)nu * (size_t)nv;
    m.nt = 2 * m.nv;
    m.p = (float *)malloc(m.nv * 3 * sizeof(float));
    m.i = (uint32_t *)malloc(m.nt * 3 * sizeof(uint32_t));
    for (a = 0; a < nu; a++)
        for (b = 0; b < nv; b++) {
            double u = 2 * 3.14159265358979 * a / nu, w = 2 * 3.14159265358979 * b / nv;
            float *p = m.p + 3 * ((size_t)a * (size_t)nv + (size_t)b);
            p[0] = (float)((R + r * cos(w)) * cos(u));
            p[1] = (float)(r * sin(w));
            p[2] = (float)((R + r * cos(w)) * sin(u));
        }
    for (a = 0; a < nu; a++)
        for (b = 0; b < nv; b++) {
            uint32_t i00 = (uint32_t)(a * nv + b), i10 = (uint32_t)(((a + 1) % nu) * nv + b);
            uint32_t i01 = (uint32_t)(a * nv + (b + 1) % nv), i11 = (uint32_t)(((a + 1) % nu) * nv + (b + 1) % nv);
            m.i[t * 3] = i00; m.i[t * 3 + 1] = i01; m.i[t * 3 + 2] = i11; t++;
            m.i[t * 3] = i00; m.i[t * 3 + 1] = i11; m.i[t * 3 + 2] = i10; t++;
        }
    return m;
}

static void mesh_free(mesh *m) { free(m->p); free(m->i); }

static void rot_model(float m[16], float ax, float ay, float tx, float ty, float tz)
{
    float ca = cosf(ax), sa = sinf(ax), cb = cosf(ay), sb = sinf(ay);
    /* R = Ry(ay) * Rx(ax), column-major */
    m[0] = cb; m[1] = 0; m[2] = -sb; m[3] = 0;
    m[4] = sb * sa; m[5] = ca; m[6] = cb * sa; m[7] = 0;
    m[8] = sb * ca; m[9] = -sa; m[10] = cb * ca; m[11] = 0;
    m[12] = tx; m[13] = ty; m[14] = tz; m[15] = 1;
}

static void count_draw(sr_framebuffer *fb, const sr_camera *cam, const mesh *m, const float *model)
{
    sr_draw_desc d;
    float zero[4] = {0, 0, 0, 0};
    sr_framebuffer_clear(fb, zero, 1.0f);
    sr_draw_desc_default(&d);
    d.positions = m->p; d.vertex_count = m->nv; d.indices = m->i; d.triangle_count = m->nt;
    d.shading = SR_SHADE_COUNT;
    d.model = model;
    sr_draw_mesh(fb, cam, &d);
}

/* ---- coverage: watertight closed meshes ----------------------------------------------------- */

static void test_closed_coverage(void)
{
    int W = g_small ? 96 : 200, k;
    sr_framebuffer fb;
    sr_camera cam;
    float eye[3] = {0, 0, 4}, at[3] = {0, 0, 0};
    mesh sph = uv_sphere(24, 37, 1.0f), tor = torus(41, 23, 0.9f, 0.35f);
    uint32_t seed = 7;
    T_EQ_INT(sr_framebuffer_create(&fb, W, W * 3 / 4, NULL), SR_OK);
    for (k = 0; k < 12; k++) {
        float model[16];
        size_t i, n = (size_t)fb.width * (size_t)fb.height, bad_convex = 0, bad_closed = 0, covered = 0;
        if (k % 2) sr_camera_look_at(&cam, eye, at, NULL, 40.0f + 3.0f * (float)k, 4.0f / 3.0f, 0.1f, 50.0f);
        else sr_camera_ortho(&cam, eye, at, NULL, 1.3f, 4.0f / 3.0f, 0.1f, 50.0f);
        rot_model(model, 6.28f * frand(&seed), 6.28f * frand(&seed), 0.3f * frand(&seed), 0.2f * frand(&seed), 0.0f);
        count_draw(&fb, &cam, &sph, model);
        for (i = 0; i < n; i++) {
            float f = fb.color[4 * i], b = fb.color[4 * i + 1];
            if (!((f == 0 && b == 0) || (f == 1 && b == 1))) bad_convex++;
            if (f > 0) covered++;
        }
        T_CHECK_MSG(bad_convex == 0 && covered > n / 25, "view %d: %zu pixels of the convex sphere not (0,0)/(1,1), covered %zu", k, bad_convex, covered);
        count_draw(&fb, &cam, &tor, model);
        covered = 0;
        for (i = 0; i < n; i++) {
            if (fb.color[4 * i] != fb.color[4 * i + 1]) bad_closed++;
            if (fb.color[4 * i] > 0) covered++;
        }
        T_CHECK_MSG(bad_closed == 0 && covered > 0, "view %d: %zu torus pixels with front != back (covered twice+: %zu)", k, bad_closed, covered);
    }
    sr_framebuffer_free(&fb);
    mesh_free(&sph);
    mesh_free(&tor);
}

/* ---- coverage: quads split along either diagonal ------------------------------------------- */

static void test_quad_diagonals(void)
{
    int W = 48, q, bad_quads = 0, double_hits = 0, any = 0;
    sr_framebuffer fa, fbb;
    sr_camera cam;
    float eye[3] = {0, 0, 5}, at[3] = {0, 0, 0};
    uint32_t seed = 12345, ia[6] = {0, 1, 2, 0, 2, 3}, ib[6] = {0, 1, 3, 1, 2, 3};
    sr_framebuffer_create(&fa, W, W, NULL);
    sr_framebuffer_create(&fbb, W, W, NULL);
    sr_camera_ortho(&cam, eye, at, NULL, 1.0f, 1.0f, 0.1f, 10.0f);
    for (q = 0; q < 400; q++) {
        float p[12];
        int k;
        size_t i, n = (size_t)W * W;
        mesh m;
        /* convex quad: 4 points on a jittered ellipse, in order; the first 50 snapped to pixel
           centres/edges so that edges run exactly through sample points */
        float cx = frand(&seed) - 0.5f, cy = frand(&seed) - 0.5f, a0 = 6.28f * frand(&seed);
        for (k = 0; k < 4; k++) {
            float ang = a0 + 1.5708f * (float)k + 0.6f * (frand(&seed) - 0.5f), rr = 0.1f + 0.5f * frand(&seed);
            p[3 * k] = cx + rr * cosf(ang);
            p[3 * k + 1] = cy + rr * sinf(ang);
            p[3 * k + 2] = 0.3f * (frand(&seed) - 0.5f);
            if (q < 50) { /* multiples of half a pixel */
                p[3 * k] = floorf(p[3 * k] * W) / W;
                p[3 * k + 1] = floorf(p[3 * k + 1] * W) / W;
            }
        }
        m.p = p; m.nv = 4; m.nt = 2;
        m.i = ia; count_draw(&fa, &cam, &m, NULL);
        m.i = ib; count_draw(&fbb, &cam, &m, NULL);
        for (i = 0; i < n; i++) {
            float ca = fa.color[4 * i] + fa.color[4 * i + 1], cb = fbb.color[4 * i] + fbb.color[4 * i + 1];
            if (ca != cb) { bad_quads++; break; }
            if (ca > 1 || cb > 1) double_hits++;
            if (ca > 0) any++;
        }
    }
    T_CHECK_MSG(bad_quads == 0, "%d of 400 quads cover different pixels split along the two diagonals", bad_quads);
    T_CHECK_MSG(double_hits == 0, "%d pixels hit twice by the two triangles of a quad", double_hits);
    T_CHECK(any > 1000);
    sr_framebuffer_free(&fa);
    sr_framebuffer_free(&fbb);
}

/* ---- ray/triangle (analytic reference) ------------------------------------------------------ */

static int ray_tri(const float o[3], const float d[3], const float *a, const float *b, const float *c, float *t_out)
{
    float e1[3], e2[3], pv[3], tv[3], qv[3], det, u, v, t;
    int k;
    for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; tv[k] = o[k] - a[k]; }
    pv[0] = d[1] * e2[2] - d[2] * e2[1]; pv[1] = d[2] * e2[0] - d[0] * e2[2]; pv[2] = d[0] * e2[1] - d[1] * e2[0];
    det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    if (fabsf(det) < 1e-12f) return 0;
    u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
    qv[0] = tv[1] * e1[2] - tv[2] * e1[1]; qv[1] = tv[2] * e1[0] - tv[0] * e1[2]; qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
    v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
    t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
    if (u < 0 || v < 0 || u + v > 1 || t <= 0) return 0;
    *t_out = t;
    return 1;
}

/* ---- near-plane clipping -------------------------------------------------------------------- */

static void test_near_clip(void)
{
    int W = g_small ? 80 : 160, H = W, x, y, mismatch = 0, covered = 0, depth_bad = 0;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    float eye[3] = {0.2f, 0.5f, 0}, at[3] = {0, 0.2f, -5};
    /* a ground triangle y = 0 that passes under and behind the camera */
    float p[9] = {-3, 0, 2, 4, 0, 1, 0.5f, 0, -20};
    uint32_t idx[3] = {0, 1, 2};
    float behind[9] = {-1, 0, 3, 1, 0, 3, 0, 1, 4};
    sr_framebuffer_create(&fb, W, H, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 70.0f, 1.0f, 0.5f, 100.0f);
    sr_draw_desc_default(&d);
    d.positions = p; d.vertex_count = 3; d.indices = idx; d.triangle_count = 1;
    d.shading = SR_SHADE_UNLIT;
    T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_OK);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            float o[3], dir[3], t, P[3], z;
            size_t i = (size_t)y * W + (size_t)x;
            int hit, drawn = fb.depth[i] < 1.0f, k;
            sr_camera_ray(&cam, W, H, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            hit = ray_tri(o, dir, p, p + 3, p + 6, &t);
            if (hit) {
                for (k = 0; k < 3; k++) P[k] = o[k] + t * dir[k];
                hit = sr_camera_depth(&cam, P, &z) && z >= 0.0f && z <= 1.0f;
                if (hit && drawn && fabsf(z - fb.depth[i]) > 1e-4f) depth_bad++;
            }
            if (hit != drawn) mismatch++;
            covered += drawn;
        }
    T_CHECK_MSG(mismatch <= 2, "%d pixels differ from the analytic coverage of the clipped triangle", mismatch);
    T_CHECK_MSG(depth_bad == 0, "%d pixels with wrong depth", depth_bad);
    T_CHECK(covered > W * H / 5);
    /* far outside the guard band on the sides: clipped against the guard planes, same coverage */
    {
        float big[9] = {-4000, -1, -6, 3000, -2, -9, 10, 5000, -7};
        mismatch = 0;
        covered = 0;
        sr_framebuffer_clear(&fb, NULL, 1.0f);
        d.positions = big;
        sr_draw_mesh(&fb, &cam, &d);
        for (y = 0; y < H; y++)
            for (x = 0; x < W; x++) {
                float o[3], dir[3], t;
                size_t i = (size_t)y * W + (size_t)x;
                int drawn = fb.depth[i] < 1.0f;
                sr_camera_ray(&cam, W, H, (float)x + 0.5f, (float)y + 0.5f, o, dir);
                if (ray_tri(o, dir, big, big + 3, big + 6, &t) != drawn) mismatch++;
                covered += drawn;
            }
        T_CHECK_MSG(mismatch <= 2 && covered > W * H / 4, "guard band: %d pixels differ, %d covered", mismatch, covered);
    }
    /* entirely behind the eye: nothing */
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    d.positions = behind;
    sr_draw_mesh(&fb, &cam, &d);
    covered = 0;
    for (x = 0; x < W * H; x++) covered += fb.depth[x] < 1.0f;
    T_EQ_INT(covered, 0);
    sr_framebuffer_free(&fb);
}

/* ---- interpenetrating triangles ------------------------------------------------------------- */

static void test_interpenetration(void)
{
    int W = g_small ? 64 : 128, x, y, wrong = 0, seen[2] = {0, 0};
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    float eye[3] = {0.3f, 0.4f, 3}, at[3] = {0, 0, 0};
    float p[18] = {-1, -1, -0.6f, 1, -1, 0.6f, 0, 1, 0, /* tilted one way */
                   -1, -0.8f, 0.5f, 1, -0.7f, -0.5f, 0.1f, 1, 0.1f};
    float col[18] = {1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
    uint32_t idx[6] = {0, 1, 2, 3, 4, 5};
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 50.0f, 1.0f, 0.5f, 10.0f);
    sr_draw_desc_default(&d);
    d.positions = p; d.vertex_count = 6; d.indices = idx; d.triangle_count = 2;
    d.colors = col; d.shading = SR_SHADE_UNLIT;
    sr_draw_mesh(&fb, &cam, &d);
    for (y = 0; y < W; y++)
        for (x = 0; x < W; x++) {
            float o[3], dir[3], t0, t1;
            size_t i = (size_t)y * W + (size_t)x;
            int h0, h1, expect;
            sr_camera_ray(&cam, W, W, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            h0 = ray_tri(o, dir, p, p + 3, p + 6, &t0);
            h1 = ray_tri(o, dir, p + 9, p + 12, p + 15, &t1);
            if (!(h0 && h1)) continue;
            if (fabsf(t0 - t1) < 2e-3f) continue; /* on the intersection line */
            expect = t0 < t1 ? 0 : 1;
            seen[expect]++;
            if (!(fb.color[4 * i + (expect == 0 ? 0 : 1)] > 0.5f)) wrong++;
        }
    T_CHECK_MSG(wrong == 0, "%d pixels show the farther triangle", wrong);
    T_CHECK(seen[0] > 50 && seen[1] > 50);
    sr_framebuffer_free(&fb);
}

/* ---- perspective-correct interpolation: checkerboard ---------------------------------------- */

static void checker_frag(void *user, const sr_fragment *f, float rgb[3])
{
    int c = ((int)floorf(f->uv[0]) + (int)floorf(f->uv[1])) & 1;
    (void)user;
    rgb[0] = rgb[1] = rgb[2] = (float)c;
}

static int checker_at(const sr_camera *cam, int W, int H, float x, float y)
{
    float o[3], dir[3], t;
    sr_camera_ray(cam, W, H, x, y, o, dir);
    if (dir[1] >= 0) return -1;
    t = (0 - o[1]) / dir[1]; /* plane y = 0; u = x, v = -z scaled by 1 (uv = world units) */
    {
        float px = o[0] + t * dir[0], pz = o[2] + t * dir[2];
        if (px < -8 || px > 8 || pz < -40 || pz > 0) return -1;
        return ((int)floorf(px + 8) + (int)floorf(-pz)) & 1;
    }
}

static void test_checkerboard(void)
{
    int W = g_small ? 128 : 256, x, y, differ = 0, far_from_edge = 0, covered = 0;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    float eye[3] = {0.37f, 1.5f, 1.0f}, at[3] = {0, 0, -6};
    float p[12] = {-8, 0, 0, 8, 0, 0, 8, 0, -40, -8, 0, -40};
    float uv[8] = {0, 0, 16, 0, 16, 40, 0, 40};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 60.0f, 1.0f, 0.1f, 100.0f);
    sr_draw_desc_default(&d);
    d.positions = p; d.vertex_count = 4; d.indices = idx; d.triangle_count = 2;
    d.uvs = uv; d.fragment = checker_frag;
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    sr_draw_mesh(&fb, &cam, &d);
    for (y = 0; y < W; y++)
        for (x = 0; x < W; x++) {
            size_t i = (size_t)y * W + (size_t)x;
            int expect = checker_at(&cam, W, W, (float)x + 0.5f, (float)y + 0.5f), got;
            if (expect < 0 || fb.depth[i] >= 1.0f) continue;
            covered++;
            got = fb.color[4 * i] > 0.5f;
            if (got != expect) {
                int dx, dy, other = 0;
                differ++;
                for (dy = -1; dy <= 1; dy++)
                    for (dx = -1; dx <= 1; dx++)
                        if (checker_at(&cam, W, W, (float)(x + dx) + 0.5f, (float)(y + dy) + 0.5f) == got) other = 1;
                if (!other) far_from_edge++;
            }
        }
    T_CHECK_MSG(covered > W * W / 3, "covered %d", covered);
    T_CHECK_MSG(differ <= covered / 200, "%d of %d checker pixels differ", differ, covered);
    T_EQ_INT(far_from_edge, 0);
    sr_framebuffer_free(&fb);
}

/* ---- volume vs mesh silhouette -------------------------------------------------------------- */

static float ball_density(void *user, const float p[3])
{
    (void)user;
    return (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 1.0f) ? 400.0f : 0.0f;
}

static void test_volume_silhouette(void)
{
    int W = g_small ? 64 : 128, x, y, bad = 0, diff = 0, in_v = 0, view;
    sr_framebuffer fv, fm;
    sr_camera cam;
    sr_volume_desc vd;
    sr_draw_desc d;
    mesh sph = uv_sphere(128, 256, 1.0f);
    sr_framebuffer_create(&fv, W, W, NULL);
    sr_framebuffer_create(&fm, W, W, NULL);
    for (view = 0; view < 2; view++) {
        float eye[3] = {0.4f, 0.7f, 3.2f}, at[3] = {0.1f, 0, 0};
        float zero[4] = {0, 0, 0, 0};
        if (view) sr_camera_ortho(&cam, eye, at, NULL, 1.2f, 1.0f, 0.1f, 10.0f);
        else sr_camera_look_at(&cam, eye, at, NULL, 45.0f, 1.0f, 0.1f, 10.0f);
        sr_framebuffer_clear(&fv, zero, 1.0f);
        sr_framebuffer_clear(&fm, zero, 1.0f);
        sr_volume_desc_default(&vd);
        vd.density = ball_density;
        vd.step = 0.004f;
        T_EQ_INT(sr_draw_volume(&fv, &cam, &vd), SR_OK);
        sr_draw_desc_default(&d);
        d.positions = sph.p; d.vertex_count = sph.nv; d.indices = sph.i; d.triangle_count = sph.nt;
        d.shading = SR_SHADE_UNLIT;
        sr_draw_mesh(&fm, &cam, &d);
        for (y = 0; y < W; y++)
            for (x = 0; x < W; x++) {
                size_t i = (size_t)y * W + (size_t)x;
                int v = fv.depth[i] < 1.0f, m = fm.depth[i] < 1.0f;
                in_v += v;
                if (v != m) {
                    /* must be within one pixel of the other mask's boundary */
                    int dx, dy, found = 0;
                    diff++;
                    for (dy = -1; dy <= 1; dy++)
                        for (dx = -1; dx <= 1; dx++) {
                            int xx = x + dx, yy = y + dy;
                            if (xx < 0 || yy < 0 || xx >= W || yy >= W) continue;
                            if ((fm.depth[(size_t)yy * W + (size_t)xx] < 1.0f) == v) found = 1;
                        }
                    if (!found) bad++;
                }
            }
    }
    T_CHECK_MSG(bad == 0, "%d silhouette pixels more than one pixel apart (%d differ)", bad, diff);
    T_CHECK(in_v > W * W / 4);
    sr_framebuffer_free(&fv);
    sr_framebuffer_free(&fm);
    mesh_free(&sph);
}

/* ---- relief mapping against the analytic intersection --------------------------------------- */

static void test_relief(void)
{
    enum { N = 64 };
    static float depth[N * N], flat[N * N];
    sr_relief_desc rd;
    uint32_t seed = 99;
    int i, k, hits = 0, bad = 0, bad_flat = 0;
    float tol = 1.0f / (10.0f * 64.0f) + 1e-4f; /* 10 linear, 5 binary: half of 1/(10*2^5) */
    for (i = 0; i < N * N; i++) {
        int x = i % N;
        float s = ((float)x + 0.5f) / N;
        depth[i] = 0.25f + 0.5f * s; /* linear in s: bilinear lookup is exact inside */
        flat[i] = 0.5f;
    }
    sr_relief_desc_default(&rd);
    rd.origin[0] = -1; rd.origin[1] = 0; rd.origin[2] = 1;
    rd.axis_u[0] = 2; rd.axis_u[1] = 0; rd.axis_u[2] = 0;
    rd.axis_v[0] = 0; rd.axis_v[1] = 0; rd.axis_v[2] = -2; /* n = u x v = +y */
    rd.depth_scale = 0.3f;
    rd.depth.width = N; rd.depth.height = N; rd.depth.channels = 1;
    for (k = 0; k < 400; k++) {
        float o[3], target[3], dir[3], t, uvd[3];
        int use_flat = k & 1;
        rd.depth.data = use_flat ? flat : depth;
        o[0] = 4 * frand(&seed) - 2; o[1] = 1 + 2 * frand(&seed); o[2] = 4 * frand(&seed) - 2;
        target[0] = 1.4f * frand(&seed) - 0.7f; target[1] = -0.15f; target[2] = 1.4f * frand(&seed) - 0.7f;
        for (i = 0; i < 3; i++) dir[i] = target[i] - o[i];
        {
            float l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            for (i = 0; i < 3; i++) dir[i] /= l;
        }
        if (!sr_relief_intersect(&rd, o, dir, &t, uvd)) continue;
        hits++;
        {
            /* analytic: entry at y = 0, then depth d = -y / scale, s = (x + 1) / 2;
               solve d = 0.25 + 0.5 s (or d = 0.5) along the ray */
            float t0 = -o[1] / dir[1], dd = -dir[1] / rd.depth_scale, sx = dir[0] / 2.0f;
            float x0 = o[0] + t0 * dir[0], s0 = (x0 + 1) / 2, ta, d_an, d_got;
            /* d(t') = dd t', s(t') = s0 + sx t' */
            if (use_flat) ta = 0.5f / dd;
            else ta = (0.25f + 0.5f * s0) / (dd - 0.5f * sx);
            d_an = dd * ta;
            d_got = uvd[2];
            if (fabsf(d_got - d_an) > tol || fabsf(t - (t0 + ta)) > tol * rd.depth_scale / -dir[1] + 1e-4f) {
                if (use_flat) bad_flat++; else bad++;
            }
        }
    }
    T_CHECK_MSG(hits > 300, "%d relief hits", hits);
    T_CHECK_MSG(bad == 0, "%d sloped relief hits away from the analytic intersection", bad);
    T_CHECK_MSG(bad_flat == 0, "%d constant-depth hits away from 0.5", bad_flat);
    {
        /* a step (a wall across s = 0.5) against a brute-force march of the same sampled map */
        static float step_map[N * N];
        int step_hits = 0, step_bad = 0;
        for (i = 0; i < N * N; i++) step_map[i] = (i % N) < N / 2 ? 0.2f : 0.8f;
        rd.depth.data = step_map;
        for (k = 0; k < 300; k++) {
            float o[3], target[3], dir[3], t, uvd[3], l, t0, dd, s0, ds, tm0, dtm, brute = -1.0f;
            int j;
            o[0] = 4 * frand(&seed) - 2; o[1] = 0.5f + 2 * frand(&seed); o[2] = 4 * frand(&seed) - 2;
            target[0] = 1.6f * frand(&seed) - 0.8f; target[1] = -0.3f; target[2] = 1.6f * frand(&seed) - 0.8f;
            for (i = 0; i < 3; i++) dir[i] = target[i] - o[i];
            l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            for (i = 0; i < 3; i++) dir[i] /= l;
            if (!sr_relief_intersect(&rd, o, dir, &t, uvd)) continue;
            t0 = -o[1] / dir[1];
            dd = -dir[1] / rd.depth_scale;              /* map depth per unit t */
            s0 = (o[0] + t0 * dir[0] + 1) / 2; ds = dir[0] / 2 / dd;      /* per unit depth */
            tm0 = (1 - (o[2] + t0 * dir[2])) / 2; dtm = -dir[2] / 2 / dd;
            for (j = 1; j <= 20000; j++) {
                float dj = (float)j / 20000.0f;
                if (dj >= sr__depth_at(&rd.depth, s0 + dj * ds, tm0 + dj * dtm)) { brute = dj; break; }
            }
            {
                /* linear search with 10 steps can only promise hits where the ray stays inside for
                   a whole step (a thinner dip under the wall's top corner may be stepped over:
                   the method's known aliasing); count only those rays */
                int robust = brute > 0, q;
                for (q = 1; q <= 200 && robust; q++) {
                    float dq = brute + 0.1f * (float)q / 200.0f;
                    if (dq < 1.0f && dq < sr__depth_at(&rd.depth, s0 + dq * ds, tm0 + dq * dtm)) robust = 0;
                }
                if (!robust) continue;
            }
            step_hits++;
            if (!(fabsf(uvd[2] - brute) <= tol)) step_bad++;
        }
        T_CHECK_MSG(step_hits > 200 && step_bad == 0, "step map: %d of %d hits differ from the brute-force march", step_bad, step_hits);
    }
    {
        /* the renderer writes the same depth as the intersection routine */
        sr_framebuffer fb;
        sr_camera cam;
        float eye[3] = {0.3f, 2.0f, 2.0f}, at[3] = {0, 0, 0}, o[3], dir[3], t, uvd[3], P[3], z = 0;
        int W = 64, ok;
        sr_framebuffer_create(&fb, W, W, NULL);
        sr_camera_look_at(&cam, eye, at, NULL, 50.0f, 1.0f, 0.1f, 10.0f);
        rd.depth.data = depth;
        T_EQ_INT(sr_draw_relief(&fb, &cam, &rd), SR_OK);
        sr_camera_ray(&cam, W, W, 32.5f, 32.5f, o, dir);
        ok = sr_relief_intersect(&rd, o, dir, &t, uvd);
        for (i = 0; i < 3; i++) P[i] = o[i] + t * dir[i];
        T_CHECK(ok && sr_camera_depth(&cam, P, &z));
        T_NEAR(fb.depth[32 * W + 32], z, 1e-6);
        sr_framebuffer_free(&fb);
    }
}

/* Shadow rays against an analytic occluder: a floor at depth 1 with a wall (depth 0) over
   s in [0.5, 0.55], the quad of test_relief (x = 2 s - 1, top at y = 0, depth_scale 0.3). The
   light comes from +x at elevation e: a floor point at x_h is shadowed exactly when its ray
   meets the wall's near face x = 0 below the top, x_h > -0.3 / tan e. Points closer to that
   boundary than the sampling allows (a texel of bilinear blur, one linear step of the search
   along the light ray, the bias) are not judged. Both shadow tests, both must be exact
   elsewhere. */
static void test_relief_shadows(void)
{
    enum { N = 64 };
    static float depth[N * N];
    sr_relief_desc rd;
    uint32_t seed = 4;
    int i, k, mode, judged[2] = {0, 0}, wrong[2] = {0, 0};
    for (i = 0; i < N * N; i++) {
        int x = i % N;
        depth[i] = (x >= N / 2 && x < N / 2 + 4) ? 0.0f : 1.0f; /* texels 32..35: s in [0.5, 0.5625) */
    }
    sr_relief_desc_default(&rd);
    rd.origin[0] = -1; rd.origin[1] = 0; rd.origin[2] = 1;
    rd.axis_u[0] = 2; rd.axis_u[1] = 0; rd.axis_u[2] = 0;
    rd.axis_v[0] = 0; rd.axis_v[1] = 0; rd.axis_v[2] = -2;
    rd.depth_scale = 0.3f;
    rd.depth.width = N; rd.depth.height = N; rd.depth.channels = 1; rd.depth.data = depth;
    for (mode = 0; mode < 2; mode++) {
        rd.shadow_search = mode;
        for (k = 0; k < 400; k++) {
            float e = (30.0f + 40.0f * frand(&seed)) * 3.14159265f / 180.0f, L[3], uvd[3], vis, xh, edge;
            float texel = 2.0f / N, step_x = (mode ? 1.0f : 0.5f) * 0.1f * 0.3f / tanf(e), margin;
            int shadowed;
            uvd[0] = 0.05f + 0.42f * frand(&seed); /* floor texels left of the wall, away from its blur */
            uvd[1] = 0.5f; uvd[2] = 1.0f;
            L[0] = cosf(e); L[1] = sinf(e); L[2] = 0.0f;
            xh = 2.0f * uvd[0] - 1.0f;
            edge = -0.3f / tanf(e);
            margin = texel + step_x + 0.02f * 0.3f / tanf(e) + 1e-3f;
            if (fabsf(xh - edge) < margin) continue;
            shadowed = xh > edge;
            vis = sr_relief_light_visibility(&rd, uvd, L);
            judged[mode]++;
            wrong[mode] += (vis == 0.0f) != shadowed;
        }
        printf("relief shadows (%s): %d points judged, %d wrong\n", mode ? "linear + binary search" : "march from the hit", judged[mode], wrong[mode]);
        T_CHECK(judged[mode] > 200);
        T_EQ_INT(wrong[mode], 0);
    }
}

/* Curved silhouettes: with a zero depth map and curvature_u = 1/R the surface is the parabolic
   cylinder y = -(x^2) / (2R) over the quad (x = 2 s - 1). Rays aimed near its edge hit it
   exactly when the analytic quadratic has a root inside the footprint; the hit distance agrees
   within one binary-refined step of the march. Rays that cross the surface for less than two
   linear steps (grazing) are not judged: linear search may step over them by design. */
static void test_relief_silhouette(void)
{
    enum { N = 16 };
    static float zero[N * N];
    sr_relief_desc rd;
    uint32_t seed = 12;
    int k, judged = 0, wrong = 0, far = 0, misses = 0;
    const float R = 1.5f, kappa = 1.0f / 1.5f;
    sr_relief_desc_default(&rd);
    rd.origin[0] = -1; rd.origin[1] = 0; rd.origin[2] = 1;
    rd.axis_u[0] = 2; rd.axis_u[1] = 0; rd.axis_u[2] = 0;
    rd.axis_v[0] = 0; rd.axis_v[1] = 0; rd.axis_v[2] = -2;
    rd.depth_scale = 0.1f;
    rd.curvature_u = kappa;
    rd.depth.width = N; rd.depth.height = N; rd.depth.channels = 1; rd.depth.data = zero;
    for (k = 0; k < 2000; k++) {
        float o[3], dir[3], t, uvd[3], l, A, B, C, disc, r1, r2, lam0, lam1, step;
        int hit, an_hit = 0, i;
        o[0] = -3.0f + 0.5f * frand(&seed); o[1] = 0.2f + 0.6f * frand(&seed); o[2] = 0.6f * frand(&seed) - 0.3f;
        dir[0] = 1.0f; dir[1] = -(0.05f + 0.5f * frand(&seed)); dir[2] = 0.1f * frand(&seed) - 0.05f;
        l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        for (i = 0; i < 3; i++) dir[i] /= l;
        lam0 = -o[1] / dir[1];
        if (fabsf(o[0] + lam0 * dir[0]) > 1.0f || fabsf(o[2] + lam0 * dir[2]) > 1.0f) continue; /* must cross the quad's plane over it */
        /* y + x^2/(2R) = 0 along the ray: A lam^2 + B lam + C = 0 */
        A = dir[0] * dir[0] / (2 * R); B = dir[1] + o[0] * dir[0] / R; C = o[1] + o[0] * o[0] / (2 * R);
        disc = B * B - 4 * A * C;
        lam1 = lam0 + (rd.depth_scale + kappa * 4.0f / 8.0f) / -dir[1];
        step = (lam1 - lam0) / 10.0f;
        if (disc > 0) {
            r1 = (-B - sqrtf(disc)) / (2 * A); r2 = (-B + sqrtf(disc)) / (2 * A);
            if (fabsf(o[0] + r1 * dir[0]) <= 1.0f && r1 >= lam0 - 1e-4f) an_hit = 1; /* float: a root at the plane crossing */
            if (an_hit && r2 - r1 < 2 * step) continue; /* grazing */
            if (!an_hit && disc < 0.05f) continue;
        } else {
            r1 = 0;
        }
        hit = sr_relief_intersect(&rd, o, dir, &t, uvd);
        judged++;
        misses += !an_hit;
        if (hit != an_hit) { wrong++; printf("  ray %d: ours %d analytic %d disc %.4f r1 %.4f x(r1) %.4f lam0 %.4f t %.4f\n", k, hit, an_hit, disc, r1, o[0] + r1 * dir[0], lam0, hit ? t : 0.0f); }
        else if (hit && fabsf(t - r1) > step / 32.0f + 1e-4f) far++; /* 5 halvings: the bracket is step / 32 */
    }
    printf("curved silhouettes: %d rays judged (%d analytic misses), %d disagree on hit/miss, %d hits off by more than a refined step\n",
           judged, misses, wrong, far);
    T_CHECK(judged > 300 && misses > 50 && judged - misses > 50);
    T_EQ_INT(wrong, 0);
    T_EQ_INT(far, 0);
}

/* ---- terrain ---------------------------------------------------------------------------------- */

static void test_terrain(void)
{
    static float h[32 * 32];
    sr_terrain_desc td;
    sr_framebuffer fb;
    sr_camera cam;
    float eye[3] = {0.2f, 3, 4}, at[3] = {0, 0, 0}, o[3], dir[3], t, P[3], z;
    int i, W = 64, bad = 0, x, y, n = 0;
    for (i = 0; i < 32 * 32; i++) h[i] = 0.25f;
    sr_terrain_desc_default(&td);
    td.heights = h; td.width = 32; td.height = 32;
    td.origin_x = -2; td.origin_z = -2; td.spacing = 4.0f / 31; td.height_scale = 2.0f; td.base_y = -0.5f;
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 50.0f, 1.0f, 0.1f, 20.0f);
    T_EQ_INT(sr_draw_terrain(&fb, &cam, &td), SR_OK);
    for (y = 0; y < W; y++)
        for (x = 0; x < W; x++) {
            size_t pi = (size_t)y * W + (size_t)x;
            sr_camera_ray(&cam, W, W, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            t = (0.0f - o[1]) / dir[1]; /* plane y = -0.5 + 2 * 0.25 = 0 */
            for (i = 0; i < 3; i++) P[i] = o[i] + t * dir[i];
            if (P[0] < -1.9f || P[0] > 1.9f || P[2] < -1.9f || P[2] > 1.9f) continue;
            n++;
            if (!sr_camera_depth(&cam, P, &z) || fabsf(z - fb.depth[pi]) > 1e-4f) bad++;
        }
    T_CHECK(n > 500);
    T_EQ_INT(bad, 0);
    sr_framebuffer_free(&fb);
}

/* ---- shading modes, culling, model matrix, normal map --------------------------------------- */

static void test_shading(void)
{
    int W = g_small ? 64 : 128, x, y, view;
    sr_framebuffer fa, fbf;
    sr_camera cam;
    sr_draw_desc d;
    sr_light light;
    float eye[3] = {0.5f, 0.8f, 3.5f}, at[3] = {0, 0, 0}, toward[3] = {0.3f, 0.7f, 0.6f};
    mesh sph = uv_sphere(48, 96, 1.0f), coarse = uv_sphere(6, 8, 1.0f);
    float *nrm = (float *)malloc(sph.nv * 3 * sizeof(float));
    double err_sum = 0, err_max = 0, gp_sum = 0;
    long n = 0;
    sr_framebuffer_create(&fa, W, W, NULL);
    sr_framebuffer_create(&fbf, W, W, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 45.0f, 1.0f, 0.5f, 10.0f);
    sr_light_default(&light, toward);
    sr_compute_vertex_normals(sph.p, sph.nv, sph.i, sph.nt, nrm);
    sr_draw_desc_default(&d);
    d.positions = sph.p; d.vertex_count = sph.nv; d.indices = sph.i; d.triangle_count = sph.nt;
    d.normals = nrm; d.lights = &light; d.light_count = 1;
    /* per-pixel Phong against the analytic sphere's lighting at the ray hit */
    sr_framebuffer_clear(&fa, NULL, 1.0f);
    sr_draw_mesh(&fa, &cam, &d);
    d.shading = SR_SHADE_GOURAUD;
    sr_framebuffer_clear(&fbf, NULL, 1.0f);
    sr_draw_mesh(&fbf, &cam, &d);
    for (y = 0; y < W; y++)
        for (x = 0; x < W; x++) {
            size_t i = (size_t)y * W + (size_t)x;
            float o[3], dir[3], b, c, disc, t, P[3], rgb[3];
            int k;
            sr_camera_ray(&cam, W, W, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            b = o[0] * dir[0] + o[1] * dir[1] + o[2] * dir[2];
            c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 1.0f;
            disc = b * b - c;
            if (disc < 0.02f || fa.depth[i] >= 1.0f) continue; /* away from the silhouette */
            t = -b - sqrtf(disc);
            for (k = 0; k < 3; k++) P[k] = o[k] + t * dir[k];
            sr_shade_blinn(&d.material, NULL, &light, 1, P, P, cam.eye, rgb);
            for (k = 0; k < 3; k++) {
                double e = fabs((double)sr__clampf(rgb[k], 0, 1) - (double)sr__clampf(fa.color[4 * i + (size_t)k], 0, 1));
                err_sum += e;
                if (e > err_max) err_max = e;
                gp_sum += fabs((double)fa.color[4 * i + (size_t)k] - (double)fbf.color[4 * i + (size_t)k]);
            }
            n += 3;
        }
    T_CHECK(n > W * W);
    T_CHECK_MSG(err_sum / (double)n < 0.01 && err_max < 0.08, "Phong vs analytic sphere: mean %g max %g", err_sum / (double)n, err_max);
    T_CHECK_MSG(gp_sum / (double)n < 0.02, "Gouraud vs Phong mean %g", gp_sum / (double)n);
    /* flat: at most one colour per triangle */
    {
        float seen[256][3];
        int nseen = 0, k, too_many = 0;
        d.positions = coarse.p; d.vertex_count = coarse.nv; d.indices = coarse.i; d.triangle_count = coarse.nt;
        d.normals = NULL; d.shading = SR_SHADE_FLAT;
        sr_framebuffer_clear(&fa, NULL, 1.0f);
        sr_draw_mesh(&fa, &cam, &d);
        for (x = 0; x < W * W && !too_many; x++) {
            if (fa.depth[x] >= 1.0f) continue;
            for (k = 0; k < nseen; k++)
                if (!memcmp(seen[k], fa.color + 4 * x, sizeof seen[k])) break;
            if (k == nseen) {
                if (nseen == 256) too_many = 1;
                else memcpy(seen[nseen++], fa.color + 4 * x, sizeof seen[0]);
            }
        }
        T_CHECK_MSG(!too_many && nseen <= (int)coarse.nt && nseen > 10, "flat: %d colours for %zu triangles", nseen, coarse.nt);
    }
    /* culling */
    for (view = 0; view < 2; view++) {
        size_t i, bad = 0, cov = 0;
        sr_draw_desc c;
        float zero[4] = {0, 0, 0, 0};
        sr_draw_desc_default(&c);
        c.positions = sph.p; c.vertex_count = sph.nv; c.indices = sph.i; c.triangle_count = sph.nt;
        c.shading = SR_SHADE_COUNT;
        c.cull = view ? SR_CULL_FRONT : SR_CULL_BACK;
        sr_framebuffer_clear(&fa, zero, 1.0f);
        sr_draw_mesh(&fa, &cam, &c);
        for (i = 0; i < (size_t)W * W; i++) {
            float f = fa.color[4 * i], b = fa.color[4 * i + 1];
            if (view ? (f != 0 || b > 1) : (b != 0 || f > 1)) bad++;
            cov += (f + b) > 0;
        }
        T_CHECK_MSG(bad == 0 && cov > (size_t)W * W / 8, "cull mode %d: %zu bad pixels", view, bad);
    }
    /* a model matrix gives the picture of pre-transformed positions */
    {
        float model[16], *moved = (float *)malloc(sph.nv * 3 * sizeof(float));
        size_t v, i, cov_diff = 0;
        float dmax = 0;
        rot_model(model, 0.4f, 1.1f, 0.2f, -0.1f, 0.3f);
        for (v = 0; v < sph.nv; v++) sr__mat_point(model, sph.p + 3 * v, moved + 3 * v);
        d.positions = sph.p; d.vertex_count = sph.nv; d.indices = sph.i; d.triangle_count = sph.nt;
        d.shading = SR_SHADE_PHONG; d.normals = nrm; d.model = model;
        sr_framebuffer_clear(&fa, NULL, 1.0f);
        sr_draw_mesh(&fa, &cam, &d);
        d.positions = moved; d.model = NULL;
        sr_framebuffer_clear(&fbf, NULL, 1.0f);
        sr_draw_mesh(&fbf, &cam, &d);
        for (i = 0; i < (size_t)W * W; i++) {
            int ca = fa.depth[i] < 1.0f, cb = fbf.depth[i] < 1.0f;
            if (ca != cb) cov_diff++;
            else if (ca && fabsf(fa.depth[i] - fbf.depth[i]) > dmax) dmax = fabsf(fa.depth[i] - fbf.depth[i]);
        }
        T_CHECK_MSG(cov_diff <= 4 && dmax < 1e-5f, "model matrix: %zu coverage differences, depth %g", cov_diff, dmax);
        free(moved);
    }
    /* object-space normal map on a quad: lighting follows the map, not the geometry */
    {
        float qp[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, quv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
        float qn[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, map[4 * 4 * 3], P[3] = {0, 0, 0}, N[3] = {0.6f, 0, 0.8f}, rgb[3];
        float qeye[3] = {0, 0, 4}, qat[3] = {0, 0, 0};
        uint32_t qi[6] = {0, 1, 2, 0, 2, 3};
        sr_image nm;
        sr_camera qcam;
        size_t c = (size_t)(W / 2) * W + (size_t)(W / 2);
        int k;
        for (k = 0; k < 16; k++) { map[3 * k] = 0.6f; map[3 * k + 1] = 0; map[3 * k + 2] = 0.8f; }
        nm.width = 4; nm.height = 4; nm.channels = 3; nm.data = map; nm.wrap = 0;
        sr_camera_ortho(&qcam, qeye, qat, NULL, 1.5f, 1.0f, 0.1f, 10.0f);
        sr_draw_desc_default(&d);
        d.positions = qp; d.vertex_count = 4; d.indices = qi; d.triangle_count = 2;
        d.normals = qn; d.uvs = quv; d.normal_map = &nm; d.lights = &light; d.light_count = 1;
        sr_framebuffer_clear(&fa, NULL, 1.0f);
        sr_draw_mesh(&fa, &qcam, &d);
        sr_shade_blinn(&d.material, NULL, &light, 1, P, N, qeye, rgb);
        T_NEAR(fa.color[4 * c], rgb[0], 2e-3);
        T_NEAR(fa.color[4 * c + 2], rgb[2], 2e-3);
    }
    free(nrm);
    mesh_free(&sph);
    mesh_free(&coarse);
    sr_framebuffer_free(&fa);
    sr_framebuffer_free(&fbf);
}

/* ---- allocation failures and volume compositing against depth -------------------------------- */

typedef struct fail_alloc { int left, live; } fail_alloc;
static void *fa_alloc(void *user, size_t n)
{
    fail_alloc *f = (fail_alloc *)user;
    if (f->left-- <= 0) return NULL;
    f->live++;
    return malloc(n);
}
static void fa_free(void *user, void *p)
{
    fail_alloc *f = (fail_alloc *)user;
    if (p) { f->live--; free(p); }
}

static void test_alloc_failures(void)
{
    sr_allocator a;
    fail_alloc st;
    sr_framebuffer fb;
    int k, fb_ok = 1, png_ok = 1, draw_ok = 0;
    uint8_t px[16 * 16 * 3], *out;
    size_t n;
    a.alloc = fa_alloc; a.free = fa_free; a.user = &st;
    for (k = 0; k < 4; k++) {
        st.left = k; st.live = 0;
        if (sr_framebuffer_create(&fb, 16, 16, &a) != SR_ERR_OUT_OF_MEMORY || st.live != 0) fb_ok = 0;
    }
    T_CHECK(fb_ok);
    for (k = 0; k < (int)sizeof px; k++) px[k] = (uint8_t)(k * 7);
    for (k = 0; k < 4; k++) {
        st.left = k; st.live = 0;
        if (sr_encode_png(px, 16, 16, 3, 0, &a, &out, &n) != SR_ERR_OUT_OF_MEMORY || st.live != 0 || out != NULL) png_ok = 0;
    }
    T_CHECK(png_ok);
    st.left = 4; st.live = 0;
    if (sr_framebuffer_create(&fb, 16, 16, &a) == SR_OK) {
        sr_camera cam;
        sr_draw_desc d;
        float eye[3] = {0, 0, 3}, at[3] = {0, 0, 0}, p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        uint32_t idx[3] = {0, 1, 2};
        sr_camera_look_at(&cam, eye, at, NULL, 45, 1, 0.1f, 10);
        sr_draw_desc_default(&d);
        d.positions = p; d.vertex_count = 3; d.indices = idx; d.triangle_count = 1;
        draw_ok = sr_draw_mesh(&fb, &cam, &d) == SR_ERR_OUT_OF_MEMORY;
        sr_framebuffer_free(&fb);
    }
    T_CHECK(draw_ok && st.live == 0);
}

static void test_volume_composite(void)
{
    int W = 48, x, y, hidden_changed = 0, visible_blended = 0, quad_px = 0;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    sr_volume_desc vd;
    float eye[3] = {0, 0, 5}, at[3] = {0, 0, 0}, white[4] = {1, 1, 1, 1};
    float qp[12] = {-0.5f, -2, 1.5f, 2, -2, 1.5f, 2, 2, 1.5f, -0.5f, 2, 1.5f}; /* covers x > -0.5, in front of the ball */
    float qc[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    uint32_t qi[6] = {0, 1, 2, 0, 2, 3};
    float *before = (float *)malloc((size_t)W * W * 4 * sizeof(float));
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_framebuffer_clear(&fb, white, 1.0f);
    sr_camera_look_at(&cam, eye, at, NULL, 40.0f, 1.0f, 0.5f, 20.0f);
    sr_draw_desc_default(&d);
    d.positions = qp; d.vertex_count = 4; d.indices = qi; d.triangle_count = 2;
    d.colors = qc; d.shading = SR_SHADE_UNLIT;
    sr_draw_mesh(&fb, &cam, &d);
    memcpy(before, fb.color, (size_t)W * W * 4 * sizeof(float));
    sr_volume_desc_default(&vd);
    vd.density = ball_density;
    vd.step = 0.01f;
    sr_draw_volume(&fb, &cam, &vd);
    for (y = 0; y < W; y++)
        for (x = 0; x < W; x++) {
            size_t i = (size_t)y * W + (size_t)x;
            float o[3], dir[3], b, c;
            sr_camera_ray(&cam, W, W, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            b = o[0] * dir[0] + o[1] * dir[1] + o[2] * dir[2];
            c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 1.0f;
            if (b * b - c < 0.05f) continue; /* clear of the ball's silhouette */
            if (before[4 * i + 2] == 1.0f && before[4 * i] == 0.0f) {
                quad_px++;
                if (memcmp(before + 4 * i, fb.color + 4 * i, 4 * sizeof(float)) != 0) hidden_changed++;
            } else if (fb.color[4 * i] < 0.99f) {
                visible_blended++;
            }
        }
    T_CHECK_MSG(quad_px > 50 && hidden_changed == 0, "%d of %d pixels behind the opaque quad changed", hidden_changed, quad_px);
    T_CHECK(visible_blended > 20);
    free(before);
    sr_framebuffer_free(&fb);
}

/* ---- PNG through independent decoders ------------------------------------------------------- */

static const char *py_decode =
    "import sys,zlib,struct\n"
    "d=open(sys.argv[1],'rb').read()\n"
    "assert d[:8]==b'\\x89PNG\\r\\n\\x1a\\n'\n"
    "p=8;idat=b''\n"
    "while p<len(d):\n"
    " n,=struct.unpack('>I',d[p:p+4]);t=d[p+4:p+8];c=d[p+8:p+8+n]\n"
    " assert zlib.crc32(t+c)&0xffffffff==struct.unpack('>I',d[p+8+n:p+12+n])[0]\n"
    " if t==b'IHDR': w,h,bd,ct=struct.unpack('>IIBB',c[:10])\n"
    " if t==b'IDAT': idat+=c\n"
    " p+=12+n\n"
    "ch={0:1,2:3,6:4}[ct];raw=zlib.decompress(idat);s=w*ch;out=bytearray();prev=bytearray(s)\n"
    "for y in range(h):\n"
    " f=raw[y*(s+1)];r=bytearray(raw[y*(s+1)+1:(y+1)*(s+1)])\n"
    " for i in range(s):\n"
    "  a=r[i-ch] if i>=ch else 0;b=prev[i];cc=prev[i-ch] if i>=ch else 0\n"
    "  if f==1:r[i]=(r[i]+a)&255\n"
    "  elif f==2:r[i]=(r[i]+b)&255\n"
    "  elif f==3:r[i]=(r[i]+(a+b)//2)&255\n"
    "  elif f==4:\n"
    "   q=a+b-cc;pa=abs(q-a);pb=abs(q-b);pc=abs(q-cc)\n"
    "   r[i]=(r[i]+(a if pa<=pb and pa<=pc else (b if pb<=pc else cc)))&255\n"
    " out+=r;prev=r\n"
    "sys.stdout.buffer.write(out)\n";

static int have_program(const char *cmd)
{
    char buf[256];
    snprintf(buf, sizeof buf, "command -v %s >/dev/null 2>&1", cmd);
    return system(buf) == 0;
}

static void test_png(void)
{
    int ch, flip, W = 67, H = 45;
    char path[256], cmd[1024];
    int have_py = have_program("python3"), have_pc = have_program("pngcheck");
    uint8_t *img = (uint8_t *)malloc((size_t)W * H * 4), *expect = (uint8_t *)malloc((size_t)W * H * 4);
    uint32_t seed = 5;
    FILE *f;
    {
        FILE *pf;
        snprintf(path, sizeof path, "/tmp/test_render_%ld_dec.py", (long)getpid());
        pf = fopen(path, "w");
        if (pf) { fputs(py_decode, pf); fclose(pf); }
    }
    for (ch = 1; ch <= 4; ch++) {
        if (ch == 2) continue;
        for (flip = 0; flip < 2; flip++) {
            char png[256];
            int x, y, c;
            size_t n = (size_t)W * H * (size_t)ch, got = 0;
            /* smooth gradients, repeats (LZ77 matches) and noise */
            for (y = 0; y < H; y++)
                for (x = 0; x < W; x++)
                    for (c = 0; c < ch; c++) {
                        uint8_t v;
                        if (y < 15) v = (uint8_t)(x * 3 + y * 5 + c * 40);
                        else if (y < 30) v = (uint8_t)((x / 7) * 30 + c);
                        else v = (uint8_t)lcg(&seed);
                        img[((size_t)y * W + (size_t)x) * (size_t)ch + (size_t)c] = v;
                    }
            for (y = 0; y < H; y++)
                memcpy(expect + (size_t)y * W * (size_t)ch, img + (size_t)(flip ? H - 1 - y : y) * W * (size_t)ch, (size_t)W * (size_t)ch);
            snprintf(png, sizeof png, "/tmp/test_render_%ld_%d_%d.png", (long)getpid(), ch, flip);
            T_EQ_INT(sr_write_png(png, img, W, H, ch, flip), SR_OK);
            if (have_pc) {
                snprintf(cmd, sizeof cmd, "pngcheck -q %s >/dev/null 2>&1", png);
                T_CHECK_MSG(system(cmd) == 0, "pngcheck rejects %s", png);
            } else {
                T_SKIP("pngcheck", "pngcheck not installed");
            }
            if (have_py) {
                uint8_t *buf = (uint8_t *)malloc(n + 16);
                snprintf(cmd, sizeof cmd, "python3 %s %s", path, png);
                f = popen(cmd, "r");
                if (f) { got = fread(buf, 1, n + 16, f); pclose(f); }
                T_CHECK_MSG(got == n && memcmp(buf, expect, n) == 0, "python3 zlib decode of %d-channel flip %d PNG: %zu bytes", ch, flip, got);
                free(buf);
            } else {
                T_SKIP("python3 PNG decode", "python3 not found");
            }
            remove(png);
        }
    }
    remove(path);
    {
        uint8_t *out;
        size_t n;
        T_EQ_INT(sr_encode_png(NULL, 1, 1, 3, 0, NULL, &out, &n), SR_ERR_INVALID_ARGUMENT);
        T_EQ_INT(sr_encode_png(img, 1, 1, 2, 0, NULL, &out, &n), SR_ERR_INVALID_ARGUMENT);
    }
    free(img);
    free(expect);
}

/* ---- one scene of everything, rendered twice ------------------------------------------------ */

static float grass_density(void *user, const float p[3])
{
    float cx = floorf(p[0] * 8) / 8 + 1.0f / 16, cz = floorf(p[2] * 8) / 8 + 1.0f / 16, dx = p[0] - cx, dz = p[2] - cz;
    (void)user;
    return (dx * dx + dz * dz < 0.0004f && p[1] < 0.3f) ? 60.0f : 0.0f;
}

static void grass_shade(void *user, const float p[3], float rgb[3], float dir[3])
{
    (void)user;
    rgb[0] = 0.2f; rgb[1] = 0.6f + 0.3f * p[1]; rgb[2] = 0.1f;
    dir[0] = 0; dir[1] = 1; dir[2] = 0;
}

static int render_scene(int W, const char *png_path, uint8_t **png, size_t *png_n)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    sr_relief_desc rd;
    sr_volume_desc vd;
    sr_light lights[2];
    float eye[3] = {1.6f, 1.4f, 2.6f}, at[3] = {0, 0.1f, 0}, l0[3] = {0.5f, 1, 0.7f}, sky[4] = {0.6f, 0.7f, 0.9f, 1};
    mesh tor = torus(48, 24, 0.45f, 0.15f);
    float *nrm = (float *)malloc(tor.nv * 3 * sizeof(float)), model[16];
    static float depth[64 * 64];
    int i;
    uint8_t *rgb;
    for (i = 0; i < 64 * 64; i++) {
        float s = ((float)(i % 64) + 0.5f) / 64, t = ((float)(i / 64) + 0.5f) / 64;
        depth[i] = 0.5f + 0.4f * sinf(s * 18.0f) * cosf(t * 12.0f);
    }
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_framebuffer_clear(&fb, sky, 1.0f);
    sr_camera_look_at(&cam, eye, at, NULL, 45.0f, 1.0f, 0.1f, 20.0f);
    sr_light_default(&lights[0], l0);
    sr_light_default(&lights[1], NULL);
    lights[1].type = SR_LIGHT_POINT;
    lights[1].vector[0] = -2; lights[1].vector[1] = 1; lights[1].vector[2] = 1;
    lights[1].diffuse[0] = 0.4f; lights[1].diffuse[1] = 0.3f; lights[1].diffuse[2] = 0.2f;
    lights[1].ambient[0] = lights[1].ambient[1] = lights[1].ambient[2] = 0;
    sr_compute_vertex_normals(tor.p, tor.nv, tor.i, tor.nt, nrm);
    rot_model(model, 0.5f, 0.3f, -0.4f, 0.35f, 0.2f);
    sr_draw_desc_default(&d);
    d.positions = tor.p; d.vertex_count = tor.nv; d.indices = tor.i; d.triangle_count = tor.nt;
    d.normals = nrm; d.model = model; d.lights = lights; d.light_count = 2;
    d.wireframe = 1; d.cull = SR_CULL_BACK;
    sr_draw_mesh(&fb, &cam, &d);
    sr_relief_desc_default(&rd);
    rd.origin[0] = -1; rd.origin[1] = 0; rd.origin[2] = 1;
    rd.axis_u[0] = 2; rd.axis_u[1] = 0; rd.axis_u[2] = 0;
    rd.axis_v[0] = 0; rd.axis_v[1] = 0; rd.axis_v[2] = -2;
    rd.depth_scale = 0.15f;
    rd.depth.width = 64; rd.depth.height = 64; rd.depth.channels = 1; rd.depth.data = depth;
    rd.lights = lights; rd.light_count = 1; rd.shadows = 1;
    sr_draw_relief(&fb, &cam, &rd);
    sr_volume_desc_default(&vd);
    vd.box_min[0] = 0.2f; vd.box_min[1] = 0; vd.box_min[2] = 0.2f;
    vd.box_max[0] = 0.9f; vd.box_max[1] = 0.3f; vd.box_max[2] = 0.9f;
    vd.density = grass_density; vd.shade = grass_shade; vd.direction = SR_VOLUME_TANGENT;
    vd.lights = lights; vd.light_count = 1; vd.shadows = 1; vd.step = 0.01f;
    sr_draw_volume(&fb, &cam, &vd);
    rgb = (uint8_t *)malloc((size_t)W * W * 3);
    sr_framebuffer_to_rgb8(&fb, rgb, 3);
    i = sr_encode_png(rgb, W, W, 3, 0, NULL, png, png_n);
    if (png_path) sr_write_png(png_path, rgb, W, W, 3, 0);
    free(rgb);
    free(nrm);
    mesh_free(&tor);
    sr_framebuffer_free(&fb);
    return i;
}

static void test_determinism(void)
{
    uint8_t *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    int W = g_small ? 96 : 256;
    const char *out = getenv("TEST_RENDER_PNG"); /* set to keep a picture of the scene */
    T_EQ_INT(render_scene(W, out, &a, &na), SR_OK);
    T_EQ_INT(render_scene(W, NULL, &b, &nb), SR_OK);
    T_CHECK(na == nb && na > 0 && memcmp(a, b, na) == 0);
    sr_free(NULL, a);
    sr_free(NULL, b);
}

/* ---- contact sheet, text, misc ---------------------------------------------------------------- */

static void test_sheet_and_errors(void)
{
    uint8_t p1[20 * 10 * 3], p2[30 * 12 * 4];
    sr_image8 ims[2], sheet;
    const char *caps[2] = {"original", "base 0.5%"};
    size_t i, dark = 0;
    sr_framebuffer fb;
    memset(p1, 0, sizeof p1);
    memset(p2, 128, sizeof p2);
    ims[0].width = 20; ims[0].height = 10; ims[0].channels = 3; ims[0].pixels = p1;
    ims[1].width = 30; ims[1].height = 12; ims[1].channels = 4; ims[1].pixels = p2;
    T_EQ_INT(sr_contact_sheet(ims, caps, 2, 0, NULL, &sheet), SR_OK);
    T_CHECK(sheet.width >= 50 + 8 && sheet.height >= 12 + 10);
    for (i = 0; i < (size_t)sheet.width * (size_t)sheet.height; i++) dark += sheet.pixels[3 * i] == 0;
    T_CHECK(dark > 200 + 30); /* the black image plus caption ink */
    sr_free(NULL, sheet.pixels);
    T_EQ_STR(sr_result_string(SR_OK), "SR_OK");
    T_EQ_STR(sr_result_string(SR_ERR_IO), "SR_ERR_IO");
    T_EQ_INT(sr_framebuffer_create(&fb, 0, 5, NULL), SR_ERR_INVALID_ARGUMENT);
    T_EQ_INT(sr_framebuffer_create(&fb, 20000, 5, NULL), SR_ERR_TOO_LARGE);
    T_EQ_INT(sr_framebuffer_create(&fb, 8, 8, NULL), SR_OK);
    {
        sr_camera cam;
        sr_draw_desc d;
        float eye[3] = {0, 0, 3}, at[3] = {0, 0, 0}, p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        uint32_t bad[3] = {0, 1, 3};
        sr_camera_look_at(&cam, eye, at, NULL, 45, 1, 0.1f, 10);
        sr_draw_desc_default(&d);
        d.positions = p; d.vertex_count = 3; d.indices = bad; d.triangle_count = 1;
        T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_ERR_INVALID_ARGUMENT);
        T_EQ_INT(sr_write_png("/nonexistent-dir/x.png", p1, 2, 2, 3, 0), SR_ERR_IO);
    }
    sr_framebuffer_free(&fb);
}


/* ---- non-finite input (issue 21 point 2): a named error, never SR_OK with a blank image -------- */

static uint64_t fb_digest(const sr_framebuffer *fb)
{
    uint64_t h = 1469598103934665603ull;
    size_t i, n = (size_t)fb->width * (size_t)fb->height;
    const unsigned char *c = (const unsigned char *)fb->color, *z = (const unsigned char *)fb->depth;
    for (i = 0; i < 16 * n; i++) h = (h ^ c[i]) * 1099511628211ull;
    for (i = 0; i < 4 * n; i++) h = (h ^ z[i]) * 1099511628211ull;
    return h;
}

static float nf_density(void *user, const float p[3]) { (void)user; (void)p; return 1.0f; }
static void nf_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    (void)user; (void)q;
    memset(out, 0, sizeof *out);
}

/* every draw with the camera: the codes, and the framebuffer left as it was */
static void nf_all_draws(sr_framebuffer *fb, const sr_camera *cam, sr_result want, const char *what)
{
    static float h[4] = {0, 0, 0, 0}, img[4] = {0, 0, 0, 0};
    float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, n[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1}, uv[6] = {0, 0, 1, 0, 0, 1};
    uint32_t tri[3] = {0, 1, 2};
    sr_draw_desc d;
    sr_relief_desc rd;
    sr_terrain_desc td;
    sr_volume_desc vd;
    sr_shell_desc sd;
    sr_mesh_shell_desc md;
    uint64_t before = fb_digest(fb);
    int ok = 1;
    sr_draw_desc_default(&d);
    d.positions = p; d.vertex_count = 3; d.indices = tri; d.triangle_count = 1;
    ok &= T_EQ_INT(sr_draw_mesh(fb, cam, &d), want);
    sr_relief_desc_default(&rd);
    rd.depth.width = 2; rd.depth.height = 2; rd.depth.channels = 1; rd.depth.data = img;
    ok &= T_EQ_INT(sr_draw_relief(fb, cam, &rd), want);
    sr_terrain_desc_default(&td);
    td.heights = h; td.width = 2; td.height = 2;
    ok &= T_EQ_INT(sr_draw_terrain(fb, cam, &td), want);
    sr_volume_desc_default(&vd);
    vd.density = nf_density; vd.box_max[0] = vd.box_max[1] = vd.box_max[2] = 1.0f;
    ok &= T_EQ_INT(sr_draw_volume(fb, cam, &vd), want);
    sr_shell_desc_default(&sd);
    sd.sample = nf_sample; sd.tile = 1.0f; sd.tiles_x = sd.tiles_y = 1;
    ok &= T_EQ_INT(sr_draw_shell(fb, cam, &sd, NULL), want);
    sr_mesh_shell_desc_default(&md);
    md.positions = p; md.normals = n; md.uvs = uv; md.vertex_count = 3; md.indices = tri; md.triangle_count = 1;
    md.height = 0.1f; md.sample = nf_sample;
    ok &= T_EQ_INT(sr_draw_mesh_shell(fb, cam, &md, NULL), want);
    ok &= T_CHECK(fb_digest(fb) == before);
    if (!ok) printf("  note: camera case: %s\n", what);
}

static void test_not_finite(void)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    float eye[3] = {0, 0, 3}, at[3] = {0, 0, 0}, nan = (float)NAN, inf = (float)INFINITY, big = 3e38f;
    float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, rgb_nan[4] = {0, 0, 0, 1};
    uint32_t tri[3] = {0, 1, 2};
    uint8_t px[4 * 4 * 3];
    uint64_t before;
    int k, bad;
    T_EQ_STR(sr_result_string(SR_ERR_NOT_FINITE), "SR_ERR_NOT_FINITE");
    T_EQ_INT(sr_framebuffer_create(&fb, 4, 4, NULL), SR_OK);
    /* the good camera draws (so the cases below fail for their own reason) */
    sr_camera_look_at(&cam, eye, at, NULL, 45, 1, 0.1f, 10);
    sr_draw_desc_default(&d);
    d.positions = p; d.vertex_count = 3; d.indices = tri; d.triangle_count = 1;
    T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_OK);
    /* bad cameras: NaN / infinite eye, target, fov, aspect, half height; eye == target; fov 0 */
    for (k = 0; k < 10; k++) {
        float e[3] = {0, 0, 3}, t[3] = {0, 0, 0}, fov = 45, asp = 1;
        const char *what[10] = {"eye nan", "eye inf", "target nan", "fov nan", "fov inf", "aspect nan",
                                "eye == target", "fov 0", "ortho half height nan", "ortho half height 0"};
        if (k == 0) e[1] = nan;
        if (k == 1) e[2] = inf;
        if (k == 2) t[0] = nan;
        if (k == 3) fov = nan;
        if (k == 4) fov = inf;
        if (k == 5) asp = nan;
        if (k == 6) e[2] = 0;
        if (k == 7) fov = 0;
        if (k < 8) sr_camera_look_at(&cam, e, t, NULL, fov, asp, 0.1f, 10);
        else sr_camera_ortho(&cam, e, t, NULL, k == 8 ? nan : 0.0f, 1, 0.1f, 10);
        nf_all_draws(&fb, &cam, SR_ERR_INVALID_ARGUMENT, what[k]);
    }
    sr_camera_look_at(&cam, eye, at, NULL, 45, 1, 0.1f, 10);
    before = fb_digest(&fb);
    /* a vertex at 3e38 (finite) overflows the camera's matrix: SR_ERR_NOT_FINITE, nothing drawn */
    p[3] = big;
    T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_ERR_NOT_FINITE);
    p[3] = -big; p[4] = big;
    T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_ERR_NOT_FINITE);
    p[3] = nan; p[4] = 0;
    T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_ERR_INVALID_ARGUMENT);
    p[3] = 1;
    {
        float model[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        d.model = model;
        model[5] = nan;
        T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_ERR_INVALID_ARGUMENT);
        model[5] = 1e30f; p[4] = 1e10f; /* finite, the product is not */
        T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_ERR_NOT_FINITE);
        d.model = NULL; p[4] = 0;
    }
    {
        static float h[4] = {1e38f, 0, 0, 1e38f};
        sr_terrain_desc td;
        sr_terrain_desc_default(&td);
        td.heights = h; td.width = 2; td.height = 2; td.height_scale = 10.0f; /* 1e39: overflows */
        T_EQ_INT(sr_draw_terrain(&fb, &cam, &td), SR_ERR_NOT_FINITE);
        td.height_scale = 1.0f; td.origin_x = nan;
        T_EQ_INT(sr_draw_terrain(&fb, &cam, &td), SR_ERR_INVALID_ARGUMENT);
        td.origin_x = 0; td.spacing = inf;
        T_EQ_INT(sr_draw_terrain(&fb, &cam, &td), SR_ERR_INVALID_ARGUMENT);
    }
    {
        sr_volume_desc vd;
        sr_volume_desc_default(&vd);
        vd.density = nf_density; vd.box_max[0] = vd.box_max[1] = 1.0f; vd.box_max[2] = inf;
        T_EQ_INT(sr_draw_volume(&fb, &cam, &vd), SR_ERR_INVALID_ARGUMENT);
        vd.box_max[2] = 3e38f; vd.box_min[2] = -3e38f; /* finite corners, an infinite diagonal */
        T_EQ_INT(sr_draw_volume(&fb, &cam, &vd), SR_ERR_NOT_FINITE);
    }
    {
        static float img[4] = {0, 0, 0, 0};
        sr_relief_desc rd;
        sr_relief_desc_default(&rd);
        rd.depth.width = 2; rd.depth.height = 2; rd.depth.channels = 1; rd.depth.data = img;
        rd.origin[1] = nan;
        T_EQ_INT(sr_draw_relief(&fb, &cam, &rd), SR_ERR_INVALID_ARGUMENT);
        rd.origin[1] = 0; rd.axis_u[0] = inf;
        T_EQ_INT(sr_draw_relief(&fb, &cam, &rd), SR_ERR_INVALID_ARGUMENT);
    }
    T_CHECK(fb_digest(&fb) == before);
    /* NaN attributes are not errors (they are data), but they must not reach an int: NaN uvs on a
       normal map and NaN colours draw, and the colour converts to 0 */
    {
        float uv[6], col[9], nm[4 * 3];
        sr_image map;
        for (k = 0; k < 6; k++) uv[k] = nan;
        for (k = 0; k < 9; k++) col[k] = nan;
        for (k = 0; k < 12; k++) nm[k] = k % 3 == 2 ? 1.0f : 0.0f;
        map.width = 2; map.height = 2; map.channels = 3; map.data = nm; map.wrap = 1;
        p[0] = -1; p[1] = -1; p[3] = 1; p[4] = -1; p[6] = 0; p[7] = 1;
        d.uvs = uv; d.normal_map = &map; d.colors = col;
        T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_OK);
        sr_framebuffer_clear(&fb, rgb_nan, 1.0f);
        for (k = 0; k < 16; k++) fb.color[4 * k] = nan;
        sr_framebuffer_to_rgb8(&fb, px, 3);
        for (k = 0, bad = 0; k < 16; k++) bad += px[3 * k] != 0;
        T_EQ_INT(bad, 0);
    }
    sr_framebuffer_free(&fb);
}


/* ---- the caption font (issue 21 point 6: '6' was drawn as '5'): every glyph against its
   intended bitmap, written here independently of the header's table, row by row ---------------- */

static const struct { char c; const char *rows[5]; } intended_font[] = {
    {' ', {"...", "...", "...", "...", "..."}}, {'0', {"###", "#.#", "#.#", "#.#", "###"}},
    {'1', {".#.", "##.", ".#.", ".#.", "###"}}, {'2', {"###", "..#", "###", "#..", "###"}},
    {'3', {"###", "..#", ".##", "..#", "###"}}, {'4', {"#.#", "#.#", "###", "..#", "..#"}},
    {'5', {"###", "#..", "###", "..#", "###"}}, {'6', {"###", "#..", "###", "#.#", "###"}},
    {'7', {"###", "..#", "..#", ".#.", ".#."}}, {'8', {"###", "#.#", "###", "#.#", "###"}},
    {'9', {"###", "#.#", "###", "..#", "###"}}, {'A', {".#.", "#.#", "###", "#.#", "#.#"}},
    {'B', {"##.", "#.#", "##.", "#.#", "##."}}, {'C', {".##", "#..", "#..", "#..", ".##"}},
    {'D', {"##.", "#.#", "#.#", "#.#", "##."}}, {'E', {"###", "#..", "##.", "#..", "###"}},
    {'F', {"###", "#..", "##.", "#..", "#.."}}, {'G', {".##", "#..", "#.#", "#.#", ".##"}},
    {'H', {"#.#", "#.#", "###", "#.#", "#.#"}}, {'I', {"###", ".#.", ".#.", ".#.", "###"}},
    {'J', {"..#", "..#", "..#", "#.#", ".#."}}, {'K', {"#.#", "#.#", "##.", "#.#", "#.#"}},
    {'L', {"#..", "#..", "#..", "#..", "###"}}, {'M', {"#.#", "###", "###", "#.#", "#.#"}},
    {'N', {"##.", "#.#", "#.#", "#.#", "#.#"}}, {'O', {".#.", "#.#", "#.#", "#.#", ".#."}},
    {'P', {"##.", "#.#", "##.", "#..", "#.."}}, {'Q', {".#.", "#.#", "#.#", "##.", ".##"}},
    {'R', {"##.", "#.#", "##.", "#.#", "#.#"}}, {'S', {".##", "#..", ".#.", "..#", "##."}},
    {'T', {"###", ".#.", ".#.", ".#.", ".#."}}, {'U', {"#.#", "#.#", "#.#", "#.#", "###"}},
    {'V', {"#.#", "#.#", "#.#", "#.#", ".#."}}, {'W', {"#.#", "#.#", "###", "###", "#.#"}},
    {'X', {"#.#", "#.#", ".#.", "#.#", "#.#"}}, {'Y', {"#.#", "#.#", ".#.", ".#.", ".#."}},
    {'Z', {"###", "..#", ".#.", "#..", "###"}}, {'.', {"...", "...", "...", "...", ".#."}},
    {',', {"...", "...", "...", ".#.", "#.."}}, {':', {"...", ".#.", "...", ".#.", "..."}},
    {';', {"...", ".#.", "...", ".#.", "#.."}}, {'-', {"...", "...", "###", "...", "..."}},
    {'_', {"...", "...", "...", "...", "###"}}, {'+', {"...", ".#.", "###", ".#.", "..."}},
    {'=', {"...", "###", "...", "###", "..."}}, {'/', {"..#", "..#", ".#.", "#..", "#.."}},
    {'|', {".#.", ".#.", ".#.", ".#.", ".#."}}, {'(', {"..#", ".#.", ".#.", ".#.", "..#"}},
    {')', {"#..", ".#.", ".#.", ".#.", "#.."}}, {'[', {"##.", "#..", "#..", "#..", "##."}},
    {']', {".##", "..#", "..#", "..#", ".##"}}, {'%', {"#.#", "..#", ".#.", "#..", "#.#"}},
    {'\'', {".#.", ".#.", "...", "...", "..."}}, {'"', {"#.#", "#.#", "...", "...", "..."}},
    {'!', {".#.", ".#.", ".#.", "...", ".#."}}, {'?', {"##.", "..#", ".#.", "...", ".#."}},
    {'<', {"..#", ".#.", "#..", ".#.", "..#"}}, {'>', {"#..", ".#.", "..#", ".#.", "#.."}},
    {'*', {"...", "#.#", ".#.", "#.#", "..."}}, {'#', {"#.#", "###", "#.#", "###", "#.#"}}};

static void test_font(void)
{
    static const char *box[5] = {"###", "#.#", "#.#", "#.#", "###"}; /* a character without a glyph */
    uint8_t px[2 * 3 * 5], white[3] = {255, 255, 255};
    sr_image8 img;
    int c, k, x, y, wrong = 0, wrong_case = 0, glyphs = 0, scale;
    img.width = 3; img.height = 5; img.channels = 1; img.pixels = px;
    for (c = 1; c < 256; c++) {
        const char *const *want = box;
        char text[2];
        int up = c >= 'a' && c <= 'z' ? c - 'a' + 'A' : c, bad = 0;
        for (k = 0; k < (int)(sizeof intended_font / sizeof intended_font[0]); k++)
            if (intended_font[k].c == up) { want = intended_font[k].rows; glyphs += c == up; }
        text[0] = (char)c; text[1] = 0;
        memset(px, 0, sizeof px);
        sr_draw_text(&img, 0, 0, text, 1, white);
        for (y = 0; y < 5; y++)
            for (x = 0; x < 3; x++) bad += (px[y * 3 + x] == 255) != (want[y][x] == '#');
        if (bad) {
            printf("  glyph %d '%c' drawn as:", c, c >= 32 && c < 127 ? c : '?');
            for (y = 0; y < 5; y++) printf(" %c%c%c", px[y * 3] ? '#' : '.', px[y * 3 + 1] ? '#' : '.', px[y * 3 + 2] ? '#' : '.');
            printf("\n");
            if (c != up) wrong_case++; else wrong++;
        }
    }
    T_EQ_INT(glyphs, (int)(sizeof intended_font / sizeof intended_font[0]));
    T_EQ_INT(wrong, 0);
    T_EQ_INT(wrong_case, 0);
    /* scale 2 and the advance: "66" at scale 2 is two 6x10 glyphs 8 pixels apart */
    {
        uint8_t big[16 * 10];
        int bad = 0;
        img.width = 16; img.height = 10; img.pixels = big;
        memset(big, 0, sizeof big);
        scale = 2;
        sr_draw_text(&img, 0, 0, "66", scale, white);
        for (y = 0; y < 10; y++)
            for (x = 0; x < 16; x++) {
                int gx = (x % 8) / 2, on = gx < 3 && intended_font[7].rows[y / 2][gx] == '#';
                bad += (big[y * 16 + x] == 255) != on;
            }
        T_CHECK(intended_font[7].c == '6');
        T_EQ_INT(bad, 0);
    }
}


/* ---- the wireframe fades out on triangles too small for it (issue 21 point 6) ---------------- */

/* the wire's ink (sum over covered pixels of 1 - colour: white unlit surface, black wire), the
   covered pixels, and the ink expected on a coarse mesh: half a pixel per pixel of each front
   triangle's perimeter (the wire is width 1, half of it on each side of an edge) */
static void wire_ink(const mesh *m, int W, double *ink, double *covered, double *expected)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    float eye[3] = {0.3f, 0.5f, 3.2f}, at[3] = {0, 0, 0};
    size_t i, t;
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 45.0f, 1.0f, 0.1f, 10.0f);
    sr_draw_desc_default(&d);
    d.positions = m->p; d.vertex_count = m->nv; d.indices = m->i; d.triangle_count = m->nt;
    d.shading = SR_SHADE_UNLIT; d.cull = SR_CULL_BACK; d.wireframe = 1;
    d.material.diffuse[0] = d.material.diffuse[1] = d.material.diffuse[2] = 1.0f;
    T_EQ_INT(sr_draw_mesh(&fb, &cam, &d), SR_OK);
    *ink = *covered = *expected = 0.0;
    for (i = 0; i < (size_t)W * (size_t)W; i++)
        if (fb.color[4 * i + 3] == 1.0f) { *covered += 1.0; *ink += 1.0 - fb.color[4 * i]; }
    for (t = 0; t < m->nt; t++) {
        double sx[3], sy[3], area2;
        int k;
        for (k = 0; k < 3; k++) {
            const float *p = m->p + 3 * (size_t)m->i[3 * t + (size_t)k], *M = cam.viewproj;
            double cx = M[0] * p[0] + M[4] * p[1] + M[8] * p[2] + M[12], cy = M[1] * p[0] + M[5] * p[1] + M[9] * p[2] + M[13];
            double cw = M[3] * p[0] + M[7] * p[1] + M[11] * p[2] + M[15];
            sx[k] = (cx / cw * 0.5 + 0.5) * W;
            sy[k] = (0.5 - cy / cw * 0.5) * W;
        }
        area2 = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
        if (area2 >= 0.0) continue; /* back-facing (y down) */
        for (k = 0; k < 3; k++) *expected += 0.5 * hypot(sx[(k + 1) % 3] - sx[k], sy[(k + 1) % 3] - sy[k]);
    }
    sr_framebuffer_free(&fb);
}

static void test_wire_density(void)
{
    mesh coarse = uv_sphere(6, 8, 1.0f), dense = uv_sphere(g_small ? 60 : 120, g_small ? 120 : 240, 1.0f);
    double ink, covered, expected;
    wire_ink(&coarse, 256, &ink, &covered, &expected);
    printf("wire on %zu triangles at 256 px: ink %.0f px, expected %.0f, %.1f%% of %.0f covered px\n", coarse.nt, ink, expected,
           100.0 * ink / covered, covered);
    /* coarse: every edge drawn as before (corners overlap a little: a few % less than the perimeters) */
    T_CHECK(ink > 0.85 * expected && ink < 1.05 * expected);
    wire_ink(&dense, g_small ? 128 : 256, &ink, &covered, &expected);
    printf("wire on %zu triangles at %d px: ink %.0f px (%.1f%% of %.0f covered px), unfaded it would be %.0f\n", dense.nt,
           g_small ? 128 : 256, ink, 100.0 * ink / covered, covered, expected);
    /* dense: the triangles are ~2 px^2, their full wire would cover everything (expected > covered) */
    T_CHECK(expected > covered);
    T_CHECK(ink < 0.35 * covered);
    mesh_free(&coarse);
    mesh_free(&dense);
}


/* ---- terrain colours are filtered (issue 21 point 6: each grid cell was a flat colour block) ---- */

static void test_terrain_colors(void)
{
    enum { N = 33, W = 256 };
    static float h[N * N], col[3 * N * N];
    sr_terrain_desc td;
    sr_framebuffer fb;
    sr_camera cam;
    float eye[3] = {16, 10, 16}, at[3] = {16, 0, 16}, up[3] = {0, 0, -1}, maxd = 0.0f;
    uint32_t seed = 7;
    int i, x, y, k, pairs = 0;
    for (i = 0; i < N * N; i++) { h[i] = 0.0f; for (k = 0; k < 3; k++) col[3 * i + k] = frand(&seed); }
    sr_terrain_desc_default(&td);
    td.heights = h; td.width = N; td.height = N; td.spacing = 1.0f; td.colors = col;
    sr_framebuffer_create(&fb, W, W, NULL);
    sr_camera_ortho(&cam, eye, at, up, 16.0f, 1.0f, 0.1f, 20.0f); /* 8 pixels per sample spacing */
    T_EQ_INT(sr_draw_terrain(&fb, &cam, &td), SR_OK);
    /* the head light from straight above on a flat ground: colour = 1.2 kd + 0.3 (ambient 0.2 +
       diffuse 1, specular 0.3 at N.H = 1), so bilinear colours change by at most 1.2 / 8 per
       pixel; a nearest-sample lookup jumps by up to 1.2 at each cell edge */
    for (y = 0; y < W; y++)
        for (x = 0; x + 1 < W; x++) {
            const float *a = fb.color + 4 * ((size_t)y * W + (size_t)x), *b = a + 4, *c = y + 1 < W ? a + 4 * W : NULL;
            if (a[3] != 1.0f || b[3] != 1.0f) continue;
            for (k = 0; k < 3; k++) {
                float dx = fabsf(a[k] - b[k]), dy = c && c[3] == 1.0f ? fabsf(a[k] - c[k]) : 0.0f;
                if (dx > maxd) maxd = dx;
                if (dy > maxd) maxd = dy;
            }
            pairs++;
        }
    printf("terrain colours: largest step between adjacent pixels %.3f over %d pairs (bound 1.2 / 8 = 0.15)\n", maxd, pairs);
    T_CHECK(pairs > W * W / 2);
    T_CHECK(maxd > 0.02f && maxd <= 0.151f);
    sr_framebuffer_free(&fb);
}


/* ---- marchers end (issue 21 point 4's fuzzing): a step under the ulp of the ray's distance looped
   forever (terrain: a tiny step; shell: a camera far away), and a long terrain box gets at most
   65536 steps a ray ---------------------------------------------------------------------------- */

static void march_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    (void)user; (void)q;
    memset(out, 0, sizeof *out);
    out->step = 1.0f / 256.0f; /* empty: only the steps end the ray */
}

static void test_march_ends(void)
{
    static float h[16];
    sr_framebuffer fb, ref;
    sr_camera cam;
    sr_terrain_desc td;
    sr_shell_desc sd;
    sr_shell_stats st;
    float eye[3] = {0.5f, 3, 4}, at[3] = {1.5f, 0, 1.5f}, far_eye[3] = {2e6f, 2e6f, 3e6f}, far_at[3] = {2, 2, 0};
    int i, same = 1;
    sr_framebuffer_create(&fb, 8, 8, NULL);
    sr_framebuffer_create(&ref, 8, 8, NULL);
    for (i = 0; i < 16; i++) h[i] = (float)(i % 3) * 0.1f;
    sr_terrain_desc_default(&td);
    td.heights = h; td.width = 4; td.height = 4;
    sr_camera_look_at(&cam, eye, at, NULL, 50.0f, 1.0f, 0.1f, 20.0f);
    T_EQ_INT(sr_draw_terrain(&ref, &cam, &td), SR_OK);
    td.step = 1e-30f; /* 65536 steps of the box's length a ray instead: the same hits, refined the same way */
    T_EQ_INT(sr_draw_terrain(&fb, &cam, &td), SR_OK);
    for (i = 0; i < 64; i++) same &= (fb.depth[i] < 1.0f) == (ref.depth[i] < 1.0f) && fabsf(fb.depth[i] - ref.depth[i]) < 1e-4f;
    T_CHECK(same);
    sr_shell_desc_default(&sd);
    sd.sample = march_sample; sd.tile = 1.0f; sd.tiles_x = sd.tiles_y = 4;
    sr_camera_look_at(&cam, far_eye, far_at, NULL, 1e-4f, 1.0f, 1e5f, 1e7f); /* steps of 1/256 under the ulp of 4e6 */
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &sd, &st), SR_OK);
    T_CHECK(st.samples > 0);
    sr_framebuffer_free(&fb);
    sr_framebuffer_free(&ref);
}


/* ---- test_render --png-msd FILE (for tests/terrain_cli.sh): the mean squared difference (8-bit
   units, summed over RGB) between horizontally adjacent pixels that both differ from the corner
   pixel (the background) by more than 24, and the number of such pairs ------------------------- */

static int png_msd(const char *path)
{
    sr_picture pic;
    long long sum = 0, pairs = 0;
    int x, y, k, ch;
    sr_result r = sr_read_image(path, NULL, &pic);
    if (r != SR_OK || !pic.samples || pic.channels < 3) {
        fprintf(stderr, "test_render --png-msd %s: %s\n", path, r != SR_OK ? sr_result_string(r) : "not an RGB image");
        if (r == SR_OK) sr_picture_free(&pic);
        return 1;
    }
    ch = pic.channels;
    for (y = 0; y < pic.height; y++)
        for (x = 0; x + 1 < pic.width; x++) {
            const uint16_t *a = pic.samples + ((size_t)y * (size_t)pic.width + (size_t)x) * (size_t)ch, *b = a + ch;
            int da = 0, db = 0, d2 = 0;
            for (k = 0; k < 3; k++) {
                da += abs((int)a[k] - (int)pic.samples[k]);
                db += abs((int)b[k] - (int)pic.samples[k]);
                d2 += ((int)a[k] - (int)b[k]) * ((int)a[k] - (int)b[k]);
            }
            if (da <= 24 || db <= 24) continue;
            sum += d2;
            pairs++;
        }
    printf("%lld %lld\n", pairs ? sum / pairs : 0, pairs);
    sr_picture_free(&pic);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--png-msd") == 0) return png_msd(argv[2]);
    T_BEGIN(argc, argv);
    g_small = getenv("TEST_SANITIZE") != NULL;
    test_closed_coverage();
    test_quad_diagonals();
    test_near_clip();
    test_interpenetration();
    test_checkerboard();
    test_volume_silhouette();
    test_relief();
    test_relief_shadows();
    test_relief_silhouette();
    test_terrain();
    test_shading();
    test_alloc_failures();
    test_volume_composite();
    test_png();
    test_determinism();
    test_sheet_and_errors();
    test_not_finite();
    test_font();
    test_wire_density();
    test_terrain_colors();
    test_march_ends();
    return T_END();
}
