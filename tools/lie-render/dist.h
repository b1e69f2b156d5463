/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render under mpirun (tools/lie-render/dist.c). */
#ifndef LIE_RENDER_DIST_H
#define LIE_RENDER_DIST_H

#include "dist/dist.h"
#include "lie.h"

/* Writes frame `frame`; *bytes (may be NULL) gets the size written. */
typedef lie_status (*render_write_fn)(void *ctx, int frame, const lie_camera *cam, const lie_frame *f,
                                      uint64_t *bytes, lie_error *err);

/* Render frames[0 .. n_frames - 1] (the path's frames, or 0: the one
 * camera's) across the ranks.  A frame of a path handed out whole is
 * encoded and written with write() by the rank that rendered it, which
 * sends rank 0 its statistics and the bytes written; the last frames (or a
 * lone frame) go out as ranges of tiles, which rank 0 assembles and
 * writes.  Rank 0 hands out the items in frame order and checks every
 * result.  Sums of the render statistics are every rank's; the seconds
 * spent writing are rank 0's own. */
lie_status render_dist(const lie_scene *s, const lie_rt *rt, const lie_render_options *ro,
                       const lie_camera_path *path, const lie_camera *cam, const int *frames, int n_frames,
                       render_write_fn write, void *write_ctx,
                       lie_render_stats *rs, double *t_write, lie_error *err);

/* Rank 0: per-rank statistics of the last render_dist, JSON members
 * (,"ranks":[...],"bytes_broadcast":N,...,"written":[{"rank":0,"frames":F,
 * "bytes":B},...]) or human lines; nothing without mpirun. */
void render_dist_stats(FILE *fp, int json);

#endif
