/* test_texel.c - texel.h: static grass texel, points and splatting, the ageing model, bad input.
   Each check states the property it asserts and where its tolerance comes from.
   TEST_SANITIZE=1 (make sanitize) builds the round-trip texel at 64^3 instead of 128^3. */
#define TVT_IMPLEMENTATION
#include "texel.h"
#include "test.h"
#include <stdlib.h>

/* ---- a counting allocator that can fail the k-th allocation ---------------------------------- */
typedef struct counting { long live, calls, fail_at; } counting;
static void *c_alloc(void *u, size_t n)
{
    counting *c = (counting *)u;
    if (++c->calls == c->fail_at) return NULL;
    c->live++;
    return malloc(n);
}
static void c_free(void *u, void *p)
{
    counting *c = (counting *)u;
    if (p) { c->live--; free(p); }
}
static tvt_allocator counting_allocator(counting *c)
{
    tvt_allocator a;
    a.alloc = c_alloc; a.free = c_free; a.user = c;
    return a;
}

static int cancel_now(void *u, float done) { (void)u; (void)done; return 1; }

/* hue in degrees of a linear RGB colour (0 red, 60 yellow, 120 green) */
static double hue_deg(const float *c)
{
    double mx = c[0], mn = c[0], h;
    int i;
    for (i = 1; i < 3; i++) { if (c[i] > mx) mx = c[i]; if (c[i] < mn) mn = c[i]; }
    if (mx - mn < 1e-9) return 0;
    if (mx == c[0]) h = 60.0 * fmod((c[1] - c[2]) / (mx - mn) + 6.0, 6.0);
    else if (mx == c[1]) h = 60.0 * ((c[2] - c[0]) / (mx - mn) + 2.0);
    else h = 60.0 * ((c[0] - c[1]) / (mx - mn) + 4.0);
    return h;
}

static tvt_blade one_blade(float x, float y, float height, float radius, float lean_deg, float az_deg)
{
    tvt_blade b;
    float l = lean_deg * 3.14159265f / 180.0f, a = az_deg * 3.14159265f / 180.0f;
    memset(&b, 0, sizeof(b));
    b.root[0] = x; b.root[1] = y;
    b.axis[0] = sinf(l) * cosf(a); b.axis[1] = sinf(l) * sinf(a); b.axis[2] = cosf(l);
    b.bend[0] = cosf(l) * cosf(a); b.bend[1] = cosf(l) * sinf(a); b.bend[2] = -sinf(l);
    b.height = height; b.radius = radius; b.brightness = 1.0f;
    return b;
}

static int texels_equal(const tvt_texel *a, const tvt_texel *b)
{
    size_t nb = (size_t)a->bricks_per_side;
    if (a->res != b->res || a->bits != b->bits || a->brick_count != b->brick_count ||
        a->density_max != b->density_max)
        return 0;
    if (memcmp(a->brick_index, b->brick_index, nb * nb * nb * 4) || a->voxel_count != b->voxel_count) return 0;
    if (a->brick_count && (memcmp(a->brick_mask, b->brick_mask, a->brick_count * 8) ||
                           memcmp(a->brick_offset, b->brick_offset, a->brick_count * 4)))
        return 0;
    return memcmp(a->data, b->data, a->voxel_count * 11 * (size_t)(a->bits / 8)) == 0;
}

