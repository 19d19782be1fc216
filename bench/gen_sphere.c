/* gen_sphere - writes the benchmark input: a bumpy geodesic icosphere as ASCII OFF.

   usage: gen_sphere [-f FREQ] [-o OUT.off]
     -f FREQ   icosahedron subdivision frequency, 1..20000 (default 224:
               501,762 vertices, 1,003,520 triangles)
     -o PATH   output file, a name ending in .off (default build/sphere1m.off); written to
               PATH.tmp and renamed when complete

   The shape is described in bench/sphere.h. Progress goes to stderr; the last stdout line is
       RESULT gen_sphere vertices=V triangles=T path=PATH
   Exit status 0 on success, 1 on failure (out of memory, write failure), 2 on bad arguments. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sphere.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#define GEN_SPHERE_VERSION "gen_sphere 0.2 (bench/sphere.h)"

static void usage(FILE *to)
{
    fprintf(to, "usage: gen_sphere [-f FREQ] [-o OUT.off]\n"
                "Writes a bumpy geodesic icosphere (bench/sphere.h) as ASCII OFF and prints a RESULT line.\n"
                "  -f FREQ            icosahedron subdivision frequency, 1..%d: 10 FREQ^2 + 2 vertices,\n"
                "                     20 FREQ^2 triangles (default 224: 501,762 vertices, 1,003,520 triangles)\n"
                "  -o, --output FILE  the OFF file to write; the name must end in .off (any case)\n"
                "                     (default build/sphere1m.off)\n"
                "  -h, --help         show this help and exit\n"
                "  --version          show the version and exit\n"
                "Exit status: 0 done, 1 failure (out of memory, failed write), 2 usage.\n"
                "The file is written to FILE.tmp and renamed when complete: a failed run leaves nothing.\n",
            GSPH_MAX_FREQ);
}

int main(int argc, char **argv)
{
    int freq = 224, i, failed, saved;
    long v;
    unsigned long nv, nt;
    const char *path = "build/sphere1m.off", *tmp;
    static char buffer[1 << 20];
    gsph_mesh mesh;
    cli_outputs out;
    FILE *file;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) { usage(stdout); return 0; }
        if (strcmp(a, "--version") == 0) { printf("%s\n", GEN_SPHERE_VERSION); return 0; }
        if (strcmp(a, "-f") == 0 || strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
            if (i + 1 >= argc) return cli_usage_error("gen_sphere", "%s needs a value", a);
            if (strcmp(a, "-f") == 0) {
                if (!cli_parse_long(argv[++i], 1, GSPH_MAX_FREQ, &v))
                    return cli_usage_error("gen_sphere", "-f '%s': not an integer in 1..%d", argv[i], GSPH_MAX_FREQ);
                freq = (int)v;
            } else path = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') return cli_usage_error("gen_sphere", "unknown option '%s'", a);
        else return cli_usage_error("gen_sphere", "unexpected argument '%s'", a);
    }
    if (!cli_has_extension(path, ".off"))
        return cli_usage_error("gen_sphere", "output '%s': only OFF is written; the name must end in .off", path);
    cli_outputs_init(&out);
    if (!(tmp = cli_output_add(&out, "gen_sphere", path))) return 2;

    fprintf(stderr, "gen_sphere: generating frequency %d icosphere\n", freq);
    if (gsph_generate(freq, &mesh) != 0) {
        fprintf(stderr, "gen_sphere: out of memory for frequency %d\n", freq);
        return 1;
    }

    fprintf(stderr, "gen_sphere: writing %lu vertices, %lu triangles to %s\n",
            (unsigned long)mesh.vertex_count, (unsigned long)mesh.triangle_count, path);
    file = fopen(tmp, "wb");
    if (!file) {
        cli_file_error("gen_sphere", path, "cannot create it", errno);
        gsph_free(&mesh);
        return 1;
    }
    setvbuf(file, buffer, _IOFBF, sizeof buffer);
    errno = 0;
    failed = gsph_write_off(file, &mesh) != 0;
    saved = errno;
    if (fclose(file) != 0 && !failed) { failed = 1; saved = errno; }
    nv = (unsigned long)mesh.vertex_count;
    nt = (unsigned long)mesh.triangle_count;
    gsph_free(&mesh);
    if (failed) {
        cli_file_error("gen_sphere", path, "writing failed", saved);
        cli_outputs_discard(&out);
        return 1;
    }
    if (!cli_outputs_commit(&out, "gen_sphere")) return 1;
    printf("RESULT gen_sphere vertices=%lu triangles=%lu path=%s\n", nv, nt, path);
    return 0;
}
