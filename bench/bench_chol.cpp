/* bench_chol - deform.h's sparse Cholesky against CHOLMOD (supernodal) and Eigen's SimplicialLLT,
   single thread, proven so at run time.

   build/bench_chol [MESH]      (default build/sphere1m.off)

   Processes: OpenBLAS reads OPENBLAS_CORETYPE and libgomp reads OMP_THREAD_LIMIT when they load,
   so the bench runs itself twice as a child (BENCH_CHOL_SETTING=detected|best, fork + execv of
   /proc/self/exe), each with OMP_THREAD_LIMIT=1 (Debian's CHOLMOD starts 4 OpenMP threads
   otherwise; OMP_NUM_THREADS=1 does not stop it):
     detected  OPENBLAS_CORETYPE unset: the kernel OpenBLAS picks by itself;
     best      OPENBLAS_CORETYPE = the best of SkylakeX, Haswell, Sandybridge, Nehalem that the CPU
               flags allow, OpenBLAS takes (openblas_get_corename agrees) and whose CHOLMOD
               residual passes (<= 1e-12); the next one is tried otherwise.
   A child started by hand without OMP_THREAD_LIMIT=1 re-executes itself with it. After CHOLMOD's
   first factorization and after the timed ones the process's threads are counted
   (/proc/self/status) and the bench fails if there is more than one.

   Systems (assembled by deform.h from the mesh, outside every timer):
     laplacian    the cotangent Laplacian L (dfm_mesh_laplacian, COTAN) with 1% of the vertices
                  constrained (every 100th vertex: +1 on its diagonal)
     bilaplacian  L^T L + the same constraints (dfm_normal_matrix); skipped above 200k vertices
   Right-hand sides: 3 columns of hashed uniform values in [-1, 1).

   Timing (bench.h): analysis, factorization and solve, each interleaved ours / CHOLMOD (and
   Eigen's factorization in the best child), one warm-up each and 11 rounds; medians with min/max.
     RESULT chol_cpu kernel_candidates=<list>
     RESULT chol_blas setting=<detected|best> requested=<coretype|none> core=<openblas_get_corename>
         lib=<the library dgemm_ resolved to> config=<openblas_get_config, spaces as _>
     RESULT chol system=<laplacian|bilaplacian> blas=<setting> core=<name> threads=1 n=... nnzL ...
         ours_analyze_ms ... cholmod_analyze_ms ... analyze_ratio ...
         ours_factor_ms ... cholmod_factor_ms ... factor_ratio ...
         ours_analyze_factor_ms ... cholmod_analyze_factor_ms ... analyze_factor_ratio ...
         eigen_factor_ms ... factor_ratio_eigen ... (best child only)
         ours_solve3_ms ... cholmod_solve3_ms ... solve_ratio ... residual=<r> cholmod_residual=<r>
       ours_analyze: dfm_chol_analyze with the vertex positions as coordinates.
       cholmod_analyze: cholmod_analyze with the default settings (supernodal; AMD, then METIS
         when AMD's fill is high; cholmod_ordering says which), its factor freed outside the timer.
       factor: dfm_chol_factor / cholmod_factorize (numeric only, on one analysis made outside the
         timer) / SimplicialLLT<Lower, AMDOrdering>::factorize after one analyzePattern.
       analyze_factor: per round, that round's analysis + factorization time of the side.
       solve3: one solve with 3 right-hand sides (dfm_chol_solve on a copy of B, the copy timed;
         cholmod_solve(CHOLMOD_A) returning a new dense X, freed outside the timer).
       nnzL: exact entries of L (ours: the symbolic count; CHOLMOD: Common->lnz); *_stored:
         entries held by the supernodal factors (amalgamation zeros included; CHOLMOD: xsize).
       residual: max over the 3 columns of |b - Ax|inf / (|A|inf |x|inf + |b|inf).
     RESULT chol_kernel ... accepted=0   a kernel rejected (not taken, or the residual failed). */
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
#include <string>
#include <vector>

#include <strings.h>
#include <sys/wait.h>
#include <unistd.h>

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

/* OpenBLAS's own report, looked up at run time so that the bench also runs on another BLAS */
static const char *openblas_string(const char *symbol)
{
    typedef char *(*fn)(void);
    void *sym = dlsym(RTLD_DEFAULT, symbol);
    if (!sym) return "none";
    fn f;
    memcpy(&f, &sym, sizeof f); /* object pointer to function pointer without a cast warning */
    const char *r = f();
    return r ? r : "none";
}

