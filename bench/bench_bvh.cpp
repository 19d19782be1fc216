/* bench_bvh - dispmesh.h's BVH ray caster against Embree 3, single thread.

   build/bench_bvh [MESH]      (default build/sphere1m.off)

   Figures (each side in this process, on the same mesh and the same rays, median of 5 after a
   warm-up, see bench.h):
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
         comparison; the ratio is against the same Embree figure.
     RESULT bvh_trace_batch ...: ours through dm_bvh_intersect_batch.
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
    size_t hits = 0;
    const dm_allocator *alloc = nullptr; /* ours: NULL = malloc, else the huge-page allocator */
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
static int run_ours_trace(void *user)
{
    state &s = *(state *)user;
    const std::vector<dm_ray> &rays = *s.rays;
    size_t n = 0;
    for (size_t i = 0; i < rays.size(); i++) n += (size_t)dm_bvh_intersect(s.bvh, &rays[i], &s.ours[i]);
    s.hits = n;
    return 0;
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

    fprintf(stderr, "bench_bvh: %s, %zu triangles: build\n", path, s.m.nt);
    double embree_build = bench_median(run_embree_build, free_embree, &s);
    static const dm_allocator hugepages = {bench_hugepage_alloc, bench_hugepage_free, nullptr};
    double ours_build_malloc = bench_median(run_ours_build, free_ours, &s);
    s.alloc = &hugepages;
    double ours_build = bench_median(run_ours_build, free_ours, &s);
    printf("RESULT bvh_build tris=%zu ours_ms=%.3f embree_ms=%.3f ratio=%.3f\n", s.m.nt, 1e3 * ours_build,
           1e3 * embree_build, ours_build / embree_build);
    printf("RESULT bvh_build_malloc tris=%zu ours_ms=%.3f ratio=%.3f\n", s.m.nt, 1e3 * ours_build_malloc,
           ours_build_malloc / embree_build);
    fflush(stdout);

    dm_bvh *with_malloc = nullptr;
    if (dm_bvh_build(s.m.pos, s.m.nv, s.m.idx, s.m.nt, NULL, &with_malloc) != DM_OK || run_ours_build(&s) != 0) {
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
        double embree_s = bench_median(run_embree_trace, NULL, &s);
        size_t embree_hits = s.hits;
        double ours_s = bench_median(run_ours_trace, NULL, &s);
        size_t ours_hits = s.hits;

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
        printf("RESULT bvh_trace kind=%s rays=%zu ours_mrays=%.3f embree_mrays=%.3f ratio=%.3f mismatches=%zu "
               "ties=%zu ours_hits=%zu embree_hits=%zu robust_hits=%zu",
               name, count, count / ours_s * 1e-6, count / embree_s * 1e-6, embree_s / ours_s, mismatches, ties,
               ours_hits, embree_hits, robust_hits);
        if (kind) printf(" simplified_tris=%zu", simplified);
        printf("\n");
        fflush(stdout);
        double batch_s = bench_median(run_ours_batch, NULL, &s);
        printf("RESULT bvh_trace_batch kind=%s rays=%zu ours_mrays=%.3f ratio=%.3f\n", name, count,
               count / batch_s * 1e-6, embree_s / batch_s);
        dm_bvh *thp_bvh = s.bvh;
        s.bvh = with_malloc;
        double malloc_s = bench_median(run_ours_trace, NULL, &s);
        s.bvh = thp_bvh;
        printf("RESULT bvh_trace_malloc kind=%s rays=%zu ours_mrays=%.3f ratio=%.3f\n", name, count,
               count / malloc_s * 1e-6, embree_s / malloc_s);
        fflush(stdout);
    }
    dm_bvh_free(with_malloc);
    rtcReleaseScene(robust);
    free_embree(&s);
    free_ours(&s);
    rtcReleaseDevice(s.device);
    mio_free_mesh(&mesh);
    printf("RESULT bench_bvh process_peak_rss_mb=%.1f\n", bench_peak_rss_kb() / 1024.0);
    return 0;
}
