/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render under mpirun: frames cut into items handed out dynamically
 * (lib/dist).  A camera path is shared out by whole frames while at least
 * as many frames remain as ranks, and each rank encodes and writes the
 * whole frames it rendered (rank 0's EXR encoding was the first limit of a
 * path's throughput: docs/mpi.md); the last frames, or a lone frame, go
 * out as ranges of tiles, so the tail balances, and rank 0 assembles and
 * writes those.  A pixel depends on its own rays only (lib/shade/render.c)
 * and a file on its frame and options only, so any split gives one
 * process's bytes. */
#include "dist.h"

#include <stdlib.h>
#include <string.h>

typedef struct item {
    int frame;             /* index into job.list */
    uint32_t first, count; /* tiles */
    int32_t chunk_first, chunk_count; /* a band of rows: the EXR chunks compressed where rendered (count 0: floats) */
} item;

typedef struct job {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_render_options *ro;
    const lie_camera_path *path;
    const lie_camera *cam;
    const int *list;        /* the frames to render (path frame indices) */
    item *items;
    size_t n_items;
    size_t n_tiles;
    lie_frame *scratch;     /* this rank's: tiles are rendered here, then packed */
    lie_frame **frames;     /* rank 0: frames being assembled */
    lie_exr_chunk **chunks; /* rank 0: their chunks compressed by the ranks (bands) */
    size_t *missing;        /* rank 0: tiles still to come per frame */
    const render_out *out;
    int n_chunks;           /* per frame, when items are bands */
    lie_render_stats rs;
    double t_write;
    lie_status setup;       /* this rank could not set up: its items fail with setup_err */
    lie_error setup_err;
    uint64_t *written;      /* rank 0: per rank, frames and bytes written (2 per rank) */
    uint64_t chunks_in;     /* rank 0: EXR chunks taken from bands */
} job;

/* What a rank sends for an item: its statistics, then the tiles' floats,
 * or nothing more when it wrote the whole frame itself. */
typedef struct item_head {
    lie_render_stats fs;
    uint64_t bytes_written; /* the frame's file, when written */
    uint32_t written;       /* 1: this rank wrote the frame */
    uint32_t pad;
} item_head;

static int last_frames;         /* of the last render_dist */
static uint64_t last_chunks;    /* EXR chunks it gathered compressed (bands) */
static uint64_t *last_written;  /* rank 0: its job's written (2 per rank) */

static int whole(const job *j, const item *it) { return it->first == 0 && it->count == j->n_tiles; }

static lie_camera frame_camera(const job *j, int f)
{
    return j->path ? lie_camera_path_frame(j->path, f) : *j->cam;
}

/* The float arrays of a frame, with their channels per pixel. */
static int frame_arrays(const lie_frame *f, float **arr, int *ch, int cap)
{
    int n = 0;
    arr[n] = f->rgb;
    ch[n++] = 3;
    for (int a = 0; a < f->n_aovs && n < cap; a++) {
        arr[n] = f->aovs[a].data;
        ch[n++] = f->aovs[a].n_channels;
    }
    return n;
}

/* Copy tiles [first, first + count) between a frame and a packed buffer
 * (array by array, tile by tile, row by row). */
static void copy_tiles(lie_frame *f, uint32_t first, uint32_t count, float *buf, int to_buf)
{
    float *arr[16];
    int ch[16];
    int n = frame_arrays(f, arr, ch, 16);
    int tiles_x = (f->width + LIE_TILE - 1) / LIE_TILE;
    size_t k = 0;
    for (int a = 0; a < n; a++)
        for (uint32_t t = first; t < first + count; t++) {
            int x0 = (int)(t % (uint32_t)tiles_x) * LIE_TILE, y0 = (int)(t / (uint32_t)tiles_x) * LIE_TILE;
            int x1 = x0 + LIE_TILE < f->width ? x0 + LIE_TILE : f->width;
            int y1 = y0 + LIE_TILE < f->height ? y0 + LIE_TILE : f->height;
            size_t row = (size_t)(x1 - x0) * (size_t)ch[a];
            for (int y = y0; y < y1; y++) {
                float *px = arr[a] + ((size_t)y * (size_t)f->width + (size_t)x0) * (size_t)ch[a];
                if (to_buf)
                    memcpy(buf + k, px, row * sizeof *px);
                else
                    memcpy(px, buf + k, row * sizeof *px);
                k += row;
            }
        }
}

static size_t packed_floats(const lie_frame *f, uint32_t first, uint32_t count)
{
    float *arr[16];
    int ch[16];
    int n = frame_arrays(f, arr, ch, 16), per_px = 0;
    for (int a = 0; a < n; a++)
        per_px += ch[a];
    int tiles_x = (f->width + LIE_TILE - 1) / LIE_TILE;
    size_t px = 0;
    for (uint32_t t = first; t < first + count; t++) {
        int x0 = (int)(t % (uint32_t)tiles_x) * LIE_TILE, y0 = (int)(t / (uint32_t)tiles_x) * LIE_TILE;
        int w = f->width - x0 < LIE_TILE ? f->width - x0 : LIE_TILE;
        int h = f->height - y0 < LIE_TILE ? f->height - y0 : LIE_TILE;
        px += (size_t)w * (size_t)h;
    }
    return px * (size_t)per_px;
}

/* A band of rows: its EXR chunks compressed here, sent as their sizes
 * and bytes (a third to a half of the floats for zip). */
static lie_status run_band(job *j, const item *it, const item_head *h, lie_dist_buf *out, lie_error *err)
{
    int n = it->chunk_count;
    lie_exr_chunk *ch = calloc((size_t)n, sizeof *ch);
    if (!ch)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    double t0 = lie_time_now();
    lie_status st = j->out->encode(j->out->ctx, j->scratch, it->chunk_first, n, ch, err);
    j->t_write += lie_time_now() - t0;
    size_t at = out->size + sizeof *h; /* the sizes, filled in as the bytes go in (out may move) */
    if (st == LIE_OK &&
        (!lie_dist_buf_add(out, h, sizeof *h) || !lie_dist_buf_add(out, NULL, sizeof(uint64_t) * (size_t)n)))
        st = lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    for (int k = 0; st == LIE_OK && k < n; k++) {
        uint64_t size = ch[k].size;
        memcpy(out->data + at + sizeof size * (size_t)k, &size, sizeof size);
        if (!lie_dist_buf_add(out, ch[k].data, (size_t)size))
            st = lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    }
    for (int k = 0; k < n; k++)
        free(ch[k].data);
    free(ch);
    return st;
}

static lie_status run(void *ctx, size_t i, lie_dist_buf *out, lie_error *err)
{
    job *j = ctx;
    if (j->setup != LIE_OK) {
        *err = j->setup_err;
        return j->setup;
    }
    const item *it = &j->items[i];
    lie_camera cam = frame_camera(j, j->list[it->frame]);
    item_head h;
    memset(&h, 0, sizeof h);
    lie_status st = lie_render_tiles(j->s, j->rt, &cam, j->ro, j->scratch, it->first, it->count, &h.fs, err);
    if (st != LIE_OK)
        return st;
    if (j->path && whole(j, it)) {
        /* a whole frame of a path: written here, rank 0 only hears of it */
        double t0 = lie_time_now();
        st = j->out->write(j->out->ctx, j->list[it->frame], &cam, j->scratch, NULL, &h.bytes_written, err);
        j->t_write += lie_time_now() - t0;
        if (st != LIE_OK)
            return st;
        h.written = 1;
        return lie_dist_buf_add(out, &h, sizeof h) ? LIE_OK : lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    }
    if (it->chunk_count > 0)
        return run_band(j, it, &h, out, err);
    size_t n = packed_floats(j->scratch, it->first, it->count);
    if (!lie_dist_buf_add(out, &h, sizeof h))
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    float *dst = lie_dist_buf_add(out, NULL, n * sizeof(float));
    if (!dst)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    copy_tiles(j->scratch, it->first, it->count, dst, 1);
    return LIE_OK;
}

/* A band's chunks, checked against the item and kept for the frame's
 * write. */
static lie_status take_band(job *j, const item *it, int rank, const unsigned char *data, size_t size,
                            lie_error *err)
{
    size_t n = (size_t)it->chunk_count, need = sizeof(uint64_t) * n;
    lie_exr_chunk **cs = &j->chunks[it->frame];
    if (!*cs && !(*cs = calloc((size_t)j->n_chunks, sizeof **cs)))
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    for (size_t k = 0; k < n && need <= size; k++) {
        uint64_t c;
        memcpy(&c, data + sizeof c * k, sizeof c);
        need = c <= size ? need + (size_t)c : SIZE_MAX;
    }
    if (need != size)
        return lie_error_set(err, LIE_ERR_FORMAT, NULL, "rank %d sent %zu bytes for the chunks of rows %u..%u of "
                             "frame %d, which do not add up", rank, size, it->first, it->first + it->count, it->frame);
    const unsigned char *q = data + sizeof(uint64_t) * n;
    for (size_t k = 0; k < n; k++) {
        lie_exr_chunk *c = &(*cs)[it->chunk_first + (int)k];
        memcpy(&c->size, data + sizeof c->size * k, sizeof c->size);
        if (!(c->data = malloc((size_t)c->size + 1)))
            return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
        memcpy(c->data, q, (size_t)c->size);
        q += c->size;
        j->chunks_in++;
    }
    return LIE_OK;
}

static void free_chunks(job *j, int frame)
{
    for (int k = 0; j->chunks[frame] && k < j->n_chunks; k++)
        free(j->chunks[frame][k].data);
    free(j->chunks[frame]);
    j->chunks[frame] = NULL;
}

/* An item's tiles are in: once its frame has all of them, write it. */
static lie_status frame_done(job *j, const item *it, lie_error *err)
{
    j->missing[it->frame] -= it->count;
    if (j->missing[it->frame])
        return LIE_OK;
    lie_frame **f = &j->frames[it->frame];
    double t0 = lie_time_now();
    lie_camera cam = frame_camera(j, j->list[it->frame]);
    uint64_t bytes = 0;
    lie_status st = j->out->write(j->out->ctx, j->list[it->frame], &cam, *f, j->chunks[it->frame], &bytes, err);
    j->t_write += lie_time_now() - t0;
    j->written[0]++;
    j->written[1] += bytes;
    lie_frame_destroy(*f);
    *f = NULL;
    free_chunks(j, it->frame);
    return st;
}

static lie_status take(void *ctx, size_t i, int rank, const unsigned char *data, size_t size, lie_error *err)
{
    job *j = ctx;
    if (j->setup != LIE_OK) {
        *err = j->setup_err;
        return j->setup;
    }
    const item *it = &j->items[i];
    item_head h;
    if (size < sizeof h)
        return lie_error_set(err, LIE_ERR_FORMAT, NULL, "rank %d sent %zu bytes for frame %d", rank, size, it->frame);
    memcpy(&h, data, sizeof h);
    if (h.written) {
        /* the check: a whole frame of a path, reported written once */
        if (!j->path || !whole(j, it) || size != sizeof h)
            return lie_error_set(err, LIE_ERR_FORMAT, NULL, "rank %d reports frame %d written, which it was not given whole",
                                 rank, it->frame);
        lie_render_stats_add(&j->rs, &h.fs);
        j->written[2 * rank]++;
        j->written[2 * rank + 1] += h.bytes_written;
        return LIE_OK;
    }
    lie_frame **f = &j->frames[it->frame];
    if (!*f) {
        lie_status st = lie_render_frame_create(j->s, j->ro, f, err);
        if (st != LIE_OK)
            return st;
        j->missing[it->frame] = j->n_tiles;
    }
    if (it->chunk_count > 0) {
        lie_status st = take_band(j, it, rank, data + sizeof h, size - sizeof h, err);
        if (st != LIE_OK)
            return st;
        lie_render_stats_add(&j->rs, &h.fs);
        return frame_done(j, it, err);
    }
    size_t n = packed_floats(*f, it->first, it->count);
    if (size != sizeof h + n * sizeof(float))
        return lie_error_set(err, LIE_ERR_FORMAT, NULL, "rank %d sent %zu bytes for tiles %u..%u of frame %d, "
                             "expected %zu", rank, size, it->first, it->first + it->count, it->frame,
                             sizeof h + n * sizeof(float));
    lie_render_stats_add(&j->rs, &h.fs);
    /* the floats may be unaligned in the message: copy through */
    float *tmp = malloc(n * sizeof(float) + 1);
    if (!tmp)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    memcpy(tmp, data + sizeof h, n * sizeof(float));
    copy_tiles(*f, it->first, it->count, tmp, 0);
    free(tmp);
    return frame_done(j, it, err);
}

static uint64_t units(void *ctx, size_t i)
{
    const job *j = ctx;
    return j->items ? j->items[i].count : 0;
}

/* Whole frames while at least as many remain as ranks; the rest (the
 * last ranks - 1 frames, or all of fewer frames than ranks) in pieces,
 * about 8 per rank over those frames together: bands of tile rows for EXR
 * output while the frames have two bands per rank or more (the rank that
 * renders a band compresses its chunks: a band is a whole number of
 * chunks, a row of tiles holding 1 or 16 chunks' scanlines and 32-line
 * chunks taking two rows), else ranges of tiles. */
static size_t plan_whole(int n_frames, int ranks)
{
    return n_frames >= ranks ? (size_t)(n_frames - (ranks - 1)) : 0;
}

/* Pieces per frame of the `pieced` frames cut up. */
static size_t plan_pieces(size_t pieced, int ranks)
{
    size_t want = 8 * (size_t)ranks;
    return pieced ? (want + pieced - 1) / pieced : 1;
}

/* Tile rows per band item, or 0: ranges of tiles.
 *
 * Bands cost render parallelism when there are fewer than ranks, and save
 * rank 0 the compression.  With a frame's render time T_r on one core, its
 * compression w T_r, C threads a rank, m = min(bands, ranks) and c the
 * threads a band's chunks can use (its chunks, at most C), the pieces of
 * a frame take about T_r (1/(C m) + w/(c m)) in bands and T_r (1/(C N) +
 * w/C) in tile ranges (rank 0 compressing).  Measured on a 512x512
 * museum1 frame, w is 0.2 for zip (taken for zips and piz too) and 0.05 for
 * rle; 0 without compression.  Bands are used where that says they are
 * faster and there are two or more per rank, or at least 4 bands all told
 * (a lone frame on many ranks: half of them idle, the frame still sooner). */
static int band_rows(const job *j, size_t pieced, int ranks)
{
    int lines = j->out->chunk_lines, tiles_y = (j->ro->height + LIE_TILE - 1) / LIE_TILE;
    if (lines <= 0 || !j->out->encode || !pieced)
        return 0;
    /* tile rows a chunk spans; a band holds whole chunks */
    int unit = lines > LIE_TILE ? (lines + LIE_TILE - 1) / LIE_TILE : 1;
    if ((unit * LIE_TILE) % lines != 0)
        return 0;
    size_t per_frame = (size_t)((tiles_y + unit - 1) / unit), bands = per_frame * pieced;
    if (bands < 2 * (size_t)ranks) {
        double w = j->out->w, threads = j->ro->threads > 0 ? j->ro->threads : lie_cpu_count();
        double m = (double)(bands < (size_t)ranks ? bands : (size_t)ranks), c = unit * LIE_TILE / lines;
        c = c < threads ? c : threads;
        if (bands < 4 || 1.0 / (threads * m) + w / (c * m) >= 1.0 / (threads * ranks) + w / threads)
            return 0;
    }
    size_t per = per_frame / plan_pieces(pieced, ranks);
    return (int)(per < 1 ? 1 : per) * unit;
}

static size_t plan(job *j, int n_frames, int ranks)
{
    size_t whole = plan_whole(n_frames, ranks), pieced = (size_t)n_frames - whole;
    size_t chunk = j->n_tiles / plan_pieces(pieced, ranks);
    if (chunk < 1)
        chunk = 1;
    int rows = band_rows(j, pieced, ranks), tiles_x = (j->ro->width + LIE_TILE - 1) / LIE_TILE;
    int tiles_y = (j->ro->height + LIE_TILE - 1) / LIE_TILE, lines = j->out->chunk_lines;
    size_t per_frame = rows ? (size_t)((tiles_y + rows - 1) / rows) : (j->n_tiles + chunk - 1) / chunk;
    size_t n = whole + pieced * per_frame;
    j->n_chunks = rows ? (j->ro->height + lines - 1) / lines : 0;
    j->items = calloc(n + 1, sizeof *j->items);
    if (!j->items)
        return n;
    size_t k = 0;
    for (int f = 0; f < n_frames; f++) {
        if ((size_t)f < whole) {
            j->items[k++] = (item){f, 0, (uint32_t)j->n_tiles, 0, 0};
        } else if (rows) {
            for (int r = 0; r < tiles_y; r += rows) {
                int r1 = r + rows < tiles_y ? r + rows : tiles_y;
                int y0 = r * LIE_TILE, y1 = r1 * LIE_TILE < j->ro->height ? r1 * LIE_TILE : j->ro->height;
                int c0 = y0 / lines, c1 = (y1 + lines - 1) / lines;
                j->items[k++] = (item){f, (uint32_t)(r * tiles_x), (uint32_t)((r1 - r) * tiles_x), c0, c1 - c0};
            }
        } else {
            for (size_t t = 0; t < j->n_tiles; t += chunk)
                j->items[k++] = (item){f, (uint32_t)t, (uint32_t)(j->n_tiles - t < chunk ? j->n_tiles - t : chunk), 0, 0};
        }
    }
    return k;
}

lie_status render_dist(const lie_scene *s, const lie_rt *rt, const lie_render_options *ro,
                       const lie_camera_path *path, const lie_camera *cam, const int *frames, int n_frames,
                       const render_out *out, lie_render_stats *rs, double *t_write, lie_error *err)
{
    job j = {.s = s, .rt = rt, .ro = ro, .path = path, .cam = cam, .list = frames, .out = out};
    j.n_tiles = lie_render_tile_count(ro->width, ro->height);
    int ranks = lie_dist_size();
    j.n_items = plan(&j, n_frames, ranks);
    j.frames = calloc((size_t)n_frames, sizeof *j.frames);
    j.chunks = calloc((size_t)n_frames, sizeof *j.chunks);
    j.missing = calloc((size_t)n_frames, sizeof *j.missing);
    free(last_written);
    last_written = j.written = calloc(2 * (size_t)ranks, sizeof *j.written);
    /* every rank takes part in lie_dist_run, even one that failed here:
     * its items then report the failure (the count is every rank's) */
    lie_error_clear(&j.setup_err);
    if (!j.items || !j.frames || !j.chunks || !j.missing || !j.written)
        j.setup = lie_error_set(&j.setup_err, LIE_ERR_NOMEM, NULL, "out of memory");
    else
        j.setup = lie_render_frame_create(s, ro, &j.scratch, &j.setup_err);
    lie_dist_work w = {j.n_items, &j, run, take, units};
    lie_status st = lie_dist_run(&w, err);
    for (int f = 0; f < n_frames; f++) {
        lie_frame_destroy(j.frames[f]);
        if (j.chunks)
            free_chunks(&j, f);
    }
    lie_frame_destroy(j.scratch);
    free(j.frames);
    free(j.chunks);
    free(j.missing);
    free(j.items);
    *rs = j.rs;
    *t_write = j.t_write;
    last_frames = n_frames;
    last_chunks = j.chunks_in;
    return st;
}

void render_dist_stats(FILE *fp, int json)
{
    if (lie_dist_size() < 2 || last_frames < 1)
        return;
    lie_dist_stats_print(fp, "tiles", json);
    double per_frame = (double)lie_dist_bytes_gathered() / (double)last_frames;
    if (json)
        fprintf(fp, ",\"bytes_gathered_per_frame\":%.0f,\"exr_chunks_gathered\":%llu", per_frame,
                (unsigned long long)last_chunks);
    else
        fprintf(fp, "  %.0f bytes gathered per frame; %llu EXR chunks compressed by the ranks that rendered them\n",
                per_frame, (unsigned long long)last_chunks);
    for (int r = 0; last_written && r < lie_dist_size(); r++) {
        unsigned long long fr = (unsigned long long)last_written[2 * r], by = (unsigned long long)last_written[2 * r + 1];
        if (json)
            fprintf(fp, "%s{\"rank\":%d,\"frames\":%llu,\"bytes\":%llu}%s", r ? "," : ",\"written\":[", r, fr, by,
                    r + 1 < lie_dist_size() ? "" : "]");
        else
            fprintf(fp, "  rank %d wrote %llu frame%s, %llu bytes\n", r, fr, fr == 1 ? "" : "s", by);
    }
}
