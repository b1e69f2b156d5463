/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the in-memory scene.
 *
 * Two layers live in one lie_scene:
 *  - the *document*: what the glTF file says (nodes with local transforms,
 *    meshes in local space, materials, textures, cameras, punctual lights).
 *    The glTF importer (gltf_*.cpp, lib/scene/gltf.h) fills it; edits
 *    (rst-update) change it.
 *  - the *world*: the document flattened by lie_scene_flatten() into
 *    world-space triangles with a stable global index in scene order
 *    (default scene's roots in order, depth-first pre-order, each node's
 *    mesh primitives in order), emitters, world cameras, bounds and the
 *    content hash.
 * The scene owns every array it points to. */
#ifndef LIE_SCENE_H
#define LIE_SCENE_H

#include "core/core.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

#define LIE_MIRROR_ROUGHNESS 0.02f /* metallic = 1, roughness <= this: perfect mirror */

/* ---- document --------------------------------------------------------- */

typedef enum lie_wrap { LIE_WRAP_REPEAT = 0, LIE_WRAP_CLAMP = 1, LIE_WRAP_MIRROR = 2 } lie_wrap;

/* A decoded texture, row 0 at v = 0 (glTF's top): linear RGBA floats, or
 * the image's codes and the linear value of each code.  The importer keeps
 * codes (8 or 16 bits, 4 a texel): a 2048 x 2048 image is then 16 MB, not
 * the 64 MB of floats whose page faults were most of loading a textured
 * scene.  Read texels with lie_texture_texel: the values are the same
 * floats either way. */
typedef struct lie_texture {
    int width, height;
    float *rgba;  /* width * height * 4, or NULL when `codes` holds the texels */
    lie_wrap wrap_s, wrap_t;
    int image;    /* the lie_scene.images entry it was decoded from, or -1 (made in memory) */
    void *codes;  /* width * height * 4 codes of code_bits (16: two bytes, low first), or NULL */
    int code_bits;            /* 8 or 16 */
    float *code_value[2];     /* per code: colour (through the sRGB curve for an sRGB slot), alpha (linear) */
} lie_texture;

/* Texel i (row-major) as linear RGBA floats. */
static inline void lie_texture_texel(const lie_texture *t, size_t i, float out[4])
{
    if (t->rgba) {
        const float *p = t->rgba + 4 * i;
        out[0] = p[0], out[1] = p[1], out[2] = p[2], out[3] = p[3];
    } else if (t->code_bits == 8) {
        const unsigned char *c = (const unsigned char *)t->codes + 4 * i;
        out[0] = t->code_value[0][c[0]], out[1] = t->code_value[0][c[1]], out[2] = t->code_value[0][c[2]];
        out[3] = t->code_value[1][c[3]];
    } else {
        const unsigned char *c = (const unsigned char *)t->codes + 8 * i;
        for (int k = 0; k < 4; k++)
            out[k] = t->code_value[k == 3][(size_t)c[2 * k] | (size_t)c[2 * k + 1] << 8];
    }
}
/* Texels [first, first + n) as linear RGBA floats, 4 a texel into out. */
void lie_texture_texels(const lie_texture *t, size_t first, size_t n, float *out);
/* Whether t has texels (its size and pixels). */
static inline int lie_texture_has_texels(const lie_texture *t)
{
    return t && (t->rgba || (t->codes && t->code_value[0] && t->code_value[1])) && t->width > 0 && t->height > 0;
}
/* Free t's texels (not t). */
void lie_texture_free(lie_texture *t);

/* An image as the file held it, kept so that lib/export writes it back
 * byte for byte (a JPEG stays that JPEG). */
typedef struct lie_image {
    unsigned char *bytes;
    size_t size;
    char *mime;   /* "image/png", "image/jpeg", ...: the file's mimeType, else by its signature */
    char *name;   /* may be NULL */
} lie_image;

/* The texture slots of a material, each with its texture coordinate set
 * and KHR_texture_transform. */
enum {
    LIE_TEX_BASE_COLOR = 0,
    LIE_TEX_METALLIC_ROUGHNESS = 1,
    LIE_TEX_EMISSIVE = 2,
    LIE_TEX_NORMAL = 3,
    LIE_TEX_TRANSMISSION = 4,
    LIE_TEX_SLOTS = 5
};

