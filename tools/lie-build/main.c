/* lie-build: build the local illumination environments of a scene and write
 * them to a cache.
 *   lie-build SCENE.gltf|SCENE.glb -o CACHE|- [options] */
#include "common/cli.h"
#include "dist.h"
#include "lie.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static const char *prog = "lie-build";

static void usage(FILE *fp)
{
    lie_build_params d = lie_build_params_default();
    fprintf(fp,
            "usage: %s SCENE.gltf|SCENE.glb -o CACHE|- [options]\n"
            "\n"
            "Build local illumination environments (per patch and emitter: visible,\n"
            "occluded, or partial with a blocker list) and write them to a cache.\n"
            "\n"
            "  -o, --output FILE     the cache to write; - writes to stdout\n"
            "      --samples N       shadow segments per patch-emitter pair in the first round\n"
            "                        (default %u)\n"
            "      --max-samples N   keep doubling while a round finds new blockers, up to N\n"
            "                        segments (default %u)\n"
            "      --max-blockers B  subdivide a patch whose blocker list is longer (default %u)\n"
            "      --min-patch F     smallest patch area, as a fraction of the largest\n"
            "                        triangle's area, in [%g, 1] (default %g, the paper's 0.01%%): a floor\n"
            "      --split-gain G    keep a split only if the children's lists are shorter\n"
            "                        than the parent's by this share on average (default %g;\n"
            "                        0 splits wherever a list is too long, as the paper)\n"
            "      --max-nodes N     refuse to build more patch-tree nodes than N, about\n"
            "                        20 bytes each (default %llu)\n"
            "      --complex-cap C   a leaf whose list is still longer is 'complex':\n"
            "                        its shadow rays go to the whole scene (default %u)\n"
            "      --blockers MODE   sampled (default, the paper's shaft sampling) |\n"
            "                        conservative (every triangle that meets the shaft: exact)\n"
            "      --view CAMERA     build only the patches seen from this camera (a name, an\n"
            "                        index or eye=..,target=..; repeatable), directly or in\n"
            "                        mirrors; the rest is marked 'none' and rendered with full\n"
            "                        visibility (§4.3.1)\n"
            "      --path PATH.yaml  build only the patches seen from the frames of this camera\n"
            "                        path (formats/camera-path.md), as --view does for one camera\n"
            "      --view-size WxH   the image the views are sampled at (default 512x512)\n"
            "      --threads N       worker threads (default: all cores); the cache is the\n"
            "                        same for any N\n"
            "      --allow-external-uris  let the glTF reference files outside its folder\n"
            "      --stats[=json]    print statistics to stderr\n"
            "  -q, --quiet           no progress bar\n"
            "  -v, --verbose         each phase's time on stderr (load, bvh, build, write)\n"
            "  -h, --help            this help\n"
            "      --version         print the version\n"
            "\n"
            "Under mpirun the ranks share the units out and rank 0 writes the cache one\n"
            "process writes (docs/mpi.md).\n",
            prog, d.samples, d.max_samples, d.max_blockers, (double)LIE_MIN_PATCH_MIN, (double)d.min_patch,
            (double)d.split_gain,
            (unsigned long long)LIE_MAX_NODES_DEFAULT, d.complex_cap);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_dist_fail(prog, err, 1); }

enum {
    OPT_SAMPLES = 256, OPT_MAX_SAMPLES, OPT_MAX_BLOCKERS, OPT_MIN_PATCH, OPT_SPLIT_GAIN, OPT_COMPLEX_CAP, OPT_BLOCKERS,
    OPT_THREADS, OPT_VIEW, OPT_VIEW_SIZE, OPT_PATH, OPT_MAX_NODES
};

static const struct option long_opts[] = {
    {"output", required_argument, NULL, 'o'},
    {"samples", required_argument, NULL, OPT_SAMPLES},
    {"max-samples", required_argument, NULL, OPT_MAX_SAMPLES},
    {"max-blockers", required_argument, NULL, OPT_MAX_BLOCKERS},
    {"min-patch", required_argument, NULL, OPT_MIN_PATCH},
    {"split-gain", required_argument, NULL, OPT_SPLIT_GAIN},
    {"max-nodes", required_argument, NULL, OPT_MAX_NODES},
    {"complex-cap", required_argument, NULL, OPT_COMPLEX_CAP},
    {"blockers", required_argument, NULL, OPT_BLOCKERS},
    {"view", required_argument, NULL, OPT_VIEW},
    {"view-size", required_argument, NULL, OPT_VIEW_SIZE},
    {"path", required_argument, NULL, OPT_PATH},
    {"threads", required_argument, NULL, OPT_THREADS},
    LIE_OPT_ENTRY_EXTERNAL,
    LIE_OPT_ENTRY_STATS,
    LIE_OPT_ENTRY_VERBOSE,
    LIE_OPT_ENTRIES_END,
};

