/* fuzz_subdiv4.c - fuzz target for subdiv4.h: curves, grids, terrain, butterfly
   libFuzzer: clang -g -O1 -I. -fsanitize=fuzzer,address,undefined tests/fuzz_subdiv4.c -o fuzz_subdiv4 -lm
   plain:     gcc -std=c99 -g -O1 -I. tests/fuzz_subdiv4.c tests/fuzz_main.c -o fuzz_subdiv4 -lm
              && ./fuzz_subdiv4 tests/fuzz/corpus/subdiv4
   The first byte picks the entry point (bits 0-1; bit 2: a grid's columns first; bit 7: raw
   numbers), the next ones its sizes, options, a cancelling progress
   callback and the allocation to fail (0 = none); numbers are read either as raw 8-byte doubles
   / 4-byte floats (any bits: NaN, infinities, 1e308, subnormals) or as small values, by a flag.
   Every call must return SD4_OK with a sound result, or one of the documented codes with nothing
   held: on SD4_OK the curve and grid outputs are finite and keep the input points bit for bit,
   the meshes have indices below their vertex count and finite positions (and normals), the
   butterfly keeps the old vertices, and the terrain stays under its max_triangles. Allocations
   are limited to 64 MB in all. A broken rule calls abort(), which the fuzzer reports. */
#define SD4_IMPLEMENTATION
#include "subdiv4.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct fz_in { const uint8_t *p; size_t n; int raw; } fz_in;

static unsigned fz_byte(fz_in *in)
{
    unsigned b;
    if (!in->n) return 0;
    b = *in->p++;
    in->n--;
    return b;
}

static double fz_double(fz_in *in)
{
    double d = 0.0;
    if (in->raw && in->n >= 8) {
        memcpy(&d, in->p, 8);
        in->p += 8;
        in->n -= 8;
        return d;
    }
    return ((double)fz_byte(in) - 128.0) / 16.0;
}

static float fz_float(fz_in *in)
{
    float f = 0.0f;
    if (in->raw && in->n >= 4) {
        memcpy(&f, in->p, 4);
        in->p += 4;
        in->n -= 4;
        return f;
    }
    return ((float)fz_byte(in) - 128.0f) / 16.0f;
}

/* ---- a counting allocator that fails the k-th call and holds at most 64 MB ------------------ */

typedef struct fz_alloc { size_t live; long blocks, calls, fail_at; } fz_alloc;

static void *fz_malloc(void *user, size_t n)
{
    fz_alloc *f = (fz_alloc *)user;
    size_t *p;
    if (++f->calls == f->fail_at || n > ((size_t)64 << 20) - f->live) return NULL;
    p = (size_t *)malloc(n + sizeof(size_t) * 2);
    if (!p) return NULL;
    p[0] = n;
    f->live += n;
    f->blocks++;
    return p + 2;
}

static void fz_free(void *user, void *q)
{
    fz_alloc *f = (fz_alloc *)user;
    size_t *p;
    if (!q) return;
    p = (size_t *)q - 2;
    f->live -= p[0];
    f->blocks--;
    free(p);
}

typedef struct fz_prog { long calls, cancel_at; } fz_prog;

static int fz_progress(void *user, float done)
{
    fz_prog *g = (fz_prog *)user;
    if (!(done >= 0.0f && done <= 1.0f)) abort(); /* progress out of [0, 1] */
    return ++g->calls == g->cancel_at;
}

static void fz_check(int ok) { if (!ok) abort(); }

static int fz_known(sd4_result r)
{
    return r == SD4_OK || r == SD4_ERR_INVALID_ARGUMENT || r == SD4_ERR_BAD_INDEX || r == SD4_ERR_BAD_POSITION ||
           r == SD4_ERR_TOO_LARGE || r == SD4_ERR_BUFFER_TOO_SMALL || r == SD4_ERR_OUT_OF_MEMORY || r == SD4_CANCELLED ||
           r == SD4_ERR_NOT_FINITE;
}

