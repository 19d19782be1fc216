/* meshio.h - v0.1 - MIT licence (see end of file)
   Triangle-mesh reading (OBJ, OFF, PLY, STL), writing (OBJ, OFF, PLY, STL) and welding, with strict
   error reporting.

   WHAT
     Reads a polygon mesh into two flat arrays: positions (x,y,z floats, packed) and indices
     (three uint32_t per triangle). Polygons are triangulated as a fan. Everything else in the
     file (normals, texture coordinates, colours, materials, groups, lines, points) is ignored.
     Writes the same two arrays as OBJ, OFF, PLY or STL (PLY and STL ascii or binary
     little-endian) so that reading the file back gives the same bits (STL keeps no shared
     vertices: it gives back each triangle's corners, bit-exact); OBJ also with vertex normals.
     mio_weld() joins vertices with equal positions (an STL soup becomes a connected mesh).

   HOW TO USE (in ten lines)
       // in exactly one C or C++ file, #define MIO_IMPLEMENTATION before #include "meshio.h";
       // everywhere else just include it.
       mio_mesh mesh;
       mio_error err;
       if (mio_read_file("bunny.obj", NULL, &mesh, &err) != MIO_OK) {
           fprintf(stderr, "bunny.obj: %s\n", err.message);  // "line 12: face index 9 ..."
           return 1;
       }
       use(mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count);
       mio_free_mesh(&mesh);

   OPTIONS
     Compile time (define before including the implementation):
       MIO_STATIC            all functions are static (MIODEF = static), for private use in one file
       MIO_MALLOC(sz)        default allocator; define both MIO_MALLOC and MIO_FREE or neither
       MIO_FREE(p)
     Run time, mio_read_options (a zeroed struct, or NULL, means defaults):
       format      MIO_FORMAT_AUTO (default) detects the format from the content, then from the
                   file name's extension; any other value forces that format.
       allocator   NULL (default) uses MIO_MALLOC/MIO_FREE; otherwise every allocation of the
                   call goes through allocator->alloc/free. The allocator has no realloc: arrays
                   grow geometrically by alloc + copy + free.

   MEMORY
     A successful read returns a mesh whose arrays were allocated with the chosen allocator; a
     copy of the allocator is kept in mesh->allocator and mio_free_mesh() uses it. On any failure
     the output mesh is all zeros and every temporary has been freed. Sizes claimed by a file
     header are checked against the bytes actually present BEFORE anything is allocated, so a
     100-byte file claiming 10^12 faces fails without allocating. Peak memory is about the output
     arrays plus (mio_read_file only) the whole file; arrays grown while parsing OBJ and ascii STL
     may be up to twice their final size.
     mio_weld() replaces mesh->positions by a smaller array from the mesh's allocator and needs
     about 12 bytes per vertex while it runs; on failure the mesh is untouched.

   ERRORS
     Every function returns a mio_result; mio_result_string() names it. If the mio_error pointer
     is not NULL it receives the code, the 1-based text line (0 for binary data), the byte offset
     and a message; messages about the content start with "line N:" or "byte N:" (argument, I/O
     and allocation-before-parsing messages do not). Decisions made by this reader:
       - Non-finite coordinates (nan, inf, or a number that overflows float) are rejected with
         MIO_ERR_SYNTAX: downstream geometry code cannot use them. Normals are never read.
       - A face with fewer than 3 vertices (OBJ "f" with 0-2 references, OFF/PLY count < 3) is
         MIO_ERR_SYNTAX. Faces with repeated indices or zero area are kept as they are.
       - A vertex index of 0 in OBJ, a negative index in OFF/PLY, or an index past the last vertex
         is MIO_ERR_INDEX_RANGE.
       - A file that parses but contains no triangle (only points, lines or vertices) is
         MIO_ERR_EMPTY; so is a 0-byte input.
       - Numbers must be complete tokens: "3.1+e2" is a syntax error, not 3.1.
       - UTF-16 text (byte order mark FE FF or FF FE) is MIO_ERR_UNSUPPORTED; a UTF-8 BOM is skipped.
       - Welding is a separate call, mio_weld(), not a reader option, so that a caller sees the
         file's own vertices first; it joins only exactly equal positions (-0 equals +0), never
         within a tolerance, keeps the first occurrence and never reorders the kept vertices.

   FORMATS
     OBJ  "v x y z [w | r g b ...]" (anything after z is ignored) and "f" with i, i/t, i//n, i/t/n
          references, negative (relative) indices, forward references. All other statements
          (vt vn vp g o s l p usemtl mtllib ...) are ignored. "#" starts a comment, a "\" at the
          end of a line continues it, CRLF and a missing final newline are fine.
     OFF  OFF, COFF, NOFF, CNOFF, STOFF, ... headers (extra per-vertex values and per-face colours
          after the indices are ignored), counts on the header line or the next one, "#"
          comments. One vertex and one face per line. 4OFF, nOFF and binary OFF: MIO_ERR_UNSUPPORTED.
     PLY  ascii, binary_little_endian, binary_big_endian. x, y, z of any scalar type (char uchar
          short ushort int uint float double and int8 ... float64); every other property and
          element is skipped, lists included. Faces are the "vertex_indices" or "vertex_index"
          list of element "face" (any integer count and index types). Header lines with an
          unknown keyword are ignored like comments (Blender 2.47 wrote such lines).
     STL  ascii (several "solid" blocks allowed, keywords case-insensitive) and binary (80-byte
          header, uint32 count, 50 bytes per facet; the size must match exactly). A binary file
          may begin with "solid": it is recognised by its size. Vertices are NOT welded: facet k
          gives vertices 3k, 3k+1, 3k+2, so a closed STL solid reads as separate triangles; call
          mio_weld() for connectivity (exact equality: a reader option would hide that choice).
     Triangulation: a polygon v0 v1 ... vn-1 becomes the fan (v0, vi, vi+1), i = 1..n-2, which is
     right for convex polygons; a concave polygon gives a fan that may overlap itself.
     Detection (MIO_FORMAT_AUTO): a size that matches a binary STL count; "ply" magic; an OFF
     keyword; "solid"; then the extension (.obj .off .ply .stl, any case); then an OBJ keyword on
     the first statement line.

   THREAD SAFETY
     No global state: every function may run on any thread at the same time as any other, as
     long as they do not share an output mesh or error struct. The allocator you pass must be
     safe for the threads you call from.

   LIMITS
     vertex_count <= UINT32_MAX; indices are uint32_t. Text numbers are converted without the C
     locale (always "." as decimal point). A decimal with at most 19 significant digits and a
     power of ten within 10^+-22 is rounded correctly (Clinger's fast path); other values are
     scaled in a few steps and may be off by a few units in the last place of the double before
     the final rounding to float, which is too small to change the float that a 9-digit decimal
     denotes. The writers print "%.9g" (9 digits identify every float) and replace any locale
     decimal separator by ".", so write-then-read is bit-exact for every finite float, subnormals
     and -0 included (tested on random bit patterns). Writers reject non-finite positions
     (MIO_ERR_INVALID_ARGUMENT) and out-of-range indices (MIO_ERR_INDEX_RANGE) before creating
     the file. Data after the last expected element (OFF, PLY, ascii STL) is MIO_ERR_SYNTAX.
     Out-of-range positive OBJ indices are found after the whole file is read (forward references
     are legal), and reported at the line of the largest one.
     The bits do not depend on the compiler's FMA contraction (dialect, C or C++, -ffp-contract):
     the implementation turns it off for its own code and restores the user's setting after it,
     except under clang's -ffp-contract=fast, which ignores that pragma (the STL writer's facet
     normals may then differ in the last bits).

   REFERENCES
     Wavefront Technologies, "Object Files (.obj)", Advanced Visualizer manual, appendix B1 (1991).
     G. Turk, "The PLY Polygon File Format" (1994).
     Geomview manual, "OFF Files" (1996).
     3D Systems, "Stereolithography Interface Specification" (1989).
     W. D. Clinger, "How to Read Floating Point Numbers Accurately", PLDI 1990.
*/
#ifndef MIO_MESHIO_H
#define MIO_MESHIO_H

#include <stddef.h>
#include <stdint.h>

#ifdef MIO_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define MIODEF static __attribute__((unused)) /* no warning for the functions you do not call */
#else
#define MIODEF static
#endif
#else
#define MIODEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ============================================================================================
   Declarations
   ============================================================================================ */

typedef enum mio_result {
    MIO_OK = 0,
    MIO_ERR_INVALID_ARGUMENT, /* NULL pointer, bad option, non-finite value given to a writer */
    MIO_ERR_OUT_OF_MEMORY,    /* the allocator returned NULL */
    MIO_ERR_IO,               /* fopen/fread/fwrite/fclose failed */
    MIO_ERR_UNKNOWN_FORMAT,   /* MIO_FORMAT_AUTO could not tell the format */
    MIO_ERR_SYNTAX,           /* malformed content (see message) */
    MIO_ERR_TRUNCATED,        /* data ends early, or header counts need more bytes than exist */
    MIO_ERR_INDEX_RANGE,      /* a face refers to a vertex that does not exist */
    MIO_ERR_TOO_LARGE,        /* more than UINT32_MAX vertices, or sizes overflow size_t */
    MIO_ERR_UNSUPPORTED,      /* valid but unsupported variant (UTF-16, 4OFF, binary OFF, ...) */
    MIO_ERR_EMPTY             /* parsed fine but no triangles */
} mio_result;

typedef enum mio_format {
    MIO_FORMAT_AUTO = 0, /* as input: detect; as mio_detect_format() result: unknown */
    MIO_FORMAT_OBJ,
    MIO_FORMAT_OFF,
    MIO_FORMAT_PLY,
    MIO_FORMAT_STL
} mio_format;

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct mio_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} mio_allocator;

typedef struct mio_mesh {
    float *positions;      /* 3 * vertex_count floats: x0 y0 z0 x1 y1 z1 ... */
    size_t vertex_count;
    uint32_t *indices;     /* 3 * triangle_count indices, each < vertex_count */
    size_t triangle_count;
    mio_allocator allocator; /* the allocator that owns the arrays; used by mio_free_mesh */
} mio_mesh;

typedef struct mio_error {
    mio_result code;
    size_t line;   /* 1-based text line, 0 if n/a */
    size_t offset; /* byte offset */
    char message[160];
} mio_error;

typedef struct mio_read_options {
    mio_format format;              /* MIO_FORMAT_AUTO (0) = detect */
    const mio_allocator *allocator; /* NULL = malloc/free */
} mio_read_options;                 /* zero = defaults */

/* Reads a mesh file.
   path  file name; its extension helps format detection. Must not be NULL.
   opt   NULL or a zeroed struct for defaults.
   out   receives the mesh (zeroed on failure). Must not be NULL.
   err   NULL, or receives code / line / offset / message (code MIO_OK and "" on success). */
MIODEF mio_result mio_read_file(const char *path, const mio_read_options *opt, mio_mesh *out, mio_error *err);

/* Reads a mesh from memory. data need not be NUL-terminated and is never read past size.
   data may be NULL only when size is 0. Other parameters as mio_read_file. */
MIODEF mio_result mio_read_memory(const void *data, size_t size, const mio_read_options *opt, mio_mesh *out, mio_error *err);

/* Writes "v x y z" lines (%.9g) and "f a b c" lines (1-based).
   positions may be NULL only if vertex_count is 0; indices only if triangle_count is 0.
   Every index must be < vertex_count and every coordinate finite (checked before writing). */
MIODEF mio_result mio_write_obj(const char *path, const float *positions, size_t vertex_count,
                                const uint32_t *indices, size_t triangle_count, mio_error *err);

/* As mio_write_obj, with a "vn x y z" line per vertex after the "v" lines (normals: 3 per vertex,
   finite; NULL = none) and faces "f a//a b//b c//c", so that viewers shade with these normals. */
MIODEF mio_result mio_write_obj_normals(const char *path, const float *positions, const float *normals,
                                        size_t vertex_count, const uint32_t *indices, size_t triangle_count,
                                        mio_error *err);

/* Writes PLY with float x,y,z and a "list uchar uint vertex_indices" face element.
   binary: 0 = ascii (%.9g), 1 = binary little-endian (on any host). Other parameters as OBJ. */
MIODEF mio_result mio_write_ply(const char *path, const float *positions, size_t vertex_count,
                                const uint32_t *indices, size_t triangle_count, int binary, mio_error *err);

/* Writes OFF: "OFF", "V T 0", one "x y z" line per vertex (%.9g), "3 a b c" per triangle.
   Parameters as mio_write_obj. */
MIODEF mio_result mio_write_off(const char *path, const float *positions, size_t vertex_count,
                                const uint32_t *indices, size_t triangle_count, mio_error *err);

/* Writes STL, one facet per triangle with its unit normal (0 0 0 for a degenerate triangle).
   binary: 0 = ascii ("solid meshio", %.9g), 1 = binary little-endian (80-byte header that does not
   begin with "solid", uint32 count). STL has no shared vertices: reading the file back gives
   3 vertices per triangle; mio_weld() joins them again. triangle_count > UINT32_MAX is
   MIO_ERR_TOO_LARGE for binary. Other parameters as mio_write_obj. */
MIODEF mio_result mio_write_stl(const char *path, const float *positions, size_t vertex_count,
                                const uint32_t *indices, size_t triangle_count, int binary, mio_error *err);

