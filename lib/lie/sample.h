/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/lie: sampled blocker lists (§4.1, §4.3.2; lib/lie/sample.c). */
#ifndef LIE_SAMPLE_H
#define LIE_SAMPLE_H

#include "lie/internal.h"

/* Fill c->halton, c->n_halton: the radical inverses the segments use. */
lie_status lie_sample_tables(build_ctx *c);

/* Classify one patch-emitter pair by sampling segments.  Leaves the sorted
 * unique blocker list in w->hits[0..*n_list). */
lie_class lie_sample_pair(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path, const lie_vec3 V[3],
                          int two_sided, int e, uint32_t *quality, size_t *n_list);

#endif
