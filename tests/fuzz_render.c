/* fuzz_render.c - fuzz target for examples/render.h's drawing entry points (issue 21 point 4):
   the rasterizer (sr_draw_mesh, every shading mode, wireframe, model matrix, normal map, a fragment
   callback), the relief, terrain, volume, shell and mesh-shell ray marchers, sr_relief_intersect /
   sr_relief_light_visibility, text, contact sheets and the PNG encoder. The image readers have their
   own target (fuzz_png.c).
   libFuzzer: clang -g -O1 -Iexamples -fsanitize=fuzzer,address,undefined tests/fuzz_render.c -o fuzz_render -lm
   plain:     gcc -std=c99 -g -O1 -Iexamples tests/fuzz_render.c tests/fuzz_main.c -o fuzz_render -lm
              && ./fuzz_render tests/fuzz/corpus/render
   Byte 0 picks the entry point (bits 0-2) and how numbers are read (bit 7: raw 4-byte floats, any
   bits: NaN, infinities, 3e38, subnormals; else small values byte / 16 - 8); bytes 1-2 the
   framebuffer (1..16 x 1..16), byte 3 the allocation to fail (0 = none), byte 4 camera flags,
   then the camera, the scene and the options. Sizes are capped so that each input is cheap: at
   most 32 vertices and triangles, 6 x 6 maps and grids, 4 x 4 tiles, march steps no finer than
   1/256 of their box. Every call must return one of the documented codes; after an error (not
   SR_CANCELLED) the framebuffer's colour and depth are bit for bit what they were; no depth is
   ever NaN; with small (finite) numbers no colour is NaN either; the mesh shell takes at most its
   documented 16384 samples a ray; every allocation is freed (counted). A broken rule calls abort(), which the fuzzer reports. */
#define SR_IMPLEMENTATION
#include "render.h"
#include "failalloc.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct fz_in { const uint8_t *p; size_t n; int raw; } fz_in;

static unsigned fz_byte(fz_in *in)
{
    unsigned b;
    if (!in->n) return 0;
    b = *in->p++;
    in->n--;
    return b;
}

static float fz_float(fz_in *in)
{
    float f = 0.0f;
    if (in->raw && in->n >= 4) {
        memcpy(&f, in->p, 4);
        in->p += 4;
        in->n -= 4;
        return f;
    }
    return ((float)fz_byte(in) - 128.0f) / 16.0f;
}

static void fz_floats(fz_in *in, float *out, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) out[i] = fz_float(in);
}

/* a value in [0, 1] from one byte (maps, heights, colours) */
static float fz_unit(fz_in *in) { return (float)fz_byte(in) / 255.0f; }

static void fz_check(int ok) { if (!ok) abort(); }

/* tests/failalloc.h: the allocator that fails the fail_at-th call and counts the live blocks (the
   inputs' caps keep every allocation small: a 16 x 16 framebuffer, 32 triangles) */

typedef struct fz_prog { long calls, cancel_at; } fz_prog;

static int fz_progress(void *user, float done)
{
    fz_prog *g = (fz_prog *)user;
    fz_check(done >= 0.0f && done <= 1.0f);
    return ++g->calls == g->cancel_at;
}

static int fz_known(sr_result r)
{
    return r == SR_OK || r == SR_ERR_INVALID_ARGUMENT || r == SR_ERR_OUT_OF_MEMORY || r == SR_ERR_TOO_LARGE ||
           r == SR_CANCELLED || r == SR_ERR_NOT_FINITE;
}

/* ---- the scene's pieces --------------------------------------------------------------------- */

typedef struct fz_scene {
    float pos[3 * 32], nrm[3 * 32], col[3 * 32], uv[2 * 32], model[16], map[6 * 6 * 3], map2[6 * 6 * 3], grid[6 * 6];
    float gcol[3 * 6 * 6], sigma[16];
    uint32_t idx[3 * 32];
    sr_light lights[2];
    int light_count;
    float step;               /* the shell content's step (tile units), 0 = default */
} fz_scene;

