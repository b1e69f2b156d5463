/* SPDX-License-Identifier: Apache-2.0 */
/* The paper's Figure 10 false colours for local illumination environments. */
#include "lie/lie.h"
#include "shade/shade.h"

void lie_complexity_colour(int cls, uint32_t count, float rgb[3])
{
    float r = 0.0f, g = 0.0f, b = 0.0f;
    switch (cls) {
    case LIE_CLASS_VISIBLE: g = 1.0f; break;
    case LIE_CLASS_OCCLUDED: b = 1.0f; break;
    case LIE_CLASS_PARTIAL: {
        float k = count <= 1 ? 0.0f : count >= 10 ? 1.0f : (float)(count - 1) / 9.0f;
        r = g = b = k;
        break;
    }
    case LIE_CLASS_UNLIT: break;
    default: r = 1.0f; break; /* complex, or not covered by the cache */
    }
    rgb[0] = r;
    rgb[1] = g;
    rgb[2] = b;
}

void lie_complexity_colour_all(const int *cls, const uint32_t *count, int n, float rgb[3])
{
    int visible = 0, occluded = 0, partial = 0, red = 0;
    uint32_t blockers = 0;
    for (int e = 0; e < n; e++) {
        switch (cls[e]) {
        case LIE_CLASS_VISIBLE: visible++; break;
        case LIE_CLASS_OCCLUDED: occluded++; break;
        case LIE_CLASS_PARTIAL: partial++; blockers += count[e]; break;
        case LIE_CLASS_UNLIT: break;
        default: red++; break;
        }
    }
    if (red || partial) {
        lie_complexity_colour(red ? LIE_CLASS_COMPLEX : LIE_CLASS_PARTIAL, blockers, rgb);
        return;
    }
    int lit = visible + occluded;
    rgb[0] = 0.0f;
    rgb[1] = lit ? (float)visible / (float)lit : 0.0f;
    rgb[2] = lit ? (float)occluded / (float)lit : 0.0f;
}
