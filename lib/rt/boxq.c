/* SPDX-License-Identifier: Apache-2.0 */
/* Box queries over the triangles' bounding boxes (lib/rt/boxq.h).
 *
 * Shaft culling (§4.1.2, lib/lie/cull.c) asks for the triangles whose
 * bounding boxes meet a box, several times per patch-emitter pair.
 * Embree's point query answers it only through the sphere around the box,
 * which for a long shaft slab holds many times the box's volume: profiled
 * on a 250k-triangle atrium it was a fifth of a build in the callback that
 * throws the extra triangles away.  This hierarchy prunes by the box
 * itself.
 *
 * Built once, on one thread, in a fixed order (triangles sorted by the
 * Morton code of their box centres, split at the median, four to a leaf),
 * so it is the same on every run; the answer is a set (callers sort it),
 * the same set Embree's query and its box test gave. */
#include "rt/boxq.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LEAF 4

typedef struct bnode {
    float lo[3], hi[3];
    uint32_t index; /* inner: the right child (the left one follows); leaf: first primitive */
    uint32_t count; /* leaf: primitives; inner: 0 */
} bnode;

struct lie_boxq {
    bnode *nodes;
    uint32_t n_nodes;
    float (*box)[6]; /* per primitive, in leaf order: lo xyz, hi xyz */
    uint32_t *tri;   /* per primitive: its triangle */
};

/* Spread the low 10 bits of v to every third bit. */
static uint32_t spread3(uint32_t v)
{
    v &= 0x3ffu;
    v = (v | (v << 16)) & 0x030000ffu;
    v = (v | (v << 8)) & 0x0300f00fu;
    v = (v | (v << 4)) & 0x030c30c3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Node for primitives [a, b), at nodes[*next]; returns its index. */
static uint32_t build_node(lie_boxq *q, uint32_t a, uint32_t b, uint32_t *next)
{
    uint32_t self = (*next)++;
    bnode *nd = &q->nodes[self];
    if (b - a <= LEAF) {
        nd->index = a;
        nd->count = b - a;
        for (int k = 0; k < 3; k++) { /* NaN fails every comparison: such a box is left out */
            nd->lo[k] = INFINITY;
            nd->hi[k] = -INFINITY;
        }
        for (uint32_t i = a; i < b; i++)
            for (int k = 0; k < 3; k++) {
                nd->lo[k] = q->box[i][k] < nd->lo[k] ? q->box[i][k] : nd->lo[k];
                nd->hi[k] = q->box[i][3 + k] > nd->hi[k] ? q->box[i][3 + k] : nd->hi[k];
            }
        return self;
    }
    uint32_t mid = a + (b - a) / 2;
    uint32_t l = build_node(q, a, mid, next);
    uint32_t r = build_node(q, mid, b, next);
    nd = &q->nodes[self]; /* the array does not move, but keep it plain */
    nd->index = r;
    nd->count = 0;
    for (int k = 0; k < 3; k++) {
        nd->lo[k] = q->nodes[l].lo[k] < q->nodes[r].lo[k] ? q->nodes[l].lo[k] : q->nodes[r].lo[k];
        nd->hi[k] = q->nodes[l].hi[k] > q->nodes[r].hi[k] ? q->nodes[l].hi[k] : q->nodes[r].hi[k];
    }
    return self;
}

lie_status lie_boxq_build(const lie_vec3 *tri_p, uint32_t n, lie_boxq **out)
{
    *out = NULL;
    lie_boxq *q = calloc(1, sizeof *q);
    uint64_t *key = malloc(sizeof *key * ((size_t)n + 1));
    float(*box)[6] = malloc(sizeof *box * ((size_t)n + 1));
    if (q) {
        q->box = malloc(sizeof *q->box * ((size_t)n + 1));
        q->tri = malloc(sizeof *q->tri * ((size_t)n + 1));
        q->nodes = malloc(sizeof *q->nodes * (2 * (size_t)n + 1));
    }
    if (!q || !key || !box || !q->box || !q->tri || !q->nodes) {
        free(key);
        free(box);
        lie_boxq_destroy(q);
        return LIE_ERR_NOMEM;
    }
    lie_box3 cb = lie_box3_empty();
    for (uint32_t t = 0; t < n; t++) {
        const lie_vec3 *P = &tri_p[3 * (size_t)t];
        /* exactly the bounds lie_rt_box_query always tested */
        lie_vec3 lo = lie_v3_min(P[0], lie_v3_min(P[1], P[2]));
        lie_vec3 hi = lie_v3_max(P[0], lie_v3_max(P[1], P[2]));
        box[t][0] = lo.x, box[t][1] = lo.y, box[t][2] = lo.z;
        box[t][3] = hi.x, box[t][4] = hi.y, box[t][5] = hi.z;
        lie_vec3 c = lie_v3_scale(lie_v3_add(lo, hi), 0.5f);
        if (isfinite(c.x) && isfinite(c.y) && isfinite(c.z))
            lie_box3_grow(&cb, c);
    }
    lie_vec3 ext = lie_box3_is_empty(&cb) ? lie_v3(1, 1, 1) : lie_v3_sub(cb.hi, cb.lo);
    for (uint32_t t = 0; t < n; t++) {
        float c[3] = {0.5f * (box[t][0] + box[t][3]), 0.5f * (box[t][1] + box[t][4]), 0.5f * (box[t][2] + box[t][5])};
        float lo[3] = {cb.lo.x, cb.lo.y, cb.lo.z}, e[3] = {ext.x, ext.y, ext.z};
        uint32_t code = 0;
        for (int k = 0; k < 3; k++) {
            float f = e[k] > 0.0f ? (c[k] - lo[k]) / e[k] * 1023.0f : 0.0f;
            uint32_t v = f >= 1023.0f ? 1023u : f >= 0.0f ? (uint32_t)f : 0u; /* NaN: 0 */
            code |= spread3(v) << k;
        }
        key[t] = ((uint64_t)code << 32) | t;
    }
    qsort(key, n, sizeof *key, cmp_u64);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t = (uint32_t)key[i];
        q->tri[i] = t;
        memcpy(q->box[i], box[t], sizeof box[t]);
    }
    free(key);
    free(box);
    uint32_t next = 0;
    if (n > 0)
        build_node(q, 0, n, &next);
    q->n_nodes = next;
    *out = q;
    return LIE_OK;
}

