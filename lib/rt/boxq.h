/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/rt: a bounding-volume hierarchy over the triangles'
 * bounding boxes, for box queries (lib/rt/boxq.c). */
#ifndef LIE_RT_BOXQ_H
#define LIE_RT_BOXQ_H

#include "rt/rt.h"

typedef struct lie_boxq lie_boxq;

/* Over the n triangles tri_p[3 i .. 3 i + 2]. */
lie_status lie_boxq_build(const lie_vec3 *tri_p, uint32_t n, lie_boxq **out);
/* fn(ctx, tri) for every triangle whose bounding box overlaps `box`
 * (boundaries included), each once, in no stated order. */
void lie_boxq_query(const lie_boxq *q, lie_box3 box, lie_rt_box_fn fn, void *ctx);
void lie_boxq_destroy(lie_boxq *q);

#endif
