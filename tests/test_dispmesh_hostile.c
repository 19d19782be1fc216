/* test_dispmesh_hostile.c - dispmesh.h on input a hostile caller gives: no silent wrong answer
   (issue 21 point 2). It checks that:
   - the BVH finds far hits of axis-parallel rays: from z = 3 with direction (0, 0, -1e-20) the
     unit sphere is hit at t = 2e20, from z = 6e19 with direction (0, 0, -1) at t = 6e19 - 1, on
     every axis and both ways, by dm_bvh_intersect, _occluded, _intersect_line and the batches
     (a tiny direction component's inverse clamped to 1e20 made the ray's slab miss them);
   - dm_bake and dm_reconstruct check the public dm_param and dm_dispmap arrays: each of an
     out-of-range neighbour, texel triangle, twin, chart or rotation, a missing array, a NaN uv
     or barycentre, and a NaN or infinite depth or normal gives DM_ERR_BAD_MAP (it read out of
     bounds, crashed, or gave a NaN mesh with DM_OK), and the untouched arrays still give DM_OK;
   - the pipeline holds at the documented coordinate limit: a sphere at 1e17 is simplified,
     weighted by dm_coverage_weights (areas about 1e33), parameterized, baked and reconstructed
     with DM_OK and a finite result that lies on the original's scale;
   - dm_surface_distance refuses more than 10^9 samples a side (2 x samples overflowed and the
     progress went past 1). */
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#include "test.h"
#include "testmesh.h"
#include <stdlib.h>
#include <string.h>
#include <math.h>

/* ---- far hits of axis-parallel rays ---------------------------------------------------------- */

static void far_hits(void)
{
    mesh s = make_sphere(6, 0.0, 1.0);
    dm_bvh *bvh = NULL;
    int axis, sgn, c;
    if (!T_EQ_INT(dm_bvh_build(s.p, s.nv, s.t, s.nt, NULL, &bvh), DM_OK)) { mesh_free(&s); return; }
    for (axis = 0; axis < 3; axis++)
        for (sgn = -1; sgn <= 1; sgn += 2)
            for (c = 0; c < 2; c++) {
                /* c = 0: from 3 along the axis, direction 1e-20 back; c = 1: from 6e19, direction 1 */
                float from = c ? 6e19f : 3.0f, speed = c ? 1.0f : 1e-20f;
                double expect = c ? (6e19 - 1.0) : 2.0 / 1e-20;
                dm_ray r, rays[4];
                dm_hit h, hs[4];
                uint8_t occ[4];
                int k;
                memset(&r, 0, sizeof r);
                r.org[axis] = (float)sgn * from;
                r.dir[axis] = -(float)sgn * speed;
                r.tmin = 0.0f;
                r.tmax = INFINITY;
                T_CHECK_MSG(dm_bvh_intersect(bvh, &r, &h) == 1 && fabs(h.t / expect - 1.0) < 1e-5,
                            "axis %d sign %d case %d: hit %d t %g, expected %g", axis, sgn, c, (int)h.triangle != (int)DM_NO_HIT,
                            (double)h.t, expect);
                T_CHECK(dm_bvh_occluded(bvh, &r) == 1);
                r.tmin = -INFINITY;
                T_CHECK_MSG(dm_bvh_intersect_line(bvh, &r, &h) == 1 && fabs(h.t / expect - 1.0) < 1e-5,
                            "line: axis %d sign %d case %d: t %g", axis, sgn, c, (double)h.t);
                r.tmin = 0.0f;
                for (k = 0; k < 4; k++) rays[k] = r;
                T_CHECK(dm_bvh_intersect_batch(bvh, rays, 4, hs) == 4 && fabs(hs[3].t / expect - 1.0) < 1e-5);
                T_CHECK(dm_bvh_occluded_batch(bvh, rays, 4, occ) == 4);
            }
    dm_bvh_free(bvh);
    mesh_free(&s);
}

/* ---- the public arrays of dm_param and dm_dispmap --------------------------------------------- */

typedef struct pipeline {
    mesh orig, base;
    dm_param *param;
    dm_dispmap *map;
} pipeline;

