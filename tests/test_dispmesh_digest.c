/* test_dispmesh_digest.c - the bits of paper 000's pipeline on fixed generated inputs, as FNV-1a
   64-bit digests: dm_simplify without and with dm_shell_constraint, dm_parameterize, dm_bake and
   dm_reconstruct, on a bumpy sphere and a bumpy torus.
   A change that is meant to keep the output (a restructuring, a speed-up) keeps every digest; a
   change of behaviour updates the table below in the same commit and says why. Each digest is
   printed, so a changed one can be read from the log. The inputs are small enough for the
   sanitizer build (which must give the same bits: no digest depends on the optimisation level).
   Welding: an unwelded copy of each mesh (every triangle its own three vertices) is refused by
   dm_simplify (DM_ERR_NOT_WELDED, nothing leaked), and dm_weld turns it into the mesh renumbered in
   first-use order, bit for bit, so the whole pipeline gives the same digests on both. */
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#include "test.h"
#include "testmesh.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct digest { uint64_t h; } digest;
static void fnv(digest *d, const void *data, size_t n)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < n; i++) d->h = (d->h ^ p[i]) * 0x100000001b3ull;
}
static digest fnv_start(void) { digest d; d.h = 0xcbf29ce484222325ull; return d; }

/* the recorded digests: one line per stage and mesh */
typedef struct expected { const char *name; uint64_t h; } expected;
static const expected table[] = {
    {"sphere simplify", 0xd29f81dab6e9d82cull},
    {"sphere simplify shell", 0xdac7f0eb9933fc4full},
    {"sphere parameterize", 0x6f87ae37c32d5792ull},
    {"sphere bake", 0x05c5cfa1d298d350ull},
    {"sphere reconstruct", 0x0e6bd84495bcf8feull},
    {"torus simplify", 0xab7b78e3a557c32cull},
    {"torus simplify shell", 0xc6ec232a9782a890ull},
    {"torus parameterize", 0x8f1a778e3feb883dull},
    {"torus bake", 0x15ad6076342c371aull},
    {"torus reconstruct", 0x8ae7e049b362f4caull},
    {"thin torus simplify", 0xcd39fba057e9cf67ull},
    {"thin torus simplify shell", 0x2ef8a356b616dfc8ull},
    {"thin torus parameterize", 0x75bbc14a58cf0286ull},
    {"thin torus bake", 0xe072a69dd65b89bcull},
    {"thin torus reconstruct", 0xe7dd65e075aca8c1ull},
};

#define STAGES 5
static void check_digest(const char *name, digest d)
{
    size_t i;
    printf("digest %-24s 0x%016llx\n", name, (unsigned long long)d.h);
    for (i = 0; i < sizeof table / sizeof table[0]; i++)
        if (strcmp(table[i].name, name) == 0) {
            T_CHECK_MSG(table[i].h == d.h, "%s: digest 0x%016llx, recorded 0x%016llx", name,
                        (unsigned long long)d.h, (unsigned long long)table[i].h);
            return;
        }
    T_CHECK_MSG(0, "%s: no recorded digest", name);
}

/* the base after dm_simplify (all its levels' records are covered by the base and the count of
   splits: a change in any collapse changes the base) */
static int simplify(const mesh *m, dm_shell *sh, size_t target, float **bp, size_t *bnv, uint32_t **bi,
                    size_t *bnt, digest *d)
{
    dm_simplify_options o = dm_simplify_default_options(); /* the explicit defaults give the zero ones' bits */
    dm_simplify_report rep;
    dm_pm *pm = NULL;
    size_t splits;
    o.target_triangles = target;
    if (sh) {
        o.constraint = dm_shell_constraint;
        o.on_collapse = dm_shell_collapsed;
        o.constraint_user = sh;
    }
    if (!T_CHECK(dm_simplify(m->p, m->nv, m->t, m->nt, &o, &pm, &rep) == DM_OK)) return 0;
    dm_pm_counts(pm, bnv, bnt);
    *bp = (float *)malloc(3 * *bnv * sizeof(float) + 1);
    *bi = (uint32_t *)malloc(3 * *bnt * sizeof(uint32_t) + 1);
    dm_pm_get_mesh(pm, *bp, *bi, NULL);
    splits = dm_pm_split_count(pm);
    *d = fnv_start();
    fnv(d, *bp, 3 * *bnv * sizeof(float));
    fnv(d, *bi, 3 * *bnt * sizeof(uint32_t));
    fnv(d, &splits, sizeof splits);
    dm_pm_free(pm);
    return 1;
}

/* the five stages' digests into out (0 where a stage failed); checked against the table when
   check is set */
