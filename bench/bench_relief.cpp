/* bench_relief - paper 003's three stages (its Table 6-1), one thread: the feature-guided synthesis
   of examples/relief.h, its normal map, and one relief-mapped frame of the rock cube, the frame
   also drawn by Mesa's llvmpipe through OSMesa with a GLSL shader doing the same search.

   usage: bench_relief [EXAMPLE] [-o PREFIX]
     EXAMPLE  a height map (default /usr/share/glmark2/textures/asteroid-height-map.png, of which the
              384 x 384 square at (112, 578), inside its lower disk, is used; other files whole)
     -o       also write PREFIX_ours.png and PREFIX_llvmpipe.png

   synth_ms   rl_synthesize (default options: patch 48, K 2, stride 8) of a 512 x 512 output from the
              example, sketch = the letter R of render.h's font, black strokes (engraved), centred.
   normal_ms  rl_normal_map of that output (d = 4, clamp).
   render_ms  one 800 x 600 frame: sr_framebuffer_clear + sr_draw_relief of the cube's 6 faces
              (front: the fused map, the others: the example), 10 linear + 5 binary steps,
              Policarpo shadow rays (the same search, bias 0.02) toward one directional light.
   llvmpipe_ms the same frame by llvmpipe (LP_NUM_THREADS=0: one thread), OpenGL 3.3 core: the 6
              faces as 12 triangles, a fragment shader that intersects the view ray with the same
              map by the same linear + binary search (depth, normal and albedo as float textures,
              GL_LINEAR, clamp to edge: the same bilinear lookups), writes gl_FragDepth of the hit,
              and shades with render.h's formula and the same shadow search. Shaders compiled and
              textures uploaded before timing; timed: glClear + glDrawArrays + glFinish.
   Timing (bench/bench.h): render and llvmpipe interleaved frame by frame, one warm-up each and 11
   rounds; synthesis and normal map (no peer) one warm-up and 11 runs; medians with min/max. diff_pixels: the share of the frame's
   pixels whose 8-bit colours differ by more than 4/255 in any channel, as bench_raster counts.
   Output: RESULT relief res=512 synth_ms=<t> synth_ms_min=.. synth_ms_max=.. normal_ms=.. ..
               render_ms=.. .. llvmpipe_ms=.. .. ratio=<ours/llvmpipe> ratio_min=.. ratio_max=.. diff_pixels=<share>
   Exit status 0; 1 bad arguments or unreadable example; 2 setup failure. */
#include "bench.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#define GL_GLEXT_PROTOTYPES 0
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include "osmesa_gl.h"

#define RL_IMPLEMENTATION
#include "relief.h"
#define SR_IMPLEMENTATION
#include "render.h"

#define FW 800
#define FH 600
#define RES 512

/* ---- the scene ------------------------------------------------------------------------------- */

struct face_maps {
    int w, h;
    float *depth, *normal, *albedo;
};

struct scene {
    rl_map example, sketch, fused;
    face_maps front, side;
    sr_camera cam;
    sr_light light;
    sr_material mat;
    float depth_scale;
};

static const float faces[6][9] = { /* origin, axis_u, axis_v: n = u x v outwards, v runs up */
    {-1, -1, 1, 2, 0, 0, 0, 2, 0},  {1, -1, -1, -2, 0, 0, 0, 2, 0}, {1, -1, 1, 0, 0, -2, 0, 2, 0},
    {-1, -1, -1, 0, 0, 2, 0, 2, 0}, {-1, 1, 1, 2, 0, 0, 0, 0, -2},  {-1, -1, -1, 2, 0, 0, 0, 0, 2}};

