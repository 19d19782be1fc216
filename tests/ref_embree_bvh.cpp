/* ref_embree_bvh - reference check of dispmesh.h's BVH ray caster against Embree 3 (Debian
   libembree-dev, link -lembree3), with the Embree scene built with RTC_SCENE_FLAG_ROBUST
   (watertight like ours).

   Meshes: the Stanford bunny (/usr/share/glmark2/models/bunny.obj, 69,666 triangles; skipped
   with a reason when glmark2-data is missing) and bumpy geodesic spheres from bench/sphere.h
   with 980, 100,820 and 1,003,520 triangles. Per mesh two ray sets of 1M rays each:
     incoherent  origins uniform in the bounding box, uniform random directions;
     bake        origins on the surface (area-uniform triangle, uniform barycentrics) moved
                 along the interpolated vertex normal by up to +-1% of the diagonal, pointing
                 along + or - that normal (the displacement bake's rays from a base mesh).
   A ray is a mismatch when one side hits and the other misses, or when
   |t_ours - t_embree| > 1e-5 max(t_embree, 1e-3 diagonal). A hit at the same t on a different
   triangle (a shared edge or vertex) is a tie: counted and reported, not a mismatch. Every
   mismatch is printed with its ray. Allowed: at most 1e-5 of the rays of each set. Also
   checked on 100k rays per set: dm_bvh_occluded against rtcOccluded1 (same rule on hit/miss).
   With TEST_SANITIZE set, the 1M-triangle sphere uses 100k rays per set instead of 1M (the
   library is instrumented and several times slower); the note is printed. */
#include <embree3/rtcore.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "test.h"
#include "sphere.h"
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

#ifndef REF_BUNNY_PATH
#define REF_BUNNY_PATH "/usr/share/glmark2/models/bunny.obj"
#endif

static const int CHECKS_PER_MESH = 9; /* counted checks of one mesh, for T_SKIP_N */

#include "bvh_rays.hpp"

/* bake-style rays on the mesh itself, origins moved up to 1% of the diagonal along the normal */
static void bake_rays(const mesh_view &m, size_t count, std::vector<dm_ray> &rays)
{
    surface_rays(m.pos, m.nv, m.idx, m.nt, 0.01 * m.diag, count, rays);
}

static double plane_t(const mesh_view &m, uint32_t tri, const dm_ray &r)
{
    if (tri >= m.nt) return NAN;
    const float *a = m.pos + 3 * (size_t)m.idx[3 * tri], *b = m.pos + 3 * (size_t)m.idx[3 * tri + 1],
                *c = m.pos + 3 * (size_t)m.idx[3 * tri + 2];
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
    }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double num = 0, den = 0;
    for (int k = 0; k < 3; k++) {
        num += ((double)a[k] - r.org[k]) * n[k];
        den += (double)r.dir[k] * n[k];
    }
    return num / den;
}

static void embree_error(void *user, RTCError code, const char *message)
{
    long *errors = (long *)user;
    (*errors)++;
    std::printf("  embree error %d: %s\n", (int)code, message ? message : "");
}

