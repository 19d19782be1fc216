/* grass - paper 002's withering grass (time-varying texels, texel.h) over a subdiv4.h terrain,
   drawn by render.h's shell marcher (sr_draw_shell) with texel.h's sampler, written with its PNG writer.

   usage: grass [--scene mountain|mesh|wither|mingle] -o OUT.png [--size WxH] [--res R] [--tiles N]
                [--mesh sphere|hill|FILE [--mesh-cells N]] [--wd A,B,C] [--wd-sun G]
                [--wd-map GREY.png [--wd-map-gain G]] [--lod-bias B] [--frames F] [--seed S] [--quiet]
     --scene   mountain (default): the paper's Fig 13, N x N tiles (80: 6400 tiles of 400 blades,
                 2.56M blades) on a four-point terrain, one panel per wd (default 0,0.30,0.917);
               mesh: grass over a mesh shell (render.h's sr_draw_mesh_shell), one panel per wd
                 (default 0.45), each tile's wd from a map over the mesh's tile coordinates:
                 wd + G (the tile's facing toward the sun less the mesh's mean) / 2, G = --wd-sun
                 (0.9), or a grey --wd-map stretched over the tiles;
               wither: one 400-blade patch seen close, at wd 0 .. 1 in six panels;
               mingle: the paper's Fig 11: two mingling functions (rows t1, t2) at three wd,
                 and 700 against 300 blades (row b).
     --size    panel size in pixels (default 800x600 for mountain, 320x240 for the others)
     --res     texel resolution, a power of two (default 64)
     --tiles   tiles per side of the mountain (default 80)
     --frames  key frames per TVT (default 6)
     --wd-map  a grey image over the mountain (row 0 at the far, +y edge): each tile's wd is
                 wd + G (grey - 0.5) at the tile's centre (plus the jitter), instead of the
                 slope term; G = --wd-map-gain (1)
     --mesh    sphere (a cube-sphere, 8 x 8 tiles per face), hill (a 12 x 12 bump of 24 x 24 tiles) or
                 a mesh file (y up), made coarse by clustering its vertices on N cells across
                 (--mesh-cells, 40), with box-projection charts and a shell of 0.4 tile (a file's
                 mesh may bend sharply; texel.h reports the folded prisms, the marcher skips them)
     --lod-bias  levels 2^B times coarser than the footprint asks (0): B = 1 halves the samples
                 and about halves the mountain's render time, a little blurrier
   Each panel prints "RESULT grass scene=... wd=... coverage=... render_ms=...". Progress goes to
   stderr. Exit status 0 on success, 2 on bad arguments (named in the message), 1 on failure. The
   PNG is written to OUT.png.tmp and renamed when complete, so a failed run leaves nothing.
   --version prints the version.

   The terrain is drawn by render.h's shell marcher (sr_draw_shell): it clips rays to the grass
   shell between the ground and one tile above it, jumps over the space above the shell, maps
   each sample to its tile's sheared frame (blades stay upright on slopes), does Kajiya-Kay
   shading with the sample's self-shadow, and stops on the ground or when opaque. texel.h
   supplies the content through one callback (grass_sample): the LOD level from the pixel's
   footprint, one voxel of that level per step, empty space skipped with the coarsest level.
   Each tile has its own wd (drier on slopes facing the sun, plus a per-tile jitter) and one of
   four mingled TVT variants. The mesh scene does the same over a triangle mesh's shell
   (sr_draw_mesh_shell walks its prisms; texel.h's tvt_build_shell checks them for folds and
   tvt_tile_wd reads the per-tile wd map). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <time.h>

#define TVT_IMPLEMENTATION
#include "texel.h"
#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#define SR_IMPLEMENTATION
#include "render.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#define CLI_IMPLEMENTATION
#include "cli.h"
#include <errno.h>
#include <limits.h>

#define VARIANTS 4
#define SAMPLES 7

typedef struct scene {
    int tiles;                 /* tiles per side */
    float tile;                /* world size of a tile (and of the shell height) */
    int hn;                    /* height samples per side */
    float *h;                  /* hn * hn heights over [0, tiles * tile]^2, NULL = flat */
    float hmax;
    const tvt_tvt *variant[VARIANTS];
    const tvt_shadow *shadow[VARIANTS];
    int variant_count;
    float wd, wd_sun, wd_jitter; /* per tile: wd + wd_sun * sun-facing slope + jitter */
    const float *wd_map;       /* or, if not NULL: wd + wd_map_gain * (map - 0.5) + jitter, the */
    int map_w, map_h;          /*   map_w x map_h grey map stretched over the terrain, row 0 at */
    float wd_map_gain;         /*   the far (+y) edge, sampled at each tile's centre */
    float sun[3];
    float eye[3], target[3], fovy;
    float lod_scale;           /* the footprint's multiplier for the level choice: 2^lod_bias (0 = 1) */
    int res;
} scene;

static int quiet = 0;
static double samples_per_pixel = 0; /* of the last render: sample calls / pixels */


/* "\rWHAT NN%" each time another tenth is done (the final line ends with a newline) */
static int last_tenth = -1;
static int progress_print(void *user, float done)
{
    int tenth = (int)(10.0f * done);
    if (!quiet && tenth != last_tenth) fprintf(stderr, "\r%s %3d%%", (const char *)user, 10 * tenth);
    last_tenth = tenth;
    return 0;
}

static void progress_end(const char *what)
{
    if (!quiet) fprintf(stderr, "\r%s done\n", what);
    last_tenth = -1;
}

/* ---- terrain ------------------------------------------------------------------------------- */
/* A 9x9 random control grid refined 4 levels by the four-point scheme (paper 001's mountain5
   look: w 0.2, amplitude 0.3 of the span), lifted so that its lowest point is 0. */
static int make_mountain(scene *s, uint64_t seed)
{
    double ctrl[81], *fine;
    size_t nx, ny, i;
    float lo = 1e30f, span = (float)s->tiles * s->tile;
    if (sd4_random_heights(9, 9, 0.3 * span, 1, seed, NULL, ctrl) != SD4_OK) return 0;
    { /* a broad summit in the middle */
        int i2, j2;
        for (j2 = 3; j2 <= 5; j2++)
            for (i2 = 3; i2 <= 5; i2++) ctrl[j2 * 9 + i2] += (i2 == 4 && j2 == 4 ? 0.16 : 0.08) * span;
    }
    if (sd4_grid_size(9, 9, 4, NULL, &nx, &ny) != SD4_OK) return 0;
    fine = (double *)malloc(nx * ny * sizeof(double));
    s->h = (float *)malloc(nx * ny * sizeof(float));
    if (!fine || !s->h || sd4_grid_refine(ctrl, 9, 9, 1, 0.2, 4, NULL, fine, nx * ny) != SD4_OK) {
        free(fine);
        return 0;
    }
    s->hn = (int)nx;
    for (i = 0; i < nx * ny; i++) if ((float)fine[i] < lo) lo = (float)fine[i];
    s->hmax = 0.0f;
    for (i = 0; i < nx * ny; i++) {
        s->h[i] = (float)fine[i] - lo;
        if (s->h[i] > s->hmax) s->hmax = s->h[i];
    }
    free(fine);
    return 1;
}

/* ---- the shell over the terrain: render.h's marcher, texel.h's content ------------------------- */
/* the terrain as render.h's shell: heights over [0, tiles * tile]^2, one tile of the TVT per tile */
static void shell_of(const scene *s, sr_shell_desc *d)
{
    sr_shell_desc_default(d);
    d->heights = s->h;
    d->nx = d->ny = s->hn;
    d->spacing = s->h ? (float)s->tiles * s->tile / (float)(s->hn - 1) : 1.0f;
    d->tile = s->tile;
    d->tiles_x = d->tiles_y = s->tiles;
}

