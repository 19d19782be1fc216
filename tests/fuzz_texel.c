/* fuzz_texel.c - fuzz target for texel.h's entry points that take user data: grass descriptions
   and blades, dense voxels, sampling, ageing (model options, wd), splatting, LOD pyramids and their
   queries, TVTs with mingling, shadows and marching, mesh shells with their maps, wd maps.
   libFuzzer: clang -g -O1 -I. -Itests -fsanitize=fuzzer,address,undefined tests/fuzz_texel.c -o fuzz_texel -lm
   plain:     gcc -std=c99 -g -O1 -I. -Itests tests/fuzz_texel.c tests/fuzz_main.c -o fuzz_texel -lm
              && ./fuzz_texel tests/fuzz/corpus/texel
   Byte 0: the entry point (bits 0-1), raw numbers (bit 7: 4-byte floats of any bits, else
   (b - 128) / 16); byte 1: the allocation to fail and the progress call that cancels (nibbles, 0 =
   none). Textures are 8^3 or 16^3, blades at most 12, meshes 12 vertices, so one run is cheap.
   Every call returns TVT_OK with a sound result (finite voxels, density >= 0, colour and
   specular in [0, 1], maps that round-trip) or a named code with nothing held; a broken rule
   calls abort(). */
#define FZ_HELPERS_ONLY
#include "fuzz_deform.c" /* the byte reader and failing allocator */
#define TVT_IMPLEMENTATION
#include "texel.h"

static int fz_known(tvt_result r) { return strcmp(tvt_result_string(r), "TVT_ERR_?") != 0; }

static void fz_voxel_sound(const tvt_voxel *v)
{
    fz_check(isfinite(v->density) && v->density >= 0.0f);
    fz_check(fz_all_finite_f(v->normal, 3) && fz_all_finite_f(v->tangent, 3));
    fz_check(v->color[0] >= 0.0f && v->color[0] <= 1.0f && v->color[1] >= 0.0f && v->color[1] <= 1.0f &&
             v->color[2] >= 0.0f && v->color[2] <= 1.0f);
    fz_check(v->specular >= 0.0f && v->specular <= 1.0f);
}

/* every voxel decoded, and the total density equals the sum of the decoded ones (to rounding) */
static void fz_texel_sound(const tvt_texel *t)
{
    long x, y, z;
    double sum = 0.0, total;
    tvt_voxel v;
    fz_check((t->res == 8 || t->res == 16 || t->res == 32) && (t->bits == 8 || t->bits == 16));
    for (z = 0; z < t->res; z++)
        for (y = 0; y < t->res; y++)
            for (x = 0; x < t->res; x++) {
                tvt_texel_voxel(t, x, y, z, &v);
                fz_voxel_sound(&v);
                sum += v.density;
            }
    total = tvt_texel_total_density(t);
    fz_check(isfinite(total) && fabs(total - sum) <= 1e-4 * (sum + 1.0));
    tvt_texel_voxel(t, -3, 1000, -1, &v); /* below the ground: empty */
    fz_check(v.density == 0.0f);
}

static void fz_desc(fz_in *in, tvt_grass_desc *d, const tvt_allocator *al, fz_cancel *cc)
{
    unsigned f = fz_u8(in);
    *d = tvt_grass_default_desc();
    d->res = (f & 1) ? 16 : 8;
    if (f & 2) { /* -4..35 but 0 (the default, 64: too slow here): 8, 16, 32 valid, the rest not */
        d->res = (int)(fz_u8(in) % 40) - 4;
        if (d->res == 0) d->res = 7;
    }
    d->blade_count = 1 + fz_u8(in) % 12;
    d->seed = fz_u8(in);
    if (f & 4) {
        d->height_min = fz_f32(in);
        d->height_max = fz_f32(in);
        d->radius_min = fz_f32(in);
        d->radius_max = fz_f32(in);
        d->lean_min_deg = fz_f32(in);
        d->lean_max_deg = fz_f32(in);
        d->specular = fz_f32(in);
    }
    d->supersample = (int)(fz_u8(in) % 4); /* 0 = default 3 */
    d->bits = (f & 8) ? 16 : 8;
    if (f & 16) d->bits = (int)fz_u8(in) % 20;
    d->allocator = al;
    d->progress = (f & 32) ? fz_progress : NULL;
    d->progress_user = cc;
}

