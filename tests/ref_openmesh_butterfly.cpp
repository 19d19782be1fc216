/* ref_openmesh_butterfly - subdiv4.h's butterfly against OpenMesh's ModifiedButterflyT (Debian
   libopenmesh-dev), two levels at OpenMesh's tension (w = 1/16), on closed meshes with regular
   and extraordinary vertices: tetrahedron (valence 3), octahedron (4), icosahedron (5), a
   geodesic sphere (5 and 6), a torus (all 6), a capped cylinder (12 at the cap centres, 4 on the
   rims) and the Stanford bunny (valences 3..15) when glmark2-data is installed; then an open
   patch, whose vertices near the boundary are reported separately (see butterfly_compare.hpp).
   Each mesh: the same vertex and triangle counts, no unmatched vertex, maxdiff <= 1e-5 of the
   bounding-box diagonal. Also: two levels in one call equal two calls of one level bit for bit. */
#include "openmesh.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "test.h"
#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#include "../bench/sphere.h"
#include "butterfly_compare.hpp"

struct simple_mesh {
    std::vector<float> p;
    std::vector<uint32_t> t;
    size_t nv() const { return p.size() / 3; }
    size_t nt() const { return t.size() / 3; }
    void v(double x, double y, double z) { p.push_back((float)x); p.push_back((float)y); p.push_back((float)z); }
    void f(uint32_t a, uint32_t b, uint32_t c) { t.push_back(a); t.push_back(b); t.push_back(c); }
};

static simple_mesh tetrahedron()
{
    simple_mesh m;
    m.v(1, 1, 1); m.v(1, -1, -1); m.v(-1, 1, -1); m.v(-1, -1, 1.3);
    m.f(0, 1, 2); m.f(0, 3, 1); m.f(0, 2, 3); m.f(1, 3, 2);
    return m;
}

static simple_mesh octahedron()
{
    simple_mesh m;
    m.v(1, 0, 0); m.v(-1, 0, 0); m.v(0, 1, 0); m.v(0, -1, 0); m.v(0, 0, 1.2); m.v(0, 0, -1);
    m.f(0, 2, 4); m.f(2, 1, 4); m.f(1, 3, 4); m.f(3, 0, 4);
    m.f(2, 0, 5); m.f(1, 2, 5); m.f(3, 1, 5); m.f(0, 3, 5);
    return m;
}

static simple_mesh from_sphere(int freq)
{
    simple_mesh m;
    gsph_mesh g;
    if (gsph_generate(freq, &g) != 0) return m;
    m.p.assign(g.positions, g.positions + 3 * g.vertex_count);
    m.t.assign(g.indices, g.indices + 3 * g.triangle_count);
    gsph_free(&g);
    return m;
}

static simple_mesh torus(int cols, int rows)
{
    simple_mesh m;
    for (int j = 0; j < rows; j++)
        for (int i = 0; i < cols; i++) {
            double u = 6.283185307179586 * i / cols, v = 6.283185307179586 * j / rows;
            m.v((2.0 + std::cos(v)) * std::cos(u), (2.0 + std::cos(v)) * std::sin(u), std::sin(v) + 0.1 * std::sin(3 * u));
        }
    for (int j = 0; j < rows; j++)
        for (int i = 0; i < cols; i++) {
            uint32_t a = j * cols + i, b = j * cols + (i + 1) % cols, c = ((j + 1) % rows) * cols + i,
                     d = ((j + 1) % rows) * cols + (i + 1) % cols;
            m.f(a, b, d);
            m.f(a, d, c);
        }
    return m;
}

/* cylinder of `seg` columns and `rings` rings, closed by a fan at each end */
static simple_mesh capped_cylinder(int seg, int rings)
{
    simple_mesh m;
    for (int j = 0; j < rings; j++)
        for (int i = 0; i < seg; i++) {
            double u = 6.283185307179586 * i / seg;
            m.v(std::cos(u), std::sin(u), (double)j / (rings - 1) * 2.0 - 1.0);
        }
    uint32_t bottom = (uint32_t)m.nv(), top = bottom + 1;
    m.v(0, 0, -1.3);
    m.v(0, 0, 1.3);
    for (int j = 0; j + 1 < rings; j++)
        for (int i = 0; i < seg; i++) {
            uint32_t a = j * seg + i, b = j * seg + (i + 1) % seg, c = (j + 1) * seg + i, d = (j + 1) * seg + (i + 1) % seg;
            m.f(a, b, d);
            m.f(a, d, c);
        }
    for (int i = 0; i < seg; i++) {
        m.f(bottom, (uint32_t)((i + 1) % seg), (uint32_t)i);
        m.f(top, (uint32_t)((rings - 1) * seg + i), (uint32_t)((rings - 1) * seg + (i + 1) % seg));
    }
    return m;
}

