/* surface_distance.hpp - symmetric surface distance between two triangle meshes, measured with
   Embree 3's point query (rtcPointQuery) as the closest-point search (link -lembree3). Used by the
   simplification reference test and bench (and meant for the displacement-map checks).

       sd_mesh a = {pos_a, nv_a, idx_a, nt_a}, b = {pos_b, nv_b, idx_b, nt_b};
       sd_result r;
       if (!sd_distance(a, b, 200000, &r)) fail();
       // r.rms, r.max: fractions of a's bounding-box diagonal

   Samples: `samples` points per side, area-uniform on the triangles (triangle by a binary search of
   the area CDF, then uniform barycentrics by the square-root rule), from tests/hashrand.h (a pure
   function of the index: the same points on every run). For the max, also every vertex a
   triangle uses, on both sides. rms = sqrt of the mean squared distance over the samples of both
   sides together; max = the largest distance over the samples and the vertices of both sides.
   Distances are divided by the diagonal of mesh a's bounding box (the reference mesh). The
   closest point on a triangle is computed in double (Ericson 2005, 5.1.5), Embree's BVH finds the
   triangle. */
#ifndef TESTS_SURFACE_DISTANCE_HPP
#define TESTS_SURFACE_DISTANCE_HPP
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "hashrand.h"

struct sd_mesh {
    const float *pos;
    size_t vertex_count;
    const uint32_t *idx;
    size_t triangle_count;
};

struct sd_result {
    double rms, max;       /* symmetric, fraction of the diagonal of a */
    double rms_ab, max_ab; /* samples of a against b */
    double rms_ba, max_ba; /* samples of b against a */
    double diagonal;       /* of a, in mesh units */
};

/* squared distance from p to triangle (a, b, c), all in double */
static inline double sd__point_triangle_d2(const double p[3], const double a[3], const double b[3], const double c[3])
{
    double ab[3], ac[3], ap[3], q[3];
    for (int k = 0; k < 3; k++) { ab[k] = b[k] - a[k]; ac[k] = c[k] - a[k]; ap[k] = p[k] - a[k]; }
    auto dot = [](const double *x, const double *y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
    double d1 = dot(ab, ap), d2 = dot(ac, ap);
    double v = 0, w = 0;
    if (d1 <= 0 && d2 <= 0) { v = 0; w = 0; }
    else {
        double bp[3], cp[3];
        for (int k = 0; k < 3; k++) { bp[k] = p[k] - b[k]; cp[k] = p[k] - c[k]; }
        double d3 = dot(ab, bp), d4 = dot(ac, bp), d5 = dot(ab, cp), d6 = dot(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0 && d4 <= d3) { v = 1; w = 0; }
        else if (d6 >= 0 && d5 <= d6) { v = 0; w = 1; }
        else if (vc <= 0 && d1 >= 0 && d3 <= 0) { v = d1 / (d1 - d3); w = 0; }
        else if (vb <= 0 && d2 >= 0 && d6 <= 0) { v = 0; w = d2 / (d2 - d6); }
        else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) { w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); v = 1 - w; }
        else {
            double den = va + vb + vc;
            if (den > 0) { v = vb / den; w = vc / den; }
        }
    }
    double d = 0;
    for (int k = 0; k < 3; k++) { q[k] = a[k] + v * ab[k] + w * ac[k] - p[k]; d += q[k] * q[k]; }
    return d;
}

/* A mesh in an Embree scene, ready for closest-point queries. */
class sd_scene {
public:
    sd_scene(RTCDevice dev, const sd_mesh &m) : m_(m), scene_(nullptr)
    {
        scene_ = rtcNewScene(dev);
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *v = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                    3 * sizeof(float), m.vertex_count);
        uint32_t *t = (uint32_t *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                          3 * sizeof(uint32_t), m.triangle_count);
        if (v && t) {
            std::memcpy(v, m.pos, 3 * sizeof(float) * m.vertex_count);
            std::memcpy(t, m.idx, 3 * sizeof(uint32_t) * m.triangle_count);
        }
        rtcCommitGeometry(g);
        rtcAttachGeometry(scene_, g);
        rtcReleaseGeometry(g);
        rtcCommitScene(scene_);
    }
    ~sd_scene() { if (scene_) rtcReleaseScene(scene_); }
    sd_scene(const sd_scene &) = delete;
    sd_scene &operator=(const sd_scene &) = delete;

    /* distance from p to the mesh */
    double distance(const double p[3]) const
    {
        RTCPointQuery q;
        q.x = (float)p[0]; q.y = (float)p[1]; q.z = (float)p[2];
        q.time = 0.f;
        q.radius = INFINITY;
        query_state st;
        st.self = this;
        for (int k = 0; k < 3; k++) st.p[k] = p[k];
        st.best_d2 = INFINITY;
        RTCPointQueryContext ctx;
        rtcInitPointQueryContext(&ctx);
        rtcPointQuery(scene_, &q, &ctx, &sd_scene::callback, &st);
        return std::sqrt(st.best_d2);
    }

