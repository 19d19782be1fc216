/* bvh_rays.hpp - the ray sets that the BVH reference test (tests/ref_embree_bvh.cpp) and the BVH bench
   (bench/bench_bvh.cpp) trace, in one place so that both measure the same kinds of rays.
   Include after dispmesh.h (uses dm_ray). Every ray is a pure function of the mesh and its index
   (tests/hashrand.h), so runs and programs agree. */
#ifndef TESTS_BVH_RAYS_HPP
#define TESTS_BVH_RAYS_HPP
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "hashrand.h"

struct mesh_view {
    const float *pos;
    size_t nv;
    const uint32_t *idx;
    size_t nt;
    float lo[3], hi[3]; /* bounding box and its diagonal, filled by bounds() */
    double diag;
};

static inline void bounds(mesh_view &m)
{
    for (int k = 0; k < 3; k++) m.lo[k] = m.hi[k] = m.pos[k];
    for (size_t v = 0; v < m.nv; v++)
        for (int k = 0; k < 3; k++) {
            m.lo[k] = std::fmin(m.lo[k], m.pos[3 * v + k]);
            m.hi[k] = std::fmax(m.hi[k], m.pos[3 * v + k]);
        }
    m.diag = 0;
    for (int k = 0; k < 3; k++) m.diag += (double)(m.hi[k] - m.lo[k]) * (m.hi[k] - m.lo[k]);
    m.diag = std::sqrt(m.diag);
}

/* incoherent rays: uniform origins in the bounding box (bounds() first), uniform directions */
static inline void incoherent_rays(const mesh_view &m, size_t count, std::vector<dm_ray> &rays)
{
    rays.resize(count);
    for (size_t i = 0; i < count; i++) {
        dm_ray &r = rays[i];
        for (int k = 0; k < 3; k++) r.org[k] = (float)(m.lo[k] + (m.hi[k] - m.lo[k]) * unit_random(i, 1 + (uint64_t)k));
        random_direction(i, 4, r.dir);
        r.tmin = 0.0f;
        r.tmax = std::numeric_limits<float>::infinity();
    }
}

/* bake-style rays from a surface (pos with nv vertices, triangles idx/nt, e.g. a simplified copy of
   the mesh): area-uniform points, direction the interpolated area-weighted vertex normal,
   alternating +n / -n. With offset > 0 each origin is moved along n by a uniform amount in
   [-offset, offset], so the surface itself is not always the start point. */
static inline void surface_rays(const float *pos, size_t nv, const uint32_t *idx, size_t nt, double offset,
                                size_t count, std::vector<dm_ray> &rays)
{
    std::vector<double> normals(3 * nv, 0.0), cdf(nt);
    double total = 0.0;
    for (size_t t = 0; t < nt; t++) {
        const float *a = pos + 3 * (size_t)idx[3 * t], *b = pos + 3 * (size_t)idx[3 * t + 1],
                    *c = pos + 3 * (size_t)idx[3 * t + 2];
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)b[k] - a[k];
            e2[k] = (double)c[k] - a[k];
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) normals[3 * (size_t)idx[3 * t + j] + k] += n[k];
        total += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        cdf[t] = total;
    }
    rays.resize(count);
    for (size_t i = 0; i < count; i++) {
        double x = unit_random(i, 7) * total;
        size_t lo = 0, hi = nt - 1;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (cdf[mid] < x) lo = mid + 1;
            else hi = mid;
        }
        double r1 = unit_random(i, 8), r2 = unit_random(i, 9);
        if (r1 + r2 > 1.0) {
            r1 = 1.0 - r1;
            r2 = 1.0 - r2;
        }
        double w[3] = {1.0 - r1 - r2, r1, r2}, p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
        for (int j = 0; j < 3; j++) {
            uint32_t v = idx[3 * lo + j];
            double len = std::sqrt(normals[3 * v] * normals[3 * v] + normals[3 * v + 1] * normals[3 * v + 1] +
                                   normals[3 * v + 2] * normals[3 * v + 2]);
            for (int k = 0; k < 3; k++) {
                p[k] += w[j] * pos[3 * (size_t)v + k];
                if (len > 0) n[k] += w[j] * normals[3 * v + k] / len;
            }
        }
        double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0)) {
            n[0] = 0; n[1] = 0; n[2] = 1; len = 1;
        }
        double shift = offset > 0 ? offset * (2.0 * unit_random(i, 10) - 1.0) : 0.0, sign = (i & 1) ? -1.0 : 1.0;
        dm_ray &r = rays[i];
        for (int k = 0; k < 3; k++) {
            r.org[k] = (float)(p[k] + shift * n[k] / len);
            r.dir[k] = (float)(sign * n[k] / len);
        }
        r.tmin = 0.0f;
        r.tmax = std::numeric_limits<float>::infinity();
    }
}
#endif
