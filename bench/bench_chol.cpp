/* bench_chol - deform.h's sparse Cholesky against CHOLMOD (supernodal) and Eigen's SimplicialLLT,
   single thread.

   build/bench_chol [MESH]      (default build/sphere1m.off)

   Systems (assembled by deform.h from the mesh, outside every timer):
     laplacian    the cotangent Laplacian L (dfm_mesh_laplacian, COTAN) with 1% of the vertices
                  constrained (every 100th vertex: +1 on its diagonal)
     bilaplacian  L^T L + the same constraints (dfm_normal_matrix); skipped above 200k vertices
                  (the peers take minutes there)
   Right-hand sides: 3 columns of hashed uniform values in [-1, 1).

   Figures (median of 5 after a warm-up, see bench.h):
     RESULT chol system=<laplacian|bilaplacian> n=<n> ours_nnzL=<n> cholmod_nnzL=<n>
         ours_analyze_ms=<t> ours_factor_ms=<t> cholmod_factor_ms=<t> eigen_factor_ms=<t>
         ours_solve3_ms=<t> cholmod_solve3_ms=<t> residual=<r> ...
       ours_analyze_ms: dfm_chol_analyze with the vertex positions as coordinates (AMD, and
         nested dissection keeping the smaller fill; etree, postorder, counts, supernodes).
       ours_factor_ms: dfm_chol_factor (numeric only, reusing the analysis).
       cholmod_factor_ms: cholmod_factorize (numeric only) after one cholmod_analyze with the
         default settings (supernodal, AMD then METIS when AMD's fill is high; the ordering it
         chose is printed as cholmod_ordering); cholmod_analyze_ms is its analysis time.
       eigen_factor_ms: SimplicialLLT<Lower, AMDOrdering>::factorize after one analyzePattern.
       ours_solve3_ms / cholmod_solve3_ms: one solve with 3 right-hand sides (dfm_chol_solve on
         a copy of B; cholmod_solve(CHOLMOD_A) returning a new dense X, freed outside the timer).
       nnzL: exact entries of L (ours: the symbolic count; CHOLMOD: Common->lnz of the chosen
         ordering; eigen_nnzL: the nonzeros of Eigen's L).
       ours_stored / cholmod_stored: entries held (supernodal blocks, amalgamation zeros
         included; CHOLMOD: L->xsize).
       residual: max over the 3 columns of |b - Ax|inf / (|A|inf |x|inf + |b|inf) for ours;
         cholmod_residual likewise for CHOLMOD's x.
     RESULT chol_blas lib=<path> the BLAS library CHOLMOD's dgemm_ resolved to at run time
         (Debian's libblas.so.3 alternative: OpenBLAS serial when libopenblas0-serial is
         installed, else the reference BLAS). */
#include "bench.h"

#include <dlfcn.h>
#include <cholmod.h>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#define DFM_IMPLEMENTATION
#include "deform.h"
#define MIO_IMPLEMENTATION
#include "meshio.h"

#include "hashrand.h"

static double norm_inf_sym(const dfm_csc &a)
{
    std::vector<double> rs(a.n_cols, 0.0);
    for (size_t j = 0; j < a.n_cols; j++)
        for (size_t p = a.col_start[j]; p < a.col_start[j + 1]; p++) {
            size_t i = (size_t)a.row_index[p];
            rs[i] += std::fabs(a.values[p]);
            if (i != j) rs[j] += std::fabs(a.values[p]);
        }
    double m = 0;
    for (double v : rs) m = std::fmax(m, v);
    return m;
}

static double residual(const dfm_csc &a, const double *x, const double *b, size_t nrhs)
{
    size_t n = a.n_cols;
    std::vector<double> y(n * nrhs);
    dfm_csc_multiply(&a, x, y.data(), nrhs);
    double an = norm_inf_sym(a), worst = 0;
    for (size_t q = 0; q < nrhs; q++) {
        double r = 0, xn = 0, bn = 0;
        for (size_t i = 0; i < n; i++) {
            r = std::fmax(r, std::fabs(b[q * n + i] - y[q * n + i]));
            xn = std::fmax(xn, std::fabs(x[q * n + i]));
            bn = std::fmax(bn, std::fabs(b[q * n + i]));
        }
        double v = r / (an * xn + bn);
        if (!(v <= worst)) worst = v;
    }
    return worst;
}

static const char *blas_library(void)
{
    static char path[PATH_MAX];
    void *sym = dlsym(RTLD_DEFAULT, "dgemm_");
    Dl_info info;
    if (!sym || !dladdr(sym, &info) || !info.dli_fname) return "unknown";
    if (!realpath(info.dli_fname, path)) snprintf(path, sizeof path, "%s", info.dli_fname);
    return path;
}