/* Welds, in place, vertices whose positions are exactly equal (float ==, so -0 and +0 are one
   vertex; no tolerance: a tolerance would join vertices that the file kept apart on purpose and
   would depend on the order of the merges). The kept vertex is the first occurrence in the
   positions array, with its bits; kept vertices stay in their order (first-use order); indices
   are renumbered; vertices no triangle uses are kept. Deterministic. A mesh with no duplicate
   position is left exactly as it was. Memory: the positions array is replaced by a new one from
   mesh->allocator (MIO_MALLOC/MIO_FREE if mesh->allocator.alloc is NULL); temporaries are about
   12 bytes per vertex. Errors: NULL mesh or arrays, a non-finite coordinate
   (MIO_ERR_INVALID_ARGUMENT), an index >= vertex_count (MIO_ERR_INDEX_RANGE), more than
   UINT32_MAX - 1 vertices (MIO_ERR_TOO_LARGE), MIO_ERR_OUT_OF_MEMORY; on any error the mesh is
   unchanged. err may be NULL. */
MIODEF mio_result mio_weld(mio_mesh *mesh, mio_error *err);

/* Frees a mesh's arrays with mesh->allocator and zeroes it. Safe on a zeroed mesh and on NULL. */
MIODEF void mio_free_mesh(mio_mesh *mesh);

/* "MIO_OK", "MIO_ERR_SYNTAX", ... (the enum name); "MIO_ERR_?" for values outside the enum. */
MIODEF const char *mio_result_string(mio_result r);

/* What the result means, in a few words ("malformed content", "out of memory", ...), for messages. */
MIODEF const char *mio_result_description(mio_result r);

/* Guesses the format from content, then from the extension of path_or_null (may be NULL).
   Returns MIO_FORMAT_AUTO when it cannot tell. data may be NULL only when size is 0. */
MIODEF mio_format mio_detect_format(const void *data, size_t size, const char *path_or_null);

/* Addition: "obj", "off", "ply", "stl", or "auto". */
MIODEF const char *mio_format_string(mio_format f);

#ifdef __cplusplus
}
#endif
#endif /* MIO_MESHIO_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef MIO_IMPLEMENTATION
#ifndef MIO_IMPLEMENTATION_DONE
#define MIO_IMPLEMENTATION_DONE

#include <stdio.h>
#include <stdarg.h>
#include <string.h>
#include <float.h>
#include <math.h>

#if defined(MIO_MALLOC) && defined(MIO_FREE)
/* both given */
#elif !defined(MIO_MALLOC) && !defined(MIO_FREE)
#include <stdlib.h>
#define MIO_MALLOC(sz) malloc(sz)
#define MIO_FREE(p) free(p)
#else
#error "meshio.h: define both MIO_MALLOC and MIO_FREE, or neither"
#endif

/* FMA contraction off from here to the end of the implementation, the user's setting restored
   after it: each a * b + c rounds twice whatever the dialect or -ffp-contract, so the bits do not
   depend on them (see LIMITS). GCC ignores STDC FP_CONTRACT but honours its optimize pragma; clang
   takes fp contract inside float_control push/pop (except under -ffp-contract=fast, which ignores
   pragmas); other compilers: nothing. */
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(push)
#pragma clang fp contract(off)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------------------------------
   Section: allocation and the parse context
   --------------------------------------------------------------------------------------------- */

static void *mio__default_alloc(void *user, size_t size) { (void)user; return MIO_MALLOC(size); }
static void mio__default_free(void *user, void *ptr) { (void)user; MIO_FREE(ptr); }

typedef struct mio__ctx {
    const unsigned char *data; /* input, not NUL-terminated */
    size_t size;
    mio_allocator alloc;
    mio_error *err;            /* never NULL inside the parsers (points to a local if needed) */
    float *pos;                /* output being built */
    size_t vertex_count, vertex_cap;
    uint32_t *idx;
    size_t triangle_count, triangle_cap;
} mio__ctx;

static void *mio__alloc(mio__ctx *c, size_t size)
{
    return c->alloc.alloc(c->alloc.user, size ? size : 1);
}

static void mio__free(mio__ctx *c, void *p)
{
    if (p) c->alloc.free(c->alloc.user, p);
}

/* Stores a formatted error. The message starts with "line N: " for text, "byte N: " otherwise. */
static mio_result mio__fail(mio__ctx *c, mio_result code, size_t line, size_t offset, const char *fmt, ...)
{
    mio_error *e = c->err;
    size_t n;
    va_list ap;
    e->code = code;
    e->line = line;
    e->offset = offset;
    if (line) snprintf(e->message, sizeof e->message, "line %llu: ", (unsigned long long)line);
    else snprintf(e->message, sizeof e->message, "byte %llu: ", (unsigned long long)offset);
    n = strlen(e->message);
    va_start(ap, fmt);
    vsnprintf(e->message + n, sizeof e->message - n, fmt, ap);
    va_end(ap);
    return code;
}

static mio_result mio__oom(mio__ctx *c, size_t line, size_t offset)
{
    return mio__fail(c, MIO_ERR_OUT_OF_MEMORY, line, offset, "out of memory");
}

/* Grows *array (capacity *cap items of elem bytes, count of them in use) to hold at least need
   items: alloc + copy + free. The new capacity is max(need, 2 * cap, 16), so one-at-a-time pushes
   cost amortised O(1) and an exact reservation allocates exactly. Returns 0 on failure. */
static int mio__grow(mio__ctx *c, void **array, size_t *cap, size_t count, size_t need, size_t elem)
{
    size_t new_cap;
    void *fresh;
    if (need <= *cap) return 1;
    if (need > ((size_t)-1) / elem) return 0;
    new_cap = *cap <= ((size_t)-1) / 2 / elem ? *cap * 2 : need;
    if (new_cap < need) new_cap = need;
    if (new_cap < 16 && 16 <= ((size_t)-1) / elem) new_cap = 16;
    fresh = mio__alloc(c, new_cap * elem);
    if (!fresh) return 0;
    if (count) memcpy(fresh, *array, count * elem);
    mio__free(c, *array);
    *array = fresh;
    *cap = new_cap;
    return 1;
}

/* Makes room for need vertices in total; fails with TOO_LARGE past UINT32_MAX. */
static mio_result mio__reserve_vertices(mio__ctx *c, size_t need, size_t line, size_t offset)
{
    void *p = c->pos;
    if (need > (size_t)UINT32_MAX)
        return mio__fail(c, MIO_ERR_TOO_LARGE, line, offset, "more than %lu vertices", (unsigned long)UINT32_MAX);
    if (!mio__grow(c, &p, &c->vertex_cap, c->vertex_count, need, 3 * sizeof(float))) return mio__oom(c, line, offset);
    c->pos = (float *)p;
    return MIO_OK;
}

/* Makes room for need triangles in total. */
static mio_result mio__reserve_triangles(mio__ctx *c, size_t need, size_t line, size_t offset)
{
    void *p = c->idx;
    if (need > ((size_t)-1) / (3 * sizeof(uint32_t)))
        return mio__fail(c, MIO_ERR_TOO_LARGE, line, offset, "too many triangles");
    if (!mio__grow(c, &p, &c->triangle_cap, c->triangle_count, need, 3 * sizeof(uint32_t))) return mio__oom(c, line, offset);
    c->idx = (uint32_t *)p;
    return MIO_OK;
}

static mio_result mio__push_vertex(mio__ctx *c, const float xyz[3], size_t line, size_t offset)
{
    if (c->vertex_count == c->vertex_cap) {
        mio_result r = mio__reserve_vertices(c, c->vertex_count + 1, line, offset);
        if (r != MIO_OK) return r;
    }
    memcpy(c->pos + 3 * c->vertex_count, xyz, 3 * sizeof(float));
    c->vertex_count++;
    return MIO_OK;
}

static mio_result mio__push_triangle(mio__ctx *c, uint32_t a, uint32_t b, uint32_t d, size_t line, size_t offset)
{
    uint32_t *t;
    if (c->triangle_count == c->triangle_cap) {
        mio_result r = mio__reserve_triangles(c, c->triangle_count + 1, line, offset);
        if (r != MIO_OK) return r;
    }
    t = c->idx + 3 * c->triangle_count;
    t[0] = a;
    t[1] = b;
    t[2] = d;
    c->triangle_count++;
    return MIO_OK;
}

static void mio__discard(mio__ctx *c)
{
    mio__free(c, c->pos);
    mio__free(c, c->idx);
    c->pos = NULL;
    c->idx = NULL;
    c->vertex_count = c->vertex_cap = c->triangle_count = c->triangle_cap = 0;
}

/* ---------------------------------------------------------------------------------------------
   Section: locale-independent number parsing on bounded text
   --------------------------------------------------------------------------------------------- */

