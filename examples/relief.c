/* relief - paper 003's pipeline: a sketch fused into an example height map (examples/relief.h),
   its normal map, and a relief-mapped rock cube (or cylinder) rendered with render.h to a PNG.

   usage: relief EXAMPLE SKETCH -o OUT.png [options]
     EXAMPLE   a height map: PNG (8/16-bit, grey or colour: channel 0), PGM or PFM; or gen:rock
               (a generated 384 x 384 ridged-noise rock)
     SKETCH    an image of the output's size (PNG/PGM/PFM, channel 0: > 0.75 white stroke = ridge,
               < 0.25 black stroke = groove, else nothing), or a text file of strokes:
                   size 512 512
                   white 40,60 200,80 300,200 width 6     (a polyline, pixels, width in pixels)
                   black 100,400 400,400 width 10
               or text:STRING (the string in the built-in font, black strokes, centred)
   options:
     --crop X,Y,N       use the N x N square of EXAMPLE at (X, Y) (e.g. 112,578,384 on glmark2's
                        asteroid-height-map.png, inside its lower disk)
     --size N           output size for stroke files without "size" and for text: (default 512)
     --white            text: strokes are white (embossed) instead of black (engraved)
     --emboss           the distance-transform baseline instead of the synthesis
     --patch P          patch size (default 48)
     --emphasis E       extra stroke relief in example ranges (default 0.45, negative = none)
     --depth D          relief depth in world units on the cube of side 2 (default 0.12)
     --frame WxH        rendering size (default 800x600)
     --light X,Y,Z      direction toward the light (default 0.6,0.7,0.5)
     --no-shadows       no shadow rays
     --cylinder         a cylinder (the map once around, curved silhouettes) instead of the cube
     --height FILE      also write the fused height map (.pfm, or 16-bit .png)
     --normal FILE      also write the normal map as an RGB PNG
     --sheet FILE       also write a contact sheet: example | sketch | fused | normal map | render
   Prints `RESULT relief ...` with the stage timings on stdout; progress goes to stderr.
   Exit status 0 on success, 2 on bad arguments (named in the message), 1 on failure (unreadable
   or invalid input, a failed write). Every file is written to NAME.tmp and renamed once all are
   complete, so a failed run leaves none of them. --version prints the version. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RL_IMPLEMENTATION
#include "relief.h"
#define SR_IMPLEMENTATION
#include "render.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#define RELIEF_VERSION "relief 0.2 (relief.h, render.h)"

typedef struct args {
    const char *example, *sketch, *out, *height_out, *normal_out, *sheet_out;
    int crop[3], size, white, emboss, patch, fw, fh, shadows, cylinder;
    float emphasis, depth, light[3];
} args;

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

static void usage(FILE *to)
{
    fprintf(to,
            "usage: relief EXAMPLE SKETCH -o OUT.png [--crop X,Y,N] [--size N] [--white] [--emboss] [--patch P]\n"
            "              [--emphasis E] [--depth D] [--frame WxH] [--light X,Y,Z] [--no-shadows] [--cylinder]\n"
            "              [--height FILE.pfm|.png] [--normal FILE.png] [--sheet FILE.png]\n"
            "Fuses a sketch into an example height map (relief.h) and renders it relief-mapped on a cube.\n"
            "  EXAMPLE            a height map: PNG (8/16-bit, channel 0), PGM or PFM; or gen:rock (generated)\n"
            "  SKETCH             an image (channel 0: > 0.75 white stroke = ridge, < 0.25 black = groove), a\n"
            "                     stroke file (lines: size W H / white|black x,y x,y ... width W), or text:STRING\n"
            "  -o, --output FILE  the rendering, a PNG; the name must end in .png (required)\n"
            "  --crop X,Y,N       use the N x N square of EXAMPLE at (X, Y), N >= 8 (default: all of it)\n"
            "  --size N           output size for stroke files without 'size' and for text:, 16..8192 (default 512)\n"
            "  --white            text: white (embossed) strokes instead of black (engraved) (default: black)\n"
            "  --emboss           the distance-transform baseline instead of the synthesis (default: synthesis)\n"
            "  --patch P          patch size in texels, 4..1024 (default 48)\n"
            "  --emphasis E       extra stroke relief in example ranges, -10..10, negative = none (default 0.45)\n"
            "  --depth D          relief depth on the cube of side 2, (0, 2) (default 0.12)\n"
            "  --frame WxH        rendering size, 16..8192 each (default 800x600)\n"
            "  --light X,Y,Z      direction toward the light (default 0.6,0.7,0.5)\n"
            "  --no-shadows       no shadow rays (default: shadows)\n"
            "  --cylinder         a cylinder with curved silhouettes instead of the cube (default: cube)\n"
            "  --height FILE      also write the fused height map: .pfm (float) or .png (16-bit) (default: none)\n"
            "  --normal FILE      also write the normal map as an RGB .png (default: none)\n"
            "  --sheet FILE       also write a .png contact sheet: example | sketch | fused | normal map | render\n"
            "                     (default: none)\n"
            "  -h, --help         show this help and exit\n"
            "  --version          show the version and exit\n"
            "Prints one RESULT relief line on stdout; progress on stderr.\n"
            "Exit status: 0 done, 1 failure (unreadable or invalid input, a failed write), 2 usage.\n"
            "The files are written to NAME.tmp and renamed once all are complete: a failed run leaves none.\n");
}

/* an output option's name: one of the extensions (any case) */
static int check_output(const char *opt, const char *path, const char *ext1, const char *ext2)
{
    if (cli_has_extension(path, ext1) || (ext2 && cli_has_extension(path, ext2))) return -1;
    return cli_usage_error("relief", "%s '%s': the name must end in %s%s%s", opt, path, ext1, ext2 ? " or " : "", ext2 ? ext2 : "");
}

