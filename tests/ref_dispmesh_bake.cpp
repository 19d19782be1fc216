/* ref_dispmesh_bake.cpp - dispmesh.h part 3 on the Stanford bunny, checked against Embree.

   Base: meshopt_simplify of the bunny to 500 triangles (not a bounding shell: the bake looks both
   ways). Checks: the parameterization properties of issue 8 on a real base (no flipped UV
   triangle, 95% of area ratios in [0.8, 1.25], seam walks come back); the bake's depths against
   Embree's rtcIntersect1 cast both ways along the same line from the same point (every 5th
   texel); at most 1% of the texels under the base flagged; the reconstruction closer to the
   bunny than the base by 10x in RMS. Skips when glmark2-data is missing. */
#include <embree3/rtcore.h>
#include <meshoptimizer.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "test.h"
#include "embree_mesh.hpp"

#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

static float embree_t(RTCScene scene, const float o[3], const float d[3], float tmax)
{
    RTCIntersectContext context;
    RTCRayHit rh;
    rtcInitIntersectContext(&context);
    std::memset(&rh, 0, sizeof rh);
    rh.ray.org_x = o[0]; rh.ray.org_y = o[1]; rh.ray.org_z = o[2];
    rh.ray.dir_x = d[0]; rh.ray.dir_y = d[1]; rh.ray.dir_z = d[2];
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = tmax;
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    const char *path = "/usr/share/glmark2/models/bunny.obj";
    mio_mesh mesh;
    mio_error err;
    if (mio_read_file(path, NULL, &mesh, &err) != MIO_OK) {
        T_SKIP_N(12, "bunny checks", "/usr/share/glmark2/models/bunny.obj missing: apt-get install glmark2-data");
        return T_END();
    }
    const float *pos = mesh.positions;
    size_t nv = mesh.vertex_count, nt = mesh.triangle_count;
    const uint32_t *idx = mesh.indices;
    std::vector<uint32_t> base(3 * nt);
    float e = 0.0f;
    size_t n3 = meshopt_simplify(base.data(), idx, 3 * nt, pos, nv, 3 * sizeof(float), 1500, 1.0f, 0, &e);
    base.resize(n3);
    size_t bt = n3 / 3;
    T_CHECK(bt > 400 && bt <= 510);

    int res = 512; /* the figure; at 256^2 the RMS ratio is 0.14 */
    dm_param_options po;
    std::memset(&po, 0, sizeof po);
    po.width = po.height = res;
    dm_param *pm = NULL;
    T_EQ_INT(dm_parameterize(pos, nv, base.data(), bt, &po, &pm), DM_OK);
    if (!pm) { mio_free_mesh(&mesh); return T_END(); }

    /* parameterization properties, computed here from the UVs */
    size_t flipped = 0, ok = 0;
    double su = 0.0, sa = 0.0;
    std::vector<double> uva(bt), a3(bt);
    for (size_t t = 0; t < bt; t++) {
        const float *u = pm->uv + 6 * t;
        const float *p0 = pos + 3 * base[3 * t], *p1 = pos + 3 * base[3 * t + 1], *p2 = pos + 3 * base[3 * t + 2];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
        uva[t] = 0.5 * (((double)u[2] - u[0]) * ((double)u[5] - u[1]) - ((double)u[4] - u[0]) * ((double)u[3] - u[1]));
        a3[t] = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
        flipped += !(uva[t] > 0.0);
        su += uva[t];
        sa += a3[t];
    }
    for (size_t t = 0; t < bt; t++) {
        double r = uva[t] / a3[t] / (su / sa);
        ok += r >= 0.8 && r <= 1.25;
    }
    T_CHECK_MSG(flipped == 0, "%zu flipped UV triangles", flipped);
    T_CHECK_MSG(ok >= 0.95 * bt, "%zu of %zu area ratios in [0.8, 1.25]", ok, bt);
    size_t n = (size_t)res * res, across = 0, failed = 0;
    static const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    for (size_t i = 0; i < n; i++) {
        if (pm->texel_triangle[i] == DM_NO_HIT) continue;
        for (int dir = 0; dir < 4; dir++) {
            uint32_t j = pm->nbr[4 * i + dir];
            if (j == UINT32_MAX) continue;
            int rot = pm->nbr_rot[4 * i + dir];
            if (pm->chart[pm->texel_triangle[j]] == pm->chart[pm->texel_triangle[i]] && rot == 0) continue;
            across++;
            int ex = dx[dir], ey = dy[dir];
            for (; rot > 0; rot--) { int tmp = ex; ex = -ey; ey = tmp; }
            int bd = ex == -1 ? 0 : ex == 1 ? 1 : ey == -1 ? 2 : 3;
            uint32_t k = pm->nbr[4 * (size_t)j + bd];
            if (k == UINT32_MAX || std::abs((int)(k % res) - (int)(i % res)) > 1 || std::abs((int)(k / res) - (int)(i / res)) > 1)
                failed++;
        }
    }
    /* all: at the few chart corners where no texel of the other chart walks back, the header
       links the texel to itself with a half turn (a mirror); counted below */
    T_CHECK_MSG(across > 0 && failed == 0, "%zu of %zu seam walks did not come back", failed, across);
    size_t mirrors = 0;
    for (size_t i = 0; i < n; i++)
        for (int dir = 0; dir < 4; dir++) mirrors += pm->nbr[4 * i + dir] == i && pm->nbr_rot[4 * i + dir] == 2;
    T_CHECK_MSG(mirrors <= across / 1000, "%zu mirror links of %zu seam crossings", mirrors, across);
    std::printf("  note: %zu mirror links (chart corners)\n", mirrors);
    std::printf("  note: bunny base %zu tris, %dx%d: %zu charts, utilization %.3f, stretch L2 %.3f max %.3f, area ok %.3f, "
                "%zu seam crossings, %zu not walking back\n", bt, res, res, pm->chart_count, pm->utilization,
                pm->stretch_l2, pm->stretch_max, pm->area_ratio_ok, across, failed);

    /* area-proportional to the original's area over each base triangle (dm_coverage_weights) */
    {
        std::vector<float> w(bt);
        double orig_area = 0.0, wsum = 0.0;
        for (size_t t = 0; t < nt; t++) {
            const float *p0 = pos + 3 * idx[3 * t], *p1 = pos + 3 * idx[3 * t + 1], *p2 = pos + 3 * idx[3 * t + 2];
            double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
            double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
            orig_area += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
        }
        T_EQ_INT(dm_coverage_weights(pos, nv, base.data(), bt, pos, nv, idx, nt, NULL, w.data()), DM_OK);
        for (size_t t = 0; t < bt; t++) wsum += w[t];
        /* every original triangle counted once; the 5% floor may add up to 5% */
        T_CHECK_MSG(wsum >= orig_area * (1.0 - 1e-4) && wsum <= 1.05 * orig_area, "weights add to %.5f, bunny area %.5f",
                    wsum, orig_area);
        dm_param_options pw = po;
        pw.triangle_weight = w.data();
        dm_param *pmw = NULL;
        T_EQ_INT(dm_parameterize(pos, nv, base.data(), bt, &pw, &pmw), DM_OK);
        if (pmw) {
            size_t wflipped = 0, wok = 0;
            double wu = 0.0;
            std::vector<double> wa(bt);
            for (size_t t = 0; t < bt; t++) {
                const float *u = pmw->uv + 6 * t;
                wa[t] = 0.5 * (((double)u[2] - u[0]) * ((double)u[5] - u[1]) - ((double)u[4] - u[0]) * ((double)u[3] - u[1]));
                wflipped += !(wa[t] > 0.0);
                wu += wa[t];
            }
            for (size_t t = 0; t < bt; t++) {
                double r = wa[t] / w[t] / (wu / wsum);
                wok += r >= 0.8 && r <= 1.25;
            }
            T_CHECK_MSG(wflipped == 0 && wok >= 0.95 * bt, "coverage weights: %zu flipped, %zu of %zu area ratios in [0.8, 1.25]",
                        wflipped, wok, bt);
            std::printf("  note: coverage weights: %zu of %zu area ratios in [0.8, 1.25], utilization %.3f\n", wok, bt,
                        pmw->utilization);
            dm_param_free(pmw);
        }
    }

    /* bake, against Embree */
    dm_dispmap *map = NULL;
    T_EQ_INT(dm_bake(pm, pos, nv, base.data(), bt, pos, nv, idx, nt, NULL, &map), DM_OK);
    if (map) {
        em_scene em;
        em_open(em, pos, nv, idx, nt);
        RTCScene scene = em.scene;
        size_t checked = 0, mismatched = 0, under = 0, flagged = 0;
        double tol = 1e-5 * 0.25; /* the bunny's diagonal is about 0.25 */
        for (size_t i = 0; i < n; i++) {
            if (map->status[i] == DM_TEXEL_EMPTY || map->status[i] == DM_TEXEL_BORDER) continue;
            under++;
            flagged += map->status[i] == DM_TEXEL_MISS;
            if (i % 5) continue;
            float o[3] = {map->pos[3 * i], map->pos[3 * i + 1], map->pos[3 * i + 2]};
            float in[3] = {-map->nrm[3 * i], -map->nrm[3 * i + 1], -map->nrm[3 * i + 2]};
            float out[3] = {map->nrm[3 * i], map->nrm[3 * i + 1], map->nrm[3 * i + 2]};
            float tf = embree_t(scene, o, in, map->max_distance), tb = embree_t(scene, o, out, map->max_distance);
            float ref = tf <= tb ? tf : -tb;
            checked++;
            if (map->valid[i] ? !(std::fabs(ref - map->disp[i]) <= tol) : std::isfinite(ref)) mismatched++;
        }
        T_CHECK_MSG(mismatched <= checked / 1000, "%zu of %zu texels disagree with Embree", mismatched, checked);
        T_CHECK_MSG(flagged <= under / 100, "%zu of %zu texels under the base flagged", flagged, under);
        std::printf("  note: bake: %zu texels under the base, %zu flagged, %zu checked against Embree, %zu differ\n",
                    under, flagged, checked, mismatched);
        em_close(em);

        dm_trimesh *rec = NULL;
        T_EQ_INT(dm_reconstruct(map, pm, pos, nv, base.data(), bt, NULL, &rec), DM_OK);
        if (rec) {
            dm_distance_report rep, brep;
            dm_distance_options dopt = {};
            dopt.samples_per_side = getenv("TEST_SANITIZE") ? 20000 : 100000;
            T_EQ_INT(dm_surface_distance(pos, nv, idx, nt, rec->positions, rec->vertex_count, rec->indices,
                                         rec->triangle_count, &dopt, &rep), DM_OK);
            T_EQ_INT(dm_surface_distance(pos, nv, idx, nt, pos, nv, base.data(), bt, &dopt, &brep), DM_OK);
            T_CHECK_MSG(rep.rms <= 0.1 * brep.rms, "recon rms %.3g vs base-only %.3g", rep.rms, brep.rms);
            std::printf("  note: recon rms %.3g max %.3g; base only rms %.3g max %.3g (of the diagonal)\n", rep.rms,
                        rep.max, brep.rms, brep.max);
            dm_trimesh_free(rec);
        }
        dm_dispmap_free(map);
    }
    dm_param_free(pm);
    mio_free_mesh(&mesh);
    return T_END();
}
