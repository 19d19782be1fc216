/* erosion.h - v0.1 - MIT licence or public domain (see end of file)
   Wind erosion and weathering of displacement-mapped surfaces and height fields (paper 000, part B:
   Chuang et al., NSC 96-2628-E-009-160-MY3, section 4.2).

   HOW TO USE (in ten lines)
       // in exactly one C or C++ file, #define ERO_IMPLEMENTATION before #include "erosion.h"
       ero_grid g = ero_heightfield_grid(512, 512, height, 0.01f, 1);   // 5.12 x 5.12, tiling
       // or ero_surface_grid(w, h, pos, nrm, disp, area, valid, nbr, nbr_rot): a displacement map
       ero_options o = ero_default_options();
       o.wind[0] = 1; o.wind[2] = -0.5f;                     // the direction the wind blows toward
       ero_material soft = {1, 4, 0, 0};                     // eps_min, eps_max (medium, ambient: auto)
       ero_report total;
       ero_erode(&g, NULL, &soft, 1, 10, &o, NULL, &total);  // 10 steps; height[] is weathered
       printf("eroded %g deposited %g\n", total.eroded, total.deposited);
       // many calls on one grid: its tables made once (the same bits as ero_erode)
       ero_workspace *ws; ero_workspace_create(&g, &o, &ws);
       ero_erode_ws(ws, &g, NULL, &soft, 1, 10, &o, NULL, &total); ... ero_workspace_destroy(ws);

   WHAT
     Each step computes, for every valid sample x, the erosion height H(x) = W_f(x) / R(x) (paper eq.
     4.2.2-1) from the current surface, low-pass filters it, and adds it to the displacement; the
     surface's normals and curvature are recomputed at the start of the next step. Windward samples
     wear, leeward ones feel the ambient wind only, concave ones fill (deposition), harder
     materials resist. Two domains, one code path:
       ERO_SURFACE      a surface sample grid (dispmesh.h's dm_dispmap): per texel the base point
                        pos, the unit base normal nrm, disp = depth along -nrm (world units,
                        positive inward), area (the base area the texel stands for), valid, and the
                        +x, -x, +y, -y neighbours nbr across chart seams (UINT32_MAX = none) with
                        nbr_rot (a step along d continues as d turned nbr_rot quarter turns
                        counter-clockwise in the neighbour's axes). The surface is pos - disp nrm.
       ERO_HEIGHTFIELD  a height field: disp is the height (up, +z), texel (x, y) at (x s, y s) for
                        the spacing s; neighbours are the grid's, optionally wrapping around.
     The domains differ only in how a neighbour is found and in the offset to it (P_j - P_i; (+-s, 0,
     h_j - h_i) for a height field, exact under circular shifts); every filter, normal and curvature
     then runs through the same walk over neighbours, which never sees a seam. The walk is resolved
     once per call (or per workspace): texels whose neighbours (or filter taps) are the grid's run
     in row loops that vectorise, the others through recorded index lists, with the same sums in the same order (the
     same bits as texel by texel). A height field without a valid map runs the same model in one pass
     over a ring of rows (a fraction of the memory traffic; its bits differ from the walk's in the
     last places: the box's sums left undivided (the averaged normal's direction does not depend
     on their length; the curvature's divided once), the curvature in a height field's closed
     form, R in powers of c, 1 / |n| by a reciprocal square root accurate to about 3 ulp, the
     report's sums in float over 32 rows per column, then in double).

   MODEL (paper section 4.2.2; its W_f and R are on pages the text lacks: the forms below are chosen)
     Lengths are world units. L = sqrt(sum of the valid texels' area) is the grid's scale; the
     texel size is h = sqrt(mean valid area) (the spacing s for a height field), which converts
     world radii to texels (dispmesh.h's area-proportional layout keeps texels nearly equal, so one
     kernel serves the map).
     Surface: normal n = (Tx x Ty) normalised, oriented along nrm, with T the central differences of
       the surface over the neighbours (one-sided at a border); mean curvature
       kappa = the mean over the axes of -2 n . (E+ + E-) / (|E+|^2 + |E-|^2), E the offsets to
       the two neighbours (each offset's normal part is -kappa |E|^2 / 2, so uneven spacing, which
       seams have, needs no special case; positive on convex parts).
     Averages: n and kappa are box-averaged over normal_radius (the paper's "average normal" and
       "average curvature"): the separable box [-r, r] with each texel weighted by its overlap, so
       the same world radius covers the same area at any resolution.
     Wind force (windward test on the averaged normal n_a, wind unit w, exposure e = -n_a . w):
       windward (e > 0): W_f = force * e + ambient   (force 1.0 as in the paper; the cosine makes
                         W_f continuous across the terminator; ERO_CONSTANT_WINDWARD gives the
                         literal constant force)
       leeward  (e <= 0): W_f = ambient, the ambient term only (paper: "H = ambientW").
     Resistance: R(c) = (1-c)^2 eps_max + 2c(1-c) eps_medium + c^2 eps_min, a quadratic Bezier in the
       normalised convex curvature c = min(max(kappa_a, 0) curvature_length, 1): flat samples resist
       most, sharp convex edges least (so wind rounds edges); with |kappa_a| a shallow hollow would
       erode faster than the flat around it and deepen (unstable: texel-scale pits grow within ten
       steps), so hollows are left to deposition. R decreases monotonically in c exactly when
       eps_min <= eps_medium <= eps_max (the paper's [y0, y2] bound on eps_medium). Leeward samples
       divide by R as well (H = ambient / R), so a harder material also resists ambient wear;
       ERO_LEEWARD_LITERAL gives the paper's H = ambient.
     Material correction (the paper's): eps_medium = 0 means (eps_min + eps_max) / 2, one outside
       [eps_min, eps_max] is clamped to it; ambient = 0 means 1.05 eps_min / (eps_max - eps_min),
       one at or below the paper's bound eps_min / (eps_max - eps_min) is raised to 1.05 times it.
       Corrections are counted in ero_report.corrected; ero_resolve_material shows the result.
     Deposition: concave samples (kappa_a < 0) get a negative H, dust filling the hollow:
       H = (W_f / R) ((1 - t) - deposit_ratio t),  t = min(-kappa_a curvature_length / deposit_ramp, 1)
       for kappa_a < 0, else t = 0. The ramp (default 0.2 of the normalised curvature) replaces
       the paper's sign switch so that a flat sample's rounding noise cannot flip it between
       erosion and deposition.
     Filter and update: H is low-pass filtered by a separable Gaussian of sigma filter_sigma
       (truncated at 3 sigma, renormalised where it meets a border or an invalid texel), then
       disp += rate * H (height -= rate * H). Across a seam the second pass reads the first
       pass's result along the axis that continues this texel's x, so the filter is separable on
       every chart.
     Deposition bound: ERO_SURFACE keeps disp >= 0 (bound_value = 0: deposition never raises the
       surface above the base, which must enclose it for ray-cast rendering; a texel already above
       it, as a base that crosses the original leaves, may erode but not rise); bound = ERO_BOUND_VALUE sets
       another (signed) lower bound, ERO_BOUND_NONE none. ERO_HEIGHTFIELD is unbounded by default;
       ERO_BOUND_VALUE keeps height <= bound_value.
     Invalid texels (valid = 0) are not eroded and not read by the filters; those within two
       texels (in the image) of valid ones take the mean change of their already-set image
       neighbours, so that a bilinear reader (a GPU, dm_reconstruct) sees the change up to a
       chart's border (ERO_KEEP_INVALID turns this off).

   REPORT
     Per step (and summed): eroded and deposited volume, the sums over valid texels of the volume
     each texel's column sweeps (area times the change, with the base normal's spread over depth:
     exact for the column between the old and new depth), the largest |change|, the corrected
     material count. The state is just the map: stopping after k steps and calling again for the
     rest gives the same bits as one call.

   OPTIONS
     Compile time: ERO_STATIC (all functions static), ERO_MALLOC(sz)/ERO_FREE(p) (both or none),
     ERO_USE_AVX2 (needs -mavx2): the height field's ring loops (no valid map) in AVX2 on 8 texels
     at once, with its y passes fused with H and the change: the same bits as the portable path
     (the same operations in the same order; a group of 8 whose lengths are not normal floats
     falls back to it), recommended where available.
     ero_options (zero = default; ero_default_options() gives them, ero_resolve_options the
     grid-derived lengths):
       wind[3]          the direction the wind blows toward (required, nonzero)
       force (1)        the directed wind's strength
       rate             world units of depth per unit H per step (1e-3 L)
       normal_radius    averaging radius of normals and curvature, world units (L / 128)
       filter_sigma     the low-pass filter's sigma, world units (L / 256: narrower lets
                        texel-scale noise of the curvature grow over steps at large rates)
       curvature_length the radius of curvature that normalises to c = 1, world units (L / 32)
       deposit_ratio (0.5; negative = no deposition), deposit_ramp (0.2)
       flags            ERO_CONSTANT_WINDWARD, ERO_LEEWARD_LITERAL, ERO_KEEP_INVALID
       bound, bound_value   the deposition bound (see MODEL)
       allocator (NULL = ERO_MALLOC/ERO_FREE), progress (per step; nonzero cancels), user.

   MEMORY
     ero_erode allocates once per call, freed before it returns (ero_workspace_create allocates the
     same, plus the workspace struct of a few KiB, kept until ero_workspace_destroy; ero_erode_ws
     allocates nothing): for a height field without a valid
     map (and at least 2 r + 3 texels a side, r the larger kernel radius in texels) a ring of about 8
     box_r + 2 gau_r + 25 rows of floats plus box_r + gau_r + 6 rows of heights; all else 24 bytes
     per texel for a height field and 56 for a surface grid (positions, base normals, normals and
     curvature (the box filter's first pass in their place, the Gaussian's in the first of them), H,
     column coefficients, the regular-run lengths) and 40 KiB plus 16 bytes per column, 8 bytes per
     run of one texel kind in a row (per pass and for the geometry), 16 bytes per valid texel off the
     four grid neighbours (its neighbours), 4 + 10 r bytes per axis and kernel for each texel within
     its radius r of a seam or border (the walks' taps, found once per call or workspace), 4 + 4 C
     bytes per tap that reaches a seam turning the axes an odd number of quarter turns (C = 4 for the box, 1 for
     the Gaussian), 4 C bytes per walked texel of the busiest pass (their values), and up to 40 bytes
     for each invalid texel next to valid ones. The maps are the caller's.

   ERRORS
     Functions return ero_result (ERO_OK = 0); ero_result_string() names it.
       ERO_ERR_INVALID_ARGUMENT  a NULL pointer (grid, disp, a surface array, workspace), an unknown
                                 domain; for ero_erode_ws a grid other than the workspace's;
       ERO_ERR_BAD_SIZE          width or height < 1;
       ERO_ERR_TOO_LARGE         width * height overflows or exceeds 2^32 - 2 texels;
       ERO_ERR_BAD_SPACING       a height field's spacing <= 0 or not finite;
       ERO_ERR_BAD_MAP           a NaN or infinite value in disp (any texel) or in pos, nrm, area (valid
                                 texels), a zero normal, a negative area;
       ERO_ERR_BAD_INDEX         a neighbour index >= width * height (other than UINT32_MAX), a rotation > 3;
       ERO_ERR_BAD_WIND          a zero, NaN or infinite wind vector;
       ERO_ERR_BAD_MATERIAL      eps_min <= 0, eps_min >= eps_max, a NaN, a material id >= count;
       ERO_ERR_BAD_STEPS         steps < 1;
       ERO_ERR_BAD_PARAMETER     a negative or non-finite option, a radius beyond 255 texels; for
                                 ero_erode_ws radii or ERO_KEEP_INVALID other than the workspace's;
       ERO_ERR_OUT_OF_MEMORY     the allocator returned NULL;
       ERO_CANCELLED             the progress callback returned nonzero.
     A change that would leave float's range (huge maps, eps_min near 0) leaves the texel as it
     was. Everything is checked before the first step; on any error but ERO_CANCELLED the maps are
     untouched; cancelled, they hold the steps completed (report.steps), a valid state to resume.
     A workspace stays usable after any error of ero_erode_ws.

   THREAD SAFETY
     No global state; every function is re-entrant. A workspace is scratch: one call at a time uses
     it (threads eroding at once need a workspace each); it only reads the grid's geometry arrays.
     The same input gives the same bits on every run, with a workspace or without: sums in a fixed
     order relative to each texel, so a circular shift of a wrapped height field shifts the result
     bit for bit.

   LIMITS
     Steps are explicit (the paper's): the windward term moves slopes like an advection, so a rate
     much above a tenth of a texel per step lets ripples across slopes grow from step to step; a
     smaller rate (more steps) or a wider filter_sigma keeps them down.
     Up to 2^32 - 2 texels; filter and averaging radii up to 255 texels. One wind for all samples
     per call (the paper's simplification; vary it between calls). At most 256 materials (ids are
     bytes). The bits do not depend on the compiler's FMA contraction: the implementation turns it
     off for its own code and restores the user's setting after it, except under clang's
     -ffp-contract=fast, which ignores that pragma.

   REFERENCES
     J.-H. Chuang et al., final report of NSC 96-2628-E-009-160-MY3 (NCTU, 2010), section 4.2: wind
       erosion through the displacement map, H = W_f / R.
     N. S. Chepil, W. S. Woodruff, F. H. Siddoway, "A wind erosion equation", SSSA J. 29, 1965.
     D. W. Fryrear et al., RWEQ: Revised Wind Erosion Equation, USDA technical bulletin 1, 1998. */
#ifndef ERO_EROSION_H
#define ERO_EROSION_H

#include <stddef.h>
#include <stdint.h>

#ifdef ERO_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define ERODEF static __attribute__((unused))
#else
#define ERODEF static
#endif
#else
#define ERODEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ero_result {
    ERO_OK = 0,
    ERO_ERR_INVALID_ARGUMENT, /* NULL pointer, unknown domain */
    ERO_ERR_BAD_SIZE,         /* width or height < 1 */
    ERO_ERR_TOO_LARGE,        /* width * height overflows */
    ERO_ERR_BAD_SPACING,      /* height-field spacing <= 0 or not finite */
    ERO_ERR_BAD_MAP,          /* NaN / Inf in a map, zero normal, negative area */
    ERO_ERR_BAD_INDEX,        /* neighbour index or rotation out of range */
    ERO_ERR_BAD_WIND,         /* zero or non-finite wind */
    ERO_ERR_BAD_MATERIAL,     /* eps_min >= eps_max, eps_min <= 0, NaN, id out of range */
    ERO_ERR_BAD_STEPS,        /* steps < 1 */
    ERO_ERR_BAD_PARAMETER,    /* negative / non-finite option, radius too large */
    ERO_ERR_OUT_OF_MEMORY,    /* the allocator returned NULL */
    ERO_CANCELLED             /* the progress callback returned nonzero */
} ero_result;

enum { ERO_SURFACE = 1, ERO_HEIGHTFIELD = 2 };
enum { ERO_BOUND_DEFAULT = 0, ERO_BOUND_NONE = 1, ERO_BOUND_VALUE = 2 };
enum { ERO_CONSTANT_WINDWARD = 1 << 0, ERO_LEEWARD_LITERAL = 1 << 1, ERO_KEEP_INVALID = 1 << 2 };
enum { ERO_CORRECTED_MEDIUM = 1 << 0, ERO_CORRECTED_AMBIENT = 1 << 1 };

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct ero_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} ero_allocator;

/* The map to erode, n = width * height texels (see WHAT). Only disp is written. */
typedef struct ero_grid {
    int domain;               /* ERO_SURFACE or ERO_HEIGHTFIELD */
    int width, height;
    float *disp;              /* n: surface depth along -nrm (positive inward) / height (up) */
    const uint8_t *valid;     /* n, 1 = simulated; NULL = all */
    /* ERO_SURFACE */
    const float *pos;         /* 3n: base point */
    const float *nrm;         /* 3n: base normal, unit */
    const float *area;        /* n: base area the texel stands for */
    const uint32_t *nbr;      /* 4n: +x, -x, +y, -y neighbour, UINT32_MAX = none */
    const uint8_t *nbr_rot;   /* 4n: quarter turns counter-clockwise into the neighbour's axes */
    /* ERO_HEIGHTFIELD */
    float spacing;            /* world units between texels, > 0 */
    int wrap;                 /* 1: neighbours wrap around (a tile stays tileable) */
} ero_grid;

/* One material. eps_medium = 0 and ambient = 0 mean "computed" (see MODEL). */
typedef struct ero_material {
    float eps_min, eps_max;   /* resistance range, 0 < eps_min < eps_max */
    float eps_medium;         /* the Bezier's middle control value */
    float ambient;            /* ambientW */
} ero_material;

typedef struct ero_options {
    float wind[3];
    float force, rate, normal_radius, filter_sigma, curvature_length;
    float deposit_ratio, deposit_ramp;
    int flags;
    int bound;
    float bound_value;
    const ero_allocator *allocator;
    int (*progress)(void *user, float done);
    void *user;
} ero_options;

/* The tables ero_erode makes for a grid, kept across calls (ero_workspace_create). */
typedef struct ero_workspace ero_workspace;

typedef struct ero_report {
    double eroded;            /* volume removed (world units^3) */
    double deposited;         /* volume added */
    float max_change;         /* largest |change| of disp / height */
    int steps;                /* steps completed */
    size_t corrected;         /* materials whose eps_medium or ambient were corrected */
} ero_report;

ERODEF const char *ero_result_string(ero_result r);
ERODEF ero_options ero_default_options(void);
ERODEF ero_grid ero_heightfield_grid(int width, int height, float *h, float spacing, int wrap);
ERODEF ero_grid ero_surface_grid(int width, int height, const float *pos, const float *nrm, float *disp,
                                 const float *area, const uint8_t *valid, const uint32_t *nbr,
                                 const uint8_t *nbr_rot);

/* Runs `steps` erosion steps on g->disp.
   material: n ids (NULL = all 0); materials/material_count: the table (NULL, 0 = one soft
   material {1, 4}); per_step: `steps` reports or NULL; total: the sum or NULL (both filled for
   the steps done, also when cancelled). */
ERODEF ero_result ero_erode(const ero_grid *g, const uint8_t *material, const ero_material *materials,
                            size_t material_count, int steps, const ero_options *options,
                            ero_report *per_step, ero_report *total);

/* A workspace: the scratch and the tables ero_erode makes from a grid's geometry, made once and
   reused by ero_erode_ws over many calls (the same bits as ero_erode). g's domain, size, spacing,
   wrap and its arrays valid, pos, nrm, area, nbr, nbr_rot must stay as they are, unchanged, for
   the workspace's life (it keeps their pointers and tables made from them); disp is not read here.
   options: as for ero_erode; its normal_radius, filter_sigma (resolved) and ERO_KEEP_INVALID
   fix the workspace's kernels, its allocator serves the workspace until ero_workspace_destroy.
   *out: the workspace, NULL on failure. */
ERODEF ero_result ero_workspace_create(const ero_grid *g, const ero_options *options, ero_workspace **out);

/* ero_erode on ws's grid, allocating nothing. g: the grid ws was made for (the same domain, size,
   spacing, wrap and geometry pointers, else ERO_ERR_INVALID_ARGUMENT); g->disp is read and written
   as by ero_erode and may differ between calls. options: resolving to ws's normal_radius,
   filter_sigma and ERO_KEEP_INVALID (else ERO_ERR_BAD_PARAMETER); the wind, rate, force, the
   curvature, deposition and bound options, the other flags, progress and user may change between
   calls. The other parameters as for ero_erode. */