static uint32_t tile_hash(int i, int j)
{
    uint32_t h = (uint32_t)i * 73856093u ^ (uint32_t)j * 19349663u;
    h ^= h >> 13; h *= 0x5bd1e995u; h ^= h >> 15;
    return h;
}

static float tile_wd(const scene *s, const sr_shell_desc *shell, int i, int j)
{
    float g[2], n[3], l, facing, wd, jitter = s->wd_jitter * ((float)(tile_hash(i, j) & 1023) / 1023.0f - 0.5f);
    if (s->wd_map) { /* the map's pixel under the tile's centre */
        int x = (int)(((float)i + 0.5f) / (float)s->tiles * (float)s->map_w);
        int y = (int)((1.0f - ((float)j + 0.5f) / (float)s->tiles) * (float)s->map_h);
        x = x < 0 ? 0 : x >= s->map_w ? s->map_w - 1 : x;
        y = y < 0 ? 0 : y >= s->map_h ? s->map_h - 1 : y;
        wd = s->wd + s->wd_map_gain * (s->wd_map[(size_t)y * (size_t)s->map_w + (size_t)x] - 0.5f) + jitter;
        return wd < 0 ? 0 : wd > 1 ? 1 : wd;
    }
    sr_shell_height(shell, ((float)i + 0.5f) * s->tile, ((float)j + 0.5f) * s->tile, g);
    n[0] = -g[0]; n[1] = -g[1]; n[2] = 1.0f;
    l = sqrtf(n[0] * n[0] + n[1] * n[1] + 1.0f);
    facing = (n[0] * s->sun[0] + n[1] * s->sun[1] + n[2] * s->sun[2]) / l - s->sun[2]; /* 0 on flat ground */
    wd = s->wd + s->wd_sun * facing + jitter;
    return wd < 0 ? 0 : wd > 1 ? 1 : wd;
}

/* the sample callback's state: the scene and the last tile's variant and wd */
typedef struct grass_view {
    const scene *s;
    const sr_shell_desc *shell;
    const tvt_wd_map *map;     /* a mesh shell's per-tile wd (NULL: the terrain's tile_wd) */
    int ci, cj, v;
    float wd;
} grass_view;

/* One sample for render.h: the level whose voxel fits the pixel's footprint, one voxel of it per
   step; after an empty sample, space the coarsest level calls empty is skipped half a coarse
   voxel at a time. The tangent drives Kajiya-Kay; voxels without one are lit by their normal. */
static void grass_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    grass_view *g = (grass_view *)user;
    const scene *s = g->s;
    const tvt_tvt *tv;
    float res = (float)s->res, p[3], sigma;
    int level, coarse;
    tvt_voxel v;
    if (q->tile_x != g->ci || q->tile_y != g->cj) { /* a new tile: its variant and wd */
        g->ci = q->tile_x; g->cj = q->tile_y;
        g->v = (int)(tile_hash(g->cj, g->ci) % (uint32_t)s->variant_count);
        g->wd = g->map ? tvt_tile_wd(g->map, g->ci, g->cj) : tile_wd(s, g->shell, g->ci, g->cj);
    }
    tv = s->variant[g->v];
    p[0] = q->p[0] * res; p[1] = q->p[1] * res; p[2] = q->p[2] * res;
    level = tvt_lod_level_for(&tv->frames[0], (s->lod_scale > 0 ? s->lod_scale : 1.0f) * q->footprint * res);
    coarse = tv->frames[0].levels - 1;
    if (coarse > level && q->after_empty && tvt_tvt_density(tv, g->wd, coarse, p) <= 0.0f) {
        out->step = 0.5f * (float)(1 << coarse) / res;
        return;
    }
    out->step = (float)(1 << level) / res; /* one voxel of the level: the trilinear field has no finer detail */
    sigma = tvt_tvt_sample(tv, g->wd, level, p, q->dir, &v);
    if (!(sigma > 0.0f)) return;
    out->sigma = sigma * res;
    memcpy(out->rgb, v.color, sizeof(out->rgb));
    out->specular = v.specular;
    if (v.tangent[0] * v.tangent[0] + v.tangent[1] * v.tangent[1] + v.tangent[2] * v.tangent[2] > 0.01f)
        memcpy(out->tangent, v.tangent, sizeof(out->tangent));
    else memcpy(out->normal, v.normal, sizeof(out->normal));
    out->light = s->shadow[g->v] ? tvt_shadow_at(s->shadow[g->v], g->wd, p) : 1.0f;
}

static void sky(const float *d, float *rgb)
{
    float t = d[2] > 0 ? d[2] : 0;
    rgb[0] = 0.55f + 0.25f * (1 - t); rgb[1] = 0.7f + 0.15f * (1 - t); rgb[2] = 0.95f;
}

static uint8_t to_srgb8(float x)
{
    float y = x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
    y = y < 0 ? 0 : y > 1 ? 1 : y;
    return (uint8_t)(y * 255.0f + 0.5f);
}

/* a panel's framebuffer with the sky, its camera and the sun; 0 on failure */
static int panel_begin(const scene *s, int w, int hgt, sr_framebuffer *fb, sr_camera *cam, sr_light *sun, sr_image8 *img)
{
    float up[3] = {0, 0, 1};
    int x, y;
    img->pixels = NULL;
    if (sr_framebuffer_create(fb, w, hgt, NULL) != SR_OK) return 0;
    sr_camera_look_at(cam, s->eye, s->target, up, s->fovy, (float)w / (float)hgt, 0.1f, 1e4f);
    sr_framebuffer_clear(fb, NULL, 1.0f);
    for (y = 0; y < hgt; y++)
        for (x = 0; x < w; x++) {
            float o[3], d[3];
            sr_camera_ray(cam, w, hgt, (float)x + 0.5f, (float)y + 0.5f, o, d);
            sky(d, fb->color + 4 * ((size_t)y * w + x));
        }
    sr_light_default(sun, s->sun);
    sun->ambient[0] = 0.22f; sun->ambient[1] = 0.25f; sun->ambient[2] = 0.30f; /* a blue sky's fill light */
    sun->diffuse[0] = sun->diffuse[1] = sun->diffuse[2] = 1.0f;
    sun->specular[0] = sun->specular[1] = sun->specular[2] = 1.0f;
    return 1;
}

static void grass_material(sr_material *m)
{
    m->specular[0] = m->specular[1] = m->specular[2] = 0.35f;
    m->shininess = 24.0f;
    memset(m->emission, 0, sizeof(m->emission));
}

/* the framebuffer into img (sRGB 8-bit), freed; the coverage, or -1 on failure */
static double panel_end(sr_framebuffer *fb, sr_result r, const sr_shell_stats *stats, sr_image8 *img)
{
    size_t i, n = (size_t)fb->width * (size_t)fb->height;
    img->width = fb->width; img->height = fb->height; img->channels = 3;
    img->pixels = r == SR_OK ? (uint8_t *)malloc(n * 3) : NULL;
    if (r != SR_OK || !img->pixels) {
        fprintf(stderr, "grass: render: %s\n", r == SR_OK ? "out of memory" : sr_result_string(r));
        sr_framebuffer_free(fb);
        return -1;
    }
    for (i = 0; i < n; i++) {
        img->pixels[3 * i + 0] = to_srgb8(fb->color[4 * i + 0]);
        img->pixels[3 * i + 1] = to_srgb8(fb->color[4 * i + 1]);
        img->pixels[3 * i + 2] = to_srgb8(fb->color[4 * i + 2]);
    }
    sr_framebuffer_free(fb);
    samples_per_pixel = (double)stats->samples / (double)n;
    return (double)stats->covered / (double)n;
}

/* Renders a panel (sky, then render.h's shell marcher over it); returns the share of pixels
   whose grass opacity reached 0.5, or -1 on failure. */
