/* erode - paper 000's wind erosion (erosion.h) on a mesh's displacement map or on a height map.

   usage: erode IN|--torus|--reliefs|--letters --steps N --wind X,Y,Z [--material MASK] [--hard EMIN,EMAX] [--soft EMIN,EMAX]
                [--res R] [--faces F] [--height-scale S] [--wrap] [--rate R] [--render-steps A,B,...]
                [--size S] [--marker X,Y,Z] [--view X,Y,Z] -o PREFIX
     --torus       instead of IN: a generated torus (radii 1 and 0.3, 128 x 48 quads), paper Fig 5.2.1's
     --reliefs     instead of IN: a cylinder (radius 0.5, height 1.2) with raised bosses, an R x 0.38R
                   surface grid whose base, the cylinder, encloses them (paper Fig 5.2.2's)
     --letters     the same cylinder with the raised letters "CGGM", "CG" of the hard material and
                   the rest soft (Fig 5.2.3's); the text faces -x
     IN            a mesh (OBJ, OFF, PLY, STL; run through dispmesh.h to a base + an R x R map first)
                   or a height map (PFM: heights in world units; PNG 8/16-bit or PGM: grey scaled by
                   --height-scale), the map spanning 1 world unit along its longer side
     --steps N     time steps (1..100000)
     --wind X,Y,Z  the direction the wind blows toward (not zero)
     --material M  a mask image stretched over the map: where its first channel is >= 0.5 the
                   texels are of the hard material, elsewhere soft (a mesh's map is in its chart
                   layout, so a mask suits a height map best)
     --hard, --soft  eps_min,eps_max of the two materials (defaults 4,16 and 1,4)
     --res R       a mesh's map resolution (default 256, 16..4096); --faces F its base (default 500)
     --height-scale S  world height of a grey value of 1 (default 0.1)
     --wrap        the height map tiles: neighbours wrap around
     --rate R      world units of depth per unit of H per step (default erosion.h's, 1e-3 x scale)
     --render-steps A,B,...  the steps after which a view is rendered (default 1 and N)
     --size S      pixels of each view (default 400); --marker X,Y,Z the wind source's marker
                   (default: 1.2 x the scale against the wind from the centre); --view X,Y,Z the
                   direction from the centre to the eye (default: beside the wind source)
     -o PREFIX     output prefix (required)
   Writes PREFIX_map.pfm (the weathered displacement or height, 1 channel, row 0 at the bottom),
   PREFIX_map.png (the same, 16-bit grey from its min to its max), PREFIX.obj (the weathered mesh:
   dispmesh.h's reconstruction, or the height field's grid), PREFIX_render.png (before | after each
   render step, the wind source marked; the change since "before" shaded: orange where worn, blue
   where filled, by the same scale in every view), and on stdout
     RESULT erosion domain=<heightfield|surface> res=<w>x<h> steps=<n> eroded=<v> deposited=<v>
            max_change=<d> step_ms=<t>
   Progress goes to stderr. Exit status: 0 done, 1 failure (unreadable input, a library error, a
   failed write), 2 usage (the bad argument named). Every file is written to NAME.tmp and renamed
   when all are complete. --version prints the version. */
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
#define ERO_IMPLEMENTATION
#include "erosion.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

#define PROG "erode"
#define ERODE_VERSION "erode 0.1 (erosion.h, dispmesh.h, meshio.h, render.h)"
#define MAX_RENDERS 6

typedef struct args {
    const char *in, *prefix, *material;
    long steps, res, faces, size;
    double wind[3], hard[2], soft[2], height_scale, rate, marker[3], view[3];
    double render_steps[MAX_RENDERS];
    int render_count, wrap, has_marker, has_view, torus, cylinder; /* cylinder: 1 reliefs, 2 letters */
} args;

/* everything one run holds, freed by run_free */
typedef struct run {
    int surface, w, h;
    float *disp, *disp0;              /* the map now and before */
    uint8_t *mat;
    ero_grid g;
    mio_mesh mesh;                    /* a mesh input */
    dm_pm *pm;
    dm_param *param;
    dm_dispmap *map;
    float *bp;
    uint32_t *bi;
    size_t bnv, bnt;
    float lo[3], hi[3];               /* the surface's bounding box */
    sr_image8 views[MAX_RENDERS + 1];
    char captions[MAX_RENDERS + 1][48];
    int view_count;
    float *states[MAX_RENDERS + 1];   /* the map at each view */
    float *gen;                       /* a generated surface grid's arrays (one block) */
    float *before_p;                  /* the "before" reconstruction's points (change shading) */
    size_t before_nv;
} run;

static void usage(FILE *to)
{
    fprintf(to, "usage: erode IN|--torus|--reliefs|--letters --steps N --wind X,Y,Z [--material MASK] [--hard EMIN,EMAX] [--soft EMIN,EMAX]\n"
                "             [--res R] [--faces F] [--height-scale S] [--wrap] [--rate R] [--render-steps A,B,...]\n"
                "             [--size S] [--marker X,Y,Z] [--view X,Y,Z] -o PREFIX\n"
                "  IN: a mesh (OBJ, OFF, PLY, STL) or a height map (PFM, PNG, PGM); --torus, --reliefs, --letters: generated\n"
                "  --steps N (1..100000)  --wind X,Y,Z toward which the wind blows  --material MASK (>= 0.5: hard)\n"
                "  --hard EMIN,EMAX (4,16)  --soft EMIN,EMAX (1,4)  --res R (256)  --faces F (500)\n"
                "  --height-scale S (0.1)  --wrap  --rate R (1e-3 x scale)  --render-steps A,B,... (1,N)\n"
                "  --size S (400)  --marker X,Y,Z (the wind source)  --view X,Y,Z (eye direction)  -o PREFIX  --version\n");
}

