/* SPDX-License-Identifier: Apache-2.0 */
/* OpenEXR through OpenEXRCore's C API: the file is assembled in memory by
 * a custom stream (so the output can be written atomically, or to stdout)
 * and read back from memory the same way.
 * Size: one job, EXR through OpenEXRCore, in one file: the writer and the
 * reader share the stream callbacks and the attribute tables. */
#include "image/image.h"

#include <OpenEXR/openexr.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* zlib level for ZIP chunks, fixed here rather than taken from the
 * library's global default so the bytes depend on the input only. */
#define EXR_ZIP_LEVEL 4
/* Readers refuse images beyond these before allocating anything. */
#define EXR_MAX_DIM (1 << 16)
#define EXR_MAX_PIXELS ((int64_t)1 << 28)
/* Channel names are "<layer>.<channel>"; OpenEXR's limit without the
 * long-names flag is 31 bytes. */
#define EXR_SHORT_NAME_MAX 31
#define EXR_NAME_SIZE (sizeof(((lie_aov *)0)->name) + sizeof(((lie_aov *)0)->channel[0]) + 1)

/* The stream behind a context: a growable buffer for writing or a whole
 * file for reading, plus the first error message the library reported
 * (the handler keeps it instead of printing). */
typedef struct exr_stream {
    unsigned char *data;
    size_t size, cap;
    char msg[256];
} exr_stream;

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    if (exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud)
        return;
    exr_stream *s = ud;
    /* chunks are compressed on worker threads: the first message wins */
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    pthread_mutex_lock(&lock);
    if (!s->msg[0]) {
        snprintf(s->msg, sizeof s->msg, "%s", msg ? msg : exr_get_error_code_as_string(code));
        for (char *p = s->msg; *p; p++)
            if (*p == '\n' || *p == '\r')
                *p = ' ';
    }
    pthread_mutex_unlock(&lock);
}

/* pwrite() semantics: chunks may arrive past the end (the offset table is
 * filled in last), so gaps are zeroed. */
static int64_t stream_write(exr_const_context_t ctxt, void *ud, const void *buf, uint64_t sz,
                            uint64_t off, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = ud;
    if (off > SIZE_MAX / 2 || sz > SIZE_MAX / 2 - off || sz > INT64_MAX) {
        error_cb(ctxt, EXR_ERR_WRITE_IO, "write beyond addressable memory");
        return -1;
    }
    size_t end = (size_t)(off + sz);
    if (!LIE_GROW(s->data, s->cap, end)) {
        error_cb(ctxt, EXR_ERR_OUT_OF_MEMORY, "out of memory");
        return -1;
    }
    if (off > s->size)
        memset(s->data + s->size, 0, (size_t)off - s->size);
    memcpy(s->data + off, buf, (size_t)sz);
    if (end > s->size)
        s->size = end;
    return (int64_t)sz;
}

/* pread() semantics: a short count at the end; the library reports it. */
static int64_t stream_read(exr_const_context_t ctxt, void *ud, void *buf, uint64_t sz,
                           uint64_t off, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = ud;
    if (off >= s->size)
        return 0;
    size_t n = s->size - (size_t)off;
    if (sz < n)
        n = (size_t)sz;
    memcpy(buf, s->data + off, n);
    return (int64_t)n;
}

static int64_t stream_size(exr_const_context_t ctxt, void *ud)
{
    exr_stream *s = ud;
    return s->size > INT64_MAX ? -1 : (int64_t)s->size;
}

/* Turn a failed OpenEXR call into a lie_error: the library's own message
 * when it gave one, else its code's name. */
static lie_status exr_fail(lie_error *err, lie_status status, const char *path,
                           const exr_stream *s, exr_result_t rv, const char *what)
{
    if (rv == EXR_ERR_OUT_OF_MEMORY)
        status = LIE_ERR_NOMEM;
    return lie_error_set(err, status, path, "%s: %s", what,
                         s->msg[0] ? s->msg : exr_get_error_code_as_string(rv));
}

/* ---- writing ----------------------------------------------------------- */

/* One output channel: its full name and where its samples live. */
typedef struct exr_out_channel {
    char name[EXR_NAME_SIZE];
    const float *base; /* sample of pixel (0, 0) */
    int stride;        /* floats between pixels */
    int half;          /* stored as 16-bit half (converted by the encoder) */
} exr_out_channel;

/* Collect RGB and every AOV channel, rejecting duplicate names (the EXR
 * channel list is a set). */