static int mio__is_space(unsigned char ch) { return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f'; }
static int mio__is_digit(unsigned char ch) { return ch >= '0' && ch <= '9'; }
static int mio__lower(int ch) { return (ch >= 'A' && ch <= 'Z') ? ch - 'A' + 'a' : ch; }

/* Exact powers of ten representable in a double. */
static const double mio__pow10[23] = {
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22 };

/* Parses [+-] digits [. digits] [(e|E) [+-] digits] at p (at most end - p bytes). Returns the
   number of bytes used, 0 if no number starts at p. Up to 19 significant digits are kept; with
   |exponent| <= 22 the result is the correctly rounded double (one exact multiply or divide of
   two exact doubles, Clinger 1990); otherwise it is scaled step by step. */
static size_t mio__parse_double(const unsigned char *p, const unsigned char *end, double *out)
{
    const unsigned char *s = p;
    int negative = 0, digits = 0, significant = 0;
    uint64_t mantissa = 0;
    long exp10 = 0;
    double v;
    if (s < end && (*s == '+' || *s == '-')) { negative = *s == '-'; s++; }
    while (s < end && mio__is_digit(*s)) {
        digits++;
        if (significant < 19) {
            mantissa = mantissa * 10 + (uint64_t)(*s - '0');
            if (mantissa) significant++;
        } else if (exp10 < 100000) {
            exp10++; /* digit beyond the 19 kept: only its weight matters */
        }
        s++;
    }
    if (s < end && *s == '.') {
        s++;
        while (s < end && mio__is_digit(*s)) {
            digits++;
            if (significant < 19 && exp10 > -100000) {
                mantissa = mantissa * 10 + (uint64_t)(*s - '0');
                if (mantissa) significant++;
                exp10--;
            }
            s++;
        }
    }
    if (!digits) return 0;
    if (s < end && (*s == 'e' || *s == 'E')) {
        const unsigned char *e = s + 1;
        int eneg = 0;
        long ev = 0;
        if (e < end && (*e == '+' || *e == '-')) { eneg = *e == '-'; e++; }
        if (e < end && mio__is_digit(*e)) {
            while (e < end && mio__is_digit(*e)) {
                if (ev < 100000) ev = ev * 10 + (*e - '0');
                e++;
            }
            exp10 += eneg ? -ev : ev;
            s = e;
        }
    }
    if (mantissa == 0) {
        v = 0.0;
    } else if (mantissa < ((uint64_t)1 << 53) && exp10 >= -22 && exp10 <= 22) {
        v = (double)mantissa;
        v = exp10 >= 0 ? v * mio__pow10[exp10] : v / mio__pow10[-exp10];
    } else if (exp10 > 400) {
        v = DBL_MAX * 2.0; /* overflows to infinity: rejected by the caller as non-finite */
    } else if (exp10 < -400) {
        v = 0.0;
    } else {
        v = (double)mantissa;
        while (exp10 > 22) { v *= 1e22; exp10 -= 22; }
        while (exp10 < -22) { v /= 1e22; exp10 += 22; }
        v = exp10 >= 0 ? v * mio__pow10[exp10] : v / mio__pow10[-exp10];
    }
    *out = negative ? -v : v;
    return (size_t)(s - p);
}

/* Double to float for a coordinate: 0 if the value is not finite or does not fit a float.
   Values between FLT_MAX and FLT_MAX + half an ulp round to FLT_MAX (as the conversion would);
   the comparison is written out so that no out-of-range conversion is ever executed. */
static int mio__to_float(double v, float *out)
{
    const double limit = 3.4028235677973366e38; /* FLT_MAX + 2^103: halfway to 2^128 */
    if (!(v == v)) return 0;
    if (v >= limit || v <= -limit) return 0;
    if (v > FLT_MAX) v = FLT_MAX;
    if (v < -FLT_MAX) v = -FLT_MAX;
    *out = (float)v;
    return 1;
}

/* Parses an optionally signed decimal integer. Returns bytes used (0 if none); *overflow is set
   when the magnitude would exceed about 2^63 / 10 * 10 (the value is then clamped). */
static size_t mio__parse_int(const unsigned char *p, const unsigned char *end, long long *out, int *overflow)
{
    const unsigned char *s = p;
    int negative = 0;
    uint64_t v = 0;
    *overflow = 0;
    if (s < end && (*s == '+' || *s == '-')) { negative = *s == '-'; s++; }
    if (s >= end || !mio__is_digit(*s)) return 0;
    while (s < end && mio__is_digit(*s)) {
        if (v > (((uint64_t)1 << 63) - 10) / 10) *overflow = 1; /* keeps v below 2^63 */
        else v = v * 10 + (uint64_t)(*s - '0');
        s++;
    }
    *out = negative ? -(long long)v : (long long)v;
    return (size_t)(s - p);
}

/* True if the token [p, p+n) spells nan or inf(inity), any case and sign: used to say
   "non-finite" instead of "not a number" in messages. */
static int mio__is_nonfinite_word(const unsigned char *p, size_t n)
{
    static const char *const words[3] = { "nan", "inf", "infinity" };
    int w;
    if (n && (*p == '+' || *p == '-')) { p++; n--; }
    for (w = 0; w < 3; w++) {
        size_t k, len = strlen(words[w]);
        if (n < len) continue;
        for (k = 0; k < len; k++)
            if (mio__lower(p[k]) != words[w][k]) break;
        if (k == len && (n == len || p[len] == '(')) return 1;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
   Section: text cursor shared by the OBJ, OFF, PLY-ascii and STL-ascii readers
   --------------------------------------------------------------------------------------------- */

typedef struct mio__text {
    mio__ctx *c;
    const unsigned char *p, *end;
    size_t line;
} mio__text;

static size_t mio__off(const mio__text *t) { return (size_t)(t->p - t->c->data); }

static int mio__at_token_end(const mio__text *t, const unsigned char *q)
{
    return q >= t->end || mio__is_space(*q) || *q == '\n' || *q == '#';
}

/* Skips blanks but not newlines. obj_continuation: a backslash before a newline joins lines. */
static void mio__skip_blanks(mio__text *t, int obj_continuation)
{
    for (;;) {
        while (t->p < t->end && mio__is_space(*t->p)) t->p++;
        if (obj_continuation && t->p < t->end && *t->p == '\\') {
            const unsigned char *q = t->p + 1;
            while (q < t->end && (*q == '\r' || *q == ' ' || *q == '\t')) q++;
            if (q < t->end && *q == '\n') { t->p = q + 1; t->line++; continue; }
        }
        return;
    }
}

/* Skips whitespace, newlines and optionally "#" comments. */
static void mio__skip_space(mio__text *t, int hash_comments)
{
    while (t->p < t->end) {
        unsigned char ch = *t->p;
        if (ch == '\n') { t->line++; t->p++; }
        else if (mio__is_space(ch)) t->p++;
        else if (hash_comments && ch == '#') { while (t->p < t->end && *t->p != '\n') t->p++; }
        else break;
    }
}

/* Moves to the start of the next line (past the '\n'). */
static void mio__next_line(mio__text *t, int obj_continuation)
{
    while (t->p < t->end) {
        unsigned char ch = *t->p++;
        if (ch == '\n') {
            t->line++;
            if (obj_continuation) {
                const unsigned char *q = t->p - 2; /* the byte before '\n' */
                while (q >= t->c->data && (*q == '\r' || *q == ' ' || *q == '\t')) q--;
                if (q >= t->c->data && *q == '\\') continue;
            }
            return;
        }
    }
}

/* True at end of line: end of data, '\n' or '#'. */
static int mio__at_eol(const mio__text *t) { return t->p >= t->end || *t->p == '\n' || *t->p == '#'; }

/* Length of the token at p (up to whitespace, newline or '#'). */
static size_t mio__token_len(const mio__text *t)
{
    const unsigned char *q = t->p;
    while (!mio__at_token_end(t, q)) q++;
    return (size_t)(q - t->p);
}

static int mio__token_is(const mio__text *t, const char *word, int any_case)
{
    size_t n = mio__token_len(t), k;
    if (n != strlen(word)) return 0;
    for (k = 0; k < n; k++) {
        int a = t->p[k], b = word[k];
        if (any_case) { a = mio__lower(a); b = mio__lower(b); }
        if (a != b) return 0;
    }
    return 1;
}

/* Copies a token into a short printable excerpt for messages. */
static const char *mio__excerpt(const mio__text *t, char *buf, size_t cap)
{
    size_t n = mio__token_len(t), k;
    if (n == 0) return t->p >= t->end ? "end of data" : "end of line";
    if (n > cap - 4) n = cap - 4;
    buf[0] = '\'';
    for (k = 0; k < n; k++) buf[k + 1] = (t->p[k] >= 32 && t->p[k] < 127) ? (char)t->p[k] : '?';
    buf[n + 1] = '\'';
    buf[n + 2] = '\0';
    return buf;
}

/* Reads one coordinate token (the token must end right after the number). */
static mio_result mio__read_coord(mio__text *t, float *out, const char *what)
{
    double v = 0.0;
    size_t n = mio__parse_double(t->p, t->end, &v);
    char ex[40];
    if (n == 0 || !mio__at_token_end(t, t->p + n)) {
        if (mio__is_nonfinite_word(t->p, mio__token_len(t)))
            return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, mio__off(t), "non-finite %s %s is not accepted", what, mio__excerpt(t, ex, sizeof ex));
        if (t->p >= t->end)
            return mio__fail(t->c, MIO_ERR_TRUNCATED, t->line, mio__off(t), "data ends where a %s was expected", what);
        return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, mio__off(t), "expected a %s, found %s", what, mio__excerpt(t, ex, sizeof ex));
    }
    if (!mio__to_float(v, out))
        return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, mio__off(t), "%s %s is not a finite float", what, mio__excerpt(t, ex, sizeof ex));
    t->p += n;
    return MIO_OK;
}

/* Reads one integer token. */
static mio_result mio__read_int(mio__text *t, long long *out, const char *what)
{
    int overflow = 0;
    size_t n = mio__parse_int(t->p, t->end, out, &overflow);
    char ex[40];
    if (n == 0 || !mio__at_token_end(t, t->p + n)) {
        if (t->p >= t->end)
            return mio__fail(t->c, MIO_ERR_TRUNCATED, t->line, mio__off(t), "data ends where %s was expected", what);
        return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, mio__off(t), "expected %s (an integer), found %s", what, mio__excerpt(t, ex, sizeof ex));
    }
    if (overflow)
        return mio__fail(t->c, MIO_ERR_TOO_LARGE, t->line, mio__off(t), "%s %s is too large", what, mio__excerpt(t, ex, sizeof ex));
    t->p += n;
    return MIO_OK;
}

/* Checks that a text file is not UTF-16 and skips a UTF-8 byte order mark. */
static mio_result mio__text_start(mio__text *t)
{
    if (t->end - t->p >= 2 && ((t->p[0] == 0xFE && t->p[1] == 0xFF) || (t->p[0] == 0xFF && t->p[1] == 0xFE)))
        return mio__fail(t->c, MIO_ERR_UNSUPPORTED, 1, 0, "UTF-16 text is not supported (convert the file to UTF-8 or ASCII)");
    if (t->end - t->p >= 3 && t->p[0] == 0xEF && t->p[1] == 0xBB && t->p[2] == 0xBF) t->p += 3;
    return MIO_OK;
}

/* Emits the fan (first, prev, cur) for polygon vertex k >= 2. */
static mio_result mio__fan(mio__ctx *c, uint32_t *first_prev, size_t k, uint32_t cur, size_t line, size_t offset)
{
    mio_result r = MIO_OK;
    if (k == 0) first_prev[0] = cur;
    else if (k >= 2) r = mio__push_triangle(c, first_prev[0], first_prev[1], cur, line, offset);
    first_prev[1] = cur;
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Section: OBJ reader
   --------------------------------------------------------------------------------------------- */

/* Parses one face reference "i", "i/t", "i//n" or "i/t/n" and resolves i to a 0-based index.
   Negative i counts back from the last vertex defined so far. Positive indices may point
   forward; they are checked against the final vertex count by the caller (max_index). */
static mio_result mio__obj_ref(mio__text *t, uint32_t *index, long long *max_index, size_t *max_line, size_t *max_offset)
{
    long long v = 0, ignored = 0;
    int overflow = 0, part;
    size_t n = mio__parse_int(t->p, t->end, &v, &overflow);
    size_t at = mio__off(t);
    char ex[40];
    if (n == 0 || (!mio__at_token_end(t, t->p + n) && t->p[n] != '/'))
        return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, at, "bad face vertex %s", mio__excerpt(t, ex, sizeof ex));
    if (overflow || v == 0 || v > (long long)UINT32_MAX || v < -(long long)t->c->vertex_count)
        return mio__fail(t->c, MIO_ERR_INDEX_RANGE, t->line, at, "face vertex index %s out of range (%llu vertices so far)",
                         mio__excerpt(t, ex, sizeof ex), (unsigned long long)t->c->vertex_count);
    t->p += n;
    /* optional /t and /n parts: each an integer or empty ("i//n") */
    for (part = 0; part < 2 && t->p < t->end && *t->p == '/'; part++) {
        t->p++;
        n = mio__parse_int(t->p, t->end, &ignored, &overflow);
        t->p += n;
    }
    if (!mio__at_token_end(t, t->p))
        return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, at, "bad face vertex reference");
    if (v < 0) {
        *index = (uint32_t)((long long)t->c->vertex_count + v);
    } else {
        *index = (uint32_t)(v - 1);
        if (v > *max_index) { *max_index = v; *max_line = t->line; *max_offset = at; }
    }
    return MIO_OK;
}

static mio_result mio__read_obj(mio__ctx *c)
{
    mio__text t;
    mio_result r;
    long long max_index = 0;
    size_t max_line = 0, max_offset = 0;
    t.c = c;
    t.p = c->data;
    t.end = c->data + c->size;
    t.line = 1;
    if ((r = mio__text_start(&t)) != MIO_OK) return r;
    while (t.p < t.end) {
        mio__skip_blanks(&t, 1);
        if (mio__token_is(&t, "v", 0)) {
            float xyz[3];
            int k;
            size_t line = t.line, at = mio__off(&t);
            t.p++;
            for (k = 0; k < 3; k++) {
                mio__skip_blanks(&t, 1);
                if (mio__at_eol(&t))
                    return mio__fail(c, MIO_ERR_SYNTAX, t.line, mio__off(&t), "vertex needs 3 coordinates, found %d", k);
                if ((r = mio__read_coord(&t, &xyz[k], "coordinate")) != MIO_OK) return r;
            }
            if ((r = mio__push_vertex(c, xyz, line, at)) != MIO_OK) return r;
        } else if (mio__token_is(&t, "f", 0)) {
            uint32_t fan[2] = { 0, 0 };
            size_t k = 0, line = t.line, at = mio__off(&t);
            t.p++;
            for (;;) {
                uint32_t index = 0;
                mio__skip_blanks(&t, 1);
                if (mio__at_eol(&t)) break;
                if ((r = mio__obj_ref(&t, &index, &max_index, &max_line, &max_offset)) != MIO_OK) return r;
                if ((r = mio__fan(c, fan, k, index, t.line, mio__off(&t))) != MIO_OK) return r;
                k++;
            }
            if (k < 3)
                return mio__fail(c, MIO_ERR_SYNTAX, line, at, "face has %llu vertices; at least 3 are needed", (unsigned long long)k);
        }
        mio__next_line(&t, 1);
    }
    if (max_index > (long long)c->vertex_count)
        return mio__fail(c, MIO_ERR_INDEX_RANGE, max_line, max_offset, "face vertex index %lld out of range (file has %llu vertices)",
                         max_index, (unsigned long long)c->vertex_count);
    return MIO_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: OFF reader
   --------------------------------------------------------------------------------------------- */

/* Skips blank lines and comment lines; leaves t at the first byte of the next content line. */
static void mio__off_skip_empty(mio__text *t)
{
    mio__skip_space(t, 1);
}

/* Reads a non-negative count or index on the current line. */
static mio_result mio__off_uint(mio__text *t, unsigned long long *out, const char *what)
{
    long long v = 0;
    mio_result r;
    mio__skip_blanks(t, 0);
    if (mio__at_eol(t)) {
        if (t->p >= t->end) return mio__fail(t->c, MIO_ERR_TRUNCATED, t->line, mio__off(t), "data ends where %s was expected", what);
        return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, mio__off(t), "line ends where %s was expected", what);
    }
    if ((r = mio__read_int(t, &v, what)) != MIO_OK) return r;
    if (v < 0) return mio__fail(t->c, MIO_ERR_INDEX_RANGE, t->line, mio__off(t), "negative %s", what);
    *out = (unsigned long long)v;
    return MIO_OK;
}