static void fz_camera(fz_in *in, sr_camera *cam, unsigned flags)
{
    float eye[3], at[3], up[3], fov, aspect, zn, zf;
    fz_floats(in, eye, 3);
    fz_floats(in, at, 3);
    if (flags & 2) fz_floats(in, up, 3);
    if (in->raw) {
        fov = fz_float(in); aspect = fz_float(in); zn = fz_float(in); zf = fz_float(in);
    } else {
        fov = (float)fz_byte(in) * 0.7f;
        aspect = 0.25f + (float)fz_byte(in) / 64.0f;
        zn = 0.01f + (float)fz_byte(in) / 256.0f;
        zf = zn + 1.0f + (float)fz_byte(in) / 8.0f;
    }
    if (flags & 1) sr_camera_ortho(cam, eye, at, (flags & 2) ? up : NULL, in->raw ? fov : fov / 16.0f + 0.1f, aspect, zn, zf);
    else sr_camera_look_at(cam, eye, at, (flags & 2) ? up : NULL, fov, aspect, zn, zf);
}

static void fz_material(fz_in *in, sr_material *m)
{
    sr_material_default(m);
    if (fz_byte(in) & 1) {
        fz_floats(in, m->ambient, 3);
        fz_floats(in, m->diffuse, 3);
        fz_floats(in, m->specular, 3);
        fz_floats(in, m->emission, 3);
        m->shininess = fz_float(in);
    }
}

static void fz_lights(fz_in *in, fz_scene *s)
{
    int k;
    s->light_count = (int)(fz_byte(in) % 3);
    for (k = 0; k < s->light_count; k++) {
        sr_light *l = &s->lights[k];
        l->type = (fz_byte(in) & 1) ? SR_LIGHT_POINT : SR_LIGHT_DIRECTIONAL;
        fz_floats(in, l->vector, 3);
        fz_floats(in, l->ambient, 3);
        fz_floats(in, l->diffuse, 3);
        fz_floats(in, l->specular, 3);
    }
}

/* a draw's lights and material */
static void fz_lighting(fz_in *in, fz_scene *s, const sr_light **lights, int *count, sr_material *m)
{
    fz_lights(in, s);
    *lights = s->lights;
    *count = s->light_count;
    fz_material(in, m);
}

/* the shell marchers' stats are counts within the frame */
static sr_result fz_stats(sr_result r, const sr_shell_stats *st, const sr_framebuffer *fb)
{
    fz_check(st->covered >= 0 && st->covered <= (long)fb->width * fb->height && st->samples >= 0);
    return r;
}

/* an image of 1..6 x 1..6 texels with `channels` channels (values in [0, 1], or signed for normals) */
static void fz_image(fz_in *in, sr_image *img, float *data, int channels, int is_signed)
{
    unsigned b = fz_byte(in);
    int i, n;
    img->width = 1 + (int)(b % 6);
    img->height = 1 + (int)((b / 6) % 6);
    img->channels = channels;
    img->wrap = (int)((b >> 7) & 1);
    img->data = data;
    n = img->width * img->height * channels;
    for (i = 0; i < n; i++) data[i] = is_signed ? 2.0f * fz_unit(in) - 1.0f : fz_unit(in);
}

static void fz_fragment(void *user, const sr_fragment *f, float rgb[3])
{
    (void)user;
    rgb[0] = f->uv[0]; rgb[1] = f->bary[1]; rgb[2] = (float)f->front_facing;
}

/* ---- the content of the shell marchers: a sigma per tile from the input, a fixed step ------------- */

static void fz_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    const fz_scene *s = (const fz_scene *)user;
    int t = ((q->tile_x & 3) + 4 * (q->tile_y & 3)) & 15;
    fz_check(q->p[0] >= 0.0f && q->p[0] < 1.0f && q->p[1] >= 0.0f && q->p[1] < 1.0f);
    out->sigma = q->p[2] < 0.5f ? s->sigma[t] : 0.0f;
    out->rgb[0] = q->p[0]; out->rgb[1] = q->p[1]; out->rgb[2] = 0.5f;
    out->specular = 0.5f;
    out->tangent[2] = (t & 1) ? 1.0f : 0.0f;
    out->normal[2] = (t & 2) ? 1.0f : 0.0f;
    out->step = s->step;
}

