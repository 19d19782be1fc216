/* bench_deform - deform.h's three editing methods against CGAL's Surface_mesh_deformation
   (as-rigid-as-possible, SPOKES_AND_RIMS, its Eigen solver, deform(5, 0)), one thread.

   build/bench_deform [MESH] [--refine K] [--free F] [--methods LIST] [--no-cgal]
     MESH       default /usr/share/glmark2/models/bunny.obj
     --refine K K butterfly levels (subdiv4.h, w = 1/16) first
     --free F   the ROI's share of the bounding box's longest extent, from the top (default 0.4)
     --methods  a comma-separated subset of laplacian,fitting,lri,cgal_arap (default: all)
     --no-cgal  our methods only (the same as leaving cgal_arap out of --methods)

   The rule (from MESH's bounding box alone): t(v) = (p_a - min_a) / h along the longest axis a
   (h its extent); the ROI is t >= 1 - F, the handle t >= 0.95, the rest is fixed. b is the
   second-longest axis. Cases (the handle's targets; LRI also gets the rotations):
     bend   dfm_pose_bend: the part of the ROI below the handle, from t = 1 - F (centred on the
            box) along +a over length (F - 0.05) h, bent by 90 degrees towards +b;
     twist  dfm_pose_twist: 90 degrees about the box's axis line along a;
     drag   a translation by 0.25 h along +b (rotation identity).
   Figures, per method and case:
     RESULT deform method=<laplacian|fitting|lri|cgal_arap> case=<bend|twist|drag> n=<vertices>
         n_free=<free vertices> init_ms=<t> frame_ms=<t> peak_mb=<m> edge_distortion=<d>
         angle_distortion=<d>
     init_ms: dfm_deform_setup (checks, rows, normal matrices, analysis, factorization; the same
       for every case, measured once per method); CGAL: the deformation object, insert_roi /
       insert_control and preprocess(). frame_ms: one dfm_deform_solve; CGAL: set_target_position
       for the handle and deform(5, 0). Medians of 5 after a warm-up (bench.h).
     peak_mb: RSS high-water mark during the method's setup and frames minus the RSS before.
     edge_distortion: RMS of |e'| / |e| - 1 over the edges with an end in the ROI;
     angle_distortion: RMS change, in radians, of the corner angles of the triangles with a
       vertex in the ROI. Both on the first frame's result.
   LRI runs with polar orthonormalization of the frames (DFM_ORTHO_POLAR); every method with
   hard handle constraints and uniform weights (the defaults). */
#include "bench.h"

#define DFM_IMPLEMENTATION
#include "deform.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"
#define SD4_IMPLEMENTATION
#include "subdiv4.h"

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_deformation.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

typedef CGAL::Simple_cartesian<double> Kernel;
typedef CGAL::Surface_mesh<Kernel::Point_3> SMesh;
typedef CGAL::Surface_mesh_deformation<SMesh> Deformation;

static const double PI = 3.14159265358979323846;

struct Problem {
    size_t nv = 0, nt = 0, nfree = 0;
    std::vector<double> pos;
    std::vector<uint32_t> idx;
    std::vector<unsigned char> roi, handle;
    int a = 0, b = 1;
    double lo[3], hi[3], h = 0;
    double free_share = 0.4;
};

struct Pose {
    std::vector<double> targets, rot;
};

static Pose make_pose(const Problem &p, const char *name)
{
    Pose q;
    q.targets.resize(3 * p.nv);
    q.rot.resize(9 * p.nv);
    dfm_pose_identity(p.pos.data(), p.nv, q.targets.data(), q.rot.data());
    double axis[3] = {0, 0, 0}, toward[3] = {0, 0, 0}, base[3];
    axis[p.a] = 1.0;
    toward[p.b] = 1.0;
    for (int k = 0; k < 3; k++) base[k] = 0.5 * (p.lo[k] + p.hi[k]);
    if (!strcmp(name, "bend")) {
        base[p.a] = p.lo[p.a] + (1.0 - p.free_share) * p.h;
        dfm_pose_bend(p.pos.data(), p.nv, p.handle.data(), base, axis, toward, (p.free_share - 0.05) * p.h,
                      0.5 * PI, q.targets.data(), q.rot.data());
    } else if (!strcmp(name, "twist")) {
        dfm_pose_twist(p.pos.data(), p.nv, p.handle.data(), base, axis, 0.5 * PI, q.targets.data(), q.rot.data());
    } else {
        double t[3] = {0, 0, 0};
        t[p.b] = 0.25 * p.h;
        dfm_pose_rigid(p.pos.data(), p.nv, p.handle.data(), NULL, NULL, t, q.targets.data(), q.rot.data());
    }
    return q;
}

