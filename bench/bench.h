/* bench.h - the small harness every bench/bench_*.c[pp] program uses (C99 and C++, Linux/POSIX)

   CONVENTIONS (every bench program follows them; bench/run.sh and bench/README.md rely on them)
     - The input mesh path is the first non-option argument (default build/sphere1m.off), so any
       mesh can be measured the same way. Outputs, if any, are named with -o.
     - Progress goes to stderr, each message ending with a newline.
     - Results go to stdout, one line per figure, starting at column 0:
           RESULT <name> key=value key=value ...
       Values have no spaces, except a value in double quotes (used for the compile flags).
     - The first RESULT line gives the compiler and flags: BENCH_PRINT_FLAGS(name).
     - Comparisons are interleaved (bench_interleave): every side gets one untimed warm-up run,
       then the sides take turns, A B A B ..., BENCH_INTERLEAVED_RUNS (11) timed runs each, so
       that a slow spell of a shared machine hits every side alike. Each figure is the median
       with its min and max, printed by bench_print_ms as
           <key>_ms=12.3 <key>_ms_min=11.9 <key>_ms_max=13.0
       and a ratio by bench_print_ratio as
           ratio=0.812 ratio_min=0.790 ratio_max=0.840
       (median, min and max of the per-round ratios A_i / B_i, so close to but not exactly
       the ratio of the two medians).
       A figure without a peer may use bench_median (one warm-up, median of 5, no spread).
       Only the work written down in bench/README.md is inside the timer; setup and freeing are
       outside it (the after callback).
     - Memory: bench_interleave measures each side's warm-up run (peak_kb); by hand,
       bench_reset_peak_rss() before a side, bench_peak_rss_kb() after it.
     - Single thread unless the figure says otherwise.

   HOW TO USE
       #include "bench.h"          // first, before any system header (it selects POSIX in C99)
       static int run(void *user) { ...the timed work...; return 0; }   // nonzero = failed
       static void after(void *user) { ...free what run made... }       // outside the timer
       BENCH_PRINT_FLAGS("bench_x");
       bench_side s[2];
       s[0] = bench_make_side("ours", run_ours, after_ours, &state);
       s[1] = bench_make_side("peer", run_peer, after_peer, &state);
       if (bench_interleave(s, 2, 0) != 0) ...a run failed...
       printf("RESULT bench_x");
       bench_print_ms("ours", &s[0]); bench_print_ms("peer", &s[1]); bench_print_ratio(&s[0], &s[1]);
       printf("\n");
       double seconds = bench_median(run, after, &state);                // < 0 if run failed

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

/* warm-up runs and timed runs of bench_median; timed runs per side of bench_interleave (default),
   and the most it stores */
#define BENCH_WARMUP 1
#define BENCH_RUNS 5
#define BENCH_INTERLEAVED_RUNS 11
#define BENCH_MAX_RUNS 64

/* prints "RESULT <name> compiler="..." flags="..."" */
#define BENCH_PRINT_FLAGS(name) \
    printf("RESULT %s compiler=\"%s\" flags=\"%s\"\n", (name), BENCH_COMPILER, BENCH_FLAGS)

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

static inline long bench_peak_rss_kb(void);
static inline long bench_current_rss_kb(void);
static inline int bench_reset_peak_rss(void);

/* One side of a comparison: the first four fields are given, the rest are filled in by
   bench_interleave. max_runs, if nonzero and smaller than the run count, makes this side stop
   after max_runs timed runs while the others go on (for a peer that takes many seconds a run on
   a large input; the bench prints <key>_runs then). */
typedef struct bench_side {
    const char *name;          /* for progress messages on stderr (slow warm-ups) */
    int (*run)(void *user);    /* the timed work; nonzero = failed */
    void (*after)(void *user); /* may be NULL: after every run, outside the timer */
    void *user;
    int max_runs;              /* 0 = as many as the others */
    int runs;                  /* timed runs done */
    double samples[BENCH_MAX_RUNS]; /* seconds, in run order */
    double median, min, max;   /* seconds */
    long peak_kb;              /* the warm-up run's RSS high-water mark above its start; -1 unknown */
} bench_side;

/* a side with the given fields and everything else zero (an aggregate initializer with fewer
   fields trips -Wmissing-field-initializers) */
static inline bench_side bench_make_side(const char *name, int (*run)(void *user), void (*after)(void *user),
                                         void *user)
{
    bench_side s;
    memset(&s, 0, sizeof s);
    s.name = name;
    s.run = run;
    s.after = after;
    s.user = user;
    return s;
}

