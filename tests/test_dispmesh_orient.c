/* test_dispmesh_orient.c - dispmesh.h's dm_orient: triangles turned to agree with their neighbours.
   - a bumpy sphere with a scattered third of its triangles turned comes back exactly as it was
     made (every turned triangle turned back, none other), and its edges each run once each way;
   - a sphere facing inward throughout (wound clockwise) is turned whole, one facing out is left alone;
   - a hollow ball (an outer sphere facing out, an inner one facing into the cavity), both
     scrambled: each comes back as made, the inner one by its nesting in the outer one; as made it is
     left alone; two overlapping spheres (not nested) both face out;
   - open parts: a bowl (a sphere's lower half) scrambled comes back facing out of it; a flat sheet
     with a quarter of its triangles turned comes back the way most of it faced; a torus too;
   - parts apart: two scrambled spheres side by side both face out;
   - a Moebius band and an edge shared by three triangles: DM_OK, nothing written out of bounds,
     and each manifold edge away from the band's one seam agrees;
   - bad input (NULL arrays, a bad index, a NaN position) gives its code and leaves the indices as
     they were; every failing allocation gives DM_ERR_OUT_OF_MEMORY, leaks nothing and leaves them
     too; the same input twice gives the same bits. */
#define DM_IMPLEMENTATION
#include "dispmesh.h"
#include "test.h"
#include "testmesh.h"
#include "failalloc.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

/* triangle t turned in place: (a, b, c) -> (a, c, b) */
static void turn(uint32_t *idx, size_t t)
{
    uint32_t b = idx[3 * t + 1];
    idx[3 * t + 1] = idx[3 * t + 2];
    idx[3 * t + 2] = b;
}

/* about share of the triangles turned, chosen by a fixed hash of their index */
static size_t scramble(uint32_t *idx, size_t nt, double share, uint32_t seed)
{
    size_t t, n = 0;
    for (t = 0; t < nt; t++) {
        uint32_t h = (uint32_t)t * 2654435761u ^ seed;
        h ^= h >> 15;
        h *= 2246822519u;
        h ^= h >> 13;
        if ((double)(h % 10000u) < share * 10000.0) {
            turn(idx, t);
            n++;
        }
    }
    return n;
}

/* directed edges used twice (two triangles running an edge the same way) */
static size_t disagreeing_edges(const uint32_t *idx, size_t nt)
{
    size_t i, j, n = 0, m = 3 * nt;
    uint64_t *k = (uint64_t *)malloc((m ? m : 1) * sizeof(uint64_t));
    if (!k) return (size_t)-1;
    for (i = 0; i < m; i++) k[i] = (uint64_t)idx[i] << 32 | idx[i - i % 3 + (i % 3 + 1) % 3];
    { /* Shell sort */
        size_t gap;
        for (gap = m / 2; gap > 0; gap /= 2)
            for (i = gap; i < m; i++) {
                uint64_t x = k[i];
                for (j = i; j >= gap && k[j - gap] > x; j -= gap) k[j] = k[j - gap];
                k[j] = x;
            }
    }
    for (i = 1; i < m; i++) n += k[i] == k[i - 1];
    free(k);
    return n;
}

/* six times the enclosed volume of triangles [t0, t1) */
static double volume6(const float *p, const uint32_t *idx, size_t t0, size_t t1)
{
    double v = 0.0;
    size_t t;
    for (t = t0; t < t1; t++) {
        const float *a = p + 3 * (size_t)idx[3 * t], *b = p + 3 * (size_t)idx[3 * t + 1], *c = p + 3 * (size_t)idx[3 * t + 2];
        v += (double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) - (double)a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
             (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0]);
    }
    return v;
}

/* m scrambled, oriented: it must come back exactly as made (with the count turned back) */
static void round_trip(const char *name, const mesh *m, double share, uint32_t seed)
{
    uint32_t *idx = (uint32_t *)malloc(3 * m->nt * sizeof(uint32_t));
    size_t scrambled, turned = 0;
    if (!T_CHECK(idx != NULL)) return;
    memcpy(idx, m->t, 3 * m->nt * sizeof(uint32_t));
    scrambled = scramble(idx, m->nt, share, seed);
    T_CHECK_MSG(disagreeing_edges(idx, m->nt) > 0, "%s: the scramble makes edges disagree", name);
    T_CHECK(dm_orient(m->p, m->nv, idx, m->nt, NULL, &turned) == DM_OK);
    T_CHECK_MSG(memcmp(idx, m->t, 3 * m->nt * sizeof(uint32_t)) == 0, "%s: back as made", name);
    T_CHECK_MSG(turned == scrambled, "%s: %zu turned, %zu scrambled", name, turned, scrambled);
    free(idx);
}

