/* SPDX-License-Identifier: Apache-2.0 */
/* The renderer: eye rays through pixel centres (or stratified sub-pixel
 * positions), direct lighting at the first hit, perfect mirrors traced
 * recursively, in 16x16 tiles over worker threads.  Each pixel's value
 * depends only on its own rays, so any thread count gives the same bytes. */
#include "lie/lie.h"
#include "shade/internal.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

lie_render_options lie_render_options_default(void)
{
    lie_render_options o;
    memset(&o, 0, sizeof o);
    o.size = sizeof o;
    o.width = LIE_RENDER_WIDTH_DEFAULT;
    o.height = LIE_RENDER_HEIGHT_DEFAULT;
    o.spp = 1;
    o.light_samples = LIE_LIGHT_SAMPLES_DEFAULT;
    o.max_depth = LIE_MAX_DEPTH_DEFAULT;
    o.threads = 0;
    o.pattern = LIE_PATTERN_FIXED;
    o.rays = LIE_RAYS_STREAM;
    o.visibility = LIE_VIS_FULL;
    o.aov_emitter = -1;
    return o;
}

void lie_render_stats_add(lie_render_stats *acc, const lie_render_stats *w)
{
    acc->eye_rays += w->eye_rays;
    acc->reflection_rays += w->reflection_rays;
    acc->shadow_rays += w->shadow_rays;
    acc->shadow_rays_skipped += w->shadow_rays_skipped;
    acc->shading_points += w->shading_points;
    acc->light_samples += w->light_samples;
    acc->pairs_occluded += w->pairs_occluded;
    acc->pairs_analytic += w->pairs_analytic;
    acc->pairs_exact += w->pairs_exact;
    acc->pairs_bitmask += w->pairs_bitmask;
    acc->pairs_blockers += w->pairs_blockers;
    acc->pairs_embree += w->pairs_embree;
    acc->pairs_unshadowed += w->pairs_unshadowed;
    acc->exact_overflows += w->exact_overflows;
    acc->pairs_unbuilt += w->pairs_unbuilt;
    acc->points_unbuilt += w->points_unbuilt;
    acc->t_analytic += w->t_analytic;
    acc->t_exact += w->t_exact;
    acc->t_bitmask += w->t_bitmask;
    acc->t_blockers += w->t_blockers;
    acc->t_embree += w->t_embree;
    acc->t_sampled_shading += w->t_sampled_shading;
    acc->seconds += w->seconds;
}

typedef struct render_job {
    lie_shade_ctx sc;
    const lie_camera *cam;
    lie_frame *frame;
    float *albedo, *normal, *depth, *complexity, *patch;
    float *coverage; /* the "A" channel */
    lie_view view;
    int tiles_x;
    lie_shade_scratch *scratch; /* one per worker */
} render_job;

/* Radiance along a ray: emission at the hit, direct lighting, and for a
 * mirror the reflected ray (Schlick-weighted) up to max_depth bounces. */
static void shade_hit(const render_job *j, const lie_hit *hitp, lie_vec3 dir, int depth, uint64_t pixel,
                      lie_shade_scratch *sc, float rgb[3], lie_surface *first);

static void trace(const render_job *j, lie_vec3 org, lie_vec3 dir, int depth, uint64_t pixel,
                  lie_shade_scratch *sc, float rgb[3], lie_surface *first)
{
    lie_hit hit;
    if (lie_rt_intersect(j->sc.rt, org, dir, 0.0f, INFINITY, 1, &hit))
        shade_hit(j, &hit, dir, depth, pixel, sc, rgb, first);
}

