/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect verify and summary: the library validates, this prints. */
#include "inspect.h"


/* Label of blocker-list histogram bucket b: 1, 2, 3-4, 5-8, ..., >65536. */
#define HIST_BUCKETS 18
static void hist_label(int b, char *buf, size_t size)
{
    if (b == 0)
        snprintf(buf, size, "1");
    else if (b == 1)
        snprintf(buf, size, "2");
    else if (b < HIST_BUCKETS - 1)
        snprintf(buf, size, "%u-%u", (1u << (b - 1)) + 1u, 1u << b);
    else
        snprintf(buf, size, ">%u", 1u << (HIST_BUCKETS - 2));
}

static double share(uint64_t part, uint64_t whole) { return whole ? 100.0 * (double)part / (double)whole : 0.0; }

/* ---- verify ----------------------------------------------------------------- */

/* The scene must be the one the cache was built for: lib/cache loads it
 * (checking its hash against scene_hash), replays the edit log (checking
 * the result against state_hash and the counts); the emitters table is
 * compared here. */
static int check_scene(const char *cache_path, const lie_cache *c, const inspect_options *o)
{
    lie_scene_options so = lie_scene_options_default();
    so.allow_external_uris = o->external;
    lie_scene *s = NULL;
    lie_error err;
    if (lie_cache_load_scene(c, cache_path, o->scene, &so, &s, &err) != LIE_OK)
        return inspect_fail(&err, 1);
    if (!o->quiet)
        lie_print_scene_warnings(inspect_prog, s, cache_path);
    int rc = 0;
    for (int e = 0; e < c->n_emitters && e < s->n_emitters; e++) {
        const lie_emitter *se = &s->emitters[e];
        const lie_cache_emitter *ce = &c->emitters[e];
        if ((uint32_t)se->type != ce->type || se->node != ce->node || se->first_tri != ce->first_tri ||
            se->n_tris != ce->n_tris) {
            fprintf(stderr,
                    "%s: %s: emitter %d differs: the scene has %s node %d triangles %u+%u, the cache %s node %d "
                    "triangles %u+%u\n",
                    inspect_prog, cache_path, e, inspect_emitter_type_name((uint32_t)se->type), se->node, se->first_tri,
                    se->n_tris, inspect_emitter_type_name(ce->type), ce->node, ce->first_tri, ce->n_tris);
            rc = 1;
            break;
        }
    }
    lie_scene_destroy(s);
    return rc;
}

