/* SPDX-License-Identifier: Apache-2.0 */
/* lib/export: writing a scene's document as glTF 2.0 (.gltf with its side
 * files, or one .glb).  It sits above lib/scene and lib/image: texture
 * pixels go back to their code values (lie_texture_code_value) and out
 * through lib/image's PNG encoder (lie_png_encode). */
#ifndef LIE_EXPORT_H
#define LIE_EXPORT_H

#include "core/core.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

/* Write the document as glTF 2.0, which lie_scene_load reads back into the
 * same world (the same hash when no node was removed).  The format follows
 * the name:
 *   "DIR/NAME.glb" (any case): one binary glTF (glTF 2.0 §4.4), a JSON chunk
 *     and one BIN chunk holding every vertex, index and image (PNG
 *     bufferViews with their mimeType); no other file is written.
 *   any other name, "DIR/NAME.gltf": JSON, plus DIR/NAME.bin (every vertex
 *     and index) and DIR/NAME_imgN.EXT (image N: the bytes of the file's own
 *     image, PNG, JPEG or any other, as they were) or DIR/NAME_texN.png (a
 *     texture made in memory, as its code values).  The .gltf lists those
 *     side files with the XXH3-64 hash of each (asset.extras "lie.files").
 *     A side file that exists already is replaced only when it is ours: the
 *     DIR/NAME.gltf being replaced is this exporter's and lists it with the
 *     hash of the bytes it holds now.  Otherwise (another program's file, a
 *     file edited since, no previous .gltf) the export fails with
 *     "FILE: exists (use --force to overwrite)" before writing anything,
 *     unless opt->force.  The .gltf itself is always replaced.
 * All files are complete on disk before any is renamed into place (the
 * .gltf last); on failure none is.
 * Left out: removed nodes with their subtrees, nodes outside the default
 * scene, unused meshes, cameras and lights, and textures no material
 * uses.  Every material is
 * written, so material indices stay, with its normal map, TANGENT,
 * KHR_materials_transmission, KHR_texture_transform and
 * KHR_materials_emissive_strength.  An image read from the file is
 * written as the file's bytes; a texture made otherwise (an object an edit
 * added) goes back to the code values it was decoded from (8-bit when every
 * value is an 8-bit code's, else 16-bit), in the colour space of the slot
 * that uses it.  "-"
 * (stdout) is refused. */
typedef struct lie_gltf_export_options {
    int force;           /* replace side files that are not this exporter's (above) */
    /* Called once per thing of the scene's file that the export does not
     * write, with one line saying what (the library prints nothing): what
     * the import did not read (lie_scene.not_read), animations, morph
     * targets (written as the morphed meshes).  NULL: not told. */
    void (*warn)(void *ctx, const char *msg);
    void *warn_ctx;
    lie_file_set *files; /* the run's inputs and outputs (lib/core): every side file is claimed there
                          * (lie_file_set_claim) before anything is written; the caller claims `path`.
                          * NULL: no check */
} lie_gltf_export_options;
lie_gltf_export_options lie_gltf_export_options_default(void);
/* With the default options. */
lie_status lie_gltf_export(const lie_scene *s, const char *path, lie_error *err);
/* Into `group` (lib/core): nothing is visible until the caller commits the
 * group, with whatever else the run writes.  opt NULL: the defaults. */
lie_status lie_gltf_export_group(const lie_scene *s, const char *path, const lie_gltf_export_options *opt,
                                 lie_atomic_group *group, lie_error *err);


#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