ERODEF ero_result ero_erode_ws(ero_workspace *ws, const ero_grid *g, const uint8_t *material,
                               const ero_material *materials, size_t material_count, int steps,
                               const ero_options *options, ero_report *per_step, ero_report *total);

/* Frees ws (NULL: nothing) with the allocator it was made with. */
ERODEF void ero_workspace_destroy(ero_workspace *ws);

/* The options with every zero replaced by its value for grid g (lengths from L). */
ERODEF ero_result ero_resolve_options(const ero_grid *g, const ero_options *options, ero_options *out);

/* The material after the paper's correction; returns ERO_CORRECTED_* flags, or -1 if invalid. */
ERODEF int ero_resolve_material(const ero_material *in, ero_material *out);

/* Paints id into material (width x height) where the mask (mask_w x mask_h, `channels` floats per
   pixel, the first read) is >= threshold, the mask stretched over the map (nearest pixel). */
ERODEF ero_result ero_paint_mask(uint8_t *material, int width, int height, const float *mask, int mask_w,
                                 int mask_h, int channels, float threshold, uint8_t id);

/* Paints id where the surface point (pos - disp nrm; (x s, y s, h)) lies within radius of centre. */
ERODEF ero_result ero_paint_sphere(const ero_grid *g, uint8_t *material, const float centre[3], float radius,
                                   uint8_t id);

#ifdef __cplusplus
}
#endif
#endif /* ERO_EROSION_H */

#ifdef ERO_IMPLEMENTATION
#ifndef ERO_IMPLEMENTATION_DONE
#define ERO_IMPLEMENTATION_DONE

#include <string.h>
#include <math.h>
#if defined(ERO_USE_AVX2)
#if !defined(__AVX2__)
#error "erosion.h: ERO_USE_AVX2 needs AVX2 code generation (gcc/clang -mavx2, MSVC /arch:AVX2)"
#endif
#include <immintrin.h>
#endif

#if defined(ERO_MALLOC) && defined(ERO_FREE)
/* both given */
#elif !defined(ERO_MALLOC) && !defined(ERO_FREE)
#include <stdlib.h>
#define ERO_MALLOC(sz) malloc(sz)
#define ERO_FREE(p) free(p)
#else
#error "erosion.h: define both ERO_MALLOC and ERO_FREE, or neither"
#endif

/* FMA contraction off from here to the end of the implementation, the user's setting restored
   after it: each a * b + c rounds twice whatever the dialect or -ffp-contract, so the bits do not
   depend on them (see LIMITS). GCC ignores STDC FP_CONTRACT but honours its optimize pragma, which
   also lets the row loops vectorise at -O2 (no-trapping-math: the selects that stand for branches
   may evaluate both sides; neither changes a result bit); clang
   takes fp contract inside float_control push/pop (except under -ffp-contract=fast, which ignores
   pragmas); other compilers: nothing. */
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(push)
#pragma clang fp contract(off)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off", "no-trapping-math", "tree-vectorize", "vect-cost-model=dynamic")
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define ERO__NONE 0xFFFFFFFFu
#define ERO__MAXR 255
#define ERO__SPAN 1024

#if defined(__GNUC__) || defined(__clang__)
#define ERO__RESTRICT __restrict
#define ERO__INLINE static inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define ERO__RESTRICT __restrict
#define ERO__INLINE static __forceinline
#else
#define ERO__RESTRICT
#define ERO__INLINE static inline
#endif
/* an eight-lane loop unrolled so that its lanes vectorise (GCC does not unroll it at -O2) */
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 8
#define ERO__UNROLL8 _Pragma("GCC unroll 8")
#else
#define ERO__UNROLL8
#endif

/* ================================================================================================
   the run: the domain, the resolved parameters, the scratch planes
   ================================================================================================ */

/* the texels a filter pass walks (off the regular stretches), their taps recorded once per call */
typedef struct ero__walks {
    size_t count;
    uint32_t *texel;                       /* the walked texels, in raster order */
    uint32_t *tap;                         /* 2 R per texel: +k, -k for k = 1..R (UINT32_MAX: none) */
    uint8_t *odd;                          /* the same: an odd number of quarter turns to the tap */
    uint32_t *seg;                         /* the pass in runs: start, length << 2 | kind (ERO__RUN_*) */
    size_t seg_count;
    size_t alt_count;                      /* the odd taps (axis 1), in the order the pass meets them: */
    uint32_t *alt_walk;                    /* their texel's walk along y (UINT32_MAX: a regular one) */
    float *alt[4];                         /* the y pass's values there (the second pass reads them) */
} ero__walks;

typedef struct ero__run {
    int hf, wrap, W, H;
    size_t n;
    float s;                               /* height-field spacing */
    float *disp;
    const uint8_t *valid;
    const float *pos, *nrm, *area;
    const uint32_t *nbr;
    const uint8_t *nbr_rot;
    const uint8_t *mat;
    ero_material mats[256];
    size_t corrected;
    size_t mat_count;                      /* the table's size */
    ero_options o;
    float wind[3];
    int has_rot;
    int ring;                              /* a plain height field: the ring of rows (ero__ring_step) */
    double texel, scale;                   /* the texel size h and the grid's scale L (MODEL) */
    int box_r, gau_r;
    float box_w[ERO__MAXR + 2], gau_w[ERO__MAXR + 1];
    float box_sum, gau_sum;
    const ero_allocator *al;
    void *block;
    float *P[3];                           /* surface points x, y, z (surface only) */
    float *N[3];                           /* base normals x, y, z (surface only) */
    uint32_t *seg;                         /* the image in runs: start, length << 2 | kind (ERO__SEG_*) */
    size_t seg_count;
    uint32_t *onb;                         /* 4 per ERO__SEG_OTHER texel, in order: its usable neighbours */
    float *wvals;                          /* a pass's walked texels' values */
    float *g[4];                           /* normal xyz, curvature; then their averages */
    float *rowbuf;                         /* 4 W: a row of an in-place pass */
    float *hh;                             /* H, then the filtered change */
    float *q1, *q2;                        /* column volume coefficients (surface only) */
    uint8_t *reg;                          /* 4n: regular run lengths along +x, -x, +y, -y */
    float *span;                           /* 9 ERO__SPAN: H's material rows, a pass's rows, scratch */
    ero__walks walks[2][2];                /* per kernel (box, Gaussian) and axis */
    uint32_t *ext;                         /* invalid texels that take their neighbours' change: i, count, neighbours */
    size_t ext_len;
} ero__run;

static size_t ero__ring_floats(const ero__run *r);

static int ero__finite(float v) { return v == v && v - v == 0.0f; }
/* finite without a branch: v - v is 0 for finite v, NaN otherwise */
ERO__INLINE int ero__fin(float v) { return v - v == 0.0f; }
static int ero__valid(const ero__run *r, uint32_t i) { return !r->valid || r->valid[i]; }

static void *ero__alloc(const ero_allocator *a, size_t n)
{
    return a ? a->alloc(a->user, n) : ERO_MALLOC(n);
}
static void ero__free(const ero_allocator *a, void *p)
{
    if (!p) return;
    if (a) a->free(a->user, p);
    else ERO_FREE(p);
}

/* the neighbour of texel i = (x, y) along d (0 +x, 1 -x, 2 +y, 3 -y), the quarter turns into its axes */
ERO__INLINE uint32_t ero__nb_xy(const ero__run *r, uint32_t i, uint32_t x, uint32_t y, int d, int *rot)
{
    uint32_t W = (uint32_t)r->W, H = (uint32_t)r->H;
    *rot = 0;
    if (!r->hf) {
        uint32_t j = r->nbr[4 * (size_t)i + (size_t)d];
        if (j != ERO__NONE) *rot = r->nbr_rot[4 * (size_t)i + (size_t)d];
        return j;
    }
    switch (d) {
    case 0: return x + 1 < W ? i + 1 : r->wrap ? i + 1 - W : ERO__NONE;
    case 1: return x > 0 ? i - 1 : r->wrap ? i + W - 1 : ERO__NONE;
    case 2: return y + 1 < H ? i + W : r->wrap ? x : ERO__NONE;
    default: return y > 0 ? i - W : r->wrap ? i + (H - 1) * W : ERO__NONE;
    }
}

ERO__INLINE uint32_t ero__nb(const ero__run *r, uint32_t i, int d, int *rot)
{
    if (!r->hf) return ero__nb_xy(r, i, 0, 0, d, rot);
    return ero__nb_xy(r, i, i % (uint32_t)r->W, i / (uint32_t)r->W, d, rot);
}

/* direction d turned `rot` quarter turns counter-clockwise (+x -> +y -> -x -> -y) */
ERO__INLINE int ero__turn(int d, int rot)
{
    static const int to_angle[4] = {0, 2, 1, 3}; /* d -> angle index; the table is its own inverse */
    return to_angle[(to_angle[d] + rot) & 3];
}

/* one step of a walk: the next usable texel (UINT32_MAX if none), the direction in its axes */
ERO__INLINE uint32_t ero__step(const ero__run *r, uint32_t i, int *d, int *turns)
{
    int rot;
    uint32_t j = ero__nb(r, i, *d, &rot);
    if (j == ERO__NONE || j == i || !ero__valid(r, j)) return ERO__NONE;
    *d = ero__turn(*d, rot);
    *turns += rot;
    return j;
}

/* ================================================================================================
   checking the input
   ================================================================================================ */

/* nonzero if a neighbour index or rotation of the 4 n entries is out of range (branch-free) */
static int ero__bad_indices(const uint32_t *nbr, const uint8_t *rot, size_t n)
{
    size_t i;
    uint32_t n32 = (uint32_t)n; /* n <= 2^32 - 2 */
    int bad = 0;
    for (i = 0; i < 4 * n; i++) bad |= ((nbr[i] >= n32) & (nbr[i] != ERO__NONE)) | (rot[i] > 3);
    return bad;
}

/* nonzero if a surface texel's map is bad (see ERO_ERR_BAD_MAP), checked where v (the valid
   map, or all ones) is nonzero */
static int ero__bad_texels(const ero_grid *g, const uint8_t *v, size_t n)
{
    const float *d = g->disp, *p = g->pos, *q = g->nrm, *a = g->area;
    size_t i;
    int bad = 0;
    for (i = 0; i < n; i++) {
        const float *pi = p + 3 * i, *qi = q + 3 * i;
        float s = (pi[0] - pi[0]) + (pi[1] - pi[1]) + (pi[2] - pi[2]) + (qi[0] - qi[0]) + (qi[1] - qi[1]) +
                  (qi[2] - qi[2]) + (a[i] - a[i]); /* 0 when all are finite, else NaN */
        int f = !(s == 0.0f) | (qi[0] * qi[0] + qi[1] * qi[1] + qi[2] * qi[2] < 1e-12f) | (a[i] < 0.0f);
        bad |= (!ero__fin(d[i])) | ((v[i] != 0) & f);
    }
    return bad;
}

static ero_result ero__check_grid(const ero_grid *g, size_t *n_out)
{
    size_t n, i;
    if (!g || !g->disp) return ERO_ERR_INVALID_ARGUMENT;
    if (g->domain != ERO_SURFACE && g->domain != ERO_HEIGHTFIELD) return ERO_ERR_INVALID_ARGUMENT;
    if (g->width < 1 || g->height < 1) return ERO_ERR_BAD_SIZE;
    if ((size_t)g->width > ((size_t)0xFFFFFFFEu) / (size_t)g->height) return ERO_ERR_TOO_LARGE;
    n = (size_t)g->width * (size_t)g->height;
    if (n > ((size_t)-1) / 96) return ERO_ERR_TOO_LARGE;
    if (g->domain == ERO_HEIGHTFIELD) {
        if (!ero__finite(g->spacing) || g->spacing <= 0.0f) return ERO_ERR_BAD_SPACING;
        for (i = 0; i < n; i++)
            if (!ero__finite(g->disp[i])) return ERO_ERR_BAD_MAP;
    } else {
        if (!g->pos || !g->nrm || !g->area || !g->nbr || !g->nbr_rot) return ERO_ERR_INVALID_ARGUMENT;
        if (ero__bad_indices(g->nbr, g->nbr_rot, n)) return ERO_ERR_BAD_INDEX;
        if (g->valid) {
            if (ero__bad_texels(g, g->valid, n)) return ERO_ERR_BAD_MAP;
        } else {
            for (i = 0; i < n; i += ERO__SPAN) {
                ero_grid part = *g;
                size_t cnt = n - i < ERO__SPAN ? n - i : ERO__SPAN;
                uint8_t all[ERO__SPAN];
                memset(all, 1, cnt);
                part.disp += i; part.pos += 3 * i; part.nrm += 3 * i; part.area += i;
                if (ero__bad_texels(&part, all, cnt)) return ERO_ERR_BAD_MAP;
            }
        }
    }
    *n_out = n;
    return ERO_OK;
}

static int ero__nonneg(float v) { return ero__finite(v) && v >= 0.0f; }

static ero_result ero__check_options(const ero_options *o)
{
    double w2;
    if (!ero__finite(o->wind[0]) || !ero__finite(o->wind[1]) || !ero__finite(o->wind[2])) return ERO_ERR_BAD_WIND;
    w2 = (double)o->wind[0] * o->wind[0] + (double)o->wind[1] * o->wind[1] + (double)o->wind[2] * o->wind[2];
    if (!(w2 > 1e-30)) return ERO_ERR_BAD_WIND;
    if (!ero__nonneg(o->force) || !ero__nonneg(o->rate) || !ero__nonneg(o->normal_radius) ||
        !ero__nonneg(o->filter_sigma) || !ero__nonneg(o->curvature_length) || !ero__finite(o->deposit_ratio) ||
        !ero__nonneg(o->deposit_ramp) || !ero__finite(o->bound_value))
        return ERO_ERR_BAD_PARAMETER;
    if (o->bound < ERO_BOUND_DEFAULT || o->bound > ERO_BOUND_VALUE) return ERO_ERR_BAD_PARAMETER;
    return ERO_OK;
}

ERODEF int ero_resolve_material(const ero_material *in, ero_material *out)
{
    ero_material m;
    int flags = 0;
    double bound;
    if (!in) return -1;
    m = *in;
    if (!ero__finite(m.eps_min) || !ero__finite(m.eps_max) || !ero__finite(m.eps_medium) || !ero__finite(m.ambient))
        return -1;
    if (!(m.eps_min > 0.0f) || !(m.eps_min < m.eps_max)) return -1;
    if (m.eps_medium == 0.0f) m.eps_medium = (float)(0.5 * ((double)m.eps_min + (double)m.eps_max)); /* no overflow */
    else if (m.eps_medium < m.eps_min || m.eps_medium > m.eps_max) {
        m.eps_medium = m.eps_medium < m.eps_min ? m.eps_min : m.eps_max;
        flags |= ERO_CORRECTED_MEDIUM;
    }
    bound = (double)m.eps_min / ((double)m.eps_max - (double)m.eps_min);
    if (m.ambient == 0.0f || (double)m.ambient <= bound) {
        if (m.ambient != 0.0f) flags |= ERO_CORRECTED_AMBIENT;
        m.ambient = (float)(1.05 * bound);
        while ((double)m.ambient <= bound) m.ambient = nextafterf(m.ambient, 3.4e38f); /* above it in float too */
    }
    if (!ero__finite(m.ambient)) return -1;
    if (out) *out = m;
    return flags;
}

static ero_result ero__check_materials(ero__run *r, const uint8_t *material, const ero_material *mats, size_t count)
{
    size_t i;
    if (!mats || count == 0) {
        ero_material soft;
        soft.eps_min = 1.0f; soft.eps_max = 4.0f; soft.eps_medium = 0.0f; soft.ambient = 0.0f;
        count = 1;
        ero_resolve_material(&soft, &r->mats[0]);
    } else {
        if (count > 256) return ERO_ERR_BAD_MATERIAL;
        for (i = 0; i < count; i++) {
            int f = ero_resolve_material(&mats[i], &r->mats[i]);
            if (f < 0) return ERO_ERR_BAD_MATERIAL;
            if (f) r->corrected++;
        }
    }
    r->mat = material;
    r->mat_count = count;
    if (material && count < 256) { /* the largest id, in a loop that vectorises */
        uint8_t top = 0;
        for (i = 0; i < r->n; i++) top = material[i] > top ? material[i] : top;
        if (top >= count) return ERO_ERR_BAD_MATERIAL;
    }
    return ERO_OK;
}

/* ================================================================================================
   options and kernels
   ================================================================================================ */

ERODEF ero_options ero_default_options(void)
{
    ero_options o;
    memset(&o, 0, sizeof o);
    o.force = 1.0f;
    o.deposit_ratio = 0.5f;
    o.deposit_ramp = 0.2f;
    return o; /* lengths 0: derived from the grid (ero_resolve_options) */
}

/* the texel size h and the scale L of a checked grid */
static void ero__scales(const ero_grid *g, size_t n, double *h, double *L)
{
    size_t i, nv = 0;
    double a = 0.0;
    if (g->domain == ERO_HEIGHTFIELD) {
        *h = g->spacing;
        *L = g->spacing * sqrt((double)n);
        return;
    }
    for (i = 0; i < n; i++)
        if (!g->valid || g->valid[i]) { a += g->area[i]; nv++; }
    *h = nv && a > 0.0 ? sqrt(a / (double)nv) : 1.0;
    *L = a > 0.0 ? sqrt(a) : 1.0;
}

static ero_options ero__resolve(const ero_options *in, double L)
{
    ero_options o = *in;
    if (o.force == 0.0f) o.force = 1.0f;
    if (o.rate == 0.0f) o.rate = (float)(1e-3 * L);
    if (o.normal_radius == 0.0f) o.normal_radius = (float)(L / 128.0);
    if (o.filter_sigma == 0.0f) o.filter_sigma = (float)(L / 256.0);
    if (o.curvature_length == 0.0f) o.curvature_length = (float)(L / 32.0);
    if (o.deposit_ratio == 0.0f) o.deposit_ratio = 0.5f;
    if (o.deposit_ramp == 0.0f) o.deposit_ramp = 0.2f;
    return o;
}

ERODEF ero_result ero_resolve_options(const ero_grid *g, const ero_options *options, ero_options *out)
{
    size_t n;
    double h, L;
    ero_result e = ero__check_grid(g, &n);
    ero_options o = options ? *options : ero_default_options();
    if (!out) return ERO_ERR_INVALID_ARGUMENT;
    if (e != ERO_OK) return e;
    if ((e = ero__check_options(&o)) != ERO_OK) return e;
    ero__scales(g, n, &h, &L);
    *out = ero__resolve(&o, L);
    return ERO_OK;
}

/* the box (fractional end taps) and Gaussian kernels, in texels of size h */
static ero_result ero__kernels(ero__run *r, double h)
{
    double rb = r->o.normal_radius / h, sg = r->o.filter_sigma / h;
    int k;
    if (rb > ERO__MAXR || 3.0 * sg > ERO__MAXR) return ERO_ERR_BAD_PARAMETER;
    r->box_r = rb < 0.5 ? 0 : (int)floor(rb + 0.5);
    r->box_w[0] = 1.0f;
    for (k = 1; k <= r->box_r; k++) r->box_w[k] = (float)(rb - k + 0.5 < 1.0 ? rb - k + 0.5 : 1.0);
    if (r->box_r > 0 && r->box_w[r->box_r] <= 0.0f) r->box_r--;
    r->gau_r = sg < 1e-3 ? 0 : (int)ceil(3.0 * sg);
    for (k = 0; k <= r->gau_r; k++) r->gau_w[k] = (float)exp(-0.5 * k * k / (sg * sg > 0 ? sg * sg : 1.0));
    r->box_sum = r->box_w[0];
    for (k = 1; k <= r->box_r; k++) { r->box_sum += r->box_w[k]; r->box_sum += r->box_w[k]; }
    r->gau_sum = r->gau_w[0];
    for (k = 1; k <= r->gau_r; k++) { r->gau_sum += r->gau_w[k]; r->gau_sum += r->gau_w[k]; }
    return ERO_OK;
}