/* Returns -1 to go on, or the exit status (0 for --help/--version, 2 for a usage error). */
static int parse_args(int argc, char **argv, args *a)
{
    static const char *const valued[] = {"-o", "--output", "--crop", "--size", "--patch", "--emphasis", "--depth",
                                         "--frame", "--light", "--height", "--normal", "--sheet"};
    int i, k, pos = 0, st;
    double d[3];
    long n;
    memset(a, 0, sizeof *a);
    a->crop[2] = 0; a->size = 512; a->patch = 48; a->fw = 800; a->fh = 600; a->shadows = 1;
    a->emphasis = 0.0f; a->depth = 0.12f;
    a->light[0] = 0.6f; a->light[1] = 0.7f; a->light[2] = 0.5f;
    for (i = 1; i < argc; i++) {
        const char *s = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int need = 0;
        for (k = 0; k < (int)(sizeof valued / sizeof valued[0]); k++) need |= !strcmp(s, valued[k]);
        if (!strcmp(s, "--help") || !strcmp(s, "-h")) { usage(stdout); return 0; }
        if (!strcmp(s, "--version")) { printf("%s\n", RELIEF_VERSION); return 0; }
        if (need && !v) return cli_usage_error("relief", "%s needs a value", s);
        if (need) i++;
        if (!strcmp(s, "-o") || !strcmp(s, "--output")) a->out = v;
        else if (!strcmp(s, "--crop")) {
            if (!cli_parse_doubles(v, ',', 3, 3, 0.0, 16384.0, d, NULL) || d[0] != floor(d[0]) || d[1] != floor(d[1]) ||
                d[2] != floor(d[2]) || d[2] < 8.0)
                return cli_usage_error("relief", "--crop '%s': not X,Y,N (integers, N >= 8)", v);
            for (k = 0; k < 3; k++) a->crop[k] = (int)d[k];
        } else if (!strcmp(s, "--size")) {
            if (!cli_parse_long(v, 16, 8192, &n)) return cli_usage_error("relief", "--size '%s': not an integer in 16..8192", v);
            a->size = (int)n;
        } else if (!strcmp(s, "--patch")) {
            if (!cli_parse_long(v, 4, 1024, &n)) return cli_usage_error("relief", "--patch '%s': not an integer in 4..1024", v);
            a->patch = (int)n;
        } else if (!strcmp(s, "--emphasis")) {
            if (!cli_parse_double(v, -10.0, 10.0, &d[0])) return cli_usage_error("relief", "--emphasis '%s': not a number in -10..10", v);
            a->emphasis = (float)d[0];
        } else if (!strcmp(s, "--depth")) {
            if (!cli_parse_double(v, 0.0, 2.0, &d[0]) || !(d[0] > 0.0 && d[0] < 2.0))
                return cli_usage_error("relief", "--depth '%s': not a number in (0, 2)", v);
            a->depth = (float)d[0];
        } else if (!strcmp(s, "--frame")) {
            if (!cli_parse_size(v, 16, 8192, 0, &a->fw, &a->fh)) return cli_usage_error("relief", "--frame '%s': not WxH with 16 <= W, H <= 8192", v);
        } else if (!strcmp(s, "--light")) {
            if (!cli_parse_doubles(v, ',', 3, 3, -1e6, 1e6, d, NULL) || (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0))
                return cli_usage_error("relief", "--light '%s': not X,Y,Z (three finite numbers, not all 0)", v);
            for (k = 0; k < 3; k++) a->light[k] = (float)d[k];
        } else if (!strcmp(s, "--height")) a->height_out = v;
        else if (!strcmp(s, "--normal")) a->normal_out = v;
        else if (!strcmp(s, "--sheet")) a->sheet_out = v;
        else if (!strcmp(s, "--white")) a->white = 1;
        else if (!strcmp(s, "--emboss")) a->emboss = 1;
        else if (!strcmp(s, "--no-shadows")) a->shadows = 0;
        else if (!strcmp(s, "--cylinder")) a->cylinder = 1;
        else if (s[0] == '-' && s[1]) return cli_usage_error("relief", "unknown option '%s'", s);
        else if (pos == 0) { a->example = s; pos++; }
        else if (pos == 1) { a->sketch = s; pos++; }
        else return cli_usage_error("relief", "unexpected argument '%s': EXAMPLE and SKETCH only", s);
    }
    if (!a->example || !a->sketch) return cli_usage_error("relief", "%s", "give EXAMPLE and SKETCH");
    if (!a->out) return cli_usage_error("relief", "%s", "no output given: -o OUT.png");
    if ((st = check_output("-o", a->out, ".png", NULL)) >= 0) return st;
    if (a->height_out && (st = check_output("--height", a->height_out, ".pfm", ".png")) >= 0) return st;
    if (a->normal_out && (st = check_output("--normal", a->normal_out, ".png", NULL)) >= 0) return st;
    if (a->sheet_out && (st = check_output("--sheet", a->sheet_out, ".png", NULL)) >= 0) return st;
    return -1;
}