struct state {
    const dfm_csc *a = nullptr;
    dfm_chol_options options = dfm_chol_default_options();
    const std::vector<double> *b = nullptr;
    dfm_chol *chol = nullptr;
    std::vector<double> x;
    cholmod_common *cc = nullptr;
    cholmod_sparse *ca = nullptr;
    cholmod_factor *cf = nullptr;
    cholmod_dense *cb = nullptr, *cx = nullptr;
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> *eigen = nullptr;
    const Eigen::SparseMatrix<double> *ea = nullptr;
    int failed = 0;
};

static int ours_analyze(void *u)
{
    state &s = *(state *)u;
    return dfm_chol_analyze(s.a, &s.options, &s.chol) != DFM_OK;
}
static void ours_analyze_after(void *u)
{
    state &s = *(state *)u;
    dfm_chol_free(s.chol);
    s.chol = nullptr;
}
static int ours_factor(void *u)
{
    state &s = *(state *)u;
    return dfm_chol_factor(s.chol, s.a) != DFM_OK;
}
static int ours_solve(void *u)
{
    state &s = *(state *)u;
    s.x = *s.b;
    return dfm_chol_solve(s.chol, s.x.data(), 3) != DFM_OK;
}
static int cholmod_factor_run(void *u)
{
    state &s = *(state *)u;
    return !cholmod_factorize(s.ca, s.cf, s.cc) || s.cc->status != CHOLMOD_OK;
}
static int cholmod_solve_run(void *u)
{
    state &s = *(state *)u;
    s.cx = cholmod_solve(CHOLMOD_A, s.cf, s.cb, s.cc);
    return s.cx == nullptr;
}
static void cholmod_solve_after(void *u)
{
    state &s = *(state *)u;
    cholmod_free_dense(&s.cx, s.cc);
}
static int eigen_factor(void *u)
{
    state &s = *(state *)u;
    s.eigen->factorize(*s.ea);
    return s.eigen->info() != Eigen::Success;
}

