/* bench_bvh - dispmesh.h's BVH ray caster against Embree 3, single thread.

   build/bench_bvh [MESH]      (default build/sphere1m.off)

   Figures (each side in this process, on the same mesh and the same rays; the sides of a figure
   interleaved, one warm-up each and 11 rounds, medians with min/max, see bench.h):
     RESULT bvh_build tris=<n> ours_ms=<t> embree_ms=<t> ratio=<ours/embree>
         ours: dm_bvh_build (default options, the huge-page allocator of bench.h as dispmesh.h
         recommends on Linux, like Embree's own allocator): validation, triangle boxes, binned
         SAH, the triangles in leaf order, the 8-wide tree. Embree: rtcNewScene (default flags), quality MEDIUM,
         rtcNewGeometry + shared vertex/index buffers + rtcCommitGeometry + rtcAttachGeometry +
         rtcCommitScene, on a device made with "threads=1" (outside the timer, like the padded
         vertex copy Embree's 16-byte loads need). Freeing is outside the timer on both sides.
     RESULT bvh_trace kind=<incoherent|bake> rays=<n> ours_mrays=<r> embree_mrays=<r>
         ratio=<ours/embree> mismatches=<n> ties=<n>
         one dm_bvh_intersect per ray against one rtcIntersect1 per ray (tnear 0, tfar inf).
         Incoherent: 1M rays from uniform points in the bounding box in uniform directions.
         Bake: 1M rays from points sampled (area-uniform) on a copy of the mesh simplified by
         meshopt_simplify to 1% of its triangles, along + and - the interpolated vertex normal
         (alternating). mismatches: rays where ours and a second Embree scene built with
         RTC_SCENE_FLAG_ROBUST disagree on hit/miss or |dt| > 1e-5 max(t, 1e-3 diagonal); ties:
         hits at the same t on a different triangle (shared edges), not mismatches.
     RESULT bvh_build_malloc / bvh_trace_malloc ...: ours with plain malloc (NULL allocator), for
         comparison; the ratio is against the same Embree figure (a third side of the build's
         interleaving, a fourth of the trace's).
     RESULT bvh_trace_batch ...: ours through dm_bvh_intersect_batch (the third side of the trace).
     RESULT bvh_memory ours_mb=<m> nodes=<n> leaves=<n> depth=<d> sah=<c>
   ratio < 1 for build time means we are faster; ratio > 1 for Mrays/s means we are faster.
   Rays are a pure function of the mesh (splitmix64 hashes, no rand()). */
#include "bench.h"

#include <embree3/rtcore.h>
#include <meshoptimizer.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

#include "bvh_rays.hpp"

/* meshopt_simplify to 1% of the triangles, then area-uniform samples with interpolated
   area-weighted vertex normals; rays alternate +n / -n */
static bool bake_rays(const mesh_view &m, size_t count, std::vector<dm_ray> &rays, size_t *simplified_tris)
{
    std::vector<unsigned int> simple(3 * m.nt);
    size_t target = 3 * (m.nt / 100 > 4 ? m.nt / 100 : 4);
    float err = 0.0f;
    size_t n = meshopt_simplify(simple.data(), m.idx, 3 * m.nt, m.pos, m.nv, 3 * sizeof(float), target, 1.0f, 0, &err);
    simple.resize(n);
    *simplified_tris = n / 3;
    if (n == 0) return false;
    surface_rays(m.pos, m.nv, simple.data(), n / 3, 0.0, count, rays);
    return true;
}

/* ---- the two sides -------------------------------------------------------------------------- */

struct state {
    mesh_view m;
    std::vector<float> padded;
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    dm_bvh *bvh = nullptr;
    const std::vector<dm_ray> *rays = nullptr;
    std::vector<dm_hit> ours;
    std::vector<float> embree_t;
    std::vector<unsigned> embree_prim;
    size_t hits = 0, embree_hits = 0, ours_hits = 0;
    const dm_allocator *alloc = nullptr; /* ours: NULL = malloc, else the huge-page allocator */
    const dm_allocator *hugepages = nullptr;
    dm_bvh *bvh_malloc = nullptr; /* ours with malloc, for bvh_trace_malloc */
};

