/* SPDX-License-Identifier: Apache-2.0 */
/* lib/image: frame buffers, OpenEXR output through OpenEXR's C API
 * (openexr.h) with extra channels for AOVs and header attributes, PNG
 * previews through libpng.  Every writer is atomic (lib/core). */
#ifndef LIE_IMAGE_H
#define LIE_IMAGE_H

#include "core/core.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

#define LIE_AOV_MAX_CHANNELS 4

/* An extra layer of channels, written to EXR as "<name>.<channel>"
 * (e.g. "complexity.R", "depth.Z"). Interleaved, n_channels per pixel.
 * An empty name is OpenEXR's default layer: bare channel names ("A", "Z"). */
typedef struct lie_aov {
    char name[32];
    int n_channels;
    char channel[LIE_AOV_MAX_CHANNELS][8];
    float *data;
} lie_aov;

/* A rendered frame: linear RGB radiance, row 0 at the top.  Owns its
 * buffers. */
typedef struct lie_frame {
    int width, height;
    float *rgb;          /* 3 floats per pixel */
    lie_aov *aovs;
    int n_aovs;
} lie_frame;

/* Zeroed frame; NULL if a size is not positive or memory runs out. */
lie_frame *lie_frame_create(int width, int height);
/* Add a zeroed AOV layer; returns its data pointer, or NULL if the name is
 * taken or too long, n_channels is not 1..LIE_AOV_MAX_CHANNELS, or a
 * channel name is empty, repeated or too long.  Names are copied. */
float *lie_frame_add_aov(lie_frame *f, const char *name, int n_channels,
                         const char *const *channel_names);
const lie_aov *lie_frame_find_aov(const lie_frame *f, const char *name);
void lie_frame_destroy(lie_frame *f);

/* Header attributes written to the EXR file. */
typedef enum lie_attr_type {
    LIE_ATTR_STRING = 0,
    LIE_ATTR_FLOAT = 1,
    LIE_ATTR_INT = 2,
    LIE_ATTR_V3F = 3,
    LIE_ATTR_M44F = 4
} lie_attr_type;

typedef struct lie_attr {
    const char *name;
    lie_attr_type type;
    const char *s;
    float f;
    int i;
    float v[16];          /* v3f: v[0..2]; m44f: 16 floats, row-major as EXR */
} lie_attr;

/* The lossless compressions of EXR output: zip (the default: 16 scanlines
 * per zlib block), zips (one scanline), piz (wavelet), rle or none. */
typedef enum lie_exr_compression {
    LIE_EXR_ZIP = 0,
    LIE_EXR_ZIPS = 1,
    LIE_EXR_PIZ = 2,
    LIE_EXR_RLE = 3,
    LIE_EXR_NONE = 4
} lie_exr_compression;
/* A compression by its name above; returns 0 for an unknown name (*out
 * unchanged). */
int lie_exr_compression_parse(const char *name, lie_exr_compression *out);

/* How one EXR file is written, passed per call as OpenEXRCore passes its
 * context initializer: no process-wide settings.  A zeroed struct (or a
 * NULL pointer) is the default: no extra attributes, zip, all cores. */
typedef struct lie_exr_options {
    const lie_attr *attrs;           /* extra header attributes */
    int n_attrs;
    lie_exr_compression compression;
    int threads;                     /* workers compressing chunks (0: all cores); the
                                        bytes written do not depend on it */
    int half;                        /* store R, G, B as 16-bit half floats (the AOVs
                                        stay 32-bit) */
    /* The required screenWindowCenter / screenWindowWidth attributes
     * (OpenEXR's ImfHeader.h): a width of 0 keeps OpenEXR's default
     * window, centre (0, 0) and width 1. */
    float screen_window_center[2];
    float screen_window_width;
    /* Chunks compressed elsewhere (lie_exr_encode_chunks), one per chunk of
     * the image (lie_exr_chunk_lines scanlines each, from the top): chunk k
     * is written from chunks[k] where its data is not NULL, and compressed
     * here otherwise.  NULL: every chunk here.  The caller keeps them. */
    const struct lie_exr_chunk *chunks;
} lie_exr_options;
/* One compressed EXR scanline chunk, as the file stores it. */
typedef struct lie_exr_chunk {
    unsigned char *data;
    uint64_t size;
} lie_exr_chunk;
/* Scanlines per chunk of a compression (OpenEXR's layout: zip 16, piz 32,
 * zips, rle and none 1); 0 for no compression of lie_exr_compression. */
