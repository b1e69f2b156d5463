/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render's frames on disk (the EXR header's provenance and camera
 * attributes) and its --stats (tools/lie-render/output.h). */
#include "output.h"
#include "common/cli.h"
#include "dist.h"
#include "version/version.h"

#include <math.h>
#include <string.h>
#include <sys/stat.h>

static const char *exact_name(const lie_render_options *o)
{
    return o->exact == LIE_EXACT_ONLY ? "only" : o->exact == LIE_EXACT_OFF ? "off" : "auto";
}

static const char *vis_name(lie_visibility_mode m)
{
    return m == LIE_VIS_FULL ? "full" : m == LIE_VIS_LIE ? "lie" : "none";
}
static const char *rays_name(lie_ray_mode m)
{
    return m == LIE_RAYS_SINGLE ? "single" : m == LIE_RAYS_PACKET ? "packet" : "stream";
}

void frame_name(const frame_out *o, int fi, char *name, size_t size)
{
    if (o->path)
        snprintf(name, size, o->output, o->first + fi);
    else
        snprintf(name, size, "%s", o->output);
}

lie_status write_frame(void *ctx, int fi, const lie_camera *fc, const lie_frame *frame, uint64_t *bytes, lie_error *err)
{
    return write_frame_chunks(ctx, fi, fc, frame, NULL, bytes, err);
}

int frame_chunk_lines(const frame_out *o)
{
    if (o->exposure_auto)
        return 0;
    lie_frame_format f = o->opt.format;
    if (f == LIE_FORMAT_AUTO && !lie_frame_format_of(o->output, &f))
        return 0;
    return f == LIE_FORMAT_EXR ? lie_exr_chunk_lines(o->opt.exr.compression) : 0;
}

double frame_encode_share(const frame_out *o)
{
    /* measured, one core: a 512x512 museum1 frame renders in 0.78 s and
     * its EXR compresses in 0.165 s with zip, 0.039 s with rle (zips and
     * piz are taken as zip) */
    switch (o->opt.exr.compression) {
    case LIE_EXR_NONE: return 0.0;
    case LIE_EXR_RLE: return 0.05;
    default: return 0.2;
    }
}

lie_status encode_chunks(void *ctx, const lie_frame *frame, int first, int count, lie_exr_chunk *out, lie_error *err)
{
    const frame_out *o = ctx;
    return lie_exr_encode_chunks(frame, &o->opt.exr, first, count, out, err);
}

lie_status write_frame_chunks(void *ctx, int fi, const lie_camera *fc, const lie_frame *frame,
                              const lie_exr_chunk *chunks, uint64_t *bytes, lie_error *err)
{
    const frame_out *o = ctx;
    const lie_render_options *ro = o->ro;
    char name[4096];
    int number = o->first + fi;
    frame_name(o, fi, name, sizeof name);
    float yfov_deg = fc->yfov * 180.0f / (float)M_PI;
    char seed[24];
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)ro->seed);
    lie_attr attrs[] = {
        {.name = "software", .type = LIE_ATTR_STRING, .s = "lie-render " LIE_VERSION},
        {.name = "lie.input", .type = LIE_ATTR_STRING, .s = o->input},
        {.name = "lie.sceneHash", .type = LIE_ATTR_STRING, .s = o->hash},
        {.name = "lie.visibility", .type = LIE_ATTR_STRING, .s = vis_name(ro->visibility)},
        {.name = "lie.pattern",
         .type = LIE_ATTR_STRING,
         .s = ro->pattern == LIE_PATTERN_FIXED && ro->sampler == LIE_SAMPLER_PER_EMITTER ? "fixed" : "rotated"},
        {.name = "lie.lightSamples", .type = LIE_ATTR_INT, .i = ro->eye_only ? 0 : ro->light_samples},
        {.name = "lie.lightSampler", .type = LIE_ATTR_STRING, .s = lie_light_sampler_name(ro->sampler)},
        {.name = "lie.seed", .type = LIE_ATTR_STRING, .s = seed},
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
    opt.exr.chunks = chunks;
    /* --exposure auto: the frame's own, said in the file whichever format */
    lie_attr with_auto[sizeof attrs / sizeof attrs[0] + 3];
    char text[160];
    lie_png_text png_text = {"lie.exposure", text};
    if (o->exposure_auto) {
        lie_auto_exposure ae = lie_frame_auto_exposure(frame, LIE_EXPOSURE_KEY);
        *o->last_auto = ae;
        opt.png.exposure = ae.ev;
        lie_auto_exposure_text(&ae, text, sizeof text);
        opt.png.text = &png_text;
        opt.png.n_text = 1;
        memcpy(with_auto, attrs, sizeof attrs);
        int n = (int)(sizeof attrs / sizeof attrs[0]);
        with_auto[n++] = (lie_attr){.name = "lie.exposure", .type = LIE_ATTR_FLOAT, .f = ae.ev};
        with_auto[n++] = (lie_attr){.name = "lie.exposureMode", .type = LIE_ATTR_STRING, .s = "auto"};
        with_auto[n++] = (lie_attr){.name = "lie.logAverageLuminance", .type = LIE_ATTR_FLOAT, .f = (float)ae.log_average};
        opt.exr.attrs = with_auto;
        opt.exr.n_attrs = n;
    }
    lie_status st = lie_frame_write(name, frame, &opt, err);
    struct stat sb;
    if (bytes)
        *bytes = st == LIE_OK && strcmp(name, "-") != 0 && stat(name, &sb) == 0 ? (uint64_t)sb.st_size : 0;
    return st;
}


