/* texel.h - v0.1 - MIT licence or public domain (see end of file)
   Time-varying texels (TVT): volumetric grass that withers over time (Jiao, Yang, Heng, Wu 2010).

   WHAT
     - Static grass texel: random cone blades voxelised into density, normal, tangent, diffuse
       colour and specular, res^3 voxels (res a power of two, 8..1024). The texel wraps at its
       four side borders (blades crossing a border come back on the other side), so it tiles.
       Storage is sparse: res^3 voxels in bricks of 4^3, an index of uint32 per brick (empty
       bricks cost 4 bytes, occupied ones only their non-empty voxels), 8- or 16-bit channels.
       tvt_texel_bytes reports the bytes.
     - Point-based structure (PBS): proportion * density points per voxel (default 6), and
       normalised Gaussian splatting back into a texel (total density kept exactly).
     - The physical-biological model: water-content curves, vein / mesophyll shrinkage with
       stiffening, droop that bends blades more toward the tip, point merging, colour from
       chlorophyll a, b and carotene absorption spectra to linear sRGB, and wd(t).
     - The TVT: key frames over wd with interpolation, mingling of K samples each with its own
       ageing function, and an LOD pyramid per frame whose coarse levels keep the mean opacity.
     - Rendering: density, tangent, colour and transmittance at a point for a level, Kajiya-Kay
       shading with self-shadow volumes, and a ray march through a tile, for any renderer.
     - Tiling over a mesh shell: the prisms a mesh sweeps along its normals, mapped to texel
       space continuously across shared faces, and per-tile wd from a map over tile coordinates.

   HOW TO USE (in ten lines)
       // in exactly one C or C++ file, #define TVT_IMPLEMENTATION before #include "texel.h"
       tvt_grass_desc g = tvt_grass_default_desc();          // 100 cones at 64^3
       tvt_texel grass, frame; tvt_points pts;
       tvt_build_grass(&g, &grass);                          // the static texel (wd = 0)
       tvt_sample(&grass, NULL, &pts);                       // texel -> points
       for (int k = 1; k <= 8; k++) {                        // age to wd = 1 in 8 steps
           tvt_age(&pts, k / 8.0f, NULL);                    // move, shrink, droop, yellow, merge
           tvt_splat(&pts, NULL, &frame);  use(&frame);  tvt_texel_free(&frame);
       }
       tvt_points_free(&pts); tvt_texel_free(&grass);

   PIPELINE (paper sections 2 and 3)
     1. Blades (tvt_grass_blades): root uniform in the base square, height uniform in
        [height_min, height_max] * res, base radius uniform in [radius_min, radius_max] voxels
        tapering linearly to 0 at the tip, lean uniform in [lean_min, lean_max] degrees toward a
        uniform azimuth. Roots are placed on a 1/4096-voxel lattice so that an integer shift of
        every root is exact in float: the voxeliser then gives the shifted texel bit for bit.
     2. Voxelisation (tvt_build_texel): each voxel is sampled on a supersample^3 lattice;
        density = covered fraction summed over blades (not clamped: it is an extinction
        density, overlapping blades add up); tangent = cone axis (the vein direction); normal =
        (sample - closest axis point) / local radius, averaged, so |normal| is about 0 on the
        axis (the paper's vein cells) and up to 1 at the surface (mesophyll cells); colour =
        the pigment colour at wd = 0 times a per-blade brightness; specular = 0.3. Every voxel
        also keeps the index of the blade that covers most of it (static texels only), so that
        points know their blade's root and axis exactly (the paper reconstructs the root from
        the tangent line, which is kept for texels without blade indices).
     3. Sampling (tvt_sample): in each voxel, q = proportion * density points, rounded down or up
        at random with the probability of the fraction (unbiased), uniform in the voxel, each
        inheriting the voxel's attributes. Random numbers come from a hash of (seed, voxel), so
        the result does not depend on the traversal order.
     4. Ageing (tvt_age): every point's position is a function of its rest state and wd, see
        MODEL; close points are merged after each step (the only path-dependent part).
     5. Splatting (tvt_splat): each point spreads its mass m over the 3^3 voxel centres around
        it with Gaussian weights exp(-d^2 / 2 sigma^2), sigma = 0.5 voxel, divided by their sum:
        density(v) = sum_i m_i w_i(v) / proportion, attributes = sum m w A / sum m w. The paper's
        a * exp(...) with a fixed a loses or gains mass depending on where a point falls in its
        voxel; normalising per point keeps the total density exactly and is the paper's formula
        for a smooth field (where the lattice sum of a normalised Gaussian is 1). Voxels below
        z = 0 or above the top are left out of the sum, so no mass is lost at the ground.

   MODEL (paper section 3; the paper gives the quantities but no curves, values or forms)
     wd(t) = clamp(t / duration, 0, 1): the paper never defines it; linear time is the choice
       that lets key frames at equal wd steps be equal time steps.
     Water content (fraction of the initial), logistic in wd, w(0) = 1 (paper Fig 9b is a figure
       only):  w(wd) = [w_end + (1 - w_end) / (1 + exp((wd - c) / s))] / (same at wd = 0),
       w_end = 0.25; standard c = 0.45, s = 0.08; ample water c = 0.60, s = 0.08; low temperature
       c = 0.55, s = 0.15. Water lost dw(wd) = 1 - w(wd).
     Shrinkage: the paper's initial strains eps0_v = k_v dw, eps0_m = k_m dw (k_v = 0.10 <
       k_m = 0.40: veins hold their water better). The moduli stiffen, E(wd) = E0 (1 + gamma wd),
       gamma = 4, and a stiffer cell realises less of its free strain: d eps = d eps0 * E0 / E(wd)
       (integrated over wd in 256 midpoint steps). So shrinkage slows and settles, as the paper
       says. Axial (blade length) strain from the vein / mesophyll mix weighted by stiffness and
       area, e_ax = 1 - (1 - eps_mix)^(1/3); radial strain of mesophyll, e_rad = 1 -
       (1 - eps_m)^(1/2). The paper writes E_v < E_m but justifies it by veins resisting
       deformation more, i.e. E_v > E_m; vein_stiffness (E_v / E_m) defaults to 2, and 0.5 gives
       the literal reading.
     Droop: the paper rotates each point about the root at omega_i = omega / h_i^2, which makes
       the root turn fastest (against its own text, and infinite at h = 0), and rigid rotation of
       each point about the root at its own rate stretches the blade and tears it. Here the
       blade's direction at arc length s is turned toward its lean azimuth by
           phi(s) = Theta(wd) * min(s / L, 1)^beta,  beta = 2,  L = droop_length * res (0.6),
       Theta(wd) = droop_max (80 degrees) * dw(wd) / dw(1) (support lost with the water), and the
       centre line is the integral of that direction: the blade bends more toward the tip, tips
       move more than roots, the length is kept (after shrinkage) and it cannot tear. L is one
       length for all blades, so that tall blades, with more lever arm, droop more.
       Points that would go below the ground lie on it (z = 0).
     Frame: tangent = the bent centre line's direction; the normal is turned with it.
     Colour (paper section 3.2): pigments chlorophyll a : b : carotene = 27 : 9 : 4 at wd = 0;
       chlorophyll follows Chl(wd) = [0.03 + 0.97 / (1 + exp((wd - 0.4) / 0.1))] / (same at 0),
       carotene stays constant. Reflectance R(l) = 0.55 exp(-3 A(l)) (Beer-Lambert: the paper's
       L - absorption can go negative), A = sum of pigment amounts times their absorption
       spectra (sums of Gaussians at the pigments' literature peaks), plus a brown term
       1.5 dw/dw(1) exp(-(l - 380) / 110) for the oxidised polyphenols of dry blades (not in the
       paper; without it wd = 1 is a clean yellow, not the yellow-brown of withered grass).
       R is integrated on 380..780 nm with the CIE 1931 fit of Wyman, Sloan, Shirley (2013)
       under an equal-energy illuminant and converted to linear sRGB. Each blade ages with a
       delay in [-colour_jitter, colour_jitter] (0.05) of wd for its colour, so a patch is not
       one flat tint. Specular: ms = ms0 (0.4 + 0.6 w(wd)) (dry grass is less glossy).
     Merging (paper Algorithm 1): after each step, each point, in the order of its voxel (the
       texel's storage order: 4^3 bricks in z, y, x order, voxels in a brick likewise; points of
       a voxel in index order), absorbs its nearest later point closer than merge_threshold
       (0.15 voxel): position, normal, tangent, colour, specular and rest state are
       mass-weighted means and masses add. Density counts mass, so merging keeps the grass (the
       paper counts each point as 1, which would make merged grass thinner). Points sorted by
       voxel (radix sort; sampling emits them in that order, so the sort moves little) and a
       search of the sorted keys make it O(n log n) at worst, nearly O(n) in practice; pairs
       across the side borders merge too (nearest periodic image). Time is the outer
       loop (the paper's Algorithm 1 loops over points outside time, which cannot merge).

   KEY FRAMES AND MINGLING (paper sections 2.2, 4.1)
     tvt_build_tvt samples the static texel once, ages the points to wd = k / (frames - 1) in
     steps_per_frame steps per frame (each step merges), splats each frame and builds its
     pyramid. Between key frames a TVT is interpolated linearly in wd: density linear,
     attributes density-weighted (interpolating rho and rho * A, then dividing), so a blend of
     two frames is what a mix of their blades would give. Mingling (Algorithm 2) sums K samples,
     each seen at its own age Mg_i(wd) = clamp((wd - delay_i) rate_i, 0, 1) (the paper leaves
     the form to the user; delay and rate are the two knobs its Fig 11 shows): density adds
     (not clamped: it is an extinction density), attributes density-weighted.

   LOD (paper section 4.2: 256 -> 128 -> 64 -> 32, no filter given)
     Each level is the 2x2x2 box filter of the one above: density the mean (the integral of
     density along a line is kept on average), attributes density-weighted. The mean keeps the
     optical depth, but not the opacity: blades are thin, nearly opaque fibres, and a coarse
     voxel that spreads one over 8 times the volume is more opaque on average (Jensen's
     inequality, 1 - exp(-tau) being concave), the more so along the blades, where the fine
     level's rays either hit a blade all the way or miss it. So each coarse level gets an
     extinction model of fibres (Kajiya and Kay's: a fibre's projected area grows with the sine
     of the angle between ray and fibre):
         sigma = extinction * density_scale * density * (1 - a + a |t x d|),
     and density_scale and a are fitted per level (a on a grid of 21 values, the scale by a
     ternary search) so that the mean opacity of calibration rays from the top of the tile to
     the ground at elevations 15, 45 and 90 degrees matches level 0's: the largest relative
     error over the three is minimised. Level 0 keeps a = 0, scale 1: its blades are resolved.
     tvt_lod_level_for picks the level whose voxel is no larger than a pixel's footprint.

   RENDERING (the paper: "volume rendering inside ray tracing", nothing more)
     Coordinates are level-0 voxels of one tile, z up, x and y wrapping, so a renderer maps a
     world point to its tile (i, j) and to (frac(x / S) res, frac(y / S) res, (z - h) / S res)
     for tiles of size S over a height field h (a vertical shear: blades stay upright on
     slopes), with the ray's direction sheared the same way. tvt_tvt_density (density only)
     finds empty space; tvt_shade_point gives one step's opacity 1 - exp(-sigma step) and its
     colour: Kajiya-Kay diffuse kd sin(t, l) and specular ks ms (sin(t,l) sin(t,e) - (t.l)(t.e))^p
     with the fibre tangent t (Lambert with the normal where there is no tangent), the light
     scaled by the self-shadowing of tvt_build_shadow: per key frame, the transmittance toward a
     directional light on one level's grid, propagated layer by layer from the top of the tile
     (each voxel's light ray crosses the layer above between voxel centres, interpolated; the
     step's optical depth by the trapezoid rule), so it costs one lookup per voxel. tvt_march
     composites front to back along a straight segment in one tile, half a voxel of the level
     per step, skipping space the coarsest level calls empty, stopping at transmittance 0.005.
     The level comes from the pixel's footprint: tvt_lod_level_for. A renderer with its own
     shading takes tvt_tvt_sample instead (the level's voxel and its extinction along the ray,
     the fibre model included) plus tvt_shadow_at; that is how a terrain driver that marches a
     shell over a height field uses a TVT: per sample, the level for the footprint, one voxel
     of it per step, and, after an empty step, a skip of half a coarsest-level voxel wherever
     that level is empty.

   MESH SHELL (tiling over a triangle mesh: Neyret 1998, Lengyel 2001, Porumbescu et al. 2005)
     A mesh with per-vertex tile coordinates (u, v in tile units; tiles repeat, the texel wraps)
     and offset directions (normals, normalised here) sweeps a prism per triangle between the
     mesh (w = 0) and the mesh moved `height` along the normals (w = 1). tvt_build_shell splits
     each prism into three tetrahedra (tvt_shell_prism_tets) and gives each the affine map that
     takes its four corners to their (u, v, w); texel coordinates are then (frac(u) res,
     frac(v) res, w res) in tile (floor u, floor v), so the shell is one texel high.
       Why tetrahedra (Porumbescu's choice) and not the bilinear prism of shell maps solved per
     point by Newton: the map is exact and closed-form both ways (tvt_shell_map, tvt_shell_unmap),
     a ray is a straight line in texel space inside each tetrahedron, and continuity holds by
     construction: the side face over edge (i, j), i < j in vertex order, is always cut along
     the diagonal from i to the offset copy of j, so both prisms that share it cut it the same
     way and their maps agree on it (a point of the face is the same combination of the same
     corners from either side). The price: a prism's side faces are two triangles, not the
     bilinear patch, so "the prism" means the union of its tetrahedra.
       Folding: a tetrahedron is folded when its map turns orientation against the prism's
     (sign of det(d uvw / d x) against the triangle's winding about its normals times its uv
     winding) or its volume is under 1e-6 of its edges' product: high curvature with a thick
     shell makes the offset surface cross itself. tvt_build_shell reports TVT_ERR_FOLDED, or with
     allow_folded keeps it (the maps stay affine and invertible where not flat; overlapping
     content then doubles) and counts the prisms in shell.folded. Thinner shells or finer meshes
     cure it; the example's bunny is built with allow_folded and prints the count.
       Per-tile wd: tvt_wd_map is a grid of wd values over tile coordinates (one value per tile,
     wrapped or clamped), read by tvt_tile_wd (i, j) = (floor u, floor v); how a renderer fills it
     (drier where the mesh faces the sun, from a painted map) is its choice.
       Memory: 3 tetrahedra of 42 floats (168 bytes) per triangle. Errors: TVT_ERR_INVALID_ARGUMENT
     (a NULL array), TVT_ERR_EMPTY (no vertex or triangle), TVT_ERR_TOO_LARGE (more than 2^31 - 1
     vertices, a size that overflows), TVT_ERR_BAD_PARAMETER (a NaN or infinite position, normal
     or uv, a zero normal, height <= 0 or not finite), TVT_ERR_BAD_INDEX (an index >= vertex_count),
     TVT_ERR_DEGENERATE (a repeated index, a triangle whose sine of angle is under 1e-7 in the world
     or in uv), TVT_ERR_FOLDED, TVT_ERR_OUT_OF_MEMORY; the shell is zeroed on failure. Thread
     safety: a built shell is read-only; queries from many threads are fine. Limits: points are
     located in a given prism (a renderer knows its prism by walking, as render.h's
     sr_draw_mesh_shell does); there is no search over all prisms.

   OPTIONS
     Compile time: TVT_STATIC (all functions static), TVT_MALLOC(sz)/TVT_FREE(p) (both or none).
     Run time: tvt_grass_desc, tvt_sample_options, tvt_model_options, tvt_splat_options,
     tvt_lod_options, tvt_tvt_options, tvt_shade_desc. Zero (or a NULL pointer) means the
     default; tvt_*_default_*() return the resolved values.
       tvt_grass_desc   res (64), blade_count (100), seed, height_min/max (0.55, 0.9 of res),
                        radius_min/max (1.5 voxels), lean_min/max (3, 12 degrees), supersample
                        (3), bits (8 or 16; 8), specular (0.3), allocator, progress.
       tvt_sample_options  proportion (6), seed, allocator, progress.
       tvt_model_options   water_curve (TVT_WATER_STANDARD / _AMPLE / _COLD), k_vein (0.10),
                        k_mesophyll (0.40), vein_stiffness (2), stiffening (4), area_ratio (3),
                        droop_max_deg (80), droop_exponent (2), droop_length (0.6 of res),
                        merge_threshold (0.15 voxel; no_merge = 1 turns merging off),
                        colour_jitter (0.05), progress.
       tvt_splat_options   bits (8), sigma (0.5 voxel), allocator, progress.
       tvt_lod_options     levels (down to 32^3), extinction (1 per level-0 voxel at density 1),
                        calibration_rays (512 per elevation), seed, allocator, progress.
       tvt_tvt_options     frames (8), steps_per_frame (2), the sample / model / splat / lod
                        options (NULL = defaults), allocator, progress.
       tvt_shade_desc      light_dir, light_rgb, ambient_rgb, kd (1), ks (0.35), shininess (24),
                        shadow (NULL = none).

   MEMORY
     A tvt_texel owns its brick index, brick data, per-voxel blade indices (static texels
     only) and blade table, allocated with the allocator it was built with; tvt_texel_free
     frees them. Each occupied brick costs a 64-bit mask of its stored voxels and a 32-bit
     offset; each stored (non-empty) voxel 11 bytes at 8 bits, 22 at 16 bits, +2 for the blade
     index of a static texel. A voxel's place is the brick's offset plus the number of mask bits
     below its own (one popcount), so thin blades cost what they fill, not whole bricks. 8-bit
     density is stored as the square root of density / density_max (fine steps for the faint
     voxels a splat makes; 16-bit is linear); vectors map [-1, 1] and colours [0, 1] linearly.
     A tvt_points holds 112 bytes per point: its rest directions (axis, bend, normal0) are
     int16, since they need no more precision than the texel's channels and smaller points make
     sampling, copying and merging cheaper. Building, splatting, mingling and the LOD filter use
     a float scratch grid of 52 bytes per voxel of each touched brick. A tvt_lod owns its levels (level 0 a copy), a tvt_tvt its frames;
     tvt_lod_free / tvt_tvt_free free them; tvt_lod_bytes / tvt_tvt_bytes count them.

   ERRORS
     Functions return tvt_result (TVT_OK = 0); tvt_result_string() names it.
       TVT_ERR_INVALID_ARGUMENT  a NULL pointer, an unknown option value;
       TVT_ERR_BAD_RESOLUTION    res not a power of two in 8..1024, bits not 8 or 16;
       TVT_ERR_BAD_PARAMETER     a NaN or infinite parameter, or one out of its range
                                 (negative radius, height_min > height_max, ...);
       TVT_ERR_BAD_WD            wd outside [0, 1] (NaN included) in tvt_age; tvt_wd_from_time
                                 clamps instead (documented there);
       TVT_ERR_EMPTY             sampling a texel with no density, mingling zero samples
                                 (blade_count 0 in a tvt_grass_desc means the default 100;
                                 tvt_build_texel with no blades gives an empty texel);
       TVT_ERR_TOO_LARGE         a size that overflows size_t or 32-bit counts;
       TVT_ERR_OUT_OF_MEMORY     the allocator returned NULL;
       TVT_CANCELLED             the progress callback returned nonzero;
       TVT_ERR_BAD_INDEX, TVT_ERR_DEGENERATE, TVT_ERR_FOLDED  a mesh shell's (see MESH SHELL).
     On failure the output object is zeroed and nothing is leaked; tvt_age leaves the points as
     they were unless cancelled after ageing (then they are valid, at the new wd, unmerged).

   THREAD SAFETY
     No global state; every function is re-entrant. The same input and options give the same
     bits on every run (random numbers from seeded hashes, sums in a fixed order).

   LIMITS
     res 8..1024 (power of two); at most 65534 blades; at most 2^32 - 1 points; 64 key frames;
     8 LOD levels, the coarsest at least 8^3.
     Tiling over a terrain is the renderer's: it maps a world point to its tile and to texel
     coordinates (see RENDERING, or MESH SHELL over a mesh) and calls the functions below with
     each tile's own wd.
     The bits do not depend on the compiler's FMA contraction (dialect, C or C++, -ffp-contract):
     the implementation turns it off for its own code and restores the user's setting after it,
     except under clang's -ffp-contract=fast, which ignores that pragma (the last bits may differ).

   REFERENCES
     Jiao Shao-Hui, Yang Gang, Heng Pheng-Ann, Wu En-Hua, "Realistic grass withering simulation
       based on time-varying texels" (in Chinese), Journal of Software 21(9), 2010, 2224-2236.
     J. T. Kajiya, T. L. Kay, "Rendering fur with three dimensional textures", SIGGRAPH 1989.
     F. Neyret, "Modeling, animating, and rendering complex scenes using volumetric textures",
       IEEE TVCG 4(1), 1998.
     J. Lengyel, E. Praun, A. Finkelstein, H. Hoppe, "Real-time fur over arbitrary surfaces",
       I3D 2001.
     S. Porumbescu, B. Budge, L. Feng, K. Joy, "Shell maps", SIGGRAPH 2005.
     C. Wyman, P.-P. Sloan, P. Shirley, "Simple analytic approximations to the CIE XYZ color
       matching functions", JCGT 2(2), 2013. */
#ifndef TVT_TEXEL_H
#define TVT_TEXEL_H

#include <stddef.h>
#include <stdint.h>

#ifdef TVT_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define TVTDEF static __attribute__((unused))
#else
#define TVTDEF static
#endif
#else
#define TVTDEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum tvt_result {
    TVT_OK = 0,
    TVT_ERR_INVALID_ARGUMENT, /* NULL pointer, unknown option value */
    TVT_ERR_BAD_RESOLUTION,   /* res not a power of two in 8..1024, bits not 8 or 16 */
    TVT_ERR_BAD_PARAMETER,    /* NaN, infinite or out-of-range parameter */
    TVT_ERR_BAD_WD,           /* wd outside [0, 1] */
    TVT_ERR_EMPTY,            /* zero blades, or a texel with no density */
    TVT_ERR_TOO_LARGE,        /* a size overflows */
    TVT_ERR_OUT_OF_MEMORY,    /* the allocator returned NULL */
    TVT_CANCELLED,            /* the progress callback returned nonzero */
    TVT_ERR_BAD_INDEX,        /* a mesh index out of range */
    TVT_ERR_DEGENERATE,       /* a triangle of zero area (in the world or in tile coordinates) */
    TVT_ERR_FOLDED            /* a shell prism folds (too thick for the curvature) */
} tvt_result;

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct tvt_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} tvt_allocator;