static mio_result mio__read_off(mio__ctx *c)
{
    mio__text t;
    mio_result r;
    unsigned long long nv = 0, nf = 0, i;
    size_t len, k, remaining, counts_line, counts_at;
    const unsigned char *kw;
    t.c = c;
    t.p = c->data;
    t.end = c->data + c->size;
    t.line = 1;
    if ((r = mio__text_start(&t)) != MIO_OK) return r;
    mio__off_skip_empty(&t);
    /* header keyword: [ST][C][N][4][n]OFF */
    kw = t.p;
    len = mio__token_len(&t);
    k = 0;
    if (len >= 2 && kw[0] == 'S' && kw[1] == 'T') k = 2;
    if (k < len && kw[k] == 'C') k++;
    if (k < len && kw[k] == 'N') k++;
    if (k < len && (kw[k] == '4' || kw[k] == 'n'))
        return mio__fail(c, MIO_ERR_UNSUPPORTED, t.line, mio__off(&t), "4OFF / nOFF (not 3-dimensional) is not supported");
    if (len != k + 3 || memcmp(kw + k, "OFF", 3) != 0)
        return mio__fail(c, MIO_ERR_SYNTAX, t.line, mio__off(&t), "missing OFF header keyword");
    t.p += len;
    mio__skip_blanks(&t, 0);
    if (mio__token_is(&t, "BINARY", 0))
        return mio__fail(c, MIO_ERR_UNSUPPORTED, t.line, mio__off(&t), "binary OFF is not supported");
    if (mio__at_eol(&t)) { /* counts on a following line */
        mio__next_line(&t, 0);
        mio__off_skip_empty(&t);
    }
    counts_line = t.line;
    counts_at = mio__off(&t);
    if ((r = mio__off_uint(&t, &nv, "the vertex count")) != MIO_OK) return r;
    if ((r = mio__off_uint(&t, &nf, "the face count")) != MIO_OK) return r;
    mio__next_line(&t, 0); /* the edge count, if present, is ignored */
    /* Size check before allocating: every vertex line holds >= 3 tokens and every face line
       >= 4, each token at least one byte plus one separator (the last may lack it). */
    remaining = (size_t)(t.end - t.p);
    if (nv > UINT32_MAX)
        return mio__fail(c, MIO_ERR_TOO_LARGE, counts_line, counts_at, "%llu vertices is more than %lu", nv, (unsigned long)UINT32_MAX);
    if (nf > (unsigned long long)remaining / 8 || nv > (unsigned long long)remaining / 6 ||
        nv * 6 + nf * 8 > (unsigned long long)remaining + 1)
        return mio__fail(c, MIO_ERR_TRUNCATED, counts_line, counts_at,
                         "header claims %llu vertices and %llu faces but only %llu bytes follow", nv, nf, (unsigned long long)remaining);
    if ((r = mio__reserve_vertices(c, (size_t)nv, t.line, mio__off(&t))) != MIO_OK) return r;
    if ((r = mio__reserve_triangles(c, (size_t)nf, t.line, mio__off(&t))) != MIO_OK) return r;
    for (i = 0; i < nv; i++) {
        float xyz[3];
        int d;
        mio__off_skip_empty(&t);
        for (d = 0; d < 3; d++) {
            mio__skip_blanks(&t, 0);
            if (mio__at_eol(&t)) {
                if (t.p >= t.end) return mio__fail(c, MIO_ERR_TRUNCATED, t.line, mio__off(&t), "data ends in vertex %llu of %llu", i, nv);
                return mio__fail(c, MIO_ERR_SYNTAX, t.line, mio__off(&t), "vertex needs 3 coordinates, found %d", d);
            }
            if ((r = mio__read_coord(&t, &xyz[d], "coordinate")) != MIO_OK) return r;
        }
        memcpy(c->pos + 3 * c->vertex_count++, xyz, sizeof xyz);
        mio__next_line(&t, 0);
    }
    for (i = 0; i < nf; i++) {
        unsigned long long n = 0, j, index = 0;
        uint32_t fan[2] = { 0, 0 };
        size_t line, at;
        mio__off_skip_empty(&t);
        line = t.line;
        at = mio__off(&t);
        if (t.p >= t.end) return mio__fail(c, MIO_ERR_TRUNCATED, t.line, at, "data ends before face %llu of %llu", i, nf);
        if ((r = mio__off_uint(&t, &n, "the face vertex count")) != MIO_OK) return r;
        if (n < 3) return mio__fail(c, MIO_ERR_SYNTAX, line, at, "face has %llu vertices; at least 3 are needed", n);
        if (n > (unsigned long long)(t.end - t.p)) return mio__fail(c, MIO_ERR_TRUNCATED, line, at, "face claims %llu vertices, more than the bytes left", n);
        for (j = 0; j < n; j++) {
            if ((r = mio__off_uint(&t, &index, "a face vertex index")) != MIO_OK) return r;
            if (index >= nv)
                return mio__fail(c, MIO_ERR_INDEX_RANGE, t.line, mio__off(&t), "face vertex index %llu out of range (%llu vertices)", index, nv);
            if ((r = mio__fan(c, fan, (size_t)j, (uint32_t)index, t.line, mio__off(&t))) != MIO_OK) return r;
        }
        mio__next_line(&t, 0); /* per-face colour ignored */
    }
    mio__off_skip_empty(&t);
    if (t.p < t.end) {
        char ex[40];
        return mio__fail(c, MIO_ERR_SYNTAX, t.line, mio__off(&t), "unexpected %s after the last face", mio__excerpt(&t, ex, sizeof ex));
    }
    return MIO_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: PLY reader
   --------------------------------------------------------------------------------------------- */

enum { MIO__PLY_ASCII, MIO__PLY_LE, MIO__PLY_BE };
enum { MIO__T_NONE, MIO__T_I8, MIO__T_U8, MIO__T_I16, MIO__T_U16, MIO__T_I32, MIO__T_U32, MIO__T_F32, MIO__T_F64 };
enum { MIO__ROLE_SKIP, MIO__ROLE_X, MIO__ROLE_Y, MIO__ROLE_Z, MIO__ROLE_FACE };
enum { MIO__ELEM_OTHER, MIO__ELEM_VERTEX, MIO__ELEM_FACE };

typedef struct mio__ply_prop {
    unsigned char type;       /* scalar type, or the list's item type */
    unsigned char count_type; /* MIO__T_NONE for a scalar */
    unsigned char role;
} mio__ply_prop;

typedef struct mio__ply_elem {
    unsigned long long count;
    size_t first_prop, prop_count;
    int kind;
    size_t line; /* header line, for messages */
} mio__ply_elem;

typedef struct mio__ply {
    int format;
    mio__ply_elem *elems;
    size_t elem_count;
    mio__ply_prop *props;
    size_t prop_count;
    size_t vertex_elem, face_elem; /* (size_t)-1 if absent */
} mio__ply;

static const unsigned char mio__ply_size[9] = { 0, 1, 1, 2, 2, 4, 4, 4, 8 };

static int mio__ply_type(const unsigned char *p, size_t n)
{
    static const char *const names[16] = { "char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                            "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64" };
    int k;
    for (k = 0; k < 16; k++)
        if (strlen(names[k]) == n && memcmp(names[k], p, n) == 0) return (k % 8) + 1;
    return MIO__T_NONE;
}

static int mio__ply_is_int(int type) { return type >= MIO__T_I8 && type <= MIO__T_U32; }

/* Splits a header line into up to 6 words; returns the word count (more words are counted but
   not stored). */
static size_t mio__words(const unsigned char *p, const unsigned char *end, const unsigned char **w, size_t *wl)
{
    size_t n = 0;
    for (;;) {
        while (p < end && mio__is_space(*p)) p++;
        if (p >= end) return n;
        if (n < 6) w[n] = p;
        while (p < end && !mio__is_space(*p)) p++;
        if (n < 6) wl[n] = (size_t)(p - w[n]);
        n++;
    }
}

static int mio__word_is(const unsigned char *w, size_t n, const char *s) { return strlen(s) == n && memcmp(w, s, n) == 0; }

#define MIO__HERR(code, ...) mio__fail(c, code, line, (size_t)(ls - c->data), __VA_ARGS__)

/* the header's "element" and "property" lines up to end_header, counted so that the tables
   are sized by the header's bytes (>= 9 bytes per entry) */
static void mio__ply_count_lines(const unsigned char *p, const unsigned char *end, size_t *elem_lines, size_t *prop_lines)
{
    const unsigned char *q;
    *elem_lines = *prop_lines = 0;
    for (q = p; q < end;) {
        const unsigned char *ls = q, *w[6];
        size_t wl[6];
        while (q < end && *q != '\n') q++;
        if (mio__words(ls, q, w, wl) > 0) {
            if (mio__word_is(w[0], wl[0], "end_header")) break;
            if (mio__word_is(w[0], wl[0], "element")) (*elem_lines)++;
            if (mio__word_is(w[0], wl[0], "property")) (*prop_lines)++;
        }
        if (q < end) q++;
    }
}

/* a "format" line of n words w at line `line` starting at ls */
static mio_result mio__ply_format_line(mio__ctx *c, mio__ply *ply, const unsigned char **w, const size_t *wl, size_t n,
                                       size_t line, const unsigned char *ls)
{
    if (n < 2) return MIO__HERR(MIO_ERR_SYNTAX, "format line needs a format name");
    if (mio__word_is(w[1], wl[1], "ascii")) ply->format = MIO__PLY_ASCII;
    else if (mio__word_is(w[1], wl[1], "binary_little_endian")) ply->format = MIO__PLY_LE;
    else if (mio__word_is(w[1], wl[1], "binary_big_endian")) ply->format = MIO__PLY_BE;
    else return MIO__HERR(MIO_ERR_UNSUPPORTED, "unknown PLY format");
    return MIO_OK;
}

/* an "element NAME COUNT" line: the next element (the first "vertex" and "face" ones are the mesh's) */
static mio_result mio__ply_element_line(mio__ctx *c, mio__ply *ply, const unsigned char **w, const size_t *wl, size_t n,
                                        size_t elem_lines, size_t line, const unsigned char *ls)
{
    mio__ply_elem *e = &ply->elems[ply->elem_count];
    long long count = 0;
    int overflow = 0;
    if (ply->elem_count >= elem_lines) return MIO__HERR(MIO_ERR_SYNTAX, "header changed while parsing");
    if (n != 3) return MIO__HERR(MIO_ERR_SYNTAX, "element line needs a name and a count");
    if (mio__parse_int(w[2], w[2] + wl[2], &count, &overflow) != wl[2] || count < 0)
        return MIO__HERR(MIO_ERR_SYNTAX, "bad element count");
    if (overflow) return MIO__HERR(MIO_ERR_TOO_LARGE, "element count too large");
    e->count = (unsigned long long)count;
    e->first_prop = ply->prop_count;
    e->prop_count = 0;
    e->line = line;
    e->kind = MIO__ELEM_OTHER;
    if (mio__word_is(w[1], wl[1], "vertex") && ply->vertex_elem == (size_t)-1) {
        e->kind = MIO__ELEM_VERTEX;
        ply->vertex_elem = ply->elem_count;
    } else if (mio__word_is(w[1], wl[1], "face") && ply->face_elem == (size_t)-1) {
        e->kind = MIO__ELEM_FACE;
        ply->face_elem = ply->elem_count;
    }
    ply->elem_count++;
    return MIO_OK;
}

/* "property list COUNT_TYPE TYPE NAME" of element e: the face's first vertex_indices (or
   vertex_index) list is the faces' role */
static mio_result mio__ply_list_property(mio__ctx *c, const mio__ply *ply, const mio__ply_elem *e, mio__ply_prop *pr,
                                         const unsigned char **w, const size_t *wl, size_t n, size_t line,
                                         const unsigned char *ls)
{
    size_t k;
    int seen = 0;
    if (n != 5) return MIO__HERR(MIO_ERR_SYNTAX, "list property needs count type, item type and name");
    pr->count_type = (unsigned char)mio__ply_type(w[2], wl[2]);
    pr->type = (unsigned char)mio__ply_type(w[3], wl[3]);
    if (pr->count_type == MIO__T_NONE || pr->type == MIO__T_NONE) return MIO__HERR(MIO_ERR_UNSUPPORTED, "unknown property type");
    if (!mio__ply_is_int(pr->count_type)) return MIO__HERR(MIO_ERR_UNSUPPORTED, "list count type must be an integer type");
    if (e->kind != MIO__ELEM_FACE || !(mio__word_is(w[4], wl[4], "vertex_indices") || mio__word_is(w[4], wl[4], "vertex_index")))
        return MIO_OK;
    for (k = 0; k < e->prop_count; k++) if (ply->props[e->first_prop + k].role == MIO__ROLE_FACE) seen = 1;
    if (seen) return MIO_OK;
    if (!mio__ply_is_int(pr->type)) return MIO__HERR(MIO_ERR_UNSUPPORTED, "face index type must be an integer type");
    pr->role = MIO__ROLE_FACE;
    return MIO_OK;
}

/* "property TYPE NAME" of element e: the vertex's x, y and z are the positions' roles */
static mio_result mio__ply_scalar_property(mio__ctx *c, const mio__ply *ply, const mio__ply_elem *e, mio__ply_prop *pr,
                                           const unsigned char **w, const size_t *wl, size_t n, size_t line,
                                           const unsigned char *ls)
{
    const unsigned char *name = w[2];
    size_t k;
    int role;
    if (n != 3) return MIO__HERR(MIO_ERR_SYNTAX, "property line needs a type and a name");
    pr->count_type = MIO__T_NONE;
    pr->type = (unsigned char)mio__ply_type(w[1], wl[1]);
    if (pr->type == MIO__T_NONE) return MIO__HERR(MIO_ERR_UNSUPPORTED, "unknown property type");
    if (e->kind != MIO__ELEM_VERTEX || wl[2] != 1 || !(*name == 'x' || *name == 'y' || *name == 'z')) return MIO_OK;
    role = MIO__ROLE_X + (*name - 'x');
    for (k = 0; k < e->prop_count; k++)
        if (ply->props[e->first_prop + k].role == role) return MIO__HERR(MIO_ERR_SYNTAX, "duplicate vertex property");
    pr->role = (unsigned char)role;
    return MIO_OK;
}

/* a "property" line: the next property of the last element */
static mio_result mio__ply_property_line(mio__ctx *c, mio__ply *ply, const unsigned char **w, const size_t *wl, size_t n,
                                         size_t prop_lines, size_t line, const unsigned char *ls)
{
    mio__ply_prop *pr = &ply->props[ply->prop_count];
    mio__ply_elem *e;
    mio_result r;
    if (ply->elem_count == 0) return MIO__HERR(MIO_ERR_SYNTAX, "property before any element");
    if (ply->prop_count >= prop_lines) return MIO__HERR(MIO_ERR_SYNTAX, "header changed while parsing");
    e = &ply->elems[ply->elem_count - 1];
    pr->role = MIO__ROLE_SKIP;
    r = n >= 2 && mio__word_is(w[1], wl[1], "list") ? mio__ply_list_property(c, ply, e, pr, w, wl, n, line, ls)
                                                     : mio__ply_scalar_property(c, ply, e, pr, w, wl, n, line, ls);
    if (r != MIO_OK) return r;
    e->prop_count++;
    ply->prop_count++;
    return MIO_OK;
}

/* Parses the header up to and including the "end_header" line. On success *body is the first
   byte of the data and *body_line its line number. */
static mio_result mio__ply_header(mio__ctx *c, mio__ply *ply, const unsigned char **body, size_t *body_line)
{
    const unsigned char *p = c->data, *end = c->data + c->size;
    size_t line = 1, elem_lines, prop_lines;
    int have_format = 0;
    ply->vertex_elem = ply->face_elem = (size_t)-1;
    if (c->size < 4 || memcmp(p, "ply", 3) != 0 || (p[3] != '\n' && p[3] != '\r'))
        return mio__fail(c, MIO_ERR_SYNTAX, 1, 0, "missing 'ply' magic line");
    mio__ply_count_lines(p, end, &elem_lines, &prop_lines);
    ply->elems = (mio__ply_elem *)mio__alloc(c, (elem_lines + 1) * sizeof *ply->elems);
    ply->props = (mio__ply_prop *)mio__alloc(c, (prop_lines + 1) * sizeof *ply->props);
    if (!ply->elems || !ply->props) return mio__oom(c, 1, 0);
    while (p < end && *p != '\n') p++;
    for (;;) {
        const unsigned char *ls, *w[6];
        size_t wl[6], n;
        mio_result r = MIO_OK;
        if (p >= end) return mio__fail(c, MIO_ERR_TRUNCATED, line, (size_t)(p - c->data), "header ends without end_header");
        p++; /* past '\n' */
        line++;
        ls = p;
        while (p < end && *p != '\n') p++;
        n = mio__words(ls, p, w, wl);
        if (n == 0) continue;
        if (mio__word_is(w[0], wl[0], "end_header")) {
            *body = p >= end ? end : p + 1;
            *body_line = line + 1;
            break;
        }
        if (mio__word_is(w[0], wl[0], "format")) {
            r = mio__ply_format_line(c, ply, w, wl, n, line, ls);
            have_format = 1;
        } else if (mio__word_is(w[0], wl[0], "element")) {
            r = mio__ply_element_line(c, ply, w, wl, n, elem_lines, line, ls);
        } else if (mio__word_is(w[0], wl[0], "property")) {
            r = mio__ply_property_line(c, ply, w, wl, n, prop_lines, line, ls);
        } /* "comment", "obj_info" and lines with unknown keywords are ignored */
        if (r != MIO_OK) return r;
    }
    if (!have_format) return mio__fail(c, MIO_ERR_SYNTAX, 2, 0, "missing format line");
    return MIO_OK;
}
#undef MIO__HERR

/* Checks the header counts against the bytes present, before anything is allocated. */
static mio_result mio__ply_check_sizes(mio__ctx *c, const mio__ply *ply, size_t remaining, size_t line, size_t at)
{
    unsigned long long total = 0; /* bytes (binary) or tokens (ascii) needed at least */
    size_t e, k;
    if (ply->vertex_elem != (size_t)-1) {
        const mio__ply_elem *v = &ply->elems[ply->vertex_elem];
        int have[3] = { 0, 0, 0 };
        for (k = 0; k < v->prop_count; k++) {
            const mio__ply_prop *pr = &ply->props[v->first_prop + k];
            if (pr->role >= MIO__ROLE_X && pr->role <= MIO__ROLE_Z) {
                if (pr->count_type != MIO__T_NONE) return mio__fail(c, MIO_ERR_SYNTAX, v->line, 0, "x, y, z must not be lists");
                have[pr->role - MIO__ROLE_X] = 1;
            }
        }
        if (!have[0] || !have[1] || !have[2]) return mio__fail(c, MIO_ERR_SYNTAX, v->line, 0, "element vertex lacks x, y or z");
        if (v->count > UINT32_MAX) return mio__fail(c, MIO_ERR_TOO_LARGE, v->line, 0, "%llu vertices is more than %lu", v->count, (unsigned long)UINT32_MAX);
    }
    if (ply->face_elem != (size_t)-1) {
        const mio__ply_elem *f = &ply->elems[ply->face_elem];
        int have = 0;
        for (k = 0; k < f->prop_count; k++) if (ply->props[f->first_prop + k].role == MIO__ROLE_FACE) have = 1;
        if (!have && f->count) return mio__fail(c, MIO_ERR_SYNTAX, f->line, 0, "element face lacks a vertex_indices list");
    }
    for (e = 0; e < ply->elem_count; e++) {
        const mio__ply_elem *el = &ply->elems[e];
        unsigned long long per = 0;
        for (k = 0; k < el->prop_count; k++) {
            const mio__ply_prop *pr = &ply->props[el->first_prop + k];
            int is_list = pr->count_type != MIO__T_NONE;
            if (ply->format == MIO__PLY_ASCII) per += (unsigned long long)(pr->role == MIO__ROLE_FACE ? 4 : 1);
            else if (!is_list) per += mio__ply_size[pr->type];
            else per += mio__ply_size[pr->count_type] + (pr->role == MIO__ROLE_FACE ? 3u * mio__ply_size[pr->type] : 0u);
        }
        if (per && el->count > (~0ull - total) / per)
            return mio__fail(c, MIO_ERR_TRUNCATED, el->line, 0, "element counts need more bytes than exist");
        total += per * el->count;
    }
    if (ply->format == MIO__PLY_ASCII ? (total > 0 && total - 1 > (unsigned long long)remaining / 2) : total > (unsigned long long)remaining)
        return mio__fail(c, MIO_ERR_TRUNCATED, line, at, "header counts need at least %llu %s but only %llu bytes follow",
                         total, ply->format == MIO__PLY_ASCII ? "values" : "bytes", (unsigned long long)remaining);
    return MIO_OK;
}

static uint32_t mio__load32(const unsigned char *p, int big_endian)
{
    if (big_endian) return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | (uint32_t)p[3];
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint16_t mio__load16(const unsigned char *p, int big_endian)
{
    return (uint16_t)(big_endian ? (p[0] << 8) | p[1] : p[0] | (p[1] << 8));
}

/* Loads one binary scalar as a double (integers are exact). Non-finite floats come back as
   infinity, which mio__to_float rejects. */
static double mio__ply_load(const unsigned char *p, int type, int big_endian)
{
    switch (type) {
    case MIO__T_I8: return (double)(int8_t)p[0];
    case MIO__T_U8: return (double)p[0];
    case MIO__T_I16: return (double)(int16_t)mio__load16(p, big_endian);
    case MIO__T_U16: return (double)mio__load16(p, big_endian);
    case MIO__T_I32: return (double)(int32_t)mio__load32(p, big_endian);
    case MIO__T_U32: return (double)mio__load32(p, big_endian);
    case MIO__T_F32: {
        uint32_t u = mio__load32(p, big_endian);
        float f;
        if ((u & 0x7F800000u) == 0x7F800000u) return DBL_MAX * 2.0;
        memcpy(&f, &u, 4);
        return (double)f;
    }
    default: {
        uint64_t u = big_endian ? ((uint64_t)mio__load32(p, 1) << 32) | mio__load32(p + 4, 1)
                                : ((uint64_t)mio__load32(p + 4, 0) << 32) | mio__load32(p, 0);
        double d;
        if ((u & 0x7FF0000000000000ull) == 0x7FF0000000000000ull) return DBL_MAX * 2.0;
        memcpy(&d, &u, 8);
        return d;
    }
    }
}

/* Reads one face index list of n items (binary); emits its fan. */
static mio_result mio__ply_bin_face(mio__ctx *c, const unsigned char **pp, const unsigned char *end, const mio__ply_prop *pr,
                                    int be, unsigned long long nv)
{
    const unsigned char *p = *pp;
    size_t isz = mio__ply_size[pr->type], csz = mio__ply_size[pr->count_type], at = (size_t)(p - c->data);
    double count;
    size_t n, j;
    uint32_t fan[2] = { 0, 0 };
    if ((size_t)(end - p) < csz) return mio__fail(c, MIO_ERR_TRUNCATED, 0, at, "data ends inside a face");
    count = mio__ply_load(p, pr->count_type, be);
    p += csz;
    if (count < 3) return mio__fail(c, MIO_ERR_SYNTAX, 0, at, "face has %lld vertices; at least 3 are needed", (long long)count);
    n = (size_t)count;
    if (n > (size_t)(end - p) / isz) return mio__fail(c, MIO_ERR_TRUNCATED, 0, at, "data ends inside a face");
    for (j = 0; j < n; j++, p += isz) {
        double v = mio__ply_load(p, pr->type, be);
        mio_result r;
        if (v < 0 || v >= (double)nv)
            return mio__fail(c, MIO_ERR_INDEX_RANGE, 0, (size_t)(p - c->data), "face vertex index %.0f out of range (%llu vertices)", v, nv);
        if ((r = mio__fan(c, fan, j, (uint32_t)v, 0, (size_t)(p - c->data))) != MIO_OK) return r;
    }
    *pp = p;
    return MIO_OK;
}

static mio_result mio__ply_binary(mio__ctx *c, const mio__ply *ply, const unsigned char *p, unsigned long long nv)
{
    const unsigned char *end = c->data + c->size;
    int be = ply->format == MIO__PLY_BE;
    size_t e, k;
    mio_result r;
    for (e = 0; e < ply->elem_count; e++) {
        const mio__ply_elem *el = &ply->elems[e];
        const mio__ply_prop *props = ply->props + el->first_prop;
        size_t fixed = 0;
        int has_list = 0;
        unsigned long long i;
        for (k = 0; k < el->prop_count; k++) {
            if (props[k].count_type != MIO__T_NONE) has_list = 1;
            else fixed += mio__ply_size[props[k].type];
        }
        if (!has_list && el->kind != MIO__ELEM_VERTEX) { /* skip the whole element at once */
            if (el->count && fixed > (size_t)(end - p) / el->count) return mio__fail(c, MIO_ERR_TRUNCATED, 0, (size_t)(p - c->data), "data ends inside an element");
            p += fixed * (size_t)el->count;
            continue;
        }
        for (i = 0; i < el->count; i++) {
            float xyz[3] = { 0, 0, 0 };
            for (k = 0; k < el->prop_count; k++) {
                const mio__ply_prop *pr = &props[k];
                size_t at = (size_t)(p - c->data);
                if (pr->role == MIO__ROLE_FACE && el->kind == MIO__ELEM_FACE) {
                    if ((r = mio__ply_bin_face(c, &p, end, pr, be, nv)) != MIO_OK) return r;
                } else if (pr->count_type != MIO__T_NONE) {
                    size_t csz = mio__ply_size[pr->count_type], isz = mio__ply_size[pr->type];
                    double count;
                    if ((size_t)(end - p) < csz) return mio__fail(c, MIO_ERR_TRUNCATED, 0, at, "data ends inside a list");
                    count = mio__ply_load(p, pr->count_type, be);
                    p += csz;
                    if (count < 0) return mio__fail(c, MIO_ERR_SYNTAX, 0, at, "negative list count");
                    if ((size_t)count > (size_t)(end - p) / isz) return mio__fail(c, MIO_ERR_TRUNCATED, 0, at, "data ends inside a list");
                    p += (size_t)count * isz;
                } else {
                    size_t sz = mio__ply_size[pr->type];
                    if ((size_t)(end - p) < sz) return mio__fail(c, MIO_ERR_TRUNCATED, 0, at, "data ends inside an element");
                    if (pr->role >= MIO__ROLE_X && pr->role <= MIO__ROLE_Z && el->kind == MIO__ELEM_VERTEX) {
                        if (!mio__to_float(mio__ply_load(p, pr->type, be), &xyz[pr->role - MIO__ROLE_X]))
                            return mio__fail(c, MIO_ERR_SYNTAX, 0, at, "coordinate is not a finite float");
                    }
                    p += sz;
                }
            }
            if (el->kind == MIO__ELEM_VERTEX) memcpy(c->pos + 3 * c->vertex_count++, xyz, sizeof xyz);
        }
    }
    if (p != end) return mio__fail(c, MIO_ERR_SYNTAX, 0, (size_t)(p - c->data), "%llu unexpected bytes after the last element", (unsigned long long)(end - p));
    return MIO_OK;
}

static mio_result mio__ply_ascii(mio__ctx *c, const mio__ply *ply, const unsigned char *p, size_t line, unsigned long long nv)
{
    mio__text t;
    size_t e, k;
    mio_result r;
    t.c = c;
    t.p = p;
    t.end = c->data + c->size;
    t.line = line;
    for (e = 0; e < ply->elem_count; e++) {
        const mio__ply_elem *el = &ply->elems[e];
        const mio__ply_prop *props = ply->props + el->first_prop;
        unsigned long long i;
        if (el->prop_count == 0) continue;
        for (i = 0; i < el->count; i++) {
            float xyz[3] = { 0, 0, 0 };
            for (k = 0; k < el->prop_count; k++) {
                const mio__ply_prop *pr = &props[k];
                mio__skip_space(&t, 0);
                if (pr->count_type != MIO__T_NONE) {
                    long long count = 0, j;
                    size_t line0 = t.line, at = mio__off(&t);
                    int face = pr->role == MIO__ROLE_FACE && el->kind == MIO__ELEM_FACE;
                    uint32_t fan[2] = { 0, 0 };
                    if ((r = mio__read_int(&t, &count, "a list count")) != MIO_OK) return r;
                    if (count < 0) return mio__fail(c, MIO_ERR_SYNTAX, line0, at, "negative list count");
                    if (face && count < 3) return mio__fail(c, MIO_ERR_SYNTAX, line0, at, "face has %lld vertices; at least 3 are needed", count);
                    if ((unsigned long long)count > (unsigned long long)(t.end - t.p))
                        return mio__fail(c, MIO_ERR_TRUNCATED, line0, at, "list claims %lld items, more than the bytes left", count);
                    for (j = 0; j < count; j++) {
                        mio__skip_space(&t, 0);
                        if (face) {
                            long long v = 0;
                            if ((r = mio__read_int(&t, &v, "a face vertex index")) != MIO_OK) return r;
                            if (v < 0 || (unsigned long long)v >= nv)
                                return mio__fail(c, MIO_ERR_INDEX_RANGE, t.line, mio__off(&t), "face vertex index %lld out of range (%llu vertices)", v, nv);
                            if ((r = mio__fan(c, fan, (size_t)j, (uint32_t)v, t.line, mio__off(&t))) != MIO_OK) return r;
                        } else {
                            size_t n = mio__token_len(&t);
                            if (n == 0) return mio__fail(c, MIO_ERR_TRUNCATED, t.line, mio__off(&t), "data ends inside a list");
                            t.p += n;
                        }
                    }
                } else if (pr->role >= MIO__ROLE_X && pr->role <= MIO__ROLE_Z && el->kind == MIO__ELEM_VERTEX) {
                    if ((r = mio__read_coord(&t, &xyz[pr->role - MIO__ROLE_X], "coordinate")) != MIO_OK) return r;
                } else {
                    size_t n = mio__token_len(&t);
                    if (n == 0) {
                        if (t.p >= t.end) return mio__fail(c, MIO_ERR_TRUNCATED, t.line, mio__off(&t), "data ends inside element %llu", i);
                        return mio__fail(c, MIO_ERR_SYNTAX, t.line, mio__off(&t), "unexpected '#'");
                    }
                    t.p += n;
                }
            }
            if (el->kind == MIO__ELEM_VERTEX) memcpy(c->pos + 3 * c->vertex_count++, xyz, sizeof xyz);
        }
    }
    mio__skip_space(&t, 0);
    if (t.p < t.end) {
        char ex[40];
        return mio__fail(c, MIO_ERR_SYNTAX, t.line, mio__off(&t), "unexpected %s after the last element", mio__excerpt(&t, ex, sizeof ex));
    }
    return MIO_OK;
}

static mio_result mio__read_ply(mio__ctx *c)
{
    mio__ply ply;
    const unsigned char *body = NULL;
    size_t body_line = 0;
    unsigned long long nv = 0, nf = 0;
    mio_result r;
    memset(&ply, 0, sizeof ply);
    r = mio__ply_header(c, &ply, &body, &body_line);
    if (r == MIO_OK)
        r = mio__ply_check_sizes(c, &ply, (size_t)(c->data + c->size - body), ply.format == MIO__PLY_ASCII ? body_line : 0, (size_t)(body - c->data));
    if (r == MIO_OK) {
        if (ply.vertex_elem != (size_t)-1) nv = ply.elems[ply.vertex_elem].count;
        if (ply.face_elem != (size_t)-1) nf = ply.elems[ply.face_elem].count;
        r = mio__reserve_vertices(c, (size_t)nv, 0, 0);
    }
    if (r == MIO_OK) r = mio__reserve_triangles(c, (size_t)nf, 0, 0);
    if (r == MIO_OK)
        r = ply.format == MIO__PLY_ASCII ? mio__ply_ascii(c, &ply, body, body_line, nv) : mio__ply_binary(c, &ply, body, nv);
    mio__free(c, ply.elems);
    mio__free(c, ply.props);
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Section: STL reader
   --------------------------------------------------------------------------------------------- */

static uint32_t mio__le32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* True if the data is exactly 84 + 50 * count bytes long. */
static int mio__stl_binary_size_ok(const unsigned char *d, size_t size)
{
    uint64_t count;
    if (size < 84) return 0;
    count = mio__le32(d + 80);
    return (uint64_t)(size - 84) == count * 50u;
}

/* True if the first token (after whitespace / UTF-8 BOM) is "solid" in any case. */
static int mio__starts_with_solid(const unsigned char *d, size_t size)
{
    size_t i = 0, k;
    if (size >= 3 && d[0] == 0xEF && d[1] == 0xBB && d[2] == 0xBF) i = 3;
    while (i < size && (mio__is_space(d[i]) || d[i] == '\n')) i++;
    if (size - i < 5) return 0;
    for (k = 0; k < 5; k++) if (mio__lower(d[i + k]) != "solid"[k]) return 0;
    return i + 5 == size || mio__is_space(d[i + 5]) || d[i + 5] == '\n';
}

static mio_result mio__stl_binary(mio__ctx *c)
{
    size_t n = mio__le32(c->data + 80), i;
    const unsigned char *p = c->data + 84;
    mio_result r;
    if (n > (size_t)UINT32_MAX / 3) return mio__fail(c, MIO_ERR_TOO_LARGE, 0, 80, "too many facets");
    if ((r = mio__reserve_vertices(c, n * 3, 0, 80)) != MIO_OK) return r;
    if ((r = mio__reserve_triangles(c, n, 0, 80)) != MIO_OK) return r;
    for (i = 0; i < n; i++, p += 50) {
        int k;
        for (k = 0; k < 9; k++) {
            uint32_t u = mio__le32(p + 12 + 4 * k);
            if ((u & 0x7F800000u) == 0x7F800000u)
                return mio__fail(c, MIO_ERR_SYNTAX, 0, (size_t)(p + 12 + 4 * k - c->data), "non-finite coordinate in facet %llu", (unsigned long long)i);
            memcpy(c->pos + 9 * i + k, &u, 4);
        }
        c->idx[3 * i] = (uint32_t)(3 * i);
        c->idx[3 * i + 1] = (uint32_t)(3 * i + 1);
        c->idx[3 * i + 2] = (uint32_t)(3 * i + 2);
    }
    c->vertex_count = 3 * n;
    c->triangle_count = n;
    return MIO_OK;
}

/* Expects the keyword at the cursor (any case) and moves past it. */
static mio_result mio__stl_expect(mio__text *t, const char *word)
{
    char ex[40];
    mio__skip_space(t, 0);
    if (mio__token_is(t, word, 1)) { t->p += strlen(word); return MIO_OK; }
    if (t->p >= t->end) return mio__fail(t->c, MIO_ERR_TRUNCATED, t->line, mio__off(t), "data ends where '%s' was expected", word);
    return mio__fail(t->c, MIO_ERR_SYNTAX, t->line, mio__off(t), "expected '%s', found %s", word, mio__excerpt(t, ex, sizeof ex));
}

static mio_result mio__stl_ascii(mio__ctx *c)
{
    mio__text t;
    mio_result r;
    t.c = c;
    t.p = c->data;
    t.end = c->data + c->size;
    t.line = 1;
    if ((r = mio__text_start(&t)) != MIO_OK) return r;
    for (;;) { /* one solid per iteration */
        if ((r = mio__stl_expect(&t, "solid")) != MIO_OK) return r;
        mio__next_line(&t, 0); /* the name */
        for (;;) {
            int k, d;
            float tri[9];
            size_t line, at;
            mio__skip_space(&t, 0);
            if (mio__token_is(&t, "endsolid", 1)) { mio__next_line(&t, 0); break; }
            line = t.line;
            at = mio__off(&t);
            if ((r = mio__stl_expect(&t, "facet")) != MIO_OK) return r;
            if ((r = mio__stl_expect(&t, "normal")) != MIO_OK) return r;
            for (k = 0; k < 3; k++) { /* the normal is not used; exporters write nan there */
                mio__skip_blanks(&t, 0);
                if (mio__at_eol(&t)) return mio__fail(c, t.p >= t.end ? MIO_ERR_TRUNCATED : MIO_ERR_SYNTAX, t.line, mio__off(&t), "facet normal needs 3 values");
                t.p += mio__token_len(&t);
            }
            if ((r = mio__stl_expect(&t, "outer")) != MIO_OK) return r;
            if ((r = mio__stl_expect(&t, "loop")) != MIO_OK) return r;
            for (k = 0; k < 3; k++) {
                if ((r = mio__stl_expect(&t, "vertex")) != MIO_OK) return r;
                for (d = 0; d < 3; d++) {
                    mio__skip_space(&t, 0);
                    if ((r = mio__read_coord(&t, &tri[3 * k + d], "coordinate")) != MIO_OK) return r;
                }
            }
            if ((r = mio__stl_expect(&t, "endloop")) != MIO_OK) return r;
            if ((r = mio__stl_expect(&t, "endfacet")) != MIO_OK) return r;
            if (c->vertex_count > (size_t)UINT32_MAX - 3) return mio__fail(c, MIO_ERR_TOO_LARGE, line, at, "too many facets");
            for (k = 0; k < 3; k++)
                if ((r = mio__push_vertex(c, tri + 3 * k, line, at)) != MIO_OK) return r;
            r = mio__push_triangle(c, (uint32_t)(c->vertex_count - 3), (uint32_t)(c->vertex_count - 2), (uint32_t)(c->vertex_count - 1), line, at);
            if (r != MIO_OK) return r;
        }
        mio__skip_space(&t, 0);
        if (t.p >= t.end) return MIO_OK;
    }
}

static mio_result mio__read_stl(mio__ctx *c)
{
    if (mio__stl_binary_size_ok(c->data, c->size)) return mio__stl_binary(c);
    if (mio__starts_with_solid(c->data, c->size)) return mio__stl_ascii(c);
    if (c->size < 84) return mio__fail(c, MIO_ERR_TRUNCATED, 0, 0, "binary STL needs at least 84 bytes, found %llu", (unsigned long long)c->size);
    {
        unsigned long long count = mio__le32(c->data + 80), need = 84 + 50 * count;
        return mio__fail(c, need > c->size ? MIO_ERR_TRUNCATED : MIO_ERR_SYNTAX, 0, 80,
                         "binary STL header claims %llu facets (%llu bytes), the data has %llu bytes", count, need, (unsigned long long)c->size);
    }
}

/* ---------------------------------------------------------------------------------------------
   Section: format detection
   --------------------------------------------------------------------------------------------- */

static int mio__ext_is(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext), k;
    if (n < e + 1 || path[n - e - 1] != '.') return 0;
    for (k = 0; k < e; k++) if (mio__lower((unsigned char)path[n - e + k]) != ext[k]) return 0;
    return 1;
}

/* First content line of a text file, skipping blank and '#' lines: returns its start. */
static size_t mio__first_statement(const unsigned char *d, size_t size)
{
    size_t i = 0;
    if (size >= 3 && d[0] == 0xEF && d[1] == 0xBB && d[2] == 0xBF) i = 3;
    for (;;) {
        while (i < size && (mio__is_space(d[i]) || d[i] == '\n')) i++;
        if (i < size && d[i] == '#') { while (i < size && d[i] != '\n') i++; continue; }
        return i;
    }
}

MIODEF mio_format mio_detect_format(const void *data, size_t size, const char *path_or_null)
{
    const unsigned char *d = (const unsigned char *)data;
    size_t i, n;
    if (!d) size = 0;
    if (mio__stl_binary_size_ok(d, size)) return MIO_FORMAT_STL;
    if (size >= 4 && memcmp(d, "ply", 3) == 0 && (d[3] == '\n' || d[3] == '\r')) return MIO_FORMAT_PLY;
    i = mio__first_statement(d, size);
    for (n = 0; i + n < size && !mio__is_space(d[i + n]) && d[i + n] != '\n'; n++) {}
    if (n >= 3 && n <= 8 && memcmp(d + i + n - 3, "OFF", 3) == 0) {
        size_t k = 0;
        if (n >= 5 && d[i] == 'S' && d[i + 1] == 'T') k = 2;
        while (k < n - 3 && (d[i + k] == 'C' || d[i + k] == 'N' || d[i + k] == '4' || d[i + k] == 'n')) k++;
        if (k == n - 3) return MIO_FORMAT_OFF;
    }
    if (mio__starts_with_solid(d, size)) return MIO_FORMAT_STL;
    if (path_or_null) {
        if (mio__ext_is(path_or_null, "obj")) return MIO_FORMAT_OBJ;
        if (mio__ext_is(path_or_null, "off")) return MIO_FORMAT_OFF;
        if (mio__ext_is(path_or_null, "ply")) return MIO_FORMAT_PLY;
        if (mio__ext_is(path_or_null, "stl")) return MIO_FORMAT_STL;
    }
    {
        static const char *const keywords[] = { "v", "vt", "vn", "vp", "f", "l", "p", "g", "o", "s", "usemtl", "mtllib" };
        size_t k;
        for (k = 0; k < sizeof keywords / sizeof keywords[0]; k++)
            if (strlen(keywords[k]) == n && memcmp(keywords[k], d + i, n) == 0) return MIO_FORMAT_OBJ;
    }
    return MIO_FORMAT_AUTO;
}

/* ---------------------------------------------------------------------------------------------
   Section: public read entry points
   --------------------------------------------------------------------------------------------- */

static void mio__clear_error(mio_error *err)
{
    err->code = MIO_OK;
    err->line = 0;
    err->offset = 0;
    err->message[0] = '\0';
}

static mio_result mio__set_error(mio_error *err, mio_result code, const char *fmt, ...)
{
    va_list ap;
    if (!err) return code;
    err->code = code;
    err->line = 0;
    err->offset = 0;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return code;
}

static mio_result mio__read(const unsigned char *data, size_t size, const char *path, const mio_read_options *opt,
                            const mio_allocator *alloc, mio_mesh *out, mio_error *err)
{
    mio__ctx c;
    mio_format format = opt ? opt->format : MIO_FORMAT_AUTO;
    mio_result r;
    memset(&c, 0, sizeof c);
    c.data = data;
    c.size = size;
    c.alloc = *alloc;
    c.err = err;
    if (size == 0) return mio__fail(&c, MIO_ERR_EMPTY, 0, 0, "input is empty");
    if (format == MIO_FORMAT_AUTO) format = mio_detect_format(data, size, path);
    switch (format) {
    case MIO_FORMAT_OBJ: r = mio__read_obj(&c); break;
    case MIO_FORMAT_OFF: r = mio__read_off(&c); break;
    case MIO_FORMAT_PLY: r = mio__read_ply(&c); break;
    case MIO_FORMAT_STL: r = mio__read_stl(&c); break;
    default: return mio__fail(&c, MIO_ERR_UNKNOWN_FORMAT, 0, 0, "cannot tell the file format");
    }
    if (r == MIO_OK && c.triangle_count == 0)
        r = mio__fail(&c, MIO_ERR_EMPTY, 0, size, "no triangles (%llu vertices)", (unsigned long long)c.vertex_count);
    if (r != MIO_OK) {
        mio__discard(&c);
        return r;
    }
    out->positions = c.pos;
    out->vertex_count = c.vertex_count;
    out->indices = c.idx;
    out->triangle_count = c.triangle_count;
    out->allocator = c.alloc;
    return MIO_OK;
}

/* Resolves options and arguments common to both readers. */
static mio_result mio__begin(const mio_read_options *opt, mio_mesh *out, mio_error *err, mio_allocator *alloc)
{
    if (err) mio__clear_error(err);
    if (out) memset(out, 0, sizeof *out);
    if (!out) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "out is NULL");
    alloc->alloc = mio__default_alloc;
    alloc->free = mio__default_free;
    alloc->user = NULL;
    if (opt && opt->allocator) {
        if (!opt->allocator->alloc || !opt->allocator->free)
            return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "allocator lacks alloc or free");
        *alloc = *opt->allocator;
    }
    if (opt && ((int)opt->format < (int)MIO_FORMAT_AUTO || (int)opt->format > (int)MIO_FORMAT_STL))
        return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "unknown format option");
    return MIO_OK;
}

