/* bench_raster - per-pixel Phong rendering of a mesh at 1024x1024: render.h (sr_draw_mesh) vs
   Mesa's llvmpipe through OSMesa (OpenGL 3.3 core, a GLSL per-fragment Blinn-Phong shader).

   usage: bench_raster [MESH] [-o PREFIX]
     MESH   input mesh, any format meshio reads (default build/sphere1m.off)
     -o     also write PREFIX_ours.png and PREFIX_llvmpipe.png

   Both sides draw the same picture: same camera (render.h's matrices handed to GL), one
   directional light, the GL fixed-function lighting model (ambient + diffuse + Blinn specular
   with a local viewer, two-sided), area-weighted vertex normals computed once, back faces culled,
   GL_LESS depth test, 8-bit RGBA output. llvmpipe runs on one thread (LP_NUM_THREADS=0 set before
   OSMesa is initialised). Setup outside the timer: reading the mesh, normals, GL context, shader
   compilation, vertex/index buffer upload, one warm-up frame per side.
   Timed, per frame: ours - sr_framebuffer_clear + sr_draw_mesh (the float framebuffer is final;
   no 8-bit conversion); llvmpipe - glClear + glDrawElements + glFinish.
   The sides interleaved frame by frame: one warm-up frame each, then 11 rounds (bench/bench.h),
   medians with min/max. glibc's mmap threshold is fixed high
   for the whole process (see main) so that neither side page-faults fresh mappings every frame.
   diff_pixels: fraction of the pixels covered by either side whose 8-bit colours differ by more
   than 4/255 in any channel (ours converted with round-to-nearest, GL read back with glReadPixels).

   Output: RESULT raster tris=<n> ours_ms=<t> ours_ms_min=.. ours_ms_max=.. llvmpipe_ms=<t> ..
               ratio=<ours/llvmpipe> ratio_min=.. ratio_max=.. diff_pixels=<f>
   Exit status 0; 1 bad arguments or unreadable mesh; 2 setup failure; 3 diff_pixels > 0.01.
   Build: c++ -O2 -Iexamples -Ibench bench/bench_raster.cpp -o bench_raster -lOSMesa -lm */
#include "bench.h"

#include <cmath>
#ifdef __GLIBC__
#include <malloc.h> /* mallopt */
#endif
#include <cstdio>
#include <cstdlib>
#include <cstring>

#define GL_GLEXT_PROTOTYPES 0
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include "osmesa_gl.h"

#define MIO_IMPLEMENTATION
#include "meshio.h"
#define SR_IMPLEMENTATION
#include "render.h"

#define W 1024
#define H 1024

/* ---- the scene, shared by both sides --------------------------------------------------------- */

struct scene {
    mio_mesh mesh;
    float *normals;
    sr_camera cam;
    sr_light light;
    sr_material mat;
};