static double render(const scene *s, int w, int hgt, sr_image8 *img, const char *what)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc shell;
    sr_shell_stats stats;
    sr_light sun;
    grass_view view;
    sr_result r;
    if (!panel_begin(s, w, hgt, &fb, &cam, &sun, img)) return -1;
    shell_of(s, &shell);
    shell.lights = &sun; shell.light_count = 1;
    grass_material(&shell.material);
    memset(&view, 0, sizeof(view));
    view.s = s; view.shell = &shell; view.ci = view.cj = -1;
    shell.sample = grass_sample; shell.user = &view;
    shell.progress = progress_print; shell.progress_user = (void *)what;
    r = sr_draw_shell(&fb, &cam, &shell, &stats);
    progress_end(what);
    return panel_end(&fb, r, &stats, img);
}

/* ---- building the TVTs ---------------------------------------------------------------------- */
typedef struct grass_set {
    tvt_tvt sample[SAMPLES];
    tvt_tvt variant[VARIANTS];
    tvt_shadow shadow[VARIANTS];
    int samples, variants;
} grass_set;

static int build_samples(grass_set *g, int res, int frames, uint64_t seed, int count)
{
    int k;
    for (k = 0; k < count; k++) {
        tvt_grass_desc d = tvt_grass_default_desc();
        tvt_tvt_options o = tvt_tvt_default_options();
        tvt_lod_options lo = tvt_lod_default_options();
        tvt_texel t;
        tvt_result r;
        char what[64];
        d.res = res; d.seed = seed * 1000 + (uint64_t)k;
        d.radius_min = 0.9f * (float)res / 64.0f; d.radius_max = 1.3f * (float)res / 64.0f;
        if (d.radius_min < 0.6f) d.radius_min = 0.6f;
        if (d.radius_max < d.radius_min) d.radius_max = d.radius_min;
        o.frames = frames;
        lo.levels = 1; /* mingling reads level 0 only; the variants get the pyramids */
        o.lod = &lo;
        snprintf(what, sizeof(what), "grass: TVT sample %d/%d", k + 1, count);
        o.progress = progress_print; o.progress_user = what;
        r = tvt_build_grass(&d, &t);
        if (r == TVT_OK) r = tvt_build_tvt(&t, &o, &g->sample[k]);
        tvt_texel_free(&t);
        if (r != TVT_OK) { fprintf(stderr, "grass: %s\n", tvt_result_string(r)); return 0; }
        g->samples = k + 1;
        progress_end(what);
    }
    return 1;
}

/* levels 0 = down to 8^3 (distant tiles are a few pixels) */
static int build_variant(grass_set *g, int v, const tvt_tvt *samples, const tvt_ageing_fn *fns, int count,
                         int frames, int levels, const float *sun)
{
    tvt_tvt_options o = tvt_tvt_default_options();
    tvt_lod_options lo = tvt_lod_default_options();
    tvt_result r;
    int res = samples[0].frames[0].level[0].res;
    o.frames = frames;
    lo.levels = 1;
    while ((res >> lo.levels) >= 8 && lo.levels < TVT_MAX_LEVELS && (levels == 0 || lo.levels < levels)) lo.levels++;
    o.lod = &lo;
    r = tvt_mingle_tvt(samples, fns, (size_t)count, &o, &g->variant[v]);
    if (r == TVT_OK) g->variants = v + 1;
    if (r == TVT_OK && sun) r = tvt_build_shadow(&g->variant[v], -1, sun, NULL, &g->shadow[v]);
    if (r != TVT_OK) { fprintf(stderr, "grass: mingling: %s\n", tvt_result_string(r)); return 0; }
    return 1;
}

/* The self-shadow volumes of every variant (the renderer's precomputation). */
static int build_shadows(grass_set *g, const float *sun)
{
    int v;
    for (v = 0; v < g->variants; v++) {
        tvt_result r;
        tvt_shadow_free(&g->shadow[v]);
        r = tvt_build_shadow(&g->variant[v], -1, sun, NULL, &g->shadow[v]);
        if (r != TVT_OK) { fprintf(stderr, "grass: shadows: %s\n", tvt_result_string(r)); return 0; }
    }
    return 1;
}

static void free_set(grass_set *g)
{
    int k;
    for (k = 0; k < g->samples; k++) tvt_tvt_free(&g->sample[k]);
    for (k = 0; k < g->variants; k++) { tvt_tvt_free(&g->variant[k]); tvt_shadow_free(&g->shadow[k]); }
}

/* Four variants of 400 blades: 4 of the 7 samples each, with ageing functions that spread the
   blades' ages (delays in -0.08..0.12, rates 0.9..1.3). */
static int build_mountain_variants(grass_set *g, int frames)
{
    int v, k;
    for (v = 0; v < VARIANTS; v++) {
        tvt_tvt pick[4];
        tvt_ageing_fn fn[4];
        for (k = 0; k < 4; k++) {
            int idx = (v * 3 + k * 2) % g->samples;
            pick[k] = g->sample[idx];
            fn[k].delay = -0.08f + 0.2f * (float)((v * 4 + k) * 37 % 11) / 10.0f;
            fn[k].rate = 0.9f + 0.4f * (float)((v * 4 + k) * 53 % 7) / 6.0f;
        }
        if (!build_variant(g, v, pick, fn, 4, frames, 0, NULL)) return 0;
    }
    return 1;
}

/* ---- scenes ---------------------------------------------------------------------------------- */
static void set_sun(scene *s)
{
    float l = sqrtf(0.5f * 0.5f + 0.35f * 0.35f + 0.8f * 0.8f);
    s->sun[0] = 0.5f / l; s->sun[1] = 0.35f / l; s->sun[2] = 0.8f / l;
}

/* The paper's mountain (Fig 13): the terrain, 7 samples of 100 blades, 4 variants of 400 (their
   pyramids; shadows are the renderer's, build_shadows), and the fixed camera. */
static int mountain_setup(scene *s, grass_set *g, int res, int tiles, int frames, uint64_t seed)
{
    int k;
    memset(g, 0, sizeof(*g));
    memset(s, 0, sizeof(*s));
    s->tiles = tiles; s->tile = 1.0f; s->res = res;
    s->wd_sun = 0.6f; s->wd_jitter = 0.08f;
    set_sun(s);
    if (!make_mountain(s, seed)) { fprintf(stderr, "grass: terrain failed\n"); return 0; }
    if (!build_samples(g, res, frames, seed, SAMPLES) || !build_mountain_variants(g, frames)) return 0;
    for (k = 0; k < g->variants; k++) { s->variant[k] = &g->variant[k]; s->shadow[k] = &g->shadow[k]; }
    s->variant_count = g->variants;
    s->target[0] = 0.5f * (float)tiles; s->target[1] = 0.55f * (float)tiles; s->target[2] = 0.3f * s->hmax;
    s->eye[0] = 0.12f * (float)tiles; s->eye[1] = -0.22f * (float)tiles;
    s->eye[2] = s->hmax + 0.12f * (float)tiles;
    s->fovy = 40.0f;
    return 1;
}

/* a grey map for the tiles' wd: channel 0 in [0, 1], m->v (free with free) */
typedef struct wd_map { float *v; int w, h; float gain; } wd_map;
/* ---- a mesh shell: grass over a triangle mesh (render.h's sr_draw_mesh_shell) ------------------ */
typedef struct gmesh { float *pos, *nrm, *uv; uint32_t *idx; size_t nv, nt; } gmesh;

static void gmesh_free(gmesh *m)
{
    free(m->pos); free(m->nrm); free(m->uv); free(m->idx);
    memset(m, 0, sizeof(*m));
}

static int gmesh_alloc(gmesh *m, size_t nv, size_t nt)
{
    m->nv = nv; m->nt = nt;
    m->pos = (float *)malloc(nv * 3 * sizeof(float)); m->nrm = (float *)malloc(nv * 3 * sizeof(float));
    m->uv = (float *)malloc(nv * 2 * sizeof(float)); m->idx = (uint32_t *)malloc(nt * 3 * sizeof(uint32_t));
    if (m->pos && m->nrm && m->uv && m->idx) return 1;
    gmesh_free(m);
    fprintf(stderr, "grass: out of memory\n");
    return 0;
}