MIODEF mio_result mio_read_memory(const void *data, size_t size, const mio_read_options *opt, mio_mesh *out, mio_error *err)
{
    mio_allocator alloc;
    mio_error local;
    mio_result r = mio__begin(opt, out, err, &alloc);
    if (r != MIO_OK) return r;
    if (!data && size) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "data is NULL");
    return mio__read((const unsigned char *)data, size, NULL, opt, &alloc, out, err ? err : &local);
}

MIODEF mio_result mio_read_file(const char *path, const mio_read_options *opt, mio_mesh *out, mio_error *err)
{
    mio_allocator alloc;
    mio_error local;
    mio_result r = mio__begin(opt, out, err, &alloc);
    FILE *f;
    unsigned char *buf = NULL;
    size_t size = 0, cap = 0;
    if (r != MIO_OK) return r;
    if (!path) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "path is NULL");
    f = fopen(path, "rb");
    if (!f) return mio__set_error(err, MIO_ERR_IO, "cannot open %.140s", path);
    /* a directory opens fine on some systems but fails the first read: check before trusting
       ftell, which reports a huge size for it. The size is only a hint: the loop below reads
       until end of file either way. */
    {
        int first = fgetc(f);
        if (first == EOF && ferror(f)) {
            fclose(f);
            return mio__set_error(err, MIO_ERR_IO, "cannot read %.140s", path);
        }
        if (first != EOF) ungetc(first, f);
    }
    if (fseek(f, 0, SEEK_END) == 0) {
        long n = ftell(f);
        if (n > 0 && (unsigned long)n < (size_t)-1) cap = (size_t)n + 1;
        if (fseek(f, 0, SEEK_SET) != 0) cap = 0;
    }
    if (cap < 4096) cap = 4096;
    for (;;) {
        size_t got;
        if (size == cap || !buf) {
            unsigned char *fresh;
            size_t new_cap = buf ? (cap > ((size_t)-1) / 2 ? (size_t)-1 : cap * 2) : cap;
            if (buf && size == (size_t)-1) { r = MIO_ERR_TOO_LARGE; break; }
            fresh = (unsigned char *)alloc.alloc(alloc.user, new_cap);
            if (!fresh) { r = MIO_ERR_OUT_OF_MEMORY; break; }
            if (size) memcpy(fresh, buf, size);
            if (buf) alloc.free(alloc.user, buf);
            buf = fresh;
            cap = new_cap;
        }
        got = fread(buf + size, 1, cap - size, f);
        size += got;
        if (got == 0) {
            if (ferror(f)) r = MIO_ERR_IO;
            break;
        }
    }
    fclose(f);
    if (r != MIO_OK) {
        if (buf) alloc.free(alloc.user, buf);
        return mio__set_error(err, r, r == MIO_ERR_IO ? "read error in %.140s" : "cannot hold %.140s in memory", path);
    }
    r = mio__read(buf, size, path, opt, &alloc, out, err ? err : &local);
    alloc.free(alloc.user, buf);
    return r;
}

