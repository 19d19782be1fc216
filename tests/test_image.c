/* test_image.c - examples/render.h's image readers and the 16-bit PNG writer, without outside
   decoders (tests/ref_png.cpp checks the PNG decoder against libpng):
   - round trips: 8-bit PNG (1, 3, 4 channels), 16-bit PNG (1-4 channels, flipped or not), PFM
     (1 and 3 channels) give back exactly the samples written;
   - PGM / PPM / PFM parsing: ASCII and binary, 8- and 16-bit, comments, both PFM byte orders,
     with hand-written files whose samples are known;
   - a hand-made PNG with stored deflate blocks, split IDAT and every filter type decodes to its
     known samples;
   - strictness: every truncation of small PNG, PGM and PFM files gives an error (never SR_OK,
     never a crash); every single-byte change of a PNG gives an error (every byte lies under a
     CRC, the signature or a length); a wrong Adler-32 under a good CRC gives SR_ERR_CHECKSUM; a
     bad block type SR_ERR_CORRUPT; oversized and zero sizes SR_ERR_TOO_LARGE / SR_ERR_CORRUPT;
     samples above maxval and NaN in PFM SR_ERR_CORRUPT;
   - allocation failure: for every k, failing the k-th allocation gives SR_ERR_OUT_OF_MEMORY and
     leaves nothing allocated, for PNG (also interlaced-free and 16-bit), PGM, PFM and the writer. */
#define _POSIX_C_SOURCE 200809L
#define SR_IMPLEMENTATION
#include "render.h"
#include "failalloc.h"
#include "test.h"

#include <stdlib.h>
#include <unistd.h>

static uint32_t lcg(uint32_t *s) { *s = *s * 1664525u + 1013904223u; return *s >> 8; }

/* counting allocator that fails the k-th allocation (k = 0: never) */

/* a test image: noise, runs and gradients, so that literals and matches both occur */
static void fill(uint16_t *s, int w, int h, int ch, unsigned maxv, uint32_t seed)
{
    int x, y, c;
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++)
            for (c = 0; c < ch; c++) {
                unsigned v = y * 3 < h ? lcg(&seed) : y * 3 < 2 * h ? (unsigned)(x / 4) * 999u + (unsigned)c : (unsigned)(x * 211 + y * 97 + c * 5000);
                s[((size_t)y * w + x) * ch + c] = (uint16_t)(v % (maxv + 1u));
            }
}

static void test_png_round_trips(void)
{
    int ch, flip, W = 53, H = 31, ok8 = 1, ok16 = 1;
    size_t n = (size_t)W * H * 4;
    uint16_t *s = (uint16_t *)malloc(n * 2);
    uint8_t *s8 = (uint8_t *)malloc(n);
    for (ch = 1; ch <= 4; ch++)
        for (flip = 0; flip < 2; flip++) {
            uint8_t *png = NULL;
            size_t size = 0, i, m = (size_t)W * H * (size_t)ch, row = (size_t)W * (size_t)ch;
            sr_picture p;
            int y, same = 1;
            fill(s, W, H, ch, 65535, (uint32_t)(ch * 7 + flip));
            T_EQ_INT(sr_encode_png16(s, W, H, ch, flip, NULL, &png, &size), SR_OK);
            T_EQ_INT(sr_decode_png(png, size, NULL, &p), SR_OK);
            T_CHECK(p.width == W && p.height == H && p.channels == ch && p.bit_depth == 16 && p.max_value == 65535 && !p.floats);
            for (y = 0; y < H && p.samples; y++)
                same &= memcmp(p.samples + (size_t)y * row, s + (size_t)(flip ? H - 1 - y : y) * row, row * 2) == 0;
            ok16 &= same && p.samples != NULL;
            sr_picture_free(&p);
            sr_free(NULL, png);
            if (ch == 2) continue;
            for (i = 0; i < m; i++) s8[i] = (uint8_t)s[i];
            T_EQ_INT(sr_encode_png(s8, W, H, ch, flip, NULL, &png, &size), SR_OK);
            T_EQ_INT(sr_decode_png(png, size, NULL, &p), SR_OK);
            T_CHECK(p.width == W && p.height == H && p.channels == ch && p.bit_depth == 8 && p.max_value == 255);
            for (y = 0, same = 1; y < H && p.samples; y++)
                for (i = 0; i < row; i++) same &= p.samples[(size_t)y * row + i] == s8[(size_t)(flip ? H - 1 - y : y) * row + i];
            ok8 &= same && p.samples != NULL;
            sr_picture_free(&p);
            sr_free(NULL, png);
        }
    T_CHECK(ok16);
    T_CHECK(ok8);
    free(s);
    free(s8);
}

