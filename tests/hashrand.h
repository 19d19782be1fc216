/* hashrand.h - deterministic "random" numbers for tests and benches (C and C++): a pure function
   of an index and a stream number (splitmix64), so every run, compiler and platform sees the same
   values and no rand() state is shared. */
#ifndef TESTS_HASHRAND_H
#define TESTS_HASHRAND_H
#include <math.h>
#include <stdint.h>

static inline uint64_t splitmix64(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/* uniform in [0, 1) with 53 random bits; streams 0..15 are independent for the same index */
static inline double unit_random(uint64_t i, uint64_t stream)
{
    return (double)(splitmix64(i * 16 + stream) >> 11) * (1.0 / 9007199254740992.0);
}

/* a unit vector uniform on the sphere, from streams `stream` and `stream + 1` */
static inline void random_direction(uint64_t i, uint64_t stream, float d[3])
{
    double z = 2.0 * unit_random(i, stream) - 1.0, phi = 6.283185307179586 * unit_random(i, stream + 1);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = (float)(s * cos(phi));
    d[1] = (float)(s * sin(phi));
    d[2] = (float)z;
}
#endif
