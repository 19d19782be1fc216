/* gen_sphere - writes the benchmark input: a bumpy geodesic icosphere as ASCII OFF.

   usage: gen_sphere [-f FREQ] [-o out.off]
     -f FREQ   icosahedron subdivision frequency, 1..20000 (default 224:
               501,762 vertices, 1,003,520 triangles)
     -o PATH   output file (default build/sphere1m.off)

   The shape is described in bench/sphere.h. Progress goes to stderr; the last stdout line is
       RESULT gen_sphere vertices=V triangles=T path=PATH
   Exit status 0 on success, 1 on bad arguments or write failure, 2 when out of memory. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sphere.h"

static void usage(FILE *to)
{
    fprintf(to, "usage: gen_sphere [-f FREQ] [-o out.off]\n"
                "  -f FREQ  subdivision frequency 1..%d (default 224 -> 1,003,520 triangles)\n"
                "  -o PATH  output OFF file (default build/sphere1m.off)\n",
            GSPH_MAX_FREQ);
}

/* strict decimal parse: the whole string must be a number in [lo, hi] */
static int parse_int(const char *s, long lo, long hi, int *out)
{
    char *end = NULL;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) return 0;
    *out = (int)v;
    return 1;
}

int main(int argc, char **argv)
{
    int freq = 224, i, failed;
    const char *path = "build/sphere1m.off";
    static char buffer[1 << 20];
    gsph_mesh mesh;
    FILE *file;

    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(argv[i], "-f") == 0 && i + 1 < argc) {
            if (!parse_int(argv[++i], 1, GSPH_MAX_FREQ, &freq)) {
                fprintf(stderr, "gen_sphere: -f wants an integer in 1..%d, got \"%s\"\n",
                        GSPH_MAX_FREQ, argv[i]);
                return 1;
            }
        } else if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) {
            path = argv[++i];
        } else {
            fprintf(stderr, "gen_sphere: unexpected argument \"%s\"\n", argv[i]);
            usage(stderr);
            return 1;
        }
    }

    fprintf(stderr, "gen_sphere: generating frequency %d icosphere\n", freq);
    if (gsph_generate(freq, &mesh) != 0) {
        fprintf(stderr, "gen_sphere: out of memory for frequency %d\n", freq);
        return 2;
    }

    fprintf(stderr, "gen_sphere: writing %lu vertices, %lu triangles to %s\n",
            (unsigned long)mesh.vertex_count, (unsigned long)mesh.triangle_count, path);
    file = fopen(path, "wb");
    if (!file) {
        fprintf(stderr, "gen_sphere: cannot open %s for writing: %s\n", path, strerror(errno));
        gsph_free(&mesh);
        return 1;
    }
    setvbuf(file, buffer, _IOFBF, sizeof buffer);
    failed = gsph_write_off(file, &mesh) != 0;
    if (fclose(file) != 0) failed = 1;
    if (failed) {
        fprintf(stderr, "gen_sphere: writing %s failed: %s\n", path, strerror(errno));
        remove(path);
        gsph_free(&mesh);
        return 1;
    }

    printf("RESULT gen_sphere vertices=%lu triangles=%lu path=%s\n",
           (unsigned long)mesh.vertex_count, (unsigned long)mesh.triangle_count, path);
    gsph_free(&mesh);
    return 0;
}