MIODEF void mio_free_mesh(mio_mesh *mesh)
{
    if (!mesh) return;
    if (mesh->allocator.free) {
        if (mesh->positions) mesh->allocator.free(mesh->allocator.user, mesh->positions);
        if (mesh->indices) mesh->allocator.free(mesh->allocator.user, mesh->indices);
    } else {
        MIO_FREE(mesh->positions);
        MIO_FREE(mesh->indices);
    }
    memset(mesh, 0, sizeof *mesh);
}

MIODEF const char *mio_result_string(mio_result r)
{
    switch (r) {
    case MIO_OK: return "MIO_OK";
    case MIO_ERR_INVALID_ARGUMENT: return "MIO_ERR_INVALID_ARGUMENT";
    case MIO_ERR_OUT_OF_MEMORY: return "MIO_ERR_OUT_OF_MEMORY";
    case MIO_ERR_IO: return "MIO_ERR_IO";
    case MIO_ERR_UNKNOWN_FORMAT: return "MIO_ERR_UNKNOWN_FORMAT";
    case MIO_ERR_SYNTAX: return "MIO_ERR_SYNTAX";
    case MIO_ERR_TRUNCATED: return "MIO_ERR_TRUNCATED";
    case MIO_ERR_INDEX_RANGE: return "MIO_ERR_INDEX_RANGE";
    case MIO_ERR_TOO_LARGE: return "MIO_ERR_TOO_LARGE";
    case MIO_ERR_UNSUPPORTED: return "MIO_ERR_UNSUPPORTED";
    case MIO_ERR_EMPTY: return "MIO_ERR_EMPTY";
    }
    return "MIO_ERR_?";
}