/* depth = 1 - height in [0, 1] (rows reversed: the faces' v runs up), normals, rock albedo */
static int make_face(const rl_map *m, float depth_scale, face_maps *f)
{
    size_t n = (size_t)m->width * (size_t)m->height, i;
    float lo = m->data[0], hi = m->data[0], *h = (float *)malloc(sizeof(float) * n);
    rl_normal_options no = rl_normal_default_options();
    f->w = m->width; f->h = m->height;
    f->depth = (float *)malloc(sizeof(float) * n);
    f->normal = (float *)malloc(sizeof(float) * 3 * n);
    f->albedo = (float *)malloc(sizeof(float) * 3 * n);
    if (!h || !f->depth || !f->normal || !f->albedo) return 0;
    for (i = 0; i < n; i++) { lo = m->data[i] < lo ? m->data[i] : lo; hi = m->data[i] > hi ? m->data[i] : hi; }
    for (i = 0; i < n; i++) {
        size_t x = i % (size_t)m->width, y = i / (size_t)m->width;
        float v = (m->data[((size_t)m->height - 1 - y) * (size_t)m->width + x] - lo) / (hi > lo ? hi - lo : 1.0f);
        h[i] = v;
        f->depth[i] = 1.0f - v;
        f->albedo[3 * i] = 0.42f + 0.30f * v; f->albedo[3 * i + 1] = 0.38f + 0.26f * v; f->albedo[3 * i + 2] = 0.33f + 0.22f * v;
    }
    no.strength = depth_scale * (float)m->width / 2.0f;
    int ok = rl_normal_map(h, m->width, m->height, &no, f->normal) == RL_OK;
    free(h);
    return ok;
}

static void setup_view(scene *s)
{
    float eye[3] = {2.3f, 1.9f, 4.2f}, at[3] = {0, 0, 0}, toward[3] = {0.6f, 0.7f, 0.5f};
    float l = std::sqrt(0.36f + 0.49f + 0.25f);
    for (int k = 0; k < 3; k++) toward[k] /= l;
    sr_camera_look_at(&s->cam, eye, at, NULL, 36.0f, (float)FW / (float)FH, 0.1f, 20.0f);
    sr_light_default(&s->light, toward);
    sr_material_default(&s->mat);
    s->mat.specular[0] = s->mat.specular[1] = s->mat.specular[2] = 0.25f;
    s->mat.shininess = 25.0f;
    s->depth_scale = 0.12f;
}

static void relief_desc(const scene *s, int k, sr_image *dimg, sr_image *nimg, sr_image *aimg, sr_relief_desc *d)
{
    const face_maps *m = k == 0 ? &s->front : &s->side;
    sr_relief_desc_default(d);
    memcpy(d->origin, faces[k], 12); memcpy(d->axis_u, faces[k] + 3, 12); memcpy(d->axis_v, faces[k] + 6, 12);
    d->depth_scale = s->depth_scale;
    dimg->width = m->w; dimg->height = m->h; dimg->channels = 1; dimg->data = m->depth; dimg->wrap = 0;
    *nimg = *dimg; nimg->channels = 3; nimg->data = m->normal;
    *aimg = *dimg; aimg->channels = 3; aimg->data = m->albedo;
    d->depth = *dimg; d->normal_map = nimg; d->albedo = aimg;
    d->shadows = 1; d->shadow_search = 1; d->shadow_light = 0.35f;
    d->lights = &s->light; d->light_count = 1;
    d->material = s->mat;
}

/* ---- ours ------------------------------------------------------------------------------------ */

struct synth_side { scene *s; rl_map out; };
static int synth_run(void *user)
{
    synth_side *o = (synth_side *)user;
    rl_synth_options opt = rl_synth_default_options();
    return rl_synthesize(&o->s->example, &o->s->sketch, &opt, &o->out) == RL_OK ? 0 : 1;
}
static void synth_after(void *user) { rl_map_free(&((synth_side *)user)->out, NULL); }

struct normal_side { const float *h; float *out; };
static int normal_run(void *user)
{
    normal_side *o = (normal_side *)user;
    return rl_normal_map(o->h, RES, RES, NULL, o->out) == RL_OK ? 0 : 1;
}

struct render_side { scene *s; sr_framebuffer fb; };
static int render_run(void *user)
{
    render_side *o = (render_side *)user;
    float clear[4] = {0.16f, 0.17f, 0.20f, 1.0f};
    sr_framebuffer_clear(&o->fb, clear, 1.0f);
    for (int k = 0; k < 6; k++) {
        sr_image di, ni, ai;
        sr_relief_desc d;
        relief_desc(o->s, k, &di, &ni, &ai, &d);
        if (sr_draw_relief(&o->fb, &o->s->cam, &d) != SR_OK) return 1;
    }
    return 0;
}

/* ---- llvmpipe -------------------------------------------------------------------------------- */

static int load_gl(void) { return bench_gl_load("bench_relief"); }

