/* test_texel_mesh - tiling over a mesh shell (issue 19 point 4): texel.h's prism map (continuity
   across shared side faces, the round trips, the flat case against the height-field tiling's
   map, folding, bad input, allocation failure, per-tile wd from a map, determinism), then
   render.h's mesh shell marcher (sr_draw_mesh_shell): a flat mesh shell against sr_draw_shell
   with the same content and with a TVT's grass at per-tile wd from a map, a closed cube-sphere
   with no holes at its seams, the sun cut under the horizon, a see-through shell's optical
   depth, a folded prism, bad input, allocation failure, cancellation and determinism.
   TEST_SANITIZE=1 shrinks the pictures. */
#define SR_IMPLEMENTATION
#include "render.h"
#define TVT_IMPLEMENTATION
#include "texel.h"
#include "test.h"
#include <stdlib.h>
#include <float.h>

/* ---- a counting allocator that can fail the k-th allocation ---------------------------------- */
typedef struct counting { long live, calls, fail_at; } counting;
static void *c_alloc(void *u, size_t n)
{
    counting *c = (counting *)u;
    if (++c->calls == c->fail_at) return NULL;
    c->live++;
    return malloc(n);
}
static void c_free(void *u, void *p)
{
    counting *c = (counting *)u;
    if (p) { c->live--; free(p); }
}

static uint64_t rng_state = 12345;
static float frand(void) /* [0, 1) */
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (float)(rng_state >> 40) / 16777216.0f;
}

/* ---- meshes ------------------------------------------------------------------------------- */
typedef struct mesh { float *pos, *nrm, *uv; uint32_t *idx; size_t nv, nt; } mesh;

static void mesh_free(mesh *m) { free(m->pos); free(m->nrm); free(m->uv); free(m->idx); memset(m, 0, sizeof(*m)); }

/* an n x n grid over [0, size]^2, z = amp sin sin (amp 0: flat), normals of that surface, uv = xy / tile */
static mesh grid_mesh(int n, float size, float amp, float tile)
{
    mesh m;
    int i, j;
    m.nv = (size_t)n * n; m.nt = 2 * (size_t)(n - 1) * (n - 1);
    m.pos = (float *)malloc(m.nv * 3 * sizeof(float)); m.nrm = (float *)malloc(m.nv * 3 * sizeof(float));
    m.uv = (float *)malloc(m.nv * 2 * sizeof(float)); m.idx = (uint32_t *)malloc(m.nt * 3 * sizeof(uint32_t));
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            size_t v = (size_t)j * n + i;
            float x = size * i / (n - 1), y = size * j / (n - 1), k = 2.0f * 3.14159265f / size;
            float z = amp * sinf(k * x) * sinf(k * y), gx = amp * k * cosf(k * x) * sinf(k * y), gy = amp * k * sinf(k * x) * cosf(k * y);
            float l = sqrtf(gx * gx + gy * gy + 1.0f);
            m.pos[3 * v] = x; m.pos[3 * v + 1] = y; m.pos[3 * v + 2] = z;
            m.nrm[3 * v] = -gx / l; m.nrm[3 * v + 1] = -gy / l; m.nrm[3 * v + 2] = 1.0f / l;
            m.uv[2 * v] = x / tile; m.uv[2 * v + 1] = y / tile;
        }
    for (j = 0; j + 1 < n; j++)
        for (i = 0; i + 1 < n; i++) {
            uint32_t a = (uint32_t)(j * n + i), b = a + 1, c = a + (uint32_t)n, d = c + 1;
            uint32_t *t = m.idx + 6 * ((size_t)j * (n - 1) + i);
            t[0] = a; t[1] = b; t[2] = d; t[3] = a; t[4] = d; t[5] = c;
        }
    return m;
}

/* a cube-sphere of radius r: 6 faces of n x n quads, each face its own chart (vertices repeated
   at the cube's edges: the charts' seams are not shared faces), uv = tiles per face */
static mesh sphere_mesh(int n, float r, float tiles)
{
    mesh m;
    int f, i, j;
    size_t v = 0, t = 0;
    m.nv = 6 * (size_t)(n + 1) * (n + 1); m.nt = 6 * 2 * (size_t)n * n;
    m.pos = (float *)malloc(m.nv * 3 * sizeof(float)); m.nrm = (float *)malloc(m.nv * 3 * sizeof(float));
    m.uv = (float *)malloc(m.nv * 2 * sizeof(float)); m.idx = (uint32_t *)malloc(m.nt * 3 * sizeof(uint32_t));
    for (f = 0; f < 6; f++) {
        int ax = f / 2; float sg = f % 2 ? -1.0f : 1.0f;
        size_t base = v;
        for (j = 0; j <= n; j++)
            for (i = 0; i <= n; i++, v++) {
                float a = 2.0f * i / n - 1.0f, b = 2.0f * j / n - 1.0f, c[3], l;
                c[ax] = sg; c[(ax + 1) % 3] = sg * a; c[(ax + 2) % 3] = b;
                l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                m.nrm[3 * v] = c[0] / l; m.nrm[3 * v + 1] = c[1] / l; m.nrm[3 * v + 2] = c[2] / l;
                m.pos[3 * v] = r * c[0] / l; m.pos[3 * v + 1] = r * c[1] / l; m.pos[3 * v + 2] = r * c[2] / l;
                m.uv[2 * v] = tiles * (float)i / n + 7.0f * f; m.uv[2 * v + 1] = tiles * (float)j / n;
            }
        for (j = 0; j < n; j++)
            for (i = 0; i < n; i++) {
                uint32_t a = (uint32_t)(base + (size_t)j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
                m.idx[3 * t] = a; m.idx[3 * t + 1] = b; m.idx[3 * t + 2] = d; t++;
                m.idx[3 * t] = a; m.idx[3 * t + 1] = d; m.idx[3 * t + 2] = c; t++;
            }
    }
    return m;
}

static tvt_shell_desc shell_desc(const mesh *m, float height)
{
    tvt_shell_desc d;
    memset(&d, 0, sizeof(d));
    d.positions = m->pos; d.normals = m->nrm; d.uvs = m->uv; d.vertex_count = m->nv;
    d.indices = m->idx; d.triangle_count = m->nt; d.height = height;
    return d;
}

/* shell vertex v of the mesh (v >= nv: offset by height along the unit normal), in double */
static void shell_vertex(const mesh *m, float height, uint32_t v, double x[3])
{
    uint32_t k = v < m->nv ? v : v - (uint32_t)m->nv;
    const float *n = m->nrm + 3 * k;
    double l = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]), h = v < m->nv ? 0.0 : height / l;
    int c;
    for (c = 0; c < 3; c++) x[c] = m->pos[3 * k + c] + h * n[c];
}

