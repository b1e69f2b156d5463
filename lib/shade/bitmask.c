/* SPDX-License-Identifier: Apache-2.0 */
/* Light samples as bitmasks, decided exactly through boxes of compact
 * sample groups (bitmask.h). */
#include "shade/bitmask.h"
#include "shade/internal.h"

#include <stdlib.h>
#include <string.h>

/* ---- the order ------------------------------------------------------------ */

typedef struct bm_pt {
    float s, t;
    int i;
} bm_pt;

/* total orders (ties by the other coordinate, then the index): the same
 * order on every run whatever qsort does with equal keys */
static int by_first(float a1, float a2, int ai, float b1, float b2, int bi)
{
    if (a1 != b1)
        return a1 < b1 ? -1 : 1;
    if (a2 != b2)
        return a2 < b2 ? -1 : 1;
    return (ai > bi) - (ai < bi);
}

static int by_s(const void *a, const void *b)
{
    const bm_pt *p = a, *q = b;
    return by_first(p->s, p->t, p->i, q->s, q->t, q->i);
}

static int by_t(const void *a, const void *b)
{
    const bm_pt *p = a, *q = b;
    return by_first(p->t, p->s, p->i, q->t, q->s, q->i);
}

/* Order p[lo, hi) so that every aligned run of 8^k samples is compact: a
 * kd split across the wider extent, at a multiple of the largest power of
 * 8 below the range's size (so no aligned run straddles a split).  lo is a
 * multiple of that unit. */
static void order(bm_pt *p, int lo, int hi)
{
    const int m = hi - lo;
    if (m <= 8)
        return;
    int unit = 8;
    while (unit * 8 < m)
        unit *= 8;
    const int k = (m + unit - 1) / unit;
    const int left = unit * ((k + 1) / 2);
    float s0 = p[lo].s, s1 = s0, t0 = p[lo].t, t1 = t0;
    for (int i = lo + 1; i < hi; i++) {
        s0 = p[i].s < s0 ? p[i].s : s0, s1 = p[i].s > s1 ? p[i].s : s1;
        t0 = p[i].t < t0 ? p[i].t : t0, t1 = p[i].t > t1 ? p[i].t : t1;
    }
    qsort(p + lo, (size_t)m, sizeof *p, s1 - s0 >= t1 - t0 ? by_s : by_t);
    order(p, lo, lo + left);
    order(p, lo + left, hi);
}

static void permute(const float *src, const bm_pt *p, int n, float *dst)
{
    for (int i = 0; i < n; i++)
        dst[i] = src[p[i].i];
}

