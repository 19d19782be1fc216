/* test_texel_tvt.c - texel.h: the LOD pyramid's opacity, key frames, mingling, bad input.
   TEST_SANITIZE=1 (make sanitize) runs the LOD opacity check at 64^3 with 2,000 rays per
   elevation instead of 128^3 with 10,000. */
#define TVT_IMPLEMENTATION
#include "texel.h"
#include "test.h"
#include <stdlib.h>

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

/* the test's own rays (not the library's calibration rays): from a uniform point of the top
   face, uniform azimuth, down to the ground */
static unsigned long long rng_state = 88172645463325252ull;
static double uniform(void)
{
    rng_state ^= rng_state << 13; rng_state ^= rng_state >> 7; rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* Along n rays at each of the elevations 15, 45 and 90 degrees, every level's mean opacity
   1 - exp(-tau) is within 5% of level 0's (the bound); the raw box-filtered density
   keeps the mass sum(rho) * 8^level to the 8-bit quantisation (2%). */
static void test_lod_opacity(int res, int n, float wd)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t, f;
    tvt_points p;
    tvt_lod l;
    const double elev[3] = {15, 45, 90};
    int e, i, lv, worst_ok = 1;
    double mass0;
    d.res = res; d.seed = 21;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    T_CHECK(tvt_sample(&t, NULL, &p) == TVT_OK);
    T_CHECK(tvt_age(&p, wd, NULL) == TVT_OK);
    T_CHECK(tvt_splat(&p, NULL, &f) == TVT_OK);
    T_CHECK(tvt_build_lod(&f, NULL, &l) == TVT_OK);
    T_EQ_INT(l.levels, res == 128 ? 3 : 2); /* down to 32^3 */
    mass0 = tvt_texel_total_density(&l.level[0]);
    for (lv = 1; lv < l.levels; lv++)
        T_NEAR(tvt_texel_total_density(&l.level[lv]) * (double)(1 << (3 * lv)) / mass0, 1.0, 0.02);
    for (e = 0; e < 3; e++) {
        double mean[TVT_MAX_LEVELS] = {0}, ce = cos(elev[e] * 3.14159265358979 / 180), se = sin(elev[e] * 3.14159265358979 / 180);
        for (i = 0; i < n; i++) {
            float o[3], dir[3], az = (float)(2 * 3.14159265358979 * uniform());
            o[0] = (float)(res * uniform()); o[1] = (float)(res * uniform()); o[2] = (float)res;
            dir[0] = (float)(ce * cos(az)); dir[1] = (float)(ce * sin(az)); dir[2] = (float)-se;
            for (lv = 0; lv < l.levels; lv++) mean[lv] += 1.0 - exp(-tvt_optical_depth(&l, lv, o, dir, (float)(res / se)));
        }
        for (lv = 1; lv < l.levels; lv++)
            if (!T_CHECK_MSG(fabs(mean[lv] / mean[0] - 1.0) <= 0.05, "wd %.3f elevation %.0f level %d: %.4f vs %.4f",
                             wd, elev[e], lv, mean[lv] / n, mean[0] / n))
                worst_ok = 0;
        T_CHECK(mean[0] / n > 0.05 && mean[0] / n < 0.999); /* a real test: neither empty nor saturated */
    }
    (void)worst_ok;
    tvt_lod_free(&l);
    tvt_texel_free(&f);
    tvt_points_free(&p);
    tvt_texel_free(&t);
}

static void small_tvt(uint64_t seed, int frames, tvt_tvt *out)
{
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_texel t;
    tvt_tvt_options o = tvt_tvt_default_options();
    tvt_splat_options sp = tvt_splat_default_options();
    tvt_lod_options lo = tvt_lod_default_options();
    d.res = 32; d.blade_count = 30; d.seed = seed;
    sp.bits = 16;
    lo.levels = 1;
    o.frames = frames; o.splat = &sp; o.lod = &lo;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    T_CHECK(tvt_build_tvt(&t, &o, out) == TVT_OK);
    tvt_texel_free(&t);
}

