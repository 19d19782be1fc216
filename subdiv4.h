/* subdiv4.h - v0.1 - MIT licence or public domain (see end of file)
   The four-point interpolatory scheme (Dyn, Levin, Gregory 1987) for curves and tensor-product
   grids, paper 001's terrain pipeline built on it, and the butterfly scheme on triangle meshes.

   WHAT
     - Curves: open or closed polylines of any dimension (2D, 3D, ...), refined k levels by
           V(2i) = V(i),   V(2i+1) = (1/2 + w)(V(i) + V(i+1)) - w (V(i-1) + V(i+2))
       with one w for all levels or one w per level. Old points are copied bit-exactly.
     - Grids: the same rule along rows, then along columns (the operators commute, so the order
       does not matter up to rounding), on any number of components per node (heights, or xyz).
       Open or periodic borders per direction. The output size is known before running
       (sd4_grid_size) and the output buffer is the caller's.
     - Terrain (Luo & Wang, paper 001): control heights (given, or seeded random), k levels of the
       grid scheme, each quad then split 1->4 (bilinear midpoints and centre) until its longest
       edge is <= epsilon, with no T-junction left (see TERRAIN), and one Gaussian-perturbed
       normal per small quad (the paper's "geometric texture"). The presets desert, vegetation,
       mountain5 and mountain6 are the paper's Figs 3-6 (sd4_terrain_preset).
     - Butterfly (Dyn, Levin, Gregory 1990, tension w) on triangle meshes, with the modified
       rules of Zorin, Schroeder, Sweldens 1996 at extraordinary vertices and the four-point
       rule on boundary edges. Non-manifold parts are passed through unrefined.

   HOW TO USE (in ten lines)
       // in exactly one C or C++ file, #define SD4_IMPLEMENTATION before #include "subdiv4.h"
       size_t nx2, ny2;                                        // 9x9 heights -> 1025x1025
       sd4_grid_size(9, 9, 7, NULL, &nx2, &ny2);
       double *fine = malloc(nx2 * ny2 * sizeof(double));
       sd4_grid_refine(heights, 9, 9, 1, 0.0625, 7, NULL, fine, nx2 * ny2);
       sd4_mesh m;                                             // two butterfly levels
       if (sd4_butterfly(pos, nv, idx, nt, 2, 0.0625, NULL, &m) == SD4_OK) {
           use(m.positions, m.vertex_count, m.indices, m.triangle_count); sd4_free_mesh(&m);
       }

   OPTIONS
     Compile time: SD4_STATIC (all functions static), SD4_MALLOC(sz)/SD4_FREE(p) (both or neither).
     Run time, sd4_options (NULL or a zeroed struct means the defaults below):
       end_rule, end_rule_y  how the first and last interval of an open line get their missing
                      outer point (a "ghost" point), for curves / grid rows (end_rule) and grid
                      columns (end_rule_y):
                      SD4_END_LINEAR (0, default): V(-1) = 2V(0) - V(1). Reproduces linear
                        functions everywhere; the end rule becomes
                        (1/2 - w) V0 + (1/2 + 2w) V1 - w V2.
                      SD4_END_CUBIC: V(-1) = 4V0 - 6V1 + 4V2 - V3 (cubic extrapolation). With
                        w = 1/16 the scheme then reproduces cubics everywhere; the end rule is
                        (1/2 - 3w) V0 + (1/2 + 7w) V1 - 5w V2 + w V3 (= (5,15,-5,1)/16 at 1/16).
                        Lines of 3 points use quadratic extrapolation 3V0 - 3V1 + V2, lines of
                        2 points the linear one.
                      SD4_END_PERIODIC: closed curve / periodic grid direction: indices wrap.
                        A closed curve of n points gives n 2^k points (the closing segment is
                        implied); open gives (n - 1) 2^k + 1.
       omega_per_level  NULL, or `levels` values: w at level 0, 1, ... (a non-stationary
                      scheme, still interpolatory); replaces the w argument.
       omega_convention SD4_OMEGA_STANDARD (0): the DLG form above. SD4_OMEGA_HALF: the literal
                      OCR reading of paper 001's equation (1), (1/2 + w/2)(...) - (w/2)(...),
                      i.e. every w is halved before use. Paper note 001 shows the standard
                      form is what the paper meant (its smoothness ranges only fit that form).
       allocator      NULL = SD4_MALLOC/SD4_FREE; kept in any sd4_mesh returned.
       progress       NULL, or called with done in [0, 1]; nonzero return cancels (SD4_CANCELLED,
                      nothing leaked, caller-owned output then holds partial results).

   SMOOTHNESS (what w gives; from paper note 001 and the literature)
     The limit curve is C0 for |w| < 1/2 (Dyn et al. 1987; the ends of the interval are
     optimistic: keep 0 < w <= 0.3), and C1 for 0 < w < (sqrt 5 - 1)/8 = 0.1545 (DLG's bound);
     the sharper known C1 bound is w < 0.1927 (Hechler, Moessner, Reif 2009). w = 0 is linear
     interpolation, w = 1/16 the cubic-precision Deslauriers-Dubuc scheme. The tensor-product
     surface has the same smoothness. The terrain presets therefore give:
       desert     w = 0.10  C1, smooth dunes, overshoot about 1% of a bump
       vegetation w = 0.18  C1 (inside the sharper bound only), rolling, 19% overshoot in 2D
       mountain5  w = 0.20  C0 only: visible creases and ridges, 26% overshoot
       mountain6  w = 0.25  C0 only: sharper ridges, 46% overshoot and 61%-deep moats around a
                            single raised control point (terrain goes below its lowest control
                            height; nothing is clamped, as in the paper).

   TERRAIN (sd4_terrain_build)
     Steps, as in paper 001 section 1.2: (1) control heights on an nx x ny grid with spacing h0
     (given, or uniform random in [0, amplitude] from the seed, optionally box-smoothed);
     (2) `levels` levels of the grid scheme on the heights (x and z stay a uniform lattice,
     which the scheme reproduces); (3) every refined quad with longest 3D edge rho > epsilon is
     split 1->4 d times, d the smallest with rho / 2^d <= epsilon (children's edges are at most
     half their parent's, so every small quad meets epsilon; this is the paper's recursion with
     its depth computed directly); (4) one normal per small quad from its diagonals, perturbed
     N' = normalize(N + sigma g), g a standard 3D Gaussian from the seed and the quad's lattice
     position (so it does not depend on traversal order).
     Cracks: neighbouring quads may get different depths. Every edge takes the larger depth of
     its two quads; a small quad whose side carries its neighbour's extra points is drawn as a
     fan of triangles from its centre through all of them, other small quads as two triangles.
     The output is then a conforming triangle mesh (every interior edge has exactly two
     triangles), watertight for any rasterizer. Axes: x along the grid rows, y up (heights),
     z along the columns; triangles are counter-clockwise seen from above.

   BUTTERFLY (sd4_butterfly)
     Each level splits every edge at a new point and every triangle into four; old vertices are
     kept (the scheme interpolates). The new point of an interior edge (a, b) with opposite
     vertices c, d and the four "wing" vertices e1..e4 beyond the triangles' other edges:
       both ends regular (valence 6) or on the boundary: 1/2 (a + b) + 2w (c + d) - w (e1+..+e4)
         (DLG 1990; w = 1/16 is the standard butterfly). A wing missing because its edge is on
         the boundary is replaced by its mirror image x + y - z of the triangle (x, y, z) whose
         edge (x, y) it lies across.
       an end interior and of valence K != 6: ZSS 1996's stencil around that end, v and its
         neighbours e_j (e_0 = the other end): 3/4 v + sum s_j e_j with s_j = (1/4 + cos(2 pi j/K)
         + 1/2 cos(4 pi j/K))/K for K >= 5, (5/12, -1/12, -1/12) for K = 3, (3/8, 0, -1/8, 0)
         for K = 4; both ends extraordinary: the average of the two stencils. These weights are
         those of the w = 1/16 scheme whatever w is. Interior vertices of valence 1 or 2 (closed
         "pillows") use the K >= 5 formula. From K = 64 on, the K stencils around a vertex are
         evaluated from three Fourier sums of its neighbours (the weights have three
         frequencies), so the work is linear in the valence rather than quadratic; the result
         differs from the direct sum by rounding only. Twins are found by binary search in each
         vertex's half-edges sorted by end vertex: a level takes O(n log valence).
       boundary edge: the four-point rule above along the boundary loop.
     These are the rules OpenMesh's ModifiedButterflyT uses (the reference test matches it to
     float rounding on closed meshes). Deviation from Zorin's thesis: interior edges next to the
     boundary use the mirrored butterfly above instead of the thesis' boundary-valence tables.
     Non-manifold input: an edge with more than two triangles or inconsistent orientation, a
     vertex whose triangles form more than one fan, and a triangle with a repeated vertex make
     their triangles "frozen": these are copied unrefined, and their edges are not split. A
     triangle next to a frozen one has some edges unsplit; it is split into 2 or 3 triangles
     instead of 4 so that the mesh stays conforming.
     Output vertex order: old vertices first (same indices), then one per split edge, in the
     order of the first half-edge (3 t + k, edge from corner k to k + 1) that names the edge.

   MEMORY
     Curves and grids never allocate: the output is the caller's, of the size returned by
     sd4_curve_size / sd4_grid_size. Butterfly and terrain return an sd4_mesh allocated with
     the options' allocator; free it with sd4_free_mesh. Butterfly keeps about 75 bytes per input
     triangle of connectivity while a level runs, plus input and output arrays.

   ERRORS
     Functions return sd4_result (SD4_OK = 0); sd4_result_string() names it. Checked: NULL
     arrays, levels outside 0..30 (curves, grids), 1..8 (butterfly) or 0..10 (terrain), dim
     outside 1..64, unknown option values, non-finite w, sizes that overflow size_t or the
     32-bit indices, too small an output buffer (SD4_ERR_BUFFER_TOO_SMALL), non-finite
     coordinates or heights (SD4_ERR_BAD_POSITION), indices >= vertex_count, finite input whose
     result is not (SD4_ERR_NOT_FINITE: a huge w, amplitude or coordinate overflows a double, or
     a float in a mesh; every output value is checked). Non-manifold or
     degenerate meshes are not errors (see BUTTERFLY). On failure an sd4_mesh is zeroed and
     nothing is leaked; a caller-owned grid buffer may hold partial results.

   THREAD SAFETY
     No global state; every function is re-entrant. Same input and options give the same bits.

   PRECISION
     Curves and grids compute in double. Butterfly reads float positions, computes each new
     point in double and rounds it to float once; old vertices are copied exactly.

   LIMITS
     2^32 - 2 vertices per mesh. The terrain's split depth is capped at 10 (option max_split) and
     its mesh at max_triangles (default 2^24, about 50 bytes a triangle while it is built): the
     size is known from the split depths before anything is made, so a divergent w (heights that
     grow level by level, every quad then split to the cap) is refused at once with
     SD4_ERR_TOO_LARGE instead of filling the memory.
     The bits do not depend on the compiler's FMA contraction (dialect, C or C++, -ffp-contract):
     the implementation turns it off for its own code and restores the user's setting after it,
     except under clang's -ffp-contract=fast, which ignores that pragma (the last bits may differ).

   REFERENCES
     N. Dyn, J. A. Gregory, D. Levin, "A 4-point interpolatory subdivision scheme for curve
       design", CAGD 4(4), 1987, 257-268.
     N. Dyn, D. Levin, J. A. Gregory, "A butterfly subdivision scheme for surface interpolation
       with tension control", ACM TOG 9(2), 1990, 160-169.
     D. Zorin, P. Schroeder, W. Sweldens, "Interpolating subdivision for meshes with arbitrary
       topology", SIGGRAPH 1996, 189-192.
     J. Hechler, B. Moessner, U. Reif, "C1-continuity of the generalized four-point scheme",
       Linear Algebra Appl. 430, 2009.
     G. Deslauriers, S. Dubuc, "Symmetric iterative interpolation processes", Constr. Approx. 5,
       1989 (w = 1/16).
     Luo Yanlin, Wang Guozhao, "Topography simulation by controlling parameters of four-point
       interpolatory scheme" (in Chinese), about 1999 (paper 001: the terrain pipeline). */
