/* SPDX-License-Identifier: Apache-2.0 */
/* exr-compare A.exr B.exr MAX_ANY MAX_2PCT: the share of pixels that differ
 * at all, and by more than 2% (in any channel, relative to the larger value,
 * values under 0.01 counting as 0.01), between two EXR images; exit 0 when
 * both shares are within the limits, 1 otherwise, 2 on error.
 *
 * exr-compare --error REF.exr TEST.exr: per-pixel error of TEST against REF
 * over lit pixels, as one JSON line: {"lit":N,"rmse":R,"p99":P,"over2":S}.
 * A pixel is lit when its reference luminance exceeds 1% of the image's
 * mean; its error is |Y_test - Y_ref| / Y_ref (Y = Rec. 709 luminance);
 * rmse is the root mean square of these, p99 their 99th percentile, over2
 * the share above 0.02.  Exit 0, or 2 on error. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lie.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double luminance(const float *p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

static int error_stats(const lie_frame *a, const lie_frame *b)
{
    size_t n = (size_t)a->width * (size_t)a->height, lit = 0, over = 0;
    double mean = 0.0, sq = 0.0;
    for (size_t i = 0; i < n; i++)
        mean += luminance(&a->rgb[3 * i]);
    mean /= (double)(n ? n : 1);
    double *e = malloc(sizeof *e * (n ? n : 1));
    if (!e)
        return 2;
    for (size_t i = 0; i < n; i++) {
        double yr = luminance(&a->rgb[3 * i]), yt = luminance(&b->rgb[3 * i]);
        if (!(yr > 0.01 * mean))
            continue;
        double r = fabs(yt - yr) / yr;
        e[lit++] = r;
        sq += r * r;
        over += r > 0.02;
    }
    qsort(e, lit, sizeof *e, cmp_double);
    double p99 = lit ? e[(size_t)(0.99 * (double)(lit - 1) + 0.5)] : 0.0;
    printf("{\"lit\":%zu,\"rmse\":%.6f,\"p99\":%.6f,\"over2\":%.6f}\n", lit, lit ? sqrt(sq / (double)lit) : 0.0,
           p99, lit ? (double)over / (double)lit : 0.0);
    free(e);
    return 0;
}

int main(int argc, char **argv)
{
    int error_mode = argc == 4 && strcmp(argv[1], "--error") == 0;
    if (argc != 5 && !error_mode) {
        fprintf(stderr, "usage: exr-compare A.exr B.exr MAX_ANY MAX_2PCT | --error REF.exr TEST.exr\n");
        return 2;
    }
    if (error_mode)
        argv++;
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
    if (error_mode) {
        int rc = error_stats(a, b);
        lie_frame_destroy(a);
        lie_frame_destroy(b);
        return rc;
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