typedef struct lie_material {
    char *name;            /* may be NULL */
    float base_color[4];   /* baseColorFactor (linear) */
    int base_color_tex;    /* texture index (sRGB-decoded at import) or -1 */
    float metallic, roughness;
    int mr_tex;            /* metallicRoughnessTexture: G roughness, B metallic; or -1 */
    float emissive[3];     /* emissiveFactor x KHR_materials_emissive_strength, nits */
    int emissive_tex;      /* sRGB-decoded, or -1 */
    int double_sided;
    /* alphaMode MASK: a point whose alpha (base colour factor x texture x
     * COLOR_0) is below alpha_cutoff is a hole, for camera, mirror and
     * shadow rays alike.  OPAQUE and BLEND are opaque (0). */
    int alpha_mask;
    float alpha_cutoff;
    /* KHR_texture_transform per texture slot (LIE_TEX_*): offset u, v,
     * rotation (radians), scale u, v as in the file (0 0 0 1 1 without the
     * extension), and the matrix they make (lie_material_tex_xf_update):
     * the texture is looked up at (xf[0] u + xf[1] v + xf[2],
     * xf[3] u + xf[4] v + xf[5]) */
    float tex_param[LIE_TEX_SLOTS][5];
    float tex_xf[LIE_TEX_SLOTS][6];
    /* The texture coordinate set each slot reads: 0 (TEXCOORD_0) or 1
     * (TEXCOORD_1); the textureInfo's texCoord, or its
     * KHR_texture_transform's. */
    int tex_set[LIE_TEX_SLOTS];
    /* normalTexture (glTF 2.0 §3.9.3): a tangent-space normal map, read
     * linear, or -1; its scale multiplies the map's X and Y.  It bends the
     * shading normal only (lie_surface_from_hit). */
    int normal_tex;
    float normal_scale;
    /* KHR_materials_transmission: the share of light that passes through
     * the surface (transmissionFactor x the texture's R), 0 without the
     * extension.  Without KHR_materials_volume the surface is thin: light
     * crossing it keeps its direction and is tinted by the base colour,
     * which is how direct light reaches what such a surface encloses
     * (lie_scene_transmittance). */
    float transmission;
    int transmission_tex;
} lie_material;

/* A material slot's texture coordinates after its KHR_texture_transform. */
static inline void lie_material_tex_xf_apply(const float xf[6], float u, float v, float *tu, float *tv)
{
    *tu = xf[0] * u + xf[1] * v + xf[2];
    *tv = xf[3] * u + xf[4] * v + xf[5];
}
/* Sets all three slots to the identity. */
void lie_material_tex_xf_identity(lie_material *m);
/* Recomputes the matrices from tex_param. */
void lie_material_tex_xf_update(lie_material *m);
/* Whether slot k's transform is the identity (by its parameters). */
int lie_material_tex_xf_is_identity(const lie_material *m, int k);

typedef struct lie_primitive {
    uint32_t n_verts;
    float *pos;            /* 3 per vertex, local space */
    float *nrm;            /* 3 per vertex or NULL (flat normals then) */
    float *uv;             /* 2 per vertex (TEXCOORD_0) or NULL */
    float *uv1;            /* 2 per vertex (TEXCOORD_1) or NULL */
    float *color;          /* 4 per vertex (COLOR_0, linear RGBA; A = 1 for RGB) or NULL */
    float *tan;            /* 4 per vertex (TANGENT: xyz unit, w = +-1 the bitangent's sign) or NULL:
                              lie_scene_flatten computes them from the texture coordinates where a
                              normal map needs them (lie_primitive_tangents) */
    uint32_t n_tris;
    uint32_t *idx;         /* 3 per triangle; strips and fans already converted */
    int material;          /* material index, or -1 for glTF's default material */
    /* Morph targets (glTF 2.0 §3.7.2.2), kept so edits can change weights:
     * base_pos / base_nrm hold the unmorphed attributes, tpos / tnrm
     * n_targets displacement sets of 3 * n_verts floats (zeros where a
     * target has none); pos and nrm are lie_primitive_morph's result.  All
     * NULL and 0 without targets. */
    int n_targets;
    float *base_pos, *base_nrm, *tpos, *tnrm;
    /* Skinning (glTF 2.0 §3.7.3): JOINTS_0 and WEIGHTS_0, 4 per vertex, or NULL. */
    uint16_t *joints;
    float *weights;
} lie_primitive;

typedef struct lie_mesh {
    char *name;
    lie_primitive *prims;
    int n_prims;
} lie_mesh;

typedef struct lie_camera_def {
    char *name;
    float yfov;            /* perspective: radians; 0 for an orthographic camera */
    float aspect;          /* 0 when the file gives none */
    float znear;
    float xmag, ymag;      /* orthographic: half the view's width and height; 0 for perspective */
    float zfar;            /* orthographic (required there); 0 for perspective (infinite) */
} lie_camera_def;

typedef enum lie_light_type {
    LIE_LIGHT_POINT = 0,
    LIE_LIGHT_SPOT = 1,
    LIE_LIGHT_DIRECTIONAL = 2
} lie_light_type;

typedef struct lie_light_def {
    char *name;
    lie_light_type type;
    float color[3];
    float intensity;       /* candela (point, spot) or lux (directional) */
    float range;           /* 0 = infinite */
    float inner_cone, outer_cone; /* radians, spot only */
} lie_light_def;

