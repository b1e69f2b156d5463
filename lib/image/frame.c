/* SPDX-License-Identifier: Apache-2.0 */
/* Frame buffers, the sRGB transfer curves, writing by extension and auto
 * exposure. */
#include "image/image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

lie_frame *lie_frame_create(int width, int height)
{
    if (width <= 0 || height <= 0 || (size_t)width > SIZE_MAX / 3 / sizeof(float) / (size_t)height)
        return NULL;
    lie_frame *f = calloc(1, sizeof *f);
    if (!f)
        return NULL;
    f->rgb = calloc((size_t)width * (size_t)height * 3, sizeof(float));
    if (!f->rgb) {
        free(f);
        return NULL;
    }
    f->width = width;
    f->height = height;
    return f;
}

/* Copy `s` into dst[size] if it is a non-empty name that fits. */
static int copy_name(char *dst, size_t size, const char *s)
{
    size_t n = s ? strlen(s) : 0;
    if (n == 0 || n >= size)
        return 0;
    memcpy(dst, s, n + 1);
    return 1;
}

float *lie_frame_add_aov(lie_frame *f, const char *name, int n_channels,
                         const char *const *channel_names)
{
    if (!f || !name || n_channels < 1 || n_channels > LIE_AOV_MAX_CHANNELS || !channel_names)
        return NULL;
    if (lie_frame_find_aov(f, name))
        return NULL;
    lie_aov aov;
    memset(&aov, 0, sizeof aov);
    /* An empty layer name is OpenEXR's default layer (bare channel names). */
    if (strlen(name) >= sizeof aov.name)
        return NULL;
    memcpy(aov.name, name, strlen(name) + 1);
    aov.n_channels = n_channels;
    for (int c = 0; c < n_channels; c++) {
        if (!copy_name(aov.channel[c], sizeof aov.channel[c], channel_names[c]))
            return NULL;
        for (int d = 0; d < c; d++)
            if (strcmp(aov.channel[c], aov.channel[d]) == 0)
                return NULL;
    }
    size_t n = (size_t)f->width * (size_t)f->height;
    aov.data = calloc(n * (size_t)n_channels, sizeof(float));
    if (!aov.data)
        return NULL;
    lie_aov *grown = realloc(f->aovs, ((size_t)f->n_aovs + 1) * sizeof *grown);
    if (!grown) {
        free(aov.data);
        return NULL;
    }
    f->aovs = grown;
    f->aovs[f->n_aovs++] = aov;
    return aov.data;
}

const lie_aov *lie_frame_find_aov(const lie_frame *f, const char *name)
{
    if (!f || !name)
        return NULL;
    for (int i = 0; i < f->n_aovs; i++)
        if (strcmp(f->aovs[i].name, name) == 0)
            return &f->aovs[i];
    return NULL;
}

void lie_frame_destroy(lie_frame *f)
{
    if (!f)
        return;
    for (int i = 0; i < f->n_aovs; i++)
        free(f->aovs[i].data);
    free(f->aovs);
    free(f->rgb);
    free(f);
}

/* IEC 61966-2-1:1999, §5.2 (encoding) and §5.3 (decoding).  The standard's
 * breakpoints 0.0031308 / 0.04045 are rounded: there the linear and power
 * pieces miss each other by 3e-8, so the encoding would step down.  We
 * switch where the pieces actually meet (1.3e-7 below), which keeps both
 * curves continuous and monotone; values differ from the standard's by
 * less than 3e-8.  Evaluated in double so the curves invert each other to
 * float precision. */
#define SRGB_LINEAR_KNEE 0.0031306684425005883
#define SRGB_ENCODED_KNEE (12.92 * SRGB_LINEAR_KNEE)

float lie_image_srgb_encode(float x)
{
    if (!(x > 0.0f))
        return 0.0f; /* also NaN */
    if (x >= 1.0f)
        return 1.0f;
    double v = x;
    return (float)(v <= SRGB_LINEAR_KNEE ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055);
}

float lie_image_srgb_decode(float x)
{
    if (!(x > 0.0f))
        return 0.0f;
    if (x >= 1.0f)
        return 1.0f;
    double v = x;
    return (float)(v <= SRGB_ENCODED_KNEE ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4));
}

