/* terrain - paper 001's terrain scenes (Luo & Wang: four-point scheme, epsilon split, Gaussian
   normal perturbation, fixed-function GL lighting) rendered with render.h to a PNG.

     terrain --preset desert|vegetation|mountain5|mountain6 -o OUT.png [options]  (terrain --help)

   The lighting is the GL fixed-function model (sr_shade_blinn): one directional light, a
   light-model ambient, and a material per scene; the values are paper note 001's recommendations
   (section 7.3; the paper gives none). Each small quad carries its own perturbed normal (the
   paper's "geometric texture"). --shading smooth (the default) gives every vertex the mean of its
   quads' perturbed normals and lights each pixel with the interpolated normal (Phong), so the
   noise reads as a continuous rough surface; --shading flat draws each quad in one colour with its
   own normal, as the paper's polygons are drawn (at large sizes the quads show as blocks).
   Outputs are written to NAME.tmp and renamed when complete: a failed run leaves no file and an
   existing output unchanged. Exit status: 0 done, 1 failure, 2 usage (bad arguments). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#define SR_IMPLEMENTATION
#include "render.h"
#define CLI_IMPLEMENTATION
#define CLI_STATIC
#include "cli.h"

#define TERRAIN_VERSION "terrain 0.2 (subdiv4.h, render.h)"

typedef struct scene_look {
    const char *name;
    float diffuse[3], ambient[3], specular[3], shininess;
    float light_dir[3], light_color[3], model_ambient[3];
} scene_look;

static const scene_look looks[4] = {
    {"desert", {0.90f, 0.72f, 0.45f}, {0.35f, 0.28f, 0.18f}, {0.10f, 0.10f, 0.08f}, 8.0f,
     {1.0f, 0.4f, 0.45f}, {1.0f, 0.95f, 0.85f}, {0.20f, 0.18f, 0.15f}},
    {"vegetation", {0.25f, 0.55f, 0.18f}, {0.08f, 0.20f, 0.06f}, {0.02f, 0.02f, 0.02f}, 2.0f,
     {0.6f, 0.5f, 0.7f}, {1.0f, 1.0f, 0.95f}, {0.15f, 0.18f, 0.15f}},
    {"mountain5", {0.58f, 0.44f, 0.32f}, {0.20f, 0.15f, 0.11f}, {0.15f, 0.15f, 0.15f}, 16.0f,
     {0.7f, 0.3f, 0.6f}, {1.0f, 0.97f, 0.9f}, {0.18f, 0.18f, 0.20f}},
    {"mountain6", {0.50f, 0.50f, 0.53f}, {0.18f, 0.18f, 0.20f}, {0.20f, 0.20f, 0.22f}, 24.0f,
     {0.5f, 0.4f, 0.75f}, {1.0f, 1.0f, 1.0f}, {0.20f, 0.20f, 0.22f}}};

typedef struct args {
    const char *preset, *out, *obj, *heights;
    int W, H, half, cubic, flat;
    int have_seed, have_levels, have_omega, have_eps, have_sigma;
    long seed, levels, max_triangles;
    double omega, eps, sigma;
} args;

static void usage(FILE *to)
{
    fprintf(to,
            "usage: terrain --preset NAME -o OUT.png [options]\n"
            "Builds paper 001's terrain (four-point subdivision, epsilon split, Gaussian normal noise)\n"
            "and renders it to a PNG.\n"
            "  --preset NAME        desert, vegetation, mountain5 or mountain6: the paper's Figs 3-6\n"
            "                       (w 0.10, 0.18, 0.20, 0.25; epsilon 2, 3, 3, 3) (required)\n"
            "  -o, --output FILE    the PNG to write; the name must end in .png, any case (required)\n"
            "  --size W[xH]         image size in pixels, 1..16384 (default: 1024x768; W alone: square)\n"
            "  --seed N             random control heights and normal noise, 0..2^31-1 (default: 1999)\n"
            "  --levels K           four-point levels, 0..10 (default: the preset's, 4)\n"
            "  --omega W            the shape parameter w, -2..2 (default: the preset's)\n"
            "  --omega-half         read w as the paper's OCR'd equation (1) does: (1/2 + w/2), -w/2\n"
            "                       (default: off, the standard four-point weights)\n"
            "  --eps E              longest edge of a small quad, 0 = no split, 0..1e6 (default: the\n"
            "                       preset's, 2 or 3)\n"
            "  --sigma S            normal perturbation, 0..10 (default: the preset's)\n"
            "  --cubic              cubic end rule at the grid border (default: off, the linear rule)\n"
            "  --max-triangles N    refuse a terrain of more triangles, 1..2^31-1 (default: 16777216;\n"
            "                       the largest preset makes 1.5 M)\n"
            "  --shading S          smooth (default: the quads' perturbed normals averaged at the\n"
            "                       vertices, lit per pixel) or flat (one colour per quad, as the\n"
            "                       paper draws its polygons)\n"
            "  --obj FILE           also write the triangle mesh (positions only) as OBJ (default: none)\n"
            "  --heights FILE       also write the four-point height grid (before the epsilon split)\n"
            "                       as a 1-channel PFM, heights over the terrain's width (default: none)\n"
            "  -h, --help           show this help and exit\n"
            "  --version            show the version and exit\n"
            "Exit status: 0 done, 1 failure (the terrain cannot be built, a write failed), 2 usage.\n"
            "Outputs are written to FILE.tmp and renamed when complete: a failed run leaves nothing.\n");
}

static const char *option_value(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) return NULL;
    return argv[++*i];
}

/* Returns -1 to go on, or the exit status (0 for --help/--version, 2 for a usage error). */
static int parse_args(int argc, char **argv, args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    a->W = 1024; a->H = 768;
    a->max_triangles = 1L << 24;
    for (i = 1; i < argc; i++) {
        const char *s = argv[i], *v;
        if (strcmp(s, "-h") == 0 || strcmp(s, "--help") == 0) { usage(stdout); return 0; }
        if (strcmp(s, "--version") == 0) { printf("%s\n", TERRAIN_VERSION); return 0; }
        if (strcmp(s, "--omega-half") == 0) { a->half = 1; continue; }
        if (strcmp(s, "--cubic") == 0) { a->cubic = 1; continue; }
        if (strcmp(s, "-o") == 0 || strcmp(s, "--output") == 0 || strcmp(s, "--preset") == 0 || strcmp(s, "--obj") == 0 || strcmp(s, "--heights") == 0 ||
            strcmp(s, "--size") == 0 || strcmp(s, "--seed") == 0 || strcmp(s, "--levels") == 0 || strcmp(s, "--omega") == 0 ||
            strcmp(s, "--eps") == 0 || strcmp(s, "--sigma") == 0 || strcmp(s, "--max-triangles") == 0 ||
            strcmp(s, "--shading") == 0) {
            v = option_value(argc, argv, &i);
            if (!v) return cli_usage_error("terrain", "%s needs a value", s);
        } else if (s[0] == '-' && s[1] != '\0') {
            return cli_usage_error("terrain", "unknown option '%s'", s);
        } else {
            return cli_usage_error("terrain", "unexpected argument '%s': every value follows its option", s);
        }
        if (strcmp(s, "-o") == 0 || strcmp(s, "--output") == 0) {
            if (!cli_has_extension(v, ".png")) return cli_usage_error("terrain", "%s '%s': the name must end in .png (any case)", s, v);
            a->out = v;
        } else if (strcmp(s, "--heights") == 0) {
            if (!cli_has_extension(v, ".pfm")) return cli_usage_error("terrain", "--heights '%s': the name must end in .pfm (any case)", v);
            a->heights = v;
        } else if (strcmp(s, "--obj") == 0) {
            if (!cli_has_extension(v, ".obj")) return cli_usage_error("terrain", "--obj '%s': the name must end in .obj (any case)", v);
            a->obj = v;
        } else if (strcmp(s, "--preset") == 0) {
            int k, found = 0;
            for (k = 0; k < 4; k++) found |= strcmp(v, looks[k].name) == 0;
            if (!found) return cli_usage_error("terrain", "--preset '%s': not desert, vegetation, mountain5 or mountain6", v);
            a->preset = v;
        } else if (strcmp(s, "--size") == 0) {
            if (!cli_parse_size(v, 1, 16384, 1, &a->W, &a->H)) return cli_usage_error("terrain", "--size '%s': not W or WxH with 1 <= W, H <= 16384", v);
        } else if (strcmp(s, "--seed") == 0) {
            if (!cli_parse_long(v, 0, 2147483647L, &a->seed)) return cli_usage_error("terrain", "--seed '%s': not an integer in 0..2147483647", v);
            a->have_seed = 1;
        } else if (strcmp(s, "--levels") == 0) {
            if (!cli_parse_long(v, 0, 10, &a->levels)) return cli_usage_error("terrain", "--levels '%s': not an integer in 0..10", v);
            a->have_levels = 1;
        } else if (strcmp(s, "--max-triangles") == 0) {
            if (!cli_parse_long(v, 1, 2147483647L, &a->max_triangles))
                return cli_usage_error("terrain", "--max-triangles '%s': not an integer in 1..2147483647", v);
        } else if (strcmp(s, "--omega") == 0) {
            if (!cli_parse_double(v, -2.0, 2.0, &a->omega)) return cli_usage_error("terrain", "--omega '%s': not a number in -2..2", v);
            a->have_omega = 1;
        } else if (strcmp(s, "--eps") == 0) {
            if (!cli_parse_double(v, 0.0, 1e6, &a->eps)) return cli_usage_error("terrain", "--eps '%s': not a number in 0..1e6", v);
            a->have_eps = 1;
        } else if (strcmp(s, "--sigma") == 0) {
            if (!cli_parse_double(v, 0.0, 10.0, &a->sigma)) return cli_usage_error("terrain", "--sigma '%s': not a number in 0..10", v);
            a->have_sigma = 1;
        } else { /* --shading */
            if (strcmp(v, "smooth") == 0) a->flat = 0;
            else if (strcmp(v, "flat") == 0) a->flat = 1;
            else return cli_usage_error("terrain", "--shading '%s': not smooth or flat", v);
        }
    }
    if (!a->preset) return cli_usage_error("terrain", "%s", "no --preset given");
    if (!a->out) return cli_usage_error("terrain", "%s", "no -o OUT.png given");
    return -1;
}

