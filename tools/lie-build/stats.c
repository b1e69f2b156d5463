/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build --stats and --stats=json (tools/lie-build/job.h). */
#include "common/cli.h"
#include "dist.h"
#include "job.h"

#include <math.h>
#include <stdio.h>

/* What both forms print, gathered once. */
typedef struct summary {
    const char *input;
    const lie_scene *s;
    const lie_env *env;
    const lie_build_stats *st;
    const lie_add_stats *as;      /* --into's, or NULL */
    const lie_prediction *pred;   /* with views, or NULL */
    double t[4], cpu_build;       /* load, bvh, build, write; the build's CPU time */
    uint64_t leaves, patches;
    double mean;                  /* mean list length */
    /* the model against the build: its build time (segments only) against
     * the CPU time the build took; the render time the splits save per
     * frame, predicted before each lookahead and as the children's lists
     * gave it; and one frame of the views, with full visibility and with
     * this cache (CPU seconds over all threads; bench/build.sh renders them) */
    double model_build, sp, sm;
    /* with views: what a frame of them saves (full visibility's shadow CPU
     * time less the cache's) and the frames the build takes to pay back */
    double saving, break_even;
    /* a whole build's model (lie_whole_pixels): the pixels of its assumed
     * frames; what one of them saves, predicted, and the break-even */
    uint32_t whole_pixels;
    size_t bytes;
    int audit;                    /* --complex-predict audit */
} summary;

static void print_json(FILE *fp, const summary *m)
{
    fprintf(fp, ",\"triangles\":%u,\"emitters\":%d,\"clusters\":%d,\"units\":%llu,"
                    "\"patches\":%llu,\"leaf_pairs\":%llu,\"pairs\":{",
            m->s->n_tris, m->s->n_emitters, m->s->n_clusters, (unsigned long long)m->s->n_tris * (unsigned long long)m->s->n_clusters,
            (unsigned long long)m->patches, (unsigned long long)m->leaves);
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        if (k != LIE_CLASS_SPLIT)
            fprintf(fp, "%s\"%s\":%llu", k ? "," : "", lie_class_name((lie_class)k),
                    (unsigned long long)m->st->pairs[k]);
    fprintf(fp, "},\"patches_per_depth\":[");
    int maxd = 0;
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        if (m->st->patches_per_depth[d])
            maxd = d;
    for (int d = 0; d <= maxd; d++)
        fprintf(fp, "%s%llu", d ? "," : "", (unsigned long long)m->st->patches_per_depth[d]);
    fprintf(fp, "],\"list_histogram\":[");
    for (int b = 0; b < 18; b++)
        fprintf(fp, "%s%llu", b ? "," : "", (unsigned long long)m->st->list_hist[b]);
    fprintf(fp,
            "],\"mean_list_length\":%.3f,\"segments\":%llu,\"splits_undone\":%llu,\"splits_kept\":%llu,"
            "\"splits_pixels\":%llu,\"unproven_occluded\":%llu,\"unproven_visible\":%llu,\"nodes\":%llu,"
            "\"nodes_stored\":%u,\"pool\":%u,"
            "\"seconds_load\":%.6f,\"seconds_bvh\":%.6f,\"seconds_build\":%.6f,\"seconds_write\":%.6f,"
            "\"bytes\":%zu",
            m->mean, (unsigned long long)m->st->segments, (unsigned long long)m->st->splits_undone,
            (unsigned long long)m->st->splits_kept, (unsigned long long)m->st->splits_pixels,
            (unsigned long long)m->st->unproven_occluded, (unsigned long long)m->st->unproven_visible,
            (unsigned long long)m->patches, m->env->n_nodes, m->env->n_pool, m->t[0], m->t[1], m->t[2], m->t[3],
            m->bytes);
    fprintf(fp, ",\"complex_units\":{\"predict\":\"%s\",\"predicted\":%llu,\"measured\":%llu",
            m->env->params.complex_predict ? "on" : m->audit ? "audit" : "off",
            (unsigned long long)m->st->complex_predicted, (unsigned long long)m->st->complex_measured);
    if (m->audit)
        fprintf(fp, ",\"predicted_and_measured\":%llu", (unsigned long long)m->st->complex_predicted_measured);
    fprintf(fp, "}");
    fprintf(fp, ",\"model\":{\"build_cpu_s_predicted\":%.6f,\"build_cpu_s_measured\":%.6f", m->model_build,
            m->cpu_build);
    if (m->pred)
        fprintf(fp,
                ",\"split_saving_s_predicted\":%.6f,\"split_saving_s_measured\":%.6f,\"view_pixels\":%.0f,"
                "\"frame_shadow_cpu_s_full\":%.6f,\"frame_shadow_cpu_s_lie\":%.6f,\"frame_full_rays\":%.0f,"
                "\"frame_list_entries\":%.0f,\"frame_lie_rays\":%.0f",
                m->sp, m->sm, m->pred->pixels, 1e-9 * m->pred->full_ns, 1e-9 * m->pred->lie_ns, m->pred->full_rays,
                m->pred->list_entries, m->pred->env_rays);
    if (m->pred)
        fprintf(fp, ",\"units_unseen\":%llu,\"units_unpaid\":%llu,\"saving_s_per_frame_predicted\":%.6f,"
                    "\"break_even_frames_predicted\":%.3f",
                (unsigned long long)m->st->units_unseen, (unsigned long long)m->st->units_unpaid, m->saving,
                isfinite(m->break_even) ? m->break_even : -1.0);
    if (m->whole_pixels)
        fprintf(fp, ",\"whole_pixels\":%u,\"units_unpaid\":%llu,\"saving_s_per_frame_predicted\":%.6f,"
                    "\"break_even_frames_predicted\":%.3f",
                m->whole_pixels, (unsigned long long)m->st->units_unpaid, m->saving,
                isfinite(m->break_even) ? m->break_even : -1.0);
    fprintf(fp, "}");
    fprintf(fp,
            ",\"partial\":%s,\"units_copied\":%llu,\"units_interrupted\":%llu,\"workers\":%d,\"seconds_cpu\":%.6f,"
            "\"seconds_cpu_workers\":%.6f,\"seconds_cpu_worker_max\":%.6f,\"seconds_tail\":%.6f",
            m->env->partial ? "true" : "false", (unsigned long long)m->st->units_copied,
            (unsigned long long)m->st->units_interrupted, m->st->workers, lie_cpu_time(), m->st->seconds_cpu_sum,
            m->st->seconds_cpu_max, m->st->seconds_tail);
    if (m->as)
        fprintf(fp, ",\"into\":{\"units_kept\":%llu,\"units_refined\":%llu,\"units_new\":%llu,"
                        "\"nodes_recomputed\":%llu}",
                (unsigned long long)m->as->units_kept, (unsigned long long)m->as->units_refined,
                (unsigned long long)m->as->units_new, (unsigned long long)m->as->nodes_flagged);
    lie_dist_stats_print(fp, "units", 1);
    fprintf(fp, "}\n");
}