/* the map's rounding: float affine maps of coordinates of size s, so a few ulps of s, times the
   map's gain (frame units per world unit, at most g); 64 ulps covers the matrices' own float
   rounding (each entry 1/2 ulp, summed over 3 terms) and the query point's (1/2 ulp of s) */
static double map_tol(double s, double g) { return 64.0 * FLT_EPSILON * (1.0 + s) * (1.0 + g); }

/* ---- texel.h: the map --------------------------------------------------------------------- */
/* Points on the side face two prisms share map to the same uvw from both. The face of edge
   (i, j), i < j, is the two triangles (i, j, j') and (i, i', j') (the split rule), so points are
   drawn on those; their true uvw is the same combination of the corners' uvw. */
static void test_continuity(void)
{
    mesh m = grid_mesh(7, 3.0f, 0.4f, 0.75f);
    float height = 0.3f;
    tvt_shell_desc d = shell_desc(&m, height);
    tvt_shell s;
    size_t t1, t2;
    long faces = 0, points = 0, inside = 0, agree = 0;
    double worst = 0;
    T_EQ_INT(tvt_build_shell(&d, &s), TVT_OK);
    T_EQ_SIZE(s.folded, 0);
    for (t1 = 0; t1 < m.nt; t1++)
        for (t2 = t1 + 1; t2 < m.nt; t2++) {
            const uint32_t *A = m.idx + 3 * t1, *B = m.idx + 3 * t2;
            uint32_t e[2];
            int a, b, c = 0, k;
            for (a = 0; a < 3; a++) for (b = 0; b < 3; b++) if (A[a] == B[b] && c < 2) e[c++] = A[a];
            if (c != 2) continue;
            if (e[0] > e[1]) { uint32_t x = e[0]; e[0] = e[1]; e[1] = x; }
            faces++;
            for (k = 0; k < 8; k++) {
                uint32_t tri[3];
                double x[3][3], w[3], p[3] = {0, 0, 0}, u[3] = {0, 0, 0};
                float pf[3], m1[3], m2[3];
                int c2, r1, r2;
                if (k & 1) { tri[0] = e[0]; tri[1] = e[1]; tri[2] = e[1] + (uint32_t)m.nv; }
                else { tri[0] = e[0]; tri[1] = e[0] + (uint32_t)m.nv; tri[2] = e[1] + (uint32_t)m.nv; }
                w[0] = frand(); w[1] = frand() * (1 - w[0]); w[2] = 1 - w[0] - w[1];
                for (c2 = 0; c2 < 3; c2++) shell_vertex(&m, height, tri[c2], x[c2]);
                for (c2 = 0; c2 < 3; c2++) {
                    uint32_t v = tri[c2] % (uint32_t)m.nv;
                    p[0] += w[c2] * x[c2][0]; p[1] += w[c2] * x[c2][1]; p[2] += w[c2] * x[c2][2];
                    u[0] += w[c2] * m.uv[2 * v]; u[1] += w[c2] * m.uv[2 * v + 1]; u[2] += w[c2] * (tri[c2] >= m.nv ? 1.0 : 0.0);
                }
                pf[0] = (float)p[0]; pf[1] = (float)p[1]; pf[2] = (float)p[2];
                r1 = tvt_shell_map(&s, t1, pf, m1);
                r2 = tvt_shell_map(&s, t2, pf, m2);
                points++;
                inside += r1 == 1 && r2 == 1;
                {
                    double d1 = 0, d2 = 0, tol = map_tol(6.0, 8.0);
                    for (c2 = 0; c2 < 3; c2++) {
                        d1 = fmax(d1, fabs(m1[c2] - m2[c2]));
                        d2 = fmax(d2, fabs(m1[c2] - u[c2]));
                    }
                    worst = fmax(worst, d1);
                    agree += d1 <= tol && d2 <= tol;
                }
            }
        }
    T_CHECK(faces == 3 * 6 * 6 - 2 * 6); /* interior edges of a 6 x 6 quad grid with diagonals: 3 per quad minus the border */
    T_EQ_INT(inside, points);
    T_CHECK_MSG(agree == points, "%ld of %ld agree, worst %.3g", agree, points, worst);
    tvt_shell_free(&s);
    mesh_free(&m);
}

/* point -> uvw -> point, and uvw -> point -> uvw, in random prisms; the prism's corners map to
   their uv and w = 0, 1 */
