/* relief.h - v0.1 - MIT licence or public domain (see end of file)
   Sketch-driven relief on textured materials (Fan 2014, after Zhou et al. 2007): the white strokes
   of a sketch rise as ridges and its black strokes sink as grooves, made of an example height
   map's own material; plus the normal map that relief mapping needs. Float in, float out,
   deterministic, libc + libm only.

   HOW TO USE (in ten lines)
       #define RL_IMPLEMENTATION          // in exactly one C or C++ file, then #include "relief.h"
       rl_map example = {384, 384, heights};        // floats, row 0 at the top, any range
       rl_map sketch  = {512, 512, strokes};        // > 0.75 white stroke, < 0.25 black, else none
       rl_map out;  float *nrm = malloc(sizeof(float) * 3 * 512 * 512);
       rl_synth_options o = rl_synth_default_options();
       rl_result r = rl_synthesize(&example, &sketch, &o, &out);   // out: 512 x 512 floats
       if (r != RL_OK) puts(rl_result_string(r));
       rl_normal_options no = rl_normal_default_options();
       rl_normal_map(out.data, out.width, out.height, &no, nrm);   // 3 floats a texel, unit length
       rl_map_free(&out, o.allocator);

   WHAT
     The thesis's three stages; this header does the first two, examples/render.h the third.
     - rl_skeleton_extract: ridge or valley lines of a height map by the thesis's simplified PPA
       (profile recognition and polygon breaking, Chang et al. 1998): candidate points, their
       8-neighbour connection with crossing diagonals resolved, loop elimination, branch pruning.
     - rl_synthesize: the feature-guided patch synthesis. Feature samples of the sketch (branch
       points, end points, and points every half a patch along its curves) are visited breadth
       first from a branch point; each gets the example patch centred on an example feature
       point of the same polarity and kind, rotated to the stroke's direction, that costs least
       (seam mismatch + feature dissimilarity); the rest is filled by the best-matching patches;
       every patch is joined by a graph-cut seam (Kwatra et al. 2003; max-flow by Boykov &
       Kolmogorov 2004) and Poisson-blended across it (Perez et al. 2003).
     - rl_emboss: the baseline: the example tiled, plus a Gaussian profile of the distance to the
       strokes (up under white ones, down under black ones).
     - rl_graph_cut: the seam on its own (minimum cut between two overlapping patches).
     Feature samples closer than patch / 6 to an earlier one of the same polarity (inside its
     pinned centre) are skipped: they would add a cut and change nothing.
     - rl_normal_map: central differences over a sampling distance d (the thesis's Eqs. 5-4 to
       5-7, d = 4 by default) with a strength factor, clamp-to-edge or wrap-around borders.

   OPTIONS
     Compile time: RL_STATIC (all functions static), RL_MALLOC(sz) / RL_FREE(p) (both or neither).
     Run time: rl_normal_options, rl_skeleton_options, rl_synth_options, each with its
     rl_*_default_options(); a zero field means its default (the field comments give them).

   MEMORY
     Every allocating call takes an rl_allocator (NULL = RL_MALLOC / RL_FREE). Results (rl_map,
     rl_skeleton) are freed with rl_map_free / rl_skeleton_free and the same allocator.
     rl_synthesize holds about 40 bytes per output texel and 16 per example texel while it runs.

   ERRORS
     Functions return rl_result (RL_OK = 0); rl_result_string names it. NULL pointers and bad
     options give RL_ERR_INVALID_ARGUMENT; an empty map RL_ERR_EMPTY; a map of more than 2^26
     texels or a side above 16384 RL_ERR_TOO_LARGE; a NaN or infinite height RL_ERR_NOT_FINITE (also
     from rl_synthesize and rl_emboss when finite heights near FLT_MAX overflow the result);
     a sketch without strokes RL_ERR_NO_STROKES; a patch larger than the example
     RL_ERR_PATCH_TOO_LARGE; allocation failure RL_ERR_OUT_OF_MEMORY; a progress callback's
     nonzero return RL_CANCELLED. On any error nothing is allocated and the outputs are zeroed.
     RL_ERR_SIZE_MISMATCH is reserved: no call takes two maps that must match (the sketch sets the
     output's size, the example may have any size that holds a patch).

   THREAD SAFETY
     No global state: calls on different data may run in different threads at once.

   DETERMINISM
     One thread, no random numbers (candidate subsets are fixed strides), ties broken by index:
     the same input gives the same bits on every run of the same build.

   PERFORMANCE
     One thread, 2-core AMD EPYC virtual machine: a 512 x 512 synthesis from a 384 x 384 example
     with the defaults takes about 0.14 s (about 45% of it in the graph cuts, 10% in the
     Poisson bands, 8% each in the fill search and the feature patches' sampling), its normal
     map about 1 ms, the emboss baseline about 25 ms.

   LIMITS
     Maps up to 16384 on a side and 2^26 texels. The sketch sets the output size. Patches up to
     1024 texels; the example must hold one patch (RL_ERR_PATCH_TOO_LARGE otherwise), and feature
     patches need example feature points 0.71 patch + 2 texels from its border (a rotated patch
     must fit): an example too small for that gets fill patches only.
     The bits do not depend on the compiler's FMA contraction (dialect, C or C++, -ffp-contract):
     the implementation turns it off for its own code and restores the user's setting after it,
     except under clang's -ffp-contract=fast, which ignores that pragma (the last bits may differ).

   DECISIONS (where the thesis is silent or wrong)
     - Sketch: > 0.75 is a white stroke, < 0.25 a black one. Its skeleton is the ridge line (PPA,
       tau 0.5) of the distance to the stroke's outside, i.e. its medial axis: one code path for
       example and sketch.
     - PPA edge weight: the mean height of the two texels (Chang's convention; the thesis's
       "height difference" gives a flat crest weight 0), negated for valleys. Loop elimination is
       Kruskal's maximum spanning forest (the same forest as deleting each loop's lightest edge,
       in O(E log E) instead of a restarted search per deletion). Pruning removes every leaf
       edge at once per round, L rounds by default: the thesis's L / 2 rounds leave 2-3 texel
       spurs inside every bend of a crest (the candidate test sees the crest on both sides).
     - Feature candidates: per kind, the example's most prominent feature points (highest ridge
       texels, lowest valley texels), at least patch / 4 apart: any crest is a ridge to PPA, and
       in raster order the crests put under white strokes stood barely above the mean.
     - Warping: feature patches are rotated to the stroke's direction (both ways tried), not
       thin-plate-spline warped: with the thesis's three control points a TPS is affine anyway.
       So c_d = 0 and alpha_d is not an option. c_f is the mean |patch - patch centre| along the
       sketch's skeleton inside the window in units of the height range (a ridge that follows
       the stroke keeps its crest height); c_g for feature patches is the mean squared
       mismatch over the filled texels (the graph cut runs once, for the chosen patch).
     - The fill visits a grid of windows (step patch - overlap) in raster order, skipping
       filled ones. It searches coarse to fine (the 4 best positions on a grid of twice the
       stride, then one stride step around each: a third of the work of the full stride grid,
       and no worse on a rock-like example). Of the K best by SSD it takes the least SSD +
       alpha_g x cut cost per overlap texel, or with tolerance > 0 a fixed pseudo-random one of
       those within (1 + tolerance) of it: always taking the best favours smooth, mid-height
       patches and narrows the height and slope histograms.
     - Graph cut: texels not filled yet are pinned to the new patch, filled texels on the
       window's border beside filled ones outside it to the old output, a feature patch's
       centre disc (radius patch / 6) to the patch. Pinned texels are folded into the terminal
       links, so max-flow runs on the free texels only.
     - Poisson: Gauss-Seidel (at most 64 sweeps) on the new texels within blend_band of a seam,
       Dirichlet elsewhere. Across the seam the guidance is the new patch's own gradient where
       the patch covers both texels, not zero as in the thesis: zero guidance flattens real
       slopes along every seam, a visible crease that also narrows the slope histogram.
     - emphasis: the synthesis puts the example's ridges under white strokes and its valleys
       under black ones, but how far a ridge stands above a valley is whatever the example's
       relief gives (on a ridged-noise rock, about a fifth of its range). The thesis demands
       that the strokes be clearly embossed or engraved, so the baseline's profile is added
       (emphasis x range, Gaussian of stroke_width); emphasis < 0 turns it off.
     - Normal map: clamp-to-edge borders (the thesis zeroes the slope within d of the border,
       a visible flat frame); the 1/(2d) of the central difference is explicit, so strength
       does not change with d.
*/
#ifndef RL_RELIEF_H
#define RL_RELIEF_H

#include <stddef.h>
#include <stdint.h>

#ifdef RL_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define RLDEF static __attribute__((unused))
#else
#define RLDEF static
#endif
#else
#define RLDEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum rl_result {
    RL_OK = 0,
    RL_ERR_INVALID_ARGUMENT,  /* NULL pointer, negative or out-of-range option */
    RL_ERR_OUT_OF_MEMORY,
    RL_CANCELLED,             /* the progress callback returned nonzero */
    RL_ERR_EMPTY,             /* a map with no texels */
    RL_ERR_TOO_LARGE,         /* a side above 16384 or more than 2^26 texels */
    RL_ERR_NOT_FINITE,        /* a NaN or infinite height */
    RL_ERR_SIZE_MISMATCH,     /* reserved: no call returns it (no two maps must match in size) */
    RL_ERR_NO_STROKES,        /* the sketch has no white and no black texel */
    RL_ERR_PATCH_TOO_LARGE    /* the patch (with its rotation margin) does not fit in the example */
} rl_result;

typedef struct rl_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} rl_allocator;

/* done in [0, 1]; a nonzero return cancels the call (RL_CANCELLED, everything freed) */
typedef int (*rl_progress_fn)(void *user, float done);

/* A float map: width * height values, row-major, row 0 at the top. */
typedef struct rl_map {
    int width, height;
    float *data;
} rl_map;

/* ---- normal map ------------------------------------------------------------------------------ */

typedef struct rl_normal_options {
    int distance;     /* sampling distance d in texels, 0 = 4 (the thesis's choice) */
    float strength;   /* heights times strength are in texel units, 0 = 1. For a relief quad of
                         width |axis_u| and depth_scale: strength = depth_scale * width_in_texels / |axis_u| */
    int wrap;         /* nonzero: wrap-around borders (tileable maps); 0: clamp to edge */
} rl_normal_options;

RLDEF rl_normal_options rl_normal_default_options(void);
/* out: 3 floats a texel, the unit normal (-Hs, -Ht, 1) / |.|, x along +column, y along +row, with
   Hs = strength (h(x+d, y) - h(x-d, y)) / (2d), Ht likewise along rows. */
RLDEF rl_result rl_normal_map(const float *height, int width, int height_texels, const rl_normal_options *options, float *out);
/* 3 floats a texel in [-1, 1] to RGB8, (n + 1) / 2 rounded (the thesis's Eq. 5-7). */
RLDEF void rl_normal_to_rgb8(const float *normals, size_t texels, uint8_t *rgb);

/* ---- skeletons (simplified PPA) ------------------------------------------------------------- */

typedef struct rl_skeleton_options {
    int half_length;      /* profile half length L in texels, 0 = 3 */
    float threshold;      /* height drop tau that marks a side, 0 = 0.03 of the map's height range */
    int prune_rounds;     /* leaf-pruning rounds, 0 = L (the thesis: L / 2; see DECISIONS), negative = none */
    int valleys;          /* nonzero: valley lines (the comparisons reversed) */
} rl_skeleton_options;

/* edges[y * width + x]: bit k set = an edge to neighbour k, clockwise from north: 0 N, 1 NE, 2 E,
   3 SE, 4 S, 5 SW, 6 W, 7 NW (y grows downwards). Symmetric; the edges form a forest. */
typedef struct rl_skeleton {
    int width, height;
    uint8_t *edges;
} rl_skeleton;

RLDEF rl_skeleton_options rl_skeleton_default_options(void);
RLDEF rl_result rl_skeleton_extract(const rl_map *height, const rl_skeleton_options *options,
                                    const rl_allocator *allocator, rl_skeleton *out);
RLDEF void rl_skeleton_free(rl_skeleton *s, const rl_allocator *allocator);

/* ---- graph-cut seam ------------------------------------------------------------------------- */

/* Labels each texel of a width x height overlap A (0) or B (1), minimising the cut cost
   sum over 4-neighbour pairs (s, t) with different labels of |a(s) - b(s)| + |a(t) - b(t)|.
   constraint[i]: 0 free, 1 must be A, 2 must be B (NULL = all free, then all A is optimal).
   *cost = the minimum. Max-flow by Boykov & Kolmogorov (2004) on the free texels. */