/* the two meshes as one (b's vertices after a's) */
static mesh join(const mesh *a, const mesh *b)
{
    mesh m;
    size_t i;
    m.nv = a->nv + b->nv;
    m.nt = a->nt + b->nt;
    m.p = (float *)malloc(3 * m.nv * sizeof(float));
    m.t = (uint32_t *)malloc(3 * m.nt * sizeof(uint32_t));
    if (!m.p || !m.t) {
        mesh_free(&m);
        m.nv = m.nt = 0;
        return m;
    }
    memcpy(m.p, a->p, 3 * a->nv * sizeof(float));
    memcpy(m.p + 3 * a->nv, b->p, 3 * b->nv * sizeof(float));
    memcpy(m.t, a->t, 3 * a->nt * sizeof(uint32_t));
    for (i = 0; i < 3 * b->nt; i++) m.t[3 * a->nt + i] = b->t[i] + (uint32_t)a->nv;
    return m;
}

static void closed_checks(void)
{
    mesh s = make_sphere(16, 0.1, 1.0), in = make_sphere(10, 0.0, 0.5), hollow, two, off;
    size_t t, turned = 1;
    uint32_t *idx;
    round_trip("sphere, a third", &s, 0.33, 1u);
    round_trip("sphere, two thirds", &s, 0.67, 2u);
    T_CHECK(volume6(s.p, s.t, 0, s.nt) > 0.0);
    T_EQ_SIZE(disagreeing_edges(s.t, s.nt), 0);
    /* consistent but facing inward (wound clockwise): turned whole */
    idx = (uint32_t *)malloc(3 * s.nt * sizeof(uint32_t));
    if (T_CHECK(idx != NULL)) {
        memcpy(idx, s.t, 3 * s.nt * sizeof(uint32_t));
        for (t = 0; t < s.nt; t++) turn(idx, t);
        {
            uint32_t *was = (uint32_t *)malloc(3 * s.nt * sizeof(uint32_t));
            if (T_CHECK(was != NULL)) {
                memcpy(was, idx, 3 * s.nt * sizeof(uint32_t));
                T_CHECK(dm_orient(s.p, s.nv, idx, s.nt, NULL, &turned) == DM_OK);
                T_EQ_SIZE(turned, s.nt);
                T_CHECK(memcmp(s.t, idx, 3 * s.nt * sizeof(uint32_t)) == 0);
                memcpy(idx, s.t, 3 * s.nt * sizeof(uint32_t)); /* consistent and facing out: left alone */
                T_CHECK(dm_orient(s.p, s.nv, idx, s.nt, NULL, &turned) == DM_OK);
                T_EQ_SIZE(turned, 0);
                T_CHECK(memcmp(s.t, idx, 3 * s.nt * sizeof(uint32_t)) == 0);
                free(was);
            }
        }
        free(idx);
    }
    /* a hollow ball: the cavity's wall faces into the cavity */
    for (t = 0; t < in.nt; t++) turn(in.t, t);
    hollow = join(&s, &in);
    if (T_CHECK(hollow.nt > 0)) {
        T_CHECK(volume6(hollow.p, hollow.t, s.nt, hollow.nt) < 0.0);
        round_trip("hollow ball", &hollow, 0.5, 3u);
        { /* as made (consistent, the cavity's wall facing into it): left alone */
            uint32_t *h = (uint32_t *)malloc(3 * hollow.nt * sizeof(uint32_t));
            if (T_CHECK(h != NULL)) {
                memcpy(h, hollow.t, 3 * hollow.nt * sizeof(uint32_t));
                T_CHECK(dm_orient(hollow.p, hollow.nv, h, hollow.nt, NULL, &turned) == DM_OK);
                T_EQ_SIZE(turned, 0);
                T_CHECK(memcmp(h, hollow.t, 3 * hollow.nt * sizeof(uint32_t)) == 0);
                free(h);
            }
        }
        { /* two overlapping spheres, both facing out: neither is nested in the other */
            mesh o = make_sphere(10, 0.0, 0.8), lap;
            for (t = 0; t < o.nv; t++) o.p[3 * t] += 0.9f;
            lap = join(&s, &o);
            if (T_CHECK(lap.nt > 0)) round_trip("overlapping spheres", &lap, 0.5, 10u);
            mesh_free(&o);
            mesh_free(&lap);
        }
    }
    /* two spheres apart, both facing out */
    off = make_sphere(10, 0.0, 0.5);
    for (t = 0; t < off.nv; t++) off.p[3 * t] += 3.0f;
    two = join(&s, &off);
    if (T_CHECK(two.nt > 0)) round_trip("two spheres", &two, 0.5, 4u);
    mesh_free(&s);
    mesh_free(&in);
    mesh_free(&hollow);
    mesh_free(&off);
    mesh_free(&two);
}