static float fz_density(void *user, const float p[3])
{
    const fz_scene *s = (const fz_scene *)user;
    return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < 1.0f ? s->sigma[0] : s->sigma[1];
}

static void fz_shade(void *user, const float p[3], float rgb[3], float dir[3])
{
    (void)user;
    rgb[0] = 0.5f; rgb[1] = 0.6f; rgb[2] = 0.7f;
    dir[0] = p[1]; dir[1] = -p[0]; dir[2] = 1.0f;
}

/* ---- the entry points --------------------------------------------------------------------------- */

static size_t fz_mesh(fz_in *in, fz_scene *s, size_t *nt)
{
    size_t nv = fz_byte(in) % 33, t;
    *nt = fz_byte(in) % 33;
    fz_floats(in, s->pos, 3 * nv);
    for (t = 0; t < 3 * *nt; t++) s->idx[t] = fz_byte(in) % (uint32_t)(nv + 1); /* nv: out of range */
    return nv;
}

static sr_result fz_draw_mesh(fz_in *in, fz_scene *s, sr_framebuffer *fb, const sr_camera *cam)
{
    sr_draw_desc d;
    sr_image nmap;
    unsigned f;
    size_t nv, nt;
    sr_draw_desc_default(&d);
    nv = fz_mesh(in, s, &nt);
    f = fz_byte(in);
    d.positions = s->pos; d.vertex_count = nv; d.indices = s->idx; d.triangle_count = nt;
    if (f & 1) { fz_floats(in, s->nrm, 3 * nv); d.normals = s->nrm; }
    if (f & 2) { fz_floats(in, s->col, 3 * nv); d.colors = s->col; }
    if (f & 4) { fz_floats(in, s->uv, 2 * nv); d.uvs = s->uv; }
    if ((f & 12) == 12) { fz_image(in, &nmap, s->map, 3, 1); d.normal_map = &nmap; }
    if (f & 16) { fz_floats(in, s->model, 16); d.model = s->model; }
    if (f & 32) { d.fragment = fz_fragment; }
    f = fz_byte(in);
    d.shading = (sr_shading)(f % 5);
    d.cull = (sr_cull)((f / 5) % 3);
    d.no_depth_test = (int)((f >> 4) & 1);
    d.no_depth_write = (int)((f >> 5) & 1);
    d.wireframe = (int)((f >> 6) & 1);
    if (d.wireframe) { d.wire_width = fz_float(in); fz_floats(in, d.wire_color, 3); }
    fz_lighting(in, s, &d.lights, &d.light_count, &d.material);
    if (nv <= 32 && (f & 128)) { /* sr_compute_vertex_normals on the same mesh */
        sr_result r = sr_compute_vertex_normals(s->pos, nv, s->idx, nt, s->nrm);
        fz_check(r == SR_OK || r == SR_ERR_INVALID_ARGUMENT);
    }
    return sr_draw_mesh(fb, cam, &d);
}

