/* SPDX-License-Identifier: Apache-2.0 */
/* Evaluating glTF animations (glTF 2.0 §3.11 and Appendix C): a pose per
 * time, which lie-animate turns into edit operations. */
#include "scene/scene.h"

#include <stdlib.h>
#include <string.h>

void lie_pose_destroy(lie_pose *p)
{
    if (!p)
        return;
    for (int i = 0; p->weights && i < p->n_nodes; i++)
        free(p->weights[i]);
    free(p->weights);
    free(p->weights_set);
    free(p->trs);
    free(p->trs_set);
    free(p);
}

lie_mat4 lie_node_trs_matrix(const double trs[10])
{
    return lie_mat4_from_trs(trs, trs + 3, trs + 7);
}

lie_mat4 lie_node_world_matrix(const lie_scene *s, int node)
{
    lie_mat4 w = s->nodes[node].local;
    for (int p = s->nodes[node].parent, guard = 0; p >= 0 && guard < s->n_nodes; p = s->nodes[p].parent, guard++)
        w = lie_mat4_mul(&s->nodes[p].local, &w);
    return w;
}

int lie_scene_find_animation(const lie_scene *s, const char *spec)
{
    if (!spec || !*spec)
        return s->n_animations > 0 ? 0 : -1;
    for (int i = 0; i < s->n_animations; i++)
        if (s->animations[i].name && strcmp(s->animations[i].name, spec) == 0)
            return i;
    const char *d = spec[0] == '#' ? spec + 1 : spec;
    char *end;
    long i = strtol(d, &end, 10);
    if (*d && !*end && i >= 0 && i < s->n_animations)
        return (int)i;
    return -1;
}

int lie_scene_node_in_scene(const lie_scene *s, int n)
{
    if (n < 0 || n >= s->n_nodes)
        return 0;
    for (int guard = 0; s->nodes[n].parent >= 0 && guard < s->n_nodes; guard++)
        n = s->nodes[n].parent;
    for (int r = 0; r < s->n_roots; r++)
        if (s->roots[r] == n)
            return 1;
    return 0;
}

/* The key interval holding time t: k with times[k] <= t < times[k+1], and
 * the fraction u in [0, 1); k = n-1 (u = 0) at or past the last key, k = 0
 * (u = 0) before the first. */