static void shade_hit(const render_job *j, const lie_hit *hitp, lie_vec3 dir, int depth, uint64_t pixel,
                      lie_shade_scratch *sc, float rgb[3], lie_surface *first)
{
    const lie_scene *s = j->sc.s;
    lie_hit hit = *hitp;
    /* straight into *first when wanted: copying a structure just written
     * field by field stalls on store forwarding */
    lie_surface local;
    lie_surface *sf = first ? first : &local;
    lie_surface_from_hit(s, &hit, dir, sf);
    sc->stats.shading_points++;
    for (int k = 0; k < 3; k++)
        rgb[k] += sf->emission[k];
    if (j->sc.opt->eye_only)
        return;
    if (sf->mirror) {
        if (depth >= j->sc.opt->max_depth)
            return;
        float dn = lie_v3_dot(dir, sf->n);
        lie_vec3 r = lie_v3_norm(lie_v3_sub(dir, lie_v3_scale(sf->n, 2.0f * dn)));
        if (lie_v3_dot(r, sf->ng) <= 0.0f)
            return; /* shading normal bent the reflection below the surface */
        float cosv = fminf(fmaxf(-dn, 0.0f), 1.0f);
        float x = 1.0f - cosv, s5 = x * x * x * x * x;
        lie_vec3 o = lie_ray_origin(sf->p, sf->ng, lie_ray_eps(sf->p));
        float sub[3] = {0.0f, 0.0f, 0.0f};
        sc->stats.reflection_rays++;
        trace(j, o, r, depth + 1, pixel, sc, sub, NULL);
        for (int k = 0; k < 3; k++) {
            float F = sf->f0[k] + (1.0f - sf->f0[k]) * s5;
            rgb[k] += F * sub[k];
        }
        return;
    }
    lie_shade_direct(&j->sc, sf, pixel, depth, sc, rgb);
}

/* Complexity and patch AOVs: the LIE of the surface seen through the pixel
 * centre (the paper's Figure 10). */
static void describe_pixel(const render_job *j, int x, int y, size_t pi)
{
    const lie_render_options *opt = j->sc.opt;
    const lie_frame *f = j->frame;
    lie_vec3 org, d;
    lie_view_ray(&j->view, (float)x + 0.5f, (float)y + 0.5f, f->width, f->height, &org, &d);
    lie_hit hit;
    float rgb[3] = {0.0f, 0.0f, 0.0f}, prgb[3] = {0.0f, 0.0f, 0.0f};
    if (lie_rt_intersect(j->sc.rt, org, d, 0.0f, INFINITY, 1, &hit)) {
        lie_surface sf;
        lie_surface_from_hit(j->sc.s, &hit, d, &sf);
        /* every cluster (lie_cluster) of the emitters asked for */
        const lie_scene *sc = j->sc.s;
        int ne = sc->n_emitters;
        int k0 = opt->aov_emitter >= 0 ? opt->aov_emitter : 0;
        int k1 = opt->aov_emitter >= 0 ? opt->aov_emitter + 1 : ne;
        int e0 = k0 < ne ? sc->emitters[k0].first_cluster : sc->n_clusters;
        int e1 = k1 < ne ? sc->emitters[k1].first_cluster : sc->n_clusters;
        int cls[64];
        uint32_t cnt[64];
        uint64_t id = 0;
        int n = 0, lit = 0;
        for (int e = e0; e < e1; e++) {
            int c;
            uint32_t k;
            uint64_t pid;
            opt->oracle->describe(opt->oracle->ctx, &sf, e, &c, &k, &pid);
            if (n < 64) {
                cls[n] = c;
                cnt[n] = k;
                n++;
            } else if (c == LIE_CLASS_COMPLEX || c > LIE_CLASS_SPLIT) {
                cls[63] = c; /* more than 64 emitters: keep the red */
            }
            if (!lit && c != LIE_CLASS_UNLIT) {
                id = pid; /* the first lit emitter's patch */
                lit = 1;
            }
        }
        if (opt->aov_emitter >= 0)
            lie_complexity_colour(cls[0], cnt[0], rgb);
        else
            lie_complexity_colour_all(cls, cnt, n, rgb);
        prgb[0] = lie_hash_to_unit(id);
        prgb[1] = lie_hash_to_unit(id << 20);
        prgb[2] = lie_hash_to_unit(id << 40);
    }
    for (int q = 0; q < 3; q++) {
        if (j->complexity)
            j->complexity[3 * pi + q] = rgb[q];
        if (j->patch)
            j->patch[3 * pi + q] = prgb[q];
    }
}

