/* dispmesh - paper 000's representation end to end: a base mesh plus one displacement map.

   usage: dispmesh IN|--brick [--faces N] [--res R] [-o PREFIX] [--no-views] [--size S] [--both-ways] [--strict]
                  [--min-quality Q] [--samples N]
     IN          any mesh file meshio.h reads (OBJ, OFF, PLY, STL), a closed manifold works best
     --brick     instead of IN: a generated 2 x 1 x 1 brick with V grooves pressed inward (paper
                 Fig 5.1.1), 496 triangles, closed and oriented outward; --faces 12 gives its box
     --faces N   base mesh triangles to aim for (default 500)
     --res R     displacement map R x R texels (default 512, 8..16384)
     -o PREFIX   output prefix (default out/dispmesh); the prefix's directory is created if missing
     --no-views  skip the rendering of PREFIX_views.png
     --size S    size in pixels of each of the three views (default 400)
     --both-ways bake with the nearest hit either way along the normal; the default is the paper's
                 rule, the first hit along -normal (dm_bake_options.inward), right for a base that
                 encloses the original, as the shell constraint makes it
     --strict    the paper's constraints only: stop where they veto every collapse left. By
                 default, where the shell is too thin for an enclosing base the constraint is
                 relaxed there (dm_shell_relax: a vetoed collapse is done relaxed once it is 16
                 times cheaper than the strict ones left, and everywhere if the target is still
                 not reached): the base may cross the original, and its triangles there are
                 baked both ways. RESULT's fallback_region= is the share of the original's area
                 over them (by the coverage weights), fallback= the share where the base then
                 lies inside the original (texels of negative depth, each triangle's share of
                 its weight), the part of the surface that needs the signed displacement.
                 --fallback names the default.
     --min-quality Q  the constrained simplifier's sliver guard (dm_simplify_options.min_quality,
                 2 area / longest edge^2; default 0.05: without it, the constraint's vetoes leave
                 knots of slivers that the parameterization stretches; the unconstrained
                 reference base never has one)
     --samples N the surface distances' area-uniform samples per side (default 200000; fewer
                 run faster, the RMS figures to about 1/sqrt(N), the max from fewer points)
   The pipeline (dispmesh.h): vertices at equal positions joined where they close a seam (an STL
   soup is welded whole; vertices that meet only at a point stay apart, said on stderr),
   triangles that repeat another's corners dropped (said on stderr), dm_orient (triangles turned to agree with their neighbours, counted on stderr), dm_shell_grow
   (the bounding shell of the original), dm_simplify with dm_shell_constraint down to N triangles
   (the base), dm_coverage_weights + dm_parameterize (an R x R map), dm_bake (displacement along
   the base normals), dm_reconstruct (base + map as a dense mesh) and dm_surface_distance
   (--samples points a side) against the original.
   Writes
     PREFIX_base.obj     the base mesh with its map coordinates (v, vt, f v/vt; vt v = 0 is the
                         map's row 0, which is the bottom row of the PFM and of the PNG)
     PREFIX_disp.pfm     the displacement, 1 channel, world units along -normal (positive inward)
     PREFIX_normal.png   the original's normals at the hits, n * 0.5 + 0.5 (gutter texels black)
     PREFIX_recon.obj    the reconstruction, with the map's normals (shade with them)
     PREFIX_views.png    original | base with wireframe | reconstruction, one camera, captions
   Progress goes to stderr; the last line on stdout is
     RESULT dispmesh target= faces= fallback= fallback_region= res= rms= max= base_only_rms= base_only_max=
            unconstrained_rms= equal_bytes_rms= equal_bytes_max= flagged= bake_ms= total_ms=
   with distances as fractions of the original's bounding-box diagonal (see print_result).
   The stage notes say which constraint vetoed how many collapses (enclosure, shell, overlap) and
   whether the target was reached; RESULT's target= is --faces and faces= what was reached. A
   note says when the input runs through itself (its edges that pass through its triangles).
   Exit status (as every program in examples/): 0 done; 1 failure: unreadable input, a stage
   failed, a failed write, or the result is unusable: base triangles without a texel (the map is
   too coarse for the base; the reconstruction would have holes) or more than 1% of the texels
   under the base without a hit; 2 usage (a bad argument, named in the message). Every file is
   written to NAME.tmp and all are renamed once all are complete, so a failed run leaves none of
   them (and an existing file unchanged). --version prints the version. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define MIO_IMPLEMENTATION
#include "meshio.h"
#define SR_IMPLEMENTATION
#include "render.h"
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#define DISPMESH_VERSION "dispmesh 0.3 (dispmesh.h, meshio.h, render.h)"

/* A mesh this program owns (malloc) or borrows. */
typedef struct mesh {
    float *p;
    size_t nv;
    uint32_t *t;
    size_t nt;
} mesh;

/* Everything allocated by one run, freed by run_free on every path. */
typedef struct run {
    mio_mesh loaded;
    mesh orig;                 /* = loaded's arrays, or the generated brick (owned) */
    int orig_owned;
    dm_shell *shell;
    dm_pm *pm, *pm_free;       /* constrained (the base), unconstrained (same count, then equal bytes) */
    mesh base, free_same, free_bytes;
    float *weights;
    uint8_t *both_ways;        /* per base triangle: in the fallback region (bake both ways) */
    size_t fallback_triangles;
    dm_param *param;
    dm_dispmap *map;
    dm_trimesh *dense;
} run;

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* ---- progress on stderr: "dispmesh: stage ... 10% 20% ... 100% (12 ms)" ---------------------- */

typedef struct stage {
    const char *name;
    int tenths;                /* last tenth printed */
    double start;
} stage;

static void stage_begin(stage *s, const char *name)
{
    s->name = name;
    s->tenths = -1;
    s->start = now_ms();
    fprintf(stderr, "dispmesh: %-26s", name);
    fflush(stderr);
}

static int stage_progress(void *user, float done)
{
    stage *s = (stage *)user;
    int k = done >= 1.0f ? 10 : done > 0.0f ? (int)(done * 10.0f) : 0;
    if (k > s->tenths) {
        s->tenths = k;
        fprintf(stderr, " %d%%", 10 * k);
        fflush(stderr);
    }
    return 0;
}

/* one of four equal parts of a stage */
typedef struct quarter {
    stage *st;
    int k;
} quarter;

static int quarter_progress(void *user, float done)
{
    quarter *q = (quarter *)user;
    return stage_progress(q->st, 0.25f * ((float)q->k + done));
}

static void stage_end(stage *s, const char *note)
{
    if (s->tenths < 10) stage_progress(s, 1.0f);
    fprintf(stderr, "  (%.0f ms)%s%s\n", now_ms() - s->start, note && *note ? "  " : "", note ? note : "");
}

static void stage_fail(stage *s, const char *what, dm_result r)
{
    char context[96];
    snprintf(context, sizeof context, "%s failed", what ? what : s->name);
    fprintf(stderr, "\n");
    cli_result_error("dispmesh", context, dm_result_string(r), 0);
}

/* "dispmesh: PATH: cannot write it: SR_ERR_IO (meaning): the system's reason" */
static void write_failed(const char *path, sr_result r, int saved_errno)
{
    fprintf(stderr, "\n");
    cli_result_error("dispmesh", path, sr_result_string(r), r == SR_ERR_IO ? saved_errno : 0);
}

/* ---- the generated brick ----------------------------------------------------------------------
   A 2 x 1 x 1 box whose surface is a grid on three sets of axis lines (so that the faces share
   their edges), with V grooves pressed inward: rings around the brick at x = 2/3 and 4/3 and a ring
   at y = 1/2 around the ends and the long sides. A vertex on a groove's centre line moves inward
   by the groove depth along the normal of every box face it lies on, so the box encloses it all.
   Faces are counter-clockwise seen from outside. 11 x 7 x 5 axis lines: 4 (10*6 + 10*4 + 6*4) =
   496 triangles. The grooves are 0.24 wide and 0.03 deep: with the default shell (2% of the
   diagonal, 0.049) the constrained simplifier reaches the 12-face box. Deeper or narrower V
   grooves (0.05 deep and 0.09 wide stopped it at 130 faces) stop the growth of the shell at their
   bottom, and the box over the groove then lies outside the shell. */