static void print_stats(const char *input, const lie_scene *s, const lie_env *env, const lie_build_stats *st,
                        double t_load, double t_bvh, double t_build, double t_write, size_t bytes, int json)
{
    uint64_t leaves = 0, patches = 0;
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        leaves += st->pairs[k];
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        patches += st->patches_per_depth[d];
    double mean = st->pairs[LIE_CLASS_PARTIAL] ? (double)st->blocker_total / (double)st->pairs[LIE_CLASS_PARTIAL] : 0.0;
    if (json) {
        fprintf(stderr, "{\"tool\":\"lie-build\",\"triangles\":%u,\"emitters\":%d,\"units\":%llu,\"patches\":%llu,"
                        "\"leaf_pairs\":%llu,\"pairs\":{",
                s->n_tris, s->n_emitters, (unsigned long long)s->n_tris * (unsigned long long)s->n_emitters,
                (unsigned long long)patches, (unsigned long long)leaves);
        for (int k = 0; k < LIE_CLASS_COUNT; k++)
            if (k != LIE_CLASS_SPLIT)
                fprintf(stderr, "%s\"%s\":%llu", k ? "," : "", lie_class_name((lie_class)k),
                        (unsigned long long)st->pairs[k]);
        fprintf(stderr, "},\"patches_per_depth\":[");
        int maxd = 0;
        for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
            if (st->patches_per_depth[d])
                maxd = d;
        for (int d = 0; d <= maxd; d++)
            fprintf(stderr, "%s%llu", d ? "," : "", (unsigned long long)st->patches_per_depth[d]);
        fprintf(stderr, "],\"list_histogram\":[");
        for (int b = 0; b < 18; b++)
            fprintf(stderr, "%s%llu", b ? "," : "", (unsigned long long)st->list_hist[b]);
        fprintf(stderr,
                "],\"mean_list_length\":%.3f,\"segments\":%llu,\"splits_undone\":%llu,\"nodes\":%u,\"pool\":%u,"
                "\"seconds_load\":%.6f,\"seconds_bvh\":%.6f,\"seconds_build\":%.6f,\"seconds_write\":%.6f,"
                "\"bytes\":%zu",
                mean, (unsigned long long)st->segments, (unsigned long long)st->splits_undone,
                env->n_nodes, env->n_pool, t_load, t_bvh, t_build, t_write,
                bytes);
        lie_dist_stats_print(stderr, "units", 1);
        fprintf(stderr, "}\n");
        return;
    }
    fprintf(stderr, "%s: %s: %u triangles, %d emitters, %llu units\n", prog, input, s->n_tris, s->n_emitters,
            (unsigned long long)s->n_tris * (unsigned long long)s->n_emitters);
    fprintf(stderr, "  pairs:");
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        if (k != LIE_CLASS_SPLIT)
            fprintf(stderr, " %s %llu (%.1f%%)", lie_class_name((lie_class)k), (unsigned long long)st->pairs[k],
                    leaves ? 100.0 * (double)st->pairs[k] / (double)leaves : 0.0);
    fprintf(stderr, "\n  patches per depth:");
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        if (st->patches_per_depth[d])
            fprintf(stderr, " %d:%llu", d, (unsigned long long)st->patches_per_depth[d]);
    fprintf(stderr, "\n  blocker lists: mean %.2f; lengths", mean);
    for (int b = 0; b < 18; b++)
        if (st->list_hist[b]) {
            unsigned lo = b == 0 ? 1 : (1u << (b - 1)) + 1, hi = 1u << b;
            if (lo == hi)
                fprintf(stderr, " %u:%llu", lo, (unsigned long long)st->list_hist[b]);
            else
                fprintf(stderr, " %u-%u:%llu", lo, hi, (unsigned long long)st->list_hist[b]);
        }
    fprintf(stderr, "\n  segments cast %llu; splits undone (did not shorten lists) %llu; %u nodes, %u pooled blockers, "
                    "%zu bytes written\n",
            (unsigned long long)st->segments, (unsigned long long)st->splits_undone, env->n_nodes, env->n_pool, bytes);
    fprintf(stderr, "  time: load %.3f s, bvh %.3f s, build %.3f s, write %.3f s\n", t_load, t_bvh, t_build,
            t_write);
    lie_dist_stats_print(stderr, "units", 0);
}

