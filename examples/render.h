/* render.h - v0.1 - MIT licence or public domain (see end of file)
   A minimal software rasterizer, height-field and volume ray marcher, image readers (PNG, PGM,
   PPM, PFM) and writers (PNG 8 / 16-bit, PPM, PFM, contact sheets) for the examples of this
   project. libc + libm only.

   WHAT
     - Framebuffer: float RGBA colour + float depth (GL convention: 0 near, 1 far, cleared to 1),
       row 0 at the top of the picture. Look-at camera, perspective or orthographic, with
       column-major GL matrices (view, proj, viewproj) that can be handed to OpenGL unchanged.
     - Triangle rasterizer: clipping in homogeneous space against the near and far planes (and a
       guard band), 8-bit sub-pixel fixed-point edge functions with the top-left fill rule,
       perspective-correct interpolation, GL_LESS depth test, optional culling, flat / Gouraud /
       per-pixel Phong lighting (the fixed-function GL model: ambient + diffuse + Blinn specular,
       directional and point lights), per-vertex colour, object-space normal map, wireframe
       overlay (faded out where triangles are too small on screen for it to stay lines), a fragment callback, and a fragment-counting mode for coverage tests.
       It is a deferred ("visibility buffer") rasterizer: each draw first resolves depth,
       triangle and barycentrics per pixel, then shades every covered pixel once.
     - Relief mapping of a height map over a world-space quad (Policarpo et al. 2005: linear
       search then binary refinement), with self-shadowing (a march up from the hit, or
       Policarpo's search down the light ray) and, for curved surfaces, a bend per quad that
       gives correct silhouettes; ray marching of a terrain height field, and ray marching
       of a box-bounded volume given by callbacks (front-to-back compositing, early termination,
       shadow rays, Kajiya-Kay hair/grass lighting). All of them write depth and so composite
       with rasterized geometry in either order (opaque ones; draw volumes last).
     - Shell marching (sr_draw_shell): a volumetric layer (grass, fur, canopy) over a height
       field, tiled, whose content comes from one callback in each tile's own sheared frame; see
       SHELL below. sr_draw_mesh_shell: the same over a triangle mesh's prisms (MESH SHELL).
     - PNG (real deflate: fixed Huffman codes + LZ77; 8- and 16-bit), PPM, PFM writers; contact
       sheets with a built-in 3x5 bitmap font for captions.
     - Strict readers: PNG (every colour type and bit depth, palettes with tRNS, Adam7
       interlacing, stored / fixed / dynamic Huffman deflate blocks, all five row filters), PGM and
       PPM (ASCII and binary, maxval up to 65535), PFM (grey and colour, either byte order).
       Samples come back unscaled (sr_picture) and sr_picture_channel turns one channel into
       floats in [0, 1]:
           sr_picture pic;  float *h;
           if (sr_read_image("height.png", NULL, &pic) != SR_OK) ...;   // sr_result_string(r)
           h = malloc(sizeof(float) * pic.width * pic.height);
           sr_picture_channel(&pic, 0, h);  sr_picture_free(&pic);

   HOW TO USE (in ten lines)
       #define SR_IMPLEMENTATION          // in exactly one C or C++ file, followed by
       ...  #include "render.h"           // (in every file that uses it)
       sr_framebuffer fb;  sr_camera cam;  sr_draw_desc d;  float eye[3] = {0, 0, 3}, at[3] = {0, 0, 0};
       sr_framebuffer_create(&fb, 512, 512, NULL);
       sr_framebuffer_clear(&fb, NULL, 1.0f);                        // NULL colour = black, alpha 1
       sr_camera_look_at(&cam, eye, at, NULL, 45.0f, 1.0f, 0.1f, 100.0f); // NULL up = +y
       sr_draw_desc_default(&d);  d.positions = pos; d.vertex_count = nv; d.indices = idx; d.triangle_count = nt;
       sr_draw_mesh(&fb, &cam, &d);                                  // Phong, a default head light
       sr_write_framebuffer_png(&fb, "out.png", 0);
       sr_framebuffer_free(&fb);

   OPTIONS
     Compile time: SR_STATIC (all functions static), SR_MALLOC(sz)/SR_FREE(p) (both or neither).
     Run time: sr_draw_desc, sr_relief_desc, sr_terrain_desc, sr_volume_desc, sr_shell_desc,
     sr_mesh_shell_desc. Call the matching
     *_default() first; zero fields then mean "default" where the field comment says so.

   MEMORY
     The framebuffer owns its arrays (allocated through the allocator given to
     sr_framebuffer_create and kept in fb->allocator): colour, depth, and 12 bytes per pixel of
     scratch for the deferred shading. sr_draw_mesh also needs about 40 bytes per vertex of
     scratch, which it allocates through the same allocator the first time and keeps in the
     framebuffer (grown when a bigger mesh comes) until sr_framebuffer_free. Encoders return
     buffers that must be released with sr_free(allocator, p). Readers allocate the picture's
     samples (2 bytes each, 4 for PFM) through the given allocator, kept in pic.allocator for
     sr_picture_free; while decoding a PNG they also hold its compressed data and its filtered
     rows (about one more byte per sample) and free them before returning. sr_read_image reads
     the whole file into memory first.

   ERRORS
     Functions return sr_result (SR_OK = 0); sr_result_string() names it. Invalid arguments give
     SR_ERR_INVALID_ARGUMENT and leave the framebuffer untouched; among them every draw's camera
     (the setters return void, so each draw checks it): a NaN or infinite eye, target, field of
     view, aspect or matrix, eye == target, a field of view (or ortho half height) or aspect that
     is not positive; a NaN or infinite vertex, model matrix, relief frame, terrain origin,
     spacing, step or height scale, volume box or step. SR_ERR_NOT_FINITE: finite input whose
     transform is not (a vertex at 3e38 overflows the camera's matrix; a terrain whose heights
     times height_scale overflow); nothing is drawn. No float becomes an int unchecked: NaN
     colours write 0, NaN texture coordinates sample the first texel. Readers never crash on bad
     data and hold no memory after a failure: SR_ERR_TRUNCATED (the data ends early),
     SR_ERR_CORRUPT (a malformed header, chunk order, deflate stream, filter type, palette index,
     a sample above maxval, a NaN or infinity in a PFM), SR_ERR_CHECKSUM (any chunk's CRC-32, or
     the Adler-32), SR_ERR_UNSUPPORTED (not one of the formats; a PNG with an unknown critical
     chunk or a zlib preset dictionary), SR_ERR_TOO_LARGE (past the limits below),
     SR_ERR_OUT_OF_MEMORY, SR_ERR_IO. The readers are stricter than libpng on purpose: the CRC
     of every chunk, ancillary ones too, is checked, so that a damaged file is reported rather
     than half read. They are lenient where libpng is: bytes after the zlib stream and chunks
     after IEND are ignored.

   SHELL (sr_draw_shell: the terrain driver of texel.h's grass, but it knows no texel)
     The layer lies between the ground z = h(x, y) (bilinear in the heights, z up) and
     `thickness` above it, over tiles_x x tiles_y square tiles of side `tile`. A world point
     (x, y, z) maps to its tile (i, j) and to the tile frame (frac((x - ox) / tile), frac((y -
     oy) / tile), (z - h) / tile): a vertical shear, so that content stays upright on slopes
     (blades grow up, not along the normal) and a tile's content tiles seamlessly across slope
     changes. Each ray is clipped to the layer's box; above the layer it jumps to where the layer
     could begin (the height field's slope bound: 1.5 x the largest sample difference per
     spacing); inside it calls sample() with the point and the ray in the tile frame and the
     pixel's footprint (distance x pixel angle, or the orthographic pixel size, in tile units),
     and steps by the sample's own step (its level of detail) or skips the empty span it reports,
     cut at the tile's border (1/4096 of a tile past it), since the next tile's content may differ.
     A step of extinction sigma has opacity 1 - exp(-sigma step) and is composited front to back;
     the ray ends on the ground (Lambert with the ground's normal), on the depth already in the
     framebuffer, or when the opacity reaches termination. Shading: the sample's tangent and
     normal are turned back to the world (the shear's inverse), Kajiya-Kay with the tangent
     (diffuse sin(T, L), specular (T.L T.V' + sin sin)^shininess times material.specular times
     sample->specular), or two-sided Lambert + Blinn with the normal, or isotropic; light 0's
     diffuse and specular are scaled by sample->light (the content's self-shadowing, which only
     it can know); ambient is not. The ground casts no shadow on the layer. Colour composites
     over the framebuffer; depth is written where the opacity reaches depth_threshold.
     Memory: none allocated. Errors: SR_ERR_INVALID_ARGUMENT for a NULL pointer or sample, tile
     <= 0, no tiles, a layer wider than 1e30, a negative or NaN thickness, a NaN or infinite
     origin, fewer than 2 x 2 heights, a spacing <= 0, a NaN or infinite height; SR_CANCELLED when progress returns nonzero (the rows drawn so far stay).
     Thread safety: sample() is called from the calling thread only, in pixel order, so its
     user data may cache per tile. Limits: the tiles and heights need not cover the same area
     (heights clamp at their border).

   MESH SHELL (sr_draw_mesh_shell: the same layer over a triangle mesh; it knows no texel either)
     Each triangle swept `height` along its unit vertex normals is a prism, split into three
     tetrahedra by the rule texel.h's tvt_shell_prism_tets documents (the side face over edge
     (i, j), i < j, cut from i to j's offset copy), so that shared faces match and the map is
     continuous; in each tetrahedron the frame (u, v, w depth) is the affine map of its corners'
     (u, v from the vertices, w 0 on the mesh and 1 on the outer surface). A ray finds where it
     enters the shell (the nearest boundary face it crosses inward: outer surface, inner surface
     when see_through, or an open border or chart seam) with a BVH over the boundary faces,
     then walks tetrahedron to tetrahedron through their shared faces, calling sample() at the
     content's own steps exactly as sr_draw_shell does (tile = (floor u, floor v), p = (frac u,
     frac v, w depth), dir the ray's image, unit; footprint = the pixel's width times the
     prism's frame units per world unit, sqrt(uv area / area); empty spans cut at the tile's
     border). Leaving through the outer surface or a border it looks for the next entry; the
     mesh itself is opaque ground (Lambert with the interpolated normals, two-sided) unless
     see_through. Tangents return to the world by the inverse map, normals by its transpose;
     shading, compositing and depth are sr_draw_shell's, except that the mesh shadows the
     layer under its horizon: light 0 is scaled by clamp(5 n.L + 0.5, 0, 1), n the unit
     gradient of w (full light above 0.1, none below -0.1; a sphere's night side stays dark).
     Memory: 3 tetrahedra per triangle (172 bytes each), the boundary faces (68 bytes each) and
     their BVH (32 bytes per node, 2 per face), through `allocator`, built by each call and freed
     before it returns; building them sorts 16 bytes per tetrahedron face. Errors: SR_ERR_INVALID_ARGUMENT for a NULL pointer or sample, fewer than 3
     vertices or no triangle, more than 2^30 vertices or 2^31 / 12 triangles, a NaN or infinite
     position, normal or uv, a zero normal, an index out of range or repeated, a triangle of zero
     area in the world or in uv, a singular tetrahedron, height <= 0 or depth < 0 or not finite;
     SR_ERR_OUT_OF_MEMORY; SR_CANCELLED (rows drawn so far stay). A folded tetrahedron (its map
     turns orientation against its prism's: texel.h's tvt_build_shell finds the same ones) or a
     nearly folded one (its map's gain, the Frobenius norm, over 16 sqrt 3 times the prism's,
     the larger of sqrt(uv area / area) and depth / height) is crossed without sampling: near a
     fold the gain is unbounded (steps would shrink to nothing) and the content would overlap
     its neighbours'; the mesh under it still stops rays. Thread safety: as sr_draw_shell.
     Limits: the camera must be outside the shell (a ray starts at its first entry); a ray walks
     at most 16384 tetrahedra and takes at most 16384 samples (the project's scenes take under
     500; a shell far taller than its triangles, whose prisms are needles, took 200000), and ends
     where a folded neighbour leaves it no exit; faces shared
     by more than two tetrahedra are walls the walk leaves by, like borders.

   THREAD SAFETY
     No global state. Different framebuffers may be drawn from different threads at once.

   DETERMINISM
     The same scene gives the same bytes on every run of the same build (no threads, no random
     numbers; ties in the depth test are won by the first fragment drawn).

   PERFORMANCE
     One thread. 1024 x 1024 per-pixel Phong with back-face culling (bench/bench_raster), on the
     2-core virtual machine this was written on: the 70k-triangle Stanford bunny in about 20 ms a
     frame, a 1M-triangle sphere in about 69 ms; Mesa llvmpipe on one thread with a GLSL Phong
     shader took about 26 ms and 136 ms. With few large triangles the balance turns: llvmpipe
     shades 8 pixels per instruction, so a sphere of a few hundred triangles filling the frame is
     about twice as fast there. Each draw shades every covered pixel once, whatever the
     overdraw. The ray marchers are plain per-pixel loops: use them at preview sizes. An 800 x 600
     relief-mapped cube (6 quads of 512^2 and 384^2 maps, 10 + 5 search steps, a shadow search
     per pixel) takes about 115 ms; llvmpipe on one thread with the same GLSL search about 93 ms
     (bench/bench_relief).

   LIMITS
     Framebuffers up to 16384 x 16384. Perspective cameras need 0 < znear < zfar. The terrain
     marcher takes at most 65536 steps a ray (a longer box lengthens the step); a marcher's ray
     ends where its step no longer moves it (a step under the ulp of its distance). Up to 2^31 - 1
     triangles per draw. Vertices must be finite (checked). One draw is opaque (no blending);
     volumes blend over what is in the framebuffer. A curved relief quad (curvature_u / _v) is
     the tangent plane of a convex bend, approximated by a parabola (for a cylinder cut into
     16 quads the bend's error at a quad's edge is 0.02% of the radius): its shadow rays use the
     flat frame, and its shading normal is tilted by the bend's slope. Read images up to 32768 on a side and 2^28
     samples (width x height x channels). PNG ancillary chunks are skipped, so gamma, colour
     profiles and a grey / RGB tRNS colour key are not applied: samples are as stored (height
     maps want exactly that); a palette's tRNS does become an alpha channel.
     The pixels do not depend on the compiler's FMA contraction (dialect, C or C++,
     -ffp-contract): the implementation turns it off for its own code and restores the user's
     setting after it, except under clang's -ffp-contract=fast, which ignores that pragma (edge
     pixels and shades may then differ).

   REFERENCES
     Pineda, "A parallel algorithm for polygon rasterization", SIGGRAPH 1988 (edge functions).
     Blinn & Newell, "Clipping using homogeneous coordinates", SIGGRAPH 1978.
     Policarpo, Oliveira & Comba, "Real-time relief mapping on arbitrary polygonal surfaces", I3D 2005.
     Kajiya & Kay, "Rendering fur with three dimensional textures", SIGGRAPH 1989.
     Porumbescu, Budge, Feng & Joy, "Shell maps", SIGGRAPH 2005 (prisms split into tetrahedra).
     Levoy, "Display of surfaces from volume data", IEEE CG&A 1988 (front-to-back compositing).
     RFC 1950 / 1951 (zlib, deflate), PNG specification (ISO/IEC 15948).
*/
#ifndef SR_RENDER_H
#define SR_RENDER_H

#include <stddef.h>
#include <stdint.h>

#ifdef SR_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define SRDEF static __attribute__((unused))
#else
#define SRDEF static
#endif
#else
#define SRDEF extern
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ============================================================================================
   Declarations
   ============================================================================================ */

typedef enum sr_result {
    SR_OK = 0,
    SR_ERR_INVALID_ARGUMENT, /* NULL pointer, bad size, index out of range, non-finite input */
    SR_ERR_OUT_OF_MEMORY,    /* the allocator returned NULL */
    SR_ERR_IO,               /* fopen / fwrite / fclose failed */
    SR_ERR_TOO_LARGE,        /* sizes past the documented limits */
    SR_ERR_TRUNCATED,        /* readers: the data ends before the image does */
    SR_ERR_CORRUPT,          /* readers: a malformed header, chunk, deflate stream or sample */
    SR_ERR_CHECKSUM,         /* readers: a PNG chunk's CRC-32 or the zlib stream's Adler-32 is wrong */
    SR_ERR_UNSUPPORTED,      /* readers: not a PNG / PNM / PFM file, or a feature this reader lacks */
    SR_CANCELLED,            /* a progress callback returned nonzero */
    SR_ERR_NOT_FINITE        /* finite input whose transform is not (a vertex near FLT_MAX overflows) */
} sr_result;

/* alloc returns NULL on failure; free accepts NULL. user is passed back unchanged. */
typedef struct sr_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} sr_allocator;

typedef struct sr_framebuffer {
    int width, height;
    float *color;      /* 4 floats (RGBA, linear, 0..1) per pixel, row 0 at the top */
    float *depth;      /* 1 float per pixel, 0 = near plane, 1 = far plane */
    uint32_t *tri_id;  /* scratch for sr_draw_mesh: triangle per pixel (UINT32_MAX = none) */
    float *bary;       /* scratch for sr_draw_mesh: 2 perspective-correct barycentrics per pixel */
    void *scratch;     /* scratch for sr_draw_mesh: transformed vertices, grown as needed and kept */
    size_t scratch_size;
    sr_allocator allocator;
} sr_framebuffer;

typedef struct sr_camera {
    float view[16], proj[16], viewproj[16]; /* column-major, GL conventions */
    float eye[3], forward[3], right[3], up[3];
    float tan_half_fovy;  /* perspective */
    float half_height;    /* orthographic: half the view height in world units */
    float aspect, znear, zfar;
    int orthographic;
} sr_camera;

typedef enum sr_light_type { SR_LIGHT_DIRECTIONAL = 0, SR_LIGHT_POINT = 1 } sr_light_type;

typedef struct sr_light {
    sr_light_type type;
    float vector[3];   /* directional: direction TOWARD the light (need not be unit); point: position */
    float ambient[3], diffuse[3], specular[3];
} sr_light;

typedef struct sr_material {
    float ambient[3], diffuse[3], specular[3], emission[3];
    float shininess;   /* Blinn exponent (GL_SHININESS) */
} sr_material;

typedef enum sr_shading {
    SR_SHADE_PHONG = 0,   /* per-pixel lighting with interpolated normals */
    SR_SHADE_GOURAUD,     /* lighting per vertex, colours interpolated */
    SR_SHADE_FLAT,        /* lighting per triangle (face normal at the centroid) */
    SR_SHADE_UNLIT,       /* vertex colour or material diffuse, no lighting */
    SR_SHADE_COUNT        /* no depth test: adds 1 to red for a front-facing fragment, to green for a back-facing one */
} sr_shading;

typedef enum sr_cull { SR_CULL_NONE = 0, SR_CULL_BACK, SR_CULL_FRONT } sr_cull;

/* A float image (maps): row-major, channels per texel, texel (x,y) centred at UV
   ((x+0.5)/width, (y+0.5)/height). */
typedef struct sr_image {
    int width, height, channels;
    const float *data;
    int wrap;          /* 0: clamp to edge, 1: repeat */
} sr_image;

/* What a fragment callback sees. */
typedef struct sr_fragment {
    int x, y;                 /* pixel */
    uint32_t triangle;        /* index of the triangle in the draw */
    int front_facing;
    float bary[3];            /* perspective-correct barycentrics of the triangle's 3 vertices */
    float position[3];        /* world space */
    float normal[3];          /* world space, unit, flipped toward the viewer on back faces */
    float uv[2];              /* 0,0 without uvs */
    float color[3];           /* interpolated vertex colour, or material diffuse */
} sr_fragment;

typedef struct sr_draw_desc {
    const float *positions;   /* 3 per vertex */
    size_t vertex_count;
    const uint32_t *indices;  /* 3 per triangle, counter-clockwise front faces */
    size_t triangle_count;
    const float *normals;     /* 3 per vertex, or NULL: flat shading uses face normals, others use
                                 face normals per pixel as well (call sr_compute_vertex_normals) */
    const float *colors;      /* 3 per vertex (replace ambient and diffuse material), or NULL */
    const float *uvs;         /* 2 per vertex, or NULL */
    const float *model;       /* 16 floats column-major model-to-world, or NULL = identity */
    sr_shading shading;
    sr_cull cull;
    int no_depth_test;        /* nonzero: every fragment passes (still writes depth) */
    int no_depth_write;
    const sr_light *lights;   /* NULL or light_count == 0: one white directional head light */
    int light_count;
    sr_material material;
    const sr_image *normal_map; /* object-space normals (3 channels, -1..1) looked up at the uvs */
    int wireframe;              /* nonzero: draw triangle edges over the shading (not on triangles
                                   cut by the near/far plane or the guard band), faded out on
                                   triangles whose edges average under 10 pixels (20 wire half
                                   widths; none under 5: see sr__wire_alpha), so that a dense
                                   mesh is not solid wire */
    float wire_color[3];
    float wire_width;           /* pixels, 0 = 1 */
    /* optional: replaces lighting; rgb receives the colour */
    void (*fragment)(void *user, const sr_fragment *frag, float rgb[3]);
    void *fragment_user;
} sr_draw_desc;

/* Relief mapping: a height map over the quad origin + s*axis_u + t*axis_v, s,t in [0,1]; the
   quad is the top surface and the map's value d in [0,1] is depth below it along -n, where
   n = normalize(axis_u x axis_v), scaled by depth_scale world units. (s,t) are the map's UV. */
typedef struct sr_relief_desc {
    float origin[3], axis_u[3], axis_v[3];
    float depth_scale;
    sr_image depth;           /* 1 channel, 0 = on the quad, 1 = deepest */
    const sr_image *albedo;   /* 3 channels, or NULL = material diffuse */
    const sr_image *normal_map; /* tangent space (x along u, y along v, z along n), or NULL = from depth */
    int linear_steps, binary_steps; /* 0 = 10 and 5 (the paper's values) */
    int shadows;              /* nonzero: shadow ray toward each light through the height field */
    const sr_light *lights; int light_count;
    sr_material material;
    /* Added later; zero keeps the behaviour of the fields above. */
    int shadow_search;        /* with shadows: 0 = march up from the hit (2 x linear_steps, bias 0.02);
                                 1 = Policarpo's test: the linear + binary search down the light ray
                                 from where it enters the top plane; shadowed if it stops above the
                                 hit by more than shadow_bias */
    float shadow_bias;        /* map depth, 0 = 0.02 */
    float shadow_light;       /* share of a light's diffuse + specular kept in shadow, 0 = none */
    float curvature_u, curvature_v; /* >= 0, 1/radius (world) of the surface's bend along u and v:
                                 nonzero gives correct silhouettes on curved surfaces (see below) */
} sr_relief_desc;

/* Terrain: heights[y*width+x] at world (origin_x + x*spacing, base_y + h*height_scale,
   origin_z + y*spacing), y up. Bilinear between samples. */
typedef struct sr_terrain_desc {
    const float *heights;
    int width, height;
    float origin_x, origin_z, base_y, spacing, height_scale;
    float step;               /* march step in world units, 0 = spacing / 2 */
    const float *colors;      /* 3 per sample (bilinear between samples), or NULL = material diffuse */
    const sr_light *lights; int light_count;
    sr_material material;
} sr_terrain_desc;

typedef enum sr_volume_direction {
    SR_VOLUME_NONE = 0,       /* isotropic: diffuse = 1 */
    SR_VOLUME_NORMAL,         /* Lambert with the returned normal (two-sided) */
    SR_VOLUME_TANGENT         /* Kajiya-Kay with the returned fibre tangent */
} sr_volume_direction;

typedef struct sr_volume_desc {
    float box_min[3], box_max[3];
    float (*density)(void *user, const float p[3]);                 /* extinction per world unit, >= 0 */
    void (*shade)(void *user, const float p[3], float rgb[3], float dir[3]); /* NULL = material diffuse */
    void *user;
    sr_volume_direction direction;
    float step;               /* world units, 0 = box diagonal / 256 */
    float shadow_step;        /* 0 = 2 * step */
    int shadows;              /* nonzero: shadow ray toward each light */
    float depth_threshold;    /* opacity at which depth is written, 0 = 0.5 */
    float termination;        /* opacity for early termination, 0 = 0.995 */
    const sr_light *lights; int light_count;
    sr_material material;
} sr_volume_desc;

/* A volumetric layer over a height field (sr_draw_shell), z up: heights[j * nx + i] at
   (origin[0] + i spacing, origin[1] + j spacing), bilinear between samples. The layer, from the
   ground to `thickness` above it, is cut into square tiles of side `tile` starting at origin,
   and its content comes from `sample` in a tile's own frame (see sr_shell_query). */
typedef struct sr_shell_query {
    int tile_x, tile_y;       /* the tile, 0..tiles_x - 1, 0..tiles_y - 1 */
    float p[3];               /* the point in tile units: x, y in [0, 1) across the tile, z the
                                 height above the ground (the frame is sheared with the ground) */
    float dir[3];             /* the ray's direction in that frame, unit */
    float footprint;          /* a pixel's width at the point, in tile units (level of detail) */
    int after_empty;          /* nonzero when the ray's previous sample was empty or above the layer */
} sr_shell_query;

typedef struct sr_shell_sample {
    float sigma;              /* extinction per tile unit along dir, >= 0; 0 = empty here */
    float rgb[3];             /* diffuse colour (linear) */
    float specular;           /* weight of the material's specular, 0..1 */
    float tangent[3];         /* fibre tangent in the tile's frame (Kajiya-Kay); zero: Lambert with */
    float normal[3];          /*   the normal (two-sided), both zero: isotropic */
    float light;              /* transmittance toward light 0 inside the layer (self-shadowing), 0..1 */
    float step;               /* tile units to the next sample (the content's level of detail), or,
                                 with sigma 0, how far along dir the content is empty; 0 = 1/256 */
} sr_shell_sample;

typedef struct sr_shell_desc {
    const float *heights;     /* nx * ny heights, rows along x; NULL = flat ground at z = 0 */
    int nx, ny;
    float origin[2], spacing; /* where sample (0, 0) lies, and the sample spacing (world) */
    float tile;               /* tile side (world), > 0 */
    int tiles_x, tiles_y;     /* the layer covers [origin, origin + tiles * tile] */
    float thickness;          /* layer height above the ground (world), 0 = tile */
    void (*sample)(void *user, const sr_shell_query *q, sr_shell_sample *out); /* the content */
    void *user;
    float ground_rgb[3];      /* the ground's diffuse colour, lit by the lights (Lambert) */
    const sr_light *lights; int light_count; /* NULL / 0: one head light; light 0 gets sample->light */
    sr_material material;     /* specular colour and shininess (Kajiya-Kay), emission */
    float termination;        /* opacity at which a ray stops, 0 = 0.99 */
    float depth_threshold;    /* opacity at which depth is written, 0 = 0.5 */
    int (*progress)(void *user, float done); /* per row; nonzero cancels (SR_CANCELLED) */
    void *progress_user;
} sr_shell_desc;

typedef struct sr_shell_stats {
    long covered;             /* pixels whose layer opacity (the ground not counted) reached 0.5 */
    long samples;             /* sample calls, empty ones included */
} sr_shell_stats;

/* A decoded image file (sr_read_image, sr_decode_*). Integer formats (PNG, PGM, PPM) fill
   samples, PFM fills floats; the other pointer is NULL. Release with sr_picture_free. */
typedef struct sr_picture {
    int width, height;
    int channels;       /* 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA; a PNG palette becomes 3 (4 with tRNS) */
    int bit_depth;      /* the file's: PNG 1, 2, 4, 8 or 16 (8 for a palette), PGM the bits of maxval, PFM 32 */
    int max_value;      /* the largest sample value: 2^bit_depth - 1 (PNG), maxval (PGM / PPM), 0 (PFM) */
    uint16_t *samples;  /* width*height*channels, row 0 = the top row, unscaled */
    float *floats;      /* PFM: width*height*channels, row 0 = the file's first row (which PFM shows at the bottom) */
    sr_allocator allocator;
} sr_picture;

/* An 8-bit image for writers and contact sheets: row 0 is the top row. */
typedef struct sr_image8 {
    int width, height, channels; /* channels 1, 3 or 4 */
    uint8_t *pixels;             /* width*height*channels */
} sr_image8;

/* ---- results, memory ---------------------------------------------------------------------- */

/* "SR_OK", "SR_ERR_INVALID_ARGUMENT", ...; "SR_ERR_?" outside the enum. */
SRDEF const char *sr_result_string(sr_result r);
/* Frees memory returned by this library with the given allocator (NULL = SR_FREE). */
SRDEF void sr_free(const sr_allocator *allocator, void *p);

/* ---- framebuffer and camera --------------------------------------------------------------- */

/* width, height in 1..16384. allocator NULL = SR_MALLOC/SR_FREE. Colour cleared to 0, depth to 1. */
SRDEF sr_result sr_framebuffer_create(sr_framebuffer *fb, int width, int height, const sr_allocator *allocator);
SRDEF void sr_framebuffer_free(sr_framebuffer *fb);
/* rgba NULL = (0,0,0,1). */
SRDEF void sr_framebuffer_clear(sr_framebuffer *fb, const float rgba[4], float depth);
/* Converts to 8 bits (round to nearest, clamped), channels 3 or 4, rows top first. */
SRDEF void sr_framebuffer_to_rgb8(const sr_framebuffer *fb, uint8_t *out, int channels);

/* Perspective look-at camera. up NULL = +y (or +z when looking along y). fovy in degrees. */
SRDEF void sr_camera_look_at(sr_camera *cam, const float eye[3], const float target[3], const float up[3],
                             float fovy_degrees, float aspect, float znear, float zfar);
/* Orthographic look-at camera showing half_height world units above and below the centre. */
SRDEF void sr_camera_ortho(sr_camera *cam, const float eye[3], const float target[3], const float up[3],
                           float half_height, float aspect, float znear, float zfar);
/* Ray through the image point (x, y) of a width x height image, in pixels from the top-left corner
   (pixel (i, j) has its centre at x = i + 0.5, y = j + 0.5); dir is unit length. */
SRDEF void sr_camera_ray(const sr_camera *cam, int width, int height, float x, float y,
                         float origin[3], float dir[3]);
/* Window depth (0..1) of a world point; returns 0 when it is behind the eye (perspective). */
SRDEF int sr_camera_depth(const sr_camera *cam, const float p[3], float *depth);

/* ---- rasterizer --------------------------------------------------------------------------- */

/* Defaults: Phong, no culling, depth test on, white material (ambient 0.2, diffuse 0.8,
   specular 0.3, shininess 32), default head light, wire colour black, width 1. */
