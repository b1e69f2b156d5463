/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render: render frames with direct lighting.
 * Size: the option table, its checks against each other and the frame plan,
 * which share the run's options; the work is in lib/ and in output.c,
 * cached.c and dist.c.
 *   lie-render CACHE|SCENE.gltf|SCENE.glb|- -o OUT.exr|OUT.png|- [options]
 * From a cache (lie-build), shadow rays are answered by the local
 * illumination environments (--visibility=lie, the default); from a scene,
 * or with --visibility=full, by Embree over the whole scene: the reference. */
#include "common/cli.h"
#include "dist.h"
#include "lie.h"
#include "cached.h"
#include "output.h"
#include "shade/cost.h" /* --lie-skip: the benchmark ablations, not part of the API */

#include <errno.h>
#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char *prog = "lie-render";

static void usage(FILE *fp)
{
    lie_render_options d = lie_render_options_default();
    fprintf(fp,
            "Usage: %s CACHE|SCENE.gltf|SCENE.glb|- -o OUT.exr|OUT.png|- [options]\n"
            "\n"
            "Render direct lighting with soft shadows, from a LIE cache (lie-build) or a\n"
            "scene.  The output format follows the extension: .exr is OpenEXR (RGB, an A\n"
            "channel of coverage, the AOVs, and the camera as OpenEXR's worldToCamera and\n"
            "worldToNDC), .png an sRGB preview; other extensions are refused.  An input\n"
            "of - reads a cache from stdin.\n"
            "\n"
            "  -o, --output FILE       output image (required); - writes to stdout (EXR,\n"
            "                          or the --format given)\n"
            "      --format F          exr or png, whatever the extension\n"
            "      --half              EXR colour (R, G, B) as 16-bit half floats\n"
            "      --scene S           with a cache: load the scene from S instead of the path\n"
            "                          the cache records (its content hash must match)\n"
            "      --camera SPEC       a camera name or index in the scene, or\n"
            "                          eye=X,Y,Z,target=X,Y,Z[,up=X,Y,Z][,fov=DEG|ortho=HEIGHT]\n"
            "                          (default: the scene's first camera; ortho: an\n"
            "                          orthographic view HEIGHT world units tall)\n"
            "      --path PATH.yaml    a camera path (formats/camera-path.md): one frame per\n"
            "                          step, -o must hold a %%d conversion (frame_%%04d.exr)\n"
            "      --frames A-B        with --path: only frames A to B (numbered from the\n"
            "                          path's first-frame)\n"
            "      --skip-existing     leave out frames whose output file exists already\n"
            "      --cache C.lie       with a scene and --path: build the cache lie-build --path\n"
            "                          builds as the frames need it (before each frame, the\n"
            "                          units its view lacks) and keep it in C.lie after each\n"
            "                          frame: a stopped run goes on from it (with\n"
            "                          --skip-existing, from the first frame not written).\n"
            "                          The frames equal lie-build --path + lie-render of C.lie\n"
            "      --view-size WxH     with --cache: as lie-build --view-size (default 512x512)\n"
            "      --size WxH          image size (default %dx%d)\n"
            "      --spp N             eye rays per pixel, stratified (default %d: pixel centre)\n"
            "      --light-samples N   light samples per shading point, shared among the\n"
            "                          emitters by the light sampler (default %d; 0 = eye\n"
            "                          rays only; per-emitter: N of every area emitter), or\n"
            "                          'exact': surfaces under planar lights of one colour in\n"
            "                          closed form (LTC for glossy ones) with exact shadows,\n"
            "                          the default count elsewhere\n"
            "      --light-sampler S   how the samples are shared: tree (default: a light\n"
            "                          BVH by power, distance and orientation; from a cache\n"
            "                          the LIE's classes guide it: no sample to occluded or\n"
            "                          unlit emitters, closed forms where seen whole, the rest\n"
            "                          to partial pairs by their unshadowed light) | power |\n"
            "                          uniform | per-emitter (N samples of every emitter from\n"
            "                          a fixed pattern: the paper's meaning, and that\n"
            "                          of earlier builds)\n"
            "      --seed S            seed of the per-pixel sample patterns (default 0);\n"
            "                          renders with two seeds are independent\n"
            "      --exact MODE        auto (default: closed forms, and from a cache exact\n"
            "                          shadows where they cost less than the samples)\n"
            "                          | off (shadows from the samples: the oracle's mode)\n"
            "      --bitmask MODE      per-emitter sampler, partial pairs toward planar emitters\n"
            "                          with all samples at once: auto (default: where cheaper,\n"
            "                          not under --exact off) | off | only (the same image,\n"
            "                          samples in another order)\n"

            "      --timers            --stats also reports per-path times (benchmarks)\n"
            "      --pattern P         per-emitter sampler: fixed (default: the same emitter\n"
            "                          samples everywhere) | rotated (a per-pixel rotation);\n"
            "                          the other samplers always rotate per pixel\n"
            "      --visibility MODE   lie (default with a cache: blocker lists only)\n"
            "                          | full (default with a scene: Embree over the whole scene)\n"
            "                          | none (no shadows: measures shading alone)\n"
            "      --rays MODE         how full visibility casts shadow rays: stream (default),\n"
            "                          packet (8-wide) or single\n"
            "      --lie-skip WHAT     benchmarks only, wrong images: answer partial pairs\n"
            "                          (blockers), complex pairs (fallback) or both as\n"
            "                          unshadowed, to see where a LIE frame's time goes\n"
            "      --max-depth D       mirror reflection depth (default %d)\n"
            "      --aov LIST          extra EXR layers, comma-separated: albedo, normal, depth,\n"
            "                          complexity (the paper's Figure 10 colours), patch\n"
            "                          (a colour per leaf patch); the last two need a cache\n"
            "      --emitter K         complexity and patch layers for emitter K only\n"
            "      --compression C     EXR compression, all lossless: zip (default), zips, piz,\n"
            "                          rle (several times faster to write than zip, files a\n"
            "                          little larger) or none\n"
            "      --exposure EV|auto  PNG exposure in stops (default 0); auto: the stops that\n"
            "                          take the frame's log-average luminance to 0.18\n"
            "                          (Reinhard et al. 2002), per frame, written in the\n"
            "                          file (PNG tEXt and EXR lie.exposure) and in --stats\n"
            "      --default-light L   a scene without emitters: headlight (a point light at\n"
            "                          the camera, 1 lux at the scene's centre) or sun (1 lux\n"
            "                          from above); a scene input only\n"
            "      --threads N         worker threads (default: all cores)\n"
            "      --allow-external-uris  let the glTF reference files outside its folder\n"
            "      --stats[=json]      print statistics to stderr\n"
            "      --stats-file FILE   the --stats=json record to FILE, not stderr\n"
            "  -q, --quiet             no progress bar\n"
            "  -v, --verbose           each phase's time on stderr (load, bvh, then render\n"
            "                          and write per frame)\n"
            "  -h, --help              this help\n"
            "      --version           print the version\n"
            "\n"
            "Under mpirun the ranks share the frames out (whole frames of a path, each\n"
            "written by its rank; bands of rows, their EXR chunks compressed by the rank\n"
            "that rendered them) and write the bytes one process writes (docs/mpi.md).\n",
            prog, d.width, d.height, d.spp, d.light_samples, d.max_depth);
}