static void render_tile(void *ctx, size_t item, int worker)
{
    render_job *j = ctx;
    lie_frame *f = j->frame;
    const lie_render_options *opt = j->sc.opt;
    lie_shade_scratch *sc = &j->scratch[worker];
    int tx = (int)(item % (size_t)j->tiles_x), ty = (int)(item / (size_t)j->tiles_x);
    int x0 = tx * LIE_TILE, y0 = ty * LIE_TILE;
    int x1 = x0 + LIE_TILE < f->width ? x0 + LIE_TILE : f->width;
    int y1 = y0 + LIE_TILE < f->height ? y0 + LIE_TILE : f->height;
    int spp = opt->spp > 0 ? opt->spp : 1;
    /* One eye ray per pixel: coherent camera rays go to Embree as 8-wide
     * packets, a row of a tile at a time. */
    lie_hit row_hits[LIE_TILE];
    lie_vec3 row_orgs[LIE_TILE], row_dirs[LIE_TILE];
    for (int y = y0; y < y1; y++) {
        if (spp == 1) {
            int n = x1 - x0;
            for (int i = 0; i < n; i++)
                lie_view_ray(&j->view, (float)(x0 + i) + 0.5f, (float)y + 0.5f, f->width, f->height, &row_orgs[i],
                             &row_dirs[i]);
            for (int i = 0; i < n; i += 8)
                lie_rt_intersect8(j->sc.rt, row_orgs + i, row_dirs + i, n - i < 8 ? n - i : 8, 1, row_hits + i);
        }
        for (int x = x0; x < x1; x++) {
            uint64_t pixel = (uint64_t)y * (uint64_t)f->width + (uint64_t)x;
            float acc[3] = {0.0f, 0.0f, 0.0f};
            float alb[3] = {0.0f, 0.0f, 0.0f}, nrm[3] = {0.0f, 0.0f, 0.0f}, dep = 0.0f;
            int first_hits = 0;
            uint64_t h = spp > 1 ? lie_hash_u64x4(pixel, 0x706978656cull, 0, 0) : 0;
            float shx = lie_hash_to_unit(h), shy = lie_hash_to_unit(h << 24);
            for (int k = 0; k < spp; k++) {
                lie_surface first;
                first.tri = LIE_NO_HIT;
                float c[3] = {0.0f, 0.0f, 0.0f};
                sc->stats.eye_rays++;
                /* the pixel and the eye sample seed the light patterns */
                const uint64_t key = pixel | (uint64_t)k << 40;
                if (spp == 1) {
                    /* the row's packet has traced it */
                    if (row_hits[x - x0].tri != LIE_NO_HIT)
                        shade_hit(j, &row_hits[x - x0], row_dirs[x - x0], 0, key, sc, c, &first);
                } else {
                    /* Stratified: a Hammersley set shifted per pixel. */
                    float sx = ((float)k + 0.5f) / (float)spp + shx;
                    float sy = lie_radical_inverse2((uint32_t)k) + shy;
                    sx -= floorf(sx);
                    sy -= floorf(sy);
                    lie_vec3 org, d;
                    lie_view_ray(&j->view, (float)x + sx, (float)y + sy, f->width, f->height, &org, &d);
                    trace(j, org, d, 0, key, sc, c, &first);
                }
                for (int q = 0; q < 3; q++)
                    acc[q] += c[q];
                if (first.tri != LIE_NO_HIT) {
                    first_hits++;
                    for (int q = 0; q < 3; q++)
                        alb[q] += first.base_color[q];
                    nrm[0] += first.n.x;
                    nrm[1] += first.n.y;
                    nrm[2] += first.n.z;
                    dep += lie_v3_dot(lie_v3_sub(first.p, j->cam->eye), j->view.fwd);
                }
            }
            size_t pi = (size_t)pixel;
            float inv = 1.0f / (float)spp;
            for (int q = 0; q < 3; q++)
                f->rgb[3 * pi + q] = acc[q] * inv;
            if (j->albedo)
                for (int q = 0; q < 3; q++)
                    j->albedo[3 * pi + q] = alb[q] * inv;
            if (j->normal)
                for (int q = 0; q < 3; q++)
                    j->normal[3 * pi + q] = nrm[q] * inv;
            if (j->depth)
                j->depth[pi] = first_hits ? dep / (float)first_hits : INFINITY;
            if (j->coverage)
                j->coverage[pi] = (float)first_hits * inv;
            if (j->complexity || j->patch)
                describe_pixel(j, x, y, pi);
        }
    }
}

