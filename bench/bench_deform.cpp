/* bench_deform - deform.h's three editing methods against CGAL's Surface_mesh_deformation
   (as-rigid-as-possible, SPOKES_AND_RIMS, its Eigen solver, deform(5, 0)), one thread.

   build/bench_deform [MESH] [--refine K] [--free F] [--methods LIST] [--no-cgal]
                      [--lri-steps K] [--lri-weights uniform|cotan] [--slow-runs N]
     MESH          default /usr/share/glmark2/models/bunny.obj
     --refine K    K butterfly levels (subdiv4.h, w = 1/16) first
     --free F      the ROI's share of the bounding box's longest extent, from the top (default 0.4)
     --methods     a comma-separated subset of laplacian,fitting,lri,lri_rigid,cgal_arap (default:
                   all)
     --no-cgal     our methods only (the same as leaving cgal_arap out of --methods)
     --lri-steps   lri_rigid's rigid_steps (default 5, CGAL's iteration count)
     --lri-weights lri_rigid's weights (default cotan, as CGAL's)
     --slow-runs   timed runs of fitting (default 3: its setup takes about 10 s at 40k free)

   The rule (from MESH's bounding box alone): t(v) = (p_a - min_a) / h along the longest axis a
   (h its extent); the ROI is t >= 1 - F, the handle t >= 0.95, the rest is fixed. b is the
   second-longest axis. Cases (the handle's targets; LRI also gets the rotations):
     bend   dfm_pose_bend: the part of the ROI below the handle, from t = 1 - F (centred on the
            box) along +a over length (F - 0.05) h, bent by 90 degrees towards +b;
     twist  dfm_pose_twist: 90 degrees about the box's axis line along a;
     drag   a translation by 0.25 h along +b (rotation identity).
   Methods: laplacian, fitting, lri (uniform weights, polar frames, rigid_steps 0: the thesis's
   LRI), lri_rigid (LRI then --lri-steps as-rigid-as-possible steps, --lri-weights), cgal_arap.
   Every method with hard handle constraints.
   Timing (bench.h's bench_interleave): the setups of all methods take turns, A B C .. A B C,
   after one warm-up each, 11 timed runs each (fitting: --slow-runs); then per case the frames
   the same way, with every method's object alive. Medians with min and max.
   Figures, per method and case:
     RESULT deform method=<laplacian|fitting|lri|lri_rigid|cgal_arap> case=<bend|twist|drag>
         n=<vertices> n_free=<free vertices> [rigid_steps=K weights=W] init_ms=<t> init_ms_min=
         init_ms_max= frame_ms=<t> frame_ms_min= frame_ms_max= [runs=N] [frame_vs_cgal=<r>
         frame_vs_cgal_min= frame_vs_cgal_max=] peak_mb=<m> edge_distortion=<d>
         angle_distortion=<d> [edge_vs_cgal=<r> angle_vs_cgal=<r>]
     init_ms: dfm_deform_setup (checks, rows, normal matrices, analysis, factorization; the same
       for every case); CGAL: the deformation object, insert_roi / insert_control and
       preprocess(). frame_ms: one dfm_deform_solve; CGAL: set_target_position for the handle and
       deform(5, 0) from the rest pose (reset() after each run, outside the timer).
       frame_vs_cgal: the per-round ratios of the frame times.
     peak_mb: the larger of the setup's RSS high-water mark (its warm-up run, above the RSS
       before it) and the live object's RSS plus what a frame's warm-up run adds.
     edge_distortion: RMS of |e'| / |e| - 1 over the edges with an end in the ROI;
     angle_distortion: RMS change, in radians, of the corner angles of the triangles with a
       vertex in the ROI. Both on the first frame's result; *_vs_cgal: ratio to cgal_arap's (left
       out when cgal_arap's is below 1e-4: a rigid answer, as drag with --free 1). */
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

/* ---- the sides: ours and CGAL's, each a setup (init) and a frame ---- */
struct Side {
    const char *name;
    const Problem *p;
    int cgal = 0;
    dfm_deform_options o;
    dfm_deform *d = nullptr;
    SMesh mesh;
    Deformation *dm = nullptr;
    const Pose *pose = nullptr;
    std::vector<double> out;
    double rss_object_mb = 0; /* the live object's RSS during the frames */
    double frame_peak_mb = 0; /* the most a frame's warm-up added */
};

