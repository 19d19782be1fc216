/* fuzz_meshio.h - the body shared by the meshio fuzz targets (fuzz_obj.c, fuzz_off.c, fuzz_ply.c,
   fuzz_stl.c). Each target defines FUZZ_FORMAT and includes this file once.
   Reads the input with the format forced to FUZZ_FORMAT and with MIO_FORMAT_AUTO, and traps if a
   result breaks the API contract: an accepted mesh with an index out of range, a non-finite
   coordinate or no triangles; a refused input with a non-zeroed mesh or an empty message; a leaked
   block. */
#ifndef FUZZ_FORMAT
#error "define FUZZ_FORMAT (MIO_FORMAT_OBJ, ...) before including fuzz_meshio.h"
#endif
#define MIO_IMPLEMENTATION
#include "../examples/meshio.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
typedef struct fuzz_counter { long live; } fuzz_counter;

static void *fuzz_alloc(void *user, size_t size)
{
    void *p = malloc(size);
    if (p) ((fuzz_counter *)user)->live++;
    return p;
}

static void fuzz_free(void *user, void *ptr)
{
    if (ptr) ((fuzz_counter *)user)->live--;
    free(ptr);
}

static void fuzz_check(const uint8_t *data, size_t size, mio_format format)
{
    fuzz_counter live = { 0 };
    mio_allocator alloc;
    mio_read_options opt;
    mio_mesh mesh;
    mio_error err;
    mio_result r;
    size_t i;
    alloc.alloc = fuzz_alloc;
    alloc.free = fuzz_free;
    alloc.user = &live;
    memset(&opt, 0, sizeof opt);
    opt.format = format;
    opt.allocator = &alloc;
    r = mio_read_memory(data, size, &opt, &mesh, &err);
    if (err.code != r) __builtin_trap();
    if (r == MIO_OK) {
        if (!mesh.positions || !mesh.indices || mesh.triangle_count == 0 || mesh.vertex_count > UINT32_MAX) __builtin_trap();
        for (i = 0; i < 3 * mesh.triangle_count; i++)
            if (mesh.indices[i] >= mesh.vertex_count) __builtin_trap();
        for (i = 0; i < 3 * mesh.vertex_count; i++) {
            uint32_t bits;
            memcpy(&bits, &mesh.positions[i], 4);
            if ((bits & 0x7F800000u) == 0x7F800000u) __builtin_trap();
        }
    } else {
        if (mesh.positions || mesh.indices || mesh.vertex_count || mesh.triangle_count || err.message[0] == '\0') __builtin_trap();
        if (err.offset > size) __builtin_trap();
    }
    mio_free_mesh(&mesh);
    if (live.live != 0) __builtin_trap();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_check(data, size, FUZZ_FORMAT);
    fuzz_check(data, size, MIO_FORMAT_AUTO);
    (void)mio_detect_format(data, size, NULL);
    return 0;
}