static sr_result fz_draw_relief(fz_in *in, fz_scene *s, sr_framebuffer *fb, const sr_camera *cam)
{
    sr_relief_desc d;
    sr_image albedo, nmap;
    unsigned f;
    float o[3], dir[3], t, uvd[3], L[3];
    sr_relief_desc_default(&d);
    fz_image(in, &d.depth, s->grid, 1, 0);
    f = fz_byte(in);
    if (f & 1) { fz_image(in, &albedo, s->map, 3, 0); d.albedo = &albedo; }
    if (f & 2) { fz_image(in, &nmap, s->map2, 3, 1); d.normal_map = &nmap; }
    fz_floats(in, d.origin, 3);
    fz_floats(in, d.axis_u, 3);
    fz_floats(in, d.axis_v, 3);
    d.depth_scale = fz_float(in);
    d.linear_steps = (int)(fz_byte(in) % 33);
    d.binary_steps = (int)(fz_byte(in) % 17);
    d.shadows = (int)((f >> 2) & 1);
    d.shadow_search = (int)((f >> 3) & 1);
    if (f & 16) { d.shadow_bias = fz_float(in); d.shadow_light = fz_float(in); }
    if (f & 32) { d.curvature_u = fz_float(in); d.curvature_v = fz_float(in); }
    fz_lighting(in, s, &d.lights, &d.light_count, &d.material);
    fz_floats(in, o, 3);
    fz_floats(in, dir, 3);
    fz_floats(in, L, 3);
    sr__normalize(dir);
    if (sr_relief_intersect(&d, o, dir, &t, uvd)) {
        float v = sr_relief_light_visibility(&d, uvd, L);
        fz_check(v == 0.0f || v == 1.0f);
    }
    return sr_draw_relief(fb, cam, &d);
}

static sr_result fz_draw_terrain(fz_in *in, fz_scene *s, sr_framebuffer *fb, const sr_camera *cam)
{
    sr_terrain_desc d;
    unsigned f = fz_byte(in);
    int i;
    sr_terrain_desc_default(&d);
    d.width = (int)(f % 7);
    d.height = (int)((f / 7) % 7);
    for (i = 0; i < d.width * d.height; i++) s->grid[i] = fz_unit(in) * 4.0f;
    d.heights = s->grid;
    d.origin_x = fz_float(in); d.origin_z = fz_float(in); d.base_y = fz_float(in);
    d.spacing = fz_float(in); d.height_scale = fz_float(in);
    if (f & 128) d.step = fz_float(in);
    if (fz_byte(in) & 1) {
        for (i = 0; i < 3 * d.width * d.height; i++) s->gcol[i] = fz_unit(in);
        d.colors = s->gcol;
    }
    fz_lighting(in, s, &d.lights, &d.light_count, &d.material);
    return sr_draw_terrain(fb, cam, &d);
}

static sr_result fz_draw_volume(fz_in *in, fz_scene *s, sr_framebuffer *fb, const sr_camera *cam)
{
    sr_volume_desc d;
    unsigned f;
    float diag;
    int k;
    sr_volume_desc_default(&d);
    fz_floats(in, d.box_min, 3);
    fz_floats(in, d.box_max, 3);
    s->sigma[0] = fz_unit(in) * 8.0f;
    s->sigma[1] = fz_unit(in);
    d.density = fz_density;
    d.user = s;
    f = fz_byte(in);
    if (f & 1) d.shade = fz_shade;
    d.direction = (sr_volume_direction)((f >> 1) % 3);
    d.shadows = (int)((f >> 3) & 1);
    /* steps no finer than 1/256 of the box (finer ones are correct, only slow) */
    for (diag = 0.0f, k = 0; k < 3; k++) diag += fabsf(d.box_max[k] - d.box_min[k]);
    if (f & 16) d.step = diag * (float)(1 + fz_byte(in)) / 256.0f;
    if (f & 32) d.shadow_step = diag * (float)(1 + fz_byte(in)) / 256.0f;
    if (f & 64) { d.depth_threshold = fz_unit(in); d.termination = fz_unit(in); }
    fz_lighting(in, s, &d.lights, &d.light_count, &d.material);
    return sr_draw_volume(fb, cam, &d);
}

static void fz_shell_content(fz_in *in, fz_scene *s)
{
    int k;
    for (k = 0; k < 16; k++) s->sigma[k] = (float)(fz_byte(in) % 4) * 4.0f;
    k = (int)(fz_byte(in) % 8);
    s->step = k ? (float)k / 64.0f : 0.0f;
}