static float lattice(int x, int y, uint32_t seed)
{
    uint32_t h = (uint32_t)x * 374761393u + (uint32_t)y * 668265263u + seed * 2246822519u;
    h = (h ^ (h >> 13)) * 1274126177u;
    return (float)((h ^ (h >> 16)) & 0xFFFF) / 65535.0f;
}

static float value_noise(float x, float y, uint32_t seed)
{
    int x0 = (int)floorf(x), y0 = (int)floorf(y);
    float fx = x - (float)x0, fy = y - (float)y0, a, b;
    fx = fx * fx * (3 - 2 * fx); fy = fy * fy * (3 - 2 * fy);
    a = lattice(x0, y0, seed) + fx * (lattice(x0 + 1, y0, seed) - lattice(x0, y0, seed));
    b = lattice(x0, y0 + 1, seed) + fx * (lattice(x0 + 1, y0 + 1, seed) - lattice(x0, y0 + 1, seed));
    return a + fy * (b - a);
}

/* gen:rock: four octaves of ridged value noise, sharp crests and valleys, in [0, 1] */
static int generate_rock(rl_map *m)
{
    int n = 384, x, y, o;
    m->width = m->height = n;
    m->data = (float *)malloc(sizeof(float) * (size_t)n * (size_t)n);
    if (!m->data) return 0;
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            float v = 0, amp = 0.6f, f = 1.0f / 40.0f;
            for (o = 0; o < 4; o++, amp *= 0.5f, f *= 2.0f) v += amp * (1.0f - fabsf(2.0f * value_noise((float)x * f, (float)y * f, (uint32_t)o + 1) - 1.0f));
            m->data[(size_t)y * n + x] = v / 1.125f;
        }
    return 1;
}

/* channel 0 of an image file as floats (PNG / PGM scaled to [0, 1]), optionally a crop */
static int load_map(const char *path, const int crop[3], rl_map *m)
{
    sr_picture p;
    sr_result r;
    if (!strcmp(path, "gen:rock")) return generate_rock(m);
    errno = 0;
    r = sr_read_image(path, NULL, &p);
    float *all;
    int y;
    if (r != SR_OK) { cli_result_error("relief", path, sr_result_string(r), r == SR_ERR_IO ? errno : 0); return 0; }
    all = (float *)malloc(sizeof(float) * (size_t)p.width * (size_t)p.height);
    if (!all) { sr_picture_free(&p); return 0; }
    sr_picture_channel(&p, 0, all);
    m->width = p.width; m->height = p.height; m->data = all;
    sr_picture_free(&p);
    if (crop && crop[2]) {
        float *c;
        if (crop[0] < 0 || crop[1] < 0 || crop[0] + crop[2] > m->width || crop[1] + crop[2] > m->height) {
            fprintf(stderr, "relief: --crop %d,%d,%d lies outside the %dx%d example\n", crop[0], crop[1], crop[2], m->width, m->height);
            free(all);
            m->data = NULL;
            return 0;
        }
        c = (float *)malloc(sizeof(float) * (size_t)crop[2] * (size_t)crop[2]);
        if (!c) { free(all); m->data = NULL; return 0; }
        for (y = 0; y < crop[2]; y++) memcpy(c + (size_t)y * crop[2], all + (size_t)(crop[1] + y) * m->width + crop[0], sizeof(float) * (size_t)crop[2]);
        free(all);
        m->width = m->height = crop[2];
        m->data = c;
    }
    return 1;
}

