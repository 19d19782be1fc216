/* bench_meshio - loading a triangle mesh: meshio.h (mio_read_file) vs loaders that also return
   flat arrays (tinyobjloader for OBJ, assimp's importer without post-processing for every format)
   and vs loading into OpenMesh (OpenMesh::IO::read_mesh into a TriMesh_ArrayKernelT<>, default
   options, which also builds the halfedge connectivity).

   usage: bench_meshio [MESH] [-o COPY.ply]
     MESH   input mesh, any format meshio, assimp and OpenMesh read (default build/sphere1m.off)
     -o     keep the binary little-endian PLY copy under this name (default: a temporary file
            $TMPDIR/bench_meshio_<pid>.ply, removed at the end)

   Three figures: the input file as given, a binary PLY copy of it written by mio_write_ply and a
   binary STL copy written by this bench. Per figure the sides are interleaved (bench/bench.h:
   one warm-up read each, then 11 rounds of meshio, tinyobjloader (OBJ only), assimp, OpenMesh),
   single thread, same process. Timed: meshio - mio_read_file(); tinyobjloader - tinyobj::LoadObj
   (triangulate on, as its default); assimp - constructing an Assimp::Importer and ReadFile(path,
   0); OpenMesh - constructing the empty TriMesh and OpenMesh::IO::read_mesh(). Not timed: freeing.
   Peak RSS per side: its warm-up run's, from a reset high-water mark. Details in README.md.

   Output, per format: one line for meshio, then one per peer:
     RESULT bench_meshio format=<f> side=meshio file_mb=.. triangles=.. vertices=.. meshio_ms=.. ..
     RESULT bench_meshio format=<f> peer=<tinyobjloader_flat|assimp_flat|openmesh_halfedge>
         vertices=.. peer_ms=.. .. ratio=<meshio / peer, per round> .. peak_rss_mb=..
   Exit status 1 when a side fails or reads another number of triangles than meshio. */
#include "bench.h"

#include "openmesh.hpp"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <tiny_obj_loader.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#include <sys/stat.h>
#include <unistd.h>

#define MIO_IMPLEMENTATION
#include "meshio.h"


struct meshio_side {
    const char *path;
    mio_mesh mesh;
    mio_error err;
    size_t vertices, triangles;
};

static int meshio_run(void *user)
{
    meshio_side *s = (meshio_side *)user;
    return mio_read_file(s->path, NULL, &s->mesh, &s->err) == MIO_OK ? 0 : 1;
}

static void meshio_after(void *user)
{
    meshio_side *s = (meshio_side *)user;
    s->vertices = s->mesh.vertex_count;
    s->triangles = s->mesh.triangle_count;
    mio_free_mesh(&s->mesh);
}

struct openmesh_side {
    const char *path;
    TriMesh *mesh;
    size_t vertices, triangles;
};

static int openmesh_run(void *user)
{
    openmesh_side *s = (openmesh_side *)user;
    s->mesh = new TriMesh;
    return OpenMesh::IO::read_mesh(*s->mesh, s->path) ? 0 : 1;
}

static void openmesh_after(void *user)
{
    openmesh_side *s = (openmesh_side *)user;
    s->vertices = s->mesh ? s->mesh->n_vertices() : 0;
    s->triangles = s->mesh ? s->mesh->n_faces() : 0;
    delete s->mesh;
    s->mesh = NULL;
}

struct tinyobj_side {
    const char *path;
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    size_t vertices, triangles;
};

static int tinyobj_run(void *user)
{
    tinyobj_side *s = (tinyobj_side *)user;
    return tinyobj::LoadObj(&s->attrib, &s->shapes, &s->materials, &s->warn, &s->err, s->path, NULL, true) ? 0 : 1;
}

static void tinyobj_after(void *user)
{
    tinyobj_side *s = (tinyobj_side *)user;
    s->vertices = s->attrib.vertices.size() / 3;
    s->triangles = 0;
    for (const tinyobj::shape_t &shape : s->shapes) s->triangles += shape.mesh.num_face_vertices.size();
    s->attrib = tinyobj::attrib_t();
    std::vector<tinyobj::shape_t>().swap(s->shapes);
    std::vector<tinyobj::material_t>().swap(s->materials);
}