enum { TVT_WATER_STANDARD = 0, TVT_WATER_AMPLE = 1, TVT_WATER_COLD = 2 };
enum { TVT_BRICK = 4, TVT_CHANNELS = 11 };
#define TVT_NO_BLADE 0xFFFFu
#define TVT_EMPTY_BRICK 0xFFFFFFFFu

/* One voxel, decoded. Vectors are not normalised (|normal| ~ 0 on a blade's axis). */
typedef struct tvt_voxel {
    float density;    /* extinction density: covered fraction of the voxel, summed over blades */
    float normal[3];  /* radial direction from the blade axis, length up to 1 */
    float tangent[3]; /* blade direction (unit where one blade covers the voxel) */
    float color[3];   /* diffuse colour, linear sRGB in [0, 1] */
    float specular;   /* specular coefficient in [0, 1] */
} tvt_voxel;

/* A cone blade, in voxel units: z up, the ground is z = 0, x and y wrap at res. */
typedef struct tvt_blade {
    float root[3];    /* centre of the base, z = 0 */
    float axis[3];    /* unit axis, axis[2] > 0 */
    float bend[3];    /* unit, perpendicular to axis, forward-down toward the lean azimuth */
    float height;     /* axis length */
    float radius;     /* base radius (voxels), tapering to 0 at the tip */
    float brightness; /* colour factor (0.85..1.15) */
    float wd_delay;   /* colour ages at wd + wd_delay */
} tvt_blade;

/* A texel: res^3 voxels in TVT_BRICK^3 bricks. */
typedef struct tvt_texel {
    int res;                 /* voxels per side */
    int bits;                /* 8 or 16 bits per channel */
    int bricks_per_side;     /* res / TVT_BRICK */
    uint32_t *brick_index;   /* bricks_per_side^3 (x fastest): brick number or TVT_EMPTY_BRICK */
    size_t brick_count;      /* occupied bricks, stored in index order */
    uint64_t *brick_mask;    /* brick_count: bit i set = voxel i of the brick is stored (i = (z*4+y)*4+x) */
    uint32_t *brick_offset;  /* brick_count: the brick's first stored voxel */
    size_t voxel_count;      /* stored (non-empty) voxels */
    void *data;              /* voxel_count * 11 channels of uint8_t or uint16_t */
    float density_max;       /* scale of the density channel */
    uint16_t *blade_of_voxel;/* NULL, or voxel_count blade indices (TVT_NO_BLADE = none) */
    tvt_blade *blades;       /* NULL, or the blades of a static texel */
    size_t blade_count;
    tvt_allocator allocator;
} tvt_texel;

typedef struct tvt_grass_desc {
    int res;                 /* 8..1024, power of two; 0 = 64 */
    size_t blade_count;      /* 1..65534; 0 = 100 (use tvt_build_texel for an empty texel) */
    uint64_t seed;
    float height_min, height_max; /* fraction of res; 0 = 0.55, 0.9 */
    float radius_min, radius_max; /* base radius in voxels; 0 = 1.5 */
    float lean_min_deg, lean_max_deg; /* 0 = 3, 12 */
    int supersample;         /* samples per voxel side, 1..8; 0 = 3 */
    int bits;                /* 8 or 16; 0 = 8 */
    float specular;          /* 0 = 0.3 */
    const tvt_allocator *allocator; /* NULL = TVT_MALLOC/TVT_FREE */
    int (*progress)(void *user, float done);
    void *progress_user;
} tvt_grass_desc;

/* One point of the PBS, voxel units, 112 bytes. The rest state (root ... normal0) is where
   the point was at wd = 0 relative to its blade; tvt_age computes pos, normal, tangent, color
   and specular from it. The rest directions are unit vectors (normal0: length <= 1) stored as
   v * 32767 rounded (error below 2e-5, far under the 8-bit texel's); tvt_point_rest_dirs
   decodes them. */
typedef struct tvt_point {
    float pos[3], normal[3], tangent[3], color[3], specular, mass;
    float root[2];                   /* the blade's root on the ground (z = 0), unwrapped near pos */
    float ell;                       /* arc length from the root along the axis at wd = 0 */
    float radial[3];                 /* offset from the axis at wd = 0 */
    float brightness, specular0, wd_delay;
    int16_t axis[3], bend[3];        /* the blade's axis and droop direction */
    int16_t normal0[3];              /* normal at wd = 0 */
} tvt_point;

typedef struct tvt_points {
    tvt_point *p;
    size_t count;
    int res;
    float proportion;        /* points per unit density, as sampled */
    float wd;                /* weathering degree of the current state */
    tvt_allocator allocator;
} tvt_points;

typedef struct tvt_sample_options {
    float proportion;        /* points per unit density per voxel; 0 = 6 */
    uint64_t seed;
    const tvt_allocator *allocator;
    int (*progress)(void *user, float done);
    void *progress_user;
} tvt_sample_options;

typedef struct tvt_model_options {
    int water_curve;         /* TVT_WATER_STANDARD (0), TVT_WATER_AMPLE, TVT_WATER_COLD */
    float k_vein, k_mesophyll; /* 0 = 0.10, 0.40 */
    float vein_stiffness;    /* E_v / E_m; 0 = 2 (the paper's literal text: 0.5) */
    float stiffening;        /* gamma in E(wd) = E0 (1 + gamma wd); 0 = 4 */
    float area_ratio;        /* mesophyll : vein cross-section; 0 = 3 */
    float droop_max_deg;     /* 0 = 80 */
    float droop_exponent;    /* beta; 0 = 2 */
    float droop_length;      /* arc length where the bend reaches droop_max, fraction of res; 0 = 0.6 */
    float merge_threshold;   /* voxels; 0 = 0.15 */
    int no_merge;            /* 1 = never merge */
    float colour_jitter;     /* per-blade wd delay bound for colour; 0 = 0.05, negative = none */
    int (*progress)(void *user, float done);
    void *progress_user;
} tvt_model_options;

/* The model's scalars at one wd (tvt_model_eval). */
typedef struct tvt_model_state {
    float water;             /* w(wd), 1 at wd = 0 */
    float water_lost;        /* 1 - w */
    float chlorophyll;       /* Chl(wd), 1 at wd = 0 */
    float strain_vein, strain_mesophyll; /* realised volume strains */
    float axial_shrink, radial_shrink;   /* linear strains e_ax, e_rad */
    float droop;             /* Theta(wd), radians */
    float specular_factor;   /* 0.4 + 0.6 w */
    float color[3];          /* pigment colour, linear sRGB */
} tvt_model_state;

typedef struct tvt_splat_options {
    int bits;                /* 8 or 16; 0 = 8 */
    float sigma;             /* Gaussian sigma in voxels, 0.25..1; 0 = 0.5 */
    const tvt_allocator *allocator; /* NULL = the points' allocator */
    int (*progress)(void *user, float done);
    void *progress_user;
} tvt_splat_options;

/* ---- defaults ----------------------------------------------------------------------------------- */
TVTDEF tvt_grass_desc tvt_grass_default_desc(void);
TVTDEF tvt_sample_options tvt_sample_default_options(void);
TVTDEF tvt_model_options tvt_model_default_options(void);
TVTDEF tvt_splat_options tvt_splat_default_options(void);

/* ---- static texel ------------------------------------------------------------------------------- */

/* Random blades of desc (steps 1 of PIPELINE). out: desc->blade_count blades (default 100). */
TVTDEF tvt_result tvt_grass_blades(const tvt_grass_desc *desc, tvt_blade *out, size_t out_capacity);

/* Voxelises blades (any number, 0 gives an empty texel) at desc->res with desc's supersample,
   bits, allocator and progress; the blade table is copied into out. out is zeroed on failure. */
TVTDEF tvt_result tvt_build_texel(const tvt_blade *blades, size_t blade_count, const tvt_grass_desc *desc,
                                  tvt_texel *out);

/* tvt_grass_blades then tvt_build_texel. desc NULL = defaults. */
TVTDEF tvt_result tvt_build_grass(const tvt_grass_desc *desc, tvt_texel *out);

/* A texel from res^3 dense voxels (x fastest, then y, then z), for any content. bits 8 or 16. */
TVTDEF tvt_result tvt_texel_from_voxels(int res, const tvt_voxel *voxels, int bits, const tvt_allocator *allocator,
                                        tvt_texel *out);

/* Voxel (x, y, z), decoded; x and y wrap, z outside 0..res-1 gives an empty voxel. */
TVTDEF void tvt_texel_voxel(const tvt_texel *t, long x, long y, long z, tvt_voxel *out);

/* Bytes held by the texel: brick index, brick data, blade indices and blade table. */
TVTDEF size_t tvt_texel_bytes(const tvt_texel *t);

/* Sum of all voxels' density. */
TVTDEF double tvt_texel_total_density(const tvt_texel *t);

TVTDEF void tvt_texel_free(tvt_texel *t);

/* ---- points ------------------------------------------------------------------------------------- */

/* Texel -> points (step 3). TVT_ERR_EMPTY if the texel has no density. */
TVTDEF tvt_result tvt_sample(const tvt_texel *t, const tvt_sample_options *options, tvt_points *out);

/* Moves the points to weathering degree wd (step 4), then merges close points. wd in [0, 1];
   going back in wd is allowed (merges are not undone). */
TVTDEF tvt_result tvt_age(tvt_points *pts, float wd, const tvt_model_options *options);

/* Points -> texel (step 5). An empty point set gives an empty texel. */
TVTDEF tvt_result tvt_splat(const tvt_points *pts, const tvt_splat_options *options, tvt_texel *out);

TVTDEF void tvt_points_free(tvt_points *pts);
/* The rest directions of a point decoded: axis, bend (unit) and normal0 (length <= 1). */
TVTDEF void tvt_point_rest_dirs(const tvt_point *p, float axis[3], float bend[3], float normal0[3]);

/* ---- LOD pyramid (paper section 4.2) -------------------------------------------------------- */
#define TVT_MAX_LEVELS 8

/* Level l has res >> l voxels per side, each 2^l level-0 voxels wide. Densities are in the
   level-0 scale: a ray of direction d through level l accumulates optical depth
       tau = extinction * density_scale[l] * sum(density * (1 - a + a |t x d|) * step),
   a = anisotropy[l], t the unit tangent, step in level-0 voxels (see LOD). */
typedef struct tvt_lod {
    int levels;
    tvt_texel level[TVT_MAX_LEVELS];
    float density_scale[TVT_MAX_LEVELS]; /* the opacity correction of each level (1 at level 0) */
    float anisotropy[TVT_MAX_LEVELS];    /* the fibre share of each level's extinction (0 at 0) */
    float extinction;                    /* kappa */
} tvt_lod;

typedef struct tvt_lod_options {
    int levels;              /* 0 = down to 32^3 (1..8 levels, the coarsest at least 8^3) */
    float extinction;        /* kappa: optical depth of density 1 over one level-0 voxel; 0 = 1 */
    int calibration_rays;    /* rays per elevation for density_scale; 0 = 512 */
    uint64_t seed;
    const tvt_allocator *allocator; /* NULL = the texel's */
    int (*progress)(void *user, float done);
    void *progress_user;
} tvt_lod_options;

TVTDEF tvt_lod_options tvt_lod_default_options(void);

/* The pyramid of t (a copy of t is its level 0). See LOD in the doc block. */
TVTDEF tvt_result tvt_build_lod(const tvt_texel *t, const tvt_lod_options *options, tvt_lod *out);
TVTDEF size_t tvt_lod_bytes(const tvt_lod *l);
TVTDEF void tvt_lod_free(tvt_lod *l);

/* Density (scaled by the level's density_scale) at point p, in level-0 voxel units,
   trilinear between the level's voxel centres; x and y wrap, outside 0 <= z < res is 0. */
TVTDEF float tvt_lod_density(const tvt_lod *l, int level, const float p[3]);

/* Every channel at p, trilinear, the attributes density-weighted (as mingling and LOD do). */
TVTDEF void tvt_lod_voxel(const tvt_lod *l, int level, const float p[3], tvt_voxel *out);

/* Optical depth tau along origin + s dir, 0 <= s <= length (level-0 units; dir unit), midpoint
   samples every half voxel of the level. Transmittance = exp(-tau). */
TVTDEF float tvt_optical_depth(const tvt_lod *l, int level, const float origin[3], const float dir[3], float length);

/* Level for a footprint (the world size of a pixel, in level-0 voxels): floor(log2), clamped. */
TVTDEF int tvt_lod_level_for(const tvt_lod *l, float footprint);

/* ---- TVT: key frames over wd, mingling (paper sections 2.2 and 4.1) ------------------------- */
#define TVT_MAX_FRAMES 64

typedef struct tvt_tvt {
    int frame_count;
    float wd[TVT_MAX_FRAMES]; /* ascending: k / (frame_count - 1) */
    tvt_lod *frames;          /* frame_count pyramids */
    tvt_allocator allocator;
} tvt_tvt;

typedef struct tvt_tvt_options {
    int frames;               /* key frames, 2..64; 0 = 8 */
    int steps_per_frame;      /* ageing steps (each with merging) between frames, 1..64; 0 = 2 */
    const tvt_sample_options *sample; /* NULL = defaults (each may be NULL) */
    const tvt_model_options *model;
    const tvt_splat_options *splat;
    const tvt_lod_options *lod;
    const tvt_allocator *allocator;   /* NULL = TVT_MALLOC/TVT_FREE */
    int (*progress)(void *user, float done);
    void *progress_user;
} tvt_tvt_options;

/* A mingling function (the paper's Mg_i): the sample is seen at clamp((wd - delay) * rate, 0, 1);
   rate 0 means 1. */
typedef struct tvt_ageing_fn { float delay, rate; } tvt_ageing_fn;

TVTDEF tvt_tvt_options tvt_tvt_default_options(void);

/* Static texel -> points -> aged and splatted at each key frame -> one LOD pyramid per frame. */
TVTDEF tvt_result tvt_build_tvt(const tvt_texel *grass, const tvt_tvt_options *options, tvt_tvt *out);

/* The frames around wd (clamped to [0, 1]): wd lies at weight w between frame f and f + 1. */
TVTDEF void tvt_tvt_frames_at(const tvt_tvt *t, float wd, int *f, float *w);

/* A voxel of the TVT at wd, level and point p (level-0 units), interpolated in wd between key
   frames and trilinearly in space: density linear, attributes density-weighted. */
TVTDEF void tvt_tvt_voxel(const tvt_tvt *t, float wd, int level, const float p[3], tvt_voxel *out);

TVTDEF size_t tvt_tvt_bytes(const tvt_tvt *t);
TVTDEF void tvt_tvt_free(tvt_tvt *t);

/* The age a mingling function gives wd. fn NULL = identity. */
TVTDEF float tvt_ageing_apply(const tvt_ageing_fn *fn, float wd);

/* Mingling (Algorithm 2) at one wd: sample i seen at Mg_i(wd), interpolated between its level-0
   key frames; density summed, attributes density-weighted. fns NULL = all identity. All samples
   must have the same res (else TVT_ERR_BAD_RESOLUTION). bits 8 or 16 (0 = 8). */
TVTDEF tvt_result tvt_mingle(const tvt_tvt *samples, const tvt_ageing_fn *fns, size_t count, float wd, int bits,
                             const tvt_allocator *allocator, tvt_texel *out);

/* A mingled TVT: tvt_mingle at each of options->frames key frames, then their pyramids. */
TVTDEF tvt_result tvt_mingle_tvt(const tvt_tvt *samples, const tvt_ageing_fn *fns, size_t count,
                                 const tvt_tvt_options *options, tvt_tvt *out);

/* ---- sampling, shading and ray marching (for a renderer; see RENDERING) --------------------- */

/* Density only (cheap), interpolated in wd and trilinear, scaled as tvt_lod_density. */
TVTDEF float tvt_tvt_density(const tvt_tvt *t, float wd, int level, const float p[3]);

/* Light transmittance toward a directional light, per key frame, on the voxel grid of one level:
   exp(-tau) from each voxel centre to the top of the tile (x and y wrap). */
typedef struct tvt_shadow {
    int res, level, frames;
    float light[3];
    float *transmittance;    /* frames * res^3, x fastest */
    tvt_allocator allocator;
} tvt_shadow;

/* level -1 = the coarsest. light_dir: unit, toward the light, light_dir[2] > 0.05. */
TVTDEF tvt_result tvt_build_shadow(const tvt_tvt *t, int level, const float light_dir[3],
                                   const tvt_allocator *allocator, tvt_shadow *out);
/* Transmittance at p (level-0 units) at wd: trilinear, interpolated between frames; 1 above the
   tile. */
TVTDEF float tvt_shadow_at(const tvt_shadow *s, float wd, const float p[3]);
TVTDEF void tvt_shadow_free(tvt_shadow *s);

typedef struct tvt_shade_desc {
    float light_dir[3];      /* unit, toward the light; zero = normalize(0.45, 0.3, 0.84) */
    float light_rgb[3];      /* zero = (1, 1, 1) */
    float ambient_rgb[3];    /* zero = (0.22, 0.25, 0.3) */
    float kd, ks, shininess; /* Kajiya-Kay: 0 = 1, 0.35, 24 */
    const tvt_shadow *shadow;/* NULL = no self-shadowing */
} tvt_shade_desc;

TVTDEF tvt_shade_desc tvt_shade_default_desc(void);

/* What another renderer needs at p (level-0 units) along unit dir: the voxel of the level at wd
   (density, frame, colour, specular) in *out, and the return value, its extinction per level-0
   unit along dir (the level's fibre model; 0 where the grass is empty). */
TVTDEF float tvt_tvt_sample(const tvt_tvt *t, float wd, int level, const float p[3], const float dir[3], tvt_voxel *out);

/* One step of length step (level-0 units) at p along unit dir: returns its opacity
   alpha = 1 - exp(-sigma step) and writes its colour (not premultiplied) to rgb. */
TVTDEF float tvt_shade_point(const tvt_tvt *t, float wd, int level, const tvt_shade_desc *s, const float p[3],
                             const float dir[3], float step, float rgb[3]);

/* Front-to-back march from origin along unit dir for length (level-0 units) through one tile
   (x, y wrap), half-voxel steps of the level, empty space skipped with the coarsest level.
   rgb receives the premultiplied colour, *transmittance what is left (stops below 0.005). */
TVTDEF void tvt_march(const tvt_tvt *t, float wd, int level, const tvt_shade_desc *s, const float origin[3],
                      const float dir[3], float length, float rgb[3], float *transmittance);

/* ---- model -------------------------------------------------------------------------------------- */

/* The model's scalars at wd (clamped to [0, 1]; NaN gives wd = 0). options NULL = defaults. */
TVTDEF tvt_result tvt_model_eval(const tvt_model_options *options, float wd, tvt_model_state *out);

/* Pigment colour (linear sRGB) for chlorophyll fraction chl (1 = fresh) and browning in [0, 1]. */
TVTDEF void tvt_pigment_color(float chlorophyll, float browning, float rgb[3]);

/* wd(t) = clamp(t / duration, 0, 1); duration <= 0 or NaN input gives 0. */
TVTDEF float tvt_wd_from_time(float t, float duration);

/* ---- Tiling over a mesh shell (see MESH SHELL) -------------------------------------------------- */
/* A triangle mesh swept along its vertex normals: each triangle becomes a prism between the mesh
   (w = 0) and the mesh offset by `height` along the unit normals (w = 1). */
typedef struct tvt_shell_desc {
    const float *positions;  /* 3 per vertex (world) */
    const float *normals;    /* 3 per vertex: offset directions (normalised here), not zero */
    const float *uvs;        /* 2 per vertex: tile coordinates (tiles repeat; tile (floor u, floor v)) */
    size_t vertex_count;     /* 3..2^31 - 1 */
    const uint32_t *indices; /* 3 per triangle, each < vertex_count */
    size_t triangle_count;   /* >= 1 */
    float height;            /* shell height along the normals (world), > 0 */
    int allow_folded;        /* 0: a folded prism is TVT_ERR_FOLDED; nonzero: kept and counted */
    const tvt_allocator *allocator; /* NULL = TVT_MALLOC/TVT_FREE */
} tvt_shell_desc;

/* The prisms' tetrahedra with their affine maps, ready for point queries. */
typedef struct tvt_shell {
    size_t prism_count;      /* the triangles */
    float *tets;             /* 3 per prism, TVT_SHELL_TET_FLOATS floats each (private layout) */
    size_t folded;           /* prisms with a folded (inverted or flat) tetrahedron */
    float height;
    tvt_allocator allocator;
} tvt_shell;
enum { TVT_SHELL_TET_FLOATS = 42 };

/* Validates the mesh and builds the prisms (see MESH SHELL for the mapping and the errors). */
TVTDEF tvt_result tvt_build_shell(const tvt_shell_desc *desc, tvt_shell *out);
TVTDEF void tvt_shell_free(tvt_shell *s);
/* The three tetrahedra of the prism over triangle tri (vertex ids v for the mesh vertex, v +
   vertex_count for its offset copy), by the rule of MESH SHELL: shared side faces are split the
   same way from both sides. */
TVTDEF void tvt_shell_prism_tets(const uint32_t tri[3], uint32_t vertex_count, uint32_t tets[3][4]);
/* World point p -> texel space uvw (u, v in tile units, w in [0, 1] from the mesh to the outer
   surface) in prism `prism`. Returns 1 if p lies in the prism (1e-5 of barycentric slack), 0 if
   not (uvw is then extrapolated from its nearest tetrahedron), -1 for a bad prism index. */
TVTDEF int tvt_shell_map(const tvt_shell *s, size_t prism, const float p[3], float uvw[3]);
/* The inverse: texel space uvw -> world point p in prism `prism`; same return values. */
TVTDEF int tvt_shell_unmap(const tvt_shell *s, size_t prism, const float uvw[3], float p[3]);

