/* rst-update: apply edit files to a cache's scene and recompute only the
 * local illumination environments the edits can have changed (§5).
 *   rst-update CACHE|- EDIT.yaml [EDIT.yaml ...] -o CACHE|- [options] */
#include "lie.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static const char *prog = "rst-update";

static void usage(FILE *fp)
{
    fprintf(fp,
            "usage: %s CACHE|- EDIT.yaml [EDIT.yaml ...] -o CACHE|- [options]\n"
            "\n"
            "Apply scene edits (formats/edit.md) to the scene of a LIE cache, find the\n"
            "blocker lists they may change through ray segment trees, recompute only\n"
            "those, and write the updated cache (its edit log gains the edits).  The\n"
            "result equals a fresh lie-build of the edited scene.\n"
            "\n"
            "  -o, --output FILE     the cache to write; - writes to stdout\n"
            "      --full            recompute everything (the reference for update = rebuild)\n"
            "      --write-scene OUT.gltf  also write the edited scene as glTF\n"
            "      --threads N       worker threads (default: all cores)\n"
            "      --allow-external-uris  let glTF files reference files outside their folder\n"
            "      --stats[=json]    pairs flagged, pairs really changed, time per phase\n"
            "  -q, --quiet           no progress output\n"
            "  -h, --help            this help\n"
            "      --version         print the version\n",
            prog);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_report_error(prog, err, 1); }

enum { OPT_FULL = 256, OPT_THREADS, OPT_STATS, OPT_VERSION, OPT_EXTERNAL, OPT_WRITE_SCENE };

static const struct option long_opts[] = {
    {"output", required_argument, NULL, 'o'},
    {"full", no_argument, NULL, OPT_FULL},
    {"write-scene", required_argument, NULL, OPT_WRITE_SCENE},
    {"threads", required_argument, NULL, OPT_THREADS},
    {"allow-external-uris", no_argument, NULL, OPT_EXTERNAL},
    {"stats", optional_argument, NULL, OPT_STATS},
    {"quiet", no_argument, NULL, 'q'},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, OPT_VERSION},
    {NULL, 0, NULL, 0},
};

/* World bounds of every node's own triangles (empty boxes for none). */
static lie_box3 *node_boxes(const lie_scene *s)
{
    lie_box3 *b = malloc(sizeof *b * ((size_t)s->n_nodes + 1));
    if (!b)
        return NULL;
    for (int i = 0; i < s->n_nodes; i++)
        b[i] = lie_box3_empty();
    for (int i = 0; i < s->n_instances; i++) {
        const lie_instance *in = &s->instances[i];
        for (uint32_t t = in->first_tri; t < in->first_tri + in->n_tris; t++)
            if (!s->tri_removed[t])
                for (int k = 0; k < 3; k++)
                    lie_box3_grow(&b[in->node], s->tri_p[3 * (size_t)t + k]);
    }
    return b;
}

/* Are the subtrees at old node a and new node b identical? */
static int same_subtree(const lie_env *A, uint32_t a, const lie_env *B, uint32_t b)
{
    const lie_pnode *x = &A->nodes[a], *y = &B->nodes[b];
    if (x->cls != y->cls || x->count != y->count || x->quality != y->quality || !x->child != !y->child)
        return 0;
    if (x->cls == LIE_CLASS_PARTIAL && memcmp(A->pool + x->list, B->pool + y->list, sizeof(uint32_t) * x->count))
        return 0;
    if (x->child)
        for (uint32_t k = 0; k < 4; k++)
            if (!same_subtree(A, x->child + k, B, y->child + k))
                return 0;
    return 1;
}

static uint64_t recomputed_nodes(const lie_build_stats *st)
{
    uint64_t n = 0;
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        n += st->patches_per_depth[d];
    return n;
}