int lie_exr_chunk_lines(lie_exr_compression c);
/* Compress chunks [first, first + count) of the file lie_exr_write(.., f,
 * opt) writes, on opt->threads workers, into out[0 .. count - 1] (data
 * malloc'd: the caller frees it).  Only those chunks' rows of f are read;
 * the attributes do not matter (a chunk's bytes depend on its pixels, the
 * channels and the compression alone, OpenEXR compressing chunks
 * independently).  So a frame rendered in bands of rows on several
 * machines is compressed where each band was rendered and written in one
 * place with opt.chunks, byte for byte the file one process writes. */
lie_status lie_exr_encode_chunks(const lie_frame *f, const lie_exr_options *opt, int first, int count,
                                 lie_exr_chunk *out, lie_error *err);

/* EXR: RGB as 32-bit float channels "R","G","B" plus every AOV, scanline,
 * increasing Y.  Path "-" writes to stdout.
 * The file is assembled in memory and written atomically.  A channel
 * name used twice, or an attribute clashing with a standard one
 * ("compression", ...), is LIE_ERR_ARG. */
lie_status lie_exr_write(const char *path, const lie_frame *f, const lie_exr_options *opt, lie_error *err);

/* Read an EXR file written by anyone: every channel as float.  "R","G","B"
 * go to rgb (missing ones are 0); other channels "layer.chan" become AOVs
 * grouped by layer in file order (the layer is everything before the last
 * dot; channels within a layer in file order, but R, G, B, A first).  The
 * frame covers the data window.  Reads the first part only; tiled, deep or
 * subsampled images and layers of more than LIE_AOV_MAX_CHANNELS channels
 * are LIE_ERR_UNSUPPORTED, images over 65536 a side or 2^28 pixels
 * LIE_ERR_LIMIT.  *out is a new frame on success, NULL on failure. */
lie_status lie_exr_read(const char *path, lie_frame **out, lie_error *err);

/* Read one string attribute from an EXR header (for tests and tools):
 * LIE_ERR_NOT_FOUND if absent, LIE_ERR_FORMAT if not a string,
 * LIE_ERR_LIMIT if it does not fit in `size` bytes with its NUL. */
lie_status lie_exr_read_string_attr(const char *path, const char *name, char *buf, size_t size,
                                    lie_error *err);

/* A PNG tEXt chunk: keyword (1 to 79 Latin-1 characters) and text. */
typedef struct lie_png_text {
    const char *key, *text;
} lie_png_text;

/* How a PNG preview is made (zeroed or NULL: exposure 0, no text). */
typedef struct lie_png_options {
    float exposure; /* stops: radiance is scaled by 2^exposure */
    const lie_png_text *text; /* tEXt chunks, in this order (lie-render's auto exposure) */
    int n_text;
} lie_png_options;

/* Auto exposure, from the image's log-average luminance as Reinhard, Stark,
 * Shirley and Ferwerda (2002, "Photographic Tone Reproduction for Digital
 * Images", eq. 1) define it: Lw = exp(mean(log(delta + L))) over the
 * pixels, L the Rec. 709 luminance of the linear RGB and delta, keeping
 * black pixels finite, LIE_EXPOSURE_DELTA times the pixels' mean
 * luminance rather than a constant: scenes lit in physical units (nits
 * from lux and candela) span many decades, and a scene k times brighter
 * then gets exactly log2(k) stops less; the exposure that maps Lw to the
 * key is log2(key / Lw) stops.  Pixels that a frame's coverage
 * channel (an AOV of the default layer, channel "A") says no eye ray hit
 * are left out: the empty background is no part of the scene's exposure.
 * The sum runs over the pixels in row order, in double: the same frame
 * gives the same bits for any thread or rank count that made it. */
