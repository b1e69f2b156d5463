/* SPDX-License-Identifier: Apache-2.0 */
/* Screen pixels per patch (§4.3.3: the constructor picks patches "in
 * proportion to the number of pixels the patch occupies on the screen"),
 * and the cost model that turns them into subdivision decisions and into
 * predictions a build can be checked against (lib/lie/lie.h). */
#include "lie/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Level k + 1's digit in bits 2 (LIE_PIXEL_LEVELS - 1 - k): a patch's hits
 * are then one contiguous range of a triangle's sorted keys. */
uint32_t lie_pixels_key(float b1, float b2)
{
    uint32_t key = 0;
    for (int k = 0; k < LIE_PIXEL_LEVELS; k++)
        key |= (uint32_t)lie_patch_descend(&b1, &b2) << (2 * (LIE_PIXEL_LEVELS - 1 - k));
    return key;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

lie_status lie_pixels_create(uint32_t n_tris, uint32_t rays_per_pixel, uint64_t *hits, size_t n_hits,
                             lie_pixels **out, lie_error *err)
{
    *out = NULL;
    if (rays_per_pixel < 1)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "pixels: rays per pixel must be at least 1");
    for (size_t i = 0; i < n_hits; i++)
        if ((hits[i] >> 32) >= n_tris)
            return lie_error_set(err, LIE_ERR_ARG, NULL, "pixels: hit on triangle %llu of %u",
                                 (unsigned long long)(hits[i] >> 32), n_tris);
    lie_pixels *px = calloc(1, sizeof *px);
    if (px) {
        px->first = calloc((size_t)n_tris + 1, sizeof *px->first);
        px->key = malloc(sizeof *px->key * (n_hits + 1));
    }
    if (!px || !px->first || !px->key) {
        lie_pixels_destroy(px);
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory for %zu pixel hits", n_hits);
    }
    px->n_tris = n_tris;
    px->rays_per_pixel = rays_per_pixel;
    px->n_hits = n_hits;
    qsort(hits, n_hits, sizeof *hits, cmp_u64); /* by triangle, then key: independent of the hit order */
    for (size_t i = 0; i < n_hits; i++) {
        px->key[i] = (uint32_t)hits[i];
        px->first[(hits[i] >> 32) + 1]++;
    }
    for (uint32_t t = 0; t < n_tris; t++)
        px->first[t + 1] += px->first[t];
    *out = px;
    return LIE_OK;
}

lie_status lie_pixels_merge(const lie_pixels *a, const lie_pixels *b, lie_pixels **out, lie_error *err)
{
    *out = NULL;
    if (a->n_tris != b->n_tris || a->rays_per_pixel != b->rays_per_pixel)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "pixels: merging views of different scenes or samplings");
    size_t n = (size_t)(a->n_hits + b->n_hits);
    uint64_t *hits = malloc(sizeof *hits * (n + 1));
    if (!hits)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory for %zu pixel hits", n);
    size_t k = 0;
    for (int i = 0; i < 2; i++) {
        const lie_pixels *p = i ? b : a;
        for (uint32_t t = 0; t < p->n_tris; t++)
            for (uint64_t h = p->first[t]; h < p->first[t + 1]; h++)
                hits[k++] = (uint64_t)t << 32 | p->key[h];
    }
    lie_status st = lie_pixels_create(a->n_tris, a->rays_per_pixel, hits, n, out, err);
    free(hits);
    return st;
}

void lie_pixels_destroy(lie_pixels *px)
{
    if (!px)
        return;
    free(px->first);
    free(px->key);
    free(px);
}