MIODEF const char *mio_result_description(mio_result r)
{
    switch (r) {
    case MIO_OK: return "success";
    case MIO_ERR_INVALID_ARGUMENT: return "invalid argument (a NULL pointer, a bad option or a non-finite coordinate)";
    case MIO_ERR_OUT_OF_MEMORY: return "out of memory";
    case MIO_ERR_IO: return "the file could not be opened, read or written";
    case MIO_ERR_UNKNOWN_FORMAT: return "neither the content nor the extension tells the format";
    case MIO_ERR_SYNTAX: return "malformed content";
    case MIO_ERR_TRUNCATED: return "the data ends early";
    case MIO_ERR_INDEX_RANGE: return "a face refers to a vertex that does not exist";
    case MIO_ERR_TOO_LARGE: return "more vertices or bytes than fit";
    case MIO_ERR_UNSUPPORTED: return "a valid variant this reader does not support";
    case MIO_ERR_EMPTY: return "no triangles";
    }
    return "unknown result code";
}

MIODEF const char *mio_format_string(mio_format f)
{
    switch (f) {
    case MIO_FORMAT_OBJ: return "obj";
    case MIO_FORMAT_OFF: return "off";
    case MIO_FORMAT_PLY: return "ply";
    case MIO_FORMAT_STL: return "stl";
    case MIO_FORMAT_AUTO: break;
    }
    return "auto";
}

/* ---------------------------------------------------------------------------------------------
   Section: writers
   --------------------------------------------------------------------------------------------- */

/* Validates writer arguments before the file is created. */
static mio_result mio__check_write(const char *path, const float *positions, size_t vertex_count, const uint32_t *indices,
                                   size_t triangle_count, mio_error *err)
{
    char msg[96];
    size_t i;
    if (err) mio__clear_error(err);
    if (!path) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "path is NULL");
    if (!positions && vertex_count) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "positions is NULL");
    if (!indices && triangle_count) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "indices is NULL");
    if (triangle_count > ((size_t)-1) / 3) return mio__set_error(err, MIO_ERR_TOO_LARGE, "too many triangles");
    if (vertex_count > ((size_t)-1) / 3) return mio__set_error(err, MIO_ERR_TOO_LARGE, "too many vertices");
    for (i = 0; i < 3 * vertex_count; i++) {
        uint32_t u;
        memcpy(&u, positions + i, 4);
        if ((u & 0x7F800000u) == 0x7F800000u) {
            snprintf(msg, sizeof msg, "vertex %llu has a non-finite coordinate", (unsigned long long)(i / 3));
            return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "%s", msg);
        }
    }
    for (i = 0; i < 3 * triangle_count; i++) {
        if ((size_t)indices[i] >= vertex_count) {
            snprintf(msg, sizeof msg, "triangle %llu: index %lu out of range (%llu vertices)", (unsigned long long)(i / 3),
                     (unsigned long)indices[i], (unsigned long long)vertex_count);
            return mio__set_error(err, MIO_ERR_INDEX_RANGE, "%s", msg);
        }
    }
    return MIO_OK;
}

/* Formats a float with %.9g (enough digits to round-trip) and replaces whatever decimal
   separator the current locale uses by '.'. Returns the length. */
static size_t mio__format_float(char *buf, size_t cap, float v)
{
    char tmp[48];
    size_t i, n = 0;
    int in_sep = 0;
    snprintf(tmp, sizeof tmp, "%.9g", (double)v);
    for (i = 0; tmp[i] && n + 1 < cap; i++) {
        char ch = tmp[i];
        if ((ch >= '0' && ch <= '9') || ch == '-' || ch == '+' || ch == 'e' || ch == 'E') {
            buf[n++] = ch;
            in_sep = 0;
        } else if (!in_sep) { /* a locale separator may span several bytes */
            buf[n++] = '.';
            in_sep = 1;
        }
    }
    buf[n] = '\0';
    return n;
}

static mio_result mio__finish_write(FILE *f, int failed, const char *path, mio_error *err)
{
    if (ferror(f)) failed = 1;
    if (fclose(f) != 0) failed = 1;
    if (failed) return mio__set_error(err, MIO_ERR_IO, "write error in %.140s", path);
    return MIO_OK;
}

static int mio__write_xyz_line(FILE *f, const char *prefix, const float *xyz)
{
    char a[48], b[48], d[48];
    mio__format_float(a, sizeof a, xyz[0]);
    mio__format_float(b, sizeof b, xyz[1]);
    mio__format_float(d, sizeof d, xyz[2]);
    return fprintf(f, "%s%s %s %s\n", prefix, a, b, d) < 0;
}

MIODEF mio_result mio_write_obj(const char *path, const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, mio_error *err)
{
    return mio_write_obj_normals(path, positions, NULL, vertex_count, indices, triangle_count, err);
}

