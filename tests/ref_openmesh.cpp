/* ref_openmesh - reference checks against OpenMesh (Debian libopenmesh-dev, link -lOpenMeshCore).

   (a) The Stanford bunny from glmark2-data, read by OpenMesh's OBJ reader and by meshio.h:
       same vertex and face counts (34835, 69666), bit-identical positions in the same order,
       identical index triples in the same order. OpenMesh's importer does not drop faces it
       cannot link into its halfedge structure: it gives such a face three fresh copies of its
       vertices, appended after the file's vertices (ImporterT::add_face). Such copies are mapped
       back to the face's file vertices before comparing, and counted; the bunny has none, which
       the halfedge checks (closed, Euler characteristic 2) confirm independently.
   (b) The benchmark sphere (bench/sphere.h, frequency 224) written as OFF to a temporary file
       and read back by OpenMesh: 1,003,520 faces, no boundary halfedge, every vertex manifold
       with one fan holding all its triangles, Euler characteristic 2, and the positions and
       triples bit-identical to what the generator made (so %.9g round-trips through a third
       party parser too). */
#include "openmesh.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#include <unistd.h>

#include "test.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#include "../bench/sphere.h"


#ifndef REF_BUNNY_PATH /* overridable to exercise the skip path */
#define REF_BUNNY_PATH "/usr/share/glmark2/models/bunny.obj"
#endif
static const char *const bunny_path = REF_BUNNY_PATH;

static bool file_exists(const char *path)
{
    FILE *f = std::fopen(path, "rb");
    if (!f) return false;
    std::fclose(f);
    return true;
}

static bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/* closed (no boundary halfedge), every vertex manifold, Euler characteristic V - E + F */
struct halfedge_summary {
    size_t boundary_halfedges = 0, nonmanifold_vertices = 0;
    long long euler = 0;
};

static halfedge_summary summarize(const TriMesh &mesh)
{
    halfedge_summary s;
    for (auto h : mesh.halfedges())
        if (mesh.is_boundary(h)) s.boundary_halfedges++;
    for (auto v : mesh.vertices())
        if (!mesh.is_manifold(v)) s.nonmanifold_vertices++;
    s.euler = (long long)mesh.n_vertices() - (long long)mesh.n_edges() + (long long)mesh.n_faces();
    return s;
}

/* triples of OpenMesh face f, in the order the face was added (the face's halfedge is the one
   that closes the loop, so the circulator starts at the face's first vertex) */
static void face_triple(const TriMesh &mesh, OpenMesh::FaceHandle f, int out[3])
{
    int k = 0;
    for (auto v : mesh.fv_range(f)) {
        if (k < 3) out[k] = v.idx();
        k++;
    }
    if (k != 3) out[0] = out[1] = out[2] = -1;
}

static void check_bunny()
{
    if (!file_exists(bunny_path)) {
        T_SKIP_N(13, "bunny vs OpenMesh", REF_BUNNY_PATH " missing: apt-get install glmark2-data");
        return;
    }
    TriMesh om;
    OpenMesh::IO::Options options; /* defaults: positions and faces only */
    T_CHECK(OpenMesh::IO::read_mesh(om, bunny_path, options));

    mio_mesh mio;
    mio_error err;
    mio_result r = mio_read_file(bunny_path, NULL, &mio, &err);
    if (!T_CHECK_MSG(r == MIO_OK, "meshio: %s (%s)", err.message, mio_result_string(r))) {
        T_SKIP_N(11, "bunny comparisons", "meshio could not read the bunny (failure counted above)");
        return;
    }

    T_EQ_SIZE(mio.vertex_count, 34835);
    T_EQ_SIZE(mio.triangle_count, 69666);
    T_EQ_SIZE(om.n_faces(), mio.triangle_count);

    /* faces: map OpenMesh's per-face vertex copies (index >= file vertex count) back */
    size_t split_faces = 0, bad_split = 0, triple_mismatch = 0, first_bad = SIZE_MAX;
    const size_t file_vertices = mio.vertex_count;
    const size_t faces = om.n_faces() < mio.triangle_count ? om.n_faces() : mio.triangle_count;
    for (size_t i = 0; i < faces; i++) {
        int t[3];
        face_triple(om, om.face_handle((int)i), t);
        const uint32_t *expect = mio.indices + 3 * i;
        bool split = false;
        for (int k = 0; k < 3; k++) {
            if (t[k] >= 0 && (size_t)t[k] >= file_vertices) {
                /* a copy made by ImporterT for a face it could not link: same position as
                   the file vertex the face names at this corner */
                split = true;
                const auto &p = om.point(om.vertex_handle(t[k]));
                const float *q = mio.positions + 3 * (size_t)expect[k];
                if (!(same_bits(p[0], q[0]) && same_bits(p[1], q[1]) && same_bits(p[2], q[2]))) bad_split++;
                t[k] = (int)expect[k];
            }
        }
        if (split) split_faces++;
        if (t[0] != (int)expect[0] || t[1] != (int)expect[1] || t[2] != (int)expect[2]) {
            if (triple_mismatch++ == 0) first_bad = i;
        }
    }
    T_CHECK_MSG(triple_mismatch == 0, "%zu of %zu triples differ, first at face %zu", triple_mismatch,
                faces, first_bad);
    T_EQ_SIZE(bad_split, 0);
    /* the bunny is a closed manifold, so OpenMesh links every face and copies no vertex */
    T_EQ_SIZE(split_faces, 0);
    T_EQ_SIZE(om.n_vertices(), file_vertices + 3 * split_faces);

    size_t position_mismatch = 0, first_pos = SIZE_MAX;
    double worst = 0.0;
    for (size_t v = 0; v < file_vertices && v < om.n_vertices(); v++) {
        const auto &p = om.point(om.vertex_handle((int)v));
        const float *q = mio.positions + 3 * v;
        for (int k = 0; k < 3; k++)
            if (!same_bits(p[k], q[k])) {
                if (position_mismatch++ == 0) first_pos = v;
                double d = std::fabs((double)p[k] - (double)q[k]);
                if (d > worst) worst = d;
            }
    }
    T_CHECK_MSG(position_mismatch == 0, "%zu coordinates differ in bits (first vertex %zu, worst %.3g)",
                position_mismatch, first_pos, worst);

    halfedge_summary s = summarize(om);
    T_EQ_SIZE(s.boundary_halfedges, 0);
    T_EQ_SIZE(s.nonmanifold_vertices, 0);
    T_EQ_INT(s.euler, 2);
    std::printf("bunny: OpenMesh %zu vertices, %zu faces, %zu edges; meshio %zu vertices, %zu triangles; "
                "%zu split faces\n", om.n_vertices(), om.n_faces(), om.n_edges(), mio.vertex_count,
                mio.triangle_count, split_faces);
    mio_free_mesh(&mio);
}