static lie_status collect_channels(const lie_frame *f, int half, exr_out_channel **out, int *n_out,
                                   const char *path, lie_error *err)
{
    int n = 3;
    for (int a = 0; a < f->n_aovs; a++) {
        const lie_aov *aov = &f->aovs[a];
        if (aov->n_channels < 1 || aov->n_channels > LIE_AOV_MAX_CHANNELS || !aov->data)
            return lie_error_set(err, LIE_ERR_ARG, path, "AOV '%.31s' has no channels", aov->name);
        n += aov->n_channels;
    }
    exr_out_channel *ch = calloc((size_t)n, sizeof *ch);
    if (!ch)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    static const char *const rgb_names[3] = {"R", "G", "B"};
    int k = 0;
    for (int c = 0; c < 3; c++, k++) {
        snprintf(ch[k].name, sizeof ch[k].name, "%s", rgb_names[c]);
        ch[k].base = f->rgb + c;
        ch[k].stride = 3;
        ch[k].half = half != 0;
    }
    for (int a = 0; a < f->n_aovs; a++) {
        const lie_aov *aov = &f->aovs[a];
        for (int c = 0; c < aov->n_channels; c++, k++) {
            /* An AOV with an empty name is OpenEXR's default layer. */
            snprintf(ch[k].name, sizeof ch[k].name, "%.31s%s%.7s", aov->name,
                     aov->name[0] ? "." : "", aov->channel[c]);
            ch[k].base = aov->data + c;
            ch[k].stride = aov->n_channels;
        }
    }
    lie_status st = LIE_OK;
    for (int i = 0; i < n && st == LIE_OK; i++) {
        size_t len = strlen(ch[i].name);
        if (len == 0 || ch[i].name[len - 1] == '.')
            st = lie_error_set(err, LIE_ERR_ARG, path, "empty EXR channel name '%s'", ch[i].name);
        for (int j = 0; j < i && st == LIE_OK; j++)
            if (strcmp(ch[i].name, ch[j].name) == 0)
                st = lie_error_set(err, LIE_ERR_ARG, path, "duplicate EXR channel '%s'",
                                   ch[i].name);
    }
    if (st != LIE_OK) {
        free(ch);
        return st;
    }
    *out = ch;
    *n_out = n;
    return LIE_OK;
}

static exr_result_t set_attr(exr_context_t ctx, int part, const lie_attr *a)
{
    switch (a->type) {
    case LIE_ATTR_STRING:
        return exr_attr_set_string(ctx, part, a->name, a->s);
    case LIE_ATTR_FLOAT:
        return exr_attr_set_float(ctx, part, a->name, a->f);
    case LIE_ATTR_INT:
        return exr_attr_set_int(ctx, part, a->name, a->i);
    case LIE_ATTR_V3F: {
        exr_attr_v3f_t v;
        v.x = a->v[0];
        v.y = a->v[1];
        v.z = a->v[2];
        return exr_attr_set_v3f(ctx, part, a->name, &v);
    }
    case LIE_ATTR_M44F: {
        exr_attr_m44f_t m;
        memcpy(m.m, a->v, sizeof m.m);
        return exr_attr_set_m44f(ctx, part, a->name, &m);
    }
    }
    return EXR_ERR_INVALID_ARGUMENT;
}

static lie_status check_attrs(const lie_attr *attrs, int n_attrs, int *long_names,
                              const char *path, lie_error *err)
{
    if (n_attrs < 0 || (n_attrs > 0 && !attrs))
        return lie_error_set(err, LIE_ERR_ARG, path, "bad attribute list");
    for (int i = 0; i < n_attrs; i++) {
        const lie_attr *a = &attrs[i];
        if (!a->name || !a->name[0])
            return lie_error_set(err, LIE_ERR_ARG, path, "attribute %d has no name", i);
        if ((unsigned)a->type > LIE_ATTR_M44F)
            return lie_error_set(err, LIE_ERR_ARG, path, "attribute '%s': unknown type %d",
                                 a->name, (int)a->type);
        if (a->type == LIE_ATTR_STRING && !a->s)
            return lie_error_set(err, LIE_ERR_ARG, path, "attribute '%s': no string", a->name);
        if (strlen(a->name) > EXR_SHORT_NAME_MAX)
            *long_names = 1;
    }
    return LIE_OK;
}

/* ---- chunks compressed in parallel, written in order ---------------------
 *
 * ZIP compression costs about as much as rendering a frame, so every chunk
 * runs OpenEXR's encode pipeline (pack, compress) on a worker thread with
 * a write step that keeps the result; the chunks are then written in
 * increasing y by this thread.  Each chunk's bytes depend on its pixels
 * only, so the file is the same for any thread count. */

/* lie_exr_compression's names and OpenEXR codes, in its order. */
/* lines: scanlines per chunk (the OpenEXR file layout's table; checked
 * against the library's exr_get_scanlines_per_chunk when writing). */