/* A per-tile wd map over the mesh's tile coordinates: tile (i, j) reads pixel (i - origin[0],
   j - origin[1]) of a width x height grid of wd values (row j, x fastest), wrapped (wrap
   nonzero) or clamped at the border. */
typedef struct tvt_wd_map {
    const float *wd;
    int width, height;
    int origin[2];
    int wrap;
} tvt_wd_map;
/* The tile's wd, clamped to [0, 1]; a NaN value, a NULL map or an empty one gives 0. */
TVTDEF float tvt_tile_wd(const tvt_wd_map *m, long i, long j);

/* "TVT_OK", "TVT_ERR_EMPTY", ... (the enum name); "TVT_ERR_?" outside the enum. */
TVTDEF const char *tvt_result_string(tvt_result r);

#ifdef __cplusplus
}
#endif
#endif /* TVT_TEXEL_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef TVT_IMPLEMENTATION
#ifndef TVT_IMPLEMENTATION_DONE
#define TVT_IMPLEMENTATION_DONE

#include <string.h>
#include <math.h>

#if defined(TVT_MALLOC) && defined(TVT_FREE)
/* both given */
#elif !defined(TVT_MALLOC) && !defined(TVT_FREE)
#include <stdlib.h>
#define TVT_MALLOC(sz) malloc(sz)
#define TVT_FREE(p) free(p)
#else
#error "texel.h: define both TVT_MALLOC and TVT_FREE, or neither"
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
   Small helpers: allocation, hashing, vectors
   --------------------------------------------------------------------------------------------- */
#define TVT__PI 3.14159265358979323846

static void *tvt__default_alloc(void *user, size_t size) { (void)user; return TVT_MALLOC(size); }
static void tvt__default_free(void *user, void *p) { (void)user; TVT_FREE(p); }

static tvt_allocator tvt__resolve_allocator(const tvt_allocator *a)
{
    tvt_allocator r;
    if (a && a->alloc && a->free) return *a;
    r.alloc = tvt__default_alloc;
    r.free = tvt__default_free;
    r.user = NULL;
    return r;
}

static void *tvt__alloc(const tvt_allocator *a, size_t count, size_t size)
{
    if (size != 0 && count > ((size_t)-1) / size) return NULL;
    if (count * size == 0) return a->alloc(a->user, 1);
    return a->alloc(a->user, count * size);
}

static void tvt__free(const tvt_allocator *a, void *p) { if (p) a->free(a->user, p); }

static int tvt__finite(float x) { return x == x && x - x == 0.0f; }

/* splitmix64: the per-voxel / per-blade random streams */
static uint64_t tvt__mix(uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* uniform in [0, 1) with 24 bits, advancing the state */
static float tvt__rand(uint64_t *s)
{
    *s += 0x9E3779B97F4A7C15ull;
    return (float)(tvt__mix(*s) >> 40) * (1.0f / 16777216.0f);
}

static float tvt__dot(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void tvt__normalize(float *v)
{
    float l = sqrtf(tvt__dot(v, v));
    if (l > 1e-20f) { v[0] /= l; v[1] /= l; v[2] /= l; }
}

static int tvt__check_res(int res)
{
    return res >= 8 && res <= 1024 && (res & (res - 1)) == 0;
}

static int tvt__report(int (*progress)(void *, float), void *user, float done)
{
    return progress ? progress(user, done) : 0;
}

/* ---------------------------------------------------------------------------------------------
   Sparse float accumulation grid (building and splatting). Per voxel TVT__ACC floats:
   weight, normal*3, tangent*3, colour*3, specular, best coverage, best blade.
   --------------------------------------------------------------------------------------------- */
enum { TVT__ACC = 13, TVT__BV = TVT_BRICK * TVT_BRICK * TVT_BRICK };

/* Bricks live in pages of TVT__PAGE, so that growing never copies them. */
enum { TVT__PAGE = 256 };

typedef struct tvt__acc {
    int res, nb;
    uint32_t *index;
    float **pages;
    size_t page_count, page_cap, count;
    int failed;
    tvt_allocator a;
} tvt__acc;

static tvt_result tvt__acc_init(tvt__acc *g, int res, const tvt_allocator *a)
{
    size_t n, i;
    memset(g, 0, sizeof(*g));
    g->res = res;
    g->nb = res / TVT_BRICK;
    g->a = *a;
    n = (size_t)g->nb * g->nb * g->nb;
    g->index = (uint32_t *)tvt__alloc(a, n, sizeof(uint32_t));
    if (!g->index) return TVT_ERR_OUT_OF_MEMORY;
    for (i = 0; i < n; i++) g->index[i] = TVT_EMPTY_BRICK;
    return TVT_OK;
}

static void tvt__acc_free(tvt__acc *g)
{
    size_t i;
    for (i = 0; i < g->page_count; i++) tvt__free(&g->a, g->pages[i]);
    tvt__free(&g->a, g->pages);
    tvt__free(&g->a, g->index);
    memset(g, 0, sizeof(*g));
}

/* the TVT__BV * TVT__ACC floats of brick k */
static float *tvt__acc_brick(const tvt__acc *g, size_t k)
{
    return g->pages[k / TVT__PAGE] + (k % TVT__PAGE) * (size_t)(TVT__ACC * TVT__BV);
}

static int tvt__acc_grow(tvt__acc *g)
{
    float *page;
    if (g->page_count == g->page_cap) {
        size_t cap = g->page_cap ? 2 * g->page_cap : 16;
        float **pages = (float **)tvt__alloc(&g->a, cap, sizeof(float *));
        if (!pages) return 0;
        if (g->page_count) memcpy(pages, g->pages, g->page_count * sizeof(float *));
        tvt__free(&g->a, g->pages);
        g->pages = pages;
        g->page_cap = cap;
    }
    page = (float *)tvt__alloc(&g->a, TVT__PAGE, sizeof(float) * TVT__ACC * TVT__BV);
    if (!page) return 0;
    g->pages[g->page_count++] = page;
    return 1;
}

/* The accumulator of voxel (x, y, z) (x, y in 0..res-1, z in 0..res-1), its brick created on
   demand; NULL after an allocation failure (g->failed is then set). */
static float *tvt__acc_voxel(tvt__acc *g, int x, int y, int z)
{
    size_t b = ((size_t)(z >> 2) * g->nb + (size_t)(y >> 2)) * g->nb + (size_t)(x >> 2);
    uint32_t k = g->index[b];
    if (k == TVT_EMPTY_BRICK) {
        float *d;
        size_t i;
        if (g->failed || (g->count == g->page_count * TVT__PAGE && !tvt__acc_grow(g))) { g->failed = 1; return NULL; }
        k = (uint32_t)g->count++;
        d = tvt__acc_brick(g, k);
        memset(d, 0, sizeof(float) * TVT__ACC * TVT__BV);
        for (i = 0; i < TVT__BV; i++) d[i * TVT__ACC + 12] = -1.0f;
        g->index[b] = k;
    }
    return tvt__acc_brick(g, k) + (size_t)(((z & 3) * 4 + (y & 3)) * 4 + (x & 3)) * TVT__ACC;
}

/* ---------------------------------------------------------------------------------------------
   Channel encoding
   --------------------------------------------------------------------------------------------- */
static unsigned tvt__q(float v, float qmax)
{
    float f = v * qmax + 0.5f;
    if (!(f > 0.0f)) return 0;
    if (f > qmax) return (unsigned)qmax;
    return (unsigned)f;
}

/* voxel -> 11 quantised channels */
static void tvt__encode(const tvt_voxel *v, float density_max, int bits, unsigned *q)
{
    float qm = bits == 8 ? 255.0f : 65535.0f, d = density_max > 0 ? v->density / density_max : 0.0f;
    int i;
    q[0] = tvt__q(bits == 8 ? sqrtf(d > 0 ? d : 0) : d, qm);
    for (i = 0; i < 3; i++) {
        q[1 + i] = tvt__q(0.5f * (v->normal[i] + 1.0f), qm);
        q[4 + i] = tvt__q(0.5f * (v->tangent[i] + 1.0f), qm);
        q[7 + i] = tvt__q(v->color[i], qm);
    }
    q[10] = tvt__q(v->specular, qm);
}

static void tvt__decode(const unsigned *q, float density_max, int bits, tvt_voxel *v)
{
    float inv = bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f, d = (float)q[0] * inv;
    int i;
    if (q[0] == 0) { memset(v, 0, sizeof(*v)); return; } /* an empty voxel has no attributes */
    v->density = density_max * (bits == 8 ? d * d : d);
    for (i = 0; i < 3; i++) {
        v->normal[i] = (float)q[1 + i] * inv * 2.0f - 1.0f;
        v->tangent[i] = (float)q[4 + i] * inv * 2.0f - 1.0f;
        v->color[i] = (float)q[7 + i] * inv;
    }
    v->specular = (float)q[10] * inv;
}

static void tvt__store(tvt_texel *t, size_t slot, const unsigned *q)
{
    int c;
    if (t->bits == 8) {
        uint8_t *d = (uint8_t *)t->data + slot * TVT_CHANNELS;
        for (c = 0; c < TVT_CHANNELS; c++) d[c] = (uint8_t)q[c];
    } else {
        uint16_t *d = (uint16_t *)t->data + slot * TVT_CHANNELS;
        for (c = 0; c < TVT_CHANNELS; c++) d[c] = (uint16_t)q[c];
    }
}

/* channels 0 (density) and 4..6 (tangent) only; the others are left as they were */
static void tvt__load_density_tangent(const tvt_texel *t, size_t slot, unsigned *q)
{
    if (t->bits == 8) {
        const uint8_t *d = (const uint8_t *)t->data + slot * TVT_CHANNELS;
        q[0] = d[0]; q[4] = d[4]; q[5] = d[5]; q[6] = d[6];
    } else {
        const uint16_t *d = (const uint16_t *)t->data + slot * TVT_CHANNELS;
        q[0] = d[0]; q[4] = d[4]; q[5] = d[5]; q[6] = d[6];
    }
}

static void tvt__load(const tvt_texel *t, size_t slot, unsigned *q)
{
    int c;
    if (t->bits == 8) {
        const uint8_t *d = (const uint8_t *)t->data + slot * TVT_CHANNELS;
        for (c = 0; c < TVT_CHANNELS; c++) q[c] = d[c];
    } else {
        const uint16_t *d = (const uint16_t *)t->data + slot * TVT_CHANNELS;
        for (c = 0; c < TVT_CHANNELS; c++) q[c] = d[c];
    }
}

/* ---------------------------------------------------------------------------------------------
   Accumulator -> texel: normalise attributes, find the density scale, keep bricks with density
   --------------------------------------------------------------------------------------------- */
/* accumulated voxel -> decoded voxel (density = weight * density_factor) */
static void tvt__acc_resolve(const float *a, float density_factor, tvt_voxel *v)
{
    float w = a[0];
    int i;
    v->density = w * density_factor;
    for (i = 0; i < 3; i++) {
        v->normal[i] = w > 0 ? a[1 + i] / w : 0.0f;
        v->tangent[i] = w > 0 ? a[4 + i] / w : 0.0f;
        v->color[i] = w > 0 ? a[7 + i] / w : 0.0f;
    }
    v->specular = w > 0 ? a[10] / w : 0.0f;
    if (w > 0) tvt__normalize(v->tangent);
}

/* The voxels of accumulator brick k that quantise to a nonzero density, as a mask (the
   density channel of tvt__encode alone). */
static uint64_t tvt__brick_occupied(const tvt__acc *g, uint32_t k, float density_factor, float density_max, int bits)
{
    const float *brick = tvt__acc_brick(g, k);
    float qm = bits == 8 ? 255.0f : 65535.0f;
    uint64_t mask = 0;
    size_t i;
    for (i = 0; i < TVT__BV; i++) {
        float d = density_max > 0 ? brick[i * TVT__ACC] * density_factor / density_max : 0.0f;
        if (tvt__q(bits == 8 ? sqrtf(d > 0 ? d : 0) : d, qm)) mask |= (uint64_t)1 << i;
    }
    return mask;
}

/* bit count (the builtin only where it is one instruction: elsewhere it is a library call) */
static unsigned tvt__popcount(uint64_t x)
{
#if (defined(__GNUC__) || defined(__clang__)) && defined(__POPCNT__)
    return (unsigned)__builtin_popcountll(x);
#else
    x = x - ((x >> 1) & 0x5555555555555555ull);
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
    return (unsigned)((x * 0x0101010101010101ull) >> 56);
#endif
}

static tvt_result tvt__texel_alloc(tvt_texel *t, int res, int bits, size_t bricks, size_t voxels, int with_blades,
                                   const tvt_allocator *a)
{
    size_t nidx = (size_t)(res / TVT_BRICK) * (res / TVT_BRICK) * (res / TVT_BRICK), i;
    memset(t, 0, sizeof(*t));
    t->res = res;
    t->bits = bits;
    t->bricks_per_side = res / TVT_BRICK;
    t->allocator = *a;
    t->brick_count = bricks;
    t->voxel_count = voxels;
    t->brick_index = (uint32_t *)tvt__alloc(a, nidx, sizeof(uint32_t));
    t->brick_mask = (uint64_t *)tvt__alloc(a, bricks, sizeof(uint64_t));
    t->brick_offset = (uint32_t *)tvt__alloc(a, bricks, sizeof(uint32_t));
    t->data = tvt__alloc(a, voxels * TVT_CHANNELS, (size_t)bits / 8);
    if (with_blades) t->blade_of_voxel = (uint16_t *)tvt__alloc(a, voxels, sizeof(uint16_t));
    if (!t->brick_index || !t->brick_mask || !t->brick_offset || !t->data || (with_blades && !t->blade_of_voxel)) {
        tvt_texel_free(t);
        return TVT_ERR_OUT_OF_MEMORY;
    }
    for (i = 0; i < nidx; i++) t->brick_index[i] = TVT_EMPTY_BRICK;
    return TVT_OK;
}

/* Writes the accumulator into a new texel. Bricks come in index order whatever order the
   accumulator made them in, so the texel's bytes depend on its content only; a brick keeps the
   voxels of nonzero quantised density (its mask), in voxel order. */
static tvt_result tvt__acc_to_texel(const tvt__acc *g, float density_factor, int bits, int with_blades,
                                    tvt_texel *out)
{
    size_t nidx = (size_t)g->nb * g->nb * g->nb, b, i, kept = 0, voxels = 0, slot = 0;
    uint64_t *masks;
    float dmax = 0.0f;
    tvt_result r;
    for (i = 0; i < g->count * TVT__BV; i++) {
        float d = tvt__acc_brick(g, i / TVT__BV)[(i % TVT__BV) * TVT__ACC] * density_factor;
        if (d > dmax) dmax = d;
    }
    masks = (uint64_t *)tvt__alloc(&g->a, g->count, sizeof(uint64_t));
    if (!masks) return TVT_ERR_OUT_OF_MEMORY;
    for (b = 0; b < g->count; b++) {
        masks[b] = tvt__brick_occupied(g, (uint32_t)b, density_factor, dmax, bits);
        if (masks[b]) { kept++; voxels += tvt__popcount(masks[b]); }
    }
    r = tvt__texel_alloc(out, g->res, bits, kept, voxels, with_blades, &g->a);
    if (r != TVT_OK) { tvt__free(&g->a, masks); return r; }
    out->density_max = dmax;
    kept = 0;
    for (b = 0; b < nidx; b++) {
        uint32_t k = g->index[b];
        if (k == TVT_EMPTY_BRICK || !masks[k]) continue;
        out->brick_index[b] = (uint32_t)kept;
        out->brick_mask[kept] = masks[k];
        out->brick_offset[kept] = (uint32_t)slot;
        for (i = 0; i < TVT__BV; i++) {
            const float *a = tvt__acc_brick(g, k) + i * TVT__ACC;
            tvt_voxel v;
            unsigned q[TVT_CHANNELS];
            if (!((masks[k] >> i) & 1)) continue;
            tvt__acc_resolve(a, density_factor, &v);
            tvt__encode(&v, dmax, bits, q);
            tvt__store(out, slot, q);
            if (with_blades) out->blade_of_voxel[slot] = (uint16_t)(a[12] >= 0 ? (unsigned)a[12] : TVT_NO_BLADE);
            slot++;
        }
        kept++;
    }
    tvt__free(&g->a, masks);
    return TVT_OK;
}

/* ---------------------------------------------------------------------------------------------
   Model: curves, shrinkage, droop, pigment colour
   --------------------------------------------------------------------------------------------- */
static float tvt__logistic(float x, float lo, float c, float s) { return lo + (1.0f - lo) / (1.0f + expf((x - c) / s)); }

static float tvt__water(int curve, float wd)
{
    static const float c[3] = {0.45f, 0.60f, 0.55f}, s[3] = {0.08f, 0.08f, 0.15f};
    return tvt__logistic(wd, 0.25f, c[curve], s[curve]) / tvt__logistic(0.0f, 0.25f, c[curve], s[curve]);
}

static float tvt__chlorophyll(float wd) { return tvt__logistic(wd, 0.03f, 0.40f, 0.10f) / tvt__logistic(0.0f, 0.03f, 0.40f, 0.10f); }

static float tvt__gauss(float x, float mu, float s1, float s2)
{
    float d = (x - mu) / (x < mu ? s1 : s2);
    return expf(-0.5f * d * d);
}

/* absorption spectra (unit peak), sums of Gaussians at the literature peaks */
static float tvt__abs_chla(float l) { return tvt__gauss(l, 430, 18, 18) + 0.8f * tvt__gauss(l, 665, 18, 18) + 0.3f * tvt__gauss(l, 620, 20, 20); }
static float tvt__abs_chlb(float l) { return tvt__gauss(l, 455, 18, 18) + 0.6f * tvt__gauss(l, 645, 16, 16); }
static float tvt__abs_car(float l) { return 0.75f * tvt__gauss(l, 425, 14, 14) + tvt__gauss(l, 452, 14, 14) + 0.9f * tvt__gauss(l, 480, 14, 14); }

TVTDEF void tvt_pigment_color(float chlorophyll, float browning, float rgb[3])
{
    float X = 0, Y = 0, Z = 0, N = 0, chl = chlorophyll, br = browning;
    int i;
    if (!(chl > 0)) chl = 0;
    if (!(br > 0)) br = 0;
    for (i = 0; i < 81; i++) {
        float l = 380.0f + 5.0f * (float)i;
        float A = 3.0f * ((27.0f / 40.0f) * chl * tvt__abs_chla(l) + (9.0f / 40.0f) * chl * tvt__abs_chlb(l) +
                          (4.0f / 40.0f) * tvt__abs_car(l)) + 1.5f * br * expf(-(l - 380.0f) / 110.0f);
        float R = 0.55f * expf(-A);
        float x = 1.056f * tvt__gauss(l, 599.8f, 37.9f, 31.0f) + 0.362f * tvt__gauss(l, 442.0f, 16.0f, 26.7f) -
                  0.065f * tvt__gauss(l, 501.1f, 20.4f, 26.2f);
        float y = 0.821f * tvt__gauss(l, 568.8f, 46.9f, 40.5f) + 0.286f * tvt__gauss(l, 530.9f, 16.3f, 31.1f);
        float z = 1.217f * tvt__gauss(l, 437.0f, 11.8f, 36.0f) + 0.681f * tvt__gauss(l, 459.0f, 26.0f, 13.8f);
        X += R * x; Y += R * y; Z += R * z; N += y;
    }
    X /= N; Y /= N; Z /= N;
    rgb[0] = 3.2406f * X - 1.5372f * Y - 0.4986f * Z;
    rgb[1] = -0.9689f * X + 1.8758f * Y + 0.0415f * Z;
    rgb[2] = 0.0557f * X - 0.2040f * Y + 1.0570f * Z;
    for (i = 0; i < 3; i++) rgb[i] = rgb[i] < 0 ? 0 : rgb[i] > 1 ? 1 : rgb[i];
}

static int tvt__model_resolve(const tvt_model_options *in, tvt_model_options *o)
{
    tvt_model_options d = tvt_model_default_options();
    *o = in ? *in : d;
    if (o->water_curve < 0 || o->water_curve > 2) return 0;
#define TVT__DEF(f) if (o->f == 0) o->f = d.f
    TVT__DEF(k_vein); TVT__DEF(k_mesophyll); TVT__DEF(vein_stiffness); TVT__DEF(stiffening);
    TVT__DEF(area_ratio); TVT__DEF(droop_max_deg); TVT__DEF(droop_exponent); TVT__DEF(droop_length);
    TVT__DEF(merge_threshold);
    TVT__DEF(colour_jitter);
#undef TVT__DEF
    if (o->colour_jitter < 0) o->colour_jitter = 0;
    return tvt__finite(o->k_vein) && tvt__finite(o->k_mesophyll) && tvt__finite(o->vein_stiffness) &&
           tvt__finite(o->stiffening) && tvt__finite(o->area_ratio) && tvt__finite(o->droop_max_deg) &&
           tvt__finite(o->droop_exponent) && tvt__finite(o->droop_length) && tvt__finite(o->merge_threshold) && tvt__finite(o->colour_jitter) &&
           o->k_vein > 0 && o->k_vein < 1 && o->k_mesophyll > 0 && o->k_mesophyll < 1 && o->vein_stiffness > 0 &&
           o->stiffening > 0 && o->area_ratio > 0 && o->droop_max_deg > 0 && o->droop_max_deg <= 90 &&
           o->droop_exponent > 0 && o->droop_exponent <= 8 && o->droop_length > 0.01f &&
           o->droop_length <= 4 && o->merge_threshold > 0 && o->merge_threshold <= 1 && o->colour_jitter <= 0.5f;
}

/* realised strains: d eps = k dw'(wd) E0 / E(wd), midpoint rule on 256 steps over [0, wd] */
static void tvt__strains(const tvt_model_options *o, float wd, float *eps_v, float *eps_m)
{
    const int n = 256;
    double h = wd / n, sum = 0.0;
    int i;
    for (i = 0; i < n; i++) {
        float a = (float)(i * h), b = (float)((i + 1) * h), mid = 0.5f * (a + b);
        float ddw = tvt__water(o->water_curve, a) - tvt__water(o->water_curve, b);
        sum += ddw / (1.0 + o->stiffening * mid);
    }
    *eps_v = (float)(o->k_vein * sum);
    *eps_m = (float)(o->k_mesophyll * sum);
}

static void tvt__model_at(const tvt_model_options *o, float wd, tvt_model_state *s)
{
    float ev, em, mix, lost1 = 1.0f - tvt__water(o->water_curve, 1.0f);
    s->water = tvt__water(o->water_curve, wd);
    s->water_lost = 1.0f - s->water;
    s->chlorophyll = tvt__chlorophyll(wd);
    tvt__strains(o, wd, &ev, &em);
    s->strain_vein = ev;
    s->strain_mesophyll = em;
    /* stiffness- and area-weighted volume strain of the blade's cross-section */
    mix = (o->vein_stiffness * ev + o->area_ratio * em) / (o->vein_stiffness + o->area_ratio);
    s->axial_shrink = 1.0f - cbrtf(1.0f - mix);
    s->radial_shrink = 1.0f - sqrtf(1.0f - em);
    s->droop = (float)(o->droop_max_deg * TVT__PI / 180.0) * (s->water_lost / lost1);
    s->specular_factor = 0.4f + 0.6f * s->water;
    tvt_pigment_color(s->chlorophyll, s->water_lost / lost1, s->color);
}

TVTDEF tvt_result tvt_model_eval(const tvt_model_options *options, float wd, tvt_model_state *out)
{
    tvt_model_options o;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!tvt__model_resolve(options, &o)) return TVT_ERR_BAD_PARAMETER;
    if (!(wd > 0)) wd = 0;
    if (wd > 1) wd = 1;
    tvt__model_at(&o, wd, out);
    return TVT_OK;
}

TVTDEF float tvt_wd_from_time(float t, float duration)
{
    float wd;
    if (!(duration > 0) || !tvt__finite(duration)) return 0.0f;
    wd = t / duration;
    return wd > 0 ? (wd < 1 ? wd : 1.0f) : 0.0f;
}

/* ---------------------------------------------------------------------------------------------
   Blades and voxelisation
   --------------------------------------------------------------------------------------------- */
static tvt_result tvt__grass_resolve(const tvt_grass_desc *in, tvt_grass_desc *d)
{
    tvt_grass_desc def = tvt_grass_default_desc();
    *d = in ? *in : def;
#define TVT__DEF(f) if (d->f == 0) d->f = def.f
    TVT__DEF(res); TVT__DEF(blade_count); TVT__DEF(height_min); TVT__DEF(height_max); TVT__DEF(radius_min);
    TVT__DEF(radius_max); TVT__DEF(lean_min_deg); TVT__DEF(lean_max_deg); TVT__DEF(supersample); TVT__DEF(bits);
    TVT__DEF(specular);
#undef TVT__DEF
    if (!tvt__check_res(d->res) || (d->bits != 8 && d->bits != 16)) return TVT_ERR_BAD_RESOLUTION;
    if (!tvt__finite(d->height_min) || !tvt__finite(d->height_max) || !tvt__finite(d->radius_min) ||
        !tvt__finite(d->radius_max) || !tvt__finite(d->lean_min_deg) || !tvt__finite(d->lean_max_deg) ||
        !tvt__finite(d->specular) || d->height_min <= 0 || d->height_max > 1 || d->height_min > d->height_max ||
        d->radius_min <= 0 || d->radius_min > d->radius_max || d->radius_max > 0.25f * (float)d->res ||
        d->lean_min_deg < 0 || d->lean_min_deg > d->lean_max_deg || d->lean_max_deg > 60 ||
        d->supersample < 1 || d->supersample > 8 || d->specular < 0 || d->specular > 1)
        return TVT_ERR_BAD_PARAMETER;
    if (d->blade_count > 65534) return TVT_ERR_TOO_LARGE;
    return TVT_OK;
}

TVTDEF tvt_result tvt_grass_blades(const tvt_grass_desc *desc, tvt_blade *out, size_t out_capacity)
{
    tvt_grass_desc d;
    tvt_result r = tvt__grass_resolve(desc, &d);
    size_t i;
    if (r != TVT_OK) return r;
    if (!out || out_capacity < d.blade_count) return TVT_ERR_INVALID_ARGUMENT;
    for (i = 0; i < d.blade_count; i++) {
        uint64_t s = tvt__mix(d.seed ^ tvt__mix((uint64_t)i + 1));
        tvt_blade *b = out + i;
        float res = (float)d.res, lean, az, ca, sa;
        /* roots on a 1/4096 lattice: integer shifts of them are exact in float */
        b->root[0] = floorf(tvt__rand(&s) * res * 4096.0f) / 4096.0f;
        b->root[1] = floorf(tvt__rand(&s) * res * 4096.0f) / 4096.0f;
        b->root[2] = 0.0f;
        b->height = res * (d.height_min + (d.height_max - d.height_min) * tvt__rand(&s));
        b->radius = d.radius_min + (d.radius_max - d.radius_min) * tvt__rand(&s);
        lean = (float)((d.lean_min_deg + (d.lean_max_deg - d.lean_min_deg) * tvt__rand(&s)) * TVT__PI / 180.0);
        az = (float)(2.0 * TVT__PI * tvt__rand(&s));
        ca = cosf(az); sa = sinf(az);
        b->axis[0] = sinf(lean) * ca; b->axis[1] = sinf(lean) * sa; b->axis[2] = cosf(lean);
        b->bend[0] = cosf(lean) * ca; b->bend[1] = cosf(lean) * sa; b->bend[2] = -sinf(lean);
        b->brightness = 0.85f + 0.3f * tvt__rand(&s);
        b->wd_delay = 2.0f * tvt__rand(&s) - 1.0f; /* scaled by the model's colour_jitter */
    }
    return TVT_OK;
}

/* Coverage of voxel (vx, vy, vz) (coordinates relative to the blade's integer root cell) by
   blade b whose root has fractional part rf: returns the covered fraction and the summed
   normals of the covered samples. */
static float tvt__voxel_cover(const tvt_blade *b, const float *rf, int vx, int vy, int vz, int ss, float *nsum)
{
    int i, j, k, inside = 0;
    float inv = 1.0f / (float)ss;
    nsum[0] = nsum[1] = nsum[2] = 0.0f;
    for (k = 0; k < ss; k++)
        for (j = 0; j < ss; j++)
            for (i = 0; i < ss; i++) {
                float p[3], ell, q[3], d2, rl;
                p[0] = (float)vx + ((float)i + 0.5f) * inv - rf[0];
                p[1] = (float)vy + ((float)j + 0.5f) * inv - rf[1];
                p[2] = (float)vz + ((float)k + 0.5f) * inv;
                ell = tvt__dot(p, b->axis);
                if (ell < 0 || ell > b->height) continue;
                q[0] = p[0] - ell * b->axis[0]; q[1] = p[1] - ell * b->axis[1]; q[2] = p[2] - ell * b->axis[2];
                d2 = tvt__dot(q, q);
                rl = b->radius * (1.0f - ell / b->height);
                if (d2 >= rl * rl) continue;
                inside++;
                nsum[0] += q[0] / rl; nsum[1] += q[1] / rl; nsum[2] += q[2] / rl;
            }
    return (float)inside / (float)(ss * ss * ss);
}

static void tvt__acc_add(float *a, float cov, const float *nsum, int ss, const tvt_blade *b, const float *green,
                         float ms, size_t blade_index)
{
    float nn = 1.0f / (float)(ss * ss * ss);
    int c;
    a[0] += cov;
    for (c = 0; c < 3; c++) {
        a[1 + c] += nsum[c] * nn;
        a[4 + c] += cov * b->axis[c];
        a[7 + c] += cov * b->brightness * green[c];
    }
    a[10] += cov * ms;
    if (cov > a[11]) { a[11] = cov; a[12] = (float)blade_index; }
}

/* One blade into the accumulator, layer by layer along z: each layer's voxels lie within
   radius + 1 of where the axis crosses the layer. */
static int tvt__voxelize_blade(tvt__acc *g, const tvt_blade *b, size_t bi, int ss, const float *green, float ms)
{
    int res = g->res, top = (int)ceilf(b->height * b->axis[2]), z;
    float rf[2];
    int ri[2];
    ri[0] = (int)floorf(b->root[0]); ri[1] = (int)floorf(b->root[1]);
    rf[0] = b->root[0] - (float)ri[0]; rf[1] = b->root[1] - (float)ri[1];
    if (top > res) top = res;
    for (z = 0; z < top; z++) {
        float t = ((float)z + 0.5f) / b->axis[2];
        float cx = rf[0] + t * b->axis[0], cy = rf[1] + t * b->axis[1];
        float reach = b->radius + 1.0f + 0.5f * sqrtf(b->axis[0] * b->axis[0] + b->axis[1] * b->axis[1]) / b->axis[2];
        int x0 = (int)floorf(cx - reach), x1 = (int)floorf(cx + reach), y0 = (int)floorf(cy - reach),
            y1 = (int)floorf(cy + reach), x, y;
        for (y = y0; y <= y1; y++)
            for (x = x0; x <= x1; x++) {
                float nsum[3], cov = tvt__voxel_cover(b, rf, x, y, z, ss, nsum), *a;
                if (cov <= 0) continue;
                a = tvt__acc_voxel(g, ((x + ri[0]) % res + res) % res, ((y + ri[1]) % res + res) % res, z);
                if (!a) return 0;
                tvt__acc_add(a, cov, nsum, ss, b, green, ms, bi);
            }
    }
    return 1;
}

static int tvt__blades_valid(const tvt_blade *b, size_t n, int res)
{
    size_t i;
    for (i = 0; i < n; i++) {
        const float *f = &b[i].root[0];
        size_t k;
        for (k = 0; k < sizeof(tvt_blade) / sizeof(float); k++)
            if (!tvt__finite(f[k])) return 0;
        if (b[i].root[0] < 0 || b[i].root[0] >= (float)res || b[i].root[1] < 0 || b[i].root[1] >= (float)res ||
            b[i].axis[2] <= 0.05f || b[i].height <= 0 || b[i].radius <= 0 || b[i].radius > 0.25f * (float)res ||
            fabsf(tvt__dot(b[i].axis, b[i].axis) - 1.0f) > 1e-3f || b[i].brightness < 0 ||
            b[i].wd_delay < -1 || b[i].wd_delay > 1)
            return 0;
    }
    return 1;
}

TVTDEF tvt_result tvt_build_texel(const tvt_blade *blades, size_t blade_count, const tvt_grass_desc *desc,
                                  tvt_texel *out)
{
    tvt_grass_desc d;
    tvt_allocator a;
    tvt__acc g;
    tvt_result r;
    float green[3];
    size_t i;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!blades && blade_count) return TVT_ERR_INVALID_ARGUMENT;
    r = tvt__grass_resolve(desc, &d);
    if (r != TVT_OK) return r;
    if (blade_count > 65534) return TVT_ERR_TOO_LARGE;
    if (!tvt__blades_valid(blades, blade_count, d.res)) return TVT_ERR_BAD_PARAMETER;
    a = tvt__resolve_allocator(d.allocator);
    tvt_pigment_color(1.0f, 0.0f, green);
    r = tvt__acc_init(&g, d.res, &a);
    for (i = 0; r == TVT_OK && i < blade_count; i++) {
        if (!tvt__voxelize_blade(&g, blades + i, i, d.supersample, green, d.specular)) r = TVT_ERR_OUT_OF_MEMORY;
        else if (tvt__report(d.progress, d.progress_user, 0.95f * (float)(i + 1) / (float)blade_count))
            r = TVT_CANCELLED;
    }
    if (r == TVT_OK) r = tvt__acc_to_texel(&g, 1.0f, d.bits, 1, out);
    tvt__acc_free(&g);
    if (r == TVT_OK && blade_count) {
        out->blades = (tvt_blade *)tvt__alloc(&a, blade_count, sizeof(tvt_blade));
        if (!out->blades) r = TVT_ERR_OUT_OF_MEMORY;
        else { memcpy(out->blades, blades, blade_count * sizeof(tvt_blade)); out->blade_count = blade_count; }
    }
    if (r == TVT_OK && tvt__report(d.progress, d.progress_user, 1.0f)) r = TVT_CANCELLED;
    if (r != TVT_OK) tvt_texel_free(out);
    return r;
}