static sr_result fz_draw_shell(fz_in *in, fz_scene *s, sr_framebuffer *fb, const sr_camera *cam, fz_prog *g)
{
    sr_shell_desc d;
    sr_shell_stats st;
    unsigned f = fz_byte(in);
    int i;
    sr_shell_desc_default(&d);
    if (f & 1) {
        d.nx = (int)(fz_byte(in) % 6); d.ny = (int)(fz_byte(in) % 6);
        for (i = 0; i < d.nx * d.ny; i++) s->grid[i] = fz_unit(in);
        d.heights = s->grid;
        d.spacing = fz_float(in);
    }
    fz_floats(in, d.origin, 2);
    d.tile = fz_float(in);
    d.tiles_x = (int)(fz_byte(in) % 5); d.tiles_y = (int)(fz_byte(in) % 5);
    d.thickness = d.tile * (float)(fz_byte(in) % 4); /* at most 3 tiles thick: cheap */
    fz_shell_content(in, s);
    d.sample = fz_sample; d.user = s;
    fz_floats(in, d.ground_rgb, 3);
    if (f & 2) { d.termination = fz_unit(in); d.depth_threshold = fz_unit(in); }
    if (f & 4) { d.progress = fz_progress; d.progress_user = g; }
    fz_lighting(in, s, &d.lights, &d.light_count, &d.material);
    return fz_stats(sr_draw_shell(fb, cam, &d, &st), &st, fb);
}

static sr_result fz_draw_mesh_shell(fz_in *in, fz_scene *s, sr_framebuffer *fb, const sr_camera *cam, fz_prog *g,
                                    const sr_allocator *a)
{
    sr_mesh_shell_desc d;
    sr_shell_stats st;
    sr_result r;
    unsigned f;
    size_t nv, nt;
    sr_mesh_shell_desc_default(&d);
    nv = fz_mesh(in, s, &nt);
    fz_floats(in, s->nrm, 3 * nv);
    fz_floats(in, s->uv, 2 * nv);
    d.positions = s->pos; d.normals = s->nrm; d.uvs = s->uv; d.vertex_count = nv; d.indices = s->idx; d.triangle_count = nt;
    d.height = fz_float(in);
    d.depth = fz_float(in);
    f = fz_byte(in);
    d.see_through = (int)(f & 1);
    fz_shell_content(in, s);
    d.sample = fz_sample; d.user = s;
    if (f & 2) { d.termination = fz_unit(in); d.depth_threshold = fz_unit(in); }
    if (f & 4) { d.progress = fz_progress; d.progress_user = g; }
    d.allocator = a;
    fz_lighting(in, s, &d.lights, &d.light_count, &d.material);
    r = fz_stats(sr_draw_mesh_shell(fb, cam, &d, &st), &st, fb);
    fz_check(st.samples <= 16384L * fb->width * fb->height); /* the documented samples a ray */
    return r;
}