static RTCScene embree_scene(state &s, RTCSceneFlags flags)
{
    RTCScene scene = rtcNewScene(s.device);
    rtcSetSceneFlags(scene, flags);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry g = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s.padded.data(), 0, 3 * sizeof(float), s.m.nv);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s.m.idx, 0, 3 * sizeof(uint32_t), s.m.nt);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    return scene;
}

static int run_embree_build(void *user)
{
    state &s = *(state *)user;
    s.scene = embree_scene(s, RTC_SCENE_FLAG_NONE);
    return s.scene ? 0 : 1;
}
static void free_embree(void *user)
{
    state &s = *(state *)user;
    rtcReleaseScene(s.scene);
    s.scene = nullptr;
}
static int run_ours_build(void *user)
{
    state &s = *(state *)user;
    dm_bvh_options o = {};
    o.allocator = s.alloc;
    return dm_bvh_build(s.m.pos, s.m.nv, s.m.idx, s.m.nt, &o, &s.bvh) == DM_OK ? 0 : 1;
}
static int run_ours_build_hugepages(void *user)
{
    state &s = *(state *)user;
    s.alloc = s.hugepages;
    return run_ours_build(user);
}
static int run_ours_build_malloc(void *user)
{
    state &s = *(state *)user;
    s.alloc = nullptr;
    return run_ours_build(user);
}
static void free_ours(void *user)
{
    state &s = *(state *)user;
    dm_bvh_free(s.bvh);
    s.bvh = nullptr;
}

static void embree_trace(RTCScene scene, const std::vector<dm_ray> &rays, std::vector<float> &t,
                         std::vector<unsigned> &prim, size_t *hits)
{
    size_t n = 0;
    for (size_t i = 0; i < rays.size(); i++) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rh;
        const dm_ray &r = rays[i];
        rh.ray.org_x = r.org[0]; rh.ray.org_y = r.org[1]; rh.ray.org_z = r.org[2];
        rh.ray.dir_x = r.dir[0]; rh.ray.dir_y = r.dir[1]; rh.ray.dir_z = r.dir[2];
        rh.ray.tnear = r.tmin;
        rh.ray.tfar = r.tmax;
        rh.ray.time = 0.0f;
        rh.ray.mask = 0xffffffffu;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        const bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        t[i] = hit ? rh.ray.tfar : -1.0f;
        prim[i] = hit ? rh.hit.primID : DM_NO_HIT;
        n += hit;
    }
    *hits = n;
}

static int run_embree_trace(void *user)
{
    state &s = *(state *)user;
    embree_trace(s.scene, *s.rays, s.embree_t, s.embree_prim, &s.hits);
    return 0;
}
static void embree_trace_after(void *user)
{
    state &s = *(state *)user;
    s.embree_hits = s.hits;
}
static size_t ours_trace(const dm_bvh *bvh, const std::vector<dm_ray> &rays, std::vector<dm_hit> &hits)
{
    size_t n = 0;
    for (size_t i = 0; i < rays.size(); i++) n += (size_t)dm_bvh_intersect(bvh, &rays[i], &hits[i]);
    return n;
}
static int run_ours_trace(void *user)
{
    state &s = *(state *)user;
    s.hits = ours_trace(s.bvh, *s.rays, s.ours);
    return 0;
}
static void ours_trace_after(void *user)
{
    state &s = *(state *)user;
    s.ours_hits = s.hits;
}
static int run_ours_trace_malloc(void *user)
{
    state &s = *(state *)user;
    s.hits = ours_trace(s.bvh_malloc, *s.rays, s.ours);
    return 0;
}

