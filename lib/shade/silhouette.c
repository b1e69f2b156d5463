/* SPDX-License-Identifier: Apache-2.0 */
/* Silhouette counting over the hierarchical sample groups (silhouette.h). */
#include "shade/silhouette.h"
#include "shade/internal.h"

#include <stdlib.h>
#include <string.h>

lie_status lie_sil_work_init(lie_sil_work *w, int cap)
{
    memset(w, 0, sizeof *w);
    if (cap < 1)
        cap = 1;
    const size_t ne = 6 * (size_t)cap;
    int ns = 8;
    while (ns < 4 * cap)
        ns *= 2;
    w->cap = cap;
    w->n_slots = ns;
    w->forms = malloc(sizeof(float) * 9 * (size_t)cap);
    w->edges = malloc(sizeof *w->edges * ne);
    w->act = malloc(sizeof *w->act * (LIE_BITMASK_MAXL + 1) * 16 * ne);
    w->slot = malloc(sizeof *w->slot * (size_t)ns);
    w->slot_tri = malloc(sizeof *w->slot_tri * (size_t)ns);
    w->ps = malloc(sizeof(float) * 3 * (size_t)cap);
    w->pt = malloc(sizeof(float) * 3 * (size_t)cap);
    w->n_vslots = 8;
    while (w->n_vslots < 16 * cap)
        w->n_vslots *= 2;
    w->vkey = malloc(sizeof *w->vkey * (size_t)w->n_vslots);
    w->cand = malloc(sizeof *w->cand * 6 * (size_t)cap);
    if (!w->forms || !w->edges || !w->act || !w->slot || !w->slot_tri || !w->ps || !w->pt || !w->vkey || !w->cand) {
        lie_sil_work_free(w);
        return LIE_ERR_NOMEM;
    }
    return LIE_OK;
}

void lie_sil_work_free(lie_sil_work *w)
{
    if (!w)
        return;
    free(w->forms);
    free(w->edges);
    free(w->act);
    free(w->slot);
    free(w->slot_tri);
    free(w->ps);
    free(w->pt);
    free(w->vkey);
    free(w->cand);
    memset(w, 0, sizeof *w);
}

typedef struct sil_query {
    const lie_bitmask *b;
    lie_sil_work *w;
    uint64_t *mask;
    int fallbacks;
} sil_query;

/* The per-sample test (lie_vis.c, in_cone) over every triangle. */
static int any_cone(const lie_sil_work *w, float s, float t)
{
    for (int j = 0; j < w->n_tris; j++) {
        const float *f = w->forms + 9 * (size_t)j;
        float e0 = fmaf(t, f[2], fmaf(s, f[1], f[0]));
        float e1 = fmaf(t, f[5], fmaf(s, f[4], f[3]));
        float e2 = fmaf(t, f[8], fmaf(s, f[7], f[6]));
        if ((e0 >= 0.0f) & (e1 >= 0.0f) & (e2 >= 0.0f))
            return 1;
    }
    return 0;
}

/* The 8 samples of level-1 group g: the count from the active edges, and
 * the per-sample test where a sample lies within a margin of one. */
static void leaf(sil_query *q, int g, const int32_t *act, int nact, int base)
{
    const lie_bitmask *b = q->b;
    const float *ss = b->ls.s + 8 * (size_t)g, *ts = b->ls.t + 8 * (size_t)g;
    unsigned on = 0, susp = 0;
    int cnt[8];
    for (int k = 0; k < 8; k++)
        cnt[k] = base;
    for (int i = 0; i < nact; i++) {
        const lie_sil_edge *E = &q->w->edges[act[i]];
        for (int k = 0; k < 8; k++) {
            const float sk = ss[k], tk = ts[k];
            const float G = fmaf(tk, E->gt, fmaf(sk, E->gs, E->g0));
            const int in = (sk >= E->a) & (sk < E->b), ext = (sk >= E->ae) & (sk < E->be);
            cnt[k] += (in & (G > 0.0f)) ? E->sigma : 0;
            susp |= (unsigned)(ext & (fabsf(G) <= E->tol)) << k;
        }
    }
    for (int k = 0; k < 8; k++)
        on |= (unsigned)(cnt[k] > 0) << k;
    for (unsigned m = susp; m; m &= m - 1) {
        const int k = __builtin_ctz(m);
        on = (on & ~(1u << k)) | (unsigned)any_cone(q->w, ss[k], ts[k]) << k;
        q->fallbacks++;
    }
    q->mask[g >> 3] |= (uint64_t)on << (8 * (g & 7));
}

/* Per active edge, for the 8 groups from g0 of level l: the groups it
 * stays active for (*keep), those wholly below it within its s range
 * (*add: sigma for each sample) and those wholly below it whose s range
 * it covers in part (*part).  Wholly above it (robustly, the bitmask's
 * margin) or outside its widened s range, it adds nothing.  NaN boxes
 * (the padding) are dropped by the caller. */
static void classify8(const lie_sil_edge *E, const float *S0, const float *S1, const float *T0, const float *T1,
                      unsigned *keep, unsigned *add, unsigned *part)
{
    unsigned above = 0, apart = 0, below = 0, inside = 0;
    for (int k = 0; k < 8; k++) {
        float p0 = S0[k] * E->gs, p1 = S1[k] * E->gs, r0 = T0[k] * E->gt, r1 = T1[k] * E->gt;
        float lo = (E->g0 + (p0 < p1 ? p0 : p1)) + (r0 < r1 ? r0 : r1);
        float hi = (E->g0 + (p0 > p1 ? p0 : p1)) + (r0 > r1 ? r0 : r1);
        above |= (unsigned)(hi < -E->tol) << k;
        apart |= (unsigned)((S1[k] < E->ae) | (S0[k] >= E->be)) << k;
        below |= (unsigned)(lo > E->tol) << k;
        inside |= (unsigned)((S0[k] >= E->a) & (S1[k] < E->b)) << k;
    }
    const unsigned live = ~(above | apart) & 0xffu;
    *add = live & below & inside;
    *part = live & below & ~inside;
    *keep = live & ~below;
}