/* One face per draw range (6 vertices); the face's frame comes as per-vertex attributes so that
   one glDrawArrays draws the cube: attribute 1 = origin, 2 = axis_u, 3 = axis_v, 4 = which maps. */
static const char *vs_src =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 1) in vec3 org; layout(location = 2) in vec3 au; layout(location = 3) in vec3 av;\n"
    "layout(location = 4) in float front;\n"
    "uniform mat4 vp;\n"
    "out vec3 P; flat out vec3 O; flat out vec3 U; flat out vec3 V; flat out float F;\n"
    "void main() { P = pos; O = org; U = au; V = av; F = front; gl_Position = vp * vec4(pos, 1.0); }\n";

/* render.h's sr__relief_search, sr_relief_intersect, sr__relief_visibility_search, sr__shade_light */
static const char *fs_src =
    "#version 330 core\n"
    "in vec3 P; flat in vec3 O; flat in vec3 U; flat in vec3 V; flat in float F;\n"
    "uniform sampler2D dmap0, nmap0, amap0, dmap1, nmap1, amap1;\n"
    "uniform mat4 vp; uniform vec3 eye, L, la, ld, ls, ms; uniform float scale, shin, spec_cut, shadow_light, bias;\n"
    "out vec4 color;\n"
    "float depth_at(vec2 st) { return F > 0.5 ? textureLod(dmap0, st, 0.0).r : textureLod(dmap1, st, 0.0).r; }\n"
    "float search(vec2 s0, vec2 d) {\n"
    "  float lo = 0.0, hi = 1.0, step = 1.0 / 10.0;\n"
    "  for (int i = 1; i <= 10; i++) { float dd = float(i) * step;\n"
    "    if (i == 10 || dd >= depth_at(s0 + dd * d)) { hi = dd; lo = dd - step; break; } }\n"
    "  for (int i = 0; i < 5; i++) { float mid = 0.5 * (lo + hi);\n"
    "    if (mid >= depth_at(s0 + mid * d)) hi = mid; else lo = mid; }\n"
    "  return 0.5 * (lo + hi);\n"
    "}\n"
    "void main() {\n"
    "  vec3 n = normalize(cross(U, V)), du = cross(V, n), dv = cross(n, U);\n"
    "  du /= dot(U, du); dv /= dot(V, dv);\n"
    "  vec3 dir = normalize(P - eye); float denom = dot(dir, n);\n"
    "  if (!(denom < 0.0)) discard;\n"
    "  vec3 rel = P - O; vec2 st0 = vec2(dot(rel, du), dot(rel, dv));\n"
    "  vec3 stp = dir * scale / -denom; vec2 dst = vec2(dot(stp, du), dot(stp, dv));\n"
    "  float hit = search(st0, dst); vec2 sh = st0 + hit * dst;\n"
    "  if (sh.x < 0.0 || sh.x > 1.0 || sh.y < 0.0 || sh.y > 1.0) discard;\n"
    "  vec3 Ph = P + dir * (hit * scale / -denom);\n"
    "  vec4 clip = vp * vec4(Ph, 1.0); gl_FragDepth = 0.5 * (clip.z / clip.w) + 0.5;\n"
    "  vec3 tn = F > 0.5 ? textureLod(nmap0, sh, 0.0).rgb : textureLod(nmap1, sh, 0.0).rgb;\n"
    "  vec3 kd = F > 0.5 ? textureLod(amap0, sh, 0.0).rgb : textureLod(amap1, sh, 0.0).rgb;\n"
    "  vec3 N = normalize(tn.x * normalize(U) + tn.y * normalize(V) + tn.z * n);\n"
    "  vec3 Vw = normalize(eye - Ph);\n"
    "  float vis = 0.0, ln = dot(L, n);\n"
    "  if (ln > 0.0) { vec3 s3 = L * scale / ln; vec2 d2 = vec2(dot(s3, du), dot(s3, dv));\n"
    "    float found = search(sh + hit * d2, -d2); vis = found < hit - bias ? 0.0 : 1.0; }\n"
    "  if (vis == 0.0) vis = shadow_light;\n"
    "  float ndl = dot(N, L), spec = 0.0;\n"
    "  if (ndl > 0.0) { vec3 H = L + Vw; float hh = dot(H, H), nh = dot(N, H);\n"
    "    if (nh > 0.0 && nh * nh > spec_cut * spec_cut * hh) spec = pow(nh * nh / hh, 0.5 * shin); }\n"
    "  else ndl = 0.0;\n"
    "  color = vec4(la * kd + vis * (ld * kd * ndl + ls * ms * spec), 1.0);\n"
    "}\n";