static void open_checks(void)
{
    mesh s = make_sphere(16, 0.0, 1.0), bowl, sheet = make_sheet(24, 0.0, 0.05, 0.0), holed = make_sheet(24, 0.0, 0.05, 0.4);
    mesh torus = make_torus(48, 24, 0.3, 0.05);
    size_t t, k;
    /* the lower half of the sphere: an open bowl */
    bowl.p = s.p;
    bowl.nv = s.nv;
    bowl.t = (uint32_t *)malloc(3 * s.nt * sizeof(uint32_t));
    bowl.nt = 0;
    if (T_CHECK(bowl.t != NULL)) {
        for (t = 0; t < s.nt; t++) {
            double z = 0.0;
            for (k = 0; k < 3; k++) z += s.p[3 * (size_t)s.t[3 * t + k] + 2];
            if (z < 0.0) memcpy(bowl.t + 3 * bowl.nt++, s.t + 3 * t, 3 * sizeof(uint32_t));
        }
        round_trip("bowl", &bowl, 0.6, 5u); /* most of it turned: comes back by its volume */
        free(bowl.t);
    }
    round_trip("sheet", &sheet, 0.25, 6u); /* flat: the way most of it faced */
    round_trip("sheet with a hole", &holed, 0.3, 7u);
    round_trip("torus", &torus, 0.5, 8u);
    mesh_free(&s);
    mesh_free(&sheet);
    mesh_free(&holed);
    mesh_free(&torus);
}

/* a Moebius band of n quads (the last row joined twisted) and a fin of three triangles on one edge */
static void odd_checks(void)
{
    enum { N = 24 };
    float p[3 * 2 * N];
    uint32_t idx[3 * 2 * N + 9];
    size_t turned = 0, nt = 2 * N, i;
    for (i = 0; i < N; i++) {
        double a = 2.0 * 3.141592653589793 * (double)i / N, w = 0.2;
        int s;
        for (s = 0; s < 2; s++) {
            double r = 1.0 + (s ? w : -w) * cos(a / 2.0), z = (s ? w : -w) * sin(a / 2.0);
            p[3 * (2 * i + (size_t)s)] = (float)(r * cos(a));
            p[3 * (2 * i + (size_t)s) + 1] = (float)(r * sin(a));
            p[3 * (2 * i + (size_t)s) + 2] = (float)z;
        }
    }
    for (i = 0; i < N; i++) {
        uint32_t a0 = (uint32_t)(2 * i), a1 = a0 + 1, b0 = (uint32_t)(2 * ((i + 1) % N)), b1 = b0 + 1;
        if (i == N - 1) { /* the twist: the band's two sides swap */
            uint32_t x = b0;
            b0 = b1;
            b1 = x;
        }
        idx[6 * i] = a0; idx[6 * i + 1] = b0; idx[6 * i + 2] = a1;
        idx[6 * i + 3] = a1; idx[6 * i + 4] = b0; idx[6 * i + 5] = b1;
        if (i % 3 == 1) turn(idx, 2 * i);
    }
    T_CHECK(dm_orient(p, 2 * N, idx, nt, NULL, &turned) == DM_OK);
    T_CHECK_MSG(disagreeing_edges(idx, nt) <= 1, "Moebius band: %zu edges disagree (one seam allowed)",
                disagreeing_edges(idx, nt));
    for (i = 0; i < 3 * nt; i++) T_CHECK(idx[i] < 2 * N);
    { /* a fin: three triangles on edge 0-1 (linked to none), and a fourth beside the first, turned: of
           the two (equal areas, flat) the first decides */
        static const float q[3 * 6] = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1, 1.5f, 1, 0};
        uint32_t f[12] = {0, 1, 2, 1, 0, 3, 0, 1, 4, 1, 2, 5};
        T_CHECK(dm_orient(q, 6, f, 4, NULL, &turned) == DM_OK);
        T_CHECK_MSG(f[9] == 1 && f[10] == 5 && f[11] == 2, "the fin's neighbour turned to agree: %u %u %u", f[9], f[10],
                    f[11]);
    }
}

