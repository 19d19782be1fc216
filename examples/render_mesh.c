/* render_mesh - renders any mesh file that meshio.h reads (OBJ, OFF, PLY, STL) to a PNG.

   usage: render_mesh IN -o OUT.png [--view NAME|AZ,EL] [--wire] [--size W[xH]] [--shading S]
     --view    iso (default), front, back, left, right, top, bottom, or azimuth,elevation in
               degrees (azimuth around +y from +z, elevation above the xz plane)
     --wire    draw the triangle edges over the shading
     --size    image size in pixels (default 800x800)
     --shading phong (default), gouraud or flat
     --ortho   orthographic instead of perspective projection
   The camera frames the mesh's bounding sphere; one directional key light from the upper left
   of the viewer plus a dim fill light; area-weighted vertex normals.
   Exit status 0 on success, 1 on bad arguments or unreadable input, 2 on render/write failure. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

#define MIO_IMPLEMENTATION
#include "meshio.h"
#define SR_IMPLEMENTATION
#include "render.h"

static void usage(FILE *to)
{
    fprintf(to, "usage: render_mesh IN -o OUT.png [--view iso|front|back|left|right|top|bottom|AZ,EL] [--wire]\n"
                "                   [--size W[xH]] [--shading phong|gouraud|flat] [--ortho]\n");
}

static int parse_view(const char *s, float *az, float *el)
{
    static const struct { const char *name; float az, el; } views[] = {
        {"iso", 35.0f, 25.0f}, {"front", 0.0f, 0.0f}, {"back", 180.0f, 0.0f}, {"left", -90.0f, 0.0f},
        {"right", 90.0f, 0.0f}, {"top", 0.0f, 89.9f}, {"bottom", 0.0f, -89.9f}};
    size_t i;
    char *end;
    for (i = 0; i < sizeof views / sizeof views[0]; i++)
        if (strcmp(s, views[i].name) == 0) { *az = views[i].az; *el = views[i].el; return 1; }
    *az = strtof(s, &end);
    if (end == s || *end != ',') return 0;
    s = end + 1;
    *el = strtof(s, &end);
    return end != s && *end == '\0' && *el > -90.0f && *el < 90.0f;
}

int main(int argc, char **argv)
{
    const char *in = NULL, *out = NULL;
    float az = 35.0f, el = 25.0f, lo[3], hi[3], c[3], radius = 0.0f, eye[3], dir[3];
    int wire = 0, W = 800, H = 800, ortho = 0, i;
    sr_shading shading = SR_SHADE_PHONG;
    mio_mesh mesh;
    mio_error err;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    sr_light lights[2];
    sr_result r;
    float *normals, bg[4] = {0.93f, 0.94f, 0.96f, 1.0f}, key[3], fill[3];
    size_t v;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) out = argv[++i];
        else if (strcmp(argv[i], "--wire") == 0) wire = 1;
        else if (strcmp(argv[i], "--ortho") == 0) ortho = 1;
        else if (strcmp(argv[i], "--view") == 0 && i + 1 < argc) {
            if (!parse_view(argv[++i], &az, &el)) { fprintf(stderr, "render_mesh: bad --view %s\n", argv[i]); return 1; }
        } else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc) {
            int n = sscanf(argv[++i], "%dx%d", &W, &H);
            if (n == 1) H = W;
            if (n < 1 || W < 1 || H < 1 || W > 16384 || H > 16384) { fprintf(stderr, "render_mesh: bad --size %s\n", argv[i]); return 1; }
        } else if (strcmp(argv[i], "--shading") == 0 && i + 1 < argc) {
            const char *s = argv[++i];
            if (strcmp(s, "phong") == 0) shading = SR_SHADE_PHONG;
            else if (strcmp(s, "gouraud") == 0) shading = SR_SHADE_GOURAUD;
            else if (strcmp(s, "flat") == 0) shading = SR_SHADE_FLAT;
            else { fprintf(stderr, "render_mesh: bad --shading %s\n", s); return 1; }
        } else if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) { usage(stdout); return 0; }
        else if (argv[i][0] != '-' && !in) in = argv[i];
        else { usage(stderr); return 1; }
    }
    if (!in || !out) { usage(stderr); return 1; }
    if (mio_read_file(in, NULL, &mesh, &err) != MIO_OK) {
        fprintf(stderr, "render_mesh: %s: %s\n", in, err.message);
        return 1;
    }
    /* bounding sphere (box centre, farthest vertex) */
    for (i = 0; i < 3; i++) { lo[i] = mesh.positions[i]; hi[i] = mesh.positions[i]; }
    for (v = 0; v < mesh.vertex_count; v++)
        for (i = 0; i < 3; i++) {
            float x = mesh.positions[3 * v + (size_t)i];
            if (x < lo[i]) lo[i] = x;
            if (x > hi[i]) hi[i] = x;
        }
    for (i = 0; i < 3; i++) c[i] = 0.5f * (lo[i] + hi[i]);
    for (v = 0; v < mesh.vertex_count; v++) {
        const float *p = mesh.positions + 3 * v;
        float dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2], r2 = sqrtf(dx * dx + dy * dy + dz * dz);
        if (r2 > radius) radius = r2;
    }
    if (!(radius > 0.0f)) radius = 1.0f;
    dir[0] = cosf(el * 0.0174533f) * sinf(az * 0.0174533f);
    dir[1] = sinf(el * 0.0174533f);
    dir[2] = cosf(el * 0.0174533f) * cosf(az * 0.0174533f);
    {
        float fov = 35.0f, dist = radius / sinf(0.5f * fov * 0.0174533f) * 1.05f, aspect = (float)W / (float)H;
        if (aspect < 1.0f) dist /= aspect;
        for (i = 0; i < 3; i++) eye[i] = c[i] + dir[i] * dist;
        if (ortho) sr_camera_ortho(&cam, eye, c, NULL, radius * 1.05f * (aspect < 1.0f ? 1.0f / aspect : 1.0f), aspect, dist - radius * 1.1f, dist + radius * 1.1f);
        else sr_camera_look_at(&cam, eye, c, NULL, fov, aspect, (dist - radius * 1.1f) > dist * 0.01f ? dist - radius * 1.1f : dist * 0.01f, dist + radius * 1.1f);
    }
    normals = (float *)malloc(mesh.vertex_count * 3 * sizeof(float) + 1);
    if (!normals) { fprintf(stderr, "render_mesh: out of memory\n"); mio_free_mesh(&mesh); return 2; }
    sr_compute_vertex_normals(mesh.positions, mesh.vertex_count, mesh.indices, mesh.triangle_count, normals);
    for (i = 0; i < 3; i++) { key[i] = -cam.forward[i] + 0.6f * cam.up[i] - 0.5f * cam.right[i]; fill[i] = -cam.forward[i] + 0.8f * cam.right[i] - 0.3f * cam.up[i]; }
    sr_light_default(&lights[0], key);
    sr_light_default(&lights[1], fill);
    for (i = 0; i < 3; i++) { lights[0].diffuse[i] = 0.85f; lights[0].specular[i] = 0.6f; lights[1].diffuse[i] = 0.3f; lights[1].specular[i] = 0.0f; lights[1].ambient[i] = 0.0f; }
    if ((r = sr_framebuffer_create(&fb, W, H, NULL)) != SR_OK) {
        fprintf(stderr, "render_mesh: framebuffer: %s\n", sr_result_string(r));
        free(normals); mio_free_mesh(&mesh); return 2;
    }
    sr_framebuffer_clear(&fb, bg, 1.0f);
    sr_draw_desc_default(&d);
    d.positions = mesh.positions; d.vertex_count = mesh.vertex_count;
    d.indices = mesh.indices; d.triangle_count = mesh.triangle_count;
    d.normals = normals;
    d.shading = shading;
    d.lights = lights; d.light_count = 2;
    d.material.diffuse[0] = 0.75f; d.material.diffuse[1] = 0.72f; d.material.diffuse[2] = 0.68f;
    d.material.ambient[0] = 0.75f; d.material.ambient[1] = 0.72f; d.material.ambient[2] = 0.68f;
    d.wireframe = wire;
    d.wire_color[0] = 0.1f; d.wire_color[1] = 0.1f; d.wire_color[2] = 0.15f;
    r = sr_draw_mesh(&fb, &cam, &d);
    if (r == SR_OK) r = sr_write_framebuffer_png(&fb, out, 0);
    if (r != SR_OK) fprintf(stderr, "render_mesh: %s: %s\n", out, sr_result_string(r));
    else fprintf(stderr, "render_mesh: %s: %zu triangles -> %s (%dx%d)\n", in, mesh.triangle_count, out, W, H);
    sr_framebuffer_free(&fb);
    free(normals);
    mio_free_mesh(&mesh);
    return r == SR_OK ? 0 : 2;
}
