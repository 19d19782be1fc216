/* cli.h - the example programs' shared command-line helpers (examples only, not a library).

   #define CLI_IMPLEMENTATION in one .c file before including it (CLI_STATIC makes the functions
   static). What every program in examples/ does the same way:
     - strict option values: cli_parse_long, cli_parse_double, cli_parse_doubles (a list like
       0.6,0.7,0.5), cli_parse_size (W or WxH): the whole string must be the value, in range,
       finite (no nan, inf, 1e999, "10x", " 10", 4294967297);
     - usage errors: cli_usage_error prints "PROG: MESSAGE (see PROG --help)" and returns 2,
       the usage exit status (0 done, 1 failure, 2 usage);
     - output names: cli_has_extension (any case: .png, .PNG);
     - outputs written whole or not at all: cli_output_add gives the name NAME.tmp to write to,
       cli_outputs_commit renames every NAME.tmp to NAME once all are written, and
       cli_outputs_discard removes every NAME.tmp after a failure, so a failed run leaves no file
       behind and an existing NAME unchanged;
     - causes: cli_file_error prints "PROG: NAME: WHAT: the system's reason" for a file;
       cli_result_error prints a library result's name (its *_result_string) with what it means
       (cli_result_meaning: a table of the result names of every header used by the examples,
       keyed by the name, so that this header needs none of them).
   No allocation: an output's name may have at most CLI_PATH_MAX - 5 bytes. */
#ifndef CLI_H
#define CLI_H

#include <stddef.h>

#ifdef CLI_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define CLIDEF static __attribute__((unused)) /* no warning for the functions a program does not call */
#else
#define CLIDEF static
#endif
#else
#define CLIDEF extern
#endif

#define CLI_PATH_MAX 1024
#define CLI_MAX_OUTPUTS 8

/* The outputs of one run: zero it (or cli_outputs_init), add each before writing it. */
typedef struct cli_outputs {
    int count;
    char tmp[CLI_MAX_OUTPUTS][CLI_PATH_MAX];
} cli_outputs;

#ifdef __cplusplus
extern "C" {
#endif

/* 1 when s is a whole decimal integer in [lo, hi] (stored in *out), else 0. */
CLIDEF int cli_parse_long(const char *s, long lo, long hi, long *out);
/* 1 when s is a whole finite number in [lo, hi] (stored in *out), else 0. */
CLIDEF int cli_parse_double(const char *s, double lo, double hi, double *out);
/* 1 when s is between min_n and max_n numbers in [lo, hi] separated by sep (no spaces); their
   count in *n (may be NULL when min_n = max_n). */
CLIDEF int cli_parse_doubles(const char *s, char sep, int min_n, int max_n, double lo, double hi, double *out, int *n);
/* 1 when s is W or WxH with lo <= W, H <= hi; W alone gives H = W when square_ok, else fails. */
CLIDEF int cli_parse_size(const char *s, long lo, long hi, int square_ok, int *w, int *h);
/* Prints "prog: " fmt... " (see prog --help)" on stderr and returns 2. */
CLIDEF int cli_usage_error(const char *prog, const char *fmt, ...);
/* 1 when path ends in ext (with its dot, e.g. ".png") in any case, with something before it. */
CLIDEF int cli_has_extension(const char *path, const char *ext);
/* Prints "prog: path: what: strerror(errnum)" (without the reason when errnum is 0). */
CLIDEF void cli_file_error(const char *prog, const char *path, const char *what, int errnum);
/* What a library result name (e.g. "SR_ERR_IO", from sr_result_string) means, in a few words; ""
   for a name the table does not know. */
CLIDEF const char *cli_result_meaning(const char *name);
/* Prints "prog: context: NAME (meaning)" and, when errnum is not 0, ": strerror(errnum)". */
CLIDEF void cli_result_error(const char *prog, const char *context, const char *name, int errnum);
/* A reader's failure: "prog: path: message[: strerror(errnum)] (name: description)", e.g. with
   meshio's mio_error message, mio_result_string and mio_result_description. */
CLIDEF void cli_read_error(const char *prog, const char *path, const char *message, const char *name,
                           const char *description, int errnum);

CLIDEF void cli_outputs_init(cli_outputs *o);
/* The temporary name (path + ".tmp") to write path's content to; NULL when path is too long or
   more than CLI_MAX_OUTPUTS outputs were added (the reason is printed). */
CLIDEF const char *cli_output_add(cli_outputs *o, const char *prog, const char *path);
/* Renames every output's temporary file to its name, in the order added. 1 when all were renamed;
   0 on the first failure (the cause printed), the remaining temporary files removed. */
CLIDEF int cli_outputs_commit(cli_outputs *o, const char *prog);
/* Removes every temporary file that is still there (after a failure). */
CLIDEF void cli_outputs_discard(cli_outputs *o);

#ifdef __cplusplus
}
#endif