struct gl_side {
    scene *s;
    OSMesaContext ctx;
    unsigned char *buf;
};

static GLuint compile(GLenum type, const char *src)
{
    GLuint sh = p_glCreateShader(type);
    GLint ok = 0;
    p_glShaderSource(sh, 1, &src, NULL);
    p_glCompileShader(sh);
    p_glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        p_glGetShaderInfoLog(sh, sizeof log, NULL, log);
        fprintf(stderr, "bench_relief: shader: %s\n", log);
        return 0;
    }
    return sh;
}

static void upload(GLuint unit, GLuint tex, int w, int h, int ch, const float *data)
{
    p_glActiveTexture(GL_TEXTURE0 + unit);
    p_glBindTexture(GL_TEXTURE_2D, tex);
    p_glTexImage2D(GL_TEXTURE_2D, 0, ch == 1 ? GL_R32F : GL_RGB32F, w, h, 0, ch == 1 ? GL_RED : GL_RGB, GL_FLOAT, data);
    p_glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    p_glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    p_glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    p_glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

static int gl_setup(gl_side *g)
{
    static const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 0,
                                  OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                                  OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    scene *s = g->s;
    GLuint vs, fs, prog, vao, vbo, tex[6];
    GLint ok = 0;
    static float verts[36 * 13];
    g->ctx = OSMesaCreateContextAttribs(attribs, NULL);
    if (!g->ctx) { fprintf(stderr, "bench_relief: OSMesaCreateContextAttribs failed\n"); return 0; }
    g->buf = (unsigned char *)malloc((size_t)FW * FH * 4);
    if (!g->buf || !OSMesaMakeCurrent(g->ctx, g->buf, GL_UNSIGNED_BYTE, FW, FH)) { fprintf(stderr, "bench_relief: OSMesaMakeCurrent failed\n"); return 0; }
    if (!load_gl()) return 0;
    fprintf(stderr, "bench_relief: GL %s, %s\n", (const char *)p_glGetString(GL_VERSION), (const char *)p_glGetString(GL_RENDERER));
    vs = compile(GL_VERTEX_SHADER, vs_src);
    fs = compile(GL_FRAGMENT_SHADER, fs_src);
    if (!vs || !fs) return 0;
    prog = p_glCreateProgram();
    p_glAttachShader(prog, vs);
    p_glAttachShader(prog, fs);
    p_glLinkProgram(prog);
    p_glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) { fprintf(stderr, "bench_relief: link failed\n"); return 0; }
    p_glUseProgram(prog);
    {
        float ms[3], spec_cut = std::pow(1e-4f, 1.0f / s->mat.shininess), L[3];
        float l = std::sqrt(s->light.vector[0] * s->light.vector[0] + s->light.vector[1] * s->light.vector[1] + s->light.vector[2] * s->light.vector[2]);
        for (int k = 0; k < 3; k++) { ms[k] = s->mat.specular[k]; L[k] = s->light.vector[k] / l; }
        p_glUniformMatrix4fv(p_glGetUniformLocation(prog, "vp"), 1, GL_FALSE, s->cam.viewproj);
        p_glUniform3fv(p_glGetUniformLocation(prog, "eye"), 1, s->cam.eye);
        p_glUniform3fv(p_glGetUniformLocation(prog, "L"), 1, L);
        p_glUniform3fv(p_glGetUniformLocation(prog, "la"), 1, s->light.ambient);
        p_glUniform3fv(p_glGetUniformLocation(prog, "ld"), 1, s->light.diffuse);
        p_glUniform3fv(p_glGetUniformLocation(prog, "ls"), 1, s->light.specular);
        p_glUniform3fv(p_glGetUniformLocation(prog, "ms"), 1, ms);
        p_glUniform1f(p_glGetUniformLocation(prog, "scale"), s->depth_scale);
        p_glUniform1f(p_glGetUniformLocation(prog, "shin"), s->mat.shininess);
        p_glUniform1f(p_glGetUniformLocation(prog, "spec_cut"), spec_cut);
        p_glUniform1f(p_glGetUniformLocation(prog, "shadow_light"), 0.35f);
        p_glUniform1f(p_glGetUniformLocation(prog, "bias"), 0.02f);
        const char *names[6] = {"dmap0", "nmap0", "amap0", "dmap1", "nmap1", "amap1"};
        for (int k = 0; k < 6; k++) p_glUniform1i(p_glGetUniformLocation(prog, names[k]), k);
    }
    p_glGenTextures(6, tex);
    upload(0, tex[0], s->front.w, s->front.h, 1, s->front.depth);
    upload(1, tex[1], s->front.w, s->front.h, 3, s->front.normal);
    upload(2, tex[2], s->front.w, s->front.h, 3, s->front.albedo);
    upload(3, tex[3], s->side.w, s->side.h, 1, s->side.depth);
    upload(4, tex[4], s->side.w, s->side.h, 3, s->side.normal);
    upload(5, tex[5], s->side.w, s->side.h, 3, s->side.albedo);
    for (int k = 0; k < 6; k++) { /* two triangles per face: corners (0,0) (1,0) (1,1), (0,0) (1,1) (0,1) */
        static const float cs[6][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
        for (int v = 0; v < 6; v++) {
            float *o = verts + (size_t)(k * 6 + v) * 13;
            for (int c = 0; c < 3; c++) o[c] = faces[k][c] + cs[v][0] * faces[k][3 + c] + cs[v][1] * faces[k][6 + c];
            memcpy(o + 3, faces[k], 36);
            o[12] = k == 0 ? 1.0f : 0.0f;
        }
    }
    p_glGenVertexArrays(1, &vao);
    p_glBindVertexArray(vao);
    p_glGenBuffers(1, &vbo);
    p_glBindBuffer(GL_ARRAY_BUFFER, vbo);
    p_glBufferData(GL_ARRAY_BUFFER, sizeof verts, verts, GL_STATIC_DRAW);
    for (int a = 0; a < 5; a++) {
        p_glVertexAttribPointer((GLuint)a, a == 4 ? 1 : 3, GL_FLOAT, GL_FALSE, 13 * sizeof(float), (const void *)(size_t)(a * 3 * sizeof(float)));
        p_glEnableVertexAttribArray((GLuint)a);
    }
    p_glViewport(0, 0, FW, FH);
    p_glEnable(GL_DEPTH_TEST);
    p_glDepthFunc(GL_LESS);
    p_glClearColor(0.16f, 0.17f, 0.20f, 1.0f);
    return p_glGetError() == GL_NO_ERROR;
}

static int gl_run(void *user)
{
    (void)user;
    p_glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    p_glDrawArrays(GL_TRIANGLES, 0, 36);
    p_glFinish();
    return 0;
}

/* the letter R, black strokes on grey, centred in RES x RES (as build/relief text:R) */
static int make_sketch(rl_map *m)
{
    sr_image8 img;
    int scale = (int)(0.8f * (float)RES / 4.0f);
    uint8_t ink[3] = {0, 0, 0};
    if (scale > RES / 7) scale = RES / 7;
    img.width = img.height = RES; img.channels = 3;
    img.pixels = (uint8_t *)malloc((size_t)RES * RES * 3);
    m->width = m->height = RES;
    m->data = (float *)malloc(sizeof(float) * RES * RES);
    if (!img.pixels || !m->data) return 0;
    memset(img.pixels, 128, (size_t)RES * RES * 3);
    sr_draw_text(&img, (RES - 3 * scale) / 2, (RES - 5 * scale) / 2, "R", scale, ink);
    for (size_t i = 0; i < (size_t)RES * RES; i++) m->data[i] = (float)img.pixels[3 * i] / 255.0f;
    free(img.pixels);
    return 1;
}

static int load_example(const char *path, int crop, rl_map *m)
{
    sr_picture p;
    sr_result r = sr_read_image(path, NULL, &p);
    if (r != SR_OK) { fprintf(stderr, "bench_relief: %s: %s\n", path, sr_result_string(r)); return 0; }
    float *all = (float *)malloc(sizeof(float) * (size_t)p.width * (size_t)p.height);
    if (!all) return 0;
    sr_picture_channel(&p, 0, all);
    if (crop && p.width >= 496 && p.height >= 962) {
        m->width = m->height = 384;
        m->data = (float *)malloc(sizeof(float) * 384 * 384);
        if (!m->data) return 0;
        for (int y = 0; y < 384; y++) memcpy(m->data + (size_t)y * 384, all + (size_t)(578 + y) * p.width + 112, sizeof(float) * 384);
        free(all);
    } else {
        m->width = p.width; m->height = p.height; m->data = all;
    }
    sr_picture_free(&p);
    return 1;
}

int main(int argc, char **argv)
{
    const char *path = "/usr/share/glmark2/textures/asteroid-height-map.png", *prefix = NULL;
    int crop = 1;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) prefix = argv[++i];
        else if (argv[i][0] != '-') { path = argv[i]; crop = 0; }
        else { fprintf(stderr, "usage: bench_relief [EXAMPLE] [-o PREFIX]\n"); return 1; }
    }
    setenv("LP_NUM_THREADS", "0", 1);
    setenv("GALLIUM_DRIVER", "llvmpipe", 1);
    static scene s;
    if (!load_example(path, crop, &s.example) || !make_sketch(&s.sketch)) return 1;
    setup_view(&s);
    BENCH_PRINT_FLAGS("relief");
    fprintf(stderr, "bench_relief: example %dx%d, output %dx%d, frame %dx%d\n", s.example.width, s.example.height, RES, RES, FW, FH);

    synth_side so = {&s, {0, 0, NULL}};
    bench_side synth = bench_make_side("synthesis", synth_run, synth_after, &so);
    int failed = bench_interleave(&synth, 1, 0);
    rl_synth_options opt = rl_synth_default_options();
    if (failed || rl_synthesize(&s.example, &s.sketch, &opt, &s.fused) != RL_OK) { fprintf(stderr, "bench_relief: synthesis failed\n"); return 2; }
    normal_side no = {s.fused.data, (float *)malloc(sizeof(float) * 3 * RES * RES)};
    bench_side normal = bench_make_side("normal map", normal_run, NULL, &no);
    if (!no.out || bench_interleave(&normal, 1, 0) != 0) return 2;
    free(no.out);
    if (!make_face(&s.fused, s.depth_scale, &s.front) || !make_face(&s.example, s.depth_scale, &s.side)) return 2;

    render_side ro;
    ro.s = &s;
    if (sr_framebuffer_create(&ro.fb, FW, FH, NULL) != SR_OK) return 2;

    gl_side g;
    g.s = &s;
    if (!gl_setup(&g)) return 2;
    bench_side frame[2] = {bench_make_side("ours", render_run, NULL, &ro), bench_make_side("llvmpipe", gl_run, NULL, &g)};
    if (bench_interleave(frame, 2, 0) != 0) return 2;
    p_glReadPixels(0, 0, FW, FH, GL_RGBA, GL_UNSIGNED_BYTE, g.buf);

    unsigned char *mine = (unsigned char *)malloc((size_t)FW * FH * 4);
    size_t differ = 0;
    if (!mine) return 2;
    render_run(&ro);
    sr_framebuffer_to_rgb8(&ro.fb, mine, 4);
    for (int y = 0; y < FH; y++)
        for (int x = 0; x < FW; x++) {
            const unsigned char *a = mine + ((size_t)y * FW + x) * 4, *b = g.buf + ((size_t)(FH - 1 - y) * FW + x) * 4;
            int d = 0;
            for (int c = 0; c < 3; c++) d |= std::abs((int)a[c] - (int)b[c]) > 4;
            differ += d != 0;
        }
    if (prefix) {
        char p1[1024], p2[1024];
        snprintf(p1, sizeof p1, "%s_ours.png", prefix);
        snprintf(p2, sizeof p2, "%s_llvmpipe.png", prefix);
        sr_write_png(p1, mine, FW, FH, 4, 0);
        sr_write_png(p2, g.buf, FW, FH, 4, 1);
    }
    printf("RESULT relief res=%d", RES);
    bench_print_ms("synth", &synth);
    bench_print_ms("normal", &normal);
    bench_print_ms("render", &frame[0]);
    bench_print_ms("llvmpipe", &frame[1]);
    bench_print_ratio(&frame[0], &frame[1]);
    printf(" diff_pixels=%.5f\n", (double)differ / ((double)FW * FH));
    free(mine);
    sr_framebuffer_free(&ro.fb);
    OSMesaDestroyContext(g.ctx);
    free(g.buf);
    return 0;
}