RLDEF rl_result rl_graph_cut(const float *a, const float *b, const uint8_t *constraint, int width, int height,
                             const rl_allocator *allocator, uint8_t *labels, double *cost);

/* ---- synthesis ------------------------------------------------------------------------------ */

typedef struct rl_synth_options {
    int patch;              /* patch side in texels, 0 = 48 */
    int overlap;            /* overlap of neighbouring fill patches, 0 = patch / 3 */
    int candidates;         /* K best fill candidates by SSD that get a graph cut, 0 = 2 */
    int search_stride;      /* fill candidates' positions: a grid of 2 x stride in the example, then
                               stride steps around the best 4, 0 = 8 */
    int feature_candidates; /* example feature points tried per sketch feature, 0 = 48 */
    float alpha_g, alpha_f; /* weights of seam and feature cost (Eq. 5-1), 0 = 1 and 3 */
    float emphasis;         /* extra relief under the strokes in units of the example's height
                               range, 0 = 0.45; negative = none (pure synthesis) */
    float stroke_width;     /* width of that relief's Gaussian profile in texels, 0 = 3 */
    int blend_band;         /* Poisson band width in texels beside a seam, 0 = 3; negative = no blending */
    float tolerance;        /* fill: a fixed pseudo-random pick among the K whose cost is within
                               (1 + tolerance) of the best (Efros & Freeman), 0 = 0.3; negative = the best */
    rl_skeleton_options skeleton; /* for the example's ridges and valleys */
    const rl_allocator *allocator;
    rl_progress_fn progress; void *progress_user;
    uint8_t *seams;         /* NULL, or width*height bytes of the sketch's size: bit 0 set where the
                               texel's right neighbour came from another patch, bit 1 its lower one */
} rl_synth_options;

RLDEF rl_synth_options rl_synth_default_options(void);
RLDEF rl_result rl_synthesize(const rl_map *example, const rl_map *sketch, const rl_synth_options *options, rl_map *out);
/* The baseline: the example tiled by mirroring (its mean removed... no: as is) to the sketch's size,
   plus emphasis * range * exp(-d^2 / (2 w^2)) with d the distance to the nearest white stroke
   texel, minus the same for black strokes. Uses emphasis, stroke_width, allocator. */
RLDEF rl_result rl_emboss(const rl_map *example, const rl_map *sketch, const rl_synth_options *options, rl_map *out);
RLDEF void rl_map_free(rl_map *m, const rl_allocator *allocator);

RLDEF const char *rl_result_string(rl_result r);

#ifdef __cplusplus
}
#endif
#endif /* RL_RELIEF_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef RL_IMPLEMENTATION
#ifndef RL_IMPLEMENTATION_DONE
#define RL_IMPLEMENTATION_DONE

#include <math.h>
#include <string.h>

#if defined(RL_MALLOC) && defined(RL_FREE)
/* both given */
#elif !defined(RL_MALLOC) && !defined(RL_FREE)
#include <stdlib.h>
#define RL_MALLOC(sz) malloc(sz)
#define RL_FREE(p) free(p)
#else
#error "relief.h: define both RL_MALLOC and RL_FREE, or neither"
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
   Section: results, allocation, map checks
   --------------------------------------------------------------------------------------------- */

#define RL__MAX_SIDE 16384
#define RL__MAX_TEXELS ((size_t)1 << 26)
#define RL__KMAX 16 /* fill candidates that get a graph cut, at most */

RLDEF const char *rl_result_string(rl_result r)
{
    switch (r) {
    case RL_OK: return "RL_OK";
    case RL_ERR_INVALID_ARGUMENT: return "RL_ERR_INVALID_ARGUMENT";
    case RL_ERR_OUT_OF_MEMORY: return "RL_ERR_OUT_OF_MEMORY";
    case RL_CANCELLED: return "RL_CANCELLED";
    case RL_ERR_EMPTY: return "RL_ERR_EMPTY";
    case RL_ERR_TOO_LARGE: return "RL_ERR_TOO_LARGE";
    case RL_ERR_NOT_FINITE: return "RL_ERR_NOT_FINITE";
    case RL_ERR_SIZE_MISMATCH: return "RL_ERR_SIZE_MISMATCH";
    case RL_ERR_NO_STROKES: return "RL_ERR_NO_STROKES";
    case RL_ERR_PATCH_TOO_LARGE: return "RL_ERR_PATCH_TOO_LARGE";
    }
    return "RL_ERR_?";
}

static void *rl__default_alloc(void *user, size_t size) { (void)user; return RL_MALLOC(size); }
static void rl__default_free(void *user, void *p) { (void)user; RL_FREE(p); }

static rl_allocator rl__allocator(const rl_allocator *a)
{
    rl_allocator r;
    if (a && a->alloc && a->free) return *a;
    r.alloc = rl__default_alloc;
    r.free = rl__default_free;
    r.user = NULL;
    return r;
}

static void *rl__alloc(const rl_allocator *a, size_t n) { return a->alloc(a->user, n ? n : 1); }
static void rl__free(const rl_allocator *a, void *p) { if (p) a->free(a->user, p); }

RLDEF void rl_map_free(rl_map *m, const rl_allocator *allocator)
{
    rl_allocator a = rl__allocator(allocator);
    if (!m) return;
    rl__free(&a, m->data);
    m->data = NULL;
}

