/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect dump: the canonical text of a cache (formats/lie-cache.md,
 * "Canonical text").  Everything is printed by content, never by storage:
 * nodes by patch name, not index, so that two caches with the same LIEs
 * dump alike however their bytes are arranged, and diff(1) of two dumps
 * shows what changed. */
#include "inspect.h"

#include <stdlib.h>
#include <string.h>

#define DUMP_VERSION 1

typedef struct pair_ref {
    lie_patch_path path;
    int e;
    uint32_t node;
} pair_ref;

typedef struct collect {
    pair_ref *v;
    size_t n, cap;
    int oom;
} collect;

static void collect_node(void *ctx, uint32_t tri, int e, lie_patch_path path, uint32_t node)
{
    (void)tri;
    collect *c = ctx;
    pair_ref r = {path, e, node};
    if (!LIE_PUSH(c->v, c->n, c->cap, r))
        c->oom = 1;
}

static int pair_cmp(const void *a, const void *b)
{
    const pair_ref *x = a, *y = b;
    int c = inspect_path_cmp(x->path, y->path);
    return c ? c : (x->e > y->e) - (x->e < y->e);
}

static void header_text(const lie_cache *c, uint64_t n_nodes, uint64_t n_leaves)
{
    const lie_build_params *p = &c->env->params;
    printf("lie-inspect-dump %d\n", DUMP_VERSION);
    printf("format-version %u\n", LIE_CACHE_VERSION);
    printf("scene-path ");
    inspect_text_string(stdout, c->scene_path);
    printf("\nscene-hash %016llx\n", (unsigned long long)c->scene_hash);
    printf("state-hash %016llx\n", (unsigned long long)c->state_hash);
    printf("triangles %u\n", c->n_tris);
    printf("emitters %d\n", c->n_emitters);
    printf("param samples %u\n", p->samples);
    printf("param max-samples %u\n", p->max_samples);
    printf("param max-blockers %u\n", p->max_blockers);
    printf("param complex-cap %u\n", p->complex_cap);
    printf("param min-patch %.9g\n", (double)p->min_patch);
    printf("param split-gain %.9g\n", (double)p->split_gain);
    printf("param blockers %s\n", inspect_mode_name(p->mode));
    printf("param frames %u\n", p->frames);
    printf("param light-samples %u\n", p->light_samples);
    printf("param cost-ns %.9g %.9g %.9g\n", (double)p->ns_segment, (double)p->ns_blocker, (double)p->ns_ray);
    printf("param complex-predict %u\n", p->complex_predict);
    printf("param whole-pixels %u\n", p->whole_pixels);
    const lie_cache_views *v = &c->views;
    printf("views %d %dx%d depth %d\n", v->n_cams, v->width, v->height, v->max_depth);
    for (int i = 0; i < v->n_cams; i++) {
        const lie_camera *k = &v->cams[i];
        printf("view %d eye %.9g %.9g %.9g forward %.9g %.9g %.9g up %.9g %.9g %.9g yfov %.9g aspect %.9g ymag %.9g\n",
               i, (double)k->eye.x, (double)k->eye.y, (double)k->eye.z, (double)k->forward.x, (double)k->forward.y,
               (double)k->forward.z, (double)k->up.x, (double)k->up.y, (double)k->up.z, (double)k->yfov,
               (double)k->aspect, (double)k->ymag);
    }
    printf("edits %d\n", c->n_edits);
    for (int i = 0; i < c->n_edits; i++) {
        printf("edit %d bytes %zu xxh3 %016llx name ", i, c->edits[i].size,
               (unsigned long long)lie_hash_bytes(c->edits[i].text, c->edits[i].size, 0));
        inspect_text_string(stdout, c->edits[i].name);
        putchar('\n');
    }
    for (int e = 0; e < c->n_emitters; e++) {
        const lie_cache_emitter *m = &c->emitters[e];
        printf("emitter %d %s node %d first-tri %u tris %u\n", e, inspect_emitter_type_name(m->type), m->node,
               m->first_tri, m->n_tris);
    }
    printf("units %llu\n", (unsigned long long)((uint64_t)c->n_tris * (uint64_t)c->env->n_clusters));
    printf("nodes %llu\n", (unsigned long long)n_nodes);
    printf("leaves %llu\n", (unsigned long long)n_leaves);
}

