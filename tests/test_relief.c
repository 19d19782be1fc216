/* test_relief.c - examples/relief.h, stage by stage:
   - normal map: on an analytic periodic height field the normals equal the exact central
     difference (to float rounding) and the analytic normals within the central difference's own
     error bound; a ramp gives the expected constant normal and sign (x along +column, y along
     +row); clamp and wrap agree away from the border;
   - skeleton: the ridge line of a Gaussian ridge along a sine curve: every skeleton texel within
     one texel of the crest, 90% of the crest covered, no loops (edges = vertices - components);
     valley mode on the negated map gives the same bits; loop elimination by Kruskal equals the
     thesis's delete-the-lightest-edge-of-a-loop procedure on random graphs;
   - graph cut: on 8x8 overlaps with random heights and pins, the cut's cost equals the exact
     minimum over every labelling (enumerated row by row: dynamic programming over the 256
     labellings of a row), and the pins are respected;
   - synthesis on a procedural rock example and a sketch with a white ring and a black bar:
     mean height under white strokes - under black >= half the example's range; away from the
     strokes the histograms of height and gradient magnitude within L1 0.1 of the example's;
     the 95th percentile of height steps across seams <= 1.5 x that inside patches; the same
     bits on a second run; the emboss baseline follows the sketch too;
   - bad input (NaN, empty, no strokes, patch too large, NULL), cancellation and failing the
     k-th allocation: named errors, nothing leaked.
   TEST_SANITIZE=1 runs fewer graph-cut trials (the synthesis keeps its size: its histograms need
   enough patches).
   test_relief --cli PROG DIR instead checks the program examples/relief.c (PROG, built by
   mk/relief.mk beside this test) on files it writes into DIR: a small good run exits 0 and
   writes its picture; bad arguments exit 2, unreadable, truncated, empty or non-finite images,
   stroke files without strokes or with bad lines, a crop outside the example and a patch too
   large exit 1, each without a signal (a crash would be a status above 128) and without
   writing the output picture. */
#define _POSIX_C_SOURCE 200809L /* sys/wait.h: the --cli mode's exit statuses */
#define RL_IMPLEMENTATION
#include "relief.h"
#include "failalloc.h"
#include "test.h"

#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

static int g_small;

/* ---- normal map --------------------------------------------------------------------------- */

