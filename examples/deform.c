/* deform - drag a handle inside a region of interest with deform.h's three methods, side by side.

   usage: deform MESH|--cylinder|--box [options] [-o OUT.png]
     MESH           OBJ / OFF / PLY / STL (examples/meshio.h); --cylinder and --box generate a
                    tube of radius 1 and height 8 (round, or square with side 2), closed by caps
     --case C       bend (default), twist or drag
     --angle DEG    bend or twist angle in degrees (default 90)
     --shift F      drag: the handle's shift, as a share of the height (default 0.25)
     --up x|y|z     the "height" axis (default: the bounding box's longest)
     --region R     top (default): the ROI is the top --roi share of the height, the handle the
                    top --handle share; ball: geodesic balls of those radii (shares of the
                    height) around the highest vertex (a bunny's ear tip)
     --roi F        default 0.5 (top), 0.3 (ball)
     --handle F     default 0.08 (top), 0.06 (ball)
     --method M     laplacian, fitting, lri or all (default: all, side by side)
     --weights W    uniform (default) or cotan
     --frames F     LRI frames: first (default) or elevation (the thesis's ch. 4)
     --ortho O      LRI orthonormalization: polar (default), none, gs
     --soft W       soft handle constraints of weight W (default: hard)
     --rigid K      LRI: K as-rigid-as-possible steps after the LRI solve (default 0)
     --steps K      reach the pose in K steps, each a new setup on the previous step's result
                    with the rotation since the previous step (default 1). One step cannot turn
                    the handle by 180 degrees or more: a rotation matrix has no turn count, and
                    LRI's linear frames solve averages I and R (singular at 180 degrees)
     --obj PREFIX   also write PREFIX_<method>.obj
     --size S       pixels of each view (default 360)
     -o OUT.png     default deform.png: the original with the ROI (red) and handle (yellow),
                    then each method's result, with captions
   Prints one line a method: "RESULT deform_example method=... init_ms=... frame_ms=...
   edge_distortion=..." and the setup's progress on stderr. Exit status 0, 1 on failure, 2 on a
   bad argument (named in the message). The PNG and the OBJ files are written to NAME.tmp and
   renamed once all are complete, so a failed run leaves none of them. --version prints the
   version. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime under -std=c99 */
#define DFM_IMPLEMENTATION
#include "deform.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#define SR_IMPLEMENTATION
#include "render.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846
#define DEFORM_VERSION "deform 0.2 (deform.h, meshio.h, render.h)"

typedef struct args {
    const char *mesh, *out, *obj;
    int gen;           /* 0 file, 1 cylinder, 2 box */
    int kase;          /* 0 bend, 1 twist, 2 drag */
    double angle, shift, roi, handle, soft;
    int up, region, method, weights, frames, ortho, size, steps, rigid;
} args;

typedef struct scene {
    size_t nv, nt;
    double *pos;
    uint32_t *idx;
    unsigned char *roi, *handle;
    uint32_t *remap; /* dfm_weld's: copies of a vertex follow the one in the triangles */
    double lo[3], hi[3];
} scene;

/* ---- generated meshes: a tube of rings x segs vertices and two fan caps ----------------------- */

static void ring_point(int square, double a, double *x, double *y)
{
    if (!square) {
        *x = cos(a);
        *y = sin(a);
    } else { /* the square of side 2, same angle */
        double c = cos(a), s = sin(a), m = fabs(c) > fabs(s) ? fabs(c) : fabs(s);
        *x = c / m;
        *y = s / m;
    }
}