/* text, a contact sheet and the PNG encoder on the framebuffer's pixels */
static void fz_images(fz_in *in, const sr_framebuffer *fb, const sr_allocator *a)
{
    uint8_t px[16 * 16 * 4], rgb[3] = {10, 200, 30}, *png = NULL;
    char text[33], cap[2][9];
    const char *caps[2];
    sr_image8 ims[2], sheet;
    size_t n, png_n = 0;
    int k, ch = (fz_byte(in) & 1) ? 4 : 3, count;
    sr_result r;
    sr_framebuffer_to_rgb8(fb, px, ch);
    n = fz_byte(in) % 33;
    for (k = 0; k < (int)n; k++) text[k] = (char)(fz_byte(in) | 1); /* no NUL inside */
    text[n] = 0;
    ims[0].width = fb->width; ims[0].height = fb->height; ims[0].channels = ch; ims[0].pixels = px;
    sr_draw_text(&ims[0], (int)(fz_byte(in) % 24) - 4, (int)(fz_byte(in) % 24) - 4, text, 1 + (int)(fz_byte(in) % 3), rgb);
    ims[1] = ims[0];
    for (k = 0; k < 2; k++) {
        size_t m = fz_byte(in) % 9, i;
        for (i = 0; i < m; i++) cap[k][i] = (char)(fz_byte(in) | 1);
        cap[k][m] = 0;
        caps[k] = (fz_byte(in) & 1) ? cap[k] : NULL;
    }
    count = 1 + (int)(fz_byte(in) % 2);
    r = sr_contact_sheet(ims, caps, count, (int)(fz_byte(in) % 3), a, &sheet);
    fz_check(r == SR_OK || r == SR_ERR_OUT_OF_MEMORY);
    if (r == SR_OK) {
        fz_check(sheet.width >= fb->width && sheet.height >= fb->height && sheet.channels == 3);
        sr_free(a, sheet.pixels);
    }
    r = sr_encode_png(px, fb->width, fb->height, ch, (int)(fz_byte(in) & 1), a, &png, &png_n);
    fz_check(r == SR_OK || r == SR_ERR_OUT_OF_MEMORY);
    if (r == SR_OK) {
        fz_check(png_n > 8 && png[0] == 0x89 && png[1] == 'P');
        sr_free(a, png);
    } else {
        fz_check(png == NULL || png_n == 0);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fail_alloc fa;
    fz_prog g;
    sr_allocator a;
    sr_framebuffer fb;
    sr_camera cam;
    static fz_scene s; /* large; zeroed per input */
    static float before[5 * 16 * 16]; /* the colour and depth before a draw */
    unsigned head, flags;
    int W, H, entry, draws, k;
    size_t i, n;
    sr_result r;
    in.p = data; in.n = size; in.raw = 0;
    head = fz_byte(&in);
    in.raw = (int)(head >> 7);
    entry = (int)(head & 7);
    W = 1 + (int)(fz_byte(&in) % 16);
    H = 1 + (int)(fz_byte(&in) % 16);
    memset(&fa, 0, sizeof fa);
    fa.fail_at = (long)fz_byte(&in);
    memset(&g, 0, sizeof g);
    g.cancel_at = (long)(fz_byte(&in) % 8);
    a.alloc = fa_alloc; a.free = fa_free; a.user = &fa;
    memset(&s, 0, sizeof s);
    r = sr_framebuffer_create(&fb, W, H, &a);
    fz_check(r == SR_OK || r == SR_ERR_OUT_OF_MEMORY);
    if (r != SR_OK) { fz_check(fa.live == 0); return 0; }
    flags = fz_byte(&in);
    fz_camera(&in, &cam, flags);
    draws = 1 + (int)((flags >> 4) & 1); /* a second draw over the first: depth tests against it */
    for (k = 0; k < draws; k++) {
        n = (size_t)W * (size_t)H;
        memcpy(before, fb.color, 4 * n * sizeof(float));
        memcpy(before + 4 * n, fb.depth, n * sizeof(float));
        switch (entry) {
        case 0: case 7: r = fz_draw_mesh(&in, &s, &fb, &cam); break;
        case 1: r = fz_draw_relief(&in, &s, &fb, &cam); break;
        case 2: r = fz_draw_terrain(&in, &s, &fb, &cam); break;
        case 3: r = fz_draw_volume(&in, &s, &fb, &cam); break;
        case 4: r = fz_draw_shell(&in, &s, &fb, &cam, &g); break;
        case 5: r = fz_draw_mesh_shell(&in, &s, &fb, &cam, &g, &a); break;
        default: r = fz_draw_mesh(&in, &s, &fb, &cam); fz_images(&in, &fb, &a); break;
        }
        fz_check(fz_known(r));
        if (r != SR_OK && r != SR_CANCELLED) /* errors draw nothing */
            fz_check(memcmp(before, fb.color, 4 * n * sizeof(float)) == 0 && memcmp(before + 4 * n, fb.depth, n * sizeof(float)) == 0);
        for (i = 0; i < n; i++) {
            fz_check(fb.depth[i] == fb.depth[i]);                    /* no NaN depth */
            if (!in.raw) fz_check(fb.color[4 * i] == fb.color[4 * i] && fb.color[4 * i + 1] == fb.color[4 * i + 1] &&
                                  fb.color[4 * i + 2] == fb.color[4 * i + 2]); /* finite numbers: no NaN colour */
        }
    }
    sr_framebuffer_free(&fb);
    fz_check(fa.live == 0);
    return 0;
}