#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_dist_fail(prog, err, 1); }

enum {
    OPT_CAMERA = 256, OPT_SIZE, OPT_SPP, OPT_LIGHT_SAMPLES, OPT_PATTERN, OPT_VISIBILITY, OPT_RAYS, OPT_LIE_SKIP,
    OPT_MAX_DEPTH, OPT_AOV, OPT_COMPRESSION, OPT_EXPOSURE, OPT_SCENE, OPT_DEFAULT_LIGHT,
    OPT_EMITTER, OPT_PATH, OPT_EXACT, OPT_TIMERS, OPT_FRAMES, OPT_SKIP_EXISTING, OPT_FORMAT, OPT_HALF, OPT_BITMASK,
    OPT_LIGHT_SAMPLER, OPT_SEED, OPT_CACHE, OPT_VIEW_SIZE
};

static const struct option long_opts[] = {
    {"scene", required_argument, NULL, OPT_SCENE},
    {"path", required_argument, NULL, OPT_PATH},
    {"cache", required_argument, NULL, OPT_CACHE},
    {"view-size", required_argument, NULL, OPT_VIEW_SIZE},
    {"frames", required_argument, NULL, OPT_FRAMES},
    {"skip-existing", no_argument, NULL, OPT_SKIP_EXISTING},
    {"emitter", required_argument, NULL, OPT_EMITTER},
    {"camera", required_argument, NULL, OPT_CAMERA},
    {"size", required_argument, NULL, OPT_SIZE},
    {"spp", required_argument, NULL, OPT_SPP},
    {"light-samples", required_argument, NULL, OPT_LIGHT_SAMPLES},
    {"pattern", required_argument, NULL, OPT_PATTERN},
    {"exact", required_argument, NULL, OPT_EXACT},
    {"timers", no_argument, NULL, OPT_TIMERS},
    {"bitmask", required_argument, NULL, OPT_BITMASK},
    {"light-sampler", required_argument, NULL, OPT_LIGHT_SAMPLER},
    {"seed", required_argument, NULL, OPT_SEED},
    {"visibility", required_argument, NULL, OPT_VISIBILITY},
    {"rays", required_argument, NULL, OPT_RAYS},
    {"lie-skip", required_argument, NULL, OPT_LIE_SKIP},
    {"max-depth", required_argument, NULL, OPT_MAX_DEPTH},
    {"aov", required_argument, NULL, OPT_AOV},
    {"compression", required_argument, NULL, OPT_COMPRESSION},
    {"format", required_argument, NULL, OPT_FORMAT},
    {"half", no_argument, NULL, OPT_HALF},
    {"exposure", required_argument, NULL, OPT_EXPOSURE},
    {"default-light", required_argument, NULL, OPT_DEFAULT_LIGHT},
    {NULL, 0, NULL, 0},
};