static int make_brick(mesh *m)
{
    static const float xs[] = {0.0f, 0.3f, 0.5467f, 0.6667f, 0.7867f, 1.0f, 1.2133f, 1.3333f, 1.4533f, 1.7f, 2.0f};
    static const float ys[] = {0.0f, 0.22f, 0.38f, 0.5f, 0.62f, 0.78f, 1.0f};
    static const float zs[] = {0.0f, 0.25f, 0.5f, 0.75f, 1.0f};
    const int n[3] = {11, 7, 5};
    const float depth = 0.03f;
    int *id, i, j, k, a, nv = 0, nt = 0;
    size_t cells = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
    memset(m, 0, sizeof *m);
    id = (int *)malloc(cells * sizeof(int));
    m->p = (float *)malloc(cells * 3 * sizeof(float));
    /* 2 sides x 2 triangles a cell x 3 indices, over the three face pairs */
    m->t = (uint32_t *)malloc((size_t)12 * (size_t)((n[0] - 1) * (n[1] - 1) + (n[1] - 1) * (n[2] - 1) + (n[2] - 1) * (n[0] - 1)) *
                              sizeof(uint32_t));
    if (!id || !m->p || !m->t) { free(id); free(m->p); free(m->t); memset(m, 0, sizeof *m); return 0; }
    for (i = 0; i < n[0]; i++)
        for (j = 0; j < n[1]; j++)
            for (k = 0; k < n[2]; k++) {
                int g[3], on_face = 0, groove;
                float *p;
                g[0] = i; g[1] = j; g[2] = k;
                for (a = 0; a < 3; a++) on_face |= (g[a] == 0 || g[a] == n[a] - 1);
                id[((size_t)i * (size_t)n[1] + (size_t)j) * (size_t)n[2] + (size_t)k] = on_face ? nv : -1;
                if (!on_face) continue;
                p = m->p + 3 * (size_t)nv++;
                p[0] = xs[i]; p[1] = ys[j]; p[2] = zs[k];
                groove = (i == 3 || i == 7 || j == 3);
                if (!groove) continue;
                for (a = 0; a < 3; a++) {
                    if (g[a] == 0) p[a] += depth;
                    else if (g[a] == n[a] - 1) p[a] -= depth;
                }
            }
    /* faces: normal +-e_a, in-plane axes b, c with e_b x e_c = e_a */
    for (a = 0; a < 3; a++) {
        int b = (a + 1) % 3, c = (a + 2) % 3, side;
        for (side = 0; side < 2; side++) {
            int u, v;
            for (u = 0; u + 1 < n[b]; u++)
                for (v = 0; v + 1 < n[c]; v++) {
                    int q[4], corner, g[3];
                    static const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
                    for (corner = 0; corner < 4; corner++) {
                        g[a] = side ? n[a] - 1 : 0;
                        g[b] = u + du[corner];
                        g[c] = v + dv[corner];
                        q[corner] = id[((size_t)g[0] * (size_t)n[1] + (size_t)g[1]) * (size_t)n[2] + (size_t)g[2]];
                    }
                    if (side) { /* +e_a: counter-clockwise in (b, c) */
                        uint32_t *t = m->t + 3 * (size_t)nt;
                        t[0] = (uint32_t)q[0]; t[1] = (uint32_t)q[1]; t[2] = (uint32_t)q[2];
                        t[3] = (uint32_t)q[0]; t[4] = (uint32_t)q[2]; t[5] = (uint32_t)q[3];
                    } else {
                        uint32_t *t = m->t + 3 * (size_t)nt;
                        t[0] = (uint32_t)q[0]; t[1] = (uint32_t)q[2]; t[2] = (uint32_t)q[1];
                        t[3] = (uint32_t)q[0]; t[4] = (uint32_t)q[3]; t[5] = (uint32_t)q[2];
                    }
                    nt += 2;
                }
        }
    }
    free(id);
    m->nv = (size_t)nv;
    m->nt = (size_t)nt;
    return 1;
}

/* ---- small helpers ---------------------------------------------------------------------------- */

static void mesh_free(mesh *m)
{
    free(m->p);
    free(m->t);
    memset(m, 0, sizeof *m);
}

