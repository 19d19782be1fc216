/* test_meshio.c - tests for examples/meshio.h
   Hand-written inputs with exact expected output for every supported feature, malformed and
   truncated inputs, huge header counts (checked with a counting allocator), allocation-failure
   injection, write/read round trips, the glmark2 bunny and the assimp test models compared with
   the committed table tests/meshio_assimp.tsv (and with assimp itself when it is installed).

   Build: gcc -std=c99 -O2 -g -Wall -Wextra -pedantic -Werror -Iexamples -Itests tests/test_meshio.c -lm */
#define _POSIX_C_SOURCE 200809L
#define MIO_IMPLEMENTATION
#include "../examples/meshio.h"
#include "test.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <float.h>
#include <locale.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---------------------------------------------------------------------------------------------
   Helpers: a counting allocator that can fail on purpose, exact-size input buffers, mesh checks
   --------------------------------------------------------------------------------------------- */

typedef struct counter {
    mio_allocator a;
    long live;          /* blocks allocated and not yet freed */
    size_t calls;       /* alloc calls so far */
    size_t fail_at;     /* 1-based call that returns NULL; 0 = never */
    size_t bytes;       /* total bytes requested */
    size_t largest;     /* largest single request */
} counter;

static void *counter_alloc(void *user, size_t size)
{
    counter *c = (counter *)user;
    void *p;
    c->calls++;
    if (c->fail_at && c->calls == c->fail_at) return NULL;
    c->bytes += size;
    if (size > c->largest) c->largest = size;
    p = malloc(size);
    if (p) c->live++;
    return p;
}

static void counter_free(void *user, void *ptr)
{
    counter *c = (counter *)user;
    if (!ptr) return;
    c->live--;
    free(ptr);
}

static void counter_init(counter *c)
{
    memset(c, 0, sizeof *c);
    c->a.alloc = counter_alloc;
    c->a.free = counter_free;
    c->a.user = c;
}

/* Reads from an exact-size heap copy so that AddressSanitizer sees any read past the end. */
static mio_result read_bytes(const void *data, size_t size, mio_format format, counter *alloc, mio_mesh *mesh, mio_error *err)
{
    mio_read_options opt;
    void *copy = malloc(size ? size : 1);
    mio_result r;
    memcpy(copy, data, size);
    memset(&opt, 0, sizeof opt);
    opt.format = format;
    opt.allocator = alloc ? &alloc->a : NULL;
    r = mio_read_memory(size ? copy : NULL, size, &opt, mesh, err);
    free(copy);
    return r;
}

#define READ_TEXT(text, format, mesh, err) read_bytes((text), sizeof(text) - 1, (format), NULL, (mesh), (err))

static int mesh_is_zero(const mio_mesh *m)
{
    return !m->positions && !m->indices && !m->vertex_count && !m->triangle_count && !m->allocator.alloc && !m->allocator.free;
}

/* Every index in range and every coordinate finite. */
static int mesh_is_valid(const mio_mesh *m)
{
    size_t i;
    if (!m->positions || !m->indices || m->triangle_count == 0) return 0;
    for (i = 0; i < 3 * m->triangle_count; i++)
        if (m->indices[i] >= m->vertex_count) return 0;
    for (i = 0; i < 3 * m->vertex_count; i++)
        if (!(m->positions[i] - m->positions[i] == 0.0f)) return 0;
    return 1;
}

static int same_floats(const float *a, const float *b, size_t n) { return n == 0 || memcmp(a, b, n * sizeof(float)) == 0; }
static int same_indices(const uint32_t *a, const uint32_t *b, size_t n) { return n == 0 || memcmp(a, b, n * sizeof(uint32_t)) == 0; }

/* Exact comparison of a read mesh with the expected arrays (4 counted checks). */
static void check_mesh(const char *what, mio_result r, const mio_mesh *m, const float *pos, size_t nv, const uint32_t *idx, size_t nt)
{
    T_CHECK_MSG(r == MIO_OK, "%s: %s", what, mio_result_string(r));
    T_CHECK_MSG(m->vertex_count == nv, "%s: %zu vertices, expected %zu", what, m->vertex_count, nv);
    T_CHECK_MSG(m->triangle_count == nt, "%s: %zu triangles, expected %zu", what, m->triangle_count, nt);
    T_CHECK_MSG(m->vertex_count == nv && m->triangle_count == nt && same_floats(m->positions, pos, 3 * nv) &&
                    same_indices(m->indices, idx, 3 * nt),
                "%s: positions or indices differ", what);
}

/* Expects failure with the given code and, if line > 0, that line in err and in the message. */
static void check_error(const char *what, mio_result r, const mio_mesh *m, const mio_error *e, mio_result want, size_t line)
{
    char prefix[32];
    T_CHECK_MSG(r == want, "%s: got %s, want %s (%s)", what, mio_result_string(r), mio_result_string(want), e->message);
    T_CHECK_MSG(e->code == r && mesh_is_zero(m) && e->message[0] != '\0', "%s: error struct / zeroed mesh", what);
    if (line) {
        snprintf(prefix, sizeof prefix, "line %zu:", line);
        T_CHECK_MSG(e->line == line && strncmp(e->message, prefix, strlen(prefix)) == 0, "%s: line %zu, message '%s', want line %zu",
                    what, e->line, e->message, line);
    }
}

/* Growable byte buffer for building binary inputs. */
typedef struct bytes {
    unsigned char data[4096];
    size_t size;
} bytes;

static void put(bytes *b, const void *p, size_t n)
{
    memcpy(b->data + b->size, p, n);
    b->size += n;
}
static void put_str(bytes *b, const char *s) { put(b, s, strlen(s)); }
/* Stores the n-byte value in the given byte order (value given as its little-endian bytes). */
static void put_ordered(bytes *b, const void *le_or_host, size_t n, int big_endian)
{
    unsigned char tmp[8];
    size_t k;
    uint16_t probe = 1;
    int host_little = *(unsigned char *)&probe == 1;
    memcpy(tmp, le_or_host, n);
    if (big_endian == host_little) /* reverse */
        for (k = 0; k < n / 2; k++) { unsigned char x = tmp[k]; tmp[k] = tmp[n - 1 - k]; tmp[n - 1 - k] = x; }
    put(b, tmp, n);
}
static void put_f32(bytes *b, float v, int be) { put_ordered(b, &v, 4, be); }
static void put_f64(bytes *b, double v, int be) { put_ordered(b, &v, 8, be); }
static void put_i16(bytes *b, int16_t v, int be) { put_ordered(b, &v, 2, be); }
static void put_u16(bytes *b, uint16_t v, int be) { put_ordered(b, &v, 2, be); }
static void put_i32(bytes *b, int32_t v, int be) { put_ordered(b, &v, 4, be); }
static void put_u32(bytes *b, uint32_t v, int be) { put_ordered(b, &v, 4, be); }
static void put_u8(bytes *b, uint8_t v) { put(b, &v, 1); }

static const float tri_pos[9] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
static const uint32_t tri_idx[3] = { 0, 1, 2 };
static const float quad_pos[12] = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0 };
static const uint32_t quad_idx[6] = { 0, 1, 2, 0, 2, 3 };

/* ---------------------------------------------------------------------------------------------
   OBJ
   --------------------------------------------------------------------------------------------- */