TVTDEF tvt_result tvt_build_grass(const tvt_grass_desc *desc, tvt_texel *out)
{
    tvt_grass_desc d;
    tvt_allocator a;
    tvt_blade *blades;
    tvt_result r;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    r = tvt__grass_resolve(desc, &d);
    if (r != TVT_OK) return r;
    a = tvt__resolve_allocator(d.allocator);
    blades = (tvt_blade *)tvt__alloc(&a, d.blade_count, sizeof(tvt_blade));
    if (!blades) return TVT_ERR_OUT_OF_MEMORY;
    r = tvt_grass_blades(&d, blades, d.blade_count);
    if (r == TVT_OK) r = tvt_build_texel(blades, d.blade_count, &d, out);
    tvt__free(&a, blades);
    return r;
}

TVTDEF tvt_result tvt_texel_from_voxels(int res, const tvt_voxel *voxels, int bits, const tvt_allocator *allocator,
                                        tvt_texel *out)
{
    tvt_allocator a = tvt__resolve_allocator(allocator);
    tvt__acc g;
    tvt_result r;
    size_t i, n;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!voxels) return TVT_ERR_INVALID_ARGUMENT;
    if (!tvt__check_res(res) || (bits != 8 && bits != 16)) return TVT_ERR_BAD_RESOLUTION;
    n = (size_t)res * res * res;
    for (i = 0; i < n; i++) {
        const float *f = &voxels[i].density;
        size_t k;
        for (k = 0; k < sizeof(tvt_voxel) / sizeof(float); k++)
            if (!tvt__finite(f[k])) return TVT_ERR_BAD_PARAMETER;
        if (voxels[i].density < 0) return TVT_ERR_BAD_PARAMETER;
    }
    r = tvt__acc_init(&g, res, &a);
    for (i = 0; r == TVT_OK && i < n; i++) {
        const tvt_voxel *v = voxels + i;
        float *acc;
        int c;
        if (!(v->density > 0)) continue;
        acc = tvt__acc_voxel(&g, (int)(i % (size_t)res), (int)(i / (size_t)res % (size_t)res),
                             (int)(i / ((size_t)res * res)));
        if (!acc) { r = TVT_ERR_OUT_OF_MEMORY; break; }
        acc[0] = v->density;
        for (c = 0; c < 3; c++) {
            acc[1 + c] = v->normal[c] * v->density;
            acc[4 + c] = v->tangent[c] * v->density;
            acc[7 + c] = v->color[c] * v->density;
        }
        acc[10] = v->specular * v->density;
    }
    if (r == TVT_OK) r = tvt__acc_to_texel(&g, 1.0f, bits, 0, out);
    tvt__acc_free(&g);
    return r;
}

static size_t tvt__slot(const tvt_texel *t, long x, long y, long z, int *ok)
{
    long res = t->res;
    size_t b;
    uint32_t k;
    unsigned i;
    *ok = 0;
    if (z < 0 || z >= res || !t->brick_index) return 0;
    x &= res - 1; /* res is a power of two: the wrap, also for negative x */
    y &= res - 1;
    b = ((size_t)(z >> 2) * (size_t)t->bricks_per_side + (size_t)(y >> 2)) * (size_t)t->bricks_per_side + (size_t)(x >> 2);
    k = t->brick_index[b];
    if (k == TVT_EMPTY_BRICK) return 0;
    i = (unsigned)(((z & 3) * 4 + (y & 3)) * 4 + (x & 3));
    if (!((t->brick_mask[k] >> i) & 1)) return 0;
    *ok = 1;
    return (size_t)t->brick_offset[k] + tvt__popcount(t->brick_mask[k] & (((uint64_t)1 << i) - 1));
}

TVTDEF void tvt_texel_voxel(const tvt_texel *t, long x, long y, long z, tvt_voxel *out)
{
    int ok;
    size_t slot = tvt__slot(t, x, y, z, &ok);
    unsigned q[TVT_CHANNELS];
    if (!ok) { memset(out, 0, sizeof(*out)); return; }
    tvt__load(t, slot, q);
    tvt__decode(q, t->density_max, t->bits, out);
}

TVTDEF size_t tvt_texel_bytes(const tvt_texel *t)
{
    size_t nb = (size_t)t->bricks_per_side, bytes = nb * nb * nb * sizeof(uint32_t);
    bytes += t->brick_count * (sizeof(uint64_t) + sizeof(uint32_t));
    bytes += t->voxel_count * TVT_CHANNELS * (size_t)(t->bits / 8);
    if (t->blade_of_voxel) bytes += t->voxel_count * sizeof(uint16_t);
    return bytes + t->blade_count * sizeof(tvt_blade);
}

TVTDEF double tvt_texel_total_density(const tvt_texel *t)
{
    double sum = 0.0;
    size_t i;
    for (i = 0; i < t->voxel_count; i++) {
        unsigned q[TVT_CHANNELS];
        tvt_voxel v;
        tvt__load(t, i, q);
        tvt__decode(q, t->density_max, t->bits, &v);
        sum += v.density;
    }
    return sum;
}

TVTDEF void tvt_texel_free(tvt_texel *t)
{
    if (!t) return;
    if (t->allocator.free) {
        tvt__free(&t->allocator, t->brick_index);
        tvt__free(&t->allocator, t->brick_mask);
        tvt__free(&t->allocator, t->brick_offset);
        tvt__free(&t->allocator, t->data);
        tvt__free(&t->allocator, t->blade_of_voxel);
        tvt__free(&t->allocator, t->blades);
    }
    memset(t, 0, sizeof(*t));
}

/* ---------------------------------------------------------------------------------------------
   Texel -> points (PIPELINE step 3)
   --------------------------------------------------------------------------------------------- */
static float tvt__luminance(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* directions of length <= 1 as int16: v * 32767 rounded, and back */
static void tvt__dir_encode(const float *v, int16_t *q)
{
    int c;
    for (c = 0; c < 3; c++) {
        float f = v[c] < -1.0f ? -1.0f : v[c] > 1.0f ? 1.0f : v[c];
        q[c] = (int16_t)lrintf(f * 32767.0f);
    }
}

static void tvt__dir_decode(const int16_t *q, float *v)
{
    int c;
    for (c = 0; c < 3; c++) v[c] = (float)q[c] * (1.0f / 32767.0f);
}

TVTDEF void tvt_point_rest_dirs(const tvt_point *p, float axis[3], float bend[3], float normal0[3])
{
    if (axis) tvt__dir_decode(p->axis, axis);
    if (bend) tvt__dir_decode(p->bend, bend);
    if (normal0) tvt__dir_decode(p->normal0, normal0);
}

/* A voxel's share of its blade's rest state: the root moved to the periodic image nearest the
   voxel centre (cx, cy), the blade's axis, bend and colour delay. */
static void tvt__blade_proto(const tvt_blade *b, int res, float cx, float cy, tvt_point *p)
{
    p->root[0] = b->root[0] + (float)res * floorf((cx - b->root[0]) / (float)res + 0.5f);
    p->root[1] = b->root[1] + (float)res * floorf((cy - b->root[1]) / (float)res + 0.5f);
    tvt__dir_encode(b->axis, p->axis);
    tvt__dir_encode(b->bend, p->bend);
    p->wd_delay = b->wd_delay;
}

/* The rest of a blade point's state: arc length along the (stored) axis and radial offset. */
static void tvt__rest_from_blade(tvt_point *p, const float *axis)
{
    float d[3];
    int c;
    d[0] = p->pos[0] - p->root[0];
    d[1] = p->pos[1] - p->root[1];
    d[2] = p->pos[2];
    p->ell = tvt__dot(d, axis);
    if (p->ell < 0) p->ell = 0;
    for (c = 0; c < 3; c++) p->radial[c] = d[c] - p->ell * axis[c];
}

/* The paper's rest state (Fig 6a): the root is where the tangent line through the point meets
   the ground; the point lies on its own axis (no radial offset). */
static void tvt__rest_from_tangent(uint64_t *s, tvt_point *p)
{
    float t[3], d[3], dl;
    int c;
    memcpy(t, p->tangent, sizeof(t));
    tvt__normalize(t);
    if (t[2] < 0.2f) { t[0] = 0; t[1] = 0; t[2] = 1; }
    tvt__dir_encode(t, p->axis);
    tvt__dir_decode(p->axis, t); /* the stored axis, so that root + ell axis is the point */
    for (c = 0; c < 2; c++) p->root[c] = p->pos[c] - t[c] * (p->pos[2] / t[2]);
    p->ell = p->pos[2] / t[2];
    memset(p->radial, 0, sizeof(p->radial));
    d[0] = t[0]; d[1] = t[1]; d[2] = 0.0f;
    dl = sqrtf(d[0] * d[0] + d[1] * d[1]);
    if (dl < 1e-3f) {
        float az = (float)(2.0 * TVT__PI) * tvt__rand(s);
        d[0] = cosf(az); d[1] = sinf(az);
    } else { d[0] /= dl; d[1] /= dl; }
    dl = tvt__dot(d, t);
    for (c = 0; c < 3; c++) d[c] -= dl * t[c];
    tvt__normalize(d);
    tvt__dir_encode(d, p->bend);
    p->wd_delay = 2.0f * tvt__rand(s) - 1.0f;
}

/* Points of one voxel: the first random number of its stream rounds q = proportion * density. */
static unsigned tvt__voxel_points(float q, uint64_t *s)
{
    float f = floorf(q);
    return (unsigned)f + (tvt__rand(s) < q - f ? 1u : 0u);
}

static tvt_result tvt__sample_resolve(const tvt_sample_options *in, tvt_sample_options *o)
{
    tvt_sample_options d = tvt_sample_default_options();
    *o = in ? *in : d;
    if (o->proportion == 0) o->proportion = d.proportion;
    if (!tvt__finite(o->proportion) || o->proportion < 0.01f || o->proportion > 1000.0f) return TVT_ERR_BAD_PARAMETER;
    return TVT_OK;
}

/* Calls fn for every stored voxel in index order with its global coordinates and slot. */
typedef struct tvt__sampler {
    const tvt_texel *t;
    tvt_sample_options o;
    tvt_point *out;     /* NULL: count only */
    size_t count;
    float green_lum;
} tvt__sampler;

static void tvt__sample_voxel(tvt__sampler *S, long x, long y, long z, size_t slot)
{
    const tvt_texel *t = S->t;
    unsigned q[TVT_CHANNELS], n, i;
    tvt_voxel v;
    float d;
    uint64_t s;
    q[0] = t->bits == 8 ? ((const uint8_t *)t->data)[slot * TVT_CHANNELS] : ((const uint16_t *)t->data)[slot * TVT_CHANNELS];
    if (!q[0]) return;
    d = (float)q[0] * (t->bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f);
    d = t->density_max * (t->bits == 8 ? d * d : d); /* = tvt__decode's density */
    s = tvt__mix(S->o.seed ^ tvt__mix((((uint64_t)z * (uint64_t)t->res + (uint64_t)y) * (uint64_t)t->res + (uint64_t)x) + 1));
    n = tvt__voxel_points(S->o.proportion * d, &s);
    if (S->out && n) {
        unsigned blade = t->blade_of_voxel ? t->blade_of_voxel[slot] : TVT_NO_BLADE;
        tvt_point proto;
        float axis[3];
        tvt__load(t, slot, q);
        tvt__decode(q, t->density_max, t->bits, &v);
        memset(&proto, 0, sizeof(proto));
        memcpy(proto.normal, v.normal, sizeof(proto.normal));
        tvt__dir_encode(v.normal, proto.normal0);
        memcpy(proto.tangent, v.tangent, sizeof(proto.tangent));
        memcpy(proto.color, v.color, sizeof(proto.color));
        proto.specular = proto.specular0 = v.specular;
        proto.mass = 1.0f;
        proto.brightness = tvt__luminance(v.color) / S->green_lum;
        if (blade < t->blade_count) tvt__blade_proto(t->blades + blade, t->res, (float)x + 0.5f, (float)y + 0.5f, &proto);
        tvt__dir_decode(proto.axis, axis);
        for (i = 0; i < n; i++) {
            tvt_point *p = S->out + S->count + i;
            *p = proto;
            p->pos[0] = (float)x + tvt__rand(&s);
            p->pos[1] = (float)y + tvt__rand(&s);
            p->pos[2] = (float)z + tvt__rand(&s);
            if (blade < t->blade_count) tvt__rest_from_blade(p, axis);
            else tvt__rest_from_tangent(&s, p);
        }
    }
    S->count += n;
}

static int tvt__sample_pass(tvt__sampler *S, float done0, float done1)
{
    const tvt_texel *t = S->t;
    size_t nb = (size_t)t->bricks_per_side, b, total = nb * nb * nb;
    for (b = 0; b < total; b++) {
        uint32_t k = t->brick_index[b];
        long bx = (long)(b % nb) * 4, by = (long)(b / nb % nb) * 4, bz = (long)(b / (nb * nb)) * 4;
        size_t slot;
        int i;
        if (k == TVT_EMPTY_BRICK) continue;
        slot = t->brick_offset[k];
        for (i = 0; i < TVT__BV; i++)
            if ((t->brick_mask[k] >> i) & 1) tvt__sample_voxel(S, bx + (i & 3), by + ((i >> 2) & 3), bz + (i >> 4), slot++);
        if ((b & 1023) == 1023 &&
            tvt__report(S->o.progress, S->o.progress_user, done0 + (done1 - done0) * (float)b / (float)total))
            return 0;
    }
    return 1;
}

TVTDEF tvt_result tvt_sample(const tvt_texel *t, const tvt_sample_options *options, tvt_points *out)
{
    tvt__sampler S;
    tvt_allocator a;
    tvt_result r;
    float green[3];
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!t || !t->brick_index) return TVT_ERR_INVALID_ARGUMENT;
    memset(&S, 0, sizeof(S));
    r = tvt__sample_resolve(options, &S.o);
    if (r != TVT_OK) return r;
    a = tvt__resolve_allocator(S.o.allocator);
    S.t = t;
    tvt_pigment_color(1.0f, 0.0f, green);
    S.green_lum = tvt__luminance(green);
    if (!tvt__sample_pass(&S, 0.0f, 0.3f)) return TVT_CANCELLED;
    if (S.count == 0) return TVT_ERR_EMPTY;
    if (S.count > 0xFFFFFFFFu) return TVT_ERR_TOO_LARGE;
    S.out = (tvt_point *)tvt__alloc(&a, S.count, sizeof(tvt_point));
    if (!S.out) return TVT_ERR_OUT_OF_MEMORY;
    out->count = S.count;
    S.count = 0;
    if (!tvt__sample_pass(&S, 0.3f, 1.0f) || tvt__report(S.o.progress, S.o.progress_user, 1.0f)) {
        tvt__free(&a, S.out);
        memset(out, 0, sizeof(*out));
        return TVT_CANCELLED;
    }
    out->p = S.out;
    out->res = t->res;
    out->proportion = S.o.proportion;
    out->wd = 0.0f;
    out->allocator = a;
    return TVT_OK;
}

