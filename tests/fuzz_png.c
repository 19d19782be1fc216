/* fuzz_png.c - fuzz target for the image readers of examples/render.h (PNG, PGM / PPM, PFM)
   libFuzzer: clang -g -O1 -Iexamples -fsanitize=fuzzer,address,undefined tests/fuzz_png.c -o fuzz_png -lm
   plain:     gcc -std=c99 -g -O1 -Iexamples tests/fuzz_png.c tests/fuzz_main.c -o fuzz_png -lm && ./fuzz_png tests/fuzz/corpus/png
   Every input must give SR_OK with a consistent picture, or a reader error with no memory held;
   a decoded picture is read in full (so that sanitizers see every sample) and decoded again,
   which must give the same bits. Allocations are limited to 64 MB so that a header promising a
   huge image fails quickly. A PNG input is also decoded once more with every chunk's CRC made
   right, so that mutations reach the inflater and the filters instead of stopping at the CRC. */
#define SR_IMPLEMENTATION
#include "render.h"
#include <stdlib.h>

typedef struct fz_alloc { size_t live; long blocks; } fz_alloc;

static void *fz_malloc(void *user, size_t n)
{
    fz_alloc *f = (fz_alloc *)user;
    size_t *p;
    if (n > ((size_t)64 << 20) - f->live) return NULL;
    p = (size_t *)malloc(n + sizeof(size_t) * 2);
    if (!p) return NULL;
    p[0] = n;
    f->live += n;
    f->blocks++;
    return p + 2;
}

static void fz_free(void *user, void *q)
{
    fz_alloc *f = (fz_alloc *)user;
    size_t *p = (size_t *)q - 2;
    f->live -= p[0];
    f->blocks--;
    free(p);
}

static uint32_t fz_crc(const uint8_t *p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    size_t i;
    int k;
    for (i = 0; i < n; i++) { c ^= p[i]; for (k = 0; k < 8; k++) c = (c & 1) ? (c >> 1) ^ 0xEDB88320u : c >> 1; }
    return ~c;
}

static int fz_one(const uint8_t *data, size_t size);

/* a copy of a PNG with each complete chunk's CRC recomputed */
static void fz_fixed_crc(const uint8_t *data, size_t size)
{
    uint8_t *d;
    size_t pos = 8;
    if (size < 8 || data[0] != 0x89) return;
    d = (uint8_t *)malloc(size);
    if (!d) return;
    memcpy(d, data, size);
    while (size - pos >= 12) {
        uint32_t n = ((uint32_t)d[pos] << 24) | ((uint32_t)d[pos + 1] << 16) | ((uint32_t)d[pos + 2] << 8) | d[pos + 3], c;
        if (n > size - pos - 12) break;
        c = fz_crc(d + pos + 4, (size_t)n + 4);
        d[pos + 8 + n] = (uint8_t)(c >> 24); d[pos + 9 + n] = (uint8_t)(c >> 16);
        d[pos + 10 + n] = (uint8_t)(c >> 8); d[pos + 11 + n] = (uint8_t)c;
        pos += 12 + (size_t)n;
    }
    fz_one(d, size);
    free(d);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_one(data, size);
    fz_fixed_crc(data, size);
    return 0;
}

static int fz_one(const uint8_t *data, size_t size)
{
    fz_alloc f = {0, 0};
    sr_allocator a;
    sr_picture p, q;
    sr_result r;
    a.alloc = fz_malloc; a.free = fz_free; a.user = &f;
    r = sr_decode_image(data, size, &a, &p);
    if (r != SR_OK) {
        if (f.blocks != 0 || p.samples || p.floats) abort();
        if (r != SR_ERR_TRUNCATED && r != SR_ERR_CORRUPT && r != SR_ERR_CHECKSUM && r != SR_ERR_UNSUPPORTED &&
            r != SR_ERR_TOO_LARGE && r != SR_ERR_OUT_OF_MEMORY) abort();
        return 0;
    } else {
        size_t i, n = (size_t)p.width * (size_t)p.height * (size_t)p.channels;
        unsigned long sum = 0;
        if (p.width < 1 || p.height < 1 || p.channels < 1 || p.channels > 4 || !(p.samples || p.floats)) abort();
        for (i = 0; i < n; i++) {
            if (p.samples && p.samples[i] > p.max_value) abort();
            sum += p.samples ? p.samples[i] : (unsigned long)(p.floats[i] != 0.0f);
        }
        if (sr_decode_image(data, size, &a, &q) != SR_OK) abort();
        if (p.samples && memcmp(p.samples, q.samples, n * 2) != 0) abort();
        if (p.floats && memcmp(p.floats, q.floats, n * 4) != 0) abort();
        sr_picture_free(&q);
        sr_picture_free(&p);
        if (f.blocks != 0) abort();
        return (int)(sum & 0);
    }
}