/* The mesh as OBJ text; 0 with errno set when a write fails. */
static int write_obj(const char *path, const sd4_mesh *m)
{
    FILE *f = fopen(path, "w");
    size_t i;
    int ok = 1, e = 0;
    if (!f) return 0;
    for (i = 0; ok && i < m->vertex_count; i++)
        ok = fprintf(f, "v %.9g %.9g %.9g\n", m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]) > 0;
    for (i = 0; ok && i < m->triangle_count; i++)
        ok = fprintf(f, "f %u %u %u\n", m->indices[3 * i] + 1, m->indices[3 * i + 1] + 1, m->indices[3 * i + 2] + 1) > 0;
    if (!ok || ferror(f)) e = errno ? errno : EIO;
    if (fclose(f) != 0 && !e) e = errno ? errno : EIO;
    errno = e;
    return e == 0;
}

/* Vertex normals for smooth shading: the mean of the perturbed normals of the triangles around
   each vertex (every quad's two triangles carry its normal), unit. */
static float *vertex_normals(const sd4_mesh *m)
{
    float *n = (float *)calloc(3 * m->vertex_count + 1, sizeof(float));
    size_t t, v;
    int k, j;
    if (!n) return NULL;
    for (t = 0; t < m->triangle_count; t++)
        for (k = 0; k < 3; k++)
            for (j = 0; j < 3; j++) n[3 * (size_t)m->indices[3 * t + (size_t)k] + (size_t)j] += m->face_normals[3 * t + (size_t)j];
    for (v = 0; v < m->vertex_count; v++) {
        float *p = n + 3 * v, l = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        if (l > 0.0f) { p[0] /= l; p[1] /= l; p[2] /= l; }
        else { p[0] = 0.0f; p[1] = 1.0f; p[2] = 0.0f; }
    }
    return n;
}