/* The frame lie_render fills for opt: RGB and the requested AOVs. */
lie_status lie_render_frame_create(const lie_scene *s, const lie_render_options *opt, lie_frame **out, lie_error *err)
{
    *out = NULL;
    const char *path = s->path ? s->path : "";
    if (opt->width < 1 || opt->height < 1 || opt->width > 65536 || opt->height > 65536)
        return lie_error_set(err, LIE_ERR_ARG, path, "image size %dx%d out of range", opt->width, opt->height);
    lie_frame *f = lie_frame_create(opt->width, opt->height);
    if (!f)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory for a %dx%d frame", opt->width, opt->height);
    static const char *const rgb_names[3] = {"R", "G", "B"};
    static const char *const xyz_names[3] = {"X", "Y", "Z"};
    static const char *const z_name[1] = {"Z"};
    static const char *const a_name[1] = {"A"};
    static const struct {
        unsigned bit;
        const char *name;
        int n;
        const char *const *chans;
    } layers[] = {
        {LIE_AOV_ALBEDO, "albedo", 3, rgb_names},         {LIE_AOV_NORMAL, "normal", 3, xyz_names},
        {LIE_AOV_DEPTH, "depth", 1, z_name},              {LIE_AOV_COMPLEXITY, "complexity", 3, rgb_names},
        {LIE_AOV_PATCH, "patch", 3, rgb_names},
    };
    for (size_t k = 0; k < sizeof layers / sizeof layers[0]; k++)
        if ((opt->aovs & layers[k].bit) && !lie_frame_add_aov(f, layers[k].name, layers[k].n, layers[k].chans)) {
            lie_frame_destroy(f);
            return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
        }
    /* coverage, OpenEXR's alpha in the default layer: the fraction of the
     * pixel's eye rays that hit a surface */
    if (!lie_frame_add_aov(f, "", 1, a_name)) {
        lie_frame_destroy(f);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    *out = f;
    return LIE_OK;
}

static float *aov_data(const lie_frame *f, const char *name)
{
    const lie_aov *a = lie_frame_find_aov(f, name);
    return a ? a->data : NULL;
}

typedef struct tile_range {
    render_job *j;
    size_t first;
} tile_range;

static void render_range_tile(void *ctx, size_t item, int worker)
{
    const tile_range *r = ctx;
    render_tile(r->j, r->first + item, worker);
}

/* The options as this library knows them: a caller's struct of an older,
 * smaller size gets the defaults for the fields it lacks. */
static lie_status options_of(const lie_scene *s, const lie_render_options *opt, lie_render_options *out,
                             lie_error *err)
{
    *out = lie_render_options_default();
    if (opt->size < offsetof(lie_render_options, bitmask) || opt->size > sizeof *out)
        return lie_error_set(err, LIE_ERR_ARG, s->path ? s->path : "",
                             "render options of size %zu: not made by lie_render_options_default", opt->size);
    memcpy(out, opt, opt->size);
    out->size = sizeof *out;
    return LIE_OK;
}

/* What a frame shares among its workers besides the scratch: the fixed
 * patterns and bitmasks of the per-emitter sampler, the closed forms, the
 * textured emitters' distributions, the emitters' bounds and the light
 * sampler. */
static lie_status frame_setup(render_job *j, const lie_scene *s, const lie_render_options *opt)
{
    lie_shade_ctx *c = &j->sc;
    lie_status st = LIE_OK;
    const int ne = s->n_emitters;
    const lie_lights *lt = opt->lights && lie_lights_fit(opt->lights, s) ? opt->lights : NULL;
    c->sampler_on = opt->sampler != LIE_SAMPLER_PER_EMITTER;
    if (!c->sampler_on) {
        lie_light_samples *fixed = calloc((size_t)ne + 1, sizeof *fixed);
        c->fixed = fixed;
        st = fixed ? LIE_OK : LIE_ERR_NOMEM;
        for (int e = 0; st == LIE_OK && e < ne; e++) {
            int n = lie_emitter_sample_count(&s->emitters[e], opt->light_samples);
            st = lie_light_samples_alloc(&fixed[e], n);
            if (st == LIE_OK) {
                float su, sv;
                lie_light_pattern_shift(e, &su, &sv);
                if (opt->seed) {
                    uint64_t h = lie_hash_u64x4((uint64_t)e, opt->seed, 0x66697865ull, 0);
                    su = lie_hash_to_unit(h), sv = lie_hash_to_unit(h << 24);
                }
                lie_light_samples_generate(s, e, n, su, sv, &fixed[e]);
            }
        }
    } else {
        float *scale = malloc(sizeof *scale * ((size_t)ne + 1));
        if (lt && lt->texlights) {
            c->texlights = lt->texlights;
            c->borrowed_tex = 1;
        } else {
            c->texlights = calloc((size_t)ne + 1, sizeof *c->texlights);
            st = c->texlights && scale ? lie_texlight_create_all(s, c->texlights, opt->threads) : LIE_ERR_NOMEM;
        }
        st = st == LIE_OK && !scale ? LIE_ERR_NOMEM : st;
        for (int e = 0; st == LIE_OK && e < ne; e++)
            scale[e] = lie_texlight_power_scale(c->texlights[e]);
        int n_delta = 0;
        for (int e = 0; e < ne; e++)
            n_delta += lie_emitter_is_delta(&s->emitters[e]);
        if (st == LIE_OK && n_delta > 0 && n_delta <= opt->light_samples) {
            int *ids = malloc(sizeof *ids * (size_t)n_delta);
            st = ids ? LIE_OK : LIE_ERR_NOMEM;
            for (int e = 0, k = 0; st == LIE_OK && e < ne; e++)
                if (lie_emitter_is_delta(&s->emitters[e])) {
                    ids[k++] = e;
                    scale[e] = 0.0f; /* no share of the budget */
                }
            c->delta_ids = ids;
            c->n_delta_apart = ids ? n_delta : 0;
        }
        lie_light_bounds *bounds = NULL;
        if (st == LIE_OK)
            st = lie_light_bounds_all(s, scale, &bounds);
        c->bounds = bounds;
        free(scale);
        /* the sampler's lights: the emitters' groups (sampler.h), their
         * bounds as the frame weighs the emitters (delta lights apart) */
        const int split = opt->exact != LIE_EXACT_ONLY;
        if (st == LIE_OK && lt && lt->groups && lt->groups->split == split) {
            c->groups = lt->groups;
            c->borrowed_groups = 1;
        } else if (st == LIE_OK) {
            st = lie_light_groups_create(s, c->texlights, bounds, split, &c->groups);
        }
        lie_light_bounds *gb = NULL;
        if (st == LIE_OK) {
            const lie_light_groups *G = c->groups;
            gb = malloc(sizeof *gb * ((size_t)G->n + 1));
            st = gb ? LIE_OK : LIE_ERR_NOMEM;
            for (int g = 0; st == LIE_OK && g < G->n; g++)
                gb[g] = G->g[g].whole ? bounds[G->g[g].emitter] : G->bounds[g];
        }
        if (st == LIE_OK)
            st = lie_light_sampler_create(opt->sampler, gb, c->groups->n, &c->sampler);
        free(gb);
        /* the LIE's classes share the budget, except in the oracle's mode
         * (the same samples as full visibility) */
        c->guided = opt->visibility == LIE_VIS_LIE && opt->oracle && opt->exact != LIE_EXACT_OFF;
        /* ... while it costs less than the budget: it visits every
         * emitter at every point, where the tree's n picks cost O(n log
         * lights); with more emitters than LIE_GUIDED_EMITTER_SAMPLES of
         * them, the tree chooses and the LIE answers each pick (occluded:
         * no ray; seen whole: its closed form; partial: its blockers) */
        if (c->guided && (long long)s->n_emitters * LIE_GUIDED_EMITTER_SAMPLES > opt->light_samples &&
            opt->exact != LIE_EXACT_ONLY)
            c->guided = 0;
    }
    /* closed forms from LIE_ANALYTIC_MIN_SAMPLES on: below, a few samples
     * cost less than an edge sum */
    c->analytic = opt->exact == LIE_EXACT_ONLY || opt->light_samples >= LIE_ANALYTIC_MIN_SAMPLES;
    c->exact = opt->visibility == LIE_VIS_LIE && opt->exact != LIE_EXACT_OFF;
    if (st == LIE_OK && c->analytic && lt && lt->poly) {
        c->poly = lt->poly;
        c->borrowed_poly = 1;
    } else if (st == LIE_OK && c->analytic) {
        c->poly = calloc((size_t)ne + 1, sizeof *c->poly);
        st = c->poly ? LIE_OK : LIE_ERR_NOMEM;
        for (int e = 0; st == LIE_OK && e < ne; e++)
            st = lie_polylight_create(s, e, &c->poly[e]);
    }
    /* all samples at once (bitmask.h): the fixed pattern of each planar
     * emitter in mask order */
    if (st == LIE_OK && !c->sampler_on && opt->visibility == LIE_VIS_LIE && opt->oracle && opt->oracle->occluded_mask &&
        (opt->bitmask == LIE_BITMASK_ONLY || (opt->bitmask == LIE_BITMASK_AUTO && opt->exact == LIE_EXACT_AUTO)) &&
        opt->exact != LIE_EXACT_ONLY && opt->pattern == LIE_PATTERN_FIXED &&
        opt->light_samples >= LIE_BITMASK_MIN_SAMPLES) {
        c->bits = calloc((size_t)ne + 1, sizeof *c->bits);
        st = c->bits ? LIE_OK : LIE_ERR_NOMEM;
        for (int e = 0; st == LIE_OK && e < ne; e++)
            if (!lie_emitter_is_delta(&s->emitters[e]))
                st = lie_bitmask_create(&c->fixed[e], &c->bits[e]);
    }
    return st;
}

static void lights_free(int n, lie_texlight **texlights, lie_polylight **poly)
{
    for (int e = 0; e < n; e++) {
        if (poly)
            lie_polylight_destroy(poly[e]);
        if (texlights)
            lie_texlight_destroy(texlights[e]);
    }
    free(poly);
    free(texlights);
}

/* lie_lights_create, and without the textured emitters' distributions
 * (textured 0: lie_lights_create_untextured). */
static lie_status lights_make(const lie_scene *s, const lie_render_options *opt, int textured, lie_lights **out,
                              lie_error *err)
{
    *out = NULL;
    const char *path = s->path ? s->path : "";
    lie_render_options o = lie_render_options_default();
    if (opt && options_of(s, opt, &o, err) != LIE_OK)
        return LIE_ERR_ARG;
    opt = &o;
    lie_lights *l = calloc(1, sizeof *l);
    const int ne = s->n_emitters;
    if (!l)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    l->hash = s->hash;
    l->n_emitters = ne;
    /* what frames with these options use: the distributions for a
     * budgeted sampler, the closed forms where they are on */
    const int sampler = opt->sampler != LIE_SAMPLER_PER_EMITTER;
    const int analytic = opt->exact == LIE_EXACT_ONLY || opt->light_samples >= LIE_ANALYTIC_MIN_SAMPLES;
    lie_status st = LIE_OK;
    if (sampler) {
        l->texlights = calloc((size_t)ne + 1, sizeof *l->texlights);
        st = !l->texlights ? LIE_ERR_NOMEM : textured ? lie_texlight_create_all(s, l->texlights, opt->threads) : LIE_OK;
        float *scale = malloc(sizeof *scale * ((size_t)ne + 1));
        lie_light_bounds *eb = NULL;
        st = st == LIE_OK && !scale ? LIE_ERR_NOMEM : st;
        for (int e = 0; st == LIE_OK && e < ne; e++)
            scale[e] = lie_texlight_power_scale(l->texlights[e]);
        if (st == LIE_OK)
            st = lie_light_bounds_all(s, scale, &eb);
        if (st == LIE_OK)
            st = lie_light_groups_create(s, l->texlights, eb, opt->exact != LIE_EXACT_ONLY, &l->groups);
        free(scale);
        free(eb);
    }
    if (st == LIE_OK && analytic) {
        l->poly = calloc((size_t)ne + 1, sizeof *l->poly);
        st = l->poly ? LIE_OK : LIE_ERR_NOMEM;
        for (int e = 0; st == LIE_OK && e < ne; e++)
            st = lie_polylight_create(s, e, &l->poly[e]);
    }
    if (st != LIE_OK) {
        lie_lights_destroy(l);
        return lie_error_set(err, st, path, "%s", lie_status_str(st));
    }
    *out = l;
    return LIE_OK;
}

lie_status lie_lights_create(const lie_scene *s, const lie_render_options *opt, lie_lights **out, lie_error *err)
{
    return lights_make(s, opt, 1, out, err);
}

lie_status lie_lights_create_untextured(const lie_scene *s, const lie_render_options *opt, lie_lights **out,
                                        lie_error *err)
{
    /* every texlight NULL: the groups weigh and sample those emitters'
     * triangles by area (lightgroup.c), the samples read the texture for
     * their light (emitter_area.c), as for an emitter without one */
    return lights_make(s, opt, 0, out, err);
}

void lie_lights_destroy(lie_lights *l)
{
    if (!l)
        return;
    lights_free(l->n_emitters, l->texlights, l->poly);
    lie_light_groups_destroy(l->groups);
    free(l);
}

int lie_lights_fit(const lie_lights *l, const lie_scene *s) { return l && l->hash == s->hash && l->n_emitters == s->n_emitters; }

static void frame_free(render_job *j, const lie_scene *s)
{
    lie_shade_ctx *c = &j->sc;
    for (int e = 0; e < s->n_emitters; e++) {
        if (c->fixed)
            lie_light_samples_free((lie_light_samples *)&c->fixed[e]);
        if (c->bits)
            lie_bitmask_destroy(c->bits[e]);
    }
    lights_free(s->n_emitters, c->borrowed_tex ? NULL : c->texlights, c->borrowed_poly ? NULL : c->poly);
    if (!c->borrowed_groups)
        lie_light_groups_destroy(c->groups);
    free((void *)c->fixed);
    free(c->bits);
    free((void *)c->bounds);
    free((void *)c->delta_ids);
    lie_light_sampler_destroy(&c->sampler);
}

lie_status lie_render_tiles(const lie_scene *s, const lie_rt *rt, const lie_camera *cam,
                            const lie_render_options *user_opt, lie_frame *f, size_t first, size_t count,
                            lie_render_stats *stats, lie_error *err)
{
    const char *path = s->path ? s->path : "";
    lie_render_options frame_opt;
    lie_status st = options_of(s, user_opt, &frame_opt, err);
    if (st != LIE_OK)
        return st;
    const lie_render_options *opt = &frame_opt;
    if (opt->width != f->width || opt->height != f->height)
        return lie_error_set(err, LIE_ERR_ARG, path, "frame %dx%d does not match image size %dx%d", f->width,
                             f->height, opt->width, opt->height);
    if (first > lie_render_tile_count(opt->width, opt->height) ||
        count > lie_render_tile_count(opt->width, opt->height) - first)
        return lie_error_set(err, LIE_ERR_ARG, path, "tiles %zu..%zu out of range", first, first + count);
    if (opt->light_samples < 1 || opt->light_samples > 1000000)
        return lie_error_set(err, LIE_ERR_ARG, path, "light samples %d out of range", opt->light_samples);
    const char *bad_camera = lie_camera_invalid(cam);
    if (bad_camera)
        return lie_error_set(err, LIE_ERR_ARG, path, "camera: %s", bad_camera);
    if (opt->visibility == LIE_VIS_LIE && !opt->oracle)
        return lie_error_set(err, LIE_ERR_ARG, path, "LIE visibility needs a cache");
    if ((opt->aovs & (LIE_AOV_COMPLEXITY | LIE_AOV_PATCH)) && (!opt->oracle || !opt->oracle->describe))
        return lie_error_set(err, LIE_ERR_ARG, path, "complexity and patch AOVs need a cache");
    if (opt->aov_emitter >= s->n_emitters)
        return lie_error_set(err, LIE_ERR_ARG, path, "emitter %d: the scene has %d", opt->aov_emitter,
                             s->n_emitters);
    if ((unsigned)opt->sampler > LIE_SAMPLER_PER_EMITTER)
        return lie_error_set(err, LIE_ERR_ARG, path, "unknown light sampler %d", (int)opt->sampler);
    double t0 = lie_time_now();
    render_job j;
    memset(&j, 0, sizeof j);
    j.sc.s = s;
    j.sc.rt = rt;
    /* a per-emitter frame of very few light samples is cheaper with full
     * visibility (LIE_ENV_MIN_SAMPLES); the oracle still serves the AOVs */
    if (opt->sampler == LIE_SAMPLER_PER_EMITTER && opt->visibility == LIE_VIS_LIE &&
        opt->light_samples < LIE_ENV_MIN_SAMPLES && opt->exact != LIE_EXACT_ONLY)
        frame_opt.visibility = LIE_VIS_FULL;
    j.sc.opt = opt;
    /* glass lets light through, tinted, to what it encloses: every shadow
     * segment's light is multiplied by what it crosses (lie_pair_kernel) */
    j.sc.transmit = lie_rt_transmits(rt) && opt->visibility != LIE_VIS_NONE;
    j.sc.ray_far = lie_pair_ray_far(s);
    if (!isfinite(j.sc.ray_far))
        j.sc.ray_far = 1e30f;
    j.cam = cam;
    j.view = lie_view_make(cam, opt->width, opt->height);
    j.frame = f;
    j.albedo = aov_data(f, "albedo");
    j.normal = aov_data(f, "normal");
    j.depth = aov_data(f, "depth");
    j.complexity = aov_data(f, "complexity");
    j.patch = aov_data(f, "patch");
    j.coverage = aov_data(f, "");
    int threads = opt->threads > 0 ? opt->threads : lie_cpu_count();
    j.scratch = aligned_alloc(128, sizeof *j.scratch * (size_t)threads);
    if (j.scratch)
        memset(j.scratch, 0, sizeof *j.scratch * (size_t)threads);
    st = j.scratch ? frame_setup(&j, s, opt) : LIE_ERR_NOMEM;
    /* picks: one per emitter (the LIE's guided budget) or light group */
    int lights = j.sc.groups && j.sc.groups->n > s->n_emitters ? j.sc.groups->n : s->n_emitters;
    for (int t = 0; st == LIE_OK && t < threads; t++)
        st = lie_shade_scratch_init(&j.scratch[t], opt->light_samples, opt->oracle ? opt->oracle->max_blockers : 0,
                                    lights);
    if (st == LIE_OK) {
        j.tiles_x = (opt->width + LIE_TILE - 1) / LIE_TILE;
        tile_range r = {&j, first};
        lie_progress prog;
        lie_progress_begin(&prog, stderr, opt->progress_label ? opt->progress_label : "render", opt->progress);
        prog.unit = "tiles";
        st = lie_parallel_for(count, threads, render_range_tile, &r, lie_progress_cb, &prog);
        lie_progress_end(&prog);
    }
    if (stats) {
        memset(stats, 0, sizeof *stats);
        for (int t = 0; j.scratch && t < threads; t++)
            lie_render_stats_add(stats, &j.scratch[t].stats);
        stats->seconds = lie_time_now() - t0;
    }
    for (int t = 0; j.scratch && t < threads; t++)
        lie_shade_scratch_free(&j.scratch[t]);
    free(j.scratch);
    frame_free(&j, s);
    if (st != LIE_OK)
        return lie_error_set(err, st, path, "%s", lie_status_str(st));
    return LIE_OK;
}

lie_status lie_render(const lie_scene *s, const lie_rt *rt, const lie_camera *cam,
                      const lie_render_options *opt, lie_frame **out, lie_render_stats *stats,
                      lie_error *err)
{
    *out = NULL;
    lie_frame *f = NULL;
    lie_status st = lie_render_frame_create(s, opt, &f, err);
    if (st == LIE_OK)
        st = lie_render_tiles(s, rt, cam, opt, f, 0, lie_render_tile_count(opt->width, opt->height), stats, err);
    if (st != LIE_OK) {
        lie_frame_destroy(f);
        return st;
    }
    *out = f;
    return LIE_OK;
}
