/* render_mesh - renders any mesh file that meshio.h reads (OBJ, OFF, PLY, STL) to a PNG.

   usage: render_mesh IN -o OUT.png [--view NAME|AZ,EL] [--wire] [--size W[xH]] [--shading S] [--ortho] [--up x|y|z]
   (render_mesh --help lists every option with its default.)
   The view is fitted: the mesh fills the frame up to a 5% border (not its bounding sphere, which
   leaves a long mesh small). One directional key light from the upper left of the viewer plus a
   dim fill light; area-weighted vertex normals. The PNG is written to
   OUT.png.tmp and renamed when complete, so a failed run leaves no file.
   Exit status: 0 done, 1 failure (unreadable input, render or write failure), 2 usage. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

#define MIO_IMPLEMENTATION
#include "meshio.h"
#define SR_IMPLEMENTATION
#include "render.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#define RENDER_MESH_VERSION "render_mesh 0.2 (meshio.h v0.1, render.h)"

typedef struct args {
    const char *in, *out;
    float az, el;
    int wire, W, H, ortho, up; /* up: 0 = x, 1 = y, 2 = z */
    sr_shading shading;
} args;

static void usage(FILE *to)
{
    fprintf(to, "usage: render_mesh IN -o OUT.png [options]\n"
                "Renders a mesh file (OBJ, OFF, PLY, STL) to a PNG image.\n"
                "  -o, --output FILE    the PNG to write; the name must end in .png (any case) (required)\n"
                "  --view V             iso (default: azimuth 35, elevation 25), front, back, left, right, top,\n"
                "                       bottom, or AZ,EL in degrees: azimuth around the up axis from the front, elevation above\n"
                "                       the ground plane, strictly between -90 and 90\n"
                "  --up A               the model's up axis: x, y (default) or z; the views turn with it\n"
                "                       (z up: front looks from -y; x up: front looks from +y)\n"
                "  --wire               draw the triangle edges over the shading (default: off)\n"
                "  --size W[xH]         image size in pixels, 1 to 16384 each; W alone is square (default 800x800)\n"
                "  --shading S          phong (default), gouraud or flat\n"
                "  --ortho              orthographic instead of perspective projection (default: perspective)\n"
                "  -h, --help           show this help and exit\n"
                "  --version            show the version and exit\n"
                "Exit status: 0 done, 1 failure (unreadable input, render or write failure), 2 usage.\n"
                "The PNG is written to FILE.tmp and renamed when complete: a failed run leaves nothing.\n");
}

static int parse_view(const char *s, float *az, float *el)
{
    static const struct { const char *name; float az, el; } views[] = {
        {"iso", 35.0f, 25.0f}, {"front", 0.0f, 0.0f}, {"back", 180.0f, 0.0f}, {"left", -90.0f, 0.0f},
        {"right", 90.0f, 0.0f}, {"top", 0.0f, 89.9f}, {"bottom", 0.0f, -89.9f}};
    size_t i;
    double d[2];
    for (i = 0; i < sizeof views / sizeof views[0]; i++)
        if (strcmp(s, views[i].name) == 0) { *az = views[i].az; *el = views[i].el; return 1; }
    if (!cli_parse_doubles(s, ',', 2, 2, -1e6, 1e6, d, NULL) || !(d[1] > -90.0 && d[1] < 90.0)) return 0;
    *az = (float)d[0];
    *el = (float)d[1];
    return 1;
}