/* the string without spaces (RESULT values have none) */
static std::string no_spaces(const char *s)
{
    std::string r(s);
    for (char &c : r)
        if (c == ' ') c = '_';
    while (!r.empty() && (r.back() == '_' || r.back() == '\n')) r.pop_back();
    return r;
}

/* the process's threads now (/proc/self/status "Threads:"), -1 if unknown */
static long thread_count(void) { return bench__status_kb("Threads"); }

struct state {
    const dfm_csc *a = nullptr;
    dfm_chol_options options = dfm_chol_default_options();
    const std::vector<double> *b = nullptr;
    dfm_chol *chol = nullptr, *chol_timed = nullptr;
    std::vector<double> x;
    cholmod_common *cc = nullptr;
    cholmod_sparse *ca = nullptr;
    cholmod_factor *cf = nullptr, *cf_timed = nullptr;
    cholmod_dense *cb = nullptr, *cx = nullptr;
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> *eigen = nullptr;
    const Eigen::SparseMatrix<double> *ea = nullptr;
};

static int ours_analyze(void *u)
{
    state &s = *(state *)u;
    return dfm_chol_analyze(s.a, &s.options, &s.chol_timed) != DFM_OK;
}
static void ours_analyze_after(void *u)
{
    state &s = *(state *)u;
    dfm_chol_free(s.chol_timed);
    s.chol_timed = nullptr;
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
static int cholmod_analyze_run(void *u)
{
    state &s = *(state *)u;
    s.cf_timed = cholmod_analyze(s.ca, s.cc);
    return s.cf_timed == nullptr;
}
static void cholmod_analyze_after(void *u)
{
    state &s = *(state *)u;
    cholmod_free_factor(&s.cf_timed, s.cc);
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

static void fail(const char *what)
{
    fprintf(stderr, "bench_chol: %s\n", what);
    exit(1);
}

/* a side whose round r took analyse[r] + factor[r]: the setup a deformation pays */
static bench_side sum_side(const bench_side &analyse, const bench_side &factor)
{
    bench_side s = bench_make_side("analyse+factor", nullptr, nullptr, nullptr);
    s.runs = analyse.runs < factor.runs ? analyse.runs : factor.runs;
    for (int r = 0; r < s.runs; r++) s.samples[r] = analyse.samples[r] + factor.samples[r];
    s.median = bench__sorted_median(s.samples, s.runs, &s.min, &s.max);
    return s;
}

/* CHOLMOD's copy of the lower triangle, and its analysis (kept for the factor and solve runs) */
static void cholmod_setup(state &s, cholmod_common &cc, const dfm_csc &a)
{
    size_t n = a.n_cols, nnz = a.col_start[n];
    cholmod_start(&cc);
    cc.supernodal = CHOLMOD_SUPERNODAL;
    s.cc = &cc;
    s.ca = cholmod_allocate_sparse(n, n, nnz, 1, 1, -1, CHOLMOD_REAL, &cc);
    if (!s.ca) fail("cholmod_allocate_sparse failed");
    int *cp = (int *)s.ca->p, *ci = (int *)s.ca->i;
    double *cxv = (double *)s.ca->x;
    for (size_t j = 0; j <= n; j++) cp[j] = (int)a.col_start[j];
    for (size_t p = 0; p < nnz; p++) {
        ci[p] = a.row_index[p];
        cxv[p] = a.values[p];
    }
    s.cf = cholmod_analyze(s.ca, &cc);
    if (!s.cf) fail("cholmod_analyze failed");
    s.cb = cholmod_allocate_dense(n, 3, n, CHOLMOD_REAL, &cc);
    if (!s.cb) fail("cholmod_allocate_dense failed");
    memcpy(s.cb->x, s.b->data(), 3 * n * sizeof(double));
}

/* Factors and solves once with CHOLMOD: the kernel check and the thread check. Returns the
   residual of CHOLMOD's x; exits when CHOLMOD ran on more than one thread. */
static double cholmod_check(state &s, const dfm_csc &a)
{
    if (cholmod_factor_run(&s) || cholmod_solve_run(&s)) fail("CHOLMOD's factorization failed");
    long threads = thread_count();
    if (threads != 1) {
        printf("RESULT chol error=cholmod_threads threads=%ld\n", threads);
        fprintf(stderr, "bench_chol: CHOLMOD ran with %ld threads (OMP_THREAD_LIMIT=%s); refusing to time it\n", threads,
                getenv("OMP_THREAD_LIMIT") ? getenv("OMP_THREAD_LIMIT") : "unset");
        exit(1);
    }
    double r = residual(a, (const double *)s.cx->x, s.b->data(), 3);
    cholmod_solve_after(&s);
    return r;
}

static void eigen_setup(state &s, Eigen::SparseMatrix<double> &ea, const dfm_csc &a)
{
    size_t n = a.n_cols;
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(a.col_start[n]);
    for (size_t j = 0; j < n; j++)
        for (size_t p = a.col_start[j]; p < a.col_start[j + 1]; p++) trip.emplace_back(a.row_index[p], (int)j, a.values[p]);
    ea.setFromTriplets(trip.begin(), trip.end());
    s.ea = &ea;
    s.eigen = new Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>>();
    s.eigen->analyzePattern(ea);
}

static const char *ordering_name(int ordering)
{
    return ordering == CHOLMOD_AMD ? "amd" : ordering == CHOLMOD_METIS ? "metis" : ordering == CHOLMOD_NESDIS ? "nesdis"
         : ordering == CHOLMOD_NATURAL ? "natural" : ordering == CHOLMOD_COLAMD ? "colamd" : "other";
}

/* a residual a backward-stable factorization stays far below (ours and CHOLMOD give 1e-17 to
   1e-15 here); a broken BLAS kernel gives O(1) */
static const double RESIDUAL_OK = 1e-12;

/* Times one system: analysis, factorization and solve, each interleaved ours / CHOLMOD (/ Eigen
   when with_eigen). Returns 4 when CHOLMOD's residual fails the kernel check (nothing printed
   then but the chol_kernel line), else 0. */
static int run_system(const char *name, const char *setting, const dfm_csc &a, const double *coords, bool with_eigen)
{
    size_t n = a.n_cols, nnz = a.col_start[n];
    std::vector<double> b(3 * n);
    for (size_t i = 0; i < 3 * n; i++) b[i] = 2.0 * unit_random(i, 9) - 1.0;
    state s;
    s.a = &a;
    s.b = &b;
    s.options.coords = coords;
    bool large = n > 200000;

    fprintf(stderr, "bench_chol: %s n=%zu nnz(A lower)=%zu, CHOLMOD with the %s BLAS kernel\n", name, n, nnz, setting);
    if (dfm_chol_analyze(&a, &s.options, &s.chol) != DFM_OK) fail("our analysis failed");
    cholmod_common cc;
    cholmod_setup(s, cc, a);
    double cholmod_lnz = cc.lnz, cholmod_stored = (double)s.cf->xsize;
    size_t cholmod_supernodes = s.cf->is_super ? (size_t)s.cf->nsuper : 0;
    int ordering = cc.method[cc.selected].ordering;
    double cholmod_res = cholmod_check(s, a);
    if (!(cholmod_res <= RESIDUAL_OK)) {
        printf("RESULT chol_kernel setting=%s core=%s system=%s cholmod_residual=%.2e accepted=0\n", setting,
               openblas_string("openblas_get_corename"), name, cholmod_res);
        fflush(stdout);
        if (strcmp(setting, "best") == 0) return 4;
    }

    fprintf(stderr, "bench_chol: %s: analysis, ours and CHOLMOD interleaved\n", name);
    bench_side an[2] = {bench_make_side("ours", ours_analyze, ours_analyze_after, &s),
                        bench_make_side("cholmod", cholmod_analyze_run, cholmod_analyze_after, &s)};
    if (bench_interleave(an, 2, 0) != 0) fail("an analysis failed");

    fprintf(stderr, "bench_chol: %s: factorization, ours, CHOLMOD%s interleaved\n", name, with_eigen ? " and Eigen" : "");
    Eigen::SparseMatrix<double> ea((Eigen::Index)n, (Eigen::Index)n);
    if (with_eigen) eigen_setup(s, ea, a);
    bench_side fa[3] = {bench_make_side("ours", ours_factor, nullptr, &s),
                        bench_make_side("cholmod", cholmod_factor_run, nullptr, &s),
                        bench_make_side("eigen", eigen_factor, nullptr, &s)};
    if (large) fa[2].max_runs = 3; /* Eigen's simplicial factor takes ~14 s a run on the 1M sphere */
    if (bench_interleave(fa, with_eigen ? 3 : 2, 0) != 0) fail("a factorization failed");
    long long eigen_nnz = with_eigen ? (long long)s.eigen->matrixL().nestedExpression().nonZeros() : -1;
    delete s.eigen;
    s.eigen = nullptr;
    long threads = thread_count();
    if (threads != 1) fail("more than one thread after the timed factorizations");

    fprintf(stderr, "bench_chol: %s: solve, ours and CHOLMOD interleaved\n", name);
    bench_side so[2] = {bench_make_side("ours", ours_solve, nullptr, &s),
                        bench_make_side("cholmod", cholmod_solve_run, cholmod_solve_after, &s)};
    if (bench_interleave(so, 2, 0) != 0) fail("a solve failed");
    double ours_res = residual(a, s.x.data(), b.data(), 3);
    dfm_chol_info info;
    dfm_chol_get_info(s.chol, &info);
    bench_side ours_af = sum_side(an[0], fa[0]), cholmod_af = sum_side(an[1], fa[1]);

    printf("RESULT chol system=%s blas=%s core=%s threads=%ld n=%zu ours_nnzL=%zu cholmod_nnzL=%.0f nnzL_ratio=%.3f "
           "cholmod_ordering=%s",
           name, setting, openblas_string("openblas_get_corename"), threads, n, info.nnz_l, cholmod_lnz,
           (double)info.nnz_l / cholmod_lnz, ordering_name(ordering));
    bench_print_ms("ours_analyze", &an[0]);
    bench_print_ms("cholmod_analyze", &an[1]);
    bench_print_ratio_named("analyze_ratio", &an[0], &an[1]);
    bench_print_ms("ours_factor", &fa[0]);
    bench_print_ms("cholmod_factor", &fa[1]);
    bench_print_ratio_named("factor_ratio", &fa[0], &fa[1]);
    bench_print_ms("ours_analyze_factor", &ours_af);
    bench_print_ms("cholmod_analyze_factor", &cholmod_af);
    bench_print_ratio_named("analyze_factor_ratio", &ours_af, &cholmod_af);
    if (with_eigen) {
        bench_print_ms("eigen_factor", &fa[2]);
        bench_print_ratio_named("factor_ratio_eigen", &fa[0], &fa[2]);
        printf(" eigen_runs=%d eigen_nnzL=%lld", fa[2].runs, eigen_nnz);
    }
    bench_print_ms("ours_solve3", &so[0]);
    bench_print_ms("cholmod_solve3", &so[1]);
    bench_print_ratio_named("solve_ratio", &so[0], &so[1]);
    printf(" residual=%.2e cholmod_residual=%.2e ours_supernodes=%zu cholmod_supernodes=%zu ours_stored=%zu "
           "cholmod_stored=%.0f\n",
           ours_res, cholmod_res, info.supernodes, cholmod_supernodes, info.stored_entries, cholmod_stored);
    fflush(stdout);

    cholmod_free_dense(&s.cb, &cc);
    cholmod_free_factor(&s.cf, &cc);
    cholmod_free_sparse(&s.ca, &cc);
    cholmod_finish(&cc);
    dfm_chol_free(s.chol);
    return 0;
}

/* One measurement process (BENCH_CHOL_SETTING = detected | best): OpenBLAS and libgomp have read
   the environment at load time. Returns the exit status: 0, 1 failure, 4 kernel rejected. */
static int measure(const char *path, const char *setting)
{
    const char *requested = getenv("OPENBLAS_CORETYPE");
    const char *core = openblas_string("openblas_get_corename");
    printf("RESULT chol_blas setting=%s requested=%s core=%s lib=%s config=%s\n", setting, requested ? requested : "none",
           core, blas_library(), no_spaces(openblas_string("openblas_get_config")).c_str());
    fflush(stdout);
    if (requested && strcasecmp(requested, core) != 0) {
        printf("RESULT chol_kernel setting=%s requested=%s core=%s accepted=0 reason=not_taken\n", setting, requested, core);
        return 4;
    }
    mio_mesh mesh;
    mio_error err;
    if (mio_read_file(path, NULL, &mesh, &err) != MIO_OK) {
        fprintf(stderr, "%s: %s\n", path, err.message);
        return 1;
    }
    size_t nv = mesh.vertex_count;
    dfm_csc lap, bil;
    if (dfm_mesh_laplacian(mesh.positions, nv, mesh.indices, mesh.triangle_count, DFM_LAPLACIAN_COTAN, NULL, &lap) != DFM_OK)
        fail("Laplacian assembly failed");
    std::vector<double> constraint(nv, 0.0);
    for (size_t i = 0; i < nv; i += 100) constraint[i] = 1.0;
    double t0 = bench_now();
    dfm_result r = dfm_normal_matrix(&lap, constraint.data(), NULL, &bil);
    double normal_ms = 1e3 * (bench_now() - t0);
    if (r != DFM_OK) fail("normal equations failed");
    for (size_t j = 0; j < nv; j++)
        if (constraint[j] != 0.0) lap.values[lap.col_start[j]] += 1.0; /* the diagonal is first */
    if (strcmp(setting, "detected") == 0) printf("RESULT chol_assembly n=%zu normal_equations_ms=%.2f\n", nv, normal_ms);
    fflush(stdout);
    std::vector<double> coords(3 * nv);
    for (size_t i = 0; i < 3 * nv; i++) coords[i] = mesh.positions[i];
    bool best = strcmp(setting, "best") == 0;
    int status = run_system("laplacian", setting, lap, coords.data(), best);
    if (status == 0 && nv <= 200000) status = run_system("bilaplacian", setting, bil, coords.data(), best);
    else if (status == 0) fprintf(stderr, "bench_chol: bilaplacian skipped above 200k vertices\n");
    dfm_csc_free(&lap);
    dfm_csc_free(&bil);
    mio_free_mesh(&mesh);
    if (status == 0)
        printf("RESULT bench_chol blas=%s process_peak_rss_mb=%.1f\n", setting, bench_peak_rss_kb() / 1024.0);
    return status;
}

/* the OPENBLAS_CORETYPE values to try, best first, from the flags of /proc/cpuinfo (x86-64) */
static std::vector<std::string> kernel_candidates(void)
{
    std::vector<std::string> r;
    char line[8192];
    std::string flags;
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f) return r;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "flags", 5) == 0) {
            flags = std::string(" ") + (strchr(line, ':') ? strchr(line, ':') + 1 : line);
            break;
        }
    fclose(f);
    for (char &c : flags)
        if (c == '\n' || c == '\t') c = ' ';
    flags += " ";
    auto has = [&](const char *flag) { return flags.find(std::string(" ") + flag + " ") != std::string::npos; };
    if (has("avx512f") && has("avx512dq") && has("avx512bw") && has("avx512vl") && has("avx512cd")) r.push_back("SkylakeX");
    if (has("avx2") && has("fma")) r.push_back("Haswell");
    if (has("avx")) r.push_back("Sandybridge");
    if (has("sse4_2")) r.push_back("Nehalem");
    return r;
}

