/* The counter-based random numbers behind the generators. A value is a pure function of
 * (seed, index, stream), so a cloud comes out the same whatever the thread count or the order
 * in which particles are filled: there is no sequential state to share or to split. */
#include "internal.h"

/* The SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijection of 64-bit words with full
 * avalanche, so neighbouring counters give unrelated outputs. */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/* Each input goes through its own finaliser round with a distinct odd multiplier, so the
 * triples (s, i, t) and (s, t, i) do not collide and a zero seed is as good as any other. */
static uint64_t hash3(uint64_t seed, uint64_t index, uint64_t stream)
{
    uint64_t z = mix64(seed + UINT64_C(0x9e3779b97f4a7c15));
    z = mix64(z ^ (index * UINT64_C(0xd1b54a32d192ed03) + UINT64_C(0x8cb92ba72f3d8dd7)));
    return mix64(z ^ (stream * UINT64_C(0xaf251af3b0f025b5) + UINT64_C(0x632be59bd9b4e019)));
}

/* The top 52 bits j give (2j + 1) * 2^-52 - 1: every value is exact, the set of values is
 * symmetric about 0 (mean exactly 0 over the full range), and +-1 are never returned. */
double pst_rng_symmetric(uint64_t seed, uint64_t index, uint64_t stream)
{
    uint64_t j = hash3(seed, index, stream) >> 12;
    return (double)(2 * j + 1) * 0x1p-52 - 1.0;
}