static int side_setup(void *u)
{
    Side *s = (Side *)u;
    const Problem &p = *s->p;
    if (!s->cgal)
        return dfm_deform_setup(p.pos.data(), p.nv, p.idx.data(), p.nt, p.roi.data(), p.handle.data(), &s->o, &s->d) !=
               DFM_OK;
    s->dm = new Deformation(s->mesh);
    for (size_t v = 0; v < p.nv; v++)
        if (p.roi[v]) s->dm->insert_roi_vertex(SMesh::Vertex_index((uint32_t)v));
    for (size_t v = 0; v < p.nv; v++)
        if (p.handle[v]) s->dm->insert_control_vertex(SMesh::Vertex_index((uint32_t)v));
    return !s->dm->preprocess();
}
static void side_free(void *u)
{
    Side *s = (Side *)u;
    dfm_deform_free(s->d);
    s->d = nullptr;
    delete s->dm;
    s->dm = nullptr;
}
/* one frame from the rest pose (CGAL: reset() in side_frame_after, outside the timer) */
static int side_frame(void *u)
{
    Side *s = (Side *)u;
    const double *t = s->pose->targets.data();
    if (!s->cgal) return dfm_deform_solve(s->d, t, s->pose->rot.data(), s->out.data()) != DFM_OK;
    for (size_t v = 0; v < s->p->nv; v++)
        if (s->p->handle[v])
            s->dm->set_target_position(SMesh::Vertex_index((uint32_t)v), Kernel::Point_3(t[3 * v], t[3 * v + 1], t[3 * v + 2]));
    s->dm->deform(5, 0.0);
    return 0;
}
static void side_frame_after(void *u)
{
    Side *s = (Side *)u;
    if (s->cgal) s->dm->reset();
}
/* the first frame's result, for the distortions */
static void side_result(Side *s)
{
    side_frame(s);
    if (s->cgal)
        for (size_t v = 0; v < s->p->nv; v++) {
            const Kernel::Point_3 &q = s->mesh.point(SMesh::Vertex_index((uint32_t)v));
            s->out[3 * v] = q.x();
            s->out[3 * v + 1] = q.y();
            s->out[3 * v + 2] = q.z();
        }
    side_frame_after(s);
}

static void make_side(Side &s, const Problem &p, const char *name, int method, int lri_steps, int lri_cotan)
{
    s.name = name;
    s.p = &p;
    s.out.resize(3 * p.nv);
    s.o = dfm_deform_default_options();
    s.cgal = method < 0;
    if (s.cgal) {
        for (size_t v = 0; v < p.nv; v++) s.mesh.add_vertex(Kernel::Point_3(p.pos[3 * v], p.pos[3 * v + 1], p.pos[3 * v + 2]));
        for (size_t t = 0; t < p.nt; t++)
            s.mesh.add_face(SMesh::Vertex_index(p.idx[3 * t]), SMesh::Vertex_index(p.idx[3 * t + 1]),
                            SMesh::Vertex_index(p.idx[3 * t + 2]));
        return;
    }
    s.o.method = method;
    s.o.orthonormalize = DFM_ORTHO_POLAR;
    s.o.rigid_steps = lri_steps;
    if (lri_cotan) s.o.weights = DFM_WEIGHTS_COTAN;
}

static void run_all(const Problem &p, std::vector<Side> &sides, const Pose *poses, const char **cases, int ncases,
                    int slow_runs)
{
    int n = (int)sides.size(), cg = -1;
    std::vector<bench_side> bs(n);
    for (int k = 0; k < n; k++) {
        bs[k] = bench_make_side(sides[k].name, side_setup, side_free, &sides[k]);
        if (sides[k].o.method == DFM_METHOD_FITTING && !sides[k].cgal) bs[k].max_runs = slow_runs;
        if (sides[k].cgal) cg = k;
    }
    fprintf(stderr, "bench_deform: setups, interleaved\n");
    if (bench_interleave(bs.data(), n, 0) != 0) {
        printf("RESULT deform error=setup_failed\n");
        return;
    }
    std::vector<bench_side> init = bs;
    for (int k = 0; k < n; k++) { /* the live objects, each measured */
        bench_reset_peak_rss();
        long rss0 = bench_current_rss_kb();
        side_setup(&sides[k]);
        sides[k].rss_object_mb = (bench_current_rss_kb() - rss0) / 1024.0;
    }
    for (int c = 0; c < ncases; c++) {
        std::vector<double> ed(n), ad(n);
        for (int k = 0; k < n; k++) {
            sides[k].pose = &poses[c];
            side_result(&sides[k]);
            distortion(p, sides[k].out.data(), &ed[k], &ad[k]);
            bs[k] = bench_make_side(sides[k].name, side_frame, side_frame_after, &sides[k]);
            if (sides[k].o.method == DFM_METHOD_FITTING && !sides[k].cgal) bs[k].max_runs = slow_runs;
        }
        fprintf(stderr, "bench_deform: %s frames, interleaved\n", cases[c]);
        if (bench_interleave(bs.data(), n, 0) != 0) {
            printf("RESULT deform error=frame_failed case=%s\n", cases[c]);
            return;
        }
        for (int k = 0; k < n; k++) {
            Side &s = sides[k];
            double frame_mb = bs[k].peak_kb > 0 ? bs[k].peak_kb / 1024.0 : 0.0;
            double peak = fmax(init[k].peak_kb / 1024.0, s.rss_object_mb + frame_mb);
            printf("RESULT deform method=%s case=%s n=%zu n_free=%zu", s.name, cases[c], p.nv, p.nfree);
            if (!s.cgal && s.o.method == DFM_METHOD_LRI)
                printf(" rigid_steps=%d weights=%s", s.o.rigid_steps, s.o.weights ? "cotan" : "uniform");
            bench_print_ms("init", &init[k]);
            bench_print_ms("frame", &bs[k]);
            if (init[k].runs < BENCH_INTERLEAVED_RUNS) printf(" runs=%d", init[k].runs);
            if (cg >= 0 && k != cg) bench_print_ratio_named("frame_vs_cgal", &bs[k], &bs[cg]);
            printf(" peak_mb=%.1f edge_distortion=%.4f angle_distortion=%.4f", peak, ed[k], ad[k]);
            if (cg >= 0 && k != cg && ed[cg] > 1e-4 && ad[cg] > 1e-4) /* not against a rigid answer */
                printf(" edge_vs_cgal=%.3f angle_vs_cgal=%.3f", ed[k] / ed[cg], ad[k] / ad[cg]);
            printf("\n");
            fflush(stdout);
        }
    }
    for (int k = 0; k < n; k++) side_free(&sides[k]);
}

