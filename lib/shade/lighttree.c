/* SPDX-License-Identifier: Apache-2.0 */
/* The light BVH sampler (sampler.h): emitters in a binary tree whose
 * nodes bound their lights' power, box and normal cone (Conty Estevez and
 * Kulla 2018, "Importance Sampling of Many Lights with Adaptive Tree
 * Splitting"; pbrt-v4's BVHLightSampler).  At a shading point a sample
 * descends from the root, at each node to a child in proportion to the
 * child's importance (lie_light_importance), so an emitter is chosen in
 * O(log emitters) with a probability that follows its distance, facing
 * and power.  Lights at infinity have no box: they share a fixed part of
 * the samples, as in pbrt-v4.
 *
 * The n samples of a point descend together: a node holding the samples
 * in the interval [lo, hi) of [0, 1) splits it between its children in
 * proportion to their importance, and a node that holds no sample is not
 * visited.  A leaf's interval is its emitter's probability; the samples
 * in it are the systematic count (sampler.h). */
#include "shade/sampler.h"

#include <stdlib.h>
#include <string.h>

typedef struct tree_node {
    lie_light_bounds b;
    lie_light_cone k; /* b as the importance reads it */
    int child[2];  /* interior; -1 at a leaf */
    int emitter;   /* leaf */
} tree_node;

typedef struct light_tree {
    tree_node *nodes;
    int n_nodes, root;      /* root -1: no finite light */
    int *infinite;          /* the lights at infinity */
    int n_infinite;
} light_tree;

/* ---- the cone of two cones (pbrt-v4's DirectionCone Union) ------------ */

static float angle_of(float c) { return acosf(fminf(fmaxf(c, -1.0f), 1.0f)); }

static void cone_union(const lie_light_bounds *a, const lie_light_bounds *b, lie_light_bounds *out)
{
    if (a->cos_o <= -1.0f || b->cos_o <= -1.0f) {
        memcpy(out->axis, a->cos_o <= -1.0f ? a->axis : b->axis, sizeof out->axis);
        out->cos_o = -1.0f;
        return;
    }
    float ta = angle_of(a->cos_o), tb = angle_of(b->cos_o);
    float td = angle_of(a->axis[0] * b->axis[0] + a->axis[1] * b->axis[1] + a->axis[2] * b->axis[2]);
    if (fminf(td + tb, (float)M_PI) <= ta) {
        memcpy(out->axis, a->axis, sizeof out->axis);
        out->cos_o = a->cos_o;
        return;
    }
    if (fminf(td + ta, (float)M_PI) <= tb) {
        memcpy(out->axis, b->axis, sizeof out->axis);
        out->cos_o = b->cos_o;
        return;
    }
    float to = 0.5f * (ta + td + tb);
    /* the axis turned from a's toward b's by to - ta, about their normal */
    float w[3] = {a->axis[1] * b->axis[2] - a->axis[2] * b->axis[1], a->axis[2] * b->axis[0] - a->axis[0] * b->axis[2],
                  a->axis[0] * b->axis[1] - a->axis[1] * b->axis[0]};
    float wl = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (to >= (float)M_PI || !(wl > 1e-7f)) {
        memcpy(out->axis, a->axis, sizeof out->axis);
        out->cos_o = -1.0f;
        return;
    }
    for (int k = 0; k < 3; k++)
        w[k] /= wl;
    float r = to - ta, cr = cosf(r), sr = sinf(r);
    const float *v = a->axis;
    float kxv[3] = {w[1] * v[2] - w[2] * v[1], w[2] * v[0] - w[0] * v[2], w[0] * v[1] - w[1] * v[0]};
    float kv = w[0] * v[0] + w[1] * v[1] + w[2] * v[2];
    float ax[3], al = 0.0f;
    for (int k = 0; k < 3; k++) {
        ax[k] = v[k] * cr + kxv[k] * sr + w[k] * kv * (1.0f - cr); /* Rodrigues */
        al += ax[k] * ax[k];
    }
    al = sqrtf(al);
    for (int k = 0; k < 3; k++)
        out->axis[k] = ax[k] / al;
    /* a little wider, against rounding */
    out->cos_o = fmaxf(cosf(to) - 1e-4f, -1.0f);
}

static void bounds_union(const lie_light_bounds *a, const lie_light_bounds *b, lie_light_bounds *out)
{
    lie_light_bounds r;
    memset(&r, 0, sizeof r);
    if (!(a->phi > 0.0f) || !(b->phi > 0.0f)) {
        *out = a->phi > 0.0f ? *a : *b;
        return;
    }
    for (int k = 0; k < 3; k++) {
        r.lo[k] = fminf(a->lo[k], b->lo[k]);
        r.hi[k] = fmaxf(a->hi[k], b->hi[k]);
    }
    cone_union(a, b, &r);
    r.cos_e = fminf(a->cos_e, b->cos_e);
    r.phi = a->phi + b->phi;
    r.two_sided = a->two_sided | b->two_sided;
    *out = r;
}

