/* SPDX-License-Identifier: Apache-2.0 */
/* Deterministic hashing (XXH3-64 from libxxhash) and sampling helpers.
 * Every random number in the project is a hash of stable identities. */
#include "core/core.h"

#include <stdlib.h>
#include <xxhash.h>

uint64_t lie_hash_bytes(const void *data, size_t size, uint64_t seed)
{
    return XXH3_64bits_withSeed(data, size, seed);
}

uint64_t lie_hash_u64x4(uint64_t a, uint64_t b, uint64_t c, uint64_t d)
{
    uint64_t v[4] = {a, b, c, d};
    return XXH3_64bits(v, sizeof v);
}

struct lie_hasher {
    XXH3_state_t *st;
};

lie_hasher *lie_hasher_create(uint64_t seed)
{
    lie_hasher *h = malloc(sizeof *h);
    if (!h)
        return NULL;
    h->st = XXH3_createState();
    if (!h->st) {
        free(h);
        return NULL;
    }
    XXH3_64bits_reset_withSeed(h->st, seed);
    return h;
}

void lie_hasher_update(lie_hasher *h, const void *data, size_t size)
{
    if (size)
        XXH3_64bits_update(h->st, data, size);
}

uint64_t lie_hasher_digest(const lie_hasher *h) { return XXH3_64bits_digest(h->st); }

void lie_hasher_destroy(lie_hasher *h)
{
    if (!h)
        return;
    XXH3_freeState(h->st);
    free(h);
}

void lie_sample_triangle(float u1, float u2, float *b1, float *b2)
{
    /* pbrt's UniformSampleTriangle: area-uniform, strata stay contiguous. */
    float su = sqrtf(u1);
    *b1 = su * (1.0f - u2);
    *b2 = su * u2;
}