static void print_text(const char *prog, const summary *m)
{
    fprintf(stderr, "%s: %s: %u triangles, %d emitters in %d clusters, %llu units\n", prog, m->input, m->s->n_tris,
            m->s->n_emitters, m->s->n_clusters, (unsigned long long)m->s->n_tris * (unsigned long long)m->s->n_clusters);
    fprintf(stderr, "  pairs:");
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        if (k != LIE_CLASS_SPLIT)
            fprintf(stderr, " %s %llu (%.1f%%)", lie_class_name((lie_class)k), (unsigned long long)m->st->pairs[k],
                    m->leaves ? 100.0 * (double)m->st->pairs[k] / (double)m->leaves : 0.0);
    fprintf(stderr, "\n  patches per depth:");
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        if (m->st->patches_per_depth[d])
            fprintf(stderr, " %d:%llu", d, (unsigned long long)m->st->patches_per_depth[d]);
    fprintf(stderr, "\n  blocker lists: mean %.2f; lengths", m->mean);
    for (int b = 0; b < 18; b++)
        if (m->st->list_hist[b]) {
            unsigned lo = b == 0 ? 1 : (1u << (b - 1)) + 1, hi = 1u << b;
            if (lo == hi)
                fprintf(stderr, " %u:%llu", lo, (unsigned long long)m->st->list_hist[b]);
            else
                fprintf(stderr, " %u-%u:%llu", lo, hi, (unsigned long long)m->st->list_hist[b]);
        }
    fprintf(stderr, "\n  segments cast %llu; splits kept %llu, undone (did not shorten lists) %llu, not tried "
                    "(too few pixels) %llu; %llu nodes (%u stored: lone units share theirs), %u pooled blockers, %zu bytes "
            "written\n",
            (unsigned long long)m->st->segments, (unsigned long long)m->st->splits_kept,
            (unsigned long long)m->st->splits_undone, (unsigned long long)m->st->splits_pixels,
            (unsigned long long)m->patches, m->env->n_nodes, m->env->n_pool, m->bytes);
    if (m->env->params.complex_predict)
        fprintf(stderr, "  complex units: %llu predicted and left one complex leaf each (Embree answers them); "
                        "%llu built that came out complex throughout (missed)\n",
                (unsigned long long)m->st->complex_predicted, (unsigned long long)m->st->complex_measured);
    else if (m->audit)
        fprintf(stderr, "  complex units (audit: built anyway): %llu predicted, %llu came out complex "
                        "throughout, %llu of them predicted\n",
                (unsigned long long)m->st->complex_predicted, (unsigned long long)m->st->complex_measured,
                (unsigned long long)m->st->complex_predicted_measured);
    if (m->st->unproven_occluded || m->st->unproven_visible)
        fprintf(stderr, "  sampled leaves not proven, given exact lists: %llu called occluded, %llu visible\n",
                (unsigned long long)m->st->unproven_occluded, (unsigned long long)m->st->unproven_visible);
    fprintf(stderr, "  time: load %.3f s, bvh %.3f s, build %.3f s, write %.3f s\n", m->t[0], m->t[1], m->t[2],
            m->t[3]);
    fprintf(stderr, "  cpu: %.3f s in all; the build's %d workers %.3f s, the busiest %.3f s, cores idle for the "
                    "last %.3f s\n", lie_cpu_time(), m->st->workers, m->st->seconds_cpu_sum, m->st->seconds_cpu_max,
            m->st->seconds_tail);
    if (m->st->units_copied || m->st->units_interrupted || m->env->partial)
        fprintf(stderr, "  units: %llu copied from the resumed cache, %llu left unbuilt by an interruption%s\n",
                (unsigned long long)m->st->units_copied, (unsigned long long)m->st->units_interrupted,
                m->env->partial ? " (the cache is partial)" : "");
    fprintf(stderr, "  model: build %.3f CPU s predicted, %.3f measured", m->model_build, m->cpu_build);
    if (m->pred)
        fprintf(stderr, "; splits save %.4f s a frame predicted, %.4f by their lists; a frame of the views "
                        "(%.0f pixels) costs %.3f shadow CPU s with full visibility, %.3f with this cache",
                m->sp, m->sm, m->pred->pixels, 1e-9 * m->pred->full_ns, 1e-9 * m->pred->lie_ns);
    fprintf(stderr, "\n");
    if (m->pred)
        fprintf(stderr, "  units left to Embree: %llu unseen, %llu whose light cannot pay for a build; a frame "
                        "saves %.4f CPU s predicted, the build pays back in %.1f frames\n",
                (unsigned long long)m->st->units_unseen, (unsigned long long)m->st->units_unpaid, m->saving,
                m->break_even);
    if (m->whole_pixels)
        fprintf(stderr, "  units left to Embree: %llu whose light cannot pay for a build in frames of %u pixels "
                        "spread over the surface by area; such a frame saves %.4f CPU s predicted, the build "
                        "pays back in %.1f frames\n",
                (unsigned long long)m->st->units_unpaid, m->whole_pixels, m->saving, m->break_even);
    if (m->as)
        fprintf(stderr, "  into: %llu units kept, %llu refined, %llu new; %llu nodes recomputed\n",
                (unsigned long long)m->as->units_kept, (unsigned long long)m->as->units_refined,
                (unsigned long long)m->as->units_new, (unsigned long long)m->as->nodes_flagged);
    lie_dist_stats_print(stderr, "units", 0);
}

