/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/lie: the patch tree of one unit (§4.1.1; lib/lie/subdiv.c). */
#ifndef LIE_SUBDIV_H
#define LIE_SUBDIV_H

#include "lie/internal.h"

/* A patch large enough to split (§4.1.1). */
int lie_subdiv_may_split(const build_ctx *c, uint32_t tri, lie_patch_path path);
/* Whether a node of class cls with this list splits. */
int lie_subdiv_splits(const build_ctx *c, uint32_t tri, lie_patch_path path, int e, lie_class cls,
                      const uint32_t *list, size_t n_list);
/* Whether the cost model decides units and splits by pixels: a build for
 * views (c->pix), or a whole build's estimate (c->whole_area). */
int lie_subdiv_modelled(const build_ctx *c);
/* The pixels per frame that see patch `path` of tri: the views' hits, or
 * a whole build's estimate by area (lie_whole_pixels); 0 without a model. */
double lie_subdiv_pixels(const build_ctx *c, uint32_t tri, lie_patch_path path);
/* With the model (lie_subdiv_modelled): whether a node that
 * lie_subdiv_splits lets split is seen by enough pixels for the split to
 * pay (§4.3.3, the cost model). */
int lie_subdiv_pixels_pay(const build_ctx *c, uint32_t tri, lie_patch_path path, lie_class cls, size_t n_list,
                          uint32_t quality);
/* Whether the views see triangle tri (always, in a build without views). */
int lie_subdiv_seen(const build_ctx *c, uint32_t tri);
/* lie_parallel_for body: build (or copy) every unit of triangle `item`
 * into c->out[item]. */
void lie_subdiv_triangle(void *ctx, size_t item, int worker_id);

#endif