/* A cube-sphere of radius r: each cube face an n x n grid pushed onto the sphere, its own chart
   of `tiles` x `tiles` tiles (face f's u offset by f tiles, so every tile is distinct; the
   charts meet at the cube's edges, where the walk crosses from one chart to the next). */
static int make_sphere(gmesh *m, int n, float r, int tiles)
{
    int f, i, j;
    size_t v = 0, t = 0;
    if (!gmesh_alloc(m, 6 * (size_t)(n + 1) * (n + 1), 12 * (size_t)n * n)) return 0;
    for (f = 0; f < 6; f++) {
        int ax = f / 2;
        float sg = f % 2 ? -1.0f : 1.0f;
        size_t base = v;
        for (j = 0; j <= n; j++)
            for (i = 0; i <= n; i++, v++) {
                float a = tanf(0.785398f * (2.0f * (float)i / (float)n - 1.0f)), b = tanf(0.785398f * (2.0f * (float)j / (float)n - 1.0f));
                float c[3], l;
                int k;
                c[ax] = sg; c[(ax + 1) % 3] = sg * a; c[(ax + 2) % 3] = b; /* equal angles, not equal steps */
                l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                for (k = 0; k < 3; k++) { m->nrm[3 * v + k] = c[k] / l; m->pos[3 * v + k] = r * c[k] / l; }
                m->uv[2 * v] = (float)tiles * ((float)i / (float)n + (float)f);
                m->uv[2 * v + 1] = (float)tiles * (float)j / (float)n;
            }
        for (j = 0; j < n; j++)
            for (i = 0; i < n; i++) {
                uint32_t a = (uint32_t)(base + (size_t)j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
                uint32_t *q = m->idx + 3 * t;
                q[0] = a; q[1] = b; q[2] = d; q[3] = a; q[4] = d; q[5] = c;
                t += 2;
            }
    }
    return 1;
}

/* A hill: an n x n grid over [0, size]^2 with a broad bump and a ridge, normals of the grid,
   uv = xy / tile (one chart). */
static int make_hill(gmesh *m, int n, float size, float tile)
{
    int i, j;
    if (!gmesh_alloc(m, (size_t)n * n, 2 * (size_t)(n - 1) * (n - 1))) return 0;
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            size_t v = (size_t)j * n + i;
            float x = size * (float)i / (float)(n - 1), y = size * (float)j / (float)(n - 1);
            float dx = (x - 0.55f * size) / (0.25f * size), dy = (y - 0.5f * size) / (0.3f * size);
            m->pos[3 * v] = x; m->pos[3 * v + 1] = y;
            m->pos[3 * v + 2] = 0.28f * size * expf(-0.5f * (dx * dx + dy * dy)) + 0.04f * size * sinf(6.2831853f * x / size) * cosf(3.14159265f * y / size);
            m->uv[2 * v] = x / tile; m->uv[2 * v + 1] = y / tile;
        }
    for (j = 0; j + 1 < n; j++)
        for (i = 0; i + 1 < n; i++) {
            uint32_t a = (uint32_t)(j * n + i), b = a + 1, c = a + (uint32_t)n, d = c + 1;
            uint32_t *q = m->idx + 6 * ((size_t)j * (n - 1) + i);
            q[0] = a; q[1] = b; q[2] = d; q[3] = a; q[4] = d; q[5] = c;
        }
    return sr_compute_vertex_normals(m->pos, m->nv, m->idx, m->nt, m->nrm) == SR_OK;
}

/* A mesh file (y up, turned to z up) made coarse and given tile coordinates: vertices clustered on a grid of `cells`
   along the bounding box's longest side (dispmesh's coarse bunny look; collapsed triangles
   dropped), smooth normals, then box-projection charts: each triangle goes to the axis its
   normal is closest to and its vertices are repeated per chart, uv = the other two coordinates
   / tile. */
static int load_mesh(gmesh *m, const char *path, int cells, float *tile, float *radius, float centre[3])
{
    mio_mesh in;
    mio_error err;
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f}, cell, *cpos = NULL, *cnrm = NULL, *cnt = NULL;
    uint32_t *cid = NULL, *tri = NULL, *slot = NULL;
    size_t i, nt = 0, nv = 0, ncells;
    int k, ok = 0;
    mio_result mr;
    memset(m, 0, sizeof(*m));
    errno = 0;
    if ((mr = mio_read_file(path, NULL, &in, &err)) != MIO_OK) {
        cli_read_error("grass", path, err.message, mio_result_string(mr), mio_result_description(mr), mr == MIO_ERR_IO ? errno : 0);
        return 0;
    }
    /* an STL soup repeats each position per triangle: one vertex each, so the clusters' means are
       those of the surface's vertices (a no-op on a welded mesh) */
    if ((mr = mio_weld(&in, &err)) != MIO_OK) {
        cli_read_error("grass", path, err.message, mio_result_string(mr), mio_result_description(mr), 0);
        mio_free_mesh(&in);
        return 0;
    }
    for (i = 0; i < in.vertex_count; i++) { /* y up (the files' custom) to z up: (x, y, z) -> (x, -z, y) */
        float y = in.positions[3 * i + 1];
        in.positions[3 * i + 1] = -in.positions[3 * i + 2];
        in.positions[3 * i + 2] = y;
    }
    for (i = 0; i < in.vertex_count; i++)
        for (k = 0; k < 3; k++) { lo[k] = fminf(lo[k], in.positions[3 * i + k]); hi[k] = fmaxf(hi[k], in.positions[3 * i + k]); }
    cell = fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2])) / (float)cells;
    if (!(cell > 0.0f) || in.triangle_count == 0) { fprintf(stderr, "grass: %s: an empty or flat mesh\n", path); goto done; }
    ncells = (size_t)(cells + 1) * (cells + 1) * (cells + 1);
    cid = (uint32_t *)malloc(in.vertex_count * sizeof(uint32_t));
    slot = (uint32_t *)malloc(ncells * sizeof(uint32_t));
    cpos = (float *)calloc(in.vertex_count * 3, sizeof(float));
    cnt = (float *)calloc(in.vertex_count, sizeof(float));
    tri = (uint32_t *)malloc(in.triangle_count * 3 * sizeof(uint32_t));
    if (!cid || !slot || !cpos || !cnt || !tri) { fprintf(stderr, "grass: out of memory\n"); goto done; }
    for (i = 0; i < ncells; i++) slot[i] = 0xFFFFFFFFu;
    for (i = 0; i < in.vertex_count; i++) { /* cluster: the mean of a cell's vertices */
        size_t c = 0;
        for (k = 2; k >= 0; k--) {
            int q = (int)((in.positions[3 * i + k] - lo[k]) / cell);
            c = c * (size_t)(cells + 1) + (size_t)(q < 0 ? 0 : q > cells ? cells : q);
        }
        if (slot[c] == 0xFFFFFFFFu) slot[c] = (uint32_t)nv++;
        cid[i] = slot[c];
        for (k = 0; k < 3; k++) cpos[3 * cid[i] + k] += in.positions[3 * i + k];
        cnt[cid[i]] += 1.0f;
    }
    for (i = 0; i < nv; i++) for (k = 0; k < 3; k++) cpos[3 * i + k] /= cnt[i];
    for (i = 0; i < in.triangle_count; i++) {
        uint32_t a = cid[in.indices[3 * i]], b = cid[in.indices[3 * i + 1]], c = cid[in.indices[3 * i + 2]];
        if (a == b || b == c || a == c) continue;
        tri[3 * nt] = a; tri[3 * nt + 1] = b; tri[3 * nt + 2] = c; nt++;
    }
    cnrm = (float *)malloc(nv * 3 * sizeof(float));
    if (!cnrm || nt == 0 || sr_compute_vertex_normals(cpos, nv, tri, nt, cnrm) != SR_OK) { fprintf(stderr, "grass: %s: no triangles left\n", path); goto done; }
    *tile = 2.0f * cell;
    *radius = 0.5f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (k = 0; k < 3; k++) centre[k] = 0.5f * (lo[k] + hi[k]);
    if (!gmesh_alloc(m, 3 * nt, nt)) goto done;
    free(slot); /* reused: the vertex of (cluster, chart), 3 per cluster */
    slot = (uint32_t *)malloc(3 * nv * sizeof(uint32_t));
    if (!slot) { fprintf(stderr, "grass: out of memory\n"); gmesh_free(m); goto done; }
    for (i = 0; i < 3 * nv; i++) slot[i] = 0xFFFFFFFFu;
    m->nv = 0;
    for (i = 0; i < nt; i++) { /* box-projection charts: a vertex per (cluster, chart), so a chart's prisms share faces */
        const float *p0 = cpos + 3 * tri[3 * i], *p1 = cpos + 3 * tri[3 * i + 1], *p2 = cpos + 3 * tri[3 * i + 2];
        float e1[3], e2[3], fn[3];
        int ax = 0, c;
        for (k = 0; k < 3; k++) { e1[k] = p1[k] - p0[k]; e2[k] = p2[k] - p0[k]; }
        fn[0] = e1[1] * e2[2] - e1[2] * e2[1]; fn[1] = e1[2] * e2[0] - e1[0] * e2[2]; fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
        for (k = 1; k < 3; k++) if (fabsf(fn[k]) > fabsf(fn[ax])) ax = k;
        for (c = 0; c < 3; c++) {
            size_t src = tri[3 * i + (size_t)c], v = slot[3 * src + (size_t)ax];
            m->idx[3 * i + (size_t)c] = (uint32_t)(v == 0xFFFFFFFFu ? m->nv : v);
            if (v != 0xFFFFFFFFu) continue;
            v = m->nv++;
            slot[3 * src + (size_t)ax] = (uint32_t)v;
            memcpy(m->pos + 3 * v, cpos + 3 * src, 3 * sizeof(float));
            memcpy(m->nrm + 3 * v, cnrm + 3 * src, 3 * sizeof(float));
            if (!(m->nrm[3 * v] * m->nrm[3 * v] + m->nrm[3 * v + 1] * m->nrm[3 * v + 1] + m->nrm[3 * v + 2] * m->nrm[3 * v + 2] > 1e-6f))
                memcpy(m->nrm + 3 * v, fn, 3 * sizeof(float)); /* opposite faces cancelled: the face's own */
            m->uv[2 * v] = cpos[3 * src + (ax + 1) % 3] / *tile + 64.0f * (float)ax;
            m->uv[2 * v + 1] = cpos[3 * src + (ax + 2) % 3] / *tile;
        }
    }
    ok = 1;