/* ================================================================================================
   scratch
   ================================================================================================ */

/* the planes are n + ERO__STAGGER floats apart: planes of a power-of-two size would start at the
   same address modulo 4 KiB, and a loop over ten of them would thrash an L1 set and stall on
   false store-to-load aliasing */
#define ERO__STAGGER 48
static ero_result ero__scratch(ero__run *r)
{
    size_t n = r->n, planes = 4 + 1 + (r->hf ? 0 : 3 + 3 + 2), bytes, k, np = n + ERO__STAGGER;
    float *f;
    if (r->ring) { /* rows only */
        r->block = ero__alloc(r->al, ero__ring_floats(r) * sizeof(float));
        r->hh = (float *)r->block;
        return r->block ? ERO_OK : ERO_ERR_OUT_OF_MEMORY;
    }
    bytes = (planes * np + 9 * ERO__SPAN + 4 * (size_t)r->W) * sizeof(float) + 4 * n;
    r->block = ero__alloc(r->al, bytes);
    if (!r->block) return ERO_ERR_OUT_OF_MEMORY;
    f = (float *)r->block;
    for (k = 0; k < 4; k++) { r->g[k] = f; f += np; }
    r->hh = f; f += np;
    r->span = f; f += 9 * ERO__SPAN;
    r->rowbuf = f; f += 4 * (size_t)r->W;
    if (!r->hf) {
        for (k = 0; k < 3; k++) { r->P[k] = f; f += np; }
        for (k = 0; k < 3; k++) { r->N[k] = f; f += np; }
        r->q1 = f; f += np;
        r->q2 = f; f += np;
    }
    r->reg = (uint8_t *)f;
    return ERO_OK;
}

/* reg[4i + d]: how many steps along d from i stay on the image grid (i +- 1, i +- W), unrotated
   and valid, capped at 255: where it covers a kernel, the filters index directly */
static void ero__regular_runs(ero__run *r)
{
    long W = r->W, H = r->H, x, y;
    int rot;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) { /* -x and -y: from the low side */
            uint32_t i = (uint32_t)(y * W + x);
            uint8_t *g = r->reg + 4 * (size_t)i;
            uint32_t j = ero__nb_xy(r, i, (uint32_t)x, (uint32_t)y, 1, &rot);
            g[1] = (uint8_t)(x > 0 && j == i - 1 && rot == 0 && ero__valid(r, j) ? (g[-4 + 1] < 255 ? g[-4 + 1] + 1 : 255) : 0);
            j = ero__nb_xy(r, i, (uint32_t)x, (uint32_t)y, 3, &rot);
            g[3] = (uint8_t)(y > 0 && j == i - (uint32_t)W && rot == 0 && ero__valid(r, j)
                                 ? (r->reg[4 * (size_t)j + 3] < 255 ? r->reg[4 * (size_t)j + 3] + 1 : 255) : 0);
        }
    for (y = H - 1; y >= 0; y--)
        for (x = W - 1; x >= 0; x--) {
            uint32_t i = (uint32_t)(y * W + x);
            uint8_t *g = r->reg + 4 * (size_t)i;
            uint32_t j = ero__nb_xy(r, i, (uint32_t)x, (uint32_t)y, 0, &rot);
            g[0] = (uint8_t)(x + 1 < W && j == i + 1 && rot == 0 && ero__valid(r, j) ? (g[4] < 255 ? g[4] + 1 : 255) : 0);
            j = ero__nb_xy(r, i, (uint32_t)x, (uint32_t)y, 2, &rot);
            g[2] = (uint8_t)(y + 1 < H && j == i + (uint32_t)W && rot == 0 && ero__valid(r, j)
                                 ? (r->reg[4 * (size_t)j + 2] < 255 ? r->reg[4 * (size_t)j + 2] + 1 : 255) : 0);
        }
}

enum { ERO__SEG_INVALID = 0, ERO__SEG_QUAD = 1, ERO__SEG_OTHER = 2 };

/* a texel's kind for the geometry: invalid, valid with the four grid neighbours, other */
static uint32_t ero__kind(const ero__run *r, size_t i)
{
    const uint8_t *g = r->reg + 4 * i;
    if (!ero__valid(r, (uint32_t)i)) return ERO__SEG_INVALID;
    return g[0] && g[1] && g[2] && g[3] ? ERO__SEG_QUAD : ERO__SEG_OTHER;
}

/* the runs of one kind within each row, at most ERO__SPAN long, into seg (NULL: counted) */
static size_t ero__segments(const ero__run *r, uint32_t *seg)
{
    size_t W = (size_t)r->W, y, x, cnt = 0;
    for (y = 0; y < (size_t)r->H; y++)
        for (x = 0; x < W;) {
            size_t i = y * W + x, e = x + 1;
            uint32_t kind = ero__kind(r, i);
            while (e < W && e - x < ERO__SPAN && ero__kind(r, y * W + e) == kind) e++;
            if (seg) { seg[2 * cnt] = (uint32_t)i; seg[2 * cnt + 1] = (uint32_t)(e - x) << 2 | kind; }
            cnt++;
            x = e;
        }
    return cnt;
}

/* a surface's per-call tables: the base normals in planes, the runs of texel kinds */
static ero_result ero__surface_tables(ero__run *r)
{
    size_t i, k, other = 0;
    int d, rot;
    if (r->hf) return ERO_OK;
    for (i = 0; i < r->n; i++) {
        r->N[0][i] = r->nrm[3 * i + 0]; r->N[1][i] = r->nrm[3 * i + 1]; r->N[2][i] = r->nrm[3 * i + 2];
    }
    r->seg_count = ero__segments(r, NULL);
    r->seg = (uint32_t *)ero__alloc(r->al, 2 * r->seg_count * sizeof(uint32_t));
    if (!r->seg) return ERO_ERR_OUT_OF_MEMORY;
    ero__segments(r, r->seg);
    for (k = 0; k < r->seg_count; k++) other += (r->seg[2 * k + 1] & 3) == ERO__SEG_OTHER ? r->seg[2 * k + 1] >> 2 : 0;
    r->onb = (uint32_t *)ero__alloc(r->al, 4 * other * sizeof(uint32_t) + 1);
    if (!r->onb) return ERO_ERR_OUT_OF_MEMORY;
    for (k = 0, other = 0; k < r->seg_count; k++) {
        size_t i0 = r->seg[2 * k], len = r->seg[2 * k + 1] >> 2;
        if ((r->seg[2 * k + 1] & 3) != ERO__SEG_OTHER) continue;
        for (i = i0; i < i0 + len; i++, other++)
            for (d = 0; d < 4; d++) {
                uint32_t j = ero__nb(r, (uint32_t)i, d, &rot);
                r->onb[4 * other + (size_t)d] = j == ERO__NONE || j == (uint32_t)i || !ero__valid(r, j) ? ERO__NONE : j;
            }
    }
    return ERO_OK;
}

/* ================================================================================================
   geometry: surface points, offsets to neighbours, normals, curvature
   ================================================================================================ */

static void ero__points(ero__run *r)
{
    size_t i;
    float *ERO__RESTRICT px = r->P[0], *ERO__RESTRICT py = r->P[1], *ERO__RESTRICT pz = r->P[2];
    if (r->hf) return;
    for (i = 0; i < r->n; i++) {
        float d = r->disp[i];
        px[i] = r->pos[3 * i + 0] - d * r->nrm[3 * i + 0];
        py[i] = r->pos[3 * i + 1] - d * r->nrm[3 * i + 1];
        pz[i] = r->pos[3 * i + 2] - d * r->nrm[3 * i + 2];
    }
}

/* the offset from texel i to its neighbour j along d: of the surface (base = 0) or of the base */
static void ero__offset(const ero__run *r, uint32_t i, uint32_t j, int d, int base, float e[3])
{
    if (r->hf) {
        e[0] = d == 0 ? r->s : d == 1 ? -r->s : 0.0f;
        e[1] = d == 2 ? r->s : d == 3 ? -r->s : 0.0f;
        e[2] = base ? 0.0f : r->disp[j] - r->disp[i];
    } else if (base) {
        e[0] = r->pos[3 * (size_t)j + 0] - r->pos[3 * (size_t)i + 0];
        e[1] = r->pos[3 * (size_t)j + 1] - r->pos[3 * (size_t)i + 1];
        e[2] = r->pos[3 * (size_t)j + 2] - r->pos[3 * (size_t)i + 2];
    } else {
        e[0] = r->P[0][j] - r->P[0][i];
        e[1] = r->P[1][j] - r->P[1][i];
        e[2] = r->P[2][j] - r->P[2][i];
    }
}

static void ero__base_normal(const ero__run *r, uint32_t i, float n[3])
{
    if (r->hf) { n[0] = 0.0f; n[1] = 0.0f; n[2] = 1.0f; return; }
    n[0] = r->nrm[3 * (size_t)i + 0];
    n[1] = r->nrm[3 * (size_t)i + 1];
    n[2] = r->nrm[3 * (size_t)i + 2];
}