static int make_tube(scene *S, int square)
{
    const size_t rings = 81, segs = 32;
    size_t r, s, t = 0, c0 = rings * segs, c1 = c0 + 1;
    S->nv = rings * segs + 2;
    S->nt = 2 * (rings - 1) * segs + 2 * segs;
    S->pos = (double *)malloc(3 * S->nv * sizeof(double));
    S->idx = (uint32_t *)malloc(3 * S->nt * sizeof(uint32_t));
    if (!S->pos || !S->idx) return 0;
    for (r = 0; r < rings; r++)
        for (s = 0; s < segs; s++) {
            double *p = S->pos + 3 * (r * segs + s);
            ring_point(square, 2.0 * PI * (double)s / (double)segs, &p[0], &p[1]);
            p[2] = 8.0 * (double)r / (double)(rings - 1);
        }
    S->pos[3 * c0] = S->pos[3 * c0 + 1] = S->pos[3 * c0 + 2] = 0.0;
    S->pos[3 * c1] = S->pos[3 * c1 + 1] = 0.0;
    S->pos[3 * c1 + 2] = 8.0;
    for (r = 0; r + 1 < rings; r++)
        for (s = 0; s < segs; s++) {
            uint32_t a = (uint32_t)(r * segs + s), b = (uint32_t)(r * segs + (s + 1) % segs);
            uint32_t c = a + (uint32_t)segs, d = b + (uint32_t)segs, *f = S->idx + 6 * t++;
            f[0] = a; f[1] = b; f[2] = d; f[3] = a; f[4] = d; f[5] = c;
        }
    for (s = 0; s < segs; s++) {
        uint32_t *f = S->idx + 3 * (2 * (rings - 1) * segs + 2 * s);
        f[0] = (uint32_t)c0; f[1] = (uint32_t)((s + 1) % segs); f[2] = (uint32_t)s;
        f[3] = (uint32_t)c1; f[4] = (uint32_t)((rings - 1) * segs + s);
        f[5] = (uint32_t)((rings - 1) * segs + (s + 1) % segs);
    }
    return 1;
}

static int load_mesh(scene *S, const char *path)
{
    dfm_result dr;
    mio_mesh m;
    mio_error err;
    size_t i;
    mio_result r;
    errno = 0;
    if ((r = mio_read_file(path, NULL, &m, &err)) != MIO_OK) {
        cli_read_error("deform", path, err.message, mio_result_string(r), mio_result_description(r), r == MIO_ERR_IO ? errno : 0);
        return 0;
    }
    S->nv = m.vertex_count;
    S->nt = m.triangle_count;
    S->pos = (double *)malloc(3 * S->nv * sizeof(double) + 1);
    S->idx = (uint32_t *)malloc(3 * S->nt * sizeof(uint32_t) + 1);
    S->remap = (uint32_t *)malloc(S->nv * sizeof(uint32_t) + 1);
    if (S->pos && S->idx && S->remap) {
        for (i = 0; i < 3 * S->nv; i++) S->pos[i] = m.positions[i];
        memcpy(S->idx, m.indices, 3 * S->nt * sizeof(uint32_t));
    }
    mio_free_mesh(&m);
    if (!S->pos || !S->idx || !S->remap) { fprintf(stderr, "deform: out of memory\n"); return 0; }
    /* a triangle soup (STL) is welded first: deform.h refuses unwelded meshes */
    if ((dr = dfm_weld(S->pos, S->nv, S->idx, S->nt, S->remap, S->idx, NULL)) != DFM_OK) {
        cli_result_error("deform", path, dfm_result_string(dr), 0);
        return 0;
    }
    return 1;
}

/* ---- selection and pose --------------------------------------------------------------------- */

static int select_region(scene *S, const args *A, int up)
{
    double h = S->hi[up] - S->lo[up];
    size_t v, top = 0;
    S->roi = (unsigned char *)calloc(S->nv, 1);
    S->handle = (unsigned char *)calloc(S->nv, 1);
    if (!S->roi || !S->handle) return 0;
    if (A->region == 0) {
        for (v = 0; v < S->nv; v++) {
            double t = (S->pos[3 * v + up] - S->lo[up]) / h;
            S->roi[v] = t >= 1.0 - A->roi;
            S->handle[v] = t >= 1.0 - A->handle;
        }
        return 1;
    }
    for (v = 1; v < S->nv; v++)
        if (S->pos[3 * v + up] > S->pos[3 * top + up]) top = v;
    {
        unsigned char *seed = (unsigned char *)calloc(S->nv, 1);
        int ok = seed != NULL;
        if (ok) seed[top] = 1;
        ok = ok && dfm_roi_geodesic(S->pos, S->nv, S->idx, S->nt, seed, A->roi * h, S->roi, NULL) == DFM_OK;
        ok = ok && dfm_roi_geodesic(S->pos, S->nv, S->idx, S->nt, seed, A->handle * h, S->handle, NULL) == DFM_OK;
        free(seed);
        return ok;
    }
}