static void frame_scene(scene *s)
{
    float lo[3], hi[3], c[3], r = 0.0f, eye[3], dist, toward[3];
    size_t v;
    int k;
    for (k = 0; k < 3; k++) lo[k] = hi[k] = s->mesh.positions[k];
    for (v = 0; v < s->mesh.vertex_count; v++)
        for (k = 0; k < 3; k++) {
            float x = s->mesh.positions[3 * v + (size_t)k];
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    for (k = 0; k < 3; k++) c[k] = 0.5f * (lo[k] + hi[k]);
    for (v = 0; v < s->mesh.vertex_count; v++) {
        const float *p = s->mesh.positions + 3 * v;
        float d = std::sqrt((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) + (p[2] - c[2]) * (p[2] - c[2]));
        if (d > r) r = d;
    }
    dist = r / std::sin(0.5f * 35.0f * 0.0174533f) * 1.05f;
    eye[0] = c[0] + dist * 0.5f; eye[1] = c[1] + dist * 0.35f; eye[2] = c[2] + dist * 0.79f;
    {
        float l = std::sqrt(0.25f + 0.35f * 0.35f + 0.79f * 0.79f);
        for (k = 0; k < 3; k++) eye[k] = c[k] + (eye[k] - c[k]) / l;
    }
    sr_camera_look_at(&s->cam, eye, c, NULL, 35.0f, 1.0f, dist - 1.1f * r, dist + 1.1f * r);
    toward[0] = 0.3f; toward[1] = 0.8f; toward[2] = 0.6f;
    sr_light_default(&s->light, toward);
    for (k = 0; k < 3; k++) { s->light.vector[k] /= std::sqrt(0.09f + 0.64f + 0.36f); s->light.ambient[k] = 0.2f; s->light.diffuse[k] = 0.9f; s->light.specular[k] = 0.7f; }
    sr_material_default(&s->mat);
    s->mat.diffuse[0] = 0.8f; s->mat.diffuse[1] = 0.6f; s->mat.diffuse[2] = 0.4f;
    s->mat.ambient[0] = 0.8f; s->mat.ambient[1] = 0.6f; s->mat.ambient[2] = 0.4f;
    s->mat.specular[0] = s->mat.specular[1] = s->mat.specular[2] = 0.4f;
    s->mat.shininess = 24.0f;
}

/* ---- ours ------------------------------------------------------------------------------------ */

struct ours_side {
    scene *s;
    sr_framebuffer fb;
    sr_draw_desc d;
};

static int ours_run(void *user)
{
    ours_side *o = (ours_side *)user;
    float bg[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    sr_framebuffer_clear(&o->fb, bg, 1.0f);
    return sr_draw_mesh(&o->fb, &o->s->cam, &o->d) == SR_OK ? 0 : 1;
}

/* ---- llvmpipe -------------------------------------------------------------------------------- */

static int load_gl(void) { return bench_gl_load("bench_raster"); }

/* the fragment shader evaluates the formula of sr__shade_light in render.h (which computes
   (N.H/|H|)^s as ((N.H)^2/|H|^2)^(s/2), the same value) */
static const char *vs_src =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 1) in vec3 nrm;\n"
    "uniform mat4 mvp;\n"
    "out vec3 P; out vec3 N;\n"
    "void main() { P = pos; N = nrm; gl_Position = mvp * vec4(pos, 1.0); }\n";
static const char *fs_src =
    "#version 330 core\n"
    "in vec3 P; in vec3 N;\n"
    "uniform vec3 eye, L, la, ld, ls, ma, md, ms; uniform float shin;\n"
    "out vec4 color;\n"
    "void main() {\n"
    "  vec3 n = normalize(N); if (!gl_FrontFacing) n = -n;\n"
    "  vec3 V = normalize(eye - P);\n"
    "  float ndl = dot(n, L), spec = 0.0;\n"
    "  if (ndl > 0.0) { vec3 h = normalize(L + V); float ndh = dot(n, h); if (ndh > 0.0) spec = pow(ndh, shin); }\n"
    "  else ndl = 0.0;\n"
    "  color = vec4(la * ma + ld * md * ndl + ls * ms * spec, 1.0);\n"
    "}\n";

struct gl_side {
    scene *s;
    OSMesaContext ctx;
    unsigned char *buf;
    GLsizei index_count;
};

static GLuint compile(GLenum type, const char *src)
{
    GLuint sh = p_glCreateShader(type);
    GLint ok = 0;
    p_glShaderSource(sh, 1, &src, NULL);
    p_glCompileShader(sh);
    p_glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048];
        p_glGetShaderInfoLog(sh, sizeof log, NULL, log);
        fprintf(stderr, "bench_raster: shader: %s\n", log);
        return 0;
    }
    return sh;
}

