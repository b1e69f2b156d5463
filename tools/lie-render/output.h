/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render's frames on disk and its statistics (tools/lie-render/output.c). */
#ifndef LIE_RENDER_OUTPUT_H
#define LIE_RENDER_OUTPUT_H

#include "common/cli.h"
#include "lie.h"

/* What every frame's file is written with. */
typedef struct frame_out {
    const char *output, *input, *hash;
    const lie_render_options *ro;
    int path;
    lie_frame_options opt; /* the attributes are set per frame */
    int first; /* the number of the path's frame 0 */
    /* --exposure auto: each frame's exposure from its log-average
     * luminance (lie_frame_auto_exposure), recorded in its file; the last
     * frame written's in *last_auto */
    int exposure_auto;
    lie_auto_exposure *last_auto;
} frame_out;

/* The file of frame fi. */
void frame_name(const frame_out *o, int fi, char *name, size_t size);
/* Write frame fi (the path's frame first + fi) of camera fc to its file,
 * its header saying how it was made (docs/tools.md, lie-render); EXR chunks
 * are compressed on the render's --threads.  *bytes (may be NULL): the
 * file's size (0 for stdout). */
lie_status write_frame(void *ctx, int fi, const lie_camera *fc, const lie_frame *frame, uint64_t *bytes, lie_error *err);
/* write_frame, EXR chunk k taken from chunks[k] where its data is not NULL
 * (compressed by another rank: lie_exr_encode_chunks); chunks may be NULL. */
lie_status write_frame_chunks(void *ctx, int fi, const lie_camera *fc, const lie_frame *frame,
                              const lie_exr_chunk *chunks, uint64_t *bytes, lie_error *err);
/* Scanlines per chunk of the frames' files when they are EXR
 * (lie_exr_chunk_lines), else 0: PNG has no chunks to compress apart, nor
 * has a frame whose exposure comes from all its pixels (--exposure auto:
 * the writer needs the whole frame). */
int frame_chunk_lines(const frame_out *o);
/* The EXR compression's cost as a share of a frame's render time, for
 * sharing out a frame's pieces (tools/lie-render/dist.c). */
double frame_encode_share(const frame_out *o);
/* Compress chunks [first, first + count) of a frame's EXR as write_frame
 * would (lie_exr_encode_chunks with the run's options). */
lie_status encode_chunks(void *ctx, const lie_frame *frame, int first, int count, lie_exr_chunk *out, lie_error *err);

/* What --stats prints: times are load, bvh, render and write seconds. */
typedef struct run_stats {
    const char *input;
    int rendered, skipped;
    double t_load, t_bvh, t_render, t_write;
    const lie_auto_exposure *exposure; /* --exposure auto: the last frame's; else NULL */
} run_stats;

/* --stats (text on stderr) or --stats=json (lie_stats_json_end: stderr or --stats-file). */
lie_status print_stats(const lie_cli *cli, const run_stats *r, const lie_scene *scene, const lie_render_options *ro,
                       const lie_render_stats *rs, lie_error *err);

#endif