static void test_round_trip(void)
{
    mesh m = grid_mesh(6, 2.0f, 0.3f, 0.5f);
    float height = 0.25f;
    tvt_shell_desc d = shell_desc(&m, height);
    tvt_shell s;
    int k, ok_p = 0, ok_u = 0, ok_c = 0, n = 400;
    T_EQ_INT(tvt_build_shell(&d, &s), TVT_OK);
    for (k = 0; k < n; k++) {
        size_t t = (size_t)(frand() * (float)m.nt);
        const uint32_t *tri = m.idx + 3 * t;
        double x[6][3], w[4], y[3], p[3] = {0, 0, 0}, err = 0, erru = 0;
        float pf[3], uvw[3], back[3], uvw2[3];
        uint32_t tets[3][4];
        int c, j, r1, r2, r3, r4, which = (int)(frand() * 3.0f) % 3;
        /* a point of the prism: of one of its three tetrahedra (random barycentric coordinates) */
        w[0] = frand(); w[1] = frand(); w[2] = frand(); w[3] = frand();
        y[0] = w[0] + w[1] + w[2] + w[3];
        tvt_shell_prism_tets(tri, (uint32_t)m.nv, tets);
        for (j = 0; j < 4; j++) {
            shell_vertex(&m, height, tets[which][j], y);
            for (c = 0; c < 3; c++) p[c] += w[j] / (w[0] + w[1] + w[2] + w[3]) * y[c];
        }
        for (j = 0; j < 6; j++) shell_vertex(&m, height, tri[j % 3] + (j >= 3 ? (uint32_t)m.nv : 0), x[j]);
        for (c = 0; c < 3; c++) pf[c] = (float)p[c];
        r1 = tvt_shell_map(&s, t, pf, uvw);
        r2 = tvt_shell_unmap(&s, t, uvw, back);
        for (c = 0; c < 3; c++) err = fmax(err, fabs(back[c] - pf[c]));
        r3 = tvt_shell_map(&s, t, back, uvw2);
        for (c = 0; c < 3; c++) erru = fmax(erru, fabs(uvw2[c] - uvw[c]));
        /* gain: world per frame unit up to tile 0.5 and height 0.25 (condition of the maps < 8) */
        ok_p += r1 == 1 && r2 == 1 && err <= map_tol(2.5, 8.0);
        ok_u += r3 == 1 && erru <= map_tol(5.0, 8.0) && uvw[2] >= -1e-5f && uvw[2] <= 1.0f + 1e-5f;
        /* a corner */
        j = (int)(frand() * 6.0f) % 6;
        for (c = 0; c < 3; c++) pf[c] = (float)x[j][c];
        r4 = tvt_shell_map(&s, t, pf, uvw);
        ok_c += r4 == 1 && fabs(uvw[0] - m.uv[2 * tri[j % 3]]) <= map_tol(4.0, 8.0) &&
                fabs(uvw[1] - m.uv[2 * tri[j % 3] + 1]) <= map_tol(4.0, 8.0) && fabs(uvw[2] - (j >= 3 ? 1.0 : 0.0)) <= map_tol(4.0, 8.0);
    }
    T_EQ_INT(ok_p, n);
    T_EQ_INT(ok_u, n);
    T_EQ_INT(ok_c, n);
    { /* a point outside the prism says so, a bad prism index is -1 */
        float far[3] = {100, 100, 100}, uvw[3];
        T_EQ_INT(tvt_shell_map(&s, 0, far, uvw), 0);
        T_EQ_INT(tvt_shell_map(&s, m.nt, far, uvw), -1);
        T_EQ_INT(tvt_shell_unmap(&s, m.nt, far, uvw), -1);
    }
    tvt_shell_free(&s);
    mesh_free(&m);
}

/* A flat mesh with upward normals and shell height = tile is the height-field tiling of a flat
   terrain: uvw = (x / tile, y / tile, z / tile) (render.h's sr_draw_shell frame, texel.h RENDERING) */
static void test_flat_is_height_field(void)
{
    float tile = 0.5f;
    mesh m = grid_mesh(5, 2.0f, 0.0f, tile);
    tvt_shell_desc d = shell_desc(&m, tile);
    tvt_shell s;
    int k, ok = 0, n = 300;
    T_EQ_INT(tvt_build_shell(&d, &s), TVT_OK);
    for (k = 0; k < n; k++) {
        size_t t = (size_t)(frand() * (float)m.nt);
        const uint32_t *tri = m.idx + 3 * t;
        float b0 = frand(), b1 = frand() * (1 - b0), p[3], uvw[3];
        int c;
        for (c = 0; c < 2; c++)
            p[c] = b0 * m.pos[3 * tri[0] + c] + b1 * m.pos[3 * tri[1] + c] + (1 - b0 - b1) * m.pos[3 * tri[2] + c];
        p[2] = frand() * tile;
        ok += tvt_shell_map(&s, t, p, uvw) == 1 && fabsf(uvw[0] - p[0] / tile) <= map_tol(4.0, 2.0) &&
              fabsf(uvw[1] - p[1] / tile) <= map_tol(4.0, 2.0) && fabsf(uvw[2] - p[2] / tile) <= map_tol(1.0, 2.0);
    }
    T_EQ_INT(ok, n);
    tvt_shell_free(&s);
    mesh_free(&m);
}

/* normals converging over a small triangle: a thin shell is fine, a thick one folds */
static void test_folded(void)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, nrm[9], uv[6] = {0, 0, 1, 0, 0, 1};
    uint32_t idx[3] = {0, 1, 2};
    mesh m;
    tvt_shell_desc d;
    tvt_shell s;
    int v;
    for (v = 0; v < 3; v++) { /* toward the centroid, 60 degrees from the vertical */
        float cx = 1.0f / 3 - pos[3 * v], cy = 1.0f / 3 - pos[3 * v + 1], l = sqrtf(cx * cx + cy * cy);
        nrm[3 * v] = 0.866f * cx / l; nrm[3 * v + 1] = 0.866f * cy / l; nrm[3 * v + 2] = 0.5f;
    }
    m.pos = pos; m.nrm = nrm; m.uv = uv; m.idx = idx; m.nv = 3; m.nt = 1;
    d = shell_desc(&m, 0.05f);
    T_EQ_INT(tvt_build_shell(&d, &s), TVT_OK);
    T_EQ_SIZE(s.folded, 0);
    tvt_shell_free(&s);
    d.height = 2.0f; /* the offset triangle passes through its centre and turns over */
    T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_FOLDED);
    T_CHECK(s.tets == NULL);
    d.allow_folded = 1;
    T_EQ_INT(tvt_build_shell(&d, &s), TVT_OK);
    T_EQ_SIZE(s.folded, 1);
    tvt_shell_free(&s);
}

