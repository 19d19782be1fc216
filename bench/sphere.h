/* sphere.h - deterministic bumpy geodesic icosphere for tests and benchmarks (C99 and C++)

   Used by bench/gen_sphere.c (writes build/sphere1m.off), tests/test_sphere.c and
   tests/ref_openmesh.cpp. Not a library of the project: every function is static inline, so the
   header can be included in any number of translation units.

       gsph_mesh m;
       if (gsph_generate(224, &m) != 0) { ...out of memory or bad frequency... }
       // m.positions: 3 floats per vertex, m.indices: 3 uint32 per triangle (CCW seen from outside)
       gsph_write_off(stdout_or_file, &m);   // returns 0, or -1 on a write error
       gsph_free(&m);

   Shape: each face of a regular icosahedron is cut into freq^2 triangles by a triangular
   lattice; lattice points are projected to the unit sphere. Vertices on icosahedron edges and
   corners are shared by the faces meeting there, so the mesh is closed, genus 0, with exactly
       V = 10 freq^2 + 2 vertices,  T = 20 freq^2 triangles,  E = 30 freq^2 edges
   (freq 224: 501,762 vertices, 1,003,520 triangles). Every vertex is then moved along its
   radius to r = 1 + d(p), where d is a sum of three sinusoids (amplitude 0.012 + 0.008 + 0.005)
   and a value noise (amplitude 0.004). The noise is hashed from integer lattice coordinates,
   so the output is a pure function of freq (no rand(), no global state).

   Why no triangle can flip: with all vertices on rays from the origin and r > 0, the signed
   volume det(p0,p1,p2) = r0 r1 r2 det(u0,u1,u2) keeps the sign of the undisplaced triangle on
   the unit sphere, and for a triangle n . centroid = det(p0,p1,p2); |d| <= 0.029 keeps r > 0.97.

   Vertex order: the 12 icosahedron corners, then (freq-1) points per icosahedron edge (edges in
   a fixed table order, each walked from its lower- to its higher-numbered corner), then the
   interior points of each face in face order, row by row.

   Errors: gsph_generate returns -1 for freq < 1 or freq > GSPH_MAX_FREQ (sizes fit uint32 and
   int) or when malloc fails, leaving *out zeroed. */
#ifndef GSPH_SPHERE_H
#define GSPH_SPHERE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

/* 10 * 20000^2 + 2 < 2^32; also keeps every size product far below SIZE_MAX on 64-bit */
#define GSPH_MAX_FREQ 20000

/* static inline: private to each includer, and no unused-function warnings */
#define GSPH_DEF static inline

typedef struct gsph_mesh {
    float *positions;       /* 3 * vertex_count */
    size_t vertex_count;
    uint32_t *indices;      /* 3 * triangle_count, counter-clockwise seen from outside */
    size_t triangle_count;
} gsph_mesh;

/* ---- icosahedron ---------------------------------------------------------------------- */

/* corners (0, +-1, +-phi) and cyclic permutations; faces listed counter-clockwise from outside */
static const double gsph__phi = 1.6180339887498948482;

GSPH_DEF void gsph__corner(int c, double p[3])
{
    static const signed char table[12][3] = {
        {-1, 2, 0}, {1, 2, 0}, {-1, -2, 0}, {1, -2, 0},
        {0, -1, 2}, {0, 1, 2}, {0, -1, -2}, {0, 1, -2},
        {2, 0, -1}, {2, 0, 1}, {-2, 0, -1}, {-2, 0, 1}};
    int k;
    double len2 = 0.0;
    for (k = 0; k < 3; k++) {
        int s = table[c][k];
        /* entry +-1 is the unit coordinate, +-2 stands for +-phi */
        p[k] = (s == 1 || s == -1) ? (double)s : (s == 0 ? 0.0 : (s > 0 ? gsph__phi : -gsph__phi));
        len2 += p[k] * p[k];
    }
    for (k = 0; k < 3; k++) p[k] /= sqrt(len2);
}

