/* thumbnail - the README gallery's pictures: a PNG made small enough to commit.

     thumbnail IN.png OUT.png [--width W] [--max-bytes N]

   Reads IN (any PNG, PGM/PPM or PFM render.h reads; 8 or 16 bits, grey or colour, alpha
   dropped), averages it down by whole factors (box filter, 1, 2, 3, ...) until it is at most W
   pixels wide (default 640) and its PNG (render.h's encoder) is at most N bytes (default 61440,
   60 KiB), and writes it to OUT.tmp, renamed to OUT when complete. `make gallery` runs it on
   the pictures `make demo` writes (see README.md, Gallery).
   Exit status: 0 done, 1 failure (unreadable input, failed write), 2 usage. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SR_IMPLEMENTATION
#include "render.h"
#define CLI_IMPLEMENTATION
#include "cli.h"

static void usage(FILE *to)
{
    fprintf(to, "usage: thumbnail IN.png OUT.png [--width W] [--max-bytes N]\n"
                "Averages IN down by whole factors until it is at most W pixels wide and its PNG at most N bytes.\n"
                "  --width W      the widest thumbnail, 16..16384 pixels (default 640)\n"
                "  --max-bytes N  the largest PNG, 1024..100000000 bytes (default 61440)\n"
                "  -h, --help     show this help and exit\n"
                "Exit status: 0 done, 1 failure, 2 usage. OUT is written to OUT.tmp and renamed when complete.\n");
}

/* RGB bytes of the picture averaged over f x f blocks (the last partial blocks averaged too) */
static uint8_t *shrink(const sr_picture *p, const float *rgb, int f, int *w, int *h)
{
    int x, y, i, j, c;
    uint8_t *out;
    *w = (p->width + f - 1) / f;
    *h = (p->height + f - 1) / f;
    out = (uint8_t *)malloc((size_t)*w * (size_t)*h * 3);
    if (!out) return NULL;
    for (y = 0; y < *h; y++)
        for (x = 0; x < *w; x++)
            for (c = 0; c < 3; c++) {
                double s = 0.0;
                int n = 0;
                for (j = y * f; j < y * f + f && j < p->height; j++)
                    for (i = x * f; i < x * f + f && i < p->width; i++, n++) s += rgb[((size_t)j * p->width + i) * 3 + c];
                s = s / n;
                out[((size_t)y * *w + x) * 3 + c] = (uint8_t)(s <= 0.0 ? 0 : s >= 1.0 ? 255 : (int)(s * 255.0 + 0.5));
            }
    return out;
}

int main(int argc, char **argv)
{
    const char *in = NULL, *out = NULL, *tmp;
    long width = 640, max_bytes = 61440;
    int i, f, c, w = 0, h = 0;
    sr_picture pic;
    sr_result r;
    float *plane = NULL, *rgb = NULL;
    uint8_t *px = NULL, *png = NULL;
    size_t n = 0, k;
    cli_outputs outs;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) { usage(stdout); return 0; }
        if (!strcmp(a, "--width") || !strcmp(a, "--max-bytes")) {
            if (!v) return cli_usage_error("thumbnail", "%s needs a value", a);
            i++;
            if (!strcmp(a, "--width") ? !cli_parse_long(v, 16, 16384, &width) : !cli_parse_long(v, 1024, 100000000L, &max_bytes))
                return cli_usage_error("thumbnail", "%s '%s': out of range", a, v);
        } else if (a[0] == '-' && a[1]) return cli_usage_error("thumbnail", "unknown option '%s'", a);
        else if (!in) in = a;
        else if (!out) out = a;
        else return cli_usage_error("thumbnail", "unexpected argument '%s'", a);
    }
    if (!in || !out) return cli_usage_error("thumbnail", "%s", "give IN and OUT");
    if (!cli_has_extension(out, ".png")) return cli_usage_error("thumbnail", "output '%s': the name must end in .png", out);
    errno = 0;
    if ((r = sr_read_image(in, NULL, &pic)) != SR_OK) {
        cli_result_error("thumbnail", in, sr_result_string(r), r == SR_ERR_IO ? errno : 0);
        return 1;
    }
    n = (size_t)pic.width * (size_t)pic.height;
    plane = (float *)malloc(n * sizeof(float));
    rgb = (float *)malloc(n * 3 * sizeof(float));
    if (!plane || !rgb) { fprintf(stderr, "thumbnail: out of memory\n"); goto fail; }
    for (c = 0; c < 3; c++) { /* grey pictures repeat channel 0; alpha is dropped */
        sr_picture_channel(&pic, pic.channels >= 3 ? c : 0, plane);
        for (k = 0; k < n; k++) rgb[3 * k + (size_t)c] = plane[k];
    }
    for (f = 1;; f++) {
        if ((pic.width + f - 1) / f > width) continue;
        free(px);
        sr_free(NULL, png);
        png = NULL;
        if (!(px = shrink(&pic, rgb, f, &w, &h))) { fprintf(stderr, "thumbnail: out of memory\n"); goto fail; }
        if ((r = sr_encode_png(px, w, h, 3, 0, NULL, &png, &n)) != SR_OK) {
            cli_result_error("thumbnail", out, sr_result_string(r), 0);
            goto fail;
        }
        if ((long)n <= max_bytes || w <= 16) break;
    }
    cli_outputs_init(&outs);
    if (!(tmp = cli_output_add(&outs, "thumbnail", out))) goto fail;
    errno = 0;
    if ((r = sr_write_png(tmp, px, w, h, 3, 0)) != SR_OK) {
        cli_result_error("thumbnail", out, sr_result_string(r), r == SR_ERR_IO ? errno : 0);
        cli_outputs_discard(&outs);
        goto fail;
    }
    if (!cli_outputs_commit(&outs, "thumbnail")) goto fail;
    printf("thumbnail: %s %dx%d -> %s %dx%d, %lu bytes\n", in, pic.width, pic.height, out, w, h, (unsigned long)n);
    free(plane); free(rgb); free(px); sr_free(NULL, png);
    sr_picture_free(&pic);
    return 0;
fail:
    free(plane); free(rgb); free(px); sr_free(NULL, png);
    sr_picture_free(&pic);
    return 1;
}