/* options from one flag byte and a w table: end rules, convention, a w per level */
static void fz_options(fz_in *in, sd4_options *o, double *wl, int levels, const sd4_allocator *a, fz_prog *g)
{
    unsigned f = fz_byte(in);
    int k;
    memset(o, 0, sizeof *o);
    o->end_rule = (int)(f & 3);           /* 3: an invalid rule */
    o->end_rule_y = (int)((f >> 2) & 3);
    o->omega_convention = (int)((f >> 4) & 1);
    if (f & 0x20) {
        for (k = 0; k < levels && k < 16; k++) wl[k] = fz_double(in);
        o->omega_per_level = wl;
    }
    o->allocator = a;
    o->progress = (f & 0x40) ? fz_progress : NULL;
    o->progress_user = g;
}

static void fz_curve_or_grid(fz_in *in, int grid, int columns_first, const sd4_allocator *a, fz_prog *g)
{
    size_t nx = fz_byte(in) % 17, ny = grid ? fz_byte(in) % 9 : 1, np, m = 0, mx = 0, my = 0, i, cap, S;
    int dim = (int)(fz_byte(in) % 5), levels = (int)(fz_byte(in) % 9) - (grid ? 2 : 0), closed;
    double pts[16 * 8 * 4], wl[16], w, *out;
    sd4_options o;
    sd4_result r, rs;
    fz_options(in, &o, wl, levels, a, g);
    w = fz_double(in);
    if (dim == 0) dim = 1;
    np = nx * ny;
    for (i = 0; i < np * (size_t)dim; i++) pts[i] = fz_double(in);
    closed = o.end_rule == SD4_END_PERIODIC;
    rs = grid ? sd4_grid_size(nx, ny, levels < 0 ? 0 : levels, &o, &mx, &my) : sd4_curve_size(nx, closed, levels < 0 ? 0 : levels, &m);
    if (rs != SD4_OK) {
        fz_check(fz_known(rs) && rs != SD4_OK);
        mx = my = m = 1;
    }
    if (grid) m = mx * my;
    if (m > (1u << 16)) return;                    /* keep each run small */
    cap = m * (size_t)(grid ? dim : 1) - (fz_byte(in) & 1); /* sometimes one short */
    out = (double *)malloc(sizeof(double) * (m * (size_t)dim + 1));
    if (!out) return;
    if (grid && columns_first) r = sd4_grid_refine_columns_first(np ? pts : NULL, nx, ny, dim, w, levels, &o, out, cap);
    else if (grid) r = sd4_grid_refine(np ? pts : NULL, nx, ny, dim, w, levels, &o, out, cap);
    else r = sd4_curve_refine(nx ? pts : NULL, nx, dim, w, levels, &o, out, cap);
    fz_check(fz_known(r));
    if (r == SD4_OK) {
        fz_check(rs == SD4_OK && cap >= m * (size_t)(grid ? dim : 1));
        for (i = 0; i < m * (size_t)dim; i++) fz_check(isfinite(out[i]));
        S = (size_t)1 << levels;
        if (!grid)
            for (i = 0; i < nx; i++) fz_check(memcmp(out + i * S * (size_t)dim, pts + i * (size_t)dim, sizeof(double) * (size_t)dim) == 0);
        else
            for (i = 0; i < np; i++) {
                size_t x = i % nx, y = i / nx;
                fz_check(memcmp(out + ((y * S) * mx + x * S) * (size_t)dim, pts + i * (size_t)dim, sizeof(double) * (size_t)dim) == 0);
            }
    }
    free(out);
}

static void fz_mesh_sound(const sd4_mesh *m, int normals)
{
    size_t i;
    for (i = 0; i < 3 * m->triangle_count; i++) fz_check(m->indices[i] < m->vertex_count);
    for (i = 0; i < 3 * m->vertex_count; i++) fz_check(isfinite(m->positions[i]));
    if (normals)
        for (i = 0; i < 3 * m->triangle_count; i++) fz_check(isfinite(m->face_normals[i]));
}

