/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect: look inside caches.
 *   lie-inspect verify CACHE [--scene S]
 *   lie-inspect summary CACHE [--json]
 *   lie-inspect dump CACHE [--json]
 *   lie-inspect patch CACHE TRI[/PATH] [--json]
 *   lie-inspect diff A B [--all] [--strict] [--json]
 *   lie-inspect image CACHE -o OUT.png [--camera C] [--emitter K] [--size WxH]
 *   lie-inspect clean DIR [--min-age SECONDS] [--dry-run]
 * A thin front end over lib/cache: the library validates, the commands
 * (one file each) print. */
#include "inspect.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *fp)
{
    fprintf(fp,
            "Usage: %s COMMAND CACHE|- [options]\n"
            "\n"
            "Look inside a LIE cache (formats/lie-cache.md).  CACHE - reads stdin.\n"
            "\n"
            "commands:\n"
            "  verify CACHE [--scene S]  check the magic, version, section table, every\n"
            "                            checksum and the patch trees' structure; with\n"
            "                            --scene, also that S, with the cache's edit log\n"
            "                            replayed, is the scene the cache was built for\n"
            "                            (content hashes, triangles, emitters).\n"
            "                            Exit 0 valid, 1 not\n"
            "  summary CACHE [--json]    counts, pairs per class, patches per depth, the\n"
            "                            blocker-list histogram, bytes per section, the\n"
            "                            build parameters and the scene's hashes\n"
            "  dump CACHE [--json]       the canonical text: a header, then one line per\n"
            "                            patch-emitter pair (leaves and split nodes),\n"
            "                            sorted by triangle, patch, emitter; diff(1) of two\n"
            "                            dumps shows what changed\n"
            "  patch CACHE TRI[/PATH]    one patch's LIE: per emitter, the node at PATH and\n"
            "                            its subtree, or the leaf that covers PATH\n"
            "  diff A B                  compare two caches by content (units by triangle\n"
            "                            and emitter, nodes by patch, lists as sets); exit\n"
            "                            0 same, 1 different, 2 trouble\n"
            "  image CACHE -o OUT.png    the false-colour complexity image (the paper's\n"
            "                            Figure 10): green visible, blue occluded, grey by\n"
            "                            blocker count (black 1, white 10 or more), red\n"
            "                            complex or not built, black unlit\n"
            "  clean DIR                 remove the temporary files (.NAME.tmpXXXXXX) that\n"
            "                            the tools leave in DIR when killed by SIGKILL\n"
            "                            (SIGINT, SIGTERM and SIGHUP remove their own):\n"
            "                            this user's regular files not modified for\n"
            "                            --min-age seconds; prints each one removed\n"
            "\n"
            "options:\n"
            "      --json                summary, dump, patch, diff: JSON on stdout\n"
            "      --scene S             verify: the scene to check the cache against;\n"
            "                            image: load the scene from S (same content hash)\n"
            "      --all                 diff: list every difference (default the first %d)\n"
            "      --strict              diff: provenance (scene path, the scene's hash\n"
            "                            before edits, the edit log) counts as a difference\n"
            "  -o, --output FILE         image: the PNG to write (- for stdout)\n"
            "      --camera SPEC         image: a camera name or index in the scene, or\n"
            "                            eye=X,Y,Z,target=X,Y,Z[,up=X,Y,Z][,fov=DEG|ortho=HEIGHT]\n"
            "      --emitter K           image: emitter K alone (default: all emitters)\n"
            "      --size WxH            image: size (default %dx%d)\n"
            "      --threads N           image: worker threads (default: all cores)\n"
            "      --allow-external-uris let the glTF reference files outside its folder\n"
            "      --min-age SECONDS     clean: spare younger files, a run may still be\n"
            "                            writing them (default %d)\n"
            "      --dry-run             clean: list what would be removed, remove nothing\n"
            "  -q, --quiet               verify, diff, clean: report by exit status only;\n"
            "                            image: no progress bar; both: no scene warnings\n"
            "                            (an image the decoder cannot read)\n"
            "  -h, --help                this help\n"
            "      --version             print the version\n",
            inspect_prog, INSPECT_DIFF_SHOWN, LIE_RENDER_WIDTH_DEFAULT, LIE_RENDER_HEIGHT_DEFAULT,
            INSPECT_CLEAN_MIN_AGE);
}

