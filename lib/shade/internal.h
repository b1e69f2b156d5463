/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/shade: per-worker scratch and the direct-lighting entry. */
#ifndef LIE_SHADE_INTERNAL_H
#define LIE_SHADE_INTERNAL_H

#include "shade/bitmask.h"
#include "shade/cost.h"
#include "shade/sampler.h"
#include "shade/texlight.h"
#include "shade/polylight.h"
#include "shade/shade.h"

#include "core/hot.h"

/* Eight partial sums added pairwise, in one fixed order (the shading
 * sums' last step, so every path rounds alike).  The sums keep eight lanes
 * whatever the vector width (8 floats in one AVX register, two SSE ones):
 * the baseline code and the AVX2 copies of lib/core/hot.h add in the same
 * order. */
static inline float lie_sum8(const float l[8]) { return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7])); }

/* Per-worker buffers, sized once for the largest sample count, so the
 * per-pixel path allocates nothing (CONTRIBUTING.md, Hot paths). */
typedef struct lie_shade_scratch {
    _Alignas(128) int cap; /* one per worker, on its own cache lines: no false sharing */
    float *contrib_r, *contrib_g, *contrib_b; /* unshadowed contribution per sample */
    int scalar;                /* 1: contrib_r holds a scalar weight, colour is `scale` */
    float scale[3];
    float *dx, *dy, *dz, *dist;
    uint32_t *blocked;         /* per sample: ~0 blocked, 0 free */
    uint32_t *blocked_part;    /* the same, for one cluster's samples against its blockers */
    /* per cluster of the emitter at hand (lie_cluster): its pair's class and pair */
    int cluster_class[LIE_CLUSTER_MAX];
    const void *cluster_pair[LIE_CLUSTER_MAX];
    uint64_t *mask;            /* the same as bits (bitmask.h) */
    uint32_t *blockers;        /* the oracle's selected blockers */
    float *blocker_work;       /* lie_shadow_query.work, .kind and .work_stride */
    uint32_t *blocker_kind;
    size_t blocker_stride;
    int *idx;                  /* batch slot -> sample */
    lie_ray_batch batch;
    lie_light_samples rotated; /* --pattern rotated: this point's samples */
    lie_polylight_work poly;   /* closed-form shading's pieces */
    /* the budgeted samplers' per-point lists, one entry per emitter at most */
    lie_light_pick *picks;
    float *weights;
    int *ids;
    uint8_t *by_tree;   /* per emitter: its pairs at this point go to the light tree (shade_guided) */
    int depth;                 /* the mirror bounce of the point at hand */
    lie_render_stats stats;
} lie_shade_scratch;

/* A Lambert receiver's geometric term toward a planar emitter of one
 * radiance, per sample (s, t): d = w + s u + t v (w = po - o), the
 * receiver's cosines are linear forms in (s, t), the emitter's cosine one
 * number ce, and G = (n.d) ce / |d|^4 (zero below either tangent plane).
 * One function for the per-sample kernel (direct.c) and the bitmask sums
 * (bitmask.c), so both weigh a sample alike. */
typedef struct lie_planar_lambert {
    float wx, wy, wz, ux, uy, uz, vx, vy, vz;
    float r0, ru, rv; /* shading normal . d */
    float g0, gu, gv; /* geometric normal . d */
    float ce;         /* the emitter's cosine times |d| */
} lie_planar_lambert;

static inline float lie_planar_lambert_g(lie_planar_lambert P, float s, float t)
{
    float dx = fmaf(t, P.vx, fmaf(s, P.ux, P.wx)), dy = fmaf(t, P.vy, fmaf(s, P.uy, P.wy)),
          dz = fmaf(t, P.vz, fmaf(s, P.uz, P.wz));
    float d2 = fmaf(dz, dz, fmaf(dy, dy, dx * dx));
    float cr = fmaf(t, P.rv, fmaf(s, P.ru, P.r0));
    float cg = fmaf(t, P.gv, fmaf(s, P.gu, P.g0));
    float inv = 1.0f / d2;
    float G = (cr * P.ce) * (inv * inv);
    int ok = (cr > 0.0f) & (cg > 0.0f) & (d2 > 0.0f);
    return ok ? G : 0.0f;
}

/* The term's set-up from o (the lifted surface point) with shading normal
 * n and geometric normal ng; 0 when o is behind the emitter (nothing lit). */