static void test_bad_input(void)
{
    mesh m = grid_mesh(3, 1.0f, 0.1f, 0.5f);
    tvt_shell_desc d = shell_desc(&m, 0.1f);
    tvt_shell s;
    float keep;
    uint32_t ik;
    T_EQ_INT(tvt_build_shell(NULL, &s), TVT_ERR_INVALID_ARGUMENT);
    T_EQ_INT(tvt_build_shell(&d, NULL), TVT_ERR_INVALID_ARGUMENT);
    d.uvs = NULL; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_INVALID_ARGUMENT); d.uvs = m.uv;
    keep = m.pos[4]; m.pos[4] = NAN; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER); m.pos[4] = keep;
    keep = m.nrm[5]; m.nrm[5] = INFINITY; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER); m.nrm[5] = keep;
    keep = m.uv[3]; m.uv[3] = NAN; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER); m.uv[3] = keep;
    { float n0[3]; memcpy(n0, m.nrm, sizeof n0); memset(m.nrm, 0, sizeof n0);
      T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER); memcpy(m.nrm, n0, sizeof n0); }
    d.height = 0.0f; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER);
    d.height = -1.0f; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER);
    d.height = NAN; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_PARAMETER);
    d.height = 0.1f;
    ik = m.idx[4]; m.idx[4] = (uint32_t)m.nv; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_BAD_INDEX);
    m.idx[4] = m.idx[3]; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_DEGENERATE); /* a repeated vertex */
    m.idx[4] = ik;
    { /* three collinear vertices: move vertex 1 onto the line of 0 and 2 ... */
        float p1[3], u1[2];
        memcpy(p1, m.pos + 3, sizeof p1); memcpy(u1, m.uv + 2, sizeof u1);
        m.pos[3] = 0.5f * (m.pos[0] + m.pos[3 * 8]); m.pos[4] = 0.5f * (m.pos[1] + m.pos[3 * 8 + 1]);
        m.pos[5] = 0.5f * (m.pos[2] + m.pos[3 * 8 + 2]);
        T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_DEGENERATE);
        memcpy(m.pos + 3, p1, sizeof p1);
        m.uv[2] = m.uv[0]; m.uv[3] = m.uv[1]; /* ... and a triangle of zero area in tile coordinates */
        T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_DEGENERATE);
        memcpy(m.uv + 2, u1, sizeof u1);
    }
    d.triangle_count = 0; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_EMPTY);
    d.triangle_count = ((size_t)-1) / 8; T_EQ_INT(tvt_build_shell(&d, &s), TVT_ERR_TOO_LARGE);
    d.triangle_count = m.nt;
    T_CHECK(s.tets == NULL && s.prism_count == 0);
    T_EQ_STR(tvt_result_string(TVT_ERR_FOLDED), "TVT_ERR_FOLDED");
    T_EQ_STR(tvt_result_string(TVT_ERR_BAD_INDEX), "TVT_ERR_BAD_INDEX");
    T_EQ_STR(tvt_result_string(TVT_ERR_DEGENERATE), "TVT_ERR_DEGENERATE");
    { /* allocation failure at every k: the named error, nothing leaked */
        counting c;
        tvt_allocator a;
        long k;
        int all = 1;
        a.alloc = c_alloc; a.free = c_free; a.user = &c;
        d.allocator = &a;
        for (k = 1; k < 10; k++) {
            tvt_result r;
            memset(&c, 0, sizeof c); c.fail_at = k;
            r = tvt_build_shell(&d, &s);
            if (r == TVT_OK) { tvt_shell_free(&s); all &= c.live == 0; break; }
            all &= r == TVT_ERR_OUT_OF_MEMORY && c.live == 0;
        }
        T_CHECK(all && k > 1);
        d.allocator = NULL;
    }
    { /* the same bits on every run */
        tvt_shell s2;
        T_EQ_INT(tvt_build_shell(&d, &s), TVT_OK);
        T_EQ_INT(tvt_build_shell(&d, &s2), TVT_OK);
        T_CHECK(!memcmp(s.tets, s2.tets, 3 * TVT_SHELL_TET_FLOATS * sizeof(float) * m.nt));
        tvt_shell_free(&s); tvt_shell_free(&s2);
    }
    mesh_free(&m);
}

/* a tile's wd from the map over tile coordinates: wrapped or clamped, values clamped to [0, 1] */
static void test_wd_map(void)
{
    float wd[6] = {0.1f, 0.2f, 0.3f, 0.4f, 1.5f, NAN}; /* 3 x 2 */
    tvt_wd_map m;
    m.wd = wd; m.width = 3; m.height = 2; m.origin[0] = -1; m.origin[1] = 5; m.wrap = 1;
    T_NEAR(tvt_tile_wd(&m, -1, 5), 0.1f, 0);
    T_NEAR(tvt_tile_wd(&m, 1, 5), 0.3f, 0);
    T_NEAR(tvt_tile_wd(&m, -1, 6), 0.4f, 0);
    T_NEAR(tvt_tile_wd(&m, 2, 7), 0.1f, 0);     /* wraps: (3, 2) -> (0, 0) */
    T_NEAR(tvt_tile_wd(&m, -2, 4), 0.0f, 0);    /* wraps to (2, 1): NaN gives 0 */
    T_NEAR(tvt_tile_wd(&m, 0, 6), 1.0f, 0);     /* 1.5 clamps to 1 */
    m.wrap = 0;
    T_NEAR(tvt_tile_wd(&m, -50, -50), 0.1f, 0); /* clamps to (0, 0) */
    T_NEAR(tvt_tile_wd(&m, 50, -50), 0.3f, 0);
    T_NEAR(tvt_tile_wd(NULL, 0, 0), 0.0f, 0);
}

/* ---- render.h: the mesh shell marcher ------------------------------------------------------ */
/* analytic content: fibres of extinction sigma (1 + cos 2 pi x) / 2 below height top, tangent
   leaning along x (so the frame's tangent turns back to the world), colour varying with y */
typedef struct content { float sigma, top, step; long calls, bad; int uniform; } content;

static void fibres(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    content *c = (content *)user;
    c->calls++;
    if (!(q->p[0] >= 0 && q->p[0] < 1 && q->p[1] >= 0 && q->p[1] < 1 && q->p[2] >= 0 && q->p[2] < 1)) c->bad++;
    out->step = c->step;
    if (q->p[2] >= c->top) return;
    out->sigma = c->uniform ? c->sigma : c->sigma * 0.5f * (1.0f + cosf(6.2831853f * q->p[0]));
    out->rgb[0] = 0.2f; out->rgb[1] = 0.4f + 0.4f * q->p[1]; out->rgb[2] = 0.1f;
    out->tangent[0] = 0.3f; out->tangent[1] = 0.0f; out->tangent[2] = 1.0f;
    out->specular = 0.5f;
    out->light = 0.8f;
}

static void set_lights(sr_light *l)
{
    float sun[3] = {0.4f, 0.3f, 0.866f};
    sr_light_default(l, sun);
}

static int sanitize(void) { const char *e = getenv("TEST_SANITIZE"); return e && *e && *e != '0'; }

static int black_ground = 0;
static int mesh_desc_draw(sr_framebuffer *fb, const sr_camera *cam, const mesh *m, float height, content *c,
                          const sr_allocator *a, sr_shell_stats *st, sr_light *sun)
{
    sr_mesh_shell_desc d;
    sr_mesh_shell_desc_default(&d);
    d.positions = m->pos; d.normals = m->nrm; d.uvs = m->uv; d.vertex_count = m->nv;
    d.indices = m->idx; d.triangle_count = m->nt; d.height = height;
    d.sample = fibres; d.user = c; d.lights = sun; d.light_count = 1; d.allocator = a;
    if (black_ground) memset(d.ground_rgb, 0, sizeof d.ground_rgb);
    return (int)sr_draw_mesh_shell(fb, cam, &d, st);
}