static const struct {
    const char *name;
    exr_compression_t c;
    int lines;
} COMPRESSIONS[] = {{"zip", EXR_COMPRESSION_ZIP, 16}, {"zips", EXR_COMPRESSION_ZIPS, 1},
                    {"piz", EXR_COMPRESSION_PIZ, 32}, {"rle", EXR_COMPRESSION_RLE, 1},
                    {"none", EXR_COMPRESSION_NONE, 1}};
#define N_COMPRESSIONS (sizeof COMPRESSIONS / sizeof *COMPRESSIONS)

int lie_exr_chunk_lines(lie_exr_compression c)
{
    return (unsigned)c < N_COMPRESSIONS ? COMPRESSIONS[c].lines : 0;
}

int lie_exr_compression_parse(const char *name, lie_exr_compression *out)
{
    for (size_t k = 0; name && k < N_COMPRESSIONS; k++)
        if (strcmp(name, COMPRESSIONS[k].name) == 0) {
            *out = (lie_exr_compression)k;
            return 1;
        }
    return 0;
}

typedef struct chunk_out {
    unsigned char *data;
    uint64_t size;
    exr_result_t rv;
} chunk_out;

typedef struct chunk_job {
    exr_context_t ctx;
    int part;
    const lie_frame *f;
    const exr_out_channel *ch;
    int n_ch;
    const exr_chunk_info_t *cinfo; /* the chunks to encode */
    chunk_out *out;
    const lie_exr_chunk *given;    /* per chunk: compressed elsewhere (data not NULL), or NULL */
} chunk_job;

static exr_result_t keep_chunk(exr_encode_pipeline_t *enc)
{
    chunk_out *o = enc->encoding_user_data;
    o->data = malloc(enc->compressed_bytes ? (size_t)enc->compressed_bytes : 1);
    if (!o->data)
        return EXR_ERR_OUT_OF_MEMORY;
    memcpy(o->data, enc->compressed_buffer, (size_t)enc->compressed_bytes);
    o->size = enc->compressed_bytes;
    return EXR_ERR_SUCCESS;
}

static void encode_chunk(void *ctx, size_t k, int worker)
{
    (void)worker;
    const chunk_job *j = ctx;
    const exr_chunk_info_t *ci = &j->cinfo[k];
    if (j->given && j->given[k].data)
        return; /* written from the caller's bytes */
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    exr_result_t rv = exr_encoding_initialize(j->ctx, j->part, ci, &enc);
    int have_enc = rv == EXR_ERR_SUCCESS;
    /* The library keeps the channel list sorted by name; the encoder's
     * channels are matched back to ours by name. */
    for (int c = 0; rv == EXR_ERR_SUCCESS && c < enc.channel_count; c++) {
        exr_coding_channel_info_t *ec = &enc.channels[c];
        const exr_out_channel *src = NULL;
        for (int q = 0; q < j->n_ch && !src; q++)
            if (strcmp(j->ch[q].name, ec->channel_name) == 0)
                src = &j->ch[q];
        if (!src) {
            rv = EXR_ERR_INVALID_ARGUMENT;
            break;
        }
        size_t row = (size_t)(ci->start_y) * (size_t)j->f->width * (size_t)src->stride;
        ec->encode_from_ptr = (const uint8_t *)(src->base + row);
        ec->user_pixel_stride = src->stride * (int32_t)sizeof(float);
        ec->user_line_stride = j->f->width * src->stride * (int32_t)sizeof(float);
        ec->user_bytes_per_element = sizeof(float);
        ec->user_data_type = EXR_PIXEL_FLOAT;
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_encoding_choose_default_routines(j->ctx, j->part, &enc);
    if (rv == EXR_ERR_SUCCESS) {
        enc.yield_until_ready_fn = NULL; /* nothing is written here */
        enc.write_fn = keep_chunk;
        enc.encoding_user_data = &j->out[k];
        rv = exr_encoding_run(j->ctx, j->part, &enc);
    }
    if (have_enc)
        exr_encoding_destroy(j->ctx, &enc);
    j->out[k].rv = rv;
}

/* A write context on `s` with the frame's header written: the channels,
 * and with attrs the attributes and screen window (chunks compress the
 * same without them: their bytes depend on the pixels, channels and
 * compression only).  *lines: scanlines per chunk. */
static lie_status start_file(exr_stream *s, const char *path, const lie_frame *f, const exr_out_channel *ch,
                             int n_ch, const lie_exr_options *opt, int long_names, int attrs, exr_context_t *pctx,
                             int32_t *lines, lie_error *err)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = s;
    init.write_fn = stream_write;
    init.zip_level = EXR_ZIP_LEVEL;
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    *pctx = ctx;
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot start EXR output");
    int part = 0;
    rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctx, part, f->width, f->height,
                                                 COMPRESSIONS[opt->compression].c);
    if (rv == EXR_ERR_SUCCESS && long_names)
        rv = exr_set_longname_support(ctx, 1);
    if (rv == EXR_ERR_SUCCESS && attrs && opt->screen_window_width > 0.0f) {
        exr_attr_v2f_t c = {.x = opt->screen_window_center[0], .y = opt->screen_window_center[1]};
        rv = exr_set_screen_window_center(ctx, part, &c);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_set_screen_window_width(ctx, part, opt->screen_window_width);
    }
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot set up EXR header");
    /* The library keeps the channel list sorted by name; the encoder's
     * channels are matched back to ours by name (encode_chunk). */
    for (int c = 0; c < n_ch; c++) {
        rv = exr_add_channel(ctx, part, ch[c].name, ch[c].half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                             EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        if (rv != EXR_ERR_SUCCESS)
            return exr_fail(err, LIE_ERR_ARG, path, s, rv, "cannot add EXR channel");
    }
    for (int i = 0; attrs && i < opt->n_attrs; i++) {
        rv = set_attr(ctx, part, &opt->attrs[i]);
        if (rv != EXR_ERR_SUCCESS) {
            char what[320];
            snprintf(what, sizeof what, "attribute '%.255s'", opt->attrs[i].name);
            return exr_fail(err, LIE_ERR_ARG, path, s, rv, what);
        }
    }
    rv = exr_write_header(ctx);
    if (rv != EXR_ERR_SUCCESS)
        return exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot write EXR header");
    rv = exr_get_scanlines_per_chunk(ctx, part, lines);
    if (rv != EXR_ERR_SUCCESS || *lines != COMPRESSIONS[opt->compression].lines)
        return exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot plan EXR chunks");
    return LIE_OK;
}