lie_status lie_bitmask_create(const lie_light_samples *ls, lie_bitmask **out)
{
    *out = NULL;
    if (!ls->planar || ls->n < 1)
        return LIE_OK;
    const int n = ls->n;
    lie_bitmask *b = calloc(1, sizeof *b);
    bm_pt *p = malloc(sizeof *p * (size_t)n);
    if (!b || !p || lie_light_samples_alloc(&b->ls, n) != LIE_OK) {
        free(b), free(p);
        return LIE_ERR_NOMEM;
    }
    for (int i = 0; i < n; i++)
        p[i] = (bm_pt){ls->s[i], ls->t[i], i};
    order(p, 0, n);
    /* the pattern in this order */
    lie_light_samples *q = &b->ls;
    const float *src[11] = {ls->x, ls->y, ls->z, ls->nx, ls->ny, ls->nz, ls->r, ls->g, ls->b, ls->s, ls->t};
    float *dst[11] = {q->x, q->y, q->z, q->nx, q->ny, q->nz, q->r, q->g, q->b, q->s, q->t};
    for (int k = 0; k < 11; k++)
        permute(src[k], p, n, dst[k]);
    free(p);
    q->n = n;
    q->uniform = ls->uniform;
    q->planar = 1;
    memcpy(q->po, ls->po, sizeof q->po);
    memcpy(q->pu, ls->pu, sizeof q->pu);
    memcpy(q->pv, ls->pv, sizeof q->pv);
    memcpy(q->pn, ls->pn, sizeof q->pn);
    q->smin = ls->smin, q->smax = ls->smax, q->tmin = ls->tmin, q->tmax = ls->tmax;
    for (int i = n; i < lie_light_samples_padded(q); i++)
        q->s[i] = q->t[i] = NAN; /* no form admits them (shade.h) */
    b->n = n;
    b->n_words = (n + 63) / 64;
    b->last = n % 64 ? (~0ull >> (64 - n % 64)) : ~0ull;
    b->s_abs = fmaxf(fabsf(ls->smin), fabsf(ls->smax));
    b->t_abs = fmaxf(fabsf(ls->tmin), fabsf(ls->tmax));
    /* the boxes, level by level; padded to whole 8s with NaN boxes, which
     * every test takes as outside */
    int count = (n + 7) / 8, l = 1;
    for (;; l++) {
        if (l > LIE_BITMASK_MAXL) {
            lie_bitmask_destroy(b);
            return LIE_ERR_ARG; /* more than 8^8 samples */
        }
        b->n_groups[l] = count;
        size_t stride = ((size_t)count + 7) & ~(size_t)7;
        b->box_stride[l] = stride;
        b->box[l] = malloc(sizeof(float) * 4 * stride);
        if (!b->box[l]) {
            lie_bitmask_destroy(b);
            return LIE_ERR_NOMEM;
        }
        float *s0 = b->box[l], *s1 = s0 + stride, *t0 = s1 + stride, *t1 = t0 + stride;
        for (size_t g = 0; g < stride; g++)
            s0[g] = s1[g] = t0[g] = t1[g] = NAN;
        for (int g = 0; g < count; g++) {
            if (l == 1) {
                int i0 = 8 * g, i1 = i0 + 8 < n ? i0 + 8 : n;
                float a = q->s[i0], c = a, d = q->t[i0], e = d;
                for (int i = i0 + 1; i < i1; i++) {
                    a = fminf(a, q->s[i]), c = fmaxf(c, q->s[i]);
                    d = fminf(d, q->t[i]), e = fmaxf(e, q->t[i]);
                }
                s0[g] = a, s1[g] = c, t0[g] = d, t1[g] = e;
            } else {
                const size_t ps = b->box_stride[l - 1];
                const float *c0 = b->box[l - 1], *c1 = c0 + ps, *d0 = c1 + ps, *d1 = d0 + ps;
                int k0 = 8 * g, k1 = k0 + 8 < b->n_groups[l - 1] ? k0 + 8 : b->n_groups[l - 1];
                float a = c0[k0], c = c1[k0], d = d0[k0], e = d1[k0];
                for (int k = k0 + 1; k < k1; k++) {
                    a = fminf(a, c0[k]), c = fmaxf(c, c1[k]);
                    d = fminf(d, d0[k]), e = fmaxf(e, d1[k]);
                }
                s0[g] = a, s1[g] = c, t0[g] = d, t1[g] = e;
            }
        }
        if (count <= 8)
            break;
        count = (count + 7) / 8;
    }
    b->levels = l;
    *out = b;
    return LIE_OK;
}

void lie_bitmask_destroy(lie_bitmask *b)
{
    if (!b)
        return;
    for (int l = 0; l <= LIE_BITMASK_MAXL; l++)
        free(b->box[l]);
    lie_light_samples_free(&b->ls);
    free(b);
}

/* ---- one blocker ---------------------------------------------------------- */

/* A linear form, and which box corner gives its least and greatest value. */
typedef struct bm_form {
    float a, s, t, tol;
    int s_lo_is_s0, t_lo_is_t0;
} bm_form;

enum { MAXF = 5 };

typedef struct bm_query {
    const lie_bitmask *b;
    bm_form f[MAXF]; /* three edges; then g and g2 for a blocker reaching the plane */
    int depth;
    uint64_t *mask;
    uint32_t unsure;
} bm_query;

static void query_init(bm_query *q, const lie_bitmask *b, const float *f, int depth, uint64_t *mask);

static bm_form form_of(const lie_bitmask *b, const float *f)
{
    bm_form r = {f[0], f[1], f[2], 0.0f, f[1] >= 0.0f, f[2] >= 0.0f};
    /* covers the rounding of a box's bound and of a sample's fmaf */
    r.tol = 1e-5f * (fabsf(f[0]) + fabsf(f[1]) * b->s_abs + fabsf(f[2]) * b->t_abs);
    return r;
}

/* The 8 samples of level-1 group g, one by one, as the per-sample path
 * tests them (lie_vis.c, in_cone): the bits they set. */
static void leaf(bm_query *q, int g)
{
    const float *ss = q->b->ls.s + 8 * (size_t)g, *ts = q->b->ls.t + 8 * (size_t)g;
    const bm_form *f = q->f;
    unsigned byte = 0, unsure = 0;
    for (int i = 0; i < 8; i++) {
        float s = ss[i], t = ts[i];
        int in = 1;
        for (int j = 0; j < 3; j++)
            in &= fmaf(t, f[j].t, fmaf(s, f[j].s, f[j].a)) >= 0.0f;
        if (q->depth) {
            float g1 = fmaf(t, f[3].t, fmaf(s, f[3].s, f[3].a)), g2 = fmaf(t, f[4].t, fmaf(s, f[4].s, f[4].a));
            unsure |= (unsigned)(in & (g1 < 0.0f) & (g2 > 0.0f)) << i;
            in &= g1 >= 0.0f;
        }
        byte |= (unsigned)in << i;
    }
    q->mask[g >> 3] |= (uint64_t)byte << (8 * (g & 7));
    q->unsure |= unsure;
}

