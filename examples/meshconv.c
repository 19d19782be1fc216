/* meshconv - read a mesh in any format meshio.h knows and write it as OBJ, OFF, PLY or STL.

     meshconv INPUT [-o OUTPUT.obj|.off|.ply|.stl] [--ascii] [--weld] [--format F]

   Prints one line "RESULT meshconv input=... vertices=V triangles=T bbox=..." on stdout. Without -o
   it only reads and reports. The output format follows the output's extension, in any case (.OBJ,
   .Stl). PLY and STL are binary little-endian unless --ascii is given. --weld joins vertices with
   exactly equal positions (mio_weld), which an STL input needs for connectivity. The output is
   written to OUTPUT.tmp and renamed to OUTPUT when complete, so a failed run leaves no file.
   Exit status: 0 done, 1 failure (unreadable input, failed write), 2 usage (bad arguments). */
#define MIO_IMPLEMENTATION
#include "meshio.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MESHCONV_VERSION "meshconv 0.2 (meshio.h v0.1)"

typedef struct args {
    const char *input, *output;
    int ascii, weld;
    mio_format in_format, out_format;
} args;

static void usage(FILE *to)
{
    fprintf(to,
            "usage: meshconv INPUT [-o OUTPUT] [--ascii] [--weld] [--format F]\n"
            "Reads a mesh (OBJ, OFF, PLY, STL), prints a RESULT line with its counts and bounding box,\n"
            "and with -o writes it again.\n"
            "  -o, --output FILE  write the mesh to FILE; the format follows the extension in any case:\n"
            "                     .obj .off .ply .stl (default: no output, only the RESULT line)\n"
            "  --ascii            write PLY and STL as ascii text (default: binary little-endian)\n"
            "  --weld             join vertices with exactly equal positions before writing, in order of\n"
            "                     first use; an STL input needs it to be connected (default: off)\n"
            "  --format F         read INPUT as F = obj, off, ply or stl (default: auto, from the\n"
            "                     content, then the extension)\n"
            "  -h, --help         show this help and exit\n"
            "  --version          show the version and exit\n"
            "Exit status: 0 done, 1 failure (unreadable input, failed write), 2 usage.\n"
            "The output is written to FILE.tmp and renamed when complete: a failed run leaves nothing.\n");
}

/* The format named by the file's extension, any case; MIO_FORMAT_AUTO if none of the four. */
static mio_format format_of_extension(const char *path)
{
    static const char *const ext[4] = {".obj", ".off", ".ply", ".stl"};
    static const mio_format fmt[4] = {MIO_FORMAT_OBJ, MIO_FORMAT_OFF, MIO_FORMAT_PLY, MIO_FORMAT_STL};
    int k;
    for (k = 0; k < 4; k++)
        if (cli_has_extension(path, ext[k])) return fmt[k];
    return MIO_FORMAT_AUTO;
}

static mio_format format_of_name(const char *s)
{
    if (strcmp(s, "obj") == 0) return MIO_FORMAT_OBJ;
    if (strcmp(s, "off") == 0) return MIO_FORMAT_OFF;
    if (strcmp(s, "ply") == 0) return MIO_FORMAT_PLY;
    if (strcmp(s, "stl") == 0) return MIO_FORMAT_STL;
    return MIO_FORMAT_AUTO;
}

/* Returns -1 to go on, or the exit status (0 for --help/--version, 2 for a usage error). */
static int parse_args(int argc, char **argv, args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    for (i = 1; i < argc; i++) {
        const char *s = argv[i];
        if (strcmp(s, "-h") == 0 || strcmp(s, "--help") == 0) { usage(stdout); return 0; }
        if (strcmp(s, "--version") == 0) { printf("%s\n", MESHCONV_VERSION); return 0; }
        if (strcmp(s, "-o") == 0 || strcmp(s, "--output") == 0) {
            if (i + 1 >= argc || argv[i + 1][0] == '\0') return cli_usage_error("meshconv", "%s needs a file name", s);
            a->output = argv[++i];
        } else if (strcmp(s, "--format") == 0) {
            if (i + 1 >= argc) return cli_usage_error("meshconv", "%s needs obj, off, ply or stl", s);
            a->in_format = format_of_name(argv[++i]);
            if (a->in_format == MIO_FORMAT_AUTO) return cli_usage_error("meshconv", "--format '%s': not obj, off, ply or stl", argv[i]);
        } else if (strcmp(s, "--ascii") == 0) a->ascii = 1;
        else if (strcmp(s, "--weld") == 0) a->weld = 1;
        else if (s[0] == '-' && s[1] != '\0') return cli_usage_error("meshconv", "unknown option '%s'", s);
        else if (a->input) return cli_usage_error("meshconv", "unexpected argument '%s': one INPUT only", s);
        else a->input = s;
    }
    if (!a->input) return cli_usage_error("meshconv", "%s", "no INPUT given");
    if (a->output) {
        a->out_format = format_of_extension(a->output);
        if (a->out_format == MIO_FORMAT_AUTO)
            return cli_usage_error("meshconv", "output '%s': the name must end in .obj, .off, .ply or .stl (any case)", a->output);
    }
    return -1;
}

