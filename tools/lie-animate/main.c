/* SPDX-License-Identifier: Apache-2.0 */
/* lie-animate: turn a glTF animation (glTF 2.0 §3.11) into one absolute
 * edit file per frame (formats/edit.md) and the animated camera's motion
 * into a camera path (formats/camera-path.md) whose frames match.
 *   lie-animate SCENE.gltf --fps F -o edits/frame_%04d.yaml [options] */
#include "common/cli.h"
#include "lie.h"

#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *prog = "lie-animate";

static void usage(FILE *fp)
{
    fprintf(fp,
            "Usage: %s SCENE.gltf|SCENE.glb --fps F -o EDITS_%%04d.yaml [options]\n"
            "\n"
            "Sample one of the scene's glTF animations at F frames a second and write,\n"
            "for every frame, an edit file that poses the scene at that time: absolute\n"
            "set-transform operations (local transforms) for the animated nodes, including\n"
            "skin joints, and set-weights for animated morph weights.  Each file is\n"
            "absolute, so `rst-update base.lie FRAME.yaml` from the base cache and the same\n"
            "update chained from the previous frame's cache give the same scene.  Time runs\n"
            "from the animation's first key: frame N is at N / F seconds after it.\n"
            "\n"
            "  -o, --output PATTERN     edit files, with one %%d conversion for the frame number\n"
            "      --fps F              frames per second (required, > 0)\n"
            "      --animation NAME|N   which animation (default: the first)\n"
            "      --frames A-B         frames A to B (default: 0 to the animation's end)\n"
            "      --camera-path FILE   also write the camera's motion as a camera path with\n"
            "                           one key per frame (first-frame A); a scene without\n"
            "                           a camera gets lie-render's default framing, held\n"
            "      --camera NAME        the camera node for --camera-path (default: the first)\n"
            "      --allow-external-uris  let glTF files reference files outside their folder\n"
            "      --stats[=json]       frames, nodes and weights written\n"
            "      --stats-file FILE    the --stats=json record to FILE, not stderr\n"
            "  -q, --quiet              no warnings\n"
            "  -h, --help               this help\n"
            "      --version            print the version\n",
            prog);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

enum { OPT_FPS = 256, OPT_ANIMATION, OPT_FRAMES, OPT_CAMERA_PATH, OPT_CAMERA };

static const struct option long_opts[] = {
    {"fps", required_argument, NULL, OPT_FPS},
    {"animation", required_argument, NULL, OPT_ANIMATION},
    {"frames", required_argument, NULL, OPT_FRAMES},
    {"camera-path", required_argument, NULL, OPT_CAMERA_PATH},
    {"camera", required_argument, NULL, OPT_CAMERA},
    {NULL, 0, NULL, 0},
};

/* A node's name for a YAML comment: printable ASCII only. */
static void comment_name(const char *name, char *out, size_t size)
{
    size_t k = 0;
    for (const char *p = name ? name : ""; *p && k + 1 < size; p++)
        out[k++] = (*p >= 32 && *p < 127) ? *p : '?';
    out[k] = 0;
}

typedef struct targets {
    int *trs_nodes, n_trs;     /* animated TRS, written as set-transform */
    int *w_nodes, n_w;         /* animated weights, written as set-weights */
    int outside, inert;        /* channels' nodes outside the default scene; nodes whose transform moves nothing */
} targets;

/* The nodes animation a writes, in node order. */
static lie_status pick_targets(const lie_scene *s, int a, int quiet, const char *scene_path, targets *t, lie_error *err)
{
    const lie_animation *an = &s->animations[a];
    unsigned char *trs = calloc((size_t)s->n_nodes + 1, 1), *w = calloc((size_t)s->n_nodes + 1, 1);
    t->trs_nodes = malloc(sizeof(int) * ((size_t)s->n_nodes + 1));
    t->w_nodes = malloc(sizeof(int) * ((size_t)s->n_nodes + 1));
    if (!trs || !w || !t->trs_nodes || !t->w_nodes) {
        free(trs);
        free(w);
        return lie_error_set(err, LIE_ERR_NOMEM, scene_path, "out of memory");
    }
    for (int c = 0; c < an->n_channels; c++) {
        const lie_anim_channel *ch = &an->channels[c];
        if (ch->path == LIE_ANIM_WEIGHTS)
            w[ch->node] = 1;
        else
            trs[ch->node] = 1;
    }
    for (int i = 0; i < s->n_nodes; i++) {
        if (!trs[i] && !w[i])
            continue;
        if (!lie_scene_node_in_scene(s, i)) {
            /* reported, and left out: the default scene never shows it */
            t->outside++;
            if (!quiet) {
                char nm[128];
                comment_name(s->nodes[i].name, nm, sizeof nm);
                fprintf(stderr, "%s: %s: warning: animation %d targets node #%d%s%s%s, which is not in the default scene\n",
                        prog, scene_path, a, i, nm[0] ? " '" : "", nm, nm[0] ? "'" : "");
            }
            continue;
        }
        if (trs[i]) {
            if (lie_edit_transform_matters(s, i))
                t->trs_nodes[t->n_trs++] = i;
            else
                t->inert++;
        }
        if (w[i])
            t->w_nodes[t->n_w++] = i;
    }
    free(trs);
    free(w);
    return LIE_OK;
}

/* The first camera node in the order lie_scene_flatten finds cameras
 * (default scene, depth-first pre-order), or the one named. */
static int find_camera_node(const lie_scene *s, const char *name)
{
    int *stack = malloc(sizeof(int) * ((size_t)s->n_nodes + 1)), n = 0, found = -1;
    if (!stack)
        return -1;
    for (int r = 0; r < s->n_roots && found < 0; r++) {
        stack[n++] = s->roots[r];
        while (n > 0 && found < 0) {
            int i = stack[--n];
            const lie_node *nd = &s->nodes[i];
            if (nd->camera >= 0 && !nd->removed &&
                (!name || (nd->name && strcmp(nd->name, name) == 0) ||
                 (s->camera_defs[nd->camera].name && strcmp(s->camera_defs[nd->camera].name, name) == 0)))
                found = i;
            for (int c = nd->n_children - 1; c >= 0 && n < s->n_nodes; c--)
                stack[n++] = nd->children[c];
        }
    }
    free(stack);
    return found;
}

/* A camera node's world view, as lie_scene_flatten computes it. */
static lie_camera_key camera_key(const lie_scene *s, int node)
{
    lie_mat4 w = lie_node_world_matrix(s, node);
    lie_camera_key k;
    memset(&k, 0, sizeof k);
    k.eye = lie_mat4_point(&w, lie_v3(0.0f, 0.0f, 0.0f));
    lie_vec3 f = lie_v3_norm(lie_mat4_vector(&w, lie_v3(0.0f, 0.0f, -1.0f)));
    lie_vec3 up = lie_mat4_vector(&w, lie_v3(0.0f, 1.0f, 0.0f));
    up = lie_v3_sub(up, lie_v3_scale(f, lie_v3_dot(up, f)));
    k.target = lie_v3_add(k.eye, f);
    k.up = lie_v3_norm(up);
    k.fov_deg = s->camera_defs[s->nodes[node].camera].yfov * (float)(180.0 / M_PI);
    k.frames = 1;
    return k;
}

static int write_frame(const char *name, const lie_scene *s, const char *scene_path, int a, long frame, double t,
                       const lie_pose *pose, const targets *tg, lie_error *err)
{
    lie_atomic_file af;
    if (lie_atomic_open(&af, name, err) != LIE_OK)
        return 0;
    FILE *fp = af.fp;
    char nm[128];
    comment_name(s->animations[a].name, nm, sizeof nm);
    fprintf(fp, "# lie-animate: animation %d%s%s%s, frame %ld, t = %.9g s after its first key\n", a,
            nm[0] ? " '" : "", nm, nm[0] ? "'" : "", frame, t);
    if (tg->n_trs + tg->n_w == 0)
        fprintf(fp, "[]\n");
    for (int k = 0; k < tg->n_trs; k++) {
        int i = tg->trs_nodes[k];
        lie_mat4 m = lie_node_trs_matrix(pose->trs + 10 * (size_t)i);
        fprintf(fp, "- set-transform: {node: \"#%d\", matrix: [", i);
        for (int c = 0; c < 16; c++)
            fprintf(fp, "%s%.17g", c ? ", " : "", m.m[c] == 0.0 ? 0.0 : m.m[c]);
        comment_name(s->nodes[i].name, nm, sizeof nm);
        fprintf(fp, "]}%s%s\n", nm[0] ? "  # " : "", nm);
    }
    for (int k = 0; k < tg->n_w; k++) {
        int i = tg->w_nodes[k];
        fprintf(fp, "- set-weights: {node: \"#%d\", weights: [", i);
        for (int c = 0; c < s->nodes[i].n_weights; c++)
            fprintf(fp, "%s%.17g", c ? ", " : "", pose->weights[i][c] == 0.0 ? 0.0 : pose->weights[i][c]);
        comment_name(s->nodes[i].name, nm, sizeof nm);
        fprintf(fp, "]}%s%s\n", nm[0] ? "  # " : "", nm);
    }
    if (ferror(fp)) {
        lie_atomic_abort(&af);
        lie_error_set(err, LIE_ERR_IO, name, "write failed");
        return 0;
    }
    (void)scene_path;
    return lie_atomic_commit(&af, err) == LIE_OK;
}

/* The command line, and what the run loads and makes. */
typedef struct run {
    lie_scene_options so;
    const char *output, *anim_spec, *path_out, *camera_name, *scene_path;
    double fps;
    long fa, fb; /* the frames */
    int have_frames;
    lie_scene *s;
    int a, cam;      /* the animation; the camera node of --camera-path */
    double duration; /* the animation's, in seconds */
    targets tg;
    lie_camera_path cp;
    lie_file_set *files;   /* the scene's files: no output may replace one */
    lie_camera_key fixed; /* a scene without a camera: every key (fixed.frames = 1) */
    lie_error err;
} run;

/* Every frame's file and --camera-path: none an input, nor the path one of
 * the frames; checked before the first is written. */
static lie_status check_outputs(run *r)
{
    lie_status st = r->path_out ? lie_file_set_claim(r->files, r->path_out, NULL, &r->err) : LIE_OK;
    for (long f = r->fa; st == LIE_OK && f <= r->fb; f++) {
        char name[4096];
        snprintf(name, sizeof name, r->output, (int)f);
        st = lie_file_set_check(r->files, name, &r->err);
    }
    return st;
}

/* The options: -1 to go on, or the exit status. */
static int parse_options(run *r, lie_cli *cli, int argc, char **argv)
{
    int c;
    while ((c = lie_cli_next(cli, argc, argv, "", long_opts)) > 0) {
        switch (c) {
        case OPT_FPS: {
            float f;
            if (!lie_parse_float(optarg, 1e-3f, 1e6f, &f))
                return usage_error("--fps: expected a number in [0.001, 1e6], got '%s'", optarg);
            r->fps = f;
            break;
        }
        case OPT_ANIMATION: r->anim_spec = optarg; break;
        case OPT_FRAMES:
            if (!lie_parse_range(optarg, 0, 999999, &r->fa, &r->fb))
                return usage_error("--frames: expected A-B with 0 <= A <= B <= 999999, got '%s'", optarg);
            r->have_frames = 1;
            break;
        case OPT_CAMERA_PATH: r->path_out = optarg; break;
        case OPT_CAMERA: r->camera_name = optarg; break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli->status;
    r->so.allow_external_uris = cli->external;
    r->output = cli->output;
    r->scene_path = cli->operand;
    if (!r->output)
        return usage_error("%s", "missing -o EDITS_%%04d.yaml");
    if (!lie_frame_pattern_ok(r->output))
        return usage_error("-o: expected one %%d conversion (e.g. frame_%%04d.yaml), got '%s'", r->output);
    if (r->fps <= 0.0)
        return usage_error("%s", "missing --fps F");
    if (r->camera_name && !r->path_out)
        return usage_error("%s", "--camera needs --camera-path");
    return -1;
}

/* The scene, the animation, its frames and targets. */
static lie_status load(run *r, int quiet)
{
    lie_error *err = &r->err;
    if (!(r->files = lie_file_set_create(LIE_FILES_NAMES)))
        return lie_error_set(err, LIE_ERR_NOMEM, r->scene_path, "out of memory");
    r->so.files = r->files;
    lie_status st = lie_scene_load(r->scene_path, &r->so, &r->s, err);
    if (st != LIE_OK)
        return st;
    const lie_scene *s = r->s;
    if (!quiet)
        lie_print_scene_warnings(prog, s, r->scene_path);
    if (s->n_animations == 0)
        return lie_error_set(err, LIE_ERR_NOT_FOUND, r->scene_path, "the scene has no animations");
    r->a = lie_scene_find_animation(s, r->anim_spec);
    if (r->a < 0)
        return lie_error_set(err, LIE_ERR_NOT_FOUND, r->scene_path,
                             "animation '%s': no animation has this name or index (0..%d)", r->anim_spec,
                             s->n_animations - 1);
    const lie_animation *an = &s->animations[r->a];
    r->duration = (double)an->end - an->start;
    if (!r->have_frames) {
        /* the last frame, compared before it is converted: an end of 1e30 s
         * (a last key, or an unused sampler's) must not reach the cast */
        double last = floor(r->duration * r->fps + 1e-6);
        if (!(last <= 999999.0))
            return lie_error_set(err, LIE_ERR_LIMIT, r->scene_path,
                                 "%.6g frames (%.6g s at %g fps): more than 1000000", last + 1.0, r->duration,
                                 r->fps);
        r->fa = 0;
        r->fb = (long)last;
    }
    return pick_targets(s, r->a, quiet, r->scene_path, &r->tg, err);
}

/* --camera-path: the camera node, and room for a key per frame.  A scene without a camera
 * (an asset such as a character) gets lie-render's default framing of the scene as loaded,
 * held for every frame: the view stays put while the asset moves in it. */
static lie_status camera_path_start(run *r, int quiet)
{
    const lie_scene *s = r->s;
    r->cam = find_camera_node(s, r->camera_name);
    if (r->cam < 0 && !r->camera_name) {
        lie_camera c = lie_scene_default_camera(s);
        r->fixed.eye = c.eye;
        r->fixed.target = lie_v3_add(c.eye, c.forward);
        r->fixed.up = c.up;
        r->fixed.fov_deg = c.yfov * (float)(180.0 / M_PI);
        r->fixed.frames = 1;
        if (!quiet)
            fprintf(stderr, "%s: %s: warning: the default scene has no camera; the camera path holds "
                            "lie-render's default framing of the scene as loaded\n", prog, r->scene_path);
    } else if (r->cam < 0)
        return lie_error_set(&r->err, LIE_ERR_NOT_FOUND, r->scene_path,
                             "camera '%s': no camera node has this name", r->camera_name);
    if (r->cam >= 0 && s->camera_defs[s->nodes[r->cam].camera].yfov <= 0.0f)
        return lie_error_set(&r->err, LIE_ERR_UNSUPPORTED, r->scene_path,
                             "camera node #%d is orthographic; camera paths hold perspective cameras", r->cam);
    r->cp.keys = calloc((size_t)(r->fb - r->fa + 1), sizeof *r->cp.keys);
    if (!r->cp.keys)
        return lie_error_set(&r->err, LIE_ERR_NOMEM, r->scene_path, "out of memory");
    return LIE_OK;
}

/* Every frame's edit file, and the camera's key for --camera-path. */
static lie_status write_frames(run *r)
{
    lie_pose *pose = NULL;
    lie_status st = LIE_OK;
    for (long f = r->fa; st == LIE_OK && f <= r->fb; f++) {
        double t = (double)f / r->fps;
        lie_pose_destroy(pose);
        pose = NULL;
        if ((st = lie_animation_pose(r->s, r->a, t, &pose, &r->err)) != LIE_OK)
            break;
        char name[4096];
        if (snprintf(name, sizeof name, r->output, (int)f) >= (int)sizeof name) {
            st = lie_error_set(&r->err, LIE_ERR_ARG, r->output, "output name too long");
            break;
        }
        if (!write_frame(name, r->s, r->scene_path, r->a, f, t, pose, &r->tg, &r->err)) {
            st = r->err.status != LIE_OK ? r->err.status : LIE_ERR_IO;
            break;
        }
        if (r->path_out) {
            /* pose the document's locals (the animated nodes only), then read the camera */
            for (int k = 0; k < r->tg.n_trs; k++)
                r->s->nodes[r->tg.trs_nodes[k]].local =
                    lie_node_trs_matrix(pose->trs + 10 * (size_t)r->tg.trs_nodes[k]);
            lie_camera_key k = r->cam >= 0 ? camera_key(r->s, r->cam) : r->fixed;
            if (!lie_v3_within(k.eye, LIE_CAMERA_COORD_MAX) || !lie_v3_within(k.target, LIE_CAMERA_COORD_MAX)) {
                st = lie_error_set(&r->err, LIE_ERR_LIMIT, r->scene_path,
                                   "frame %ld: the camera is outside the coordinate range (+-%g)", f,
                                   (double)LIE_CAMERA_COORD_MAX);
                break;
            }
            r->cp.keys[r->cp.n_keys++] = k;
        }
    }
    lie_pose_destroy(pose);
    return st;
}

static lie_status print_stats(run *r, double secs, const lie_cli *cli)
{
    const targets *tg = &r->tg;
    int channels = r->s->animations[r->a].n_channels;
    long frames = r->fb - r->fa + 1;
    if (cli->stats == 2) {
        lie_stats_json js;
        FILE *fp = lie_stats_json_begin(&js, prog, r->scene_path);
        if (fp) {
            fprintf(fp, ",\"animation\":%d,\"frames\":%ld,\"first\":%ld,\"fps\":%.9g,"
                        "\"duration\":%.9g,\"channels\":%d,\"transforms\":%d,\"weights\":%d,\"outside_scene\":%d,"
                        "\"inert\":%d,\"camera_path\":%d,\"seconds\":%.6f}\n",
                r->a, frames, r->fa, r->fps, r->duration, channels, tg->n_trs, tg->n_w, tg->outside, tg->inert,
                r->path_out != NULL, secs);
        }
        return lie_stats_json_end(cli, &js, &r->err);
    }
    fprintf(stderr,
                "%s: %s: animation %d, %d channels, %.3f s at %g fps: frames %ld-%ld\n"
                "  per frame: %d set-transform, %d set-weights; %d nodes outside the default scene, %d whose "
                "transform moves nothing%s\n"
                "  time: %.3f s\n",
                prog, r->scene_path, r->a, channels, r->duration, r->fps, r->fa, r->fb, tg->n_trs, tg->n_w,
                tg->outside, tg->inert, r->path_out ? "; camera path written" : "", secs);
    return LIE_OK;
}

int main(int argc, char **argv)
{
    run r;
    memset(&r, 0, sizeof r);
    r.so = lie_scene_options_default();
    r.fb = -1;
    r.cam = -1;
    lie_error_clear(&r.err);
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing scene",
                   .takes = LIE_CLI_OUTPUT | LIE_CLI_EXTERNAL | LIE_CLI_STATS};
    int rc = parse_options(&r, &cli, argc, argv);
    if (rc >= 0)
        return rc;
    double t0 = lie_time_now();
    lie_status st = load(&r, cli.quiet);
    if (st == LIE_OK && r.path_out)
        st = camera_path_start(&r, cli.quiet);
    if (st == LIE_OK)
        st = check_outputs(&r);
    if (st == LIE_OK)
        st = write_frames(&r);
    if (st == LIE_OK && r.path_out) {
        r.cp.smooth = 0; /* one key per frame: frame i is key i exactly */
        r.cp.first = (int)r.fa;
        r.cp.n_frames = r.cp.n_keys;
        st = lie_camera_path_write(&r.cp, r.path_out, &r.err);
    }
    if (st == LIE_OK && cli.stats)
        st = print_stats(&r, lie_time_now() - t0, &cli);
    rc = st == LIE_OK ? 0 : lie_report_error(prog, &r.err, 1);
    free(r.cp.keys);
    free(r.tg.trs_nodes);
    free(r.tg.w_nodes);
    lie_scene_destroy(r.s);
    lie_file_set_destroy(r.files);
    return rc;
}