/* The first of keys[0..n) not below k. */
static size_t lower_bound(const uint32_t *keys, size_t n, uint64_t k)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if ((uint64_t)keys[mid] < k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

uint64_t lie_pixels_hits(const lie_pixels *px, uint32_t tri, lie_patch_path path)
{
    if (!px || tri >= px->n_tris)
        return 0;
    const uint32_t *keys = px->key + px->first[tri];
    size_t n = (size_t)(px->first[tri + 1] - px->first[tri]);
    if (n == 0 || path.depth == 0)
        return n;
    /* deeper than the keys go: the ancestor at LIE_PIXEL_LEVELS counts (more
     * pixels than the patch has, so the rule errs towards splitting) */
    int d = path.depth < LIE_PIXEL_LEVELS ? path.depth : LIE_PIXEL_LEVELS;
    uint64_t lo = 0;
    for (int k = 0; k < d; k++)
        lo |= (uint64_t)lie_patch_digit(path, k) << (2 * (LIE_PIXEL_LEVELS - 1 - k));
    uint64_t hi = lo + (UINT64_C(1) << (2 * (LIE_PIXEL_LEVELS - d)));
    return lower_bound(keys, n, hi) - lower_bound(keys, n, lo);
}

uint64_t lie_pixels_tri_hash(const lie_pixels *px, uint32_t tri)
{
    if (!px || tri >= px->n_tris)
        return 0;
    size_t n = (size_t)(px->first[tri + 1] - px->first[tri]);
    return n ? lie_hash_bytes(px->key + px->first[tri], sizeof *px->key * n, n) : 0;
}

/* ---- the cost model ---------------------------------------------------- */

double lie_cost_list_ns(const lie_build_params *p, lie_class cls, size_t n_list)
{
    switch (cls) {
    case LIE_CLASS_PARTIAL:
    case LIE_CLASS_SPLIT:
        return n_list > p->complex_cap ? (double)p->ns_ray : (double)n_list * (double)p->ns_blocker;
    case LIE_CLASS_COMPLEX:
    case LIE_CLASS_NONE:
        return (double)p->ns_ray;
    default:
        return 0.0;
    }
}

void lie_unit_shares(const lie_scene *s, uint32_t tri, float far, double *share)
{
    const lie_vec3 *V = &s->tri_p[3 * (size_t)tri];
    lie_vec3 ng = s->tri_ng[tri];
    int two_sided = lie_pair_two_sided(s, tri);
    lie_vec3 p = lie_v3_scale(lie_v3_add(lie_v3_add(V[0], V[1]), V[2]), 1.0f / 3.0f);
    double total = 0.0;
    for (int c = 0; c < s->n_clusters; c++) {
        if (!lie_cluster_can_reach(s, c, tri, V, ng, two_sided)) {
            share[c] = -1.0;
            continue;
        }
        share[c] = lie_cluster_unshadowed(s, c, p, ng, two_sided, far);
        total += share[c];
    }
    for (int c = 0; c < s->n_clusters; c++)
        if (share[c] >= 0.0)
            share[c] = total > 0.0 ? share[c] / total : 0.0;
}

int lie_unit_pays_pixels(const lie_build_params *p, double pixels, double share)
{
    if (p->frames == 0 || share < 0.0)
        return 1; /* no model, or an unlit unit: built at no cost */
    double saving = (double)p->frames * pixels * (double)p->light_samples * share * (double)p->ns_ray;
    return saving >= (double)p->samples * (double)p->ns_segment;
}

int lie_unit_pays(const lie_build_params *p, const lie_pixels *px, uint32_t tri, double share)
{
    if (!px)
        return 1; /* no views */
    return lie_unit_pays_pixels(p, (double)lie_pixels_hits(px, tri, lie_patch_root()) / (double)px->rays_per_pixel,
                                share);
}

int lie_unit_none_pays(const lie_build_params *p, double pixels)
{
    /* rounding is monotonic, so a share s <= 1 never saves more than 1 */
    return p->frames != 0 && !lie_unit_pays_pixels(p, pixels, 1.0);
}

double lie_whole_area(const lie_scene *s)
{
    double a = 0.0;
    for (uint32_t t = 0; t < s->n_tris; t++)
        a += (double)s->tri_area[t];
    if (!(a > 0.0) || !isfinite(a))
        return 1.0;
    int e;
    double m = frexp(a, &e); /* a = m 2^e, m in [0.5, 1) */
    return m == 0.5 ? a : ldexp(1.0, e);
}

double lie_whole_pixels(const lie_scene *s, const lie_build_params *p, double area, uint32_t tri)
{
    if (!p->frames || !p->whole_pixels || tri >= s->n_tris)
        return 0.0;
    return (double)p->whole_pixels * (double)s->tri_area[tri] / area;
}

void lie_env_predict(const lie_env *env, const lie_scene *s, const lie_pixels *px, lie_prediction *pred)
{
    memset(pred, 0, sizeof *pred);
    if (!px || px->n_tris != env->n_tris || s->n_tris != env->n_tris || s->n_clusters != env->n_clusters)
        return;
    const lie_build_params *p = &env->params;
    double rpp = (double)px->rays_per_pixel;
    double *share = malloc(sizeof *share * ((size_t)env->n_clusters + 1));
    if (!share)
        return; /* no prediction: what --stats prints, not what the build makes */
    float far = lie_pair_ray_far(s);
    pred->pixels = (double)px->n_hits / rpp;
    for (uint32_t t = 0; t < env->n_tris; t++) {
        if (px->first[t + 1] > px->first[t])
            lie_unit_shares(s, t, far, share);
        for (uint64_t h = px->first[t]; h < px->first[t + 1]; h++) {
            uint32_t key = px->key[h];
            for (int e = 0; e < env->n_clusters; e++) {
                /* the leaf holding this hit: down the tree by the key's digits */
                const lie_pnode *n = &env->nodes[env->root[(size_t)t * (size_t)env->n_clusters + (size_t)e]];
                int level = 0;
                while (n->child && level < LIE_PIXEL_LEVELS) {
                    n = &env->nodes[n->child + ((key >> (2 * (LIE_PIXEL_LEVELS - 1 - level))) & 3u)];
                    level++;
                }
                while (n->child) /* past the keys' depth: any leaf below is as good */
                    n = &env->nodes[n->child];
                lie_class cls = (lie_class)n->cls;
                pred->pair_pixels[cls < LIE_CLASS_COUNT ? cls : LIE_CLASS_COMPLEX] += 1.0 / rpp;
                if (cls == LIE_CLASS_UNLIT || share[e] <= 0.0)
                    continue; /* no shadow ray either way */
                /* the pixel's budget, shared by light (lie_unit_shares) */
                double spp = (double)p->light_samples * share[e];
                double ns = lie_cost_list_ns(p, cls, n->count);
                pred->full_rays += spp / rpp;
                pred->full_ns += spp * (double)p->ns_ray / rpp;
                pred->lie_ns += spp * ns / rpp;
                if (cls == LIE_CLASS_PARTIAL && n->count <= p->complex_cap)
                    pred->list_entries += spp * (double)n->count / rpp;
                else if (ns > 0.0)
                    pred->env_rays += spp / rpp;
            }
        }
    }
    free(share);
}