static RTCRayHit embree_ray(const dm_ray &r)
{
    RTCRayHit rh;
    std::memset(&rh, 0, sizeof rh);
    rh.ray.org_x = r.org[0]; rh.ray.org_y = r.org[1]; rh.ray.org_z = r.org[2];
    rh.ray.dir_x = r.dir[0]; rh.ray.dir_y = r.dir[1]; rh.ray.dir_z = r.dir[2];
    rh.ray.tnear = r.tmin;
    rh.ray.tfar = r.tmax;
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

static void check_mesh(const char *name, const mesh_view &m, RTCDevice device, size_t rays_per_set)
{
    dm_bvh *bvh = NULL;
    dm_result r = dm_bvh_build(m.pos, m.nv, m.idx, m.nt, NULL, &bvh);
    T_CHECK_MSG(r == DM_OK, "%s: %s", name, dm_result_string(r));
    if (r != DM_OK) {
        T_SKIP_N(CHECKS_PER_MESH - 1, name, "build failed (counted above)");
        return;
    }
    std::vector<float> padded(3 * m.nv + 1, 0.0f);
    std::memcpy(padded.data(), m.pos, 3 * m.nv * sizeof(float));
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, padded.data(), 0, 3 * sizeof(float), m.nv);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m.idx, 0, 3 * sizeof(uint32_t), m.nt);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);

    for (int kind = 0; kind < 2; kind++) {
        const char *kind_name = kind ? "bake" : "incoherent";
        std::vector<dm_ray> rays;
        if (kind) bake_rays(m, rays_per_set, rays);
        else incoherent_rays(m, rays_per_set, rays);
        size_t mismatches = 0, ties = 0, hits = 0, occl_bad = 0, embree_rounding = 0;
        double worst = 0.0;
        for (size_t i = 0; i < rays.size(); i++) {
            dm_hit h;
            int ours = dm_bvh_intersect(bvh, &rays[i], &h);
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            RTCRayHit rh = embree_ray(rays[i]);
            rtcIntersect1(scene, &context, &rh);
            bool eh = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            hits += (size_t)ours;
            bool bad = (ours != 0) != eh;
            if (!bad && eh) {
                double dt = std::fabs((double)h.t - rh.ray.tfar), tol = 1e-5 * std::fmax(rh.ray.tfar, 1e-3 * m.diag);
                bad = dt > tol;
                if (dt / tol > worst) worst = dt / tol;
                if (!bad && h.triangle != rh.hit.primID) ties++;
            }
            if (bad) {
                mismatches++;
                /* both hit the same triangle and our t is its exact plane distance: the
                   difference is Embree's rounding (grazing rays on large triangles) */
                if (ours && eh && h.triangle == rh.hit.primID &&
                    std::fabs(h.t - plane_t(m, h.triangle, rays[i])) <= 1e-6 * std::fabs(h.t))
                    embree_rounding++;
                const dm_ray &ray = rays[i];
                std::printf("  mismatch %s %s ray %zu: org %.9g %.9g %.9g dir %.9g %.9g %.9g: ours %s t=%.9g tri=%u, "
                            "embree %s t=%.9g tri=%u; plane t in double: ours' triangle %.9g, embree's %.9g\n", name,
                            kind_name, i, ray.org[0], ray.org[1], ray.org[2], ray.dir[0], ray.dir[1], ray.dir[2],
                            ours ? "hit" : "miss", h.t, h.triangle, eh ? "hit" : "miss", rh.ray.tfar, rh.hit.primID,
                            ours ? plane_t(m, h.triangle, ray) : NAN, eh ? plane_t(m, rh.hit.primID, ray) : NAN);
            }
            if (i % 10 == 0) {
                RTCRay occ = embree_ray(rays[i]).ray;
                rtcInitIntersectContext(&context);
                rtcOccluded1(scene, &context, &occ);
                bool e_occ = occ.tfar == -std::numeric_limits<float>::infinity();
                if ((dm_bvh_occluded(bvh, &rays[i]) != 0) != e_occ) occl_bad++;
            }
        }
        std::printf("%s %s: %zu triangles, %zu rays, %zu hits, %zu mismatches (%zu where our t is the exact plane "
                    "distance and Embree's is not), %zu ties (same t, other triangle), worst |dt| %.3g of the "
                    "tolerance, %zu occlusion differences in %zu\n", name, kind_name, m.nt, rays.size(), hits,
                    mismatches, embree_rounding, ties, worst, occl_bad, (rays.size() + 9) / 10);
        T_CHECK_MSG(hits > rays.size() / 10, "%s %s: %zu hits", name, kind_name, hits);
        T_CHECK_MSG((double)mismatches <= 1e-5 * (double)rays.size(), "%s %s: %zu mismatches of %zu rays", name,
                    kind_name, mismatches, rays.size());
        T_CHECK_MSG((double)occl_bad <= 1e-5 * (double)rays.size() + 1.0, "%s %s: %zu occlusion differences", name,
                    kind_name, occl_bad);
    }
    dm_bvh_info info;
    dm_bvh_get_info(bvh, &info);
    T_EQ_SIZE(info.triangle_count, m.nt);
    T_CHECK(info.memory_bytes > 0 && info.max_depth < 128);
    rtcReleaseScene(scene);
    dm_bvh_free(bvh);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    const bool sanitize = std::getenv("TEST_SANITIZE") != NULL;
    long embree_errors = 0;
    RTCDevice device = rtcNewDevice(NULL);
    T_CHECK(device != NULL);
    if (!device) {
        T_SKIP_N(4 * CHECKS_PER_MESH + 1, "dispmesh BVH vs Embree", "rtcNewDevice failed (counted above)");
        return T_END();
    }
    rtcSetDeviceErrorFunction(device, embree_error, &embree_errors);

    mio_mesh bunny;
    mio_error err;
    mio_result mr = mio_read_file(REF_BUNNY_PATH, NULL, &bunny, &err);
    if (mr == MIO_OK) {
        mesh_view m = {bunny.positions, bunny.vertex_count, bunny.indices, bunny.triangle_count, {0, 0, 0}, {0, 0, 0}, 0};
        bounds(m);
        check_mesh("bunny", m, device, 1000000);
        mio_free_mesh(&bunny);
    } else {
        T_SKIP_N(CHECKS_PER_MESH, "bunny vs Embree", REF_BUNNY_PATH " unreadable: apt-get install glmark2-data");
    }

    const int freqs[3] = {7, 71, 224};
    for (int f = 0; f < 3; f++) {
        gsph_mesh g;
        char name[32];
        std::snprintf(name, sizeof name, "sphere_f%d", freqs[f]);
        if (gsph_generate(freqs[f], &g) != 0) {
            T_CHECK_MSG(0, "%s: gsph_generate failed", name);
            T_SKIP_N(CHECKS_PER_MESH - 1, name, "no mesh (counted above)");
            continue;
        }
        mesh_view m = {g.positions, g.vertex_count, g.indices, g.triangle_count, {0, 0, 0}, {0, 0, 0}, 0};
        bounds(m);
        size_t rays = 1000000;
        if (sanitize && g.triangle_count > 500000) {
            rays = 100000;
            std::printf("note: TEST_SANITIZE is set: %s uses %zu rays per set instead of 1,000,000\n", name, rays);
        }
        check_mesh(name, m, device, rays);
        gsph_free(&g);
    }
    rtcReleaseDevice(device);
    T_EQ_INT(embree_errors, 0);
    return T_END();
}
