/* lie-build: build the local illumination environments of a scene and write
 * them to a cache.
 *   lie-build SCENE.gltf|SCENE.glb -o CACHE|- [options] */
#include "common/cli.h"
#include "dist.h"
#include "lie.h"

#include <getopt.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

static const char *prog = "lie-build";

static void usage(FILE *fp)
{
    lie_build_params d = lie_build_params_default();
    fprintf(fp,
            "usage: %s SCENE.gltf|SCENE.glb -o CACHE|- [options]\n"
            "       %s --into CACHE --view CAMERA|--path PATH.yaml [-o OUT] [SCENE]\n"
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
            "      --view-size WxH   the image the views are sampled at (default 512x512); its\n"
            "                        pixels decide how fine the views' patches get (§4.3.3)\n"
            "      --into CACHE      add the units more views need to CACHE, a cache built for\n"
            "                        views: units already built are kept (or refined where the\n"
            "                        new pixels make a split pay), and the result is the cache\n"
            "                        one build for all the views gives.  CACHE's parameters,\n"
            "                        scene (SCENE overrides its path) and view size are used;\n"
            "                        written back to CACHE unless -o\n"
            "    The cost model (views only: a split must save more render time over the\n"
            "    frames than it costs to build; --stats shows its predictions):\n"
            "      --frames N        frames the cache will serve (default %u; 0: no pixel\n"
            "                        rule, patches as fine as their lists need)\n"
            "      --light-samples N shadow rays per pixel and emitter in them (default %u)\n"
            "      --cost S,B,R      ns per build segment, per blocker test, per Embree shadow\n"
            "                        ray (default %g,%g,%g; make bench-build measures them)\n"
            "      --emitter-clusters K  split each large area emitter into up to K clusters\n"
            "                        in space (default 1; README, \"Emitters of many triangles\")\n"
            "      --threads N       worker threads (default: all cores); the cache is the\n"
            "                        same for any N\n"
            "      --edit EDIT.yaml  apply these edits (formats/edit.md; repeatable, in order)\n"
            "                        to the scene first, and log them in the cache: the cache\n"
            "                        equals lie-build SCENE | rst-update - EDIT.yaml\n"
            "      --partial         on SIGINT, SIGTERM or SIGHUP, stop building and write what\n"
            "                        is done as a valid partial cache (units not built are\n"
            "                        'none': lie-render answers them from the whole scene), then\n"
            "                        exit 128+signal; a second signal aborts at once, writing\n"
            "                        nothing.  Without it a signal aborts and writes nothing\n"
            "      --resume PARTIAL  continue an interrupted build: copy the units PARTIAL holds\n"
            "                        and build the rest; give the same scene, --edit, --view\n"
            "                        and --path.  The parameters are PARTIAL's; the cache\n"
            "                        equals an uninterrupted build's, byte for byte\n"
            "      --allow-external-uris  let the glTF reference files outside its folder\n"
            "      --stats[=json]    print statistics to stderr\n"
            "  -q, --quiet           no progress bar\n"
            "  -v, --verbose         each phase's time on stderr (load, bvh, build, write)\n"
            "  -h, --help            this help\n"
            "      --version         print the version\n"
            "\n"
            "Under mpirun the ranks share the units out and rank 0 writes the cache one\n"
            "process writes (docs/mpi.md).\n",
            prog, prog, d.samples, d.max_samples, d.max_blockers, (double)LIE_MIN_PATCH_MIN, (double)d.min_patch,
            (double)d.split_gain,
            (unsigned long long)LIE_MAX_NODES_DEFAULT, d.complex_cap, d.frames, d.light_samples,
            (double)d.ns_segment, (double)d.ns_blocker, (double)d.ns_ray);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_dist_fail(prog, err, 1); }

