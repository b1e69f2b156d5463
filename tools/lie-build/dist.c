/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build under mpirun: the units (triangle, emitter) in ranges handed
 * out dynamically, so they balance by their measured cost (a rank that
 * finishes early takes more).  Ranges shrink as the work runs out (guided
 * self-scheduling: a quarter of a rank's share of what is left, down to a
 * floor), so the last ones are small.  Rank 0 joins the parts in unit order
 * into the env one process builds (lie_env_join). */
#include "dist.h"

#include <stdlib.h>
#include <string.h>

typedef struct range {
    uint64_t first, count;
} range;

typedef struct job {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_build_params *p;
    const lie_pixels *px;
    range *items;
    size_t n_items;
    lie_env_part *parts;    /* rank 0: per item */
    lie_build_stats stats;  /* rank 0: the sum */
    int nomem;              /* this rank could not set up: its items fail */
} job;

typedef struct part_head {
    uint64_t first, n_units, n_nodes, n_pool;
    lie_build_stats stats;
} part_head;


static size_t plan(range *out, uint64_t n_units, int ranks)
{
    uint64_t floor_ = n_units / (64 * (uint64_t)ranks), k = 0;
    if (floor_ < 1)
        floor_ = 1;
    for (uint64_t u = 0; u < n_units; k++) {
        uint64_t left = n_units - u, c = (left + 4 * (uint64_t)ranks - 1) / (4 * (uint64_t)ranks);
        if (c < floor_)
            c = floor_;
        if (c > left)
            c = left;
        if (out)
            out[k] = (range){u, c};
        u += c;
    }
    return (size_t)k;
}

static lie_status run(void *ctx, size_t i, lie_dist_buf *out, lie_error *err)
{
    job *j = ctx;
    if (j->nomem)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    lie_env_part part;
    part_head h;
    lie_status st = lie_env_build_range_views(j->s, j->rt, j->p, j->px, j->items[i].first, j->items[i].count, &part,
                                        &h.stats, err);
    if (st != LIE_OK)
        return st;
    h.first = part.first_unit;
    h.n_units = part.n_units;
    h.n_nodes = part.n_nodes;
    h.n_pool = part.n_pool;
    if (!lie_dist_buf_add(out, &h, sizeof h) || !lie_dist_buf_add(out, part.root, sizeof *part.root * part.n_units) ||
        !lie_dist_buf_add(out, part.nodes, sizeof *part.nodes * part.n_nodes) ||
        !lie_dist_buf_add(out, part.pool, sizeof *part.pool * part.n_pool))
        st = lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    lie_env_part_free(&part);
    return st;
}

static lie_status take(void *ctx, size_t i, int rank, const unsigned char *data, size_t size, lie_error *err)
{
    job *j = ctx;
    part_head h;
    if (j->nomem)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    if (size < sizeof h)
        return lie_error_set(err, LIE_ERR_FORMAT, NULL, "rank %d sent a short part", rank);
    memcpy(&h, data, sizeof h);
    if (h.first != j->items[i].first || h.n_units != j->items[i].count || h.n_nodes >= 0xFFFFFFF0u ||
        h.n_pool >= 0xFFFFFFF0u ||
        size != sizeof h + 4 * h.n_units + sizeof(lie_pnode) * h.n_nodes + 4 * h.n_pool)
        return lie_error_set(err, LIE_ERR_FORMAT, NULL, "rank %d sent a part that is not units %llu..%llu", rank,
                             (unsigned long long)j->items[i].first,
                             (unsigned long long)(j->items[i].first + j->items[i].count));
    lie_env_part *p = &j->parts[i];
    p->first_unit = h.first;
    p->n_units = h.n_units;
    p->n_nodes = (uint32_t)h.n_nodes;
    p->n_pool = (uint32_t)h.n_pool;
    p->root = malloc(4 * h.n_units + 1);
    p->nodes = malloc(sizeof(lie_pnode) * h.n_nodes + 1);
    p->pool = malloc(4 * h.n_pool + 1);
    if (!p->root || !p->nodes || !p->pool)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    const unsigned char *q = data + sizeof h;
    memcpy(p->root, q, 4 * h.n_units);
    q += 4 * h.n_units;
    memcpy(p->nodes, q, sizeof(lie_pnode) * h.n_nodes);
    q += sizeof(lie_pnode) * h.n_nodes;
    memcpy(p->pool, q, 4 * h.n_pool);
    lie_build_stats_add(&j->stats, &h.stats);
    return LIE_OK;
}

static uint64_t units(void *ctx, size_t i)
{
    const job *j = ctx;
    return j->items ? j->items[i].count : 0;
}

lie_status build_dist(const lie_scene *s, const lie_rt *rt, const lie_build_params *p, const lie_pixels *px,
                      lie_env **out, lie_build_stats *stats, lie_error *err)
{
    *out = NULL;
    double t0 = lie_time_now();
    int ranks = lie_dist_size();
    job j = {.s = s, .rt = rt, .p = p, .px = px};
    uint64_t n_units = (uint64_t)s->n_tris * (uint64_t)s->n_clusters;
    j.n_items = plan(NULL, n_units, ranks);
    j.items = calloc(j.n_items + 1, sizeof *j.items);
    j.parts = calloc(j.n_items + 1, sizeof *j.parts);
    /* a rank short of memory still takes part: its items report it */
    j.nomem = !j.items || !j.parts;
    if (!j.nomem)
        plan(j.items, n_units, ranks);
    memset(&j.stats, 0, sizeof j.stats);
    lie_dist_work w = {j.n_items, &j, run, take, units};
    lie_status st = lie_dist_run(&w, err);
    if (st == LIE_OK && lie_dist_rank() == 0)
        st = lie_env_join(s, p, j.parts, j.n_items, out, err);
    for (size_t i = 0; j.parts && i < j.n_items; i++)
        lie_env_part_free(&j.parts[i]);
    free(j.parts);
    free(j.items);
    j.stats.seconds = lie_time_now() - t0;
    *stats = j.stats;
    return st;
}

typedef struct inputs {
    const char *input, *path_file;
    lie_scene **scene;
    lie_camera_path **cpath;
} inputs;

static lie_status load_inputs(void *ctx, const lie_scene_options *so, lie_error *err)
{
    const inputs *in = ctx;
    lie_status st = lie_scene_load(in->input, so, in->scene, err);
    if (st != LIE_OK || !in->path_file)
        return st;
    unsigned char *data = NULL;
    size_t size = 0;
    st = lie_file_set_read(so->files, in->path_file, LIE_READ_MAX_TEXT, &data, &size, err);
    if (st == LIE_OK)
        st = lie_camera_path_parse(data, size, in->path_file, in->cpath, err);
    free(data);
    return st;
}

lie_status build_load_inputs(const char *input, const char *path_file, const lie_scene_options *so,
                             lie_scene **scene, lie_camera_path **cpath, lie_error *err)
{
    inputs in = {input, path_file, scene, cpath};
    *scene = NULL;
    *cpath = NULL;
    return lie_dist_load(so, load_inputs, &in, err);
}