static int parse_args(int argc, char **argv, args *a)
{
    int i, n;
    memset(a, 0, sizeof *a);
    a->res = 256; a->faces = 500; a->size = 400; a->height_scale = 0.1;
    a->hard[0] = 4; a->hard[1] = 16; a->soft[0] = 1; a->soft[1] = 4;
    for (i = 1; i < argc; i++) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(o, "--help") == 0) { usage(stdout); exit(0); }
        if (strcmp(o, "--version") == 0) { printf("%s\n", ERODE_VERSION); exit(0); }
        if (strcmp(o, "--wrap") == 0) { a->wrap = 1; continue; }
        if (strcmp(o, "--torus") == 0) { a->torus = 1; continue; }
        if (strcmp(o, "--reliefs") == 0 || strcmp(o, "--letters") == 0) {
            if (a->cylinder) return cli_usage_error(PROG, "more than one of --reliefs and --letters");
            a->cylinder = o[2] == 'r' ? 1 : 2;
            continue;
        }
        if (o[0] != '-') {
            if (a->in) return cli_usage_error(PROG, "more than one input: '%s' and '%s'", a->in, o);
            a->in = o;
            continue;
        }
        if (!v) return cli_usage_error(PROG, "%s needs a value", o);
        i++;
        if (strcmp(o, "-o") == 0) a->prefix = v;
        else if (strcmp(o, "--steps") == 0) { if (!cli_parse_long(v, 1, 100000, &a->steps)) return cli_usage_error(PROG, "--steps '%s': an integer in 1..100000", v); }
        else if (strcmp(o, "--wind") == 0) {
            if (!cli_parse_doubles(v, ',', 3, 3, -1e6, 1e6, a->wind, NULL)) return cli_usage_error(PROG, "--wind '%s': three numbers X,Y,Z", v);
            if (a->wind[0] == 0 && a->wind[1] == 0 && a->wind[2] == 0) return cli_usage_error(PROG, "--wind '%s': the wind vector is zero", v);
        } else if (strcmp(o, "--material") == 0) a->material = v;
        else if (strcmp(o, "--hard") == 0 || strcmp(o, "--soft") == 0) {
            double *e = o[2] == 'h' ? a->hard : a->soft;
            if (!cli_parse_doubles(v, ',', 2, 2, 1e-6, 1e6, e, NULL) || !(e[0] < e[1]))
                return cli_usage_error(PROG, "%s '%s': EMIN,EMAX with 0 < EMIN < EMAX", o, v);
        } else if (strcmp(o, "--res") == 0) { if (!cli_parse_long(v, 16, 4096, &a->res)) return cli_usage_error(PROG, "--res '%s': an integer in 16..4096", v); }
        else if (strcmp(o, "--faces") == 0) { if (!cli_parse_long(v, 4, 100000, &a->faces)) return cli_usage_error(PROG, "--faces '%s': an integer in 4..100000", v); }
        else if (strcmp(o, "--size") == 0) { if (!cli_parse_long(v, 32, 4096, &a->size)) return cli_usage_error(PROG, "--size '%s': an integer in 32..4096", v); }
        else if (strcmp(o, "--height-scale") == 0) { if (!cli_parse_double(v, 1e-9, 1e9, &a->height_scale)) return cli_usage_error(PROG, "--height-scale '%s': a positive number", v); }
        else if (strcmp(o, "--rate") == 0) { if (!cli_parse_double(v, 1e-12, 1e6, &a->rate)) return cli_usage_error(PROG, "--rate '%s': a positive number", v); }
        else if (strcmp(o, "--marker") == 0) { if (!cli_parse_doubles(v, ',', 3, 3, -1e9, 1e9, a->marker, NULL)) return cli_usage_error(PROG, "--marker '%s': three numbers X,Y,Z", v); a->has_marker = 1; }
        else if (strcmp(o, "--view") == 0) {
            if (!cli_parse_doubles(v, ',', 3, 3, -1e9, 1e9, a->view, NULL) || (a->view[0] == 0 && a->view[1] == 0 && a->view[2] == 0))
                return cli_usage_error(PROG, "--view '%s': three numbers X,Y,Z, not all zero", v);
            a->has_view = 1;
        } else if (strcmp(o, "--render-steps") == 0) {
            if (!cli_parse_doubles(v, ',', 1, MAX_RENDERS, 0, 100000, a->render_steps, &n))
                return cli_usage_error(PROG, "--render-steps '%s': 1 to %d step numbers", v, MAX_RENDERS);
            a->render_count = n;
        } else return cli_usage_error(PROG, "unknown option '%s'", o);
    }
    if (!a->in && !a->torus && !a->cylinder) return cli_usage_error(PROG, "no input (IN, --torus, --reliefs or --letters)");
    if ((a->in != NULL) + a->torus + (a->cylinder != 0) > 1) return cli_usage_error(PROG, "more than one input (IN, --torus, --reliefs, --letters)");
    if (!a->prefix) return cli_usage_error(PROG, "no output prefix (-o PREFIX)");
    if (!a->steps) return cli_usage_error(PROG, "--steps is required");
    if (a->wind[0] == 0 && a->wind[1] == 0 && a->wind[2] == 0) return cli_usage_error(PROG, "--wind is required");
    if (!a->render_count) { a->render_steps[0] = 1; a->render_steps[1] = (double)a->steps; a->render_count = a->steps > 1 ? 2 : 1; }
    for (n = 0; n < a->render_count; n++)
        if (a->render_steps[n] != floor(a->render_steps[n]) || a->render_steps[n] > a->steps || (n && a->render_steps[n] <= a->render_steps[n - 1]))
            return cli_usage_error(PROG, "--render-steps: increasing whole steps up to --steps (%ld)", a->steps);
    return 0;
}

static int is_image(const char *p)
{
    return cli_has_extension(p, ".pfm") || cli_has_extension(p, ".png") || cli_has_extension(p, ".pgm");
}