TVTDEF void tvt_points_free(tvt_points *pts)
{
    if (!pts) return;
    if (pts->allocator.free) tvt__free(&pts->allocator, pts->p);
    memset(pts, 0, sizeof(*pts));
}

/* ---------------------------------------------------------------------------------------------
   Ageing (PIPELINE step 4, MODEL)
   --------------------------------------------------------------------------------------------- */
enum { TVT__BEND_N = 768, TVT__COLOR_N = 64 };

/* The bent centre line in units of L: G(u) = integral_0^u (cos phi, sin phi), phi(u) =
   Theta min(u, 1)^beta, tabulated at u = k / 512 for k = 0..768 (midpoint rule). */
typedef struct tvt__ageing {
    tvt_model_state st;
    float theta, beta, jitter, length;
    float gc[TVT__BEND_N + 1], gs[TVT__BEND_N + 1];
    float pc[TVT__BEND_N + 1], ps[TVT__BEND_N + 1]; /* cos and sin of phi at the same nodes */
    float color[TVT__COLOR_N + 1][3];
} tvt__ageing;

static float tvt__phi(const tvt__ageing *A, float u) { return A->theta * powf(u < 1 ? u : 1.0f, A->beta); }

static void tvt__ageing_init(const tvt_model_options *o, float wd, tvt__ageing *A)
{
    const float h = 1.0f / 512.0f;
    float lost1 = 1.0f - tvt__water(o->water_curve, 1.0f);
    double c = 0, s = 0;
    int k;
    tvt__model_at(o, wd, &A->st);
    A->theta = A->st.droop;
    A->beta = o->droop_exponent;
    A->length = o->droop_length;
    A->jitter = o->colour_jitter;
    A->gc[0] = A->gs[0] = 0.0f;
    for (k = 0; k <= TVT__BEND_N; k++) {
        double phi = tvt__phi(A, (float)k * h);
        A->pc[k] = (float)cos(phi);
        A->ps[k] = (float)sin(phi);
    }
    for (k = 0; k < TVT__BEND_N; k++) {
        float phi = tvt__phi(A, ((float)k + 0.5f) * h);
        c += h * cos(phi);
        s += h * sin(phi);
        A->gc[k + 1] = (float)c;
        A->gs[k + 1] = (float)s;
    }
    for (k = 0; k <= TVT__COLOR_N; k++) {
        float w = (float)k / (float)TVT__COLOR_N;
        tvt_pigment_color(tvt__chlorophyll(w), (1.0f - tvt__water(o->water_curve, w)) / lost1, A->color[k]);
    }
}

/* The centre line G(u) and the direction (cos phi, sin phi) at u, both interpolated in the
   tables (the direction renormalised); past the table phi is constant (u > 1). */
static void tvt__bend_at(const tvt__ageing *A, float u, float *gc, float *gs, float *c, float *s)
{
    float f = u * 512.0f, t, len;
    int k;
    if (f >= (float)TVT__BEND_N) {
        float extra = (f - (float)TVT__BEND_N) / 512.0f;
        *c = A->pc[TVT__BEND_N];
        *s = A->ps[TVT__BEND_N];
        *gc = A->gc[TVT__BEND_N] + extra * *c;
        *gs = A->gs[TVT__BEND_N] + extra * *s;
        return;
    }
    k = (int)f;
    t = f - (float)k;
    *gc = A->gc[k] + t * (A->gc[k + 1] - A->gc[k]);
    *gs = A->gs[k] + t * (A->gs[k + 1] - A->gs[k]);
    *c = A->pc[k] + t * (A->pc[k + 1] - A->pc[k]);
    *s = A->ps[k] + t * (A->ps[k + 1] - A->ps[k]);
    len = 1.0f / sqrtf(*c * *c + *s * *s);
    *c *= len;
    *s *= len;
}

/* v turned by angle (c, s) in the plane (axis, bend), toward bend */
static void tvt__turn(const float *v, const float *axis, const float *bend, float c, float s, float *out)
{
    float va = tvt__dot(v, axis), vb = tvt__dot(v, bend);
    int i;
    for (i = 0; i < 3; i++) {
        float h = v[i] - va * axis[i] - vb * bend[i];
        out[i] = va * (c * axis[i] + s * bend[i]) + vb * (c * bend[i] - s * axis[i]) + h;
    }
}

static void tvt__age_point(const tvt__ageing *A, float wd, int res, tvt_point *p)
{
    float L = A->length * (float)res, u = p->ell * (1.0f - A->st.axial_shrink) / L, gc, gs, c, s, r[3], rr[3], w, f;
    float axis[3], bend[3], normal0[3];
    int i, k;
    tvt_point_rest_dirs(p, axis, bend, normal0);
    tvt__bend_at(A, u, &gc, &gs, &c, &s);
    for (i = 0; i < 3; i++) r[i] = p->radial[i] * (1.0f - A->st.radial_shrink);
    tvt__turn(r, axis, bend, c, s, rr);
    for (i = 0; i < 3; i++) {
        p->pos[i] = (i < 2 ? p->root[i] : 0.0f) + L * (gc * axis[i] + gs * bend[i]) + rr[i];
        p->tangent[i] = c * axis[i] + s * bend[i];
    }
    if (p->pos[2] < 0) p->pos[2] = 0;
    if (p->pos[2] >= (float)res) p->pos[2] = (float)res - 1e-3f;
    for (i = 0; i < 2; i++) p->pos[i] -= (float)res * floorf(p->pos[i] * (1.0f / (float)res)); /* exact: res is 2^k */
    for (i = 0; i < 2; i++) if (p->pos[i] >= (float)res) p->pos[i] = 0.0f;
    tvt__turn(normal0, axis, bend, c, s, p->normal);
    w = wd + A->jitter * p->wd_delay;
    w = w < 0 ? 0 : w > 1 ? 1 : w;
    f = w * (float)TVT__COLOR_N;
    k = (int)f;
    if (k >= TVT__COLOR_N) k = TVT__COLOR_N - 1;
    f -= (float)k;
    for (i = 0; i < 3; i++) {
        float col = p->brightness * (A->color[k][i] + f * (A->color[k + 1][i] - A->color[k][i]));
        p->color[i] = col < 1 ? col : 1.0f;
    }
    p->specular = p->specular0 * A->st.specular_factor;
}

/* ---- merging. The points are sorted by voxel (a radix sort of the voxel keys) and their
   positions copied in that order into a compact array; a neighbour voxel's run of points is
   found by a galloping search from p's own place (x neighbours are adjacent, y and z ones a row
   or a layer away). A point closer than threshold (< 1 voxel) to p lies in p's voxel or, along
   each axis where p is within threshold of a face, in the neighbour across it: at most 8 voxels,
   x and y wrapping (distances are taken to the nearest periodic image). */
typedef struct tvt__merge_grid {
    uint32_t *order;  /* sorted position -> point index */
    uint32_t *rank;   /* point index -> sorted position */
    float *pos;       /* 4 floats per sorted position: x, y, z, unused */
    uint32_t *key;    /* voxel key per sorted position */
    uint32_t *tmp_key, *tmp_idx; /* voxel key and index per point index (written while ageing) */
    float *ipos;      /* 4 floats per point index: x, y, z, unused (written while ageing) */
    uint8_t *dead;    /* per sorted position */
    size_t n;
    int res;
    uint32_t cache_key[8], cache_start[8]; /* the last run found per neighbour slot (points of one
                                              voxel mostly come one after another) */
} tvt__merge_grid;

/* a voxel's key in the texel's own order: bricks of 4^3 in (z, y, x) order, voxels within a
   brick in (z, y, x) order (points are sampled in this order, so sorting them moves little) */
static uint32_t tvt__cell_key(long x, long y, long z, int res)
{
    uint32_t nb = (uint32_t)res / TVT_BRICK;
    uint32_t brick = ((uint32_t)(z >> 2) * nb + (uint32_t)(y >> 2)) * nb + (uint32_t)(x >> 2);
    return brick * TVT__BV + (uint32_t)(((z & 3) << 4) | ((y & 3) << 2) | (x & 3));
}

static uint32_t tvt__voxel_key(const float *p, int res)
{
    long x = (long)p[0], y = (long)p[1], z = (long)p[2];
    if (x >= res) x = res - 1;
    if (y >= res) y = res - 1;
    if (z >= res) z = res - 1;
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    if (z < 0) z = 0;
    return tvt__cell_key(x, y, z, res);
}

/* Stable LSD radix sort of (key, index) by keys of key_bits bits (3 log2 res <= 30): two
   passes up to 24 bits (res <= 256), three above, at most 12 bits a pass. Returns 1 if the
   sorted data is in key2 / idx2 (an odd number of passes), 0 if back in key / idx. */
static int tvt__radix_sort(uint32_t *key, uint32_t *idx, uint32_t *key2, uint32_t *idx2, size_t n, int key_bits)
{
    int passes = key_bits <= 24 ? 2 : 3, bits = (key_bits + passes - 1) / passes, pass;
    size_t buckets = (size_t)1 << bits, mask = buckets - 1;
    for (pass = 0; pass < passes; pass++) {
        size_t count[4096], i, sum = 0;
        int shift = bits * pass;
        uint32_t *t;
        memset(count, 0, buckets * sizeof(size_t));
        for (i = 0; i < n; i++) count[(key[i] >> shift) & mask]++;
        for (i = 0; i < buckets; i++) { size_t c = count[i]; count[i] = sum; sum += c; }
        for (i = 0; i < n; i++) {
            size_t d = count[(key[i] >> shift) & mask]++;
            key2[d] = key[i];
            idx2[d] = idx[i];
        }
        t = key; key = key2; key2 = t;
        t = idx; idx = idx2; idx2 = t;
    }
    return passes & 1;
}

/* first sorted position with key >= k, galloping from position `from` */
static size_t tvt__lower_bound_from(const uint32_t *key, size_t n, size_t from, uint32_t k)
{
    size_t lo, hi, step = 1;
    if (key[from] >= k) { /* backward: find lo with key[lo] < k */
        hi = from;
        while (hi >= step && key[hi - step] >= k) { hi -= step; step *= 2; }
        lo = hi >= step ? hi - step : 0;
        if (key[lo] >= k) return lo;
    } else { /* forward: key[lo] < k */
        lo = from;
        while (lo + step < n && key[lo + step] < k) { lo += step; step *= 2; }
        hi = lo + step < n ? lo + step : n;
    }
    while (hi - lo > 1) { /* key[lo] < k <= key[hi] (hi = n: past the end) */
        size_t mid = lo + (hi - lo) / 2;
        if (key[mid] < k) lo = mid; else hi = mid;
    }
    return hi;
}

/* the merge's arrays, allocated before ageing (which fills tmp_key, tmp_idx and ipos, so the
   points are read once less); 0 when out of memory (everything freed) */
static void tvt__merge_grid_free(tvt__merge_grid *g, const tvt_allocator *a)
{
    tvt__free(a, g->order); tvt__free(a, g->rank); tvt__free(a, g->key); tvt__free(a, g->pos);
    tvt__free(a, g->tmp_key); tvt__free(a, g->tmp_idx); tvt__free(a, g->ipos); tvt__free(a, g->dead);
    memset(g, 0, sizeof(*g));
}

static int tvt__merge_grid_alloc(tvt__merge_grid *g, const tvt_allocator *a, size_t n, int res)
{
    memset(g, 0, sizeof(*g));
    g->res = res;
    g->order = (uint32_t *)tvt__alloc(a, n, sizeof(uint32_t));
    g->rank = (uint32_t *)tvt__alloc(a, n, sizeof(uint32_t));
    g->key = (uint32_t *)tvt__alloc(a, n, sizeof(uint32_t));
    g->pos = (float *)tvt__alloc(a, n, 4 * sizeof(float));
    g->tmp_key = (uint32_t *)tvt__alloc(a, n, sizeof(uint32_t));
    g->tmp_idx = (uint32_t *)tvt__alloc(a, n, sizeof(uint32_t));
    g->ipos = (float *)tvt__alloc(a, n, 4 * sizeof(float));
    g->dead = (uint8_t *)tvt__alloc(a, n, 1);
    if (g->order && g->rank && g->key && g->pos && g->tmp_key && g->tmp_idx && g->ipos && g->dead) return 1;
    tvt__merge_grid_free(g, a);
    return 0;
}

/* point i (aged) enters the merge: its voxel key and position */
static void tvt__merge_grid_put(tvt__merge_grid *g, size_t i, const float *pos)
{
    g->tmp_key[i] = tvt__voxel_key(pos, g->res);
    g->tmp_idx[i] = (uint32_t)i;
    g->ipos[4 * i] = pos[0]; g->ipos[4 * i + 1] = pos[1]; g->ipos[4 * i + 2] = pos[2]; g->ipos[4 * i + 3] = 0.0f;
}

static void tvt__merge_grid_fill(tvt__merge_grid *g, size_t n)
{
    size_t i;
    int bits = 0;
    while ((1 << bits) < g->res) bits++;
    if (!tvt__radix_sort(g->tmp_key, g->tmp_idx, g->key, g->order, n, 3 * bits)) { /* sorted in place: swap roles */
        uint32_t *t = g->key; g->key = g->tmp_key; g->tmp_key = t;
        t = g->order; g->order = g->tmp_idx; g->tmp_idx = t;
    }
    g->n = n;
    memset(g->cache_key, 0xFF, sizeof(g->cache_key)); /* no voxel has key 2^32 - 1 (res <= 1024) */
    for (i = 0; i < n; i++) {
        g->rank[g->order[i]] = (uint32_t)i;
        memcpy(g->pos + 4 * i, g->ipos + 4 * (size_t)g->order[i], 4 * sizeof(float));
    }
}

/* the nearest point after sorted position i (alive) closer than thr, as a sorted position;
   (size_t)-1 if none; ties: the earlier position */
static size_t tvt__merge_partner(tvt__merge_grid *g, const uint8_t *dead, size_t n, size_t i, float thr)
{
    const float *p = g->pos + 4 * i;
    long c[3], o[3];
    float best_d2 = thr * thr, res = (float)g->res, half = 0.5f * res;
    size_t best = (size_t)-1;
    int k, m, need, visited = 0;
    for (k = 0; k < 3; k++) {
        float f;
        c[k] = (long)p[k];
        if (c[k] >= g->res) c[k] = g->res - 1;
        if (c[k] < 0) c[k] = 0;
        f = p[k] - (float)c[k];
        o[k] = f < thr ? -1 : (f > 1.0f - thr ? 1 : 0);
    }
    need = (o[0] ? 1 : 0) | (o[1] ? 2 : 0) | (o[2] ? 4 : 0);
    for (m = 0;; m = (m - need) & need) { /* the subsets of the needed offsets, in increasing order */
        long x = c[0], y = c[1], z = c[2];
        uint32_t start, k2;
        size_t j;
        if (m == 0 && visited) break;
        visited = 1;
        if (m & 1) x += o[0];
        if (m & 2) y += o[1];
        if (m & 4) z += o[2];
        if (z < 0 || z >= g->res) continue;
        x &= g->res - 1;
        y &= g->res - 1;
        k2 = tvt__cell_key(x, y, z, g->res);
        if (k2 < g->key[i]) continue; /* a voxel sorted before p's holds no later point */
        if (g->cache_key[m] == k2) start = g->cache_start[m];
        else {
            start = (uint32_t)tvt__lower_bound_from(g->key, n, i, k2);
            g->cache_key[m] = k2;
            g->cache_start[m] = start;
        }
        for (j = start > i ? start : i + 1; j < n && g->key[j] == k2; j++) {
            const float *q = g->pos + 4 * j;
            float d[3], d2;
            if (dead[j]) continue;
            d[0] = q[0] - p[0]; d[1] = q[1] - p[1]; d[2] = q[2] - p[2];
            if (d[0] > half) d[0] -= res; else if (d[0] < -half) d[0] += res; /* the nearest periodic image */
            if (d[1] > half) d[1] -= res; else if (d[1] < -half) d[1] += res;
            d2 = tvt__dot(d, d);
            if (d2 < best_d2 || (d2 == best_d2 && best != (size_t)-1 && j < best)) { best = j; best_d2 = d2; }
        }
    }
    return best;
}

/* b merged into a: every field the mass-weighted mean, masses added, directions renormalised.
   Positions and roots are averaged at b's periodic image nearest a. */
static void tvt__merge_into(tvt_point *a, const tvt_point *b, int res)
{
    float m = a->mass + b->mass, wa = a->mass / m, wb = b->mass / m, *fa = &a->pos[0], d, shift[2];
    float da[3][3], db[3][3];
    const float *fb = &b->pos[0];
    size_t k, n = offsetof(tvt_point, axis) / sizeof(float); /* the float fields come first */
    for (k = 0; k < 2; k++) shift[k] = (float)res * floorf((b->pos[k] - a->pos[k]) / (float)res + 0.5f);
    for (k = 0; k < n; k++) fa[k] = wa * fa[k] + wb * fb[k];
    for (k = 0; k < 2; k++) {
        a->pos[k] -= wb * shift[k];
        a->root[k] -= wb * shift[k];
        if (a->pos[k] < 0) a->pos[k] += (float)res;
        if (a->pos[k] >= (float)res) a->pos[k] -= (float)res;
    }
    a->mass = m;
    tvt__normalize(a->tangent);
    tvt_point_rest_dirs(a, da[0], da[1], da[2]);
    tvt_point_rest_dirs(b, db[0], db[1], db[2]);
    for (k = 0; k < 9; k++) da[k / 3][k % 3] = wa * da[k / 3][k % 3] + wb * db[k / 3][k % 3];
    tvt__normalize(da[0]);
    d = tvt__dot(da[1], da[0]);
    for (k = 0; k < 3; k++) da[1][k] -= d * da[0][k];
    tvt__normalize(da[1]);
    tvt__dir_encode(da[0], a->axis);
    tvt__dir_encode(da[1], a->bend);
    tvt__dir_encode(da[2], a->normal0);
}

