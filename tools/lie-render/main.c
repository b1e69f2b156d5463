/* lie-render: render frames with direct lighting.
 *   lie-render CACHE|SCENE.gltf|SCENE.glb|- -o OUT.exr|OUT.png|- [options]
 * From a cache (lie-build), shadow rays are answered by the local
 * illumination environments (--visibility=lie, the default); from a scene,
 * or with --visibility=full, by Embree over the whole scene: the reference. */
#include "common/cli.h"
#include "dist.h"
#include "lie.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char *prog = "lie-render";

static void usage(FILE *fp)
{
    lie_render_options d = lie_render_options_default();
    fprintf(fp,
            "usage: %s CACHE|SCENE.gltf|SCENE.glb|- -o OUT.exr|OUT.png|- [options]\n"
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
            "      --size WxH          image size (default %dx%d)\n"
            "      --spp N             eye rays per pixel, stratified (default %d: pixel centre)\n"
            "      --light-samples N   shadow rays per area emitter per shading point\n"
            "                          (default %d; 0 = eye rays only), or 'exact': surfaces\n"
            "                          under planar lights of one colour in closed form (LTC\n"
            "                          for glossy ones) with exact shadows, the default count\n"
            "                          elsewhere\n"
            "      --exact MODE        auto (default: closed forms, and from a cache exact\n"
            "                          shadows where they cost less than the samples)\n"
            "                          | off (shadows from the samples: the oracle's mode)\n"
            "      --bitmask MODE      partial pairs toward planar emitters with all samples at\n"
            "                          once: auto (default: where cheaper, not under --exact\n"
            "                          off) | off | only (the same image, samples in another order)\n"
            "      --timers            --stats also reports per-path times (benchmarks)\n"
            "      --pattern P         fixed (default: the same emitter samples everywhere)\n"
            "                          | rotated (a per-pixel rotation of the pattern)\n"
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
            "      --exposure EV       PNG exposure in stops (default 0)\n"
            "      --threads N         worker threads (default: all cores)\n"
            "      --allow-external-uris  let the glTF reference files outside its folder\n"
            "      --stats[=json]      print statistics to stderr\n"
            "  -q, --quiet             no progress bar\n"
            "  -v, --verbose           each phase's time on stderr (load, bvh, then render\n"
            "                          and write per frame)\n"
            "  -h, --help              this help\n"
            "      --version           print the version\n"
            "\n"
            "Under mpirun the ranks share the frames out (tiles, or whole frames of a path)\n"
            "and rank 0 writes the bytes one process writes (docs/mpi.md).\n",
            prog, d.width, d.height, d.spp, d.light_samples, d.max_depth);
}

