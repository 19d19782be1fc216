/* bench.h - the small harness every bench/bench_*.c[pp] program uses (C99 and C++, Linux/POSIX)

   CONVENTIONS (every bench program follows them; bench/run.sh and bench/README.md rely on them)
     - The input mesh path is the first non-option argument (default build/sphere1m.off), so any
       mesh can be measured the same way. Outputs, if any, are named with -o.
     - Progress goes to stderr, each message ending with a newline.
     - Results go to stdout, one line per figure, starting at column 0:
           RESULT <name> key=value key=value ...
       Values have no spaces, except a value in double quotes (used for the compile flags).
     - The first RESULT line gives the compiler and flags: BENCH_PRINT_FLAGS(name).
     - Each side is timed in the same process on the same input: one warm-up run, then the
       median of 5 timed runs (bench_median). Only the work written down in bench/README.md is
       inside the timer; setup and freeing are outside it.
     - Memory: bench_reset_peak_rss() before a side, bench_peak_rss_kb() after it.
     - Single thread unless the figure says otherwise.

   HOW TO USE
       #include "bench.h"          // first, before any system header (it selects POSIX in C99)
       static int run(void *user) { ...the timed work...; return 0; }   // nonzero = failed
       static void after(void *user) { ...free what run made... }       // outside the timer
       BENCH_PRINT_FLAGS("bench_x");
       double seconds = bench_median(run, after, &state);                // < 0 if run failed
       printf("RESULT bench_x ms=%.3f\n", 1e3 * seconds);

   BENCH_FLAGS is set by the Makefile (-DBENCH_FLAGS="\"$(CXX) $(CXXFLAGS)\""); "unknown" if not.
   Everything here is static inline: no state, nothing to link, no unused-function warnings. */
#ifndef BENCH_H
#define BENCH_H

#if !defined(__cplusplus) && !defined(_POSIX_C_SOURCE) && !defined(_GNU_SOURCE)
#define _POSIX_C_SOURCE 200809L /* clock_gettime and getrusage under -std=c99 */
#endif

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h> /* malloc_trim */
#endif

#ifndef BENCH_FLAGS
#define BENCH_FLAGS "unknown"
#endif
#if defined(__clang__) && defined(__VERSION__)
#define BENCH_COMPILER __VERSION__ /* "Debian Clang 14.0.6" */
#elif defined(__GNUC__) && defined(__VERSION__)
#define BENCH_COMPILER "gcc " __VERSION__ /* gcc's __VERSION__ is the number alone */
#else
#define BENCH_COMPILER "unknown"
#endif

/* An allocator for large blocks backed by transparent huge pages (Linux, THP in "madvise" or
   "always" mode): blocks of 1 MiB and more are 2 MiB-aligned and madvise(MADV_HUGEPAGE)d, others
   come from malloc. Embree does the same for its BVHs; a library user passes these two to the
   library's allocator hook (dispmesh.h's dm_allocator documents it). Elsewhere it is malloc/free. */
#if defined(__linux__)
#include <sys/mman.h>
#endif
static inline void *bench_hugepage_alloc(void *user, size_t size)
{
    (void)user;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (size >= ((size_t)1 << 20)) {
        const size_t huge = (size_t)1 << 21;
        size_t len = (size + huge - 1) & ~(huge - 1);
        void *p = len >= size ? aligned_alloc(huge, len) : NULL;
        if (p) madvise(p, len, MADV_HUGEPAGE);
        return p;
    }
#endif
    return malloc(size);
}
static inline void bench_hugepage_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

/* warm-up runs and timed runs of bench_median */
#define BENCH_WARMUP 1
#define BENCH_RUNS 5

/* prints "RESULT <name> compiler="..." flags="..."" */
#define BENCH_PRINT_FLAGS(name) \
    printf("RESULT %s compiler=\"%s\" flags=\"%s\"\n", (name), BENCH_COMPILER, BENCH_FLAGS)

/* monotonic clock in seconds (arbitrary origin) */
/* Seconds of CPU time of the whole process (user + system, every thread): on a shared machine a
   run is not charged for the time other processes hold the core, and a peer that starts helper
   threads is charged for them. Every peer is run single-threaded anyway; for a single thread on
   an idle machine this is the wall time. */
static inline double bench_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Runs run(user) BENCH_WARMUP times untimed, then BENCH_RUNS times timed, and returns the median
   of the timed runs in seconds. after(user), which may be NULL, is called after every run
   (warm-up included) outside the timer, to free what run made. Returns -1.0 as soon as run
   returns nonzero (after is still called for that run). */
static inline double bench_median(int (*run)(void *user), void (*after)(void *user), void *user)
{
    double samples[BENCH_RUNS];
    int i, j;
    for (i = 0; i < BENCH_WARMUP + BENCH_RUNS; i++) {
        double start = bench_now(), elapsed;
        int failed = run(user);
        elapsed = bench_now() - start;
        if (after) after(user);
        if (failed) return -1.0;
        if (i >= BENCH_WARMUP) samples[i - BENCH_WARMUP] = elapsed;
    }
    for (i = 1; i < BENCH_RUNS; i++) /* insertion sort: five numbers */
        for (j = i; j > 0 && samples[j - 1] > samples[j]; j--) {
            double t = samples[j];
            samples[j] = samples[j - 1];
            samples[j - 1] = t;
        }
    return samples[BENCH_RUNS / 2];
}

/* a "Vm...:" field of /proc/self/status in kB, or -1 */
static inline long bench__status_kb(const char *field)
{
    char line[256];
    size_t n = strlen(field);
    long kb = -1;
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, field, n) == 0 && line[n] == ':') {
            kb = strtol(line + n + 1, NULL, 10);
            break;
        }
    fclose(f);
    return kb;
}

/* peak resident set size of this process in kB since start or the last successful
   bench_reset_peak_rss(): VmHWM, else getrusage's ru_maxrss (kB on Linux, never reset) */
static inline long bench_peak_rss_kb(void)
{
    struct rusage usage;
    long kb = bench__status_kb("VmHWM");
    if (kb >= 0) return kb;
    if (getrusage(RUSAGE_SELF, &usage) == 0) return (long)usage.ru_maxrss;
    return -1;
}

/* current resident set size in kB (VmRSS), or -1 */
static inline long bench_current_rss_kb(void) { return bench__status_kb("VmRSS"); }

/* Resets the peak to the current RSS (Linux >= 4.0: "5" into /proc/self/clear_refs), so that
   bench_peak_rss_kb() minus bench_current_rss_kb() taken right after measures one side. With
   glibc it first returns freed heap memory to the system (malloc_trim), or a side could reuse
   pages the previous side left resident and look smaller than it is. Returns 0 on success, -1
   if not possible (then peaks are process-wide). */
static inline int bench_reset_peak_rss(void)
{
    int ok;
    FILE *f;
#ifdef __GLIBC__
    malloc_trim(0);
#endif
    f = fopen("/proc/self/clear_refs", "w");
    if (!f) return -1;
    ok = fputs("5", f) >= 0;
    if (fclose(f) != 0) ok = 0;
    return ok ? 0 : -1;
}

#endif /* BENCH_H */