static void test_pfm_round_trip(void)
{
    int ch, W = 17, H = 9;
    char path[256];
    float *f = (float *)malloc(sizeof(float) * W * H * 3), *one = (float *)malloc(sizeof(float) * W * H);
    uint32_t seed = 3;
    for (ch = 1; ch <= 3; ch += 2) {
        size_t i, n = (size_t)W * H * (size_t)ch;
        sr_picture p;
        int same = 1;
        for (i = 0; i < n; i++) f[i] = ((float)lcg(&seed) - 8388608.0f) * 1e-3f;
        snprintf(path, sizeof path, "/tmp/test_image_%ld_%d.pfm", (long)getpid(), ch);
        T_EQ_INT(sr_write_pfm(path, f, W, H, ch), SR_OK);
        T_EQ_INT(sr_read_image(path, NULL, &p), SR_OK);
        T_CHECK(p.width == W && p.height == H && p.channels == ch && p.bit_depth == 32 && p.floats && !p.samples);
        for (i = 0; p.floats && i < n; i++) same &= memcmp(&p.floats[i], &f[i], 4) == 0;
        T_CHECK(same);
        T_EQ_INT(sr_picture_channel(&p, ch - 1, one), SR_OK);
        T_CHECK(one[5] == f[5 * (size_t)ch + (size_t)ch - 1]);
        T_EQ_INT(sr_picture_channel(&p, ch, one), SR_ERR_INVALID_ARGUMENT);
        sr_picture_free(&p);
        remove(path);
    }
    T_EQ_INT(sr_read_image("/nonexistent/dir/x.png", NULL, NULL), SR_ERR_INVALID_ARGUMENT);
    {
        sr_picture p;
        T_EQ_INT(sr_read_image("/nonexistent/dir/x.png", NULL, &p), SR_ERR_IO);
        T_CHECK(!p.samples && !p.floats);
    }
    free(f);
    free(one);
}

static sr_result decode_text(const char *s, size_t n, sr_picture *p) { return sr_decode_image((const uint8_t *)s, n, NULL, p); }