/* Runs this program again as a measurement process with the environment OpenBLAS and libgomp
   read at load time; returns its exit status. */
static int spawn(char **argv, const char *setting, const char *coretype)
{
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) return 1;
    if (pid == 0) {
        setenv("BENCH_CHOL_SETTING", setting, 1);
        setenv("OMP_THREAD_LIMIT", "1", 1); /* OMP_NUM_THREADS alone does not stop CHOLMOD's 4 threads */
        setenv("OMP_NUM_THREADS", "1", 1);
        setenv("OPENBLAS_NUM_THREADS", "1", 1);
        if (coretype) setenv("OPENBLAS_CORETYPE", coretype, 1);
        else unsetenv("OPENBLAS_CORETYPE");
        execv("/proc/self/exe", argv);
        _exit(127);
    }
    int st = 0;
    if (waitpid(pid, &st, 0) != pid) return 1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 1;
}

int main(int argc, char **argv)
{
    const char *path = "build/sphere1m.off";
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            printf("usage: bench_chol [MESH]   (default build/sphere1m.off)\n");
            return 0;
        }
        if (argv[i][0] != '-') path = argv[i];
    }
    const char *setting = getenv("BENCH_CHOL_SETTING");
    if (setting) {
        const char *limit = getenv("OMP_THREAD_LIMIT");
        if (!limit || strcmp(limit, "1") != 0) { /* run by hand: the limit must be there before libgomp loads */
            setenv("OMP_THREAD_LIMIT", "1", 1);
            execv("/proc/self/exe", argv);
            fail("cannot re-execute /proc/self/exe");
        }
        return measure(path, setting);
    }
    BENCH_PRINT_FLAGS("bench_chol");
    std::vector<std::string> candidates = kernel_candidates();
    std::string list;
    for (const std::string &c : candidates) list += (list.empty() ? "" : ",") + c;
    printf("RESULT chol_cpu kernel_candidates=%s\n", list.empty() ? "none" : list.c_str());
    int status = spawn(argv, "detected", nullptr);
    if (status != 0) return 1;
    for (const std::string &c : candidates) {
        fprintf(stderr, "bench_chol: CHOLMOD with OPENBLAS_CORETYPE=%s\n", c.c_str());
        status = spawn(argv, "best", c.c_str());
        if (status == 0) return 0;
        if (status != 4) return 1;
    }
    printf("RESULT chol_kernel setting=best accepted=none\n");
    return 0;
}
