/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade: BRDFs (Lambert; GGX as glTF's metallic-roughness BRDF; perfect
 * mirror), emitter sample patterns and the direct-lighting renderer.
 *
 * There is one shading code (docs/architecture.md, "a visibility method").  Visibility
 * strategies differ only in how a shadow ray is answered: `full` asks Embree
 * over the whole scene (the reference), `lie` (lib/lie) asks the patch's
 * local illumination environment. */
#ifndef LIE_SHADE_H
#define LIE_SHADE_H

#include "core/core.h"
#include "image/image.h"
#include "lie/lie.h"
#include "rt/rt.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

/* ---- emitter sample patterns ----------------------------------------- */

/* Per emitter, `n` samples as structure of arrays: position, emitter normal
 * (area emitters), and radiance weight Le * area / n (area; so the estimate
 * is the plain sum of weight * G * f * V) or the intensity (punctual). */
typedef struct lie_light_samples {
    int n;
    float *x, *y, *z, *nx, *ny, *nz, *r, *g, *b;
    int uniform;           /* every sample has the same weight (no emissive texture) */
    /* A planar area emitter (lie_emitter.planar): the plane's frame, and
     * each sample's coordinates (s, t) in it, with (x, y, z) exactly
     * po + s pu + t pv as evaluated in float; [smin, smax] x [tmin, tmax]
     * bounds the samples.  Shading and blocker tests then work with linear
     * forms in (s, t). */
    int planar;
    float po[3], pu[3], pv[3], pn[3];
    float *s, *t;
    float smin, smax, tmin, tmax;
    uint32_t *tri;         /* area: each sample's emitter triangle (its cluster answers its visibility) */
} lie_light_samples;

/* Samples of emitter e: a Hammersley point set over the unit square,
 * Cranley-Patterson shifted by (su, sv), mapped through the triangle area CDF
 * onto the emitter.  `out` arrays must hold `n` floats each (see
 * lie_light_samples_alloc).  Punctual emitters produce exactly one sample. */
void lie_light_samples_generate(const lie_scene *s, int e, int n, float su, float sv,
                                lie_light_samples *out);
lie_status lie_light_samples_alloc(lie_light_samples *ls, int n);
void lie_light_samples_free(lie_light_samples *ls);
/* n rounded up to a whole 8-wide vector: vector loops over (s, t) may run
 * to it, the arrays hold it (they are padded to 16), and the padding's s and
 * t are NaN, so no linear form admits a padding sample. */
static inline int lie_light_samples_padded(const lie_light_samples *ls) { return (ls->n + 7) & ~7; }
/* The fixed per-emitter shift (the paper's "same sample points every time"). */
void lie_light_pattern_shift(int e, float *su, float *sv);

/* ---- surfaces --------------------------------------------------------- */

/* Everything the integrator needs about a hit point. */
typedef struct lie_surface {
    uint32_t tri;
    float b1, b2;          /* barycentrics of vertices 1 and 2 */
    lie_vec3 p;            /* position */
    lie_vec3 ng, n;        /* geometric and shading normal, on the side of wo */
    lie_vec3 wo;           /* unit direction towards the viewer */
    float diffuse[3];      /* c_diff = baseColor * (1 - metallic) */
    float f0[3];           /* mix(0.04, baseColor, metallic) */
    float alpha;           /* GGX alpha = roughness^2 */
    int mirror;            /* perfect specular */
    int lambert;           /* metallic == 0 and roughness == 1: pure Lambert fast path */
    float base_color[3];
    float emission[3];     /* emitted radiance towards wo */
} lie_surface;

/* Fill a surface from a ray hit. */
void lie_surface_from_hit(const lie_scene *s, const lie_hit *hit, lie_vec3 ray_dir, lie_surface *sf);

/* glTF metallic-roughness BRDF f(wi, wo) * cos(theta_i) (Appendix B of the
 * glTF 2.0 specification: GGX D, height-correlated Smith V, Schlick F). */
void lie_brdf_eval_cos(const lie_surface *sf, lie_vec3 wi, float out[3]);

/* ---- visibility strategies ------------------------------------------- */

