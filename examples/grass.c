/* grass - paper 002's withering grass (time-varying texels, texel.h) over a subdiv4.h terrain,
   rendered with texel.h's sampler and shader and written with render.h's PNG writer.

   usage: grass [--scene mountain|wither|mingle] -o OUT.png [--size WxH] [--res R] [--tiles N]
                [--wd A,B,C] [--frames F] [--seed S] [--quiet]
     --scene   mountain (default): the paper's Fig 13, N x N tiles (80: 6400 tiles of 400 blades,
                 2.56M blades) on a four-point terrain, one panel per wd (default 0,0.30,0.917);
               wither: one 400-blade patch seen close, at wd 0 .. 1 in six panels;
               mingle: the paper's Fig 11: two mingling functions (rows t1, t2) at three wd,
                 and 700 against 300 blades (row b).
     --size    panel size in pixels (default 800x600 for mountain, 320x240 for the others)
     --res     texel resolution, a power of two (default 64)
     --tiles   tiles per side of the mountain (default 80)
     --frames  key frames per TVT (default 6)
   Each panel prints "RESULT grass scene=... wd=... coverage=... render_ms=...". Progress goes to
   stderr. Exit status 0 on success, 2 on bad arguments, 1 on failure.

   The terrain driver here is what a renderer does with texel.h: a world point (x, y, z), z up,
   maps to tile (floor(x / S), floor(y / S)) and texel point (frac(x / S) res, frac(y / S) res,
   (z - h(x, y)) / S res), a vertical shear that keeps blades upright on slopes; rays march the
   shell between the ground and S above it with half-voxel steps of the level that the pixel's
   footprint picks, skip what lies above the shell and what the coarsest level calls empty, and
   stop on the ground (soil colour) or when opaque. Each tile has its own wd (drier on slopes
   facing the sun, plus a per-tile jitter) and one of four mingled TVT variants. */
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

#define VARIANTS 4
#define SAMPLES 7

typedef struct scene {
    int tiles;                 /* tiles per side */
    float tile;                /* world size of a tile (and of the shell height) */
    int hn;                    /* height samples per side */
    float *h;                  /* hn * hn heights over [0, tiles * tile]^2, NULL = flat */
    float hmax, slope_max;
    const tvt_tvt *variant[VARIANTS];
    const tvt_shadow *shadow[VARIANTS];
    int variant_count;
    float wd, wd_sun, wd_jitter; /* per tile: wd + wd_sun * sun-facing slope + jitter */
    float sun[3];
    float eye[3], target[3], fovy;
    int res;
} scene;

static int quiet = 0;


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
static float height_at(const scene *s, float x, float y, float *gx, float *gy)
{
    float scale, fx, fy, h00, h10, h01, h11;
    int i, j, n = s->hn;
    if (!s->h) { *gx = *gy = 0.0f; return 0.0f; }
    scale = (float)(n - 1) / ((float)s->tiles * s->tile); /* height samples per world unit */
    fx = x * scale;
    fy = y * scale;
    if (fx < 0) fx = 0;
    if (fy < 0) fy = 0;
    if (fx > (float)(n - 1) - 1e-3f) fx = (float)(n - 1) - 1e-3f;
    if (fy > (float)(n - 1) - 1e-3f) fy = (float)(n - 1) - 1e-3f;
    i = (int)fx; j = (int)fy; fx -= (float)i; fy -= (float)j;
    h00 = s->h[j * n + i]; h10 = s->h[j * n + i + 1]; h01 = s->h[(j + 1) * n + i]; h11 = s->h[(j + 1) * n + i + 1];
    *gx = ((h10 - h00) * (1 - fy) + (h11 - h01) * fy) * scale;
    *gy = ((h01 - h00) * (1 - fx) + (h11 - h10) * fx) * scale;
    return (h00 * (1 - fx) + h10 * fx) * (1 - fy) + (h01 * (1 - fx) + h11 * fx) * fy;
}

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
    s->slope_max = 0.0f;
    for (i = 0; i + 1 < nx * ny; i++) {
        float d = fabsf(s->h[i + 1] - s->h[i]) * (float)(nx - 1) / span;
        if (d > s->slope_max) s->slope_max = d;
    }
    s->slope_max *= 1.5f;
    return 1;
}