MIODEF mio_result mio_write_obj_normals(const char *path, const float *positions, const float *normals,
                                        size_t vertex_count, const uint32_t *indices, size_t triangle_count,
                                        mio_error *err)
{
    mio_result r = mio__check_write(path, positions, vertex_count, indices, triangle_count, err);
    FILE *f;
    size_t i;
    int failed = 0;
    if (r != MIO_OK) return r;
    for (i = 0; normals && i < 3 * vertex_count; i++) {
        uint32_t u;
        memcpy(&u, normals + i, 4);
        if ((u & 0x7F800000u) == 0x7F800000u)
            return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "normal %llu is not finite", (unsigned long long)(i / 3));
    }
    f = fopen(path, "wb");
    if (!f) return mio__set_error(err, MIO_ERR_IO, "cannot create %.140s", path);
    failed |= fprintf(f, "# written by meshio.h: %llu vertices, %llu triangles\n", (unsigned long long)vertex_count,
                      (unsigned long long)triangle_count) < 0;
    for (i = 0; i < vertex_count && !failed; i++) failed |= mio__write_xyz_line(f, "v ", positions + 3 * i);
    for (i = 0; normals && i < vertex_count && !failed; i++) failed |= mio__write_xyz_line(f, "vn ", normals + 3 * i);
    for (i = 0; i < triangle_count && !failed; i++) {
        unsigned long long a = (unsigned long long)indices[3 * i] + 1, b = (unsigned long long)indices[3 * i + 1] + 1,
                           c = (unsigned long long)indices[3 * i + 2] + 1;
        if (normals) failed |= fprintf(f, "f %llu//%llu %llu//%llu %llu//%llu\n", a, a, b, b, c, c) < 0;
        else failed |= fprintf(f, "f %llu %llu %llu\n", a, b, c) < 0;
    }
    return mio__finish_write(f, failed, path, err);
}

static void mio__put_le32(unsigned char *p, uint32_t u)
{
    p[0] = (unsigned char)u;
    p[1] = (unsigned char)(u >> 8);
    p[2] = (unsigned char)(u >> 16);
    p[3] = (unsigned char)(u >> 24);
}

MIODEF mio_result mio_write_ply(const char *path, const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, int binary, mio_error *err)
{
    mio_result r = mio__check_write(path, positions, vertex_count, indices, triangle_count, err);
    FILE *f;
    size_t i;
    int failed = 0;
    if (r != MIO_OK) return r;
    if (binary != 0 && binary != 1) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "binary must be 0 or 1");
    f = fopen(path, "wb");
    if (!f) return mio__set_error(err, MIO_ERR_IO, "cannot create %.140s", path);
    failed |= fprintf(f, "ply\nformat %s 1.0\ncomment written by meshio.h\nelement vertex %llu\n"
                         "property float x\nproperty float y\nproperty float z\nelement face %llu\n"
                         "property list uchar uint vertex_indices\nend_header\n",
                      binary ? "binary_little_endian" : "ascii", (unsigned long long)vertex_count,
                      (unsigned long long)triangle_count) < 0;
    if (binary) {
        unsigned char rec[13];
        for (i = 0; i < vertex_count && !failed; i++) {
            uint32_t u[3];
            memcpy(u, positions + 3 * i, sizeof u);
            mio__put_le32(rec, u[0]);
            mio__put_le32(rec + 4, u[1]);
            mio__put_le32(rec + 8, u[2]);
            failed |= fwrite(rec, 1, 12, f) != 12;
        }
        for (i = 0; i < triangle_count && !failed; i++) {
            rec[0] = 3;
            mio__put_le32(rec + 1, indices[3 * i]);
            mio__put_le32(rec + 5, indices[3 * i + 1]);
            mio__put_le32(rec + 9, indices[3 * i + 2]);
            failed |= fwrite(rec, 1, 13, f) != 13;
        }
    } else {
        for (i = 0; i < vertex_count && !failed; i++) failed |= mio__write_xyz_line(f, "", positions + 3 * i);
        for (i = 0; i < triangle_count && !failed; i++)
            failed |= fprintf(f, "3 %lu %lu %lu\n", (unsigned long)indices[3 * i], (unsigned long)indices[3 * i + 1],
                              (unsigned long)indices[3 * i + 2]) < 0;
    }
    return mio__finish_write(f, failed, path, err);
}

MIODEF mio_result mio_write_off(const char *path, const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, mio_error *err)
{
    mio_result r = mio__check_write(path, positions, vertex_count, indices, triangle_count, err);
    FILE *f;
    size_t i;
    int failed = 0;
    if (r != MIO_OK) return r;
    f = fopen(path, "wb");
    if (!f) return mio__set_error(err, MIO_ERR_IO, "cannot create %.140s", path);
    failed |= fprintf(f, "OFF\n%llu %llu 0\n", (unsigned long long)vertex_count, (unsigned long long)triangle_count) < 0;
    for (i = 0; i < vertex_count && !failed; i++) failed |= mio__write_xyz_line(f, "", positions + 3 * i);
    for (i = 0; i < triangle_count && !failed; i++)
        failed |= fprintf(f, "3 %lu %lu %lu\n", (unsigned long)indices[3 * i], (unsigned long)indices[3 * i + 1],
                          (unsigned long)indices[3 * i + 2]) < 0;
    return mio__finish_write(f, failed, path, err);
}

/* The unit normal of triangle t (computed in double), or 0 0 0 when it has no area. */
static void mio__facet_normal(const float *positions, const uint32_t *tri, float n[3])
{
    const float *a = positions + 3 * (size_t)tri[0], *b = positions + 3 * (size_t)tri[1], *d = positions + 3 * (size_t)tri[2];
    double u[3], v[3], c[3], len;
    int k;
    for (k = 0; k < 3; k++) { u[k] = (double)b[k] - a[k]; v[k] = (double)d[k] - a[k]; }
    c[0] = u[1] * v[2] - u[2] * v[1];
    c[1] = u[2] * v[0] - u[0] * v[2];
    c[2] = u[0] * v[1] - u[1] * v[0];
    len = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    len = len > 0.0 && len <= DBL_MAX ? 1.0 / sqrt(len) : 0.0;
    for (k = 0; k < 3; k++) n[k] = (float)(c[k] * len);
}

static int mio__write_stl_facet(FILE *f, const float *positions, const uint32_t *tri, int binary)
{
    float n[3];
    int k, failed = 0;
    mio__facet_normal(positions, tri, n);
    if (binary) {
        unsigned char rec[50];
        uint32_t u[3];
        memcpy(u, n, sizeof u);
        for (k = 0; k < 3; k++) mio__put_le32(rec + 4 * k, u[k]);
        for (k = 0; k < 3; k++) {
            memcpy(u, positions + 3 * (size_t)tri[k], sizeof u);
            mio__put_le32(rec + 12 + 12 * k, u[0]);
            mio__put_le32(rec + 16 + 12 * k, u[1]);
            mio__put_le32(rec + 20 + 12 * k, u[2]);
        }
        rec[48] = rec[49] = 0;
        return fwrite(rec, 1, 50, f) != 50;
    }
    failed |= mio__write_xyz_line(f, " facet normal ", n);
    failed |= fputs("  outer loop\n", f) < 0;
    for (k = 0; k < 3 && !failed; k++) failed |= mio__write_xyz_line(f, "   vertex ", positions + 3 * (size_t)tri[k]);
    failed |= fputs("  endloop\n endfacet\n", f) < 0;
    return failed;
}

MIODEF mio_result mio_write_stl(const char *path, const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, int binary, mio_error *err)
{
    mio_result r = mio__check_write(path, positions, vertex_count, indices, triangle_count, err);
    FILE *f;
    size_t i;
    int failed = 0;
    if (r != MIO_OK) return r;
    if (binary != 0 && binary != 1) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "binary must be 0 or 1");
    if (binary && (uint64_t)triangle_count > 0xFFFFFFFFu)
        return mio__set_error(err, MIO_ERR_TOO_LARGE, "binary STL holds at most 4294967295 triangles");
    f = fopen(path, "wb");
    if (!f) return mio__set_error(err, MIO_ERR_IO, "cannot create %.140s", path);
    if (binary) {
        unsigned char head[84];
        memset(head, ' ', 80);
        memcpy(head, "binary STL written by meshio.h", 30);
        mio__put_le32(head + 80, (uint32_t)triangle_count);
        failed |= fwrite(head, 1, 84, f) != 84;
    } else {
        failed |= fputs("solid meshio\n", f) < 0;
    }
    for (i = 0; i < triangle_count && !failed; i++) failed |= mio__write_stl_facet(f, positions, indices + 3 * i, binary);
    if (!binary && !failed) failed |= fputs("endsolid meshio\n", f) < 0;
    return mio__finish_write(f, failed, path, err);
}

/* ---------------------------------------------------------------------------------------------
   Section: welding
   --------------------------------------------------------------------------------------------- */

/* Hash of a position's bits, -0 counted as +0 so that equal floats hash equally. */
static uint32_t mio__hash_position(const float *p)
{
    uint32_t h = 2166136261u, u;
    int k;
    for (k = 0; k < 3; k++) {
        memcpy(&u, p + k, 4);
        if (u == 0x80000000u) u = 0;
        h = (h ^ u) * 16777619u;
        h ^= h >> 15;
    }
    return h;
}

static mio_result mio__weld_check(const mio_mesh *m, mio_error *err)
{
    size_t i;
    if (!m) return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "mesh is NULL");
    if ((!m->positions && m->vertex_count) || (!m->indices && m->triangle_count))
        return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "mesh arrays are NULL");
    if ((uint64_t)m->vertex_count >= 0xFFFFFFFFu || m->triangle_count > ((size_t)-1) / 12)
        return mio__set_error(err, MIO_ERR_TOO_LARGE, "too many vertices or triangles to weld");
    for (i = 0; i < 3 * m->vertex_count; i++)
        if (!(m->positions[i] - m->positions[i] == 0.0f))
            return mio__set_error(err, MIO_ERR_INVALID_ARGUMENT, "vertex %llu has a non-finite coordinate",
                                  (unsigned long long)(i / 3));
    for (i = 0; i < 3 * m->triangle_count; i++)
        if ((size_t)m->indices[i] >= m->vertex_count)
            return mio__set_error(err, MIO_ERR_INDEX_RANGE, "triangle %llu: index %lu out of range (%llu vertices)",
                                  (unsigned long long)(i / 3), (unsigned long)m->indices[i],
                                  (unsigned long long)m->vertex_count);
    return MIO_OK;
}

/* remap[i] = the welded number of vertex i; returns the number of distinct positions.
   table has cap (a power of two > vertex_count) slots; UINT32_MAX marks an empty slot. */
static size_t mio__weld_map(const float *pos, size_t n, uint32_t *table, size_t cap, uint32_t *remap)
{
    size_t i, kept = 0;
    for (i = 0; i < cap; i++) table[i] = 0xFFFFFFFFu;
    for (i = 0; i < n; i++) {
        const float *p = pos + 3 * i;
        size_t s = mio__hash_position(p) & (cap - 1);
        for (;;) {
            uint32_t j = table[s];
            if (j == 0xFFFFFFFFu) { table[s] = (uint32_t)i; remap[i] = (uint32_t)kept++; break; }
            if (pos[3 * (size_t)j] == p[0] && pos[3 * (size_t)j + 1] == p[1] && pos[3 * (size_t)j + 2] == p[2]) {
                remap[i] = remap[j];
                break;
            }
            s = (s + 1) & (cap - 1);
        }
    }
    return kept;
}

MIODEF mio_result mio_weld(mio_mesh *mesh, mio_error *err)
{
    mio_allocator a;
    mio_result r;
    size_t n, cap = 16, kept, i;
    uint32_t *table, *remap;
    float *fresh;
    if (err) mio__clear_error(err);
    r = mio__weld_check(mesh, err);
    if (r != MIO_OK) return r;
    n = mesh->vertex_count;
    a = mesh->allocator;
    if (!a.alloc || !a.free) { a.alloc = mio__default_alloc; a.free = mio__default_free; a.user = NULL; }
    while (cap < 2 * n) cap *= 2; /* n < 2^32 and 12 bytes/vertex fit, so this does not overflow */
    if (cap > ((size_t)-1) / 4 - n) return mio__set_error(err, MIO_ERR_TOO_LARGE, "too many vertices to weld");
    table = (uint32_t *)a.alloc(a.user, (cap + n) * sizeof(uint32_t));
    if (!table) return mio__set_error(err, MIO_ERR_OUT_OF_MEMORY, "out of memory");
    remap = table + cap;
    kept = mio__weld_map(mesh->positions, n, table, cap, remap);
    if (kept == n) { a.free(a.user, table); return MIO_OK; }
    fresh = (float *)a.alloc(a.user, kept * 3 * sizeof(float) + (kept == 0));
    if (!fresh) { a.free(a.user, table); return mio__set_error(err, MIO_ERR_OUT_OF_MEMORY, "out of memory"); }
    for (i = 0, kept = 0; i < n; i++)
        if (remap[i] == kept) memcpy(fresh + 3 * kept++, mesh->positions + 3 * i, 3 * sizeof(float));
    for (i = 0; i < 3 * mesh->triangle_count; i++) mesh->indices[i] = remap[mesh->indices[i]];
    a.free(a.user, table);
    a.free(a.user, mesh->positions);
    mesh->positions = fresh;
    mesh->vertex_count = kept;
    return MIO_OK;
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* MIO_IMPLEMENTATION_DONE */
#endif /* MIO_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
MIT License

Copyright (c) 2026 the meshio.h authors

Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:

The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
*/