static void fz_model(fz_in *in, tvt_model_options *m, fz_cancel *cc)
{
    unsigned f = fz_u8(in);
    *m = tvt_model_default_options();
    m->water_curve = (int)(f & 3); /* 3: invalid */
    if (f & 4) {
        m->k_vein = fz_f32(in);
        m->k_mesophyll = fz_f32(in);
        m->vein_stiffness = fz_f32(in);
        m->stiffening = fz_f32(in);
        m->area_ratio = fz_f32(in);
        m->droop_max_deg = fz_f32(in);
        m->droop_exponent = fz_f32(in);
        m->droop_length = fz_f32(in);
        m->merge_threshold = fz_f32(in);
        m->colour_jitter = fz_f32(in);
    }
    m->no_merge = (int)((f >> 3) & 1);
    m->progress = (f & 16) ? fz_progress : NULL;
    m->progress_user = cc;
}

/* LOD pyramid of t and its queries at points from the bytes */
static void fz_lod(fz_in *in, const tvt_texel *t, const tvt_allocator *al, fz_cancel *cc)
{
    tvt_lod_options o = tvt_lod_default_options();
    tvt_lod l;
    tvt_result r;
    unsigned f = fz_u8(in);
    int k;
    o.levels = (int)(f & 3);
    o.calibration_rays = (f & 16) ? (int)fz_u8(in) : 16 + (int)(fz_u8(in) % 16); /* below 16: refused */
    o.extinction = (f & 4) ? fz_f32(in) : 0.0f;
    o.allocator = al;
    o.progress = (f & 8) ? fz_progress : NULL;
    o.progress_user = cc;
    r = tvt_build_lod(t, &o, &l);
    fz_check(fz_known(r));
    if (r != TVT_OK) return;
    fz_check(l.levels >= 1 && l.levels <= TVT_MAX_LEVELS);
    for (k = 0; k < 4; k++) {
        float p[3], dir[3], len, d, tau;
        int level = (int)(fz_u8(in) % (unsigned)(l.levels + 1)) - (k == 3);
        tvt_voxel v;
        p[0] = fz_f32(in), p[1] = fz_f32(in), p[2] = fz_f32(in);
        dir[0] = fz_f32(in), dir[1] = fz_f32(in), dir[2] = fz_f32(in);
        len = fz_f32(in);
        if (!(fz_all_finite_f(p, 3) && fabsf(p[0]) < 1e6f && fabsf(p[1]) < 1e6f && fabsf(p[2]) < 1e6f)) continue;
        if (level < 0 || level >= l.levels) level = 0;
        d = tvt_lod_density(&l, level, p);
        fz_check(isfinite(d) && d >= 0.0f);
        tvt_lod_voxel(&l, level, p, &v);
        fz_voxel_sound(&v);
        {
            float n = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            if (!(n > 0.1f && n < 10.0f) || !(len >= 0.0f && len < 64.0f)) continue;
            dir[0] /= n, dir[1] /= n, dir[2] /= n;
        }
        tau = tvt_optical_depth(&l, level, p, dir, len);
        fz_check(isfinite(tau) && tau >= 0.0f);
    }
    k = tvt_lod_level_for(&l, fz_f32(in));
    fz_check(k >= 0 && k < l.levels);
    tvt_lod_free(&l);
}

