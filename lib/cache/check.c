/* SPDX-License-Identifier: Apache-2.0 */
/* The structural rules a cache's patch trees must keep (formats/lie-cache.md,
 * "What a reader must reject", 15).  The decoder runs them on every file
 * before handing out an env; the encoder runs them too, so that nothing is
 * written that could not be read back. */
#include "cache/internal.h"

#include <stdlib.h>

const char *lie_cache_check_emitter(const lie_cache_emitter *e, uint32_t n_tris)
{
    if (e->type > LIE_EMITTER_DIRECTIONAL)
        return "unknown emitter type";
    if (e->node < 0)
        return "negative node index";
    if (e->type == LIE_EMITTER_AREA) {
        if (e->n_tris == 0)
            return "area emitter without triangles";
        if ((uint64_t)e->first_tri + e->n_tris > n_tris)
            return "area emitter triangles beyond the scene's";
        if (e->n_clusters < 1 || e->n_clusters > LIE_CLUSTER_MAX || e->n_clusters > e->n_tris)
            return "cluster count out of range";
        if ((e->n_clusters == 1) != (e->partition == 0))
            return "partition digest does not fit the cluster count";
    } else if (e->first_tri != 0 || e->n_tris != 0) {
        return "point or directional emitter with triangles";
    } else if (e->n_clusters != 1 || e->partition != 0) {
        return "point or directional emitter with clusters";
    }
    return NULL;
}

static int finite_f(float f) { return f == f && f - f == 0.0f; }

const char *lie_cache_check_views(const lie_cache_views *v)
{
    if (v->n_cams == 0)
        return NULL;
    if (v->n_cams < 0 || !v->cams)
        return "bad camera array";
    if (v->width < 1 || v->width > LIE_CACHE_VIEW_MAX || v->height < 1 || v->height > LIE_CACHE_VIEW_MAX)
        return "image size out of range";
    if (v->max_depth < 0 || v->max_depth > 64)
        return "mirror depth out of range";
    for (int i = 0; i < v->n_cams; i++) {
        const lie_camera *c = &v->cams[i];
        const float f[12] = {c->eye.x, c->eye.y, c->eye.z, c->forward.x, c->forward.y, c->forward.z,
                             c->up.x,  c->up.y,  c->up.z,  c->yfov,      c->aspect,    c->ymag};
        for (int k = 0; k < 12; k++)
            if (!finite_f(f[k]) || f[k] > 1e30f || f[k] < -1e30f)
                return "a camera field is not a finite number";
        if (lie_v3_dot(c->forward, c->forward) < 0.25f || lie_v3_dot(c->up, c->up) < 0.25f)
            return "a camera's forward or up is not a unit vector";
        if (c->aspect < 0.0f || c->ymag < 0.0f || (c->ymag == 0.0f && !(c->yfov > 0.0f && c->yfov < 3.1415f)))
            return "a camera's field of view, aspect or height is out of range";
    }
    return NULL;
}

/* Per node: 0 = not reached yet, else its depth + 1. */
typedef uint8_t node_state;