/* The handle's targets and rotations for the case: bend about the ROI's base, twist about the
   box's axis line, drag along the second-longest axis. */
static void make_pose(const scene *S, const args *A, int up, double frac, double *tg, double *rot)
{
    double axis[3] = {0, 0, 0}, toward[3] = {0, 0, 0}, base[3], h = S->hi[up] - S->lo[up], ext = -1.0;
    int k, side = (up + 1) % 3;
    for (k = 0; k < 3; k++)
        if (k != up && S->hi[k] - S->lo[k] > ext) {
            ext = S->hi[k] - S->lo[k];
            side = k;
        }
    axis[up] = 1.0;
    toward[side] = 1.0;
    for (k = 0; k < 3; k++) base[k] = 0.5 * (S->lo[k] + S->hi[k]);
    dfm_pose_identity(S->pos, S->nv, tg, rot);
    if (A->kase == 0) {
        base[up] = S->lo[up] + (1.0 - A->roi) * h;
        dfm_pose_bend(S->pos, S->nv, S->handle, base, axis, toward, (A->roi - A->handle) * h,
                      frac * A->angle * PI / 180.0, tg, rot);
    } else if (A->kase == 1) {
        dfm_pose_twist(S->pos, S->nv, S->handle, base, axis, frac * A->angle * PI / 180.0, tg, rot);
    } else {
        double t[3] = {0, 0, 0};
        t[side] = frac * A->shift * h;
        dfm_pose_rigid(S->pos, S->nv, S->handle, NULL, NULL, t, tg, rot);
    }
}

/* ---- rendering ------------------------------------------------------------------------------ */

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct progress_state {
    const char *name;
    int shown; /* last tenth printed */
} progress_state;

static int progress(void *user, float done)
{
    progress_state *ps = (progress_state *)user;
    int tenth = (int)(10.0f * done);
    if (tenth > ps->shown) {
        ps->shown = tenth;
        fprintf(stderr, "\rdeform: %s setup %3d%%", ps->name, 10 * tenth);
    }
    return 0;
}

/* renders positions (double) into img with one camera for every view */
static int render_view(const scene *S, const double *p, const sr_camera *cam, int size, const float *colors,
                       sr_image8 *img)
{
    sr_framebuffer fb;
    sr_draw_desc d;
    float bg[4] = {0.93f, 0.94f, 0.96f, 1.0f}, *fp = (float *)malloc(3 * S->nv * sizeof(float) + 1);
    float *nrm = (float *)malloc(3 * S->nv * sizeof(float) + 1);
    size_t i;
    int ok = 0;
    img->pixels = (uint8_t *)malloc((size_t)size * (size_t)size * 3);
    if (!fp || !nrm || !img->pixels || sr_framebuffer_create(&fb, size, size, NULL) != SR_OK) goto done;
    for (i = 0; i < 3 * S->nv; i++) fp[i] = (float)p[i];
    sr_compute_vertex_normals(fp, S->nv, S->idx, S->nt, nrm);
    sr_framebuffer_clear(&fb, bg, 1.0f);
    sr_draw_desc_default(&d);
    d.positions = fp;
    d.vertex_count = S->nv;
    d.indices = S->idx;
    d.triangle_count = S->nt;
    d.normals = nrm;
    d.colors = colors;
    d.cull = SR_CULL_NONE;
    ok = sr_draw_mesh(&fb, cam, &d) == SR_OK;
    img->width = img->height = size;
    img->channels = 3;
    sr_framebuffer_to_rgb8(&fb, img->pixels, 3);
    sr_framebuffer_free(&fb);
done:
    free(fp);
    free(nrm);
    return ok;
}