typedef enum lie_visibility_mode {
    LIE_VIS_FULL = 0,      /* Embree over the whole scene: the reference */
    LIE_VIS_LIE = 1,       /* local illumination environments (lib/lie) */
    LIE_VIS_NONE = 2       /* no shadows at all (benchmarks: shading cost alone) */
} lie_visibility_mode;

/* A pair's class is lib/lie's lie_class (lie/lie.h), one enum for the
 * cache and the renderer: classify() answers VISIBLE, OCCLUDED (or unlit:
 * no light either way), PARTIAL (test the blocker list), COMPLEX (ask the
 * whole scene) or NONE (not built: the whole scene too); the renderer
 * calls an emitter of several clusters SPLIT (each cluster's own pair
 * answers its samples). */

/* One shading point's shadow segments toward one emitter: o -> o + d_i,
 * d_i the vector to sample i shortened by eps.  For an area emitter the
 * samples are `ls` and dx, dy, dz are filled only on demand
 * (lie_shadow_query_segments), since a planar emitter's segments can be tested
 * from (s, t) alone; for a punctual one (ls NULL) the one segment is in
 * dx[0], dy[0], dz[0] from the start. */
typedef struct lie_shadow_query {
    lie_vec3 o;
    float eps;
    const lie_light_samples *ls;
    int n;
    int have_segments;
    float *dx, *dy, *dz;
    /* the oracle's per-blocker workspace: LIE_BLOCKER_WORK arrays of
     * work_stride floats and work_stride kinds (work_stride >= the
     * oracle's max_blockers) */
    float *work;
    uint32_t *kind;
    size_t work_stride;
} lie_shadow_query;
#define LIE_BLOCKER_WORK 15
void lie_shadow_query_segments(lie_shadow_query *q);

/* A visibility oracle other than Embree-over-everything.  classify() looks
 * up the pair; for LIE_CLASS_PARTIAL, select() keeps the pair's
 * blockers that can matter to segments from origin o shortened by eps
 * (lie_shadow_query) (writing at most max_blockers
 * triangle indices; none left means the point sees the emitter whole) and
 * occluded() answers the query's segments against them (occ[i] = ~0 if
 * blocked, 0 if free). */
typedef struct lie_bitmask lie_bitmask; /* lib/shade/bitmask.h */
typedef struct lie_vis_oracle {
    void *ctx;
    int max_blockers;
    lie_class (*classify)(void *ctx, const lie_surface *sf, int emitter, const void **pair);
    int (*select)(void *ctx, const void *pair, int emitter, lie_vec3 o, float eps, uint32_t *out);
    void (*occluded)(void *ctx, const uint32_t *blockers, int n_blockers, lie_shadow_query *q,
                     uint32_t *occ);
    /* Optional: the same as a bitmask over bm's samples (q->ls is bm's
     * pattern), bit i set if sample i is blocked; returns 0 where it cannot
     * answer (then occluded() does). */
    int (*occluded_mask)(void *ctx, const uint32_t *blockers, int n_blockers, lie_shadow_query *q,
                         const lie_bitmask *bm, uint64_t *mask);
    /* For AOVs: the pair's class (lie_class), list length and a patch id. */
    void (*describe)(void *ctx, const lie_surface *sf, int emitter, int *cls, uint32_t *count,
                     uint64_t *patch_id);
    /* per triangle, its closed convex solid or -1 (lie_solids_find); may be NULL */
    const int32_t *solid;
} lie_vis_oracle;

/* The LIE strategy (§4.2): the hit's patch finds its leaf per emitter;
 * visible pairs need no ray, occluded and unlit ones contribute nothing,
 * partial ones test their rays against the blocker list only (compact
 * precomputed triangles, a loop the compiler vectorises over rays), and
 * complex pairs ask Embree.  `env` must match the scene. */
typedef struct lie_env lie_env;
typedef struct lie_env_shadows lie_env_shadows;
lie_status lie_env_shadows_create(const lie_scene *s, const lie_env *env, lie_env_shadows **out, lie_error *err);
const lie_vis_oracle *lie_env_shadows_oracle(const lie_env_shadows *v);
/* The env grew lists up to `longest` blockers since the oracle was made (an
 * env built while it is rendered from, lib/update's lie_ctor): the
 * oracle's max_blockers follows.  Call while nothing renders from it. */