/* pbrt-v4's cost of a node (EvaluateCost): its power times the solid
 * angle its cone of emission covers, times its box's surface area. */
static double node_cost(const lie_light_bounds *b)
{
    double to = angle_of(b->cos_o), te = angle_of(b->cos_e);
    double tw = fmin(to + te, M_PI), so = sin(to);
    double m = 2.0 * M_PI * (1.0 - cos(to)) +
               M_PI / 2.0 * (2.0 * tw * so - cos(to - 2.0 * tw) - 2.0 * to * so + cos(to));
    double d[3] = {b->hi[0] - b->lo[0], b->hi[1] - b->lo[1], b->hi[2] - b->lo[2]};
    double area = 2.0 * (d[0] * d[1] + d[1] * d[2] + d[0] * d[2]);
    return b->phi * m * (area > 0.0 ? area : 1e-12);
}

/* ---- the build: binned splits of the centroids, 12 bins per axis ------- */

#define BINS 12

typedef struct build_ctx {
    light_tree *t;
    const lie_light_bounds *B;
    int *ids;
} build_ctx;

static float centroid(const lie_light_bounds *b, int a) { return 0.5f * (b->lo[a] + b->hi[a]); }

static int build(build_ctx *bc, int first, int count)
{
    light_tree *t = bc->t;
    int me = t->n_nodes++;
    tree_node *nd = &t->nodes[me];
    if (count == 1) {
        nd->b = bc->B[bc->ids[first]];
        nd->child[0] = nd->child[1] = -1;
        nd->emitter = bc->ids[first];
        return me;
    }
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = first; i < first + count; i++)
        for (int a = 0; a < 3; a++) {
            float c = centroid(&bc->B[bc->ids[i]], a);
            clo[a] = fminf(clo[a], c);
            chi[a] = fmaxf(chi[a], c);
        }
    double best = INFINITY;
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3; a++) {
        if (!(chi[a] > clo[a]))
            continue;
        lie_light_bounds bin[BINS];
        int has[BINS] = {0};
        memset(bin, 0, sizeof bin);
        for (int i = first; i < first + count; i++) {
            const lie_light_bounds *b = &bc->B[bc->ids[i]];
            int k = (int)((float)BINS * (centroid(b, a) - clo[a]) / (chi[a] - clo[a]));
            k = k < 0 ? 0 : k >= BINS ? BINS - 1 : k;
            if (has[k])
                bounds_union(&bin[k], b, &bin[k]);
            else
                bin[k] = *b;
            has[k] = 1;
        }
        for (int split = 1; split < BINS; split++) {
            lie_light_bounds L, R;
            int hl = 0, hr = 0;
            for (int k = 0; k < BINS; k++) {
                if (!has[k])
                    continue;
                if (k < split) {
                    if (hl)
                        bounds_union(&L, &bin[k], &L);
                    else
                        L = bin[k];
                    hl = 1;
                } else {
                    if (hr)
                        bounds_union(&R, &bin[k], &R);
                    else
                        R = bin[k];
                    hr = 1;
                }
            }
            if (!hl || !hr)
                continue;
            double c = node_cost(&L) + node_cost(&R);
            if (c < best) {
                best = c;
                best_axis = a;
                best_bin = split;
            }
        }
    }
    int mid = first + count / 2;
    if (best_axis >= 0) {
        /* partition by the bin, stably: the same tree for any input order */
        const int a = best_axis;
        int *tmp = bc->ids + first, l = 0;
        int *right = malloc(sizeof(int) * (size_t)count);
        int r = 0;
        if (right) {
            for (int i = 0; i < count; i++) {
                const lie_light_bounds *b = &bc->B[tmp[i]];
                int k = (int)((float)BINS * (centroid(b, a) - clo[a]) / (chi[a] - clo[a]));
                k = k < 0 ? 0 : k >= BINS ? BINS - 1 : k;
                if (k < best_bin)
                    tmp[l++] = tmp[i];
                else
                    right[r++] = tmp[i];
            }
            memcpy(tmp + l, right, sizeof(int) * (size_t)r);
            free(right);
            if (l > 0 && l < count)
                mid = first + l;
        }
    }
    int c0 = build(bc, first, mid - first);
    int c1 = build(bc, mid, first + count - mid);
    nd = &t->nodes[me];
    nd->child[0] = c0;
    nd->child[1] = c1;
    nd->emitter = -1;
    bounds_union(&t->nodes[c0].b, &t->nodes[c1].b, &nd->b);
    return me;
}