SRDEF void sr_draw_desc_default(sr_draw_desc *d);
/* Fills a material and a light with the defaults used above. */
SRDEF void sr_material_default(sr_material *m);
SRDEF void sr_light_default(sr_light *l, const float toward_light[3]);
/* Area-weighted vertex normals (unit; zero for unreferenced vertices). out: 3 * vertex_count. */
SRDEF sr_result sr_compute_vertex_normals(const float *positions, size_t vertex_count, const uint32_t *indices,
                                          size_t triangle_count, float *out);
/* Draws a triangle mesh. */
SRDEF sr_result sr_draw_mesh(sr_framebuffer *fb, const sr_camera *cam, const sr_draw_desc *d);

/* Blinn-Phong with the GL fixed-function model: emission + sum over lights of
   la*ma + ld*md*max(N.L,0) + ls*ms*max(N.H,0)^shininess (specular only where N.L > 0).
   P, N world space (N unit), eye the camera position. Used by all renderers here. */
SRDEF void sr_shade_blinn(const sr_material *m, const float diffuse_rgb[3], const sr_light *lights, int light_count,
                          const float P[3], const float N[3], const float eye[3], float rgb[3]);

/* ---- ray marchers ------------------------------------------------------------------------- */

SRDEF void sr_relief_desc_default(sr_relief_desc *d);
/* Intersects one ray with the relief: returns 1 and the hit distance t along dir (unit) and
   (s, t_map, depth) in uvd, or 0 for a miss. */
SRDEF int sr_relief_intersect(const sr_relief_desc *d, const float origin[3], const float dir[3], float *t,
                              float uvd[3]);
/* 1 if the map point uvd (s, t_map, depth) sees a light in direction toward_light (unit, world),
   0 if the height field shadows it, by the test shadow_search selects. */
SRDEF float sr_relief_light_visibility(const sr_relief_desc *d, const float uvd[3], const float toward_light[3]);
SRDEF sr_result sr_draw_relief(sr_framebuffer *fb, const sr_camera *cam, const sr_relief_desc *d);

SRDEF void sr_terrain_desc_default(sr_terrain_desc *d);
SRDEF sr_result sr_draw_terrain(sr_framebuffer *fb, const sr_camera *cam, const sr_terrain_desc *d);

SRDEF void sr_volume_desc_default(sr_volume_desc *d);
SRDEF sr_result sr_draw_volume(sr_framebuffer *fb, const sr_camera *cam, const sr_volume_desc *d);

/* The shell marcher: see sr_shell_desc and the doc block (SHELL). stats may be NULL. */
SRDEF void sr_shell_desc_default(sr_shell_desc *d);
SRDEF sr_result sr_draw_shell(sr_framebuffer *fb, const sr_camera *cam, const sr_shell_desc *d, sr_shell_stats *stats);
/* The ground's height at (x, y) (bilinear, clamped at the borders) and, if grad is not NULL,
   its gradient (dh/dx, dh/dy), as sr_draw_shell sees it. */
SRDEF float sr_shell_height(const sr_shell_desc *d, float x, float y, float grad[2]);

/* A volumetric layer over a triangle mesh (sr_draw_mesh_shell): each triangle swept `height`
   along its unit vertex normals is a prism; the content comes from `sample` in texel space (u, v
   tile coordinates interpolated from the vertices, tiles repeating; w from the mesh to the
   outer surface), with the same query and sample structs as sr_draw_shell: tile_x, tile_y =
   floor(u), floor(v), p = (frac u, frac v, w * depth). See MESH SHELL. */
typedef struct sr_mesh_shell_desc {
    const float *positions;   /* 3 per vertex (world) */
    const float *normals;     /* 3 per vertex: offset directions, not zero (normalised here) */
    const float *uvs;         /* 2 per vertex: tile coordinates */
    size_t vertex_count;
    const uint32_t *indices;  /* 3 per triangle */
    size_t triangle_count;
    float height;             /* shell height along the normals (world), > 0 */
    float depth;              /* the shell's height in the content's frame (tile units), 0 = 1 */
    void (*sample)(void *user, const sr_shell_query *q, sr_shell_sample *out); /* the content */
    void *user;
    float ground_rgb[3];      /* the mesh surface's diffuse colour (Lambert, two-sided) */
    int see_through;          /* 0: the mesh is opaque ground; nonzero: rays cross it (no ground) */
    const sr_light *lights; int light_count; /* NULL / 0: one head light; light 0 gets sample->light */
    sr_material material;     /* specular colour and shininess (Kajiya-Kay), emission */
    float termination;        /* opacity at which a ray stops, 0 = 0.99 */
    float depth_threshold;    /* opacity at which depth is written, 0 = 0.5 */
    const sr_allocator *allocator; /* the prisms' tetrahedra and the boundary's BVH; NULL = malloc */
    int (*progress)(void *user, float done); /* per row; nonzero cancels (SR_CANCELLED) */
    void *progress_user;
} sr_mesh_shell_desc;

SRDEF void sr_mesh_shell_desc_default(sr_mesh_shell_desc *d);
/* The mesh shell marcher: see sr_mesh_shell_desc and the doc block (MESH SHELL). stats may be NULL. */
SRDEF sr_result sr_draw_mesh_shell(sr_framebuffer *fb, const sr_camera *cam, const sr_mesh_shell_desc *d,
                                   sr_shell_stats *stats);

/* ---- images ------------------------------------------------------------------------------- */

/* Encodes 8-bit pixels (channels 1 gray, 3 RGB, 4 RGBA; row stride = width*channels) as PNG in
   memory. flip_y nonzero: the last row goes on top. *out is allocated with allocator (NULL =
   SR_MALLOC), release it with sr_free. */
SRDEF sr_result sr_encode_png(const uint8_t *pixels, int width, int height, int channels, int flip_y,
                              const sr_allocator *allocator, uint8_t **out, size_t *out_size);
SRDEF sr_result sr_write_png(const char *path, const uint8_t *pixels, int width, int height, int channels, int flip_y);
/* Binary PPM (P6) of RGB pixels (channels 3, or 4 with alpha dropped). */
SRDEF sr_result sr_write_ppm(const char *path, const uint8_t *pixels, int width, int height, int channels, int flip_y);
/* PFM of a float map with 1 or 3 channels; memory row 0 is written first, which PFM shows at
   the bottom (the project's map convention). */
SRDEF sr_result sr_write_pfm(const char *path, const float *data, int width, int height, int channels);
/* The framebuffer as an RGB PNG (flip_y as sr_encode_png). */
SRDEF sr_result sr_write_framebuffer_png(const sr_framebuffer *fb, const char *path, int flip_y);
/* 16-bit PNG of samples (channels 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA; host-order uint16_t). */
SRDEF sr_result sr_encode_png16(const uint16_t *samples, int width, int height, int channels, int flip_y,
                                const sr_allocator *allocator, uint8_t **out, size_t *out_size);
SRDEF sr_result sr_write_png16(const char *path, const uint16_t *samples, int width, int height, int channels, int flip_y);

/* Readers. Each fills *out (zeroed first; on failure it holds no memory) with memory from the
   allocator (NULL = SR_MALLOC). sr_decode_png: PNG of every colour type and bit depth, Adam7
   interlaced or not; sr_decode_pnm: P2 / P5 (PGM), P3 / P6 (PPM), maxval up to 65535, and PFM
   (Pf grey, PF colour, either byte order); sr_decode_image picks by the first bytes;
   sr_read_image reads a file (SR_ERR_IO when it cannot). */
SRDEF sr_result sr_decode_png(const uint8_t *data, size_t size, const sr_allocator *allocator, sr_picture *out);
SRDEF sr_result sr_decode_pnm(const uint8_t *data, size_t size, const sr_allocator *allocator, sr_picture *out);
SRDEF sr_result sr_decode_image(const uint8_t *data, size_t size, const sr_allocator *allocator, sr_picture *out);
SRDEF sr_result sr_read_image(const char *path, const sr_allocator *allocator, sr_picture *out);
SRDEF void sr_picture_free(sr_picture *p);
/* One channel as width*height floats into out: sample / max_value (so [0, 1]), or PFM's value. */
SRDEF sr_result sr_picture_channel(const sr_picture *p, int channel, float *out);

/* Draws text with the built-in 3x5 font (letters drawn upper case) at pixel (x, y) = top left,
   each font pixel scale x scale. Characters without a glyph draw as a box. Clipped to the image. */
SRDEF void sr_draw_text(sr_image8 *img, int x, int y, const char *text, int scale, const uint8_t rgb[3]);
/* Places count images (channels 3 or 4) side by side in rows of `columns` (0 = all in one row),
   each with its caption (captions or captions[i] may be NULL) under it, on a white background.
   out->pixels is allocated (RGB) with allocator (NULL = SR_MALLOC); free with sr_free. */
SRDEF sr_result sr_contact_sheet(const sr_image8 *images, const char *const *captions, int count, int columns,
                                 const sr_allocator *allocator, sr_image8 *out);

#ifdef __cplusplus
}
#endif
#endif /* SR_RENDER_H */

/* ============================================================================================
   Implementation
   ============================================================================================ */
#ifdef SR_IMPLEMENTATION
#ifndef SR_IMPLEMENTATION_DONE
#define SR_IMPLEMENTATION_DONE

#include <math.h>
#include <stdio.h>
#include <string.h>

#if defined(SR_MALLOC) && defined(SR_FREE)
/* both given */
#elif !defined(SR_MALLOC) && !defined(SR_FREE)
#include <stdlib.h>
#define SR_MALLOC(sz) malloc(sz)
#define SR_FREE(p) free(p)
#else
#error "render.h: define both SR_MALLOC and SR_FREE, or neither"
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
   Section: results, allocation, small vector maths
   --------------------------------------------------------------------------------------------- */

#if defined(__GNUC__) || defined(__clang__)
#define SR__INLINE inline __attribute__((always_inline))
#else
#define SR__INLINE inline
#endif
#define SR__NO_ID 0xFFFFFFFFu
#define SR__BACK_BIT 0x80000000u
#define SR__MAX_SIZE 16384

SRDEF const char *sr_result_string(sr_result r)
{
    switch (r) {
    case SR_OK: return "SR_OK";
    case SR_ERR_INVALID_ARGUMENT: return "SR_ERR_INVALID_ARGUMENT";
    case SR_ERR_OUT_OF_MEMORY: return "SR_ERR_OUT_OF_MEMORY";
    case SR_ERR_IO: return "SR_ERR_IO";
    case SR_ERR_TOO_LARGE: return "SR_ERR_TOO_LARGE";
    case SR_ERR_TRUNCATED: return "SR_ERR_TRUNCATED";
    case SR_ERR_CORRUPT: return "SR_ERR_CORRUPT";
    case SR_ERR_CHECKSUM: return "SR_ERR_CHECKSUM";
    case SR_ERR_UNSUPPORTED: return "SR_ERR_UNSUPPORTED";
    case SR_CANCELLED: return "SR_CANCELLED";
    case SR_ERR_NOT_FINITE: return "SR_ERR_NOT_FINITE";
    }
    return "SR_ERR_?";
}

static void *sr__default_alloc(void *user, size_t size) { (void)user; return SR_MALLOC(size); }
static void sr__default_free(void *user, void *ptr) { (void)user; SR_FREE(ptr); }

static sr_allocator sr__resolve_allocator(const sr_allocator *a)
{
    sr_allocator r;
    if (a && a->alloc && a->free) return *a;
    r.alloc = sr__default_alloc;
    r.free = sr__default_free;
    r.user = NULL;
    return r;
}

static void *sr__alloc(const sr_allocator *a, size_t size) { return a->alloc(a->user, size ? size : 1); }

SRDEF void sr_free(const sr_allocator *allocator, void *p)
{
    sr_allocator a = sr__resolve_allocator(allocator);
    if (p) a.free(a.user, p);
}

static SR__INLINE float sr__dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static SR__INLINE void sr__sub(const float a[3], const float b[3], float r[3])
{
    r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2];
}
static SR__INLINE void sr__cross(const float a[3], const float b[3], float r[3])
{
    float x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    r[0] = x; r[1] = y; r[2] = z;
}
static SR__INLINE float sr__normalize(float v[3])
{
    float l = sqrtf(sr__dot(v, v));
    if (l > 0.0f) { float s = 1.0f / l; v[0] *= s; v[1] *= s; v[2] *= s; }
    return l;
}
/* NaN gives lo: every float that becomes an int here goes through a clamp first (converting NaN,
   or a float outside int's range, is undefined behaviour) */
static SR__INLINE float sr__clampf(float x, float lo, float hi) { return x > lo ? (x < hi ? x : hi) : lo; }
static int sr__finite3(const float *p) { return p[0] - p[0] == 0.0f && p[1] - p[1] == 0.0f && p[2] - p[2] == 0.0f; }
static int sr__finite_n(const float *p, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!(p[i] - p[i] == 0.0f)) return 0;
    return 1;
}

/* A camera the draws can use: every field finite, a unit forward (eye != target), a positive
   field of view (or half height) and aspect. Not checked by the camera setters (they return void),
   so each draw checks it. */
static int sr__camera_ok(const sr_camera *cam)
{
    float f = cam->forward[0] * cam->forward[0] + cam->forward[1] * cam->forward[1] + cam->forward[2] * cam->forward[2];
    if (!sr__finite_n(cam->view, 16) || !sr__finite_n(cam->proj, 16) || !sr__finite_n(cam->viewproj, 16) ||
        !sr__finite3(cam->eye) || !sr__finite3(cam->right) || !sr__finite3(cam->up) || !(fabsf(f - 1.0f) < 1e-3f))
        return 0;
    if (!(cam->aspect > 0.0f && cam->aspect < 1e30f)) return 0;
    return cam->orthographic ? cam->half_height > 0.0f && cam->half_height < 1e30f
                             : cam->tan_half_fovy > 0.0f && cam->tan_half_fovy < 1e30f;
}

/* r = a * b, column-major 4x4 */
static void sr__mat_mul(const float a[16], const float b[16], float r[16])
{
    float t[16];
    int i, j, k;
    for (j = 0; j < 4; j++)
        for (i = 0; i < 4; i++) {
            float s = 0.0f;
            for (k = 0; k < 4; k++) s += a[k * 4 + i] * b[j * 4 + k];
            t[j * 4 + i] = s;
        }
    memcpy(r, t, sizeof t);
}

static void sr__mat_point(const float m[16], const float p[3], float r[3])
{
    float x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    float y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    float z = m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14];
    r[0] = x; r[1] = y; r[2] = z;
}

/* cofactor matrix of the upper 3x3 = det * inverse transpose: maps normals (renormalised after) */
static void sr__normal_matrix(const float m[16], float n[9])
{
    float a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    float det;
    n[0] = e * i - f * h; n[3] = c * h - b * i; n[6] = b * f - c * e;
    n[1] = f * g - d * i; n[4] = a * i - c * g; n[7] = c * d - a * f;
    n[2] = d * h - e * g; n[5] = b * g - a * h; n[8] = a * e - b * d;
    det = a * n[0] + b * n[1] + c * n[2];
    if (det < 0.0f) { int k; for (k = 0; k < 9; k++) n[k] = -n[k]; }
}
/* n is stored so that world normal = (n0 n1 n2)*x + ... : out_j = sum_k n[j*3+k] * v_k */
static void sr__mat3_vec(const float n[9], const float v[3], float r[3])
{
    float x = n[0] * v[0] + n[3] * v[1] + n[6] * v[2];
    float y = n[1] * v[0] + n[4] * v[1] + n[7] * v[2];
    float z = n[2] * v[0] + n[5] * v[1] + n[8] * v[2];
    r[0] = x; r[1] = y; r[2] = z;
}

/* ---------------------------------------------------------------------------------------------
   Section: framebuffer and camera
   --------------------------------------------------------------------------------------------- */

SRDEF sr_result sr_framebuffer_create(sr_framebuffer *fb, int width, int height, const sr_allocator *allocator)
{
    size_t n;
    sr_allocator a;
    if (!fb) return SR_ERR_INVALID_ARGUMENT;
    memset(fb, 0, sizeof *fb);
    if (width < 1 || height < 1) return SR_ERR_INVALID_ARGUMENT;
    if (width > SR__MAX_SIZE || height > SR__MAX_SIZE) return SR_ERR_TOO_LARGE;
    a = sr__resolve_allocator(allocator);
    n = (size_t)width * (size_t)height;
    fb->color = (float *)sr__alloc(&a, n * 4 * sizeof(float));
    fb->depth = (float *)sr__alloc(&a, n * sizeof(float));
    fb->tri_id = (uint32_t *)sr__alloc(&a, n * sizeof(uint32_t));
    fb->bary = (float *)sr__alloc(&a, n * 2 * sizeof(float));
    fb->allocator = a;
    fb->width = width;
    fb->height = height;
    if (!fb->color || !fb->depth || !fb->tri_id || !fb->bary) {
        sr_framebuffer_free(fb);
        return SR_ERR_OUT_OF_MEMORY;
    }
    memset(fb->tri_id, 0xFF, n * sizeof(uint32_t));
    memset(fb->bary, 0, n * 2 * sizeof(float));
    sr_framebuffer_clear(fb, NULL, 1.0f);
    {
        size_t i;
        for (i = 0; i < n; i++) fb->color[4 * i + 3] = 0.0f;
    }
    return SR_OK;
}

SRDEF void sr_framebuffer_free(sr_framebuffer *fb)
{
    if (!fb) return;
    if (fb->allocator.free) {
        if (fb->color) fb->allocator.free(fb->allocator.user, fb->color);
        if (fb->depth) fb->allocator.free(fb->allocator.user, fb->depth);
        if (fb->tri_id) fb->allocator.free(fb->allocator.user, fb->tri_id);
        if (fb->bary) fb->allocator.free(fb->allocator.user, fb->bary);
        if (fb->scratch) fb->allocator.free(fb->allocator.user, fb->scratch);
    }
    memset(fb, 0, sizeof *fb);
}

SRDEF void sr_framebuffer_clear(sr_framebuffer *fb, const float rgba[4], float depth)
{
    size_t i, n;
    float c[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    if (!fb || !fb->color) return;
    if (rgba) memcpy(c, rgba, sizeof c);
    n = (size_t)fb->width;
    /* fill the first row, then copy it: memcpy streams far faster than a strided store loop */
    for (i = 0; i < n; i++) {
        fb->color[4 * i + 0] = c[0]; fb->color[4 * i + 1] = c[1];
        fb->color[4 * i + 2] = c[2]; fb->color[4 * i + 3] = c[3];
        fb->depth[i] = depth;
    }
    for (i = 1; i < (size_t)fb->height; i++) {
        memcpy(fb->color + 4 * n * i, fb->color, 4 * n * sizeof(float));
        memcpy(fb->depth + n * i, fb->depth, n * sizeof(float));
    }
}

static uint8_t sr__to8(float v)
{
    v = sr__clampf(v, 0.0f, 1.0f) * 255.0f + 0.5f;
    return (uint8_t)(int)v;
}

SRDEF void sr_framebuffer_to_rgb8(const sr_framebuffer *fb, uint8_t *out, int channels)
{
    size_t i, n;
    int c;
    if (!fb || !out || (channels != 3 && channels != 4)) return;
    n = (size_t)fb->width * (size_t)fb->height;
    for (i = 0; i < n; i++)
        for (c = 0; c < channels; c++) out[i * (size_t)channels + (size_t)c] = sr__to8(fb->color[4 * i + (size_t)c]);
}

static void sr__camera_basis(sr_camera *cam, const float eye[3], const float target[3], const float up[3])
{
    float f[3], u[3], r[3], *m = cam->view;
    float upv[3] = {0.0f, 1.0f, 0.0f};
    sr__sub(target, eye, f);
    sr__normalize(f);
    if (up) memcpy(upv, up, sizeof upv);
    sr__cross(f, upv, r);
    if (sr__normalize(r) < 1e-6f) { /* looking along up: pick +z, then +x */
        float alt[3] = {0.0f, 0.0f, 1.0f};
        sr__cross(f, alt, r);
        if (sr__normalize(r) < 1e-6f) { alt[0] = 1.0f; alt[2] = 0.0f; sr__cross(f, alt, r); sr__normalize(r); }
    }
    sr__cross(r, f, u);
    memcpy(cam->eye, eye, sizeof cam->eye);
    memcpy(cam->forward, f, sizeof f);
    memcpy(cam->right, r, sizeof r);
    memcpy(cam->up, u, sizeof u);
    m[0] = r[0]; m[4] = r[1]; m[8] = r[2]; m[12] = -sr__dot(r, eye);
    m[1] = u[0]; m[5] = u[1]; m[9] = u[2]; m[13] = -sr__dot(u, eye);
    m[2] = -f[0]; m[6] = -f[1]; m[10] = -f[2]; m[14] = sr__dot(f, eye);
    m[3] = 0.0f; m[7] = 0.0f; m[11] = 0.0f; m[15] = 1.0f;
}

SRDEF void sr_camera_look_at(sr_camera *cam, const float eye[3], const float target[3], const float up[3],
                             float fovy_degrees, float aspect, float znear, float zfar)
{
    float *p;
    if (!cam || !eye || !target) return;
    memset(cam, 0, sizeof *cam);
    sr__camera_basis(cam, eye, target, up);
    cam->tan_half_fovy = (float)tan((double)fovy_degrees * 3.14159265358979323846 / 360.0);
    cam->aspect = aspect;
    cam->znear = znear;
    cam->zfar = zfar;
    p = cam->proj;
    p[0] = 1.0f / (cam->tan_half_fovy * aspect);
    p[5] = 1.0f / cam->tan_half_fovy;
    p[10] = (zfar + znear) / (znear - zfar);
    p[11] = -1.0f;
    p[14] = 2.0f * zfar * znear / (znear - zfar);
    sr__mat_mul(cam->proj, cam->view, cam->viewproj);
}

SRDEF void sr_camera_ortho(sr_camera *cam, const float eye[3], const float target[3], const float up[3],
                           float half_height, float aspect, float znear, float zfar)
{
    float *p;
    if (!cam || !eye || !target) return;
    memset(cam, 0, sizeof *cam);
    sr__camera_basis(cam, eye, target, up);
    cam->orthographic = 1;
    cam->half_height = half_height;
    cam->aspect = aspect;
    cam->znear = znear;
    cam->zfar = zfar;
    p = cam->proj;
    p[0] = 1.0f / (half_height * aspect);
    p[5] = 1.0f / half_height;
    p[10] = -2.0f / (zfar - znear);
    p[14] = -(zfar + znear) / (zfar - znear);
    p[15] = 1.0f;
    sr__mat_mul(cam->proj, cam->view, cam->viewproj);
}

SRDEF void sr_camera_ray(const sr_camera *cam, int width, int height, float x, float y, float origin[3], float dir[3])
{
    float nx = 2.0f * x / (float)width - 1.0f, ny = 1.0f - 2.0f * y / (float)height;
    int k;
    if (cam->orthographic) {
        float sx = nx * cam->half_height * cam->aspect, sy = ny * cam->half_height;
        for (k = 0; k < 3; k++) {
            origin[k] = cam->eye[k] + cam->right[k] * sx + cam->up[k] * sy;
            dir[k] = cam->forward[k];
        }
    } else {
        float sx = nx * cam->tan_half_fovy * cam->aspect, sy = ny * cam->tan_half_fovy;
        for (k = 0; k < 3; k++) {
            origin[k] = cam->eye[k];
            dir[k] = cam->forward[k] + cam->right[k] * sx + cam->up[k] * sy;
        }
        sr__normalize(dir);
    }
}

SRDEF int sr_camera_depth(const sr_camera *cam, const float p[3], float *depth)
{
    const float *m = cam->viewproj;
    float z = m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14];
    float w = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    if (w <= 0.0f) return 0;
    *depth = 0.5f * z / w + 0.5f;
    return 1;
}

/* ---------------------------------------------------------------------------------------------
   Section: lighting (GL fixed-function model)
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_material_default(sr_material *m)
{
    int k;
    memset(m, 0, sizeof *m);
    for (k = 0; k < 3; k++) { m->ambient[k] = 0.8f; m->diffuse[k] = 0.8f; m->specular[k] = 0.3f; }
    m->shininess = 32.0f;
}

SRDEF void sr_light_default(sr_light *l, const float toward_light[3])
{
    int k;
    memset(l, 0, sizeof *l);
    l->type = SR_LIGHT_DIRECTIONAL;
    for (k = 0; k < 3; k++) {
        l->vector[k] = toward_light ? toward_light[k] : (k == 2 ? 1.0f : 0.0f);
        l->ambient[k] = 0.2f; l->diffuse[k] = 1.0f; l->specular[k] = 1.0f;
    }
}

/* unit vector from P toward the light */
static SR__INLINE void sr__light_dir(const sr_light *l, const float P[3], float L[3])
{
    if (l->type == SR_LIGHT_POINT) {
        sr__sub(l->vector, P, L);
        sr__normalize(L);
    } else {
        memcpy(L, l->vector, 3 * sizeof(float));
        if (fabsf(sr__dot(L, L) - 1.0f) > 1e-6f) sr__normalize(L); /* most callers pass unit vectors */
    }
}

/* one light's contribution (ambient always, diffuse+specular scaled by visibility) */
/* the N.H below which the specular term is under 1e-4 (1/40 of an 8-bit step) */
static float sr__spec_cut(const sr_material *m)
{
    return m->shininess > 0.0f ? powf(1e-4f, 1.0f / m->shininess) : 0.0f;
}

static SR__INLINE void sr__shade_light(const sr_material *m, const float kd[3], const float ka[3], const sr_light *l,
                            const float P[3], const float N[3], const float V[3], float visibility, float spec_cut, float rgb[3])
{
    float L[3], H[3], ndl, spec = 0.0f;
    int k;
    sr__light_dir(l, P, L);
    ndl = sr__dot(N, L);
    if (ndl > 0.0f) {
        float hh, nh;
        H[0] = L[0] + V[0]; H[1] = L[1] + V[1]; H[2] = L[2] + V[2];
        hh = sr__dot(H, H);
        nh = sr__dot(N, H);
        /* (N.H/|H|)^s computed as ((N.H)^2/|H|^2)^(s/2), no square root; skipped below spec_cut
           (computed once per material), where it is under 1e-4 */
        if (nh > 0.0f && nh * nh > spec_cut * spec_cut * hh) spec = powf(nh * nh / hh, 0.5f * m->shininess);
    } else {
        ndl = 0.0f;
    }
    for (k = 0; k < 3; k++)
        rgb[k] += l->ambient[k] * ka[k] + visibility * (l->diffuse[k] * kd[k] * ndl + l->specular[k] * m->specular[k] * spec);
}

static SR__INLINE void sr__view_dir(const float eye[3], const float P[3], float V[3])
{
    sr__sub(eye, P, V);
    sr__normalize(V);
}

SRDEF void sr_shade_blinn(const sr_material *m, const float diffuse_rgb[3], const sr_light *lights, int light_count,
                          const float P[3], const float N[3], const float eye[3], float rgb[3])
{
    float V[3];
    const float *kd = diffuse_rgb ? diffuse_rgb : m->diffuse, *ka = diffuse_rgb ? diffuse_rgb : m->ambient;
    int i;
    sr__view_dir(eye, P, V);
    rgb[0] = m->emission[0]; rgb[1] = m->emission[1]; rgb[2] = m->emission[2];
    for (i = 0; i < light_count; i++) sr__shade_light(m, kd, ka, &lights[i], P, N, V, 1.0f, sr__spec_cut(m), rgb);
}

/* the light list of a draw: the caller's, or a white head light */
static const sr_light *sr__lights(const sr_light *lights, int count, const sr_camera *cam, sr_light *head, int *n)
{
    float toward[3];
    if (lights && count > 0) { *n = count; return lights; }
    toward[0] = -cam->forward[0]; toward[1] = -cam->forward[1]; toward[2] = -cam->forward[2];
    sr_light_default(head, toward);
    *n = 1;
    return head;
}

/* bilinear lookup of up to 4 channels; texel centres at (i+0.5)/w */
static void sr__sample(const sr_image *img, float u, float v, float *out)
{
    float x = sr__clampf(u * (float)img->width - 0.5f, -1e9f, 1e9f), y = sr__clampf(v * (float)img->height - 0.5f, -1e9f, 1e9f);
    float fx = floorf(x), fy = floorf(y), ax = x - fx, ay = y - fy;
    int x0 = (int)fx, y0 = (int)fy, x1 = x0 + 1, y1 = y0 + 1, c, ch = img->channels;
    const float *d = img->data;
    if (img->wrap) {
        x0 %= img->width; if (x0 < 0) x0 += img->width;
        y0 %= img->height; if (y0 < 0) y0 += img->height;
        x1 = (x0 + 1) % img->width; y1 = (y0 + 1) % img->height;
    } else {
        x0 = x0 < 0 ? 0 : (x0 >= img->width ? img->width - 1 : x0);
        x1 = x1 < 0 ? 0 : (x1 >= img->width ? img->width - 1 : x1);
        y0 = y0 < 0 ? 0 : (y0 >= img->height ? img->height - 1 : y0);
        y1 = y1 < 0 ? 0 : (y1 >= img->height ? img->height - 1 : y1);
    }
    for (c = 0; c < ch && c < 4; c++) {
        float a = d[((size_t)y0 * (size_t)img->width + (size_t)x0) * (size_t)ch + (size_t)c];
        float b = d[((size_t)y0 * (size_t)img->width + (size_t)x1) * (size_t)ch + (size_t)c];
        float e = d[((size_t)y1 * (size_t)img->width + (size_t)x0) * (size_t)ch + (size_t)c];
        float f = d[((size_t)y1 * (size_t)img->width + (size_t)x1) * (size_t)ch + (size_t)c];
        out[c] = (a + (b - a) * ax) * (1.0f - ay) + (e + (f - e) * ax) * ay;
    }
}

static int sr__image_ok(const sr_image *img, int min_channels)
{
    return img && img->data && img->width > 0 && img->height > 0 && img->channels >= min_channels && img->channels <= 4;
}

