/* bench_dispmesh.cpp - dispmesh.h part 3: parameterize a base mesh and bake a displacement map.

   The base mesh is meshopt_simplify of the input to 500 triangles (issue 8's bunny figure; the
   base is not a bounding shell, so rays go both ways, as dm_bake always looks). Then:
     RESULT dispmesh_param res=<r> base_tris=<n> charts=<n> ms=<t> utilization=<u> stretch_l2=<s> area_ok=<f>
     RESULT dispmesh_bake res=<r> orig_tris=<n> ms=<t> mtexels=<texels per s / 1e6> hits=<n> misses=<n>
     RESULT dispmesh_recon res=<r> ms=<t> rms=<e> max=<e> base_only_rms=<e> base_only_max=<e>
   Timed (median of 5 after a warm-up, one thread): dm_parameterize alone; dm_bake alone (its BVH
   build over the original included); dm_reconstruct alone. Both with bench.h's huge-page
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
    if (b->constrained) {
        so.constraint = dm_shell_constraint;
        so.on_collapse = dm_shell_collapsed;
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

/*   RESULT dispmesh_base target=<n> faces=<reached> shell_ms= constrained_ms= unconstrained_ms=
            ratio=<constrained / unconstrained time> base_ms=<shell + constrained> peak_mb=
            base_only_rms= unconstrained_rms= rms_ratio= vetoed=
   Medians of 5 after a warm-up (bench_median): the shell; the constrained simplification (with a
   shell grown once outside the timer); the unconstrained one to the same face count. peak_mb: the
   peak resident memory of one shell + constrained run above what was resident before. The
   distances (200k samples a side, of the diagonal) once, outside the timers. */
static void bench_base(const float *pos, size_t nv, const uint32_t *idx, size_t nt, size_t target)
{
    base_state b;
    b.pos = pos; b.nv = nv; b.idx = idx; b.nt = nt; b.target = target;
    double t_shell = bench_median(run_shell, free_shell, &b);
    if (t_shell < 0) { fprintf(stderr, "dm_shell_grow failed\n"); return; }
    long before = bench_reset_peak_rss() == 0 ? bench_current_rss_kb() : -1;
    if (run_shell(&b)) { fprintf(stderr, "dm_shell_grow failed\n"); return; }
    double t_con = bench_median(run_simplify, free_simplify, &b);
    long peak = before >= 0 ? bench_peak_rss_kb() - before : -1;
    if (t_con < 0 || run_simplify(&b)) { fprintf(stderr, "dm_simplify (constrained) failed\n"); free_shell(&b); return; }
    dm_pm *con = b.pm;
    dm_simplify_report rep_c = b.rep;
    double rms_c = base_rms(&b, con);
    b.pm = nullptr;
    b.constrained = 0;
    b.target = rep_c.triangle_count;
    double t_unc = bench_median(run_simplify, free_simplify, &b);
    double rms_u = -1.0;
    if (t_unc >= 0 && !run_simplify(&b)) {
        rms_u = base_rms(&b, b.pm);
        free_simplify(&b);
    }
    printf("RESULT dispmesh_base target=%zu faces=%zu shell_ms=%.1f constrained_ms=%.1f unconstrained_ms=%.2f ratio=%.1f "
           "base_ms=%.1f peak_mb=%.1f base_only_rms=%.3g unconstrained_rms=%.3g rms_ratio=%.2f vetoed=%zu\n",
           target, rep_c.triangle_count, 1e3 * t_shell, 1e3 * t_con, 1e3 * t_unc, t_unc > 0 ? t_con / t_unc : 0.0,
           1e3 * (t_shell + t_con), peak >= 0 ? peak / 1024.0 : -1.0, rms_c, rms_u, rms_u > 0 ? rms_c / rms_u : 0.0,
           rep_c.vetoed);
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
    double t_param = bench_median(run_param, free_param, &s);
    if (t_param < 0 || run_param(&s)) { fprintf(stderr, "dm_parameterize failed\n"); return 1; }
    printf("RESULT dispmesh_param res=%d base_tris=%zu charts=%zu ms=%.3f utilization=%.3f stretch_l2=%.3f area_ok=%.3f\n",
           res, n / 3, s.pm->chart_count, 1e3 * t_param, s.pm->utilization, s.pm->stretch_l2, s.pm->area_ratio_ok);

    double t_bake = bench_median(run_bake, free_bake, &s);
    if (t_bake < 0 || run_bake(&s)) { fprintf(stderr, "dm_bake failed\n"); return 1; }
    printf("RESULT dispmesh_bake res=%d orig_tris=%zu ms=%.3f mtexels=%.3f hits=%zu misses=%zu\n", res, s.nt,
           1e3 * t_bake, (double)res * res / t_bake * 1e-6, s.map->hit_count, s.map->miss_count);

    {
        dm_dispmap *keep = s.map;
        s.map = nullptr;
        s.alloc = nullptr;
        double t_malloc = bench_median(run_bake, free_bake, &s);
        printf("RESULT dispmesh_bake_malloc res=%d ms=%.3f\n", res, 1e3 * t_malloc);
        s.alloc = &hugepages;
        s.map = keep;
    }
    double t_rec = bench_median(run_recon, free_recon, &s);
    if (t_rec < 0 || run_recon(&s)) { fprintf(stderr, "dm_reconstruct failed\n"); return 1; }
    dm_distance_report rep, base_rep;
    dm_surface_distance(s.pos, s.nv, s.idx, s.nt, s.rec->positions, s.rec->vertex_count, s.rec->indices,
                        s.rec->triangle_count, nullptr, &rep);
    dm_surface_distance(s.pos, s.nv, s.idx, s.nt, s.pos, s.nv, s.base.data(), n / 3, nullptr, &base_rep);
    printf("RESULT dispmesh_recon res=%d ms=%.3f rms=%.3g max=%.3g base_only_rms=%.3g base_only_max=%.3g\n", res,
           1e3 * t_rec, rep.rms, rep.max, base_rep.rms, base_rep.max);
    free_recon(&s);
    free_bake(&s);
    free_param(&s);

    bench_base(s.pos, s.nv, s.idx, s.nt, 500);
    bench_base(s.pos, s.nv, s.idx, s.nt, s.nt / 100);
    sd4_free_mesh(&fine);
    mio_free_mesh(&mesh);
    return 0;
}