/* A flat mesh shell (normals up, height = tile) and sr_draw_shell over flat ground give the same
   picture: the same frame at every point, so only the samples' phase along each ray differs. */
static void test_flat_against_height_field(void)
{
    int w = sanitize() ? 48 : 96, h = sanitize() ? 36 : 72, x, ok, n = 0;
    float tile = 0.5f, eye[3] = {1.1f, -1.2f, 1.4f}, at[3] = {1.0f, 1.0f, 0.0f}, up[3] = {0, 0, 1};
    mesh m = grid_mesh(5, 2.0f, 0.0f, tile);
    sr_framebuffer a, b;
    sr_camera cam;
    sr_shell_desc sd;
    sr_shell_stats sa, sb;
    sr_light sun;
    content ca = {6.0f, 0.8f, 1.0f / 128.0f, 0, 0, 0}, cb = ca;
    double maxd = 0, mean = 0;
    set_lights(&sun);
    sr_camera_look_at(&cam, eye, at, up, 50.0f, (float)w / (float)h, 0.05f, 100.0f);
    sr_framebuffer_create(&a, w, h, NULL); sr_framebuffer_create(&b, w, h, NULL);
    sr_framebuffer_clear(&a, NULL, 1.0f); sr_framebuffer_clear(&b, NULL, 1.0f);
    sr_shell_desc_default(&sd);
    sd.tile = tile; sd.tiles_x = sd.tiles_y = 4; sd.sample = fibres; sd.user = &ca; sd.lights = &sun; sd.light_count = 1;
    /* a black ground on a black background: sr_draw_shell misses the ground where a ray's last
       step jumps past its box's bottom (1/1000 of a tile under the ground, less than a step) */
    memset(sd.ground_rgb, 0, sizeof sd.ground_rgb);
    T_EQ_INT(sr_draw_shell(&a, &cam, &sd, &sa), SR_OK);
    black_ground = 1;
    ok = mesh_desc_draw(&b, &cam, &m, tile, &cb, NULL, &sb, &sun);
    black_ground = 0;
    T_EQ_INT(ok, SR_OK);
    for (x = 0; x < w * h; x++) {
        int k;
        for (k = 0; k < 3; k++) {
            double dd = fabs(a.color[4 * x + k] - b.color[4 * x + k]);
            maxd = fmax(maxd, dd); mean += dd; n++;
        }
    }
    mean /= n;
    /* The two are Riemann sums of one integral along each ray, of step h = 1/128 tile with
       different phases: they differ by at most about one step's opacity, 1 - exp(-sigma h) =
       4.6%, times the radiance (< 1.5), where the density changes fastest; on average far less
       (sigma's cosine averages out over the step's phase). */
    T_CHECK_MSG(maxd <= 1.5 * (1.0 - exp(-6.0 / 128.0)), "max %.4f", maxd);
    T_CHECK_MSG(mean <= 0.1 * 1.5 * (1.0 - exp(-6.0 / 128.0)), "mean %.5f", mean);
    T_CHECK_MSG(labs(sa.covered - sb.covered) <= w * h / 100, "covered %ld %ld", sa.covered, sb.covered);
    T_CHECK(sb.covered > w * h / 4);
    T_EQ_INT(cb.bad, 0);
    sr_framebuffer_free(&a); sr_framebuffer_free(&b);
    mesh_free(&m);
}

/* A closed cube-sphere (24 charts' seams are side borders, not shared faces) under a dense
   layer: every pixel whose ray meets the sphere is covered (no ray falls through a seam, an edge
   or a vertex), none outside the outer surface's disc is touched, and the pictures repeat bit
   for bit. */
static void test_sphere(void)
{
    int w = sanitize() ? 40 : 80, h = w, x, y, holes = 0, stray = 0, inner = 0;
    float r = 1.0f, hs = 0.15f, eye[3] = {0.3f, -4.0f, 1.2f}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    mesh m = sphere_mesh(6, r, 3.0f);
    sr_framebuffer fb, fb2;
    sr_camera cam;
    sr_shell_stats st;
    sr_light sun;
    content c = {40.0f, 0.9f, 1.0f / 64.0f, 0, 0, 1}, c2 = c;
    float dist = sqrtf(eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2]);
    set_lights(&sun);
    sr_camera_look_at(&cam, eye, at, up, 40.0f, 1.0f, 0.05f, 100.0f);
    sr_framebuffer_create(&fb, w, h, NULL); sr_framebuffer_create(&fb2, w, h, NULL);
    sr_framebuffer_clear(&fb, NULL, 1.0f); sr_framebuffer_clear(&fb2, NULL, 1.0f);
    T_EQ_INT(mesh_desc_draw(&fb, &cam, &m, hs, &c, NULL, &st, &sun), SR_OK);
    T_EQ_INT(mesh_desc_draw(&fb2, &cam, &m, hs, &c2, NULL, NULL, &sun), SR_OK);
    T_CHECK(!memcmp(fb.color, fb2.color, sizeof(float) * 4 * (size_t)w * h));
    T_CHECK(!memcmp(fb.depth, fb2.depth, sizeof(float) * (size_t)w * h));
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            float o[3], d[3], oc, b, miss;
            size_t i = (size_t)y * w + x;
            sr_camera_ray(&cam, w, h, x + 0.5f, y + 0.5f, o, d);
            oc = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
            b = sqrtf(fmaxf(dist * dist - oc * oc, 0.0f)); /* the ray's distance from the centre */
            /* rays within 0.97 r of the centre meet the inscribed mesh (its faces are within 2% of r) */
            miss = fb.color[4 * i + 3] <= 1.0f && fb.depth[i] >= 1.0f;
            if (b < 0.97f * r) { inner++; holes += miss || fb.color[4 * i + 1] <= fb.color[4 * i + 0]; } /* ground shows */
            if (b > (r + hs) * 1.01f) stray += !miss;
        }
    T_CHECK(inner > w * h / 10);
    T_EQ_INT(holes, 0);
    T_EQ_INT(stray, 0);
    T_EQ_INT(c.bad, 0);
    T_CHECK(st.covered >= inner);
    sr_framebuffer_free(&fb); sr_framebuffer_free(&fb2);
    mesh_free(&m);
}


/* ---- texel.h's grass over the mesh shell ---------------------------------------------------- */
typedef struct grass { tvt_tvt tv; int res; tvt_wd_map map; long calls; } grass;

