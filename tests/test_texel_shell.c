/* test_texel_shell - render.h's shell marcher (sr_draw_shell), the terrain driver of texel.h's
   grass, with analytic content: a uniform layer, a layer on a slope (the sheared frame), a
   fibre layer (Kajiya-Kay with the tangent turned back to the world), the ground, existing
   depth, bad input, cancellation and determinism. Then texel.h's grass through the same driver
   (tvt_tvt_sample on a 32^3 TVT): each pixel's opacity is the texel column's. */
#define SR_IMPLEMENTATION
#include "render.h"
#define TVT_IMPLEMENTATION
#include "texel.h"
#include "test.h"
#include <stdlib.h>

#define W 24
#define H 16

/* the content: a uniform layer of extinction sigma up to height top (tile units) */
typedef struct content {
    float sigma, top, step, rgb[3], tangent[3], light, specular;
    long calls, bad_frame;
    float footprint_min, footprint_max;
    float slope;   /* the ground's dh/dx, to check the frame's z against */
} content;

static void uniform(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    content *c = (content *)user;
    c->calls++;
    if (c->calls == 1 || q->footprint < c->footprint_min) c->footprint_min = q->footprint;
    if (c->calls == 1 || q->footprint > c->footprint_max) c->footprint_max = q->footprint;
    if (!(q->p[0] >= 0 && q->p[0] < 1 && q->p[1] >= 0 && q->p[1] < 1 && q->p[2] >= 0 && q->p[2] < 1.0f + 1e-6f))
        c->bad_frame++;
    out->step = c->step;
    if (q->p[2] >= c->top) return;
    out->sigma = c->sigma;
    memcpy(out->rgb, c->rgb, sizeof(out->rgb));
    memcpy(out->tangent, c->tangent, sizeof(out->tangent));
    out->light = c->light;
    out->specular = c->specular;
}

/* a light straight above: ambient a, diffuse 1, specular 1 */
static void sun_above(sr_light *l, float a)
{
    float up[3] = {0, 0, 1};
    sr_light_default(l, up);
    l->ambient[0] = l->ambient[1] = l->ambient[2] = a;
    l->diffuse[0] = l->diffuse[1] = l->diffuse[2] = 1.0f;
    l->specular[0] = l->specular[1] = l->specular[2] = 1.0f;
}

/* an orthographic camera looking straight down on the 4 x 4 tiles [0, 4]^2 */
static void camera_down(sr_camera *cam)
{
    float eye[3] = {2, 2, 10}, at[3] = {2, 2, 0}, up[3] = {0, 1, 0};
    sr_camera_ortho(cam, eye, at, up, 1.2f, (float)W / (float)H, 0.1f, 100.0f);
}

static void base_desc(sr_shell_desc *d, content *c, sr_light *l)
{
    sr_shell_desc_default(d);
    d->tiles_x = d->tiles_y = 4;
    d->sample = uniform; d->user = c;
    d->lights = l; d->light_count = 1;
    memset(d->material.emission, 0, sizeof(d->material.emission));
    d->termination = 0.99999f;
}

static double max_abs_diff(const sr_framebuffer *fb, const float *rgb)
{
    double worst = 0;
    int i, k;
    for (i = 0; i < fb->width * fb->height; i++)
        for (k = 0; k < 3; k++) {
            double e = fabs(fb->color[4 * i + k] - rgb[k]);
            if (e > worst) worst = e;
        }
    return worst;
}

/* Seen straight down, the layer's steps of 1/64 sum to its height exactly (the first sample
   starts 1/4096 of a tile below the top): opacity 1 - exp(-sigma top), over the Lambert-lit
   ground. Isotropic content: ambient + diffuse, no specular. */