static int gl_setup(gl_side *g)
{
    static const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 0,
                                  OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                                  OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    scene *s = g->s;
    GLuint vs, fs, prog, vao, vbo[2], ibo;
    GLint ok = 0;
    g->ctx = OSMesaCreateContextAttribs(attribs, NULL);
    if (!g->ctx) { fprintf(stderr, "bench_raster: OSMesaCreateContextAttribs failed\n"); return 0; }
    g->buf = (unsigned char *)malloc((size_t)W * H * 4);
    if (!g->buf || !OSMesaMakeCurrent(g->ctx, g->buf, GL_UNSIGNED_BYTE, W, H)) {
        fprintf(stderr, "bench_raster: OSMesaMakeCurrent failed\n");
        return 0;
    }
    if (!load_gl()) return 0;
    fprintf(stderr, "bench_raster: GL %s, %s\n", (const char *)p_glGetString(GL_VERSION), (const char *)p_glGetString(GL_RENDERER));
    vs = compile(GL_VERTEX_SHADER, vs_src);
    fs = compile(GL_FRAGMENT_SHADER, fs_src);
    if (!vs || !fs) return 0;
    prog = p_glCreateProgram();
    p_glAttachShader(prog, vs);
    p_glAttachShader(prog, fs);
    p_glLinkProgram(prog);
    p_glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) { fprintf(stderr, "bench_raster: link failed\n"); return 0; }
    p_glUseProgram(prog);
    p_glUniformMatrix4fv(p_glGetUniformLocation(prog, "mvp"), 1, GL_FALSE, s->cam.viewproj);
    p_glUniform3fv(p_glGetUniformLocation(prog, "eye"), 1, s->cam.eye);
    p_glUniform3fv(p_glGetUniformLocation(prog, "L"), 1, s->light.vector);
    p_glUniform3fv(p_glGetUniformLocation(prog, "la"), 1, s->light.ambient);
    p_glUniform3fv(p_glGetUniformLocation(prog, "ld"), 1, s->light.diffuse);
    p_glUniform3fv(p_glGetUniformLocation(prog, "ls"), 1, s->light.specular);
    p_glUniform3fv(p_glGetUniformLocation(prog, "ma"), 1, s->mat.ambient);
    p_glUniform3fv(p_glGetUniformLocation(prog, "md"), 1, s->mat.diffuse);
    p_glUniform3fv(p_glGetUniformLocation(prog, "ms"), 1, s->mat.specular);
    p_glUniform1f(p_glGetUniformLocation(prog, "shin"), s->mat.shininess);
    p_glGenVertexArrays(1, &vao);
    p_glBindVertexArray(vao);
    p_glGenBuffers(2, vbo);
    p_glBindBuffer(GL_ARRAY_BUFFER, vbo[0]);
    p_glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(s->mesh.vertex_count * 3 * sizeof(float)), s->mesh.positions, GL_STATIC_DRAW);
    p_glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    p_glEnableVertexAttribArray(0);
    p_glBindBuffer(GL_ARRAY_BUFFER, vbo[1]);
    p_glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(s->mesh.vertex_count * 3 * sizeof(float)), s->normals, GL_STATIC_DRAW);
    p_glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    p_glEnableVertexAttribArray(1);
    p_glGenBuffers(1, &ibo);
    p_glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    p_glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(s->mesh.triangle_count * 3 * sizeof(uint32_t)), s->mesh.indices, GL_STATIC_DRAW);
    g->index_count = (GLsizei)(s->mesh.triangle_count * 3);
    p_glViewport(0, 0, W, H);
    p_glEnable(GL_DEPTH_TEST);
    p_glDepthFunc(GL_LESS);
    p_glEnable(GL_CULL_FACE);
    p_glCullFace(GL_BACK);
    p_glFrontFace(GL_CCW);
    p_glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    return p_glGetError() == GL_NO_ERROR;
}

static int gl_run(void *user)
{
    gl_side *g = (gl_side *)user;
    p_glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    p_glDrawElements(GL_TRIANGLES, g->index_count, GL_UNSIGNED_INT, NULL);
    p_glFinish();
    return 0;
}

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off", *prefix = NULL;
    scene s;
    ours_side o;
    gl_side g;
    mio_error err;
    bench_side sides[2];
    unsigned char *mine;
    size_t covered = 0, differ = 0;
    int i, x, y, status = 0;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) prefix = argv[++i];
        else if (argv[i][0] != '-') path = argv[i];
        else { fprintf(stderr, "usage: bench_raster [MESH] [-o PREFIX]\n"); return 1; }
    }
#ifdef __GLIBC__
    /* Large blocks from the heap instead of fresh mmap()s: llvmpipe allocates and frees big
       per-frame buffers, and with glibc's default (dynamic) mmap threshold its frame time on a
       1M-triangle mesh varied 5x with whatever the process had freed before (every new mapping
       is page-faulted again). Fixing the threshold gives both sides their best, stable case. */
    mallopt(M_MMAP_THRESHOLD, 512 * 1024 * 1024);
    mallopt(M_TRIM_THRESHOLD, 1024 * 1024 * 1024);