/* orig: a bumpy sphere; base: it simplified (no shell); 128^2 map, baked */
static int make_pipeline(pipeline *p, double scale, int coverage)
{
    dm_simplify_options so = dm_simplify_default_options();
    dm_param_options po = dm_param_default_options();
    dm_pm *pm = NULL;
    float *w = NULL;
    int ok = 0;
    memset(p, 0, sizeof *p);
    p->orig = make_sphere(12, 0.05, scale);
    so.target_triangles = 200;
    if (!T_EQ_INT(dm_simplify(p->orig.p, p->orig.nv, p->orig.t, p->orig.nt, &so, &pm, NULL), DM_OK)) goto done;
    dm_pm_counts(pm, &p->base.nv, &p->base.nt);
    p->base.p = (float *)malloc(3 * p->base.nv * sizeof(float));
    p->base.t = (uint32_t *)malloc(3 * p->base.nt * sizeof(uint32_t));
    if (!T_CHECK(p->base.p && p->base.t)) goto done;
    dm_pm_get_mesh(pm, p->base.p, p->base.t, NULL);
    if (coverage) {
        w = (float *)malloc(p->base.nt * sizeof(float));
        if (!T_CHECK(w != NULL)) goto done;
        if (!T_EQ_INT(dm_coverage_weights(p->base.p, p->base.nv, p->base.t, p->base.nt, p->orig.p, p->orig.nv,
                                          p->orig.t, p->orig.nt, NULL, w), DM_OK)) goto done;
        po.triangle_weight = w;
    }
    po.width = po.height = 128;
    if (!T_EQ_INT(dm_parameterize(p->base.p, p->base.nv, p->base.t, p->base.nt, &po, &p->param), DM_OK)) goto done;
    if (!T_EQ_INT(dm_bake(p->param, p->base.p, p->base.nv, p->base.t, p->base.nt, p->orig.p, p->orig.nv, p->orig.t,
                          p->orig.nt, NULL, &p->map), DM_OK)) goto done;
    ok = 1;
done:
    dm_pm_free(pm);
    free(w);
    return ok;
}

static void free_pipeline(pipeline *p)
{
    dm_dispmap_free(p->map);
    dm_param_free(p->param);
    mesh_free(&p->orig);
    mesh_free(&p->base);
}

static dm_result try_bake(pipeline *p)
{
    dm_dispmap *m = NULL;
    dm_result r = dm_bake(p->param, p->base.p, p->base.nv, p->base.t, p->base.nt, p->orig.p, p->orig.nv, p->orig.t,
                          p->orig.nt, NULL, &m);
    T_CHECK((r == DM_OK) == (m != NULL));
    dm_dispmap_free(m);
    return r;
}

static dm_result try_reconstruct(pipeline *p)
{
    dm_trimesh *d = NULL;
    dm_result r = dm_reconstruct(p->map, p->param, p->base.p, p->base.nv, p->base.t, p->base.nt, NULL, &d);
    size_t i;
    T_CHECK((r == DM_OK) == (d != NULL));
    if (d) { /* an accepted map gives a finite mesh */
        int finite = 1;
        for (i = 0; i < 3 * d->vertex_count; i++) finite &= isfinite(d->positions[i]) && isfinite(d->normals[i]);
        T_CHECK_MSG(finite, "dm_reconstruct returned DM_OK with a non-finite vertex");
    }
    dm_trimesh_free(d);
    return r;
}

/* sets word (of type T) to bad, checks that dm_reconstruct (and dm_bake when both) refuse it
   with DM_ERR_BAD_MAP, restores it */
