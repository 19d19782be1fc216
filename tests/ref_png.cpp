/* ref_png - render.h's image readers against libpng (Debian libpng-dev, link -lpng -lz).

   Generated images: every PNG colour type and bit depth (grey 1/2/4/8/16, RGB 8/16, palette
   1/2/4/8 with and without tRNS, grey+alpha 8/16, RGBA 8/16), odd sizes (1x1 up to 37x23, so
   that Adam7 passes are empty or ragged), interlaced and not, each of the five row filters
   alone and libpng's adaptive choice, zlib levels 0 (stored blocks), 1, 6, 9 and the strategies
   Z_HUFFMAN_ONLY, Z_RLE and Z_FIXED (fixed-Huffman blocks), with IDAT split into 64-byte chunks
   for some. The content mixes noise (literals) with repeated runs (matches), so dynamic,
   fixed and stored blocks all occur. Each file is written by libpng, read back by libpng
   (palette expanded to RGB / RGBA, low depths unpacked, 16-bit kept) and by sr_decode_png:
   the samples must be identical, and so must width, height and channel count.
   Real files: every PNG in /usr/share/glmark2/textures/ (glmark2-data), the same comparison.
   Our writers: 8-bit and 16-bit PNGs from sr_encode_png / sr_encode_png16 read by libpng give
   back the samples written.
   `ref_png --seeds DIR` writes a small set of these files to DIR (the fuzz seed corpus). */
#include <png.h>
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <string>
#include <vector>

#include "test.h"
#include "hashrand.h"
#define SR_IMPLEMENTATION
#include "render.h"

struct png_case {
    int w, h, color, depth, interlace, filter, level, strategy, trns, chunk;
};

static void write_cb(png_structp p, png_bytep d, png_size_t n)
{
    std::vector<uint8_t> *v = (std::vector<uint8_t> *)png_get_io_ptr(p);
    v->insert(v->end(), d, d + n);
}
static void flush_cb(png_structp) {}

struct reader { const uint8_t *d; size_t n, pos; };
static void read_cb(png_structp p, png_bytep d, png_size_t n)
{
    reader *r = (reader *)png_get_io_ptr(p);
    if (n > r->n - r->pos) png_error(p, "short");
    memcpy(d, r->d + r->pos, n);
    r->pos += n;
}

static int channels_of(int color) { return color == 0 ? 1 : color == 2 ? 3 : color == 3 ? 1 : color == 4 ? 2 : 4; }

/* content: noise in the first third, runs of repeated values in the second, gradients after */
static unsigned sample_value(const png_case &c, int x, int y, int ch, uint64_t seed)
{
    unsigned maxv = c.color == 3 ? (1u << c.depth) - 1u : (1u << c.depth) - 1u;
    unsigned v;
    if (y * 3 < c.h) v = (unsigned)(splitmix64(seed ^ ((uint64_t)y << 32) ^ (uint64_t)(x * 8 + ch)) >> 20);
    else if (y * 3 < 2 * c.h) v = (unsigned)((x / 5) * 37 + ch * 11);
    else v = (unsigned)(x * 9 + y * 5 + ch * 70) * (c.depth == 16 ? 257u : 1u);
    return v & maxv;
}

