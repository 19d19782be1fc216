/* fuzz_erosion.c - fuzz target for erosion.h: ero_erode on height fields and surface sample grids
   built from the bytes (sizes, spacing, wrap, valid masks, neighbours and rotations, maps,
   materials and ids, every option), ero_resolve_options, ero_resolve_material, ero_paint_mask and
   ero_paint_sphere.
   libFuzzer: clang -g -O1 -I. -Itests -fsanitize=fuzzer,address,undefined tests/fuzz_erosion.c -o fuzz_erosion -lm
   plain:     gcc -std=c99 -g -O1 -I. -Itests tests/fuzz_erosion.c tests/fuzz_main.c -o fuzz_erosion -lm
              && ./fuzz_erosion tests/fuzz/corpus/erosion
   Byte 0: the domain (bit 0: surface), raw numbers (bit 7: 4-byte floats of any bits, else
   (b - 128) / 16); byte 1: the allocation to fail and the progress call that cancels (nibbles,
   0 = none). Grids are at most 12 x 12, at most 3 steps, so one run is cheap. Every call returns
   ERO_OK with a finite map (and finite, non-negative report volumes), ERO_CANCELLED with the steps
   it reports done, or a named error with the map untouched; nothing is held after any result; a
   broken rule calls abort(). */
#define FZ_HELPERS_ONLY
#include "fuzz_deform.c" /* the byte reader and failing allocator */
#define ERO_IMPLEMENTATION
#include "erosion.h"

enum { FZ_MAXW = 12 };

static int fz_known(ero_result r) { return strcmp(ero_result_string(r), "ERO_ERR_?") != 0; }

static void fz_options(fz_in *in, ero_options *o, const ero_allocator *al, fz_cancel *cc)
{
    unsigned f = fz_u8(in);
    *o = ero_default_options();
    o->wind[0] = fz_f32(in);
    o->wind[1] = fz_f32(in);
    o->wind[2] = fz_f32(in);
    if (f & 1) { o->force = fz_f32(in); o->rate = fz_f32(in); }
    if (f & 2) { o->normal_radius = fz_f32(in); o->filter_sigma = fz_f32(in); o->curvature_length = fz_f32(in); }
    if (f & 4) { o->deposit_ratio = fz_f32(in); o->deposit_ramp = fz_f32(in); }
    if (f & 8) { o->bound = (int)(fz_u8(in) % 5) - 1; o->bound_value = fz_f32(in); }
    o->flags = (int)(fz_u8(in) & 7);
    o->allocator = al;
    o->progress = (f & 16) ? fz_progress : NULL;
    o->user = cc;
}

static void fz_report_sound(const ero_report *r, int steps)
{
    fz_check(isfinite(r->eroded) && isfinite(r->deposited) && r->eroded >= 0.0 && r->deposited >= 0.0);
    fz_check(isfinite(r->max_change) && r->max_change >= 0.0f);
    fz_check(r->steps >= 0 && r->steps <= steps);
}