static void test_obj(void)
{
    mio_mesh m;
    mio_error e;
    mio_result r;

    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj plain", r, &m, tri_pos, 3, tri_idx, 1);
    T_CHECK(e.code == MIO_OK && e.message[0] == '\0');
    mio_free_mesh(&m);
    T_CHECK(mesh_is_zero(&m));

    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj i/t", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj i//n", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj i/t/n", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf -3/-1 -2/-1 -1/-1\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj negative", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    {   /* negative indices are relative to the vertices defined so far */
        static const float pos[15] = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 6, 6, 6 };
        static const uint32_t idx[6] = { 0, 1, 2, 2, 3, 4 };
        r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nv 6 6 6\nf -3 -2 -1\n", MIO_FORMAT_OBJ, &m, &e);
        check_mesh("obj relative", r, &m, pos, 5, idx, 2);
        mio_free_mesh(&m);
    }
    r = READ_TEXT("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj crlf", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj no final newline", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("# a comment\n\n   # indented comment\nv 0 0 0 # trailing\nv\t1  0\t\t0\n  v 0 1 0   \n\nf\t1  2   3 # done\n#end",
                  MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj comments and blanks", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 \\\n 0\nv 1 0 0\nv 0 1 0\nf 1 \\\r\n2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj line continuation", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 0 1\nv 1 0 0 0.5 0.5 0.5\nv 0 1 0 1 0 0 1\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj w and colours ignored", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("mtllib a.mtl\no obj\ng group\ns 1\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nvp 0.5\n"
                  "l 1 2\np 3\ncstype bezier\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj other statements ignored", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj quad fan", r, &m, quad_pos, 4, quad_idx, 2);
    mio_free_mesh(&m);
    {
        static const float pos[15] = { 0, 0, 0, 2, 0, 0, 3, 1, 0, 1, 2, 0, -1, 1, 0 };
        static const uint32_t idx[9] = { 0, 1, 2, 0, 2, 3, 0, 3, 4 };
        r = READ_TEXT("v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n", MIO_FORMAT_OBJ, &m, &e);
        check_mesh("obj pentagon fan", r, &m, pos, 5, idx, 3);
        mio_free_mesh(&m);
    }
    {   /* number formats, exact values */
        static const float pos[9] = { 1e-3f, 1.0f, 0.5f, -0.5f, 100.0f, 5.0f, 0.0f, -0.0f, 123456789.0f };
        r = READ_TEXT("v 1e-3 +1.0 .5\nv -.5 1.E2 5.\nv 0 -0.0 123456789\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
        check_mesh("obj number formats", r, &m, pos, 3, tri_idx, 1);
        T_CHECK(r == MIO_OK && m.positions[7] == 0.0f && 1.0f / m.positions[7] < 0); /* -0.0 kept */
        mio_free_mesh(&m);
        r = READ_TEXT("v 0.1 3.14159265358979323846264338327950288 1e-45\nv 3.4028234663852886e38 1.17549435e-38 -2.5e-7\nv 0 0 0\nf 1 2 3\n",
                      MIO_FORMAT_OBJ, &m, &e);
        T_CHECK(r == MIO_OK);
        T_CHECK(r == MIO_OK && m.positions[0] == 0.1f && m.positions[1] == 3.14159265f && m.positions[2] == 1e-45f);
        T_NEAR(r == MIO_OK ? m.positions[1] : 0.0f, 3.14159265358979, 1e-6);
        T_CHECK(r == MIO_OK && m.positions[3] == FLT_MAX && m.positions[4] == FLT_MIN && m.positions[5] == -2.5e-7f);
        mio_free_mesh(&m);
    }
    r = READ_TEXT("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj forward reference", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_mesh("obj utf-8 bom", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);

    /* errors, with the line they name */
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj index 0", r, &m, &e, MIO_ERR_INDEX_RANGE, 4);
    T_EQ_SIZE(e.offset, 30);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj index past end", r, &m, &e, MIO_ERR_INDEX_RANGE, 5);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj negative past start", r, &m, &e, MIO_ERR_INDEX_RANGE, 4);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj huge index", r, &m, &e, MIO_ERR_INDEX_RANGE, 4);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj 2-vertex face", r, &m, &e, MIO_ERR_SYNTAX, 4);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj empty face", r, &m, &e, MIO_ERR_SYNTAX, 4);
    r = READ_TEXT("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj 2 coordinates", r, &m, &e, MIO_ERR_SYNTAX, 2);
    r = READ_TEXT("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj nan", r, &m, &e, MIO_ERR_SYNTAX, 2);
    T_CHECK(strstr(e.message, "non-finite") != NULL);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv -inf 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj inf", r, &m, &e, MIO_ERR_SYNTAX, 3);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 1e39 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj float overflow", r, &m, &e, MIO_ERR_SYNTAX, 3);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 3.1+e2 1 0\nf 1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj bad number", r, &m, &e, MIO_ERR_SYNTAX, 3);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj bad reference", r, &m, &e, MIO_ERR_SYNTAX, 4);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj 4-part reference", r, &m, &e, MIO_ERR_SYNTAX, 4);
    r = READ_TEXT("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\np 3\n", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj no faces", r, &m, &e, MIO_ERR_EMPTY, 0);
    r = READ_TEXT("\xFE\xFF\0v\0 \0" "0", MIO_FORMAT_OBJ, &m, &e);
    check_error("obj utf-16", r, &m, &e, MIO_ERR_UNSUPPORTED, 1);
    r = read_bytes("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 12, MIO_FORMAT_OBJ, NULL, &m, &e);
    check_error("obj cut inside vertex 2", r, &m, &e, MIO_ERR_SYNTAX, 2);
}

/* ---------------------------------------------------------------------------------------------
   OFF
   --------------------------------------------------------------------------------------------- */

static void test_off(void)
{
    mio_mesh m;
    mio_error e;
    mio_result r;
    counter c;

    r = READ_TEXT("OFF\n# comment\n4 1 0\n0 0 0\n1 0 0\n\n1 1 0 # comment\n0 1 0\n4 0 1 2 3\n", MIO_FORMAT_OFF, &m, &e);
    check_mesh("off quad with comments", r, &m, quad_pos, 4, quad_idx, 2);
    mio_free_mesh(&m);
    r = READ_TEXT("OFF 4 1\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n4 0 1 2 3 255 0 0\r\n", MIO_FORMAT_OFF, &m, &e);
    check_mesh("off counts on header line, face colour", r, &m, quad_pos, 4, quad_idx, 2);
    mio_free_mesh(&m);
    r = READ_TEXT("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 0.5 0.5 0.5 1\n", MIO_FORMAT_AUTO, &m, &e);
    check_mesh("coff", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2", MIO_FORMAT_AUTO, &m, &e);
    check_mesh("noff, no final newline", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("STCNOFF\n3 1 0\n0 0 0 0 0 1 1 0 0 1 0 0\n1 0 0 0 0 1 1 0 0 1 1 0\n0 1 0 0 0 1 1 0 0 1 0 1\n3 0 1 2\n", MIO_FORMAT_AUTO, &m, &e);
    check_mesh("stcnoff", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);

    r = READ_TEXT("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off index range", r, &m, &e, MIO_ERR_INDEX_RANGE, 6);
    r = READ_TEXT("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off negative index", r, &m, &e, MIO_ERR_INDEX_RANGE, 6);
    r = READ_TEXT("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1    \n", MIO_FORMAT_OFF, &m, &e);
    check_error("off 2-vertex face", r, &m, &e, MIO_ERR_SYNTAX, 7);
    r = READ_TEXT("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 inf\n3 0 1 2\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off inf", r, &m, &e, MIO_ERR_SYNTAX, 5);
    r = READ_TEXT("OFF\n3 1 0\n0 0 0\n1 0         \n0 1 0\n3 0 1 2\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off short vertex line", r, &m, &e, MIO_ERR_SYNTAX, 4);
    r = READ_TEXT("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off extra face", r, &m, &e, MIO_ERR_SYNTAX, 7);
    r = READ_TEXT("4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n", MIO_FORMAT_OFF, &m, &e);
    check_error("4off", r, &m, &e, MIO_ERR_UNSUPPORTED, 1);
    r = READ_TEXT("OFF BINARY\n", MIO_FORMAT_OFF, &m, &e);
    check_error("binary off", r, &m, &e, MIO_ERR_UNSUPPORTED, 1);
    r = READ_TEXT("OFX\n3 1 0\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off bad keyword", r, &m, &e, MIO_ERR_SYNTAX, 1);
    r = READ_TEXT("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", MIO_FORMAT_OFF, &m, &e);
    check_error("off no faces", r, &m, &e, MIO_ERR_EMPTY, 0);

    /* huge counts: refused before allocating anything */
    counter_init(&c);
    r = read_bytes("OFF\n1000000000 1000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 56, MIO_FORMAT_OFF, &c, &m, &e);
    check_error("off huge counts", r, &m, &e, MIO_ERR_TRUNCATED, 2);
    T_CHECK_MSG(c.bytes == 0 && c.live == 0, "allocated %zu bytes", c.bytes);
    counter_init(&c);
    r = read_bytes("OFF\n1000000000000 1 0\n0 0 0\n", 27, MIO_FORMAT_OFF, &c, &m, &e);
    check_error("off vertex count above uint32", r, &m, &e, MIO_ERR_TOO_LARGE, 2);
    T_CHECK_MSG(c.bytes == 0 && c.live == 0, "allocated %zu bytes", c.bytes);
    counter_init(&c);
    r = read_bytes("OFF\n3 99999999999999999999999 0\n", 31, MIO_FORMAT_OFF, &c, &m, &e);
    T_CHECK(r == MIO_ERR_TOO_LARGE && c.bytes == 0);
}

/* ---------------------------------------------------------------------------------------------
   PLY
   --------------------------------------------------------------------------------------------- */

/* A binary PLY with mixed types: x double, y float, z int16, extra props and lists, a face
   element with ushort counts and int32 indices, and an edge element after it. */
static void build_binary_ply(bytes *b, int be)
{
    b->size = 0;
    put_str(b, "ply\n");
    put_str(b, be ? "format binary_big_endian 1.0\n" : "format binary_little_endian 1.0\n");
    put_str(b, "comment mixed types\nobj_info anything\nelement material 1\nproperty uchar red\nproperty list uchar float weights\n"
               "element vertex 4\nproperty float64 x\nproperty uint8 flags\nproperty float y\nproperty list uint8 int32 neighbours\n"
               "property int16 z\nproperty float nx\nelement face 1\nproperty uchar flag\nproperty list ushort int vertex_indices\n"
               "property list uchar float texcoord\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n");
    /* material */
    put_u8(b, 7);
    put_u8(b, 2);
    put_f32(b, 0.25f, be);
    put_f32(b, 0.75f, be);
    {
        static const double xs[4] = { 0, 1, 1, 0 };
        static const float ys[4] = { 0, 0, 1, 1 };
        int i;
        for (i = 0; i < 4; i++) {
            put_f64(b, xs[i], be);
            put_u8(b, 0xAA);
            put_f32(b, ys[i], be);
            put_u8(b, (uint8_t)(i & 1));
            if (i & 1) put_i32(b, 3, be);
            put_i16(b, 0, be);
            put_f32(b, 1.0f, be);
        }
    }
    put_u8(b, 1);
    put_u16(b, 4, be);
    put_i32(b, 0, be);
    put_i32(b, 1, be);
    put_i32(b, 2, be);
    put_i32(b, 3, be);
    put_u8(b, 2);
    put_f32(b, 0.5f, be);
    put_f32(b, 0.5f, be);
    put_i32(b, 0, be);
    put_i32(b, 1, be);
}

static void test_ply(void)
{
    mio_mesh m;
    mio_error e;
    mio_result r;
    counter c;
    bytes b;
    int be;

    r = READ_TEXT("ply\nformat ascii 1.0\ncomment hello\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_mesh("ply ascii plain", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("ply\r\nformat ascii 1.0\r\nobj_info x\r\nelement vertex 4\r\nproperty double x\r\nproperty float nx\r\nproperty double y\r\n"
                  "property uchar red\r\nproperty list uchar float uv\r\nproperty double z\r\nproperty float32 s\r\n"
                  "element edge 2\r\nproperty int vertex1\r\nproperty int vertex2\r\n"
                  "element face 1\r\nproperty uint8 flags\r\nproperty list int32 uint32 vertex_index\r\nproperty list uchar float texcoord\r\n"
                  "element material 1\r\nproperty float shininess\r\nend_header\r\n"
                  "0 0.5 0 255 2 0.1 0.2 0 9\r\n1 0.5 0 255 0 0 9\r\n1 0.5 1 255 1 7 0 9\r\n0 0.5 1 255 0 0 9\r\n"
                  "0 1\r\n1 2\r\n"
                  "3 4 0 1 2 3 2 0.5 0.5\r\n"
                  "0.8\r\n",
                  MIO_FORMAT_AUTO, &m, &e);
    check_mesh("ply ascii extras, double, int lists, other elements", r, &m, quad_pos, 4, quad_idx, 2);
    mio_free_mesh(&m);
    r = READ_TEXT("ply\nformat ascii 1.0\nCreated by an exporter that forgot the comment keyword\nelement vertex 3\nproperty int x\n"
                  "property short y\nproperty uchar z\nelement face 1\nproperty list uchar ushort vertex_indices\nend_header\n"
                  "0 0 0 1 0 0 0 1 0 3 0 1 2",
                  MIO_FORMAT_AUTO, &m, &e);
    check_mesh("ply ascii integer coordinates, unknown header line", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);

    for (be = 0; be <= 1; be++) {
        build_binary_ply(&b, be);
        r = read_bytes(b.data, b.size, MIO_FORMAT_AUTO, NULL, &m, &e);
        check_mesh(be ? "ply binary big-endian" : "ply binary little-endian", r, &m, quad_pos, 4, quad_idx, 2);
        mio_free_mesh(&m);
        counter_init(&c);
        r = read_bytes(b.data, b.size - 1, MIO_FORMAT_PLY, &c, &m, &e);
        check_error("ply binary cut by one byte", r, &m, &e, MIO_ERR_TRUNCATED, 0);
        T_CHECK(c.live == 0);
    }

    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply index range", r, &m, &e, MIO_ERR_INDEX_RANGE, 13);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply negative index", r, &m, &e, MIO_ERR_INDEX_RANGE, 13);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply 2-vertex face", r, &m, &e, MIO_ERR_SYNTAX, 13);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply nan", r, &m, &e, MIO_ERR_SYNTAX, 11);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0\n1 0\n0 1\n3 0 1 2\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply no z", r, &m, &e, MIO_ERR_SYNTAX, 3);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float128 x\nend_header\n", MIO_FORMAT_PLY, &m, &e);
    check_error("ply unknown type", r, &m, &e, MIO_ERR_UNSUPPORTED, 4);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list float int vertex_indices\nend_header\n", MIO_FORMAT_PLY, &m, &e);
    check_error("ply float list count", r, &m, &e, MIO_ERR_UNSUPPORTED, 8);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply trailing data", r, &m, &e, MIO_ERR_SYNTAX, 14);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
                  MIO_FORMAT_PLY, &m, &e);
    check_error("ply vertices only", r, &m, &e, MIO_ERR_EMPTY, 0);
    r = READ_TEXT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", MIO_FORMAT_PLY, &m, &e);
    check_error("ply header without end", r, &m, &e, MIO_ERR_TRUNCATED, 5);
    r = READ_TEXT("plx\nformat ascii 1.0\n", MIO_FORMAT_PLY, &m, &e);
    check_error("ply bad magic", r, &m, &e, MIO_ERR_SYNTAX, 1);
    r = READ_TEXT("ply\nformat binary_middle_endian 1.0\nend_header\n", MIO_FORMAT_PLY, &m, &e);
    check_error("ply unknown format", r, &m, &e, MIO_ERR_UNSUPPORTED, 2);

    /* huge counts */
    counter_init(&c);
    r = READ_TEXT("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n\0\0\0\0", MIO_FORMAT_PLY, &m, &e);
    T_CHECK(r == MIO_ERR_TRUNCATED);
    r = read_bytes("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 999999999999\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                   169, MIO_FORMAT_PLY, &c, &m, &e);
    check_error("ply ascii huge face count", r, &m, &e, MIO_ERR_TRUNCATED, 10);
    T_CHECK_MSG(c.bytes < 1024 && c.live == 0, "allocated %zu bytes", c.bytes);
    counter_init(&c);
    r = read_bytes("ply\nformat binary_big_endian 1.0\nelement vertex 5000000000\nproperty uchar x\nproperty uchar y\nproperty uchar z\n"
                   "end_header\n\1\2\3",
                   117, MIO_FORMAT_PLY, &c, &m, &e);
    T_CHECK_MSG(r == MIO_ERR_TOO_LARGE || r == MIO_ERR_TRUNCATED, "%s", e.message);
    T_CHECK_MSG(c.bytes < 1024 && c.live == 0, "allocated %zu bytes", c.bytes);
    counter_init(&c);
    r = read_bytes("ply\nformat binary_little_endian 1.0\nelement junk 18446744073709551615\nproperty list uint uint stuff\nend_header\n\1\0\0\0",
                   109, MIO_FORMAT_PLY, &c, &m, &e);
    T_CHECK_MSG(r == MIO_ERR_TRUNCATED || r == MIO_ERR_TOO_LARGE, "%s", e.message);
    T_CHECK_MSG(c.bytes < 1024 && c.live == 0, "allocated %zu bytes", c.bytes);
    {   /* a list claiming 2^32-1 items in a small file */
        bytes hb;
        hb.size = 0;
        put_str(&hb, "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 1\nproperty list uint uint vertex_indices\nend_header\n");
        put(&hb, tri_pos, sizeof tri_pos);
        put_u32(&hb, 0xFFFFFFFFu, 0);
        put_u32(&hb, 0, 0);
        put_u32(&hb, 1, 0);
        put_u32(&hb, 2, 0);
        counter_init(&c);
        r = read_bytes(hb.data, hb.size, MIO_FORMAT_PLY, &c, &m, &e);
        check_error("ply huge list", r, &m, &e, MIO_ERR_TRUNCATED, 0);
        T_CHECK_MSG(c.bytes < 4096 && c.live == 0, "allocated %zu bytes", c.bytes);
    }
}

/* ---------------------------------------------------------------------------------------------
   STL
   --------------------------------------------------------------------------------------------- */

static void build_binary_stl(bytes *b, const char *header, uint32_t count, const float *pos9)
{
    uint32_t i;
    char h[80];
    memset(h, ' ', sizeof h);
    memcpy(h, header, strlen(header));
    b->size = 0;
    put(b, h, 80);
    put_u32(b, count, 0);
    for (i = 0; i < count; i++) {
        int k;
        for (k = 0; k < 3; k++) put_f32(b, 0.0f, 0); /* normal */
        for (k = 0; k < 9; k++) put_f32(b, pos9[9 * i + k], 0);
        put_u16(b, 0, 0);
    }
}

static void test_stl(void)
{
    static const float two_pos[18] = { 1, 1, 0, -1, 1, 0, 0, -1, 0, 3, 3, 0, 2, 3, 0, 0, 2, 0 };
    static const uint32_t two_idx[6] = { 0, 1, 2, 3, 4, 5 };
    mio_mesh m;
    mio_error e;
    mio_result r;
    bytes b;
    counter c;

    r = READ_TEXT("solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n",
                  MIO_FORMAT_AUTO, &m, &e);
    check_mesh("stl ascii", r, &m, tri_pos, 3, tri_idx, 1);
    mio_free_mesh(&m);
    r = READ_TEXT("solid one\r\nfacet normal nan nan nan\r\nouter loop\r\nvertex 1 1 0\r\nvertex -1 1 0\r\nvertex 0 -1 0\r\nendloop\r\nendfacet\r\nendsolid one\r\n"
                  "SOLID\nFACET NORMAL 0 0 0\nOUTER LOOP\nVERTEX 3 3 0\nVERTEX 2 3 0\nVERTEX 0 2 0\nENDLOOP\nENDFACET\nENDSOLID\n"
                  "solid empty\nendsolid",
                  MIO_FORMAT_STL, &m, &e);
    check_mesh("stl ascii two solids, upper case, nan normal, empty solid", r, &m, two_pos, 6, two_idx, 2);
    mio_free_mesh(&m);

    /* binary, with a header that begins with "solid": recognised by its size */
    build_binary_stl(&b, "solid but binary", 2, two_pos);
    r = read_bytes(b.data, b.size, MIO_FORMAT_AUTO, NULL, &m, &e);
    check_mesh("stl binary with solid header", r, &m, two_pos, 6, two_idx, 2);
    mio_free_mesh(&m);
    T_CHECK(mio_detect_format(b.data, b.size, NULL) == MIO_FORMAT_STL);
    build_binary_stl(&b, "binary", 2, two_pos);
    r = read_bytes(b.data, b.size - 1, MIO_FORMAT_STL, NULL, &m, &e);
    check_error("stl binary short", r, &m, &e, MIO_ERR_TRUNCATED, 0);
    T_EQ_SIZE(e.offset, 80);
    b.data[b.size++] = 0;
    r = read_bytes(b.data, b.size, MIO_FORMAT_STL, NULL, &m, &e);
    check_error("stl binary long", r, &m, &e, MIO_ERR_SYNTAX, 0);
    {
        float bad[18];
        uint32_t nan_bits = 0x7FC00000u;
        memcpy(bad, two_pos, sizeof bad);
        memcpy(&bad[13], &nan_bits, 4);
        build_binary_stl(&b, "binary", 2, bad);
        r = read_bytes(b.data, b.size, MIO_FORMAT_STL, NULL, &m, &e);
        check_error("stl binary nan", r, &m, &e, MIO_ERR_SYNTAX, 0);
        T_EQ_SIZE(e.offset, 84 + 50 + 12 + 4 * 4);
    }
    counter_init(&c);
    build_binary_stl(&b, "binary", 0, two_pos);
    b.data[80] = 0xFF;
    b.data[81] = 0xFF;
    b.data[82] = 0xFF;
    b.data[83] = 0xFF;
    r = read_bytes(b.data, b.size, MIO_FORMAT_STL, &c, &m, &e);
    check_error("stl binary huge count", r, &m, &e, MIO_ERR_TRUNCATED, 0);
    T_CHECK(c.bytes == 0);
    build_binary_stl(&b, "binary", 0, two_pos);
    r = read_bytes(b.data, b.size, MIO_FORMAT_STL, NULL, &m, &e);
    check_error("stl binary zero facets", r, &m, &e, MIO_ERR_EMPTY, 0);

    r = READ_TEXT("solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n  endloop\n endfacet\nendsolid t\n",
                  MIO_FORMAT_STL, &m, &e);
    check_error("stl ascii 2 vertices", r, &m, &e, MIO_ERR_SYNTAX, 6);
    r = READ_TEXT("solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n",
                  MIO_FORMAT_STL, &m, &e);
    check_error("stl ascii no endsolid", r, &m, &e, MIO_ERR_TRUNCATED, 9);
    r = READ_TEXT("solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1e40 0\n  endloop\n endfacet\nendsolid\n",
                  MIO_FORMAT_STL, &m, &e);
    check_error("stl ascii overflow", r, &m, &e, MIO_ERR_SYNTAX, 6);
    r = READ_TEXT("solid t\nendsolid t\njunk\n", MIO_FORMAT_STL, &m, &e);
    check_error("stl ascii trailing junk", r, &m, &e, MIO_ERR_SYNTAX, 3);
    r = READ_TEXT("solid t\nendsolid t\n", MIO_FORMAT_STL, &m, &e);
    check_error("stl ascii empty", r, &m, &e, MIO_ERR_EMPTY, 0);
}

/* ---------------------------------------------------------------------------------------------
   Detection, arguments, strings
   --------------------------------------------------------------------------------------------- */

static void test_detect_and_arguments(void)
{
    mio_mesh m;
    mio_error e;
    mio_result r;
    mio_read_options opt;
    mio_allocator broken = { NULL, NULL, NULL };
    int k;

    T_CHECK(mio_detect_format("ply\nformat ascii 1.0\n", 20, NULL) == MIO_FORMAT_PLY);
    T_CHECK(mio_detect_format("OFF\n3 1 0\n", 10, "x.obj") == MIO_FORMAT_OFF);
    T_CHECK(mio_detect_format("# c\nCOFF\n", 9, NULL) == MIO_FORMAT_OFF);
    T_CHECK(mio_detect_format("solid x\n", 8, "x.obj") == MIO_FORMAT_STL);
    T_CHECK(mio_detect_format("whatever", 8, "MODEL.STL") == MIO_FORMAT_STL);
    T_CHECK(mio_detect_format("whatever", 8, "a.Ply") == MIO_FORMAT_PLY);
    T_CHECK(mio_detect_format("whatever", 8, "a.off") == MIO_FORMAT_OFF);
    T_CHECK(mio_detect_format("whatever", 8, "a.obj") == MIO_FORMAT_OBJ);
    T_CHECK(mio_detect_format("# c\nv 1 2 3\n", 12, NULL) == MIO_FORMAT_OBJ);
    T_CHECK(mio_detect_format("mtllib a\n", 9, "noext") == MIO_FORMAT_OBJ);
    T_CHECK(mio_detect_format("hello\n", 6, "a.txt") == MIO_FORMAT_AUTO);
    T_CHECK(mio_detect_format(NULL, 0, NULL) == MIO_FORMAT_AUTO);
    T_CHECK(mio_detect_format("ply", 3, NULL) == MIO_FORMAT_AUTO);

    r = READ_TEXT("hello world\n", MIO_FORMAT_AUTO, &m, &e);
    check_error("unknown format", r, &m, &e, MIO_ERR_UNKNOWN_FORMAT, 0);
    for (k = MIO_FORMAT_AUTO; k <= MIO_FORMAT_STL; k++) {
        r = read_bytes("", 0, (mio_format)k, NULL, &m, &e);
        check_error("empty input", r, &m, &e, MIO_ERR_EMPTY, 0);
    }
    memset(&m, 0xAB, sizeof m);
    r = mio_read_memory(NULL, 5, NULL, &m, &e);
    T_CHECK(r == MIO_ERR_INVALID_ARGUMENT && e.code == r && mesh_is_zero(&m));
    T_CHECK(mio_read_memory("v", 1, NULL, NULL, &e) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_read_memory("v", 1, NULL, NULL, NULL) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_read_memory("v 0 0 0\n", 8, NULL, &m, NULL) == MIO_ERR_EMPTY && mesh_is_zero(&m));
    memset(&opt, 0, sizeof opt);
    opt.format = (mio_format)42;
    T_CHECK(mio_read_memory("v 0 0 0\n", 8, &opt, &m, &e) == MIO_ERR_INVALID_ARGUMENT);
    opt.format = MIO_FORMAT_AUTO;
    opt.allocator = &broken;
    T_CHECK(mio_read_memory("v 0 0 0\n", 8, &opt, &m, &e) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_read_file(NULL, NULL, &m, &e) == MIO_ERR_INVALID_ARGUMENT && mesh_is_zero(&m));
    T_CHECK(mio_read_file("/nonexistent/dir/x.obj", NULL, &m, &e) == MIO_ERR_IO && e.code == MIO_ERR_IO && mesh_is_zero(&m));
    T_CHECK(strstr(e.message, "/nonexistent/dir/x.obj") != NULL);
    T_CHECK(mio_read_file("/", NULL, &m, &e) != MIO_OK && mesh_is_zero(&m)); /* a directory */
    T_CHECK(mio_write_obj(NULL, tri_pos, 3, tri_idx, 1, &e) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_write_obj("/nonexistent/dir/x.obj", NULL, 3, tri_idx, 1, &e) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_write_ply("/nonexistent/dir/x.ply", tri_pos, 3, NULL, 1, 0, &e) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_write_ply("/nonexistent/dir/x.ply", tri_pos, 3, tri_idx, 1, 2, &e) == MIO_ERR_INVALID_ARGUMENT);
    T_CHECK(mio_write_obj("/nonexistent/dir/x.obj", tri_pos, 2, tri_idx, 1, &e) == MIO_ERR_INDEX_RANGE);
    T_CHECK(mio_write_obj("/nonexistent/dir/x.obj", tri_pos, 3, tri_idx, 1, &e) == MIO_ERR_IO && e.code == MIO_ERR_IO);
    T_CHECK(mio_write_ply("/nonexistent/dir/x.ply", tri_pos, 3, tri_idx, 1, 1, NULL) == MIO_ERR_IO);
    {
        float bad[9];
        memcpy(bad, tri_pos, sizeof bad);
        bad[4] = (float)HUGE_VAL;
        T_CHECK(mio_write_obj("/nonexistent/dir/x.obj", bad, 3, tri_idx, 1, &e) == MIO_ERR_INVALID_ARGUMENT);
        T_CHECK(mio_write_obj_normals("/nonexistent/dir/x.obj", tri_pos, bad, 3, tri_idx, 1, &e) == MIO_ERR_INVALID_ARGUMENT);
        T_CHECK(strstr(e.message, "normal 1") != NULL);
    }
    mio_free_mesh(NULL);
    memset(&m, 0, sizeof m);
    mio_free_mesh(&m);
    T_CHECK(mesh_is_zero(&m));
    T_EQ_STR(mio_result_string(MIO_OK), "MIO_OK");
    T_EQ_STR(mio_result_string(MIO_ERR_EMPTY), "MIO_ERR_EMPTY");
    T_EQ_STR(mio_result_string((mio_result)99), "MIO_ERR_?");
    T_EQ_STR(mio_format_string(MIO_FORMAT_PLY), "ply");
}

/* ---------------------------------------------------------------------------------------------
   Truncation at every byte, allocation-failure injection
   --------------------------------------------------------------------------------------------- */

/* Sample inputs of every format (binary ones filled in at run time). */
typedef struct sample {
    const char *name;
    const unsigned char *data;
    size_t size;
    mio_format format;
} sample;

static const char obj_sample[] = "# cube part\nv 0 0 0\nv 1 0 0\nv 1 1 0\r\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
                                 "f 1/1 2/1 3/1 4/1\nf 1//1 2//1 5//1\nf -1/1/1 -2/1/1 -3/1/1\ng x\nf 1 2 \\\n 5 3\nl 1 2\n";
static const char off_sample[] = "OFF\n# c\n5 3 0\n0 0 0\n1 0 0\n1 1 0 # c\n0 1 0\n0 0 1\n4 0 1 2 3 1 0 0\n3 0 1 4\n3 4 3 2\n";
static const char ply_sample[] = "ply\nformat ascii 1.0\ncomment c\nelement vertex 4\nproperty float x\nproperty double y\nproperty int z\n"
                                 "property list uchar float uv\nelement face 2\nproperty list uchar uint vertex_indices\n"
                                 "end_header\n0 0 0 2 0 0\n1 0 0 0\n1 1 0 1 5\n0 1 0 0\n4 0 1 2 3\n3 0 2 3\n";
static const char stl_sample[] = "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
                                 "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid a\n";

static size_t make_samples(sample *s, bytes *ply_le, bytes *ply_be, bytes *stl_bin)
{
    static const float two_pos[18] = { 1, 1, 0, -1, 1, 0, 0, -1, 0, 3, 3, 0, 2, 3, 0, 0, 2, 0 };
    size_t n = 0;
    build_binary_ply(ply_le, 0);
    build_binary_ply(ply_be, 1);
    build_binary_stl(stl_bin, "solid binary", 2, two_pos);
#define MIO_T_SAMPLE(nm, d, sz, f) do { s[n].name = nm; s[n].data = (const unsigned char *)(d); s[n].size = sz; s[n].format = f; n++; } while (0)
    MIO_T_SAMPLE("obj", obj_sample, sizeof obj_sample - 1, MIO_FORMAT_OBJ);
    MIO_T_SAMPLE("off", off_sample, sizeof off_sample - 1, MIO_FORMAT_OFF);
    MIO_T_SAMPLE("ply ascii", ply_sample, sizeof ply_sample - 1, MIO_FORMAT_PLY);
    MIO_T_SAMPLE("ply binary le", ply_le->data, ply_le->size, MIO_FORMAT_PLY);
    MIO_T_SAMPLE("ply binary be", ply_be->data, ply_be->size, MIO_FORMAT_PLY);
    MIO_T_SAMPLE("stl ascii", stl_sample, sizeof stl_sample - 1, MIO_FORMAT_STL);
    MIO_T_SAMPLE("stl binary", stl_bin->data, stl_bin->size, MIO_FORMAT_STL);
#undef MIO_T_SAMPLE
    return n;
}

/* Every prefix of the sample, read with the format forced and with AUTO: the result is either a
   valid mesh or an error with a zeroed mesh, and nothing leaks. */
static void test_truncations(const sample *s)
{
    size_t cut, bad_at = (size_t)-1, ok_count = 0;
    int pass;
    for (cut = 0; cut < s->size && bad_at == (size_t)-1; cut++) {
        for (pass = 0; pass < 2; pass++) {
            counter c;
            mio_mesh m;
            mio_error e;
            mio_result r;
            int good;
            counter_init(&c);
            r = read_bytes(s->data, cut, pass ? MIO_FORMAT_AUTO : s->format, &c, &m, &e);
            if (r == MIO_OK) {
                good = mesh_is_valid(&m) && e.code == MIO_OK;
                ok_count++;
            } else {
                good = mesh_is_zero(&m) && e.code == r && e.message[0] != '\0' && e.offset <= cut;
            }
            mio_free_mesh(&m);
            if (!good || c.live != 0) bad_at = cut;
        }
    }
    T_CHECK_MSG(bad_at == (size_t)-1, "%s: prefix of %zu bytes gave an invalid result or leaked", s->name, bad_at);
    T_CHECK_MSG(ok_count < 2 * s->size, "%s: every prefix accepted", s->name);
}

/* Fails the k-th allocation for every k up to the number a successful read makes. */
static void test_alloc_failures(const sample *s)
{
    counter c;
    mio_mesh m;
    mio_error e;
    mio_result r;
    size_t needed, k, bad_at = 0;
    counter_init(&c);
    r = read_bytes(s->data, s->size, s->format, &c, &m, &e);
    T_CHECK_MSG(r == MIO_OK, "%s: %s", s->name, e.message);
    T_CHECK(m.allocator.user == &c);
    mio_free_mesh(&m);
    T_CHECK_MSG(c.live == 0, "%s: %ld blocks leaked", s->name, c.live);
    needed = c.calls;
    T_CHECK(needed >= 2);
    for (k = 1; k <= needed; k++) {
        counter_init(&c);
        c.fail_at = k;
        r = read_bytes(s->data, s->size, s->format, &c, &m, &e);
        if (r != MIO_ERR_OUT_OF_MEMORY || c.live != 0 || !mesh_is_zero(&m) || e.code != r) bad_at = k;
        mio_free_mesh(&m);
    }
    T_CHECK_MSG(bad_at == 0, "%s: failing allocation %zu of %zu not reported as OUT_OF_MEMORY or leaked", s->name, bad_at, needed);
}

/* ---------------------------------------------------------------------------------------------
   Round trips through the writers
   --------------------------------------------------------------------------------------------- */

static void temp_path(char *buf, size_t cap, const char *tag)
{
    const char *dir = getenv("TMPDIR");
    if (!dir || !*dir) dir = "/tmp";
    snprintf(buf, cap, "%s/test_meshio_%ld_%s", dir, (long)getpid(), tag);
}

static uint32_t rng_next(uint64_t *state)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return (uint32_t)(*state >> 32);
}