lie_status job_print_stats(const lie_cli *cli, build_job *j, double cpu_build, const double t[4])
{
    const char *prog = cli->tool;
    const lie_build_stats *st = &j->st;
    lie_prediction prediction;
    summary m = {.input = j->input, .s = j->scene, .env = j->env, .st = st, .as = j->into ? &j->as : NULL,
                 .t = {t[0], t[1], t[2], t[3]}, .cpu_build = cpu_build, .bytes = j->bytes,
                 .audit = j->audit_complex && !j->bp.complex_predict};
    if (j->px) {
        lie_env_predict(j->env, j->scene, j->px, &prediction);
        m.pred = &prediction;
    }
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        m.leaves += st->pairs[k];
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        m.patches += st->patches_per_depth[d];
    m.mean = st->pairs[LIE_CLASS_PARTIAL] ? (double)st->blocker_total / (double)st->pairs[LIE_CLASS_PARTIAL] : 0.0;
    m.model_build = 1e-9 * (double)st->segments * (double)j->env->params.ns_segment;
    const lie_build_params *bp = &j->env->params;
    if (!j->px && !j->into && bp->frames && bp->whole_pixels) {
        m.whole_pixels = bp->whole_pixels;
        m.saving = 1e-9 * st->frame_saving_ns;
    }
    if (m.pred)
        m.saving = 1e-9 * (prediction.full_ns - prediction.lie_ns);
    if (m.pred || m.whole_pixels)
        m.break_even = m.saving > 0.0 ? m.model_build / m.saving : INFINITY;
    m.sp = 1e-9 * st->split_saving_predicted_ns;
    m.sm = 1e-9 * st->split_saving_measured_ns;
    if (cli->stats == 2) {
        lie_stats_json js;
        FILE *fp = lie_stats_json_begin(&js, prog, j->input);
        if (fp)
            print_json(fp, &m);
        return lie_stats_json_end(cli, &js, &j->err);
    }
    print_text(prog, &m);
    return LIE_OK;
}