/* a camera looking along the third axis at the box of every result */
static void frame_camera(const scene *S, double *const *res, int nres, int up, sr_camera *cam)
{
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f}, c[3], eye[3], upv[3] = {0, 0, 0}, r = 0;
    int k, j, view = (up + 2) % 3;
    size_t v;
    for (j = 0; j < nres; j++)
        for (v = 0; v < S->nv; v++)
            for (k = 0; k < 3; k++) {
                lo[k] = fminf(lo[k], (float)res[j][3 * v + k]);
                hi[k] = fmaxf(hi[k], (float)res[j][3 * v + k]);
            }
    for (k = 0; k < 3; k++) {
        c[k] = 0.5f * (lo[k] + hi[k]);
        r = fmaxf(r, 0.5f * (hi[k] - lo[k]));
    }
    for (k = 0; k < 3; k++) eye[k] = c[k];
    eye[view] += 4.0f * r;
    eye[up] += 1.2f * r;
    eye[(up + 1) % 3] += 1.5f * r;
    upv[up] = 1.0f;
    sr_camera_look_at(cam, eye, c, upv, 30.0f, 1.0f, 0.5f * r, 12.0f * r);
}

/* ---- arguments ------------------------------------------------------------------------------ */

static int usage(FILE *to, int status)
{
    fprintf(to,
            "usage: deform MESH|--cylinder|--box [-o OUT.png] [--case bend|twist|drag] [--angle DEG] [--shift F]\n"
            "       [--up x|y|z] [--region top|ball] [--roi F] [--handle F] [--method laplacian|fitting|lri|all]\n"
            "       [--weights uniform|cotan] [--frames first|elevation] [--ortho polar|none|gs] [--soft W]\n"
            "       [--rigid K] [--steps K] [--obj PREFIX] [--size S]\n"
            "Drags a handle inside a region of interest with deform.h's three methods and renders them side by side.\n"
            "  MESH               OBJ, OFF, PLY or STL (an STL soup is welded first)\n"
            "  --cylinder, --box  instead of MESH: a tube of radius 1 and height 8, round or square, with caps\n"
            "  -o, --output FILE  the PNG to write; the name must end in .png (default deform.png)\n"
            "  --case C           bend (default), twist or drag\n"
            "  --angle DEG        bend or twist angle in degrees, -36000..36000 (default 90)\n"
            "  --shift F          drag: the handle's shift as a share of the height, -10..10 (default 0.25)\n"
            "  --up A             the height axis x, y or z (default: the bounding box's longest)\n"
            "  --region R         top (default: the top --roi share of the height; the handle the top --handle\n"
            "                     share) or ball (geodesic balls of those radii around the highest vertex)\n"
            "  --roi F            the region's size, (0, 1] (default 0.5 for top, 0.3 for ball)\n"
            "  --handle F         the handle's size, (0, --roi) (default 0.08 for top, 0.06 for ball)\n"
            "  --method M         laplacian, fitting, lri or all (default all, side by side)\n"
            "  --weights W        uniform (default) or cotan\n"
            "  --frames F         LRI frames: first (default) or elevation\n"
            "  --ortho O          LRI orthonormalization: polar (default), none or gs\n"
            "  --soft W           soft handle constraints of weight W > 0 (default 0: hard constraints)\n"
            "  --rigid K          LRI: K as-rigid-as-possible steps after the solve, 0..100 (default 0)\n"
            "  --steps K          reach the pose in K steps, 1..1000, each a new setup on the previous result\n"
            "                     (default 1; one step cannot turn the handle by 180 degrees or more)\n"
            "  --obj PREFIX       also write PREFIX_<method>.obj for each method (default: none)\n"
            "  --size S           pixels of each view, 32..4096 (default 360)\n"
            "  -h, --help         show this help and exit\n"
            "  --version          show the version and exit\n"
            "Prints one RESULT deform_example line a method on stdout; progress on stderr.\n"
            "Exit status: 0 done, 1 failure (unreadable input, a failed setup or solve, a failed write),\n"
            "2 usage. The files are written to NAME.tmp and renamed once all are complete.\n");
    return status;
}