/* Writes with kind 0..5 (obj, ascii ply, binary ply, off, ascii stl, binary stl). */
static mio_result write_kind(int kind, const char *path, const float *pos, size_t nv, const uint32_t *idx, size_t nt, mio_error *e)
{
    switch (kind) {
    case 0: return mio_write_obj(path, pos, nv, idx, nt, e);
    case 1: case 2: return mio_write_ply(path, pos, nv, idx, nt, kind - 1, e);
    case 3: return mio_write_off(path, pos, nv, idx, nt, e);
    case 6: return mio_write_obj_normals(path, pos, pos, nv, idx, nt, e); /* any finite floats serve as normals */
    default: return mio_write_stl(path, pos, nv, idx, nt, kind - 4, e);
    }
}

/* STL keeps no shared vertices: corner k of triangle t reads back as vertex 3t+k, with the bits of
   pos[idx[3t+k]], and the indices are 0, 1, 2, ... */
static int same_soup(const mio_mesh *m, const float *pos, const uint32_t *idx, size_t nt)
{
    size_t i;
    if (m->vertex_count != 3 * nt || m->triangle_count != nt) return 0;
    for (i = 0; i < 3 * nt; i++)
        if (m->indices[i] != (uint32_t)i || memcmp(m->positions + 3 * i, pos + 3 * (size_t)idx[i], 3 * sizeof(float)) != 0) return 0;
    return 1;
}