static void fz_erode(fz_in *in, unsigned op, const ero_allocator *al, fz_cancel *cc)
{
    float disp[FZ_MAXW * FZ_MAXW], before[FZ_MAXW * FZ_MAXW], pos[3 * FZ_MAXW * FZ_MAXW], nrm[3 * FZ_MAXW * FZ_MAXW];
    float area[FZ_MAXW * FZ_MAXW], mask[16], centre[3];
    uint32_t nbr[4 * FZ_MAXW * FZ_MAXW];
    uint8_t rot[4 * FZ_MAXW * FZ_MAXW], valid[FZ_MAXW * FZ_MAXW], mat[FZ_MAXW * FZ_MAXW];
    ero_material mats[3], resolved;
    ero_options o, ro;
    ero_report total, steps_rep[3];
    ero_grid g;
    ero_result r;
    int w = 1 + (int)(fz_u8(in) % FZ_MAXW), h = 1 + (int)(fz_u8(in) % FZ_MAXW), steps = (int)(fz_u8(in) % 4), nm, k;
    unsigned f = fz_u8(in);
    size_t n = (size_t)w * (size_t)h, i;
    for (i = 0; i < n; i++) {
        disp[i] = fz_f32(in);
        valid[i] = (uint8_t)((f & 1) ? fz_u8(in) & 1 : 1);
        mat[i] = (uint8_t)(fz_u8(in) % 4); /* id 3 is out of range for up to 3 materials */
    }
    if (op & 1) {
        for (i = 0; i < n; i++) {
            size_t x = i % (size_t)w, y = i / (size_t)w;
            int d;
            pos[3 * i] = (float)x * 0.1f + ((f & 2) ? fz_f32(in) * 0.01f : 0.0f);
            pos[3 * i + 1] = (float)y * 0.1f;
            pos[3 * i + 2] = (f & 2) ? fz_f32(in) * 0.01f : 0.0f;
            nrm[3 * i] = (f & 4) ? fz_f32(in) : 0.0f;
            nrm[3 * i + 1] = 0.0f;
            nrm[3 * i + 2] = 1.0f;
            area[i] = (f & 8) ? fz_f32(in) : 0.01f;
            for (d = 0; d < 4; d++) {
                unsigned b = fz_u8(in);
                long nx = (long)x + (d == 0) - (d == 1), ny = (long)y + (d == 2) - (d == 3);
                if (b < 200) nbr[4 * i + d] = nx >= 0 && ny >= 0 && nx < w && ny < h ? (uint32_t)(ny * w + nx) : UINT32_MAX;
                else if (b < 250) nbr[4 * i + d] = (uint32_t)(fz_u8(in) % (n + 1)); /* n: out of range */
                else nbr[4 * i + d] = UINT32_MAX;
                rot[4 * i + d] = (uint8_t)(b < 180 ? 0 : (b % 5)); /* 4: out of range */
            }
        }
        g = ero_surface_grid(w, h, pos, nrm, disp, area, (f & 1) ? valid : NULL, nbr, rot);
    } else {
        g = ero_heightfield_grid(w, h, disp, (f & 16) ? fz_f32(in) : 0.1f, (f & 32) != 0);
        g.valid = (f & 1) ? valid : NULL;
    }
    nm = (int)(fz_u8(in) % 4);
    for (k = 0; k < nm; k++) {
        mats[k].eps_min = fz_f32(in);
        mats[k].eps_max = fz_f32(in);
        mats[k].eps_medium = (f & 64) ? fz_f32(in) : 0.0f;
        mats[k].ambient = (f & 64) ? fz_f32(in) : 0.0f;
        if (ero_resolve_material(&mats[k], &resolved) >= 0)
            fz_check(resolved.eps_min <= resolved.eps_medium && resolved.eps_medium <= resolved.eps_max &&
                     (double)resolved.ambient > (double)resolved.eps_min / ((double)resolved.eps_max - resolved.eps_min));
    }
    fz_options(in, &o, al, cc);
    if (ero_resolve_options(&g, &o, &ro) == ERO_OK) fz_check(ro.rate >= 0.0f && ro.normal_radius >= 0.0f);
    memcpy(before, disp, n * sizeof(float));
    r = ero_erode(&g, (f & 128) ? mat : NULL, nm ? mats : NULL, (size_t)nm, steps, &o, steps_rep, &total);
    fz_check(fz_known(r));
    if (r == ERO_OK || r == ERO_CANCELLED) {
        fz_check(fz_all_finite_f(disp, n));
        fz_report_sound(&total, steps);
        if (r == ERO_OK) fz_check(total.steps == steps);
        for (k = 0; k < total.steps; k++) fz_report_sound(&steps_rep[k], steps);
    } else {
        fz_check(memcmp(before, disp, n * sizeof(float)) == 0); /* untouched */
        fz_check(total.steps == 0);
    }
    /* the painting helpers on the same grid */
    for (k = 0; k < 16; k++) mask[k] = fz_f32(in);
    r = ero_paint_mask(mat, w, h, mask, 1 + (int)(fz_u8(in) % 4), 1 + (int)(fz_u8(in) % 4), 1, fz_f32(in), 2);
    fz_check(r == ERO_OK || fz_known(r));
    centre[0] = fz_f32(in); centre[1] = fz_f32(in); centre[2] = fz_f32(in);
    r = ero_paint_sphere(&g, mat, centre, fz_f32(in), 1);
    fz_check(r == ERO_OK || fz_known(r));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fz_heap h;
    fz_cancel c;
    ero_allocator a;
    unsigned op = fz_begin(&in, data, size, &h, &c);
    FZ_HEAP_ALLOCATOR(a, &h);
    fz_erode(&in, op, &a, &c);
    fz_check(h.live == 0 && h.bytes == 0); /* nothing held after any result */
    return 0;
}