/* Flat shading: every triangle gets its own three vertices carrying its quad's perturbed normal
   (Gouraud over equal normals: one colour per polygon). */
static int unshare(const sd4_mesh *m, float **pos, float **nrm, uint32_t **idx)
{
    size_t t, k;
    *pos = (float *)malloc(m->triangle_count * 9 * sizeof(float) + 1);
    *nrm = (float *)malloc(m->triangle_count * 9 * sizeof(float) + 1);
    *idx = (uint32_t *)malloc(m->triangle_count * 3 * sizeof(uint32_t) + 1);
    if (!*pos || !*nrm || !*idx) return 0;
    for (t = 0; t < m->triangle_count; t++)
        for (k = 0; k < 3; k++) {
            memcpy(*pos + 9 * t + 3 * k, m->positions + 3 * (size_t)m->indices[3 * t + k], 3 * sizeof(float));
            memcpy(*nrm + 9 * t + 3 * k, m->face_normals + 3 * t, 3 * sizeof(float));
            (*idx)[3 * t + k] = (uint32_t)(3 * t + k);
        }
    return 1;
}

/* 32 degrees above the terrain, looking at its centre from the -z, +x side */
static void frame_camera(const sd4_mesh *m, int W, int H, sr_camera *cam)
{
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f}, c[3], eye[3], extent;
    float el = 32.0f * 0.0174533f, az = 35.0f * 0.0174533f, dist;
    size_t t;
    int k;
    for (t = 0; t < m->vertex_count; t++)
        for (k = 0; k < 3; k++) {
            if (m->positions[3 * t + (size_t)k] < lo[k]) lo[k] = m->positions[3 * t + (size_t)k];
            if (m->positions[3 * t + (size_t)k] > hi[k]) hi[k] = m->positions[3 * t + (size_t)k];
        }
    for (k = 0; k < 3; k++) c[k] = 0.5f * (lo[k] + hi[k]);
    c[1] = lo[1] + 0.25f * (hi[1] - lo[1]);
    extent = hi[0] - lo[0] > hi[2] - lo[2] ? hi[0] - lo[0] : hi[2] - lo[2];
    dist = 1.45f * extent;
    eye[0] = c[0] + dist * cosf(el) * sinf(az);
    eye[1] = c[1] + dist * sinf(el);
    eye[2] = c[2] - dist * cosf(el) * cosf(az);
    sr_camera_look_at(cam, eye, c, NULL, 45.0f, (float)W / (float)H, 0.01f * dist, 4.0f * dist);
}

