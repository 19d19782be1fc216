/* bench_texel - texel.h: the paper's timing case (a 256^3 texel of 100 blades: sampling, one
   simulation step, splatting, the key frame's bytes) and the mountain of 2.56M blades at 800x600.
   No peer: no library ages grass (the paper's own figures are in bench/README.md).

   usage: bench_texel [ignored mesh path] [--no-render] [--mesh-only]

   Figures (details and timed regions in bench/README.md):
     RESULT texel res=256 blades=100 points=<n> sample_ms=<t> step_ms=<t> splat_ms=<t> keyframe_mb=<m> ...
     RESULT texel_render scene=mountain width=800 height=600 blades=2560000 coverage=<c> render_ms=<t> peak_mb=<m>
     RESULT texel_render_lod1 ... the same with LOD levels one step coarser (grass --lod-bias 1)
     RESULT texel_render scene=mesh mesh=sphere width=800 height=600 triangles=<n> blades=<n> coverage=<c> render_ms=<t> peak_mb=<m>
       grass over a cube-sphere's mesh shell (grass --mesh sphere --wd 0.45), median of 5
   Each figure: one warm-up run, then the median of 11 with its min and max (bench.h's
   bench_interleave, one side), one thread. sample_cold_ms is the process's first tvt_sample
   (fresh heap pages: the page faults of the points array are in it), before the warm-up. */
#include "bench.h"

#define GRASS_NO_MAIN
#include "../examples/grass.c"

/* one warm-up, then BENCH_INTERLEAVED_RUNS (11) timed runs of run(user) (bench.h's
   bench_interleave with one side); after(user) outside the timer. Returns 0 if a run failed. */
static int measure(bench_side *s, const char *name, int (*run)(void *), void (*after)(void *), void *user)
{
    *s = bench_make_side(name, run, after, user);
    return bench_interleave(s, 1, 0) == 0;
}

typedef struct texel_case {
    tvt_texel grass, frame;
    tvt_points pts, base, aged;
    tvt_lod lod;
} texel_case;

static int run_sample(void *u) { texel_case *c = (texel_case *)u; return tvt_sample(&c->grass, NULL, &c->pts) != TVT_OK; }
static void after_sample(void *u) { tvt_points_free(&((texel_case *)u)->pts); }

/* the step from wd 0.45 to 0.5 (shrink, droop, colour, merge), on a fresh copy each time */
static int copy_points(const tvt_points *from, tvt_points *to)
{
    *to = *from;
    to->p = (tvt_point *)malloc(from->count * sizeof(tvt_point));
    if (!to->p) return 0;
    memcpy(to->p, from->p, from->count * sizeof(tvt_point)); /* the default allocator is malloc's */
    return 1;
}
static int run_step(void *u)
{
    texel_case *c = (texel_case *)u;
    return tvt_age(&c->pts, 0.5f, NULL) != TVT_OK;
}
static void after_step(void *u)
{
    texel_case *c = (texel_case *)u;
    free(c->pts.p);
    copy_points(&c->base, &c->pts);
}
static int run_splat(void *u) { texel_case *c = (texel_case *)u; return tvt_splat(&c->aged, NULL, &c->frame) != TVT_OK; }
static void after_splat(void *u) { tvt_texel_free(&((texel_case *)u)->frame); }

static int bench_texel_case(void)
{
    texel_case c;
    tvt_grass_desc d = tvt_grass_default_desc();
    bench_side ts, tp, tl;
    size_t points;
    double cold;
    memset(&c, 0, sizeof(c));
    d.res = 256; d.blade_count = 100; d.seed = 1; /* radius 1.5 voxels, heights 0.55..0.9 of res */
    fprintf(stderr, "bench_texel: building the 256^3 texel\n");
    if (tvt_build_grass(&d, &c.grass) != TVT_OK) return 0;
    cold = bench_now();
    if (run_sample(&c)) return 0;
    cold = bench_now() - cold;
    after_sample(&c);
    if (!measure(&ts, "sample", run_sample, after_sample, &c)) return 0;
    if (tvt_sample(&c.grass, NULL, &c.base) != TVT_OK || tvt_age(&c.base, 0.45f, NULL) != TVT_OK) return 0;
    points = c.base.count;
    if (!copy_points(&c.base, &c.pts)) return 0;
    fprintf(stderr, "bench_texel: step\n");
    if (!measure(&tp, "step", run_step, after_step, &c)) return 0;
    if (!copy_points(&c.base, &c.aged) || tvt_age(&c.aged, 0.5f, NULL) != TVT_OK) return 0;
    fprintf(stderr, "bench_texel: splat\n");
    if (!measure(&tl, "splat", run_splat, after_splat, &c)) return 0;
    if (tvt_splat(&c.aged, NULL, &c.frame) != TVT_OK || tvt_build_lod(&c.frame, NULL, &c.lod) != TVT_OK) return 0;
    printf("RESULT texel res=256 blades=100 points=%zu", points);
    bench_print_ms("sample", &ts);
    bench_print_ms("step", &tp);
    bench_print_ms("splat", &tl);
    printf(" keyframe_mb=%.2f sample_cold_ms=%.2f static_mb=%.2f levels=%d point_bytes=%zu\n", tvt_lod_bytes(&c.lod) / 1048576.0,
           1e3 * cold, tvt_texel_bytes(&c.grass) / 1048576.0, c.lod.levels, sizeof(tvt_point));
    tvt_lod_free(&c.lod);
    tvt_texel_free(&c.frame);
    free(c.pts.p);
    free(c.aged.p);
    tvt_points_free(&c.base);
    tvt_texel_free(&c.grass);
    return 1;
}

