/* terrain - paper 001's terrain scenes (Luo & Wang: four-point scheme, epsilon split, Gaussian
   normal perturbation, fixed-function GL lighting) rendered with render.h to a PNG.

   usage: terrain --preset desert|vegetation|mountain5|mountain6 -o OUT.png
                  [--size W[xH]] [--seed N] [--levels K] [--omega W] [--omega-half] [--eps E]
                  [--sigma S] [--cubic] [--obj OUT.obj]
     --preset     the paper's Figs 3-6 (w 0.10, 0.18, 0.20, 0.25; epsilon 2, 3, 3, 3)
     --omega-half read w as the paper's OCR'd equation (1) does: (1/2 + w/2), -w/2
     --cubic      cubic end rule instead of the linear one at the grid border
     --obj        also write the triangle mesh (positions only) as OBJ
   The lighting is the GL fixed-function model (sr_shade_blinn): one directional light, a
   light-model ambient, and a material per scene; each small quad is shaded with its own
   perturbed normal (flat, as the paper draws its polygons). The values are paper note 001's
   recommendations (section 7.3); the paper gives none.
   Exit status 0 on success, 1 on bad arguments, 2 on failure. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#define SR_IMPLEMENTATION
#include "render.h"

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

static void usage(FILE *to)
{
    fprintf(to, "usage: terrain --preset desert|vegetation|mountain5|mountain6 -o OUT.png [--size W[xH]] [--seed N]\n"
                "               [--levels K] [--omega W] [--omega-half] [--eps E] [--sigma S] [--cubic] [--obj OUT.obj]\n");
}

/* The paper's light direction is given in the note as (x, y, z) with z up; here y is up. */
static void light_toward(const float d[3], float out[3]) { out[0] = d[0]; out[1] = d[2]; out[2] = d[1]; }

