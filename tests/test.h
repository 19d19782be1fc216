/* test.h - the project's tiny test harness (one header, C99 and C++).

   Every check is one counted assertion. A test program:

       #include "test.h"
       int main(int argc, char **argv) {
           T_BEGIN(argc, argv);
           T_CHECK(1 + 1 == 2);
           T_EQ_SIZE(count, 34835);
           T_NEAR(x, 1.0, 1e-6);
           if (!have_file) T_SKIP("bunny checks", "/usr/share/... missing: apt-get install glmark2-data");
           return T_END();
       }

   On exit it prints one line that tests/run.sh adds up:
       TESTCOUNT <program> passed=N failed=N skipped=N
   A failed check prints "FAIL file:line: expression" (with values where known) to stdout.
   A program that dies before T_END is counted by the runner as one failure.
   Never put a check inside a condition that makes it unable to fail: a skipped
   check is reported with T_SKIP, never silently dropped. */
#ifndef TEST_H
#define TEST_H
#include <stdio.h>
#include <string.h>
#include <math.h>

typedef struct t__state { long passed, failed, skipped; const char *name; } t__state;
static t__state t__s;

static inline int t__record(int ok, const char *file, int line, const char *expr)
{
    if (ok) { t__s.passed++; return 1; }
    t__s.failed++;
    printf("FAIL %s:%d: %s\n", file, line, expr);
    fflush(stdout);
    return 0;
}

#define T_BEGIN(argc, argv) \
    do { (void)(argc); t__s.name = (argv)[0]; t__s.passed = t__s.failed = t__s.skipped = 0; } while (0)
#define T_CHECK(cond) t__record((cond) ? 1 : 0, __FILE__, __LINE__, #cond)
#define T_CHECK_MSG(cond, ...) \
    (((cond) ? 1 : (printf("  note: "), printf(__VA_ARGS__), printf("\n"), 0)) ? \
        t__record(1, __FILE__, __LINE__, #cond) : t__record(0, __FILE__, __LINE__, #cond))
#define T_EQ_INT(a, b) t__eq_ll((long long)(a), (long long)(b), __FILE__, __LINE__, #a " == " #b)
#define T_EQ_SIZE(a, b) t__eq_ll((long long)(a), (long long)(b), __FILE__, __LINE__, #a " == " #b)
#define T_NEAR(a, b, tol) t__near((double)(a), (double)(b), (double)(tol), __FILE__, __LINE__, #a " ~ " #b)
#define T_EQ_STR(a, b) t__eq_str((a), (b), __FILE__, __LINE__, #a " == " #b)
/* n checks that were not run, with the reason (always printed) */
#define T_SKIP_N(n, what, why) \
    do { t__s.skipped += (n); printf("SKIP %s: %s\n", (what), (why)); fflush(stdout); } while (0)
#define T_SKIP(what, why) T_SKIP_N(1, what, why)
#define T_END() t__end()

static inline int t__eq_ll(long long a, long long b, const char *file, int line, const char *expr)
{
    if (a == b) return t__record(1, file, line, expr);
    printf("  values: %lld != %lld\n", a, b);
    return t__record(0, file, line, expr);
}

static inline int t__near(double a, double b, double tol, const char *file, int line, const char *expr)
{
    /* NaN on either side fails: the comparison below is false for NaN */
    if (fabs(a - b) <= tol) return t__record(1, file, line, expr);
    printf("  values: %.17g vs %.17g (tol %g)\n", a, b, tol);
    return t__record(0, file, line, expr);
}

static inline int t__eq_str(const char *a, const char *b, const char *file, int line, const char *expr)
{
    if (a && b && strcmp(a, b) == 0) return t__record(1, file, line, expr);
    printf("  values: \"%s\" vs \"%s\"\n", a ? a : "(null)", b ? b : "(null)");
    return t__record(0, file, line, expr);
}

static inline int t__end(void)
{
    const char *n = t__s.name ? t__s.name : "test";
    const char *slash = strrchr(n, '/');
    printf("TESTCOUNT %s passed=%ld failed=%ld skipped=%ld\n", slash ? slash + 1 : n,
           t__s.passed, t__s.failed, t__s.skipped);
    fflush(stdout);
    return t__s.failed ? 1 : 0;
}
#endif
