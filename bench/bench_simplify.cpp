/* bench_simplify - QEM simplification: dispmesh.h (dm_simplify) vs meshoptimizer (meshopt_simplify)
   vs OpenMesh (Decimater with ModQuadric + ModNormalFlipping), at 1% and 10% of the triangles.
   All three outputs are measured with the same Embree point-query sampler
   (tests/surface_distance.hpp: 200k area-uniform samples per side, max also over every vertex,
   fractions of the input's bounding-box diagonal). Ours runs last, with the smaller of the two
   peers' triangle counts as its target, so that it never has more triangles than either.

   build/bench_simplify [MESH]     (default build/sphere1m.off)

   Timed, the three sides interleaved (bench.h: one warm-up each, then 11 rounds of meshopt,
   OpenMesh, ours; medians with min/max), one thread:
     ours      dm_simplify + dm_pm_counts + dm_pm_get_mesh (compact positions and indices)
     meshopt   meshopt_simplify(target_index_count, target_error = 1.0 so only the count stops it)
     openmesh  Decimater construction, add modules, initialize, decimate_to_faces, garbage_collection
               (the TriMesh is built from the arrays outside the timer). On meshes above 200k
               triangles OpenMesh stops after 3 rounds (it takes ~30 s a run there); the line then
               says openmesh_runs=3.
   Ours' target is known from the peers' warm-up runs, which come before ours'. Ratios are ours
   over each peer, per round. */
#include "bench.h"

#include <meshoptimizer.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <algorithm>

#include "openmesh_decimate.hpp"
#include "surface_distance.hpp"
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

struct ctx {
    const mio_mesh *m;
    size_t target;      /* the peers' target */
    /* meshopt */
    std::vector<unsigned> mo_idx;
    size_t mo_count;
    /* openmesh: its result of the first run, kept for the distances */
    TriMesh *om;
    std::vector<float> om_pos;
    std::vector<uint32_t> om_idx;
    bool om_kept;
    /* ours */
    std::vector<float> d_pos;
    std::vector<uint32_t> d_idx;
    size_t d_nv, d_nt;
    dm_pm *pm;
};

static int run_meshopt(void *u)
{
    ctx *c = (ctx *)u;
    c->mo_idx.resize(3 * c->m->triangle_count);
    c->mo_count = meshopt_simplify(c->mo_idx.data(), c->m->indices, 3 * c->m->triangle_count, c->m->positions,
                                   c->m->vertex_count, 3 * sizeof(float), 3 * c->target, 1.0f, 0, nullptr);
    return 0;
}

static int run_openmesh(void *u)
{
    ctx *c = (ctx *)u;
    om_decimate_run(*c->om, c->target);
    return 0;
}

static void build_openmesh(ctx *c)
{
    c->om = new TriMesh;
    om_build(c->m->positions, c->m->vertex_count, c->m->indices, c->m->triangle_count, *c->om);
}

/* after an OpenMesh run, outside the timer: keep the first result, build the next run's input */
static void openmesh_after(void *u)
{
    ctx *c = (ctx *)u;
    if (!c->om_kept) om_extract(*c->om, c->om_pos, c->om_idx);
    c->om_kept = true;
    delete c->om;
    build_openmesh(c);
}

/* ours never gets more triangles than either peer reached */
static size_t ours_target(const ctx *c) { return std::min(c->mo_count / 3, c->om_idx.size() / 3); }

static int run_ours(void *u)
{
    ctx *c = (ctx *)u;
    dm_simplify_options o = {};
    o.target_triangles = ours_target(c);
    c->pm = nullptr;
    if (dm_simplify(c->m->positions, c->m->vertex_count, c->m->indices, c->m->triangle_count, &o, &c->pm, nullptr) != DM_OK)
        return 1;
    dm_pm_counts(c->pm, &c->d_nv, &c->d_nt);
    c->d_pos.resize(3 * c->d_nv + 3);
    c->d_idx.resize(3 * c->d_nt + 3);
    dm_pm_get_mesh(c->pm, c->d_pos.data(), c->d_idx.data(), nullptr);
    return 0;
}