static void run_free(run *R)
{
    int k;
    free(R->disp0);
    free(R->mat);
    if (!R->surface) free(R->disp);
    free(R->gen);
    free(R->before_p);
    for (k = 0; k <= MAX_RENDERS; k++) free(R->states[k]);
    dm_dispmap_free(R->map);
    dm_param_free(R->param);
    dm_pm_free(R->pm);
    free(R->bp);
    free(R->bi);
    mio_free_mesh(&R->mesh);
    for (k = 0; k < R->view_count; k++) free(R->views[k].pixels);
}

/* ---- the inputs ----------------------------------------------------------------------------- */

static int load_heightmap(run *R, const args *a)
{
    sr_picture pic;
    sr_result r = sr_read_image(a->in, NULL, &pic);
    int x, y;
    if (r != SR_OK) { cli_result_error(PROG, a->in, sr_result_string(r), r == SR_ERR_IO ? errno : 0); return 0; }
    R->w = pic.width; R->h = pic.height;
    R->disp = (float *)malloc((size_t)R->w * R->h * sizeof(float));
    if (!R->disp || sr_picture_channel(&pic, 0, R->disp) != SR_OK) { sr_picture_free(&pic); fprintf(stderr, "erode: out of memory\n"); return 0; }
    if (!pic.floats) /* grey values, row 0 at the top: scaled, and flipped so that row 0 is y = 0 */
        for (y = 0; y < R->h / 2; y++)
            for (x = 0; x < R->w; x++) {
                float *p = R->disp + (size_t)y * R->w + x, *q = R->disp + (size_t)(R->h - 1 - y) * R->w + x, t = *p;
                *p = *q; *q = t;
            }
    for (x = 0; x < R->w * R->h; x++) if (!pic.floats) R->disp[x] *= (float)a->height_scale;
    sr_picture_free(&pic);
    R->g = ero_heightfield_grid(R->w, R->h, R->disp, 1.0f / (float)(R->w > R->h ? R->w : R->h), a->wrap);
    R->lo[0] = R->lo[1] = 0; R->hi[0] = R->w * R->g.spacing; R->hi[1] = R->h * R->g.spacing;
    fprintf(stderr, "erode: %s: height map %d x %d\n", a->in, R->w, R->h);
    return 1;
}

/* the generated torus as a mio_mesh (malloc'd arrays: meshio's default allocator frees them) */
static int make_torus(mio_mesh *m)
{
    enum { U = 128, V = 48 };
    int i, j;
    memset(m, 0, sizeof *m);
    m->vertex_count = (size_t)U * V;
    m->triangle_count = 2 * (size_t)U * V;
    m->positions = (float *)malloc(3 * m->vertex_count * sizeof(float));
    m->indices = (uint32_t *)malloc(3 * m->triangle_count * sizeof(uint32_t));
    if (!m->positions || !m->indices) return 0;
    for (i = 0; i < U; i++)
        for (j = 0; j < V; j++) {
            double al = 6.283185307179586 * i / U, be = 6.283185307179586 * j / V;
            float *p = m->positions + 3 * ((size_t)i * V + j);
            p[0] = (float)((1.0 + 0.3 * cos(be)) * cos(al));
            p[1] = (float)((1.0 + 0.3 * cos(be)) * sin(al));
            p[2] = (float)(0.3 * sin(be));
        }
    for (i = 0; i < U; i++)
        for (j = 0; j < V; j++) {
            uint32_t q0 = (uint32_t)(i * V + j), q1 = (uint32_t)(((i + 1) % U) * V + j);
            uint32_t q2 = (uint32_t)(((i + 1) % U) * V + (j + 1) % V), q3 = (uint32_t)(i * V + (j + 1) % V);
            uint32_t *t = m->indices + 6 * ((size_t)i * V + j);
            t[0] = q0; t[1] = q1; t[2] = q2; t[3] = q0; t[4] = q2; t[5] = q3;
        }
    return 1;
}

static int load_mesh(run *R, const args *a)
{
    mio_error err;
    mio_result mr;
    dm_simplify_options so;
    dm_param_options po;
    dm_bake_options bo;
    dm_result r;
    size_t i;
    errno = 0;
    if (a->torus) {
        if (!make_torus(&R->mesh)) { fprintf(stderr, "erode: out of memory\n"); return 0; }
    } else if ((mr = mio_read_file(a->in, NULL, &R->mesh, &err)) != MIO_OK) {
        cli_read_error(PROG, a->in, err.message, mio_result_string(mr), mio_result_description(mr), mr == MIO_ERR_IO ? errno : 0);
        return 0;
    }
    if (!a->torus && (mr = mio_weld(&R->mesh, &err)) != MIO_OK) { cli_read_error(PROG, a->in, err.message, mio_result_string(mr), mio_result_description(mr), 0); return 0; }
    fprintf(stderr, "erode: %s: %zu triangles; base of %ld triangles, %ld^2 map\n", a->torus ? "torus" : a->in, R->mesh.triangle_count, a->faces, a->res);
    memset(&so, 0, sizeof so);
    so.target_triangles = (size_t)a->faces;
    so.min_quality = 0.1f;
    memset(&po, 0, sizeof po);
    po.width = po.height = (int)a->res;
    memset(&bo, 0, sizeof bo);
    /* inward = 0: the nearest crossing either way (the unconstrained base may cross the original) */
    if ((r = dm_simplify(R->mesh.positions, R->mesh.vertex_count, R->mesh.indices, R->mesh.triangle_count, &so, &R->pm, NULL)) != DM_OK) {
        cli_result_error(PROG, "dm_simplify", dm_result_string(r), 0); return 0;
    }
    dm_pm_counts(R->pm, &R->bnv, &R->bnt);
    R->bp = (float *)malloc(3 * R->bnv * sizeof(float));
    R->bi = (uint32_t *)malloc(3 * R->bnt * sizeof(uint32_t));
    if (!R->bp || !R->bi) { fprintf(stderr, "erode: out of memory\n"); return 0; }
    dm_pm_get_mesh(R->pm, R->bp, R->bi, NULL);
    if ((r = dm_parameterize(R->bp, R->bnv, R->bi, R->bnt, &po, &R->param)) != DM_OK) { cli_result_error(PROG, "dm_parameterize", dm_result_string(r), 0); return 0; }
    if ((r = dm_bake(R->param, R->bp, R->bnv, R->bi, R->bnt, R->mesh.positions, R->mesh.vertex_count, R->mesh.indices,
                     R->mesh.triangle_count, &bo, &R->map)) != DM_OK) {
        cli_result_error(PROG, "dm_bake", dm_result_string(r), 0); return 0;
    }
    R->surface = 1;
    R->w = R->map->width; R->h = R->map->height;
    R->disp = R->map->disp;
    R->g = ero_surface_grid(R->w, R->h, R->map->pos, R->map->nrm, R->disp, R->map->area, R->map->valid, R->map->nbr, R->map->nbr_rot);
    for (i = 0; i < 3; i++) { R->lo[i] = 1e30f; R->hi[i] = -1e30f; }
    for (i = 0; i < 3 * R->mesh.vertex_count; i++) {
        float v = R->mesh.positions[i];
        if (v < R->lo[i % 3]) R->lo[i % 3] = v;
        if (v > R->hi[i % 3]) R->hi[i % 3] = v;
    }
    return 1;
}

