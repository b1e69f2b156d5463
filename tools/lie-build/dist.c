/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build under mpirun: the units (triangle, emitter) in ranges handed
 * out dynamically (a rank that finishes early takes more), costliest
 * first by the library's estimate (lie_env_unit_weights, the order a
 * build's threads take triangles in), so that no long range starts last
 * while the other ranks idle.  Each range holds about 1/(16 ranks) of the
 * estimated cost and of the units (or one unit), so the estimate's errors
 * even out over the last, cheapest ranges.  Rank 0 joins the parts in
 * unit order into the env one process builds (lie_env_join).
 *
 * Why by cost: units differ by orders of magnitude (the large walls and
 * floors of a room subdivide deepest).  On museum1, units handed out in
 * unit order in shrinking ranges (a quarter of a rank's share of what is
 * left) put 70% of the build into the first range: 2 ranks took 1.57
 * times as long as 2 threads (docs/mpi.md). */
#include "dist.h"

#include <stdlib.h>
#include <string.h>

typedef struct range {
    uint64_t first, count;
    uint64_t slot;   /* its place in unit order: parts[slot] */
    double weight;   /* estimated cost */
} range;

typedef struct job {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_build_params *p;
    const lie_pixels *px;
    range *items;           /* in the order handed out */
    size_t n_items;
    lie_env_part *parts;    /* rank 0: per range, in unit order */
    lie_build_stats stats;  /* rank 0: the sum */
    int nomem;              /* this rank could not plan: its items fail */
} job;

typedef struct part_head {
    uint64_t first, n_units, n_nodes, n_pool;
    lie_build_stats stats;
} part_head;

#define RANGES_PER_RANK 16

static int heavier(const void *a, const void *b)
{
    const range *x = a, *y = b;
    if (x->weight != y->weight)
        return x->weight > y->weight ? -1 : 1;
    return x->slot < y->slot ? -1 : x->slot > y->slot;
}

/* The ranges, costliest first (ties in unit order), in j->items; the same
 * on every rank (the same binary and inputs: lie_dist_check). */
static lie_status plan(job *j, uint64_t n_units, int ranks, lie_error *err)
{
    double *w = malloc(sizeof *w * ((size_t)n_units + 1));
    j->items = calloc((size_t)n_units + 1, sizeof *j->items);
    lie_status st = w && j->items ? lie_env_unit_weights(j->s, j->p, j->px, 0, n_units, w, err)
                                  : lie_error_set(err, LIE_ERR_NOMEM, j->s->path, "out of memory");
    if (st != LIE_OK) {
        free(w);
        return st;
    }
    double total = 0.0;
    for (uint64_t u = 0; u < n_units; u++)
        total += w[u];
    uint64_t parts = RANGES_PER_RANK * (uint64_t)ranks;
    double max_w = total / (double)parts;
    uint64_t max_n = (n_units + parts - 1) / parts, k = 0;
    for (uint64_t u = 0; u < n_units; k++) {
        range *r = &j->items[k];
        *r = (range){u, 0, k, 0.0};
        while (u < n_units && (r->count == 0 || (r->weight + w[u] <= max_w && r->count < max_n))) {
            r->weight += w[u++];
            r->count++;
        }
    }
    free(w);
    j->n_items = (size_t)k;
    qsort(j->items, j->n_items, sizeof *j->items, heavier);
    return LIE_OK;
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
    lie_env_part *p = &j->parts[j->items[i].slot];
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
    job j = {.s = s, .rt = rt, .p = p, .px = px};
    uint64_t n_units = (uint64_t)s->n_tris * (uint64_t)s->n_clusters;
    /* a rank that cannot plan still takes part: a worker's items then
     * report it, and rank 0 hands out nothing and reports its own */
    lie_error plan_err;
    lie_error_clear(&plan_err);
    lie_status planned = plan(&j, n_units, lie_dist_size(), &plan_err);
    if (planned == LIE_OK && !(j.parts = calloc(j.n_items + 1, sizeof *j.parts)))
        planned = lie_error_set(&plan_err, LIE_ERR_NOMEM, s->path, "out of memory");
    j.nomem = planned != LIE_OK;
    memset(&j.stats, 0, sizeof j.stats);
    lie_dist_work w = {j.nomem ? 0 : j.n_items, &j, run, take, units};
    lie_status st = lie_dist_run(&w, err);
    if (st == LIE_OK && lie_dist_rank() == 0 && planned != LIE_OK) {
        *err = plan_err;
        st = planned;
    }
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