#ifndef SD4_SUBDIV4_H
#define SD4_SUBDIV4_H

#include <stddef.h>
#include <stdint.h>

#ifdef SD4_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define SD4DEF static __attribute__((unused))
#else
#define SD4DEF static
#endif
#else
#define SD4DEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sd4_result {
    SD4_OK = 0,
    SD4_ERR_INVALID_ARGUMENT, /* NULL pointer, bad dim, levels or option value */
    SD4_ERR_BAD_INDEX,        /* a triangle index is >= vertex_count */
    SD4_ERR_BAD_POSITION,     /* a coordinate or height is NaN or infinite */
    SD4_ERR_TOO_LARGE,        /* a size overflows size_t or the 32-bit indices */
    SD4_ERR_BUFFER_TOO_SMALL, /* the caller's output buffer is smaller than the size functions say */
    SD4_ERR_OUT_OF_MEMORY,    /* the allocator returned NULL */
    SD4_CANCELLED,            /* the progress callback returned nonzero */
    SD4_ERR_NOT_FINITE        /* finite input whose result is not (it overflows a double or float) */
} sd4_result;

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct sd4_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} sd4_allocator;

enum { SD4_END_LINEAR = 0, SD4_END_CUBIC = 1, SD4_END_PERIODIC = 2 };
enum { SD4_OMEGA_STANDARD = 0, SD4_OMEGA_HALF = 1 };

typedef struct sd4_options {
    int end_rule;                   /* curves and grid rows: SD4_END_LINEAR (0), _CUBIC, _PERIODIC */
    int end_rule_y;                 /* grid columns: same values */
    const double *omega_per_level;  /* NULL, or one w per level (replaces the w argument) */
    int omega_convention;           /* SD4_OMEGA_STANDARD (0) or SD4_OMEGA_HALF (paper's OCR text) */
    const sd4_allocator *allocator; /* NULL = SD4_MALLOC/SD4_FREE */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} sd4_options;                      /* zero = defaults */

/* A triangle mesh returned by the library (free with sd4_free_mesh). */
typedef struct sd4_mesh {
    float *positions;        /* 3 per vertex */
    size_t vertex_count;
    uint32_t *indices;       /* 3 per triangle, counter-clockwise front faces */
    size_t triangle_count;
    float *face_normals;     /* terrain only: 3 per triangle, unit, perturbed; NULL otherwise */
    sd4_allocator allocator;
} sd4_mesh;

/* ---- curves and grids ------------------------------------------------------------------------ */

/* Number of points after `levels` levels of a curve of n points (closed: end_rule PERIODIC).
   Returns SD4_ERR_TOO_LARGE on overflow, SD4_ERR_INVALID_ARGUMENT for n == 0 or levels > 30. */
SD4DEF sd4_result sd4_curve_size(size_t n, int closed, int levels, size_t *out_n);

/* Refines a curve.
   points    n points of dim doubles each (x0, y0, [z0,] x1, ...).
   n         at least 1 (2 for an open curve to have a segment).
   dim       1..64 components per point.
   omega     w of the rule (see omega_per_level and omega_convention).
   levels    0..30.
   options   NULL or zeroed: open curve, linear end rule; end_rule = SD4_END_PERIODIC: closed.
   out       caller's buffer of out_capacity points (dim doubles each); must not overlap points.
             Point i of the input is out[i * 2^levels]. */
SD4DEF sd4_result sd4_curve_refine(const double *points, size_t n, int dim, double omega, int levels,
                                   const sd4_options *options, double *out, size_t out_capacity);

/* Size of a refined nx x ny grid: open directions give (n - 1) 2^levels + 1, periodic ones
   n 2^levels (end_rule for x, end_rule_y for y). options may be NULL. */
SD4DEF sd4_result sd4_grid_size(size_t nx, size_t ny, int levels, const sd4_options *options, size_t *out_nx,
                                size_t *out_ny);

/* Refines a grid: rows (x) then columns (y) at each level.
   grid      nx * ny nodes of dim doubles, row-major: node (i, j) at grid[(j * nx + i) * dim].
   out       caller's buffer of out_capacity doubles (>= out_nx * out_ny * dim), row-major with
             out_nx columns; node (i, j) of the input is node (i 2^levels, j 2^levels). */
SD4DEF sd4_result sd4_grid_refine(const double *grid, size_t nx, size_t ny, int dim, double omega, int levels,
                                  const sd4_options *options, double *out, size_t out_capacity);

/* The same grid refined with columns first, then rows (for tests of the commutation). */
SD4DEF sd4_result sd4_grid_refine_columns_first(const double *grid, size_t nx, size_t ny, int dim, double omega,
                                                int levels, const sd4_options *options, double *out,
                                                size_t out_capacity);

/* ---- terrain (paper 001) ---------------------------------------------------------------------- */

typedef struct sd4_terrain_desc {
    const double *heights;   /* nx * ny control heights (row-major, x fastest), or NULL = random */
    size_t nx, ny;           /* control grid, 0 = 9 */
    double spacing;          /* control spacing h0 in world units, 0 = 64 */
    double amplitude;        /* random heights uniform in [0, amplitude], 0 = 60 */
    int smooth_passes;       /* random heights: 3x3 box-filter passes (0 = none) */
    uint64_t seed;           /* random heights and normal noise */
    double omega;            /* shape parameter w, used as given (0 = linear interpolation) */
    int levels;              /* four-point levels 0..10 (paper: below 7) */
    double epsilon;          /* longest edge of a small quad; <= 0 = no split */
    double sigma;            /* normal perturbation; 0 = none */
    int border;              /* end rule in both directions, SD4_END_LINEAR (0) or SD4_END_CUBIC */
    int omega_convention;    /* SD4_OMEGA_STANDARD (0) or SD4_OMEGA_HALF */
    int max_split;           /* split depth cap, 0 = 10 */
    const sd4_allocator *allocator;
    int (*progress)(void *user, float done);
    void *progress_user;
    size_t max_triangles;    /* refuse a mesh of more (SD4_ERR_TOO_LARGE), counted before any of it
                                is made; 0 = 2^24 (the largest preset makes 1.5 M) */
} sd4_terrain_desc;

/* Fills d with paper 001's scene: "desert" (Fig 3: w 0.10, epsilon 2, sigma 0.06, amplitude 24,
   one smoothing pass), "vegetation" (Fig 4: 0.18, 3, 0.35, 60), "mountain5" (Fig 5: 0.20, 3,
   0.20, 120), "mountain6" (Fig 6: 0.25, 3, 0.25, 160); 9 x 9 control points 64 apart, 4 levels,
   seed 1999. w and epsilon are the paper's; the rest (which the paper does not give) are paper
   note 001's recommendations. Returns SD4_ERR_INVALID_ARGUMENT for an unknown name. */
SD4DEF sd4_result sd4_terrain_preset(const char *name, sd4_terrain_desc *d);

/* Runs the pipeline (see TERRAIN above). out->face_normals holds the perturbed normals. */
SD4DEF sd4_result sd4_terrain_build(const sd4_terrain_desc *d, sd4_mesh *out);

/* Seeded control heights: uniform in [0, amplitude], then smooth_passes 3x3 box passes (borders
   clamped). out: nx * ny doubles. Allocates a scratch row pair only when smoothing. */
SD4DEF sd4_result sd4_random_heights(size_t nx, size_t ny, double amplitude, int smooth_passes, uint64_t seed,
                                     const sd4_allocator *allocator, double *out);

/* ---- butterfly -------------------------------------------------------------------------------- */

/* Refines a triangle mesh `levels` times (1..8) with the modified butterfly scheme, tension w
   (1/16 = the standard scheme). positions: 3 floats per vertex; indices: 3 per triangle.
   Neither array is referenced after the call. out is filled on success, zeroed on failure. */
SD4DEF sd4_result sd4_butterfly(const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, int levels, double w, const sd4_options *options,
                                sd4_mesh *out);

/* Frees the arrays of a mesh returned by this library (NULL or a zeroed mesh is fine). */
SD4DEF void sd4_free_mesh(sd4_mesh *m);