/* Key frames: frame k holds wd = k / (F - 1); between frames the density is the linear blend. */
static void test_key_frames(void)
{
    tvt_tvt s;
    tvt_voxel a, b, m;
    float p[3] = {0, 0, 2.5f};
    long x, y, found = 0;
    small_tvt(1, 3, &s);
    T_EQ_INT(s.frame_count, 3);
    T_CHECK(s.wd[0] == 0.0f && s.wd[1] == 0.5f && s.wd[2] == 1.0f);
    for (y = 0; y < 32 && !found; y++)
        for (x = 0; x < 32 && !found; x++) {
            p[0] = (float)x + 0.5f; p[1] = (float)y + 0.5f;
            tvt_lod_voxel(&s.frames[0], 0, p, &a);
            tvt_lod_voxel(&s.frames[1], 0, p, &b);
            if (a.density > 0.1f && b.density > 0.1f) found = 1;
        }
    T_CHECK(found);
    tvt_tvt_voxel(&s, 0.25f, 0, p, &m);
    T_NEAR(m.density, 0.5 * (a.density + b.density), 1e-5);
    /* colour: the density-weighted blend */
    T_NEAR(m.color[1], (a.density * a.color[1] + b.density * b.color[1]) / (a.density + b.density), 1e-5);
    tvt_tvt_voxel(&s, 0.5f, 0, p, &m);
    T_NEAR(m.density, b.density, 1e-6);
    tvt_tvt_free(&s);
}

/* Mingling sums density: two different samples give, voxel by voxel, the sum of their
   densities (to the 16-bit quantisation of the three texels: 3 steps of the largest scale);
   K copies of one sample give K times its density and the same colour. */
static void test_mingling(void)
{
    tvt_tvt s[3];
    tvt_texel m, m3;
    tvt_ageing_fn fn[2];
    long x, y, z, bad = 0, bad_copy = 0, checked = 0;
    double total_a, total_b;
    small_tvt(1, 3, &s[0]);
    small_tvt(2, 3, &s[1]);
    T_CHECK(tvt_mingle(s, NULL, 2, 0.5f, 16, NULL, &m) == TVT_OK);
    total_a = tvt_texel_total_density(&s[0].frames[1].level[0]);
    total_b = tvt_texel_total_density(&s[1].frames[1].level[0]);
    T_NEAR(tvt_texel_total_density(&m) / (total_a + total_b), 1.0, 1e-3);
    for (z = 0; z < 32; z++)
        for (y = 0; y < 32; y++)
            for (x = 0; x < 32; x++) {
                tvt_voxel a, b, c;
                double tol = 3.0 * m.density_max / 65535.0;
                tvt_texel_voxel(&s[0].frames[1].level[0], x, y, z, &a);
                tvt_texel_voxel(&s[1].frames[1].level[0], x, y, z, &b);
                tvt_texel_voxel(&m, x, y, z, &c);
                if (fabs(c.density - a.density - b.density) > tol) bad++;
            }
    T_EQ_INT(bad, 0);
    tvt_texel_free(&m);
    /* three copies of sample 0 */
    s[2] = s[0];
    {
        tvt_tvt copies[3];
        copies[0] = s[0]; copies[1] = s[0]; copies[2] = s[0];
        T_CHECK(tvt_mingle(copies, NULL, 3, 0.5f, 16, NULL, &m3) == TVT_OK);
    }
    for (z = 0; z < 32; z++)
        for (y = 0; y < 32; y++)
            for (x = 0; x < 32; x++) {
                tvt_voxel a, c;
                tvt_texel_voxel(&s[0].frames[1].level[0], x, y, z, &a);
                tvt_texel_voxel(&m3, x, y, z, &c);
                if (fabs(c.density - 3 * a.density) > 3.0 * m3.density_max / 65535.0) bad_copy++;
                if (a.density > 0.01f * s[0].frames[1].level[0].density_max) {
                    checked++;
                    if (fabs(c.color[1] - a.color[1]) > 2.0 / 65535 + 1e-6) bad_copy++;
                }
            }
    T_EQ_INT(bad_copy, 0);
    T_CHECK(checked > 100);
    tvt_texel_free(&m3);
    /* ageing functions: a delay of 1 keeps sample 1 fresh at any wd; rate 2 ages sample 0 twice
       as fast, so at wd = 0.25 it is seen at 0.5 (its frame 1) */
    fn[0].delay = 0; fn[0].rate = 2;
    fn[1].delay = 1; fn[1].rate = 1;
    T_CHECK(tvt_ageing_apply(&fn[0], 0.25f) == 0.5f && tvt_ageing_apply(&fn[1], 0.9f) == 0.0f);
    T_CHECK(tvt_mingle(s, fn, 2, 0.25f, 16, NULL, &m) == TVT_OK);
    T_NEAR(tvt_texel_total_density(&m) /
               (total_a + tvt_texel_total_density(&s[1].frames[0].level[0])), 1.0, 1e-3);
    tvt_texel_free(&m);
    /* a mingled TVT: its frames are the mingled texels; same bits on every run */
    {
        tvt_tvt_options o = tvt_tvt_default_options();
        tvt_lod_options lo = tvt_lod_default_options();
        tvt_tvt mt, mt2;
        lo.levels = 2;
        o.frames = 3; o.lod = &lo;
        T_CHECK(tvt_mingle_tvt(s, fn, 2, &o, &mt) == TVT_OK);
        T_CHECK(tvt_mingle_tvt(s, fn, 2, &o, &mt2) == TVT_OK);
        T_EQ_INT(mt.frame_count, 3);
        T_EQ_INT(mt.frames[0].levels, 2);
        T_CHECK(mt.frames[2].level[1].voxel_count == mt2.frames[2].level[1].voxel_count &&
                memcmp(mt.frames[2].level[1].data, mt2.frames[2].level[1].data,
                       mt.frames[2].level[1].voxel_count * 11) == 0 &&
                mt.frames[2].density_scale[1] == mt2.frames[2].density_scale[1]);
        tvt_tvt_free(&mt);
        tvt_tvt_free(&mt2);
    }
    tvt_tvt_free(&s[0]);
    tvt_tvt_free(&s[1]);
}