/* Encode chunks [first, first + count) of the file on ctx into out[]
 * (on opt->threads workers), except those given[] holds. */
static lie_status encode_range(exr_context_t ctx, const char *path, const exr_stream *s, const lie_frame *f,
                               const exr_out_channel *ch, int n_ch, const lie_exr_options *opt, int32_t lines,
                               size_t first, size_t count, const lie_exr_chunk *given, chunk_out *out,
                               exr_chunk_info_t *cinfo, lie_error *err)
{
    exr_result_t rv = EXR_ERR_SUCCESS;
    for (size_t k = 0; k < count && rv == EXR_ERR_SUCCESS; k++)
        rv = exr_write_scanline_chunk_info(ctx, 0, (int)(first + k) * lines, &cinfo[k]);
    if (rv == EXR_ERR_SUCCESS) {
        chunk_job job = {ctx, 0, f, ch, n_ch, cinfo, out, given};
        if (lie_parallel_for(count, opt->threads > 0 ? opt->threads : 0, encode_chunk, &job, NULL, NULL) != LIE_OK)
            rv = EXR_ERR_OUT_OF_MEMORY;
    }
    for (size_t k = 0; k < count && rv == EXR_ERR_SUCCESS; k++)
        if (!(given && given[k].data))
            rv = out[k].rv;
    return rv == EXR_ERR_SUCCESS ? LIE_OK : exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot encode EXR scanlines");
}

/* Build the whole file in `s`: chunk k from opt->chunks[k] where given,
 * the others compressed here. */
static lie_status encode_exr(exr_stream *s, const char *path, const lie_frame *f,
                             const exr_out_channel *ch, int n_ch, const lie_exr_options *opt,
                             int long_names, lie_error *err)
{
    exr_context_t ctx = NULL;
    int32_t lines = 0;
    lie_status st = start_file(s, path, f, ch, n_ch, opt, long_names, 1, &ctx, &lines, err);
    size_t n_chunks = st == LIE_OK ? (size_t)(f->height + lines - 1) / (size_t)lines : 0;
    exr_chunk_info_t *cinfo = st == LIE_OK ? calloc(n_chunks + 1, sizeof *cinfo) : NULL;
    chunk_out *out = st == LIE_OK ? calloc(n_chunks + 1, sizeof *out) : NULL;
    if (st == LIE_OK && (!cinfo || !out))
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    if (st == LIE_OK)
        st = encode_range(ctx, path, s, f, ch, n_ch, opt, lines, 0, n_chunks, opt->chunks, out, cinfo, err);
    exr_result_t rv = EXR_ERR_SUCCESS;
    for (size_t k = 0; st == LIE_OK && k < n_chunks && rv == EXR_ERR_SUCCESS; k++) {
        const lie_exr_chunk *g = opt->chunks && opt->chunks[k].data ? &opt->chunks[k] : NULL;
        rv = exr_write_scanline_chunk(ctx, 0, cinfo[k].start_y, g ? g->data : out[k].data,
                                      g ? g->size : out[k].size);
    }
    if (rv != EXR_ERR_SUCCESS)
        st = exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot encode EXR scanlines");
    for (size_t k = 0; out && k < n_chunks; k++)
        free(out[k].data);
    free(out);
    free(cinfo);
    /* exr_finish writes the chunk offset table. */
    rv = exr_finish(&ctx);
    if (st == LIE_OK && rv != EXR_ERR_SUCCESS)
        st = exr_fail(err, LIE_ERR_IO, path, s, rv, "cannot finish EXR output");
    return st;
}