typedef struct lie_node {
    char *name;            /* may be NULL */
    int parent;            /* -1 for a root */
    lie_mat4 local;        /* TRS or matrix, as the file gives */
    int mesh, camera, light; /* indices or -1 */
    int *children;
    int n_children;
    int removed;           /* set by an edit: the node and its subtree are gone, but keep
                              their triangle slots (empty) so other indices never move */
    /* The TRS the file gives (t, r as x y z w, s), which animation channels
     * replace one property at a time; has_trs 0 when the file gives a
     * matrix (such a node cannot be animated, glTF 2.0 §3.11). */
    int has_trs;
    double trs[10];
    /* Morph weights this node's mesh is drawn with (the node's, else the
     * mesh's, else zeros), n_weights = the mesh's target count; NULL, 0 without. */
    double *weights;
    int n_weights;
    int skin;              /* skin index, or -1 */
} lie_node;

/* A skin (glTF 2.0 §3.7.3): joint nodes and their inverse bind matrices. */
typedef struct lie_skin {
    char *name;
    int *joints;
    int n_joints;
    lie_mat4 *inverse_bind; /* n_joints; identities when the file gives none */
} lie_skin;

/* Animations (glTF 2.0 §3.11). */
typedef enum lie_anim_path {
    LIE_ANIM_TRANSLATION = 0,
    LIE_ANIM_ROTATION = 1,
    LIE_ANIM_SCALE = 2,
    LIE_ANIM_WEIGHTS = 3
} lie_anim_path;

typedef enum lie_anim_interp { LIE_INTERP_LINEAR = 0, LIE_INTERP_STEP = 1, LIE_INTERP_CUBICSPLINE = 2 } lie_anim_interp;

typedef struct lie_anim_sampler {
    lie_anim_interp interp;
    uint32_t n_keys;
    float *times;          /* n_keys, strictly increasing */
    int n_comp;            /* floats per key value: 3, 4, or the target count for weights */
    float *values;         /* n_keys * n_comp; CUBICSPLINE: n_keys * 3 * n_comp (in-tangent, value, out-tangent) */
} lie_anim_sampler;

typedef struct lie_anim_channel {
    int node;
    lie_anim_path path;
    int sampler;
} lie_anim_channel;

typedef struct lie_animation {
    char *name;            /* may be NULL */
    lie_anim_sampler *samplers; int n_samplers;
    lie_anim_channel *channels; int n_channels;
    float start, end;      /* first and last key time over all samplers */
} lie_animation;

/* ---- world ------------------------------------------------------------ */

/* One (node instance, primitive): its triangles are contiguous. */
typedef struct lie_instance {
    int node, mesh, prim, material;
    uint32_t first_tri, n_tris;
    lie_mat4 world;
} lie_instance;

typedef enum lie_emitter_type {
    LIE_EMITTER_AREA = 0,
    LIE_EMITTER_POINT = 1,     /* KHR_lights_punctual point and spot */
    LIE_EMITTER_DIRECTIONAL = 2
} lie_emitter_type;

#define LIE_EMITTER_HULL_TRIS 4

typedef struct lie_emitter {
    lie_emitter_type type;
    int node;              /* node it comes from */
    int instance;          /* area: the instance; else -1 */
    /* area */
    uint32_t first_tri, n_tris;
    float area;
    float *tri_cdf;        /* n_tris, cumulative area (last = area) */
    float radiance[3];     /* emissive (before any emissive texture), nits */
    int double_sided;
    /* A few points whose convex hull contains the emitter, for shaft tests
     * (lib/lie): the corners of a bounding box oriented to the emitter's
     * plane when it has more than LIE_EMITTER_HULL_TRIS triangles; n_hull
     * 0: its triangles' vertices serve. */
    lie_vec3 hull[8];
    int n_hull;
    /* Planar: every triangle lies in one plane (within rounding) and faces
     * one way, or the emitter is double-sided.  Then plane_u, plane_v and
     * plane_n are an orthonormal frame with plane_n the emitters' facing
     * and plane_o the centre of its vertices' extent in the plane; light
     * samples carry coordinates in it (lib/shade). */
    int planar;
    lie_vec3 plane_o, plane_u, plane_v, plane_n;
    float plane_ext[4];    /* its vertices' extent in the frame: s min, max, t min, max */
    /* punctual */
    lie_vec3 position;
    lie_vec3 direction;    /* where the light points (spot, directional), unit */
    float intensity[3];    /* colour x intensity: cd (point/spot) or lux (directional) */
    float cos_inner, cos_outer; /* spot cone; point: both -2 (no cone) */
    float range;           /* 0 = infinite */
    /* its clusters: s->clusters[first_cluster .. first_cluster + n_clusters) */
    int first_cluster, n_clusters;
} lie_emitter;

