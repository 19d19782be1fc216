/* fuzz_dispmesh.c - fuzz target for dispmesh.h: BVH build, refit and queries, dm_simplify with its
   progressive mesh, dm_weld, dm_orient, dm_shell_grow with the shell constraint, dm_parameterize, dm_bake,
   dm_reconstruct, dm_coverage_weights and dm_surface_distance, on a tiny mesh decoded from the
   bytes.
   libFuzzer: clang -g -O1 -I. -Itests -fsanitize=fuzzer,address,undefined tests/fuzz_dispmesh.c -o fuzz_dispmesh -lm
   plain:     gcc -std=c99 -g -O1 -I. -Itests tests/fuzz_dispmesh.c tests/fuzz_main.c -o fuzz_dispmesh -lm
              && ./fuzz_dispmesh tests/fuzz/corpus/dispmesh
   Byte 0: the entry point (bits 0-1), the mesh kind (bit 2: an octahedron split once, 18 vertices
   and 32 triangles, with per-vertex radial offsets from the bytes; else up to 24 vertices and 40
   triangles of any indices), raw numbers (bit 7: 4-byte floats of any bits; else (b - 128) / 16);
   byte 1: the allocation to fail and the progress call that cancels (nibbles, 0 = none). Maps are
   at most 48 x 48 texels. Every call returns DM_OK with a sound result (hits inside their ray's
   range and triangle, occlusion agreeing with the nearest hit, meshes with indices in range and
   finite positions, the progressive mesh's finest level equal to the input, maps whose arrays
   stay in range) or a named code with nothing held; a broken rule calls abort(). */
#define FZ_HELPERS_ONLY
#include "fuzz_deform.c" /* the byte reader and failing allocator */
#define DM_IMPLEMENTATION
#include "dispmesh.h"

#define FZ_V 24
#define FZ_T 40

static int fz_known(dm_result r) { return strcmp(dm_result_string(r), "DM_ERR_?") != 0; }

typedef struct fz_tri { float pos[3 * FZ_V]; uint32_t idx[3 * FZ_T]; size_t nv, nt; } fz_tri;