static lie_status write_bytes(const char *path, const void *data, size_t size, lie_error *err)
{
    lie_atomic_file af;
    lie_status st = lie_atomic_open(&af, path, err);
    if (st != LIE_OK)
        return st;
    if (fwrite(data, 1, size, af.fp) != size) {
        lie_atomic_abort(&af);
        return lie_error_set(err, LIE_ERR_IO, path, "write failed");
    }
    return lie_atomic_commit(&af, err);
}

/* What every writer checks of the options and the frame, and the frame's
 * channels (*ch: free). */
static lie_status check_write(const char *path, const lie_frame *f, const lie_exr_options *opt, int *long_names,
                              exr_out_channel **ch, int *n_ch, lie_error *err)
{
    if ((unsigned)opt->compression >= N_COMPRESSIONS || opt->n_attrs < 0 || (opt->n_attrs > 0 && !opt->attrs) ||
        !(opt->screen_window_width >= 0.0f) || !isfinite(opt->screen_window_width) ||
        !isfinite(opt->screen_window_center[0]) || !isfinite(opt->screen_window_center[1]))
        return lie_error_set(err, LIE_ERR_ARG, path, "bad EXR options");
    if (!path || !f || !f->rgb || f->width <= 0 || f->height <= 0 || f->n_aovs < 0 ||
        (f->n_aovs > 0 && !f->aovs))
        return lie_error_set(err, LIE_ERR_ARG, path, "no frame to write");
    /* Line strides are int32 in the encoder. */
    if (f->width > INT32_MAX / (LIE_AOV_MAX_CHANNELS * (int)sizeof(float)))
        return lie_error_set(err, LIE_ERR_LIMIT, path, "frame too wide for EXR: %d", f->width);
    *long_names = 0;
    lie_status st = check_attrs(opt->attrs, opt->n_attrs, long_names, path, err);
    if (st == LIE_OK)
        st = collect_channels(f, opt->half, ch, n_ch, path, err);
    for (int c = 0; st == LIE_OK && c < *n_ch; c++)
        if (strlen((*ch)[c].name) > EXR_SHORT_NAME_MAX)
            *long_names = 1;
    return st;
}

lie_status lie_exr_write(const char *path, const lie_frame *f, const lie_exr_options *opt, lie_error *err)
{
    static const lie_exr_options defaults;
    if (!opt)
        opt = &defaults;
    exr_out_channel *ch = NULL;
    int n_ch = 0, long_names = 0;
    lie_status st = check_write(path, f, opt, &long_names, &ch, &n_ch, err);
    if (st != LIE_OK)
        return st;
    exr_stream s;
    memset(&s, 0, sizeof s);
    st = encode_exr(&s, path, f, ch, n_ch, opt, long_names, err);
    if (st == LIE_OK)
        st = write_bytes(path, s.data, s.size, err);
    free(s.data);
    free(ch);
    return st;
}

lie_status lie_exr_encode_chunks(const lie_frame *f, const lie_exr_options *opt, int first, int count,
                                 lie_exr_chunk *out, lie_error *err)
{
    static const lie_exr_options defaults;
    static const char *const what = "EXR chunks";
    if (!opt)
        opt = &defaults;
    for (int k = 0; out && k < count; k++)
        out[k] = (lie_exr_chunk){NULL, 0};
    exr_out_channel *ch = NULL;
    int n_ch = 0, long_names = 0;
    lie_status st = check_write(what, f, opt, &long_names, &ch, &n_ch, err);
    if (st != LIE_OK)
        return st;
    int lines = COMPRESSIONS[opt->compression].lines, n_chunks = (f->height + lines - 1) / lines;
    if (!out || first < 0 || count < 0 || first > n_chunks || count > n_chunks - first) {
        free(ch);
        return lie_error_set(err, LIE_ERR_ARG, what, "chunks %d..%d of a %d-chunk image", first, first + count,
                             n_chunks);
    }
    /* the header goes to a scratch stream: only the chunks are kept */
    exr_stream s;
    memset(&s, 0, sizeof s);
    exr_context_t ctx = NULL;
    int32_t got = 0;
    st = start_file(&s, what, f, ch, n_ch, opt, long_names, 0, &ctx, &got, err);
    exr_chunk_info_t *cinfo = calloc((size_t)count + 1, sizeof *cinfo);
    chunk_out *co = calloc((size_t)count + 1, sizeof *co);
    if (st == LIE_OK && (!cinfo || !co))
        st = lie_error_set(err, LIE_ERR_NOMEM, what, "out of memory");
    if (st == LIE_OK)
        st = encode_range(ctx, what, &s, f, ch, n_ch, opt, got, (size_t)first, (size_t)count, NULL, co, cinfo,
                          err);
    for (int k = 0; co && k < count; k++) {
        if (st == LIE_OK)
            out[k] = (lie_exr_chunk){co[k].data, co[k].size};
        else
            free(co[k].data);
    }
    free(co);
    free(cinfo);
    exr_finish(&ctx); /* the scratch file lacks its chunks: only closed */
    free(s.data);
    free(ch);
    return st;
}

