/* SPDX-License-Identifier: Apache-2.0 */
/* PNG through libpng: encoded in memory (lie_png_encode), previews written
 * atomically.  No tIME chunk, and text chunks only those asked for: the
 * bytes are a function of the pixels and that text. */
#include "image/image.h"

#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>

/* Where libpng's output and its first error message go. */
typedef struct png_sink {
    unsigned char *data;
    size_t size, cap;
    int oom;
    char msg[256];
} png_sink;

static void on_png_error(png_structp png, png_const_charp msg)
{
    png_sink *s = png_get_error_ptr(png);
    if (s && !s->msg[0])
        snprintf(s->msg, sizeof s->msg, "%s", msg ? msg : "libpng error");
    png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp msg) {}

static void sink_write(png_structp png, png_bytep data, size_t n)
{
    png_sink *s = png_get_io_ptr(png);
    if (n > SIZE_MAX - s->size || !LIE_GROW(s->data, s->cap, s->size + n)) {
        s->oom = 1;
        png_error(png, "out of memory");
    }
    memcpy(s->data + s->size, data, n);
    s->size += n;
}

static void sink_flush(png_structp png) {}

/* Encode into s.  Kept apart from the caller so that nothing the caller
 * owns is live across setjmp. */
static int encode_png(png_sink *s, const lie_png_pixels *px)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, s, on_png_error,
                                              on_png_warning);
    if (!png)
        return 0;
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, NULL);
        return 0;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return 0;
    }
    png_set_write_fn(png, s, sink_write, sink_flush);
    png_set_IHDR(png, info, (png_uint_32)px->width, (png_uint_32)px->height, px->bits,
                 px->channels == 4 ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* sRGB chunk plus the matching gAMA/cHRM for readers that ignore sRGB. */
    if (px->srgb)
        png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    for (int k = 0; k < px->n_text && px->text; k++) {
        png_text t;
        memset(&t, 0, sizeof t);
        t.compression = PNG_TEXT_COMPRESSION_NONE;
        t.key = (png_charp)px->text[k].key;
        t.text = (png_charp)px->text[k].text;
        t.text_length = strlen(px->text[k].text);
        png_set_text(png, info, &t, 1);
    }
    png_write_info(png, info);
    if (px->bits == 16) {
        /* PNG stores 16-bit samples big-endian; ours are in host order */
        const uint16_t one = 1;
        unsigned char little;
        memcpy(&little, &one, 1);
        if (little)
            png_set_swap(png);
    }
    size_t row = (size_t)px->width * (size_t)px->channels * (size_t)(px->bits / 8);
    for (int y = 0; y < px->height; y++)
        png_write_row(png, (png_const_bytep)px->data + (size_t)y * row);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 1;
}

lie_status lie_png_encode(const lie_png_pixels *px, const char *path, unsigned char **out, size_t *size,
                          lie_error *err)
{
    if (!px || !px->data || !out || !size || px->width <= 0 || px->height <= 0 ||
        (px->bits != 8 && px->bits != 16) || (px->channels != 3 && px->channels != 4))
        return lie_error_set(err, LIE_ERR_ARG, path, "PNG of %dx%d, %d-bit, %d channels: not supported",
                             px ? px->width : 0, px ? px->height : 0, px ? px->bits : 0, px ? px->channels : 0);
    /* PNG's limit is 2^31-1; libpng's default user limit is 10^6. */
    if (px->width > 1000000 || px->height > 1000000)
        return lie_error_set(err, LIE_ERR_LIMIT, path, "image too large for PNG: %dx%d", px->width,
                             px->height);
    png_sink s;
    memset(&s, 0, sizeof s);
    if (!encode_png(&s, px)) {
        free(s.data);
        if (s.oom || !s.msg[0])
            return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory encoding PNG");
        return lie_error_set(err, LIE_ERR_IO, path, "cannot encode PNG: %s", s.msg);
    }
    *out = s.data;
    *size = s.size;
    return LIE_OK;
}

/* Encode px and write it to path atomically. */
static lie_status png_write_pixels(const char *path, const lie_png_pixels *px, lie_error *err)
{
    unsigned char *data = NULL;
    size_t size = 0;
    lie_status st = lie_png_encode(px, path, &data, &size, err);
    if (st != LIE_OK)
        return st;
    lie_atomic_file af;
    st = lie_atomic_open(&af, path, err);
    if (st == LIE_OK) {
        if (fwrite(data, 1, size, af.fp) != size) {
            lie_atomic_abort(&af);
            st = lie_error_set(err, LIE_ERR_IO, path, "write failed");
        } else {
            st = lie_atomic_commit(&af, err);
        }
    }
    free(data);
    return st;
}

lie_status lie_png_write_rgb8(const char *path, int width, int height, const uint8_t *rgb,
                              lie_error *err)
{
    if (!path || !rgb || width <= 0 || height <= 0)
        return lie_error_set(err, LIE_ERR_ARG, path, "no image to write");
    lie_png_pixels px = {width, height, 8, 3, rgb, 1, NULL, 0};
    return png_write_pixels(path, &px, err);
}

/* clamp(srgb(x)) to 8 bits, rounded to nearest; NaN gives 0. */
static uint8_t encode_8bit(float x)
{
    float v = lie_image_srgb_encode(x);
    if (!(v > 0.0f))
        return 0;
    if (v >= 1.0f)
        return 255;
    return (uint8_t)(v * 255.0f + 0.5f);
}

lie_status lie_png_write(const char *path, const lie_frame *f, const lie_png_options *opt, lie_error *err)
{
    if (!path || !f || !f->rgb || f->width <= 0 || f->height <= 0)
        return lie_error_set(err, LIE_ERR_ARG, path, "no frame to write");
    size_t n = (size_t)f->width * (size_t)f->height * 3;
    uint8_t *rgb = malloc(n);
    if (!rgb)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    float scale = exp2f(opt ? opt->exposure : 0.0f);
    for (size_t i = 0; i < n; i++)
        rgb[i] = encode_8bit(f->rgb[i] * scale);
    lie_png_pixels px = {f->width, f->height, 8, 3, rgb, 1, opt ? opt->text : NULL, opt ? opt->n_text : 0};
    lie_status st = png_write_pixels(path, &px, err);
    free(rgb);
    return st;
}