/* ---- 1. static texel ------------------------------------------------------------------------- */
static void test_static_texel(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_blade b = one_blade(20.25f, 30.5f, 40.0f, 3.0f, 0.0f, 0.0f);
    tvt_texel t, t8, t2;
    tvt_voxel v;
    double cone, total;
    d.res = 64; d.bits = 16; d.supersample = 4;
    T_CHECK(tvt_build_texel(&b, 1, &d, &t) == TVT_OK);
    /* density is coverage: its sum is the cone's volume pi r^2 H / 3 up to the supersampling
       error of the surface voxels (4^3 samples; about 1% at r = 3 voxels), so 3% */
    cone = 3.14159265 * 3.0 * 3.0 * 40.0 / 3.0;
    total = tvt_texel_total_density(&t);
    T_NEAR(total / cone, 1.0, 0.03);
    /* on the axis, near the root: tangent = the axis (z), the normal short (vein cell) */
    tvt_texel_voxel(&t, 20, 30, 2, &v);
    T_CHECK(v.density > 0.9f);
    T_NEAR(v.tangent[2], 1.0, 2.0 / 65535 + 1e-6);
    T_CHECK(sqrtf(v.normal[0] * v.normal[0] + v.normal[1] * v.normal[1] + v.normal[2] * v.normal[2]) < 0.35f);
    /* at the surface: the normal points away from the axis (mesophyll cell), +x here */
    tvt_texel_voxel(&t, 22, 30, 2, &v);
    T_CHECK(v.density > 0.0f && v.normal[0] > 0.5f);
    /* nothing beyond the cone (radius 3 at the base, 0 at z = 40) */
    tvt_texel_voxel(&t, 26, 30, 2, &v);
    T_CHECK(v.density == 0.0f);
    tvt_texel_voxel(&t, 20, 30, 41, &v);
    T_CHECK(v.density == 0.0f);
    /* fresh colour is green: G > R > B */
    tvt_texel_voxel(&t, 20, 30, 2, &v);
    T_CHECK(v.color[1] > v.color[0] && v.color[0] > v.color[2]);
    /* sparse: one thin blade occupies few of the 16^3 bricks and stores only its covered voxels
       (the cone's 377 voxels of volume touch a few hundred more at its surface); the bytes are
       the index, a mask and an offset per occupied brick, 11 channels x 2 bytes and a blade
       index per stored voxel, and the blade */
    T_CHECK(t.brick_count > 0 && t.brick_count < 60);
    T_CHECK(t.voxel_count >= 377 && t.voxel_count < 2 * 377);
    T_EQ_SIZE(tvt_texel_bytes(&t), 16 * 16 * 16 * 4 + t.brick_count * 12 + t.voxel_count * (22 + 2) + sizeof(tvt_blade));
    /* 8 bits: same bricks, half the channel bytes, total density within the sqrt-coded
       quantisation (step 2 sqrt(d) / 255 at most per voxel, far less on average): 1% */
    d.bits = 8;
    T_CHECK(tvt_build_texel(&b, 1, &d, &t8) == TVT_OK);
    T_EQ_SIZE(t8.brick_count, t.brick_count);
    T_NEAR(tvt_texel_total_density(&t8) / total, 1.0, 0.01);
    /* the same bits on every run */
    T_CHECK(tvt_build_texel(&b, 1, &d, &t2) == TVT_OK);
    T_CHECK(texels_equal(&t8, &t2));
    tvt_texel_free(&t); tvt_texel_free(&t8); tvt_texel_free(&t2);
}

/* A blade across the corner comes back on the other sides; shifting every root by whole voxels
   shifts the texel, bit for bit (the voxeliser works relative to each root's voxel). */
static void test_tiling(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_blade blades[40], shifted[40];
    tvt_texel t, s;
    tvt_voxel v, w;
    long x, y, z, bad = 0, occupied = 0;
    const int dx = 13, dy = 50, res = 64;
    size_t i;
    d.res = res; d.blade_count = 40; d.seed = 99;
    T_CHECK(tvt_grass_blades(&d, blades, 40) == TVT_OK);
    blades[0] = one_blade(63.5f, 63.5f, 30.0f, 2.0f, 0.0f, 0.0f);
    for (i = 0; i < 40; i++) {
        shifted[i] = blades[i];
        shifted[i].root[0] = fmodf(blades[i].root[0] + dx, (float)res);
        shifted[i].root[1] = fmodf(blades[i].root[1] + dy, (float)res);
    }
    T_CHECK(tvt_build_texel(blades, 40, &d, &t) == TVT_OK);
    T_CHECK(tvt_build_texel(shifted, 40, &d, &s) == TVT_OK);
    tvt_texel_voxel(&t, 0, 0, 1, &v);
    T_CHECK(v.density > 0.1f); /* blade 0's root is at the corner: all four corners are covered */
    tvt_texel_voxel(&t, 63, 0, 1, &v);
    T_CHECK(v.density > 0.1f);
    for (z = 0; z < res; z++)
        for (y = 0; y < res; y++)
            for (x = 0; x < res; x++) {
                tvt_texel_voxel(&t, x, y, z, &v);
                tvt_texel_voxel(&s, x + dx, y + dy, z, &w);
                if (memcmp(&v, &w, sizeof(v))) bad++;
                if (v.density > 0) occupied++;
            }
    T_EQ_INT(bad, 0);
    T_CHECK(occupied > 1000);
    tvt_texel_free(&t); tvt_texel_free(&s);
}