/* a disc of value v and radius r at (x, y) */
static void stamp(rl_map *m, float x, float y, float r, float v)
{
    int i, j;
    for (j = (int)floorf(y - r); j <= (int)ceilf(y + r); j++)
        for (i = (int)floorf(x - r); i <= (int)ceilf(x + r); i++)
            if (i >= 0 && j >= 0 && i < m->width && j < m->height && (i - x) * (i - x) + (j - y) * (j - y) <= r * r)
                m->data[(size_t)j * m->width + i] = v;
}

static int alloc_sketch(rl_map *m, int w, int h)
{
    size_t i;
    m->width = w; m->height = h;
    m->data = (float *)malloc(sizeof(float) * (size_t)w * (size_t)h);
    if (!m->data) return 0;
    for (i = 0; i < (size_t)w * (size_t)h; i++) m->data[i] = 0.5f;
    return 1;
}

/* "size W H" and "white|black x,y x,y ... [width W]" lines */
static int load_strokes(const char *path, int size, rl_map *m)
{
    FILE *f = fopen(path, "r");
    char line[4096];
    int lineno = 0, strokes = 0;
    m->data = NULL;
    if (!f) { cli_file_error("relief", path, "cannot open it", errno); return 0; }
    while (fgets(line, sizeof line, f)) {
        char *tok, *save = NULL;
        float px = 0, py = 0, width = 6.0f, pts[2 * 256];
        int n = 0, k, w = 0, h = 0, white;
        lineno++;
        tok = strtok_r(line, " \t\r\n", &save);
        if (!tok || tok[0] == '#') continue;
        if (!strcmp(tok, "size")) {
            char *a = strtok_r(NULL, " \t\r\n", &save), *b = strtok_r(NULL, " \t\r\n", &save);
            if (!a || !b || (w = atoi(a)) < 16 || (h = atoi(b)) < 16 || w > 8192 || h > 8192 || m->data) goto bad;
            if (!alloc_sketch(m, w, h)) goto bad;
            continue;
        }
        if (strcmp(tok, "white") && strcmp(tok, "black")) goto bad;
        white = !strcmp(tok, "white");
        if (!m->data && !alloc_sketch(m, size, size)) goto bad;
        while ((tok = strtok_r(NULL, " \t\r\n", &save)) != NULL) {
            if (!strcmp(tok, "width")) {
                tok = strtok_r(NULL, " \t\r\n", &save);
                if (!tok || !((width = (float)atof(tok)) > 0.0f)) goto bad;
                continue;
            }
            if (n >= 256 || sscanf(tok, "%f,%f", &px, &py) != 2) goto bad;
            pts[2 * n] = px; pts[2 * n + 1] = py; n++;
        }
        if (n < 1) goto bad;
        for (k = 0; k < n; k++) { /* the polyline as stamped discs every half texel */
            float x0 = pts[2 * k], y0 = pts[2 * k + 1], x1 = pts[2 * (k + 1 < n ? k + 1 : k)], y1 = pts[2 * (k + 1 < n ? k + 1 : k) + 1];
            float len = sqrtf((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0)), t;
            for (t = 0.0f; t <= len; t += 0.5f) stamp(m, x0 + (x1 - x0) * t / (len > 0 ? len : 1), y0 + (y1 - y0) * t / (len > 0 ? len : 1), 0.5f * width, white ? 1.0f : 0.0f);
        }
        strokes++;
    }
    fclose(f);
    if (!strokes) { fprintf(stderr, "relief: %s has no strokes\n", path); free(m->data); m->data = NULL; return 0; }
    return 1;
bad:
    fprintf(stderr, "relief: %s:%d: expected 'size W H' or 'white|black x,y ... [width W]'\n", path, lineno);
    fclose(f);
    free(m->data);
    m->data = NULL;
    return 0;
}