/* ---- the march over the terrain ------------------------------------------------------------ */
static uint32_t tile_hash(int i, int j)
{
    uint32_t h = (uint32_t)i * 73856093u ^ (uint32_t)j * 19349663u;
    h ^= h >> 13; h *= 0x5bd1e995u; h ^= h >> 15;
    return h;
}

static float tile_wd(const scene *s, int i, int j)
{
    float gx, gy, n[3], l, facing, wd;
    height_at(s, ((float)i + 0.5f) * s->tile, ((float)j + 0.5f) * s->tile, &gx, &gy);
    n[0] = -gx; n[1] = -gy; n[2] = 1.0f;
    l = sqrtf(n[0] * n[0] + n[1] * n[1] + 1.0f);
    facing = (n[0] * s->sun[0] + n[1] * s->sun[1] + n[2] * s->sun[2]) / l - s->sun[2]; /* 0 on flat ground */
    wd = s->wd + s->wd_sun * facing + s->wd_jitter * ((float)(tile_hash(i, j) & 1023) / 1023.0f - 0.5f);
    return wd < 0 ? 0 : wd > 1 ? 1 : wd;
}

typedef struct pixel_out { float rgb[3]; int grass; } pixel_out;

static void sky(const float *d, float *rgb)
{
    float t = d[2] > 0 ? d[2] : 0;
    rgb[0] = 0.55f + 0.25f * (1 - t); rgb[1] = 0.7f + 0.15f * (1 - t); rgb[2] = 0.95f;
}

/* The segment of the ray inside the box of the shell, or 0. */
static int clip_box(const scene *s, const float *o, const float *d, float *t0, float *t1)
{
    float lo[3], hi[3];
    int c;
    lo[0] = lo[1] = 0.0f; lo[2] = -1e-3f;
    hi[0] = hi[1] = (float)s->tiles * s->tile; hi[2] = s->hmax + s->tile;
    *t0 = 0.0f; *t1 = 1e30f;
    for (c = 0; c < 3; c++) {
        float a, b;
        if (fabsf(d[c]) < 1e-12f) { if (o[c] < lo[c] || o[c] > hi[c]) return 0; continue; }
        a = (lo[c] - o[c]) / d[c]; b = (hi[c] - o[c]) / d[c];
        if (a > b) { float x = a; a = b; b = x; }
        if (a > *t0) *t0 = a;
        if (b < *t1) *t1 = b;
    }
    return *t0 < *t1;
}

static void soil(const scene *s, float gx, float gy, float *rgb)
{
    float n[3] = {-gx, -gy, 1.0f}, l = sqrtf(gx * gx + gy * gy + 1.0f), lam;
    lam = (n[0] * s->sun[0] + n[1] * s->sun[1] + n[2] * s->sun[2]) / l;
    lam = lam > 0 ? lam : 0;
    rgb[0] = 0.30f * (0.3f + lam); rgb[1] = 0.22f * (0.3f + lam); rgb[2] = 0.14f * (0.3f + lam);
}