/* ---- 2. points and splatting ----------------------------------------------------------------- */
static void test_round_trip(int sanitize)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t, back;
    tvt_points p;
    double before, after, expected;
    size_t i;
    int bits;
    d.res = sanitize ? 64 : 128;
    d.seed = 5;
    for (bits = 8; bits <= 16; bits += 8) {
        d.bits = bits;
        T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
        before = tvt_texel_total_density(&t);
        T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
        /* the point count is the sum of independent roundings of 6 rho per voxel: mean 6 sum rho,
           variance at most 1/4 per stored voxel; 5 standard deviations */
        expected = 6.0 * before;
        T_NEAR((double)p.count, expected, 5.0 * sqrt(0.25 * (double)t.voxel_count));
        /* every point inherits its voxel: inside the texel, with unit mass */
        for (i = 0; i < p.count; i++)
            if (p.p[i].pos[2] < 0 || p.p[i].pos[2] >= (float)d.res || p.p[i].mass != 1.0f) break;
        T_EQ_SIZE(i, p.count);
        T_CHECK(tvt_splat(&p, NULL, &back) == TVT_OK);
        after = tvt_texel_total_density(&back);
        /* the bound: total density within 2% (splatting keeps each point's mass; what is
           left is the rounding of the point counts and the channel quantisation) */
        T_NEAR(after / before, 1.0, 0.02);
        tvt_points_free(&p);
        tvt_texel_free(&back);
        tvt_texel_free(&t);
    }
}

/* The rest state reproduces the sample: at wd = 0 nothing shrinks or bends, so tvt_age puts
   every point back where tvt_sample put it, for blade points (root + ell axis + radial) and for
   the paper's tangent-line rest state of a texel without blade indices (a splatted one). The
   rest directions are stored as int16 (v * 32767 rounded): decoded, the axis and bend are unit
   within sqrt(3) / 2 / 32767 < 3e-5 and perpendicular within 1e-4. The positions agree within
   2e-4 voxel: float rounding of coordinates below 64 (ulp 8e-6) over a few operations; had the
   rest state been taken along the unrounded axis, points 60 voxels up would be off by up to
   60 * 2.6e-5 = 1.6e-3. */
static void test_rest_state(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_model_options o = tvt_model_default_options();
    tvt_texel t, back;
    tvt_points p, q;
    double worst_pos = 0, worst_unit = 0, worst_perp = 0, worst_tangent_rest = 0;
    size_t i;
    int pass;
    d.res = 64; d.seed = 9;
    o.no_merge = 1;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    T_CHECK(tvt_splat(&p, NULL, &back) == TVT_OK); /* no blade indices: the tangent-line rest state */
    for (pass = 0; pass < 2; pass++) {
        const tvt_texel *src = pass ? &back : &t;
        T_CHECK(tvt_sample(src, NULL, &q) == TVT_OK);
        {
            float *start = (float *)malloc(q.count * 3 * sizeof(float));
            for (i = 0; i < q.count; i++) memcpy(start + 3 * i, q.p[i].pos, 3 * sizeof(float));
            T_CHECK(tvt_age(&q, 0.0f, &o) == TVT_OK);
            for (i = 0; i < q.count; i++) {
                float axis[3], bend[3], dp[3];
                double e, u, perp;
                int c;
                tvt_point_rest_dirs(q.p + i, axis, bend, NULL);
                for (c = 0; c < 3; c++) dp[c] = q.p[i].pos[c] - start[3 * i + c];
                for (c = 0; c < 2; c++) dp[c] -= (float)d.res * floorf(dp[c] / (float)d.res + 0.5f);
                e = sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]);
                u = fabs(sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]) - 1.0);
                if (fabs(sqrt(bend[0] * bend[0] + bend[1] * bend[1] + bend[2] * bend[2]) - 1.0) > u)
                    u = fabs(sqrt(bend[0] * bend[0] + bend[1] * bend[1] + bend[2] * bend[2]) - 1.0);
                perp = fabs(axis[0] * bend[0] + axis[1] * bend[1] + axis[2] * bend[2]);
                if (pass == 0 && e > worst_pos) worst_pos = e;
                if (pass == 1 && e > worst_tangent_rest) worst_tangent_rest = e;
                if (u > worst_unit) worst_unit = u;
                if (perp > worst_perp) worst_perp = perp;
            }
            free(start);
        }
        tvt_points_free(&q);
    }
    T_NEAR(worst_pos, 0.0, 2e-4);
    T_NEAR(worst_tangent_rest, 0.0, 2e-4);
    T_NEAR(worst_unit, 0.0, 3e-5);
    T_NEAR(worst_perp, 0.0, 1e-4);
    T_CHECK(sizeof(tvt_point) == 112); /* the documented size (the doc block's MEMORY) */
    tvt_points_free(&p);
    tvt_texel_free(&back);
    tvt_texel_free(&t);
}

/* A smooth field (a slab of density 0.5, tangent (0.6, 0, 0.8)) comes back as itself: the mean
   density of each interior layer within 5% (one layer averages 32^2 voxels of per-voxel noise
   about 30%: the layer mean's noise is under 1%), the tangent to the 8-bit step. */