/* ---------------------------------------------------------------------------------------------
   Section: rasterizer - vertex stage
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_draw_desc_default(sr_draw_desc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    sr_material_default(&d->material);
    d->wire_width = 1.0f;
}

SRDEF sr_result sr_compute_vertex_normals(const float *positions, size_t vertex_count, const uint32_t *indices,
                                          size_t triangle_count, float *out)
{
    size_t t, v;
    if (!out || (vertex_count && !positions) || (triangle_count && !indices)) return SR_ERR_INVALID_ARGUMENT;
    for (t = 0; t < 3 * triangle_count; t++)
        if (indices[t] >= vertex_count) return SR_ERR_INVALID_ARGUMENT;
    memset(out, 0, vertex_count * 3 * sizeof(float));
    for (t = 0; t < triangle_count; t++) {
        const uint32_t *i = indices + 3 * t;
        float e1[3], e2[3], n[3];
        int k;
        sr__sub(positions + 3 * (size_t)i[1], positions + 3 * (size_t)i[0], e1);
        sr__sub(positions + 3 * (size_t)i[2], positions + 3 * (size_t)i[0], e2);
        sr__cross(e1, e2, n); /* length = twice the area: area weighting */
        for (k = 0; k < 3; k++) {
            float *o = out + 3 * (size_t)i[k];
            o[0] += n[0]; o[1] += n[1]; o[2] += n[2];
        }
    }
    for (v = 0; v < vertex_count; v++) sr__normalize(out + 3 * v);
    return SR_OK;
}

/* Outcodes: bits 0-5 the view frustum (trivial reject), bits 4-9 what forces clipping
   (near, far, and a guard band of SR__GUARD viewports that keeps fixed-point values small). */
#define SR__OUT_NEAR 16u
#define SR__OUT_FAR 32u
#define SR__CLIP_BITS (16u | 32u | 64u | 128u | 256u | 512u)
#define SR__GUARD 4.0f
#define SR__SUBPIX 256.0f

typedef struct sr__cv {
    float clip[4];
    float sx, sy, sz, invw; /* screen position (pixels, y down), window depth, 1/w */
    int32_t fx, fy;         /* screen position in 1/256 pixel */
    uint32_t code;
} sr__cv;

static uint32_t sr__outcode(const float c[4])
{
    uint32_t k = 0;
    float gw = SR__GUARD * c[3];
    if (c[0] < -c[3]) k |= 1u;
    if (c[0] > c[3]) k |= 2u;
    if (c[1] < -c[3]) k |= 4u;
    if (c[1] > c[3]) k |= 8u;
    if (c[2] < -c[3]) k |= 16u;
    if (c[2] > c[3]) k |= 32u;
    if (c[0] < -gw) k |= 64u;
    if (c[0] > gw) k |= 128u;
    if (c[1] < -gw) k |= 256u;
    if (c[1] > gw) k |= 512u;
    return k;
}

/* perspective divide and viewport; only for vertices inside near plane and guard band */
static void sr__to_screen(sr__cv *v, float w, float h)
{
    float iw = 1.0f / v->clip[3];
    v->invw = iw;
    v->sx = (v->clip[0] * iw * 0.5f + 0.5f) * w;
    v->sy = (0.5f - v->clip[1] * iw * 0.5f) * h;
    v->sz = v->clip[2] * iw * 0.5f + 0.5f;
    /* inside the guard band |sx|, |sy| < 3 x 16384 px (2^24 in 1/256 px); the clamp only keeps a
       w near zero (1/w infinite) from becoming a float-to-int overflow */
    v->fx = (int32_t)floorf(sr__clampf(v->sx * SR__SUBPIX + 0.5f, -67108864.0f, 67108864.0f));
    v->fy = (int32_t)floorf(sr__clampf(v->sy * SR__SUBPIX + 0.5f, -67108864.0f, 67108864.0f));
}

/* ---------------------------------------------------------------------------------------------
   Section: rasterizer - triangle setup and edge-function scan (visibility pass)
   --------------------------------------------------------------------------------------------- */

typedef struct sr__raster {
    sr_framebuffer *fb;
    int count_mode, depth_test, depth_write;
    sr_cull cull;
    int minx, miny, maxx, maxy; /* pixels touched by this draw */
} sr__raster;

/* Rasterizes one screen triangle. B (may be NULL = identity) gives each corner's barycentrics
   with respect to the original triangle `id` (clipped pieces). */
static void sr__raster_tri(sr__raster *r, const sr__cv *v0, const sr__cv *v1, const sr__cv *v2,
                           const float B[3][3], uint32_t id)
{
    sr_framebuffer *fb = r->fb;
    int64_t X0 = v0->fx, Y0 = v0->fy, X1 = v1->fx, Y1 = v1->fy, X2 = v2->fx, Y2 = v2->fy;
    int64_t area = (X1 - X0) * (Y2 - Y0) - (X2 - X0) * (Y1 - Y0);
    int64_t A0, B0, A1, B1, A2, B2, E0, E1, E2, Px, Py, mnx, mny, mxx, mxy;
    int front, swapped = 0, x, y, minx, miny, maxx, maxy;
    float z0, z1, z2, iw0, iw1, iw2, inv_area, dzdx, dzdy, zrow;
    int b0bias, b1bias, b2bias;
    const float *Bc1 = B ? B[1] : NULL, *Bc2 = B ? B[2] : NULL;
    if (area == 0) return;
    front = area < 0; /* counter-clockwise in y-up NDC is clockwise in y-down pixels */
    if ((r->cull == SR_CULL_BACK && !front) || (r->cull == SR_CULL_FRONT && front)) return;
    z0 = v0->sz; iw0 = v0->invw;
    if (area < 0) { /* orient so that the inside has positive edge functions */
        const sr__cv *t = v1; v1 = v2; v2 = t;
        X1 = v1->fx; Y1 = v1->fy; X2 = v2->fx; Y2 = v2->fy;
        area = -area;
        swapped = 1;
        if (B) { Bc1 = B[2]; Bc2 = B[1]; }
    }
    z1 = v1->sz; z2 = v2->sz; iw1 = v1->invw; iw2 = v2->invw;
    /* bounding box of pixel centres (x*256+128) inside [min, max] */
    mnx = X0 < X1 ? (X0 < X2 ? X0 : X2) : (X1 < X2 ? X1 : X2);
    mxx = X0 > X1 ? (X0 > X2 ? X0 : X2) : (X1 > X2 ? X1 : X2);
    mny = Y0 < Y1 ? (Y0 < Y2 ? Y0 : Y2) : (Y1 < Y2 ? Y1 : Y2);
    mxy = Y0 > Y1 ? (Y0 > Y2 ? Y0 : Y2) : (Y1 > Y2 ? Y1 : Y2);
    /* +2^24 keeps the shifted values positive (guard band keeps |coords| < 2^24 / 256 px) */
    minx = (int)(((mnx - 128 + 255) + ((int64_t)1 << 32)) >> 8) - (1 << 24);
    maxx = (int)(((mxx - 128) + ((int64_t)1 << 32)) >> 8) - (1 << 24);
    miny = (int)(((mny - 128 + 255) + ((int64_t)1 << 32)) >> 8) - (1 << 24);
    maxy = (int)(((mxy - 128) + ((int64_t)1 << 32)) >> 8) - (1 << 24);
    if (minx < 0) minx = 0;
    if (miny < 0) miny = 0;
    if (maxx > fb->width - 1) maxx = fb->width - 1;
    if (maxy > fb->height - 1) maxy = fb->height - 1;
    if (minx > maxx || miny > maxy) return;
    /* edge functions: w0 = E12, w1 = E20, w2 = E01; E_ab(p) = (Xb-Xa)(Py-Ya) - (Yb-Ya)(Px-Xa) */
    A0 = Y1 - Y2; B0 = X2 - X1;
    A1 = Y2 - Y0; B1 = X0 - X2;
    A2 = Y0 - Y1; B2 = X1 - X0;
    /* top-left rule: an edge owns its pixels when it is a top edge (dy == 0, dx > 0) or a left
       edge (dy < 0); for other edges E == 0 is outside, done by a bias of -1 (E is integer) */
    b0bias = (A0 > 0 || (A0 == 0 && B0 > 0)) ? 0 : -1;
    b1bias = (A1 > 0 || (A1 == 0 && B1 > 0)) ? 0 : -1;
    b2bias = (A2 > 0 || (A2 == 0 && B2 > 0)) ? 0 : -1;
    Px = (int64_t)minx * 256 + 128;
    Py = (int64_t)miny * 256 + 128;
    E0 = B0 * (Py - Y1) + A0 * (Px - X1);
    E1 = B1 * (Py - Y2) + A1 * (Px - X2);
    E2 = B2 * (Py - Y0) + A2 * (Px - X0);
    inv_area = 1.0f / (float)area;
    dzdx = ((float)A0 * z0 + (float)A1 * z1 + (float)A2 * z2) * 256.0f * inv_area;
    dzdy = ((float)B0 * z0 + (float)B1 * z1 + (float)B2 * z2) * 256.0f * inv_area;
    zrow = (float)(((double)E0 * z0 + (double)E1 * z1 + (double)E2 * z2) / (double)area);
    E0 += b0bias; E1 += b1bias; E2 += b2bias;
    A0 *= 256; A1 *= 256; A2 *= 256; B0 *= 256; B1 *= 256; B2 *= 256;
    if (minx < r->minx) r->minx = minx;
    if (miny < r->miny) r->miny = miny;
    if (maxx > r->maxx) r->maxx = maxx;
    if (maxy > r->maxy) r->maxy = maxy;
    for (y = miny; y <= maxy; y++) {
        int64_t e0 = E0, e1 = E1, e2 = E2;
        size_t row = (size_t)y * (size_t)fb->width;
        for (x = minx; x <= maxx; x++, e0 += A0, e1 += A1, e2 += A2) {
            size_t i;
            float z;
            if ((e0 | e1 | e2) < 0) continue;
            i = row + (size_t)x;
            if (r->count_mode) {
                fb->color[4 * i + (front ? 0 : 1)] += 1.0f;
                continue;
            }
            z = zrow + dzdx * (float)(x - minx);
            if (r->depth_test && !(z < fb->depth[i])) continue;
            if (r->depth_write) fb->depth[i] = z;
            {
                /* perspective-correct barycentrics: screen weights divided by w, renormalised */
                float f0 = (float)e0 * iw0, f1 = (float)e1 * iw1, f2 = (float)e2 * iw2;
                float s = 1.0f / (f0 + f1 + f2), b1, b2;
                f0 *= s; f1 *= s; f2 *= s;
                if (B) {
                    b1 = f0 * B[0][1] + f1 * Bc1[1] + f2 * Bc2[1];
                    b2 = f0 * B[0][2] + f1 * Bc1[2] + f2 * Bc2[2];
                } else if (swapped) {
                    b1 = f2; b2 = f1;
                } else {
                    b1 = f1; b2 = f2;
                }
                fb->tri_id[i] = id | (front ? 0u : SR__BACK_BIT);
                fb->bary[2 * i] = b1;
                fb->bary[2 * i + 1] = b2;
            }
        }
        E0 += B0; E1 += B1; E2 += B2;
        zrow += dzdy;
    }
}

/* Sutherland-Hodgman in clip space against the planes named in `bits`, then a fan. */
static void sr__clip_tri(sr__raster *r, const sr__cv *v[3], uint32_t bits, uint32_t id)
{
    sr__cv poly[2][16];
    float bary[2][16][3];
    int n = 3, cur = 0, p, i, k;
    for (i = 0; i < 3; i++) {
        poly[0][i] = *v[i];
        for (k = 0; k < 3; k++) bary[0][i][k] = (i == k) ? 1.0f : 0.0f;
    }
    for (p = 0; p < 6; p++) {
        uint32_t bit = 16u << p;
        int m = 0, nxt = 1 - cur;
        if (!(bits & bit)) continue;
        for (i = 0; i < n; i++) {
            const sr__cv *a = &poly[cur][i], *b = &poly[cur][(i + 1) % n];
            const float *ba = bary[cur][i], *bb = bary[cur][(i + 1) % n];
            float da, db;
            switch (p) {
            case 0: da = a->clip[2] + a->clip[3]; db = b->clip[2] + b->clip[3]; break;
            case 1: da = a->clip[3] - a->clip[2]; db = b->clip[3] - b->clip[2]; break;
            case 2: da = SR__GUARD * a->clip[3] + a->clip[0]; db = SR__GUARD * b->clip[3] + b->clip[0]; break;
            case 3: da = SR__GUARD * a->clip[3] - a->clip[0]; db = SR__GUARD * b->clip[3] - b->clip[0]; break;
            case 4: da = SR__GUARD * a->clip[3] + a->clip[1]; db = SR__GUARD * b->clip[3] + b->clip[1]; break;
            default: da = SR__GUARD * a->clip[3] - a->clip[1]; db = SR__GUARD * b->clip[3] - b->clip[1]; break;
            }
            if (da >= 0.0f) { poly[nxt][m] = *a; memcpy(bary[nxt][m], ba, sizeof bary[0][0]); m++; }
            if ((da >= 0.0f) != (db >= 0.0f) && m < 15) {
                /* interpolate from the inside vertex so both triangles of a shared edge agree */
                const sr__cv *in = da >= 0.0f ? a : b, *out = da >= 0.0f ? b : a;
                const float *bin = da >= 0.0f ? ba : bb, *bout = da >= 0.0f ? bb : ba;
                float din = da >= 0.0f ? da : db, dout = da >= 0.0f ? db : da;
                float t = din / (din - dout);
                sr__cv *o = &poly[nxt][m];
                for (k = 0; k < 4; k++) o->clip[k] = in->clip[k] + t * (out->clip[k] - in->clip[k]);
                for (k = 0; k < 3; k++) bary[nxt][m][k] = bin[k] + t * (bout[k] - bin[k]);
                m++;
            }
        }
        n = m;
        cur = nxt;
        if (n < 3) return;
    }
    for (i = 0; i < n; i++) {
        if (!(poly[cur][i].clip[3] > 0.0f)) return;
        sr__to_screen(&poly[cur][i], (float)r->fb->width, (float)r->fb->height);
    }
    for (i = 1; i + 1 < n; i++) {
        float B[3][3];
        memcpy(B[0], bary[cur][0], sizeof B[0]);
        memcpy(B[1], bary[cur][i], sizeof B[1]);
        memcpy(B[2], bary[cur][i + 1], sizeof B[2]);
        sr__raster_tri(r, &poly[cur][0], &poly[cur][i], &poly[cur][i + 1], (const float(*)[3])B, id);
    }
}

/* ---------------------------------------------------------------------------------------------
   Section: rasterizer - shading pass and sr_draw_mesh
   --------------------------------------------------------------------------------------------- */

typedef struct sr__shader {
    const sr_draw_desc *d;
    const sr_camera *cam;
    const sr__cv *cv;
    const float *wpos, *wnrm; /* world positions and normals (the inputs when model is NULL) */
    const float *gouraud;     /* 6 floats per vertex: lit colour front, back */
    const sr_light *lights;
    int light_count;
    float nmat[9];
    int has_model;
    float spec_cut;
} sr__shader;

static void sr__face_normal(const float *p0, const float *p1, const float *p2, float n[3])
{
    float e1[3], e2[3];
    sr__sub(p1, p0, e1);
    sr__sub(p2, p0, e2);
    sr__cross(e1, e2, n);
    sr__normalize(n);
}

static void sr__fill_fragment(const sr__shader *s, int x, int y, uint32_t id, float b1, float b2, sr_fragment *f)
{
    const sr_draw_desc *d = s->d;
    const uint32_t *idx = d->indices + 3 * (size_t)(id & ~SR__BACK_BIT);
    size_t i0 = idx[0], i1 = idx[1], i2 = idx[2];
    float b0 = 1.0f - b1 - b2;
    int k;
    f->x = x; f->y = y;
    f->triangle = id & ~SR__BACK_BIT;
    f->front_facing = (id & SR__BACK_BIT) == 0;
    f->bary[0] = b0; f->bary[1] = b1; f->bary[2] = b2;
    for (k = 0; k < 3; k++)
        f->position[k] = b0 * s->wpos[3 * i0 + k] + b1 * s->wpos[3 * i1 + k] + b2 * s->wpos[3 * i2 + k];
    if (d->normal_map && d->uvs) {
        float uv[2], n[4] = {0.0f, 0.0f, 1.0f, 0.0f};
        for (k = 0; k < 2; k++) uv[k] = b0 * d->uvs[2 * i0 + k] + b1 * d->uvs[2 * i1 + k] + b2 * d->uvs[2 * i2 + k];
        sr__sample(d->normal_map, uv[0], uv[1], n);
        if (s->has_model) sr__mat3_vec(s->nmat, n, f->normal);
        else memcpy(f->normal, n, 3 * sizeof(float));
    } else if (s->wnrm && d->shading != SR_SHADE_FLAT) {
        for (k = 0; k < 3; k++)
            f->normal[k] = b0 * s->wnrm[3 * i0 + k] + b1 * s->wnrm[3 * i1 + k] + b2 * s->wnrm[3 * i2 + k];
    } else {
        sr__face_normal(s->wpos + 3 * i0, s->wpos + 3 * i1, s->wpos + 3 * i2, f->normal);
    }
    sr__normalize(f->normal);
    if (!f->front_facing) { f->normal[0] = -f->normal[0]; f->normal[1] = -f->normal[1]; f->normal[2] = -f->normal[2]; }
    if (d->uvs) {
        for (k = 0; k < 2; k++) f->uv[k] = b0 * d->uvs[2 * i0 + k] + b1 * d->uvs[2 * i1 + k] + b2 * d->uvs[2 * i2 + k];
    } else {
        f->uv[0] = f->uv[1] = 0.0f;
    }
    if (d->colors) {
        for (k = 0; k < 3; k++)
            f->color[k] = b0 * d->colors[3 * i0 + k] + b1 * d->colors[3 * i1 + k] + b2 * d->colors[3 * i2 + k];
    } else {
        memcpy(f->color, d->material.diffuse, sizeof f->color);
    }
}

static void sr__shade_pixel(const sr__shader *s, int x, int y, uint32_t id, float b1, float b2, float rgb[3])
{
    const sr_draw_desc *d = s->d;
    sr_fragment f;
    if (d->shading == SR_SHADE_GOURAUD && !d->fragment && s->gouraud) {
        const uint32_t *idx = d->indices + 3 * (size_t)(id & ~SR__BACK_BIT);
        size_t off = (id & SR__BACK_BIT) ? 3 : 0;
        float b0 = 1.0f - b1 - b2;
        int k;
        for (k = 0; k < 3; k++)
            rgb[k] = b0 * s->gouraud[6 * (size_t)idx[0] + off + (size_t)k] + b1 * s->gouraud[6 * (size_t)idx[1] + off + (size_t)k] +
                     b2 * s->gouraud[6 * (size_t)idx[2] + off + (size_t)k];
        return;
    }
    if (d->shading == SR_SHADE_FLAT) { b1 = b2 = 1.0f / 3.0f; }
    sr__fill_fragment(s, x, y, id, b1, b2, &f);
    if (d->fragment) { d->fragment(d->fragment_user, &f, rgb); return; }
    if (d->shading == SR_SHADE_UNLIT) { memcpy(rgb, f.color, 3 * sizeof(float)); return; }
    {
        float V[3];
        const float *kd = d->colors ? f.color : d->material.diffuse, *ka = d->colors ? f.color : d->material.ambient;
        int l;
        if (s->cam->orthographic) { V[0] = -s->cam->forward[0]; V[1] = -s->cam->forward[1]; V[2] = -s->cam->forward[2]; }
        else sr__view_dir(s->cam->eye, f.position, V);
        memcpy(rgb, d->material.emission, 3 * sizeof(float));
        for (l = 0; l < s->light_count; l++) sr__shade_light(&d->material, kd, ka, &s->lights[l], f.position, f.normal, V, 1.0f, s->spec_cut, rgb);
    }
}

/* coverage of the wireframe at a pixel centre: distance to the nearest edge of its triangle,
   faded out on triangles too small on screen for their edges to stay lines. The wire's share of
   an equilateral triangle of side L pixels is about 6.9 half / L (half = half the wire width): with
   L >= 20 half (10 pixels at width 1, a third of it wire) the wire is drawn as it is, below that
   it fades linearly to nothing at L = 10 half, so that a dense mesh shows its shading instead of
   a solid wire colour. L is the mean of the three projected edge lengths: a triangle seen edge-on
   near a silhouette keeps its wire (its long edges stay lines). */
#define SR__WIRE_FULL 20.0f
#define SR__WIRE_NONE 10.0f
static float sr__wire_alpha(const sr__shader *s, int x, int y, uint32_t id)
{
    const uint32_t *idx = s->d->indices + 3 * (size_t)(id & ~SR__BACK_BIT);
    const sr__cv *v[3];
    float px = (float)x + 0.5f, py = (float)y + 0.5f, dmin = 1e30f, half, mean = 0.0f;
    int k;
    for (k = 0; k < 3; k++) {
        v[k] = &s->cv[idx[k]];
        if (v[k]->code & SR__CLIP_BITS) return 0.0f;
    }
    for (k = 0; k < 3; k++) {
        const sr__cv *a = v[k], *b = v[(k + 1) % 3];
        float ex = b->sx - a->sx, ey = b->sy - a->sy, len = sqrtf(ex * ex + ey * ey), dist;
        mean += len * (1.0f / 3.0f);
        if (len <= 0.0f) continue;
        dist = fabsf(ex * (py - a->sy) - ey * (px - a->sx)) / len;
        if (dist < dmin) dmin = dist;
    }
    half = (s->d->wire_width > 0.0f ? s->d->wire_width : 1.0f) * 0.5f;
    if (mean >= SR__WIRE_FULL * half) return sr__clampf(half + 0.5f - dmin, 0.0f, 1.0f);
    return sr__clampf(half + 0.5f - dmin, 0.0f, 1.0f) *
           sr__clampf((mean / half - SR__WIRE_NONE) / (SR__WIRE_FULL - SR__WIRE_NONE), 0.0f, 1.0f);
}

/* Per-pixel Phong for a batch of pixels, one step at a time over the whole batch: the steps of
   one pixel form a long chain of dependent square roots and divisions, while the same step for
   different pixels is independent work the processor can overlap. Same formula as
   sr__shade_light. */
#define SR__BATCH 64

typedef struct sr__batch {
    int n;
    size_t pixel[SR__BATCH];
    uint32_t id[SR__BATCH];
    float b1[SR__BATCH], b2[SR__BATCH];
    float P[3][SR__BATCH], N[3][SR__BATCH], V[3][SR__BATCH], kd[3][SR__BATCH], rgb[3][SR__BATCH];
} sr__batch;

static void sr__shade_batch(const sr__shader *s, sr__batch *b, sr_framebuffer *fb)
{
    const sr_draw_desc *d = s->d;
    const sr_material *m = &d->material;
    int j, k, l, n = b->n;
    for (j = 0; j < n; j++) { /* gather and interpolate */
        const uint32_t *idx = d->indices + 3 * (size_t)(b->id[j] & ~SR__BACK_BIT);
        const float *p0 = s->wpos + 3 * (size_t)idx[0], *p1 = s->wpos + 3 * (size_t)idx[1], *p2 = s->wpos + 3 * (size_t)idx[2];
        const float *n0 = s->wnrm + 3 * (size_t)idx[0], *n1 = s->wnrm + 3 * (size_t)idx[1], *n2 = s->wnrm + 3 * (size_t)idx[2];
        float b1 = b->b1[j], b2 = b->b2[j], b0 = 1.0f - b1 - b2;
        for (k = 0; k < 3; k++) {
            b->P[k][j] = b0 * p0[k] + b1 * p1[k] + b2 * p2[k];
            b->N[k][j] = b0 * n0[k] + b1 * n1[k] + b2 * n2[k];
        }
        if (d->colors) {
            const float *c0 = d->colors + 3 * (size_t)idx[0], *c1 = d->colors + 3 * (size_t)idx[1], *c2 = d->colors + 3 * (size_t)idx[2];
            for (k = 0; k < 3; k++) b->kd[k][j] = b0 * c0[k] + b1 * c1[k] + b2 * c2[k];
        }
    }
    for (j = 0; j < n; j++) { /* unit normal (toward the viewer on back faces) and view vector */
        float nn = b->N[0][j] * b->N[0][j] + b->N[1][j] * b->N[1][j] + b->N[2][j] * b->N[2][j], sn;
        float vx, vy, vz, vv, sv;
        if (s->cam->orthographic) { vx = -s->cam->forward[0]; vy = -s->cam->forward[1]; vz = -s->cam->forward[2]; }
        else { vx = s->cam->eye[0] - b->P[0][j]; vy = s->cam->eye[1] - b->P[1][j]; vz = s->cam->eye[2] - b->P[2][j]; }
        vv = vx * vx + vy * vy + vz * vz;
        sn = nn > 0.0f ? 1.0f / sqrtf(nn) : 0.0f;
        sv = vv > 0.0f ? 1.0f / sqrtf(vv) : 0.0f;
        if (b->id[j] & SR__BACK_BIT) sn = -sn;
        for (k = 0; k < 3; k++) b->N[k][j] *= sn;
        b->V[0][j] = vx * sv; b->V[1][j] = vy * sv; b->V[2][j] = vz * sv;
        for (k = 0; k < 3; k++) b->rgb[k][j] = m->emission[k];
    }
    for (l = 0; l < s->light_count; l++) {
        const sr_light *lt = &s->lights[l];
        float Ld[3], amb[3], dif[3], spc[3], half_shininess = 0.5f * m->shininess, cut2 = s->spec_cut * s->spec_cut;
        int point = lt->type == SR_LIGHT_POINT, vcol = d->colors != NULL;
        sr__light_dir(lt, lt->vector, Ld); /* directional: the unit direction; point: unused */
        for (k = 0; k < 3; k++) { /* per-light constants (vertex colours multiply them per pixel) */
            amb[k] = lt->ambient[k] * (vcol ? 1.0f : m->ambient[k]);
            dif[k] = lt->diffuse[k] * (vcol ? 1.0f : m->diffuse[k]);
            spc[k] = lt->specular[k] * m->specular[k];
        }
        for (j = 0; j < n; j++) {
            float L[3], nx = b->N[0][j], ny = b->N[1][j], nz = b->N[2][j], ndl, spec = 0.0f;
            if (point) {
                float P[3];
                P[0] = b->P[0][j]; P[1] = b->P[1][j]; P[2] = b->P[2][j];
                sr__light_dir(lt, P, L);
            } else {
                L[0] = Ld[0]; L[1] = Ld[1]; L[2] = Ld[2];
            }
            ndl = nx * L[0] + ny * L[1] + nz * L[2];
            if (ndl > 0.0f) {
                float hx = L[0] + b->V[0][j], hy = L[1] + b->V[1][j], hz = L[2] + b->V[2][j];
                float hh = hx * hx + hy * hy + hz * hz, nh = nx * hx + ny * hy + nz * hz;
                /* (N.H/|H|)^s as ((N.H)^2/|H|^2)^(s/2): no square root */
                if (nh > 0.0f && nh * nh > cut2 * hh) spec = powf(nh * nh / hh, half_shininess);
            } else {
                ndl = 0.0f;
            }
            if (vcol) {
                for (k = 0; k < 3; k++) b->rgb[k][j] += b->kd[k][j] * (amb[k] + dif[k] * ndl) + spc[k] * spec;
            } else {
                for (k = 0; k < 3; k++) b->rgb[k][j] += amb[k] + dif[k] * ndl + spc[k] * spec;
            }
        }
    }
    for (j = 0; j < n; j++) {
        float *c = fb->color + 4 * b->pixel[j];
        c[0] = b->rgb[0][j]; c[1] = b->rgb[1][j]; c[2] = b->rgb[2][j];
    }
    b->n = 0;
}

static void sr__shading_pass(const sr__shader *s, sr__raster *r)
{
    sr_framebuffer *fb = r->fb;
    int x, y;
    const sr_draw_desc *d = s->d;
    if (d->shading == SR_SHADE_PHONG && !d->fragment && !d->normal_map && s->wnrm) {
        sr__batch batch;
        batch.n = 0;
        for (y = r->miny; y <= r->maxy; y++) {
            size_t row = (size_t)y * (size_t)fb->width;
            for (x = r->minx; x <= r->maxx; x++) {
                size_t i = row + (size_t)x;
                uint32_t id = fb->tri_id[i];
                if (id == SR__NO_ID) continue;
                batch.pixel[batch.n] = i;
                batch.id[batch.n] = id;
                batch.b1[batch.n] = fb->bary[2 * i];
                batch.b2[batch.n] = fb->bary[2 * i + 1];
                if (++batch.n == SR__BATCH) sr__shade_batch(s, &batch, fb);
            }
        }
        if (batch.n) sr__shade_batch(s, &batch, fb);
        /* the wireframe and the bookkeeping over the shaded colours */
        for (y = r->miny; y <= r->maxy; y++) {
            size_t row = (size_t)y * (size_t)fb->width;
            for (x = r->minx; x <= r->maxx; x++) {
                size_t i = row + (size_t)x;
                uint32_t id = fb->tri_id[i];
                if (id == SR__NO_ID) continue;
                fb->tri_id[i] = SR__NO_ID;
                if (d->wireframe) {
                    float a = sr__wire_alpha(s, x, y, id), *c = fb->color + 4 * i;
                    int k;
                    for (k = 0; k < 3; k++) c[k] += (d->wire_color[k] - c[k]) * a;
                }
                fb->color[4 * i + 3] = 1.0f;
            }
        }
        return;
    }
    for (y = r->miny; y <= r->maxy; y++) {
        size_t row = (size_t)y * (size_t)fb->width;
        for (x = r->minx; x <= r->maxx; x++) {
            size_t i = row + (size_t)x;
            uint32_t id = fb->tri_id[i];
            float rgb[3];
            if (id == SR__NO_ID) continue;
            fb->tri_id[i] = SR__NO_ID;
            sr__shade_pixel(s, x, y, id, fb->bary[2 * i], fb->bary[2 * i + 1], rgb);
            if (s->d->wireframe) {
                float a = sr__wire_alpha(s, x, y, id);
                int k;
                for (k = 0; k < 3; k++) rgb[k] += (s->d->wire_color[k] - rgb[k]) * a;
            }
            fb->color[4 * i + 0] = rgb[0];
            fb->color[4 * i + 1] = rgb[1];
            fb->color[4 * i + 2] = rgb[2];
            fb->color[4 * i + 3] = 1.0f;
        }
    }
}

/* sr_draw_mesh's arguments: the pointers, the model matrix, the sizes, the normal map, every
   index in range and every position finite */
static sr_result sr__draw_check(const sr_framebuffer *fb, const sr_camera *cam, const sr_draw_desc *d)
{
    size_t v, t;
    if (!fb || !fb->color || !cam || !d || !sr__camera_ok(cam)) return SR_ERR_INVALID_ARGUMENT;
    if ((d->vertex_count && !d->positions) || (d->triangle_count && !d->indices)) return SR_ERR_INVALID_ARGUMENT;
    if (d->model && !sr__finite_n(d->model, 16)) return SR_ERR_INVALID_ARGUMENT;
    if (d->triangle_count >= (size_t)SR__BACK_BIT || d->vertex_count > (size_t)UINT32_MAX) return SR_ERR_TOO_LARGE;
    if (d->normal_map && !sr__image_ok(d->normal_map, 3)) return SR_ERR_INVALID_ARGUMENT;
    for (t = 0; t < 3 * d->triangle_count; t++)
        if (d->indices[t] >= d->vertex_count) return SR_ERR_INVALID_ARGUMENT;
    for (v = 0; v < d->vertex_count; v++)
        if (!sr__finite3(d->positions + 3 * v)) return SR_ERR_INVALID_ARGUMENT;
    return SR_OK;
}