#define ROUND_TRIP_KINDS 7
static void round_trip(const char *what, const float *pos, size_t nv, const uint32_t *idx, size_t nt)
{
    static const char *const tags[ROUND_TRIP_KINDS] = { "rt.obj", "rt_ascii.ply", "rt_binary.ply", "rt.off", "rt_ascii.stl", "rt_binary.stl",
                                                        "rt_normals.obj" };
    int kind;
    for (kind = 0; kind < ROUND_TRIP_KINDS; kind++) {
        char path[512];
        mio_error e;
        mio_mesh m;
        mio_result r;
        counter c;
        mio_read_options opt;
        int same;
        temp_path(path, sizeof path, tags[kind]);
        r = write_kind(kind, path, pos, nv, idx, nt, &e);
        T_CHECK_MSG(r == MIO_OK, "%s %s write: %s", what, tags[kind], e.message);
        counter_init(&c);
        memset(&opt, 0, sizeof opt);
        opt.allocator = &c.a;
        r = mio_read_file(path, &opt, &m, &e);
        if (kind == 4 || kind == 5) same = r == MIO_OK && same_soup(&m, pos, idx, nt);
        else same = r == MIO_OK && m.vertex_count == nv && m.triangle_count == nt && same_floats(m.positions, pos, 3 * nv) &&
                    same_indices(m.indices, idx, 3 * nt);
        T_CHECK_MSG(same, "%s %s: read back %s (%s), not bit-exact", what, tags[kind], mio_result_string(r), e.message);
        mio_free_mesh(&m);
        T_CHECK(c.live == 0);
        remove(path);
    }
}