/* The 64 samples of word w one by one.  Deciding its 8 groups of level 1
 * by their boxes first cost more than it saved (the bit loops' branches
 * and one more call): 10-15% slower per blocker, measured at 256 to 4096
 * samples. */
static void word(bm_query *q, int w)
{
    const int g1 = 8 * w + 8 < q->b->n_groups[1] ? 8 * w + 8 : q->b->n_groups[1];
    for (int g = 8 * w; g < g1; g++)
        leaf(q, g);
}

/* Which of the 8 boxes of level l from group g0 lie wholly inside the
 * blocker (bits of *in) and which wholly outside it (bits of *out; NaN
 * boxes, the padding, are outside).  A form's least and greatest values
 * over a box come from its corners: a + min(s s0, s s1) + min(t t0, t t1). */
static void classify8(const bm_query *q, int l, int g0, unsigned *in, unsigned *out)
{
    const lie_bitmask *b = q->b;
    const size_t st = b->box_stride[l];
    const float *s0 = b->box[l] + g0, *s1 = s0 + st, *t0 = s1 + st, *t1 = t0 + st;
    const int nf = q->depth ? 5 : 3;
    unsigned bi = 0, bo = 0;
    for (int k = 0; k < 8; k++) {
        float lo[MAXF], hi[MAXF];
        for (int j = 0; j < nf; j++) {
            const bm_form *f = &q->f[j];
            float p0 = s0[k] * f->s, p1 = s1[k] * f->s, r0 = t0[k] * f->t, r1 = t1[k] * f->t;
            /* NaN boxes stay NaN: comparisons, not fminf */
            lo[j] = (f->a + (p0 < p1 ? p0 : p1)) + (r0 < r1 ? r0 : r1);
            hi[j] = (f->a + (p0 > p1 ? p0 : p1)) + (r0 > r1 ? r0 : r1);
        }
        int in_ = 1, out_ = 0;
        for (int j = 0; j < 3; j++) {
            in_ &= lo[j] > q->f[j].tol;
            out_ |= !(hi[j] >= -q->f[j].tol);
        }
        if (q->depth) {
            in_ &= lo[3] > q->f[3].tol;
            out_ |= (hi[3] < -q->f[3].tol) & (hi[4] < -q->f[4].tol);
        }
        bi |= (unsigned)(in_ & !out_) << k;
        bo |= (unsigned)out_ << k;
    }
    *in = bi;
    *out = bo;
    *in &= ~*out;
}

/* The words group g of level l >= 2 covers: [*w0, *w1). */
static void group_words(const lie_bitmask *b, int l, int g, size_t *w0, size_t *w1)
{
    size_t per = (size_t)1 << (3 * (l - 2));
    *w0 = (size_t)g * per;
    *w1 = *w0 + per < (size_t)b->n_words ? *w0 + per : (size_t)b->n_words;
}

int lie_bitmask_group_full(const lie_bitmask *b, const uint64_t *mask, int l, int g)
{
    if (l == 1)
        return ((mask[g >> 3] >> (8 * (g & 7))) & 0xffu) == 0xffu;
    size_t w0, w1;
    group_words(b, l, g, &w0, &w1);
    for (size_t w = w0; w < w1; w++)
        if (mask[w] != ~0ull)
            return 0;
    return 1;
}

void lie_bitmask_set_group(const lie_bitmask *b, uint64_t *mask, int l, int g)
{
    if (l == 1) {
        mask[g >> 3] |= 0xffull << (8 * (g & 7));
        return;
    }
    size_t w0, w1;
    group_words(b, l, g, &w0, &w1);
    for (size_t w = w0; w < w1; w++)
        mask[w] = ~0ull;
}

/* Groups g0 .. g0 + 7 of level l: inside sets their bits, outside is
 * skipped, the rest goes a level down (unless its bits are all set). */
