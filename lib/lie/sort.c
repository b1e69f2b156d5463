/* SPDX-License-Identifier: Apache-2.0 */
/* Sorting blocker and candidate lists (lib/lie/internal.h). */
#include "lie/internal.h"

#include <stdlib.h>
#include <string.h>

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

size_t lie_sort_unique(uint32_t *v, size_t n)
{
    if (n < 2)
        return n;
    if (n <= 32) { /* the usual blocker list: insertion sort beats qsort's calls */
        for (size_t i = 1; i < n; i++) {
            uint32_t x = v[i];
            size_t j = i;
            for (; j > 0 && v[j - 1] > x; j--)
                v[j] = v[j - 1];
            v[j] = x;
        }
    } else {
        /* candidate lists run to thousands: byte-wise radix passes,
         * skipping a byte every key shares (the top ones, mostly) */
        uint32_t *tmp = malloc(n * sizeof *tmp);
        if (!tmp) {
            qsort(v, n, sizeof *v, cmp_u32);
        } else {
            uint32_t *src = v, *dst = tmp;
            for (int shift = 0; shift < 32; shift += 8) {
                size_t count[257] = {0};
                for (size_t i = 0; i < n; i++)
                    count[((src[i] >> shift) & 0xFFu) + 1]++;
                if (count[((src[0] >> shift) & 0xFFu) + 1] == n)
                    continue; /* one bucket: already in order by this byte */
                for (int b = 0; b < 256; b++)
                    count[b + 1] += count[b];
                for (size_t i = 0; i < n; i++)
                    dst[count[(src[i] >> shift) & 0xFFu]++] = src[i];
                uint32_t *x = src;
                src = dst;
                dst = x;
            }
            if (src != v)
                memcpy(v, src, n * sizeof *v);
            free(tmp);
        }
    }
    size_t m = 1;
    for (size_t i = 1; i < n; i++)
        if (v[i] != v[m - 1])
            v[m++] = v[i];
    return m;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

void lie_sort_u64(uint64_t *v, size_t n)
{
    qsort(v, n, sizeof *v, cmp_u64);
}