/* mio_write_obj_normals: one "vn" line per vertex, bit-exact, and faces naming them */
static void test_obj_normals(void)
{
    static const float nrm[9] = { 0.0f, 0.0f, 1.0f, 0.6f, 0.0f, 0.8f, -1.0f / 3.0f, 2.0f / 3.0f, 2.0f / 3.0f };
    char path[512], line[256];
    FILE *f;
    int nvn = 0, exact = 1, nf = 0;
    mio_error e;
    temp_path(path, sizeof path, "normals.obj");
    T_CHECK(mio_write_obj_normals(path, tri_pos, nrm, 3, tri_idx, 1, &e) == MIO_OK);
    f = fopen(path, "rb");
    while (f && fgets(line, sizeof line, f)) {
        if (strncmp(line, "vn ", 3) == 0 && nvn < 3) {
            char *q = line + 3;
            int k;
            for (k = 0; k < 3; k++) exact &= strtof(q, &q) == nrm[3 * nvn + k];
            nvn++;
        }
        if (strncmp(line, "f 1//1 2//2 3//3", 16) == 0) nf++;
    }
    if (f) fclose(f);
    T_CHECK(nvn == 3 && exact && nf == 1);
    remove(path);
}

static void test_round_trips(void)
{
    uint64_t state = 12345;
    size_t nv = 3000, nt = 5000, i;
    float *pos = (float *)malloc(nv * 3 * sizeof(float));
    uint32_t *idx = (uint32_t *)malloc(nt * 3 * sizeof(uint32_t));
    static const float special[] = { 0.0f, -0.0f, FLT_MIN, -FLT_MIN, FLT_MAX, -FLT_MAX, 1e-45f, -1e-45f, FLT_EPSILON,
                                     0.1f, 1.0f / 3.0f, 16777216.0f, 16777215.0f, 1e-38f, 1e38f, 3.14159274f };
    /* random bit patterns: every finite float, normal or subnormal, any exponent */
    for (i = 0; i < 3 * nv; i++) {
        uint32_t u;
        do u = rng_next(&state); while ((u & 0x7F800000u) == 0x7F800000u);
        memcpy(&pos[i], &u, 4);
    }
    memcpy(pos, special, sizeof special);
    for (i = 0; i < 3 * nt; i++) idx[i] = rng_next(&state) % (uint32_t)nv;
    round_trip("random bits", pos, nv, idx, nt);
    /* a regular grid with decimal coordinates */
    for (i = 0; i < nv; i++) {
        pos[3 * i] = (float)(i % 50) * 0.1f;
        pos[3 * i + 1] = (float)(i / 50) * -0.37f;
        pos[3 * i + 2] = (float)i * 1e-3f;
    }
    round_trip("grid", pos, nv, idx, nt);
    round_trip("one triangle", tri_pos, 3, tri_idx, 1);
    {   /* locale: writers must still print '.', the reader ignores the locale */
        static const char *const names[4] = { "de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "C.UTF-8" };
        int k, found = 0;
        for (k = 0; k < 4 && !found; k++) {
            if (!setlocale(LC_NUMERIC, names[k])) continue;
            {
                char buf[16];
                snprintf(buf, sizeof buf, "%.1f", 0.5);
                if (strcmp(buf, "0,5") != 0) { setlocale(LC_NUMERIC, "C"); continue; }
            }
            found = 1;
            round_trip("comma locale", pos, nv, idx, nt);
            setlocale(LC_NUMERIC, "C");
        }
        if (!found) T_SKIP_N(3 * ROUND_TRIP_KINDS, "comma-locale round trip", "no de_DE/fr_FR locale (make test generates de_DE.UTF-8 as root: localedef -i de_DE -f UTF-8 de_DE.UTF-8)");
    }
    {   /* allocation failures in mio_read_file (the file buffer too) */
        char path[512];
        counter c;
        mio_read_options opt;
        mio_mesh m;
        mio_error e;
        size_t needed, k, bad_at = 0;
        temp_path(path, sizeof path, "fail.obj");
        T_CHECK(mio_write_obj(path, pos, 100, idx, 10, &e) == MIO_ERR_INDEX_RANGE); /* indices reach 2999 */
        for (i = 0; i < 30; i++) idx[i] %= 100;
        T_CHECK(mio_write_obj(path, pos, 100, idx, 10, &e) == MIO_OK);
        counter_init(&c);
        memset(&opt, 0, sizeof opt);
        opt.allocator = &c.a;
        T_CHECK(mio_read_file(path, &opt, &m, &e) == MIO_OK && m.vertex_count == 100);
        mio_free_mesh(&m);
        needed = c.calls;
        for (k = 1; k <= needed; k++) {
            counter_init(&c);
            c.fail_at = k;
            if (mio_read_file(path, &opt, &m, &e) != MIO_ERR_OUT_OF_MEMORY || c.live != 0 || !mesh_is_zero(&m)) bad_at = k;
        }
        T_CHECK_MSG(bad_at == 0, "read_file: failing allocation %zu of %zu", bad_at, needed);
        remove(path);
    }
    free(pos);
    free(idx);
}

/* ---------------------------------------------------------------------------------------------
   mio_weld
   --------------------------------------------------------------------------------------------- */

static const float cube_pos[24] = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1 };
static const uint32_t cube_idx[36] = { 0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                       1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7 };