static void free_ours(void *u) /* outside the timer, as the README says */
{
    ctx *c = (ctx *)u;
    dm_pm_free(c->pm);
    c->pm = nullptr;
}

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off";
    for (int i = 1; i < argc; i++)
        if (argv[i][0] != '-') path = argv[i];
    BENCH_PRINT_FLAGS("simplify");
#ifdef __GLIBC__
    /* Large blocks from the heap, kept between runs, for every side: with glibc's dynamic mmap
       and trim thresholds, whether a side's repeated runs page-fault their memory in again
       depended on what the process had allocated and freed before (on the bunny, ours faulted
       3018 pages in every run at 1% after OpenMesh's run, and none at 10%). bench_raster does
       the same. */
    mallopt(M_MMAP_THRESHOLD, 512 * 1024 * 1024);
    mallopt(M_TRIM_THRESHOLD, 1024 * 1024 * 1024);
#endif
    mio_mesh m;
    mio_error err;
    if (mio_read_file(path, nullptr, &m, &err) != MIO_OK) {
        fprintf(stderr, "bench_simplify: %s: %s\n", path, err.message);
        return 1;
    }
    bool big = m.triangle_count > 200000;
    sd_mesh in = {m.positions, m.vertex_count, m.indices, m.triangle_count};
    const double fractions[2] = {0.01, 0.10};
    for (double f : fractions) {
        ctx c;
        c.m = &m;
        c.mo_count = 0;
        c.om_kept = false;
        c.pm = nullptr;
        c.target = (size_t)(f * (double)m.triangle_count);
        fprintf(stderr, "bench_simplify: %s at %g%%: meshoptimizer, OpenMesh and ours interleaved\n", path, 100 * f);
        build_openmesh(&c);
        bench_side sides[3] = {bench_make_side("meshopt", run_meshopt, nullptr, &c),
                               bench_make_side("openmesh", run_openmesh, openmesh_after, &c),
                               bench_make_side("ours", run_ours, free_ours, &c)};
        if (big) sides[1].max_runs = 3;
        int failed = bench_interleave(sides, 3, 0);
        delete c.om;
        if (failed) {
            fprintf(stderr, "bench_simplify: a run failed (dm_simplify)\n");
            return 1;
        }
        /* ours' last result is still in d_pos / d_idx (free_ours frees only the pm) */
        fprintf(stderr, "bench_simplify: measuring distances\n");
        size_t mo_tris = c.mo_count / 3, om_tris = c.om_idx.size() / 3;
        sd_mesh mo = {m.positions, m.vertex_count, c.mo_idx.data(), mo_tris};
        sd_mesh om = {c.om_pos.data(), c.om_pos.size() / 3, c.om_idx.data(), om_tris};
        sd_mesh ours = {c.d_pos.data(), c.d_nv, c.d_idx.data(), c.d_nt};
        sd_result r_mo = {}, r_om = {}, r_d = {};
        sd_distance(in, mo, 200000, &r_mo);
        sd_distance(in, om, 200000, &r_om);
        sd_distance(in, ours, 200000, &r_d);
        printf("RESULT simplify target=%g tris=%zu ours_tris=%zu meshopt_tris=%zu openmesh_tris=%zu", 100 * f,
               m.triangle_count, c.d_nt, mo_tris, om_tris);
        bench_print_ms("ours", &sides[2]);
        bench_print_ms("meshopt", &sides[0]);
        bench_print_ms("openmesh", &sides[1]);
        bench_print_ratio_named("ratio_meshopt", &sides[2], &sides[0]);
        bench_print_ratio_named("ratio_openmesh", &sides[2], &sides[1]);
        printf(" openmesh_runs=%d ours_rms=%.3e ours_max=%.3e meshopt_rms=%.3e meshopt_max=%.3e openmesh_rms=%.3e "
               "openmesh_max=%.3e\n",
               sides[1].runs, r_d.rms, r_d.max, r_mo.rms, r_mo.max, r_om.rms, r_om.max);
        fflush(stdout);
    }
    mio_free_mesh(&m);
    return 0;
}