static int write_obj(const char *path, const sd4_mesh *m)
{
    FILE *f = fopen(path, "w");
    size_t i;
    if (!f) return 0;
    for (i = 0; i < m->vertex_count; i++)
        fprintf(f, "v %.9g %.9g %.9g\n", m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
    for (i = 0; i < m->triangle_count; i++)
        fprintf(f, "f %u %u %u\n", m->indices[3 * i] + 1, m->indices[3 * i + 1] + 1, m->indices[3 * i + 2] + 1);
    return fclose(f) == 0;
}

int main(int argc, char **argv)
{
    const char *preset = NULL, *out = NULL, *obj = NULL;
    const scene_look *look = NULL;
    sd4_terrain_desc d;
    sd4_mesh m;
    sd4_result r;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc dd;
    sr_light light;
    float *pos = NULL, *nrm = NULL, lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f}, c[3], eye[3];
    float sky[4] = {0.55f, 0.70f, 0.90f, 1.0f}, extent;
    uint32_t *idx = NULL;
    int W = 1024, H = 768, i, half = 0, cubic = 0, status = 0;
    long seed = -1, levels = -1;
    double omega = NAN, eps = NAN, sigma = NAN;
    size_t t, k;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) out = argv[++i];
        else if (strcmp(argv[i], "--preset") == 0 && i + 1 < argc) preset = argv[++i];
        else if (strcmp(argv[i], "--obj") == 0 && i + 1 < argc) obj = argv[++i];
        else if (strcmp(argv[i], "--seed") == 0 && i + 1 < argc) seed = strtol(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--levels") == 0 && i + 1 < argc) levels = strtol(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--omega") == 0 && i + 1 < argc) omega = strtod(argv[++i], NULL);
        else if (strcmp(argv[i], "--eps") == 0 && i + 1 < argc) eps = strtod(argv[++i], NULL);
        else if (strcmp(argv[i], "--sigma") == 0 && i + 1 < argc) sigma = strtod(argv[++i], NULL);
        else if (strcmp(argv[i], "--omega-half") == 0) half = 1;
        else if (strcmp(argv[i], "--cubic") == 0) cubic = 1;
        else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc) {
            int n = sscanf(argv[++i], "%dx%d", &W, &H);
            if (n == 1) H = W;
            if (n < 1 || W < 1 || H < 1 || W > 16384 || H > 16384) { fprintf(stderr, "terrain: bad --size\n"); return 1; }
        } else if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) { usage(stdout); return 0; }
        else { usage(stderr); return 1; }
    }
    if (!preset || !out) { usage(stderr); return 1; }
    for (i = 0; i < 4; i++)
        if (strcmp(preset, looks[i].name) == 0) look = &looks[i];
    if (!look || sd4_terrain_preset(preset, &d) != SD4_OK) { fprintf(stderr, "terrain: unknown preset %s\n", preset); return 1; }
    if (seed >= 0) d.seed = (uint64_t)seed;
    if (levels >= 0) d.levels = (int)levels;
    if (!isnan(omega)) d.omega = omega;
    if (!isnan(eps)) d.epsilon = eps;
    if (!isnan(sigma)) d.sigma = sigma;
    if (half) d.omega_convention = SD4_OMEGA_HALF;
    if (cubic) d.border = SD4_END_CUBIC;
    if ((r = sd4_terrain_build(&d, &m)) != SD4_OK) {
        fprintf(stderr, "terrain: %s%s\n", sd4_result_string(r),
                r == SD4_ERR_TOO_LARGE ? " (the mesh would have more than 2^24 triangles: a divergent --omega, or --eps too small)"
                : r == SD4_ERR_NOT_FINITE ? " (the heights overflow: --omega too large)" : "");
        return 2;
    }
    if (obj && !write_obj(obj, &m)) { fprintf(stderr, "terrain: cannot write %s\n", obj); status = 2; }
    /* every triangle gets its own three vertices carrying its quad's perturbed normal */
    pos = (float *)malloc(m.triangle_count * 9 * sizeof(float) + 1);
    nrm = (float *)malloc(m.triangle_count * 9 * sizeof(float) + 1);
    idx = (uint32_t *)malloc(m.triangle_count * 3 * sizeof(uint32_t) + 1);
    if (!pos || !nrm || !idx) { fprintf(stderr, "terrain: out of memory\n"); status = 2; goto done; }
    for (t = 0; t < m.triangle_count; t++)
        for (k = 0; k < 3; k++) {
            memcpy(pos + 9 * t + 3 * k, m.positions + 3 * (size_t)m.indices[3 * t + k], 3 * sizeof(float));
            memcpy(nrm + 9 * t + 3 * k, m.face_normals + 3 * t, 3 * sizeof(float));
            idx[3 * t + k] = (uint32_t)(3 * t + k);
        }
    for (t = 0; t < m.vertex_count; t++)
        for (k = 0; k < 3; k++) {
            if (m.positions[3 * t + k] < lo[k]) lo[k] = m.positions[3 * t + k];
            if (m.positions[3 * t + k] > hi[k]) hi[k] = m.positions[3 * t + k];
        }
    for (k = 0; k < 3; k++) c[k] = 0.5f * (lo[k] + hi[k]);
    c[1] = lo[1] + 0.25f * (hi[1] - lo[1]);
    extent = hi[0] - lo[0] > hi[2] - lo[2] ? hi[0] - lo[0] : hi[2] - lo[2];
    {
        /* 32 degrees above the terrain, looking at its centre from the -z, +x side */
        float el = 32.0f * 0.0174533f, az = 35.0f * 0.0174533f, dist = 1.45f * extent;
        eye[0] = c[0] + dist * cosf(el) * sinf(az);
        eye[1] = c[1] + dist * sinf(el);
        eye[2] = c[2] - dist * cosf(el) * cosf(az);
        sr_camera_look_at(&cam, eye, c, NULL, 45.0f, (float)W / (float)H, 0.01f * dist, 4.0f * dist);
    }
    memset(&light, 0, sizeof light);
    light.type = SR_LIGHT_DIRECTIONAL;
    light_toward(look->light_dir, light.vector);
    for (k = 0; k < 3; k++) {
        light.diffuse[k] = look->light_color[k];
        light.specular[k] = look->light_color[k];
        light.ambient[k] = look->model_ambient[k]; /* GL_LIGHT_MODEL_AMBIENT; LIGHT0's own ambient is 0 */
    }
    if ((r = (sd4_result)0, sr_framebuffer_create(&fb, W, H, NULL)) != SR_OK) { fprintf(stderr, "terrain: framebuffer\n"); status = 2; goto done; }
    sr_framebuffer_clear(&fb, sky, 1.0f);
    sr_draw_desc_default(&dd);
    dd.positions = pos;
    dd.vertex_count = 3 * m.triangle_count;
    dd.indices = idx;
    dd.triangle_count = m.triangle_count;
    dd.normals = nrm;
    dd.shading = SR_SHADE_GOURAUD; /* equal normals at the three corners: one colour per polygon */
    dd.lights = &light;
    dd.light_count = 1;
    memcpy(dd.material.diffuse, look->diffuse, sizeof look->diffuse);
    memcpy(dd.material.ambient, look->ambient, sizeof look->ambient);
    memcpy(dd.material.specular, look->specular, sizeof look->specular);
    memset(dd.material.emission, 0, sizeof dd.material.emission);
    dd.material.shininess = look->shininess;
    {
        sr_result rr = sr_draw_mesh(&fb, &cam, &dd);
        if (rr == SR_OK) rr = sr_write_framebuffer_png(&fb, out, 0);
        if (rr != SR_OK) { fprintf(stderr, "terrain: %s: %s\n", out, sr_result_string(rr)); status = 2; }
        else
            fprintf(stderr, "terrain: %s (w %.2f%s, %d levels, epsilon %g, sigma %g): %zu vertices, %zu triangles -> %s (%dx%d)\n",
                    preset, d.omega, half ? " halved" : "", d.levels, d.epsilon, d.sigma, m.vertex_count, m.triangle_count,
                    out, W, H);
    }
    sr_framebuffer_free(&fb);
done:
    free(pos);
    free(nrm);
    free(idx);
    sd4_free_mesh(&m);
    return status;
}