static double corner_angle(const double *o, const double *x, const double *y)
{
    double u[3], v[3], c[3];
    for (int k = 0; k < 3; k++) {
        u[k] = x[k] - o[k];
        v[k] = y[k] - o[k];
    }
    c[0] = u[1] * v[2] - u[2] * v[1];
    c[1] = u[2] * v[0] - u[0] * v[2];
    c[2] = u[0] * v[1] - u[1] * v[0];
    return atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
}

static void distortion(const Problem &p, const double *out, double *edge, double *angle)
{
    double se = 0, sa = 0;
    size_t ne = 0, na = 0;
    for (size_t t = 0; t < p.nt; t++) {
        const uint32_t *f = &p.idx[3 * t];
        if (!p.roi[f[0]] && !p.roi[f[1]] && !p.roi[f[2]]) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t i = f[k], j = f[(k + 1) % 3], o = f[(k + 2) % 3];
            if (p.roi[i] || p.roi[j]) { /* each interior edge is seen twice: the RMS is the same */
                double l0 = 0, l1 = 0;
                for (int c = 0; c < 3; c++) {
                    l0 += (p.pos[3 * i + c] - p.pos[3 * j + c]) * (p.pos[3 * i + c] - p.pos[3 * j + c]);
                    l1 += (out[3 * i + c] - out[3 * j + c]) * (out[3 * i + c] - out[3 * j + c]);
                }
                double r = sqrt(l1 / l0) - 1.0;
                se += r * r;
                ne++;
            }
            double a0 = corner_angle(&p.pos[3 * o], &p.pos[3 * i], &p.pos[3 * j]);
            double a1 = corner_angle(out + 3 * o, out + 3 * i, out + 3 * j);
            sa += (a1 - a0) * (a1 - a0);
            na++;
        }
    }
    *edge = ne ? sqrt(se / (double)ne) : 0.0;
    *angle = na ? sqrt(sa / (double)na) : 0.0;
}

/* ---- ours ---- */
struct Ours {
    const Problem *p;
    dfm_deform_options o;
    dfm_deform *d = nullptr;
    const Pose *pose = nullptr;
    std::vector<double> out;
};

static int ours_setup(void *u)
{
    Ours *s = (Ours *)u;
    return dfm_deform_setup(s->p->pos.data(), s->p->nv, s->p->idx.data(), s->p->nt, s->p->roi.data(),
                            s->p->handle.data(), &s->o, &s->d) != DFM_OK;
}
static void ours_setup_after(void *u)
{
    Ours *s = (Ours *)u;
    dfm_deform_free(s->d);
    s->d = nullptr;
}
static int ours_frame(void *u)
{
    Ours *s = (Ours *)u;
    return dfm_deform_solve(s->d, s->pose->targets.data(), s->pose->rot.data(), s->out.data()) != DFM_OK;
}

static void run_ours(const Problem &p, const char *name, int method, const Pose *poses, const char **cases, int ncases)
{
    Ours s;
    s.p = &p;
    s.o = dfm_deform_default_options();
    s.o.method = method;
    s.o.orthonormalize = DFM_ORTHO_POLAR;
    s.out.resize(3 * p.nv);
    fprintf(stderr, "bench_deform: %s setup\n", name);
    bench_reset_peak_rss();
    long rss0 = bench_current_rss_kb();
    double init = bench_median(ours_setup, ours_setup_after, &s);
    dfm_result err = dfm_deform_setup(p.pos.data(), p.nv, p.idx.data(), p.nt, p.roi.data(), p.handle.data(), &s.o, &s.d);
    if (init < 0 || err != DFM_OK) {
        printf("RESULT deform method=%s error=%s\n", name, dfm_result_string(err));
        return;
    }
    for (int c = 0; c < ncases; c++) {
        double ed, ad;
        s.pose = &poses[c];
        fprintf(stderr, "bench_deform: %s %s\n", name, cases[c]);
        ours_frame(&s);
        distortion(p, s.out.data(), &ed, &ad);
        double frame = bench_median(ours_frame, nullptr, &s);
        double peak = (bench_peak_rss_kb() - rss0) / 1024.0;
        printf("RESULT deform method=%s case=%s n=%zu n_free=%zu init_ms=%.1f frame_ms=%.2f peak_mb=%.1f "
               "edge_distortion=%.4f angle_distortion=%.4f\n",
               name, cases[c], p.nv, p.nfree, 1e3 * init, 1e3 * frame, peak, ed, ad);
        fflush(stdout);
    }
    dfm_deform_free(s.d);
}

