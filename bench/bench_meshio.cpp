/* bench_meshio - loading a triangle mesh: meshio.h (mio_read_file) vs OpenMesh
   (OpenMesh::IO::read_mesh into a TriMesh_ArrayKernelT<>, default options).

   usage: bench_meshio [MESH] [-o COPY.ply]
     MESH   input mesh, any format both read (default build/sphere1m.off)
     -o     keep the binary little-endian PLY copy under this name (default: a temporary file
            $TMPDIR/bench_meshio_<pid>.ply, removed at the end)

   Two figures: the input file as given, and a binary PLY copy of it written by mio_write_ply.
   Per figure, each side: one warm-up read, then the median of 5 timed reads (bench/bench.h),
   single thread, same process. Timed: meshio - mio_read_file() alone; OpenMesh - constructing
   the empty TriMesh and OpenMesh::IO::read_mesh(). Not timed: mio_free_mesh() and deleting the
   TriMesh. Peak RSS is measured per side from a reset high-water mark. Details in README.md. */
#include "bench.h"

#include "openmesh.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
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

struct side_result {
    double seconds;
    double peak_mb; /* high-water mark above the RSS at the start of the side */
};

static side_result measure(int (*run)(void *), void (*after)(void *), void *user)
{
    side_result r;
    long before, peak;
    int reset = bench_reset_peak_rss();
    before = bench_current_rss_kb();
    r.seconds = bench_median(run, after, user);
    peak = bench_peak_rss_kb();
    r.peak_mb = (reset == 0 && before >= 0 && peak >= before) ? (double)(peak - before) / 1024.0 : -1.0;
    return r;
}

static double file_mb(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_size / (1024.0 * 1024.0) : -1.0;
}

/* one figure: both sides on one file; 0 on success */
static int compare(const char *format, const char *path)
{
    std::fprintf(stderr, "bench_meshio: %s: meshio, 1 warm-up + %d timed reads\n", path, BENCH_RUNS);
    meshio_side ours;
    std::memset(&ours, 0, sizeof ours);
    ours.path = path;
    side_result a = measure(meshio_run, meshio_after, &ours);
    if (a.seconds < 0) {
        std::fprintf(stderr, "bench_meshio: meshio cannot read %s: %s (%s)\n", path, ours.err.message,
                     mio_result_string(ours.err.code));
        return 1;
    }

    std::fprintf(stderr, "bench_meshio: %s: OpenMesh, 1 warm-up + %d timed reads\n", path, BENCH_RUNS);
    openmesh_side peer;
    peer.path = path;
    peer.mesh = NULL;
    peer.vertices = peer.triangles = 0;
    side_result b = measure(openmesh_run, openmesh_after, &peer);
    if (b.seconds < 0) {
        std::fprintf(stderr, "bench_meshio: OpenMesh cannot read %s\n", path);
        return 1;
    }

    if (ours.triangles != peer.triangles) {
        std::fprintf(stderr, "bench_meshio: error: %s: meshio read %zu triangles, OpenMesh %zu faces\n", path,
                     ours.triangles, peer.triangles);
        std::printf("RESULT bench_meshio format=%s error=triangle_count_mismatch meshio_triangles=%zu "
                    "openmesh_triangles=%zu\n", format, ours.triangles, peer.triangles);
        return 1;
    }
    std::printf("RESULT bench_meshio format=%s file_mb=%.1f triangles=%zu vertices=%zu openmesh_vertices=%zu "
                "meshio_ms=%.2f openmesh_ms=%.2f ratio=%.3f meshio_peak_rss_mb=%.1f openmesh_peak_rss_mb=%.1f\n",
                format, file_mb(path), ours.triangles, ours.vertices, peer.vertices, 1e3 * a.seconds,
                1e3 * b.seconds, a.seconds / b.seconds, a.peak_mb, b.peak_mb);
    std::fflush(stdout);
    return 0;
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
    std::fprintf(stderr, "bench_meshio: writing binary PLY copy of %s to %s\n", input, copy_path);
    mio_mesh mesh;
    mio_error err;
    mio_result r = mio_read_file(input, NULL, &mesh, &err);
    if (r != MIO_OK) {
        std::fprintf(stderr, "bench_meshio: cannot read %s: %s (%s)\n", input, err.message, mio_result_string(r));
        return 1;
    }
    r = mio_write_ply(copy_path, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count, 1, &err);
    mio_free_mesh(&mesh);
    if (r != MIO_OK) {
        std::fprintf(stderr, "bench_meshio: cannot write %s: %s (%s)\n", copy_path, err.message, mio_result_string(r));
        std::remove(copy_path);
        return 1;
    }

    int status = compare(extension(input), input);
    if (status == 0) status = compare("ply_binary", copy_path);
    if (copy_path == temp.c_str()) std::remove(copy_path);

    std::printf("RESULT bench_meshio process_peak_rss_mb=%.1f threads=1\n", (double)bench_peak_rss_kb() / 1024.0);
    return status;
}