static inline double bench__sorted_median(const double *v, int n, double *lo, double *hi)
{
    double t[BENCH_MAX_RUNS];
    int i, j;
    for (i = 0; i < n; i++) t[i] = v[i];
    for (i = 1; i < n; i++) /* insertion sort: a few dozen numbers at most */
        for (j = i; j > 0 && t[j - 1] > t[j]; j--) {
            double x = t[j];
            t[j] = t[j - 1];
            t[j - 1] = x;
        }
    if (lo) *lo = t[0];
    if (hi) *hi = t[n - 1];
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

/* one run of a side: the timed run, then after; stores the time in *elapsed; nonzero = failed */
static inline int bench__run_once(bench_side *s, double *elapsed)
{
    double start = bench_now();
    int failed = s->run(s->user);
    *elapsed = bench_now() - start;
    if (s->after) s->after(s->user);
    return failed;
}

/* The warm-up of every side, in order, each measured for memory: freed heap memory is returned
   to the system and the high-water mark reset before it, so peak_kb is what this one run adds. */
static inline int bench__warm_up(bench_side *sides, int count)
{
    int k;
    for (k = 0; k < count; k++) {
        bench_side *s = &sides[k];
        int reset = bench_reset_peak_rss() == 0;
        long rss0 = bench_current_rss_kb();
        double start = bench_now();
        int failed = s->run(s->user);
        s->peak_kb = reset && rss0 >= 0 ? bench_peak_rss_kb() - rss0 : -1;
        if (bench_now() - start > 2.0) fprintf(stderr, "bench: warm-up of %s done\n", s->name ? s->name : "a side");
        if (s->after) s->after(s->user);
        if (failed) return -1;
    }
    return 0;
}

/* Times count sides against each other: one warm-up run of each side (A, B, ...), then `runs`
   rounds (0 = BENCH_INTERLEAVED_RUNS, at most BENCH_MAX_RUNS) in which every side runs once, in
   order: A B A B ... Fills in runs, samples, median, min, max (seconds) and peak_kb of each side.
   Progress goes to stderr. Returns 0, or -1 as soon as a run fails (after is still called for
   it). */
static inline int bench_interleave(bench_side *sides, int count, int runs)
{
    int r, k;
    if (runs <= 0) runs = BENCH_INTERLEAVED_RUNS;
    if (runs > BENCH_MAX_RUNS) runs = BENCH_MAX_RUNS;
    for (k = 0; k < count; k++) sides[k].runs = 0;
    if (bench__warm_up(sides, count) != 0) return -1;
    for (r = 0; r < runs; r++) {
        double round_start = bench_now();
        for (k = 0; k < count; k++) {
            bench_side *s = &sides[k];
            if (s->max_runs > 0 && s->runs >= s->max_runs) continue;
            if (bench__run_once(s, &s->samples[s->runs]) != 0) return -1;
            s->runs++;
        }
        if (bench_now() - round_start > 2.0) fprintf(stderr, "bench: round %d of %d done\n", r + 1, runs);
    }
    for (k = 0; k < count; k++)
        sides[k].median = bench__sorted_median(sides[k].samples, sides[k].runs, &sides[k].min, &sides[k].max);
    return 0;
}

/* Prints " <key>_ms=<median> <key>_ms_min=<min> <key>_ms_max=<max>" (no newline), each with
   three decimals below 10 ms, two below 100 ms, one above; key may be "" (then
   " ms=... ms_min=... ms_max=..."). */
static inline void bench__print_value(double ms)
{
    if (ms < 10.0) printf("%.3f", ms);
    else if (ms < 100.0) printf("%.2f", ms);
    else printf("%.1f", ms);
}
static inline void bench_print_ms(const char *key, const bench_side *s)
{
    const char *sep = key[0] ? "_" : "";
    printf(" %s%sms=", key, sep);
    bench__print_value(1e3 * s->median);
    printf(" %s%sms_min=", key, sep);
    bench__print_value(1e3 * s->min);
    printf(" %s%sms_max=", key, sep);
    bench__print_value(1e3 * s->max);
}

/* Prints " <key>=<median> <key>_min=<min> <key>_max=<max>" (no newline) of the per-round ratios
   a_i / b_i over the rounds both sides ran: a pair of runs next to each other in time shares the
   machine's state, so the round ratio is steadier than either time. key NULL = "ratio". */
static inline void bench_print_ratio_named(const char *key, const bench_side *a, const bench_side *b)
{
    double q[BENCH_MAX_RUNS], med = 0, lo = 0, hi = 0;
    int r, n = a->runs < b->runs ? a->runs : b->runs;
    if (!key) key = "ratio";
    for (r = 0; r < n; r++) q[r] = b->samples[r] > 0 ? a->samples[r] / b->samples[r] : 0;
    if (n > 0) med = bench__sorted_median(q, n, &lo, &hi);
    printf(" %s=%.3f %s_min=%.3f %s_max=%.3f", key, med, key, lo, key, hi);
}
static inline void bench_print_ratio(const bench_side *a, const bench_side *b) { bench_print_ratio_named(NULL, a, b); }

/* Runs run(user) BENCH_WARMUP times untimed, then BENCH_RUNS times timed, and returns the median
   of the timed runs in seconds, without spread (for a figure without a peer; comparisons use
   bench_interleave). after(user), which may be NULL, is called after every run (warm-up
   included) outside the timer, to free what run made. Returns -1.0 as soon as run returns
   nonzero (after is still called for that run). */
static inline double bench_median(int (*run)(void *user), void (*after)(void *user), void *user)
{
    double samples[BENCH_RUNS], elapsed;
    bench_side s = bench_make_side("", run, after, user);
    int i;
    for (i = 0; i < BENCH_WARMUP + BENCH_RUNS; i++) {
        if (bench__run_once(&s, &elapsed) != 0) return -1.0;
        if (i >= BENCH_WARMUP) samples[i - BENCH_WARMUP] = elapsed;
    }
    return bench__sorted_median(samples, BENCH_RUNS, NULL, NULL);
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