/* grass -> points -> aged -> splatted, then the LOD and (sometimes) a TVT with its renderer calls */
static void fz_grass(fz_in *in, const tvt_allocator *al, fz_cancel *cc)
{
    tvt_grass_desc d;
    tvt_texel t, s;
    tvt_points pts;
    tvt_sample_options so = tvt_sample_default_options();
    tvt_model_options mo;
    tvt_splat_options sp = tvt_splat_default_options();
    tvt_result r;
    unsigned f;
    float wd;
    fz_desc(in, &d, al, cc);
    r = tvt_build_grass(&d, &t);
    fz_check(fz_known(r));
    if (r != TVT_OK) return;
    fz_texel_sound(&t);
    f = fz_u8(in);
    so.proportion = (f & 1) ? fz_f32(in) : 1.0f + (float)(fz_u8(in) % 4);
    if (!(so.proportion <= 8.0f)) so.proportion = 8.0f + (so.proportion != so.proportion ? 0.0f : 1.0f); /* keep runs cheap */
    so.seed = fz_u8(in);
    so.allocator = al;
    so.progress = (f & 2) ? fz_progress : NULL;
    so.progress_user = cc;
    r = tvt_sample(&t, &so, &pts);
    fz_check(fz_known(r));
    if (r == TVT_OK) {
        double before = 0.0, after;
        size_t i;
        for (i = 0; i < pts.count; i++) before += pts.p[i].mass;
        fz_model(in, &mo, cc);
        wd = (f & 4) ? fz_f32(in) : (float)(fz_u8(in) % 9) / 8.0f;
        r = tvt_age(&pts, wd, &mo);
        fz_check(fz_known(r));
        if (r == TVT_OK) {
            for (i = 0, after = 0.0; i < pts.count; i++) {
                fz_check(fz_all_finite_f(pts.p[i].pos, 3) && isfinite(pts.p[i].mass) && pts.p[i].mass >= 0.0f);
                after += pts.p[i].mass;
            }
            fz_check(fabs(after - before) <= 1e-3 * (before + 1.0)); /* merging keeps the mass */
        }
        sp.bits = (f & 8) ? 16 : 8;
        sp.sigma = (f & 16) ? fz_f32(in) : 0.0f;
        sp.allocator = al;
        sp.progress = (f & 32) ? fz_progress : NULL;
        sp.progress_user = cc;
        r = tvt_splat(&pts, &sp, &s);
        fz_check(fz_known(r));
        if (r == TVT_OK) {
            fz_texel_sound(&s);
            tvt_texel_free(&s);
        }
        tvt_points_free(&pts);
    }
    if (f & 64) fz_lod(in, &t, al, cc);
    if (f & 128) { /* a two-frame TVT, a mingle of two, a shadow, a march */
        tvt_tvt_options to = tvt_tvt_default_options();
        tvt_tvt v;
        tvt_lod_options lo;
        memset(&lo, 0, sizeof lo); /* zero = defaults for the frames' resolution */
        lo.calibration_rays = 16; /* the least allowed */
        to.frames = 2 + (int)(fz_u8(in) % 2);
        to.steps_per_frame = 1;
        to.lod = &lo;
        to.allocator = al;
        r = tvt_build_tvt(&t, &to, &v);
        fz_check(fz_known(r));
        if (r == TVT_OK) {
            tvt_ageing_fn fn[2];
            tvt_tvt two[2];
            tvt_texel m;
            tvt_shadow sh;
            tvt_shade_desc sd = tvt_shade_default_desc();
            float light[3], o3[3], dir[3], rgb[3], tr, n;
            fn[0].delay = fz_f32(in);
            fn[0].rate = fz_f32(in);
            fn[1].delay = 0.0f;
            fn[1].rate = 0.0f;
            two[0] = v;
            two[1] = v;
            wd = fz_f32(in);
            r = tvt_mingle(two, fn, 2, wd, 8, al, &m);
            fz_check(fz_known(r));
            if (r == TVT_OK) {
                fz_texel_sound(&m);
                tvt_texel_free(&m);
            }
            light[0] = fz_f32(in), light[1] = fz_f32(in), light[2] = fz_f32(in);
            r = tvt_build_shadow(&v, -1, light, al, &sh);
            fz_check(fz_known(r));
            if (r == TVT_OK) sd.shadow = &sh;
            o3[0] = fz_f32(in), o3[1] = fz_f32(in), o3[2] = fz_f32(in);
            dir[0] = fz_f32(in), dir[1] = fz_f32(in), dir[2] = fz_f32(in);
            n = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
            if (fz_all_finite_f(o3, 3) && fabsf(o3[0]) + fabsf(o3[1]) + fabsf(o3[2]) < 1e5f && n > 0.1f && n < 10.0f &&
                isfinite(wd)) {
                dir[0] /= n, dir[1] /= n, dir[2] /= n;
                tvt_march(&v, wd, 0, &sd, o3, dir, 24.0f, rgb, &tr);
                fz_check(fz_all_finite_f(rgb, 3) && tr >= 0.0f && tr <= 1.0f);
            }
            if (r == TVT_OK) tvt_shadow_free(&sh);
            tvt_tvt_free(&v);
        }
    }
    tvt_texel_free(&t);
}