static void bad_input_checks(void)
{
    mesh s = make_sphere(6, 0.0, 1.0);
    uint32_t *idx = (uint32_t *)malloc(3 * s.nt * sizeof(uint32_t)), *again;
    size_t turned = 7, calls, k;
    fail_alloc fa;
    dm_allocator al;
    if (!T_CHECK(idx != NULL)) return;
    memcpy(idx, s.t, 3 * s.nt * sizeof(uint32_t));
    scramble(idx, s.nt, 0.5, 9u);
    T_EQ_INT(dm_orient(NULL, s.nv, idx, s.nt, NULL, &turned), DM_ERR_INVALID_ARGUMENT);
    T_EQ_SIZE(turned, 0);
    T_EQ_INT(dm_orient(s.p, s.nv, NULL, s.nt, NULL, NULL), DM_ERR_INVALID_ARGUMENT);
    T_EQ_INT(dm_orient(s.p, s.nv, idx, 0, NULL, NULL), DM_ERR_NO_TRIANGLES);
    again = (uint32_t *)malloc(3 * s.nt * sizeof(uint32_t));
    if (!T_CHECK(again != NULL)) return;
    memcpy(again, idx, 3 * s.nt * sizeof(uint32_t));
    idx[3 * s.nt - 1] = (uint32_t)s.nv; /* a bad index */
    T_EQ_INT(dm_orient(s.p, s.nv, idx, s.nt, NULL, NULL), DM_ERR_BAD_INDEX);
    T_CHECK(memcmp(idx, again, 3 * s.nt * sizeof(uint32_t) - sizeof(uint32_t)) == 0);
    idx[3 * s.nt - 1] = again[3 * s.nt - 1];
    s.p[3 * idx[0]] = NAN;
    T_EQ_INT(dm_orient(s.p, s.nv, idx, s.nt, NULL, NULL), DM_ERR_BAD_POSITION);
    T_CHECK(memcmp(idx, again, 3 * s.nt * sizeof(uint32_t)) == 0);
    s.p[3 * idx[0]] = 1.0f;
    /* every allocation failing in turn: the code, nothing leaked, the indices as they were */
    al.alloc = fa_alloc;
    al.free = fa_free;
    al.user = &fa;
    memset(&fa, 0, sizeof fa);
    T_CHECK(dm_orient(s.p, s.nv, idx, s.nt, &al, &turned) == DM_OK); /* counts the calls */
    calls = (size_t)fa.calls;
    T_CHECK(calls > 0 && fa.live == 0);
    memcpy(idx, again, 3 * s.nt * sizeof(uint32_t));
    for (k = 1; k <= calls; k++) {
        memset(&fa, 0, sizeof fa);
        fa.fail_at = (long)k;
        T_EQ_INT(dm_orient(s.p, s.nv, idx, s.nt, &al, &turned), DM_ERR_OUT_OF_MEMORY);
        T_EQ_INT(fa.live, 0);
        T_CHECK(memcmp(idx, again, 3 * s.nt * sizeof(uint32_t)) == 0);
    }
    /* the same input, the same bits */
    {
        uint32_t *b = (uint32_t *)malloc(3 * s.nt * sizeof(uint32_t));
        if (T_CHECK(b != NULL)) {
            memcpy(b, again, 3 * s.nt * sizeof(uint32_t));
            T_CHECK(dm_orient(s.p, s.nv, idx, s.nt, NULL, NULL) == DM_OK);
            T_CHECK(dm_orient(s.p, s.nv, b, s.nt, NULL, NULL) == DM_OK);
            T_CHECK(memcmp(idx, b, 3 * s.nt * sizeof(uint32_t)) == 0);
            free(b);
        }
    }
    free(again);
    free(idx);
    mesh_free(&s);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    closed_checks();
    open_checks();
    odd_checks();
    bad_input_checks();
    return T_END();
}