/* Algorithm 1's merging over the grid g (filled by tvt__merge_grid_put for every point) */
static void tvt__merge(tvt_points *pts, float thr, tvt__merge_grid *g)
{
    size_t n = pts->count, i, kept = 0;
    uint8_t *dead = g->dead; /* by sorted position */
    tvt__merge_grid_fill(g, n);
    memset(dead, 0, n);
    for (i = 0; i < n; i++) {
        size_t j;
        if (dead[i]) continue;
        j = tvt__merge_partner(g, dead, n, i, thr);
        if (j == (size_t)-1) continue;
        tvt__merge_into(pts->p + g->order[i], pts->p + g->order[j], pts->res);
        memcpy(g->pos + 4 * i, pts->p[g->order[i]].pos, 3 * sizeof(float));
        dead[j] = 1;
    }
    for (i = 0; i < n; i++) /* the survivors in their index order */
        if (!dead[g->rank[i]]) {
            if (kept != i) pts->p[kept] = pts->p[i];
            kept++;
        }
    pts->count = kept;
}

TVTDEF tvt_result tvt_age(tvt_points *pts, float wd, const tvt_model_options *options)
{
    tvt_model_options o;
    tvt__ageing *A;
    tvt__merge_grid g;
    size_t i;
    tvt_result r = TVT_OK;
    int merge;
    if (!pts || (!pts->p && pts->count)) return TVT_ERR_INVALID_ARGUMENT;
    if (!(wd >= 0.0f && wd <= 1.0f)) return TVT_ERR_BAD_WD;
    if (!tvt__model_resolve(options, &o)) return TVT_ERR_BAD_PARAMETER;
    if (pts->count == 0) { pts->wd = wd; return TVT_OK; }
    merge = !o.no_merge;
    A = (tvt__ageing *)tvt__alloc(&pts->allocator, 1, sizeof(tvt__ageing));
    if (!A) return TVT_ERR_OUT_OF_MEMORY;
    if (merge && !tvt__merge_grid_alloc(&g, &pts->allocator, pts->count, pts->res)) {
        tvt__free(&pts->allocator, A);
        return TVT_ERR_OUT_OF_MEMORY;
    }
    tvt__ageing_init(&o, wd, A);
    if (tvt__report(o.progress, o.progress_user, 0.0f)) r = TVT_CANCELLED;
    for (i = 0; r == TVT_OK && i < pts->count; i++) { /* age, and enter the merge's grid */
        tvt__age_point(A, wd, pts->res, pts->p + i);
        if (merge) tvt__merge_grid_put(&g, i, pts->p[i].pos);
    }
    tvt__free(&pts->allocator, A);
    if (r == TVT_OK) {
        pts->wd = wd;
        if (tvt__report(o.progress, o.progress_user, 0.5f)) r = TVT_CANCELLED;
        else if (merge) tvt__merge(pts, o.merge_threshold, &g);
    }
    if (merge) tvt__merge_grid_free(&g, &pts->allocator);
    if (r == TVT_OK && tvt__report(o.progress, o.progress_user, 1.0f)) r = TVT_CANCELLED;
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Points -> texel (PIPELINE step 5)
   --------------------------------------------------------------------------------------------- */
/* Gaussian weights of the 2R + 1 voxel centres around coordinate x along one axis; centres
   outside 0..res-1 get 0 unless the axis wraps. Returns their sum. */
static float tvt__axis_weights(float x, int res, int wraps, int R, float inv2s2, int *idx, float *w)
{
    int base = (int)floorf(x), k;
    float sum = 0.0f;
    for (k = -R; k <= R; k++) {
        int v = base + k;
        float d = (float)v + 0.5f - x;
        w[k + R] = expf(-d * d * inv2s2);
        if (wraps) v &= res - 1; /* res is a power of two: the wrap, negative v too */
        else if (v < 0 || v >= res) w[k + R] = 0.0f;
        idx[k + R] = v;
        sum += w[k + R];
    }
    return sum;
}

static int tvt__splat_point(tvt__acc *g, const tvt_point *p, int R, float inv2s2)
{
    int ix[5], iy[5], iz[5], i, j, k, c;
    float wx[5], wy[5], wz[5], norm;
    norm = tvt__axis_weights(p->pos[0], g->res, 1, R, inv2s2, ix, wx) *
           tvt__axis_weights(p->pos[1], g->res, 1, R, inv2s2, iy, wy) *
           tvt__axis_weights(p->pos[2], g->res, 0, R, inv2s2, iz, wz);
    if (!(norm > 0)) return 1;
    norm = p->mass / norm;
    for (k = 0; k <= 2 * R; k++) {
        if (wz[k] == 0.0f) continue;
        for (j = 0; j <= 2 * R; j++) {
            float *a = NULL;
            for (i = 0; i <= 2 * R; i++) {
                float w = wx[i] * wy[j] * wz[k] * norm;
                /* the next voxel along x in the same brick is the next accumulator */
                if (a && ix[i] == ix[i - 1] + 1 && (ix[i] & 3) != 0) a += TVT__ACC;
                else a = tvt__acc_voxel(g, ix[i], iy[j], iz[k]);
                if (!a) return 0;
                a[0] += w;
                for (c = 0; c < 3; c++) {
                    a[1 + c] += w * p->normal[c];
                    a[4 + c] += w * p->tangent[c];
                    a[7 + c] += w * p->color[c];
                }
                a[10] += w * p->specular;
            }
        }
    }
    return 1;
}

TVTDEF tvt_result tvt_splat(const tvt_points *pts, const tvt_splat_options *options, tvt_texel *out)
{
    tvt_splat_options o = tvt_splat_default_options();
    tvt_allocator a;
    tvt__acc g;
    tvt_result r;
    size_t i;
    int R;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!pts || (!pts->p && pts->count)) return TVT_ERR_INVALID_ARGUMENT;
    if (options) {
        o = *options;
        if (o.bits == 0) o.bits = 8;
        if (o.sigma == 0) o.sigma = 0.5f;
    }
    if (!tvt__check_res(pts->res) || (o.bits != 8 && o.bits != 16)) return TVT_ERR_BAD_RESOLUTION;
    if (!tvt__finite(o.sigma) || o.sigma < 0.25f || o.sigma > 1.0f || !tvt__finite(pts->proportion) ||
        !(pts->proportion > 0))
        return TVT_ERR_BAD_PARAMETER;
    a = tvt__resolve_allocator(o.allocator ? o.allocator : (pts->allocator.alloc ? &pts->allocator : NULL));
    R = o.sigma <= 0.5f ? 1 : 2;
    r = tvt__acc_init(&g, pts->res, &a);
    for (i = 0; r == TVT_OK && i < pts->count; i++) {
        if (!tvt__splat_point(&g, pts->p + i, R, 0.5f / (o.sigma * o.sigma))) r = TVT_ERR_OUT_OF_MEMORY;
        else if ((i & 65535) == 65535 &&
                 tvt__report(o.progress, o.progress_user, 0.9f * (float)i / (float)pts->count))
            r = TVT_CANCELLED;
    }
    if (r == TVT_OK) r = tvt__acc_to_texel(&g, 1.0f / pts->proportion, o.bits, 0, out);
    tvt__acc_free(&g);
    if (r == TVT_OK && tvt__report(o.progress, o.progress_user, 1.0f)) { tvt_texel_free(out); r = TVT_CANCELLED; }
    return r;
}

/* ---------------------------------------------------------------------------------------------
   LOD pyramid (paper section 4.2)
   --------------------------------------------------------------------------------------------- */
/* Deep copy of a texel (the pyramid owns its level 0). */
static tvt_result tvt__texel_copy(const tvt_texel *t, const tvt_allocator *a, tvt_texel *out)
{
    size_t nb = (size_t)t->bricks_per_side;
    tvt_result r = tvt__texel_alloc(out, t->res, t->bits, t->brick_count, t->voxel_count, t->blade_of_voxel != NULL, a);
    if (r != TVT_OK) return r;
    out->density_max = t->density_max;
    memcpy(out->brick_index, t->brick_index, nb * nb * nb * sizeof(uint32_t));
    if (t->brick_count) {
        memcpy(out->brick_mask, t->brick_mask, t->brick_count * sizeof(uint64_t));
        memcpy(out->brick_offset, t->brick_offset, t->brick_count * sizeof(uint32_t));
    }
    if (t->voxel_count) memcpy(out->data, t->data, t->voxel_count * TVT_CHANNELS * (size_t)(t->bits / 8));
    if (t->blade_of_voxel && t->voxel_count) memcpy(out->blade_of_voxel, t->blade_of_voxel, t->voxel_count * sizeof(uint16_t));
    return TVT_OK;
}

/* 2x2x2 box filter: density the mean of the children (so that the integral of density along
   any line is kept on average), attributes density-weighted means. */
static tvt_result tvt__downsample(const tvt_texel *t, const tvt_allocator *a, tvt_texel *out)
{
    size_t nb = (size_t)t->bricks_per_side, b;
    tvt__acc g;
    tvt_result r = tvt__acc_init(&g, t->res / 2, a);
    for (b = 0; r == TVT_OK && b < nb * nb * nb; b++) {
        uint32_t k = t->brick_index[b];
        int bx = (int)(b % nb) * 4, by = (int)(b / nb % nb) * 4, bz = (int)(b / (nb * nb)) * 4, i, c;
        size_t slot;
        if (k == TVT_EMPTY_BRICK) continue;
        slot = t->brick_offset[k];
        for (i = 0; i < TVT__BV; i++) {
            unsigned q[TVT_CHANNELS];
            tvt_voxel v;
            float *acc, w;
            if (!((t->brick_mask[k] >> i) & 1)) continue;
            tvt__load(t, slot++, q);
            if (!q[0]) continue;
            tvt__decode(q, t->density_max, t->bits, &v);
            acc = tvt__acc_voxel(&g, (bx + (i & 3)) / 2, (by + ((i >> 2) & 3)) / 2, (bz + (i >> 4)) / 2);
            if (!acc) { r = TVT_ERR_OUT_OF_MEMORY; break; }
            w = v.density * 0.125f;
            acc[0] += w;
            for (c = 0; c < 3; c++) {
                acc[1 + c] += w * v.normal[c];
                acc[4 + c] += w * v.tangent[c];
                acc[7 + c] += w * v.color[c];
            }
            acc[10] += w * v.specular;
        }
    }
    if (r == TVT_OK) r = tvt__acc_to_texel(&g, 1.0f, t->bits, 0, out);
    tvt__acc_free(&g);
    return r;
}

static float tvt__slot_density(const tvt_texel *t, size_t slot)
{
    float d;
    if (t->bits == 8) {
        d = (float)((const uint8_t *)t->data)[slot * TVT_CHANNELS] * (1.0f / 255.0f);
        return t->density_max * d * d;
    }
    return t->density_max * (float)((const uint16_t *)t->data)[slot * TVT_CHANNELS] * (1.0f / 65535.0f);
}

/* trilinear corner weights of p (level units, voxel centres at k + 1/2) */
static void tvt__trilinear(const float *p, long *base, float *f)
{
    int c;
    for (c = 0; c < 3; c++) {
        float x = p[c] - 0.5f, fl = floorf(x);
        base[c] = (long)fl;
        f[c] = x - fl;
    }
}

static void tvt__corner_slots(const tvt_texel *t, const long *b, size_t *slot, int *ok);

static float tvt__level_density(const tvt_texel *t, const float *p)
{
    long b[3];
    float f[3], sum = 0.0f;
    size_t slots[8];
    int n, oks[8];
    tvt__trilinear(p, b, f);
    if (!t->brick_index) return 0.0f;
    tvt__corner_slots(t, b, slots, oks);
    for (n = 0; n < 8; n++) {
        float w = ((n & 1) ? f[0] : 1 - f[0]) * ((n & 2) ? f[1] : 1 - f[1]) * ((n & 4) ? f[2] : 1 - f[2]);
        if (w > 0) sum += w * (oks[n] ? tvt__slot_density(t, slots[n]) : 0.0f);
    }
    return sum;
}

TVTDEF float tvt_lod_density(const tvt_lod *l, int level, const float p[3])
{
    float s = 1.0f / (float)(1 << level), q[3];
    q[0] = p[0] * s; q[1] = p[1] * s; q[2] = p[2] * s;
    return l->density_scale[level] * tvt__level_density(&l->level[level], q);
}

/* The channels are linear in their codes (density apart), so the density-weighted mean of the
   8 corners is taken on the codes and decoded once. */
/* The slots of the 8 corners from base b (ok[n] = 0: not stored; x and y wrap). A brick is
   looked up only when it differs from the previous corner's (all 8 corners share one brick
   in 42% of the cases, and never need more than 8). */
static void tvt__corner_slots(const tvt_texel *t, const long *b, size_t *slot, int *ok)
{
    long m = t->res - 1, xs[2], ys[2];
    size_t nb = (size_t)t->bricks_per_side, last = (size_t)-1;
    uint32_t k = TVT_EMPTY_BRICK;
    uint64_t mask = 0;
    int n;
    xs[0] = b[0] & m; xs[1] = (b[0] + 1) & m;
    ys[0] = b[1] & m; ys[1] = (b[1] + 1) & m;
    for (n = 0; n < 8; n++) {
        long x = xs[n & 1], y = ys[(n >> 1) & 1], z = b[2] + ((n >> 2) & 1);
        size_t bi;
        unsigned i;
        ok[n] = 0;
        slot[n] = 0;
        if (z < 0 || z > m) continue;
        bi = ((size_t)(z >> 2) * nb + (size_t)(y >> 2)) * nb + (size_t)(x >> 2);
        if (bi != last) {
            last = bi;
            k = t->brick_index[bi];
            mask = k == TVT_EMPTY_BRICK ? 0 : t->brick_mask[k];
        }
        i = (unsigned)(((z & 3) * 4 + (y & 3)) * 4 + (x & 3));
        if (!((mask >> i) & 1)) continue;
        ok[n] = 1;
        slot[n] = (size_t)t->brick_offset[k] + tvt__popcount(mask & (((uint64_t)1 << i) - 1));
    }
}

TVTDEF void tvt_lod_voxel(const tvt_lod *l, int level, const float p[3], tvt_voxel *out)
{
    const tvt_texel *t = &l->level[level];
    float s = 1.0f / (float)(1 << level), q[3], f[3], wsum = 0.0f, code[TVT_CHANNELS] = {0}, inv;
    long b[3];
    size_t slots[8];
    int n, c, oks[8];
    q[0] = p[0] * s; q[1] = p[1] * s; q[2] = p[2] * s;
    tvt__trilinear(q, b, f);
    memset(out, 0, sizeof(*out));
    if (!t->brick_index) return;
    tvt__corner_slots(t, b, slots, oks);
    for (n = 0; t->bits == 8 && n < 8; n++) { /* 8 bits: the codes read in place (the same sums) */
        float w = ((n & 1) ? f[0] : 1 - f[0]) * ((n & 2) ? f[1] : 1 - f[1]) * ((n & 4) ? f[2] : 1 - f[2]), d, wd;
        const uint8_t *v;
        if (!(w > 0) || !oks[n]) continue;
        v = (const uint8_t *)t->data + slots[n] * TVT_CHANNELS;
        d = (float)v[0] * (1.0f / 255.0f);
        d = t->density_max * (d * d);
        wd = w * d;
        for (c = 1; c < TVT_CHANNELS; c++) code[c] += wd * (float)v[c];
        wsum += wd;
    }
    for (n = 0; t->bits != 8 && n < 8; n++) {
        float w = ((n & 1) ? f[0] : 1 - f[0]) * ((n & 2) ? f[1] : 1 - f[1]) * ((n & 4) ? f[2] : 1 - f[2]), d, wd;
        unsigned qc[TVT_CHANNELS];
        size_t slot = slots[n];
        if (!(w > 0) || !oks[n]) continue;
        tvt__load(t, slot, qc);
        d = (float)qc[0] * (t->bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f);
        d = t->density_max * (t->bits == 8 ? d * d : d);
        wd = w * d;
        for (c = 1; c < TVT_CHANNELS; c++) code[c] += wd * (float)qc[c];
        wsum += wd;
    }
    if (!(wsum > 0)) return;
    inv = (t->bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f) / wsum;
    for (c = 0; c < 3; c++) {
        out->normal[c] = code[1 + c] * inv * 2.0f - 1.0f;
        out->tangent[c] = code[4 + c] * inv * 2.0f - 1.0f;
        out->color[c] = code[7 + c] * inv;
    }
    out->specular = code[10] * inv;
    out->density = wsum * l->density_scale[level];
}

/* density and the density-weighted tangent at p (level units), trilinear */
static float tvt__level_density_tangent(const tvt_texel *t, const float *p, float *tangent)
{
    long b[3];
    float f[3], sum = 0.0f;
    size_t slots[8];
    int n, c, oks[8];
    tvt__trilinear(p, b, f);
    tangent[0] = tangent[1] = tangent[2] = 0.0f;
    if (!t->brick_index) return 0.0f;
    tvt__corner_slots(t, b, slots, oks);
    for (n = 0; n < 8; n++) {
        float w = ((n & 1) ? f[0] : 1 - f[0]) * ((n & 2) ? f[1] : 1 - f[1]) * ((n & 4) ? f[2] : 1 - f[2]);
        unsigned q[TVT_CHANNELS] = {0};
        tvt_voxel v;
        if (!(w > 0) || !oks[n]) continue;
        tvt__load_density_tangent(t, slots[n], q);
        if (!q[0]) continue;
        tvt__decode(q, t->density_max, t->bits, &v);
        sum += w * v.density;
        for (c = 0; c < 3; c++) tangent[c] += w * v.density * v.tangent[c];
    }
    return sum;
}

/* the two parts of the optical depth at scale 1: isotropic sum(rho) and fibre sum(rho |t x d|) */
static void tvt__depth_parts(const tvt_lod *l, int level, const float *origin, const float *dir, float length,
                             float *iso, float *fibre)
{
    float step = 0.5f * (float)(1 << level), inv = 1.0f / (float)(1 << level), si = 0.0f, sf = 0.0f;
    int n = (int)ceilf(length / step), i;
    *iso = *fibre = 0.0f;
    if (n <= 0) return;
    step = length / (float)n;
    for (i = 0; i < n; i++) {
        float p[3], t[3], rho, tl, cosang, s = ((float)i + 0.5f) * step;
        p[0] = (origin[0] + s * dir[0]) * inv; p[1] = (origin[1] + s * dir[1]) * inv;
        p[2] = (origin[2] + s * dir[2]) * inv;
        rho = tvt__level_density_tangent(&l->level[level], p, t);
        if (!(rho > 0)) continue;
        si += rho;
        tl = sqrtf(tvt__dot(t, t));
        cosang = tl > 0 ? tvt__dot(t, dir) / tl : 0.0f;
        sf += rho * sqrtf(fmaxf(0.0f, 1.0f - cosang * cosang));
    }
    *iso = l->extinction * si * step;
    *fibre = l->extinction * sf * step;
}

TVTDEF float tvt_optical_depth(const tvt_lod *l, int level, const float origin[3], const float dir[3], float length)
{
    float iso, fibre, a = l->anisotropy[level];
    tvt__depth_parts(l, level, origin, dir, length, &iso, &fibre);
    return l->density_scale[level] * ((1.0f - a) * iso + a * fibre);
}

TVTDEF int tvt_lod_level_for(const tvt_lod *l, float footprint)
{
    int level = 0;
    while (level + 1 < l->levels && footprint >= (float)(2 << level)) level++;
    return level;
}

/* The calibration rays: from the top of the texel down to the ground at elevation e, from a
   uniform point of the top face in a uniform azimuth. */
static void tvt__calibration_ray(uint64_t seed, int res, float elevation, int i, float *o, float *d, float *len)
{
    uint64_t s = tvt__mix(seed ^ tvt__mix((uint64_t)i * 3 + 1 + (uint64_t)(elevation * 1000.0f)));
    float az = (float)(2.0 * TVT__PI) * tvt__rand(&s), ce = cosf(elevation), se = sinf(elevation);
    o[0] = (float)res * tvt__rand(&s);
    o[1] = (float)res * tvt__rand(&s);
    o[2] = (float)res;
    d[0] = ce * cosf(az); d[1] = ce * sinf(az); d[2] = -se;
    *len = (float)res / se;
}

/* Largest relative error of the mean opacity over the three elevations for scale c and
   anisotropy a; iso / fibre hold 3 * n ray depths of the level, target the level-0 means. */
static double tvt__fit_error(const float *iso, const float *fibre, int n, const double *target, double c, double a)
{
    double worst = 0.0;
    int e, i;
    for (e = 0; e < 3; e++) {
        double sum = 0.0, err;
        for (i = 0; i < n; i++) sum += 1.0 - exp(-c * ((1.0 - a) * iso[e * n + i] + a * fibre[e * n + i]));
        err = fabs(sum / n / (target[e] > 1e-9 ? target[e] : 1e-9) - 1.0);
        if (err > worst) worst = err;
    }
    return worst;
}

/* Scale c and anisotropy a of a level: for each a on a grid of 21 values in [0, 1], the c that
   minimises the largest relative error (the mean opacity grows with c, so each error is
   unimodal in c and so is their maximum: a ternary search on log c); the best pair wins. */
static void tvt__fit_level(const float *tau0, const float *iso, const float *fibre, int n, float *scale, float *aniso)
{
    double target[3], best = 1e30;
    int e, i, k, it;
    for (e = 0; e < 3; e++) {
        double sum = 0.0;
        for (i = 0; i < n; i++) sum += 1.0 - exp(-(double)tau0[e * n + i]);
        target[e] = sum / n;
    }
    *scale = 1.0f;
    *aniso = 0.0f;
    for (k = 0; k <= 20; k++) {
        double a = k / 20.0, lo = log(1.0 / 64), hi = log(8.0), err;
        for (it = 0; it < 40; it++) {
            double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
            if (tvt__fit_error(iso, fibre, n, target, exp(m1), a) <= tvt__fit_error(iso, fibre, n, target, exp(m2), a))
                hi = m2;
            else
                lo = m1;
        }
        err = tvt__fit_error(iso, fibre, n, target, exp(0.5 * (lo + hi)), a);
        if (err < best) { best = err; *scale = (float)exp(0.5 * (lo + hi)); *aniso = (float)a; }
    }
}