static void test_normal_map(void)
{
    enum { W = 128, H = 96 };
    static float h[W * H], n[3 * W * H], n2[3 * W * H];
    const double A = 0.7, wx = 2 * 3.14159265358979 / 64.0, wy = 2 * 3.14159265358979 / 48.0, k = 6.0;
    rl_normal_options o = rl_normal_default_options();
    int x, y, d;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) h[y * W + x] = (float)(A * sin(wx * x) * cos(wy * y));
    o.strength = (float)k;
    o.wrap = 1;
    for (d = 1; d <= 4; d *= 2) {
        double worst_exact = 0, worst_true = 0, bound;
        o.distance = d;
        T_EQ_INT(rl_normal_map(h, W, H, &o, n), RL_OK);
        for (y = 0; y < H; y++)
            for (x = 0; x < W; x++) {
                /* (sin(w(x+d)) - sin(w(x-d))) / 2d = cos(wx) sin(wd) / d */
                double gs = k * A * cos(wx * x) * cos(wy * y), gt = -k * A * sin(wx * x) * sin(wy * y);
                double es = gs * sin(wx * d) / (d * 1.0), et = gt * sin(wy * d) / (d * 1.0);
                double ts = gs * wx, tt = gt * wy, l1 = sqrt(es * es + et * et + 1), l2 = sqrt(ts * ts + tt * tt + 1);
                const float *m = n + 3 * (y * W + x);
                double e1 = fabs(m[0] + es / l1) + fabs(m[1] + et / l1) + fabs(m[2] - 1 / l1);
                double e2 = sqrt((m[0] + ts / l2) * (m[0] + ts / l2) + (m[1] + tt / l2) * (m[1] + tt / l2) + (m[2] - 1 / l2) * (m[2] - 1 / l2));
                worst_exact = e1 > worst_exact ? e1 : worst_exact;
                worst_true = e2 > worst_true ? e2 : worst_true;
            }
        /* normalize(-g, 1) is 1-Lipschitz in g: the error is at most that of the gradient, whose
           relative error per axis is 1 - sin(w d) / (w d) */
        bound = k * A * sqrt(pow(wx * (1 - sin(wx * d) / (wx * d)), 2) + pow(wy * (1 - sin(wy * d) / (wy * d)), 2)) + 1e-5;
        printf("normal map d=%d: worst vs exact central difference %.2g, vs analytic %.4f (bound %.4f)\n", d, worst_exact, worst_true, bound);
        T_CHECK(worst_exact < 2e-5);
        T_CHECK(worst_true <= bound);
    }
    {   /* clamp agrees with wrap at least d texels from the border */
        int diff = 0;
        o.distance = 4;
        rl_normal_map(h, W, H, &o, n);
        o.wrap = 0;
        T_EQ_INT(rl_normal_map(h, W, H, &o, n2), RL_OK);
        for (y = 4; y < H - 4; y++)
            for (x = 4; x < W - 4; x++) diff += memcmp(n + 3 * (y * W + x), n2 + 3 * (y * W + x), 12) != 0;
        T_EQ_INT(diff, 0);
    }
    {   /* ramps: h = 0.1 x gives (-k 0.1, 0, 1)/|.|; h = 0.1 y gives a negative y component */
        int bad = 0;
        double l = sqrt(1 + 0.36);
        for (y = 0; y < H; y++) for (x = 0; x < W; x++) h[y * W + x] = 0.1f * (float)x;
        o.strength = 6.0f;
        rl_normal_map(h, W, H, &o, n);
        for (y = 0; y < H; y++)
            for (x = 4; x < W - 4; x++) {
                const float *m = n + 3 * (y * W + x);
                bad += fabs(m[0] + 0.6 / l) > 1e-5 || fabs(m[1]) > 1e-6 || fabs(m[2] - 1 / l) > 1e-5;
            }
        T_EQ_INT(bad, 0);
        for (y = 0; y < H; y++) for (x = 0; x < W; x++) h[y * W + x] = 0.1f * (float)y;
        rl_normal_map(h, W, H, &o, n);
        T_CHECK(fabsf(n[3 * (40 * W + 7) + 1] + (float)(0.6 / l)) < 1e-5f);
        {
            uint8_t rgb[3];
            float flat[3] = {0.0f, 0.0f, 1.0f};
            rl_normal_to_rgb8(flat, 1, rgb);
            T_CHECK(rgb[0] == 128 && rgb[1] == 128 && rgb[2] == 255);
        }
    }
    /* issue 21 point 2, found by fuzz_relief: finite heights whose slopes' squares overflow float
       (a step of 2e25 at strength 1: hs = 2.5e24, hs^2 = inf) gave the normal (-0, 0, 0); it is
       unit, pointing away from the step */
    {
        float step[16 * 8], nn[3 * 16 * 8];
        int i;
        for (i = 0; i < 16 * 8; i++) step[i] = (i % 16) < 8 ? -1e25f : 1e25f;
        T_EQ_INT(rl_normal_map(step, 16, 8, NULL, nn), RL_OK);
        i = 3 * (3 * 16 + 8);
        T_CHECK_MSG(fabsf(nn[i] * nn[i] + nn[i + 1] * nn[i + 1] + nn[i + 2] * nn[i + 2] - 1.0f) < 1e-5f && nn[i] < -0.99f,
                    "normal at the step (%g, %g, %g)", nn[i], nn[i + 1], nn[i + 2]);
    }
    o.distance = -1;
    T_EQ_INT(rl_normal_map(h, W, H, &o, n), RL_ERR_INVALID_ARGUMENT);
    h[5] = NAN;
    T_EQ_INT(rl_normal_map(h, W, H, NULL, n), RL_ERR_NOT_FINITE);
    T_EQ_INT(rl_normal_map(h, 0, H, NULL, n), RL_ERR_EMPTY);
    T_EQ_INT(rl_normal_map(h, W, H, NULL, NULL), RL_ERR_INVALID_ARGUMENT);
}

/* ---- skeleton ----------------------------------------------------------------------------- */

static double crest(double x) { return 48.0 + 10.0 * sin(2 * 3.14159265358979 * x / 64.0); }

static double crest_distance(double x, double y)
{
    double best = 1e30, t;
    for (t = x - 20; t <= x + 20; t += 0.01) {
        double dx = t - x, dy = crest(t) - y, d = dx * dx + dy * dy;
        if (d < best) best = d;
    }
    return sqrt(best);
}

static int count_components(const uint8_t *e, int w, int h, int *vertices, int *edges)
{
    int *parent = (int *)malloc(sizeof(int) * (size_t)w * h), i, k, comps = 0;
    *vertices = 0; *edges = 0;
    for (i = 0; i < w * h; i++) parent[i] = i;
    for (i = 0; i < w * h; i++) {
        if (!e[i]) continue;
        (*vertices)++;
        for (k = 0; k < 8; k++)
            if (e[i] & (1 << k)) {
                int j = (i / w + rl__dy[k]) * w + (i % w + rl__dx[k]), a = i, b = j;
                (*edges)++;
                while (parent[a] != a) a = parent[a];
                while (parent[b] != b) b = parent[b];
                if (a != b) parent[a] = b;
            }
    }
    for (i = 0; i < w * h; i++) comps += e[i] && parent[i] == i;
    *edges /= 2;
    free(parent);
    return comps;
}

