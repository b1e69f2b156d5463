/* SPDX-License-Identifier: Apache-2.0 */
/* rst-update: apply edit files to a cache's scene and recompute only the
 * local illumination environments the edits can have changed (§5).
 *   rst-update CACHE|- EDIT.yaml [EDIT.yaml ...] -o CACHE|- [options] */
#include "common/cli.h"
#include "lie.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *prog = "rst-update";

static void usage(FILE *fp)
{
    fprintf(fp,
            "Usage: %s CACHE|- EDIT.yaml [EDIT.yaml ...] -o CACHE|- [options]\n"
            "\n"
            "Apply scene edits (formats/edit.md) to the scene of a LIE cache, find the\n"
            "blocker lists they may change through ray segment trees, recompute only\n"
            "those, and write the updated cache (its edit log gains the edits).  The\n"
            "result equals a fresh lie-build of the edited scene.\n"
            "\n"
            "  -o, --output FILE     the cache to write; - writes to stdout\n"
            "      --full            recompute everything (the reference for update = rebuild)\n"
            "      --write-scene OUT.gltf|OUT.glb  also write the edited scene: .glb is one\n"
            "                        binary glTF file (images inside); .gltf also writes\n"
            "                        OUT.bin and its images beside it (OUT_imgN.jpg, .png:\n"
            "                        the file's own bytes; OUT_texN.png: textures an edit\n"
            "                        added); one warning line per thing not written\n"
            "      --force           let --write-scene replace side files (OUT.bin,\n"
            "                        images) that are not its own; its own are the\n"
            "                        ones the OUT.gltf being replaced lists, with the hash\n"
            "                        of the bytes they still hold (lie wrote them)\n"
            "      --threads N       worker threads (default: all cores)\n"
            "      --allow-external-uris  let glTF files reference files outside their folder\n"
            "      --stats[=json]    pairs flagged, pairs really changed, time per phase\n"
            "      --stats-file FILE the --stats=json record to FILE, not stderr\n"
            "  -q, --quiet           no progress bar, no warnings\n"
            "  -v, --verbose         each phase's time on stderr (load, update, write)\n"
            "  -h, --help            this help\n"
            "      --version         print the version\n"
            "\n"
            "rst-update is one process: it is not shared out under mpirun (an update\n"
            "recomputes few units; run it without mpirun, see docs/mpi.md).\n",
            prog);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_report_error(prog, err, 1); }

enum { OPT_FULL = 256, OPT_WRITE_SCENE, OPT_FORCE };

static const struct option long_opts[] = {
    {"full", no_argument, NULL, OPT_FULL},
    {"write-scene", required_argument, NULL, OPT_WRITE_SCENE},
    {"force", no_argument, NULL, OPT_FORCE},
    {NULL, 0, NULL, 0},
};

/* --write-scene names a .gltf or a .glb (lie_gltf_export_group). */
static int scene_format_ok(const char *path)
{
    size_t n = strlen(path);
    return (n > 5 && strcasecmp(path + n - 5, ".gltf") == 0) || (n > 4 && strcasecmp(path + n - 4, ".glb") == 0);
}

/* Read and parse every edit file first: a bad edit leaves everything untouched. */
static lie_status read_edits(lie_file_set *set, char **files, int n, lie_edit **edits, lie_error *err)
{
    for (int i = 0; i < n; i++) {
        unsigned char *text = NULL;
        size_t size = 0;
        lie_status st = lie_file_set_read(set, files[i], LIE_READ_MAX_TEXT, &text, &size, err);
        if (st == LIE_OK)
            st = lie_edit_parse(text, size, files[i], &edits[i], err);
        free(text);
        if (st != LIE_OK)
            return st;
    }
    return LIE_OK;
}

/* Phase 2 in chunks while a progress bar shows (a terminal, no -q), else at once. */
static lie_status run_steps(lie_update *u, int quiet, lie_error *err)
{
    lie_progress bar;
    lie_progress_begin(&bar, stderr, prog, !quiet);
    size_t total = lie_update_pending(u), left = total;
    size_t chunk = bar.active ? total / 16 + 1 : 0;
    lie_status st;
    do {
        st = lie_update_step(u, chunk, &left, err);
        lie_progress_update(&bar, total - left, total);
    } while (st == LIE_OK && left);
    lie_progress_end(&bar);
    return st;
}