/* Every welded corner equals (float ==: -0 may have become +0) the original corner, and the
   welded positions are pairwise different (so nothing equal was left apart). */
static int weld_keeps_corners(const mio_mesh *m, const float *pos, const uint32_t *idx, size_t nt)
{
    size_t i, j, k;
    if (m->triangle_count != nt) return 0;
    for (i = 0; i < 3 * nt; i++)
        for (k = 0; k < 3; k++)
            if (!(m->positions[3 * (size_t)m->indices[i] + k] == pos[3 * (size_t)idx[i] + k])) return 0;
    for (i = 0; i < m->vertex_count; i++)
        for (j = i + 1; j < m->vertex_count; j++) {
            const float *a = m->positions + 3 * i, *b = m->positions + 3 * j;
            if (a[0] == b[0] && a[1] == b[1] && a[2] == b[2]) return 0;
        }
    return 1;
}

/* Reads the cube written as an STL soup (ascii or binary) with allocator c. */
static mio_result read_cube_soup(int binary, counter *c, mio_mesh *m)
{
    char path[512];
    mio_read_options opt;
    mio_error e;
    mio_result r;
    temp_path(path, sizeof path, binary ? "cube_b.stl" : "cube_a.stl");
    r = mio_write_stl(path, cube_pos, 8, cube_idx, 12, binary, &e);
    if (r != MIO_OK) return r;
    memset(&opt, 0, sizeof opt);
    opt.allocator = c ? &c->a : NULL;
    r = mio_read_file(path, &opt, m, &e);
    remove(path);
    return r;
}

static void test_weld_cube(void)
{
    int binary;
    for (binary = 0; binary < 2; binary++) {
        mio_mesh m;
        mio_error e;
        counter c;
        counter_init(&c);
        T_CHECK(read_cube_soup(binary, &c, &m) == MIO_OK && m.vertex_count == 36 && m.triangle_count == 12);
        T_CHECK(mio_weld(&m, &e) == MIO_OK && e.code == MIO_OK);
        T_EQ_SIZE(m.vertex_count, 8);
        T_CHECK(weld_keeps_corners(&m, cube_pos, cube_idx, 12));
        /* first-use order: the soup's corners visit the cube's vertices in the order 0 2 1 3 4 5 6 7 */
        {
            static const uint32_t order[8] = { 0, 2, 1, 3, 4, 5, 6, 7 };
            size_t k;
            int ok = m.vertex_count == 8;
            for (k = 0; k < 8 && ok; k++) ok = memcmp(m.positions + 3 * k, cube_pos + 3 * order[k], 3 * sizeof(float)) == 0;
            T_CHECK(ok);
        }
        mio_free_mesh(&m);
        T_CHECK_MSG(c.live == 0, "%ld blocks leaked", c.live);
    }
}

static void test_weld_unchanged_and_errors(void)
{
    mio_mesh m, copy;
    mio_error e;
    float pos[24];
    uint32_t idx[36];
    /* already welded: same arrays, same bits */
    memcpy(pos, cube_pos, sizeof pos);
    memcpy(idx, cube_idx, sizeof idx);
    memset(&m, 0, sizeof m);
    m.positions = pos; m.vertex_count = 8; m.indices = idx; m.triangle_count = 12;
    copy = m;
    T_CHECK(mio_weld(&m, &e) == MIO_OK);
    T_CHECK(m.positions == pos && m.indices == idx && m.vertex_count == 8 && m.triangle_count == 12);
    T_CHECK(same_floats(pos, cube_pos, 24) && same_indices(idx, cube_idx, 36));
    /* -0 and +0 are one vertex; the first occurrence's bits are kept */
    {
        static const float pz[12] = { 0.0f, 0, 0, -0.0f, 0, 0, 1, 0, 0, 0, 1, 0 };
        static const uint32_t iz[6] = { 1, 2, 3, 0, 3, 2 };
        mio_mesh z;
        memset(&z, 0, sizeof z);
        z.positions = (float *)malloc(sizeof pz);
        z.indices = (uint32_t *)malloc(sizeof iz);
        memcpy(z.positions, pz, sizeof pz);
        memcpy(z.indices, iz, sizeof iz);
        z.vertex_count = 4; z.triangle_count = 2;
        T_CHECK(mio_weld(&z, &e) == MIO_OK && z.vertex_count == 3);
        T_CHECK(z.vertex_count == 3 && !signbit(z.positions[0]) && z.indices[0] == 0 && z.indices[3] == 0);
        mio_free_mesh(&z);
    }
    /* errors leave the mesh as it was */
    T_CHECK(mio_weld(NULL, &e) == MIO_ERR_INVALID_ARGUMENT && e.code == MIO_ERR_INVALID_ARGUMENT);
    idx[5] = 8;
    T_CHECK(mio_weld(&m, &e) == MIO_ERR_INDEX_RANGE && e.code == MIO_ERR_INDEX_RANGE);
    idx[5] = cube_idx[5];
    pos[4] = (float)NAN;
    T_CHECK(mio_weld(&m, &e) == MIO_ERR_INVALID_ARGUMENT);
    pos[4] = cube_pos[4];
    m.positions = NULL;
    T_CHECK(mio_weld(&m, NULL) == MIO_ERR_INVALID_ARGUMENT);
    m = copy;
    T_CHECK(same_floats(pos, cube_pos, 24) && same_indices(idx, cube_idx, 36) && m.vertex_count == 8);
}