void lie_env_shadows_grow(lie_env_shadows *v, uint32_t longest);
/* From now on, set mask[tri] (n_tris bytes, the caller's, not cleared) for
 * every triangle whose unbuilt (LIE_CLASS_NONE) unit a render asks about:
 * what a render from an env still being built answered with Embree
 * (lie-render --cache).  NULL stops it. */
void lie_env_shadows_record_unbuilt(lie_env_shadows *v, uint8_t *mask);
void lie_env_shadows_destroy(lie_env_shadows *v);

/* ---- the renderer ------------------------------------------------------ */

typedef enum lie_pattern { LIE_PATTERN_FIXED = 0, LIE_PATTERN_ROTATED = 1 } lie_pattern;

enum {
    LIE_AOV_ALBEDO = 1 << 0,
    LIE_AOV_NORMAL = 1 << 1,
    LIE_AOV_DEPTH = 1 << 2,
    LIE_AOV_COMPLEXITY = 1 << 3, /* Figure 10 colours (needs an oracle) */
    LIE_AOV_PATCH = 1 << 4       /* a colour per leaf patch (needs an oracle) */
};

/* Figure 10's colour code for one pair: green visible, blue occluded, grey
 * from black (1 blocker) to white (>= 10) for partial, red complex or not
 * covered, black unlit.  `cls` is a lie_class (or -1: not covered). */
void lie_complexity_colour(int cls, uint32_t count, float rgb[3]);
/* Over all emitters: red if any pair is complex, else grey by the summed
 * blocker count if any is partial, else the mix of green (visible) and blue
 * (occluded) over the lit emitters, black if none is lit. */
void lie_complexity_colour_all(const int *cls, const uint32_t *count, int n, float rgb[3]);

/* Lambert receivers under planar emitters of one radiance are shaded in
 * closed form (Lambert's edge sum) with any visibility: a pair seen whole
 * takes no samples, a pair whose visibility is sampled is scaled by the
 * ratio of its visible samples' weight to all its samples' (Heitz, Hill,
 * McGuire 2018).  With LIE visibility, a partial pair's visible part can
 * be found exactly by back-projecting its blockers: LIE_EXACT_ONLY always,
 * LIE_EXACT_AUTO when that costs less than testing its samples (the cost
 * model of lib/shade/cost.h). */
typedef enum lie_exact_mode {
    LIE_EXACT_AUTO = 0,
    LIE_EXACT_OFF = 1,     /* partial pairs sampled (the oracle: LIE image = full image) */
    LIE_EXACT_ONLY = 2     /* closed forms and exact visibility wherever they apply */
} lie_exact_mode;
/* Partial pairs toward a planar emitter may also be answered with all
 * samples at once (lib/shade/bitmask.h): LIE_BITMASK_AUTO where the cost
 * model says it is the cheapest of samples, bitmask and exact;
 * LIE_BITMASK_ONLY wherever it applies (not with LIE_EXACT_ONLY, whose
 * exact shadows win); LIE_BITMASK_OFF never.  AUTO is off under
 * LIE_EXACT_OFF, the oracle's mode (the same samples in the same order as
 * full visibility).  It needs the per-emitter sampler's fixed pattern. */
typedef enum lie_bitmask_mode {
    LIE_BITMASK_AUTO = 0,
    LIE_BITMASK_OFF = 1,
    LIE_BITMASK_ONLY = 2
} lie_bitmask_mode;

/* How a shading point's light samples are shared among the emitters
 * (lib/shade/sampler.h; chosen by name, lie_light_sampler_parse):
 *  - LIE_SAMPLER_TREE (the default): `light_samples` is a budget per
 *    shading point, each sample going to an emitter picked through a
 *    light BVH with orientation bounds (Conty Estevez and Kulla 2018), in
 *    O(log emitters).  Under LIE visibility (not LIE_EXACT_OFF) the
 *    pair's classes guide it instead: unlit and occluded pairs take
 *    nothing, visible ones their closed form, and the budget goes to the
 *    partial pairs in proportion to their unshadowed light;
 *  - LIE_SAMPLER_POWER, LIE_SAMPLER_UNIFORM: the same budget, emitters in
 *    proportion to their power (the emissive texture's included), or all
 *    alike (pbrt-v4's PowerLightSampler and UniformLightSampler);
 *  - LIE_SAMPLER_PER_EMITTER: the paper's meaning, `light_samples` of
 *    every emitter at every point, from one fixed pattern per emitter
 *    (§6.1) or a rotated one (`pattern`).
 * The budgeted samplers take a fresh pattern per pixel, rotated by hashes
 * of the pixel, the emitter and `seed` (Cranley and Patterson 1976):
 * their error is noise, not structure. */