static void test_skeleton(void)
{
    enum { W = 128, H = 96 };
    static float h[W * H], neg[W * H];
    rl_map m = {W, H, h}, mn = {W, H, neg};
    rl_skeleton s, sv;
    int x, y, far = 0, covered = 0, cols = 0, v, e, c;
    double worst = 0;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            double d = crest_distance(x, y);
            h[y * W + x] = (float)exp(-d * d / (2 * 2.0 * 2.0));
            neg[y * W + x] = -h[y * W + x];
        }
    T_EQ_INT(rl_skeleton_extract(&m, NULL, NULL, &s), RL_OK);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++)
            if (s.edges[y * W + x]) {
                double d = crest_distance(x, y);
                worst = d > worst ? d : worst;
                far += d > 1.0;
            }
    for (x = 4; x < W - 4; x++) { /* the crest point above column x has a skeleton texel within 1.5 */
        int yy, xx, hit = 0, yc = (int)floor(crest(x) + 0.5);
        cols++;
        for (yy = yc - 2; yy <= yc + 2; yy++)
            for (xx = x - 2; xx <= x + 2; xx++)
                if (xx >= 0 && xx < W && yy >= 0 && yy < H && s.edges[yy * W + xx] &&
                    (xx - x) * (xx - x) + (yy - crest(x)) * (yy - crest(x)) <= 2.25) hit = 1;
        covered += hit;
    }
    c = count_components(s.edges, W, H, &v, &e);
    printf("skeleton: %d texels, %d edges, %d components, farthest %.3f texels from the crest, %d of %d columns covered\n", v, e, c, worst, covered, cols);
    T_CHECK_MSG(far == 0, "%d skeleton texels more than one texel from the crest", far);
    T_CHECK(covered >= (cols * 9) / 10);
    T_CHECK(v > 0 && e == v - c);
    {
        rl_skeleton_options o = rl_skeleton_default_options();
        o.valleys = 1;
        T_EQ_INT(rl_skeleton_extract(&mn, &o, NULL, &sv), RL_OK);
        T_CHECK(memcmp(s.edges, sv.edges, (size_t)W * H) == 0);
        rl_skeleton_free(&sv, NULL);
    }
    rl_skeleton_free(&s, NULL);
    m.width = 0;
    T_EQ_INT(rl_skeleton_extract(&m, NULL, NULL, &s), RL_ERR_EMPTY);
    T_CHECK(s.edges == NULL);
}

static uint32_t lcg(uint32_t *s) { *s = *s * 1664525u + 1013904223u; return *s >> 8; }
static float frand(uint32_t *s) { return (float)(lcg(s) & 0xFFFF) / 65536.0f; }

/* Loop elimination: Kruskal's maximum spanning forest equals the thesis's procedure (find a
   loop, delete its lightest edge, repeat) on random 8-neighbour graphs of 6x6 texels with
   distinct weights (where both give the unique maximum forest). */
static int find_loop(const uint8_t *alive, const rl__edge *e, int ne, int nv, int *loop, int *len)
{
    /* the first alive edge (in order) whose ends the alive edges before it already connect
       closes a loop: that edge plus the path between its ends (depth-first search) */
    int via[36], i, k;
    for (k = 0; k < ne; k++) {
        int a = (int)e[k].a, b = (int)e[k].b, stack[36], sp = 0, seen[36], found = 0;
        if (!alive[k]) continue;
        /* depth-first search from a to b over the alive edges before k */
        for (i = 0; i < nv; i++) { seen[i] = 0; via[i] = -1; }
        stack[sp++] = a; seen[a] = 1;
        while (sp && !found) {
            int u = stack[--sp], j;
            for (j = 0; j < k; j++) {
                int v;
                if (!alive[j]) continue;
                if ((int)e[j].a == u) v = (int)e[j].b; else if ((int)e[j].b == u) v = (int)e[j].a; else continue;
                if (seen[v]) continue;
                seen[v] = 1; via[v] = j; stack[sp++] = v;
                if (v == b) { found = 1; break; }
            }
        }
        if (found) {
            int v = b;
            *len = 0;
            loop[(*len)++] = k;
            while (v != a) { int j = via[v]; loop[(*len)++] = j; v = (int)e[j].a == v ? (int)e[j].b : (int)e[j].a; }
            return 1;
        }
    }
    return 0;
}