/* A cluster: a part of an emitter that LIEs see as a visibility source of
 * its own (lib/lie builds one unit per triangle and cluster).  Clustering
 * partitions visibility only: the renderer samples the emitter whole, as
 * ever, and sends each sample's shadow test to its triangle's cluster.  An
 * area emitter of few triangles, or compact, is one cluster; a large one is
 * split in space (lib/scene/cluster.c).  A punctual emitter is one cluster
 * without triangles. */
#define LIE_CLUSTER_MAX 16     /* clusters per emitter at most */
#define LIE_CLUSTER_MIN_TRIS 16 /* triangles per cluster at least */
typedef struct lie_cluster {
    int emitter;
    uint32_t first, n_tris; /* its triangles: s->cluster_tris[first .. first + n_tris), ascending */
    float area;
    /* like lie_emitter's hull: a box's corners, or (n_hull 0) its vertices */
    lie_vec3 hull[8];
    int n_hull;
    /* Dark: its emissive texture is black wherever the renderer can look it
     * up on these triangles, so no sample on them carries light and none of
     * its pairs is built (unlit). */
    int dark;
} lie_cluster;

typedef struct lie_camera {
    char *name;            /* node name, else camera name; may be NULL */
    lie_vec3 eye, forward, up; /* unit forward and up, orthogonal */
    float yfov;            /* radians */
    float aspect;          /* 0 = the image's */
    float ymag;            /* > 0: orthographic, half the view's height in world units (yfov unused) */
} lie_camera;

typedef struct lie_scene_stats {
    uint32_t points_skipped, lines_skipped; /* primitives of these modes */
    uint32_t prims_without_material;
    uint32_t degenerate_tris;  /* zero-area triangles (kept, never lit) */
    uint32_t normals_generated; /* primitives with flat normals */
} lie_scene_stats;

#define LIE_SCENE_WARNINGS_MAX 8
typedef struct lie_scene {
    char *path;            /* as given to lie_scene_load */
    /* document */
    lie_node *nodes;          int n_nodes;
    int *roots;               int n_roots;   /* default scene's root nodes */
    lie_mesh *meshes;         int n_meshes;
    lie_material *materials;  int n_materials;
    lie_texture *textures;    int n_textures;
    lie_image *images;        int n_images;   /* the images textures were decoded from */
    /* What the import did not read (an extension, occlusionTexture, a
     * third texture coordinate set, ...), one short phrase each: it warned
     * of each once, and lib/export says each is not written. */
    char **not_read;          int n_not_read;
    lie_camera_def *camera_defs; int n_camera_defs;
    lie_light_def *light_defs;   int n_light_defs;
    lie_skin *skins;          int n_skins;
    lie_animation *animations; int n_animations;
    /* world (lie_scene_flatten) */
    lie_instance *instances;  int n_instances;
    uint32_t n_tris;
    lie_vec3 *tri_p;          /* 3 per triangle: world positions, CCW = front */
    lie_vec3 *tri_n;          /* 3 per triangle: unit shading normals */
    float *tri_uv;            /* 6 per triangle */
    float *tri_uv1;           /* TEXCOORD_1, 6 per triangle (TEXCOORD_0's where a primitive has
                               * none); NULL when no primitive has it */
    float *tri_color;         /* 12 per triangle (COLOR_0 RGBA per corner, 1 where a primitive
                                 has none), or NULL when no primitive has COLOR_0 */
    float *tri_tan;           /* 12 per triangle: world tangent xyz and handedness w per corner
                                 (zeros on triangles without a normal map), or NULL when no
                                 material has a normal map */
    lie_vec3 *tri_ng;         /* unit geometric normal (front side) */
    float *tri_area;
    int32_t *tri_material;    /* -1: default material (see lie_scene_material) */
    uint32_t *tri_instance;
    uint8_t *tri_removed;     /* 1: slot of a removed node (an empty triangle) */
    lie_emitter *emitters;    int n_emitters;
    int32_t *tri_emitter;     /* area emitter of each triangle, or -1 */
    lie_cluster *clusters;    int n_clusters;  /* emitter by emitter, in emitter order */
    uint32_t *cluster_tris;   /* every cluster's triangles (see lie_cluster) */
    float *cluster_cdf;       /* beside cluster_tris: cumulative area within its cluster */
    int32_t *tri_cluster;     /* cluster of each emitter triangle, or -1 */
    int cluster_max;          /* lie_scene_options.emitter_clusters, resolved (0: 1) */
    lie_camera *cameras;      int n_cameras;
    lie_box3 bounds;
    float max_tri_area;
    uint64_t hash;            /* content hash of the world (geometry, materials, emitters) */
    lie_scene_stats stats;
    /* What the import tolerated and a tool should tell (the library prints
     * nothing): one line each, without the file name, e.g. an image the
     * decoder cannot read, whose texture slots fall back to their factors.
     * n_warnings counts them all; the first LIE_SCENE_WARNINGS_MAX are kept. */
    int n_warnings;
    char warnings[LIE_SCENE_WARNINGS_MAX][256];
} lie_scene;