static inline void ero__cross(const float a[3], const float b[3], float c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline float ero__dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* the tangent along one axis from the offsets to its + and - neighbours (have: bit 0 +, bit 1 -);
   0 when neither exists */
static inline int ero__tangent(const float ep[3], const float em[3], int have, float t[3])
{
    int k;
    for (k = 0; k < 3; k++)
        t[k] = have == 3 ? 0.5f * (ep[k] - em[k]) : have == 1 ? ep[k] : have == 2 ? -em[k] : 0.0f;
    return have != 0;
}

/* the normal curvature along one axis from the offsets E+, E- to its two neighbours, unevenly
   spaced ones included: each offset's normal part is -kappa |E|^2 / 2 on a surface of normal
   curvature kappa, so kappa = -2 n . (E+ + E-) / (|E+|^2 + |E-|^2) (no square root) */
static inline float ero__second(const float ep[3], const float em[3], const float n[3])
{
    float q = ero__dot(ep, ep) + ero__dot(em, em), k;
    if (!(q > 0.0f)) return 0.0f;
    k = -2.0f * (ero__dot(ep, n) + ero__dot(em, n)) / q;
    return ero__finite(k) ? k : 0.0f; /* lengths beyond float's range: no curvature */
}

/* a texel's normal (oriented along the base normal nb) and mean curvature from the offsets e to
   its neighbours (have: bit d set where neighbour d exists), into out[0..3] */
static inline void ero__texel_geometry(float e[4][3], int have, const float nb[3], float *g0, float *g1, float *g2, float *g3)
{
    float tx[3], ty[3], c[3], n[3], len, kappa = 0.0f;
    int axes = 0;
    n[0] = nb[0]; n[1] = nb[1]; n[2] = nb[2];
    if (ero__tangent(e[0], e[1], have & 3, tx) && ero__tangent(e[2], e[3], (have >> 2) & 3, ty)) {
        ero__cross(tx, ty, c);
        len = sqrtf(ero__dot(c, c));
        if (len > 0.0f) {
            float inv = (ero__dot(c, nb) < 0.0f ? -1.0f : 1.0f) / len;
            n[0] = c[0] * inv; n[1] = c[1] * inv; n[2] = c[2] * inv;
        }
    }
    if ((have & 3) == 3) { kappa += ero__second(e[0], e[1], n); axes++; }
    if ((have & 12) == 12) { kappa += ero__second(e[2], e[3], n); axes++; }
    if (axes) kappa /= (float)axes;
    if (!ero__finite(n[0]) || !ero__finite(n[1]) || !ero__finite(n[2])) { n[0] = nb[0]; n[1] = nb[1]; n[2] = nb[2]; }
    *g0 = n[0]; *g1 = n[1]; *g2 = n[2]; *g3 = kappa;
}

/* texel i's normal and mean curvature into g[0..3] (0 where invalid), its neighbours looked up;
   a height field's texels with the four grid neighbours (the regular-run table) without a lookup */
static void ero__texel_at(ero__run *r, size_t i)
{
    float e[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, nb[3];
    const uint8_t *reg = r->reg + 4 * i;
    int d, have = 0, rot;
    static const float up[3] = {0.0f, 0.0f, 1.0f};
    if (!ero__valid(r, (uint32_t)i)) { r->g[0][i] = r->g[1][i] = r->g[2][i] = r->g[3][i] = 0.0f; return; }
    if (r->hf && reg[0] && reg[1] && reg[2] && reg[3]) {
        const size_t j[4] = {i + 1, i - 1, i + (size_t)r->W, i - (size_t)r->W};
        e[0][0] = r->s; e[1][0] = -r->s; e[2][1] = r->s; e[3][1] = -r->s;
        for (d = 0; d < 4; d++) e[d][2] = r->disp[j[d]] - r->disp[i];
        ero__texel_geometry(e, 15, up, &r->g[0][i], &r->g[1][i], &r->g[2][i], &r->g[3][i]);
        return;
    }
    for (d = 0; d < 4; d++) {
        uint32_t j = ero__nb(r, (uint32_t)i, d, &rot);
        if (j == ERO__NONE || j == (uint32_t)i || !ero__valid(r, j)) continue;
        ero__offset(r, (uint32_t)i, j, d, 0, e[d]);
        have |= 1 << d;
    }
    ero__base_normal(r, (uint32_t)i, nb);
    ero__texel_geometry(e, have, nb, &r->g[0][i], &r->g[1][i], &r->g[2][i], &r->g[3][i]);
}

/* the offsets from texel x of a run to its + and - neighbours along one axis (o: 1 or W) */
#define ERO__OFFSETS(ep, em, o)                                                                       \
    float ep##0 = px[x + o] - px[x], ep##1 = py[x + o] - py[x], ep##2 = pz[x + o] - pz[x];            \
    float em##0 = px[x - o] - px[x], em##1 = py[x - o] - py[x], em##2 = pz[x - o] - pz[x]

/* the geometry of n texels of a row whose four grid neighbours are valid texels (rows W apart):
   ero__texel_geometry's sums in its order, its branches as selects, in loops that vectorise (the
   square roots in a scalar loop apart, as sqrtf's errno keeps a loop from vectorising; ln is
   scratch) */
static void ero__quad_geometry(const float *ERO__RESTRICT px, const float *ERO__RESTRICT py, const float *ERO__RESTRICT pz,
                               const float *ERO__RESTRICT nb0, const float *ERO__RESTRICT nb1,
                               const float *ERO__RESTRICT nb2, long W, long n, float *ERO__RESTRICT ln,
                               float *ERO__RESTRICT g0, float *ERO__RESTRICT g1, float *ERO__RESTRICT g2,
                               float *ERO__RESTRICT g3)
{
    long x;
    for (x = 0; x < n; x++) {
        ERO__OFFSETS(a, b, 1);
        ERO__OFFSETS(c, d, W);
        float t0 = 0.5f * (a0 - b0), t1 = 0.5f * (a1 - b1), t2 = 0.5f * (a2 - b2);
        float u0 = 0.5f * (c0 - d0), u1 = 0.5f * (c1 - d1), u2 = 0.5f * (c2 - d2);
        float m0 = t1 * u2 - t2 * u1, m1 = t2 * u0 - t0 * u2, m2 = t0 * u1 - t1 * u0;
        ln[x] = (m0 * m0 + m1 * m1) + m2 * m2;
    }
    for (x = 0; x < n; x++) ln[x] = sqrtf(ln[x]);
    for (x = 0; x < n; x++) {
        ERO__OFFSETS(a, b, 1);
        ERO__OFFSETS(c, d, W);
        float t0 = 0.5f * (a0 - b0), t1 = 0.5f * (a1 - b1), t2 = 0.5f * (a2 - b2);
        float u0 = 0.5f * (c0 - d0), u1 = 0.5f * (c1 - d1), u2 = 0.5f * (c2 - d2);
        float m0 = t1 * u2 - t2 * u1, m1 = t2 * u0 - t0 * u2, m2 = t0 * u1 - t1 * u0, len = ln[x];
        float side = (m0 * nb0[x] + m1 * nb1[x]) + m2 * nb2[x], inv = (side < 0.0f ? -1.0f : 1.0f) / len;
        float n0 = len > 0.0f ? m0 * inv : nb0[x], n1 = len > 0.0f ? m1 * inv : nb1[x], n2 = len > 0.0f ? m2 * inv : nb2[x];
        float qx = ((a0 * a0 + a1 * a1) + a2 * a2) + ((b0 * b0 + b1 * b1) + b2 * b2);
        float qy = ((c0 * c0 + c1 * c1) + c2 * c2) + ((d0 * d0 + d1 * d1) + d2 * d2);
        float kx = -2.0f * (((a0 * n0 + a1 * n1) + a2 * n2) + ((b0 * n0 + b1 * n1) + b2 * n2)) / qx;
        float ky = -2.0f * (((c0 * n0 + c1 * n1) + c2 * n2) + ((d0 * n0 + d1 * n1) + d2 * n2)) / qy;
        float fx0 = qx > 0.0f ? kx : 0.0f, fy0 = qy > 0.0f ? ky : 0.0f;
        float fx = ero__fin(fx0) ? fx0 : 0.0f, fy = ero__fin(fy0) ? fy0 : 0.0f;
        float fin = (n0 - n0) + (n1 - n1) + (n2 - n2); /* 0 when all are finite, else NaN */
        g0[x] = fin == 0.0f ? n0 : nb0[x]; g1[x] = fin == 0.0f ? n1 : nb1[x]; g2[x] = fin == 0.0f ? n2 : nb2[x];
        g3[x] = ((0.0f + fx) + fy) / 2.0f;
    }
}
#undef ERO__OFFSETS

/* a hint that p is read soon (a seam's neighbours are far apart: cache misses) */
#if defined(__GNUC__) || defined(__clang__)
#define ERO__PREFETCH(p) __builtin_prefetch(p)
#else
#define ERO__PREFETCH(p) ((void)(p))
#endif

/* the surface geometry of texel i (not one of ero__quad_geometry's) from its usable neighbours j
   (ero__texel_at's sums); the points of the neighbours of the texel `ahead` fetched meanwhile */
static void ero__other_geometry(ero__run *r, size_t i, const uint32_t *j, const uint32_t *ahead)
{
    float e[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, nb[3];
    int d, k, have = 0;
    for (d = 0; d < 4; d++)
        if (ahead[d] != ERO__NONE)
            for (k = 0; k < 3; k++) ERO__PREFETCH(r->P[k] + ahead[d]);
    for (d = 0; d < 4; d++) {
        if (j[d] == ERO__NONE) continue;
        for (k = 0; k < 3; k++) e[d][k] = r->P[k][j[d]] - r->P[k][i];
        have |= 1 << d;
    }
    for (k = 0; k < 3; k++) nb[k] = r->N[k][i];
    ero__texel_geometry(e, have, nb, &r->g[0][i], &r->g[1][i], &r->g[2][i], &r->g[3][i]);
}

/* normal and mean curvature of the surface at every valid texel, into g[0..3]: a surface's runs
   of texels with the four grid neighbours in rows, the rest (and a height field) texel by texel */
static void ero__geometry(ero__run *r)
{
    size_t i, k, m = 0, other = 0;
    int c;
    if (r->hf) {
        for (i = 0; i < r->n; i++) ero__texel_at(r, i);
        return;
    }
    for (k = 0; k < r->seg_count; k++) other += (r->seg[2 * k + 1] & 3) == ERO__SEG_OTHER ? r->seg[2 * k + 1] >> 2 : 0;
    for (k = 0; k < r->seg_count; k++) {
        size_t i0 = r->seg[2 * k], len = r->seg[2 * k + 1] >> 2;
        if ((r->seg[2 * k + 1] & 3) == ERO__SEG_OTHER)
            for (i = i0; i < i0 + len; i++, m++)
                ero__other_geometry(r, i, r->onb + 4 * m, r->onb + 4 * (m + 8 < other ? m + 8 : m));
        else if ((r->seg[2 * k + 1] & 3) == ERO__SEG_QUAD)
            ero__quad_geometry(r->P[0] + i0, r->P[1] + i0, r->P[2] + i0, r->N[0] + i0, r->N[1] + i0, r->N[2] + i0, r->W,
                               (long)len, r->span + 8 * ERO__SPAN, r->g[0] + i0, r->g[1] + i0, r->g[2] + i0, r->g[3] + i0);
        else
            for (c = 0; c < 4; c++) memset(r->g[c] + i0, 0, len * sizeof(float));
    }
}

/* the column volume coefficients (surface): a texel's column between depths t0 and t1 holds
   area (t1 - t0 + q1 (t1^2 - t0^2) / 2 + q2 (t1^3 - t0^3) / 3), from
   det(Bu - t Nu, Bv - t Nv, n) / det(Bu, Bv, n) = 1 + q1 t + q2 t^2 (B base, N normal differences) */
static void ero__column_at(ero__run *r, size_t i, const uint32_t *nbj)
{
    float eb[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, en[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    float bu[3], bv[3], nu[3], nv[3], c[3], n[3], a0, a1, a2;
    int d, have = 0, k;
    r->q1[i] = r->q2[i] = 0.0f;
    for (d = 0; d < 4; d++) {
        uint32_t j = nbj[d];
        if (j == ERO__NONE) continue;
        ero__offset(r, (uint32_t)i, j, d, 1, eb[d]);
        for (k = 0; k < 3; k++) en[d][k] = r->nrm[3 * (size_t)j + (size_t)k] - r->nrm[3 * i + (size_t)k];
        have |= 1 << d;
    }
    if (!ero__tangent(eb[0], eb[1], have & 3, bu) || !ero__tangent(eb[2], eb[3], (have >> 2) & 3, bv)) return;
    ero__tangent(en[0], en[1], have & 3, nu);
    ero__tangent(en[2], en[3], (have >> 2) & 3, nv);
    ero__base_normal(r, (uint32_t)i, n);
    ero__cross(bu, bv, c);
    a0 = ero__dot(c, n);
    if (fabsf(a0) < 1e-30f) return;
    ero__cross(nu, bv, c);
    a1 = -ero__dot(c, n);
    ero__cross(bu, nv, c);
    a1 -= ero__dot(c, n);
    ero__cross(nu, nv, c);
    a2 = ero__dot(c, n);
    r->q1[i] = a1 / a0;
    r->q2[i] = a2 / a0;
    if (!ero__finite(r->q1[i]) || !ero__finite(r->q2[i])) r->q1[i] = r->q2[i] = 0.0f; /* beyond float's range */
}

/* ero__column_at's sums in its order for n texels of a row with the four grid neighbours (base
   points b, normals m in planes), its branches as selects, in a loop that vectorises */
#define ERO__TANGENT(t, f, o)                                                                         \
    float t##0 = 0.5f * ((f##0[x + o] - f##0[x]) - (f##0[x - o] - f##0[x]));                           \
    float t##1 = 0.5f * ((f##1[x + o] - f##1[x]) - (f##1[x - o] - f##1[x]));                           \
    float t##2 = 0.5f * ((f##2[x + o] - f##2[x]) - (f##2[x - o] - f##2[x]))
#define ERO__TRIPLE(a, b) (((a##1 * b##2 - a##2 * b##1) * m0[x] + (a##2 * b##0 - a##0 * b##2) * m1[x]) +     \
                           (a##0 * b##1 - a##1 * b##0) * m2[x])
static void ero__quad_columns(const float *ERO__RESTRICT b0, const float *ERO__RESTRICT b1, const float *ERO__RESTRICT b2,
                              const float *ERO__RESTRICT m0, const float *ERO__RESTRICT m1,
                              const float *ERO__RESTRICT m2, long W, long n, float *ERO__RESTRICT q1,
                              float *ERO__RESTRICT q2)
{
    long x;
    for (x = 0; x < n; x++) {
        ERO__TANGENT(bu, b, 1);
        ERO__TANGENT(bv, b, W);
        ERO__TANGENT(nu, m, 1);
        ERO__TANGENT(nv, m, W);
        float a0 = ERO__TRIPLE(bu, bv), a1 = -ERO__TRIPLE(nu, bv), a2 = ERO__TRIPLE(nu, nv);
        float a1b = a1 - ERO__TRIPLE(bu, nv), c1 = a1b / a0, c2 = a2 / a0;
        float small = fabsf(a0) < 1e-30f ? 1.0f : 0.0f;
        float bad = small + ((c1 - c1) + (c2 - c2)); /* 0 when a0 is usable and both are finite */
        q1[x] = bad == 0.0f ? c1 : 0.0f;
        q2[x] = bad == 0.0f ? c2 : 0.0f;
    }
}
#undef ERO__TANGENT
#undef ERO__TRIPLE

/* the column coefficients of every valid texel (surface): runs with the four grid neighbours in
   rows (the base points in P for the while), the rest texel by texel; 0 where invalid */
static void ero__columns(ero__run *r)
{
    size_t i, k, m = 0;
    if (r->hf) return;
    for (i = 0; i < r->n; i++) {
        r->P[0][i] = r->pos[3 * i + 0]; r->P[1][i] = r->pos[3 * i + 1]; r->P[2][i] = r->pos[3 * i + 2];
    }
    for (k = 0; k < r->seg_count; k++) {
        size_t i0 = r->seg[2 * k], len = r->seg[2 * k + 1] >> 2;
        if ((r->seg[2 * k + 1] & 3) == ERO__SEG_QUAD)
            ero__quad_columns(r->P[0] + i0, r->P[1] + i0, r->P[2] + i0, r->N[0] + i0, r->N[1] + i0, r->N[2] + i0, r->W,
                              (long)len, r->q1 + i0, r->q2 + i0);
        else if ((r->seg[2 * k + 1] & 3) == ERO__SEG_OTHER)
            for (i = i0; i < i0 + len; i++, m++) ero__column_at(r, i, r->onb + 4 * m);
        else {
            memset(r->q1 + i0, 0, len * sizeof(float));
            memset(r->q2 + i0, 0, len * sizeof(float));
        }
    }
}

/* ================================================================================================
   the seam-aware separable filter
   ================================================================================================ */

enum { ERO__RUN_INVALID = 0, ERO__RUN_REGULAR = 1, ERO__RUN_WALK = 2 };

/* a texel's kind for a pass along axis with radius R: invalid, regular (R grid steps both ways
   stay valid and unrotated: the taps index directly), walked */
static uint32_t ero__pass_kind(const ero__run *r, size_t i, int axis, int R)
{
    const uint8_t *g = r->reg + 4 * i + 2 * axis;
    if (!ero__valid(r, (uint32_t)i)) return ERO__RUN_INVALID;
    return g[0] >= R && g[1] >= R ? ERO__RUN_REGULAR : ERO__RUN_WALK;
}

/* the runs of one pass kind within each row (at most ERO__SPAN long) into seg (NULL: counted); the
   walked texels' count into *walked */
static size_t ero__pass_runs(const ero__run *r, int axis, int R, uint32_t *seg, size_t *walked)
{
    size_t W = (size_t)r->W, y, x, cnt = 0;
    *walked = 0;
    for (y = 0; y < (size_t)r->H; y++)
        for (x = 0; x < W;) {
            size_t i = y * W + x, e = x + 1;
            uint32_t kind = ero__pass_kind(r, i, axis, R);
            while (e < W && e - x < ERO__SPAN && ero__pass_kind(r, y * W + e, axis, R) == kind) e++;
            if (seg) { seg[2 * cnt] = (uint32_t)i; seg[2 * cnt + 1] = (uint32_t)(e - x) << 2 | kind; }
            if (kind == ERO__RUN_WALK) *walked += e - x;
            cnt++;
            x = e;
        }
    return cnt;
}

/* ero__step, the grid's steps (the regular-run table) without a lookup */
ERO__INLINE uint32_t ero__walk_step(const ero__run *r, uint32_t j, int *d, int *turns)
{
    static const int sign[4] = {1, -1, 1, -1};
    if (j == ERO__NONE) return j;
    if (r->reg[4 * (size_t)j + (size_t)*d]) return (uint32_t)((long)j + sign[*d] * (*d < 2 ? 1L : (long)r->W));
    return ero__step(r, j, d, turns);
}

/* the walks of walked texel i (number e): R steps each way along axis, the taps met and whether
   an odd number of quarter turns led to them */
static void ero__walk(const ero__run *r, ero__walks *wk, size_t e, uint32_t i, int axis, int R)
{
    uint32_t *t = wk->tap + 2 * (size_t)R * e, jp = i, jm = i;
    uint8_t *o = wk->odd + 2 * (size_t)R * e;
    int dp = 2 * axis, dm = 2 * axis + 1, tp = 0, tm = 0, k;
    wk->texel[e] = i;
    for (k = 0; k < R; k++) {
        jp = ero__walk_step(r, jp, &dp, &tp);
        jm = ero__walk_step(r, jm, &dm, &tm);
        t[2 * k] = jp; o[2 * k] = (uint8_t)(tp & 1);
        t[2 * k + 1] = jm; o[2 * k + 1] = (uint8_t)(tm & 1);
    }
}

/* the odd taps of the second pass (axis 1): their walks (a texel's walk number kept in the
   bits of hh, free until the first step) and room for C channels of values */
static ero_result ero__record_alt(ero__run *r, ero__walks *wk, int R, int C)
{
    size_t e, m = 0, k;
    uint32_t q;
    for (e = 0; e < 2 * (size_t)R * wk->count; e++) m += wk->odd[e] && wk->tap[e] != ERO__NONE;
    wk->alt_count = m;
    if (!m) return ERO_OK;
    wk->alt_walk = (uint32_t *)ero__alloc(r->al, m * sizeof(uint32_t));
    wk->alt[0] = (float *)ero__alloc(r->al, (size_t)C * m * sizeof(float));
    if (!wk->alt_walk || !wk->alt[0]) return ERO_ERR_OUT_OF_MEMORY;
    for (k = 1; k < (size_t)C; k++) wk->alt[k] = wk->alt[0] + k * m;
    for (e = 0; e < wk->count; e++) {
        q = (uint32_t)e;
        memcpy(r->hh + wk->texel[e], &q, sizeof q);
    }
    for (e = 0, m = 0; e < 2 * (size_t)R * wk->count; e++) {
        uint32_t j = wk->tap[e];
        if (!wk->odd[e] || j == ERO__NONE) continue;
        q = ERO__NONE;
        if (ero__pass_kind(r, j, 1, R) == ERO__RUN_WALK) memcpy(&q, r->hh + j, sizeof q);
        wk->alt_walk[m++] = q;
    }
    return ERO_OK;
}

/* walked texel e's taps as the first R of the Rb a wider kernel's walk q recorded */
static void ero__walk_prefix(ero__walks *wk, size_t e, int R, const ero__walks *wide, size_t q, int Rb)
{
    memcpy(wk->tap + 2 * (size_t)R * e, wide->tap + 2 * (size_t)Rb * q, 2 * (size_t)R * sizeof(uint32_t));
    memcpy(wk->odd + 2 * (size_t)R * e, wide->odd + 2 * (size_t)Rb * q, 2 * (size_t)R);
    wk->texel[e] = wide->texel[q];
}

/* one kernel's and axis's runs and walks; a texel walked for R is walked for the wider kernel's
   Rb >= R as well (wide, NULL: none), and the first R steps of its walks are the same */
static ero_result ero__record_walks(ero__run *r, ero__walks *wk, int axis, int R, int C, const ero__walks *wide, int Rb)
{
    size_t walked, k, e = 0, q = 0;
    wk->seg_count = ero__pass_runs(r, axis, R, NULL, &walked);
    wk->count = walked;
    wk->seg = (uint32_t *)ero__alloc(r->al, 2 * wk->seg_count * sizeof(uint32_t));
    wk->texel = (uint32_t *)ero__alloc(r->al, walked * sizeof(uint32_t) + 1);
    wk->tap = (uint32_t *)ero__alloc(r->al, 2 * (size_t)R * walked * sizeof(uint32_t) + 1);
    wk->odd = (uint8_t *)ero__alloc(r->al, 2 * (size_t)R * walked + 1);
    if (!wk->seg || !wk->texel || !wk->tap || !wk->odd) return ERO_ERR_OUT_OF_MEMORY;
    ero__pass_runs(r, axis, R, wk->seg, &walked);
    for (k = 0; k < wk->seg_count; k++) {
        uint32_t i0 = wk->seg[2 * k], len = wk->seg[2 * k + 1] >> 2, i;
        if ((wk->seg[2 * k + 1] & 3) != ERO__RUN_WALK) continue;
        for (i = i0; i < i0 + len; i++) {
            if (!wide) { ero__walk(r, wk, e++, i, axis, R); continue; }
            while (wide->texel[q] < i) q++;
            ero__walk_prefix(wk, e++, R, wide, q, Rb);
        }
    }
    return axis == 1 && r->has_rot ? ero__record_alt(r, wk, R, C) : ERO_OK;
}

/* every kernel's and axis's walks (box: 4 channels, Gaussian: 1) */
static ero_result ero__record_all_walks(ero__run *r)
{
    int axis;
    ero_result e;
    size_t most = 0;
    if (r->hf && r->ring) return ERO_OK;
    for (axis = 0; axis < 2; axis++) {
        int wide = r->gau_r >= r->box_r, Rw = wide ? r->gau_r : r->box_r, Rn = wide ? r->box_r : r->gau_r;
        ero__walks *ww = &r->walks[wide][axis];
        if (Rw && (e = ero__record_walks(r, ww, axis, Rw, wide ? 1 : 4, NULL, 0)) != ERO_OK) return e;
        if (Rn && (e = ero__record_walks(r, &r->walks[!wide][axis], axis, Rn, wide ? 4 : 1, ww, Rw)) != ERO_OK) return e;
        if (4 * r->walks[0][axis].count > most) most = 4 * r->walks[0][axis].count;
        if (r->walks[1][axis].count > most) most = r->walks[1][axis].count;
    }
    r->wvals = (float *)ero__alloc(r->al, most * sizeof(float) + 1);
    return r->wvals ? ERO_OK : ERO_ERR_OUT_OF_MEMORY;
}

static void ero__free_walks(ero__run *r)
{
    int kern, axis;
    ero__free(r->al, r->wvals);
    for (kern = 0; kern < 2; kern++)
        for (axis = 0; axis < 2; axis++) {
            ero__walks *wk = &r->walks[kern][axis];
            ero__free(r->al, wk->seg);
            ero__free(r->al, wk->texel);
            ero__free(r->al, wk->tap);
            ero__free(r->al, wk->odd);
            ero__free(r->al, wk->alt_walk);
            ero__free(r->al, wk->alt[0]);
        }
}

/* the taps of a regular run of n texels along a stride st (1 or W): w[0] f + (w[k] f(+k) +
   w[k] f(-k)) for k = 1..R in that order, times inv (the reciprocal of the weights' sum), as
   ero__walked_taps sums them */
static void ero__taps_line(const float *ERO__RESTRICT f, float *ERO__RESTRICT out, long n, long st, const float *w,
                           int R, float inv)
{
    long x;
    int k;
    float w0 = w[0];
    for (x = 0; x < n; x++) out[x] = w0 * f[x];
    for (k = 1; k <= R; k++) {
        const float *ERO__RESTRICT up = f + k * st, *ERO__RESTRICT dn = f - k * st;
        float wk = w[k];
        for (x = 0; x < n; x++) out[x] = (out[x] + wk * up[x]) + wk * dn[x];
    }
    for (x = 0; x < n; x++) out[x] = out[x] * inv;
}

/* the taps of walked texel number e: odd taps read alt's values in the order the pass meets
   them (*next counts them; alt NULL: src's own values) */
ERO__INLINE void ero__walked_taps(const ero__walks *wk, size_t e, uint32_t i, float *const *src, float *const *alt,
                                  size_t *next, int C, const float *w, int R, float *out)
{
    const uint32_t *t = wk->tap + 2 * (size_t)R * e;
    const uint8_t *o = wk->odd + 2 * (size_t)R * e;
    float acc[4], ws = w[0];
    int c, k, s;
    for (c = 0; c < C; c++) acc[c] = w[0] * src[c][i];
    for (k = 0; k < R; k++)
        for (s = 0; s < 2; s++) {
            uint32_t j = t[2 * k + s];
            if (j == ERO__NONE) continue;
            if (o[2 * k + s] && alt) {
                for (c = 0; c < C; c++) acc[c] += w[k + 1] * alt[c][*next];
                ++*next;
            } else
                for (c = 0; c < C; c++) acc[c] += w[k + 1] * src[c][j];
            ws += w[k + 1];
        }
    ws = 1.0f / ws;
    for (c = 0; c < C; c++) out[c] = acc[c] * ws;
}

/* every walked texel's taps (ero__walked_taps, in its order) into vals, C per texel: one loop
   whose loads do not wait on each other, as those across seams miss the cache */
static void ero__walked_all(const ero__walks *wk, float *const *src, float *const *alt, int C, const float *w, int R,
                            float *vals)
{
    size_t e, next = 0;
    if (C == 4)
        for (e = 0; e < wk->count; e++) ero__walked_taps(wk, e, wk->texel[e], src, alt, &next, 4, w, R, vals + 4 * e);
    else
        for (e = 0; e < wk->count; e++) ero__walked_taps(wk, e, wk->texel[e], src, alt, &next, C, w, R, vals + (size_t)C * e);
}

/* the y pass of src at the second pass's odd taps (texel by texel: regular ones directly,
   the others by their walks), into wk->alt */
static void ero__alt_values(const ero__run *r, ero__walks *wk, float *const *src, int C, const float *w, int R,
                            float inv)
{
    size_t e, m = 0, W = (size_t)r->W;
    float v[4];
    int c, k;
    for (e = 0; e < 2 * (size_t)R * wk->count; e++) {
        uint32_t j = wk->tap[e], q;
        if (!wk->odd[e] || j == ERO__NONE) continue;
        q = wk->alt_walk[m];
        if (q != ERO__NONE) ero__walked_taps(wk, q, j, src, NULL, NULL, C, w, R, v);
        else
            for (c = 0; c < C; c++) {
                const float *f = src[c] + j;
                float acc = w[0] * f[0];
                for (k = 1; k <= R; k++) {
                    acc += w[k] * f[(size_t)k * W];
                    acc += w[k] * f[-(ptrdiff_t)((size_t)k * W)];
                }
                v[c] = acc * inv;
            }
        for (c = 0; c < C; c++) wk->alt[c][m] = v[c];
        m++;
    }
}

/* what a pass does with a run's values: planes (into out), H of the box's averages (into hh), the
   change applied (the Gaussian's) */
enum { ERO__SINK_PLANES = 0, ERO__SINK_H = 1, ERO__SINK_APPLY = 2 };

static float ero__apply_texel(ero__run *r, size_t i, float h, ero_report *rep);
static void ero__surface_apply_run(ero__run *r, size_t i0, long n, const float *h, ero_report *rep);
static void ero__h_span(const ero__run *r, const float *a0, const float *a1, const float *a2, const float *kap,
                        const uint8_t *mat, long cnt, float *const *mrow, float *out);
static void ero__fill_materials(const ero__run *r, float *const *mrow);

/* a run's values v (len of them, C channels, from texel i0) to the sink */
static void ero__sink(ero__run *r, int sink, float *const *v, size_t i0, size_t len, ero_report *rep)
{
    size_t x;
    float *mrow[4];
    int k;
    if (sink == ERO__SINK_H) {
        for (k = 0; k < 4; k++) mrow[k] = r->span + (size_t)k * ERO__SPAN;
        ero__h_span(r, v[0], v[1], v[2], v[3], r->mat ? r->mat + i0 : NULL, (long)len, mrow, r->hh + i0);
    } else if (sink == ERO__SINK_APPLY && !r->hf)
        ero__surface_apply_run(r, i0, (long)len, v[0], rep);
    else if (sink == ERO__SINK_APPLY)
        for (x = 0; x < len; x++) r->hh[i0 + x] = ero__apply_texel(r, i0 + x, v[0][x], rep);
}

/* one filter pass along `axis` of every texel of src: regular runs by ero__taps_line, walked
   texels by their recorded taps (odd ones from alt, NULL: src); a run's values go into out
   (invalid texels 0; out = src along x: a row at a time, once the row is done) or, a run at a
   time, to a sink (invalid texels: H 0, no change) */
static void ero__pass(ero__run *r, int axis, float *const *src, float *const *alt, float *const *out, int C,
                      const float *w, int R, float wfull, const ero__walks *wk, int sink, ero_report *rep)
{
    size_t k, e = 0, W = (size_t)r->W;
    long st = axis ? (long)r->W : 1;
    float inv = 1.0f / wfull, *o[4];
    int c, inplace = sink == ERO__SINK_PLANES && out == src && axis == 0;
    if (sink != ERO__SINK_PLANES) ero__fill_materials(r, NULL);
    ero__walked_all(wk, src, alt, C, w, R, r->wvals);
    for (k = 0; k < wk->seg_count; k++) {
        uint32_t i0 = wk->seg[2 * k], len = wk->seg[2 * k + 1] >> 2, kind = wk->seg[2 * k + 1] & 3, i;
        size_t row0 = i0 / W * W;
        if (inplace && k > 0 && i0 == row0)
            for (c = 0; c < C; c++) memcpy(src[c] + row0 - W, r->rowbuf + (size_t)c * W, W * sizeof(float));
        for (c = 0; c < C; c++)
            o[c] = inplace ? r->rowbuf + (size_t)c * W + (i0 - row0)
                 : sink == ERO__SINK_PLANES ? out[c] + i0 : r->span + (size_t)(4 + c) * ERO__SPAN;
        if (kind == ERO__RUN_INVALID) {
            if (sink == ERO__SINK_PLANES) for (c = 0; c < C; c++) memset(o[c], 0, len * sizeof(float));
            if (sink == ERO__SINK_H) memset(r->hh + i0, 0, len * sizeof(float));
            continue;
        }
        if (kind == ERO__RUN_REGULAR)
            for (c = 0; c < C; c++) ero__taps_line(src[c] + i0, o[c], (long)len, st, w, R, inv);
        else
            for (i = 0; i < len; i++, e++)
                for (c = 0; c < C; c++) o[c][i] = r->wvals[(size_t)C * e + (size_t)c];
        ero__sink(r, sink, o, i0, len, rep);
    }
    if (inplace && wk->seg_count)
        for (c = 0; c < C; c++) memcpy(src[c] + r->n - W, r->rowbuf + (size_t)c * W, W * sizeof(float));
}

/* the planes src (C of them) filtered along each texel's x then y: pass 1 along own x into mid
   (may be src), pass 2 along own y over the values that continue this texel's x (across a seam
   that turns the axes, the y pass of src at the texel reached: ero__alt_values, before pass 1
   overwrites src), to the sink (R > 0) */
static void ero__filter(ero__run *r, int kern, float **src, float **mid, int C, const float *w, int R, float wfull,
                        int sink, ero_report *rep)
{
    ero__walks *wk = r->walks[kern];
    if (wk[1].alt_count) ero__alt_values(r, &wk[1], src, C, w, R, 1.0f / wfull);
    ero__pass(r, 0, src, NULL, mid, C, w, R, wfull, &wk[0], ERO__SINK_PLANES, NULL);
    ero__pass(r, 1, mid, wk[1].alt_count ? wk[1].alt : NULL, NULL, C, w, R, wfull, &wk[1], sink, rep);
}

/* ================================================================================================
   the model: H = W_f / R
   ================================================================================================ */




/* ================================================================================================
   applying the change, the report, the invalid texels
   ================================================================================================ */

static inline double ero__column(const ero__run *r, size_t i, float t0, float t1)
{
    double a = t0, b = t1;
    if (r->hf) return (double)r->s * r->s * (b - a);
    return r->area[i] * ((b - a) + r->q1[i] * (b * b - a * a) / 2.0 + r->q2[i] * (b * b * b - a * a * a) / 3.0);
}

/* the deposition bound (see MODEL): disp >= bound for a surface, height <= bound for a height
   field, for the new value d of a texel that was d0; a texel already beyond the bound may erode
   back toward it but not deposit further */
static float ero__bounded(const ero__run *r, float d0, float d)
{
    float bv = r->o.bound == ERO_BOUND_VALUE ? r->o.bound_value : 0.0f;
    if (r->o.bound == ERO_BOUND_NONE || (r->o.bound == ERO_BOUND_DEFAULT && r->hf)) return d;
    if (r->hf) {
        float lim = d0 > bv ? d0 : bv;
        return d > lim ? lim : d;
    } else {
        float lim = d0 < bv ? d0 : bv;
        return d < lim ? lim : d;
    }
}

/* adds rate * h to valid texel i (the bound, the report), returns the change of disp */
static inline float ero__apply_texel(ero__run *r, size_t i, float h, ero_report *rep)
{
    float d0 = r->disp[i], d1, ch;
    double vol;
    if (r->hf) { /* height: erosion lowers it */
        d1 = ero__bounded(r, d0, d0 - r->o.rate * h);
        if (!ero__finite(d1)) d1 = d0;
        ch = d0 - d1;
        vol = ero__column(r, i, -d0, -d1);
    } else {
        d1 = ero__bounded(r, d0, d0 + r->o.rate * h);
        if (!ero__finite(d1)) d1 = d0;
        ch = d1 - d0;
        vol = ero__column(r, i, d0, d1);
    }
    r->disp[i] = d1;
    if (!(vol - vol == 0.0)) vol = 0.0; /* not finite: beyond float's range, unreported */
    if (vol > 0.0) rep->eroded += vol;
    else rep->deposited -= vol;
    if (fabsf(ch) > rep->max_change) rep->max_change = fabsf(ch);
    return d1 - d0;
}

/* ero__apply_texel for n valid surface texels from i0 (changes h), in loops that vectorise, the
   report's sums in their order; the texels' surface points updated */
static void ero__surface_apply_run(ero__run *r, size_t i0, long n, const float *ERO__RESTRICT h, ero_report *rep)
{
    float *ERO__RESTRICT d = r->disp + i0, *ERO__RESTRICT chg = r->hh + i0, rate = r->o.rate, mx = rep->max_change;
    const float *ERO__RESTRICT q1 = r->q1 + i0, *ERO__RESTRICT q2 = r->q2 + i0, *ERO__RESTRICT ar = r->area + i0;
    const float *ERO__RESTRICT pos = r->pos + 3 * i0, *ERO__RESTRICT nrm = r->nrm + 3 * i0;
    float bv = r->o.bound == ERO_BOUND_VALUE ? r->o.bound_value : 0.0f;
    int bounded = r->o.bound != ERO_BOUND_NONE;
    double vol[ERO__SPAN], er = rep->eroded, de = rep->deposited;
    long x;
    int k;
    for (x = 0; x < n; x++) {
        float d0 = d[x], dn = d0 + rate * h[x], lim = d0 < bv ? d0 : bv, db = dn < lim ? lim : dn;
        float d1b = bounded ? db : dn, d1 = ero__fin(d1b) ? d1b : d0;
        double a = d0, b = d1;
        chg[x] = d1 - d0;
        d[x] = d1;
        vol[x] = ar[x] * ((b - a) + q1[x] * (b * b - a * a) / 2.0 + q2[x] * (b * b * b - a * a * a) / 3.0);
    }
    for (x = 0; x < n; x++) { /* in order: the same sums as ero__apply_texel's */
        double v = vol[x] - vol[x] == 0.0 ? vol[x] : 0.0;
        float c = fabsf(chg[x]);
        er += v > 0.0 ? v : 0.0;
        de -= v > 0.0 ? 0.0 : v;
        mx = c > mx ? c : mx;
    }
    rep->eroded = er;
    rep->deposited = de;
    rep->max_change = mx;
    for (k = 0; k < 3; k++) {
        float *ERO__RESTRICT p = r->P[k] + i0;
        for (x = 0; x < n; x++) p[x] = pos[3 * x + k] - d[x] * nrm[3 * x + k];
    }
}

static void ero__apply(ero__run *r, ero_report *rep)
{
    size_t i;
    for (i = 0; i < r->n; i++)
        if (ero__valid(r, (uint32_t)i)) r->hh[i] = ero__apply_texel(r, i, r->hh[i], rep);
}

/* the image neighbours j of texel (x, y), row by row, with 0 <= mark[j] < ring, into nb */
ERO__INLINE int ero__ext_neighbours(const float *mark, long W, long H, long x, long y, float ring, uint32_t *nb)
{
    long dx, dy;
    int cnt = 0;
    for (dy = -1; dy <= 1; dy++) {
        long yy = y + dy;
        if (yy < 0 || yy >= H) continue;
        for (dx = -1; dx <= 1; dx++) {
            long xx = x + dx;
            size_t j = (size_t)(yy * W + xx);
            if (xx >= 0 && xx < W && mark[j] >= 0.0f && mark[j] < ring) nb[cnt++] = (uint32_t)j;
        }
    }
    return cnt;
}

/* invalid texels within two image texels of valid ones take the mean change of the image
   neighbours set before them (ring 1 from valid texels, ring 2 from ring 1): the rings marked in
   g[0] (0 valid, 1 and 2 the rings, -1 the rest) and their length counted; with ext, each ring
   texel and its neighbours (in the order they are summed) listed from the marks */
static size_t ero__find_extension(ero__run *r, uint32_t *ext)
{
    long W = r->W, H = r->H, x, y;
    int ring, k;
    float *mark = r->g[0];
    size_t i, len = 0;
    uint32_t nb[9];
    if (ext) {
        for (ring = 1; ring <= 2; ring++)
            for (y = 0, i = 0; y < H; y++)
                for (x = 0; x < W; x++, i++) {
                    if (mark[i] != (float)ring) continue;
                    ext[len] = (uint32_t)i;
                    ext[len + 1] = (uint32_t)ero__ext_neighbours(mark, W, H, x, y, (float)ring, nb);
                    for (k = 0; k < (int)ext[len + 1]; k++) ext[len + 2 + (size_t)k] = nb[k];
                    len += 2 + ext[len + 1];
                }
        return len;
    }
    for (i = 0; i < r->n; i++) mark[i] = r->valid[i] ? 0.0f : -1.0f;
    for (ring = 1; ring <= 2; ring++) {
        for (y = 0, i = 0; y < H; y++)
            for (x = 0; x < W; x++, i++) {
                int cnt;
                if (mark[i] >= 0.0f || mark[i] < -1.5f) continue;
                cnt = ero__ext_neighbours(mark, W, H, x, y, (float)ring, nb);
                if (!cnt) continue;
                mark[i] = -2.0f - (float)ring;
                len += 2 + (size_t)cnt;
            }
        for (i = 0; i < r->n; i++) /* this ring becomes readable by the next */
            if (mark[i] <= -3.0f) mark[i] = (float)ring;
    }
    return len;
}

static ero_result ero__extension(ero__run *r)
{
    if (!r->valid || (r->o.flags & ERO_KEEP_INVALID)) return ERO_OK;
    r->ext_len = ero__find_extension(r, NULL);
    r->ext = (uint32_t *)ero__alloc(r->al, (r->ext_len + 1) * sizeof(uint32_t));
    if (!r->ext) return ERO_ERR_OUT_OF_MEMORY;
    ero__find_extension(r, r->ext);
    return ERO_OK;
}

/* the rings' changes (ring 1 then ring 2: each mean reads the ones before it) and their bound */
static void ero__extend_invalid(ero__run *r)
{
    size_t e, k;
    if (!r->ext) return;
    for (e = 0; e < r->ext_len; e += 2 + r->ext[e + 1]) {
        double s = 0.0;
        uint32_t cnt = r->ext[e + 1];
        for (k = 0; k < cnt; k++) s += r->hh[r->ext[e + 2 + k]];
        r->hh[r->ext[e]] = (float)(s / cnt);
    }
    for (e = 0; e < r->ext_len; e += 2 + r->ext[e + 1]) {
        uint32_t i = r->ext[e];
        float d = ero__bounded(r, r->disp[i], r->disp[i] + r->hh[i]);
        if (ero__finite(d)) r->disp[i] = d;
    }
}

/* ================================================================================================
   a plain height field (no valid map): one pass over a ring of rows
   ================================================================================================ */

/* Every texel of a wrapped field, and every texel off a border of an unwrapped one, has the four
   grid neighbours: its geometry, filters and H run row by row on short rows that stay in cache,
   in loops that vectorise, the same sums for every texel (so a circular shift shifts the bits).
   A row's geometry is box-filtered along x as it is made, into a ring of 2 box_r + 1 rows; box_r
   rows later the box's y pass over them and H, H's Gaussian along x into a ring of 2 gau_r + 1
   rows; gau_r rows later the Gaussian's y pass and the change (each y pass reads its rows in
   place, so it fuses with what follows). The rows the geometry still reads after they changed
   come from copies (the first ones, for the wrap; the last four).
   The box sums are not divided by the weights' sum: the averaged normal's direction does not
   depend on its length, and the curvature's sum is divided through kf (per column: minus
   curvature_length over the sum) and a row factor. The geometry's four channels are the unit
   normal's x and y negated, its z, and the mean curvature negated (ero__hf_texel); the signs are
   folded into the wind and kf. */

typedef struct ero__rows {
    size_t Wp;            /* the row length (ero__ring_stride) */
    int pad;              /* columns before x = 0 in a padded row: the larger radius, rounded up to 8 */
    float *geo[4];        /* padded: one row's geometry (ero__hf_texel's channels) */
    float *gx[4];         /* 2 box_r + 2 rows each, chs floats apart: the geometry's box sums along x
                             (the last row zeros: the rows beyond an unwrapped border) */
    size_t chs;
    float *hrow;          /* padded: one row's H */
    float *hx;            /* 2 gau_r + 2 rows: H's Gaussian along x (the last row zeros) */
    float *avg[4];        /* one row's box sums (along x, then y) */
    float *chg;           /* one row's Gaussian (along x, then y) */
    float *er, *de, *mx;  /* per column: the report's sums and largest change over the last rows */
    float *kf;            /* per column: -curvature_length / (the box's x weights inside the row times all of them) */
    float *gf;            /* per column: rate / the Gaussian's x weights inside the row (over their full sum) */
    float *mrow[4];       /* a row's resistance R(c) = m0 + c (m1 + c m2), and ambient */
    float wb[ERO__MAXR + 1], wg[ERO__MAXR + 1]; /* the box's weights; the Gaussian's over their sum */
    float coef[256][4];   /* per material: m0, m1, m2, ambient */
    float *head;          /* the first rows before the step (a wrapped field reads them last) */
    float *orig;          /* the last four applied rows before the step (box_r = gau_r = 0 only) */
    long head_rows, applied;
} ero__rows;

static int ero__ring_fits(const ero__run *r)
{
    long R = r->box_r > r->gau_r ? r->box_r : r->gau_r;
    return r->hf && !r->valid && r->W >= 2 * R + 3 && r->H >= 2 * (r->box_r + r->gau_r) + 4;
}

/* the rows' length: W rounded up to 8, and 16 more so that rows a power of two long do not sit
   4 KiB apart (the ring's rows would share L1 sets and stall on false store-to-load aliasing) */
static size_t ero__ring_stride(const ero__run *r) { return (((size_t)r->W + 7) & ~(size_t)7) + 16; }
static int ero__ring_pad(const ero__run *r) { return ((r->box_r > r->gau_r ? r->box_r : r->gau_r) + 7) & ~7; }

static size_t ero__ring_floats(const ero__run *r)
{
    size_t Wp = ero__ring_stride(r), rows, padded = Wp + 2 * (size_t)ero__ring_pad(r);
    rows = 4 * (2 * (size_t)r->box_r + 2) + (2 * (size_t)r->gau_r + 2) + 4 + 1 + 3 + 2 + 4;
    return rows * Wp + 5 * padded + ((size_t)(r->box_r + r->gau_r + 2) + 4) * (size_t)r->W + 16;
}

static void ero__ring_carve(ero__run *r, ero__rows *q, float *f)
{
    size_t Wp = ero__ring_stride(r), padded;
    int k;
    f += (64 - (size_t)((uintptr_t)f % 64)) % 64 / sizeof(float); /* rows on cache lines: 8-float loads do not split */
    q->Wp = Wp;
    q->pad = ero__ring_pad(r);
    padded = Wp + 2 * (size_t)q->pad;
    q->chs = (2 * (size_t)r->box_r + 2) * Wp;
    for (k = 0; k < 4; k++) { q->gx[k] = f; f += q->chs; }
    q->hx = f; f += (2 * (size_t)r->gau_r + 2) * Wp;
    for (k = 0; k < 4; k++) { q->geo[k] = f + q->pad; f += padded; }
    q->hrow = f + q->pad; f += padded;
    for (k = 0; k < 4; k++) { q->avg[k] = f; f += Wp; }
    q->chg = f; f += Wp;
    q->er = f; f += Wp;
    q->de = f; f += Wp;
    q->mx = f; f += Wp;
    q->kf = f; f += Wp;
    q->gf = f; f += Wp;
    for (k = 0; k < 4; k++) { q->mrow[k] = f; f += Wp; }
    q->head_rows = r->box_r + r->gau_r + 2;
    q->head = f; f += (size_t)q->head_rows * (size_t)r->W;
    q->orig = f;
}

/* the weights of the taps inside the row at column x (all of them with wrap), summed as
   ero__kernels sums the full kernel */
static float ero__col_sum(const ero__run *r, const float *w, int R, long x)
{
    float s = w[0];
    int k;
    for (k = 1; k <= R; k++) {
        if (r->wrap || x + k < r->W) s += w[k];
        if (r->wrap || x - k >= 0) s += w[k];
    }
    return s;
}

/* the weights and the per-column factors (kf, gf: see ero__rows); the resistance's coefficients */
static void ero__ring_weights(const ero__run *r, ero__rows *q)
{
    long x;
    size_t m;
    int k;
    float lc = r->o.curvature_length;
    for (k = 0; k <= r->box_r; k++) q->wb[k] = r->box_w[k];
    for (k = 0; k <= r->gau_r; k++) q->wg[k] = r->gau_w[k] / r->gau_sum;
    for (x = 0; x < r->W; x++) {
        q->kf[x] = -lc / (ero__col_sum(r, r->box_w, r->box_r, x) * r->box_sum);
        q->gf[x] = r->o.rate * (r->gau_sum / ero__col_sum(r, r->gau_w, r->gau_r, x));
    }
    for (m = 0; m < r->mat_count; m++) {
        const ero_material *e = &r->mats[m];
        q->coef[m][0] = e->eps_max;
        q->coef[m][1] = 2.0f * (e->eps_medium - e->eps_max);
        q->coef[m][2] = (e->eps_max - 2.0f * e->eps_medium) + e->eps_min;
        q->coef[m][3] = e->ambient;
    }
}

/* out[x] = w[0] c[x] + w[1] (up[0][x] + dn[0][x]) + ... + w[R] (up[R - 1][x] + dn[R - 1][x]),
   added in that order (two taps a loop) */
static void ero__taps(const float *const *up, const float *const *dn, const float *ERO__RESTRICT c,
                      float *ERO__RESTRICT out, long n, const float *w, int R)
{
    long x;
    int k = 1;
    float w0 = w[0];
    if (R >= 3 && R % 2 == 1) { /* three taps first, then pairs: no single tap left */
        const float *ERO__RESTRICT u1 = up[0], *ERO__RESTRICT d1 = dn[0], *ERO__RESTRICT u2 = up[1],
                                   *ERO__RESTRICT d2 = dn[1], *ERO__RESTRICT u3 = up[2], *ERO__RESTRICT d3 = dn[2];
        float w1 = w[1], w2 = w[2], w3 = w[3];
        for (x = 0; x < n; x++)
            out[x] = ((w0 * c[x] + w1 * (u1[x] + d1[x])) + w2 * (u2[x] + d2[x])) + w3 * (u3[x] + d3[x]);
        k = 4;
    } else if (R >= 2) {
        const float *ERO__RESTRICT u1 = up[0], *ERO__RESTRICT d1 = dn[0], *ERO__RESTRICT u2 = up[1],
                                   *ERO__RESTRICT d2 = dn[1];
        float w1 = w[1], w2 = w[2];
        for (x = 0; x < n; x++) out[x] = (w0 * c[x] + w1 * (u1[x] + d1[x])) + w2 * (u2[x] + d2[x]);
        k = 3;
    } else if (R == 1) {
        const float *ERO__RESTRICT u1 = up[0], *ERO__RESTRICT d1 = dn[0];
        float w1 = w[1];
        for (x = 0; x < n; x++) out[x] = w0 * c[x] + w1 * (u1[x] + d1[x]);
        k = 2;
    } else for (x = 0; x < n; x++) out[x] = w0 * c[x];
    for (; k + 1 <= R; k += 2) {
        const float *ERO__RESTRICT ua = up[k - 1], *ERO__RESTRICT da = dn[k - 1], *ERO__RESTRICT ub = up[k],
                                   *ERO__RESTRICT db = dn[k];
        float wa = w[k], wb = w[k + 1];
        for (x = 0; x < n; x++) out[x] = (out[x] + wa * (ua[x] + da[x])) + wb * (ub[x] + db[x]);
    }
    if (k == R) {
        const float *ERO__RESTRICT ua = up[k - 1], *ERO__RESTRICT da = dn[k - 1];
        float wa = w[k];
        for (x = 0; x < n; x++) out[x] = out[x] + wa * (ua[x] + da[x]);
    }
}

/* ero__taps for the box (ero__kernels: w[k] = 1 for k < R, w[R] = the end tap's weight): the same
   sums without the products by 1 */
static void ero__box_taps(const float *const *up, const float *const *dn, const float *ERO__RESTRICT c,
                          float *ERO__RESTRICT out, long n, const float *w, int R)
{
    long x;
    int k = 1;
    float we = w[R];
    if (R == 2) {
        const float *ERO__RESTRICT u1 = up[0], *ERO__RESTRICT d1 = dn[0], *ERO__RESTRICT u2 = up[1],
                                   *ERO__RESTRICT d2 = dn[1];
        for (x = 0; x < n; x++) out[x] = (c[x] + (u1[x] + d1[x])) + we * (u2[x] + d2[x]);
        return;
    }
    if (R < 2) {
        const float *ERO__RESTRICT u1 = up[0], *ERO__RESTRICT d1 = dn[0];
        if (R == 1) for (x = 0; x < n; x++) out[x] = c[x] + we * (u1[x] + d1[x]);
        else for (x = 0; x < n; x++) out[x] = c[x];
        return;
    }
    {
        const float *ERO__RESTRICT u1 = up[0], *ERO__RESTRICT d1 = dn[0], *ERO__RESTRICT u2 = up[1],
                                   *ERO__RESTRICT d2 = dn[1];
        for (x = 0; x < n; x++) out[x] = (c[x] + (u1[x] + d1[x])) + (u2[x] + d2[x]);
        k = 3;
    }
    for (; k + 1 < R; k += 2) {
        const float *ERO__RESTRICT ua = up[k - 1], *ERO__RESTRICT da = dn[k - 1], *ERO__RESTRICT ub = up[k],
                                   *ERO__RESTRICT db = dn[k];
        for (x = 0; x < n; x++) out[x] = (out[x] + (ua[x] + da[x])) + (ub[x] + db[x]);
    }
    for (; k < R; k++) {
        const float *ERO__RESTRICT ua = up[k - 1], *ERO__RESTRICT da = dn[k - 1];
        for (x = 0; x < n; x++) out[x] = out[x] + (ua[x] + da[x]);
    }
    {
        const float *ERO__RESTRICT ua = up[R - 1], *ERO__RESTRICT da = dn[R - 1];
        for (x = 0; x < n; x++) out[x] = out[x] + we * (ua[x] + da[x]);
    }
}

/* a padded row's columns beyond 0 .. W - 1: the other end's with wrap, else zeros */
static void ero__ring_pad_row(const ero__run *r, const ero__rows *q, float *p)
{
    long W = r->W, x;
    for (x = 1; x <= q->pad; x++) {
        p[-x] = r->wrap ? p[W - x] : 0.0f;
        p[W - 1 + x] = r->wrap ? p[x - 1] : 0.0f;
    }
}

/* one padded row filtered along x (its pads set first) into out (box: by ero__box_taps) */
static void ero__ring_xpass(const ero__run *r, const ero__rows *q, float *p, float *ERO__RESTRICT out, const float *w, int R,
                            int box)
{
    const float *up[ERO__MAXR], *dn[ERO__MAXR];
    int k;
    ero__ring_pad_row(r, q, p);
    up[0] = dn[0] = p; /* unread when R = 0 */
    for (k = 1; k <= R; k++) { up[k - 1] = p + k; dn[k - 1] = p - k; }
    if (box) ero__box_taps(up, dn, p, out, r->W, w, R);
    else ero__taps(up, dn, p, out, r->W, w, R);
}

#if !defined(ERO_USE_AVX2) /* (its AVX2 form fused with H and the change, below) */
/* the y pass: rows[R + k] is the row at offset k (ero__ring_window) */
static void ero__ring_ypass(float *const *rows, float *ERO__RESTRICT out, long W, const float *w, int R, int box)
{
    const float *up[ERO__MAXR], *dn[ERO__MAXR];
    int k;
    up[0] = dn[0] = rows[R]; /* unread when R = 0 */
    for (k = 1; k <= R; k++) { up[k - 1] = rows[R + k]; dn[k - 1] = rows[R - k]; }
    if (box) ero__box_taps(up, dn, rows[R], out, W, w, R);
    else ero__taps(up, dn, rows[R], out, W, w, R);
}
#endif
/* 1 / sqrt(x) for x >= 0 without sqrtf (whose errno keeps a loop from vectorising): the exponent
   halved on the bits (Lomont's constant), three Newton steps (relative error below 2e-7, about
   3 ulp; subnormal x scaled by 2^48 first); 0 for x = +inf, as 1 / sqrtf gives, and for x = 0
   or NaN (where callers take no direction) */
ERO__INLINE float ero__rsqrt(float x)
{
    uint32_t i;
    int tiny = x < 1.17549435e-38f;
    float xs = tiny ? x * 281474976710656.0f : x, y, hx = 0.5f * xs;
    memcpy(&i, &xs, sizeof i);
    i = 0x5f375a86u - (i >> 1);
    memcpy(&y, &i, sizeof y);
    y = y * (1.5f - hx * y * y);
    y = y * (1.5f - hx * y * y);
    y = y * (1.5f - hx * y * y);
    y = tiny ? y * 16777216.0f : y;
    return x > 0.0f && x < HUGE_VALF ? y : 0.0f;
}

/* the geometry of a texel with its four neighbours (MODEL's sums for a height field, where the
   offsets are (+-s, 0, d) and (0, +-s, d)): n = (-A, -B, 2s) / |.| with A, B twice the central
   differences, and the mean curvature -n_z ((d+x + d-x) / q_x + (d+y + d-y) / q_y) with q the
   offsets' squared lengths summed per axis. Out: A / |.|, B / |.|, n_z (0, 0, 1 where there is no
   direction) and minus the curvature (0 where not finite). The branches as selects, so that a
   row's loop vectorises. s2 = (2s)^2, q0 = 2 s^2 */
ERO__INLINE void ero__hf_texel(float hc, float hr, float hl, float hu, float hd, float S, float s2, float q0,
                               float *g0, float *g1, float *g2, float *g3)
{
    float dr = hr - hc, dl = hl - hc, du = hu - hc, dd = hd - hc;
    float A = dr - dl, B = du - dd, inv = ero__rsqrt((A * A + B * B) + s2), nz = S * inv;
    float qx = (dr * dr + dl * dl) + q0, qy = (du * du + dd * dd) + q0;
    float k = nz * ((dr + dl) / qx + (du + dd) / qy);
    *g0 = inv > 0.0f ? A * inv : 0.0f;
    *g1 = inv > 0.0f ? B * inv : 0.0f;
    *g2 = inv > 0.0f ? nz : 1.0f;
    *g3 = ero__fin(k) ? k : 0.0f;
}

#if !defined(ERO_USE_AVX2) /* (its AVX2 form below) */
/* the texels 1 .. W - 2 of a row with rows on both sides, in a loop that vectorises */
static void ero__hf_interior(const float *ERO__RESTRICT d, const float *ERO__RESTRICT m, const float *ERO__RESTRICT u,
                             float s, long W, float *ERO__RESTRICT g0, float *ERO__RESTRICT g1, float *ERO__RESTRICT g2,
                             float *ERO__RESTRICT g3)
{
    long x;
    float S = 2.0f * s, s2 = S * S, q0 = 2.0f * (s * s);
    for (x = 1; x < W - 1; x++) ero__hf_texel(m[x], m[x + 1], m[x - 1], u[x], d[x], S, s2, q0, &g0[x], &g1[x], &g2[x], &g3[x]);
}
#endif

#if defined(ERO_USE_AVX2)
/* ---- the ring's row loops in AVX2: the portable loops' operations, in their order, on 8 texels
   at once (so the same bits), the x passes fused with H and with the change; a group of 8 whose
   squared lengths are not all normal floats runs the portable code texel by texel ---- */

#define ERO__V8(f) _mm256_set1_ps(f)
/* ero__rsqrt for x in [FLT_MIN, inf): the same operations without its special cases */
ERO__INLINE __m256 ero__rsqrt8(__m256 x)
{
    __m256 hx = _mm256_mul_ps(ERO__V8(0.5f), x), th = ERO__V8(1.5f);
    __m256i i = _mm256_sub_epi32(_mm256_set1_epi32(0x5f375a86), _mm256_srli_epi32(_mm256_castps_si256(x), 1));
    __m256 y = _mm256_castsi256_ps(i);
    y = _mm256_mul_ps(y, _mm256_sub_ps(th, _mm256_mul_ps(_mm256_mul_ps(hx, y), y)));
    y = _mm256_mul_ps(y, _mm256_sub_ps(th, _mm256_mul_ps(_mm256_mul_ps(hx, y), y)));
    return _mm256_mul_ps(y, _mm256_sub_ps(th, _mm256_mul_ps(_mm256_mul_ps(hx, y), y)));
}
/* all 8 lanes in [FLT_MIN, inf) */
ERO__INLINE int ero__normal8(__m256 x)
{
    __m256 lo = _mm256_cmp_ps(x, ERO__V8(1.17549435e-38f), _CMP_GE_OQ), hi = _mm256_cmp_ps(x, ERO__V8(HUGE_VALF), _CMP_LT_OQ);
    return _mm256_movemask_ps(_mm256_and_ps(lo, hi)) == 0xff;
}
/* v where finite (v - v == 0), else 0 */
ERO__INLINE __m256 ero__fin8(__m256 v) { return _mm256_and_ps(_mm256_cmp_ps(_mm256_sub_ps(v, v), _mm256_setzero_ps(), _CMP_EQ_OQ), v); }

/* ero__hf_interior */
static void ero__hf_interior8(const float *d, const float *m, const float *u, float s, long W, float *g0, float *g1,
                              float *g2, float *g3)
{
    long x = 1;
    float S = 2.0f * s, s2 = S * S, q0 = 2.0f * (s * s);
    __m256 vS = ERO__V8(S), vs2 = ERO__V8(s2), vq0 = ERO__V8(q0);
    for (; x + 8 <= W - 1; x += 8) {
        __m256 hc = _mm256_loadu_ps(m + x), dr = _mm256_sub_ps(_mm256_loadu_ps(m + x + 1), hc);
        __m256 dl = _mm256_sub_ps(_mm256_loadu_ps(m + x - 1), hc), du = _mm256_sub_ps(_mm256_loadu_ps(u + x), hc);
        __m256 dd = _mm256_sub_ps(_mm256_loadu_ps(d + x), hc), A = _mm256_sub_ps(dr, dl), B = _mm256_sub_ps(du, dd);
        __m256 len = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(A, A), _mm256_mul_ps(B, B)), vs2), inv, nz, qx, qy, k;
        if (!ero__normal8(len)) {
            long e;
            for (e = x; e < x + 8; e++)
                ero__hf_texel(m[e], m[e + 1], m[e - 1], u[e], d[e], S, s2, q0, &g0[e], &g1[e], &g2[e], &g3[e]);
            continue;
        }
        inv = ero__rsqrt8(len);
        nz = _mm256_mul_ps(vS, inv);
        qx = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dr, dr), _mm256_mul_ps(dl, dl)), vq0);
        qy = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(du, du), _mm256_mul_ps(dd, dd)), vq0);
        k = _mm256_mul_ps(nz, _mm256_add_ps(_mm256_div_ps(_mm256_add_ps(dr, dl), qx), _mm256_div_ps(_mm256_add_ps(du, dd), qy)));
        _mm256_storeu_ps(g0 + x, _mm256_mul_ps(A, inv));
        _mm256_storeu_ps(g1 + x, _mm256_mul_ps(B, inv));
        _mm256_storeu_ps(g2 + x, nz);
        _mm256_storeu_ps(g3 + x, ero__fin8(k));
    }
    for (; x < W - 1; x++) ero__hf_texel(m[x], m[x + 1], m[x - 1], u[x], d[x], S, s2, q0, &g0[x], &g1[x], &g2[x], &g3[x]);
}