static void test_pnm(void)
{
    sr_picture p;
    /* P2 with comments and odd spacing: 3x2, maxval 1000 */
    static const char p2[] = "P2 # grey\n3 2\n#c\n1000\n0 1 2\n999 1000\t500\n";
    /* P5 16-bit: 2x1, maxval 65535, samples 0x1234 and 0xFFFE (big-endian) */
    static const char p5[] = "P5\n2 1\n65535\n\x12\x34\xff\xfe";
    static const char p6[] = "P6 1 1 255 \x01\x02\x03";
    static const char p3[] = "P3 1 1 7 1 2 3";
    /* PFM big-endian (positive scale) 1x1 grey 1.5 = 0x3FC00000; little-endian -2.0 = 0xC0000000 */
    static const char pfm_be[] = "Pf\n1 1\n1.0\n\x3f\xc0\x00\x00";
    static const char pfm_le[] = "Pf 1 1 -0.5e0\n\x00\x00\x00\xc0";
    static const char pfm_nan[] = "Pf 1 1 -1\n\x00\x00\xc0\x7f";
    float v[6];
    T_EQ_INT(decode_text(p2, sizeof p2 - 1, &p), SR_OK);
    T_CHECK(p.width == 3 && p.height == 2 && p.channels == 1 && p.max_value == 1000 && p.bit_depth == 10);
    T_CHECK(p.samples && p.samples[0] == 0 && p.samples[2] == 2 && p.samples[3] == 999 && p.samples[4] == 1000 && p.samples[5] == 500);
    T_EQ_INT(sr_picture_channel(&p, 0, v), SR_OK);
    T_CHECK(v[4] == 1.0f && v[5] == 0.5f);
    sr_picture_free(&p);
    T_EQ_INT(decode_text(p5, sizeof p5 - 1, &p), SR_OK);
    T_CHECK(p.width == 2 && p.height == 1 && p.bit_depth == 16 && p.samples && p.samples[0] == 0x1234 && p.samples[1] == 0xFFFE);
    sr_picture_free(&p);
    T_EQ_INT(decode_text(p6, sizeof p6 - 1, &p), SR_OK);
    T_CHECK(p.channels == 3 && p.samples && p.samples[0] == 1 && p.samples[1] == 2 && p.samples[2] == 3);
    sr_picture_free(&p);
    T_EQ_INT(decode_text(p3, sizeof p3 - 1, &p), SR_OK);
    T_CHECK(p.channels == 3 && p.max_value == 7 && p.bit_depth == 3 && p.samples && p.samples[2] == 3);
    sr_picture_free(&p);
    T_EQ_INT(decode_text(pfm_be, sizeof pfm_be - 1, &p), SR_OK);
    T_CHECK(p.floats && p.floats[0] == 1.5f);
    sr_picture_free(&p);
    T_EQ_INT(decode_text(pfm_le, sizeof pfm_le - 1, &p), SR_OK);
    T_CHECK(p.floats && p.floats[0] == -2.0f);
    sr_picture_free(&p);
    T_EQ_INT(decode_text(pfm_nan, sizeof pfm_nan - 1, &p), SR_ERR_CORRUPT);
    T_EQ_INT(decode_text("P2 2 1 10 3 11", 14, &p), SR_ERR_CORRUPT);       /* sample above maxval */
    T_EQ_INT(decode_text("P5 1 1 0 \x01", 10, &p), SR_ERR_CORRUPT);        /* maxval 0 */
    T_EQ_INT(decode_text("P5 1 1 65536 \x01", 14, &p), SR_ERR_CORRUPT);    /* maxval too large */
    T_EQ_INT(decode_text("P5 0 1 255 ", 11, &p), SR_ERR_CORRUPT);
    T_EQ_INT(decode_text("P5 40000 1 255 ", 15, &p), SR_ERR_TOO_LARGE);
    T_EQ_INT(decode_text("P5 30000 30000 255 ", 19, &p), SR_ERR_TOO_LARGE); /* 9e8 samples > 2^28 */
    T_EQ_INT(decode_text("P5 99999999999 1 255 ", 21, &p), SR_ERR_CORRUPT);
    T_EQ_INT(decode_text("Pf 1 1 0.0\n\0\0\0\0", 15, &p), SR_ERR_CORRUPT); /* scale 0 */
    T_EQ_INT(decode_text("P4 1 1\n\0", 8, &p), SR_ERR_UNSUPPORTED);
    T_EQ_INT(decode_text("GIF89a", 6, &p), SR_ERR_UNSUPPORTED);
    T_EQ_INT(decode_text("", 0, &p), SR_ERR_TRUNCATED);
    T_CHECK(!p.samples && !p.floats);
    {   /* every truncation of the binary files is an error */
        const char *files[4] = {p5, p6, pfm_be, p2};
        size_t sizes[4] = {sizeof p5 - 1, sizeof p6 - 1, sizeof pfm_be - 1, sizeof p2 - 1};
        int k, bad = 0;
        size_t len;
        for (k = 0; k < 4; k++)
            for (len = 0; len < sizes[k]; len++) {
                /* an ASCII file may end inside its last sample, "500\n": "... 5" is a valid P2 ending in 5 */
                if (k == 3 && len >= sizes[k] - 3) continue;
                if (decode_text(files[k], len, &p) == SR_OK) { bad++; sr_picture_free(&p); }
            }
        T_EQ_INT(bad, 0);
    }
}

