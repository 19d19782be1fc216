/* meshconv - read a mesh in any format meshio.h knows and write it as OBJ or PLY.

     meshconv INPUT [-o OUTPUT.obj|OUTPUT.ply] [--ascii]

   Prints one line "RESULT meshconv vertices=V triangles=T bbox=..." on stdout. Without -o it only
   reads and reports. PLY output is binary little-endian unless --ascii is given. On malformed input
   it prints meshio's message (with the line or byte offset) and exits with status 1. */
#define MIO_IMPLEMENTATION
#include "meshio.h"

#include <stdio.h>
#include <string.h>

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcmp(s + n - k, suffix) == 0;
}

int main(int argc, char **argv)
{
    const char *input = NULL, *output = NULL;
    int ascii = 0, i;
    mio_mesh mesh;
    mio_error err;
    mio_result r;
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    size_t v;

    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) output = argv[++i];
        else if (strcmp(argv[i], "--ascii") == 0) ascii = 1;
        else if (argv[i][0] != '-' && !input) input = argv[i];
        else {
            fprintf(stderr, "usage: meshconv INPUT [-o OUTPUT.obj|OUTPUT.ply] [--ascii]\n");
            return 2;
        }
    }
    if (!input) {
        fprintf(stderr, "usage: meshconv INPUT [-o OUTPUT.obj|OUTPUT.ply] [--ascii]\n");
        return 2;
    }
    r = mio_read_file(input, NULL, &mesh, &err);
    if (r != MIO_OK) {
        fprintf(stderr, "meshconv: %s: %s (%s)\n", input, err.message, mio_result_string(r));
        return 1;
    }
    for (v = 0; v < mesh.vertex_count; v++) {
        int k;
        for (k = 0; k < 3; k++) {
            float x = mesh.positions[3 * v + k];
            if (v == 0 || x < lo[k]) lo[k] = x;
            if (v == 0 || x > hi[k]) hi[k] = x;
        }
    }
    if (output) {
        if (ends_with(output, ".obj"))
            r = mio_write_obj(output, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count, &err);
        else if (ends_with(output, ".ply"))
            r = mio_write_ply(output, mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count,
                              !ascii, &err);
        else {
            fprintf(stderr, "meshconv: %s: the output must end in .obj or .ply\n", output);
            mio_free_mesh(&mesh);
            return 2;
        }
        if (r != MIO_OK) {
            fprintf(stderr, "meshconv: %s: %s (%s)\n", output, err.message, mio_result_string(r));
            mio_free_mesh(&mesh);
            return 1;
        }
    }
    printf("RESULT meshconv input=%s vertices=%lu triangles=%lu bbox=%g,%g,%g:%g,%g,%g%s%s\n", input,
           (unsigned long)mesh.vertex_count, (unsigned long)mesh.triangle_count, lo[0], lo[1], lo[2], hi[0],
           hi[1], hi[2], output ? " output=" : "", output ? output : "");
    mio_free_mesh(&mesh);
    return 0;
}