static lie_env *env_copy(const lie_env *e)
{
    lie_env *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    *c = *e;
    size_t units = (size_t)e->n_tris * (size_t)e->n_emitters;
    c->root = malloc(sizeof *c->root * (units + 1));
    c->nodes = malloc(sizeof *c->nodes * ((size_t)e->n_nodes + 1));
    c->pool = malloc(sizeof *c->pool * ((size_t)e->n_pool + 1));
    if (!c->root || !c->nodes || !c->pool) {
        lie_env_destroy(c);
        return NULL;
    }
    memcpy(c->root, e->root, sizeof *c->root * units);
    memcpy(c->nodes, e->nodes, sizeof *c->nodes * e->n_nodes);
    memcpy(c->pool, e->pool, sizeof *c->pool * e->n_pool);
    return c;
}

int main(int argc, char **argv)
{
    lie_scene_options so = lie_scene_options_default();
    const char *output = NULL, *scene_out = NULL;
    int stats = 0, quiet = 0, full = 0, threads = 0;
    long v;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:qh", long_opts, NULL)) != -1) {
        switch (c) {
        case 'o': output = optarg; break;
        case OPT_FULL: full = 1; break;
        case OPT_WRITE_SCENE: scene_out = optarg; break;
        case OPT_THREADS:
            if (!lie_parse_long(optarg, 0, 4096, &v))
                return usage_error("--threads: expected an integer in 0..4096, got '%s'", optarg);
            threads = (int)v;
            break;
        case OPT_EXTERNAL: so.allow_external_uris = 1; break;
        case OPT_STATS:
            if (!(stats = lie_parse_stats(optarg)))
                return usage_error("--stats: expected --stats or --stats=json, got '%s'", optarg);
            break;
        case 'q': quiet = 1; break;
        case 'h': usage(stdout); return 0;
        case OPT_VERSION: { char vr[512]; lie_version_report(prog, vr, sizeof vr); fputs(vr, stdout); return 0; }
        case ':': return usage_error("%s: missing value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
    (void)quiet;
    if (optind >= argc)
        return usage_error("%s", "missing input cache");
    if (optind + 1 >= argc)
        return usage_error("%s", "missing edit files");
    if (!output)
        return usage_error("%s", "missing -o CACHE");
    const char *input = argv[optind];
    int n_files = argc - optind - 1;
    char **files = argv + optind + 1;
    for (int i = 0; i < n_files; i++)
        if (strcmp(files[i], "-") == 0 && strcmp(input, "-") == 0)
            return usage_error("%s", "only one of the cache and the edit files can be stdin");

    lie_error err;
    lie_error_clear(&err);
    double t0 = lie_time_now();
    lie_cache *cache = NULL;
    lie_scene *scene = NULL;
    lie_rt *rt0 = NULL, *rt1 = NULL;
    lie_rst *rst = NULL;
    lie_edit **edits = calloc((size_t)n_files, sizeof *edits);
    unsigned char **texts = calloc((size_t)n_files, sizeof *texts);
    size_t *sizes = calloc((size_t)n_files, sizeof *sizes);
    lie_box3 *before = NULL, *after = NULL;
    uint8_t *flags = NULL;
    int32_t *old_unit = NULL;
    lie_env *old_env = NULL;
    lie_edit_effect fx;
    memset(&fx, 0, sizeof fx);
    lie_rst_stats rs;
    memset(&rs, 0, sizeof rs);
    lie_build_stats bst;
    memset(&bst, 0, sizeof bst);
    int rc = 1;
    uint64_t flagged_units = 0, changed_units = 0, rebuilt_units = 0, flagged_nodes = 0, flagged_nodes_5d = 0;
    double t_load = 0, t_rst = 0, t_edit = 0, t_query = 0, t_bvh = 0, t_update = 0, t_write = 0;
    size_t bytes = 0;
    if (!edits || !texts || !sizes) {
        lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        goto done;
    }
    /* Read and parse every edit first: a bad edit leaves everything untouched. */
    for (int i = 0; i < n_files; i++) {
        if (lie_read_file_max(files[i], LIE_READ_MAX_TEXT, &texts[i], &sizes[i], &err) != LIE_OK ||
            lie_edit_parse(texts[i], sizes[i], files[i], &edits[i], &err) != LIE_OK)
            goto done;
    }
    if (lie_cache_read(input, &cache, &err) != LIE_OK)
        goto done;
    if (lie_cache_load_scene(cache, input, NULL, &so, &scene, &err) != LIE_OK)
        goto done;
    t_load = lie_time_now() - t0;
    double ta = lie_time_now();
    uint32_t old_tris = scene->n_tris;
    int old_emitters = scene->n_emitters;
    float old_max_area = scene->max_tri_area;
    if (!full) {
        if (lie_rst_build(scene, cache->env, threads, &rst, &rs, &err) != LIE_OK)
            goto done;
    }
    t_rst = lie_time_now() - ta;
    /* Apply the edits, collecting every edited node's bounds before and after. */
    ta = lie_time_now();
    lie_box3 *boxes_acc = NULL;
    int n_acc = 0;
    for (int i = 0; i < n_files; i++) {
        free(before);
        before = node_boxes(scene);
        int n_before_nodes = scene->n_nodes;
        lie_edit_effect one;
        memset(&one, 0, sizeof one);
        if (!before || lie_edit_apply(scene, edits[i], &so, &one, &err) != LIE_OK) {
            lie_edit_effect_free(&one);
            free(boxes_acc);
            goto done;
        }
        free(after);
        after = node_boxes(scene);
        lie_box3 *nb = realloc(boxes_acc, sizeof *nb * ((size_t)n_acc + 2 * (size_t)one.n_nodes + 1));
        if (nb)
            boxes_acc = nb;
        if (!after || !nb) {
            lie_edit_effect_free(&one);
            free(boxes_acc);
            lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
            goto done;
        }
        for (int k = 0; k < one.n_nodes; k++) {
            int nd = one.nodes[k];
            if (nd < scene->n_nodes && !lie_box3_is_empty(&after[nd]))
                boxes_acc[n_acc++] = after[nd];
            if (nd < n_before_nodes && !lie_box3_is_empty(&before[nd]))
                boxes_acc[n_acc++] = before[nd];
        }
        /* remember which nodes moved or changed, across all files */
        for (int k = 0; k < one.n_nodes; k++) {
            int *nn = realloc(fx.nodes, sizeof *nn * ((size_t)fx.n_nodes + 1));
            if (!nn) {
                lie_edit_effect_free(&one);
                free(boxes_acc);
                lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
                goto done;
            }
            fx.nodes = nn;
            fx.nodes[fx.n_nodes++] = one.nodes[k];
        }
        lie_edit_effect_free(&one);
    }
    t_edit = lie_time_now() - ta;

    /* Which units continue, which are rebuilt, which nodes are recomputed. */
    ta = lie_time_now();
    size_t n_units = (size_t)scene->n_tris * (size_t)scene->n_emitters;
    old_unit = malloc(sizeof *old_unit * (n_units + 1));
    flags = calloc((size_t)cache->env->n_nodes + 1, 1);
    uint8_t *moved = calloc((size_t)scene->n_nodes + 1, 1);
    int32_t *emap = malloc(sizeof *emap * ((size_t)scene->n_emitters + 1));
    if (!old_unit || !flags || !moved || !emap) {
        free(moved);
        free(emap);
        free(boxes_acc);
        lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        goto done;
    }
    for (int k = 0; k < fx.n_nodes; k++)
        if (fx.nodes[k] >= 0 && fx.nodes[k] < scene->n_nodes)
            moved[fx.nodes[k]] = 1;
    /* emitters continue when the same instance emits before and after */
    for (int e = 0; e < scene->n_emitters; e++) {
        const lie_emitter *em = &scene->emitters[e];
        emap[e] = -1;
        if (moved[em->node])
            continue;
        for (int o = 0; o < cache->n_emitters; o++)
            if (cache->emitters[o].type == (uint32_t)em->type && cache->emitters[o].node == em->node &&
                cache->emitters[o].first_tri == em->first_tri && cache->emitters[o].n_tris == em->n_tris)
                emap[e] = o;
    }
    int everything = full || scene->max_tri_area != old_max_area;
    for (uint32_t t = 0; t < scene->n_tris; t++) {
        int patch_moved = t >= old_tris || moved[scene->instances[scene->tri_instance[t]].node];
        for (int e = 0; e < scene->n_emitters; e++) {
            size_t u = (size_t)t * (size_t)scene->n_emitters + (size_t)e;
            old_unit[u] = everything || patch_moved || emap[e] < 0
                              ? -1
                              : (int32_t)((size_t)t * (size_t)old_emitters + (size_t)emap[e]);
        }
    }
    free(moved);
    free(emap);
    if (rst)
        for (int i = 0; i < n_acc; i++)
            lie_rst_query(rst, boxes_acc[i], flags);
    for (uint32_t i = 0; i < cache->env->n_nodes; i++)
        flagged_nodes_5d += flags[i];
    /* Tighten the trees' answers (unit roots) with each flagged root's exact
     * hull, and carry them down the patch trees while the hulls meet.  The
     * hulls are computed on the edited scene, which is right for every
     * patch and emitter that did not move (the others are rebuilt anyway)
     * as long as emitters kept their indices. */
    int same_emitters = scene->n_emitters == cache->n_emitters;
    for (int e = 0; same_emitters && e < scene->n_emitters; e++)
        same_emitters = cache->emitters[e].node == scene->emitters[e].node &&
                        cache->emitters[e].first_tri == scene->emitters[e].first_tri;
    if (rst && same_emitters)
        lie_rst_refine(scene, cache->env, boxes_acc, n_acc, flags);
    else if (rst)
        lie_rst_spread(cache->env, flags); /* the trees answer for roots; their subtrees go along */
    free(boxes_acc);
    for (uint32_t i = 0; i < cache->env->n_nodes; i++)
        flagged_nodes += flags[i];
    t_query = lie_time_now() - ta;

    /* Recompute. */
    ta = lie_time_now();
    old_env = env_copy(cache->env);
    if (!old_env) {
        lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        goto done;
    }
    double tb = lie_time_now();
    if (lie_rt_create(scene, &rt1, &err) != LIE_OK)
        goto done;
    t_bvh = lie_time_now() - tb;
    if (lie_env_update(cache->env, scene, rt1, old_unit, flags, threads, &bst, &err) != LIE_OK)
        goto done;
    t_update = lie_time_now() - ta - t_bvh;
    /* Precision: units with a recomputed node, and those whose content changed. */
    for (size_t u = 0; u < n_units; u++) {
        if (old_unit[u] < 0) {
            rebuilt_units++;
            continue;
        }
        uint32_t r_old = old_env->root[old_unit[u]];
        /* flagged: the unit's root was flagged (children's regions lie inside it) */
        if (!flags[r_old])
            continue;
        flagged_units++;
        changed_units += !same_subtree(old_env, r_old, cache->env, cache->env->root[u]);
    }

    /* The cache: the same scene file, the new state, the longer edit log. */
    ta = lie_time_now();
    lie_cache_edit *log = realloc(cache->edits, sizeof *log * ((size_t)cache->n_edits + (size_t)n_files + 1));
    if (!log) {
        lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        goto done;
    }
    cache->edits = log;
    for (int i = 0; i < n_files; i++) {
        lie_cache_edit *le = &cache->edits[cache->n_edits];
        le->name = strdup(files[i]);
        le->text = texts[i];
        le->size = sizes[i];
        if (!le->name) {
            lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
            goto done;
        }
        texts[i] = NULL;
        cache->n_edits++;
    }
    lie_cache_emitter *em = realloc(cache->emitters, sizeof *em * ((size_t)scene->n_emitters + 1));
    if (!em) {
        lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        goto done;
    }
    cache->emitters = em;
    cache->n_emitters = scene->n_emitters;
    for (int e = 0; e < scene->n_emitters; e++) {
        em[e].type = (uint32_t)scene->emitters[e].type;
        em[e].node = scene->emitters[e].node;
        em[e].first_tri = scene->emitters[e].first_tri;
        em[e].n_tris = scene->emitters[e].n_tris;
    }
    cache->n_tris = scene->n_tris;
    cache->state_hash = scene->hash;
    if (lie_cache_write_with_scene(output, cache, scene, scene_out, &bytes, &err) != LIE_OK)
        goto done;
    t_write = lie_time_now() - ta;
    rc = 0;
    if (stats) {
        double precision = flagged_units ? (double)changed_units / (double)flagged_units : 1.0;
        if (stats == 2) {
            fprintf(stderr,
                    "{\"tool\":\"rst-update\",\"edits\":%d,\"units\":%zu,\"units_rebuilt\":%llu,"
                    "\"units_flagged\":%llu,\"units_changed\":%llu,\"precision\":%.4f,\"nodes_flagged_5d\":%llu,\"nodes_flagged\":%llu,"
                    "\"nodes_recomputed\":%llu,\"rst_regions\":%llu,\"rst_fallback\":%llu,\"rst_tree_nodes\":%llu,"
                    "\"rst_bytes\":%zu,\"seconds_load\":%.6f,\"seconds_rst\":%.6f,\"seconds_edit\":%.6f,"
                    "\"seconds_query\":%.6f,\"seconds_bvh\":%.6f,\"seconds_update\":%.6f,\"seconds_write\":%.6f,\"bytes\":%zu}\n",
                    n_files, n_units, (unsigned long long)rebuilt_units, (unsigned long long)flagged_units,
                    (unsigned long long)changed_units, precision, (unsigned long long)flagged_nodes_5d,
                    (unsigned long long)flagged_nodes,
                    (unsigned long long)recomputed_nodes(&bst), (unsigned long long)rs.regions,
                    (unsigned long long)rs.fallback, (unsigned long long)rs.tree_nodes, rs.bytes, t_load, t_rst,
                    t_edit, t_query, t_bvh, t_update, t_write, bytes);
        } else {
            uint64_t recomputed = recomputed_nodes(&bst);
            fprintf(stderr,
                    "%s: %s: %d edit file%s, %zu units (%u triangles x %d emitters)\n"
                    "  ray segment trees: %llu regions (%llu by bounds only), %llu tree nodes, %.1f MB\n"
                    "  units rebuilt (patch or emitter edited): %llu; units flagged: %llu, really changed: %llu "
                    "(precision %.0f%%)\n"
                    "  unit roots flagged by the trees %llu; patch-tree nodes flagged by exact hull tests down from them %llu, recomputed %llu\n"
                    "  time: load %.3f s, trees %.3f s, edits %.3f s, queries %.3f s, bvh %.3f s, update %.3f s, write %.3f s\n",
                    prog, input, n_files, n_files == 1 ? "" : "s", n_units, scene->n_tris, scene->n_emitters,
                    (unsigned long long)rs.regions, (unsigned long long)rs.fallback,
                    (unsigned long long)rs.tree_nodes, (double)rs.bytes / 1e6, (unsigned long long)rebuilt_units,
                    (unsigned long long)flagged_units, (unsigned long long)changed_units, 100.0 * precision,
                    (unsigned long long)flagged_nodes_5d, (unsigned long long)flagged_nodes,
                    (unsigned long long)recomputed, t_load, t_rst, t_edit,
                    t_query, t_bvh, t_update, t_write);
        }
    }
done:
    if (rc)
        fail(&err);
    for (int i = 0; edits && i < n_files; i++) {
        lie_edit_destroy(edits[i]);
        free(texts[i]);
    }
    free(edits);
    free(texts);
    free(sizes);
    free(before);
    free(after);
    free(flags);
    free(old_unit);
    lie_edit_effect_free(&fx);
    lie_env_destroy(old_env);
    lie_rst_destroy(rst);
    lie_rt_destroy(rt0);
    lie_rt_destroy(rt1);
    lie_scene_destroy(scene);
    lie_cache_destroy(cache);
    return rc;
}