/* ---- hand-made PNGs ------------------------------------------------------------------------ */

typedef struct bytes { uint8_t d[4096]; size_t n; } bytes;
static void put(bytes *b, const void *p, size_t n) { memcpy(b->d + b->n, p, n); b->n += n; }
static void put32(bytes *b, uint32_t v) { uint8_t s[4] = {(uint8_t)(v >> 24), (uint8_t)(v >> 16), (uint8_t)(v >> 8), (uint8_t)v}; put(b, s, 4); }
static uint32_t crc32_ref(const uint8_t *p, size_t n) /* bitwise, independent of render.h's table */
{
    uint32_t c = 0xFFFFFFFFu;
    size_t i;
    int k;
    for (i = 0; i < n; i++) { c ^= p[i]; for (k = 0; k < 8; k++) c = (c & 1) ? (c >> 1) ^ 0xEDB88320u : c >> 1; }
    return ~c;
}
static void chunk(bytes *b, const char *type, const uint8_t *d, size_t n)
{
    size_t at;
    put32(b, (uint32_t)n);
    at = b->n;
    put(b, type, 4);
    if (n) put(b, d, n);
    put32(b, crc32_ref(b->d + at, n + 4));
}
static void ihdr(bytes *b, uint32_t w, uint32_t h, int depth, int color)
{
    uint8_t d[13] = {0};
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    b->n = 0;
    put(b, sig, 8);
    d[0] = (uint8_t)(w >> 24); d[1] = (uint8_t)(w >> 16); d[2] = (uint8_t)(w >> 8); d[3] = (uint8_t)w;
    d[4] = (uint8_t)(h >> 24); d[5] = (uint8_t)(h >> 16); d[6] = (uint8_t)(h >> 8); d[7] = (uint8_t)h;
    d[8] = (uint8_t)depth; d[9] = (uint8_t)color;
    chunk(b, "IHDR", d, 13);
}
/* zlib stream of stored blocks of at most `block` bytes each */
static size_t zlib_stored(const uint8_t *raw, size_t n, size_t block, uint8_t *z)
{
    size_t o = 0, i = 0;
    uint32_t s1 = 1, s2 = 0;
    z[o++] = 0x78; z[o++] = 0x01;
    do {
        size_t k = n - i < block ? n - i : block;
        z[o++] = (uint8_t)(i + k == n);
        z[o++] = (uint8_t)k; z[o++] = (uint8_t)(k >> 8); z[o++] = (uint8_t)~k; z[o++] = (uint8_t)(~k >> 8);
        memcpy(z + o, raw + i, k);
        o += k; i += k;
    } while (i < n);
    for (i = 0; i < n; i++) { s1 = (s1 + raw[i]) % 65521u; s2 = (s2 + s1) % 65521u; }
    z[o++] = (uint8_t)(s2 >> 8); z[o++] = (uint8_t)s2; z[o++] = (uint8_t)(s1 >> 8); z[o++] = (uint8_t)s1;
    return o;
}

/* 4x5 RGB 8-bit: row y uses filter y (0..4); the filtered bytes are made here from known samples */
static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}
static void make_filtered_png(bytes *b, uint8_t *samples, size_t split)
{
    enum { W = 4, H = 5, C = 3, RB = W * C };
    uint8_t raw[H * (RB + 1)], z[512];
    size_t zn;
    int x, y;
    uint32_t seed = 9;
    for (x = 0; x < W * H * C; x++) samples[x] = (uint8_t)lcg(&seed);
    for (y = 0; y < H; y++) {
        uint8_t *o = raw + y * (RB + 1);
        const uint8_t *r = samples + y * RB, *up = y ? samples + (y - 1) * RB : NULL;
        o[0] = (uint8_t)y;
        for (x = 0; x < RB; x++) {
            int a = x >= C ? r[x - C] : 0, bb = up ? up[x] : 0, c = up && x >= C ? up[x - C] : 0;
            int pred = y == 0 ? 0 : y == 1 ? a : y == 2 ? bb : y == 3 ? (a + bb) / 2 : paeth(a, bb, c);
            o[1 + x] = (uint8_t)(r[x] - pred);
        }
    }
    zn = zlib_stored(raw, sizeof raw, 7, z);
    ihdr(b, W, H, 8, 2);
    chunk(b, "tEXt", (const uint8_t *)"Comment\0hand-made", 17);
    chunk(b, "IDAT", z, split);
    chunk(b, "IDAT", z + split, zn - split);
    chunk(b, "IEND", NULL, 0);
}

