/* testmesh.h - generated test meshes shared by the dispmesh tests (C99): a bumpy cube-sphere
   (closed, genus 0), a bumpy torus (genus 1), an open bumpy sheet with an optional hole; and a
   counting allocator that fails on request. */
#ifndef TESTMESH_H
#define TESTMESH_H
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct mesh {
    float *p;
    uint32_t *t;
    size_t nv, nt;
} mesh;

static inline void mesh_free(mesh *m) { free(m->p); free(m->t); m->p = NULL; m->t = NULL; }

static inline double bump_sphere(const double d[3], double amp)
{
    return 1.0 + amp * sin(5.0 * d[0]) * sin(5.0 * d[1]) * sin(5.0 * d[2]);
}

/* cube-sphere: n x n quads per cube face, projected to radius(dir); or, when groove > 0, the
   cube [-1,1]^3 itself (scale ignored) with grooves pressed in by `groove` along every face normal
   at the grid lines through the middle (n even): a box with sharp edges and narrow channels. */
static inline mesh make_cube_grid(int n, double amp, double scale, double groove);
static inline mesh make_sphere(int n, double amp, double scale) { return make_cube_grid(n, amp, scale, 0.0); }
static inline mesh make_grooved_box(int n, double groove) { return make_cube_grid(n, 0.0, 1.0, groove); }
static inline mesh make_cube_grid(int n, double amp, double scale, double groove)
{
    mesh m;
    int N = n + 1, i, j, k, f;
    size_t cells = (size_t)N * N * N;
    uint32_t *id = (uint32_t *)malloc(cells * sizeof(uint32_t));
    m.p = (float *)malloc(cells * 3 * sizeof(float));
    m.t = (uint32_t *)malloc((size_t)12 * n * n * 3 * sizeof(uint32_t));
    m.nv = 0;
    m.nt = 0;
    for (i = 0; i < N; i++)
        for (j = 0; j < N; j++)
            for (k = 0; k < N; k++) {
                size_t c = ((size_t)i * N + j) * N + k;
                id[c] = 0xffffffffu;
                if (i == 0 || j == 0 || k == 0 || i == n || j == n || k == n) {
                    double d[3] = {2.0 * i / n - 1.0, 2.0 * j / n - 1.0, 2.0 * k / n - 1.0}, l, r;
                    if (groove > 0.0) {
                        int g[3] = {i, j, k}, a;
                        if (i == n / 2 || j == n / 2 || k == n / 2)
                            for (a = 0; a < 3; a++) {
                                if (g[a] == 0) d[a] += groove;
                                if (g[a] == n) d[a] -= groove;
                            }
                        l = 1.0;
                        r = 1.0;
                    } else {
                        l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                        d[0] /= l; d[1] /= l; d[2] /= l;
                        r = scale * bump_sphere(d, amp);
                    }
                    m.p[3 * m.nv] = (float)(r * d[0]);
                    m.p[3 * m.nv + 1] = (float)(r * d[1]);
                    m.p[3 * m.nv + 2] = (float)(r * d[2]);
                    id[c] = (uint32_t)m.nv++;
                }
            }
    /* each face: axis a fixed at 0 or n; (u, v) over the other two, oriented outward */
    for (f = 0; f < 6; f++) {
        int a = f / 2, hi = f % 2, u, v, ua = (a + 1) % 3, va = (a + 2) % 3;
        for (u = 0; u < n; u++)
            for (v = 0; v < n; v++) {
                uint32_t q[4];
                int c, co[3];
                for (c = 0; c < 4; c++) {
                    co[a] = hi ? n : 0;
                    co[ua] = u + (c == 1 || c == 2);
                    co[va] = v + (c == 2 || c == 3);
                    q[c] = id[((size_t)co[0] * N + co[1]) * N + co[2]];
                }
                if (hi) {
                    uint32_t *o = m.t + 3 * m.nt;
                    o[0] = q[0]; o[1] = q[1]; o[2] = q[2]; o[3] = q[0]; o[4] = q[2]; o[5] = q[3];
                } else {
                    uint32_t *o = m.t + 3 * m.nt;
                    o[0] = q[0]; o[1] = q[2]; o[2] = q[1]; o[3] = q[0]; o[4] = q[3]; o[5] = q[2];
                }
                m.nt += 2;
            }
    }
    free(id);
    return m;
}