#endif /* CLI_H */

#ifdef CLI_IMPLEMENTATION
#ifndef CLI_IMPLEMENTATION_DONE
#define CLI_IMPLEMENTATION_DONE

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

CLIDEF int cli_parse_long(const char *s, long lo, long hi, long *out)
{
    char *end;
    long v;
    if (!s || !(*s == '-' || *s == '+' || (*s >= '0' && *s <= '9'))) return 0; /* no leading space */
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno != 0 || v < lo || v > hi) return 0;
    *out = v;
    return 1;
}

/* a finite number filling [s, stop) where *stop is sep or the end; NULL when not */
static const char *cli__number(const char *s, char sep, double lo, double hi, double *out)
{
    char *end;
    double v;
    if (!s || !(*s == '-' || *s == '+' || *s == '.' || (*s >= '0' && *s <= '9'))) return NULL; /* no nan, inf, space */
    errno = 0;
    v = strtod(s, &end);
    if (end == s || (*end != '\0' && *end != sep) || errno == ERANGE || !(v - v == 0.0) || !(v >= lo && v <= hi)) return NULL;
    *out = v;
    return end;
}

CLIDEF int cli_parse_double(const char *s, double lo, double hi, double *out)
{
    const char *end = cli__number(s, '\0', lo, hi, out);
    return end != NULL && *end == '\0';
}

CLIDEF int cli_parse_doubles(const char *s, char sep, int min_n, int max_n, double lo, double hi, double *out, int *n)
{
    int k = 0;
    const char *p = s;
    for (;;) {
        if (k >= max_n) return 0;
        p = cli__number(p, sep, lo, hi, &out[k]);
        if (!p) return 0;
        k++;
        if (*p == '\0') break;
        p++; /* the separator */
    }
    if (k < min_n) return 0;
    if (n) *n = k;
    return 1;
}

/* a decimal integer in [lo, hi] filling [s, stop) with *stop == stop; its end or NULL */
static const char *cli__pixels(const char *s, char stop, long lo, long hi, int *out)
{
    long v = 0;
    const char *p = s;
    while (*p >= '0' && *p <= '9' && v <= hi) v = v * 10 + (*p++ - '0');
    if (p == s || *p != stop || v < lo || v > hi || v > INT_MAX) return NULL;
    *out = (int)v;
    return p;
}

CLIDEF int cli_parse_size(const char *s, long lo, long hi, int square_ok, int *w, int *h)
{
    const char *x;
    if (!s) return 0;
    if (square_ok && cli__pixels(s, '\0', lo, hi, w)) { *h = *w; return 1; }
    x = cli__pixels(s, 'x', lo, hi, w);
    return x != NULL && cli__pixels(x + 1, '\0', lo, hi, h) != NULL;
}

CLIDEF int cli_usage_error(const char *prog, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (see %s --help)\n", prog);
    return 2;
}

CLIDEF int cli_has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), m = strlen(ext), i;
    if (n <= m || path[n - m - 1] == '/') return 0;
    for (i = 0; i < m; i++) {
        char c = path[n - m + i], e = ext[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (e >= 'A' && e <= 'Z') e = (char)(e - 'A' + 'a');
        if (c != e) return 0;
    }
    return 1;
}