static void trace(const scene *s, const float *o, const float *d, float pixel_angle, pixel_out *out)
{
    float t0, t1, T = 1.0f, rgb[3] = {0, 0, 0}, vox = s->tile / (float)s->res, t;
    tvt_shade_desc sd = tvt_shade_default_desc();
    memcpy(sd.light_dir, s->sun, sizeof(sd.light_dir));
    out->grass = 0;
    if (!clip_box(s, o, d, &t0, &t1)) { sky(d, out->rgb); return; }
    t = t0;
    int ci = -1, cj = -1, v = 0, empty = 1;
    float wd = 0.0f;
    while (t < t1 && T > 0.01f) {
        float p[3], gx, gy, h, zrel, q[3], dt[3], dl, fx, fy, step_w, c[3], alpha;
        int i, j, level, coarse;
        const tvt_tvt *tv;
        p[0] = o[0] + t * d[0]; p[1] = o[1] + t * d[1]; p[2] = o[2] + t * d[2];
        h = height_at(s, p[0], p[1], &gx, &gy);
        zrel = p[2] - h;
        if (zrel < 0) { /* the ground */
            soil(s, gx, gy, c);
            rgb[0] += T * c[0]; rgb[1] += T * c[1]; rgb[2] += T * c[2];
            T = 0;
            break;
        }
        if (zrel >= s->tile) { /* above the shell: the nearest the shell can be */
            float gap = (zrel - s->tile) / (fabsf(d[2]) + s->slope_max * sqrtf(d[0] * d[0] + d[1] * d[1]) + 1e-6f);
            t += gap > 0.5f * vox ? gap : 0.5f * vox;
            continue;
        }
        level = tvt_lod_level_for(&s->variant[0]->frames[0], t * pixel_angle / vox);
        step_w = vox * (float)(1 << level); /* one voxel of the level: the trilinear field has no finer detail */
        fx = p[0] / s->tile; fy = p[1] / s->tile;
        i = (int)floorf(fx); j = (int)floorf(fy);
        if (i >= s->tiles) i = s->tiles - 1;
        if (j >= s->tiles) j = s->tiles - 1;
        if (i != ci || j != cj) { /* a new tile: its variant and wd */
            ci = i; cj = j;
            v = (int)(tile_hash(j, i) % (uint32_t)s->variant_count);
            wd = tile_wd(s, i, j);
        }
        tv = s->variant[v];
        q[0] = (fx - (float)i) * (float)s->res; q[1] = (fy - (float)j) * (float)s->res; q[2] = zrel / vox;
        /* the ray's direction in texel space (the shear), and its step there */
        dt[0] = d[0] / vox; dt[1] = d[1] / vox; dt[2] = (d[2] - gx * d[0] - gy * d[1]) / vox;
        dl = sqrtf(dt[0] * dt[0] + dt[1] * dt[1] + dt[2] * dt[2]);
        dt[0] /= dl; dt[1] /= dl; dt[2] /= dl;
        coarse = tv->frames[0].levels - 1;
        if (coarse > level && empty && tvt_tvt_density(tv, wd, coarse, q) <= 0.0f) { /* only after an empty step */
            t += 0.5f * vox * (float)(1 << coarse) / (dl * vox);
            continue;
        }
        sd.shadow = s->shadow[v];
        alpha = tvt_shade_point(tv, wd, level, &sd, q, dt, step_w * dl, c);
        empty = alpha <= 0.0f;
        rgb[0] += T * alpha * c[0]; rgb[1] += T * alpha * c[1]; rgb[2] += T * alpha * c[2];
        T *= 1.0f - alpha;
        t += step_w;
    }
    out->grass = T < 0.5f && rgb[1] > 0; /* mostly grass (not soil only) */
    if (T > 0) {
        float c[3];
        sky(d, c);
        rgb[0] += T * c[0]; rgb[1] += T * c[1]; rgb[2] += T * c[2];
    }
    memcpy(out->rgb, rgb, sizeof(rgb));
}

static uint8_t to_srgb8(float x)
{
    float y = x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
    y = y < 0 ? 0 : y > 1 ? 1 : y;
    return (uint8_t)(y * 255.0f + 0.5f);
}