private:
    struct query_state {
        const sd_scene *self;
        double p[3];
        double best_d2;
    };
    static bool callback(RTCPointQueryFunctionArguments *args)
    {
        query_state *st = (query_state *)args->userPtr;
        const sd_mesh &m = st->self->m_;
        const uint32_t *t = m.idx + 3 * (size_t)args->primID;
        double a[3], b[3], c[3];
        for (int k = 0; k < 3; k++) {
            a[k] = m.pos[3 * (size_t)t[0] + k];
            b[k] = m.pos[3 * (size_t)t[1] + k];
            c[k] = m.pos[3 * (size_t)t[2] + k];
        }
        double d2 = sd__point_triangle_d2(st->p, a, b, c);
        if (d2 < st->best_d2) {
            st->best_d2 = d2;
            /* Embree's radius is a float: round up so that the triangle's own box is never culled */
            float r = (float)std::sqrt(d2);
            args->query->radius = std::nextafter(r, INFINITY);
            return true;
        }
        return false;
    }
    sd_mesh m_;
    RTCScene scene_;
};

/* area-uniform sample i of mesh m (cdf: prefix sums of triangle areas) */
static inline void sd__sample(const sd_mesh &m, const std::vector<double> &cdf, uint64_t i, uint64_t stream, double p[3])
{
    double total = cdf.back();
    double u = unit_random(i, stream) * total;
    size_t t = (size_t)(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
    if (t >= m.triangle_count) t = m.triangle_count - 1;
    double r1 = std::sqrt(unit_random(i, stream + 1)), r2 = unit_random(i, stream + 2);
    double wa = 1 - r1, wb = r1 * (1 - r2), wc = r1 * r2;
    const uint32_t *tr = m.idx + 3 * t;
    for (int k = 0; k < 3; k++)
        p[k] = wa * m.pos[3 * (size_t)tr[0] + k] + wb * m.pos[3 * (size_t)tr[1] + k] + wc * m.pos[3 * (size_t)tr[2] + k];
}

static inline std::vector<double> sd__area_cdf(const sd_mesh &m)
{
    std::vector<double> cdf(m.triangle_count);
    double acc = 0;
    for (size_t t = 0; t < m.triangle_count; t++) {
        const float *a = m.pos + 3 * (size_t)m.idx[3 * t], *b = m.pos + 3 * (size_t)m.idx[3 * t + 1],
                    *c = m.pos + 3 * (size_t)m.idx[3 * t + 2];
        double e[3], f[3];
        for (int k = 0; k < 3; k++) { e[k] = (double)b[k] - a[k]; f[k] = (double)c[k] - a[k]; }
        double n0 = e[1] * f[2] - e[2] * f[1], n1 = e[2] * f[0] - e[0] * f[2], n2 = e[0] * f[1] - e[1] * f[0];
        acc += 0.5 * std::sqrt(n0 * n0 + n1 * n1 + n2 * n2);
        cdf[t] = acc;
    }
    return cdf;
}

/* one side: samples of `from` against `to`; sum of squares and max in mesh units */
static inline void sd__one_side(const sd_mesh &from, const sd_scene &to, size_t samples, uint64_t stream, double *sum2,
                                double *max_sample, double *max_vertex)
{
    std::vector<double> cdf = sd__area_cdf(from);
    double s2 = 0, mx = 0, mv = 0;
    if (!cdf.empty() && cdf.back() > 0)
        for (size_t i = 0; i < samples; i++) {
            double p[3];
            sd__sample(from, cdf, i, stream, p);
            double d = to.distance(p);
            s2 += d * d;
            if (d > mx) mx = d;
        }
    std::vector<char> used(from.vertex_count, 0);
    for (size_t i = 0; i < 3 * from.triangle_count; i++) used[from.idx[i]] = 1;
    for (size_t v = 0; v < from.vertex_count; v++) {
        if (!used[v]) continue;
        double p[3] = {from.pos[3 * v], from.pos[3 * v + 1], from.pos[3 * v + 2]};
        double d = to.distance(p);
        if (d > mv) mv = d;
    }
    *sum2 = s2;
    *max_sample = mx;
    *max_vertex = mv;
}

static inline double sd_diagonal(const sd_mesh &m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < 3 * m.triangle_count; i++)
        for (int k = 0; k < 3; k++) {
            double x = m.pos[3 * (size_t)m.idx[i] + k];
            lo[k] = std::min(lo[k], x);
            hi[k] = std::max(hi[k], x);
        }
    double d2 = 0;
    for (int k = 0; k < 3; k++) d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return std::sqrt(d2);
}

/* Symmetric distance between a (the reference) and b. Returns false for an empty mesh. */
static inline bool sd_distance(const sd_mesh &a, const sd_mesh &b, size_t samples, sd_result *out)
{
    if (!a.triangle_count || !b.triangle_count || samples == 0) return false;
    RTCDevice dev = rtcNewDevice("threads=1");
    if (!dev) return false;
    double diag = sd_diagonal(a);
    double s_ab, m_ab, v_ab, s_ba, m_ba, v_ba;
    {
        sd_scene sa(dev, a), sb(dev, b);
        sd__one_side(a, sb, samples, 0, &s_ab, &m_ab, &v_ab);
        sd__one_side(b, sa, samples, 4, &s_ba, &m_ba, &v_ba);
    }
    rtcReleaseDevice(dev);
    double inv = diag > 0 ? 1.0 / diag : 1.0;
    out->diagonal = diag;
    out->rms_ab = std::sqrt(s_ab / (double)samples) * inv;
    out->rms_ba = std::sqrt(s_ba / (double)samples) * inv;
    out->max_ab = std::max(m_ab, v_ab) * inv;
    out->max_ba = std::max(m_ba, v_ba) * inv;
    out->rms = std::sqrt((s_ab + s_ba) / (2.0 * (double)samples)) * inv;
    out->max = std::max(out->max_ab, out->max_ba);
    return true;
}
#endif