static void test_smooth_field(void)
{
    const int res = 32;
    tvt_voxel *vox = (tvt_voxel *)calloc((size_t)res * res * res, sizeof(tvt_voxel));
    tvt_texel t, back;
    tvt_points p;
    tvt_voxel v;
    int x, y, z, bad_layers = 0;
    double worst_tangent = 0;
    for (z = 8; z < 24; z++)
        for (y = 0; y < res; y++)
            for (x = 0; x < res; x++) {
                tvt_voxel *o = vox + ((size_t)z * res + y) * res + x;
                o->density = 0.5f;
                o->tangent[0] = 0.6f; o->tangent[2] = 0.8f;
                o->color[1] = 0.5f;
                o->specular = 0.3f;
            }
    T_CHECK(tvt_texel_from_voxels(res, vox, 16, NULL, &t) == TVT_OK);
    T_NEAR(tvt_texel_total_density(&t), 0.5 * 16 * res * res, 1e-3);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    T_CHECK(tvt_splat(&p, NULL, &back) == TVT_OK);
    for (z = 10; z < 22; z++) {
        double sum = 0;
        for (y = 0; y < res; y++)
            for (x = 0; x < res; x++) {
                tvt_texel_voxel(&back, x, y, z, &v);
                sum += v.density;
                if (fabs(v.tangent[0] - 0.6) > worst_tangent) worst_tangent = fabs(v.tangent[0] - 0.6);
                if (fabs(v.tangent[2] - 0.8) > worst_tangent) worst_tangent = fabs(v.tangent[2] - 0.8);
            }
        if (fabs(sum / (res * res) - 0.5) > 0.025) bad_layers++;
    }
    T_EQ_INT(bad_layers, 0);
    T_CHECK(worst_tangent <= 2.0 / 255 + 1e-6);
    /* outside the slab, beyond the kernel's reach (2 voxels), nothing */
    tvt_texel_voxel(&back, 5, 5, 4, &v);
    T_CHECK(v.density == 0.0f);
    tvt_points_free(&p);
    tvt_texel_free(&t); tvt_texel_free(&back);
    free(vox);
}

/* ---- 3. the model ---------------------------------------------------------------------------- */
static void test_model_curves(void)
{
    tvt_model_options ample = tvt_model_default_options(), cold = ample;
    tvt_model_state s, prev, a, c;
    double hue0 = 0, hue_prev = 1e9;
    int k, water_down = 1, strain_up = 1, vein_less = 1, ample_wetter = 1, hue_down = 1;
    float mid_rate = 0, late_rate = 0;
    ample.water_curve = TVT_WATER_AMPLE;
    cold.water_curve = TVT_WATER_COLD;
    T_CHECK(tvt_model_eval(NULL, 0.0f, &prev) == TVT_OK);
    T_NEAR(prev.water, 1.0, 1e-6);
    T_NEAR(prev.chlorophyll, 1.0, 1e-6);
    T_NEAR(prev.droop, 0.0, 1e-6);
    hue0 = hue_deg(prev.color);
    for (k = 1; k <= 40; k++) {
        float wd = (float)k / 40.0f;
        double h;
        T_CHECK(tvt_model_eval(NULL, wd, &s) == TVT_OK);
        tvt_model_eval(&ample, wd, &a);
        tvt_model_eval(&cold, wd, &c);
        if (!(s.water <= prev.water && s.chlorophyll <= prev.chlorophyll && s.droop >= prev.droop)) water_down = 0;
        if (!(s.strain_vein >= prev.strain_vein && s.strain_mesophyll >= prev.strain_mesophyll &&
              s.axial_shrink >= prev.axial_shrink))
            strain_up = 0;
        if (!(s.strain_vein < s.strain_mesophyll)) vein_less = 0;
        if (!(a.water >= s.water)) ample_wetter = 0;
        if (k == 20) mid_rate = s.strain_mesophyll - prev.strain_mesophyll;
        if (k == 40) late_rate = s.strain_mesophyll - prev.strain_mesophyll;
        h = hue_deg(s.color);
        if (h > hue_prev + 1e-6) hue_down = 0;
        hue_prev = h;
        prev = s;
    }
    T_CHECK(water_down);   /* water and chlorophyll fall, droop grows, all monotone */
    T_CHECK(strain_up);    /* shrinkage only grows */
    T_CHECK(vein_less);    /* veins shrink less than mesophyll (k_v < k_m) */
    T_CHECK(ample_wetter); /* the ample-water curve keeps more water at every wd */
    T_CHECK(late_rate < 0.2f * mid_rate); /* stiffening: shrinkage settles at the end */
    T_CHECK(hue_down);     /* hue moves one way only, from green toward yellow-brown */
    T_CHECK(hue0 > 80 && hue0 < 140);      /* green */
    T_CHECK(hue_prev > 20 && hue_prev < 60); /* yellow-brown at wd = 1 */
    T_NEAR(prev.droop * 180 / 3.14159265, 80.0, 1e-3);
    T_CHECK(tvt_wd_from_time(5.0f, 10.0f) == 0.5f && tvt_wd_from_time(20.0f, 10.0f) == 1.0f &&
            tvt_wd_from_time(-1.0f, 10.0f) == 0.0f && tvt_wd_from_time(1.0f, 0.0f) == 0.0f);
}

