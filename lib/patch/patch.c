/* SPDX-License-Identifier: Apache-2.0 */
/* Patch geometry and names. */
#include "patch/patch.h"

#include <errno.h>
#include <stdlib.h>

void lie_patch_corners(lie_patch_path p, double c[3][3])
{
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int level = 0; level < p.depth; level++) {
        int d = lie_patch_digit(p, level);
        double m01[3], m02[3], m12[3], n[3][3];
        for (int k = 0; k < 3; k++) {
            m01[k] = 0.5 * (v[0][k] + v[1][k]);
            m02[k] = 0.5 * (v[0][k] + v[2][k]);
            m12[k] = 0.5 * (v[1][k] + v[2][k]);
        }
        for (int k = 0; k < 3; k++) {
            switch (d) {
            case 0: n[0][k] = v[0][k]; n[1][k] = m01[k]; n[2][k] = m02[k]; break;
            case 1: n[0][k] = m01[k]; n[1][k] = v[1][k]; n[2][k] = m12[k]; break;
            case 2: n[0][k] = m02[k]; n[1][k] = m12[k]; n[2][k] = v[2][k]; break;
            default: n[0][k] = m12[k]; n[1][k] = m02[k]; n[2][k] = m01[k]; break;
            }
        }
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                v[i][k] = n[i][k];
    }
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            c[i][k] = v[i][k];
}

void lie_patch_world(lie_patch_path p, const lie_vec3 v[3], lie_vec3 out[3])
{
    double c[3][3];
    lie_patch_corners(p, c);
    for (int i = 0; i < 3; i++)
        out[i] = lie_v3((float)(c[i][0] * v[0].x + c[i][1] * v[1].x + c[i][2] * v[2].x),
                        (float)(c[i][0] * v[0].y + c[i][1] * v[1].y + c[i][2] * v[2].y),
                        (float)(c[i][0] * v[0].z + c[i][1] * v[1].z + c[i][2] * v[2].z));
}

int lie_patch_format(uint32_t tri, lie_patch_path p, char *buf, size_t size)
{
    char digits[LIE_PATCH_MAX_DEPTH + 2];
    int n = 0;
    if (p.depth > 0) {
        digits[n++] = '/';
        for (int l = 0; l < p.depth && l < LIE_PATCH_MAX_DEPTH; l++)
            digits[n++] = (char)('0' + lie_patch_digit(p, l));
    }
    digits[n] = 0;
    return snprintf(buf, size, "%u%s", tri, digits);
}

int lie_patch_parse(const char *s, uint32_t *tri, lie_patch_path *p)
{
    if (!s || *s < '0' || *s > '9')
        return 0;
    char *end;
    errno = 0;
    unsigned long t = strtoul(s, &end, 10);
    if (errno || t > 0xFFFFFFFEul)
        return 0;
    lie_patch_path path = lie_patch_root();
    if (*end == '/') {
        const char *d = end + 1;
        if (!*d)
            return 0;
        for (; *d; d++) {
            if (*d < '0' || *d > '3' || path.depth >= LIE_PATCH_MAX_DEPTH)
                return 0;
            path = lie_patch_child(path, *d - '0');
        }
    } else if (*end) {
        return 0;
    }
    *tri = (uint32_t)t;
    *p = path;
    return 1;
}