static void check_sphere()
{
    const int freq = 224;
    gsph_mesh sphere;
    if (!T_EQ_INT(gsph_generate(freq, &sphere), 0)) {
        T_SKIP_N(11, "sphere vs OpenMesh", "generator failed (counted above)");
        return;
    }
    const char *dir = std::getenv("TMPDIR");
    std::string path = std::string(dir && *dir ? dir : "/tmp") + "/ref_openmesh_sphere_" +
                       std::to_string((long)getpid()) + ".off";
    FILE *file = std::fopen(path.c_str(), "wb");
    bool written = file && gsph_write_off(file, &sphere) == 0;
    if (file && std::fclose(file) != 0) written = false;
    if (!T_CHECK_MSG(written, "cannot write %s", path.c_str())) {
        std::remove(path.c_str());
        gsph_free(&sphere);
        T_SKIP_N(10, "sphere vs OpenMesh", "temporary OFF could not be written (counted above)");
        return;
    }

    TriMesh om;
    OpenMesh::IO::Options options;
    T_CHECK(OpenMesh::IO::read_mesh(om, path, options));
    std::remove(path.c_str());

    T_EQ_SIZE(om.n_faces(), 1003520);
    T_EQ_SIZE(om.n_faces(), sphere.triangle_count);
    T_EQ_SIZE(om.n_vertices(), sphere.vertex_count);

    halfedge_summary s = summarize(om);
    T_EQ_SIZE(s.boundary_halfedges, 0);
    T_EQ_SIZE(s.nonmanifold_vertices, 0);
    T_EQ_INT(s.euler, 2);

    /* one fan per vertex: the faces OpenMesh circulates around a vertex are all the triangles
       that name it (a pinched vertex would have two fans and lose faces from the circulator) */
    std::vector<uint32_t> incident(sphere.vertex_count, 0);
    for (size_t i = 0; i < 3 * sphere.triangle_count; i++) incident[sphere.indices[i]]++;
    size_t fan_mismatch = 0;
    for (auto v : om.vertices()) {
        size_t n = 0;
        for (auto f : om.vf_range(v)) { (void)f; n++; }
        if ((size_t)v.idx() >= incident.size() || n != incident[(size_t)v.idx()]) fan_mismatch++;
    }
    T_EQ_SIZE(fan_mismatch, 0);

    size_t position_mismatch = 0, triple_mismatch = 0;
    for (size_t v = 0; v < sphere.vertex_count && v < om.n_vertices(); v++) {
        const auto &p = om.point(om.vertex_handle((int)v));
        for (int k = 0; k < 3; k++)
            if (!same_bits(p[k], sphere.positions[3 * v + (size_t)k])) position_mismatch++;
    }
    for (size_t i = 0; i < sphere.triangle_count && i < om.n_faces(); i++) {
        int t[3];
        face_triple(om, om.face_handle((int)i), t);
        const uint32_t *e = sphere.indices + 3 * i;
        if (t[0] != (int)e[0] || t[1] != (int)e[1] || t[2] != (int)e[2]) triple_mismatch++;
    }
    T_EQ_SIZE(position_mismatch, 0);
    T_EQ_SIZE(triple_mismatch, 0);
    std::printf("sphere: OpenMesh %zu vertices, %zu faces, %zu edges, %zu boundary halfedges\n",
                om.n_vertices(), om.n_faces(), om.n_edges(), s.boundary_halfedges);
    gsph_free(&sphere);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    check_bunny();
    check_sphere();
    return T_END();
}