/* Returns -1 to go on, or the exit status (0 for --help/--version, 2 for a usage error). */
static int parse_args(int argc, char **argv, args *a)
{
    int i;
    memset(a, 0, sizeof *a);
    a->az = 35.0f; a->el = 25.0f; a->W = a->H = 800; a->up = 1; a->shading = SR_SHADE_PHONG;
    for (i = 1; i < argc; i++) {
        const char *s = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int takes = strcmp(s, "-o") == 0 || strcmp(s, "--output") == 0 || strcmp(s, "--view") == 0 ||
                    strcmp(s, "--size") == 0 || strcmp(s, "--shading") == 0 || strcmp(s, "--up") == 0;
        if (strcmp(s, "-h") == 0 || strcmp(s, "--help") == 0) { usage(stdout); return 0; }
        if (strcmp(s, "--version") == 0) { printf("%s\n", RENDER_MESH_VERSION); return 0; }
        if (takes && !v) return cli_usage_error("render_mesh", "%s needs a value", s);
        if (takes) i++;
        if (strcmp(s, "-o") == 0 || strcmp(s, "--output") == 0) a->out = v;
        else if (strcmp(s, "--view") == 0) {
            if (!parse_view(v, &a->az, &a->el)) return cli_usage_error("render_mesh", "--view '%s': not a view name or AZ,EL with -90 < EL < 90", v);
        } else if (strcmp(s, "--size") == 0) {
            if (!cli_parse_size(v, 1, 16384, 1, &a->W, &a->H)) return cli_usage_error("render_mesh", "--size '%s': not W or WxH with 1 <= W, H <= 16384", v);
        } else if (strcmp(s, "--shading") == 0) {
            if (strcmp(v, "phong") == 0) a->shading = SR_SHADE_PHONG;
            else if (strcmp(v, "gouraud") == 0) a->shading = SR_SHADE_GOURAUD;
            else if (strcmp(v, "flat") == 0) a->shading = SR_SHADE_FLAT;
            else return cli_usage_error("render_mesh", "--shading '%s': not phong, gouraud or flat", v);
        } else if (strcmp(s, "--up") == 0) {
            if ((v[0] != 'x' && v[0] != 'y' && v[0] != 'z') || v[1] != '\0') return cli_usage_error("render_mesh", "--up '%s': not x, y or z", v);
            a->up = v[0] - 'x';
        } else if (strcmp(s, "--wire") == 0) a->wire = 1;
        else if (strcmp(s, "--ortho") == 0) a->ortho = 1;
        else if (s[0] == '-' && s[1] != '\0') return cli_usage_error("render_mesh", "unknown option '%s'", s);
        else if (a->in) return cli_usage_error("render_mesh", "unexpected argument '%s': one IN only", s);
        else a->in = s;
    }
    if (!a->in) return cli_usage_error("render_mesh", "%s", "no input mesh given");
    if (!a->out) return cli_usage_error("render_mesh", "%s", "no output given: -o OUT.png");
    if (!cli_has_extension(a->out, ".png")) return cli_usage_error("render_mesh", "output '%s': only PNG is written; the name must end in .png", a->out);
    return -1;
}

/* Writes the framebuffer to OUT.tmp and renames it to OUT; removes OUT.tmp on failure. 0 or 1. */
static int write_png(const sr_framebuffer *fb, const char *out)
{
    cli_outputs outs;
    const char *tmp;
    sr_result r;
    cli_outputs_init(&outs);
    if (!(tmp = cli_output_add(&outs, "render_mesh", out))) return 1;
    errno = 0;
    r = sr_write_framebuffer_png(fb, tmp, 0);
    if (r != SR_OK) {
        cli_result_error("render_mesh", out, sr_result_string(r), r == SR_ERR_IO ? errno : 0);
        cli_outputs_discard(&outs);
        return 1;
    }
    return cli_outputs_commit(&outs, "render_mesh") ? 0 : 1;
}

/* The view direction (from the target towards the eye) for azimuth az around the up axis from the
   front axis and elevation el above the ground plane. Frames (side, up, front): y up (x, y, z),
   z up (x, z, -y), x up (z, x, y): each right-handed, so "front" looks at the model's front. */