static void test_uniform_layer(void)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc d;
    sr_shell_stats st;
    sr_light l;
    content c;
    float expect[3];
    int k;
    memset(&c, 0, sizeof(c));
    c.sigma = 1.0f; c.top = 2.0f; c.step = 1.0f / 64.0f; c.light = 1.0f;
    c.rgb[0] = 0.2f; c.rgb[1] = 0.6f; c.rgb[2] = 0.1f;
    sun_above(&l, 0.25f);
    camera_down(&cam);
    base_desc(&d, &c, &l);
    T_CHECK(sr_framebuffer_create(&fb, W, H, NULL) == SR_OK);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, &st), SR_OK);
    for (k = 0; k < 3; k++) {
        double T = exp(-1.0), medium = c.rgb[k] * (0.25 + 1.0), ground = d.ground_rgb[k] * (0.25 + 1.0);
        expect[k] = (float)((1 - T) * medium + T * ground);
    }
    /* 64 steps of alpha 1 - exp(-1/64) in float: the product's rounding is below 1e-5 */
    T_NEAR(max_abs_diff(&fb, expect), 0.0, 2e-5);
    T_CHECK(c.bad_frame == 0);
    T_CHECK(st.covered == W * H); /* layer opacity 1 - 1/e > 0.5 everywhere */
    T_CHECK(st.samples == c.calls && c.calls >= (long)W * H * 64);
    /* orthographic: a pixel's width is 2 * half_height / H = 2.4 / 16 tile units everywhere */
    T_NEAR(c.footprint_min, 2.4 / H, 1e-6);
    T_NEAR(c.footprint_max, 2.4 / H, 1e-6);
    /* a thin layer: opacity 1 - exp(-0.5) < 0.5, so no pixel counts as covered */
    c.sigma = 0.5f;
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, &st), SR_OK);
    T_CHECK(st.covered == 0);
    /* the ground alone (empty content) and the depth written there: its plane z = 0. Empty
       samples advance by their step: 64 of 1/64 cross the layer (t is exact in float here:
       the eye at z = 10, steps of 2^-6 after the first 2^-12), then the ground */
    c.sigma = 0.0f;
    c.calls = 0;
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, &st), SR_OK);
    T_CHECK(c.calls == 64L * W * H);
    for (k = 0; k < 3; k++) expect[k] = d.ground_rgb[k] * 1.25f;
    T_NEAR(max_abs_diff(&fb, expect), 0.0, 1e-6);
    {
        float ground_point[3] = {2, 2, 0}, z;
        T_CHECK(sr_camera_depth(&cam, ground_point, &z));
        T_NEAR(fb.depth[(H / 2) * W + W / 2], z, 1e-3); /* the ground is hit within a step of 1/64 */
    }
    sr_framebuffer_free(&fb);
}

/* On the slope h = 0.5 x the layer is vertical (the frame is sheared, not offset along the
   normal): seen straight down it is as thick as on flat ground, and the content's z is the
   height above the ground. A dense layer hides the ground (exp(-12) < 1e-5). */
static void test_sheared_frame(void)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc d;
    sr_light l;
    content c;
    float heights[5 * 5], expect[3];
    int i, j, k;
    for (j = 0; j < 5; j++)
        for (i = 0; i < 5; i++) heights[j * 5 + i] = 0.5f * (float)i;
    memset(&c, 0, sizeof(c));
    c.sigma = 12.0f; c.top = 2.0f; c.step = 1.0f / 64.0f; c.light = 1.0f;
    c.rgb[0] = 0.3f; c.rgb[1] = 0.5f; c.rgb[2] = 0.2f;
    sun_above(&l, 0.25f);
    camera_down(&cam);
    base_desc(&d, &c, &l);
    d.heights = heights; d.nx = d.ny = 5; d.spacing = 1.0f;
    T_CHECK(sr_framebuffer_create(&fb, W, H, NULL) == SR_OK);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_OK);
    for (k = 0; k < 3; k++) expect[k] = c.rgb[k] * 1.25f;
    T_NEAR(max_abs_diff(&fb, expect), 0.0, 1e-4);
    T_CHECK(c.bad_frame == 0);
    {
        float g[2];
        T_NEAR(sr_shell_height(&d, 1.3f, 2.7f, g), 0.65, 1e-6);
        T_NEAR(g[0], 0.5, 1e-6);
        T_NEAR(g[1], 0.0, 1e-6);
    }
    sr_framebuffer_free(&fb);
}