LIE_HOT static void visit(bm_query *q, int l, int g0)
{
    unsigned in, out;
    classify8(q, l, g0, &in, &out);
    unsigned rest = ~(in | out) & 0xffu;
    if (l == 1) {
        /* group g0 + k is byte k of word g0 / 8 */
        uint64_t *w = &q->mask[g0 >> 3];
        uint64_t set = 0;
        for (unsigned m = in; m; m &= m - 1)
            set |= 0xffull << (8 * __builtin_ctz(m));
        *w |= set;
        for (unsigned m = rest; m; m &= m - 1) {
            int k = __builtin_ctz(m);
            if (((*w >> (8 * k)) & 0xffu) != 0xffu)
                leaf(q, g0 + k);
        }
        return;
    }
    for (unsigned m = in; m; m &= m - 1)
        lie_bitmask_set_group(q->b, q->mask, l, g0 + __builtin_ctz(m));
    for (unsigned m = rest; m; m &= m - 1) {
        int g = g0 + __builtin_ctz(m);
        if (lie_bitmask_group_full(q->b, q->mask, l, g))
            continue;
        if (l == 2)
            word(q, g);
        else
            visit(q, l - 1, 8 * g);
    }
}

static void query_init(bm_query *q, const lie_bitmask *b, const float *f, int depth, uint64_t *mask)
{
    q->b = b;
    q->depth = depth;
    q->mask = mask;
    q->unsure = 0;
    for (int j = 0; j < (depth ? 5 : 3); j++) {
        q->f[j] = form_of(b, f + 3 * j);
    }
}

LIE_HOT void lie_bitmask_cone(const lie_bitmask *b, const float f[9], uint64_t *mask)
{
    bm_query q;
    query_init(&q, b, f, 0, mask);
    visit(&q, b->levels, 0);
    mask[b->n_words - 1] &= b->last;
}

LIE_HOT int lie_bitmask_cone_depth(const lie_bitmask *b, const float f[15], uint64_t *mask)
{
    bm_query q;
    query_init(&q, b, f, 1, mask);
    visit(&q, b->levels, 0);
    mask[b->n_words - 1] &= b->last;
    return q.unsure != 0;
}

int lie_bitmask_all(const lie_bitmask *b, const uint64_t *mask)
{
    for (int w = 0; w + 1 < b->n_words; w++)
        if (mask[w] != ~0ull)
            return 0;
    return mask[b->n_words - 1] == b->last;
}

/* eight lanes, as unblocked_sum in direct.c: the same order, the same bits */
LIE_HOT float lie_bitmask_unblocked_sum(const float *w, const uint64_t *mask, int n)
{
    int i = 0;
    float acc[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    for (; i + 8 <= n; i += 8) {
        const unsigned byte = (unsigned)((mask[i >> 6] >> (i & 63)) & 0xffu);
        for (int k = 0; k < 8; k++)
            acc[k] += (byte >> k) & 1u ? 0.0f : w[i + k];
    }
    float sum = lie_sum8(acc);
    for (; i < n; i++)
        sum += (mask[i >> 6] >> (i & 63)) & 1u ? 0.0f : w[i];
    return sum;
}

/* Sum of G over the samples whose bit is `blocked`, a word at a time and
 * eight samples at a time within it, skipping what holds none: the cost
 * follows the words the set touches. */
static float lambert_sum(const lie_bitmask *b, const lie_planar_lambert *P, const uint64_t *mask, int blocked)
{
    float acc[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    const lie_planar_lambert Pv = *P;
    const float *ss = b->ls.s, *ts = b->ls.t;
    for (int w = 0; w < b->n_words; w++) {
        uint64_t m = blocked ? mask[w] : ~mask[w];
        if (w == b->n_words - 1)
            m &= b->last;
        for (int k = 0; m; k++, m >>= 8) {
            const unsigned byte = (unsigned)(m & 0xffu);
            if (!byte)
                continue;
            const float *s = ss + 64 * (size_t)w + 8 * k, *t = ts + 64 * (size_t)w + 8 * k;
#pragma omp simd
            for (int j = 0; j < 8; j++) {
                float g = lie_planar_lambert_g(Pv, s[j], t[j]);
                acc[j] += (byte >> j) & 1u ? g : 0.0f;
            }
        }
    }
    return lie_sum8(acc);
}

LIE_HOT double lie_bitmask_lambert(const lie_bitmask *b, const lie_planar_lambert *P, const uint64_t *mask, double omega,
                           double area)
{
    int blocked = 0;
    for (int w = 0; w < b->n_words; w++)
        blocked += __builtin_popcountll(mask[w]);
    if (blocked == 0)
        return omega;
    if (blocked >= b->n)
        return 0.0;
    const double k = area / b->n;
    if (2 * blocked <= b->n) {
        double r = omega - k * (double)lambert_sum(b, P, mask, 1);
        return r > 0.0 ? r : 0.0;
    }
    return k * (double)lambert_sum(b, P, mask, 0);
}
