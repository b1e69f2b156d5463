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
            "usage: %s SCENE.gltf|SCENE.glb --fps F -o EDITS_%%04d.yaml [options]\n"
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
            "                           one key per frame (first-frame A)\n"
            "      --camera NAME        the camera node for --camera-path (default: the first)\n"
            "      --allow-external-uris  let glTF files reference files outside their folder\n"
            "      --stats[=json]       frames, nodes and weights written\n"
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

int main(int argc, char **argv)
{
    lie_scene_options so = lie_scene_options_default();
    const char *output = NULL, *anim_spec = NULL, *path_out = NULL, *camera_name = NULL;
    double fps = 0.0;
    long fa = 0, fb = -1;
    int have_frames = 0, c;
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing scene",
                   .takes = LIE_CLI_OUTPUT | LIE_CLI_EXTERNAL | LIE_CLI_STATS};
    while ((c = lie_cli_next(&cli, argc, argv, "", long_opts)) > 0) {
        switch (c) {
        case OPT_FPS: {
            float f;
            if (!lie_parse_float(optarg, 1e-3f, 1e6f, &f))
                return usage_error("--fps: expected a number in [0.001, 1e6], got '%s'", optarg);
            fps = f;
            break;
        }
        case OPT_ANIMATION: anim_spec = optarg; break;
        case OPT_FRAMES:
            if (!lie_parse_range(optarg, 0, 999999, &fa, &fb))
                return usage_error("--frames: expected A-B with 0 <= A <= B <= 999999, got '%s'", optarg);
            have_frames = 1;
            break;
        case OPT_CAMERA_PATH: path_out = optarg; break;
        case OPT_CAMERA: camera_name = optarg; break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    so.allow_external_uris = cli.external;
    output = cli.output;
    const char *scene_path = cli.operand;
    if (!output)
        return usage_error("%s", "missing -o EDITS_%%04d.yaml");
    if (!lie_frame_pattern_ok(output))
        return usage_error("-o: expected one %%d conversion (e.g. frame_%%04d.yaml), got '%s'", output);
    if (fps <= 0.0)
        return usage_error("%s", "missing --fps F");
    if (camera_name && !path_out)
        return usage_error("%s", "--camera needs --camera-path");

    double t0 = lie_time_now();
    lie_error err;
    lie_error_clear(&err);
    lie_scene *s = NULL;
    lie_pose *pose = NULL;
    lie_camera_path cp;
    memset(&cp, 0, sizeof cp);
    targets tg;
    memset(&tg, 0, sizeof tg);
    int rc = 1, cam = -1;
    if (lie_scene_load(scene_path, &so, &s, &err) != LIE_OK)
        goto done;
    if (!cli.quiet)
        lie_print_scene_warnings(prog, s, scene_path);
    if (s->n_animations == 0) {
        lie_error_set(&err, LIE_ERR_NOT_FOUND, scene_path, "the scene has no animations");
        goto done;
    }
    int a = lie_scene_find_animation(s, anim_spec);
    if (a < 0) {
        lie_error_set(&err, LIE_ERR_NOT_FOUND, scene_path, "animation '%s': no animation has this name or index (0..%d)",
                      anim_spec, s->n_animations - 1);
        goto done;
    }
    const lie_animation *an = &s->animations[a];
    double duration = (double)an->end - an->start;
    if (!have_frames) {
        fa = 0;
        fb = (long)floor(duration * fps + 1e-6);
    }
    if (fb > 999999) {
        lie_error_set(&err, LIE_ERR_LIMIT, scene_path, "%ld frames: more than 1000000", fb + 1);
        goto done;
    }
    if (pick_targets(s, a, cli.quiet, scene_path, &tg, &err) != LIE_OK)
        goto done;
    if (path_out) {
        cam = find_camera_node(s, camera_name);
        if (cam < 0) {
            lie_error_set(&err, LIE_ERR_NOT_FOUND, scene_path, camera_name ? "camera '%s': no camera node has this name"
                                                                          : "%sthe default scene has no camera",
                          camera_name ? camera_name : "");
            goto done;
        }
        if (s->camera_defs[s->nodes[cam].camera].yfov <= 0.0f) {
            lie_error_set(&err, LIE_ERR_UNSUPPORTED, scene_path,
                          "camera node #%d is orthographic; camera paths hold perspective cameras", cam);
            goto done;
        }
        cp.keys = calloc((size_t)(fb - fa + 1), sizeof *cp.keys);
        if (!cp.keys) {
            lie_error_set(&err, LIE_ERR_NOMEM, scene_path, "out of memory");
            goto done;
        }
    }
    for (long f = fa; f <= fb; f++) {
        double t = (double)f / fps;
        lie_pose_destroy(pose);
        pose = NULL;
        if (lie_animation_pose(s, a, t, &pose, &err) != LIE_OK)
            goto done;
        char name[4096];
        if (snprintf(name, sizeof name, output, (int)f) >= (int)sizeof name) {
            lie_error_set(&err, LIE_ERR_ARG, output, "output name too long");
            goto done;
        }
        if (!write_frame(name, s, scene_path, a, f, t, pose, &tg, &err))
            goto done;
        if (path_out) {
            /* pose the document's locals (the animated nodes only), then read the camera */
            for (int k = 0; k < tg.n_trs; k++)
                s->nodes[tg.trs_nodes[k]].local = lie_node_trs_matrix(pose->trs + 10 * (size_t)tg.trs_nodes[k]);
            cp.keys[cp.n_keys++] = camera_key(s, cam);
        }
    }
    if (path_out) {
        cp.smooth = 0; /* one key per frame: frame i is key i exactly */
        cp.first = (int)fa;
        cp.n_frames = cp.n_keys;
        if (lie_camera_path_write(&cp, path_out, &err) != LIE_OK)
            goto done;
    }
    rc = 0;
    if (cli.stats) {
        double secs = lie_time_now() - t0;
        long frames = fb - fa + 1;
        if (cli.stats == 2) {
            fprintf(stderr, "{\"tool\":\"lie-animate\",\"animation\":%d,\"frames\":%ld,\"first\":%ld,\"fps\":%.9g,"
                            "\"duration\":%.9g,\"channels\":%d,\"transforms\":%d,\"weights\":%d,\"outside_scene\":%d,"
                            "\"inert\":%d,\"camera_path\":%d,\"seconds\":%.6f}\n",
                    a, frames, fa, fps, duration, an->n_channels, tg.n_trs, tg.n_w, tg.outside, tg.inert,
                    path_out != NULL, secs);
        } else {
            fprintf(stderr,
                    "%s: %s: animation %d, %d channels, %.3f s at %g fps: frames %ld-%ld\n"
                    "  per frame: %d set-transform, %d set-weights; %d nodes outside the default scene, %d whose "
                    "transform moves nothing%s\n"
                    "  time: %.3f s\n",
                    prog, scene_path, a, an->n_channels, duration, fps, fa, fb, tg.n_trs, tg.n_w, tg.outside,
                    tg.inert, path_out ? "; camera path written" : "", secs);
        }
    }
done:
    if (rc)
        lie_report_error(prog, &err, 1);
    free(cp.keys);
    free(tg.trs_nodes);
    free(tg.w_nodes);
    lie_pose_destroy(pose);
    lie_scene_destroy(s);
    return rc;
}