static int has_item(const char *list, const char *name)
{
    size_t n = strlen(name);
    for (const char *q = list; (q = strstr(q, name)) != nullptr; q += n)
        if ((q == list || q[-1] == ',') && (q[n] == ',' || q[n] == 0)) return 1;
    return 0;
}

static int usage(void)
{
    fprintf(stderr, "usage: bench_deform [MESH] [--refine K] [--free F] [--methods LIST] [--no-cgal]\n"
                    "                    [--lri-steps K] [--lri-weights uniform|cotan] [--slow-runs N]\n");
    return 2;
}

int main(int argc, char **argv)
{
    const char *path = "/usr/share/glmark2/models/bunny.obj", *methods = "laplacian,fitting,lri,lri_rigid,cgal_arap";
    int refine = 0, cgal = 1, lri_steps = 5, lri_cotan = 1, slow_runs = 3;
    Problem p;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--refine") && i + 1 < argc) refine = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--free") && i + 1 < argc) p.free_share = atof(argv[++i]);
        else if (!strcmp(argv[i], "--no-cgal")) cgal = 0;
        else if (!strcmp(argv[i], "--methods") && i + 1 < argc) methods = argv[++i];
        else if (!strcmp(argv[i], "--lri-steps") && i + 1 < argc) lri_steps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--slow-runs") && i + 1 < argc) slow_runs = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--lri-weights") && i + 1 < argc) {
            const char *w = argv[++i];
            if (strcmp(w, "uniform") && strcmp(w, "cotan")) return usage();
            lri_cotan = !strcmp(w, "cotan");
        }
        else if (argv[i][0] == '-') return usage();
        else path = argv[i];
    }
    if (refine < 0 || refine > 4 || !(p.free_share > 0.05 && p.free_share <= 1.0)) return usage();
    if (lri_steps < 1 || lri_steps > 100 || slow_runs < 1 || slow_runs > BENCH_INTERLEAVED_RUNS) return usage();
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
    /* the sides, in this order (a name is in LIST when it is one of its comma-separated items) */
    std::vector<Side> sides(5);
    int ns = 0;
    if (has_item(methods, "laplacian")) make_side(sides[ns++], p, "laplacian", DFM_METHOD_LAPLACIAN, 0, 0);
    if (has_item(methods, "fitting")) make_side(sides[ns++], p, "fitting", DFM_METHOD_FITTING, 0, 0);
    if (has_item(methods, "lri")) make_side(sides[ns++], p, "lri", DFM_METHOD_LRI, 0, 0);
    if (has_item(methods, "lri_rigid")) make_side(sides[ns++], p, "lri_rigid", DFM_METHOD_LRI, lri_steps, lri_cotan);
    if (cgal && has_item(methods, "cgal_arap")) make_side(sides[ns++], p, "cgal_arap", -1, 0, 0);
    sides.resize(ns);
    if (ns == 0) return usage();
    run_all(p, sides, poses, cases, 3, slow_runs);
    printf("RESULT bench_deform process_peak_rss_mb=%.1f\n", bench_peak_rss_kb() / 1024.0);
    return 0;
}