/* "SD4_OK", "SD4_ERR_BAD_INDEX", ... (the enum name); "SD4_ERR_?" outside the enum. */
SD4DEF const char *sd4_result_string(sd4_result r);

#ifdef __cplusplus
}
#endif
#endif /* SD4_SUBDIV4_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef SD4_IMPLEMENTATION
#ifndef SD4_IMPLEMENTATION_DONE
#define SD4_IMPLEMENTATION_DONE

#include <string.h>
#include <math.h>

#if defined(SD4_MALLOC) && defined(SD4_FREE)
/* both given */
#elif !defined(SD4_MALLOC) && !defined(SD4_FREE)
#include <stdlib.h>
#define SD4_MALLOC(sz) malloc(sz)
#define SD4_FREE(p) free(p)
#else
#error "subdiv4.h: define both SD4_MALLOC and SD4_FREE, or neither"
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
   Section: results and allocation
   --------------------------------------------------------------------------------------------- */

SD4DEF const char *sd4_result_string(sd4_result r)
{
    switch (r) {
    case SD4_OK: return "SD4_OK";
    case SD4_ERR_INVALID_ARGUMENT: return "SD4_ERR_INVALID_ARGUMENT";
    case SD4_ERR_BAD_INDEX: return "SD4_ERR_BAD_INDEX";
    case SD4_ERR_BAD_POSITION: return "SD4_ERR_BAD_POSITION";
    case SD4_ERR_TOO_LARGE: return "SD4_ERR_TOO_LARGE";
    case SD4_ERR_BUFFER_TOO_SMALL: return "SD4_ERR_BUFFER_TOO_SMALL";
    case SD4_ERR_OUT_OF_MEMORY: return "SD4_ERR_OUT_OF_MEMORY";
    case SD4_ERR_NOT_FINITE: return "SD4_ERR_NOT_FINITE";
    case SD4_CANCELLED: return "SD4_CANCELLED";
    }
    return "SD4_ERR_?";
}

static void *sd4__default_alloc(void *user, size_t size) { (void)user; return SD4_MALLOC(size); }
static void sd4__default_free(void *user, void *ptr) { (void)user; SD4_FREE(ptr); }

static sd4_allocator sd4__resolve_allocator(const sd4_allocator *a)
{
    sd4_allocator r;
    if (a && a->alloc && a->free) return *a;
    r.alloc = sd4__default_alloc;
    r.free = sd4__default_free;
    r.user = NULL;
    return r;
}

/* count * size bytes (at least 1), or NULL when the product overflows or the allocator fails */
static void *sd4__alloc_array(const sd4_allocator *a, size_t count, size_t size)
{
    if (size != 0 && count > (size_t)-1 / size) return NULL;
    return a->alloc(a->user, count * size > 0 ? count * size : 1);
}

static void sd4__free(const sd4_allocator *a, void *p)
{
    if (p) a->free(a->user, p);
}

SD4DEF void sd4_free_mesh(sd4_mesh *m)
{
    if (!m) return;
    if (m->allocator.free) {
        sd4__free(&m->allocator, m->positions);
        sd4__free(&m->allocator, m->indices);
        sd4__free(&m->allocator, m->face_normals);
    }
    memset(m, 0, sizeof *m);
}