/* text in the built-in 3x5 font, centred, as black (or white) strokes on grey */
static int text_sketch(const char *text, int size, int white, rl_map *m)
{
    sr_image8 img;
    int len = (int)strlen(text), scale, x, y;
    size_t i;
    uint8_t ink[3] = {0, 0, 0};
    if (len < 1) return 0;
    scale = (int)(0.8f * (float)size / (4.0f * (float)len));
    if (scale > size / 7) scale = size / 7;
    if (scale < 1) { fprintf(stderr, "relief: text '%s' does not fit in %d texels\n", text, size); return 0; }
    img.width = img.height = size; img.channels = 3;
    img.pixels = (uint8_t *)malloc((size_t)size * (size_t)size * 3);
    if (!img.pixels || !alloc_sketch(m, size, size)) { free(img.pixels); return 0; }
    memset(img.pixels, 128, (size_t)size * (size_t)size * 3);
    x = (size - (4 * len - 1) * scale) / 2;
    y = (size - 5 * scale) / 2;
    if (white) ink[0] = ink[1] = ink[2] = 255;
    sr_draw_text(&img, x, y, text, scale, ink);
    for (i = 0; i < (size_t)size * (size_t)size; i++) m->data[i] = (float)img.pixels[3 * i] / 255.0f;
    free(img.pixels);
    return 1;
}

static int load_sketch(const args *a, rl_map *m)
{
    const char *s = a->sketch, *dot = strrchr(s, '.');
    if (!strncmp(s, "text:", 5)) return text_sketch(s + 5, a->size, a->white, m);
    if (dot && (!strcmp(dot, ".txt") || !strcmp(dot, ".strokes"))) return load_strokes(s, a->size, m);
    return load_map(s, NULL, m);
}

static int progress(void *user, float done)
{
    int *last = (int *)user, pct = (int)(100.0f * done);
    if (pct / 10 != *last / 10) fprintf(stderr, "\rrelief: synthesis %3d%%", pct);
    *last = pct;
    return 0;
}

/* the map's range to [0, 1] (a copy), rows reversed when flip is set (the cube's v runs up) */
static float *normalized_rows(const rl_map *m, int flip)
{
    size_t n = (size_t)m->width * (size_t)m->height, i;
    float lo = m->data[0], hi = m->data[0], *o = (float *)malloc(sizeof(float) * n);
    if (!o) return NULL;
    for (i = 0; i < n; i++) { lo = m->data[i] < lo ? m->data[i] : lo; hi = m->data[i] > hi ? m->data[i] : hi; }
    for (i = 0; i < n; i++) {
        size_t x = i % (size_t)m->width, y = i / (size_t)m->width, src = (flip ? (size_t)m->height - 1 - y : y) * (size_t)m->width + x;
        o[i] = hi > lo ? (m->data[src] - lo) / (hi - lo) : 0.5f;
    }
    return o;
}

static float *normalized(const rl_map *m) { return normalized_rows(m, 0); }

/* one face's maps: depth (1 - height), tangent-space normals, a rock albedo */
typedef struct face_maps { float *depth, *normal, *albedo; int w, h; } face_maps;

static int make_face(const float *h01, int w, int h, float depth_world, float width_world, face_maps *f)
{
    size_t n = (size_t)w * (size_t)h, i;
    rl_normal_options no = rl_normal_default_options();
    f->w = w; f->h = h;
    f->depth = (float *)malloc(sizeof(float) * n);
    f->normal = (float *)malloc(sizeof(float) * 3 * n);
    f->albedo = (float *)malloc(sizeof(float) * 3 * n);
    if (!f->depth || !f->normal || !f->albedo) return 0;
    for (i = 0; i < n; i++) {
        float v = h01[i];
        f->depth[i] = 1.0f - v;
        f->albedo[3 * i] = 0.42f + 0.30f * v; f->albedo[3 * i + 1] = 0.38f + 0.26f * v; f->albedo[3 * i + 2] = 0.33f + 0.22f * v;
    }
    no.strength = depth_world * (float)w / width_world;
    return rl_normal_map(h01, w, h, &no, f->normal) == RL_OK;
}

static void free_face(face_maps *f) { free(f->depth); free(f->normal); free(f->albedo); }