static void tvt__level_depths(const tvt_lod *l, int level, uint64_t seed, int n, float *iso, float *fibre)
{
    static const float elev[3] = {15.0f, 45.0f, 90.0f};
    int e, i;
    for (e = 0; e < 3; e++)
        for (i = 0; i < n; i++) {
            float o[3], d[3], len;
            tvt__calibration_ray(seed, l->level[0].res, elev[e] * (float)(TVT__PI / 180.0), i, o, d, &len);
            tvt__depth_parts(l, level, o, d, len, iso + e * n + i, fibre + e * n + i);
        }
}

static tvt_result tvt__lod_resolve(const tvt_lod_options *in, int res, tvt_lod_options *o)
{
    tvt_lod_options d = tvt_lod_default_options();
    int max_levels = 1;
    *o = in ? *in : d;
    while (max_levels < TVT_MAX_LEVELS && (res >> max_levels) >= 8) max_levels++;
    if (o->levels == 0) {
        o->levels = 1;
        while (o->levels < max_levels && (res >> o->levels) >= 32) o->levels++;
    }
    if (o->extinction == 0) o->extinction = d.extinction;
    if (o->calibration_rays == 0) o->calibration_rays = d.calibration_rays;
    if (o->levels < 1 || o->levels > max_levels) return TVT_ERR_BAD_RESOLUTION;
    if (!tvt__finite(o->extinction) || o->extinction <= 0 || o->calibration_rays < 16 ||
        o->calibration_rays > (1 << 20))
        return TVT_ERR_BAD_PARAMETER;
    return TVT_OK;
}

TVTDEF tvt_result tvt_build_lod(const tvt_texel *t, const tvt_lod_options *options, tvt_lod *out)
{
    tvt_lod_options o;
    tvt_allocator a;
    tvt_result r;
    float *depth = NULL;
    int l, n;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!t || !t->brick_index) return TVT_ERR_INVALID_ARGUMENT;
    r = tvt__lod_resolve(options, t->res, &o);
    if (r != TVT_OK) return r;
    a = tvt__resolve_allocator(o.allocator ? o.allocator : &t->allocator);
    n = o.calibration_rays;
    out->extinction = o.extinction;
    r = tvt__texel_copy(t, &a, &out->level[0]);
    if (r == TVT_OK) {
        out->levels = 1;
        out->density_scale[0] = 1.0f;
        if (o.levels > 1) {
            depth = (float *)tvt__alloc(&a, 12 * (size_t)n, sizeof(float)); /* level 0, then the level's two parts */
            if (!depth) r = TVT_ERR_OUT_OF_MEMORY;
            else tvt__level_depths(out, 0, o.seed, n, depth, depth + 3 * n);
        }
    }
    for (l = 1; r == TVT_OK && l < o.levels; l++) {
        r = tvt__downsample(&out->level[l - 1], &a, &out->level[l]);
        if (r != TVT_OK) break;
        out->levels = l + 1;
        tvt__level_depths(out, l, o.seed, n, depth + 6 * n, depth + 9 * n);
        tvt__fit_level(depth, depth + 6 * n, depth + 9 * n, n, &out->density_scale[l], &out->anisotropy[l]);
        if (tvt__report(o.progress, o.progress_user, (float)l / (float)(o.levels - 1))) r = TVT_CANCELLED;
    }
    tvt__free(&a, depth);
    if (r != TVT_OK) tvt_lod_free(out);
    return r;
}

TVTDEF size_t tvt_lod_bytes(const tvt_lod *l)
{
    size_t sum = 0;
    int i;
    for (i = 0; i < l->levels; i++) sum += tvt_texel_bytes(&l->level[i]);
    return sum;
}

TVTDEF void tvt_lod_free(tvt_lod *l)
{
    int i;
    if (!l) return;
    for (i = 0; i < TVT_MAX_LEVELS; i++) tvt_texel_free(&l->level[i]);
    memset(l, 0, sizeof(*l));
}

/* ---------------------------------------------------------------------------------------------
   TVT: key frames, interpolation, mingling
   --------------------------------------------------------------------------------------------- */
static tvt_result tvt__tvt_resolve(const tvt_tvt_options *in, tvt_tvt_options *o)
{
    tvt_tvt_options d = tvt_tvt_default_options();
    *o = in ? *in : d;
    if (o->frames == 0) o->frames = d.frames;
    if (o->steps_per_frame == 0) o->steps_per_frame = d.steps_per_frame;
    if (o->frames < 2 || o->frames > TVT_MAX_FRAMES || o->steps_per_frame < 1 || o->steps_per_frame > 64)
        return TVT_ERR_BAD_PARAMETER;
    return TVT_OK;
}

static tvt_result tvt__tvt_alloc(tvt_tvt *t, int frames, const tvt_allocator *a)
{
    int k;
    memset(t, 0, sizeof(*t));
    t->allocator = *a;
    t->frames = (tvt_lod *)tvt__alloc(a, (size_t)frames, sizeof(tvt_lod));
    if (!t->frames) return TVT_ERR_OUT_OF_MEMORY;
    memset(t->frames, 0, (size_t)frames * sizeof(tvt_lod));
    t->frame_count = frames;
    for (k = 0; k < frames; k++) t->wd[k] = (float)k / (float)(frames - 1);
    return TVT_OK;
}

/* progress of one stage of a long call, mapped into [done0, done1] of the caller's */
typedef struct tvt__subprogress {
    int (*progress)(void *user, float done);
    void *user;
    float done0, done1;
} tvt__subprogress;

static int tvt__sub_report(void *user, float done)
{
    tvt__subprogress *s = (tvt__subprogress *)user;
    return tvt__report(s->progress, s->user, s->done0 + (s->done1 - s->done0) * done);
}

/* One key frame: the points' splat and its pyramid. */
static tvt_result tvt__key_frame(const tvt_points *pts, const tvt_tvt_options *o, const tvt_allocator *a,
                                 tvt__subprogress *sub, tvt_lod *out)
{
    tvt_splat_options sp = o->splat ? *o->splat : tvt_splat_default_options();
    tvt_lod_options lo = o->lod ? *o->lod : tvt_lod_default_options();
    tvt_texel frame;
    tvt_result r;
    sp.allocator = a;
    lo.allocator = a;
    lo.progress = o->progress ? tvt__sub_report : NULL;
    lo.progress_user = sub;
    r = tvt_splat(pts, &sp, &frame);
    if (r != TVT_OK) return r;
    r = tvt_build_lod(&frame, &lo, out);
    tvt_texel_free(&frame);
    return r;
}

TVTDEF tvt_result tvt_build_tvt(const tvt_texel *grass, const tvt_tvt_options *options, tvt_tvt *out)
{
    tvt_tvt_options o;
    tvt_sample_options so;
    tvt_allocator a;
    tvt_points pts;
    tvt_result r;
    int k, s;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!grass) return TVT_ERR_INVALID_ARGUMENT;
    r = tvt__tvt_resolve(options, &o);
    if (r != TVT_OK) return r;
    a = tvt__resolve_allocator(o.allocator);
    so = o.sample ? *o.sample : tvt_sample_default_options();
    so.allocator = &a;
    r = tvt_sample(grass, &so, &pts);
    if (r != TVT_OK) return r;
    r = tvt__tvt_alloc(out, o.frames, &a);
    for (k = 0; r == TVT_OK && k < o.frames; k++) {
        tvt__subprogress sub;
        sub.progress = o.progress; sub.user = o.progress_user;
        sub.done0 = (float)k / (float)o.frames; sub.done1 = (float)(k + 1) / (float)o.frames;
        for (s = 1; k > 0 && r == TVT_OK && s <= o.steps_per_frame; s++) {
            float wd = out->wd[k - 1] + (out->wd[k] - out->wd[k - 1]) * (float)s / (float)o.steps_per_frame;
            r = tvt_age(&pts, s == o.steps_per_frame ? out->wd[k] : wd, o.model);
        }
        if (r == TVT_OK) r = tvt__key_frame(&pts, &o, &a, &sub, &out->frames[k]);
        if (r == TVT_OK && tvt__report(o.progress, o.progress_user, sub.done1)) r = TVT_CANCELLED;
    }
    tvt_points_free(&pts);
    if (r != TVT_OK) tvt_tvt_free(out);
    return r;
}

TVTDEF void tvt_tvt_frames_at(const tvt_tvt *t, float wd, int *f, float *w)
{
    float x;
    if (!(wd > 0)) wd = 0;
    if (wd > 1) wd = 1;
    x = wd * (float)(t->frame_count - 1);
    *f = (int)x;
    if (*f >= t->frame_count - 1) *f = t->frame_count - 2;
    *w = x - (float)*f;
}

/* acc += weight * (density, density * attributes) of v */
static void tvt__acc_add_voxel(float *acc, const tvt_voxel *v, float weight)
{
    float w = weight * v->density;
    int c;
    acc[0] += w;
    for (c = 0; c < 3; c++) {
        acc[1 + c] += w * v->normal[c];
        acc[4 + c] += w * v->tangent[c];
        acc[7 + c] += w * v->color[c];
    }
    acc[10] += w * v->specular;
}

TVTDEF void tvt_tvt_voxel(const tvt_tvt *t, float wd, int level, const float p[3], tvt_voxel *out)
{
    tvt_voxel a, b;
    float acc[TVT__ACC], w;
    int f;
    tvt_tvt_frames_at(t, wd, &f, &w);
    if (w <= 0.0f || w >= 1.0f) { /* on a key frame */
        tvt_lod_voxel(&t->frames[w <= 0.0f ? f : f + 1], level, p, out);
        return;
    }
    tvt_lod_voxel(&t->frames[f], level, p, &a);
    tvt_lod_voxel(&t->frames[f + 1], level, p, &b);
    memset(acc, 0, sizeof(acc));
    tvt__acc_add_voxel(acc, &a, 1.0f - w);
    tvt__acc_add_voxel(acc, &b, w);
    tvt__acc_resolve(acc, 1.0f, out);
}

TVTDEF size_t tvt_tvt_bytes(const tvt_tvt *t)
{
    size_t sum = 0;
    int k;
    for (k = 0; k < t->frame_count; k++) sum += tvt_lod_bytes(&t->frames[k]);
    return sum;
}

TVTDEF void tvt_tvt_free(tvt_tvt *t)
{
    int k;
    if (!t) return;
    for (k = 0; t->frames && k < t->frame_count; k++) tvt_lod_free(&t->frames[k]);
    if (t->frames) tvt__free(&t->allocator, t->frames);
    memset(t, 0, sizeof(*t));
}

TVTDEF float tvt_ageing_apply(const tvt_ageing_fn *fn, float wd)
{
    float x = wd;
    if (fn) x = (wd - fn->delay) * (fn->rate != 0 ? fn->rate : 1.0f);
    return x > 0 ? (x < 1 ? x : 1.0f) : 0.0f;
}

/* Adds sample s at its own wd (between frames f and f + 1 at weight w) into the accumulator. */
static int tvt__mingle_add(tvt__acc *g, const tvt_tvt *s, int f, float w)
{
    const tvt_texel *t0 = &s->frames[f].level[0], *t1 = &s->frames[f + 1].level[0];
    size_t nb = (size_t)t0->bricks_per_side, b;
    for (b = 0; b < nb * nb * nb; b++) {
        long bx = (long)(b % nb) * 4, by = (long)(b / nb % nb) * 4, bz = (long)(b / (nb * nb)) * 4;
        int i;
        if (t0->brick_index[b] == TVT_EMPTY_BRICK && t1->brick_index[b] == TVT_EMPTY_BRICK) continue;
        for (i = 0; i < TVT__BV; i++) {
            long x = bx + (i & 3), y = by + ((i >> 2) & 3), z = bz + (i >> 4);
            tvt_voxel a, c;
            float *acc;
            tvt_texel_voxel(t0, x, y, z, &a);
            tvt_texel_voxel(t1, x, y, z, &c);
            if (!(a.density > 0) && !(c.density > 0)) continue;
            acc = tvt__acc_voxel(g, (int)x, (int)y, (int)z);
            if (!acc) return 0;
            tvt__acc_add_voxel(acc, &a, 1.0f - w);
            tvt__acc_add_voxel(acc, &c, w);
        }
    }
    return 1;
}

TVTDEF tvt_result tvt_mingle(const tvt_tvt *samples, const tvt_ageing_fn *fns, size_t count, float wd, int bits,
                             const tvt_allocator *allocator, tvt_texel *out)
{
    tvt_allocator a = tvt__resolve_allocator(allocator);
    tvt__acc g;
    tvt_result r;
    size_t i;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!samples || count == 0) return count == 0 ? TVT_ERR_EMPTY : TVT_ERR_INVALID_ARGUMENT;
    if (!(wd >= 0.0f && wd <= 1.0f)) return TVT_ERR_BAD_WD;
    if (bits == 0) bits = 8;
    if (bits != 8 && bits != 16) return TVT_ERR_BAD_RESOLUTION;
    for (i = 0; i < count; i++) {
        if (!samples[i].frames || samples[i].frame_count < 2) return TVT_ERR_INVALID_ARGUMENT;
        if (samples[i].frames[0].level[0].res != samples[0].frames[0].level[0].res) return TVT_ERR_BAD_RESOLUTION;
        if (fns && (!tvt__finite(fns[i].delay) || !tvt__finite(fns[i].rate) || fns[i].rate < 0))
            return TVT_ERR_BAD_PARAMETER;
    }
    r = tvt__acc_init(&g, samples[0].frames[0].level[0].res, &a);
    for (i = 0; r == TVT_OK && i < count; i++) {
        int f;
        float w;
        tvt_tvt_frames_at(samples + i, tvt_ageing_apply(fns ? fns + i : NULL, wd), &f, &w);
        if (!tvt__mingle_add(&g, samples + i, f, w)) r = TVT_ERR_OUT_OF_MEMORY;
    }
    if (r == TVT_OK) r = tvt__acc_to_texel(&g, 1.0f, bits, 0, out);
    tvt__acc_free(&g);
    return r;
}

TVTDEF tvt_result tvt_mingle_tvt(const tvt_tvt *samples, const tvt_ageing_fn *fns, size_t count,
                                 const tvt_tvt_options *options, tvt_tvt *out)
{
    tvt_tvt_options o;
    tvt_allocator a;
    tvt_result r;
    int k;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    r = tvt__tvt_resolve(options, &o);
    if (r != TVT_OK) return r;
    a = tvt__resolve_allocator(o.allocator);
    r = tvt__tvt_alloc(out, o.frames, &a);
    for (k = 0; r == TVT_OK && k < o.frames; k++) {
        tvt_lod_options lo = o.lod ? *o.lod : tvt_lod_default_options();
        tvt_texel m;
        int bits = o.splat ? o.splat->bits : 8;
        r = tvt_mingle(samples, fns, count, out->wd[k], bits, &a, &m);
        if (r != TVT_OK) break;
        lo.allocator = &a;
        r = tvt_build_lod(&m, &lo, &out->frames[k]);
        tvt_texel_free(&m);
        if (r == TVT_OK && tvt__report(o.progress, o.progress_user, (float)(k + 1) / (float)o.frames)) r = TVT_CANCELLED;
    }
    if (r != TVT_OK) tvt_tvt_free(out);
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Sampling, shading, ray marching
   --------------------------------------------------------------------------------------------- */
TVTDEF float tvt_tvt_density(const tvt_tvt *t, float wd, int level, const float p[3])
{
    int f;
    float w, a, b;
    tvt_tvt_frames_at(t, wd, &f, &w);
    a = w < 1.0f ? tvt_lod_density(&t->frames[f], level, p) : 0.0f;
    b = w > 0.0f ? tvt_lod_density(&t->frames[f + 1], level, p) : 0.0f;
    return (1.0f - w) * a + w * b;
}

/* extinction sigma of a sample (density, unit-ish tangent) along dir at a level */
static float tvt__sigma(const tvt_lod *l, int level, const tvt_voxel *v, const float *dir)
{
    float a = l->anisotropy[level], tl = sqrtf(tvt__dot(v->tangent, v->tangent)), c, sin_td;
    c = tl > 0 ? tvt__dot(v->tangent, dir) / tl : 0.0f;
    sin_td = sqrtf(fmaxf(0.0f, 1.0f - c * c));
    return l->extinction * v->density * (1.0f - a + a * sin_td);
}

/* Light transmittance of one frame by layers from the top down: a voxel centre's ray toward the
   light crosses the layer above at (x + lx / lz, y + ly / lz) (in voxels of the level), whose
   transmittance is interpolated there (x, y wrap), times exp(-tau) of the step between, tau
   from the two ends' extinction (trapezoid rule). */
static void tvt__shadow_frame(const tvt_tvt *t, int k, int level, const float *light, float *out)
{
    const tvt_lod *l = &t->frames[k];
    const tvt_texel *tx = &l->level[level];
    int res = tx->res, x, y, z;
    float vox = (float)(1 << level), ox = light[0] / light[2], oy = light[1] / light[2];
    float len = vox / light[2]; /* level-0 length of one layer's step */
    size_t plane = (size_t)res * res;
    for (z = res - 1; z >= 0; z--)
        for (y = 0; y < res; y++)
            for (x = 0; x < res; x++) {
                float p[3], pa[3], T_above = 1.0f, sig, sig_a = 0.0f;
                tvt_voxel v;
                p[0] = ((float)x + 0.5f) * vox; p[1] = ((float)y + 0.5f) * vox; p[2] = ((float)z + 0.5f) * vox;
                tvt_lod_voxel(l, level, p, &v);
                sig = tvt__sigma(l, level, &v, light);
                if (z + 1 < res) {
                    float fx = (float)x + ox, fy = (float)y + oy, gx = floorf(fx), gy = floorf(fy), ax = fx - gx, ay = fy - gy;
                    long ix = (long)gx, iy = (long)gy;
                    const float *up = out + plane * (size_t)(z + 1);
                    size_t x0 = (size_t)(ix & (res - 1)), x1 = (size_t)((ix + 1) & (res - 1));
                    size_t y0 = (size_t)(iy & (res - 1)), y1 = (size_t)((iy + 1) & (res - 1));
                    T_above = (1 - ay) * ((1 - ax) * up[y0 * res + x0] + ax * up[y0 * res + x1]) +
                              ay * ((1 - ax) * up[y1 * res + x0] + ax * up[y1 * res + x1]);
                    pa[0] = p[0] + ox * vox; pa[1] = p[1] + oy * vox; pa[2] = p[2] + vox;
                    tvt_lod_voxel(l, level, pa, &v);
                    sig_a = tvt__sigma(l, level, &v, light);
                } else
                    len = 0.5f * vox / light[2], sig_a = 0.0f; /* half a voxel to the top */
                out[plane * (size_t)z + (size_t)y * res + (size_t)x] = T_above * expf(-0.5f * (sig + sig_a) * len);
                len = vox / light[2];
            }
}

TVTDEF tvt_result tvt_build_shadow(const tvt_tvt *t, int level, const float light_dir[3],
                                   const tvt_allocator *allocator, tvt_shadow *out)
{
    tvt_allocator a;
    size_t n;
    int k;
    if (!out) return TVT_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof(*out));
    if (!t || !t->frames || !light_dir) return TVT_ERR_INVALID_ARGUMENT;
    if (level < 0) level = t->frames[0].levels - 1;
    if (level >= t->frames[0].levels) return TVT_ERR_BAD_RESOLUTION;
    if (!tvt__finite(light_dir[0]) || !tvt__finite(light_dir[1]) || !tvt__finite(light_dir[2]) ||
        light_dir[2] <= 0.05f || fabsf(tvt__dot(light_dir, light_dir) - 1.0f) > 1e-3f)
        return TVT_ERR_BAD_PARAMETER;
    a = tvt__resolve_allocator(allocator ? allocator : &t->allocator);
    out->res = t->frames[0].level[level].res;
    n = (size_t)out->res * out->res * out->res;
    out->transmittance = (float *)tvt__alloc(&a, n * (size_t)t->frame_count, sizeof(float));
    if (!out->transmittance) return TVT_ERR_OUT_OF_MEMORY;
    out->level = level;
    out->frames = t->frame_count;
    memcpy(out->light, light_dir, sizeof(out->light));
    out->allocator = a;
    for (k = 0; k < t->frame_count; k++) tvt__shadow_frame(t, k, level, light_dir, out->transmittance + n * (size_t)k);
    return TVT_OK;
}

static float tvt__shadow_grid(const float *g, int res, const float *q)
{
    long b[3];
    float f[3], sum = 0.0f;
    int n;
    tvt__trilinear(q, b, f);
    for (n = 0; n < 8; n++) {
        float w = ((n & 1) ? f[0] : 1 - f[0]) * ((n & 2) ? f[1] : 1 - f[1]) * ((n & 4) ? f[2] : 1 - f[2]);
        long x = b[0] + (n & 1), y = b[1] + ((n >> 1) & 1), z = b[2] + ((n >> 2) & 1);
        x &= res - 1;
        y &= res - 1;
        if (z < 0) z = 0;
        sum += w * (z >= res ? 1.0f : g[((size_t)z * res + (size_t)y) * res + (size_t)x]);
    }
    return sum;
}

TVTDEF float tvt_shadow_at(const tvt_shadow *s, float wd, const float p[3])
{
    float q[3], inv = 1.0f / (float)(1 << s->level), x, w;
    size_t n = (size_t)s->res * s->res * s->res;
    int f;
    if (!(wd > 0)) wd = 0;
    if (wd > 1) wd = 1;
    x = wd * (float)(s->frames - 1);
    f = (int)x;
    if (f >= s->frames - 1) f = s->frames - 2;
    w = x - (float)f;
    q[0] = p[0] * inv; q[1] = p[1] * inv; q[2] = p[2] * inv;
    return (1.0f - w) * tvt__shadow_grid(s->transmittance + n * (size_t)f, s->res, q) +
           w * tvt__shadow_grid(s->transmittance + n * (size_t)(f + 1), s->res, q);
}

TVTDEF void tvt_shadow_free(tvt_shadow *s)
{
    if (!s) return;
    if (s->transmittance) tvt__free(&s->allocator, s->transmittance);
    memset(s, 0, sizeof(*s));
}