struct assimp_side {
    const char *path;
    Assimp::Importer *importer;
    size_t vertices, triangles;
};

static int assimp_run(void *user)
{
    assimp_side *s = (assimp_side *)user;
    s->importer = new Assimp::Importer;
    return s->importer->ReadFile(s->path, 0) ? 0 : 1;
}

static void assimp_after(void *user)
{
    assimp_side *s = (assimp_side *)user;
    const aiScene *scene = s->importer ? s->importer->GetScene() : NULL;
    s->vertices = s->triangles = 0;
    for (unsigned m = 0; scene && m < scene->mNumMeshes; m++) {
        const aiMesh *mesh = scene->mMeshes[m];
        s->vertices += mesh->mNumVertices;
        for (unsigned f = 0; f < mesh->mNumFaces; f++)
            if (mesh->mFaces[f].mNumIndices >= 3) s->triangles += mesh->mFaces[f].mNumIndices - 2;
    }
    delete s->importer;
    s->importer = NULL;
}

static double file_mb(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_size / (1024.0 * 1024.0) : -1.0;
}

/* " peak_rss_mb=<m>" of a side's warm-up run, -1 if unknown */
static double peak_mb(const bench_side &side) { return side.peak_kb >= 0 ? (double)side.peak_kb / 1024.0 : -1.0; }

/* one peer's line: its time, meshio's over it per round, its counts */
static void print_peer(const char *format, const char *peer, const bench_side &meshio, const bench_side &side,
                       size_t vertices)
{
    std::printf("RESULT bench_meshio format=%s peer=%s vertices=%zu", format, peer, vertices);
    bench_print_ms("peer", &side);
    bench_print_ratio(&meshio, &side);
    std::printf(" peak_rss_mb=%.1f\n", peak_mb(side));
}

/* one figure: every side on one file; 0 on success */
static int compare(const char *format, const char *path)
{
    bool obj = std::strcmp(format, "obj") == 0;
    meshio_side ours;
    std::memset(&ours, 0, sizeof ours);
    ours.path = path;
    tinyobj_side tiny;
    tiny.path = path;
    tiny.vertices = tiny.triangles = 0;
    assimp_side assimp = {path, NULL, 0, 0};
    openmesh_side peer = {path, NULL, 0, 0};
    bench_side sides[4] = {bench_make_side("meshio", meshio_run, meshio_after, &ours),
                           bench_make_side("assimp", assimp_run, assimp_after, &assimp),
                           bench_make_side("openmesh", openmesh_run, openmesh_after, &peer),
                           bench_make_side("tinyobjloader", tinyobj_run, tinyobj_after, &tiny)};
    std::fprintf(stderr, "bench_meshio: %s: meshio, assimp, OpenMesh%s interleaved\n", path, obj ? ", tinyobjloader" : "");
    if (bench_interleave(sides, obj ? 4 : 3, 0) != 0) {
        std::fprintf(stderr, "bench_meshio: a side cannot read %s (meshio: %s)\n", path, ours.err.message);
        std::printf("RESULT bench_meshio format=%s error=read_failed\n", format);
        return 1;
    }
    if (ours.triangles != peer.triangles || ours.triangles != assimp.triangles || (obj && ours.triangles != tiny.triangles)) {
        std::fprintf(stderr, "bench_meshio: error: %s: meshio read %zu triangles, OpenMesh %zu, assimp %zu, tinyobjloader %zu\n",
                     path, ours.triangles, peer.triangles, assimp.triangles, tiny.triangles);
        std::printf("RESULT bench_meshio format=%s error=triangle_count_mismatch meshio_triangles=%zu "
                    "openmesh_triangles=%zu assimp_triangles=%zu\n", format, ours.triangles, peer.triangles, assimp.triangles);
        return 1;
    }
    std::printf("RESULT bench_meshio format=%s side=meshio file_mb=%.1f triangles=%zu vertices=%zu", format, file_mb(path),
                ours.triangles, ours.vertices);
    bench_print_ms("meshio", &sides[0]);
    std::printf(" peak_rss_mb=%.1f\n", peak_mb(sides[0]));
    if (obj) print_peer(format, "tinyobjloader_flat", sides[0], sides[3], tiny.vertices);
    print_peer(format, "assimp_flat", sides[0], sides[1], assimp.vertices);
    print_peer(format, "openmesh_halfedge", sides[0], sides[2], peer.vertices);
    std::fflush(stdout);
    return 0;
}