/* Droop over time on the default 100-blade patch: every step lowers the mean height of the tips
   (the top tenth of each blade) and moves tips more than roots; merging keeps the mass. */
static void test_droop(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t;
    tvt_points p;
    float *start;
    double prev_tip = 1e9, tip0 = 0, mass = 0;
    int k, monotone = 1, tips_more = 1;
    size_t i, n0;
    d.res = 64; d.seed = 3;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    n0 = p.count;
    start = (float *)malloc(n0 * 3 * sizeof(float));
    for (i = 0; i < n0; i++) memcpy(start + 3 * i, p.p[i].pos, 3 * sizeof(float));
    for (k = 0; k <= 10; k++) {
        tvt_model_options o = tvt_model_default_options();
        double tip = 0, tip_move = 0, root_move = 0;
        size_t ntip = 0, nroot = 0;
        o.no_merge = 1; /* keep the indices so that each point's motion can be measured */
        T_CHECK(tvt_age(&p, (float)k / 10.0f, &o) == TVT_OK);
        for (i = 0; i < p.count; i++) {
            const tvt_point *q = p.p + i;
            float dxyz[3];
            double move;
            int c;
            for (c = 0; c < 3; c++) dxyz[c] = q->pos[c] - start[3 * i + c];
            for (c = 0; c < 2; c++) dxyz[c] -= (float)d.res * floorf(dxyz[c] / (float)d.res + 0.5f);
            move = sqrt(dxyz[0] * dxyz[0] + dxyz[1] * dxyz[1] + dxyz[2] * dxyz[2]);
            if (q->ell > 0.5f * d.res) { tip += q->pos[2]; tip_move += move; ntip++; }
            if (q->ell < 0.1f * d.res) { root_move += move; nroot++; }
        }
        tip /= (double)ntip;
        if (tip > prev_tip + 1e-4) monotone = 0;
        if (k > 0 && !(tip_move / (double)ntip > 4.0 * root_move / (double)nroot)) tips_more = 0;
        if (k == 0) tip0 = tip;
        prev_tip = tip;
    }
    T_CHECK(monotone);
    T_CHECK(tips_more);
    /* at wd = 1 the upper blade parts hang down: a point at arc length ell had height ell cos(a)
       (lean a) and now has at most cos(a) * integral_0^ell cos(phi(s)) ds, phi(s) = 80 deg
       (s / 0.6 res)^2; for ell = 0.5 res that is 0.910 of its height, and less higher up, so the
       tips' mean height falls to 0.91 of its start at most (shrinkage only lowers it more) */
    T_CHECK_MSG(prev_tip < 0.91 * tip0, "tip height %.2f at wd 1, %.2f at wd 0", prev_tip, tip0);
    /* merging (default options) conserves the mass: the masses are whole numbers, added exactly */
    T_CHECK(tvt_age(&p, 1.0f, NULL) == TVT_OK);
    for (i = 0; i < p.count; i++) mass += p.p[i].mass;
    T_CHECK(p.count < n0);
    T_NEAR(mass, (double)n0, 0.0);
    free(start);
    tvt_points_free(&p);
    tvt_texel_free(&t);
}

/* 26-connectivity of the voxels with density above 1% of the maximum: the share of density
   in the component that holds voxel (x0, y0, z0) */
static double connected_share(const tvt_texel *t, int x0, int y0, int z0)
{
    int res = t->res;
    size_t n = (size_t)res * res * res, head = 0, tail = 0;
    int *queue = (int *)malloc(n * sizeof(int));
    unsigned char *seen = (unsigned char *)calloc(n, 1);
    double in = 0, all = tvt_texel_total_density(t), thr = 0.01 * t->density_max;
    tvt_voxel v;
    tvt_texel_voxel(t, x0, y0, z0, &v);
    if (v.density > thr) { queue[tail++] = (z0 * res + y0) * res + x0; seen[queue[0]] = 1; }
    while (head < tail) {
        int id = queue[head++], x = id % res, y = id / res % res, z = id / (res * res), i, j, k;
        tvt_texel_voxel(t, x, y, z, &v);
        in += v.density;
        for (k = -1; k <= 1; k++)
            for (j = -1; j <= 1; j++)
                for (i = -1; i <= 1; i++) {
                    int xx = (x + i + res) % res, yy = (y + j + res) % res, zz = z + k, nid;
                    if (zz < 0 || zz >= res) continue;
                    nid = (zz * res + yy) * res + xx;
                    if (seen[nid]) continue;
                    tvt_texel_voxel(t, xx, yy, zz, &v);
                    if (v.density <= thr) continue;
                    seen[nid] = 1;
                    queue[tail++] = nid;
                }
    }
    free(queue); free(seen);
    return in / all;
}