typedef enum lie_light_sampler_kind {
    LIE_SAMPLER_TREE = 0,
    LIE_SAMPLER_POWER = 1,
    LIE_SAMPLER_UNIFORM = 2,
    LIE_SAMPLER_PER_EMITTER = 3
} lie_light_sampler_kind;
/* The sampler named `name` ("tree", "power", "uniform", "per-emitter"):
 * 1 and *out set, or 0.  lie_light_sampler_name is the inverse. */
int lie_light_sampler_parse(const char *name, lie_light_sampler_kind *out);
const char *lie_light_sampler_name(lie_light_sampler_kind k);

/* Options of a render.  `size` is sizeof(lie_render_options) as the caller
 * was compiled (lie_render_options_default sets it): a library built with
 * more fields takes the defaults for those a smaller struct lacks
 * (OpenEXRCore's exr_context_initializer_t), so callers built against an
 * older header keep working. */
typedef struct lie_render_options {
    size_t size;
    int width, height;
    int spp;               /* eye rays per pixel, stratified; 1 = pixel centre */
    int light_samples;     /* light samples per shading point, shared among the emitters
                              (LIE_SAMPLER_PER_EMITTER: per area emitter) */
    int max_depth;         /* mirror bounces */
    int threads;           /* 0 = all cores */
    lie_pattern pattern;
    lie_ray_mode rays;     /* how full visibility batches shadow rays */
    lie_visibility_mode visibility;
    const lie_vis_oracle *oracle; /* for LIE_VIS_LIE */
    unsigned aovs;         /* LIE_AOV_* bits */
    int aov_emitter;       /* complexity/patch AOVs for this emitter; -1 = all */
    int eye_only;          /* trace eye rays only (benchmark baseline) */
    unsigned ablate;       /* benchmark ablations, wrong images (lib/shade/cost.h); 0 */
    int progress;          /* progress bar on stderr if a terminal */
    const char *progress_label; /* its label (NULL: "render"), e.g. "frame 3/20" */
    lie_exact_mode exact;  /* closed-form shading and exact visibility (polylight.h) */
    int timers;            /* per-worker timers of each path into the stats (costs a clock read per pair) */
    lie_bitmask_mode bitmask; /* all samples at once for partial pairs (bitmask.h) */
    lie_light_sampler_kind sampler; /* how light samples are shared among emitters */
    uint64_t seed;         /* mixed into every per-pixel pattern: renders with two seeds are independent */
    const struct lie_lights *lights; /* the scene's lights prepared once (lie_lights_create; NULL: per call) */
} lie_render_options;

#define LIE_RENDER_WIDTH_DEFAULT 512
#define LIE_RENDER_HEIGHT_DEFAULT 512
#define LIE_LIGHT_SAMPLES_DEFAULT 100
#define LIE_MAX_DEPTH_DEFAULT 2
#define LIE_TILE 16
lie_render_options lie_render_options_default(void);

/* A scene's lights prepared for shading, once: the textured emitters'
 * distributions (their texels' light) and the emitters' closed forms
 * (polylight.h), whose cost grows with texels and triangles, not with
 * pixels.  lie_render and lie_render_tiles otherwise prepare them at every
 * call: a camera path, or a frame rendered as many calls of a few tiles
 * (lie-render under mpirun, lie-view's bands), shares one through
 * lie_render_options.lights.  It serves while the scene's content hash is
 * the one it was made for; a call with another scene (an edit since)
 * prepares its own, so a stale one costs time, never a wrong image.  It
 * holds what frames with options like `opt` use (the distributions for a
 * budgeted sampler, the closed forms where `light_samples` or `exact`
 * turn them on; opt NULL: the defaults'); a frame prepares what it
 * lacks.  The images are the same with or without it. */