/* splitmix64: the hash behind every seeded random number here (a pure function of its input) */
static uint64_t sd4__mix(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/* uniform in [0, 1) */
static double sd4__uniform(uint64_t seed, uint64_t i, uint64_t stream)
{
    return (double)(sd4__mix(sd4__mix(seed) ^ (i * 8 + stream)) >> 11) * (1.0 / 9007199254740992.0);
}

/* ---------------------------------------------------------------------------------------------
   Section: the four-point rule on one line (stencils, end rules)
   --------------------------------------------------------------------------------------------- */

/* The new point of interval i (between points i and i + 1) of a line of m points, as a sum of
   at most 10 weighted old points (ghost points expanded into the real points they stand for). */
typedef struct sd4__stencil {
    size_t idx[10];
    double wt[10];
    int n;
} sd4__stencil;

static void sd4__add(sd4__stencil *st, size_t idx, double wt)
{
    st->idx[st->n] = idx;
    st->wt[st->n] = wt;
    st->n++;
}

/* Adds scale * V(-1) (left) or scale * V(m) (right), the ghost point of an open line. */
static void sd4__add_ghost(sd4__stencil *st, size_t m, int rule, int right, double scale)
{
    static const double lin[2] = {2.0, -1.0}, quad[3] = {3.0, -3.0, 1.0}, cub[4] = {4.0, -6.0, 4.0, -1.0};
    const double *c = lin;
    size_t k, count = 2;
    if (rule == SD4_END_CUBIC && m >= 4) { c = cub; count = 4; }
    else if (rule == SD4_END_CUBIC && m == 3) { c = quad; count = 3; }
    for (k = 0; k < count; k++) sd4__add(st, right ? m - 1 - k : k, scale * c[k]);
}

static void sd4__line_stencil(size_t i, size_t m, int rule, double w, sd4__stencil *st)
{
    double a = 0.5 + w;
    st->n = 0;
    if (rule == SD4_END_PERIODIC) {
        sd4__add(st, (i + m - 1) % m, -w);
        sd4__add(st, i % m, a);
        sd4__add(st, (i + 1) % m, a);
        sd4__add(st, (i + 2) % m, -w);
        return;
    }
    if (i >= 1) sd4__add(st, i - 1, -w);
    else sd4__add_ghost(st, m, rule, 0, -w);
    sd4__add(st, i, a);
    sd4__add(st, i + 1, a);
    if (i + 2 <= m - 1) sd4__add(st, i + 2, -w);
    else sd4__add_ghost(st, m, rule, 1, -w);
}

/* ---------------------------------------------------------------------------------------------
   Section: curves and grids
   The output array holds the finest grid; the input sits at stride S = 2^levels. Level l
   (stride s, half stride h = s / 2) fills the odd multiples of h: first along x on the rows that
   exist, then along y on every column that then exists (or the other way round).
   --------------------------------------------------------------------------------------------- */

static size_t sd4__points_at(size_t n, int periodic, int level)
{
    return periodic ? n << level : ((n - 1) << level) + 1;
}

static sd4_result sd4__line_size(size_t n, int periodic, int levels, size_t *out)
{
    if (n == 0 || levels < 0 || levels > 30) return SD4_ERR_INVALID_ARGUMENT;
    if ((periodic ? n : n - 1) > ((size_t)-1 - 1) >> levels) return SD4_ERR_TOO_LARGE;
    *out = sd4__points_at(n, periodic, levels);
    return SD4_OK;
}

/* x pass: on nrows rows (row r * rstep), fill the odd half-stride columns of a line of m coarse
   points at stride s. W = output columns. */
static void sd4__pass_x(double *out, size_t W, int dim, size_t rstep, size_t nrows, size_t s, size_t m, int rule,
                        double w)
{
    size_t intervals = rule == SD4_END_PERIODIC ? m : m - 1, h = s / 2, r, i, D = (size_t)dim;
    double a = 0.5 + w;
    int k, d;
    if (m < 2 && rule != SD4_END_PERIODIC) return;
    for (r = 0; r < nrows; r++) {
        double *row = out + r * rstep * W * D;
        for (i = 0; i < intervals; i++) {
            double *dst = row + (i * s + h) * D;
            if (i >= 1 && i + 2 < m) { /* interior: the plain four-point rule */
                const double *p0 = row + (i - 1) * s * D, *p1 = p0 + s * D, *p2 = p1 + s * D, *p3 = p2 + s * D;
                for (d = 0; d < dim; d++) dst[d] = a * (p1[d] + p2[d]) - w * (p0[d] + p3[d]);
            } else {
                sd4__stencil st;
                sd4__line_stencil(i, m, rule, w, &st);
                for (d = 0; d < dim; d++) {
                    double sum = 0.0;
                    for (k = 0; k < st.n; k++) sum += st.wt[k] * row[st.idx[k] * s * D + (size_t)d];
                    dst[d] = sum;
                }
            }
        }
    }
}

/* y pass: on ncols columns (column c * cstep), fill the odd half-stride rows of a column of m
   coarse rows at stride s. Row-by-row so that the inner loop runs along memory. */
static void sd4__pass_y(double *out, size_t W, int dim, size_t cstep, size_t ncols, size_t s, size_t m, int rule,
                        double w)
{
    size_t intervals = rule == SD4_END_PERIODIC ? m : m - 1, h = s / 2, i, c, D = (size_t)dim, RS = W * D;
    size_t run = ncols * D; /* contiguous length when cstep == 1 */
    double a = 0.5 + w;
    int k, d;
    if (m < 2 && rule != SD4_END_PERIODIC) return;
    for (i = 0; i < intervals; i++) {
        double *dst = out + (i * s + h) * RS;
        if (i >= 1 && i + 2 < m) {
            const double *p0 = out + (i - 1) * s * RS, *p1 = p0 + s * RS, *p2 = p1 + s * RS, *p3 = p2 + s * RS;
            if (cstep == 1) {
                for (c = 0; c < run; c++) dst[c] = a * (p1[c] + p2[c]) - w * (p0[c] + p3[c]);
            } else {
                for (c = 0; c < ncols; c++) {
                    size_t o = c * cstep * D;
                    for (d = 0; d < dim; d++)
                        dst[o + (size_t)d] = a * (p1[o + (size_t)d] + p2[o + (size_t)d]) - w * (p0[o + (size_t)d] + p3[o + (size_t)d]);
                }
            }
        } else {
            sd4__stencil st;
            sd4__line_stencil(i, m, rule, w, &st);
            for (c = 0; c < ncols; c++) {
                size_t o = c * cstep * D;
                for (d = 0; d < dim; d++) {
                    double sum = 0.0;
                    for (k = 0; k < st.n; k++) sum += st.wt[k] * out[st.idx[k] * s * RS + o + (size_t)d];
                    dst[o + (size_t)d] = sum;
                }
            }
        }
    }
}

/* 1 when none of the n values is NaN or infinite */
static int sd4__all_finite(const double *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* a double as float, out-of-range values as infinities (the plain conversion is undefined) */
static float sd4__to_float(double x)
{
    if (x > 3.4028234663852886e38) return HUGE_VALF;
    if (x < -3.4028234663852886e38) return -HUGE_VALF;
    return (float)x;
}

static int sd4__all_finite_f(const float *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

static int sd4__valid_rule(int r) { return r == SD4_END_LINEAR || r == SD4_END_CUBIC || r == SD4_END_PERIODIC; }

static sd4_result sd4__grid(const double *grid, size_t nx, size_t ny, int dim, double omega, int levels,
                            const sd4_options *o, double *out, size_t cap, int columns_first)
{
    sd4_options def;
    size_t W, H, S, i, j, total, D;
    int lev, d, rx, ry;
    sd4_result r;
    if (!o) { memset(&def, 0, sizeof def); o = &def; }
    if (!grid || !out || dim < 1 || dim > 64 || levels < 0 || levels > 30) return SD4_ERR_INVALID_ARGUMENT;
    if (!sd4__valid_rule(o->end_rule) || !sd4__valid_rule(o->end_rule_y)) return SD4_ERR_INVALID_ARGUMENT;
    if (o->omega_convention != SD4_OMEGA_STANDARD && o->omega_convention != SD4_OMEGA_HALF)
        return SD4_ERR_INVALID_ARGUMENT;
    rx = o->end_rule;
    ry = o->end_rule_y;
    if ((r = sd4_grid_size(nx, ny, levels, o, &W, &H)) != SD4_OK) return r;
    D = (size_t)dim;
    if (H != 0 && W > (size_t)-1 / H) return SD4_ERR_TOO_LARGE;
    if (W * H > (size_t)-1 / D) return SD4_ERR_TOO_LARGE;
    total = W * H * D;
    if (cap < total) return SD4_ERR_BUFFER_TOO_SMALL;
    if (!isfinite(omega) && !o->omega_per_level) return SD4_ERR_INVALID_ARGUMENT;
    for (lev = 0; o->omega_per_level && lev < levels; lev++)
        if (!isfinite(o->omega_per_level[lev])) return SD4_ERR_INVALID_ARGUMENT;
    for (i = 0; i < nx * ny * D; i++)
        if (!isfinite(grid[i])) return SD4_ERR_BAD_POSITION;
    S = (size_t)1 << levels;
    for (j = 0; j < ny; j++)
        for (i = 0; i < nx; i++)
            for (d = 0; d < dim; d++) out[((j * S) * W + i * S) * D + (size_t)d] = grid[(j * nx + i) * D + (size_t)d];
    for (lev = 0; lev < levels; lev++) {
        size_t s = S >> lev, h = s / 2;
        size_t mx = sd4__points_at(nx, rx == SD4_END_PERIODIC, lev), my = sd4__points_at(ny, ry == SD4_END_PERIODIC, lev);
        size_t mx2 = sd4__points_at(nx, rx == SD4_END_PERIODIC, lev + 1), my2 = sd4__points_at(ny, ry == SD4_END_PERIODIC, lev + 1);
        double w = o->omega_per_level ? o->omega_per_level[lev] : omega;
        if (o->omega_convention == SD4_OMEGA_HALF) w *= 0.5;
        if (o->progress && o->progress(o->progress_user, (float)lev / (float)levels)) return SD4_CANCELLED;
        if (!columns_first) {
            sd4__pass_x(out, W, dim, s, my, s, mx, rx, w);
            sd4__pass_y(out, W, dim, h, mx2, s, my, ry, w);
        } else {
            sd4__pass_y(out, W, dim, s, mx, s, my, ry, w);
            sd4__pass_x(out, W, dim, h, my2, s, mx, rx, w);
        }
    }
    if (!sd4__all_finite(out, total)) return SD4_ERR_NOT_FINITE;
    if (o->progress && o->progress(o->progress_user, 1.0f)) return SD4_CANCELLED;
    return SD4_OK;
}

SD4DEF sd4_result sd4_grid_size(size_t nx, size_t ny, int levels, const sd4_options *o, size_t *out_nx,
                                size_t *out_ny)
{
    sd4_result r;
    int px = o && o->end_rule == SD4_END_PERIODIC, py = o && o->end_rule_y == SD4_END_PERIODIC;
    if (!out_nx || !out_ny) return SD4_ERR_INVALID_ARGUMENT;
    if ((r = sd4__line_size(nx, px, levels, out_nx)) != SD4_OK) return r;
    return sd4__line_size(ny, py, levels, out_ny);
}

SD4DEF sd4_result sd4_grid_refine(const double *grid, size_t nx, size_t ny, int dim, double omega, int levels,
                                  const sd4_options *options, double *out, size_t out_capacity)
{
    return sd4__grid(grid, nx, ny, dim, omega, levels, options, out, out_capacity, 0);
}

SD4DEF sd4_result sd4_grid_refine_columns_first(const double *grid, size_t nx, size_t ny, int dim, double omega,
                                                int levels, const sd4_options *options, double *out,
                                                size_t out_capacity)
{
    return sd4__grid(grid, nx, ny, dim, omega, levels, options, out, out_capacity, 1);
}

SD4DEF sd4_result sd4_curve_size(size_t n, int closed, int levels, size_t *out_n)
{
    if (!out_n) return SD4_ERR_INVALID_ARGUMENT;
    return sd4__line_size(n, closed != 0, levels, out_n);
}

/* A curve is a grid of one row; the column direction then has no interval. */
SD4DEF sd4_result sd4_curve_refine(const double *points, size_t n, int dim, double omega, int levels,
                                   const sd4_options *options, double *out, size_t out_capacity)
{
    sd4_options o;
    if (options) o = *options;
    else memset(&o, 0, sizeof o);
    o.end_rule_y = SD4_END_LINEAR;
    if (out_capacity > (size_t)-1 / 64) out_capacity = (size_t)-1 / 64;
    return sd4__grid(points, n, 1, dim, omega, levels, &o, out, out_capacity * (size_t)(dim > 0 ? dim : 1), 0);
}

/* ---------------------------------------------------------------------------------------------
   Section: terrain (paper 001)
   --------------------------------------------------------------------------------------------- */

SD4DEF sd4_result sd4_random_heights(size_t nx, size_t ny, double amplitude, int smooth_passes, uint64_t seed,
                                     const sd4_allocator *allocator, double *out)
{
    sd4_allocator al = sd4__resolve_allocator(allocator);
    double *tmp;
    size_t i, j, n;
    int pass;
    if (!out || nx == 0 || ny == 0 || smooth_passes < 0 || !isfinite(amplitude)) return SD4_ERR_INVALID_ARGUMENT;
    if (nx > (size_t)-1 / ny) return SD4_ERR_TOO_LARGE;
    n = nx * ny;
    for (i = 0; i < n; i++) out[i] = amplitude * sd4__uniform(seed, i, 0);
    if (smooth_passes == 0) return SD4_OK; /* |amplitude| * [0, 1): finite */
    tmp = (double *)sd4__alloc_array(&al, n, sizeof(double));
    if (!tmp) return SD4_ERR_OUT_OF_MEMORY;
    for (pass = 0; pass < smooth_passes; pass++) {
        memcpy(tmp, out, n * sizeof(double));
        for (j = 0; j < ny; j++)
            for (i = 0; i < nx; i++) {
                double sum = 0.0;
                int di, dj;
                for (dj = -1; dj <= 1; dj++)
                    for (di = -1; di <= 1; di++) {
                        size_t x = i, y = j; /* clamped to the border */
                        if (di < 0 && i > 0) x = i - 1;
                        if (di > 0 && i + 1 < nx) x = i + 1;
                        if (dj < 0 && j > 0) y = j - 1;
                        if (dj > 0 && j + 1 < ny) y = j + 1;
                        sum += tmp[y * nx + x];
                    }
                out[j * nx + i] = sum / 9.0;
            }
    }
    sd4__free(&al, tmp);
    return sd4__all_finite(out, n) ? SD4_OK : SD4_ERR_NOT_FINITE; /* the sum of 9 may overflow */
}

SD4DEF sd4_result sd4_terrain_preset(const char *name, sd4_terrain_desc *d)
{
    static const struct { const char *name; double omega, epsilon, sigma, amplitude; int smooth; } presets[] = {
        {"desert", 0.10, 2.0, 0.06, 24.0, 1},
        {"vegetation", 0.18, 3.0, 0.35, 60.0, 0},
        {"mountain5", 0.20, 3.0, 0.20, 120.0, 0},
        {"mountain6", 0.25, 3.0, 0.25, 160.0, 0}};
    size_t k;
    if (!name || !d) return SD4_ERR_INVALID_ARGUMENT;
    for (k = 0; k < sizeof presets / sizeof presets[0]; k++)
        if (strcmp(name, presets[k].name) == 0) {
            memset(d, 0, sizeof *d);
            d->nx = d->ny = 9;
            d->spacing = 64.0;
            d->amplitude = presets[k].amplitude;
            d->smooth_passes = presets[k].smooth;
            d->seed = 1999;
            d->omega = presets[k].omega;
            d->levels = 4;
            d->epsilon = presets[k].epsilon;
            d->sigma = presets[k].sigma;
            return SD4_OK;
        }
    return SD4_ERR_INVALID_ARGUMENT;
}

/* Lattice-point -> vertex index map (open addressing), and the vertex arrays it fills. */
typedef struct sd4__terrain {
    const double *fine;      /* refined heights, NX x NY */
    size_t NX, NY, D;        /* D = finest split depth; lattice step = cell / 2^D */
    double cell;             /* refined grid spacing */
    uint64_t *keys;          /* key + 1, 0 = empty */
    uint32_t *vals;
    size_t mask;
    float *pos;
    size_t nv, cap_v;
    uint32_t *idx;
    float *fn;
    size_t nt;
    uint64_t seed;
    double sigma;
} sd4__terrain;

static double sd4__height_at(const sd4__terrain *t, size_t I, size_t J)
{
    size_t cx = t->NX - 1, cy = t->NY - 1, ci = I >> t->D, cj = J >> t->D;
    double scale = 1.0 / (double)((size_t)1 << t->D), u, v;
    const double *f = t->fine;
    if (ci >= cx) ci = cx - 1;
    if (cj >= cy) cj = cy - 1;
    u = (double)(I - (ci << t->D)) * scale;
    v = (double)(J - (cj << t->D)) * scale;
    return (1 - u) * (1 - v) * f[cj * t->NX + ci] + u * (1 - v) * f[cj * t->NX + ci + 1] +
           (1 - u) * v * f[(cj + 1) * t->NX + ci] + u * v * f[(cj + 1) * t->NX + ci + 1];
}

static uint32_t sd4__vertex(sd4__terrain *t, size_t I, size_t J)
{
    uint64_t key = ((uint64_t)J << 32 | (uint64_t)I) + 1;
    size_t slot = (size_t)sd4__mix(key) & t->mask;
    double lat = t->cell / (double)((size_t)1 << t->D);
    while (t->keys[slot] != 0) {
        if (t->keys[slot] == key) return t->vals[slot];
        slot = (slot + 1) & t->mask;
    }
    t->keys[slot] = key;
    t->vals[slot] = (uint32_t)t->nv;
    t->pos[3 * t->nv + 0] = sd4__to_float((double)I * lat);
    t->pos[3 * t->nv + 1] = sd4__to_float(sd4__height_at(t, I, J));
    t->pos[3 * t->nv + 2] = sd4__to_float((double)J * lat);
    return (uint32_t)t->nv++;
}

/* Normal of the small quad with corners p00 (x0,z0), p10, p01, p11 from its diagonals, perturbed
   by sigma times a Gaussian drawn from the seed and the quad's centre (cI, cJ on the doubled
   lattice). */
static void sd4__quad_normal(const sd4__terrain *t, uint32_t v00, uint32_t v10, uint32_t v01, uint32_t v11,
                             uint64_t cI, uint64_t cJ, float n_out[3])
{
    const float *p00 = t->pos + 3 * (size_t)v00, *p10 = t->pos + 3 * (size_t)v10;
    const float *p01 = t->pos + 3 * (size_t)v01, *p11 = t->pos + 3 * (size_t)v11;
    double a[3], b[3], n[3], m[3], len, g[4];
    int k;
    for (k = 0; k < 3; k++) { a[k] = (double)p01[k] - p10[k]; b[k] = (double)p11[k] - p00[k]; }
    n[0] = a[1] * b[2] - a[2] * b[1];
    n[1] = a[2] * b[0] - a[0] * b[2];
    n[2] = a[0] * b[1] - a[1] * b[0];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0)) { n[0] = 0; n[1] = 1; n[2] = 0; len = 1.0; }
    for (k = 0; k < 3; k++) n[k] /= len;
    if (t->sigma > 0.0) {
        uint64_t q = cJ << 32 ^ cI;
        for (k = 0; k < 4; k += 2) { /* Box-Muller: two pairs of uniforms give four Gaussians */
            double u1 = 1.0 - sd4__uniform(t->seed, q, (uint64_t)k + 1), u2 = sd4__uniform(t->seed, q, (uint64_t)k + 2);
            double r = sqrt(-2.0 * log(u1));
            g[k] = r * cos(6.283185307179586 * u2);
            g[k + 1] = r * sin(6.283185307179586 * u2);
        }
        for (k = 0; k < 3; k++) m[k] = n[k] + t->sigma * g[k];
        len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (len > 0.0 && (m[0] * n[0] + m[1] * n[1] + m[2] * n[2]) > 0.0)
            for (k = 0; k < 3; k++) n[k] = m[k] / len;
    }
    for (k = 0; k < 3; k++) n_out[k] = (float)n[k];
}

static void sd4__emit(sd4__terrain *t, uint32_t a, uint32_t b, uint32_t c, const float n[3])
{
    t->idx[3 * t->nt + 0] = a;
    t->idx[3 * t->nt + 1] = b;
    t->idx[3 * t->nt + 2] = c;
    memcpy(t->fn + 3 * t->nt, n, 3 * sizeof(float));
    t->nt++;
}

/* Triangles of one refined cell split to depth dc; edge depths dl, dr (x = x0, x1 sides), db, dt
   (z = z0, z1 sides). Returns the triangle count; emits them when t->idx is set. */
static size_t sd4__cell(sd4__terrain *t, size_t ci, size_t cj, size_t dc, size_t dl, size_t dr, size_t db, size_t dt)
{
    size_t n = (size_t)1 << dc, step = (size_t)1 << (t->D - dc), a, b, count = 0;
    size_t I0 = ci << t->D, J0 = cj << t->D;
    for (b = 0; b < n; b++)
        for (a = 0; a < n; a++) {
            size_t x0 = I0 + a * step, z0 = J0 + b * step, x1 = x0 + step, z1 = z0 + step;
            size_t sl = (a == 0 && dl > dc) ? (size_t)1 << (t->D - dl) : step;
            size_t sr = (a == n - 1 && dr > dc) ? (size_t)1 << (t->D - dr) : step;
            size_t sb = (b == 0 && db > dc) ? (size_t)1 << (t->D - db) : step;
            size_t st = (b == n - 1 && dt > dc) ? (size_t)1 << (t->D - dt) : step;
            int plain = sl == step && sr == step && sb == step && st == step;
            size_t ring = plain ? 4 : step / sl + step / sr + step / sb + step / st;
            count += plain ? 2 : ring;
            if (t->idx) {
                uint32_t v00 = sd4__vertex(t, x0, z0), v01 = sd4__vertex(t, x0, z1);
                uint32_t v11 = sd4__vertex(t, x1, z1), v10 = sd4__vertex(t, x1, z0), first = 0, prev = 0, centre, cur;
                float nrm[3];
                size_t k;
                sd4__quad_normal(t, v00, v10, v01, v11, 2 * x0 + step, 2 * z0 + step, nrm);
                if (plain) {
                    sd4__emit(t, v00, v01, v11, nrm);
                    sd4__emit(t, v00, v11, v10, nrm);
                    continue;
                }
                /* fan from the centre around the boundary, counter-clockwise seen from +y:
                   up the x0 side, along the z1 side, down the x1 side, back along z0 */
                centre = sd4__vertex(t, x0 + step / 2, z0 + step / 2);
                for (k = 0; k < ring; k++) {
                    size_t e = k, I, J;
                    if (e < step / sl) { I = x0; J = z0 + e * sl; }
                    else if ((e -= step / sl) < step / st) { I = x0 + e * st; J = z1; }
                    else if ((e -= step / st) < step / sr) { I = x1; J = z1 - e * sr; }
                    else { e -= step / sr; I = x1 - e * sb; J = z0; }
                    cur = sd4__vertex(t, I, J);
                    if (k == 0) first = cur;
                    else sd4__emit(t, centre, prev, cur, nrm);
                    prev = cur;
                }
                sd4__emit(t, centre, prev, first, nrm);
            }
        }
    return count;
}

/* The split depth of each refined quad (the smallest d with rho / 2^d <= epsilon, at most
   max_split; rho its longest edge) into dcell, and of each edge (the larger of its quads') into
   deh (horizontal, cx x NY) and dev (vertical, NX x cy); returns the largest. */
static size_t sd4__split_depths(const double *fine, size_t NX, size_t NY, double cell, double epsilon, int max_split,
                                unsigned char *dcell, unsigned char *deh, unsigned char *dev)
{
    size_t cx = NX - 1, cy = NY - 1, i, j, D = 0;
    for (j = 0; j < cy; j++)
        for (i = 0; i < cx; i++) {
            const double *f = fine + j * NX + i;
            double e[4], rho = 0.0;
            int k, dep = 0;
            e[0] = f[1] - f[0];
            e[1] = f[NX + 1] - f[1];
            e[2] = f[NX + 1] - f[NX];
            e[3] = f[NX] - f[0];
            for (k = 0; k < 4; k++) {
                double len = sqrt(cell * cell + e[k] * e[k]);
                if (len > rho) rho = len;
            }
            if (epsilon > 0.0)
                while (rho > epsilon && dep < max_split) { rho *= 0.5; dep++; }
            dcell[j * cx + i] = (unsigned char)dep;
            if ((size_t)dep > D) D = (size_t)dep;
        }
    for (j = 0; j < NY; j++)
        for (i = 0; i < cx; i++) {
            unsigned char a = j > 0 ? dcell[(j - 1) * cx + i] : 0, b = j < cy ? dcell[j * cx + i] : 0;
            deh[j * cx + i] = a > b ? a : b;
        }
    for (j = 0; j < cy; j++)
        for (i = 0; i < NX; i++) {
            unsigned char a = i > 0 ? dcell[j * cx + i - 1] : 0, b = i < cx ? dcell[j * cx + i] : 0;
            dev[j * NX + i] = a > b ? a : b;
        }
    return D;
}

/* the mesh of t into out (t keeps none of it) */
static void sd4__terrain_hand_over(sd4__terrain *t, const sd4_allocator *al, sd4_mesh *out)
{
    out->positions = t->pos;
    out->vertex_count = t->nv;
    out->indices = t->idx;
    out->triangle_count = t->nt;
    out->face_normals = t->fn;
    out->allocator = *al;
    t->pos = NULL;
    t->idx = NULL;
    t->fn = NULL;
}

/* what t still holds */
static void sd4__terrain_free(const sd4_allocator *al, sd4__terrain *t)
{
    sd4__free(al, t->keys);
    sd4__free(al, t->vals);
    sd4__free(al, t->pos);
    sd4__free(al, t->idx);
    sd4__free(al, t->fn);
}

/* 1 when the n quads of depths dcell make more than max_tris triangles for certain: every small
   quad is at least two (a divergent w or a tiny epsilon would otherwise run for minutes before
   the exact count) */
static int sd4__least_triangles_above(const unsigned char *dcell, size_t n, size_t max_tris)
{
    size_t j, tris = 0;
    for (j = 0; j < n; j++) {
        size_t least = (size_t)2 << (2 * dcell[j]);
        if (least > max_tris - tris) return 1;
        tris += least;
    }
    return 0;
}

SD4DEF sd4_result sd4_terrain_build(const sd4_terrain_desc *d, sd4_mesh *out)
{
    sd4_allocator al;
    sd4_options o;
    sd4__terrain t;
    double *control = NULL, *fine = NULL, h0, cell;
    unsigned char *dcell = NULL, *deh = NULL, *dev = NULL;
    size_t nx, ny, NX, NY, cx, cy, i, j, tris = 0, vbound = 0, cap, max_tris;
    int levels, max_split;
    sd4_result r = SD4_OK;
    if (!out) return SD4_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!d) return SD4_ERR_INVALID_ARGUMENT;
    al = sd4__resolve_allocator(d->allocator);
    memset(&t, 0, sizeof t);
    nx = d->nx ? d->nx : 9;
    ny = d->ny ? d->ny : 9;
    h0 = d->spacing != 0.0 ? d->spacing : 64.0;
    levels = d->levels;
    max_split = d->max_split ? d->max_split : 10;
    max_tris = d->max_triangles ? d->max_triangles : (size_t)1 << 24;
    if (nx < 2 || ny < 2 || nx > 65536 || ny > 65536 || levels < 0 || levels > 10 || max_split < 0 || max_split > 10 ||
        !(h0 > 0.0) || !isfinite(h0) || !isfinite(d->epsilon) || !(d->sigma >= 0.0) || !isfinite(d->sigma) ||
        !isfinite(d->omega) || (d->border != SD4_END_LINEAR && d->border != SD4_END_CUBIC))
        return SD4_ERR_INVALID_ARGUMENT;
    memset(&o, 0, sizeof o);
    o.end_rule = o.end_rule_y = d->border;
    o.omega_convention = d->omega_convention;
    o.allocator = &al;
    if ((r = sd4_grid_size(nx, ny, levels, &o, &NX, &NY)) != SD4_OK) return r;
    if (((NX - 1) << max_split) >= 0xffffffffu || ((NY - 1) << max_split) >= 0xffffffffu) return SD4_ERR_TOO_LARGE;
    control = (double *)sd4__alloc_array(&al, nx * ny, sizeof(double));
    fine = (double *)sd4__alloc_array(&al, NX * NY, sizeof(double));
    cx = NX - 1;
    cy = NY - 1;
    dcell = (unsigned char *)sd4__alloc_array(&al, cx * cy, 1);
    deh = (unsigned char *)sd4__alloc_array(&al, cx * NY, 1);
    dev = (unsigned char *)sd4__alloc_array(&al, NX * cy, 1);
    if (!control || !fine || !dcell || !deh || !dev) { r = SD4_ERR_OUT_OF_MEMORY; goto done; }
    /* (1) control heights */
    if (d->heights) memcpy(control, d->heights, nx * ny * sizeof(double));
    else if ((r = sd4_random_heights(nx, ny, d->amplitude != 0.0 ? d->amplitude : 60.0, d->smooth_passes, d->seed,
                                     &al, control)) != SD4_OK)
        goto done;
    if (d->progress && d->progress(d->progress_user, 0.1f)) { r = SD4_CANCELLED; goto done; }
    /* (2) the four-point scheme on the heights */
    if ((r = sd4_grid_refine(control, nx, ny, 1, d->omega, levels, &o, fine, NX * NY)) != SD4_OK) goto done;
    if (d->progress && d->progress(d->progress_user, 0.4f)) { r = SD4_CANCELLED; goto done; }
    /* (3) split depth per refined quad and per edge; a mesh above max_triangles refused early */
    cell = h0 / (double)((size_t)1 << levels);
    t.D = sd4__split_depths(fine, NX, NY, cell, d->epsilon, max_split, dcell, deh, dev);
    if (sd4__least_triangles_above(dcell, cx * cy, max_tris)) { r = SD4_ERR_TOO_LARGE; goto done; }
    tris = 0;
    /* count triangles and bound the vertices */
    t.fine = fine;
    t.NX = NX;
    t.NY = NY;
    t.cell = cell;
    t.seed = d->seed;
    t.sigma = d->sigma;
    for (j = 0; j < cy; j++)
        for (i = 0; i < cx; i++) {
            size_t dc = dcell[j * cx + i], n = (size_t)1 << dc;
            tris += sd4__cell(&t, i, j, dc, dev[j * NX + i], dev[j * NX + i + 1], deh[j * cx + i], deh[(j + 1) * cx + i]);
            vbound += (n + 1) * (n + 1) + 4 * n + ((size_t)1 << dev[j * NX + i]) + ((size_t)1 << dev[j * NX + i + 1]) +
                      ((size_t)1 << deh[j * cx + i]) + ((size_t)1 << deh[(j + 1) * cx + i]);
        }
    if (vbound >= 0xffffffffu || tris > ((size_t)-1) / 64 || tris > max_tris) { r = SD4_ERR_TOO_LARGE; goto done; }
    cap = 16;
    while (cap < 2 * vbound) cap *= 2;
    t.mask = cap - 1;
    t.keys = (uint64_t *)sd4__alloc_array(&al, cap, sizeof(uint64_t));
    t.vals = (uint32_t *)sd4__alloc_array(&al, cap, sizeof(uint32_t));
    t.pos = (float *)sd4__alloc_array(&al, vbound, 3 * sizeof(float));
    t.idx = (uint32_t *)sd4__alloc_array(&al, tris, 3 * sizeof(uint32_t));
    t.fn = (float *)sd4__alloc_array(&al, tris, 3 * sizeof(float));
    if (!t.keys || !t.vals || !t.pos || !t.idx || !t.fn) { r = SD4_ERR_OUT_OF_MEMORY; goto done; }
    memset(t.keys, 0, cap * sizeof(uint64_t));
    if (d->progress && d->progress(d->progress_user, 0.6f)) { r = SD4_CANCELLED; goto done; }
    /* (4) emit the small quads with their perturbed normals */
    for (j = 0; j < cy; j++)
        for (i = 0; i < cx; i++)
            sd4__cell(&t, i, j, dcell[j * cx + i], dev[j * NX + i], dev[j * NX + i + 1], deh[j * cx + i],
                      deh[(j + 1) * cx + i]);
    if (!sd4__all_finite_f(t.pos, 3 * t.nv) || !sd4__all_finite_f(t.fn, 3 * t.nt)) { r = SD4_ERR_NOT_FINITE; goto done; }
    sd4__terrain_hand_over(&t, &al, out);
    if (d->progress && d->progress(d->progress_user, 1.0f)) { sd4_free_mesh(out); r = SD4_CANCELLED; }
done:
    sd4__free(&al, control);
    sd4__free(&al, fine);
    sd4__free(&al, dcell);
    sd4__free(&al, deh);
    sd4__free(&al, dev);
    sd4__terrain_free(&al, &t);
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Section: butterfly on triangle meshes
   Half-edge h = 3 t + k runs from corner k to corner k + 1 of triangle t. Connectivity is
   rebuilt at every level from the index array alone: outgoing half-edges grouped by vertex
   (with their end vertex beside them, so the twin search reads memory in order), twins, fans.
   --------------------------------------------------------------------------------------------- */

/* SD4_COUNT_OPS(n): a test hook (default: nothing) told the steps of the connectivity searches
   and of the stencils, so that a test can check the work is linear in a vertex's valence */
#ifndef SD4_COUNT_OPS
#define SD4_COUNT_OPS(n) ((void)0)
#endif

#define SD4__NONE 0xffffffffu     /* no twin: boundary edge; no new vertex */
#define SD4__NONMANIFOLD 0xfffffffeu
#define SD4__VBOUNDARY 1u
#define SD4__VNONMANIFOLD 2u

typedef struct sd4__level {
    const float *pos;
    const uint32_t *tri;
    size_t nv, nt;
    uint32_t *off;      /* nv + 1: outgoing half-edges of v at out[off[v] .. off[v + 1]) */
    uint32_t *out;      /* half-edge ids grouped by origin */
    uint32_t *dest;     /* end vertex of out[k] */
    uint32_t *twin;     /* per half-edge: twin, SD4__NONE or SD4__NONMANIFOLD */
    uint32_t *eid;      /* per half-edge: index of its new vertex or SD4__NONE */
    uint32_t *bprev;    /* per vertex on the boundary: the vertex before it along the boundary */
    uint32_t *bnext;    /* ... and after it */
    uint32_t *valence;
    unsigned char *vflag;
    unsigned char *frozen; /* per triangle */
    uint32_t *rot;      /* per half-edge out of a vertex of valence >= SD4__FOURIER: its place in the fan */
    uint32_t *slot;     /* per vertex: its Fourier sums' index in four, or SD4__NONE */
    double *four;       /* 15 a vertex of valence >= SD4__FOURIER: sum e_j, sum (cos, sin)(2 pi j/K) e_j, same at 4 pi */
} sd4__level;

/* from this valence on, ZSS stencils are evaluated from three Fourier sums per vertex (see
   sd4__extraordinary): work linear in the valence instead of quadratic */
#define SD4__FOURIER 64u

static uint32_t sd4__next(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
static uint32_t sd4__prev(uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

/* The number of half-edges a -> b (a's group is sorted by end vertex: a binary search, then the
   run of equal ends); *last = the last of them. */
static uint32_t sd4__run(const sd4__level *L, uint32_t a, uint32_t b, uint32_t *last)
{
    uint32_t lo = L->off[a], hi = L->off[a + 1], n = 0;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        SD4_COUNT_OPS(1);
        if (L->dest[mid] < b) lo = mid + 1;
        else hi = mid;
    }
    for (; lo < L->off[a + 1] && L->dest[lo] == b; lo++, n++) { *last = L->out[lo]; SD4_COUNT_OPS(1); }
    return n;
}

/* For each closed manifold fan of valence K >= SD4__FOURIER: its half-edges' places j in the
   fan (rotating as sd4__extraordinary does) and F0 = sum e_j, F1 = sum (cos, sin)(2 pi j / K) e_j,
   F2 the same at 4 pi j / K, in L->four. */
static void sd4__fourier_sums(sd4__level *L)
{
    size_t v, n = 0;
    for (v = 0; v < L->nv; v++) {
        uint32_t K = L->valence[v], j, hh;
        double *F;
        L->slot[v] = SD4__NONE;
        if (K < SD4__FOURIER || L->vflag[v] || L->off[v + 1] - L->off[v] != K) continue;
        L->slot[v] = (uint32_t)n;
        F = L->four + 15 * n++;
        memset(F, 0, 15 * sizeof(double));
        for (j = 0, hh = L->out[L->off[v]]; j < K; j++, hh = L->twin[sd4__prev(hh)]) {
            const float *e = L->pos + 3 * (size_t)L->tri[sd4__next(hh)];
            double x = 6.283185307179586 * (double)j / (double)K, c1 = cos(x), s1 = sin(x), c2 = cos(2.0 * x), s2 = sin(2.0 * x);
            int k;
            SD4_COUNT_OPS(1);
            L->rot[hh] = j;
            for (k = 0; k < 3; k++) {
                F[k] += e[k];
                F[3 + k] += c1 * e[k]; F[6 + k] += s1 * e[k];
                F[9 + k] += c2 * e[k]; F[12 + k] += s2 * e[k];
            }
        }
    }
}

static void sd4__topology(sd4__level *L)
{
    size_t nh = 3 * L->nt, v, h, k;
    const uint32_t *T = L->tri;
    uint32_t *by_dest = L->eid; /* scratch until the level numbers its new vertices */
    /* half-edges by end vertex, then (stably) by origin: each origin's group sorted by end */
    memset(L->off, 0, (L->nv + 1) * sizeof(uint32_t));
    for (h = 0; h < nh; h++) L->off[T[sd4__next((uint32_t)h)] + 1]++;
    for (v = 0; v < L->nv; v++) L->off[v + 1] += L->off[v];
    memcpy(L->valence, L->off, L->nv * sizeof(uint32_t)); /* L->valence is the fill cursor here */
    for (h = 0; h < nh; h++) by_dest[L->valence[T[sd4__next((uint32_t)h)]]++] = (uint32_t)h;
    memset(L->off, 0, (L->nv + 1) * sizeof(uint32_t));
    for (h = 0; h < nh; h++) L->off[T[h] + 1]++;
    for (v = 0; v < L->nv; v++) L->off[v + 1] += L->off[v];
    memcpy(L->valence, L->off, L->nv * sizeof(uint32_t));
    for (k = 0; k < nh; k++) {
        uint32_t g = by_dest[k], a = T[g], s = L->valence[a]++;
        L->out[s] = g;
        L->dest[s] = T[sd4__next(g)];
    }
    /* twins: h = a -> b is manifold when it is the only a -> b and at most one b -> a exists */
    for (h = 0; h < nh; h++) {
        uint32_t a = T[h], b = T[sd4__next((uint32_t)h)], same, opp, g;
        if (a == b) { L->twin[h] = SD4__NONMANIFOLD; continue; }
        same = sd4__run(L, a, b, &g);
        opp = sd4__run(L, b, a, &g);
        if (same != 1 || opp > 1) L->twin[h] = SD4__NONMANIFOLD;
        else L->twin[h] = opp ? g : SD4__NONE;
    }
    /* fans: a vertex is manifold when one walk around it meets all its outgoing half-edges */
    for (v = 0; v < L->nv; v++) {
        uint32_t deg = L->off[v + 1] - L->off[v], count = 1, h0, hh, t, flag = 0;
        L->bprev[v] = L->bnext[v] = SD4__NONE;
        L->valence[v] = deg;
        if (deg == 0) { L->vflag[v] = 0; continue; }
        h0 = L->out[L->off[v]];
        hh = h0;
        for (;;) { /* rotate: the half-edge into v in this triangle, then its twin */
            t = L->twin[sd4__prev(hh)];
            if (t == SD4__NONMANIFOLD) { flag |= SD4__VNONMANIFOLD; break; }
            if (t == SD4__NONE) { flag |= SD4__VBOUNDARY; L->bprev[v] = T[sd4__prev(hh)]; break; }
            if (t == h0 || count > deg) break;
            hh = t;
            count++;
            SD4_COUNT_OPS(1);
        }
        if (flag) { /* open fan: walk the other way from h0 */
            hh = h0;
            for (;;) {
                t = L->twin[hh];
                if (t == SD4__NONMANIFOLD) { flag |= SD4__VNONMANIFOLD; break; }
                if (t == SD4__NONE) { L->bnext[v] = T[sd4__next(hh)]; break; }
                hh = sd4__next(t);
                if (hh == h0 || count > deg) break;
                count++;
                SD4_COUNT_OPS(1);
            }
            L->valence[v] = deg + 1;
        }
        if (count != deg) flag |= SD4__VNONMANIFOLD;
        L->vflag[v] = (unsigned char)flag;
    }
    sd4__fourier_sums(L);
    for (h = 0; h < L->nt; h++) {
        unsigned char fz = 0;
        for (k = 0; k < 3; k++)
            if (L->twin[3 * h + k] == SD4__NONMANIFOLD || (L->vflag[T[3 * h + k]] & SD4__VNONMANIFOLD)) fz = 1;
        L->frozen[h] = fz;
    }
}

/* ZSS 1996 weight of the j-th neighbour (j = 0: the other end of the edge) of a vertex of
   valence K; the vertex itself gets 1 minus their sum (3/4). */
static double sd4__zss_weight(uint32_t K, uint32_t j)
{
    static const double k3[3] = {5.0 / 12.0, -1.0 / 12.0, -1.0 / 12.0}, k4[4] = {3.0 / 8.0, 0.0, -1.0 / 8.0, 0.0};
    double x;
    if (K == 3) return k3[j];
    if (K == 4) return k4[j];
    x = 6.283185307179586 * (double)j / (double)K;
    return (0.25 + cos(x) + 0.5 * cos(2.0 * x)) / (double)K;
}

static void sd4__acc(double p[3], const float *q, double w)
{
    p[0] += w * (double)q[0];
    p[1] += w * (double)q[1];
    p[2] += w * (double)q[2];
}

/* The stencil of ZSS around the extraordinary interior vertex v, starting at half-edge hv from
   v; adds the point to p. */
static void sd4__extraordinary(const sd4__level *L, uint32_t v, uint32_t hv, const double *wtab, double p[3])
{
    uint32_t K = L->valence[v], j, hh = hv;
    double sum = 0.0, wj;
    if (K >= SD4__FOURIER && L->slot[v] != SD4__NONE) {
        /* s_j = (1/4 + cos(2 pi j/K) + 1/2 cos(4 pi j/K)) / K is a circular convolution with three
           frequencies: sum_j s_j e_(m+j) = (F0 / 4 + Re(conj(z^m) F1) + Re(conj(z^2m) F2) / 2) / K,
           z = exp(2 pi i / K), m = hv's place in the fan; the weights sum to exactly 1/4 */
        const double *F = L->four + 15 * (size_t)L->slot[v];
        double x = 6.283185307179586 * (double)L->rot[hv] / (double)K, c1 = cos(x), s1 = sin(x), c2 = cos(2.0 * x), s2 = sin(2.0 * x);
        int k;
        SD4_COUNT_OPS(1);
        for (k = 0; k < 3; k++)
            p[k] += 0.75 * (double)L->pos[3 * (size_t)v + k] +
                    (0.25 * F[k] + c1 * F[3 + k] + s1 * F[6 + k] + 0.5 * (c2 * F[9 + k] + s2 * F[12 + k])) / (double)K;
        return;
    }
    for (j = 0; j < K; j++) {
        SD4_COUNT_OPS(1);
        wj = K < 32 ? wtab[K * 32 + j] : sd4__zss_weight(K, j);
        sd4__acc(p, L->pos + 3 * (size_t)L->tri[sd4__next(hh)], wj);
        sum += wj;
        hh = L->twin[sd4__prev(hh)];
        if (hh >= SD4__NONMANIFOLD) break; /* cannot happen on a closed manifold fan */
    }
    sd4__acc(p, L->pos + 3 * (size_t)v, 1.0 - sum);
}

/* The vertex beyond the edge of half-edge e (in e's triangle with third vertex z), or its mirror
   image x + y - z when the edge has no second triangle. */
static void sd4__wing(const sd4__level *L, uint32_t e, double p[3], double w)
{
    uint32_t t = L->twin[e];
    if (t < SD4__NONMANIFOLD) {
        sd4__acc(p, L->pos + 3 * (size_t)L->tri[sd4__prev(t)], w);
    } else {
        sd4__acc(p, L->pos + 3 * (size_t)L->tri[e], w);
        sd4__acc(p, L->pos + 3 * (size_t)L->tri[sd4__next(e)], w);
        sd4__acc(p, L->pos + 3 * (size_t)L->tri[sd4__prev(e)], -w);
    }
}

static void sd4__edge_point(const sd4__level *L, uint32_t h, double w, const double *wtab, float out[3])
{
    const uint32_t *T = L->tri;
    uint32_t a = T[h], b = T[sd4__next(h)], t = L->twin[h];
    double p[3] = {0.0, 0.0, 0.0};
    if (t == SD4__NONE) { /* boundary edge: four-point rule along the boundary loop */
        sd4__acc(p, L->pos + 3 * (size_t)a, 0.5 + w);
        sd4__acc(p, L->pos + 3 * (size_t)b, 0.5 + w);
        if (L->bprev[a] != SD4__NONE && L->bnext[b] != SD4__NONE) {
            sd4__acc(p, L->pos + 3 * (size_t)L->bprev[a], -w);
            sd4__acc(p, L->pos + 3 * (size_t)L->bnext[b], -w);
        } else { /* cannot happen for a manifold boundary: linear ghosts, i.e. the midpoint */
            sd4__acc(p, L->pos + 3 * (size_t)a, -w);
            sd4__acc(p, L->pos + 3 * (size_t)b, -w);
        }
    } else {
        int exa = !(L->vflag[a] & SD4__VBOUNDARY) && L->valence[a] != 6;
        int exb = !(L->vflag[b] & SD4__VBOUNDARY) && L->valence[b] != 6;
        if (!exa && !exb) { /* the butterfly of DLG 1990 */
            sd4__acc(p, L->pos + 3 * (size_t)a, 0.5);
            sd4__acc(p, L->pos + 3 * (size_t)b, 0.5);
            sd4__acc(p, L->pos + 3 * (size_t)T[sd4__prev(h)], 2.0 * w);
            sd4__acc(p, L->pos + 3 * (size_t)T[sd4__prev(t)], 2.0 * w);
            sd4__wing(L, sd4__next(h), p, -w);
            sd4__wing(L, sd4__prev(h), p, -w);
            sd4__wing(L, sd4__next(t), p, -w);
            sd4__wing(L, sd4__prev(t), p, -w);
        } else {
            if (exa) sd4__extraordinary(L, a, h, wtab, p);
            if (exb) sd4__extraordinary(L, b, t, wtab, p);
            if (exa && exb) { p[0] *= 0.5; p[1] *= 0.5; p[2] *= 0.5; }
        }
    }
    out[0] = sd4__to_float(p[0]);
    out[1] = sd4__to_float(p[1]);
    out[2] = sd4__to_float(p[2]);
}

/* One level: L (with its arrays allocated) -> new positions and triangles (allocated here). */
static sd4_result sd4__butterfly_level(sd4__level *L, double w, const double *wtab, const sd4_allocator *al,
                                       float **pos_out, size_t *nv_out, uint32_t **tri_out, size_t *nt_out)
{
    size_t nh = 3 * L->nt, h, f, ne = 0, nt2 = 0, nv2;
    float *P;
    uint32_t *T2;
    sd4__topology(L);
    for (h = 0; h < nh; h++) {
        uint32_t t = L->twin[h];
        if (L->frozen[h / 3] || t == SD4__NONMANIFOLD || (t != SD4__NONE && L->frozen[t / 3])) L->eid[h] = SD4__NONE;
        else if (t != SD4__NONE && t < h) L->eid[h] = L->eid[t];
        else L->eid[h] = (uint32_t)(L->nv + ne++);
    }
    nv2 = L->nv + ne;
    if (nv2 >= SD4__NONMANIFOLD) return SD4_ERR_TOO_LARGE;
    for (f = 0; f < L->nt; f++) {
        int s = (L->eid[3 * f] != SD4__NONE) + (L->eid[3 * f + 1] != SD4__NONE) + (L->eid[3 * f + 2] != SD4__NONE);
        nt2 += (size_t)s + 1;
    }
    P = (float *)sd4__alloc_array(al, nv2, 3 * sizeof(float));
    T2 = (uint32_t *)sd4__alloc_array(al, nt2, 3 * sizeof(uint32_t));
    if (!P || !T2) {
        sd4__free(al, P);
        sd4__free(al, T2);
        return SD4_ERR_OUT_OF_MEMORY;
    }
    memcpy(P, L->pos, L->nv * 3 * sizeof(float));
    for (h = 0; h < nh; h++) {
        uint32_t e = L->eid[h], t = L->twin[h];
        if (e != SD4__NONE && (t >= SD4__NONMANIFOLD || t > h)) sd4__edge_point(L, (uint32_t)h, w, wtab, P + 3 * (size_t)e);
    }
    nt2 = 0;
    for (f = 0; f < L->nt; f++) {
        const uint32_t *v = L->tri + 3 * f, *m = L->eid + 3 * f;
        uint32_t *o = T2 + 3 * nt2;
        int s = (m[0] != SD4__NONE) + (m[1] != SD4__NONE) + (m[2] != SD4__NONE), r;
        if (s == 3) {
            uint32_t q[12] = {v[0], m[0], m[2], m[0], v[1], m[1], m[2], m[1], v[2], m[0], m[1], m[2]};
            memcpy(o, q, sizeof q);
        } else if (s == 0) {
            memcpy(o, v, 3 * sizeof(uint32_t));
        } else if (s == 1) { /* split edge r: two triangles */
            for (r = 0; m[r] == SD4__NONE; r++) {}
            {
                uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3], q[6] = {a, m[r], c, m[r], b, c};
                memcpy(o, q, sizeof q);
            }
        } else { /* unsplit edge k: rotate it to position 2, three triangles */
            int k;
            for (k = 0; m[k] != SD4__NONE; k++) {}
            r = (k + 1) % 3;
            {
                uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3], mab = m[r], mbc = m[(r + 1) % 3];
                uint32_t q[9] = {mab, b, mbc, a, mab, mbc, a, mbc, c};
                memcpy(o, q, sizeof q);
            }
        }
        nt2 += (size_t)s + 1;
    }
    *pos_out = P;
    *nv_out = nv2;
    *tri_out = T2;
    *nt_out = nt2;
    return SD4_OK;
}