CLIDEF void cli_file_error(const char *prog, const char *path, const char *what, int errnum)
{
    if (errnum) fprintf(stderr, "%s: %s: %s: %s\n", prog, path, what, strerror(errnum));
    else fprintf(stderr, "%s: %s: %s\n", prog, path, what);
}

CLIDEF const char *cli_result_meaning(const char *name)
{
    static const char *const table[][2] = {
        /* common suffixes first: every header has them */
        {"_ERR_OUT_OF_MEMORY", "out of memory"},
        {"_CANCELLED", "cancelled by the progress callback"},
        {"_ERR_TOO_LARGE", "a size past the library's limits"},
        {"_ERR_NOT_FINITE", "a result that is not finite (it overflows)"},
        /* render.h */
        {"SR_ERR_INVALID_ARGUMENT", "a bad size, an index out of range or a non-finite input"},
        {"SR_ERR_IO", "the file could not be opened, read, written or closed"},
        {"SR_ERR_TRUNCATED", "the data ends before the image does"},
        {"SR_ERR_CORRUPT", "a malformed header, chunk, deflate stream or sample"},
        {"SR_ERR_CHECKSUM", "a PNG chunk's CRC-32 or the zlib stream's Adler-32 is wrong"},
        {"SR_ERR_UNSUPPORTED", "not a PNG, PGM/PPM or PFM file, or a feature the reader lacks"},
        /* dispmesh.h */
        {"DM_ERR_INVALID_ARGUMENT", "a missing array or mismatched counts"},
        {"DM_ERR_NO_TRIANGLES", "the mesh has no triangles"},
        {"DM_ERR_BAD_INDEX", "a triangle refers to a vertex that does not exist"},
        {"DM_ERR_BAD_POSITION", "a coordinate is NaN, infinite or beyond 1e18"},
        {"DM_ERR_MAP_TOO_SMALL", "the charts and their gutters do not fit in the map"},
        {"DM_ERR_NOT_WELDED", "a triangle soup: no vertex is shared by two triangles"},
        {"DM_ERR_BAD_MAP", "a parameterization or map array holds an index out of range or a NaN"},
        /* deform.h */
        {"DFM_ERR_INVALID_ARGUMENT", "missing data or a matrix of the wrong kind"},
        {"DFM_ERR_BAD_INDEX", "an index out of range"},
        {"DFM_ERR_BAD_VALUE", "a NaN or infinite value or position"},
        {"DFM_ERR_NOT_POSITIVE_DEFINITE", "the system is singular (a pivot <= 0)"},
        {"DFM_ERR_STRUCTURALLY_SINGULAR", "a column without a diagonal entry"},
        {"DFM_ERR_PATTERN_MISMATCH", "a refactorization with another pattern"},
        {"DFM_ERR_EMPTY_ROI", "no vertex of the region of interest may move"},
        {"DFM_ERR_HANDLE_OUTSIDE_ROI", "a handle vertex lies outside the region of interest"},
        {"DFM_ERR_UNCONSTRAINED", "a connected part of the region touches no fixed or handle vertex"},
        {"DFM_ERR_DEGENERATE_TRIANGLE", "a zero-area triangle touches the region of interest"},
        {"DFM_ERR_NON_MANIFOLD", "an edge is shared by more than two triangles"},
        {"DFM_ERR_UNWELDED", "two used vertices lie at exactly the same position"},
        /* relief.h */
        {"RL_ERR_INVALID_ARGUMENT", "an out-of-range option"},
        {"RL_ERR_EMPTY", "a map with no texels"},
        {"RL_ERR_NO_STROKES", "the sketch has no white and no black texel"},
        {"RL_ERR_PATCH_TOO_LARGE", "the patch (with its rotation margin) does not fit in the example"},
        /* texel.h */
        {"TVT_ERR_INVALID_ARGUMENT", "an unknown option value"},
        {"TVT_ERR_BAD_RESOLUTION", "the resolution is not a power of two in 8..1024"},
        {"TVT_ERR_BAD_PARAMETER", "a NaN, infinite or out-of-range parameter"},
        {"TVT_ERR_BAD_WD", "a weathering degree outside [0, 1]"},
        {"TVT_ERR_EMPTY", "no blades, or a texel with no density"},
        {"TVT_ERR_BAD_INDEX", "a triangle refers to a vertex that does not exist"},
        {"TVT_ERR_DEGENERATE", "a triangle of zero area"},
        {"TVT_ERR_FOLDED", "a shell prism folds (the shell is too thick for the curvature)"},
        /* subdiv4.h */
        {"SD4_ERR_INVALID_ARGUMENT", "a bad dimension, level count or option value"},
        {"SD4_ERR_BAD_INDEX", "a triangle refers to a vertex that does not exist"},
        {"SD4_ERR_BAD_POSITION", "a coordinate or height is NaN or infinite"},
        {"SD4_ERR_BUFFER_TOO_SMALL", "an output buffer smaller than the size functions say"},
    };
    size_t i, n = strlen(name);
    for (i = 0; i < sizeof table / sizeof table[0]; i++) {
        size_t m = strlen(table[i][0]);
        if (table[i][0][0] == '_' ? (n > m && strcmp(name + n - m, table[i][0]) == 0) : strcmp(name, table[i][0]) == 0)
            return table[i][1];
    }
    return "";
}