static void test_loop_elimination(void)
{
    int trial, bad = 0, trials = g_small ? 20 : 100;
    uint32_t seed = 21;
    for (trial = 0; trial < trials; trial++) {
        rl__edge e[36 * 4], sorted[36 * 4 * 2];
        uint8_t alive[36 * 4], mask[36], naive[36];
        uint32_t parent[36];
        static size_t count[65536];
        int ne = 0, x, y, k, i, loop[40], len;
        for (y = 0; y < 6; y++)
            for (x = 0; x < 6; x++)
                for (k = 2; k <= 5; k++) {
                    int px = x + rl__dx[k], py = y + rl__dy[k];
                    if (px < 0 || py < 0 || px >= 6 || py >= 6 || (lcg(&seed) & 3) == 0) continue;
                    e[ne].a = (uint32_t)(y * 6 + x); e[ne].b = (uint32_t)(py * 6 + px); e[ne].dir = (uint8_t)k;
                    e[ne].weight = (float)(lcg(&seed) & 0xFFFFF) + (float)ne / 1024.0f; /* distinct */
                    ne++;
                }
        memcpy(sorted, e, sizeof(rl__edge) * (size_t)ne);
        memset(mask, 0, sizeof mask);
        rl__ppa_forest(sorted, sorted + ne, count, (size_t)ne, parent, 36, mask);
        for (i = 0; i < ne; i++) alive[i] = 1;
        while (find_loop(alive, e, ne, 36, loop, &len)) { /* delete the loop's lightest edge */
            int lightest = loop[0];
            for (i = 1; i < len; i++) if (e[loop[i]].weight < e[lightest].weight) lightest = loop[i];
            alive[lightest] = 0;
        }
        memset(naive, 0, sizeof naive);
        for (i = 0; i < ne; i++)
            if (alive[i]) { naive[e[i].a] |= (uint8_t)(1u << e[i].dir); naive[e[i].b] |= (uint8_t)(1u << ((e[i].dir + 4) & 7)); }
        bad += memcmp(mask, naive, sizeof mask) != 0;
    }
    printf("loop elimination: %d random graphs, Kruskal and loop-by-loop deletion differ on %d\n", trials, bad);
    T_EQ_INT(bad, 0);
}

/* ---- graph cut ---------------------------------------------------------------------------- */


/* the cost of cutting between texels s and t, as rl_graph_cut defines it */
static double pair_cost(const float *a, const float *b, size_t s, size_t t)
{
    return fabs((double)a[s] - (double)b[s]) + fabs((double)a[t] - (double)b[t]);
}

/* exact minimum over all 2^64 labellings, one row (8 labels, bit x = B) at a time */
static double cut_exact(const float *a, const float *b, const uint8_t *cons)
{
    double best[256], next[256], m;
    int y, r, q, x;
    for (r = 0; r < 256; r++) best[r] = 0;
    for (y = 0; y < 8; y++) {
        for (r = 0; r < 256; r++) {
            double row = 0;
            int ok = 1;
            for (x = 0; x < 8; x++) {
                int l = (r >> x) & 1, p = y * 8 + x;
                if ((cons[p] == 1 && l) || (cons[p] == 2 && !l)) ok = 0;
                if (x < 7 && l != ((r >> (x + 1)) & 1)) row += pair_cost(a, b, (size_t)p, (size_t)p + 1);
            }
            next[r] = 1e300;
            if (!ok) continue;
            for (q = 0; q < 256; q++) {
                double c = best[q] + row;
                if (y > 0) {
                    for (x = 0; x < 8; x++)
                        if (((q ^ r) >> x) & 1) c += pair_cost(a, b, (size_t)((y - 1) * 8 + x), (size_t)(y * 8 + x));
                } else if (q) {
                    continue;
                }
                if (c < next[r]) next[r] = c;
            }
        }
        memcpy(best, next, sizeof best);
    }
    for (m = 1e300, r = 0; r < 256; r++) m = best[r] < m ? best[r] : m;
    return m;
}

static void test_graph_cut(void)
{
    int trial, bad = 0, pin_bad = 0, trials = g_small ? 40 : 150;
    uint32_t seed = 7;
    for (trial = 0; trial < trials; trial++) {
        float a[64], b[64];
        uint8_t cons[64], lab[64];
        double cost = -1, exact;
        int i;
        for (i = 0; i < 64; i++) {
            a[i] = frand(&seed);
            b[i] = trial % 3 == 0 ? a[i] + 0.3f * frand(&seed) : frand(&seed);
            cons[i] = 0;
        }
        for (i = 0; i < 8; i++) {
            if (trial % 2) { cons[i * 8] = 1; cons[i * 8 + 7] = 2; }      /* a vertical overlap */
            else { cons[i] = 1; cons[i * 8] = 1; cons[63 - i] = 2; }    /* an L-shaped one */
        }
        for (i = 0; i < 3; i++) cons[lcg(&seed) % 64] = (uint8_t)(1 + (lcg(&seed) & 1));
        T_EQ_INT(rl_graph_cut(a, b, cons, 8, 8, NULL, lab, &cost), RL_OK);
        exact = cut_exact(a, b, cons);
        if (fabs(cost - exact) > 1e-9 * (1 + exact)) { bad++; printf("  trial %d: cut %.9f, exact %.9f\n", trial, cost, exact); }
        for (i = 0; i < 64; i++) pin_bad += (cons[i] == 1 && lab[i]) || (cons[i] == 2 && !lab[i]);
    }
    printf("graph cut: %d 8x8 overlaps against exhaustive minima, %d differ\n", trials, bad);
    T_EQ_INT(bad, 0);
    T_EQ_INT(pin_bad, 0);
    {
        float a[4] = {0, 0, 0, 0}, b[4] = {0, 0, 0, NAN};
        uint8_t lab[4];
        T_EQ_INT(rl_graph_cut(a, b, NULL, 2, 2, NULL, lab, NULL), RL_ERR_NOT_FINITE);
        T_EQ_INT(rl_graph_cut(a, a, NULL, 0, 2, NULL, lab, NULL), RL_ERR_INVALID_ARGUMENT);
    }
}