#undef ERO__V8
#endif

/* the geometry of row y from the rows dn (y - 1), mid, up (y + 1; NULL beyond a border) into g */
static void ero__ring_geometry(const ero__run *r, float *const *g, const float *dn, const float *mid, const float *up)
{
    long W = r->W, x;
    float s = r->s, S = 2.0f * s, s2 = S * S, q0 = 2.0f * (s * s);
#if defined(ERO_USE_AVX2)
    if (up && dn) ero__hf_interior8(dn, mid, up, s, W, g[0], g[1], g[2], g[3]);
#else
    if (up && dn) ero__hf_interior(dn, mid, up, s, W, g[0], g[1], g[2], g[3]);
#endif
    for (x = 0; x < W; x++) {
        float e[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, nb[3] = {0.0f, 0.0f, 1.0f}, n[4];
        int have = 0;
        long xr = x + 1 < W ? x + 1 : r->wrap ? 0 : -1, xl = x > 0 ? x - 1 : r->wrap ? W - 1 : -1;
        if (up && dn && x > 0 && x < W - 1) { x = W - 2; continue; }
        if (xr >= 0 && xl >= 0 && up && dn) {
            ero__hf_texel(mid[x], mid[xr], mid[xl], up[x], dn[x], S, s2, q0, &g[0][x], &g[1][x], &g[2][x], &g[3][x]);
            continue;
        }
        if (xr >= 0) { e[0][0] = s; e[0][2] = mid[xr] - mid[x]; have |= 1; }
        if (xl >= 0) { e[1][0] = -s; e[1][2] = mid[xl] - mid[x]; have |= 2; }
        if (up) { e[2][1] = s; e[2][2] = up[x] - mid[x]; have |= 4; }
        if (dn) { e[3][1] = -s; e[3][2] = dn[x] - mid[x]; have |= 8; }
        ero__texel_geometry(e, have, nb, &n[0], &n[1], &n[2], &n[3]);
        g[0][x] = -n[0]; g[1][x] = -n[1]; g[2][x] = n[2]; g[3][x] = -n[3];
    }
}

static long ero__mod(long a, long m) { return ((a % m) + m) % m; }

/* row y of the heights as they were before this step (with box_r + gau_r >= 1 the geometry reads
   no applied row but the first ones, at the end of a wrapped field) */
static const float *ero__ring_row(const ero__run *r, const ero__rows *q, long y)
{
    if (y >= q->applied) return r->disp + (size_t)y * (size_t)r->W;
    if (y < q->head_rows) return q->head + (size_t)y * (size_t)r->W;
    return q->orig + (size_t)(y & 3) * (size_t)r->W;
}

/* geometry of row v (wrapped into the field), its box sums along x into its ring slot */
static void ero__ring_row_geometry(ero__run *r, ero__rows *q, long v)
{
    long H = r->H, y = ero__mod(v, H);
    size_t at = (size_t)ero__mod(v, 2 * (long)r->box_r + 1) * q->Wp;
    const float *dn = y > 0 ? ero__ring_row(r, q, y - 1) : r->wrap ? ero__ring_row(r, q, H - 1) : NULL;
    const float *up = y + 1 < H ? ero__ring_row(r, q, y + 1) : r->wrap ? ero__ring_row(r, q, 0) : NULL;
    int k;
    ero__ring_geometry(r, q->geo, dn, ero__ring_row(r, q, y), up);
    for (k = 0; k < 4; k++) ero__ring_xpass(r, q, q->geo[k], q->gx[k] + at, q->wb, r->box_r, 1);
}

/* the rows at offsets -R..R from v in a ring of 2R + 1 slots (its zero row 2R + 1 beyond an
   unwrapped border); returns the weights w of the rows there are, summed as ero__kernels sums them */
static float ero__ring_window(const ero__run *r, const ero__rows *q, float *ring, long v, int R, const float *w,
                              float **rows)
{
    long slot = ero__mod(v - R, 2 * (long)R + 1);
    float ws = w[0], *zero = ring + (2 * (size_t)R + 1) * q->Wp;
    int k;
    for (k = -R; k <= R; k++) {
        long y = v + k;
        rows[R + k] = !r->wrap && (y < 0 || y >= r->H) ? zero : ring + (size_t)slot * q->Wp;
        slot = slot == 2 * R ? 0 : slot + 1;
    }
    for (k = 1; k <= R; k++) {
        if (rows[R + k] != zero) ws += w[k];
        if (rows[R - k] != zero) ws += w[k];
    }
    return ws;
}
/* H of a row (MODEL: exposure e = -n_a . w / |n_a|, c the normalised convex curvature, R the
   Bezier, W_f / R windward, ambient / R leeward, the deposition ramp where kap < 0; the branches
   as selects, 1 / |n_a| by ero__rsqrt in a loop apart (into out), one division; the materials'
   lookup in a loop apart) */
typedef struct ero__hparams {
    float w0, w1, w2, force, lc, inv_ramp, ratio;
    int constant, literal, deposit;
} ero__hparams;

static void ero__h_row(const ero__hparams *p, long W, const float *ERO__RESTRICT n0, const float *ERO__RESTRICT n1,
                       const float *ERO__RESTRICT n2, const float *ERO__RESTRICT kap,
                       const float *ERO__RESTRICT emin, const float *ERO__RESTRICT emax, const float *ERO__RESTRICT emed,
                       const float *ERO__RESTRICT amb, float *ERO__RESTRICT out)
{
    long x;
    float w0 = p->w0, w1 = p->w1, w2 = p->w2, force = p->force, lc = p->lc, inv_ramp = p->inv_ramp;
    float ratio = p->ratio;
    int constant = p->constant, literal = p->literal, deposit = p->deposit;
    for (x = 0; x < W; x++) out[x] = ero__rsqrt((n0[x] * n0[x] + n1[x] * n1[x]) + n2[x] * n2[x]);
    for (x = 0; x < W; x++) {
        float inv = out[x], k = kap[x];
        float dot = (n0[x] * w0 + n1[x] * w1) + n2[x] * w2, ev = -dot * inv, e = inv > 0.0f ? ev : 0.0f;
        float ck = k * lc, c0 = k > 0.0f ? ck : 0.0f, c = c0 > 1.0f ? 1.0f : c0, u = 1.0f - c;
        float res = u * u * emax[x] + 2.0f * c * u * emed[x] + c * c * emin[x], ir = 1.0f / res;
        float fe = force * e, wf = (constant ? force : fe) + amb[x], hw = wf * ir, al = amb[x] * ir;
        float hl = literal ? amb[x] : al, h = e > 0.0f ? hw : hl;
        float tr = -k * lc * inv_ramp, t0 = inv_ramp > 0.0f ? tr : 1.0f, t = t0 > 1.0f ? 1.0f : t0;
        float hd = h * ((1.0f - t) - ratio * t);
        h = deposit && k < 0.0f ? hd : h;
        out[x] = ero__fin(h) ? h : 0.0f;
    }
}

/* H of cnt texels from their averaged normals a0..a2 and curvature kap: mrow (four rows of the
   materials, filled by the caller when there is one material) is scratch */
static void ero__h_span(const ero__run *r, const float *a0, const float *a1, const float *a2, const float *kap,
                        const uint8_t *mat, long cnt, float *const *mrow, float *out)
{
    ero__hparams p;
    long x;
    p.w0 = r->wind[0]; p.w1 = r->wind[1]; p.w2 = r->wind[2];
    p.force = r->o.force; p.lc = r->o.curvature_length; p.ratio = r->o.deposit_ratio;
    p.inv_ramp = r->o.deposit_ramp > 0.0f ? 1.0f / r->o.deposit_ramp : 0.0f;
    p.constant = (r->o.flags & ERO_CONSTANT_WINDWARD) != 0;
    p.literal = (r->o.flags & ERO_LEEWARD_LITERAL) != 0;
    p.deposit = r->o.deposit_ratio >= 0.0f;
    if (r->mat_count > 1)
        for (x = 0; x < cnt; x++) {
            const ero_material *m = &r->mats[mat ? mat[x] : 0];
            mrow[0][x] = m->eps_min; mrow[1][x] = m->eps_max; mrow[2][x] = m->eps_medium; mrow[3][x] = m->ambient;
        }
    ero__h_row(&p, cnt, a0, a1, a2, kap, mrow[0], mrow[1], mrow[2], mrow[3], out);
}

/* fills the material rows with the one material */
static void ero__one_material(const ero__run *r, float *const *mrow, long cnt)
{
    long x;
    for (x = 0; x < cnt; x++) {
        mrow[0][x] = r->mats[0].eps_min; mrow[1][x] = r->mats[0].eps_max;
        mrow[2][x] = r->mats[0].eps_medium; mrow[3][x] = r->mats[0].ambient;
    }
}

/* the material rows in span (or mrow) for ero__h_span: the one material, if there is one */
static void ero__fill_materials(const ero__run *r, float *const *mrow)
{
    float *rows[4];
    int k;
    for (k = 0; k < 4; k++) rows[k] = mrow ? mrow[k] : r->span + (size_t)k * ERO__SPAN;
    if (r->mat_count == 1) ero__one_material(r, rows, ERO__SPAN);
}

/* H of every texel of the planes g (0 where invalid), in spans of ERO__SPAN */
static void ero__erosion_heights(ero__run *r)
{
    size_t i0, k;
    float *mrow[4];
    for (k = 0; k < 4; k++) mrow[k] = r->span + k * ERO__SPAN;
    ero__fill_materials(r, mrow);
    for (i0 = 0; i0 < r->n; i0 += ERO__SPAN) {
        long cnt = (long)(r->n - i0 < ERO__SPAN ? r->n - i0 : ERO__SPAN);
        ero__h_span(r, r->g[0] + i0, r->g[1] + i0, r->g[2] + i0, r->g[3] + i0, r->mat ? r->mat + i0 : NULL, cnt, mrow,
                    r->hh + i0);
        if (r->valid)
            for (k = 0; k < (size_t)cnt; k++)
                if (!r->valid[i0 + k]) r->hh[i0 + k] = 0.0f;
    }
}

/* H of a ring row (MODEL, as ero__h_row) from the box sums a0..a2 of ero__hf_texel's normal
   channels and ak of its curvature's: the exposure e = (a0 w0 + a1 w1 - a2 w2) / |a|, c from
   ak kf rowf (the mean curvature times curvature_length), R(c) = m0 + c (m1 + c m2) (the Bezier
   in powers of c), H = (force e + ambient) / R windward, ambient / R leeward (force e taken as 0
   there), the deposition ramp t = min(max(-c' / deposit_ramp, 0), 1) with c' the unclamped c (0
   on convex and flat texels, where it leaves H as it is); the branches as selects */
typedef struct ero__ring_hp {
    float w0, w1, w2, force, mr, ratio, rowf;
    int constant, literal;
} ero__ring_hp;

ERO__INLINE float ero__ring_h(const ero__ring_hp *p, float a0, float a1, float a2, float ak, float kf, float m0,
                              float m1, float m2, float amb)
{
    float inv = ero__rsqrt((a0 * a0 + a1 * a1) + a2 * a2);
    float e = ((a0 * p->w0 + a1 * p->w1) + a2 * p->w2) * inv;
    float ck = (ak * kf) * p->rowf, c0 = ck > 0.0f ? ck : 0.0f, c = c0 < 1.0f ? c0 : 1.0f;
    float ir = 1.0f / (m0 + c * (m1 + c * m2));
    float fe = p->constant ? p->force : p->force * e, pe = e > 0.0f ? fe : 0.0f, hw = (pe + amb) * ir;
    float h = p->literal && !(e > 0.0f) ? amb : hw;
    float t0 = ck * p->mr, t1 = t0 > 0.0f ? t0 : 0.0f, t = t1 < 1.0f ? t1 : 1.0f;
    float hd = h * ((1.0f - t) - p->ratio * t);
    return ero__fin(hd) ? hd : 0.0f;
}

#if !defined(ERO_USE_AVX2) /* (its AVX2 form below) */
static void ero__ring_h_row(const ero__ring_hp *p, long W, const float *ERO__RESTRICT a0, const float *ERO__RESTRICT a1,
                            const float *ERO__RESTRICT a2, const float *ERO__RESTRICT ak, const float *ERO__RESTRICT kf,
                            float *const *mr, float *ERO__RESTRICT out)
{
    const float *ERO__RESTRICT m0 = mr[0], *ERO__RESTRICT m1 = mr[1], *ERO__RESTRICT m2 = mr[2], *ERO__RESTRICT amb = mr[3];
    ero__ring_hp q = *p;
    long x;
    for (x = 0; x < W; x++) out[x] = ero__ring_h(&q, a0[x], a1[x], a2[x], ak[x], kf[x], m0[x], m1[x], m2[x], amb[x]);
}
#endif

/* the resistance's coefficients and ambient of a row's texels (ids mat; NULL: material 0) */
static void ero__ring_materials(const ero__rows *q, const uint8_t *mat, long W)
{
    long x;
    int k;
    for (k = 0; k < 4; k++)
        for (x = 0; x < W; x++) q->mrow[k][x] = q->coef[mat ? mat[x] : 0][k];
}

/* a row's change applied to the heights h: the Gaussian's sums g times the column factors gf
   (bounded above by bv; beyond float's range: as it was); the change made (old - new; 0 where
   not finite) added to the columns' sums of its eroded part er and deposited part de, and its
   size to their largest mx */
static void ero__hf_change_row(float *ERO__RESTRICT h, const float *ERO__RESTRICT g, const float *ERO__RESTRICT gf,
                               long W, float bv, float *ERO__RESTRICT er, float *ERO__RESTRICT de,
                               float *ERO__RESTRICT mx)
{
    long x;
    for (x = 0; x < W; x++) {
        float d0 = h[x], d = d0 - g[x] * gf[x], lim = d0 > bv ? d0 : bv, d1 = d > lim ? lim : d;
        float h1 = ero__fin(d1) ? d1 : d0, a0 = d0 - h1, a = ero__fin(a0) ? a0 : 0.0f;
        float ea = a > 0.0f ? a : 0.0f, da = -a > 0.0f ? -a : 0.0f, fa = ea + da; /* one is 0: fa = |a| */
        h[x] = h1;
        er[x] += ea;
        de[x] += da;
        mx[x] = fa > mx[x] ? fa : mx[x];
    }
}

/* the columns' sums into the report (in double, in column order), the columns cleared */
static void ero__hf_report(const ero__run *r, ero__rows *q, ero_report *rep)
{
    double s2 = (double)r->s * r->s, e = 0.0, d = 0.0;
    long x;
    float mx = 0.0f;
    for (x = 0; x < r->W; x++) {
        e += q->er[x];
        d += q->de[x];
        mx = q->mx[x] > mx ? q->mx[x] : mx;
    }
    rep->eroded += s2 * e;
    rep->deposited += s2 * d;
    if (mx > rep->max_change) rep->max_change = mx;
    memset(q->er, 0, 3 * q->Wp * sizeof(float));
}

#if defined(ERO_USE_AVX2)
#define ERO__V8(f) _mm256_set1_ps(f)
/* ero__ring_h of 8 texels from their box sums a0..ak and kf; 0 (nothing stored) when a squared
   length is not normal */
ERO__INLINE int ero__ring_h8(const ero__ring_hp *p, __m256 a0, __m256 a1, __m256 a2, __m256 ak, __m256 kf,
                             const float *m0, const float *m1, const float *m2, const float *mamb, float *out)
{
    __m256 zero = _mm256_setzero_ps(), one = ERO__V8(1.0f), amb = _mm256_loadu_ps(mamb);
    __m256 len = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a0, a0), _mm256_mul_ps(a1, a1)), _mm256_mul_ps(a2, a2));
    __m256 inv, e, ck, c, ir, fe, pos, h, t, hd;
    if (!ero__normal8(len)) return 0;
    inv = ero__rsqrt8(len);
    e = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a0, ERO__V8(p->w0)), _mm256_mul_ps(a1, ERO__V8(p->w1))),
                      _mm256_mul_ps(a2, ERO__V8(p->w2)));
    e = _mm256_mul_ps(e, inv);
    ck = _mm256_mul_ps(_mm256_mul_ps(ak, kf), ERO__V8(p->rowf));
    c = _mm256_min_ps(_mm256_max_ps(ck, zero), one);
    ir = _mm256_mul_ps(c, _mm256_add_ps(_mm256_loadu_ps(m1), _mm256_mul_ps(c, _mm256_loadu_ps(m2))));
    ir = _mm256_div_ps(one, _mm256_add_ps(_mm256_loadu_ps(m0), ir));
    fe = p->constant ? ERO__V8(p->force) : p->force == 1.0f ? e : _mm256_mul_ps(ERO__V8(p->force), e); /* 1 e = e */
    pos = _mm256_cmp_ps(e, zero, _CMP_GT_OQ);
    h = _mm256_mul_ps(_mm256_add_ps(_mm256_and_ps(pos, fe), amb), ir);
    if (p->literal) h = _mm256_blendv_ps(amb, h, pos);
    t = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(ck, ERO__V8(p->mr)), zero), one);
    hd = _mm256_mul_ps(h, _mm256_sub_ps(_mm256_sub_ps(one, t), _mm256_mul_ps(ERO__V8(p->ratio), t)));
    _mm256_storeu_ps(out, ero__fin8(hd));
    return 1;
}