/* ---- reading ----------------------------------------------------------- */

static lie_status open_exr(exr_context_t *ctx, exr_stream *s, const char *path, lie_error *err)
{
    memset(s, 0, sizeof *s);
    *ctx = NULL;
    lie_status st = lie_read_file(path, &s->data, &s->size, err);
    if (st != LIE_OK)
        return st;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = s;
    init.read_fn = stream_read;
    init.size_fn = stream_size;
    /* A damaged file is an error, not something to patch up. */
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_result_t rv = exr_start_read(ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(ctx);
        free(s->data);
        s->data = NULL;
        return exr_fail(err, LIE_ERR_FORMAT, path, s, rv, "not a readable OpenEXR file");
    }
    return LIE_OK;
}

static void close_exr(exr_context_t *ctx, exr_stream *s)
{
    exr_finish(ctx);
    free(s->data);
    s->data = NULL;
}

/* Where one file channel goes in the frame. */
typedef struct exr_in_channel {
    float *base;
    int stride;
} exr_in_channel;

/* Layers collected from the channel list before the frame exists. */
typedef struct exr_layer {
    char name[sizeof(((lie_aov *)0)->name)];
    int n;
    char chan[LIE_AOV_MAX_CHANNELS][sizeof(((lie_aov *)0)->channel[0])];
    int file_index[LIE_AOV_MAX_CHANNELS];
} exr_layer;

/* R, G, B, A first within a layer, in that order; the rest as listed. */
static int channel_rank(const char *c)
{
    static const char *const order[4] = {"R", "G", "B", "A"};
    for (int i = 0; i < 4; i++)
        if (strcmp(c, order[i]) == 0)
            return i;
    return 4;
}