static int pick(const char *v, const char *const *names, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (v && strcmp(v, names[i]) == 0) return i;
    return -1;
}

static int parse(int argc, char **argv, args *A)
{
    static const char *cases[] = {"bend", "twist", "drag"}, *ups[] = {"x", "y", "z"}, *regions[] = {"top", "ball"};
    static const char *methods[] = {"laplacian", "fitting", "lri", "all"}, *weights[] = {"uniform", "cotan"};
    static const char *frames[] = {"first", "elevation"}, *orthos[] = {"none", "polar", "gs"};
    static const char *valued[] = {"-o", "--output", "--obj", "--angle", "--shift", "--roi", "--handle", "--soft", "--size",
                                   "--steps", "--rigid", "--case", "--up", "--region", "--method", "--weights", "--frames",
                                   "--ortho"};
    int i;
    memset(A, 0, sizeof *A);
    A->out = "deform.png";
    A->angle = 90.0;
    A->shift = 0.25;
    A->up = -1;
    A->roi = A->handle = -1.0;
    A->method = 3;
    A->ortho = 1;
    A->size = 360;
    A->steps = 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int *slot = NULL, k = -2;
        long n;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return usage(stdout, 0);
        if (!strcmp(a, "--version")) { printf("%s\n", DEFORM_VERSION); return 0; }
        if (!strcmp(a, "--cylinder")) { A->gen = 1; continue; }
        if (!strcmp(a, "--box")) { A->gen = 2; continue; }
        if (a[0] != '-' || !a[1]) {
            if (A->mesh) return cli_usage_error("deform", "unexpected argument '%s': one MESH only", a);
            A->mesh = a;
            continue;
        }
        if (!v) return cli_usage_error("deform", pick(a, valued, 18) < 0 ? "unknown option '%s'" : "%s needs a value", a);
        i++;
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) A->out = v;
        else if (!strcmp(a, "--obj")) A->obj = v;
        else if (!strcmp(a, "--angle")) { if (!cli_parse_double(v, -36000.0, 36000.0, &A->angle)) return cli_usage_error("deform", "--angle '%s': not a number of degrees in -36000..36000", v); }
        else if (!strcmp(a, "--shift")) { if (!cli_parse_double(v, -10.0, 10.0, &A->shift)) return cli_usage_error("deform", "--shift '%s': not a number in -10..10", v); }
        else if (!strcmp(a, "--roi")) { if (!cli_parse_double(v, 1e-6, 1.0, &A->roi)) return cli_usage_error("deform", "--roi '%s': not a number in (0, 1]", v); }
        else if (!strcmp(a, "--handle")) { if (!cli_parse_double(v, 1e-6, 1.0, &A->handle)) return cli_usage_error("deform", "--handle '%s': not a number in (0, 1)", v); }
        else if (!strcmp(a, "--soft")) { if (!cli_parse_double(v, 0.0, 1e12, &A->soft)) return cli_usage_error("deform", "--soft '%s': not a weight in [0, 1e12]", v); }
        else if (!strcmp(a, "--size")) { if (!cli_parse_long(v, 32, 4096, &n)) return cli_usage_error("deform", "--size '%s': not an integer in 32..4096", v); A->size = (int)n; }
        else if (!strcmp(a, "--steps")) { if (!cli_parse_long(v, 1, 1000, &n)) return cli_usage_error("deform", "--steps '%s': not an integer in 1..1000", v); A->steps = (int)n; }
        else if (!strcmp(a, "--rigid")) { if (!cli_parse_long(v, 0, 100, &n)) return cli_usage_error("deform", "--rigid '%s': not an integer in 0..100", v); A->rigid = (int)n; }
        else if (!strcmp(a, "--case")) { slot = &A->kase; k = pick(v, cases, 3); }
        else if (!strcmp(a, "--up")) { slot = &A->up; k = pick(v, ups, 3); }
        else if (!strcmp(a, "--region")) { slot = &A->region; k = pick(v, regions, 2); }
        else if (!strcmp(a, "--method")) { slot = &A->method; k = pick(v, methods, 4); }
        else if (!strcmp(a, "--weights")) { slot = &A->weights; k = pick(v, weights, 2); }
        else if (!strcmp(a, "--frames")) { slot = &A->frames; k = pick(v, frames, 2); }
        else if (!strcmp(a, "--ortho")) { slot = &A->ortho; k = pick(v, orthos, 3); }
        else return cli_usage_error("deform", "unknown option '%s'", a);
        if (slot) {
            if (k < 0) return cli_usage_error("deform", "%s '%s': not one of the names --help lists", a, v);
            *slot = k;
        }
    }
    if (A->roi < 0) A->roi = A->region ? 0.3 : 0.5;
    if (A->handle < 0) A->handle = A->region ? 0.06 : 0.08;
    if ((A->gen == 0) == (A->mesh == NULL)) return cli_usage_error("deform", "%s", "give exactly one of MESH, --cylinder or --box");
    if (!(A->roi > A->handle)) return cli_usage_error("deform", "--handle %g: not smaller than --roi", A->handle);
    if (!cli_has_extension(A->out, ".png")) return cli_usage_error("deform", "output '%s': only PNG is written; the name must end in .png", A->out);
    if (A->obj && strlen(A->obj) + 16 >= CLI_PATH_MAX) return cli_usage_error("deform", "--obj '%s': the prefix is too long", A->obj);
    return -1;
}