/* ero__box_taps along y at column x: rows[R + k] is the first channel's row at offset k, the
   others' chs floats after each other's; the four channels at once, s gets their sums */
#define ERO__ROW4(p, s, c) _mm256_loadu_ps((p) + (c) * (s))
ERO__INLINE void ero__box8x4(float *const *rows, size_t chs, long x, int R, __m256 we, __m256 *s)
{
    const float *p = rows[R] + x, *u, *d;
    int k;
    s[0] = ERO__ROW4(p, chs, 0); s[1] = ERO__ROW4(p, chs, 1); s[2] = ERO__ROW4(p, chs, 2); s[3] = ERO__ROW4(p, chs, 3);
    if (R == 0) return;
    for (k = 1; k < R; k++) {
        u = rows[R + k] + x; d = rows[R - k] + x;
        s[0] = _mm256_add_ps(s[0], _mm256_add_ps(ERO__ROW4(u, chs, 0), ERO__ROW4(d, chs, 0)));
        s[1] = _mm256_add_ps(s[1], _mm256_add_ps(ERO__ROW4(u, chs, 1), ERO__ROW4(d, chs, 1)));
        s[2] = _mm256_add_ps(s[2], _mm256_add_ps(ERO__ROW4(u, chs, 2), ERO__ROW4(d, chs, 2)));
        s[3] = _mm256_add_ps(s[3], _mm256_add_ps(ERO__ROW4(u, chs, 3), ERO__ROW4(d, chs, 3)));
    }
    u = rows[R + R] + x; d = rows[0] + x;
    s[0] = _mm256_add_ps(s[0], _mm256_mul_ps(we, _mm256_add_ps(ERO__ROW4(u, chs, 0), ERO__ROW4(d, chs, 0))));
    s[1] = _mm256_add_ps(s[1], _mm256_mul_ps(we, _mm256_add_ps(ERO__ROW4(u, chs, 1), ERO__ROW4(d, chs, 1))));
    s[2] = _mm256_add_ps(s[2], _mm256_mul_ps(we, _mm256_add_ps(ERO__ROW4(u, chs, 2), ERO__ROW4(d, chs, 2))));
    s[3] = _mm256_add_ps(s[3], _mm256_mul_ps(we, _mm256_add_ps(ERO__ROW4(u, chs, 3), ERO__ROW4(d, chs, 3))));
}
#undef ERO__ROW4
/* the same, one column of channel c */
static float ero__box1(float *const *rows, size_t c, long x, int R, float we)
{
    float acc = rows[R][c + x];
    int k;
    if (R == 0) return acc;
    for (k = 1; k < R; k++) acc = acc + (rows[R + k][c + x] + rows[R - k][c + x]);
    return acc + we * (rows[R + R][c + x] + rows[0][c + x]);
}