/* Split the channel list into RGB and AOV layers and build the frame. */
static lie_status plan_frame(const exr_attr_chlist_t *cl, int w, int h, lie_frame **out,
                             exr_in_channel *map, const char *path, lie_error *err)
{
    exr_layer *layers = calloc((size_t)cl->num_channels + 1, sizeof *layers);
    if (!layers)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    int n_layers = 0;
    lie_status st = LIE_OK;
    for (int i = 0; i < cl->num_channels && st == LIE_OK; i++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[i];
        const char *name = e->name.str ? e->name.str : "";
        map[i].base = NULL;
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            st = lie_error_set(err, LIE_ERR_UNSUPPORTED, path,
                               "channel '%s' is subsampled (%dx%d)", name, e->x_sampling,
                               e->y_sampling);
            break;
        }
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT &&
            e->pixel_type != EXR_PIXEL_UINT) {
            st = lie_error_set(err, LIE_ERR_FORMAT, path, "channel '%s' has unknown type %d",
                               name, (int)e->pixel_type);
            break;
        }
        if (strcmp(name, "R") == 0 || strcmp(name, "G") == 0 || strcmp(name, "B") == 0)
            continue;
        /* OpenEXR's layer convention: the layer is everything before the
         * last dot; no dot means the default (empty) layer. */
        const char *dot = strrchr(name, '.');
        size_t llen = dot ? (size_t)(dot - name) : 0;
        const char *chan = dot ? dot + 1 : name;
        if (!chan[0]) {
            st = lie_error_set(err, LIE_ERR_FORMAT, path, "channel '%s' has an empty name", name);
            break;
        }
        if (llen >= sizeof layers[0].name || strlen(chan) >= sizeof layers[0].chan[0]) {
            st = lie_error_set(err, LIE_ERR_UNSUPPORTED, path, "channel name '%s' is too long",
                               name);
            break;
        }
        int l = 0;
        while (l < n_layers && !(strlen(layers[l].name) == llen &&
                                 memcmp(layers[l].name, name, llen) == 0))
            l++;
        if (l == n_layers) {
            memcpy(layers[l].name, name, llen);
            layers[l].name[llen] = 0;
            n_layers++;
        }
        exr_layer *L = &layers[l];
        if (L->n == LIE_AOV_MAX_CHANNELS) {
            st = lie_error_set(err, LIE_ERR_UNSUPPORTED, path,
                               "layer '%s' has more than %d channels", L->name,
                               LIE_AOV_MAX_CHANNELS);
            break;
        }
        /* Stable insertion by rank keeps R,G,B,A in display order. */
        int pos = L->n;
        while (pos > 0 && channel_rank(L->chan[pos - 1]) > channel_rank(chan)) {
            memcpy(L->chan[pos], L->chan[pos - 1], sizeof L->chan[pos]);
            L->file_index[pos] = L->file_index[pos - 1];
            pos--;
        }
        snprintf(L->chan[pos], sizeof L->chan[pos], "%s", chan);
        L->file_index[pos] = i;
        L->n++;
    }

    lie_frame *f = NULL;
    if (st == LIE_OK && !(f = lie_frame_create(w, h)))
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory for a %dx%d frame", w, h);
    for (int i = 0; st == LIE_OK && i < cl->num_channels; i++) {
        const char *name = cl->entries[i].name.str ? cl->entries[i].name.str : "";
        int c = strcmp(name, "R") == 0 ? 0 : strcmp(name, "G") == 0 ? 1 : strcmp(name, "B") == 0 ? 2 : -1;
        if (c >= 0) {
            map[i].base = f->rgb + c;
            map[i].stride = 3;
        }
    }
    for (int l = 0; st == LIE_OK && l < n_layers; l++) {
        const char *names[LIE_AOV_MAX_CHANNELS];
        for (int c = 0; c < layers[l].n; c++)
            names[c] = layers[l].chan[c];
        float *data = lie_frame_add_aov(f, layers[l].name, layers[l].n, names);
        if (!data) {
            /* Names are unique by construction, so only memory can fail. */
            st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory for layer '%s'",
                               layers[l].name);
            break;
        }
        for (int c = 0; c < layers[l].n; c++) {
            map[layers[l].file_index[c]].base = data + c;
            map[layers[l].file_index[c]].stride = layers[l].n;
        }
    }
    free(layers);
    if (st != LIE_OK) {
        lie_frame_destroy(f);
        return st;
    }
    *out = f;
    return LIE_OK;
}

static lie_status decode_exr(exr_context_t ctx, const exr_stream *s, const exr_attr_box2i_t *dw,
                             const exr_attr_chlist_t *cl, const exr_in_channel *map,
                             lie_frame *f, const char *path, lie_error *err)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (rv != EXR_ERR_SUCCESS || lines < 1)
        return exr_fail(err, LIE_ERR_FORMAT, path, s, rv, "bad EXR chunk layout");
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int have_dec = 0;
    lie_status st = LIE_OK;
    for (int64_t y = dw->min.y; y <= dw->max.y; y += lines) {
        exr_chunk_info_t cinfo;
        rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &cinfo);
        if (rv == EXR_ERR_SUCCESS) {
            rv = have_dec ? exr_decoding_update(ctx, 0, &cinfo, &dec)
                          : exr_decoding_initialize(ctx, 0, &cinfo, &dec);
            have_dec = 1;
        }
        /* The chunk must lie inside the data window we allocated for. */
        if (rv == EXR_ERR_SUCCESS &&
            (cinfo.start_y < dw->min.y || cinfo.height < 1 ||
             (int64_t)cinfo.start_y + cinfo.height - 1 > dw->max.y || cinfo.width != f->width ||
             dec.channel_count != cl->num_channels))
            rv = EXR_ERR_CORRUPT_CHUNK;
        for (int c = 0; rv == EXR_ERR_SUCCESS && c < dec.channel_count; c++) {
            exr_coding_channel_info_t *dc = &dec.channels[c];
            const exr_in_channel *dst = NULL;
            for (int k = 0; k < cl->num_channels && !dst; k++)
                if (cl->entries[k].name.str && dc->channel_name &&
                    strcmp(cl->entries[k].name.str, dc->channel_name) == 0)
                    dst = &map[k];
            if (!dst || !dst->base || dc->height != cinfo.height || dc->width != f->width) {
                rv = EXR_ERR_CORRUPT_CHUNK;
                break;
            }
            size_t row = (size_t)(cinfo.start_y - dw->min.y) * (size_t)f->width *
                         (size_t)dst->stride;
            dc->decode_to_ptr = (uint8_t *)(dst->base + row);
            dc->user_pixel_stride = dst->stride * (int32_t)sizeof(float);
            dc->user_line_stride = f->width * dst->stride * (int32_t)sizeof(float);
            dc->user_bytes_per_element = sizeof(float);
            dc->user_data_type = EXR_PIXEL_FLOAT;
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_decoding_run(ctx, 0, &dec);
        if (rv != EXR_ERR_SUCCESS) {
            char what[64];
            snprintf(what, sizeof what, "cannot decode scanline %lld", (long long)y);
            st = exr_fail(err, LIE_ERR_FORMAT, path, s, rv, what);
            break;
        }
    }
    if (have_dec)
        exr_decoding_destroy(ctx, &dec);
    return st;
}