static bool libpng_write(const png_case &c, std::vector<uint8_t> &out, uint64_t seed)
{
    png_structp p = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(p);
    int nc = channels_of(c.color);
    size_t rb = ((size_t)c.w * nc * c.depth + 7) / 8;
    std::vector<uint8_t> rows((size_t)c.h * rb, 0);
    std::vector<png_bytep> ptr(c.h);
    if (setjmp(png_jmpbuf(p))) { png_destroy_write_struct(&p, &info); return false; }
    png_set_write_fn(p, &out, write_cb, flush_cb);
    png_set_IHDR(p, info, c.w, c.h, c.depth, c.color, c.interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (c.color == 3) {
        png_color pal[256];
        png_byte alpha[256];
        int n = 1 << c.depth;
        for (int i = 0; i < n; i++) {
            pal[i].red = (png_byte)(i * 37 + 5); pal[i].green = (png_byte)(255 - i * 13); pal[i].blue = (png_byte)(i * i);
            alpha[i] = (png_byte)(255 - i * 7);
        }
        png_set_PLTE(p, info, pal, n);
        if (c.trns) png_set_tRNS(p, info, alpha, n > 40 ? 40 : n, NULL);
    }
    png_set_filter(p, 0, c.filter);
    png_set_compression_level(p, c.level);
    png_set_compression_strategy(p, c.strategy);
    if (c.chunk) png_set_compression_buffer_size(p, (size_t)c.chunk);
    for (int y = 0; y < c.h; y++) {
        uint8_t *r = &rows[(size_t)y * rb];
        ptr[y] = r;
        for (int x = 0; x < c.w; x++)
            for (int ch = 0; ch < nc; ch++) {
                unsigned v = sample_value(c, x, y, ch, seed);
                size_t i = (size_t)x * nc + ch;
                if (c.depth == 16) { r[2 * i] = (uint8_t)(v >> 8); r[2 * i + 1] = (uint8_t)v; }
                else if (c.depth == 8) r[i] = (uint8_t)v;
                else r[i * c.depth / 8] |= (uint8_t)(v << (8 - c.depth - (int)(i * c.depth % 8)));
            }
    }
    png_write_info(p, info);
    png_write_image(p, ptr.data());
    png_write_end(p, info);
    png_destroy_write_struct(&p, &info);
    return true;
}

/* libpng's reading: palette to RGB(A), low depths one sample a byte, 16-bit kept */
static bool libpng_read(const uint8_t *d, size_t n, int &w, int &h, int &nc, std::vector<uint16_t> &s)
{
    png_structp p = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(p);
    reader rd = {d, n, 0};
    std::vector<uint8_t> rows;
    std::vector<png_bytep> ptr;
    if (setjmp(png_jmpbuf(p))) { png_destroy_read_struct(&p, &info, NULL); return false; }
    png_set_read_fn(p, &rd, read_cb);
    png_read_info(p, info);
    int color = png_get_color_type(p, info), depth = png_get_bit_depth(p, info);
    if (color == PNG_COLOR_TYPE_PALETTE) {
        png_set_palette_to_rgb(p);
        if (png_get_valid(p, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(p);
    }
    if (depth < 8) png_set_packing(p);
    png_set_interlace_handling(p);
    png_read_update_info(p, info);
    w = (int)png_get_image_width(p, info);
    h = (int)png_get_image_height(p, info);
    nc = png_get_channels(p, info);
    int od = png_get_bit_depth(p, info);
    size_t rb = png_get_rowbytes(p, info);
    rows.resize(rb * h);
    ptr.resize(h);
    for (int y = 0; y < h; y++) ptr[y] = &rows[(size_t)y * rb];
    png_read_image(p, ptr.data());
    png_read_end(p, NULL);
    png_destroy_read_struct(&p, &info, NULL);
    s.resize((size_t)w * h * nc);
    for (size_t i = 0; i < s.size(); i++) {
        size_t y = i / ((size_t)w * nc), k = i % ((size_t)w * nc);
        const uint8_t *r = &rows[y * rb];
        s[i] = od == 16 ? (uint16_t)((r[2 * k] << 8) | r[2 * k + 1]) : r[k];
    }
    return true;
}

/* 1 when both decoders give the same picture */
static int same_as_libpng(const uint8_t *d, size_t n, const char *what)
{
    int w = 0, h = 0, nc = 0;
    std::vector<uint16_t> ref;
    sr_picture pic;
    if (!libpng_read(d, n, w, h, nc, ref)) { printf("  libpng cannot read %s\n", what); return 0; }
    sr_result r = sr_decode_png(d, n, NULL, &pic);
    if (r != SR_OK) { printf("  %s: %s\n", what, sr_result_string(r)); return 0; }
    int ok = pic.width == w && pic.height == h && pic.channels == nc &&
             memcmp(pic.samples, ref.data(), ref.size() * sizeof(uint16_t)) == 0;
    if (!ok) printf("  %s: %dx%dx%d, libpng %dx%dx%d or samples differ\n", what, pic.width, pic.height, pic.channels, w, h, nc);
    sr_picture_free(&pic);
    return ok;
}

static void generated(const char *seed_dir)
{
    static const int types[][2] = {{0, 1}, {0, 2}, {0, 4}, {0, 8}, {0, 16}, {2, 8}, {2, 16}, {3, 1}, {3, 2},
                                   {3, 4}, {3, 8}, {4, 8}, {4, 16}, {6, 8}, {6, 16}};
    static const int filters[] = {PNG_FILTER_NONE, PNG_FILTER_SUB, PNG_FILTER_UP, PNG_FILTER_AVG, PNG_FILTER_PAETH, PNG_ALL_FILTERS};
    static const int comp[][2] = {{0, Z_DEFAULT_STRATEGY}, {1, Z_DEFAULT_STRATEGY}, {6, Z_DEFAULT_STRATEGY}, {9, Z_DEFAULT_STRATEGY},
                                  {6, Z_HUFFMAN_ONLY}, {6, Z_RLE}, {6, Z_FIXED}};
    static const int sizes[][2] = {{1, 1}, {3, 2}, {9, 9}, {37, 23}};
    long cases = 0, failed = 0;
    int seeds = 0;
    for (auto &t : types)
        for (int il = 0; il < 2; il++)
            for (size_t f = 0; f < sizeof filters / sizeof *filters; f++)
                for (size_t cm = 0; cm < sizeof comp / sizeof *comp; cm++)
                    for (auto &sz : sizes) {
                        png_case c = {sz[0], sz[1], t[0], t[1], il, filters[f], comp[cm][0], comp[cm][1],
                                      (int)((cases & 1) != 0), (cases % 5 == 0) ? 64 : 0};
                        std::vector<uint8_t> file;
                        char what[160];
                        snprintf(what, sizeof what, "color %d depth %d %dx%d interlace %d filter 0x%x level %d strategy %d trns %d",
                                 c.color, c.depth, c.w, c.h, il, c.filter, c.level, c.strategy, c.trns);
                        cases++;
                        if (!libpng_write(c, file, (uint64_t)cases)) { failed++; printf("  libpng cannot write %s\n", what); continue; }
                        if (!same_as_libpng(file.data(), file.size(), what)) failed++;
                        if (seed_dir && sz[0] == 9 && f == 5 && (cm == 2 || (cm == 0 && il))) {
                            char path[512];
                            snprintf(path, sizeof path, "%s/gen_c%d_d%d_i%d_l%d.png", seed_dir, c.color, c.depth, il, c.level);
                            FILE *o = fopen(path, "wb");
                            if (o) { fwrite(file.data(), 1, file.size(), o); fclose(o); seeds++; }
                        }
                    }
    printf("generated PNGs: %ld cases, %ld differ\n", cases, failed);
    T_CHECK_MSG(failed == 0, "%ld of %ld generated PNGs decode differently from libpng", failed, cases);
    if (seed_dir) printf("wrote %d seeds to %s\n", seeds, seed_dir);
}

static bool read_file(const std::string &path, std::vector<uint8_t> &d)
{
    FILE *f = fopen(path.c_str(), "rb");
    if (!f) return false;
    uint8_t buf[65536];
    size_t got;
    while ((got = fread(buf, 1, sizeof buf, f)) > 0) d.insert(d.end(), buf, buf + got);
    fclose(f);
    return true;
}

static void real_files(void)
{
    const char *dir = "/usr/share/glmark2/textures";
    DIR *dp = opendir(dir);
    int files = 0, bad = 0, asteroid = 0;
    if (!dp) { T_SKIP_N(2, "glmark2 textures", "/usr/share/glmark2/textures missing: apt-get install glmark2-data"); return; }
    std::vector<std::string> names;
    while (struct dirent *e = readdir(dp)) {
        std::string n = e->d_name;
        if (n.size() > 4 && n.compare(n.size() - 4, 4, ".png") == 0) names.push_back(n);
    }
    closedir(dp);
    for (const std::string &n : names) {
        std::vector<uint8_t> d;
        if (!read_file(std::string(dir) + "/" + n, d)) continue;
        files++;
        if (!same_as_libpng(d.data(), d.size(), n.c_str())) bad++;
        if (n == "asteroid-height-map.png") asteroid = 1;
    }
    printf("glmark2 textures: %d PNGs, %d differ\n", files, bad);
    T_CHECK_MSG(files > 0 && bad == 0, "%d of %d glmark2 PNGs decode differently from libpng", bad, files);
    T_CHECK_MSG(asteroid, "asteroid-height-map.png not among the textures");
}

static void our_writers(void)
{
    int bad = 0, cases = 0;
    for (int ch = 1; ch <= 4; ch++)
        for (int depth = 8; depth <= 16; depth += 8) {
            int W = 41, H = 29;
            if (depth == 8 && ch == 2) continue;
            std::vector<uint16_t> s((size_t)W * H * ch);
            std::vector<uint8_t> s8(s.size());
            for (size_t i = 0; i < s.size(); i++) {
                uint64_t r = splitmix64(i * 31 + (uint64_t)ch);
                s[i] = (uint16_t)(i < s.size() / 2 ? r : (i / 7) * 613);
                if (depth == 8) s[i] &= 255;
                s8[i] = (uint8_t)s[i];
            }
            uint8_t *png = NULL;
            size_t n = 0;
            sr_result r = depth == 16 ? sr_encode_png16(s.data(), W, H, ch, 0, NULL, &png, &n)
                                      : sr_encode_png(s8.data(), W, H, ch, 0, NULL, &png, &n);
            int w, h, nc;
            std::vector<uint16_t> ref;
            cases++;
            if (r != SR_OK || !libpng_read(png, n, w, h, nc, ref) || w != W || h != H || nc != ch || ref != s) bad++;
            sr_free(NULL, png);
        }
    T_CHECK_MSG(bad == 0, "%d of %d PNGs from our writers read back differently by libpng", bad, cases);
}

int main(int argc, char **argv)
{
    T_BEGIN(argc, argv);
    const char *seeds = (argc == 3 && strcmp(argv[1], "--seeds") == 0) ? argv[2] : NULL;
    generated(seeds);
    real_files();
    our_writers();
    return T_END();
}