/* ---- CGAL ---- */
struct Cgal {
    const Problem *p;
    SMesh mesh;
    Deformation *dm = nullptr;
    const Pose *pose = nullptr;
};

static int cgal_setup(void *u)
{
    Cgal *s = (Cgal *)u;
    s->dm = new Deformation(s->mesh);
    for (size_t v = 0; v < s->p->nv; v++)
        if (s->p->roi[v]) s->dm->insert_roi_vertex(SMesh::Vertex_index((uint32_t)v));
    for (size_t v = 0; v < s->p->nv; v++)
        if (s->p->handle[v]) s->dm->insert_control_vertex(SMesh::Vertex_index((uint32_t)v));
    return !s->dm->preprocess();
}
static void cgal_setup_after(void *u)
{
    Cgal *s = (Cgal *)u;
    delete s->dm;
    s->dm = nullptr;
}
static int cgal_frame(void *u)
{
    Cgal *s = (Cgal *)u;
    const double *t = s->pose->targets.data();
    for (size_t v = 0; v < s->p->nv; v++)
        if (s->p->handle[v])
            s->dm->set_target_position(SMesh::Vertex_index((uint32_t)v), Kernel::Point_3(t[3 * v], t[3 * v + 1], t[3 * v + 2]));
    s->dm->deform(5, 0.0);
    return 0;
}

static void run_cgal(const Problem &p, const Pose *poses, const char **cases, int ncases)
{
    Cgal s;
    s.p = &p;
    for (size_t v = 0; v < p.nv; v++) s.mesh.add_vertex(Kernel::Point_3(p.pos[3 * v], p.pos[3 * v + 1], p.pos[3 * v + 2]));
    for (size_t t = 0; t < p.nt; t++)
        s.mesh.add_face(SMesh::Vertex_index(p.idx[3 * t]), SMesh::Vertex_index(p.idx[3 * t + 1]),
                        SMesh::Vertex_index(p.idx[3 * t + 2]));
    fprintf(stderr, "bench_deform: cgal_arap setup\n");
    bench_reset_peak_rss();
    long rss0 = bench_current_rss_kb();
    double init = bench_median(cgal_setup, cgal_setup_after, &s);
    if (init < 0 || cgal_setup(&s)) {
        printf("RESULT deform method=cgal_arap error=preprocess\n");
        return;
    }
    std::vector<double> out(3 * p.nv);
    for (int c = 0; c < ncases; c++) {
        double ed, ad;
        s.pose = &poses[c];
        fprintf(stderr, "bench_deform: cgal_arap %s\n", cases[c]);
        s.dm->reset();
        cgal_frame(&s);
        for (size_t v = 0; v < p.nv; v++) {
            const Kernel::Point_3 &q = s.mesh.point(SMesh::Vertex_index((uint32_t)v));
            out[3 * v] = q.x();
            out[3 * v + 1] = q.y();
            out[3 * v + 2] = q.z();
        }
        distortion(p, out.data(), &ed, &ad);
        double frame = bench_median(cgal_frame, nullptr, &s);
        double peak = (bench_peak_rss_kb() - rss0) / 1024.0;
        printf("RESULT deform method=cgal_arap case=%s n=%zu n_free=%zu init_ms=%.1f frame_ms=%.2f peak_mb=%.1f "
               "edge_distortion=%.4f angle_distortion=%.4f\n",
               cases[c], p.nv, p.nfree, 1e3 * init, 1e3 * frame, peak, ed, ad);
        fflush(stdout);
    }
    delete s.dm;
}

