/* bench_simplify - QEM simplification: dispmesh.h (dm_simplify) vs meshoptimizer (meshopt_simplify)
   vs OpenMesh (Decimater with ModQuadric + ModNormalFlipping), at 1% and 10% of the triangles.
   All three outputs are measured with the same Embree point-query sampler
   (tests/surface_distance.hpp: 200k area-uniform samples per side, max also over every vertex,
   fractions of the input's bounding-box diagonal). Ours runs last, with the smaller of the two
   peers' triangle counts as its target, so that it never has more triangles than either.

   build/bench_simplify [MESH]     (default build/sphere1m.off)

   Timed (median of 5 after a warm-up, one thread):
     ours      dm_simplify + dm_pm_counts + dm_pm_get_mesh (compact positions and indices)
     meshopt   meshopt_simplify(target_index_count, target_error = 1.0 so only the count stops it)
     openmesh  Decimater construction, add modules, initialize, decimate_to_faces, garbage_collection
               (the TriMesh is built from the arrays outside the timer). On meshes above 200k
               triangles OpenMesh gets one timed run after the warm-up (it takes ~20 s a run);
               the line then says openmesh_runs=1. */
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
    size_t target;
    /* meshopt */
    std::vector<unsigned> mo_idx;
    size_t mo_count;
    /* openmesh */
    TriMesh *om;
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

static void rebuild_openmesh(void *u)
{
    ctx *c = (ctx *)u;
    delete c->om;
    c->om = new TriMesh;
    om_build(c->m->positions, c->m->vertex_count, c->m->indices, c->m->triangle_count, *c->om);
}

static int run_ours(void *u)
{
    ctx *c = (ctx *)u;
    dm_simplify_options o = {};
    o.target_triangles = c->target;
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
        c.om = nullptr;
        c.pm = nullptr;
        c.target = (size_t)(f * (double)m.triangle_count);
        fprintf(stderr, "bench_simplify: %s at %g%%: meshoptimizer\n", path, 100 * f);
        double mo_s = bench_median(run_meshopt, nullptr, &c);
        fprintf(stderr, "bench_simplify: openmesh\n");
        double om_s;
        rebuild_openmesh(&c);
        if (big) {
            double t0 = bench_now();
            run_openmesh(&c);
            (void)t0;
            rebuild_openmesh(&c); /* the warm-up */
            t0 = bench_now();
            run_openmesh(&c);
            om_s = bench_now() - t0;
        } else {
            om_s = bench_median(run_openmesh, rebuild_openmesh, &c);
            rebuild_openmesh(&c);
            run_openmesh(&c);
        }
        std::vector<float> op;
        std::vector<uint32_t> oi;
        om_extract(*c.om, op, oi);
        delete c.om;
        size_t mo_tris = c.mo_count / 3, om_tris = oi.size() / 3;
        c.target = std::min(mo_tris, om_tris);
        fprintf(stderr, "bench_simplify: ours\n");
        double d_s = bench_median(run_ours, free_ours, &c);
        if (d_s < 0) {
            fprintf(stderr, "bench_simplify: dm_simplify failed\n");
            return 1;
        }
        fprintf(stderr, "bench_simplify: measuring distances\n");
        sd_mesh mo = {m.positions, m.vertex_count, c.mo_idx.data(), mo_tris};
        sd_mesh om = {op.data(), op.size() / 3, oi.data(), om_tris};
        sd_mesh ours = {c.d_pos.data(), c.d_nv, c.d_idx.data(), c.d_nt};
        sd_result r_mo = {}, r_om = {}, r_d = {};
        sd_distance(in, mo, 200000, &r_mo);
        sd_distance(in, om, 200000, &r_om);
        sd_distance(in, ours, 200000, &r_d);
        printf("RESULT simplify target=%g tris=%zu ours_tris=%zu meshopt_tris=%zu openmesh_tris=%zu ours_ms=%.1f "
               "meshopt_ms=%.1f openmesh_ms=%.1f ours_rms=%.3e ours_max=%.3e meshopt_rms=%.3e meshopt_max=%.3e "
               "openmesh_rms=%.3e openmesh_max=%.3e%s\n",
               100 * f, m.triangle_count, c.d_nt, mo_tris, om_tris, 1e3 * d_s, 1e3 * mo_s, 1e3 * om_s, r_d.rms, r_d.max,
               r_mo.rms, r_mo.max, r_om.rms, r_om.max, big ? " openmesh_runs=1" : "");
        fflush(stdout);
    }
    mio_free_mesh(&m);
    return 0;
}