/* The paper's light direction is given in the note as (x, y, z) with z up; here y is up. */
static void scene_light(const scene_look *look, sr_light *light)
{
    int k;
    memset(light, 0, sizeof *light);
    light->type = SR_LIGHT_DIRECTIONAL;
    light->vector[0] = look->light_dir[0]; light->vector[1] = look->light_dir[2]; light->vector[2] = look->light_dir[1];
    for (k = 0; k < 3; k++) {
        light->diffuse[k] = look->light_color[k];
        light->specular[k] = look->light_color[k];
        light->ambient[k] = look->model_ambient[k]; /* GL_LIGHT_MODEL_AMBIENT; LIGHT0's own ambient is 0 */
    }
}

/* The four-point grid of heights (sd4_terrain_build's steps 1 and 2) over the terrain's width, as PFM. */
static int write_heights(const char *path, const sd4_terrain_desc *d)
{
    size_t nx = d->nx ? d->nx : 9, ny = d->ny ? d->ny : 9, NX, NY, i;
    double *control = NULL, *fine = NULL, width;
    float *h = NULL;
    sd4_options o;
    int ok = 0;
    memset(&o, 0, sizeof o);
    o.end_rule = o.end_rule_y = d->border;
    o.omega_convention = d->omega_convention;
    if (sd4_grid_size(nx, ny, d->levels, &o, &NX, &NY) != SD4_OK) return 0;
    control = (double *)malloc(nx * ny * sizeof(double));
    fine = (double *)malloc(NX * NY * sizeof(double));
    h = (float *)malloc(NX * NY * sizeof(float));
    width = (double)((NX > NY ? NX : NY) - 1) * (d->spacing != 0.0 ? d->spacing : 64.0) / (double)((size_t)1 << d->levels);
    if (control && fine && h &&
        (d->heights ? (memcpy(control, d->heights, nx * ny * sizeof(double)), SD4_OK)
                    : sd4_random_heights(nx, ny, d->amplitude != 0.0 ? d->amplitude : 60.0, d->smooth_passes, d->seed, NULL, control)) == SD4_OK &&
        sd4_grid_refine(control, nx, ny, 1, d->omega, d->levels, &o, fine, NX * NY) == SD4_OK) {
        for (i = 0; i < NX * NY; i++) h[i] = (float)(fine[i] / width);
        ok = sr_write_pfm(path, h, (int)NX, (int)NY, 1) == SR_OK;
    }
    free(control); free(fine); free(h);
    return ok;
}