done:
    free(cid); free(slot); free(cpos); free(cnt); free(tri); free(cnrm);
    mio_free_mesh(&in);
    if (!ok) gmesh_free(m);
    return ok;
}

/* the per-tile wd over the mesh's tile coordinates: wd + gain * (the tile's mean facing toward
   the sun, less the whole mesh's) / 2 + jitter, or, with a grey map stretched over the tiles,
   wd + gain (grey - 0.5) + jitter */
typedef struct tile_map { float *wd; tvt_wd_map m; long covered; } tile_map; /* covered: tiles with triangles */

static int make_tile_map(const gmesh *g, const scene *s, float gain, const wd_map *grey, tile_map *out)
{
    float ulo = 1e30f, uhi = -1e30f, vlo = 1e30f, vhi = -1e30f, *acc, mean = 0.0f, area = 0.0f;
    size_t i, n;
    int w, h;
    memset(out, 0, sizeof(*out));
    for (i = 0; i < g->nv; i++) {
        ulo = fminf(ulo, g->uv[2 * i]); uhi = fmaxf(uhi, g->uv[2 * i]);
        vlo = fminf(vlo, g->uv[2 * i + 1]); vhi = fmaxf(vhi, g->uv[2 * i + 1]);
    }
    w = (int)floorf(uhi) - (int)floorf(ulo) + 1; h = (int)floorf(vhi) - (int)floorf(vlo) + 1;
    if (w < 1 || h < 1 || (double)w * h > 16e6) { fprintf(stderr, "grass: the mesh has too many tiles (%d x %d)\n", w, h); return 0; }
    n = (size_t)w * (size_t)h;
    out->wd = (float *)calloc(n, sizeof(float));
    acc = (float *)calloc(n, sizeof(float));
    if (!out->wd || !acc) { free(out->wd); free(acc); out->wd = NULL; fprintf(stderr, "grass: out of memory\n"); return 0; }
    out->m.wd = out->wd; out->m.width = w; out->m.height = h;
    out->m.origin[0] = (int)floorf(ulo); out->m.origin[1] = (int)floorf(vlo);
    for (i = 0; i < g->nt; i++) { /* each triangle's area-weighted facing into the tile of its centroid */
        const uint32_t *t = g->idx + 3 * i;
        const float *a = g->pos + 3 * t[0], *b = g->pos + 3 * t[1], *c = g->pos + 3 * t[2];
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]}, fn[3], area;
        int x = (int)floorf((g->uv[2 * t[0]] + g->uv[2 * t[1]] + g->uv[2 * t[2]]) / 3.0f) - out->m.origin[0];
        int y = (int)floorf((g->uv[2 * t[0] + 1] + g->uv[2 * t[1] + 1] + g->uv[2 * t[2] + 1]) / 3.0f) - out->m.origin[1];
        fn[0] = e1[1] * e2[2] - e1[2] * e2[1]; fn[1] = e1[2] * e2[0] - e1[0] * e2[2]; fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
        area = sqrtf(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
        if (!(area > 0.0f) || x < 0 || y < 0 || x >= w || y >= h) continue;
        out->wd[(size_t)y * w + x] += fn[0] * s->sun[0] + fn[1] * s->sun[1] + fn[2] * s->sun[2];
        acc[(size_t)y * w + x] += area;
    }
    for (i = 0; i < n; i++) { out->covered += acc[i] > 0.0f; mean += out->wd[i]; area += acc[i]; }
    mean = area > 0.0f ? mean / area : 0.0f; /* the facing relative to the mesh's mean (a hill's flat ground: 0) */
    for (i = 0; i < n; i++) {
        float jitter = s->wd_jitter * ((float)(tile_hash((int)(i % (size_t)w) + out->m.origin[0], (int)(i / (size_t)w) + out->m.origin[1]) & 1023) / 1023.0f - 0.5f);
        float v;
        if (grey && grey->v) { /* the grey map's pixel under the tile, row 0 at the top (largest v) */
            int gx = (int)(((float)(i % (size_t)w) + 0.5f) / (float)w * (float)grey->w);
            int gy = (int)((1.0f - ((float)(i / (size_t)w) + 0.5f) / (float)h) * (float)grey->h);
            v = s->wd + gain * (grey->v[(size_t)(gy < grey->h ? gy : grey->h - 1) * (size_t)grey->w + (size_t)(gx < grey->w ? gx : grey->w - 1)] - 0.5f);
        } else
            v = s->wd + 0.5f * gain * (acc[i] > 0.0f ? out->wd[i] / acc[i] - mean : 0.0f);
        out->wd[i] = v + jitter; /* tvt_tile_wd clamps to [0, 1] */
    }
    free(acc);
    return 1;
}

/* Renders a panel of the grass over the mesh shell (height along the normals, one texel high);
   returns the coverage, or -1 on failure. */