/* ---- main ------------------------------------------------------------------------------------- */

static double edge_distortion(const scene *S, const double *out)
{
    size_t t, k, n = 0;
    double s = 0.0;
    for (t = 0; t < S->nt; t++)
        for (k = 0; k < 3; k++) {
            uint32_t a = S->idx[3 * t + k], b = S->idx[3 * t + (k + 1) % 3];
            double l0 = 0, l1 = 0, r;
            int c;
            if (!S->roi[a] && !S->roi[b]) continue;
            for (c = 0; c < 3; c++) {
                l0 += (S->pos[3 * a + c] - S->pos[3 * b + c]) * (S->pos[3 * a + c] - S->pos[3 * b + c]);
                l1 += (out[3 * a + c] - out[3 * b + c]) * (out[3 * a + c] - out[3 * b + c]);
            }
            r = sqrt(l1 / l0) - 1.0;
            s += r * r;
            n++;
        }
    return n ? sqrt(s / (double)n) : 0.0;
}

/* Writes PREFIX_METHOD.obj.tmp (renamed with the other outputs when all are written). */
static int write_obj(cli_outputs *outs, const char *prefix, const char *method, const scene *S, const double *p)
{
    char path[CLI_PATH_MAX];
    const char *tmp;
    float *fp = (float *)malloc(3 * S->nv * sizeof(float) + 1);
    size_t i;
    mio_error err;
    mio_result r;
    if (!fp) { fprintf(stderr, "deform: out of memory\n"); return 0; }
    for (i = 0; i < 3 * S->nv; i++) fp[i] = (float)p[i];
    snprintf(path, sizeof path, "%s_%s.obj", prefix, method);
    if (!(tmp = cli_output_add(outs, "deform", path))) { free(fp); return 0; }
    errno = 0;
    r = mio_write_obj(tmp, fp, S->nv, S->idx, S->nt, &err);
    if (r != MIO_OK) cli_read_error("deform", path, err.message, mio_result_string(r), mio_result_description(r), r == MIO_ERR_IO ? errno : 0);
    free(fp);
    return r == MIO_OK;
}

/* rot = the rotation from pose a to pose b at the vertices the solve reads (b a^T) */
static void step_rotation(size_t nv, const double *ra, const double *rb, double *rot)
{
    size_t v;
    int i, j, k;
    for (v = 0; v < nv; v++)
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) {
                double sum = 0.0;
                for (k = 0; k < 3; k++) sum += rb[9 * v + 3 * i + k] * ra[9 * v + 3 * j + k];
                rot[9 * v + 3 * i + j] = sum;
            }
}