#define BAD_VALUE(T, word, bad, both)                                                                   \
    do {                                                                                                \
        T keep_ = (word);                                                                               \
        (word) = (bad);                                                                                 \
        if (both) T_CHECK_MSG(try_bake(&p) == DM_ERR_BAD_MAP, "bake accepted %s = %g", #word, (double)(bad)); \
        T_CHECK_MSG(try_reconstruct(&p) == DM_ERR_BAD_MAP, "reconstruct accepted %s = %g", #word, (double)(bad)); \
        (word) = keep_;                                                                                 \
    } while (0)
#define BAD_U32(word, bad, both) BAD_VALUE(uint32_t, word, bad, both)
#define BAD_F(word, bad, both) BAD_VALUE(float, word, bad, both)

static void public_arrays(void)
{
    pipeline p;
    size_t n, mid, tex = 0;
    if (!make_pipeline(&p, 1.0, 0)) { free_pipeline(&p); return; }
    n = (size_t)p.param->width * (size_t)p.param->height;
    mid = n / 2;
    while (tex < n && p.param->texel_triangle[tex] == DM_NO_HIT) tex++; /* a covered texel */
    T_CHECK(tex < n);
    T_EQ_INT(try_bake(&p), DM_OK);
    T_EQ_INT(try_reconstruct(&p), DM_OK);
    BAD_U32(p.param->nbr[4 * mid], (uint32_t)n + 5, 1);
    BAD_U32(p.param->nbr[4 * tex + 2], (uint32_t)n, 1);
    BAD_U32(p.param->texel_triangle[tex], 0x7FFFFFFFu, 1);
    BAD_U32(p.param->texel_triangle[mid], (uint32_t)p.param->triangle_count, 1);
    BAD_U32(p.param->twin[5], (uint32_t)p.param->triangle_count + 1, 1);
    BAD_U32(p.param->chart[3], (uint32_t)p.param->chart_count, 1);
    {
        uint8_t keep = p.param->nbr_rot[7];
        p.param->nbr_rot[7] = 4;
        T_EQ_INT(try_bake(&p), DM_ERR_BAD_MAP);
        T_EQ_INT(try_reconstruct(&p), DM_ERR_BAD_MAP);
        p.param->nbr_rot[7] = keep;
    }
    BAD_F(p.param->uv[4], NAN, 1);
    BAD_F(p.param->uv[1], INFINITY, 1);
    BAD_F(p.param->texel_bary[2 * tex], NAN, 1);
    BAD_F(p.map->disp[tex], NAN, 0);
    BAD_F(p.map->disp[tex], INFINITY, 0);
    BAD_F(p.map->disp[tex], 1e30f, 0);
    BAD_F(p.map->nrm[3 * tex + 1], NAN, 0);
    BAD_F(p.map->normal[3 * tex], NAN, 0);
    {
        float *keep = p.map->disp;
        p.map->disp = NULL;
        T_EQ_INT(try_reconstruct(&p), DM_ERR_BAD_MAP);
        p.map->disp = keep;
    }
    {
        uint32_t *keep = p.param->nbr;
        p.param->nbr = NULL;
        T_EQ_INT(try_bake(&p), DM_ERR_BAD_MAP);
        T_EQ_INT(try_reconstruct(&p), DM_ERR_BAD_MAP);
        p.param->nbr = keep;
    }
    T_EQ_INT(try_bake(&p), DM_OK); /* restored: accepted again */
    T_EQ_INT(try_reconstruct(&p), DM_OK);
    free_pipeline(&p);
}

/* ---- coordinates at 1e17 --------------------------------------------------------------------- */

static void large_coordinates(void)
{
    pipeline p;
    dm_trimesh *d = NULL;
    size_t i;
    double worst = 0.0;
    if (!make_pipeline(&p, 1e17, 1)) { free_pipeline(&p); return; }
    T_CHECK_MSG(p.map->hit_count > 0 && p.map->miss_count * 100 <= p.map->hit_count, "hits %zu misses %zu",
                p.map->hit_count, p.map->miss_count);
    if (T_EQ_INT(dm_reconstruct(p.map, p.param, p.base.p, p.base.nv, p.base.t, p.base.nt, NULL, &d), DM_OK)) {
        /* every vertex on the bumpy sphere of radius ~1e17 (amplitude 5%) */
        for (i = 0; i < d->vertex_count; i++) {
            double r = sqrt((double)d->positions[3 * i] * d->positions[3 * i] + (double)d->positions[3 * i + 1] * d->positions[3 * i + 1] +
                            (double)d->positions[3 * i + 2] * d->positions[3 * i + 2]) / 1e17;
            if (!(fabs(r - 1.0) <= worst)) worst = isfinite(r) ? fabs(r - 1.0) : HUGE_VAL;
        }
        T_CHECK_MSG(worst < 0.1, "a reconstructed vertex at %g radii from the sphere", worst);
    }
    dm_trimesh_free(d);
    free_pipeline(&p);
}

/* ---- dm_surface_distance's sample count ------------------------------------------------------ */

static void sample_bound(void)
{
    mesh s = make_sphere(2, 0.0, 1.0);
    dm_distance_options o = dm_distance_default_options();
    dm_distance_report rep;
    o.samples_per_side = (size_t)-1 / 2 + 1;
    T_EQ_INT(dm_surface_distance(s.p, s.nv, s.t, s.nt, s.p, s.nv, s.t, s.nt, &o, &rep), DM_ERR_INVALID_ARGUMENT);
    o.samples_per_side = 1000000001u;
    T_EQ_INT(dm_surface_distance(s.p, s.nv, s.t, s.nt, s.p, s.nv, s.t, s.nt, &o, &rep), DM_ERR_INVALID_ARGUMENT);
    o.samples_per_side = 1000;
    T_EQ_INT(dm_surface_distance(s.p, s.nv, s.t, s.nt, s.p, s.nv, s.t, s.nt, &o, &rep), DM_OK);
    mesh_free(&s);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    far_hits();
    public_arrays();
    large_coordinates();
    sample_bound();
    return T_END();
}