static double render_mesh(const scene *s, const gmesh *g, float height, const tvt_wd_map *map, int w, int hgt,
                          sr_image8 *img, const char *what)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_mesh_shell_desc d;
    sr_shell_stats stats;
    sr_light sun;
    grass_view view;
    sr_result r;
    if (!panel_begin(s, w, hgt, &fb, &cam, &sun, img)) return -1;
    sr_mesh_shell_desc_default(&d);
    d.positions = g->pos; d.normals = g->nrm; d.uvs = g->uv; d.vertex_count = g->nv;
    d.indices = g->idx; d.triangle_count = g->nt; d.height = height;
    d.lights = &sun; d.light_count = 1;
    grass_material(&d.material);
    memset(&view, 0, sizeof(view));
    view.s = s; view.map = map; view.ci = view.cj = -2147483647 - 1; /* no tile yet (tiles may be negative) */
    d.sample = grass_sample; d.user = &view;
    d.progress = progress_print; d.progress_user = (void *)what;
    r = sr_draw_mesh_shell(&fb, &cam, &d, &stats);
    progress_end(what);
    return panel_end(&fb, r, &stats, img);
}

/* The mesh scene's grass: 7 samples of 100 blades, 4 variants of 400, shadows for light from the
   tile's zenith (a mesh's tiles each see the sun from their own direction; one shadow volume
   per variant cannot follow it, so the self-shadow is the depth below the top, and the
   direction's part is Kajiya-Kay's and the marcher's horizon cut). */
static int mesh_grass(scene *s, grass_set *g, int res, int frames, uint64_t seed)
{
    const float zenith[3] = {0, 0, 1};
    int k;
    memset(g, 0, sizeof(*g));
    if (!build_samples(g, res, frames, seed, SAMPLES) || !build_mountain_variants(g, frames) || !build_shadows(g, zenith)) return 0;
    for (k = 0; k < g->variants; k++) { s->variant[k] = &g->variant[k]; s->shadow[k] = &g->shadow[k]; }
    s->variant_count = g->variants;
    return 1;
}

/* The mesh, its shell height (one tile: blades keep the texel's proportions) and the camera:
   kind "sphere", "hill" or a mesh file. */
static int mesh_setup(scene *s, gmesh *g, float *height, const char *kind, int cells, int res)
{
    float tile, radius, c[3] = {0, 0, 0};
    memset(s, 0, sizeof(*s));
    s->res = res; s->wd_jitter = 0.08f;
    set_sun(s);
    s->fovy = 40.0f;
    if (!strcmp(kind, "hill")) {
        if (!make_hill(g, 65, 12.0f, 0.5f)) return 0;
        s->target[0] = 6.5f; s->target[1] = 6.5f; s->target[2] = 1.2f;
        s->eye[0] = 0.5f; s->eye[1] = -5.0f; s->eye[2] = 6.5f;
        *height = 0.5f;
        return 1;
    }
    if (!strcmp(kind, "sphere")) {
        if (!make_sphere(g, 24, 1.0f, 8)) return 0;
        *height = 1.5708f / 8.0f; /* a tile: a face's quarter circle over 8 tiles */
        radius = 1.0f + *height;
    } else {
        if (!load_mesh(g, kind, cells, &tile, &radius, c)) return 0;
        *height = 0.4f * tile; /* a file's mesh may bend sharply anywhere: a short lawn (blades squashed 2.5x) */
        radius *= 0.7f;        /* the bounding box's half diagonal overstates a shape's size */
    }
    s->target[0] = c[0]; s->target[1] = c[1]; s->target[2] = c[2];
    s->eye[0] = c[0] + 1.2f * radius; s->eye[1] = c[1] - 3.4f * radius; s->eye[2] = c[2] + 1.5f * radius; /* the sun's side */
    return 1;
}

#ifndef GRASS_NO_MAIN /* bench/bench_texel.c includes this file for the mountain */
#define GRASS_VERSION "grass 0.2 (texel.h, subdiv4.h, render.h, meshio.h)"

static double now_ms(void) { return 1e3 * (double)clock() / CLOCKS_PER_SEC; }

/* The contact sheet of the panels, written to PATH.tmp and renamed to PATH when complete. */
static int write_sheet(const sr_image8 *panels, const char *const *captions, int count, int columns, const char *path)
{
    sr_image8 sheet;
    cli_outputs outs;
    const char *tmp;
    int saved = 0;
    sr_result r = sr_contact_sheet(panels, captions, count, columns, NULL, &sheet);
    cli_outputs_init(&outs);
    if (r == SR_OK && !(tmp = cli_output_add(&outs, "grass", path))) { sr_free(NULL, sheet.pixels); return 0; }
    if (r == SR_OK) {
        errno = 0;
        r = sr_write_png(tmp, sheet.pixels, sheet.width, sheet.height, 3, 0);
        saved = errno;
    }
    if (sheet.pixels) sr_free(NULL, sheet.pixels);
    if (r != SR_OK) {
        cli_result_error("grass", path, sr_result_string(r), r == SR_ERR_IO ? saved : 0);
        cli_outputs_discard(&outs);
        return 0;
    }
    if (!cli_outputs_commit(&outs, "grass")) return 0;
    if (!quiet) fprintf(stderr, "grass: wrote %s\n", path);
    return 1;
}


static int read_wd_map(const char *path, wd_map *m)
{
    sr_picture pic;
    sr_result r;
    errno = 0;
    r = sr_read_image(path, NULL, &pic);
    if (r != SR_OK) { cli_result_error("grass", path, sr_result_string(r), r == SR_ERR_IO ? errno : 0); return 0; }
    m->w = pic.width; m->h = pic.height;
    m->v = (float *)malloc(sizeof(float) * (size_t)pic.width * (size_t)pic.height);
    if (!m->v || sr_picture_channel(&pic, 0, m->v) != SR_OK) {
        fprintf(stderr, "grass: %s: out of memory\n", path);
        free(m->v);
        m->v = NULL;
        sr_picture_free(&pic);
        return 0;
    }
    sr_picture_free(&pic);
    return 1;
}

static int scene_mountain(int w, int h, int res, int tiles, int frames, uint64_t seed, const float *wds, int nwd,
                          const wd_map *map, int lod_bias, const char *path)
{
    grass_set g;
    scene s;
    sr_image8 panels[8];
    char caption[8][64];
    const char *caps[8];
    int k, ok, done = 0;
    ok = mountain_setup(&s, &g, res, tiles, frames, seed);
    if (map->v) { s.wd_map = map->v; s.map_w = map->w; s.map_h = map->h; s.wd_map_gain = map->gain; }
    s.lod_scale = (float)(1 << lod_bias);
    for (k = 0; ok && k < nwd; k++) {
        double t0 = now_ms(), cov;
        char what[64];
        s.wd = wds[k];
        snprintf(what, sizeof(what), "grass: mountain wd %.3f", wds[k]);
        ok = build_shadows(&g, s.sun);
        cov = ok ? render(&s, w, h, &panels[k], what) : -1;
        if (cov < 0) { ok = 0; break; }
        done = k + 1;
        printf("RESULT grass scene=mountain wd=%.3f width=%d height=%d tiles=%d blades=%d coverage=%.3f render_ms=%.0f "
               "samples_per_pixel=%.1f\n", wds[k], w, h, tiles * tiles, tiles * tiles * 400, cov, now_ms() - t0,
               samples_per_pixel);
        snprintf(caption[k], sizeof(caption[k]), "wd = %.3f", wds[k]);
        caps[k] = caption[k];
    }
    if (ok) ok = write_sheet(panels, caps, nwd, nwd, path);
    for (k = 0; k < done; k++) free(panels[k].pixels);
    free(s.h);
    free_set(&g);
    return ok;
}

/* A flat 3 x 3 patch of tiles seen from the side, for the close-up scenes. */
static void close_up(scene *s, int res)
{
    s->tiles = 3; s->tile = 1.0f; s->res = res; s->h = NULL; s->hmax = 0;
    s->wd_sun = 0; s->wd_jitter = 0;
    set_sun(s);
    s->target[0] = 1.5f; s->target[1] = 1.5f; s->target[2] = 0.3f;
    s->eye[0] = 1.5f; s->eye[1] = -1.3f; s->eye[2] = 1.3f;
    s->fovy = 40.0f;
}