/* runs one method in A->steps steps; res receives the result (malloc'd) */
static int run_method(const scene *S, const args *A, int up, int method, double **res, cli_outputs *outs)
{
    static const char *names[] = {"laplacian", "fitting", "lri"};
    dfm_deform_options o = dfm_deform_default_options();
    dfm_result r = DFM_OK;
    progress_state ps;
    double t_init = 0.0, t_frame = 0.0, *cur = (double *)malloc(3 * S->nv * sizeof(double));
    double *tg = (double *)malloc(3 * S->nv * sizeof(double)), *rot = (double *)malloc(9 * S->nv * sizeof(double));
    double *prev = (double *)malloc(9 * S->nv * sizeof(double)), *step = (double *)malloc(9 * S->nv * sizeof(double));
    size_t v;
    int k, ok = 0;
    o.method = method;
    o.weights = A->weights;
    o.frames = A->frames;
    o.orthonormalize = A->ortho;
    o.rigid_steps = A->rigid;
    if (A->soft > 0.0) {
        o.handle_constraint = DFM_HANDLE_SOFT;
        o.handle_weight = A->soft;
    }
    ps.name = names[method];
    o.progress = progress;
    o.progress_user = &ps;
    *res = (double *)malloc(3 * S->nv * sizeof(double));
    if (!*res || !cur || !tg || !rot || !prev || !step) goto done;
    memcpy(cur, S->pos, 3 * S->nv * sizeof(double));
    dfm_pose_identity(S->pos, S->nv, tg, prev);
    for (k = 1; k <= A->steps && r == DFM_OK; k++) {
        dfm_deform *d = NULL;
        double t0 = seconds(), t1, t2;
        ps.shown = -1;
        make_pose(S, A, up, (double)k / (double)A->steps, tg, rot);
        step_rotation(S->nv, prev, rot, step);
        memcpy(prev, rot, 9 * S->nv * sizeof(double));
        r = dfm_deform_setup(cur, S->nv, S->idx, S->nt, S->roi, S->handle, &o, &d);
        t1 = seconds();
        if (r == DFM_OK) r = dfm_deform_solve(d, tg, step, *res);
        t2 = seconds();
        t_init += t1 - t0;
        t_frame += t2 - t1;
        dfm_deform_free(d);
        if (S->remap)
            for (v = 0; v < S->nv; v++) memcpy(*res + 3 * v, *res + 3 * (size_t)S->remap[v], 3 * sizeof(double));
        memcpy(cur, *res, 3 * S->nv * sizeof(double));
    }
    fprintf(stderr, "\n");
    if (r != DFM_OK) {
        cli_result_error("deform", names[method], dfm_result_string(r), 0);
        goto done;
    }
    printf("RESULT deform_example method=%s n=%zu steps=%d init_ms=%.1f frame_ms=%.2f edge_distortion=%.4f\n",
           names[method], S->nv, A->steps, 1e3 * t_init / A->steps, 1e3 * t_frame / A->steps,
           edge_distortion(S, *res));
    ok = !A->obj || write_obj(outs, A->obj, names[method], S, *res);
done:
    free(cur);
    free(tg);
    free(rot);
    free(prev);
    free(step);
    return ok;
}