/* the framebuffer's scratch block, at least bytes long (kept between draws: no page faults for
   a fresh block every frame) */
static sr_result sr__draw_scratch(sr_framebuffer *fb, size_t bytes)
{
    sr_allocator a = fb->allocator;
    if (fb->scratch_size >= bytes) return SR_OK;
    if (fb->scratch) a.free(a.user, fb->scratch);
    fb->scratch_size = 0;
    fb->scratch = sr__alloc(&a, bytes);
    if (!fb->scratch) return SR_ERR_OUT_OF_MEMORY;
    fb->scratch_size = bytes;
    return SR_OK;
}

/* the shader's state; with a model matrix, the world positions and normals into extra (6 per
   vertex) and mvp = viewproj x model; returns where the next per-vertex block starts */
static float *sr__draw_shader(sr__shader *s, const sr_camera *cam, const sr_draw_desc *d, sr__cv *cv, float *extra,
                              sr_light *head, float mvp[16])
{
    size_t v, nv = d->vertex_count;
    memset(s, 0, sizeof *s);
    s->d = d;
    s->cam = cam;
    s->cv = cv;
    s->lights = sr__lights(d->lights, d->light_count, cam, head, &s->light_count);
    s->spec_cut = sr__spec_cut(&d->material);
    s->wpos = d->positions;
    s->wnrm = d->normals;
    if (!d->model) {
        memcpy(mvp, cam->viewproj, 16 * sizeof(float));
        return extra;
    }
    s->has_model = 1;
    sr__normal_matrix(d->model, s->nmat);
    for (v = 0; v < nv; v++) {
        sr__mat_point(d->model, d->positions + 3 * v, extra + 3 * v);
        if (d->normals) { sr__mat3_vec(s->nmat, d->normals + 3 * v, extra + 3 * nv + 3 * v); sr__normalize(extra + 3 * nv + 3 * v); }
    }
    s->wpos = extra;
    s->wnrm = d->normals ? extra + 3 * nv : NULL;
    sr__mat_mul(cam->viewproj, d->model, mvp);
    return extra + 6 * nv;
}

/* the vertex stage: clip coordinates, outcodes and screen positions; SR_ERR_NOT_FINITE when a
   transformed vertex overflows */
static sr_result sr__draw_vertices(const sr_framebuffer *fb, const sr__shader *s, const float mvp[16], sr__cv *cv)
{
    const sr_draw_desc *d = s->d;
    size_t v;
    for (v = 0; v < d->vertex_count; v++) {
        const float *p = d->positions + 3 * v;
        sr__cv *o = &cv[v];
        o->clip[0] = mvp[0] * p[0] + mvp[4] * p[1] + mvp[8] * p[2] + mvp[12];
        o->clip[1] = mvp[1] * p[0] + mvp[5] * p[1] + mvp[9] * p[2] + mvp[13];
        o->clip[2] = mvp[2] * p[0] + mvp[6] * p[1] + mvp[10] * p[2] + mvp[14];
        o->clip[3] = mvp[3] * p[0] + mvp[7] * p[1] + mvp[11] * p[2] + mvp[15];
        if (!sr__finite_n(o->clip, 4) || (d->model && !sr__finite3(s->wpos + 3 * v))) return SR_ERR_NOT_FINITE;
        o->code = sr__outcode(o->clip);
        if (!(o->code & SR__CLIP_BITS)) sr__to_screen(o, (float)fb->width, (float)fb->height);
        else { o->sx = o->sy = o->sz = o->invw = 0.0f; o->fx = o->fy = 0; }
    }
    return SR_OK;
}

/* Gouraud shading: each vertex's colour lit from both sides into g (6 per vertex) */
static void sr__draw_gouraud(sr__shader *s, float *g)
{
    const sr_draw_desc *d = s->d;
    const sr_camera *cam = s->cam;
    size_t v;
    s->gouraud = g;
    for (v = 0; v < d->vertex_count; v++) {
        float N[3], V[3];
        const float *P = s->wpos + 3 * v;
        const float *kd = d->colors ? d->colors + 3 * v : d->material.diffuse;
        const float *ka = d->colors ? d->colors + 3 * v : d->material.ambient;
        int side, k, l;
        if (s->wnrm) memcpy(N, s->wnrm + 3 * v, sizeof N);
        else { N[0] = 0.0f; N[1] = 0.0f; N[2] = 1.0f; }
        if (cam->orthographic) { V[0] = -cam->forward[0]; V[1] = -cam->forward[1]; V[2] = -cam->forward[2]; }
        else sr__view_dir(cam->eye, P, V);
        for (side = 0; side < 2; side++) {
            float *o = g + 6 * v + 3 * side;
            memcpy(o, d->material.emission, 3 * sizeof(float));
            for (l = 0; l < s->light_count; l++) sr__shade_light(&d->material, kd, ka, &s->lights[l], P, N, V, 1.0f, s->spec_cut, o);
            for (k = 0; k < 3; k++) N[k] = -N[k];
        }
    }
}

/* the visibility pass: every triangle not outside one clip plane rasterized (clipped where it
   crosses one) into the depth and id buffers */
static void sr__draw_visibility(sr__raster *r, sr_framebuffer *fb, const sr_draw_desc *d, const sr__cv *cv)
{
    size_t t;
    memset(r, 0, sizeof *r);
    r->fb = fb;
    r->count_mode = d->shading == SR_SHADE_COUNT;
    r->depth_test = !d->no_depth_test;
    r->depth_write = !d->no_depth_write;
    r->cull = d->cull;
    r->minx = fb->width; r->miny = fb->height; r->maxx = -1; r->maxy = -1;
    for (t = 0; t < d->triangle_count; t++) {
        const uint32_t *idx = d->indices + 3 * t;
        const sr__cv *tv[3];
        uint32_t c0, c1, c2;
        tv[0] = &cv[idx[0]]; tv[1] = &cv[idx[1]]; tv[2] = &cv[idx[2]];
        c0 = tv[0]->code; c1 = tv[1]->code; c2 = tv[2]->code;
        if (c0 & c1 & c2 & 63u) continue;
        if ((c0 | c1 | c2) & SR__CLIP_BITS) sr__clip_tri(r, tv, (c0 | c1 | c2) & SR__CLIP_BITS, (uint32_t)t);
        else sr__raster_tri(r, tv[0], tv[1], tv[2], NULL, (uint32_t)t);
    }
}

