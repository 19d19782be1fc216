/* openmesh_decimate.hpp - OpenMesh's Decimater with ModQuadric + ModNormalFlipping (both at their
   defaults: no error bound, 90-degree normal limit), as the simplification test and bench run it.
   Link -lOpenMeshCore. */
#ifndef TESTS_OPENMESH_DECIMATE_HPP
#define TESTS_OPENMESH_DECIMATE_HPP
#include "openmesh.hpp"
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#include <cstdint>
#include <vector>

/* Builds the TriMesh (outside any timer a caller keeps: see om_decimate_run). */
static inline void om_build(const float *pos, size_t nv, const uint32_t *idx, size_t nt, TriMesh &mesh)
{
    std::vector<TriMesh::VertexHandle> vh(nv);
    for (size_t v = 0; v < nv; v++) vh[v] = mesh.add_vertex(TriMesh::Point(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
    for (size_t t = 0; t < nt; t++) mesh.add_face(vh[idx[3 * t]], vh[idx[3 * t + 1]], vh[idx[3 * t + 2]]);
}

/* Decimates to at most target_faces faces and removes the deleted elements. */
static inline void om_decimate_run(TriMesh &mesh, size_t target_faces)
{
    typedef OpenMesh::Decimater::DecimaterT<TriMesh> Decimater;
    typedef OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle HQuadric;
    typedef OpenMesh::Decimater::ModNormalFlippingT<TriMesh>::Handle HFlip;
    Decimater dec(mesh);
    HQuadric hq;
    HFlip hf;
    dec.add(hq);
    dec.add(hf);
    dec.initialize();
    dec.decimate_to_faces(0, target_faces);
    mesh.garbage_collection();
}

/* The mesh as flat arrays. */
static inline void om_extract(const TriMesh &mesh, std::vector<float> &pos, std::vector<uint32_t> &idx)
{
    pos.clear();
    idx.clear();
    for (auto v : mesh.vertices()) {
        auto p = mesh.point(v);
        pos.push_back(p[0]);
        pos.push_back(p[1]);
        pos.push_back(p[2]);
    }
    for (auto f : mesh.faces())
        for (auto v : mesh.fv_range(f)) idx.push_back((uint32_t)v.idx());
}
#endif
