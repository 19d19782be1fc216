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
     RESULT dispmesh_base faces=<n> shell_ms=<t> constrained_ms=<t> unconstrained_ms=<t> base_only_rms=<e> unconstrained_rms=<e> ...
                  paper 000's base (bounding shell + constrained simplification to 500 faces), one run,
                  for meshes up to 200k triangles. The distances (dm_surface_distance,
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
    return dm_reconstruct(s->map, s->pm, NULL, &s->rec) != DM_OK;
}
static void free_recon(void *u) { state *s = (state *)u; dm_trimesh_free(s->rec); s->rec = nullptr; }

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off";
    int res = 1024;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--res") && i + 1 < argc) res = atoi(argv[++i]);
        else if (argv[i][0] != '-') path = argv[i];
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

    /* paper 000's own base: the bounding shell and dm_simplify under dm_shell_constraint to 500
       faces (one run each: seconds, and no peer to compare with), against our unconstrained
       simplification to the same count; meshes up to 200k triangles */
    if (s.nt <= 200000) {
        dm_shell *sh = NULL;
        double t0 = bench_now();
        if (dm_shell_grow(s.pos, s.nv, s.idx, s.nt, NULL, &sh) != DM_OK) { fprintf(stderr, "dm_shell_grow failed\n"); return 1; }
        double t_shell = bench_now() - t0;
        dm_simplify_options so;
        memset(&so, 0, sizeof so);
        so.target_triangles = 500;
        so.constraint = dm_shell_constraint;
        so.on_collapse = dm_shell_collapsed;
        so.constraint_user = sh;
        dm_pm *pm = NULL, *pu = NULL;
        dm_simplify_report rep_c;
        t0 = bench_now();
        if (dm_simplify(s.pos, s.nv, s.idx, s.nt, &so, &pm, &rep_c) != DM_OK) { fprintf(stderr, "dm_simplify failed\n"); return 1; }
        double t_con = bench_now() - t0;
        so.constraint = NULL;
        so.on_collapse = NULL;
        so.target_triangles = rep_c.triangle_count;
        t0 = bench_now();
        if (dm_simplify(s.pos, s.nv, s.idx, s.nt, &so, &pu, NULL) != DM_OK) { fprintf(stderr, "dm_simplify failed\n"); return 1; }
        double t_unc = bench_now() - t0;
        dm_distance_report rc, ru;
        size_t bnv, bnt;
        dm_pm *both[2] = {pm, pu};
        dm_distance_report *reps[2] = {&rc, &ru};
        for (int k = 0; k < 2; k++) {
            dm_pm_counts(both[k], &bnv, &bnt);
            std::vector<float> bp(3 * bnv);
            std::vector<uint32_t> bi(3 * bnt);
            dm_pm_get_mesh(both[k], bp.data(), bi.data(), NULL);
            dm_surface_distance(s.pos, s.nv, s.idx, s.nt, bp.data(), bnv, bi.data(), bnt, nullptr, reps[k]);
        }
        printf("RESULT dispmesh_base faces=%zu shell_ms=%.1f constrained_ms=%.1f unconstrained_ms=%.1f base_only_rms=%.3g "
               "unconstrained_rms=%.3g ratio=%.2f moved=%zu vetoed=%zu\n",
               rep_c.triangle_count, 1e3 * t_shell, 1e3 * t_con, 1e3 * t_unc, rc.rms, ru.rms, rc.rms / ru.rms, sh->moved,
               rep_c.vetoed);
        dm_pm_free(pm);
        dm_pm_free(pu);
        dm_shell_free(sh);
    }
    mio_free_mesh(&mesh);
    return 0;
}