static lie_status print_stats(const lie_cli *cli, const char *input, const lie_scene *s, const lie_update_stats *st,
                              double t_load, double t_write, size_t bytes, lie_error *err)
{
    const lie_rst_stats *rs = &st->rst;
    double precision = st->units_flagged ? (double)st->units_changed / (double)st->units_flagged : 1.0;
    if (cli->stats == 2) {
        lie_stats_json js;
        FILE *fp = lie_stats_json_begin(&js, prog, input);
        if (!fp)
            return lie_stats_json_end(cli, &js, err);
        fprintf(fp,
                ",\"edits\":%d,\"units\":%llu,\"units_rebuilt\":%llu,\"units_views\":%llu,"
                "\"units_flagged\":%llu,\"units_changed\":%llu,\"precision\":%.4f,\"nodes_flagged_5d\":%llu,\"nodes_flagged\":%llu,"
                "\"nodes_recomputed\":%llu,\"rst_regions\":%llu,\"rst_fallback\":%llu,\"rst_tree_nodes\":%llu,"
                "\"rst_bytes\":%zu,\"seconds_load\":%.6f,\"seconds_rst\":%.6f,\"seconds_edit\":%.6f,"
                "\"seconds_query\":%.6f,\"seconds_bvh\":%.6f,\"seconds_views\":%.6f,\"seconds_update\":%.6f,"
                "\"seconds_write\":%.6f,\"bytes\":%zu,\"seconds_cpu\":%.6f,\"seconds_cpu_workers\":%.6f,"
                "\"seconds_cpu_worker_max\":%.6f,\"seconds_tail\":%.6f}\n",
                st->edits, (unsigned long long)st->units, (unsigned long long)st->units_rebuilt,
                (unsigned long long)st->units_views,
                (unsigned long long)st->units_flagged, (unsigned long long)st->units_changed, precision,
                (unsigned long long)st->nodes_flagged_5d, (unsigned long long)st->nodes_flagged,
                (unsigned long long)st->nodes_recomputed, (unsigned long long)rs->regions,
                (unsigned long long)rs->fallback, (unsigned long long)rs->tree_nodes, rs->bytes, t_load,
                st->seconds_rst, st->seconds_edit, st->seconds_query, st->seconds_bvh, st->seconds_views,
                st->seconds_update, t_write, bytes, lie_cpu_time(), st->seconds_cpu_workers, st->seconds_cpu_worker_max,
                st->seconds_tail);
        return lie_stats_json_end(cli, &js, err);
    }
    fprintf(stderr,
            "%s: %s: %d edit file%s, %llu units (%u triangles x %d emitters)\n"
            "  ray segment trees: %llu regions (%llu by bounds only), %llu tree nodes, %.1f MB\n"
            "  units rebuilt (patch or emitter edited, or its pixels in the cache's views changed: %llu): %llu; "
            "units flagged: %llu, really changed: %llu "
            "(precision %.0f%%)\n"
            "  unit roots flagged by the trees %llu; patch-tree nodes flagged by exact hull tests down from them %llu, recomputed %llu\n"
            "  time: load %.3f s, trees %.3f s, edits %.3f s, queries %.3f s, bvh %.3f s, update %.3f s, write %.3f s\n",
            prog, input, st->edits, st->edits == 1 ? "" : "s", (unsigned long long)st->units, s->n_tris,
            s->n_emitters, (unsigned long long)rs->regions, (unsigned long long)rs->fallback,
            (unsigned long long)rs->tree_nodes, (double)rs->bytes / 1e6, (unsigned long long)st->units_views,
            (unsigned long long)st->units_rebuilt,
            (unsigned long long)st->units_flagged, (unsigned long long)st->units_changed, 100.0 * precision,
            (unsigned long long)st->nodes_flagged_5d, (unsigned long long)st->nodes_flagged,
            (unsigned long long)st->nodes_recomputed, t_load, st->seconds_rst, st->seconds_edit, st->seconds_query,
            st->seconds_bvh, st->seconds_update, t_write);
    fprintf(stderr, "  cpu: %.3f s in all; the recomputation's workers %.3f s, the busiest %.3f s, cores idle %.3f s\n",
            lie_cpu_time(), st->seconds_cpu_workers, st->seconds_cpu_worker_max, st->seconds_tail);
    return LIE_OK;
}

/* Read the cache and its scene, update them (lib/update), write the cache. */
/* What main hands run(). */
typedef struct run_opts {
    const char *output, *scene_out;
    lie_gltf_export_options scene_opt;
    int quiet, verbose, stats;
    const lie_cli *cli; /* --stats=json's destination */
} run_opts;

/* The outputs, before any work: neither may be an input (the cache, the edit
 * files, the scene with its buffers and images, the files edits add) or the
 * other; -o may replace the input cache (an update in place).  The scene's
 * side files are claimed by the export. */
static lie_status claim_outputs(lie_file_set *set, const char *input, const run_opts *ro, lie_error *err)
{
    lie_status st = lie_file_set_claim(set, ro->output, input, err);
    if (st == LIE_OK && ro->scene_out)
        st = lie_file_set_claim(set, ro->scene_out, NULL, err);
    return st;
}

/* What --write-scene does not write, one warning line each. */
static void scene_warn(void *ctx, const char *msg)
{
    fprintf(stderr, "%s: %s: warning: %s\n", prog, (const char *)ctx, msg);
}