/* the box's y pass over the rings' rows (ero__box8x4) and H (ero__ring_h_row) in one loop */
static void ero__ring_yh8(const ero__rows *q, const ero__ring_hp *hp, float *const *rows, long W, int R,
                          float *ERO__RESTRICT out)
{
    const float *kf = q->kf, *m0 = q->mrow[0], *m1 = q->mrow[1], *m2 = q->mrow[2], *m3 = q->mrow[3];
    ero__ring_hp p = *hp;
    size_t chs = q->chs;
    float we = q->wb[R], a[4][8];
    __m256 vwe = ERO__V8(we), sv[4];
    long x = 0;
    int l, c;
    for (; x + 8 <= W; x += 8) {
        ero__box8x4(rows, chs, x, R, vwe, sv);
        if (ero__ring_h8(&p, sv[0], sv[1], sv[2], sv[3], _mm256_loadu_ps(kf + x), m0 + x, m1 + x, m2 + x, m3 + x, out + x))
            continue;
        for (c = 0; c < 4; c++) _mm256_storeu_ps(a[c], sv[c]);
        for (l = 0; l < 8; l++)
            out[x + l] = ero__ring_h(&p, a[0][l], a[1][l], a[2][l], a[3][l], kf[x + l], m0[x + l], m1[x + l], m2[x + l],
                                     m3[x + l]);
    }
    for (; x < W; x++)
        out[x] = ero__ring_h(&p, ero__box1(rows, 0, x, R, we), ero__box1(rows, chs, x, R, we),
                             ero__box1(rows, 2 * chs, x, R, we), ero__box1(rows, 3 * chs, x, R, we), kf[x], m0[x], m1[x],
                             m2[x], m3[x]);
}

/* ero__taps along y at column x (rows[R + k]: the row at offset k), 8 columns at once; and one */
ERO__INLINE __m256 ero__gau8(float *const *rows, long x, const float *w, int R)
{
    __m256 acc = _mm256_mul_ps(ERO__V8(w[0]), _mm256_loadu_ps(rows[R] + x));
    int k;
    for (k = 1; k <= R; k++)
        acc = _mm256_add_ps(acc, _mm256_mul_ps(ERO__V8(w[k]), _mm256_add_ps(_mm256_loadu_ps(rows[R + k] + x),
                                                                           _mm256_loadu_ps(rows[R - k] + x))));
    return acc;
}
static float ero__gau1(float *const *rows, long x, const float *w, int R)
{
    float acc = w[0] * rows[R][x];
    int k;
    for (k = 1; k <= R; k++) acc = acc + w[k] * (rows[R + k][x] + rows[R - k][x]);
    return acc;
}

/* the Gaussian's y pass over the ring's rows (times sc on an unwrapped border's rows, border != 0)
   and ero__hf_change_row in one loop */
static void ero__ring_ychange8(const ero__rows *q, float *const *rows, const float *w, int R, int border, float sc,
                               float *ERO__RESTRICT h, long W, float bv)
{
    float *ERO__RESTRICT er = q->er, *ERO__RESTRICT de = q->de, *ERO__RESTRICT mx = q->mx;
    const float *gf = q->gf;
    __m256 vbv = ERO__V8(bv), zero = _mm256_setzero_ps(), sign = ERO__V8(-0.0f), vsc = ERO__V8(sc);
    long x = 0;
    int bounded = bv < HUGE_VALF;
    for (; x + 8 <= W; x += 8) {
        __m256 g = ero__gau8(rows, x, w, R), d0 = _mm256_loadu_ps(h + x), d, lim, d1, fin, h1, a, ea, da;
        if (border) g = _mm256_mul_ps(g, vsc);
        d = _mm256_sub_ps(d0, _mm256_mul_ps(g, _mm256_loadu_ps(gf + x)));
        lim = _mm256_max_ps(d0, vbv);
        d1 = bounded ? _mm256_min_ps(lim, d) : d; /* unbounded: lim = inf, min(inf, d) = d */
        fin = _mm256_cmp_ps(_mm256_sub_ps(d1, d1), zero, _CMP_EQ_OQ);
        h1 = _mm256_blendv_ps(d0, d1, fin);
        a = ero__fin8(_mm256_sub_ps(d0, h1));
        ea = _mm256_max_ps(a, zero);
        da = _mm256_max_ps(_mm256_xor_ps(a, sign), zero);
        _mm256_storeu_ps(h + x, h1);
        _mm256_storeu_ps(er + x, _mm256_add_ps(_mm256_loadu_ps(er + x), ea));
        _mm256_storeu_ps(de + x, _mm256_add_ps(_mm256_loadu_ps(de + x), da));
        _mm256_storeu_ps(mx + x, _mm256_max_ps(_mm256_add_ps(ea, da), _mm256_loadu_ps(mx + x)));
    }
    for (; x < W; x++) {
        float g = ero__gau1(rows, x, w, R);
        if (border) g *= sc;
        ero__hf_change_row(h + x, &g, gf + x, 1, bv, er + x, de + x, mx + x);
    }
}
#undef ERO__V8
#endif

