/* failalloc.h - an allocator for tests that fails exactly one call (the fail_at-th, counting from 1;
   0 = never) and counts the blocks still live, so that a test can fail every allocation of a call
   in turn and check that nothing leaks (C99 and C++). */
#ifndef TESTS_FAILALLOC_H
#define TESTS_FAILALLOC_H
#include <stdlib.h>

typedef struct fail_alloc { long calls, fail_at, live; } fail_alloc;
static inline void *fa_alloc(void *user, size_t n)
{
    fail_alloc *f = (fail_alloc *)user;
    void *p;
    if (++f->calls == f->fail_at) return NULL;
    p = malloc(n);
    if (p) f->live++;
    return p;
}
static inline void fa_free(void *user, void *p)
{
    fail_alloc *f = (fail_alloc *)user;
    if (p) { f->live--; free(p); }
}
#endif
