/* SPDX-License-Identifier: Apache-2.0 */
/* cache-poke: damage caches on purpose, for the hardening tests.
 *
 *   cache-poke sections CACHE
 *       one line per region: NAME OFFSET SIZE, for the header, the section
 *       table, every section in the table (as far as it lies inside the file)
 *       and the file checksum; no validation beyond staying in bounds.
 *   cache-poke edit IN OUT [--reseal] OP...
 *       apply each OP to the bytes of IN and write OUT:
 *         flip:OFFSET:BIT     invert one bit
 *         set32:OFFSET:VALUE  store a little-endian u32
 *         set64:OFFSET:VALUE  store a little-endian u64
 *         truncate:SIZE       keep the first SIZE bytes
 *       --reseal then recomputes every section checksum (of sections that
 *       lie inside the file) and the file checksum, so that the damage gets
 *       past the checksums to the checks behind them.
 * Exit 0, or 2 on a usage or I/O error. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"

static uint64_t get(const unsigned char *p, int n)
{
    uint64_t v = 0;
    for (int k = n - 1; k >= 0; k--)
        v = (v << 8) | p[k];
    return v;
}

static void put(unsigned char *p, uint64_t v, int n)
{
    for (int k = 0; k < n; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}

static int bad(const char *what)
{
    fprintf(stderr, "cache-poke: %s\n", what);
    return 2;
}

static void reseal(unsigned char *b, size_t size)
{
    if (size < 40)
        return;
    uint64_t n = get(b + 20, 4);
    for (uint64_t i = 0; i < n && 32 + 32 * (i + 1) <= size - 8; i++) {
        unsigned char *t = b + 32 + 32 * i;
        uint64_t off = get(t + 8, 8), sz = get(t + 16, 8);
        if (off <= size && sz <= size - off)
            put(t + 24, lie_hash_bytes(b + off, (size_t)sz, 0), 8);
    }
    put(b + size - 8, lie_hash_bytes(b, size - 8, 0), 8);
}

int main(int argc, char **argv)
{
    if (argc < 3)
        return bad("usage: cache-poke sections CACHE | cache-poke edit IN OUT [--reseal] OP...");
    unsigned char *b = NULL;
    size_t size = 0;
    lie_error err;
    if (lie_read_file(argv[2], &b, &size, &err) != LIE_OK)
        return bad("cannot read the input");
    if (strcmp(argv[1], "sections") == 0) {
        if (size < 40)
            return bad("too short");
        uint64_t n = get(b + 20, 4);
        printf("HEADER 0 32\nTABLE 32 %" PRIu64 "\n", 32 * n);
        for (uint64_t i = 0; i < n && 32 + 32 * (i + 1) <= size - 8; i++) {
            const unsigned char *t = b + 32 + 32 * i;
            char id[5];
            for (int k = 0; k < 4; k++)
                id[k] = t[k] >= 'A' && t[k] <= 'Z' ? (char)t[k] : '?';
            id[4] = 0;
            printf("%s %" PRIu64 " %" PRIu64 "\n", id, get(t + 8, 8), get(t + 16, 8));
        }
        printf("CHECKSUM %zu 8\n", size - 8);
        free(b);
        return 0;
    }
    if (strcmp(argv[1], "edit") != 0 || argc < 4)
        return bad("unknown command");
    int resealing = 0;
    for (int i = 4; i < argc; i++) {
        unsigned long long off, val;
        unsigned bit;
        if (strcmp(argv[i], "--reseal") == 0) {
            resealing = 1;
        } else if (sscanf(argv[i], "flip:%llu:%u", &off, &bit) == 2 && off < size && bit < 8) {
            b[off] ^= (unsigned char)(1u << bit);
        } else if (sscanf(argv[i], "set32:%llu:%llu", &off, &val) == 2 && off + 4 <= size) {
            put(b + off, val, 4);
        } else if (sscanf(argv[i], "set64:%llu:%llu", &off, &val) == 2 && off + 8 <= size) {
            put(b + off, val, 8);
        } else if (sscanf(argv[i], "truncate:%llu", &val) == 1 && val <= size) {
            size = (size_t)val;
        } else {
            free(b);
            return bad("bad operation (or out of the file's bounds)");
        }
    }
    if (resealing)
        reseal(b, size);
    FILE *f = fopen(argv[3], "wb");
    int ok = f && fwrite(b, 1, size, f) == size;
    if (f && fclose(f) != 0)
        ok = 0;
    free(b);
    return ok ? 0 : bad("cannot write the output");
}