typedef struct render_case {
    scene s;
    grass_set g;
    sr_image8 img;
    double coverage;
} render_case;

/* timed: the shadow volumes of the four variants at wd 0.30, then the 800x600 image */
static int run_render(void *u)
{
    render_case *c = (render_case *)u;
    if (!build_shadows(&c->g, c->s.sun)) return 1;
    c->coverage = render(&c->s, 800, 600, &c->img, "bench_texel: mountain");
    return c->coverage < 0;
}
static void after_render(void *u) { render_case *c = (render_case *)u; free(c->img.pixels); c->img.pixels = NULL; }

static int bench_render(void)
{
    render_case c;
    bench_side t;
    int ok;
    memset(&c, 0, sizeof(c));
    quiet = 1;
    fprintf(stderr, "bench_texel: building the mountain's TVTs\n");
    if (!mountain_setup(&c.s, &c.g, 64, 80, 6, 2010)) return 0;
    c.s.wd = 0.30f;
    bench_reset_peak_rss(); /* peak_mb: the process's high-water mark from here (TVTs included) */
    fprintf(stderr, "bench_texel: rendering 12 times\n");
    ok = measure(&t, "render", run_render, after_render, &c);
    if (ok) {
        printf("RESULT texel_render scene=mountain width=800 height=600 blades=2560000 coverage=%.3f", c.coverage);
        bench_print_ms("render", &t);
        printf(" peak_mb=%.1f tvt_mb=%.2f\n", bench_peak_rss_kb() / 1024.0,
           (tvt_tvt_bytes(&c.g.variant[0]) + tvt_tvt_bytes(&c.g.variant[1]) + tvt_tvt_bytes(&c.g.variant[2]) +
            tvt_tvt_bytes(&c.g.variant[3])) / 1048576.0);
        /* the same with levels one step coarser than the footprint asks (grass --lod-bias 1) */
        c.s.lod_scale = 2.0f;
        fprintf(stderr, "bench_texel: rendering 12 times with --lod-bias 1\n");
        ok = measure(&t, "render", run_render, after_render, &c);
        if (ok) {
            printf("RESULT texel_render_lod1 scene=mountain width=800 height=600 blades=2560000 coverage=%.3f", c.coverage);
            bench_print_ms("render", &t);
            printf("\n");
        }
    }
    free(c.s.h);
    free_set(&c.g);
    return ok;
}

typedef struct mesh_case {
    scene s;
    grass_set g;
    gmesh m;
    float height;
    sr_image8 img;
    double coverage;
    long tiles;
} mesh_case;

/* timed: the variants' shadow volumes, the per-tile wd map, then the 800x600 image */
static int run_mesh(void *u)
{
    mesh_case *c = (mesh_case *)u;
    const float zenith[3] = {0, 0, 1};
    tile_map tm;
    if (!build_shadows(&c->g, zenith) || !make_tile_map(&c->m, &c->s, 0.9f, NULL, &tm)) return 1;
    c->tiles = tm.covered;
    c->coverage = render_mesh(&c->s, &c->m, c->height, &tm.m, 800, 600, &c->img, "bench_texel: mesh");
    free(tm.wd);
    return c->coverage < 0;
}
static void after_mesh(void *u) { mesh_case *c = (mesh_case *)u; free(c->img.pixels); c->img.pixels = NULL; }

/* grass over the cube-sphere's shell (grass --mesh sphere --wd 0.45 at 800x600): one warm-up,
   the median of 5 */
static int bench_mesh(void)
{
    mesh_case c;
    bench_side t;
    int ok;
    memset(&c, 0, sizeof(c));
    quiet = 1;
    fprintf(stderr, "bench_texel: building the mesh scene's TVTs\n");
    if (!mesh_setup(&c.s, &c.m, &c.height, "sphere", 40, 64) || !mesh_grass(&c.s, &c.g, 64, 6, 2010)) return 0;
    c.s.wd = 0.45f;
    bench_reset_peak_rss();
    fprintf(stderr, "bench_texel: rendering the mesh scene 6 times\n");
    t = bench_make_side("render", run_mesh, after_mesh, &c);
    ok = bench_interleave(&t, 1, 5) == 0;
    if (ok) {
        printf("RESULT texel_render scene=mesh mesh=sphere width=800 height=600 triangles=%zu blades=%ld coverage=%.3f",
               c.m.nt, 400 * c.tiles, c.coverage);
        bench_print_ms("render", &t);
        printf(" peak_mb=%.1f\n", bench_peak_rss_kb() / 1024.0);
    }
    gmesh_free(&c.m);
    free_set(&c.g);
    return ok;
}

int main(int argc, char **argv)
{
    int i, do_texel = 1, do_render = 1, do_mesh = 1;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--no-render")) do_render = do_mesh = 0;
        if (!strcmp(argv[i], "--mesh-only")) do_texel = do_render = 0;
    }
    BENCH_PRINT_FLAGS("bench_texel");
    if (do_texel && !bench_texel_case()) { fprintf(stderr, "bench_texel: the texel case failed\n"); return 1; }
    if (do_render && !bench_render()) { fprintf(stderr, "bench_texel: the render failed\n"); return 1; }
    if (do_mesh && !bench_mesh()) { fprintf(stderr, "bench_texel: the mesh render failed\n"); return 1; }
    return 0;
}