/* size and finiteness of a map; min and max heights when wanted */
static rl_result rl__check_map(const rl_map *m, float *lo, float *hi)
{
    size_t i, n;
    float a = 0.0f, b = 0.0f;
    if (!m) return RL_ERR_INVALID_ARGUMENT;
    if (m->width <= 0 || m->height <= 0) return (m->width < 0 || m->height < 0) ? RL_ERR_INVALID_ARGUMENT : RL_ERR_EMPTY;
    if (m->width > RL__MAX_SIDE || m->height > RL__MAX_SIDE) return RL_ERR_TOO_LARGE;
    n = (size_t)m->width * (size_t)m->height;
    if (n > RL__MAX_TEXELS) return RL_ERR_TOO_LARGE;
    if (!m->data) return RL_ERR_INVALID_ARGUMENT;
    a = b = m->data[0];
    for (i = 0; i < n; i++) {
        float v = m->data[i];
        if (!(v - v == 0.0f)) return RL_ERR_NOT_FINITE;
        a = v < a ? v : a;
        b = v > b ? v : b;
    }
    if (lo) *lo = a;
    if (hi) *hi = b;
    return RL_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: normal map (Eqs. 5-4 to 5-7)
   --------------------------------------------------------------------------------------------- */

RLDEF rl_normal_options rl_normal_default_options(void)
{
    rl_normal_options o;
    o.distance = 4;
    o.strength = 1.0f;
    o.wrap = 0;
    return o;
}

static int rl__index(int i, int n, int wrap)
{
    if (wrap) { i %= n; return i < 0 ? i + n : i; }
    return i < 0 ? 0 : i >= n ? n - 1 : i;
}

RLDEF rl_result rl_normal_map(const float *height, int width, int height_texels, const rl_normal_options *options, float *out)
{
    rl_normal_options o = options ? *options : rl_normal_default_options();
    rl_map m;
    rl_result r;
    int x, y, d;
    float k;
    m.width = width; m.height = height_texels; m.data = (float *)(size_t)height;
    if (!out) return RL_ERR_INVALID_ARGUMENT;
    if ((r = rl__check_map(&m, NULL, NULL)) != RL_OK) return r;
    if (o.distance < 0 || !(o.strength >= 0.0f) || o.strength > 1e30f) return RL_ERR_INVALID_ARGUMENT;
    d = o.distance ? o.distance : 4;
    k = (o.strength ? o.strength : 1.0f) / (2.0f * (float)d);
    for (y = 0; y < height_texels; y++) {
        const float *up = height + (size_t)rl__index(y - d, height_texels, o.wrap) * (size_t)width;
        const float *dn = height + (size_t)rl__index(y + d, height_texels, o.wrap) * (size_t)width;
        const float *row = height + (size_t)y * (size_t)width;
        float *n = out + (size_t)y * (size_t)width * 3;
        for (x = 0; x < width; x++, n += 3) {
            const float *east = row + rl__index(x + d, width, o.wrap), *west = row + rl__index(x - d, width, o.wrap);
            float hs = k * (*east - *west);
            float ht = k * (dn[x] - up[x]);
            float s2 = hs * hs + ht * ht + 1.0f;
            if (s2 - s2 == 0.0f) {
                float inv = 1.0f / sqrtf(s2);
                n[0] = -hs * inv; n[1] = -ht * inv; n[2] = inv;
            } else { /* slopes whose squares overflow float (heights near 1e19 and up): in double */
                double hsd = (double)k * ((double)*east - (double)*west), htd = (double)k * ((double)dn[x] - (double)up[x]);
                double inv = 1.0 / sqrt(hsd * hsd + htd * htd + 1.0);
                n[0] = (float)(-hsd * inv); n[1] = (float)(-htd * inv); n[2] = (float)inv;
            }
        }
    }
    return RL_OK;
}

RLDEF void rl_normal_to_rgb8(const float *normals, size_t texels, uint8_t *rgb)
{
    size_t i;
    if (!normals || !rgb) return;
    for (i = 0; i < 3 * texels; i++) {
        float v = (normals[i] + 1.0f) * 0.5f * 255.0f + 0.5f;
        rgb[i] = (uint8_t)(v < 0.0f ? 0.0f : v > 255.0f ? 255.0f : v);
    }
}

/* ---------------------------------------------------------------------------------------------
   Section: distance transform (Felzenszwalb & Huttenlocher 2012, exact squared Euclidean)
   --------------------------------------------------------------------------------------------- */

/* 1-D lower envelope of parabolas: f (n values, 1e20 = none) -> d, with scratch v (n ints), z (n+1) */
static void rl__edt_1d(const float *f, int n, size_t stride_f, float *d, size_t stride_d, int *v, float *z)
{
    int k = 0, q;
    v[0] = 0; z[0] = -1e30f; z[1] = 1e30f;
    for (q = 1; q < n; q++) {
        float s;
        for (;;) {
            int p = v[k];
            s = ((f[(size_t)q * stride_f] + (float)q * (float)q) - (f[(size_t)p * stride_f] + (float)p * (float)p)) / (2.0f * (float)(q - p));
            if (s <= z[k] && k > 0) k--;
            else break;
        }
        if (s <= z[k]) { v[k] = q; z[k + 1] = 1e30f; continue; } /* k == 0: q replaces it */
        k++;
        v[k] = q; z[k] = s; z[k + 1] = 1e30f;
    }
    for (q = 0, k = 0; q < n; q++) {
        float t;
        while (z[k + 1] < (float)q) k++;
        t = (float)(q - v[k]);
        d[(size_t)q * stride_d] = t * t + f[(size_t)v[k] * stride_f];
    }
}

/* dist[i] = Euclidean distance from texel i to the nearest texel with mask[i] == value; 1e10 if none */
static rl_result rl__distance(const uint8_t *mask, uint8_t value, int w, int h, const rl_allocator *a, float *dist)
{
    size_t n = (size_t)w * (size_t)h, i;
    int m = w > h ? w : h, x, y;
    float *col = (float *)rl__alloc(a, sizeof(float) * (size_t)m * 2 + sizeof(float) * ((size_t)m + 1));
    int *v = (int *)rl__alloc(a, sizeof(int) * (size_t)m);
    if (!col || !v) { rl__free(a, col); rl__free(a, v); return RL_ERR_OUT_OF_MEMORY; }
    for (i = 0; i < n; i++) dist[i] = mask[i] == value ? 0.0f : 1e20f;
    /* a line of nothing but 1e20 stays so (q^2 + 1e20 rounds to 1e20): skipped */
    for (x = 0; x < w; x++) { /* columns, through a copy */
        int any = 0;
        for (y = 0; y < h; y++) { col[y] = dist[(size_t)y * w + x]; any |= col[y] < 1e20f; }
        if (any) rl__edt_1d(col, h, 1, dist + x, (size_t)w, v, col + 2 * m);
    }
    for (y = 0; y < h; y++) {
        float *row = dist + (size_t)y * w;
        int any = 0;
        for (x = 0; x < w; x++) any |= row[x] < 1e20f;
        if (!any) continue;
        memcpy(col, row, sizeof(float) * (size_t)w);
        rl__edt_1d(col, w, 1, row, 1, v, col + 2 * m);
    }
    for (i = 0; i < n; i++) dist[i] = dist[i] >= 1e19f ? 1e10f : sqrtf(dist[i]);
    rl__free(a, col);
    rl__free(a, v);
    return RL_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: skeletons - the thesis's simplified PPA (Sec. 5.2.2)
   --------------------------------------------------------------------------------------------- */

static const int rl__dx[8] = {0, 1, 1, 1, 0, -1, -1, -1};
static const int rl__dy[8] = {-1, -1, 0, 1, 1, 1, 0, -1};

RLDEF rl_skeleton_options rl_skeleton_default_options(void)
{
    rl_skeleton_options o;
    o.half_length = 3;
    o.threshold = 0.0f;
    o.prune_rounds = 0;
    o.valleys = 0;
    return o;
}

RLDEF void rl_skeleton_free(rl_skeleton *s, const rl_allocator *allocator)
{
    rl_allocator a = rl__allocator(allocator);
    if (!s) return;
    rl__free(&a, s->edges);
    s->edges = NULL;
}

/* Step 1: a texel is a candidate when, along one of the 4 lines through it, both sides have a
   texel within L whose height is below it by more than tau (above it, for valleys). "Some texel
   within L is below by more than tau" is tested on the side's minimum, c - min > tau: float
   subtraction is monotone, so that is the same test bit for bit, without branches. */
static int rl__ppa_side(const float *h, int w, int hh, int x, int y, int dx, int dy, int L, float c, float tau, float sign)
{
    int k, mark = 0;
    for (k = 1; k <= L && !mark; k++) {
        int px = x + k * dx, py = y + k * dy;
        if (px < 0 || py < 0 || px >= w || py >= hh) break;
        mark = c - sign * h[(size_t)py * w + px] > tau;
    }
    return mark;
}

/* RL__PPA_BLOCK texels of a row whose lines stay inside the map (fixed-size local arrays, so
   the compiler can vectorise): both sides' minima along each of the 4 lines */
#define RL__PPA_BLOCK 32
static void rl__ppa_block(const float *r0, int w, int L, float tau, float sign, uint8_t *out)
{
    static const int lx[4] = {1, 0, 1, 1}, ly[4] = {0, 1, 1, -1};
    float mp[RL__PPA_BLOCK], mm[RL__PPA_BLOCK];
    int32_t is[RL__PPA_BLOCK];
    int x, k, l;
    for (x = 0; x < RL__PPA_BLOCK; x++) is[x] = 0;
    for (l = 0; l < 4; l++) {
        ptrdiff_t off = (ptrdiff_t)ly[l] * w + lx[l];
        for (x = 0; x < RL__PPA_BLOCK; x++) { mp[x] = sign * r0[x + off]; mm[x] = sign * r0[x - off]; }
        for (k = 2; k <= L; k++) {
            const float *ra = r0 + k * off, *rb = r0 - k * off;
            for (x = 0; x < RL__PPA_BLOCK; x++) {
                float a = sign * ra[x], b = sign * rb[x];
                mp[x] = a < mp[x] ? a : mp[x];
                mm[x] = b < mm[x] ? b : mm[x];
            }
        }
        for (x = 0; x < RL__PPA_BLOCK; x++) {
            float c = sign * r0[x];
            is[x] |= (c - mp[x] > tau) & (c - mm[x] > tau);
        }
    }
    for (x = 0; x < RL__PPA_BLOCK; x++) out[x] = (uint8_t)is[x];
}

static void rl__ppa_candidates(const float *h, int w, int hh, int L, float tau, float sign, uint8_t *cand)
{
    static const int lx[4] = {1, 0, 1, 1}, ly[4] = {0, 1, 1, -1};
    int x, y, l;
    for (y = 0; y < hh; y++) {
        const float *row = h + (size_t)y * w;
        uint8_t *out = cand + (size_t)y * w;
        int inner = y >= L && y + L < hh && w - 2 * L >= RL__PPA_BLOCK, x0 = inner ? L : w, x1 = inner ? w - L : w;
        for (x = 0; x < w; x++) {          /* texels whose lines leave the map: one by one */
            float c;
            int is = 0;
            if (x == x0) x = x1;
            if (x >= w) break;
            c = sign * row[x];
            for (l = 0; l < 4 && !is; l++)
                is = rl__ppa_side(h, w, hh, x, y, lx[l], ly[l], L, c, tau, sign) && rl__ppa_side(h, w, hh, x, y, -lx[l], -ly[l], L, c, tau, sign);
            out[x] = (uint8_t)is;
        }
        for (x = x0; x < x1; x += RL__PPA_BLOCK) { /* the last block flush with x1 (overlaps: same values) */
            int b0 = x + RL__PPA_BLOCK <= x1 ? x : x1 - RL__PPA_BLOCK;
            rl__ppa_block(row + b0, w, L, tau, sign, out + b0);
        }
    }
}

typedef struct rl__edge { float weight; uint32_t a, b; uint8_t dir; } rl__edge;

/* a float's bits as an unsigned key that sorts the same way, inverted: heavier first */
static uint32_t rl__weight_key(float w)
{
    uint32_t u;
    memcpy(&u, &w, 4);
    u = (u & 0x80000000u) ? ~u : (u | 0x80000000u);
    return ~u;
}

/* Edges are made in (a, dir) order; a stable radix sort on the key (two 16-bit passes) puts
   them heavier first, ties in that order. tmp: n edges of scratch; count: 65536 sizes. */
static void rl__sort_edges(rl__edge *e, rl__edge *tmp, size_t n, size_t *count)
{
    int pass;
    for (pass = 0; pass < 2; pass++) {
        rl__edge *src = pass ? tmp : e, *dst = pass ? e : tmp;
        size_t i, sum = 0;
        int sh = pass * 16;
        memset(count, 0, sizeof(size_t) * 65536);
        for (i = 0; i < n; i++) count[(rl__weight_key(src[i].weight) >> sh) & 0xFFFFu]++;
        for (i = 0; i < 65536; i++) { size_t c = count[i]; count[i] = sum; sum += c; }
        for (i = 0; i < n; i++) dst[count[(rl__weight_key(src[i].weight) >> sh) & 0xFFFFu]++] = src[i];
    }
}

/* Step 2: edges between neighbouring candidates (E, SE, S, SW of each), weight = mean height
   (Chang's convention; negated for valleys); of two crossing diagonals the lighter is dropped. */
static size_t rl__ppa_connect(const float *h, int w, int hh, float sign, const uint8_t *cand, rl__edge *e)
{
    size_t n = 0;
    int x, y, k;
    for (y = 0; y < hh; y++)
        for (x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            if (!cand[i]) continue;
            for (k = 2; k <= 5; k++) {
                int px = x + rl__dx[k], py = y + rl__dy[k];
                size_t j;
                float wt;
                if (px < 0 || py < 0 || px >= w || py >= hh || !cand[(size_t)py * w + px]) continue;
                j = (size_t)py * w + px;
                wt = 0.5f * sign * (h[i] + h[j]);
                if (k == 3 && x + 1 < w && y + 1 < hh && cand[i + 1] && cand[i + (size_t)w]) {
                    float other = 0.5f * sign * (h[i + 1] + h[i + (size_t)w]); /* the SW diagonal from x+1 */
                    if (other > wt) continue;
                }
                if (k == 5 && x >= 1 && y + 1 < hh && cand[i - 1] && cand[i + (size_t)w]) {
                    float other = 0.5f * sign * (h[i - 1] + h[i + (size_t)w]); /* the SE diagonal from x-1 */
                    if (other >= wt) continue;
                }
                e[n].weight = wt; e[n].a = (uint32_t)i; e[n].b = (uint32_t)j; e[n].dir = (uint8_t)k;
                n++;
            }
        }
    return n;
}

static uint32_t rl__find(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i) { parent[i] = parent[parent[i]]; i = parent[i]; }
    return i;
}

/* Step 3: loop elimination. Deleting the lightest edge of a loop until none is left (the
   thesis's repeated depth-first search) leaves the maximum-weight spanning forest; Kruskal
   finds the same forest in O(E log E). */
static void rl__ppa_forest(rl__edge *e, rl__edge *tmp, size_t *count, size_t n, uint32_t *parent, size_t texels, uint8_t *edges)
{
    size_t i;
    rl__sort_edges(e, tmp, n, count);
    for (i = 0; i < texels; i++) parent[i] = (uint32_t)i;
    for (i = 0; i < n; i++) {
        uint32_t ra = rl__find(parent, e[i].a), rb = rl__find(parent, e[i].b);
        if (ra == rb) continue;
        parent[ra] = rb;
        edges[e[i].a] |= (uint8_t)(1u << e[i].dir);
        edges[e[i].b] |= (uint8_t)(1u << ((e[i].dir + 4) & 7));
    }
}

static int rl__degree(uint8_t m)
{
    int d = 0;
    while (m) { d += m & 1; m >>= 1; }
    return d;
}

/* Step 4: each round removes the edge of every leaf at once (synchronously, so the result does
   not depend on the scan order). list: scratch of texels entries. */
static void rl__ppa_prune(uint8_t *edges, int w, int hh, int rounds, uint32_t *list)
{
    size_t n = (size_t)w * (size_t)hh, i, count;
    int r, k;
    for (r = 0; r < rounds; r++) {
        count = 0;
        for (i = 0; i < n; i++)
            if (edges[i] && rl__degree(edges[i]) == 1) list[count++] = (uint32_t)i;
        for (i = 0; i < count; i++) {
            uint32_t t = list[i];
            int x = (int)(t % (uint32_t)w), y = (int)(t / (uint32_t)w);
            for (k = 0; k < 8; k++)
                if (edges[t] & (1u << k)) {
                    size_t j = (size_t)(y + rl__dy[k]) * w + (size_t)(x + rl__dx[k]);
                    edges[t] &= (uint8_t)~(1u << k);
                    edges[j] &= (uint8_t)~(1u << ((k + 4) & 7));
                }
        }
    }
}

RLDEF rl_result rl_skeleton_extract(const rl_map *height, const rl_skeleton_options *options,
                                    const rl_allocator *allocator, rl_skeleton *out)
{
    rl_skeleton_options o = options ? *options : rl_skeleton_default_options();
    rl_allocator a = rl__allocator(allocator);
    float lo, hi, tau, sign;
    rl_result r;
    size_t n, ne, nc, i, *count;
    uint8_t *cand;
    rl__edge *e;
    uint32_t *parent;
    int L, rounds;
    if (!out) return RL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if ((r = rl__check_map(height, &lo, &hi)) != RL_OK) return r;
    if (o.half_length < 0 || o.half_length > 64 || !(o.threshold >= 0.0f) || !(o.threshold < 1e30f)) return RL_ERR_INVALID_ARGUMENT;
    L = o.half_length ? o.half_length : 3;
    tau = o.threshold > 0.0f ? o.threshold : 0.03f * (hi - lo);
    rounds = o.prune_rounds < 0 ? 0 : o.prune_rounds ? o.prune_rounds : L;
    sign = o.valleys ? -1.0f : 1.0f;
    n = (size_t)height->width * (size_t)height->height;
    cand = (uint8_t *)rl__alloc(&a, n);
    if (!cand) return RL_ERR_OUT_OF_MEMORY;
    rl__ppa_candidates(height->data, height->width, height->height, L, tau, sign, cand);
    for (i = 0, nc = 0; i < n; i++) nc += cand[i];
    out->edges = (uint8_t *)rl__alloc(&a, n);
    e = (rl__edge *)rl__alloc(&a, sizeof(rl__edge) * 8 * nc); /* the edges and the sort's scratch */
    parent = (uint32_t *)rl__alloc(&a, sizeof(uint32_t) * n);
    count = (size_t *)rl__alloc(&a, sizeof(size_t) * 65536);
    if (!out->edges || !e || !parent || !count) {
        rl__free(&a, out->edges); rl__free(&a, cand); rl__free(&a, e); rl__free(&a, parent); rl__free(&a, count);
        out->edges = NULL;
        return RL_ERR_OUT_OF_MEMORY;
    }
    memset(out->edges, 0, n);
    out->width = height->width;
    out->height = height->height;
    ne = rl__ppa_connect(height->data, height->width, height->height, sign, cand, e);
    rl__ppa_forest(e, e + 4 * nc, count, ne, parent, n, out->edges);
    rl__ppa_prune(out->edges, height->width, height->height, rounds, parent);
    rl__free(&a, cand); rl__free(&a, e); rl__free(&a, parent); rl__free(&a, count);
    return RL_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: graph-cut seam (Kwatra et al. 2003, Eqs. 5-2 and 5-3), max-flow by Boykov & Kolmogorov
   --------------------------------------------------------------------------------------------- */

/* A grid graph: each non-terminal node has 4 arc slots, e = 4 u + d with d = 0 south, 1 east,
   2 west, 3 north (to[e] = -1: no arc), the order a node's arcs are visited in; arc e's reverse
   is 4 to[e] + 3 - d and its tail e / 4. Each node's terminal link is one residual tr: > 0 from
   the source, < 0 to the sink (Boykov & Kolmogorov 2004). */
typedef struct rl__flow {
    int nodes;
    int *to, *parent, *pn, *queue, *orphans, *stamp, time, qtail; /* pn: the parent arc's head */
    uint8_t *tree, *queued;     /* tree: 0 free, 1 source, 2 sink */
    double *cap, *tr, *diff;    /* diff: per grid texel (nodes of them), |a - b| */
} rl__flow;

#define RL__TERMINAL (-1)
#define RL__ORPHAN (-2)
#define RL__REV(f, e) (4 * (f)->to[e] + 3 - ((e) & 3))

static void rl__flow_free(rl__flow *f, const rl_allocator *a)
{
    rl__free(a, f->to); rl__free(a, f->parent); rl__free(a, f->pn);
    rl__free(a, f->queue); rl__free(a, f->orphans); rl__free(a, f->tree); rl__free(a, f->queued); rl__free(a, f->stamp);
    rl__free(a, f->cap); rl__free(a, f->tr); rl__free(a, f->diff);
    memset(f, 0, sizeof *f);
}

static rl_result rl__flow_init(rl__flow *f, int nodes, const rl_allocator *a)
{
    size_t nn = (size_t)nodes;
    memset(f, 0, sizeof *f);
    f->nodes = nodes;
    f->parent = (int *)rl__alloc(a, sizeof(int) * nn);
    f->pn = (int *)rl__alloc(a, sizeof(int) * nn);
    f->queue = (int *)rl__alloc(a, sizeof(int) * nn);
    f->orphans = (int *)rl__alloc(a, sizeof(int) * nn);
    f->stamp = (int *)rl__alloc(a, sizeof(int) * nn);
    f->tree = (uint8_t *)rl__alloc(a, nn);
    f->queued = (uint8_t *)rl__alloc(a, nn);
    f->tr = (double *)rl__alloc(a, sizeof(double) * nn);
    f->diff = (double *)rl__alloc(a, sizeof(double) * nn);
    f->to = (int *)rl__alloc(a, sizeof(int) * 4 * nn);
    f->cap = (double *)rl__alloc(a, sizeof(double) * 4 * nn);
    if (!f->parent || !f->pn || !f->queue || !f->orphans || !f->stamp || !f->tree || !f->queued || !f->tr || !f->diff || !f->to || !f->cap) {
        rl__flow_free(f, a);
        return RL_ERR_OUT_OF_MEMORY;
    }
    return RL_OK;
}

static void rl__flow_reset(rl__flow *f, int nodes)
{
    f->nodes = nodes;
    memset(f->to, 0xFF, sizeof(int) * 4 * (size_t)nodes);
    memset(f->tr, 0, sizeof(double) * (size_t)nodes);
}

/* the residual of the arc that carries flow along the tree toward the sink: in the source tree
   from q to its child, in the sink tree from the child to q */
static double rl__tree_res(const rl__flow *f, int tree, int e) { return tree == 1 ? f->cap[RL__REV(f, e)] : f->cap[e]; }

/* pushes the bottleneck along source root -> u -> v -> sink root (arc e from u to v); the
   saturated tree arcs make orphans */
static int rl__flow_augment(rl__flow *f, int e, int norph)
{
    double m = f->cap[e];
    int x, k;
    for (x = e >> 2; f->parent[x] != RL__TERMINAL; x = f->pn[x]) { double r = f->cap[4 * f->pn[x] + 3 - (f->parent[x] & 3)]; m = r < m ? r : m; }
    m = f->tr[x] < m ? f->tr[x] : m;
    for (x = f->to[e]; f->parent[x] != RL__TERMINAL; x = f->pn[x]) { double r = f->cap[f->parent[x]]; m = r < m ? r : m; }
    m = -f->tr[x] < m ? -f->tr[x] : m;
    f->cap[e] -= m; f->cap[RL__REV(f, e)] += m;
    for (k = 0; k < 2; k++) {
        for (x = k ? f->to[e] : e >> 2;;) {
            int pe = f->parent[x], re;
            if (pe == RL__TERMINAL) {
                f->tr[x] += k ? m : -m;
                if (f->tr[x] == 0.0) { f->parent[x] = RL__ORPHAN; f->orphans[norph++] = x; }
                break;
            }
            re = 4 * f->pn[x] + 3 - (pe & 3);
            if (k) { f->cap[pe] -= m; f->cap[re] += m; if (f->cap[pe] == 0.0) { f->parent[x] = RL__ORPHAN; f->orphans[norph++] = x; } }
            else { f->cap[re] -= m; f->cap[pe] += m; if (f->cap[re] == 0.0) { f->parent[x] = RL__ORPHAN; f->orphans[norph++] = x; } }
            x = f->pn[x];
        }
    }
    return norph;
}

/* 1 when q's chain of parents reaches a terminal; the chain's nodes are then stamped, and a
   stamped node ends later walks of the same adoption (an intact chain stays intact while
   orphans are processed: only broken subtrees are freed) */
static int rl__rooted(rl__flow *f, int q)
{
    int x = q, ok;
    while (f->parent[x] >= 0 && f->stamp[x] != f->time) x = f->pn[x];
    ok = f->stamp[x] == f->time || f->parent[x] == RL__TERMINAL;
    if (ok)
        for (x = q; f->stamp[x] != f->time; x = f->parent[x] >= 0 ? f->pn[x] : x) {
            f->stamp[x] = f->time;
            if (f->parent[x] < 0) break;
        }
    return ok;
}

/* the active queue: a ring of nodes slots (a node is in it at most once); *qt counts pushes */
static void rl__activate(rl__flow *f, int q, int *qt)
{
    if (f->queued[q]) return;
    f->queued[q] = 1;
    f->queue[f->qtail] = q;
    if (++f->qtail == f->nodes) f->qtail = 0;
    (*qt)++;
}

/* each orphan takes a new parent of its tree whose chain is rooted, or leaves the tree */
static void rl__flow_adopt(rl__flow *f, int norph, int *qt)
{
    f->time++;
    while (norph > 0) {
        int x = f->orphans[--norph], e, t = f->tree[x], found = -1;
        for (e = 4 * x; e < 4 * x + 4 && found < 0; e++) {
            int q = f->to[e];
            if (q >= 0 && f->tree[q] == t && rl__tree_res(f, t, e) > 0.0 && f->parent[q] != RL__ORPHAN && rl__rooted(f, q)) found = e;
        }
        if (found >= 0) { f->parent[x] = found; f->pn[x] = f->to[found]; continue; }
        for (e = 4 * x; e < 4 * x + 4; e++) {
            int q = f->to[e];
            if (q < 0 || f->tree[q] != t) continue;
            if (rl__tree_res(f, t, e) > 0.0) rl__activate(f, q, qt);
            if (f->parent[q] >= 0 && f->pn[q] == x) { f->parent[q] = RL__ORPHAN; f->orphans[norph++] = q; }
        }
        f->tree[x] = 0;
    }
}

/* max-flow from the source tree to the sink tree: grow, augment, adopt, until no path is left;
   then tree[v] == 1 exactly for the nodes the source still reaches */
static void rl__flow_run(rl__flow *f)
{
    int qh = 0, qt = 0, v, e, head = 0, cur = -1;
    f->time = 0;
    f->qtail = 0;
    for (v = 0; v < f->nodes; v++) {
        f->stamp[v] = 0;
        f->queued[v] = 0;
        f->tree[v] = (uint8_t)(f->tr[v] > 0.0 ? 1 : f->tr[v] < 0.0 ? 2 : 0);
        f->parent[v] = RL__TERMINAL;
        if (f->tree[v]) rl__activate(f, v, &qt);
    }
    for (;;) {
        int p, found = -1, t;
        if (cur >= 0 && f->tree[cur]) p = cur; /* after an augmentation, the same node goes on */
        else {
            if (qh >= qt) break;
            p = f->queue[head];
            qh++;
            if (++head == f->nodes) head = 0;
            f->queued[p] = 0;
        }
        cur = -1;
        t = f->tree[p];
        if (!t) continue;
        for (e = 4 * p; e < 4 * p + 4 && found < 0; e++) {
            int q = f->to[e];
            if (q < 0 || (t == 1 ? f->cap[e] : f->cap[RL__REV(f, e)]) <= 0.0) continue;
            if (!f->tree[q]) { f->tree[q] = (uint8_t)t; f->parent[q] = RL__REV(f, e); f->pn[q] = p; rl__activate(f, q, &qt); }
            else if (f->tree[q] != t) found = t == 1 ? e : RL__REV(f, e);
        }
        if (found >= 0) {
            rl__flow_adopt(f, rl__flow_augment(f, found, 0), &qt);
            cur = p;
        }
    }
}

/* One grid pair, q east (d = 1) or south (d = 0) of p: free-free pairs become an arc pair, a
   free texel beside a pinned one gets the cost on its link to the pinned side's terminal (the
   pair is cut exactly when the free texel takes the other label), pinned-pinned pairs cost
   nothing that a cut can change. */
static void rl__cut_pair(rl__flow *f, const int *node, const uint8_t *cons, size_t p, size_t q, int d)
{
    int np = node[p], nq = node[q];
    double c;
    if (np < 0 && nq < 0) return;
    c = f->diff[p] + f->diff[q]; /* |a(p) - b(p)| + |a(q) - b(q)|, each texel's computed once */
    if (np >= 0 && nq >= 0) {
        f->to[4 * np + d] = nq; f->cap[4 * np + d] = c;
        f->to[4 * nq + 3 - d] = np; f->cap[4 * nq + 3 - d] = c;
    }
    else if (np >= 0) f->tr[np] += cons[q] == 1 ? c : -c;
    else f->tr[nq] += cons[p] == 1 ? c : -c;
}

/* the cut on a flow workspace with room for width*height nodes; node: width*height ints of
   scratch */
static void rl__cut_solve(rl__flow *f, const float *a, const float *b, const uint8_t *cons, int width, int height,
                          int *node, uint8_t *labels)
{
    size_t n = (size_t)width * (size_t)height, i;
    int x, y, free_count = 0;
    for (i = 0; i < n; i++) {
        node[i] = (!cons || !cons[i]) ? free_count++ : -1;
        f->diff[i] = fabs((double)a[i] - (double)b[i]);
    }
    rl__flow_reset(f, free_count > 0 ? free_count : 1);
    for (y = 0; y < height; y++)
        for (x = 0; x < width; x++) {
            size_t p = (size_t)y * width + x;
            if (x + 1 < width) rl__cut_pair(f, node, cons, p, p + 1, 1);
            if (y + 1 < height) rl__cut_pair(f, node, cons, p, p + (size_t)width, 0);
        }
    /* a texel linked to both terminals passes the smaller link's flow at once (Boykov & Kolmogorov) */
    if (free_count) rl__flow_run(f);
    for (i = 0; i < n; i++) labels[i] = node[i] >= 0 ? (f->tree[node[i]] == 1 ? 0 : 1) : (cons[i] == 1 ? 0 : 1);
}

/* the cost of labels: over pairs with different labels, diff[s] + diff[t] (rl__cut_solve's
   per-texel |a - b|) */
static double rl__cut_cost(const double *diff, const uint8_t *labels, int width, int height)
{
    double c = 0.0;
    int x, y;
    for (y = 0; y < height; y++)
        for (x = 0; x < width; x++) {
            size_t p = (size_t)y * width + x;
            if (x + 1 < width && labels[p] != labels[p + 1]) c += diff[p] + diff[p + 1];
            if (y + 1 < height && labels[p] != labels[p + (size_t)width]) c += diff[p] + diff[p + (size_t)width];
        }
    return c;
}

RLDEF rl_result rl_graph_cut(const float *a, const float *b, const uint8_t *constraint, int width, int height,
                             const rl_allocator *allocator, uint8_t *labels, double *cost)
{
    rl_allocator al = rl__allocator(allocator);
    rl__flow f;
    size_t n, i;
    int *node;
    rl_result r;
    if (!a || !b || !labels || width <= 0 || height <= 0) return RL_ERR_INVALID_ARGUMENT;
    if (width > RL__MAX_SIDE || height > RL__MAX_SIDE || (size_t)width * (size_t)height > ((size_t)1 << 24)) return RL_ERR_TOO_LARGE;
    n = (size_t)width * (size_t)height;
    for (i = 0; i < n; i++) {
        if (!(a[i] - a[i] == 0.0f) || !(b[i] - b[i] == 0.0f)) return RL_ERR_NOT_FINITE;
        if (constraint && constraint[i] > 2) return RL_ERR_INVALID_ARGUMENT;
    }
    if ((r = rl__flow_init(&f, (int)n, &al)) != RL_OK) return r;
    node = (int *)rl__alloc(&al, sizeof(int) * n);
    if (!node) { rl__flow_free(&f, &al); return RL_ERR_OUT_OF_MEMORY; }
    rl__cut_solve(&f, a, b, constraint, width, height, node, labels);
    rl__free(&al, node);
    if (cost) *cost = rl__cut_cost(f.diff, labels, width, height);
    rl__flow_free(&f, &al);
    return RL_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: synthesis state, patch sampling, placement (graph cut + Poisson band)
   --------------------------------------------------------------------------------------------- */

RLDEF rl_synth_options rl_synth_default_options(void)
{
    rl_synth_options o;
    memset(&o, 0, sizeof o);
    o.patch = 48;
    o.overlap = 0;              /* patch / 3 */
    o.candidates = 2;
    o.search_stride = 8;
    o.feature_candidates = 24;
    o.alpha_g = 1.0f;
    o.alpha_f = 3.0f;
    o.emphasis = 0.45f;
    o.stroke_width = 3.0f;
    o.blend_band = 3;
    o.tolerance = 0.3f;
    o.skeleton = rl_skeleton_default_options();
    return o;
}

/* a feature point: texel, kind (0 end, 1 curve, 2 branch), polarity (0 ridge, 1 valley), direction */
typedef struct rl__feat { int x, y, kind, valley; float angle; } rl__feat;

typedef struct rl__synth {
    rl_synth_options o;
    rl_allocator a;
    const float *ex;
    int ew, eh, w, h, P, O, patch_id, windows_done, windows_total;
    float lo, range;
    float *out;              /* w*h output heights */
    int32_t *owner;          /* w*h: patch id, -1 = not filled yet */
    uint8_t *stroke;         /* w*h: 1 white stroke, 2 black stroke, 0 none */
    uint8_t *locked;         /* w*h: a feature patch's centre, kept by every later cut */
    uint8_t *sk_edges[2];    /* the sketch's ridge (white) and valley (black) skeletons */
    float *cand, *best;      /* P*P candidate patches */
    float *ga, *gb;          /* P*P graph-cut inputs */
    uint8_t *cons, *lab;     /* P*P */
    uint8_t *best_lab;       /* K*P*P: each fill candidate's cut */
    int32_t *band;           /* P*P: Poisson distance, -1 outside */
    int32_t *queue;          /* P*P */
    int32_t *st_nb; float *st_g; uint8_t *st_cnt; /* 4*P*P, 4*P*P, P*P: the band's stencils */
    int *node;               /* P*P */
    int32_t *fill_off;       /* P*P: the fill search's runs (or a feature's texel list) */
    float *fill_val;         /* and output values */
    float *ex_half;          /* ew*eh: the example's even columns, then its odd ones */
    rl__flow flow;           /* graph-cut workspace for P*P texels */
} rl__synth;

static float rl__bilinear(const float *m, int w, int h, float x, float y)
{
    int x0, y0, x1, y1;
    float fx, fy, a, b;
    x0 = (int)x; y0 = (int)y;           /* floor, without a libm call: |x|, |y| < 2^31 here */
    x0 -= (float)x0 > x; y0 -= (float)y0 > y;
    fx = x - (float)x0; fy = y - (float)y0;
    x1 = x0 + 1; y1 = y0 + 1;
    x0 = x0 < 0 ? 0 : x0 >= w ? w - 1 : x0; x1 = x1 < 0 ? 0 : x1 >= w ? w - 1 : x1;
    y0 = y0 < 0 ? 0 : y0 >= h ? h - 1 : y0; y1 = y1 < 0 ? 0 : y1 >= h ? h - 1 : y1;
    a = m[(size_t)y0 * w + x0] + fx * (m[(size_t)y0 * w + x1] - m[(size_t)y0 * w + x0]);
    b = m[(size_t)y1 * w + x0] + fx * (m[(size_t)y1 * w + x1] - m[(size_t)y1 * w + x0]);
    return a + fy * (b - a);
}

/* rl__bilinear where x, y >= 0 and x + 1, y + 1 < the map's sides (no clamp would act: the same
   values) */
static float rl__bilinear_in(const float *m, int w, float x, float y)
{
    int x0 = (int)x, y0 = (int)y;
    float fx = x - (float)x0, fy = y - (float)y0, a, b;
    const float *r0 = m + (size_t)y0 * w + x0, *r1 = r0 + w;
    a = r0[0] + fx * (r0[1] - r0[0]);
    b = r1[0] + fx * (r1[1] - r1[0]);
    return a + fy * (b - a);
}

/* The example patch centred at example texel (cx, cy), rotated by angle, for the output window
   whose centre is at window texel (P/2, P/2): the only warp (see DECISIONS). With a list, only
   its n window texels (j * P + i) are sampled; else every step-th texel of every step-th row. */
static void rl__sample_patch(const rl__synth *S, float cx, float cy, float angle, int step, const int32_t *list, int n, float *dst)
{
    float c = cosf(angle), s = sinf(angle), h = 0.5f * (float)S->P - 0.5f, R = 2.0f * h + 2.0f;
    int i, j, t, count = list ? n : ((S->P + step - 1) / step) * ((S->P + step - 1) / step), per_row = (S->P + step - 1) / step;
    int inside = cx - R >= 0.0f && cy - R >= 0.0f && cx + R + 1.0f < (float)S->ew && cy + R + 1.0f < (float)S->eh;
    for (t = 0; t < count; t++) {
        float u, v, x, y;
        if (list) { i = list[t] % S->P; j = list[t] / S->P; }
        else { i = (t % per_row) * step; j = (t / per_row) * step; }
        u = (float)i - h; v = (float)j - h;
        x = cx + 0.5f + c * u - s * v - 0.5f;
        y = cy + 0.5f + s * u + c * v - 0.5f;
        dst[j * S->P + i] = inside ? rl__bilinear_in(S->ex, S->ew, x, y) : rl__bilinear(S->ex, S->ew, S->eh, x, y);
    }
}

static void rl__copy_patch(const rl__synth *S, int ex, int ey, float *dst)
{
    int j;
    for (j = 0; j < S->P; j++) memcpy(dst + j * S->P, S->ex + (size_t)(ey + j) * S->ew + ex, sizeof(float) * (size_t)S->P);
}

/* mean squared difference between a candidate and the filled output texels of window (wx, wy),
   every step-th texel; *count = the texels compared */
static double rl__overlap_ssd(const rl__synth *S, int wx, int wy, const float *cand, int step, int *count)
{
    double sum = 0.0;
    int i, j, n = 0;
    for (j = 0; j < S->P; j += step) {
        int y = wy + j;
        if (y < 0 || y >= S->h) continue;
        for (i = 0; i < S->P; i += step) {
            int x = wx + i;
            size_t p;
            double d;
            if (x < 0 || x >= S->w) continue;
            p = (size_t)y * S->w + x;
            if (S->owner[p] < 0) continue;
            d = (double)cand[j * S->P + i] - (double)S->out[p];
            sum += d * d;
            n++;
        }
    }
    if (count) *count = n;
    return n ? sum / n : 0.0;
}

/* The graph cut of a candidate in window (wx, wy) against the output: texels not filled yet
   must come from the candidate, filled texels on the window's border whose outside neighbour
   is filled must stay, and (pin_radius > 0) texels that near the centre must be the candidate's.
   Leaves the labels in S->lab (1 = candidate) over the window's in-bounds rectangle; returns the
   cut cost, 0 with all labels 1 when nothing overlaps. */
static rl_result rl__cut(rl__synth *S, int wx, int wy, const float *cand, float pin_radius, double *cost, int *overlap)
{
    int x0 = wx < 0 ? 0 : wx, y0 = wy < 0 ? 0 : wy, x1 = wx + S->P > S->w ? S->w : wx + S->P, y1 = wy + S->P > S->h ? S->h : wy + S->P;
    int rw = x1 - x0, rh = y1 - y0, i, j, nover = 0;
    float c = 0.5f * (float)S->P - 0.5f;
    for (j = 0; j < rh; j++)
        for (i = 0; i < rw; i++) {
            int x = x0 + i, y = y0 + j, q = j * rw + i;
            size_t p = (size_t)y * S->w + x;
            float b = cand[(y - wy) * S->P + (x - wx)], du = (float)(x - wx) - c, dv = (float)(y - wy) - c;
            S->gb[q] = b;
            if (S->owner[p] < 0) { S->ga[q] = b; S->cons[q] = 2; continue; }
            S->ga[q] = S->out[p];
            S->cons[q] = 0;
            nover++;
            if ((i == 0 && x > 0 && S->owner[p - 1] >= 0) || (i == rw - 1 && x + 1 < S->w && S->owner[p + 1] >= 0) ||
                (j == 0 && y > 0 && S->owner[p - (size_t)S->w] >= 0) || (j == rh - 1 && y + 1 < S->h && S->owner[p + (size_t)S->w] >= 0))
                S->cons[q] = 1;
            if (pin_radius > 0.0f && du * du + dv * dv <= pin_radius * pin_radius) S->cons[q] = 2;
            if (S->locked[p]) S->cons[q] = 1; /* an earlier feature patch's centre stays */
        }
    *overlap = nover;
    if (!nover) { memset(S->lab, 1, (size_t)rw * (size_t)rh); *cost = 0.0; return RL_OK; }
    rl__cut_solve(&S->flow, S->ga, S->gb, S->cons, rw, rh, S->node, S->lab);
    *cost = rl__cut_cost(S->flow.diff, S->lab, rw, rh);
    return RL_OK;
}

/* The Gauss-Seidel sweeps over the band's nq texels (S->queue, window-local in the rw-wide
   rectangle at (x0, y0)): each texel's neighbours and their guidance are gathered once
   (S->st_nb, S->st_g, 4 a texel; S->st_cnt), then each sweep is v = mean(out[nb] + g) in the
   queue's order, until no texel moves by more than 1e-5 of the range (at most 64 sweeps). */
static void rl__blend_solve(rl__synth *S, int x0, int y0, int rw, int nq, const float *cand, int wx, int wy)
{
    static const int nx[4] = {1, -1, 0, 0}, ny[4] = {0, 0, 1, -1};
    int i, k, it, id = S->patch_id;
    for (i = 0; i < nq; i++) {
        int q = S->queue[i], x = x0 + q % rw, y = y0 + q / rw, cnt = 0;
        float b = cand[(y - wy) * S->P + (x - wx)];
        for (k = 0; k < 4; k++) {
            int xx = x + nx[k], yy = y + ny[k];
            size_t pq;
            if (xx < 0 || yy < 0 || xx >= S->w || yy >= S->h) continue;
            pq = (size_t)yy * S->w + xx;
            if (S->owner[pq] < 0) continue;
            S->st_nb[4 * i + cnt] = (int32_t)pq;   /* sum never is -0, so adding a zero guidance is exact */
            S->st_g[4 * i + cnt] = (S->owner[pq] == id || (xx >= wx && yy >= wy && xx < wx + S->P && yy < wy + S->P))
                                       ? b - cand[(yy - wy) * S->P + (xx - wx)] : 0.0f;
            cnt++;
        }
        S->st_cnt[i] = (uint8_t)cnt;
        S->queue[i] = (int32_t)((size_t)y * S->w + x); /* from here on: the texel's output index */
    }
    for (it = 0; it < 64; it++) {
        float change = 0.0f;
        for (i = 0; i < nq; i++) {
            size_t p = (size_t)S->queue[i];
            const int32_t *nb = S->st_nb + 4 * i;
            const float *g = S->st_g + 4 * i;
            float sum = 0.0f, v, d;
            for (k = 0; k < S->st_cnt[i]; k++) sum += S->out[nb[k]] + g[k];
            v = sum / (float)S->st_cnt[i];
            d = fabsf(v - S->out[p]);
            change = d > change ? d : change;
            S->out[p] = v;
        }
        if (change <= 1e-5f * S->range) break;
    }
}

/* Poisson seam removal in a band: the texels this patch just took that lie within blend_band
   (4-neighbour steps) of a texel of another patch are solved for, with the patch's own gradients
   as guidance, zero guidance across the seam, and everything else fixed (Gauss-Seidel). */
static void rl__blend(rl__synth *S, int x0, int y0, int rw, int rh, const float *cand, int wx, int wy)
{
    int band = S->o.blend_band, qh = 0, qt = 0, i, k, id = S->patch_id;
    static const int nx[4] = {1, -1, 0, 0}, ny[4] = {0, 0, 1, -1};
    if (band <= 0) return;
    for (i = 0; i < rw * rh; i++) {
        int x = x0 + i % rw, y = y0 + i / rw, seam = 0;
        size_t p = (size_t)y * S->w + x;
        S->band[i] = -1;
        if (S->owner[p] != id) continue;
        for (k = 0; k < 4 && !seam; k++) {
            int xx = x + nx[k], yy = y + ny[k];
            if (xx < 0 || yy < 0 || xx >= S->w || yy >= S->h) continue;
            seam = S->owner[(size_t)yy * S->w + xx] >= 0 && S->owner[(size_t)yy * S->w + xx] != id;
        }
        if (seam) { S->band[i] = 0; S->queue[qt++] = i; }
    }
    while (qh < qt) { /* breadth-first distance from the seam inside this patch's texels */
        int q = S->queue[qh++], x = q % rw, y = q / rw;
        if (S->band[q] >= band - 1) continue;
        for (k = 0; k < 4; k++) {
            int xx = x + nx[k], yy = y + ny[k], r;
            if (xx < 0 || yy < 0 || xx >= rw || yy >= rh) continue;
            r = yy * rw + xx;
            if (S->band[r] >= 0 || S->owner[(size_t)(y0 + yy) * S->w + (x0 + xx)] != id) continue;
            S->band[r] = S->band[q] + 1;
            S->queue[qt++] = r;
        }
    }
    rl__blend_solve(S, x0, y0, rw, qt, cand, wx, wy);
}

/* copies the candidate's side of the cut in S->lab into window (wx, wy), blends the seam */
static rl_result rl__commit(rl__synth *S, int wx, int wy, const float *cand)
{
    int x0 = wx < 0 ? 0 : wx, y0 = wy < 0 ? 0 : wy, x1 = wx + S->P > S->w ? S->w : wx + S->P, y1 = wy + S->P > S->h ? S->h : wy + S->P;
    int rw = x1 - x0, rh = y1 - y0, i, j;
    if (rw <= 0 || rh <= 0) return RL_OK;
    S->patch_id++;
    for (j = 0; j < rh; j++)
        for (i = 0; i < rw; i++) {
            size_t p = (size_t)(y0 + j) * S->w + (size_t)(x0 + i);
            if (!S->lab[j * rw + i]) continue;
            S->out[p] = cand[(y0 + j - wy) * S->P + (x0 + i - wx)];
            S->owner[p] = S->patch_id;
        }
    rl__blend(S, x0, y0, rw, rh, cand, wx, wy);
    return RL_OK;
}

/* cuts the candidate into window (wx, wy) and commits it; a feature patch's centre disc
   (pin_radius > 0) is then locked against later patches */
static rl_result rl__place(rl__synth *S, int wx, int wy, const float *cand, float pin_radius)
{
    double cost;
    int nover, i, j;
    float c = 0.5f * (float)S->P - 0.5f;
    rl_result r;
    if (wx >= S->w || wy >= S->h || wx + S->P <= 0 || wy + S->P <= 0) return RL_OK;
    if ((r = rl__cut(S, wx, wy, cand, pin_radius, &cost, &nover)) != RL_OK) return r;
    if ((r = rl__commit(S, wx, wy, cand)) != RL_OK || pin_radius <= 0.0f) return r;
    for (j = 0; j < S->P; j++)
        for (i = 0; i < S->P; i++) {
            int x = wx + i, y = wy + j;
            size_t p;
            if (x < 0 || y < 0 || x >= S->w || y >= S->h) continue;
            p = (size_t)y * S->w + x;
            if (S->owner[p] == S->patch_id && ((float)i - c) * ((float)i - c) + ((float)j - c) * ((float)j - c) <= pin_radius * pin_radius)
                S->locked[p] = 1;
        }
    return RL_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: feature points (Sec. 5.2.3: branch nodes, terminal nodes, curve paths)
   --------------------------------------------------------------------------------------------- */

/* the direction (mod pi) of the skeleton texels within radius r of (x, y): principal axis */
static float rl__direction(const uint8_t *edges, int w, int h, int x, int y, int r)
{
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, n = 0;
    int i, j;
    for (j = y - r; j <= y + r; j++)
        for (i = x - r; i <= x + r; i++) {
            if (i < 0 || j < 0 || i >= w || j >= h || !edges[(size_t)j * w + i]) continue;
            sx += i; sy += j; sxx += (double)i * i; syy += (double)j * j; sxy += (double)i * j; n++;
        }
    if (n < 2) return 0.0f;
    sxx -= sx * sx / n; syy -= sy * sy / n; sxy -= sx * sy / n;
    return (float)(0.5 * atan2(2.0 * sxy, sxx - syy));
}

static int rl__kind(uint8_t e) { int d = rl__degree(e); return d == 1 ? 0 : d >= 3 ? 2 : 1; }

/* Feature samples of a skeleton, breadth first over each tree from a branch node (else an end
   node, else its first texel), each component's roots in raster order: every node, and a curve
   sample every `spacing` steps of depth. Returns the count (at most cap). seen, queue: w*h. */
static int rl__feature_samples(const uint8_t *edges, int w, int h, int valley, int spacing, int32_t *seen, int32_t *queue,
                               rl__feat *f, int cap)
{
    size_t n = (size_t)w * (size_t)h, i;
    int count = 0, pass, k;
    for (i = 0; i < n; i++) seen[i] = -1;
    for (pass = 2; pass >= 0; pass--) /* roots: branch nodes first, then ends, then anything */
        for (i = 0; i < n; i++) {
            int qh = 0, qt = 0;
            int kind0 = edges[i] ? rl__kind(edges[i]) : -1;
            if (kind0 < 0 || seen[i] >= 0 || (pass == 2 && kind0 != 2) || (pass == 1 && kind0 != 0)) continue;
            seen[i] = 0;
            queue[qt++] = (int32_t)i;
            while (qh < qt) {
                int32_t q = queue[qh++];
                int x = (int)(q % w), y = (int)(q / w), kind = rl__kind(edges[q]);
                if ((kind != 1 || seen[q] % spacing == 0) && count < cap) {
                    f[count].x = x; f[count].y = y; f[count].kind = kind; f[count].valley = valley;
                    f[count].angle = rl__direction(edges, w, h, x, y, 4);
                    count++;
                }
                for (k = 0; k < 8; k++) {
                    size_t r;
                    if (!(edges[q] & (1u << k))) continue;
                    r = (size_t)(y + rl__dy[k]) * w + (size_t)(x + rl__dx[k]);
                    if (seen[r] >= 0) continue;
                    seen[r] = seen[q] + 1;
                    queue[qt++] = (int32_t)r;
                }
            }
        }
    return count;
}

static int rl__u64_cmp(const void *p, const void *q)
{
    uint64_t a = *(const uint64_t *)p, b = *(const uint64_t *)q;
    return a < b ? -1 : a > b;
}

/* The example's feature points of one polarity far enough from its border for a rotated patch:
   per kind, the most prominent first (highest ridge texels, lowest valley texels; ties by
   index), skipping any closer than patch / 4 to one already taken, at most `cap`. Prominence
   first because a ridge of the example is a ridge at any height: taking them in raster order
   put crests under white strokes that stood barely above the mean. keys: ew*eh scratch. */
static int rl__example_features(const rl__synth *S, const uint8_t *edges, int valley, rl__feat *f, int cap, uint64_t *keys)
{
    int margin = (int)ceilf(0.7072f * (float)S->P) + 2, kind, count = 0, x, y, sep = S->P / 4;
    for (kind = 0; kind < 3; kind++) {
        size_t total = 0, k;
        int first = count;
        for (y = margin; y < S->eh - margin; y++)
            for (x = margin; x < S->ew - margin; x++) {
                size_t q = (size_t)y * S->ew + x;
                uint8_t e = edges[q];
                if (e && rl__kind(e) == kind) keys[total++] = ((uint64_t)rl__weight_key(valley ? -S->ex[q] : S->ex[q]) << 32) | (uint64_t)q;
            }
        qsort(keys, total, sizeof *keys, rl__u64_cmp);
        for (k = 0; k < total && count - first < cap; k++) {
            uint32_t q = (uint32_t)(keys[k] & 0xFFFFFFFFu);
            int qx = (int)(q % (uint32_t)S->ew), qy = (int)(q / (uint32_t)S->ew), j, close = 0;
            for (j = first; j < count && !close; j++) close = abs(f[j].x - qx) < sep && abs(f[j].y - qy) < sep;
            if (close) continue;
            f[count].x = qx; f[count].y = qy;
            f[count].kind = kind; f[count].valley = valley;
            f[count].angle = rl__direction(edges, S->ew, S->eh, qx, qy, 4);
            count++;
        }
    }
    return count;
}

/* feature dissimilarity c_f: along the sketch's skeleton texels of this polarity inside the
   window, the mean |candidate - candidate's centre| in units of the height range (a candidate
   whose ridge follows the stroke keeps its crest height along it) */
static float rl__feature_cost(const rl__synth *S, const uint8_t *edges, int wx, int wy, const float *cand)
{
    int c0 = (S->P / 2) & ~1;
    float centre = cand[c0 * S->P + c0], sum = 0.0f;
    int i, j, n = 0;
    for (j = 0; j < S->P; j += 2)
        for (i = 0; i < S->P; i += 2) {
            int x = wx + i, y = wy + j;
            if (x < 0 || y < 0 || x >= S->w || y >= S->h || !edges[(size_t)y * S->w + x]) continue;
            sum += fabsf(cand[j * S->P + i] - centre);
            n++;
        }
    return n ? sum / (float)n / S->range : 0.0f;
}

/* the example patch for one sketch feature: same polarity and kind (any kind when none), both
   orientations; least alpha_g * overlap mismatch + alpha_f * c_f */
static rl_result rl__place_feature(rl__synth *S, const rl__feat *t, const rl__feat *src, int nsrc)
{
    int wx = t->x - S->P / 2, wy = t->y - S->P / 2, k, flip, best = -1, best_flip = 0, any_kind = 1;
    double best_cost = 0.0;
    const uint8_t *edges = S->sk_edges[t->valley];
    int i, j, c0 = (S->P / 2) & ~1, nl = 0;
    for (k = 0; k < nsrc; k++) if (src[k].valley == t->valley && src[k].kind == t->kind) any_kind = 0;
    for (j = 0; j < S->P; j += 2) /* the texels the two costs read: filled or skeleton ones, and the centre */
        for (i = 0; i < S->P; i += 2) {
            int x = wx + i, y = wy + j;
            size_t p = (size_t)y * S->w + x;
            if ((i == c0 && j == c0) || (x >= 0 && y >= 0 && x < S->w && y < S->h && (S->owner[p] >= 0 || edges[p])))
                S->fill_off[nl++] = j * S->P + i;
        }
    for (k = 0; k < nsrc; k++) {
        if (src[k].valley != t->valley || (!any_kind && src[k].kind != t->kind)) continue;
        for (flip = 0; flip < 2; flip++) {
            float angle = src[k].angle - t->angle + (flip ? 3.14159265f : 0.0f);
            double c;
            rl__sample_patch(S, (float)src[k].x, (float)src[k].y, angle, 2, S->fill_off, nl, S->cand);
            c = S->o.alpha_g * rl__overlap_ssd(S, wx, wy, S->cand, 2, NULL) / ((double)S->range * S->range) +
                S->o.alpha_f * rl__feature_cost(S, edges, wx, wy, S->cand);
            if (best < 0 || c < best_cost) { best = k; best_flip = flip; best_cost = c; }
        }
    }
    if (best < 0) return RL_OK;
    rl__sample_patch(S, (float)src[best].x, (float)src[best].y, src[best].angle - t->angle + (best_flip ? 3.14159265f : 0.0f), 1, NULL, 0, S->best);
    return rl__place(S, wx, wy, S->best, (float)S->P / 6.0f);
}

/* ---------------------------------------------------------------------------------------------
   Section: non-feature fill (K best by SSD, then SSD + seam cost), the pipeline, the baseline
   --------------------------------------------------------------------------------------------- */

/* mean squared difference of the example patch at (ex, ey) over the window's n filled texels
   (every other one of every other row, so all in example columns of ex's parity), listed as
   nruns runs along rows (S->fill_off: row j, column i / 2, length; values in S->fill_val).
   The example's columns of that parity lie contiguous in S->ex_half, so each run is a plain
   loop (8 float lanes) that the compiler vectorises; -1 once the sum passes limit * n (checked
   after each run); with nothing to match, a fixed spread of costs in [0, 1000). */
static double rl__fill_score(const rl__synth *S, int wx, int wy, int ex, int ey, int nruns, int n, double limit)
{
    int par = ex & 1, hw = par ? S->ew / 2 : (S->ew + 1) / 2, r, t, k;
    const float *base = S->ex_half + (par ? (size_t)S->eh * (size_t)((S->ew + 1) / 2) : 0) + (size_t)ey * hw + (ex >> 1);
    const float *val = S->fill_val;
    const int32_t *run = S->fill_off;
    double c = 0.0, stop = limit * n;
    if (!n) return (double)(((uint32_t)wx * 73856093u ^ (uint32_t)wy * 19349663u ^ (uint32_t)ex * 83492791u ^ (uint32_t)ey * 2654435761u) % 1000u);
    for (r = 0; r < nruns && c < stop; r++, run += 3) {
        const float *e = base + (size_t)run[0] * hw + run[1];
        int len = run[2];
        float acc[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
        for (t = 0; t + 8 <= len; t += 8)
            for (k = 0; k < 8; k++) { float d = e[t + k] - val[t + k]; acc[k] += d * d; }
        for (; t < len; t++) { float d = e[t] - val[t]; acc[0] += d * d; }
        c += (double)(((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])));
        val += len;
    }
    return c >= stop ? -1.0 : c / n;
}

/* keeps the k best (least cost) positions, sorted, ties to the earlier one */
static void rl__keep_best(double *cost, int *px, int *py, int *count, int k, double c, int x, int y)
{
    int i;
    if (*count == k && c >= cost[k - 1]) return;
    i = *count < k ? (*count)++ : k - 1;
    while (i > 0 && cost[i - 1] > c) { cost[i] = cost[i - 1]; px[i] = px[i - 1]; py[i] = py[i - 1]; i--; }
    cost[i] = c; px[i] = x; py[i] = y;
}

/* Of the nk candidates, the one to place: the least full SSD + alpha_g * cut cost per overlap
   texel (ties to the lower index), or with tolerance a fixed pick among those within
   (1 + tolerance) of it. The cut cost is never negative, so a candidate whose SSD alone passes
   that bound cannot be picked and gets no cut; candidates go by SSD so that happens early.
   Each cut's labels are kept (best_lab, P*P a candidate) for the one placed. */
static rl_result rl__pick_fill(rl__synth *S, int wx, int wy, const int *kx, const int *ky, int nk, int *pick)
{
    double ssd[RL__KMAX], costs[RL__KMAX], best_cost = 0.0, tol = S->o.tolerance > 0.0f ? S->o.tolerance : 0.0;
    int order[RL__KMAX], k, t, best = -1;
    size_t pp = (size_t)S->P * (size_t)S->P;
    rl_result r;
    for (k = 0; k < nk; k++) {
        rl__copy_patch(S, kx[k], ky[k], S->cand);
        ssd[k] = rl__overlap_ssd(S, wx, wy, S->cand, 1, NULL) / ((double)S->range * S->range);
        costs[k] = 1e300;
        for (t = k; t > 0 && ssd[order[t - 1]] > ssd[k]; t--) order[t] = order[t - 1];
        order[t] = k;
    }
    for (t = 0; t < nk; t++) {
        double cut, c;
        int nover;
        k = order[t];
        if (best >= 0 && ssd[k] > (1.0 + tol) * best_cost) break;
        rl__copy_patch(S, kx[k], ky[k], S->cand);
        if ((r = rl__cut(S, wx, wy, S->cand, 0.0f, &cut, &nover)) != RL_OK) return r;
        c = ssd[k] + S->o.alpha_g * cut / ((nover ? nover : 1) * (double)S->range);
        memcpy(S->best_lab + (size_t)k * pp, S->lab, pp);
        if (best < 0 || c < best_cost || (c == best_cost && k < best)) { best = k; best_cost = c; }
        costs[k] = c;
    }
    *pick = best;
    if (best >= 0 && tol > 0.0) {
        int ok[RL__KMAX], nok = 0;
        uint32_t hsh = (uint32_t)(wx * 2654435761u) ^ (uint32_t)(wy * 40503u + 7u);
        for (k = 0; k < nk; k++) if (costs[k] <= (1.0 + tol) * best_cost) ok[nok++] = k;
        *pick = ok[(hsh ^ (hsh >> 15)) % (uint32_t)nok];
    }
    return RL_OK;
}

/* The window's best example position. The filled texels it is compared on: every other one.
   Coarse to fine: the 4 best positions on a grid of 2 x stride, then the stride neighbourhoods
   (3 x 3) of those give the K least SSD; rl__pick_fill chooses among them by SSD and seam. */
static rl_result rl__place_fill(rl__synth *S, int wx, int wy)
{
    enum { COARSE = 4 };
    double kc[RL__KMAX], cc[COARSE];
    int kx[RL__KMAX], ky[RL__KMAX], cx[COARSE], cy[COARSE], nk = 0, nc = 0, K = S->o.candidates, stride = S->o.search_stride;
    int ex, ey, n = 0, nr = 0, i, j, q, pick;
    rl_result r;
    K = K > RL__KMAX ? RL__KMAX : K;
    for (j = 0; j < S->P; j += 2)           /* the filled texels compared on, as runs along rows */
        for (i = 0; i < S->P; i += 2) {
            int x = wx + i, y = wy + j;
            size_t p = (size_t)y * S->w + x;
            if (x < 0 || y < 0 || x >= S->w || y >= S->h || S->owner[p] < 0) continue;
            if (!nr || S->fill_off[3 * nr - 3] != j || S->fill_off[3 * nr - 2] + S->fill_off[3 * nr - 1] != i / 2) {
                S->fill_off[3 * nr] = j; S->fill_off[3 * nr + 1] = i / 2; S->fill_off[3 * nr + 2] = 0;
                nr++;
            }
            S->fill_off[3 * nr - 1]++;
            S->fill_val[n++] = S->out[p];
        }
    for (ey = 0; ey + S->P <= S->eh; ey += 2 * stride)
        for (ex = 0; ex + S->P <= S->ew; ex += 2 * stride) {
            double c = rl__fill_score(S, wx, wy, ex, ey, nr, n, nc == COARSE ? cc[COARSE - 1] : 1e300);
            if (c >= 0.0) rl__keep_best(cc, cx, cy, &nc, COARSE, c, ex, ey);
        }
    for (q = 0; q < nc; q++)
        for (j = -1; j <= 1; j++)
            for (i = -1; i <= 1; i++) {
                int t, dup = 0;
                double c;
                ex = cx[q] + i * stride; ey = cy[q] + j * stride;
                if (ex < 0 || ey < 0 || ex + S->P > S->ew || ey + S->P > S->eh) continue;
                for (t = 0; t < nk; t++) dup |= kx[t] == ex && ky[t] == ey;
                if (dup) continue;
                c = rl__fill_score(S, wx, wy, ex, ey, nr, n, nk == K ? kc[K - 1] : 1e300);
                if (c >= 0.0) rl__keep_best(kc, kx, ky, &nk, K, c, ex, ey);
            }
    if ((r = rl__pick_fill(S, wx, wy, kx, ky, nk, &pick)) != RL_OK || pick < 0) return r;
    rl__copy_patch(S, kx[pick], ky[pick], S->best);
    memcpy(S->lab, S->best_lab + (size_t)pick * (size_t)S->P * (size_t)S->P, (size_t)S->P * (size_t)S->P);
    return rl__commit(S, wx, wy, S->best);
}

static int rl__window_has_hole(const rl__synth *S, int wx, int wy)
{
    int i, j;
    for (j = wy < 0 ? 0 : wy; j < wy + S->P && j < S->h; j++)
        for (i = wx < 0 ? 0 : wx; i < wx + S->P && i < S->w; i++)
            if (S->owner[(size_t)j * S->w + i] < 0) return 1;
    return 0;
}

static int rl__progress(rl__synth *S)
{
    S->windows_done++;
    if (!S->o.progress) return 0;
    return S->o.progress(S->o.progress_user, S->windows_total ? (float)S->windows_done / (float)S->windows_total : 1.0f);
}

/* grid windows at steps of P - O, the last one flush with the far border, raster order */
static rl_result rl__fill(rl__synth *S)
{
    int step = S->P - S->O, nx = S->w > S->P ? (S->w - S->P + step - 1) / step + 1 : 1, ny = S->h > S->P ? (S->h - S->P + step - 1) / step + 1 : 1, i, j;
    rl_result r;
    for (j = 0; j < ny; j++)
        for (i = 0; i < nx; i++) {
            int wx = i * step, wy = j * step;
            if (wx + S->P > S->w) wx = S->w - S->P < 0 ? 0 : S->w - S->P;
            if (wy + S->P > S->h) wy = S->h - S->P < 0 ? 0 : S->h - S->P;
            if (!rl__window_has_hole(S, wx, wy)) continue;
            if ((r = rl__place_fill(S, wx, wy)) != RL_OK) return r;
            if (rl__progress(S)) return RL_CANCELLED;
        }
    return RL_OK;
}

/* strokes: 1 where the sketch is above 0.75 (white), 2 below 0.25 (black); also their
   skeletons, from the distance to the stroke's outside (its medial axis is that map's ridge), computed once
   into all and masked per polarity into dist (both w*h floats of scratch) */
static rl_result rl__sketch_features(rl__synth *S, const rl_map *sketch, float *all, float *dist)
{
    size_t n = (size_t)S->w * (size_t)S->h, i;
    int pol, any = 0;
    rl_skeleton_options so = rl_skeleton_default_options();
    rl_result r;
    for (i = 0; i < n; i++) {
        float v = sketch->data[i];
        S->stroke[i] = (uint8_t)(v > 0.75f ? 1 : v < 0.25f ? 2 : 0);
        any |= S->stroke[i];
    }
    if (!any) return RL_ERR_NO_STROKES;
    so.threshold = 0.5f;
    if ((r = rl__distance(S->stroke, 0, S->w, S->h, &S->a, all)) != RL_OK) return r;
    for (pol = 0; pol < 2; pol++) {
        rl_map m;
        rl_skeleton sk;
        uint8_t keep = (uint8_t)(pol + 1);
        for (i = 0; i < n; i++) dist[i] = S->stroke[i] == keep ? all[i] : 0.0f;
        m.width = S->w; m.height = S->h; m.data = dist;
        if ((r = rl_skeleton_extract(&m, &so, &S->a, &sk)) != RL_OK) return r;
        S->sk_edges[pol] = sk.edges;
    }
    return RL_OK;
}

/* adds emphasis * range * (G(d_white) - G(d_black)), G(d) = exp(-d^2 / (2 w^2)) */
/* 1 when the n values are finite */
static int rl__all_finite(const float *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (x[i] - x[i] != 0.0f) return 0;
    return 1;
}

static rl_result rl__emphasis(const uint8_t *stroke, int w, int h, float amount, float width, const rl_allocator *a, float *out)
{
    size_t n = (size_t)w * (size_t)h, i;
    float *d = (float *)rl__alloc(a, sizeof(float) * n), k = -0.5f / (width * width);
    uint8_t *m = (uint8_t *)rl__alloc(a, n);
    int pol;
    rl_result r = RL_OK;
    if (!d || !m) { rl__free(a, d); rl__free(a, m); return RL_ERR_OUT_OF_MEMORY; }
    for (pol = 1; pol <= 2 && r == RL_OK && amount != 0.0f; pol++) {
        for (i = 0; i < n; i++) m[i] = stroke[i] == pol;
        r = rl__distance(m, 1, w, h, a, d);
        /* on a stroke (d = 0) the profile is 1 even when a tiny width makes k -infinity */
        for (i = 0; r == RL_OK && i < n; i++) out[i] += (pol == 1 ? amount : -amount) * (d[i] > 0.0f ? expf(k * d[i] * d[i]) : 1.0f);
    }
    rl__free(a, d);
    rl__free(a, m);
    return r;
}

static void rl__synth_free(rl__synth *S)
{
    rl__free(&S->a, S->owner); rl__free(&S->a, S->stroke); rl__free(&S->a, S->locked); rl__free(&S->a, S->sk_edges[0]); rl__free(&S->a, S->sk_edges[1]);
    rl__free(&S->a, S->cand); rl__free(&S->a, S->best); rl__free(&S->a, S->ga); rl__free(&S->a, S->gb);
    rl__free(&S->a, S->cons); rl__free(&S->a, S->lab); rl__free(&S->a, S->band); rl__free(&S->a, S->queue);
    rl__free(&S->a, S->st_nb); rl__free(&S->a, S->st_g); rl__free(&S->a, S->st_cnt);
    rl__free(&S->a, S->node); rl__free(&S->a, S->best_lab); rl__free(&S->a, S->fill_off); rl__free(&S->a, S->fill_val); rl__free(&S->a, S->ex_half);
    if (S->flow.to) rl__flow_free(&S->flow, &S->a);
}

/* checks both maps and the options, resolves defaults, allocates the state */
static rl_result rl__synth_init(rl__synth *S, const rl_map *example, const rl_map *sketch, const rl_synth_options *options)
{
    rl_synth_options d = rl_synth_default_options();
    size_t pp, n;
    float hi;
    rl_result r;
    memset(S, 0, sizeof *S);
    S->o = options ? *options : d;
    S->a = rl__allocator(S->o.allocator);
    if ((r = rl__check_map(example, &S->lo, &hi)) != RL_OK) return r;
    if ((r = rl__check_map(sketch, NULL, NULL)) != RL_OK) return r;
    if (S->o.patch < 0 || S->o.overlap < 0 || S->o.candidates < 0 || S->o.search_stride < 0 || S->o.feature_candidates < 0 ||
        !(S->o.alpha_g >= 0.0f) || !(S->o.alpha_f >= 0.0f) || !(S->o.stroke_width >= 0.0f) || S->o.emphasis != S->o.emphasis ||
        S->o.patch > 1024)
        return RL_ERR_INVALID_ARGUMENT;
    if (!S->o.patch) S->o.patch = d.patch;
    if (!S->o.overlap) S->o.overlap = S->o.patch / 3;
    if (!S->o.candidates) S->o.candidates = d.candidates;
    if (!S->o.search_stride) S->o.search_stride = d.search_stride;
    if (!S->o.feature_candidates) S->o.feature_candidates = d.feature_candidates;
    if (S->o.alpha_g == 0.0f) S->o.alpha_g = d.alpha_g;
    if (S->o.alpha_f == 0.0f) S->o.alpha_f = d.alpha_f;
    if (S->o.emphasis == 0.0f) S->o.emphasis = d.emphasis;
    if (S->o.stroke_width == 0.0f) S->o.stroke_width = d.stroke_width;
    if (S->o.blend_band == 0) S->o.blend_band = d.blend_band;
    if (S->o.tolerance == 0.0f) S->o.tolerance = d.tolerance;
    if (S->o.patch < 4 || S->o.overlap >= S->o.patch) return RL_ERR_INVALID_ARGUMENT;
    if (S->o.patch > example->width || S->o.patch > example->height) return RL_ERR_PATCH_TOO_LARGE;
    S->ex = example->data; S->ew = example->width; S->eh = example->height;
    S->w = sketch->width; S->h = sketch->height;
    S->P = S->o.patch; S->O = S->o.overlap;
    S->range = hi > S->lo ? hi - S->lo : 1.0f;
    n = (size_t)S->w * (size_t)S->h;
    pp = (size_t)S->P * (size_t)S->P;
    S->owner = (int32_t *)rl__alloc(&S->a, sizeof(int32_t) * n);
    S->stroke = (uint8_t *)rl__alloc(&S->a, n);
    S->locked = (uint8_t *)rl__alloc(&S->a, n);
    if (!S->locked) S->stroke = (rl__free(&S->a, S->stroke), (uint8_t *)NULL);
    S->cand = (float *)rl__alloc(&S->a, sizeof(float) * pp);
    S->best = (float *)rl__alloc(&S->a, sizeof(float) * pp);
    S->ga = (float *)rl__alloc(&S->a, sizeof(float) * pp);
    S->gb = (float *)rl__alloc(&S->a, sizeof(float) * pp);
    S->cons = (uint8_t *)rl__alloc(&S->a, pp);
    S->lab = (uint8_t *)rl__alloc(&S->a, pp);
    S->best_lab = (uint8_t *)rl__alloc(&S->a, pp * (size_t)(S->o.candidates < RL__KMAX ? S->o.candidates : RL__KMAX));
    S->band = (int32_t *)rl__alloc(&S->a, sizeof(int32_t) * pp);
    S->st_nb = (int32_t *)rl__alloc(&S->a, sizeof(int32_t) * 4 * pp);
    S->st_g = (float *)rl__alloc(&S->a, sizeof(float) * 4 * pp);
    S->st_cnt = (uint8_t *)rl__alloc(&S->a, pp);
    if (!S->st_nb || !S->st_g || !S->st_cnt) S->band = (rl__free(&S->a, S->band), (int32_t *)NULL);
    S->queue = (int32_t *)rl__alloc(&S->a, sizeof(int32_t) * pp);
    S->node = (int *)rl__alloc(&S->a, sizeof(int) * pp);
    S->fill_off = (int32_t *)rl__alloc(&S->a, sizeof(int32_t) * pp);
    S->fill_val = (float *)rl__alloc(&S->a, sizeof(float) * pp);
    S->ex_half = (float *)rl__alloc(&S->a, sizeof(float) * (size_t)S->ew * (size_t)S->eh);
    if (!S->fill_off || !S->fill_val || !S->ex_half) S->node = (rl__free(&S->a, S->node), (int *)NULL);
    if (S->owner && S->stroke && S->cand && S->best && S->ga && S->gb && S->cons && S->lab && S->best_lab && S->band && S->queue && S->node &&
        rl__flow_init(&S->flow, (int)pp, &S->a) != RL_OK)
        S->node = (rl__free(&S->a, S->node), (int *)NULL);
    if (!S->owner || !S->stroke || !S->cand || !S->best || !S->ga || !S->gb || !S->cons || !S->lab || !S->best_lab || !S->band || !S->queue || !S->node) {
        rl__synth_free(S);
        return RL_ERR_OUT_OF_MEMORY;
    }
    memset(S->owner, 0xFF, sizeof(int32_t) * n);
    memset(S->locked, 0, n);
    {
        int x, y, h0 = (S->ew + 1) / 2, h1 = S->ew / 2;
        for (y = 0; y < S->eh; y++)
            for (x = 0; x < S->ew; x++)
                S->ex_half[(x & 1) ? (size_t)S->eh * h0 + (size_t)y * h1 + x / 2 : (size_t)y * h0 + x / 2] = S->ex[(size_t)y * S->ew + x];
    }
    return RL_OK;
}

/* the sketch's features in breadth-first order get example feature patches */
static rl_result rl__features(rl__synth *S, int32_t *scratch_a, int32_t *scratch_b)
{
    rl_skeleton_options so = S->o.skeleton;
    rl_map ex;
    int pol, nt = 0, ns = 0, cap = 4 * S->w + 4 * S->h + 64, k;
    rl__feat *tf = (rl__feat *)rl__alloc(&S->a, sizeof(rl__feat) * (size_t)cap);
    rl__feat *sf = (rl__feat *)rl__alloc(&S->a, sizeof(rl__feat) * (size_t)(6 * S->o.feature_candidates));
    uint64_t *tmp = (uint64_t *)rl__alloc(&S->a, sizeof(uint64_t) * (size_t)S->ew * (size_t)S->eh);
    rl_result r = RL_OK;
    if (!tf || !sf || !tmp) { rl__free(&S->a, tf); rl__free(&S->a, sf); rl__free(&S->a, tmp); return RL_ERR_OUT_OF_MEMORY; }
    ex.width = S->ew; ex.height = S->eh; ex.data = (float *)(size_t)S->ex;
    for (pol = 0; pol < 2 && r == RL_OK; pol++) {
        rl_skeleton sk;
        nt += rl__feature_samples(S->sk_edges[pol], S->w, S->h, pol, S->P / 2 > 1 ? S->P / 2 : 1, scratch_a, scratch_b, tf + nt, cap - nt);
        so.valleys = pol;
        r = rl_skeleton_extract(&ex, &so, &S->a, &sk);
        if (r == RL_OK) {
            ns += rl__example_features(S, sk.edges, pol, sf + ns, S->o.feature_candidates, tmp);
            rl_skeleton_free(&sk, &S->a);
        }
    }
    S->windows_total += nt;
    for (k = 0; k < nt && r == RL_OK; k++) {
        int j, near = 0; /* a sample within the pinned centre of an earlier one adds nothing */
        float rr = (float)S->P / 6.0f;
        for (j = k - 1; j >= 0 && j >= k - 64 && !near; j--)
            near = tf[j].valley == tf[k].valley && (float)((tf[j].x - tf[k].x) * (tf[j].x - tf[k].x) + (tf[j].y - tf[k].y) * (tf[j].y - tf[k].y)) < rr * rr;
        if (!near) r = rl__place_feature(S, &tf[k], sf, ns);
        if (r == RL_OK && rl__progress(S)) r = RL_CANCELLED;
    }
    rl__free(&S->a, tf); rl__free(&S->a, sf); rl__free(&S->a, tmp);
    return r;
}

RLDEF rl_result rl_synthesize(const rl_map *example, const rl_map *sketch, const rl_synth_options *options, rl_map *out)
{
    rl__synth S;
    rl_result r;
    size_t n, i;
    int32_t *sa = NULL, *sb = NULL;
    if (!out) return RL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if ((r = rl__synth_init(&S, example, sketch, options)) != RL_OK) return r;
    n = (size_t)S.w * (size_t)S.h;
    S.out = (float *)rl__alloc(&S.a, sizeof(float) * n);
    sa = (int32_t *)rl__alloc(&S.a, sizeof(int32_t) * n);
    sb = (int32_t *)rl__alloc(&S.a, sizeof(int32_t) * n);
    r = (S.out && sa && sb) ? RL_OK : RL_ERR_OUT_OF_MEMORY;
    S.windows_total = ((S.w + S.P - S.O - 1) / (S.P - S.O)) * ((S.h + S.P - S.O - 1) / (S.P - S.O));
    if (r == RL_OK) r = rl__sketch_features(&S, sketch, (float *)sb, (float *)sa);     /* 1. the sketch's skeletons */
    if (r == RL_OK) r = rl__features(&S, sa, sb);                         /* 2. feature patches, breadth first */
    if (r == RL_OK) r = rl__fill(&S);                                     /* 3. the rest by best matches */
    if (r == RL_OK && S.o.emphasis > 0.0f)                                /* 4. the strokes' extra relief */
        r = rl__emphasis(S.stroke, S.w, S.h, S.o.emphasis * S.range, S.o.stroke_width, &S.a, S.out);
    if (r == RL_OK && !rl__all_finite(S.out, n)) r = RL_ERR_NOT_FINITE;       /* heights near FLT_MAX */
    if (r == RL_OK && S.o.seams)
        for (i = 0; i < n; i++) {
            size_t x = i % (size_t)S.w;
            S.o.seams[i] = (uint8_t)((x + 1 < (size_t)S.w && S.owner[i] != S.owner[i + 1]) | ((i + (size_t)S.w < n && S.owner[i] != S.owner[i + (size_t)S.w]) << 1));
        }
    rl__free(&S.a, sa);
    rl__free(&S.a, sb);
    rl__synth_free(&S);
    if (r != RL_OK) { rl__free(&S.a, S.out); return r; }
    out->width = S.w; out->height = S.h; out->data = S.out;
    return RL_OK;
}

static int rl__mirror(int i, int n)
{
    int m = i % (2 * n);
    return m < n ? m : 2 * n - 1 - m;
}

RLDEF rl_result rl_emboss(const rl_map *example, const rl_map *sketch, const rl_synth_options *options, rl_map *out)
{
    rl_synth_options o = options ? *options : rl_synth_default_options();
    rl_allocator a = rl__allocator(o.allocator);
    float lo, hi, amount, width;
    uint8_t *stroke;
    size_t n, i;
    int x, y, any = 0;
    rl_result r;
    if (!out) return RL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if ((r = rl__check_map(example, &lo, &hi)) != RL_OK) return r;
    if ((r = rl__check_map(sketch, NULL, NULL)) != RL_OK) return r;
    if (o.emphasis != o.emphasis || !(o.stroke_width >= 0.0f) || !(o.stroke_width < 1e6f)) return RL_ERR_INVALID_ARGUMENT;
    amount = (o.emphasis == 0.0f ? 0.45f : o.emphasis < 0.0f ? 0.0f : o.emphasis) * (hi > lo ? hi - lo : 1.0f);
    width = o.stroke_width == 0.0f ? 3.0f : o.stroke_width;
    n = (size_t)sketch->width * (size_t)sketch->height;
    stroke = (uint8_t *)rl__alloc(&a, n);
    out->data = (float *)rl__alloc(&a, sizeof(float) * n);
    if (!stroke || !out->data) { rl__free(&a, stroke); rl__free(&a, out->data); out->data = NULL; return RL_ERR_OUT_OF_MEMORY; }
    for (i = 0; i < n; i++) {
        float v = sketch->data[i];
        stroke[i] = (uint8_t)(v > 0.75f ? 1 : v < 0.25f ? 2 : 0);
        any |= stroke[i];
    }
    for (y = 0; y < sketch->height; y++)
        for (x = 0; x < sketch->width; x++)
            out->data[(size_t)y * sketch->width + x] = example->data[(size_t)rl__mirror(y, example->height) * example->width + rl__mirror(x, example->width)];
    r = any ? rl__emphasis(stroke, sketch->width, sketch->height, amount, width, &a, out->data) : RL_ERR_NO_STROKES;
    if (r == RL_OK && !rl__all_finite(out->data, n)) r = RL_ERR_NOT_FINITE; /* heights near FLT_MAX */
    rl__free(&a, stroke);
    if (r != RL_OK) { rl__free(&a, out->data); out->data = NULL; return r; }
    out->width = sketch->width; out->height = sketch->height;
    return RL_OK;
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* RL_IMPLEMENTATION_DONE */
#endif /* RL_IMPLEMENTATION */

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