lie_status lie_exr_read(const char *path, lie_frame **out, lie_error *err)
{
    if (!out)
        return lie_error_set(err, LIE_ERR_ARG, path, "no output frame");
    *out = NULL;
    if (!path)
        return lie_error_set(err, LIE_ERR_ARG, path, "no input path");
    exr_context_t ctx;
    exr_stream s;
    lie_status st = open_exr(&ctx, &s, path, err);
    if (st != LIE_OK)
        return st;

    exr_result_t rv;
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *cl = NULL;
    int32_t chunks = 0;
    exr_in_channel *map = NULL;
    lie_frame *f = NULL;
    if ((rv = exr_get_storage(ctx, 0, &storage)) != EXR_ERR_SUCCESS) {
        st = exr_fail(err, LIE_ERR_FORMAT, path, &s, rv, "bad EXR part");
        goto done;
    }
    if (storage != EXR_STORAGE_SCANLINE) {
        st = lie_error_set(err, LIE_ERR_UNSUPPORTED, path,
                           "only scanline EXR images are supported (not tiled or deep)");
        goto done;
    }
    if ((rv = exr_get_data_window(ctx, 0, &dw)) != EXR_ERR_SUCCESS ||
        (rv = exr_get_channels(ctx, 0, &cl)) != EXR_ERR_SUCCESS ||
        (rv = exr_get_chunk_count(ctx, 0, &chunks)) != EXR_ERR_SUCCESS) {
        st = exr_fail(err, LIE_ERR_FORMAT, path, &s, rv, "bad EXR header");
        goto done;
    }
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "empty EXR data window");
        goto done;
    }
    if (w > EXR_MAX_DIM || h > EXR_MAX_DIM || w * h > EXR_MAX_PIXELS) {
        st = lie_error_set(err, LIE_ERR_LIMIT, path, "EXR image too large: %lldx%lld",
                           (long long)w, (long long)h);
        goto done;
    }
    /* Each chunk needs an 8-byte offset and an 8-byte leader: refuse a
     * header whose image cannot fit in the file before allocating for it. */
    if (chunks < 1 || (uint64_t)chunks * 16 > s.size) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "EXR file too short for its data window");
        goto done;
    }
    if (!cl || cl->num_channels < 1) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "EXR file has no channels");
        goto done;
    }
    map = calloc((size_t)cl->num_channels, sizeof *map);
    if (!map) {
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
        goto done;
    }
    st = plan_frame(cl, (int)w, (int)h, &f, map, path, err);
    if (st == LIE_OK)
        st = decode_exr(ctx, &s, &dw, cl, map, f, path, err);

done:
    free(map);
    close_exr(&ctx, &s);
    if (st != LIE_OK) {
        lie_frame_destroy(f);
        return st;
    }
    *out = f;
    return LIE_OK;
}

lie_status lie_exr_read_string_attr(const char *path, const char *name, char *buf, size_t size,
                                    lie_error *err)
{
    if (!path || !name || !buf || size == 0)
        return lie_error_set(err, LIE_ERR_ARG, path, "bad arguments");
    buf[0] = 0;
    exr_context_t ctx;
    exr_stream s;
    lie_status st = open_exr(&ctx, &s, path, err);
    if (st != LIE_OK)
        return st;
    int32_t len = 0;
    const char *str = NULL;
    exr_result_t rv = exr_attr_get_string(ctx, 0, name, &len, &str);
    if (rv == EXR_ERR_NO_ATTR_BY_NAME)
        st = lie_error_set(err, LIE_ERR_NOT_FOUND, path, "no attribute '%s'", name);
    else if (rv == EXR_ERR_ATTR_TYPE_MISMATCH)
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "attribute '%s' is not a string", name);
    else if (rv != EXR_ERR_SUCCESS)
        st = exr_fail(err, LIE_ERR_FORMAT, path, &s, rv, "cannot read attribute");
    else if (len < 0 || (size_t)len >= size)
        st = lie_error_set(err, LIE_ERR_LIMIT, path, "attribute '%s' is longer than %zu bytes",
                           name, size - 1);
    else {
        memcpy(buf, str, (size_t)len);
        buf[len] = 0;
    }
    close_exr(&ctx, &s);
    return st;
}
