/* SPDX-License-Identifier: Apache-2.0 */
/* Joining parts of an env built apart (lie_env_build_range): a build lays
 * units out in unit order, each unit's nodes and blocker lists contiguous,
 * so the env of one build is the parts' arrays concatenated, each part's
 * child and list offsets moved by where its arrays land. */
#include "lie/internal.h"

#include <stdlib.h>
#include <string.h>

void lie_forest_free(uint32_t *root, lie_pnode *nodes, uint32_t *pool)
{
    free(root);
    free(nodes);
    free(pool);
}

void lie_env_part_free(lie_env_part *part)
{
    if (!part)
        return;
    lie_forest_free(part->root, part->nodes, part->pool);
    memset(part, 0, sizeof *part);
}

/* Offsets inside the part, so a joined env never points outside itself. */
static int part_valid(const lie_env_part *p, uint32_t n_tris)
{
    for (uint64_t i = 0; i < p->n_units; i++)
        if (p->root[i] >= p->n_nodes)
            return 0;
    for (uint32_t i = 0; i < p->n_nodes; i++) {
        const lie_pnode *x = &p->nodes[i];
        if (x->child && (x->child <= i || x->child > p->n_nodes - 4 || p->n_nodes < 4))
            return 0;
        if (!x->child && x->cls == LIE_CLASS_PARTIAL &&
            (x->list > p->n_pool || x->count > p->n_pool - x->list))
            return 0;
        if (x->cls >= LIE_CLASS_COUNT)
            return 0;
    }
    for (uint32_t i = 0; i < p->n_pool; i++)
        if (p->pool[i] >= n_tris)
            return 0;
    return 1;
}

lie_status lie_env_join(const lie_scene *s, const lie_build_params *p, const lie_env_part *parts, size_t n_parts,
                        lie_env **out, lie_error *err)
{
    *out = NULL;
    uint64_t n_units = (uint64_t)s->n_tris * (uint64_t)s->n_clusters, next = 0, nodes = 0, pool = 0;
    for (size_t i = 0; i < n_parts; i++) {
        if (parts[i].first_unit != next)
            return lie_error_set(err, LIE_ERR_ARG, s->path, "part %zu starts at unit %llu, expected %llu", i,
                                 (unsigned long long)parts[i].first_unit, (unsigned long long)next);
        if (!part_valid(&parts[i], s->n_tris))
            return lie_error_set(err, LIE_ERR_FORMAT, s->path, "part %zu (units %llu..%llu) is inconsistent", i,
                                 (unsigned long long)next, (unsigned long long)(next + parts[i].n_units));
        next += parts[i].n_units;
        nodes += parts[i].n_nodes;
        pool += parts[i].n_pool;
    }
    if (next != n_units)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "parts cover %llu of %llu units", (unsigned long long)next,
                             (unsigned long long)n_units);
    /* one build stops past max-nodes; parts were held to it one by one */
    if (nodes > (p->max_nodes ? p->max_nodes : LIE_MAX_NODES_DEFAULT))
        return lie_budget_error(err, s, p);
    if (nodes >= 0xFFFFFFF0u || pool >= 0xFFFFFFF0u)
        return lie_error_set(err, LIE_ERR_LIMIT, s->path, "too many nodes");
    lie_env *env = calloc(1, sizeof *env);
    if (env) {
        env->root = malloc(sizeof *env->root * ((size_t)n_units + 1));
        env->nodes = malloc(sizeof *env->nodes * ((size_t)nodes + 1));
        env->pool = malloc(sizeof *env->pool * ((size_t)pool + 1));
    }
    if (!env || !env->root || !env->nodes || !env->pool) {
        lie_env_destroy(env);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    lie_env_describe(env, s, p);
    uint32_t nb = 0, pb = 0;
    for (size_t i = 0; i < n_parts; i++) {
        const lie_env_part *q = &parts[i];
        for (uint64_t u = 0; u < q->n_units; u++)
            env->root[q->first_unit + u] = nb + q->root[u];
        for (uint32_t k = 0; k < q->n_nodes; k++) {
            lie_pnode x = q->nodes[k];
            if (x.child)
                x.child += nb;
            if (!x.child && x.cls == LIE_CLASS_PARTIAL)
                x.list += pb;
            env->nodes[nb + k] = x;
        }
        if (q->n_pool)
            memcpy(env->pool + pb, q->pool, sizeof *env->pool * q->n_pool);
        nb += q->n_nodes;
        pb += q->n_pool;
    }
    env->n_nodes = nb;
    env->n_pool = pb;
    *out = env;
    return LIE_OK;
}