/* the octahedron split once onto a sphere of radius 1 + offset / 4 per vertex */
static void fz_octa(fz_in *in, fz_tri *m)
{
    static const float ov[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
    static const uint32_t of[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    size_t t, k, v;
    memcpy(m->pos, ov, sizeof ov);
    m->nv = 6;
    m->nt = 0;
    for (t = 0; t < 8; t++) {
        uint32_t c[3], mid[3];
        for (k = 0; k < 3; k++) c[k] = of[3 * t + k];
        for (k = 0; k < 3; k++) {
            uint32_t a = c[k], b = c[(k + 1) % 3];
            for (v = 6; v < m->nv; v++)
                if (m->pos[3 * v] == 0.5f * (m->pos[3 * a] + m->pos[3 * b]) &&
                    m->pos[3 * v + 1] == 0.5f * (m->pos[3 * a + 1] + m->pos[3 * b + 1]) &&
                    m->pos[3 * v + 2] == 0.5f * (m->pos[3 * a + 2] + m->pos[3 * b + 2]))
                    break;
            if (v == m->nv) {
                int q;
                for (q = 0; q < 3; q++) m->pos[3 * v + q] = 0.5f * (m->pos[3 * a + q] + m->pos[3 * b + q]);
                m->nv++;
            }
            mid[k] = (uint32_t)v;
        }
        {
            uint32_t f[12] = {c[0], mid[0], mid[2], c[1], mid[1], mid[0], c[2], mid[2], mid[1], mid[0], mid[1], mid[2]};
            memcpy(m->idx + 3 * m->nt, f, sizeof f);
            m->nt += 4;
        }
    }
    for (v = 0; v < m->nv; v++) {
        float *p = m->pos + 3 * v, r = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        float s = (1.0f + 0.25f * fz_f32(in)) / r;
        p[0] *= s, p[1] *= s, p[2] *= s;
    }
}

static void fz_decode(fz_in *in, unsigned op, fz_tri *m)
{
    if (op & 4) fz_octa(in, m);
    else fz_mesh(in, FZ_V, FZ_T, m->pos, NULL, m->idx, &m->nv, &m->nt);
}

static void fz_trimesh_sound(const float *pos, size_t nv, const uint32_t *idx, size_t nt)
{
    size_t i;
    for (i = 0; i < 3 * nt; i++) fz_check(idx[i] < nv);
    fz_check(fz_all_finite_f(pos, 3 * nv));
}

/* ---- BVH ----------------------------------------------------------------------------------- */

static void fz_ray(fz_in *in, dm_ray *r)
{
    int k;
    for (k = 0; k < 3; k++) {
        r->org[k] = fz_f32(in);
        r->dir[k] = fz_f32(in);
    }
    r->tmin = (fz_u8(in) & 1) ? fz_f32(in) : 0.0f;
    r->tmax = (fz_u8(in) & 1) ? fz_f32(in) : INFINITY;
}

static void fz_hit_sound(const dm_ray *r, const dm_hit *h, size_t nt)
{
    const float e = 1e-4f;
    fz_check(h->triangle < nt);
    fz_check(isfinite(h->t) && h->u >= -e && h->v >= -e && h->u + h->v <= 1.0f + e);
    fz_check(h->t >= r->tmin && h->t <= r->tmax);
}

static void fz_bvh(fz_in *in, unsigned op, const dm_allocator *al, fz_cancel *cc)
{
    fz_tri m;
    dm_bvh_options o = dm_bvh_default_options();
    dm_bvh *b = NULL;
    dm_result r;
    dm_ray rays[4];
    dm_hit hits[4];
    unsigned char occ[4];
    unsigned f;
    int k;
    fz_decode(in, op, &m);
    f = fz_u8(in);
    o.quality = (int)(f & 1);
    o.bins = (int)(fz_u8(in) % 70) - 2;
    o.max_leaf_size = (int)(fz_u8(in) % 12) - 1;
    o.allocator = al;
    o.progress = (f & 2) ? fz_progress : NULL;
    o.progress_user = cc;
    r = dm_bvh_build(m.pos, m.nv, m.idx, m.nt, &o, &b);
    fz_check(fz_known(r));
    if (r != DM_OK) {
        fz_check(b == NULL);
        return;
    }
    {
        dm_bvh_info info;
        dm_bvh_get_info(b, &info);
        fz_check(info.triangle_count == m.nt && info.leaf_count >= 1 && info.node_count >= info.leaf_count);
    }
    if (f & 4) { /* refit to moved positions */
        size_t i;
        fz_tri moved = m;
        for (i = 0; i < 3 * m.nv; i++) moved.pos[i] += fz_f32(in);
        r = dm_bvh_refit(b, moved.pos, m.nv, m.idx, m.nt);
        fz_check(fz_known(r));
        if (r == DM_OK) m = moved;
    }
    for (k = 0; k < 4; k++) {
        dm_hit h, hl;
        int hit, oc, li;
        fz_ray(in, &rays[k]);
        hit = dm_bvh_intersect(b, &rays[k], &h);
        oc = dm_bvh_occluded(b, &rays[k]);
        if (hit) fz_hit_sound(&rays[k], &h, m.nt);
        else fz_check(h.triangle == DM_NO_HIT);
        fz_check(hit == oc); /* the same triangle test, any hit vs the nearest */
        li = dm_bvh_intersect_line(b, &rays[k], &hl);
        if (li) {
            fz_hit_sound(&rays[k], &hl, m.nt);
            if (hit) fz_check(fabsf(hl.t) <= fabsf(h.t)); /* the smallest |t| on the line */
        }
        hits[k] = h;
    }
    {
        dm_hit bh[4];
        size_t n = dm_bvh_intersect_batch(b, rays, 4, bh), no = dm_bvh_occluded_batch(b, rays, 4, occ), c = 0;
        for (k = 0; k < 4; k++) {
            fz_check(bh[k].triangle == hits[k].triangle && (bh[k].triangle == DM_NO_HIT || bh[k].t == hits[k].t));
            fz_check(occ[k] == (hits[k].triangle != DM_NO_HIT));
            c += hits[k].triangle != DM_NO_HIT;
        }
        fz_check(n == c && no == c);
    }
    for (k = 0; k < 2; k++) {
        float p[3], maxd;
        dm_closest cl;
        p[0] = fz_f32(in), p[1] = fz_f32(in), p[2] = fz_f32(in);
        maxd = (fz_u8(in) & 1) ? fz_f32(in) : INFINITY;
        if (dm_bvh_closest_point(b, p, maxd, &cl)) {
            fz_check(cl.triangle < m.nt && isfinite(cl.distance) && cl.distance <= maxd && fz_all_finite_f(cl.point, 3));
            fz_check(cl.u >= -1e-4f && cl.v >= -1e-4f && cl.u + cl.v <= 1.0f + 1e-4f);
        } else {
            fz_check(cl.triangle == DM_NO_HIT);
        }
    }
    dm_bvh_free(b);
}

/* ---- simplification, progressive mesh, weld ------------------------------------------------------- */

static void fz_simplify(fz_in *in, unsigned op, const dm_allocator *al, fz_cancel *cc)
{
    fz_tri m;
    dm_simplify_options o = dm_simplify_default_options();
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    dm_result r;
    uint8_t locked[FZ_V];
    float wpos[3 * FZ_V], gpos[3 * FZ_V];
    uint32_t widx[3 * FZ_T], gidx[3 * FZ_T], ids[FZ_V];
    size_t wnv = 0, i, vc, tc, level;
    unsigned f;
    fz_decode(in, op, &m);
    f = fz_u8(in);
    r = dm_weld(m.pos, m.nv, m.idx, m.nt, al, wpos, widx, &wnv); /* the weld, checked on its own */
    fz_check(fz_known(r));
    if (r == DM_OK) {
        fz_check(wnv <= m.nv);
        fz_trimesh_sound(wpos, wnv, widx, m.nt);
        for (i = 0; i < 3 * m.nt; i++) /* the same corners, bit for bit up to -0 = +0 */
            fz_check(wpos[3 * widx[i]] == m.pos[3 * m.idx[i]] && wpos[3 * widx[i] + 1] == m.pos[3 * m.idx[i] + 1] &&
                     wpos[3 * widx[i] + 2] == m.pos[3 * m.idx[i] + 2]);
    }
    { /* the orientation, checked on its own, on the mesh and on a copy with some triangles turned
         (chosen from op, no byte taken): each triangle keeps its corners' cycle or turns */
        int pass;
        for (pass = 0; pass < 2; pass++) {
            uint32_t src[3 * FZ_T];
            size_t turned = 0, n = 0;
            memcpy(src, m.idx, 3 * m.nt * sizeof(uint32_t));
            for (i = 0; pass && i < m.nt; i++)
                if ((((uint32_t)i * 2654435761u) >> 13 ^ op) & 1) {
                    uint32_t x = src[3 * i + 1];
                    src[3 * i + 1] = src[3 * i + 2];
                    src[3 * i + 2] = x;
                }
            memcpy(gidx, src, 3 * m.nt * sizeof(uint32_t));
            r = dm_orient(m.pos, m.nv, gidx, m.nt, al, &turned);
            fz_check(fz_known(r));
            for (i = 0; i < m.nt; i++) {
                const uint32_t *a = src + 3 * i, *g = gidx + 3 * i;
                int kept = a[0] == g[0] && a[1] == g[1] && a[2] == g[2], turn = a[0] == g[0] && a[1] == g[2] && a[2] == g[1];
                fz_check(kept || turn);
                n += !kept;
            }
            fz_check(r == DM_OK ? n == turned : n == 0 && turned == 0);
        }
    }
    o.target_triangles = fz_u8(in) % (m.nt + 1);
    o.target_error = (f & 1) ? (double)fz_f32(in) : 0.0;
    o.flags = (f >> 1) & 1;
    for (i = 0; i < m.nv; i++) locked[i] = (uint8_t)(fz_u8(in) % 8 == 0);
    o.locked = (f & 4) ? locked : NULL;
    o.max_collapses = fz_u8(in) % 16;
    o.min_quality = (f & 8) ? fz_f32(in) : 0.0f;
    o.allocator = al;
    o.progress = (f & 16) ? fz_progress : NULL;
    o.progress_user = cc;
    r = dm_simplify(m.pos, m.nv, m.idx, m.nt, &o, &pm, &rep);
    fz_check(fz_known(r));
    if (r != DM_OK) {
        fz_check(pm == NULL);
        return;
    }
    fz_check(rep.triangle_count <= rep.input_triangles && rep.input_triangles + rep.dropped_triangles == m.nt);
    fz_check(dm_pm_split_count(pm) == rep.collapse_count && dm_pm_level(pm) == 0);
    dm_pm_counts(pm, &vc, &tc);
    fz_check(tc == rep.triangle_count && vc <= m.nv);
    dm_pm_get_mesh(pm, gpos, gidx, ids);
    fz_trimesh_sound(gpos, vc, gidx, tc);
    for (i = 0; i < vc; i++) {
        const uint32_t *list;
        size_t n = dm_pm_merged_vertices(pm, ids[i], &list);
        fz_check(ids[i] < m.nv && n >= 1);
    }
    for (level = 0; level < 3; level++) { /* up and down the levels, then the finest */
        size_t to = fz_u8(in) % (dm_pm_split_count(pm) + 2);
        dm_vsplit vs;
        dm_pm_set_level(pm, to);
        fz_check(dm_pm_level(pm) == (to < dm_pm_split_count(pm) ? to : dm_pm_split_count(pm)));
        if (dm_pm_get_vsplit(pm, dm_pm_level(pm), &vs)) fz_check(vs.keep < m.nv && vs.remove < m.nv && vs.keep != vs.remove);
    }
    dm_pm_set_level(pm, dm_pm_split_count(pm));
    dm_pm_counts(pm, &vc, &tc);
    fz_check(tc == rep.input_triangles);
    dm_pm_get_mesh(pm, gpos, gidx, ids);
    for (i = 0; i < vc; i++) /* the finest level is the input */
        fz_check(memcmp(gpos + 3 * i, m.pos + 3 * ids[i], 3 * sizeof(float)) == 0);
    dm_pm_free(pm);
}

/* ---- shell-constrained simplification ----------------------------------------------------------- */

static void fz_shell(fz_in *in, unsigned op, const dm_allocator *al, fz_cancel *cc)
{
    fz_tri m;
    dm_shell_options so = dm_shell_default_options();
    dm_shell *sh = NULL;
    dm_result r;
    unsigned f;
    fz_decode(in, op, &m);
    f = fz_u8(in);
    so.thickness = (f & 1) ? fz_f32(in) : 0.0f;
    so.steps = (int)(fz_u8(in) % 10) - 1;
    so.overlap_samples = (int)(fz_u8(in) % 9) - 1;
    so.allocator = al;
    so.progress = (f & 2) ? fz_progress : NULL;
    so.progress_user = cc;
    r = dm_shell_grow(m.pos, m.nv, m.idx, m.nt, &so, &sh);
    fz_check(fz_known(r));
    if (r != DM_OK) {
        fz_check(sh == NULL);
        return;
    }
    {
        size_t i;
        fz_check(sh->vertex_count == m.nv && fz_all_finite_f(sh->positions, 3 * m.nv));
        for (i = 0; i < m.nv; i++) fz_check(sh->offset[i] >= 0.0f && sh->offset[i] <= sh->thickness * 1.0001f);
    }
    {
        dm_simplify_options o = dm_simplify_default_options();
        dm_simplify_report rep;
        dm_pm *pm = NULL;
        o.target_triangles = 4 + fz_u8(in) % 16;
        o.constraint = dm_shell_constraint;
        o.on_collapse = dm_shell_collapsed;
        o.relax = (f & 4) ? dm_shell_relax : NULL;
        o.constraint_user = sh;
        o.allocator = al;
        r = dm_simplify(m.pos, m.nv, m.idx, m.nt, &o, &pm, &rep);
        fz_check(fz_known(r));
        if (r == DM_OK) {
            size_t vc, tc, n;
            float gpos[3 * FZ_V];
            uint32_t gidx[3 * FZ_T], ids[FZ_V];
            uint8_t flags[FZ_T];
            dm_pm_counts(pm, &vc, &tc);
            dm_pm_get_mesh(pm, gpos, gidx, ids);
            fz_trimesh_sound(gpos, vc, gidx, tc);
            n = dm_shell_fallback_triangles(sh, gidx, tc, ids, flags);
            fz_check(n <= tc);
            dm_pm_free(pm);
        }
    }
    dm_shell_free(sh);
}

/* ---- parameterization, bake, reconstruction, coverage, distance -------------------------------- */

static void fz_map_pipeline(fz_in *in, unsigned op, const dm_allocator *al, fz_cancel *cc)
{
    fz_tri base, orig;
    dm_param_options po = dm_param_default_options();
    dm_param *pa = NULL;
    dm_dispmap *map = NULL;
    dm_trimesh *tm = NULL;
    dm_result r;
    float weights[FZ_T];
    unsigned f;
    size_t i, n;
    fz_decode(in, op, &base);
    orig = base; /* the original: the base moved a little along its vertices */
    for (i = 0; i < 3 * orig.nv; i++) orig.pos[i] += 0.0625f * fz_f32(in);
    f = fz_u8(in);
    if (f & 1) {
        dm_coverage_options co = dm_coverage_default_options();
        co.allocator = al;
        co.floor = (f & 2) ? fz_f32(in) : 0.0f;
        r = dm_coverage_weights(base.pos, base.nv, base.idx, base.nt, orig.pos, orig.nv, orig.idx, orig.nt, &co, weights);
        fz_check(fz_known(r));
        if (r == DM_OK)
            for (i = 0; i < base.nt; i++) fz_check(isfinite(weights[i]) && weights[i] >= 0.0f);
        po.triangle_weight = r == DM_OK ? weights : NULL;
    }
    po.width = 8 + (int)(fz_u8(in) % 41);
    po.height = (f & 4) ? 8 + (int)(fz_u8(in) % 41) : po.width;
    po.gutter = (int)(fz_u8(in) % 6) - 1;
    po.max_chart_triangles = (int)(fz_u8(in) % 40) - 1;
    po.max_chart_angle = (f & 8) ? fz_f32(in) : 0.0f;
    po.stretch_iterations = (int)(fz_u8(in) % 5) - 1;
    po.allocator = al;
    po.progress = (f & 16) ? fz_progress : NULL;
    po.progress_user = cc;
    r = dm_parameterize(base.pos, base.nv, base.idx, base.nt, &po, &pa);
    fz_check(fz_known(r));
    if (r != DM_OK) {
        fz_check(pa == NULL);
        return;
    }
    n = (size_t)pa->width * (size_t)pa->height;
    fz_check(pa->triangle_count == base.nt && pa->chart_count >= 1);
    for (i = 0; i < 6 * base.nt; i++) fz_check(pa->uv[i] >= 0.0f && pa->uv[i] <= 1.0f);
    for (i = 0; i < base.nt; i++) fz_check(pa->chart[i] < pa->chart_count);
    for (i = 0; i < 3 * base.nt; i++) fz_check(pa->twin[i] < base.nt || pa->twin[i] == DM_NO_HIT);
    for (i = 0; i < n; i++) {
        int k;
        fz_check(pa->texel_triangle[i] < base.nt || pa->texel_triangle[i] == DM_NO_HIT);
        for (k = 0; k < 4; k++) fz_check(pa->nbr[4 * i + k] < n || pa->nbr[4 * i + k] == UINT32_MAX);
    }
    {
        dm_bake_options bo = dm_bake_default_options();
        uint8_t both[FZ_T];
        for (i = 0; i < base.nt; i++) both[i] = (uint8_t)(fz_u8(in) & 1);
        bo.max_distance = (f & 32) ? fz_f32(in) : 0.0f;
        bo.inward = (int)(fz_u8(in) & 1);
        bo.both_ways = (f & 64) ? both : NULL;
        bo.allocator = al;
        bo.progress = (f & 128) ? fz_progress : NULL;
        bo.progress_user = cc;
        r = dm_bake(pa, base.pos, base.nv, base.idx, base.nt, orig.pos, orig.nv, orig.idx, orig.nt, &bo, &map);
        fz_check(fz_known(r));
    }
    if (r == DM_OK) {
        dm_reconstruct_options ro = dm_reconstruct_default_options();
        fz_check(map->width == pa->width && map->height == pa->height && map->hit_count + map->miss_count <= n);
        for (i = 0; i < n; i++) {
            fz_check(map->status[i] <= DM_TEXEL_BORDER && map->valid[i] == (map->status[i] == DM_TEXEL_HIT));
            if (map->valid[i]) fz_check(isfinite(map->disp[i]) && fz_all_finite_f(map->normal + 3 * i, 3));
        }
        ro.density = (fz_u8(in) & 1) ? fz_f32(in) : 0.0f;
        if (ro.density > 2.0f && ro.density <= 16.0f) ro.density = 2.0f; /* 16 makes 100k+ vertices: too slow here */
        ro.allocator = al;
        r = dm_reconstruct(map, pa, base.pos, base.nv, base.idx, base.nt, &ro, &tm);
        fz_check(fz_known(r));
        if (r == DM_OK) {
            fz_trimesh_sound(tm->positions, tm->vertex_count, tm->indices, tm->triangle_count);
            fz_check(fz_all_finite_f(tm->normals, 3 * tm->vertex_count) && tm->vertex_count >= base.nv);
            for (i = 0; i < tm->triangle_count; i++) fz_check(tm->face_base[i] < base.nt);
            if (fz_u8(in) & 1) {
                dm_distance_options dop = dm_distance_default_options();
                dm_distance_report dr;
                dop.samples_per_side = 1 + fz_u8(in) % 64; /* 0 would be the default 200000: too slow here */
                dop.allocator = al;
                r = dm_surface_distance(tm->positions, tm->vertex_count, tm->indices, tm->triangle_count, orig.pos,
                                        orig.nv, orig.idx, orig.nt, &dop, &dr);
                fz_check(fz_known(r));
                if (r == DM_OK) fz_check(isfinite(dr.rms) && isfinite(dr.max) && dr.rms <= dr.max + 1e-9 && dr.rms >= 0.0);
            }
            dm_trimesh_free(tm);
        }
        dm_dispmap_free(map);
    }
    dm_param_free(pa);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fz_heap h;
    fz_cancel c;
    dm_allocator a;
    unsigned op = fz_begin(&in, data, size, &h, &c);
    FZ_HEAP_ALLOCATOR(a, &h);
    switch (op & 3) {
    case 0: fz_bvh(&in, op, &a, &c); break;
    case 1: fz_simplify(&in, op, &a, &c); break;
    case 2: fz_shell(&in, op, &a, &c); break;
    default: fz_map_pipeline(&in, op, &a, &c); break;
    }
    fz_check(h.live == 0 && h.bytes == 0); /* nothing held after any result */
    return 0;
}
