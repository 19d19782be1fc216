/* bench_dispmesh.cpp - dispmesh.h part 3: parameterize a base mesh and bake a displacement map.

   The base mesh is meshopt_simplify of the input to 500 triangles (issue 8's bunny figure; the
   base is not a bounding shell, so rays go both ways, as dm_bake always looks). Then:
     RESULT dispmesh_param res=<r> base_tris=<n> charts=<n> ms=<t> utilization=<u> stretch_l2=<s> area_ok=<f>
     RESULT dispmesh_bake res=<r> orig_tris=<n> ms=<t> mtexels=<texels per s / 1e6> hits=<n> misses=<n>
     RESULT dispmesh_recon res=<r> ms=<t> rms=<e> max=<e> base_only_rms=<e> base_only_max=<e>
   Timed (bench_interleave: a warm-up, then the median and min-max of 11 runs, one thread):
   dm_parameterize alone; dm_bake alone (its BVH build over the original included), interleaved
   with the same bake on plain malloc; dm_reconstruct alone. With bench.h's huge-page
   allocator (as dispmesh.h recommends on Linux; a bake touches ~70 MB of fresh memory at 1024^2);
     RESULT dispmesh_bake_malloc res=<r> ms=<t>   the bake with plain malloc (NULL allocator).
     RESULT dispmesh_base target=<n> faces=<n> shell_ms=<t> constrained_ms=<t> unconstrained_ms=<t> ...
                  paper 000's base (bounding shell + constrained simplification) at 500 faces and at
                  1% of the input's, any size (see bench_base). The distances (dm_surface_distance,
   200k samples a side, fraction of the diagonal) are computed once, outside the timer. There is
   no peer library for the bake as a whole; bench_bvh compares the bake rays with Embree. */
#include "bench.h"

#include <meshoptimizer.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

struct state {
    const float *pos;
    size_t nv, nt;
    const uint32_t *idx;
    std::vector<uint32_t> base;
    int res;
    dm_param *pm = nullptr;
    dm_dispmap *map = nullptr;
    dm_trimesh *rec = nullptr;
    const dm_allocator *alloc = nullptr; /* NULL = malloc, else the huge-page allocator */
};

static int run_param(void *u)
{
    state *s = (state *)u;
    dm_param_options po;
    memset(&po, 0, sizeof po);
    po.width = po.height = s->res;
    po.allocator = s->alloc;
    return dm_parameterize(s->pos, s->nv, s->base.data(), s->base.size() / 3, &po, &s->pm) != DM_OK;
}
static void free_param(void *u) { state *s = (state *)u; dm_param_free(s->pm); s->pm = nullptr; }

static int run_bake(void *u)
{
    state *s = (state *)u;
    dm_bake_options bo;
    memset(&bo, 0, sizeof bo);
    bo.allocator = s->alloc;
    return dm_bake(s->pm, s->pos, s->nv, s->base.data(), s->base.size() / 3, s->pos, s->nv, s->idx, s->nt, &bo,
                   &s->map) != DM_OK;
}
static void free_bake(void *u) { state *s = (state *)u; dm_dispmap_free(s->map); s->map = nullptr; }

static int run_recon(void *u)
{
    state *s = (state *)u;
    return dm_reconstruct(s->map, s->pm, s->pos, s->nv, s->base.data(), s->base.size() / 3, NULL, &s->rec) != DM_OK;
}
static void free_recon(void *u) { state *s = (state *)u; dm_trimesh_free(s->rec); s->rec = nullptr; }

/* ---- paper 000's own base: the bounding shell, then dm_simplify under dm_shell_constraint ---- */
struct base_state {
    const float *pos;
    size_t nv, nt;
    const uint32_t *idx;
    size_t target;
    dm_shell *shell = nullptr;
    dm_pm *pm = nullptr;
    dm_simplify_report rep;
    int constrained = 1;
};
static int run_shell(void *u)
{
    base_state *b = (base_state *)u;
    return dm_shell_grow(b->pos, b->nv, b->idx, b->nt, NULL, &b->shell) != DM_OK;
}
static void free_shell(void *u) { base_state *b = (base_state *)u; dm_shell_free(b->shell); b->shell = nullptr; }
static int run_simplify(void *u)
{
    base_state *b = (base_state *)u;
    dm_simplify_options so;
    memset(&so, 0, sizeof so);
    so.target_triangles = b->target;
    if (b->constrained) { /* as build/dispmesh runs it: the sliver guard, the fallback where the shell is thin */
        so.constraint = dm_shell_constraint;
        so.on_collapse = dm_shell_collapsed;
        so.relax = dm_shell_relax;
        so.min_quality = 0.05f;
        so.constraint_user = b->shell;
    }
    return dm_simplify(b->pos, b->nv, b->idx, b->nt, &so, &b->pm, &b->rep) != DM_OK;
}
static void free_simplify(void *u) { base_state *b = (base_state *)u; dm_pm_free(b->pm); b->pm = nullptr; }
static double base_rms(const base_state *b, dm_pm *pm)
{
    size_t bnv, bnt;
    dm_distance_report r;
    dm_pm_counts(pm, &bnv, &bnt);
    std::vector<float> bp(3 * bnv);
    std::vector<uint32_t> bi(3 * bnt);
    dm_pm_get_mesh(pm, bp.data(), bi.data(), NULL);
    if (dm_surface_distance(b->pos, b->nv, b->idx, b->nt, bp.data(), bnv, bi.data(), bnt, nullptr, &r) != DM_OK) return -1.0;
    return r.rms;
}