/* ---- the generated cylinders (Figs 5.2.2, 5.2.3) ------------------------------------------- */

#define CYL_RB 0.5     /* the base cylinder's radius: it encloses the reliefs (disp >= 0) */
#define CYL_R0 0.44    /* the relief surface's radius between the reliefs */
#define CYL_HALF 0.6   /* half the height */
#define CYL_PI 3.14159265358979323846

/* "CGGM" as one 23 x 7 bitmap (5 x 7 letters, a column between), row 0 at the top */
static const char *const cyl_font[7] = {
    ".###.. .###.. .###.. #...#",
    "#...#. #...#. #...#. ##.##",
    "#..... #..... #..... #.#.#",
    "#..... #.###. #.###. #.#.#",
    "#..... #...#. #...#. #...#",
    "#...#. #...#. #...#. #...#",
    ".###.. .###.. .###.. #...#"};

static float cyl_cell(int col, int row)
{
    int c = col + col / 6; /* the strings have a space after each 6 columns */
    if (col < 0 || col >= 23 || row < 0 || row >= 7) return 0.0f;
    return cyl_font[row][c] == '#' ? 1.0f : 0.0f;
}

/* the letters' height (0 .. 1) at arc length s from the text's centre and height z, and the letter */
static float cyl_letters(double s, double z, int *letter)
{
    const double cell = 0.05;
    double col = (s + 11.5 * cell) / cell - 0.5, row = (3.5 * cell - z) / cell - 0.5, fx, fy, m, t;
    int c0 = (int)floor(col), r0 = (int)floor(row);
    fx = col - c0; fy = row - r0;
    m = (1 - fy) * ((1 - fx) * cyl_cell(c0, r0) + fx * cyl_cell(c0 + 1, r0)) +
        fy * ((1 - fx) * cyl_cell(c0, r0 + 1) + fx * cyl_cell(c0 + 1, r0 + 1));
    *letter = (int)floor((col + 0.5) / 6.0);
    t = (m - 0.25) / 0.5;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return (float)(t * t * (3 - 2 * t));
}

/* the bosses' height (0 .. 1): 12 around by 3 along the axis */
static float cyl_bosses(double th, double z)
{
    const double rad = 0.11;
    int i, j;
    float best = 0.0f;
    for (i = 0; i < 12; i++)
        for (j = -1; j <= 1; j++) {
            double dth = th - 2 * CYL_PI * (i + 0.5) / 12, ds, dz = z - 0.35 * j, q;
            dth -= 2 * CYL_PI * floor(dth / (2 * CYL_PI) + 0.5);
            ds = CYL_RB * dth;
            q = (ds * ds + dz * dz) / (rad * rad);
            if (q < 1 && (float)((1 - q) * (1 - q)) > best) best = (float)((1 - q) * (1 - q));
        }
    return best;
}

/* the texel (x, y)'s angle and height on a W x H cylinder grid */
static void cyl_texel(int x, int y, int W, int H, double *th, double *z)
{
    *th = 2 * CYL_PI * (x + 0.5) / W;
    *z = -CYL_HALF + 2 * CYL_HALF * (y + 0.5) / H;
}