lie_status lie_cache_check_env(const lie_env *env, lie_status status, const char *name, const char *prefix,
                               lie_error *err)
{
    if (env->n_clusters < 0)
        return lie_error_set(err, status, name, "%snegative cluster count", prefix);
    const uint32_t n_nodes = env->n_nodes, n_pool = env->n_pool, n_tris = env->n_tris;
    const size_t n_units = (size_t)n_tris * (size_t)env->n_clusters;
    node_state *state = calloc((size_t)n_nodes + 1, sizeof *state);
    if (!state)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "%sout of memory checking %u nodes", prefix, n_nodes);
    lie_status st = LIE_OK;

    for (size_t u = 0; u < n_units && st == LIE_OK; u++) {
        uint32_t r = env->root[u];
        if (r >= n_nodes)
            st = lie_error_set(err, status, name, "%ssection ROOTS: unit %zu: root %u beyond the %u nodes", prefix,
                               u, r, n_nodes);
        else if (state[r] && !lie_pnode_lone(&env->nodes[r])) /* lone leaves are shared (lib/lie/lie.h) */
            st = lie_error_set(err, status, name, "%ssection ROOTS: unit %zu: node %u is already a root", prefix,
                               u, r);
        else
            state[r] = 1;
    }

    /* Children always come after their parent, so one pass in index order
     * sees every node's only reference before the node itself. */
    for (uint32_t i = 0; i < n_nodes && st == LIE_OK; i++) {
        const lie_pnode *x = &env->nodes[i];
        if (!state[i]) {
            st = lie_error_set(err, status, name, "%ssection NODES: node %u belongs to no unit's tree", prefix, i);
            break;
        }
        if (x->cls >= LIE_CLASS_COUNT) {
            st = lie_error_set(err, status, name, "%ssection NODES: node %u: class %u is unknown", prefix, i,
                               x->cls);
            break;
        }
        if (x->child) {
            if (x->cls != LIE_CLASS_SPLIT)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: has children but class %s", prefix,
                                   i, lie_class_name((lie_class)x->cls));
            else if (x->child <= i)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: child %u does not come after it",
                                   prefix, i, x->child);
            else if ((uint64_t)x->child + 3u >= n_nodes)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: children %u..%u beyond the %u nodes",
                                   prefix, i, x->child, x->child + 3u, n_nodes);
            else if (x->list != 0)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: split node with a list offset",
                                   prefix, i);
            else if (state[i] > LIE_PATCH_MAX_DEPTH)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: children deeper than %d", prefix,
                                   i, LIE_PATCH_MAX_DEPTH);
            for (uint32_t k = 0; k < 4 && st == LIE_OK; k++) {
                uint32_t c = x->child + k;
                if (state[c])
                    st = lie_error_set(err, status, name, "%ssection NODES: node %u is referenced twice", prefix, c);
                else
                    state[c] = (node_state)(state[i] + 1);
            }
            continue;
        }
        switch ((lie_class)x->cls) {
        case LIE_CLASS_SPLIT:
            st = lie_error_set(err, status, name, "%ssection NODES: node %u: split node without children", prefix, i);
            break;
        case LIE_CLASS_UNLIT:
        case LIE_CLASS_VISIBLE:
        case LIE_CLASS_NONE:
            if (x->list != 0 || x->count != 0)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: %s leaf with a blocker list",
                                   prefix, i, lie_class_name((lie_class)x->cls));
            break;
        case LIE_CLASS_OCCLUDED:
        case LIE_CLASS_COMPLEX:
            if (x->list != 0)
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: %s leaf with a list offset", prefix,
                                   i, lie_class_name((lie_class)x->cls));
            break;
        case LIE_CLASS_PARTIAL:
            if (x->count == 0) {
                st = lie_error_set(err, status, name, "%ssection NODES: node %u: partial leaf with an empty list",
                                   prefix, i);
            } else if ((uint64_t)x->list + x->count > n_pool) {
                st = lie_error_set(err, status, name,
                                   "%ssection NODES: node %u: list %u+%u beyond the %u pool entries", prefix, i,
                                   x->list, x->count, n_pool);
            } else {
                const uint32_t *l = env->pool + x->list;
                for (uint32_t k = 0; k < x->count; k++) {
                    if (l[k] >= n_tris) {
                        st = lie_error_set(err, status, name,
                                           "%ssection POOL: entry %u (node %u): triangle %u beyond the %u triangles",
                                           prefix, x->list + k, i, l[k], n_tris);
                        break;
                    }
                    if (k > 0 && l[k] <= l[k - 1]) {
                        st = lie_error_set(err, status, name,
                                           "%ssection POOL: entry %u (node %u): list not strictly increasing", prefix,
                                           x->list + k, i);
                        break;
                    }
                }
            }
            break;
        }
    }
    free(state);
    return st;
}