static void test_png_handmade(void)
{
    bytes b;
    uint8_t samples[60];
    sr_picture p;
    int i, same = 1;
    make_filtered_png(&b, samples, 10);
    T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_OK);
    T_CHECK(p.width == 4 && p.height == 5 && p.channels == 3);
    for (i = 0; p.samples && i < 60; i++) same &= p.samples[i] == samples[i];
    T_CHECK(same && p.samples);
    sr_picture_free(&p);
    {   /* grey 2-bit 5x1 (0,1,2,3,2) stored: bytes 0b00011011 0b10xxxxxx */
        uint8_t raw[3] = {0, 0x1B, 0x80}, z[64];
        size_t zn = zlib_stored(raw, 3, 100, z);
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_OK);
        T_CHECK(p.samples && p.max_value == 3 && p.samples[0] == 0 && p.samples[1] == 1 && p.samples[2] == 2 && p.samples[3] == 3 && p.samples[4] == 2);
        sr_picture_free(&p);
        /* the same with a palette of 3 entries: index 3 is outside it */
        ihdr(&b, 5, 1, 2, 3);
        chunk(&b, "PLTE", (const uint8_t *)"\1\2\3\4\5\6\7\10\11", 9);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        /* palette image without PLTE */
        ihdr(&b, 5, 1, 2, 3);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        /* an unknown critical chunk */
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "ABCD", NULL, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_UNSUPPORTED);
        /* filter type 5 */
        raw[0] = 5;
        zn = zlib_stored(raw, 3, 100, z);
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        /* too much image data: 4 bytes for a 3-byte image */
        zn = zlib_stored((const uint8_t *)"\0\0\0\0", 4, 100, z);
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        /* too little */
        zn = zlib_stored((const uint8_t *)"\0\0", 2, 100, z);
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        /* a wrong Adler-32 under a correct CRC */
        zn = zlib_stored((const uint8_t *)"\0\0\0", 3, 100, z);
        z[zn - 1] ^= 1;
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CHECKSUM);
        /* block type 3 */
        z[2] = 0x07;
        ihdr(&b, 5, 1, 2, 0);
        chunk(&b, "IDAT", z, zn);
        chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        /* sizes: zero, past the signed 31 bits, past the reader's limits, overflowing in size_t */
        ihdr(&b, 0, 1, 8, 0); chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        ihdr(&b, 0x80000000u, 1, 8, 0); chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        ihdr(&b, 40000, 1, 8, 0); chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_TOO_LARGE);
        ihdr(&b, 32768, 32768, 16, 6); chunk(&b, "IEND", NULL, 0);
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_TOO_LARGE);
        ihdr(&b, 4, 4, 3, 0); chunk(&b, "IEND", NULL, 0);  /* bit depth 3 */
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        ihdr(&b, 4, 4, 16, 3); chunk(&b, "IEND", NULL, 0); /* 16-bit palette */
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        ihdr(&b, 4, 4, 8, 0); chunk(&b, "IEND", NULL, 0);  /* no IDAT */
        T_EQ_INT(sr_decode_png(b.d, b.n, NULL, &p), SR_ERR_CORRUPT);
        T_CHECK(!p.samples);
    }
}