typedef struct lie_scene_options {
    int allow_external_uris; /* let URIs leave the scene's folder */
    uint64_t max_triangles;  /* refuse larger scenes before allocating */
    /* NULL: read the file system.  Else the glTF and every buffer and image
     * it references are taken from this set when it holds them (lib/core,
     * lie_file_set); the URI policy applies the same either way. */
    lie_file_set *files;
    /* Clusters an area emitter's lit triangles may be split into in space
     * (lib/scene/cluster.c), 1..LIE_CLUSTER_MAX; 0 means the default, 1:
     * measured, a spatial split costs more than it saves
     * (docs/measurements.md, "Emitters in clusters").  lie-build --emitter-clusters sets it; a cache
     * records each emitter's cluster count, and lie_cache_load_scene loads
     * with the largest of them when this is 0, which reproduces the
     * partition (its digest is checked). */
    int emitter_clusters;
    /* Threads decoding the textures' images and converting their pixels
     * (0: one a core); the scene is the same for any count. */
    int threads;
} lie_scene_options;
#define LIE_SCENE_MAX_TRIANGLES_DEFAULT 50000000u
lie_scene_options lie_scene_options_default(void);

/* Load a .gltf or .glb (by content, not extension) and flatten it.
 * On success *out is owned by the caller (lie_scene_destroy). */
lie_status lie_scene_load(const char *path, const lie_scene_options *opt, lie_scene **out,
                          lie_error *err);
void lie_scene_destroy(lie_scene *s);

/* (Re)compute the world from the document: instances, triangles, normals,
 * emitters, cameras, bounds, hash.  Called by lie_scene_load and after edits. */
lie_status lie_scene_flatten(lie_scene *s, lie_error *err);

/* The material of a triangle (glTF's default material for -1). */
const lie_material *lie_scene_material(const lie_scene *s, int32_t index);

/* The texture coordinates material slot k (LIE_TEX_*) looks its texture up
 * at, at barycentrics (b1, b2) of triangle tri: its set's coordinates,
 * through its KHR_texture_transform. */
void lie_scene_slot_uv(const lie_scene *s, const lie_material *m, int k, uint32_t tri, float b1, float b2,
                       float *u, float *v);

/* A point on area emitter e from (u1, u2) in [0,1)^2: a triangle picked in
 * proportion to area (u1's position inside its CDF interval reused, so
 * strata stay strata), then an area-uniform point on it.  Returns the
 * triangle; writes position, unit front normal and barycentrics. */
uint32_t lie_emitter_point(const lie_scene *s, int e, float u1, float u2, lie_vec3 *p, lie_vec3 *n,
                           float *b1, float *b2);

/* ---- the emitter interface -----------------------------------------------
 * Everything lie-build, the ray segment trees, the cache tools and the
 * renderer ask of an emitter, in one place, as pbrt-v4 gives each light one
 * interface.  Each type implements it in its own file (lib/scene/emitter_area.c,
 * emitter_point.c for point and spot lights, emitter_directional.c), and
 * lib/scene/emitter.c dispatches to it in one table; no other code switches
 * on lie_emitter_type.  A new emitter type is a new file, a line in that
 * table, its creation in the import (lib/scene/scene.c) and its code in the
 * cache format (formats/lie-cache.md); docs/architecture.md. */
const char *lie_emitter_type_name(lie_emitter_type t);
/* Whether triangle tri is one of the emitter's own (punctual emitters own none). */
static inline int lie_emitter_owns(const lie_emitter *em, uint32_t tri)
{
    return tri - em->first_tri < em->n_tris;
}

/* -- geometry: shafts, hulls, culls (lib/lie, lib/rst, lib/shade) -- */
/* How many points lie_emitter_hull_points writes at most. */
int lie_emitter_hull_cap(const lie_emitter *em);
/* The emitter's points of the hull of its pair with patch V (world
 * corners): points whose convex hull holds every point a shadow segment
 * from the patch aims at (for a directional light, the patch moved `far`
 * against its direction).  Returns how many were written. */
int lie_emitter_hull_points(const lie_scene *s, int e, const lie_vec3 V[3], float far, lie_vec3 *out);
/* A normal every front of the emitter faces, or NULL (for shaft tests). */
const lie_vec3 *lie_emitter_facing(const lie_scene *s, int e);
/* The point a shadow segment from p aims at, for sample (u1, u2) in
 * [0,1)^2: *q, and *n its surface's front normal (area emitters; else 0).
 * *one_sided is set when only segments reaching the front count.  Returns
 * the emitter's triangle holding q, or UINT32_MAX for a punctual one. */