/* an open, bumpy, irregularly triangulated square patch */
static simple_mesh open_patch(int n)
{
    simple_mesh m;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) m.v(i, j, 0.3 * std::sin(0.9 * i) * std::cos(0.7 * j));
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
            if ((i + 2 * j) % 3) { m.f(a, b, d); m.f(a, d, c); }
            else { m.f(a, b, c); m.f(b, d, c); }
        }
    return m;
}

static void check(const char *name, const simple_mesh &m, bool closed)
{
    bf_result r = bf_compare(m.p.data(), m.nv(), m.t.data(), m.nt(), 2);
    T_CHECK_MSG(r.ok, "%s: a side failed", name);
    T_EQ_SIZE(r.ours_vertices, r.om_vertices);
    T_EQ_SIZE(r.ours_triangles, r.om_faces);
    T_EQ_SIZE(r.unmatched, 0);
    T_CHECK_MSG(r.maxdiff <= 1e-5, "%s: maxdiff %g", name, r.maxdiff);
    if (closed) T_EQ_SIZE(r.boundary_vertices, 0);
    std::printf("note: %-16s %7zu -> %8zu triangles, maxdiff %.3g over %zu vertices; near a boundary: %zu vertices, "
                "maxdiff %.3g\n", name, m.nt(), r.ours_triangles, r.maxdiff, r.vertices, r.boundary_vertices,
                r.maxdiff_boundary);
    /* two levels at once = one level twice */
    sd4_mesh a, b, c;
    bool same = false;
    if (sd4_butterfly(m.p.data(), m.nv(), m.t.data(), m.nt(), 2, 1.0 / 16.0, NULL, &a) == SD4_OK) {
        if (sd4_butterfly(m.p.data(), m.nv(), m.t.data(), m.nt(), 1, 1.0 / 16.0, NULL, &b) == SD4_OK) {
            if (sd4_butterfly(b.positions, b.vertex_count, b.indices, b.triangle_count, 1, 1.0 / 16.0, NULL, &c) == SD4_OK) {
                same = a.vertex_count == c.vertex_count && a.triangle_count == c.triangle_count &&
                       std::memcmp(a.positions, c.positions, 12 * a.vertex_count) == 0 &&
                       std::memcmp(a.indices, c.indices, 12 * a.triangle_count) == 0;
                sd4_free_mesh(&c);
            }
            sd4_free_mesh(&b);
        }
        sd4_free_mesh(&a);
    }
    T_CHECK_MSG(same, "%s: levels=2 differs from two levels of 1", name);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    check("tetrahedron", tetrahedron(), true);
    check("octahedron", octahedron(), true);
    check("icosahedron", from_sphere(1), true);
    check("sphere_f6", from_sphere(6), true);
    check("torus", torus(16, 10), true);
    check("capped_cylinder", capped_cylinder(12, 5), true);
    const char *bunny = "/usr/share/glmark2/models/bunny.obj";
    mio_mesh bm;
    mio_error err;
    if (std::getenv("TEST_SANITIZE")) {
        T_SKIP_N(7, "bunny butterfly vs OpenMesh", "TEST_SANITIZE: the 70k-triangle bunny is skipped under sanitizers");
    } else if (mio_read_file(bunny, NULL, &bm, &err) == MIO_OK) {
        simple_mesh m;
        m.p.assign(bm.positions, bm.positions + 3 * bm.vertex_count);
        m.t.assign(bm.indices, bm.indices + 3 * bm.triangle_count);
        mio_free_mesh(&bm);
        check("bunny", m, true);
    } else {
        T_SKIP_N(7, "bunny butterfly vs OpenMesh", "/usr/share/glmark2/models/bunny.obj missing: apt-get install glmark2-data");
    }
    check("open_patch", open_patch(9), false);
    return T_END();
}