/* the rock cube of side 2: the front face (+z) carries the fused map, the others the example */
static sr_result render_cube(sr_framebuffer *fb, const face_maps *front, const face_maps *side, const args *a)
{
    static const float faces[6][9] = { /* origin, axis_u, axis_v: n = u x v points outwards; v runs up */
        {-1, -1, 1, 2, 0, 0, 0, 2, 0},  {1, -1, -1, -2, 0, 0, 0, 2, 0}, {1, -1, 1, 0, 0, -2, 0, 2, 0},
        {-1, -1, -1, 0, 0, 2, 0, 2, 0}, {-1, 1, 1, 2, 0, 0, 0, 0, -2},  {-1, -1, -1, 2, 0, 0, 0, 0, 2}};
    float eye[3] = {2.3f, 1.9f, 4.2f}, at[3] = {0, 0, 0}, clear[4] = {0.16f, 0.17f, 0.20f, 1.0f};
    sr_camera cam;
    sr_light light;
    sr_image dimg, nimg, aimg;
    int k;
    sr_result r = SR_OK;
    sr_camera_look_at(&cam, eye, at, NULL, 36.0f, (float)a->fw / (float)a->fh, 0.1f, 20.0f);
    sr_light_default(&light, a->light);
    sr_framebuffer_clear(fb, clear, 1.0f);
    for (k = 0; k < 6 && r == SR_OK; k++) {
        const face_maps *m = k == 0 ? front : side;
        sr_relief_desc d;
        sr_relief_desc_default(&d);
        memcpy(d.origin, faces[k], 12); memcpy(d.axis_u, faces[k] + 3, 12); memcpy(d.axis_v, faces[k] + 6, 12);
        d.depth_scale = a->depth;
        dimg.width = m->w; dimg.height = m->h; dimg.channels = 1; dimg.data = m->depth; dimg.wrap = 0;
        nimg = dimg; nimg.channels = 3; nimg.data = m->normal;
        aimg = dimg; aimg.channels = 3; aimg.data = m->albedo;
        d.depth = dimg; d.normal_map = &nimg; d.albedo = &aimg;
        d.shadows = a->shadows; d.shadow_search = 1; d.shadow_light = 0.35f;
        d.lights = &light; d.light_count = 1;
        d.material.specular[0] = d.material.specular[1] = d.material.specular[2] = 0.25f;
        d.material.shininess = 25.0f;
        r = sr_draw_relief(fb, &cam, &d);
    }
    return r;
}

/* Paper 003's Fig 6-7: the fused map three times around a cylinder of radius 1 and height 2
   (so that a texel is about as wide as it is high), as 18 relief quads tangent to it, each a
   sixth of the map, with the bend 1/R, which gives the cylinder its silhouette; open ends,
   seen from nearly level. */
static sr_result render_cylinder(sr_framebuffer *fb, const face_maps *m, const args *a)
{
    enum { N = 18, PER_MAP = 6 };
    float eye[3] = {0.0f, 0.45f, 4.6f}, at[3] = {0, 0, 0}, clear[4] = {0.16f, 0.17f, 0.20f, 1.0f};
    float half = 3.14159265f / (float)N, w = 2.0f * tanf(half);
    int sw = m->w / PER_MAP, k, y;
    sr_camera cam;
    sr_light light;
    sr_result r = SR_OK;
    float *strip = (float *)malloc(sizeof(float) * 7 * (size_t)sw * (size_t)m->h);
    if (!strip || sw < 2) { free(strip); return SR_ERR_INVALID_ARGUMENT; }
    sr_camera_look_at(&cam, eye, at, NULL, 34.0f, (float)a->fw / (float)a->fh, 0.1f, 20.0f);
    sr_light_default(&light, a->light);
    sr_framebuffer_clear(fb, clear, 1.0f);
    for (k = 0; k < N && r == SR_OK; k++) {
        float th = ((float)k + 0.5f - (float)PER_MAP / 2.0f) / (float)N * 6.2831853f, c = cosf(th), s = sinf(th); /* map 0 faces +z */
        float *dd = strip, *nn = strip + (size_t)sw * m->h, *aa = nn + 3 * (size_t)sw * m->h;
        sr_image dimg, nimg, aimg;
        sr_relief_desc d;
        for (y = 0; y < m->h; y++) { /* the strip's columns */
            size_t src = (size_t)y * m->w + (size_t)(k % PER_MAP) * sw, dst = (size_t)y * sw;
            memcpy(dd + dst, m->depth + src, sizeof(float) * (size_t)sw);
            memcpy(nn + 3 * dst, m->normal + 3 * src, sizeof(float) * 3 * (size_t)sw);
            memcpy(aa + 3 * dst, m->albedo + 3 * src, sizeof(float) * 3 * (size_t)sw);
        }
        sr_relief_desc_default(&d);
        d.axis_u[0] = w * c; d.axis_u[1] = 0.0f; d.axis_u[2] = -w * s;
        d.axis_v[0] = 0.0f; d.axis_v[1] = 2.0f; d.axis_v[2] = 0.0f;
        d.origin[0] = s - 0.5f * d.axis_u[0]; d.origin[1] = -1.0f; d.origin[2] = c - 0.5f * d.axis_u[2];
        d.depth_scale = a->depth;
        d.curvature_u = 1.0f;
        dimg.width = sw; dimg.height = m->h; dimg.channels = 1; dimg.data = dd; dimg.wrap = 0;
        nimg = dimg; nimg.channels = 3; nimg.data = nn;
        aimg = dimg; aimg.channels = 3; aimg.data = aa;
        d.depth = dimg; d.normal_map = &nimg; d.albedo = &aimg;
        d.shadows = a->shadows; d.shadow_search = 1; d.shadow_light = 0.35f;
        d.lights = &light; d.light_count = 1;
        d.material.specular[0] = d.material.specular[1] = d.material.specular[2] = 0.25f;
        d.material.shininess = 25.0f;
        r = sr_draw_relief(fb, &cam, &d);
    }
    free(strip);
    return r;
}

