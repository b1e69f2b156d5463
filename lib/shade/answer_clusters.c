/* SPDX-License-Identifier: Apache-2.0 */
/* An emitter of several clusters (lie_cluster) under the LIE: the samples
 * are the emitter's, as ever; each sample's shadow test goes to the pair of
 * the cluster holding its triangle (answer.h).  A dark cluster's samples
 * carry no light: they count as either. */
#include "shade/answer.h"

#include <string.h>

lie_class lie_clusters_classify(const lie_shade_ctx *c, const lie_surface *sf, const lie_emitter *em,
                                lie_shade_scratch *sc, int *unbuilt)
{
    const lie_vis_oracle *vo = c->opt->oracle;
    int all_occ = 1, all_vis = 1;
    for (int j = 0; j < em->n_clusters; j++) {
        const void *pair = NULL;
        if (c->s->clusters[em->first_cluster + j].dark) {
            sc->cluster_class[j] = LIE_CLASS_VISIBLE; /* its samples weigh 0: any answer serves */
            sc->cluster_pair[j] = NULL;
            continue;
        }
        lie_class k = vo->classify(vo->ctx, sf, em->first_cluster + j, &pair);
        if (k == LIE_CLASS_NONE) {
            *unbuilt = 1;
            k = LIE_CLASS_COMPLEX;
        }
        if ((k == LIE_CLASS_COMPLEX && (c->opt->ablate & LIE_ABLATE_FALLBACK)) ||
            (k == LIE_CLASS_PARTIAL && (c->opt->ablate & LIE_ABLATE_BLOCKERS)))
            k = LIE_CLASS_VISIBLE;
        sc->cluster_class[j] = (int)k;
        sc->cluster_pair[j] = pair;
        all_occ &= k == LIE_CLASS_OCCLUDED;
        all_vis &= k == LIE_CLASS_VISIBLE;
    }
    return all_occ ? LIE_CLASS_OCCLUDED : all_vis ? LIE_CLASS_VISIBLE : LIE_CLASS_SPLIT;
}

/* sc->blocked for the query's samples, each by its cluster's pair.  The
 * samples are bucketed by cluster first (sc->idx), so that a partial
 * cluster tests only its own samples against its own list: the segments of
 * its samples are gathered (into the ray batch's direction arrays, free
 * until the Embree pass at the end) and answered in 3D. */
static void clustered_occlusion(const lie_shade_ctx *c, lie_shade_scratch *sc, lie_shadow_query *q, int n,
                                const lie_emitter *em)
{
    const lie_scene *s = c->s;
    const lie_vis_oracle *vo = c->opt->oracle;
    const uint32_t *tri = q->ls->tri;
    const int first = em->first_cluster, nc = em->n_clusters;
    lie_render_stats *st = &sc->stats;
    int at[LIE_CLUSTER_MAX + 1] = {0};
    for (int i = 0; i < n; i++)
        at[s->tri_cluster[tri[i]] - first + 1]++;
    for (int j = 0; j < nc; j++)
        at[j + 1] += at[j];
    int fill[LIE_CLUSTER_MAX];
    memcpy(fill, at, sizeof(int) * (size_t)nc);
    for (int i = 0; i < n; i++)
        sc->idx[fill[s->tri_cluster[tri[i]] - first]++] = i;
    memset(sc->blocked, 0, sizeof *sc->blocked * (size_t)n);
    int any_embree = 0;
    for (int j = 0; j < nc; j++) {
        const int k = sc->cluster_class[j], m = at[j + 1] - at[j];
        const int *ix = sc->idx + at[j];
        if (m == 0)
            continue;
        if (k == LIE_CLASS_OCCLUDED) {
            for (int i = 0; i < m; i++)
                sc->blocked[ix[i]] = ~0u;
            st->pairs_occluded++;
        } else if (k == LIE_CLASS_PARTIAL) {
            int nb = vo->select(vo->ctx, sc->cluster_pair[j], first + j, q->o, q->eps, sc->blockers);
            if (nb == 0)
                continue;
            if (c->opt->exact == LIE_EXACT_AUTO && c->opt->bitmask == LIE_BITMASK_AUTO &&
                lie_cost_embree(m) < lie_cost_samples(m, nb)) {
                sc->cluster_class[j] = LIE_CLASS_COMPLEX; /* never slower than full, as a single pair */
                any_embree = 1;
                continue;
            }
            lie_shadow_query_segments(q);
            float *gx = sc->batch.dx, *gy = sc->batch.dy, *gz = sc->batch.dz;
            for (int i = 0; i < m; i++) {
                gx[i] = q->dx[ix[i]];
                gy[i] = q->dy[ix[i]];
                gz[i] = q->dz[ix[i]];
            }
            lie_shadow_query g = {q->o, q->eps, NULL, m, 1, gx, gy, gz, q->work, q->kind, q->work_stride};
            vo->occluded(vo->ctx, sc->blockers, nb, &g, sc->blocked_part);
            for (int i = 0; i < m; i++)
                sc->blocked[ix[i]] = sc->blocked_part[i];
            st->pairs_blockers++;
        } else if (k == LIE_CLASS_COMPLEX) {
            any_embree = 1;
        }
    }
    if (any_embree) {
        for (int i = 0; i < n; i++)
            sc->blocked_part[i] = sc->cluster_class[s->tri_cluster[tri[i]] - first] == LIE_CLASS_COMPLEX;
        lie_shadow_query_segments(q);
        sc->stats.shadow_rays += (uint64_t)lie_pair_embree(c, q->o, n, sc, sc->blocked_part);
        st->pairs_embree++;
    }
}

static int clusters_applies(const lie_pair *p) { return p->cls == LIE_CLASS_SPLIT; }
static double clusters_cost(const lie_pair *p)
{
    (void)p;
    return LIE_COST_FORCED; /* the only answer that applies */
}

static int clusters_shade(lie_pair *p, float rgb[3])
{
    const lie_light_samples *ls = lie_pair_samples(p, 0);
    int n = lie_pair_kernel(p, ls);
    lie_shadow_query q = lie_pair_query(p, ls, n);
    double t0 = lie_clock_if(p->c->opt->timers);
    clustered_occlusion(p->c, p->sc, &q, n, p->em);
    p->sc->stats.shadow_rays_skipped += (uint64_t)n;
    if (p->c->opt->timers)
        p->sc->stats.t_blockers += lie_time_now() - t0;
    lie_pair_combine(p, p->sc->blocked, 0, n, rgb);
    return 1;
}

const lie_answer lie_answer_clusters = {"clusters", clusters_applies, clusters_cost, clusters_shade};
