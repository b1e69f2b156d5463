/* lie-build --stats and --stats=json (tools/lie-build/job.h). */
#include "dist.h"
#include "job.h"

#include <stdio.h>

void job_print_stats(const char *prog, const build_job *j, double cpu_build, const double t[4], int json)
{
    const char *input = j->input;
    const lie_scene *s = j->scene;
    const lie_env *env = j->env;
    const lie_build_stats *st = &j->st;
    const lie_add_stats *as = j->into ? &j->as : NULL;
    lie_prediction prediction;
    const lie_prediction *pred = NULL;
    if (j->px) {
        lie_env_predict(env, j->px, &prediction);
        pred = &prediction;
    }
    double t_load = t[0], t_bvh = t[1], t_build = t[2], t_write = t[3];
    size_t bytes = j->bytes;

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