/* ---- synthesis ---------------------------------------------------------------------------- */

static float lattice(int x, int y, uint32_t seed)
{
    uint32_t h = (uint32_t)x * 374761393u + (uint32_t)y * 668265263u + seed * 2246822519u;
    h = (h ^ (h >> 13)) * 1274126177u;
    return (float)((h ^ (h >> 16)) & 0xFFFF) / 65535.0f;
}

static float value_noise(float x, float y, uint32_t seed)
{
    int x0 = (int)floorf(x), y0 = (int)floorf(y);
    float fx = x - (float)x0, fy = y - (float)y0, a, b;
    fx = fx * fx * (3 - 2 * fx); fy = fy * fy * (3 - 2 * fy);
    a = lattice(x0, y0, seed) + fx * (lattice(x0 + 1, y0, seed) - lattice(x0, y0, seed));
    b = lattice(x0, y0 + 1, seed) + fx * (lattice(x0 + 1, y0 + 1, seed) - lattice(x0, y0 + 1, seed));
    return a + fy * (b - a);
}

/* a rock-like example: ridged multi-octave noise (sharp ridges and valleys) in [0, 1] */
static void make_rock(float *h, int n)
{
    int x, y, o;
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            float v = 0, amp = 0.6f, f = 1.0f / 24.0f;
            for (o = 0; o < 4; o++, amp *= 0.5f, f *= 2.0f) v += amp * (1.0f - fabsf(2.0f * value_noise(x * f, y * f, (uint32_t)o + 1) - 1.0f));
            h[y * n + x] = v / 1.125f;
        }
}

/* a ring of white (ridge) and a bar of black (groove), 6 texels wide, on grey */
static void make_sketch(float *s, int n)
{
    int x, y;
    float c = 0.5f * (float)n, r = 0.3f * (float)n;
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            float dx = (float)x - c * 0.8f, dy = (float)y - c, d = sqrtf(dx * dx + dy * dy);
            s[y * n + x] = 0.5f;
            if (fabsf(d - r) < 3.0f) s[y * n + x] = 1.0f;
            if (x > n * 0.55f && x < n * 0.9f && fabsf((float)y - 0.5f * n) < 3.0f) s[y * n + x] = 0.0f;
        }
}

static void histogram(const float *v, const uint8_t *use, size_t n, float lo, float hi, double *hist)
{
    size_t i, count = 0;
    int b;
    for (b = 0; b < 16; b++) hist[b] = 0;
    for (i = 0; i < n; i++) {
        int k;
        if (use && !use[i]) continue;
        k = (int)((v[i] - lo) / (hi - lo) * 16.0f);
        k = k < 0 ? 0 : k > 15 ? 15 : k;
        hist[k] += 1;
        count++;
    }
    for (b = 0; b < 16; b++) hist[b] /= count ? (double)count : 1.0;
}

static double l1(const double *a, const double *b)
{
    double s = 0;
    int i;
    for (i = 0; i < 16; i++) s += fabs(a[i] - b[i]);
    return s;
}

static void gradient(const float *h, int n, float *g)
{
    int x, y;
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            float gx = h[y * n + (x + 1 < n ? x + 1 : x)] - h[y * n + (x ? x - 1 : x)];
            float gy = h[(y + 1 < n ? y + 1 : y) * n + x] - h[(y ? y - 1 : y) * n + x];
            g[y * n + x] = 0.5f * sqrtf(gx * gx + gy * gy);
        }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static float percentile(float *v, size_t n, double q)
{
    qsort(v, n, sizeof *v, cmp_float);
    return n ? v[(size_t)(q * (double)(n - 1))] : 0.0f;
}

/* mean under white strokes - mean under black strokes, in units of the example's range */
static double stroke_contrast(const float *out, const float *sketch, size_t n)
{
    double w = 0, b = 0;
    size_t i, nw = 0, nb = 0;
    for (i = 0; i < n; i++) {
        if (sketch[i] > 0.75f) { w += out[i]; nw++; }
        if (sketch[i] < 0.25f) { b += out[i]; nb++; }
    }
    return w / (double)nw - b / (double)nb;
}

/* the 95th percentiles of |height step| across seams and between neighbours of one patch */
static void seam_steps(const float *out, const uint8_t *seams, int n, float *across, float *inside)
{
    int x, y;
    float *a = (float *)malloc(sizeof(float) * 2 * (size_t)n * n), *in = (float *)malloc(sizeof(float) * 2 * (size_t)n * n);
    size_t na = 0, ni = 0;
    for (y = 0; y < n; y++)
        for (x = 0; x < n; x++) {
            float v = out[y * n + x];
            if (x + 1 < n) { float d = fabsf(out[y * n + x + 1] - v); if (seams[y * n + x] & 1) a[na++] = d; else in[ni++] = d; }
            if (y + 1 < n) { float d = fabsf(out[(y + 1) * n + x] - v); if (seams[y * n + x] & 2) a[na++] = d; else in[ni++] = d; }
        }
    *across = percentile(a, na, 0.95);
    *inside = percentile(in, ni, 0.95);
    free(a);
    free(in);
}