/* a binary STL copy (80-byte header, count, per triangle a zero normal, 3 corners, 0 attribute) */
static bool write_stl(const char *path, const mio_mesh &m)
{
    FILE *f = std::fopen(path, "wb");
    if (!f) return false;
    char header[80] = "bench_meshio binary STL copy";
    uint32_t count = (uint32_t)m.triangle_count;
    bool ok = std::fwrite(header, 1, 80, f) == 80 && std::fwrite(&count, 4, 1, f) == 1;
    for (size_t t = 0; ok && t < m.triangle_count; t++) {
        float rec[12] = {0, 0, 0};
        for (int c = 0; c < 3; c++) std::memcpy(rec + 3 + 3 * c, m.positions + 3 * (size_t)m.indices[3 * t + c], 3 * sizeof(float));
        uint16_t attr = 0;
        ok = std::fwrite(rec, sizeof rec, 1, f) == 1 && std::fwrite(&attr, 2, 1, f) == 1;
    }
    return std::fclose(f) == 0 && ok;
}

static const char *extension(const char *path)
{
    const char *dot = std::strrchr(path, '.'), *slash = std::strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "unknown";
}

int main(int argc, char **argv)
{
    const char *input = "build/sphere1m.off", *copy_path = NULL;
    bool have_input = false;
    for (int i = 1; i < argc; i++) {
        if (std::strcmp(argv[i], "-o") == 0 && i + 1 < argc) {
            copy_path = argv[++i];
        } else if (argv[i][0] != '-' && !have_input) {
            input = argv[i];
            have_input = true;
        } else {
            std::fprintf(stderr, "usage: bench_meshio [MESH] [-o COPY.ply]\n");
            return 2;
        }
    }
    std::string temp;
    if (!copy_path) {
        const char *dir = std::getenv("TMPDIR");
        temp = std::string(dir && *dir ? dir : "/tmp") + "/bench_meshio_" + std::to_string((long)getpid()) + ".ply";
        copy_path = temp.c_str();
    }

    BENCH_PRINT_FLAGS("bench_meshio");
    std::fflush(stdout);

    /* the binary PLY copy, written by meshio from meshio's own reading (not timed) */
    std::fprintf(stderr, "bench_meshio: writing binary PLY and STL copies of %s to %s(.stl)\n", input, copy_path);
    mio_mesh mesh;
    mio_error err;
    mio_result r = mio_read_file(input, NULL, &mesh, &err);
    if (r != MIO_OK) {
        std::fprintf(stderr, "bench_meshio: cannot read %s: %s (%s)\n", input, err.message, mio_result_string(r));
        return 1;
    }
    r = mio_write_ply(copy_path, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count, 1, &err);
    std::string stl_path = std::string(copy_path) + ".stl";
    bool stl_ok = write_stl(stl_path.c_str(), mesh);
    mio_free_mesh(&mesh);
    if (r != MIO_OK || !stl_ok) {
        std::fprintf(stderr, "bench_meshio: cannot write %s or %s: %s\n", copy_path, stl_path.c_str(),
                     r != MIO_OK ? err.message : "write error");
        std::remove(copy_path);
        std::remove(stl_path.c_str());
        return 1;
    }

    int status = compare(extension(input), input);
    if (status == 0) status = compare("ply_binary", copy_path);
    if (status == 0) status = compare("stl_binary", stl_path.c_str());
    if (copy_path == temp.c_str()) std::remove(copy_path);
    std::remove(stl_path.c_str());

    std::printf("RESULT bench_meshio process_peak_rss_mb=%.1f threads=1\n", (double)bench_peak_rss_kb() / 1024.0);
    return status;
}