/* Renders a panel; returns the share of pixels whose opacity came mostly from grass. */
static double render(const scene *s, int w, int hgt, sr_image8 *img, const char *what)
{
    sr_camera cam;
    float up[3] = {0, 0, 1}, pixel_angle;
    long grass = 0;
    int x, y;
    sr_camera_look_at(&cam, s->eye, s->target, up, s->fovy, (float)w / (float)hgt, 0.1f, 1e4f);
    pixel_angle = 2.0f * cam.tan_half_fovy / (float)hgt;
    img->width = w; img->height = hgt; img->channels = 3;
    img->pixels = (uint8_t *)malloc((size_t)w * hgt * 3);
    if (!img->pixels) return -1;
    for (y = 0; y < hgt; y++) {
        for (x = 0; x < w; x++) {
            float o[3], d[3];
            pixel_out px;
            sr_camera_ray(&cam, w, hgt, (float)x + 0.5f, (float)y + 0.5f, o, d);
            trace(s, o, d, pixel_angle, &px);
            grass += px.grass;
            img->pixels[3 * ((size_t)y * w + x) + 0] = to_srgb8(px.rgb[0]);
            img->pixels[3 * ((size_t)y * w + x) + 1] = to_srgb8(px.rgb[1]);
            img->pixels[3 * ((size_t)y * w + x) + 2] = to_srgb8(px.rgb[2]);
        }
        if ((y & 15) == 15) progress_print((void *)what, (float)(y + 1) / (float)hgt);
    }
    progress_end(what);
    return (double)grass / ((double)w * hgt);
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

#ifndef GRASS_NO_MAIN /* bench/bench_texel.c includes this file for the mountain */
static double now_ms(void) { return 1e3 * (double)clock() / CLOCKS_PER_SEC; }

static int write_sheet(const sr_image8 *panels, const char *const *captions, int count, int columns, const char *path)
{
    sr_image8 sheet;
    sr_result r = sr_contact_sheet(panels, captions, count, columns, NULL, &sheet);
    if (r == SR_OK) r = sr_write_png(path, sheet.pixels, sheet.width, sheet.height, 3, 0);
    if (sheet.pixels) sr_free(NULL, sheet.pixels);
    if (r != SR_OK) { fprintf(stderr, "grass: writing %s: %s\n", path, sr_result_string(r)); return 0; }
    if (!quiet) fprintf(stderr, "grass: wrote %s\n", path);
    return 1;
}

static int scene_mountain(int w, int h, int res, int tiles, int frames, uint64_t seed, const float *wds, int nwd,
                          const char *path)
{
    grass_set g;
    scene s;
    sr_image8 panels[8];
    char caption[8][64];
    const char *caps[8];
    int k, ok, done = 0;
    ok = mountain_setup(&s, &g, res, tiles, frames, seed);
    for (k = 0; ok && k < nwd; k++) {
        double t0 = now_ms(), cov;
        char what[64];
        s.wd = wds[k];
        snprintf(what, sizeof(what), "grass: mountain wd %.3f", wds[k]);
        ok = build_shadows(&g, s.sun);
        cov = ok ? render(&s, w, h, &panels[k], what) : -1;
        if (cov < 0) { ok = 0; break; }
        done = k + 1;
        printf("RESULT grass scene=mountain wd=%.3f width=%d height=%d tiles=%d blades=%d coverage=%.3f render_ms=%.0f\n",
               wds[k], w, h, tiles * tiles, tiles * tiles * 400, cov, now_ms() - t0);
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
    s->tiles = 3; s->tile = 1.0f; s->res = res; s->h = NULL; s->hmax = 0; s->slope_max = 0;
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

static void usage(FILE *to)
{
    fprintf(to, "usage: grass [--scene mountain|wither|mingle] -o OUT.png [--size WxH] [--res R] [--tiles N]\n"
                "             [--wd A,B,C] [--frames F] [--seed S] [--quiet]\n");
    if (to != stdout) return;
    fprintf(to, "  --scene   mountain: the paper's Fig 13 (N x N tiles of 400 blades), one panel per wd;\n"
                "            wither: one patch at wd 0..1; mingle: the paper's Fig 11 (default mountain)\n"
                "  -o        the PNG to write (a contact sheet of the panels)\n"
                "  --size    panel size (800x600 for mountain, 320x240 otherwise)\n"
                "  --res     texel resolution, a power of two in 16..256 (64)\n"
                "  --tiles   mountain tiles per side (80: 6400 tiles, 2.56M blades)\n"
                "  --wd      mountain's weathering degrees, in [0, 1] (0,0.30,0.917)\n"
                "  --frames  key frames per TVT, 2..64 (6)\n"
                "  --seed    terrain and blades (2010)\n"
                "  --quiet   no progress on stderr\n");
}

int main(int argc, char **argv)
{
    const char *scene_name = "mountain", *out = NULL;
    int w = 0, h = 0, res = 64, tiles = 80, frames = 6, nwd = 3, i, ok;
    float wds[8] = {0.0f, 0.30f, 0.917f};
    uint64_t seed = 2010;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
        if (!strcmp(a, "--quiet")) { quiet = 1; continue; }
        if (!v) { fprintf(stderr, "grass: %s needs a value\n", a); usage(stderr); return 2; }
        if (!strcmp(a, "-o")) out = v;
        else if (!strcmp(a, "--scene")) scene_name = v;
        else if (!strcmp(a, "--size")) { if (sscanf(v, "%dx%d", &w, &h) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192) { fprintf(stderr, "grass: bad --size %s\n", v); return 2; } }
        else if (!strcmp(a, "--res")) { res = atoi(v); if (res < 16 || res > 256 || (res & (res - 1))) { fprintf(stderr, "grass: --res must be a power of two in 16..256\n"); return 2; } }
        else if (!strcmp(a, "--tiles")) { tiles = atoi(v); if (tiles < 1 || tiles > 1000) { fprintf(stderr, "grass: bad --tiles %s\n", v); return 2; } }
        else if (!strcmp(a, "--frames")) { frames = atoi(v); if (frames < 2 || frames > 64) { fprintf(stderr, "grass: --frames must be 2..64\n"); return 2; } }
        else if (!strcmp(a, "--seed")) seed = (uint64_t)strtoull(v, NULL, 10);
        else if (!strcmp(a, "--wd")) {
            char *end;
            const char *p = v;
            nwd = 0;
            while (*p && nwd < 8) {
                wds[nwd] = strtof(p, &end);
                if (end == p || !(wds[nwd] >= 0.0f && wds[nwd] <= 1.0f)) { fprintf(stderr, "grass: --wd values must be in [0, 1]\n"); return 2; }
                nwd++;
                p = *end == ',' ? end + 1 : end;
                if (*end && *end != ',') { fprintf(stderr, "grass: bad --wd %s\n", v); return 2; }
            }
        } else { fprintf(stderr, "grass: unknown option %s\n", a); usage(stderr); return 2; }
        i++;
    }
    if (!out) { fprintf(stderr, "grass: -o OUT.png is required\n"); usage(stderr); return 2; }
    if (!strcmp(scene_name, "mountain")) {
        if (!w) { w = 800; h = 600; }
        ok = scene_mountain(w, h, res, tiles, frames, seed, wds, nwd, out);
    } else if (!strcmp(scene_name, "wither")) {
        if (!w) { w = 320; h = 240; }
        ok = scene_wither(w, h, res, frames, seed, out);
    } else if (!strcmp(scene_name, "mingle")) {
        if (!w) { w = 320; h = 240; }
        ok = scene_mingle(w, h, res, frames, seed, out);
    } else {
        fprintf(stderr, "grass: unknown scene %s (mountain, wither, mingle)\n", scene_name);
        return 2;
    }
    return ok ? 0 : 1;
}
#endif /* GRASS_NO_MAIN */