static void sd4__level_free(sd4__level *L, const sd4_allocator *al)
{
    sd4__free(al, L->off);
    sd4__free(al, L->out);
    sd4__free(al, L->dest);
    sd4__free(al, L->twin);
    sd4__free(al, L->eid);
    sd4__free(al, L->bprev);
    sd4__free(al, L->bnext);
    sd4__free(al, L->valence);
    sd4__free(al, L->vflag);
    sd4__free(al, L->frozen);
    sd4__free(al, L->rot);
    sd4__free(al, L->slot);
    sd4__free(al, L->four);
}

static sd4_result sd4__level_alloc(sd4__level *L, const sd4_allocator *al)
{
    size_t nh = 3 * L->nt;
    L->off = (uint32_t *)sd4__alloc_array(al, L->nv + 1, sizeof(uint32_t));
    L->out = (uint32_t *)sd4__alloc_array(al, nh, sizeof(uint32_t));
    L->dest = (uint32_t *)sd4__alloc_array(al, nh, sizeof(uint32_t));
    L->twin = (uint32_t *)sd4__alloc_array(al, nh, sizeof(uint32_t));
    L->eid = (uint32_t *)sd4__alloc_array(al, nh, sizeof(uint32_t));
    L->bprev = (uint32_t *)sd4__alloc_array(al, L->nv, sizeof(uint32_t));
    L->bnext = (uint32_t *)sd4__alloc_array(al, L->nv, sizeof(uint32_t));
    L->valence = (uint32_t *)sd4__alloc_array(al, L->nv, sizeof(uint32_t));
    L->vflag = (unsigned char *)sd4__alloc_array(al, L->nv, 1);
    L->frozen = (unsigned char *)sd4__alloc_array(al, L->nt, 1);
    L->rot = (uint32_t *)sd4__alloc_array(al, nh, sizeof(uint32_t));
    L->slot = (uint32_t *)sd4__alloc_array(al, L->nv, sizeof(uint32_t));
    L->four = (double *)sd4__alloc_array(al, nh / SD4__FOURIER + 1, 15 * sizeof(double));
    if (!L->off || !L->out || !L->dest || !L->twin || !L->eid || !L->bprev || !L->bnext || !L->valence || !L->vflag ||
        !L->frozen || !L->rot || !L->slot || !L->four)
        return SD4_ERR_OUT_OF_MEMORY;
    return SD4_OK;
}