static int cancel_at(void *user, float done) { (void)done; return --*(int *)user <= 0; }

static void test_synthesis(void)
{
    int E = 192, N = 256; /* not smaller under TEST_SANITIZE: the histograms need enough patches */
    size_t n = (size_t)N * N, i;
    float *ex = (float *)malloc(sizeof(float) * (size_t)E * E), *sk = (float *)malloc(sizeof(float) * n);
    float *g_ex = (float *)malloc(sizeof(float) * (size_t)E * E), *g_out = (float *)malloc(sizeof(float) * n);
    uint8_t *seams = (uint8_t *)malloc(n), *away = (uint8_t *)malloc(n);
    rl_map example = {E, E, ex}, sketch = {N, N, sk}, out, out2, plain;
    rl_synth_options o = rl_synth_default_options();
    double hh_ex[16], hh_out[16], hg_ex[16], hg_out[16], contrast, d_h, d_g;
    float across, inside, gmax;
    make_rock(ex, E);
    make_sketch(sk, N);
    o.patch = 48;
    o.seams = seams;
    T_EQ_INT(rl_synthesize(&example, &sketch, &o, &out), RL_OK);
    if (!out.data) return;
    contrast = stroke_contrast(out.data, sk, n);
    printf("synthesis: mean under white - under black = %.3f of the example's range\n", contrast);
    T_CHECK(contrast >= 0.5);
    {   /* away from the strokes: farther than half a patch (the feature patches, which carry the
           example's most prominent crests and valleys, reach that far) from any stroke texel */
        for (i = 0; i < n; i++) away[i] = sk[i] > 0.75f || sk[i] < 0.25f;
        {
            float *dist = (float *)malloc(sizeof(float) * n);
            rl_allocator a = rl__allocator(NULL);
            rl__distance(away, 1, N, N, &a, dist);
            for (i = 0; i < n; i++) away[i] = dist[i] > 0.5f * (float)o.patch; /* beyond the feature patches' reach */
            free(dist);
        }
        gradient(ex, E, g_ex);
        gradient(out.data, N, g_out);
        {
            float *tmp = (float *)malloc(sizeof(float) * (size_t)E * E);
            memcpy(tmp, g_ex, sizeof(float) * (size_t)E * E);
            gmax = percentile(tmp, (size_t)E * E, 0.99) * 1.5f;
            free(tmp);
        }
        histogram(ex, NULL, (size_t)E * E, 0.0f, 1.0f, hh_ex);
        histogram(out.data, away, n, 0.0f, 1.0f, hh_out);
        histogram(g_ex, NULL, (size_t)E * E, 0.0f, gmax, hg_ex);
        histogram(g_out, away, n, 0.0f, gmax, hg_out);
        d_h = l1(hh_ex, hh_out);
        d_g = l1(hg_ex, hg_out);
        printf("material away from the strokes (16 bins): height histogram L1 %.3f, gradient histogram L1 %.3f\n", d_h, d_g);
        printf("  height   example:"); for (i = 0; i < 16; i++) printf(" %.3f", hh_ex[i]); printf("\n");
        printf("  height   output: "); for (i = 0; i < 16; i++) printf(" %.3f", hh_out[i]); printf("\n");
        printf("  gradient example:"); for (i = 0; i < 16; i++) printf(" %.3f", hg_ex[i]); printf("\n");
        printf("  gradient output: "); for (i = 0; i < 16; i++) printf(" %.3f", hg_out[i]); printf("\n");
        T_CHECK(d_h <= 0.1);
        T_CHECK(d_g <= 0.1);
    }
    seam_steps(out.data, seams, N, &across, &inside);
    printf("seams: 95th percentile step across %.4f, inside patches %.4f (ratio %.2f)\n", across, inside, across / inside);
    T_CHECK(across <= 1.5f * inside);
    T_EQ_INT(rl_synthesize(&example, &sketch, &o, &out2), RL_OK);
    T_CHECK(out2.data && memcmp(out.data, out2.data, sizeof(float) * n) == 0);
    rl_map_free(&out2, NULL);
    {   /* without blending, and without the extra stroke relief: reported, for comparison */
        rl_synth_options p = o;
        float a2, i2;
        p.blend_band = -1;
        if (rl_synthesize(&example, &sketch, &p, &plain) == RL_OK) {
            seam_steps(plain.data, seams, N, &a2, &i2);
            printf("  without Poisson blending: across %.4f, inside %.4f (ratio %.2f)\n", a2, i2, a2 / i2);
            rl_map_free(&plain, NULL);
        }
        p = o;
        p.emphasis = -1.0f;
        if (rl_synthesize(&example, &sketch, &p, &plain) == RL_OK) {
            printf("  pure synthesis (emphasis off): white - black = %.3f of the range\n", stroke_contrast(plain.data, sk, n));
            rl_map_free(&plain, NULL);
        }
    }
    rl_map_free(&out, NULL);
    T_EQ_INT(rl_emboss(&example, &sketch, NULL, &out), RL_OK);
    contrast = stroke_contrast(out.data, sk, n);
    printf("emboss baseline: white - black = %.3f of the range\n", contrast);
    T_CHECK(contrast >= 0.5);
    rl_map_free(&out, NULL);

    /* bad input */
    {
        rl_map small = {20, 20, ex}, empty = {0, 5, ex};
        float keep = sk[3];
        for (i = 0; i < n; i++) g_out[i] = 0.5f;
        {
            rl_map blank = {N, N, g_out};
            T_EQ_INT(rl_synthesize(&example, &blank, &o, &out), RL_ERR_NO_STROKES);
            T_EQ_INT(rl_emboss(&example, &blank, &o, &out), RL_ERR_NO_STROKES);
        }
        T_EQ_INT(rl_synthesize(&small, &sketch, &o, &out), RL_ERR_PATCH_TOO_LARGE);
        T_EQ_INT(rl_synthesize(&empty, &sketch, &o, &out), RL_ERR_EMPTY);
        T_EQ_INT(rl_synthesize(NULL, &sketch, &o, &out), RL_ERR_INVALID_ARGUMENT);
        sk[3] = NAN;
        T_EQ_INT(rl_synthesize(&example, &sketch, &o, &out), RL_ERR_NOT_FINITE);
        sk[3] = keep;
        ex[7] = INFINITY;
        T_EQ_INT(rl_emboss(&example, &sketch, &o, &out), RL_ERR_NOT_FINITE);
        T_CHECK(out.data == NULL);
        make_rock(ex, E);
        /* issue 21 point 2, found by fuzz_relief: finite input whose result is not finite. A
           stroke width of 1e-30 squared underflows, so the profile's exponent on a stroke was
           -inf * 0 = NaN (even with emphasis off); heights of +-3e38 make the range, and with it
           the emphasis, overflow: RL_ERR_NOT_FINITE instead of RL_OK with NaN/Inf */
        {
            rl_synth_options t = rl_synth_default_options();
            int finite = 1;
            t.stroke_width = 1e-30f;
            T_EQ_INT(rl_emboss(&example, &sketch, &t, &out), RL_OK);
            for (i = 0; i < n && out.data; i++) finite &= isfinite(out.data[i]) != 0;
            T_CHECK(finite);
            rl_map_free(&out, NULL);
            t.emphasis = -1.0f;
            T_EQ_INT(rl_emboss(&example, &sketch, &t, &out), RL_OK);
            for (i = 0; i < n && out.data; i++) finite &= isfinite(out.data[i]) != 0;
            T_CHECK(finite);
            rl_map_free(&out, NULL);
            ex[5] = 3e38f;
            ex[6] = -3e38f;
            T_EQ_INT(rl_emboss(&example, &sketch, NULL, &out), RL_ERR_NOT_FINITE);
            T_CHECK(out.data == NULL);
            make_rock(ex, E);
        }
    }
    {   /* cancellation at several points, and failing each allocation in turn, on a small case */
        rl_map ex2 = {40, 40, ex}, sk2 = {40, 40, sk};
        fail_alloc f;
        rl_allocator a;
        long k;
        int leaks = 0, wrong = 0, c;
        make_rock(ex, 40);
        make_sketch(sk, 40);
        a.alloc = fa_alloc; a.free = fa_free; a.user = &f;
        o.patch = 12;
        o.seams = NULL;
        o.allocator = &a;
        for (c = 1; c <= 6; c++) {
            int left = c;
            memset(&f, 0, sizeof f);
            o.progress = cancel_at; o.progress_user = &left;
            wrong += rl_synthesize(&ex2, &sk2, &o, &out) != RL_CANCELLED;
            leaks += f.live != 0;
        }
        o.progress = NULL;
        for (k = 1; k < 100000; k++) {
            rl_result r;
            memset(&f, 0, sizeof f);
            f.fail_at = k;
            r = rl_synthesize(&ex2, &sk2, &o, &out);
            if (r == RL_OK) { rl_map_free(&out, &a); leaks += f.live != 0; break; }
            if (r != RL_ERR_OUT_OF_MEMORY || out.data != NULL) { wrong++; printf("  allocation %ld failed: %s\n", k, rl_result_string(r)); break; }
            leaks += f.live != 0;
        }
        printf("allocation failure: %ld allocations tried one by one\n", k);
        T_EQ_INT(wrong, 0);
        T_EQ_INT(leaks, 0);
    }
    free(ex); free(sk); free(g_ex); free(g_out); free(seams); free(away);
}

