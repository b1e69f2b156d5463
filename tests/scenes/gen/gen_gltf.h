/* SPDX-License-Identifier: Apache-2.0 */
/* tests/scenes/gen: a small glTF 2.0 writer for the bundled test scenes.
 *
 * Two parts:
 *  - gen_geom: a growable indexed triangle list (positions, normals, uvs)
 *    with helpers for the shapes the scenes use (quads, boxes, lathes).
 *    Winding is counter-clockwise seen from the front; normals are given
 *    per vertex (flat shapes duplicate vertices per face).
 *  - gen_gltf: a builder that collects materials, textures, meshes,
 *    cameras and nodes, then writes NAME.gltf + NAME.bin.  Mesh data is
 *    copied into the binary buffer when the mesh is added, so the caller
 *    may free its gen_geom right after.
 *
 * Output is a function of the calls made: no timestamps, floats as "%.9g",
 * little-endian binary, files written atomically (temporary + rename).
 * Errors are sticky: a failed allocation makes later calls return -1 and
 * gen_gltf_write report it. */
#ifndef GEN_GLTF_H
#define GEN_GLTF_H

#include <stddef.h>
#include <stdint.h>

/* ---- geometry --------------------------------------------------------- */

typedef struct gen_geom {
    float *pos;        /* 3 per vertex */
    float *nrm;        /* 3 per vertex */
    float *uv;         /* 2 per vertex (zeros unless given) */
    uint32_t n_verts, cap_verts;
    uint32_t *idx;     /* 3 per triangle */
    uint32_t n_idx, cap_idx;
    int has_uv;        /* some vertex was given a uv: write TEXCOORD_0 */
    int failed;        /* an allocation failed */
} gen_geom;

void gen_geom_init(gen_geom *m);
void gen_geom_free(gen_geom *m);          /* accepts NULL; leaves m empty */

/* Append a vertex (uv may be NULL) and return its index. */
uint32_t gen_geom_vertex(gen_geom *m, const float p[3], const float n[3],
                         const float uv[2]);
void gen_geom_tri(gen_geom *m, uint32_t a, uint32_t b, uint32_t c);

/* A planar quad p0..p3, counter-clockwise seen from its front, two
 * triangles (p0 p1 p2) (p0 p2 p3), flat normal (Newell's method).
 * uv may be NULL. */
void gen_geom_quad(gen_geom *m, const float p[4][3], const float uv[4][2]);

/* The same quad, reordered if needed so its normal points along `want`. */
void gen_geom_quad_facing(gen_geom *m, const float p[4][3], const float want[3]);

/* Axis-aligned box lo..hi, six faces pointing outward, 12 triangles. */
void gen_geom_box(gen_geom *m, const float lo[3], const float hi[3]);

/* Surface of revolution about the local +Y axis.  `prof` holds n points
 * (r, y, nr, ny): radius, height and the profile normal in the (r, y)
 * plane.  The profile runs counter-clockwise around the solid's section in
 * the (r, y) plane (r to the right, y up) -- e.g. bottom centre, rim, up the
 * side, top centre -- so faces point outward.  Zero-length segments are
 * skipped (repeat a point to start a sharp edge); segments touching the
 * axis give triangles, not degenerate quads.  `segs` steps around. */
void gen_geom_lathe(gen_geom *m, const float (*prof)[4], int n, int segs);

uint32_t gen_geom_triangles(const gen_geom *m);

/* ---- glTF builder ----------------------------------------------------- */

typedef struct gen_gltf gen_gltf;

gen_gltf *gen_gltf_create(void);          /* NULL when out of memory */
void gen_gltf_destroy(gen_gltf *g);       /* accepts NULL */

typedef struct gen_material {
    const char *name;
    float base_color[4];      /* linear */
    float metallic, roughness;
    int base_color_texture;   /* from gen_gltf_add_texture, or -1 */
    float emissive[3];        /* emissiveFactor, each component in [0, 1] */
    float emissive_strength;  /* KHR_materials_emissive_strength; 0: none */
    int double_sided;
} gen_material;

#define GEN_MATERIAL_INIT {NULL, {1, 1, 1, 1}, 0, 1, -1, {0, 0, 0}, 0, 0}

typedef struct gen_prim {
    const gen_geom *geom;
    int material;             /* index, or -1 for glTF's default material */
} gen_prim;

typedef struct gen_node {
    const char *name;         /* required, unique within the file */
    int parent;               /* node index (added before), or -1: a root */
    int mesh, camera;         /* index or -1 */
    int use_matrix;           /* write `matrix` instead of TRS */
    float matrix[16];         /* column-major, as glTF */
    float translation[3];
    float rotation[4];        /* unit quaternion x, y, z, w */
    float scale[3];
} gen_node;

#define GEN_NODE_INIT {NULL, -1, -1, -1, 0, {0}, {0, 0, 0}, {0, 0, 0, 1}, {1, 1, 1}}

/* Each returns the new object's index, or -1 after an error. */
int gen_gltf_add_material(gen_gltf *g, const gen_material *mat);
/* An external PNG image (uri relative to the .gltf) with a repeating,
 * trilinear sampler. */
int gen_gltf_add_texture(gen_gltf *g, const char *uri);
int gen_gltf_add_mesh(gen_gltf *g, const char *name, const gen_prim *prims,
                      int n_prims);
/* Perspective camera; yfov in radians; aspect 0 = not written. */
int gen_gltf_add_camera(gen_gltf *g, const char *name, float yfov,
                        float aspect, float znear, float zfar);
int gen_gltf_add_node(gen_gltf *g, const gen_node *node);

/* Triangles in the scene with every mesh instance counted. */
uint32_t gen_gltf_triangles(const gen_gltf *g);
int gen_gltf_node_count(const gen_gltf *g);

/* Write DIR/NAME.gltf and DIR/NAME.bin.  Returns 0, or -1 with a one-line
 * message in err. */
int gen_gltf_write(const gen_gltf *g, const char *dir, const char *name,
                   char *err, size_t err_size);

/* Write an 8-bit sRGB RGB PNG (rows top to bottom) atomically. */
int gen_png_write(const char *path, int width, int height,
                  const uint8_t *rgb, char *err, size_t err_size);

#endif