/* The values of the options that name a mode (each message lists them in
 * this order). */
static const lie_cli_choice exact_modes[] = {{"auto", LIE_EXACT_AUTO}, {"off", LIE_EXACT_OFF}, {NULL, 0}};
static const lie_cli_choice bitmask_modes[] = {
    {"auto", LIE_BITMASK_AUTO}, {"off", LIE_BITMASK_OFF}, {"only", LIE_BITMASK_ONLY}, {NULL, 0}};
static const lie_cli_choice samplers[] = {{"tree", LIE_SAMPLER_TREE},
                                          {"power", LIE_SAMPLER_POWER},
                                          {"uniform", LIE_SAMPLER_UNIFORM},
                                          {"per-emitter", LIE_SAMPLER_PER_EMITTER},
                                          {NULL, 0}};
static const lie_cli_choice patterns[] = {{"fixed", LIE_PATTERN_FIXED}, {"rotated", LIE_PATTERN_ROTATED}, {NULL, 0}};
static const lie_cli_choice lie_skips[] = {{"blockers", LIE_ABLATE_BLOCKERS},
                                           {"fallback", LIE_ABLATE_FALLBACK},
                                           {"both", LIE_ABLATE_BLOCKERS | LIE_ABLATE_FALLBACK},
                                           {NULL, 0}};
static const lie_cli_choice visibilities[] = {
    {"full", LIE_VIS_FULL}, {"lie", LIE_VIS_LIE}, {"none", LIE_VIS_NONE}, {NULL, 0}};
static const lie_cli_choice ray_modes[] = {
    {"stream", LIE_RAYS_STREAM}, {"packet", LIE_RAYS_PACKET}, {"single", LIE_RAYS_SINGLE}, {NULL, 0}};

/* An option that names a mode of lie_render_options: 1 when it set it, 0
 * when c is not one, -1 after its usage error (cli->status). */
static int pick_mode(lie_cli *cli, int c, lie_render_options *ro)
{
    static const struct {
        int code;
        const lie_cli_choice *choices;
        size_t offset; /* of an enum or unsigned field: int-sized (below) */
    } modes[] = {
        {OPT_EXACT, exact_modes, offsetof(lie_render_options, exact)},
        {OPT_BITMASK, bitmask_modes, offsetof(lie_render_options, bitmask)},
        {OPT_LIGHT_SAMPLER, samplers, offsetof(lie_render_options, sampler)},
        {OPT_PATTERN, patterns, offsetof(lie_render_options, pattern)},
        {OPT_LIE_SKIP, lie_skips, offsetof(lie_render_options, ablate)},
        {OPT_VISIBILITY, visibilities, offsetof(lie_render_options, visibility)},
        {OPT_RAYS, ray_modes, offsetof(lie_render_options, rays)},
    };
    _Static_assert(sizeof(lie_exact_mode) == sizeof(int) && sizeof(lie_bitmask_mode) == sizeof(int) &&
                       sizeof(lie_light_sampler_kind) == sizeof(int) &&
                       sizeof(lie_pattern) == sizeof(int) && sizeof(lie_visibility_mode) == sizeof(int) &&
                       sizeof(lie_ray_mode) == sizeof(int) && sizeof(unsigned) == sizeof(int),
                   "the modes are stored as ints");
    for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++)
        if (modes[i].code == c)
            return lie_cli_pick(cli, modes[i].choices, (int *)((char *)ro + modes[i].offset)) ? 1 : -1;
    return 0;
}

static int parse_aovs(const char *list, unsigned *bits)
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (strcmp(tok, "albedo") == 0)
            *bits |= LIE_AOV_ALBEDO;
        else if (strcmp(tok, "normal") == 0)
            *bits |= LIE_AOV_NORMAL;
        else if (strcmp(tok, "depth") == 0)
            *bits |= LIE_AOV_DEPTH;
        else if (strcmp(tok, "complexity") == 0)
            *bits |= LIE_AOV_COMPLEXITY;
        else if (strcmp(tok, "patch") == 0)
            *bits |= LIE_AOV_PATCH;
        else
            return 0;
    }
    return 1;
}