void lie_boxq_query(const lie_boxq *q, lie_box3 box, lie_rt_box_fn fn, void *ctx)
{
    if (!q->n_nodes)
        return;
    const float blo[3] = {box.lo.x, box.lo.y, box.lo.z}, bhi[3] = {box.hi.x, box.hi.y, box.hi.z};
    uint32_t stack[64];
    int sp = 0;
    uint32_t at = 0;
    for (;;) {
        const bnode *nd = &q->nodes[at];
        int meets = nd->lo[0] <= bhi[0] && nd->hi[0] >= blo[0] && nd->lo[1] <= bhi[1] && nd->hi[1] >= blo[1] &&
                    nd->lo[2] <= bhi[2] && nd->hi[2] >= blo[2];
        if (meets && nd->count) {
            for (uint32_t i = nd->index; i < nd->index + nd->count; i++) {
                const float *b = q->box[i];
                if (b[0] <= bhi[0] && b[3] >= blo[0] && b[1] <= bhi[1] && b[4] >= blo[1] && b[2] <= bhi[2] &&
                    b[5] >= blo[2])
                    fn(ctx, q->tri[i]);
            }
        } else if (meets) {
            stack[sp++] = nd->index; /* the right child; the left one follows this node */
            at++;
            continue;
        }
        if (sp == 0)
            break;
        at = stack[--sp];
    }
}

void lie_boxq_destroy(lie_boxq *q)
{
    if (!q)
        return;
    free(q->nodes);
    free(q->box);
    free(q->tri);
    free(q);
}
