/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render under mpirun (tools/lie-render/dist.c). */
#ifndef LIE_RENDER_DIST_H
#define LIE_RENDER_DIST_H

#include "dist/dist.h"
#include "lie.h"

/* Writes frame `frame`, EXR chunk k from chunks[k] where chunks is not
 * NULL and its data is; *bytes (may be NULL) gets the size written. */
typedef lie_status (*render_write_fn)(void *ctx, int frame, const lie_camera *cam, const lie_frame *f,
                                      const lie_exr_chunk *chunks, uint64_t *bytes, lie_error *err);
/* Compresses EXR chunks [first, first + count) of a frame (lie_exr_encode_chunks). */
typedef lie_status (*render_encode_fn)(void *ctx, const lie_frame *f, int first, int count, lie_exr_chunk *out,
                                       lie_error *err);

/* Where frames go: write() (and encode(), with the same ctx) and, for EXR
 * output, the scanlines per chunk (lie_exr_chunk_lines; 0: not EXR) and
 * the compression's cost as a share of a frame's render time
 * (frame_encode_share). */
typedef struct render_out {
    render_write_fn write;
    render_encode_fn encode;
    int chunk_lines;
    void *ctx;
    double w;
} render_out;

/* Render frames[0 .. n_frames - 1] (the path's frames, or 0: the one
 * camera's) across the ranks.  A frame of a path handed out whole is
 * encoded and written by the rank that rendered it, which sends rank 0 its
 * statistics and the bytes written; the last frames (or a lone frame) go
 * out in pieces, which rank 0 assembles and writes: for EXR output, bands
 * of rows whose chunks the rank that rendered them compresses, when there
 * are enough bands (dist.c, band_rows); otherwise ranges of tiles, sent as
 * floats.  Rank 0 hands out the items in frame order and checks every
 * result.  Sums of the render statistics are every rank's; the seconds
 * spent writing (and compressing chunks) are rank 0's own. */
lie_status render_dist(const lie_scene *s, const lie_rt *rt, const lie_render_options *ro,
                       const lie_camera_path *path, const lie_camera *cam, const int *frames, int n_frames,
                       const render_out *out, lie_render_stats *rs, double *t_write, lie_error *err);

/* Rank 0: per-rank statistics of the last render_dist, JSON members
 * (,"ranks":[...],"bytes_broadcast":N,...,"written":[{"rank":0,"frames":F,
 * "bytes":B},...]) or human lines; nothing without mpirun. */
void render_dist_stats(FILE *fp, int json);

#endif