static void run_system(const char *name, const dfm_csc &a, const double *coords)
{
    size_t n = a.n_cols, nnz = a.col_start[n];
    std::vector<double> b(3 * n);
    for (size_t i = 0; i < 3 * n; i++) b[i] = 2.0 * unit_random(i, 9) - 1.0;
    state s;
    s.a = &a;
    s.b = &b;
    s.options.coords = coords;

    /* ours */
    fprintf(stderr, "bench_chol: %s n=%zu nnz(A lower)=%zu: ours\n", name, n, nnz);
    double ours_analyze_s = bench_median(ours_analyze, ours_analyze_after, &s);
    if (ours_analyze_s < 0 || dfm_chol_analyze(&a, &s.options, &s.chol) != DFM_OK) {
        fprintf(stderr, "bench_chol: our analysis failed\n");
        exit(1);
    }
    double ours_factor_s = bench_median(ours_factor, nullptr, &s);
    double ours_solve_s = bench_median(ours_solve, nullptr, &s);
    if (ours_factor_s < 0 || ours_solve_s < 0) {
        fprintf(stderr, "bench_chol: our factorization failed\n");
        exit(1);
    }
    dfm_chol_info info;
    dfm_chol_get_info(s.chol, &info);
    double ours_res = residual(a, s.x.data(), b.data(), 3);

    /* CHOLMOD */
    fprintf(stderr, "bench_chol: %s: cholmod\n", name);
    cholmod_common cc;
    cholmod_start(&cc);
    cc.supernodal = CHOLMOD_SUPERNODAL;
    s.cc = &cc;
    s.ca = cholmod_allocate_sparse(n, n, nnz, 1, 1, -1, CHOLMOD_REAL, &cc);
    int *cp = (int *)s.ca->p, *ci = (int *)s.ca->i;
    double *cxv = (double *)s.ca->x;
    for (size_t j = 0; j <= n; j++) cp[j] = (int)a.col_start[j];
    for (size_t p = 0; p < nnz; p++) {
        ci[p] = a.row_index[p];
        cxv[p] = a.values[p];
    }
    double t0 = bench_now();
    s.cf = cholmod_analyze(s.ca, &cc);
    double cholmod_analyze_s = bench_now() - t0;
    double cholmod_lnz = cc.lnz;
    double cholmod_stored = s.cf ? (double)s.cf->xsize : -1.0;
    int ordering = cc.method[cc.selected].ordering;
    const char *ordering_name = ordering == CHOLMOD_AMD ? "amd" : ordering == CHOLMOD_METIS ? "metis"
                              : ordering == CHOLMOD_NESDIS ? "nesdis" : ordering == CHOLMOD_NATURAL ? "natural"
                              : ordering == CHOLMOD_COLAMD ? "colamd" : "other";
    double cholmod_factor_s = bench_median(cholmod_factor_run, nullptr, &s);
    s.cb = cholmod_allocate_dense(n, 3, n, CHOLMOD_REAL, &cc);
    memcpy(s.cb->x, b.data(), 3 * n * sizeof(double));
    double cholmod_solve_s = bench_median(cholmod_solve_run, cholmod_solve_after, &s);
    s.cx = cholmod_solve(CHOLMOD_A, s.cf, s.cb, &cc);
    double cholmod_res = s.cx ? residual(a, (const double *)s.cx->x, b.data(), 3) : -1;
    cholmod_free_dense(&s.cx, &cc);
    cholmod_free_dense(&s.cb, &cc);
    cholmod_free_factor(&s.cf, &cc);
    cholmod_free_sparse(&s.ca, &cc);
    cholmod_finish(&cc);

    /* Eigen */
    fprintf(stderr, "bench_chol: %s: eigen\n", name);
    Eigen::SparseMatrix<double> ea((Eigen::Index)n, (Eigen::Index)n);
    {
        std::vector<Eigen::Triplet<double>> trip;
        trip.reserve(nnz);
        for (size_t j = 0; j < n; j++)
            for (size_t p = a.col_start[j]; p < a.col_start[j + 1]; p++)
                trip.emplace_back(a.row_index[p], (int)j, a.values[p]);
        ea.setFromTriplets(trip.begin(), trip.end());
    }
    s.ea = &ea;
    s.eigen = new Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>>();
    s.eigen->analyzePattern(ea);
    double eigen_factor_s = bench_median(eigen_factor, nullptr, &s);
    long long eigen_nnz = s.eigen->info() == Eigen::Success ? (long long)s.eigen->matrixL().nestedExpression().nonZeros() : -1;
    delete s.eigen;

    printf("RESULT chol system=%s n=%zu ours_nnzL=%zu cholmod_nnzL=%.0f ours_analyze_ms=%.2f ours_factor_ms=%.2f "
           "cholmod_factor_ms=%.2f eigen_factor_ms=%.2f ours_solve3_ms=%.3f cholmod_solve3_ms=%.3f residual=%.2e "
           "cholmod_residual=%.2e eigen_nnzL=%lld cholmod_analyze_ms=%.2f cholmod_ordering=%s ours_supernodes=%zu "
           "nnzL_ratio=%.3f factor_ratio_cholmod=%.3f factor_ratio_eigen=%.3f solve_ratio=%.3f ours_stored=%zu "
           "cholmod_stored=%.0f\n",
           name, n, info.nnz_l, cholmod_lnz, 1e3 * ours_analyze_s, 1e3 * ours_factor_s, 1e3 * cholmod_factor_s,
           1e3 * eigen_factor_s, 1e3 * ours_solve_s, 1e3 * cholmod_solve_s, ours_res, cholmod_res, eigen_nnz,
           1e3 * cholmod_analyze_s, ordering_name, info.supernodes, (double)info.nnz_l / cholmod_lnz,
           ours_factor_s / cholmod_factor_s, ours_factor_s / eigen_factor_s, ours_solve_s / cholmod_solve_s,
           info.stored_entries, cholmod_stored);
    fflush(stdout);
    dfm_chol_free(s.chol);
}

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off";
    for (int i = 1; i < argc; i++)
        if (argv[i][0] != '-') path = argv[i];
    BENCH_PRINT_FLAGS("bench_chol");
    mio_mesh mesh;
    mio_error err;
    if (mio_read_file(path, NULL, &mesh, &err) != MIO_OK) {
        fprintf(stderr, "%s: %s\n", path, err.message);
        return 1;
    }
    size_t nv = mesh.vertex_count;
    dfm_csc lap, bil;
    if (dfm_mesh_laplacian(mesh.positions, nv, mesh.indices, mesh.triangle_count, DFM_LAPLACIAN_COTAN, NULL, &lap) != DFM_OK) {
        fprintf(stderr, "bench_chol: Laplacian assembly failed\n");
        return 1;
    }
    std::vector<double> constraint(nv, 0.0);
    for (size_t i = 0; i < nv; i += 100) constraint[i] = 1.0;
    double t0 = bench_now();
    dfm_result r = dfm_normal_matrix(&lap, constraint.data(), NULL, &bil);
    double normal_ms = 1e3 * (bench_now() - t0);
    if (r != DFM_OK) {
        fprintf(stderr, "bench_chol: normal equations failed: %s\n", dfm_result_string(r));
        return 1;
    }
    for (size_t j = 0; j < nv; j++)
        if (constraint[j] != 0.0) lap.values[lap.col_start[j]] += 1.0; /* the diagonal is first */
    printf("RESULT chol_blas lib=%s\n", blas_library());
    printf("RESULT chol_assembly n=%zu normal_equations_ms=%.2f\n", nv, normal_ms);
    fflush(stdout);
    std::vector<double> coords(3 * nv);
    for (size_t i = 0; i < 3 * nv; i++) coords[i] = mesh.positions[i];
    run_system("laplacian", lap, coords.data());
    if (nv <= 200000) run_system("bilaplacian", bil, coords.data());
    else fprintf(stderr, "bench_chol: bilaplacian skipped above 200k vertices\n");
    dfm_csc_free(&lap);
    dfm_csc_free(&bil);
    mio_free_mesh(&mesh);
    printf("RESULT bench_chol process_peak_rss_mb=%.1f\n", bench_peak_rss_kb() / 1024.0);
    return 0;
}