/* Fails the k-th allocation of mio_weld for every k: OUT_OF_MEMORY, mesh unchanged, nothing leaked. */
static void test_weld_alloc_failures(void)
{
    counter c;
    mio_mesh m, before;
    mio_error e;
    size_t base, needed, k, bad_at = 0;
    float snapshot[108];
    uint32_t snap_idx[36];
    counter_init(&c);
    T_CHECK(read_cube_soup(1, &c, &m) == MIO_OK && m.vertex_count == 36);
    base = c.calls;
    T_CHECK(mio_weld(&m, &e) == MIO_OK && m.vertex_count == 8);
    needed = c.calls - base;
    T_CHECK(needed == 2); /* the table + remap block, the new positions */
    mio_free_mesh(&m);
    for (k = 1; k <= needed; k++) {
        counter_init(&c);
        if (read_cube_soup(1, &c, &m) != MIO_OK || m.vertex_count != 36) { bad_at = k; continue; }
        memcpy(snapshot, m.positions, sizeof snapshot);
        memcpy(snap_idx, m.indices, sizeof snap_idx);
        before = m;
        c.fail_at = c.calls + k;
        if (mio_weld(&m, &e) != MIO_ERR_OUT_OF_MEMORY || e.code != MIO_ERR_OUT_OF_MEMORY || m.positions != before.positions ||
            m.vertex_count != 36 || !same_floats(m.positions, snapshot, 108) || !same_indices(m.indices, snap_idx, 36))
            bad_at = k;
        mio_free_mesh(&m);
        if (c.live != 0) bad_at = k;
    }
    T_CHECK_MSG(bad_at == 0, "mio_weld: failing allocation %zu of %zu", bad_at, needed);
}

/* A soup drawn from a pool of 200 positions (with -0/+0 twins): the weld gives exactly the distinct
   positions in their order of first occurrence, found here by brute force. */
static void test_weld_random(void)
{
    uint64_t state = 777;
    size_t nv = 3000, nt = 1000, i, j, distinct = 0;
    float pool[600], *pos = (float *)malloc(nv * 3 * sizeof(float)), *ref = (float *)malloc(nv * 3 * sizeof(float));
    uint32_t *idx = (uint32_t *)malloc(nt * 3 * sizeof(uint32_t)), *orig = (uint32_t *)malloc(nt * 3 * sizeof(uint32_t));
    mio_mesh m;
    mio_error e;
    int order_ok = 1;
    for (i = 0; i < 600; i++) pool[i] = (float)(rng_next(&state) % 7) - 3.0f; /* 0 appears: -0 below */
    for (i = 0; i < nv; i++) {
        uint32_t p = rng_next(&state) % 200;
        for (j = 0; j < 3; j++) {
            float x = pool[3 * p + j];
            pos[3 * i + j] = (x == 0.0f && (rng_next(&state) & 1)) ? -0.0f : x;
        }
    }
    for (i = 0; i < 3 * nt; i++) orig[i] = idx[i] = rng_next(&state) % (uint32_t)nv;
    for (i = 0; i < nv; i++) {
        const float *p = pos + 3 * i;
        for (j = 0; j < distinct; j++)
            if (ref[3 * j] == p[0] && ref[3 * j + 1] == p[1] && ref[3 * j + 2] == p[2]) break;
        if (j == distinct) { memcpy(ref + 3 * distinct, p, 3 * sizeof(float)); distinct++; }
    }
    memset(&m, 0, sizeof m);
    m.positions = pos; m.vertex_count = nv; m.indices = idx; m.triangle_count = nt;
    {   /* the corners' original positions, before the weld replaces pos */
        float *corners = (float *)malloc(nt * 9 * sizeof(float));
        uint32_t *seq = (uint32_t *)malloc(nt * 3 * sizeof(uint32_t));
        for (i = 0; i < 3 * nt; i++) { memcpy(corners + 3 * i, pos + 3 * (size_t)orig[i], 3 * sizeof(float)); seq[i] = (uint32_t)i; }
        T_CHECK(mio_weld(&m, &e) == MIO_OK);
        T_EQ_SIZE(m.vertex_count, distinct);
        T_CHECK(distinct < 200 + 100); /* the pool bounds it (plus -0 twins); the test means something */
        T_CHECK(weld_keeps_corners(&m, corners, seq, nt));
        for (i = 0; i < distinct && i < m.vertex_count; i++)
            if (memcmp(m.positions + 3 * i, ref + 3 * i, 3 * sizeof(float)) != 0) order_ok = 0;
        T_CHECK(order_ok);
        free(corners);
        free(seq);
    }
    mio_free_mesh(&m);
    free(ref);
    free(orig);
}

/* ---------------------------------------------------------------------------------------------
   Real files: the glmark2 bunny and the assimp test models against tests/meshio_assimp.tsv
   --------------------------------------------------------------------------------------------- */

#define ASSIMP_DIR "/usr/share/assimp/models"

