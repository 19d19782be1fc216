/* butterfly_compare.hpp - subdiv4.h's butterfly against OpenMesh's ModifiedButterflyT, one level
   at a time, for tests/ref_openmesh_butterfly.cpp and bench/bench_subdiv4.cpp (C++, needs
   openmesh.hpp and subdiv4.h included before it).

   Correspondence: old vertices by index (both keep them); a new vertex by the edge it split,
   i.e. by its two neighbours that existed before the level (in a 1 -> 4 split a new vertex is
   adjacent to exactly two old ones). maxdiff = largest distance between corresponding vertices
   divided by the input's bounding-box diagonal. A vertex "touches a boundary" when a boundary
   vertex, or a vertex that touched one at an earlier level, lies in the one-ring of either end
   of its edge; such vertices are reported in maxdiff_boundary instead. */
#ifndef TESTS_BUTTERFLY_COMPARE_HPP
#define TESTS_BUTTERFLY_COMPARE_HPP
#include <OpenMesh/Tools/Subdivider/Uniform/ModifiedButterFlyT.hh>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

struct bf_result {
    double maxdiff = 0.0;          /* over vertices whose stencils see no boundary */
    double maxdiff_boundary = 0.0; /* over the others */
    size_t vertices = 0, boundary_vertices = 0;
    size_t unmatched = 0;          /* OpenMesh vertices without a counterpart (should be 0) */
    size_t ours_vertices = 0, om_vertices = 0, ours_triangles = 0, om_faces = 0;
    bool ok = false;               /* both ran */
};

/* builds an OpenMesh mesh; returns false if OpenMesh rejected a face */
static inline bool bf_to_openmesh(const float *pos, size_t nv, const uint32_t *tri, size_t nt, TriMesh &om)
{
    std::vector<TriMesh::VertexHandle> vh(nv);
    for (size_t v = 0; v < nv; v++) vh[v] = om.add_vertex(TriMesh::Point(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
    bool all = true;
    for (size_t t = 0; t < nt; t++)
        if (!om.add_face(vh[tri[3 * t]], vh[tri[3 * t + 1]], vh[tri[3 * t + 2]]).is_valid()) all = false;
    return all;
}

/* OpenMesh's subdivision, n levels (what the bench times) */
static inline void bf_openmesh_subdivide(TriMesh &om, int levels)
{
    OpenMesh::Subdivider::Uniform::ModifiedButterflyT<TriMesh> sub;
    sub.attach(om);
    sub(static_cast<size_t>(levels));
    sub.detach();
}

static inline bf_result bf_compare(const float *pos, size_t nv, const uint32_t *tri, size_t nt, int levels)
{
    bf_result res;
    TriMesh om;
    if (!bf_to_openmesh(pos, nv, tri, nt, om)) return res;
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = std::min(lo[k], (double)pos[3 * v + k]);
            hi[k] = std::max(hi[k], (double)pos[3 * v + k]);
        }
    double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                            (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(diag > 0.0)) diag = 1.0;
    std::vector<float> cp(pos, pos + 3 * nv);
    std::vector<uint32_t> ct(tri, tri + 3 * nt);
    std::vector<uint32_t> om_to_ours(nv);
    std::vector<char> flagged(nv, 0); /* by our index */
    for (size_t v = 0; v < nv; v++) om_to_ours[v] = (uint32_t)v;
    for (int lev = 0; lev < levels; lev++) {
        size_t nprev = cp.size() / 3, omprev = om.n_vertices();
        /* which old vertices have a boundary (or a flagged vertex) in their one-ring */
        std::vector<char> touch(omprev, 0);
        for (auto v : om.vertices()) {
            bool t = om.is_boundary(v) || flagged[om_to_ours[v.idx()]];
            for (auto w : om.vv_range(v)) t = t || om.is_boundary(w) || flagged[om_to_ours[w.idx()]];
            touch[v.idx()] = t;
        }
        sd4_mesh m;
        if (sd4_butterfly(cp.data(), nprev, ct.data(), ct.size() / 3, 1, 1.0 / 16.0, NULL, &m) != SD4_OK) return res;
        bf_openmesh_subdivide(om, 1);
        /* our new vertices by their old ends */
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> by_edge;
        std::vector<std::vector<uint32_t>> old_nbr(m.vertex_count);
        for (size_t t = 0; t < m.triangle_count; t++)
            for (int k = 0; k < 3; k++) {
                uint32_t x = m.indices[3 * t + k], y = m.indices[3 * t + (k + 1) % 3];
                if (x < nprev && y >= nprev) old_nbr[y].push_back(x);
                if (y < nprev && x >= nprev) old_nbr[x].push_back(y);
            }
        for (size_t y = nprev; y < m.vertex_count; y++) {
            std::vector<uint32_t> &o = old_nbr[y];
            std::sort(o.begin(), o.end());
            o.erase(std::unique(o.begin(), o.end()), o.end());
            if (o.size() == 2) by_edge[std::make_pair(o[0], o[1])] = (uint32_t)y;
        }
        std::vector<uint32_t> map2(om.n_vertices(), UINT32_MAX);
        std::vector<char> flag2(m.vertex_count, 0);
        for (size_t v = 0; v < nprev; v++) flag2[v] = flagged[v];
        for (auto v : om.vertices()) {
            size_t i = (size_t)v.idx();
            if (i < omprev) { map2[i] = om_to_ours[i]; continue; }
            std::vector<uint32_t> o;
            bool t = false;
            for (auto w : om.vv_range(v))
                if ((size_t)w.idx() < omprev) { o.push_back(om_to_ours[w.idx()]); t = t || touch[w.idx()]; }
            std::sort(o.begin(), o.end());
            if (o.size() != 2 || !by_edge.count(std::make_pair(o[0], o[1]))) { res.unmatched++; continue; }
            uint32_t y = by_edge[std::make_pair(o[0], o[1])];
            map2[i] = y;
            flag2[y] = t;
        }
        om_to_ours.swap(map2);
        flagged.swap(flag2);
        cp.assign(m.positions, m.positions + 3 * m.vertex_count);
        ct.assign(m.indices, m.indices + 3 * m.triangle_count);
        sd4_free_mesh(&m);
    }
    res.vertices = res.boundary_vertices = 0;
    for (auto v : om.vertices()) {
        uint32_t y = om_to_ours[v.idx()];
        if (y == UINT32_MAX) continue;
        TriMesh::Point p = om.point(v);
        double d = 0.0;
        for (int k = 0; k < 3; k++) d += ((double)p[k] - cp[3 * (size_t)y + k]) * ((double)p[k] - cp[3 * (size_t)y + k]);
        d = std::sqrt(d) / diag;
        if (flagged[y]) { res.maxdiff_boundary = std::max(res.maxdiff_boundary, d); res.boundary_vertices++; }
        else { res.maxdiff = std::max(res.maxdiff, d); res.vertices++; }
    }
    res.ours_vertices = cp.size() / 3;
    res.ours_triangles = ct.size() / 3;
    res.om_vertices = om.n_vertices();
    res.om_faces = om.n_faces();
    res.ok = true;
    return res;
}
#endif