lie_status print_stats(const lie_cli *cli, const run_stats *r, const lie_scene *scene, const lie_render_options *ro,
                       const lie_render_stats *rs, lie_error *err)
{
    const char *prog = cli->tool;
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
    if (cli->stats == 2) {
        lie_stats_json js;
        FILE *fp = lie_stats_json_begin(&js, prog, input);
        if (!fp)
            return lie_stats_json_end(cli, &js, err);
        fprintf(fp,
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
        fprintf(fp,
                "\"exact\":\"%s\",\"pairs_occluded\":%llu,\"pairs_analytic\":%llu,\"pairs_exact\":%llu,"
                "\"pairs_blockers\":%llu,\"pairs_embree\":%llu,\"pairs_unshadowed\":%llu,"
                "\"exact_overflows\":%llu,\"pairs_unbuilt\":%llu,\"points_unbuilt\":%llu,"
                "\"timers\":%s,\"cpu_seconds_analytic\":%.6f,"
                "\"cpu_seconds_exact\":%.6f,\"cpu_seconds_blockers\":%.6f,\"cpu_seconds_embree\":%.6f,"
                "\"cpu_seconds_sampled_shading\":%.6f,\"pairs_bitmask\":%llu,\"cpu_seconds_bitmask\":%.6f,"
                "\"light_sampler\":\"%s\"",
                exact_name(ro), pairs[0], pairs[1], pairs[2], pairs[3], pairs[4], pairs[5], pairs[6],
                (unsigned long long)rs->pairs_unbuilt, (unsigned long long)rs->points_unbuilt,
                ro->timers ? "true" : "false", rs->t_analytic,
                rs->t_exact, rs->t_blockers, rs->t_embree, rs->t_sampled_shading, pairs[7], rs->t_bitmask,
                lie_light_sampler_name(ro->sampler));
        if (r->exposure)
            fprintf(fp, ",\"exposure_auto\":%.6f,\"log_average_luminance\":%.9g,\"exposure_pixels\":%llu",
                    (double)r->exposure->ev, r->exposure->log_average, (unsigned long long)r->exposure->pixels);
        render_dist_stats(fp, 1);
        fprintf(fp, "}\n");
        return lie_stats_json_end(cli, &js, err);
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
                "    %llu seen whole and sampled, %llu partial as bitmasks;\n"
                "    %llu exact pairs fell back to samples; light sampler %s\n",
                exact_name(ro), pairs[0], pairs[1], pairs[2], pairs[3], pairs[4], pairs[5], pairs[7], pairs[6],
                lie_light_sampler_name(ro->sampler));
        if (rs->pairs_unbuilt)
            fprintf(stderr, "  not built in the cache (outside its views, or left by the cost model): %llu pairs at "
                            "%llu shading points, answered by Embree\n",
                    (unsigned long long)rs->pairs_unbuilt, (unsigned long long)rs->points_unbuilt);
        if (ro->timers)
            fprintf(stderr,
                    "  worker seconds: closed form %.3f, exact shadows %.3f, blocker samples %.3f,\n"
                    "    Embree %.3f, sampled shading %.3f, bitmasks %.3f\n",
                    rs->t_analytic, rs->t_exact, rs->t_blockers, rs->t_embree, rs->t_sampled_shading, rs->t_bitmask);
        if (r->exposure)
            fprintf(stderr, "  exposure auto: %.3f stops (log-average luminance %.6g over %llu pixels, key %.2f%s)\n",
                    (double)r->exposure->ev, r->exposure->log_average, (unsigned long long)r->exposure->pixels,
                    (double)r->exposure->key, rendered > 1 ? "; the last frame's" : "");
        render_dist_stats(stderr, 0);
    }
    return LIE_OK;
}
