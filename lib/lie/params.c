/* SPDX-License-Identifier: Apache-2.0 */
/* Build parameters, class names and statistics of local illumination
 * environments (lib/lie/lie.h). */
#include "lie/internal.h"

#include <string.h>

const char *lie_class_name(lie_class c)
{
    static const char *const names[LIE_CLASS_COUNT] = {"unlit",   "visible", "occluded", "partial",
                                                       "complex", "split",   "none"};
    return (unsigned)c < LIE_CLASS_COUNT ? names[c] : "invalid";
}

lie_build_params lie_build_params_default(void)
{
    return (lie_build_params){
        .samples = LIE_SAMPLES_DEFAULT,
        .max_samples = LIE_MAX_SAMPLES_DEFAULT,
        .max_blockers = LIE_MAX_BLOCKERS_DEFAULT,
        .complex_cap = LIE_COMPLEX_CAP_DEFAULT,
        .min_patch = LIE_MIN_PATCH_DEFAULT,
        .split_gain = LIE_SPLIT_GAIN_DEFAULT,
        .mode = LIE_BLOCKERS_SAMPLED,
        .complex_predict = LIE_COMPLEX_PREDICT_DEFAULT,
        .frames = LIE_FRAMES_DEFAULT,
        .light_samples = LIE_MODEL_LIGHT_SAMPLES_DEFAULT,
        .ns_segment = LIE_NS_SEGMENT_DEFAULT,
        .ns_blocker = LIE_NS_BLOCKER_DEFAULT,
        .ns_ray = LIE_NS_RAY_DEFAULT,
        .whole_pixels = LIE_WHOLE_PIXELS_DEFAULT,
    };
}

lie_status lie_build_params_check(const lie_build_params *p, lie_error *err)
{
    if (p->samples < 1 || p->samples > (1u << 20))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "samples must be in 1..%u", 1u << 20);
    if (p->max_samples < p->samples || p->max_samples > (1u << 24))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "max-samples must be in samples..%u", 1u << 24);
    if (p->max_blockers > (1u << 20) || p->complex_cap > (1u << 24))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "max-blockers or complex-cap too large");
    if (!(p->min_patch >= LIE_MIN_PATCH_MIN) || !(p->min_patch <= 1.0f))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "min-patch must be in [%g, 1]", (double)LIE_MIN_PATCH_MIN);
    if (!(p->split_gain >= 0.0f) || !(p->split_gain < 1.0f))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "split-gain must be in [0, 1)");
    if (p->frames > (1u << 24) || p->light_samples < 1 || p->light_samples > (1u << 24))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "frames must be in 0..%u, light-samples in 1..%u", 1u << 24, 1u << 24);
    if (!(p->ns_segment > 0.0f && p->ns_segment <= 1e9f) || !(p->ns_blocker > 0.0f && p->ns_blocker <= 1e9f) ||
        !(p->ns_ray > 0.0f && p->ns_ray <= 1e9f))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "the cost model's times must be in (0, 1e9] ns");
    if (p->whole_pixels > (1u << 28))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "whole-pixels must be in 0..%u", 1u << 28);
    if (p->complex_predict > 1)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "complex-predict must be 0 or 1");
    if (p->mode != LIE_BLOCKERS_SAMPLED && p->mode != LIE_BLOCKERS_CONSERVATIVE)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "unknown blocker mode");
    return LIE_OK;
}

void lie_stats_hist_add(lie_build_stats *st, uint32_t n)
{
    int b = 0;
    while (b < 17 && n > (1u << b))
        b++;
    st->list_hist[b]++;
}

void lie_build_stats_add(lie_build_stats *a, const lie_build_stats *b) { lie_stats_merge(a, b); }

void lie_stats_merge(lie_build_stats *dst, const lie_build_stats *src)
{
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        dst->pairs[k] += src->pairs[k];
    for (int k = 0; k <= LIE_PATCH_MAX_DEPTH; k++)
        dst->patches_per_depth[k] += src->patches_per_depth[k];
    for (int k = 0; k < 18; k++)
        dst->list_hist[k] += src->list_hist[k];
    dst->segments += src->segments;
    dst->blocker_total += src->blocker_total;
    dst->splits_undone += src->splits_undone;
    dst->units_copied += src->units_copied;
    dst->units_interrupted += src->units_interrupted;
    dst->units_unseen += src->units_unseen;
    dst->units_unpaid += src->units_unpaid;
    dst->splits_pixels += src->splits_pixels;
    dst->splits_kept += src->splits_kept;
    dst->unproven_occluded += src->unproven_occluded;
    dst->unproven_visible += src->unproven_visible;
    dst->complex_predicted += src->complex_predicted;
    dst->complex_measured += src->complex_measured;
    dst->complex_predicted_measured += src->complex_predicted_measured;
    dst->split_saving_predicted_ns += src->split_saving_predicted_ns;
    dst->split_saving_measured_ns += src->split_saving_measured_ns;
    dst->frame_saving_ns += src->frame_saving_ns;
}

static void stats_walk(const lie_env *env, uint32_t idx, int depth, lie_build_stats *st)
{
    const lie_pnode *x = &env->nodes[idx];
    st->patches_per_depth[depth < LIE_PATCH_MAX_DEPTH ? depth : LIE_PATCH_MAX_DEPTH]++;
    if (x->child) {
        for (uint32_t k = 0; k < 4; k++)
            stats_walk(env, x->child + k, depth + 1, st);
        return;
    }
    st->pairs[x->cls < LIE_CLASS_COUNT ? x->cls : LIE_CLASS_COMPLEX]++;
    st->segments += x->quality;
    if (x->cls == LIE_CLASS_PARTIAL) {
        st->blocker_total += x->count;
        lie_stats_hist_add(st, x->count);
    }
}

void lie_env_stats(const lie_env *env, lie_build_stats *stats)
{
    memset(stats, 0, sizeof *stats);
    size_t n = (size_t)env->n_tris * (size_t)env->n_clusters;
    for (size_t u = 0; u < n; u++)
        stats_walk(env, env->root[u], 0, stats);
}
