/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/scene: what the files of the glTF 2.0 importer share.
 *
 * The importer (.gltf and .glb, built on tinygltf) fills the *document*
 * half of a lie_scene (scene.h); lie_scene_flatten builds the world from
 * it.  It is the trust boundary for scene files (CONTRIBUTING.md, Files):
 * every index, offset, size and count from the file is checked before it
 * is used, so flatten and the renderer can trust the document.  Its files,
 * by concern:
 *   gltf_sandbox.cpp  what tinygltf may open and decode: the URI policy
 *                     (file-system callbacks) and the image loader's limits;
 *   gltf_check.cpp    reading the file and the checks around tinygltf: the
 *                     GLB container, JSON nesting, the schema's integer
 *                     rules, required extensions; one-line messages;
 *   gltf_mesh.cpp     accessors, checked whole before any read, and meshes;
 *   gltf_import.cpp   materials and textures, nodes, cameras, lights, the
 *                     document, and lie_gltf_import;
 *   gltf_texture.cpp  the images materials use, decoded on every core;
 *   gltf_anim.cpp     skins and animations.
 * The exporter is lib/export, above lib/image, whose PNG encoder it uses.
 *
 * Errors travel inside the importer as a C++ exception (ImportError) and
 * leave lie_gltf_import as a lie_status; no exception escapes.  Every C
 * array is hung on the scene, with its count, as soon as it is allocated,
 * so lie_scene_destroy frees a half-built document too. */
#ifndef LIE_SCENE_GLTF_H
#define LIE_SCENE_GLTF_H

#include "scene/scene.h"

#include <tiny_gltf.h>

#include <climits>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <map>
#include <memory>
#include <new>
#include <string>
#include <vector>

namespace lie_gltf {

/* Largest decoded image, in pixels (8192 x 8192); a texture keeps it as 4
 * or 8 bytes a pixel (RGBA codes, lie_texture). */
const uint64_t MAX_IMAGE_PIXELS = uint64_t(1) << 26;

/* extensionsRequired we honour; any other required extension is refused. */
const char *const SUPPORTED_REQUIRED[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                         "KHR_materials_transmission", "KHR_mesh_quantization",
                                         "KHR_texture_transform"};

struct ImportError {
    lie_status status;
    std::string msg;
    int line, col;
};

/* ---- gltf_check.cpp: messages ------------------------------------------- */

/* Throws ImportError with the formatted message. */
[[noreturn]] __attribute__((format(printf, 2, 3))) void fail(lie_status status, const char *fmt, ...);
/* A string from the file, fit for a one-line message. */
std::string clean(const std::string &s, size_t max = 160);
/* The first non-empty line of a (possibly multi-line) tinygltf message. */
std::string first_line(const std::string &s);
char *dup_name(const std::string &s);
size_t mul_size(size_t a, size_t b, const char *what);

/* C arrays that lie_scene_destroy can free; n == 0 gives NULL. */
template <class T> T *alloc_array(size_t n)
{
    if (n == 0)
        return nullptr;
    void *p = calloc(n, sizeof(T));
    if (!p)
        throw std::bad_alloc();
    return static_cast<T *>(p);
}

/* An array for one of the glTF's top-level lists (skins, animations), its
 * count in an int (`what`: the list's name for the error). */
template <class T, class V> T *alloc_list(const std::vector<V> &list, int *count, const char *what)
{
    if (list.size() > size_t(INT_MAX))
        fail(LIE_ERR_LIMIT, "too many %s", what);
    T *a = alloc_array<T>(list.size());
    *count = int(list.size()); /* after the allocation: a failed one leaves an empty list */
    return a;
}

/* ---- gltf_sandbox.cpp: what tinygltf may open and decode ---------------- */

struct FsState {
    std::string prefix; /* the scene's folder as tinygltf joins it, ending in '/' */
    std::string root;   /* the same folder resolved (realpath), ending in '/' */
    bool allow_external;
    std::string refused, refused_why;            /* first URI refused by policy */
    std::map<std::string, std::string> missing;  /* URI -> why it could not be opened */
    std::string last_uri;
    lie_file_set *files; /* lie_scene_options.files: consulted first (lib/core) */
};

/* tinygltf's file-system callbacks (user data: an FsState) */
std::string fs_expand(const std::string &joined, void *user);
bool fs_exists(const std::string &path, void *user);
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user);
bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *);

struct ImageState {
    const tinygltf::Model *model;
    std::map<int, std::vector<unsigned char>> encoded; /* image -> its bytes, undecoded */
};

/* tinygltf's image loader (user data: an ImageState): checks a bufferView
 * image's range and keeps the bytes; it decodes nothing. */
bool image_load(tinygltf::Image *image, const int index, std::string *err, std::string *warn, int req_w,
                int req_h, const unsigned char *bytes, int size, void *user);
/* An image as stb decodes it: 8 or 16 bits a channel, expanded to RGBA
 * (what tinygltf's LoadImageData gives by default), in stb's own buffer. */