/* row j's box sums along y (of the rows' sums along x), its H, H's Gaussian along x into its ring slot */
static void ero__ring_row_h(ero__run *r, ero__rows *q, long j)
{
    float *rows[2 * ERO__MAXR + 1], ws = ero__ring_window(r, q, q->gx[0], j, r->box_r, q->wb, rows);
    long W = r->W, y = ero__mod(j, r->H);
    ero__ring_hp p;
    if (r->mat_count > 1) ero__ring_materials(q, r->mat ? r->mat + (size_t)y * (size_t)W : NULL, W);
    p.w0 = r->wind[0]; p.w1 = r->wind[1]; p.w2 = -r->wind[2];
    p.force = r->o.force;
    p.mr = r->o.deposit_ratio >= 0.0f ? -1.0f / r->o.deposit_ramp : 0.0f;
    p.ratio = r->o.deposit_ratio;
    p.rowf = r->box_sum / ws;
    p.constant = (r->o.flags & ERO_CONSTANT_WINDWARD) != 0;
    p.literal = (r->o.flags & ERO_LEEWARD_LITERAL) != 0;
#if defined(ERO_USE_AVX2)
    ero__ring_yh8(q, &p, rows, W, r->box_r, q->hrow);
#else
    {
        float *ck[2 * ERO__MAXR + 1];
        int k, i;
        for (k = 0; k < 4; k++) { /* channel k's rows: channel 0's, k chs floats on */
            for (i = 0; i <= 2 * r->box_r; i++) ck[i] = rows[i] + (size_t)k * q->chs;
            ero__ring_ypass(ck, q->avg[k], W, q->wb, r->box_r, 1);
        }
    }
    ero__ring_h_row(&p, W, q->avg[0], q->avg[1], q->avg[2], q->avg[3], q->kf, q->mrow, q->hrow);
#endif
    ero__ring_xpass(r, q, q->hrow, q->hx + (size_t)ero__mod(j, 2 * (long)r->gau_r + 1) * q->Wp, q->wg, r->gau_r, 0);
}

/* row m's H filtered (x then y) and applied to the heights (the row kept first: the geometry may
   still read it); the report's sums in float over ERO__REPORT_ROWS rows per column, then in double */
#define ERO__REPORT_ROWS 32
static void ero__ring_row_apply(ero__run *r, ero__rows *q, long m, ero_report *rep)
{
    float *rows[2 * ERO__MAXR + 1], bv = r->o.bound == ERO_BOUND_VALUE ? r->o.bound_value : HUGE_VALF;
    float sc = 1.0f / ero__ring_window(r, q, q->hx, m, r->gau_r, q->wg, rows);
    size_t W = (size_t)r->W, i0 = (size_t)m * W;
    int border = !r->wrap && (m < r->gau_r || m >= r->H - r->gau_r); /* over the weights of the rows there are */
    if (r->box_r + r->gau_r == 0) memcpy(q->orig + (size_t)(m & 3) * W, r->disp + i0, W * sizeof(float));
    q->applied = m + 1;
#if defined(ERO_USE_AVX2)
    ero__ring_ychange8(q, rows, q->wg, r->gau_r, border, sc, r->disp + i0, (long)W, bv);
#else
    ero__ring_ypass(rows, q->chg, (long)W, q->wg, r->gau_r, 0);
    if (border) {
        size_t x;
        for (x = 0; x < W; x++) q->chg[x] *= sc;
    }
    ero__hf_change_row(r->disp + i0, q->chg, q->gf, (long)W, bv, q->er, q->de, q->mx);
#endif
    if (m % ERO__REPORT_ROWS == ERO__REPORT_ROWS - 1 || m == r->H - 1) ero__hf_report(r, q, rep);
}

/* one time step of a plain height field: row v's geometry, row v - box_r's H, row
   v - box_r - gau_r's change */
static void ero__ring_step(ero__run *r, ero_report *rep)
{
    ero__rows q;
    long H = r->H, lag = r->box_r + r->gau_r, v;
    int k;
    ero__ring_carve(r, &q, r->hh);
    ero__ring_weights(r, &q);
    for (k = 0; k < 4; k++) memset(q.gx[k] + (2 * (size_t)r->box_r + 1) * q.Wp, 0, q.Wp * sizeof(float));
    memset(q.hx + (2 * (size_t)r->gau_r + 1) * q.Wp, 0, q.Wp * sizeof(float));
    memset(q.er, 0, 3 * q.Wp * sizeof(float));
    memcpy(q.head, r->disp, (size_t)q.head_rows * (size_t)r->W * sizeof(float));
    if (r->mat_count == 1) ero__ring_materials(&q, NULL, r->W);
    q.applied = 0;
    memset(rep, 0, sizeof *rep);
    for (v = r->wrap ? -lag : 0; v < H + lag; v++) {
        long j = v - r->box_r, m = j - r->gau_r;
        if (r->wrap || v < H) ero__ring_row_geometry(r, &q, v);
        if (r->wrap ? j >= -(long)r->gau_r : j >= 0 && j < H) ero__ring_row_h(r, &q, j);
        if (m >= 0 && m < H) ero__ring_row_apply(r, &q, m, rep);
    }
}

/* ================================================================================================
   the step and the run
   ================================================================================================ */

/* one time step (paper section 4.2.3, steps 1-5) */
static void ero__time_step(ero__run *r, ero_report *rep)
{
    float *one[1], *mid[1];
    if (r->ring) { ero__ring_step(r, rep); return; }
    ero__geometry(r);                                       /* 5. (of the last step) normals, curvature */
    memset(rep, 0, sizeof *rep);
    if (r->box_r)                                           /*    their averages, 1-2. H */
        ero__filter(r, 0, r->g, r->g, 4, r->box_w, r->box_r, r->box_sum, ERO__SINK_H, NULL);
    else
        ero__erosion_heights(r);
    one[0] = r->hh;
    mid[0] = r->g[0];                                       /* free once H is made */
    if (r->gau_r)                                           /* 3. low-pass filter, 4. added */
        ero__filter(r, 1, one, mid, 1, r->gau_w, r->gau_r, r->gau_sum, ERO__SINK_APPLY, rep);
    else {
        ero__apply(r, rep);
        ero__points(r);
    }
    ero__extend_invalid(r);
}

/* the resolved options and the wind's unit vector */
static void ero__set_options(ero__run *r, const ero_options *o)
{
    double wl = sqrt((double)o->wind[0] * o->wind[0] + (double)o->wind[1] * o->wind[1] + (double)o->wind[2] * o->wind[2]);
    int i;
    r->o = ero__resolve(o, r->scale);
    for (i = 0; i < 3; i++) r->wind[i] = (float)(o->wind[i] / wl);
}

static ero_result ero__setup(ero__run *r, const ero_grid *g, const uint8_t *material, const ero_material *materials,
                             size_t material_count, int steps, const ero_options *options)
{
    ero_result e;
    double h, L;
    size_t i;
    ero_options o = options ? *options : ero_default_options();
    memset(r, 0, sizeof *r);
    if ((e = ero__check_grid(g, &r->n)) != ERO_OK) return e;
    if ((e = ero__check_options(&o)) != ERO_OK) return e;
    if (steps < 1) return ERO_ERR_BAD_STEPS;
    r->hf = g->domain == ERO_HEIGHTFIELD;
    r->wrap = g->wrap != 0;
    r->W = g->width;
    r->H = g->height;
    r->s = g->spacing;
    r->disp = g->disp;
    r->valid = g->valid;
    r->pos = g->pos; r->nrm = g->nrm; r->area = g->area; r->nbr = g->nbr; r->nbr_rot = g->nbr_rot;
    if ((e = ero__check_materials(r, material, materials, material_count)) != ERO_OK) return e;
    ero__scales(g, r->n, &h, &L);
    r->texel = h;
    r->scale = L;
    ero__set_options(r, &o);
    if ((e = ero__kernels(r, h)) != ERO_OK) return e;
    r->ring = ero__ring_fits(r);
    if (!r->hf)
        for (i = 0; i < 4 * r->n && !r->has_rot; i++) r->has_rot = r->nbr[i] != ERO__NONE && r->nbr_rot[i] != 0;
    r->al = o.allocator;
    return ERO_OK;
}

/* frees what ero__build allocated (what it did not is NULL) */
static void ero__release(ero__run *r)
{
    ero__free(r->al, r->ext);
    ero__free(r->al, r->seg);
    ero__free(r->al, r->onb);
    ero__free_walks(r);
    ero__free(r->al, r->block);
    r->ext = NULL; r->seg = NULL; r->onb = NULL; r->block = NULL;
}

/* the scratch and every table that depends on the grid's geometry and the kernels alone */
static ero_result ero__build(ero__run *r)
{
    ero_result e;
    if ((e = ero__scratch(r)) != ERO_OK) return e;
    if (!r->ring) ero__regular_runs(r);
    if ((e = ero__surface_tables(r)) != ERO_OK || (e = ero__record_all_walks(r)) != ERO_OK ||
        (e = ero__extension(r)) != ERO_OK) {
        ero__release(r);
        return e;
    }
    ero__columns(r);
    return ERO_OK;
}

/* `steps` steps from the map as it is (the state is the map alone: the surface points made from
   it first, then kept by each step's change) */
static ero_result ero__run_steps(ero__run *r, int steps, ero_report *per_step, ero_report *total)
{
    ero_report rep, sum;
    ero_result e = ERO_OK;
    int s;
    memset(&sum, 0, sizeof sum);
    ero__points(r);
    sum.corrected = r->corrected;
    for (s = 0; s < steps; s++) {
        if (r->o.progress && r->o.progress(r->o.user, (float)s / (float)steps)) { e = ERO_CANCELLED; break; }
        ero__time_step(r, &rep);
        rep.steps = 1;
        rep.corrected = r->corrected;
        if (per_step) per_step[s] = rep;
        sum.eroded += rep.eroded;
        sum.deposited += rep.deposited;
        if (rep.max_change > sum.max_change) sum.max_change = rep.max_change;
        sum.steps++;
    }
    if (e == ERO_OK && r->o.progress) r->o.progress(r->o.user, 1.0f);
    if (total) *total = sum;
    return e;
}

ERODEF ero_result ero_erode(const ero_grid *g, const uint8_t *material, const ero_material *materials,
                            size_t material_count, int steps, const ero_options *options, ero_report *per_step,
                            ero_report *total)
{
    ero__run r;
    ero_result e;
    if (total) memset(total, 0, sizeof *total);
    if ((e = ero__setup(&r, g, material, materials, material_count, steps, options)) != ERO_OK) return e;
    if ((e = ero__build(&r)) != ERO_OK) return e;
    e = ero__run_steps(&r, steps, per_step, total);
    ero__release(&r);
    return e;
}

/* ================================================================================================
   the workspace: ero__build's tables kept across calls
   ================================================================================================ */

struct ero_workspace {
    ero__run r;
    ero_grid g;              /* the grid it was made for (disp aside) */
    float normal_radius, filter_sigma; /* the resolved lengths the kernels came from */
    int keep_invalid;
    ero_allocator al;        /* a copy of the caller's allocator (r.al points here), if one was given */
};

ERODEF ero_result ero_workspace_create(const ero_grid *g, const ero_options *options, ero_workspace **out)
{
    ero__run r;
    ero_workspace *ws;
    ero_result e;
    if (!out) return ERO_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if ((e = ero__setup(&r, g, NULL, NULL, 0, 1, options)) != ERO_OK) return e;
    ws = (ero_workspace *)ero__alloc(r.al, sizeof *ws);
    if (!ws) return ERO_ERR_OUT_OF_MEMORY;
    memset(ws, 0, sizeof *ws);
    ws->r = r;
    if (r.al) { ws->al = *r.al; ws->r.al = &ws->al; }
    ws->g = *g;
    ws->normal_radius = r.o.normal_radius;
    ws->filter_sigma = r.o.filter_sigma;
    ws->keep_invalid = (r.o.flags & ERO_KEEP_INVALID) != 0;
    if ((e = ero__build(&ws->r)) != ERO_OK) {
        ero__free(r.al, ws);
        return e;
    }
    *out = ws;
    return ERO_OK;
}

ERODEF void ero_workspace_destroy(ero_workspace *ws)
{
    ero_allocator al;
    const ero_allocator *a;
    if (!ws) return;
    ero__release(&ws->r);
    al = ws->al;
    a = ws->r.al ? &al : NULL;
    ero__free(a, ws);
}

/* nonzero unless g is the grid ws was made for: its domain, size, spacing, wrap and geometry arrays */
static int ero__other_grid(const ero_workspace *ws, const ero_grid *g)
{
    const ero_grid *m = &ws->g;
    return g->domain != m->domain || g->width != m->width || g->height != m->height || g->valid != m->valid ||
           g->pos != m->pos || g->nrm != m->nrm || g->area != m->area || g->nbr != m->nbr ||
           g->nbr_rot != m->nbr_rot || (g->domain == ERO_HEIGHTFIELD && (!(g->spacing == m->spacing) ||
                                                                          (g->wrap != 0) != (m->wrap != 0)));
}

/* nonzero if a value of disp is not finite (branch-free) */
static int ero__bad_disp(const float *d, size_t n)
{
    size_t i;
    int bad = 0;
    for (i = 0; i < n; i++) bad |= !ero__fin(d[i]);
    return bad;
}

ERODEF ero_result ero_erode_ws(ero_workspace *ws, const ero_grid *g, const uint8_t *material,
                               const ero_material *materials, size_t material_count, int steps,
                               const ero_options *options, ero_report *per_step, ero_report *total)
{
    ero__run *r;
    ero_options o = options ? *options : ero_default_options(), ro;
    ero_result e;
    if (total) memset(total, 0, sizeof *total);
    if (!ws || !g || !g->disp || ero__other_grid(ws, g)) return ERO_ERR_INVALID_ARGUMENT;
    r = &ws->r;
    if (ero__bad_disp(g->disp, r->n)) return ERO_ERR_BAD_MAP;
    if ((e = ero__check_options(&o)) != ERO_OK) return e;
    ro = ero__resolve(&o, r->scale);
    if (!(ro.normal_radius == ws->normal_radius) || !(ro.filter_sigma == ws->filter_sigma) ||
        ((ro.flags & ERO_KEEP_INVALID) != 0) != ws->keep_invalid)
        return ERO_ERR_BAD_PARAMETER;
    if (steps < 1) return ERO_ERR_BAD_STEPS;
    r->corrected = 0;
    if ((e = ero__check_materials(r, material, materials, material_count)) != ERO_OK) return e;
    r->disp = g->disp;
    ero__set_options(r, &o);
    return ero__run_steps(r, steps, per_step, total);
}

/* ================================================================================================
   grids, painting, names
   ================================================================================================ */

ERODEF ero_grid ero_heightfield_grid(int width, int height, float *h, float spacing, int wrap)
{
    ero_grid g;
    memset(&g, 0, sizeof g);
    g.domain = ERO_HEIGHTFIELD;
    g.width = width;
    g.height = height;
    g.disp = h;
    g.spacing = spacing;
    g.wrap = wrap;
    return g;
}

ERODEF ero_grid ero_surface_grid(int width, int height, const float *pos, const float *nrm, float *disp,
                                 const float *area, const uint8_t *valid, const uint32_t *nbr, const uint8_t *nbr_rot)
{
    ero_grid g;
    memset(&g, 0, sizeof g);
    g.domain = ERO_SURFACE;
    g.width = width;
    g.height = height;
    g.pos = pos; g.nrm = nrm; g.disp = disp; g.area = area; g.valid = valid; g.nbr = nbr; g.nbr_rot = nbr_rot;
    return g;
}

ERODEF ero_result ero_paint_mask(uint8_t *material, int width, int height, const float *mask, int mask_w, int mask_h,
                                 int channels, float threshold, uint8_t id)
{
    long x, y;
    if (!material || !mask || channels < 1) return ERO_ERR_INVALID_ARGUMENT;
    if (width < 1 || height < 1 || mask_w < 1 || mask_h < 1) return ERO_ERR_BAD_SIZE;
    if ((size_t)width > ((size_t)0xFFFFFFFEu) / (size_t)height) return ERO_ERR_TOO_LARGE;
    for (y = 0; y < height; y++)
        for (x = 0; x < width; x++) {
            long mx = (long)(((double)x + 0.5) * mask_w / width), my = (long)(((double)y + 0.5) * mask_h / height);
            float v = mask[((size_t)my * (size_t)mask_w + (size_t)mx) * (size_t)channels];
            if (v >= threshold) material[(size_t)y * (size_t)width + (size_t)x] = id;
        }
    return ERO_OK;
}

ERODEF ero_result ero_paint_sphere(const ero_grid *g, uint8_t *material, const float centre[3], float radius, uint8_t id)
{
    size_t n, i;
    ero_result e = ero__check_grid(g, &n);
    if (e != ERO_OK) return e;
    if (!material || !centre) return ERO_ERR_INVALID_ARGUMENT;
    if (!ero__finite(radius) || radius < 0.0f || !ero__finite(centre[0]) || !ero__finite(centre[1]) ||
        !ero__finite(centre[2]))
        return ERO_ERR_BAD_PARAMETER;
    for (i = 0; i < n; i++) {
        double p[3], d2 = 0.0;
        int k;
        if (g->domain == ERO_HEIGHTFIELD) {
            p[0] = (double)(i % (size_t)g->width) * g->spacing;
            p[1] = (double)(i / (size_t)g->width) * g->spacing;
            p[2] = g->disp[i];
        } else
            for (k = 0; k < 3; k++) p[k] = (double)g->pos[3 * i + (size_t)k] - (double)g->disp[i] * g->nrm[3 * i + (size_t)k];
        for (k = 0; k < 3; k++) d2 += (p[k] - centre[k]) * (p[k] - centre[k]);
        if (d2 <= (double)radius * radius) material[i] = id;
    }
    return ERO_OK;
}

ERODEF const char *ero_result_string(ero_result r)
{
    switch (r) {
    case ERO_OK: return "ERO_OK";
    case ERO_ERR_INVALID_ARGUMENT: return "ERO_ERR_INVALID_ARGUMENT";
    case ERO_ERR_BAD_SIZE: return "ERO_ERR_BAD_SIZE";
    case ERO_ERR_TOO_LARGE: return "ERO_ERR_TOO_LARGE";
    case ERO_ERR_BAD_SPACING: return "ERO_ERR_BAD_SPACING";
    case ERO_ERR_BAD_MAP: return "ERO_ERR_BAD_MAP";
    case ERO_ERR_BAD_INDEX: return "ERO_ERR_BAD_INDEX";
    case ERO_ERR_BAD_WIND: return "ERO_ERR_BAD_WIND";
    case ERO_ERR_BAD_MATERIAL: return "ERO_ERR_BAD_MATERIAL";
    case ERO_ERR_BAD_STEPS: return "ERO_ERR_BAD_STEPS";
    case ERO_ERR_BAD_PARAMETER: return "ERO_ERR_BAD_PARAMETER";
    case ERO_ERR_OUT_OF_MEMORY: return "ERO_ERR_OUT_OF_MEMORY";
    case ERO_CANCELLED: return "ERO_CANCELLED";
    }
    return "ERO_ERR_?";
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* ERO_IMPLEMENTATION_DONE */
#endif /* ERO_IMPLEMENTATION */
/*
------------------------------------------------------------------------------
This software is available under 2 licences -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT Licence
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
In jurisdictions that recognize copyright law, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication in favor of the public domain for the benefit
of our descendants and successors in perpetuity of all present and future
rights to this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
*/