static void tvt__shade_resolve(const tvt_shade_desc *in, tvt_shade_desc *o)
{
    tvt_shade_desc d = tvt_shade_default_desc();
    *o = in ? *in : d;
    if (o->light_dir[0] == 0 && o->light_dir[1] == 0 && o->light_dir[2] == 0) memcpy(o->light_dir, d.light_dir, sizeof(d.light_dir));
    if (o->light_rgb[0] == 0 && o->light_rgb[1] == 0 && o->light_rgb[2] == 0) memcpy(o->light_rgb, d.light_rgb, sizeof(d.light_rgb));
    if (o->ambient_rgb[0] == 0 && o->ambient_rgb[1] == 0 && o->ambient_rgb[2] == 0)
        memcpy(o->ambient_rgb, d.ambient_rgb, sizeof(d.ambient_rgb));
    if (o->kd == 0) o->kd = d.kd;
    if (o->ks == 0) o->ks = d.ks;
    if (o->shininess == 0) o->shininess = d.shininess;
}

/* Kajiya-Kay (1989): diffuse kd sin(t, l), specular ks (sin(t,l) sin(t,e) - (t.l)(t.e))^p with e
   toward the eye; a voxel without a tangent (|t| ~ 0) is lit as Lambert with its normal. */
static void tvt__kajiya_kay(const tvt_shade_desc *s, const tvt_voxel *v, const float *dir, float shadow, float *rgb)
{
    float t[3], e[3], tl = sqrtf(tvt__dot(v->tangent, v->tangent)), diff, spec = 0.0f;
    int c;
    e[0] = -dir[0]; e[1] = -dir[1]; e[2] = -dir[2];
    if (tl > 0.1f) {
        float tdl, tde, sl, se, k;
        t[0] = v->tangent[0] / tl; t[1] = v->tangent[1] / tl; t[2] = v->tangent[2] / tl;
        tdl = tvt__dot(t, s->light_dir);
        tde = tvt__dot(t, e);
        sl = sqrtf(fmaxf(0.0f, 1.0f - tdl * tdl));
        se = sqrtf(fmaxf(0.0f, 1.0f - tde * tde));
        diff = s->kd * sl;
        k = sl * se - tdl * tde;
        if (k > 0) spec = s->ks * v->specular * powf(k, s->shininess);
    } else {
        float n[3];
        memcpy(n, v->normal, sizeof(n));
        tvt__normalize(n);
        diff = s->kd * fmaxf(0.0f, tvt__dot(n, s->light_dir));
    }
    for (c = 0; c < 3; c++)
        rgb[c] = v->color[c] * (s->ambient_rgb[c] + s->light_rgb[c] * shadow * diff) + s->light_rgb[c] * shadow * spec;
}

TVTDEF float tvt_tvt_sample(const tvt_tvt *t, float wd, int level, const float p[3], const float dir[3], tvt_voxel *out)
{
    int f;
    float w;
    tvt_tvt_voxel(t, wd, level, p, out);
    if (!(out->density > 0)) return 0.0f;
    tvt_tvt_frames_at(t, wd, &f, &w);
    return tvt__sigma(&t->frames[w < 0.5f ? f : f + 1], level, out, dir);
}

TVTDEF float tvt_shade_point(const tvt_tvt *t, float wd, int level, const tvt_shade_desc *s, const float p[3],
                             const float dir[3], float step, float rgb[3])
{
    tvt_shade_desc sd;
    tvt_voxel v;
    float sigma, shadow = 1.0f;
    tvt__shade_resolve(s, &sd);
    sigma = tvt_tvt_sample(t, wd, level, p, dir, &v);
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!(sigma > 0)) return 0.0f;
    if (sd.shadow) shadow = tvt_shadow_at(sd.shadow, wd, p);
    tvt__kajiya_kay(&sd, &v, dir, shadow, rgb);
    return 1.0f - expf(-sigma * step);
}

TVTDEF void tvt_march(const tvt_tvt *t, float wd, int level, const tvt_shade_desc *s, const float origin[3],
                      const float dir[3], float length, float rgb[3], float *transmittance)
{
    int coarse = t->frames[0].levels - 1;
    float step = 0.5f * (float)(1 << level), skip = 0.5f * (float)(1 << coarse), T = 1.0f, x = 0.0f;
    int empty = 1; /* the coarse test only after an empty step: inside grass it would not skip */
    tvt_shade_desc sd;
    tvt__shade_resolve(s, &sd);
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    while (x < length && T > 0.005f) {
        float p[3], c[3], alpha, h = fminf(step, length - x);
        p[0] = origin[0] + (x + 0.5f * h) * dir[0];
        p[1] = origin[1] + (x + 0.5f * h) * dir[1];
        p[2] = origin[2] + (x + 0.5f * h) * dir[2];
        if (skip > step && empty && tvt_tvt_density(t, wd, coarse, p) <= 0.0f) { x += skip; continue; }
        alpha = tvt_shade_point(t, wd, level, &sd, p, dir, h, c);
        empty = alpha <= 0.0f;
        rgb[0] += T * alpha * c[0]; rgb[1] += T * alpha * c[1]; rgb[2] += T * alpha * c[2];
        T *= 1.0f - alpha;
        x += h;
    }
    *transmittance = T;
}

/* ---------------------------------------------------------------------------------------------
   Defaults and names
   --------------------------------------------------------------------------------------------- */
TVTDEF tvt_grass_desc tvt_grass_default_desc(void)
{
    tvt_grass_desc d;
    memset(&d, 0, sizeof(d));
    d.res = 64;
    d.blade_count = 100;
    d.height_min = 0.55f; d.height_max = 0.9f;
    d.radius_min = 1.5f; d.radius_max = 1.5f;
    d.lean_min_deg = 3.0f; d.lean_max_deg = 12.0f;
    d.supersample = 3;
    d.bits = 8;
    d.specular = 0.3f;
    return d;
}

TVTDEF tvt_sample_options tvt_sample_default_options(void)
{
    tvt_sample_options o;
    memset(&o, 0, sizeof(o));
    o.proportion = 6.0f;
    return o;
}

TVTDEF tvt_model_options tvt_model_default_options(void)
{
    tvt_model_options o;
    memset(&o, 0, sizeof(o));
    o.water_curve = TVT_WATER_STANDARD;
    o.k_vein = 0.10f; o.k_mesophyll = 0.40f;
    o.vein_stiffness = 2.0f; o.stiffening = 4.0f; o.area_ratio = 3.0f;
    o.droop_max_deg = 80.0f; o.droop_exponent = 2.0f; o.droop_length = 0.6f;
    o.merge_threshold = 0.15f;
    o.colour_jitter = 0.05f;
    return o;
}

TVTDEF tvt_shade_desc tvt_shade_default_desc(void)
{
    tvt_shade_desc d;
    float l = sqrtf(0.45f * 0.45f + 0.3f * 0.3f + 0.84f * 0.84f);
    memset(&d, 0, sizeof(d));
    d.light_dir[0] = 0.45f / l; d.light_dir[1] = 0.3f / l; d.light_dir[2] = 0.84f / l;
    d.light_rgb[0] = d.light_rgb[1] = d.light_rgb[2] = 1.0f;
    d.ambient_rgb[0] = 0.22f; d.ambient_rgb[1] = 0.25f; d.ambient_rgb[2] = 0.3f;
    d.kd = 1.0f; d.ks = 0.35f; d.shininess = 24.0f;
    return d;
}

TVTDEF tvt_tvt_options tvt_tvt_default_options(void)
{
    tvt_tvt_options o;
    memset(&o, 0, sizeof(o));
    o.frames = 8;
    o.steps_per_frame = 2;
    return o;
}

TVTDEF tvt_lod_options tvt_lod_default_options(void)
{
    tvt_lod_options o;
    memset(&o, 0, sizeof(o));
    o.extinction = 1.0f;
    o.calibration_rays = 512;
    return o;
}

TVTDEF tvt_splat_options tvt_splat_default_options(void)
{
    tvt_splat_options o;
    memset(&o, 0, sizeof(o));
    o.bits = 8;
    o.sigma = 0.5f;
    return o;
}

/* ---------------------------------------------------------------------------------------------
   Tiling over a mesh shell: prisms split into tetrahedra, an affine map in each
   --------------------------------------------------------------------------------------------- */
TVTDEF void tvt_shell_prism_tets(const uint32_t tri[3], uint32_t vertex_count, uint32_t tets[3][4])
{
    uint32_t a = tri[0], b = tri[1], c = tri[2], t, n = vertex_count;
    if (a > b) { t = a; a = b; b = t; }
    if (b > c) { t = b; b = c; c = t; }
    if (a > b) { t = a; a = b; b = t; }
    /* side face (i, j), i < j, is cut along i -> j': the same from both prisms that share it */
    tets[0][0] = a; tets[0][1] = b;     tets[0][2] = c;     tets[0][3] = c + n;
    tets[1][0] = a; tets[1][1] = b;     tets[1][2] = b + n; tets[1][3] = c + n;
    tets[2][0] = a; tets[2][1] = a + n; tets[2][2] = b + n; tets[2][3] = c + n;
}

static double tvt__det3(const double m[9])
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* inverse of the row-major 3x3 m (det != 0) */
static void tvt__inv3(const double m[9], double det, double r[9])
{
    double id = 1.0 / det;
    r[0] = (m[4] * m[8] - m[5] * m[7]) * id; r[1] = (m[2] * m[7] - m[1] * m[8]) * id; r[2] = (m[1] * m[5] - m[2] * m[4]) * id;
    r[3] = (m[5] * m[6] - m[3] * m[8]) * id; r[4] = (m[0] * m[8] - m[2] * m[6]) * id; r[5] = (m[2] * m[3] - m[0] * m[5]) * id;
    r[6] = (m[3] * m[7] - m[4] * m[6]) * id; r[7] = (m[1] * m[6] - m[0] * m[7]) * id; r[8] = (m[0] * m[4] - m[1] * m[3]) * id;
}

/* checks every vertex and index: 0 or an error */
static tvt_result tvt__shell_check(const tvt_shell_desc *d)
{
    size_t i;
    if (!d->positions || !d->normals || !d->uvs || !d->indices) return TVT_ERR_INVALID_ARGUMENT;
    if (d->vertex_count == 0 || d->triangle_count == 0) return TVT_ERR_EMPTY;
    if (d->vertex_count > 0x7FFFFFFFu || d->triangle_count > ((size_t)-1) / (3 * TVT_SHELL_TET_FLOATS * sizeof(float)))
        return TVT_ERR_TOO_LARGE;
    if (!tvt__finite(d->height) || !(d->height > 0.0f)) return TVT_ERR_BAD_PARAMETER;
    for (i = 0; i < d->vertex_count; i++) {
        const float *p = d->positions + 3 * i, *n = d->normals + 3 * i, *uv = d->uvs + 2 * i;
        if (!tvt__finite(p[0]) || !tvt__finite(p[1]) || !tvt__finite(p[2]) || !tvt__finite(n[0]) || !tvt__finite(n[1]) ||
            !tvt__finite(n[2]) || !tvt__finite(uv[0]) || !tvt__finite(uv[1]) || !(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.0f))
            return TVT_ERR_BAD_PARAMETER;
    }
    for (i = 0; i < 3 * d->triangle_count; i++)
        if (d->indices[i] >= d->vertex_count) return TVT_ERR_BAD_INDEX;
    return TVT_OK;
}

/* a shell vertex (v < n: the mesh, else offset by height along the unit normal) and its uvw */
static void tvt__shell_vertex(const tvt_shell_desc *d, uint32_t v, double x[3], double u[3])
{
    uint32_t n = (uint32_t)d->vertex_count, m = v < n ? v : v - n;
    const float *p = d->positions + 3 * (size_t)m, *nr = d->normals + 3 * (size_t)m;
    double l = sqrt((double)nr[0] * nr[0] + (double)nr[1] * nr[1] + (double)nr[2] * nr[2]), h = v < n ? 0.0 : d->height / l;
    int k;
    for (k = 0; k < 3; k++) x[k] = (double)p[k] + h * nr[k];
    u[0] = d->uvs[2 * (size_t)m]; u[1] = d->uvs[2 * (size_t)m + 1]; u[2] = v < n ? 0.0 : 1.0;
}

/* the triangle's orientation: sign of its area against the normals (world) and in uv; 0 = degenerate */
static int tvt__shell_orientation(const tvt_shell_desc *d, const uint32_t *tri, int *o_uv)
{
    double x[3][3], u[3][3], e1[3], e2[3], c[3], ns = 0, l1, l2, cu, d1, d2;
    int k, j;
    for (k = 0; k < 3; k++) tvt__shell_vertex(d, tri[k], x[k], u[k]);
    for (j = 0; j < 3; j++) { e1[j] = x[1][j] - x[0][j]; e2[j] = x[2][j] - x[0][j]; }
    c[0] = e1[1] * e2[2] - e1[2] * e2[1]; c[1] = e1[2] * e2[0] - e1[0] * e2[2]; c[2] = e1[0] * e2[1] - e1[1] * e2[0];
    l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]); l2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
    if (!(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) > 1e-7 * l1 * l2)) return 0;
    cu = (u[1][0] - u[0][0]) * (u[2][1] - u[0][1]) - (u[1][1] - u[0][1]) * (u[2][0] - u[0][0]);
    d1 = hypot(u[1][0] - u[0][0], u[1][1] - u[0][1]); d2 = hypot(u[2][0] - u[0][0], u[2][1] - u[0][1]);
    if (!(fabs(cu) > 1e-7 * d1 * d2)) return 0;
    *o_uv = cu > 0 ? 1 : -1;
    for (k = 0; k < 3; k++) {
        const float *n = d->normals + 3 * (size_t)tri[k];
        ns += c[0] * n[0] + c[1] * n[1] + c[2] * n[2];
    }
    return ns > 0 ? 1 : ns < 0 ? -1 : 2; /* 2: normals in the triangle's plane (a flat prism) */
}

/* one tetrahedron's maps into out (TVT_SHELL_TET_FLOATS); 0 if it is folded (inverted or flat) */
static int tvt__shell_tet(const tvt_shell_desc *d, const uint32_t ids[4], int orient, float *out)
{
    double x[4][3], u[4][3], A[9], B[9], Ai[9], Bi[9], J[9], da, db, l[3];
    int k, r, c;
    for (k = 0; k < 4; k++) tvt__shell_vertex(d, ids[k], x[k], u[k]);
    for (r = 0; r < 3; r++)
        for (c = 0; c < 3; c++) { A[r * 3 + c] = x[c + 1][r] - x[0][r]; B[r * 3 + c] = u[c + 1][r] - u[0][r]; }
    for (c = 0; c < 3; c++) l[c] = sqrt(A[c] * A[c] + A[3 + c] * A[3 + c] + A[6 + c] * A[6 + c]);
    da = tvt__det3(A); db = tvt__det3(B);
    memset(out, 0, TVT_SHELL_TET_FLOATS * sizeof(float));
    if (!(fabs(da) > 1e-6 * l[0] * l[1] * l[2]) || db == 0.0) return 0;
    tvt__inv3(A, da, Ai); tvt__inv3(B, db, Bi);
    for (r = 0; r < 3; r++)
        for (c = 0; c < 3; c++) J[r * 3 + c] = B[r * 3] * Ai[c] + B[r * 3 + 1] * Ai[3 + c] + B[r * 3 + 2] * Ai[6 + c];
    for (k = 0; k < 3; k++) { out[k] = (float)x[0][k]; out[12 + k] = (float)u[0][k]; }
    for (k = 0; k < 9; k++) {
        out[3 + k] = (float)Ai[k]; out[15 + k] = (float)J[k]; out[24 + k] = (float)Bi[k];
        out[33 + k] = (float)A[(k % 3) * 3 + k / 3]; /* edge k / 3, component k % 3 */
    }
    return (da > 0) == (db > 0) ? orient > 0 : orient < 0; /* det J's sign must be the prism's */
}

TVTDEF tvt_result tvt_build_shell(const tvt_shell_desc *desc, tvt_shell *out)
{
    tvt_allocator a;
    tvt_result r;
    size_t t;
    if (out) memset(out, 0, sizeof(*out));
    if (!desc || !out) return TVT_ERR_INVALID_ARGUMENT;
    if ((r = tvt__shell_check(desc)) != TVT_OK) return r;
    a = tvt__resolve_allocator(desc->allocator);
    out->tets = (float *)tvt__alloc(&a, 3 * TVT_SHELL_TET_FLOATS * desc->triangle_count, sizeof(float));
    if (!out->tets) return TVT_ERR_OUT_OF_MEMORY;
    out->allocator = a;
    out->prism_count = desc->triangle_count;
    out->height = desc->height;
    for (t = 0; t < desc->triangle_count; t++) {
        const uint32_t *tri = desc->indices + 3 * t;
        uint32_t ids[3][4];
        int o_uv = 0, o_w, k, ok = 1;
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || !(o_w = tvt__shell_orientation(desc, tri, &o_uv))) {
            tvt_shell_free(out);
            return TVT_ERR_DEGENERATE;
        }
        tvt_shell_prism_tets(tri, (uint32_t)desc->vertex_count, ids);
        for (k = 0; k < 3; k++)
            ok &= tvt__shell_tet(desc, ids[k], o_w == 2 ? 0 : o_w * o_uv, out->tets + (3 * t + (size_t)k) * TVT_SHELL_TET_FLOATS);
        if (!ok) {
            out->folded++;
            if (!desc->allow_folded) { tvt_shell_free(out); return TVT_ERR_FOLDED; }
        }
    }
    return TVT_OK;
}

TVTDEF void tvt_shell_free(tvt_shell *s)
{
    if (!s) return;
    if (s->tets) tvt__free(&s->allocator, s->tets);
    memset(s, 0, sizeof(*s));
}

/* y = a + M (x - o) for a row-major 3x3 M */
static void tvt__affine3(const float *o, const float *M, const float *a, const float x[3], float y[3])
{
    float d0 = x[0] - o[0], d1 = x[1] - o[1], d2 = x[2] - o[2];
    int r;
    for (r = 0; r < 3; r++) y[r] = (a ? a[r] : 0.0f) + M[3 * r] * d0 + M[3 * r + 1] * d1 + M[3 * r + 2] * d2;
}

/* the prism's tetrahedron that holds x best (largest smallest barycentric coordinate); its
   coordinates lambda_1..3 into lam, the smallest one returned */
static float tvt__shell_pick(const tvt_shell *s, size_t prism, const float x[3], int uvw_side, const float **tet, float lam[3])
{
    float best = -1e30f;
    int k;
    for (k = 0; k < 3; k++) {
        const float *T = s->tets + (3 * prism + (size_t)k) * TVT_SHELL_TET_FLOATS;
        float l[3], m;
        if (uvw_side) tvt__affine3(T + 12, T + 24, NULL, x, l);
        else tvt__affine3(T, T + 3, NULL, x, l);
        m = 1.0f - l[0] - l[1] - l[2];
        if (l[0] < m) m = l[0];
        if (l[1] < m) m = l[1];
        if (l[2] < m) m = l[2];
        if (m > best) { best = m; *tet = T; memcpy(lam, l, sizeof(l)); }
    }
    return best;
}

TVTDEF int tvt_shell_map(const tvt_shell *s, size_t prism, const float p[3], float uvw[3])
{
    const float *T = NULL;
    float lam[3], m;
    if (!s || !s->tets || prism >= s->prism_count || !p || !uvw) return -1;
    m = tvt__shell_pick(s, prism, p, 0, &T, lam);
    tvt__affine3(T, T + 15, T + 12, p, uvw);
    return m >= -1e-5f;
}

TVTDEF int tvt_shell_unmap(const tvt_shell *s, size_t prism, const float uvw[3], float p[3])
{
    const float *T = NULL;
    float lam[3], m;
    int k;
    if (!s || !s->tets || prism >= s->prism_count || !uvw || !p) return -1;
    m = tvt__shell_pick(s, prism, uvw, 1, &T, lam);
    for (k = 0; k < 3; k++) p[k] = T[k] + T[33 + k] * lam[0] + T[36 + k] * lam[1] + T[39 + k] * lam[2];
    return m >= -1e-5f;
}

TVTDEF float tvt_tile_wd(const tvt_wd_map *m, long i, long j)
{
    long x, y;
    float v;
    if (!m || !m->wd || m->width < 1 || m->height < 1) return 0.0f;
    x = i - m->origin[0]; y = j - m->origin[1];
    if (m->wrap) {
        x %= m->width; y %= m->height;
        if (x < 0) x += m->width;
        if (y < 0) y += m->height;
    } else {
        x = x < 0 ? 0 : x >= m->width ? m->width - 1 : x;
        y = y < 0 ? 0 : y >= m->height ? m->height - 1 : y;
    }
    v = m->wd[(size_t)y * (size_t)m->width + (size_t)x];
    return v >= 0.0f ? (v <= 1.0f ? v : 1.0f) : 0.0f;
}

TVTDEF const char *tvt_result_string(tvt_result r)
{
    switch (r) {
    case TVT_OK: return "TVT_OK";
    case TVT_ERR_INVALID_ARGUMENT: return "TVT_ERR_INVALID_ARGUMENT";
    case TVT_ERR_BAD_RESOLUTION: return "TVT_ERR_BAD_RESOLUTION";
    case TVT_ERR_BAD_PARAMETER: return "TVT_ERR_BAD_PARAMETER";
    case TVT_ERR_BAD_WD: return "TVT_ERR_BAD_WD";
    case TVT_ERR_EMPTY: return "TVT_ERR_EMPTY";
    case TVT_ERR_TOO_LARGE: return "TVT_ERR_TOO_LARGE";
    case TVT_ERR_OUT_OF_MEMORY: return "TVT_ERR_OUT_OF_MEMORY";
    case TVT_CANCELLED: return "TVT_CANCELLED";
    case TVT_ERR_BAD_INDEX: return "TVT_ERR_BAD_INDEX";
    case TVT_ERR_DEGENERATE: return "TVT_ERR_DEGENERATE";
    case TVT_ERR_FOLDED: return "TVT_ERR_FOLDED";
    }
    return "TVT_ERR_?";
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* TVT_IMPLEMENTATION_DONE */
#endif /* TVT_IMPLEMENTATION */

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