SRDEF sr_result sr_draw_mesh(sr_framebuffer *fb, const sr_camera *cam, const sr_draw_desc *d)
{
    sr__raster r;
    sr__shader s;
    sr_light head;
    float mvp[16], *extra;
    size_t nv, per_vertex;
    sr__cv *cv;
    int gouraud;
    sr_result res = sr__draw_check(fb, cam, d);
    if (res != SR_OK || d->triangle_count == 0) return res;
    nv = d->vertex_count;
    gouraud = d->shading == SR_SHADE_GOURAUD && !d->fragment;
    per_vertex = sizeof(sr__cv) + (d->model ? 6 * sizeof(float) : 0) + (gouraud ? 6 * sizeof(float) : 0);
    if (nv > ((size_t)-1) / per_vertex) return SR_ERR_TOO_LARGE;
    if ((res = sr__draw_scratch(fb, nv * per_vertex)) != SR_OK) return res;
    cv = (sr__cv *)fb->scratch;                                       /* per vertex: clip and screen */
    extra = (float *)((unsigned char *)fb->scratch + nv * sizeof(sr__cv)); /* then world, then Gouraud */
    extra = sr__draw_shader(&s, cam, d, cv, extra, &head, mvp);
    if ((res = sr__draw_vertices(fb, &s, mvp, cv)) != SR_OK) return res;
    if (gouraud) sr__draw_gouraud(&s, extra);
    sr__draw_visibility(&r, fb, d, cv);
    if (!r.count_mode) sr__shading_pass(&s, &r);
    return SR_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: relief mapping (Policarpo, Oliveira & Comba 2005)
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_relief_desc_default(sr_relief_desc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    d->axis_u[0] = 1.0f; d->axis_v[1] = 1.0f;
    d->depth_scale = 0.1f;
    d->linear_steps = 10;
    d->binary_steps = 5;
    sr_material_default(&d->material);
}

/* the quad's frame: unit normal n and the dual basis that maps a world offset to (s, t) */
typedef struct sr__relief_frame { float n[3], du[3], dv[3]; } sr__relief_frame;

static int sr__relief_frame_init(const sr_relief_desc *d, sr__relief_frame *f)
{
    float a, b;
    sr__cross(d->axis_u, d->axis_v, f->n);
    if (sr__normalize(f->n) <= 0.0f) return 0;
    sr__cross(d->axis_v, f->n, f->du);
    sr__cross(f->n, d->axis_u, f->dv);
    a = sr__dot(d->axis_u, f->du);
    b = sr__dot(d->axis_v, f->dv);
    if (a == 0.0f || b == 0.0f) return 0;
    f->du[0] /= a; f->du[1] /= a; f->du[2] /= a;
    f->dv[0] /= b; f->dv[1] /= b; f->dv[2] /= b;
    return 1;
}

/* floorf for |x| < 2^23 (exact there: the same bits), without the libm call that plain x86-64
   builds make; NaN and huge values go to -2^22 */
static SR__INLINE int sr__floor_int(float x)
{
    int i;
    if (!(x > -4194304.0f && x < 4194304.0f)) return -4194304;
    i = (int)x;
    return (float)i > x ? i - 1 : i;
}

/* sr__sample of channel 0 alone (the same arithmetic, so the same bits), the marchers' inner loop */
static SR__INLINE float sr__depth_at(const sr_image *img, float u, float v)
{
    float x = u * (float)img->width - 0.5f, y = v * (float)img->height - 0.5f;
    int x0 = sr__floor_int(x), y0 = sr__floor_int(y), x1 = x0 + 1, y1 = y0 + 1, w = img->width, h = img->height;
    float ax = x - (float)x0, ay = y - (float)y0, a, b, e, f;
    size_t ch = (size_t)img->channels, r0, r1;
    if (img->wrap) {
        x0 %= w; if (x0 < 0) x0 += w;
        y0 %= h; if (y0 < 0) y0 += h;
        x1 = (x0 + 1) % w; y1 = (y0 + 1) % h;
    } else {
        x0 = x0 < 0 ? 0 : (x0 >= w ? w - 1 : x0);
        x1 = x1 < 0 ? 0 : (x1 >= w ? w - 1 : x1);
        y0 = y0 < 0 ? 0 : (y0 >= h ? h - 1 : y0);
        y1 = y1 < 0 ? 0 : (y1 >= h ? h - 1 : y1);
    }
    r0 = (size_t)y0 * (size_t)w;
    r1 = (size_t)y1 * (size_t)w;
    a = img->data[(r0 + (size_t)x0) * ch];
    b = img->data[(r0 + (size_t)x1) * ch];
    e = img->data[(r1 + (size_t)x0) * ch];
    f = img->data[(r1 + (size_t)x1) * ch];
    return (a + (b - a) * ax) * (1.0f - ay) + (e + (f - e) * ax) * ay;
}

/* Search along the map-space ray (s0 + d*ds, t0 + d*dt, d) for the first d >= depth(s, t):
   `linear` uniform steps (the last one, d = 1, always hits since depth <= 1), then `binary`
   halvings of the bracketing interval; returns its midpoint. */
static float sr__relief_search(const sr_image *img, float s0, float t0, float ds, float dt, int linear, int binary)
{
    float lo = 0.0f, hi = 1.0f, step = 1.0f / (float)linear;
    int i;
    for (i = 1; i <= linear; i++) {
        float dd = (float)i * step;
        if (i == linear || dd >= sr__depth_at(img, s0 + dd * ds, t0 + dd * dt)) { hi = dd; lo = dd - step; break; }
    }
    for (i = 0; i < binary; i++) {
        float mid = 0.5f * (lo + hi);
        if (mid >= sr__depth_at(img, s0 + mid * ds, t0 + mid * dt)) hi = mid;
        else lo = mid;
    }
    return 0.5f * (lo + hi);
}

/* Curved mode (Oliveira & Policarpo 2005's idea, with the bend given per quad): the reference
   surface lies sag = (cu x^2 + cv y^2) / 2 below the quad's plane, x and y the world offsets from
   the quad's centre along u and v; the map's depth is measured from it. The ray is followed from
   where it crosses the plane (over the quad or beside it: the bend lies below the plane) to
   where it is below the deepest possible surface, in linear_steps uniform steps and
   binary_steps halvings of the step that first finds it at or below the map; the hit must lie
   over the quad: a ray that passes the bend, or meets the extended bend beside the quad (a
   neighbouring quad's part of the surface), is a miss, which draws the silhouette. */
static float sr__relief_shell_gap(const sr_relief_desc *d, const sr__relief_frame *f, const float o[3], const float dir[3],
                                  float lam, float *s, float *tm, float *r)
{
    float P[3], rel[3], x, y, lu = sqrtf(sr__dot(d->axis_u, d->axis_u)), lv = sqrtf(sr__dot(d->axis_v, d->axis_v)), z;
    int k;
    for (k = 0; k < 3; k++) P[k] = o[k] + lam * dir[k];
    sr__sub(P, d->origin, rel);
    *s = sr__dot(rel, f->du);
    *tm = sr__dot(rel, f->dv);
    z = sr__dot(rel, f->n);
    x = (*s - 0.5f) * lu;
    y = (*tm - 0.5f) * lv;
    *r = (-z - 0.5f * (d->curvature_u * x * x + d->curvature_v * y * y)) / d->depth_scale;
    return *r - sr__depth_at(&d->depth, *s, *tm);
}

static int sr__relief_intersect_curved(const sr_relief_desc *d, const sr__relief_frame *f, const float o[3], const float dir[3],
                                       float lam0, float *t, float uvd[3])
{
    float lu = sqrtf(sr__dot(d->axis_u, d->axis_u)), lv = sqrtf(sr__dot(d->axis_v, d->axis_v));
    float sag = 0.125f * (d->curvature_u * lu * lu + d->curvature_v * lv * lv), denom = -sr__dot(dir, f->n);
    float lam1 = lam0 + (d->depth_scale + sag) / denom, lo, hi, s, tm, r, step;
    int linear = d->linear_steps > 0 ? d->linear_steps : 10, binary = d->binary_steps > 0 ? d->binary_steps : 5, i;
    step = (lam1 - lam0) / (float)linear;
    lo = lam0;
    for (i = 1; i <= linear; i++) {
        float lam = lam0 + (float)i * step;
        float gap = sr__relief_shell_gap(d, f, o, dir, lam, &s, &tm, &r);
        if (gap >= 0.0f && r >= 0.0f) break;
        lo = lam;
    }
    if (i > linear) return 0;
    hi = lo + step;
    for (i = 0; i < binary; i++) {
        float mid = 0.5f * (lo + hi);
        if (sr__relief_shell_gap(d, f, o, dir, mid, &s, &tm, &r) >= 0.0f && r >= 0.0f) hi = mid;
        else lo = mid;
    }
    sr__relief_shell_gap(d, f, o, dir, 0.5f * (lo + hi), &s, &tm, &r);
    if (!d->depth.wrap && (s < 0.0f || s > 1.0f || tm < 0.0f || tm > 1.0f)) return 0;
    if (t) *t = 0.5f * (lo + hi);
    if (uvd) { uvd[0] = s; uvd[1] = tm; uvd[2] = r < 0.0f ? 0.0f : r > 1.0f ? 1.0f : r; }
    return 1;
}

/* the intersection for a checked descriptor and its frame */
static int sr__relief_hit(const sr_relief_desc *d, const sr__relief_frame *fp, const float origin[3], const float dir[3], float *t, float uvd[3])
{
    const sr__relief_frame f = *fp;
    float denom, t0, E[3], rel[3], s0, tm0, step[3], ds, dt, hit, sh, th;
    int k, linear, binary;
    denom = sr__dot(dir, f.n);
    if (!(denom < 0.0f)) return 0; /* only rays entering the surface from above */
    sr__sub(d->origin, origin, rel);
    t0 = sr__dot(rel, f.n) / denom;
    if (t0 < 0.0f) return 0;
    for (k = 0; k < 3; k++) E[k] = origin[k] + t0 * dir[k];
    sr__sub(E, d->origin, rel);
    s0 = sr__dot(rel, f.du);
    tm0 = sr__dot(rel, f.dv);
    if (d->curvature_u != 0.0f || d->curvature_v != 0.0f) { /* may cross the plane beside the quad */
        if (!(d->curvature_u >= 0.0f) || !(d->curvature_v >= 0.0f)) return 0;
        return sr__relief_intersect_curved(d, &f, origin, dir, t0, t, uvd);
    }
    if (s0 < 0.0f || s0 > 1.0f || tm0 < 0.0f || tm0 > 1.0f) return 0;
    /* world offset per unit of map depth: depth_scale along -n */
    for (k = 0; k < 3; k++) step[k] = dir[k] * d->depth_scale / -denom;
    ds = sr__dot(step, f.du);
    dt = sr__dot(step, f.dv);
    linear = d->linear_steps > 0 ? d->linear_steps : 10;
    binary = d->binary_steps > 0 ? d->binary_steps : 5;
    hit = sr__relief_search(&d->depth, s0, tm0, ds, dt, linear, binary);
    sh = s0 + hit * ds;
    th = tm0 + hit * dt;
    if (!d->depth.wrap && (sh < 0.0f || sh > 1.0f || th < 0.0f || th > 1.0f)) return 0; /* left through a side */
    if (t) *t = t0 + hit * d->depth_scale / -denom;
    if (uvd) { uvd[0] = sh; uvd[1] = th; uvd[2] = hit; }
    return 1;
}

SRDEF int sr_relief_intersect(const sr_relief_desc *d, const float origin[3], const float dir[3], float *t, float uvd[3])
{
    sr__relief_frame f;
    if (!d || !origin || !dir || !sr__image_ok(&d->depth, 1) || !(d->depth_scale > 0.0f)) return 0;
    if (!sr__relief_frame_init(d, &f)) return 0;
    return sr__relief_hit(d, &f, origin, dir, t, uvd);
}

/* The pixels the relief's prism (the quad and its copy depth_scale, plus the bend's sag, below
   it) can cover: the bounding box of its 8 corners' projections, one pixel wider; the whole
   frame when a corner is not in front of the camera. */
static void sr__relief_bounds(const sr_relief_desc *d, const sr__relief_frame *f, const sr_camera *cam, int W, int H, int box[4])
{
    float lu = sqrtf(sr__dot(d->axis_u, d->axis_u)), lv = sqrtf(sr__dot(d->axis_v, d->axis_v));
    float drop = d->depth_scale + 0.125f * (d->curvature_u * lu * lu + d->curvature_v * lv * lv), lo[2] = {1e30f, 1e30f}, hi[2] = {-1e30f, -1e30f};
    int c, k;
    box[0] = 0; box[1] = 0; box[2] = W - 1; box[3] = H - 1;
    for (c = 0; c < 8; c++) {
        float P[3], rel[3], z, sx, sy;
        for (k = 0; k < 3; k++)
            P[k] = d->origin[k] + ((c & 1) ? d->axis_u[k] : 0.0f) + ((c & 2) ? d->axis_v[k] : 0.0f) - ((c & 4) ? drop * f->n[k] : 0.0f);
        sr__sub(P, cam->eye, rel);
        z = sr__dot(rel, cam->forward);
        if (cam->orthographic) {
            sx = sr__dot(rel, cam->right) / (cam->half_height * cam->aspect);
            sy = sr__dot(rel, cam->up) / cam->half_height;
        } else {
            if (!(z > 1e-6f)) return;
            sx = sr__dot(rel, cam->right) / (z * cam->tan_half_fovy * cam->aspect);
            sy = sr__dot(rel, cam->up) / (z * cam->tan_half_fovy);
        }
        sx = (sx + 1.0f) * 0.5f * (float)W;
        sy = (1.0f - sy) * 0.5f * (float)H;
        lo[0] = sx < lo[0] ? sx : lo[0]; hi[0] = sx > hi[0] ? sx : hi[0];
        lo[1] = sy < lo[1] ? sy : lo[1]; hi[1] = sy > hi[1] ? sy : hi[1];
    }
    if (!(hi[0] - lo[0] < 1e7f) || !(hi[1] - lo[1] < 1e7f)) return;
    box[0] = lo[0] - 1.0f > 0.0f ? (int)(lo[0] - 1.0f) : 0;
    box[1] = lo[1] - 1.0f > 0.0f ? (int)(lo[1] - 1.0f) : 0;
    box[2] = hi[0] + 1.0f < (float)(W - 1) ? (int)(hi[0] + 1.0f) : W - 1;
    box[3] = hi[1] + 1.0f < (float)(H - 1) ? (int)(hi[1] + 1.0f) : H - 1;
}

/* 1 if the light ray from map point (s, t, depth) escapes the height field */
static float sr__relief_visibility(const sr_relief_desc *d, const sr__relief_frame *f, const float L[3], const float uvd[3])
{
    float ln = sr__dot(L, f->n), step[3], ds, dt;
    int k, i, n = 2 * (d->linear_steps > 0 ? d->linear_steps : 10);
    if (ln <= 0.0f) return 0.0f;
    for (k = 0; k < 3; k++) step[k] = L[k] * d->depth_scale / ln; /* world offset per unit of depth rise */
    ds = sr__dot(step, f->du);
    dt = sr__dot(step, f->dv);
    for (i = 1; i < n; i++) {
        float rise = uvd[2] * (float)i / (float)n, depth = uvd[2] - rise;
        if (depth > sr__depth_at(&d->depth, uvd[0] + rise * ds, uvd[1] + rise * dt) + 0.02f) return 0.0f;
    }
    return 1.0f;
}

/* Policarpo's test: from where the light ray through the hit enters the top plane, the linear +
   binary search down it; lit when it stops no higher than the hit's depth - bias */
static float sr__relief_visibility_search(const sr_relief_desc *d, const sr__relief_frame *f, const float L[3], const float uvd[3])
{
    float ln = sr__dot(L, f->n), step[3], ds, dt, found, bias = d->shadow_bias > 0.0f ? d->shadow_bias : 0.02f;
    int k;
    if (ln <= 0.0f) return 0.0f;
    for (k = 0; k < 3; k++) step[k] = L[k] * d->depth_scale / ln;
    ds = sr__dot(step, f->du);
    dt = sr__dot(step, f->dv);
    found = sr__relief_search(&d->depth, uvd[0] + uvd[2] * ds, uvd[1] + uvd[2] * dt, -ds, -dt,
                              d->linear_steps > 0 ? d->linear_steps : 10, d->binary_steps > 0 ? d->binary_steps : 5);
    return found < uvd[2] - bias ? 0.0f : 1.0f;
}

SRDEF float sr_relief_light_visibility(const sr_relief_desc *d, const float uvd[3], const float toward_light[3])
{
    sr__relief_frame f;
    if (!d || !uvd || !toward_light || !sr__image_ok(&d->depth, 1) || !(d->depth_scale > 0.0f) || !sr__relief_frame_init(d, &f)) return 1.0f;
    return d->shadow_search ? sr__relief_visibility_search(d, &f, toward_light, uvd) : sr__relief_visibility(d, &f, toward_light, uvd);
}

SRDEF sr_result sr_draw_relief(sr_framebuffer *fb, const sr_camera *cam, const sr_relief_desc *d)
{
    sr__relief_frame f;
    sr_light head;
    const sr_light *lights;
    float spec_cut;
    int nl, x, y, box[4];
    if (!fb || !fb->color || !cam || !d || !sr__camera_ok(cam) || !sr__image_ok(&d->depth, 1) ||
        !(d->depth_scale > 0.0f && d->depth_scale < 1e30f))
        return SR_ERR_INVALID_ARGUMENT;
    if (!sr__finite3(d->origin) || !sr__finite3(d->axis_u) || !sr__finite3(d->axis_v) || !(d->curvature_u < 1e30f) ||
        !(d->curvature_v < 1e30f))
        return SR_ERR_INVALID_ARGUMENT;
    if ((d->albedo && !sr__image_ok(d->albedo, 3)) || (d->normal_map && !sr__image_ok(d->normal_map, 3)))
        return SR_ERR_INVALID_ARGUMENT;
    if (!sr__relief_frame_init(d, &f)) return SR_ERR_INVALID_ARGUMENT;
    if (!(d->curvature_u >= 0.0f) || !(d->curvature_v >= 0.0f) || !(d->shadow_light >= 0.0f) || !(d->shadow_bias >= 0.0f))
        return SR_ERR_INVALID_ARGUMENT;
    lights = sr__lights(d->lights, d->light_count, cam, &head, &nl);
    spec_cut = sr__spec_cut(&d->material);
    sr__relief_bounds(d, &f, cam, fb->width, fb->height, box);
    for (y = box[1]; y <= box[3]; y++)
        for (x = box[0]; x <= box[2]; x++) {
            float o[3], dir[3], t, uvd[3], P[3], N[3], V[3], kd[3], rgb[3], z;
            size_t i = (size_t)y * (size_t)fb->width + (size_t)x;
            int k, l;
            sr_camera_ray(cam, fb->width, fb->height, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            if (!sr__relief_hit(d, &f, o, dir, &t, uvd)) continue;
            for (k = 0; k < 3; k++) P[k] = o[k] + t * dir[k];
            if (!sr_camera_depth(cam, P, &z) || !(z < fb->depth[i]) || z < 0.0f) continue;
            if (d->normal_map) {
                float tn[4] = {0.0f, 0.0f, 1.0f, 0.0f}, uh[3], vh[3];
                sr__sample(d->normal_map, uvd[0], uvd[1], tn);
                memcpy(uh, d->axis_u, sizeof uh); sr__normalize(uh);
                memcpy(vh, d->axis_v, sizeof vh); sr__normalize(vh);
                for (k = 0; k < 3; k++) N[k] = tn[0] * uh[k] + tn[1] * vh[k] + tn[2] * f.n[k];
            } else {
                /* P(s,t) = O + sU + tV - scale*h(s,t) n; N = dP/ds x dP/dt */
                float es = 1.0f / (float)d->depth.width, et = 1.0f / (float)d->depth.height, hs, ht, Ps[3], Pt[3];
                hs = (sr__depth_at(&d->depth, uvd[0] + es, uvd[1]) - sr__depth_at(&d->depth, uvd[0] - es, uvd[1])) / (2.0f * es);
                ht = (sr__depth_at(&d->depth, uvd[0], uvd[1] + et) - sr__depth_at(&d->depth, uvd[0], uvd[1] - et)) / (2.0f * et);
                for (k = 0; k < 3; k++) {
                    Ps[k] = d->axis_u[k] - d->depth_scale * hs * f.n[k];
                    Pt[k] = d->axis_v[k] - d->depth_scale * ht * f.n[k];
                }
                sr__cross(Ps, Pt, N);
            }
            sr__normalize(N);
            if (d->curvature_u != 0.0f || d->curvature_v != 0.0f) { /* tilt by the bend's slope at (s, t) */
                float lu = sqrtf(sr__dot(d->axis_u, d->axis_u)), lv = sqrtf(sr__dot(d->axis_v, d->axis_v));
                float gu = d->curvature_u * (uvd[0] - 0.5f) * lu, gv = d->curvature_v * (uvd[1] - 0.5f) * lv;
                for (k = 0; k < 3; k++) N[k] += gu * d->axis_u[k] / lu + gv * d->axis_v[k] / lv;
                sr__normalize(N);
            }
            if (d->albedo) { float a4[4]; sr__sample(d->albedo, uvd[0], uvd[1], a4); memcpy(kd, a4, sizeof kd); }
            else memcpy(kd, d->material.diffuse, sizeof kd);
            sr__view_dir(o, P, V);
            memcpy(rgb, d->material.emission, sizeof rgb);
            for (l = 0; l < nl; l++) {
                float vis = 1.0f;
                if (d->shadows) {
                    float L[3];
                    sr__light_dir(&lights[l], P, L);
                    vis = d->shadow_search ? sr__relief_visibility_search(d, &f, L, uvd) : sr__relief_visibility(d, &f, L, uvd);
                    if (vis == 0.0f) vis = d->shadow_light;
                }
                sr__shade_light(&d->material, kd, d->albedo ? kd : d->material.ambient, &lights[l], P, N, V, vis, spec_cut, rgb);
            }
            fb->depth[i] = z;
            fb->color[4 * i] = rgb[0]; fb->color[4 * i + 1] = rgb[1]; fb->color[4 * i + 2] = rgb[2];
            fb->color[4 * i + 3] = 1.0f;
        }
    return SR_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: terrain ray marching
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_terrain_desc_default(sr_terrain_desc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    d->spacing = 1.0f;
    d->height_scale = 1.0f;
    sr_material_default(&d->material);
}

/* bilinear height (world y) at world (x, z), clamped to the grid */
static float sr__terrain_y(const sr_terrain_desc *d, float x, float z)
{
    float gx = (x - d->origin_x) / d->spacing, gz = (z - d->origin_z) / d->spacing, fx, fz, ax, az;
    int x0, z0, x1, z1;
    const float *h = d->heights;
    gx = sr__clampf(gx, 0.0f, (float)(d->width - 1));
    gz = sr__clampf(gz, 0.0f, (float)(d->height - 1));
    fx = floorf(gx); fz = floorf(gz);
    x0 = (int)fx; z0 = (int)fz;
    x1 = x0 + 1 < d->width ? x0 + 1 : x0;
    z1 = z0 + 1 < d->height ? z0 + 1 : z0;
    ax = gx - fx; az = gz - fz;
    {
        float a = h[(size_t)z0 * (size_t)d->width + (size_t)x0], b = h[(size_t)z0 * (size_t)d->width + (size_t)x1];
        float c = h[(size_t)z1 * (size_t)d->width + (size_t)x0], e = h[(size_t)z1 * (size_t)d->width + (size_t)x1];
        return d->base_y + d->height_scale * ((a + (b - a) * ax) * (1.0f - az) + (c + (e - c) * ax) * az);
    }
}

/* the colour at world (x, z), bilinear between the samples' colours (as the heights are), clamped
   to the grid: a nearest-sample lookup showed every grid cell as a flat block */
static void sr__terrain_color(const sr_terrain_desc *d, float x, float z, float rgb[3])
{
    float gx = sr__clampf((x - d->origin_x) / d->spacing, 0.0f, (float)(d->width - 1));
    float gz = sr__clampf((z - d->origin_z) / d->spacing, 0.0f, (float)(d->height - 1)), fx = floorf(gx), fz = floorf(gz);
    int x0 = (int)fx, z0 = (int)fz, x1 = x0 + 1 < d->width ? x0 + 1 : x0, z1 = z0 + 1 < d->height ? z0 + 1 : z0, k;
    float ax = gx - fx, az = gz - fz;
    const float *a = d->colors + 3 * ((size_t)z0 * (size_t)d->width + (size_t)x0), *b = d->colors + 3 * ((size_t)z0 * (size_t)d->width + (size_t)x1);
    const float *c = d->colors + 3 * ((size_t)z1 * (size_t)d->width + (size_t)x0), *e = d->colors + 3 * ((size_t)z1 * (size_t)d->width + (size_t)x1);
    for (k = 0; k < 3; k++) rgb[k] = (a[k] + (b[k] - a[k]) * ax) * (1.0f - az) + (c[k] + (e[k] - c[k]) * ax) * az;
}

/* slab test against an axis-aligned box; returns 0 when the ray misses */
static int sr__ray_box(const float o[3], const float dir[3], const float lo[3], const float hi[3], float *t0, float *t1)
{
    float a = -1e30f, b = 1e30f;
    int k;
    for (k = 0; k < 3; k++) {
        if (dir[k] == 0.0f) {
            if (o[k] < lo[k] || o[k] > hi[k]) return 0;
        } else {
            float inv = 1.0f / dir[k], ta = (lo[k] - o[k]) * inv, tb = (hi[k] - o[k]) * inv;
            if (ta > tb) { float s = ta; ta = tb; tb = s; }
            if (ta > a) a = ta;
            if (tb < b) b = tb;
        }
    }
    if (a < 0.0f) a = 0.0f;
    if (a > b || !(b < 1e30f)) return 0; /* no finite exit: a zero or NaN direction, a NaN origin */
    *t0 = a; *t1 = b;
    return 1;
}

SRDEF sr_result sr_draw_terrain(sr_framebuffer *fb, const sr_camera *cam, const sr_terrain_desc *d)
{
    float lo[3], hi[3], hmin = 1e30f, hmax = -1e30f, step, spec_cut;
    size_t n, i;
    sr_light head;
    const sr_light *lights;
    int nl, x, y;
    if (!fb || !fb->color || !cam || !d || !sr__camera_ok(cam) || !d->heights || d->width < 2 || d->height < 2 ||
        !(d->spacing > 0.0f && d->spacing < 1e30f) || !(d->step >= 0.0f && d->step < 1e30f))
        return SR_ERR_INVALID_ARGUMENT;
    if (!(d->origin_x - d->origin_x == 0.0f && d->origin_z - d->origin_z == 0.0f && d->base_y - d->base_y == 0.0f &&
          d->height_scale - d->height_scale == 0.0f))
        return SR_ERR_INVALID_ARGUMENT;
    n = (size_t)d->width * (size_t)d->height;
    for (i = 0; i < n; i++) {
        float h = d->heights[i];
        if (h - h != 0.0f) return SR_ERR_INVALID_ARGUMENT;
        if (h < hmin) hmin = h;
        if (h > hmax) hmax = h;
    }
    lo[0] = d->origin_x; hi[0] = d->origin_x + d->spacing * (float)(d->width - 1);
    lo[2] = d->origin_z; hi[2] = d->origin_z + d->spacing * (float)(d->height - 1);
    lo[1] = d->base_y + d->height_scale * (d->height_scale >= 0.0f ? hmin : hmax) - 1e-4f;
    hi[1] = d->base_y + d->height_scale * (d->height_scale >= 0.0f ? hmax : hmin) + 1e-4f;
    if (!sr__finite3(lo) || !sr__finite3(hi)) return SR_ERR_NOT_FINITE; /* the heights' box overflows */
    step = d->step > 0.0f ? d->step : 0.5f * d->spacing;
    lights = sr__lights(d->lights, d->light_count, cam, &head, &nl);
    spec_cut = sr__spec_cut(&d->material);
    for (y = 0; y < fb->height; y++)
        for (x = 0; x < fb->width; x++) {
            float o[3], dir[3], t0, t1, t, prev, P[3], z, st;
            size_t pi = (size_t)y * (size_t)fb->width + (size_t)x;
            int k, hit = 0;
            sr_camera_ray(cam, fb->width, fb->height, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            if (!sr__ray_box(o, dir, lo, hi, &t0, &t1)) continue;
            st = t1 - t0 > 65536.0f * step ? (t1 - t0) / 65536.0f : step; /* at most 65536 steps a ray */
            if (!(t1 + st > t1)) continue;                                  /* a step under t1's ulp never ends */
            prev = t0;
            for (t = t0; t <= t1 + st; t += st) {
                float tt = t > t1 ? t1 : t;
                float py = o[1] + tt * dir[1];
                if (py <= sr__terrain_y(d, o[0] + tt * dir[0], o[2] + tt * dir[2])) {
                    float a = prev, b = tt;
                    int it;
                    for (it = 0; it < 12; it++) { /* refine the crossing */
                        float m = 0.5f * (a + b);
                        if (o[1] + m * dir[1] <= sr__terrain_y(d, o[0] + m * dir[0], o[2] + m * dir[2])) b = m;
                        else a = m;
                    }
                    t = b;
                    hit = 1;
                    break;
                }
                prev = tt;
                if (tt >= t1) break;
            }
            if (!hit) continue;
            for (k = 0; k < 3; k++) P[k] = o[k] + t * dir[k];
            if (!sr_camera_depth(cam, P, &z) || !(z < fb->depth[pi]) || z < 0.0f) continue;
            {
                float e = 0.5f * d->spacing, N[3], V[3], kd[3], rgb[3];
                int l;
                N[0] = -(sr__terrain_y(d, P[0] + e, P[2]) - sr__terrain_y(d, P[0] - e, P[2])) / (2.0f * e);
                N[1] = 1.0f;
                N[2] = -(sr__terrain_y(d, P[0], P[2] + e) - sr__terrain_y(d, P[0], P[2] - e)) / (2.0f * e);
                sr__normalize(N);
                if (d->colors) {
                    sr__terrain_color(d, P[0], P[2], kd);
                } else {
                    memcpy(kd, d->material.diffuse, sizeof kd);
                }
                sr__view_dir(o, P, V);
                memcpy(rgb, d->material.emission, sizeof rgb);
                for (l = 0; l < nl; l++) sr__shade_light(&d->material, kd, d->colors ? kd : d->material.ambient, &lights[l], P, N, V, 1.0f, spec_cut, rgb);
                fb->depth[pi] = z;
                fb->color[4 * pi] = rgb[0]; fb->color[4 * pi + 1] = rgb[1]; fb->color[4 * pi + 2] = rgb[2];
                fb->color[4 * pi + 3] = 1.0f;
            }
        }
    return SR_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: volume ray marching (front-to-back compositing, Kajiya-Kay texels)
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_volume_desc_default(sr_volume_desc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    sr_material_default(&d->material);
    d->box_min[0] = d->box_min[1] = d->box_min[2] = -1.0f;
    d->box_max[0] = d->box_max[1] = d->box_max[2] = 1.0f;
}

/* transmittance from p toward the light, through the box */
static float sr__volume_shadow(const sr_volume_desc *d, const float p[3], const float L[3], float step)
{
    float t0, t1, tau = 0.0f, t;
    if (!sr__ray_box(p, L, d->box_min, d->box_max, &t0, &t1) || !(t1 + step > t1)) return 1.0f;
    for (t = t0 + 0.5f * step; t < t1; t += step) {
        float q[3];
        q[0] = p[0] + t * L[0]; q[1] = p[1] + t * L[1]; q[2] = p[2] + t * L[2];
        tau += d->density(d->user, q) * step;
        if (tau > 12.0f) return 0.0f;
    }
    return expf(-tau);
}

/* Kajiya & Kay 1989 for a fibre along T (any length): diffuse sin(T,L); specular
   (T.L T.V' + sin(T,L) sin(T,V'))^p with V' = -V */
static void sr__kajiya_kay(const float dir[3], const float L[3], const float V[3], float shininess, float *diff, float *spec)
{
    float T[3], tl, tv, sl, sv, c;
    memcpy(T, dir, sizeof T);
    sr__normalize(T);
    tl = sr__dot(T, L); tv = -sr__dot(T, V);
    sl = sqrtf(sr__clampf(1.0f - tl * tl, 0.0f, 1.0f));
    sv = sqrtf(sr__clampf(1.0f - tv * tv, 0.0f, 1.0f));
    *diff = sl;
    c = tl * tv + sl * sv;
    *spec = c > 0.0f ? powf(c, shininess) : 0.0f;
}

/* colour of one sample: ambient + diffuse + specular per light, with the direction model */
static void sr__volume_light(const sr_volume_desc *d, const sr_light *lights, int nl, const float p[3], const float V[3],
                             const float kd[3], const float dir[3], float shadow_step, float rgb[3])
{
    int l, k;
    memcpy(rgb, d->material.emission, 3 * sizeof(float));
    for (l = 0; l < nl; l++) {
        float L[3], diff = 1.0f, spec = 0.0f, vis = 1.0f;
        sr__light_dir(&lights[l], p, L);
        if (d->direction == SR_VOLUME_NORMAL) {
            float N[3], H[3], nh;
            memcpy(N, dir, sizeof N);
            sr__normalize(N);
            if (sr__dot(N, V) < 0.0f) { N[0] = -N[0]; N[1] = -N[1]; N[2] = -N[2]; }
            diff = sr__dot(N, L); if (diff < 0.0f) diff = 0.0f;
            H[0] = L[0] + V[0]; H[1] = L[1] + V[1]; H[2] = L[2] + V[2];
            sr__normalize(H);
            nh = sr__dot(N, H);
            spec = (diff > 0.0f && nh > 0.0f) ? powf(nh, d->material.shininess) : 0.0f;
        } else if (d->direction == SR_VOLUME_TANGENT) {
            sr__kajiya_kay(dir, L, V, d->material.shininess, &diff, &spec);
        }
        if (d->shadows) vis = sr__volume_shadow(d, p, L, shadow_step);
        for (k = 0; k < 3; k++)
            rgb[k] += lights[l].ambient[k] * kd[k] + vis * (lights[l].diffuse[k] * kd[k] * diff + lights[l].specular[k] * d->material.specular[k] * spec);
    }
}

/* a ray ends at the opaque surface of depth D: ndc z(t) = (cz0 + t cz1) / (cw0 + t cw1) = 2D - 1 */
static void sr__depth_limit(const float *m, const float o[3], const float dir[3], float D, float *t1)
{
    float cz0 = m[2] * o[0] + m[6] * o[1] + m[10] * o[2] + m[14], cz1 = m[2] * dir[0] + m[6] * dir[1] + m[10] * dir[2];
    float cw0 = m[3] * o[0] + m[7] * o[1] + m[11] * o[2] + m[15], cw1 = m[3] * dir[0] + m[7] * dir[1] + m[11] * dir[2];
    float nd = 2.0f * D - 1.0f, den = cz1 - nd * cw1;
    if (den != 0.0f) { float ts = (nd * cw0 - cz0) / den; if (ts < *t1) *t1 = ts; }
}

SRDEF sr_result sr_draw_volume(sr_framebuffer *fb, const sr_camera *cam, const sr_volume_desc *d)
{
    float step, sstep, thr, term, diag[3];
    sr_light head;
    const sr_light *lights;
    int nl, x, y;
    const float *m;
    if (!fb || !fb->color || !cam || !d || !d->density || !sr__camera_ok(cam)) return SR_ERR_INVALID_ARGUMENT;
    sr__sub(d->box_max, d->box_min, diag);
    if (!(diag[0] > 0.0f && diag[1] > 0.0f && diag[2] > 0.0f) || !sr__finite3(d->box_min) || !sr__finite3(d->box_max) ||
        !(d->step >= 0.0f && d->step < 1e30f) || !(d->shadow_step >= 0.0f && d->shadow_step < 1e30f))
        return SR_ERR_INVALID_ARGUMENT;
    if (!sr__finite3(diag)) return SR_ERR_NOT_FINITE;
    step = d->step > 0.0f ? d->step : sqrtf(sr__dot(diag, diag)) / 256.0f;
    sstep = d->shadow_step > 0.0f ? d->shadow_step : 2.0f * step;
    thr = d->depth_threshold > 0.0f ? d->depth_threshold : 0.5f;
    term = d->termination > 0.0f ? d->termination : 0.995f;
    lights = sr__lights(d->lights, d->light_count, cam, &head, &nl);
    m = cam->viewproj;
    for (y = 0; y < fb->height; y++)
        for (x = 0; x < fb->width; x++) {
            float o[3], dir[3], V[3], t0, t1, t, acc[3] = {0.0f, 0.0f, 0.0f}, A = 0.0f, zhit = 2.0f;
            size_t i = (size_t)y * (size_t)fb->width + (size_t)x;
            float D = fb->depth[i];
            int k;
            sr_camera_ray(cam, fb->width, fb->height, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            if (!sr__ray_box(o, dir, d->box_min, d->box_max, &t0, &t1)) continue;
            if (D < 1.0f) sr__depth_limit(m, o, dir, D, &t1);
            if (!(t1 + step > t1)) continue; /* a step under t1's ulp would never end */
            V[0] = -dir[0]; V[1] = -dir[1]; V[2] = -dir[2];
            for (t = t0 + 0.5f * step; t < t1; t += step) {
                float p[3], sigma, alpha, rgb[3], kd[3], sdir[3] = {0.0f, 0.0f, 1.0f};
                for (k = 0; k < 3; k++) p[k] = o[k] + t * dir[k];
                sigma = d->density(d->user, p);
                if (!(sigma > 0.0f)) continue;
                alpha = 1.0f - expf(-sigma * step);
                if (d->shade) d->shade(d->user, p, kd, sdir);
                else memcpy(kd, d->material.diffuse, sizeof kd);
                sr__volume_light(d, lights, nl, p, V, kd, sdir, sstep, rgb);
                for (k = 0; k < 3; k++) acc[k] += (1.0f - A) * alpha * rgb[k];
                A += (1.0f - A) * alpha;
                if (zhit > 1.0f && A >= thr) { float z; if (sr_camera_depth(cam, p, &z)) zhit = z; }
                if (A >= term) break;
            }
            if (A <= 0.0f) continue;
            for (k = 0; k < 3; k++) fb->color[4 * i + (size_t)k] = acc[k] + (1.0f - A) * fb->color[4 * i + (size_t)k];
            fb->color[4 * i + 3] = A + (1.0f - A) * fb->color[4 * i + 3];
            if (zhit < fb->depth[i]) fb->depth[i] = zhit;
        }
    return SR_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: shell marcher (a volumetric layer over a height field, tiled, content by callback)
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_shell_desc_default(sr_shell_desc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    sr_material_default(&d->material);
    d->spacing = 1.0f;
    d->tile = 1.0f;
    d->tiles_x = d->tiles_y = 1;
    d->ground_rgb[0] = 0.30f; d->ground_rgb[1] = 0.22f; d->ground_rgb[2] = 0.14f;
}

typedef struct sr__shell {
    const sr_shell_desc *d;
    const sr_light *lights;
    int nl;
    float thickness, lo[3], hi[3];  /* the layer's box */
    float slope;                    /* a bound on |grad h| (for skipping above the layer) */
    float pixel_angle, pixel_size;  /* footprint = distance * angle (perspective) or size (ortho) */
    long samples;
} sr__shell;

/* the ground's height at (x, y) and its gradient, bilinear, clamped at the borders */
static float sr__shell_height(const sr_shell_desc *d, float x, float y, float *gx, float *gy)
{
    float fx, fy, h00, h10, h01, h11, inv;
    int i, j;
    if (!d->heights) { *gx = *gy = 0.0f; return 0.0f; }
    inv = 1.0f / d->spacing;
    fx = sr__clampf((x - d->origin[0]) * inv, 0.0f, (float)(d->nx - 1) - 1e-3f);
    fy = sr__clampf((y - d->origin[1]) * inv, 0.0f, (float)(d->ny - 1) - 1e-3f);
    i = (int)fx; j = (int)fy; fx -= (float)i; fy -= (float)j;
    h00 = d->heights[(size_t)j * (size_t)d->nx + (size_t)i]; h10 = d->heights[(size_t)j * (size_t)d->nx + (size_t)i + 1];
    h01 = d->heights[(size_t)(j + 1) * (size_t)d->nx + (size_t)i]; h11 = d->heights[(size_t)(j + 1) * (size_t)d->nx + (size_t)i + 1];
    *gx = ((h10 - h00) * (1 - fy) + (h11 - h01) * fy) * inv;
    *gy = ((h01 - h00) * (1 - fx) + (h11 - h10) * fx) * inv;
    return (h00 * (1 - fx) + h10 * fx) * (1 - fy) + (h01 * (1 - fx) + h11 * fx) * fy;
}

/* checks the description and finds the layer's box and slope bound; 0 if invalid */
SRDEF float sr_shell_height(const sr_shell_desc *d, float x, float y, float grad[2])
{
    float g[2], h;
    if (!d || (d->heights && (d->nx < 2 || d->ny < 2 || !(d->spacing > 0.0f)))) { if (grad) grad[0] = grad[1] = 0.0f; return 0.0f; }
    h = sr__shell_height(d, x, y, &g[0], &g[1]);
    if (grad) { grad[0] = g[0]; grad[1] = g[1]; }
    return h;
}

static int sr__shell_init(sr__shell *S, const sr_shell_desc *d, const sr_camera *cam, int height)
{
    size_t i, n;
    int x, y;
    memset(S, 0, sizeof *S);
    S->d = d;
    if (!d->sample || !(d->tile > 0.0f) || d->tiles_x < 1 || d->tiles_y < 1 || !(d->thickness >= 0.0f) ||
        !(d->origin[0] - d->origin[0] == 0.0f && d->origin[1] - d->origin[1] == 0.0f) ||
        !(d->tile * (float)d->tiles_x < 1e30f && d->tile * (float)d->tiles_y < 1e30f))
        return 0;
    S->thickness = d->thickness > 0.0f ? d->thickness : d->tile;
    S->lo[0] = d->origin[0]; S->lo[1] = d->origin[1];
    S->hi[0] = d->origin[0] + d->tile * (float)d->tiles_x; S->hi[1] = d->origin[1] + d->tile * (float)d->tiles_y;
    S->lo[2] = 0.0f; S->hi[2] = 0.0f;
    if (d->heights) {
        if (d->nx < 2 || d->ny < 2 || !(d->spacing > 0.0f) || (size_t)d->nx > ((size_t)-1) / sizeof(float) / (size_t)d->ny) return 0;
        n = (size_t)d->nx * (size_t)d->ny;
        S->lo[2] = S->hi[2] = d->heights[0];
        for (i = 0; i < n; i++) {
            float h = d->heights[i];
            if (!(h - h == 0.0f)) return 0;
            if (h < S->lo[2]) S->lo[2] = h;
            if (h > S->hi[2]) S->hi[2] = h;
        }
        for (y = 0; y < d->ny; y++)
            for (x = 0; x < d->nx; x++) {
                const float *h = d->heights + (size_t)y * (size_t)d->nx + (size_t)x;
                if (x + 1 < d->nx && fabsf(h[1] - h[0]) > S->slope) S->slope = fabsf(h[1] - h[0]);
                if (y + 1 < d->ny && fabsf(h[d->nx] - h[0]) > S->slope) S->slope = fabsf(h[d->nx] - h[0]);
            }
        S->slope = 1.5f * S->slope / d->spacing; /* bilinear patches: |grad| <= sqrt(2) max difference */
    }
    S->lo[2] -= 1e-3f * d->tile;
    S->hi[2] += S->thickness;
    S->pixel_angle = cam->orthographic ? 0.0f : 2.0f * cam->tan_half_fovy / (float)height;
    S->pixel_size = cam->orthographic ? 2.0f * cam->half_height / (float)height : 0.0f;
    return 1;
}

/* Lambert for a ground of colour g with normal N (normalised here) */
static void sr__ground_lambert(const sr_light *lights, int nl, const float g[3], float N[3], const float p[3], float rgb[3])
{
    int l, k;
    sr__normalize(N);
    memset(rgb, 0, 3 * sizeof(float));
    for (l = 0; l < nl; l++) {
        float L[3], ndl;
        sr__light_dir(&lights[l], p, L);
        ndl = sr__dot(N, L);
        if (ndl < 0.0f) ndl = 0.0f;
        for (k = 0; k < 3; k++) rgb[k] += g[k] * (lights[l].ambient[k] + lights[l].diffuse[k] * ndl);
    }
}

/* Lambert for the ground with normal (-gx, -gy, 1) */
static void sr__shell_ground(const sr__shell *S, const float p[3], float gx, float gy, float rgb[3])
{
    float N[3] = {-gx, -gy, 1.0f};
    sr__ground_lambert(S->lights, S->nl, S->d->ground_rgb, N, p, rgb);
}

/* a layer sample's colour from its world tangent T and normal N: Kajiya-Kay with the tangent,
   two-sided Lambert with the normal, or isotropic; light 0 scaled by the sample's light */
static void sr__layer_light(const sr_material *m, const sr_light *lights, int nl, const sr_shell_sample *s, float T[3],
                            float N[3], const float p[3], const float V[3], float rgb[3])
{
    int l, k, mode = 0;
    if (sr__dot(T, T) > 1e-12f) mode = 2;
    else if (sr__dot(N, N) > 1e-12f) { mode = 1; sr__normalize(N); if (sr__dot(N, V) < 0.0f) { N[0] = -N[0]; N[1] = -N[1]; N[2] = -N[2]; } }
    memcpy(rgb, m->emission, 3 * sizeof(float));
    for (l = 0; l < nl; l++) {
        float L[3], diff = 1.0f, spec = 0.0f, vis = l == 0 ? sr__clampf(s->light, 0.0f, 1.0f) : 1.0f;
        sr__light_dir(&lights[l], p, L);
        if (mode == 2) sr__kajiya_kay(T, L, V, m->shininess, &diff, &spec);
        else if (mode == 1) {
            float H[3], nh;
            diff = sr__dot(N, L); if (diff < 0.0f) diff = 0.0f;
            H[0] = L[0] + V[0]; H[1] = L[1] + V[1]; H[2] = L[2] + V[2];
            sr__normalize(H);
            nh = sr__dot(N, H);
            spec = (diff > 0.0f && nh > 0.0f) ? powf(nh, m->shininess) : 0.0f;
        }
        for (k = 0; k < 3; k++)
            rgb[k] += lights[l].ambient[k] * s->rgb[k] +
                      vis * (lights[l].diffuse[k] * s->rgb[k] * diff + lights[l].specular[k] * m->specular[k] * s->specular * spec);
    }
}

/* one sample's colour: its frame turned back to the world (the shear's inverse), then lit */
static void sr__shell_light(const sr__shell *S, const sr_shell_sample *s, const float p[3], const float V[3], float gx,
                            float gy, float rgb[3])
{
    float T[3], N[3];
    T[0] = s->tangent[0]; T[1] = s->tangent[1]; T[2] = s->tangent[2] + gx * s->tangent[0] + gy * s->tangent[1];
    N[0] = s->normal[0] + gx * s->normal[2]; N[1] = s->normal[1] + gy * s->normal[2]; N[2] = s->normal[2];
    sr__layer_light(&S->d->material, S->lights, S->nl, s, T, N, p, V, rgb);
}

/* the tile of world point p and the point in its frame; dir's image in the frame (unit) and
   the frame's length per world unit along dir */
static float sr__shell_frame(const sr__shell *S, const float p[3], const float dir[3], float zrel, float gx, float gy,
                             sr_shell_query *q)
{
    const sr_shell_desc *d = S->d;
    float fx = (p[0] - d->origin[0]) / d->tile, fy = (p[1] - d->origin[1]) / d->tile, len;
    int i = (int)floorf(sr__clampf(fx, -1.0f, (float)d->tiles_x)), j = (int)floorf(sr__clampf(fy, -1.0f, (float)d->tiles_y));
    if (i < 0) i = 0;
    if (j < 0) j = 0;
    if (i >= d->tiles_x) i = d->tiles_x - 1;
    if (j >= d->tiles_y) j = d->tiles_y - 1;
    q->tile_x = i; q->tile_y = j;
    q->p[0] = sr__clampf(fx - (float)i, 0.0f, 0.99999994f);
    q->p[1] = sr__clampf(fy - (float)j, 0.0f, 0.99999994f);
    q->p[2] = zrel / d->tile;
    q->dir[0] = dir[0]; q->dir[1] = dir[1]; q->dir[2] = dir[2] - gx * dir[0] - gy * dir[1];
    len = sqrtf(sr__dot(q->dir, q->dir));
    q->dir[0] /= len; q->dir[1] /= len; q->dir[2] /= len;
    return len / d->tile;
}

typedef struct sr__shell_ray { float rgb[3], T, layer_T, depth_t; } sr__shell_ray;

/* t += dt, or 0 when that does not move t (a step under t's ulp, far from the eye, or NaN): the
   ray ends there rather than looping forever */
static int sr__advance(float *t, float dt)
{
    float n = *t + dt;
    if (!(n > *t)) return 0;
    *t = n;
    return 1;
}

/* Marches one ray over [t0, t1]: above the layer it jumps to where the layer could begin (the
   slope bound), in it the callback's steps (or its empty-space skips) composite front to back,
   and the ground ends the ray. */
static void sr__shell_trace(sr__shell *S, const float o[3], const float dir[3], float t0, float t1, sr__shell_ray *r)
{
    const sr_shell_desc *d = S->d;
    float t = t0, term = d->termination > 0.0f ? 1.0f - d->termination : 0.01f, V[3], min_step = d->tile / 4096.0f;
    float horiz = sqrtf(dir[0] * dir[0] + dir[1] * dir[1]);
    int after_empty = 1;
    V[0] = -dir[0]; V[1] = -dir[1]; V[2] = -dir[2];
    r->rgb[0] = r->rgb[1] = r->rgb[2] = 0.0f;
    r->T = r->layer_T = 1.0f;
    r->depth_t = -1.0f;
    while (t < t1 && r->T > term) {
        float p[3], gx, gy, zrel, per_world, alpha, c[3], step;
        sr_shell_query q;
        sr_shell_sample s;
        int k;
        for (k = 0; k < 3; k++) p[k] = o[k] + t * dir[k];
        zrel = p[2] - sr__shell_height(d, p[0], p[1], &gx, &gy);
        if (zrel < 0.0f) { /* the ground */
            sr__shell_ground(S, p, gx, gy, c);
            for (k = 0; k < 3; k++) r->rgb[k] += r->T * c[k];
            r->T = 0.0f;
            if (r->depth_t < 0.0f) r->depth_t = t;
            return;
        }
        if (zrel >= S->thickness) { /* above the layer: the nearest it can be */
            float gap = (zrel - S->thickness) / (fabsf(dir[2]) + S->slope * horiz + 1e-6f);
            if (!sr__advance(&t, gap > min_step ? gap : min_step)) return;
            after_empty = 1;
            continue;
        }
        per_world = sr__shell_frame(S, p, dir, zrel, gx, gy, &q);
        q.footprint = (S->pixel_angle * t + S->pixel_size) / d->tile;
        q.after_empty = after_empty;
        memset(&s, 0, sizeof s);
        s.light = 1.0f;
        d->sample(d->user, &q, &s);
        S->samples++;
        step = s.step > 0.0f ? s.step : 1.0f / 256.0f;
        if (!(s.sigma > 0.0f)) { /* an empty span ends at the tile's border: the next tile's content may differ */
            for (k = 0; k < 2; k++) {
                float to_border = q.dir[k] > 0.0f ? (1.0f - q.p[k]) / q.dir[k] : q.dir[k] < 0.0f ? -q.p[k] / q.dir[k] : 1e30f;
                if (to_border + 1.0f / 4096.0f < step) step = to_border + 1.0f / 4096.0f;
            }
            if (!sr__advance(&t, fmaxf(step / per_world, min_step))) return;
            after_empty = 1;
            continue;
        }
        if (!sr__advance(&t, fmaxf(step / per_world, min_step))) return;
        after_empty = 0;
        alpha = 1.0f - expf(-s.sigma * step);
        sr__shell_light(S, &s, p, V, gx, gy, c);
        for (k = 0; k < 3; k++) r->rgb[k] += r->T * alpha * c[k];
        r->T *= 1.0f - alpha;
        r->layer_T *= 1.0f - alpha;
        if (r->depth_t < 0.0f && 1.0f - r->T >= (d->depth_threshold > 0.0f ? d->depth_threshold : 0.5f)) r->depth_t = t;
    }
}

SRDEF sr_result sr_draw_shell(sr_framebuffer *fb, const sr_camera *cam, const sr_shell_desc *d, sr_shell_stats *stats)
{
    sr__shell S;
    sr_light head;
    long covered = 0;
    int x, y;
    if (stats) memset(stats, 0, sizeof *stats);
    if (!fb || !fb->color || !cam || !d || !sr__camera_ok(cam) || !sr__shell_init(&S, d, cam, fb->height))
        return SR_ERR_INVALID_ARGUMENT;
    S.lights = sr__lights(d->lights, d->light_count, cam, &head, &S.nl);
    for (y = 0; y < fb->height; y++) {
        for (x = 0; x < fb->width; x++) {
            float o[3], dir[3], t0, t1, z;
            size_t i = (size_t)y * (size_t)fb->width + (size_t)x;
            sr__shell_ray r;
            int k;
            sr_camera_ray(cam, fb->width, fb->height, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            if (!sr__ray_box(o, dir, S.lo, S.hi, &t0, &t1)) continue;
            if (fb->depth[i] < 1.0f) sr__depth_limit(cam->viewproj, o, dir, fb->depth[i], &t1);
            sr__shell_trace(&S, o, dir, t0, t1, &r);
            if (r.T >= 1.0f) continue;
            if (r.layer_T <= 0.5f) covered++;
            if (r.depth_t >= 0.0f) {
                float p[3];
                for (k = 0; k < 3; k++) p[k] = o[k] + r.depth_t * dir[k];
                if (sr_camera_depth(cam, p, &z) && z < fb->depth[i]) fb->depth[i] = z;
            }
            for (k = 0; k < 3; k++) fb->color[4 * i + (size_t)k] = r.rgb[k] + r.T * fb->color[4 * i + (size_t)k];
            fb->color[4 * i + 3] = 1.0f - r.T * (1.0f - fb->color[4 * i + 3]);
        }
        if (d->progress && d->progress(d->progress_user, (float)(y + 1) / (float)fb->height)) return SR_CANCELLED;
    }
    if (stats) { stats->covered = covered; stats->samples = S.samples; }
    return SR_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: mesh shell marcher (prisms over a triangle mesh, split into tetrahedra, walked)
   --------------------------------------------------------------------------------------------- */

SRDEF void sr_mesh_shell_desc_default(sr_mesh_shell_desc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    sr_material_default(&d->material);
    d->ground_rgb[0] = 0.30f; d->ground_rgb[1] = 0.22f; d->ground_rgb[2] = 0.14f;
}

typedef struct sr__mtet {
    float o[3], M[9];   /* world -> barycentric coordinates 1..3 (about vertex 0) */
    float u0[3], J[9];  /* world -> the content's frame (u, v, w depth) */
    float Ji[9];        /* frame -> world (tangents) */
    float scale;        /* frame units per world unit across the surface (footprints) */
    int folded;         /* the map turns orientation against the prism's: content skipped */
    int32_t nb[4];      /* across face k (opposite vertex k): 4 tet + its face; -1 inner, -2 outer, -3 side */
    uint32_t v[4];      /* shell vertex ids: a mesh vertex, or vertex_count + it for its offset copy */
} sr__mtet;

typedef struct sr__mface { float a[3], e1[3], e2[3], g[3]; uint32_t v[3]; int32_t id; int inner; } sr__mface;
typedef struct sr__mnode { float lo[3], hi[3]; int32_t first, count; } sr__mnode; /* count 0: children node + 1, first */
typedef struct sr__mkey { uint32_t v[3]; int32_t id; } sr__mkey;
typedef struct sr__mpair { float key; int32_t i; } sr__mpair;

typedef struct sr__mshell {
    const sr_mesh_shell_desc *d;
    sr_allocator a;
    sr__mtet *tets;
    size_t ntets, nfaces, nnodes;
    sr__mface *faces;
    sr__mnode *nodes;
    const sr_light *lights;
    int nl;
    float depth, tol, min_step, pixel_angle, pixel_size;
    long samples;
} sr__mshell;

static int sr__mkey_cmp(const void *pa, const void *pb)
{
    const sr__mkey *a = (const sr__mkey *)pa, *b = (const sr__mkey *)pb;
    int k;
    for (k = 0; k < 3; k++) if (a->v[k] != b->v[k]) return a->v[k] < b->v[k] ? -1 : 1;
    return a->id < b->id ? -1 : a->id > b->id;
}

static int sr__mpair_cmp(const void *pa, const void *pb)
{
    const sr__mpair *a = (const sr__mpair *)pa, *b = (const sr__mpair *)pb;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return a->i < b->i ? -1 : a->i > b->i;
}

static double sr__det3d(const double m[9])
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* r = m^-1 (row-major); 0 if m is singular */
static int sr__inv3d(const double m[9], double r[9])
{
    double det = sr__det3d(m), id;
    int k;
    if (!(det != 0.0)) return 0;
    id = 1.0 / det;
    r[0] = (m[4] * m[8] - m[5] * m[7]) * id; r[1] = (m[2] * m[7] - m[1] * m[8]) * id; r[2] = (m[1] * m[5] - m[2] * m[4]) * id;
    r[3] = (m[5] * m[6] - m[3] * m[8]) * id; r[4] = (m[0] * m[8] - m[2] * m[6]) * id; r[5] = (m[2] * m[3] - m[0] * m[5]) * id;
    r[6] = (m[3] * m[7] - m[4] * m[6]) * id; r[7] = (m[1] * m[6] - m[0] * m[7]) * id; r[8] = (m[0] * m[4] - m[1] * m[3]) * id;
    for (k = 0; k < 9; k++) if (!(r[k] - r[k] == 0.0) || fabs(r[k]) > 1e30) return 0;
    return 1;
}

static void sr__mul3d(const double a[9], const double b[9], float r[9])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) r[i * 3 + j] = (float)(a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j]);
}

/* shell vertex v (v < n: the mesh; else offset by height along the unit normal), world and frame */
static void sr__mshell_vertex(const sr__mshell *S, uint32_t v, double x[3], double u[3])
{
    const sr_mesh_shell_desc *d = S->d;
    uint32_t n = (uint32_t)d->vertex_count, m = v < n ? v : v - n;
    const float *p = d->positions + 3 * (size_t)m, *nr = d->normals + 3 * (size_t)m;
    double l = sqrt((double)nr[0] * nr[0] + (double)nr[1] * nr[1] + (double)nr[2] * nr[2]), h = v < n ? 0.0 : d->height / l;
    int k;
    for (k = 0; k < 3; k++) x[k] = (double)p[k] + h * nr[k];
    u[0] = d->uvs[2 * (size_t)m]; u[1] = d->uvs[2 * (size_t)m + 1]; u[2] = v < n ? 0.0 : S->depth;
}

/* one tetrahedron's maps (orient: the sign its map's determinant must have, the triangle's
   winding about its normals times its uv winding); 0 if it is singular in the world or frame */
static int sr__mshell_tet(const sr__mshell *S, const uint32_t ids[4], float scale, int orient, sr__mtet *T)
{
    double x[4][3], u[4][3], A[9], B[9], Ai[9], Bi[9];
    int k, r;
    for (k = 0; k < 4; k++) sr__mshell_vertex(S, ids[k], x[k], u[k]);
    for (r = 0; r < 3; r++)
        for (k = 0; k < 3; k++) { A[r * 3 + k] = x[k + 1][r] - x[0][r]; B[r * 3 + k] = u[k + 1][r] - u[0][r]; }
    if (!sr__inv3d(A, Ai) || !sr__inv3d(B, Bi)) return 0;
    T->folded = (sr__det3d(A) > 0.0) == (sr__det3d(B) > 0.0) ? orient <= 0 : orient >= 0;
    for (k = 0; k < 3; k++) { T->o[k] = (float)x[0][k]; T->u0[k] = (float)u[0][k]; }
    for (k = 0; k < 9; k++) T->M[k] = (float)Ai[k];
    sr__mul3d(B, Ai, T->J);
    { /* nearly folded: a gain over 16 times the prism's own (across, scale; up, depth / height) */
        float g2 = 0.0f, nominal = scale > S->depth / S->d->height ? scale : S->depth / S->d->height;
        for (k = 0; k < 9; k++) g2 += T->J[k] * T->J[k];
        if (!(g2 <= 3.0f * 256.0f * nominal * nominal)) T->folded = 1;
    }
    sr__mul3d(A, Bi, T->Ji);
    T->scale = scale;
    memcpy(T->v, ids, sizeof T->v);
    return 1;
}

/* checks the mesh, builds 3 tetrahedra per prism (the side faces split by the vertex order, as
   texel.h's tvt_shell_prism_tets does) and finds the mean edge length; 0 if invalid */
static int sr__mshell_tets(sr__mshell *S, double *mean_edge)
{
    const sr_mesh_shell_desc *d = S->d;
    uint32_t n = (uint32_t)d->vertex_count;
    size_t t, i;
    double edges = 0.0;
    for (i = 0; i < d->vertex_count; i++) {
        const float *p = d->positions + 3 * i, *nr = d->normals + 3 * i;
        if (!sr__finite3(p) || !sr__finite3(nr) || !(d->uvs[2 * i] - d->uvs[2 * i] == 0.0f) ||
            !(d->uvs[2 * i + 1] - d->uvs[2 * i + 1] == 0.0f) || !(sr__dot(nr, nr) > 0.0f)) return 0;
    }
    for (t = 0; t < d->triangle_count; t++) {
        const uint32_t *tri = d->indices + 3 * t;
        uint32_t a = tri[0], b = tri[1], c = tri[2], s, ids[3][4];
        double x[3][3], u[3][3], e1[3], e2[3], cr[3], aw, au, cu, ns = 0.0;
        int k, orient;
        if (a >= n || b >= n || c >= n || a == b || b == c || a == c) return 0;
        for (k = 0; k < 3; k++) sr__mshell_vertex(S, tri[k], x[k], u[k]);
        for (k = 0; k < 3; k++) { e1[k] = x[1][k] - x[0][k]; e2[k] = x[2][k] - x[0][k]; }
        cr[0] = e1[1] * e2[2] - e1[2] * e2[1]; cr[1] = e1[2] * e2[0] - e1[0] * e2[2]; cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
        aw = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        cu = (u[1][0] - u[0][0]) * (u[2][1] - u[0][1]) - (u[1][1] - u[0][1]) * (u[2][0] - u[0][0]);
        au = fabs(cu);
        for (k = 0; k < 3; k++) {
            const float *nr = d->normals + 3 * (size_t)tri[k];
            ns += cr[0] * nr[0] + cr[1] * nr[1] + cr[2] * nr[2];
        }
        orient = (ns > 0.0 ? 1 : ns < 0.0 ? -1 : 0) * (cu > 0.0 ? 1 : -1);
        edges += sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]) + sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
        if (!(aw > 0.0) || !(au > 0.0)) return 0;
        if (a > b) { s = a; a = b; b = s; }
        if (b > c) { s = b; b = c; c = s; }
        if (a > b) { s = a; a = b; b = s; }
        ids[0][0] = a; ids[0][1] = b;     ids[0][2] = c;     ids[0][3] = c + n;
        ids[1][0] = a; ids[1][1] = b;     ids[1][2] = b + n; ids[1][3] = c + n;
        ids[2][0] = a; ids[2][1] = a + n; ids[2][2] = b + n; ids[2][3] = c + n;
        for (k = 0; k < 3; k++)
            if (!sr__mshell_tet(S, ids[k], (float)sqrt(au / aw), orient, &S->tets[3 * t + (size_t)k])) return 0;
    }
    *mean_edge = edges / (2.0 * (double)d->triangle_count);
    return 1;
}

/* neighbours across the faces (faces keyed by their sorted vertex ids); the boundary faces
   into S->faces; 0 if out of memory */
static int sr__mshell_links(sr__mshell *S)
{
    size_t nk = 4 * S->ntets, i, j;
    uint32_t n = (uint32_t)S->d->vertex_count;
    sr__mkey *keys = (sr__mkey *)sr__alloc(&S->a, nk * sizeof(sr__mkey));
    if (!keys) return 0;
    for (i = 0; i < nk; i++) {
        const uint32_t *v = S->tets[i / 4].v;
        uint32_t f[3], s;
        int k, m = 0;
        for (k = 0; k < 4; k++) if (k != (int)(i % 4)) f[m++] = v[k];
        if (f[0] > f[1]) { s = f[0]; f[0] = f[1]; f[1] = s; }
        if (f[1] > f[2]) { s = f[1]; f[1] = f[2]; f[2] = s; }
        if (f[0] > f[1]) { s = f[0]; f[0] = f[1]; f[1] = s; }
        memcpy(keys[i].v, f, sizeof f);
        keys[i].id = (int32_t)i;
    }
    qsort(keys, nk, sizeof(sr__mkey), sr__mkey_cmp);
    S->nfaces = 0;
    for (i = 0; i < nk; i = j) {
        int32_t a = keys[i].id;
        j = i + 1;
        if (j < nk && !memcmp(keys[j].v, keys[i].v, sizeof keys[i].v)) {
            int32_t b = keys[j].id;
            S->tets[a / 4].nb[a % 4] = b;
            S->tets[b / 4].nb[b % 4] = a;
            j++;
            for (; j < nk && !memcmp(keys[j].v, keys[i].v, sizeof keys[i].v); j++) /* a non-manifold rest: a wall */
                S->tets[keys[j].id / 4].nb[keys[j].id % 4] = -3;
        } else {
            int inner = keys[i].v[2] < n, outer = keys[i].v[0] >= n;
            S->tets[a / 4].nb[a % 4] = inner ? -1 : outer ? -2 : -3;
            keys[S->nfaces++] = keys[i];
        }
    }
    S->faces = (sr__mface *)sr__alloc(&S->a, S->nfaces * sizeof(sr__mface));
    if (!S->faces) { S->a.free(S->a.user, keys); return 0; }
    for (i = 0; i < S->nfaces; i++) {
        sr__mface *F = &S->faces[i];
        const sr__mtet *T = &S->tets[keys[i].id / 4];
        int k = keys[i].id % 4, c;
        double x[3][3], u[3];
        for (c = 0; c < 3; c++) sr__mshell_vertex(S, keys[i].v[c], x[c], u);
        for (c = 0; c < 3; c++) {
            F->a[c] = (float)x[0][c]; F->e1[c] = (float)(x[1][c] - x[0][c]); F->e2[c] = (float)(x[2][c] - x[0][c]);
            F->g[c] = k > 0 ? T->M[3 * (k - 1) + c] : -(T->M[c] + T->M[3 + c] + T->M[6 + c]); /* grad lambda_k: inward */
        }
        memcpy(F->v, keys[i].v, sizeof F->v);
        F->id = keys[i].id;
        F->inner = keys[i].v[2] < n;
    }
    S->a.free(S->a.user, keys);
    return 1;
}

/* a BVH node over faces perm[first, first + count), median split on the longest centroid axis */
static int32_t sr__mshell_bvh(sr__mshell *S, int32_t *perm, sr__mpair *tmp, size_t first, size_t count)
{
    int32_t node = (int32_t)S->nnodes++;
    float clo[3] = {1e30f, 1e30f, 1e30f}, chi[3] = {-1e30f, -1e30f, -1e30f};
    sr__mnode *N = &S->nodes[node];
    size_t i;
    int k, axis = 0;
    for (k = 0; k < 3; k++) { N->lo[k] = 1e30f; N->hi[k] = -1e30f; }
    for (i = first; i < first + count; i++) {
        const sr__mface *F = &S->faces[perm[i]];
        for (k = 0; k < 3; k++) {
            float a = F->a[k], b = a + F->e1[k], c = a + F->e2[k], cen = (a + b + c) / 3.0f;
            N->lo[k] = fminf(N->lo[k], fminf(a, fminf(b, c))); N->hi[k] = fmaxf(N->hi[k], fmaxf(a, fmaxf(b, c)));
            clo[k] = fminf(clo[k], cen); chi[k] = fmaxf(chi[k], cen);
        }
    }
    if (count <= 4) { N->first = (int32_t)first; N->count = (int32_t)count; return node; }
    for (k = 1; k < 3; k++) if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    for (i = 0; i < count; i++) {
        const sr__mface *F = &S->faces[perm[first + i]];
        tmp[i].key = 3.0f * F->a[axis] + F->e1[axis] + F->e2[axis];
        tmp[i].i = perm[first + i];
    }
    qsort(tmp, count, sizeof(sr__mpair), sr__mpair_cmp);
    for (i = 0; i < count; i++) perm[first + i] = tmp[i].i;
    N->count = 0;
    sr__mshell_bvh(S, perm, tmp, first, count / 2);
    N = &S->nodes[node];
    N->first = sr__mshell_bvh(S, perm, tmp, first + count / 2, count - count / 2);
    return node;
}

/* the tetrahedra, their links, the boundary faces' BVH: 1, or 0 with *r set (all freed) */
static int sr__mshell_init(sr__mshell *S, const sr_mesh_shell_desc *d, const sr_camera *cam, int height, sr_result *r)
{
    double mean_edge = 0.0;
    int32_t *perm = NULL;
    sr__mpair *tmp = NULL;
    sr__mface *sorted = NULL;
    size_t i;
    memset(S, 0, sizeof *S);
    S->d = d;
    S->a = sr__resolve_allocator(d->allocator);
    *r = SR_ERR_INVALID_ARGUMENT;
    if (!d->positions || !d->normals || !d->uvs || !d->indices || !d->sample || d->vertex_count < 3 ||
        d->triangle_count < 1 || d->vertex_count > 0x3FFFFFFFu || d->triangle_count > 0x7FFFFFFFu / 12u ||
        !(d->height > 0.0f && d->height < 1e30f) || !(d->depth >= 0.0f && d->depth < 1e30f)) return 0;
    S->depth = d->depth > 0.0f ? d->depth : 1.0f;
    S->ntets = 3 * d->triangle_count;
    *r = SR_ERR_OUT_OF_MEMORY;
    S->tets = (sr__mtet *)sr__alloc(&S->a, S->ntets * sizeof(sr__mtet));
    if (!S->tets) return 0;
    *r = SR_ERR_INVALID_ARGUMENT;
    if (!sr__mshell_tets(S, &mean_edge)) goto fail;
    *r = SR_ERR_OUT_OF_MEMORY;
    if (!sr__mshell_links(S)) goto fail;
    S->nodes = (sr__mnode *)sr__alloc(&S->a, 2 * S->nfaces * sizeof(sr__mnode));
    perm = (int32_t *)sr__alloc(&S->a, S->nfaces * sizeof(int32_t));
    tmp = (sr__mpair *)sr__alloc(&S->a, S->nfaces * sizeof(sr__mpair));
    sorted = (sr__mface *)sr__alloc(&S->a, S->nfaces * sizeof(sr__mface));
    if (!S->nodes || !perm || !tmp || !sorted) goto fail;
    for (i = 0; i < S->nfaces; i++) perm[i] = (int32_t)i;
    sr__mshell_bvh(S, perm, tmp, 0, S->nfaces);
    for (i = 0; i < S->nfaces; i++) sorted[i] = S->faces[perm[i]];
    S->a.free(S->a.user, S->faces);
    S->faces = sorted;
    S->a.free(S->a.user, perm);
    S->a.free(S->a.user, tmp);
    S->tol = (float)(1e-5 * mean_edge);
    S->min_step = (float)(mean_edge / 4096.0);
    S->pixel_angle = cam->orthographic ? 0.0f : 2.0f * cam->tan_half_fovy / (float)height;
    S->pixel_size = cam->orthographic ? 2.0f * cam->half_height / (float)height : 0.0f;
    return 1;
fail:
    if (perm) S->a.free(S->a.user, perm);
    if (tmp) S->a.free(S->a.user, tmp);
    if (sorted) S->a.free(S->a.user, sorted);
    if (S->nodes) S->a.free(S->a.user, S->nodes);
    if (S->faces) S->a.free(S->a.user, S->faces);
    S->a.free(S->a.user, S->tets);
    return 0;
}

static void sr__mshell_free(sr__mshell *S)
{
    S->a.free(S->a.user, S->nodes);
    S->a.free(S->a.user, S->faces);
    S->a.free(S->a.user, S->tets);
}

/* the nearest boundary face in [tmin, tmax] the ray enters the shell by (or opaque ground); 0 if none */
static int sr__mshell_hit(const sr__mshell *S, const float o[3], const float dir[3], float tmin, float tmax,
                          float *th, const sr__mface **hit, float bary[2])
{
    int32_t stack[64];
    int sp = 0, k, found = 0;
    float inv[3], best = tmax;
    for (k = 0; k < 3; k++) inv[k] = dir[k] != 0.0f ? 1.0f / dir[k] : 1e30f;
    stack[sp++] = 0;
    while (sp > 0) {
        const sr__mnode *N = &S->nodes[stack[--sp]];
        float t0 = tmin, t1 = best;
        int32_t i;
        for (k = 0; k < 3; k++) {
            float a = (N->lo[k] - o[k]) * inv[k], b = (N->hi[k] - o[k]) * inv[k];
            if (a > b) { float s = a; a = b; b = s; }
            t0 = a > t0 ? a : t0; t1 = b < t1 ? b : t1;
        }
        if (t0 > t1 * 1.000001f + S->tol) continue;
        if (N->count == 0) {
            if (sp + 2 > 64) continue;
            stack[sp++] = N->first;
            stack[sp++] = (int32_t)(N - S->nodes) + 1;
            continue;
        }
        for (i = N->first; i < N->first + N->count; i++) {
            const sr__mface *F = &S->faces[i];
            float pv[3], tv[3], qv[3], det, id, u, v, t;
            sr__cross(dir, F->e2, pv);
            det = sr__dot(F->e1, pv);
            if (det == 0.0f) continue;
            id = 1.0f / det;
            sr__sub(o, F->a, tv);
            u = sr__dot(tv, pv) * id;
            if (u < -1e-6f || u > 1.000001f) continue;
            sr__cross(tv, F->e1, qv);
            v = sr__dot(dir, qv) * id;
            if (v < -1e-6f || u + v > 1.000001f) continue;
            t = sr__dot(F->e2, qv) * id;
            if (t < tmin || t >= best || !((F->inner && !S->d->see_through) || sr__dot(F->g, dir) > 0.0f)) continue;
            best = t; *hit = F; bary[0] = u; bary[1] = v; found = 1;
        }
    }
    *th = best;
    return found;
}

/* where a ray is in its tetrahedron: barycentric coordinates lam + (t' - t) b, and where it leaves */
typedef struct sr__mwalk { int32_t tet; int k_exit; float t, t_exit, lam[4], b[4]; } sr__mwalk;

static void sr__mwalk_set(const sr__mshell *S, sr__mwalk *w, int32_t tet, int entry, const float o[3], const float dir[3], float t)
{
    const sr__mtet *T = &S->tets[tet];
    float p[3], l[3];
    int k;
    for (k = 0; k < 3; k++) p[k] = o[k] + t * dir[k] - T->o[k];
    for (k = 0; k < 3; k++) {
        l[k] = T->M[3 * k] * p[0] + T->M[3 * k + 1] * p[1] + T->M[3 * k + 2] * p[2];
        w->b[k + 1] = T->M[3 * k] * dir[0] + T->M[3 * k + 1] * dir[1] + T->M[3 * k + 2] * dir[2];
        w->lam[k + 1] = l[k];
    }
    w->lam[0] = 1.0f - l[0] - l[1] - l[2];
    w->b[0] = -(w->b[1] + w->b[2] + w->b[3]);
    w->tet = tet; w->t = t; w->t_exit = 1e30f; w->k_exit = -1;
    for (k = 0; k < 4; k++)
        if (k != entry && w->b[k] < 0.0f) {
            float te = t + (w->lam[k] > 0.0f ? w->lam[k] : 0.0f) / -w->b[k];
            if (te < w->t_exit) { w->t_exit = te; w->k_exit = k; }
        }
}

/* the ground (the mesh) at p: Lambert with the normals of shell vertices v weighted by l, two-sided */
static void sr__mshell_ground(const sr__mshell *S, const uint32_t v[3], const float l[3], const float p[3],
                              const float V[3], sr__shell_ray *r, float t)
{
    const float *nr = S->d->normals;
    float N[3], c[3];
    int k;
    for (k = 0; k < 3; k++) N[k] = l[0] * nr[3 * (size_t)v[0] + k] + l[1] * nr[3 * (size_t)v[1] + k] + l[2] * nr[3 * (size_t)v[2] + k];
    if (sr__dot(N, V) < 0.0f) { N[0] = -N[0]; N[1] = -N[1]; N[2] = -N[2]; }
    sr__ground_lambert(S->lights, S->nl, S->d->ground_rgb, N, p, c);
    for (k = 0; k < 3; k++) r->rgb[k] += r->T * c[k];
    r->T = 0.0f;
    if (r->depth_t < 0.0f) r->depth_t = t;
}

/* the ground where the walk leaves its tetrahedron through the inner face */
static void sr__mshell_ground_exit(const sr__mshell *S, const sr__mwalk *w, const float o[3], const float dir[3],
                                   const float V[3], sr__shell_ray *r)
{
    const sr__mtet *T = &S->tets[w->tet];
    uint32_t v[3];
    float l[3], p[3];
    int k, m = 0;
    for (k = 0; k < 4; k++)
        if (k != w->k_exit) { v[m] = T->v[k]; l[m] = w->lam[k] + (w->t_exit - w->t) * w->b[k]; m++; }
    for (k = 0; k < 3; k++) p[k] = o[k] + w->t_exit * dir[k];
    sr__mshell_ground(S, v, l, p, V, r, w->t_exit);
}

/* the boundary face the ray enters by, after tmin: 1 with the walk set there, 0 if none or the
   ground (then shaded into r) */
static int sr__mshell_enter(const sr__mshell *S, sr__mwalk *w, const float o[3], const float dir[3], float tmin,
                            float tmax, const float V[3], sr__shell_ray *r)
{
    const sr__mface *F = NULL;
    float th, bary[2];
    if (!sr__mshell_hit(S, o, dir, tmin, tmax, &th, &F, bary)) return 0;
    if (F->inner && !S->d->see_through) {
        float l[3], p[3];
        int k;
        l[0] = 1.0f - bary[0] - bary[1]; l[1] = bary[0]; l[2] = bary[1];
        for (k = 0; k < 3; k++) p[k] = o[k] + th * dir[k];
        sr__mshell_ground(S, F->v, l, p, V, r, th);
        return 0;
    }
    sr__mwalk_set(S, w, F->id / 4, F->id % 4, o, dir, th);
    return 1;
}

/* one sample in the walk's tetrahedron at t: the content's query, its colour composited into r;
   returns the world distance to the next sample and whether it was empty */
static float sr__mshell_sample(sr__mshell *S, const sr__mwalk *w, const float o[3], const float dir[3], float t,
                               const float V[3], int *after_empty, sr__shell_ray *r)
{
    const sr_mesh_shell_desc *d = S->d;
    const sr__mtet *T = &S->tets[w->tet];
    float p[3], x[3], f[3], per_world, step, alpha, c[3], Tw[3], Nw[3], fu, fv;
    sr_shell_query q;
    sr_shell_sample s;
    int k;
    for (k = 0; k < 3; k++) { p[k] = o[k] + t * dir[k]; x[k] = p[k] - T->o[k]; }
    for (k = 0; k < 3; k++) {
        f[k] = T->J[3 * k] * x[0] + T->J[3 * k + 1] * x[1] + T->J[3 * k + 2] * x[2] + T->u0[k];
        q.dir[k] = T->J[3 * k] * dir[0] + T->J[3 * k + 1] * dir[1] + T->J[3 * k + 2] * dir[2];
    }
    per_world = sqrtf(sr__dot(q.dir, q.dir));
    for (k = 0; k < 3; k++) q.dir[k] /= per_world;
    fu = floorf(sr__clampf(f[0], -2e9f, 2e9f)); fv = floorf(sr__clampf(f[1], -2e9f, 2e9f));
    q.tile_x = (int)fu; q.tile_y = (int)fv;
    q.p[0] = sr__clampf(f[0] - fu, 0.0f, 0.99999994f);
    q.p[1] = sr__clampf(f[1] - fv, 0.0f, 0.99999994f);
    q.p[2] = sr__clampf(f[2], 0.0f, S->depth * 0.99999994f);
    q.footprint = (S->pixel_angle * t + S->pixel_size) * T->scale;
    q.after_empty = *after_empty;
    memset(&s, 0, sizeof s);
    s.light = 1.0f;
    d->sample(d->user, &q, &s);
    S->samples++;
    step = s.step > 0.0f ? s.step : 1.0f / 256.0f;
    *after_empty = !(s.sigma > 0.0f);
    if (*after_empty) { /* an empty span ends at the tile's border: the next tile's content may differ */
        for (k = 0; k < 2; k++) {
            float to_border = q.dir[k] > 0.0f ? (1.0f - q.p[k]) / q.dir[k] : q.dir[k] < 0.0f ? -q.p[k] / q.dir[k] : 1e30f;
            if (to_border + 1.0f / 4096.0f < step) step = to_border + 1.0f / 4096.0f;
        }
        return fmaxf(step / per_world, S->min_step);
    }
    alpha = 1.0f - expf(-s.sigma * step);
    if (S->nl > 0) { /* the mesh hides light 0 under the layer's local horizon (n: the w gradient) */
        float n[3] = {T->J[6], T->J[7], T->J[8]}, L[3];
        sr__normalize(n);
        sr__light_dir(&S->lights[0], p, L);
        s.light *= sr__clampf(5.0f * sr__dot(n, L) + 0.5f, 0.0f, 1.0f);
    }
    for (k = 0; k < 3; k++) { /* tangents by the inverse map, normals by its transpose */
        Tw[k] = T->Ji[3 * k] * s.tangent[0] + T->Ji[3 * k + 1] * s.tangent[1] + T->Ji[3 * k + 2] * s.tangent[2];
        Nw[k] = T->J[k] * s.normal[0] + T->J[3 + k] * s.normal[1] + T->J[6 + k] * s.normal[2];
    }
    sr__layer_light(&d->material, S->lights, S->nl, &s, Tw, Nw, p, V, c);
    for (k = 0; k < 3; k++) r->rgb[k] += r->T * alpha * c[k];
    r->T *= 1.0f - alpha;
    r->layer_T *= 1.0f - alpha;
    if (r->depth_t < 0.0f && 1.0f - r->T >= (d->depth_threshold > 0.0f ? d->depth_threshold : 0.5f)) r->depth_t = t;
    return fmaxf(step / per_world, S->min_step);
}

/* Marches one ray: enters the shell by its first boundary face, walks tetrahedron to tetrahedron
   (leaving through the outer surface or a side border it looks for the next entry), samples at
   the content's steps, and ends on the ground, at t1, or when opaque. */
static void sr__mshell_trace(sr__mshell *S, const float o[3], const float dir[3], float t1, sr__shell_ray *r)
{
    const sr_mesh_shell_desc *d = S->d;
    float term = d->termination > 0.0f ? 1.0f - d->termination : 0.01f, V[3], ts;
    sr__mwalk w;
    int after_empty = 1;
    long budget = 1L << 14, samples = 1L << 14;
    V[0] = -dir[0]; V[1] = -dir[1]; V[2] = -dir[2];
    r->rgb[0] = r->rgb[1] = r->rgb[2] = 0.0f;
    r->T = r->layer_T = 1.0f;
    r->depth_t = -1.0f;
    if (!sr__mshell_enter(S, &w, o, dir, 0.0f, t1, V, r)) return;
    ts = w.t;
    while (ts < t1 && r->T > term) {
        while (ts > w.t_exit) { /* walk to the tetrahedron that holds ts */
            int32_t nb = S->tets[w.tet].nb[w.k_exit];
            if (--budget < 0) return;
            if (nb >= 0) { sr__mwalk_set(S, &w, nb / 4, nb % 4, o, dir, w.t_exit); continue; }
            if (nb == -1 && !d->see_through) { sr__mshell_ground_exit(S, &w, o, dir, V, r); return; }
            if (!sr__mshell_enter(S, &w, o, dir, w.t_exit - S->tol, t1, V, r)) return;
            if (w.t > ts) { ts = w.t; after_empty = 1; }
        }
        if (ts >= t1 || w.k_exit < 0) break; /* no way out: a folded neighbour turned the walk back */
        if (S->tets[w.tet].folded) { /* skipped: its map is turned over, and its gain unbounded */
            ts = w.t_exit + fmaxf(S->tol, 1e-6f * fabsf(w.t_exit));
            after_empty = 1;
            continue;
        }
        if (--samples < 0 || !sr__advance(&ts, sr__mshell_sample(S, &w, o, dir, ts, V, &after_empty, r))) return;
    }
}

SRDEF sr_result sr_draw_mesh_shell(sr_framebuffer *fb, const sr_camera *cam, const sr_mesh_shell_desc *d,
                                   sr_shell_stats *stats)
{
    sr__mshell S;
    sr_light head;
    sr_result res;
    long covered = 0;
    int x, y;
    if (stats) memset(stats, 0, sizeof *stats);
    if (!fb || !fb->color || !cam || !d || !sr__camera_ok(cam)) return SR_ERR_INVALID_ARGUMENT;
    if (!sr__mshell_init(&S, d, cam, fb->height, &res)) return res;
    S.lights = sr__lights(d->lights, d->light_count, cam, &head, &S.nl);
    for (y = 0; y < fb->height; y++) {
        for (x = 0; x < fb->width; x++) {
            float o[3], dir[3], t1 = 1e30f, z;
            size_t i = (size_t)y * (size_t)fb->width + (size_t)x;
            sr__shell_ray r;
            int k;
            sr_camera_ray(cam, fb->width, fb->height, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            if (fb->depth[i] < 1.0f) sr__depth_limit(cam->viewproj, o, dir, fb->depth[i], &t1);
            sr__mshell_trace(&S, o, dir, t1, &r);
            if (r.T >= 1.0f) continue;
            if (r.layer_T <= 0.5f) covered++;
            if (r.depth_t >= 0.0f) {
                float p[3];
                for (k = 0; k < 3; k++) p[k] = o[k] + r.depth_t * dir[k];
                if (sr_camera_depth(cam, p, &z) && z < fb->depth[i]) fb->depth[i] = z;
            }
            for (k = 0; k < 3; k++) fb->color[4 * i + (size_t)k] = r.rgb[k] + r.T * fb->color[4 * i + (size_t)k];
            fb->color[4 * i + 3] = 1.0f - r.T * (1.0f - fb->color[4 * i + 3]);
        }
        if (d->progress && d->progress(d->progress_user, (float)(y + 1) / (float)fb->height)) {
            sr__mshell_free(&S);
            return SR_CANCELLED;
        }
    }
    sr__mshell_free(&S);
    if (stats) { stats->covered = covered; stats->samples = S.samples; }
    return SR_OK;
}

/* ---------------------------------------------------------------------------------------------
   Section: PNG encoder (zlib stream, fixed-Huffman deflate with greedy LZ77)
   --------------------------------------------------------------------------------------------- */

typedef struct sr__buf {
    uint8_t *data;
    size_t size, cap;
    sr_allocator a;
    int failed;
    uint32_t bits; /* bit accumulator for deflate, LSB first */
    int nbits;
} sr__buf;

static void sr__buf_reserve(sr__buf *b, size_t extra)
{
    size_t cap;
    uint8_t *p;
    if (b->failed) return;
    if (extra <= b->cap - b->size) return;
    cap = b->cap ? b->cap : 4096;
    while (cap - b->size < extra) {
        if (cap > ((size_t)-1) / 2) { b->failed = 1; return; }
        cap *= 2;
    }
    p = (uint8_t *)sr__alloc(&b->a, cap);
    if (!p) { b->failed = 1; return; }
    if (b->data) { memcpy(p, b->data, b->size); b->a.free(b->a.user, b->data); }
    b->data = p;
    b->cap = cap;
}

static void sr__put(sr__buf *b, const void *src, size_t n)
{
    sr__buf_reserve(b, n);
    if (b->failed) return;
    memcpy(b->data + b->size, src, n);
    b->size += n;
}

static void sr__put_u32be(sr__buf *b, uint32_t v)
{
    uint8_t s[4];
    s[0] = (uint8_t)(v >> 24); s[1] = (uint8_t)(v >> 16); s[2] = (uint8_t)(v >> 8); s[3] = (uint8_t)v;
    sr__put(b, s, 4);
}

static void sr__bits(sr__buf *b, uint32_t value, int n)
{
    b->bits |= value << b->nbits;
    b->nbits += n;
    while (b->nbits >= 8) {
        uint8_t c = (uint8_t)b->bits;
        sr__put(b, &c, 1);
        b->bits >>= 8;
        b->nbits -= 8;
    }
}

/* Huffman codes are sent most significant bit first */
static void sr__huff(sr__buf *b, uint32_t code, int len)
{
    uint32_t r = 0;
    int i;
    for (i = 0; i < len; i++) r |= ((code >> i) & 1u) << (len - 1 - i);
    sr__bits(b, r, len);
}

static void sr__fixed_literal(sr__buf *b, int sym)
{
    if (sym < 144) sr__huff(b, 0x30u + (uint32_t)sym, 8);
    else if (sym < 256) sr__huff(b, 0x190u + (uint32_t)(sym - 144), 9);
    else if (sym < 280) sr__huff(b, (uint32_t)(sym - 256), 7);
    else sr__huff(b, 0xC0u + (uint32_t)(sym - 280), 8);
}

/* RFC 1951 3.2.5: length and distance codes */
static const unsigned short sr__len_base[29] = {3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31,
                                               35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const unsigned char sr__len_extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const unsigned short sr__dist_base[30] = {1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129, 193, 257, 385,
                                                513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
static const unsigned char sr__dist_extra[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

static void sr__deflate_match(sr__buf *b, int len, int dist)
{
    int li = 28, di = 29;
    while (sr__len_base[li] > len) li--;
    while (sr__dist_base[di] > dist) di--;
    sr__fixed_literal(b, 257 + li);
    if (sr__len_extra[li]) sr__bits(b, (uint32_t)(len - sr__len_base[li]), sr__len_extra[li]);
    sr__huff(b, (uint32_t)di, 5);
    if (sr__dist_extra[di]) sr__bits(b, (uint32_t)(dist - sr__dist_base[di]), sr__dist_extra[di]);
}

#define SR__HASH_BITS 15
#define SR__WINDOW 32768
#define SR__CHAIN 32

/* zlib stream of one final fixed-Huffman block */
static sr_result sr__zlib(const uint8_t *in, size_t n, sr__buf *b)
{
    int32_t *head = NULL, *prev = NULL;
    size_t i = 0, k;
    uint32_t s1 = 1, s2 = 0;
    uint8_t hdr[2];
    head = (int32_t *)sr__alloc(&b->a, sizeof(int32_t) << SR__HASH_BITS);
    prev = (int32_t *)sr__alloc(&b->a, sizeof(int32_t) * SR__WINDOW);
    if (!head || !prev) {
        if (head) b->a.free(b->a.user, head);
        if (prev) b->a.free(b->a.user, prev);
        return SR_ERR_OUT_OF_MEMORY;
    }
    for (k = 0; k < ((size_t)1 << SR__HASH_BITS); k++) head[k] = -1;
    hdr[0] = 0x78; hdr[1] = 0x01; /* deflate, 32K window, check bits: 0x7801 % 31 == 0 */
    sr__put(b, hdr, 2);
    sr__bits(b, 1, 1); /* BFINAL */
    sr__bits(b, 1, 2); /* BTYPE = fixed Huffman */
    while (i < n && !b->failed) {
        int best = 0, bestd = 0;
        if (i + 3 <= n) {
            uint32_t h = ((uint32_t)in[i] * 506832829u ^ (uint32_t)in[i + 1] * 2654435761u ^ (uint32_t)in[i + 2] * 40503u) >> (32 - SR__HASH_BITS);
            int32_t cand = head[h];
            int chain = SR__CHAIN;
            size_t maxlen = n - i < 258 ? n - i : 258;
            while (cand >= 0 && chain-- > 0 && i - (size_t)cand <= SR__WINDOW - 1) {
                size_t l = 0;
                const uint8_t *p = in + cand, *q = in + i;
                while (l < maxlen && p[l] == q[l]) l++;
                if ((int)l > best) { best = (int)l; bestd = (int)(i - (size_t)cand); if (l == maxlen) break; }
                cand = prev[(size_t)cand % SR__WINDOW];
            }
            prev[i % SR__WINDOW] = head[h];
            head[h] = (int32_t)i;
        }
        if (best >= 3) {
            size_t end = i + (size_t)best;
            sr__deflate_match(b, best, bestd);
            for (i++; i < end; i++) /* keep the hash chains complete inside the match */
                if (i + 3 <= n) {
                    uint32_t h = ((uint32_t)in[i] * 506832829u ^ (uint32_t)in[i + 1] * 2654435761u ^ (uint32_t)in[i + 2] * 40503u) >> (32 - SR__HASH_BITS);
                    prev[i % SR__WINDOW] = head[h];
                    head[h] = (int32_t)i;
                }
        } else {
            sr__fixed_literal(b, in[i]);
            i++;
        }
    }
    sr__fixed_literal(b, 256);
    if (b->nbits > 0) sr__bits(b, 0, 8 - b->nbits);
    for (k = 0; k < n; k++) { /* Adler-32 */
        s1 = (s1 + in[k]) % 65521u;
        s2 = (s2 + s1) % 65521u;
    }
    sr__put_u32be(b, (s2 << 16) | s1);
    b->a.free(b->a.user, head);
    b->a.free(b->a.user, prev);
    return b->failed ? SR_ERR_OUT_OF_MEMORY : SR_OK;
}

static uint32_t sr__crc(const uint8_t *p, size_t n, uint32_t crc)
{
    size_t i;
    static const uint32_t nibble[16] = { /* CRC-32 of each 4-bit value (polynomial 0xEDB88320) */
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
        0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu, 0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};
    crc = ~crc;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        crc = (crc >> 4) ^ nibble[crc & 15u];
        crc = (crc >> 4) ^ nibble[crc & 15u];
    }
    return ~crc;
}

static void sr__chunk(sr__buf *b, const char *type, const uint8_t *data, size_t n)
{
    uint32_t crc;
    sr__put_u32be(b, (uint32_t)n);
    sr__put(b, type, 4);
    if (n) sr__put(b, data, n);
    crc = sr__crc((const uint8_t *)type, 4, 0);
    crc = sr__crc(data, n, crc);
    sr__put_u32be(b, crc);
}

static int sr__paeth(int a, int b, int c)
{
    int p = a + b - c, pa = p > a ? p - a : a - p, pb = p > b ? p - b : b - p, pc = p > c ? p - c : c - p;
    return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

/* filter every row with each of the five filters and keep the smallest sum of |residual| */
static void sr__filter_rows(const uint8_t *pixels, int w, int h, int ch, int flip, uint8_t *out)
{
    size_t stride = (size_t)w * (size_t)ch, y, x;
    for (y = 0; y < (size_t)h; y++) {
        const uint8_t *row = pixels + (flip ? (size_t)h - 1 - y : y) * stride;
        const uint8_t *up = y ? pixels + (flip ? (size_t)h - y : y - 1) * stride : NULL;
        uint8_t *o = out + y * (stride + 1);
        unsigned long best_cost = (unsigned long)-1;
        int f, best = 0;
        for (f = 0; f < 5; f++) {
            unsigned long cost = 0;
            for (x = 0; x < stride; x++) {
                int a = x >= (size_t)ch ? row[x - (size_t)ch] : 0, b = up ? up[x] : 0, c = (up && x >= (size_t)ch) ? up[x - (size_t)ch] : 0;
                int pred = f == 0 ? 0 : f == 1 ? a : f == 2 ? b : f == 3 ? (a + b) / 2 : sr__paeth(a, b, c);
                int r = (uint8_t)(row[x] - pred);
                cost += (unsigned long)(r < 128 ? r : 256 - r);
            }
            if (cost < best_cost) { best_cost = cost; best = f; }
        }
        o[0] = (uint8_t)best;
        for (x = 0; x < stride; x++) {
            int a = x >= (size_t)ch ? row[x - (size_t)ch] : 0, b = up ? up[x] : 0, c = (up && x >= (size_t)ch) ? up[x - (size_t)ch] : 0;
            int pred = best == 0 ? 0 : best == 1 ? a : best == 2 ? b : best == 3 ? (a + b) / 2 : sr__paeth(a, b, c);
            o[1 + x] = (uint8_t)(row[x] - pred);
        }
    }
}

/* PNG of rows of bpp-byte pixels (already in file order: big-endian 16-bit samples) */
static sr_result sr__png_encode(const uint8_t *bytes, int width, int height, int bpp, int depth, int color, int flip_y,
                                const sr_allocator *a, uint8_t **out, size_t *out_size)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    sr__buf b, z;
    uint8_t ihdr[13], *filtered;
    size_t raw;
    sr_result res;
    memset(&b, 0, sizeof b);
    b.a = *a;
    z = b;
    raw = ((size_t)width * (size_t)bpp + 1) * (size_t)height;
    filtered = (uint8_t *)sr__alloc(&b.a, raw);
    if (!filtered) return SR_ERR_OUT_OF_MEMORY;
    sr__filter_rows(bytes, width, height, bpp, flip_y, filtered);
    res = sr__zlib(filtered, raw, &z);
    b.a.free(b.a.user, filtered);
    if (res != SR_OK) { if (z.data) z.a.free(z.a.user, z.data); return res; }
    ihdr[0] = (uint8_t)(width >> 24); ihdr[1] = (uint8_t)(width >> 16); ihdr[2] = (uint8_t)(width >> 8); ihdr[3] = (uint8_t)width;
    ihdr[4] = (uint8_t)(height >> 24); ihdr[5] = (uint8_t)(height >> 16); ihdr[6] = (uint8_t)(height >> 8); ihdr[7] = (uint8_t)height;
    ihdr[8] = (uint8_t)depth;
    ihdr[9] = (uint8_t)color;
    ihdr[10] = 0; ihdr[11] = 0; ihdr[12] = 0;
    sr__put(&b, sig, 8);
    sr__chunk(&b, "IHDR", ihdr, 13);
    sr__chunk(&b, "IDAT", z.data, z.size);
    sr__chunk(&b, "IEND", NULL, 0);
    z.a.free(z.a.user, z.data);
    if (b.failed) { if (b.data) b.a.free(b.a.user, b.data); return SR_ERR_OUT_OF_MEMORY; }
    *out = b.data;
    *out_size = b.size;
    return SR_OK;
}

SRDEF sr_result sr_encode_png(const uint8_t *pixels, int width, int height, int channels, int flip_y,
                              const sr_allocator *allocator, uint8_t **out, size_t *out_size)
{
    sr_allocator a;
    if (out) *out = NULL;
    if (out_size) *out_size = 0;
    if (!pixels || !out || !out_size || width < 1 || height < 1 || (channels != 1 && channels != 3 && channels != 4))
        return SR_ERR_INVALID_ARGUMENT;
    if (width > 1000000 || height > 1000000 || (size_t)width * (size_t)channels + 1 > ((size_t)-1) / (size_t)height)
        return SR_ERR_TOO_LARGE;
    a = sr__resolve_allocator(allocator);
    return sr__png_encode(pixels, width, height, channels, 8, channels == 1 ? 0 : channels == 3 ? 2 : 6, flip_y, &a, out, out_size);
}

static sr_result sr__write_file(const char *path, const void *head, size_t head_n, const void *data, size_t n)
{
    FILE *f;
    int ok;
    if (!path) return SR_ERR_INVALID_ARGUMENT;
    f = fopen(path, "wb");
    if (!f) return SR_ERR_IO;
    ok = fwrite(head, 1, head_n, f) == head_n;
    if (ok && n) ok = fwrite(data, 1, n, f) == n;
    if (fclose(f) != 0) ok = 0;
    return ok ? SR_OK : SR_ERR_IO;
}

SRDEF sr_result sr_write_png(const char *path, const uint8_t *pixels, int width, int height, int channels, int flip_y)
{
    uint8_t *png;
    size_t n;
    sr_result r;
    if (!path) return SR_ERR_INVALID_ARGUMENT;
    r = sr_encode_png(pixels, width, height, channels, flip_y, NULL, &png, &n);
    if (r != SR_OK) return r;
    r = sr__write_file(path, png, n, NULL, 0);
    sr_free(NULL, png);
    return r;
}

SRDEF sr_result sr_write_ppm(const char *path, const uint8_t *pixels, int width, int height, int channels, int flip_y)
{
    char head[64];
    uint8_t *rgb;
    size_t n, y, x;
    sr_result r;
    sr_allocator a = sr__resolve_allocator(NULL);
    if (!path || !pixels || width < 1 || height < 1 || (channels != 3 && channels != 4)) return SR_ERR_INVALID_ARGUMENT;
    n = (size_t)width * (size_t)height * 3;
    rgb = (uint8_t *)sr__alloc(&a, n);
    if (!rgb) return SR_ERR_OUT_OF_MEMORY;
    for (y = 0; y < (size_t)height; y++) {
        const uint8_t *row = pixels + (flip_y ? (size_t)height - 1 - y : y) * (size_t)width * (size_t)channels;
        for (x = 0; x < (size_t)width; x++) memcpy(rgb + (y * (size_t)width + x) * 3, row + x * (size_t)channels, 3);
    }
    sprintf(head, "P6\n%d %d\n255\n", width, height);
    r = sr__write_file(path, head, strlen(head), rgb, n);
    a.free(a.user, rgb);
    return r;
}

SRDEF sr_result sr_write_pfm(const char *path, const float *data, int width, int height, int channels)
{
    char head[64];
    uint8_t *bytes;
    size_t n, i;
    sr_result r;
    sr_allocator a = sr__resolve_allocator(NULL);
    if (!path || !data || width < 1 || height < 1 || (channels != 1 && channels != 3)) return SR_ERR_INVALID_ARGUMENT;
    n = (size_t)width * (size_t)height * (size_t)channels;
    bytes = (uint8_t *)sr__alloc(&a, n * 4);
    if (!bytes) return SR_ERR_OUT_OF_MEMORY;
    for (i = 0; i < n; i++) { /* little-endian on any host (scale -1 below) */
        uint32_t u;
        memcpy(&u, data + i, 4);
        bytes[4 * i] = (uint8_t)u; bytes[4 * i + 1] = (uint8_t)(u >> 8);
        bytes[4 * i + 2] = (uint8_t)(u >> 16); bytes[4 * i + 3] = (uint8_t)(u >> 24);
    }
    sprintf(head, "%s\n%d %d\n-1.0\n", channels == 3 ? "PF" : "Pf", width, height);
    r = sr__write_file(path, head, strlen(head), bytes, n * 4);
    a.free(a.user, bytes);
    return r;
}

SRDEF sr_result sr_write_framebuffer_png(const sr_framebuffer *fb, const char *path, int flip_y)
{
    uint8_t *rgb;
    sr_result r;
    sr_allocator a;
    if (!fb || !fb->color || !path) return SR_ERR_INVALID_ARGUMENT;
    a = fb->allocator;
    rgb = (uint8_t *)sr__alloc(&a, (size_t)fb->width * (size_t)fb->height * 3);
    if (!rgb) return SR_ERR_OUT_OF_MEMORY;
    sr_framebuffer_to_rgb8(fb, rgb, 3);
    r = sr_write_png(path, rgb, fb->width, fb->height, 3, flip_y);
    a.free(a.user, rgb);
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Section: image readers (zlib inflate, PNG decoder, PGM / PPM / PFM) and the 16-bit PNG writer
   --------------------------------------------------------------------------------------------- */

#define SR__IMG_MAX_SIDE 32768
#define SR__IMG_MAX_SAMPLES ((size_t)1 << 28)
#define SR__FAST_BITS 9

/* a canonical Huffman code (RFC 1951 3.2.2) with a table for codes of up to SR__FAST_BITS bits */
typedef struct sr__huffman {
    uint16_t count[16];                  /* codes of each length */
    uint16_t symbol[288];                /* symbols ordered by (length, value) */
    uint16_t fast[1 << SR__FAST_BITS];   /* (length << 9) | symbol for short codes; 0 = take the long way */
} sr__huffman;

typedef struct sr__inflate {
    const uint8_t *in;
    size_t n, pos, over;                 /* over: zero bytes fed past the end of the input */
    uint64_t bits;                       /* LSB first */
    int cnt;
    uint8_t *out;
    size_t out_n, out_pos;
} sr__inflate;

static void sr__z_refill(sr__inflate *z)
{
    while (z->cnt <= 56) {
        uint64_t b = 0;
        if (z->pos < z->n) b = z->in[z->pos++];
        else z->over++;
        z->bits |= b << z->cnt;
        z->cnt += 8;
    }
}

/* n <= 32 bits, after a refill that guarantees them */
static uint32_t sr__z_get(sr__inflate *z, int n)
{
    uint32_t v = (uint32_t)(z->bits & ((((uint64_t)1) << n) - 1u));
    z->bits >>= n;
    z->cnt -= n;
    return v;
}

/* nonzero when bits past the end of the input have been consumed */
static int sr__z_overrun(const sr__inflate *z) { return (size_t)z->cnt < 8 * z->over; }

/* Builds the code from its lengths. Over-subscribed codes are corrupt; an incomplete code is
   accepted only as zlib does: a code-length code never, the others when no code is longer than 1
   bit (one code, or none: then every use is corrupt). */
static sr_result sr__huff_build(sr__huffman *h, const uint8_t *lengths, int n, int is_code_lengths)
{
    int offs[16], next[16], len, sym, left = 1, maxlen = 0, code = 0;
    memset(h->count, 0, sizeof h->count);
    memset(h->fast, 0, sizeof h->fast);
    for (sym = 0; sym < n; sym++) h->count[lengths[sym]]++;
    h->count[0] = 0;
    for (len = 1; len <= 15; len++) {
        left = 2 * left - h->count[len];
        if (left < 0) return SR_ERR_CORRUPT;
        if (h->count[len]) maxlen = len;
    }
    if (left > 0 && (is_code_lengths ? maxlen > 0 : maxlen > 1)) return SR_ERR_CORRUPT;
    offs[1] = 0;
    for (len = 1; len < 15; len++) offs[len + 1] = offs[len] + h->count[len];
    for (len = 1; len <= 15; len++) { code = (code + h->count[len - 1]) << 1; next[len] = code; }
    for (sym = 0; sym < n; sym++) {
        int l = lengths[sym];
        if (!l) continue;
        h->symbol[offs[l]++] = (uint16_t)sym;
        if (l <= SR__FAST_BITS) {
            int c = next[l]++, rev = 0, k;
            for (k = 0; k < l; k++) rev |= ((c >> k) & 1) << (l - 1 - k);
            for (k = rev; k < (1 << SR__FAST_BITS); k += 1 << l) h->fast[k] = (uint16_t)((l << 9) | sym);
        } else {
            next[l]++;
        }
    }
    return SR_OK;
}

/* one symbol (at least 15 bits must be buffered), or -1 for a bit pattern that is no code */
static int sr__huff_decode(sr__inflate *z, const sr__huffman *h)
{
    int e = h->fast[z->bits & ((1u << SR__FAST_BITS) - 1u)], len, code = 0, first = 0, index = 0;
    if (e) { sr__z_get(z, e >> 9); return e & 511; }
    for (len = 1; len <= 15; len++) {
        int count = h->count[len];
        code |= (int)((z->bits >> (len - 1)) & 1u);
        if (code - first < count) { sr__z_get(z, len); return h->symbol[index + code - first]; }
        index += count;
        first = (first + count) << 1;
        code <<= 1;
    }
    return -1;
}

/* the symbols of one Huffman block up to end-of-block; output past out_n is corrupt */
static sr_result sr__inflate_codes(sr__inflate *z, const sr__huffman *lit, const sr__huffman *dist)
{
    for (;;) {
        int sym;
        sr__z_refill(z);
        if (sr__z_overrun(z)) return SR_ERR_TRUNCATED;
        sym = sr__huff_decode(z, lit);
        if (sym < 0) return sr__z_overrun(z) ? SR_ERR_TRUNCATED : SR_ERR_CORRUPT;
        if (sym < 256) {
            if (z->out_pos >= z->out_n) return SR_ERR_CORRUPT;
            z->out[z->out_pos++] = (uint8_t)sym;
        } else if (sym == 256) {
            return sr__z_overrun(z) ? SR_ERR_TRUNCATED : SR_OK;
        } else {
            size_t len, d, k;
            uint8_t *o;
            const uint8_t *src;
            sym -= 257;
            if (sym >= 29) return SR_ERR_CORRUPT;
            len = sr__len_base[sym] + sr__z_get(z, sr__len_extra[sym]);
            sym = sr__huff_decode(z, dist);
            if (sym < 0 || sym >= 30) return sr__z_overrun(z) ? SR_ERR_TRUNCATED : SR_ERR_CORRUPT;
            d = sr__dist_base[sym] + sr__z_get(z, sr__dist_extra[sym]);
            if (sr__z_overrun(z)) return SR_ERR_TRUNCATED;
            if (d > z->out_pos || len > z->out_n - z->out_pos) return SR_ERR_CORRUPT;
            o = z->out + z->out_pos;
            src = o - d;
            for (k = 0; k < len; k++) o[k] = src[k]; /* overlapping copies repeat the pattern */
            z->out_pos += len;
        }
    }
}

static sr_result sr__inflate_stored(sr__inflate *z)
{
    uint32_t len, nlen, k;
    sr__z_get(z, z->cnt & 7);
    sr__z_refill(z);
    len = sr__z_get(z, 16);
    nlen = sr__z_get(z, 16);
    if (sr__z_overrun(z)) return SR_ERR_TRUNCATED;
    if ((len ^ 0xFFFFu) != nlen) return SR_ERR_CORRUPT;
    if (len > z->out_n - z->out_pos) return SR_ERR_CORRUPT;
    for (k = 0; k < len; k++) {
        if (z->cnt < 8) sr__z_refill(z);
        z->out[z->out_pos++] = (uint8_t)sr__z_get(z, 8);
    }
    return sr__z_overrun(z) ? SR_ERR_TRUNCATED : SR_OK;
}

static sr_result sr__inflate_fixed(sr__inflate *z, sr__huffman *lit, sr__huffman *dist)
{
    uint8_t l[288];
    int i;
    for (i = 0; i < 288; i++) l[i] = (uint8_t)(i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8);
    sr__huff_build(lit, l, 288, 0);
    for (i = 0; i < 32; i++) l[i] = 5;
    sr__huff_build(dist, l, 32, 0);
    return sr__inflate_codes(z, lit, dist);
}

/* the code lengths of a dynamic block (RFC 1951 3.2.7), then its symbols */
static sr_result sr__inflate_dynamic(sr__inflate *z, sr__huffman *lit, sr__huffman *dist)
{
    static const unsigned char order[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};
    uint8_t lens[286 + 30];
    int hlit, hdist, hclen, i = 0;
    sr_result r;
    sr__z_refill(z);
    hlit = (int)sr__z_get(z, 5) + 257;
    hdist = (int)sr__z_get(z, 5) + 1;
    hclen = (int)sr__z_get(z, 4) + 4;
    if (hlit > 286 || hdist > 30) return SR_ERR_CORRUPT;
    memset(lens, 0, sizeof lens);
    for (i = 0; i < hclen; i++) {
        if (z->cnt < 3) sr__z_refill(z);
        lens[order[i]] = (uint8_t)sr__z_get(z, 3);
    }
    if (sr__z_overrun(z)) return SR_ERR_TRUNCATED;
    if ((r = sr__huff_build(lit, lens, 19, 1)) != SR_OK) return r;
    for (i = 0; i < hlit + hdist;) {
        int sym, rep = 0, val = 0;
        sr__z_refill(z);
        sym = sr__huff_decode(z, lit);
        if (sym < 0) return sr__z_overrun(z) ? SR_ERR_TRUNCATED : SR_ERR_CORRUPT;
        if (sym < 16) { lens[i++] = (uint8_t)sym; continue; }
        if (sym == 16) {
            if (i == 0) return SR_ERR_CORRUPT;
            val = lens[i - 1];
            rep = 3 + (int)sr__z_get(z, 2);
        } else if (sym == 17) {
            rep = 3 + (int)sr__z_get(z, 3);
        } else {
            rep = 11 + (int)sr__z_get(z, 7);
        }
        if (rep > hlit + hdist - i) return SR_ERR_CORRUPT;
        while (rep--) lens[i++] = (uint8_t)val;
    }
    if (sr__z_overrun(z)) return SR_ERR_TRUNCATED;
    if (lens[256] == 0) return SR_ERR_CORRUPT; /* no end-of-block code */
    if ((r = sr__huff_build(lit, lens, hlit, 0)) != SR_OK) return r;
    if ((r = sr__huff_build(dist, lens + hlit, hdist, 0)) != SR_OK) return r;
    return sr__inflate_codes(z, lit, dist);
}

static uint32_t sr__adler(const uint8_t *p, size_t n)
{
    uint32_t s1 = 1, s2 = 0;
    while (n) {
        size_t k = n < 5552 ? n : 5552; /* the longest run whose sums cannot overflow 32 bits */
        n -= k;
        while (k--) { s1 += *p++; s2 += s1; }
        s1 %= 65521u;
        s2 %= 65521u;
    }
    return (s2 << 16) | s1;
}

/* A zlib stream (RFC 1950) that must inflate to exactly out_n bytes; bytes after the Adler-32
   are ignored (libpng also accepts them). */
static sr_result sr__zlib_decode(const uint8_t *in, size_t n, uint8_t *out, size_t out_n)
{
    sr__inflate z;
    sr__huffman lit, dist;
    uint32_t adler = 0;
    int final = 0, k;
    sr_result r = SR_OK;
    if (n < 2) return SR_ERR_TRUNCATED;
    if ((in[0] & 15) != 8 || (in[0] >> 4) > 7 || ((unsigned)in[0] * 256u + in[1]) % 31u != 0) return SR_ERR_CORRUPT;
    if (in[1] & 0x20) return SR_ERR_UNSUPPORTED; /* preset dictionary */
    memset(&z, 0, sizeof z);
    z.in = in; z.n = n; z.pos = 2; z.out = out; z.out_n = out_n;
    while (!final && r == SR_OK) {
        uint32_t type;
        sr__z_refill(&z);
        final = (int)sr__z_get(&z, 1);
        type = sr__z_get(&z, 2);
        if (sr__z_overrun(&z)) return SR_ERR_TRUNCATED;
        if (type == 0) r = sr__inflate_stored(&z);
        else if (type == 1) r = sr__inflate_fixed(&z, &lit, &dist);
        else if (type == 2) r = sr__inflate_dynamic(&z, &lit, &dist);
        else r = SR_ERR_CORRUPT;
    }
    if (r != SR_OK) return r;
    sr__z_get(&z, z.cnt & 7);
    sr__z_refill(&z);
    for (k = 0; k < 4; k++) adler = (adler << 8) | sr__z_get(&z, 8);
    if (sr__z_overrun(&z)) return SR_ERR_TRUNCATED;
    if (z.out_pos != out_n) return SR_ERR_CORRUPT; /* a complete stream with too little image data */
    return adler == sr__adler(out, out_n) ? SR_OK : SR_ERR_CHECKSUM;
}

SRDEF void sr_picture_free(sr_picture *p)
{
    if (!p) return;
    if (p->samples) p->allocator.free(p->allocator.user, p->samples);
    if (p->floats) p->allocator.free(p->allocator.user, p->floats);
    p->samples = NULL;
    p->floats = NULL;
}

/* checks the size limits and allocates the picture's array */
static sr_result sr__picture_alloc(sr_picture *p, uint32_t w, uint32_t h, int channels, int floats)
{
    size_t n;
    if (w < 1 || h < 1) return SR_ERR_CORRUPT;
    if (w > SR__IMG_MAX_SIDE || h > SR__IMG_MAX_SIDE) return SR_ERR_TOO_LARGE;
    n = (size_t)w * (size_t)h * (size_t)channels;
    if (n > SR__IMG_MAX_SAMPLES) return SR_ERR_TOO_LARGE;
    p->width = (int)w;
    p->height = (int)h;
    p->channels = channels;
    if (floats) p->floats = (float *)sr__alloc(&p->allocator, n * sizeof(float));
    else p->samples = (uint16_t *)sr__alloc(&p->allocator, n * sizeof(uint16_t));
    return (p->floats || p->samples) ? SR_OK : SR_ERR_OUT_OF_MEMORY;
}

static uint32_t sr__get_u32be(const uint8_t *p)
{
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | (uint32_t)p[3];
}

typedef struct sr__png {
    uint32_t width, height;
    int depth, color, interlace, channels; /* channels in the file: palette = 1 */
    uint8_t palette[256][4];
    int palette_n, have_trns;
    sr__buf idat;                          /* the IDAT chunks' data, concatenated */
} sr__png;

static sr_result sr__png_ihdr(sr__png *p, const uint8_t *d, uint32_t n)
{
    static const int ch[7] = {1, 0, 3, 1, 2, 0, 4};
    int dp;
    if (n != 13) return SR_ERR_CORRUPT;
    p->width = sr__get_u32be(d);
    p->height = sr__get_u32be(d + 4);
    p->depth = d[8];
    p->color = d[9];
    p->interlace = d[12];
    dp = p->depth;
    if (p->width == 0 || p->height == 0 || p->width > 0x7FFFFFFFu || p->height > 0x7FFFFFFFu) return SR_ERR_CORRUPT;
    if (p->color > 6 || ch[p->color] == 0) return SR_ERR_CORRUPT;
    p->channels = ch[p->color];
    if (dp != 1 && dp != 2 && dp != 4 && dp != 8 && dp != 16) return SR_ERR_CORRUPT;
    if ((p->color == 3 && dp == 16) || (p->color != 0 && p->color != 3 && dp < 8)) return SR_ERR_CORRUPT;
    if (d[10] != 0 || d[11] != 0 || d[12] > 1) return SR_ERR_CORRUPT;
    if (p->width > SR__IMG_MAX_SIDE || p->height > SR__IMG_MAX_SIDE) return SR_ERR_TOO_LARGE;
    if ((size_t)p->width * p->height * (size_t)(p->color == 3 ? 4 : p->channels) > SR__IMG_MAX_SAMPLES) return SR_ERR_TOO_LARGE;
    return SR_OK;
}

static sr_result sr__png_plte(sr__png *p, const uint8_t *d, uint32_t n)
{
    uint32_t i;
    if (p->color == 0 || p->color == 4 || p->palette_n || p->idat.size) return SR_ERR_CORRUPT;
    if (n == 0 || n % 3 || n / 3 > 256 || (p->color == 3 && n / 3 > (1u << p->depth))) return SR_ERR_CORRUPT;
    for (i = 0; i < n / 3; i++) {
        p->palette[i][0] = d[3 * i]; p->palette[i][1] = d[3 * i + 1]; p->palette[i][2] = d[3 * i + 2];
        p->palette[i][3] = 255;
    }
    p->palette_n = (int)(n / 3);
    return SR_OK;
}

/* tRNS: palette alpha is applied (the picture gets 4 channels); a grey or RGB colour key is ignored */
static sr_result sr__png_trns(sr__png *p, const uint8_t *d, uint32_t n)
{
    uint32_t i;
    if (p->color != 3) return (p->color == 0 || p->color == 2) ? SR_OK : SR_ERR_CORRUPT;
    if (!p->palette_n || p->idat.size || n > (uint32_t)p->palette_n) return SR_ERR_CORRUPT;
    for (i = 0; i < n; i++) p->palette[i][3] = d[i];
    p->have_trns = 1;
    return SR_OK;
}

/* Walks the chunks: signature, lengths, CRCs, order; keeps IHDR, PLTE, tRNS and gathers IDAT. */
static sr_result sr__png_chunks(sr__png *p, const uint8_t *data, size_t size)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    size_t pos = 8;
    int seen_ihdr = 0, idat_done = 0;
    if (size < 8) return memcmp(data, sig, size) == 0 ? SR_ERR_TRUNCATED : SR_ERR_UNSUPPORTED;
    if (memcmp(data, sig, 8) != 0) return SR_ERR_UNSUPPORTED;
    for (;;) {
        uint32_t n, k;
        const uint8_t *type, *d;
        sr_result r = SR_OK;
        if (size - pos < 12) return SR_ERR_TRUNCATED;
        n = sr__get_u32be(data + pos);
        type = data + pos + 4;
        d = type + 4;
        if (n > 0x7FFFFFFFu) return SR_ERR_CORRUPT;
        if (size - pos - 12 < n) return SR_ERR_TRUNCATED;
        for (k = 0; k < 4; k++)
            if (!((type[k] >= 'A' && type[k] <= 'Z') || (type[k] >= 'a' && type[k] <= 'z'))) return SR_ERR_CORRUPT;
        if (sr__crc(type, 4 + (size_t)n, 0) != sr__get_u32be(d + n)) return SR_ERR_CHECKSUM;
        pos += 12 + (size_t)n;
        if (!seen_ihdr) {
            if (memcmp(type, "IHDR", 4) != 0) return SR_ERR_CORRUPT;
            if ((r = sr__png_ihdr(p, d, n)) != SR_OK) return r;
            seen_ihdr = 1;
            continue;
        }
        if (p->idat.size && memcmp(type, "IDAT", 4) != 0) idat_done = 1;
        if (memcmp(type, "IEND", 4) == 0) break;
        if (memcmp(type, "IDAT", 4) == 0) {
            if (idat_done || (p->color == 3 && !p->palette_n)) return SR_ERR_CORRUPT;
            sr__put(&p->idat, d, n);
            if (p->idat.failed) return SR_ERR_OUT_OF_MEMORY;
        } else if (memcmp(type, "PLTE", 4) == 0) r = sr__png_plte(p, d, n);
        else if (memcmp(type, "tRNS", 4) == 0) r = sr__png_trns(p, d, n);
        else if (memcmp(type, "IHDR", 4) == 0) r = SR_ERR_CORRUPT;
        else if (!(type[0] & 0x20)) r = SR_ERR_UNSUPPORTED; /* an unknown critical chunk */
        if (r != SR_OK) return r;
    }
    return p->idat.size ? SR_OK : SR_ERR_CORRUPT;
}

/* bytes of one filtered row of a pass w pixels wide (without the filter byte) */
static size_t sr__png_row_bytes(const sr__png *p, uint32_t w)
{
    return ((size_t)w * (size_t)(p->channels * p->depth) + 7) / 8;
}

static const uint8_t sr__adam7[7][4] = { /* x0, y0, dx, dy */
    {0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4}, {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};

static void sr__png_pass_size(const sr__png *p, int pass, uint32_t *w, uint32_t *h)
{
    const uint8_t *a = sr__adam7[p->interlace ? pass : 6];
    if (!p->interlace) { *w = p->width; *h = p->height; return; }
    *w = p->width > a[0] ? (p->width - a[0] + a[2] - 1) / a[2] : 0;
    *h = p->height > a[1] ? (p->height - a[1] + a[3] - 1) / a[3] : 0;
    if (*w == 0) *h = 0;
    if (*h == 0) *w = 0;
}

/* undoes the row filters of one pass in place: each row is its filter byte and rb bytes */
static sr_result sr__png_unfilter(uint8_t *rows, size_t rb, uint32_t h, size_t bpp)
{
    uint32_t y;
    size_t x;
    for (y = 0; y < h; y++) {
        uint8_t *r = rows + (size_t)y * (rb + 1);
        const uint8_t *up = y ? r - (rb + 1) + 1 : NULL;
        int f = r[0];
        r++;
        if (f > 4) return SR_ERR_CORRUPT;
        if (!up && (f == 2 || f == 4)) f = f == 2 ? 0 : 1; /* the row above is zero */
        switch (f) {
        case 1: for (x = bpp; x < rb; x++) r[x] = (uint8_t)(r[x] + r[x - bpp]); break;
        case 2: for (x = 0; x < rb; x++) r[x] = (uint8_t)(r[x] + up[x]); break;
        case 3:
            for (x = 0; x < rb; x++) {
                int a = x >= bpp ? r[x - bpp] : 0, b = up ? up[x] : 0;
                r[x] = (uint8_t)(r[x] + ((a + b) >> 1));
            }
            break;
        case 4:
            for (x = 0; x < bpp; x++) r[x] = (uint8_t)(r[x] + up[x]);
            for (x = bpp; x < rb; x++) r[x] = (uint8_t)(r[x] + sr__paeth(r[x - bpp], up[x], up[x - bpp]));
            break;
        default: break;
        }
    }
    return SR_OK;
}

/* one pass's unfiltered rows to the picture's samples (palette expanded) */
static sr_result sr__png_unpack(const sr__png *p, int pass, const uint8_t *rows, uint32_t w, uint32_t h, sr_picture *out)
{
    const uint8_t *a = sr__adam7[p->interlace ? pass : 6];
    uint32_t x0 = p->interlace ? a[0] : 0, y0 = p->interlace ? a[1] : 0, dx = p->interlace ? a[2] : 1, dy = p->interlace ? a[3] : 1;
    size_t rb = sr__png_row_bytes(p, w), oc = (size_t)out->channels;
    int c, nc = p->channels, depth = p->depth;
    uint32_t x, y;
    for (y = 0; y < h; y++) {
        const uint8_t *r = rows + (size_t)y * (rb + 1) + 1;
        uint16_t *o = out->samples + ((size_t)(y0 + y * dy) * p->width + x0) * oc;
        for (x = 0; x < w; x++, o += dx * oc)
            for (c = 0; c < nc; c++) {
                size_t i = (size_t)x * (size_t)nc + (size_t)c;
                unsigned v;
                if (depth == 16) v = ((unsigned)r[2 * i] << 8) | r[2 * i + 1];
                else if (depth == 8) v = r[i];
                else v = (r[i * (size_t)depth / 8] >> (8 - depth - (int)(i * (size_t)depth % 8))) & ((1u << depth) - 1u);
                if (p->color == 3) {
                    int k;
                    if ((int)v >= p->palette_n) return SR_ERR_CORRUPT;
                    for (k = 0; k < (int)oc; k++) o[k] = p->palette[v][k];
                } else {
                    o[c] = (uint16_t)v;
                }
            }
    }
    return SR_OK;
}

/* inflates the IDAT stream into every pass's filtered rows, then unfilters and unpacks the passes */
static sr_result sr__png_pixels(sr__png *p, sr_allocator *al, sr_picture *out)
{
    size_t total = 0, off = 0, bpp = (size_t)(p->channels * p->depth + 7) / 8;
    uint32_t w, h;
    uint8_t *raw;
    sr_result r;
    int pass, passes = p->interlace ? 7 : 1;
    for (pass = 0; pass < passes; pass++) {
        sr__png_pass_size(p, pass, &w, &h);
        if (h) total += (sr__png_row_bytes(p, w) + 1) * h;
    }
    raw = (uint8_t *)sr__alloc(al, total);
    if (!raw) return SR_ERR_OUT_OF_MEMORY;
    r = sr__zlib_decode(p->idat.data, p->idat.size, raw, total);
    if (r == SR_OK) r = sr__picture_alloc(out, p->width, p->height, p->color == 3 ? (p->have_trns ? 4 : 3) : p->channels, 0);
    for (pass = 0; pass < passes && r == SR_OK; pass++) {
        sr__png_pass_size(p, pass, &w, &h);
        if (!h) continue;
        r = sr__png_unfilter(raw + off, sr__png_row_bytes(p, w), h, bpp);
        if (r == SR_OK) r = sr__png_unpack(p, pass, raw + off, w, h, out);
        off += (sr__png_row_bytes(p, w) + 1) * h;
    }
    al->free(al->user, raw);
    return r;
}

SRDEF sr_result sr_decode_png(const uint8_t *data, size_t size, const sr_allocator *allocator, sr_picture *out)
{
    sr__png p;
    sr_result r;
    if (!out) return SR_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    out->allocator = sr__resolve_allocator(allocator);
    if (!data && size) return SR_ERR_INVALID_ARGUMENT;
    if (!data) return SR_ERR_TRUNCATED;
    memset(&p, 0, sizeof p);
    p.idat.a = out->allocator;
    r = sr__png_chunks(&p, data, size);
    if (r == SR_OK) r = sr__png_pixels(&p, &out->allocator, out);
    if (p.idat.data) p.idat.a.free(p.idat.a.user, p.idat.data);
    if (r != SR_OK) { sr_picture_free(out); return r; }
    out->bit_depth = p.color == 3 ? 8 : p.depth;
    out->max_value = (1 << out->bit_depth) - 1;
    return SR_OK;
}

/* ---- PGM / PPM / PFM ---- */

typedef struct sr__text {
    const uint8_t *d;
    size_t n, pos;
} sr__text;

/* skips white space and '#' comments (to the end of the line) */
static void sr__pnm_space(sr__text *t)
{
    while (t->pos < t->n) {
        uint8_t c = t->d[t->pos];
        if (c == '#') {
            while (t->pos < t->n && t->d[t->pos] != '\n' && t->d[t->pos] != '\r') t->pos++;
        } else if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') {
            t->pos++;
        } else {
            break;
        }
    }
}

/* an unsigned decimal number up to max after optional space; TRUNCATED at the end of the data */
static sr_result sr__pnm_uint(sr__text *t, uint32_t max, uint32_t *v)
{
    uint32_t x = 0;
    size_t start;
    sr__pnm_space(t);
    start = t->pos;
    while (t->pos < t->n && t->d[t->pos] >= '0' && t->d[t->pos] <= '9') {
        x = x * 10u + (uint32_t)(t->d[t->pos++] - '0');
        if (x > max) return SR_ERR_CORRUPT;
    }
    if (t->pos == start) return t->pos == t->n ? SR_ERR_TRUNCATED : SR_ERR_CORRUPT;
    *v = x;
    return SR_OK;
}

/* PFM's scale: only its sign matters (negative: little-endian); parsed here rather than with
   strtod, whose decimal separator follows the locale */
static sr_result sr__pfm_scale(sr__text *t, int *little)
{
    int neg = 0, digits = 0, nonzero = 0;
    sr__pnm_space(t);
    if (t->pos < t->n && (t->d[t->pos] == '-' || t->d[t->pos] == '+')) neg = t->d[t->pos++] == '-';
    while (t->pos < t->n && ((t->d[t->pos] >= '0' && t->d[t->pos] <= '9') || t->d[t->pos] == '.')) {
        uint8_t c = t->d[t->pos++];
        if (c != '.') { digits++; nonzero |= c != '0'; }
    }
    if (t->pos < t->n && (t->d[t->pos] == 'e' || t->d[t->pos] == 'E') && digits) {
        t->pos++;
        if (t->pos < t->n && (t->d[t->pos] == '-' || t->d[t->pos] == '+')) t->pos++;
        while (t->pos < t->n && t->d[t->pos] >= '0' && t->d[t->pos] <= '9') t->pos++;
    }
    if (t->pos >= t->n) return SR_ERR_TRUNCATED;
    if (!digits || !nonzero) return SR_ERR_CORRUPT;
    *little = neg;
    return SR_OK;
}

static sr_result sr__pnm_samples(sr__text *t, int ascii, uint32_t maxval, sr_picture *out)
{
    size_t i, n = (size_t)out->width * (size_t)out->height * (size_t)out->channels;
    size_t bytes = maxval > 255 ? 2 : 1;
    if (ascii) {
        for (i = 0; i < n; i++) {
            uint32_t v = 0;
            sr_result r = sr__pnm_uint(t, maxval, &v);
            if (r != SR_OK) return r;
            out->samples[i] = (uint16_t)v;
        }
        return SR_OK;
    }
    if ((t->n - t->pos) / bytes < n) return SR_ERR_TRUNCATED;
    for (i = 0; i < n; i++) {
        const uint8_t *s = t->d + t->pos + i * bytes;
        uint32_t v = bytes == 2 ? ((uint32_t)s[0] << 8) | s[1] : s[0];
        if (v > maxval) return SR_ERR_CORRUPT;
        out->samples[i] = (uint16_t)v;
    }
    return SR_OK;
}

static sr_result sr__pfm_samples(sr__text *t, int little, sr_picture *out)
{
    size_t i, n = (size_t)out->width * (size_t)out->height * (size_t)out->channels;
    if ((t->n - t->pos) / 4 < n) return SR_ERR_TRUNCATED;
    for (i = 0; i < n; i++) {
        const uint8_t *s = t->d + t->pos + 4 * i;
        uint32_t u = little ? ((uint32_t)s[3] << 24) | ((uint32_t)s[2] << 16) | ((uint32_t)s[1] << 8) | s[0] : sr__get_u32be(s);
        float f;
        memcpy(&f, &u, 4);
        if (!(f - f == 0.0f)) return SR_ERR_CORRUPT; /* NaN or infinity */
        out->floats[i] = f;
    }
    return SR_OK;
}

SRDEF sr_result sr_decode_pnm(const uint8_t *data, size_t size, const sr_allocator *allocator, sr_picture *out)
{
    sr__text t;
    uint32_t w = 0, h = 0, maxval = 0;
    int kind, ascii, pfm, little = 0;
    sr_result r;
    if (!out) return SR_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    out->allocator = sr__resolve_allocator(allocator);
    if (!data && size) return SR_ERR_INVALID_ARGUMENT;
    if (size < 2) return (size == 0 || data[0] == 'P') ? SR_ERR_TRUNCATED : SR_ERR_UNSUPPORTED;
    kind = data[1];
    if (data[0] != 'P' || !(kind == '2' || kind == '3' || kind == '5' || kind == '6' || kind == 'f' || kind == 'F'))
        return SR_ERR_UNSUPPORTED;
    ascii = kind == '2' || kind == '3';
    pfm = kind == 'f' || kind == 'F';
    t.d = data; t.n = size; t.pos = 2;
    if ((r = sr__pnm_uint(&t, 100000000u, &w)) != SR_OK) return r;
    if ((r = sr__pnm_uint(&t, 100000000u, &h)) != SR_OK) return r;
    r = pfm ? sr__pfm_scale(&t, &little) : sr__pnm_uint(&t, 65535, &maxval);
    if (r != SR_OK) return r;
    if (!pfm && maxval == 0) return SR_ERR_CORRUPT;
    if (!ascii) { /* exactly one white-space byte before the binary samples */
        if (t.pos >= t.n) return SR_ERR_TRUNCATED;
        if (!(t.d[t.pos] == ' ' || t.d[t.pos] == '\t' || t.d[t.pos] == '\n' || t.d[t.pos] == '\r')) return SR_ERR_CORRUPT;
        t.pos++;
    }
    r = sr__picture_alloc(out, w, h, (kind == '3' || kind == '6' || kind == 'F') ? 3 : 1, pfm);
    if (r == SR_OK) r = pfm ? sr__pfm_samples(&t, little, out) : sr__pnm_samples(&t, ascii, maxval, out);
    if (r != SR_OK) { sr_picture_free(out); return r; }
    out->max_value = (int)maxval;
    for (out->bit_depth = pfm ? 32 : 1; !pfm && (1u << out->bit_depth) - 1u < maxval; out->bit_depth++) {}
    return SR_OK;
}

SRDEF sr_result sr_decode_image(const uint8_t *data, size_t size, const sr_allocator *allocator, sr_picture *out)
{
    if (data && size >= 1 && data[0] == 0x89) return sr_decode_png(data, size, allocator, out);
    return sr_decode_pnm(data, size, allocator, out);
}

SRDEF sr_result sr_read_image(const char *path, const sr_allocator *allocator, sr_picture *out)
{
    sr__buf b;
    FILE *f;
    sr_result r;
    int err;
    if (!out) return SR_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    out->allocator = sr__resolve_allocator(allocator);
    if (!path) return SR_ERR_INVALID_ARGUMENT;
    f = fopen(path, "rb");
    if (!f) return SR_ERR_IO;
    memset(&b, 0, sizeof b);
    b.a = out->allocator;
    for (;;) {
        uint8_t chunk[16384];
        size_t got = fread(chunk, 1, sizeof chunk, f);
        if (got) sr__put(&b, chunk, got);
        if (got < sizeof chunk || b.failed) break;
        if (b.size > SR__IMG_MAX_SAMPLES * 4) { b.failed = 2; break; }
    }
    err = ferror(f);
    fclose(f);
    if (b.failed || err) {
        if (b.data) b.a.free(b.a.user, b.data);
        return err ? SR_ERR_IO : b.failed == 2 ? SR_ERR_TOO_LARGE : SR_ERR_OUT_OF_MEMORY;
    }
    r = sr_decode_image(b.data, b.size, &b.a, out);
    if (b.data) b.a.free(b.a.user, b.data);
    return r;
}

SRDEF sr_result sr_picture_channel(const sr_picture *p, int channel, float *out)
{
    size_t i, n, ch;
    if (!p || !out || channel < 0 || channel >= p->channels || (!p->samples && !p->floats)) return SR_ERR_INVALID_ARGUMENT;
    n = (size_t)p->width * (size_t)p->height;
    ch = (size_t)p->channels;
    if (p->floats) {
        for (i = 0; i < n; i++) out[i] = p->floats[i * ch + (size_t)channel];
    } else {
        float m = (float)p->max_value;
        for (i = 0; i < n; i++) out[i] = (float)p->samples[i * ch + (size_t)channel] / m;
    }
    return SR_OK;
}

SRDEF sr_result sr_encode_png16(const uint16_t *samples, int width, int height, int channels, int flip_y,
                                const sr_allocator *allocator, uint8_t **out, size_t *out_size)
{
    static const uint8_t color[5] = {0, 0, 4, 2, 6};
    sr_allocator a = sr__resolve_allocator(allocator);
    uint8_t *bytes;
    size_t n, i;
    sr_result r;
    if (out) *out = NULL;
    if (out_size) *out_size = 0;
    if (!samples || !out || !out_size || width < 1 || height < 1 || channels < 1 || channels > 4)
        return SR_ERR_INVALID_ARGUMENT;
    if (width > 1000000 || height > 1000000 || (size_t)width * (size_t)channels * 2 + 1 > ((size_t)-1) / 2 / (size_t)height)
        return SR_ERR_TOO_LARGE;
    n = (size_t)width * (size_t)height * (size_t)channels;
    bytes = (uint8_t *)sr__alloc(&a, n * 2);
    if (!bytes) return SR_ERR_OUT_OF_MEMORY;
    for (i = 0; i < n; i++) { bytes[2 * i] = (uint8_t)(samples[i] >> 8); bytes[2 * i + 1] = (uint8_t)samples[i]; }
    r = sr__png_encode(bytes, width, height, 2 * channels, 16, color[channels], flip_y, &a, out, out_size);
    a.free(a.user, bytes);
    return r;
}

SRDEF sr_result sr_write_png16(const char *path, const uint16_t *samples, int width, int height, int channels, int flip_y)
{
    uint8_t *png;
    size_t n;
    sr_result r;
    if (!path) return SR_ERR_INVALID_ARGUMENT;
    r = sr_encode_png16(samples, width, height, channels, flip_y, NULL, &png, &n);
    if (r != SR_OK) return r;
    r = sr__write_file(path, png, n, NULL, 0);
    sr_free(NULL, png);
    return r;
}

/* ---------------------------------------------------------------------------------------------
   Section: bitmap font and contact sheets
   --------------------------------------------------------------------------------------------- */

/* 3x5 glyphs, rows top to bottom, '#' = ink */
static const char *sr__glyph(int c)
{
    static const char chars[] = " 0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ.,:;-_+=/|()[]%'\"!?<>*#";
    static const char *const glyphs[] = {
        "...............",
        "####.##.##.####", ".#.##..#..#.###", "###..#####..###", "###..#.##..####", "#.##.####..#..#",
        "####..###..####", "####..####.####", "###..#..#.#..#.", "####.#####.####", "####.####..####",
        ".#.#.#####.##.#", "##.#.###.#.###.", ".###..#..#...##", "##.#.##.##.###.", "####..##.#..###",
        "####..##.#..#..", ".###..#.##.#.##", "#.##.#####.##.#", "###.#..#..#.###", "..#..#..##.#.#.",
        "#.##.###.#.##.#", "#..#..#..#..###", "#.########.##.#", "##.#.##.##.##.#", ".#.#.##.##.#.#.",
        "##.#.###.#..#..", ".#.#.##.###..##", "##.#.###.#.##.#", ".###...#...###.", "###.#..#..#..#.",
        "#.##.##.##.####", "#.##.##.##.#.#.", "#.##.########.#", "#.##.#.#.#.##.#", "#.##.#.#..#..#.",
        "###..#.#.#..###",
        ".............#.", "..........#.#..", "....#.....#....", "....#.....#.#..", "......###......",
        "............###", "....#.###.#....", "...###...###...", "..#..#.#.#..#..", ".#..#..#..#..#.",
        "..#.#..#..#...#", "#...#..#..#.#..", "##.#..#..#..##.", ".##..#..#..#.##", "#.#..#.#.#..#.#",
        ".#..#..........", "#.##.#.........", ".#..#..#.....#.", "##...#.#.....#.", "..#.#.#...#...#",
        "#...#...#.#.#..", "...#.#.#.#.#...", "#.#####.#####.#"};
    const char *p;
    if (c >= 'a' && c <= 'z') c -= 'a' - 'A';
    p = c ? strchr(chars, c) : NULL;
    if (!p) return NULL;
    return glyphs[p - chars];
}

SRDEF void sr_draw_text(sr_image8 *img, int x, int y, const char *text, int scale, const uint8_t rgb[3])
{
    int gx, gy, sx, sy, k;
    if (!img || !img->pixels || !text || !rgb) return;
    if (scale < 1) scale = 1;
    for (; *text; text++, x += 4 * scale) {
        const char *g = sr__glyph((unsigned char)*text);
        for (gy = 0; gy < 5; gy++)
            for (gx = 0; gx < 3; gx++) {
                int on = g ? (strlen(g) > (size_t)(gy * 3 + gx) && g[gy * 3 + gx] == '#') : (gx == 0 || gx == 2 || gy == 0 || gy == 4);
                if (!on) continue;
                for (sy = 0; sy < scale; sy++)
                    for (sx = 0; sx < scale; sx++) {
                        int px = x + gx * scale + sx, py = y + gy * scale + sy;
                        uint8_t *o;
                        if (px < 0 || py < 0 || px >= img->width || py >= img->height) continue;
                        o = img->pixels + ((size_t)py * (size_t)img->width + (size_t)px) * (size_t)img->channels;
                        if (img->channels >= 3) for (k = 0; k < 3; k++) o[k] = rgb[k];
                        else o[0] = rgb[1];
                    }
            }
    }
}

SRDEF sr_result sr_contact_sheet(const sr_image8 *images, const char *const *captions, int count, int columns,
                                 const sr_allocator *allocator, sr_image8 *out)
{
    int i, cw = 0, ch = 0, rows, margin = 8, caption_h = 5 * 2 + 8, W, H;
    sr_allocator a;
    size_t n;
    if (!out) return SR_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!images || count < 1) return SR_ERR_INVALID_ARGUMENT;
    for (i = 0; i < count; i++) {
        if (!images[i].pixels || images[i].width < 1 || images[i].height < 1 || (images[i].channels != 3 && images[i].channels != 4))
            return SR_ERR_INVALID_ARGUMENT;
        if (images[i].width > cw) cw = images[i].width;
        if (images[i].height > ch) ch = images[i].height;
        if (captions && captions[i]) { /* cells are wide enough for their captions (8 px per character) */
            size_t len = strlen(captions[i]);
            int tw = len > 2000 ? 16000 : 8 * (int)len;
            if (tw > cw) cw = tw;
        }
    }
    if (columns < 1 || columns > count) columns = count;
    rows = (count + columns - 1) / columns;
    if (cw > 16384 || ch > 16384 || columns > 64 || rows > 64) return SR_ERR_TOO_LARGE;
    W = margin + columns * (cw + margin);
    H = margin + rows * (ch + caption_h + margin);
    a = sr__resolve_allocator(allocator);
    n = (size_t)W * (size_t)H * 3;
    out->pixels = (uint8_t *)sr__alloc(&a, n);
    if (!out->pixels) return SR_ERR_OUT_OF_MEMORY;
    memset(out->pixels, 255, n);
    out->width = W; out->height = H; out->channels = 3;
    for (i = 0; i < count; i++) {
        const sr_image8 *im = &images[i];
        int ox = margin + (i % columns) * (cw + margin), oy = margin + (i / columns) * (ch + caption_h + margin), x, y;
        static const uint8_t black[3] = {0, 0, 0};
        for (y = 0; y < im->height; y++)
            for (x = 0; x < im->width; x++)
                memcpy(out->pixels + ((size_t)(oy + y) * (size_t)W + (size_t)(ox + x)) * 3,
                       im->pixels + ((size_t)y * (size_t)im->width + (size_t)x) * (size_t)im->channels, 3);
        if (captions && captions[i]) sr_draw_text(out, ox, oy + ch + 4, captions[i], 2, black);
    }
    return SR_OK;
}

#ifdef __cplusplus
}
#endif
#if defined(__clang__) && (__clang_major__ >= 13 || (__clang_major__ >= 11 && !defined(__apple_build_version__)))
#pragma float_control(pop)
#elif defined(__GNUC__) && !defined(__clang__) && !defined(__INTEL_COMPILER)
#pragma GCC pop_options
#endif
#endif /* SR_IMPLEMENTATION_DONE */
#endif /* SR_IMPLEMENTATION */

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
------------------------------------------------------------------------------
*/