/* Fibres along the frame's x on the slope h = a x run along the slope in the world, (1, 0, a):
   with the light and the eye straight above, Kajiya-Kay's diffuse is sin(T, L) = 1 / sqrt(1 +
   a^2) and its specular (T.L T.V' + sin sin)^p = (sin^2 - cos^2)^p, both with the self-shadow
   (sample->light) on light 0; the ambient term is not shadowed; specular colour 0.4 times the
   sample's weight 0.5. */
static void test_kajiya_kay(void)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc d;
    sr_light l;
    content c;
    const float a = 0.5f;
    float heights[5 * 5], expect[3];
    int i, j, k;
    double s2, c2, diff, spec;
    for (j = 0; j < 5; j++)
        for (i = 0; i < 5; i++) heights[j * 5 + i] = a * (float)i;
    memset(&c, 0, sizeof(c));
    c.sigma = 12.0f; c.top = 2.0f; c.step = 1.0f / 64.0f; c.light = 0.5f;
    c.rgb[0] = 0.3f; c.rgb[1] = 0.5f; c.rgb[2] = 0.2f;
    c.tangent[0] = 1.0f;
    c.specular = 0.5f;
    sun_above(&l, 0.2f);
    camera_down(&cam);
    base_desc(&d, &c, &l);
    d.heights = heights; d.nx = d.ny = 5; d.spacing = 1.0f;
    d.material.specular[0] = d.material.specular[1] = d.material.specular[2] = 0.4f;
    d.material.shininess = 3.0f;
    T_CHECK(sr_framebuffer_create(&fb, W, H, NULL) == SR_OK);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_OK);
    s2 = 1.0 / (1.0 + a * a); /* sin^2 of the angle between (1, 0, a) and (0, 0, 1) */
    c2 = 1.0 - s2;
    diff = sqrt(s2);
    spec = pow(s2 - c2, 3.0);
    for (k = 0; k < 3; k++) expect[k] = (float)(0.2 * c.rgb[k] + 0.5 * (diff * c.rgb[k] + 0.4 * 0.5 * spec));
    T_NEAR(max_abs_diff(&fb, expect), 0.0, 1e-4);
    sr_framebuffer_free(&fb);
}

/* tile x = 0 reports a long empty span (10 tiles), the others are dense: horizontal rays that
   start in tile 0 must still meet tile 1 (an empty skip ends at the tile's border), so every
   pixel sees the dense content, opaque (exp(-12 * 0.5) leaves 0.25% over a half tile, and the
   rays cross 3 tiles) and lit isotropically. */
static void tiled(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    content *c = (content *)user;
    c->calls++;
    if (q->tile_x == 0) { out->step = 10.0f; return; }
    out->step = c->step;
    out->sigma = c->sigma;
    memcpy(out->rgb, c->rgb, sizeof(out->rgb));
    out->light = 1.0f;
}

static void test_skip_stops_at_tile_border(void)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc d;
    sr_light l;
    content c;
    float eye[3] = {-1.0f, 2.0f, 0.5f}, at[3] = {3.0f, 2.0f, 0.5f}, up[3] = {0, 0, 1}, expect[3];
    int k;
    memset(&c, 0, sizeof(c));
    c.sigma = 12.0f; c.step = 1.0f / 64.0f;
    c.rgb[0] = 0.8f; c.rgb[1] = 0.1f; c.rgb[2] = 0.1f;
    sun_above(&l, 0.25f);
    sr_camera_ortho(&cam, eye, at, up, 0.2f, (float)W / (float)H, 0.1f, 100.0f);
    base_desc(&d, &c, &l);
    d.sample = tiled;
    T_CHECK(sr_framebuffer_create(&fb, W, H, NULL) == SR_OK);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_OK);
    for (k = 0; k < 3; k++) expect[k] = c.rgb[k] * 1.25f;
    T_NEAR(max_abs_diff(&fb, expect), 0.0, 1e-3);
    sr_framebuffer_free(&fb);
}

static int cancel_at_once(void *user, float done) { (void)user; (void)done; return 1; }

/* Geometry already in the framebuffer nearer than the layer hides it (the colour stays and
   no sample is taken); bad input, cancellation, and the same bits on every run. */