static void view_direction(const args *a, float dir[3], float up[3])
{
    static const float frames[3][3][3] = {{{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
                                          {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                                          {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}}};
    const float (*f)[3] = frames[a->up];
    float cs = cosf(a->el * 0.0174533f) * sinf(a->az * 0.0174533f), sn = sinf(a->el * 0.0174533f);
    float cc = cosf(a->el * 0.0174533f) * cosf(a->az * 0.0174533f);
    int i;
    for (i = 0; i < 3; i++) {
        dir[i] = cs * f[0][i] + sn * f[1][i] + cc * f[2][i];
        up[i] = f[1][i];
    }
}

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* A fitted view: the camera looks along the chosen direction at the middle of the mesh's extent
   across the view, from the nearest distance at which every vertex is inside the frame with a 5%
   border (perspective: each vertex needs distance >= its depth + its offset / tan(fov/2)). */
static void frame_camera(const mio_mesh *mesh, const args *a, sr_camera *cam)
{
    float dir[3], up[3], c[3] = {0, 0, 0}, eye[3], R[3], U[3], lo[3], hi[3], d[3];
    float fov = 35.0f, aspect = (float)a->W / (float)a->H, t, need = 0.0f, span, half, dist;
    size_t v;
    int i, k;
    view_direction(a, dir, up);
    for (i = 0; i < 3; i++) eye[i] = dir[i];
    sr_camera_look_at(cam, eye, c, up, fov, aspect, 0.1f, 10.0f); /* only for its right and up axes */
    for (i = 0; i < 3; i++) { R[i] = cam->right[i]; U[i] = cam->up[i]; }
    /* extents along (right, up, dir); float is enough for framing */
    for (v = 0; v < mesh->vertex_count; v++) {
        const float *p = mesh->positions + 3 * v;
        d[0] = dot3(p, R); d[1] = dot3(p, U); d[2] = dot3(p, dir);
        for (k = 0; k < 3; k++) {
            if (v == 0 || d[k] < lo[k]) lo[k] = d[k];
            if (v == 0 || d[k] > hi[k]) hi[k] = d[k];
        }
    }
    for (i = 0; i < 3; i++) c[i] = 0.5f * (lo[0] + hi[0]) * R[i] + 0.5f * (lo[1] + hi[1]) * U[i] + 0.5f * (lo[2] + hi[2]) * dir[i];
    span = hi[0] - lo[0];
    if (hi[1] - lo[1] > span) span = hi[1] - lo[1];
    if (hi[2] - lo[2] > span) span = hi[2] - lo[2];
    if (!(span > 0.0f)) span = 1.0f; /* a single point: any scale shows it */
    half = 0.5f * (hi[2] - lo[2]);   /* the depth of the mesh in front of the centre */
    t = tanf(0.5f * fov * 0.0174533f) / 1.05f;
    for (v = 0; v < mesh->vertex_count; v++) {
        const float *p = mesh->positions + 3 * v;
        float x = fabsf(dot3(p, R) - dot3(c, R)), y = fabsf(dot3(p, U) - dot3(c, U)), z = dot3(p, dir) - dot3(c, dir);
        float n = z + (y / t > x / (t * aspect) ? y / t : x / (t * aspect));
        if (a->ortho) n = 1.05f * (y > x / aspect ? y : x / aspect);
        if (n > need) need = n;
    }
    if (a->ortho) {
        dist = half + span;
        for (i = 0; i < 3; i++) eye[i] = c[i] + dir[i] * dist;
        sr_camera_ortho(cam, eye, c, up, need > 0.0f ? need : 0.5f * span, aspect, dist - half - 0.05f * span,
                        dist + half + 0.05f * span);
        return;
    }
    dist = need > half + 0.01f * span ? need : half + 0.01f * span;
    for (i = 0; i < 3; i++) eye[i] = c[i] + dir[i] * dist;
    sr_camera_look_at(cam, eye, c, up, fov, aspect, (dist - half) * 0.99f > dist * 0.001f ? (dist - half) * 0.99f : dist * 0.001f,
                      (dist + half) * 1.01f);
}

/* Moves the mesh's bounding box centre to the origin and scales its largest side to 1 (in double),
   so that framing and rasterizing work alike for any finite size: 3e38 or 1e-30 wide meshes would
   otherwise overflow or underflow in float and render as an empty picture. The picture is the same
   up to rounding: the camera is fitted and the lights are directional. */
static void normalize_mesh(mio_mesh *mesh)
{
    double lo[3], hi[3], c[3], span = 0.0;
    size_t v;
    int k;
    for (k = 0; k < 3; k++) lo[k] = hi[k] = mesh->positions[k];
    for (v = 0; v < mesh->vertex_count; v++)
        for (k = 0; k < 3; k++) {
            double x = mesh->positions[3 * v + (size_t)k];
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    for (k = 0; k < 3; k++) {
        c[k] = 0.5 * (lo[k] + hi[k]);
        if (hi[k] - lo[k] > span) span = hi[k] - lo[k];
    }
    if (!(span > 0.0)) span = 1.0;
    for (v = 0; v < mesh->vertex_count; v++)
        for (k = 0; k < 3; k++) {
            float *x = &mesh->positions[3 * v + (size_t)k];
            *x = (float)((*x - c[k]) / span);
        }
}

/* Draws the mesh with a key light from the viewer's upper left and a dim fill light. */
static sr_result draw(sr_framebuffer *fb, const sr_camera *cam, const mio_mesh *mesh, const float *normals, const args *a)
{
    sr_draw_desc d;
    sr_light lights[2];
    float key[3], fill[3];
    int i;
    for (i = 0; i < 3; i++) {
        key[i] = -cam->forward[i] + 0.6f * cam->up[i] - 0.5f * cam->right[i];
        fill[i] = -cam->forward[i] + 0.8f * cam->right[i] - 0.3f * cam->up[i];
    }
    sr_light_default(&lights[0], key);
    sr_light_default(&lights[1], fill);
    for (i = 0; i < 3; i++) {
        lights[0].diffuse[i] = 0.85f; lights[0].specular[i] = 0.6f;
        lights[1].diffuse[i] = 0.3f; lights[1].specular[i] = 0.0f; lights[1].ambient[i] = 0.0f;
    }
    sr_draw_desc_default(&d);
    d.positions = mesh->positions; d.vertex_count = mesh->vertex_count;
    d.indices = mesh->indices; d.triangle_count = mesh->triangle_count;
    d.normals = normals;
    d.shading = a->shading;
    d.lights = lights; d.light_count = 2;
    d.material.diffuse[0] = 0.75f; d.material.diffuse[1] = 0.72f; d.material.diffuse[2] = 0.68f;
    d.material.ambient[0] = 0.75f; d.material.ambient[1] = 0.72f; d.material.ambient[2] = 0.68f;
    d.wireframe = a->wire;
    d.wire_color[0] = 0.1f; d.wire_color[1] = 0.1f; d.wire_color[2] = 0.15f;
    return sr_draw_mesh(fb, cam, &d);
}

int main(int argc, char **argv)
{
    args a;
    mio_mesh mesh;
    mio_error err;
    mio_result mr;
    sr_framebuffer fb;
    sr_camera cam;
    sr_result r;
    float *normals, bg[4] = {0.93f, 0.94f, 0.96f, 1.0f};
    int status = parse_args(argc, argv, &a), saved;
    if (status >= 0) return status;
    errno = 0;
    mr = mio_read_file(a.in, NULL, &mesh, &err);
    saved = errno;
    if (mr != MIO_OK) {
        cli_read_error("render_mesh", a.in, err.message, mio_result_string(mr), mio_result_description(mr), mr == MIO_ERR_IO ? saved : 0);
        return 1;
    }
    normalize_mesh(&mesh);
    frame_camera(&mesh, &a, &cam);
    normals = (float *)malloc(mesh.vertex_count * 3 * sizeof(float) + 1);
    if (!normals) { fprintf(stderr, "render_mesh: out of memory\n"); mio_free_mesh(&mesh); return 1; }
    sr_compute_vertex_normals(mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count, normals);
    if ((r = sr_framebuffer_create(&fb, a.W, a.H, NULL)) != SR_OK) {
        char context[64];
        snprintf(context, sizeof context, "%dx%d framebuffer", a.W, a.H);
        cli_result_error("render_mesh", context, sr_result_string(r), 0);
        free(normals); mio_free_mesh(&mesh); return 1;
    }
    sr_framebuffer_clear(&fb, bg, 1.0f);
    r = draw(&fb, &cam, &mesh, normals, &a);
    if (r != SR_OK) cli_result_error("render_mesh", a.in, sr_result_string(r), 0);
    status = r == SR_OK ? write_png(&fb, a.out) : 1;
    if (status == 0) fprintf(stderr, "render_mesh: %s: %zu triangles -> %s (%dx%d)\n", a.in, mesh.triangle_count, a.out, a.W, a.H);
    sr_framebuffer_free(&fb);
    free(normals);
    mio_free_mesh(&mesh);
    return status;
}
