/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build: build the local illumination environments of a scene and write
 * them to a cache.
 *   lie-build SCENE.gltf|SCENE.glb -o CACHE|- [options]
 * The steps are in tools/lie-build/job.c, the statistics in stats.c. */
#include "common/cli.h"
#include "dist.h"
#include "job.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static const char *prog = "lie-build";

static void usage(FILE *fp)
{
    lie_build_params d = lie_build_params_default();
    fprintf(fp,
            "Usage: %s SCENE.gltf|SCENE.glb -o CACHE|- [options]\n"
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
            "      --complex-predict on|off|audit  on: leave a unit whose lists will all\n"
            "                        pass the complex cap unbuilt, one complex leaf answered by\n"
            "                        Embree; audit: build it anyway and count, for --stats,\n"
            "                        what the prediction names beside what the build measures\n"
            "                        (default off)\n"
            "      --view CAMERA     build only the patches seen from this camera (a name, an\n"
            "                        index or eye=..,target=..; repeatable), directly or in\n"
            "                        mirrors; the rest is marked 'none' and rendered with full\n"
            "                        visibility (§4.3.1)\n"
            "      --path PATH.yaml  build only the patches seen from the frames of this camera\n"
            "                        path (formats/camera-path.md), as --view does for one camera\n"
            "      --view-size WxH   the image the views are sampled at (default 512x512); its\n"
            "                        pixels decide how fine the views' patches get (§4.3.3).\n"
            "                        Without views, the image of the frames a whole build\n"
            "                        assumes, its pixels spread over the scene's surface by area\n"
            "      --into CACHE      add the units more views need to CACHE, a cache built for\n"
            "                        views: units already built are kept (or refined where the\n"
            "                        new pixels make a split pay), and the result is the cache\n"
            "                        one build for all the views gives.  CACHE's parameters,\n"
            "                        scene (SCENE overrides its path) and view size are used;\n"
            "                        written back to CACHE unless -o\n"
            "    The cost model (a unit, and a split, must save more render time over the\n"
            "    frames than it costs to build, else it is left to Embree; pixels are the\n"
            "    views', or without views --view-size's spread over the surface by area;\n"
            "    --stats shows its predictions):\n"
            "      --frames N        frames the cache will serve (default %u; 0: no pixel\n"
            "                        rule, every seen unit built, patches as fine as their\n"
            "                        lists need: a whole build then builds every unit)\n"
            "      --light-samples N light samples per pixel in them, shared among the\n"
            "                        emitters by their unshadowed light (default %u)\n"
            "      --cost S,B,R      ns per build segment, per blocker test, per Embree shadow\n"
            "                        ray (default %g,%g,%g; make bench-build measures them)\n"
            "      --emitter-clusters K  split each large area emitter into up to K clusters\n"
            "                        in space (default 1; docs/measurements.md, \"Emitters\n"
            "                        in clusters\")\n"
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
            "      --stats-file FILE the --stats=json record to FILE, not stderr\n"
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
    OPT_VIEW, OPT_VIEW_SIZE, OPT_PATH, OPT_MAX_NODES,
    OPT_INTO, OPT_FRAMES, OPT_LIGHT_SAMPLES, OPT_COST, OPT_PARTIAL, OPT_RESUME, OPT_EDIT, OPT_CLUSTERS,
    OPT_COMPLEX_PREDICT
};

static const struct option long_opts[] = {
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
    {"emitter-clusters", required_argument, NULL, OPT_CLUSTERS},
    {"complex-predict", required_argument, NULL, OPT_COMPLEX_PREDICT},
    {NULL, 0, NULL, 0},
};

/* --cost S,B,R: three times in ns, each in (0, 1e9]. */
static int parse_cost(const char *arg, lie_build_params *bp)
{
    char *end = NULL;
    double a = strtod(arg, &end), b = end && *end == ',' ? strtod(end + 1, &end) : -1.0,
           r = end && *end == ',' ? strtod(end + 1, &end) : -1.0;
    if (!end || *end || !(a > 0 && a <= 1e9) || !(b > 0 && b <= 1e9) || !(r > 0 && r <= 1e9))
        return 0;
    bp->ns_segment = (float)a;
    bp->ns_blocker = (float)b;
    bp->ns_ray = (float)r;
    return 1;
}

/* A build parameter of the command line: 1 when it took it, 0 when it is
 * not one, -1 after its usage error (cli->status). */
static int build_param(lie_cli *cli, int c, lie_build_params *bp)
{
    static const lie_cli_choice modes[] = {
        {"sampled", LIE_BLOCKERS_SAMPLED}, {"conservative", LIE_BLOCKERS_CONSERVATIVE}, {NULL, 0}};
    static const lie_cli_choice predict[] = {{"on", 1}, {"off", 0}, {"audit", 2}, {NULL, 0}};
    static const lie_cli_int ints[] = {
        {OPT_SAMPLES, 1, 1 << 20, offsetof(lie_build_params, samples)},
        {OPT_MAX_SAMPLES, 1, 1 << 24, offsetof(lie_build_params, max_samples)},
        {OPT_MAX_BLOCKERS, 0, 1 << 20, offsetof(lie_build_params, max_blockers)},
        {OPT_COMPLEX_CAP, 0, 1 << 24, offsetof(lie_build_params, complex_cap)},
        {OPT_FRAMES, 0, 1 << 24, offsetof(lie_build_params, frames)},
        {OPT_LIGHT_SAMPLES, 1, 1 << 24, offsetof(lie_build_params, light_samples)},
    };
    int mode, taken = lie_cli_set_int(cli, c, ints, sizeof ints / sizeof ints[0], bp);
    if (taken)
        return taken;
    switch (c) {
    case OPT_MIN_PATCH:
        if (lie_parse_float(optarg, LIE_MIN_PATCH_MIN, 1.0f, &bp->min_patch))
            return 1;
        cli->status = usage_error("--min-patch: expected a fraction in [%g, 1], got '%s'", (double)LIE_MIN_PATCH_MIN,
                                  optarg);
        return -1;
    case OPT_SPLIT_GAIN:
        if (lie_parse_float(optarg, 0.0f, 0.999f, &bp->split_gain))
            return 1;
        cli->status = usage_error("--split-gain: expected a share in [0, 1), got '%s'", optarg);
        return -1;
    case OPT_COST:
        if (parse_cost(optarg, bp))
            return 1;
        cli->status = usage_error("--cost: expected three times in ns, S,B,R, each in (0, 1e9], got '%s'", optarg);
        return -1;
    case OPT_BLOCKERS:
        if (!lie_cli_pick(cli, modes, &mode))
            return -1;
        bp->mode = (lie_blocker_mode)mode;
        return 1;
    case OPT_COMPLEX_PREDICT:
        if (!lie_cli_pick(cli, predict, &mode))
            return -1;
        bp->complex_predict = mode == 1; /* audit: built as off (build_job.audit_complex) */
        return 1;
    default: return 0;
    }
}

/* The options: -1 to go on, or the exit status. */
static int parse_options(build_job *j, lie_cli *cli, int argc, char **argv)
{
    long v;
    int c, taken;
    while ((c = lie_cli_next(cli, argc, argv, "", long_opts)) > 0) {
        if ((taken = build_param(cli, c, &j->bp)) != 0) {
            if (taken < 0)
                return cli->status;
            j->params_given = 1;
            if (c == OPT_COMPLEX_PREDICT)
                j->audit_complex = strcmp(optarg, "audit") == 0;
            continue;
        }
        switch (c) {
        case OPT_MAX_NODES:
            if (!lie_cli_long(cli, 1, 0xFFFFFFF0L, &v))
                return cli->status;
            j->bp.max_nodes = (uint64_t)v;
            break;
        case OPT_VIEW:
            if (j->n_views == JOB_MAX_VIEWS)
                return usage_error("--view: at most 64 views, got another: '%s'", optarg);
            j->views[j->n_views++] = optarg;
            break;
        case OPT_CLUSTERS:
            if (!lie_cli_long(cli, 1, LIE_CLUSTER_MAX, &v))
                return cli->status;
            j->so.emitter_clusters = (int)v;
            break;
        case OPT_PATH: j->path_file = optarg; break;
        case OPT_INTO: j->into = optarg; break;
        case OPT_PARTIAL: j->partial = 1; break;
        case OPT_RESUME: j->resume_file = optarg; break;
        case OPT_EDIT:
            if (j->n_edits == JOB_MAX_EDITS)
                return usage_error("--edit: at most 64 edit files, got another: '%s'", optarg);
            j->edit_log[j->n_edits].name = optarg;
            j->edit_log[j->n_edits++].text = NULL;
            break;
        case OPT_VIEW_SIZE:
            if (!lie_parse_size(optarg, 16384, &j->view_w, &j->view_h))
                return usage_error("--view-size: expected WxH, got '%s'", optarg);
            j->size_given = 1;
            break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli->status;
    j->bp.threads = cli->threads;
    j->output = cli->output;
    j->so.allow_external_uris = cli->external;
    j->so.threads = cli->threads;
    return -1;
}

/* The operands and the options that exclude each other: -1 to go on, or
 * the exit status. */
static int check_operands(build_job *j, int argc, char **argv)
{
    if (j->into && (j->resume_file || j->n_edits))
        return usage_error("%s", "--into: give no --resume or --edit (rst-update edits a cache)");
    if (j->resume_file && j->params_given)
        return usage_error("%s", "--resume: the partial cache's build parameters are used; give none");
    if (j->into) {
        if (optind + 1 < argc)
            return usage_error("unexpected argument '%s'", argv[optind + 1]);
        if (!j->n_views && !j->path_file)
            return usage_error("%s", "--into: give the views to add (--view or --path)");
        if (j->params_given)
            return usage_error("%s", "--into: the cache's build parameters are used; give none");
        if (!j->output)
            j->output = j->into;
    } else {
        if (optind >= argc)
            return usage_error("%s", "missing input scene");
        if (optind + 1 < argc)
            return usage_error("unexpected argument '%s'", argv[optind + 1]);
        if (!j->output)
            return usage_error("%s", "missing -o CACHE");
    }
    /* a whole build's model assumes frames of --view-size's pixels (a view
     * build keeps the default, which its model does not read, as lie-view's
     * constructor does) */
    if (!j->into && !j->resume_file && !j->n_views && !j->path_file)
        j->bp.whole_pixels = (uint32_t)j->view_w * (uint32_t)j->view_h;
    if (j->bp.max_samples < j->bp.samples)
        j->bp.max_samples = j->bp.samples; /* --samples above the default cap: one round */
    j->input = optind < argc ? argv[optind] : NULL;
    return -1;
}

/* The scene's warnings, after --edit (which may add emitters). */
static void warn_scene(const build_job *j)
{
    lie_print_scene_warnings(prog, j->scene, j->input);
    if (j->scene->n_emitters == 0)
        fprintf(stderr, "%s: %s: warning: no emitters (no emissive material, no KHR_lights_punctual light): "
                        "the cache holds no environments\n", prog, j->input);
}

/* After a signal under --partial: one line, and the shell's status for a
 * signal, so the caller sees it stopped. */
static int report_stop(const char *output, int partial_done, uint64_t unbuilt)
{
    if (partial_done)
        fprintf(stderr, "%s: %s: interrupted by %s: wrote a partial cache, %llu units not built "
                        "(lie-build --resume %s completes it)\n", prog, output, job_signal_name(job_stop_signal),
                (unsigned long long)unbuilt, strcmp(output, "-") == 0 ? "CACHE" : output);
    else
        fprintf(stderr, "%s: %s: interrupted by %s after the last unit: the cache is complete\n", prog, output,
                job_signal_name(job_stop_signal));
    return 128 + job_stop_signal;
}

/* The run after the command line: load, bvh, views, build, write, each a
 * phase of -v; t[] their times for --stats. */
static int run(build_job *j, const lie_cli *cli)
{
    double t[5], cpu0;
    t[0] = lie_time_now();
    if (job_load(j) != LIE_OK)
        return fail(&j->err);
    if (!cli->quiet)
        warn_scene(j);
    t[1] = lie_phase(prog, cli->verbose, "load", t[0]);
    if (lie_rt_create(j->scene, &j->rt, &j->err) != LIE_OK)
        return fail(&j->err);
    t[2] = lie_phase(prog, cli->verbose, "bvh", t[1]);
    if (job_views(j) != LIE_OK)
        return fail(&j->err);
    if (j->px)
        t[2] = lie_phase(prog, cli->verbose, "views", t[2]);
    lie_progress bar;
    lie_progress_begin(&bar, stderr, "lie-build", !cli->quiet);
    cpu0 = lie_cpu_time();
    lie_status rc = job_build(j, &bar);
    lie_progress_end(&bar);
    if (rc != LIE_OK || !j->env) /* !env: another rank than 0 under mpirun: rank 0 writes */
        return rc != LIE_OK ? fail(&j->err) : 0;
    t[3] = lie_phase(prog, cli->verbose, "build", t[2]);
    double cpu_build = lie_cpu_time() - cpu0;
    rc = job_write(j);
    t[4] = lie_phase(prog, cli->verbose && rc == LIE_OK, "write", t[3]);
    if (rc != LIE_OK)
        return fail(&j->err);
    if (cli->stats) {
        double dt[4] = {t[1] - t[0], t[2] - t[1], t[3] - t[2], t[4] - t[3]};
        if (job_print_stats(cli, j, cpu_build, dt) != LIE_OK)
            return fail(&j->err);
    }
    return job_stop_signal ? report_stop(j->output, j->env->partial, j->st.units_interrupted) : 0;
}

int main(int argc, char **argv)
{
    build_job j;
    job_init(&j);
    lie_cli cli = {.tool = prog, .usage = usage, .takes = LIE_CLI_OUTPUT | LIE_CLI_THREADS | LIE_CLI_EXTERNAL |
                                                          LIE_CLI_STATS | LIE_CLI_VERBOSE};
    int rc = parse_options(&j, &cli, argc, argv);
    if (rc < 0)
        rc = check_operands(&j, argc, argv);
    if (rc >= 0)
        return rc;
    if (lie_dist_start(&argc, &argv) > 1) {
        cli.quiet = 1; /* rank 0 prints the statistics */
        if (lie_dist_rank() != 0)
            cli.stats = 0;
        if (j.into || j.partial || j.resume_file || j.n_edits) {
            lie_error e;
            lie_error_set(&e, LIE_ERR_ARG, j.into ? j.into : j.input,
                          "--into, --edit, --partial and --resume run in one process, not under mpirun");
            return fail(&e);
        }
    }
    rc = run(&j, &cli);
    job_free(&j);
    return rc;
}