/* the result of writing path (through its temporary name tmp), with the cause when it failed */
static int written(const char *path, sr_result r, int saved_errno)
{
    if (r != SR_OK) cli_result_error("relief", path, sr_result_string(r), r == SR_ERR_IO ? saved_errno : 0);
    return r == SR_OK;
}

static int write_height(const char *path, const char *tmp, const rl_map *m)
{
    size_t n = (size_t)m->width * (size_t)m->height, i;
    sr_result r;
    errno = 0;
    if (cli_has_extension(path, ".png")) {
        float *h = normalized(m);
        uint16_t *s = (uint16_t *)malloc(sizeof(uint16_t) * n);
        if (!h || !s) { free(h); free(s); fprintf(stderr, "relief: out of memory\n"); return 0; }
        for (i = 0; i < n; i++) s[i] = (uint16_t)(h[i] * 65535.0f + 0.5f);
        r = sr_write_png16(tmp, s, m->width, m->height, 1, 0);
        free(h); free(s);
    } else {
        r = sr_write_pfm(tmp, m->data, m->width, m->height, 1);
    }
    return written(path, r, errno);
}

static uint8_t *grey_rgb(const float *v01, size_t n)
{
    uint8_t *p = (uint8_t *)malloc(3 * n);
    size_t i;
    if (!p) return NULL;
    for (i = 0; i < n; i++) { float x = v01[i] < 0 ? 0 : v01[i] > 1 ? 1 : v01[i]; p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = (uint8_t)(x * 255.0f + 0.5f); }
    return p;
}

static int write_sheet(const char *path, const char *tmp, const rl_map *ex, const rl_map *sk, const rl_map *fused, const face_maps *front, sr_framebuffer *fb)
{
    sr_image8 im[5], sheet;
    static const char *caps[5] = {"example", "sketch", "fused height", "normal map", "relief mapped"};
    float *e = normalized(ex), *f = normalized(fused);
    size_t nf = (size_t)fused->width * (size_t)fused->height;
    int k, ok, saved = 0;
    sr_result r = SR_ERR_OUT_OF_MEMORY;
    im[0].width = ex->width; im[0].height = ex->height; im[0].channels = 3; im[0].pixels = e ? grey_rgb(e, (size_t)ex->width * (size_t)ex->height) : NULL;
    im[1].width = sk->width; im[1].height = sk->height; im[1].channels = 3; im[1].pixels = grey_rgb(sk->data, (size_t)sk->width * (size_t)sk->height);
    im[2].width = fused->width; im[2].height = fused->height; im[2].channels = 3; im[2].pixels = f ? grey_rgb(f, nf) : NULL;
    im[3] = im[2]; im[3].pixels = (uint8_t *)malloc(3 * nf);
    if (im[3].pixels) { /* the face's rows run up: back to picture order */
        int y;
        for (y = 0; y < fused->height; y++)
            rl_normal_to_rgb8(front->normal + 3 * (size_t)(fused->height - 1 - y) * (size_t)fused->width, (size_t)fused->width,
                              im[3].pixels + 3 * (size_t)y * (size_t)fused->width);
    }
    im[4].width = fb->width; im[4].height = fb->height; im[4].channels = 3; im[4].pixels = (uint8_t *)malloc((size_t)fb->width * (size_t)fb->height * 3);
    if (im[4].pixels) sr_framebuffer_to_rgb8(fb, im[4].pixels, 3);
    ok = im[0].pixels && im[1].pixels && im[2].pixels && im[3].pixels && im[4].pixels &&
         (r = sr_contact_sheet(im, caps, 5, 0, NULL, &sheet)) == SR_OK;
    if (ok) {
        errno = 0;
        r = sr_write_png(tmp, sheet.pixels, sheet.width, sheet.height, 3, 0);
        saved = errno;
        sr_free(NULL, sheet.pixels);
    }
    for (k = 0; k < 5; k++) free(im[k].pixels);
    free(e); free(f);
    return written(path, r, saved);
}

