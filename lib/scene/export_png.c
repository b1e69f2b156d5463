/* PNG output for the glTF exporter (gltf.cpp): texture code values to a
 * PNG stream through libpng.  lib/scene does not depend on lib/image, so
 * this small writer lives here.  No tIME or text chunks: the bytes are a
 * function of the pixels. */
#include "scene/scene.h"

#include <png.h>
#include <string.h>

typedef struct png_state {
    char msg[256];
} png_state;

static void on_png_error(png_structp png, png_const_charp msg)
{
    png_state *st = png_get_error_ptr(png);
    if (st && !st->msg[0])
        snprintf(st->msg, sizeof st->msg, "%s", msg ? msg : "libpng error");
    png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp msg) {}

/* Kept apart from the caller so that nothing it owns is live across setjmp. */
static int encode(png_state *st, FILE *fp, int width, int height, int bits, int channels,
                  const void *codes)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, st, on_png_error, on_png_warning);
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
    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, bits,
                 channels == 4 ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (bits == 16) {
        /* PNG stores 16-bit samples big-endian; ours are in host order */
        const uint16_t one = 1;
        unsigned char little;
        memcpy(&little, &one, 1);
        if (little)
            png_set_swap(png);
    }
    size_t row = (size_t)width * (size_t)channels * (size_t)(bits / 8);
    for (int y = 0; y < height; y++)
        png_write_row(png, (png_const_bytep)codes + (size_t)y * row);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 1;
}

lie_status lie_scene_png_write(FILE *fp, const char *path, int width, int height, int bits, int channels,
                               const void *codes, lie_error *err)
{
    if (width <= 0 || height <= 0 || (bits != 8 && bits != 16) || (channels != 3 && channels != 4))
        return lie_error_set(err, LIE_ERR_ARG, path, "PNG of %dx%d, %d-bit, %d channels: not supported",
                             width, height, bits, channels);
    png_state st;
    memset(&st, 0, sizeof st);
    if (!encode(&st, fp, width, height, bits, channels, codes))
        return lie_error_set(err, LIE_ERR_IO, path, "cannot write PNG: %s", st.msg[0] ? st.msg : "out of memory");
    return LIE_OK;
}