/* blades straight from the bytes (any values), voxelised */
static void fz_blades(fz_in *in, const tvt_allocator *al, fz_cancel *cc)
{
    tvt_blade b[12];
    tvt_grass_desc d;
    tvt_texel t;
    tvt_result r;
    size_t n, i;
    fz_desc(in, &d, al, cc);
    n = fz_u8(in) % 13;
    for (i = 0; i < n; i++) {
        int k;
        for (k = 0; k < 3; k++) {
            b[i].root[k] = fz_f32(in);
            b[i].axis[k] = fz_f32(in);
            b[i].bend[k] = fz_f32(in);
        }
        b[i].height = fz_f32(in);
        b[i].radius = fz_f32(in);
        b[i].brightness = fz_f32(in);
        b[i].wd_delay = fz_f32(in);
    }
    r = tvt_build_texel(n ? b : NULL, n, &d, &t);
    fz_check(fz_known(r));
    if (r != TVT_OK) return;
    fz_texel_sound(&t);
    tvt_texel_free(&t);
}

/* dense voxels of any values */
static void fz_voxels(fz_in *in, const tvt_allocator *al)
{
    static tvt_voxel vox[8 * 8 * 8];
    tvt_texel t;
    tvt_result r;
    size_t i, n = 8 * 8 * 8;
    unsigned f = fz_u8(in);
    int res = (f & 1) ? (int)fz_u8(in) : 8, bits = (f & 2) ? 16 : 8;
    memset(vox, 0, sizeof vox);
    for (i = 0; i < n && in->n > 0; i++) { /* what the bytes give, the rest empty */
        size_t v = (i * 37u) % n;
        int k;
        vox[v].density = fz_f32(in);
        for (k = 0; k < 3; k++) {
            vox[v].normal[k] = fz_f32(in);
            vox[v].tangent[k] = fz_f32(in);
            vox[v].color[k] = fz_f32(in);
        }
        vox[v].specular = fz_f32(in);
    }
    if (res != 8) res = res == 4 ? 4 : 8 + (res & 1); /* 9: invalid; 4: too small */
    r = tvt_texel_from_voxels(res, vox, (f & 4) ? (int)fz_u8(in) : bits, al, &t);
    fz_check(fz_known(r));
    if (r != TVT_OK) return;
    fz_texel_sound(&t);
    tvt_texel_free(&t);
}