/* every prefix of a small PNG fails; so does every change of one byte */
static void test_png_truncation_and_damage(void)
{
    uint16_t s[8 * 6 * 4];
    uint8_t *png = NULL, *copy;
    size_t size = 0, len, i;
    int depth, bad_trunc = 0, bad_flip = 0;
    sr_picture p;
    for (depth = 8; depth <= 16; depth += 8) {
        fill(s, 8, 6, 4, depth == 16 ? 65535u : 255u, 11);
        if (depth == 16) {
            T_EQ_INT(sr_encode_png16(s, 8, 6, 4, 0, NULL, &png, &size), SR_OK);
        } else {
            uint8_t s8[8 * 6 * 4];
            for (i = 0; i < sizeof s8; i++) s8[i] = (uint8_t)s[i];
            T_EQ_INT(sr_encode_png(s8, 8, 6, 4, 0, NULL, &png, &size), SR_OK);
        }
        copy = (uint8_t *)malloc(size);
        for (len = 0; len < size; len++) { /* an exact-size copy: sanitizers see reads past the end */
            uint8_t *t = (uint8_t *)malloc(len ? len : 1);
            memcpy(t, png, len);
            if (sr_decode_png(t, len, NULL, &p) == SR_OK) { bad_trunc++; sr_picture_free(&p); }
            free(t);
        }
        for (i = 0; i < size; i++) {
            int bit;
            for (bit = 0; bit < 8; bit += 3) {
                memcpy(copy, png, size);
                copy[i] ^= (uint8_t)(1u << bit);
                if (sr_decode_png(copy, size, NULL, &p) == SR_OK) { bad_flip++; sr_picture_free(&p); }
            }
        }
        free(copy);
        sr_free(NULL, png);
    }
    T_EQ_INT(bad_trunc, 0);
    T_EQ_INT(bad_flip, 0);
}

static void test_alloc_failure(void)
{
    uint16_t s[19 * 7 * 2];
    uint8_t *png = NULL, *out;
    size_t size = 0, n;
    sr_picture p;
    const char pgm[] = "P5 3 1 255 abc", pfm[] = "PF 1 1 -1 \0\0\200?\0\0\0@\0\0@@";
    int which, leaks = 0, wrong = 0;
    fill(s, 19, 7, 2, 65535, 5);
    T_EQ_INT(sr_encode_png16(s, 19, 7, 2, 1, NULL, &png, &size), SR_OK);
    for (which = 0; which < 4; which++) {
        long k;
        for (k = 1;; k++) {
            fail_alloc f = {0, 0, 0};
            sr_allocator a;
            sr_result r;
            a.alloc = fa_alloc; a.free = fa_free; a.user = &f;
            f.fail_at = k;
            if (which == 0) r = sr_decode_png(png, size, &a, &p);
            else if (which == 1) r = sr_decode_image((const uint8_t *)pgm, sizeof pgm - 1, &a, &p);
            else if (which == 2) r = sr_decode_image((const uint8_t *)pfm, sizeof pfm - 1, &a, &p);
            else r = sr_encode_png16(s, 19, 7, 2, 0, &a, &out, &n);
            if (r == SR_OK) {
                if (which == 3) sr_free(&a, out);
                else sr_picture_free(&p);
                leaks += f.live != 0;
                break;
            }
            wrong += r != SR_ERR_OUT_OF_MEMORY;
            leaks += f.live != 0;
            if (which < 3) wrong += p.samples != NULL || p.floats != NULL;
        }
        T_CHECK_MSG(k > 1, "decoder %d allocated nothing", which);
    }
    if (1) {
        float v[3];
        T_EQ_INT(sr_decode_image((const uint8_t *)pfm, sizeof pfm - 1, NULL, &p), SR_OK);
        T_EQ_INT(sr_picture_channel(&p, 1, v), SR_OK);
        T_CHECK(v[0] == 2.0f);
        sr_picture_free(&p);
    }
    T_EQ_INT(leaks, 0);
    T_EQ_INT(wrong, 0);
    sr_free(NULL, png);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    test_png_round_trips();
    test_pfm_round_trip();
    test_pnm();
    test_png_handmade();
    test_png_truncation_and_damage();
    test_alloc_failure();
    return T_END();
}
