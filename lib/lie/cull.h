/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/lie: shaft culling (§4.1.2; lib/lie/cull.c). */
#ifndef LIE_CULL_H
#define LIE_CULL_H

#include "lie/internal.h"

/* Candidates for the triangles meeting the convex hull of hull[0..nh)
 * (grown by tol when tol > 0) into w->cand, sorted and unique. */
void lie_cull_candidates(const build_ctx *c, worker *w, const lie_vec3 *hull, int nh, float tol);
/* The triangles entering the pair's shaft (other than the patch's own and
 * the emitter's) into w->cand, sorted and unique; returns how many. */
size_t lie_cull_shaft(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e);
/* The leaf list of a sampled pair, exact: the triangles entering the
 * pair's shaft (as lie_cull_shaft, contact not counting), a non-planar
 * emitter's own among them, into w->hits (sorted, unique); counted up to
 * limit + 1 (more: the list is incomplete, only its length > limit means
 * anything).  Returns how many. */
size_t lie_cull_exact(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                      size_t limit);
/* Whether no triangle enters the pair's shaft (lie_cull_shaft finds none):
 * the pair is visible, proven; stops at the first that does. */
int lie_cull_shaft_empty(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e);
/* Add to w->hits every triangle meeting the shaft of an instance already
 * there, until it holds more than limit (its triangles stamped with
 * w->stamp_id, as lie_sample_pair leaves them). */
void lie_cull_expand(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                     size_t limit);
/* Conservative mode: every triangle meeting the pair's hull into w->hits
 * (among parent[0..n_parent) when parent is not NULL).  The search stops
 * once the list holds more than `limit` triangles (SIZE_MAX: never); the
 * list is then incomplete and only its length (> limit) means anything. */
lie_class lie_cull_conservative(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided,
                                int e, const uint32_t *parent, size_t n_parent, size_t limit,
                                size_t *n_list);
/* Whether the pair is occluded, proven: the triangles of list[0..n_list)
 * lying in one plane that separates the patch from the emitter cover
 * every segment between them (lib/lie/cull.c). */
int lie_cull_occlusion_proven(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                              const uint32_t *list, size_t n_list);

#endif