uint32_t lie_emitter_target(const lie_scene *s, int e, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                            lie_vec3 *n, int *one_sided);
/* 0 when no point of patch V (on triangle tri, with geometric normal ng
 * and shaded from both sides when two_sided) can receive light from any
 * point of emitter e with a non-zero geometric term; 1 when it may. */
int lie_emitter_can_reach(const lie_scene *s, int e, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng, int two_sided);
/* Points whose convex hull holds every point of the emitter: *pts points
 * into the scene (not copied); returns how many, 0 for a light at infinity. */
int lie_emitter_extent(const lie_scene *s, int e, const lie_vec3 **pts);
/* A sphere holding the emitter, as x, y, z, r (lie_bound_sphere of its
 * vertices for an area emitter, radius 0 for a point light); r < 0 for a
 * light at infinity, which no sphere holds. */
void lie_emitter_bounding_sphere(const lie_scene *s, int e, float sphere[4]);

/* -- radiance and sampling (lib/shade) -- */
/* One point of an emitter (lie_emitter_sample). */
typedef struct lie_emitter_sample {
    lie_vec3 p;        /* area, point: the point; directional: the unit direction towards the light */
    lie_vec3 n;        /* area: its surface's front normal; punctual: where the light points */
    float le[3];       /* area: radiance at p (the emissive texture applied), nits;
                          point and spot: intensity, cd; directional: illuminance, lux */
    float inv_pdf;     /* 1 / the density of p in area measure: the area of an area emitter; 1 for a delta light */
    uint32_t tri;      /* area: the triangle holding p; else UINT32_MAX */
} lie_emitter_sample;
/* Light arriving at a point from a delta light (lie_emitter_light_at). */
typedef struct lie_emitter_incident {
    lie_vec3 wi;       /* unit direction towards the light */
    float dist;        /* distance to it (directional: the `far` given) */
    float li[3];       /* intensity x distance falloff x spot cone x range window (KHR_lights_punctual):
                          the irradiance at normal incidence */
} lie_emitter_incident;
/* Whether the emitter is a delta light (a point, a spot, a direction): one
 * sample says everything, lie_emitter_light_at gives it in closed form. */
int lie_emitter_is_delta(const lie_emitter *em);
/* How many light samples of a frame asking n per emitter it takes: n, or 1
 * for a delta light. */
static inline int lie_emitter_sample_count(const lie_emitter *em, int n)
{
    return lie_emitter_is_delta(em) ? 1 : n;
}
/* Sample (u1, u2) in [0,1)^2 of the emitter: an area emitter's triangle in
 * proportion to area (lie_emitter_point), then a uniform point; a delta
 * light's only point. */
void lie_emitter_sample_point(const lie_scene *s, int e, float u1, float u2, lie_emitter_sample *out);
/* The density in area measure of lie_emitter_sample_point at a point of the
 * emitter: 1 / area; 0 for a delta light (as pbrt's PDF_Li). */
float lie_emitter_pdf(const lie_scene *s, int e);
/* Whether the emitter's radiance is one colour over its whole surface (an
 * area emitter without an emissive texture); 0 for a delta light. */
int lie_emitter_uniform(const lie_scene *s, int e);
/* A delta light seen from o: direction, distance (a directional light's is
 * `far`), and radiant intensity after falloff; 0 (and *out zeroed) for an
 * area emitter, whose light is sampled. */
int lie_emitter_light_at(const lie_scene *s, int e, lie_vec3 o, float far, lie_emitter_incident *out);
/* An emitter that closed forms can integrate: triangles of one radiance
 * (lib/shade/polylight.c takes them plane by plane: the edge sum, exact
 * shadows by back-projection, LTC). */
typedef struct lie_emitter_polygon {
    uint32_t first_tri, n_tris; /* its triangles */
    int two_sided;
    float radiance[3];
    int planar;                 /* all in one plane (lie_emitter.planar), whose frame follows */
    lie_vec3 o, u, v, n;        /* the plane's frame (lie_emitter.plane_*) when planar */
} lie_emitter_polygon;
/* 1 and *out filled when the emitter is such a set of triangles (an area
 * emitter without an emissive texture, planar or not), else 0. */
int lie_emitter_polygon_of(const lie_scene *s, int e, lie_emitter_polygon *out);
/* Emitted power in watts per channel (photometric units as given),
 * for choosing among lights in proportion to power: area pi Le A (twice for
 * two sides; the emissive factor, an emissive texture's mean not applied),
 * point 4 pi I, spot 2 pi (1 - (cos_inner + cos_outer) / 2) I (pbrt-v4's
 * SpotLight::Phi), directional pi r^2 E with r the scene's bounding radius. */