/* level 0 at the tile's wd from the map, one voxel per step, the texel's colour and tangent */
static void grass_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    grass *g = (grass *)user;
    float p[3], sigma, res = (float)g->res;
    tvt_voxel v;
    g->calls++;
    p[0] = q->p[0] * res; p[1] = q->p[1] * res; p[2] = q->p[2] * res;
    out->step = 1.0f / res;
    sigma = tvt_tvt_sample(&g->tv, tvt_tile_wd(&g->map, q->tile_x, q->tile_y), 0, p, q->dir, &v);
    if (!(sigma > 0)) return;
    out->sigma = sigma * res;
    memcpy(out->rgb, v.color, sizeof(out->rgb));
    memcpy(out->tangent, v.tangent, sizeof(out->tangent));
    out->light = 1.0f;
}

/* The same grass (a 32^3 TVT, wd per tile from a 2 x 2 map wrapped over 4 x 4 tiles) over a
   flat mesh shell and over sr_draw_shell's flat terrain: (1) from an oblique camera the two
   pictures agree (only the samples' phase along a ray differs, by under one step of a voxel:
   a pixel differs by at most that voxel's opacity, and on average by a small part of it);
   (2) from straight above, the tiles the map calls dry (wd 1) are yellower than the fresh ones
   (wd 0) in both. */
static void test_grass_mesh_against_terrain(void)
{
    tvt_grass_desc gd = tvt_grass_default_desc();
    tvt_tvt_options o = tvt_tvt_default_options();
    tvt_texel t;
    grass g;
    float wd[4] = {0.0f, 1.0f, 1.0f, 0.0f}, tile = 0.5f, up[3] = {0, 0, 1};
    float eye[3] = {1.2f, -1.0f, 1.3f}, at[3] = {1.0f, 1.0f, 0.0f}, top[3] = {1.0f, 1.0f, 5.0f}, mid[3] = {1.0f, 1.0f, 0.0f}, north[3] = {0, 1, 0};
    mesh m = grid_mesh(5, 2.0f, 0.0f, tile);
    int w = sanitize() ? 48 : 96, h = sanitize() ? 36 : 72, view, x;
    sr_light sun;
    memset(&g, 0, sizeof(g));
    gd.res = 32; gd.blade_count = 60; gd.seed = 5;
    o.frames = 2;
    T_CHECK(tvt_build_grass(&gd, &t) == TVT_OK);
    T_CHECK(tvt_build_tvt(&t, &o, &g.tv) == TVT_OK);
    tvt_texel_free(&t);
    g.res = 32;
    g.map.wd = wd; g.map.width = 2; g.map.height = 2; g.map.wrap = 1;
    set_lights(&sun);
    for (view = 0; view < 2; view++) {
        sr_framebuffer a, b;
        sr_camera cam;
        sr_shell_desc sd;
        sr_mesh_shell_desc md;
        double mean = 0, ratio[2][2] = {{0, 0}, {0, 0}}; /* [picture][dry] sum of r / g */
        long cnt[2] = {0, 0};
        if (view == 0) sr_camera_look_at(&cam, eye, at, up, 50.0f, (float)w / (float)h, 0.05f, 100.0f);
        else sr_camera_ortho(&cam, top, mid, north, 1.0f, (float)w / (float)h, 0.05f, 100.0f);
        sr_framebuffer_create(&a, w, h, NULL); sr_framebuffer_create(&b, w, h, NULL);
        sr_framebuffer_clear(&a, NULL, 1.0f); sr_framebuffer_clear(&b, NULL, 1.0f);
        sr_shell_desc_default(&sd);
        sd.tile = tile; sd.tiles_x = sd.tiles_y = 4; sd.sample = grass_sample; sd.user = &g;
        sd.lights = &sun; sd.light_count = 1;
        memset(sd.ground_rgb, 0, sizeof sd.ground_rgb); /* see test_flat_against_height_field */
        sr_mesh_shell_desc_default(&md);
        md.positions = m.pos; md.normals = m.nrm; md.uvs = m.uv; md.vertex_count = m.nv;
        md.indices = m.idx; md.triangle_count = m.nt; md.height = tile;
        md.sample = grass_sample; md.user = &g; md.lights = &sun; md.light_count = 1;
        memset(md.ground_rgb, 0, sizeof md.ground_rgb);
        T_EQ_INT(sr_draw_shell(&a, &cam, &sd, NULL), SR_OK);
        T_EQ_INT(sr_draw_mesh_shell(&b, &cam, &md, NULL), SR_OK);
        for (x = 0; x < w * h; x++) {
            int k;
            for (k = 0; k < 3; k++) mean += fabs(a.color[4 * x + k] - b.color[4 * x + k]);
            if (view == 1) { /* the pixel's tile from its place: 2 world units over h pixels, x from -w/h */
                float px = 1.0f + ((float)(x % w) + 0.5f - 0.5f * w) * 2.0f / h, py = 1.0f - ((float)(x / w) + 0.5f - 0.5f * h) * 2.0f / h;
                int ti = (int)floorf(px / tile), tj = (int)floorf(py / tile), dry;
                if (px < 0 || py < 0 || px >= 2 || py >= 2 || fabsf(px / tile - ti - 0.5f) > 0.4f || fabsf(py / tile - tj - 0.5f) > 0.4f) continue;
                dry = wd[(tj & 1) * 2 + (ti & 1)] > 0.5f;
                if (a.color[4 * x + 1] > 0.02f && b.color[4 * x + 1] > 0.02f) {
                    ratio[0][dry] += a.color[4 * x] / a.color[4 * x + 1];
                    ratio[1][dry] += b.color[4 * x] / b.color[4 * x + 1];
                    cnt[dry]++;
                }
            }
        }
        mean /= 3.0 * w * h;
        T_CHECK_MSG(mean <= 0.02, "view %d: mean difference %.4f", view, mean);
        if (view == 1) {
            T_CHECK(cnt[0] > w * h / 20 && cnt[1] > w * h / 20);
            T_CHECK_MSG(ratio[0][1] / cnt[1] > ratio[0][0] / cnt[0] + 0.2, "terrain r/g dry %.3f fresh %.3f", ratio[0][1] / cnt[1], ratio[0][0] / cnt[0]);
            T_CHECK_MSG(ratio[1][1] / cnt[1] > ratio[1][0] / cnt[0] + 0.2, "mesh r/g dry %.3f fresh %.3f", ratio[1][1] / cnt[1], ratio[1][0] / cnt[0]);
        }
        sr_framebuffer_free(&a); sr_framebuffer_free(&b);
    }
    tvt_tvt_free(&g.tv);
    mesh_free(&m);
}