static void header_json(const lie_cache *c, uint64_t n_nodes, uint64_t n_leaves)
{
    const lie_build_params *p = &c->env->params;
    printf("{\"dump_version\":%d,\"format_version\":%u,\"scene_path\":", DUMP_VERSION, LIE_CACHE_VERSION);
    inspect_json_string(stdout, c->scene_path);
    printf(",\"scene_hash\":\"%016llx\",\"state_hash\":\"%016llx\",\"triangles\":%u,\"emitters\":%d",
           (unsigned long long)c->scene_hash, (unsigned long long)c->state_hash, c->n_tris, c->n_emitters);
    printf(",\"params\":{\"samples\":%u,\"max_samples\":%u,\"max_blockers\":%u,\"complex_cap\":%u,"
           "\"min_patch\":%.9g,\"split_gain\":%.9g,\"blockers\":\"%s\",\"frames\":%u,\"light_samples\":%u,"
           "\"cost_ns\":[%.9g,%.9g,%.9g],\"complex_predict\":%u,\"whole_pixels\":%u},\"views\":%d",
           p->samples, p->max_samples, p->max_blockers, p->complex_cap, (double)p->min_patch, (double)p->split_gain,
           inspect_mode_name(p->mode), p->frames, p->light_samples, (double)p->ns_segment, (double)p->ns_blocker,
           (double)p->ns_ray, p->complex_predict, p->whole_pixels, c->views.n_cams);
    printf(",\"edits\":[");
    for (int i = 0; i < c->n_edits; i++) {
        printf("%s{\"name\":", i ? "," : "");
        inspect_json_string(stdout, c->edits[i].name);
        printf(",\"bytes\":%zu,\"xxh3\":\"%016llx\"}", c->edits[i].size,
               (unsigned long long)lie_hash_bytes(c->edits[i].text, c->edits[i].size, 0));
    }
    printf("],\"emitter_table\":[");
    for (int e = 0; e < c->n_emitters; e++) {
        const lie_cache_emitter *m = &c->emitters[e];
        printf("%s{\"type\":\"%s\",\"node\":%d,\"first_tri\":%u,\"tris\":%u}", e ? "," : "",
               inspect_emitter_type_name(m->type), m->node, m->first_tri, m->n_tris);
    }
    printf("],\"units\":%llu,\"nodes\":%llu,\"leaves\":%llu,\"pairs\":[",
           (unsigned long long)((uint64_t)c->n_tris * (uint64_t)c->env->n_clusters), (unsigned long long)n_nodes,
           (unsigned long long)n_leaves);
}

int inspect_dump(const char *path, const inspect_options *o)
{
    inspect_cache l;
    lie_error err;
    if (inspect_load(path, &l, &err) != LIE_OK) {
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    const lie_cache *c = l.cache;
    const lie_env *env = c->env;
    /* the trees' nodes and leaves, not the arrays' (units share lone
     * leaves: lie_pnode_lone) */
    lie_build_stats tally;
    lie_env_stats(env, &tally);
    uint64_t nodes = 0, leaves = 0;
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        nodes += tally.patches_per_depth[d];
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        leaves += tally.pairs[k];
    if (o->json)
        header_json(c, nodes, leaves);
    else
        header_text(c, nodes, leaves);

    /* One triangle at a time: its units' nodes sorted by patch, then emitter. */
    collect col = {NULL, 0, 0, 0};
    int first = 1;
    for (uint32_t t = 0; t < env->n_tris && !col.oom; t++) {
        col.n = 0;
        for (int e = 0; e < env->n_clusters; e++) /* "emitter" in the dump: a cluster (lie_cluster) */
            inspect_walk(env, env->root[(size_t)t * (size_t)env->n_clusters + (size_t)e], t, e, lie_patch_root(),
                         collect_node, &col);
        if (col.oom)
            break;
        qsort(col.v, col.n, sizeof *col.v, pair_cmp);
        for (size_t i = 0; i < col.n; i++) {
            char name[64];
            lie_patch_format(t, col.v[i].path, name, sizeof name);
            const lie_pnode *n = &env->nodes[col.v[i].node];
            if (o->json) {
                printf("%s\n{\"patch\":\"%s\",\"emitter\":%d,", first ? "" : ",", name, col.v[i].e);
                inspect_json_node(stdout, env, n);
                putchar('}');
            } else {
                printf("%s %d ", name, col.v[i].e);
                inspect_print_node(stdout, env, n);
                putchar('\n');
            }
            first = 0;
        }
    }
    free(col.v);
    int oom = col.oom;
    inspect_unload(&l);
    if (oom) {
        lie_error_set(&err, LIE_ERR_NOMEM, path, "out of memory");
        return inspect_fail(&err, 1);
    }
    if (o->json)
        printf("\n]}\n");
    return inspect_stdout_check();
}