/* Renders the mesh into png_tmp. 0 done, 1 failure (reported). */
static int render(const args *a, const scene_look *look, const sd4_mesh *m, const char *png_tmp)
{
    float sky[4] = {0.55f, 0.70f, 0.90f, 1.0f}, *pos = NULL, *nrm = NULL;
    uint32_t *idx = NULL;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc dd;
    sr_light light;
    sr_result rr;
    int status = 1, e;
    if (a->flat ? !unshare(m, &pos, &nrm, &idx) : (nrm = vertex_normals(m)) == NULL) {
        fprintf(stderr, "terrain: out of memory for the %lu-triangle mesh's normals\n", (unsigned long)m->triangle_count);
        goto done;
    }
    frame_camera(m, a->W, a->H, &cam);
    scene_light(look, &light);
    if ((rr = sr_framebuffer_create(&fb, a->W, a->H, NULL)) != SR_OK) {
        cli_result_error("terrain", "the framebuffer", sr_result_string(rr), 0);
        goto done;
    }
    sr_framebuffer_clear(&fb, sky, 1.0f);
    sr_draw_desc_default(&dd);
    if (a->flat) {
        dd.positions = pos; dd.vertex_count = 3 * m->triangle_count; dd.indices = idx;
        dd.shading = SR_SHADE_GOURAUD; /* equal normals at the three corners: one colour per polygon */
    } else {
        dd.positions = m->positions; dd.vertex_count = m->vertex_count; dd.indices = m->indices;
        dd.shading = SR_SHADE_PHONG;
    }
    dd.triangle_count = m->triangle_count;
    dd.normals = nrm;
    dd.lights = &light;
    dd.light_count = 1;
    memcpy(dd.material.diffuse, look->diffuse, sizeof look->diffuse);
    memcpy(dd.material.ambient, look->ambient, sizeof look->ambient);
    memcpy(dd.material.specular, look->specular, sizeof look->specular);
    memset(dd.material.emission, 0, sizeof dd.material.emission);
    dd.material.shininess = look->shininess;
    if ((rr = sr_draw_mesh(&fb, &cam, &dd)) != SR_OK) {
        cli_result_error("terrain", "drawing the terrain", sr_result_string(rr), 0);
    } else {
        errno = 0;
        rr = sr_write_framebuffer_png(&fb, png_tmp, 0);
        e = errno;
        if (rr != SR_OK) cli_result_error("terrain", a->out, sr_result_string(rr), rr == SR_ERR_IO ? e : 0);
        else status = 0;
    }
    sr_framebuffer_free(&fb);
done:
    free(pos);
    free(nrm);
    free(idx);
    return status;
}

int main(int argc, char **argv)
{
    args a;
    const scene_look *look = NULL;
    sd4_terrain_desc d;
    sd4_mesh m;
    sd4_result r;
    cli_outputs outs;
    const char *png_tmp, *obj_tmp = NULL, *heights_tmp = NULL;
    int i, status = parse_args(argc, argv, &a);
    if (status >= 0) return status;
    for (i = 0; i < 4; i++)
        if (strcmp(a.preset, looks[i].name) == 0) look = &looks[i];
    if (!look || sd4_terrain_preset(a.preset, &d) != SD4_OK) return cli_usage_error("terrain", "--preset '%s': unknown", a.preset);
    if (a.have_seed) d.seed = (uint64_t)a.seed;
    if (a.have_levels) d.levels = (int)a.levels;
    if (a.have_omega) d.omega = a.omega;
    if (a.have_eps) d.epsilon = a.eps;
    if (a.have_sigma) d.sigma = a.sigma;
    if (a.half) d.omega_convention = SD4_OMEGA_HALF;
    if (a.cubic) d.border = SD4_END_CUBIC;
    d.max_triangles = (size_t)a.max_triangles;
    if ((r = sd4_terrain_build(&d, &m)) != SD4_OK) {
        cli_result_error("terrain", "building the terrain", sd4_result_string(r), 0);
        if (r == SD4_ERR_TOO_LARGE)
            fprintf(stderr, "terrain: the mesh would have more than --max-triangles %ld triangles: a divergent --omega, or --eps too small\n",
                    a.max_triangles);
        if (r == SD4_ERR_NOT_FINITE) fprintf(stderr, "terrain: the heights overflow: --omega too large\n");
        return 1;
    }
    cli_outputs_init(&outs);
    png_tmp = cli_output_add(&outs, "terrain", a.out);
    if (a.obj) obj_tmp = cli_output_add(&outs, "terrain", a.obj);
    if (a.heights) heights_tmp = cli_output_add(&outs, "terrain", a.heights);
    if (!png_tmp || (a.obj && !obj_tmp) || (a.heights && !heights_tmp)) status = 1;
    else if (a.heights && (errno = 0, !write_heights(heights_tmp, &d))) {
        cli_file_error("terrain", a.heights, "cannot write", errno);
        status = 1;
    }
    else if (a.obj && (errno = 0, !write_obj(obj_tmp, &m))) {
        cli_file_error("terrain", a.obj, "cannot write", errno);
        status = 1;
    } else {
        status = render(&a, look, &m, png_tmp);
    }
    if (status == 0 && !cli_outputs_commit(&outs, "terrain")) status = 1;
    if (status != 0) cli_outputs_discard(&outs);
    else
        fprintf(stderr, "terrain: %s (w %.2f%s, %d levels, epsilon %g, sigma %g, %s): %lu vertices, %lu triangles -> %s (%dx%d)\n",
                a.preset, d.omega, a.half ? " halved" : "", d.levels, d.epsilon, d.sigma, a.flat ? "flat" : "smooth",
                (unsigned long)m.vertex_count, (unsigned long)m.triangle_count, a.out, a.W, a.H);
    sd4_free_mesh(&m);
    return status;
}