typedef struct lie_lights lie_lights;
lie_status lie_lights_create(const lie_scene *s, const lie_render_options *opt, lie_lights **out, lie_error *err);
/* The same without the textured emitters' distributions, which read every
 * texel of their emissive textures (bedroom_corner's lamp: most of
 * preparing its lights): such an emitter's samples are spread by area, as
 * an untextured emitter's, and carry the texture's light.  Images made
 * with it are right on average but noisier where the texture is dark in
 * places, and are not lie_render's: a progressive viewer shows its first,
 * coarse images with it while lie_lights_create prepares the lights of
 * its refined frames. */
lie_status lie_lights_create_untextured(const lie_scene *s, const lie_render_options *opt, lie_lights **out,
                                        lie_error *err);
void lie_lights_destroy(lie_lights *l);
/* Whether l was made for s as it is now. */
int lie_lights_fit(const lie_lights *l, const lie_scene *s);

typedef struct lie_render_stats {
    uint64_t eye_rays, reflection_rays, shadow_rays, shadow_rays_skipped;
    uint64_t shading_points, light_samples;
    /* (shading point, area or punctual emitter) pairs by the path they took */
    uint64_t pairs_occluded;  /* no contribution: occluded or unlit */
    uint64_t pairs_analytic;  /* seen whole, closed form */
    uint64_t pairs_exact;     /* partial, exact back-projection */
    uint64_t pairs_blockers;  /* partial, samples against the blocker list */
    uint64_t pairs_embree;    /* samples against the whole scene */
    uint64_t pairs_unshadowed; /* seen whole, sampled shading */
    uint64_t pairs_bitmask;   /* partial, all samples at once as a bitmask (bitmask.h) */
    uint64_t exact_overflows; /* exact pairs that fell back to samples */
    uint64_t pairs_unbuilt;   /* of pairs_embree: units lie-build left out (--view, --path) */
    uint64_t points_unbuilt;  /* shading points with such a pair: pixels, at 1 spp without mirrors */
    /* with lie_render_options.timers: seconds summed over workers */
    double t_analytic, t_exact, t_blockers, t_embree, t_sampled_shading, t_bitmask;
    double seconds;
} lie_render_stats;
/* acc += w, field by field */
void lie_render_stats_add(lie_render_stats *acc, const lie_render_stats *w);

/* Render the scene from camera `cam` into a new frame (RGB + requested AOVs).
 * The result is a function of the inputs only: any thread count gives the
 * same bytes. */
lie_status lie_render(const lie_scene *s, const lie_rt *rt, const lie_camera *cam,
                      const lie_render_options *opt, lie_frame **out, lie_render_stats *stats,
                      lie_error *err);

/* The same in pieces, for renderers that share a frame's tiles out (a
 * cluster, lie-render under mpirun): the frame lie_render returns (RGB and
 * opt's AOVs, zeroed), and the tiles [first, first + count) of it, LIE_TILE
 * pixels square in row-major order, lie_render_tile_count of them.  A
 * pixel's value depends only on its own rays, so any split of the tiles
 * gives lie_render's bytes.  Other pixels of f are left as they are. */
static inline size_t lie_render_tile_count(int width, int height)
{
    return (size_t)((width + LIE_TILE - 1) / LIE_TILE) * (size_t)((height + LIE_TILE - 1) / LIE_TILE);
}
lie_status lie_render_frame_create(const lie_scene *s, const lie_render_options *opt, lie_frame **out,
                                   lie_error *err);
lie_status lie_render_tiles(const lie_scene *s, const lie_rt *rt, const lie_camera *cam,
                            const lie_render_options *opt, lie_frame *f, size_t first, size_t count,
                            lie_render_stats *stats, lie_error *err);

/* A camera's rays for a width x height image: perspective from the eye,
 * or orthographic (ymag > 0) along forward from the image plane through
 * the eye.  The image's aspect ratio wins over the camera's, so pixels stay
 * square (an orthographic view keeps its height, 2 ymag). */