/* the cylinder as a surface grid: u around (wrapping, no rotation), v along the axis (open ends) */
static int make_cylinder(run *R, const args *a)
{
    int W = (int)a->res, H = (int)(a->res * 2 * CYL_HALF / (2 * CYL_PI * CYL_RB) + 0.5), x, y, d;
    size_t n = (size_t)W * H, i;
    float *pos, *nrm, *area;
    uint32_t *nbr;
    uint8_t *valid, *rot;
    R->gen = (float *)malloc(n * (8 * sizeof(float) + 4 * sizeof(uint32_t) + 5));
    if (!R->gen) { fprintf(stderr, "erode: out of memory\n"); return 0; }
    pos = R->gen; nrm = pos + 3 * n; R->disp = nrm + 3 * n; area = R->disp + n;
    nbr = (uint32_t *)(area + n); valid = (uint8_t *)(nbr + 4 * n); rot = valid + n;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            double th, z, relief;
            int letter;
            i = (size_t)y * W + x;
            cyl_texel(x, y, W, H, &th, &z);
            relief = a->cylinder == 1 ? 0.045 * cyl_bosses(th, z) : 0.04 * cyl_letters(CYL_RB * (th - CYL_PI), z, &letter);
            pos[3 * i] = (float)(CYL_RB * cos(th)); pos[3 * i + 1] = (float)(CYL_RB * sin(th)); pos[3 * i + 2] = (float)z;
            nrm[3 * i] = (float)cos(th); nrm[3 * i + 1] = (float)sin(th); nrm[3 * i + 2] = 0.0f;
            R->disp[i] = (float)(CYL_RB - CYL_R0 - relief);
            area[i] = (float)((2 * CYL_PI * CYL_RB / W) * (2 * CYL_HALF / H));
            valid[i] = 1;
            nbr[4 * i + 0] = (uint32_t)(y * W + (x + 1) % W);
            nbr[4 * i + 1] = (uint32_t)(y * W + (x + W - 1) % W);
            nbr[4 * i + 2] = y + 1 < H ? (uint32_t)((y + 1) * W + x) : UINT32_MAX;
            nbr[4 * i + 3] = y > 0 ? (uint32_t)((y - 1) * W + x) : UINT32_MAX;
            for (d = 0; d < 4; d++) rot[4 * i + (size_t)d] = 0;
        }
    R->surface = 1;
    R->w = W; R->h = H;
    R->g = ero_surface_grid(W, H, pos, nrm, R->disp, area, valid, nbr, rot);
    R->lo[0] = R->lo[1] = (float)-CYL_RB; R->lo[2] = (float)-CYL_HALF;
    R->hi[0] = R->hi[1] = (float)CYL_RB; R->hi[2] = (float)CYL_HALF;
    fprintf(stderr, "erode: a cylinder with %s, %d x %d surface grid\n", a->cylinder == 1 ? "bosses" : "the letters CGGM", W, H);
    return 1;
}

/* Fig 5.2.3's materials: the letters C and G (the first two) hard, the rest soft */
static void cylinder_materials(run *R)
{
    int x, y, letter;
    for (y = 0; y < R->h; y++)
        for (x = 0; x < R->w; x++) {
            double th, z;
            cyl_texel(x, y, R->w, R->h, &th, &z);
            if (cyl_letters(CYL_RB * (th - CYL_PI), z, &letter) > 0.0f && letter >= 0 && letter < 2)
                R->mat[(size_t)y * R->w + x] = 1;
        }
}

static int load_material(run *R, const args *a)
{
    sr_picture pic;
    float *mask;
    sr_result r;
    size_t n = (size_t)R->w * R->h;
    R->mat = (uint8_t *)calloc(n, 1);
    if (!R->mat) return 0;
    if (a->cylinder == 2) cylinder_materials(R);
    if (!a->material) return 1;
    if ((r = sr_read_image(a->material, NULL, &pic)) != SR_OK) { cli_result_error(PROG, a->material, sr_result_string(r), r == SR_ERR_IO ? errno : 0); return 0; }
    mask = (float *)malloc((size_t)pic.width * pic.height * sizeof(float));
    if (!mask || sr_picture_channel(&pic, 0, mask) != SR_OK) { free(mask); sr_picture_free(&pic); return 0; }
    if (!pic.floats) { /* row 0 at the top: flip to the map's row order */
        int x, y;
        for (y = 0; y < pic.height / 2; y++)
            for (x = 0; x < pic.width; x++) {
                float *p = mask + (size_t)y * pic.width + x, *q = mask + (size_t)(pic.height - 1 - y) * pic.width + x, t = *p;
                *p = *q; *q = t;
            }
    }
    ero_paint_mask(R->mat, R->w, R->h, mask, pic.width, pic.height, 1, 0.5f, 1);
    free(mask);
    sr_picture_free(&pic);
    return 1;
}

/* ---- the mesh of the map: reconstruction or the height field's grid ------------------------- */

typedef struct tri_mesh { float *p; uint32_t *t; size_t nv, nt; dm_trimesh *rec; } tri_mesh;

static void tri_mesh_free(tri_mesh *m)
{
    if (m->rec) dm_trimesh_free(m->rec);
    else { free(m->p); free(m->t); }
    memset(m, 0, sizeof *m);
}

/* the height field as a grid mesh, every `stride`-th sample (stride 1 for the OBJ) */
static int grid_mesh(const run *R, int stride, tri_mesh *m)
{
    int gw = (R->w - 1) / stride + 1, gh = (R->h - 1) / stride + 1, x, y;
    memset(m, 0, sizeof *m);
    m->nv = (size_t)gw * gh;
    m->nt = 2 * (size_t)(gw - 1) * (gh - 1);
    m->p = (float *)malloc(3 * m->nv * sizeof(float));
    m->t = (uint32_t *)malloc(3 * (m->nt ? m->nt : 1) * sizeof(uint32_t));
    if (!m->p || !m->t) return 0;
    for (y = 0; y < gh; y++)
        for (x = 0; x < gw; x++) {
            float *p = m->p + 3 * ((size_t)y * gw + x);
            p[0] = (float)(x * stride) * R->g.spacing;
            p[1] = (float)(y * stride) * R->g.spacing;
            p[2] = R->disp[(size_t)(y * stride) * R->w + (size_t)(x * stride)];
        }
    for (y = 0; y + 1 < gh; y++)
        for (x = 0; x + 1 < gw; x++) {
            uint32_t a = (uint32_t)(y * gw + x), *t = m->t + 6 * ((size_t)y * (gw - 1) + x);
            t[0] = a; t[1] = a + 1; t[2] = a + 1 + (uint32_t)gw; t[3] = a; t[4] = a + 1 + (uint32_t)gw; t[5] = a + (uint32_t)gw;
        }
    return 1;
}