/* " <key>_mrays=<median> <key>_mrays_min=<...> <key>_mrays_max=<...>": rays over the run times */
static void print_mrays(const char *key, const bench_side &side, size_t rays)
{
    printf(" %s_mrays=%.3f %s_mrays_min=%.3f %s_mrays_max=%.3f", key, rays / side.median * 1e-6, key,
           rays / side.max * 1e-6, key, rays / side.min * 1e-6);
}
static int run_ours_batch(void *user)
{
    state &s = *(state *)user;
    s.hits = dm_bvh_intersect_batch(s.bvh, s.rays->data(), s.rays->size(), s.ours.data());
    return 0;
}

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off";
    for (int i = 1; i < argc; i++)
        if (argv[i][0] != '-') path = argv[i];
    BENCH_PRINT_FLAGS("bench_bvh");
#if defined(DM_USE_AVX2)
    printf("RESULT bench_bvh_config path=avx2\n");
#elif defined(DM_USE_SSE2)
    printf("RESULT bench_bvh_config path=sse2\n");
#else
    printf("RESULT bench_bvh_config path=portable\n");
#endif
    mio_mesh mesh;
    mio_error err;
    if (mio_read_file(path, NULL, &mesh, &err) != MIO_OK) {
        fprintf(stderr, "%s: %s\n", path, err.message);
        return 1;
    }
    state s;
    s.m.pos = mesh.positions;
    s.m.nv = mesh.vertex_count;
    s.m.idx = mesh.indices;
    s.m.nt = mesh.triangle_count;
    s.padded.assign(3 * s.m.nv + 1, 0.0f);
    memcpy(s.padded.data(), s.m.pos, 3 * s.m.nv * sizeof(float));
    s.device = rtcNewDevice("threads=1");
    if (!s.device) {
        fprintf(stderr, "rtcNewDevice failed\n");
        return 1;
    }
    bounds(s.m);
    const double diag = s.m.diag;

    fprintf(stderr, "bench_bvh: %s, %zu triangles: build, Embree and ours (huge pages, malloc) interleaved\n", path,
            s.m.nt);
    static const dm_allocator hugepages = {bench_hugepage_alloc, bench_hugepage_free, nullptr};
    s.hugepages = &hugepages;
    bench_side build[3] = {bench_make_side("embree", run_embree_build, free_embree, &s),
                           bench_make_side("ours", run_ours_build_hugepages, free_ours, &s),
                           bench_make_side("ours_malloc", run_ours_build_malloc, free_ours, &s)};
    if (bench_interleave(build, 3, 0) != 0) {
        fprintf(stderr, "a BVH build failed\n");
        return 1;
    }
    printf("RESULT bvh_build tris=%zu", s.m.nt);
    bench_print_ms("ours", &build[1]);
    bench_print_ms("embree", &build[0]);
    bench_print_ratio(&build[1], &build[0]);
    printf("\nRESULT bvh_build_malloc tris=%zu", s.m.nt);
    bench_print_ms("ours", &build[2]);
    bench_print_ratio(&build[2], &build[0]);
    printf("\n");
    fflush(stdout);

    if (dm_bvh_build(s.m.pos, s.m.nv, s.m.idx, s.m.nt, NULL, &s.bvh_malloc) != DM_OK || run_ours_build_hugepages(&s) != 0) {
        fprintf(stderr, "dm_bvh_build failed\n");
        return 1;
    }
    dm_bvh_info info;
    dm_bvh_get_info(s.bvh, &info);
    printf("RESULT bvh_memory ours_mb=%.2f nodes=%zu leaves=%zu depth=%zu sah=%.2f\n",
           info.memory_bytes / 1048576.0, info.node_count, info.leaf_count, info.max_depth, info.sah_cost);
    s.scene = embree_scene(s, RTC_SCENE_FLAG_NONE);
    RTCScene robust = embree_scene(s, RTC_SCENE_FLAG_ROBUST);

    const size_t count = 1000000;
    for (int kind = 0; kind < 2; kind++) {
        std::vector<dm_ray> rays;
        size_t simplified = 0;
        if (kind == 0) incoherent_rays(s.m, count, rays);
        else if (!bake_rays(s.m, count, rays, &simplified)) {
            fprintf(stderr, "meshopt_simplify produced nothing\n");
            return 1;
        }
        const char *name = kind == 0 ? "incoherent" : "bake";
        fprintf(stderr, "bench_bvh: trace %s%s\n", name, kind ? " (simplified copy made)" : "");
        s.rays = &rays;
        s.ours.assign(count, dm_hit());
        s.embree_t.assign(count, 0.0f);
        s.embree_prim.assign(count, 0);
        bench_side trace[4] = {bench_make_side("embree", run_embree_trace, embree_trace_after, &s),
                               bench_make_side("ours", run_ours_trace, ours_trace_after, &s),
                               bench_make_side("ours_batch", run_ours_batch, nullptr, &s),
                               bench_make_side("ours_malloc", run_ours_trace_malloc, nullptr, &s)};
        if (bench_interleave(trace, 4, 0) != 0) return 1;
        run_ours_trace(&s); /* s.ours from dm_bvh_intersect on the huge-page BVH, for the check */
        size_t embree_hits = s.embree_hits, ours_hits = s.ours_hits;

        /* mismatches against the robust scene */
        std::vector<float> rt(count);
        std::vector<unsigned> rp(count);
        size_t robust_hits = 0, mismatches = 0, ties = 0;
        embree_trace(robust, rays, rt, rp, &robust_hits);
        for (size_t i = 0; i < count; i++) {
            bool oh = s.ours[i].triangle != DM_NO_HIT, eh = rp[i] != DM_NO_HIT;
            bool bad = oh != eh;
            if (!bad && oh) {
                double t = rt[i], dt = std::fabs((double)s.ours[i].t - t);
                bad = dt > 1e-5 * std::fmax(t, 1e-3 * diag);
                if (!bad && s.ours[i].triangle != rp[i]) ties++;
            }
            if (bad) {
                mismatches++;
                if (mismatches <= 20) {
                    const dm_ray &r = rays[i];
                    printf("mismatch %s ray %zu org %.9g %.9g %.9g dir %.9g %.9g %.9g: ours %s t=%.9g tri=%u, "
                           "embree_robust %s t=%.9g tri=%u\n", name, i, r.org[0], r.org[1], r.org[2], r.dir[0], r.dir[1],
                           r.dir[2], oh ? "hit" : "miss", s.ours[i].t, s.ours[i].triangle, eh ? "hit" : "miss", rt[i], rp[i]);
                }
            }
        }
        printf("RESULT bvh_trace kind=%s rays=%zu", name, count);
        print_mrays("ours", trace[1], count);
        print_mrays("embree", trace[0], count);
        bench_print_ratio(&trace[0], &trace[1]); /* Embree's time over ours: ours' Mrays/s over Embree's */
        printf(" mismatches=%zu ties=%zu ours_hits=%zu embree_hits=%zu robust_hits=%zu", mismatches, ties, ours_hits,
               embree_hits, robust_hits);
        if (kind) printf(" simplified_tris=%zu", simplified);
        printf("\nRESULT bvh_trace_batch kind=%s rays=%zu", name, count);
        print_mrays("ours", trace[2], count);
        bench_print_ratio(&trace[0], &trace[2]);
        printf("\nRESULT bvh_trace_malloc kind=%s rays=%zu", name, count);
        print_mrays("ours", trace[3], count);
        bench_print_ratio(&trace[0], &trace[3]);
        printf("\n");
        fflush(stdout);
    }
    dm_bvh_free(s.bvh_malloc);
    rtcReleaseScene(robust);
    free_embree(&s);
    free_ours(&s);
    rtcReleaseDevice(s.device);
    mio_free_mesh(&mesh);
    printf("RESULT bench_bvh process_peak_rss_mb=%.1f\n", bench_peak_rss_kb() / 1024.0);
    return 0;
}