static void test_depth_bad_input_cancel(void)
{
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc d;
    sr_light l;
    content c;
    float grey[4] = {0.5f, 0.5f, 0.5f, 1.0f}, z, front[3] = {2, 2, 3};
    float heights[4] = {0, 0, 0, 0};
    uint8_t *a, *b;
    int i, same = 1;
    memset(&c, 0, sizeof(c));
    c.sigma = 3.0f; c.top = 2.0f; c.step = 1.0f / 32.0f; c.light = 1.0f;
    c.rgb[1] = 1.0f;
    sun_above(&l, 0.25f);
    camera_down(&cam);
    base_desc(&d, &c, &l);
    T_CHECK(sr_framebuffer_create(&fb, W, H, NULL) == SR_OK);
    T_CHECK(sr_camera_depth(&cam, front, &z));
    sr_framebuffer_clear(&fb, grey, z); /* an opaque plane at height 3, above the layer */
    c.calls = 0;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_OK);
    T_NEAR(max_abs_diff(&fb, grey), 0.0, 0.0);
    T_CHECK(c.calls == 0);
    /* bad input */
    T_EQ_INT(sr_draw_shell(NULL, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    T_EQ_INT(sr_draw_shell(&fb, NULL, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    T_EQ_INT(sr_draw_shell(&fb, &cam, NULL, NULL), SR_ERR_INVALID_ARGUMENT);
    d.sample = NULL;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.sample = uniform; d.tile = 0.0f;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.tile = 1.0f; d.tiles_x = 0;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.tiles_x = 4; d.thickness = -1.0f;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.thickness = (float)NAN;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.thickness = 0.0f; d.origin[1] = (float)INFINITY;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.origin[1] = 0.0f; d.tile = 1e30f;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.tile = 1.0f;
    d.thickness = 0.0f; d.heights = heights; d.nx = 1; d.ny = 4; d.spacing = 1.0f;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.nx = 2; d.ny = 2; heights[3] = (float)NAN;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    heights[3] = 0.0f; d.spacing = 0.0f;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_ERR_INVALID_ARGUMENT);
    d.spacing = 4.0f;
    d.progress = cancel_at_once;
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_CANCELLED);
    T_CHECK(strcmp(sr_result_string(SR_CANCELLED), "SR_CANCELLED") == 0);
    d.progress = NULL;
    /* the same bits on every run */
    a = (uint8_t *)malloc(sizeof(float) * 4 * W * H);
    b = (uint8_t *)malloc(sizeof(float) * 4 * W * H);
    for (i = 0; i < 2; i++) {
        float eye[3] = {-1, -2, 3}, at[3] = {2, 2, 0}, up[3] = {0, 0, 1};
        sr_camera_look_at(&cam, eye, at, up, 50.0f, (float)W / (float)H, 0.1f, 100.0f);
        sr_framebuffer_clear(&fb, NULL, 1.0f);
        T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_OK);
        memcpy(i ? b : a, fb.color, sizeof(float) * 4 * W * H);
    }
    for (i = 0; i < (int)(sizeof(float) * 4 * W * H); i++) if (a[i] != b[i]) same = 0;
    T_CHECK(same);
    free(a);
    free(b);
    sr_framebuffer_free(&fb);
}

/* ---- texel.h's grass through the driver ------------------------------------------------------- */
typedef struct grass { tvt_tvt tv; int res; } grass;

/* level 0 at wd 0 (key frame 0 exactly), white, lit by ambient only: a pixel's colour is the
   layer's opacity */
static void grass_sample(void *user, const sr_shell_query *q, sr_shell_sample *out)
{
    grass *g = (grass *)user;
    float p[3], sigma, res = (float)g->res;
    tvt_voxel v;
    p[0] = q->p[0] * res; p[1] = q->p[1] * res; p[2] = q->p[2] * res;
    out->step = 1.0f / res;
    sigma = tvt_tvt_sample(&g->tv, 0.0f, 0, p, q->dir, &v);
    if (!(sigma > 0)) return;
    out->sigma = sigma * res;
    out->rgb[0] = out->rgb[1] = out->rgb[2] = 1.0f;
    out->light = 1.0f;
}

