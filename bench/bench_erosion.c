/* bench_erosion - erosion.h: one erosion step against the memory-bandwidth floor of a step.

   usage: bench_erosion [MESH] [--res N]...
     MESH     the mesh whose displacement map is the surface grid (default the glmark2 bunny; made
              through dispmesh.h: dm_simplify to 500 triangles, dm_parameterize, dm_bake)
     --res N  a resolution to measure (repeatable; default 1024 and 4096)
   For each resolution, for a height field and for MESH's map:
     RESULT erosion domain=<heightfield|surface> res=<n> step_ms=<t> stream_ms=<t> ratio=<step/stream>
            call_ms=<t>
   step_ms: one step on a reused workspace (a 4-step ero_erode_ws call divided by 4, the
   workspace made once per grid outside the timer: the per-call disp, option and material checks
   spread over the steps); stream_ms: one plain loop over exactly the arrays a step must touch
   (height field: height and a 1-byte material id; surface: pos, nrm, disp, area, valid, nbr,
   nbr_rot, material id), writing disp once; call_ms: one 4-step ero_erode call divided by 4 (the
   one-call form: the input checks, scratch and tables of the workspace made and freed inside
   it). The three interleaved with bench_interleave, one thread.
   Fixed parameters (bench/README.md): normal-averaging radius 2 texels and filter sigma 1 texel at
   1024^2 (the same world lengths at 4096^2), wind (1, 0.3, -1), one material {1, 4}.
   mk/erosion.mk builds it with erosion.h's ERO_USE_AVX2 and -mavx2 where the CPU has AVX2 (the
   stream loop in the same binary); the flags are the first RESULT line. */
#include "bench.h"
#define ERO_IMPLEMENTATION
#include "erosion.h"
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#include <math.h>

enum { STEPS = 4 };

typedef struct bench_case {
    ero_grid g;
    ero_options o;
    float *disp0;   /* the map before (restored after each timed run) */
    uint8_t *mat;
    size_t n;
    ero_workspace *ws;  /* made once per grid, outside the timer */
    volatile float zero; /* 0 at run time: the stream loop reads every array, the compiler cannot drop it */
} bench_case;

static int run_step(void *user)
{
    bench_case *c = (bench_case *)user;
    return ero_erode_ws(c->ws, &c->g, c->mat, NULL, 0, STEPS, &c->o, NULL, NULL) != ERO_OK;
}
static int run_call(void *user)
{
    bench_case *c = (bench_case *)user;
    return ero_erode(&c->g, c->mat, NULL, 0, STEPS, &c->o, NULL, NULL) != ERO_OK;
}
static void after_step(void *user)
{
    bench_case *c = (bench_case *)user;
    memcpy(c->g.disp, c->disp0, c->n * sizeof(float));
}

static int run_stream(void *user)
{
    bench_case *c = (bench_case *)user;
    float z = c->zero, *d = c->g.disp;
    size_t i, n = c->n;
    int k;
    for (k = 0; k < STEPS; k++) { /* as many passes as steps: the figure is per step */
        if (c->g.domain == ERO_HEIGHTFIELD) {
            for (i = 0; i < n; i++) d[i] = d[i] + z * (float)c->mat[i];
        } else {
            const float *p = c->g.pos, *q = c->g.nrm, *a = c->g.area;
            const uint32_t *nb = c->g.nbr;
            const uint8_t *r = c->g.nbr_rot, *v = c->g.valid;
            for (i = 0; i < n; i++) {
                float s = p[3 * i] + p[3 * i + 1] + p[3 * i + 2] + q[3 * i] + q[3 * i + 1] + q[3 * i + 2] + a[i] +
                          (float)v[i] + (float)c->mat[i] + (float)(nb[4 * i] ^ nb[4 * i + 1] ^ nb[4 * i + 2] ^ nb[4 * i + 3]) +
                          (float)(r[4 * i] + r[4 * i + 1] + r[4 * i + 2] + r[4 * i + 3]);
                d[i] = d[i] + z * s;
            }
        }
    }
    return 0;
}

static void measure(bench_case *c, const char *domain, int res)
{
    bench_side s[3];
    int k;
    c->disp0 = (float *)malloc(c->n * sizeof(float));
    c->mat = (uint8_t *)calloc(c->n, 1);
    if (!c->disp0 || !c->mat) { fprintf(stderr, "bench_erosion: out of memory\n"); exit(1); }
    memcpy(c->disp0, c->g.disp, c->n * sizeof(float));
    if (ero_workspace_create(&c->g, &c->o, &c->ws) != ERO_OK) { fprintf(stderr, "bench_erosion: no workspace\n"); exit(1); }
    s[0] = bench_make_side("step", run_step, after_step, c);
    s[1] = bench_make_side("stream", run_stream, after_step, c);
    s[2] = bench_make_side("call", run_call, after_step, c);
    fprintf(stderr, "bench_erosion: %s %d^2\n", domain, res);
    if (bench_interleave(s, 3, 0) != 0) { fprintf(stderr, "bench_erosion: a run failed\n"); exit(1); }
    for (k = 0; k < 3; k++) { /* per step */
        s[k].median /= STEPS; s[k].min /= STEPS; s[k].max /= STEPS;
        for (int j = 0; j < s[k].runs; j++) s[k].samples[j] /= STEPS;
    }
    printf("RESULT erosion domain=%s res=%d", domain, res);
    bench_print_ms("step", &s[0]);
    bench_print_ms("stream", &s[1]);
    bench_print_ratio(&s[0], &s[1]);
    bench_print_ms("call", &s[2]);
    printf("\n");
    fflush(stdout);
    ero_workspace_destroy(c->ws);
    free(c->disp0);
    free(c->mat);
}