static int usage(void)
{
    fprintf(stderr, "usage: bench_deform [MESH] [--refine K] [--free F] [--methods LIST] [--no-cgal]\n");
    return 2;
}

int main(int argc, char **argv)
{
    const char *path = "/usr/share/glmark2/models/bunny.obj", *methods = "laplacian,fitting,lri,cgal_arap";
    int refine = 0, cgal = 1;
    Problem p;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--refine") && i + 1 < argc) refine = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--free") && i + 1 < argc) p.free_share = atof(argv[++i]);
        else if (!strcmp(argv[i], "--no-cgal")) cgal = 0;
        else if (!strcmp(argv[i], "--methods") && i + 1 < argc) methods = argv[++i];
        else if (argv[i][0] == '-') return usage();
        else path = argv[i];
    }
    if (refine < 0 || refine > 4 || !(p.free_share > 0.05 && p.free_share <= 1.0)) return usage();
    BENCH_PRINT_FLAGS("deform");
    mio_mesh mesh;
    mio_error merr;
    if (mio_read_file(path, NULL, &mesh, &merr) != MIO_OK) {
        fprintf(stderr, "bench_deform: %s: %s\n", path, merr.message);
        return 1;
    }
    const float *fp = mesh.positions;
    const uint32_t *ip = mesh.indices;
    size_t nv = mesh.vertex_count, nt = mesh.triangle_count;
    sd4_mesh fine;
    memset(&fine, 0, sizeof fine);
    if (refine > 0) {
        if (sd4_butterfly(fp, nv, ip, nt, refine, 0.0625, NULL, &fine) != SD4_OK) {
            fprintf(stderr, "bench_deform: butterfly refinement failed\n");
            return 1;
        }
        fp = fine.positions;
        ip = fine.indices;
        nv = fine.vertex_count;
        nt = fine.triangle_count;
    }
    p.nv = nv;
    p.nt = nt;
    p.pos.assign(fp, fp + 3 * nv);
    p.idx.assign(ip, ip + 3 * nt);
    sd4_free_mesh(&fine);
    mio_free_mesh(&mesh);
    for (int k = 0; k < 3; k++) {
        p.lo[k] = HUGE_VAL;
        p.hi[k] = -HUGE_VAL;
    }
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 3; k++) {
            p.lo[k] = fmin(p.lo[k], p.pos[3 * v + k]);
            p.hi[k] = fmax(p.hi[k], p.pos[3 * v + k]);
        }
    double ext[3];
    for (int k = 0; k < 3; k++) ext[k] = p.hi[k] - p.lo[k];
    p.a = ext[0] >= ext[1] && ext[0] >= ext[2] ? 0 : ext[1] >= ext[2] ? 1 : 2;
    p.b = (p.a + 1) % 3;
    if (ext[(p.a + 2) % 3] > ext[p.b]) p.b = (p.a + 2) % 3;
    p.h = ext[p.a];
    p.roi.resize(nv);
    p.handle.resize(nv);
    for (size_t v = 0; v < nv; v++) {
        double t = (p.pos[3 * v + p.a] - p.lo[p.a]) / p.h;
        p.roi[v] = t >= 1.0 - p.free_share;
        p.handle[v] = t >= 0.95;
        p.nfree += p.roi[v] && !p.handle[v];
    }
    fprintf(stderr, "bench_deform: %s, %zu vertices, %zu free\n", path, nv, p.nfree);
    const char *cases[3] = {"bend", "twist", "drag"};
    Pose poses[3] = {make_pose(p, cases[0]), make_pose(p, cases[1]), make_pose(p, cases[2])};
    if (strstr(methods, "laplacian")) run_ours(p, "laplacian", DFM_METHOD_LAPLACIAN, poses, cases, 3);
    if (strstr(methods, "fitting")) run_ours(p, "fitting", DFM_METHOD_FITTING, poses, cases, 3);
    if (strstr(methods, "lri")) run_ours(p, "lri", DFM_METHOD_LRI, poses, cases, 3);
    if (cgal && strstr(methods, "cgal")) run_cgal(p, poses, cases, 3);
    printf("RESULT bench_deform process_peak_rss_mb=%.1f\n", bench_peak_rss_kb() / 1024.0);
    return 0;
}
