/* PNG previews through libpng, encoded in memory and written atomically. */
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
static int encode_png(png_sink *s, int width, int height, const uint8_t *rgb)
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
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* sRGB chunk plus the matching gAMA/cHRM for readers that ignore sRGB. */
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    for (int y = 0; y < height; y++)
        png_write_row(png, rgb + (size_t)y * (size_t)width * 3);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 1;
}

lie_status lie_png_write_rgb8(const char *path, int width, int height, const uint8_t *rgb,
                              lie_error *err)
{
    if (!path || !rgb || width <= 0 || height <= 0)
        return lie_error_set(err, LIE_ERR_ARG, path, "no image to write");
    /* PNG's limit is 2^31-1; libpng's default user limit is 10^6. */
    if (width > 1000000 || height > 1000000)
        return lie_error_set(err, LIE_ERR_LIMIT, path, "image too large for PNG: %dx%d", width,
                             height);
    png_sink s;
    memset(&s, 0, sizeof s);
    if (!encode_png(&s, width, height, rgb)) {
        free(s.data);
        if (s.oom || !s.msg[0])
            return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory encoding PNG");
        return lie_error_set(err, LIE_ERR_IO, path, "cannot encode PNG: %s", s.msg);
    }
    lie_atomic_file af;
    lie_status st = lie_atomic_open(&af, path, err);
    if (st == LIE_OK) {
        if (fwrite(s.data, 1, s.size, af.fp) != s.size) {
            lie_atomic_abort(&af);
            st = lie_error_set(err, LIE_ERR_IO, path, "write failed");
        } else {
            st = lie_atomic_commit(&af, err);
        }
    }
    free(s.data);
    return st;
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
    lie_status st = lie_png_write_rgb8(path, f->width, f->height, rgb, err);
    free(rgb);
    return st;
}