static void fz_terrain(fz_in *in, const sd4_allocator *a, fz_prog *g)
{
    sd4_terrain_desc d;
    sd4_mesh m;
    sd4_result r;
    double h[9 * 9];
    unsigned f;
    size_t i;
    memset(&d, 0, sizeof d);
    f = fz_byte(in);
    d.nx = 2 + fz_byte(in) % 8;
    d.ny = 2 + fz_byte(in) % 8;
    if (f & 1) {
        for (i = 0; i < d.nx * d.ny; i++) h[i] = fz_double(in);
        d.heights = h;
    } else {
        d.amplitude = fz_double(in);
        d.smooth_passes = (int)(fz_byte(in) % 3);
        d.seed = fz_byte(in);
    }
    d.spacing = (f & 2) ? fz_double(in) : 0.0;
    d.omega = fz_double(in);
    d.levels = (int)(fz_byte(in) % 5) - (int)((f >> 2) & 1);
    d.epsilon = fz_double(in);
    d.sigma = fz_double(in);
    d.border = (int)((f >> 3) & 1) + ((f & 0x80) ? 2 : 0); /* 2, 3: invalid */
    d.omega_convention = (int)((f >> 4) & 1);
    d.max_split = (int)(fz_byte(in) % 12);
    d.max_triangles = 1 + (size_t)(fz_byte(in)) * 1024;          /* at most 256k triangles */
    d.allocator = a;
    d.progress = (f & 0x20) ? fz_progress : NULL;
    d.progress_user = g;
    r = sd4_terrain_build(&d, &m);
    fz_check(fz_known(r));
    if (r != SD4_OK) {
        fz_check(m.positions == NULL && m.indices == NULL && m.face_normals == NULL && m.triangle_count == 0);
        return;
    }
    fz_check(m.triangle_count <= d.max_triangles && m.face_normals != NULL);
    fz_mesh_sound(&m, 1);
    sd4_free_mesh(&m);
}

static void fz_butterfly(fz_in *in, const sd4_allocator *a, fz_prog *g)
{
    float pos[3 * 32];
    uint32_t tri[3 * 48];
    size_t nv = fz_byte(in) % 33, nt = fz_byte(in) % 49, i;
    int levels = (int)(fz_byte(in) % 5);
    double w, wl[16];
    sd4_options o;
    sd4_mesh m;
    sd4_result r;
    fz_options(in, &o, wl, 0, a, g);
    w = fz_double(in);
    for (i = 0; i < 3 * nv; i++) pos[i] = fz_float(in);
    for (i = 0; i < 3 * nt; i++) tri[i] = (uint32_t)(fz_byte(in) % (nv + 2)); /* some out of range */
    r = sd4_butterfly(pos, nv, tri, nt, levels, w, &o, &m);
    fz_check(fz_known(r));
    if (r != SD4_OK) {
        fz_check(m.positions == NULL && m.indices == NULL && m.vertex_count == 0);
        return;
    }
    fz_check(m.vertex_count >= nv && memcmp(m.positions, pos, sizeof(float) * 3 * nv) == 0);
    fz_mesh_sound(&m, 0);
    sd4_free_mesh(&m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fz_alloc f = {0, 0, 0, 0};
    fz_prog g = {0, 0};
    sd4_allocator a;
    unsigned op, k;
    in.p = data;
    in.n = size;
    in.raw = 0;
    op = fz_byte(&in);
    k = fz_byte(&in);
    in.raw = (op & 0x80) != 0;
    f.fail_at = (long)(k & 15);          /* 0: never */
    g.cancel_at = (long)(k >> 4);        /* 0: never */
    a.alloc = fz_malloc;
    a.free = fz_free;
    a.user = &f;
    switch (op & 3) {
    case 0: fz_curve_or_grid(&in, 0, 0, &a, &g); break;
    case 1: fz_curve_or_grid(&in, 1, (op & 4) != 0, &a, &g); break;
    case 2: fz_terrain(&in, &a, &g); break;
    default: fz_butterfly(&in, &a, &g); break;
    }
    fz_check(f.blocks == 0 && f.live == 0); /* nothing held after any result */
    return 0;
}