/* a generated cylinder's surface points as a grid mesh, closed around */
static int cylinder_mesh(const run *R, tri_mesh *m)
{
    int W = R->w, H = R->h, x, y, k;
    memset(m, 0, sizeof *m);
    m->nv = (size_t)W * H;
    m->nt = 2 * (size_t)W * (H - 1);
    m->p = (float *)malloc(3 * m->nv * sizeof(float));
    m->t = (uint32_t *)malloc(3 * (m->nt ? m->nt : 1) * sizeof(uint32_t));
    if (!m->p || !m->t) return 0;
    for (x = 0; x < W * H; x++)
        for (k = 0; k < 3; k++) m->p[3 * x + k] = R->g.pos[3 * x + k] - R->disp[x] * R->g.nrm[3 * x + k];
    for (y = 0; y + 1 < H; y++)
        for (x = 0; x < W; x++) {
            uint32_t a0 = (uint32_t)(y * W + x), a1 = (uint32_t)(y * W + (x + 1) % W), *t = m->t + 6 * ((size_t)y * W + x);
            t[0] = a0; t[1] = a1; t[2] = a1 + (uint32_t)W; t[3] = a0; t[4] = a1 + (uint32_t)W; t[5] = a0 + (uint32_t)W;
        }
    return 1;
}

static int surface_mesh(const run *R, int stride, tri_mesh *m)
{
    dm_result r;
    memset(m, 0, sizeof *m);
    if (!R->surface) return grid_mesh(R, stride, m);
    if (R->gen) return cylinder_mesh(R, m);
    if ((r = dm_reconstruct(R->map, R->param, R->bp, R->bnv, R->bi, R->bnt, NULL, &m->rec)) != DM_OK) {
        cli_result_error(PROG, "dm_reconstruct", dm_result_string(r), 0);
        return 0;
    }
    m->p = m->rec->positions; m->nv = m->rec->vertex_count; m->t = m->rec->indices; m->nt = m->rec->triangle_count;
    return 1;
}

/* ---- views ---------------------------------------------------------------------------------- */

static void wind_source(const run *R, const args *a, float src[3], float centre[3])
{
    double wl = sqrt(a->wind[0] * a->wind[0] + a->wind[1] * a->wind[1] + a->wind[2] * a->wind[2]), diag = 0;
    int k;
    float lo[3], hi[3];
    memcpy(lo, R->lo, sizeof lo); memcpy(hi, R->hi, sizeof hi);
    if (!R->surface) { lo[2] = hi[2] = 0; }
    for (k = 0; k < 3; k++) { centre[k] = 0.5f * (lo[k] + hi[k]); diag += (hi[k] - lo[k]) * (hi[k] - lo[k]); }
    diag = sqrt(diag);
    for (k = 0; k < 3; k++) src[k] = a->has_marker ? (float)a->marker[k] : (float)(centre[k] - 0.6 * diag * a->wind[k] / wl);
}

/* the shade of a change (world units, worn > 0) on the scale s: grey, orange where worn, blue where
   filled, linear in the change */
static void change_colour(float c, float s, float *rgb)
{
    static const float grey[3] = {0.72f, 0.72f, 0.72f}, worn[3] = {0.95f, 0.42f, 0.1f}, filled[3] = {0.2f, 0.45f, 1.0f};
    float t = s > 0 ? c / s : 0.0f;
    const float *to = t < 0 ? filled : worn;
    int k;
    t = fabsf(t) > 1 ? 1 : fabsf(t);
    for (k = 0; k < 3; k++) rgb[k] = grey[k] + t * (to[k] - grey[k]);
}

/* per-vertex shades of the change since "before": a grid mesh's vertices are texels; a
   reconstruction's are compared with the first one's (the same tessellation) along its normals */
static float *change_colours(run *R, const tri_mesh *m, int stride, float scale)
{
    float *c = (float *)malloc(3 * (m->nv ? m->nv : 1) * sizeof(float));
    size_t v;
    int k;
    if (!c) return NULL;
    if (m->rec) {
        if (!R->before_p) { /* this is "before" */
            R->before_p = (float *)malloc(3 * m->nv * sizeof(float));
            if (R->before_p) memcpy(R->before_p, m->p, 3 * m->nv * sizeof(float));
            R->before_nv = m->nv;
        }
        for (v = 0; v < m->nv; v++) {
            float ch = 0.0f;
            if (R->before_p && R->before_nv == m->nv)
                for (k = 0; k < 3; k++) ch += (R->before_p[3 * v + k] - m->p[3 * v + k]) * m->rec->normals[3 * v + k];
            change_colour(ch, scale, c + 3 * v);
        }
    } else if (R->gen) {
        for (v = 0; v < m->nv; v++) change_colour(R->disp[v] - R->disp0[v], scale, c + 3 * v);
    } else {
        int gw = (R->w - 1) / stride + 1;
        for (v = 0; v < m->nv; v++) {
            size_t i = (size_t)((int)(v / gw) * stride) * R->w + (size_t)((int)(v % gw) * stride);
            change_colour(R->disp0[i] - R->disp[i], scale, c + 3 * v);
        }
    }
    return c;
}

/* renders the map's mesh from the side the wind comes from, with a marker at the wind source, the
   change since "before" shaded on the scale `scale` */
