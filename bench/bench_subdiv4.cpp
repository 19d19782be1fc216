/* bench_subdiv4 - subdiv4.h: the four-point grid (no peer) and butterfly vs OpenMesh's
   ModifiedButterflyT (Debian libopenmesh-dev).

   usage: bench_subdiv4 [MESH]     (default build/sphere1m.off)

   Figures (details and timed regions in bench/README.md):
     RESULT subdiv4_grid size=1025x1025 levels=7 ms=<t>
         a 9 x 9 grid of heights refined 7 levels to 1025 x 1025 (w = 0.1, linear end rule) into
         a caller-owned buffer; timed: sd4_grid_refine alone.
     RESULT butterfly tris_out=<n> ours_ms=<t> openmesh_ms=<t> ratio=<ours/openmesh> maxdiff=<d> ...
         two levels of butterfly at w = 1/16 on MESH. Timed: ours - sd4_butterfly (connectivity,
         stencils, output arrays); OpenMesh - the subdivider's attach + operator()(2) + detach on a
         TriMesh built beforehand. maxdiff: largest distance between corresponding vertices over
         the bounding-box diagonal (tests/butterfly_compare.hpp), vertices near a boundary apart.
   Timing (bench.h): ours and OpenMesh interleaved, one warm-up each and 11 rounds, medians with
   min/max (the grid alone, 11 runs); the peak memory is each side's warm-up run's. One thread.
   For inputs above 300k triangles OpenMesh stops after 3 timed runs (om_runs=3) and maxdiff is
   not computed (maxdiff=skipped): its two levels take ~5 s and 1.5 GB a run there. */
#include "bench.h"

#include "openmesh.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#include "hashrand.h"
#include "butterfly_compare.hpp"

struct grid_side {
    double control[81];
    std::vector<double> out;
};

static int grid_run(void *user)
{
    grid_side *s = (grid_side *)user;
    return sd4_grid_refine(s->control, 9, 9, 1, 0.1, 7, NULL, s->out.data(), s->out.size()) == SD4_OK ? 0 : 1;
}

struct ours_side {
    const mio_mesh *in;
    sd4_mesh out;
    size_t tris_out;
};

static int ours_run(void *user)
{
    ours_side *s = (ours_side *)user;
    return sd4_butterfly(s->in->positions, s->in->vertex_count, s->in->indices, s->in->triangle_count, 2, 1.0 / 16.0,
                         NULL, &s->out) == SD4_OK ? 0 : 1;
}

static void ours_after(void *user)
{
    ours_side *s = (ours_side *)user;
    s->tris_out = s->out.triangle_count;
    sd4_free_mesh(&s->out);
}

struct om_side {
    const mio_mesh *in;
    TriMesh *mesh;
    size_t faces_out;
};

static int om_run(void *user)
{
    om_side *s = (om_side *)user;
    bf_openmesh_subdivide(*s->mesh, 2);
    return 0;
}

static void om_after(void *user)
{
    om_side *s = (om_side *)user;
    s->faces_out = s->mesh->n_faces();
    delete s->mesh;
    s->mesh = new TriMesh; /* the next run's input, built outside the timer */
    bf_to_openmesh(s->in->positions, s->in->vertex_count, s->in->indices, s->in->triangle_count, *s->mesh);
}

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "build/sphere1m.off";
    BENCH_PRINT_FLAGS("bench_subdiv4");
    /* ---- grid ---- */
    {
        grid_side g;
        size_t W, H;
        for (int i = 0; i < 81; i++) g.control[i] = 100.0 * unit_random((uint64_t)i, 0);
        sd4_grid_size(9, 9, 7, NULL, &W, &H);
        g.out.assign(W * H, 0.0);
        std::fprintf(stderr, "bench_subdiv4: grid 9x9 -> %zux%zu\n", W, H);
        bench_side side = bench_make_side("grid", grid_run, NULL, &g);
        if (bench_interleave(&side, 1, 0) != 0) { std::printf("RESULT subdiv4_grid error=refine_failed\n"); return 1; }
        std::printf("RESULT subdiv4_grid size=%zux%zu levels=7", W, H);
        bench_print_ms("", &side);
        std::printf("\n");
        std::fflush(stdout);
    }
    /* ---- butterfly ---- */
    mio_mesh in;
    mio_error err;
    if (mio_read_file(path, NULL, &in, &err) != MIO_OK) {
        std::fprintf(stderr, "bench_subdiv4: %s: %s\n", path, err.message);
        return 1;
    }
    bool large = in.triangle_count > 300000;
    std::fprintf(stderr, "bench_subdiv4: butterfly, 2 levels on %s (%zu triangles)\n", path, in.triangle_count);
    ours_side o;
    o.in = &in;
    std::memset(&o.out, 0, sizeof o.out);
    o.tris_out = 0;
    om_side s;
    s.in = &in;
    s.mesh = new TriMesh;
    s.faces_out = 0;
    if (!bf_to_openmesh(in.positions, in.vertex_count, in.indices, in.triangle_count, *s.mesh))
        std::fprintf(stderr, "bench_subdiv4: OpenMesh rejected some faces of %s\n", path);
    std::fprintf(stderr, "bench_subdiv4: ours and OpenMesh ModifiedButterflyT interleaved\n");
    bench_side sides[2] = {bench_make_side("ours", ours_run, ours_after, &o),
                           bench_make_side("openmesh", om_run, om_after, &s)};
    if (large) sides[1].max_runs = 3;
    if (bench_interleave(sides, 2, 0) != 0) {
        std::printf("RESULT butterfly error=subdivision_failed\n");
        return 1;
    }
    delete s.mesh;
    char maxdiff[64] = "skipped", maxdiff_b[64] = "skipped";
    if (!large) {
        std::fprintf(stderr, "bench_subdiv4: comparing vertices\n");
        bf_result r = bf_compare(in.positions, in.vertex_count, in.indices, in.triangle_count, 2);
        if (r.ok && r.unmatched == 0) {
            std::snprintf(maxdiff, sizeof maxdiff, "%.3g", r.maxdiff);
            std::snprintf(maxdiff_b, sizeof maxdiff_b, "%.3g", r.maxdiff_boundary);
        } else {
            std::snprintf(maxdiff, sizeof maxdiff, "mismatch");
        }
    }
    std::printf("RESULT butterfly tris_in=%zu tris_out=%zu", in.triangle_count, o.tris_out);
    bench_print_ms("ours", &sides[0]);
    bench_print_ms("openmesh", &sides[1]);
    bench_print_ratio(&sides[0], &sides[1]);
    std::printf(" maxdiff=%s maxdiff_near_boundary=%s om_faces_out=%zu om_runs=%d ours_peak_rss_mb=%.1f "
                "openmesh_peak_rss_mb=%.1f\n",
                maxdiff, maxdiff_b, s.faces_out, sides[1].runs, sides[0].peak_kb / 1024.0, sides[1].peak_kb / 1024.0);
    mio_free_mesh(&in);
    return o.tris_out == s.faces_out ? 0 : 1;
}