typedef struct lie_view {
    lie_vec3 eye, fwd, right, up;
    float half_w, half_h;  /* tangents (perspective) or world units (orthographic) */
    int ortho;
} lie_view;
lie_view lie_view_make(const lie_camera *cam, int width, int height);
/* The ray through image point (x, y) in pixels (0, 0 the top left corner). */
void lie_view_ray(const lie_view *v, float x, float y, int width, int height, lie_vec3 *org, lie_vec3 *dir);

/* A view as OpenEXR's standard attributes describe it (ImfStandardAttributes.h,
 * ImfHeader.h): row-vector 4x4 matrices, row-major (p' = p M, translation in
 * the last row), the form lie_attr's m44f takes.
 *  - world_to_camera: RenderMan's left-handed camera space, origin at the
 *    eye, +x right and +y up in the image, +z the viewing direction;
 *  - world_to_ndc: to NDC after the divide by w, (0, 0) the display
 *    window's upper left corner and (1, 1) its lower right, z discarded
 *    (here 1/depth for a perspective view, depth for an orthographic one);
 *  - the screen window: centre (0, 0), width 2 half_w, in screen space
 *    (the image plane at distance 1 for a perspective view, camera x, y
 *    for an orthographic one). */
typedef struct lie_view_exr {
    float world_to_camera[16];
    float world_to_ndc[16];
    float screen_window_center[2];
    float screen_window_width;
} lie_view_exr;
lie_view_exr lie_view_exr_make(const lie_view *v);

/* Parse a --camera value: a camera name or index in the scene, or
 * "eye=X,Y,Z,target=X,Y,Z[,up=X,Y,Z][,fov=DEG|ortho=HEIGHT]" (ortho: an
 * orthographic view HEIGHT world units tall). */
lie_status lie_camera_parse(const lie_scene *s, const char *spec, lie_camera *out, lie_error *err);
/* What makes a camera unusable, or NULL: its eye outside the coordinate
 * range (LIE_CAMERA_COORD_MAX, lib/core/core.h), forward or up not unit
 * vectors at right angles (eye on target, up along the view), no field of
 * view.  lie_render refuses such a camera; --camera values and every frame
 * of a camera path are checked when parsed. */
const char *lie_camera_invalid(const lie_camera *c);

/* Mark in mask (n_tris entries, not cleared) every triangle seen from the
 * cameras through a width x height image (2 x 2 rays per pixel) and through
 * up to max_depth mirror bounces: the patches lie-build --view builds (§4.3.1:
 * only what the user looks at). */
lie_status lie_camera_mark_visible(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams,
                                   int width, int height, int max_depth, uint8_t *mask, lie_error *err);
/* The same views' pixels, where on each triangle they land (§4.3.3): the
 * input of lie_env_build_views.  *out: lie_pixels_destroy. */
lie_status lie_camera_pixels(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams, int width,
                             int height, int max_depth, lie_pixels **out, lie_error *err);

/* ---- camera paths (formats/camera-path.md) ---------------------------- */

typedef struct lie_camera_key {
    lie_vec3 eye, target, up;
    float fov_deg;
    int frames;
} lie_camera_key;

typedef struct lie_camera_path {
    lie_camera_key *keys;
    int n_keys;
    int smooth;            /* Catmull-Rom (1) or linear (0) */
    int n_frames;
    int first;             /* the number of frame 0 (first-frame), 0 by default */
} lie_camera_path;

/* Parse a camera path from YAML text; `name` is used in messages, which
 * carry line:col and the key.  Every frame the path interpolates is checked
 * (lie_camera_invalid): keys whose eye and target cross give a frame with
 * no view direction, and a spline can overshoot the coordinate range.  On
 * success *out is owned by the caller. */
lie_status lie_camera_path_parse(const unsigned char *text, size_t size, const char *name,
                                 lie_camera_path **out, lie_error *err);
lie_status lie_camera_path_read(const char *path, lie_camera_path **out, lie_error *err);
/* The camera of frame `frame` (0 .. n_frames - 1). */
lie_camera lie_camera_path_frame(const lie_camera_path *p, int frame);
/* Write p as YAML (formats/camera-path.md) to path ("-": stdout),
 * atomically; numbers as %.9g, so the floats read back exactly. */
lie_status lie_camera_path_write(const lie_camera_path *p, const char *path, lie_error *err);
void lie_camera_path_destroy(lie_camera_path *p);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