static void pipeline(const char *what, const mesh *m, size_t target, int res, int check, uint64_t out[STAGES])
{
    char name[64];
    float *bp = NULL, *up = NULL;
    uint32_t *bi = NULL, *ui = NULL;
    size_t bnv = 0, bnt = 0, unv = 0, unt = 0, n;
    dm_shell *sh = NULL;
    dm_param *param = NULL;
    dm_dispmap *map = NULL;
    dm_trimesh *dense = NULL;
    dm_param_options po;
    dm_bake_options bo;
    digest d;
    memset(out, 0, STAGES * sizeof out[0]);
#define RECORD(stage, label) do { snprintf(name, sizeof name, "%s " label, what); out[stage] = d.h; \
                                  if (check) check_digest(name, d); } while (0)
    if (simplify(m, NULL, target, &up, &unv, &ui, &unt, &d)) RECORD(0, "simplify");
    {
        dm_shell_options so = dm_shell_default_options();
        if (!T_CHECK(dm_shell_grow(m->p, m->nv, m->t, m->nt, &so, &sh) == DM_OK)) goto done;
    }
    if (!simplify(m, sh, target, &bp, &bnv, &bi, &bnt, &d)) goto done;
    RECORD(1, "simplify shell");
    po = dm_param_default_options();
    po.width = po.height = res;
    if (!T_CHECK(dm_parameterize(bp, bnv, bi, bnt, &po, &param) == DM_OK)) goto done;
    n = (size_t)res * (size_t)res;
    d = fnv_start();
    fnv(&d, param->uv, 6 * bnt * sizeof(float));
    fnv(&d, param->chart, bnt * sizeof(uint32_t));
    fnv(&d, param->twin, 3 * bnt * sizeof(uint32_t));
    fnv(&d, param->texel_triangle, n * sizeof(uint32_t));
    fnv(&d, param->texel_bary, 2 * n * sizeof(float));
    fnv(&d, param->nbr, 4 * n * sizeof(uint32_t));
    fnv(&d, param->nbr_rot, 4 * n);
    RECORD(2, "parameterize");
    bo = dm_bake_default_options();
    bo.inward = 1;
    if (!T_CHECK(dm_bake(param, bp, bnv, bi, bnt, m->p, m->nv, m->t, m->nt, &bo, &map) == DM_OK)) goto done;
    d = fnv_start();
    fnv(&d, map->pos, 3 * n * sizeof(float));
    fnv(&d, map->nrm, 3 * n * sizeof(float));
    fnv(&d, map->disp, n * sizeof(float));
    fnv(&d, map->normal, 3 * n * sizeof(float));
    fnv(&d, map->area, n * sizeof(float));
    fnv(&d, map->valid, n);
    fnv(&d, map->status, n);
    RECORD(3, "bake");
    if (!T_CHECK(dm_reconstruct(map, param, bp, bnv, bi, bnt, NULL, &dense) == DM_OK)) goto done;
    d = fnv_start();
    fnv(&d, dense->positions, 3 * dense->vertex_count * sizeof(float));
    fnv(&d, dense->normals, 3 * dense->vertex_count * sizeof(float));
    fnv(&d, dense->indices, 3 * dense->triangle_count * sizeof(uint32_t));
    fnv(&d, dense->face_base, dense->triangle_count * sizeof(uint32_t));
    RECORD(4, "reconstruct");
#undef RECORD
done:
    dm_trimesh_free(dense);
    dm_dispmap_free(map);
    dm_param_free(param);
    dm_shell_free(sh);
    free(bp);
    free(bi);
    free(up);
    free(ui);
}

/* every triangle its own three vertices */
static mesh unweld(const mesh *m)
{
    mesh u;
    size_t i;
    u.nv = 3 * m->nt;
    u.nt = m->nt;
    u.p = (float *)malloc(3 * u.nv * sizeof(float));
    u.t = (uint32_t *)malloc(3 * u.nt * sizeof(uint32_t));
    for (i = 0; i < 3 * m->nt; i++) {
        memcpy(u.p + 3 * i, m->p + 3 * (size_t)m->t[i], 3 * sizeof(float));
        u.t[i] = (uint32_t)i;
    }
    return u;
}

/* the same mesh with its vertices numbered in the order the triangles first use them */
static mesh first_use_order(const mesh *m)
{
    mesh r;
    uint32_t *id = (uint32_t *)malloc(m->nv * sizeof(uint32_t));
    size_t i, n = 0;
    r.p = (float *)malloc(3 * m->nv * sizeof(float));
    r.t = (uint32_t *)malloc(3 * m->nt * sizeof(uint32_t));
    r.nt = m->nt;
    for (i = 0; i < m->nv; i++) id[i] = UINT32_MAX;
    for (i = 0; i < 3 * m->nt; i++) {
        uint32_t v = m->t[i];
        if (id[v] == UINT32_MAX) {
            memcpy(r.p + 3 * n, m->p + 3 * (size_t)v, 3 * sizeof(float));
            id[v] = (uint32_t)n++;
        }
        r.t[i] = id[v];
    }
    r.nv = n;
    free(id);
    return r;
}

