/* ref_openmesh_simplify - dispmesh.h's QEM simplifier against OpenMesh's Decimater (ModQuadric +
   ModNormalFlipping, tests/openmesh_decimate.hpp), measured with Embree's point query
   (tests/surface_distance.hpp).

   For the bunny (/usr/share/glmark2/models/bunny.obj; skipped with a reason if missing) at 1% and
   10% of its triangles: OpenMesh decimates to the target; ours runs with OpenMesh's triangle count
   as its target and must reach no more triangles. The symmetric surface distance to the input
   (RMS over 200k area-uniform samples per side; max over those samples and every vertex; both as
   fractions of the input's bounding-box diagonal) must satisfy ours RMS <= 1.0 x OpenMesh's and
   ours max <= 1.15 x OpenMesh's. Ours must also be a closed, consistently oriented 2-manifold
   (the bunny is one) without degenerate triangles. With TEST_SANITIZE set the samples drop to
   50k per side (the note is printed). */
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <algorithm>

#include "test.h"
#include "openmesh_decimate.hpp"
#include "surface_distance.hpp"
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

#define BUNNY "/usr/share/glmark2/models/bunny.obj"

/* directed-edge check: every edge twice, once each way; degenerate: 2 area <= 1e-6 longest^2 */
static void check_manifold(const std::vector<float> &p, const std::vector<uint32_t> &idx, size_t *bad, size_t *deg)
{
    std::vector<uint64_t> e, r;
    *bad = *deg = 0;
    for (size_t t = 0; t < idx.size() / 3; t++) {
        double a[3], b[3], c[3], l;
        for (int k = 0; k < 3; k++) {
            uint64_t x = idx[3 * t + k], y = idx[3 * t + (k + 1) % 3];
            e.push_back(x << 32 | y);
            r.push_back(y << 32 | x);
        }
        for (int k = 0; k < 3; k++) {
            a[k] = (double)p[3 * idx[3 * t + 1] + k] - p[3 * idx[3 * t] + k];
            b[k] = (double)p[3 * idx[3 * t + 2] + k] - p[3 * idx[3 * t] + k];
            c[k] = (double)p[3 * idx[3 * t + 2] + k] - p[3 * idx[3 * t + 1] + k];
        }
        double n0 = a[1] * b[2] - a[2] * b[1], n1 = a[2] * b[0] - a[0] * b[2], n2 = a[0] * b[1] - a[1] * b[0];
        l = std::max({a[0] * a[0] + a[1] * a[1] + a[2] * a[2], b[0] * b[0] + b[1] * b[1] + b[2] * b[2],
                      c[0] * c[0] + c[1] * c[1] + c[2] * c[2]});
        if (!(std::sqrt(n0 * n0 + n1 * n1 + n2 * n2) > 1e-6 * l)) (*deg)++;
    }
    std::sort(e.begin(), e.end());
    std::sort(r.begin(), r.end());
    for (size_t i = 0; i < e.size(); i++)
        if ((i && e[i] == e[i - 1]) || e[i] != r[i]) (*bad)++;
}

static void compare(const mio_mesh &m, double fraction, size_t samples)
{
    size_t target = (size_t)(fraction * (double)m.triangle_count);
    TriMesh tm;
    om_build(m.positions, m.vertex_count, m.indices, m.triangle_count, tm);
    om_decimate_run(tm, target);
    std::vector<float> op;
    std::vector<uint32_t> oi;
    om_extract(tm, op, oi);
    dm_simplify_options o = {};
    o.target_triangles = oi.size() / 3;
    dm_pm *pm = nullptr;
    dm_simplify_report rep;
    T_EQ_INT(dm_simplify(m.positions, m.vertex_count, m.indices, m.triangle_count, &o, &pm, &rep), DM_OK);
    if (!pm) return;
    size_t nv, nt;
    dm_pm_counts(pm, &nv, &nt);
    std::vector<float> dp(3 * nv + 3);
    std::vector<uint32_t> di(3 * nt + 3);
    dm_pm_get_mesh(pm, dp.data(), di.data(), nullptr);
    di.resize(3 * nt);
    dm_pm_free(pm);
    sd_mesh in = {m.positions, m.vertex_count, m.indices, m.triangle_count};
    sd_mesh om = {op.data(), op.size() / 3, oi.data(), oi.size() / 3};
    sd_mesh ours = {dp.data(), nv, di.data(), nt};
    sd_result ro = {}, rd = {};
    T_CHECK(sd_distance(in, om, samples, &ro));
    T_CHECK(sd_distance(in, ours, samples, &rd));
    printf("  bunny %g%%: openmesh %zu tris rms %.4e max %.4e | ours %zu tris rms %.4e max %.4e | ratio rms %.3f max %.3f\n",
           100 * fraction, oi.size() / 3, ro.rms, ro.max, nt, rd.rms, rd.max, rd.rms / ro.rms, rd.max / ro.max);
    T_CHECK_MSG(nt <= oi.size() / 3, "ours %zu triangles > openmesh %zu", nt, oi.size() / 3);
    T_CHECK_MSG(rd.rms <= 1.0 * ro.rms, "rms %.4e > openmesh %.4e", rd.rms, ro.rms);
    T_CHECK_MSG(rd.max <= 1.15 * ro.max, "max %.4e > 1.15 x openmesh %.4e", rd.max, ro.max);
    size_t bad, deg;
    check_manifold(dp, di, &bad, &deg);
    T_CHECK_MSG(bad == 0, "%zu directed edges without a single opposite", bad);
    T_CHECK_MSG(deg == 0, "%zu degenerate triangles", deg);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    size_t samples = 200000;
    if (getenv("TEST_SANITIZE")) {
        samples = 50000;
        printf("  note: TEST_SANITIZE: 50k samples per side instead of 200k\n");
    }
    mio_mesh m;
    mio_error err;
    if (mio_read_file(BUNNY, nullptr, &m, &err) != MIO_OK) {
        T_SKIP_N(14, "bunny comparison", BUNNY " missing: apt-get install glmark2-data");
        return T_END();
    }
    compare(m, 0.01, samples);
    compare(m, 0.10, samples);
    mio_free_mesh(&m);
    return T_END();
}