/* Straight down, the driver samples the column at z = res (1 - 1/4096) - k voxels, k = 0, 1,
   ..., one voxel per step: on the trilinear field, linear in z between voxel centres, that is
   the midpoint rule on those linear pieces, so it integrates density exactly from z = 0.5 up
   (the sample offset of res/4096 voxel changes it by under 1%). tvt_optical_depth's own
   half-voxel midpoint sum over [0.5, res] is also exact there: the two optical depths agree
   within 2% (+1e-4), so the opacities within 0.02 tau exp(-tau) + 1e-4. */
static void test_grass_through_driver(void)
{
    tvt_grass_desc gd = tvt_grass_default_desc();
    tvt_tvt_options o = tvt_tvt_default_options();
    tvt_texel t;
    grass g;
    sr_framebuffer fb;
    sr_camera cam;
    sr_shell_desc d;
    sr_light l;
    float eye[3] = {0.5f, 0.5f, 10}, at[3] = {0.5f, 0.5f, 0}, up[3] = {0, 1, 0};
    long bad = 0, seen = 0;
    int x, y, n = 32;
    memset(&g, 0, sizeof(g));
    gd.res = 32; gd.blade_count = 60; gd.seed = 5;
    o.frames = 2;
    T_CHECK(tvt_build_grass(&gd, &t) == TVT_OK);
    T_CHECK(tvt_build_tvt(&t, &o, &g.tv) == TVT_OK);
    g.res = 32;
    sr_light_default(&l, up);
    l.ambient[0] = l.ambient[1] = l.ambient[2] = 1.0f;
    memset(l.diffuse, 0, sizeof(l.diffuse));
    memset(l.specular, 0, sizeof(l.specular));
    sr_shell_desc_default(&d);
    d.sample = grass_sample; d.user = &g; d.lights = &l; d.light_count = 1;
    memset(d.ground_rgb, 0, sizeof(d.ground_rgb));
    memset(d.material.emission, 0, sizeof(d.material.emission));
    d.termination = 0.999999f;
    sr_camera_ortho(&cam, eye, at, up, 0.5f, 1.0f, 0.1f, 100.0f);
    T_CHECK(sr_framebuffer_create(&fb, n, n, NULL) == SR_OK);
    sr_framebuffer_clear(&fb, NULL, 1.0f);
    T_EQ_INT(sr_draw_shell(&fb, &cam, &d, NULL), SR_OK);
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            float o3[3], dir[3], top[3], down[3] = {0, 0, -1};
            double tau, alpha = fb.color[4 * (y * n + x)];
            sr_camera_ray(&cam, n, n, (float)x + 0.5f, (float)y + 0.5f, o3, dir);
            top[0] = o3[0] * 32.0f; top[1] = o3[1] * 32.0f; top[2] = 32.0f;
            tau = tvt_optical_depth(&g.tv.frames[0], 0, top, down, 31.5f);
            if (tau > 0.05) seen++;
            if (fabs(alpha - (1.0 - exp(-tau))) > 0.02 * tau * exp(-tau) + 1e-4) bad++;
        }
    T_CHECK(bad == 0);
    T_CHECK(seen > n * n / 4); /* the grass is there: a quarter of the columns at least */
    {
        float p[3] = {10.3f, 12.7f, 5.2f}, dir[3] = {0.6f, 0.0f, -0.8f}, rgb[3];
        tvt_voxel v;
        float sigma = tvt_tvt_sample(&g.tv, 0.3f, 0, p, dir, &v);
        float alpha = tvt_shade_point(&g.tv, 0.3f, 0, NULL, p, dir, 0.5f, rgb);
        T_NEAR(alpha, 1.0 - exp(-sigma * 0.5), 1e-6);
    }
    sr_framebuffer_free(&fb);
    tvt_tvt_free(&g.tv);
    tvt_texel_free(&t);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    test_uniform_layer();
    test_sheared_frame();
    test_kajiya_kay();
    test_depth_bad_input_cancel();
    test_skip_stops_at_tile_border();
    test_grass_through_driver();
    return T_END();
}