enum {
    OPT_SAMPLES = 256, OPT_MAX_SAMPLES, OPT_MAX_BLOCKERS, OPT_MIN_PATCH, OPT_SPLIT_GAIN, OPT_COMPLEX_CAP, OPT_BLOCKERS,
    OPT_THREADS, OPT_VIEW, OPT_VIEW_SIZE, OPT_PATH, OPT_MAX_NODES,
    OPT_INTO, OPT_FRAMES, OPT_LIGHT_SAMPLES, OPT_COST, OPT_PARTIAL, OPT_RESUME, OPT_EDIT, OPT_CLUSTERS
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
    {"into", required_argument, NULL, OPT_INTO},
    {"partial", no_argument, NULL, OPT_PARTIAL},
    {"resume", required_argument, NULL, OPT_RESUME},
    {"edit", required_argument, NULL, OPT_EDIT},
    {"frames", required_argument, NULL, OPT_FRAMES},
    {"light-samples", required_argument, NULL, OPT_LIGHT_SAMPLES},
    {"cost", required_argument, NULL, OPT_COST},
    {"threads", required_argument, NULL, OPT_THREADS},
    {"emitter-clusters", required_argument, NULL, OPT_CLUSTERS},
    LIE_OPT_ENTRY_EXTERNAL,
    LIE_OPT_ENTRY_STATS,
    LIE_OPT_ENTRY_VERBOSE,
    LIE_OPT_ENTRIES_END,
};

/* --partial: the first SIGINT, SIGTERM or SIGHUP asks the build to stop
 * (lie_build_control.stop); a second one aborts at once, as without
 * --partial.  The write that follows is the library's: its handler removes
 * the temporary and re-raises (lib/core/file.c), so the cache on disk is
 * the whole partial cache or nothing. */
static volatile sig_atomic_t stop_signal;
static const int stop_signals[3] = {SIGINT, SIGTERM, SIGHUP};

static void on_stop(int sig)
{
    if (stop_signal) {
        signal(sig, SIG_DFL);
        raise(sig); /* delivered with the default action once the handler returns */
        return;
    }
    stop_signal = sig;
}

/* Install on_stop where a signal has its default action (a signal the
 * caller ignores, as nohup does SIGHUP, stays ignored), or put the default
 * back. */