CLIDEF void cli_result_error(const char *prog, const char *context, const char *name, int errnum)
{
    const char *meaning = cli_result_meaning(name);
    fprintf(stderr, "%s: %s: %s", prog, context, name);
    if (*meaning) fprintf(stderr, " (%s)", meaning);
    if (errnum) fprintf(stderr, ": %s", strerror(errnum));
    fprintf(stderr, "\n");
}

CLIDEF void cli_read_error(const char *prog, const char *path, const char *message, const char *name,
                           const char *description, int errnum)
{
    fprintf(stderr, "%s: %s: %s", prog, path, message);
    if (errnum) fprintf(stderr, ": %s", strerror(errnum));
    fprintf(stderr, " (%s: %s)\n", name, description);
}

CLIDEF void cli_outputs_init(cli_outputs *o) { o->count = 0; }

CLIDEF const char *cli_output_add(cli_outputs *o, const char *prog, const char *path)
{
    size_t n = strlen(path);
    char *t;
    if (o->count >= CLI_MAX_OUTPUTS) { fprintf(stderr, "%s: %s: too many outputs\n", prog, path); return NULL; }
    if (n + 5 > CLI_PATH_MAX) { fprintf(stderr, "%s: %s: the name is too long (over %d bytes)\n", prog, path, CLI_PATH_MAX - 5); return NULL; }
    t = o->tmp[o->count++];
    memcpy(t, path, n);
    memcpy(t + n, ".tmp", 5);
    return t;
}

CLIDEF int cli_outputs_commit(cli_outputs *o, const char *prog)
{
    int i;
    for (i = 0; i < o->count; i++) {
        char path[CLI_PATH_MAX];
        size_t n = strlen(o->tmp[i]) - 4;
        memcpy(path, o->tmp[i], n);
        path[n] = '\0';
        if (rename(o->tmp[i], path) != 0) {
            int e = errno;
            fprintf(stderr, "%s: %s: cannot rename %s to it: %s\n", prog, path, o->tmp[i], strerror(e));
            for (; i < o->count; i++) remove(o->tmp[i]);
            o->count = 0;
            return 0;
        }
    }
    o->count = 0;
    return 1;
}

CLIDEF void cli_outputs_discard(cli_outputs *o)
{
    int i;
    for (i = 0; i < o->count; i++) remove(o->tmp[i]);
    o->count = 0;
}

#endif /* CLI_IMPLEMENTATION_DONE */
#endif /* CLI_IMPLEMENTATION */