void lie_emitter_power(const lie_scene *s, int e, float phi[3]);

/* ---- clusters (lib/scene/cluster.c) --------------------------------------
 * The same questions asked of one cluster c (lie_cluster): lib/lie builds
 * its units per cluster.  For the single cluster of an emitter they are the
 * emitter's answers exactly. */
int lie_cluster_hull_cap(const lie_scene *s, int c);
int lie_cluster_hull_points(const lie_scene *s, int c, const lie_vec3 V[3], float far, lie_vec3 *out);
const lie_vec3 *lie_cluster_facing(const lie_scene *s, int c);
/* A segment's target on cluster c: a point picked by area on its triangles. */
uint32_t lie_cluster_target(const lie_scene *s, int c, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                            lie_vec3 *n, int *one_sided);
int lie_cluster_can_reach(const lie_scene *s, int c, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng, int two_sided);
/* The light cluster c sends to a Lambert receiver at p with normal n (and
 * -n too when two_sided), unshadowed, as the luminance of the irradiance:
 * an area cluster's triangles by the closed form (Lambert's edge sum,
 * clipped to the receiver's hemisphere) times its emitter's radiance (an
 * emissive texture's variation not counted), a delta light's
 * lie_emitter_light_at times the cosine (`far`: a directional light's
 * reach).  What lib/lie's cost model weighs a unit's light samples by. */
double lie_cluster_unshadowed(const lie_scene *s, int c, lie_vec3 p, lie_vec3 n, int two_sided, float far);
/* A digest of everything lie_cluster_unshadowed reads of every cluster
 * (emission, punctual parameters, the triangles' positions) and of which
 * emissive texture an area emitter has: equal digests, equal light at
 * every point.  lib/update watches it. */
uint64_t lie_scene_light_digest(const lie_scene *s);
/* Partition every emitter into clusters (s->clusters and the arrays beside
 * it), a function of each emitter's own triangles alone.  Called by
 * lie_scene_flatten; LIE_ERR_NOMEM. */
lie_status lie_scene_cluster(lie_scene *s);
/* A 32-bit digest of emitter e's partition (its clusters' triangles, in
 * order); 0 for an emitter of one cluster.  Caches record it, so a cache
 * is never read against another clustering. */
uint32_t lie_scene_cluster_digest(const lie_scene *s, int e);

/* Texel index i of a row or column of n texels, wrapped as `wrap` wraps. */
int lie_texture_wrap_index(long long i, int n, lie_wrap wrap);
/* Bilinear lookup with the texture's wrap modes; rgba out. */
void lie_texture_sample(const lie_texture *t, float u, float v, float rgba[4]);
/* The linear value the importer decodes code i of an image with `levels`
 * code values (256 or 65536) to, through the sRGB transfer curve
 * (IEC 61966-2-1) when `srgb`; the exporter (lib/export) inverts exactly
 * this. */
float lie_texture_code_value(size_t i, size_t levels, int srgb);

/* Whether the point (b1, b2) of triangle tri is solid: always, unless its
 * material is alphaMode MASK and the alpha there is below the cutoff. */
int lie_scene_solid_at(const lie_scene *s, uint32_t tri, float b1, float b2);

/* Whether light passes through surfaces of material m
 * (KHR_materials_transmission with a factor above 0).  Such surfaces block
 * no shadow segment: lib/rt leaves them out of every occlusion query and
 * shaft, and the renderer multiplies each segment's light by the
 * lie_scene_transmittance of those it crosses (lie_rt_transmittance). */
static inline int lie_material_transmits(const lie_material *m) { return m->transmission > 0.0f; }
/* The share of light, per channel, that crosses transmissive triangle tri
 * at barycentrics (b1, b2): a thin surface (no KHR_materials_volume) whose
 * transmission lobe is tinted by its base colour, glTF's dielectric mix
 * (KHR_materials_transmission): (1 - metallic) x transmission (factor x
 * the texture's R) x base colour (factor x texture x COLOR_0).  Refraction
 * and the Fresnel share reflected are not modelled: a thin wall keeps a
 * ray's direction, and direct light is what this renderer computes.  A
 * hole of an alpha-masked surface passes everything (1). */
void lie_scene_transmittance(const lie_scene *s, uint32_t tri, float b1, float b2, float rgb[3]);

/* Camera by name (node or camera name) or by "#index"/decimal index into
 * s->cameras; NULL or "" gives the first camera, or the default camera when
 * the scene has none. */
lie_status lie_scene_camera(const lie_scene *s, const char *spec, lie_camera *out, lie_error *err);
/* The default camera: looks at the bounds' centre from +z+y of the box,
 * 45 degree vertical fov, framing the whole bounding sphere. */