static inline int lie_planar_lambert_setup(const lie_light_samples *ls, lie_vec3 o, lie_vec3 n, lie_vec3 ng,
                                           int two_sided, lie_planar_lambert *P)
{
    const float sgn = two_sided ? -1.0f : 1.0f; /* two-sided: |cos| via max(c, -c) */
    P->wx = ls->po[0] - o.x, P->wy = ls->po[1] - o.y, P->wz = ls->po[2] - o.z;
    P->ux = ls->pu[0], P->uy = ls->pu[1], P->uz = ls->pu[2];
    P->vx = ls->pv[0], P->vy = ls->pv[1], P->vz = ls->pv[2];
    float ce = -(ls->pn[0] * P->wx + ls->pn[1] * P->wy + ls->pn[2] * P->wz);
    P->ce = ce > sgn * ce ? ce : sgn * ce;
    P->r0 = n.x * P->wx + n.y * P->wy + n.z * P->wz;
    P->ru = n.x * P->ux + n.y * P->uy + n.z * P->uz;
    P->rv = n.x * P->vx + n.y * P->vy + n.z * P->vz;
    P->g0 = ng.x * P->wx + ng.y * P->wy + ng.z * P->wz;
    P->gu = ng.x * P->ux + ng.y * P->uy + ng.z * P->uz;
    P->gv = ng.x * P->vx + ng.y * P->vy + ng.z * P->vz;
    return P->ce > 0.0f;
}

/* lie_light_samples_generate, the points drawn by the emitter's texture
 * (tl; NULL: by area). */
void lie_light_samples_generate_with(const lie_scene *s, int e, int n, float su, float sv, const lie_texlight *tl,
                                     lie_light_samples *out);
/* The same over light group j (not whole) of G, its emitter's
 * distribution tl (NULL: by area, or by solid angle from o where o, may be
 * NULL, is near: lie_light_group_sample). */
void lie_light_samples_generate_group(const lie_scene *s, const lie_light_groups *G, int j, int n, float su, float sv,
                                      const lie_texlight *tl, const lie_vec3 *o, lie_light_samples *out);

lie_status lie_shade_scratch_init(lie_shade_scratch *sc, int cap, int max_blockers, int n_emitters);
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
    lie_bitmask **bits;             /* per emitter, NULL where partial pairs are not answered as bitmasks */
    int sampler_on;                 /* a budgeted sampler (not LIE_SAMPLER_PER_EMITTER) */
    lie_light_sampler sampler;      /* ... and it */
    const lie_light_bounds *bounds; /* per emitter (sampler.h) */
    int guided;                     /* the LIE's classes share the budget (lie_shade_direct) */
    /* Delta lights apart from the budget: when there are at most n of
     * them, each takes its one sample at every point (no selection can do
     * better than a sample that is exact), and the sampler shares the n
     * samples among the other emitters alone. */
    const int *delta_ids;
    int n_delta_apart;
    lie_texlight **texlights;       /* per emitter, NULL where its texture does not guide its samples */
    lie_light_groups *groups;       /* what the sampler chooses among (sampler.h) */
    int borrowed_tex, borrowed_poly, borrowed_groups; /* opt->lights', not the frame's to free */
    /* The scene has transmissive surfaces (lie_rt_transmits) and shadows
     * are on: each sample's light is multiplied by the transmittance of its
     * shadow segment (lie_rt_transmittance), and the closed forms, exact
     * shadows and bitmasks, which integrate without samples or in another
     * sample order, stand aside. */
    int transmit;
} lie_shade_ctx;

struct lie_lights {
    uint64_t hash; /* the scene's content hash it was made for */
    int n_emitters;
    lie_texlight **texlights; /* per emitter (lie_texlight_create_all); NULL for the per-emitter sampler */
    lie_polylight **poly;     /* per emitter (lie_polylight_create); NULL where closed forms are off */
    lie_light_groups *groups; /* with texlights */
};

/* Per triangle, the instance it belongs to if that instance is a closed
 * convex mesh with every light outside it (solids.c), else -1; NULL when
 * out of memory. */
int32_t *lie_solids_find(const lie_scene *s);

/* Direct lighting at sf from every emitter, added to rgb.  `pixel` (the
 * pixel's index, and the eye sample's above bit 40) seeds the rotated
 * patterns. */
void lie_shade_direct(const lie_shade_ctx *c, const lie_surface *sf, uint64_t pixel, int depth,
                      lie_shade_scratch *sc, float rgb[3]);

#endif