static void test_weld(const char *what, const mesh *m, size_t target, int res)
{
    mesh soup = unweld(m), ref = first_use_order(m), w;
    uint64_t a[STAGES], b[STAGES];
    size_t nw = 0, k;
    counting c;
    dm_allocator al;
    dm_simplify_options o;
    dm_pm *pm = NULL;
    int i;
    al.alloc = c_alloc;
    al.free = c_free;
    al.user = &c;
    memset(&c, 0, sizeof c);
    c.fail_at = 1L << 40;
    memset(&o, 0, sizeof o);
    o.target_triangles = target;
    o.allocator = &al;
    T_CHECK(dm_simplify(soup.p, soup.nv, soup.t, soup.nt, &o, &pm, NULL) == DM_ERR_NOT_WELDED);
    T_CHECK(pm == NULL && c.live == 0);
    w.p = (float *)malloc(3 * soup.nv * sizeof(float));
    w.t = (uint32_t *)malloc(3 * soup.nt * sizeof(uint32_t));
    w.nt = soup.nt;
    T_CHECK(dm_weld(soup.p, soup.nv, soup.t, soup.nt, &al, w.p, w.t, &nw) == DM_OK);
    w.nv = nw;
    T_CHECK(c.live == 0);
    T_CHECK_MSG(nw == ref.nv && memcmp(w.p, ref.p, 3 * nw * sizeof(float)) == 0 &&
                    memcmp(w.t, ref.t, 3 * ref.nt * sizeof(uint32_t)) == 0,
                "%s: welded %zu vertices, the mesh has %zu", what, nw, ref.nv);
    /* welding a welded mesh renumbers it, nothing more */
    T_CHECK(dm_weld(m->p, m->nv, m->t, m->nt, NULL, w.p, w.t, &nw) == DM_OK);
    T_CHECK(nw == ref.nv && memcmp(w.p, ref.p, 3 * nw * sizeof(float)) == 0);
    T_CHECK(dm_weld(soup.p, soup.nv, soup.t, soup.nt, NULL, w.p, w.t, &nw) == DM_OK);
    pipeline(what, &ref, target, res, 0, a);
    pipeline(what, &w, target, res, 0, b);
    for (i = 0; i < STAGES; i++)
        T_CHECK_MSG(a[i] != 0 && a[i] == b[i], "%s stage %d: welded soup 0x%016llx, renumbered mesh 0x%016llx", what, i,
                    (unsigned long long)b[i], (unsigned long long)a[i]);
    /* bad input and every allocation failing in turn: an error, nothing leaked */
    soup.p[3 * soup.t[7] + 1] = NAN;
    T_CHECK(dm_weld(soup.p, soup.nv, soup.t, soup.nt, NULL, w.p, w.t, &nw) == DM_ERR_BAD_POSITION && nw == 0);
    soup.t[4] = (uint32_t)soup.nv;
    T_CHECK(dm_weld(soup.p, soup.nv, soup.t, soup.nt, NULL, w.p, w.t, &nw) == DM_ERR_BAD_INDEX);
    T_CHECK(dm_weld(soup.p, soup.nv, soup.t, soup.nt, NULL, NULL, w.t, &nw) == DM_ERR_INVALID_ARGUMENT);
    for (k = 0; k <= 3; k++) { /* dm_weld allocates three arrays */
        dm_result r;
        memset(&c, 0, sizeof c);
        c.fail_at = (long)k;
        r = dm_weld(ref.p, ref.nv, ref.t, ref.nt, &al, w.p, w.t, &nw);
        T_CHECK_MSG((k < 3 ? r == DM_ERR_OUT_OF_MEMORY : r == DM_OK) && c.live == 0, "%s: allocation %zu fails: %s, %ld live",
                    what, k, dm_result_string(r), c.live);
    }
    mesh_free(&soup);
    mesh_free(&ref);
    mesh_free(&w);
}

int main(int argc, char **argv)
{
    mesh sphere, torus;
    uint64_t d[STAGES];
    T_BEGIN(argc, argv);
    sphere = make_sphere(12, 0.08, 1.0);
    pipeline("sphere", &sphere, 200, 128, 1, d);
    test_weld("sphere", &sphere, 200, 128);
    torus = make_torus(64, 32, 0.5, 0.05);
    pipeline("torus", &torus, 300, 128, 1, d);
    test_weld("torus", &torus, 300, 128);
    mesh_free(&torus);
    /* a narrow hole: the shell stops on its inner side and the constraint vetoes there */
    torus = make_torus(96, 48, 0.9, 0.05);
    pipeline("thin torus", &torus, 400, 128, 1, d);
    mesh_free(&sphere);
    mesh_free(&torus);
    return T_END();
}
