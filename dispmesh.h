/* dispmesh.h - v0.2 - MIT licence or public domain (see end of file)
   Displacement-mapped meshes (paper 000, Chuang et al.): a dense mesh becomes a coarse base mesh
   that encloses it plus one displacement map that holds its detail, and back.

   HOW TO USE (the main job: dense mesh P, T -> base + map -> dense again)
       // in exactly one C or C++ file, #define DM_IMPLEMENTATION before #include "dispmesh.h"
       dm_shell *shell; dm_pm *pm; dm_param *param; dm_dispmap *map; dm_trimesh *dense;
       dm_shell_grow(P, nv, T, nt, NULL, &shell);                      // 1. the bounding shell
       dm_simplify_options so = {0};  so.target_triangles = 500;       // 2. the base mesh
       so.constraint = dm_shell_constraint;  so.on_collapse = dm_shell_collapsed;
       so.constraint_user = shell;  dm_simplify(P, nv, T, nt, &so, &pm, NULL);
       dm_pm_counts(pm, &bnv, &bnt);  dm_pm_get_mesh(pm, B, BT, NULL); // 3. its arrays (yours)
       dm_param_options po = {0};  po.width = po.height = 1024;        // 4. charts in one map
       dm_parameterize(B, bnv, BT, bnt, &po, &param);
       dm_bake(param, B, bnv, BT, bnt, P, nv, T, nt, NULL, &map);      // 5. displacement, normals
       dm_reconstruct(map, param, B, bnv, BT, bnt, NULL, &dense);      // 6. base + map as a mesh
       dm_trimesh_free(dense); dm_dispmap_free(map); dm_param_free(param); dm_pm_free(pm);
       dm_shell_free(shell);
     Every call returns a dm_result (DM_OK = 0; dm_result_string() names it). Check each one.
     A triangle soup (an STL file) is welded first with dm_weld; dm_simplify refuses it. A mesh wound
     clockwise, or whose triangles disagree with their neighbours, is turned first with dm_orient.

   THE PARTS (each below under the same headings: options, memory, errors, thread safety, limits)
     PART 1  BVH ray caster: dm_bvh_build, dm_bvh_intersect, _occluded, _intersect_line, batches,
             dm_bvh_closest_point, dm_bvh_refit.
     PART 2  Simplification with progressive-mesh records: dm_simplify, dm_pm_*, dm_weld, dm_orient.
     PART 3  Bounding shell and paper 000's constraints: dm_shell_grow, dm_shell_constraint,
             dm_shell_collapsed, dm_shell_relax (the fallback), dm_shell_fallback_triangles.
     PART 4  Parameterization, bake, surface sample grid, reconstruction: dm_parameterize, dm_bake,
             dm_reconstruct, dm_base_normals, dm_coverage_weights, dm_surface_distance.

   COMMON TO ALL PARTS
     Meshes: float xyz positions (3 per vertex), uint32 indices (3 per triangle, counter-clockwise
     front faces). Compile time: DM_STATIC (static functions), DM_MALLOC/DM_FREE (the default
     allocator; both or neither), DM_USE_SSE2 (x86), DM_USE_AVX2 (needs -mavx2; implies SSE2): SIMD
     box and triangle tests (with AVX2 also the shell constraint's nearest-triangle searches),
     bit-identical to the portable path, recommended where available. Run-time options are structs
     whose zero value (or NULL) means the defaults (dm_<call>_default_options() spells them out);
     allocating calls take a dm_allocator (NULL = DM_MALLOC/DM_FREE) that objects outliving the call
     keep for their free; long calls take a progress callback (done in [0, 1]; nonzero cancels:
     DM_CANCELLED, nothing leaked). Bad input gets a code, never a crash: NULL arrays
     (DM_ERR_INVALID_ARGUMENT), no triangles (DM_ERR_NO_TRIANGLES), an index >= vertex_count
     (DM_ERR_BAD_INDEX), a NaN, infinite or huge (|x| > 1e18) referenced coordinate
     (DM_ERR_BAD_POSITION), sizes that overflow (DM_ERR_TOO_LARGE), allocation failure
     (DM_ERR_OUT_OF_MEMORY); on failure *out is NULL and nothing is left allocated. No global state;
     calls are re-entrant and deterministic (same input, same bits; ties go to the lower index). Do
     not build with -ffast-math. FMA contraction is off in the implementation (the user's setting
     restored), except under clang's -ffp-contract=fast, which ignores that pragma (bits change).

   PART 1: BVH RAY CASTER
     WHAT. A bounding volume hierarchy with the queries a bake, picking or occlusion needs: the
     closest hit in [tmin, tmax], any hit, the nearest hit along a line either way, batches, the
     closest point on the mesh. The ray/triangle test is watertight (Woop et al. 2013): no ray
     slips between triangles through a shared edge or vertex. Degenerate triangles are never hit;
     a ray with NaN components, a zero direction or tmin > tmax misses.
         dm_bvh *bvh;  dm_bvh_build(P, nv, T, nt, NULL, &bvh);
         dm_ray ray = {{ox, oy, oz}, 0.0f, {dx, dy, dz}, INFINITY};  dm_hit hit;
         if (dm_bvh_intersect(bvh, &ray, &hit)) use(hit.t, hit.triangle, hit.u, hit.v);
         dm_bvh_free(bvh);                             // point = (1-u-v) p0 + u p1 + v p2
     METHOD. Binned SAH build (Wald 2007) of a binary tree of 32-byte nodes, collapsed into an
     8-wide tree for rays (Dammertz et al. 2008); triangles stored four to a 160-byte block;
     nearest child first; conservative box test (Ize 2013); t from the triangle's plane in double.
     OPTIONS (dm_bvh_options). quality: DM_BVH_QUALITY_DEFAULT (16 bins over the widest axis) or
     _HIGH (64 bins over three axes, a slower build); bins (0 = from quality, [4, 256]);
     max_leaf_size (0 = 8, [1, 16]); allocator (huge pages help large meshes); progress.
     MEMORY. About 120 bytes per triangle allocated, 70 touched (dm_bvh_get_info reports it);
     queries never allocate (a ray keeps a 10 KB stack).
     ERRORS. As above for dm_bvh_build and dm_bvh_refit (which needs the same triangle count).
     THREAD SAFETY. A built BVH may be queried from any number of threads; refit and free run alone.
     LIMITS. At most 2^30 - 1 triangles; coordinates up to 1e18; FMA as in COMMON.

   PART 2: SIMPLIFICATION (dm_simplify, dm_pm_*, dm_weld, dm_orient)
     WHAT. Edge collapses in order of quadric error (Garland-Heckbert 1997), recorded as a
     progressive mesh (Hoppe 1996): the base and one vertex split per collapse, so any level can
     be rebuilt exactly, up and down; for every base vertex, the input vertices merged into it. A
     constraint hook lets the caller veto or move each candidate (Part 3 uses it).
         dm_simplify_options opt = {0};  opt.target_triangles = nt / 100;
         dm_simplify(P, nv, T, nt, &opt, &pm, &report);
         dm_pm_counts(pm, &bnv, &bnt);  dm_pm_get_mesh(pm, B, BT, ids);   // level 0: the base
         dm_pm_set_level(pm, dm_pm_split_count(pm) / 2);                 // any level
     METHOD. Area-weighted quadrics (with boundary planes) in a frame centred on the bounding box,
     scaled by its largest side. The position is the quadric's minimiser when well conditioned and
     near the edge, else the best point on the edge (Lindstrom-Turk). Checks on each candidate: the
     link condition (Dey et al. 1999), no degenerate fan, no triangle turning by 78 degrees or more,
     then the constraint. Non-manifold vertices are frozen, and no collapse has one opposite its
     edge (one of its fans could fold, or two triangles coincide). A refused or vetoed edge is
     retried when its one-ring changes; one the constraint moves to more than twice its cost waits
     in the queue at the new cost.
     GUARANTEES. A manifold region stays manifold and keeps its orientation; no new degenerate or
     flipped triangle; boundaries stay on their edges; locked and frozen vertices keep their
     positions bit for bit. A collapse's error (mesh units): the area-weighted RMS distance from the new
     position to the planes merged into it (the report gives the largest). Level k is bit for bit
     the mesh after the (split_count - k)-th collapse, triangles in input order.
     dm_pm_merged_vertices gives a base vertex's sorted input vertices (a partition of them all).
     OPTIONS (dm_simplify_options). target_triangles (stop at or below; 0 none); target_error (no
     collapse above it; 0 none; neither: until no collapse passes the checks); flags
     (DM_SIMPLIFY_LOCK_BOUNDARY); locked (per vertex, nonzero = never moves or goes); max_collapses
     (0 none; the first k are the same whatever the limit); min_quality (a sliver guard: no
     collapse drops a triangle's 2 area / longest edge^2 below it while others are left; off by
     default: beside the shell it costs closeness); constraint, constraint_user, on_collapse (just
     before each collapse is applied, for a constraint that follows the mesh), relax (when no
     candidate is left above the target and some were vetoed: nonzero = less strict now, every
     vetoed edge is queued again), relax_cost (a vetoed candidate also comes back at this times its
     cost, 0 = 16, asked with dm_collapse.relaxed); allocator; progress (the share of the triangles
     to remove that are gone). dm_weld merges vertices at the same position (bit for bit, -0 = +0)
     in first-use order. dm_orient turns triangles to agree with their neighbours (the way each
     part faces: out of what it encloses, else as most of its area did); it has no options.
     MEMORY. During dm_simplify about 160 bytes per vertex and 45 per triangle plus the candidate
     queue (16 bytes an entry, about 1.5 per triangle). The progressive mesh keeps the positions,
     the triangles, about 72 bytes per split and 12 bytes per vertex. dm_weld: 8 bytes per vertex;
     dm_orient: about 80 bytes per triangle.
     ERRORS. As in COMMON; a negative or NaN target_error, a NaN min_quality or one above 0.5 is
     DM_ERR_INVALID_ARGUMENT; a triangle soup (no vertex in two triangles) with repeated positions
     is DM_ERR_NOT_WELDED. Stopping above the target still gives DM_OK (report.reached_target = 0).
     Triangles with a repeated index are dropped (counted); duplicate vertices are different
     vertices (a seam between them is two boundaries); isolated ones are in no level.
     THREAD SAFETY. dm_simplify is re-entrant. A dm_pm may be read from several threads;
     dm_pm_set_level and dm_pm_get_mesh must run alone on it.
     LIMITS. Fewer than 2^32 - 1 vertices and 1431655764 triangles, and 3 triangles + 2 vertices
     below about 4.0e9. Attributes (normals, UVs) are not simplified.

   PART 3: BOUNDING SHELL AND PAPER 000'S CONSTRAINTS
     WHAT. The base must lie outside the original (every ray that meets the displaced surface
     meets the base first) but inside a shell grown from it (Cohen et al.'s simplification
     envelopes), and each texel must get one depth (no overlap, the paper's Fig 4.1.3).
     dm_shell_grow grows the shell; dm_shell_constraint and dm_shell_collapsed keep the base in it.
     METHOD. Growth: every vertex moves out along its angle-weighted normal in `steps` steps up to
     `thickness`, and stops for good when its next offset point comes closer to the original than
     90% of what its own faces allow (less than the offset where the surface is concave): it would
     run into another part. The paper's smoothing pass is not needed. Per candidate collapse:
       1. Enclosure (the paper does not say how): the original's vertices that the collapse can
          sweep over (in the box of the old one-ring and the proposed position), whose closest
          feature of the old one-ring touches keep or remove, stay on the inner side of the new
          one-ring (signed distance with the angle-weighted pseudonormal, Baerentzen-Aanaes 2005).
          Each asks keep to lie outside one plane; the proposed position is projected on those
          half-spaces exactly (a dual active set, in the metric of the collapse's quadric plus its
          mean eigenvalue: where the error grows least, without sliding along flat parts) and
          checked again (DM_COLLAPSE_MOVE; a veto where no position meets them all, whose proof,
          at most four planes, is tried first on the edge's next time). It encloses the original,
          not the previous level (Sander et al.'s progressive hulls): offsets do not pile up.
       2. Shell: keep within the offset grown at its closest point of the original; along each
          ray of 3., the depth to the original no more than the offset grown at the hit.
       3. Overlap: from overlap_samples points of each new triangle and the middle and quarter
          points of its edge from keep, a ray along the inverted interpolated normal (started a
          quarter thickness outside) must meet a front face of the original first, within 2.25
          thicknesses, and not go out and in again within that depth. The normals are the mesh's
          angle-weighted ones after the collapse (dm_shell_collapsed keeps their sums), not the
          bake's turned ones (BASE NORMALS), which differ at a few crease vertices. A miss is a
          violation unless the original is open and the sample lies within 0.05 thickness of it
          (beside its boundary: a base reaching farther out overhangs it).
     The checks are sampled: a fold can hide between a triangle's samples. Asked with
     placement_only, the constraint answers after 1 (DM_COLLAPSE_PLACED).
     FALLBACK. Where the shell is too thin for an enclosing base (thin limbs, horns, narrow gaps)
     the constraint vetoes. With opt.relax = dm_shell_relax a vetoed candidate comes back at
     relax_cost (16) times its cost, asked relaxed (relaxing only once all are stuck leaves knots of
     small triangles): it passes when, from each overlap sample, the nearest crossing of the
     original either way within the thickness faces the way the base does (a bake both ways finds
     one depth) and no vertex of the original ends a quarter thickness farther outside (tips stay
     in reach), keep where the enclosure put it if that passes. Still above the target, dm_simplify
     relaxes it everywhere, then to its own checks. Bake dm_shell_fallback_triangles both ways.
     OPTIONS (dm_shell_options). thickness (0 = 2% of the bounding-box diagonal); steps (0 = 8);
     overlap_samples (0 = 4, at most 7); allocator; progress. A shell serves any number of
     dm_simplify runs, one at a time (a candidate at level 0 after collapses starts again).
     MEMORY. About 68 bytes per original vertex and 24 per triangle, a copy of the original, its
     BVH and its face normals; while dm_shell_grow runs, about 100 per fragment besides; the
     constraint 100 per original vertex near the widest candidate, 340 per triangle of the widest
     one-ring, 32 KB of kept proofs.
     ERRORS. dm_shell_grow as in COMMON; the constraint vetoes what it cannot check.
     THREAD SAFETY. One dm_simplify run at a time per shell.
     LIMITS. As Part 2; the constraint needs on_collapse = dm_shell_collapsed for the mesh's own
     vertex normals (else from the one-ring). The overlap is checked on the new one-ring only: a
     later collapse that turns a triangle's corner normals can make its texels miss.

   PART 4: PARAMETERIZATION, BAKE, SURFACE SAMPLE GRID, RECONSTRUCTION
     WHAT. A base mesh laid out in one width x height map, the displacement and the original's
     normals baked into it, the surface sample grid other headers filter on, the dense mesh again.
     PARAMETERIZATION. Disk charts grow breadth first (within max_chart_angle of the chart's mean
     normal, up to max_chart_triangles). A chart's boundary is its projection on the chart's plane
     (or a circle by arc length), its inside Floater's mean value map, then Yoshizawa-Belyaev-Seidel
     stretch rounds toward area targets (triangle_weight, default the areas; dm_coverage_weights
     gives the original's area over each base triangle; a sliver's is cut so that, scaled to it, its
     longest edge spans at most the side of the total's square) while the stretch drops and nothing
     flips; a chart that curls (no flip-free layout within L2 stretch 2) is cut in two, down to lone
     triangles. Charts turned to their smallest box (12 angles) are packed at the largest scale that
     fits: shelves of boxes, or footprints in a bitmap (largest first, best quarter turn). dm_param
     reports utilization, L2 and max stretch (Sander et al. 2001) and the share of area ratios in
     [0.8, 1.25]. Deviation: many charts with seams, not the paper's one global chart (its text
     omits the cut); neighbour lookups go through nbr.
     BAKE. For each texel whose centre lies in a base triangle (the first in index order on a shared
     edge), base point p and interpolated base normal n: the line p - t n, |t| <= max_distance
     (default 5% of the original's diagonal), gives disp = t (world units, positive inward) and the
     original's interpolated normal at the hit: with inward the first hit along -n (the paper's
     rule) unless a back face (p lies inside), else and on both_ways triangles the nearest crossing
     either way. No crossing, or a depth 8 texel sizes beyond most chart neighbours within 2 texels
     (a ray that slipped past a thin part), is DM_TEXEL_MISS (valid = 0). Gutter texels within 2
     texels of a chart (DM_TEXEL_BORDER) extend the nearest triangle's plane (the chart's field
     where that ray meets a crease or lands 8 texel sizes off), for filtering and the first mip
     level, fitted (least squares) so that a chart's bilinear read along its boundary gives the
     edge point's own ray's depth: the charts on a seam read one depth there (on a crease of the
     original each keeps its own face). MISS and EMPTY texels get push-pull values for filtering.
     BASE NORMALS (dm_base_normals, the bake's and the reconstruction's): angle-weighted, except
     where a vertex sees one of its triangles beyond 60 degrees (a short wall by a wide flat part,
     whose lines would run along it and fold): there it turns toward the axis of its triangles'
     smallest normal cone, just enough to see each within 60 degrees, at most 30 degrees.
     Deviation: the paper names only "the interpolated vertex normal".
     SURFACE SAMPLE GRID. dm_dispmap holds per texel pos, nrm, disp, area (the base area it stands
     for: sums are areas), valid, and nbr/nbr_rot in the order +x, -x, +y, -y (the dm_param's
     arrays, shared: free the dm_dispmap first). Inside a chart nbr is the adjacent texel (rot 0);
     across a seam, the texel nearest where the centre lands, carried over the nearest chart edge
     into the twin triangle's chart; UINT32_MAX at the mesh's boundary. nbr_rot = r: a step
     along d continues as d turned r quarter turns counter-clockwise in the neighbour's axes; a step
     back along -(d turned r) lands where it started. Where one texel cannot serve two charts
     (corners), nbr is the texel itself with a half turn (a mirror, as a clamped filter sees it).
     RECONSTRUCTION. Each base triangle is tessellated as a GPU tessellator does (a barycentric grid
     of level sqrt(2 x its uv area in texels), as many points on each base edge as its longer uv
     side has texels, shared across the edge, strips between), made Delaunay in the map by edge
     flips, then flipped where the map's depth at the other diagonal's midpoint lies nearer the mean
     of its ends (a squared gap a fifth smaller, no triangle under 0.3 in 2 area / longest edge^2),
     so that creases are cut along. A vertex is its base point moved along the base normal by the
     map's bilinear depth, averaged over the triangles sharing it, with the map's normal (shade with
     those: geometric normals show the original's facets). A closed manifold base gives a closed
     manifold result with no T-junction. Vertex v < base_vertex_count is base vertex v; face_base
     gives each triangle's base triangle. dm_surface_distance samples both meshes area-uniformly
     (deterministic) and measures with dm_bvh_closest_point; its max also covers every vertex.
     OPTIONS. dm_param_options: width, height (0 = 1024, at most 16384), gutter (0 = 4),
     triangle_weight, max_chart_triangles (0 = 96), max_chart_angle (0 = 30 degrees),
     stretch_iterations (0 = 6, negative none, at most 1000). dm_bake_options: max_distance, inward,
     both_ways. dm_reconstruct_options: density (micro-edges per texel, 0 = 1), depth_flips (0 = on,
     negative = off). dm_coverage_options: floor (0 = 5% of the mean weight). dm_distance_options:
     samples_per_side (0 = 200000, at most 10^9). Each also has allocator and progress.
     MEMORY. dm_param: 32 bytes per texel and 24 per base triangle (2 more per texel while
     packing); dm_dispmap: 46 bytes per texel (42 more while dm_bake runs) plus a BVH of the
     original; dm_trimesh: 24 bytes per vertex and 16 per triangle (2 triangles per covered texel);
     while dm_reconstruct runs, 60 per vertex and 183 per triangle of the largest tessellation.
     ERRORS. As in COMMON, for every mesh argument; DM_ERR_MAP_TOO_SMALL when the charts with their
     gutters do not fit the map at any scale. dm_bake and dm_reconstruct check the public dm_param
     and dm_dispmap arrays they read (a caller may have edited them): an index out of range, a
     missing array, or a NaN or infinite value (a depth beyond 1e18) is DM_ERR_BAD_MAP.
     THREAD SAFETY. Results are read-only once made; the calls are re-entrant.
     LIMITS. Maps up to 16384 x 16384; a reconstruction below 2^32 vertices (DM_ERR_TOO_LARGE), at
     most 1024 segments along one base edge. Where no direction sees all of a base vertex's
     triangles (a thin part's rim at a coarse level) the normal lines fold: a few reconstructed
     triangles there face backwards (not repaired).

   REFERENCES
     Woop, Benthin, Wald, Watertight ray/triangle intersection, JCGT 2013. Wald, SAH-based BVH
     construction, RT 2007. Ize, Robust BVH ray traversal, JCGT 2013. Ericson, Real-Time Collision
     Detection 5.1.5, 2005. Bikker, tinybvh, 2024. Dammertz, Hanika, Keller, Shallow BVHs for SIMD
     ray tracing, EGSR 2008. Garland, Heckbert, Quadric error metrics, SIGGRAPH 1997. Hoppe,
     Progressive meshes, SIGGRAPH 1996. Dey et al., Topology preserving edge contraction, 1999.
     Lindstrom, Turk, Fast and memory efficient simplification, Vis 1998. Cohen et al.,
     Simplification envelopes, SIGGRAPH 1996. Sander et al., Silhouette clipping (progressive
     hulls), SIGGRAPH 2000. Baerentzen, Aanaes, Angle weighted pseudonormal, TVCG 2005. Floater,
     Mean value coordinates, CAGD 2003. Yoshizawa, Belyaev, Seidel, Stretch-minimizing
     parameterization, SMI 2004. Sander et al., Texture mapping progressive meshes, SIGGRAPH 2001.
     Gortler et al., The Lumigraph (push-pull), SIGGRAPH 1996. Thurmer, Wuthrich, Vertex normals
     from polygonal facets, JGT 1998. Dyn, Levin, Rippa, Data dependent triangulations, IMA J.
     Numer. Anal. 1990. Jiang et al., Bijective projection in a shell, TOG 2020. Goldfarb, Idnani,
     A dual method for strictly convex quadratic programs, Math. Prog. 1983. */
#ifndef DM_DISPMESH_H
#define DM_DISPMESH_H

#include <stddef.h>
#include <stdint.h>

#ifdef DM_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define DMDEF static __attribute__((unused)) /* no warning for the functions you do not call */
#else
#define DMDEF static
#endif
#else
#define DMDEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum dm_result {
    DM_OK = 0,
    DM_ERR_INVALID_ARGUMENT, /* NULL pointer where an array is needed, or mismatched counts */
    DM_ERR_NO_TRIANGLES,     /* triangle_count is 0 */
    DM_ERR_BAD_INDEX,        /* an index is >= vertex_count */
    DM_ERR_BAD_POSITION,     /* a referenced coordinate is NaN, infinite or beyond 1e18 */
    DM_ERR_TOO_LARGE,        /* a byte size overflows size_t, or counts exceed the 32-bit ids */
    DM_ERR_OUT_OF_MEMORY,    /* the allocator returned NULL */
    DM_CANCELLED,            /* the progress callback returned nonzero */
    DM_ERR_MAP_TOO_SMALL,    /* dm_parameterize: the charts and gutters do not fit the map */
    DM_ERR_NOT_WELDED,       /* dm_simplify: a triangle soup (no vertex shared by two triangles,
                                positions repeated): weld it first (dm_weld) */
    DM_ERR_BAD_MAP           /* dm_bake, dm_reconstruct: a dm_param or dm_dispmap array holds an
                                index out of range, a NaN or infinite value, or is missing */
} dm_result;

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct dm_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} dm_allocator;

/* ---- BVH ray caster ------------------------------------------------------------------------ */

enum { DM_BVH_QUALITY_DEFAULT = 0, DM_BVH_QUALITY_HIGH = 1 };

typedef struct dm_bvh_options {
    int quality;                            /* DM_BVH_QUALITY_DEFAULT (0) or DM_BVH_QUALITY_HIGH */
    int bins;                               /* SAH bins per axis; 0 = 16 (64 for HIGH) */
    int max_leaf_size;                      /* 0 = 8 */
    const dm_allocator *allocator;          /* NULL = DM_MALLOC/DM_FREE */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} dm_bvh_options;                           /* zero = defaults */

typedef struct dm_bvh dm_bvh; /* opaque */

/* A ray o + t d, t in [tmin, tmax]. d need not be unit length (t is then in units of |d|). */
typedef struct dm_ray {
    float org[3];
    float tmin;
    float dir[3];
    float tmax;
} dm_ray;

#define DM_NO_HIT 0xffffffffu

/* A hit: point = (1-u-v) p0 + u p1 + v p2 of triangle (p0, p1, p2 in index order). On a miss
   triangle is DM_NO_HIT and t, u, v are 0. */
typedef struct dm_hit {
    float t, u, v;
    uint32_t triangle;
} dm_hit;

/* The closest point of the mesh: point = (1-u-v) p0 + u p1 + v p2 of triangle. */
typedef struct dm_closest {
    float point[3];
    float distance;
    float u, v;
    uint32_t triangle; /* DM_NO_HIT when nothing lies within max_distance */
} dm_closest;

typedef struct dm_bvh_info {
    size_t triangle_count;
    size_t node_count;   /* nodes in use (one slot after the root is padding and not counted) */
    size_t leaf_count;
    size_t max_depth;    /* root = 0 */
    size_t memory_bytes; /* everything the BVH holds, allocation padding included */
    double sah_cost;     /* SAH cost with traversal 1 and triangle 1, relative to the root box */
} dm_bvh_info;

/* The options with every zero field replaced by the value it stands for. */
DMDEF dm_bvh_options dm_bvh_default_options(void);

/* Builds a BVH over a triangle mesh.
   positions       3 floats per vertex; only vertices referenced by indices are read.
   vertex_count    number of vertices; every index must be smaller.
   indices         3 per triangle. Neither array is referenced after the call.
   triangle_count  at least 1.
   options         NULL or zeroed for defaults.
   out             receives the BVH, or NULL on failure. Must not be NULL. */
DMDEF dm_result dm_bvh_build(const float *positions, size_t vertex_count, const uint32_t *indices,
                             size_t triangle_count, const dm_bvh_options *options, dm_bvh **out);

/* Frees a BVH with the allocator it was built with. NULL is allowed. */
DMDEF void dm_bvh_free(dm_bvh *bvh);

/* Updates the BVH after vertices moved: the same indices (same triangle_count as the build),
   new positions. The tree topology is kept; boxes are recomputed bottom-up. On an error
   (bad index or position) the BVH is left unchanged. Rays cast after a large deformation stay
   correct, only slower; rebuild then. */
DMDEF dm_result dm_bvh_refit(dm_bvh *bvh, const float *positions, size_t vertex_count,
                             const uint32_t *indices, size_t triangle_count);

/* Node count, depth, memory used and SAH cost. */
DMDEF void dm_bvh_get_info(const dm_bvh *bvh, dm_bvh_info *info);

/* Nearest hit with tmin <= t <= tmax. Returns 1 and fills *hit, or 0 (hit->triangle =
   DM_NO_HIT). Both faces of a triangle are hit. */
DMDEF int dm_bvh_intersect(const dm_bvh *bvh, const dm_ray *ray, dm_hit *hit);

/* 1 if any triangle is hit with tmin <= t <= tmax (occlusion), else 0. */
DMDEF int dm_bvh_occluded(const dm_bvh *bvh, const dm_ray *ray);

/* The hit with the smallest |t| on the whole line o + t d for t in [tmin, tmax]; tmin may be
   negative (for a bake: tmin = -tmax looks both ways). hit->t is signed. Returns 1 or 0. On
   equal |t| the lower triangle index wins, then the forward hit. */
DMDEF int dm_bvh_intersect_line(const dm_bvh *bvh, const dm_ray *ray, dm_hit *hit);

/* dm_bvh_intersect for count rays; returns the number of hits. */
DMDEF size_t dm_bvh_intersect_batch(const dm_bvh *bvh, const dm_ray *rays, size_t count, dm_hit *hits);

/* dm_bvh_occluded for count rays into occluded[i] (0 or 1); returns the number occluded. */
DMDEF size_t dm_bvh_occluded_batch(const dm_bvh *bvh, const dm_ray *rays, size_t count,
                                   unsigned char *occluded);

/* The closest point on the mesh to point, within max_distance (INFINITY for no limit).
   Returns 1 and fills *out, or 0 (out->triangle = DM_NO_HIT). */
DMDEF int dm_bvh_closest_point(const dm_bvh *bvh, const float point[3], float max_distance,
                               dm_closest *out);

/* ---- Part 3: parameterization, displacement bake, surface sample grid, reconstruction ------- */

/* Texel status in a dm_dispmap. */
enum { DM_TEXEL_EMPTY = 0, DM_TEXEL_HIT = 1, DM_TEXEL_MISS = 2, DM_TEXEL_BORDER = 3 };

typedef struct dm_param_options {
    int width, height;            /* map size in texels; 0 = 1024 each; at most 16384 */
    int gutter;                   /* empty texels between charts (at least); 0 = 4: bilinear
                                     filtering and one mip level read no other chart */
    const float *triangle_weight; /* NULL = each base triangle's own area; else one weight >= 0
                                     per base triangle: its map area is proportional to it */
    int max_chart_triangles;      /* 0 = 96; clamped to [1, 256] */
    float max_chart_angle;        /* largest angle (degrees) between a triangle's normal and its
                                     chart's mean normal; 0 = 30 */
    int stretch_iterations;       /* Yoshizawa-Belyaev-Seidel rounds; 0 = 6, negative = none, at most 1000 */
    const dm_allocator *allocator; /* NULL = DM_MALLOC/DM_FREE; kept in the dm_param */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} dm_param_options;                /* zero = defaults */
DMDEF dm_param_options dm_param_default_options(void);

/* A base mesh laid out in one map. Texel (x, y) has its centre at UV ((x+0.5)/width,
   (y+0.5)/height); uv[6 t + 2 c] is corner c of base triangle t (0..1). */
typedef struct dm_param {
    dm_allocator allocator;
    int width, height;
    size_t triangle_count;     /* base triangles */
    size_t chart_count;
    float *uv;                 /* 6 per triangle */
    uint32_t *chart;           /* chart of each triangle */
    uint32_t *twin;            /* 3 per triangle: triangle across edge c (corner c to c+1), or
                                  DM_NO_HIT on a boundary or non-manifold edge */
    uint32_t *texel_triangle;  /* width*height: the base triangle under the texel centre, or
                                  DM_NO_HIT (gutter) */
    float *texel_bary;         /* 2 per texel: (u, v), point = (1-u-v) p0 + u p1 + v p2 */
    uint32_t *nbr;             /* 4 per texel (+x, -x, +y, -y), across seams; UINT32_MAX none */
    uint8_t *nbr_rot;          /* 4 per texel: quarter turns counter-clockwise that carry this
                                  texel's axes onto the neighbour's (see "SURFACE SAMPLE GRID") */
    float utilization;         /* texels under a triangle / all texels */
    float stretch_l2;          /* Sander's L2 stretch of the whole map against the target areas
                                  (1 = every triangle its target shape-free area, isotropic) */
    float stretch_max;         /* largest per-triangle L2 stretch against its target (both stretches
                                  leave out triangles of zero area) */
    float area_ratio_ok;       /* fraction of triangles whose map-area / weight, over the mean,
                                  lies in [0.8, 1.25] */
} dm_param;

typedef struct dm_bake_options {
    float max_distance;        /* search both ways along the line up to this far; 0 = 5% of the
                                  original's bounding-box diagonal. For a base made under
                                  dm_shell_constraint, 1.5 x the shell's thickness: the base lies
                                  within the shell, so a deeper hit is a ray that slipped past a
                                  thin part of the original to another sheet */
    int inward;                /* nonzero: the paper's rule, the first hit along -n (t from
                                  -max_distance / 10, where a base triangle grazes the original,
                                  up to max_distance), then, if none or a back face, the nearest
                                  either way; for a base that encloses the original
                                  (dm_shell_constraint). 0: the nearest either way */
    const uint8_t *both_ways;  /* NULL, or per base triangle: nonzero = the nearest crossing either
                                  way even when inward is set (the signed region of a relaxed
                                  shell constraint: dm_shell_fallback_triangles) */
    const dm_allocator *allocator; /* NULL = DM_MALLOC/DM_FREE; kept in the dm_dispmap */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} dm_bake_options;             /* zero = defaults */
DMDEF dm_bake_options dm_bake_default_options(void);

/* The baked map and the surface sample grid of DESIGN.md, structure of arrays over n = width *
   height texels. pos, nrm, area, nbr, nbr_rot are the grid; disp and normal the paper's
   4-channel map. Texels that are EMPTY (gutter) or MISS have push-pull filled disp and normal
   (for filtering) and valid = 0. */
typedef struct dm_dispmap {
    dm_allocator allocator;
    int width, height;
    float *pos;                /* 3 per texel: base-surface point (0 for EMPTY) */
    float *nrm;                /* 3 per texel: interpolated base normal, unit (0 for EMPTY) */
    float *disp;               /* depth along -nrm, world units, positive inward */
    float *normal;             /* 3 per texel: original's normal at the hit, object space, unit */
    float *area;               /* surface area of the base the texel stands for (0 for EMPTY) */
    uint8_t *valid;            /* 1 = HIT */
    uint8_t *status;           /* DM_TEXEL_EMPTY / HIT / MISS / BORDER (gutter, baked for filtering) */
    const uint32_t *nbr;       /* the dm_param's neighbours (not a copy: keep the dm_param alive) */
    const uint8_t *nbr_rot;
    size_t hit_count, miss_count;
    size_t border_count;       /* BORDER texels: gutter texels near a chart, baked (valid = 0) */
    float max_distance;        /* the search distance used */
} dm_dispmap;

/* A mesh made by this header (reconstruction). Free with dm_trimesh_free. */
typedef struct dm_trimesh {
    dm_allocator allocator;
    float *positions;
    float *normals;            /* 3 per vertex, unit: the map's normals */
    size_t vertex_count;
    uint32_t *indices;
    uint32_t *face_base;       /* per triangle: the base triangle it tessellates */
    size_t triangle_count;
} dm_trimesh;

/* Sampled symmetric surface distance between meshes A and B, as fractions of A's bounding-box
   diagonal (also given). */
typedef struct dm_distance_report {
    double rms, max;           /* over both directions' samples (and, for max, all vertices) */
    double rms_a_to_b, max_a_to_b, rms_b_to_a, max_b_to_a;
    double diagonal;           /* A's bounding-box diagonal, world units */
    size_t samples;            /* per side */
} dm_distance_report;

/* Cuts the base mesh into disk-shaped charts, lays each out (Floater's mean value coordinates,
   then Yoshizawa-Belyaev-Seidel stretch rounds against area-proportional targets), packs them
   with gutters into one width x height map, and finds each texel's triangle and neighbours.
   positions/vertex_count/indices/triangle_count: the base mesh (as dm_bvh_build).
   options   NULL or zeroed for defaults.  out receives the result or NULL on failure. */
DMDEF dm_result dm_parameterize(const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, const dm_param_options *options, dm_param **out);
DMDEF void dm_param_free(dm_param *param);

/* Bakes the displacement map: for every texel under a base triangle, the base point p and the
   interpolated (renormalised) base normal n of dm_base_normals; the line p - t n meets the original
   mesh at the smallest |t| within max_distance; disp = t (positive inward), normal = the
   original's interpolated vertex normal there. Misses are flagged and push-pull filled.
   param     from dm_parameterize on the same base mesh.
   base_*    the base mesh; orig_* the original (dense) mesh. */
DMDEF dm_result dm_bake(const dm_param *param, const float *base_positions, size_t base_vertex_count,
                        const uint32_t *base_indices, size_t base_triangle_count,
                        const float *orig_positions, size_t orig_vertex_count,
                        const uint32_t *orig_indices, size_t orig_triangle_count,
                        const dm_bake_options *options, dm_dispmap **out);
DMDEF void dm_dispmap_free(dm_dispmap *map);

/* The directions dm_bake and dm_reconstruct displace the base along (a renderer that displaces
   the base by the map itself needs the same): per base vertex, unit, into normals[3 vertex_count]
   (zero for a vertex no triangle uses). The rule: BASE NORMALS in the doc block. Takes about 24
   bytes per vertex while it runs, and 4 per vertex and 12 per triangle more where a vertex turns. */
DMDEF dm_result dm_base_normals(const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, const dm_allocator *allocator, float *normals);

typedef struct dm_reconstruct_options {
    float density;             /* micro-edges per texel along each base edge; 0 = 1, at most 16 */
    int depth_flips;           /* 0 = on; negative = off: the tessellation is only made
                                  Delaunay in the map (RECONSTRUCTION above) */
    const dm_allocator *allocator; /* NULL = DM_MALLOC/DM_FREE; kept in the dm_trimesh */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} dm_reconstruct_options;      /* zero = defaults */
DMDEF dm_reconstruct_options dm_reconstruct_default_options(void);

/* The dense mesh base + map: every base triangle tessellated at the map's resolution (a
   barycentric grid inside, its edges' points shared with the triangles across them), each
   vertex at its base point moved along the base normal by the map's bilinear depth (averaged
   over the triangles that share it), with the map's normal. Vertex v < base_vertex_count is
   base vertex v. The base mesh is the one given to dm_parameterize and dm_bake. */
DMDEF dm_result dm_reconstruct(const dm_dispmap *map, const dm_param *param, const float *base_positions,
                               size_t base_vertex_count, const uint32_t *base_indices, size_t base_triangle_count,
                               const dm_reconstruct_options *options, dm_trimesh **out);
DMDEF void dm_trimesh_free(dm_trimesh *mesh);

/* Symmetric distance: samples_per_side area-uniform (deterministic) points on each mesh, each
   measured to the other with dm_bvh_closest_point, and every vertex (for the max). options NULL =
   all defaults. progress gets the fraction of the closest-point queries done, about every 4096
   of them and at the end; nonzero cancels (DM_CANCELLED, *out zeroed). Each search is bounded by
   the previous point's answer, and a vertex is searched only when it could raise the max. A
   35k-vertex mesh against a 1.4M-triangle one at 200000 samples a side takes about 2 s. */
typedef struct dm_distance_options {
    size_t samples_per_side;          /* 0 = 200000; at most 10^9 (more is DM_ERR_INVALID_ARGUMENT) */
    const dm_allocator *allocator;    /* NULL = malloc/free */
    int (*progress)(void *user, float done);
    void *progress_user;
} dm_distance_options;
DMDEF dm_distance_options dm_distance_default_options(void);
DMDEF dm_result dm_surface_distance(const float *a_positions, size_t a_vertex_count,
                                    const uint32_t *a_indices, size_t a_triangle_count,
                                    const float *b_positions, size_t b_vertex_count,
                                    const uint32_t *b_indices, size_t b_triangle_count,
                                    const dm_distance_options *options, dm_distance_report *out);

/* Area-proportional weights for dm_param_options.triangle_weight: per base triangle, the area of
   the original that lies over it (each original triangle's area goes to the base triangle
   closest to its centroid), so that the map spends its texels where the original's surface
   is. A base triangle with almost nothing over it still gets a floor (5% of the mean weight
   by default), so that every base triangle keeps texels. weights: base_triangle_count floats,
   written on success. options NULL = all defaults. */
typedef struct dm_coverage_options {
    const dm_allocator *allocator;    /* NULL = malloc/free */
    int (*progress)(void *user, float done); /* fraction of the original's triangles placed, about
                                                every 16384 and at the end; nonzero cancels */
    void *progress_user;
    float floor;                      /* the least weight, a fraction of the mean: 0 = 0.05 */
} dm_coverage_options;
DMDEF dm_coverage_options dm_coverage_default_options(void);
DMDEF dm_result dm_coverage_weights(const float *base_positions, size_t base_vertex_count,
                                    const uint32_t *base_indices, size_t base_triangle_count,
                                    const float *orig_positions, size_t orig_vertex_count,
                                    const uint32_t *orig_indices, size_t orig_triangle_count,
                                    const dm_coverage_options *options, float *weights);

/* "DM_OK", "DM_ERR_BAD_INDEX", ... (the enum name); "DM_ERR_?" outside the enum. */
DMDEF const char *dm_result_string(dm_result r);

/* ---- QEM simplification with progressive-mesh records (part 2) ---------------------------- */

/* dm_simplify_options.flags */
#define DM_SIMPLIFY_LOCK_BOUNDARY 1u /* boundary vertices never move and are never removed */

/* What a constraint returns for a candidate collapse. */
enum { DM_COLLAPSE_ALLOW = 0, DM_COLLAPSE_VETO = 1, DM_COLLAPSE_MOVE = 2, DM_COLLAPSE_PLACED = 3 };

/* A candidate collapse, as the constraint sees it. Vertex ids are the input's. */
typedef struct dm_collapse {
    uint32_t keep;             /* the vertex that stays */
    uint32_t remove;           /* the vertex merged into keep */
    float position[3];         /* proposed position of keep after the collapse */
    double error;              /* the collapse's error at that position (mesh units, see PART 2) */
    const float *positions;    /* current positions, 3 per input vertex; keep's entry is still the old one */
    const uint32_t *triangles; /* 3 per triangle: keep's one-ring after the collapse (remove replaced by
                                  keep, keep at `position`, every other vertex at positions[3 * id]) */
    size_t triangle_count;
    const uint32_t *old_triangles; /* 3 per triangle: the triangles of keep and remove before the
                                      collapse (the dying ones included), at `positions` */
    size_t old_triangle_count;
    size_t level;              /* collapses done before this one in this dm_simplify run: 0 until
                                  the first is done, so a constraint that follows the mesh (like
                                  dm_shell_constraint) sees a new run begin */
    double metric[6];          /* how the error grows away from position: as (x - position)^T M
                                  (x - position), up to a scale, M = (m00 m01 m02 m11 m12 m22), the
                                  summed quadrics' matrix; all 0: as the plain distance does */
    int relaxed;               /* 1: a candidate the constraint vetoed, queued again at relax_cost
                                  times its cost (dm_simplify_options): the simplifier asks for the
                                  check relax() would give, for this candidate alone; else 0 */
    int placement_only;        /* 1: only where keep would go is asked for. The constraint may
                                  answer DM_COLLAPSE_PLACED with that place in corrected[] before
                                  making the checks that do not move keep: the simplifier then
                                  either queues the candidate again at the cost there or asks
                                  again, in full, with the same candidate (placement_only 0) */
} dm_collapse;

/* Returns DM_COLLAPSE_ALLOW, DM_COLLAPSE_VETO, or DM_COLLAPSE_MOVE after writing a corrected position
   into corrected[3] (checked again for flips and degenerate triangles; vetoed if it fails); or,
   only when candidate->placement_only, DM_COLLAPSE_PLACED (see dm_collapse). */
typedef int (*dm_collapse_constraint)(void *user, const dm_collapse *candidate, float corrected[3]);

typedef struct dm_simplify_options {
    size_t target_triangles;          /* stop at or below this many triangles; 0 = no count target */
    double target_error;              /* never do a collapse whose error exceeds this (mesh units);
                                         0 = no error bound */
    unsigned flags;                   /* DM_SIMPLIFY_LOCK_BOUNDARY */
    const uint8_t *locked;            /* NULL, or one byte per vertex: nonzero = never moved or removed */
    size_t max_collapses;             /* 0 = no limit; stop after this many collapses */
    float min_quality;                /* 0 (or less) = no guard; else a collapse may not make a
                                         triangle's 2 area / longest edge^2 fall below this and below
                                         what it was (equilateral 0.87; 0.1 allows no angle above
                                         about 157 degrees), until nothing else is left above the
                                         target; at most 0.5 */
    dm_collapse_constraint constraint; /* NULL, or called for each candidate that passed every check */
    void *constraint_user;
    void (*on_collapse)(void *user, const dm_collapse *done); /* NULL, or called with constraint_user
                                         once a collapse is decided, just before it is applied:
                                         position = where keep goes, positions still the old ones */
    int (*relax)(void *user);         /* NULL, or called with constraint_user when no candidate is
                                         left above target_triangles and some were vetoed: nonzero
                                         = the constraint is now less strict, and every vetoed or
                                         refused edge is queued again (dm_shell_relax) */
    double relax_cost;                /* with relax: a candidate the constraint vetoes is queued again
                                         at this many times its cost and then asked relaxed
                                         (dm_collapse.relaxed), so that the fallback takes the
                                         collapses much cheaper than the strict ones left, not only
                                         those left once every candidate is stuck; 0 = 16; < 0 = no
                                         such retries */
    const dm_allocator *allocator;    /* NULL = DM_MALLOC/DM_FREE; kept in the result for dm_pm_free */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} dm_simplify_options;                /* zero = simplify as far as the checks allow */
DMDEF dm_simplify_options dm_simplify_default_options(void);

typedef struct dm_simplify_report {
    size_t input_triangles;       /* triangles taken from the input (repeated-index ones dropped) */
    size_t dropped_triangles;     /* triangles with a repeated index, in no level */
    size_t triangle_count;        /* triangles reached */
    size_t vertex_count;          /* vertices the reached triangles use */
    size_t collapse_count;        /* collapses done = vertex splits recorded */
    size_t rejected;              /* candidates refused by the link, flip or degeneracy checks */
    size_t vetoed;                /* candidates vetoed by the constraint */
    size_t relaxed;               /* times the constraint was relaxed (options.relax) */
    size_t frozen_vertices;       /* vertices left alone because they are non-manifold (their
                                     triangles make no single consistently oriented fan: where
                                     they only disagree in orientation, dm_orient mends that) */
    double error;                 /* largest error of a collapse done (mesh units), 0 if none */
    int reached_target;           /* 1 when target_triangles (if set) was reached */
} dm_simplify_report;

typedef struct dm_pm dm_pm; /* opaque: a progressive mesh */

/* One vertex split (Hoppe 1996), the inverse of one collapse. */
typedef struct dm_vsplit {
    uint32_t keep;            /* the vertex that splits */
    uint32_t remove;          /* the vertex it gives back */
    float keep_position[3];   /* keep's position after the split (before the collapse) */
    float merged_position[3]; /* keep's position before the split (after the collapse) */
    size_t restored_triangles; /* triangles the split brings back (2 inside, 1 on a boundary) */
    size_t moved_corners;     /* triangle corners that go from keep back to remove */
} dm_vsplit;

/* Simplifies a triangle mesh by quadric-error edge collapses and records them as a progressive
   mesh. positions/vertex_count/indices/triangle_count as for dm_bvh_build (not referenced after
   the call). options NULL or zeroed: no target, simplify until no collapse passes the checks.
   On DM_OK *out holds the progressive mesh at its base level (the simplified mesh); report (may
   be NULL) says what was reached. Vetoes or checks that stop above the target still give DM_OK. */
DMDEF dm_result dm_simplify(const float *positions, size_t vertex_count, const uint32_t *indices,
                            size_t triangle_count, const dm_simplify_options *options, dm_pm **out,
                            dm_simplify_report *report);

/* Frees a progressive mesh (NULL is fine) with the allocator it was made with. */
DMDEF void dm_pm_free(dm_pm *pm);

/* Welds a mesh whose triangles do not share vertices (an STL file, a triangle soup): vertices at
   the same position (bit for bit, -0 = +0) become one, numbered in the order the indices first
   use them; unreferenced vertices are dropped. out_positions holds 3 * vertex_count floats and
   out_indices 3 * triangle_count (caller-owned; they may not alias the input); *out_vertex_count
   receives the welded count. A mesh already welded comes back renumbered in first-use order, so
   welding a soup made from a mesh gives that mesh renumbered in first-use order, bit for bit.
   allocator NULL = default (a hash table of 8 bytes per vertex while it runs). Errors as for
   dm_bvh_build (NULL arrays, bad index, bad position of a referenced vertex, sizes). */
DMDEF dm_result dm_weld(const float *positions, size_t vertex_count, const uint32_t *indices,
                        size_t triangle_count, const dm_allocator *allocator, float *out_positions,
                        uint32_t *out_indices, size_t *out_vertex_count);

/* Turns triangles (a, b, c) -> (a, c, b) in place so that across every edge that exactly two
   triangles share they run it in opposite directions (a consistently oriented surface), where
   the surface allows it (a Moebius band keeps one seam), and then picks the way each connected
   part faces. A closed part faces out of the volume it encloses, or into it when it lies inside
   an odd number of other closed parts (a cavity's wall), so a mesh wound clockwise is turned
   too; a consistent closed part that faces out already is left as it is. A consistent open part
   is left as it is; another faces out of what it clearly encloses (a bowl), else the way most
   of its area faced. *turned (may be NULL) receives the number of triangles turned. Cost: a sort
   of the edges, and for each closed part that may turn a box test against the other closed
   parts and one ray against those whose box holds its own. allocator NULL = default (about 80
   bytes per triangle while it runs). Errors as for dm_weld; on an error indices are unchanged. */
DMDEF dm_result dm_orient(const float *positions, size_t vertex_count, uint32_t *indices,
                          size_t triangle_count, const dm_allocator *allocator, size_t *turned);

/* Number of vertex splits (= collapses done). Levels run from 0 (base) to this (the input). */
DMDEF size_t dm_pm_split_count(const dm_pm *pm);

/* The current level. */
DMDEF size_t dm_pm_level(const dm_pm *pm);

/* Moves to a level by applying vertex splits (up) or collapses (down); levels above
   dm_pm_split_count() are clamped. Level k is exactly the simplifier's mesh after its
   (split_count - k)-th collapse. Never allocates. */
DMDEF void dm_pm_set_level(dm_pm *pm, size_t level);

/* Vertex and triangle counts of the current level. */
DMDEF void dm_pm_counts(const dm_pm *pm, size_t *vertex_count, size_t *triangle_count);

/* Writes the current level as a compact mesh: positions (3 * vertex_count floats), indices
   (3 * triangle_count) and, if vertex_ids is not NULL, the input id of each vertex. Vertices come
   in increasing input id, triangles in input order. Sizes from dm_pm_counts. Uses a scratch array
   inside pm: not concurrently with anything else on the same pm. */
DMDEF void dm_pm_get_mesh(dm_pm *pm, float *positions, uint32_t *indices, uint32_t *vertex_ids);

/* Current positions by input vertex id (3 floats each; entries of vertices not in the current
   level hold their last position). */
DMDEF const float *dm_pm_positions(const dm_pm *pm);

/* The vertex split that takes level `level` to level + 1. Returns 0 if level is out of range. */
DMDEF int dm_pm_get_vsplit(const dm_pm *pm, size_t level, dm_vsplit *out);

/* The input vertices merged into `vertex` at the base level (itself included), in increasing id.
   *list points into pm; returns the count (0 for an id out of range or a vertex merged away). */
DMDEF size_t dm_pm_merged_vertices(const dm_pm *pm, uint32_t vertex, const uint32_t **list);

/* ---- Part 3 (continued): the bounding shell ---------------------------------------------- */

/* The bounding shell of paper 000 and its two simplification constraints (see "BOUNDING SHELL"
   under PART 3). */
typedef struct dm_shell_options {
    float thickness;           /* the shell's largest offset from the original, world units;
                                  0 = 2% of the original's bounding-box diagonal */
    int steps;                 /* growth steps (each thickness / steps); 0 = 8 */
    int overlap_samples;       /* points per candidate triangle for the overlap check; 0 = 4,
                                  at most 7 */
    const dm_allocator *allocator; /* NULL = DM_MALLOC/DM_FREE; kept in the dm_shell */
    int (*progress)(void *user, float done); /* NULL, or nonzero return cancels */
    void *progress_user;
} dm_shell_options;            /* zero = defaults */
DMDEF dm_shell_options dm_shell_default_options(void);

/* An offset surface grown outward from the original: same connectivity, vertex v at
   orig[v] + offset[v] * normal[v]. It also holds a BVH of the original and the counters of
   dm_shell_constraint. */
typedef struct dm_shell {
    dm_allocator allocator;
    size_t vertex_count, triangle_count;
    float *positions;          /* 3 per original vertex: the shell surface */
    float *normals;            /* 3 per original vertex: the original's angle-weighted normal */
    float *offset;             /* per original vertex: how far it grew (0 .. thickness) */
    float thickness;           /* the limit used, world units */
    float diagonal;            /* the original's bounding-box diagonal */
    size_t stopped_vertices;   /* vertices stopped before the full thickness */
    size_t moved, vetoed_enclose, vetoed_shell, vetoed_overlap; /* dm_shell_constraint's verdicts in
                                  the current (or last) dm_simplify run */
    int fallback;              /* 0: the paper's constraints (but the candidates asked relaxed);
                                  1 after dm_shell_relax: the base may cross the original (signed
                                  displacement); 2 after a second one: the simplifier's own checks */
    uint8_t *fallback_vertex;  /* per original vertex: 1 = keep of a collapse done relaxed;
                                  the base triangles at such vertices need a bake both ways */
    size_t fallback_collapses; /* collapses done while relaxed (this run) */
    void *internal;            /* private: the original's BVH and a copy of its mesh */
} dm_shell;

/* Grows the bounding shell of a (dense) mesh (as dm_bvh_build's arguments). */
DMDEF dm_result dm_shell_grow(const float *positions, size_t vertex_count, const uint32_t *indices,
                              size_t triangle_count, const dm_shell_options *options, dm_shell **out);
DMDEF void dm_shell_free(dm_shell *shell);

/* A dm_collapse_constraint for dm_simplify on the same mesh, user = the dm_shell: keeps the
   simplified mesh enclosing the original (a corrected position outside every plane of the
   collapse's old triangles), inside the shell, and free of height-field overlap along its
   interpolated normals. Not for two dm_simplify calls at once on one shell. */
DMDEF int dm_shell_constraint(void *shell, const dm_collapse *candidate, float corrected[3]);

/* dm_simplify_options.on_collapse for the same shell: follows the simplified mesh so that the
   overlap check sees its exact vertex normals. Set both:
     opt.constraint = dm_shell_constraint; opt.on_collapse = dm_shell_collapsed; opt.constraint_user = shell;
   (without it, after two accepted candidates the check falls back to normals from the one-ring).
   One shell serves any number of dm_simplify runs, one at a time: a candidate or collapse with
   level 0 after a run that did collapses starts again from the original's normals. */
DMDEF void dm_shell_collapsed(void *shell, const dm_collapse *done);

/* dm_simplify_options.relax for the same shell: the fallback where the shell is too thin for the
   enclosing base to reach the face count. The first call lets the base cross the original: a
   candidate then needs, from each of its ray samples, the nearest crossing of the original along
   the line (either way, within the thickness) to face the same way as the base, which is what a
   bake both ways needs to be single-valued; the second leaves only the simplifier's own checks.
   Returns 1 when it relaxed, 0 when it cannot relax further. A candidate with
   dm_collapse.relaxed gets the first call's check without it. The keep vertices of the collapses
   done relaxed are marked in fallback_vertex (dm_shell_fallback_triangles turns them into
   the base triangles to bake both ways). */
DMDEF int dm_shell_relax(void *shell);

/* For a base from a dm_simplify run with this shell (vertex_ids from dm_pm_get_mesh, so input
   ids): flags[t] = 1 when base triangle t has a vertex in fallback_vertex, else 0. Returns the
   number flagged. */
DMDEF size_t dm_shell_fallback_triangles(const dm_shell *shell, const uint32_t *base_indices, size_t triangle_count,
                                         const uint32_t *vertex_ids, uint8_t *flags);

#ifdef __cplusplus
}
#endif
#endif /* DM_DISPMESH_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef DM_IMPLEMENTATION
#ifndef DM_IMPLEMENTATION_DONE
#define DM_IMPLEMENTATION_DONE

#include <string.h>
#include <float.h>
#include <math.h>

#if defined(DM_MALLOC) && defined(DM_FREE)
/* both given */
#elif !defined(DM_MALLOC) && !defined(DM_FREE)
#include <stdlib.h>
#define DM_MALLOC(sz) malloc(sz)
#define DM_FREE(p) free(p)
#else
#error "dispmesh.h: define both DM_MALLOC and DM_FREE, or neither"
#endif

#if defined(DM_USE_AVX2)
#if !defined(__AVX__)
#error "dispmesh.h: DM_USE_AVX2 needs AVX code generation (gcc/clang -mavx2, MSVC /arch:AVX2)"
#endif
#include <immintrin.h>
#ifndef DM_USE_SSE2
#define DM_USE_SSE2
#endif
#endif
#if defined(DM_USE_SSE2)
#include <emmintrin.h>
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
   Section: results, allocation, scratch memory
   --------------------------------------------------------------------------------------------- */

DMDEF const char *dm_result_string(dm_result r)
{
    switch (r) {
    case DM_OK: return "DM_OK";
    case DM_ERR_INVALID_ARGUMENT: return "DM_ERR_INVALID_ARGUMENT";
    case DM_ERR_NO_TRIANGLES: return "DM_ERR_NO_TRIANGLES";
    case DM_ERR_BAD_INDEX: return "DM_ERR_BAD_INDEX";
    case DM_ERR_BAD_POSITION: return "DM_ERR_BAD_POSITION";
    case DM_ERR_TOO_LARGE: return "DM_ERR_TOO_LARGE";
    case DM_ERR_OUT_OF_MEMORY: return "DM_ERR_OUT_OF_MEMORY";
    case DM_CANCELLED: return "DM_CANCELLED";
    case DM_ERR_MAP_TOO_SMALL: return "DM_ERR_MAP_TOO_SMALL";
    case DM_ERR_NOT_WELDED: return "DM_ERR_NOT_WELDED";
    case DM_ERR_BAD_MAP: return "DM_ERR_BAD_MAP";
    }
    return "DM_ERR_?";
}

static void *dm__default_alloc(void *user, size_t size) { (void)user; return DM_MALLOC(size); }
static void dm__default_free(void *user, void *ptr) { (void)user; DM_FREE(ptr); }

static dm_allocator dm__resolve_allocator(const dm_allocator *a)
{
    dm_allocator r;
    if (a && a->alloc && a->free) return *a;
    r.alloc = dm__default_alloc;
    r.free = dm__default_free;
    r.user = NULL;
    return r;
}

/* count * size bytes, or NULL with *overflow set when that does not fit size_t */
static void *dm__alloc_array(const dm_allocator *a, size_t count, size_t size, int *overflow)
{
    if (size != 0 && count > (size_t)-1 / size) {
        *overflow = 1;
        return NULL;
    }
    return a->alloc(a->user, count * size > 0 ? count * size : 1);
}

/* Temporaries of one call, all freed together on every exit path. */
#define DM__SLOTS 64
typedef struct dm__scratch {
    dm_allocator a;
    void *p[DM__SLOTS];
    int n;
    int overflow;
} dm__scratch;

static void *dm__take(dm__scratch *s, size_t count, size_t size)
{
    void *p;
    if (s->n >= DM__SLOTS) return NULL;
    p = dm__alloc_array(&s->a, count, size, &s->overflow);
    if (p) s->p[s->n++] = p;
    return p;
}

static void dm__release(dm__scratch *s)
{
    while (s->n > 0) s->a.free(s->a.user, s->p[--s->n]);
}

static dm_result dm__scratch_fail(const dm__scratch *s)
{
    return s->overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
}

/* ---------------------------------------------------------------------------------------------
   Section: small maths in double, vertex normals, sorted edges and twins (shared by parts 2, 3, 4)
   --------------------------------------------------------------------------------------------- */

static double dm__dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void dm__cross3(const double a[3], const double b[3], double r[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

static void dm__load3(const float *pos, uint32_t v, double out[3])
{
    out[0] = pos[3 * (size_t)v];
    out[1] = pos[3 * (size_t)v + 1];
    out[2] = pos[3 * (size_t)v + 2];
}

static void dm__sub3(const double a[3], const double b[3], double r[3])
{
    r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2];
}


static double dm__len3(const double a[3]) { return sqrt(dm__dot3(a, a)); }

/* The angle of triangle p at corner j (radians), or -1 when an edge there has zero length:
   the weight of an angle-weighted vertex normal (Thurmer and Wuthrich 1998). */
static double dm__corner_angle(const double p[3][3], int j)
{
    double ea[3], eb[3], la, lb, ang;
    dm__sub3(p[(j + 1) % 3], p[j], ea);
    dm__sub3(p[(j + 2) % 3], p[j], eb);
    la = dm__len3(ea);
    lb = dm__len3(eb);
    if (!(la > 0.0 && lb > 0.0)) return -1.0;
    ang = dm__dot3(ea, eb) / (la * lb);
    return acos(ang < -1.0 ? -1.0 : ang > 1.0 ? 1.0 : ang);
}

/* twice the area normal of triangle t */
static void dm__face_normal(const float *pos, const uint32_t *idx, size_t t, double n[3])
{
    double p0[3], p1[3], p2[3], e1[3], e2[3];
    dm__load3(pos, idx[3 * t], p0);
    dm__load3(pos, idx[3 * t + 1], p1);
    dm__load3(pos, idx[3 * t + 2], p2);
    dm__sub3(p1, p0, e1);
    dm__sub3(p2, p0, e2);
    dm__cross3(e1, e2, n);
}

/* Angle-weighted vertex normals (Thurmer and Wüthrich 1998), unit or zero, into nrm[3 nv]. */
static void dm__vertex_normals(const float *pos, size_t nv, const uint32_t *idx, size_t nt, double *acc,
                               float *nrm)
{
    size_t t, v;
    int c, k;
    memset(acc, 0, 3 * nv * sizeof(double));
    for (t = 0; t < nt; t++) {
        double n[3], len, p[3][3];
        dm__face_normal(pos, idx, t, n);
        len = dm__len3(n);
        if (!(len > 0.0)) continue;
        for (c = 0; c < 3; c++) dm__load3(pos, idx[3 * t + (size_t)c], p[c]);
        for (c = 0; c < 3; c++) {
            double ang = dm__corner_angle((const double(*)[3])p, c);
            if (ang < 0.0) continue;
            for (k = 0; k < 3; k++) acc[3 * (size_t)idx[3 * t + (size_t)c] + (size_t)k] += ang * n[k] / len;
        }
    }
    for (v = 0; v < nv; v++) {
        double len = dm__len3(acc + 3 * v);
        for (k = 0; k < 3; k++) nrm[3 * v + (size_t)k] = len > 0.0 ? (float)(acc[3 * v + (size_t)k] / len) : 0.0f;
    }
}

/* Base normals (dm_base_normals). A base vertex whose angle-weighted normal sees one of its
   triangles at more than 60 degrees (a short wall beside a wide flat part, at a crease) would
   send that triangle's displacement lines along its own plane, where they meet the original in
   one point and fold. Such a vertex turns its normal toward the direction that sees all its
   triangles best (the axis of the smallest cone holding their normals): the least turn that sees
   each at 60 degrees, or as far as the axis, and never more than 30 degrees (in a crumpled part of
   a base no direction sees every triangle, and a longer turn sends the lines across other
   sheets). Every other vertex keeps its angle-weighted normal. Shell maps ask their directions
   for the same visibility (Jiang et al. 2020, "Bijective projection in a shell"). */
#define DM__CONE_MIN 0.5                   /* cos 60 degrees */
#define DM__CONE_TURN 0.86602540378443865  /* cos 30 degrees */
#define DM__CONE_FACES 32                  /* more triangles at a vertex: it keeps its normal */

/* the smallest dot product of unit n with the k unit face normals fn */
static double dm__cone_min(const double *fn, int k, const double n[3])
{
    double m = HUGE_VAL;
    int i;
    for (i = 0; i < k; i++) {
        double d = dm__dot3(fn + 3 * i, n);
        if (d < m) m = d;
    }
    return m;
}

/* the unit direction that maximises the smallest dot product with the k unit normals fn (one of
   them, the bisector of two or the circumcentre of three: the optimum is one of these), into
   axis; returns that dot product */
static double dm__cone_axis(const double *fn, int k, double axis[3])
{
    double best = -HUGE_VAL;
    int a, b, c, j;
    for (a = 0; a < k; a++)
        for (b = a; b < k; b++)
            for (c = b; c < k; c++) {
                double d[3], u[3], v[3], len, m;
                if (a == b && b == c) {
                    for (j = 0; j < 3; j++) d[j] = fn[3 * a + j];
                } else if (a == b) {
                    continue;
                } else if (b == c) {
                    for (j = 0; j < 3; j++) d[j] = fn[3 * a + j] + fn[3 * b + j];
                } else {
                    dm__sub3(fn + 3 * b, fn + 3 * a, u);
                    dm__sub3(fn + 3 * c, fn + 3 * a, v);
                    dm__cross3(u, v, d);
                    if (dm__dot3(d, fn + 3 * a) < 0.0)
                        for (j = 0; j < 3; j++) d[j] = -d[j];
                }
                len = dm__len3(d);
                if (!(len > 1e-12)) continue;
                for (j = 0; j < 3; j++) d[j] /= len;
                m = dm__cone_min(fn, k, d);
                if (m > best) {
                    best = m;
                    for (j = 0; j < 3; j++) axis[j] = d[j];
                }
            }
    return best;
}

/* unit n0 turned toward unit axis by s in [0, 1] (the chord, renormalised), into out */
static void dm__cone_step(const double n0[3], const double axis[3], double s, double out[3])
{
    double len;
    int j;
    for (j = 0; j < 3; j++) out[j] = (1.0 - s) * n0[j] + s * axis[j];
    len = dm__len3(out);
    for (j = 0; j < 3; j++) out[j] = len > 0.0 ? out[j] / len : n0[j];
}

/* one vertex's normal n (unit, seeing its k triangles fn at worst `worst`), turned as the
   section's head says; n is left alone where the axis sees no better */
static void dm__cone_turn(const double *fn, int k, double worst, double n[3])
{
    double axis[3], n0[3], d[3], best, target, lo = 0.0, hi = 1.0, lo2 = 0.0, hi2 = 1.0;
    int it, j;
    best = dm__cone_axis(fn, k, axis);
    if (!(best > worst)) return;
    target = best < DM__CONE_MIN ? best : DM__CONE_MIN;
    for (j = 0; j < 3; j++) n0[j] = n[j];
    for (it = 0; it < 40; it++) { /* the least turn that reaches target (hi) */
        double s = 0.5 * (lo + hi);
        dm__cone_step(n0, axis, s, d);
        if (dm__cone_min(fn, k, d) >= target) hi = s;
        else lo = s;
    }
    for (it = 0; it < 40; it++) { /* the longest turn within DM__CONE_TURN (lo2) */
        double s = 0.5 * (lo2 + hi2);
        dm__cone_step(n0, axis, s, d);
        if (dm__dot3(d, n0) >= DM__CONE_TURN) lo2 = s;
        else hi2 = s;
    }
    dm__cone_step(n0, axis, hi < lo2 ? hi : lo2, n);
}

/* dm__vertex_normals, then each vertex that sees one of its triangles at less than DM__CONE_MIN
   turned (dm__cone_turn); the corner lists (first: nv + 1, corner: 3 nt) are taken from sc only
   when a vertex needs them. acc: 3 nv doubles of work space. */
static dm_result dm__base_normals(dm__scratch *sc, const float *pos, size_t nv, const uint32_t *idx, size_t nt,
                                  double *acc, float *nrm)
{
    size_t t, v, nflag = 0;
    uint32_t *first, *corner;
    dm__vertex_normals(pos, nv, idx, nt, acc, nrm);
    for (v = 0; v < nv; v++) acc[v] = HUGE_VAL; /* 1. each vertex's worst dot product with a triangle */
    for (t = 0; t < nt; t++) {
        double n[3], len, vn[3];
        int c;
        dm__face_normal(pos, idx, t, n);
        len = dm__len3(n);
        if (!(len > 0.0)) continue;
        for (c = 0; c < 3; c++) {
            size_t w = idx[3 * t + (size_t)c];
            dm__load3(nrm, w, vn);
            if (dm__dot3(vn, n) / len < acc[w]) acc[w] = dm__dot3(vn, n) / len;
        }
    }
    for (v = 0; v < nv; v++) nflag += acc[v] < DM__CONE_MIN;
    if (!nflag) return DM_OK;
    first = (uint32_t *)dm__take(sc, nv + 1, sizeof(uint32_t)); /* 2. corners by vertex */
    corner = (uint32_t *)dm__take(sc, 3 * nt + 1, sizeof(uint32_t));
    if (!first || !corner) return dm__scratch_fail(sc);
    memset(first, 0, (nv + 1) * sizeof(uint32_t));
    for (t = 0; t < 3 * nt; t++) first[idx[t] + 1]++;
    for (v = 0; v < nv; v++) first[v + 1] += first[v];
    for (t = 0; t < 3 * nt; t++) corner[first[idx[t]]++] = (uint32_t)t;
    for (v = nv; v > 0; v--) first[v] = first[v - 1];
    first[0] = 0;
    for (v = 0; v < nv; v++) { /* 3. the turns */
        double fn[3 * DM__CONE_FACES], n[3];
        int k = 0, j;
        uint32_t q;
        if (!(acc[v] < DM__CONE_MIN) || first[v + 1] - first[v] > DM__CONE_FACES) continue;
        for (q = first[v]; q < first[v + 1]; q++) {
            double len;
            dm__face_normal(pos, idx, corner[q] / 3, fn + 3 * k);
            len = dm__len3(fn + 3 * k);
            if (!(len > 0.0)) continue;
            for (j = 0; j < 3; j++) fn[3 * k + j] /= len;
            k++;
        }
        dm__load3(nrm, v, n);
        dm__cone_turn(fn, k, acc[v], n);
        for (j = 0; j < 3; j++) nrm[3 * v + (size_t)j] = (float)n[j];
    }
    return DM_OK;
}

typedef struct dm__edge {
    uint64_t key; /* min vertex << 32 | max vertex */
    uint32_t he;  /* 3 triangle + corner */
} dm__edge;

static int dm__edge_cmp(const void *a, const void *b)
{
    const dm__edge *x = (const dm__edge *)a, *y = (const dm__edge *)b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->he < y->he ? -1 : x->he > y->he ? 1 : 0;
}

/* e[]: the 3 nt half-edges keyed by their vertex pair, sorted (by key, then half-edge) */
static void dm__sorted_edges(const uint32_t *idx, size_t nt, dm__edge *e)
{
    size_t i, n = 3 * nt;
    for (i = 0; i < n; i++) {
        uint32_t a = idx[i], b = idx[i - i % 3 + (i % 3 + 1) % 3];
        e[i].key = a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
        e[i].he = (uint32_t)i;
    }
    qsort(e, n, sizeof(dm__edge), dm__edge_cmp);
}

/* twin[he]: the opposite half-edge's triangle, when exactly two triangles share the edge and
   run it in opposite directions (a consistently oriented manifold edge); DM_NO_HIT otherwise. */
static void dm__twins(const uint32_t *idx, size_t nt, dm__edge *e, uint32_t *twin, uint32_t *twin_he)
{
    size_t i, j, n = 3 * nt;
    for (i = 0; i < n; i++) {
        twin[i] = DM_NO_HIT;
        twin_he[i] = DM_NO_HIT;
    }
    dm__sorted_edges(idx, nt, e);
    for (i = 0; i < n; i = j) {
        for (j = i + 1; j < n && e[j].key == e[i].key; j++) {}
        if (j - i == 2) {
            uint32_t h0 = e[i].he, h1 = e[i + 1].he;
            if (idx[h0] != idx[h1] && h0 / 3 != h1 / 3) { /* opposite directions, two triangles */
                twin[h0] = h1 / 3; twin_he[h0] = h1;
                twin[h1] = h0 / 3; twin_he[h1] = h0;
            }
        }
    }
}

/* ---------------------------------------------------------------------------------------------
   Section: BVH data
   --------------------------------------------------------------------------------------------- */

/* 32 bytes. Interior: count == 0, children at first and first + 1 (siblings share one 64-byte
   line). Leaf: count triangles starting at slot first (a multiple of 4, see dm__tri4). */
typedef struct dm__node {
    float lo[3];
    uint32_t first;
    float hi[3];
    uint32_t count;
} dm__node;

/* Four triangles of a leaf, side by side (160 bytes): v[3 c + k][lane] is coordinate k of
   corner c, so one ray is tested against four triangles with the same instruction stream.
   Leaves start at a block boundary; unused lanes of a leaf's last block have id DM_NO_HIT
   and a copy of the leaf's first triangle (never reported: lanes past the leaf's count are
   masked). A triangle's slot is 4 block + lane. */
typedef struct dm__tri4 {
    float v[9][4];
    uint32_t id[4];
} dm__tri4;

/* The width of the traversal tree's nodes. */
#define DM__W 8

/* 256 bytes, four cache lines: a node of the 8-wide traversal tree, derived from the binary
   tree by collapsing (dm__collapse). The child boxes lie side by side (lo[axis][child]), so one
   node load gives eight box tests. Child i: count[i] == 0 is an interior child (wide node
   ref[i]), count[i] > 0 a leaf of count[i] triangles from slot ref[i]. Unused slots have NaN
   boxes, which every box test misses. */
typedef struct dm__wnode {
    float lo[3][DM__W];
    float hi[3][DM__W];
    uint32_t ref[DM__W];
    uint32_t count[DM__W];
} dm__wnode;

struct dm_bvh {
    dm_allocator allocator;
    dm__node *nodes;    /* 64-byte aligned inside node_block */
    void *node_block;
    size_t node_slots;  /* nodes in use (root, padding slot, then sibling pairs) */
    size_t node_bytes;  /* size of node_block */
    dm__wnode *wnodes;  /* 64-byte aligned inside wide_block; wnodes[0] is the root */
    void *wide_block;
    size_t wide_count;  /* wide nodes in use */
    size_t wide_bytes;  /* size of wide_block; 0 when the wide nodes live in node_block's tail */
    dm__tri4 *blocks;   /* 64-byte aligned inside tri_block */
    void *tri_block;
    size_t tri_bytes;   /* size of tri_block */
    size_t block_count;
    size_t triangle_count;
    size_t max_depth;
};

/* the hot helpers of the traversal must be inlined for speed */
#if defined(__GNUC__) || defined(__clang__)
#define DM__INLINE static inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define DM__INLINE static __forceinline
#else
#define DM__INLINE static inline
#endif

/* Memory latency dominates an incoherent traversal: start loading what a child points to
   (its children or its triangles) while its box is still being tested. */
#if defined(__GNUC__) || defined(__clang__)
#define DM__PREFETCH(p) __builtin_prefetch(p)
#else
#define DM__PREFETCH(p) ((void)(p))
#endif

/* min and max as the SSE instructions define them: the second operand when either is NaN */
#define DM__MINF(a, b) ((a) < (b) ? (a) : (b))
#define DM__MAXF(a, b) ((a) > (b) ? (a) : (b))

/* Traversal stacks are fixed arrays; the build caps the depth below this (see dm__build). */
#define DM__STACK 128
#define DM__SAH_DEPTH 64

/* ---------------------------------------------------------------------------------------------
   Section: build (binned SAH, Wald 2007)
   --------------------------------------------------------------------------------------------- */

typedef struct dm__bin {
    float lo[3], hi[3];
    uint32_t count;
} dm__bin;

typedef struct dm__task {
    uint32_t node, begin, end, depth;
    float clo[3], chi[3]; /* bounds of the doubled centroids (lo + hi) of the task's triangles */
} dm__task;

/* A triangle's box and id, 32 bytes. The build partitions an array of these in place, so that
   every pass over a range reads memory in order (no indirection through triangle ids). */
typedef struct dm__ref {
    float lo[3];
    uint32_t id;
    float hi[3];
    float pad;
} dm__ref;

typedef struct dm__builder {
    dm__ref *refs;      /* one per triangle, partitioned in place; leaves are ranges of it */
    dm__node *nodes;
    uint32_t used;      /* nodes handed out, padding slot included */
    int bins;
    int all_axes;       /* bin all three axes (high quality) or only the widest */
    uint32_t max_leaf;
    size_t max_depth;
    size_t done, next_report, report_step, total;
    int (*progress)(void *user, float done);
    void *progress_user;
    dm__bin *bin_store; /* 3 * bins */
    float *right_area;  /* bins */
    uint32_t *right_count;
} dm__builder;

DM__INLINE float dm__half_area(const float lo[3], const float hi[3])
{
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return dx * dy + dy * dz + dz * dx;
}

static void dm__box_empty(float lo[3], float hi[3])
{
    lo[0] = lo[1] = lo[2] = FLT_MAX;
    hi[0] = hi[1] = hi[2] = -FLT_MAX;
}

DM__INLINE void dm__box_grow(float lo[3], float hi[3], const float *plo, const float *phi)
{
    /* unrolled: the build spends most of its time here */
    lo[0] = plo[0] < lo[0] ? plo[0] : lo[0];
    lo[1] = plo[1] < lo[1] ? plo[1] : lo[1];
    lo[2] = plo[2] < lo[2] ? plo[2] : lo[2];
    hi[0] = phi[0] > hi[0] ? phi[0] : hi[0];
    hi[1] = phi[1] > hi[1] ? phi[1] : hi[1];
    hi[2] = phi[2] > hi[2] ? phi[2] : hi[2];
}

/* the SAH bin of doubled centroid c, given the axis minimum and scale bins / extent */
DM__INLINE uint32_t dm__bin_of(float c, float cmin, float scale, uint32_t last)
{
    float f = (c - cmin) * scale;
    uint32_t b = f > 0.0f ? (uint32_t)f : 0u;
    return b < last ? b : last;
}

/* Box and centroid bounds of order[begin, end). */
static void dm__range_bounds(const dm__builder *b, uint32_t begin, uint32_t end, float lo[3], float hi[3],
                             float clo[3], float chi[3])
{
    uint32_t i;
    int k;
    dm__box_empty(lo, hi);
    dm__box_empty(clo, chi);
    for (i = begin; i < end; i++) {
        const dm__ref *ref = &b->refs[i];
        float c[3];
        for (k = 0; k < 3; k++) c[k] = ref->lo[k] + ref->hi[k];
        dm__box_grow(lo, hi, ref->lo, ref->hi);
        dm__box_grow(clo, chi, c, c);
    }
}

/* The best binned SAH split of a task: axis and last bin of the left side, or axis -1 when
   no split separates the centroids. *cost is sum(area * count) over both sides. */
/* Bins for a range of n triangles: fewer for small ranges, where clearing and sweeping the
   bins would cost more than binning the triangles. */
static uint32_t dm__bins_for(const dm__builder *b, uint32_t n)
{
    uint32_t nb = 4 + n / 2;
    return nb < (uint32_t)b->bins ? nb : (uint32_t)b->bins;
}

static int dm__find_split(dm__builder *b, const dm__task *t, int *split_axis, uint32_t *split_bin,
                          float *cost, float left_lo[3], float left_hi[3], float right_lo[3],
                          float right_hi[3])
{
    const uint32_t nb = dm__bins_for(b, t->end - t->begin);
    float scale[3];
    int axis, found = 0;
    uint32_t i, j;
    dm__bin *bins = b->bin_store;
    for (axis = 0; axis < 3; axis++) {
        float extent = t->chi[axis] - t->clo[axis];
        scale[axis] = extent > 0.0f ? (float)nb / extent : 0.0f;
        if (!(scale[axis] <= FLT_MAX)) scale[axis] = 0.0f; /* extent below ~1e-38: do not split */
        for (i = 0; i < nb; i++) {
            dm__box_empty(bins[axis * nb + i].lo, bins[axis * nb + i].hi);
            bins[axis * nb + i].count = 0;
        }
    }
    /* The fast build bins only the axis where the centroids spread most (a third of the
       work, a slightly costlier tree); the high-quality build bins all three. An axis with
       scale 0 is not binned and not swept. */
    if (!b->all_axes) {
        int widest = 0;
        for (axis = 1; axis < 3; axis++)
            if (t->chi[axis] - t->clo[axis] > t->chi[widest] - t->clo[widest]) widest = axis;
        for (axis = 0; axis < 3; axis++)
            if (axis != widest) scale[axis] = 0.0f;
    }
    for (axis = 0; axis < 3; axis++) {
        dm__bin *axis_bins = bins + (size_t)axis * nb;
        const float cmin = t->clo[axis], s = scale[axis];
        if (s == 0.0f) continue;
        for (i = t->begin; i < t->end; i++) {
            const dm__ref *ref = &b->refs[i];
            dm__bin *bin = &axis_bins[dm__bin_of(ref->lo[axis] + ref->hi[axis], cmin, s, nb - 1)];
            bin->count++;
            dm__box_grow(bin->lo, bin->hi, ref->lo, ref->hi);
        }
    }
    for (axis = 0; axis < 3; axis++) {
        float lo[3], hi[3];
        uint32_t count = 0;
        if (scale[axis] == 0.0f) continue;
        /* right-to-left sweep: area and count of bins (i, nb) */
        dm__box_empty(lo, hi);
        for (i = nb - 1; i > 0; i--) {
            const dm__bin *bin = &bins[axis * nb + i];
            if (bin->count) dm__box_grow(lo, hi, bin->lo, bin->hi);
            count += bin->count;
            b->right_area[i - 1] = count ? dm__half_area(lo, hi) : 0.0f;
            b->right_count[i - 1] = count;
        }
        /* left-to-right sweep: split after bin i */
        dm__box_empty(lo, hi);
        count = 0;
        for (i = 0; i + 1 < nb; i++) {
            const dm__bin *bin = &bins[axis * nb + i];
            float c;
            if (bin->count) dm__box_grow(lo, hi, bin->lo, bin->hi);
            count += bin->count;
            if (count == 0 || b->right_count[i] == 0) continue;
            c = dm__half_area(lo, hi) * (float)count + b->right_area[i] * (float)b->right_count[i];
            if (!found || c < *cost) {
                found = 1;
                *cost = c;
                *split_axis = axis;
                *split_bin = i;
            }
        }
    }
    if (!found) return 0;
    /* the two sides' boxes, from the winning axis' bins */
    axis = *split_axis;
    dm__box_empty(left_lo, left_hi);
    dm__box_empty(right_lo, right_hi);
    for (j = 0; j < nb; j++) {
        const dm__bin *bin = &bins[axis * nb + j];
        if (!bin->count) continue;
        if (j <= *split_bin) dm__box_grow(left_lo, left_hi, bin->lo, bin->hi);
        else dm__box_grow(right_lo, right_hi, bin->lo, bin->hi);
    }
    return 1;
}

/* Partitions order[begin, end) by the split; returns the first index of the right side and the
   centroid bounds of both sides. */
static uint32_t dm__partition(dm__builder *b, const dm__task *t, int axis, uint32_t split_bin,
                              float lclo[3], float lchi[3], float rclo[3], float rchi[3])
{
    const uint32_t nb = dm__bins_for(b, t->end - t->begin);
    float extent = t->chi[axis] - t->clo[axis], scale = (float)nb / extent;
    uint32_t i = t->begin, j = t->end;
    dm__box_empty(lclo, lchi);
    dm__box_empty(rclo, rchi);
    while (i < j) {
        dm__ref *ref = &b->refs[i];
        float c[3];
        c[0] = ref->lo[0] + ref->hi[0];
        c[1] = ref->lo[1] + ref->hi[1];
        c[2] = ref->lo[2] + ref->hi[2];
        if (dm__bin_of(c[axis], t->clo[axis], scale, nb - 1) <= split_bin) {
            dm__box_grow(lclo, lchi, c, c);
            i++;
        } else {
            dm__ref swap = *ref;
            dm__box_grow(rclo, rchi, c, c);
            j--;
            *ref = b->refs[j];
            b->refs[j] = swap;
        }
    }
    return i;
}

static int dm__report(dm__builder *b, uint32_t leaf_triangles)
{
    b->done += leaf_triangles;
    if (!b->progress || b->done < b->next_report) return 0;
    b->next_report = b->done + b->report_step;
    return b->progress(b->progress_user, (float)((double)b->done / (double)b->total));
}

/* Splits tasks until every range is a leaf. Children of a node are allocated together
   (siblings in one cache line); the right child is pushed first, so the left subtree is laid
   out right after its parent's pair. Below DM__SAH_DEPTH, and when all centroids coincide, a
   range is cut at its middle instead: the depth stays below DM__SAH_DEPTH + 32 < DM__STACK.
   Returns 0, or nonzero when the progress callback cancelled. */
static int dm__build(dm__builder *b, float root_clo[3], float root_chi[3])
{
    dm__task stack[DM__STACK];
    size_t sp = 0;
    dm__task t;
    int k;
    t.node = 0;
    t.begin = 0;
    t.end = (uint32_t)b->total;
    t.depth = 0;
    for (k = 0; k < 3; k++) {
        t.clo[k] = root_clo[k];
        t.chi[k] = root_chi[k];
    }
    for (;;) {
        dm__node *node = &b->nodes[t.node];
        uint32_t n = t.end - t.begin, mid = 0;
        float llo[3], lhi[3], rlo[3], rhi[3], lclo[3], lchi[3], rclo[3], rchi[3];
        int axis = -1, split = 0;
        if (t.depth > b->max_depth) b->max_depth = t.depth;
        /* Leaves of up to max_leaf triangles. Letting the SAH also stop early (leaf cost n
           against traversal + children) made no measurable difference to ray speed on the
           bench meshes and a third more nodes: the range size alone decides. */
        if (n > b->max_leaf) {
            uint32_t split_bin = 0;
            float cost = 0.0f;
            split = 1;
            if (t.depth < DM__SAH_DEPTH &&
                dm__find_split(b, &t, &axis, &split_bin, &cost, llo, lhi, rlo, rhi)) {
                mid = dm__partition(b, &t, axis, split_bin, lclo, lchi, rclo, rchi);
            } else { /* too deep, or every centroid in one point: cut the range in half */
                mid = t.begin + n / 2;
                dm__range_bounds(b, t.begin, mid, llo, lhi, lclo, lchi);
                dm__range_bounds(b, mid, t.end, rlo, rhi, rclo, rchi);
            }
        }
        if (split) {
            uint32_t left = b->used;
            dm__task right_task;
            b->used += 2;
            node->first = left;
            node->count = 0;
            for (k = 0; k < 3; k++) {
                b->nodes[left].lo[k] = llo[k];
                b->nodes[left].hi[k] = lhi[k];
                b->nodes[left + 1].lo[k] = rlo[k];
                b->nodes[left + 1].hi[k] = rhi[k];
                right_task.clo[k] = rclo[k];
                right_task.chi[k] = rchi[k];
                t.clo[k] = lclo[k];
                t.chi[k] = lchi[k];
            }
            right_task.node = left + 1;
            right_task.begin = mid;
            right_task.end = t.end;
            right_task.depth = t.depth + 1;
            stack[sp++] = right_task;
            t.node = left;
            t.end = mid;
            t.depth++;
            continue;
        }
        node->first = t.begin;
        node->count = n;
        if (dm__report(b, n)) return 1;
        if (sp == 0) return 0;
        t = stack[--sp];
    }
}

/* The 8-wide traversal tree from the binary tree: each wide node takes a binary interior node's
   two children and keeps opening the interior child with the largest surface area until it has
   eight (or only leaves are left). A node's interior children get consecutive numbers, after
   their parent's; w must hold bvh->node_slots / 2 + 1 of them (a wide node uses up at least one
   binary interior node). Run again after a refit (the new areas may open other nodes; the
   bound holds for any choice). Returns the wide nodes in use. */
static size_t dm__collapse(const dm__node *nodes, dm__wnode *w)
{
    uint32_t stack_b[DM__W * DM__STACK], stack_w[DM__W * DM__STACK], used = 1;
    size_t sp = 0;
    stack_b[sp] = 0;
    stack_w[sp++] = 0;
    while (sp) {
        uint32_t cand[DM__W], nc, bi, wi, s, next[DM__W];
        int k, pushed = 0;
        dm__wnode *wn;
        sp--;
        bi = stack_b[sp];
        wi = stack_w[sp];
        if (nodes[bi].count) {
            cand[0] = bi;
            nc = 1;
        } else {
            cand[0] = nodes[bi].first;
            cand[1] = nodes[bi].first + 1;
            nc = 2;
        }
        while (nc < DM__W) {
            uint32_t pick = DM__W;
            float best = -1.0f;
            for (s = 0; s < nc; s++) {
                const dm__node *c = &nodes[cand[s]];
                float area;
                if (c->count) continue;
                area = dm__half_area(c->lo, c->hi);
                if (area > best) {
                    best = area;
                    pick = s;
                }
            }
            if (pick == DM__W) break;
            { /* the child's two children take its slot and the next free one */
                uint32_t first = nodes[cand[pick]].first;
                cand[pick] = first;
                cand[nc++] = first + 1;
            }
        }
        wn = &w[wi];
        for (s = 0; s < DM__W; s++) {
            if (s < nc) {
                const dm__node *c = &nodes[cand[s]];
                for (k = 0; k < 3; k++) {
                    wn->lo[k][s] = c->lo[k];
                    wn->hi[k][s] = c->hi[k];
                }
                if (c->count) {
                    wn->ref[s] = c->first;
                    wn->count[s] = c->count;
                } else {
                    wn->ref[s] = used;
                    wn->count[s] = 0;
                    next[pushed++] = s;
                    used++;
                }
            } else {
                for (k = 0; k < 3; k++) wn->lo[k][s] = wn->hi[k][s] = (float)NAN;
                wn->ref[s] = 0;
                wn->count[s] = 0;
            }
        }
        while (pushed > 0) { /* the first interior child is taken next: depth first */
            pushed--;
            stack_b[sp] = cand[next[pushed]];
            stack_w[sp++] = wn->ref[next[pushed]];
        }
    }
    return used;
}

DMDEF dm_bvh_options dm_bvh_default_options(void)
{
    dm_bvh_options o;
    memset(&o, 0, sizeof o);
    o.quality = DM_BVH_QUALITY_DEFAULT;
    o.bins = 16;
    o.max_leaf_size = 8;
    return o;
}

static dm_bvh_options dm__resolve_options(const dm_bvh_options *given)
{
    dm_bvh_options o = dm_bvh_default_options();
    if (!given) return o;
    o.quality = given->quality == DM_BVH_QUALITY_HIGH ? DM_BVH_QUALITY_HIGH : DM_BVH_QUALITY_DEFAULT;
    o.bins = given->bins > 0 ? given->bins : (o.quality == DM_BVH_QUALITY_HIGH ? 64 : 16);
    if (o.bins < 4) o.bins = 4;
    if (o.bins > 256) o.bins = 256;
    o.max_leaf_size = given->max_leaf_size > 0 ? given->max_leaf_size : 8;
    if (o.max_leaf_size > 16) o.max_leaf_size = 16;
    o.allocator = given->allocator;
    o.progress = given->progress;
    o.progress_user = given->progress_user;
    return o;
}

/* slots (4 per block, at most one partly used block per triangle) stay below 2^32 */
#define DM__MAX_TRIANGLES 0x3fffffffu

/* coordinates beyond this could overflow float in the intersection arithmetic */
#define DM__MAX_COORD 1e18f

/* Reads triangle tri's corners into p[9] after checking its indices and coordinates. */
static dm_result dm__fetch_triangle(const float *positions, size_t vertex_count, const uint32_t *indices,
                                    size_t tri, float p[9])
{
    int c, k;
    for (c = 0; c < 3; c++) {
        size_t v = indices[3 * tri + (size_t)c];
        if (v >= vertex_count) return DM_ERR_BAD_INDEX;
        for (k = 0; k < 3; k++) {
            float x = positions[3 * v + (size_t)k];
            if (!(x >= -DM__MAX_COORD && x <= DM__MAX_COORD)) return DM_ERR_BAD_POSITION; /* NaN too */
            p[3 * c + k] = x;
        }
    }
    return DM_OK;
}

/* dm__fetch_triangle without the checks, for a triangle that passed them */
DM__INLINE void dm__load_triangle(const float *positions, const uint32_t *indices, size_t tri, float p[9])
{
    const float *a = positions + 3 * (size_t)indices[3 * tri], *b = positions + 3 * (size_t)indices[3 * tri + 1];
    const float *c = positions + 3 * (size_t)indices[3 * tri + 2];
    p[0] = a[0], p[1] = a[1], p[2] = a[2];
    p[3] = b[0], p[4] = b[1], p[5] = b[2];
    p[6] = c[0], p[7] = c[1], p[8] = c[2];
}

/* Bytes per triangle allocated for the build's refs, which the leaf blocks then replace in
   place when they fit: 56 holds blocks filled to 5/7 on average (the bench meshes fill them
   to 7/8); a tree with more padding gets a second allocation. */
#define DM__REF_BYTES 56

/* Writes every leaf's triangles into blocks (lane j of block j / 4 holds triangle j; unused
   lanes of the last block copy its lane 0 and have id DM_NO_HIT) and points the leaf at its
   first slot. The blocks may lie over the refs themselves: leaves are taken from the last
   range to the first (the build gives the left child the lower range, so a right-first
   depth-first walk does that), each leaf's ids are read before its blocks are written, and a
   leaf starting at ref k starts at block >= k / 4, that is at byte >= 160 k / 4 = 40 k, past
   the 32 k bytes of the refs still to be read. */
static void dm__place_blocks(dm__node *nodes, const dm__ref *refs, dm__tri4 *blocks, size_t end,
                             const float *positions, const uint32_t *indices)
{
    uint32_t stack[DM__STACK + 2];
    size_t sp = 0;
    stack[sp++] = 0;
    while (sp) {
        dm__node *n = &nodes[stack[--sp]];
        if (!n->count) {
            stack[sp++] = n->first;     /* left: visited second */
            stack[sp++] = n->first + 1; /* right: visited first */
            continue;
        }
        {
            uint32_t ids[16], j, count = n->count, nb = (count + 3) / 4;
            dm__tri4 *blk;
            for (j = 0; j < count; j++) ids[j] = refs[n->first + j].id;
            end -= nb;
            blk = blocks + end;
            for (j = 0; j < 4 * nb; j++) {
                uint32_t id = ids[j < count ? j : (j & ~3u)];
                float p[9];
                int q;
                dm__load_triangle(positions, indices, id, p);
                for (q = 0; q < 9; q++) blk[j >> 2].v[q][j & 3] = p[q];
                blk[j >> 2].id[j & 3] = j < count ? id : DM_NO_HIT;
            }
            n->first = (uint32_t)(4 * end);
        }
    }
}

/* the corners of the triangle in slot (4 block + lane) */
DM__INLINE void dm__slot_triangle(const dm_bvh *bvh, size_t slot, float p[9])
{
    const dm__tri4 *q = &bvh->blocks[slot >> 2];
    int k;
    for (k = 0; k < 9; k++) p[k] = q->v[k][slot & 3];
}

static dm_result dm__check_sizes(const float *positions, size_t vertex_count, const uint32_t *indices,
                                 size_t triangle_count)
{
    if (!indices || (!positions && vertex_count)) return DM_ERR_INVALID_ARGUMENT;
    if (triangle_count == 0) return DM_ERR_NO_TRIANGLES;
    if (vertex_count == 0) return DM_ERR_BAD_INDEX;
    /* every byte size we form: 3 floats per vertex, 3 indices and 6 box floats per triangle,
       2 nodes per triangle, node ids in uint32 */
    if (vertex_count > (size_t)-1 / (3 * sizeof(float))) return DM_ERR_TOO_LARGE;
    if (triangle_count > (size_t)-1 / (6 * sizeof(float)) || triangle_count > DM__MAX_TRIANGLES) return DM_ERR_TOO_LARGE;
    if (triangle_count > ((size_t)-1 - 64) / sizeof(dm__tri4) || triangle_count > ((size_t)-1 - 64) / DM__REF_BYTES)
        return DM_ERR_TOO_LARGE;
    if (triangle_count > ((size_t)-1 - 64) / (2 * sizeof(dm__node))) return DM_ERR_TOO_LARGE;
    return DM_OK;
}

/* the checks every mesh argument gets (as dm_bvh_build's) */
static dm_result dm__check_mesh(const float *pos, size_t nv, const uint32_t *idx, size_t nt)
{
    size_t i;
    dm_result r = dm__check_sizes(pos, nv, idx, nt); /* the BVH's checks, as for every mesh argument */
    if (r == DM_OK && !pos) r = DM_ERR_INVALID_ARGUMENT;
    for (i = 0; r == DM_OK && i < nt; i++) {
        float p[9];
        r = dm__fetch_triangle(pos, nv, idx, i, p);
    }
    return r;
}

/* Sum over nodes of area * (1 for interior, count for leaves), over the root's area. */
static double dm__sah_cost(const dm_bvh *bvh)
{
    double sum = 0.0, root = dm__half_area(bvh->nodes[0].lo, bvh->nodes[0].hi);
    size_t i;
    for (i = 0; i < bvh->node_slots; i++) {
        const dm__node *n = &bvh->nodes[i];
        if (i == 1) continue;
        sum += (double)dm__half_area(n->lo, n->hi) * (n->count ? (double)n->count : 1.0);
    }
    return root > 0.0 ? sum / root : 0.0;
}

DMDEF void dm_bvh_free(dm_bvh *bvh)
{
    dm_allocator a;
    if (!bvh) return;
    a = bvh->allocator;
    a.free(a.user, bvh->node_block);
    a.free(a.user, bvh->wide_block);
    a.free(a.user, bvh->tri_block);
    a.free(a.user, bvh);
}

/* every triangle checked and its box taken into b->refs (sized so that the leaf blocks usually
   fit in their place, see dm__place_blocks) */
static dm_result dm__ref_boxes(dm__builder *b, dm_allocator *a, const float *positions, size_t vertex_count,
                               const uint32_t *indices, size_t triangle_count, int *overflow)
{
    size_t i;
    b->refs = (dm__ref *)dm__alloc_array(a, triangle_count, DM__REF_BYTES, overflow);
    if (!b->refs) return *overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    for (i = 0; i < triangle_count; i++) {
        float p[9];
        dm__ref *ref = &b->refs[i];
        int c;
        dm_result r = dm__fetch_triangle(positions, vertex_count, indices, i, p);
        if (r != DM_OK) return r;
        dm__box_empty(ref->lo, ref->hi);
        for (c = 0; c < 3; c++) dm__box_grow(ref->lo, ref->hi, p + 3 * c, p + 3 * c);
        ref->id = (uint32_t)i;
        ref->pad = 0.0f;
    }
    return DM_OK;
}

/* the builder's bins and node array (root, padding slot, then at most triangle_count - 1
   sibling pairs; 64-byte aligned inside *wide_block) and its settings; 0 when out of memory */
static int dm__builder_init(dm__builder *b, const dm_bvh_options *opt, dm_allocator *a, size_t triangle_count,
                            void **wide_block, int *overflow)
{
    size_t slots = 2 * triangle_count;
    *wide_block = dm__alloc_array(a, slots * sizeof(dm__node) + 64, 1, overflow);
    b->bins = opt->bins;
    b->all_axes = opt->quality == DM_BVH_QUALITY_HIGH;
    b->bin_store = (dm__bin *)dm__alloc_array(a, 3 * (size_t)opt->bins, sizeof(dm__bin), overflow);
    b->right_area = (float *)dm__alloc_array(a, (size_t)opt->bins, sizeof(float), overflow);
    b->right_count = (uint32_t *)dm__alloc_array(a, (size_t)opt->bins, sizeof(uint32_t), overflow);
    if (!*wide_block || !b->bin_store || !b->right_area || !b->right_count) return 0;
    b->nodes = (dm__node *)((char *)*wide_block + ((64 - ((uintptr_t)*wide_block & 63)) & 63));
    b->used = 2;
    b->max_leaf = (uint32_t)opt->max_leaf_size;
    b->total = triangle_count;
    b->progress = opt->progress;
    b->progress_user = opt->progress_user;
    b->report_step = triangle_count / 64 > 4096 ? triangle_count / 64 : 4096;
    b->next_report = b->report_step;
    return 1;
}

/* the triangles in leaf order, four to a block, over the refs when they fit; 0 when out of
   memory */
static int dm__leaf_blocks(dm_bvh *bvh, dm__builder *b, dm_allocator *a, const float *positions,
                           const uint32_t *indices, int *overflow)
{
    const dm__node *wide = b->nodes;
    size_t blocks = 0, i, triangle_count = bvh->triangle_count;
    for (i = 0; i < b->used; i++)
        if (i != 1 && wide[i].count) blocks += (wide[i].count + 3) / 4;
    if (blocks * sizeof(dm__tri4) + 64 <= triangle_count * DM__REF_BYTES) {
        bvh->tri_block = b->refs;
        bvh->tri_bytes = triangle_count * DM__REF_BYTES;
        b->refs = NULL;
    } else {
        bvh->tri_bytes = blocks * sizeof(dm__tri4) + 64;
        bvh->tri_block = dm__alloc_array(a, bvh->tri_bytes, 1, overflow);
        if (!bvh->tri_block) return 0;
    }
    bvh->blocks = (dm__tri4 *)((char *)bvh->tri_block + ((64 - ((uintptr_t)bvh->tri_block & 63)) & 63));
    bvh->block_count = blocks;
    dm__place_blocks(b->nodes, b->refs ? b->refs : (const dm__ref *)bvh->tri_block, bvh->blocks, blocks, positions,
                     indices);
    return 1;
}

/* The builder's node array goes to the BVH at its worst-case size (2 slots per triangle): a
   copy to the used size (about 1.2 slots per triangle with leaves of 4) cost more time in page
   faults and copying than it saved, and the pages past the used slots are never touched. The
   8-wide traversal tree goes in its unused tail when it fits there (one allocation fewer, and
   pages next to the ones just written); 0 when out of memory */
static int dm__wide_tree(dm_bvh *bvh, const dm__builder *b, void **wide_block, dm_allocator *a, int *overflow)
{
    size_t slots = 2 * bvh->triangle_count, used = b->used;
    size_t first_free = (used + 1) & ~(size_t)1; /* 64-byte aligned */
    size_t need = (used / 2 + 1) * sizeof(dm__wnode);
    bvh->node_slots = used;
    bvh->node_block = *wide_block;
    bvh->node_bytes = slots * sizeof(dm__node) + 64;
    bvh->nodes = b->nodes;
    *wide_block = NULL;
    if (need <= (slots - first_free) * sizeof(dm__node)) {
        bvh->wnodes = (dm__wnode *)(void *)(bvh->nodes + first_free);
    } else {
        bvh->wide_bytes = need + 64;
        bvh->wide_block = dm__alloc_array(a, bvh->wide_bytes, 1, overflow);
        if (!bvh->wide_block) return 0;
        bvh->wnodes = (dm__wnode *)((char *)bvh->wide_block + ((64 - ((uintptr_t)bvh->wide_block & 63)) & 63));
    }
    bvh->wide_count = dm__collapse(bvh->nodes, bvh->wnodes);
    return 1;
}

/* The build pipeline: validate, triangle boxes, binned SAH splits, copy the triangles in leaf
   order, collapse the binary tree into the 8-wide traversal tree. */
DMDEF dm_result dm_bvh_build(const float *positions, size_t vertex_count, const uint32_t *indices,
                             size_t triangle_count, const dm_bvh_options *options, dm_bvh **out)
{
    dm_bvh_options opt;
    dm_allocator a;
    dm__builder b;
    dm_bvh *bvh = NULL;
    void *wide_block = NULL;
    dm_result r;
    int overflow = 0;
    float root_clo[3], root_chi[3];

    if (!out) return DM_ERR_INVALID_ARGUMENT;
    *out = NULL;
    r = dm__check_sizes(positions, vertex_count, indices, triangle_count);
    if (r != DM_OK) return r;
    opt = dm__resolve_options(options);
    a = dm__resolve_allocator(opt.allocator);
    memset(&b, 0, sizeof b);
    r = dm__ref_boxes(&b, &a, positions, vertex_count, indices, triangle_count, &overflow);
    if (r != DM_OK) goto fail;
    bvh = (dm_bvh *)a.alloc(a.user, sizeof *bvh);
    if (!bvh) goto out_of_memory;
    memset(bvh, 0, sizeof *bvh);
    bvh->allocator = a;
    bvh->triangle_count = triangle_count;
    if (!dm__builder_init(&b, &opt, &a, triangle_count, &wide_block, &overflow)) goto out_of_memory;

    /* binned SAH splits from the root down, then the triangles in leaf order and the wide tree */
    memset(&b.nodes[1], 0, sizeof b.nodes[1]);
    dm__range_bounds(&b, 0, (uint32_t)triangle_count, b.nodes[0].lo, b.nodes[0].hi, root_clo, root_chi);
    if (opt.progress && opt.progress(opt.progress_user, 0.0f)) goto cancelled;
    if (dm__build(&b, root_clo, root_chi)) goto cancelled;
    bvh->max_depth = b.max_depth;
    if (!dm__leaf_blocks(bvh, &b, &a, positions, indices, &overflow)) goto out_of_memory;
    if (!dm__wide_tree(bvh, &b, &wide_block, &a, &overflow)) goto out_of_memory;

    if (opt.progress && opt.progress(opt.progress_user, 1.0f)) goto cancelled;
    r = DM_OK;
    goto done;
out_of_memory:
    r = overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    goto fail;
cancelled:
    r = DM_CANCELLED;
fail:
    dm_bvh_free(bvh);
    bvh = NULL;
done:
    a.free(a.user, b.refs);
    a.free(a.user, wide_block);
    a.free(a.user, b.bin_store);
    a.free(a.user, b.right_area);
    a.free(a.user, b.right_count);
    *out = bvh;
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Section: refit and info
   --------------------------------------------------------------------------------------------- */

/* node i's box from its triangles (leaf) or its children (interior, already refitted) */
static void dm__refit_node(dm_bvh *bvh, size_t i)
{
    dm__node *n = &bvh->nodes[i];
    uint32_t j;
    int c;
    dm__box_empty(n->lo, n->hi);
    if (n->count) {
        for (j = 0; j < n->count; j++) {
            float p[9];
            dm__slot_triangle(bvh, (size_t)n->first + j, p);
            for (c = 0; c < 3; c++) dm__box_grow(n->lo, n->hi, p + 3 * c, p + 3 * c);
        }
    } else {
        dm__box_grow(n->lo, n->hi, bvh->nodes[n->first].lo, bvh->nodes[n->first].hi);
        dm__box_grow(n->lo, n->hi, bvh->nodes[n->first + 1].lo, bvh->nodes[n->first + 1].hi);
    }
}

DMDEF dm_result dm_bvh_refit(dm_bvh *bvh, const float *positions, size_t vertex_count,
                             const uint32_t *indices, size_t triangle_count)
{
    dm_result r;
    size_t i;
    if (!bvh) return DM_ERR_INVALID_ARGUMENT;
    r = dm__check_sizes(positions, vertex_count, indices, triangle_count);
    if (r != DM_OK) return r;
    if (triangle_count != bvh->triangle_count) return DM_ERR_INVALID_ARGUMENT;
    for (i = 0; i < triangle_count; i++) { /* validate everything before changing anything */
        float p[9];
        r = dm__fetch_triangle(positions, vertex_count, indices, i, p);
        if (r != DM_OK) return r;
    }
    for (i = 0; i < 4 * bvh->block_count; i++) { /* an unused lane copies lane 0 of its block */
        dm__tri4 *q = &bvh->blocks[i >> 2];
        uint32_t id = q->id[i & 3] != DM_NO_HIT ? q->id[i & 3] : q->id[0];
        float p[9];
        int k;
        dm__load_triangle(positions, indices, id, p);
        for (k = 0; k < 9; k++) q->v[k][i & 3] = p[k];
    }
    /* children always come after their parent: one backward pass refits bottom-up */
    for (i = bvh->node_slots; i-- > 0;)
        if (i != 1) dm__refit_node(bvh, i);
    bvh->wide_count = dm__collapse(bvh->nodes, bvh->wnodes);
    return DM_OK;
}

DMDEF void dm_bvh_get_info(const dm_bvh *bvh, dm_bvh_info *info)
{
    size_t i;
    if (!info) return;
    memset(info, 0, sizeof *info);
    if (!bvh) return;
    info->triangle_count = bvh->triangle_count;
    info->node_count = bvh->node_slots - 1;
    for (i = 0; i < bvh->node_slots; i++)
        if (i != 1 && bvh->nodes[i].count) info->leaf_count++;
    info->max_depth = bvh->max_depth;
    info->memory_bytes = sizeof *bvh + bvh->node_bytes + bvh->wide_bytes + bvh->tri_bytes;
    info->sah_cost = dm__sah_cost(bvh);
}

/* ---------------------------------------------------------------------------------------------
   Section: watertight ray/triangle test (Woop, Benthin, Wald 2013)
   --------------------------------------------------------------------------------------------- */

/* Per-ray constants: the shear that maps the ray to the +z axis (kz = largest |dir|), and
   the inverse direction for box tests (tiny components replaced by +-1e-20, so that a ray
   in a box's face plane gives 0 * big = 0, never 0 * inf = NaN). */
typedef struct dm__ray_pre {
    float org[3], dir[3], inv[3];
    int kx, ky, kz;
    float sx, sy;
    int near_off[3], far_off[3]; /* per axis, the float offset in a wide node of the near and far planes */
#if defined(DM_USE_SSE2) && !defined(DM_USE_AVX2)
    __m128 org4[3], inv4[3]; /* org and inv, each component in all four lanes (AVX broadcasts them from memory) */
#endif
} dm__ray_pre;

static int dm__prepare_ray(const float org[3], const float dir[3], float sign, dm__ray_pre *r)
{
    const float d0 = sign * dir[0], d1 = sign * dir[1], d2 = sign * dir[2];
    const float a0 = fabsf(d0), a1 = fabsf(d1), a2 = fabsf(d2);
    int kx, ky, kz;
    float dz;
    /* x - x is 0 for finite x and NaN for NaN or an infinity: one test for all six */
    if (!((org[0] - org[0]) + (org[1] - org[1]) + (org[2] - org[2]) + (d0 - d0) + (d1 - d1) + (d2 - d2) == 0.0f))
        return 0;
    kz = a0 >= a1 ? (a0 >= a2 ? 0 : 2) : (a1 >= a2 ? 1 : 2); /* the first of equal maxima */
    dz = kz == 0 ? d0 : kz == 1 ? d1 : d2;
    if (dz == 0.0f) return 0;
    r->org[0] = org[0];
    r->org[1] = org[1];
    r->org[2] = org[2];
    r->dir[0] = d0;
    r->dir[1] = d1;
    r->dir[2] = d2;
    /* 1/d with zero and subnormal components replaced by +-1e-37: inv stays finite, so 0 * inv
       is 0, never NaN, and a slab the ray runs inside spans +-1e37 or more (an infinity once a
       product overflows), beyond any hit distance the coordinates allow (a 1e-20 here missed
       hits beyond t = 1e20 on axis-parallel rays) */
    r->inv[0] = 1.0f / (a0 < 1e-37f ? (d0 < 0.0f ? -1e-37f : 1e-37f) : d0);
    r->inv[1] = 1.0f / (a1 < 1e-37f ? (d1 < 0.0f ? -1e-37f : 1e-37f) : d1);
    r->inv[2] = 1.0f / (a2 < 1e-37f ? (d2 < 0.0f ? -1e-37f : 1e-37f) : d2);
    /* a wide node is lo[3][W] then hi[3][W]: the near plane is lo when the ray goes up */
    r->near_off[0] = r->inv[0] >= 0.0f ? 0 : 3 * DM__W;
    r->near_off[1] = r->inv[1] >= 0.0f ? DM__W : 4 * DM__W;
    r->near_off[2] = r->inv[2] >= 0.0f ? 2 * DM__W : 5 * DM__W;
    r->far_off[0] = 3 * DM__W - r->near_off[0];
    r->far_off[1] = 5 * DM__W - r->near_off[1];
    r->far_off[2] = 7 * DM__W - r->near_off[2];
    kx = kz == 2 ? 0 : kz + 1;
    ky = kx == 2 ? 0 : kx + 1;
    if (dz < 0.0f) { /* keep the winding, so that U, V, W keep their signs */
        int swap = kx;
        kx = ky;
        ky = swap;
    }
    r->kx = kx;
    r->ky = ky;
    r->kz = kz;
    r->sx = r->dir[kx] / dz;
    r->sy = r->dir[ky] / dz;
#if defined(DM_USE_SSE2) && !defined(DM_USE_AVX2)
    {
        int k;
        for (k = 0; k < 3; k++) {
            r->org4[k] = _mm_set1_ps(r->org[k]);
            r->inv4[k] = _mm_set1_ps(r->inv[k]);
        }
    }
#endif
    return 1;
}

/* The edge functions decide hit or miss; the distance comes from the plane equation in double,
   t = n.(p0 - o) / n.d, rounded to float: the sheared T / det loses digits at grazing angles.
   Coordinate k of corner c is p[(3 c + k) stride] (stride 1: 9 floats; 4: a lane of a block). */
DM__INLINE float dm__plane_t(const dm__ray_pre *r, const float *p, size_t stride)
{
    double e1[3], e2[3], s[3], n0, n1, n2;
    size_t k;
    for (k = 0; k < 3; k++) {
        const double a = p[k * stride], b = p[(3 + k) * stride], c = p[(6 + k) * stride];
        e1[k] = b - a;
        e2[k] = c - a;
        s[k] = a - (double)r->org[k];
    }
    n0 = e1[1] * e2[2] - e1[2] * e2[1];
    n1 = e1[2] * e2[0] - e1[0] * e2[2];
    n2 = e1[0] * e2[1] - e1[1] * e2[0];
    return (float)((n0 * s[0] + n1 * s[1] + n2 * s[2]) / (n0 * r->dir[0] + n1 * r->dir[1] + n2 * r->dir[2]));
}

/* Hit of triangle p (9 floats) with t in [tmin, tmax]: 1 and t, u, v, else 0. The scaled
   barycentrics U, V, W are 2D edge functions of the sheared corners; a shared edge gives the
   same value with opposite sign in both triangles, so a ray cannot pass between them. Exact
   zeros are recomputed in double (section 4.4 of the paper). */
DM__INLINE int dm__triangle(const dm__ray_pre *r, const float *p, float tmin, float tmax, float *t_out,
                        float *u_out, float *v_out)
{
    const int kx = r->kx, ky = r->ky, kz = r->kz;
    const float az = p[kz] - r->org[kz], bz = p[3 + kz] - r->org[kz], cz = p[6 + kz] - r->org[kz];
    const float ax = p[kx] - r->org[kx] - r->sx * az, ay = p[ky] - r->org[ky] - r->sy * az;
    const float bx = p[3 + kx] - r->org[kx] - r->sx * bz, by = p[3 + ky] - r->org[ky] - r->sy * bz;
    const float cx = p[6 + kx] - r->org[kx] - r->sx * cz, cy = p[6 + ky] - r->org[ky] - r->sy * cz;
    float U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax, det, rcp, t;
    if ((U == 0.0f) | (V == 0.0f) | (W == 0.0f)) { /* bitwise: fewer branches to mispredict */
        U = (float)((double)cx * (double)by - (double)cy * (double)bx);
        V = (float)((double)ax * (double)cy - (double)ay * (double)cx);
        W = (float)((double)bx * (double)ay - (double)by * (double)ax);
    }
    if (((U < 0.0f) | (V < 0.0f) | (W < 0.0f)) & ((U > 0.0f) | (V > 0.0f) | (W > 0.0f))) return 0;
    det = U + V + W;
    if (det == 0.0f) return 0; /* degenerate triangle, or the ray lies in its plane */
    rcp = 1.0f / det;
    t = dm__plane_t(r, p, 1);
    if (!(t >= tmin && t <= tmax && t <= FLT_MAX)) return 0; /* NaN and inf fail too */
    *t_out = t;
    *u_out = V * rcp;
    *v_out = W * rcp;
    return 1;
}

/* The edge functions of the ray against the four triangles of block q, as in dm__triangle
   (the same float operations, so the same values). Returns the lanes that pass (all three of
   one sign, none zero) and, in *zero, the lanes where one or more are exactly zero and the
   others agree in sign, which dm__triangle decides with its double fallback. (A lane with a
   zero and both signs among the others misses in double too: nonzero floats keep their sign.)
   In terms of mn = min(U, V, W) and mx = max(U, V, W): pass is mn > 0 or mx < 0, a candidate
   mn >= 0 or mx <= 0. */
#if defined(DM_USE_SSE2)
DM__INLINE int dm__edges4(const dm__ray_pre *r, const dm__tri4 *q, float U[4], float V[4], float W[4], int *zero)
{
    const __m128 ox = _mm_set1_ps(r->org[r->kx]), oy = _mm_set1_ps(r->org[r->ky]), oz = _mm_set1_ps(r->org[r->kz]);
    const __m128 sx = _mm_set1_ps(r->sx), sy = _mm_set1_ps(r->sy), z0 = _mm_setzero_ps();
    const __m128 az = _mm_sub_ps(_mm_load_ps(q->v[r->kz]), oz);
    const __m128 bz = _mm_sub_ps(_mm_load_ps(q->v[3 + r->kz]), oz);
    const __m128 cz = _mm_sub_ps(_mm_load_ps(q->v[6 + r->kz]), oz);
    const __m128 ax = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q->v[r->kx]), ox), _mm_mul_ps(sx, az));
    const __m128 ay = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q->v[r->ky]), oy), _mm_mul_ps(sy, az));
    const __m128 bx = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q->v[3 + r->kx]), ox), _mm_mul_ps(sx, bz));
    const __m128 by = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q->v[3 + r->ky]), oy), _mm_mul_ps(sy, bz));
    const __m128 cx = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q->v[6 + r->kx]), ox), _mm_mul_ps(sx, cz));
    const __m128 cy = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(q->v[6 + r->ky]), oy), _mm_mul_ps(sy, cz));
    const __m128 u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
    const __m128 v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
    const __m128 w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
    const __m128 mn = _mm_min_ps(_mm_min_ps(u, v), w), mx = _mm_max_ps(_mm_max_ps(u, v), w);
    const int pass = _mm_movemask_ps(_mm_or_ps(_mm_cmpgt_ps(mn, z0), _mm_cmplt_ps(mx, z0)));
    const int cand = _mm_movemask_ps(_mm_or_ps(_mm_cmpge_ps(mn, z0), _mm_cmple_ps(mx, z0)));
    _mm_storeu_ps(U, u);
    _mm_storeu_ps(V, v);
    _mm_storeu_ps(W, w);
    *zero = cand & ~pass;
    return pass;
}
#else
DM__INLINE int dm__edges4(const dm__ray_pre *r, const dm__tri4 *q, float U[4], float V[4], float W[4], int *zero)
{
    const float *pax = q->v[r->kx], *pay = q->v[r->ky], *paz = q->v[r->kz];
    const float *pbx = q->v[3 + r->kx], *pby = q->v[3 + r->ky], *pbz = q->v[3 + r->kz];
    const float *pcx = q->v[6 + r->kx], *pcy = q->v[6 + r->ky], *pcz = q->v[6 + r->kz];
    const float ox = r->org[r->kx], oy = r->org[r->ky], oz = r->org[r->kz], sx = r->sx, sy = r->sy;
    float mn[4], mx[4];
    int i;
    for (i = 0; i < 4; i++) {
        const float az = paz[i] - oz, bz = pbz[i] - oz, cz = pcz[i] - oz;
        const float ax = pax[i] - ox - sx * az, ay = pay[i] - oy - sy * az;
        const float bx = pbx[i] - ox - sx * bz, by = pby[i] - oy - sy * bz;
        const float cx = pcx[i] - ox - sx * cz, cy = pcy[i] - oy - sy * cz;
        U[i] = cx * by - cy * bx;
        V[i] = ax * cy - ay * cx;
        W[i] = bx * ay - by * ax;
        mn[i] = DM__MINF(DM__MINF(U[i], V[i]), W[i]);
        mx[i] = DM__MAXF(DM__MAXF(U[i], V[i]), W[i]);
    }
    {
        const int pass = ((mn[0] > 0.0f) | (mx[0] < 0.0f)) | ((mn[1] > 0.0f) | (mx[1] < 0.0f)) << 1 |
                         ((mn[2] > 0.0f) | (mx[2] < 0.0f)) << 2 | ((mn[3] > 0.0f) | (mx[3] < 0.0f)) << 3;
        const int cand = ((mn[0] >= 0.0f) | (mx[0] <= 0.0f)) | ((mn[1] >= 0.0f) | (mx[1] <= 0.0f)) << 1 |
                         ((mn[2] >= 0.0f) | (mx[2] <= 0.0f)) << 2 | ((mn[3] >= 0.0f) | (mx[3] <= 0.0f)) << 3;
        *zero = cand & ~pass;
        return pass;
    }
}
#endif

/* Lane i of block q after dm__edges4 said it passes: the distance in double from the plane
   (as dm__triangle computes it) checked against [tmin, tmax], then u, v. */
DM__INLINE int dm__finish(const dm__ray_pre *r, const dm__tri4 *q, int i, float U, float V, float W, float tmin,
                          float tmax, float *t_out, float *u_out, float *v_out)
{
    const float rcp = 1.0f / (U + V + W);
    const float t = dm__plane_t(r, &q->v[0][i], 4);
    if (!(t >= tmin && t <= tmax && t <= FLT_MAX)) return 0;
    *t_out = t;
    *u_out = V * rcp;
    *v_out = W * rcp;
    return 1;
}

/* Hit of lane i of block q, for a lane that passed dm__edges4 (pass) or has a zero edge
   function (decided by dm__triangle). */
DM__INLINE int dm__lane_hit(const dm__ray_pre *r, const dm__tri4 *q, int i, int pass, const float *U,
                            const float *V, const float *W, float tmin, float tmax, float *t, float *u, float *v)
{
    float p[9];
    int k;
    if (pass) return dm__finish(r, q, i, U[i], V[i], W[i], tmin, tmax, t, u, v);
    for (k = 0; k < 9; k++) p[k] = q->v[k][i];
    return dm__triangle(r, p, tmin, tmax, t, u, v);
}

/* the lanes of a leaf's block that hold its triangles, given how many are left */
#define DM__LANES(left) ((left) >= 4 ? 15 : (1 << (left)) - 1)

/* ---------------------------------------------------------------------------------------------
   Section: traversal (near child first, Ize's conservative box test)
   --------------------------------------------------------------------------------------------- */

/* 1 + 2 gamma(3) rounded up: widens the far distance so that rounding in the slab test never
   culls a box the ray touches (Ize 2013) */
#define DM__FAR_SCALE 1.00000036f

/* The child boxes of a wide node: bit i of the result tells whether the ray enters child i
   within [tmin, tmax], t[i] its entry distance. Per axis the ray meets the near plane (lo when
   it goes up, hi when it goes down) first, so no per-axis min/max is needed. The maxima and minima are ordered so that a NaN (the boxes of unused
   slots) reaches the final comparison, which it fails; MINF/MAXF return the second operand
   when either is NaN, as the SSE and AVX instructions do, so every path gives the same bits. */
#if defined(DM_USE_AVX2)
DM__INLINE int dm__boxw(const dm__wnode *n, const dm__ray_pre *r, float tmin, float tmax, float t[DM__W])
{
    const float *f = &n->lo[0][0];
    const __m256 ox = _mm256_broadcast_ss(&r->org[0]), oy = _mm256_broadcast_ss(&r->org[1]), oz = _mm256_broadcast_ss(&r->org[2]);
    const __m256 ix = _mm256_broadcast_ss(&r->inv[0]), iy = _mm256_broadcast_ss(&r->inv[1]), iz = _mm256_broadcast_ss(&r->inv[2]);
    const __m256 nx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(f + r->near_off[0]), ox), ix);
    const __m256 ny = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(f + r->near_off[1]), oy), iy);
    const __m256 nz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(f + r->near_off[2]), oz), iz);
    const __m256 fx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(f + r->far_off[0]), ox), ix);
    const __m256 fy = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(f + r->far_off[1]), oy), iy);
    const __m256 fz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(f + r->far_off[2]), oz), iz);
    const __m256 tn = _mm256_max_ps(_mm256_set1_ps(tmin), _mm256_max_ps(nz, _mm256_max_ps(ny, nx)));
    const __m256 tf = _mm256_min_ps(_mm256_set1_ps(tmax),
                                    _mm256_mul_ps(_mm256_min_ps(fz, _mm256_min_ps(fy, fx)), _mm256_set1_ps(DM__FAR_SCALE)));
    _mm256_storeu_ps(t, tn);
    return _mm256_movemask_ps(_mm256_cmp_ps(tn, tf, _CMP_LE_OQ));
}
#elif defined(DM_USE_SSE2)
DM__INLINE int dm__boxw(const dm__wnode *n, const dm__ray_pre *r, float tmin, float tmax, float t[DM__W])
{
    const __m128 lo = _mm_set1_ps(tmin), hi = _mm_set1_ps(tmax), scale = _mm_set1_ps(DM__FAR_SCALE);
    int h, mask = 0;
    for (h = 0; h < DM__W; h += 4) {
        const float *f = &n->lo[0][h];
        const __m128 nx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + r->near_off[0]), r->org4[0]), r->inv4[0]);
        const __m128 ny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + r->near_off[1]), r->org4[1]), r->inv4[1]);
        const __m128 nz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + r->near_off[2]), r->org4[2]), r->inv4[2]);
        const __m128 fx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + r->far_off[0]), r->org4[0]), r->inv4[0]);
        const __m128 fy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + r->far_off[1]), r->org4[1]), r->inv4[1]);
        const __m128 fz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f + r->far_off[2]), r->org4[2]), r->inv4[2]);
        const __m128 tn = _mm_max_ps(lo, _mm_max_ps(nz, _mm_max_ps(ny, nx)));
        const __m128 tf = _mm_min_ps(hi, _mm_mul_ps(_mm_min_ps(fz, _mm_min_ps(fy, fx)), scale));
        _mm_storeu_ps(t + h, tn);
        mask |= _mm_movemask_ps(_mm_cmple_ps(tn, tf)) << h;
    }
    return mask;
}
#else
DM__INLINE int dm__boxw(const dm__wnode *n, const dm__ray_pre *r, float tmin, float tmax, float t[DM__W])
{
    /* written lane by lane over arrays, so that compilers may vectorize it */
    const float *f = &n->lo[0][0];
    const float *nx = f + r->near_off[0], *ny = f + r->near_off[1], *nz = f + r->near_off[2];
    const float *fx = f + r->far_off[0], *fy = f + r->far_off[1], *fz = f + r->far_off[2];
    float tf[DM__W];
    int i, mask = 0;
    for (i = 0; i < DM__W; i++) {
        const float x0 = (nx[i] - r->org[0]) * r->inv[0], x1 = (fx[i] - r->org[0]) * r->inv[0];
        const float y0 = (ny[i] - r->org[1]) * r->inv[1], y1 = (fy[i] - r->org[1]) * r->inv[1];
        const float z0 = (nz[i] - r->org[2]) * r->inv[2], z1 = (fz[i] - r->org[2]) * r->inv[2];
        t[i] = DM__MAXF(tmin, DM__MAXF(z0, DM__MAXF(y0, x0)));
        tf[i] = DM__MINF(tmax, DM__MINF(z1, DM__MINF(y1, x1)) * DM__FAR_SCALE);
    }
    for (i = 0; i < DM__W; i++) mask |= (t[i] <= tf[i]) << i;
    return mask;
}
#endif

/* A subtree waiting on the traversal stack: a wide node (count 0) or a leaf, and the ray's
   entry distance into its box. A wide node pushes at most DM__W - 1 entries and the wide tree
   is no deeper than the binary one (below DM__STACK). */
typedef struct dm__entry {
    uint32_t ref, count;
    float t;
} dm__entry;
#define DM__WSTACK ((DM__W - 1) * DM__STACK)

/* Start loading child i: the four cache lines of a wide node, or the first three of a leaf
   (its first block and a half), so that they arrive while the other children are ordered.
   DM__PREFETCH_LINES (compile time, default 4) sets how many; 0 turns it off. */
#ifndef DM__PREFETCH_LINES
#define DM__PREFETCH_LINES 4
#endif
#if DM__PREFETCH_LINES > 0
#define DM__PREFETCH_CHILD(wn, tris, n, i)                                                       \
    do {                                                                                         \
        const char *p_ = (n)->count[i] ? (const char *)&(tris)[(n)->ref[i] >> 2]                  \
                                       : (const char *)&(wn)[(n)->ref[i]];                        \
        DM__PREFETCH(p_);                                                                        \
        if (DM__PREFETCH_LINES > 1) DM__PREFETCH(p_ + 64);                                       \
        if (DM__PREFETCH_LINES > 2) DM__PREFETCH(p_ + 128);                                      \
        if (DM__PREFETCH_LINES > 3 && (!(n)->count[i] || (n)->count[i] > 4)) DM__PREFETCH(p_ + 192); \
        if (DM__PREFETCH_LINES > 4 && (n)->count[i] > 4) DM__PREFETCH(p_ + 256);                 \
    } while (0)
#else
#define DM__PREFETCH_CHILD(wn, tris, n, i) ((void)0)
#endif

/* index of the lowest set bit of x != 0 */
#if defined(__GNUC__) || defined(__clang__)
#define DM__CTZ(x) ((uint32_t)__builtin_ctz(x))
#else
DM__INLINE uint32_t DM__CTZ(uint32_t x)
{
    uint32_t n = 0;
    while (!(x & 1u)) {
        x >>= 1;
        n++;
    }
    return n;
}
#endif

#if defined(DM_USE_AVX2)
/* dm__edges4 for the eight triangles of blocks q[0] and q[1] at once: the same operations
   lane by lane, so the same bits. */
#define DM__LOAD8(q, row) _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps((q)[0].v[row])), _mm_load_ps((q)[1].v[row]), 1)
DM__INLINE int dm__edges8(const dm__ray_pre *r, const dm__tri4 *q, float U[8], float V[8], float W[8], int *zero)
{
    const __m256 ox = _mm256_set1_ps(r->org[r->kx]), oy = _mm256_set1_ps(r->org[r->ky]), oz = _mm256_set1_ps(r->org[r->kz]);
    const __m256 sx = _mm256_set1_ps(r->sx), sy = _mm256_set1_ps(r->sy), z0 = _mm256_setzero_ps();
    const __m256 az = _mm256_sub_ps(DM__LOAD8(q, r->kz), oz);
    const __m256 bz = _mm256_sub_ps(DM__LOAD8(q, 3 + r->kz), oz);
    const __m256 cz = _mm256_sub_ps(DM__LOAD8(q, 6 + r->kz), oz);
    const __m256 ax = _mm256_sub_ps(_mm256_sub_ps(DM__LOAD8(q, r->kx), ox), _mm256_mul_ps(sx, az));
    const __m256 ay = _mm256_sub_ps(_mm256_sub_ps(DM__LOAD8(q, r->ky), oy), _mm256_mul_ps(sy, az));
    const __m256 bx = _mm256_sub_ps(_mm256_sub_ps(DM__LOAD8(q, 3 + r->kx), ox), _mm256_mul_ps(sx, bz));
    const __m256 by = _mm256_sub_ps(_mm256_sub_ps(DM__LOAD8(q, 3 + r->ky), oy), _mm256_mul_ps(sy, bz));
    const __m256 cx = _mm256_sub_ps(_mm256_sub_ps(DM__LOAD8(q, 6 + r->kx), ox), _mm256_mul_ps(sx, cz));
    const __m256 cy = _mm256_sub_ps(_mm256_sub_ps(DM__LOAD8(q, 6 + r->ky), oy), _mm256_mul_ps(sy, cz));
    const __m256 u = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
    const __m256 v = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
    const __m256 w = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
    const __m256 mn = _mm256_min_ps(_mm256_min_ps(u, v), w), mx = _mm256_max_ps(_mm256_max_ps(u, v), w);
    const int pass = _mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(mn, z0, _CMP_GT_OQ), _mm256_cmp_ps(mx, z0, _CMP_LT_OQ)));
    const int cand = _mm256_movemask_ps(_mm256_or_ps(_mm256_cmp_ps(mn, z0, _CMP_GE_OQ), _mm256_cmp_ps(mx, z0, _CMP_LE_OQ)));
    _mm256_storeu_ps(U, u);
    _mm256_storeu_ps(V, v);
    _mm256_storeu_ps(W, w);
    *zero = cand & ~pass;
    return pass;
}
#endif

/* The candidate lanes of the next one or two blocks of a leaf with left triangles to go:
   fills U, V, W (8 each), *pass (lanes decided in float) and sets *nb to the blocks taken. */
DM__INLINE int dm__leaf_lanes(const dm__ray_pre *r, const dm__tri4 *q, uint32_t left, float *U, float *V, float *W,
                              int *pass, int *nb)
{
    int zero;
#if defined(DM_USE_AVX2)
    if (left > 4) {
        *pass = dm__edges8(r, q, U, V, W, &zero);
        *nb = 2;
        return (*pass | zero) & (left >= 8 ? 255 : (1 << left) - 1);
    }
#endif
    *pass = dm__edges4(r, q, U, V, W, &zero);
    *nb = 1;
    return (*pass | zero) & DM__LANES(left);
}

/* Visits a wide node's hit children (mask, entry distances te) nearest first: the nearest
   becomes the current subtree (*ref, *count); the others are pushed, farthest deepest. Equal
   distances keep the slot order. */
#define DM__ORDER_CHILDREN(n, mask, te, stack, sp, ref, count)                                   \
    do {                                                                                         \
        uint32_t m_ = (uint32_t)(mask), i_ = DM__CTZ(m_), j_;                                    \
        m_ &= m_ - 1;                                                                            \
        DM__PREFETCH_CHILD(wn, tris, n, i_);                                                     \
        if (m_) {                                                                                \
            j_ = DM__CTZ(m_);                                                                    \
            m_ &= m_ - 1;                                                                        \
            DM__PREFETCH_CHILD(wn, tris, n, j_);                                                 \
            if (!m_) { /* two: push the farther */                                               \
                if (te[j_] < te[i_]) {                                                           \
                    uint32_t s_ = i_;                                                            \
                    i_ = j_;                                                                     \
                    j_ = s_;                                                                     \
                }                                                                                \
                stack[sp].ref = (n)->ref[j_];                                                    \
                stack[sp].count = (n)->count[j_];                                                \
                stack[sp++].t = te[j_];                                                          \
            } else { /* three or more: push all, sort the new entries, take the nearest */       \
                size_t b_ = sp, k_;                                                              \
                stack[sp].ref = (n)->ref[i_];                                                    \
                stack[sp].count = (n)->count[i_];                                                \
                stack[sp++].t = te[i_];                                                          \
                m_ |= 1u << j_;                                                                  \
                do {                                                                             \
                    dm__entry e_;                                                                \
                    j_ = DM__CTZ(m_);                                                            \
                    m_ &= m_ - 1;                                                                \
                    DM__PREFETCH_CHILD(wn, tris, n, j_);                                         \
                    e_.ref = (n)->ref[j_];                                                       \
                    e_.count = (n)->count[j_];                                                   \
                    e_.t = te[j_];                                                               \
                    /* insertion: nearer entries (and equal ones, being later slots) go deeper */ \
                    for (k_ = sp++; k_ > b_ && stack[k_ - 1].t < e_.t; k_--) stack[k_] = stack[k_ - 1]; \
                    stack[k_] = e_;                                                              \
                } while (m_);                                                                    \
                sp--;                                                                            \
                ref = stack[sp].ref;                                                             \
                count = stack[sp].count;                                                         \
                break;                                                                           \
            }                                                                                    \
        }                                                                                        \
        ref = (n)->ref[i_];                                                                      \
        count = (n)->count[i_];                                                                  \
    } while (0)

/* Nearest hit in [tmin, tmax]; equal t goes to the lower triangle id (whatever the order of
   the visit). The hit children of a wide node are visited nearest first; the others wait on
   the stack with their entry distance and are skipped when a hit closer than that has been
   found. */
static int dm__closest_hit(const dm_bvh *bvh, const dm__ray_pre *r, float tmin, float tmax, dm_hit *hit)
{
    const dm__wnode *wn = bvh->wnodes;
    const dm__tri4 *tris = bvh->blocks;
    dm__entry stack[DM__WSTACK];
    uint32_t ref = 0, count = 0, best_id = DM_NO_HIT;
    float best = tmax, bu = 0.0f, bv = 0.0f;
    size_t sp = 0;
    for (;;) {
        if (count) {
            const dm__tri4 *q = &tris[ref >> 2];
            uint32_t left = count;
            for (;;) {
                float U[8], V[8], W[8];
                int pass, nb, m = dm__leaf_lanes(r, q, left, U, V, W, &pass, &nb);
                while (m) {
                    const int i = (int)DM__CTZ((uint32_t)m), b = i >> 2, l = i & 3;
                    float t, u, v;
                    m &= m - 1;
                    if (dm__lane_hit(r, q + b, l, (pass >> i) & 1, U + 4 * b, V + 4 * b, W + 4 * b, tmin, best, &t,
                                     &u, &v) &&
                        (t < best || q[b].id[l] < best_id)) {
                        best = t;
                        best_id = q[b].id[l];
                        bu = u;
                        bv = v;
                    }
                }
                if (left <= 4 * (uint32_t)nb) break;
                left -= 4 * (uint32_t)nb;
                q += nb;
            }
        } else {
            const dm__wnode *n = &wn[ref];
            float te[DM__W];
            int mask = dm__boxw(n, r, tmin, best, te);
            if (mask) {
                DM__ORDER_CHILDREN(n, mask, te, stack, sp, ref, count);
                continue;
            }
        }
        for (;;) {
            if (sp == 0) goto done;
            sp--;
            if (stack[sp].t <= best) {
                ref = stack[sp].ref;
                count = stack[sp].count;
                break;
            }
        }
    }
done:
    if (best_id == DM_NO_HIT) return 0;
    hit->t = best;
    hit->u = bu;
    hit->v = bv;
    hit->triangle = best_id;
    return 1;
}

/* Every hit in [tmin, tmax], up to cap of them, into out (in traversal order, children in slot
   order); returns their number, or cap + 1 when there are more (so cap 0 is an any-hit query that
   ends at the first). The hits are those dm__closest_hit would find with the same ray and bounds:
   the same test per triangle. */
static size_t dm__all_hits(const dm_bvh *bvh, const dm__ray_pre *r, float tmin, float tmax, dm_hit *out, size_t cap)
{
    const dm__wnode *wn = bvh->wnodes;
    const dm__tri4 *tris = bvh->blocks;
    dm__entry stack[DM__WSTACK];
    uint32_t ref = 0, count = 0;
    size_t sp = 0, n = 0;
    for (;;) {
        if (count) {
            const dm__tri4 *q = &tris[ref >> 2];
            uint32_t left = count;
            for (;;) {
                float U[8], V[8], W[8];
                int pass, nb, m = dm__leaf_lanes(r, q, left, U, V, W, &pass, &nb);
                while (m) {
                    const int i = (int)DM__CTZ((uint32_t)m), b = i >> 2, l = i & 3;
                    float t, u, v;
                    m &= m - 1;
                    if (dm__lane_hit(r, q + b, l, (pass >> i) & 1, U + 4 * b, V + 4 * b, W + 4 * b, tmin, tmax, &t,
                                     &u, &v)) {
                        if (n == cap) return cap + 1;
                        out[n].t = t;
                        out[n].u = u;
                        out[n].v = v;
                        out[n++].triangle = q[b].id[l];
                    }
                }
                if (left <= 4 * (uint32_t)nb) break;
                left -= 4 * (uint32_t)nb;
                q += nb;
            }
        } else {
            const dm__wnode *nd = &wn[ref];
            float te[DM__W];
            int mask = dm__boxw(nd, r, tmin, tmax, te);
            if (mask) {
                uint32_t i, m = (uint32_t)mask, take = DM__CTZ(m);
                DM__PREFETCH_CHILD(wn, tris, nd, take);
                for (m &= m - 1; m; m &= m - 1) {
                    i = DM__CTZ(m);
                    DM__PREFETCH_CHILD(wn, tris, nd, i);
                    stack[sp].ref = nd->ref[i];
                    stack[sp].count = nd->count[i];
                    stack[sp++].t = te[i];
                }
                ref = nd->ref[take];
                count = nd->count[take];
                continue;
            }
        }
        if (sp == 0) return n;
        sp--;
        ref = stack[sp].ref;
        count = stack[sp].count;
    }
}

/* Of the n hits in h, the nearest at or beyond tmin (the lower triangle id on a tie, as
   dm__closest_hit chooses); NULL if none. */
static const dm_hit *dm__first_hit_from(const dm_hit *h, size_t n, float tmin)
{
    const dm_hit *best = NULL;
    size_t i;
    for (i = 0; i < n; i++)
        if (h[i].t >= tmin && (!best || h[i].t < best->t || (h[i].t == best->t && h[i].triangle < best->triangle)))
            best = h + i;
    return best;
}

/* Any hit in [tmin, tmax]: the first one found ends the search. */
static int dm__any_hit(const dm_bvh *bvh, const dm__ray_pre *r, float tmin, float tmax)
{
    return dm__all_hits(bvh, r, tmin, tmax, NULL, 0) > 0;
}

static void dm__clear_hit(dm_hit *hit)
{
    hit->t = hit->u = hit->v = 0.0f;
    hit->triangle = DM_NO_HIT;
}

DMDEF int dm_bvh_intersect(const dm_bvh *bvh, const dm_ray *ray, dm_hit *hit)
{
    dm__ray_pre r;
    if (!hit) return 0;
    dm__clear_hit(hit);
    if (!bvh || !ray || !(ray->tmin <= ray->tmax)) return 0;
    if (!dm__prepare_ray(ray->org, ray->dir, 1.0f, &r)) return 0;
    return dm__closest_hit(bvh, &r, ray->tmin, ray->tmax, hit);
}

DMDEF int dm_bvh_occluded(const dm_bvh *bvh, const dm_ray *ray)
{
    dm__ray_pre r;
    if (!bvh || !ray || !(ray->tmin <= ray->tmax)) return 0;
    if (!dm__prepare_ray(ray->org, ray->dir, 1.0f, &r)) return 0;
    return dm__any_hit(bvh, &r, ray->tmin, ray->tmax);
}

/* Two rays from the origin: forward over [max(tmin, 0), tmax], then backward (direction
   negated, s = -t) over [max(-tmax, 0), -tmin] limited to the forward hit's distance. */
DMDEF int dm_bvh_intersect_line(const dm_bvh *bvh, const dm_ray *ray, dm_hit *hit)
{
    dm__ray_pre r;
    dm_hit fwd, back;
    int have_fwd = 0, have_back = 0;
    if (!hit) return 0;
    dm__clear_hit(hit);
    dm__clear_hit(&fwd);
    dm__clear_hit(&back);
    if (!bvh || !ray || !(ray->tmin <= ray->tmax)) return 0;
    if (ray->tmax >= 0.0f) {
        if (!dm__prepare_ray(ray->org, ray->dir, 1.0f, &r)) return 0;
        have_fwd = dm__closest_hit(bvh, &r, ray->tmin > 0.0f ? ray->tmin : 0.0f, ray->tmax, &fwd);
    }
    if (ray->tmin <= 0.0f) {
        float smax = -ray->tmin;
        if (have_fwd && fwd.t < smax) smax = fwd.t;
        if (!dm__prepare_ray(ray->org, ray->dir, -1.0f, &r)) return 0;
        have_back = dm__closest_hit(bvh, &r, ray->tmax < 0.0f ? -ray->tmax : 0.0f, smax, &back);
    }
    if (have_back && (!have_fwd || back.t < fwd.t || (back.t == fwd.t && back.triangle < fwd.triangle))) {
        *hit = back;
        hit->t = -back.t;
        return 1;
    }
    if (have_fwd) *hit = fwd;
    return have_fwd;
}

DMDEF size_t dm_bvh_intersect_batch(const dm_bvh *bvh, const dm_ray *rays, size_t count, dm_hit *hits)
{
    size_t i, n = 0;
    if (!rays || !hits) return 0;
    for (i = 0; i < count; i++) n += (size_t)dm_bvh_intersect(bvh, &rays[i], &hits[i]);
    return n;
}

DMDEF size_t dm_bvh_occluded_batch(const dm_bvh *bvh, const dm_ray *rays, size_t count,
                                   unsigned char *occluded)
{
    size_t i, n = 0;
    if (!rays || !occluded) return 0;
    for (i = 0; i < count; i++) {
        occluded[i] = (unsigned char)dm_bvh_occluded(bvh, &rays[i]);
        n += occluded[i];
    }
    return n;
}

/* ---------------------------------------------------------------------------------------------
   Section: closest point (Ericson 2005, 5.1.5), in double
   --------------------------------------------------------------------------------------------- */

/* squared distance from p to segment a + s (b - a), s in [0, 1]; *s receives s */
static double dm__segment_d2(const double p[3], const double a[3], const double b[3], double *s)
{
    double ab[3], ap[3], len2, d2 = 0.0;
    int k;
    for (k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    len2 = dm__dot3(ab, ab);
    *s = len2 > 0.0 ? dm__dot3(ap, ab) / len2 : 0.0;
    *s = *s < 0.0 ? 0.0 : (*s > 1.0 ? 1.0 : *s);
    for (k = 0; k < 3; k++) {
        double e = ap[k] - *s * ab[k];
        d2 += e * e;
    }
    return d2;
}

/* Squared distance from p to triangle (a, b, c) and the closest point's barycentrics u (of b)
   and v (of c). Ericson's Voronoi-region walk; a degenerate triangle, where the interior
   formula divides by zero, takes the nearest of its three edges. */
static double dm__triangle_d2(const double p[3], const double tri[9], double *u_out, double *v_out)
{
    double a[3], b[3], c[3], ab[3], ac[3], ap[3], bp[3], cp[3];
    double d1, d2, d3, d4, d5, d6, va, vb, vc, u, v, q[3], dist2 = 0.0, s;
    int k;
    for (k = 0; k < 3; k++) {
        a[k] = tri[k];
        b[k] = tri[3 + k];
        c[k] = tri[6 + k];
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
        bp[k] = p[k] - b[k];
        cp[k] = p[k] - c[k];
    }
    d1 = dm__dot3(ab, ap);
    d2 = dm__dot3(ac, ap);
    d3 = dm__dot3(ab, bp);
    d4 = dm__dot3(ac, bp);
    d5 = dm__dot3(ab, cp);
    d6 = dm__dot3(ac, cp);
    vc = d1 * d4 - d3 * d2;
    vb = d5 * d2 - d1 * d6;
    va = d3 * d6 - d5 * d4;
    if (!(va + vb + vc > 0.0)) { /* degenerate: nearest edge */
        double best, e;
        best = dm__segment_d2(p, a, b, &s);
        u = s;
        v = 0.0;
        e = dm__segment_d2(p, a, c, &s);
        if (e < best) {
            best = e;
            u = 0.0;
            v = s;
        }
        e = dm__segment_d2(p, b, c, &s);
        if (e < best) {
            best = e;
            u = 1.0 - s;
            v = s;
        }
        *u_out = u;
        *v_out = v;
        return best;
    }
    if (d1 <= 0.0 && d2 <= 0.0) u = 0.0, v = 0.0;                                 /* vertex a */
    else if (d3 >= 0.0 && d4 <= d3) u = 1.0, v = 0.0;                             /* vertex b */
    else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) u = d1 / (d1 - d3), v = 0.0;   /* edge ab */
    else if (d6 >= 0.0 && d5 <= d6) u = 0.0, v = 1.0;                             /* vertex c */
    else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) u = 0.0, v = d2 / (d2 - d6);   /* edge ac */
    else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {                    /* edge bc */
        v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        u = 1.0 - v;
    } else { /* inside */
        double inv = 1.0 / (va + vb + vc);
        u = vb * inv;
        v = vc * inv;
    }
    for (k = 0; k < 3; k++) {
        q[k] = a[k] + u * ab[k] + v * ac[k];
        dist2 += (p[k] - q[k]) * (p[k] - q[k]);
    }
    *u_out = u;
    *v_out = v;
    return dist2;
}

static double dm__box_d2(const dm__node *n, const double p[3])
{
    double d2 = 0.0;
    int k;
    for (k = 0; k < 3; k++) {
        double e = (double)n->lo[k] - p[k];
        if (e < 0.0) e = p[k] - (double)n->hi[k];
        if (e > 0.0) d2 += e * e;
    }
    return d2;
}

DMDEF int dm_bvh_closest_point(const dm_bvh *bvh, const float point[3], float max_distance, dm_closest *out)
{
    uint32_t stack[DM__STACK], ni = 0, best_id = DM_NO_HIT, best_slot = 0;
    double stack_d2[DM__STACK], p[3], best, bu = 0.0, bv = 0.0;
    size_t sp = 0;
    int k;
    if (!out) return 0;
    memset(out, 0, sizeof *out);
    out->triangle = DM_NO_HIT;
    if (!bvh || !point || !(max_distance >= 0.0f)) return 0;
    for (k = 0; k < 3; k++) {
        if (!(point[k] >= -FLT_MAX && point[k] <= FLT_MAX)) return 0;
        p[k] = point[k];
    }
    best = (double)max_distance * (double)max_distance; /* inf stays inf */
    if (dm__box_d2(&bvh->nodes[0], p) > best) return 0;
    for (;;) {
        const dm__node *n = &bvh->nodes[ni];
        if (n->count) {
            uint32_t i;
            for (i = n->first; i < n->first + n->count; i++) {
                float tri[9];
                uint32_t id = bvh->blocks[i >> 2].id[i & 3];
                double u, v, d2, td[9];
                int k;
                dm__slot_triangle(bvh, i, tri);
                for (k = 0; k < 9; k++) td[k] = tri[k];
                d2 = dm__triangle_d2(p, td, &u, &v);
                if (d2 < best || (d2 == best && id < best_id)) {
                    best = d2;
                    best_id = id;
                    best_slot = i;
                    bu = u;
                    bv = v;
                }
            }
        } else {
            double d0 = dm__box_d2(&bvh->nodes[n->first], p), d1 = dm__box_d2(&bvh->nodes[n->first + 1], p);
            int h0 = d0 <= best, h1 = d1 <= best;
            if (h0 && h1) {
                int far_first = d1 < d0;
                ni = n->first + (uint32_t)far_first;
                stack[sp] = n->first + (uint32_t)!far_first;
                stack_d2[sp++] = far_first ? d0 : d1;
                continue;
            }
            if (h0 | h1) {
                ni = n->first + (uint32_t)h1;
                continue;
            }
        }
        for (;;) {
            if (sp == 0) goto done;
            sp--;
            if (stack_d2[sp] <= best) {
                ni = stack[sp];
                break;
            }
        }
    }
done:
    if (best_id == DM_NO_HIT) return 0;
    for (k = 0; k < 3; k++) {
        float t[9];
        dm__slot_triangle(bvh, best_slot, t);
        out->point[k] = (float)((1.0 - bu - bv) * t[k] + bu * t[3 + k] + bv * t[6 + k]);
    }
    out->distance = (float)sqrt(best);
    out->u = (float)bu;
    out->v = (float)bv;
    out->triangle = best_id;
    return 1;
}

/* ---------------------------------------------------------------------------------------------
   Section: QEM simplification (Garland-Heckbert 1997) with progressive-mesh records (Hoppe 1996)
   --------------------------------------------------------------------------------------------- */

#define DM__QEM_V_BOUNDARY 1u    /* on an open boundary */
#define DM__QEM_V_LOCKED 2u      /* never moved or removed; a free neighbour may merge into it */
#define DM__QEM_V_FROZEN 4u      /* non-manifold: never collapsed */
#define DM__QEM_V_REMOVED 8u     /* merged into another vertex */
#define DM__QEM_V_PARKED 16u     /* a candidate of it was refused: retried when its one-ring changes */
#define DM__QEM_V_NONMANIFOLD 32u
#define DM__QEM_NONE 0xffffffffu
#define DM__QEM_BOUNDARY_WEIGHT 10.0 /* boundary planes weigh this times the squared edge length */
#define DM__QEM_REQUEUE 2.0          /* a moved candidate costing more than this times its queued cost waits */
#define DM__QEM_RELAX_COST 16.0      /* dm_simplify_options.relax_cost's default */
#define DM__QEM_MIN_COS 0.2          /* a triangle's normal may turn by at most acos(0.2) = 78 degrees */
#define DM__QEM_MIN_SIN 1e-5         /* new triangles: 2 area > DM__QEM_MIN_SIN * longest edge^2 */
#define DM__QEM_ADJ_MAX 0xfffffff0u  /* the corner pool's offsets are 32-bit */
#if defined(__GNUC__) || defined(__clang__)
#define DM__QEM_PREFETCH(p) __builtin_prefetch(p)
#else
#define DM__QEM_PREFETCH(p) ((void)0)
#endif

/* Q(x) = x^T A x + 2 b^T x + c, A symmetric; w is the total weight (area) of its planes. */
typedef struct dm__qem_quadric {
    double a00, a01, a02, a11, a12, a22, b0, b1, b2, c, w;
} dm__qem_quadric;

/* A heap entry (16 bytes): the edge (a < b) with its cost when the sum of its endpoints'
   versions was `stamp` (versions only grow, so any change to either makes the entry stale).
   key = the cost's float bits (a non-negative float orders like its bits) above a, so one
   integer compare orders by cost, then by the lower vertex id. */
typedef struct dm__qem_cand {
    uint64_t key;
    uint32_t b, stamp;
} dm__qem_cand;

#define DM__QEM_CAND_A(e) ((uint32_t)((e)->key & 0xffffffffu))
#define DM__QEM_RETRY 0x80000000u /* in stamp: a vetoed candidate queued again, to be asked relaxed */
/* the next and previous slot of a triangle (0 1 2), by shifts: a ternary here compiles to a
   branch that mispredicts a third of the time */
#define DM__QEM_NEXT(slot) ((0x09u >> (2u * (slot))) & 3u)
#define DM__QEM_PREV(slot) ((0x12u >> (2u * (slot))) & 3u)

/* A radix heap (Ahuja, Mehlhorn, Orlin, Tarjan 1990) over the 64-bit keys: bucket 0 holds keys
   equal to the last popped one, bucket i > 0 the keys whose highest bit differing from it is
   bit i - 1. Pushes append; a pop that finds bucket 0 empty takes the first non-empty bucket,
   makes its smallest key the new `last` and spreads it over the buckets below. Every access is
   sequential, where a binary or 4-ary heap of a million entries misses the cache at every level
   of every pop. Keys must not go below the last popped one: a new candidate cheaper than that
   (placement keeps Q(x) of a merged quadric close to monotone, not exactly) is queued at the
   last popped cost, i.e. next. A bucket is a stack of 4 KiB chunks taken from a free list, so
   spreading a bucket moves entries without ever copying a whole array.
   The radix is 8, not 2: a key goes by the highest octal digit (3 bits) where it differs from
   the last popped key, and by its own value of that digit: bucket 1 + 8 d + value. The buckets
   are still in key order, and the entries of a spread bucket agree with its smallest key on
   that digit too, so each spread sends them at least a whole digit (3 bits) down (bunny to
   10%: 3.4 bucket writes per queued candidate with radix 2, 2.6 with radix 8; the order of
   collapses is the same). A bitmap finds the first non-empty bucket. */
#define DM__QEM_BUCKETS (1 + 22 * 8)
#define DM__QEM_MASKWORDS ((DM__QEM_BUCKETS + 63) / 64)
#define DM__QEM_CHUNK 255
typedef struct dm__qem_chunk {
    struct dm__qem_chunk *next; /* the older (full) chunks of the bucket, or the free list */
    dm__qem_cand e[DM__QEM_CHUNK];
} dm__qem_chunk;
typedef struct dm__qem_bucket {
    dm__qem_chunk *top; /* the chunk being filled, NULL when empty */
    size_t fill;        /* entries in top (DM__QEM_CHUNK when empty: the next add takes a chunk) */
    size_t n;           /* entries in the bucket */
} dm__qem_bucket;
#define DM__QEM_CHUNKS_PER_BLOCK 64

/* One collapse: `dead` triangle ids then `moved` corner ids (3 triangle + slot) at ops[first]. */
typedef struct dm__qem_rec {
    size_t first;
    uint32_t keep, remove, dead, moved;
    float before[3], after[3];
} dm__qem_rec;

struct dm_pm {
    dm_allocator alloc;
    size_t vertex_count, triangle_count, split_count, level, live_triangles, live_vertices;
    float *pos;         /* 3 per input vertex */
    uint32_t *idx;      /* 3 per triangle (input order, repeated-index triangles dropped) */
    uint8_t *alive;     /* per triangle */
    dm__qem_rec *rec;       /* collapses in the order done */
    uint32_t *ops;
    uint32_t *merge_first, *merge_list; /* base vertex -> input vertices merged into it */
    uint32_t *scratch;  /* vertex_count, for dm_pm_get_mesh */
};

/* Everything the simplifier reads about one vertex, in one 128-byte record (two cache lines when
   the array is 64-byte aligned): a collapse visits a few dozen vertices at random places of the
   mesh, and one record costs two cache misses where separate arrays cost seven. */
typedef struct dm__qem_vert {
    dm__qem_quadric q;     /* 88 bytes */
    double np[3];          /* the position (pos) in the normalised frame */
    uint32_t first, count; /* its live corners: adj[first .. first + count) */
    uint32_t mark;         /* visit stamp */
    uint32_t flag;         /* DM__QEM_V_* */
} dm__qem_vert;

typedef struct dm__qem_simp {
    dm_allocator al;
    const dm_simplify_options *opt;
    size_t n, t, live, target;
    float *pos;
    uint32_t *idx;
    uint8_t *alive;
    dm__qem_vert *vx;              /* n records, 64-byte aligned inside vraw */
    void *vraw;
    uint32_t *adj;                 /* corner lists (3 triangle + slot), each after a 2-word header
                                      (owner, length); a collapse appends keep's new list */
    size_t adjend, adjcap;
    uint32_t stamp;
    uint32_t *nbr;                 /* scratch, n: neighbours of one vertex */
    size_t nnbr;
    uint32_t *ring;                /* scratch, 3 t: the new one-ring for the constraint */
    uint32_t *oring;               /* scratch, 3 t: the old triangles of keep and remove (constraint only) */
    uint32_t *ver;                 /* per vertex, candidate version: bumped when its edges change
                                      (a dense array: the stale checks touch nothing else) */
    uint32_t *slots;               /* per vertex, the words its list fills in adj: its live corners
                                      and the dropped ones not yet swept out (dm__qem_drop_corner) */
    dm__qem_bucket bucket[DM__QEM_BUCKETS]; /* the candidates: a radix heap */
    uint64_t nonempty[DM__QEM_MASKWORDS];   /* bit i: bucket i > 0 holds entries */
    dm__qem_chunk *free_chunks;    /* free list */
    void *blocks;                  /* allocated chunk blocks, linked through their first word */
    uint64_t last;                 /* its last popped key */
    size_t hsize;                  /* candidates in it */
    uint64_t floor;                /* the key being collapsed: a cheaper new candidate is queued at it */
    dm__qem_cand *front;           /* the candidates at or below `last`, out of the buckets: the
                                      next few, popped ahead (see dm__qem_next); a binary heap
                                      (dm__qem_front_push) */
    size_t *fseq;                  /* their push order */
    size_t nfront, capfront, capfseq, pushes;
    uint64_t ahead_key;            /* the key of the candidate whose neighbours were asked for */
    dm__qem_rec *rec;
    size_t nrec, caprec;
    uint32_t *ops;
    size_t nops, capops;
    double center[3], scale, inv_scale;
    double max_error;
    double min_quality;            /* new triangles' 2 area / longest edge^2 (0 = no guard) */
    double relax_cost;             /* a vetoed candidate comes back at this times its cost (<= 0: never) */
    size_t rejected, vetoed, requeued;
} dm__qem_simp;

/* grows *p (elements of elem bytes, capacity *cap) to hold at least need; 0 on failure */
static int dm__qem_grow(const dm_allocator *al, void **p, size_t *cap, size_t need, size_t elem)
{
    size_t ncap;
    void *np;
    int overflow = 0;
    if (need <= *cap) return 1;
    ncap = *cap ? *cap : 256;
    while (ncap < need) {
        if (ncap > (size_t)-1 / 2) return 0;
        ncap *= 2;
    }
    np = dm__alloc_array(al, ncap, elem, &overflow);
    if (!np) return 0;
    if (*p) {
        memcpy(np, *p, *cap * elem);
        al->free(al->user, *p);
    }
    *p = np;
    *cap = ncap;
    return 1;
}

static uint32_t dm__qem_new_stamp(dm__qem_simp *s)
{
    if (s->stamp >= 0xfffffff0u) { /* wrap: clear the marks once */
        size_t v;
        for (v = 0; v < s->n; v++) s->vx[v].mark = 0;
        s->stamp = 0;
    }
    s->stamp += 2;
    return s->stamp;
}

static void dm__qem_norm_pos(const dm__qem_simp *s, uint32_t v, double x[3])
{
    const double *p = s->vx[v].np;
    x[0] = p[0];
    x[1] = p[1];
    x[2] = p[2];
}

static void dm__qem_quadric_add_plane(dm__qem_quadric *q, const double n[3], double d, double w)
{
    q->a00 += w * n[0] * n[0];
    q->a01 += w * n[0] * n[1];
    q->a02 += w * n[0] * n[2];
    q->a11 += w * n[1] * n[1];
    q->a12 += w * n[1] * n[2];
    q->a22 += w * n[2] * n[2];
    q->b0 += w * d * n[0];
    q->b1 += w * d * n[1];
    q->b2 += w * d * n[2];
    q->c += w * d * d;
    q->w += w;
}

static void dm__qem_quadric_sum(dm__qem_quadric *r, const dm__qem_quadric *a, const dm__qem_quadric *b)
{
    r->a00 = a->a00 + b->a00;
    r->a01 = a->a01 + b->a01;
    r->a02 = a->a02 + b->a02;
    r->a11 = a->a11 + b->a11;
    r->a12 = a->a12 + b->a12;
    r->a22 = a->a22 + b->a22;
    r->b0 = a->b0 + b->b0;
    r->b1 = a->b1 + b->b1;
    r->b2 = a->b2 + b->b2;
    r->c = a->c + b->c;
    r->w = a->w + b->w;
}

static double dm__qem_quadric_eval(const dm__qem_quadric *q, const double x[3])
{
    double ax = q->a00 * x[0] + q->a01 * x[1] + q->a02 * x[2];
    double ay = q->a01 * x[0] + q->a11 * x[1] + q->a12 * x[2];
    double az = q->a02 * x[0] + q->a12 * x[1] + q->a22 * x[2];
    double e = x[0] * (ax + 2.0 * q->b0) + x[1] * (ay + 2.0 * q->b1) + x[2] * (az + 2.0 * q->b2) + q->c;
    return e > 0.0 ? e : 0.0;
}

/* The minimiser of Q on the segment p0 p1 (a 1-D quadratic, always well posed). */
static void dm__qem_segment_min(const dm__qem_quadric *q, const double p0[3], const double p1[3], double x[3])
{
    double e[3], ae[3], num, den, t;
    int k;
    for (k = 0; k < 3; k++) e[k] = p1[k] - p0[k];
    ae[0] = q->a00 * e[0] + q->a01 * e[1] + q->a02 * e[2];
    ae[1] = q->a01 * e[0] + q->a11 * e[1] + q->a12 * e[2];
    ae[2] = q->a02 * e[0] + q->a12 * e[1] + q->a22 * e[2];
    den = e[0] * ae[0] + e[1] * ae[1] + e[2] * ae[2];
    /* dQ/dt at t = 0 is 2 (e^T A p0 + b^T e) */
    num = -(ae[0] * p0[0] + ae[1] * p0[1] + ae[2] * p0[2] + q->b0 * e[0] + q->b1 * e[1] + q->b2 * e[2]);
    if (den > 1e-300 && num > 0.0) t = num < den ? num / den : 1.0;
    else if (den > 1e-300) t = 0.0;
    else t = dm__qem_quadric_eval(q, p1) < dm__qem_quadric_eval(q, p0) ? 1.0 : 0.0;
    for (k = 0; k < 3; k++) x[k] = p0[k] + t * e[k];
}

/* Optimal placement: solve A x = -b when A is well conditioned (det against trace^3) and the
   solution stays within two edge lengths of the midpoint (then it is Q's global minimum);
   otherwise the best point of the edge, which always exists. Returns Q at the chosen x. */
static double dm__qem_optimal(const dm__qem_quadric *q, const double p0[3], const double p1[3], double x[3])
{
    double c00 = q->a11 * q->a22 - q->a12 * q->a12;
    double c01 = q->a02 * q->a12 - q->a01 * q->a22;
    double c02 = q->a01 * q->a12 - q->a02 * q->a11;
    double det = q->a00 * c00 + q->a01 * c01 + q->a02 * c02;
    double tr = q->a00 + q->a11 + q->a22;
    double len2 = 0.0, d2 = 0.0;
    int k;
    if (tr > 0.0 && det > 1e-7 * tr * tr * tr) {
        double c11 = q->a00 * q->a22 - q->a02 * q->a02;
        double c12 = q->a01 * q->a02 - q->a00 * q->a12;
        double c22 = q->a00 * q->a11 - q->a01 * q->a01;
        double inv = 1.0 / det, o[3];
        o[0] = -(c00 * q->b0 + c01 * q->b1 + c02 * q->b2) * inv;
        o[1] = -(c01 * q->b0 + c11 * q->b1 + c12 * q->b2) * inv;
        o[2] = -(c02 * q->b0 + c12 * q->b1 + c22 * q->b2) * inv;
        { /* written out: as a loop this check cost a quarter of the function */
            double ex = p1[0] - p0[0], ey = p1[1] - p0[1], ez = p1[2] - p0[2];
            double mx = o[0] - 0.5 * (p0[0] + p1[0]), my = o[1] - 0.5 * (p0[1] + p1[1]), mz = o[2] - 0.5 * (p0[2] + p1[2]);
            len2 = ex * ex + ey * ey + ez * ez;
            d2 = mx * mx + my * my + mz * mz;
        }
        if (d2 <= 4.0 * len2) { /* at the minimiser A x = -b, so Q(x) = x.b + c */
            double e = q->c + o[0] * q->b0 + o[1] * q->b1 + o[2] * q->b2;
            for (k = 0; k < 3; k++) x[k] = o[k];
            return e > 0.0 ? e : 0.0;
        }
    }
    dm__qem_segment_min(q, p0, p1, x);
    return dm__qem_quadric_eval(q, x);
}

/* DM__QEM_LANES placements at once: lane by lane the arithmetic of dm__qem_optimal (the same
   bits), in loops over the lanes without a branch, so that the solves overlap (a solve is a
   chain of dependent operations, the division in the middle; the compiler may also run the
   lanes as vectors). cost[l] is valid when ok[l]; a lane whose solve is refused (A nearly
   singular, or the minimiser too far from the edge) gets ok[l] = 0, and dm__qem_optimal then
   takes its fallback for it. Two lanes: four measured the same on the bunny and the sphere, and
   pair up more of a vertex's few edges. */
#define DM__QEM_LANES 2
static void dm__qem_optimal_lanes(const dm__qem_quadric q[DM__QEM_LANES], const double *const p0[DM__QEM_LANES],
                             const double *const p1[DM__QEM_LANES], double cost[DM__QEM_LANES], int ok[DM__QEM_LANES])
{
    double c00[DM__QEM_LANES], c01[DM__QEM_LANES], c02[DM__QEM_LANES], c11[DM__QEM_LANES], c12[DM__QEM_LANES];
    double c22[DM__QEM_LANES], det[DM__QEM_LANES], tr[DM__QEM_LANES], inv[DM__QEM_LANES];
    double o0[DM__QEM_LANES], o1[DM__QEM_LANES], o2[DM__QEM_LANES];
    int l;
    for (l = 0; l < DM__QEM_LANES; l++) {
        c00[l] = q[l].a11 * q[l].a22 - q[l].a12 * q[l].a12;
        c01[l] = q[l].a02 * q[l].a12 - q[l].a01 * q[l].a22;
        c02[l] = q[l].a01 * q[l].a12 - q[l].a02 * q[l].a11;
        c11[l] = q[l].a00 * q[l].a22 - q[l].a02 * q[l].a02;
        c12[l] = q[l].a01 * q[l].a02 - q[l].a00 * q[l].a12;
        c22[l] = q[l].a00 * q[l].a11 - q[l].a01 * q[l].a01;
        det[l] = q[l].a00 * c00[l] + q[l].a01 * c01[l] + q[l].a02 * c02[l];
        tr[l] = q[l].a00 + q[l].a11 + q[l].a22;
    }
    for (l = 0; l < DM__QEM_LANES; l++) {
        int good = (tr[l] > 0.0) & (det[l] > 1e-7 * tr[l] * tr[l] * tr[l]);
        inv[l] = 1.0 / (good ? det[l] : 1.0);
        ok[l] = good;
    }
    for (l = 0; l < DM__QEM_LANES; l++) {
        const double *a = p0[l], *b = p1[l];
        double ex, ey, ez, mx, my, mz, e;
        o0[l] = -(c00[l] * q[l].b0 + c01[l] * q[l].b1 + c02[l] * q[l].b2) * inv[l];
        o1[l] = -(c01[l] * q[l].b0 + c11[l] * q[l].b1 + c12[l] * q[l].b2) * inv[l];
        o2[l] = -(c02[l] * q[l].b0 + c12[l] * q[l].b1 + c22[l] * q[l].b2) * inv[l];
        ex = b[0] - a[0], ey = b[1] - a[1], ez = b[2] - a[2];
        mx = o0[l] - 0.5 * (a[0] + b[0]), my = o1[l] - 0.5 * (a[1] + b[1]), mz = o2[l] - 0.5 * (a[2] + b[2]);
        ok[l] &= mx * mx + my * my + mz * mz <= 4.0 * (ex * ex + ey * ey + ez * ez);
        e = q[l].c + o0[l] * q[l].b0 + o1[l] * q[l].b1 + o2[l] * q[l].b2;
        cost[l] = e > 0.0 ? e : 0.0;
    }
}

/* Which vertex stays, where it goes (normalised coordinates) and the cost Q(x). Returns 0 when the
   edge is never collapsible, 2 when keep stays where it is (x = keep's position), else 1. */
static int dm__qem_place(const dm__qem_simp *s, uint32_t a, uint32_t b, uint32_t *keep, uint32_t *rem, double x[3],
                         double *cost)
{
    unsigned fa = s->vx[a].flag, fb = s->vx[b].flag;
    dm__qem_quadric q;
    const double *pa, *pb;
    if ((fa | fb) & (DM__QEM_V_FROZEN | DM__QEM_V_REMOVED)) return 0;
    if ((fa & fb) & DM__QEM_V_LOCKED) return 0;
    dm__qem_quadric_sum(&q, &s->vx[a].q, &s->vx[b].q);
    if ((fa | fb) & DM__QEM_V_LOCKED || ((fa ^ fb) & DM__QEM_V_BOUNDARY)) {
        /* the caller takes keep's float position as it is (no round trip) */
        if (fa & DM__QEM_V_LOCKED) *keep = a;
        else if (fb & DM__QEM_V_LOCKED) *keep = b;
        else *keep = (fa & DM__QEM_V_BOUNDARY) ? a : b;
        *rem = *keep == a ? b : a;
        dm__qem_norm_pos(s, *keep, x);
        *cost = dm__qem_quadric_eval(&q, x);
        return 2;
    }
    *keep = a < b ? a : b;
    *rem = a < b ? b : a;
    pa = s->vx[a].np;
    pb = s->vx[b].np;
    if (fa & DM__QEM_V_BOUNDARY) { /* along a boundary edge: stay on it (exact on lines) */
        dm__qem_segment_min(&q, pa, pb, x);
        *cost = dm__qem_quadric_eval(&q, x);
    } else {
        *cost = dm__qem_optimal(&q, pa, pb, x);
    }
    return 1;
}

/* A collapse's error in mesh units: sqrt(Q(x) / W), W the planes' total weight. */
static double dm__qem_error(const dm__qem_simp *s, uint32_t a, uint32_t b, double cost)
{
    double w = s->vx[a].q.w + s->vx[b].q.w;
    return w > 0.0 ? sqrt(cost / w) * s->scale : 0.0;
}

static unsigned dm__qem_bucket_of(uint64_t key, uint64_t last)
{
    uint64_t x = key ^ last;
    unsigned h;
    if (!x) return 0u;
#if defined(__GNUC__) || defined(__clang__)
    h = 64u - (unsigned)__builtin_clzll((unsigned long long)x);
#else
    h = 0;
    while (x) {
        h++;
        x >>= 1;
    }
#endif
    h = (h - 1u) / 3u; /* the octal digit */
    return 1u + 8u * h + ((unsigned)(key >> (3u * h)) & 7u);
}

static dm__qem_chunk *dm__qem_chunk_new(dm__qem_simp *s)
{
    dm__qem_chunk *c = s->free_chunks;
    if (!c) { /* a block: a link word (padded to a chunk's alignment), then the chunks */
        size_t i;
        char *blk = (char *)s->al.alloc(s->al.user, sizeof(dm__qem_chunk) * (DM__QEM_CHUNKS_PER_BLOCK + 1));
        if (!blk) return NULL;
        memcpy(blk, &s->blocks, sizeof(void *));
        s->blocks = blk;
        for (i = 1; i <= DM__QEM_CHUNKS_PER_BLOCK; i++) {
            dm__qem_chunk *k = (dm__qem_chunk *)(void *)(blk + i * sizeof(dm__qem_chunk));
            k->next = s->free_chunks;
            s->free_chunks = k;
        }
        c = s->free_chunks;
    }
    s->free_chunks = c->next;
    return c;
}

/* a new chunk on top of a full (or empty) bucket; 0 on allocation failure */
#if defined(__GNUC__) || defined(__clang__)
__attribute__((noinline))
#endif
static int dm__qem_bucket_refill(dm__qem_simp *s, dm__qem_bucket *b)
{
    dm__qem_chunk *c = dm__qem_chunk_new(s);
    if (!c) return 0;
    c->next = b->top;
    b->top = c;
    b->fill = 0;
    return 1;
}

/* inlined: the common case is a few instructions, and the spread calls it for every entry */
DM__INLINE int dm__qem_bucket_add(dm__qem_simp *s, unsigned i, const dm__qem_cand *e)
{
    dm__qem_bucket *b = &s->bucket[i];
    if (b->fill == DM__QEM_CHUNK && !dm__qem_bucket_refill(s, b)) return 0;
    b->top->e[b->fill++] = *e;
    b->n++;
    s->nonempty[i >> 6] |= (uint64_t)1 << (i & 63u);
    return 1;
}

/* Takes bucket i's chunks out (the bucket is left empty): returns the top chunk; *fill gets the
   entry count of the top chunk (the ones below are full). */
static dm__qem_chunk *dm__qem_bucket_take(dm__qem_simp *s, unsigned i, size_t *fill)
{
    dm__qem_bucket *b = &s->bucket[i];
    dm__qem_chunk *c = b->top;
    *fill = c ? b->fill : 0;
    s->nonempty[i >> 6] &= ~((uint64_t)1 << (i & 63u));
    b->n = 0;
    b->top = NULL;
    b->fill = DM__QEM_CHUNK;
    return c;
}

static void dm__qem_chunk_free(dm__qem_simp *s, dm__qem_chunk *c)
{
    c->next = s->free_chunks;
    s->free_chunks = c;
}

static int dm__qem_stale(const dm__qem_simp *s, const dm__qem_cand *e)
{
    return (((s->ver[DM__QEM_CAND_A(e)] + s->ver[e->b]) ^ e->stamp) & ~DM__QEM_RETRY) != 0;
}

/* DM_COUNT_OPS(n): a test hook (default: nothing) told the comparisons of the candidate queue's
   front and the words of the corner lists walked, so that a test can check that they grow
   linearly with the mesh, whatever its valences. */
#ifndef DM_COUNT_OPS
#define DM_COUNT_OPS(n) ((void)0)
#endif

/* The front (dm__qem_next) as a binary heap: the cheapest first, the last pushed among equals
   (as from bucket 0), so that many equal keys (the zero costs of a flat part) cost a logarithm
   each, not a scan of them all. Is entry i before entry j? */
static int dm__qem_front_before(const dm__qem_simp *s, size_t i, size_t j)
{
    DM_COUNT_OPS(1);
    return s->front[i].key < s->front[j].key || (s->front[i].key == s->front[j].key && s->fseq[i] > s->fseq[j]);
}

static void dm__qem_front_swap(dm__qem_simp *s, size_t i, size_t j)
{
    dm__qem_cand c = s->front[i];
    size_t q = s->fseq[i];
    s->front[i] = s->front[j];
    s->fseq[i] = s->fseq[j];
    s->front[j] = c;
    s->fseq[j] = q;
}

/* 0 on allocation failure */
static int dm__qem_front_push(dm__qem_simp *s, const dm__qem_cand *c)
{
    size_t i = s->nfront;
    if (!dm__qem_grow(&s->al, (void **)&s->front, &s->capfront, s->nfront + 1, sizeof(dm__qem_cand)) ||
        !dm__qem_grow(&s->al, (void **)&s->fseq, &s->capfseq, s->nfront + 1, sizeof(size_t)))
        return 0;
    s->front[i] = *c;
    s->fseq[i] = s->pushes++;
    s->nfront++;
    for (; i > 0 && dm__qem_front_before(s, i, (i - 1) / 2); i = (i - 1) / 2) dm__qem_front_swap(s, i, (i - 1) / 2);
    return 1;
}

/* the first of the front out into *out (the front is not empty) */
static void dm__qem_front_take(dm__qem_simp *s, dm__qem_cand *out)
{
    size_t i = 0, n = --s->nfront;
    *out = s->front[0];
    s->front[0] = s->front[n];
    s->fseq[0] = s->fseq[n];
    for (;;) {
        size_t l = 2 * i + 1, m = i;
        if (l < n && dm__qem_front_before(s, l, m)) m = l;
        if (l + 1 < n && dm__qem_front_before(s, l + 1, m)) m = l + 1;
        if (m == i) break;
        dm__qem_front_swap(s, i, m);
        i = m;
    }
}

static int dm__qem_heap_push(dm__qem_simp *s, const dm__qem_cand *e)
{
    dm__qem_cand c = *e;
    if (c.key < s->floor) { /* below the key being collapsed: at its cost (one ulp up if needed) */
        uint64_t k = (s->floor & ~(uint64_t)0xffffffffu) | (c.key & 0xffffffffu);
        c.key = k < s->floor ? k + ((uint64_t)1 << 32) : k;
    }
    if (c.key <= s->last) { /* not above the ones popped ahead: with them */
        return dm__qem_front_push(s, &c);
    }
    if (!dm__qem_bucket_add(s, dm__qem_bucket_of(c.key, s->last), &c)) return 0;
    s->hsize++;
    return 1;
}

/* Drops the stale entries once the heap holds more than three entries per live triangle (there
   are about 1.5 live edges per triangle), so that it stays near the size of the live mesh
   (spreading a bucket drops the stale entries it meets, so purges are rarely needed; at two
   per triangle they took 15% of the bunny's time).
   The entries that stay are re-added to their bucket: a chunk freed is reused at once, so this
   never needs more than one new chunk. 0 on allocation failure. */
static int dm__qem_heap_purge(dm__qem_simp *s)
{
    unsigned i;
    s->hsize = 0;
    for (i = 0; i < DM__QEM_BUCKETS; i++) {
        size_t fill, j;
        dm__qem_chunk *c = dm__qem_bucket_take(s, i, &fill), *next;
        for (; c; c = next, fill = DM__QEM_CHUNK) {
            next = c->next;
            for (j = 0; j < fill; j++)
                if (!dm__qem_stale(s, &c->e[j]) && !dm__qem_bucket_add(s, i, &c->e[j])) return 0;
            dm__qem_chunk_free(s, c);
        }
        s->hsize += s->bucket[i].n;
    }
    return 1;
}

/* The smallest entry into *out: 1, or 0 when the heap is empty, -1 on allocation failure.
   Equal keys come out last in, first out. Stale entries met while spreading are dropped. */
static int dm__qem_heap_pop(dm__qem_simp *s, dm__qem_cand *out)
{
    dm__qem_bucket *b0 = &s->bucket[0];
    while (b0->n == 0) {
        unsigned i = 1;
        size_t j, fill;
        uint64_t m = ~(uint64_t)0;
        dm__qem_chunk *c, *next;
        { /* the first non-empty bucket above 0 */
            unsigned w;
            for (w = 0; w < DM__QEM_MASKWORDS; w++) {
                uint64_t mk = s->nonempty[w] & (w ? ~(uint64_t)0 : ~(uint64_t)1);
                if (mk) {
#if defined(__GNUC__) || defined(__clang__)
                    i = 64u * w + (unsigned)__builtin_ctzll((unsigned long long)mk);
#else
                    i = 64u * w;
                    while (!(mk & 1u)) {
                        mk >>= 1;
                        i++;
                    }
#endif
                    break;
                }
            }
            if (w == DM__QEM_MASKWORDS) return 0;
        }
        c = dm__qem_bucket_take(s, i, &fill);
        for (next = c, j = fill; next; next = next->next, j = DM__QEM_CHUNK) {
            size_t k;
            for (k = 0; k < j; k++)
                if (next->e[k].key < m) m = next->e[k].key;
        }
        s->last = m;
        for (; c; c = next, fill = DM__QEM_CHUNK) {
            next = c->next;
            for (j = 0; j < fill; j++) {
                const dm__qem_cand *e = &c->e[j];
                if (j + 16 < fill) { /* versions of a large mesh miss the cache: ask early */
                    DM__QEM_PREFETCH(&s->ver[DM__QEM_CAND_A(e + 16)]);
                    DM__QEM_PREFETCH(&s->ver[e[16].b]);
                }
                if (dm__qem_stale(s, e)) {
                    s->hsize--;
                    continue;
                }
                if (!dm__qem_bucket_add(s, dm__qem_bucket_of(e->key, m), e)) return -1;
            }
            dm__qem_chunk_free(s, c);
        }
    }
    *out = b0->top->e[--b0->fill];
    b0->n--;
    if (b0->fill == 0) { /* the chunks below are full */
        dm__qem_chunk *c = b0->top;
        b0->top = c->next;
        b0->fill = DM__QEM_CHUNK;
        dm__qem_chunk_free(s, c);
    }
    s->hsize--;
    return 1;
}

/* The candidates are taken from s->front, which the radix heap's next few are popped into
   DM__QEM_AHEAD collapses ahead: on a large mesh each collapse works at a random place, and
   its data (versions, records, corner lists, triangles, the neighbours' records: each needs
   the one before) would otherwise come from memory one miss after another. A collapse asks
   for the next candidate's data one stage at a time (dm__qem_ahead), so that it arrives while
   the collapse works. New candidates not above the last popped key join the front (heap_push).
   The cheapest in front comes next, the last pushed among equals (as from bucket 0), so the
   order of collapses is the one without look-ahead. */
#define DM__QEM_AHEAD 2

/* the index in the front of its first (which 0) or second (which 1) entry, DM__QEM_NONE if none */
static size_t dm__qem_front_min(const dm__qem_simp *s, int which)
{
    if (s->nfront <= (size_t)which) return DM__QEM_NONE;
    if (!which) return 0;
    return s->nfront > 2 && dm__qem_front_before(s, 2, 1) ? 2 : 1;
}

/* The next candidate into *out: 1, or 0 when none is left, -1 on allocation failure. */
static int dm__qem_next(dm__qem_simp *s, dm__qem_cand *out)
{
    while (s->nfront <= DM__QEM_AHEAD) {
        dm__qem_cand c;
        int got = dm__qem_heap_pop(s, &c);
        if (got <= 0) {
            if (got < 0) return -1;
            break;
        }
        if (!dm__qem_front_push(s, &c)) return -1;
        DM__QEM_PREFETCH(&s->ver[DM__QEM_CAND_A(&c)]); /* the first stage */
        DM__QEM_PREFETCH(&s->ver[c.b]);
        DM__QEM_PREFETCH(&s->vx[DM__QEM_CAND_A(&c)]);
        DM__QEM_PREFETCH(&s->vx[c.b]);
        DM__QEM_PREFETCH(s->pos + 3 * (size_t)DM__QEM_CAND_A(&c));
        DM__QEM_PREFETCH(s->pos + 3 * (size_t)c.b);
    }
    if (!s->nfront) return 0;
    dm__qem_front_take(s, out);
    return 1;
}

/* For the candidate `which` places ahead (0: the next one, 1: the one after), stage 0 asks
   for its corner lists, stage 1 for its triangles, stage 2 for its neighbours' records (and
   notes its key: the topology check need not ask again): each stage reads what the one before
   asked for, a collapse or so earlier. (A function of prefetches alone would be dropped: gcc
   takes it for one without effect.) */
static void dm__qem_ahead(dm__qem_simp *s, int which, int stage)
{
    uint32_t v[2];
    size_t i0;
    int k;
    if (!s->nfront) return;
    i0 = dm__qem_front_min(s, which);
    if (i0 == DM__QEM_NONE) return;
    v[0] = DM__QEM_CAND_A(&s->front[i0]);
    v[1] = s->front[i0].b;
    if (stage == 2) s->ahead_key = s->front[i0].key;
    for (k = 0; k < 2; k++) {
        const uint32_t *cl = s->adj + s->vx[v[k]].first;
        uint32_t i, n = s->vx[v[k]].count;
        if (stage == 0) {
            DM__QEM_PREFETCH(cl);
            continue;
        }
        if (stage == 1) { /* the corner's own word: its triangle's line, but for a rare straddle */
            for (i = 0; i < n; i++) DM__QEM_PREFETCH(s->idx + cl[i]);
            continue;
        }
        for (i = 0; i < n; i++) {
            uint32_t c = cl[i], slot = c % 3;
            const uint32_t *t = s->idx + (c - slot);
            DM__QEM_PREFETCH(&s->vx[t[DM__QEM_NEXT(slot)]]);
            DM__QEM_PREFETCH((const char *)&s->vx[t[DM__QEM_NEXT(slot)]] + 64);
            DM__QEM_PREFETCH(&s->ver[t[DM__QEM_NEXT(slot)]]); /* for its new candidates */
        }
    }
}

/* Drops the corner of the dead triangle `tri` from v's list: only counted here, and swept out
   (order kept) when the list is next read, so that a vertex of high valence whose triangles die
   one at a time costs a pass per read of its list, not a pass per triangle. */
static void dm__qem_drop_corner(dm__qem_simp *s, uint32_t v, uint32_t tri)
{
    (void)tri; /* the sweep finds it dead */
    s->vx[v].count--;
}

/* Sweeps the dropped corners out of v's list (those of dead triangles; the others are live). */
static void dm__qem_sweep(dm__qem_simp *s, uint32_t v)
{
    uint32_t *cl, n = s->slots[v], i, j = 0;
    if (n == s->vx[v].count) return;
    cl = s->adj + s->vx[v].first;
    DM_COUNT_OPS(n);
    for (i = 0; i < n; i++) {
        uint32_t c = cl[i];
        cl[j] = c;
        j += s->alive[c / 3];
    }
    s->slots[v] = j;
}

/* The distinct neighbours of v (alive triangles) into s->nbr; returns the count. */
static size_t dm__qem_neighbours(dm__qem_simp *s, uint32_t v)
{
    uint32_t st, i, nc;
    const uint32_t *cl;
    size_t m = 0;
    dm__qem_sweep(s, v);
    st = dm__qem_new_stamp(s);
    nc = s->vx[v].count;
    cl = s->adj + s->vx[v].first;
    DM_COUNT_OPS(nc);
    for (i = 0; i < nc; i++) {
        const uint32_t *t = s->idx + 3 * (size_t)(cl[i] / 3);
        int k;
        for (k = 0; k < 3; k++)
            if (t[k] != v && s->vx[t[k]].mark != st) {
                s->vx[t[k]].mark = st;
                s->nbr[m++] = t[k];
            }
    }
    return m;
}

/* the cost a key was made with */
static float dm__qem_key_cost(uint64_t key)
{
    uint32_t bits = (uint32_t)(key >> 32);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

static dm__qem_cand dm__qem_make_cand(const dm__qem_simp *s, uint32_t a, uint32_t b, double cost)
{
    dm__qem_cand e;
    const double *pa = s->vx[a].np, *pb = s->vx[b].np;
    float f;
    /* ties (the zero costs of a flat part) go to the shorter edge: in index order they sweep the
       part row by row into fans of slivers, and every candidate there is refused again and
       again (a flat 20k-triangle grid took 6 s, now 20 ms); far below any cost of a curved part */
    cost += 1e-20 * ((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) + (pa[2] - pb[2]) * (pa[2] - pb[2]));
    f = cost < (double)FLT_MAX ? (float)cost : FLT_MAX; /* cost >= 0 */
    uint32_t bits, lo = a < b ? a : b;
    memcpy(&bits, &f, sizeof bits);
    e.key = (uint64_t)bits << 32 | lo;
    e.b = a < b ? b : a;
    e.stamp = (s->ver[lo] + s->ver[e.b]) & ~DM__QEM_RETRY;
    return e;
}

#define DM__QEM_BATCH 32

/* Pushes the collapsible ones of the edges (ea[i], eb[i]), i < n <= DM__QEM_BATCH, in order.
   Costs first: the edges between free interior vertices (most) go two at a time through
   dm__qem_optimal_lanes, whose two solves overlap (a solve is a chain of dependent operations: on
   the bunny this takes a tenth off the time, for a few more instructions). 0 on allocation
   failure. */
static int dm__qem_push_edges(dm__qem_simp *s, const uint32_t *ea, const uint32_t *eb, size_t n)
{
    const unsigned special = DM__QEM_V_FROZEN | DM__QEM_V_REMOVED | DM__QEM_V_LOCKED | DM__QEM_V_BOUNDARY;
    double cost[DM__QEM_BATCH], p[3];
    int use[DM__QEM_BATCH];
    size_t i, at[DM__QEM_LANES], npend = 0;
    for (i = 0; i < n; i++) {
        const dm__qem_vert *va = &s->vx[ea[i]], *vb = &s->vx[eb[i]];
        uint32_t keep, rem;
        use[i] = 1;
        if ((va->flag | vb->flag) & special) {
            use[i] = dm__qem_place(s, ea[i], eb[i], &keep, &rem, p, &cost[i]);
            continue;
        }
        at[npend++] = i;
        if (npend == DM__QEM_LANES) { /* the waiting ones together */
            dm__qem_quadric q[DM__QEM_LANES];
            const double *p0[DM__QEM_LANES], *p1[DM__QEM_LANES];
            double c2[DM__QEM_LANES];
            int ok[DM__QEM_LANES], l;
            for (l = 0; l < DM__QEM_LANES; l++) {
                const dm__qem_vert *a = &s->vx[ea[at[l]]], *b = &s->vx[eb[at[l]]];
                dm__qem_quadric_sum(&q[l], &a->q, &b->q);
                p0[l] = a->np;
                p1[l] = b->np;
            }
            dm__qem_optimal_lanes(q, p0, p1, c2, ok);
            for (l = 0; l < DM__QEM_LANES; l++) cost[at[l]] = ok[l] ? c2[l] : dm__qem_optimal(&q[l], p0[l], p1[l], p);
            npend = 0;
        }
    }
    for (i = 0; i < npend; i++) { /* the rest one by one */
        const dm__qem_vert *a = &s->vx[ea[at[i]]], *b = &s->vx[eb[at[i]]];
        dm__qem_quadric q;
        dm__qem_quadric_sum(&q, &a->q, &b->q);
        cost[at[i]] = dm__qem_optimal(&q, a->np, b->np, p);
    }
    for (i = 0; i < n; i++) {
        dm__qem_cand e;
        if (!use[i]) continue;
        e = dm__qem_make_cand(s, ea[i], eb[i], cost[i]);
        if (!dm__qem_heap_push(s, &e)) return 0;
    }
    return 1;
}

/* Pushes every collapsible edge (v, x) for x in nbr[0..m), x != skip. 0 on allocation failure. */
static int dm__qem_push_list(dm__qem_simp *s, uint32_t v, const uint32_t *nbr, size_t m, uint32_t skip)
{
    uint32_t ea[DM__QEM_BATCH], eb[DM__QEM_BATCH];
    size_t i, n = 0;
    for (i = 0; i < m; i++) {
        if (nbr[i] == skip) continue;
        ea[n] = v;
        eb[n++] = nbr[i];
        if (n == DM__QEM_BATCH) {
            if (!dm__qem_push_edges(s, ea, eb, n)) return 0;
            n = 0;
        }
    }
    return n == 0 || dm__qem_push_edges(s, ea, eb, n);
}

/* Geometry: every triangle of keep or rem that survives, with both moved to `at`, keeps its
   orientation (normal turns by less than acos(DM__QEM_MIN_COS)) and is not degenerate. Writes the
   new one-ring into s->ring. Returns the triangle count, or (size_t)-1 if refused. Each triangle
   is (v, p1, p2) from v's corner on: old normal (p1 - v) x (p2 - v), new one with v at `at`;
   the tests compare squares, so no square root, and they are scale-free, so they run in the
   normalised frame. */
static size_t dm__qem_check_geometry(dm__qem_simp *s, uint32_t keep, uint32_t rem, const float at[3])
{
    size_t m = 0;
    double pa[3];
    int pass, k, bad = 0;
    const double min_sin2 = DM__QEM_MIN_SIN * DM__QEM_MIN_SIN, min_cos2 = DM__QEM_MIN_COS * DM__QEM_MIN_COS,
                 min_q2 = s->min_quality * s->min_quality;
    for (k = 0; k < 3; k++) pa[k] = ((double)at[k] - s->center[k]) * s->inv_scale;
    dm__qem_sweep(s, keep);
    dm__qem_sweep(s, rem);
    DM_COUNT_OPS((size_t)s->vx[keep].count + s->vx[rem].count);
    for (pass = 0; pass < 2; pass++) {
        uint32_t v = pass ? rem : keep, other = pass ? keep : rem, nc = s->vx[v].count, j0;
        const uint32_t *cl = s->adj + s->vx[v].first;
        const double *pv = s->vx[v].np;
        /* The triangles that die (they hold `other`: two of each one-ring, a third of all) are
           left out first, without a branch on which ones they are (unpredictable), by blocks of
           64 corners; then the test runs on the others. */
        for (j0 = 0; j0 < nc; j0 += 64) {
            uint32_t lc[64], nl = 0, jj, jn = nc - j0 < 64u ? nc - j0 : 64u;
            for (jj = 0; jj < jn; jj++) {
                uint32_t c = cl[j0 + jj], slot = c % 3;
                const uint32_t *t = s->idx + (c - slot);
                lc[nl] = c;
                nl += (t[DM__QEM_NEXT(slot)] != other) & (t[DM__QEM_PREV(slot)] != other);
            }
            for (jj = 0; jj < nl; jj++) {
                uint32_t c = lc[jj], slot = c % 3, i1, i2;
                const uint32_t *t = s->idx + (c - slot);
                const double *f1, *f2;
                double u0x, u0y, u0z, v0x, v0y, v0z, u1x, u1y, u1z, v1x, v1y, v1z, wx, wy, wz;
                double n0x, n0y, n0z, n1x, n1y, n1z, l1, l0, dot, lu, lv, lw, e2;
                int thin, turned;
                i1 = t[DM__QEM_NEXT(slot)];
                i2 = t[DM__QEM_PREV(slot)];
                f1 = s->vx[i1].np;
                f2 = s->vx[i2].np;
                /* scalars, crosses written out: the compiler keeps them in registers */
                u0x = f1[0] - pv[0], u0y = f1[1] - pv[1], u0z = f1[2] - pv[2];
                v0x = f2[0] - pv[0], v0y = f2[1] - pv[1], v0z = f2[2] - pv[2];
                u1x = f1[0] - pa[0], u1y = f1[1] - pa[1], u1z = f1[2] - pa[2];
                v1x = f2[0] - pa[0], v1y = f2[1] - pa[1], v1z = f2[2] - pa[2];
                wx = f2[0] - f1[0], wy = f2[1] - f1[1], wz = f2[2] - f1[2];
                n1x = u1y * v1z - u1z * v1y;
                n1y = u1z * v1x - u1x * v1z;
                n1z = u1x * v1y - u1y * v1x;
                n0x = u0y * v0z - u0z * v0y;
                n0y = u0z * v0x - u0x * v0z;
                n0z = u0x * v0y - u0y * v0x;
                lu = u1x * u1x + u1y * u1y + u1z * u1z;
                lv = v1x * v1x + v1y * v1y + v1z * v1z;
                lw = wx * wx + wy * wy + wz * wz;
                e2 = lu;
                e2 = lv > e2 ? lv : e2;
                e2 = lw > e2 ? lw : e2;
                l1 = n1x * n1x + n1y * n1y + n1z * n1z;
                l0 = n0x * n0x + n0y * n0y + n0z * n0z;
                dot = n0x * n1x + n0y * n1y + n0z * n1z;
                thin = !(l1 > min_sin2 * e2 * e2);
                if (min_q2 > 0.0 && !(l1 >= min_q2 * e2 * e2)) { /* a sliver: refused unless it was one already */
                    double o2 = u0x * u0x + u0y * u0y + u0z * u0z, ov = v0x * v0x + v0y * v0y + v0z * v0z;
                    o2 = ov > o2 ? ov : o2;
                    o2 = lw > o2 ? lw : o2;
                    thin |= l1 * o2 * o2 < l0 * e2 * e2;
                }
                turned = (l0 > 0.0) & ((dot <= 0.0) | !(dot * dot > min_cos2 * l0 * l1));
                bad |= thin | turned;
                s->ring[3 * m + slot] = keep;
                s->ring[3 * m + DM__QEM_NEXT(slot)] = i1;
                s->ring[3 * m + DM__QEM_PREV(slot)] = i2;
                m++;
            }
        }
    }
    return bad ? (size_t)-1 : m;
}

/* The triangles of keep and rem before the collapse (each once) into s->oring; returns the count. */
static size_t dm__qem_old_ring(dm__qem_simp *s, uint32_t keep, uint32_t rem)
{
    size_t m = 0;
    uint32_t j, nk = s->vx[keep].count, nr = s->vx[rem].count;
    const uint32_t *ck = s->adj + s->vx[keep].first, *cr = s->adj + s->vx[rem].first;
    dm__qem_sweep(s, keep); /* (the sweep keeps first and count) */
    dm__qem_sweep(s, rem);
    for (j = 0; j < nk; j++, m++) memcpy(s->oring + 3 * m, s->idx + 3 * (size_t)(ck[j] / 3), 3 * sizeof(uint32_t));
    for (j = 0; j < nr; j++) {
        const uint32_t *t = s->idx + 3 * (size_t)(cr[j] / 3);
        if (t[0] == keep || t[1] == keep || t[2] == keep) continue; /* listed with keep */
        memcpy(s->oring + 3 * m, t, 3 * sizeof(uint32_t));
        m++;
    }
    return m;
}

/* Topology: the link condition (Dey, Edelsbrunner et al. 1999; boundary by a virtual vertex
   joined to every boundary vertex), no vertex left with a degenerate fan, and no non-manifold
   vertex opposite the edge (its triangles span several fans: the fan test cannot see one fold,
   nor a triangle land on another's vertices). On the way, the union of the two one-rings (keep's
   neighbours after the collapse) goes to nbr[0 .. nnbr). */
static int dm__qem_check_topology(dm__qem_simp *s, uint32_t keep, uint32_t rem, int fetched)
{
    uint32_t st = dm__qem_new_stamp(s), opp[2], j, nk = s->vx[keep].count, nr = s->vx[rem].count;
    const uint32_t *ck = s->adj + s->vx[keep].first, *cr = s->adj + s->vx[rem].first;
    size_t common = 0, shared = 0, i;
    int both_boundary = (s->vx[keep].flag & s->vx[rem].flag & DM__QEM_V_BOUNDARY) != 0;
    size_t m = 0;
    dm__qem_sweep(s, keep); /* (the sweep keeps first and count) */
    dm__qem_sweep(s, rem);
    DM_COUNT_OPS((size_t)nk + nr);
    /* This is the first touch of the collapse's neighbourhood, cold on a large mesh: the loads
       of its triangles and the records of their vertices go out together first (no branch on
       loaded data in this loop), and the logic below finds them in flight or in cache; unless
       the collapse before asked for them already (dm__qem_ahead). */
    for (j = 0; j < (fetched ? 0 : nk + nr); j++) { /* the two vertices after the corner's own */
        uint32_t c = j < nk ? ck[j] : cr[j - nk], tri = c / 3, slot = c - 3 * tri;
        const uint32_t *t = s->idx + 3 * (size_t)tri;
        const char *x1 = (const char *)&s->vx[t[DM__QEM_NEXT(slot)]];
        const char *x2 = (const char *)&s->vx[t[DM__QEM_PREV(slot)]];
        DM__QEM_PREFETCH(x1);
        DM__QEM_PREFETCH(x1 + 64);
        DM__QEM_PREFETCH(x2);
        DM__QEM_PREFETCH(x2 + 64);
    }
    /* The marks: st for keep's neighbours, st + 1 once seen around rem. Each corner's own
       vertex is keep or rem, so only its two others are looked at. The loops have no
       data-dependent branches (the tests are unpredictable): every vertex is written to nbr and
       the count moves on only for a new one; rem gets a mark too, unused. */
    for (j = 0; j < nk; j++) {
        uint32_t c = ck[j], slot = c % 3, y[2];
        const uint32_t *t = s->idx + (c - slot);
        int k;
        y[0] = t[slot == 0]; /* the other two in triangle order (the order nbr has always had) */
        y[1] = t[2u - (slot == 2)];
        for (k = 0; k < 2; k++) {
            dm__qem_vert *x = &s->vx[y[k]];
            size_t fresh = (size_t)((x->mark != st) & (y[k] != rem));
            x->mark = st;
            s->nbr[m] = y[k];
            m += fresh;
        }
    }
    for (j = 0; j < nr; j++) {
        uint32_t c = cr[j], slot = c % 3, y[2];
        const uint32_t *t = s->idx + (c - slot);
        int k, has_keep;
        y[0] = t[slot == 0]; /* the other two in triangle order (the order nbr has always had) */
        y[1] = t[2u - (slot == 2)];
        has_keep = (y[0] == keep) | (y[1] == keep);
        if (has_keep) {
            if (shared < 2) opp[shared] = y[0] ^ y[1] ^ keep; /* the third vertex */
            shared++;
        }
        for (k = 0; k < 2; k++) {
            dm__qem_vert *x = &s->vx[y[k]];
            size_t live = (size_t)((y[k] != keep) & (x->mark != st + 1)), seen = (size_t)(x->mark == st);
            common += live & seen;
            s->nbr[m] = y[k];
            m += live & (seen ^ 1u);
            x->mark = st + 1;
        }
    }
    s->nnbr = m;
    if (shared == 1) {
        if (!both_boundary || common != 1) return 0;
    } else if (shared == 2) {
        if (both_boundary || common != 2) return 0;
    } else {
        return 0;
    }
    for (i = 0; i < shared; i++) {
        size_t nt = s->vx[opp[i]].count;
        if (s->vx[opp[i]].flag & DM__QEM_V_NONMANIFOLD) return 0;
        if (nt <= ((s->vx[opp[i]].flag & DM__QEM_V_BOUNDARY) ? 1u : 3u)) return 0;
        DM__QEM_PREFETCH(s->adj + s->vx[opp[i]].first); /* the collapse drops a corner there */
    }
    return 1;
}


/* Makes room for n more words at the end of adj: first by compacting it in place (the lists
   that are still current slide down over the dead ones, in pool order), then by growing it. */
static int dm__qem_adj_reserve(dm__qem_simp *s, size_t n)
{
    size_t r = 0, w = 0;
    if (s->adjend + n <= s->adjcap) return 1;
    while (r < s->adjend) {
        uint32_t owner = s->adj[r], len = s->adj[r + 1];
        dm__qem_vert *ov = &s->vx[owner];
        if (ov->first == r + 2) dm__qem_sweep(s, owner);
        if (ov->first == r + 2 && ov->count > 0) {
            uint32_t cnt = ov->count;
            memmove(s->adj + w + 2, s->adj + r + 2, cnt * sizeof(uint32_t));
            s->adj[w] = owner;
            s->adj[w + 1] = cnt;
            ov->first = (uint32_t)(w + 2);
            w += 2 + (size_t)cnt;
        }
        r += 2 + (size_t)len;
    }
    s->adjend = w;
    if (s->adjend + n <= s->adjcap && s->adjend <= s->adjcap - s->adjcap / 4) return 1;
    if (s->adjend + n > DM__QEM_ADJ_MAX) return 0;
    return dm__qem_grow(&s->al, (void **)&s->adj, &s->adjcap, 2 * (s->adjend + n), sizeof(uint32_t));
}

/* Does the collapse rem -> keep with keep moved to `at`, and records it: keep's new corner list
   (its live corners, then rem's) is appended to adj. 0 on allocation failure. */
static int dm__qem_collapse(dm__qem_simp *s, uint32_t keep, uint32_t rem, const float at[3])
{
    dm__qem_rec *r;
    uint32_t opp[3], dead[3], nk, nr, j, *out, *ck, *cr, ndead = 0, nmoved = 0;
    size_t nopp = 0, i;
    int k;
    dm__qem_sweep(s, keep);
    dm__qem_sweep(s, rem);
    nk = s->vx[keep].count;
    nr = s->vx[rem].count;
    if (!dm__qem_adj_reserve(s, 2 + (size_t)nk + nr)) return 0;
    if (!dm__qem_grow(&s->al, (void **)&s->ops, &s->capops, s->nops + nr + 1, sizeof(uint32_t))) return 0;
    if (!dm__qem_grow(&s->al, (void **)&s->rec, &s->caprec, s->nrec + 1, sizeof(dm__qem_rec))) return 0;
    ck = s->adj + s->vx[keep].first;
    cr = s->adj + s->vx[rem].first;
    r = &s->rec[s->nrec]; /* written in place: a copy of a record built on the stack stalls on
                             store forwarding (16-byte loads of 8-byte stores) */
    r->keep = keep;
    r->remove = rem;
    r->first = s->nops;
    for (k = 0; k < 3; k++) {
        r->before[k] = s->pos[3 * (size_t)keep + k];
        r->after[k] = at[k];
    }
    /* The loops below have no branch on the mesh data (which triangle dies is unpredictable):
       every candidate is written and the counts move on by 0 or 1. The topology check let
       at most two triangles of rem contain keep. */
    for (j = 0; j < nr; j++) {
        uint32_t tri = cr[j] / 3, dies;
        const uint32_t *t = s->idx + 3 * (size_t)tri;
        dies = (t[0] == keep) | (t[1] == keep) | (t[2] == keep);
        opp[nopp] = t[0] ^ t[1] ^ t[2] ^ keep ^ rem; /* the third vertex, if it dies */
        dead[nopp] = tri;
        nopp += dies & (nopp < 2);
        s->alive[tri] = (uint8_t)(dies ^ 1u);
        s->ops[s->nops] = tri;
        s->nops += dies;
        ndead += dies;
    }
    out = s->adj + s->adjend;
    out[0] = keep;
    out += 2;
    i = 0;
    if (nopp < 2) dead[1] = dead[0]; /* nopp >= 1: the topology check saw one or two */
    for (j = 0; j < nk; j++) { /* keep's list holds live triangles but the ones that die now */
        uint32_t c = ck[j];
        out[i] = c;
        i += (c - 3u * dead[0] > 2u) & (c - 3u * dead[1] > 2u); /* c / 3 is neither */
    }
    for (j = 0; j < nr; j++) {
        uint32_t c = cr[j], live = s->alive[c / 3];
        s->idx[c] = live ? keep : rem; /* a dead triangle keeps rem, for the vertex split */
        s->ops[s->nops] = c;
        s->nops += live;
        nmoved += live;
        out[i] = c;
        i += live;
    }
    out[-1] = (uint32_t)i;
    s->vx[keep].first = (uint32_t)(s->adjend + 2);
    s->vx[keep].count = s->slots[keep] = (uint32_t)i;
    s->adjend += 2 + i;
    s->vx[rem].count = s->slots[rem] = 0;
    for (i = 0; i < nopp; i++) dm__qem_drop_corner(s, opp[i], dead[i]);
    for (k = 0; k < 3; k++) {
        s->pos[3 * (size_t)keep + k] = at[k];
        s->vx[keep].np[k] = ((double)at[k] - s->center[k]) * s->inv_scale;
    }
    dm__qem_quadric_sum(&s->vx[keep].q, &s->vx[keep].q, &s->vx[rem].q);
    s->vx[rem].flag |= DM__QEM_V_REMOVED;
    s->ver[keep]++;
    s->ver[rem]++;
    s->live -= ndead;
    r->dead = ndead;
    r->moved = nmoved;
    s->nrec++;
    return 1;
}

/* When the constraint was relaxed: every parked vertex (one of its candidates was refused or
   vetoed) gets all its edges queued again, each edge once (from its lower parked endpoint, or
   from the parked one). *queued says whether anything was. */
static int dm__qem_requeue_parked(dm__qem_simp *s, int *queued)
{
    size_t v, i, m;
    *queued = 0;
    /* the queue is empty: it starts again from cost 0, so that the requeued edges go to their
       buckets at their own costs (above the last popped key they would all join the short front
       list, which is searched linearly) */
    s->last = 0;
    s->floor = 0;
    for (v = 0; v < s->n; v++)
        if (s->vx[v].flag & DM__QEM_V_PARKED) s->ver[v]++;
    for (v = 0; v < s->n; v++) {
        size_t keep_n = 0;
        if ((s->vx[v].flag & (DM__QEM_V_PARKED | DM__QEM_V_REMOVED | DM__QEM_V_FROZEN)) != DM__QEM_V_PARKED) continue;
        m = dm__qem_neighbours(s, (uint32_t)v);
        for (i = 0; i < m; i++) { /* an edge to a parked vertex below v was queued from there */
            uint32_t x = s->nbr[i];
            if ((s->vx[x].flag & DM__QEM_V_PARKED) && x < v) continue;
            s->nbr[keep_n++] = x;
        }
        if (keep_n && !dm__qem_push_list(s, (uint32_t)v, s->nbr, keep_n, DM__QEM_NONE)) return 0;
        *queued |= keep_n > 0;
    }
    for (v = 0; v < s->n; v++) s->vx[v].flag &= ~(uint32_t)DM__QEM_V_PARKED;
    return 1;
}

/* After a collapse: new candidates for keep's edges, and a retry of the refused candidates of
   its neighbours, whose one-ring just changed. */
static int dm__qem_refresh(dm__qem_simp *s, uint32_t keep)
{
    size_t m = s->nnbr, i, np = 0; /* from the topology check */
    s->vx[keep].flag &= ~(uint32_t)DM__QEM_V_PARKED;
    for (i = 0; i < m; i++) { /* the parked neighbours: to the ring scratch, new versions */
        uint32_t x = s->nbr[i];
        if (s->vx[x].flag & DM__QEM_V_PARKED) {
            s->vx[x].flag &= ~(uint32_t)DM__QEM_V_PARKED;
            s->ver[x]++;
            s->ring[np++] = x;
        }
    }
    if (!dm__qem_push_list(s, keep, s->nbr, m, DM__QEM_NONE)) return 0;
    for (i = 0; i < np; i++) { /* nbr is reused: the parked ones are in ring */
        size_t mx = dm__qem_neighbours(s, s->ring[i]);
        if (!dm__qem_push_list(s, s->ring[i], s->nbr, mx, keep)) return 0;
    }
    return 1;
}

/* The boundary edge from corner c (of v) to the next vertex of its triangle adds the plane
   through it perpendicular to the triangle to both its ends. */
static void dm__qem_boundary_plane(dm__qem_simp *s, uint32_t v, uint32_t c)
{
    const uint32_t *tr = s->idx + 3 * (size_t)(c / 3);
    uint32_t slot = c % 3, nx = tr[(slot + 1) % 3];
    double p[3][3], e[3], f[3], nrm[3], pl[3], len, l2;
    int k, j;
    for (j = 0; j < 3; j++) dm__qem_norm_pos(s, tr[(slot + (uint32_t)j) % 3], p[j]);
    for (k = 0; k < 3; k++) {
        e[k] = p[1][k] - p[0][k];
        f[k] = p[2][k] - p[0][k];
    }
    dm__cross3(e, f, nrm);
    dm__cross3(e, nrm, pl);
    len = sqrt(pl[0] * pl[0] + pl[1] * pl[1] + pl[2] * pl[2]);
    l2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    if (len > 0.0) {
        double d;
        dm__qem_quadric pq;
        for (k = 0; k < 3; k++) pl[k] /= len;
        d = -(pl[0] * p[0][0] + pl[1] * p[0][1] + pl[2] * p[0][2]);
        memset(&pq, 0, sizeof pq);
        dm__qem_quadric_add_plane(&pq, pl, d, DM__QEM_BOUNDARY_WEIGHT * l2); /* the same terms */
        dm__qem_quadric_sum(&s->vx[v].q, &s->vx[v].q, &pq);
        dm__qem_quadric_sum(&s->vx[nx].q, &s->vx[nx].q, &pq);
    }
}

/* The common case of the classification, a vertex of at most 16 triangles that is manifold:
   each triangle's next one around v is the one whose previous vertex is this one's next, no
   next or previous vertex repeats, and following the links from the one triangle without a
   predecessor (or from any, on a closed fan) visits every triangle. Returns 0 interior,
   1 boundary (its boundary planes added), -1 for anything else (the general code decides). */
static int dm__qem_classify_small(dm__qem_simp *s, uint32_t v, uint32_t *mark, uint32_t *loc, uint32_t st)
{
    uint32_t nxs[16], pvs[16], succ[16], i, j, nc = s->vx[v].count, links = 0, start = 0, steps = 0, has_pred = 0;
    const uint32_t *cl = s->adj + s->vx[v].first;
    if (nc > 16 || nc == 0) return -1;
    for (i = 0; i < nc; i++) {
        const uint32_t *tr = s->idx + 3 * (size_t)(cl[i] / 3);
        uint32_t slot = cl[i] % 3;
        nxs[i] = tr[DM__QEM_NEXT(slot)];
        pvs[i] = tr[DM__QEM_PREV(slot)];
    }
    /* Each triangle's successor around v is the one whose previous vertex is its next one:
       found through the per-vertex scratch (mark, loc) in O(nc). A repeated previous vertex is
       refused at once (in a single fan it would be matched twice), a repeated next one points
       twice at the same triangle (has_pred). */
    for (j = 0; j < nc; j++) {
        uint32_t x = pvs[j];
        if (mark[x] == st) return -1;
        mark[x] = st;
        loc[x] = j;
    }
    for (i = 0; i < nc; i++) {
        uint32_t x = nxs[i], sj = mark[x] == st ? loc[x] : DM__QEM_NONE;
        succ[i] = sj;
        if (sj != DM__QEM_NONE) {
            if (has_pred & (1u << sj)) return -1;
            has_pred |= 1u << sj;
            links++;
        }
    }
    if (links + 1 < nc) return -1;
    while (links < nc && (has_pred & (1u << start))) start++; /* open fan: from the first triangle */
    i = start;
    do {
        steps++;
        i = succ[i];
    } while (i != DM__QEM_NONE && i != start && steps <= nc);
    if (steps != nc || (links == nc) != (i == start)) return -1;
    if (links == nc) return 0;
    for (i = 0; i < nc; i++)
        if (succ[i] == DM__QEM_NONE) dm__qem_boundary_plane(s, v, cl[i]);
    return 1;
}

/* Non-manifold detection, boundary flags and the initial quadrics (triangle planes weighted by
   area; boundary edges add a perpendicular plane). tmp holds 4 n uint32, the last n zeroed. */
static void dm__qem_classify(dm__qem_simp *s, uint32_t *tmp)
{
    uint32_t *loc = tmp, *uf = tmp + s->n, *cnt = tmp + 2 * s->n; /* cnt: out | in << 16 */
    uint32_t *mark = tmp + 3 * s->n, st = 0;
    size_t v, t;
    for (v = 0; v < s->n; v++) {
        size_t m = 0, i, fans = 0;
        int nonmanifold = 0, boundary = 0, small = dm__qem_classify_small(s, (uint32_t)v, mark, loc, ++st);
        uint32_t ci, nc = s->vx[v].count;
        const uint32_t *cl = s->adj + s->vx[v].first;
        if (small >= 0) {
            if (small) s->vx[v].flag |= DM__QEM_V_BOUNDARY;
            continue;
        }
        st++;
        for (ci = 0; ci < nc; ci++) {
            uint32_t c = cl[ci];
            const uint32_t *tr = s->idx + 3 * (size_t)(c / 3);
            uint32_t slot = c % 3, nx = tr[(slot + 1) % 3], pv = tr[(slot + 2) % 3], li[2], x;
            int k;
            for (k = 0; k < 2; k++) {
                x = k ? pv : nx;
                if (mark[x] != st) {
                    mark[x] = st;
                    loc[x] = (uint32_t)m;
                    uf[m] = (uint32_t)m;
                    cnt[m] = 0;
                    s->nbr[m++] = x;
                }
                li[k] = loc[x];
            }
            /* edge v -> nx, edge pv -> v; counts saturate at 2 (all that matters is > 1) */
            if ((cnt[li[0]] & 0xffffu) < 2u) cnt[li[0]] += 1u;
            if ((cnt[li[1]] >> 16) < 2u) cnt[li[1]] += 1u << 16;
            { /* union the two neighbours: they share an edge of the fan */
                uint32_t ra = li[0], rb = li[1];
                while (uf[ra] != ra) ra = uf[ra] = uf[uf[ra]];
                while (uf[rb] != rb) rb = uf[rb] = uf[uf[rb]];
                if (ra != rb) uf[ra > rb ? ra : rb] = ra < rb ? ra : rb;
            }
        }
        for (i = 0; i < m; i++) {
            uint32_t out = cnt[i] & 0xffffu, in = cnt[i] >> 16;
            if (out > 1 || in > 1) nonmanifold = 1;
            else if (out + in == 1) boundary = 1;
            if (uf[i] == i) fans++;
        }
        if (fans > 1) nonmanifold = 1;
        if (nonmanifold) s->vx[v].flag |= DM__QEM_V_NONMANIFOLD;
        if (boundary) s->vx[v].flag |= DM__QEM_V_BOUNDARY;
        if (boundary && !nonmanifold) /* boundary planes, from the edge's tail */
            for (ci = 0; ci < nc; ci++) {
                const uint32_t *tr = s->idx + 3 * (size_t)(cl[ci] / 3);
                uint32_t slot = cl[ci] % 3;
                if (cnt[loc[tr[(slot + 1) % 3]]] == 1u) dm__qem_boundary_plane(s, (uint32_t)v, cl[ci]);
            }
    }
    for (t = 0; t < s->t; t++) {
        const uint32_t *tr = s->idx + 3 * t;
        const double *p0, *p1, *p2;
        double e[3], f[3], nrm[3], len, d;
        dm__qem_quadric pq;
        int k, j;
        for (j = 0; j < 3; j++)
            if (s->vx[tr[j]].flag & DM__QEM_V_NONMANIFOLD) s->vx[tr[j]].flag |= DM__QEM_V_FROZEN;
        p0 = s->vx[tr[0]].np;
        p1 = s->vx[tr[1]].np;
        p2 = s->vx[tr[2]].np;
        for (k = 0; k < 3; k++) {
            e[k] = p1[k] - p0[k];
            f[k] = p2[k] - p0[k];
        }
        nrm[0] = e[1] * f[2] - e[2] * f[1];
        nrm[1] = e[2] * f[0] - e[0] * f[2];
        nrm[2] = e[0] * f[1] - e[1] * f[0];
        len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        if (!(len > 0.0)) continue; /* zero area: no plane */
        for (k = 0; k < 3; k++) nrm[k] /= len;
        d = -(nrm[0] * p0[0] + nrm[1] * p0[1] + nrm[2] * p0[2]);
        memset(&pq, 0, sizeof pq);
        dm__qem_quadric_add_plane(&pq, nrm, d, 0.5 * len); /* once: the same terms go to all three */
        for (j = 0; j < 3; j++) dm__qem_quadric_sum(&s->vx[tr[j]].q, &s->vx[tr[j]].q, &pq);
    }
}

static void dm__qem_simp_free(dm__qem_simp *s)
{
    const dm_allocator *a = &s->al;
    a->free(a->user, s->pos);
    a->free(a->user, s->idx);
    a->free(a->user, s->alive);
    a->free(a->user, s->vraw);
    a->free(a->user, s->adj);
    a->free(a->user, s->nbr);
    a->free(a->user, s->ring);
    a->free(a->user, s->oring);
    a->free(a->user, s->ver);
    a->free(a->user, s->slots);
    while (s->blocks) {
        void *next;
        memcpy(&next, s->blocks, sizeof(void *));
        a->free(a->user, s->blocks);
        s->blocks = next;
    }
    a->free(a->user, s->rec);
    a->free(a->user, s->ops);
    a->free(a->user, s->front);
    a->free(a->user, s->fseq);
}

DMDEF void dm_pm_free(dm_pm *pm)
{
    dm_allocator a;
    if (!pm) return;
    a = pm->alloc;
    a.free(a.user, pm->pos);
    a.free(a.user, pm->idx);
    a.free(a.user, pm->alive);
    a.free(a.user, pm->rec);
    a.free(a.user, pm->ops);
    a.free(a.user, pm->merge_first);
    a.free(a.user, pm->merge_list);
    a.free(a.user, pm->scratch);
    a.free(a.user, pm);
}

/* ---- welding ---- */

/* a position's bits with -0 read as +0, for hashing and comparing */
static void dm__weld_key(const float *p, uint32_t key[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        float x = p[k] == 0.0f ? 0.0f : p[k];
        memcpy(&key[k], &x, sizeof x);
    }
}

static uint32_t dm__weld_hash(const uint32_t key[3])
{
    uint64_t h = 0x9e3779b97f4a7c15ull;
    int k;
    for (k = 0; k < 3; k++) h = (h ^ key[k]) * 0xff51afd7ed558ccdull;
    return (uint32_t)(h ^ (h >> 32));
}

/* remap[v] = the welded id of vertex v in first-use order (UINT32_MAX when unreferenced);
   *welded = the number of welded vertices. Indices must be checked already. */
static dm_result dm__weld_map(const float *pos, size_t nv, const uint32_t *idx, size_t nt, const dm_allocator *a,
                              uint32_t *remap, size_t *welded)
{
    size_t cap = 16, i, count = 0;
    uint32_t *table, *first; /* open addressing: the welded id + 1 (0 = empty); first input vertex of each id */
    int overflow = 0;
    while (cap < 2 * nv) cap *= 2;
    table = (uint32_t *)dm__alloc_array(a, cap, sizeof(uint32_t), &overflow);
    first = (uint32_t *)dm__alloc_array(a, nv, sizeof(uint32_t), &overflow);
    if (!table || !first) {
        a->free(a->user, table);
        a->free(a->user, first);
        return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    }
    memset(table, 0, cap * sizeof(uint32_t));
    for (i = 0; i < nv; i++) remap[i] = UINT32_MAX;
    for (i = 0; i < 3 * nt; i++) {
        uint32_t v = idx[i], key[3], slot;
        if (remap[v] != UINT32_MAX) continue;
        dm__weld_key(pos + 3 * (size_t)v, key);
        for (slot = dm__weld_hash(key) & (uint32_t)(cap - 1);; slot = (slot + 1) & (uint32_t)(cap - 1)) {
            uint32_t other[3];
            if (table[slot] == 0) {
                first[count] = v;
                table[slot] = (uint32_t)++count;
                remap[v] = (uint32_t)(count - 1);
                break;
            }
            dm__weld_key(pos + 3 * (size_t)first[table[slot] - 1], other);
            if (memcmp(key, other, sizeof key) == 0) {
                remap[v] = table[slot] - 1;
                break;
            }
        }
    }
    a->free(a->user, table);
    a->free(a->user, first);
    *welded = count;
    return DM_OK;
}

DMDEF dm_result dm_weld(const float *positions, size_t vertex_count, const uint32_t *indices,
                        size_t triangle_count, const dm_allocator *allocator, float *out_positions,
                        uint32_t *out_indices, size_t *out_vertex_count)
{
    dm_allocator a = dm__resolve_allocator(allocator);
    uint32_t *remap;
    size_t i, welded = 0;
    int overflow = 0;
    dm_result r;
    if (!out_positions || !out_indices || !out_vertex_count) return DM_ERR_INVALID_ARGUMENT;
    *out_vertex_count = 0;
    r = dm__check_mesh(positions, vertex_count, indices, triangle_count);
    if (r != DM_OK) return r;
    remap = (uint32_t *)dm__alloc_array(&a, vertex_count, sizeof(uint32_t), &overflow);
    if (!remap) return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    r = dm__weld_map(positions, vertex_count, indices, triangle_count, &a, remap, &welded);
    if (r == DM_OK) {
        size_t written = 0; /* ids come in first-use order: the first corner of each id writes it */
        for (i = 0; i < 3 * triangle_count; i++) {
            uint32_t id = remap[indices[i]];
            out_indices[i] = id;
            if (id == written) memcpy(out_positions + 3 * written++, positions + 3 * (size_t)indices[i], 3 * sizeof(float));
        }
        *out_vertex_count = welded;
    }
    a.free(a.user, remap);
    return r;
}

/* ---- dm_orient: triangles turned to agree with their neighbours ---------------------------- */

/* nb[he]: the triangle across half-edge he where exactly two triangles share its edge (either
   direction), else DM_NO_HIT; same[he] = 1 when that triangle runs the edge the same way. */
static void dm__orient_links(const uint32_t *idx, size_t nt, dm__edge *e, uint32_t *nb, uint8_t *same)
{
    size_t i, j, n = 3 * nt;
    for (i = 0; i < n; i++) {
        nb[i] = DM_NO_HIT;
        same[i] = 0;
    }
    dm__sorted_edges(idx, nt, e);
    for (i = 0; i < n; i = j) {
        for (j = i + 1; j < n && e[j].key == e[i].key; j++) {}
        if (j - i == 2 && e[i].he / 3 != e[i + 1].he / 3 && (e[i].key >> 32) != (e[i].key & 0xffffffffu)) {
            uint32_t h0 = e[i].he, h1 = e[i + 1].he;
            nb[h0] = h1 / 3;
            nb[h1] = h0 / 3;
            same[h0] = same[h1] = (uint8_t)(idx[h0] == idx[h1]);
        }
    }
}

/* The parts (triangles joined across links), each walked breadth-first from its lowest triangle:
   flip[t] = 1 where t must turn to agree with it. order[] lists the triangles part by part
   (start[p] to start[p + 1]); returns the part count. A link the walk cannot satisfy (a
   non-orientable part) is left as it is. */
static size_t dm__orient_walk(const uint32_t *nb, const uint8_t *same, size_t nt, uint32_t *part, uint8_t *flip,
                              uint32_t *order, uint32_t *start)
{
    size_t t, head = 0, tail = 0, np = 0;
    for (t = 0; t < nt; t++) part[t] = DM_NO_HIT;
    for (t = 0; t < nt; t++) {
        if (part[t] != DM_NO_HIT) continue;
        start[np] = (uint32_t)tail;
        part[t] = (uint32_t)np;
        flip[t] = 0;
        order[tail++] = (uint32_t)t;
        while (head < tail) {
            uint32_t u = order[head++];
            int k;
            for (k = 0; k < 3; k++) {
                size_t h = 3 * (size_t)u + (size_t)k;
                uint32_t w = nb[h];
                if (w == DM_NO_HIT || part[w] != DM_NO_HIT) continue;
                part[w] = (uint32_t)np;
                flip[w] = (uint8_t)(flip[u] ^ same[h]);
                order[tail++] = w;
            }
        }
        np++;
    }
    start[np] = (uint32_t)tail;
    return np;
}

/* corners of triangle t as walked (b and c swapped where flip[t]) */
static void dm__orient_corners(const float *pos, const uint32_t *idx, const uint8_t *flip, size_t t, double q[3][3])
{
    dm__load3(pos, idx[3 * t], q[0]);
    dm__load3(pos, idx[3 * t + (flip[t] ? 2 : 1)], q[1]);
    dm__load3(pos, idx[3 * t + (flip[t] ? 1 : 2)], q[2]);
}

/* Part p as walked: *vol = its enclosed volume seen from its area centroid (6 x), *area (2 x),
   *turned_area (2 x, of its triangles with flip set), *mixed (any flip set), *closed (every edge
   linked), at = the centroid of its largest triangle, box = its bounding box. */
typedef struct dm__orient_part {
    double vol, area, turned_area, at[3], lo[3], hi[3];
    int mixed, closed;
} dm__orient_part;

static void dm__orient_measure(const float *pos, const uint32_t *idx, const uint32_t *nb, const uint8_t *flip,
                               const uint32_t *tris, size_t n, dm__orient_part *pt)
{
    double c[3] = {0.0, 0.0, 0.0}, best = -1.0, q[3][3], e1[3], e2[3], x[3], r[3], a;
    size_t i;
    int k, j;
    memset(pt, 0, sizeof *pt);
    pt->closed = 1;
    for (k = 0; k < 3; k++) {
        pt->lo[k] = DBL_MAX;
        pt->hi[k] = -DBL_MAX;
    }
    for (i = 0; i < n; i++) { /* area, the centroid, the box, the largest triangle */
        size_t t = tris[i];
        dm__orient_corners(pos, idx, flip, t, q);
        dm__sub3(q[1], q[0], e1);
        dm__sub3(q[2], q[0], e2);
        dm__cross3(e1, e2, x);
        a = dm__len3(x);
        pt->area += a;
        if (flip[t]) pt->turned_area += a;
        pt->mixed |= flip[t];
        for (k = 0; k < 3; k++) {
            c[k] += a * (q[0][k] + q[1][k] + q[2][k]) / 3.0;
            for (j = 0; j < 3; j++) {
                if (q[j][k] < pt->lo[k]) pt->lo[k] = q[j][k];
                if (q[j][k] > pt->hi[k]) pt->hi[k] = q[j][k];
            }
            pt->closed &= nb[3 * t + (size_t)k] != DM_NO_HIT;
        }
        if (a > best) {
            best = a;
            for (k = 0; k < 3; k++) pt->at[k] = (q[0][k] + q[1][k] + q[2][k]) / 3.0;
        }
    }
    if (pt->area > 0.0)
        for (k = 0; k < 3; k++) c[k] /= pt->area;
    for (i = 0; i < n; i++) { /* the volume of the cones from the centroid */
        dm__orient_corners(pos, idx, flip, tris[i], q);
        dm__sub3(q[1], q[0], e1);
        dm__sub3(q[2], q[0], e2);
        dm__cross3(e1, e2, x);
        dm__sub3(q[0], c, r);
        pt->vol += dm__dot3(r, x);
    }
}

/* 1 when the ray from o along the fixed direction D crosses triangle t (Moeller-Trumbore) */
static int dm__orient_crosses(const float *pos, const uint32_t *idx, size_t t, const double o[3])
{
    static const double D[3] = {0.5734623443633283, 0.5239859690962837, 0.6297937373427766};
    double q[3][3], e1[3], e2[3], s[3], h[3], w[3], det, u, v, tt;
    int k;
    for (k = 0; k < 3; k++) dm__load3(pos, idx[3 * t + (size_t)k], q[k]);
    dm__sub3(q[1], q[0], e1);
    dm__sub3(q[2], q[0], e2);
    dm__cross3(D, e2, h);
    det = dm__dot3(e1, h);
    if (det == 0.0) return 0;
    dm__sub3(o, q[0], s);
    u = dm__dot3(s, h) / det;
    if (!(u >= 0.0 && u <= 1.0)) return 0;
    dm__cross3(s, e1, w);
    v = dm__dot3(D, w) / det;
    if (!(v >= 0.0 && u + v <= 1.0)) return 0;
    tt = dm__dot3(e2, w) / det;
    return tt > 0.0;
}

/* 1 when part p lies inside an odd number of the other closed parts (a cavity's wall): one
   ray's crossings from its largest triangle, against each closed part whose box holds p's box
   (parts that only overlap, as primitives built into one model do, are not nested) */
static int dm__orient_nested(const float *pos, const uint32_t *idx, const uint32_t *order, const uint32_t *start,
                             const dm__orient_part *parts, size_t np, size_t p)
{
    const double *o = parts[p].at;
    size_t q, i;
    int odd = 0;
    for (q = 0; q < np; q++) {
        const dm__orient_part *b = parts + q;
        int k, in = 1, cross = 0;
        if (q == p || !b->closed) continue;
        for (k = 0; k < 3; k++) in &= parts[p].lo[k] >= b->lo[k] && parts[p].hi[k] <= b->hi[k];
        if (!in) continue;
        for (i = start[q]; i < start[q + 1]; i++) cross ^= dm__orient_crosses(pos, idx, order[i], o);
        odd ^= cross;
    }
    return odd;
}

/* Whether part p, as walked, turns as a whole. A closed part faces out of the volume it encloses
   (into it when nested in an odd number of closed parts), except that one whose triangles agreed
   and faced out already is left as it is (not tested for nesting). An open part whose triangles
   agreed is left as it is; else it faces out of what it clearly encloses (|vol| >=
   DM__ORIENT_BOWL area^1.5), or the way most of its area faced. */
#define DM__ORIENT_BOWL 0.01
static int dm__orient_turns(const float *pos, const uint32_t *idx, const uint32_t *order, const uint32_t *start,
                            const dm__orient_part *parts, size_t np, size_t p)
{
    const dm__orient_part *pt = parts + p;
    double a = 0.5 * pt->area, v = pt->vol / 6.0;
    if (pt->closed && v != 0.0 && (pt->mixed || v < 0.0))
        return (v < 0.0) != dm__orient_nested(pos, idx, order, start, parts, np, p);
    if (!pt->mixed) return 0;
    if (fabs(v) >= DM__ORIENT_BOWL * a * sqrt(a)) return v < 0.0;
    return pt->turned_area > 0.5 * pt->area;
}

DMDEF dm_result dm_orient(const float *positions, size_t vertex_count, uint32_t *indices, size_t triangle_count,
                          const dm_allocator *allocator, size_t *turned)
{
    dm__scratch sc;
    dm__edge *e;
    uint32_t *nb, *part, *order, *start;
    uint8_t *same, *flip;
    dm__orient_part *parts;
    size_t np, p, i, count = 0;
    dm_result r;
    if (turned) *turned = 0;
    r = dm__check_mesh(positions, vertex_count, indices, triangle_count);
    if (r != DM_OK) return r;
    memset(&sc, 0, sizeof sc);
    sc.a = dm__resolve_allocator(allocator);
    e = (dm__edge *)dm__take(&sc, 3 * triangle_count, sizeof(dm__edge)); /* 1. links across edges */
    nb = (uint32_t *)dm__take(&sc, 3 * triangle_count, sizeof(uint32_t));
    same = (uint8_t *)dm__take(&sc, 3 * triangle_count, 1);
    part = (uint32_t *)dm__take(&sc, triangle_count, sizeof(uint32_t));
    order = (uint32_t *)dm__take(&sc, triangle_count, sizeof(uint32_t));
    start = (uint32_t *)dm__take(&sc, triangle_count + 1, sizeof(uint32_t));
    flip = (uint8_t *)dm__take(&sc, triangle_count, 1);
    if (!e || !nb || !same || !part || !order || !start || !flip) goto fail;
    dm__orient_links(indices, triangle_count, e, nb, same);
    np = dm__orient_walk(nb, same, triangle_count, part, flip, order, start); /* 2. parts */
    parts = (dm__orient_part *)dm__take(&sc, np, sizeof(dm__orient_part));
    if (!parts) goto fail;
    for (p = 0; p < np; p++) /* 3. each part measured as walked */
        dm__orient_measure(positions, indices, nb, flip, order + start[p], start[p + 1] - start[p], parts + p);
    for (p = 0; p < np; p++) /* 4. which way each part faces */
        if (dm__orient_turns(positions, indices, order, start, parts, np, p))
            for (i = start[p]; i < start[p + 1]; i++) flip[order[i]] ^= 1;
    for (i = 0; i < triangle_count; i++) /* 5. the triangles turned */
        if (flip[i]) {
            uint32_t b = indices[3 * i + 1];
            indices[3 * i + 1] = indices[3 * i + 2];
            indices[3 * i + 2] = b;
            count++;
        }
    if (turned) *turned = count;
    dm__release(&sc);
    return DM_OK;
fail:
    r = dm__scratch_fail(&sc);
    dm__release(&sc);
    return r;
}

/* A mesh in which no vertex is in two triangles cannot be simplified; when positions repeat it is
   an unwelded mesh (an STL file, say), which the caller should weld rather than get back as it was. */
static dm_result dm__qem_check_welded(dm__qem_simp *s, const float *positions, size_t vertex_count)
{
    uint32_t *remap;
    size_t welded = 0, used = 0, v;
    int overflow = 0;
    dm_result r;
    remap = (uint32_t *)dm__alloc_array(&s->al, vertex_count, sizeof(uint32_t), &overflow);
    if (!remap) return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    r = dm__weld_map(positions, vertex_count, s->idx, s->t, &s->al, remap, &welded);
    for (v = 0; v < vertex_count; v++) used += remap[v] != UINT32_MAX;
    s->al.free(s->al.user, remap);
    if (r != DM_OK) return r;
    return welded < used ? DM_ERR_NOT_WELDED : DM_OK;
}

/* Input checks and the simplifier's arrays (triangles with a repeated index dropped). */
static dm_result dm__qem_simp_init(dm__qem_simp *s, const float *positions, size_t vertex_count, const uint32_t *indices,
                               size_t triangle_count, size_t *dropped)
{
    size_t v, t, kept = 0;
    int overflow = 0;
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    if (!indices || !positions) return DM_ERR_INVALID_ARGUMENT;
    if (triangle_count == 0) return DM_ERR_NO_TRIANGLES;
    if (vertex_count == 0) return DM_ERR_BAD_INDEX;
    if (vertex_count >= 0xffffffffu || triangle_count > 0x55555554u ||
        3 * (double)triangle_count + 2 * (double)vertex_count > (double)DM__QEM_ADJ_MAX)
        return DM_ERR_TOO_LARGE; /* corner ids and the corner pool's offsets are 32-bit */
    if (vertex_count > (size_t)-1 / (3 * sizeof(uint32_t)) || triangle_count > (size_t)-1 / (3 * sizeof(uint32_t)))
        return DM_ERR_TOO_LARGE;
    for (t = 0; t < 3 * triangle_count; t++)
        if (indices[t] >= vertex_count) return DM_ERR_BAD_INDEX;
    s->n = vertex_count;
#define DM__QEM_ALLOC(field, count, type)                                                      \
    do {                                                                                   \
        s->field = (type *)dm__alloc_array(&s->al, (count), sizeof(type), &overflow);      \
        if (!s->field) return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;          \
    } while (0)
    DM__QEM_ALLOC(pos, 3 * vertex_count, float);
    DM__QEM_ALLOC(idx, 3 * triangle_count, uint32_t);
    DM__QEM_ALLOC(alive, triangle_count, uint8_t);
    DM__QEM_ALLOC(nbr, vertex_count, uint32_t);
    DM__QEM_ALLOC(ver, vertex_count, uint32_t);
    DM__QEM_ALLOC(slots, vertex_count, uint32_t);
    /* the positions of the vertices used, each once (not once per corner) */
    memset(s->ver, 0, vertex_count * sizeof(uint32_t));
    for (t = 0; t < 3 * triangle_count; t++) s->ver[indices[t]] = 1;
    for (v = 0; v < vertex_count; v++) {
        int k;
        if (!s->ver[v]) continue;
        for (k = 0; k < 3; k++) {
            float x = positions[3 * v + (size_t)k];
            if (!(x >= -DM__MAX_COORD && x <= DM__MAX_COORD)) return DM_ERR_BAD_POSITION;
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    }
    DM__QEM_ALLOC(ring, 3 * triangle_count > 3 * vertex_count ? 3 * triangle_count : 3 * vertex_count, uint32_t);
    if (s->opt->constraint || s->opt->on_collapse) DM__QEM_ALLOC(oring, 3 * triangle_count, uint32_t);
    /* the corner pool: every list with its header, and half as much again for the appended
       lists (compacted in place when full) */
    s->adjcap = 3 * triangle_count + 2 * vertex_count;
    s->adjcap += s->adjcap / 2 + 64;
    if (s->adjcap > DM__QEM_ADJ_MAX) s->adjcap = DM__QEM_ADJ_MAX;
    DM__QEM_ALLOC(adj, s->adjcap, uint32_t);
#undef DM__QEM_ALLOC
    if (vertex_count > ((size_t)-1 - 64) / sizeof(dm__qem_vert)) return DM_ERR_TOO_LARGE;
    s->vraw = s->al.alloc(s->al.user, vertex_count * sizeof(dm__qem_vert) + 64);
    if (!s->vraw) return DM_ERR_OUT_OF_MEMORY;
    s->vx = (dm__qem_vert *)(void *)((char *)s->vraw + (64 - (size_t)((uintptr_t)s->vraw & 63)) % 64);
    memcpy(s->pos, positions, 3 * vertex_count * sizeof(float));
    for (t = 0; t < triangle_count; t++) {
        const uint32_t *tr = indices + 3 * t;
        if (tr[0] == tr[1] || tr[1] == tr[2] || tr[0] == tr[2]) continue;
        memcpy(s->idx + 3 * kept, tr, 3 * sizeof(uint32_t));
        s->alive[kept++] = 1;
    }
    *dropped = triangle_count - kept;
    s->t = kept;
    s->live = kept;
    memset(s->vx, 0, vertex_count * sizeof(dm__qem_vert));
    memset(s->ver, 0, vertex_count * sizeof(uint32_t));
    memset(s->slots, 0, vertex_count * sizeof(uint32_t));
    s->stamp = 0;
    /* counting sort, lists in increasing corner order; counts and cursors in the dense ver and
       nbr arrays (random increments in the 128-byte records miss the cache) */
    for (t = 0; t < 3 * kept; t++) s->ver[s->idx[t]]++;
    s->adjend = 0;
    for (v = 0; v < vertex_count; v++) {
        uint32_t cnt = s->ver[v];
        if (!cnt) continue;
        s->adj[s->adjend] = (uint32_t)v;
        s->adj[s->adjend + 1] = cnt;
        s->vx[v].first = s->nbr[v] = (uint32_t)(s->adjend + 2);
        s->vx[v].count = s->slots[v] = cnt;
        s->adjend += 2 + (size_t)cnt;
    }
    for (t = 0; t < 3 * kept; t++) s->adj[s->nbr[s->idx[t]]++] = (uint32_t)t;
    memset(s->ver, 0, vertex_count * sizeof(uint32_t));
    for (v = 0; v < 3; v++) {
        s->center[v] = 0.5 * ((double)lo[v] + (double)hi[v]);
        if ((double)hi[v] - lo[v] > s->scale) s->scale = (double)hi[v] - lo[v];
    }
    if (!(s->scale > 0.0)) s->scale = 1.0;
    s->inv_scale = 1.0 / s->scale;
    for (v = 0; v < vertex_count; v++) {
        int k;
        for (k = 0; k < 3; k++)
            s->vx[v].np[k] = ((double)positions[3 * v + (size_t)k] - s->center[k]) * s->inv_scale;
    }
    for (v = 0; v < vertex_count && s->vx[v].count <= 1; v++) {}
    return v == vertex_count && kept > 1 ? dm__qem_check_welded(s, positions, vertex_count) : DM_OK;
}

/* The progressive mesh from the simplifier's final state (arrays moved, not copied). */
static dm_result dm__qem_make_pm(dm__qem_simp *s, dm_pm **out)
{
    dm_pm *pm;
    int overflow = 0;
    size_t i, v;
    uint32_t *root;
    pm = (dm_pm *)s->al.alloc(s->al.user, sizeof(dm_pm));
    if (!pm) return DM_ERR_OUT_OF_MEMORY;
    memset(pm, 0, sizeof *pm);
    pm->alloc = s->al;
    pm->merge_first = (uint32_t *)dm__alloc_array(&s->al, s->n + 1, sizeof(uint32_t), &overflow);
    pm->merge_list = (uint32_t *)dm__alloc_array(&s->al, s->n, sizeof(uint32_t), &overflow);
    pm->scratch = (uint32_t *)dm__alloc_array(&s->al, s->n, sizeof(uint32_t), &overflow);
    if (!pm->merge_first || !pm->merge_list || !pm->scratch) {
        dm_pm_free(pm);
        return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    }
    pm->vertex_count = s->n;
    pm->triangle_count = s->t;
    pm->split_count = s->nrec;
    pm->live_triangles = s->live;
    pm->pos = s->pos;
    pm->idx = s->idx;
    pm->alive = s->alive;
    pm->rec = s->rec;
    pm->ops = s->ops;
    s->pos = NULL;
    s->idx = NULL;
    s->alive = NULL;
    s->rec = NULL;
    s->ops = NULL;
    /* merged sets: each vertex's representative at the base, found by replaying the collapses
       from the last; then bucketed by representative in increasing id */
    root = pm->scratch;
    for (v = 0; v < s->n; v++) root[v] = (uint32_t)v;
    for (i = pm->split_count; i-- > 0;) root[pm->rec[i].remove] = root[pm->rec[i].keep];
    memset(pm->merge_first, 0, (s->n + 1) * sizeof(uint32_t));
    for (v = 0; v < s->n; v++) pm->merge_first[root[v] + 1]++;
    for (v = 0; v < s->n; v++) pm->merge_first[v + 1] += pm->merge_first[v];
    for (v = 0; v < s->n; v++) pm->merge_list[pm->merge_first[root[v]]++] = (uint32_t)v;
    for (v = s->n; v > 0; v--) pm->merge_first[v] = pm->merge_first[v - 1];
    pm->merge_first[0] = 0;
    /* referenced vertices at the base */
    memset(pm->scratch, 0, s->n * sizeof(uint32_t));
    for (i = 0; i < pm->triangle_count; i++)
        if (pm->alive[i])
            for (v = 0; v < 3; v++) pm->scratch[pm->idx[3 * i + v]] = 1;
    for (v = 0; v < s->n; v++) pm->live_vertices += pm->scratch[v];
    *out = pm;
    return DM_OK;
}

/* dm_simplify's setup: the working state, the vertex classes (boundary, frozen), the locks;
   frozen gets the count of frozen vertices */
static dm_result dm__qem_prepare(dm__qem_simp *s, const float *positions, size_t vertex_count,
                                 const uint32_t *indices, size_t triangle_count, size_t *dropped, size_t *frozen)
{
    const dm_simplify_options *opt = s->opt;
    uint32_t *tmp;
    size_t v;
    int overflow = 0;
    dm_result r = dm__qem_simp_init(s, positions, vertex_count, indices, triangle_count, dropped);
    if (r != DM_OK) return r;
    tmp = (uint32_t *)dm__alloc_array(&s->al, 4 * vertex_count, sizeof(uint32_t), &overflow);
    if (!tmp) return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    memset(tmp + 3 * vertex_count, 0, vertex_count * sizeof(uint32_t));
    dm__qem_classify(s, tmp);
    s->al.free(s->al.user, tmp);
    for (v = 0; v < vertex_count; v++) {
        if (opt->locked && opt->locked[v]) s->vx[v].flag |= DM__QEM_V_LOCKED;
        if ((opt->flags & DM_SIMPLIFY_LOCK_BOUNDARY) && (s->vx[v].flag & DM__QEM_V_BOUNDARY)) s->vx[v].flag |= DM__QEM_V_LOCKED;
        if (s->vx[v].flag & DM__QEM_V_FROZEN) (*frozen)++;
    }
    return DM_OK;
}

/* the first candidates: every collapsible edge once, from its lower endpoint. A vertex that is
   not frozen is manifold: its neighbours are the next vertices of its corners, each once, and
   on a boundary also the one previous vertex that is nobody's next. Costed and pushed by
   batches. */
static dm_result dm__qem_seed_edges(dm__qem_simp *s, size_t vertex_count)
{
    uint32_t ea[DM__QEM_BATCH], eb[DM__QEM_BATCH];
    size_t v, nedge;
    for (v = 0, nedge = 0; v < vertex_count; v++) {
        uint32_t i, nc = s->vx[v].count, st = 0;
        const uint32_t *cl = s->adj + s->vx[v].first;
        if (s->vx[v].flag & DM__QEM_V_FROZEN) continue;
        DM_COUNT_OPS(2 * (size_t)nc);
        if (s->vx[v].flag & DM__QEM_V_BOUNDARY) { /* the next vertices marked: nobody's next is unmarked */
            st = dm__qem_new_stamp(s);
            for (i = 0; i < nc; i++) s->vx[s->idx[cl[i] - cl[i] % 3 + DM__QEM_NEXT(cl[i] % 3)]].mark = st;
        }
        for (i = 0; i < 2 * nc; i++) {
            uint32_t ci = cl[i < nc ? i : i - nc], slot = ci % 3, x;
            const uint32_t *t = s->idx + (ci - slot);
            if (i < nc) {
                x = t[DM__QEM_NEXT(slot)];
            } else {
                if (!(s->vx[v].flag & DM__QEM_V_BOUNDARY)) break;
                x = t[DM__QEM_PREV(slot)];
                if (s->vx[x].mark == st) continue;
            }
            if (x < v) continue;
            if (nedge == DM__QEM_BATCH) {
                if (!dm__qem_push_edges(s, ea, eb, nedge)) return DM_ERR_OUT_OF_MEMORY;
                nedge = 0;
            }
            ea[nedge] = (uint32_t)v;
            eb[nedge++] = x;
        }
    }
    if (nedge && !dm__qem_push_edges(s, ea, eb, nedge)) return DM_ERR_OUT_OF_MEMORY;
    return DM_OK;
}

/* the records for the collapses to come (one per 2 triangles, about 6 ops each): grown by
   doubling they would be copied several times */
static dm_result dm__qem_reserve(dm__qem_simp *s, size_t to_remove, size_t vertex_count)
{
    size_t expect = to_remove / 2 + 16;
    if (s->opt->max_collapses && expect > s->opt->max_collapses) expect = s->opt->max_collapses;
    if (expect > vertex_count) expect = vertex_count;
    if (!dm__qem_grow(&s->al, (void **)&s->rec, &s->caprec, expect, sizeof(dm__qem_rec)) ||
        !dm__qem_grow(&s->al, (void **)&s->ops, &s->capops, 7 * expect, sizeof(uint32_t)))
        return DM_ERR_OUT_OF_MEMORY;
    return DM_OK;
}

/* The cost and error of collapse (keep, rem) with keep at `at`; if that costs much more than the
   candidate was queued at, it goes back in the queue at that cost: returns 1 (0 if not, -1 when
   out of memory). */
static int dm__qem_requeue_if_dear(dm__qem_simp *s, const dm__qem_cand *e, uint32_t keep, uint32_t rem,
                                   const float at[3], double *cost, double *err)
{
    dm__qem_quadric qs;
    dm__qem_cand e2;
    double q[3];
    int k;
    for (k = 0; k < 3; k++) q[k] = ((double)at[k] - s->center[k]) * s->inv_scale;
    dm__qem_quadric_sum(&qs, &s->vx[keep].q, &s->vx[rem].q);
    *cost = dm__qem_quadric_eval(&qs, q);
    *err = qs.w > 0.0 ? sqrt(*cost / qs.w) * s->scale : 0.0;
    e2 = dm__qem_make_cand(s, DM__QEM_CAND_A(e), e->b, *cost);
    e2.stamp |= e->stamp & DM__QEM_RETRY;
    if (!((e2.key >> 32) > (e->key >> 32) && (double)*cost > DM__QEM_REQUEUE * (double)dm__qem_key_cost(e->key)))
        return 0;
    if (!dm__qem_heap_push(s, &e2)) return -1;
    s->requeued++;
    return 1;
}

/* May keep go to `at`, where the constraint moved it: finite, not a locked vertex or a boundary
   one that absorbs an interior one (those stay put), and no flip or degenerate triangle there
   (which refills the ring scratch at `at`). */
static int dm__qem_move_ok(dm__qem_simp *s, uint32_t keep, uint32_t rem, const float at[3])
{
    int k, ok = 1;
    for (k = 0; k < 3; k++) ok &= at[k] >= -DM__MAX_COORD && at[k] <= DM__MAX_COORD;
    if (((s->vx[keep].flag & DM__QEM_V_LOCKED) || ((s->vx[keep].flag ^ s->vx[rem].flag) & DM__QEM_V_BOUNDARY)) &&
        memcmp(at, s->pos + 3 * (size_t)keep, 3 * sizeof(float)) != 0)
        ok = 0;
    return ok && dm__qem_check_geometry(s, keep, rem, at) != (size_t)-1;
}

/* The candidate as the constraint sees it (metric: the summed quadrics' matrix). */
static void dm__qem_fill_collapse(dm__qem_simp *s, uint32_t keep, uint32_t rem, const float at[3], double err,
                                  size_t ring_count, dm_collapse *c)
{
    const dm__qem_quadric *qa = &s->vx[keep].q, *qb = &s->vx[rem].q;
    int k;
    c->keep = keep;
    c->remove = rem;
    for (k = 0; k < 3; k++) c->position[k] = at[k];
    c->error = err;
    c->positions = s->pos;
    c->triangles = s->ring;
    c->triangle_count = ring_count;
    c->old_triangles = s->oring;
    c->old_triangle_count = dm__qem_old_ring(s, keep, rem);
    c->level = s->nrec;
    c->metric[0] = qa->a00 + qb->a00;
    c->metric[1] = qa->a01 + qb->a01;
    c->metric[2] = qa->a02 + qb->a02;
    c->metric[3] = qa->a11 + qb->a11;
    c->metric[4] = qa->a12 + qb->a12;
    c->metric[5] = qa->a22 + qb->a22;
    c->placement_only = 0;
    c->relaxed = 0;
}

/* the user's constraint on collapse (keep, rem) of candidate e to at: 1 = go on (at, cost and
   err as the constraint moved them), 0 = skip it (vetoed: both ends parked; or moved to where it
   costs much more: back in the queue at that cost), -1 = out of memory. First only where keep
   would go is asked for; a candidate that waits needs no more. */
static int dm__qem_ask_constraint(dm__qem_simp *s, const dm__qem_cand *e, uint32_t keep, uint32_t rem, float at[3],
                                  double *cost, double *err, size_t ring_count)
{
    const dm_simplify_options *opt = s->opt;
    dm_collapse cand;
    float corrected[3];
    int verdict, k, wait;
    dm__qem_fill_collapse(s, keep, rem, at, *err, ring_count, &cand);
    cand.relaxed = (e->stamp & DM__QEM_RETRY) != 0;
    for (k = 0; k < 3; k++) corrected[k] = at[k];
    cand.placement_only = 1;
    verdict = opt->constraint(opt->constraint_user, &cand, corrected);
    if (verdict == DM_COLLAPSE_PLACED) {
        double c2, e2;
        wait = dm__qem_requeue_if_dear(s, e, keep, rem, corrected, &c2, &e2);
        if (wait) return wait < 0 ? -1 : 0;
        cand.placement_only = 0;
        for (k = 0; k < 3; k++) corrected[k] = at[k];
        verdict = opt->constraint(opt->constraint_user, &cand, corrected);
        if (verdict == DM_COLLAPSE_PLACED) verdict = DM_COLLAPSE_VETO; /* not an answer in full */
    }
    if (verdict == DM_COLLAPSE_MOVE) {
        for (k = 0; k < 3; k++) at[k] = corrected[k];
        if (!dm__qem_move_ok(s, keep, rem, at)) {
            verdict = DM_COLLAPSE_VETO;
        } else {
            wait = dm__qem_requeue_if_dear(s, e, keep, rem, at, cost, err);
            if (wait) return wait < 0 ? -1 : 0;
        }
    } else if (verdict != DM_COLLAPSE_ALLOW) {
        verdict = DM_COLLAPSE_VETO;
    }
    if (verdict == DM_COLLAPSE_VETO) {
        s->vetoed++;
        if (opt->relax && !cand.relaxed && s->relax_cost > 0.0) { /* back later, to be asked relaxed */
            dm__qem_cand e2 = dm__qem_make_cand(s, DM__QEM_CAND_A(e), e->b, s->relax_cost * *cost);
            e2.stamp |= DM__QEM_RETRY;
            if (!dm__qem_heap_push(s, &e2)) return -1;
        }
        s->vx[DM__QEM_CAND_A(e)].flag |= DM__QEM_V_PARKED;
        s->vx[e->b].flag |= DM__QEM_V_PARKED;
        return 0;
    }
    return 1;
}

/* the user's on_collapse told of collapse (keep, rem) to at, before it is made */
static void dm__qem_tell_collapse(dm__qem_simp *s, uint32_t keep, uint32_t rem, const float at[3], double err,
                                  size_t ring_count)
{
    dm_collapse done_c;
    dm__qem_fill_collapse(s, keep, rem, at, err, ring_count, &done_c); /* the ring from the geometry check at `at` */
    s->opt->on_collapse(s->opt->constraint_user, &done_c);
}

/* the collapse loop: the cheapest candidate first, checked (stale, placement, error bound,
   topology, geometry, the user's constraint), then made; until the target, the collapse bound
   or an empty queue (after which the constraint may relax and the parked edges come back) */
static dm_result dm__qem_collapse_loop(dm__qem_simp *s, dm_simplify_report *rep, size_t to_remove)
{
    const dm_simplify_options *opt = s->opt;
    size_t next_progress = 0;
    while ((s->target == 0 || s->live > s->target) && (opt->max_collapses == 0 || s->nrec < opt->max_collapses)) {
        dm__qem_cand e;
        uint32_t ea, keep, rem;
        double x[3], cost, err;
        float at[3];
        size_t ring_count;
        int k, placed, got = dm__qem_next(s, &e);
        if (got < 0) return DM_ERR_OUT_OF_MEMORY;
        if (got == 0) {
            int again = 0;
            if (s->min_quality > 0.0 && s->target && s->live > s->target && s->rejected > 0) {
                s->min_quality = 0.0; /* the sliver guard gives way before the target does */
                if (!dm__qem_requeue_parked(s, &again)) return DM_ERR_OUT_OF_MEMORY;
            }
            if (!again && opt->relax && s->target && s->live > s->target && s->vetoed > 0 && opt->relax(opt->constraint_user)) {
                rep->relaxed++;
                if (!dm__qem_requeue_parked(s, &again)) return DM_ERR_OUT_OF_MEMORY;
            }
            if (!again) break;
            continue;
        }
        s->floor = e.key;
        dm__qem_ahead(s, 0, 1); /* the next one: its triangles */
        ea = DM__QEM_CAND_A(&e);
        DM__QEM_PREFETCH(&s->vx[ea]); /* in flight while the versions are read */
        DM__QEM_PREFETCH(&s->vx[e.b]);
        if (dm__qem_stale(s, &e)) continue; /* a collapse bumped a version (removed ones too) */
        DM__QEM_PREFETCH(s->adj + s->vx[ea].first); /* for the topology check, while placing */
        DM__QEM_PREFETCH(s->adj + s->vx[e.b].first);
        placed = dm__qem_place(s, ea, e.b, &keep, &rem, x, &cost);
        if (!placed) continue;
        err = dm__qem_error(s, ea, e.b, cost);
        if (opt->target_error > 0.0 && err > opt->target_error) continue;
        for (k = 0; k < 3; k++)
            at[k] = placed == 2 ? s->pos[3 * (size_t)keep + k] : (float)(s->center[k] + x[k] * s->scale);
        if (!dm__qem_check_topology(s, keep, rem, e.key == s->ahead_key) ||
            (ring_count = dm__qem_check_geometry(s, keep, rem, at)) == (size_t)-1) {
            s->rejected++;
            s->vx[ea].flag |= DM__QEM_V_PARKED;
            s->vx[e.b].flag |= DM__QEM_V_PARKED;
            continue;
        }
        dm__qem_ahead(s, 1, 0); /* the one after the next (popped at the start): its corner lists */
        if (opt->constraint) {
            int go = dm__qem_ask_constraint(s, &e, keep, rem, at, &cost, &err, ring_count);
            if (go < 0) return DM_ERR_OUT_OF_MEMORY;
            if (go == 0) continue;
        }
        if (opt->on_collapse) dm__qem_tell_collapse(s, keep, rem, at, err, ring_count);
        if (!dm__qem_collapse(s, keep, rem, at) || !dm__qem_refresh(s, keep)) return DM_ERR_OUT_OF_MEMORY;
        dm__qem_ahead(s, 0, 2); /* the next one: its neighbours */
        if (s->hsize > 4096 && s->hsize / 3 > s->live && !dm__qem_heap_purge(s)) return DM_ERR_OUT_OF_MEMORY;
        if (err > s->max_error) s->max_error = err;
        if (opt->progress && s->nrec >= next_progress) {
            float done = to_remove ? (float)(s->t - s->live) / (float)to_remove : 0.0f;
            if (opt->progress(opt->progress_user, done > 1.0f ? 1.0f : done)) return DM_CANCELLED;
            next_progress = s->nrec + 1024;
        }
    }
    return DM_OK;
}

DMDEF dm_simplify_options dm_simplify_default_options(void)
{
    dm_simplify_options o; /* no target, no bound, no guard, no constraint */
    memset(&o, 0, sizeof o);
    return o;
}

DMDEF dm_result dm_simplify(const float *positions, size_t vertex_count, const uint32_t *indices,
                            size_t triangle_count, const dm_simplify_options *options, dm_pm **out,
                            dm_simplify_report *report)
{
    dm__qem_simp s;
    dm_simplify_options opt;
    dm_simplify_report rep;
    dm_result r;
    size_t v, dropped = 0, frozen = 0, to_remove = 0;
    memset(&s, 0, sizeof s);
    memset(&rep, 0, sizeof rep);
    for (v = 0; v < DM__QEM_BUCKETS; v++) s.bucket[v].fill = DM__QEM_CHUNK;
    if (options) opt = *options;
    else memset(&opt, 0, sizeof opt);
    s.al = dm__resolve_allocator(opt.allocator);
    s.opt = &opt;
    if (report) *report = rep;
    if (!out) return DM_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!(opt.target_error >= 0.0)) return DM_ERR_INVALID_ARGUMENT; /* NaN or negative */
    if (!(opt.min_quality <= 0.5f)) return DM_ERR_INVALID_ARGUMENT; /* NaN or too strict */
    if (opt.relax_cost != opt.relax_cost) return DM_ERR_INVALID_ARGUMENT; /* NaN */
    s.min_quality = opt.min_quality > 0.0f ? opt.min_quality : 0.0;
    s.relax_cost = opt.relax_cost == 0.0 ? DM__QEM_RELAX_COST : opt.relax_cost;
    r = dm__qem_prepare(&s, positions, vertex_count, indices, triangle_count, &dropped, &frozen);
    if (r == DM_OK) r = dm__qem_seed_edges(&s, vertex_count); /* every edge a candidate */
    if (r == DM_OK) {
        s.target = opt.target_triangles;
        to_remove = s.live > s.target ? s.live - s.target : 0;
        r = dm__qem_reserve(&s, to_remove, vertex_count);
    }
    if (r == DM_OK) r = dm__qem_collapse_loop(&s, &rep, to_remove); /* the cheapest first */
    if (r == DM_OK && opt.progress && opt.progress(opt.progress_user, 1.0f)) r = DM_CANCELLED;
    if (r == DM_OK) {
        rep.input_triangles = s.t;
        rep.dropped_triangles = dropped;
        rep.triangle_count = s.live;
        rep.collapse_count = s.nrec;
        rep.rejected = s.rejected;
        rep.vetoed = s.vetoed;
        rep.frozen_vertices = frozen;
        rep.error = s.max_error;
        rep.reached_target = s.target == 0 || s.live <= s.target;
        r = dm__qem_make_pm(&s, out); /* the records become the progressive mesh */
        if (r == DM_OK) rep.vertex_count = (*out)->live_vertices;
    }
    dm__qem_simp_free(&s);
    if (r == DM_OK && report) *report = rep;
    return r;
}

DMDEF size_t dm_pm_split_count(const dm_pm *pm) { return pm ? pm->split_count : 0; }

DMDEF size_t dm_pm_level(const dm_pm *pm) { return pm ? pm->level : 0; }

DMDEF void dm_pm_set_level(dm_pm *pm, size_t level)
{
    if (!pm) return;
    if (level > pm->split_count) level = pm->split_count;
    while (pm->level < level) { /* vertex split: undo collapse split_count - 1 - level */
        const dm__qem_rec *r = &pm->rec[pm->split_count - 1 - pm->level];
        const uint32_t *op = pm->ops + r->first;
        uint32_t i;
        int k;
        for (k = 0; k < 3; k++) pm->pos[3 * (size_t)r->keep + k] = r->before[k];
        for (i = 0; i < r->dead; i++) pm->alive[op[i]] = 1;
        for (i = 0; i < r->moved; i++) pm->idx[op[r->dead + i]] = r->remove;
        pm->live_triangles += r->dead;
        pm->live_vertices++;
        pm->level++;
    }
    while (pm->level > level) { /* edge collapse: redo it */
        const dm__qem_rec *r = &pm->rec[pm->split_count - pm->level];
        const uint32_t *op = pm->ops + r->first;
        uint32_t i;
        int k;
        for (k = 0; k < 3; k++) pm->pos[3 * (size_t)r->keep + k] = r->after[k];
        for (i = 0; i < r->dead; i++) pm->alive[op[i]] = 0;
        for (i = 0; i < r->moved; i++) pm->idx[op[r->dead + i]] = r->keep;
        pm->live_triangles -= r->dead;
        pm->live_vertices--;
        pm->level--;
    }
}

DMDEF void dm_pm_counts(const dm_pm *pm, size_t *vertex_count, size_t *triangle_count)
{
    if (vertex_count) *vertex_count = pm ? pm->live_vertices : 0;
    if (triangle_count) *triangle_count = pm ? pm->live_triangles : 0;
}

DMDEF void dm_pm_get_mesh(dm_pm *pm, float *positions, uint32_t *indices, uint32_t *vertex_ids)
{
    size_t t, v, nv = 0, nt = 0;
    uint32_t *map;
    if (!pm) return;
    map = pm->scratch;
    for (v = 0; v < pm->vertex_count; v++) map[v] = DM__QEM_NONE;
    for (t = 0; t < pm->triangle_count; t++)
        if (pm->alive[t])
            for (v = 0; v < 3; v++) map[pm->idx[3 * t + v]] = 0;
    for (v = 0; v < pm->vertex_count; v++) {
        if (map[v] == DM__QEM_NONE) continue;
        map[v] = (uint32_t)nv;
        if (positions) memcpy(positions + 3 * nv, pm->pos + 3 * v, 3 * sizeof(float));
        if (vertex_ids) vertex_ids[nv] = (uint32_t)v;
        nv++;
    }
    for (t = 0; t < pm->triangle_count; t++) {
        if (!pm->alive[t]) continue;
        if (indices)
            for (v = 0; v < 3; v++) indices[3 * nt + v] = map[pm->idx[3 * t + v]];
        nt++;
    }
}

DMDEF const float *dm_pm_positions(const dm_pm *pm) { return pm ? pm->pos : NULL; }

DMDEF int dm_pm_get_vsplit(const dm_pm *pm, size_t level, dm_vsplit *out)
{
    const dm__qem_rec *r;
    int k;
    if (!pm || !out || level >= pm->split_count) return 0;
    r = &pm->rec[pm->split_count - 1 - level];
    out->keep = r->keep;
    out->remove = r->remove;
    for (k = 0; k < 3; k++) {
        out->keep_position[k] = r->before[k];
        out->merged_position[k] = r->after[k];
    }
    out->restored_triangles = r->dead;
    out->moved_corners = r->moved;
    return 1;
}

DMDEF size_t dm_pm_merged_vertices(const dm_pm *pm, uint32_t vertex, const uint32_t **list)
{
    if (list) *list = NULL;
    if (!pm || vertex >= pm->vertex_count) return 0;
    if (list) *list = pm->merge_list + pm->merge_first[vertex];
    return pm->merge_first[vertex + 1] - pm->merge_first[vertex];
}

/* ---------------------------------------------------------------------------------------------
   Section: parameterization (charts, Floater 2003, Yoshizawa-Belyaev-Seidel 2004, packing)
   --------------------------------------------------------------------------------------------- */

/* Grows disk-shaped charts from the lowest unassigned triangle, breadth first. A triangle joins
   when it shares one edge with the chart and its third vertex is not yet in it, or shares two
   edges (fills a notch); so every chart stays a topological disk. It must also lie within
   max_angle of the chart's mean normal, and the chart stay within max_tris. */
static size_t dm__pz_grow_charts(const float *pos, const uint32_t *idx, size_t nt, const uint32_t *twin,
                                 int max_tris, double cos_max, uint32_t *chart, uint32_t *vstamp,
                                 uint32_t *queue)
{
    size_t t, count = 0;
    for (t = 0; t < nt; t++) chart[t] = DM_NO_HIT;
    for (t = 0; t < nt; t++) {
        size_t head = 0, tail = 0;
        int size = 1, c;
        double nsum[3];
        uint32_t cid = (uint32_t)count;
        if (chart[t] != DM_NO_HIT) continue;
        count++;
        chart[t] = cid;
        dm__face_normal(pos, idx, t, nsum);
        for (c = 0; c < 3; c++) {
            vstamp[idx[3 * t + (size_t)c]] = cid;
            if (twin[3 * t + (size_t)c] != DM_NO_HIT) queue[tail++] = twin[3 * t + (size_t)c];
        }
        while (head < tail && size < max_tris) {
            uint32_t q = queue[head++];
            int k = 0, shared = -1;
            double n[3], ln, ls;
            if (chart[q] != DM_NO_HIT) continue;
            for (c = 0; c < 3; c++)
                if (twin[3 * (size_t)q + (size_t)c] != DM_NO_HIT && chart[twin[3 * (size_t)q + (size_t)c]] == cid) {
                    k++;
                    shared = c;
                }
            if (k == 0 || k == 3) continue;
            if (k == 1 && vstamp[idx[3 * (size_t)q + (size_t)((shared + 2) % 3)]] == cid) continue;
            dm__face_normal(pos, idx, q, n);
            ln = dm__len3(n);
            ls = dm__len3(nsum);
            if (ln > 0.0 && ls > 0.0 && dm__dot3(n, nsum) < cos_max * ln * ls) continue;
            chart[q] = cid;
            size++;
            nsum[0] += n[0]; nsum[1] += n[1]; nsum[2] += n[2];
            for (c = 0; c < 3; c++) {
                uint32_t o = twin[3 * (size_t)q + (size_t)c];
                vstamp[idx[3 * (size_t)q + (size_t)c]] = cid;
                if (o != DM_NO_HIT && chart[o] == DM_NO_HIT) queue[tail++] = o;
            }
        }
    }
    return count;
}

/* One chart's working arrays (sized for the largest chart). */
typedef struct dm__pz_chart {
    size_t nt, nv;      /* triangles and local vertices */
    uint32_t *tri;      /* global triangle ids */
    uint32_t *lv;       /* 3 per local triangle: local vertex */
    uint32_t *gv;       /* local -> global vertex */
    double *x;          /* 3 per local vertex */
    double *uv, *uv_prev; /* 2 per local vertex */
    double *w;          /* 6 per local triangle: weight of corner c towards corner c+1, c+2 */
    double *target;     /* per local triangle: target area */
    double *sigma;      /* per local vertex */
    double *sig_w;
    int *interior;      /* per local vertex: row in the system, or -1 on the boundary */
    uint32_t *bnext;    /* per local vertex: next boundary vertex, or DM_NO_HIT */
    double *mat, *rhs;  /* dense system, n_int^2 and 2 n_int */
    size_t n_int;
} dm__pz_chart;

static double dm__pz_uv_area(const double *uv, const uint32_t *l)
{
    const double *a = uv + 2 * l[0], *b = uv + 2 * l[1], *c = uv + 2 * l[2];
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

/* Solves the interior positions: sum_j w_ij (u_i - u_j) = 0 (Floater 2003 with mean value
   weights; later rounds with the stretch-scaled weights). Dense Gaussian elimination with
   partial pivoting: charts are small. Returns 0 on a singular system. */
static int dm__pz_solve(dm__pz_chart *ch)
{
    size_t n = ch->n_int, i, j, k, t;
    int c, d;
    double *m = ch->mat, *r = ch->rhs;
    if (n == 0) return 1;
    memset(m, 0, n * n * sizeof(double));
    memset(r, 0, 2 * n * sizeof(double));
    for (t = 0; t < ch->nt; t++)
        for (c = 0; c < 3; c++) {
            uint32_t vi = ch->lv[3 * t + (size_t)c];
            int row = ch->interior[vi];
            if (row < 0) continue;
            for (d = 1; d <= 2; d++) {
                uint32_t vj = ch->lv[3 * t + (size_t)((c + d) % 3)];
                double w = ch->w[6 * t + 2 * (size_t)c + (size_t)(d - 1)];
                m[(size_t)row * n + (size_t)row] += w;
                if (ch->interior[vj] >= 0) m[(size_t)row * n + (size_t)ch->interior[vj]] -= w;
                else {
                    r[2 * (size_t)row] += w * ch->uv[2 * vj];
                    r[2 * (size_t)row + 1] += w * ch->uv[2 * vj + 1];
                }
            }
        }
    for (k = 0; k < n; k++) {
        size_t p = k;
        double best = fabs(m[k * n + k]);
        for (i = k + 1; i < n; i++)
            if (fabs(m[i * n + k]) > best) { best = fabs(m[i * n + k]); p = i; }
        if (!(best > 1e-300)) return 0;
        if (p != k) {
            for (j = 0; j < n; j++) { double tmp = m[k * n + j]; m[k * n + j] = m[p * n + j]; m[p * n + j] = tmp; }
            for (j = 0; j < 2; j++) { double tmp = r[2 * k + j]; r[2 * k + j] = r[2 * p + j]; r[2 * p + j] = tmp; }
        }
        for (i = k + 1; i < n; i++) {
            double f = m[i * n + k] / m[k * n + k];
            if (f == 0.0) continue;
            for (j = k; j < n; j++) m[i * n + j] -= f * m[k * n + j];
            r[2 * i] -= f * r[2 * k];
            r[2 * i + 1] -= f * r[2 * k + 1];
        }
    }
    for (i = n; i-- > 0;) {
        double s0 = r[2 * i], s1 = r[2 * i + 1];
        for (j = i + 1; j < n; j++) { s0 -= m[i * n + j] * r[2 * j]; s1 -= m[i * n + j] * r[2 * j + 1]; }
        r[2 * i] = s0 / m[i * n + i];
        r[2 * i + 1] = s1 / m[i * n + i];
    }
    for (i = 0; i < ch->nv; i++)
        if (ch->interior[i] >= 0) {
            ch->uv[2 * i] = r[2 * (size_t)ch->interior[i]];
            ch->uv[2 * i + 1] = r[2 * (size_t)ch->interior[i] + 1];
        }
    return 1;
}

/* 1 when some triangle with positive 3D area has a non-positive or non-finite UV area */
static int dm__pz_flipped(const dm__pz_chart *ch)
{
    size_t t;
    for (t = 0; t < ch->nt; t++) {
        double a = dm__pz_uv_area(ch->uv, ch->lv + 3 * t);
        if (!(a > 0.0) && ch->target[t] > 0.0) return 1;
    }
    return 0;
}

/* Sander et al. 2001 L2 stretch of each triangle against its target area (the 3D triangle
   scaled to the target area, the chart's UV scaled to the chart's target total); returns the
   chart's L2 stretch sqrt(sum A' s^2 / sum A'). sig_t receives the per-triangle values. */
static double dm__pz_stretch(const dm__pz_chart *ch, double *sig_t)
{
    size_t t;
    double uv_total = 0.0, target_total = 0.0, acc = 0.0, scale;
    for (t = 0; t < ch->nt; t++) {
        uv_total += dm__pz_uv_area(ch->uv, ch->lv + 3 * t);
        target_total += ch->target[t];
    }
    scale = (uv_total > 0.0 && target_total > 0.0) ? sqrt(uv_total / target_total) : 1.0;
    for (t = 0; t < ch->nt; t++) {
        const uint32_t *l = ch->lv + 3 * t;
        const double *q1 = ch->x + 3 * l[0], *q2 = ch->x + 3 * l[1], *q3 = ch->x + 3 * l[2];
        double s1 = ch->uv[2 * l[0]], t1 = ch->uv[2 * l[0] + 1], s2 = ch->uv[2 * l[1]], t2 = ch->uv[2 * l[1] + 1];
        double s3 = ch->uv[2 * l[2]], t3 = ch->uv[2 * l[2] + 1];
        double a2 = (s2 - s1) * (t3 - t1) - (s3 - s1) * (t2 - t1), ss[3], st[3], a3[3], b3[3], c3[3], area3, k2, sg;
        int k;
        dm__sub3(q2, q1, a3);
        dm__sub3(q3, q1, b3);
        dm__cross3(a3, b3, c3);
        area3 = 0.5 * dm__len3(c3);
        if (!(a2 > 0.0) || !(area3 > 0.0) || !(ch->target[t] > 0.0)) { sig_t[t] = 1.0; continue; }
        for (k = 0; k < 3; k++) {
            ss[k] = (q1[k] * (t2 - t3) + q2[k] * (t3 - t1) + q3[k] * (t1 - t2)) / a2;
            st[k] = (q1[k] * (s3 - s2) + q2[k] * (s1 - s3) + q3[k] * (s2 - s1)) / a2;
        }
        k2 = ch->target[t] / area3; /* squared scale that takes the 3D triangle to its target */
        sg = sqrt(0.5 * (dm__dot3(ss, ss) + dm__dot3(st, st)) * k2) * scale;
        sig_t[t] = sg;
        acc += ch->target[t] * sg * sg;
    }
    return target_total > 0.0 ? sqrt(acc / target_total) : 1.0;
}

/* Mean value weights (Floater 2003): for vertex i and neighbour j in triangle (i, j, k),
   tan(alpha/2) / |x_j - x_i| with alpha the angle at i; tan(alpha/2) = |a x b| / (|a||b| + a.b). */
static void dm__pz_mean_value_weights(dm__pz_chart *ch)
{
    size_t t;
    int c;
    for (t = 0; t < ch->nt; t++)
        for (c = 0; c < 3; c++) {
            const double *xi = ch->x + 3 * ch->lv[3 * t + (size_t)c];
            const double *xj = ch->x + 3 * ch->lv[3 * t + (size_t)((c + 1) % 3)];
            const double *xk = ch->x + 3 * ch->lv[3 * t + (size_t)((c + 2) % 3)];
            double a[3], b[3], ab[3], la, lb, den, tn;
            dm__sub3(xj, xi, a);
            dm__sub3(xk, xi, b);
            dm__cross3(a, b, ab);
            la = dm__len3(a);
            lb = dm__len3(b);
            den = la * lb + dm__dot3(a, b);
            tn = den > 1e-300 ? dm__len3(ab) / den : 1e6;
            if (tn > 1e6) tn = 1e6;
            if (tn < 1e-12) tn = 1e-12;
            ch->w[6 * t + 2 * (size_t)c] = la > 1e-300 ? tn / la : 1e-12;
            ch->w[6 * t + 2 * (size_t)c + 1] = lb > 1e-300 ? tn / lb : 1e-12;
        }
}

/* Places the boundary loop: mode 0 projects it onto the plane of the chart's mean normal, mode 1
   spreads it over a circle by arc length. Returns 0 when the loop is not one simple cycle. */
static int dm__pz_place_boundary(dm__pz_chart *ch, int mode, const double nrm[3])
{
    size_t i, start = DM_NO_HIT, len = 0, nb = 0;
    double e1[3], e2[3], total = 0.0, run = 0.0, area = 0.0;
    uint32_t v;
    for (i = 0; i < ch->nv; i++)
        if (ch->bnext[i] != DM_NO_HIT) {
            nb++;
            if (start == DM_NO_HIT) start = i;
        }
    if (nb < 3) return 0;
    v = (uint32_t)start;
    do {
        double d[3];
        if (ch->bnext[v] == DM_NO_HIT) return 0; /* an open chain (a pinched boundary) */
        dm__sub3(ch->x + 3 * ch->bnext[v], ch->x + 3 * v, d);
        total += dm__len3(d);
        v = ch->bnext[v];
        len++;
    } while (v != start && v != DM_NO_HIT && len <= nb);
    if (v != start || len != nb) return 0;
    /* a basis of the plane orthogonal to nrm */
    if (fabs(nrm[0]) < 0.6) { e1[0] = 0.0; e1[1] = nrm[2]; e1[2] = -nrm[1]; }
    else { e1[0] = -nrm[2]; e1[1] = 0.0; e1[2] = nrm[0]; }
    {
        double l = dm__len3(e1);
        e1[0] /= l; e1[1] /= l; e1[2] /= l;
    }
    dm__cross3(nrm, e1, e2);
    v = (uint32_t)start;
    do {
        if (mode == 0) {
            ch->uv[2 * v] = dm__dot3(ch->x + 3 * v, e1);
            ch->uv[2 * v + 1] = dm__dot3(ch->x + 3 * v, e2);
        } else {
            double ang = total > 0.0 ? 6.283185307179586 * run / total : 0.0, d[3];
            ch->uv[2 * v] = cos(ang);
            ch->uv[2 * v + 1] = sin(ang);
            dm__sub3(ch->x + 3 * ch->bnext[v], ch->x + 3 * v, d);
            run += dm__len3(d);
        }
        v = ch->bnext[v];
    } while (v != start);
    if (mode == 1) return total > 0.0;
    /* the projected loop must run counter-clockwise and not cross itself */
    v = (uint32_t)start;
    do {
        uint32_t w = ch->bnext[v];
        area += ch->uv[2 * v] * ch->uv[2 * w + 1] - ch->uv[2 * w] * ch->uv[2 * v + 1];
        v = w;
    } while (v != start);
    if (!(area > 0.0)) return 0;
    {
        uint32_t a = (uint32_t)start;
        do {
            uint32_t b = ch->bnext[a], c = ch->bnext[b];
            while (c != start && ch->bnext[c] != a) {
                uint32_t d = ch->bnext[c];
                const double *p = ch->uv + 2 * a, *q = ch->uv + 2 * b, *r = ch->uv + 2 * c, *s = ch->uv + 2 * d;
                double o1 = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
                double o2 = (q[0] - p[0]) * (s[1] - p[1]) - (q[1] - p[1]) * (s[0] - p[0]);
                double o3 = (s[0] - r[0]) * (p[1] - r[1]) - (s[1] - r[1]) * (p[0] - r[0]);
                double o4 = (s[0] - r[0]) * (q[1] - r[1]) - (s[1] - r[1]) * (q[0] - r[0]);
                if (((o1 > 0.0) != (o2 > 0.0)) && ((o3 > 0.0) != (o4 > 0.0))) return 0;
                c = d;
            }
            a = b;
        } while (a != start);
    }
    return 1;
}

/* A chart whose layout stretches more than this (L2, against its targets) is not kept: a
   grown chart that curls (its boundary on a convex polygon squeezes part of it) would get
   almost no texels there. */
#define DM__PZ_MAX_STRETCH 2.0

/* Lays out one chart: boundary (projected, else circle), Floater's mean value interior, then
   Yoshizawa-Belyaev-Seidel rounds w_ij <- w_ij / sigma_j (sigma_j the area-weighted L2 stretch
   around vertex j against the targets), kept while the chart's stretch drops and nothing flips.
   Returns 0 when no flip-free layout was found, or none within DM__PZ_MAX_STRETCH. */
static int dm__pz_layout(dm__pz_chart *ch, const double nrm[3], int rounds, double *sig_t)
{
    int mode, r;
    size_t i, t;
    int c;
    for (mode = 0; mode < 2; mode++) {
        if (!dm__pz_place_boundary(ch, mode, nrm)) continue;
        dm__pz_mean_value_weights(ch);
        if (!dm__pz_solve(ch) || dm__pz_flipped(ch)) continue;
        break;
    }
    if (mode == 2) return 0;
    if (ch->n_int == 0) return dm__pz_stretch(ch, sig_t) <= DM__PZ_MAX_STRETCH;
    {
        double cur = dm__pz_stretch(ch, sig_t);
        for (r = 0; r < rounds; r++) {
            double next;
            memcpy(ch->uv_prev, ch->uv, 2 * ch->nv * sizeof(double));
            for (i = 0; i < ch->nv; i++) { ch->sigma[i] = 0.0; ch->sig_w[i] = 0.0; }
            for (t = 0; t < ch->nt; t++)
                for (c = 0; c < 3; c++) {
                    uint32_t v = ch->lv[3 * t + (size_t)c];
                    ch->sigma[v] += ch->target[t] * sig_t[t] * sig_t[t];
                    ch->sig_w[v] += ch->target[t];
                }
            for (i = 0; i < ch->nv; i++)
                ch->sigma[i] = ch->sig_w[i] > 0.0 ? sqrt(ch->sigma[i] / ch->sig_w[i]) : 1.0;
            for (t = 0; t < ch->nt; t++)
                for (c = 0; c < 3; c++) {
                    double sj = ch->sigma[ch->lv[3 * t + (size_t)((c + 1) % 3)]];
                    double sk = ch->sigma[ch->lv[3 * t + (size_t)((c + 2) % 3)]];
                    if (sj > 1e-6) ch->w[6 * t + 2 * (size_t)c] /= sj;
                    if (sk > 1e-6) ch->w[6 * t + 2 * (size_t)c + 1] /= sk;
                }
            if (!dm__pz_solve(ch) || dm__pz_flipped(ch) || !((next = dm__pz_stretch(ch, sig_t)) < cur)) {
                memcpy(ch->uv, ch->uv_prev, 2 * ch->nv * sizeof(double));
                dm__pz_stretch(ch, sig_t);
                break;
            }
            cur = next;
        }
        return cur <= DM__PZ_MAX_STRETCH;
    }
}

/* lays out a lone triangle isometrically (an equilateral one for a degenerate triangle) */
static void dm__pz_single(const float *pos, const uint32_t *idx, size_t t, double *cuv)
{
    double p0[3], p1[3], p2[3], e1[3], e2[3], n[3], l1, h;
    dm__load3(pos, idx[3 * t], p0);
    dm__load3(pos, idx[3 * t + 1], p1);
    dm__load3(pos, idx[3 * t + 2], p2);
    dm__sub3(p1, p0, e1);
    dm__sub3(p2, p0, e2);
    dm__cross3(e1, e2, n);
    l1 = dm__len3(e1);
    h = dm__len3(n);
    cuv[0] = 0.0; cuv[1] = 0.0;
    if (l1 > 0.0 && h > 0.0 && h / (l1 * l1) > 1e-9) {
        cuv[2] = l1; cuv[3] = 0.0;
        cuv[4] = dm__dot3(e2, e1) / l1; cuv[5] = h / l1;
    } else {
        cuv[2] = 1.0; cuv[3] = 0.0; cuv[4] = 0.5; cuv[5] = 0.8660254037844386;
    }
}

static double dm__pz_cuv_area(const double *c)
{
    return 0.5 * ((c[2] - c[0]) * (c[5] - c[1]) - (c[4] - c[0]) * (c[3] - c[1]));
}

/* 1 when the square of half-side h around point c meets the counter-clockwise triangle P
   (separating axes: x, y and the three edge normals) */
static int dm__square_meets(const double P[3][2], const double c[2], double h)
{
    int e, k;
    for (k = 0; k < 2; k++) {
        double lo = fmin(P[0][k], fmin(P[1][k], P[2][k])), hi = fmax(P[0][k], fmax(P[1][k], P[2][k]));
        if (hi < c[k] - h || lo > c[k] + h) return 0;
    }
    for (e = 0; e < 3; e++) {
        const double *a = P[e], *b = P[(e + 1) % 3];
        double nx = -(b[1] - a[1]), ny = b[0] - a[0];
        if (nx * c[0] + ny * c[1] + h * (fabs(nx) + fabs(ny)) < nx * a[0] + ny * a[1]) return 0;
    }
    return 1;
}

/* Bitmap packing (the approach of xatlas and of Levy et al. 2002's "Tetris" packer, our own
   code): each chart's footprint at scale s is the set of texels within half a gutter of it, kept
   exactly (each row's runs of texels), so that charts interlock, or as its silhouette (each row
   from its first texel to its last). Charts go largest first, each in the quarter turn whose
   lowest free place (rows from the bottom, then columns) puts its top lowest; a place is free
   when no run of the footprint meets a taken texel. */
typedef struct dm__pz_shape {
    int w, h;           /* footprint size in texels */
    const int *lo, *hi; /* per row: its first and last texel (lo > hi: none) */
    const int *longest; /* per row: its longest run */
    const int *rstart;  /* per row r: its runs are rstart[r] .. rstart[r + 1] - 1 */
    const int *run;     /* run k: row run[3k], texels run[3k + 1] .. run[3k + 2] */
    int wide;           /* the row with the longest run */
    int wide_run;       /* that run */
} dm__pz_shape;

typedef struct dm__pz_bitpack {
    int W, H, words;    /* map size; 64-bit words per row */
    uint64_t *taken;    /* H rows of taken texels */
    uint16_t *free_run; /* per map texel: the free texels from it to the right (0: taken) */
    uint64_t *foot;     /* a chart's footprint, unturned: rows of `words` words */
    int *lo[4], *hi[4], *longest[4], *rstart[4]; /* its rows in each quarter turn */
    int *run[4];        /* its runs in each quarter turn (3 ints each, run_cap runs) */
    size_t run_cap;
    int *first_free;    /* per map row: its first free texel (W: none) */
    int *longest_free;  /* per map row: its longest run of free texels */
    int rows_cap;       /* entries in each lo / hi / longest (rstart: one more) */
    int silhouette;     /* 1: each row's runs as one, from its first texel to its last */
    dm_allocator al;    /* for run[] */
} dm__pz_bitpack;

/* the index of the highest set bit of m (nonzero) */
static int dm__highest_bit(uint64_t m)
{
#if defined(__GNUC__) || defined(__clang__)
    return 63 - __builtin_clzll(m);
#else
    int b = 0;
    if (m >> 32) { m >>= 32; b += 32; }
    if (m >> 16) { m >>= 16; b += 16; }
    if (m >> 8) { m >>= 8; b += 8; }
    if (m >> 4) { m >>= 4; b += 4; }
    if (m >> 2) { m >>= 2; b += 2; }
    return b + (int)(m >> 1);
#endif
}

/* the index of the lowest set bit of m (nonzero) */
static int dm__lowest_bit(uint64_t m)
{
    return dm__highest_bit(m & (~m + 1));
}

/* the first texel of row y at or after x whose bit is `taken` (0 free, 1 taken), or W */
static long dm__pz_first_bit(const dm__pz_bitpack *b, int y, long x, int taken)
{
    const uint64_t *row = b->taken + (size_t)y * (size_t)b->words;
    long w;
    for (w = x >> 6; x < b->W && w < b->words; w++) {
        uint64_t m = taken ? row[w] : ~row[w];
        if (w == (x >> 6)) m &= ~(((uint64_t)1 << (x & 63)) - 1);
        if (m) {
            long at = w * 64 + dm__lowest_bit(m);
            return at < b->W ? at : b->W;
        }
    }
    return b->W;
}

/* the first x at or after `from` where texels x .. x + need - 1 of row y are all free, or -1:
   from each free run too short, on past the taken texels after it */
static long dm__pz_next_fit(const dm__pz_bitpack *b, int y, long from, long need)
{
    const uint16_t *fr = b->free_run + (size_t)y * (size_t)b->W;
    while (from + need <= b->W) {
        if (fr[from] >= need) return from;
        from = dm__pz_first_bit(b, y, from + fr[from], 0);
    }
    return -1;
}

/* the lowest free place for the shape with its bottom row at most y_max: 1 and (*px, *py), or
   0. Rows whose longest free run is shorter than the shape's longest run there are skipped
   whole; a run that meets a taken texel moves the shape on to where that run fits next. */
static int dm__pz_find_place(const dm__pz_bitpack *b, const dm__pz_shape *sh, int y_max, int *px, int *py)
{
    int y, r, hint = 0, nrun = sh->rstart[sh->h];
    if (y_max > b->H - sh->h) y_max = b->H - sh->h;
    for (y = 0; y <= y_max; y++) {
        long x = 0;
        int fits = b->longest_free[y + sh->wide] >= sh->longest[sh->wide]; /* the likeliest to refuse */
        for (r = 0; r < sh->h && fits; r++) { /* a start at each row's first free texel at the least */
            long x0;
            if (sh->lo[r] > sh->hi[r]) continue;
            if (b->longest_free[y + r] < sh->longest[r]) fits = 0;
            x0 = (long)b->first_free[y + r] - sh->lo[r];
            if (x0 > x) x = x0;
        }
        if (!fits) continue;
        while (x + sh->w <= b->W) {
            long jump = -1;
            int k;
            for (k = nrun ? -1 : 0; k < nrun && jump < 0; k++) { /* the widest run, then the one that refused last */
                int q = k < 0 ? sh->wide_run : (k + hint) % nrun, yq = y + sh->run[3 * q];
                long a = sh->run[3 * q + 1], len = sh->run[3 * q + 2] - a + 1;
                if (b->free_run[(size_t)yq * (size_t)b->W + (size_t)(x + a)] < len) { /* on to where this run fits next */
                    long t = dm__pz_next_fit(b, yq, x + a, len);
                    jump = t < 0 ? b->W : t - a;
                    hint = q;
                }
            }
            if (jump < 0) { *px = (int)x; *py = y; return 1; }
            x = jump > x ? jump : x + 1;
        }
    }
    return 0;
}

/* row y's first free texel and longest free run, again */
static void dm__pz_row_runs(dm__pz_bitpack *b, int y)
{
    const uint64_t *row = b->taken + (size_t)y * (size_t)b->words;
    int x, run = 0, best = 0, first = b->W;
    for (x = 0; x < b->W; x++) {
        if (!(x & 63) && row[x >> 6] == ~(uint64_t)0 && x + 64 <= b->W) { run = 0; x += 63; continue; }
        if (row[x >> 6] >> (x & 63) & 1) run = 0;
        else {
            if (first == b->W) first = x;
            if (++run > best) best = run;
        }
    }
    b->first_free[y] = first;
    b->longest_free[y] = best;
}

static void dm__pz_take_place(dm__pz_bitpack *b, const dm__pz_shape *sh, int px, int py)
{
    int r, k;
    for (r = 0; r < sh->h; r++) {
        uint64_t *row = b->taken + (size_t)(py + r) * (size_t)b->words;
        if (sh->rstart[r] == sh->rstart[r + 1]) continue;
        for (k = sh->rstart[r]; k < sh->rstart[r + 1]; k++) {
            long x, x0 = px + sh->run[3 * k + 1];
            uint16_t *fr = b->free_run + (size_t)(py + r) * (size_t)b->W;
            for (x = x0; x <= px + sh->run[3 * k + 2]; x++) {
                row[x >> 6] |= (uint64_t)1 << (x & 63);
                fr[x] = 0;
            }
            for (x = x0 - 1; x >= 0 && fr[x] > x0 - x; x--) fr[x] = (uint16_t)(x0 - x); /* the free run before it ends here now */
        }
        dm__pz_row_runs(b, py + r);
    }
}

typedef struct dm__pz_pack {
    double bw, bh;  /* chart box in world-scale units */
    int ox, oy;     /* packed box corner, texels */
    int turn;       /* bitmap packing: quarter turns, and the unturned footprint's size */
    int fw, fh;
} dm__pz_pack;

static int dm__pz_try_pack(dm__pz_pack *pk, const uint32_t *order, size_t nc, double s, int g, int W, int H)
{
    long x = 0, y = 0, shelf = 0;
    size_t i;
    for (i = 0; i < nc; i++) {
        dm__pz_pack *p = pk + order[i];
        double fw = ceil(s * p->bw + 1e-9), fh = ceil(s * p->bh + 1e-9);
        long w, h;
        if (fw > (double)W || fh > (double)H) return 0;
        w = (long)fw + g;
        h = (long)fh + g;
        if (x + w > W) { x = 0; y += shelf; shelf = 0; }
        if (w > W || y + h > H) return 0;
        p->ox = (int)x;
        p->oy = (int)y;
        x += w;
        if (h > shelf) shelf = h;
    }
    return 1;
}

/* insertion order by descending box height (or area), ties by chart id (stable, deterministic) */
static void dm__pz_order(const dm__pz_pack *pk, size_t nc, int by_area, uint32_t *order, uint32_t *tmp)
{
    /* merge sort on (height desc, or box area desc, id asc) */
    size_t width, i;
    for (i = 0; i < nc; i++) order[i] = (uint32_t)i;
    for (width = 1; width < nc; width *= 2) {
        for (i = 0; i < nc; i += 2 * width) {
            size_t a = i, am = i + width < nc ? i + width : nc, b = am, bm = i + 2 * width < nc ? i + 2 * width : nc, o = i;
            while (a < am || b < bm) {
                int take_a;
                if (a >= am) take_a = 0;
                else if (b >= bm) take_a = 1;
                else {
                    double ha = pk[order[a]].bh * (by_area ? pk[order[a]].bw : 1.0),
                           hb = pk[order[b]].bh * (by_area ? pk[order[b]].bw : 1.0);
                    take_a = ha > hb || (ha == hb && order[a] < order[b]);
                }
                tmp[o++] = take_a ? order[a++] : order[b++];
            }
        }
        memcpy(order, tmp, nc * sizeof(uint32_t));
    }
}

/* the texel of the other chart across the seam nearest to pixel point P of triangle t's chart */
static uint32_t dm__pz_across(const dm_param *pm, const uint32_t *idx, const uint32_t *twin_he,
                              const uint32_t *blist, size_t b0, size_t b1, const double P[2], int dir, uint8_t *rot)
{
    size_t i, best = DM_NO_HIT;
    double bestd = 0.0, W = pm->width, H = pm->height;
    double A[2], B[2], e[2], el, s, F[2], o[2], along, perp, A2[2], B2[2], e2[2], e2l, k, Q[2], th;
    uint32_t he, he2, t2, c2;
    long qx, qy, dx, dy, sx, sy;
    uint32_t found = UINT32_MAX;
    double found_d = 0.0;
    for (i = b0; i < b1; i++) {
        uint32_t h = blist[i], t = h / 3, c = h % 3, c1 = (c + 1) % 3;
        double a[2], b[2], ab[2], L, u, f[2], d;
        a[0] = pm->uv[6 * t + 2 * c] * W; a[1] = pm->uv[6 * t + 2 * c + 1] * H;
        b[0] = pm->uv[6 * t + 2 * c1] * W; b[1] = pm->uv[6 * t + 2 * c1 + 1] * H;
        ab[0] = b[0] - a[0]; ab[1] = b[1] - a[1];
        L = ab[0] * ab[0] + ab[1] * ab[1];
        u = L > 0.0 ? ((P[0] - a[0]) * ab[0] + (P[1] - a[1]) * ab[1]) / L : 0.0;
        u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
        f[0] = a[0] + u * ab[0] - P[0]; f[1] = a[1] + u * ab[1] - P[1];
        d = f[0] * f[0] + f[1] * f[1];
        if (best == DM_NO_HIT || d < bestd) { best = i; bestd = d; }
    }
    if (best == DM_NO_HIT) return UINT32_MAX;
    he = blist[best];
    he2 = twin_he[he];
    if (he2 == DM_NO_HIT) return UINT32_MAX;
    {
        uint32_t t = he / 3, c = he % 3, c1 = (c + 1) % 3;
        A[0] = pm->uv[6 * t + 2 * c] * W; A[1] = pm->uv[6 * t + 2 * c + 1] * H;
        B[0] = pm->uv[6 * t + 2 * c1] * W; B[1] = pm->uv[6 * t + 2 * c1 + 1] * H;
    }
    t2 = he2 / 3;
    c2 = he2 % 3; /* in t2 the edge runs from corner c2 (vertex b) to c2 + 1 (vertex a) */
    B2[0] = pm->uv[6 * t2 + 2 * c2] * W; B2[1] = pm->uv[6 * t2 + 2 * c2 + 1] * H;
    A2[0] = pm->uv[6 * t2 + 2 * ((c2 + 1) % 3)] * W; A2[1] = pm->uv[6 * t2 + 2 * ((c2 + 1) % 3) + 1] * H;
    (void)idx;
    e[0] = B[0] - A[0]; e[1] = B[1] - A[1];
    e2[0] = B2[0] - A2[0]; e2[1] = B2[1] - A2[1];
    el = sqrt(e[0] * e[0] + e[1] * e[1]);
    e2l = sqrt(e2[0] * e2[0] + e2[1] * e2[1]);
    if (!(el > 0.0) || !(e2l > 0.0)) return UINT32_MAX;
    s = ((P[0] - A[0]) * e[0] + (P[1] - A[1]) * e[1]) / (el * el);
    s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
    F[0] = A[0] + s * e[0]; F[1] = A[1] + s * e[1];
    o[0] = P[0] - F[0]; o[1] = P[1] - F[1];
    along = (o[0] * e[0] + o[1] * e[1]) / el;
    perp = (o[0] * e[1] - o[1] * e[0]) / el; /* along the right-hand normal: out of this chart */
    k = e2l / el;
    Q[0] = A2[0] + s * e2[0] + k * (along * e2[0] / e2l + perp * e2[1] / e2l);
    Q[1] = A2[1] + s * e2[1] + k * (along * e2[1] / e2l - perp * e2[0] / e2l);
    th = atan2(e2[1], e2[0]) - atan2(e[1], e[0]);
    {
        long q = lround(th / 1.5707963267948966);
        *rot = (uint8_t)(((q % 4) + 4) % 4);
    }
    qx = (long)floor(Q[0]);
    qy = (long)floor(Q[1]);
    /* the step direction as seen in the other chart, to prefer texels on its seam side: from
       there a step back crosses the seam again */
    {
        int r = *rot;
        sx = dir == 0 ? 1 : dir == 1 ? -1 : 0;
        sy = dir == 2 ? 1 : dir == 3 ? -1 : 0;
        for (; r > 0; r--) { long tmp = sx; sx = -sy; sy = tmp; }
    }
    for (dy = -1; dy <= 1; dy++)
        for (dx = -1; dx <= 1; dx++) {
            long x = qx + dx, y = qy + dy;
            uint32_t tt;
            double cx, cy, d;
            if (x < 0 || y < 0 || x >= pm->width || y >= pm->height) continue;
            tt = pm->texel_triangle[(size_t)y * (size_t)pm->width + (size_t)x];
            if (tt == DM_NO_HIT || pm->chart[tt] != pm->chart[t2]) continue;
            cx = (double)x + 0.5 - Q[0];
            cy = (double)y + 0.5 - Q[1];
            d = cx * cx + cy * cy;
            if (x - sx >= 0 && y - sy >= 0 && x - sx < pm->width && y - sy < pm->height) {
                uint32_t tb = pm->texel_triangle[(size_t)(y - sy) * (size_t)pm->width + (size_t)(x - sx)];
                if (tb != DM_NO_HIT && pm->chart[tb] == pm->chart[t2]) d += 1e6;
            }
            if (found == UINT32_MAX || d < found_d) {
                found = (uint32_t)((size_t)y * (size_t)pm->width + (size_t)x);
                found_d = d;
            }
        }
    return found;
}

/* 1 when the texel reached from i by a step along dir and a step back lies within one texel of i */
static int dm__pz_walk_back(const dm_param *pm, size_t i, int dir, uint32_t j, int rot)
{
    long ex = dir == 0 ? 1 : dir == 1 ? -1 : 0, ey = dir == 2 ? 1 : dir == 3 ? -1 : 0, tmp;
    int bd;
    uint32_t k;
    for (; rot > 0; rot--) { tmp = ex; ex = -ey; ey = tmp; }
    bd = ex == -1 ? 0 : ex == 1 ? 1 : ey == -1 ? 2 : 3;
    k = pm->nbr[4 * (size_t)j + (size_t)bd];
    if (k == UINT32_MAX) return 0;
    return labs((long)(k % (uint32_t)pm->width) - (long)(i % (size_t)pm->width)) <= 1 &&
           labs((long)(k / (uint32_t)pm->width) - (long)(i / (size_t)pm->width)) <= 1;
}

static void dm__pz_fix_walk(dm_param *pm, size_t i, int dir)
{
    uint32_t j = pm->nbr[4 * i + (size_t)dir], cj;
    int rot = pm->nbr_rot[4 * i + (size_t)dir], ring, dx, dy, turn;
    long W = pm->width, H = pm->height, jx, jy;
    static const int turns[4] = {0, 1, 3, 2};
    if (j == UINT32_MAX) return;
    cj = pm->chart[pm->texel_triangle[j]];
    if (cj == pm->chart[pm->texel_triangle[i]] && rot == 0) return;
    if (dm__pz_walk_back(pm, i, dir, j, rot)) return;
    jx = (long)(j % (uint32_t)W);
    jy = (long)(j / (uint32_t)W);
    /* the rounded rotation first, then the two next quarter turns (a seam near 45 degrees) */
    for (turn = 0; turn < 4; turn++) {
        int rr = (rot + turns[turn]) % 4;
        for (ring = 0; ring <= 3; ring++)
            for (dy = -ring; dy <= ring; dy++)
                for (dx = -ring; dx <= ring; dx++) {
                    long x = jx + dx, y = jy + dy;
                    uint32_t m, tm;
                    if ((dx > -ring && dx < ring && dy > -ring && dy < ring) || x < 0 || y < 0 || x >= W || y >= H)
                        continue;
                    m = (uint32_t)(y * W + x);
                    tm = pm->texel_triangle[m];
                    if (tm == DM_NO_HIT || pm->chart[tm] != cj) continue;
                    if (dm__pz_walk_back(pm, i, dir, m, rr)) {
                        pm->nbr[4 * i + (size_t)dir] = m;
                        pm->nbr_rot[4 * i + (size_t)dir] = (uint8_t)rr;
                        return;
                    }
                }
    }
}

/* 1 when the link (i, dir) is sound: none, a plain in-chart neighbour that links back, or a
   seam crossing whose step back lands within one texel of i */
static int dm__pz_link_ok(const dm_param *pm, size_t i, int dir)
{
    uint32_t j = pm->nbr[4 * i + (size_t)dir];
    int rot = pm->nbr_rot[4 * i + (size_t)dir];
    if (j == UINT32_MAX) return 1;
    if (rot == 0 && pm->chart[pm->texel_triangle[j]] == pm->chart[pm->texel_triangle[i]])
        return pm->nbr[4 * (size_t)j + (size_t)(dir ^ 1)] == i;
    return dm__pz_walk_back(pm, i, dir, j, rot);
}

/* unsound links of the texels within r of texel c */
static size_t dm__pz_window_fails(const dm_param *pm, uint32_t c, long r)
{
    long W = pm->width, H = pm->height, cx = (long)(c % (uint32_t)W), cy = (long)(c / (uint32_t)W), x, y;
    size_t fails = 0;
    int dir;
    for (y = cy - r; y <= cy + r; y++)
        for (x = cx - r; x <= cx + r; x++) {
            size_t id;
            if (x < 0 || y < 0 || x >= W || y >= H) continue;
            id = (size_t)y * (size_t)W + (size_t)x;
            if (pm->texel_triangle[id] == DM_NO_HIT) continue;
            for (dir = 0; dir < 4; dir++) fails += !dm__pz_link_ok(pm, id, dir);
        }
    return fails;
}

/* Last resort for a seam walk from i that does not come back (at chart corners, and where a
   lone-triangle chart meets a seam at an angle far from a quarter turn): point the neighbour's
   step back at i itself, with the inverse rotation. The rounded rotation first, then the other
   quarter turns; a turn whose step back is a plain in-chart link is skipped (others rely on
   it). Kept only when the texels around i and around the old target then fail less often. */
static void dm__pz_relink_back(dm_param *pm, size_t i, int dir)
{
    static const int turns[4] = {0, 1, 3, 2};
    uint32_t j = pm->nbr[4 * i + (size_t)dir], old;
    int rot0 = pm->nbr_rot[4 * i + (size_t)dir], r, bd, oldrot, turn;
    size_t before, after;
    if (j == UINT32_MAX || dm__pz_link_ok(pm, i, dir)) return;
    for (turn = 0; turn < 4; turn++) {
        int rot = (rot0 + turns[turn]) % 4;
        long ex = dir == 0 ? 1 : dir == 1 ? -1 : 0, ey = dir == 2 ? 1 : dir == 3 ? -1 : 0, tmp;
        for (r = rot; r > 0; r--) { tmp = ex; ex = -ey; ey = tmp; }
        bd = ex == -1 ? 0 : ex == 1 ? 1 : ey == -1 ? 2 : 3;
        old = pm->nbr[4 * (size_t)j + (size_t)bd];
        oldrot = pm->nbr_rot[4 * (size_t)j + (size_t)bd];
        if (old != UINT32_MAX && oldrot == 0 && pm->chart[pm->texel_triangle[old]] == pm->chart[pm->texel_triangle[j]])
            continue;
        before = dm__pz_window_fails(pm, (uint32_t)i, 3) + (old != UINT32_MAX ? dm__pz_window_fails(pm, old, 3) : 0);
        pm->nbr[4 * (size_t)j + (size_t)bd] = (uint32_t)i;
        pm->nbr_rot[4 * (size_t)j + (size_t)bd] = (uint8_t)((4 - rot) % 4);
        pm->nbr_rot[4 * i + (size_t)dir] = (uint8_t)rot;
        after = dm__pz_window_fails(pm, (uint32_t)i, 3) + (old != UINT32_MAX ? dm__pz_window_fails(pm, old, 3) : 0);
        if (after < before) return;
        pm->nbr[4 * (size_t)j + (size_t)bd] = old;
        pm->nbr_rot[4 * (size_t)j + (size_t)bd] = (uint8_t)oldrot;
        pm->nbr_rot[4 * i + (size_t)dir] = (uint8_t)rot0;
    }
}

DMDEF void dm_param_free(dm_param *pm)
{
    dm_allocator a;
    if (!pm) return;
    a = pm->allocator;
    a.free(a.user, pm->uv);
    a.free(a.user, pm->chart);
    a.free(a.user, pm->twin);
    a.free(a.user, pm->texel_triangle);
    a.free(a.user, pm->texel_bary);
    a.free(a.user, pm->nbr);
    a.free(a.user, pm->nbr_rot);
    a.free(a.user, pm);
}

static int dm__pz_report(int (*progress)(void *, float), void *user, float done)
{
    return progress ? progress(user, done) : 0;
}

/* dm_parameterize's working state: the input, the resolved options, the result being filled and
   the temporaries (all in sc, freed together on the one exit path) */
typedef struct dm__pz_run {
    const float *positions;
    const uint32_t *indices;
    size_t nt, nv, n;  /* triangles, vertices, texels (W * H) */
    dm_param_options o;
    int W, H, g, max_tris, rounds;
    double cos_max;
    dm__scratch sc;
    dm_param *pm;
    dm__edge *edges;
    uint32_t *twin_he, *chart0, *vstamp, *queue, *gl;
    uint32_t *cstart, *ctris;                   /* triangles bucketed by chart */
    uint32_t *order, *otmp, *bstart, *blist;    /* packing order; boundary half-edges by chart */
    double *target, *cuv, *sig_t, *chart_n;     /* target areas, chart-space uv, true areas */
    double total_area;
    size_t nc0, maxc;                           /* grown charts, most triangles in one */
    uint32_t next_label;                        /* chart0 label for the next half of a cut chart */
    dm__pz_pack *pk;
    dm__pz_chart ch;
} dm__pz_run;

static dm_result dm__pz_step_report(const dm__pz_run *r, float done)
{
    return dm__pz_report(r->o.progress, r->o.progress_user, done) ? DM_CANCELLED : DM_OK;
}

/* the options with their defaults, checked; then the mesh and the triangle weights */
static dm_result dm__pz_read_options(dm__pz_run *r, const dm_param_options *options)
{
    dm_param_options o;
    dm_result res;
    size_t t;
    int W, H, g, max_tris;
    memset(&o, 0, sizeof o);
    if (options) o = *options;
    r->o = o;
    W = o.width ? o.width : 1024;
    H = o.height ? o.height : 1024;
    g = o.gutter ? o.gutter : 4;
    max_tris = o.max_chart_triangles ? o.max_chart_triangles : 96;
    max_tris = max_tris < 1 ? 1 : max_tris > 256 ? 256 : max_tris;
    r->W = W; r->H = H; r->g = g; r->max_tris = max_tris;
    r->rounds = o.stretch_iterations == 0 ? 6 : o.stretch_iterations < 0 ? 0 : o.stretch_iterations > 1000 ? 1000 : o.stretch_iterations;
    if (W < 1 || H < 1 || W > 16384 || H > 16384 || g < 0 || g > 1024 || !(o.max_chart_angle >= 0.0f) ||
        o.max_chart_angle > 180.0f)
        return DM_ERR_INVALID_ARGUMENT;
    r->cos_max = cos((o.max_chart_angle > 0.0f ? o.max_chart_angle : 30.0f) * 0.017453292519943295);
    res = dm__check_mesh(r->positions, r->nv, r->indices, r->nt);
    if (res != DM_OK) return res;
    if (o.triangle_weight)
        for (t = 0; t < r->nt; t++)
            if (!(o.triangle_weight[t] >= 0.0f) || o.triangle_weight[t] > FLT_MAX) return DM_ERR_INVALID_ARGUMENT;
    return DM_OK;
}

/* the result (its arrays owned by it) and the first temporaries */
static dm_result dm__pz_alloc_result(dm__pz_run *r)
{
    dm__scratch *sc = &r->sc;
    size_t nt = r->nt, nv = r->nv, n;
    dm_param *pm;
    sc->a = dm__resolve_allocator(r->o.allocator);
    n = r->n = (size_t)r->W * (size_t)r->H;
    pm = r->pm = (dm_param *)sc->a.alloc(sc->a.user, sizeof(dm_param));
    if (!pm) return DM_ERR_OUT_OF_MEMORY;
    memset(pm, 0, sizeof *pm);
    pm->allocator = sc->a;
    pm->width = r->W;
    pm->height = r->H;
    pm->triangle_count = nt;
    pm->uv = (float *)dm__alloc_array(&sc->a, 6 * nt, sizeof(float), &sc->overflow);
    pm->chart = (uint32_t *)dm__alloc_array(&sc->a, nt, sizeof(uint32_t), &sc->overflow);
    pm->twin = (uint32_t *)dm__alloc_array(&sc->a, 3 * nt, sizeof(uint32_t), &sc->overflow);
    pm->texel_triangle = (uint32_t *)dm__alloc_array(&sc->a, n, sizeof(uint32_t), &sc->overflow);
    pm->texel_bary = (float *)dm__alloc_array(&sc->a, 2 * n, sizeof(float), &sc->overflow);
    pm->nbr = (uint32_t *)dm__alloc_array(&sc->a, 4 * n, sizeof(uint32_t), &sc->overflow);
    pm->nbr_rot = (uint8_t *)dm__alloc_array(&sc->a, 4 * n, sizeof(uint8_t), &sc->overflow);
    r->edges = (dm__edge *)dm__take(sc, 3 * nt, sizeof(dm__edge));
    r->twin_he = (uint32_t *)dm__take(sc, 3 * nt, sizeof(uint32_t));
    r->chart0 = (uint32_t *)dm__take(sc, nt, sizeof(uint32_t));
    r->vstamp = (uint32_t *)dm__take(sc, nv, sizeof(uint32_t));
    r->queue = (uint32_t *)dm__take(sc, 3 * nt + 3, sizeof(uint32_t));
    r->gl = (uint32_t *)dm__take(sc, nv, sizeof(uint32_t));
    r->target = (double *)dm__take(sc, nt, sizeof(double));
    r->cuv = (double *)dm__take(sc, 6 * nt, sizeof(double));
    r->sig_t = (double *)dm__take(sc, nt, sizeof(double));
    if (!pm->uv || !pm->chart || !pm->twin || !pm->texel_triangle || !pm->texel_bary || !pm->nbr || !pm->nbr_rot ||
        !r->edges || !r->twin_he || !r->chart0 || !r->vstamp || !r->queue || !r->gl || !r->target || !r->cuv ||
        !r->sig_t)
        return dm__scratch_fail(sc);
    return DM_OK;
}

/* 1. adjacency, then charts grown over edges while the normals stay within the cone */
static dm_result dm__pz_find_charts(dm__pz_run *r)
{
    size_t i;
    dm__twins(r->indices, r->nt, r->edges, r->pm->twin, r->twin_he);
    for (i = 0; i < r->nv; i++) { r->vstamp[i] = DM_NO_HIT; r->gl[i] = DM_NO_HIT; }
    r->nc0 = dm__pz_grow_charts(r->positions, r->indices, r->nt, r->pm->twin, r->max_tris, r->cos_max, r->chart0,
                                r->vstamp, r->queue);
    return DM_OK;
}

/* the squared length of triangle tri's longest edge */
static double dm__pz_longest_edge2(const float *pos, const uint32_t *tri)
{
    double l2 = 0.0, d[3], a[3], b[3];
    int c;
    for (c = 0; c < 3; c++) {
        dm__load3(pos, tri[c], a);
        dm__load3(pos, tri[(c + 1) % 3], b);
        dm__sub3(b, a, d);
        if (dm__dot3(d, d) > l2) l2 = dm__dot3(d, d);
    }
    return l2;
}

/* A sliver scaled up to a larger target area is a needle that can outrun the map, whose scale
   would then shrink to fit it: scaled to its target, a triangle's longest edge stays within the
   side of the total area's square (DM__PZ_NEEDLE, squared; the target is cut to fit). */
#define DM__PZ_NEEDLE 1.0

/* 2. targets: weights (default: area), floored at 1e-4 of the mean, scaled to the total area,
   needles cut */
static dm_result dm__pz_targets(dm__pz_run *r)
{
    size_t t, nt = r->nt, capped = 0;
    double total_area = 0.0, total_w = 0.0, floor_w, sum = 0.0;
    double *target = r->target;
    for (t = 0; t < nt; t++) {
        double fnv[3];
        dm__face_normal(r->positions, r->indices, t, fnv);
        r->sig_t[t] = 0.5 * dm__len3(fnv);
        total_area += r->sig_t[t];
        target[t] = r->o.triangle_weight ? (double)r->o.triangle_weight[t] : r->sig_t[t];
        total_w += target[t];
    }
    if (!(total_area > 0.0)) total_area = (double)nt;
    if (!(total_w > 0.0)) { for (t = 0; t < nt; t++) target[t] = 1.0; total_w = (double)nt; }
    floor_w = 1e-4 * total_w / (double)nt;
    for (t = 0; t < nt; t++) { if (target[t] < floor_w) target[t] = floor_w; sum += target[t]; }
    for (t = 0; t < nt; t++) target[t] *= total_area / sum;
    for (t = 0; t < nt; t++) { /* needles cut */
        double l2 = dm__pz_longest_edge2(r->positions, r->indices + 3 * t);
        if (l2 > 0.0 && target[t] * l2 > DM__PZ_NEEDLE * total_area * r->sig_t[t]) {
            target[t] = DM__PZ_NEEDLE * total_area * r->sig_t[t] / l2;
            capped++;
        }
    }
    if (capped) { /* (only then: other maps keep their bits) */
        for (t = 0, sum = 0.0; t < nt; t++) sum += target[t];
        for (t = 0; t < nt; t++) target[t] *= total_area / sum;
    }
    r->total_area = total_area;
    return DM_OK;
}

/* 3. bucket the triangles by chart (stable: in triangle order within a chart) */
static dm_result dm__pz_bucket_charts(dm__pz_run *r)
{
    size_t t, i, nc0 = r->nc0;
    uint32_t *fillp;
    r->cstart = (uint32_t *)dm__take(&r->sc, nc0 + 1, sizeof(uint32_t));
    r->ctris = (uint32_t *)dm__take(&r->sc, r->nt, sizeof(uint32_t));
    if (!r->cstart || !r->ctris) return dm__scratch_fail(&r->sc);
    memset(r->cstart, 0, (nc0 + 1) * sizeof(uint32_t));
    for (t = 0; t < r->nt; t++) r->cstart[r->chart0[t] + 1]++;
    for (i = 0; i < nc0; i++) {
        if (r->cstart[i + 1] > r->maxc) r->maxc = r->cstart[i + 1];
        r->cstart[i + 1] += r->cstart[i];
    }
    fillp = (uint32_t *)dm__take(&r->sc, nc0, sizeof(uint32_t));
    if (!fillp) return dm__scratch_fail(&r->sc);
    memcpy(fillp, r->cstart, nc0 * sizeof(uint32_t));
    for (t = 0; t < r->nt; t++) r->ctris[fillp[r->chart0[t]]++] = (uint32_t)t;
    return DM_OK;
}

/* the working arrays of one chart's layout, sized for the largest chart */
static dm_result dm__pz_alloc_chart(dm__pz_run *r)
{
    dm__scratch *sc = &r->sc;
    dm__pz_chart *ch = &r->ch;
    size_t maxc = r->maxc;
    memset(ch, 0, sizeof *ch);
    ch->tri = (uint32_t *)dm__take(sc, maxc, sizeof(uint32_t));
    ch->lv = (uint32_t *)dm__take(sc, 3 * maxc, sizeof(uint32_t));
    ch->gv = (uint32_t *)dm__take(sc, 3 * maxc, sizeof(uint32_t));
    ch->x = (double *)dm__take(sc, 9 * maxc, sizeof(double));
    ch->uv = (double *)dm__take(sc, 6 * maxc, sizeof(double));
    ch->uv_prev = (double *)dm__take(sc, 6 * maxc, sizeof(double));
    ch->w = (double *)dm__take(sc, 6 * maxc, sizeof(double));
    ch->target = (double *)dm__take(sc, maxc, sizeof(double));
    ch->sigma = (double *)dm__take(sc, 3 * maxc, sizeof(double));
    ch->sig_w = (double *)dm__take(sc, 3 * maxc, sizeof(double));
    ch->interior = (int *)dm__take(sc, 3 * maxc, sizeof(int));
    ch->bnext = (uint32_t *)dm__take(sc, 3 * maxc, sizeof(uint32_t));
    ch->mat = (double *)dm__take(sc, 9 * maxc * maxc, sizeof(double));
    ch->rhs = (double *)dm__take(sc, 6 * maxc, sizeof(double));
    r->chart_n = (double *)dm__take(sc, 3 * maxc, sizeof(double));
    if (!ch->tri || !ch->lv || !ch->gv || !ch->x || !ch->uv || !ch->uv_prev || !ch->w || !ch->target || !ch->sigma ||
        !ch->sig_w || !ch->interior || !ch->bnext || !ch->mat || !ch->rhs || !r->chart_n)
        return dm__scratch_fail(sc);
    return DM_OK;
}

/* the chart of triangles ctris[s..e) (chart0 = label) and its local vertices into ch, its
   boundary loop (bnext) and interior numbering; nsum gets the chart's mean normal */
static void dm__pz_gather_chart(dm__pz_run *r, size_t s, size_t e, uint32_t label, double nsum[3])
{
    dm__pz_chart *ch = &r->ch;
    size_t k, lt, t;
    double ln;
    int c;
    nsum[0] = nsum[1] = nsum[2] = 0.0;
    ch->nt = e - s;
    ch->nv = 0;
    for (lt = 0; lt < ch->nt; lt++) {
        double fn[3];
        t = r->ctris[s + lt];
        ch->tri[lt] = (uint32_t)t;
        ch->target[lt] = r->target[t];
        dm__face_normal(r->positions, r->indices, t, fn);
        nsum[0] += fn[0]; nsum[1] += fn[1]; nsum[2] += fn[2];
        for (c = 0; c < 3; c++) {
            uint32_t v = r->indices[3 * t + (size_t)c];
            if (r->gl[v] == DM_NO_HIT) {
                r->gl[v] = (uint32_t)ch->nv;
                ch->gv[ch->nv] = v;
                dm__load3(r->positions, v, ch->x + 3 * ch->nv);
                ch->bnext[ch->nv] = DM_NO_HIT;
                ch->nv++;
            }
            ch->lv[3 * lt + (size_t)c] = r->gl[v];
        }
    }
    for (lt = 0; lt < ch->nt; lt++)
        for (c = 0; c < 3; c++) {
            uint32_t o2 = r->pm->twin[3 * (size_t)ch->tri[lt] + (size_t)c];
            if (o2 == DM_NO_HIT || r->chart0[o2] != label)
                ch->bnext[ch->lv[3 * lt + (size_t)c]] = ch->lv[3 * lt + (size_t)((c + 1) % 3)];
        }
    ch->n_int = 0;
    for (k = 0; k < ch->nv; k++) ch->interior[k] = ch->bnext[k] == DM_NO_HIT ? (int)ch->n_int++ : -1;
    ln = dm__len3(nsum);
    if (ln > 0.0) { nsum[0] /= ln; nsum[1] /= ln; nsum[2] /= ln; } else { nsum[2] = 1.0; }
}

/* the laid-out chart in ch becomes chart nc, scaled to its target area; returns the next number */
static size_t dm__pz_keep_chart(dm__pz_run *r, size_t nc)
{
    const dm__pz_chart *ch = &r->ch;
    double uvsum = 0.0, tsum = 0.0, f;
    size_t lt;
    int c;
    for (lt = 0; lt < ch->nt; lt++) {
        for (c = 0; c < 3; c++) {
            r->cuv[6 * (size_t)ch->tri[lt] + 2 * (size_t)c] = ch->uv[2 * ch->lv[3 * lt + (size_t)c]];
            r->cuv[6 * (size_t)ch->tri[lt] + 2 * (size_t)c + 1] = ch->uv[2 * ch->lv[3 * lt + (size_t)c] + 1];
        }
        uvsum += dm__pz_uv_area(ch->uv, ch->lv + 3 * lt);
        tsum += ch->target[lt];
    }
    f = sqrt(tsum / uvsum);
    for (lt = 0; lt < ch->nt; lt++) {
        r->pm->chart[ch->tri[lt]] = (uint32_t)nc;
        for (c = 0; c < 6; c++) r->cuv[6 * (size_t)ch->tri[lt] + (size_t)c] *= f;
    }
    return nc + 1;
}

/* the chart in ch, too small to cut further, falls apart into lone triangles, numbered from
   nc; returns the next number */
static size_t dm__pz_split_chart(dm__pz_run *r, size_t nc)
{
    const dm__pz_chart *ch = &r->ch;
    size_t lt;
    int c;
    for (lt = 0; lt < ch->nt; lt++) {
        double *q = r->cuv + 6 * (size_t)ch->tri[lt], f;
        dm__pz_single(r->positions, r->indices, ch->tri[lt], q);
        f = sqrt(ch->target[lt] / dm__pz_cuv_area(q));
        for (c = 0; c < 6; c++) q[c] *= f;
        r->pm->chart[ch->tri[lt]] = (uint32_t)nc++;
    }
    return nc;
}

/* The chart ctris[s..e) (chart0 = label) in two: the first half of a breadth-first walk over
   its edges from the triangle at the low end of its widest axis (chart0 = fresh), then the rest
   (label). Returns the split point. */
static size_t dm__pz_bisect(dm__pz_run *r, size_t s, size_t e, uint32_t label, uint32_t fresh)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, best = DBL_MAX;
    size_t k, head = 0, tail = 0, half = (e - s) / 2, m;
    uint32_t seed = r->ctris[s];
    int c, ax = 0;
    for (k = s; k < e; k++)
        for (c = 0; c < 3; c++) {
            double q[3];
            int j;
            dm__load3(r->positions, r->indices[3 * (size_t)r->ctris[k] + (size_t)c], q);
            for (j = 0; j < 3; j++) { lo[j] = q[j] < lo[j] ? q[j] : lo[j]; hi[j] = q[j] > hi[j] ? q[j] : hi[j]; }
        }
    for (c = 1; c < 3; c++) if (hi[c] - lo[c] > hi[ax] - lo[ax]) ax = c;
    for (k = s; k < e; k++) {
        const uint32_t *tr = r->indices + 3 * (size_t)r->ctris[k];
        double x = (double)r->positions[3 * (size_t)tr[0] + (size_t)ax] + r->positions[3 * (size_t)tr[1] + (size_t)ax] +
                   r->positions[3 * (size_t)tr[2] + (size_t)ax];
        if (x < best) { best = x; seed = r->ctris[k]; }
    }
    r->chart0[seed] = fresh;
    r->queue[tail++] = seed;
    while (head < tail && tail < half) {
        uint32_t t = r->queue[head++];
        for (c = 0; c < 3 && tail < half; c++) {
            uint32_t o2 = r->pm->twin[3 * (size_t)t + (size_t)c];
            if (o2 == DM_NO_HIT || r->chart0[o2] != label) continue;
            r->chart0[o2] = fresh;
            r->queue[tail++] = o2;
        }
    }
    m = s + tail;
    for (k = s; k < e; k++) /* the rest, after the walk's triangles */
        if (r->chart0[r->ctris[k]] == label) r->queue[tail++] = r->ctris[k];
    for (k = s; k < e; k++) r->ctris[k] = r->queue[k - s];
    return m;
}

/* lays out the chart ctris[s..e) (chart0 = label), kept as chart nc when it lays out (within
   DM__PZ_MAX_STRETCH, nothing flipped), else cut in two and each half laid out the same way,
   down to lone triangles; returns the next chart number */
static size_t dm__pz_layout_part(dm__pz_run *r, size_t s, size_t e, uint32_t label, size_t nc, int depth)
{
    double nsum[3];
    size_t k, m;
    uint32_t fresh;
    int ok, last = e - s < 4 || depth >= 40; /* too small (or too deep) to cut again */
    dm__pz_gather_chart(r, s, e, label, nsum);
    ok = r->ch.nt > 1 && dm__pz_layout(&r->ch, nsum, r->rounds, r->sig_t);
    if (ok) nc = dm__pz_keep_chart(r, nc);
    else if (last) nc = dm__pz_split_chart(r, nc);
    for (k = 0; k < r->ch.nv; k++) r->gl[r->ch.gv[k]] = DM_NO_HIT;
    if (ok || last) return nc;
    fresh = r->next_label++;
    m = dm__pz_bisect(r, s, e, label, fresh);
    nc = dm__pz_layout_part(r, s, m, fresh, nc, depth + 1);
    return dm__pz_layout_part(r, m, e, label, nc, depth + 1);
}

/* 4. lay out each grown chart; the charts are renumbered as they are kept or split */
static dm_result dm__pz_layout_charts(dm__pz_run *r)
{
    size_t i, nc = 0;
    dm_result res = dm__pz_alloc_chart(r);
    if (res != DM_OK) return res;
    r->pm->stretch_l2 = 0.0f;
    r->next_label = (uint32_t)r->nc0;
    for (i = 0; i < r->nc0; i++) {
        if (dm__pz_step_report(r, 0.6f * (float)i / (float)r->nc0) != DM_OK) return DM_CANCELLED;
        nc = dm__pz_layout_part(r, r->cstart[i], r->cstart[i + 1], (uint32_t)i, nc, 0);
    }
    r->pm->chart_count = nc;
    return DM_OK;
}

/* chart i (its triangles ctris[bstart[i]..bstart[i+1]]) turned to the smallest of 12 box
   angles and moved to the origin; its box size goes to pk[i] */
static void dm__pz_box_chart(dm__pz_run *r, size_t i)
{
    const uint32_t *ctris = r->ctris, *bstart = r->bstart;
    double *cuv = r->cuv;
    int a, best_a = 0, c;
    double best_area = 0.0, mn[2], mx[2], cs, sn;
    size_t k;
    for (a = 0; a < 12; a++) {
        double ang = a * (3.141592653589793 / 12.0), area;
        cs = cos(ang); sn = sin(ang);
        mn[0] = mn[1] = HUGE_VAL; mx[0] = mx[1] = -HUGE_VAL;
        for (k = bstart[i]; k < bstart[i + 1]; k++)
            for (c = 0; c < 3; c++) {
                const double *q = cuv + 6 * (size_t)ctris[k] + 2 * (size_t)c;
                double u = cs * q[0] - sn * q[1], v = sn * q[0] + cs * q[1];
                if (u < mn[0]) mn[0] = u;
                if (u > mx[0]) mx[0] = u;
                if (v < mn[1]) mn[1] = v;
                if (v > mx[1]) mx[1] = v;
            }
        area = (mx[0] - mn[0]) * (mx[1] - mn[1]);
        if (a == 0 || area < best_area) { best_area = area; best_a = a; }
    }
    cs = cos(best_a * (3.141592653589793 / 12.0));
    sn = sin(best_a * (3.141592653589793 / 12.0));
    mn[0] = mn[1] = HUGE_VAL; mx[0] = mx[1] = -HUGE_VAL;
    for (k = bstart[i]; k < bstart[i + 1]; k++)
        for (c = 0; c < 3; c++) {
            double *q = cuv + 6 * (size_t)ctris[k] + 2 * (size_t)c;
            double u = cs * q[0] - sn * q[1], v = sn * q[0] + cs * q[1];
            q[0] = u; q[1] = v;
            if (u < mn[0]) mn[0] = u;
            if (u > mx[0]) mx[0] = u;
            if (v < mn[1]) mn[1] = v;
            if (v > mx[1]) mx[1] = v;
        }
    for (k = bstart[i]; k < bstart[i + 1]; k++)
        for (c = 0; c < 3; c++) {
            double *q = cuv + 6 * (size_t)ctris[k] + 2 * (size_t)c;
            q[0] -= mn[0];
            q[1] -= mn[1];
        }
    r->pk[i].bw = mx[0] - mn[0];
    r->pk[i].bh = mx[1] - mn[1];
}

/* 5a. the triangles bucketed again by final chart, each chart turned to its smallest box */
static dm_result dm__pz_box_charts(dm__pz_run *r)
{
    size_t t, i, nt = r->nt, nc = r->pm->chart_count;
    const uint32_t *chart = r->pm->chart;
    r->pk = (dm__pz_pack *)dm__take(&r->sc, nc, sizeof(dm__pz_pack));
    r->order = (uint32_t *)dm__take(&r->sc, nc, sizeof(uint32_t));
    r->otmp = (uint32_t *)dm__take(&r->sc, nc, sizeof(uint32_t));
    r->bstart = (uint32_t *)dm__take(&r->sc, nc + 1, sizeof(uint32_t));
    r->blist = (uint32_t *)dm__take(&r->sc, 3 * nt, sizeof(uint32_t));
    if (!r->pk || !r->order || !r->otmp || !r->bstart || !r->blist) return dm__scratch_fail(&r->sc);
    memset(r->bstart, 0, (nc + 1) * sizeof(uint32_t));
    for (t = 0; t < nt; t++) r->bstart[chart[t] + 1]++;
    for (i = 0; i < nc; i++) r->bstart[i + 1] += r->bstart[i];
    memcpy(r->otmp, r->bstart, nc * sizeof(uint32_t));
    for (t = 0; t < nt; t++) r->ctris[r->otmp[chart[t]]++] = (uint32_t)t;
    for (i = 0; i < nc; i++) dm__pz_box_chart(r, i);
    return DM_OK;
}

/* the x extent of triangle P within the band y0 <= y <= y1: its corners there and its edges'
   crossings of the band's two lines; 0 when the triangle misses the band */
static int dm__pz_band_extent(const double P[3][2], double y0, double y1, double *xmin, double *xmax)
{
    int c, k, any = 0;
    *xmin = HUGE_VAL;
    *xmax = -HUGE_VAL;
    for (c = 0; c < 3; c++) {
        const double *a = P[c], *b = P[(c + 1) % 3];
        if (a[1] >= y0 && a[1] <= y1) {
            *xmin = fmin(*xmin, a[0]);
            *xmax = fmax(*xmax, a[0]);
            any = 1;
        }
        for (k = 0; k < 2; k++) {
            double yl = k ? y1 : y0, t;
            if ((a[1] - yl) * (b[1] - yl) >= 0.0 || a[1] == b[1]) continue;
            t = (yl - a[1]) / (b[1] - a[1]);
            *xmin = fmin(*xmin, a[0] + t * (b[0] - a[0]));
            *xmax = fmax(*xmax, a[0] + t * (b[0] - a[0]));
            any = 1;
        }
    }
    return any;
}

/* the footprint bit of shape texel (tx, ty) in quarter turn q (the unturned footprint w x h) */
static int dm__pz_foot_bit(const dm__pz_bitpack *b, int q, int w, int h, int tx, int ty)
{
    int x = q == 0 ? tx : q == 1 ? ty : q == 2 ? w - 1 - tx : w - 1 - ty;
    int y = q == 0 ? ty : q == 1 ? h - 1 - tx : q == 2 ? h - 1 - ty : tx;
    return (int)(b->foot[(size_t)y * (size_t)b->words + (size_t)(x >> 6)] >> (x & 63) & 1);
}

/* the runs of the footprint in quarter turn q: counted (fill 0) or written (fill 1); returns
   their number */
static size_t dm__pz_foot_runs(dm__pz_bitpack *b, int q, int w, int h, int fill)
{
    int sw = q & 1 ? h : w, sh = q & 1 ? w : h, tx, ty;
    size_t n = 0;
    for (ty = 0; ty < sh; ty++) {
        int lo = INT32_MAX, hi = -1, longest = 0;
        if (fill) b->rstart[q][ty] = (int)n;
        for (tx = 0; tx < sw; tx++) {
            int start;
            if (!dm__pz_foot_bit(b, q, w, h, tx, ty)) continue;
            for (start = tx; tx + 1 < sw && dm__pz_foot_bit(b, q, w, h, tx + 1, ty); tx++) {}
            if (b->silhouette) /* on to the row's last texel */
                for (tx = sw - 1; !dm__pz_foot_bit(b, q, w, h, tx, ty); tx--) {}
            if (fill) {
                b->run[q][3 * n] = ty;
                b->run[q][3 * n + 1] = start;
                b->run[q][3 * n + 2] = tx;
            }
            if (start < lo) lo = start;
            hi = tx;
            if (tx - start + 1 > longest) longest = tx - start + 1;
            n++;
        }
        if (fill) {
            b->lo[q][ty] = lo;
            b->hi[q][ty] = hi;
            b->longest[q][ty] = longest;
        }
    }
    if (fill) b->rstart[q][sh] = (int)n;
    return n;
}

/* chart i's footprint at scale s with margin o (texels): the texels whose square grown by o
   meets one of its triangles, as runs of each row in each of the four quarter turns; 1 done,
   0 when it does not fit the map, -1 when out of memory */
static int dm__pz_footprint(dm__pz_run *r, dm__pz_bitpack *b, size_t i, double s, double o, int *w, int *h)
{
    const uint32_t *ctris = r->ctris, *bstart = r->bstart;
    double fw = ceil(s * r->pk[i].bw + 2.0 * o - 1e-9), fh = ceil(s * r->pk[i].bh + 2.0 * o - 1e-9);
    size_t k, n0, n1;
    int y, c, q;
    if (!(fw <= (double)b->W && fh <= (double)b->H)) return 0;
    *w = fw < 1.0 ? 1 : (int)fw;
    *h = fh < 1.0 ? 1 : (int)fh;
    memset(b->foot, 0, (size_t)*h * (size_t)b->words * sizeof(uint64_t));
    for (k = bstart[i]; k < bstart[i + 1]; k++) {
        double P[3][2], mn = HUGE_VAL, mx = -HUGE_VAL, e0, e1;
        for (c = 0; c < 3; c++) {
            P[c][0] = o + s * r->cuv[6 * (size_t)ctris[k] + 2 * (size_t)c];
            P[c][1] = o + s * r->cuv[6 * (size_t)ctris[k] + 2 * (size_t)c + 1];
            mn = fmin(mn, P[c][1]);
            mx = fmax(mx, P[c][1]);
        }
        for (y = (int)floor(mn - o); y <= (int)floor(mx + o); y++) {
            long x0, x1, x;
            uint64_t *row = b->foot + (size_t)y * (size_t)b->words;
            if (y < 0 || y >= *h || !dm__pz_band_extent((const double(*)[2])P, y - o, y + 1 + o, &e0, &e1)) continue;
            x0 = (long)ceil(e0 - 1.0 - o);
            x1 = (long)floor(e1 + o);
            if (x0 < 0) x0 = 0;
            if (x1 > *w - 1) x1 = *w - 1;
            for (x = x0; x <= x1; x++) row[x >> 6] |= (uint64_t)1 << (x & 63);
        }
    }
    n0 = dm__pz_foot_runs(b, 0, *w, *h, 0); /* turn 2 has turn 0's runs mirrored, turn 3 turn 1's */
    n1 = dm__pz_foot_runs(b, 1, *w, *h, 0);
    if (n1 > n0) n0 = n1;
    if (n0 > b->run_cap) {
        size_t cap = 2 * n0;
        int of = 0;
        for (q = 0; q < 4; q++) {
            b->al.free(b->al.user, b->run[q]);
            b->run[q] = (int *)dm__alloc_array(&b->al, cap, 3 * sizeof(int), &of);
        }
        b->run_cap = b->run[0] && b->run[1] && b->run[2] && b->run[3] ? cap : 0;
        if (!b->run_cap) return -1;
    }
    for (q = 0; q < 4; q++) dm__pz_foot_runs(b, q, *w, *h, 1);
    return 1;
}

/* footprint quarter turn q of a chart w x h texels unturned, as a shape, with its widest run
   (the likeliest to refuse a place, the first asked) */
static dm__pz_shape dm__pz_turned(const dm__pz_bitpack *b, int q, int w, int h)
{
    dm__pz_shape sh;
    int r;
    sh.w = q & 1 ? h : w;
    sh.h = q & 1 ? w : h;
    sh.lo = b->lo[q];
    sh.hi = b->hi[q];
    sh.longest = b->longest[q];
    sh.rstart = b->rstart[q];
    sh.run = b->run[q];
    sh.wide = 0;
    for (r = 1; r < sh.h; r++)
        if (sh.longest[r] > sh.longest[sh.wide]) sh.wide = r;
    for (sh.wide_run = sh.rstart[sh.wide]; sh.wide_run + 1 < sh.rstart[sh.wide + 1] &&
                                           sh.run[3 * sh.wide_run + 2] - sh.run[3 * sh.wide_run + 1] + 1 < sh.longest[sh.wide];
         sh.wide_run++) {}
    return sh;
}

/* every chart at scale s: its quarter turn and place into pk[i].turn, ox, oy, and the highest
   row used into *top; 1 done, 0 when one does not fit, -1 when out of memory */
static int dm__pz_bitmap_pack(dm__pz_run *r, dm__pz_bitpack *b, double s, double o, int *top)
{
    size_t n, nc = r->pm->chart_count;
    int y;
    *top = 0;
    memset(b->taken, 0, (size_t)b->H * (size_t)b->words * sizeof(uint64_t));
    for (y = 0; y < b->H; y++) {
        int x;
        b->first_free[y] = 0;
        b->longest_free[y] = b->W;
        for (x = 0; x < b->W; x++) b->free_run[(size_t)y * (size_t)b->W + (size_t)x] = (uint16_t)(b->W - x);
    }
    for (n = 0; n < nc; n++) {
        size_t i = r->order[n];
        int w, h, q, best_q = -1, bx = 0, by = 0, got = dm__pz_footprint(r, b, i, s, o, &w, &h);
        dm__pz_shape sh;
        if (got <= 0) return got;
        for (q = 0; q < 4; q++) {
            int px, py;
            sh = dm__pz_turned(b, q, w, h);
            if (!dm__pz_find_place(b, &sh, best_q < 0 ? b->H : by + (best_q & 1 ? w : h) - sh.h, &px, &py)) continue;
            if (best_q < 0 || py + sh.h < by + (best_q & 1 ? w : h) || (py + sh.h == by + (best_q & 1 ? w : h) && px < bx)) {
                best_q = q;
                bx = px;
                by = py;
            }
        }
        if (best_q < 0) return 0;
        sh = dm__pz_turned(b, best_q, w, h);
        dm__pz_take_place(b, &sh, bx, by);
        r->pk[i].turn = best_q;
        r->pk[i].ox = bx;
        r->pk[i].oy = by;
        r->pk[i].fw = w;
        r->pk[i].fh = h;
        if (by + sh.h > *top) *top = by + sh.h;
    }
    return 1;
}

/* the largest scale at which the charts fit as b's footprints, by bisection from s_lo (the
   shelves' scale) up: into *s_best (0 when they fit at no scale tried), their places into saved;
   0 when out of memory */
static int dm__pz_bitmap_search(dm__pz_run *r, dm__pz_bitpack *b, double s_lo, double o, dm__pz_pack *saved,
                                double *s_best)
{
    size_t nc = r->pm->chart_count;
    double s_hi = 1.6 * s_lo;
    int it, top = 0;
    *s_best = 0.0;
    for (it = 0; it < 8; it++) { /* from 1.15 x the shelves' scale: the scale that fills the rows
                                    the last fit left unused, else halfway to the least that failed */
        double s = it == 0 ? 1.15 * s_lo : *s_best > 0.0 ? *s_best * sqrt((double)b->H / (double)(top > 0 ? top : 1)) * 0.998 : s_lo;
        int t2, got;
        if (*s_best > 0.0 && !(s < s_hi)) s = 0.5 * (*s_best + s_hi);
        if (*s_best > 0.0 && !(s > *s_best * 1.002)) break;
        got = dm__pz_bitmap_pack(r, b, s, o, &t2);
        if (got < 0) return 0;
        if (got) {
            *s_best = s;
            top = t2;
            memcpy(saved, r->pk, nc * sizeof(dm__pz_pack));
        } else {
            s_hi = s;
            if (s <= s_lo) break; /* not even at the shelves' scale */
        }
    }
    return 1;
}

/* the largest scale at which the charts fit as bitmap footprints, exact or, when there are at
   most DM__PZ_FEW charts, also as silhouettes (interlocking charts mostly pack tighter, but not
   always when they are few; few pack fast): the larger; 0 when they fit at no scale tried, -1
   when out of memory. The places of the best are in pk. */
#define DM__PZ_FEW 64
static double dm__pz_bitmap_scale(dm__pz_run *r, double s_lo, double o)
{
    dm__pz_bitpack b;
    size_t nc = r->pm->chart_count;
    double best = 0.0, s = 0.0, res = -1.0;
    int q, ok = 1;
    dm__pz_pack *saved, *found;
    memset(&b, 0, sizeof b);
    b.W = r->W;
    b.H = r->H;
    b.words = (r->W + 63) / 64;
    b.rows_cap = r->W > r->H ? r->W : r->H;
    b.al = r->sc.a;
    b.taken = (uint64_t *)dm__take(&r->sc, (size_t)b.H * (size_t)b.words, sizeof(uint64_t));
    b.foot = (uint64_t *)dm__take(&r->sc, (size_t)b.H * (size_t)b.words, sizeof(uint64_t));
    b.free_run = (uint16_t *)dm__take(&r->sc, (size_t)b.H * (size_t)b.W, sizeof(uint16_t));
    for (q = 0; q < 4; q++) {
        b.lo[q] = (int *)dm__take(&r->sc, (size_t)b.rows_cap, sizeof(int));
        b.hi[q] = (int *)dm__take(&r->sc, (size_t)b.rows_cap, sizeof(int));
        b.longest[q] = (int *)dm__take(&r->sc, (size_t)b.rows_cap, sizeof(int));
        b.rstart[q] = (int *)dm__take(&r->sc, (size_t)b.rows_cap + 1, sizeof(int));
        ok &= b.lo[q] && b.hi[q] && b.longest[q] && b.rstart[q];
    }
    b.first_free = (int *)dm__take(&r->sc, (size_t)b.H, sizeof(int));
    b.longest_free = (int *)dm__take(&r->sc, (size_t)b.H, sizeof(int));
    saved = (dm__pz_pack *)dm__take(&r->sc, nc, sizeof(dm__pz_pack));
    found = (dm__pz_pack *)dm__take(&r->sc, nc, sizeof(dm__pz_pack));
    if (!ok || !b.taken || !b.foot || !b.free_run || !b.first_free || !b.longest_free || !saved || !found) return -1.0;
    dm__pz_order(r->pk, nc, 1, r->order, r->otmp);
    for (b.silhouette = 0; b.silhouette < (nc <= DM__PZ_FEW ? 2 : 1); b.silhouette++) {
        if (!dm__pz_bitmap_search(r, &b, s_lo, o, found, &s)) goto done;
        if (s > best) {
            best = s;
            memcpy(saved, found, nc * sizeof(dm__pz_pack));
        }
    }
    if (best > 0.0) memcpy(r->pk, saved, nc * sizeof(dm__pz_pack));
    res = best;
done:
    for (q = 0; q < 4; q++) b.al.free(b.al.user, b.run[q]);
    return res;
}

/* chart point (u, v) of chart p (chart units) at scale s and margin o, turned and placed: texels */
static void dm__pz_bitmap_uv(const dm__pz_pack *p, double s, double o, double u, double v, double out[2])
{
    double x = o + s * u, y = o + s * v, tx, ty;
    if (p->turn == 0) { tx = x; ty = y; }
    else if (p->turn == 1) { tx = p->fh - y; ty = x; }
    else if (p->turn == 2) { tx = p->fw - x; ty = p->fh - y; }
    else { tx = y; ty = p->fw - x; }
    out[0] = p->ox + tx;
    out[1] = p->oy + ty;
}

/* 5b. the charts packed into the map at the largest scale that fits: as boxes in shelves
   (found by bisection), then, larger where it fits, as bitmap footprints with quarter turns;
   the uv follow */
static dm_result dm__pz_pack_charts(dm__pz_run *r)
{
    size_t i, t, nc = r->pm->chart_count;
    int W = r->W, H = r->H, g = r->g, c;
    double s_lo = 0.0, s_hi, s_best, s_bits, o = 0.5 * g;
    dm__pz_order(r->pk, nc, 0, r->order, r->otmp);
    s_hi = sqrt((double)W * (double)H / r->total_area);
    if (!dm__pz_try_pack(r->pk, r->order, nc, 0.0, g, W, H)) return DM_ERR_MAP_TOO_SMALL;
    s_best = 0.0;
    for (i = 0; i < 48; i++) {
        double s = 0.5 * (s_lo + s_hi);
        if (dm__pz_try_pack(r->pk, r->order, nc, s, g, W, H)) { s_best = s; s_lo = s; } else s_hi = s;
    }
    if (!(s_best > 0.0)) return DM_ERR_MAP_TOO_SMALL;
    s_bits = dm__pz_bitmap_scale(r, s_best, o);
    if (s_bits < 0.0) return dm__scratch_fail(&r->sc);
    if (!(s_bits > s_best)) {
        dm__pz_order(r->pk, nc, 0, r->order, r->otmp);
        dm__pz_try_pack(r->pk, r->order, nc, s_best, g, W, H);
    }
    for (t = 0; t < r->nt; t++) {
        const dm__pz_pack *p = r->pk + r->pm->chart[t];
        for (c = 0; c < 3; c++) {
            double q[2];
            if (s_bits > s_best) {
                dm__pz_bitmap_uv(p, s_bits, o, r->cuv[6 * t + 2 * (size_t)c], r->cuv[6 * t + 2 * (size_t)c + 1], q);
            } else {
                q[0] = p->ox + 0.5 * g + s_best * r->cuv[6 * t + 2 * (size_t)c];
                q[1] = p->oy + 0.5 * g + s_best * r->cuv[6 * t + 2 * (size_t)c + 1];
            }
            r->pm->uv[6 * t + 2 * (size_t)c] = (float)(q[0] / W);
            r->pm->uv[6 * t + 2 * (size_t)c + 1] = (float)(q[1] / H);
        }
    }
    return dm__pz_step_report(r, 0.6f);
}

/* base triangle t's corners in texel units into P, twice its signed uv area in texels into *d,
   and the texels (clamped to the map) whose centres lie within `grow` texels of its box into
   box = {x0, y0, x1, y1}; 0 when its uv area is not positive */
static int dm__uv_texel_box(const dm_param *pm, size_t t, double grow, double P[3][2], double *d, long box[4])
{
    int W = pm->width, H = pm->height, c;
    double mnx, mxx, mny, mxy;
    for (c = 0; c < 3; c++) {
        P[c][0] = (double)pm->uv[6 * t + 2 * (size_t)c] * W;
        P[c][1] = (double)pm->uv[6 * t + 2 * (size_t)c + 1] * H;
    }
    *d = (P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[2][0] - P[0][0]) * (P[1][1] - P[0][1]);
    if (!(*d > 0.0)) return 0;
    mnx = fmin(P[0][0], fmin(P[1][0], P[2][0])); mxx = fmax(P[0][0], fmax(P[1][0], P[2][0]));
    mny = fmin(P[0][1], fmin(P[1][1], P[2][1])); mxy = fmax(P[0][1], fmax(P[1][1], P[2][1]));
    box[0] = (long)floor(mnx - 0.5 - grow); box[2] = (long)ceil(mxx - 0.5 + grow);
    box[1] = (long)floor(mny - 0.5 - grow); box[3] = (long)ceil(mxy - 0.5 + grow);
    if (box[0] < 0) box[0] = 0;
    if (box[1] < 0) box[1] = 0;
    if (box[2] > W - 1) box[2] = W - 1;
    if (box[3] > H - 1) box[3] = H - 1;
    return 1;
}

/* the texels whose centres lie in triangle t (of positive uv area) and are not taken yet */
static void dm__pz_raster_triangle(dm_param *pm, size_t t)
{
    int W = pm->width;
    double P[3][2], d;
    long box[4], x0, x1, y0, y1, xx, yy;
    if (!dm__uv_texel_box(pm, t, 0.0, P, &d, box)) return;
    x0 = box[0]; y0 = box[1]; x1 = box[2]; y1 = box[3];
    for (yy = y0; yy <= y1; yy++)
        for (xx = x0; xx <= x1; xx++) {
            double cx = xx + 0.5 - P[0][0], cy = yy + 0.5 - P[0][1], u, v;
            size_t id = (size_t)yy * (size_t)W + (size_t)xx;
            u = (cx * (P[2][1] - P[0][1]) - cy * (P[2][0] - P[0][0])) / d;
            v = ((P[1][0] - P[0][0]) * cy - (P[1][1] - P[0][1]) * cx) / d;
            if (u < -1e-7 || v < -1e-7 || u + v > 1.0 + 1e-7 || pm->texel_triangle[id] != DM_NO_HIT) continue;
            if (u < 0.0) u = 0.0;
            if (v < 0.0) v = 0.0;
            if (u + v > 1.0) { double sm = u + v; u /= sm; v /= sm; }
            pm->texel_triangle[id] = (uint32_t)t;
            pm->texel_bary[2 * id] = (float)u;
            pm->texel_bary[2 * id + 1] = (float)v;
        }
}

/* 6. the texel -> triangle map: texel centres inside a triangle, first triangle wins */
static dm_result dm__pz_rasterize(dm__pz_run *r)
{
    dm_param *pm = r->pm;
    size_t i, t;
    for (i = 0; i < r->n; i++) { pm->texel_triangle[i] = DM_NO_HIT; pm->texel_bary[2 * i] = pm->texel_bary[2 * i + 1] = 0.0f; }
    for (t = 0; t < r->nt; t++) dm__pz_raster_triangle(pm, t);
    return dm__pz_step_report(r, 0.8f);
}

/* 7a. each chart's boundary half-edges (3 t + c), listed by chart in blist[bstart[chart]..] */
static void dm__pz_seam_lists(dm__pz_run *r)
{
    const dm_param *pm = r->pm;
    size_t t, i, nc = pm->chart_count;
    int c;
    memset(r->bstart, 0, (nc + 1) * sizeof(uint32_t));
    for (t = 0; t < r->nt; t++)
        for (c = 0; c < 3; c++) {
            uint32_t o2 = pm->twin[3 * t + (size_t)c];
            if (o2 == DM_NO_HIT || pm->chart[o2] != pm->chart[t]) r->bstart[pm->chart[t] + 1]++;
        }
    for (i = 0; i < nc; i++) r->bstart[i + 1] += r->bstart[i];
    memcpy(r->otmp, r->bstart, nc * sizeof(uint32_t));
    for (t = 0; t < r->nt; t++)
        for (c = 0; c < 3; c++) {
            uint32_t o2 = pm->twin[3 * t + (size_t)c];
            if (o2 == DM_NO_HIT || pm->chart[o2] != pm->chart[t])
                r->blist[r->otmp[pm->chart[t]]++] = (uint32_t)(3 * t + (size_t)c);
        }
}

/* texel (x, y)'s four neighbours: the next texel of its chart, else the texel across the seam */
static void dm__pz_link_texel(dm__pz_run *r, size_t x, size_t y)
{
    dm_param *pm = r->pm;
    int W = r->W, H = r->H, dir;
    size_t id = y * (size_t)W + x;
    uint32_t tt = pm->texel_triangle[id], cc;
    for (dir = 0; dir < 4; dir++) { pm->nbr[4 * id + (size_t)dir] = UINT32_MAX; pm->nbr_rot[4 * id + (size_t)dir] = 0; }
    if (tt == DM_NO_HIT) return;
    cc = pm->chart[tt];
    for (dir = 0; dir < 4; dir++) {
        long nx = (long)x + (dir == 0 ? 1 : dir == 1 ? -1 : 0), ny = (long)y + (dir == 2 ? 1 : dir == 3 ? -1 : 0);
        double P[2];
        uint8_t rot = 0;
        if (nx >= 0 && ny >= 0 && nx < W && ny < H) {
            uint32_t t2 = pm->texel_triangle[(size_t)ny * (size_t)W + (size_t)nx];
            if (t2 != DM_NO_HIT && pm->chart[t2] == cc) {
                pm->nbr[4 * id + (size_t)dir] = (uint32_t)((size_t)ny * (size_t)W + (size_t)nx);
                continue;
            }
        }
        P[0] = (double)nx + 0.5;
        P[1] = (double)ny + 0.5;
        pm->nbr[4 * id + (size_t)dir] =
            dm__pz_across(pm, r->indices, r->twin_he, r->blist, r->bstart[cc], r->bstart[cc + 1], P, dir, &rot);
        pm->nbr_rot[4 * id + (size_t)dir] = pm->nbr[4 * id + (size_t)dir] == UINT32_MAX ? 0 : rot;
    }
}

/* 7. the neighbours of every texel, across seams too */
static dm_result dm__pz_link_texels(dm__pz_run *r)
{
    size_t x, y;
    dm__pz_seam_lists(r);
    for (y = 0; y < (size_t)r->H; y++) {
        for (x = 0; x < (size_t)r->W; x++) dm__pz_link_texel(r, x, y);
        if ((y & 63) == 63 && dm__pz_step_report(r, 0.8f + 0.2f * (float)y / (float)r->H) != DM_OK) return DM_CANCELLED;
    }
    return DM_OK;
}

/* 7b. a seam neighbour whose step back (in its own axes) does not come back within one texel
   is replaced by the nearest texel of its chart, around it, from which it does; the
   quarter-turn rotation cannot follow a seam at 45 degrees exactly, so this keeps walks
   consistent. Two sweeps, in texel order (a third changed nothing on the test meshes). Then
   the step back is relinked where that helps, and what is left (a chart corner where no texel
   of the other chart walks back) gets the texel itself with a half turn, a mirror boundary, so
   that every walk comes back. */
static dm_result dm__pz_repair_links(dm__pz_run *r)
{
    dm_param *pm = r->pm;
    size_t i, n = r->n;
    int dir;
    for (i = 0; i < 2 * n; i++) {
        size_t id = i % n;
        if (pm->texel_triangle[id] == DM_NO_HIT) continue;
        for (dir = 0; dir < 4; dir++)
            dm__pz_fix_walk(pm, id, dir);
    }
    for (i = 0; i < n; i++) {
        if (pm->texel_triangle[i] == DM_NO_HIT) continue;
        for (dir = 0; dir < 4; dir++)
            dm__pz_relink_back(pm, i, dir);
    }
    for (i = 0; i < n; i++) {
        if (pm->texel_triangle[i] == DM_NO_HIT) continue;
        for (dir = 0; dir < 4; dir++)
            if (!dm__pz_link_ok(pm, i, dir)) {
                pm->nbr[4 * i + (size_t)dir] = (uint32_t)i;
                pm->nbr_rot[4 * i + (size_t)dir] = 2;
            }
    }
    return DM_OK;
}

/* 8. statistics: utilization, stretch and area ratios against the targets */
static dm_result dm__pz_statistics(dm__pz_run *r)
{
    dm_param *pm = r->pm;
    size_t covered = 0, ok = 0, i, t, nt = r->nt;
    double uv_total = 0.0, acc = 0.0, mx = 0.0, scale, total_area = r->total_area;
    double *cuv = r->cuv, *target = r->target;
    int c;
    for (i = 0; i < r->n; i++) covered += pm->texel_triangle[i] != DM_NO_HIT;
    pm->utilization = (float)((double)covered / (double)r->n);
    for (t = 0; t < nt; t++) {
        for (c = 0; c < 6; c++) cuv[6 * t + (size_t)c] = (double)pm->uv[6 * t + (size_t)c] * (c % 2 ? r->H : r->W);
        uv_total += dm__pz_cuv_area(cuv + 6 * t);
    }
    scale = sqrt(uv_total / total_area);
    for (t = 0; t < nt; t++) {
        double ratio = dm__pz_cuv_area(cuv + 6 * t) / target[t] / (uv_total / total_area);
        dm__pz_chart one;
        uint32_t lv[3] = {0, 1, 2};
        double xs[9], sg;
        ok += ratio >= 0.8 && ratio <= 1.25;
        if (!(r->sig_t[t] > 0.0)) continue; /* no surface to stretch (an input's degenerate triangle) */
        memset(&one, 0, sizeof one);
        for (c = 0; c < 3; c++) dm__load3(r->positions, r->indices[3 * t + (size_t)c], xs + 3 * c);
        one.nt = 1; one.nv = 3; one.lv = lv; one.x = xs; one.uv = cuv + 6 * t; one.target = target + t;
        dm__pz_stretch(&one, &sg);
        sg *= scale / sqrt(dm__pz_cuv_area(cuv + 6 * t) / target[t]);
        acc += target[t] * sg * sg;
        if (sg > mx) mx = sg;
    }
    pm->stretch_l2 = (float)sqrt(acc / total_area);
    pm->stretch_max = (float)mx;
    pm->area_ratio_ok = (float)((double)ok / (double)nt);
    return dm__pz_step_report(r, 1.0f);
}

DMDEF dm_param_options dm_param_default_options(void)
{
    dm_param_options o;
    memset(&o, 0, sizeof o);
    o.width = o.height = 1024;
    o.gutter = 4;
    o.max_chart_triangles = 96;
    o.max_chart_angle = 30.0f;
    o.stretch_iterations = 6;
    return o;
}

DMDEF dm_result dm_parameterize(const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, const dm_param_options *options, dm_param **out)
{
    dm__pz_run r;
    dm_result res;
    if (out) *out = NULL;
    if (!out) return DM_ERR_INVALID_ARGUMENT;
    memset(&r, 0, sizeof r);
    r.positions = positions;
    r.nv = vertex_count;
    r.indices = indices;
    r.nt = triangle_count;
    res = dm__pz_read_options(&r, options);
    if (res != DM_OK) return res;
    res = dm__pz_alloc_result(&r);
    if (res == DM_OK) res = dm__pz_find_charts(&r);    /* 1. adjacency and charts */
    if (res == DM_OK) res = dm__pz_targets(&r);        /* 2. target area of each triangle */
    if (res == DM_OK) res = dm__pz_bucket_charts(&r);  /* 3. triangles by chart */
    if (res == DM_OK) res = dm__pz_layout_charts(&r);  /* 4. flatten each chart, or split it */
    if (res == DM_OK) res = dm__pz_box_charts(&r);     /* 5a. each chart to its smallest box */
    if (res == DM_OK) res = dm__pz_pack_charts(&r);    /* 5b. pack the boxes into the map */
    if (res == DM_OK) res = dm__pz_rasterize(&r);      /* 6. texel -> triangle */
    if (res == DM_OK) res = dm__pz_link_texels(&r);    /* 7. texel neighbours, across seams */
    if (res == DM_OK) res = dm__pz_repair_links(&r);   /* 7b. walks across seams come back */
    if (res == DM_OK) res = dm__pz_statistics(&r);     /* 8. utilization, stretch, area ratios */
    dm__release(&r.sc);
    if (res != DM_OK) {
        dm_param_free(r.pm);
        return res;
    }
    *out = r.pm;
    return DM_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: displacement bake, push-pull fill, surface sample grid
   --------------------------------------------------------------------------------------------- */

/* A bilinear read of a width x height map at (u, v) in [0, 1]^2 (texel centres at half
   integers, clamped at the map's edges): its 4 texels (row by row) and their weights. */
static void dm__bilinear(int W, int H, double u, double v, size_t id[4], double w[4])
{
    double fx = u * W - 0.5, fy = v * H - 0.5, ix = floor(fx), iy = floor(fy), tx = fx - ix, ty = fy - iy;
    long x0 = (long)ix, y0 = (long)iy, xs[2], ys[2];
    int i;
    xs[0] = x0 < 0 ? 0 : x0 >= W ? W - 1 : x0;
    xs[1] = x0 + 1 < 0 ? 0 : x0 + 1 >= W ? W - 1 : x0 + 1;
    ys[0] = y0 < 0 ? 0 : y0 >= H ? H - 1 : y0;
    ys[1] = y0 + 1 < 0 ? 0 : y0 + 1 >= H ? H - 1 : y0 + 1;
    for (i = 0; i < 4; i++) {
        id[i] = (size_t)ys[i / 2] * (size_t)W + (size_t)xs[i % 2];
        w[i] = (i % 2 ? tx : 1.0 - tx) * (i / 2 ? ty : 1.0 - ty);
    }
}

DMDEF void dm_dispmap_free(dm_dispmap *m)
{
    dm_allocator a;
    if (!m) return;
    a = m->allocator;
    a.free(a.user, m->pos);
    a.free(a.user, m->nrm);
    a.free(a.user, m->disp);
    a.free(a.user, m->normal);
    a.free(a.user, m->area);
    a.free(a.user, m->valid);
    a.free(a.user, m->status);
    a.free(a.user, m);
}

/* Push-pull (Gortler et al. 1996): averages of the known texels down a pyramid, then every
   unknown texel takes its parent's value on the way back up. val has 4 channels per texel;
   known[i] says which texels are given. */
static int dm__pz_push_pull(dm__scratch *sc, float *val, const uint8_t *known, int W, int H)
{
    int levels = 0, w = W, h = H, l;
    float *lv[32];
    uint8_t *lk[32];
    int lw[32], lh[32];
    size_t i;
    lv[0] = val;
    lw[0] = W;
    lh[0] = H;
    lk[0] = (uint8_t *)dm__take(sc, (size_t)W * (size_t)H, 1);
    if (!lk[0]) return 0;
    for (i = 0; i < (size_t)W * (size_t)H; i++) lk[0][i] = known[i];
    while ((w > 1 || h > 1) && levels < 30) {
        int nw = (w + 1) / 2, nh = (h + 1) / 2, x, y;
        levels++;
        lv[levels] = (float *)dm__take(sc, 4 * (size_t)nw * (size_t)nh, sizeof(float));
        lk[levels] = (uint8_t *)dm__take(sc, (size_t)nw * (size_t)nh, 1);
        if (!lv[levels] || !lk[levels]) return 0;
        lw[levels] = nw;
        lh[levels] = nh;
        for (y = 0; y < nh; y++)
            for (x = 0; x < nw; x++) {
                double s[4] = {0, 0, 0, 0};
                int cnt = 0, dx, dy, k;
                for (dy = 0; dy < 2; dy++)
                    for (dx = 0; dx < 2; dx++) {
                        int sx = 2 * x + dx, sy = 2 * y + dy;
                        size_t id;
                        if (sx >= w || sy >= h) continue;
                        id = (size_t)sy * (size_t)w + (size_t)sx;
                        if (!lk[levels - 1][id]) continue;
                        for (k = 0; k < 4; k++) s[k] += lv[levels - 1][4 * id + (size_t)k];
                        cnt++;
                    }
                i = (size_t)y * (size_t)nw + (size_t)x;
                lk[levels][i] = cnt > 0;
                for (k = 0; k < 4; k++) lv[levels][4 * i + (size_t)k] = cnt > 0 ? (float)(s[k] / cnt) : 0.0f;
            }
        w = nw;
        h = nh;
    }
    for (l = levels - 1; l >= 0; l--) {
        int x, y, k;
        for (y = 0; y < lh[l]; y++)
            for (x = 0; x < lw[l]; x++) {
                size_t id = (size_t)y * (size_t)lw[l] + (size_t)x, pid = (size_t)(y / 2) * (size_t)lw[l + 1] + (size_t)(x / 2);
                if (lk[l][id]) continue;
                for (k = 0; k < 4; k++) lv[l][4 * id + (size_t)k] = lv[l + 1][4 * pid + (size_t)k];
                lk[l][id] = lk[l + 1][pid];
            }
    }
    return 1;
}

/* dm_bake's working state: the two meshes, the options, the map being filled, the search
   structure over the original and the temporaries (in sc, freed together on the one exit path) */
typedef struct dm__bk_run {
    const dm_param *param;
    const float *bpos, *opos;                 /* base and original positions */
    const uint32_t *bidx, *oidx;
    size_t bnv, bnt, onv, ont;
    dm_bake_options o;
    dm__scratch sc;
    dm_dispmap *m;
    dm_bvh *bvh;
    float *bnrm, *onrm, *fill;                /* vertex normals of both meshes; push-pull values */
    double *acc;
    float maxd;                               /* search distance */
} dm__bk_run;

/* 1 if every x[i] is finite and |x[i]| <= lim */
static int dm__finite_within(const float *x, size_t n, float lim)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!(fabsf(x[i]) <= lim)) return 0;
    return 1;
}

/* The public dm_param arrays, as dm_bake and dm_reconstruct read them: present, every index in
   range (or the documented none), every coordinate finite and in the map. */
static dm_result dm__check_param(const dm_param *p, size_t base_triangle_count)
{
    size_t n, i, nt = p->triangle_count;
    if (p->triangle_count != base_triangle_count) return DM_ERR_INVALID_ARGUMENT;
    if (p->width < 1 || p->height < 1 || p->width > 16384 || p->height > 16384) return DM_ERR_BAD_MAP;
    n = (size_t)p->width * (size_t)p->height;
    if (!p->uv || !p->chart || !p->twin || !p->texel_triangle || !p->texel_bary || !p->nbr || !p->nbr_rot)
        return DM_ERR_BAD_MAP;
    if (!dm__finite_within(p->uv, 6 * nt, 2.0f) || !dm__finite_within(p->texel_bary, 2 * n, 1e3f)) return DM_ERR_BAD_MAP;
    for (i = 0; i < nt; i++)
        if (p->chart[i] >= p->chart_count) return DM_ERR_BAD_MAP;
    for (i = 0; i < 3 * nt; i++)
        if (p->twin[i] >= nt && p->twin[i] != DM_NO_HIT) return DM_ERR_BAD_MAP;
    for (i = 0; i < n; i++)
        if (p->texel_triangle[i] >= nt && p->texel_triangle[i] != DM_NO_HIT) return DM_ERR_BAD_MAP;
    for (i = 0; i < 4 * n; i++)
        if ((p->nbr[i] >= n && p->nbr[i] != UINT32_MAX) || p->nbr_rot[i] > 3) return DM_ERR_BAD_MAP;
    return DM_OK;
}

/* The dm_dispmap arrays dm_reconstruct reads: present, of the dm_param's size, finite, and the
   depths within the coordinates' limit. */
static dm_result dm__check_map(const dm_dispmap *m, const dm_param *p)
{
    size_t n;
    if (m->width != p->width || m->height != p->height) return DM_ERR_INVALID_ARGUMENT;
    n = (size_t)m->width * (size_t)m->height;
    if (!m->pos || !m->nrm || !m->disp || !m->normal || !m->valid || !m->status) return DM_ERR_BAD_MAP;
    if (!dm__finite_within(m->disp, n, 1e18f) || !dm__finite_within(m->nrm, 3 * n, 2.0f) ||
        !dm__finite_within(m->normal, 3 * n, 2.0f) || !dm__finite_within(m->pos, 3 * n, 1e18f))
        return DM_ERR_BAD_MAP;
    return DM_OK;
}

/* the options and both meshes checked, the parameterization matched to the base */
static dm_result dm__bk_check(dm__bk_run *r, const dm_bake_options *options)
{
    dm_result res;
    memset(&r->o, 0, sizeof r->o);
    if (options) r->o = *options;
    if (!(r->o.max_distance >= 0.0f) || r->o.max_distance > 1e30f) return DM_ERR_INVALID_ARGUMENT;
    res = dm__check_mesh(r->bpos, r->bnv, r->bidx, r->bnt);
    if (res != DM_OK) return res;
    res = dm__check_mesh(r->opos, r->onv, r->oidx, r->ont);
    if (res != DM_OK) return res;
    return dm__check_param(r->param, r->bnt);
}

/* the map (its arrays owned by it) and the temporaries */
static dm_result dm__bk_alloc(dm__bk_run *r)
{
    dm__scratch *sc = &r->sc;
    int W = r->param->width, H = r->param->height;
    size_t n = (size_t)W * (size_t)H;
    dm_dispmap *m;
    sc->a = dm__resolve_allocator(r->o.allocator);
    m = r->m = (dm_dispmap *)sc->a.alloc(sc->a.user, sizeof(dm_dispmap));
    if (!m) return DM_ERR_OUT_OF_MEMORY;
    memset(m, 0, sizeof *m);
    m->allocator = sc->a;
    m->width = W;
    m->height = H;
    m->pos = (float *)dm__alloc_array(&sc->a, 3 * n, sizeof(float), &sc->overflow);
    m->nrm = (float *)dm__alloc_array(&sc->a, 3 * n, sizeof(float), &sc->overflow);
    m->disp = (float *)dm__alloc_array(&sc->a, n, sizeof(float), &sc->overflow);
    m->normal = (float *)dm__alloc_array(&sc->a, 3 * n, sizeof(float), &sc->overflow);
    m->area = (float *)dm__alloc_array(&sc->a, n, sizeof(float), &sc->overflow);
    m->valid = (uint8_t *)dm__alloc_array(&sc->a, n, 1, &sc->overflow);
    m->status = (uint8_t *)dm__alloc_array(&sc->a, n, 1, &sc->overflow);
    m->nbr = r->param->nbr;
    m->nbr_rot = r->param->nbr_rot;
    r->bnrm = (float *)dm__take(sc, 3 * r->bnv, sizeof(float));
    r->onrm = (float *)dm__take(sc, 3 * r->onv, sizeof(float));
    r->acc = (double *)dm__take(sc, 3 * (r->bnv > r->onv ? r->bnv : r->onv), sizeof(double));
    r->fill = (float *)dm__take(sc, 4 * n, sizeof(float));
    if (!m->pos || !m->nrm || !m->disp || !m->normal || !m->area || !m->valid || !m->status || !r->bnrm ||
        !r->onrm || !r->acc || !r->fill)
        return dm__scratch_fail(sc);
    return DM_OK;
}

/* vertex normals of both meshes, the search distance (default 5% of the original's box
   diagonal) and the BVH over the original */
static dm_result dm__bk_prepare(dm__bk_run *r)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, diag;
    dm_bvh_options bo;
    size_t t;
    dm_result res = dm__base_normals(&r->sc, r->bpos, r->bnv, r->bidx, r->bnt, r->acc, r->bnrm);
    if (res != DM_OK) return res;
    dm__vertex_normals(r->opos, r->onv, r->oidx, r->ont, r->acc, r->onrm);
    for (t = 0; t < 3 * r->ont; t++) {
        int k;
        for (k = 0; k < 3; k++) {
            double v = r->opos[3 * (size_t)r->oidx[t] + (size_t)k];
            if (v < lo[k]) lo[k] = v;
            if (v > hi[k]) hi[k] = v;
        }
    }
    diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    r->maxd = r->o.max_distance > 0.0f ? r->o.max_distance : (float)(0.05 * diag);
    r->m->max_distance = r->maxd;
    memset(&bo, 0, sizeof bo);
    bo.allocator = &r->sc.a;
    return dm_bvh_build(r->opos, r->onv, r->oidx, r->ont, &bo, &r->bvh);
}

/* base triangle tt's area in the map, in texels */
static double dm__bk_uv_area(const dm_param *param, uint32_t tt)
{
    const float *uv = param->uv + 6 * (size_t)tt;
    return 0.5 * fabs(((double)uv[2] - uv[0]) * ((double)uv[5] - uv[1]) - ((double)uv[4] - uv[0]) * ((double)uv[3] - uv[1])) *
           (double)param->width * (double)param->height;
}

/* the world size of base triangle tt's texels, from its face normal fnv (twice its area) */
static double dm__bk_texel_size(const dm_param *param, uint32_t tt, const double fnv[3])
{
    double uva = dm__bk_uv_area(param, tt);
    return uva > 0.0 ? sqrt(0.5 * dm__len3(fnv) / uva) : 0.0;
}

/* the point of base triangle tt at barycentrics (bu, bv) into pos, its unit interpolated normal
   into nrm (the face's where the interpolated one vanishes) and the face's normal (twice the
   area) into fnv. (bu, bv) outside the triangle (a border texel's): the point is the triangle's
   plane extended, the normal the one at the nearest point of the triangle. Returns the normal's
   length before normalizing (0: no direction to search). */
static double dm__bk_point(const dm__bk_run *r, uint32_t tt, double bu, double bv, float pos[3], float nrm[3],
                           double fnv[3])
{
    const uint32_t *bi = r->bidx + 3 * (size_t)tt;
    double p[3][3], nv[3], b0, len, e1[3], e2[3], nu = bu, nw = bv, nb;
    int k, c;
    b0 = 1.0 - bu - bv;
    if (nu < 0.0) nu = 0.0;
    if (nw < 0.0) nw = 0.0;
    if (nu + nw > 1.0) { double sm = nu + nw; nu /= sm; nw /= sm; }
    nb = 1.0 - nu - nw;
    for (c = 0; c < 3; c++) dm__load3(r->bpos, bi[c], p[c]);
    for (k = 0; k < 3; k++) {
        const float *n0 = r->bnrm + 3 * (size_t)bi[0];
        const float *n1 = r->bnrm + 3 * (size_t)bi[1];
        const float *n2 = r->bnrm + 3 * (size_t)bi[2];
        pos[k] = (float)(b0 * p[0][k] + bu * p[1][k] + bv * p[2][k]);
        nv[k] = nb * n0[k] + nu * n1[k] + nw * n2[k];
    }
    dm__sub3(p[1], p[0], e1);
    dm__sub3(p[2], p[0], e2);
    dm__cross3(e1, e2, fnv);
    len = dm__len3(nv);
    if (!(len > 1e-12)) { for (k = 0; k < 3; k++) nv[k] = fnv[k]; len = dm__len3(nv); }
    for (k = 0; k < 3; k++) nrm[k] = len > 0.0 ? (float)(nv[k] / len) : 0.0f;
    return len;
}

/* texel id at barycentrics (bu, bv) of base triangle tt: its point and normal (dm__bk_point)
   and, when area is set, the surface area it stands for (3D area over the UV area in texels; 0
   otherwise); returns the normal's length before normalizing */
static double dm__bk_base_point(dm__bk_run *r, size_t id, uint32_t tt, double bu, double bv, int area)
{
    dm_dispmap *m = r->m;
    double fnv[3], uva, len = dm__bk_point(r, tt, bu, bv, m->pos + 3 * id, m->nrm + 3 * id, fnv);
    uva = dm__bk_uv_area(r->param, tt);
    m->area[id] = area && uva > 0.0 ? (float)(0.5 * dm__len3(fnv) / uva) : 0.0f;
    return len;
}

/* the ray from point pos along -nrm, by the rule of base triangle tt (inward first where asked,
   unless that hit is a back face; else the whole line): 1 and its hit, or 0 */
static int dm__bk_trace(const dm__bk_run *r, const float pos[3], const float nrm[3], uint32_t tt, dm_hit *hit)
{
    float maxd = r->maxd;
    dm_ray ray;
    int got = 0, in_t, k;
    for (k = 0; k < 3; k++) {
        ray.org[k] = pos[k];
        ray.dir[k] = -nrm[k];
    }
    in_t = r->o.inward && !(r->o.both_ways && r->o.both_ways[tt]);
    ray.tmin = in_t ? -0.1f * maxd : -maxd;
    ray.tmax = maxd;
    if (in_t) got = dm_bvh_intersect(r->bvh, &ray, hit);
    if (got) { /* a back face first: the ray starts inside the original, where the base does not
                  enclose it (a thin part's far side lies ahead); the nearest crossing either way */
        double fn[3];
        dm__face_normal(r->opos, r->oidx, hit->triangle, fn);
        if (fn[0] * ray.dir[0] + fn[1] * ray.dir[1] + fn[2] * ray.dir[2] > 0.0) got = 0;
    }
    if (!got) {
        ray.tmin = -maxd;
        got = dm_bvh_intersect_line(r->bvh, &ray, hit);
    }
    return got;
}

/* texel id's ray (dm__bk_trace): the depth and the original's normal at the hit, or a miss (a
   border texel that misses stays EMPTY); returns the original's triangle hit, or DM_NO_HIT */
static uint32_t dm__bk_shoot(dm__bk_run *r, size_t id, uint32_t tt, double len, int border)
{
    dm_dispmap *m = r->m;
    dm_hit hit;
    int k;
    if (len > 0.0 && dm__bk_trace(r, m->pos + 3 * id, m->nrm + 3 * id, tt, &hit)) {
        const uint32_t *oi = r->oidx + 3 * (size_t)hit.triangle;
        const float *onrm = r->onrm;
        double hn[3], hl, w0 = 1.0 - (double)hit.u - (double)hit.v;
        for (k = 0; k < 3; k++)
            hn[k] = w0 * onrm[3 * (size_t)oi[0] + (size_t)k] + hit.u * onrm[3 * (size_t)oi[1] + (size_t)k] +
                    hit.v * onrm[3 * (size_t)oi[2] + (size_t)k];
        hl = dm__len3(hn);
        if (!(hl > 1e-12)) {
            dm__face_normal(r->opos, r->oidx, hit.triangle, hn);
            hl = dm__len3(hn);
        }
        m->disp[id] = hit.t;
        for (k = 0; k < 3; k++) m->normal[3 * id + (size_t)k] = hl > 0.0 ? (float)(hn[k] / hl) : 0.0f;
        if (border) {
            m->status[id] = DM_TEXEL_BORDER;
            m->border_count++;
            return hit.triangle;
        }
        m->status[id] = DM_TEXEL_HIT;
        m->valid[id] = 1;
        m->hit_count++;
        return hit.triangle;
    }
    if (!border) {
        m->status[id] = DM_TEXEL_MISS;
        m->miss_count++;
    }
    return DM_NO_HIT;
}

/* every texel: EMPTY off the charts, else its base point and its ray */
static dm_result dm__bk_cast(dm__bk_run *r)
{
    const dm_param *param = r->param;
    dm_dispmap *m = r->m;
    int W = param->width, H = param->height, y, x, k;
    for (y = 0; y < H; y++) {
        for (x = 0; x < W; x++) {
            size_t id = (size_t)y * (size_t)W + (size_t)x;
            uint32_t tt = param->texel_triangle[id];
            m->valid[id] = 0;
            if (tt == DM_NO_HIT || tt >= r->bnt) {
                m->status[id] = DM_TEXEL_EMPTY;
                for (k = 0; k < 3; k++) m->pos[3 * id + (size_t)k] = m->nrm[3 * id + (size_t)k] = 0.0f;
                m->area[id] = 0.0f;
                continue;
            }
            (void)dm__bk_shoot(r, id, tt, dm__bk_base_point(r, id, tt, param->texel_bary[2 * id], param->texel_bary[2 * id + 1], 1), 0);
        }
        if ((y & 15) == 15 && r->o.progress && r->o.progress(r->o.progress_user, 0.95f * (float)(y + 1) / (float)H))
            return DM_CANCELLED;
    }
    return DM_OK;
}

/* distance from point c to the segment a b */
static double dm__bk_segment_distance(const double a[2], const double b[2], const double c[2])
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy, s = 0.0, ex, ey;
    if (l2 > 0.0) s = ((c[0] - a[0]) * dx + (c[1] - a[1]) * dy) / l2;
    s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
    ex = a[0] + s * dx - c[0];
    ey = a[1] + s * dy - c[1];
    return sqrt(ex * ex + ey * ey);
}

/* the empty texels near base triangle t in the map: each takes t (and its barycentrics, outside
   the triangle) when t is the nearest triangle whose uv triangle its square of half-side
   DM__BORDER texels meets; ties go to the lower triangle */
#define DM__BORDER 2
static void dm__bk_border_triangle(const dm_param *pm, size_t t, float *best, uint32_t *tri, float *bary)
{
    int W = pm->width;
    double P[3][2], d;
    long box[4], x0, x1, y0, y1, xx, yy;
    if (!dm__uv_texel_box(pm, t, DM__BORDER, P, &d, box)) return;
    x0 = box[0]; y0 = box[1]; x1 = box[2]; y1 = box[3];
    for (yy = y0; yy <= y1; yy++)
        for (xx = x0; xx <= x1; xx++) {
            size_t id = (size_t)yy * (size_t)W + (size_t)xx;
            double cc[2], dist, cx, cy;
            if (pm->texel_triangle[id] != DM_NO_HIT) continue;
            cc[0] = xx + 0.5;
            cc[1] = yy + 0.5;
            if (!dm__square_meets((const double(*)[2])P, cc, DM__BORDER)) continue;
            dist = fmin(dm__bk_segment_distance(P[0], P[1], cc),
                        fmin(dm__bk_segment_distance(P[1], P[2], cc), dm__bk_segment_distance(P[2], P[0], cc)));
            if (!(dist < best[id])) continue;
            cx = cc[0] - P[0][0];
            cy = cc[1] - P[0][1];
            best[id] = (float)dist;
            tri[id] = (uint32_t)t;
            bary[2 * id] = (float)((cx * (P[2][1] - P[0][1]) - cy * (P[2][0] - P[0][0])) / d);
            bary[2 * id + 1] = (float)(((P[1][0] - P[0][0]) * cy - (P[1][1] - P[0][1]) * cx) / d);
        }
}

/* Hits that do not belong to their neighbourhood: a hit texel whose depth lies more than
   DM__BK_OUTLIER texel sizes beyond more than half of its hit neighbours in the chart, all on one
   side (the 24 within two texels, at least 5 of them; at a chart's edge a group of slipped rays
   fills a 3 x 3 window), had its ray slip past a thin part of the original to another sheet; it
   becomes a MISS (filled from its neighbours). Decided on the depths as cast, so the order does
   not matter. */
#define DM__BK_OUTLIER 8.0
static dm_result dm__bk_outliers(dm__bk_run *r)
{
    const dm_param *param = r->param;
    dm_dispmap *m = r->m;
    int W = param->width, H = param->height, x, y;
    size_t n = (size_t)W * (size_t)H;
    uint8_t *odd = (uint8_t *)dm__take(&r->sc, n, 1);
    if (!odd) return dm__scratch_fail(&r->sc);
    memset(odd, 0, n);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            size_t id = (size_t)y * (size_t)W + (size_t)x;
            double d, tol;
            int dx, dy, k = 0, below = 0, above = 0;
            uint32_t chart;
            if (!m->valid[id]) continue;
            chart = param->chart[param->texel_triangle[id]];
            d = m->disp[id];
            tol = DM__BK_OUTLIER * sqrt((double)m->area[id]);
            for (dy = -2; dy <= 2; dy++)
                for (dx = -2; dx <= 2; dx++) {
                    size_t j;
                    if ((dx == 0 && dy == 0) || x + dx < 0 || y + dy < 0 || x + dx >= W || y + dy >= H) continue;
                    j = (size_t)(y + dy) * (size_t)W + (size_t)(x + dx);
                    if (!m->valid[j] || param->chart[param->texel_triangle[j]] != chart) continue;
                    k++;
                    below += m->disp[j] < d - tol;
                    above += m->disp[j] > d + tol;
                }
            odd[id] = k >= 5 && (2 * below > k || 2 * above > k);
        }
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            size_t id = (size_t)y * (size_t)W + (size_t)x;
            if (!odd[id]) continue;
            m->valid[id] = 0;
            m->status[id] = DM_TEXEL_MISS;
            m->hit_count--;
            m->miss_count++;
        }
    return DM_OK;
}

/* the linear extension of chart's field at texel id: a least-squares plane through the chart's
   hits within DM__BORDER + 1 texels (weighted toward the nearest) evaluated at the texel, for the
   depth and the normal; 0 when those hits do not span a plane */
static int dm__bk_chart_extension(const dm__bk_run *r, size_t id, uint32_t chart, double val[4])
{
    const dm_param *param = r->param;
    const dm_dispmap *m = r->m;
    int W = param->width, H = param->height, x = (int)(id % (size_t)W), y = (int)(id / (size_t)W), R = DM__BORDER + 1, dx, dy, k;
    double A[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, b[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, det;
    for (dy = -R; dy <= R; dy++)
        for (dx = -R; dx <= R; dx++) {
            size_t j;
            double w, f[3], v[4];
            int a, c;
            if (x + dx < 0 || y + dy < 0 || x + dx >= W || y + dy >= H) continue;
            j = (size_t)(y + dy) * (size_t)W + (size_t)(x + dx);
            if (!m->valid[j] || param->chart[param->texel_triangle[j]] != chart) continue;
            w = 1.0 / (0.5 + dx * dx + dy * dy);
            f[0] = 1.0; f[1] = dx; f[2] = dy;
            v[0] = m->disp[j]; v[1] = m->normal[3 * j]; v[2] = m->normal[3 * j + 1]; v[3] = m->normal[3 * j + 2];
            for (a = 0; a < 3; a++) {
                for (c = 0; c < 3; c++) A[a][c] += w * f[a] * f[c];
                for (k = 0; k < 4; k++) b[k][a] += w * f[a] * v[k];
            }
        }
    det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
          A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    if (!(A[0][0] > 0.0) || !(det > 1e-3 * A[0][0] * A[0][0] * A[0][0])) return 0;
    for (k = 0; k < 4; k++) /* the plane's constant term, by Cramer's rule */
        val[k] = (b[k][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (b[k][1] * A[2][2] - A[1][2] * b[k][2]) +
                  A[0][2] * (b[k][1] * A[2][1] - A[1][1] * b[k][2])) / det;
    return 1;
}

/* border texel id of base triangle tt at (bu, bv): the ray from the triangle's plane extended,
   unless it misses, lands on a face of the original more than 60 degrees from the base triangle
   (the original has a crease along the chart's edge: the ray reached the face beyond it) or lands
   DM__BK_OUTLIER texel sizes off the chart's own field extended linearly (it slipped past a thin
   part to another sheet): then that extension is what a filter at the edge must read */
#define DM__BORDER_CREASE_COS 0.5
static void dm__bk_border_texel(dm__bk_run *r, size_t id, uint32_t tt, double bu, double bv)
{
    dm_dispmap *m = r->m;
    double ext[4], l, fo[3], fb[3];
    uint32_t hit = dm__bk_shoot(r, id, tt, dm__bk_base_point(r, id, tt, bu, bv, 0), 1);
    int k, have = 0;
    if (hit != DM_NO_HIT) {
        dm__face_normal(r->opos, r->oidx, hit, fo);
        dm__face_normal(r->bpos, r->bidx, tt, fb);
        if (dm__dot3(fo, fb) >= DM__BORDER_CREASE_COS * dm__len3(fo) * dm__len3(fb)) {
            /* unless it slipped to another sheet (the hits' outlier rule, against the extension) */
            double texel = dm__bk_texel_size(r->param, tt, fb);
            have = dm__bk_chart_extension(r, id, r->param->chart[tt], ext);
            if (!have || fabs((double)m->disp[id] - ext[0]) <= DM__BK_OUTLIER * texel) return;
        }
    }
    if (!have && !dm__bk_chart_extension(r, id, r->param->chart[tt], ext)) return;
    l = sqrt(ext[1] * ext[1] + ext[2] * ext[2] + ext[3] * ext[3]);
    if (!(l > 1e-12)) return;
    if (m->status[id] != DM_TEXEL_BORDER) m->border_count++;
    m->status[id] = DM_TEXEL_BORDER;
    m->disp[id] = (float)ext[0];
    for (k = 0; k < 3; k++) m->normal[3 * id + (size_t)k] = (float)(ext[1 + k] / l);
}

/* the charts' borders: each empty texel within DM__BORDER texels (a square's half-side) of a
   chart is baked from the nearest base triangle's plane extended, so that bilinear filtering
   at any point of a chart, and at the next mip level, reads real samples */
static dm_result dm__bk_border(dm__bk_run *r)
{
    const dm_param *param = r->param;
    size_t n = (size_t)param->width * (size_t)param->height, t, i;
    float *best = (float *)dm__take(&r->sc, n, sizeof(float));
    uint32_t *tri = (uint32_t *)dm__take(&r->sc, n, sizeof(uint32_t));
    float *bary = (float *)dm__take(&r->sc, 2 * n, sizeof(float));
    if (!best || !tri || !bary) return dm__scratch_fail(&r->sc);
    for (i = 0; i < n; i++) {
        best[i] = INFINITY;
        tri[i] = DM_NO_HIT;
    }
    for (t = 0; t < r->bnt; t++) dm__bk_border_triangle(param, t, best, tri, bary);
    for (i = 0; i < n; i++)
        if (tri[i] != DM_NO_HIT) dm__bk_border_texel(r, i, tri[i], bary[2 * i], bary[2 * i + 1]);
    if (r->o.progress && r->o.progress(r->o.progress_user, 0.97f)) return DM_CANCELLED;
    return DM_OK;
}

/* The seams. The charts on a seam read the map at the same edge points, each from its own
   texels, and the reconstruction averages what they read. Where the depth bends within the last
   texel before the edge, each chart's border texels (its field extended) continue its own side,
   the reads disagree and the average lies off the surface. So the border texels are fitted: at
   points along every chart boundary edge, DM__BK_SEAM_STEP texels apart (its ends included), the
   bilinear read should give the depth of the ray shot from that edge point, the same ray for both
   sides. Least squares over the border texels (the hits stay), each held to its rule's value with
   weight DM__BK_SEAM_HOLD; Gauss-Seidel sweeps in texel order. A point is left out where its ray
   slipped (DM__BK_OUTLIER texel sizes off the read) or lands on a face turned more than 75 degrees
   (DM__BK_SEAM_CREASE_COS) from the triangle: on a crease of the original along the edge, each
   chart keeps its own face up to the edge (a bilinear read cannot have both that face and the
   edge's depth). The border rule's 60 degrees would leave out more points beside sharp base edges
   of smooth surfaces, where the fit helps. A texel moves at most DM__BK_SEAM_REACH texel sizes
   from its rule's value (where the base's normals swing, the edge rays disagree with the hits). */
#define DM__BK_SEAM_STEP 0.5
#define DM__BK_SEAM_HOLD 0.05
#define DM__BK_SEAM_SWEEPS 16
#define DM__BK_SEAM_CREASE_COS 0.26
#define DM__BK_SEAM_REACH 2.0
#define DM__BK_SEAM_MAX ((size_t)UINT32_MAX / 4 - 1) /* points (their texel slots count in 32 bits) */

typedef struct dm__bk_edge_sample {
    size_t id[4]; /* the texels the read uses */
    double w[4];  /* and their bilinear weights */
    double depth; /* the edge point's own ray */
    double texel; /* the world size of its triangle's texels */
} dm__bk_edge_sample;

/* the samples along chart boundary edges into *out (count *n); each reads a border texel, and
   only texels already baked (hits and border texels) */
static dm_result dm__bk_edge_samples(dm__bk_run *r, dm__bk_edge_sample **out, size_t *n)
{
    const dm_param *pm = r->param;
    const dm_dispmap *m = r->m;
    size_t t, cap = 0, ns = 0;
    int c, pass;
    dm__bk_edge_sample *smp = NULL;
    for (pass = 0; pass < 2; pass++) {
        for (t = 0; t < r->bnt; t++)
            for (c = 0; c < 3; c++) {
                const float *uv = pm->uv + 6 * t;
                uint32_t tw = pm->twin[3 * t + (size_t)c];
                int c1 = (c + 1) % 3;
                double du = (uv[2 * c1] - uv[2 * c]) * pm->width, dv = (uv[2 * c1 + 1] - uv[2 * c + 1]) * pm->height;
                size_t j, cnt;
                if (tw != DM_NO_HIT && tw < r->bnt && pm->chart[tw] == pm->chart[t]) continue; /* inside a chart */
                cnt = (size_t)ceil(sqrt(du * du + dv * dv) / DM__BK_SEAM_STEP) + 1;
                if (cnt > 1u << 20) cnt = 1u << 20;
                if (pass == 0) { cap += cnt; continue; }
                for (j = 0; j < cnt && ns < DM__BK_SEAM_MAX; j++) {
                    double sv = cnt > 1 ? (double)j / (double)(cnt - 1) : 0.5, w[3] = {0.0, 0.0, 0.0}, fnv[3];
                    float pos[3], nrm[3];
                    dm__bk_edge_sample *e = smp + ns;
                    dm_hit hit;
                    int i, border = 0, known = 1;
                    w[c] = 1.0 - sv;
                    w[c1] = sv;
                    if (!(dm__bk_point(r, (uint32_t)t, w[1], w[2], pos, nrm, fnv) > 0.0) ||
                        !dm__bk_trace(r, pos, nrm, (uint32_t)t, &hit))
                        continue;
                    dm__bilinear(pm->width, pm->height, w[0] * uv[0] + w[1] * uv[2] + w[2] * uv[4],
                                 w[0] * uv[1] + w[1] * uv[3] + w[2] * uv[5], e->id, e->w);
                    for (i = 0; i < 4; i++) {
                        border |= m->status[e->id[i]] == DM_TEXEL_BORDER && e->w[i] > 0.0;
                        known &= m->valid[e->id[i]] || m->status[e->id[i]] == DM_TEXEL_BORDER || !(e->w[i] > 0.0);
                    }
                    if (!border || !known) continue;
                    { /* a ray that slipped past a thin part to another sheet (as dm__bk_border_texel) */
                        double rd = 0.0, texel = dm__bk_texel_size(pm, (uint32_t)t, fnv);
                        for (i = 0; i < 4; i++) rd += e->w[i] * m->disp[e->id[i]];
                        if (fabs((double)hit.t - rd) > DM__BK_OUTLIER * texel) continue;
                        e->texel = texel;
                    }
                    { /* on a face turned from the triangle (a crease along the edge): left as it is */
                        double fo[3];
                        dm__face_normal(r->opos, r->oidx, hit.triangle, fo);
                        if (dm__dot3(fo, fnv) < DM__BK_SEAM_CREASE_COS * dm__len3(fo) * dm__len3(fnv)) continue;
                    }
                    e->depth = hit.t;
                    ns++;
                }
            }
        if (pass == 0) {
            smp = (dm__bk_edge_sample *)dm__take(&r->sc, cap ? cap : 1, sizeof(dm__bk_edge_sample));
            if (!smp) return dm__scratch_fail(&r->sc);
        }
    }
    *out = smp;
    *n = ns;
    return DM_OK;
}

static dm_result dm__bk_seams(dm__bk_run *r)
{
    dm_dispmap *m = r->m;
    size_t n = (size_t)m->width * (size_t)m->height, ns = 0, na = 0, s, i;
    dm__bk_edge_sample *smp;
    uint32_t *first, *slot, *act;
    float *hold, *lim;
    int sweep, k;
    dm_result res = dm__bk_edge_samples(r, &smp, &ns);
    if (res != DM_OK) return res;
    first = (uint32_t *)dm__take(&r->sc, n + 1, sizeof(uint32_t));
    slot = (uint32_t *)dm__take(&r->sc, 4 * ns + 1, sizeof(uint32_t));
    if (!first || !slot) return dm__scratch_fail(&r->sc);
    /* each border texel's places in the samples' reads (4 x sample + place), in sample order */
    memset(first, 0, (n + 1) * sizeof(uint32_t));
    for (s = 0; s < ns; s++)
        for (k = 0; k < 4; k++)
            if (m->status[smp[s].id[k]] == DM_TEXEL_BORDER && smp[s].w[k] > 0.0) first[smp[s].id[k] + 1]++;
    for (i = 0; i < n; i++) {
        na += first[i + 1] > 0;
        first[i + 1] += first[i];
    }
    for (s = 0; s < ns; s++)
        for (k = 0; k < 4; k++)
            if (m->status[smp[s].id[k]] == DM_TEXEL_BORDER && smp[s].w[k] > 0.0)
                slot[first[smp[s].id[k]]++] = (uint32_t)(4 * s + (size_t)k);
    for (i = n; i > 0; i--) first[i] = first[i - 1];
    first[0] = 0;
    act = (uint32_t *)dm__take(&r->sc, na + 1, sizeof(uint32_t));
    hold = (float *)dm__take(&r->sc, na + 1, sizeof(float));
    lim = (float *)dm__take(&r->sc, na + 1, sizeof(float));
    if (!act || !hold || !lim) return dm__scratch_fail(&r->sc);
    for (i = 0, na = 0; i < n; i++) /* the texels to fit, each held to its rule's value, and how far it may go */
        if (first[i] < first[i + 1]) {
            uint32_t q;
            hold[na] = m->disp[i];
            lim[na] = FLT_MAX;
            for (q = first[i]; q < first[i + 1]; q++)
                if (DM__BK_SEAM_REACH * smp[slot[q] / 4].texel < lim[na])
                    lim[na] = (float)(DM__BK_SEAM_REACH * smp[slot[q] / 4].texel);
            act[na++] = (uint32_t)i;
        }
    for (sweep = 0; sweep < DM__BK_SEAM_SWEEPS; sweep++)
        for (i = 0; i < na; i++) {
            double num = DM__BK_SEAM_HOLD * hold[i], den = DM__BK_SEAM_HOLD;
            uint32_t q;
            for (q = first[act[i]]; q < first[act[i] + 1]; q++) {
                const dm__bk_edge_sample *e = smp + slot[q] / 4;
                int own = (int)(slot[q] % 4), j;
                double rest = e->depth; /* what this texel's share of the read should be */
                for (j = 0; j < 4; j++)
                    if (j != own) rest -= e->w[j] * m->disp[e->id[j]];
                num += e->w[own] * rest;
                den += e->w[own] * e->w[own];
            }
            num /= den;
            if (num > hold[i] + lim[i]) num = hold[i] + lim[i];
            if (num < hold[i] - lim[i]) num = hold[i] - lim[i];
            m->disp[act[i]] = (float)num;
        }
    if (r->o.progress && r->o.progress(r->o.progress_user, 0.98f)) return DM_CANCELLED;
    return DM_OK;
}

/* push-pull fill of everything that is not a hit or a border texel, for filtering only */
static dm_result dm__bk_fill(dm__bk_run *r)
{
    dm_dispmap *m = r->m;
    float *fill = r->fill;
    size_t i, n = (size_t)m->width * (size_t)m->height;
    uint8_t *known = (uint8_t *)dm__take(&r->sc, n, 1);
    if (!known) return dm__scratch_fail(&r->sc);
    for (i = 0; i < n; i++) {
        known[i] = m->valid[i] || m->status[i] == DM_TEXEL_BORDER;
        fill[4 * i] = known[i] ? m->disp[i] : 0.0f;
        fill[4 * i + 1] = known[i] ? m->normal[3 * i] : 0.0f;
        fill[4 * i + 2] = known[i] ? m->normal[3 * i + 1] : 0.0f;
        fill[4 * i + 3] = known[i] ? m->normal[3 * i + 2] : 0.0f;
    }
    if (!dm__pz_push_pull(&r->sc, fill, known, m->width, m->height)) return dm__scratch_fail(&r->sc);
    for (i = 0; i < n; i++) {
        double l;
        if (known[i]) continue;
        m->disp[i] = fill[4 * i];
        l = sqrt((double)fill[4 * i + 1] * fill[4 * i + 1] + (double)fill[4 * i + 2] * fill[4 * i + 2] +
                 (double)fill[4 * i + 3] * fill[4 * i + 3]);
        if (l > 1e-12) {
            m->normal[3 * i] = (float)(fill[4 * i + 1] / l);
            m->normal[3 * i + 1] = (float)(fill[4 * i + 2] / l);
            m->normal[3 * i + 2] = (float)(fill[4 * i + 3] / l);
        } else if (m->status[i] == DM_TEXEL_MISS) {
            memcpy(m->normal + 3 * i, m->nrm + 3 * i, 3 * sizeof(float));
        } else {
            m->normal[3 * i] = 0.0f; m->normal[3 * i + 1] = 0.0f; m->normal[3 * i + 2] = 1.0f;
        }
    }
    if (r->o.progress && r->o.progress(r->o.progress_user, 1.0f)) return DM_CANCELLED;
    return DM_OK;
}

DMDEF dm_result dm_base_normals(const float *positions, size_t vertex_count, const uint32_t *indices,
                                size_t triangle_count, const dm_allocator *allocator, float *normals)
{
    dm__scratch sc;
    double *acc;
    dm_result res = dm__check_mesh(positions, vertex_count, indices, triangle_count);
    if (res == DM_OK && !normals) res = DM_ERR_INVALID_ARGUMENT;
    if (res != DM_OK) return res;
    memset(&sc, 0, sizeof sc);
    sc.a = dm__resolve_allocator(allocator);
    acc = (double *)dm__take(&sc, 3 * vertex_count + 1, sizeof(double));
    res = acc ? dm__base_normals(&sc, positions, vertex_count, indices, triangle_count, acc, normals)
              : dm__scratch_fail(&sc);
    dm__release(&sc);
    return res;
}

DMDEF dm_bake_options dm_bake_default_options(void)
{
    dm_bake_options o; /* max_distance 0: 5% of the original's diagonal, which only the call knows */
    memset(&o, 0, sizeof o);
    return o;
}

DMDEF dm_result dm_bake(const dm_param *param, const float *base_positions, size_t base_vertex_count,
                        const uint32_t *base_indices, size_t base_triangle_count,
                        const float *orig_positions, size_t orig_vertex_count,
                        const uint32_t *orig_indices, size_t orig_triangle_count,
                        const dm_bake_options *options, dm_dispmap **out)
{
    dm__bk_run r;
    dm_result res;
    if (out) *out = NULL;
    if (!out || !param) return DM_ERR_INVALID_ARGUMENT;
    memset(&r, 0, sizeof r);
    r.param = param;
    r.bpos = base_positions; r.bnv = base_vertex_count; r.bidx = base_indices; r.bnt = base_triangle_count;
    r.opos = orig_positions; r.onv = orig_vertex_count; r.oidx = orig_indices; r.ont = orig_triangle_count;
    res = dm__bk_check(&r, options);
    if (res != DM_OK) return res;
    res = dm__bk_alloc(&r);
    if (res == DM_OK) res = dm__bk_prepare(&r);  /* normals, search distance, BVH */
    if (res == DM_OK) res = dm__bk_cast(&r);     /* one ray per texel */
    if (res == DM_OK) res = dm__bk_outliers(&r); /* rays that slipped to another sheet */
    if (res == DM_OK) res = dm__bk_border(&r);   /* and per texel of the charts' borders */
    if (res == DM_OK) res = dm__bk_seams(&r);    /* border texels fitted to the seams' rays */
    if (res == DM_OK) res = dm__bk_fill(&r);     /* push-pull over the misses */
    dm_bvh_free(r.bvh);
    dm__release(&r.sc);
    if (res != DM_OK) {
        dm_dispmap_free(r.m);
        return res;
    }
    *out = r.m;
    return DM_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: reconstruction and sampled surface distance
   --------------------------------------------------------------------------------------------- */

DMDEF void dm_trimesh_free(dm_trimesh *mesh)
{
    dm_allocator a;
    if (!mesh) return;
    a = mesh->allocator;
    a.free(a.user, mesh->positions);
    a.free(a.user, mesh->normals);
    a.free(a.user, mesh->indices);
    a.free(a.user, mesh->face_base);
    a.free(a.user, mesh);
}

/* dm_reconstruct's working state: the map and its parameterization, the base mesh, its
   vertex normals, the base edges (one per vertex pair, shared by every triangle on it) with
   their levels and first vertices, each triangle's level and first interior vertex, the
   per-vertex sums of the map's samples, and the mesh being made (all temporaries in sc) */
typedef struct dm__rc_run {
    const dm_dispmap *map;
    const dm_param *param;
    const float *bpos;
    const uint32_t *bidx;
    size_t bnv, bnt;
    dm_reconstruct_options o;
    dm__scratch sc;
    float *bnrm;          /* base vertex normals */
    double *acc;          /* 3 per base vertex (the normals' sums), then 5 per vertex: depth, normal, count */
    dm__edge *edges;      /* the 3 bnt half-edges sorted by vertex pair */
    uint32_t *he_edge;    /* 3 per triangle: the edge of half-edge 3 t + c */
    uint32_t *edge_level; /* per edge: segments along it */
    uint32_t *edge_first; /* per edge: its first inner vertex, numbered from the lower base vertex */
    uint32_t *tri_level;  /* per triangle: the level of its barycentric grid */
    uint32_t *tri_first;  /* per triangle: its first interior vertex */
    float *nb;            /* 3 per vertex: base normal at the vertex's base point */
    float *vuv;           /* 2 per vertex: its map position (texels) in the triangle being made */
    uint64_t *lkey;       /* an open-addressing table of one triangle's edges (lcap slots, 0 = free) */
    uint32_t *lval;       /* the half-edge that put each key there */
    uint32_t *lslot;      /* per half-edge: the slot it used, to empty the table after */
    size_t lcap;
    int32_t *ltwin;       /* per half-edge of one triangle's tessellation: the one across it, or -1 */
    uint32_t *lstack;     /* the half-edges still to test for a flip */
    unsigned char *lq;    /* per half-edge: 1 while it waits in lstack */
    size_t ne, nvtx, ntri, lmax;
    dm_trimesh *mesh;
} dm__rc_run;

#define DM__RC_MAX_LEVEL 1024

/* the options and the meshes checked, the parameterization matched to map and base */
static dm_result dm__rc_check(dm__rc_run *r, const dm_reconstruct_options *options)
{
    dm_result res;
    memset(&r->o, 0, sizeof r->o);
    if (options) r->o = *options;
    if (!(r->o.density >= 0.0f) || r->o.density > 16.0f) return DM_ERR_INVALID_ARGUMENT;
    if (r->o.density == 0.0f) r->o.density = 1.0f;
    res = dm__check_mesh(r->bpos, r->bnv, r->bidx, r->bnt);
    if (res != DM_OK) return res;
    if (r->bnv >= DM_NO_HIT) return DM_ERR_INVALID_ARGUMENT;
    res = dm__check_param(r->param, r->bnt);
    return res != DM_OK ? res : dm__check_map(r->map, r->param);
}

/* length in texels of half-edge c of base triangle t in its chart */
static double dm__rc_uv_length(const dm__rc_run *r, size_t t, int c)
{
    const float *uv = r->param->uv + 6 * t;
    int d = (c + 1) % 3;
    double dx = ((double)uv[2 * d] - uv[2 * c]) * r->param->width, dy = ((double)uv[2 * d + 1] - uv[2 * c + 1]) * r->param->height;
    return sqrt(dx * dx + dy * dy);
}

/* the segments of a run of uv length len texels: density per texel, at least 1 */
static uint32_t dm__rc_segments(const dm__rc_run *r, double len)
{
    double s = ceil(len * (double)r->o.density - 1e-9);
    if (!(s >= 1.0)) return 1;
    return s > DM__RC_MAX_LEVEL ? DM__RC_MAX_LEVEL : (uint32_t)s;
}

/* 1. the base edges: half-edges with the same vertex pair are one edge (two on a manifold
   edge, one on a boundary, more on a non-manifold edge), its level the largest of its
   half-edges' uv lengths in texels; each triangle's level sqrt(2 uv area), at least 3 (one
   interior vertex), so that its grid has about one vertex per texel as the map has */
static dm_result dm__rc_edges(dm__rc_run *r)
{
    size_t i, j, n = 3 * r->bnt, t;
    dm__edge *e = r->edges;
    dm__sorted_edges(r->bidx, r->bnt, e);
    r->ne = 0;
    for (i = 0; i < n; i = j) {
        uint32_t level = 1;
        for (j = i; j < n && e[j].key == e[i].key; j++) {
            uint32_t s = dm__rc_segments(r, dm__rc_uv_length(r, e[j].he / 3, (int)(e[j].he % 3)));
            if (s > level) level = s;
            r->he_edge[e[j].he] = (uint32_t)r->ne;
        }
        r->edge_level[r->ne++] = level;
    }
    for (t = 0; t < r->bnt; t++) { /* about one vertex per texel of its uv area */
        const float *uv = r->param->uv + 6 * t;
        double area = 0.5 * fabs(((double)uv[2] - uv[0]) * ((double)uv[5] - uv[1]) - ((double)uv[4] - uv[0]) * ((double)uv[3] - uv[1])) *
                      (double)r->param->width * (double)r->param->height;
        uint32_t level = dm__rc_segments(r, sqrt(2.0 * area));
        if (level < 3) level = 3;
        r->tri_level[t] = level;
    }
    return DM_OK;
}

/* 2. the vertex and triangle counts: the base vertices, each edge's inner points, each
   triangle's interior grid points; per triangle the inner grid's (n-3)^2 triangles and three
   strips of m_c + n - 3 */
static dm_result dm__rc_count(dm__rc_run *r)
{
    uint64_t nv = r->bnv, nt = 0;
    size_t e, t;
    for (e = 0; e < r->ne; e++) {
        r->edge_first[e] = (uint32_t)nv;
        nv += r->edge_level[e] - 1;
        if (nv >= DM_NO_HIT) return DM_ERR_TOO_LARGE;
    }
    for (t = 0; t < r->bnt; t++) {
        uint64_t n = r->tri_level[t];
        int c;
        r->tri_first[t] = (uint32_t)nv;
        nv += (n - 1) * (n - 2) / 2;
        uint64_t nt0 = nt;
        nt += (n - 3) * (n - 3);
        for (c = 0; c < 3; c++) nt += r->edge_level[r->he_edge[3 * t + (size_t)c]] + n - 3;
        if (nt - nt0 > r->lmax) r->lmax = (size_t)(nt - nt0);
        if (nv >= DM_NO_HIT || nt >= ((uint64_t)1 << 40)) return DM_ERR_TOO_LARGE;
    }
    r->nvtx = (size_t)nv;
    r->ntri = (size_t)nt;
    if ((uint64_t)r->nvtx != nv || (uint64_t)r->ntri != nt) return DM_ERR_TOO_LARGE;
    return DM_OK;
}

/* 3. the mesh's arrays and the per-vertex sums */
static dm_result dm__rc_alloc(dm__rc_run *r)
{
    dm__scratch *sc = &r->sc;
    dm_trimesh *m = r->mesh = (dm_trimesh *)sc->a.alloc(sc->a.user, sizeof(dm_trimesh));
    if (!m) return DM_ERR_OUT_OF_MEMORY;
    memset(m, 0, sizeof *m);
    m->allocator = sc->a;
    m->positions = (float *)dm__alloc_array(&sc->a, 3 * r->nvtx, sizeof(float), &sc->overflow);
    m->normals = (float *)dm__alloc_array(&sc->a, 3 * r->nvtx, sizeof(float), &sc->overflow);
    m->indices = (uint32_t *)dm__alloc_array(&sc->a, 3 * r->ntri, sizeof(uint32_t), &sc->overflow);
    m->face_base = (uint32_t *)dm__alloc_array(&sc->a, r->ntri, sizeof(uint32_t), &sc->overflow);
    r->acc = (double *)dm__take(sc, 5 * (r->nvtx > r->bnv ? r->nvtx : r->bnv), sizeof(double));
    r->nb = (float *)dm__take(sc, 3 * r->nvtx, sizeof(float));
    r->vuv = (float *)dm__take(sc, 2 * r->nvtx, sizeof(float));
    for (r->lcap = 64; r->lcap < 6 * r->lmax; r->lcap *= 2) {}
    r->lkey = (uint64_t *)dm__take(sc, r->lcap, sizeof(uint64_t));
    r->lval = (uint32_t *)dm__take(sc, r->lcap, sizeof(uint32_t));
    r->lslot = (uint32_t *)dm__take(sc, 3 * r->lmax, sizeof(uint32_t));
    r->ltwin = (int32_t *)dm__take(sc, 3 * r->lmax, sizeof(int32_t));
    r->lstack = (uint32_t *)dm__take(sc, 3 * r->lmax, sizeof(uint32_t));
    r->lq = (unsigned char *)dm__take(sc, 3 * r->lmax, 1);
    if (!m->positions || !m->normals || !m->indices || !m->face_base || !r->acc || !r->nb || !r->vuv || !r->lkey ||
        !r->lval || !r->lslot || !r->ltwin || !r->lstack || !r->lq)
        return dm__scratch_fail(sc);
    memset(r->lkey, 0, r->lcap * sizeof(uint64_t));
    memset(r->lq, 0, 3 * r->lmax);
    memset(r->acc, 0, 5 * r->nvtx * sizeof(double));
    m->vertex_count = r->nvtx;
    m->triangle_count = r->ntri;
    return DM_OK;
}

/* the map bilinearly at uv (0..1): depth and the original's normal (unnormalized), as a GPU's
   linear filter reads it; the borders' baked texels make this exact up to the map's resolution
   at every point of a chart */
static void dm__rc_lookup(const dm_dispmap *map, double u, double v, double *d, double n[3])
{
    size_t id[4];
    double w[4];
    int k, i;
    dm__bilinear(map->width, map->height, u, v, id, w);
    *d = 0.0;
    n[0] = n[1] = n[2] = 0.0;
    for (i = 0; i < 4; i++) {
        *d += w[i] * map->disp[id[i]];
        for (k = 0; k < 3; k++) n[k] += w[i] * map->normal[3 * id[i] + (size_t)k];
    }
}

/* vertex id of point i of m along edge c of base triangle t, from corner c (i = 0) to corner
   c + 1 (i = m); the edge's inner points are numbered from its lower base vertex */
static uint32_t dm__rc_edge_vertex(const dm__rc_run *r, size_t t, int c, uint32_t i)
{
    size_t e = r->he_edge[3 * t + (size_t)c];
    uint32_t m = r->edge_level[e], from = r->bidx[3 * t + (size_t)c], to = r->bidx[3 * t + (size_t)(c + 1) % 3];
    if (i == 0) return from;
    if (i == m) return to;
    return r->edge_first[e] + (from <= to ? i - 1 : m - 1 - i);
}

/* vertex id of base triangle t's interior grid point (a0, a1, a2), a0 + a1 + a2 = n, each >= 1:
   rows a2 = 1 .. n-2, row a2 holding a1 = 1 .. n-1-a2 */
static uint32_t dm__rc_inner_vertex(const dm__rc_run *r, size_t t, uint32_t n, const uint32_t a[3])
{
    return r->tri_first[t] + (uint32_t)(((size_t)(a[2] - 1) * (2 * (size_t)n - 2 - (size_t)a[2])) / 2) + a[1] - 1;
}

/* one sample of base triangle t at barycentrics w (a grid point): the base point and base
   normal into vertex id (the same point from every triangle that shares it), its map position in
   texels into vuv (for the flips of 4b), and the map's depth and normal there added to the
   vertex's sums */
static void dm__rc_sample(dm__rc_run *r, size_t t, uint32_t id, const double w[3])
{
    const uint32_t *bi = r->bidx + 3 * t;
    const float *uv = r->param->uv + 6 * t;
    double p[3], nb[3], d, nn[3], len, u = 0.0, v = 0.0, *acc = r->acc + 5 * (size_t)id;
    int c, k;
    for (k = 0; k < 3; k++) p[k] = nb[k] = 0.0;
    for (c = 0; c < 3; c++) {
        for (k = 0; k < 3; k++) {
            p[k] += w[c] * r->bpos[3 * (size_t)bi[c] + (size_t)k];
            nb[k] += w[c] * r->bnrm[3 * (size_t)bi[c] + (size_t)k];
        }
        u += w[c] * uv[2 * c];
        v += w[c] * uv[2 * c + 1];
    }
    len = dm__len3(nb);
    if (!(len > 1e-12)) { dm__face_normal(r->bpos, r->bidx, t, nb); len = dm__len3(nb); }
    for (k = 0; k < 3; k++) {
        r->mesh->positions[3 * (size_t)id + (size_t)k] = (float)p[k];
        r->nb[3 * (size_t)id + (size_t)k] = len > 0.0 ? (float)(nb[k] / len) : 0.0f;
    }
    r->vuv[2 * (size_t)id] = (float)(u * r->param->width);
    r->vuv[2 * (size_t)id + 1] = (float)(v * r->param->height);
    dm__rc_lookup(r->map, u, v, &d, nn);
    acc[0] += d;
    for (k = 0; k < 3; k++) acc[1 + k] += nn[k];
    acc[4] += 1.0;
}

/* point (w_c, w_c1, w_c2) of base triangle t in uv (texels) */
static void dm__rc_uv_point(const dm__rc_run *r, size_t t, int c, double wc, double wc1, double wc2, double out[2])
{
    const float *uv = r->param->uv + 6 * t;
    int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    out[0] = (wc * uv[2 * c] + wc1 * uv[2 * c1] + wc2 * uv[2 * c2]) * r->param->width;
    out[1] = (wc * uv[2 * c + 1] + wc1 * uv[2 * c1 + 1] + wc2 * uv[2 * c2 + 1]) * r->param->height;
}

/* the strip between edge c of triangle t (m segments P_i, corner c to c+1) and the interior
   grid's row next to it (n - 3 segments, Q_j = (n-2-j, 1+j, 1) in the order c, c+1, c+2),
   triangulated by walking both in step, each step taking the shorter new diagonal in uv (no
   slivers where the two rows' spacings differ); written at *tri */
static void dm__rc_strip(dm__rc_run *r, size_t t, uint32_t n, int c, size_t *tri)
{
    int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    uint32_t m = r->edge_level[r->he_edge[3 * t + (size_t)c]], rr = n - 3, i = 0, j = 0, q[3];
    while (i < m || j < rr) {
        uint32_t *o = r->mesh->indices + 3 * *tri;
        int outer = j == rr;
        if (!outer && i < m) { /* diagonals P_{i+1} Q_j and P_i Q_{j+1} */
            double p0[2], p1[2], q0[2], q1[2], da, db;
            dm__rc_uv_point(r, t, c, (double)(m - i) / m, (double)i / m, 0.0, p0);
            dm__rc_uv_point(r, t, c, (double)(m - i - 1) / m, (double)(i + 1) / m, 0.0, p1);
            dm__rc_uv_point(r, t, c, (double)(n - 2 - j) / n, (double)(1 + j) / n, 1.0 / n, q0);
            dm__rc_uv_point(r, t, c, (double)(n - 3 - j) / n, (double)(2 + j) / n, 1.0 / n, q1);
            da = (p1[0] - q0[0]) * (p1[0] - q0[0]) + (p1[1] - q0[1]) * (p1[1] - q0[1]);
            db = (p0[0] - q1[0]) * (p0[0] - q1[0]) + (p0[1] - q1[1]) * (p0[1] - q1[1]);
            outer = da <= db;
        }
        q[c] = n - 2 - j; q[c1] = 1 + j; q[c2] = 1;
        o[0] = dm__rc_edge_vertex(r, t, c, i);
        if (outer) {
            o[1] = dm__rc_edge_vertex(r, t, c, i + 1);
            o[2] = dm__rc_inner_vertex(r, t, n, q);
            i++;
        } else {
            o[2] = dm__rc_inner_vertex(r, t, n, q);
            q[c] = n - 3 - j; q[c1] = 2 + j;
            o[1] = dm__rc_inner_vertex(r, t, n, q);
            j++;
        }
        r->mesh->face_base[(*tri)++] = (uint32_t)t;
    }
}

/* twice the signed area of (a, b, c) in the map (texels) */
static double dm__rc_orient(const float *a, const float *b, const float *c)
{
    return ((double)b[0] - a[0]) * ((double)c[1] - a[1]) - ((double)b[1] - a[1]) * ((double)c[0] - a[0]);
}

/* d strictly inside the circle through the counter-clockwise a, b, c (all in texels) */
static int dm__rc_in_circle(const float *a, const float *b, const float *c, const float *d)
{
    double ax = (double)a[0] - d[0], ay = (double)a[1] - d[1], bx = (double)b[0] - d[0], by = (double)b[1] - d[1];
    double cx = (double)c[0] - d[0], cy = (double)c[1] - d[1];
    double det = (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay) +
                 (cx * cx + cy * cy) * (ax * by - bx * ay);
    double scale = (ax * ax + ay * ay + bx * bx + by * by + cx * cx + cy * cy);
    return det > 1e-9 * scale * scale;
}

/* 4c's tests: a flip may take the other diagonal when the map's depth bends away from it
   (squared) by DM__RC_FIT_GAIN less than from the edge, and only where neither new triangle is
   thinner in the map than DM__RC_FIT_SHAPE (2 area / longest edge^2) */
#define DM__RC_FIT_GAIN 0.8
#define DM__RC_FIT_SHAPE 0.3

/* the depth the vertex has read so far (the mean of its reads) */
static double dm__rc_depth(const dm__rc_run *r, uint32_t id)
{
    const double *acc = r->acc + 5 * (size_t)id;
    return acc[4] > 0.0 ? acc[0] / acc[4] : 0.0;
}

/* the map's bilinear depth at x (texels, as vuv) */
static double dm__rc_map_depth(const dm__rc_run *r, const double x[2])
{
    size_t id[4];
    double w[4], d = 0.0;
    int i;
    dm__bilinear(r->map->width, r->map->height, x[0] / r->param->width, x[1] / r->param->height, id, w);
    for (i = 0; i < 4; i++) d += w[i] * r->map->disp[id[i]];
    return d;
}

/* 2 area / longest edge^2 of (a, b, c) in the map */
static double dm__rc_shape(const float *a, const float *b, const float *c)
{
    double l = 0.0, e;
    int k;
    const float *p[3];
    p[0] = a; p[1] = b; p[2] = c;
    for (k = 0; k < 3; k++) {
        const float *u = p[k], *v = p[(k + 1) % 3];
        e = ((double)v[0] - u[0]) * ((double)v[0] - u[0]) + ((double)v[1] - u[1]) * ((double)v[1] - u[1]);
        if (e > l) l = e;
    }
    return l > 0.0 ? dm__rc_orient(a, b, c) / l : 0.0;
}

/* the squared gap between the map's depth at the middle of edge (a, b) and the mean of its ends'
   depths: how far the map bends away from the edge */
static double dm__rc_edge_gap(const dm__rc_run *r, uint32_t a, uint32_t b)
{
    const float *A = r->vuv + 2 * (size_t)a, *B = r->vuv + 2 * (size_t)b;
    double m[2], g;
    m[0] = 0.5 * ((double)A[0] + B[0]);
    m[1] = 0.5 * ((double)A[1] + B[1]);
    g = dm__rc_map_depth(r, m) - 0.5 * (dm__rc_depth(r, a) + dm__rc_depth(r, b));
    return g * g;
}

/* Does the quad (a, b, c) + (b, a, d) follow the map better cut along c-d (data-dependent
   triangulation, Dyn, Levin and Rippa 1990)? Each flip lowers the sum of the inner edges' gaps,
   which depend on the edges alone, so the flips end. */
static int dm__rc_fits_better(const dm__rc_run *r, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    const float *uv = r->vuv, *A = uv + 2 * (size_t)a, *B = uv + 2 * (size_t)b, *C = uv + 2 * (size_t)c,
                *D = uv + 2 * (size_t)d;
    if (dm__rc_shape(A, D, C) < DM__RC_FIT_SHAPE || dm__rc_shape(D, B, C) < DM__RC_FIT_SHAPE) return 0;
    return dm__rc_edge_gap(r, c, d) < DM__RC_FIT_GAIN * dm__rc_edge_gap(r, a, b);
}

/* half-edge h of the local triangles (3 lt + c) of the mesh's triangles from tri0 */
#define DM__RC_HE(tri0, h) (3 * (tri0) + (size_t)(h))

/* 4b. base triangle t's tessellation (its triangles tri0 .. tri1): each edge's two half-edges
   paired in ltwin (-1 on its border), one of each pair queued in lstack; returns how many */
static size_t dm__rc_twins(dm__rc_run *r, size_t tri0, size_t tri1)
{
    const uint32_t *I = r->mesh->indices;
    size_t nh = 3 * (tri1 - tri0), i, ns = 0, mask = 63;
    int32_t *tw = r->ltwin;
    while (mask + 1 < 2 * nh && mask + 1 < r->lcap) mask = 2 * mask + 1; /* a table this triangle's size */
    for (i = 0; i < nh; i++) { /* the twins: each edge's two half-edges meet in the table */
        uint32_t a = I[DM__RC_HE(tri0, i)], b = I[DM__RC_HE(tri0, i - i % 3 + (i % 3 + 1) % 3)];
        uint64_t key = (a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a)) + 1; /* never 0 */
        size_t slot = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
        tw[i] = -1;
        while (r->lkey[slot] != 0 && r->lkey[slot] != key) slot = (slot + 1) & mask;
        r->lslot[i] = (uint32_t)slot;
        if (r->lkey[slot] == key) {
            tw[i] = (int32_t)r->lval[slot];
            tw[r->lval[slot]] = (int32_t)i;
            r->lstack[ns++] = r->lval[slot];
            r->lq[r->lval[slot]] = 1;
        } else {
            r->lkey[slot] = key;
            r->lval[slot] = (uint32_t)i;
        }
    }
    for (i = 0; i < nh; i++) r->lkey[r->lslot[i]] = 0; /* the table emptied again */
    return ns;
}

/* 4c. edge flips over the tessellation's ns queued edges, its border fixed (Lawson): with fit = 0
   until it is Delaunay in the map (the strips' and corners' slivers become the triangles with
   the largest smallest angles the same points allow, so that the surface's normals do not jump
   where the grid meets its edges); with fit = 1 where the other diagonal follows the map's depth
   better (dm__rc_fits_better). Each edge waits in the queue at most once. */
static void dm__rc_flips(dm__rc_run *r, size_t tri0, size_t tri1, size_t ns, int fit)
{
    uint32_t *I = r->mesh->indices;
    const float *uv = r->vuv;
    size_t budget = 8 * 3 * (tri1 - tri0) + 64; /* both kinds end; the budget only guards rounding */
    int32_t *tw = r->ltwin;
    while (ns > 0 && budget-- > 0) {
        uint32_t h = r->lstack[--ns], g, f0, f1, a, b, c, d, out[4];
        int32_t ot[4];
        int k;
        r->lq[h] = 0;
        if (tw[h] < 0) continue;
        g = (uint32_t)tw[h];
        f0 = h / 3; f1 = g / 3;
        a = I[DM__RC_HE(tri0, h)];
        b = I[DM__RC_HE(tri0, 3 * f0 + (h % 3 + 1) % 3)];
        c = I[DM__RC_HE(tri0, 3 * f0 + (h % 3 + 2) % 3)];
        d = I[DM__RC_HE(tri0, 3 * f1 + (g % 3 + 2) % 3)];
        if (!(dm__rc_orient(uv + 2 * (size_t)a, uv + 2 * (size_t)d, uv + 2 * (size_t)c) > 0.0) ||
            !(dm__rc_orient(uv + 2 * (size_t)d, uv + 2 * (size_t)b, uv + 2 * (size_t)c) > 0.0) ||
            !(fit ? dm__rc_fits_better(r, a, b, c, d)
                  : dm__rc_in_circle(uv + 2 * (size_t)a, uv + 2 * (size_t)b, uv + 2 * (size_t)c, uv + 2 * (size_t)d)))
            continue;
        /* the outer half-edges: b->c, c->a of f0; a->d, d->b of f1, and who is across them */
        out[0] = 3 * f0 + (h % 3 + 1) % 3; out[1] = 3 * f0 + (h % 3 + 2) % 3;
        out[2] = 3 * f1 + (g % 3 + 1) % 3; out[3] = 3 * f1 + (g % 3 + 2) % 3;
        for (k = 0; k < 4; k++) ot[k] = tw[out[k]];
        /* f0 = (a, d, c): a->d (was out 2), d->c (new), c->a (was out 1);
           f1 = (d, b, c): d->b (was out 3), b->c (was out 0), c->d (new) */
        I[DM__RC_HE(tri0, 3 * f0)] = a; I[DM__RC_HE(tri0, 3 * f0 + 1)] = d; I[DM__RC_HE(tri0, 3 * f0 + 2)] = c;
        I[DM__RC_HE(tri0, 3 * f1)] = d; I[DM__RC_HE(tri0, 3 * f1 + 1)] = b; I[DM__RC_HE(tri0, 3 * f1 + 2)] = c;
        {
            uint32_t nhs[6] = {3 * f0, 3 * f0 + 1, 3 * f0 + 2, 3 * f1, 3 * f1 + 1, 3 * f1 + 2};
            int32_t nt[6];
            nt[0] = ot[2]; nt[1] = (int32_t)(3 * f1 + 2); nt[2] = ot[1];
            nt[3] = ot[3]; nt[4] = ot[0]; nt[5] = (int32_t)(3 * f0 + 1);
            for (k = 0; k < 6; k++) {
                tw[nhs[k]] = nt[k];
                if (nt[k] >= 0 && k != 1 && k != 5) {
                    tw[nt[k]] = (int32_t)nhs[k];
                    if (!r->lq[nhs[k]] && !r->lq[nt[k]]) {
                        r->lq[nhs[k]] = 1;
                        r->lstack[ns++] = nhs[k];
                    }
                }
            }
        }
    }
    while (ns > 0) r->lq[r->lstack[--ns]] = 0; /* what the budget left */
}

/* 4d. the fit's queue: one half-edge of every inner edge */
static size_t dm__rc_queue_all(dm__rc_run *r, size_t tri0, size_t tri1)
{
    size_t i, ns = 0;
    for (i = 0; i < 3 * (tri1 - tri0); i++)
        if (r->ltwin[i] > (int32_t)i) {
            r->lq[i] = 1;
            r->lstack[ns++] = (uint32_t)i;
        }
    return ns;
}
#undef DM__RC_HE

/* 4. base triangle t: its samples (corners, edge points, interior grid), then its triangles
   (the interior grid and the three strips), made Delaunay in the map, then flipped along its
   depth */
static void dm__rc_triangle(dm__rc_run *r, size_t t, size_t *tri)
{
    size_t tri0 = *tri;
    uint32_t n = r->tri_level[t], a[3], b1, b2, q[4][3];
    double w[3];
    int c, k;
    for (c = 0; c < 3; c++) {
        uint32_t m = r->edge_level[r->he_edge[3 * t + (size_t)c]], i;
        for (i = 0; i < m; i++) { /* corner c (i = 0), then edge c's inner points */
            w[c] = (double)(m - i) / (double)m;
            w[(c + 1) % 3] = (double)i / (double)m;
            w[(c + 2) % 3] = 0.0;
            dm__rc_sample(r, t, dm__rc_edge_vertex(r, t, c, i), w);
        }
    }
    for (a[2] = 1; a[2] + 2 <= n; a[2]++)
        for (a[1] = 1; a[1] + a[2] + 1 <= n; a[1]++) {
            a[0] = n - a[1] - a[2];
            for (k = 0; k < 3; k++) w[k] = (double)a[k] / (double)n;
            dm__rc_sample(r, t, dm__rc_inner_vertex(r, t, n, a), w);
        }
    for (b2 = 0; b2 + 3 <= n; b2++) /* the interior grid: level n - 3 over the points a >= 1 */
        for (b1 = 0; b1 + b2 + 3 <= n; b1++) {
            uint32_t *o;
            q[0][1] = b1 + 1; q[0][2] = b2 + 1;
            q[1][1] = b1 + 2; q[1][2] = b2 + 1;
            q[2][1] = b1 + 1; q[2][2] = b2 + 2;
            q[3][1] = b1 + 2; q[3][2] = b2 + 2;
            for (k = 0; k < 4; k++) q[k][0] = n - q[k][1] - q[k][2];
            if (b1 + b2 + 4 <= n) { /* the upward triangle */
                o = r->mesh->indices + 3 * *tri;
                o[0] = dm__rc_inner_vertex(r, t, n, q[0]);
                o[1] = dm__rc_inner_vertex(r, t, n, q[1]);
                o[2] = dm__rc_inner_vertex(r, t, n, q[2]);
                r->mesh->face_base[(*tri)++] = (uint32_t)t;
            }
            if (b1 + b2 + 5 <= n) { /* and the downward one */
                o = r->mesh->indices + 3 * *tri;
                o[0] = dm__rc_inner_vertex(r, t, n, q[1]);
                o[1] = dm__rc_inner_vertex(r, t, n, q[3]);
                o[2] = dm__rc_inner_vertex(r, t, n, q[2]);
                r->mesh->face_base[(*tri)++] = (uint32_t)t;
            }
        }
    for (c = 0; c < 3; c++) dm__rc_strip(r, t, n, c, tri);
    dm__rc_flips(r, tri0, *tri, dm__rc_twins(r, tri0, *tri), 0);     /* Delaunay in the map */
    if (r->o.depth_flips >= 0) dm__rc_flips(r, tri0, *tri, dm__rc_queue_all(r, tri0, *tri), 1); /* along the depth */
}

/* 5. every vertex: its base point moved by the mean of its samples' depths along the base
   normal, and the mean of their normals, unit */
static void dm__rc_finish(dm__rc_run *r)
{
    size_t v;
    int k;
    for (v = 0; v < r->nvtx; v++) {
        const double *acc = r->acc + 5 * v;
        double cnt = acc[4] > 0.0 ? acc[4] : 1.0, d = acc[0] / cnt, len = dm__len3(acc + 1);
        float *p = r->mesh->positions + 3 * v, *nrm = r->mesh->normals + 3 * v;
        if (!(acc[4] > 0.0)) { /* a base vertex no triangle uses */
            for (k = 0; k < 3; k++) { p[k] = r->bpos[3 * v + (size_t)k]; nrm[k] = r->bnrm[3 * v + (size_t)k]; }
            continue;
        }
        for (k = 0; k < 3; k++) {
            p[k] = (float)((double)p[k] - d * (double)r->nb[3 * v + (size_t)k]);
            nrm[k] = len > 0.0 ? (float)(acc[1 + k] / len) : r->nb[3 * v + (size_t)k];
        }
    }
}

DMDEF dm_reconstruct_options dm_reconstruct_default_options(void)
{
    dm_reconstruct_options o;
    memset(&o, 0, sizeof o);
    o.density = 1.0f;
    return o;
}

DMDEF dm_result dm_reconstruct(const dm_dispmap *map, const dm_param *param, const float *base_positions,
                               size_t base_vertex_count, const uint32_t *base_indices, size_t base_triangle_count,
                               const dm_reconstruct_options *options, dm_trimesh **out)
{
    dm__rc_run r;
    dm_result res;
    size_t t, tri = 0;
    if (out) *out = NULL;
    if (!out || !map || !param) return DM_ERR_INVALID_ARGUMENT;
    memset(&r, 0, sizeof r);
    r.map = map; r.param = param;
    r.bpos = base_positions; r.bnv = base_vertex_count; r.bidx = base_indices; r.bnt = base_triangle_count;
    res = dm__rc_check(&r, options);
    if (res != DM_OK) return res;
    r.sc.a = dm__resolve_allocator(r.o.allocator);
    r.bnrm = (float *)dm__take(&r.sc, 3 * r.bnv, sizeof(float));
    r.edges = (dm__edge *)dm__take(&r.sc, 3 * r.bnt, sizeof(dm__edge));
    r.he_edge = (uint32_t *)dm__take(&r.sc, 3 * r.bnt, sizeof(uint32_t));
    r.edge_level = (uint32_t *)dm__take(&r.sc, 3 * r.bnt, sizeof(uint32_t));
    r.edge_first = (uint32_t *)dm__take(&r.sc, 3 * r.bnt, sizeof(uint32_t));
    r.tri_level = (uint32_t *)dm__take(&r.sc, r.bnt, sizeof(uint32_t));
    r.tri_first = (uint32_t *)dm__take(&r.sc, r.bnt, sizeof(uint32_t));
    r.acc = (double *)dm__take(&r.sc, 3 * r.bnv, sizeof(double));
    if (!r.bnrm || !r.edges || !r.he_edge || !r.edge_level || !r.edge_first || !r.tri_level || !r.tri_first || !r.acc)
        res = dm__scratch_fail(&r.sc);
    if (res == DM_OK) {
        res = dm__base_normals(&r.sc, r.bpos, r.bnv, r.bidx, r.bnt, r.acc, r.bnrm); /* as dm_bake's */
        if (res == DM_OK) res = dm__rc_edges(&r);                                        /* 1. shared edges, levels */
    }
    if (res == DM_OK) res = dm__rc_count(&r);                          /* 2. sizes */
    if (res == DM_OK) res = dm__rc_alloc(&r);                          /* 3. arrays */
    for (t = 0; res == DM_OK && t < r.bnt; t++) {                      /* 4. samples, triangles */
        dm__rc_triangle(&r, t, &tri);
        if ((t & 63) == 63 && r.o.progress && r.o.progress(r.o.progress_user, 0.95f * (float)(t + 1) / (float)r.bnt))
            res = DM_CANCELLED;
    }
    if (res == DM_OK) dm__rc_finish(&r);                               /* 5. positions, normals */
    if (res == DM_OK && r.o.progress && r.o.progress(r.o.progress_user, 1.0f)) res = DM_CANCELLED;
    dm__release(&r.sc);
    if (res != DM_OK) {
        dm_trimesh_free(r.mesh);
        return res;
    }
    *out = r.mesh;
    return DM_OK;
}

/* progress of dm_surface_distance: queries done of all */
typedef struct dm__pz_count {
    const dm_distance_options *opt;
    size_t done, total, next;
} dm__pz_count;

/* counts one query; 1 when the caller cancelled */
static int dm__pz_tick(dm__pz_count *c)
{
    if (++c->done < c->next) return 0;
    c->next = c->done + 4096;
    return c->opt->progress && c->opt->progress(c->opt->progress_user, (float)((double)c->done / (double)c->total)) != 0;
}

static uint64_t dm__pz_hash(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

static double dm__pz_unit(uint64_t i, uint64_t stream)
{
    return (double)(dm__pz_hash(i * 8 + stream) >> 11) * (1.0 / 9007199254740992.0);
}

/* An upper bound on the distance from x to Q, from the closest point c of Q found for an earlier
   point: |x - c|, widened by c's float rounding (relative 2^-24 a coordinate) and the bound's own. */
static double dm__pz_bound(const float x[3], const dm_closest *c)
{
    double d2 = 0.0, cmax = 0.0;
    int k;
    for (k = 0; k < 3; k++) {
        double e = (double)x[k] - (double)c->point[k], a = fabs((double)c->point[k]);
        d2 += e * e;
        if (a > cmax) cmax = a;
    }
    return sqrt(d2) * (1.0 + 1e-6) + 1e-6 * cmax;
}

/* the closest point of Q to x; prev (when has_prev) bounds the search (the same answer, fewer
   nodes: consecutive points lie close together) */
static int dm__pz_closest(const dm_bvh *q, const float x[3], const dm_closest *prev, int has_prev, dm_closest *out)
{
    if (has_prev && dm_bvh_closest_point(q, x, (float)dm__pz_bound(x, prev), out)) return 1;
    return dm_bvh_closest_point(q, x, INFINITY, out);
}

/* one side: samples on mesh P measured to the BVH of mesh Q; sums squared distances, max (over
   the samples and every vertex of P; seen: nv bits of scratch). 0, or 1 when cancelled. */
static int dm__pz_sample_side(const float *pos, size_t nv, const uint32_t *idx, size_t nt, const double *cum,
                              const dm_bvh *q, size_t samples, uint64_t stream, unsigned char *seen, double *sum2,
                              double *mx, dm__pz_count *cnt)
{
    size_t i;
    double total = cum[nt];
    dm_closest prev;
    int has_prev = 0;
    *sum2 = 0.0;
    *mx = 0.0;
    memset(&prev, 0, sizeof prev);
    for (i = 0; i < samples && total > 0.0; i++) {
        double r = ((double)i + dm__pz_unit(i, stream)) / (double)samples * total, a = dm__pz_unit(i, stream + 1),
               b = dm__pz_unit(i, stream + 2), sa, p0[3], p1[3], p2[3];
        size_t lo = 0, hi = nt - 1, t;
        float pt[3];
        int k;
        dm_closest cl;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (cum[mid + 1] <= r) lo = mid + 1; else hi = mid;
        }
        t = lo;
        sa = sqrt(a);
        dm__load3(pos, idx[3 * t], p0);
        dm__load3(pos, idx[3 * t + 1], p1);
        dm__load3(pos, idx[3 * t + 2], p2);
        for (k = 0; k < 3; k++) pt[k] = (float)((1.0 - sa) * p0[k] + sa * (1.0 - b) * p1[k] + sa * b * p2[k]);
        if (dm__pz_closest(q, pt, &prev, has_prev, &cl)) {
            *sum2 += (double)cl.distance * cl.distance;
            if (cl.distance > *mx) *mx = cl.distance;
            prev = cl;
            has_prev = 1;
        }
        if (dm__pz_tick(cnt)) return 1;
    }
    /* every vertex once; one whose bound does not pass the max cannot raise it */
    memset(seen, 0, (nv + 7) / 8);
    for (i = 0; i < 3 * nt; i++) {
        dm_closest cl;
        uint32_t v = idx[i];
        const float *x = pos + 3 * (size_t)v;
        if (!(seen[v >> 3] & (1u << (v & 7)))) {
            seen[v >> 3] = (unsigned char)(seen[v >> 3] | (1u << (v & 7)));
            if (!has_prev || dm__pz_bound(x, &prev) > *mx) {
                if (dm__pz_closest(q, x, &prev, has_prev, &cl)) {
                    if (cl.distance > *mx) *mx = cl.distance;
                    prev = cl;
                    has_prev = 1;
                }
            }
        }
        if (dm__pz_tick(cnt)) return 1;
    }
    return 0;
}

DMDEF dm_distance_options dm_distance_default_options(void)
{
    dm_distance_options o;
    memset(&o, 0, sizeof o);
    o.samples_per_side = 200000;
    return o;
}

#define DM__MAX_SAMPLES 1000000000u /* dm_distance_options.samples_per_side */

DMDEF dm_result dm_surface_distance(const float *ap, size_t anv, const uint32_t *ai, size_t ant, const float *bp,
                                    size_t bnv, const uint32_t *bi, size_t bnt, const dm_distance_options *options,
                                    dm_distance_report *out)
{
    dm_distance_options opt;
    dm__pz_count cnt;
    size_t samples;
    dm__scratch sc;
    dm_bvh *ba = NULL, *bb = NULL;
    dm_bvh_options bo;
    dm_result res;
    unsigned char *seen;
    double *ca, *cb, lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, s2a, s2b, ma, mb, d;
    size_t t;
    int k;
    if (!out) return DM_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    res = dm__check_mesh(ap, anv, ai, ant);
    if (res != DM_OK) return res;
    res = dm__check_mesh(bp, bnv, bi, bnt);
    if (res != DM_OK) return res;
    if (options) opt = *options;
    else memset(&opt, 0, sizeof opt);
    if (opt.samples_per_side > DM__MAX_SAMPLES) return DM_ERR_INVALID_ARGUMENT; /* (counts stay far from overflow) */
    samples = opt.samples_per_side ? opt.samples_per_side : 200000;
    memset(&cnt, 0, sizeof cnt);
    cnt.opt = &opt;
    cnt.total = 2 * samples + 3 * ant + 3 * bnt;
    cnt.next = 4096;
    memset(&sc, 0, sizeof sc);
    sc.a = dm__resolve_allocator(opt.allocator);
    ca = (double *)dm__take(&sc, ant + 1, sizeof(double));
    cb = (double *)dm__take(&sc, bnt + 1, sizeof(double));
    seen = (unsigned char *)dm__take(&sc, ((anv > bnv ? anv : bnv) + 7) / 8, 1);
    if (!ca || !cb || !seen) { res = dm__scratch_fail(&sc); goto done; }
    ca[0] = cb[0] = 0.0;
    for (t = 0; t < ant; t++) {
        double n[3];
        dm__face_normal(ap, ai, t, n);
        ca[t + 1] = ca[t] + 0.5 * dm__len3(n);
    }
    for (t = 0; t < bnt; t++) {
        double n[3];
        dm__face_normal(bp, bi, t, n);
        cb[t + 1] = cb[t] + 0.5 * dm__len3(n);
    }
    for (t = 0; t < 3 * ant; t++)
        for (k = 0; k < 3; k++) {
            double v = ap[3 * (size_t)ai[t] + (size_t)k];
            if (v < lo[k]) lo[k] = v;
            if (v > hi[k]) hi[k] = v;
        }
    d = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    memset(&bo, 0, sizeof bo);
    bo.allocator = &sc.a;
    res = dm_bvh_build(ap, anv, ai, ant, &bo, &ba);
    if (res == DM_OK) res = dm_bvh_build(bp, bnv, bi, bnt, &bo, &bb);
    if (res != DM_OK) goto done;
    if (dm__pz_sample_side(ap, anv, ai, ant, ca, bb, samples, 1, seen, &s2a, &ma, &cnt) ||
        dm__pz_sample_side(bp, bnv, bi, bnt, cb, ba, samples, 5, seen, &s2b, &mb, &cnt) ||
        (opt.progress && opt.progress(opt.progress_user, 1.0f) != 0)) {
        res = DM_CANCELLED;
        goto done;
    }
    if (!(d > 0.0)) d = 1.0;
    out->diagonal = d;
    out->samples = samples;
    out->rms_a_to_b = sqrt(s2a / (double)samples) / d;
    out->rms_b_to_a = sqrt(s2b / (double)samples) / d;
    out->max_a_to_b = ma / d;
    out->max_b_to_a = mb / d;
    out->rms = sqrt((s2a + s2b) / (2.0 * (double)samples)) / d;
    out->max = (ma > mb ? ma : mb) / d;
done:
    dm_bvh_free(ba);
    dm_bvh_free(bb);
    dm__release(&sc);
    return res;
}

DMDEF dm_coverage_options dm_coverage_default_options(void)
{
    dm_coverage_options o;
    memset(&o, 0, sizeof o);
    o.floor = 0.05f;
    return o;
}

DMDEF dm_result dm_coverage_weights(const float *bp, size_t bnv, const uint32_t *bi, size_t bnt, const float *op,
                                    size_t onv, const uint32_t *oi, size_t ont, const dm_coverage_options *options,
                                    float *weights)
{
    dm_coverage_options opt;
    dm_bvh_options bo;
    dm_bvh *bvh = NULL;
    dm_allocator a;
    double *sum, total = 0.0, floor_w;
    int overflow = 0;
    size_t t;
    dm_result r;
    if (options) opt = *options;
    else memset(&opt, 0, sizeof opt);
    a = dm__resolve_allocator(opt.allocator);
    if (!weights || !(opt.floor >= 0.0f && opt.floor <= 1.0f)) return DM_ERR_INVALID_ARGUMENT;
    r = dm__check_mesh(bp, bnv, bi, bnt);
    if (r == DM_OK) r = dm__check_mesh(op, onv, oi, ont);
    if (r != DM_OK) return r;
    sum = (double *)dm__alloc_array(&a, bnt, sizeof(double), &overflow);
    if (!sum) return overflow ? DM_ERR_TOO_LARGE : DM_ERR_OUT_OF_MEMORY;
    memset(&bo, 0, sizeof bo);
    bo.allocator = opt.allocator;
    r = dm_bvh_build(bp, bnv, bi, bnt, &bo, &bvh);
    if (r != DM_OK) {
        a.free(a.user, sum);
        return r;
    }
    for (t = 0; t < bnt; t++) sum[t] = 0.0;
    for (t = 0; t < ont; t++) {
        double p[3][3], e1[3], e2[3], n[3], area;
        float c[3];
        dm_closest cl;
        int k;
        for (k = 0; k < 3; k++) dm__load3(op, oi[3 * t + (size_t)k], p[k]);
        for (k = 0; k < 3; k++) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
            c[k] = (float)((p[0][k] + p[1][k] + p[2][k]) / 3.0);
        }
        dm__cross3(e1, e2, n);
        area = 0.5 * sqrt(dm__dot3(n, n));
        if (dm_bvh_closest_point(bvh, c, INFINITY, &cl)) sum[cl.triangle] += area;
        if (opt.progress && ((t & 16383) == 16383 || t + 1 == ont) &&
            opt.progress(opt.progress_user, (float)((double)(t + 1) / (double)ont))) {
            dm_bvh_free(bvh);
            a.free(a.user, sum);
            return DM_CANCELLED;
        }
    }
    for (t = 0; t < bnt; t++) total += sum[t];
    floor_w = (double)(opt.floor > 0.0f ? opt.floor : 0.05f) * total / (double)bnt; /* 0 and the default agree bit for bit */
    for (t = 0; t < bnt; t++) weights[t] = (float)(sum[t] > floor_w ? sum[t] : floor_w);
    dm_bvh_free(bvh);
    a.free(a.user, sum);
    return DM_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: the bounding shell and paper 000's two simplification constraints
   --------------------------------------------------------------------------------------------- */

/* An original vertex the enclosure check constrains: its position and its nearest old one-ring
   triangle bt at barycentric (bu, bv), squared distance d2 (its old signed distance is taken
   from these only where the check needs it). */
typedef struct dm__sh_pt {
    float p[3];
    uint32_t bt;       /* its nearest old triangle (bu, bv, d2 its closest point and distance) */
    uint32_t nt;       /* its nearest new triangle at the proposed position (UINT32_MAX: none) */
    uint32_t q;        /* which vertex: its index in the grid's cell order */
    double bu, bv, d2;
} dm__sh_pt;

#define DM__SH_PROOFS 1024 /* kept proofs of enclosure vetoes (a direct-mapped table by edge) */

typedef struct dm__sh_internal {
    dm_bvh *bvh;         /* the original */
    float *pos;          /* the original's positions and indices (copies) */
    uint32_t *idx;
    size_t nv, nt;
    int open;            /* the original has an edge without a (consistently oriented) twin */
    int samples;         /* overlap samples per triangle */
    double margin;       /* how far outside a plane counts as outside (world units) */
    double *scratch;     /* planes, their normals in the metric's frame, one-ring normals */
    size_t scratch_cap;  /* in doubles */
    double *fnrm;        /* per triangle of the original: its unit normal (dm__sh_plane), NaN where
                            it has none */
    double *vsum;        /* per vertex: the angle-weighted normal sum of the simplified mesh, kept
                            by dm_shell_collapsed */
    size_t accepted, collapsed; /* candidates allowed or moved; dm_shell_collapsed calls (this run) */
    size_t last_level;   /* the level of the last candidate or collapse seen */
    dm__sh_pt *pts;      /* the original's vertices near one candidate */
    size_t pts_cap;
    double *tri;         /* the candidate's old and new triangles: 9 coordinates, a bounding
                            sphere (centre, radius) and the unit normal each, float values */
    uint32_t *tri_new;   /* per old triangle: the new one on the same two other corners (or
                            UINT32_MAX), a first guess for the nearest new triangle */
    size_t tri_cap;      /* in triangles */
    /* a uniform grid of the original's (referenced) vertices */
    double lo[3], cell;
    int dim[3];
    uint32_t *cell_first; /* cell i's vertices are cell_pos[3 cell_first[i] .. 3 cell_first[i + 1]) */
    float *cell_pos;     /* the vertices' positions in cell order (the gather reads them in a row) */
    uint32_t relaxed_keep; /* keep of the last candidate allowed only by the relaxed check */
    size_t relaxed_level;
    /* the enclosure's answer for the last candidate (asked for where keep goes, then in full) */
    int placed_valid, placed_verdict, placed_moved;
    uint32_t placed_keep, placed_remove;
    size_t placed_level;
    float placed_at[3];
    double placed_x[3];
    size_t gathered;       /* the relevant vertices in pts from the last enclosure (DM__SH_REACH) */
    uint32_t *proof;       /* DM__SH_PROOFS slots of 8: an edge's ends (lower first), then the count and
                              cell-order indices of the at most four vertices whose planes last had no
                              common point (dm__sh_proof_holds); NULL until the first such veto */
} dm__sh_internal;

DMDEF void dm_shell_free(dm_shell *shell)
{
    dm_allocator a;
    dm__sh_internal *in;
    if (!shell) return;
    a = shell->allocator;
    in = (dm__sh_internal *)shell->internal;
    if (in) {
        dm_bvh_free(in->bvh);
        a.free(a.user, in->pos);
        a.free(a.user, in->idx);
        a.free(a.user, in->scratch);
        a.free(a.user, in->pts);
        a.free(a.user, in->vsum);
        a.free(a.user, in->fnrm);
        a.free(a.user, in->tri);
        a.free(a.user, in->tri_new);
        a.free(a.user, in->proof);
        a.free(a.user, in->cell_first);
        a.free(a.user, in->cell_pos);
        a.free(a.user, in);
    }
    a.free(a.user, shell->positions);
    a.free(a.user, shell->normals);
    a.free(a.user, shell->offset);
    a.free(a.user, shell->fallback_vertex);
    a.free(a.user, shell);
}

static int dm__sh_coord(const dm__sh_internal *in, double x, int k)
{
    double c = floor((x - in->lo[k]) / in->cell);
    return c < 0.0 ? 0 : c >= (double)in->dim[k] ? in->dim[k] - 1 : (int)c;
}

static size_t dm__sh_cell_of(const dm__sh_internal *in, const float *p)
{
    return ((size_t)dm__sh_coord(in, p[2], 2) * (size_t)in->dim[1] + (size_t)dm__sh_coord(in, p[1], 1)) *
               (size_t)in->dim[0] + (size_t)dm__sh_coord(in, p[0], 0);
}

/* dm_shell_grow's working state: the original, the options, the shell being made and the
   temporaries (in sc, freed together on the one exit path) */
typedef struct dm__sh_run {
    const float *pos;
    const uint32_t *idx;
    size_t nv, nt;
    dm_shell_options opt;
    dm_allocator a;
    dm__scratch sc;
    dm_shell *sh;
    dm__sh_internal *in;
    double lo[3], hi[3], diag;    /* the original's box */
    double *acc;                  /* angle-weighted normal sums */
    uint8_t *stopped;             /* per vertex */
} dm__sh_run;

/* the box of the referenced vertices and its diagonal */
static void dm__sh_bounds(dm__sh_run *r)
{
    size_t i;
    int k;
    for (k = 0; k < 3; k++) { r->lo[k] = DBL_MAX; r->hi[k] = -DBL_MAX; }
    for (i = 0; i < 3 * r->nt; i++)
        for (k = 0; k < 3; k++) {
            double x = r->pos[3 * (size_t)r->idx[i] + (size_t)k];
            if (x < r->lo[k]) r->lo[k] = x;
            if (x > r->hi[k]) r->hi[k] = x;
        }
    r->diag = sqrt((r->hi[0] - r->lo[0]) * (r->hi[0] - r->lo[0]) + (r->hi[1] - r->lo[1]) * (r->hi[1] - r->lo[1]) +
                   (r->hi[2] - r->lo[2]) * (r->hi[2] - r->lo[2]));
}

/* the shell, its internal state (thickness, overlap samples, margin) and their arrays, with a
   copy of the original */
static dm_result dm__sh_alloc(dm__sh_run *r)
{
    dm_allocator *a = &r->a;
    size_t nv = r->nv, nt = r->nt;
    dm_shell *sh;
    dm__sh_internal *in;
    sh = r->sh = (dm_shell *)a->alloc(a->user, sizeof *sh);
    if (!sh) return DM_ERR_OUT_OF_MEMORY;
    memset(sh, 0, sizeof *sh);
    sh->allocator = *a;
    in = r->in = (dm__sh_internal *)a->alloc(a->user, sizeof *in);
    if (!in) return dm__scratch_fail(&r->sc);
    memset(in, 0, sizeof *in);
    in->relaxed_keep = UINT32_MAX;
    sh->internal = in;
    sh->vertex_count = in->nv = nv;
    sh->triangle_count = in->nt = nt;
    sh->diagonal = (float)r->diag;
    sh->thickness = r->opt.thickness > 0.0f ? r->opt.thickness : (float)(0.02 * r->diag);
    in->samples = r->opt.overlap_samples == 0 ? 4 : r->opt.overlap_samples > 7 ? 7 : r->opt.overlap_samples;
    in->margin = 1e-6 * r->diag;
    sh->positions = (float *)dm__alloc_array(a, 3 * nv, sizeof(float), &r->sc.overflow);
    sh->normals = (float *)dm__alloc_array(a, 3 * nv, sizeof(float), &r->sc.overflow);
    sh->offset = (float *)dm__alloc_array(a, nv, sizeof(float), &r->sc.overflow);
    sh->fallback_vertex = (uint8_t *)dm__alloc_array(a, nv, 1, &r->sc.overflow);
    in->pos = (float *)dm__alloc_array(a, 3 * nv, sizeof(float), &r->sc.overflow);
    in->idx = (uint32_t *)dm__alloc_array(a, 3 * nt, sizeof(uint32_t), &r->sc.overflow);
    if (!sh->positions || !sh->normals || !sh->offset || !sh->fallback_vertex || !in->pos || !in->idx)
        return dm__scratch_fail(&r->sc);
    memset(sh->fallback_vertex, 0, nv);
    memcpy(in->pos, r->pos, 3 * nv * sizeof(float));
    memcpy(in->idx, r->idx, 3 * nt * sizeof(uint32_t));
    return DM_OK;
}

static int dm__sh_plane(const double *p0, const double *p1, const double *p2, double n[3]);

/* the BVH over the original, its face and vertex normals (and the vertex normals' sums, kept for
   dm_shell_collapsed), and whether it is open (an edge without a consistently oriented twin) */
static dm_result dm__sh_normals(dm__sh_run *r)
{
    dm__sh_internal *in = r->in;
    size_t nv = r->nv, nt = r->nt, i;
    dm_bvh_options bo;
    dm__edge *e;
    uint32_t *twin, *twin_he;
    dm_result res;
    memset(&bo, 0, sizeof bo);
    bo.allocator = r->opt.allocator;
    res = dm_bvh_build(r->pos, nv, r->idx, nt, &bo, &in->bvh);
    if (res != DM_OK) return res;
    r->acc = (double *)dm__take(&r->sc, 3 * nv, sizeof(double));
    e = (dm__edge *)dm__take(&r->sc, 3 * nt, sizeof(dm__edge));
    twin = (uint32_t *)dm__take(&r->sc, 3 * nt, sizeof(uint32_t));
    twin_he = (uint32_t *)dm__take(&r->sc, 3 * nt, sizeof(uint32_t));
    r->stopped = (uint8_t *)dm__take(&r->sc, nv, 1);
    if (!r->acc || !e || !twin || !twin_he || !r->stopped) return dm__scratch_fail(&r->sc);
    dm__vertex_normals(r->pos, nv, r->idx, nt, r->acc, r->sh->normals);
    in->vsum = (double *)dm__alloc_array(&r->a, 3 * nv, sizeof(double), &r->sc.overflow);
    in->fnrm = (double *)dm__alloc_array(&r->a, 3 * nt, sizeof(double), &r->sc.overflow);
    if (!in->vsum || !in->fnrm) return dm__scratch_fail(&r->sc);
    memcpy(in->vsum, r->acc, 3 * nv * sizeof(double));
    for (i = 0; i < nt; i++) { /* the overlap rays ask which side of it they meet, many times */
        double q[3][3];
        int k;
        for (k = 0; k < 3; k++) dm__load3(r->pos, r->idx[3 * i + (size_t)k], q[k]);
        if (!dm__sh_plane(q[0], q[1], q[2], in->fnrm + 3 * i)) in->fnrm[3 * i] = NAN;
    }
    dm__twins(r->idx, nt, e, twin, twin_he);
    for (i = 0; i < 3 * nt && !in->open; i++) in->open = twin[i] == DM_NO_HIT;
    return DM_OK;
}

/* the uniform grid of the original's referenced vertices: about two per cell, at most 1024
   cells a side (stopped[] marks the referenced vertices meanwhile) */
static dm_result dm__sh_vertex_grid(dm__sh_run *r)
{
    dm__sh_internal *in = r->in;
    const double *lo = r->lo, *hi = r->hi;
    uint8_t *stopped = r->stopped;
    double ext = 0.0, vol = 1.0;
    size_t ncell, nref = 0, v, i;
    uint32_t *cnt;
    int k;
    for (k = 0; k < 3; k++) if (hi[k] - lo[k] > ext) ext = hi[k] - lo[k];
    for (v = 0; v < r->nv; v++) stopped[v] = 0;
    for (i = 0; i < 3 * r->nt; i++) stopped[r->idx[i]] = 1;
    for (v = 0; v < r->nv; v++) nref += stopped[v];
    for (k = 0; k < 3; k++) vol *= (hi[k] - lo[k]) > 1e-3 * ext ? (hi[k] - lo[k]) : 1e-3 * ext;
    in->cell = ext > 0.0 ? cbrt(2.0 * vol / (double)nref) : 1.0;
    if (!(in->cell > 0.0)) in->cell = 1.0;
    ncell = 1;
    for (k = 0; k < 3; k++) {
        double d = floor((hi[k] - lo[k]) / in->cell) + 1.0;
        in->dim[k] = d > 1024.0 ? 1024 : (int)d;
        in->lo[k] = lo[k];
        ncell *= (size_t)in->dim[k];
    }
    if (ext > 0.0 && in->cell * 1024.0 < ext) in->cell = ext / 1023.0;
    in->cell_first = (uint32_t *)dm__alloc_array(&r->a, ncell + 1, sizeof(uint32_t), &r->sc.overflow);
    in->cell_pos = (float *)dm__alloc_array(&r->a, nref ? nref : 1, 3 * sizeof(float), &r->sc.overflow);
    cnt = (uint32_t *)dm__take(&r->sc, ncell + 1, sizeof(uint32_t));
    if (!in->cell_first || !in->cell_pos || !cnt) return dm__scratch_fail(&r->sc);
    memset(cnt, 0, (ncell + 1) * sizeof(uint32_t));
    for (v = 0; v < r->nv; v++)
        if (stopped[v]) cnt[dm__sh_cell_of(in, r->pos + 3 * v)]++;
    in->cell_first[0] = 0;
    for (i = 0; i < ncell; i++) in->cell_first[i + 1] = in->cell_first[i] + cnt[i];
    for (i = 0; i < ncell; i++) cnt[i] = in->cell_first[i];
    for (v = 0; v < r->nv; v++)
        if (stopped[v]) memcpy(in->cell_pos + 3 * (size_t)cnt[dm__sh_cell_of(in, r->pos + 3 * v)]++, r->pos + 3 * v, 3 * sizeof(float));
    return DM_OK;
}

/* The growth test asks whether a point comes within r of the original. Boxes over its triangles
   answer that slowly where long thin triangles fan around a vertex: each box reaches from the
   centre to the rim, and every one near the query point holds it, so the work grows with the
   square of the valence. So the test has its own hierarchy: the triangles split (halving the
   longest edge) into fragments about as long as the thickest query, within a budget of four per
   triangle plus 1024, and every node carries, beside its box, a slab: the area-weighted mean
   normal n of its fragments and the interval of n.x over them. A point offset from the surface
   lies above the nearby nodes' slabs by about its offset and falls away from the far ones by
   their boxes. The answer is the exact distance test on the original triangles, as
   dm_bvh_closest_point takes it. */
typedef struct dm__sh_slab {
    float n[3], lo, hi;
} dm__sh_slab;

typedef struct dm__sh_near {
    dm_bvh *bvh;       /* over the fragments */
    dm__sh_slab *slab; /* per node of bvh */
    uint32_t *tri;     /* fragment -> triangle of the original */
    double slack;      /* covers the rounding of the fragments' corners to float */
} dm__sh_near;

#define DM__SH_SPLIT_DEPTH 6 /* at most 64 fragments a triangle */

/* The fragments of triangle (a, b, c), halving the longest edge until no edge is longer than
   len (sqrt(len2)): their count, and their corners into out (9 floats each) unless it is NULL. */
static size_t dm__sh_split(const double *a, const double *b, const double *c, double len2, int depth, float *out)
{
    const double *p[3];
    double e[3], m[3];
    size_t n;
    int k, j, longest = 0;
    p[0] = a; p[1] = b; p[2] = c;
    for (j = 0; j < 3; j++) {
        const double *u = p[j], *v = p[(j + 1) % 3];
        e[j] = (u[0] - v[0]) * (u[0] - v[0]) + (u[1] - v[1]) * (u[1] - v[1]) + (u[2] - v[2]) * (u[2] - v[2]);
        if (e[j] > e[longest]) longest = j;
    }
    if (!(e[longest] > len2) || depth >= DM__SH_SPLIT_DEPTH) {
        if (out)
            for (j = 0; j < 3; j++)
                for (k = 0; k < 3; k++) out[3 * j + k] = (float)p[j][k];
        return 1;
    }
    a = p[longest]; b = p[(longest + 1) % 3]; c = p[(longest + 2) % 3]; /* a b is the longest edge */
    for (k = 0; k < 3; k++) m[k] = 0.5 * (a[k] + b[k]);
    n = dm__sh_split(a, m, c, len2, depth + 1, out);
    return n + dm__sh_split(m, b, c, len2, depth + 1, out ? out + 9 * n : NULL);
}

/* every triangle's fragments at length len: their count (stops counting past limit), and into
   out (when not NULL) their corners, with their triangles into tri */
static size_t dm__sh_fragments(const dm__sh_run *r, double len, size_t limit, float *out, uint32_t *tri)
{
    size_t t, n = 0;
    for (t = 0; t < r->nt && n <= limit; t++) {
        double p[3][3];
        size_t m, j;
        int c, k;
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) p[c][k] = r->pos[3 * (size_t)r->idx[3 * t + (size_t)c] + (size_t)k];
        m = dm__sh_split(p[0], p[1], p[2], len * len, 0, out ? out + 9 * n : NULL);
        if (tri)
            for (j = 0; j < m; j++) tri[n + j] = (uint32_t)t;
        n += m;
    }
    return n;
}

/* The fragment length: the thickness, or longer when the fragments would exceed the budget
   (started where the sum of longest edges, or of areas, says it must be). */
static double dm__sh_fragment_length(const dm__sh_run *r, size_t budget)
{
    double len = r->sh->thickness, sum_long = 0.0, sum_area = 0.0;
    size_t t;
    for (t = 0; t < r->nt; t++) {
        double p[3][3], e[3], x[3], l2 = 0.0;
        int c, k;
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++) p[c][k] = r->pos[3 * (size_t)r->idx[3 * t + (size_t)c] + (size_t)k];
        for (c = 0; c < 3; c++) {
            double d2 = 0.0;
            for (k = 0; k < 3; k++) d2 += (p[(c + 1) % 3][k] - p[c][k]) * (p[(c + 1) % 3][k] - p[c][k]);
            if (d2 > l2) l2 = d2;
        }
        for (k = 0; k < 3; k++) { e[k] = p[1][k] - p[0][k]; x[k] = p[2][k] - p[0][k]; }
        sum_long += sqrt(l2);
        {
            double cr[3];
            dm__cross3(e, x, cr);
            sum_area += 0.5 * sqrt(dm__dot3(cr, cr));
        }
    }
    if (2.0 * sum_long / (double)budget > len) len = 2.0 * sum_long / (double)budget;
    if (sqrt(2.0 * sum_area / (double)budget) > len) len = sqrt(2.0 * sum_area / (double)budget);
    if (!(len > 0.0)) len = r->diag > 0.0 ? r->diag : 1.0;
    while (dm__sh_fragments(r, len, budget, NULL, NULL) > budget && len < 4.0 * r->diag) len *= 2.0;
    return len;
}

/* the slabs, children before parents: a leaf's from its fragments' corners, an inner node's
   normal from its children's area sums and its interval from the fragments below it (their
   blocks are a contiguous run) */
static dm_result dm__sh_slabs(dm__sh_run *r, dm__sh_near *nr)
{
    const dm_bvh *bvh = nr->bvh;
    size_t ns = bvh->node_slots, i;
    double *area = (double *)dm__take(&r->sc, 3 * ns, sizeof(double));
    uint32_t *run = (uint32_t *)dm__take(&r->sc, 2 * ns, sizeof(uint32_t));
    if (!area || !run) return dm__scratch_fail(&r->sc);
    for (i = ns; i-- > 0;) {
        const dm__node *n = &bvh->nodes[i];
        double s[3] = {0.0, 0.0, 0.0}, len, lo = DBL_MAX, hi = -DBL_MAX, nn[3];
        size_t b;
        int k;
        if (i == 1) continue; /* the padding slot */
        if (n->count) {
            run[2 * i] = n->first >> 2;
            run[2 * i + 1] = (n->first >> 2) + ((n->count + 3) >> 2);
            for (b = run[2 * i]; b < run[2 * i + 1]; b++) {
                int l;
                for (l = 0; l < 4; l++) {
                    double u[3], v[3], cr[3];
                    const dm__tri4 *q = &bvh->blocks[b];
                    if (q->id[l] == DM_NO_HIT) continue;
                    for (k = 0; k < 3; k++) {
                        u[k] = (double)q->v[3 + k][l] - q->v[k][l];
                        v[k] = (double)q->v[6 + k][l] - q->v[k][l];
                    }
                    dm__cross3(u, v, cr);
                    for (k = 0; k < 3; k++) s[k] += cr[k];
                }
            }
        } else {
            uint32_t c0 = n->first, c1 = n->first + 1;
            run[2 * i] = run[2 * c0] < run[2 * c1] ? run[2 * c0] : run[2 * c1];
            run[2 * i + 1] = run[2 * c0 + 1] > run[2 * c1 + 1] ? run[2 * c0 + 1] : run[2 * c1 + 1];
            for (k = 0; k < 3; k++) s[k] = area[3 * c0 + k] + area[3 * c1 + k];
        }
        for (k = 0; k < 3; k++) area[3 * i + k] = s[k];
        len = sqrt(dm__dot3(s, s));
        for (k = 0; k < 3; k++) nr->slab[i].n[k] = (float)(len > 0.0 ? s[k] / len : 0.0);
        for (k = 0; k < 3; k++) nn[k] = nr->slab[i].n[k]; /* the interval is of the float normal's n.x */
        for (b = run[2 * i]; b < run[2 * i + 1]; b++) {
            const dm__tri4 *q = &bvh->blocks[b];
            int l, c;
            for (l = 0; l < 4; l++)
                for (c = 0; c < 3 && q->id[l] != DM_NO_HIT; c++) {
                    double d = nn[0] * q->v[3 * c][l] + nn[1] * q->v[3 * c + 1][l] + nn[2] * q->v[3 * c + 2][l];
                    if (d < lo) lo = d;
                    if (d > hi) hi = d;
                }
        }
        /* widened by the fragments' corner rounding (|n|_1 <= sqrt 3 times the slack) */
        nr->slab[i].lo = len > 0.0 ? (float)(lo - 2.0 * nr->slack) : 0.0f;
        nr->slab[i].hi = len > 0.0 ? (float)(hi + 2.0 * nr->slack) : 0.0f;
    }
    return DM_OK;
}

/* the growth test's hierarchy over the original (above) */
static dm_result dm__sh_near_build(dm__sh_run *r, dm__sh_near *nr)
{
    size_t budget = 4 * r->nt + 1024, nf, i;
    double len = dm__sh_fragment_length(r, budget), ext = 0.0;
    float *fp;
    uint32_t *fi;
    dm_bvh_options bo;
    dm_result res;
    int k;
    memset(nr, 0, sizeof *nr);
    nf = dm__sh_fragments(r, len, (size_t)-1, NULL, NULL);
    nr->tri = (uint32_t *)dm__take(&r->sc, nf, sizeof(uint32_t));
    fp = (float *)dm__alloc_array(&r->a, 9 * nf, sizeof(float), &r->sc.overflow); /* the BVH copies them */
    fi = (uint32_t *)dm__alloc_array(&r->a, 3 * nf, sizeof(uint32_t), &r->sc.overflow);
    if (!fp || !fi || !nr->tri) {
        if (fp) r->a.free(r->a.user, fp);
        if (fi) r->a.free(r->a.user, fi);
        return dm__scratch_fail(&r->sc);
    }
    dm__sh_fragments(r, len, (size_t)-1, fp, nr->tri);
    for (i = 0; i < 3 * nf; i++) fi[i] = (uint32_t)i;
    for (k = 0; k < 3; k++) {
        if (fabs(r->lo[k]) > ext) ext = fabs(r->lo[k]);
        if (fabs(r->hi[k]) > ext) ext = fabs(r->hi[k]);
    }
    nr->slack = 8.0 * FLT_EPSILON * ext; /* a fragment's float corners lie this close to its triangle */
    memset(&bo, 0, sizeof bo);
    bo.allocator = r->opt.allocator;
    res = dm_bvh_build(fp, 3 * nf, fi, nf, &bo, &nr->bvh);
    r->a.free(r->a.user, fp);
    r->a.free(r->a.user, fi);
    if (res != DM_OK) return res;
    nr->slab = (dm__sh_slab *)dm__take(&r->sc, nr->bvh->node_slots, sizeof(dm__sh_slab));
    if (!nr->slab) return dm__scratch_fail(&r->sc);
    return dm__sh_slabs(r, nr);
}

/* Does q come closer than rad to the original: is there a triangle t with (float)sqrt(d2) < rad,
   d2 its squared distance (dm__triangle_d2)? That is dm_bvh_closest_point's answer with
   max_distance rad, compared with rad. */
static int dm__sh_near_hit(const dm__sh_near *nr, const float *pos, const uint32_t *idx, const float qf[3], float rad)
{
    const dm_bvh *bvh = nr->bvh;
    uint32_t stack[DM__STACK + 2], ni = 0;
    double q[3], reach = (double)rad + nr->slack, reach2 = reach * reach;
    size_t sp = 0;
    int k;
    for (k = 0; k < 3; k++) q[k] = qf[k];
    stack[sp++] = 0;
    while (sp) {
        const dm__node *n;
        const dm__sh_slab *s;
        double d;
        ni = stack[--sp];
        n = &bvh->nodes[ni];
        s = &nr->slab[ni];
        DM_COUNT_OPS(1);
        if (dm__box_d2(n, q) > reach2) continue;
        d = s->n[0] * q[0] + s->n[1] * q[1] + s->n[2] * q[2];
        if (d - s->hi > reach || s->lo - d > reach) continue;
        if (n->count) {
            uint32_t i;
            for (i = n->first; i < n->first + n->count; i++) {
                uint32_t f = bvh->blocks[i >> 2].id[i & 3];
                float tri[9];
                double u, v, td[9];
                int k;
                DM_COUNT_OPS(1);
                dm__load_triangle(pos, idx, nr->tri[f], tri);
                for (k = 0; k < 9; k++) td[k] = tri[k];
                if ((float)sqrt(dm__triangle_d2(q, td, &u, &v)) < rad) return 1;
            }
        } else { /* the depth is below DM__STACK (dm__build) */
            stack[sp++] = n->first + 1;
            stack[sp++] = n->first;
        }
    }
    return 0;
}

/* How far from the original a vertex's own neighbourhood lets its offset point lie, per unit of
   offset: 1 where the surface is convex or flat, the smallest cosine between the vertex normal and
   an adjacent face's normal where it is concave (the offset point is nearer those faces' planes),
   at least DM__SH_CONCAVE. Growth compares the distance with this, so that a concave vertex stops
   where another part comes near, not at its first step. */
#define DM__SH_CONCAVE 0.75f
static void dm__sh_local_reach(const dm__sh_run *r, float *near)
{
    size_t v, t;
    int j, k;
    for (v = 0; v < r->nv; v++) near[v] = 1.0f;
    for (t = 0; t < r->nt; t++) {
        const uint32_t *tv = r->idx + 3 * t;
        double p[3][3], fn[3], e1[3], e2[3], len;
        for (j = 0; j < 3; j++) dm__load3(r->pos, tv[j], p[j]);
        dm__sub3(p[1], p[0], e1);
        dm__sub3(p[2], p[0], e2);
        dm__cross3(e1, e2, fn);
        len = dm__len3(fn);
        if (!(len > 0.0)) continue;
        for (k = 0; k < 3; k++) fn[k] /= len;
        for (j = 0; j < 3; j++) {
            const float *n = r->sh->normals + 3 * (size_t)tv[j];
            double c = 0.0, e[3];
            float cf;
            /* concave at this corner: the other corners lie on the normal's side of the tangent plane */
            for (k = 0; k < 3; k++) e[k] = p[(j + 1) % 3][k] + p[(j + 2) % 3][k] - 2.0 * p[j][k];
            if (e[0] * n[0] + e[1] * n[1] + e[2] * n[2] <= 0.0) continue;
            for (k = 0; k < 3; k++) c += (double)n[k] * fn[k];
            cf = (float)c < DM__SH_CONCAVE ? DM__SH_CONCAVE : (float)c;
            if (cf < near[tv[j]]) near[tv[j]] = cf;
        }
    }
}

/* Growth (Cohen et al. 1996, in steps of thickness / steps): every vertex moves out along its
   normal; a vertex whose next offset point comes closer to the original than 90% of what its own
   faces allow (dm__sh_local_reach) would make the offset surface run into another part, and
   stops. Then the shell's positions. */
static dm_result dm__sh_grow_offsets(dm__sh_run *r)
{
    dm_shell *sh = r->sh;
    const float *pos = r->pos;
    uint8_t *stopped = r->stopped;
    int steps = r->opt.steps == 0 ? 8 : r->opt.steps > 256 ? 256 : r->opt.steps, step, k;
    size_t v, nv = r->nv;
    dm__sh_near nr;
    float *near = (float *)dm__take(&r->sc, nv, sizeof(float));
    dm_result res;
    memset(&nr, 0, sizeof nr);
    res = near ? dm__sh_near_build(r, &nr) : dm__scratch_fail(&r->sc);
    if (res != DM_OK) {
        dm_bvh_free(nr.bvh);
        return res;
    }
    for (v = 0; v < nv; v++) {
        sh->offset[v] = 0.0f;
        stopped[v] = sh->normals[3 * v] == 0.0f && sh->normals[3 * v + 1] == 0.0f && sh->normals[3 * v + 2] == 0.0f;
    }
    dm__sh_local_reach(r, near);
    for (step = 1; step <= steps; step++) {
        float h = sh->thickness * (float)step / (float)steps;
        for (v = 0; v < nv; v++) {
            float q[3];
            if (stopped[v]) continue;
            for (k = 0; k < 3; k++) q[k] = pos[3 * v + (size_t)k] + h * sh->normals[3 * v + (size_t)k];
            if (dm__sh_near_hit(&nr, pos, r->idx, q, 0.9f * h * near[v])) {
                stopped[v] = 1;
                sh->stopped_vertices++;
            } else {
                sh->offset[v] = h;
            }
        }
        if (r->opt.progress && r->opt.progress(r->opt.progress_user, (float)step / (float)steps)) {
            dm_bvh_free(nr.bvh);
            return DM_CANCELLED;
        }
    }
    dm_bvh_free(nr.bvh);
    for (v = 0; v < nv; v++)
        for (k = 0; k < 3; k++) sh->positions[3 * v + (size_t)k] = pos[3 * v + (size_t)k] + sh->offset[v] * sh->normals[3 * v + (size_t)k];
    return DM_OK;
}

DMDEF dm_shell_options dm_shell_default_options(void)
{
    dm_shell_options o; /* thickness 0: 2% of the original's diagonal, which only the call knows */
    memset(&o, 0, sizeof o);
    o.steps = 8;
    o.overlap_samples = 4;
    return o;
}

DMDEF dm_result dm_shell_grow(const float *pos, size_t nv, const uint32_t *idx, size_t nt,
                              const dm_shell_options *options, dm_shell **out)
{
    dm__sh_run r;
    dm_result res;
    if (!out) return DM_ERR_INVALID_ARGUMENT;
    *out = NULL;
    memset(&r, 0, sizeof r);
    if (options) r.opt = *options;
    if (!(r.opt.thickness >= 0.0f) || r.opt.thickness > 1e18f || r.opt.steps < 0 || r.opt.overlap_samples < 0)
        return DM_ERR_INVALID_ARGUMENT;
    res = dm__check_mesh(pos, nv, idx, nt);
    if (res != DM_OK) return res;
    r.pos = pos; r.nv = nv; r.idx = idx; r.nt = nt;
    r.a = dm__resolve_allocator(r.opt.allocator);
    r.sc.a = r.a;
    dm__sh_bounds(&r);
    res = dm__sh_alloc(&r);                          /* the shell, a copy of the original */
    if (res == DM_OK) res = dm__sh_normals(&r);      /* BVH, vertex normals, open or closed */
    if (res == DM_OK) res = dm__sh_vertex_grid(&r);  /* the original's vertices by cell */
    if (res == DM_OK) res = dm__sh_grow_offsets(&r); /* every vertex out along its normal */
    dm__release(&r.sc);
    if (res != DM_OK) {
        dm_shell_free(r.sh);
        return res;
    }
    *out = r.sh;
    return DM_OK;
}

/* unit normal of triangle (p0, p1, p2); 0 if degenerate */
static int dm__sh_plane(const double *p0, const double *p1, const double *p2, double n[3])
{
    double e1[3], e2[3], len;
    dm__sub3(p1, p0, e1);
    dm__sub3(p2, p0, e2);
    dm__cross3(e1, e2, n);
    len = dm__len3(n);
    if (!(len > 0.0)) return 0;
    n[0] /= len; n[1] /= len; n[2] /= len;
    return 1;
}

/* the position of vertex v during a candidate: keep at x, the rest at positions */
static void dm__sh_at(const dm_collapse *c, uint32_t v, const double x[3], double out[3])
{
    if (v == c->keep) {
        out[0] = x[0]; out[1] = x[1]; out[2] = x[2];
    } else {
        dm__load3(c->positions, v, out);
    }
}

static int dm__sh_grow_scratch(dm_shell *sh, dm__sh_internal *in, size_t need)
{
    double *p;
    int overflow = 0;
    if (need <= in->scratch_cap) return 1;
    p = (double *)dm__alloc_array(&sh->allocator, 2 * need, sizeof(double), &overflow);
    if (!p) return 0;
    sh->allocator.free(sh->allocator.user, in->scratch);
    in->scratch = p;
    in->scratch_cap = 2 * need;
    return 1;
}

/* The angle-weighted unit normal that triangle t (keep at x) adds to its corner j's vertex. */
static void dm__sh_contrib(const dm_collapse *c, const uint32_t *t, int j, const double x[3], double out[3])
{
    double p[3][3], n[3], ang;
    int k;
    out[0] = out[1] = out[2] = 0.0;
    for (k = 0; k < 3; k++) dm__sh_at(c, t[k], x, p[k]);
    if (!dm__sh_plane(p[0], p[1], p[2], n)) return;
    ang = dm__corner_angle((const double(*)[3])p, j);
    if (ang < 0.0) return;
    for (k = 0; k < 3; k++) out[k] = ang * n[k];
}

/* A call at level 0 after one at a higher level, or after collapses were followed: a new
   dm_simplify run on the original, so the followed normals, the counters and the verdicts go
   back to the state dm_shell_grow left. */
static void dm__sh_run_check(dm_shell *sh, dm__sh_internal *in, size_t level)
{
    if (level == 0 && (in->collapsed > 0 || in->last_level > 0)) {
        dm__vertex_normals(in->pos, in->nv, in->idx, in->nt, in->vsum, sh->normals);
        in->collapsed = in->accepted = 0;
        in->placed_valid = 0;
        sh->moved = sh->vetoed_enclose = sh->vetoed_shell = sh->vetoed_overlap = 0;
        sh->fallback = 0;
        sh->fallback_collapses = 0;
        memset(sh->fallback_vertex, 0, in->nv);
        if (in->proof) memset(in->proof, 0, DM__SH_PROOFS * 8 * sizeof(uint32_t)); /* a run owes nothing to the last */
    }
    in->last_level = level;
}

DMDEF void dm_shell_collapsed(void *user, const dm_collapse *done)
{
    dm_shell *sh = (dm_shell *)user;
    dm__sh_internal *in;
    double xk[3], xn[3], d[3];
    size_t i;
    int j, k;
    if (!sh || !done || !sh->internal || !done->positions || !done->triangles || !done->old_triangles) return;
    in = (dm__sh_internal *)sh->internal;
    if (done->keep >= in->nv || done->remove >= in->nv) return;
    dm__sh_run_check(sh, in, done->level);
    in->collapsed++;
    if (in->relaxed_keep == done->keep && in->relaxed_level == done->level) { /* set only when relaxed */
        sh->fallback_vertex[done->keep] = 1;
        sh->fallback_collapses++;
    }
    in->relaxed_keep = UINT32_MAX;
    dm__load3(done->positions, done->keep, xk);
    for (k = 0; k < 3; k++) xn[k] = done->position[k];
    for (i = 0; i < done->old_triangle_count; i++)
        for (j = 0; j < 3; j++) {
            uint32_t w = done->old_triangles[3 * i + (size_t)j];
            if (w >= in->nv) continue;
            dm__sh_contrib(done, done->old_triangles + 3 * i, j, xk, d);
            for (k = 0; k < 3; k++) in->vsum[3 * (size_t)w + (size_t)k] -= d[k];
        }
    for (i = 0; i < done->triangle_count; i++)
        for (j = 0; j < 3; j++) {
            uint32_t w = done->triangles[3 * i + (size_t)j];
            if (w >= in->nv) continue;
            dm__sh_contrib(done, done->triangles + 3 * i, j, xn, d);
            for (k = 0; k < 3; k++) in->vsum[3 * (size_t)w + (size_t)k] += d[k];
        }
}

/* Sample points of the overlap check, barycentric: the centroid, then towards each corner. */
static const double dm__sh_bary[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {4.0 / 6, 1.0 / 6, 1.0 / 6},
                                         {1.0 / 6, 4.0 / 6, 1.0 / 6}, {1.0 / 6, 1.0 / 6, 4.0 / 6},
                                         {1.0 / 6, 5.0 / 12, 5.0 / 12}, {5.0 / 12, 1.0 / 6, 5.0 / 12},
                                         {5.0 / 12, 5.0 / 12, 1.0 / 6}};

/* Is point y inside the shell: within the offset grown at its closest point of the original? */
static int dm__sh_in_shell(const dm_shell *sh, const dm__sh_internal *in, const double y[3])
{
    float q[3];
    dm_closest cl;
    const uint32_t *t;
    double h;
    q[0] = (float)y[0]; q[1] = (float)y[1]; q[2] = (float)y[2];
    if (!dm_bvh_closest_point(in->bvh, q, sh->thickness * 1.0001f + (float)in->margin, &cl)) return 0;
    t = in->idx + 3 * (size_t)cl.triangle;
    h = (1.0 - cl.u - cl.v) * sh->offset[t[0]] + cl.u * sh->offset[t[1]] + cl.v * sh->offset[t[2]];
    return cl.distance <= h + in->margin;
}

/* Fills 16 floats per triangle (its corners, keep at x, a bounding sphere, the unit normal or 0)
   into out. (A table of doubles holding these float values would be as good, but GCC 12.2's SLP
   vectoriser drops (double)(float) round trips from such stores: the bits would then depend on
   the compiler.) */
static void dm__sh_tris(const dm_collapse *c, const uint32_t *tris, size_t n, const double x[3], double *out)
{
    size_t i;
    int j, k;
    for (i = 0; i < n; i++) {
        double *f = out + 16 * i;
        double p[3][3], r2 = 0.0, n[3];
        for (j = 0; j < 3; j++) {
            dm__sh_at(c, tris[3 * i + (size_t)j], x, p[j]);
            for (k = 0; k < 3; k++) f[3 * j + k] = (float)p[j][k];
        }
        for (k = 0; k < 3; k++) f[9 + k] = (float)((p[0][k] + p[1][k] + p[2][k]) / 3.0);
        for (j = 0; j < 3; j++) {
            double d2 = 0.0;
            for (k = 0; k < 3; k++) d2 += (p[j][k] - f[9 + k]) * (p[j][k] - f[9 + k]);
            if (d2 > r2) r2 = d2;
        }
        f[12] = (float)(sqrt(r2) * (1.0 + 1e-6)) + 1e-30f;
        if (!dm__sh_plane(p[0], p[1], p[2], n)) n[0] = n[1] = n[2] = 0.0;
        for (k = 0; k < 3; k++) f[13 + k] = (float)n[k];
    }
}


#if defined(DM_USE_AVX2)
/* dm__triangle_d2 in four lanes (one triangle, four points): corners A, B, C (AB = B - A and
   AC = C - A as dm__triangle_d2 takes them) and points P; the
   squared distances, with (u, v) and va + vb + vc (not positive: degenerate) into *t. Each lane
   does dm__triangle_d2's operations in its order (the region's one quotient; no contraction), so
   the same bits. */
DM__INLINE __m256d dm__sh_d2v(const __m256d A[3], const __m256d B[3], const __m256d C[3], const __m256d AB[3],
                              const __m256d AC[3], const __m256d P[3], __m256d *u, __m256d *v, __m256d *t)
{
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
    __m256d ap[3], bp[3], cp[3], d1, d2, d3, d4, d5, d6, va, vb, vc, e43, e56, num, den, r, m;
    __m256d mA, mB, mAB, mC, mAC, mBC, dist = zero;
    int k;
    for (k = 0; k < 3; k++) {
        ap[k] = _mm256_sub_pd(P[k], A[k]);
        bp[k] = _mm256_sub_pd(P[k], B[k]);
        cp[k] = _mm256_sub_pd(P[k], C[k]);
    }
#define DM__DOT4(x, y) \
    _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x[0], y[0]), _mm256_mul_pd(x[1], y[1])), _mm256_mul_pd(x[2], y[2]))
#define DM__LE(x, y) _mm256_cmp_pd(x, y, _CMP_LE_OQ)
#define DM__GE(x, y) _mm256_cmp_pd(x, y, _CMP_GE_OQ)
    d1 = DM__DOT4(AB, ap); d2 = DM__DOT4(AC, ap); d3 = DM__DOT4(AB, bp);
    d4 = DM__DOT4(AC, bp); d5 = DM__DOT4(AB, cp); d6 = DM__DOT4(AC, cp);
    vc = _mm256_sub_pd(_mm256_mul_pd(d1, d4), _mm256_mul_pd(d3, d2));
    vb = _mm256_sub_pd(_mm256_mul_pd(d5, d2), _mm256_mul_pd(d1, d6));
    va = _mm256_sub_pd(_mm256_mul_pd(d3, d6), _mm256_mul_pd(d5, d4));
    *t = _mm256_add_pd(_mm256_add_pd(va, vb), vc);
    e43 = _mm256_sub_pd(d4, d3);
    e56 = _mm256_sub_pd(d5, d6);
    mA = _mm256_and_pd(DM__LE(d1, zero), DM__LE(d2, zero)); /* the regions, as dm__triangle_d2 asks */
    mB = _mm256_and_pd(DM__GE(d3, zero), DM__LE(d4, d3));
    mAB = _mm256_and_pd(DM__LE(vc, zero), _mm256_and_pd(DM__GE(d1, zero), DM__LE(d3, zero)));
    mC = _mm256_and_pd(DM__GE(d6, zero), DM__LE(d5, d6));
    mAC = _mm256_and_pd(DM__LE(vb, zero), _mm256_and_pd(DM__GE(d2, zero), DM__LE(d6, zero)));
    mBC = _mm256_and_pd(DM__LE(va, zero), _mm256_and_pd(DM__GE(e43, zero), DM__GE(e56, zero)));
#undef DM__DOT4
#undef DM__LE
#undef DM__GE
    mB = _mm256_andnot_pd(mA, mB); /* a later region only where no earlier one holds */
    mAB = _mm256_andnot_pd(_mm256_or_pd(mA, mB), mAB);
    m = _mm256_or_pd(_mm256_or_pd(mA, mB), mAB);
    mC = _mm256_andnot_pd(m, mC);
    m = _mm256_or_pd(m, mC);
    mAC = _mm256_andnot_pd(m, mAC);
    m = _mm256_or_pd(m, mAC);
    mBC = _mm256_andnot_pd(m, mBC);
    m = _mm256_or_pd(m, mBC); /* any edge or vertex region; else inside: 1 / t */
    num = _mm256_blendv_pd(one, e43, mBC);
    den = _mm256_blendv_pd(*t, _mm256_add_pd(e43, e56), mBC);
    num = _mm256_blendv_pd(num, d2, mAC);
    den = _mm256_blendv_pd(den, _mm256_sub_pd(d2, d6), mAC);
    num = _mm256_blendv_pd(num, d1, mAB);
    den = _mm256_blendv_pd(den, _mm256_sub_pd(d1, d3), mAB);
    r = _mm256_div_pd(num, den);
    *u = _mm256_blendv_pd(_mm256_mul_pd(vb, r), zero, m);
    *v = _mm256_blendv_pd(_mm256_mul_pd(vc, r), zero, m);
    *u = _mm256_blendv_pd(_mm256_blendv_pd(*u, one, mB), r, mAB);
    *u = _mm256_blendv_pd(*u, _mm256_sub_pd(one, r), mBC);
    *v = _mm256_blendv_pd(_mm256_blendv_pd(_mm256_blendv_pd(*v, one, mC), r, mAC), r, mBC);
    for (k = 0; k < 3; k++) {
        __m256d q = _mm256_add_pd(_mm256_add_pd(A[k], _mm256_mul_pd(*u, AB[k])), _mm256_mul_pd(*v, AC[k]));
        __m256d w = _mm256_sub_pd(P[k], q);
        dist = k == 0 ? _mm256_mul_pd(w, w) : _mm256_add_pd(dist, _mm256_mul_pd(w, w));
    }
    return dist;
}

/* dm__sh_nearest for four points at once (p: 3 doubles each), one triangle of tf in the four
   lanes at a time, triangle `hint` first: each lane keeps the nearest, of equally near ones the
   first, skipping (as dm__sh_nearest does) the triangles whose bounding sphere lies beyond every
   lane's best. dm__sh_nearest's answers into bt, d2, bu and bv. */
static void dm__sh_nearest4_avx2(const double *tf, size_t n, const double *p, double best, size_t hint, size_t bt[4],
                                 double d2[4], double bu[4], double bv[4])
{
    const __m256d zero = _mm256_setzero_pd(), rb0 = _mm256_set1_pd(best < DBL_MAX ? sqrt(best) : 1e150);
    __m256d P[3], bd = _mm256_set1_pd(HUGE_VAL), bi = _mm256_set1_pd(-1.0), bU = zero, bV = zero, rb = rb0;
    double di[4], dd[4];
    size_t i, j;
    int k, l;
    for (k = 0; k < 3; k++) P[k] = _mm256_set_pd(p[9 + k], p[6 + k], p[3 + k], p[k]);
    for (j = 0; j <= n; j++) {
        const double *f;
        __m256d A[3], B[3], C[3], AB[3], AC[3], u, v, t, m, dist, iv, cs, e;
        int deg;
        if (j == 0 && !(hint < n)) continue;
        i = j == 0 ? hint : j - 1;
        if (j > 0 && i == hint) continue;
        f = tf + 16 * i;
        cs = zero;
        for (k = 0; k < 3; k++) {
            e = _mm256_sub_pd(P[k], _mm256_set1_pd(f[9 + k]));
            cs = k == 0 ? _mm256_mul_pd(e, e) : _mm256_add_pd(cs, _mm256_mul_pd(e, e));
        }
        e = _mm256_add_pd(rb, _mm256_set1_pd(f[12]));
        if (_mm256_movemask_pd(_mm256_cmp_pd(cs, _mm256_mul_pd(e, e), _CMP_GT_OQ)) == 15) continue;
        for (k = 0; k < 3; k++) {
            A[k] = _mm256_set1_pd(f[k]);
            B[k] = _mm256_set1_pd(f[3 + k]);
            C[k] = _mm256_set1_pd(f[6 + k]);
            AB[k] = _mm256_set1_pd(f[3 + k] - f[k]);
            AC[k] = _mm256_set1_pd(f[6 + k] - f[k]);
        }
        dist = dm__sh_d2v(A, B, C, AB, AC, P, &u, &v, &t);
        deg = _mm256_movemask_pd(_mm256_cmp_pd(t, zero, _CMP_NGT_UQ));
        if (deg) { /* degenerate lanes: the edges' nearest, as dm__triangle_d2 */
            double dl[4], ul[4], vl[4];
            _mm256_storeu_pd(dl, dist); _mm256_storeu_pd(ul, u); _mm256_storeu_pd(vl, v);
            for (l = 0; l < 4; l++)
                if (deg >> l & 1) dl[l] = dm__triangle_d2(p + 3 * l, f, ul + l, vl + l);
            dist = _mm256_loadu_pd(dl); u = _mm256_loadu_pd(ul); v = _mm256_loadu_pd(vl);
        }
        iv = _mm256_set1_pd((double)i);
        m = _mm256_and_pd(_mm256_cmp_pd(dist, bd, _CMP_EQ_OQ), _mm256_cmp_pd(iv, bi, _CMP_LT_OQ));
        m = _mm256_or_pd(_mm256_cmp_pd(dist, bd, _CMP_LT_OQ), m); /* nearer, or as near and first */
        if (!_mm256_movemask_pd(m)) continue;
        bd = _mm256_blendv_pd(bd, dist, m);
        bi = _mm256_blendv_pd(bi, iv, m);
        bU = _mm256_blendv_pd(bU, u, m);
        bV = _mm256_blendv_pd(bV, v, m);
        rb = _mm256_min_pd(_mm256_sqrt_pd(bd), rb0);
    }
    _mm256_storeu_pd(dd, bd); _mm256_storeu_pd(di, bi); _mm256_storeu_pd(bu, bU); _mm256_storeu_pd(bv, bV);
    for (l = 0; l < 4; l++) {
        bt[l] = di[l] >= 0.0 && dd[l] <= best ? (size_t)di[l] : (size_t)-1;
        d2[l] = bt[l] == (size_t)-1 ? best : dd[l];
        if (bt[l] == (size_t)-1) bu[l] = bv[l] = 0.0;
    }
}
#endif

/* The nearest to p of n one-ring triangles (tf from dm__sh_tris) closer than max_dist: its index
   ((size_t)-1 if none), with the squared distance and the barycentric (u, v) of the closest point;
   of equally near ones the first. Triangle `hint` (a neighbour's answer, or (size_t)-1) is tried
   first, so that the others are mostly skipped by their bounding spheres and planes; the answer
   is the one a scan in order gives (with DM_USE_AVX2, dm__sh_nearest4_avx2 gives it for four). */
static size_t dm__sh_nearest(const double *tf, size_t n, const double p[3], double max_dist, size_t hint,
                             double *d2best, double *bu, double *bv)
{
    double best = max_dist < 1e150 ? max_dist * max_dist : DBL_MAX, rb = max_dist < 1e150 ? max_dist : 1e150;
    size_t i, k, bt = (size_t)-1;
    *bu = *bv = 0.0;
    for (k = 0; k <= n; k++) {
        const double *f;
        double u, v, d2, cs, pd, del;
        if (k == 0 && !(hint < n)) continue;
        i = k == 0 ? hint : k - 1;
        if (k > 0 && i == hint) continue;
        f = tf + 16 * i;
        cs = (p[0] - f[9]) * (p[0] - f[9]) + (p[1] - f[10]) * (p[1] - f[10]) + (p[2] - f[11]) * (p[2] - f[11]);
        if (cs > (rb + f[12]) * (rb + f[12])) continue; /* its bounding sphere lies beyond the best */
        pd = (p[0] - f[0]) * f[13] + (p[1] - f[1]) * f[14] + (p[2] - f[2]) * f[15];
        del = 3e-7 * (rb + 2.0 * f[12]); /* pd's error bound: the float unit normal is off by up to
                                           1.1e-7, times |p - a| <= |p - c| + r <= rb + 2 r */
        if (pd * pd * 0.99999 > best + (2.0 * rb + del) * del)
            continue; /* so does its plane (|pd| - del > rb): never a triangle as near as the best,
                         so the answer is the nearest whatever the order or the hint */
        d2 = dm__triangle_d2(p, f, &u, &v);
        if (d2 < best || (d2 == best && i < bt)) {
            best = d2;
            rb = sqrt(d2);
            bt = i;
            *bu = u;
            *bv = v;
        }
    }
    *d2best = best;
    return bt;
}

/* The closest feature on triangle bt at barycentric (bu, bv): its nf vertices into fv; returns 1
   when the feature touches keep (or, when with_remove, remove). */
static int dm__sh_feature(const dm_collapse *c, const uint32_t *tris, size_t bt, double bu, double bv,
                          int with_remove, uint32_t fv[3], int *nf)
{
    double w[3];
    int j, inner = 0;
    w[0] = 1.0 - bu - bv;
    w[1] = bu;
    w[2] = bv;
    *nf = 0;
    for (j = 0; j < 3; j++)
        if (w[j] > 1e-7) {
            fv[(*nf)++] = tris[3 * bt + (size_t)j];
            if (fv[*nf - 1] == c->keep || (with_remove && fv[*nf - 1] == c->remove)) inner = 1;
        }
    return inner;
}

/* The sign of p's distance dist to the one-ring at its closest feature fv (nf vertices) of
   triangle bt, taken with the angle-weighted pseudonormal (Baerentzen and Aanaes 2005) computed
   from these triangles only: +dist outside, -dist inside. */
static double dm__sh_sign(const uint32_t *tris, const double *tf, size_t n, size_t bt, double bu, double bv,
                          const uint32_t fv[3], int nf, const double p[3], double dist)
{
    double q[3], w[3], N[3] = {0.0, 0.0, 0.0}, pt[3][3], d[3];
    size_t i;
    int k, j;
    w[0] = 1.0 - bu - bv;
    w[1] = bu;
    w[2] = bv;
    for (j = 0; j < 3; j++)
        for (k = 0; k < 3; k++) pt[j][k] = tf[16 * bt + 3 * (size_t)j + (size_t)k];
    for (k = 0; k < 3; k++) q[k] = w[0] * pt[0][k] + w[1] * pt[1][k] + w[2] * pt[2][k];
    for (i = 0; i < n; i++) {
        const uint32_t *t = tris + 3 * i;
        double fn[3], ang = 1.0;
        int has = 0, corner = -1;
        for (j = 0; j < nf; j++)
            for (k = 0; k < 3; k++)
                if (t[k] == fv[j]) {
                    has++;
                    corner = k;
                }
        if (has < nf) continue;
        for (k = 0; k < 3; k++) fn[k] = tf[16 * i + 13 + (size_t)k];
        if (nf == 1) { /* vertex: weight by the corner angle */
            for (j = 0; j < 3; j++)
                for (k = 0; k < 3; k++) pt[j][k] = tf[16 * i + 3 * (size_t)j + (size_t)k];
            double ea[3], eb[3], la, lb2, cs;
            dm__sub3(pt[(corner + 1) % 3], pt[corner], ea);
            dm__sub3(pt[(corner + 2) % 3], pt[corner], eb);
            la = dm__len3(ea);
            lb2 = dm__len3(eb);
            if (!(la > 0.0 && lb2 > 0.0)) continue;
            cs = dm__dot3(ea, eb) / (la * lb2);
            ang = acos(cs < -1.0 ? -1.0 : cs > 1.0 ? 1.0 : cs);
        }
        for (k = 0; k < 3; k++) N[k] += ang * fn[k];
        if (nf == 3) break;
    }
    dm__sub3(p, q, d);
    return dm__dot3(d, N) > 0.0 ? dist : -dist;
}

/* Signed distance from p to the new one-ring (keep at its proposed position; -DBL_MAX when there
   is no triangle); *hint: the nearest triangle of a neighbouring point, then this one's. */
/* the same, given p's nearest new triangle bt (dm__sh_nearest's answer) */
static double dm__sh_signed_at(const dm_collapse *c, const double *tf, const double p[3], size_t bt, double d2,
                               double bu, double bv)
{
    uint32_t fv[3];
    int nf;
    if (bt == (size_t)-1) return -DBL_MAX;
    dm__sh_feature(c, c->triangles, bt, bu, bv, 0, fv, &nf);
    return dm__sh_sign(c->triangles, tf, c->triangle_count, bt, bu, bv, fv, nf, p, sqrt(d2));
}

static double dm__sh_signed_new(const dm_collapse *c, const double *tf, const double p[3], size_t *hint)
{
    double d2, bu, bv;
    size_t bt = dm__sh_nearest(tf, c->triangle_count, p, DBL_MAX, *hint, &d2, &bu, &bv);
    if (bt != (size_t)-1) *hint = bt;
    return dm__sh_signed_at(c, tf, p, bt, d2, bu, bv);
}

/* The box the enclosure check gathers original vertices from: the proposed position and the
   old triangles, grown by a tenth of their span; reach is how far from the old triangles a
   vertex still counts (1.5 thicknesses, at most the span: deeper than the one-ring is wide only
   where the base bridges a crevice, at coarse levels, whose rings are wide). */
typedef struct dm__sh_box {
    double lo[3], hi[3], reach, grow;
} dm__sh_box;

static void dm__sh_enclose_box(const dm_shell *sh, const dm__sh_internal *in, const dm_collapse *c, dm__sh_box *b)
{
    size_t i;
    double span;
    int k;
    b->reach = 1.5 * (double)sh->thickness;
    for (k = 0; k < 3; k++) b->lo[k] = b->hi[k] = c->position[k];
    for (i = 0; i < 3 * c->old_triangle_count; i++)
        for (k = 0; k < 3; k++) {
            double q = c->positions[3 * (size_t)c->old_triangles[i] + (size_t)k];
            if (q < b->lo[k]) b->lo[k] = q;
            if (q > b->hi[k]) b->hi[k] = q;
        }
    span = sqrt((b->hi[0] - b->lo[0]) * (b->hi[0] - b->lo[0]) + (b->hi[1] - b->lo[1]) * (b->hi[1] - b->lo[1]) +
                (b->hi[2] - b->lo[2]) * (b->hi[2] - b->lo[2]));
    if (span < b->reach) b->reach = span;
    b->grow = 0.1 * span + 4.0 * in->margin;
}

/* in->tri_new: old triangle i's other corners than keep and remove, found in a new triangle */
static void dm__sh_old_to_new(dm__sh_internal *in, const dm_collapse *c)
{
    size_t i, j;
    int k;
    for (i = 0; i < c->old_triangle_count; i++) {
        const uint32_t *t = c->old_triangles + 3 * i;
        uint32_t o[2];
        int n = 0;
        in->tri_new[i] = UINT32_MAX;
        for (k = 0; k < 3; k++)
            if (t[k] != c->keep && t[k] != c->remove && n < 2) o[n++] = t[k];
        for (j = 0; n == 2 && j < c->triangle_count; j++) {
            const uint32_t *u = c->triangles + 3 * j;
            int h = 0;
            for (k = 0; k < 3; k++) h += u[k] == o[0] || u[k] == o[1];
            if (h == 2) {
                in->tri_new[i] = (uint32_t)j;
                break;
            }
        }
    }
}

/* in->tri: the old triangles with keep where it is now, then the new ones with keep at x0; and
   in->tri_new; 0 when out of memory */
static int dm__sh_old_new_tris(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const double x0[3])
{
    size_t no = c->old_triangle_count, nr = c->triangle_count;
    double xk[3];
    if (no + nr > in->tri_cap) {
        int of = 0;
        double *nt2 = (double *)dm__alloc_array(&sh->allocator, 2 * (no + nr), 16 * sizeof(double), &of);
        uint32_t *nm = (uint32_t *)dm__alloc_array(&sh->allocator, 2 * (no + nr), sizeof(uint32_t), &of);
        if (!nt2 || !nm) {
            sh->allocator.free(sh->allocator.user, nt2);
            sh->allocator.free(sh->allocator.user, nm);
            return 0;
        }
        sh->allocator.free(sh->allocator.user, in->tri);
        sh->allocator.free(sh->allocator.user, in->tri_new);
        in->tri = nt2;
        in->tri_new = nm;
        in->tri_cap = 2 * (no + nr);
    }
    dm__load3(c->positions, c->keep, xk);
    dm__sh_tris(c, c->old_triangles, no, xk, in->tri);
    dm__sh_tris(c, c->triangles, nr, x0, in->tri + 16 * no);
    dm__sh_old_to_new(in, c);
    return 1;
}

/* pt appended to in->pts as entry npts; 0 when out of memory */
static int dm__sh_push_pt(dm_shell *sh, dm__sh_internal *in, size_t npts, const dm__sh_pt *pt)
{
    if (npts >= in->pts_cap) {
        dm__sh_pt *np2;
        int of = 0;
        size_t cap = in->pts_cap ? 2 * in->pts_cap : 1024;
        np2 = (dm__sh_pt *)dm__alloc_array(&sh->allocator, cap, sizeof(dm__sh_pt), &of);
        if (!np2) return 0;
        if (npts) memcpy(np2, in->pts, npts * sizeof(dm__sh_pt));
        sh->allocator.free(sh->allocator.user, in->pts);
        in->pts = np2;
        in->pts_cap = cap;
    }
    in->pts[npts] = *pt;
    return 1;
}

/* Is the original's vertex q (in cell order) relevant to candidate c: in the grown box b, within
   reach of the old triangles, its closest feature of them at keep or remove (not on the ring's
   rim)? 1 with pt filled (its nearest old triangle); *hint: the last point's nearest triangle, the
   next one is near it. */
static int dm__sh_in_box(const dm__sh_box *b, const double pp[3])
{
    const double *lo = b->lo, *hi = b->hi, grow = b->grow;
    return !(pp[0] < lo[0] - grow || pp[0] > hi[0] + grow || pp[1] < lo[1] - grow || pp[1] > hi[1] + grow ||
             pp[2] < lo[2] - grow || pp[2] > hi[2] + grow);
}

/* the rest of dm__sh_relevant, given q's nearest old triangle bt (dm__sh_nearest's answer) */
static int dm__sh_relevant_at(const dm__sh_internal *in, const dm_collapse *c, const dm__sh_box *b, uint32_t q,
                              size_t bt, double d2, double bu, double bv, dm__sh_pt *pt)
{
    uint32_t fv[3];
    int nf;
    if (bt == (size_t)-1 || sqrt(d2) > b->reach || !dm__sh_feature(c, c->old_triangles, bt, bu, bv, 1, fv, &nf))
        return 0; /* beyond reach, or closest to the ring's rim */
    memcpy(pt->p, in->cell_pos + 3 * (size_t)q, sizeof pt->p);
    pt->bt = (uint32_t)bt;
    pt->bu = bu;
    pt->nt = UINT32_MAX;
    pt->q = q;
    pt->bv = bv;
    pt->d2 = d2;
    return 1;
}

static int dm__sh_relevant(const dm__sh_internal *in, const dm_collapse *c, const dm__sh_box *b, uint32_t q,
                           size_t *hint, dm__sh_pt *pt)
{
    double pp[3], d2, bu, bv;
    size_t bt;
    dm__load3(in->cell_pos, q, pp);
    if (!dm__sh_in_box(b, pp)) return 0;
    bt = dm__sh_nearest(in->tri, c->old_triangle_count, pp, b->reach, *hint, &d2, &bu, &bv);
    if (bt != (size_t)-1) *hint = bt;
    return dm__sh_relevant_at(in, c, b, q, bt, d2, bu, bv, pt);
}

/* The box vertices waiting for their nearest old triangles (four at a time with DM_USE_AVX2). */
typedef struct dm__sh_batch {
    uint32_t q[4];
    double p[4][3];
    int n;
    size_t hint;
} dm__sh_batch;

/* the batch's relevant vertices appended to in->pts (*npts of them), in the batch's order; 0 when
   out of memory */
static int dm__sh_flush(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const dm__sh_box *b,
                        dm__sh_batch *bt, size_t *npts)
{
    size_t t[4];
    double d2[4], bu[4], bv[4];
    int j;
#if defined(DM_USE_AVX2)
    if (bt->n > 0) { /* all at once: the lanes past bt->n repeat the first and do not count */
        for (j = bt->n; j < 4; j++) memcpy(bt->p[j], bt->p[0], sizeof bt->p[0]);
        dm__sh_nearest4_avx2(in->tri, c->old_triangle_count, bt->p[0],
                             b->reach < 1e150 ? b->reach * b->reach : DBL_MAX, bt->hint, t, d2, bu, bv);
        if (t[bt->n - 1] != (size_t)-1) bt->hint = t[bt->n - 1];
    } else
#endif
        for (j = 0; j < bt->n; j++) {
            t[j] = dm__sh_nearest(in->tri, c->old_triangle_count, bt->p[j], b->reach, bt->hint, d2 + j, bu + j, bv + j);
            if (t[j] != (size_t)-1) bt->hint = t[j];
        }
    for (j = 0; j < bt->n; j++) {
        dm__sh_pt pt;
        if (!dm__sh_relevant_at(in, c, b, bt->q[j], t[j], d2[j], bu[j], bv[j], &pt)) continue;
        if (!dm__sh_push_pt(sh, in, *npts, &pt)) return 0;
        (*npts)++;
    }
    bt->n = 0;
    return 1;
}

/* the relevant original vertices (dm__sh_relevant), from the grid cells of the box: *npts of them
   in in->pts; 0 when out of memory */
static int dm__sh_gather(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const dm__sh_box *b, size_t *npts)
{
    dm__sh_batch bt;
    int cl[3], ch[3], cx, cy, cz, k;
    bt.n = 0;
    bt.hint = (size_t)-1;
    for (k = 0; k < 3; k++) {
        cl[k] = dm__sh_coord(in, b->lo[k] - b->grow, k);
        ch[k] = dm__sh_coord(in, b->hi[k] + b->grow, k);
    }
    for (cz = cl[2]; cz <= ch[2]; cz++)
        for (cy = cl[1]; cy <= ch[1]; cy++)
            for (cx = cl[0]; cx <= ch[0]; cx++) {
                size_t cell = ((size_t)cz * (size_t)in->dim[1] + (size_t)cy) * (size_t)in->dim[0] + (size_t)cx;
                uint32_t q;
                for (q = in->cell_first[cell]; q < in->cell_first[cell + 1]; q++) {
                    dm__load3(in->cell_pos, q, bt.p[bt.n]);
                    if (!dm__sh_in_box(b, bt.p[bt.n])) continue;
                    bt.q[bt.n++] = q;
                    if (bt.n == 4 && !dm__sh_flush(sh, in, c, b, &bt, npts)) return 0;
                }
            }
    return dm__sh_flush(sh, in, c, b, &bt, npts);
}

/* The plane of relevant vertex pt, from its nearest new triangle (keep, u, w) at the proposed
   position (kept in its nt): through p, u and w, pushed out by 2 margins (4 doubles into out);
   keep must lie on its outer side. 0 when there is none: a void plane (zero normal, offset
   -DBL_MAX) that any position meets. *hint: the last point's nearest new triangle. */
static int dm__sh_plane_at(const dm__sh_internal *in, const dm_collapse *c, dm__sh_pt *pt, size_t t, double out[4]);
static int dm__sh_plane_of(const dm__sh_internal *in, const dm_collapse *c, dm__sh_pt *pt, size_t *hint, double out[4])
{
    double pp[3], d2, bu, bv;
    size_t t, no = c->old_triangle_count;
    dm__load3(pt->p, 0, pp);
    if (in->tri_new[pt->bt] != UINT32_MAX) *hint = in->tri_new[pt->bt]; /* the same answer, sooner */
    t = dm__sh_nearest(in->tri + 16 * no, c->triangle_count, pp, DBL_MAX, *hint, &d2, &bu, &bv);
    if (t != (size_t)-1) *hint = t;
    return dm__sh_plane_at(in, c, pt, t, out);
}

/* the rest of dm__sh_plane_of, given pt's nearest new triangle t (or (size_t)-1) */
static int dm__sh_plane_at(const dm__sh_internal *in, const dm_collapse *c, dm__sh_pt *pt, size_t t, double out[4])
{
    double pp[3], pu[3], pw[3], A[3], len;
    int j, k;
    const uint32_t *tr;
    out[0] = out[1] = out[2] = 0.0;
    out[3] = -DBL_MAX;
    dm__load3(pt->p, 0, pp);
    pt->nt = t == (size_t)-1 ? UINT32_MAX : (uint32_t)t;
    if (t == (size_t)-1) return 0;
    tr = c->triangles + 3 * t;
    for (j = 0; j < 3 && tr[j] != c->keep; j++) {}
    if (j == 3) return 0;
    dm__load3(c->positions, tr[(j + 1) % 3], pu);
    dm__load3(c->positions, tr[(j + 2) % 3], pw);
    dm__sub3(pu, pp, pu);
    dm__sub3(pw, pp, pw);
    dm__cross3(pu, pw, A);
    len = dm__len3(A);
    if (!(len > 0.0)) return 0;
    for (k = 0; k < 3; k++) out[k] = A[k] / len;
    out[3] = dm__dot3(out, pp) + 2.0 * in->margin;
    return 1;
}

/* one plane per relevant vertex (dm__sh_plane_of; with DM_USE_AVX2 four searches at a time), in
   their order: 4 doubles each into pl */
static void dm__sh_planes(dm__sh_internal *in, const dm_collapse *c, size_t npts, double *pl)
{
    size_t i = 0, hint = (size_t)-1;
#if defined(DM_USE_AVX2)
    for (; i + 4 <= npts; i += 4) {
        double p4[4][3], d2[4], bu[4], bv[4];
        size_t t[4];
        int j;
        for (j = 0; j < 4; j++) dm__load3(in->pts[i + (size_t)j].p, 0, p4[j]);
        hint = in->tri_new[in->pts[i].bt]; /* the same answer, sooner */
        dm__sh_nearest4_avx2(in->tri + 16 * c->old_triangle_count, c->triangle_count, p4[0], DBL_MAX, hint, t, d2, bu,
                             bv);
        for (j = 0; j < 4; j++) dm__sh_plane_at(in, c, in->pts + i + (size_t)j, t[j], pl + 4 * (i + (size_t)j));
    }
#endif
    for (; i < npts; i++) dm__sh_plane_of(in, c, in->pts + i, &hint, pl + 4 * i);
}

/* The metric the enclosure projects in: the quadric's matrix plus this fraction of its mean
   eigenvalue. With the plain distance keep moves the shortest way, often where its error grows
   fastest; with much less than the mean eigenvalue added it slides far along flat parts (their
   quadric does not see it), its triangles lose their shape and the charts stretch. */
#define DM__SH_TANGENT 1.0

/* The metric M the enclosure projects in (DM__SH_TANGENT); the plain distance where there is no
   quadric. */
static void dm__sh_metric(const double metric[6], double M[3][3])
{
    double tr;
    int j, k;
    M[0][0] = metric[0]; M[0][1] = M[1][0] = metric[1]; M[0][2] = M[2][0] = metric[2];
    M[1][1] = metric[3]; M[1][2] = M[2][1] = metric[4]; M[2][2] = metric[5];
    tr = (M[0][0] + M[1][1] + M[2][2]) / 3.0;
    if (!(tr > 0.0 && tr < 1e300)) /* no quadric: the plain distance */
        for (j = 0; j < 3; j++)
            for (k = 0; k < 3; k++) M[j][k] = j == k;
    else
        for (j = 0; j < 3; j++) M[j][j] += DM__SH_TANGENT * tr;
}

/* The metric's frame for n planes in pl: L with M = L L^T (dm__sh_metric; Cholesky) and each
   plane's normal in y = L^T x, a_i = L^-1 n_i (3 doubles each into a). 0 when M is not positive
   definite. */
static int dm__sh_frame(const double metric[6], const double *pl, size_t np, double L[3][3], double *a)
{
    double M[3][3];
    size_t i;
    dm__sh_metric(metric, M);
    L[0][0] = sqrt(M[0][0]);
    L[1][0] = M[1][0] / L[0][0];
    L[2][0] = M[2][0] / L[0][0];
    L[1][1] = sqrt(M[1][1] - L[1][0] * L[1][0]);
    L[2][1] = (M[2][1] - L[2][0] * L[1][0]) / L[1][1];
    L[2][2] = sqrt(M[2][2] - L[2][0] * L[2][0] - L[2][1] * L[2][1]);
    if (!(L[0][0] > 0.0 && L[1][1] > 0.0 && L[2][2] > 0.0)) return 0;
    for (i = 0; i < np; i++) {
        const double *n = pl + 4 * i;
        double *ai = a + 3 * i;
        ai[0] = n[0] / L[0][0];
        ai[1] = (n[1] - L[1][0] * ai[0]) / L[1][1];
        ai[2] = (n[2] - L[2][0] * ai[0] - L[2][1] * ai[1]) / L[2][2];
    }
    return 1;
}

/* ap split along the nact active normals (a, act): ap = sum r_q a_act[q] + z, z orthogonal to
   them (their Gram system, by Gauss-Jordan: it is positive definite). 0 when it is not. */
static int dm__sh_split_span(const double *a, const size_t *act, size_t nact, const double ap[3], double r[3],
                             double z[3])
{
    double G[3][4];
    size_t q, q2, q3;
    int k;
    for (q = 0; q < nact; q++) {
        for (q2 = 0; q2 < nact; q2++) G[q][q2] = dm__dot3(a + 3 * act[q], a + 3 * act[q2]);
        G[q][3] = dm__dot3(a + 3 * act[q], ap);
    }
    for (q = 0; q < nact; q++) {
        if (!(G[q][q] > 0.0)) return 0;
        for (q2 = 0; q2 < nact; q2++) {
            double f;
            if (q2 == q) continue;
            f = G[q2][q] / G[q][q];
            for (q3 = q; q3 < 4; q3++) G[q2][q3] -= f * G[q][q3];
        }
    }
    for (q = 0; q < nact; q++) r[q] = G[q][3] / G[q][q];
    for (k = 0; k < 3; k++) {
        z[k] = ap[k];
        for (q = 0; q < nact; q++) z[k] -= r[q] * a[3 * act[q] + (size_t)k];
    }
    return 1;
}

/* The exact projection (Goldfarb and Idnani's dual active set, 1983): x moved to the point nearest
   it in the metric M (dm__sh_metric) on the outer side of all np planes in pl, in a few steps
   (alternating projections crawl along nearly parallel planes). In y = L^T x the metric is the
   plain distance and plane i reads a_i . y >= d_i (dm__sh_frame; a: 3 doubles per plane). The
   active set holds at most three independent planes; a violated plane that cannot be added (its
   normal in their span, no multiplier to give way) proves the planes inconsistent.
   Returns 1 with x moved (every plane met within tol), 0 with x as it was when the planes are
   inconsistent or the steps run out. Where they are found inconsistent and proof is not NULL,
   the planes that prove it (the violated one and the active ones: at most four, with no common
   point by themselves) go into proof, their number into *nproof (else 0). */
static int dm__sh_project(const double metric[6], const double *pl, size_t np, double tol, double *a, double x[3],
                          size_t proof[4], size_t *nproof)
{
    double L[3][3], y[3], u[4], z[3], r[3];
    size_t i, act[4], nact = 0, p;
    int k, steps = 0;
    if (nproof) *nproof = 0;
    if (!dm__sh_frame(metric, pl, np, L, a)) return 0;
    y[0] = L[0][0] * x[0] + L[1][0] * x[1] + L[2][0] * x[2]; /* y = L^T x */
    y[1] = L[1][1] * x[1] + L[2][1] * x[2];
    y[2] = L[2][2] * x[2];
    for (;;) {
        double worst = tol, up = 0.0;
        p = np;
        for (i = 0; i < np; i++) { /* the most violated plane not active */
            double sd = pl[4 * i + 3] - dm__dot3(a + 3 * i, y);
            size_t q;
            if (!(sd > worst)) continue;
            for (q = 0; q < nact && act[q] != i; q++) {}
            if (q == nact) {
                worst = sd;
                p = i;
            }
        }
        if (p == np) break;
        for (;;) { /* add p: full steps along z, partial ones that drop a plane whose multiplier ends */
            const double *ap = a + 3 * p;
            double t1 = DBL_MAX, t2 = DBL_MAX, t, zz;
            size_t q, kd = 0;
            if (++steps > 64 || !dm__sh_split_span(a, act, nact, ap, r, z)) return 0;
            zz = dm__dot3(z, z);
            if (nact < 3 && zz > 1e-12 * dm__dot3(ap, ap)) t1 = (pl[4 * p + 3] - dm__dot3(ap, y)) / zz;
            for (q = 0; q < nact; q++)
                if (r[q] > 0.0 && u[q] / r[q] < t2) {
                    t2 = u[q] / r[q];
                    kd = q;
                }
            if (t1 == DBL_MAX && t2 == DBL_MAX) { /* inconsistent */
                for (q = 0; proof && q < nact; q++) proof[q] = act[q];
                if (proof) proof[nact] = p;
                if (nproof) *nproof = nact + 1;
                return 0;
            }
            t = t1 < t2 ? t1 : t2;
            if (t1 < DBL_MAX)
                for (k = 0; k < 3; k++) y[k] += t * z[k];
            for (q = 0; q < nact; q++) u[q] -= t * r[q];
            up += t;
            if (t1 <= t2) { /* full step: p is met and joins */
                act[nact] = p;
                u[nact++] = up;
                break;
            }
            act[kd] = act[nact - 1]; /* partial step: plane kd gives way */
            u[kd] = u[nact - 1];
            nact--;
        }
    }
    if (steps == 0) return 1; /* met as it was */
    x[2] = y[2] / L[2][2]; /* x = L^-T y */
    x[1] = (y[1] - L[2][1] * x[2]) / L[1][1];
    x[0] = (y[0] - L[1][0] * x[1] - L[2][0] * x[2]) / L[0][0];
    return 1;
}

/* pt's old signed distance, as a float (the old triangles of in->tri) */
static float dm__sh_old_signed(const dm_collapse *c, const double *tf, const dm__sh_pt *pt)
{
    uint32_t fv[3];
    double pp[3];
    int nf;
    dm__load3(pt->p, 0, pp);
    dm__sh_feature(c, c->old_triangles, pt->bt, pt->bu, pt->bv, 1, fv, &nf);
    return (float)dm__sh_sign(c->old_triangles, tf, c->old_triangle_count, pt->bt, pt->bu, pt->bv, fv, nf, pp,
                              sqrt(pt->d2));
}

/* the check at the rounded position x: no relevant vertex (of the npts in pts) ends outside, its
   signed distance beyond `outside` and beyond its old one by `slack` (the enclosure: 4 margins and
   one; a candidate asked relaxed: DM__SH_REACH thicknesses, both) */
static int dm__sh_recheck(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const double x[3], size_t npts,
                          double outside, double slack)
{
    size_t i, no = c->old_triangle_count, nr = c->triangle_count, hint = (size_t)-1;
#if defined(DM_USE_AVX2)
    size_t t[4];
    double p4[4][3], d2[4], bu[4], bv[4];
#endif
    dm__sh_tris(c, c->triangles, nr, x, in->tri + 16 * no);
    for (i = 0; i < npts; i++) {
        const dm__sh_pt *pt = in->pts + i;
        double pp[3], sd = 0.0;
        int batched = 0;
        dm__load3(pt->p, 0, pp);
#if defined(DM_USE_AVX2)
        batched = i - i % 4 + 4 <= npts; /* in a whole four: their searches at once */
        if (batched && i % 4 == 0) {
            int j;
            for (j = 0; j < 4; j++) dm__load3(in->pts[i + (size_t)j].p, 0, p4[j]);
            dm__sh_nearest4_avx2(in->tri + 16 * no, nr, p4[0], DBL_MAX, pt->nt, t, d2, bu, bv);
        }
        if (batched) sd = dm__sh_signed_at(c, in->tri + 16 * no, pp, t[i % 4], d2[i % 4], bu[i % 4], bv[i % 4]);
#endif
        if (!batched) {
            if (pt->nt != UINT32_MAX) hint = pt->nt; /* its nearest before the move: the same answer, sooner */
            sd = dm__sh_signed_new(c, in->tri + 16 * no, pp, &hint);
        }
        if (sd > outside && sd > (double)dm__sh_old_signed(c, in->tri, pt) + slack) {
            sh->vetoed_enclose++;
            return DM_COLLAPSE_VETO;
        }
    }
    return DM_COLLAPSE_ALLOW;
}

/* A candidate asked relaxed for itself alone may leave the original's relevant vertices (those of
   its enclosure) outside the new one-ring by at most this many thicknesses beyond where they
   were: the cheap relaxed collapses must not cut off the tips of thin parts (horns, ears), which
   the bake's rays then miss. */
#define DM__SH_REACH 0.25

/* The slot of the kept proofs (in->proof) for candidate c's edge, whose ends (lower first) go
   into end[2]. */
static uint32_t *dm__sh_proof_slot(const dm__sh_internal *in, const dm_collapse *c, uint32_t end[2])
{
    end[0] = c->keep < c->remove ? c->keep : c->remove;
    end[1] = c->keep ^ c->remove ^ end[0];
    return in->proof + 8 * (size_t)(((end[0] * 2654435761u) ^ (end[1] * 40503u)) & (DM__SH_PROOFS - 1));
}

/* The proof kept for c's edge, tried before the gather: its vertices, where they are still
   relevant (dm__sh_relevant), give the planes they would give in the full plane set; lowered to
   the recheck's tolerance, if those still have no common point, the full set has none either and
   the enclosure vetoes as the full check would. 1 when it holds. */
static int dm__sh_proof_holds(const dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const dm__sh_box *b)
{
    const uint32_t *e;
    double pl[16], a[12], x[3];
    size_t i, hint = (size_t)-1, hint2 = (size_t)-1;
    uint32_t end[2];
    int k;
    if (!in->proof || sh->fallback || c->relaxed) return 0; /* a relaxed candidate needs the gather */
    e = dm__sh_proof_slot(in, c, end);
    if (e[2] == 0 || e[0] != end[0] || e[1] != end[1]) return 0;
    for (i = 0; i < e[2]; i++) {
        dm__sh_pt pt;
        if (!dm__sh_relevant(in, c, b, e[3 + i], &hint, &pt) || !dm__sh_plane_of(in, c, &pt, &hint2, pl + 4 * i))
            return 0;
        pl[4 * i + 3] -= 6.0 * in->margin;
    }
    for (k = 0; k < 3; k++) x[k] = c->position[k];
    return !dm__sh_project(c->metric, pl, e[2], 1e-3 * in->margin, a, x, NULL, NULL);
}

/* keeps the proof (the planes proof[0..n), of the gathered vertices in in->pts) for c's edge */
static void dm__sh_proof_keep(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const size_t *proof, size_t n)
{
    uint32_t *e, end[2];
    size_t i;
    if (!in->proof) { /* without the table (out of memory) every veto takes the full check */
        int of = 0;
        in->proof = (uint32_t *)dm__alloc_array(&sh->allocator, DM__SH_PROOFS * 8, sizeof(uint32_t), &of);
        if (!in->proof) return;
        memset(in->proof, 0, DM__SH_PROOFS * 8 * sizeof(uint32_t));
    }
    e = dm__sh_proof_slot(in, c, end);
    e[0] = end[0];
    e[1] = end[1];
    e[2] = (uint32_t)n;
    for (i = 0; i < n; i++) e[3 + i] = in->pts[proof[i]].q;
}

/* (1) of dm_shell_constraint. Enclosure: the original's vertices near the collapse whose
   closest feature of the old triangles is at keep or remove (not on the ring's rim, which
   belongs to the rest of the mesh) must stay on the inner side of the new one-ring: their
   signed distance, taken with the angle-weighted pseudonormal at the closest feature, must not
   become positive. Each such vertex p, nearest to new triangle (keep, u, w), asks keep to lie on
   the outer side of the plane through p, u, w (an exact, linear condition on keep's position);
   the position is the point nearest the proposed one that meets all of them (dm__sh_project;
   where the planes have no common point even at the recheck's tolerance, a veto, whose proof is
   kept for the edge's next time: dm__sh_proof_holds), then everything is checked again at the
   rounded position. */
static int dm__sh_enclose(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, double x[3], float corrected[3],
                          int *moved)
{
    double x0[3], *pl;
    dm__sh_box b;
    size_t npts = 0, i, proof[4], nproof;
    int k;
    dm__sh_enclose_box(sh, in, c, &b);
    for (k = 0; k < 3; k++) x0[k] = x[k] = c->position[k];
    if (!dm__sh_old_new_tris(sh, in, c, x0)) return DM_COLLAPSE_VETO;
    in->gathered = 0;
    if (dm__sh_proof_holds(sh, in, c, &b)) {
        sh->vetoed_enclose++; /* as the full check below would */
        return DM_COLLAPSE_VETO;
    }
    if (!dm__sh_gather(sh, in, c, &b, &npts)) return DM_COLLAPSE_VETO;
    in->gathered = npts;
    if (!dm__sh_grow_scratch(sh, in, 7 * npts + 9 * c->triangle_count + 16)) return DM_COLLAPSE_VETO;
    pl = in->scratch;
    dm__sh_planes(in, c, npts, pl);
    if (!dm__sh_project(c->metric, pl, npts, 1e-3 * in->margin, pl + 4 * npts, x, NULL, NULL)) {
        for (i = 0; i < npts; i++) pl[4 * i + 3] -= 6.0 * in->margin; /* again at the recheck's tolerance */
        if (!dm__sh_project(c->metric, pl, npts, 1e-3 * in->margin, pl + 4 * npts, x, proof, &nproof)) {
            if (nproof) dm__sh_proof_keep(sh, in, c, proof, nproof);
            sh->vetoed_enclose++; /* no position keeps them all inside */
            return DM_COLLAPSE_VETO;
        }
    }
    for (k = 0; k < 3; k++) {
        corrected[k] = (float)x[k];
        x[k] = corrected[k];
        if (corrected[k] != c->position[k]) *moved = 1;
        if (x[k] < b.lo[k] - b.grow || x[k] > b.hi[k] + b.grow) { /* beyond the gathered box */
            sh->vetoed_enclose++;
            return DM_COLLAPSE_VETO;
        }
    }
    return dm__sh_recheck(sh, in, c, x, npts, 4.0 * in->margin, in->margin);
}

/* The corner normals of the new one-ring, 9 doubles per triangle, into the scratch (keep at x):
   keep's from its whole new one-ring; a neighbour's from the mesh's normal sums that
   dm_shell_collapsed keeps (less its old triangles here, plus its new ones). NULL when out of
   memory. */
static double *dm__sh_ring_normals(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, const double x[3])
{
    double *vn;
    size_t i, j, no = c->old_triangle_count, nr = c->triangle_count;
    int k;
    if (!dm__sh_grow_scratch(sh, in, 9 * nr + 16)) return NULL;
    vn = in->scratch;
    for (i = 0; i < 9 * nr; i++) vn[i] = 0.0;
    for (i = 0; i < nr; i++) {
        const uint32_t *t = c->triangles + 3 * i;
        double p[3][3], n[3];
        for (k = 0; k < 3; k++) dm__sh_at(c, t[k], x, p[k]);
        if (!dm__sh_plane(p[0], p[1], p[2], n)) continue;
        for (j = 0; j < 3; j++) {
            double ang = dm__corner_angle((const double(*)[3])p, (int)j);
            if (ang < 0.0) continue;
            /* add to every ring triangle's corner at this vertex (all of them contain keep) */
            {
                size_t m;
                for (m = 0; m < nr; m++) {
                    const uint32_t *u = c->triangles + 3 * m;
                    int q;
                    for (q = 0; q < 3; q++)
                        if (u[q] == t[j])
                            for (k = 0; k < 3; k++) vn[9 * m + 3 * (size_t)q + (size_t)k] += ang * n[k];
                }
            }
        }
    }
    if (in->collapsed > 0 || in->accepted < 2) { /* dm_shell_collapsed follows the mesh: exact */
        double xk[3];
        dm__load3(c->positions, c->keep, xk);
        for (i = 0; i < nr; i++)
            for (j = 0; j < 3; j++) {
                uint32_t w = c->triangles[3 * i + j];
                size_t m;
                int q;
                if (w == c->keep || w >= in->nv) continue;
                for (k = 0; k < 3; k++) vn[9 * i + 3 * j + (size_t)k] += in->vsum[3 * (size_t)w + (size_t)k];
                for (m = 0; m < no; m++) /* less what w's old triangles here gave it */
                    for (q = 0; q < 3; q++)
                        if (c->old_triangles[3 * m + (size_t)q] == w) {
                            double d[3];
                            dm__sh_contrib(c, c->old_triangles + 3 * m, q, xk, d);
                            for (k = 0; k < 3; k++) vn[9 * i + 3 * j + (size_t)k] -= d[k];
                        }
            }
    }
    return vn;
}

/* (2, along the rays) and (3) of dm_shell_constraint, with the corner normals vn. */
/* The sample at barycentric w of a ring triangle (corners p, corner normals vn9): the point y and
   the interpolated normal n (not normalised). */
static void dm__sh_sample(const double p[3][3], const double *vn9, const double w[3], double y[3], double n[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        y[k] = w[0] * p[0][k] + w[1] * p[1][k] + w[2] * p[2][k];
        n[k] = w[0] * vn9[k] + w[1] * vn9[3 + k] + w[2] * vn9[6 + k];
    }
}

/* Which way the original's triangle faces against direction n: 1 along it, -1 against it (or
   across), 0 when it is degenerate. */
static int dm__sh_side(const dm__sh_internal *in, uint32_t tri, const double n[3])
{
    const double *fn = in->fnrm + 3 * (size_t)tri;
    if (fn[0] != fn[0]) return 0; /* no normal */
    return dm__dot3(fn, n) > 0.0 ? 1 : -1;
}

/* The hits of one ray (from tmin 0) along the original, asked for nearest first from a given
   distance on: one traversal collects them all when there are few (there are a handful on these
   short rays), with the same hits and ties as a query per distance would give. */
typedef struct dm__sh_walk {
    dm_ray ray;
    dm_hit hit[16];
    size_t n;
} dm__sh_walk;

static void dm__sh_walk_start(const dm__sh_internal *in, dm__sh_walk *w, const dm_ray *ray)
{
    dm__ray_pre r;
    w->ray = *ray;
    w->n = 0;
    if (dm__prepare_ray(ray->org, ray->dir, 1.0f, &r)) w->n = dm__all_hits(in->bvh, &r, 0.0f, ray->tmax, w->hit, 16);
}

/* the nearest hit at or beyond `from` into *hit: 1, or 0 if none */
static int dm__sh_walk_next(const dm__sh_internal *in, dm__sh_walk *w, float from, dm_hit *hit)
{
    const dm_hit *h;
    if (w->n > 16) { /* too many for the buffer: one query */
        w->ray.tmin = from;
        return dm_bvh_intersect(in->bvh, &w->ray, hit);
    }
    h = dm__first_hit_from(w->hit, w->n, from);
    if (h) *hit = *h;
    return h != NULL;
}

/* The overlap check of one sample: point y with normal n (not normalised). 0 when a ray from a
   little outside y along -n meets the original's front side first (or nothing, where
   dm__sh_miss_ok), within the offset grown at the hit, with no re-entry within that depth; else 1
   (overlap: a back face first, a re-entry, a zero normal, any other miss) or 2 (the hit lies
   deeper than the shell). */
/* May a ray from sample y miss the original? Only on an open original, and only where y lies
   within DM__SH_EDGE_REACH thicknesses of it (beside its boundary): a base triangle that reaches
   farther out overhangs the boundary, and the bake finds nothing under it. */
#define DM__SH_EDGE_REACH 0.05f
static int dm__sh_miss_ok(const dm_shell *sh, const dm__sh_internal *in, const double y[3])
{
    dm_closest cl;
    float q[3];
    int k;
    if (!in->open) return 0;
    for (k = 0; k < 3; k++) q[k] = (float)y[k];
    return dm_bvh_closest_point(in->bvh, q, DM__SH_EDGE_REACH * sh->thickness, &cl);
}

static int dm__sh_sample_fails(const dm_shell *sh, const dm__sh_internal *in, const double y[3], const double n[3])
{
    double len = dm__len3(n), h;
    dm_ray ray;
    dm_hit hit;
    dm__sh_walk walk;
    const uint32_t *ot;
    int k, crossings;
    if (!(len > 0.0)) return 1;
    for (k = 0; k < 3; k++) { /* from a little outside: the triangle may graze a bump */
        ray.dir[k] = (float)(-n[k] / len);
        ray.org[k] = (float)(y[k] + 0.25 * sh->thickness * n[k] / len);
    }
    ray.tmin = 0.0f;
    ray.tmax = 2.25f * sh->thickness;
    dm__sh_walk_start(in, &walk, &ray);
    if (!dm__sh_walk_next(in, &walk, 0.0f, &hit)) return !dm__sh_miss_ok(sh, in, y);
    ot = in->idx + 3 * (size_t)hit.triangle;
    if (dm__sh_side(in, hit.triangle, n) < 0) return 1;
    /* the shell along the ray: no deeper than the offset grown at the hit */
    h = (1.0 - hit.u - hit.v) * sh->offset[ot[0]] + hit.u * sh->offset[ot[1]] + hit.v * sh->offset[ot[2]];
    if ((double)hit.t - 0.25 * sh->thickness > h + in->margin) return 2;
    /* and no re-entry within the same depth: in (this hit), out, in again is the fold of the
       paper's Fig 4.1.3, where one texel would have three depths and the part of the original
       between them would be reached by no ray */
    for (crossings = 0; crossings < 8; crossings++) {
        float from = hit.t + (float)in->margin;
        if (!(from < ray.tmax) || !dm__sh_walk_next(in, &walk, from, &hit)) break;
        if (dm__sh_side(in, hit.triangle, n) > 0) return 1;
    }
    return 0;
}

/* Sample s of a triangle (dm__sh_sample weights): its in->samples inner points, then its edge
   from corner kc to the next at 1/2, 1/4 and 3/4. */
static void dm__sh_sample_weights(const dm__sh_internal *in, int s, int kc, double w[3])
{
    int k;
    if (s < in->samples) {
        for (k = 0; k < 3; k++) w[k] = dm__sh_bary[s][k];
        return;
    }
    w[0] = w[1] = w[2] = 0.0;
    w[kc] = 0.5 - 0.25 * (s - in->samples == 1) + 0.25 * (s - in->samples == 2);
    w[(kc + 1) % 3] = 1.0 - w[kc];
}

static int dm__sh_overlap(dm_shell *sh, const dm__sh_internal *in, const dm_collapse *c, const double x[3],
                          const double *vn)
{
    size_t i, nr = c->triangle_count;
    int k;
    /* (3) No height-field overlap: rays from points of each new triangle along the inverted
       interpolated normal meet the original's front side first, within twice the shell's
       thickness (a miss is allowed only when the original is open). Vertex normals: keep's from
       its whole new one-ring, a neighbour's from the one-ring triangles it is in. */
    for (i = 0; i < nr; i++) {
        const uint32_t *t = c->triangles + 3 * i;
        double p[3][3];
        int s, kc;
        for (k = 0; k < 3; k++) dm__sh_at(c, t[k], x, p[k]);
        for (kc = 0; kc < 2 && t[kc] != c->keep; kc++) {}
        for (s = 0; s < in->samples + 3; s++) {
            double y[3], n[3], w[3];
            int fails;
            dm__sh_sample_weights(in, s, kc, w);
            dm__sh_sample((const double(*)[3])p, vn + 9 * i, w, y, n);
            fails = dm__sh_sample_fails(sh, in, y, n);
            if (fails) {
                if (fails == 2) sh->vetoed_shell++;
                else sh->vetoed_overlap++;
                return DM_COLLAPSE_VETO;
            }
        }
    }
    return DM_COLLAPSE_ALLOW;
}

/* (3) once relaxed: from the same samples as the overlap check, the nearest crossing of the
   original along the line, either way within the thickness, must face the way the base does
   (the original's front side when it lies inward, seen from inside when it lies outward), so that
   a bake both ways finds one depth there. */
static int dm__sh_crossings(dm_shell *sh, const dm__sh_internal *in, const dm_collapse *c, const double x[3],
                            const double *vn)
{
    size_t i, nr = c->triangle_count;
    int k, s;
    for (i = 0; i < nr; i++) {
        const uint32_t *t = c->triangles + 3 * i;
        double p[3][3];
        for (k = 0; k < 3; k++) dm__sh_at(c, t[k], x, p[k]);
        for (s = 0; s < in->samples; s++) {
            double y[3], n[3], len;
            dm_ray ray;
            dm_hit hit;
            dm__sh_sample((const double(*)[3])p, vn + 9 * i, dm__sh_bary[s], y, n);
            len = dm__len3(n);
            if (!(len > 0.0)) {
                sh->vetoed_overlap++;
                return DM_COLLAPSE_VETO;
            }
            for (k = 0; k < 3; k++) {
                ray.dir[k] = (float)(-n[k] / len);
                ray.org[k] = (float)y[k];
            }
            ray.tmin = -sh->thickness;
            ray.tmax = sh->thickness;
            if (!dm_bvh_intersect_line(in->bvh, &ray, &hit)) {
                if (dm__sh_miss_ok(sh, in, y)) continue;
                sh->vetoed_overlap++;
                return DM_COLLAPSE_VETO;
            }
            if (dm__sh_side(in, hit.triangle, n) < 0) {
                sh->vetoed_overlap++;
                return DM_COLLAPSE_VETO;
            }
        }
    }
    return DM_COLLAPSE_ALLOW;
}

DMDEF int dm_shell_relax(void *user)
{
    dm_shell *sh = (dm_shell *)user;
    if (!sh || sh->fallback >= 2) return 0;
    sh->fallback++;
    return 1;
}

DMDEF size_t dm_shell_fallback_triangles(const dm_shell *sh, const uint32_t *idx, size_t nt, const uint32_t *ids,
                                         uint8_t *flags)
{
    size_t t, n = 0;
    int k;
    if (!sh || !idx || !ids || !flags) return 0;
    for (t = 0; t < nt; t++) {
        flags[t] = 0;
        for (k = 0; k < 3; k++) {
            uint32_t v = ids[idx[3 * t + (size_t)k]];
            if (v < sh->vertex_count && sh->fallback_vertex[v]) flags[t] = 1;
        }
        n += flags[t];
    }
    return n;
}

/* The enclosure for candidate c (dm__sh_enclose), kept for the call in full that follows a
   placement_only one: x, corrected and *moved as it leaves them. */
static int dm__sh_placed(dm_shell *sh, dm__sh_internal *in, const dm_collapse *c, double x[3], float corrected[3],
                         int *moved)
{
    int k;
    if (in->placed_valid && in->placed_keep == c->keep && in->placed_remove == c->remove &&
        in->placed_level == c->level && memcmp(in->placed_at, c->position, sizeof in->placed_at) == 0) {
        for (k = 0; k < 3; k++) {
            x[k] = in->placed_x[k];
            corrected[k] = (float)x[k];
        }
        *moved = in->placed_moved;
        in->placed_valid = 0;
        return in->placed_verdict;
    }
    for (k = 0; k < 3; k++) x[k] = c->position[k];
    in->placed_verdict = dm__sh_enclose(sh, in, c, x, corrected, moved);
    if (in->placed_verdict != DM_COLLAPSE_ALLOW) /* x and corrected are the position */
        for (k = 0; k < 3; k++) x[k] = corrected[k] = c->position[k];
    in->placed_valid = 1;
    in->placed_keep = c->keep;
    in->placed_remove = c->remove;
    in->placed_level = c->level;
    memcpy(in->placed_at, c->position, sizeof in->placed_at);
    for (k = 0; k < 3; k++) in->placed_x[k] = x[k];
    in->placed_moved = *moved;
    return in->placed_verdict;
}

DMDEF int dm_shell_constraint(void *user, const dm_collapse *c, float corrected[3])
{
    dm_shell *sh = (dm_shell *)user;
    dm__sh_internal *in;
    double x[3], *vn;
    int k, moved = 0, verdict, enclosed, fb;
    if (!sh || !c || !corrected || !sh->internal || !c->positions || !c->triangles || !c->old_triangles)
        return DM_COLLAPSE_VETO;
    in = (dm__sh_internal *)sh->internal;
    dm__sh_run_check(sh, in, c->level);
    fb = sh->fallback ? sh->fallback : c->relaxed ? 1 : 0; /* relaxed everywhere, or for this one */
    in->relaxed_keep = UINT32_MAX;
    verdict = dm__sh_placed(sh, in, c, x, corrected, &moved);
    enclosed = verdict == DM_COLLAPSE_ALLOW;
    if (c->placement_only) { /* where keep goes; where the enclosure fails, the relaxed check decides */
        if (verdict != DM_COLLAPSE_ALLOW && !fb) return DM_COLLAPSE_VETO;
        if (verdict != DM_COLLAPSE_ALLOW)
            for (k = 0; k < 3; k++) corrected[k] = c->position[k];
        return DM_COLLAPSE_PLACED;
    }
    /* (2) Inside the shell: keep lies within the offset grown at its closest point of the
       original; the points of the new triangles are checked along the overlap rays, where the
       depth to the original must not exceed the offset grown at the hit. */
    if (verdict == DM_COLLAPSE_ALLOW && !dm__sh_in_shell(sh, in, x)) {
        sh->vetoed_shell++;
        verdict = DM_COLLAPSE_VETO;
    }
    vn = verdict == DM_COLLAPSE_ALLOW ? dm__sh_ring_normals(sh, in, c, x) : NULL;
    if (vn) verdict = dm__sh_overlap(sh, in, c, x, vn);
    else verdict = DM_COLLAPSE_VETO;
    if (verdict != DM_COLLAPSE_ALLOW && fb) { /* relaxed: where the paper's constraints fail */
        if (enclosed && fb < 2) { /* the relaxed check where the enclosure put keep first */
            vn = dm__sh_ring_normals(sh, in, c, x);
            verdict = vn ? dm__sh_crossings(sh, in, c, x, vn) : DM_COLLAPSE_VETO;
        }
        if (verdict != DM_COLLAPSE_ALLOW) { /* then where the simplifier put it */
            for (k = 0; k < 3; k++) x[k] = corrected[k] = c->position[k];
            moved = 0;
            vn = fb >= 2 ? NULL : dm__sh_ring_normals(sh, in, c, x);
            verdict = fb >= 2 ? DM_COLLAPSE_ALLOW : vn ? dm__sh_crossings(sh, in, c, x, vn) : DM_COLLAPSE_VETO;
        }
        if (verdict == DM_COLLAPSE_ALLOW && !sh->fallback) { /* asked relaxed: tips stay in reach */
            double tau = DM__SH_REACH * (double)sh->thickness;
            verdict = dm__sh_recheck(sh, in, c, x, in->gathered, tau, tau);
        }
        if (verdict == DM_COLLAPSE_ALLOW) { /* dm_shell_collapsed marks it when it is done */
            in->relaxed_keep = c->keep;
            in->relaxed_level = c->level;
        }
    }
    if (verdict != DM_COLLAPSE_ALLOW) return verdict;
    in->accepted++;
    if (moved) {
        sh->moved++;
        return DM_COLLAPSE_MOVE;
    }
    return DM_COLLAPSE_ALLOW;
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* DM_IMPLEMENTATION_DONE */
#endif /* DM_IMPLEMENTATION */

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