static void stop_handlers(int on, int installed[3])
{
    for (int i = 0; i < 3; i++) {
        struct sigaction old, sa;
        memset(&sa, 0, sizeof sa);
        sigemptyset(&sa.sa_mask);
        if (on) {
            installed[i] = sigaction(stop_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_DFL &&
                           !(old.sa_flags & SA_SIGINFO);
            if (!installed[i])
                continue;
            sa.sa_handler = on_stop;
            for (int j = 0; j < 3; j++)
                sigaddset(&sa.sa_mask, stop_signals[j]);
        } else {
            if (!installed[i])
                continue;
            sa.sa_handler = SIG_DFL;
        }
        sigaction(stop_signals[i], &sa, NULL);
    }
}

static const char *signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

/* --edit: read, parse and apply each edit file in order (a resumed build's
 * log must hold the same texts); edit_log[i].name is set, text and size
 * are filled. */
static lie_status apply_edits(lie_scene *scene, const lie_scene_options *so, lie_cache_edit *edit_log, int n,
                              const lie_cache *resume, lie_error *err)
{
    for (int i = 0; i < n; i++)
        edit_log[i].text = NULL;
    if (resume && resume->n_edits != n)
        return lie_error_set(err, LIE_ERR_ARG, scene->path, "the partial cache was built with %d edit files, not %d",
                             resume->n_edits, n);
    for (int i = 0; i < n; i++) {
        lie_cache_edit *ed = &edit_log[i];
        lie_edit *e = NULL;
        if (lie_read_file_max(ed->name, LIE_READ_MAX_TEXT, &ed->text, &ed->size, err) != LIE_OK ||
            lie_edit_parse(ed->text, ed->size, ed->name, &e, err) != LIE_OK ||
            lie_edit_apply(scene, e, so, NULL, err) != LIE_OK) {
            lie_edit_destroy(e);
            return err->status;
        }
        lie_edit_destroy(e);
        if (resume && (resume->edits[i].size != ed->size || memcmp(resume->edits[i].text, ed->text, ed->size)))
            return lie_error_set(err, LIE_ERR_ARG, ed->name, "differs from edit %d of the partial cache", i);
    }
    return LIE_OK;
}

static void free_edits(lie_cache_edit *edit_log, int n)
{
    for (int i = 0; i < n; i++)
        free(edit_log[i].text);
}

/* A resumed build's views must be the partial cache's. */
static int same_views(const lie_cache_views *a, const lie_cache_views *b)
{
    if (a->n_cams != b->n_cams || (a->n_cams && (a->width != b->width || a->height != b->height ||
                                                 a->max_depth != b->max_depth)))
        return 0;
    for (int i = 0; i < a->n_cams; i++) {
        lie_camera x = a->cams[i], y = b->cams[i];
        x.name = y.name = NULL;
        if (memcmp(&x, &y, sizeof x) != 0)
            return 0;
    }
    return 1;
}

static void print_stats(const char *input, const lie_scene *s, const lie_env *env, const lie_build_stats *st,
                        const lie_add_stats *as, const lie_prediction *pred, double cpu_build, double t_load,
                        double t_bvh, double t_build, double t_write, size_t bytes, int json)
{
    uint64_t leaves = 0, patches = 0;
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        leaves += st->pairs[k];
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        patches += st->patches_per_depth[d];
    double mean = st->pairs[LIE_CLASS_PARTIAL] ? (double)st->blocker_total / (double)st->pairs[LIE_CLASS_PARTIAL] : 0.0;
    /* the model against the build: its build time (segments only) against
     * the CPU time the build took; the render time the splits save per
     * frame, predicted before each lookahead and as the children's lists
     * gave it; and one frame of the views, with full visibility and with
     * this cache (CPU seconds over all threads; bench/build.sh renders them) */
    const lie_build_params *p = &env->params;
    double model_build = 1e-9 * (double)st->segments * (double)p->ns_segment;
    double sp = 1e-9 * st->split_saving_predicted_ns, sm = 1e-9 * st->split_saving_measured_ns;
    if (json) {
        fprintf(stderr, "{\"tool\":\"lie-build\",\"triangles\":%u,\"emitters\":%d,\"clusters\":%d,\"units\":%llu,"
                        "\"patches\":%llu,\"leaf_pairs\":%llu,\"pairs\":{",
                s->n_tris, s->n_emitters, s->n_clusters, (unsigned long long)s->n_tris * (unsigned long long)s->n_clusters,
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
                "],\"mean_list_length\":%.3f,\"segments\":%llu,\"splits_undone\":%llu,\"splits_kept\":%llu,"
                "\"splits_pixels\":%llu,\"nodes\":%u,\"pool\":%u,"
                "\"seconds_load\":%.6f,\"seconds_bvh\":%.6f,\"seconds_build\":%.6f,\"seconds_write\":%.6f,"
                "\"bytes\":%zu",
                mean, (unsigned long long)st->segments, (unsigned long long)st->splits_undone,
                (unsigned long long)st->splits_kept, (unsigned long long)st->splits_pixels,
                env->n_nodes, env->n_pool, t_load, t_bvh, t_build, t_write, bytes);
        fprintf(stderr, ",\"model\":{\"build_cpu_s_predicted\":%.6f,\"build_cpu_s_measured\":%.6f", model_build,
                cpu_build);
        if (pred)
            fprintf(stderr,
                    ",\"split_saving_s_predicted\":%.6f,\"split_saving_s_measured\":%.6f,\"view_pixels\":%.0f,"
                    "\"frame_shadow_cpu_s_full\":%.6f,\"frame_shadow_cpu_s_lie\":%.6f,\"frame_full_rays\":%.0f,"
                    "\"frame_list_entries\":%.0f,\"frame_lie_rays\":%.0f",
                    sp, sm, pred->pixels, 1e-9 * pred->full_ns, 1e-9 * pred->lie_ns, pred->full_rays,
                    pred->list_entries, pred->env_rays);
        fprintf(stderr, "}");
        fprintf(stderr,
                ",\"partial\":%s,\"units_copied\":%llu,\"units_interrupted\":%llu,\"workers\":%d,\"seconds_cpu\":%.6f,"
                "\"seconds_cpu_workers\":%.6f,\"seconds_cpu_worker_max\":%.6f,\"seconds_tail\":%.6f",
                env->partial ? "true" : "false", (unsigned long long)st->units_copied,
                (unsigned long long)st->units_interrupted, st->workers, lie_cpu_time(), st->seconds_cpu_sum,
                st->seconds_cpu_max, st->seconds_tail);
        if (as)
            fprintf(stderr, ",\"into\":{\"units_kept\":%llu,\"units_refined\":%llu,\"units_new\":%llu,"
                            "\"nodes_recomputed\":%llu}",
                    (unsigned long long)as->units_kept, (unsigned long long)as->units_refined,
                    (unsigned long long)as->units_new, (unsigned long long)as->nodes_flagged);
        lie_dist_stats_print(stderr, "units", 1);
        fprintf(stderr, "}\n");
        return;
    }
    fprintf(stderr, "%s: %s: %u triangles, %d emitters in %d clusters, %llu units\n", prog, input, s->n_tris,
            s->n_emitters, s->n_clusters, (unsigned long long)s->n_tris * (unsigned long long)s->n_clusters);
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
    fprintf(stderr, "\n  segments cast %llu; splits kept %llu, undone (did not shorten lists) %llu, not tried "
                    "(too few pixels) %llu; %u nodes, %u pooled blockers, %zu bytes written\n",
            (unsigned long long)st->segments, (unsigned long long)st->splits_kept,
            (unsigned long long)st->splits_undone, (unsigned long long)st->splits_pixels, env->n_nodes, env->n_pool,
            bytes);
    fprintf(stderr, "  time: load %.3f s, bvh %.3f s, build %.3f s, write %.3f s\n", t_load, t_bvh, t_build,
            t_write);
    fprintf(stderr, "  cpu: %.3f s in all; the build's %d workers %.3f s, the busiest %.3f s, cores idle for the "
                    "last %.3f s\n", lie_cpu_time(), st->workers, st->seconds_cpu_sum, st->seconds_cpu_max,
            st->seconds_tail);
    if (st->units_copied || st->units_interrupted || env->partial)
        fprintf(stderr, "  units: %llu copied from the resumed cache, %llu left unbuilt by an interruption%s\n",
                (unsigned long long)st->units_copied, (unsigned long long)st->units_interrupted,
                env->partial ? " (the cache is partial)" : "");
    fprintf(stderr, "  model: build %.3f CPU s predicted, %.3f measured", model_build, cpu_build);
    if (pred)
        fprintf(stderr, "; splits save %.4f s a frame predicted, %.4f by their lists; a frame of the views "
                        "(%.0f pixels) costs %.3f shadow CPU s with full visibility, %.3f with this cache",
                sp, sm, pred->pixels, 1e-9 * pred->full_ns, 1e-9 * pred->lie_ns);
    fprintf(stderr, "\n");
    if (as)
        fprintf(stderr, "  into: %llu units kept, %llu refined, %llu new; %llu nodes recomputed\n",
                (unsigned long long)as->units_kept, (unsigned long long)as->units_refined,
                (unsigned long long)as->units_new, (unsigned long long)as->nodes_flagged);
    lie_dist_stats_print(stderr, "units", 0);
}

/* The cameras of the --view options and the frames of --path, appended to
 * *cams (the cache's views first, with --into). */
static lie_status gather_views(const lie_scene *scene, const char *input, const char *const *views, int n_views,
                               const lie_camera_path *cpath, lie_cache_views *v, lie_error *err)
{
    lie_status st = LIE_OK;
    int n_new = n_views + (cpath ? cpath->n_frames : 0);
    lie_camera *cams = st == LIE_OK ? realloc(v->cams, sizeof *cams * ((size_t)(v->n_cams + n_new) + 1)) : NULL;
    if (st == LIE_OK && !cams)
        st = lie_error_set(err, LIE_ERR_NOMEM, input, "out of memory");
    if (cams)
        v->cams = cams;
    for (int i = 0; st == LIE_OK && i < n_views; i++) {
        st = lie_camera_parse(scene, views[i], &cams[v->n_cams], err);
        if (st != LIE_OK && !err->file[0])
            snprintf(err->file, sizeof err->file, "%s", input);
        cams[v->n_cams].name = NULL; /* caches keep the geometry, not the name */
        if (st == LIE_OK)
            v->n_cams++;
    }
    for (int i = 0; st == LIE_OK && cpath && i < cpath->n_frames; i++) {
        cams[v->n_cams] = lie_camera_path_frame(cpath, i);
        cams[v->n_cams++].name = NULL;
    }
    return st;
}


int main(int argc, char **argv)
{
    lie_build_params bp = lie_build_params_default();
    lie_scene_options so = lie_scene_options_default();
    const char *output = NULL, *into = NULL;
    int params_given = 0, size_given = 0, partial = 0;
    const char *views[64], *path_file = NULL, *resume_file = NULL;
    lie_cache_edit edit_log[64];
    int n_edits = 0;
    int n_views = 0, view_w = 512, view_h = 512;
    long v;
    float f;
    int c;
    lie_cli cli = {.tool = prog, .usage = usage};
    while ((c = lie_cli_next(&cli, argc, argv, ":o:qvh", long_opts)) > 0) {
        switch (c) {
        case 'o': output = optarg; break;
        case OPT_SAMPLES:
            if (!lie_parse_long(optarg, 1, 1 << 20, &v))
                return usage_error("--samples: expected an integer in 1..1048576, got '%s'", optarg);
            bp.samples = (uint32_t)v;
            params_given = 1;
            break;
        case OPT_MAX_SAMPLES:
            if (!lie_parse_long(optarg, 1, 1 << 24, &v))
                return usage_error("--max-samples: expected an integer in 1..16777216, got '%s'", optarg);
            bp.max_samples = (uint32_t)v;
            params_given = 1;
            break;
        case OPT_MAX_BLOCKERS:
            if (!lie_parse_long(optarg, 0, 1 << 20, &v))
                return usage_error("--max-blockers: expected an integer in 0..1048576, got '%s'", optarg);
            bp.max_blockers = (uint32_t)v;
            params_given = 1;
            break;
        case OPT_CLUSTERS:
            if (!lie_parse_long(optarg, 1, LIE_CLUSTER_MAX, &v))
                return usage_error("--emitter-clusters: expected an integer in 1..%d, got '%s'", LIE_CLUSTER_MAX, optarg);
            so.emitter_clusters = (int)v;
            break;
        case OPT_COMPLEX_CAP:
            if (!lie_parse_long(optarg, 0, 1 << 24, &v))
                return usage_error("--complex-cap: expected an integer in 0..16777216, got '%s'", optarg);
            bp.complex_cap = (uint32_t)v;
            params_given = 1;
            break;
        case OPT_MIN_PATCH:
            if (!lie_parse_float(optarg, LIE_MIN_PATCH_MIN, 1.0f, &f))
                return usage_error("--min-patch: expected a fraction in [%g, 1], got '%s'", (double)LIE_MIN_PATCH_MIN,
                                   optarg);
            bp.min_patch = f;
            params_given = 1;
            break;
        case OPT_SPLIT_GAIN:
            if (!lie_parse_float(optarg, 0.0f, 0.999f, &f))
                return usage_error("--split-gain: expected a share in [0, 1), got '%s'", optarg);
            bp.split_gain = f;
            params_given = 1;
            break;
        case OPT_FRAMES:
            if (!lie_parse_long(optarg, 0, 1 << 24, &v))
                return usage_error("--frames: expected an integer in 0..16777216, got '%s'", optarg);
            bp.frames = (uint32_t)v;
            params_given = 1;
            break;
        case OPT_LIGHT_SAMPLES:
            if (!lie_parse_long(optarg, 1, 1 << 24, &v))
                return usage_error("--light-samples: expected an integer in 1..16777216, got '%s'", optarg);
            bp.light_samples = (uint32_t)v;
            params_given = 1;
            break;
        case OPT_COST: {
            char *end = NULL;
            double a = strtod(optarg, &end), b = end && *end == ',' ? strtod(end + 1, &end) : -1.0,
                   r = end && *end == ',' ? strtod(end + 1, &end) : -1.0;
            if (!end || *end || !(a > 0 && a <= 1e9) || !(b > 0 && b <= 1e9) || !(r > 0 && r <= 1e9))
                return usage_error("--cost: expected three times in ns, S,B,R, each in (0, 1e9], got '%s'", optarg);
            bp.ns_segment = (float)a;
            bp.ns_blocker = (float)b;
            bp.ns_ray = (float)r;
            params_given = 1;
            break;
        }
        case OPT_MAX_NODES:
            if (!lie_parse_long(optarg, 1, 0xFFFFFFF0L, &v))
                return usage_error("--max-nodes: expected an integer in 1..4294967280, got '%s'", optarg);
            bp.max_nodes = (uint64_t)v;
            break;
        case OPT_BLOCKERS:
            if (strcmp(optarg, "sampled") == 0) bp.mode = LIE_BLOCKERS_SAMPLED;
            else if (strcmp(optarg, "conservative") == 0) bp.mode = LIE_BLOCKERS_CONSERVATIVE;
            else return usage_error("--blockers: expected sampled or conservative, got '%s'", optarg);
            params_given = 1;
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
        case OPT_INTO: into = optarg; break;
        case OPT_PARTIAL: partial = 1; break;
        case OPT_RESUME: resume_file = optarg; break;
        case OPT_EDIT:
            if (n_edits == 64)
                return usage_error("--edit: at most 64 edit files, got another: '%s'", optarg);
            edit_log[n_edits].name = optarg;
            edit_log[n_edits++].text = NULL;
            break;
        case OPT_VIEW_SIZE:
            if (!lie_parse_size(optarg, 16384, &view_w, &view_h))
                return usage_error("--view-size: expected WxH, got '%s'", optarg);
            size_given = 1;
            break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    so.allow_external_uris = cli.external;
    if (into && (resume_file || n_edits))
        return usage_error("%s", "--into: give no --resume or --edit (rst-update edits a cache)");
    if (resume_file && params_given)
        return usage_error("%s", "--resume: the partial cache's build parameters are used; give none");
    if (into) {
        if (optind + 1 < argc)
            return usage_error("unexpected argument '%s'", argv[optind + 1]);
        if (!n_views && !path_file)
            return usage_error("%s", "--into: give the views to add (--view or --path)");
        if (params_given)
            return usage_error("%s", "--into: the cache's build parameters are used; give none");
        if (!output)
            output = into;
    } else {
        if (optind >= argc)
            return usage_error("%s", "missing input scene");
        if (optind + 1 < argc)
            return usage_error("unexpected argument '%s'", argv[optind + 1]);
        if (!output)
            return usage_error("%s", "missing -o CACHE");
    }
    if (bp.max_samples < bp.samples)
        bp.max_samples = bp.samples; /* --samples above the default cap: one round */
    const char *input = optind < argc ? argv[optind] : NULL;

    if (lie_dist_start(&argc, &argv) > 1) {
        cli.quiet = 1; /* rank 0 prints the statistics */
        if (lie_dist_rank() != 0)
            cli.stats = 0;
        if (into || partial || resume_file || n_edits) {
            lie_error e;
            lie_error_set(&e, LIE_ERR_ARG, into ? into : input,
                          "--into, --edit, --partial and --resume run in one process, not under mpirun");
            return fail(&e);
        }
    }
    lie_error err;
    lie_error_clear(&err);
    double t0 = lie_time_now(), cpu0 = lie_cpu_time();
    lie_scene *scene = NULL;
    lie_cache *old = NULL, *resume = NULL;
    if (resume_file) {
        if (lie_cache_read(resume_file, &resume, &err) != LIE_OK)
            return fail(&err);
        int threads = bp.threads;
        uint64_t max_nodes = bp.max_nodes;
        bp = resume->env->params;
        bp.threads = threads;
        bp.max_nodes = max_nodes;
    }
    lie_camera_path *cpath = NULL; /* --path */
    lie_cache_views cv = {NULL, 0, view_w, view_h, LIE_MAX_DEPTH_DEFAULT};
    if (into) {
        if (lie_cache_read(into, &old, &err) != LIE_OK ||
            lie_cache_load_scene(old, into, input, &so, &scene, &err) != LIE_OK ||
            (path_file && lie_camera_path_read(path_file, &cpath, &err) != LIE_OK)) {
            lie_scene_destroy(scene);
            lie_cache_destroy(old);
            return fail(&err);
        }
        if (!old->views.n_cams) {
            lie_error_set(&err, LIE_ERR_ARG, into, "built for the whole scene, not for views: nothing to add");
        } else if (size_given && (view_w != old->views.width || view_h != old->views.height)) {
            lie_error_set(&err, LIE_ERR_ARG, into, "built for views of %dx%d, not %dx%d", old->views.width,
                          old->views.height, view_w, view_h);
        }
        if (err.status) {
            lie_camera_path_destroy(cpath);
            lie_cache_destroy(old);
            lie_scene_destroy(scene);
            return fail(&err);
        }
        bp = old->env->params;
        cv.width = old->views.width;
        cv.height = old->views.height;
        cv.max_depth = old->views.max_depth;
        input = old->scene_path;
    } else if (build_load_inputs(input, path_file, &so, &scene, &cpath, &err) != LIE_OK) {
        lie_camera_path_destroy(cpath);
        lie_scene_destroy(scene);
        lie_cache_destroy(resume);
        return fail(&err);
    }
    uint64_t loaded_hash = scene->hash;
    if (apply_edits(scene, &so, edit_log, n_edits, resume, &err) != LIE_OK) {
        free_edits(edit_log, n_edits);
        lie_camera_path_destroy(cpath);
        lie_cache_destroy(resume);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    if (!cli.quiet)
        lie_print_scene_warnings(prog, scene, input);
    if (scene->n_emitters == 0 && !cli.quiet) /* after --edit, which may add some */
        fprintf(stderr, "%s: %s: warning: no emitters (no emissive material, no KHR_lights_punctual light): "
                        "the cache holds no environments\n", prog, input);
    double t1 = lie_phase(prog, cli.verbose, "load", t0);
    lie_rt *rt = NULL;
    if (lie_rt_create(scene, &rt, &err) != LIE_OK) {
        lie_camera_path_destroy(cpath);
        lie_cache_destroy(old);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    double t2 = lie_phase(prog, cli.verbose, "bvh", t1);
    lie_pixels *px = NULL, *old_px = NULL;
    lie_status rc = LIE_OK;
    if (into) {
        /* the old views' pixels, then the old and new views' together */
        cv.cams = malloc(sizeof *cv.cams * ((size_t)old->views.n_cams + 1));
        if (!cv.cams)
            rc = lie_error_set(&err, LIE_ERR_NOMEM, into, "out of memory");
        else
            memcpy(cv.cams, old->views.cams, sizeof *cv.cams * (size_t)old->views.n_cams);
        cv.n_cams = cv.cams ? old->views.n_cams : 0;
        if (rc == LIE_OK)
            rc = lie_camera_pixels(scene, rt, cv.cams, cv.n_cams, cv.width, cv.height, cv.max_depth, &old_px, &err);
    }
    if (rc == LIE_OK && (n_views || path_file)) {
        int first_new = cv.n_cams;
        rc = gather_views(scene, input, views, n_views, cpath, &cv, &err);
        if (rc == LIE_OK)
            rc = lie_camera_pixels(scene, rt, cv.cams + first_new, cv.n_cams - first_new, cv.width, cv.height,
                                   cv.max_depth, &px, &err);
        if (rc == LIE_OK && old_px) { /* the old views' pixels and the new: all the views' */
            lie_pixels *added = px;
            px = NULL;
            rc = lie_pixels_merge(old_px, added, &px, &err);
            lie_pixels_destroy(added);
        }
    }
    lie_camera_path_destroy(cpath);
    if (rc == LIE_OK && resume && !same_views(&resume->views, &cv))
        rc = lie_error_set(&err, LIE_ERR_ARG, resume_file, "was built for other views (--view, --path, --view-size)");
    if (rc == LIE_OK)
        rc = lie_dist_check(scene->hash, scene->hash, &err);
    if (rc != LIE_OK) {
        free_edits(edit_log, n_edits);
        lie_cache_destroy(resume);
        lie_pixels_destroy(px);
        lie_pixels_destroy(old_px);
        free(cv.cams);
        lie_cache_destroy(old);
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    if (px)
        t2 = lie_phase(prog, cli.verbose, "views", t2);
    lie_progress prog_bar;
    lie_progress_begin(&prog_bar, stderr, "lie-build", !cli.quiet);
    cpu0 = lie_cpu_time();
    lie_env *env = NULL;
    lie_build_stats st;
    lie_add_stats as;
    memset(&st, 0, sizeof st);
    memset(&as, 0, sizeof as);
    if (into) {
        env = old->env;
        old->env = NULL;
        rc = lie_env_add_views(env, scene, rt, old_px, px, bp.threads, &st, &as, &err);
    } else if (lie_dist_size() > 1) {
        rc = build_dist(scene, rt, &bp, px, &env, &st, &err);
    } else {
        lie_build_control ctl;
        memset(&ctl, 0, sizeof ctl);
        ctl.pixels = px;
        ctl.progress = &prog_bar;
        ctl.resume = resume ? resume->env : NULL;
        ctl.stop = partial ? &stop_signal : NULL;
        int handlers[3] = {0, 0, 0};
        if (partial)
            stop_handlers(1, handlers);
        rc = lie_env_build_with(scene, rt, &bp, &ctl, &env, &st, &err);
        if (partial)
            stop_handlers(0, handlers); /* from here a signal aborts; the write's handler cleans up */
    }
    lie_cache_destroy(resume);
    lie_pixels_destroy(old_px);
    lie_progress_end(&prog_bar);
    if (rc != LIE_OK || !env) { /* !env: another rank than 0 under mpirun: rank 0 writes */
        free_edits(edit_log, n_edits);
        lie_env_destroy(env);
        lie_pixels_destroy(px);
        free(cv.cams);
        lie_cache_destroy(old);
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return rc != LIE_OK ? fail(&err) : 0;
    }
    double t3 = lie_phase(prog, cli.verbose, "build", t2), cpu_build = lie_cpu_time() - cpu0;
    lie_cache cache;
    memset(&cache, 0, sizeof cache);
    cache.scene_path = (char *)input;
    cache.scene_hash = old ? old->scene_hash : loaded_hash;
    if (old) { /* the edit log goes on */
        cache.edits = old->edits;
        cache.n_edits = old->n_edits;
    } else {
        cache.edits = edit_log;
        cache.n_edits = n_edits;
    }
    rc = lie_cache_set_state(&cache, scene, &err);
    cache.env = env;
    cache.views = cv;
    size_t bytes = 0;
    if (rc == LIE_OK)
        rc = lie_cache_write(output, &cache, &bytes, &err);
    double t4 = lie_phase(prog, cli.verbose && rc == LIE_OK, "write", t3);
    if (rc == LIE_OK && cli.stats) {
        lie_prediction pred;
        lie_env_predict(env, px, &pred);
        print_stats(input, scene, env, &st, into ? &as : NULL, px ? &pred : NULL, cpu_build, t1 - t0, t2 - t1,
                    t3 - t2, t4 - t3, bytes, cli.stats == 2);
    }
    free(cache.emitters);
    free(cv.cams);
    free_edits(edit_log, n_edits);
    lie_pixels_destroy(px);
    int partial_done = env->partial;
    uint64_t unbuilt = st.units_interrupted;
    lie_env_destroy(env);
    lie_cache_destroy(old);
    lie_rt_destroy(rt);
    lie_scene_destroy(scene);
    if (rc != LIE_OK)
        return fail(&err);
    if (stop_signal) {
        /* one line, and the shell's status for a signal: the caller sees it stopped */
        if (partial_done)
            fprintf(stderr, "%s: %s: interrupted by %s: wrote a partial cache, %llu units not built "
                            "(lie-build --resume %s completes it)\n", prog, output, signal_name(stop_signal),
                    (unsigned long long)unbuilt, strcmp(output, "-") == 0 ? "CACHE" : output);
        else
            fprintf(stderr, "%s: %s: interrupted by %s after the last unit: the cache is complete\n", prog, output,
                    signal_name(stop_signal));
        return 128 + stop_signal;
    }
    return 0;
}