/* One blade, aged to wd = 0.3, 0.6 and 1: its voxels stay one piece from root to tip (the
   component of the root voxel holds all but the sub-threshold fringe, 1% of voxels at most
   0.01 dmax each) and its top comes down. */
static void test_connectivity(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_blade b = one_blade(32.0f, 32.0f, 56.0f, 1.5f, 8.0f, 30.0f);
    tvt_texel t, f;
    tvt_points p;
    float wds[3] = {0.3f, 0.6f, 1.0f};
    int k, top0 = 0, top = 0, z;
    d.res = 64;
    T_CHECK(tvt_build_texel(&b, 1, &d, &t) == TVT_OK);
    T_CHECK(connected_share(&t, 32, 32, 0) > 0.99);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    for (z = 0; z < 64; z++) { tvt_voxel v; int x, y; for (y = 0; y < 64; y++) for (x = 0; x < 64; x++) { tvt_texel_voxel(&t, x, y, z, &v); if (v.density > 0.01f * t.density_max) top0 = z; } }
    for (k = 0; k < 3; k++) {
        T_CHECK(tvt_age(&p, wds[k], NULL) == TVT_OK);
        T_CHECK(tvt_splat(&p, NULL, &f) == TVT_OK);
        T_CHECK_MSG(connected_share(&f, 32, 32, 0) > 0.98, "wd %.2f share %.4f", wds[k], connected_share(&f, 32, 32, 0));
        if (k == 2) {
            for (z = 0; z < 64; z++) { tvt_voxel v; int x, y; for (y = 0; y < 64; y++) for (x = 0; x < 64; x++) { tvt_texel_voxel(&f, x, y, z, &v); if (v.density > 0.01f * f.density_max) top = z; } }
        }
        tvt_texel_free(&f);
    }
    T_CHECK(top < top0 - 10);
    tvt_points_free(&p);
    tvt_texel_free(&t);
}

/* The splatted colour of the whole patch goes from green to yellow-brown. */
static void test_texel_hue(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t, f;
    tvt_points p;
    float wds[4] = {0.0f, 0.3f, 0.6f, 0.917f};
    double prev = 1e9;
    int k, down = 1;
    d.res = 32;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    for (k = 0; k < 4; k++) {
        float mean[3] = {0, 0, 0};
        double w = 0, h;
        int c;
        T_CHECK(tvt_age(&p, wds[k], NULL) == TVT_OK);
        T_CHECK(tvt_splat(&p, NULL, &f) == TVT_OK);
        {
            long x, y, z;
            for (z = 0; z < 32; z++) for (y = 0; y < 32; y++) for (x = 0; x < 32; x++) {
                tvt_voxel v;
                tvt_texel_voxel(&f, x, y, z, &v);
                for (c = 0; c < 3; c++) mean[c] += v.density * v.color[c];
                w += v.density;
            }
        }
        for (c = 0; c < 3; c++) mean[c] = (float)(mean[c] / w);
        h = hue_deg(mean);
        if (h >= prev) down = 0;
        prev = h;
        tvt_texel_free(&f);
    }
    T_CHECK(down);
    T_CHECK(prev < 60);
    tvt_points_free(&p);
    tvt_texel_free(&t);
}

/* ---- determinism ----------------------------------------------------------------------------- */
static void test_same_bits(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t[2], f[2];
    tvt_points p[2];
    int k;
    d.res = 32; d.seed = 11;
    for (k = 0; k < 2; k++) {
        T_CHECK(tvt_build_grass(&d, &t[k]) == TVT_OK);
        T_CHECK(tvt_sample(&t[k], NULL, &p[k]) == TVT_OK);
        T_CHECK(tvt_age(&p[k], 0.5f, NULL) == TVT_OK);
        T_CHECK(tvt_age(&p[k], 0.917f, NULL) == TVT_OK);
        T_CHECK(tvt_splat(&p[k], NULL, &f[k]) == TVT_OK);
    }
    T_CHECK(texels_equal(&t[0], &t[1]));
    T_CHECK(p[0].count == p[1].count && memcmp(p[0].p, p[1].p, p[0].count * sizeof(tvt_point)) == 0);
    T_CHECK(texels_equal(&f[0], &f[1]));
    for (k = 0; k < 2; k++) { tvt_texel_free(&t[k]); tvt_texel_free(&f[k]); tvt_points_free(&p[k]); }
}

