/* SPDX-License-Identifier: Apache-2.0 */
/* lib/patch: patch trees (§4.1.1).  One quad-tree per triangle in
 * barycentric space: a split cuts a triangle into four at its edge
 * midpoints.  Child 0, 1, 2 keep corner 0, 1, 2 of the parent; child 3 is
 * the middle triangle (m12, m02, m01).  A patch is named by its triangle and
 * the path of child digits from the root, which does not change when other
 * objects do.
 *
 * Local barycentrics: a point is (b1, b2) relative to vertices 1 and 2 of
 * the triangle it lies in (b0 = 1 - b1 - b2), as Embree reports hits. */
#ifndef LIE_PATCH_H
#define LIE_PATCH_H

#include "core/core.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

#define LIE_PATCH_MAX_DEPTH 24

/* The path of a patch: digit k (level k + 1) in bits 2k..2k+1. */
typedef struct lie_patch_path {
    uint64_t digits;
    int depth;
} lie_patch_path;

static inline lie_patch_path lie_patch_root(void)
{
    lie_patch_path p = {0, 0};
    return p;
}

static inline lie_patch_path lie_patch_child(lie_patch_path p, int digit)
{
    lie_patch_path c = {p.digits | ((uint64_t)digit << (2 * p.depth)), p.depth + 1};
    return c;
}

static inline int lie_patch_digit(lie_patch_path p, int level)
{
    return (int)((p.digits >> (2 * level)) & 3u);
}

/* Which child holds local point (b1, b2), and the point's barycentrics in
 * that child.  Points on a shared edge go to a corner child first, so every
 * point has exactly one leaf. */
static inline int lie_patch_descend(float *b1, float *b2)
{
    float x = *b1, y = *b2, z = 1.0f - x - y;
    if (z >= 0.5f) {
        *b1 = 2.0f * x;
        *b2 = 2.0f * y;
        return 0;
    }
    if (x >= 0.5f) {
        *b1 = 2.0f * x - 1.0f;
        *b2 = 2.0f * y;
        return 1;
    }
    if (y >= 0.5f) {
        *b1 = 2.0f * x;
        *b2 = 2.0f * y - 1.0f;
        return 2;
    }
    *b1 = 1.0f - 2.0f * x;
    *b2 = 1.0f - 2.0f * y;
    return 3;
}

/* The corners of a patch as barycentrics (b0, b1, b2) of its root triangle. */
void lie_patch_corners(lie_patch_path p, double corners[3][3]);

/* World-space corners of a patch of the triangle with vertices v[3]. */
void lie_patch_world(lie_patch_path p, const lie_vec3 v[3], lie_vec3 out[3]);

/* "TRI" or "TRI/0312".  Returns the length written (snprintf semantics). */
int lie_patch_format(uint32_t tri, lie_patch_path p, char *buf, size_t size);
/* Parse the same; 0 on malformed input. */
int lie_patch_parse(const char *s, uint32_t *tri, lie_patch_path *p);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