lie_status lie_frame_write(const char *path, const lie_frame *f, const lie_frame_options *opt, lie_error *err)
{
    if (!path || !f)
        return lie_error_set(err, LIE_ERR_ARG, path, "no output path or frame");
    lie_frame_format fmt = opt ? opt->format : LIE_FORMAT_AUTO;
    if (fmt == LIE_FORMAT_AUTO && !lie_frame_format_of(path, &fmt))
        return lie_error_set(err, LIE_ERR_ARG, path, "cannot write this format: the extension must be .exr or .png");
    if (fmt == LIE_FORMAT_PNG)
        return lie_png_write(path, f, opt ? &opt->png : NULL, err);
    if (fmt != LIE_FORMAT_EXR)
        return lie_error_set(err, LIE_ERR_ARG, path, "unknown image format %d", (int)fmt);
    return lie_exr_write(path, f, opt ? &opt->exr : NULL, err);
}

int lie_frame_format_parse(const char *name, lie_frame_format *out)
{
    if (name && strcmp(name, "exr") == 0)
        *out = LIE_FORMAT_EXR;
    else if (name && strcmp(name, "png") == 0)
        *out = LIE_FORMAT_PNG;
    else
        return 0;
    return 1;
}

int lie_frame_format_of(const char *path, lie_frame_format *out)
{
    if (!path)
        return 0;
    size_t n = strlen(path);
    struct stat sb;
    if (strcmp(path, "-") == 0 || (n >= 4 && strcasecmp(path + n - 4, ".exr") == 0))
        *out = LIE_FORMAT_EXR;
    else if (n >= 4 && strcasecmp(path + n - 4, ".png") == 0)
        *out = LIE_FORMAT_PNG;
    else if (stat(path, &sb) == 0 && S_ISCHR(sb.st_mode))
        *out = LIE_FORMAT_EXR; /* a device (/dev/null to time a run): the bytes of -o - */
    else
        return 0;
    return 1;
}

lie_auto_exposure lie_frame_auto_exposure(const lie_frame *f, float key)
{
    lie_auto_exposure r = {0.0f, key, 0.0, 0};
    if (!f || !f->rgb)
        return r;
    /* the coverage channel: the default layer's "A" */
    const lie_aov *cov = lie_frame_find_aov(f, "");
    int ca = -1;
    for (int c = 0; cov && c < cov->n_channels; c++)
        if (strcmp(cov->channel[c], "A") == 0)
            ca = c;
    size_t n = (size_t)f->width * (size_t)f->height;
    /* two passes in row order: the mean luminance (delta's scale), then the
     * mean log */
    double mean = 0.0, sum = 0.0;
    for (int pass = 0; pass < 2; pass++) {
        const double delta = LIE_EXPOSURE_DELTA * mean;
        r.pixels = 0;
        for (size_t i = 0; i < n; i++) {
            if (ca >= 0 && !(cov->data[i * (size_t)cov->n_channels + (size_t)ca] > 0.0f))
                continue;
            const float *p = &f->rgb[3 * i];
            double l = 0.2126 * (double)p[0] + 0.7152 * (double)p[1] + 0.0722 * (double)p[2];
            if (!(l >= 0.0)) /* NaN or negative: no light */
                l = 0.0;
            if (isinf(l))
                continue;
            if (pass == 0)
                mean += l;
            else
                sum += log(delta + l);
            r.pixels++;
        }
        if (r.pixels == 0)
            return r;
        if (pass == 0)
            mean /= (double)r.pixels;
        if (!(mean > 0.0)) { /* no light at all: nothing to expose for */
            r.pixels = 0;
            return r;
        }
    }
    if (r.pixels == 0)
        return r;
    r.log_average = exp(sum / (double)r.pixels);
    double ev = log2((double)key / r.log_average);
    r.ev = (float)(ev < -64.0 ? -64.0 : ev > 64.0 ? 64.0 : ev);
    return r;
}

void lie_auto_exposure_text(const lie_auto_exposure *ae, char *buf, size_t size)
{
    snprintf(buf, size,
             "auto: %.4f stops, from a log-average luminance of %.6g over %llu pixels and the key %.2f "
             "(Reinhard et al. 2002)",
             (double)ae->ev, ae->log_average, (unsigned long long)ae->pixels, (double)ae->key);
}