/* The mesh hides the sun under the layer's horizon: with no ambient light, a sphere's grass is
   black where the surface faces away from the sun (n.L < -0.2: the marcher cuts light 0 below
   -0.1 of its prisms' w gradient, which follows the sphere's normal within the faceting) and
   lit where it faces it (n.L > 0.3); a see-through shell lets rays cross the mesh. */
static void test_horizon(void)
{
    int w = sanitize() ? 32 : 64, h = w, x, y, dark_bad = 0, lit_bad = 0, dark = 0, lit = 0;
    float r = 1.0f, hs = 0.1f, eye[3] = {0.0f, -4.0f, 0.0f}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1}, Ld[3] = {1, 0, 0};
    mesh m = sphere_mesh(6, r, 3.0f);
    sr_framebuffer fb;
    sr_camera cam;
    sr_light sun;
    content c = {40.0f, 0.9f, 1.0f / 64.0f, 0, 0, 1};
    sr_light_default(&sun, Ld);
    memset(sun.ambient, 0, sizeof sun.ambient);
    sr_camera_look_at(&cam, eye, at, up, 40.0f, 1.0f, 0.05f, 100.0f);
    sr_framebuffer_create(&fb, w, h, NULL);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(mesh_desc_draw(&fb, &cam, &m, hs, &c, NULL, NULL, &sun), SR_OK);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            float o[3], d[3], oc, b2, R = r + 0.5f * hs, t, n;
            size_t i = (size_t)y * w + x;
            sr_camera_ray(&cam, w, h, x + 0.5f, y + 0.5f, o, d);
            oc = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
            b2 = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - oc * oc;
            if (b2 > 0.9f * R * R) continue; /* the silhouette: left out */
            t = -oc - sqrtf(R * R - b2);
            n = (o[0] + t * d[0]) / R; /* n.L with L = +x */
            if (n < -0.2f) { dark++; dark_bad += fb.color[4 * i] + fb.color[4 * i + 1] + fb.color[4 * i + 2] > 0.0f; }
            if (n > 0.3f) { lit++; lit_bad += !(fb.color[4 * i + 1] > 0.01f); }
        }
    T_CHECK(dark > w * h / 20 && lit > w * h / 20);
    T_EQ_INT(dark_bad, 0);
    T_EQ_INT(lit_bad, 0);
    { /* see-through: with a thin layer, the rays through the middle cross it twice and see the sky */
        sr_mesh_shell_desc d;
        content thin = {0.2f, 0.9f, 1.0f / 64.0f, 0, 0, 1};
        size_t i = (size_t)(h / 2) * w + w / 2;
        float bg[4] = {0.0f, 0.0f, 1.0f, 1.0f};
        sr_framebuffer_clear(&fb, bg, 1.0f);
        sr_mesh_shell_desc_default(&d);
        d.positions = m.pos; d.normals = m.nrm; d.uvs = m.uv; d.vertex_count = m.nv;
        d.indices = m.idx; d.triangle_count = m.nt; d.height = hs;
        d.sample = fibres; d.user = &thin; d.lights = &sun; d.light_count = 1; d.see_through = 1;
        memset(sun.diffuse, 0, sizeof sun.diffuse); memset(sun.specular, 0, sizeof sun.specular); /* an unlit layer */
        memset(d.material.emission, 0, sizeof d.material.emission);
        T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_OK);
        /* two crossings of the content (w below 0.9, one frame unit per shell height along the normal)
           at sigma 0.2: the sky's blue times exp(-0.36); each crossing may lose or gain one step of
           1/64 and the ray's slant at the centre pixel is under 1%: within 2 (2/64 + 0.01) 0.2 = 0.017 in
           optical depth */
        T_CHECK_MSG(fabs(log(fb.color[4 * i + 2]) + 0.36) < 0.017, "blue %.4f", fb.color[4 * i + 2]);
    }
    sr_framebuffer_free(&fb);
    mesh_free(&m);
}

/* A mesh whose prism folds (a thick shell over converging normals): the marcher crosses the folded
   tetrahedra without sampling, ends every ray and returns; the samples stay bounded. */
static void test_folded_render(void)
{
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, nrm[9], uv[6] = {0, 0, 1, 0, 0, 1}, eye[3] = {0.3f, -2.0f, 2.0f}, at[3] = {0.33f, 0.33f, 0.5f};
    uint32_t idx[3] = {0, 1, 2};
    mesh m;
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_stats st;
    sr_light sun;
    content c = {4.0f, 0.9f, 1.0f / 32.0f, 0, 0, 1};
    int v;
    for (v = 0; v < 3; v++) {
        float cx = 1.0f / 3 - pos[3 * v], cy = 1.0f / 3 - pos[3 * v + 1], l = sqrtf(cx * cx + cy * cy);
        nrm[3 * v] = 0.866f * cx / l; nrm[3 * v + 1] = 0.866f * cy / l; nrm[3 * v + 2] = 0.5f;
    }
    m.pos = pos; m.nrm = nrm; m.uv = uv; m.idx = idx; m.nv = 3; m.nt = 1;
    set_lights(&sun);
    sr_camera_look_at(&cam, eye, at, NULL, 50.0f, 1.0f, 0.05f, 100.0f);
    sr_framebuffer_create(&fb, 32, 32, NULL);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(mesh_desc_draw(&fb, &cam, &m, 2.0f, &c, NULL, &st, &sun), SR_OK);
    /* at most one sample per 1/32 frame unit along a ray of at most ~3 frame units per tetrahedron crossed */
    T_CHECK_MSG(st.samples < 32L * 32 * 3 * 3 * 32, "samples %ld", st.samples);
    sr_framebuffer_free(&fb);
}


/* render.h's marcher and texel.h's map are the same map: looking straight down on a bumpy mesh
   shell, the frame point (tile + p) of each ray's first sample, taken back to the world by
   tvt_shell_unmap in the prism that holds it, lies on that ray (x, y of the pixel's centre) and
   on the outer surface or the mesh's open border (the first sample is where the ray enters). */
typedef struct first { int have; int tile[2]; float p[3]; } first;
static void first_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    first *f = (first *)user;
    if (!f->have) { f->have = 1; f->tile[0] = q->tile_x; f->tile[1] = q->tile_y; memcpy(f->p, q->p, sizeof f->p); }
    out->sigma = 1000.0f; /* opaque: one sample per ray */
    out->step = 1.0f;
}

