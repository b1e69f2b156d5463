/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/lie: the update memo (lib/lie/memo.c). */
#ifndef LIE_MEMO_H
#define LIE_MEMO_H

#include "lie/internal.h"

/* A recomputed pair, waiting for build_node to take it. */
#define MEMO_NO_OLD UINT32_MAX

typedef struct memo_entry {
    uint32_t old;         /* the old node, or MEMO_NO_OLD for a node new in this update */
    uint32_t tri;
    lie_patch_path path;
    int e;
    lie_class cls;
    uint32_t quality;
    uint32_t n_list;
    uint32_t *list;
} memo_entry;


/* The memo entry of a node new in this update (no old node), or -1. */
int32_t lie_memo_find_new(const build_ctx *c, uint32_t tri, lie_patch_path path, int e);
/* Compute, in parallel, every node of an update that build_node will
 * compute (flagged old nodes and units built afresh); *n_memo gets how many
 * entries to free with lie_memo_free, also on failure. */
lie_status lie_memo_precompute(build_ctx *c, int threads, size_t *n_memo);
void lie_memo_free(build_ctx *c, size_t n);

#endif
