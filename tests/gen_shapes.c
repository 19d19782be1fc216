/* gen_shapes.c - generated test meshes for tests/dispmesh_meshes.sh (issue 16's many-mesh test), as
   ASCII OFF:
     gen_shapes parts OUT.off   three closed components: a bumpy sphere, a smaller one beside it and a
                                thin limb (an ellipsoid 10 times longer than it is thick), 16k triangles
     gen_shapes open OUT.off    an open bumpy height-field patch (a boundary all round), 8k triangles
   Exit status: 0 written, 1 the file could not be written, 2 usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

typedef struct shape {
    double *p;   /* 3 per vertex */
    int *t;      /* 3 per triangle */
    int nv, nt, cv, ct;
} shape;

static int add_vertex(shape *s, double x, double y, double z)
{
    if (s->nv == s->cv) {
        double *np2;
        s->cv = s->cv ? 2 * s->cv : 1024;
        np2 = (double *)realloc(s->p, (size_t)s->cv * 3 * sizeof(double));
        if (!np2) return -1;
        s->p = np2;
    }
    s->p[3 * s->nv] = x;
    s->p[3 * s->nv + 1] = y;
    s->p[3 * s->nv + 2] = z;
    return s->nv++;
}

static int add_triangle(shape *s, int a, int b, int c)
{
    if (a < 0 || b < 0 || c < 0) return 0;
    if (s->nt == s->ct) {
        int *nt2;
        s->ct = s->ct ? 2 * s->ct : 1024;
        nt2 = (int *)realloc(s->t, (size_t)s->ct * 3 * sizeof(int));
        if (!nt2) return 0;
        s->t = nt2;
    }
    s->t[3 * s->nt] = a;
    s->t[3 * s->nt + 1] = b;
    s->t[3 * s->nt + 2] = c;
    s->nt++;
    return 1;
}

/* a closed latitude-longitude ellipsoid (semi-axes a, b, c, centre o) with a bump of relative height
   bump; nlat rows, nlon columns, one vertex at each pole; outward (counter-clockwise) faces */
static int ellipsoid(shape *s, const double o[3], double a, double b, double c, double bump, int nlat, int nlon)
{
    int i, j, first, north, south, ok = 1;
    north = add_vertex(s, o[0], o[1], o[2] + c * (1.0 + bump * 0.0));
    first = s->nv;
    for (i = 1; i < nlat; i++)
        for (j = 0; j < nlon; j++) {
            double th = PI * i / nlat, ph = 2.0 * PI * j / nlon;
            double r = 1.0 + bump * sin(5.0 * ph) * sin(3.0 * th) * sin(th);
            add_vertex(s, o[0] + a * r * sin(th) * cos(ph), o[1] + b * r * sin(th) * sin(ph), o[2] + c * r * cos(th));
        }
    south = add_vertex(s, o[0], o[1], o[2] - c);
    if (s->nv != first + (nlat - 1) * nlon + 1) return 0;
    for (j = 0; j < nlon; j++) {
        int j1 = (j + 1) % nlon;
        ok &= add_triangle(s, north, first + j, first + j1);
        ok &= add_triangle(s, south, first + (nlat - 2) * nlon + j1, first + (nlat - 2) * nlon + j);
    }
    for (i = 0; i + 2 < nlat; i++)
        for (j = 0; j < nlon; j++) {
            int j1 = (j + 1) % nlon, v00 = first + i * nlon + j, v01 = first + i * nlon + j1;
            int v10 = v00 + nlon, v11 = v01 + nlon;
            ok &= add_triangle(s, v00, v10, v11);
            ok &= add_triangle(s, v00, v11, v01);
        }
    return ok;
}

/* an open patch z = h(x, y) over [-1, 1]^2, n x n quads, faces up */
static int patch(shape *s, int n)
{
    int i, j, first = s->nv, ok = 1;
    for (j = 0; j <= n; j++)
        for (i = 0; i <= n; i++) {
            double x = -1.0 + 2.0 * i / n, y = -1.0 + 2.0 * j / n;
            double z = 0.15 * sin(3.0 * x) * cos(2.0 * y) + 0.05 * sin(7.0 * x + 5.0 * y);
            if (add_vertex(s, x, y, z) < 0) return 0;
        }
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            int v00 = first + j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
            ok &= add_triangle(s, v00, v10, v11);
            ok &= add_triangle(s, v00, v11, v01);
        }
    return ok;
}

static int write_off(const shape *s, const char *path)
{
    FILE *f = fopen(path, "w");
    int i, ok;
    if (!f) return 0;
    fprintf(f, "OFF\n%d %d 0\n", s->nv, s->nt);
    for (i = 0; i < s->nv; i++) fprintf(f, "%.9g %.9g %.9g\n", s->p[3 * i], s->p[3 * i + 1], s->p[3 * i + 2]);
    for (i = 0; i < s->nt; i++) fprintf(f, "3 %d %d %d\n", s->t[3 * i], s->t[3 * i + 1], s->t[3 * i + 2]);
    ok = !ferror(f);
    return fclose(f) == 0 && ok;
}

int main(int argc, char **argv)
{
    shape s;
    int ok;
    memset(&s, 0, sizeof s);
    if (argc != 3 || (strcmp(argv[1], "parts") != 0 && strcmp(argv[1], "open") != 0)) {
        fprintf(stderr, "usage: gen_shapes parts|open OUT.off\n");
        return 2;
    }
    if (strcmp(argv[1], "parts") == 0) {
        const double o1[3] = {0.0, 0.0, 0.0}, o2[3] = {1.9, 0.0, 0.2}, o3[3] = {0.0, 1.6, 0.0};
        ok = ellipsoid(&s, o1, 1.0, 1.0, 1.0, 0.04, 48, 96) && ellipsoid(&s, o2, 0.6, 0.6, 0.6, 0.05, 32, 64) &&
             ellipsoid(&s, o3, 0.08, 0.08, 0.9, 0.0, 40, 24);
    } else {
        ok = patch(&s, 64);
    }
    if (ok) ok = write_off(&s, argv[2]);
    if (!ok) fprintf(stderr, "gen_shapes: could not make or write %s\n", argv[2]);
    free(s.p);
    free(s.t);
    return ok ? 0 : 1;
}