static int render_view(run *R, const args *a, const char *caption, float scale)
{
    tri_mesh m;
    sr_framebuffer fb;
    sr_camera cam;
    sr_draw_desc d;
    float src[3], c[3], eye[3], up[3] = {0, 0, 1}, bg[4] = {0.08f, 0.08f, 0.1f, 1}, *colours;
    sr_image8 *img = &R->views[R->view_count];
    int S = (int)a->size, k, mx, my, stride = R->surface ? 1 : (R->w > 256 ? R->w / 256 : 1);
    double dist = 0;
    if (!surface_mesh(R, stride, &m)) return 0;
    wind_source(R, a, src, c);
    for (k = 0; k < 3; k++) dist += (src[k] - c[k]) * (src[k] - c[k]);
    dist = sqrt(dist);
    if (a->has_view) { /* from the direction given */
        double vl = sqrt(a->view[0] * a->view[0] + a->view[1] * a->view[1] + a->view[2] * a->view[2]);
        for (k = 0; k < 3; k++) eye[k] = (float)(c[k] + 1.6 * dist * a->view[k] / vl);
    } else
        for (k = 0; k < 3; k++) eye[k] = (float)(c[k] + 1.6 * (src[k] - c[k]) + 0.25 * dist * (k == 2)); /* beside the source */
    if (fabs(src[0] - c[0]) < 1e-6 * dist && fabs(src[1] - c[1]) < 1e-6 * dist) { up[1] = 1; up[2] = 0; }
    if (sr_framebuffer_create(&fb, S, S, NULL) != SR_OK) { tri_mesh_free(&m); return 0; }
    sr_framebuffer_clear(&fb, bg, 1.0f);
    sr_camera_look_at(&cam, eye, c, up, 40.0f, 1.0f, (float)(0.05 * dist), (float)(8 * dist));
    sr_draw_desc_default(&d);
    d.positions = m.p; d.vertex_count = m.nv; d.indices = m.t; d.triangle_count = m.nt;
    d.colors = colours = change_colours(R, &m, stride, scale);
    if (!colours) { sr_framebuffer_free(&fb); tri_mesh_free(&m); return 0; }
    sr_draw_mesh(&fb, &cam, &d);
    free(colours);
    img->width = img->height = S; img->channels = 3;
    img->pixels = (uint8_t *)malloc((size_t)S * S * 3);
    if (!img->pixels) { sr_framebuffer_free(&fb); tri_mesh_free(&m); return 0; }
    sr_framebuffer_to_rgb8(&fb, img->pixels, 3);
    { /* the wind source: a white disc where it projects (clamped into the view) */
        float p[3] = {src[0], src[1], src[2]}, o[3], dir[3], best = 1e30f;
        int x, y, bx = S / 2, by = S / 8;
        for (y = 0; y < S; y += 4)
            for (x = 0; x < S; x += 4) {
                float q[3], t, dd = 0;
                sr_camera_ray(&cam, S, S, x + 0.5f, y + 0.5f, o, dir);
                t = (p[0] - o[0]) * dir[0] + (p[1] - o[1]) * dir[1] + (p[2] - o[2]) * dir[2];
                for (k = 0; k < 3; k++) { q[k] = o[k] + t * dir[k] - p[k]; dd += q[k] * q[k]; }
                if (dd < best) { best = dd; bx = x; by = y; }
            }
        for (my = -6; my <= 6; my++)
            for (mx = -6; mx <= 6; mx++)
                if (mx * mx + my * my <= 36 && bx + mx >= 0 && by + my >= 0 && bx + mx < S && by + my < S)
                    memset(img->pixels + 3 * ((size_t)(by + my) * S + (size_t)(bx + mx)), 255, 3);
    }
    snprintf(R->captions[R->view_count], sizeof R->captions[0], "%s", caption);
    R->view_count++;
    sr_framebuffer_free(&fb);
    tri_mesh_free(&m);
    return 1;
}

/* ---- outputs -------------------------------------------------------------------------------- */

static int write_outputs(run *R, const args *a, cli_outputs *outs)
{
    char path[CLI_PATH_MAX];
    const char *tmp;
    size_t n = (size_t)R->w * R->h, i;
    float lo = 1e30f, hi = -1e30f;
    uint16_t *g16;
    sr_image8 sheet;
    const char *caps[MAX_RENDERS + 1];
    tri_mesh m;
    sr_result r;
    int k, ok;
    snprintf(path, sizeof path, "%s_map.pfm", a->prefix);
    if (!(tmp = cli_output_add(outs, PROG, path))) return 0;
    if ((r = sr_write_pfm(tmp, R->disp, R->w, R->h, 1)) != SR_OK) { cli_result_error(PROG, path, sr_result_string(r), errno); return 0; }
    for (i = 0; i < n; i++) {
        if (R->surface && R->map && !R->map->valid[i]) continue;
        if (R->disp[i] < lo) lo = R->disp[i];
        if (R->disp[i] > hi) hi = R->disp[i];
    }
    g16 = (uint16_t *)malloc(n * sizeof(uint16_t));
    if (!g16) return 0;
    for (i = 0; i < n; i++) {
        float v = hi > lo ? (R->disp[i] - lo) / (hi - lo) : 0.0f;
        g16[i] = (uint16_t)(v < 0 ? 0 : v > 1 ? 65535 : v * 65535.0f + 0.5f);
    }
    snprintf(path, sizeof path, "%s_map.png", a->prefix);
    ok = (tmp = cli_output_add(outs, PROG, path)) != NULL && (r = sr_write_png16(tmp, g16, R->w, R->h, 1, 1)) == SR_OK;
    free(g16);
    if (!ok) { if (tmp) cli_result_error(PROG, path, sr_result_string(r), errno); return 0; }
    if (!surface_mesh(R, 1, &m)) return 0;
    snprintf(path, sizeof path, "%s.obj", a->prefix);
    ok = (tmp = cli_output_add(outs, PROG, path)) != NULL && mio_write_obj(tmp, m.p, m.nv, m.t, m.nt, NULL) == MIO_OK;
    tri_mesh_free(&m);
    if (!ok) { if (tmp) cli_file_error(PROG, path, "cannot write", errno); return 0; }
    for (k = 0; k < R->view_count; k++) caps[k] = R->captions[k];
    if (sr_contact_sheet(R->views, caps, R->view_count, 0, NULL, &sheet) != SR_OK) return 0;
    snprintf(path, sizeof path, "%s_render.png", a->prefix);
    ok = (tmp = cli_output_add(outs, PROG, path)) != NULL && (r = sr_write_png(tmp, sheet.pixels, sheet.width, sheet.height, 3, 0)) == SR_OK;
    sr_free(NULL, sheet.pixels);
    if (!ok) { if (tmp) cli_result_error(PROG, path, sr_result_string(r), errno); return 0; }
    return 1;
}

