/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/export: what the glTF exporter's files share.
 *
 * lie_gltf_export builds a tinygltf::Model from the document, lets tinygltf
 * serialise it, and adds the one external buffer itself (tinygltf's stream
 * writer embeds buffers as data URIs).  Everything the world hash covers
 * travels exactly: vertex data as the same floats; matrices as the same
 * doubles (nlohmann prints a double so that it reads back bit for bit);
 * float fields as the shortest decimal the importer turns back into the
 * same float; texture pixels as the code values they were decoded from
 * (lie_texture_code_value), encoded by lib/image (lie_png_encode).
 *   document.cpp  the document as a tinygltf::Model: meshes, materials,
 *                 cameras, lights, nodes, skins;
 *   textures.cpp  the textures a material uses, as PNG code values;
 *   write.cpp     the JSON and the GLB container, side files, atomic
 *                 output, and the public functions.
 * Errors travel as a C++ exception (ExportError) and leave
 * lie_gltf_export_group as a lie_status. */
#ifndef LIE_EXPORT_INTERNAL_H
#define LIE_EXPORT_INTERNAL_H

#include "export/export.h"

#include <tiny_gltf.h>

#include <charconv>
#include <map>
#include <string>
#include <vector>

namespace lie_export {

struct ExportError {
    lie_status status;
    std::string msg;
};

struct Png {
    std::string path, uri; /* where it goes (.gltf), as the .gltf names it */
    int width, height, bits, channels;
    std::vector<uint8_t> b8;
    std::vector<uint16_t> b16;
    std::vector<unsigned char> bytes; /* the PNG file */
};

struct Export {
    const lie_scene &s;
    std::string dir, stem; /* "DIR/" (or ""), NAME */
    bool glb;              /* one .glb: images are bufferViews of the one buffer */
    tinygltf::Model m;
    std::vector<unsigned char> bin;
    std::vector<Png> pngs;
};

/* ---- document.cpp ------------------------------------------------------- */

/* The double with the fewest significant decimal digits near `exact` that
 * `ok` accepts, else `exact`: JSON stays readable (0.1, not
 * 0.10000000149011612) and reads back to what the importer must compute. */
template <class F> double shortest(double exact, F ok)
{
    for (int digits = 1; digits <= 17; digits++) {
        char buf[64];
        std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, exact, std::chars_format::general, digits);
        double d;
        if (r.ec == std::errc() && std::from_chars(buf, r.ptr, d).ec == std::errc() && ok(d))
            return d;
    }
    return exact;
}


/* A float field: the importer's float() of the value is f again. */
double short_float(float f);
/* Append bytes as a new bufferView (4-byte aligned); returns its index. */
int add_view(Export &ex, const void *data, size_t bytes, int target);
/* Fill ex.m from the scene. */
void export_document(Export &ex);

/* ---- textures.cpp ------------------------------------------------------- */

/* A file name as a URI path segment (RFC 3986 unreserved characters kept). */
std::string uri_escape(const std::string &name);
/* Textures: one glTF texture (and PNG) per (lie_texture, colour space) that
 * a material uses, in texture order, sRGB before linear.  Returns the map
 * texture * 2 + srgb -> glTF texture. */
std::map<int, int> export_textures(Export &ex);

} // namespace lie_export

#endif