static lie_status run(const char *input, char **files, int n_files, const lie_update_options *uo_in,
                      const run_opts *ro_in, lie_error *err)
{
    lie_update_options uo_copy = *uo_in;
    run_opts ro_copy = *ro_in;
    const lie_update_options *uo = &uo_copy;
    const run_opts *ro = &ro_copy;
    lie_file_set *set = lie_file_set_create(LIE_FILES_NAMES); /* the run's inputs and outputs */
    uo_copy.scene.files = ro_copy.scene_opt.files = set;
    int quiet = ro->quiet, stats = ro->stats;
    if (!quiet && ro->scene_out) {
        ro_copy.scene_opt.warn = scene_warn;
        ro_copy.scene_opt.warn_ctx = (void *)ro->scene_out;
    }
    double t0 = lie_time_now();
    lie_cache *cache = NULL;
    lie_scene *scene = NULL;
    lie_update *u = NULL;
    lie_edit **edits = calloc((size_t)n_files, sizeof *edits);
    lie_update_stats ust;
    size_t bytes = 0;
    double t_load = 0;
    lie_status st = edits && set ? LIE_OK : lie_error_set(err, LIE_ERR_NOMEM, input, "out of memory");
    if (st == LIE_OK)
        st = read_edits(set, files, n_files, edits, err);
    if (st == LIE_OK && (st = lie_cache_read(input, &cache, err)) == LIE_OK)
        st = lie_file_set_note(set, input, err);
    if (st == LIE_OK)
        st = lie_cache_load_scene(cache, input, NULL, &uo->scene, &scene, err);
    if (st == LIE_OK)
        st = claim_outputs(set, input, ro, err);
    if (st == LIE_OK) {
        t_load = lie_time_now() - t0;
        lie_phase(prog, ro->verbose, "load", t0);
        if (!quiet)
            lie_print_scene_warnings(prog, scene, input);
        st = lie_update_create(cache, scene, uo, &u, err);
    }
    double tp = lie_phase(prog, ro->verbose && st == LIE_OK, "trees", t0 + t_load);
    for (int i = 0; st == LIE_OK && i < n_files; i++)
        st = lie_update_edit(u, edits[i], err);
    tp = lie_phase(prog, ro->verbose && st == LIE_OK, "edits", tp);
    if (st == LIE_OK)
        st = run_steps(u, quiet, err);
    lie_phase(prog, ro->verbose && st == LIE_OK, "update", tp);
    if (st == LIE_OK && scene->n_emitters == 0 && !quiet)
        fprintf(stderr, "%s: %s: warning: the edited scene has no emitters: every pixel is black\n", prog, input);
    double ta = lie_time_now();
    if (st == LIE_OK) {
        lie_cache_log_relative_to(cache, cache->n_edits - n_files, ro->output);
        st = lie_cache_write_with_scene(ro->output, cache, scene, ro->scene_out, &ro->scene_opt, &bytes, err);
    }
    lie_phase(prog, ro->verbose && st == LIE_OK, "write", ta);
    if (st == LIE_OK && stats) {
        lie_update_get_stats(u, &ust);
        st = print_stats(ro->cli, input, scene, &ust, t_load, lie_time_now() - ta, bytes, err);
    }
    for (int i = 0; edits && i < n_files; i++)
        lie_edit_destroy(edits[i]);
    free(edits);
    lie_update_destroy(u);
    lie_scene_destroy(scene);
    lie_cache_destroy(cache);
    lie_file_set_destroy(set);
    return st;
}

int main(int argc, char **argv)
{
    lie_update_options uo = lie_update_options_default();
    run_opts ro = {NULL, NULL, lie_gltf_export_options_default(), 0, 0, 0, NULL};
    int c;
    lie_cli cli = {.tool = prog, .usage = usage,
                   .takes = LIE_CLI_OUTPUT | LIE_CLI_THREADS | LIE_CLI_EXTERNAL | LIE_CLI_STATS | LIE_CLI_VERBOSE};
    while ((c = lie_cli_next(&cli, argc, argv, "", long_opts)) > 0) {
        switch (c) {
        case OPT_FULL: uo.full = 1; break;
        case OPT_WRITE_SCENE: ro.scene_out = optarg; break;
        case OPT_FORCE: ro.scene_opt.force = 1; break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    uo.scene.allow_external_uris = cli.external;
    uo.threads = cli.threads;
    ro.output = cli.output;
    ro.stats = cli.stats;
    ro.cli = &cli;
    ro.quiet = cli.quiet;
    ro.verbose = cli.verbose;
    if (optind >= argc)
        return usage_error("%s", "missing input cache");
    if (optind + 1 >= argc)
        return usage_error("%s", "missing edit files");
    if (!ro.output)
        return usage_error("%s", "missing -o CACHE");
    if (ro.scene_out && strcmp(ro.scene_out, "-") == 0)
        return usage_error("%s", "--write-scene: not to stdout: name a .gltf or .glb file");
    if (ro.scene_out && !scene_format_ok(ro.scene_out))
        return usage_error("--write-scene: %s: cannot write this format: use .gltf or .glb", ro.scene_out);
    const char *input = argv[optind];
    int n_files = argc - optind - 1;
    char **files = argv + optind + 1;
    for (int i = 0; i < n_files; i++)
        if (strcmp(files[i], "-") == 0 && strcmp(input, "-") == 0)
            return usage_error("%s", "only one of the cache and the edit files can be stdin");
    lie_error err;
    lie_error_clear(&err);
    if (run(input, files, n_files, &uo, &ro, &err) != LIE_OK)
        return fail(&err);
    return 0;
}