static const unsigned char gsph__faces[20][3] = {
    {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
    {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
    {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
    {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};

/* the 30 edges, lower corner first, in the order they first appear in gsph__faces */
GSPH_DEF void gsph__edges(unsigned char edges[30][2])
{
    int f, k, n = 0;
    for (f = 0; f < 20; f++)
        for (k = 0; k < 3; k++) {
            int a = gsph__faces[f][k], b = gsph__faces[f][(k + 1) % 3], e, found = 0;
            int lo = a < b ? a : b, hi = a < b ? b : a;
            for (e = 0; e < n; e++)
                if (edges[e][0] == lo && edges[e][1] == hi) found = 1;
            if (!found && n < 30) {
                edges[n][0] = (unsigned char)lo;
                edges[n][1] = (unsigned char)hi;
                n++;
            }
        }
}

GSPH_DEF int gsph__edge_id(const unsigned char edges[30][2], int a, int b)
{
    int e, lo = a < b ? a : b, hi = a < b ? b : a;
    for (e = 0; e < 30; e++)
        if (edges[e][0] == lo && edges[e][1] == hi) return e;
    return -1; /* unreachable for edges of gsph__faces */
}

/* ---- displacement ----------------------------------------------------------------------- */

GSPH_DEF uint32_t gsph__hash3(int32_t x, int32_t y, int32_t z)
{
    /* integer mix (lowbias32 finaliser) over the three lattice coordinates */
    uint32_t h = (uint32_t)x * 0x8da6b343u ^ (uint32_t)y * 0xd8163841u ^ (uint32_t)z * 0xcb1ab31fu;
    h ^= h >> 16; h *= 0x7feb352du;
    h ^= h >> 15; h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

GSPH_DEF double gsph__lattice_value(int32_t x, int32_t y, int32_t z)
{
    return (double)(gsph__hash3(x, y, z) >> 8) * (2.0 / 16777216.0) - 1.0; /* [-1, 1) */
}

GSPH_DEF double gsph__smooth(double t) { return t * t * (3.0 - 2.0 * t); }

/* trilinear value noise with smoothstep weights, in [-1, 1] */
GSPH_DEF double gsph__value_noise(double x, double y, double z)
{
    double fx = floor(x), fy = floor(y), fz = floor(z);
    int32_t ix = (int32_t)fx, iy = (int32_t)fy, iz = (int32_t)fz;
    double wx = gsph__smooth(x - fx), wy = gsph__smooth(y - fy), wz = gsph__smooth(z - fz);
    double c[2][2][2];
    int a, b, d;
    for (a = 0; a < 2; a++)
        for (b = 0; b < 2; b++)
            for (d = 0; d < 2; d++) c[a][b][d] = gsph__lattice_value(ix + a, iy + b, iz + d);
    {
        double x00 = c[0][0][0] + wx * (c[1][0][0] - c[0][0][0]);
        double x10 = c[0][1][0] + wx * (c[1][1][0] - c[0][1][0]);
        double x01 = c[0][0][1] + wx * (c[1][0][1] - c[0][0][1]);
        double x11 = c[0][1][1] + wx * (c[1][1][1] - c[0][1][1]);
        double y0 = x00 + wy * (x10 - x00), y1 = x01 + wy * (x11 - x01);
        return y0 + wz * (y1 - y0);
    }
}

/* radial offset for a unit direction u; |result| <= 0.029 */
GSPH_DEF double gsph__displacement(const double u[3])
{
    double d = 0.012 * sin(5.0 * u[0] + 0.7) * sin(4.0 * u[1] + 0.3);
    d += 0.008 * sin(11.0 * u[2] + 9.0 * u[0] + 1.9);
    d += 0.005 * sin(23.0 * u[1] - 17.0 * u[2] + 0.4);
    d += 0.004 * gsph__value_noise(40.0 * u[0] + 100.5, 40.0 * u[1] + 200.5, 40.0 * u[2] + 300.5);
    return d;
}

/* projects p to the unit sphere, displaces it and stores it as vertex v */
GSPH_DEF void gsph__store_vertex(float *positions, size_t v, const double p[3])
{
    double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    double u[3], r;
    int k;
    for (k = 0; k < 3; k++) u[k] = p[k] / len;
    r = 1.0 + gsph__displacement(u);
    for (k = 0; k < 3; k++) positions[3 * v + (size_t)k] = (float)(r * u[k]);
}

/* ---- generation ------------------------------------------------------------------------- */

GSPH_DEF void gsph_free(gsph_mesh *m)
{
    if (!m) return;
    free(m->positions);
    free(m->indices);
    memset(m, 0, sizeof *m);
}

/* number of vertices and triangles for a frequency, without generating anything */
GSPH_DEF void gsph_counts(int freq, size_t *vertex_count, size_t *triangle_count)
{
    size_t f = freq > 0 ? (size_t)freq : 0;
    if (vertex_count) *vertex_count = 10 * f * f + 2;
    if (triangle_count) *triangle_count = 20 * f * f;
}

/* Fills *out with the sphere of frequency freq (1..GSPH_MAX_FREQ). Returns 0, or -1 with *out
   zeroed. Free with gsph_free. */
GSPH_DEF int gsph_generate(int freq, gsph_mesh *out)
{
    unsigned char edges[30][2];
    uint32_t *lattice = NULL; /* (F+1)^2 global indices for the face being emitted */
    size_t F, V, T, edge_base, face_base, interior_per_face, t = 0;
    int e, f, c;

    if (!out) return -1;
    memset(out, 0, sizeof *out);
    if (freq < 1 || freq > GSPH_MAX_FREQ) return -1;
    F = (size_t)freq;
    gsph_counts(freq, &V, &T);
    edge_base = 12;
    face_base = edge_base + 30 * (F - 1);
    interior_per_face = (F - 1) * (F - 2) / 2; /* lattice points with all three weights >= 1 */

    out->positions = (float *)malloc(3 * V * sizeof(float));
    out->indices = (uint32_t *)malloc(3 * T * sizeof(uint32_t));
    lattice = (uint32_t *)malloc((F + 1) * (F + 1) * sizeof(uint32_t));
    if (!out->positions || !out->indices || !lattice) {
        free(lattice);
        gsph_free(out);
        return -1;
    }
    out->vertex_count = V;
    out->triangle_count = T;
    gsph__edges(edges);

    for (c = 0; c < 12; c++) {
        double p[3];
        gsph__corner(c, p);
        gsph__store_vertex(out->positions, (size_t)c, p);
    }
    /* edge points are computed once, from the edge's own endpoints, so faces share bits */
    for (e = 0; e < 30; e++) {
        double a[3], b[3];
        size_t s;
        gsph__corner(edges[e][0], a);
        gsph__corner(edges[e][1], b);
        for (s = 1; s < F; s++) {
            double w = (double)s / (double)F, p[3];
            int k;
            for (k = 0; k < 3; k++) p[k] = (1.0 - w) * a[k] + w * b[k];
            gsph__store_vertex(out->positions, edge_base + (size_t)e * (F - 1) + (s - 1), p);
        }
    }

    for (f = 0; f < 20; f++) {
        int ca = gsph__faces[f][0], cb = gsph__faces[f][1], cc = gsph__faces[f][2];
        int e_ab = gsph__edge_id((const unsigned char(*)[2])edges, ca, cb);
        int e_bc = gsph__edge_id((const unsigned char(*)[2])edges, cb, cc);
        int e_ac = gsph__edge_id((const unsigned char(*)[2])edges, ca, cc);
        double A[3], B[3], C[3];
        size_t i, j, next_interior = face_base + (size_t)f * interior_per_face;
        gsph__corner(ca, A);
        gsph__corner(cb, B);
        gsph__corner(cc, C);

        /* lattice point (i, j) has weights (F-i-j, i, j) on corners (a, b, c) */
        for (j = 0; j <= F; j++)
            for (i = 0; i + j <= F; i++) {
                size_t k = F - i - j, id;
                if (k == F) id = (size_t)ca;
                else if (i == F) id = (size_t)cb;
                else if (j == F) id = (size_t)cc;
                else if (j == 0) /* edge a-b, i steps from a */
                    id = edge_base + (size_t)e_ab * (F - 1) + (ca < cb ? i : F - i) - 1;
                else if (i == 0) /* edge a-c, j steps from a */
                    id = edge_base + (size_t)e_ac * (F - 1) + (ca < cc ? j : F - j) - 1;
                else if (k == 0) /* edge b-c, j steps from b */
                    id = edge_base + (size_t)e_bc * (F - 1) + (cb < cc ? j : F - j) - 1;
                else {
                    double p[3];
                    int q;
                    for (q = 0; q < 3; q++)
                        p[q] = ((double)k * A[q] + (double)i * B[q] + (double)j * C[q]) / (double)F;
                    id = next_interior++;
                    gsph__store_vertex(out->positions, id, p);
                }
                lattice[j * (F + 1) + i] = (uint32_t)id;
            }

        /* "up" triangles (i,j),(i+1,j),(i,j+1) keep the orientation of (a,b,c); "down"
           triangles (i+1,j),(i+1,j+1),(i,j+1) fill the gaps with the same orientation */
        for (j = 0; j < F; j++)
            for (i = 0; i + j < F; i++) {
                uint32_t *tri = out->indices + 3 * t++;
                tri[0] = lattice[j * (F + 1) + i];
                tri[1] = lattice[j * (F + 1) + i + 1];
                tri[2] = lattice[(j + 1) * (F + 1) + i];
                if (i + j + 1 < F) {
                    tri = out->indices + 3 * t++;
                    tri[0] = lattice[j * (F + 1) + i + 1];
                    tri[1] = lattice[(j + 1) * (F + 1) + i + 1];
                    tri[2] = lattice[(j + 1) * (F + 1) + i];
                }
            }
    }
    free(lattice);
    return 0;
}

/* Writes the mesh as ASCII OFF ("OFF", "V T 0", vertices with %.9g so floats round-trip
   exactly, then "3 a b c" per triangle). Returns 0, or -1 if any write failed. */
GSPH_DEF int gsph_write_off(FILE *file, const gsph_mesh *m)
{
    size_t v, t;
    int bad = 0;
    if (!file || !m) return -1;
    if (fprintf(file, "OFF\n%lu %lu 0\n", (unsigned long)m->vertex_count,
                (unsigned long)m->triangle_count) < 0)
        bad = 1;
    for (v = 0; v < m->vertex_count && !bad; v++) {
        const float *p = m->positions + 3 * v;
        if (fprintf(file, "%.9g %.9g %.9g\n", (double)p[0], (double)p[1], (double)p[2]) < 0) bad = 1;
    }
    for (t = 0; t < m->triangle_count && !bad; t++) {
        const uint32_t *tri = m->indices + 3 * t;
        if (fprintf(file, "3 %lu %lu %lu\n", (unsigned long)tri[0], (unsigned long)tri[1],
                    (unsigned long)tri[2]) < 0)
            bad = 1;
    }
    if (fflush(file) != 0 || ferror(file)) bad = 1;
    return bad ? -1 : 0;
}

#endif /* GSPH_SPHERE_H */