static void report_error(const char *path, mio_result r, const mio_error *err, int saved_errno)
{
    cli_read_error("meshconv", path, err->message, mio_result_string(r), mio_result_description(r), r == MIO_ERR_IO ? saved_errno : 0);
}

static mio_result write_mesh(const args *a, const char *path, const mio_mesh *m, mio_error *err)
{
    switch (a->out_format) {
    case MIO_FORMAT_OBJ: return mio_write_obj(path, m->positions, m->vertex_count, m->indices, m->triangle_count, err);
    case MIO_FORMAT_OFF: return mio_write_off(path, m->positions, m->vertex_count, m->indices, m->triangle_count, err);
    case MIO_FORMAT_PLY:
        return mio_write_ply(path, m->positions, m->vertex_count, m->indices, m->triangle_count, !a->ascii, err);
    default: return mio_write_stl(path, m->positions, m->vertex_count, m->indices, m->triangle_count, !a->ascii, err);
    }
}

/* Writes OUTPUT.tmp, then renames it to OUTPUT; on any failure removes OUTPUT.tmp. Returns 0 or 1. */
static int write_output(const args *a, const mio_mesh *m)
{
    cli_outputs outs;
    const char *tmp;
    mio_error err;
    mio_result r;
    cli_outputs_init(&outs);
    if (!(tmp = cli_output_add(&outs, "meshconv", a->output))) return 1;
    errno = 0;
    r = write_mesh(a, tmp, m, &err);
    if (r != MIO_OK) {
        report_error(a->output, r, &err, errno);
        cli_outputs_discard(&outs);
        return 1;
    }
    return cli_outputs_commit(&outs, "meshconv") ? 0 : 1;
}

static void bounding_box(const mio_mesh *m, float lo[3], float hi[3])
{
    size_t v;
    int k;
    for (k = 0; k < 3; k++) lo[k] = hi[k] = 0.0f;
    for (v = 0; v < m->vertex_count; v++)
        for (k = 0; k < 3; k++) {
            float x = m->positions[3 * v + (size_t)k];
            if (v == 0 || x < lo[k]) lo[k] = x;
            if (v == 0 || x > hi[k]) hi[k] = x;
        }
}

int main(int argc, char **argv)
{
    args a;
    mio_read_options opt;
    mio_mesh mesh;
    mio_error err;
    mio_result r;
    float lo[3], hi[3];
    int status = parse_args(argc, argv, &a), saved;
    if (status >= 0) return status;
    memset(&opt, 0, sizeof opt);
    opt.format = a.in_format;
    errno = 0;
    r = mio_read_file(a.input, &opt, &mesh, &err);
    saved = errno;
    if (r != MIO_OK) { report_error(a.input, r, &err, saved); return 1; }
    if (a.weld && (r = mio_weld(&mesh, &err)) != MIO_OK) {
        report_error(a.input, r, &err, 0);
        mio_free_mesh(&mesh);
        return 1;
    }
    if (a.output && write_output(&a, &mesh) != 0) { mio_free_mesh(&mesh); return 1; }
    bounding_box(&mesh, lo, hi);
    printf("RESULT meshconv input=%s vertices=%lu triangles=%lu bbox=%g,%g,%g:%g,%g,%g%s%s\n", a.input,
           (unsigned long)mesh.vertex_count, (unsigned long)mesh.triangle_count, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
           a.output ? " output=" : "", a.output ? a.output : "");
    mio_free_mesh(&mesh);
    return 0;
}