static void test_bad_input(void)
{
    tvt_tvt s[2], bad;
    tvt_texel m, t;
    tvt_lod l;
    tvt_tvt_options o = tvt_tvt_default_options();
    tvt_lod_options lo = tvt_lod_default_options();
    tvt_ageing_fn fn[2];
    tvt_grass_desc d = tvt_grass_default_desc();
    float nan = (float)strtod("nan", NULL);
    small_tvt(1, 2, &s[0]);
    T_EQ_INT(tvt_mingle(s, NULL, 0, 0.5f, 8, NULL, &m), TVT_ERR_EMPTY);
    T_EQ_INT(tvt_mingle(s, NULL, 1, nan, 8, NULL, &m), TVT_ERR_BAD_WD);
    T_EQ_INT(tvt_mingle(s, NULL, 1, 1.5f, 8, NULL, &m), TVT_ERR_BAD_WD);
    fn[0].delay = nan; fn[0].rate = 1;
    T_EQ_INT(tvt_mingle(s, fn, 1, 0.5f, 8, NULL, &m), TVT_ERR_BAD_PARAMETER);
    T_CHECK(m.data == NULL);
    /* samples of different res */
    d.res = 16; d.blade_count = 5;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    lo.levels = 1;
    o.frames = 2; o.lod = &lo;
    T_CHECK(tvt_build_tvt(&t, &o, &s[1]) == TVT_OK);
    T_EQ_INT(tvt_mingle(s, NULL, 2, 0.5f, 8, NULL, &m), TVT_ERR_BAD_RESOLUTION);
    o.frames = 1;
    T_EQ_INT(tvt_build_tvt(&t, &o, &bad), TVT_ERR_BAD_PARAMETER);
    o.frames = 65;
    T_EQ_INT(tvt_build_tvt(&t, &o, &bad), TVT_ERR_BAD_PARAMETER);
    lo.levels = 3; /* 16 -> 8 -> 4: below 8^3 */
    T_EQ_INT(tvt_build_lod(&t, &lo, &l), TVT_ERR_BAD_RESOLUTION);
    lo.levels = 2; lo.extinction = nan;
    T_EQ_INT(tvt_build_lod(&t, &lo, &l), TVT_ERR_BAD_PARAMETER);
    T_CHECK(l.levels == 0);
    tvt_texel_free(&t);
    tvt_tvt_free(&s[0]);
    tvt_tvt_free(&s[1]);
}