/* Edges wholly below a group but covering its s range in part add sigma
 * to the samples whose s is in their ranges: a step function of s.  Where
 * their steps cancel over the group's s range [s0, s1] (the two edges of a
 * silhouette meeting at a vertex above the group), the sum is one number:
 * returns 1 and it in *sum.  Otherwise (0) they stay active. */
static int steps_constant(const lie_sil_edge *edges, const int32_t *e, int n, float s0, float s1, int *sum)
{
    int at0 = 0;
    for (int i = 0; i < n; i++) {
        const lie_sil_edge *E = &edges[e[i]];
        at0 += ((s0 >= E->a) & (s0 < E->b)) ? E->sigma : 0;
    }
    for (int j = 0; j < n; j++) {
        const float x[2] = {edges[e[j]].a, edges[e[j]].b};
        for (int c = 0; c < 2; c++) {
            if (!(x[c] > s0 && x[c] <= s1))
                continue;
            int v = 0;
            for (int i = 0; i < n; i++) {
                const lie_sil_edge *E = &edges[e[i]];
                v += ((x[c] >= E->a) & (x[c] < E->b)) ? E->sigma : 0;
            }
            if (v != at0)
                return 0;
        }
    }
    *sum = at0;
    return 1;
}

/* Groups g0 .. g0 + 7 of level l, with the edges still active over their
 * parent and the count they share (classify8 per edge, each edge then
 * appended to the lists of the few groups it stays active for).  A group
 * with no active edge is set whole if its count is positive; one with
 * some goes a level down, or to the samples. */
LIE_HOT static void visit(sil_query *q, int l, int g0, const int32_t *act, int nact, int base)
{
    const lie_bitmask *b = q->b;
    lie_sil_work *w = q->w;
    const size_t st = b->box_stride[l];
    const float *S0 = b->box[l] + g0, *S1 = S0 + st, *T0 = S1 + st, *T1 = T0 + st;
    const size_t ne = 6 * (size_t)w->cap;
    int32_t *list = w->act + (size_t)(l - 1) * 16 * ne; /* per group: active, then in part */
    int c[8], m[8], np[8];
    for (int k = 0; k < 8; k++)
        c[k] = base, m[k] = 0, np[k] = 0;
    for (int i = 0; i < nact; i++) {
        const lie_sil_edge *E = &w->edges[act[i]];
        unsigned kb, ab, pb;
        classify8(E, S0, S1, T0, T1, &kb, &ab, &pb);
        for (; ab; ab &= ab - 1)
            c[__builtin_ctz(ab)] += E->sigma;
        for (; kb; kb &= kb - 1) {
            const int k = __builtin_ctz(kb);
            list[(size_t)k * 2 * ne + (size_t)m[k]++] = act[i];
        }
        for (; pb; pb &= pb - 1) {
            const int k = __builtin_ctz(pb);
            list[((size_t)k * 2 + 1) * ne + (size_t)np[k]++] = act[i];
        }
    }
    const int ng = b->n_groups[l];
    for (int k = 0; k < 8 && g0 + k < ng; k++) {
        const int g = g0 + k;
        int32_t *child = list + (size_t)k * 2 * ne, n = m[k];
        if (np[k]) {
            const int32_t *pl = list + ((size_t)k * 2 + 1) * ne;
            int sum;
            if (steps_constant(w->edges, pl, np[k], S0[k], S1[k], &sum)) {
                c[k] += sum;
            } else {
                for (int i = 0; i < np[k]; i++)
                    child[n++] = pl[i];
            }
        }
        if (n == 0) {
            if (c[k] > 0)
                lie_bitmask_set_group(b, q->mask, l, g);
            continue;
        }
        if (lie_bitmask_group_full(b, q->mask, l, g))
            continue;
        if (l == 1)
            leaf(q, g, child, n, c[k]);
        else
            visit(q, l - 1, 8 * g, child, n, c[k]);
    }
}

LIE_HOT int lie_sil_mask(const lie_bitmask *b, lie_sil_work *w, uint64_t *mask)
{
    sil_query q = {b, w, mask, 0};
    if (w->n_tris == 0)
        return 0;
    /* the edges that matter to the pattern's box at all, and the count
     * of those wholly below it */
    int32_t *top = w->act + (size_t)b->levels * 16 * 6 * (size_t)w->cap;
    const float R[4][8] = {{b->ls.smin}, {b->ls.smax}, {b->ls.tmin}, {b->ls.tmax}};
    int n = 0, base = 0;
    for (int i = 0; i < w->n_edges; i++) {
        unsigned kb, ab, pb;
        classify8(&w->edges[i], R[0], R[1], R[2], R[3], &kb, &ab, &pb);
        if (ab & 1u)
            base += w->edges[i].sigma;
        else if ((kb | pb) & 1u)
            top[n++] = i;
    }
    visit(&q, b->levels, 0, top, n, base);
    mask[b->n_words - 1] &= b->last;
    return q.fallbacks;
}