#endif
    /* one llvmpipe thread; must be set before the first OSMesa call */
    setenv("LP_NUM_THREADS", "0", 1);
    setenv("GALLIUM_DRIVER", "llvmpipe", 1);
    memset(&s, 0, sizeof s);
    if (mio_read_file(path, NULL, &s.mesh, &err) != MIO_OK) {
        fprintf(stderr, "bench_raster: %s: %s\n", path, err.message);
        return 1;
    }
    s.normals = (float *)malloc(s.mesh.vertex_count * 3 * sizeof(float));
    if (!s.normals) return 2;
    sr_compute_vertex_normals(s.mesh.positions, s.mesh.vertex_count, s.mesh.indices, s.mesh.triangle_count, s.normals);
    frame_scene(&s);
    BENCH_PRINT_FLAGS("raster");
    fprintf(stderr, "bench_raster: %s: %zu triangles at %dx%d\n", path, s.mesh.triangle_count, W, H);

    memset(&o, 0, sizeof o);
    o.s = &s;
    if (sr_framebuffer_create(&o.fb, W, H, NULL) != SR_OK) return 2;
    sr_draw_desc_default(&o.d);
    o.d.positions = s.mesh.positions; o.d.vertex_count = s.mesh.vertex_count;
    o.d.indices = s.mesh.indices; o.d.triangle_count = s.mesh.triangle_count;
    o.d.normals = s.normals;
    o.d.cull = SR_CULL_BACK;
    o.d.lights = &s.light; o.d.light_count = 1;
    o.d.material = s.mat;

    memset(&g, 0, sizeof g);
    g.s = &s;
    if (!gl_setup(&g)) { fprintf(stderr, "bench_raster: OpenGL setup failed\n"); return 2; }
    sides[0] = bench_make_side("ours", ours_run, NULL, &o);
    sides[1] = bench_make_side("llvmpipe", gl_run, NULL, &g);
    if (bench_interleave(sides, 2, 0) != 0) return 2;

    /* compare the last frames (GL rows are bottom-up) */
    mine = (unsigned char *)malloc((size_t)W * H * 4);
    if (!mine) return 2;
    sr_framebuffer_to_rgb8(&o.fb, mine, 4);
    p_glReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, g.buf);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            const unsigned char *a = mine + ((size_t)y * W + (size_t)x) * 4, *b = g.buf + ((size_t)(H - 1 - y) * W + (size_t)x) * 4;
            int c, bad = 0;
            if (a[3] == 0 && b[3] == 0) continue;
            covered++;
            for (c = 0; c < 4; c++) if (std::abs((int)a[c] - (int)b[c]) > 4) bad = 1;
            differ += (size_t)bad;
        }
    if (prefix) {
        char name[1024];
        unsigned char *rgb = (unsigned char *)malloc((size_t)W * H * 3);
        snprintf(name, sizeof name, "%s_ours.png", prefix);
        sr_write_framebuffer_png(&o.fb, name, 0);
        for (i = 0; i < W * H; i++) memcpy(rgb + 3 * (size_t)i, g.buf + 4 * (size_t)i, 3);
        snprintf(name, sizeof name, "%s_llvmpipe.png", prefix);
        sr_write_png(name, rgb, W, H, 3, 1);
        free(rgb);
    }
    printf("RESULT raster tris=%zu", s.mesh.triangle_count);
    bench_print_ms("ours", &sides[0]);
    bench_print_ms("llvmpipe", &sides[1]);
    bench_print_ratio(&sides[0], &sides[1]);
    printf(" diff_pixels=%.5f\n", covered ? (double)differ / (double)covered : 0.0);
    fflush(stdout);
    if (covered == 0 || (double)differ > 0.01 * (double)covered) {
        fprintf(stderr, "bench_raster: the two pictures differ (%zu of %zu covered pixels): not the same work\n", differ, covered);
        status = 3;
    }
    OSMesaDestroyContext(g.ctx);
    free(g.buf);
    free(mine);
    sr_framebuffer_free(&o.fb);
    free(s.normals);
    mio_free_mesh(&s.mesh);
    return status;
}