static void tree_destroy(void *state)
{
    light_tree *t = state;
    if (!t)
        return;
    free(t->nodes);
    free(t->infinite);
    free(t);
}

static lie_status tree_create(const lie_light_bounds *B, int n_lights, void **state)
{
    light_tree *t = calloc(1, sizeof *t);
    int *ids = malloc(sizeof(int) * ((size_t)n_lights + 1));
    if (t) {
        t->nodes = malloc(sizeof *t->nodes * (2 * (size_t)n_lights + 1));
        t->infinite = malloc(sizeof(int) * ((size_t)n_lights + 1));
    }
    if (!t || !ids || !t->nodes || !t->infinite) {
        free(ids);
        tree_destroy(t);
        return LIE_ERR_NOMEM;
    }
    int n = 0;
    for (int e = 0; e < n_lights; e++) {
        if (!(B[e].phi > 0.0f))
            continue; /* no light: never chosen */
        if (B[e].infinite)
            t->infinite[t->n_infinite++] = e;
        else
            ids[n++] = e;
    }
    build_ctx bc = {t, B, ids};
    t->root = n > 0 ? build(&bc, 0, n) : -1;
    free(ids);
    for (int i = 0; i < t->n_nodes; i++)
        lie_light_cone_of(&t->nodes[i].b, &t->nodes[i].k);
    *state = t;
    return LIE_OK;
}

typedef struct descent {
    const light_tree *t;
    lie_vec3 p, n;
    int count;
    double u;
    lie_light_pick *out;
    int k;
} descent;

/* The samples in [lo, hi) of node i, reached with probability pmf; blo
 * and bhi are the systematic counts below lo and hi (a split point's
 * count is found once, for both children). */
static void descend(descent *d, int i, double lo, double hi, int blo, int bhi, double pmf)
{
    int have = bhi - blo;
    if (have <= 0 || !(pmf > 0.0))
        return;
    const tree_node *nd = &d->t->nodes[i];
    if (nd->child[0] < 0) {
        d->out[d->k].emitter = nd->emitter;
        d->out[d->k].count = have;
        d->out[d->k].pmf = (float)pmf;
        d->k++;
        return;
    }
    float w0 = lie_light_cone_importance(&d->t->nodes[nd->child[0]].k, d->p, &d->n);
    float w1 = lie_light_cone_importance(&d->t->nodes[nd->child[1]].k, d->p, &d->n);
    double sum = (double)w0 + (double)w1;
    if (!(sum > 0.0))
        return; /* nothing below can reach p */
    double p0 = w0 / sum, split = lo + (hi - lo) * p0;
    if (w0 > 0.0f && w1 > 0.0f) {
        int bs = lie_systematic_below(split, d->count, d->u);
        descend(d, nd->child[0], lo, split, blo, bs, pmf * p0);
        descend(d, nd->child[1], split, hi, bs, bhi, pmf * (1.0 - p0));
    } else if (w0 > 0.0f) {
        descend(d, nd->child[0], lo, hi, blo, bhi, pmf * p0);
    } else {
        descend(d, nd->child[1], lo, hi, blo, bhi, pmf * (1.0 - p0));
    }
}

static int tree_distribute(const void *state, lie_vec3 p, lie_vec3 n_, int n, double u, lie_light_pick *out)
{
    const light_tree *t = state;
    descent d = {t, p, n_, n, u, out, 0};
    /* lights at infinity: an equal share each of the part 1 / (1 + theirs) */
    double p_inf = t->n_infinite ? (double)t->n_infinite / (double)(t->n_infinite + (t->root >= 0 ? 1 : 0)) : 0.0;
    for (int j = 0; j < t->n_infinite; j++) {
        double lo = p_inf * j / t->n_infinite, hi = p_inf * (j + 1) / t->n_infinite;
        int have = lie_systematic_below(hi, n, u) - lie_systematic_below(lo, n, u);
        if (have > 0) {
            out[d.k].emitter = t->infinite[j];
            out[d.k].count = have;
            out[d.k].pmf = (float)(p_inf / t->n_infinite);
            d.k++;
        }
    }
    if (t->root >= 0) {
        float w = lie_light_cone_importance(&t->nodes[t->root].k, p, &n_);
        if (w > 0.0f)
            descend(&d, t->root, p_inf, 1.0, lie_systematic_below(p_inf, n, u), lie_systematic_below(1.0, n, u),
                    1.0 - p_inf);
    }
    return d.k;
}

const lie_light_sampler_class lie_light_sampler_tree = {"tree", tree_create, tree_destroy, tree_distribute};