struct StbFree {
    void operator()(unsigned char *p) const;
};
struct Decoded {
    int width = 0, height = 0, component = 0, bits = 0;
    std::unique_ptr<unsigned char, StbFree> pixels;
    std::string why;          /* the decoder cannot read it: a warning, its slots keep their factors */
    std::exception_ptr error; /* decode_image threw: thrown again where a material first uses the image */
};

/* Decode image `index` (its glTF entry `meta`, its bytes) into *out: its
 * size from the header first (any format stb reads), refused
 * (LIE_ERR_LIMIT, thrown) past MAX_IMAGE_PIXELS before anything is
 * allocated.  An image the decoder cannot read sets out->why and leaves
 * it without pixels.  Safe to call from several threads at once (stb
 * keeps its failure reason per thread). */
void decode_image(const tinygltf::Image &meta, int index, const std::vector<unsigned char> &bytes, Decoded *out);

/* ---- gltf_texture.cpp: the images materials use, decoded on every core --- */

/* The glTF images the materials' texture slots name, those the importer
 * reads (base colour, metallic-roughness, emissive, normal, transmission),
 * in increasing order; indices out of range are left to the import to
 * refuse. */
std::vector<int> material_images(const tinygltf::Model &m);
/* Decode `images` (their bytes in `encoded`) into `decoded` on `threads`
 * workers (0: one a core), the largest first: each image by one worker,
 * so the pixels are those one decoder makes.  What decode_image throws is
 * kept in the image's Decoded, for the import to throw where a material
 * first uses it, as if decoded there. */
void decode_images(const tinygltf::Model &m, const std::map<int, std::vector<unsigned char>> &encoded,
                   const std::vector<int> &images, std::map<int, Decoded> &decoded, int threads);

/* ---- gltf_check.cpp: the file ------------------------------------------- */

/* Parse the file into `model`; `image_errors` gets why external images that
 * tinygltf skipped (with a warning) could not be opened, `encoded` every
 * image's bytes, undecoded (decode_image decodes those a material uses). */
void load_model(tinygltf::Model &model, const char *path, const lie_scene_options &opt,
                std::map<int, std::string> &image_errors, std::map<int, std::vector<unsigned char>> &encoded);

/* ---- gltf_mesh.cpp: accessors and meshes -------------------------------- */

size_t component_size(int ctype);
size_t type_components(int type);
struct Accessor {
    size_t count, ncomp, csize, stride;
    int ctype;
    bool normalized;
    const unsigned char *data;  /* element 0, or NULL: all zeros (no bufferView) */
    size_t sparse_count;
    int sparse_itype;
    const unsigned char *sparse_idx, *sparse_val;
};

Accessor check_accessor(const tinygltf::Model &m, int index, const std::string &what);
/* One component as a number. */
double component(const unsigned char *p, int ctype, bool normalized);
/* Element i of the dense part or, for sparse entries, of the values. */
template <class F> void accessor_each(const Accessor &a, F put)
{
    for (size_t i = 0; i < a.count; i++)
        for (size_t c = 0; c < a.ncomp; c++)
            put(i, c, a.data ? component(a.data + i * a.stride + c * a.csize, a.ctype, a.normalized) : 0.0);
    size_t isize = component_size(a.sparse_itype);
    for (size_t k = 0; k < a.sparse_count; k++) {
        size_t i = size_t(component(a.sparse_idx + k * isize, a.sparse_itype, false));
        for (size_t c = 0; c < a.ncomp; c++)
            put(i, c, component(a.sparse_val + (k * a.ncomp + c) * a.csize, a.ctype, a.normalized));
    }
}

void read_floats(const Accessor &a, float *dst, const std::string &what);

struct PrimPlan {
    bool skip;                   /* points or lines */
    int mode;
    Accessor pos, nrm, tan, uv, uv1, col, idx;
    bool has_nrm, has_tan, has_uv, has_uv1, has_col, has_idx;
    size_t n_verts, n_idx, n_tris;
    /* morph targets: position and normal displacements (index -1: none) */
    std::vector<Accessor> tpos, tnrm;
    std::vector<int> tpos_at, tnrm_at;
    Accessor joints, wts;        /* JOINTS_0, WEIGHTS_0 (skins) */
    bool has_skin;
};

/* Check a primitive and count its triangles; nothing is allocated yet. */
PrimPlan plan_primitive(const tinygltf::Model &m, int mi, int pi, lie_scene *s);
/* Read a planned primitive into `out` (attached to the scene already). */
void read_primitive(const PrimPlan &pl, int mi, int pi, lie_primitive *out);
/* Keep a read primitive's targets (for edits of its weights) and morph it
 * with weights w (lie_primitive_morph). */
void apply_morph(const PrimPlan &pl, const std::vector<double> &w, int mi, int pi, lie_primitive *out);
/* The weights a node's instance of mesh mi is drawn with: the node's, else
 * the mesh's, else zeros (§3.7.2.2); checked against the target count. */
std::vector<double> morph_weights(const tinygltf::Model &m, size_t mi, const std::vector<double> *node_w,
                                  const std::string &w);

/* ---- gltf_anim.cpp ------------------------------------------------------- */

void import_skins(const tinygltf::Model &m, lie_scene *s);
void import_animations(const tinygltf::Model &m, lie_scene *s);

} // namespace lie_gltf

#endif