#define LIE_EXPOSURE_KEY 0.18f
#define LIE_EXPOSURE_DELTA 1e-4
typedef struct lie_auto_exposure {
    float ev;            /* stops, within [-64, 64]; 0 when no pixel counts or none is lit */
    float key;
    double log_average;  /* Lw */
    uint64_t pixels;     /* the pixels counted */
} lie_auto_exposure;
lie_auto_exposure lie_frame_auto_exposure(const lie_frame *f, float key);
/* The sentence a file says its auto exposure with (PNG tEXt lie.exposure):
 * every program that writes an auto-exposed frame says it alike, so that
 * the same frame gives the same bytes from any of them. */
void lie_auto_exposure_text(const lie_auto_exposure *ae, char *buf, size_t size);

/* PNG preview: 8-bit RGB, radiance x 2^exposure, clamped, sRGB transfer
 * curve, with an sRGB chunk.  Written atomically. */
lie_status lie_png_write(const char *path, const lie_frame *f, const lie_png_options *opt, lie_error *err);

/* Pixels for lie_png_encode: height rows of width pixels of `channels`
 * (3: RGB, 4: RGBA) samples of `bits` (8: uint8_t, 16: uint16_t in host
 * order), row 0 first. */
typedef struct lie_png_pixels {
    int width, height, bits, channels;
    const void *data;
    int srgb; /* 1: an sRGB chunk (with gAMA and cHRM); 0: no colour chunk */
    const lie_png_text *text; /* tEXt chunks before the pixels, or NULL */
    int n_text;
} lie_png_pixels;

/* Encode a PNG in memory: *out (malloc'd; the caller frees it) of *size
 * bytes, a function of the pixels and the text given (no time chunk).  `path`
 * names the file in messages. */
lie_status lie_png_encode(const lie_png_pixels *px, const char *path, unsigned char **out, size_t *size,
                          lie_error *err);

/* 8-bit RGB PNG from raw pixels (for false-colour images and tests), with
 * an sRGB chunk.  Written atomically. */
lie_status lie_png_write_rgb8(const char *path, int width, int height, const uint8_t *rgb,
                              lie_error *err);

/* The formats a frame can be written in. */
typedef enum lie_frame_format {
    LIE_FORMAT_AUTO = 0, /* by the path's extension (lie_frame_format_of) */
    LIE_FORMAT_EXR = 1,
    LIE_FORMAT_PNG = 2
} lie_frame_format;

/* A format by name ("exr", "png"); returns 0 for an unknown name (*out
 * unchanged). */
int lie_frame_format_parse(const char *name, lie_frame_format *out);
/* The format a path's extension names, case-insensitively: ".exr" EXR,
 * ".png" PNG, "-" (stdout) or an existing character device (/dev/null)
 * EXR.  Returns 0 for any other path (*out unchanged): a writer must not
 * guess. */
int lie_frame_format_of(const char *path, lie_frame_format *out);

/* Each format's options, for a writer that picks the format by name. */
typedef struct lie_frame_options {
    lie_exr_options exr;
    lie_png_options png;
    lie_frame_format format; /* LIE_FORMAT_AUTO: by the path's extension */
} lie_frame_options;

/* Write in opt->format, or when that is LIE_FORMAT_AUTO (or opt is NULL)
 * in the format of the path's extension (lie_frame_format_of): a path of
 * no known extension is LIE_ERR_ARG.  "-" writes to stdout.  opt may be
 * NULL: the defaults. */
lie_status lie_frame_write(const char *path, const lie_frame *f, const lie_frame_options *opt, lie_error *err);

/* Linear to sRGB-encoded value (IEC 61966-2-1); both clamp to [0, 1] and
 * map NaN to 0. */
float lie_image_srgb_encode(float x);
float lie_image_srgb_decode(float x);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