/* rounds for a side whose one run took t seconds: 11 below 5 s, 3 below 30 s, else 1 */
static int rounds_for(double t) { return t < 5.0 ? 0 : t < 30.0 ? 3 : 1; }

/*   RESULT dispmesh_base target=<n> faces=<reached> shell_ms= constrained_ms= unconstrained_ms=
            ratio=<constrained / unconstrained time> base_ms=<shell + constrained> peak_mb=
            base_only_rms= unconstrained_rms= rms_ratio= vetoed=
   Each time with its min and max (bench_print_ms): the shell alone; the constrained
   simplification (with a shell grown once outside the timer) interleaved with the unconstrained
   one to the face count the constrained one reached (bench_interleave; fewer rounds when a run
   takes many seconds: *_runs). ratio is the median of the rounds' ratios. peak_mb: the peak
   resident memory of one shell + constrained run above what was resident before. The distances
   (200k samples a side, of the diagonal) once, outside the timers. */
static void bench_base(const float *pos, size_t nv, const uint32_t *idx, size_t nt, size_t target)
{
    base_state b, u;
    b.pos = pos; b.nv = nv; b.idx = idx; b.nt = nt; b.target = target;
    long before = bench_reset_peak_rss() == 0 ? bench_current_rss_kb() : -1;
    double t0 = bench_now();
    if (run_shell(&b)) { fprintf(stderr, "dm_shell_grow failed\n"); return; }
    double t_shell1 = bench_now() - t0;
    t0 = bench_now();
    if (run_simplify(&b)) { fprintf(stderr, "dm_simplify (constrained) failed\n"); free_shell(&b); return; }
    double t_con1 = bench_now() - t0;
    long peak = before >= 0 ? bench_peak_rss_kb() - before : -1;
    dm_pm *con = b.pm;
    dm_simplify_report rep_c = b.rep;
    double rms_c = base_rms(&b, con);
    b.pm = nullptr;
    dm_shell *shell = b.shell;
    b.shell = nullptr;
    bench_side sh = bench_make_side("shell", run_shell, free_shell, &b);
    if (bench_interleave(&sh, 1, rounds_for(t_shell1)) != 0) { fprintf(stderr, "dm_shell_grow failed\n"); return; }
    b.shell = shell;
    u.pos = pos; u.nv = nv; u.idx = idx; u.nt = nt; u.target = rep_c.triangle_count; u.constrained = 0;
    bench_side sides[2];
    sides[0] = bench_make_side("constrained simplification", run_simplify, free_simplify, &b);
    sides[1] = bench_make_side("unconstrained simplification", run_simplify, free_simplify, &u);
    if (bench_interleave(sides, 2, rounds_for(t_con1)) != 0) { fprintf(stderr, "dm_simplify failed\n"); return; }
    double rms_u = -1.0;
    if (!run_simplify(&u)) {
        rms_u = base_rms(&u, u.pm);
        free_simplify(&u);
    }
    printf("RESULT dispmesh_base target=%zu faces=%zu", target, rep_c.triangle_count);
    bench_print_ms("shell", &sh);
    bench_print_ms("constrained", &sides[0]);
    bench_print_ms("unconstrained", &sides[1]);
    bench_print_ratio(&sides[0], &sides[1]);
    if (sides[0].runs < BENCH_INTERLEAVED_RUNS) printf(" runs=%d", sides[0].runs);
    printf(" base_ms=%.1f peak_mb=%.1f base_only_rms=%.3g unconstrained_rms=%.3g rms_ratio=%.2f vetoed=%zu\n",
           1e3 * (sh.median + sides[0].median), peak >= 0 ? peak / 1024.0 : -1.0, rms_c, rms_u,
           rms_u > 0 ? rms_c / rms_u : 0.0, rep_c.vetoed);
    fflush(stdout);
    dm_pm_free(con);
    free_shell(&b);
}

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off";
    int res = 1024, refine = 0, base_only = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--res") && i + 1 < argc) res = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--refine") && i + 1 < argc) refine = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--base-only")) base_only = 1;
        else if (argv[i][0] != '-') path = argv[i];
        else { fprintf(stderr, "usage: bench_dispmesh [MESH] [--res R] [--refine K] [--base-only]\n"); return 2; }
    }
    BENCH_PRINT_FLAGS("bench_dispmesh");
    mio_mesh mesh;
    mio_error err;
    if (mio_read_file(path, NULL, &mesh, &err) != MIO_OK) {
        fprintf(stderr, "%s: %s\n", path, err.message);
        return 1;
    }
    state s;
    s.pos = mesh.positions;
    s.nv = mesh.vertex_count;
    s.idx = mesh.indices;
    s.nt = mesh.triangle_count;
    sd4_mesh fine;
    memset(&fine, 0, sizeof fine);
    if (refine > 0) { /* K butterfly levels (subdiv4.h), e.g. the bunny twice: 1,114,656 triangles */
        if (sd4_butterfly(s.pos, s.nv, s.idx, s.nt, refine, 0.0625, NULL, &fine) != SD4_OK) {
            fprintf(stderr, "sd4_butterfly failed\n");
            return 1;
        }
        s.pos = fine.positions;
        s.nv = fine.vertex_count;
        s.idx = fine.indices;
        s.nt = fine.triangle_count;
    }
    if (base_only) {
        fprintf(stderr, "bench_dispmesh: %s%s, %zu triangles: the base only\n", path, refine ? " refined" : "", s.nt);
        bench_base(s.pos, s.nv, s.idx, s.nt, 500);
        bench_base(s.pos, s.nv, s.idx, s.nt, s.nt / 100);
        sd4_free_mesh(&fine);
        mio_free_mesh(&mesh);
        return 0;
    }
    s.res = res;
    s.base.resize(3 * s.nt);
    float e = 0.0f;
    size_t n = meshopt_simplify(s.base.data(), s.idx, 3 * s.nt, s.pos, s.nv, 3 * sizeof(float), 1500, 1.0f, 0, &e);
    s.base.resize(n);
    fprintf(stderr, "bench_dispmesh: %s, %zu triangles, base %zu triangles, %dx%d map\n", path, s.nt, n / 3, res, res);
    if (n == 0) return 1;

    static const dm_allocator hugepages = {bench_hugepage_alloc, bench_hugepage_free, nullptr};
    s.alloc = &hugepages;
    bench_side one = bench_make_side("dm_parameterize", run_param, free_param, &s);
    if (bench_interleave(&one, 1, 0) != 0 || run_param(&s)) { fprintf(stderr, "dm_parameterize failed\n"); return 1; }
    printf("RESULT dispmesh_param res=%d base_tris=%zu charts=%zu", res, n / 3, s.pm->chart_count);
    bench_print_ms("", &one);
    printf(" utilization=%.3f stretch_l2=%.3f area_ok=%.3f\n", s.pm->utilization, s.pm->stretch_l2, s.pm->area_ratio_ok);

    state m = s; /* the same bake with plain malloc (its own map; the parameterization shared) */
    m.alloc = nullptr;
    m.map = nullptr;
    m.rec = nullptr;
    bench_side bakes[2];
    bakes[0] = bench_make_side("dm_bake", run_bake, free_bake, &s);
    bakes[1] = bench_make_side("dm_bake (malloc)", run_bake, free_bake, &m);
    if (bench_interleave(bakes, 2, 0) != 0 || run_bake(&s)) { fprintf(stderr, "dm_bake failed\n"); return 1; }
    printf("RESULT dispmesh_bake res=%d orig_tris=%zu", res, s.nt);
    bench_print_ms("", &bakes[0]);
    printf(" mtexels=%.3f hits=%zu misses=%zu\n", (double)res * res / bakes[0].median * 1e-6, s.map->hit_count,
           s.map->miss_count);
    printf("RESULT dispmesh_bake_malloc res=%d", res);
    bench_print_ms("", &bakes[1]);
    bench_print_ratio_named("hugepage_ratio", &bakes[0], &bakes[1]);
    printf("\n");
    bench_side rec = bench_make_side("dm_reconstruct", run_recon, free_recon, &s);
    if (bench_interleave(&rec, 1, 0) != 0 || run_recon(&s)) { fprintf(stderr, "dm_reconstruct failed\n"); return 1; }
    dm_distance_report rep, base_rep;
    dm_surface_distance(s.pos, s.nv, s.idx, s.nt, s.rec->positions, s.rec->vertex_count, s.rec->indices,
                        s.rec->triangle_count, nullptr, &rep);
    dm_surface_distance(s.pos, s.nv, s.idx, s.nt, s.pos, s.nv, s.base.data(), n / 3, nullptr, &base_rep);
    printf("RESULT dispmesh_recon res=%d", res);
    bench_print_ms("", &rec);
    printf(" triangles=%zu rms=%.3g max=%.3g base_only_rms=%.3g base_only_max=%.3g\n", s.rec->triangle_count, rep.rms,
           rep.max, base_rep.rms, base_rep.max);
    free_recon(&s);
    free_bake(&s);
    free_param(&s);

    bench_base(s.pos, s.nv, s.idx, s.nt, 500);
    bench_base(s.pos, s.nv, s.idx, s.nt, s.nt / 100);
    sd4_free_mesh(&fine);
    mio_free_mesh(&mesh);
    return 0;
}