static void set_options(bench_case *c, double texel_1024)
{
    c->o = ero_default_options();
    c->o.wind[0] = 1.0f; c->o.wind[1] = 0.3f; c->o.wind[2] = -1.0f;
    c->o.normal_radius = (float)(2.0 * texel_1024);
    c->o.filter_sigma = (float)(1.0 * texel_1024);
    c->zero = 0.0f;
}

static void bench_heightfield(int res)
{
    bench_case c;
    float *h;
    size_t x, y, n = (size_t)res * res;
    memset(&c, 0, sizeof c);
    h = (float *)malloc(n * sizeof(float));
    if (!h) exit(1);
    for (y = 0; y < (size_t)res; y++)
        for (x = 0; x < (size_t)res; x++) {
            double px = (x + 0.5) / res, py = (y + 0.5) / res;
            h[y * res + x] = (float)(0.02 * sin(12.566 * px) * cos(18.85 * py) + 0.005 * sin(50.27 * px + 31.4 * py));
        }
    c.g = ero_heightfield_grid(res, res, h, 1.0f / res, 1);
    c.n = n;
    set_options(&c, 1.0 / 1024);
    measure(&c, "heightfield", res);
    free(h);
}

static void bench_surface(const mio_mesh *m, int res)
{
    bench_case c;
    dm_simplify_options so;
    dm_param_options po;
    dm_pm *pm = NULL;
    dm_param *param = NULL;
    dm_dispmap *map = NULL;
    float *bp = NULL;
    uint32_t *bi = NULL;
    size_t bnv, bnt, i, nv = 0;
    double area = 0.0;
    memset(&c, 0, sizeof c);
    memset(&so, 0, sizeof so);
    so.target_triangles = 500;
    so.min_quality = 0.1f;
    memset(&po, 0, sizeof po);
    po.width = po.height = res;
    fprintf(stderr, "bench_erosion: the %d^2 map (dm_simplify, dm_parameterize, dm_bake)\n", res);
    if (dm_simplify(m->positions, m->vertex_count, m->indices, m->triangle_count, &so, &pm, NULL) != DM_OK) exit(1);
    dm_pm_counts(pm, &bnv, &bnt);
    bp = (float *)malloc(3 * bnv * sizeof(float));
    bi = (uint32_t *)malloc(3 * bnt * sizeof(uint32_t));
    dm_pm_get_mesh(pm, bp, bi, NULL);
    if (dm_parameterize(bp, bnv, bi, bnt, &po, &param) != DM_OK) exit(1);
    if (dm_bake(param, bp, bnv, bi, bnt, m->positions, m->vertex_count, m->indices, m->triangle_count, NULL, &map) != DM_OK)
        exit(1);
    c.g = ero_surface_grid(map->width, map->height, map->pos, map->nrm, map->disp, map->area, map->valid, map->nbr,
                           map->nbr_rot);
    c.n = (size_t)res * res;
    for (i = 0; i < c.n; i++)
        if (map->valid[i]) { area += map->area[i]; nv++; }
    /* the texel size at 1024^2: this map's texel size times res / 1024 */
    set_options(&c, sqrt(area / (double)nv) * res / 1024.0);
    measure(&c, "surface", res);
    dm_dispmap_free(map);
    dm_param_free(param);
    dm_pm_free(pm);
    free(bp);
    free(bi);
}

int main(int argc, char **argv)
{
    const char *mesh_path = "/usr/share/glmark2/models/bunny.obj";
    int res[8], nres = 0, k;
    mio_mesh m;
    mio_error err;
    for (k = 1; k < argc; k++) {
        if (strcmp(argv[k], "--res") == 0 && k + 1 < argc && nres < 8) res[nres++] = atoi(argv[++k]);
        else mesh_path = argv[k];
    }
    if (nres == 0) { res[0] = 1024; res[1] = 4096; nres = 2; }
    BENCH_PRINT_FLAGS("bench_erosion");
    for (k = 0; k < nres; k++) bench_heightfield(res[k]);
    if (mio_read_file(mesh_path, NULL, &m, &err) != MIO_OK || mio_weld(&m, &err) != MIO_OK) {
        fprintf(stderr, "bench_erosion: cannot read %s: %s (the bunny: apt-get install glmark2-data)\n", mesh_path, err.message);
        return 1;
    }
    for (k = 0; k < nres; k++) bench_surface(&m, res[k]);
    mio_free_mesh(&m);
    return 0;
}