static int scene_wither(int w, int h, int res, int frames, uint64_t seed, const char *path)
{
    grass_set g;
    scene s;
    sr_image8 panels[6];
    char caption[6][32];
    const char *caps[6];
    int k, ok;
    memset(&g, 0, sizeof(g));
    memset(&s, 0, sizeof(s));
    close_up(&s, res);
    ok = build_samples(&g, res, frames, seed, 4);
    if (ok) ok = build_variant(&g, 0, g.sample, NULL, 4, frames, 2, s.sun);
    s.variant[0] = &g.variant[0]; s.shadow[0] = &g.shadow[0]; s.variant_count = 1;
    for (k = 0; ok && k < 6; k++) {
        s.wd = (float)k / 5.0f;
        snprintf(caption[k], sizeof(caption[k]), "wd = %.1f", s.wd);
        caps[k] = caption[k];
        if (render(&s, w, h, &panels[k], caption[k]) < 0) ok = 0;
    }
    if (ok) ok = write_sheet(panels, caps, 6, 3, path);
    for (k = 0; k < 6; k++) free(panels[k].pixels);
    free_set(&g);
    return ok;
}

/* Fig 11: rows t1 and t2 mingle all 7 samples with two sets of ageing functions (t1: ages
   spread by delays, t2: by rates); row b compares 700 and 300 blades at wd 0.5. */
static int scene_mingle(int w, int h, int res, int frames, uint64_t seed, const char *path)
{
    grass_set g;
    scene s;
    sr_image8 panels[9];
    char caption[9][48];
    const char *caps[9];
    tvt_ageing_fn f1[SAMPLES], f2[SAMPLES];
    const float wds[3] = {0.2f, 0.45f, 0.7f};
    int k, ok, n = 0;
    memset(&g, 0, sizeof(g));
    memset(&s, 0, sizeof(s));
    close_up(&s, res);
    ok = build_samples(&g, res, frames, seed, SAMPLES);
    for (k = 0; k < SAMPLES; k++) {
        f1[k].delay = -0.2f + 0.4f * (float)k / (SAMPLES - 1); f1[k].rate = 1.0f;
        f2[k].delay = 0.0f; f2[k].rate = 0.6f + 1.2f * (float)k / (SAMPLES - 1);
    }
    if (ok) ok = build_variant(&g, 0, g.sample, f1, SAMPLES, frames, 2, s.sun);
    if (ok) ok = build_variant(&g, 1, g.sample, f2, SAMPLES, frames, 2, s.sun);
    if (ok) ok = build_variant(&g, 2, g.sample, f1, 3, frames, 2, s.sun);
    s.variant_count = 1;
    for (k = 0; ok && k < 9; k++) {
        int v = k < 3 ? 0 : k < 6 ? 1 : (k == 6 ? 0 : 2);
        s.variant[0] = &g.variant[v]; s.shadow[0] = &g.shadow[v];
        s.wd = k < 6 ? wds[k % 3] : 0.45f;
        if (k < 6) snprintf(caption[k], sizeof(caption[k]), "t%d wd %.2f", k / 3 + 1, s.wd);
        else if (k == 6) snprintf(caption[k], sizeof(caption[k]), "b 700 blades");
        else if (k == 7) snprintf(caption[k], sizeof(caption[k]), "b 300 blades");
        else snprintf(caption[k], sizeof(caption[k]), "t2 700 wd 0.45");
        if (k == 8) { s.variant[0] = &g.variant[1]; s.shadow[0] = &g.shadow[1]; }
        caps[k] = caption[k];
        if (render(&s, w, h, &panels[k], caption[k]) < 0) ok = 0;
        n = k + 1;
    }
    if (ok) ok = write_sheet(panels, caps, 9, 3, path);
    for (k = 0; k < n; k++) free(panels[k].pixels);
    free_set(&g);
    return ok;
}

/* Grass over a mesh shell (issue 19 point 4): one panel per wd, each tile's wd from a map over
   the mesh's tile coordinates (drier where the tile faces the sun, or a grey map). */
static int scene_mesh(int w, int h, int res, int frames, uint64_t seed, const float *wds, int nwd, const wd_map *grey,
                      const char *kind, int cells, float gain, const char *path)
{
    grass_set g;
    scene s;
    gmesh m;
    sr_image8 panels[8];
    char caption[8][64];
    const char *caps[8];
    float height = 0;
    int k, ok, done = 0;
    memset(&g, 0, sizeof(g));
    ok = mesh_setup(&s, &m, &height, kind, cells, res);
    if (ok) { /* texel.h's check of the prisms: a folded one overlaps its neighbours */
        tvt_shell_desc sd;
        tvt_shell sh;
        tvt_result r;
        memset(&sd, 0, sizeof(sd));
        sd.positions = m.pos; sd.normals = m.nrm; sd.uvs = m.uv; sd.vertex_count = m.nv;
        sd.indices = m.idx; sd.triangle_count = m.nt; sd.height = height; sd.allow_folded = 1;
        r = tvt_build_shell(&sd, &sh);
        if (r != TVT_OK) { fprintf(stderr, "grass: the mesh shell: %s\n", tvt_result_string(r)); ok = 0; }
        else if (sh.folded && !quiet) fprintf(stderr, "grass: %zu of %zu prisms fold (the marcher skips their content)\n", sh.folded, m.nt);
        tvt_shell_free(&sh);
    }
    if (ok) ok = mesh_grass(&s, &g, res, frames, seed);
    for (k = 0; ok && k < nwd; k++) {
        double t0 = now_ms(), cov;
        char what[64];
        tile_map tm;
        s.wd = wds[k];
        snprintf(what, sizeof(what), "grass: mesh wd %.3f", wds[k]);
        if (!make_tile_map(&m, &s, grey && grey->v ? grey->gain : gain, grey, &tm)) { ok = 0; break; }
        cov = render_mesh(&s, &m, height, &tm.m, w, h, &panels[k], what);
        free(tm.wd);
        if (cov < 0) { ok = 0; break; }
        done = k + 1;
        printf("RESULT grass scene=mesh mesh=%s wd=%.3f width=%d height=%d triangles=%zu tiles=%ld blades=%ld coverage=%.3f "
               "render_ms=%.0f samples_per_pixel=%.1f\n", strchr(kind, '/') ? strrchr(kind, '/') + 1 : kind, wds[k], w, h,
               m.nt, tm.covered, 400 * tm.covered, cov, now_ms() - t0, samples_per_pixel);
        snprintf(caption[k], sizeof(caption[k]), "wd = %.3f", wds[k]);
        caps[k] = caption[k];
    }
    if (ok) ok = write_sheet(panels, caps, nwd, nwd, path);
    for (k = 0; k < done; k++) free(panels[k].pixels);
    gmesh_free(&m);
    free_set(&g);
    return ok;
}

