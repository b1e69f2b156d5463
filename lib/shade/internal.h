/* Private to lib/shade: per-worker scratch and the direct-lighting entry. */
#ifndef LIE_SHADE_INTERNAL_H
#define LIE_SHADE_INTERNAL_H

#include "shade/polylight.h"
#include "shade/shade.h"

/* Per-worker buffers, sized once for the largest sample count, so the
 * per-pixel path allocates nothing (CONTRIBUTING.md, Hot paths). */
typedef struct lie_shade_scratch {
    _Alignas(128) int cap; /* one per worker, on its own cache lines: no false sharing */
    float *wr, *wg, *wb;       /* unshadowed contribution per sample */
    int scalar;                /* 1: wr holds a scalar weight, colour is `scale` */
    float scale[3];
    float *dx, *dy, *dz, *dist;
    uint32_t *occ;             /* per sample: ~0 blocked, 0 free */
    uint32_t *occ2;            /* the same, for one cluster's blockers */
    /* per cluster of the emitter at hand (lie_cluster) */
    int ccls[LIE_CLUSTER_MAX];
    const void *cpair[LIE_CLUSTER_MAX];
    uint32_t *blockers;        /* the oracle's selected blockers */
    float *bwork;              /* lie_shadow_query.work */
    uint32_t *bkind;
    size_t bstride;
    int *idx;                  /* batch slot -> sample */
    lie_ray_batch batch;
    lie_light_samples rotated; /* --pattern rotated: this point's samples */
    lie_polylight_work poly;   /* closed-form shading's pieces */
    lie_render_stats stats;
} lie_shade_scratch;

lie_status lie_shade_scratch_init(lie_shade_scratch *sc, int cap, int max_blockers);
void lie_shade_scratch_free(lie_shade_scratch *sc);

typedef struct lie_shade_ctx {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_render_options *opt;
    const lie_light_samples *fixed; /* one per emitter (fixed pattern) */
    float ray_far;                  /* shadow ray length toward directional lights */
    lie_polylight **poly;           /* per emitter, NULL where the closed form does not serve */
    int analytic;                   /* this frame shades Lambert receivers of poly[e] in closed form */
    int exact;                      /* ... and answers their partial pairs by back-projection */
} lie_shade_ctx;

/* Per triangle, the instance it belongs to if that instance is a closed
 * convex mesh with every light outside it (solids.c), else -1; NULL when
 * out of memory. */
int32_t *lie_solids_find(const lie_scene *s);

/* Direct lighting at sf from every emitter, added to rgb.  `pixel` seeds the
 * rotated pattern. */
void lie_shade_direct(const lie_shade_ctx *c, const lie_surface *sf, uint64_t pixel, int depth,
                      lie_shade_scratch *sc, float rgb[3]);

#endif