typedef struct row {
    char path[128];
    char ours[40];
    char our_tris[24];
    char assimp_tris[24];
    char reason[600];
    int seen;
} row;

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static int cmp_triple(const void *a, const void *b)
{
    const float *x = (const float *)a, *y = (const float *)b;
    int k;
    for (k = 0; k < 3; k++)
        if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* The number of distinct positions, by sorting a copy (independent of mio_weld's hashing). */
static size_t distinct_positions(const float *pos, size_t n)
{
    float *copy = (float *)malloc(n * 3 * sizeof(float) + 1);
    size_t i, d = n ? 1 : 0;
    memcpy(copy, pos, n * 3 * sizeof(float));
    qsort(copy, n, 3 * sizeof(float), cmp_triple);
    for (i = 1; i < n; i++) d += cmp_triple(copy + 3 * (i - 1), copy + 3 * i) != 0;
    free(copy);
    return d;
}

/* The bunny written as binary STL (208998 corners) welds back to its distinct positions, each
   corner at its original place. */
static void bunny_weld(const mio_mesh *orig)
{
    char path[512];
    mio_mesh s;
    mio_error e;
    size_t i, d = distinct_positions(orig->positions, orig->vertex_count);
    int corners_ok = 1;
    temp_path(path, sizeof path, "bunny.stl");
    T_CHECK(mio_write_stl(path, orig->positions, orig->vertex_count, orig->indices, orig->triangle_count, 1, &e) == MIO_OK);
    T_CHECK(mio_read_file(path, NULL, &s, &e) == MIO_OK && s.vertex_count == 3 * orig->triangle_count);
    remove(path);
    T_CHECK(mio_weld(&s, &e) == MIO_OK);
    T_EQ_SIZE(s.vertex_count, d);
    for (i = 0; i < 3 * orig->triangle_count && s.triangle_count == orig->triangle_count; i++)
        if (memcmp(s.positions + 3 * (size_t)s.indices[i], orig->positions + 3 * (size_t)orig->indices[i], 3 * sizeof(float)) != 0)
            corners_ok = 0;
    T_CHECK(corners_ok && s.triangle_count == orig->triangle_count);
    mio_free_mesh(&s);
}

static void test_bunny(void)
{
    const char *path = "/usr/share/glmark2/models/bunny.obj";
    mio_mesh m;
    mio_error e;
    mio_result r;
    if (!file_exists(path)) {
        T_SKIP_N(9, "bunny.obj", "/usr/share/glmark2/models/bunny.obj missing: apt-get install glmark2-data");
        return;
    }
    r = mio_read_file(path, NULL, &m, &e);
    T_CHECK_MSG(r == MIO_OK, "%s", e.message);
    T_EQ_SIZE(m.vertex_count, 34835);
    T_EQ_SIZE(m.triangle_count, 69666);
    T_CHECK(r == MIO_OK && mesh_is_valid(&m));
    if (r == MIO_OK) bunny_weld(&m);
    else T_SKIP_N(5, "bunny weld", "bunny.obj unreadable (failed above)");
    mio_free_mesh(&m);
}

static size_t load_table(const char *path, row *rows, size_t cap)
{
    FILE *f = fopen(path, "r");
    char line[1024];
    size_t n = 0;
    int header_seen = 0;
    if (!f) return 0;
    while (fgets(line, sizeof line, f) && n < cap) {
        char *fields[5];
        char *p = line;
        int k;
        size_t len = strlen(line);
        while (len && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
        if (line[0] == '#' || line[0] == '\0') continue;
        if (!header_seen) { header_seen = 1; continue; } /* column names */
        for (k = 0; k < 5; k++) {
            fields[k] = p;
            p = k < 4 ? strchr(p, '\t') : NULL;
            if (k < 4) {
                if (!p) break;
                *p++ = '\0';
            }
        }
        if (k < 5) continue; /* malformed row: it will show up as a missing row */
        memset(&rows[n], 0, sizeof rows[n]);
        snprintf(rows[n].path, sizeof rows[n].path, "%s", fields[0]);
        snprintf(rows[n].ours, sizeof rows[n].ours, "%s", fields[1]);
        snprintf(rows[n].our_tris, sizeof rows[n].our_tris, "%s", fields[2]);
        snprintf(rows[n].assimp_tris, sizeof rows[n].assimp_tris, "%s", fields[3]);
        snprintf(rows[n].reason, sizeof rows[n].reason, "%s", fields[4]);
        n++;
    }
    fclose(f);
    return n;
}

/* Sum of faces of the meshes whose primitive type is exactly "triangle" in `assimp info`;
   "fail" when the import fails. */
static void assimp_triangles(const char *path, char *out, size_t cap)
{
    char cmd[1024], line[1024];
    FILE *p;
    long sum = 0;
    int in_meshes = 0, imported = 0;
    snprintf(cmd, sizeof cmd, "assimp info '%s' 2>/dev/null", path);
    p = popen(cmd, "r");
    if (!p) { snprintf(out, cap, "popen-failed"); return; }
    while (fgets(line, sizeof line, p)) {
        if (strncmp(line, "Importing file", 14) == 0 && strstr(line, "OK")) imported = 1;
        if (strncmp(line, "Meshes:  (name)", 15) == 0) { in_meshes = 1; continue; }
        if (in_meshes) {
            char *open = strrchr(line, '['), *bar;
            unsigned long v = 0, b = 0, faces = 0;
            char type[64];
            if (!open) { if (line[0] == '\n' || line[0] == '\0') in_meshes = 0; continue; }
            bar = strchr(open, '|');
            if (!bar || sscanf(open, "[%lu / %lu / %lu", &v, &b, &faces) != 3 || sscanf(bar + 1, " %63[a-z]", type) != 1) continue;
            if (strcmp(type, "triangle") == 0 && bar[1 + strspn(bar + 1, " ") + 8] == ']') sum += (long)faces;
        }
    }
    pclose(p);
    if (!imported) snprintf(out, cap, "fail");
    else snprintf(out, cap, "%ld", sum);
}

static int wanted_file(const char *dir, const char *name)
{
    const char *dot = strrchr(name, '.');
    char ext[16] = "";
    size_t k;
    if (dot && strlen(dot + 1) < sizeof ext)
        for (k = 0; dot[1 + k]; k++) ext[k] = (char)((dot[1 + k] >= 'A' && dot[1 + k] <= 'Z') ? dot[1 + k] - 'A' + 'a' : dot[1 + k]);
    if (strcmp(dir, "invalid") == 0)
        return strcmp(ext, "obj") == 0 || strcmp(ext, "off") == 0 || strcmp(ext, "ply") == 0 || strcmp(ext, "stl") == 0;
    return strcmp(ext, "mtl") != 0 && strcmp(ext, "jpg") != 0 && strcmp(ext, "jpeg") != 0 && strcmp(ext, "png") != 0 &&
           strcmp(ext, "bmp") != 0 && strcmp(ext, "tga") != 0;
}

static int compare_names(const void *a, const void *b) { return strcmp(*(const char *const *)a, *(const char *const *)b); }

static void test_assimp_models(const char *table_path)
{
    static const char *const dirs[5] = { "OBJ", "OFF", "PLY", "STL", "invalid" };
    /* assimp spends about two minutes failing on this one (353535235358 vertices claimed) */
    static const char *const too_slow_for_assimp = "invalid/OutOfMemory.off";
    static row rows[256];
    size_t nrows, i;
    long assimp_unchecked = 0;
    int d, have_assimp;
    if (access(ASSIMP_DIR, F_OK) != 0) {
        T_SKIP("assimp test models", ASSIMP_DIR " missing: apt-get install assimp-testmodels");
        return;
    }
    nrows = load_table(table_path, rows, sizeof rows / sizeof rows[0]);
    T_CHECK_MSG(nrows > 0, "cannot read %s", table_path);
    have_assimp = system("command -v assimp >/dev/null 2>&1") == 0;
    for (d = 0; d < 5; d++) {
        char dirpath[256];
        DIR *dir;
        struct dirent *ent;
        char *names[256];
        size_t nnames = 0, k;
        snprintf(dirpath, sizeof dirpath, "%s/%s", ASSIMP_DIR, dirs[d]);
        dir = opendir(dirpath);
        T_CHECK_MSG(dir != NULL, "cannot list %s", dirpath);
        if (!dir) continue;
        while ((ent = readdir(dir)) != NULL && nnames < 256) {
            char full[600];
            snprintf(full, sizeof full, "%s/%s", dirpath, ent->d_name);
            if (!file_exists(full) || !wanted_file(dirs[d], ent->d_name)) continue;
            names[nnames++] = strdup(ent->d_name);
        }
        closedir(dir);
        qsort(names, nnames, sizeof names[0], compare_names);
        for (k = 0; k < nnames; k++) {
            char rel[300], full[600], tris[24];
            row *rw = NULL;
            mio_mesh m;
            mio_error e;
            mio_result r;
            int ours_ok, assimp_ok, differs;
            snprintf(rel, sizeof rel, "%s/%s", dirs[d], names[k]);
            snprintf(full, sizeof full, "%s/%s", ASSIMP_DIR, rel);
            free(names[k]);
            for (i = 0; i < nrows; i++) if (strcmp(rows[i].path, rel) == 0) rw = &rows[i];
            T_CHECK_MSG(rw != NULL, "%s has no row in %s", rel, table_path);
            r = mio_read_file(full, NULL, &m, &e);
            if (r == MIO_OK) snprintf(tris, sizeof tris, "%zu", m.triangle_count);
            else snprintf(tris, sizeof tris, "-");
            T_CHECK_MSG(r == MIO_OK ? mesh_is_valid(&m) : mesh_is_zero(&m), "%s", rel);
            mio_free_mesh(&m);
            if (strcmp(dirs[d], "invalid") == 0) T_CHECK_MSG(r != MIO_OK, "%s under invalid/ was accepted", rel);
            if (!rw) continue;
            rw->seen = 1;
            T_CHECK_MSG(strcmp(rw->ours, mio_result_string(r) + (r == MIO_OK ? 4 : 0)) == 0 && strcmp(rw->our_tris, tris) == 0,
                        "%s: we give %s %s, table says %s %s (%s)", rel, r == MIO_OK ? "OK" : mio_result_string(r), tris, rw->ours,
                        rw->our_tris, e.message);
            ours_ok = strcmp(rw->ours, "OK") == 0;
            assimp_ok = strcmp(rw->assimp_tris, "fail") != 0;
            differs = ours_ok != assimp_ok || (ours_ok && strcmp(rw->our_tris, rw->assimp_tris) != 0);
            T_CHECK_MSG(differs ? (rw->reason[0] != '\0' && strcmp(rw->reason, "-") != 0) : strcmp(rw->reason, "-") == 0,
                        "%s: reason column must be %s", rel, differs ? "filled (outcomes differ)" : "'-' (outcomes agree)");
            if (!have_assimp) {
                assimp_unchecked++;
            } else {
                if (strcmp(rel, too_slow_for_assimp) == 0) {
                    T_SKIP(rel, "assimp info needs about two minutes to fail on this file; its 'fail' was measured once by hand");
                } else {
                    char theirs[32];
                    assimp_triangles(full, theirs, sizeof theirs);
                    T_CHECK_MSG(strcmp(theirs, rw->assimp_tris) == 0, "%s: assimp gives %s, table says %s", rel, theirs, rw->assimp_tris);
                }
            }
        }
    }
    for (i = 0; i < nrows; i++) T_CHECK_MSG(rows[i].seen, "table row %s names no file", rows[i].path);
    if (assimp_unchecked)
        T_SKIP_N(assimp_unchecked, "assimp info cross-check of the table's assimp column", "assimp not on PATH: apt-get install assimp-utils");
}

/* ---------------------------------------------------------------------------------------------
   main
   --------------------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    sample samples[8];
    bytes ply_le, ply_be, stl_bin;
    size_t n, i;
    char table[512];
    const char *slash;
    T_BEGIN(argc, argv);
    test_obj();
    test_off();
    test_ply();
    test_stl();
    test_detect_and_arguments();
    n = make_samples(samples, &ply_le, &ply_be, &stl_bin);
    for (i = 0; i < n; i++) {
        test_truncations(&samples[i]);
        test_alloc_failures(&samples[i]);
    }
    test_obj_normals(); /* strtof: before the round trips try a comma locale */
    test_round_trips();
    test_weld_cube();
    test_weld_unchanged_and_errors();
    test_weld_alloc_failures();
    test_weld_random();
    test_bunny();
    /* the table sits beside this source file (found from the repository top, where tests/run.sh
       runs tests); MIO_ASSIMP_TABLE names another file */
    slash = strrchr(__FILE__, '/');
    if (getenv("MIO_ASSIMP_TABLE")) snprintf(table, sizeof table, "%s", getenv("MIO_ASSIMP_TABLE"));
    else if (getenv("TOP")) snprintf(table, sizeof table, "%s/tests/meshio_assimp.tsv", getenv("TOP")); /* tests/run.sh */
    else if (slash) snprintf(table, sizeof table, "%.*s/meshio_assimp.tsv", (int)(slash - __FILE__), __FILE__);
    else snprintf(table, sizeof table, "meshio_assimp.tsv");
    test_assimp_models(table);
    return T_END();
}
