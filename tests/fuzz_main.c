/* fuzz_main.c - runs fuzz targets without libFuzzer (for gcc builds and regression runs).
   Usage: ./fuzz_obj FILE_OR_DIR...   Every file given, and every regular file directly inside a
   directory given, is passed once to LLVMFuzzerTestOneInput. Prints how many inputs ran. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Runs one file; returns 1 if it ran, 0 if it could not be read. */
static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    size_t size = 0, cap = 0;
    if (!f) return 0;
    for (;;) {
        size_t got;
        if (size == cap) {
            unsigned char *bigger;
            cap = cap ? cap * 2 : 65536;
            bigger = (unsigned char *)realloc(buf, cap);
            if (!bigger) { free(buf); fclose(f); return 0; }
            buf = bigger;
        }
        got = fread(buf + size, 1, cap - size, f);
        size += got;
        if (got == 0) break;
    }
    fclose(f);
    /* an exact-size copy, so that sanitizers catch reads past the end */
    {
        unsigned char *exact = (unsigned char *)malloc(size ? size : 1);
        if (exact) {
            memcpy(exact, buf, size);
            LLVMFuzzerTestOneInput(exact, size);
            free(exact);
        }
    }
    free(buf);
    return 1;
}

int main(int argc, char **argv)
{
    long ran = 0, failed = 0;
    int i;
    for (i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) != 0) { fprintf(stderr, "cannot stat %s\n", argv[i]); failed++; continue; }
        if (S_ISDIR(st.st_mode)) {
            DIR *dir = opendir(argv[i]);
            struct dirent *ent;
            if (!dir) { failed++; continue; }
            while ((ent = readdir(dir)) != NULL) {
                char path[4096];
                struct stat fs;
                snprintf(path, sizeof path, "%s/%s", argv[i], ent->d_name);
                if (stat(path, &fs) != 0 || !S_ISREG(fs.st_mode)) continue;
                if (run_file(path)) ran++;
                else failed++;
            }
            closedir(dir);
        } else {
            if (run_file(argv[i])) ran++;
            else failed++;
        }
    }
    printf("fuzz_main: %ld inputs ran, %ld unreadable\n", ran, failed);
    return failed ? 1 : 0;
}