static uint32_t find_key(const lie_anim_sampler *sp, double t, double *u)
{
    const float *x = sp->times;
    uint32_t n = sp->n_keys;
    *u = 0.0;
    if (n == 1 || t <= x[0])
        return 0;
    if (t >= x[n - 1])
        return n - 1;
    uint32_t lo = 0, hi = n - 1; /* x[lo] <= t < x[hi] */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (x[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    *u = (t - x[lo]) / ((double)x[lo + 1] - x[lo]);
    return lo;
}

/* Appendix C: slerp along the shorter arc, plain lerp (then normalised)
 * when the two are nearly parallel. */
static void slerp(const float *a, const float *b0, double u, double *out)
{
    double b[4], dot = 0.0;
    for (int k = 0; k < 4; k++)
        dot += (double)a[k] * b0[k];
    double sign = dot < 0.0 ? -1.0 : 1.0;
    for (int k = 0; k < 4; k++)
        b[k] = sign * b0[k];
    dot *= sign;
    double wa, wb;
    if (dot > 0.9995) {
        wa = 1.0 - u;
        wb = u;
    } else {
        double theta = acos(dot), st = sin(theta);
        wa = sin((1.0 - u) * theta) / st;
        wb = sin(u * theta) / st;
    }
    for (int k = 0; k < 4; k++)
        out[k] = wa * a[k] + wb * b[k];
}

static void normalize4(double *q)
{
    double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (len > 0.0)
        for (int k = 0; k < 4; k++)
            q[k] /= len;
    else
        q[0] = q[1] = q[2] = 0.0, q[3] = 1.0;
}

/* The sampler's value at time t into out[n_comp]. */
static void sample(const lie_anim_sampler *sp, int rotation, double t, double *out)
{
    int c = sp->n_comp;
    double u;
    uint32_t k = find_key(sp, t, &u);
    int last = k + 1 >= sp->n_keys;
    if (sp->interp == LIE_INTERP_CUBICSPLINE) {
        /* elements per key: in-tangent a, value v, out-tangent b (3 * c floats) */
        const float *v0 = sp->values + ((size_t)k * 3 + 1) * (size_t)c;
        if (last || u == 0.0) {
            for (int i = 0; i < c; i++)
                out[i] = v0[i];
        } else {
            const float *b0 = sp->values + ((size_t)k * 3 + 2) * (size_t)c;
            const float *a1 = sp->values + ((size_t)(k + 1) * 3) * (size_t)c;
            const float *v1 = sp->values + ((size_t)(k + 1) * 3 + 1) * (size_t)c;
            double td = (double)sp->times[k + 1] - sp->times[k];
            double u2 = u * u, u3 = u2 * u;
            double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
            for (int i = 0; i < c; i++)
                out[i] = h00 * v0[i] + h10 * td * b0[i] + h01 * v1[i] + h11 * td * a1[i];
        }
        if (rotation)
            normalize4(out);
        return;
    }
    const float *v0 = sp->values + (size_t)k * (size_t)c;
    if (sp->interp == LIE_INTERP_STEP || last || u == 0.0) {
        for (int i = 0; i < c; i++)
            out[i] = v0[i];
        if (rotation)
            normalize4(out);
        return;
    }
    const float *v1 = v0 + c;
    if (rotation) {
        slerp(v0, v1, u, out);
        normalize4(out);
        return;
    }
    for (int i = 0; i < c; i++)
        out[i] = (1.0 - u) * v0[i] + u * v1[i];
}

lie_status lie_animation_pose(const lie_scene *s, int a, double t, lie_pose **out, lie_error *err)
{
    const char *path = s->path ? s->path : "";
    *out = NULL;
    if (a < 0 || a >= s->n_animations)
        return lie_error_set(err, LIE_ERR_ARG, path, "animation %d does not exist", a);
    const lie_animation *an = &s->animations[a];
    lie_pose *p = calloc(1, sizeof *p);
    if (!p)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    p->n_nodes = s->n_nodes;
    size_t n = (size_t)s->n_nodes + 1;
    p->trs = calloc(10 * n, sizeof *p->trs);
    p->trs_set = calloc(n, 1);
    p->weights = calloc(n, sizeof *p->weights);
    p->weights_set = calloc(n, 1);
    if (!p->trs || !p->trs_set || !p->weights || !p->weights_set) {
        lie_pose_destroy(p);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    for (int i = 0; i < s->n_nodes; i++) {
        const lie_node *nd = &s->nodes[i];
        memcpy(p->trs + 10 * (size_t)i, nd->trs, sizeof nd->trs);
        if (nd->n_weights) {
            p->weights[i] = malloc(sizeof(double) * (size_t)nd->n_weights);
            if (!p->weights[i]) {
                lie_pose_destroy(p);
                return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
            }
            memcpy(p->weights[i], nd->weights, sizeof(double) * (size_t)nd->n_weights);
        }
    }
    double time = (double)an->start + t;
    for (int c = 0; c < an->n_channels; c++) {
        const lie_anim_channel *ch = &an->channels[c];
        const lie_anim_sampler *sp = &an->samplers[ch->sampler];
        if (ch->path == LIE_ANIM_WEIGHTS) {
            if (!p->weights[ch->node] || sp->n_comp != s->nodes[ch->node].n_weights)
                continue; /* the importer matched them; an edited document may not */
            sample(sp, 0, time, p->weights[ch->node]);
            p->weights_set[ch->node] = 1;
            continue;
        }
        double *trs = p->trs + 10 * (size_t)ch->node;
        int off = ch->path == LIE_ANIM_TRANSLATION ? 0 : ch->path == LIE_ANIM_ROTATION ? 3 : 7;
        sample(sp, ch->path == LIE_ANIM_ROTATION, time, trs + off);
        p->trs_set[ch->node] |= (unsigned char)(1u << ch->path);
    }
    *out = p;
    return LIE_OK;
}