static int render_all(const scene *S, const args *A, int up, double **res, const int *methods, int nm, cli_outputs *outs)
{
    static const char *names[] = {"LAPLACIAN", "FITTING", "LRI"};
    sr_image8 img[4], sheet;
    const char *caps[4];
    char cap0[96], cap_lri[64];
    double *all[4];
    float *col = (float *)malloc(3 * S->nv * sizeof(float) + 1);
    sr_camera cam;
    sr_result r;
    const char *tmp = NULL;
    size_t v;
    int i, ok = col != NULL;
    memset(img, 0, sizeof img);
    memset(&sheet, 0, sizeof sheet);
    all[0] = S->pos;
    for (i = 0; i < nm; i++) all[i + 1] = res[i];
    frame_camera(S, all, nm + 1, up, &cam);
    for (v = 0; ok && v < S->nv; v++) { /* grey, the ROI red, the handle yellow */
        col[3 * v] = S->handle[v] ? 0.95f : S->roi[v] ? 0.85f : 0.72f;
        col[3 * v + 1] = S->handle[v] ? 0.85f : S->roi[v] ? 0.35f : 0.72f;
        col[3 * v + 2] = S->handle[v] ? 0.2f : S->roi[v] ? 0.3f : 0.72f;
    }
    for (i = 0; ok && i <= nm; i++) ok = render_view(S, all[i], &cam, A->size, col, &img[i]);
    snprintf(cap0, sizeof cap0, "ORIGINAL %zu VERTICES", S->nv);
    caps[0] = cap0;
    snprintf(cap_lri, sizeof cap_lri, "LRI + %d RIGID STEPS", A->rigid);
    for (i = 0; i < nm; i++) caps[i + 1] = methods[i] == 2 && A->rigid > 0 ? cap_lri : names[methods[i]];
    if (!ok) fprintf(stderr, "deform: out of memory or a failed render\n");
    if (ok && (r = sr_contact_sheet(img, caps, nm + 1, nm + 1, NULL, &sheet)) != SR_OK) {
        cli_result_error("deform", "the contact sheet", sr_result_string(r), 0);
        ok = 0;
    }
    if (ok && !(tmp = cli_output_add(outs, "deform", A->out))) ok = 0;
    errno = 0;
    if (ok && (r = sr_write_png(tmp, sheet.pixels, sheet.width, sheet.height, 3, 0)) != SR_OK) {
        cli_result_error("deform", A->out, sr_result_string(r), r == SR_ERR_IO ? errno : 0);
        ok = 0;
    }
    for (i = 0; i < 4; i++) free(img[i].pixels);
    sr_free(NULL, sheet.pixels);
    free(col);
    return ok;
}

int main(int argc, char **argv)
{
    args A;
    scene S;
    double *res[3] = {NULL, NULL, NULL};
    int methods[3], nm = 0, i, up, status = 1, p = parse(argc, argv, &A);
    size_t v;
    cli_outputs outs;
    if (p >= 0) return p;
    cli_outputs_init(&outs);
    memset(&S, 0, sizeof S);
    if (!(A.gen ? make_tube(&S, A.gen == 2) : load_mesh(&S, A.mesh))) goto done;
    for (i = 0; i < 3; i++) {
        S.lo[i] = HUGE_VAL;
        S.hi[i] = -HUGE_VAL;
    }
    for (v = 0; v < S.nv; v++)
        for (i = 0; i < 3; i++) {
            S.lo[i] = fmin(S.lo[i], S.pos[3 * v + i]);
            S.hi[i] = fmax(S.hi[i], S.pos[3 * v + i]);
        }
    up = A.up;
    if (up < 0) {
        up = 0;
        for (i = 1; i < 3; i++)
            if (S.hi[i] - S.lo[i] > S.hi[up] - S.lo[up]) up = i;
    }
    if (!select_region(&S, &A, up)) {
        fprintf(stderr, "deform: out of memory or bad selection\n");
        goto done;
    }
    if (A.method == 3)
        for (i = 0; i < 3; i++) methods[nm++] = i;
    else
        methods[nm++] = A.method;
    for (i = 0; i < nm; i++)
        if (!run_method(&S, &A, up, methods[i], &res[i], &outs)) goto done;
    if (!render_all(&S, &A, up, res, methods, nm, &outs) || !cli_outputs_commit(&outs, "deform")) goto done;
    fprintf(stderr, "deform: wrote %s\n", A.out);
    status = 0;
done:
    cli_outputs_discard(&outs); /* after a failure: no file of this run is left */
    for (i = 0; i < 3; i++) free(res[i]);
    free(S.pos);
    free(S.idx);
    free(S.roi);
    free(S.handle);
    free(S.remap);
    return status;
}
