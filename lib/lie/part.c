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
    uint64_t n_units = (uint64_t)s->n_tris * (uint64_t)s->n_clusters, next = 0;
    for (size_t i = 0; i < n_parts; i++) {
        if (parts[i].first_unit != next)
            return lie_error_set(err, LIE_ERR_ARG, s->path, "part %zu starts at unit %llu, expected %llu", i,
                                 (unsigned long long)parts[i].first_unit, (unsigned long long)next);
        if (!part_valid(&parts[i], s->n_tris))
            return lie_error_set(err, LIE_ERR_FORMAT, s->path, "part %zu (units %llu..%llu) is inconsistent", i,
                                 (unsigned long long)next, (unsigned long long)(next + parts[i].n_units));
        next += parts[i].n_units;
    }
    if (next != n_units)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "parts cover %llu of %llu units", (unsigned long long)next,
                             (unsigned long long)n_units);
    lie_env *env = calloc(1, sizeof *env);
    const lie_env **views = calloc(n_parts + 1, sizeof *views);
    lie_env *view = calloc(n_parts + 1, sizeof *view);
    uint64_t *counts = calloc(n_parts + 1, sizeof *counts);
    lie_status st = env && views && view && counts ? LIE_OK : LIE_ERR_NOMEM;
    uint64_t own = 0;
    for (size_t i = 0; st == LIE_OK && i < n_parts; i++) {
        view[i].root = parts[i].root;
        view[i].nodes = parts[i].nodes;
        view[i].pool = parts[i].pool;
        view[i].n_nodes = parts[i].n_nodes;
        view[i].n_pool = parts[i].n_pool;
        views[i] = &view[i];
        counts[i] = parts[i].n_units;
    }
    /* each part laid out as a build lays its units out: parts' shared
     * leaves become the env's */
    if (st == LIE_OK)
        st = lie_env_lay_out(views, counts, n_parts, NULL, env, &own);
    free(views);
    free(view);
    free(counts);
    /* one build stops past max-nodes (its own nodes: the shared leaves are
     * not made); parts were held to it one by one */
    if (st == LIE_OK && own > (p->max_nodes ? p->max_nodes : LIE_MAX_NODES_DEFAULT)) {
        lie_env_destroy(env);
        return lie_budget_error(err, s, p);
    }
    if (st != LIE_OK) {
        lie_env_destroy(env);
        return st == LIE_ERR_LIMIT ? lie_error_set(err, LIE_ERR_LIMIT, s->path, "too many nodes")
                                   : lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    lie_env_describe(env, s, p);
    *out = env;
    return LIE_OK;
}