/* ---- bad input ------------------------------------------------------------------------------- */
static void test_bad_input(void)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_blade b = one_blade(3.0f, 3.0f, 20.0f, 1.5f, 5.0f, 0.0f);
    tvt_texel t;
    tvt_points p;
    tvt_voxel vox[512];
    tvt_model_options mo = tvt_model_default_options();
    float nan = (float)strtod("nan", NULL);
    memset(vox, 0, sizeof(vox));
    d.res = 48;
    T_EQ_INT(tvt_build_grass(&d, &t), TVT_ERR_BAD_RESOLUTION);
    T_CHECK(t.brick_index == NULL && t.data == NULL);
    d.res = 2048;
    T_EQ_INT(tvt_build_grass(&d, &t), TVT_ERR_BAD_RESOLUTION);
    d.res = 32; d.bits = 12;
    T_EQ_INT(tvt_build_grass(&d, &t), TVT_ERR_BAD_RESOLUTION);
    d.bits = 8; d.height_max = nan;
    T_EQ_INT(tvt_build_grass(&d, &t), TVT_ERR_BAD_PARAMETER);
    d.height_max = 0.9f; d.radius_min = -1.0f;
    T_EQ_INT(tvt_build_grass(&d, &t), TVT_ERR_BAD_PARAMETER);
    d.radius_min = 1.5f; d.blade_count = 70000;
    T_EQ_INT(tvt_build_grass(&d, &t), TVT_ERR_TOO_LARGE);
    d.blade_count = 0; /* 0 = the default count; an empty texel comes from tvt_build_texel */
    T_EQ_INT(tvt_texel_from_voxels(0, vox, 8, NULL, &t), TVT_ERR_BAD_RESOLUTION);
    T_EQ_INT(tvt_texel_from_voxels(12, vox, 8, NULL, &t), TVT_ERR_BAD_RESOLUTION);
    vox[7].density = nan;
    T_EQ_INT(tvt_texel_from_voxels(8, vox, 8, NULL, &t), TVT_ERR_BAD_PARAMETER);
    vox[7].density = 0.0f;
    b.axis[0] = nan;
    T_EQ_INT(tvt_build_texel(&b, 1, &d, &t), TVT_ERR_BAD_PARAMETER);
    b = one_blade(3.0f, 3.0f, 20.0f, 1.5f, 5.0f, 0.0f);
    /* zero blades: an empty texel of no bricks (4 bytes per brick of index); sampling it is
       TVT_ERR_EMPTY, and so is an all-zero voxel array */
    T_CHECK(tvt_build_texel(NULL, 0, &d, &t) == TVT_OK);
    T_EQ_SIZE(t.brick_count, 0);
    T_EQ_SIZE(tvt_texel_bytes(&t), 8 * 8 * 8 * 4);
    T_EQ_INT(tvt_sample(&t, NULL, &p), TVT_ERR_EMPTY);
    T_CHECK(p.p == NULL && p.count == 0);
    tvt_texel_free(&t);
    T_CHECK(tvt_texel_from_voxels(8, vox, 8, NULL, &t) == TVT_OK);
    T_EQ_INT(tvt_sample(&t, NULL, &p), TVT_ERR_EMPTY);
    tvt_texel_free(&t);
    /* wd outside [0, 1] or NaN: TVT_ERR_BAD_WD, the points untouched */
    T_CHECK(tvt_build_texel(&b, 1, &d, &t) == TVT_OK);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    {
        tvt_point first = p.p[0];
        T_EQ_INT(tvt_age(&p, nan, NULL), TVT_ERR_BAD_WD);
        T_EQ_INT(tvt_age(&p, 1.5f, NULL), TVT_ERR_BAD_WD);
        T_EQ_INT(tvt_age(&p, -0.01f, NULL), TVT_ERR_BAD_WD);
        T_CHECK(memcmp(&first, &p.p[0], sizeof(first)) == 0 && p.wd == 0.0f);
    }
    mo.droop_max_deg = nan;
    T_EQ_INT(tvt_age(&p, 0.5f, &mo), TVT_ERR_BAD_PARAMETER);
    mo = tvt_model_default_options();
    mo.water_curve = 7;
    T_EQ_INT(tvt_age(&p, 0.5f, &mo), TVT_ERR_BAD_PARAMETER);
    {
        tvt_sample_options so = tvt_sample_default_options();
        tvt_points q;
        so.proportion = nan;
        T_EQ_INT(tvt_sample(&t, &so, &q), TVT_ERR_BAD_PARAMETER);
    }
    {
        tvt_splat_options sp = tvt_splat_default_options();
        tvt_texel f;
        sp.sigma = 3.0f;
        T_EQ_INT(tvt_splat(&p, &sp, &f), TVT_ERR_BAD_PARAMETER);
        sp.sigma = 0.5f; sp.bits = 4;
        T_EQ_INT(tvt_splat(&p, &sp, &f), TVT_ERR_BAD_RESOLUTION);
    }
    tvt_points_free(&p);
    T_EQ_INT(tvt_sample(NULL, NULL, &p), TVT_ERR_INVALID_ARGUMENT);
    tvt_texel_free(&t);
    T_EQ_STR(tvt_result_string(TVT_ERR_BAD_WD), "TVT_ERR_BAD_WD");
    T_EQ_STR(tvt_result_string((tvt_result)99), "TVT_ERR_?");
}