/* torus R = 1, tube radius r(angle) = r0 (1 + amp bumps), U x V quads */
static inline mesh make_torus(int U, int V, double r0, double amp)
{
    mesh m;
    int i, j;
    m.nv = (size_t)U * V;
    m.nt = 2 * m.nv;
    m.p = (float *)malloc(m.nv * 3 * sizeof(float));
    m.t = (uint32_t *)malloc(m.nt * 3 * sizeof(uint32_t));
    for (i = 0; i < U; i++)
        for (j = 0; j < V; j++) {
            double a = 6.283185307179586 * i / U, b = 6.283185307179586 * j / V;
            double r = r0 * (1.0 + amp * sin(7.0 * a) * sin(3.0 * b));
            float *p = m.p + 3 * ((size_t)i * V + j);
            p[0] = (float)((1.0 + r * cos(b)) * cos(a));
            p[1] = (float)((1.0 + r * cos(b)) * sin(a));
            p[2] = (float)(r * sin(b));
        }
    for (i = 0; i < U; i++)
        for (j = 0; j < V; j++) {
            uint32_t q0 = (uint32_t)(i * V + j), q1 = (uint32_t)(((i + 1) % U) * V + j);
            uint32_t q2 = (uint32_t)(((i + 1) % U) * V + (j + 1) % V), q3 = (uint32_t)(i * V + (j + 1) % V);
            uint32_t *o = m.t + 6 * ((size_t)i * V + j);
            o[0] = q0; o[1] = q1; o[2] = q2; o[3] = q0; o[4] = q2; o[5] = q3;
        }
    return m;
}

/* sheet over [-1,1]^2 at height z0 + amp bumps, n x n quads; hole: drop quads within radius */
static inline mesh make_sheet(int n, double z0, double amp, double hole)
{
    mesh m;
    int i, j;
    m.nv = (size_t)(n + 1) * (n + 1);
    m.p = (float *)malloc(m.nv * 3 * sizeof(float));
    m.t = (uint32_t *)malloc((size_t)n * n * 6 * sizeof(uint32_t));
    m.nt = 0;
    for (i = 0; i <= n; i++)
        for (j = 0; j <= n; j++) {
            double x = 2.0 * i / n - 1.0, y = 2.0 * j / n - 1.0;
            float *p = m.p + 3 * ((size_t)i * (n + 1) + j);
            p[0] = (float)x;
            p[1] = (float)y;
            p[2] = (float)(z0 + amp * sin(4.0 * x) * cos(3.0 * y));
        }
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) {
            double cx = 2.0 * (i + 0.5) / n - 1.0, cy = 2.0 * (j + 0.5) / n - 1.0;
            uint32_t q0 = (uint32_t)(i * (n + 1) + j), q1 = q0 + (uint32_t)(n + 1), q2 = q1 + 1, q3 = q0 + 1;
            uint32_t *o = m.t + 3 * m.nt;
            if (sqrt(cx * cx + cy * cy) < hole) continue;
            o[0] = q0; o[1] = q1; o[2] = q2; o[3] = q0; o[4] = q2; o[5] = q3;
            m.nt += 2;
        }
    return m;
}

/* an allocator that fails from the fail_at-th call on and counts what is outstanding */
typedef struct counting { long calls, fail_at, live; } counting;
static inline void *c_alloc(void *u, size_t s)
{
    counting *c = (counting *)u;
    void *p;
    if (c->calls++ >= c->fail_at) return NULL;
    p = malloc(s);
    if (p) c->live++;
    return p;
}
static inline void c_free(void *u, void *p)
{
    counting *c = (counting *)u;
    if (p) { c->live--; free(p); }
}

#endif