/* ---- the program: exit statuses on good and bad input -------------------------------------- */

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    T_CHECK_MSG(f != NULL, "cannot write %s", path);
    if (!f) return;
    if (n) T_CHECK(fwrite(data, 1, n, f) == n);
    fclose(f);
}

/* runs PROG ARGS (output to DIR/cli.log) with DIR/out.png removed first; the exit status, or
   1000 + the signal */
static int run_cli(const char *prog, const char *dir, const char *args)
{
    char cmd[4096], out[1024], here[1024] = "";
    int st;
    snprintf(out, sizeof out, "%s/out.png", dir);
    remove(out);
    if (prog[0] != '/' && !getcwd(here, sizeof here)) return -1;
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s%s%s' %s >>cli.log 2>&1", dir, here, here[0] ? "/" : "", prog, args);
    st = system(cmd);
    if (st == -1) return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 1000 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
}

static int file_exists(const char *dir, const char *name)
{
    char path[1024];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "rb");
    if (f) fclose(f);
    return f != NULL;
}

static void test_cli(const char *prog, const char *dir)
{
    static const struct { const char *args; int status; } cases[] = {
        {"gen:rock text:R", 2},                                   /* no -o */
        {"gen:rock text:R -o out.png --bogus", 2},
        {"gen:rock text:R -o out.png --patch 0", 2},
        {"missing.png text:R -o out.png", 1},
        {"trunc.png text:R -o out.png", 1},
        {"trunc.pgm text:R -o out.png", 1},
        {"empty.pgm text:R -o out.png", 1},
        {"nan.pfm text:R -o out.png", 1},
        {"gen:rock trunc.png -o out.png", 1},
        {"gen:rock nostroke.txt -o out.png", 1},
        {"gen:rock badline.txt -o out.png", 1},
        {"tiny.pgm text:R -o out.png --size 64", 1},              /* patch 48 larger than the 8x8 example */
        {"big.pgm text:R -o out.png --crop 40,40,32", 1},        /* the crop leaves the 64x64 example */
        {"gen:rock blank.pgm -o out.png", 1},                     /* a sketch image without strokes */
    };
    static const unsigned char png_sig[12] = {0x89, 'P', 'N', 'G', 13, 10, 26, 10, 0, 0, 0, 13};
    unsigned char tiny[11 + 64], big[13 + 64 * 64], blank[13 + 64 * 64], pfm[12 + 4 * 64];
    float nan_value = NAN;
    char path[1024], cmd[1200];
    size_t k;
    int i, st;
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
    T_CHECK(system(cmd) == 0);
#define CLI_FILE(name, data, n) (snprintf(path, sizeof path, "%s/%s", dir, name), write_bytes(path, data, n))
    CLI_FILE("trunc.png", png_sig, sizeof png_sig);
    CLI_FILE("trunc.pgm", "P5\n4 4\n255\nab", 13);
    CLI_FILE("empty.pgm", "P5\n0 0\n255\n", 11);
    CLI_FILE("nostroke.txt", "size 64 64\n", 11);
    CLI_FILE("badline.txt", "size 64 64\nwhite 1,1 nonsense\n", 31);
    memcpy(tiny, "P5\n8 8\n255\n", 11);
    for (i = 0; i < 64; i++) tiny[11 + i] = (unsigned char)(4 * i);
    CLI_FILE("tiny.pgm", tiny, sizeof tiny);
    memcpy(big, "P5\n64 64\n255\n", 13);
    for (i = 0; i < 64 * 64; i++) big[13 + i] = (unsigned char)(i * 7);
    CLI_FILE("big.pgm", big, sizeof big);
    memcpy(blank, "P5\n64 64\n255\n", 13);
    memset(blank + 13, 128, sizeof blank - 13);
    CLI_FILE("blank.pgm", blank, sizeof blank);
    memcpy(pfm, "Pf\n8 8\n-1.0\n", 12);
    for (i = 0; i < 64; i++) memcpy(pfm + 12 + 4 * i, &nan_value, 4);
    CLI_FILE("nan.pfm", pfm, sizeof pfm);
#undef CLI_FILE
    st = run_cli(prog, dir, "gen:rock text:R --size 96 --frame 120x90 -o out.png");
    T_CHECK_MSG(st == 0, "good run: status %d", st);
    T_CHECK(file_exists(dir, "out.png"));
    for (k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        st = run_cli(prog, dir, cases[k].args);
        T_CHECK_MSG(st == cases[k].status, "relief %s: status %d, expected %d", cases[k].args, st, cases[k].status);
        T_CHECK_MSG(!file_exists(dir, "out.png"), "relief %s wrote its output", cases[k].args);
    }
    printf("relief program: 1 good run, %d bad ones with their statuses\n", (int)k);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    if (argc == 4 && strcmp(argv[1], "--cli") == 0) {
        test_cli(argv[2], argv[3]);
        return T_END();
    }
    g_small = getenv("TEST_SANITIZE") != NULL;
    test_normal_map();
    test_skeleton();
    test_loop_elimination();
    test_graph_cut();
    test_synthesis();
    return T_END();
}
