/* fuzz_relief.c - fuzz target for examples/relief.h: normal maps, skeletons, graph-cut seams,
   synthesis and the emboss baseline on a small exemplar and sketch decoded from the bytes.
   libFuzzer: clang -g -O1 -I. -Iexamples -Itests -fsanitize=fuzzer,address,undefined tests/fuzz_relief.c -o fuzz_relief -lm
   plain:     gcc -std=c99 -g -O1 -I. -Iexamples -Itests tests/fuzz_relief.c tests/fuzz_main.c -o fuzz_relief -lm
              && ./fuzz_relief tests/fuzz/corpus/relief
   Byte 0: the entry point (bits 0-1), raw numbers (bit 7: 4-byte floats of any bits, NaN and
   infinities included; else (b - 128) / 16); byte 1: the allocation to fail and the progress call
   that cancels (nibbles, 0 = none). Maps are at most 32 x 32 (examples) and 40 x 40 (sketches),
   patches 4..19 texels, so one run is cheap. Every call returns RL_OK with a sound result (finite
   heights of the sketch's size, unit normals, symmetric skeleton edges, seam labels that keep the
   constraints and whose cut costs the reported minimum) or a named code with nothing held and
   the outputs zeroed; a broken rule calls abort(). */
#define FZ_HELPERS_ONLY
#include "fuzz_deform.c" /* the byte reader and failing allocator */
#define RL_IMPLEMENTATION
#include "relief.h"

static int fz_known(rl_result r) { return strcmp(rl_result_string(r), "RL_ERR_?") != 0; }

/* a map of w x h (from the bytes, w and h up to max); kind 0: heights, 1: a sketch (strokes) */
static void fz_map(fz_in *in, int max, int kind, float *data, rl_map *m)
{
    int i, n;
    m->width = (int)(fz_u8(in) % (unsigned)(max + 1));
    m->height = (int)(fz_u8(in) % (unsigned)(max + 1));
    m->data = data;
    n = m->width * m->height;
    if (kind == 0) {
        unsigned f = fz_u8(in);
        for (i = 0; i < n; i++) /* a smooth bump field plus the bytes' values */
            data[i] = (float)(sin(0.7 * (i % (m->width ? m->width : 1)) + 0.3 * (double)(f & 7)) * cos(0.5 * (double)(i / (m->width ? m->width : 1)))) +
                      ((f & 8) ? fz_f32(in) : 0.0f);
    } else {
        int x0 = (int)fz_u8(in) % (m->width + 1), y0 = (int)fz_u8(in) % (m->height + 1), r = 1 + (int)fz_u8(in) % 12;
        unsigned f = fz_u8(in);
        for (i = 0; i < n; i++) { /* a ring (white) and a bar (black), or values from the bytes */
            int x = i % m->width, y = i / m->width, dx = x - x0, dy = y - y0, d2 = dx * dx + dy * dy;
            data[i] = 0.5f;
            if (d2 >= r * r && d2 <= (r + 2) * (r + 2)) data[i] = 1.0f;
            if ((f & 1) && abs(y - m->height / 2) <= 1 && x > m->width / 4) data[i] = 0.0f;
            if (f & 2) data[i] = fz_f32(in);
        }
    }
}

static void fz_map_sound(const rl_map *out, const rl_map *sketch)
{
    fz_check(out->width == sketch->width && out->height == sketch->height && out->data);
    fz_check(fz_all_finite_f(out->data, (size_t)out->width * (size_t)out->height));
}

static void fz_options(fz_in *in, rl_synth_options *o, const rl_allocator *al, fz_cancel *cc, uint8_t *seams)
{
    unsigned f = fz_u8(in);
    *o = rl_synth_default_options();
    o->patch = 4 + (int)(fz_u8(in) % 16) - ((f & 1) ? 6 : 0); /* sometimes too small or negative */
    o->overlap = (int)(fz_u8(in) % 8) - 1;
    o->candidates = (int)(fz_u8(in) % 4);
    o->search_stride = (int)(fz_u8(in) % 5);
    o->feature_candidates = 1 + (int)(fz_u8(in) % 8);
    if (f & 2) {
        o->alpha_g = fz_f32(in);
        o->alpha_f = fz_f32(in);
        o->emphasis = fz_f32(in);
        o->stroke_width = fz_f32(in);
        o->tolerance = fz_f32(in);
    }
    o->blend_band = (int)(fz_u8(in) % 6) - 1;
    o->skeleton.half_length = (int)(fz_u8(in) % 6);
    o->skeleton.threshold = (f & 4) ? fz_f32(in) : 0.0f;
    o->skeleton.prune_rounds = (int)(fz_u8(in) % 5) - 1;
    o->allocator = al;
    o->progress = (f & 8) ? fz_progress : NULL;
    o->progress_user = cc;
    o->seams = (f & 16) ? seams : NULL;
}

static void fz_synth(fz_in *in, const rl_allocator *al, fz_cancel *cc, int emboss)
{
    static float ex[32 * 32], sk[40 * 40];
    static uint8_t seams[40 * 40];
    rl_map example, sketch, out;
    rl_synth_options o;
    rl_result r;
    fz_map(in, 32, 0, ex, &example);
    fz_map(in, 40, 1, sk, &sketch);
    fz_options(in, &o, al, cc, seams);
    memset(&out, 0x55, sizeof out);
    r = emboss ? rl_emboss(&example, &sketch, &o, &out) : rl_synthesize(&example, &sketch, &o, &out);
    fz_check(fz_known(r));
    if (r != RL_OK) {
        fz_check(out.data == NULL && out.width == 0 && out.height == 0);
        return;
    }
    fz_map_sound(&out, &sketch);
    if (o.seams) {
        int i;
        for (i = 0; i < sketch.width * sketch.height; i++) fz_check(seams[i] <= 3);
    }
    rl_map_free(&out, al);
}