static void usage(FILE *to)
{
    fprintf(to,
            "usage: grass [--scene mountain|mesh|wither|mingle] -o OUT.png [--size WxH] [--res R] [--tiles N]\n"
            "             [--mesh sphere|hill|FILE [--mesh-cells N]] [--wd A,B,C] [--wd-sun G]\n"
            "             [--wd-map GREY.png [--wd-map-gain G]] [--lod-bias B] [--frames F] [--seed S] [--quiet]\n"
            "Paper 002's withering grass (texel.h) over a terrain or a mesh shell, written as a PNG contact sheet.\n"
            "  --scene S          mountain (default): the paper's Fig 13 (N x N tiles of 400 blades), one panel\n"
            "                     per wd; mesh: grass over a mesh shell, drier where it faces the sun; wither:\n"
            "                     one patch at wd 0..1; mingle: the paper's Fig 11\n"
            "  -o, --output FILE  the PNG to write; the name must end in .png (required)\n"
            "  --size WxH         panel size, 16..8192 each (default 800x600 for mountain, 640x480 for mesh,\n"
            "                     320x240 otherwise)\n"
            "  --res R            texel resolution, a power of two in 16..256 (default 64)\n"
            "  --tiles N          mountain tiles per side, 1..1000 (default 80: 6400 tiles, 2.56M blades)\n"
            "  --mesh M           the mesh scene's mesh (implies --scene mesh): sphere (default), hill, or a mesh\n"
            "                     file (OBJ, OFF, PLY, STL; y up; an STL soup is welded first)\n"
            "  --mesh-cells N     a file's mesh is made coarse on N cells across, 4..512 (default 40)\n"
            "  --wd A,B,...       weathering degrees, one panel each, 1 to 8 values in [0, 1]\n"
            "                     (default 0,0.30,0.917; mesh 0.45)\n"
            "  --wd-sun G         mesh: a tile's wd is wd + G * (its facing toward the sun) / 2, G in [0, 2]\n"
            "                     (default 0.9)\n"
            "  --wd-map FILE      a grey image (PNG, PGM, PPM, PFM) over the mountain or the mesh's tiles: a tile's\n"
            "                     wd is wd + G * (grey - 0.5) at its centre, instead of the sun term (default: none)\n"
            "  --wd-map-gain G    the map's G, in [0, 2] (default 1)\n"
            "  --lod-bias B       mountain: levels 2^B times coarser than the pixel's footprint asks, 0..3 (default 0)\n"
            "  --frames F         key frames per TVT, 2..64 (default 6)\n"
            "  --seed S           terrain and blades, a non-negative integer (default 2010)\n"
            "  --quiet            no progress on stderr (default: progress)\n"
            "  -h, --help         show this help and exit\n"
            "  --version          show the version and exit\n"
            "Prints one RESULT grass line a panel on stdout.\n"
            "Exit status: 0 done, 1 failure (unreadable input, a failed build or render, a failed write), 2 usage.\n"
            "The PNG is written to FILE.tmp and renamed when complete: a failed run leaves nothing.\n");
}

int main(int argc, char **argv)
{
    static const char *const valued[] = {"-o", "--output", "--scene", "--size", "--res", "--tiles", "--frames", "--seed",
                                         "--wd-map", "--mesh", "--mesh-cells", "--wd-sun", "--lod-bias", "--wd-map-gain", "--wd"};
    const char *scene_name = "mountain", *out = NULL, *mesh_kind = "sphere";
    int w = 0, h = 0, res = 64, tiles = 80, frames = 6, nwd = 3, lod_bias = 0, cells = 40, wd_given = 0, i, k, ok;
    float wd_sun = 0.9f;
    float wds[8] = {0.0f, 0.30f, 0.917f};
    double d[8];
    long n;
    uint64_t seed = 2010;
    const char *map_path = NULL;
    wd_map map = {NULL, 0, 0, 1.0f};
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int takes = 0;
        for (k = 0; k < (int)(sizeof valued / sizeof valued[0]); k++) takes |= !strcmp(a, valued[k]);
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
        if (!strcmp(a, "--version")) { printf("%s\n", GRASS_VERSION); return 0; }
        if (!strcmp(a, "--quiet")) { quiet = 1; continue; }
        if (!takes) return cli_usage_error("grass", a[0] == '-' ? "unknown option '%s'" : "unexpected argument '%s'", a);
        if (!v) return cli_usage_error("grass", "%s needs a value", a);
        i++;
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) out = v;
        else if (!strcmp(a, "--scene")) {
            if (strcmp(v, "mountain") && strcmp(v, "mesh") && strcmp(v, "wither") && strcmp(v, "mingle"))
                return cli_usage_error("grass", "--scene '%s': not mountain, mesh, wither or mingle", v);
            scene_name = v;
        } else if (!strcmp(a, "--size")) {
            if (!cli_parse_size(v, 16, 8192, 0, &w, &h)) return cli_usage_error("grass", "--size '%s': not WxH with 16 <= W, H <= 8192", v);
        } else if (!strcmp(a, "--res")) {
            if (!cli_parse_long(v, 16, 256, &n) || (n & (n - 1))) return cli_usage_error("grass", "--res '%s': not a power of two in 16..256", v);
            res = (int)n;
        } else if (!strcmp(a, "--tiles")) {
            if (!cli_parse_long(v, 1, 1000, &n)) return cli_usage_error("grass", "--tiles '%s': not an integer in 1..1000", v);
            tiles = (int)n;
        } else if (!strcmp(a, "--frames")) {
            if (!cli_parse_long(v, 2, 64, &n)) return cli_usage_error("grass", "--frames '%s': not an integer in 2..64", v);
            frames = (int)n;
        } else if (!strcmp(a, "--seed")) {
            if (!cli_parse_long(v, 0, LONG_MAX, &n)) return cli_usage_error("grass", "--seed '%s': not an integer in 0..%ld", v, LONG_MAX);
            seed = (uint64_t)n;
        } else if (!strcmp(a, "--wd-map")) map_path = v;
        else if (!strcmp(a, "--mesh")) { mesh_kind = v; scene_name = "mesh"; }
        else if (!strcmp(a, "--mesh-cells")) {
            if (!cli_parse_long(v, 4, 512, &n)) return cli_usage_error("grass", "--mesh-cells '%s': not an integer in 4..512", v);
            cells = (int)n;
        } else if (!strcmp(a, "--wd-sun")) {
            if (!cli_parse_double(v, 0.0, 2.0, &d[0])) return cli_usage_error("grass", "--wd-sun '%s': not a number in [0, 2]", v);
            wd_sun = (float)d[0];
        } else if (!strcmp(a, "--lod-bias")) {
            if (!cli_parse_long(v, 0, 3, &n)) return cli_usage_error("grass", "--lod-bias '%s': not an integer in 0..3", v);
            lod_bias = (int)n;
        } else if (!strcmp(a, "--wd-map-gain")) {
            if (!cli_parse_double(v, 0.0, 2.0, &d[0])) return cli_usage_error("grass", "--wd-map-gain '%s': not a number in [0, 2]", v);
            map.gain = (float)d[0];
        } else { /* --wd */
            if (!cli_parse_doubles(v, ',', 1, 8, 0.0, 1.0, d, &nwd))
                return cli_usage_error("grass", "--wd '%s': not 1 to 8 numbers in [0, 1] separated by commas", v);
            for (k = 0; k < nwd; k++) wds[k] = (float)d[k];
            wd_given = 1;
        }
    }
    if (!out) return cli_usage_error("grass", "%s", "no output given: -o OUT.png");
    if (!cli_has_extension(out, ".png")) return cli_usage_error("grass", "output '%s': only PNG is written; the name must end in .png", out);
    if (map_path && strcmp(scene_name, "mountain") && strcmp(scene_name, "mesh"))
        return cli_usage_error("grass", "%s", "--wd-map is for the mountain and the mesh scenes");
    if (!strcmp(scene_name, "mountain")) {
        if (!w) { w = 800; h = 600; }
        if (map_path && !read_wd_map(map_path, &map)) return 1;
        ok = scene_mountain(w, h, res, tiles, frames, seed, wds, nwd, &map, lod_bias, out);
        free(map.v);
    } else if (!strcmp(scene_name, "mesh")) {
        if (!w) { w = 640; h = 480; }
        if (!wd_given) { wds[0] = 0.45f; nwd = 1; }
        if (map_path && !read_wd_map(map_path, &map)) return 1;
        ok = scene_mesh(w, h, res, frames, seed, wds, nwd, &map, mesh_kind, cells, wd_sun, out);
        free(map.v);
    } else if (!strcmp(scene_name, "wither")) {
        if (!w) { w = 320; h = 240; }
        ok = scene_wither(w, h, res, frames, seed, out);
    } else {
        if (!w) { w = 320; h = 240; }
        ok = scene_mingle(w, h, res, frames, seed, out);
    }
    return ok ? 0 : 1;
}
#endif /* GRASS_NO_MAIN */