#define usage_error(...) lie_usage_error(inspect_prog, __VA_ARGS__)

enum {
    OPT_SCENE = 256, OPT_JSON, OPT_ALL, OPT_STRICT, OPT_CAMERA, OPT_EMITTER, OPT_SIZE,
    OPT_THREADS, OPT_MIN_AGE, OPT_DRY_RUN
};

static const struct option long_opts[] = {
    {"scene", required_argument, NULL, OPT_SCENE},
    {"json", no_argument, NULL, OPT_JSON},
    {"all", no_argument, NULL, OPT_ALL},
    {"strict", no_argument, NULL, OPT_STRICT},
    {"output", required_argument, NULL, 'o'},
    {"camera", required_argument, NULL, OPT_CAMERA},
    {"emitter", required_argument, NULL, OPT_EMITTER},
    {"size", required_argument, NULL, OPT_SIZE},
    {"threads", required_argument, NULL, OPT_THREADS},
    {"min-age", required_argument, NULL, OPT_MIN_AGE},
    {"dry-run", no_argument, NULL, OPT_DRY_RUN},
    {NULL, 0, NULL, 0},
};

/* Which commands take which options (bits of `command`). */
enum { C_VERIFY = 1, C_SUMMARY = 2, C_DUMP = 4, C_PATCH = 8, C_DIFF = 16, C_IMAGE = 32, C_CLEAN = 64 };
typedef struct command {
    const char *name;
    unsigned bit;
    int n_args; /* after the command name */
    const char *args;
} command;
static const command commands[] = {
    {"verify", C_VERIFY, 1, "CACHE"},       {"summary", C_SUMMARY, 1, "CACHE"},
    {"dump", C_DUMP, 1, "CACHE"},           {"patch", C_PATCH, 2, "CACHE and TRI[/PATH]"},
    {"diff", C_DIFF, 2, "two caches A and B"}, {"image", C_IMAGE, 1, "CACHE"},
    {"clean", C_CLEAN, 1, "DIR"},
};

typedef struct opt_use {
    int code;
    const char *name;
    unsigned commands;
} opt_use;
static const opt_use uses[] = {
    {OPT_SCENE, "--scene", C_VERIFY | C_IMAGE},
    {OPT_JSON, "--json", C_SUMMARY | C_DUMP | C_PATCH | C_DIFF},
    {OPT_ALL, "--all", C_DIFF},
    {OPT_STRICT, "--strict", C_DIFF},
    {'o', "-o", C_IMAGE},
    {OPT_CAMERA, "--camera", C_IMAGE},
    {OPT_EMITTER, "--emitter", C_IMAGE},
    {OPT_SIZE, "--size", C_IMAGE},
    {OPT_THREADS, "--threads", C_IMAGE},
    {LIE_OPT_EXTERNAL, "--allow-external-uris", C_VERIFY | C_IMAGE},
    {OPT_MIN_AGE, "--min-age", C_CLEAN},
    {OPT_DRY_RUN, "--dry-run", C_CLEAN},
    {'q', "-q", C_VERIFY | C_DIFF | C_IMAGE | C_CLEAN},
};
#define N_USES (sizeof uses / sizeof uses[0])