lie_camera lie_scene_default_camera(const lie_scene *s);

/* ---- building scenes in memory (tests, edits that add objects) -------- */

/* An empty scene; `path` (may be NULL) names it in messages. */
lie_scene *lie_scene_new(const char *path);
/* Each returns the new element's index, or -1 when out of memory.  Arrays
 * and strings are copied.  The world is stale until lie_scene_flatten(). */
int lie_scene_add_material(lie_scene *s, const lie_material *m);
/* A deep copy of src's arrays into *out (everything else copied as is);
 * 0 when out of memory, and then nothing is left allocated. */
int lie_primitive_copy(const lie_primitive *src, lie_primitive *out);
/* Per-vertex tangents for a normal map read through texture coordinate set
 * `set` (0 or 1), where the primitive gives none (lib/scene/tangent.c says
 * how, and how they relate to MikkTSpace): 4 floats per vertex into out
 * (xyz unit, w = +-1).  0 when out of memory. */
int lie_primitive_tangents(const lie_primitive *p, int set, float *out);
/* Frees a primitive's arrays (not the struct). */
void lie_primitive_free(lie_primitive *p);
/* pos (and nrm) = base + the weighted target displacements, target by
 * target in order, skipping zero weights (the importer's arithmetic, so a
 * file's weights and the same weights set by an edit give the same bits).
 * Extra weights are ignored, missing ones are zero.  Without targets this
 * does nothing.  LIE_ERR_FORMAT when a morphed position is not finite. */
lie_status lie_primitive_morph(lie_primitive *p, const double *w, int n_w);

/* ---- animation (animate.c) ---------------------------------------------- */

/* A pose: per node, its TRS and weights at some time.  Only the nodes an
 * animation targets are marked (trs_set, weights_set). */
typedef struct lie_pose {
    int n_nodes;
    double *trs;           /* 10 per node: t, r (x y z w), s */
    unsigned char *trs_set;    /* per node: bit path (1 << LIE_ANIM_*) set by a channel */
    double **weights;      /* per node: n_weights of the node, or NULL */
    unsigned char *weights_set;
} lie_pose;

/* Evaluate animation a at time t (seconds from the animation's start,
 * clamped to its range): LINEAR (slerp for rotations), STEP and
 * CUBICSPLINE as glTF 2.0 §3.11 and Appendix C say.  Untargeted properties
 * keep the node's own.  *out owned by the caller (lie_pose_destroy). */
lie_status lie_animation_pose(const lie_scene *s, int a, double t, lie_pose **out, lie_error *err);
void lie_pose_destroy(lie_pose *p);
/* The local matrix of a node's TRS (10 doubles as in lie_node.trs). */
lie_mat4 lie_node_trs_matrix(const double trs[10]);
/* A node's world matrix from the nodes' local ones: its parents' times its
 * own, as lie_scene_flatten composes them (a chain longer than n_nodes, a
 * cycle, stops there). */
lie_mat4 lie_node_world_matrix(const lie_scene *s, int node);
/* Animation by name or index; -1 when none matches. */
int lie_scene_find_animation(const lie_scene *s, const char *spec);
/* Whether node n is the default scene's (reachable from its roots). */
int lie_scene_node_in_scene(const lie_scene *s, int n);

int lie_scene_add_mesh(lie_scene *s, const char *name, const float *pos, const float *nrm,
                       const float *uv, uint32_t n_verts, const uint32_t *idx, uint32_t n_tris,
                       int material);
int lie_scene_add_light_def(lie_scene *s, const lie_light_def *l);
/* parent -1 makes a root of the default scene. */
int lie_scene_add_node(lie_scene *s, const char *name, int parent, const lie_mat4 *local, int mesh,
                       int camera, int light);
/* A light for a scene without emitters (lie-render --default-light), added to the document
 * as a root node named "lie-default-light" and the world flattened again:
 * HEADLIGHT a point light at cam's eye giving 1 lux at the bounds' centre; SUN a directional
 * light of 1 lux from above (+y, tilted 30 degrees toward +z).  The scene's content hash
 * changes with it, so a cache of the scene without it does not match. */
typedef enum lie_default_light { LIE_DEFAULT_LIGHT_HEADLIGHT = 1, LIE_DEFAULT_LIGHT_SUN = 2 } lie_default_light;
lie_status lie_scene_add_default_light(lie_scene *s, lie_default_light kind, const lie_camera *cam, lie_error *err);
/* A material with glTF's defaults (white, metallic 1, roughness 1). */
lie_material lie_material_default(void);

/* Internal to lib/scene: the importer (gltf_*.cpp, lib/scene/gltf.h) fills the document. */
lie_status lie_gltf_import(lie_scene *s, const char *path, const lie_scene_options *opt,
                           lie_error *err);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