static double bbox_diagonal(const mesh *m, float lo[3], float hi[3])
{
    size_t v;
    int i;
    for (i = 0; i < 3; i++) { lo[i] = INFINITY; hi[i] = -INFINITY; }
    for (v = 0; v < m->nt * 3; v++) {
        const float *p = m->p + 3 * (size_t)m->t[v];
        for (i = 0; i < 3; i++) {
            if (p[i] < lo[i]) lo[i] = p[i];
            if (p[i] > hi[i]) hi[i] = p[i];
        }
    }
    return sqrt((double)(hi[0] - lo[0]) * (hi[0] - lo[0]) + (double)(hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (double)(hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* The current level of a progressive mesh as an owned mesh. */
static int pm_to_mesh(dm_pm *pm, mesh *m)
{
    dm_pm_counts(pm, &m->nv, &m->nt);
    m->p = (float *)malloc(m->nv * 3 * sizeof(float) + 1);
    m->t = (uint32_t *)malloc(m->nt * 3 * sizeof(uint32_t) + 1);
    if (!m->p || !m->t) { mesh_free(m); return 0; }
    dm_pm_get_mesh(pm, m->p, m->t, NULL);
    return 1;
}

/* Creates the directory part of a prefix when it does not exist (one level). */
static void make_parent_dir(const char *prefix)
{
    char dir[4096];
    const char *slash = strrchr(prefix, '/');
    size_t n;
    struct stat st;
    if (!slash || slash == prefix) return;
    n = (size_t)(slash - prefix);
    if (n >= sizeof dir) return;
    memcpy(dir, prefix, n);
    dir[n] = '\0';
    if (stat(dir, &st) != 0) mkdir(dir, 0777); /* a failure shows up when the files are written */
}

static char *path_with(const char *prefix, const char *suffix)
{
    size_t a = strlen(prefix), b = strlen(suffix);
    char *s = (char *)malloc(a + b + 1);
    if (!s) return NULL;
    memcpy(s, prefix, a);
    memcpy(s + a, suffix, b + 1);
    return s;
}

/* 1 when PREFIX_base.obj.tmp can be created (the probe's file is removed again; an existing
   PREFIX_base.obj is not touched). */
static int probe_writable(const char *prefix)
{
    char *path = path_with(prefix, "_base.obj.tmp");
    FILE *f;
    if (!path) { fprintf(stderr, "dispmesh: out of memory\n"); return 0; }
    f = fopen(path, "w");
    if (!f) {
        cli_file_error("dispmesh", path, "cannot create it", errno);
        free(path);
        return 0;
    }
    fclose(f);
    remove(path);
    free(path);
    return 1;
}

/* ---- the base mesh's map coordinates: distinct (vertex, u, v) corners ------------------------- */

typedef struct uvkey {
    uint32_t vertex;
    float u, v;
    uint32_t corner;
} uvkey;

static int uvkey_cmp(const void *pa, const void *pb)
{
    const uvkey *a = (const uvkey *)pa, *b = (const uvkey *)pb;
    if (a->vertex != b->vertex) return a->vertex < b->vertex ? -1 : 1;
    if (a->u != b->u) return a->u < b->u ? -1 : 1;
    if (a->v != b->v) return a->v < b->v ? -1 : 1;
    return a->corner < b->corner ? -1 : a->corner > b->corner;
}

/* corner_uv[c] receives the index of corner c's distinct UV; returns the count (0 on failure). */
static size_t distinct_uvs(const mesh *base, const dm_param *param, uint32_t *corner_uv, float *uv_out)
{
    size_t n = base->nt * 3, c, count = 0;
    uvkey *k = (uvkey *)malloc(n * sizeof(uvkey) + 1);
    if (!k) return 0;
    for (c = 0; c < n; c++) {
        k[c].vertex = base->t[c];
        k[c].u = param->uv[2 * c];
        k[c].v = param->uv[2 * c + 1];
        k[c].corner = (uint32_t)c;
    }
    qsort(k, n, sizeof *k, uvkey_cmp);
    for (c = 0; c < n; c++) {
        if (c == 0 || k[c].vertex != k[c - 1].vertex || k[c].u != k[c - 1].u || k[c].v != k[c - 1].v) {
            if (uv_out) { uv_out[2 * count] = k[c].u; uv_out[2 * count + 1] = k[c].v; }
            count++;
        }
        corner_uv[k[c].corner] = (uint32_t)(count - 1);
    }
    free(k);
    return count;
}

/* ---- writers ---------------------------------------------------------------------------------- */

/* The base as OBJ with its map coordinates (meshio.h writes positions only). */
static int write_base_obj(const char *path, const char *tmp, const mesh *base, const dm_param *param, size_t *uv_count)
{
    uint32_t *cuv = (uint32_t *)malloc(base->nt * 3 * sizeof(uint32_t) + 1);
    float *uv = (float *)malloc(base->nt * 6 * sizeof(float) + 1);
    size_t n = 0, i;
    FILE *f = NULL;
    int ok = 0, saved;
    if (!cuv || !uv) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
    n = distinct_uvs(base, param, cuv, uv);
    if (n == 0) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
    *uv_count = n;
    f = fopen(tmp, "w");
    if (!f) { fprintf(stderr, "\n"); cli_file_error("dispmesh", path, "cannot create it", errno); goto done; }
    errno = 0;
    fprintf(f, "# dispmesh base mesh: %zu vertices, %zu triangles, %zu map coordinates (%d x %d map)\n",
            base->nv, base->nt, n, param->width, param->height);
    for (i = 0; i < base->nv; i++)
        fprintf(f, "v %.9g %.9g %.9g\n", base->p[3 * i], base->p[3 * i + 1], base->p[3 * i + 2]);
    for (i = 0; i < n; i++) fprintf(f, "vt %.9g %.9g\n", uv[2 * i], uv[2 * i + 1]);
    for (i = 0; i < base->nt; i++)
        fprintf(f, "f %u/%u %u/%u %u/%u\n", base->t[3 * i] + 1, cuv[3 * i] + 1, base->t[3 * i + 1] + 1,
                cuv[3 * i + 1] + 1, base->t[3 * i + 2] + 1, cuv[3 * i + 2] + 1);
    ok = !ferror(f);
    saved = errno;
    if (fclose(f) != 0 && ok) { ok = 0; saved = errno; }
    if (!ok) { fprintf(stderr, "\n"); cli_file_error("dispmesh", path, "writing failed", saved); }
done:
    free(cuv);
    free(uv);
    return ok;
}

static int write_normal_png(const char *path, const char *tmp, const dm_dispmap *map)
{
    size_t n = (size_t)map->width * (size_t)map->height, i;
    uint8_t *px = (uint8_t *)malloc(n * 3 + 1);
    sr_result r;
    int c;
    if (!px) { fprintf(stderr, "\ndispmesh: out of memory\n"); return 0; }
    for (i = 0; i < n; i++)
        for (c = 0; c < 3; c++) {
            float x = map->normal[3 * i + (size_t)c] * 0.5f + 0.5f;
            if (map->status[i] == DM_TEXEL_EMPTY || !(x == x)) x = 0.0f;
            px[3 * i + (size_t)c] = (uint8_t)(x <= 0.0f ? 0 : x >= 1.0f ? 255 : (int)(x * 255.0f + 0.5f));
        }
    errno = 0;
    r = sr_write_png(tmp, px, map->width, map->height, 3, 1); /* row 0 (v = 0) at the bottom */
    if (r != SR_OK) write_failed(path, r, errno);
    free(px);
    return r == SR_OK;
}

/* ---- views ------------------------------------------------------------------------------------ */

typedef struct view {
    sr_camera cam;
    sr_light lights[2];
    int size;
} view;

/* One iso camera framing the original's bounding sphere, as render_mesh does. */
static void view_setup(view *vw, const mesh *orig, int size)
{
    float lo[3], hi[3], c[3], radius = 0.0f, eye[3], dir[3], key[3], fill[3], dist;
    const float az = 35.0f * 0.0174533f, el = 25.0f * 0.0174533f, fov = 35.0f;
    size_t v;
    int i;
    bbox_diagonal(orig, lo, hi);
    for (i = 0; i < 3; i++) c[i] = 0.5f * (lo[i] + hi[i]);
    for (v = 0; v < orig->nt * 3; v++) {
        const float *p = orig->p + 3 * (size_t)orig->t[v];
        float dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2], r = sqrtf(dx * dx + dy * dy + dz * dz);
        if (r > radius) radius = r;
    }
    if (!(radius > 0.0f)) radius = 1.0f;
    dir[0] = cosf(el) * sinf(az);
    dir[1] = sinf(el);
    dir[2] = cosf(el) * cosf(az);
    dist = radius / sinf(0.5f * fov * 0.0174533f) * 1.05f;
    for (i = 0; i < 3; i++) eye[i] = c[i] + dir[i] * dist;
    sr_camera_look_at(&vw->cam, eye, c, NULL, fov, 1.0f, (dist - radius * 1.1f) > dist * 0.01f ? dist - radius * 1.1f : dist * 0.01f,
                      dist + radius * 1.1f);
    for (i = 0; i < 3; i++) {
        key[i] = -vw->cam.forward[i] + 0.6f * vw->cam.up[i] - 0.5f * vw->cam.right[i];
        fill[i] = -vw->cam.forward[i] + 0.8f * vw->cam.right[i] - 0.3f * vw->cam.up[i];
    }
    sr_light_default(&vw->lights[0], key);
    sr_light_default(&vw->lights[1], fill);
    for (i = 0; i < 3; i++) {
        vw->lights[0].diffuse[i] = 0.85f; vw->lights[0].specular[i] = 0.5f;
        vw->lights[1].diffuse[i] = 0.3f; vw->lights[1].specular[i] = 0.0f; vw->lights[1].ambient[i] = 0.0f;
    }
    vw->size = size;
}

/* Renders a mesh into img (RGB, allocated here). smooth: the mesh's own vertex normals when it has
   them (the reconstruction's come from the map, as a renderer of base + map shades it), else
   area-weighted vertex normals; not smooth: face normals. wire: wireframe overlay. */
static sr_result view_render(const view *vw, const float *p, size_t nv, const uint32_t *t, size_t nt, int smooth,
                             const float *own_normals, int wire, const float rgb[3], sr_image8 *img)
{
    sr_framebuffer fb;
    sr_draw_desc d;
    float bg[4] = {0.93f, 0.94f, 0.96f, 1.0f}, *normals = NULL;
    sr_result r;
    int i;
    memset(img, 0, sizeof *img);
    if (smooth) {
        normals = (float *)malloc(nv * 3 * sizeof(float) + 1);
        if (!normals) return SR_ERR_OUT_OF_MEMORY;
        if (own_normals) memcpy(normals, own_normals, nv * 3 * sizeof(float));
        else if ((r = sr_compute_vertex_normals(p, nv, t, nt, normals)) != SR_OK) { free(normals); return r; }
    }
    if ((r = sr_framebuffer_create(&fb, vw->size, vw->size, NULL)) != SR_OK) { free(normals); return r; }
    sr_framebuffer_clear(&fb, bg, 1.0f);
    sr_draw_desc_default(&d);
    d.positions = p; d.vertex_count = nv; d.indices = t; d.triangle_count = nt;
    d.normals = normals;
    d.lights = vw->lights; d.light_count = 2;
    for (i = 0; i < 3; i++) { d.material.diffuse[i] = rgb[i]; d.material.ambient[i] = rgb[i]; }
    d.wireframe = wire;
    d.wire_color[0] = 0.1f; d.wire_color[1] = 0.1f; d.wire_color[2] = 0.15f;
    d.wire_width = 1.5f;
    r = sr_draw_mesh(&fb, &vw->cam, &d);
    if (r == SR_OK) {
        img->pixels = (uint8_t *)malloc((size_t)vw->size * (size_t)vw->size * 3);
        if (!img->pixels) r = SR_ERR_OUT_OF_MEMORY;
        else {
            img->width = img->height = vw->size;
            img->channels = 3;
            sr_framebuffer_to_rgb8(&fb, img->pixels, 3);
        }
    }
    sr_framebuffer_free(&fb);
    free(normals);
    return r;
}

static int write_views(const char *path, const char *tmp, const run *R, int size, int smooth, double rms)
{
    static const float grey[3] = {0.75f, 0.72f, 0.68f}, blue[3] = {0.55f, 0.65f, 0.80f}, warm[3] = {0.80f, 0.68f, 0.55f};
    view vw;
    sr_image8 img[3], sheet;
    char cap[3][96];
    const char *caps[3];
    sr_result r;
    int i, ok = 0;
    memset(img, 0, sizeof img);
    memset(&sheet, 0, sizeof sheet);
    view_setup(&vw, &R->orig, size);
    r = view_render(&vw, R->orig.p, R->orig.nv, R->orig.t, R->orig.nt, smooth, NULL, 0, grey, &img[0]);
    if (r == SR_OK) r = view_render(&vw, R->base.p, R->base.nv, R->base.t, R->base.nt, 0, NULL, 1, blue, &img[1]);
    if (r == SR_OK)
        r = view_render(&vw, R->dense->positions, R->dense->vertex_count, R->dense->indices, R->dense->triangle_count, smooth,
                        R->dense->normals, 0, warm, &img[2]);
    if (r != SR_OK) { fprintf(stderr, "\n"); cli_result_error("dispmesh", "rendering the views", sr_result_string(r), 0); goto done; }
    snprintf(cap[0], sizeof cap[0], "ORIGINAL %zu TRIANGLES", R->orig.nt);
    snprintf(cap[1], sizeof cap[1], "BASE %zu TRIANGLES", R->base.nt);
    snprintf(cap[2], sizeof cap[2], "BASE + %dX%d MAP RMS %.3f%%", R->map->width, R->map->height, 100.0 * rms);
    for (i = 0; i < 3; i++) caps[i] = cap[i];
    r = sr_contact_sheet(img, caps, 3, 3, NULL, &sheet);
    errno = 0;
    if (r == SR_OK) r = sr_write_png(tmp, sheet.pixels, sheet.width, sheet.height, 3, 0);
    if (r != SR_OK) { write_failed(path, r, errno); goto done; }
    ok = 1;
done:
    for (i = 0; i < 3; i++) free(img[i].pixels);
    sr_free(NULL, sheet.pixels);
    return ok;
}

/* ---- the pipeline ----------------------------------------------------------------------------- */

static void run_free(run *R)
{
    dm_trimesh_free(R->dense);
    dm_dispmap_free(R->map); /* before the dm_param: it shares its neighbour arrays */
    dm_param_free(R->param);
    free(R->weights);
    free(R->both_ways);
    mesh_free(&R->base);
    mesh_free(&R->free_same);
    mesh_free(&R->free_bytes);
    dm_pm_free(R->pm);
    dm_pm_free(R->pm_free);
    dm_shell_free(R->shell);
    if (R->orig_owned) mesh_free(&R->orig);
    mio_free_mesh(&R->loaded);
    memset(R, 0, sizeof *R);
}

static double triangle_area(const mesh *m, size_t t)
{
    const float *a = m->p + 3 * (size_t)m->t[3 * t], *b = m->p + 3 * (size_t)m->t[3 * t + 1], *c = m->p + 3 * (size_t)m->t[3 * t + 2];
    double u[3], v[3], w[3];
    int k;
    for (k = 0; k < 3; k++) { u[k] = (double)b[k] - a[k]; v[k] = (double)c[k] - a[k]; }
    w[0] = u[1] * v[2] - u[2] * v[1]; w[1] = u[2] * v[0] - u[0] * v[2]; w[2] = u[0] * v[1] - u[1] * v[0];
    return 0.5 * sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}

/* The base triangles in the fallback region of a relaxed shell constraint (baked both ways). */
static int fallback_region(run *R)
{
    uint32_t *ids = (uint32_t *)malloc(R->base.nv * sizeof(uint32_t) + 1);
    R->both_ways = (uint8_t *)malloc(R->base.nt + 1);
    if (!ids || !R->both_ways) { free(ids); return 0; }
    dm_pm_get_mesh(R->pm, R->base.p, R->base.t, ids);
    R->fallback_triangles = dm_shell_fallback_triangles(R->shell, R->base.t, R->base.nt, ids, R->both_ways);
    free(ids);
    return 1;
}

/* The share of the original's area (by the coverage weights) where the base lies inside the
   original: of each both-ways triangle's weight, the share of its baked texels with a negative
   depth. The fallback's signed displacement is used there and nowhere else. */
static double signed_share(const run *R)
{
    size_t n = (size_t)R->map->width * (size_t)R->map->height, k, t;
    size_t *cnt = (size_t *)calloc(2 * R->base.nt + 1, sizeof(size_t));
    double all = 0.0, neg = 0.0;
    if (!cnt) return -1.0;
    for (k = 0; k < n; k++) {
        uint32_t tt = R->param->texel_triangle[k];
        if (R->map->status[k] != DM_TEXEL_HIT || tt >= R->base.nt || !R->both_ways[tt]) continue;
        cnt[2 * tt]++;
        if (R->map->disp[k] < 0.0f) cnt[2 * tt + 1]++;
    }
    for (t = 0; t < R->base.nt; t++) {
        all += R->weights[t];
        if (cnt[2 * t]) neg += R->weights[t] * (double)cnt[2 * t + 1] / (double)cnt[2 * t];
    }
    free(cnt);
    return all > 0.0 ? neg / all : 0.0;
}

/* The result is unusable when parts of the base get no texel (the map is too coarse for the base:
   the reconstruction would have holes there) or when more than 1% of the texels under the base
   find no original surface. Returns 1 when it is usable; otherwise says why. */
static int result_usable(const run *R, long res, size_t inside, size_t missed)
{
    size_t n = (size_t)R->map->width * (size_t)R->map->height, t, k, bare = 0;
    double area = 0.0, bare_area = 0.0;
    uint8_t *has = (uint8_t *)calloc(R->base.nt + 1, 1);
    if (!has) { fprintf(stderr, "dispmesh: out of memory\n"); return 0; }
    for (k = 0; k < n; k++)
        if (R->param->texel_triangle[k] < R->base.nt) has[R->param->texel_triangle[k]] = 1;
    for (t = 0; t < R->base.nt; t++) {
        double a = triangle_area(&R->base, t);
        area += a;
        if (!has[t]) { bare++; bare_area += a; }
    }
    free(has);
    if (bare_area > 0.005 * area) { /* slivers may miss every texel centre: their neighbours' texels span them */
        fprintf(stderr, "dispmesh: error: the map is too coarse for the base: %zu of %zu base triangles (%.1f%% of its area) "
                        "have no texel, so the reconstruction would have holes there; use a larger --res than %ld or fewer "
                        "--faces\n", bare, R->base.nt, 100.0 * bare_area / area, res);
        return 0;
    }
    if (missed * 100 > inside) {
        fprintf(stderr, "dispmesh: error: %zu of %zu texels under the base (%.1f%%, more than 1%%) found no surface of "
                        "the original within the search distance\n", missed, inside, 100.0 * (double)missed / (double)inside);
        return 0;
    }
    return 1;
}

/* ---- joining vertices at equal positions where they close a seam ------------------------------ */
typedef struct { float p[3]; uint32_t v; } poskey;
typedef struct { uint32_t k0, k1, a, b; } edgekey; /* sorted by (k0, k1, a, b); a -> b an edge */

static int poskey_cmp(const void *pa, const void *pb)
{
    const poskey *x = (const poskey *)pa, *y = (const poskey *)pb;
    int k;
    for (k = 0; k < 3; k++)
        if (x->p[k] != y->p[k]) return x->p[k] < y->p[k] ? -1 : 1;
    return x->v < y->v ? -1 : x->v > y->v;
}

static int edgekey_cmp(const void *pa, const void *pb)
{
    const edgekey *x = (const edgekey *)pa, *y = (const edgekey *)pb;
    if (x->k0 != y->k0) return x->k0 < y->k0 ? -1 : 1;
    if (x->k1 != y->k1) return x->k1 < y->k1 ? -1 : 1;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    return x->b < y->b ? -1 : x->b > y->b;
}

static uint32_t uf_find(uint32_t *up, uint32_t v)
{
    while (up[v] != v) v = up[v] = up[up[v]];
    return v;
}

static void uf_join(uint32_t *up, uint32_t a, uint32_t b)
{
    a = uf_find(up, a);
    b = uf_find(up, b);
    if (a < b) up[b] = a; /* the first vertex of a set represents it */
    else if (b < a) up[a] = b;
}

/* Join vertices at exactly equal positions (-0 = +0) where they close a seam: boundary edges (of
   one triangle each) whose ends lie at the same two positions become one edge. A triangle soup
   (an STL file) is so welded whole and a mesh split along seams stitched, as mio_weld would; but
   vertices at one position that meet only at a point (holes touching at a corner) stay apart:
   joined, they would make a non-manifold vertex, which dm_simplify freezes with its neighbours.
   The first vertex of each joined set stays, the kept ones in their order. Returns the number of
   vertices kept apart that a weld by position would have joined, or -1 when out of memory. */
static long stitch(mio_mesh *m)
{
    size_t nv = m->vertex_count, nt = m->triangle_count, i, j, q, ne = 0, nb = 0, kept = 0;
    poskey *pk = (poskey *)malloc((nv + 1) * sizeof *pk);
    edgekey *ek = (edgekey *)malloc((3 * nt + 1) * sizeof *ek);
    uint32_t *first = (uint32_t *)malloc((nv + 1) * sizeof *first), *up = (uint32_t *)malloc((nv + 1) * sizeof *up);
    long apart = 0;
    if (!pk || !ek || !first || !up) {
        free(pk); free(ek); free(first); free(up);
        return -1;
    }
    /* 1. each vertex's position class: the first vertex at its position */
    for (i = 0; i < nv; i++) {
        for (q = 0; q < 3; q++) pk[i].p[q] = m->positions[3 * i + q] + 0.0f; /* -0 + 0 = +0 */
        pk[i].v = (uint32_t)i;
        up[i] = (uint32_t)i;
    }
    qsort(pk, nv, sizeof *pk, poskey_cmp);
    for (i = 0; i < nv; i = j) {
        for (j = i + 1; j < nv && memcmp(pk[j].p, pk[i].p, sizeof pk[i].p) == 0; j++) {}
        for (q = i; q < j; q++) first[pk[q].v] = pk[i].v;
    }
    /* 2. the boundary edges (by vertex index, an edge of exactly one triangle), keyed by their
       ends' position classes */
    for (i = 0; i < nt; i++)
        for (j = 0; j < 3; j++) {
            uint32_t a = m->indices[3 * i + j], b = m->indices[3 * i + (j + 1) % 3];
            if (a == b) continue;
            ek[ne].k0 = a < b ? a : b;
            ek[ne].k1 = a < b ? b : a;
            ek[ne].a = a;
            ek[ne].b = b;
            ne++;
        }
    qsort(ek, ne, sizeof *ek, edgekey_cmp);
    for (i = 0; i < ne; i = j) {
        for (j = i + 1; j < ne && ek[j].k0 == ek[i].k0 && ek[j].k1 == ek[i].k1; j++) {}
        if (j == i + 1) {
            uint32_t ca = first[ek[i].a], cb = first[ek[i].b];
            ek[nb] = ek[i];
            ek[nb].k0 = ca < cb ? ca : cb;
            ek[nb].k1 = ca < cb ? cb : ca;
            nb++;
        }
    }
    /* 3. boundary edges on the same two positions close a seam: their ends are joined */
    qsort(ek, nb, sizeof *ek, edgekey_cmp);
    for (i = 0; i < nb; i = j)
        for (j = i + 1; j < nb && ek[j].k0 == ek[i].k0 && ek[j].k1 == ek[i].k1; j++) {
            if (ek[i].k0 == ek[i].k1) continue; /* both ends at one position */
            if (first[ek[i].a] == first[ek[j].a]) {
                uf_join(up, ek[i].a, ek[j].a);
                uf_join(up, ek[i].b, ek[j].b);
            } else {
                uf_join(up, ek[i].a, ek[j].b);
                uf_join(up, ek[i].b, ek[j].a);
            }
        }
    /* 4. keep each set's first vertex, in order; the triangles refer to the kept ones */
    for (i = 0; i < nv; i++) {
        uint32_t r = uf_find(up, (uint32_t)i);
        if (r != i) continue;
        apart += first[i] != i;
        memmove(m->positions + 3 * kept, m->positions + 3 * i, 3 * sizeof(float));
        first[i] = (uint32_t)kept++; /* first[] now maps a kept vertex to its new index */
    }
    for (i = 0; i < 3 * nt; i++) m->indices[i] = first[uf_find(up, m->indices[i])];
    m->vertex_count = kept;
    free(pk); free(ek); free(first); free(up);
    return apart;
}

/* Drop the triangles that repeat an earlier one's corners (in any order: a face written twice, or
   once each way), keeping the first and the order of the rest: a repeated face makes its edges
   non-manifold, which the simplifier cannot collapse across, and hides a sheet from the bake.
   Triangles with a repeated index stay (dm_simplify drops them). Returns the number dropped, or
   -1 when out of memory. */
typedef struct { uint32_t k[3], t; } trikey;
static int trikey_cmp(const void *pa, const void *pb)
{
    const trikey *x = (const trikey *)pa, *y = (const trikey *)pb;
    int i;
    for (i = 0; i < 3; i++)
        if (x->k[i] != y->k[i]) return x->k[i] < y->k[i] ? -1 : 1;
    return x->t < y->t ? -1 : x->t > y->t;
}

static long drop_repeats(mio_mesh *m)
{
    size_t nt = m->triangle_count, i, j, kept = 0;
    trikey *tk = (trikey *)malloc((nt + 1) * sizeof *tk);
    unsigned char *drop = (unsigned char *)calloc(nt + 1, 1);
    long dropped = 0;
    if (!tk || !drop) {
        free(tk); free(drop);
        return -1;
    }
    for (i = 0; i < nt; i++) { /* the corners sorted, then the triangle's index */
        uint32_t a = m->indices[3 * i], b = m->indices[3 * i + 1], c = m->indices[3 * i + 2], x;
        if (a > b) { x = a; a = b; b = x; }
        if (b > c) { x = b; b = c; c = x; }
        if (a > b) { x = a; a = b; b = x; }
        tk[i].k[0] = a; tk[i].k[1] = b; tk[i].k[2] = c; tk[i].t = (uint32_t)i;
    }
    qsort(tk, nt, sizeof *tk, trikey_cmp);
    for (i = 0; i < nt; i = j)
        for (j = i + 1; j < nt && memcmp(tk[j].k, tk[i].k, sizeof tk[i].k) == 0; j++)
            if (tk[i].k[0] != tk[i].k[1] && tk[i].k[1] != tk[i].k[2]) {
                drop[tk[j].t] = 1;
                dropped++;
            }
    for (i = 0; i < nt; i++)
        if (!drop[i]) memmove(m->indices + 3 * kept++, m->indices + 3 * i, 3 * sizeof(uint32_t));
    m->triangle_count = kept;
    free(tk); free(drop);
    return dropped;
}

/* How often the surface runs through itself: the edges of m that pass through one of its
   triangles (away from the edge's own ends), each counted once; -1 when out of memory. No
   enclosing base can follow such a surface, and its shell cannot grow there. */
static long self_crossings(const mesh *m)
{
    dm_bvh *bvh = NULL;
    size_t t;
    long n = 0;
    int c, k;
    if (dm_bvh_build(m->p, m->nv, m->t, m->nt, NULL, &bvh) != DM_OK) return -1;
    for (t = 0; t < m->nt; t++)
        for (c = 0; c < 3; c++) {
            uint32_t a = m->t[3 * t + (size_t)c], b = m->t[3 * t + (size_t)(c + 1) % 3];
            const float *pa = m->p + 3 * (size_t)a, *pb = m->p + 3 * (size_t)b;
            double d[3], len = 0.0;
            dm_ray ray;
            dm_hit hit;
            if (a > b) continue; /* an edge of two triangles once (a boundary edge may be skipped) */
            for (k = 0; k < 3; k++) {
                d[k] = (double)pb[k] - pa[k];
                len += d[k] * d[k];
            }
            len = sqrt(len);
            if (!(len > 0.0)) continue;
            for (k = 0; k < 3; k++) {
                ray.org[k] = pa[k];
                ray.dir[k] = (float)(d[k] / len);
            }
            ray.tmin = (float)(1e-3 * len);
            ray.tmax = (float)((1.0 - 1e-3) * len);
            if (!dm_bvh_intersect(bvh, &ray, &hit)) continue;
            for (k = 0; k < 3 && m->t[3 * (size_t)hit.triangle + (size_t)k] != a && m->t[3 * (size_t)hit.triangle + (size_t)k] != b; k++) {}
            n += k == 3;
        }
    dm_bvh_free(bvh);
    return n;
}

static void usage(FILE *to)
{
    fprintf(to,
            "usage: dispmesh IN|--brick [-o PREFIX] [--faces N] [--res R] [--size S] [--no-views] [--both-ways]\n"
            "                [--strict] [--min-quality Q] [--samples N]\n"
            "Paper 000 end to end: a base mesh plus one displacement map, baked from IN and rebuilt from them.\n"
            "  IN                 a mesh file meshio.h reads (OBJ, OFF, PLY, STL; an STL soup is welded first);\n"
            "                     a closed manifold works best\n"
            "  --brick            instead of IN: a generated 2 x 1 x 1 brick with V grooves (496 triangles)\n"
            "  -o, --output PREFIX  write PREFIX_base.obj, PREFIX_disp.pfm, PREFIX_normal.png, PREFIX_recon.obj\n"
            "                     and PREFIX_views.png; the directory is created if missing (default out/dispmesh)\n"
            "  --faces N          base mesh triangles to aim for, 1..1000000000 (default 500)\n"
            "  --res R            displacement map R x R texels, 8..16384 (default 512)\n"
            "  --size S           pixels of each of the three views, 16..4096 (default 400)\n"
            "  --no-views         do not render PREFIX_views.png (default: render it)\n"
            "  --both-ways        bake the nearest hit either way along the normal (default: the first hit\n"
            "                     along -normal, right for a base that encloses the original)\n"
            "  --strict           the paper's constraints only, even where they stop above --faces (default:\n"
            "                     where the shell is too thin for an enclosing base, relax the constraint there\n"
            "                     once a collapse there is 16x cheaper than the strict ones left, and bake those\n"
            "                     triangles both ways; --fallback names that default)\n"
            "  --min-quality Q    the constrained simplifier's sliver guard, 2 area / longest edge^2, in [-1, 0.5]\n"
            "                     (default 0.05; 0 = none)\n"
            "  --samples N        surface-distance samples per side, 1000..100000000 (default 200000)\n"
            "  -h, --help         show this help and exit\n"
            "  --version          show the version and exit\n"
            "Prints one RESULT dispmesh line on stdout; progress on stderr.\n"
            "Exit status: 0 done, 1 failure (unreadable input, a failed stage, an unusable result, a failed\n"
            "write), 2 usage. The files are written to NAME.tmp and renamed once all are complete: a failed\n"
            "run leaves none of them behind.\n");
}

typedef struct options {
    const char *in, *prefix;
    long faces, res, size, samples;
    double min_quality;
    int brick, views, inward, fallback;
} options;

/* Returns -1 to go on, or the exit status (0 for --help/--version, 2 for a usage error). */
static int parse_args(int argc, char **argv, options *o)
{
    int i;
    memset(o, 0, sizeof *o);
    o->prefix = "out/dispmesh";
    o->faces = 500; o->res = 512; o->size = 400; o->samples = 200000;
    o->min_quality = 0.05; /* the constrained run's sliver guard (the library's default is none) */
    o->views = o->inward = o->fallback = 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int takes = !strcmp(a, "--faces") || !strcmp(a, "--res") || !strcmp(a, "--size") || !strcmp(a, "--min-quality") ||
                    !strcmp(a, "--samples") || !strcmp(a, "-o") || !strcmp(a, "--output");
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) { usage(stdout); return 0; }
        if (!strcmp(a, "--version")) { printf("%s\n", DISPMESH_VERSION); return 0; }
        if (takes && !v) return cli_usage_error("dispmesh", "%s needs a value", a);
        if (takes) i++;
        if (!strcmp(a, "--brick")) o->brick = 1;
        else if (!strcmp(a, "--no-views")) o->views = 0;
        else if (!strcmp(a, "--both-ways")) o->inward = 0;
        else if (!strcmp(a, "--fallback")) o->fallback = 1;
        else if (!strcmp(a, "--strict")) o->fallback = 0;
        else if (!strcmp(a, "--faces")) {
            if (!cli_parse_long(v, 1, 1000000000L, &o->faces)) return cli_usage_error("dispmesh", "--faces '%s': not an integer in 1..1000000000", v);
        } else if (!strcmp(a, "--res")) {
            if (!cli_parse_long(v, 8, 16384, &o->res)) return cli_usage_error("dispmesh", "--res '%s': not an integer in 8..16384", v);
        } else if (!strcmp(a, "--size")) {
            if (!cli_parse_long(v, 16, 4096, &o->size)) return cli_usage_error("dispmesh", "--size '%s': not an integer in 16..4096", v);
        } else if (!strcmp(a, "--samples")) {
            if (!cli_parse_long(v, 1000, 100000000L, &o->samples))
                return cli_usage_error("dispmesh", "--samples '%s': not an integer in 1000..100000000", v);
        } else if (!strcmp(a, "--min-quality")) {
            if (!cli_parse_double(v, -1.0, 0.5, &o->min_quality))
                return cli_usage_error("dispmesh", "--min-quality '%s': not a number in [-1, 0.5]", v);
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (!*v) return cli_usage_error("dispmesh", "%s: an empty prefix", a);
            o->prefix = v;
        } else if (a[0] == '-' && a[1] != '\0') return cli_usage_error("dispmesh", "unknown option '%s'", a);
        else if (o->in) return cli_usage_error("dispmesh", "unexpected argument '%s': one IN only", a);
        else o->in = a;
    }
    if ((o->in != NULL) == (o->brick != 0)) return cli_usage_error("dispmesh", "%s", "give exactly one of IN or --brick");
    if (strlen(o->prefix) + 16 >= CLI_PATH_MAX) return cli_usage_error("dispmesh", "-o '%s': the prefix is too long", o->prefix);
    return -1;
}

int main(int argc, char **argv)
{
    options O;
    const char *in, *prefix;
    long faces, res, size;
    double min_quality;
    int brick, views, inward, fallback, status = parse_args(argc, argv, &O);
    run R;
    cli_outputs outs;
    stage st;
    dm_result r;
    dm_simplify_options so;
    dm_simplify_report srep;
    dm_param_options po;
    dm_bake_options bo;
    dm_distance_report d_recon, d_base, d_same, d_bytes;
    double t0 = now_ms(), diag, bake_ms = 0.0, flagged = 0.0, fallback_share = 0.0, fallback_signed = 0.0;
    float lo[3], hi[3];
    size_t uv_count = 0, inside = 0, missed = 0, k, bytes_base = 0, bytes_free = 0;
    char *path = NULL;

    if (status >= 0) return status;
    status = 1;
    in = O.in; prefix = O.prefix; faces = O.faces; res = O.res; size = O.size; min_quality = O.min_quality;
    brick = O.brick; views = O.views; inward = O.inward; fallback = O.fallback;
    memset(&R, 0, sizeof R);
    cli_outputs_init(&outs);

    /* 1. the original */
    if (brick) {
        if (!make_brick(&R.orig)) { fprintf(stderr, "dispmesh: out of memory\n"); return 1; }
        R.orig_owned = 1;
        fprintf(stderr, "dispmesh: generated brick: %zu vertices, %zu triangles\n", R.orig.nv, R.orig.nt);
    } else {
        mio_error err;
        mio_result mr;
        size_t before;
        long apart, crossings, repeats;
        size_t turned = 0;
        errno = 0;
        if ((mr = mio_read_file(in, NULL, &R.loaded, &err)) != MIO_OK) {
            cli_read_error("dispmesh", in, err.message, mio_result_string(mr), mio_result_description(mr),
                           mr == MIO_ERR_IO ? errno : 0);
            return 1;
        }
        /* a triangle soup (an STL file) shares no vertex: dm_simplify needs them joined */
        before = R.loaded.vertex_count;
        if ((apart = stitch(&R.loaded)) < 0) {
            fprintf(stderr, "dispmesh: out of memory\n");
            goto done;
        }
        if (R.loaded.vertex_count != before)
            fprintf(stderr, "dispmesh: welded vertices at equal positions: %zu -> %zu vertices\n", before, R.loaded.vertex_count);
        if (apart > 0)
            fprintf(stderr, "dispmesh: %ld vertices share a position with another but meet it only at a point: "
                            "kept apart (joined, they would be non-manifold)\n", apart);
        if ((repeats = drop_repeats(&R.loaded)) < 0) {
            fprintf(stderr, "dispmesh: out of memory\n");
            goto done;
        }
        if (repeats > 0)
            fprintf(stderr, "dispmesh: note: %ld triangles repeat another's corners: dropped (the first of each kept)\n",
                    repeats);
        R.orig.p = R.loaded.positions; R.orig.nv = R.loaded.vertex_count;
        R.orig.t = R.loaded.indices; R.orig.nt = R.loaded.triangle_count;
        fprintf(stderr, "dispmesh: %s: %zu vertices, %zu triangles\n", in, R.orig.nv, R.orig.nt);
        /* triangles that disagree with their neighbours' orientation: the simplifier cannot
           collapse across them, and the shell would grow to both sides */
        if ((r = dm_orient(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, NULL, &turned)) != DM_OK) {
            fprintf(stderr, "dispmesh: %s: %s\n", in, dm_result_string(r));
            goto done;
        }
        if (turned > 0)
            fprintf(stderr, "dispmesh: note: %zu of %zu triangles turned (to agree with their neighbours, each closed "
                            "part facing out)\n",
                    turned, R.orig.nt);
        if ((crossings = self_crossings(&R.orig)) < 0) {
            fprintf(stderr, "dispmesh: out of memory\n");
            goto done;
        }
        if (crossings > 0)
            fprintf(stderr, "dispmesh: note: the surface runs through itself: %ld of its edges pass through another of its "
                            "triangles (the shell cannot grow there, and no enclosing base can follow the surface)\n",
                    crossings);
    }
    diag = bbox_diagonal(&R.orig, lo, hi);
    if (!(diag > 0.0) || !isfinite(diag)) {
        fprintf(stderr, "dispmesh: %s: the mesh has no extent (bounding-box diagonal %g)\n", brick ? "brick" : in, diag);
        status = 1;
        goto done;
    }

    /* the output location, before any work (and only for a usable input: a bad one creates no directory) */
    make_parent_dir(prefix);
    if (!probe_writable(prefix)) goto done;

    /* 2. the bounding shell */
    {
        dm_shell_options sho;
        memset(&sho, 0, sizeof sho);
        stage_begin(&st, "bounding shell");
        sho.progress = stage_progress; sho.progress_user = &st;
        r = dm_shell_grow(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, &sho, &R.shell);
        if (r != DM_OK) { stage_fail(&st, "dm_shell_grow", r); goto done; }
        {
            char note[128];
            snprintf(note, sizeof note, "thickness %.3g, %zu of %zu vertices stopped early", (double)R.shell->thickness,
                     R.shell->stopped_vertices, R.shell->vertex_count);
            stage_end(&st, note);
        }
    }

    /* 3. the base: constrained simplification */
    memset(&so, 0, sizeof so);
    so.target_triangles = (size_t)faces;
    so.min_quality = (float)min_quality;
    so.constraint = dm_shell_constraint;
    so.on_collapse = dm_shell_collapsed;
    so.relax = fallback ? dm_shell_relax : NULL;
    so.constraint_user = R.shell;
    stage_begin(&st, "simplify (shell-constrained)");
    so.progress = stage_progress; so.progress_user = &st;
    r = dm_simplify(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, &so, &R.pm, &srep);
    if (r != DM_OK) { stage_fail(&st, "dm_simplify", r); goto done; }
    dm_pm_set_level(R.pm, 0);
    if (!pm_to_mesh(R.pm, &R.base) || !fallback_region(&R)) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
    {
        char note[256];
        snprintf(note, sizeof note, "%zu -> %zu triangles%s, %zu vetoed (enclosure %zu, shell %zu, overlap %zu)",
                 srep.input_triangles, R.base.nt, srep.reached_target ? "" : " (target not reached)", srep.vetoed,
                 R.shell->vetoed_enclose, R.shell->vetoed_shell, R.shell->vetoed_overlap);
        stage_end(&st, note);
    }
    if (R.shell->fallback_collapses)
        fprintf(stderr, "dispmesh: note: where the shell is too thin for an enclosing base, %zu collapses were done relaxed%s; "
                        "%zu of %zu base triangles are baked both ways\n",
                R.shell->fallback_collapses,
                R.shell->fallback >= 2 ? " (at the end with the simplifier's own checks only)"
                : R.shell->fallback ? " (at the end everywhere)" : "",
                R.fallback_triangles, R.base.nt);
    if (!srep.reached_target && srep.frozen_vertices)
        fprintf(stderr, "dispmesh: note: %zu vertices are non-manifold (their triangles do not make one oriented fan): "
                        "the simplifier does not move or remove them\n",
                srep.frozen_vertices);
    if (!srep.reached_target)
        fprintf(stderr, "dispmesh: note: the simplifier stopped at %zu triangles, above --faces %ld: %s\n", R.base.nt, faces,
                !srep.vetoed || R.shell->fallback >= 2
                    ? "no edge left passes the simplifier's own checks (a collapse may not change the surface's "
                      "topology, fold a triangle over or move a non-manifold vertex)"
                : fallback ? "the relaxed constraint still vetoed the rest"
                           : "the shell constraint vetoed every remaining collapse (see the counts above; the shell is too "
                             "thin there for an enclosing base); without --strict it is relaxed there and those parts are "
                             "baked both ways");

    /* 4. the map's layout, texels where the original's area is */
    R.weights = (float *)malloc(R.base.nt * sizeof(float) + 1);
    if (!R.weights) { fprintf(stderr, "dispmesh: out of memory\n"); goto done; }
    stage_begin(&st, "coverage weights");
    {
        dm_coverage_options copt;
        memset(&copt, 0, sizeof copt);
        copt.progress = stage_progress;
        copt.progress_user = &st;
        r = dm_coverage_weights(R.base.p, R.base.nv, R.base.t, R.base.nt, R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, &copt,
                                R.weights);
    }
    if (r != DM_OK) { stage_fail(&st, "dm_coverage_weights", r); goto done; }
    stage_end(&st, NULL);
    memset(&po, 0, sizeof po);
    po.width = po.height = (int)res;
    po.triangle_weight = R.weights;
    { /* the share of the original's area over the fallback region, by the coverage weights */
        double all = 0.0, fb = 0.0;
        for (k = 0; k < R.base.nt; k++) {
            all += R.weights[k];
            if (R.both_ways[k]) fb += R.weights[k];
        }
        fallback_share = all > 0.0 ? fb / all : 0.0;
    }
    stage_begin(&st, "parameterize");
    po.progress = stage_progress; po.progress_user = &st;
    r = dm_parameterize(R.base.p, R.base.nv, R.base.t, R.base.nt, &po, &R.param);
    if (r != DM_OK) {
        stage_fail(&st, "dm_parameterize", r);
        if (r == DM_ERR_MAP_TOO_SMALL)
            fprintf(stderr, "dispmesh: --res %ld is too small for the charts of %zu base triangles\n", res, R.base.nt);
        goto done;
    }
    {
        char note[160];
        snprintf(note, sizeof note, "%zu charts, utilization %.3f, stretch L2 %.3f", R.param->chart_count,
                 (double)R.param->utilization, (double)R.param->stretch_l2);
        stage_end(&st, note);
    }

    /* 5. the bake */
    memset(&bo, 0, sizeof bo);
    bo.inward = inward;
    bo.both_ways = R.both_ways;
    /* the base lies within the shell: a deeper hit is a ray that slipped past a thin part of the
       original to another sheet, better filled from its neighbours than kept */
    bo.max_distance = 1.5f * R.shell->thickness;
    stage_begin(&st, inward ? "bake (inward)" : "bake (both ways)");
    bo.progress = stage_progress; bo.progress_user = &st;
    bake_ms = now_ms();
    r = dm_bake(R.param, R.base.p, R.base.nv, R.base.t, R.base.nt, R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, &bo, &R.map);
    bake_ms = now_ms() - bake_ms;
    if (r != DM_OK) { stage_fail(&st, "dm_bake", r); goto done; }
    for (k = 0; k < (size_t)R.map->width * (size_t)R.map->height; k++) {
        if (R.map->status[k] != DM_TEXEL_HIT && R.map->status[k] != DM_TEXEL_MISS) continue; /* EMPTY, BORDER */
        inside++;
        if (R.map->status[k] == DM_TEXEL_MISS) missed++;
    }
    flagged = inside ? (double)missed / (double)inside : 0.0;
    {
        char note[160];
        snprintf(note, sizeof note, "%zu texels in charts, %zu missed", inside, missed);
        stage_end(&st, note);
    }
    if (!result_usable(&R, res, inside, missed)) goto done;
    if ((fallback_signed = signed_share(&R)) < 0.0) { fprintf(stderr, "dispmesh: out of memory\n"); goto done; }

    /* 6. the reconstruction and the distances */
    stage_begin(&st, "reconstruct");
    r = dm_reconstruct(R.map, R.param, R.base.p, R.base.nv, R.base.t, R.base.nt, NULL, &R.dense);
    if (r != DM_OK) { stage_fail(&st, "dm_reconstruct", r); goto done; }
    {
        char note[96];
        snprintf(note, sizeof note, "%zu triangles", R.dense->triangle_count);
        stage_end(&st, note);
    }
    if (R.dense->triangle_count == 0) { fprintf(stderr, "dispmesh: the reconstruction is empty (no texel hit the original)\n"); goto done; }

    /* the unconstrained simplifier at the base's triangle count; its progressive mesh then gives the
       equal-bytes mesh */
    memset(&so, 0, sizeof so);
    so.target_triangles = R.base.nt; /* the library's defaults: no sliver guard */
    stage_begin(&st, "simplify (unconstrained)");
    so.progress = stage_progress; so.progress_user = &st;
    r = dm_simplify(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, &so, &R.pm_free, NULL);
    if (r != DM_OK) { stage_fail(&st, "dm_simplify", r); goto done; }
    dm_pm_set_level(R.pm_free, 0);
    if (!pm_to_mesh(R.pm_free, &R.free_same)) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
    {
        /* base bytes: 12 V + 12 F + 8 per map coordinate + 2 per texel (16-bit displacement) */
        uint32_t *cuv = (uint32_t *)malloc(R.base.nt * 3 * sizeof(uint32_t) + 1);
        size_t lo_l = 0, hi_l = dm_pm_split_count(R.pm_free), nv, nt;
        char note[160];
        if (!cuv) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
        uv_count = distinct_uvs(&R.base, R.param, cuv, NULL);
        free(cuv);
        if (uv_count == 0) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
        bytes_base = 12 * R.base.nv + 12 * R.base.nt + 8 * uv_count + 2 * (size_t)res * (size_t)res;
        /* the finest level whose 12 V + 12 F fits the budget (counts grow with the level) */
        while (lo_l < hi_l) {
            size_t mid = lo_l + (hi_l - lo_l + 1) / 2;
            dm_pm_set_level(R.pm_free, mid);
            dm_pm_counts(R.pm_free, &nv, &nt);
            if (12 * nv + 12 * nt <= bytes_base) lo_l = mid;
            else hi_l = mid - 1;
        }
        dm_pm_set_level(R.pm_free, lo_l);
        if (!pm_to_mesh(R.pm_free, &R.free_bytes)) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
        bytes_free = 12 * R.free_bytes.nv + 12 * R.free_bytes.nt;
        snprintf(note, sizeof note, "%zu triangles; equal bytes (%zu): %zu triangles (%zu bytes)%s", R.free_same.nt,
                 bytes_base, R.free_bytes.nt, bytes_free,
                 lo_l == dm_pm_split_count(R.pm_free) ? " = the original" : "");
        stage_end(&st, note);
    }

    stage_begin(&st, "surface distances");
    {
        /* four measurements, each a quarter of the stage */
        quarter q;
        dm_distance_options dopt;
        memset(&dopt, 0, sizeof dopt);
        dopt.samples_per_side = (size_t)O.samples;
        dopt.progress = quarter_progress;
        dopt.progress_user = &q;
        q.st = &st;
        q.k = 0;
        r = dm_surface_distance(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, R.dense->positions, R.dense->vertex_count,
                                R.dense->indices, R.dense->triangle_count, &dopt, &d_recon);
        q.k = 1;
        if (r == DM_OK)
            r = dm_surface_distance(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, R.base.p, R.base.nv, R.base.t, R.base.nt,
                                    &dopt, &d_base);
        q.k = 2;
        if (r == DM_OK)
            r = dm_surface_distance(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, R.free_same.p, R.free_same.nv,
                                    R.free_same.t, R.free_same.nt, &dopt, &d_same);
        q.k = 3;
        if (r == DM_OK)
            r = dm_surface_distance(R.orig.p, R.orig.nv, R.orig.t, R.orig.nt, R.free_bytes.p, R.free_bytes.nv,
                                    R.free_bytes.t, R.free_bytes.nt, &dopt, &d_bytes);
    }
    if (r != DM_OK) { stage_fail(&st, "dm_surface_distance", r); goto done; }
    stage_end(&st, NULL);

    /* 7. files */
    stage_begin(&st, "write files");
    {
        size_t uvs_written = 0;
        mio_error err;
        mio_result mr;
        sr_result wr;
        static const char *const suffix[5] = {"_base.obj", "_disp.pfm", "_normal.png", "_recon.obj", "_views.png"};
        const char *tmp[5];
        int f, saved;
        for (f = 0; f < (views ? 5 : 4); f++) {
            free(path);
            if (!(path = path_with(prefix, suffix[f]))) { fprintf(stderr, "\ndispmesh: out of memory\n"); goto done; }
            if (!(tmp[f] = cli_output_add(&outs, "dispmesh", path))) goto done;
            errno = 0;
            switch (f) {
            case 0: wr = write_base_obj(path, tmp[f], &R.base, R.param, &uvs_written) ? SR_OK : SR_ERR_IO; break;
            case 1:
                wr = sr_write_pfm(tmp[f], R.map->disp, R.map->width, R.map->height, 1);
                if (wr != SR_OK) write_failed(path, wr, errno);
                break;
            case 2: wr = write_normal_png(path, tmp[f], R.map) ? SR_OK : SR_ERR_IO; break;
            case 3:
                mr = mio_write_obj_normals(tmp[f], R.dense->positions, R.dense->normals, R.dense->vertex_count,
                                           R.dense->indices, R.dense->triangle_count, &err);
                saved = errno;
                if (mr != MIO_OK) {
                    fprintf(stderr, "\n");
                    cli_read_error("dispmesh", path, err.message, mio_result_string(mr), mio_result_description(mr),
                                   mr == MIO_ERR_IO ? saved : 0);
                }
                wr = mr == MIO_OK ? SR_OK : SR_ERR_IO;
                break;
            default: wr = write_views(path, tmp[f], &R, (int)size, !brick, d_recon.rms) ? SR_OK : SR_ERR_IO; break;
            }
            if (wr != SR_OK) goto done;
            stage_progress(&st, 0.2f * (float)(f + 1));
        }
        free(path);
        path = NULL;
        if (!cli_outputs_commit(&outs, "dispmesh")) goto done;
        stage_end(&st, views ? NULL : "(views skipped)");
    }
    fprintf(stderr, "dispmesh: wrote %s_{base.obj,disp.pfm,normal.png,recon.obj%s}\n", prefix, views ? ",views.png" : "");
    fprintf(stderr, "dispmesh: base %zu vertices %zu triangles %zu map coordinates; bytes: base+map %zu, equal-bytes mesh %zu "
                    "(%zu triangles)\n", R.base.nv, R.base.nt, uv_count, bytes_base, bytes_free, R.free_bytes.nt);

    /* 8. the result */
    printf("RESULT dispmesh target=%ld faces=%zu fallback=%.4f fallback_region=%.4f res=%ld rms=%.4e max=%.4e base_only_rms=%.4e "
           "base_only_max=%.4e unconstrained_rms=%.4e equal_bytes_rms=%.4e equal_bytes_max=%.4e flagged=%.5f bake_ms=%.1f "
           "total_ms=%.1f\n",
           faces, R.base.nt, fallback_signed, fallback_share, res, d_recon.rms, d_recon.max, d_base.rms, d_base.max, d_same.rms, d_bytes.rms, d_bytes.max, flagged,
           bake_ms, now_ms() - t0);
    fflush(stdout);
    status = ferror(stdout) ? 1 : 0;
done:
    cli_outputs_discard(&outs); /* after a failure: no file of this run is left */
    free(path);
    run_free(&R);
    return status;
}