/* Every allocation of build_tvt (sampling, ageing, splatting, pyramids) and of mingling fails
   in turn: TVT_ERR_OUT_OF_MEMORY and nothing leaked. */
static void test_allocation_failure(void)
{
    counting c;
    tvt_allocator a;
    tvt_grass_desc d = tvt_grass_default_desc();
    tvt_tvt_options o = tvt_tvt_default_options();
    tvt_lod_options lo = tvt_lod_default_options();
    tvt_texel t, m;
    tvt_tvt s, out;
    long k, leaks = 0, wrong = 0, failed = 0;
    tvt_result r;
    a.alloc = c_alloc; a.free = c_free; a.user = &c;
    memset(&c, 0, sizeof(c));
    d.res = 16; d.blade_count = 6;
    T_CHECK(tvt_build_grass(&d, &t) == TVT_OK);
    lo.levels = 2; lo.calibration_rays = 16;
    o.frames = 3; o.lod = &lo; o.allocator = &a;
    for (k = 1;; k++) {
        c.fail_at = c.calls + k;
        r = tvt_build_tvt(&t, &o, &out);
        if (r == TVT_OK) break;
        failed++;
        if (r != TVT_ERR_OUT_OF_MEMORY || out.frames) wrong++;
        if (c.live) leaks++;
    }
    s = out;
    for (k = 1;; k++) {
        c.fail_at = c.calls + k;
        r = tvt_mingle(&s, NULL, 1, 0.3f, 8, &a, &m);
        if (r == TVT_OK) { tvt_texel_free(&m); break; }
        failed++;
        if (r != TVT_ERR_OUT_OF_MEMORY || m.data) wrong++;
    }
    for (k = 1;; k++) {
        long base = c.live;
        c.fail_at = c.calls + k;
        r = tvt_mingle_tvt(&s, NULL, 1, &o, &out);
        if (r == TVT_OK) { tvt_tvt_free(&out); if (c.live != base) leaks++; break; }
        failed++;
        if (r != TVT_ERR_OUT_OF_MEMORY) wrong++;
        if (c.live != base) leaks++;
    }
    tvt_tvt_free(&s);
    tvt_texel_free(&t);
    T_EQ_INT(wrong, 0);
    T_EQ_INT(leaks, 0);
    T_EQ_INT(c.live, 0);
    T_CHECK(failed > 20);
}

/* A TVT made of one uniform slab (density 0.1 for 8 <= z < 24, tangent along x): the march's
   transmittance is exp(-kappa rho L) for the path length L inside the slab (level 0: isotropic;
   the half-voxel midpoint steps integrate a constant exactly, the trilinear edges of the slab
   are symmetric, so 1e-3); the shadow volume's transmittance at the voxel centres below the
   slab is exp(-kappa rho 16 / l_z) (the trapezoid rule is exact on the slab's linear edges; the
   light's horizontal shift is interpolated in a constant layer: 1e-3);
   Kajiya-Kay lights the fibres more with the light across them than along them. */