int inspect_verify(const char *path, const inspect_options *o)
{
    inspect_cache l;
    lie_error err;
    if (inspect_load(path, &l, &err) != LIE_OK) {
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    int rc = o->scene ? check_scene(path, l.cache, o) : 0;
    if (rc == 0 && !o->quiet) {
        if (o->scene)
            printf("%s: valid, built for %s\n", path, o->scene);
        else
            printf("%s: valid\n", path);
    }
    inspect_unload(&l);
    return rc ? rc : inspect_stdout_check();
}

/* ---- summary ---------------------------------------------------------------- */

/* Units whose root is class none: outside lie-build's views, or not built
 * yet by an interrupted build (env->partial). */
static uint64_t units_none(const lie_env *env)
{
    uint64_t n = 0, units = (uint64_t)env->n_tris * (uint64_t)env->n_clusters;
    for (uint64_t u = 0; u < units; u++)
        n += env->nodes[env->root[u]].cls == LIE_CLASS_NONE;
    return n;
}

static void summary_text(const char *path, const inspect_cache *l, const lie_build_stats *st,
                         const lie_cache_section *sec, int n_sec)
{
    const lie_cache *c = l->cache;
    const lie_env *env = c->env;
    const lie_build_params *p = &env->params;
    uint64_t leaves = 0, nodes = 0; /* the trees' (lone units share a leaf: lie_pnode_lone) */
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        leaves += st->pairs[k];
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        nodes += st->patches_per_depth[d];
    int by_type[3] = {0, 0, 0};
    for (int e = 0; e < c->n_emitters; e++)
        if (c->emitters[e].type < 3)
            by_type[c->emitters[e].type]++;
    fputs("cache           ", stdout);
    inspect_text_string(stdout, path);
    printf(" (%zu bytes, format version %u)\n", l->size, LIE_CACHE_VERSION);
    fputs("scene           ", stdout);
    inspect_text_string(stdout, c->scene_path); /* from the file: may hold control bytes */
    putchar('\n');
    printf("scene hash      %016llx\n", (unsigned long long)c->scene_hash);
    printf("state hash      %016llx\n", (unsigned long long)c->state_hash);
    printf("edits           %d\n", c->n_edits);
    for (int i = 0; i < c->n_edits; i++) {
        printf("  %d  ", i);
        inspect_text_string(stdout, c->edits[i].name); /* from the file, as the scene's path */
        printf(" (%zu bytes)\n", c->edits[i].size);
    }
    char mp[32];
    inspect_fmt_float(p->min_patch, mp, sizeof mp);
    printf("parameters      samples %u, max-samples %u, max-blockers %u, complex-cap %u, min-patch %s, "
           "split-gain %.9g, blockers %s, complex-predict %s, whole-pixels %u\n",
           p->samples, p->max_samples, p->max_blockers, p->complex_cap, mp, (double)p->split_gain,
           inspect_mode_name(p->mode), p->complex_predict ? "on" : "off", p->whole_pixels);
    printf("triangles       %u\n", c->n_tris);
    printf("emitters        %d (%d area, %d point, %d directional)\n", c->n_emitters, by_type[0], by_type[1],
           by_type[2]);
    printf("units           %llu\n", (unsigned long long)((uint64_t)c->n_tris * (uint64_t)env->n_clusters));
    if (env->partial)
        printf("partial         yes: an interrupted lie-build, %llu units not built yet (lie-build --resume "
               "completes it; until then lie-render answers them from the whole scene)\n",
               (unsigned long long)units_none(env));
    printf("nodes           %llu (%llu leaves; %u stored, lone units sharing theirs)\n", (unsigned long long)nodes,
           (unsigned long long)leaves, env->n_nodes);
    printf("pool entries    %u\n", env->n_pool);
    printf("pairs by class (leaves):\n");
    for (int k = 0; k < LIE_CLASS_COUNT; k++) {
        if (k == LIE_CLASS_SPLIT)
            continue;
        printf("  %-10s %12llu  %6.2f%%\n", lie_class_name((lie_class)k), (unsigned long long)st->pairs[k],
               share(st->pairs[k], leaves));
    }
    printf("patches per depth:\n");
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        if (st->patches_per_depth[d])
            printf("  %-10d %12llu\n", d, (unsigned long long)st->patches_per_depth[d]);
    uint64_t partial = st->pairs[LIE_CLASS_PARTIAL];
    printf("blocker lists   %llu, mean length %.2f\n", (unsigned long long)partial,
           partial ? (double)st->blocker_total / (double)partial : 0.0);
    for (int b = 0; b < HIST_BUCKETS; b++) {
        if (!st->list_hist[b])
            continue;
        char label[32];
        hist_label(b, label, sizeof label);
        printf("  %-10s %12llu  %6.2f%%\n", label, (unsigned long long)st->list_hist[b],
               share(st->list_hist[b], partial));
    }
    printf("sections:\n");
    for (int i = 0; i < n_sec; i++)
        printf("  %-10s %12llu bytes at %llu\n", sec[i].name, (unsigned long long)sec[i].size,
               (unsigned long long)sec[i].offset);
}

static void summary_json(const char *path, const inspect_cache *l, const lie_build_stats *st,
                         const lie_cache_section *sec, int n_sec)
{
    const lie_cache *c = l->cache;
    const lie_env *env = c->env;
    const lie_build_params *p = &env->params;
    uint64_t leaves = 0, nodes = 0; /* the trees' (lone units share a leaf: lie_pnode_lone) */
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        leaves += st->pairs[k];
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        nodes += st->patches_per_depth[d];
    printf("{\"cache\":");
    inspect_json_string(stdout, path);
    printf(",\"file_bytes\":%zu,\"format_version\":%u,\"scene_path\":", l->size, LIE_CACHE_VERSION);
    inspect_json_string(stdout, c->scene_path);
    printf(",\"scene_hash\":\"%016llx\",\"state_hash\":\"%016llx\"", (unsigned long long)c->scene_hash,
           (unsigned long long)c->state_hash);
    printf(",\"edits\":[");
    for (int i = 0; i < c->n_edits; i++) {
        printf("%s{\"name\":", i ? "," : "");
        inspect_json_string(stdout, c->edits[i].name);
        printf(",\"bytes\":%zu}", c->edits[i].size);
    }
    char mp[32];
    inspect_fmt_float(p->min_patch, mp, sizeof mp);
    printf("],\"params\":{\"samples\":%u,\"max_samples\":%u,\"max_blockers\":%u,\"complex_cap\":%u,"
           "\"min_patch\":%s,\"split_gain\":%.9g,\"blockers\":\"%s\"}",
           p->samples, p->max_samples, p->max_blockers, p->complex_cap, mp, (double)p->split_gain,
           inspect_mode_name(p->mode));
    printf(",\"triangles\":%u,\"emitters\":%d,\"units\":%llu,\"nodes\":%llu,\"nodes_stored\":%u,\"leaves\":%llu,"
           "\"pool_entries\":%u",
           c->n_tris, c->n_emitters, (unsigned long long)((uint64_t)c->n_tris * (uint64_t)env->n_clusters),
           (unsigned long long)nodes, env->n_nodes, (unsigned long long)leaves, env->n_pool);
    printf(",\"partial\":%s,\"units_none\":%llu", env->partial ? "true" : "false",
           (unsigned long long)units_none(env));
    printf(",\"emitter_types\":{");
    for (uint32_t t = 0; t < 3; t++) {
        int n = 0;
        for (int e = 0; e < c->n_emitters; e++)
            n += c->emitters[e].type == t;
        printf("%s\"%s\":%d", t ? "," : "", inspect_emitter_type_name(t), n);
    }
    printf("},\"pairs\":{");
    for (int k = 0; k < LIE_CLASS_COUNT; k++) {
        if (k == LIE_CLASS_SPLIT)
            continue;
        printf("%s\"%s\":{\"count\":%llu,\"percent\":%.4f}", k ? "," : "", lie_class_name((lie_class)k),
               (unsigned long long)st->pairs[k], share(st->pairs[k], leaves));
    }
    int deepest = 0;
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        if (st->patches_per_depth[d])
            deepest = d;
    printf("},\"patches_per_depth\":[");
    for (int d = 0; d <= deepest && env->n_nodes; d++)
        printf("%s%llu", d ? "," : "", (unsigned long long)st->patches_per_depth[d]);
    uint64_t partial = st->pairs[LIE_CLASS_PARTIAL];
    printf("],\"blocker_lists\":{\"count\":%llu,\"total\":%llu,\"mean\":%.4f,\"histogram\":{",
           (unsigned long long)partial, (unsigned long long)st->blocker_total,
           partial ? (double)st->blocker_total / (double)partial : 0.0);
    for (int b = 0; b < HIST_BUCKETS; b++) {
        char label[32];
        hist_label(b, label, sizeof label);
        printf("%s\"%s\":%llu", b ? "," : "", label, (unsigned long long)st->list_hist[b]);
    }
    printf("}},\"segments\":%llu,\"sections\":[", (unsigned long long)st->segments);
    for (int i = 0; i < n_sec; i++) {
        printf("%s{\"name\":", i ? "," : "");
        inspect_json_string(stdout, sec[i].name);
        printf(",\"offset\":%llu,\"bytes\":%llu}", (unsigned long long)sec[i].offset,
               (unsigned long long)sec[i].size);
    }
    printf("]}\n");
}

int inspect_summary(const char *path, const inspect_options *o)
{
    inspect_cache l;
    lie_error err;
    if (inspect_load(path, &l, &err) != LIE_OK) {
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    lie_cache_section sec[LIE_CACHE_MAX_SECTIONS];
    int n_sec = 0;
    if (lie_cache_sections(l.data, l.size, path, sec, &n_sec, &err) != LIE_OK) {
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    lie_build_stats st;
    lie_env_stats(l.cache->env, &st);
    if (o->json)
        summary_json(path, &l, &st, sec, n_sec);
    else
        summary_text(path, &l, &st, sec, n_sec);
    inspect_unload(&l);
    return inspect_stdout_check();
}