/* a mesh shell, its maps, a wd map, the model's scalars */
static void fz_shell(fz_in *in, const tvt_allocator *al, fz_cancel *cc)
{
    float pos[3 * 12], nrm[3 * 12], uv[2 * 12], wdv[9];
    uint32_t idx[3 * 16];
    size_t nv, nt, i;
    tvt_shell_desc d;
    tvt_shell s;
    tvt_result r;
    tvt_wd_map m;
    tvt_model_options mo;
    tvt_model_state ms;
    float rgb[3], w;
    fz_mesh(in, 12, 16, pos, NULL, idx, &nv, &nt);
    for (i = 0; i < 3 * nv; i++) nrm[i] = fz_f32(in);
    for (i = 0; i < 2 * nv; i++) uv[i] = fz_f32(in);
    memset(&d, 0, sizeof d);
    d.positions = pos;
    d.normals = nrm;
    d.uvs = uv;
    d.vertex_count = nv;
    d.indices = idx;
    d.triangle_count = nt;
    d.height = fz_f32(in);
    d.allow_folded = (int)(fz_u8(in) & 1);
    d.allocator = al;
    r = tvt_build_shell(&d, &s);
    fz_check(fz_known(r));
    if (r == TVT_OK) {
        int k;
        fz_check(s.prism_count == nt && s.folded <= nt);
        for (k = 0; k < 4; k++) {
            size_t prism = fz_u8(in) % (nt + 1);
            float p[3], uvw[3], q[3];
            int in_map, in_unmap;
            if (fz_u8(in) & 1 || prism >= nt) {
                p[0] = fz_f32(in), p[1] = fz_f32(in), p[2] = fz_f32(in);
            } else { /* a point of the prism: barycentric b over the corners raised by w * height */
                float b[3], w = (float)(fz_u8(in) % 17) / 16.0f, sum;
                int c, q;
                b[0] = 1.0f + (float)(fz_u8(in) % 8), b[1] = 1.0f + (float)(fz_u8(in) % 8), b[2] = 1.0f + (float)(fz_u8(in) % 8);
                sum = b[0] + b[1] + b[2];
                p[0] = p[1] = p[2] = 0.0f;
                for (c = 0; c < 3; c++) {
                    const float *v = pos + 3 * idx[3 * prism + c], *nn = nrm + 3 * idx[3 * prism + c];
                    float len = sqrtf(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
                    for (q = 0; q < 3; q++) p[q] += b[c] / sum * (v[q] + w * d.height * nn[q] / len);
                }
            }
            in_map = tvt_shell_map(&s, prism, p, uvw);
            fz_check(in_map >= -1 && in_map <= 1 && (in_map == -1) == (prism >= nt));
            if (in_map != 1 || s.folded) continue;
            in_unmap = tvt_shell_unmap(&s, prism, uvw, q);
            fz_check(in_unmap >= 0);
            fz_check(fz_all_finite_f(uvw, 3) && fz_all_finite_f(q, 3));
            { /* inside an unfolded prism the maps round-trip, to float rounding of the extent */
                float e = fabsf(q[0] - p[0]) + fabsf(q[1] - p[1]) + fabsf(q[2] - p[2]), ext = fabsf(d.height);
                size_t j;
                for (j = 0; j < 3 * nv; j++) ext = fmaxf(ext, fabsf(pos[j]));
                fz_check(e <= 1e-3f * (ext + 1e-30f));
            }
        }
        tvt_shell_free(&s);
    }
    for (i = 0; i < 9; i++) wdv[i] = fz_f32(in);
    m.wd = wdv;
    m.width = (int)(fz_u8(in) % 4);
    m.height = (int)(fz_u8(in) % 4);
    if (m.width * m.height > 9) m.width = m.height = 3;
    m.origin[0] = (int)fz_u8(in) - 128;
    m.origin[1] = (int)fz_u8(in) - 128;
    m.wrap = (int)(fz_u8(in) & 1);
    w = tvt_tile_wd(&m, (long)fz_u8(in) - 128, (long)fz_u8(in) - 128);
    fz_check(w >= 0.0f && w <= 1.0f);
    fz_model(in, &mo, cc);
    w = fz_f32(in);
    r = tvt_model_eval(&mo, w, &ms);
    fz_check(fz_known(r));
    if (r == TVT_OK) {
        fz_check(isfinite(ms.water) && isfinite(ms.droop) && isfinite(ms.chlorophyll));
        fz_check(ms.color[0] >= 0.0f && ms.color[0] <= 1.0f && ms.color[1] >= 0.0f && ms.color[1] <= 1.0f &&
                 ms.color[2] >= 0.0f && ms.color[2] <= 1.0f);
    }
    tvt_pigment_color(fz_f32(in), fz_f32(in), rgb);
    w = tvt_wd_from_time(fz_f32(in), fz_f32(in));
    fz_check(w >= 0.0f && w <= 1.0f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fz_heap h;
    fz_cancel c;
    tvt_allocator a;
    unsigned op = fz_begin(&in, data, size, &h, &c);
    FZ_HEAP_ALLOCATOR(a, &h);
    switch (op & 3) {
    case 0: fz_grass(&in, &a, &c); break;
    case 1: fz_blades(&in, &a, &c); break;
    case 2: fz_voxels(&in, &a); break;
    default: fz_shell(&in, &a, &c); break;
    }
    fz_check(h.live == 0 && h.bytes == 0); /* nothing held after any result */
    return 0;
}