static void test_march(void)
{
    const int res = 32;
    tvt_voxel *vox = (tvt_voxel *)calloc((size_t)res * res * res, sizeof(tvt_voxel));
    tvt_texel slab, empty;
    tvt_tvt t;
    tvt_lod_options lo = tvt_lod_default_options();
    tvt_shadow sh;
    tvt_shade_desc sd = tvt_shade_default_desc();
    float o[3] = {3.3f, 7.1f, 30.0f}, d[3] = {0, 0, -1}, rgb[3], T, across[3], along[3];
    float light[3] = {0.6f, 0.0f, 0.8f}, p[3] = {16.5f, 16.5f, 7.5f};
    int x, y, z;
    for (z = 8; z < 24; z++)
        for (y = 0; y < res; y++)
            for (x = 0; x < res; x++) {
                tvt_voxel *v = vox + ((size_t)z * res + y) * res + x;
                v->density = 0.1f; v->tangent[0] = 1.0f; v->color[1] = 0.6f; v->specular = 0.3f;
            }
    T_CHECK(tvt_texel_from_voxels(res, vox, 16, NULL, &slab) == TVT_OK);
    lo.levels = 1;
    memset(&t, 0, sizeof(t));
    t.frame_count = 2; t.wd[0] = 0; t.wd[1] = 1;
    t.frames = (tvt_lod *)calloc(2, sizeof(tvt_lod));
    T_CHECK(tvt_build_lod(&slab, &lo, &t.frames[0]) == TVT_OK);
    T_CHECK(tvt_build_lod(&slab, &lo, &t.frames[1]) == TVT_OK);
    tvt_march(&t, 0.5f, 0, &sd, o, d, 30.0f, rgb, &T);
    T_NEAR(T, exp(-0.1 * 16), 1e-3 * exp(-0.1 * 16));
    T_CHECK(rgb[1] > rgb[0] && rgb[1] > rgb[2]); /* green fibres */
    d[0] = 0.6f; d[2] = -0.8f; /* slanted: 16 / 0.8 = 20 voxels inside */
    tvt_march(&t, 0.5f, 0, &sd, o, d, 37.5f, rgb, &T);
    T_NEAR(T, exp(-0.1 * 20), 1e-3 * exp(-0.1 * 20));
    T_CHECK(tvt_build_shadow(&t, 0, light, NULL, &sh) == TVT_OK);
    T_NEAR(tvt_shadow_at(&sh, 0.3f, p) / exp(-0.1 * 16 / 0.8), 1.0, 1e-3);
    p[2] = 30.0f;
    T_NEAR(tvt_shadow_at(&sh, 0.3f, p), 1.0, 1e-6);
    tvt_shadow_free(&sh);
    /* light across the fibres (tangent x, light z) against along them (light x) */
    {
        float q[3] = {16, 16, 16}, e[3] = {0, 0.6f, -0.8f};
        tvt_shade_desc a = tvt_shade_default_desc(), b = a;
        a.light_dir[0] = 0; a.light_dir[1] = 0; a.light_dir[2] = 1;
        b.light_dir[0] = 1; b.light_dir[1] = 0; b.light_dir[2] = 0;
        tvt_shade_point(&t, 0.0f, 0, &a, q, e, 1.0f, across);
        tvt_shade_point(&t, 0.0f, 0, &b, q, e, 1.0f, along);
        T_CHECK(across[1] > along[1] + 0.3f);
    }
    tvt_lod_free(&t.frames[0]); tvt_lod_free(&t.frames[1]);
    /* an empty TVT: nothing seen */
    memset(vox, 0, (size_t)res * res * res * sizeof(tvt_voxel));
    T_CHECK(tvt_texel_from_voxels(res, vox, 8, NULL, &empty) == TVT_OK);
    T_CHECK(tvt_build_lod(&empty, &lo, &t.frames[0]) == TVT_OK);
    T_CHECK(tvt_build_lod(&empty, &lo, &t.frames[1]) == TVT_OK);
    d[0] = 0; d[2] = -1;
    tvt_march(&t, 0.2f, 0, &sd, o, d, 30.0f, rgb, &T);
    T_CHECK(T == 1.0f && rgb[0] == 0 && rgb[1] == 0 && rgb[2] == 0);
    T_EQ_INT(tvt_build_shadow(&t, 0, d, NULL, &sh), TVT_ERR_BAD_PARAMETER); /* light from below */
    tvt_lod_free(&t.frames[0]); tvt_lod_free(&t.frames[1]);
    free(t.frames);
    tvt_texel_free(&slab); tvt_texel_free(&empty);
    free(vox);
}

int main(int argc, char **argv)
{
    int sanitize = getenv("TEST_SANITIZE") != NULL;
    T_BEGIN(argc, argv);
    if (sanitize) printf("note: TEST_SANITIZE is set: LOD opacity at 64^3 with 2000 rays per elevation\n");
    test_lod_opacity(sanitize ? 64 : 128, sanitize ? 2000 : 10000, 0.0f);
    test_lod_opacity(sanitize ? 64 : 128, sanitize ? 2000 : 10000, 0.917f);
    test_key_frames();
    test_mingling();
    test_march();
    test_bad_input();
    test_allocation_failure();
    return T_END();
}
