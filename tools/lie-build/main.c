/* lie-build: build the local illumination environments of a scene and write
 * them to a cache.
 *   lie-build SCENE.gltf|SCENE.glb -o CACHE|- [options] */
#include "common/cli.h"
#include "dist.h"
#include "lie.h"

#include <getopt.h>
#include <time.h>
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
            prog, prog, d.samples, d.max_samples, d.max_blockers, (double)LIE_MIN_PATCH_MIN, (double)d.min_patch,
            (double)d.split_gain,
            (unsigned long long)LIE_MAX_NODES_DEFAULT, d.complex_cap, d.frames, d.light_samples,
            (double)d.ns_segment, (double)d.ns_blocker, (double)d.ns_ray);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_dist_fail(prog, err, 1); }

enum {
    OPT_SAMPLES = 256, OPT_MAX_SAMPLES, OPT_MAX_BLOCKERS, OPT_MIN_PATCH, OPT_SPLIT_GAIN, OPT_COMPLEX_CAP, OPT_BLOCKERS,
    OPT_THREADS, OPT_STATS, OPT_VERSION, OPT_EXTERNAL, OPT_VIEW, OPT_VIEW_SIZE, OPT_PATH, OPT_MAX_NODES,
    OPT_INTO, OPT_FRAMES, OPT_LIGHT_SAMPLES, OPT_COST
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
    {"frames", required_argument, NULL, OPT_FRAMES},
    {"light-samples", required_argument, NULL, OPT_LIGHT_SAMPLES},
    {"cost", required_argument, NULL, OPT_COST},
    {"threads", required_argument, NULL, OPT_THREADS},
    {"allow-external-uris", no_argument, NULL, OPT_EXTERNAL},
    {"stats", optional_argument, NULL, OPT_STATS},
    {"quiet", no_argument, NULL, 'q'},
    {"verbose", no_argument, NULL, 'v'},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, OPT_VERSION},
    {NULL, 0, NULL, 0},
};

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
        if (as)
            fprintf(stderr, ",\"into\":{\"units_kept\":%llu,\"units_refined\":%llu,\"units_new\":%llu,"
                            "\"nodes_recomputed\":%llu}",
                    (unsigned long long)as->units_kept, (unsigned long long)as->units_refined,
                    (unsigned long long)as->units_new, (unsigned long long)as->nodes_flagged);
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
    fprintf(stderr, "\n  segments cast %llu; splits kept %llu, undone (did not shorten lists) %llu, not tried "
                    "(too few pixels) %llu; %u nodes, %u pooled blockers, %zu bytes written\n",
            (unsigned long long)st->segments, (unsigned long long)st->splits_kept,
            (unsigned long long)st->splits_undone, (unsigned long long)st->splits_pixels, env->n_nodes, env->n_pool,
            bytes);
    fprintf(stderr, "  time: load %.3f s, bvh %.3f s, build %.3f s, write %.3f s\n", t_load, t_bvh, t_build,
            t_write);
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
                               const char *path_file, lie_cache_views *v, lie_error *err)
{
    lie_camera_path *cpath = NULL;
    lie_status st = path_file ? lie_camera_path_read(path_file, &cpath, err) : LIE_OK;
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
    lie_camera_path_destroy(cpath);
    return st;
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    lie_build_params bp = lie_build_params_default();
    lie_scene_options so = lie_scene_options_default();
    const char *output = NULL, *into = NULL;
    int stats = 0, quiet = 0, verbose = 0, params_given = 0, size_given = 0;
    const char *views[64], *path_file = NULL;
    int n_views = 0, view_w = 512, view_h = 512;
    long v;
    float f;
    int c;
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:qvh", long_opts, NULL)) != -1) {
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
        case OPT_EXTERNAL: so.allow_external_uris = 1; break;
        case OPT_VIEW:
            if (n_views == 64)
                return usage_error("--view: at most 64 views, got another: '%s'", optarg);
            views[n_views++] = optarg;
            break;
        case OPT_PATH: path_file = optarg; break;
        case OPT_INTO: into = optarg; break;
        case OPT_VIEW_SIZE:
            if (!lie_parse_size(optarg, 16384, &view_w, &view_h))
                return usage_error("--view-size: expected WxH, got '%s'", optarg);
            size_given = 1;
            break;
        case OPT_STATS:
            if (!(stats = lie_parse_stats(optarg)))
                return usage_error("--stats: expected --stats or --stats=json, got '%s'", optarg);
            break;
        case 'q': quiet = 1; break;
        case 'v': verbose = 1; break;
        case 'h': usage(stdout); return 0;
        case OPT_VERSION: { char vr[512]; lie_version_report(prog, vr, sizeof vr); fputs(vr, stdout); return 0; }
        case ':': return usage_error("%s: missing value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
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
        quiet = 1; /* rank 0 prints the statistics */
        if (lie_dist_rank() != 0)
            stats = 0;
        if (into) {
            lie_error e;
            lie_error_set(&e, LIE_ERR_ARG, into, "--into runs in one process, not under mpirun");
            return fail(&e);
        }
    }
    lie_error err;
    lie_error_clear(&err);
    double t0 = lie_time_now(), cpu0 = cpu_seconds();
    lie_scene *scene = NULL;
    lie_cache *old = NULL;
    lie_cache_views cv = {NULL, 0, view_w, view_h, LIE_MAX_DEPTH_DEFAULT};
    if (into) {
        if (lie_cache_read(into, &old, &err) != LIE_OK ||
            lie_cache_load_scene(old, into, input, &so, &scene, &err) != LIE_OK) {
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
            lie_cache_destroy(old);
            lie_scene_destroy(scene);
            return fail(&err);
        }
        bp = old->env->params;
        cv.width = old->views.width;
        cv.height = old->views.height;
        cv.max_depth = old->views.max_depth;
        input = old->scene_path;
    } else if (build_load_scene(input, &so, &scene, &err) != LIE_OK) {
        lie_scene_destroy(scene);
        return fail(&err);
    }
    if (!quiet)
        lie_print_scene_warnings(prog, scene, input);
    if (scene->n_emitters == 0 && !quiet)
        fprintf(stderr, "%s: %s: warning: no emitters (no emissive material, no KHR_lights_punctual light): "
                        "the cache holds no environments\n", prog, input);
    double t1 = lie_phase(prog, verbose, "load", t0);
    lie_rt *rt = NULL;
    if (lie_rt_create(scene, &rt, &err) != LIE_OK) {
        lie_cache_destroy(old);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    double t2 = lie_phase(prog, verbose, "bvh", t1);
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
        rc = gather_views(scene, input, views, n_views, path_file, &cv, &err);
        if (rc == LIE_OK)
            rc = lie_camera_pixels(scene, rt, cv.cams, cv.n_cams, cv.width, cv.height, cv.max_depth, &px, &err);
    }
    if (rc == LIE_OK)
        rc = lie_dist_check(scene->hash, scene->hash, &err);
    if (rc != LIE_OK) {
        lie_pixels_destroy(px);
        lie_pixels_destroy(old_px);
        free(cv.cams);
        lie_cache_destroy(old);
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return fail(&err);
    }
    if (px)
        t2 = lie_phase(prog, verbose, "views", t2);
    lie_progress prog_bar;
    lie_progress_begin(&prog_bar, stderr, "lie-build", !quiet);
    cpu0 = cpu_seconds();
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
        rc = lie_env_build_views(scene, rt, &bp, px, &prog_bar, &env, &st, &err);
    }
    lie_pixels_destroy(old_px);
    lie_progress_end(&prog_bar);
    if (rc != LIE_OK || !env) { /* !env: another rank than 0 under mpirun: rank 0 writes */
        lie_env_destroy(env);
        lie_pixels_destroy(px);
        free(cv.cams);
        lie_cache_destroy(old);
        lie_rt_destroy(rt);
        lie_scene_destroy(scene);
        return rc != LIE_OK ? fail(&err) : 0;
    }
    double t3 = lie_phase(prog, verbose, "build", t2), cpu_build = cpu_seconds() - cpu0;
    lie_cache cache;
    memset(&cache, 0, sizeof cache);
    cache.scene_path = (char *)input;
    cache.scene_hash = old ? old->scene_hash : scene->hash;
    if (old) { /* the edit log goes on */
        cache.edits = old->edits;
        cache.n_edits = old->n_edits;
    }
    rc = lie_cache_set_state(&cache, scene, &err);
    cache.env = env;
    cache.views = cv;
    size_t bytes = 0;
    if (rc == LIE_OK)
        rc = lie_cache_write(output, &cache, &bytes, &err);
    double t4 = lie_phase(prog, verbose && rc == LIE_OK, "write", t3);
    if (rc == LIE_OK && stats) {
        lie_prediction pred;
        lie_env_predict(env, px, &pred);
        print_stats(input, scene, env, &st, into ? &as : NULL, px ? &pred : NULL, cpu_build, t1 - t0, t2 - t1,
                    t3 - t2, t4 - t3, bytes, stats == 2);
    }
    free(cache.emitters);
    free(cv.cams);
    lie_pixels_destroy(px);
    lie_env_destroy(env);
    lie_cache_destroy(old);
    lie_rt_destroy(rt);
    lie_scene_destroy(scene);
    if (rc != LIE_OK)
        return fail(&err);
    return 0;
}