/* the prefix's directory, created when missing (one level; a failure shows when the files are written) */
static void make_parent_dir(const char *prefix)
{
    char dir[CLI_PATH_MAX];
    const char *slash = strrchr(prefix, '/');
    size_t n;
    struct stat st;
    if (!slash || slash == prefix) return;
    n = (size_t)(slash - prefix);
    if (n >= sizeof dir) return;
    memcpy(dir, prefix, n);
    dir[n] = '\0';
    if (stat(dir, &st) != 0) mkdir(dir, 0777);
}

/* ---- erosion with progress ------------------------------------------------------------------ */

typedef struct progress { long done_before, segment, total; double last; } progress;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int show_progress(void *user, float done)
{
    progress *p = (progress *)user;
    if (now_s() - p->last > 1.0) { /* long runs only: a line a second at most */
        fprintf(stderr, "erode: step %ld of %ld\n", p->done_before + (long)(done * (float)p->segment + 0.5f), p->total);
        p->last = now_s();
    }
    return 0;
}

int main(int argc, char **argv)
{
    args a;
    run R;
    cli_outputs outs;
    ero_options o = ero_default_options();
    ero_material mats[2];
    ero_report seg, total;
    ero_result er;
    ero_workspace *ws = NULL; /* the grid's tables, made once for the render segments' calls */
    progress pr;
    long done = 0;
    int k, status = 1, u = parse_args(argc, argv, &a);
    size_t n, i;
    float *final = NULL, scale = 0.0f;
    double t0, t_erode = 0;
    char cap[48];
    if (u) return u;
    memset(&R, 0, sizeof R);
    memset(&total, 0, sizeof total);
    cli_outputs_init(&outs);
    if (!(a.cylinder ? make_cylinder(&R, &a) : a.in && is_image(a.in) ? load_heightmap(&R, &a) : load_mesh(&R, &a))) goto done;
    if (!load_material(&R, &a)) goto done;
    n = (size_t)R.w * R.h;
    R.disp0 = (float *)malloc((size_t)R.w * R.h * sizeof(float));
    if (!R.disp0) goto done;
    memcpy(R.disp0, R.disp, (size_t)R.w * R.h * sizeof(float));
    mats[0].eps_min = (float)a.soft[0]; mats[0].eps_max = (float)a.soft[1]; mats[0].eps_medium = 0; mats[0].ambient = 0;
    mats[1].eps_min = (float)a.hard[0]; mats[1].eps_max = (float)a.hard[1]; mats[1].eps_medium = 0; mats[1].ambient = 0;
    for (k = 0; k < 3; k++) o.wind[k] = (float)a.wind[k];
    o.rate = (float)a.rate;
    o.progress = show_progress;
    o.user = &pr;
    pr.total = a.steps; pr.last = now_s();
    t0 = now_s();
    er = ero_workspace_create(&R.g, &o, &ws);
    t_erode += now_s() - t0;
    if (er != ERO_OK) { cli_result_error(PROG, "ero_workspace_create", ero_result_string(er), 0); goto done; }
    for (k = 0; k <= a.render_count; k++) { /* erode up to each render step (resuming gives the same bits) */
        long until = k < a.render_count ? (long)a.render_steps[k] : a.steps;
        if (until > done) {
            pr.done_before = done;
            pr.segment = until - done;
            t0 = now_s();
            er = ero_erode_ws(ws, &R.g, R.mat, mats, 2, (int)(until - done), &o, NULL, &seg);
            t_erode += now_s() - t0;
            if (er != ERO_OK) { cli_result_error(PROG, "ero_erode_ws", ero_result_string(er), 0); goto done; }
            total.eroded += seg.eroded; total.deposited += seg.deposited;
            if (seg.max_change > total.max_change) total.max_change = seg.max_change;
            done = until;
        }
        if (k < a.render_count) { /* the map now, rendered when all are done (one shading scale) */
            if (!(R.states[k] = (float *)malloc(n * sizeof(float)))) goto done;
            memcpy(R.states[k], R.disp, n * sizeof(float));
        }
    }
    if (!(final = (float *)malloc(n * sizeof(float)))) goto done;
    memcpy(final, R.disp, n * sizeof(float));
    for (i = 0; i < n; i++) /* the shading scale: the largest change over the run */
        if ((!R.map || R.map->valid[i]) && fabsf(final[i] - R.disp0[i]) > scale) scale = fabsf(final[i] - R.disp0[i]);
    memcpy(R.disp, R.disp0, n * sizeof(float));
    if (!render_view(&R, &a, "before", scale)) goto done;
    for (k = 0; k < a.render_count; k++) {
        snprintf(cap, sizeof cap, "after %ld step%s", (long)a.render_steps[k], a.render_steps[k] == 1 ? "" : "s");
        memcpy(R.disp, R.states[k], n * sizeof(float));
        if (!render_view(&R, &a, cap, scale)) goto done;
    }
    memcpy(R.disp, final, n * sizeof(float));
    make_parent_dir(a.prefix);
    if (!write_outputs(&R, &a, &outs) || !cli_outputs_commit(&outs, PROG)) goto done;
    printf("RESULT erosion domain=%s res=%dx%d steps=%ld eroded=%.6g deposited=%.6g max_change=%.6g step_ms=%.3f\n",
           R.surface ? "surface" : "heightfield", R.w, R.h, a.steps, total.eroded, total.deposited, total.max_change,
           1e3 * t_erode / (double)a.steps);
    status = 0;
done:
    if (status) cli_outputs_discard(&outs);
    ero_workspace_destroy(ws);
    free(final);
    run_free(&R);
    return status;
}