/* Does the buffer hold glTF (JSON or GLB) rather than a cache? */
static int looks_like_gltf(const unsigned char *d, size_t n)
{
    size_t i = 0;
    if (n >= 4 && memcmp(d, "glTF", 4) == 0)
        return 1;
    if (n >= 3 && d[0] == 0xEF && d[1] == 0xBB && d[2] == 0xBF)
        i = 3; /* UTF-8 byte order mark */
    while (i < n && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n'))
        i++;
    return i < n && d[i] == '{';
}

/* Load a scene, or a cache and the scene it was built for, and the camera
 * path: through so->files, which under mpirun records what rank 0 reads
 * for the other ranks (lie_dist_load).  On failure the caller frees what
 * was made. */
typedef struct inputs {
    const char *input, *override, *path_file;
    lie_scene *scene;
    lie_cache *cache;
    lie_camera_path *cpath;
} inputs;

static lie_status load_input(void *ctx, const lie_scene_options *so, lie_error *err)
{
    inputs *in = ctx;
    unsigned char *data = NULL;
    size_t size = 0;
    lie_status st = lie_file_set_read(so->files, in->input, LIE_READ_MAX_DEFAULT, &data, &size, err);
    if (st != LIE_OK)
        return st;
    if (looks_like_gltf(data, size)) {
        /* the scene's file: a set holds it already; stdin is read once, so
         * its bytes go to the loader in a set of their own */
        lie_scene_options o = *so;
        lie_file_set *own = NULL;
        if ((!so->files || lie_file_set_get_mode(so->files) == LIE_FILES_NAMES) && strcmp(in->input, "-") == 0) {
            o.files = own = lie_file_set_create(LIE_FILES_RECORD);
            st = own ? lie_file_set_add(own, in->input, data, size, err)
                     : lie_error_set(err, LIE_ERR_NOMEM, in->input, "out of memory");
        }
        free(data);
        if (st == LIE_OK)
            st = lie_scene_load(in->input, &o, &in->scene, err);
        lie_file_set_destroy(own);
    } else {
        st = lie_cache_decode(data, size, in->input, &in->cache, err);
        free(data);
        if (st == LIE_OK)
            st = lie_cache_load_scene(in->cache, in->input, in->override, so, &in->scene, err);
    }
    if (st == LIE_OK && in->path_file) {
        st = lie_file_set_read(so->files, in->path_file, LIE_READ_MAX_TEXT, &data, &size, err);
        if (st == LIE_OK)
            st = lie_camera_path_parse(data, size, in->path_file, &in->cpath, err);
        free(data);
    }
    return st;
}

/* The command line. */
typedef struct args {
    lie_render_options ro;
    lie_scene_options so;
    lie_frame_options fopt;
    const char *input, *output, *camera, *scene_override, *path_file, *cache_file;
    int default_light;     /* --default-light: lie_default_light, 0 none */
    int view_w, view_h;    /* --view-size */
    long frame_a, frame_b; /* --frames, or -1 */
    int skip_existing, visibility_set, pattern_set;
    int exposure_auto;     /* --exposure auto */
} args;

/* A render option of the command line, not a mode (pick_mode): 1 when it
 * took it, 0 when c is not one, -1 after its usage error (cli->status). */
static int render_option(lie_cli *cli, int c, lie_render_options *ro)
{
    static const lie_cli_int ints[] = {
        {OPT_SPP, 1, 65536, offsetof(lie_render_options, spp)},
        {OPT_MAX_DEPTH, 0, 64, offsetof(lie_render_options, max_depth)},
    };
    _Static_assert(sizeof ro->spp == 4 && sizeof ro->max_depth == 4, "32-bit fields");
    long v;
    int taken = lie_cli_set_int(cli, c, ints, sizeof ints / sizeof ints[0], ro);
    if (taken)
        return taken;
    switch (c) {
    case OPT_SIZE:
        if (lie_parse_size(optarg, 65536, &ro->width, &ro->height))
            return 1;
        cli->status = usage_error("--size: expected WxH, got '%s'", optarg);
        return -1;
    case OPT_LIGHT_SAMPLES:
        if (strcmp(optarg, "exact") == 0) {
            ro->exact = LIE_EXACT_ONLY;
            ro->light_samples = LIE_LIGHT_SAMPLES_DEFAULT;
            return 1;
        }
        if (!lie_parse_long(optarg, 0, 1000000, &v)) {
            cli->status = usage_error("--light-samples: expected an integer in 0..1000000 or exact, got '%s'", optarg);
            return -1;
        }
        ro->light_samples = (int)v;
        if (ro->exact == LIE_EXACT_ONLY)
            ro->exact = LIE_EXACT_AUTO;
        return 1;
    case OPT_TIMERS: ro->timers = 1; return 1;
    case OPT_SEED: {
        unsigned long long seed;
        char *end;
        errno = 0;
        seed = strtoull(optarg, &end, 10);
        if (errno || end == optarg || *end || optarg[0] == '-') {
            cli->status = usage_error("--seed: expected a non-negative integer, got '%s'", optarg);
            return -1;
        }
        ro->seed = (uint64_t)seed;
        return 1;
    }
    case OPT_AOV:
        if (parse_aovs(optarg, &ro->aovs))
            return 1;
        cli->status = usage_error("--aov: expected a list of albedo, normal, depth, complexity, patch, got '%s'", optarg);
        return -1;
    case OPT_EMITTER:
        if (!lie_parse_long(optarg, 0, 1 << 30, &v)) {
            cli->status = usage_error("--emitter: expected an emitter index, got '%s'", optarg);
            return -1;
        }
        ro->aov_emitter = (int)v;
        return 1;
    default: return 0;
    }
}

/* The options: -1 to go on, or the exit status. */
static int parse_options(args *a, lie_cli *cli, int argc, char **argv)
{
    int c, taken;
    while ((c = lie_cli_next(cli, argc, argv, "", long_opts)) > 0) {
        if ((taken = pick_mode(cli, c, &a->ro)) != 0 || (taken = render_option(cli, c, &a->ro)) != 0) {
            if (taken < 0)
                return cli->status;
            a->visibility_set |= c == OPT_VISIBILITY;
            a->pattern_set |= c == OPT_PATTERN;
            continue;
        }
        switch (c) {
        case OPT_CAMERA: a->camera = optarg; break;
        case OPT_FORMAT:
            if (!lie_frame_format_parse(optarg, &a->fopt.format))
                return usage_error("--format: expected exr or png, got '%s'", optarg);
            break;
        case OPT_HALF: a->fopt.exr.half = 1; break;
        case OPT_COMPRESSION:
            if (!lie_exr_compression_parse(optarg, &a->fopt.exr.compression))
                return usage_error("--compression: expected zip, zips, piz, rle or none, got '%s'", optarg);
            break;
        case OPT_EXPOSURE:
            a->exposure_auto = strcmp(optarg, "auto") == 0;
            if (!a->exposure_auto && !lie_parse_float(optarg, -64.0f, 64.0f, &a->fopt.png.exposure))
                return usage_error("--exposure: expected a number of stops or auto, got '%s'", optarg);
            break;
        case OPT_SCENE: a->scene_override = optarg; break;
        case OPT_DEFAULT_LIGHT: {
            static const lie_cli_choice lights[] = {
                {"headlight", LIE_DEFAULT_LIGHT_HEADLIGHT}, {"sun", LIE_DEFAULT_LIGHT_SUN}, {NULL, 0}};
            if (!lie_cli_pick(cli, lights, &a->default_light))
                return cli->status;
            break;
        }
        case OPT_PATH: a->path_file = optarg; break;
        case OPT_FRAMES:
            if (!lie_parse_range(optarg, 0, 999999, &a->frame_a, &a->frame_b))
                return usage_error("--frames: expected A-B with 0 <= A <= B <= 999999, got '%s'", optarg);
            break;
        case OPT_SKIP_EXISTING: a->skip_existing = 1; break;
        case OPT_CACHE: a->cache_file = optarg; break;
        case OPT_VIEW_SIZE:
            if (!lie_parse_size(optarg, 16384, &a->view_w, &a->view_h))
                return usage_error("--view-size: expected WxH, got '%s'", optarg);
            break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli->status;
    a->so.allow_external_uris = cli->external;
    a->so.threads = cli->threads;
    a->ro.threads = cli->threads;
    a->fopt.exr.threads = a->ro.threads;
    a->output = cli->output;
    a->input = cli->operand;
    return -1;
}

/* The output and the options that go together: -1 to go on, or the exit
 * status. */
static int check_args(args *a)
{
    if (!a->output)
        return usage_error("%s", "missing -o OUTPUT");
    lie_frame_format out_format;
    if (a->fopt.format == LIE_FORMAT_AUTO && !lie_frame_format_of(a->output, &out_format))
        return usage_error("%s: cannot write this format: use .exr or .png (or --format exr|png)", a->output);
    if (a->path_file && !lie_frame_pattern_ok(a->output))
        return usage_error("--path: -o must hold one %%d conversion (e.g. frame_%%04d.exr), got '%s'", a->output);
    if (a->path_file && a->camera)
        return usage_error("%s", "--path and --camera exclude each other");
    if (a->frame_a >= 0 && !a->path_file)
        return usage_error("%s", "--frames needs --path");
    /* the fixed pattern and its bitmasks are the per-emitter sampler's
     * (the others rotate theirs per pixel) */
    int fixed = a->pattern_set && a->ro.pattern == LIE_PATTERN_FIXED;
    if (a->ro.sampler != LIE_SAMPLER_PER_EMITTER && (fixed || a->ro.bitmask == LIE_BITMASK_ONLY))
        return usage_error("%s needs --light-sampler per-emitter", fixed ? "--pattern fixed" : "--bitmask only");
    if (a->cache_file && !a->path_file)
        return usage_error("%s", "--cache needs --path");
    if (a->view_w && !a->cache_file)
        return usage_error("%s", "--view-size needs --cache");
    if (a->ro.light_samples == 0) {
        a->ro.eye_only = 1;
        a->ro.light_samples = 1;
    }
    return -1;
}

/* What a run loads and makes. */
typedef struct run {
    lie_scene *scene;
    lie_cache *cache;
    lie_camera_path *cpath;
    lie_env_shadows *lv;
    lie_rt *rt;
    lie_camera cam; /* without --path */
    lie_file_set *files; /* the run's inputs: no frame may replace one */
    lie_error err;
} run;

static void run_free(run *r)
{
    lie_file_set_destroy(r->files);
    lie_camera_path_destroy(r->cpath);
    lie_rt_destroy(r->rt);
    lie_env_shadows_destroy(r->lv);
    lie_cache_destroy(r->cache);
    lie_scene_destroy(r->scene);
}

/* After the load: the oracle, the warnings, --emitter and the camera
 * checked against the scene. */
static lie_status prepare(args *a, run *r, int quiet)
{
    lie_render_options *ro = &a->ro;
    lie_status st = LIE_OK;
    if (r->cache && (st = lie_env_shadows_create(r->scene, r->cache->env, &r->lv, &r->err)) != LIE_OK)
        return st;
    ro->oracle = r->lv ? lie_env_shadows_oracle(r->lv) : NULL;
    if (!quiet)
        lie_print_scene_warnings(prog, r->scene, a->input);
    st = a->path_file ? LIE_OK : lie_camera_parse(r->scene, a->camera, &r->cam, &r->err);
    if (st == LIE_OK && a->default_light && r->scene->n_emitters == 0) {
        /* the headlight stays where the camera (a path's first frame) is */
        lie_camera at = r->cpath ? lie_camera_path_frame(r->cpath, 0) : r->cam;
        st = lie_scene_add_default_light(r->scene, (lie_default_light)a->default_light, &at, &r->err);
    } else if (st == LIE_OK && r->scene->n_emitters == 0 && !quiet) {
        fprintf(stderr, "%s: %s: warning: no emitters (no emissive material, no KHR_lights_punctual light): "
                        "the image shows emission only; --default-light headlight or sun lights the geometry\n",
                prog, a->input);
    }
    if (st != LIE_OK)
        goto done;
    if (ro->aov_emitter >= r->scene->n_emitters)
        return lie_error_set(&r->err, LIE_ERR_ARG, a->input, "--emitter %d: the scene has %d emitters",
                             ro->aov_emitter, r->scene->n_emitters);
done:
    if (st != LIE_OK && !r->err.file[0])
        snprintf(r->err.file, sizeof r->err.file, "%s", a->input);
    return st;
}

/* The frames to render (indices into the path, or 0 alone): --frames, and
 * --skip-existing's files as rank 0 sees them.  *todo is the caller's. */
static lie_status plan_frames(const args *a, const run *r, int **todo, int *n_todo, int *skipped, lie_error *err)
{
    int n_frames = r->cpath ? r->cpath->n_frames : 1, first = r->cpath ? r->cpath->first : 0;
    if (r->cpath && a->frame_a >= 0 && (a->frame_a < first || a->frame_b > (long)first + n_frames - 1))
        return lie_error_set(err, LIE_ERR_ARG, a->path_file, "--frames %ld-%ld: the path has frames %d-%d",
                             a->frame_a, a->frame_b, first, first + n_frames - 1);
    *n_todo = *skipped = 0;
    *todo = malloc(sizeof **todo * ((size_t)n_frames + 1));
    if (!*todo)
        return lie_error_set(err, LIE_ERR_NOMEM, a->input, "out of memory");
    for (int fi = 0; fi < n_frames; fi++) {
        int number = first + fi;
        if (a->frame_a >= 0 && (number < a->frame_a || number > a->frame_b))
            continue;
        char name[4096];
        if (r->cpath)
            snprintf(name, sizeof name, a->output, number);
        else
            snprintf(name, sizeof name, "%s", a->output);
        struct stat sb;
        if (a->skip_existing && strcmp(name, "-") != 0 && stat(name, &sb) == 0) {
            (*skipped)++; /* a resumed run: the frame was written (atomically) before */
            continue;
        }
        (*todo)[(*n_todo)++] = fi;
    }
    return LIE_OK;
}

/* One process's frames, rendered and written in order; -v's phases. */
static lie_status render_here(args *a, run *r, frame_out *fo, const int *todo, int n_todo, int verbose,
                              lie_render_stats *rs, double *t_render, double *t_write, int *rendered)
{
    lie_render_options *ro = &a->ro;
    lie_status st = LIE_OK;
    for (int k = 0; k < n_todo && st == LIE_OK; k++) {
        int fi = todo[k];
        lie_camera fc = r->cpath ? lie_camera_path_frame(r->cpath, fi) : r->cam;
        (*rendered)++;
        double ta = lie_time_now();
        lie_frame *frame = NULL;
        lie_render_stats fs;
        char label[64];
        if (r->cpath) {
            snprintf(label, sizeof label, "frame %d/%d", k + 1, n_todo);
            ro->progress_label = label;
        }
        st = lie_render(r->scene, r->rt, &fc, ro, &frame, &fs, &r->err);
        ro->progress_label = NULL;
        if (st != LIE_OK)
            break;
        double tb = lie_time_now();
        lie_render_stats_add(rs, &fs);
        if (r->cpath)
            snprintf(label, sizeof label, "frame %d: render", fo->first + fi);
        lie_phase(prog, verbose, r->cpath ? label : "render", ta);
        st = write_frame(fo, fi, &fc, frame, NULL, &r->err);
        lie_frame_destroy(frame);
        if (r->cpath)
            snprintf(label, sizeof label, "frame %d: write", fo->first + fi);
        lie_phase(prog, verbose && st == LIE_OK, r->cpath ? label : "write", tb);
        *t_render += tb - ta;
        *t_write += lie_time_now() - tb;
    }
    return st;
}

/* Load, bvh, then every frame, shared out under mpirun: LIE_OK, or an
 * error in r->err; 2 after a usage error found once the input is known. */
static int render_all(args *a, run *r, const lie_cli *cli)
{
    lie_render_options *ro = &a->ro;
    double t0 = lie_time_now();
    inputs in = {a->input, a->scene_override, a->path_file, NULL, NULL, NULL};
    lie_file_set *files = r->files = lie_file_set_create(LIE_FILES_NAMES);
    if (!files)
        return lie_error_set(&r->err, LIE_ERR_NOMEM, a->input, "out of memory");
    a->so.files = files;
    lie_status st = lie_dist_load(&a->so, load_input, &in, &r->err);
    a->so.files = NULL;
    r->scene = in.scene;
    r->cache = in.cache;
    r->cpath = in.cpath;
    if (st != LIE_OK)
        return st;
    double t1 = lie_phase(prog, cli->verbose, "load", t0);
    if (a->cache_file && (r->cache || a->visibility_set))
        return usage_error("%s: --cache takes a scene, and renders with the cache it builds (no --visibility)",
                           a->input);
    if (a->default_light && (r->cache || a->cache_file))
        return usage_error("%s: --default-light renders a scene: a cache holds no environments of its light",
                           a->input);
    if (a->cache_file && lie_dist_size() > 1)
        return usage_error("%s", "--cache: not under mpirun (the frames build as they go, one after another)");
    if (!a->visibility_set)
        ro->visibility = r->cache || a->cache_file ? LIE_VIS_LIE : LIE_VIS_FULL;
    if (!r->cache && !a->cache_file &&
        (ro->visibility == LIE_VIS_LIE || (ro->aovs & (LIE_AOV_COMPLEXITY | LIE_AOV_PATCH))))
        return usage_error("%s: --visibility=lie and the complexity and patch layers need a cache", a->input);
    if (a->cache_file)
        ro->visibility = LIE_VIS_FULL; /* until cached_render has its oracle */
    if ((st = prepare(a, r, cli->quiet)) != LIE_OK || (st = lie_rt_create(r->scene, &r->rt, &r->err)) != LIE_OK ||
        (st = lie_dist_check(r->scene->hash, r->cache ? r->cache->state_hash : 0, &r->err)) != LIE_OK)
        return st;
    double t2 = lie_phase(prog, cli->verbose, "bvh", t1);
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)r->scene->hash);
    int *todo = NULL, n_todo = 0, rendered = 0, skipped = 0;
    st = plan_frames(a, r, &todo, &n_todo, &skipped, &r->err);
    /* with --cache, the frames say what lie-render of the cache says */
    lie_auto_exposure last_auto = {0.0f, LIE_EXPOSURE_KEY, 0.0, 0};
    frame_out fo = {a->output, a->cache_file ? a->cache_file : a->input, hash, ro, r->cpath != NULL, a->fopt,
                    r->cpath ? r->cpath->first : 0, a->exposure_auto, &last_auto};
    /* no output may be an input (the cache, the scene's files, the path),
     * nor a frame --cache: every name is checked before the first is
     * written (an interrupted run's --cache is read by cached_render, not
     * through the set: it may be replaced) */
    if (st == LIE_OK && a->cache_file)
        st = lie_file_set_claim(files, a->cache_file, NULL, &r->err);
    for (int i = 0; st == LIE_OK && lie_dist_rank() == 0 && i < n_todo; i++) {
        char name[4096];
        frame_name(&fo, todo[i], name, sizeof name);
        st = lie_file_set_check(files, name, &r->err);
    }
    if (st != LIE_OK) {
        free(todo);
        return st;
    }
    lie_render_stats rs;
    memset(&rs, 0, sizeof rs);
    double t_render = 0.0, t_write = 0.0;
    /* the lights prepared once for every frame and tile (its time is the
     * render's) */
    double tl = lie_time_now();
    lie_lights *lights = NULL;
    if (!ro->eye_only && (st = lie_lights_create(r->scene, ro, &lights, &r->err)) != LIE_OK) {
        free(todo);
        return st;
    }
    ro->lights = lights;
    t_render += lie_time_now() - tl;
    if (a->cache_file) {
        cached_run cr = {a->cache_file, a->input, a->view_w ? a->view_w : 512, a->view_h ? a->view_h : 512, r->scene,
                         r->rt, r->cpath, ro, cli->quiet, cli->verbose, a->frame_a < 0, 0, 0};
        st = cached_render(&cr, &fo, todo, n_todo, &rs, &t_render, &t_write, &rendered, &r->err);
        if (cli->verbose)
            fprintf(stderr, "%s: --cache: %llu triangles built, %d frames rendered again\n", prog,
                    (unsigned long long)cr.units_built, cr.rerenders);
    } else if (lie_dist_size() > 1) {
        lie_dist_bcast(&n_todo, sizeof n_todo);
        lie_dist_bcast(todo, sizeof *todo * (size_t)n_todo);
        double ta = lie_time_now();
        render_out out = {write_frame_chunks, encode_chunks, frame_chunk_lines(&fo), &fo, frame_encode_share(&fo)};
        st = render_dist(r->scene, r->rt, ro, r->cpath, &r->cam, todo, n_todo, &out, &rs, &t_write, &r->err);
        t_render += lie_time_now() - ta - t_write;
        rendered = n_todo;
    } else {
        st = render_here(a, r, &fo, todo, n_todo, cli->verbose, &rs, &t_render, &t_write, &rendered);
    }
    ro->lights = NULL;
    lie_lights_destroy(lights);
    free(todo);
    if (st == LIE_OK && cli->stats) {
        run_stats rst = {a->input, rendered, skipped, t1 - t0, t2 - t1, t_render, t_write,
                         a->exposure_auto && rendered > 0 ? &last_auto : NULL};
        st = print_stats(cli, &rst, r->scene, ro, &rs, &r->err);
    }
    return st;
}

int main(int argc, char **argv)
{
    args a = {.ro = lie_render_options_default(), .so = lie_scene_options_default(), .frame_a = -1, .frame_b = -1};
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing input scene",
                   .takes = LIE_CLI_OUTPUT | LIE_CLI_THREADS | LIE_CLI_EXTERNAL | LIE_CLI_STATS | LIE_CLI_VERBOSE};
    int rc = parse_options(&a, &cli, argc, argv);
    if (rc < 0)
        rc = check_args(&a);
    if (rc >= 0)
        return rc;
    if (lie_dist_start(&argc, &argv) > 1) {
        cli.quiet = 1; /* progress and warnings: one process's are enough; rank 0 prints the statistics */
        if (lie_dist_rank() != 0)
            cli.stats = 0;
    }
    a.ro.progress = !cli.quiet;
    run r;
    memset(&r, 0, sizeof r);
    lie_error_clear(&r.err);
    rc = render_all(&a, &r, &cli);
    run_free(&r);
    if (rc == 2)
        return 2;
    return rc != LIE_OK ? fail(&r.err) : 0;
}