static void test_same_map(void)
{
    mesh m = grid_mesh(6, 2.0f, 0.3f, 0.5f);
    float height = 0.25f, top[3] = {1.0f, 1.0f, 5.0f}, mid[3] = {1.0f, 1.0f, 0.0f}, north[3] = {0, 1, 0};
    tvt_shell_desc sd = shell_desc(&m, height);
    tvt_shell s;
    sr_camera cam;
    int n = 24, x, y, rays = 0, found = 0;
    T_EQ_INT(tvt_build_shell(&sd, &s), TVT_OK);
    sr_camera_ortho(&cam, top, mid, north, 0.9f, 1.0f, 0.05f, 100.0f);
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            sr_framebuffer fb;
            sr_mesh_shell_desc d;
            first f;
            float o[3], dir[3];
            size_t k;
            int ok = 0;
            /* the pixel's ray, drawn alone: a 1 x 1 orthographic frame around it */
            sr_camera_ray(&cam, n, n, x + 0.5f, y + 0.5f, o, dir);
            {
                float eye1[3] = {o[0], o[1], 5.0f}, at1[3] = {o[0], o[1], 0.0f};
                sr_camera c1;
                sr_camera_ortho(&c1, eye1, at1, north, 1e-4f, 1.0f, 0.05f, 100.0f);
                memset(&f, 0, sizeof f);
                sr_framebuffer_create(&fb, 1, 1, NULL);
                sr_mesh_shell_desc_default(&d);
                d.positions = m.pos; d.normals = m.nrm; d.uvs = m.uv; d.vertex_count = m.nv;
                d.indices = m.idx; d.triangle_count = m.nt; d.height = height; d.sample = first_sample; d.user = &f;
                sr_draw_mesh_shell(&fb, &c1, &d, NULL);
                sr_framebuffer_free(&fb);
            }
            if (!f.have) continue;
            rays++;
            for (k = 0; k < m.nt && !ok; k++) {
                float uvw[3], p[3];
                uvw[0] = (float)f.tile[0] + f.p[0]; uvw[1] = (float)f.tile[1] + f.p[1]; uvw[2] = f.p[2];
                if (tvt_shell_unmap(&s, k, uvw, p) != 1) continue;
                /* float maps of coordinates up to 5 with gains up to 8 (map_tol), and w clamped below 1
                   by 1 ulp: the outer surface within the same */
                ok = fabsf(p[0] - o[0]) <= map_tol(5.0, 8.0) && fabsf(p[1] - o[1]) <= map_tol(5.0, 8.0) &&
                     (fabsf(uvw[2] - 1.0f) <= map_tol(1.0, 8.0) || /* or it enters by the mesh's open border */
                      fabsf(uvw[0]) <= map_tol(4.0, 8.0) || fabsf(uvw[0] - 4.0f) <= map_tol(4.0, 8.0) ||
                      fabsf(uvw[1]) <= map_tol(4.0, 8.0) || fabsf(uvw[1] - 4.0f) <= map_tol(4.0, 8.0));
            }
            found += ok;
        }
    T_CHECK(rays > n * n / 2);
    T_EQ_INT(found, rays);
    tvt_shell_free(&s);
    mesh_free(&m);
}

static int cancel_at_half(void *user, float done) { (void)user; return done >= 0.5f; }

static void test_render_bad_input(void)
{
    mesh m = grid_mesh(4, 1.0f, 0.1f, 0.5f);
    sr_framebuffer fb;
    sr_camera cam;
    sr_mesh_shell_desc d;
    content c = {4.0f, 0.8f, 1.0f / 32.0f, 0, 0, 0};
    float eye[3] = {0.5f, -1.0f, 1.0f}, at[3] = {0.5f, 0.5f, 0.0f}, keep;
    uint32_t ik;
    sr_framebuffer_create(&fb, 16, 12, NULL);
    sr_camera_look_at(&cam, eye, at, NULL, 50.0f, 16.0f / 12.0f, 0.05f, 10.0f);
    sr_mesh_shell_desc_default(&d);
    d.positions = m.pos; d.normals = m.nrm; d.uvs = m.uv; d.vertex_count = m.nv;
    d.indices = m.idx; d.triangle_count = m.nt; d.height = 0.2f; d.sample = fibres; d.user = &c;
    T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_OK);
    T_EQ_INT(sr_draw_mesh_shell(NULL, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.sample = NULL; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT); d.sample = fibres;
    keep = m.pos[7]; m.pos[7] = NAN; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT); m.pos[7] = keep;
    keep = m.uv[7]; m.uv[7] = INFINITY; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT); m.uv[7] = keep;
    ik = m.idx[5]; m.idx[5] = 1000; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    m.idx[5] = m.idx[4]; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT); m.idx[5] = ik;
    d.height = 0.0f; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.height = NAN; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.height = 0.2f;
    d.depth = -1.0f; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT); d.depth = 0.0f;
    d.triangle_count = 0; T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT); d.triangle_count = m.nt;
    { /* allocation failure at every k, and a cancel: the named result, nothing leaked */
        counting cnt;
        sr_allocator a;
        long k;
        int all = 1;
        a.alloc = c_alloc; a.free = c_free; a.user = &cnt;
        d.allocator = &a;
        for (k = 1; k < 20; k++) {
            sr_result r;
            memset(&cnt, 0, sizeof cnt); cnt.fail_at = k;
            r = sr_draw_mesh_shell(&fb, &cam, &d, NULL);
            if (r == SR_OK) { all &= cnt.live == 0; break; }
            all &= r == SR_ERR_OUT_OF_MEMORY && cnt.live == 0;
        }
        T_CHECK(all && k > 3);
        memset(&cnt, 0, sizeof cnt);
        d.progress = cancel_at_half;
        T_EQ_INT(sr_draw_mesh_shell(&fb, &cam, &d, NULL), SR_CANCELLED);
        T_EQ_INT(cnt.live, 0);
        T_CHECK(cnt.calls > 0);
    }
    sr_framebuffer_free(&fb);
    mesh_free(&m);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    test_continuity();
    test_round_trip();
    test_flat_is_height_field();
    test_folded();
    test_bad_input();
    test_wd_map();
    test_flat_against_height_field();
    test_sphere();
    test_grass_mesh_against_terrain();
    test_horizon();
    test_folded_render();
    test_same_map();
    test_render_bad_input();
    return T_END();
}