int main(int argc, char **argv)
{
    inspect_options o;
    memset(&o, 0, sizeof o);
    o.emitter = -1;
    o.width = LIE_RENDER_WIDTH_DEFAULT;
    o.height = LIE_RENDER_HEIGHT_DEFAULT;
    o.min_age = INSPECT_CLEAN_MIN_AGE;
    int given[N_USES] = {0};
    long v;
    int c;
    lie_cli cli = {.tool = inspect_prog, .usage = usage, .takes = LIE_CLI_EXTERNAL};
    while ((c = lie_cli_next(&cli, argc, argv, "o:", long_opts)) > 0) {
        for (size_t i = 0; i < N_USES; i++)
            if (uses[i].code == c)
                given[i] = 1;
        switch (c) {
        case OPT_SCENE: o.scene = optarg; break;
        case OPT_JSON: o.json = 1; break;
        case OPT_ALL: o.all = 1; break;
        case OPT_STRICT: o.strict = 1; break;
        case 'o': o.output = optarg; break;
        case OPT_CAMERA: o.camera = optarg; break;
        case OPT_EMITTER:
            if (!lie_parse_long(optarg, 0, 1 << 30, &v))
                return usage_error("--emitter: expected an emitter index, got '%s'", optarg);
            o.emitter = (int)v;
            break;
        case OPT_SIZE:
            if (!lie_parse_size(optarg, 65536, &o.width, &o.height))
                return usage_error("--size: expected WxH, got '%s'", optarg);
            break;
        case OPT_THREADS:
            if (!lie_cli_long(&cli, 0, 4096, &v))
                return cli.status;
            o.threads = (int)v;
            break;
        case OPT_MIN_AGE:
            if (!lie_parse_long(optarg, 0, 1L << 30, &v))
                return usage_error("--min-age: expected seconds, an integer >= 0, got '%s'", optarg);
            o.min_age = (int)v;
            break;
        case OPT_DRY_RUN: o.dry_run = 1; break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    o.external = cli.external;
    o.quiet = cli.quiet;
    if (optind >= argc)
        return usage_error("%s", "missing command (verify, summary, dump, patch, diff, image or clean)");
    const char *name = argv[optind];
    const command *cmd = NULL;
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (strcmp(name, commands[i].name) == 0)
            cmd = &commands[i];
    if (!cmd)
        return usage_error("unknown command '%s'", name);
    int n_args = argc - optind - 1;
    if (n_args < cmd->n_args) {
        fprintf(stderr, "%s: %s: missing %s (see --help)\n", inspect_prog, cmd->name, cmd->args);
        return 2;
    }
    if (n_args > cmd->n_args)
        return usage_error("unexpected argument '%s'", argv[optind + 1 + cmd->n_args]);
    for (size_t i = 0; i < N_USES; i++)
        if (given[i] && !(uses[i].commands & cmd->bit)) {
            fprintf(stderr, "%s: %s does not apply to %s (see --help)\n", inspect_prog, uses[i].name, cmd->name);
            return 2;
        }
    const char *a = argv[optind + 1], *b = cmd->n_args > 1 ? argv[optind + 2] : NULL;
    switch (cmd->bit) {
    case C_VERIFY: return inspect_verify(a, &o);
    case C_SUMMARY: return inspect_summary(a, &o);
    case C_DUMP: return inspect_dump(a, &o);
    case C_PATCH: return inspect_patch(a, b, &o);
    case C_CLEAN: return inspect_clean(a, &o);
    case C_DIFF:
        if (strcmp(a, "-") == 0 && strcmp(b, "-") == 0)
            return usage_error("%s", "diff: only one of A and B can be stdin");
        return inspect_diff(a, b, &o);
    default:
        if (!o.output)
            return usage_error("%s", "image: missing -o OUT.png");
        lie_frame_format fmt;
        if (strcmp(o.output, "-") != 0 && (!lie_frame_format_of(o.output, &fmt) || fmt != LIE_FORMAT_PNG))
            return usage_error("%s: image writes PNG only: use .png or - (stdout)", o.output);
        return inspect_image(a, &o);
    }
}