SD4DEF sd4_result sd4_butterfly(const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, int levels, double w, const sd4_options *options,
                                sd4_mesh *out)
{
    sd4_options def;
    sd4_allocator al;
    const sd4_options *o = options;
    float *pos = NULL;
    uint32_t *tri = NULL;
    size_t nv = vertex_count, nt = triangle_count, i;
    double wtab[32 * 32];
    int lev;
    sd4_result r = SD4_OK;
    if (!out) return SD4_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!o) { memset(&def, 0, sizeof def); o = &def; }
    al = sd4__resolve_allocator(o->allocator);
    if (!positions || !indices || levels < 1 || levels > 8 || !isfinite(w) || vertex_count == 0)
        return SD4_ERR_INVALID_ARGUMENT;
    if (vertex_count >= SD4__NONMANIFOLD || triangle_count >= 0x55555555u) return SD4_ERR_TOO_LARGE;
    for (i = 0; i < 3 * nt; i++)
        if (indices[i] >= vertex_count) return SD4_ERR_BAD_INDEX;
    for (i = 0; i < 3 * nv; i++)
        if (!isfinite(positions[i])) return SD4_ERR_BAD_POSITION;
    if (o->omega_convention == SD4_OMEGA_HALF) w *= 0.5;
    for (i = 0; i < 32 * 32; i++) {
        uint32_t K = (uint32_t)(i / 32), j = (uint32_t)(i % 32);
        wtab[i] = (K >= 1 && j < K) ? sd4__zss_weight(K, j) : 0.0;
    }
    for (lev = 0; lev < levels; lev++) {
        sd4__level L;
        float *pos2 = NULL;
        uint32_t *tri2 = NULL;
        size_t nv2 = 0, nt2 = 0;
        if (o->progress && o->progress(o->progress_user, (float)lev / (float)levels)) { r = SD4_CANCELLED; break; }
        memset(&L, 0, sizeof L);
        L.pos = pos ? pos : positions;
        L.tri = tri ? tri : indices;
        L.nv = nv;
        L.nt = nt;
        if (3 * nt >= SD4__NONMANIFOLD) r = SD4_ERR_TOO_LARGE;
        else if ((r = sd4__level_alloc(&L, &al)) == SD4_OK)
            r = sd4__butterfly_level(&L, w, wtab, &al, &pos2, &nv2, &tri2, &nt2);
        sd4__level_free(&L, &al);
        if (r != SD4_OK) break;
        sd4__free(&al, pos);
        sd4__free(&al, tri);
        pos = pos2;
        tri = tri2;
        nv = nv2;
        nt = nt2;
    }
    if (r == SD4_OK && !sd4__all_finite_f(pos, 3 * nv)) r = SD4_ERR_NOT_FINITE; /* a large w overflows float */
    if (r == SD4_OK && o->progress && o->progress(o->progress_user, 1.0f)) r = SD4_CANCELLED;
    if (r != SD4_OK) {
        sd4__free(&al, pos);
        sd4__free(&al, tri);
        return r;
    }
    out->positions = pos;
    out->vertex_count = nv;
    out->indices = tri;
    out->triangle_count = nt;
    out->allocator = al;
    return SD4_OK;
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* SD4_IMPLEMENTATION_DONE */
#endif /* SD4_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under two licences; choose whichever you prefer.

------------------------------------------------------------------------------
ALTERNATIVE A - MIT License

Copyright (c) 2026 the detailed-surface graphics headers authors

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
ALTERNATIVE B - Public Domain (www.unlicense.org)

This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.

In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication for the benefit of the public at large and to
the detriment of our heirs and successors. We intend this dedication to be an
overt act of relinquishment in perpetuity of all present and future rights to
this software under copyright law.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN
ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION
WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
*/