static void fz_normals_and_skeleton(fz_in *in, const rl_allocator *al)
{
    static float h[32 * 32], nrm[3 * 32 * 32];
    static uint8_t rgb[3 * 32 * 32];
    rl_map m;
    rl_normal_options no = rl_normal_default_options();
    rl_skeleton_options so = rl_skeleton_default_options();
    rl_skeleton s;
    rl_result r;
    unsigned f;
    int i, n;
    fz_map(in, 32, 0, h, &m);
    n = m.width * m.height;
    f = fz_u8(in);
    no.distance = (int)(fz_u8(in) % 40) - 1;
    no.strength = (f & 1) ? fz_f32(in) : 0.0f;
    no.wrap = (int)((f >> 1) & 1);
    r = rl_normal_map(h, m.width, m.height, &no, nrm);
    fz_check(fz_known(r));
    if (r == RL_OK) {
        for (i = 0; i < n; i++) {
            const float *v = nrm + 3 * i;
            float len = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            fz_check(fz_all_finite_f(v, 3) && fabsf(len - 1.0f) <= 1e-4f && v[2] >= 0.0f); /* z may underflow */
        }
        rl_normal_to_rgb8(nrm, (size_t)n, rgb);
    }
    so.half_length = (int)(fz_u8(in) % 8) - 1;
    so.threshold = (f & 4) ? fz_f32(in) : 0.0f;
    so.prune_rounds = (int)(fz_u8(in) % 6) - 1;
    so.valleys = (int)((f >> 3) & 1);
    memset(&s, 0x55, sizeof s);
    r = rl_skeleton_extract(&m, &so, al, &s);
    fz_check(fz_known(r));
    if (r != RL_OK) {
        fz_check(s.edges == NULL);
        return;
    }
    fz_check(s.width == m.width && s.height == m.height && s.edges);
    { /* symmetric: an edge to neighbour k is seen from there as the edge to k + 4 */
        static const int dx[8] = {0, 1, 1, 1, 0, -1, -1, -1}, dy[8] = {-1, -1, 0, 1, 1, 1, 0, -1};
        int x, y, k;
        for (y = 0; y < m.height; y++)
            for (x = 0; x < m.width; x++)
                for (k = 0; k < 8; k++)
                    if (s.edges[y * m.width + x] & (1u << k)) {
                        int u = x + dx[k], v = y + dy[k];
                        fz_check(u >= 0 && u < m.width && v >= 0 && v < m.height);
                        fz_check((s.edges[v * m.width + u] >> ((k + 4) & 7)) & 1u);
                    }
    }
    rl_skeleton_free(&s, al);
}

static void fz_cut(fz_in *in, const rl_allocator *al)
{
    static float a[24 * 24], b[24 * 24];
    static uint8_t c[24 * 24], labels[24 * 24];
    int w = (int)(fz_u8(in) % 25), h = (int)(fz_u8(in) % 25), i, x, y;
    unsigned f = fz_u8(in);
    double cost = -1.0, check = 0.0;
    rl_result r;
    for (i = 0; i < w * h; i++) {
        a[i] = fz_f32(in);
        b[i] = (f & 1) ? fz_f32(in) : a[i] + (float)(i % 7) * 0.125f;
        c[i] = (uint8_t)(i % w == 0 ? 1 : i % w == w - 1 ? 2 : (fz_u8(in) % 4 == 0 ? 3 : 0)); /* 3: invalid */
        if (!(f & 2) && c[i] == 3) c[i] = 0;
    }
    r = rl_graph_cut(a, b, (f & 4) ? NULL : c, w, h, al, labels, &cost);
    fz_check(fz_known(r));
    if (r != RL_OK) return;
    for (i = 0; i < w * h; i++) {
        fz_check(labels[i] <= 1);
        if (!(f & 4) && c[i]) fz_check(labels[i] == c[i] - 1); /* the constraints hold */
    }
    for (y = 0; y < h; y++) /* the labels' cut cost is the reported minimum */
        for (x = 0; x < w; x++) {
            int s = y * w + x;
            if (x + 1 < w && labels[s] != labels[s + 1])
                check += fabs((double)a[s] - b[s]) + fabs((double)a[s + 1] - b[s + 1]);
            if (y + 1 < h && labels[s] != labels[s + w])
                check += fabs((double)a[s] - b[s]) + fabs((double)a[s + w] - b[s + w]);
        }
    fz_check(cost >= 0.0 && fabs(check - cost) <= 1e-4 * (check + 1.0));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in in;
    fz_heap h;
    fz_cancel c;
    rl_allocator a;
    unsigned op = fz_begin(&in, data, size, &h, &c);
    FZ_HEAP_ALLOCATOR(a, &h);
    switch (op & 3) {
    case 0: fz_synth(&in, &a, &c, 0); break;
    case 1: fz_synth(&in, &a, &c, 1); break;
    case 2: fz_normals_and_skeleton(&in, &a); break;
    default: fz_cut(&in, &a); break;
    }
    fz_check(h.live == 0 && h.bytes == 0); /* nothing held after any result */
    return 0;
}
