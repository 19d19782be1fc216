/* bench_texel - texel.h: the paper's timing case (a 256^3 texel of 100 blades: sampling, one
   simulation step, splatting, the key frame's bytes) and the mountain of 2.56M blades at 800x600.
   No peer: no library ages grass (the paper's own figures are in bench/README.md).

   usage: bench_texel [ignored mesh path] [--no-render]

   Figures (details and timed regions in bench/README.md):
     RESULT texel res=256 blades=100 points=<n> sample_ms=<t> step_ms=<t> splat_ms=<t> keyframe_mb=<m> ...
     RESULT texel_render scene=mountain width=800 height=600 blades=2560000 coverage=<c> render_ms=<t> peak_mb=<m>
   Each figure: one warm-up run, then the median of 5 (min and max beside it), one thread. */
#include "bench.h"

#define GRASS_NO_MAIN
#include "../examples/grass.c"

#define RUNS 5

typedef struct timing { double median, lo, hi; } timing;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* one warm-up, then RUNS timed runs of run(user); after(user) outside the timer */
static timing measure(int (*run)(void *), void (*after)(void *), void *user)
{
    double t[RUNS];
    timing r = {-1, -1, -1};
    int i;
    for (i = 0; i <= RUNS; i++) {
        double start = bench_now(), el;
        int failed = run(user);
        el = bench_now() - start;
        if (after) after(user);
        if (failed) return r;
        if (i > 0) t[i - 1] = el;
    }
    qsort(t, RUNS, sizeof(double), cmp_double);
    r.median = 1e3 * t[RUNS / 2]; r.lo = 1e3 * t[0]; r.hi = 1e3 * t[RUNS - 1];
    return r;
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
    timing ts, tp, tl;
    size_t points;
    memset(&c, 0, sizeof(c));
    d.res = 256; d.blade_count = 100; d.seed = 1; /* radius 1.5 voxels, heights 0.55..0.9 of res */
    fprintf(stderr, "bench_texel: building the 256^3 texel\n");
    if (tvt_build_grass(&d, &c.grass) != TVT_OK) return 0;
    ts = measure(run_sample, after_sample, &c);
    if (tvt_sample(&c.grass, NULL, &c.base) != TVT_OK || tvt_age(&c.base, 0.45f, NULL) != TVT_OK) return 0;
    points = c.base.count;
    if (!copy_points(&c.base, &c.pts)) return 0;
    fprintf(stderr, "bench_texel: step\n");
    tp = measure(run_step, after_step, &c);
    if (!copy_points(&c.base, &c.aged) || tvt_age(&c.aged, 0.5f, NULL) != TVT_OK) return 0;
    fprintf(stderr, "bench_texel: splat\n");
    tl = measure(run_splat, after_splat, &c);
    if (tvt_splat(&c.aged, NULL, &c.frame) != TVT_OK || tvt_build_lod(&c.frame, NULL, &c.lod) != TVT_OK) return 0;
    printf("RESULT texel res=256 blades=100 points=%zu sample_ms=%.2f step_ms=%.2f splat_ms=%.2f keyframe_mb=%.2f "
           "sample_range=%.2f-%.2f step_range=%.2f-%.2f splat_range=%.2f-%.2f static_mb=%.2f levels=%d\n",
           points, ts.median, tp.median, tl.median, tvt_lod_bytes(&c.lod) / 1048576.0, ts.lo, ts.hi, tp.lo, tp.hi,
           tl.lo, tl.hi, tvt_texel_bytes(&c.grass) / 1048576.0, c.lod.levels);
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
    timing t;
    memset(&c, 0, sizeof(c));
    quiet = 1;
    fprintf(stderr, "bench_texel: building the mountain's TVTs\n");
    if (!mountain_setup(&c.s, &c.g, 64, 80, 6, 2010)) return 0;
    c.s.wd = 0.30f;
    bench_reset_peak_rss(); /* peak_mb: the process's high-water mark from here (TVTs included) */
    fprintf(stderr, "bench_texel: rendering 6 times\n");
    t = measure(run_render, after_render, &c);
    printf("RESULT texel_render scene=mountain width=800 height=600 blades=2560000 coverage=%.3f render_ms=%.0f "
           "render_range=%.0f-%.0f peak_mb=%.1f tvt_mb=%.2f\n",
           c.coverage, t.median, t.lo, t.hi, bench_peak_rss_kb() / 1024.0,
           (tvt_tvt_bytes(&c.g.variant[0]) + tvt_tvt_bytes(&c.g.variant[1]) + tvt_tvt_bytes(&c.g.variant[2]) +
            tvt_tvt_bytes(&c.g.variant[3])) / 1048576.0);
    free(c.s.h);
    free_set(&c.g);
    return t.median >= 0;
}

int main(int argc, char **argv)
{
    int i, do_render = 1;
    for (i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--no-render")) do_render = 0;
    BENCH_PRINT_FLAGS("bench_texel");
    if (!bench_texel_case()) { fprintf(stderr, "bench_texel: the texel case failed\n"); return 1; }
    if (do_render && !bench_render()) { fprintf(stderr, "bench_texel: the render failed\n"); return 1; }
    return 0;
}