static const char *exact_name(const lie_render_options *o)
{
    return o->exact == LIE_EXACT_ONLY ? "only" : o->exact == LIE_EXACT_OFF ? "off" : "auto";
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

static int fail(const lie_error *err) { return lie_dist_fail(prog, err, 1); }

enum {
    OPT_CAMERA = 256, OPT_SIZE, OPT_SPP, OPT_LIGHT_SAMPLES, OPT_PATTERN, OPT_VISIBILITY, OPT_RAYS, OPT_LIE_SKIP,
    OPT_MAX_DEPTH, OPT_AOV, OPT_COMPRESSION, OPT_EXPOSURE, OPT_SCENE,
    OPT_EMITTER, OPT_PATH, OPT_EXACT, OPT_TIMERS, OPT_FRAMES, OPT_SKIP_EXISTING, OPT_FORMAT, OPT_HALF, OPT_BITMASK
};

static const struct option long_opts[] = {
    {"scene", required_argument, NULL, OPT_SCENE},
    {"path", required_argument, NULL, OPT_PATH},
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
    {"visibility", required_argument, NULL, OPT_VISIBILITY},
    {"rays", required_argument, NULL, OPT_RAYS},
    {"lie-skip", required_argument, NULL, OPT_LIE_SKIP},
    {"max-depth", required_argument, NULL, OPT_MAX_DEPTH},
    {"aov", required_argument, NULL, OPT_AOV},
    {"compression", required_argument, NULL, OPT_COMPRESSION},
    {"format", required_argument, NULL, OPT_FORMAT},
    {"half", no_argument, NULL, OPT_HALF},
    {"exposure", required_argument, NULL, OPT_EXPOSURE},
    {NULL, 0, NULL, 0},
};

/* The values of the options that name a mode (each message lists them in
 * this order). */
static const lie_cli_choice exact_modes[] = {{"auto", LIE_EXACT_AUTO}, {"off", LIE_EXACT_OFF}, {NULL, 0}};
static const lie_cli_choice bitmask_modes[] = {
    {"auto", LIE_BITMASK_AUTO}, {"off", LIE_BITMASK_OFF}, {"only", LIE_BITMASK_ONLY}, {NULL, 0}};
static const lie_cli_choice patterns[] = {{"fixed", LIE_PATTERN_FIXED}, {"rotated", LIE_PATTERN_ROTATED}, {NULL, 0}};
static const lie_cli_choice lie_skips[] = {{"blockers", LIE_SKIP_BLOCKERS},
                                           {"fallback", LIE_SKIP_FALLBACK},
                                           {"both", LIE_SKIP_BLOCKERS | LIE_SKIP_FALLBACK},
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
        {OPT_PATTERN, patterns, offsetof(lie_render_options, pattern)},
        {OPT_LIE_SKIP, lie_skips, offsetof(lie_render_options, lie_skip)},
        {OPT_VISIBILITY, visibilities, offsetof(lie_render_options, visibility)},
        {OPT_RAYS, ray_modes, offsetof(lie_render_options, rays)},
    };
    _Static_assert(sizeof(lie_exact_mode) == sizeof(int) && sizeof(lie_bitmask_mode) == sizeof(int) &&
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
        if (!so->files && strcmp(in->input, "-") == 0) {
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

static const char *vis_name(lie_visibility_mode m)
{
    return m == LIE_VIS_FULL ? "full" : m == LIE_VIS_LIE ? "lie" : "none";
}
static const char *rays_name(lie_ray_mode m)
{
    return m == LIE_RAYS_SINGLE ? "single" : m == LIE_RAYS_PACKET ? "packet" : "stream";
}

/* What every frame's file is written with. */
typedef struct frame_out {
    const char *output, *input, *hash;
    const lie_render_options *ro;
    int path;
    lie_frame_options opt; /* the attributes are set per frame */
    int first; /* the number of the path's frame 0 */
} frame_out;

static lie_status write_frame(void *ctx, int fi, const lie_camera *fc, const lie_frame *frame, lie_error *err)
{
    const frame_out *o = ctx;
    const lie_render_options *ro = o->ro;
    char name[4096];
    int number = o->first + fi;
    if (o->path)
        snprintf(name, sizeof name, o->output, number);
    else
        snprintf(name, sizeof name, "%s", o->output);
    float yfov_deg = fc->yfov * 180.0f / (float)M_PI;
    lie_attr attrs[] = {
        {.name = "software", .type = LIE_ATTR_STRING, .s = "lie-render " LIE_VERSION},
        {.name = "lie.input", .type = LIE_ATTR_STRING, .s = o->input},
        {.name = "lie.sceneHash", .type = LIE_ATTR_STRING, .s = o->hash},
        {.name = "lie.visibility", .type = LIE_ATTR_STRING, .s = vis_name(ro->visibility)},
        {.name = "lie.pattern", .type = LIE_ATTR_STRING, .s = ro->pattern == LIE_PATTERN_FIXED ? "fixed" : "rotated"},
        {.name = "lie.lightSamples", .type = LIE_ATTR_INT, .i = ro->eye_only ? 0 : ro->light_samples},
        {.name = "lie.spp", .type = LIE_ATTR_INT, .i = ro->spp},
        {.name = "lie.maxDepth", .type = LIE_ATTR_INT, .i = ro->max_depth},
        {.name = "lie.frame", .type = LIE_ATTR_INT, .i = number},
        {.name = "lie.cameraEye", .type = LIE_ATTR_V3F, .v = {fc->eye.x, fc->eye.y, fc->eye.z}},
        {.name = "lie.cameraForward", .type = LIE_ATTR_V3F, .v = {fc->forward.x, fc->forward.y, fc->forward.z}},
        {.name = "lie.cameraUp", .type = LIE_ATTR_V3F, .v = {fc->up.x, fc->up.y, fc->up.z}},
        {.name = "lie.cameraYFovDegrees", .type = LIE_ATTR_FLOAT, .f = yfov_deg},
        /* orthographic views: their height in world units (0: perspective) */
        {.name = "lie.cameraOrthoHeight", .type = LIE_ATTR_FLOAT, .f = 2.0f * fc->ymag},
        /* OpenEXR's standard camera attributes (lie_view_exr_make) */
        {.name = "worldToCamera", .type = LIE_ATTR_M44F},
        {.name = "worldToNDC", .type = LIE_ATTR_M44F},
    };
    const int n_base = (int)(sizeof attrs / sizeof attrs[0]) - 2;
    lie_frame_options opt = o->opt;
    lie_view view = lie_view_make(fc, ro->width, ro->height);
    lie_view_exr ve = lie_view_exr_make(&view);
    memcpy(attrs[n_base].v, ve.world_to_camera, sizeof ve.world_to_camera);
    memcpy(attrs[n_base + 1].v, ve.world_to_ndc, sizeof ve.world_to_ndc);
    opt.exr.screen_window_center[0] = ve.screen_window_center[0];
    opt.exr.screen_window_center[1] = ve.screen_window_center[1];
    opt.exr.screen_window_width = ve.screen_window_width;
    opt.exr.attrs = attrs;
    opt.exr.n_attrs = (int)(sizeof attrs / sizeof attrs[0]);
    return lie_frame_write(name, frame, &opt, err);
}

/* What --stats prints: times are load, bvh, render and write seconds. */
typedef struct run_stats {
    const char *input;
    int rendered, skipped;
    double t_load, t_bvh, t_render, t_write;
} run_stats;

static void print_stats(int json, const run_stats *r, const lie_scene *scene, const lie_render_options *ro,
                        const lie_render_stats *rs)
{
    const char *input = r->input;
    int rendered = r->rendered, skipped = r->skipped;
    int threads = ro->threads > 0 ? ro->threads : lie_cpu_count();
    char size[32];
    snprintf(size, sizeof size, "%dx%d", ro->width, ro->height);
    /* pairs by path: occluded, closed form, exact, blockers, Embree, unshadowed, exact overflows, bitmasks */
    const unsigned long long pairs[8] = {rs->pairs_occluded, rs->pairs_analytic,  rs->pairs_exact,
                                         rs->pairs_blockers, rs->pairs_embree,    rs->pairs_unshadowed,
                                         rs->exact_overflows, rs->pairs_bitmask};
    double render = r->t_render;
    double mrays = render > 0.0 ? (double)rs->shadow_rays / render * 1e-6 : 0.0;
    if (json) {
        fprintf(stderr, "{\"tool\":\"lie-render\",\"input\":");
        lie_json_string(stderr, input);
        fprintf(stderr,
                ",\"frames\":%d,\"frames_skipped\":%d,\"triangles\":%u,\"emitters\":%d,"
                "\"width\":%d,\"height\":%d,\"spp\":%d,\"light_samples\":%d,\"visibility\":\"%s\","
                "\"rays\":\"%s\",\"threads\":%d,\"eye_rays\":%llu,\"reflection_rays\":%llu,"
                "\"shadow_rays\":%llu,\"shading_points\":%llu,\"seconds_load\":%.6f,"
                "\"seconds_bvh\":%.6f,\"seconds_render\":%.6f,\"seconds_write\":%.6f,"
                "\"shadow_mrays_per_second\":%.3f,\"shadow_tests_without_embree\":%llu,"
                "\"light_samples_total\":%llu,",
                rendered, skipped, scene->n_tris, scene->n_emitters, ro->width, ro->height, ro->spp,
                ro->eye_only ? 0 : ro->light_samples, vis_name(ro->visibility), rays_name(ro->rays), threads,
                (unsigned long long)rs->eye_rays, (unsigned long long)rs->reflection_rays,
                (unsigned long long)rs->shadow_rays, (unsigned long long)rs->shading_points, r->t_load,
                r->t_bvh, render, r->t_write, mrays, (unsigned long long)rs->shadow_rays_skipped,
                (unsigned long long)rs->light_samples);
        fprintf(stderr,
                "\"exact\":\"%s\",\"pairs_occluded\":%llu,\"pairs_analytic\":%llu,\"pairs_exact\":%llu,"
                "\"pairs_blockers\":%llu,\"pairs_embree\":%llu,\"pairs_unshadowed\":%llu,"
                "\"exact_overflows\":%llu,\"pairs_unbuilt\":%llu,\"points_unbuilt\":%llu,"
                "\"timers\":%s,\"cpu_seconds_analytic\":%.6f,"
                "\"cpu_seconds_exact\":%.6f,\"cpu_seconds_blockers\":%.6f,\"cpu_seconds_embree\":%.6f,"
                "\"cpu_seconds_sampled_shading\":%.6f,\"pairs_bitmask\":%llu,\"cpu_seconds_bitmask\":%.6f",
                exact_name(ro), pairs[0], pairs[1], pairs[2], pairs[3], pairs[4], pairs[5], pairs[6],
                (unsigned long long)rs->pairs_unbuilt, (unsigned long long)rs->points_unbuilt,
                ro->timers ? "true" : "false", rs->t_analytic,
                rs->t_exact, rs->t_blockers, rs->t_embree, rs->t_sampled_shading, pairs[7], rs->t_bitmask);
        render_dist_stats(stderr, 1);
        fprintf(stderr, "}\n");
    } else {
        fprintf(stderr,
                "%s: %s: %u triangles, %d emitters, %d points and %d lines skipped\n"
                "  image %s, %d spp, %d light samples, visibility %s, rays %s, %d threads\n"
                "  %d frame%s (%d skipped: their files exist); rays: %llu eye, %llu reflection, %llu shadow (Embree); %llu light samples\n"
                "  answered without Embree: %llu (visible pairs, blocker lists, or no shadows)\n"
                "  time: load %.3f s, bvh %.3f s, render %.3f s, write %.3f s\n"
                "  %.1f million Embree shadow rays per second of render time\n",
                prog, input, scene->n_tris, scene->n_emitters, scene->stats.points_skipped,
                scene->stats.lines_skipped, size, ro->spp, ro->eye_only ? 0 : ro->light_samples,
                vis_name(ro->visibility), rays_name(ro->rays), threads, rendered, rendered == 1 ? "" : "s", skipped,
                (unsigned long long)rs->eye_rays, (unsigned long long)rs->reflection_rays,
                (unsigned long long)rs->shadow_rays, (unsigned long long)rs->light_samples,
                (unsigned long long)rs->shadow_rays_skipped, r->t_load, r->t_bvh, render, r->t_write, mrays);
        fprintf(stderr,
                "  pairs (exact %s): %llu occluded, %llu seen whole in closed form, %llu partial exact,\n"
                "    %llu partial sampled against blockers, %llu sampled against the scene (Embree),\n"
                "    %llu seen whole and sampled, %llu partial as bitmasks; %llu exact pairs fell back to samples\n",
                exact_name(ro), pairs[0], pairs[1], pairs[2], pairs[3], pairs[4], pairs[5], pairs[7], pairs[6]);
        if (rs->pairs_unbuilt)
            fprintf(stderr, "  not built in the cache (lie-build --view/--path): %llu pairs at %llu shading points, "
                            "answered by Embree\n",
                    (unsigned long long)rs->pairs_unbuilt, (unsigned long long)rs->points_unbuilt);
        if (ro->timers)
            fprintf(stderr,
                    "  worker seconds: closed form %.3f, exact shadows %.3f, blocker samples %.3f,\n"
                    "    Embree %.3f, sampled shading %.3f, bitmasks %.3f\n",
                    rs->t_analytic, rs->t_exact, rs->t_blockers, rs->t_embree, rs->t_sampled_shading, rs->t_bitmask);
        render_dist_stats(stderr, 0);
    }
}

int main(int argc, char **argv)
{
    lie_render_options ro = lie_render_options_default();
    lie_scene_options so = lie_scene_options_default();
    const char *output = NULL, *camera = NULL, *scene_override = NULL, *path_file = NULL;
    long frame_a = -1, frame_b = -1;
    int skip_existing = 0;
    int visibility_set = 0;
    lie_frame_options fopt = {0};
    long v;
    int c;
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing input scene",
                   .takes = LIE_CLI_OUTPUT | LIE_CLI_THREADS | LIE_CLI_EXTERNAL | LIE_CLI_STATS | LIE_CLI_VERBOSE};
    int taken;
    while ((c = lie_cli_next(&cli, argc, argv, "", long_opts)) > 0) {
        if ((taken = pick_mode(&cli, c, &ro)) != 0) {
            if (taken < 0)
                return cli.status;
            visibility_set |= c == OPT_VISIBILITY;
            continue;
        }
        switch (c) {
        case OPT_CAMERA: camera = optarg; break;
        case OPT_SIZE:
            if (!lie_parse_size(optarg, 65536, &ro.width, &ro.height))
                return usage_error("--size: expected WxH, got '%s'", optarg);
            break;
        case OPT_SPP:
            if (!lie_cli_long(&cli, 1, 65536, &v))
                return cli.status;
            ro.spp = (int)v;
            break;
        case OPT_LIGHT_SAMPLES:
            if (strcmp(optarg, "exact") == 0) {
                ro.exact = LIE_EXACT_ONLY;
                ro.light_samples = LIE_LIGHT_SAMPLES_DEFAULT;
                break;
            }
            if (!lie_parse_long(optarg, 0, 1000000, &v))
                return usage_error("--light-samples: expected an integer in 0..1000000 or exact, got '%s'", optarg);
            ro.light_samples = (int)v;
            if (ro.exact == LIE_EXACT_ONLY)
                ro.exact = LIE_EXACT_AUTO;
            break;
        case OPT_TIMERS: ro.timers = 1; break;
        case OPT_MAX_DEPTH:
            if (!lie_cli_long(&cli, 0, 64, &v))
                return cli.status;
            ro.max_depth = (int)v;
            break;
        case OPT_AOV:
            if (!parse_aovs(optarg, &ro.aovs))
                return usage_error("--aov: expected a list of albedo, normal, depth, complexity, patch, got '%s'",
                                   optarg);
            break;
        case OPT_FORMAT:
            if (!lie_frame_format_parse(optarg, &fopt.format))
                return usage_error("--format: expected exr or png, got '%s'", optarg);
            break;
        case OPT_HALF: fopt.exr.half = 1; break;
        case OPT_COMPRESSION:
            if (!lie_exr_compression_parse(optarg, &fopt.exr.compression))
                return usage_error("--compression: expected zip, zips, piz, rle or none, got '%s'", optarg);
            break;
        case OPT_EXPOSURE:
            if (!lie_parse_float(optarg, -64.0f, 64.0f, &fopt.png.exposure))
                return usage_error("--exposure: expected a number of stops, got '%s'", optarg);
            break;
        case OPT_SCENE: scene_override = optarg; break;
        case OPT_PATH: path_file = optarg; break;
        case OPT_FRAMES:
            if (!lie_parse_range(optarg, 0, 999999, &frame_a, &frame_b))
                return usage_error("--frames: expected A-B with 0 <= A <= B <= 999999, got '%s'", optarg);
            break;
        case OPT_SKIP_EXISTING: skip_existing = 1; break;
        case OPT_EMITTER:
            if (!lie_parse_long(optarg, 0, 1 << 30, &v))
                return usage_error("--emitter: expected an emitter index, got '%s'", optarg);
            ro.aov_emitter = (int)v;
            break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    so.allow_external_uris = cli.external;
    ro.threads = cli.threads;
    fopt.exr.threads = ro.threads;
    output = cli.output;
    const char *input = cli.operand;
    if (!output)
        return usage_error("%s", "missing -o OUTPUT");
    lie_frame_format out_format;
    if (fopt.format == LIE_FORMAT_AUTO && !lie_frame_format_of(output, &out_format))
        return usage_error("%s: cannot write this format: use .exr or .png (or --format exr|png)", output);
    if (path_file && !lie_frame_pattern_ok(output))
        return usage_error("--path: -o must hold one %%d conversion (e.g. frame_%%04d.exr), got '%s'", output);
    if (path_file && camera)
        return usage_error("%s", "--path and --camera exclude each other");
    if (frame_a >= 0 && !path_file)
        return usage_error("%s", "--frames needs --path");
    if (ro.light_samples == 0) {
        ro.eye_only = 1;
        ro.light_samples = 1;
    }
    if (lie_dist_start(&argc, &argv) > 1) {
        cli.quiet = 1; /* progress and warnings: one process's are enough; rank 0 prints the statistics */
        if (lie_dist_rank() != 0)
            cli.stats = 0;
    }
    ro.progress = !cli.quiet;

    lie_error err;
    lie_error_clear(&err);
    double t0 = lie_time_now();
    inputs in = {input, scene_override, path_file, NULL, NULL, NULL};
    if (lie_dist_load(&so, load_input, &in, &err) != LIE_OK) {
        lie_camera_path_destroy(in.cpath);
        lie_scene_destroy(in.scene);
        lie_cache_destroy(in.cache);
        return fail(&err);
    }
    lie_scene *scene = in.scene;
    lie_cache *cache = in.cache;
    lie_camera_path *cpath = in.cpath;
    lie_lie_vis *lv = NULL;
    lie_rt *rt = NULL;
    lie_status st = LIE_OK;
    double t1 = lie_phase(prog, cli.verbose, "load", t0);
    if (!visibility_set)
        ro.visibility = cache ? LIE_VIS_LIE : LIE_VIS_FULL;
    if (!cache && (ro.visibility == LIE_VIS_LIE || (ro.aovs & (LIE_AOV_COMPLEXITY | LIE_AOV_PATCH)))) {
        lie_camera_path_destroy(cpath);
        lie_scene_destroy(scene);
        return usage_error("%s: --visibility=lie and the complexity and patch layers need a cache", input);
    }
    if (cache && (st = lie_lie_vis_create(scene, cache->env, &lv, &err)) != LIE_OK)
        goto done;
    ro.oracle = lv ? lie_lie_vis_oracle(lv) : NULL;
    if (!cli.quiet)
        lie_print_scene_warnings(prog, scene, input);
    if (scene->n_emitters == 0 && !cli.quiet)
        fprintf(stderr, "%s: %s: warning: no emitters (no emissive material, no KHR_lights_punctual light): "
                        "the image shows emission only\n", prog, input);
    if (ro.aov_emitter >= scene->n_emitters) {
        st = lie_error_set(&err, LIE_ERR_ARG, input, "--emitter %d: the scene has %d emitters", ro.aov_emitter,
                           scene->n_emitters);
        goto done;
    }
    lie_camera cam;
    st = path_file ? LIE_OK : lie_camera_parse(scene, camera, &cam, &err);
    if (st != LIE_OK) {
        if (!err.file[0])
            snprintf(err.file, sizeof err.file, "%s", input);
        goto done;
    }
    if ((st = lie_rt_create(scene, &rt, &err)) != LIE_OK ||
        (st = lie_dist_check(scene->hash, cache ? cache->state_hash : 0, &err)) != LIE_OK)
        goto done;
    double t2 = lie_phase(prog, cli.verbose, "bvh", t1);
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)scene->hash);
    int n_frames = cpath ? cpath->n_frames : 1, first = cpath ? cpath->first : 0, rendered = 0, skipped = 0;
    if (cpath && frame_a >= 0 && (frame_a < first || frame_b > (long)first + n_frames - 1)) {
        st = lie_error_set(&err, LIE_ERR_ARG, path_file, "--frames %ld-%ld: the path has frames %d-%d", frame_a,
                           frame_b, first, first + n_frames - 1);
        goto done;
    }
    lie_render_stats rs;
    memset(&rs, 0, sizeof rs);
    double t_render = 0.0, t_write = 0.0;
    /* the frames to render: --frames, and --skip-existing's files as rank 0 sees them */
    int *todo = malloc(sizeof *todo * ((size_t)n_frames + 1)), n_todo = 0;
    if (!todo) {
        lie_error_set(&err, LIE_ERR_NOMEM, input, "out of memory");
        st = LIE_ERR_NOMEM;
    }
    for (int fi = 0; todo && fi < n_frames; fi++) {
        int number = first + fi;
        if (frame_a >= 0 && (number < frame_a || number > frame_b))
            continue;
        char name[4096];
        if (cpath)
            snprintf(name, sizeof name, output, number);
        else
            snprintf(name, sizeof name, "%s", output);
        struct stat sb;
        if (skip_existing && strcmp(name, "-") != 0 && stat(name, &sb) == 0) {
            skipped++; /* a resumed run: the frame was written (atomically) before */
            continue;
        }
        todo[n_todo++] = fi;
    }
    frame_out fo = {output, input, hash, &ro, cpath != NULL, fopt, first};
    if (todo && lie_dist_size() > 1) {
        lie_dist_bcast(&n_todo, sizeof n_todo);
        lie_dist_bcast(todo, sizeof *todo * (size_t)n_todo);
        double ta = lie_time_now();
        st = render_dist(scene, rt, &ro, cpath, &cam, todo, n_todo, write_frame, &fo, &rs, &t_write, &err);
        t_render = lie_time_now() - ta - t_write;
        rendered = n_todo;
    }
    for (int k = 0; todo && lie_dist_size() == 1 && k < n_todo && st == LIE_OK; k++) {
        int fi = todo[k];
        lie_camera fc = cpath ? lie_camera_path_frame(cpath, fi) : cam;
        rendered++;
        double ta = lie_time_now();
        lie_frame *frame = NULL;
        lie_render_stats fs;
        char label[64];
        if (cpath) {
            snprintf(label, sizeof label, "frame %d/%d", k + 1, n_todo);
            ro.progress_label = label;
        }
        st = lie_render(scene, rt, &fc, &ro, &frame, &fs, &err);
        ro.progress_label = NULL;
        if (st != LIE_OK)
            break;
        double tb = lie_time_now();
        lie_render_stats_add(&rs, &fs);
        if (cpath)
            snprintf(label, sizeof label, "frame %d: render", first + fi);
        lie_phase(prog, cli.verbose, cpath ? label : "render", ta);
        st = write_frame(&fo, fi, &fc, frame, &err);
        lie_frame_destroy(frame);
        if (cpath)
            snprintf(label, sizeof label, "frame %d: write", first + fi);
        lie_phase(prog, cli.verbose && st == LIE_OK, cpath ? label : "write", tb);
        t_render += tb - ta;
        t_write += lie_time_now() - tb;
    }
    free(todo);
    if (st == LIE_OK && cli.stats) {
        run_stats r = {input, rendered, skipped, t1 - t0, t2 - t1, t_render, t_write};
        print_stats(cli.stats == 2, &r, scene, &ro, &rs);
    }
done:
    lie_camera_path_destroy(cpath);
    lie_rt_destroy(rt);
    lie_lie_vis_destroy(lv);
    lie_cache_destroy(cache);
    lie_scene_destroy(scene);
    if (st != LIE_OK)
        return fail(&err);
    return 0;
}
