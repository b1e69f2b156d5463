/* SPDX-License-Identifier: Apache-2.0 */
/* exr-layer-png IN.exr LAYER OUT.png: write an EXR layer's R, G, B channels
 * as an 8-bit PNG, values in [0, 1] scaled to 255 without a transfer curve
 * (as lie-inspect image writes its false colours), so that tests can
 * compare the two byte for byte.  Exit 0, or 2 on error. */
#include <stdio.h>
#include <stdlib.h>

#include "lie.h"

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: exr-layer-png IN.exr LAYER OUT.png\n");
        return 2;
    }
    lie_error err;
    lie_frame *f = NULL;
    if (lie_exr_read(argv[1], &f, &err) != LIE_OK) {
        char line[2200];
        lie_error_format(&err, line, sizeof line);
        fprintf(stderr, "exr-layer-png: %s\n", line);
        return 2;
    }
    const lie_aov *a = lie_frame_find_aov(f, argv[2]);
    if (!a || a->n_channels != 3) {
        fprintf(stderr, "exr-layer-png: %s: no 3-channel layer '%s'\n", argv[1], argv[2]);
        lie_frame_destroy(f);
        return 2;
    }
    size_t n = (size_t)f->width * (size_t)f->height * 3;
    uint8_t *rgb = malloc(n);
    for (size_t i = 0; rgb && i < n; i++) {
        float v = a->data[i];
        v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;
        rgb[i] = (uint8_t)(v * 255.0f + 0.5f);
    }
    int rc = rgb && lie_png_write_rgb8(argv[3], f->width, f->height, rgb, &err) == LIE_OK ? 0 : 2;
    if (rc)
        fprintf(stderr, "exr-layer-png: %s: cannot write\n", argv[3]);
    free(rgb);
    lie_frame_destroy(f);
    return rc;
}