/* Every allocation of every call fails in turn: TVT_ERR_OUT_OF_MEMORY, nothing leaked, the
   output zeroed; a cancelling progress callback gives TVT_CANCELLED, nothing leaked. */
static void test_allocation_failure(void)
{
    counting c;
    tvt_allocator a = counting_allocator(&c);
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t, f;
    tvt_points p;
    tvt_sample_options so = tvt_sample_default_options();
    tvt_splat_options sp = tvt_splat_default_options();
    long k, failures_ok = 1, leaks = 0, calls_seen = 0;
    tvt_result r;
    d.res = 16; d.blade_count = 10; d.allocator = &a;
    so.allocator = &a; sp.allocator = &a;
    for (k = 1;; k++) { /* build */
        memset(&c, 0, sizeof(c)); c.fail_at = k;
        r = tvt_build_grass(&d, &t);
        if (r == TVT_OK) { tvt_texel_free(&t); if (c.live) leaks++; break; }
        if (r != TVT_ERR_OUT_OF_MEMORY || t.data || t.brick_index) failures_ok = 0;
        if (c.live) leaks++;
        calls_seen++;
    }
    memset(&c, 0, sizeof(c));
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    for (k = 1;; k++) { /* sample */
        long base;
        c.fail_at = c.calls + k;
        base = c.live;
        r = tvt_sample(&t, &so, &p);
        if (r == TVT_OK) { tvt_points_free(&p); if (c.live != base) leaks++; break; }
        if (r != TVT_ERR_OUT_OF_MEMORY || p.p) failures_ok = 0;
        if (c.live != base) leaks++;
        calls_seen++;
    }
    c.fail_at = 0;
    T_CHECK(tvt_sample(&t, &so, &p) == TVT_OK);
    for (k = 1;; k++) { /* age (merging allocates) */
        long base = c.live;
        c.fail_at = c.calls + k;
        r = tvt_age(&p, 0.5f, NULL);
        if (r == TVT_OK) { if (c.live != base) leaks++; break; }
        if (r != TVT_ERR_OUT_OF_MEMORY) failures_ok = 0;
        if (c.live != base) leaks++;
        calls_seen++;
    }
    for (k = 1;; k++) { /* splat */
        long base = c.live;
        c.fail_at = c.calls + k;
        r = tvt_splat(&p, &sp, &f);
        if (r == TVT_OK) { tvt_texel_free(&f); if (c.live != base) leaks++; break; }
        if (r != TVT_ERR_OUT_OF_MEMORY || f.data) failures_ok = 0;
        if (c.live != base) leaks++;
        calls_seen++;
    }
    T_CHECK(failures_ok);
    T_EQ_INT(leaks, 0);
    T_CHECK(calls_seen >= 8); /* every call above allocates more than once: the loops did fail */
    c.fail_at = 0;
    d.progress = cancel_now;
    T_EQ_INT(tvt_build_grass(&d, &f), TVT_CANCELLED);
    so.progress = cancel_now;
    {
        tvt_points q;
        T_EQ_INT(tvt_sample(&t, &so, &q), TVT_CANCELLED);
    }
    sp.progress = cancel_now;
    T_EQ_INT(tvt_splat(&p, &sp, &f), TVT_CANCELLED);
    tvt_points_free(&p);
    tvt_texel_free(&t);
    T_EQ_INT(c.live, 0);
}

int main(int argc, char **argv)
{
    int sanitize = getenv("TEST_SANITIZE") != NULL;
    T_BEGIN(argc, argv);
    if (sanitize) printf("note: TEST_SANITIZE is set: the round trip runs at 64^3 instead of 128^3\n");
    test_static_texel();
    test_tiling();
    test_round_trip(sanitize);
    test_rest_state();
    test_smooth_field();
    test_model_curves();
    test_droop();
    test_connectivity();
    test_texel_hue();
    test_same_bits();
    test_bad_input();
    test_allocation_failure();
    return T_END();
}
