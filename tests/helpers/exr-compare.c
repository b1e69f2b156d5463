/* exr-compare A.exr B.exr MAX_ANY MAX_2PCT: the share of pixels that differ
 * at all, and by more than 2% (in any channel, relative to the larger value,
 * values under 0.01 counting as 0.01), between two EXR images; exit 0 when
 * both shares are within the limits, 1 otherwise, 2 on error. */
#include <stdio.h>
#include <stdlib.h>

#include "lie.h"

int main(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: exr-compare A.exr B.exr MAX_ANY MAX_2PCT\n");
        return 2;
    }
    lie_error err;
    lie_frame *a = NULL, *b = NULL;
    if (lie_exr_read(argv[1], &a, &err) != LIE_OK || lie_exr_read(argv[2], &b, &err) != LIE_OK) {
        char line[2200];
        lie_error_format(&err, line, sizeof line);
        fprintf(stderr, "exr-compare: %s\n", line);
        return 2;
    }
    if (a->width != b->width || a->height != b->height) {
        fprintf(stderr, "exr-compare: sizes differ\n");
        return 2;
    }
    size_t n = (size_t)a->width * (size_t)a->height, any = 0, big = 0;
    for (size_t i = 0; i < n; i++) {
        int d = 0, d2 = 0;
        for (int k = 0; k < 3; k++) {
            float x = a->rgb[3 * i + k], y = b->rgb[3 * i + k];
            float m = fmaxf(fmaxf(fabsf(x), fabsf(y)), 0.01f);
            d |= x != y;
            d2 |= fabsf(x - y) > 0.02f * m;
        }
        any += (size_t)d;
        big += (size_t)d2;
    }
    double fa = (double)any / (double)n, fb = (double)big / (double)n;
    printf("%zu of %zu pixels differ (%.4f%%), %zu by more than 2%% (%.4f%%)\n", any, n, 100.0 * fa, big, 100.0 * fb);
    lie_frame_destroy(a);
    lie_frame_destroy(b);
    return fa <= atof(argv[3]) && fb <= atof(argv[4]) ? 0 : 1;
}