int main(int argc, char **argv)
{
    args a;
    rl_map ex = {0, 0, NULL}, sk = {0, 0, NULL}, fused = {0, 0, NULL};
    rl_synth_options o = rl_synth_default_options();
    face_maps front, side;
    sr_framebuffer fb;
    float *h01 = NULL, *e01 = NULL;
    double t0, t_synth, t_normal, t_render;
    rl_result r;
    int status = parse_args(argc, argv, &a), last_pct = -10;
    cli_outputs outs;
    const char *tmp;
    if (status >= 0) return status;
    status = 1;
    cli_outputs_init(&outs);
    memset(&front, 0, sizeof front); memset(&side, 0, sizeof side);
    if (!load_map(a.example, a.crop, &ex) || !load_sketch(&a, &sk)) goto done;
    o.patch = a.patch;
    if (a.emphasis != 0.0f) o.emphasis = a.emphasis;
    o.progress = progress;
    o.progress_user = &last_pct;
    t0 = now_ms();
    r = a.emboss ? rl_emboss(&ex, &sk, &o, &fused) : rl_synthesize(&ex, &sk, &o, &fused);
    t_synth = now_ms() - t0;
    if (!a.emboss) fprintf(stderr, "\rrelief: synthesis done  \n");
    if (r != RL_OK) { cli_result_error("relief", a.emboss ? "emboss" : "synthesis", rl_result_string(r), 0); goto done; }
    h01 = normalized_rows(&fused, 1);
    e01 = normalized_rows(&ex, 1);
    t0 = now_ms();
    if (!h01 || !e01 || !make_face(h01, fused.width, fused.height, a.depth, a.cylinder ? 6.2831853f / 3.0f : 2.0f, &front)) goto done;
    t_normal = now_ms() - t0;
    if (!make_face(e01, ex.width, ex.height, a.depth, 2.0f, &side)) goto done;
    if (sr_framebuffer_create(&fb, a.fw, a.fh, NULL) != SR_OK) goto done;
    t0 = now_ms();
    if ((a.cylinder ? render_cylinder(&fb, &front, &a) : render_cube(&fb, &front, &side, &a)) != SR_OK) { sr_framebuffer_free(&fb); goto done; }
    t_render = now_ms() - t0;
    status = 0;
    if (!(tmp = cli_output_add(&outs, "relief", a.out))) status = 1;
    else {
        sr_result wr;
        errno = 0;
        wr = sr_write_framebuffer_png(&fb, tmp, 0);
        if (!written(a.out, wr, errno)) status = 1;
    }
    if (!status && a.height_out && (!(tmp = cli_output_add(&outs, "relief", a.height_out)) || !write_height(a.height_out, tmp, &fused)))
        status = 1;
    if (!status && a.normal_out) {
        size_t n = (size_t)fused.width * (size_t)fused.height;
        uint8_t *rgb = (uint8_t *)malloc(3 * n);
        if (!rgb || !(tmp = cli_output_add(&outs, "relief", a.normal_out))) status = 1;
        else { /* the face's rows run up, the PNG's down */
            sr_result wr;
            rl_normal_to_rgb8(front.normal, n, rgb);
            errno = 0;
            wr = sr_write_png(tmp, rgb, fused.width, fused.height, 3, 1);
            if (!written(a.normal_out, wr, errno)) status = 1;
        }
        free(rgb);
    }
    if (!status && a.sheet_out &&
        (!(tmp = cli_output_add(&outs, "relief", a.sheet_out)) || !write_sheet(a.sheet_out, tmp, &ex, &sk, &fused, &front, &fb)))
        status = 1;
    sr_framebuffer_free(&fb);
    if (status || !cli_outputs_commit(&outs, "relief")) { status = 1; goto done; }
    printf("RESULT relief example=%dx%d out=%dx%d mode=%s synth_ms=%.1f normal_ms=%.2f render_ms=%.1f frame=%dx%d\n", ex.width, ex.height,
           fused.width, fused.height, a.emboss ? "emboss" : "synth", t_synth, t_normal, t_render, a.fw, a.fh);
    fprintf(stderr, "relief: wrote %s\n", a.out);
done:
    cli_outputs_discard(&outs); /* after a failure: no file of this run is left */
    free(ex.data); free(sk.data); rl_map_free(&fused, NULL); free(h01); free(e01);
    free_face(&front); free_face(&side);
    return status;
}