int main(int argc, char **argv)
{
    lie_build_params bp = lie_build_params_default();
    lie_scene_options so = lie_scene_options_default();
    const char *output = NULL;
    const char *views[64], *path_file = NULL;
    int n_views = 0, view_w = 512, view_h = 512;
    long v;
    float f;
    int c;
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing input scene"};
    while ((c = lie_cli_next(&cli, argc, argv, ":o:qvh", long_opts)) > 0) {
        switch (c) {
        case 'o': output = optarg; break;
        case OPT_SAMPLES:
            if (!lie_parse_long(optarg, 1, 1 << 20, &v))
                return usage_error("--samples: expected an integer in 1..1048576, got '%s'", optarg);
            bp.samples = (uint32_t)v;
            break;
        case OPT_MAX_SAMPLES:
            if (!lie_parse_long(optarg, 1, 1 << 24, &v))
                return usage_error("--max-samples: expected an integer in 1..16777216, got '%s'", optarg);
            bp.max_samples = (uint32_t)v;
            break;
        case OPT_MAX_BLOCKERS:
            if (!lie_parse_long(optarg, 0, 1 << 20, &v))
                return usage_error("--max-blockers: expected an integer in 0..1048576, got '%s'", optarg);
            bp.max_blockers = (uint32_t)v;
            break;
        case OPT_COMPLEX_CAP:
            if (!lie_parse_long(optarg, 0, 1 << 24, &v))
                return usage_error("--complex-cap: expected an integer in 0..16777216, got '%s'", optarg);
            bp.complex_cap = (uint32_t)v;
            break;
        case OPT_MIN_PATCH:
            if (!lie_parse_float(optarg, LIE_MIN_PATCH_MIN, 1.0f, &f))
                return usage_error("--min-patch: expected a fraction in [%g, 1], got '%s'", (double)LIE_MIN_PATCH_MIN,
                                   optarg);
            bp.min_patch = f;
            break;
        case OPT_SPLIT_GAIN:
            if (!lie_parse_float(optarg, 0.0f, 0.999f, &f))
                return usage_error("--split-gain: expected a share in [0, 1), got '%s'", optarg);
            bp.split_gain = f;
            break;
        case OPT_MAX_NODES:
            if (!lie_parse_long(optarg, 1, 0xFFFFFFF0L, &v))
                return usage_error("--max-nodes: expected an integer in 1..4294967280, got '%s'", optarg);
            bp.max_nodes = (uint64_t)v;
            break;
        case OPT_BLOCKERS:
            if (strcmp(optarg, "sampled") == 0) bp.mode = LIE_BLOCKERS_SAMPLED;
            else if (strcmp(optarg, "conservative") == 0) bp.mode = LIE_BLOCKERS_CONSERVATIVE;
            else return usage_error("--blockers: expected sampled or conservative, got '%s'", optarg);
            break;
        case OPT_THREADS:
            if (!lie_parse_long(optarg, 0, 4096, &v))
                return usage_error("--threads: expected an integer in 0..4096, got '%s'", optarg);
            bp.threads = (int)v;
            break;
        case OPT_VIEW:
            if (n_views == 64)
                return usage_error("--view: at most 64 views, got another: '%s'", optarg);
            views[n_views++] = optarg;
            break;
        case OPT_PATH: path_file = optarg; break;
        case OPT_VIEW_SIZE:
            if (!lie_parse_size(optarg, 16384, &view_w, &view_h))
                return usage_error("--view-size: expected WxH, got '%s'", optarg);
            break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    so.allow_external_uris = cli.external;
    const char *input = cli.operand;
    if (!output)
        return usage_error("%s", "missing -o CACHE");
    if (bp.max_samples < bp.samples)
        bp.max_samples = bp.samples; /* --samples above the default cap: one round */

    if (lie_dist_start(&argc, &argv) > 1) {
        cli.quiet = 1; /* rank 0 prints the statistics */
        if (lie_dist_rank() != 0)
            cli.stats = 0;
    }
    lie_error err;
    lie_error_clear(&err);
    double t0 = lie_time_now();
    lie_scene *scene = NULL;
    if (lie_scene_load(input, &so, &scene, &err) != LIE_OK)
        return fail(&err);
    if (!cli.quiet)
        lie_print_scene_warnings(prog, scene, input);
    if (scene->n_emitters == 0 && !cli.quiet)
        fprintf(stderr, "%s: %s: warning: no emitters (no emissive material, no KHR_lights_punctual light): "
                        "the cache holds no environments\n", prog, input);
    double t1 = lie_phase(prog, cli.verbose, "load", t0);
    lie_rt *rt = NULL;
    if (lie_rt_create(scene, &rt, &err) != LIE_OK) {
        lie_scene_destroy(scene);
        return fail(&err);
    }
    double t2 = lie_phase(prog, cli.verbose, "bvh", t1);
    uint8_t *mask = NULL;
    if (n_views || path_file) {
        /* the views: each --view, then every frame of --path */
        lie_camera_path *cpath = NULL;
        lie_status vs = path_file ? lie_camera_path_read(path_file, &cpath, &err) : LIE_OK;
        int n_cams = n_views + (cpath ? cpath->n_frames : 0);
        lie_camera *cams = vs == LIE_OK ? calloc((size_t)n_cams, sizeof *cams) : NULL;
        mask = cams ? calloc((size_t)scene->n_tris + 1, 1) : NULL;
        if (vs == LIE_OK && !mask)
            vs = lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        for (int i = 0; vs == LIE_OK && i < n_views; i++) {
            vs = lie_camera_parse(scene, views[i], &cams[i], &err);
            if (vs != LIE_OK && !err.file[0])
                snprintf(err.file, sizeof err.file, "%s", input);
        }
        for (int i = n_views; vs == LIE_OK && i < n_cams; i++)
            cams[i] = lie_camera_path_frame(cpath, i - n_views);
        if (vs == LIE_OK)
            vs = lie_camera_mark_visible(scene, rt, cams, n_cams, view_w, view_h, LIE_MAX_DEPTH_DEFAULT, mask, &err);
        free(cams);
        lie_camera_path_destroy(cpath);
        if (vs != LIE_OK) {
            free(mask);
            lie_rt_destroy(rt);
            lie_scene_destroy(scene);
            return fail(&err);
        }
    }
    if (lie_dist_check(scene->hash, scene->hash, &err) != LIE_OK) {
        free(mask);
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    if (n_views || path_file)
        t2 = lie_phase(prog, cli.verbose, "views", t2);
    lie_progress prog_bar;
    lie_progress_begin(&prog_bar, stderr, "lie-build", !cli.quiet);
    lie_env *env = NULL;
    lie_build_stats st;
    lie_status rc = lie_dist_size() > 1 ? build_dist(scene, rt, &bp, mask, &env, &st, &err)
                                         : lie_env_build_masked(scene, rt, &bp, mask, &prog_bar, &env, &st, &err);
    free(mask);
    lie_progress_end(&prog_bar);
    if (rc != LIE_OK) {
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    if (!env) { /* another rank than 0 under mpirun: rank 0 writes */
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return 0;
    }
    double t3 = lie_phase(prog, cli.verbose, "build", t2);
    lie_cache cache;
    memset(&cache, 0, sizeof cache);
    cache.scene_path = (char *)input;
    cache.scene_hash = scene->hash;
    rc = lie_cache_set_state(&cache, scene, &err);
    cache.env = env;
    size_t bytes = 0;
    if (rc == LIE_OK)
        rc = lie_cache_write(output, &cache, &bytes, &err);
    double t4 = lie_phase(prog, cli.verbose && rc == LIE_OK, "write", t3);
    if (rc == LIE_OK && cli.stats)
        print_stats(input, scene, env, &st, t1 - t0, t2 - t1, t3 - t2, t4 - t3, bytes, cli.stats == 2);
    free(cache.emitters);
    lie_env_destroy(env);
    lie_rt_destroy(rt);
    lie_scene_destroy(scene);
    if (rc != LIE_OK)
        return fail(&err);
    return 0;
}
