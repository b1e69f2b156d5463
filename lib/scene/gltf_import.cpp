/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the glTF importer's document (lib/scene/gltf.h): materials and
 * their textures, nodes, cameras, lights and the default scene, then
 * lie_gltf_import, which runs every part of the import in order.
 * Size: the document's parts in import order; materials and textures are
 * the longest, and share the Import state with the rest. */
#include "scene/gltf.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>

namespace lie_gltf {

/* ---- textures and materials -------------------------------------------- */

struct Import {
    const tinygltf::Model &m;
    lie_scene *s;
    const std::map<int, std::string> &image_errors; /* from load_model */
    const std::map<int, std::vector<unsigned char>> &encoded; /* from load_model: images' bytes */
    std::map<int, Decoded> decoded;  /* those decoded so far (decode_images, decode_image) */
    std::set<int> used;              /* images a texture was made from so far */
    std::map<int, int> codes_of;     /* glTF image -> the texture that took its decoded codes */
    std::map<int, int> texture_of; /* glTF texture * 2 + srgb -> s->textures index */
    std::map<int, int> image_of;   /* glTF image -> s->images index */
    std::set<int> warned;          /* images warned about */
};

/* A warning for the tools to print (lie_scene.warnings). */
void scene_warn(lie_scene *s, const std::string &msg)
{
    if (s->n_warnings < LIE_SCENE_WARNINGS_MAX)
        snprintf(s->warnings[s->n_warnings], sizeof s->warnings[0], "%s", msg.c_str());
    if (s->n_warnings < INT_MAX)
        s->n_warnings++;
}

/* Something the import does not read: warned of once, and kept in
 * s->not_read for lib/export to say it is not written. */
void not_read(lie_scene *s, const std::string &what, const std::string &why, bool warn = true)
{
    for (int i = 0; i < s->n_not_read; i++)
        if (what == s->not_read[i])
            return;
    char **grown = static_cast<char **>(realloc(s->not_read, sizeof *grown * (size_t(s->n_not_read) + 1)));
    if (!grown)
        throw std::bad_alloc();
    s->not_read = grown;
    s->not_read[s->n_not_read] = dup_name(what);
    if (!s->not_read[s->n_not_read])
        throw std::bad_alloc();
    s->n_not_read++;
    if (warn)
        scene_warn(s, "not read: " + what + " (" + why + ")");
}

/* The file's bytes of glTF image `source`, kept in s->images once. */
int keep_image(Import &im, int source)
{
    auto found = im.image_of.find(source);
    if (found != im.image_of.end())
        return found->second;
    auto enc = im.encoded.find(source);
    if (enc == im.encoded.end() || enc->second.empty())
        return -1;
    const tinygltf::Image &meta = im.m.images[size_t(source)];
    const std::vector<unsigned char> &b = enc->second;
    std::string mime = meta.mimeType;
    if (mime.empty())
        mime = b.size() >= 8 && memcmp(b.data(), "\x89PNG", 4) == 0 ? "image/png"
               : b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF ? "image/jpeg"
                                                                               : "application/octet-stream";
    lie_image &img = im.s->images[im.s->n_images];
    img.bytes = alloc_array<unsigned char>(b.size());
    img.size = b.size();
    memcpy(img.bytes, b.data(), b.size());
    img.mime = dup_name(mime);
    if (!img.mime)
        throw std::bad_alloc();
    img.name = meta.name.empty() ? nullptr : dup_name(meta.name);
    int index = im.s->n_images++;
    im.image_of[source] = index;
    return index;
}

lie_wrap wrap_mode(int mode, const std::string &what)
{
    switch (mode) {
    case TINYGLTF_TEXTURE_WRAP_REPEAT: return LIE_WRAP_REPEAT;
    case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return LIE_WRAP_CLAMP;
    case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return LIE_WRAP_MIRROR;
    default: fail(LIE_ERR_FORMAT, "%s: unknown wrap mode %d", what.c_str(), mode);
    }
}

/* The lie_texture for glTF texture `ti` in a colour space, made on first use. */
int texture_for(Import &im, int ti, bool srgb, const std::string &what)
{
    const tinygltf::Model &m = im.m;
    if (ti < 0 || size_t(ti) >= m.textures.size())
        fail(LIE_ERR_FORMAT, "%s: texture %d out of range", what.c_str(), ti);
    auto found = im.texture_of.find(ti * 2 + srgb);
    if (found != im.texture_of.end())
        return found->second;

    const tinygltf::Texture &tex = m.textures[size_t(ti)];
    std::string tw = "texture " + std::to_string(ti);
    if (tex.source < 0)
        fail(LIE_ERR_UNSUPPORTED, "%s has no image source (only PNG/JPEG sources are supported)", tw.c_str());
    if (size_t(tex.source) >= m.images.size())
        fail(LIE_ERR_FORMAT, "%s: image %d out of range", tw.c_str(), tex.source);
    std::string iw = "image " + std::to_string(tex.source);
    auto dec = im.decoded.find(tex.source);
    if (dec == im.decoded.end()) { /* decode_images decodes the images materials name; any other here */
        dec = im.decoded.emplace(tex.source, Decoded()).first;
        auto enc = im.encoded.find(tex.source);
        if (enc != im.encoded.end())
            decode_image(m.images[size_t(tex.source)], tex.source, enc->second, &dec->second);
    }
    const Decoded &img = dec->second;
    if (im.used.insert(tex.source).second) { /* its first use: what its decoding found is said here */
        if (img.error)
            std::rethrow_exception(img.error);
        if (!img.why.empty()) {
            /* An image the decoder cannot read (a corrupt PNG, a KTX2 or
             * WebP named as a plain source) is not the whole scene's
             * failure: the slots using it fall back to their factors, as
             * Blender and three.js do, with a warning.  Required extensions
             * are refused earlier. */
            im.warned.insert(tex.source);
            scene_warn(im.s, img.why + "; its textures fall back to their factors");
            not_read(im.s, iw, "the decoder cannot read it", false); /* warned of just above */
        }
    }
    if (im.warned.count(tex.source))
        return -1; /* no texture: the slot keeps its factor */
    if ((!img.pixels && !im.codes_of.count(tex.source)) || img.width <= 0 || img.height <= 0) {
        auto e = im.image_errors.find(tex.source);
        if (e != im.image_errors.end())
            fail(LIE_ERR_IO, "%s %s", iw.c_str(), e->second.c_str());
        fail(LIE_ERR_FORMAT, "%s has no decoded pixels", iw.c_str());
    }
    size_t bytes = img.bits == 8 ? 1 : img.bits == 16 ? 2 : 0;
    if (!bytes || img.component != 4) /* decode_image expands every image to RGBA */
        fail(LIE_ERR_UNSUPPORTED, "%s: %d-bit, %d-channel images are not supported", iw.c_str(), img.bits,
             img.component);
    size_t w = size_t(img.width), h = size_t(img.height);
    if (uint64_t(w) * h > MAX_IMAGE_PIXELS)
        fail(LIE_ERR_LIMIT, "%s is %zux%zu, beyond the limit of %llu pixels", iw.c_str(), w, h,
             (unsigned long long)MAX_IMAGE_PIXELS);

    lie_wrap ws = LIE_WRAP_REPEAT, wt = LIE_WRAP_REPEAT;
    if (tex.sampler >= 0) {
        if (size_t(tex.sampler) >= m.samplers.size())
            fail(LIE_ERR_FORMAT, "%s: sampler %d out of range", tw.c_str(), tex.sampler);
        const tinygltf::Sampler &sm = m.samplers[size_t(tex.sampler)];
        std::string sw = "sampler " + std::to_string(tex.sampler);
        ws = wrap_mode(sm.wrapS, sw);
        wt = wrap_mode(sm.wrapT, sw);
    }

    /* the texels as stb decoded them (lie_texture_texel reads them through
     * the tables): the first texture of an image takes stb's buffer, a
     * second (the other colour space, another sampler) a copy */
    lie_texture &t = im.s->textures[im.s->n_textures];
    t.width = int(w);
    t.height = int(h);
    t.wrap_s = ws;
    t.wrap_t = wt;
    t.image = -1;
    t.code_bits = img.bits;
    int index = im.s->n_textures++;
    size_t levels = bytes == 1 ? 256 : 65536, size = w * h * 4 * bytes;
    for (int k = 0; k < 2; k++) { /* colour through the sRGB transfer function when asked, alpha always linear */
        t.code_value[k] = alloc_array<float>(levels);
        for (size_t i = 0; i < levels; i++)
            t.code_value[k][i] = lie_texture_code_value(i, levels, k == 0 && srgb);
    }
    auto owner = im.codes_of.find(tex.source);
    if (owner == im.codes_of.end()) {
        t.codes = dec->second.pixels.release();
        im.codes_of[tex.source] = index;
    } else {
        t.codes = alloc_array<unsigned char>(size);
        memcpy(t.codes, im.s->textures[owner->second].codes, size);
    }
    t.image = keep_image(im, tex.source);
    im.texture_of[ti * 2 + srgb] = index;
    return index;
}

float unit_factor(double v, const std::string &what)
{
    if (!std::isfinite(v))
        fail(LIE_ERR_FORMAT, "%s is not a finite number", what.c_str());
    return float(fmin(fmax(v, 0.0), 1.0)); /* spec range [0, 1]; exporters overshoot by rounding */
}

/* A textureInfo's texture.  Its texture coordinate set (texCoord, or its
 * KHR_texture_transform's) goes to *set: 0 or 1, the sets the importer
 * reads; a higher one reads TEXCOORD_0.  Its KHR_texture_transform, if
 * any, goes to param (offset, rotation in radians, scale: the matrix
 * T R S of the extension's specification). */
template <class Info>
int texture_info(Import &im, const Info &ti, bool srgb, const std::string &what, float param[5], int *set)
{
    *set = 0;
    if (ti.index < 0)
        return -1;
    if (ti.texCoord < 0)
        fail(LIE_ERR_FORMAT, "%s: texCoord must be >= 0", what.c_str());
    *set = ti.texCoord == 1 ? 1 : 0;
    if (ti.texCoord > 1)
        not_read(im.s, "texCoord " + std::to_string(ti.texCoord), "such slots read TEXCOORD_0");
    auto ext = ti.extensions.find("KHR_texture_transform");
    if (ext != ti.extensions.end()) {
        const tinygltf::Value &v = ext->second;
        if (!v.IsObject())
            fail(LIE_ERR_FORMAT, "%s: KHR_texture_transform must be an object", what.c_str());
        auto numbers = [&](const char *key, double *out, int n) {
            if (!v.Has(key))
                return;
            const tinygltf::Value &a = v.Get(key);
            bool ok = n == 1 ? a.IsNumber() : a.IsArray() && a.ArrayLen() == size_t(n);
            for (int k = 0; ok && k < n; k++) {
                const tinygltf::Value &x = n == 1 ? a : a.Get(k);
                ok = x.IsNumber() && std::isfinite(x.GetNumberAsDouble());
                if (ok)
                    out[k] = x.GetNumberAsDouble();
            }
            if (!ok)
                fail(LIE_ERR_FORMAT, "%s: KHR_texture_transform %s must be %s", what.c_str(), key,
                     n == 1 ? "a finite number" : "two finite numbers");
        };
        double off[2] = {0.0, 0.0}, rot = 0.0, scl[2] = {1.0, 1.0}, tc = -1.0;
        numbers("offset", off, 2);
        numbers("rotation", &rot, 1);
        numbers("scale", scl, 2);
        numbers("texCoord", &tc, 1);
        if (v.Has("texCoord")) {
            if (!(tc >= 0.0) || tc != std::floor(tc))
                fail(LIE_ERR_FORMAT, "%s: KHR_texture_transform texCoord must be an integer >= 0", what.c_str());
            *set = tc == 1.0 ? 1 : 0;
        }
        const double p[5] = {off[0], off[1], rot, scl[0], scl[1]};
        for (int k = 0; k < 5; k++) {
            if (!(fabs(p[k]) <= FLT_MAX))
                fail(LIE_ERR_FORMAT, "%s: KHR_texture_transform value out of range", what.c_str());
            param[k] = float(p[k]);
        }
    }
    return texture_for(im, ti.index, srgb, what);
}

/* A textureInfo held inside an extension (tinygltf leaves those as JSON
 * values): index, texCoord and its own extensions, checked as the core's. */
tinygltf::TextureInfo extension_texture_info(const tinygltf::Value &v, const std::string &what)
{
    tinygltf::TextureInfo ti;
    if (!v.IsObject())
        fail(LIE_ERR_FORMAT, "%s must be an object", what.c_str());
    auto integer = [&](const char *key, int *out) {
        if (!v.Has(key))
            return;
        const tinygltf::Value &x = v.Get(key);
        double d = x.IsNumber() ? x.GetNumberAsDouble() : -1.0;
        if (!(d >= 0.0 && d <= double(INT_MAX)) || d != std::floor(d))
            fail(LIE_ERR_FORMAT, "%s: %s must be an integer >= 0", what.c_str(), key);
        *out = int(d);
    };
    if (!v.Has("index"))
        fail(LIE_ERR_FORMAT, "%s has no index", what.c_str());
    integer("index", &ti.index);
    integer("texCoord", &ti.texCoord);
    if (v.Has("extensions") && v.Get("extensions").IsObject()) {
        const tinygltf::Value &e = v.Get("extensions");
        if (e.Has("KHR_texture_transform"))
            ti.extensions["KHR_texture_transform"] = e.Get("KHR_texture_transform");
    }
    return ti;
}

/* KHR_materials_transmission: transmissionFactor and transmissionTexture
 * (its R channel), read linear. */
void import_transmission(Import &im, const tinygltf::Material &g, lie_material &mt, const std::string &w)
{
    auto ext = g.extensions.find("KHR_materials_transmission");
    if (ext == g.extensions.end())
        return;
    const tinygltf::Value &v = ext->second;
    if (!v.IsObject())
        fail(LIE_ERR_FORMAT, "%s: KHR_materials_transmission must be an object", w.c_str());
    if (v.Has("transmissionFactor"))
        mt.transmission = unit_factor(v.Get("transmissionFactor").IsNumber()
                                          ? v.Get("transmissionFactor").GetNumberAsDouble()
                                          : std::nan(""),
                                      w + " transmissionFactor");
    if (v.Has("transmissionTexture")) {
        std::string tw = w + " transmissionTexture";
        tinygltf::TextureInfo ti = extension_texture_info(v.Get("transmissionTexture"), tw);
        mt.transmission_tex = texture_info(im, ti, false, tw, mt.tex_param[LIE_TEX_TRANSMISSION],
                                           &mt.tex_set[LIE_TEX_TRANSMISSION]);
    }
    if (mt.transmission <= 0.0f)
        mt.transmission_tex = -1; /* a factor of 0 lets nothing through, whatever the texture */
}

void import_materials(Import &im)
{
    const tinygltf::Model &m = im.m;
    lie_scene *s = im.s;
    if (m.textures.size() > size_t(INT_MAX / 2) || m.materials.size() > size_t(INT_MAX))
        fail(LIE_ERR_LIMIT, "too many materials or textures");
    s->textures = alloc_array<lie_texture>(m.textures.size() * 2); /* at most one per colour space */
    s->images = alloc_array<lie_image>(m.images.size());
    s->materials = alloc_array<lie_material>(m.materials.size());
    s->n_materials = int(m.materials.size());
    for (size_t i = 0; i < m.materials.size(); i++) {
        const tinygltf::Material &g = m.materials[i];
        const tinygltf::PbrMetallicRoughness &pbr = g.pbrMetallicRoughness;
        lie_material &mt = s->materials[i];
        std::string w = "material " + std::to_string(i);
        mt.name = dup_name(g.name);
        lie_material_tex_xf_identity(&mt);
        if (pbr.baseColorFactor.size() != 4)
            fail(LIE_ERR_FORMAT, "%s: baseColorFactor needs 4 numbers", w.c_str());
        for (int c = 0; c < 4; c++)
            mt.base_color[c] = unit_factor(pbr.baseColorFactor[size_t(c)], w + " baseColorFactor");
        mt.base_color_tex = texture_info(im, pbr.baseColorTexture, true, w + " baseColorTexture",
                                         mt.tex_param[LIE_TEX_BASE_COLOR], &mt.tex_set[LIE_TEX_BASE_COLOR]);
        mt.metallic = unit_factor(pbr.metallicFactor, w + " metallicFactor");
        mt.roughness = unit_factor(pbr.roughnessFactor, w + " roughnessFactor");
        mt.mr_tex = texture_info(im, pbr.metallicRoughnessTexture, false, w + " metallicRoughnessTexture",
                                 mt.tex_param[LIE_TEX_METALLIC_ROUGHNESS], &mt.tex_set[LIE_TEX_METALLIC_ROUGHNESS]);

        double strength = 1.0;
        auto ext = g.extensions.find("KHR_materials_emissive_strength");
        if (ext != g.extensions.end() && ext->second.IsObject() && ext->second.Has("emissiveStrength")) {
            const tinygltf::Value &v = ext->second.Get("emissiveStrength");
            if (!v.IsNumber() || !std::isfinite(v.GetNumberAsDouble()) || v.GetNumberAsDouble() < 0.0)
                fail(LIE_ERR_FORMAT, "%s: emissiveStrength must be a number >= 0", w.c_str());
            strength = v.GetNumberAsDouble();
        }
        if (!g.emissiveFactor.empty() && g.emissiveFactor.size() != 3)
            fail(LIE_ERR_FORMAT, "%s: emissiveFactor needs 3 numbers", w.c_str());
        for (size_t c = 0; c < 3; c++) {
            double e = g.emissiveFactor.empty() ? 0.0 : g.emissiveFactor[c];
            if (!std::isfinite(e) || e < 0.0)
                fail(LIE_ERR_FORMAT, "%s: emissiveFactor must be numbers >= 0", w.c_str());
            mt.emissive[c] = float(e * strength);
        }
        mt.emissive_tex = texture_info(im, g.emissiveTexture, true, w + " emissiveTexture", mt.tex_param[LIE_TEX_EMISSIVE],
                                       &mt.tex_set[LIE_TEX_EMISSIVE]);
        mt.normal_tex = texture_info(im, g.normalTexture, false, w + " normalTexture", mt.tex_param[LIE_TEX_NORMAL],
                                     &mt.tex_set[LIE_TEX_NORMAL]);
        if (!std::isfinite(g.normalTexture.scale) || !(fabs(g.normalTexture.scale) <= 1e6))
            fail(LIE_ERR_FORMAT, "%s: normalTexture scale is not a finite number", w.c_str());
        mt.normal_scale = float(g.normalTexture.scale);
        mt.transmission_tex = -1;
        import_transmission(im, g, mt, w);
        if (g.occlusionTexture.index >= 0)
            not_read(s, "occlusionTexture", "ambient occlusion has no part in direct light");
        if (g.alphaMode == "BLEND")
            not_read(s, "alphaMode BLEND", "such surfaces are opaque");
        mt.double_sided = g.doubleSided ? 1 : 0;
        mt.alpha_mask = g.alphaMode == "MASK";
        if (!std::isfinite(g.alphaCutoff))
            fail(LIE_ERR_FORMAT, "%s: alphaCutoff is not a finite number", w.c_str());
        mt.alpha_cutoff = float(g.alphaCutoff);
        lie_material_tex_xf_update(&mt);
    }
}

/* ---- nodes and scenes ------------------------------------------------------ */

lie_mat4 node_local(const tinygltf::Node &n, const std::string &w)
{
    auto finite = [&](const std::vector<double> &v, const char *what) {
        for (double x : v)
            if (!std::isfinite(x))
                fail(LIE_ERR_FORMAT, "%s: %s has a value that is not a finite number", w.c_str(), what);
    };
    if (!n.matrix.empty()) {
        if (n.matrix.size() != 16)
            fail(LIE_ERR_FORMAT, "%s: matrix needs 16 numbers", w.c_str());
        finite(n.matrix, "matrix");
        lie_mat4 r;
        for (int k = 0; k < 16; k++)
            r.m[k] = n.matrix[size_t(k)]; /* both column-major */
        return r;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, sc[3] = {1, 1, 1};
    if (!n.translation.empty()) {
        if (n.translation.size() != 3)
            fail(LIE_ERR_FORMAT, "%s: translation needs 3 numbers", w.c_str());
        finite(n.translation, "translation");
        for (int k = 0; k < 3; k++)
            t[k] = n.translation[size_t(k)];
    }
    if (!n.rotation.empty()) {
        if (n.rotation.size() != 4)
            fail(LIE_ERR_FORMAT, "%s: rotation needs 4 numbers", w.c_str());
        finite(n.rotation, "rotation");
        double len = sqrt(n.rotation[0] * n.rotation[0] + n.rotation[1] * n.rotation[1] +
                          n.rotation[2] * n.rotation[2] + n.rotation[3] * n.rotation[3]);
        if (!(len > 0.0))
            fail(LIE_ERR_FORMAT, "%s: rotation is not a unit quaternion", w.c_str());
        for (int k = 0; k < 4; k++) /* exporters round; the spec asks for unit length */
            q[k] = n.rotation[size_t(k)] / len;
    }
    if (!n.scale.empty()) {
        if (n.scale.size() != 3)
            fail(LIE_ERR_FORMAT, "%s: scale needs 3 numbers", w.c_str());
        finite(n.scale, "scale");
        for (int k = 0; k < 3; k++)
            sc[k] = n.scale[size_t(k)];
    }
    return lie_mat4_from_trs(t, q, sc);
}

int node_light(const tinygltf::Model &m, const tinygltf::Node &n, const std::string &w)
{
    auto ext = n.extensions.find("KHR_lights_punctual");
    if (ext == n.extensions.end())
        return -1;
    const tinygltf::Value &v = ext->second;
    if (!v.IsObject() || !v.Has("light") || !v.Get("light").IsInt())
        fail(LIE_ERR_FORMAT, "%s: KHR_lights_punctual needs an integer light", w.c_str());
    int li = v.Get("light").GetNumberAsInt();
    if (li < 0 || size_t(li) >= m.lights.size())
        fail(LIE_ERR_FORMAT, "%s: light %d out of range", w.c_str(), li);
    return li;
}

void import_nodes(const tinygltf::Model &m, lie_scene *s)
{
    size_t nn = m.nodes.size();
    if (nn > size_t(INT_MAX))
        fail(LIE_ERR_LIMIT, "too many nodes");
    s->nodes = alloc_array<lie_node>(nn);
    s->n_nodes = int(nn);
    for (size_t i = 0; i < nn; i++) { /* parents first, so partial nodes stay consistent */
        s->nodes[i].parent = -1;
        s->nodes[i].mesh = s->nodes[i].camera = s->nodes[i].light = -1;
        s->nodes[i].local = lie_mat4_identity();
    }
    for (size_t i = 0; i < nn; i++) {
        const tinygltf::Node &g = m.nodes[i];
        lie_node &n = s->nodes[i];
        std::string w = "node " + std::to_string(i);
        n.name = dup_name(g.name);
        n.local = node_local(g, w);
        n.skin = -1;
        if (g.matrix.empty()) { /* the TRS node_local checked; animations replace parts of it */
            n.has_trs = 1;
            double def[10] = {0, 0, 0, 0, 0, 0, 1, 1, 1, 1};
            memcpy(n.trs, def, sizeof def);
            for (size_t k = 0; k < g.translation.size() && k < 3; k++)
                n.trs[k] = g.translation[k];
            if (g.rotation.size() == 4) {
                double len = sqrt(g.rotation[0] * g.rotation[0] + g.rotation[1] * g.rotation[1] +
                                  g.rotation[2] * g.rotation[2] + g.rotation[3] * g.rotation[3]);
                for (size_t k = 0; k < 4; k++)
                    n.trs[3 + k] = g.rotation[k] / len;
            }
            for (size_t k = 0; k < g.scale.size() && k < 3; k++)
                n.trs[7 + k] = g.scale[k];
        }
        if (g.mesh >= 0 && size_t(g.mesh) >= m.meshes.size())
            fail(LIE_ERR_FORMAT, "%s: mesh %d out of range", w.c_str(), g.mesh);
        if (g.camera >= 0 && size_t(g.camera) >= m.cameras.size())
            fail(LIE_ERR_FORMAT, "%s: camera %d out of range", w.c_str(), g.camera);
        n.mesh = g.mesh < 0 ? -1 : g.mesh;
        n.camera = g.camera < 0 ? -1 : g.camera;
        n.light = node_light(m, g, w);
        n.children = alloc_array<int>(g.children.size());
        n.n_children = int(g.children.size());
        for (size_t k = 0; k < g.children.size(); k++) {
            int c = g.children[k];
            if (c < 0 || size_t(c) >= nn)
                fail(LIE_ERR_FORMAT, "%s: child %d out of range", w.c_str(), c);
            if (size_t(c) == i)
                fail(LIE_ERR_FORMAT, "%s is its own child", w.c_str());
            if (s->nodes[c].parent >= 0)
                fail(LIE_ERR_FORMAT, "node %d has two parents (nodes %d and %zu)", c, s->nodes[c].parent, i);
            s->nodes[c].parent = int(i);
            n.children[k] = c;
        }
    }
    /* With one parent each, a node not reachable from a parentless node sits
     * on (or under) a cycle. */
    std::vector<char> seen(nn, 0);
    std::vector<int> stack;
    for (size_t i = 0; i < nn; i++)
        if (s->nodes[i].parent < 0)
            stack.push_back(int(i));
    while (!stack.empty()) {
        int i = stack.back();
        stack.pop_back();
        seen[size_t(i)] = 1;
        for (int k = 0; k < s->nodes[i].n_children; k++)
            stack.push_back(s->nodes[i].children[k]);
    }
    for (size_t i = 0; i < nn; i++)
        if (!seen[i])
            fail(LIE_ERR_FORMAT, "node %zu is part of a cycle of children", i);
}

void import_roots(const tinygltf::Model &m, lie_scene *s)
{
    std::vector<int> roots;
    int scene = m.defaultScene >= 0 ? m.defaultScene : (m.scenes.empty() ? -1 : 0);
    if (scene >= 0) {
        if (size_t(scene) >= m.scenes.size())
            fail(LIE_ERR_FORMAT, "default scene %d out of range", scene);
        std::vector<char> used(m.nodes.size(), 0);
        for (int r : m.scenes[size_t(scene)].nodes) {
            if (r < 0 || size_t(r) >= m.nodes.size())
                fail(LIE_ERR_FORMAT, "scene %d: node %d out of range", scene, r);
            if (s->nodes[r].parent >= 0)
                fail(LIE_ERR_FORMAT, "scene %d: node %d is not a root (its parent is node %d)", scene, r,
                     s->nodes[r].parent);
            if (used[size_t(r)]++)
                fail(LIE_ERR_FORMAT, "scene %d lists node %d twice", scene, r);
            roots.push_back(r);
        }
    } else {
        for (int i = 0; i < s->n_nodes; i++)
            if (s->nodes[i].parent < 0)
                roots.push_back(i);
    }
    s->roots = alloc_array<int>(roots.size());
    s->n_roots = int(roots.size());
    if (!roots.empty())
        memcpy(s->roots, roots.data(), roots.size() * sizeof(int));
}

/* ---- cameras and lights -------------------------------------------------- */

void import_cameras(const tinygltf::Model &m, lie_scene *s)
{
    s->camera_defs = alloc_array<lie_camera_def>(m.cameras.size());
    s->n_camera_defs = int(m.cameras.size());
    for (size_t i = 0; i < m.cameras.size(); i++) {
        const tinygltf::Camera &g = m.cameras[i];
        lie_camera_def &c = s->camera_defs[i];
        c.name = dup_name(g.name);
        if (g.type == "perspective") {
            const tinygltf::PerspectiveCamera &p = g.perspective;
            if (!(p.yfov > 0.0 && p.yfov < M_PI) || !(p.aspectRatio >= 0.0) || !std::isfinite(p.aspectRatio) ||
                !(p.znear >= 0.0) || !std::isfinite(p.znear))
                fail(LIE_ERR_FORMAT, "camera %zu: yfov must be in (0, pi), aspectRatio and znear >= 0", i);
            c.yfov = float(p.yfov);
            c.aspect = float(p.aspectRatio);
            c.znear = float(p.znear);
        } else if (g.type == "orthographic") {
            /* glTF 2.0 §5.13: xmag and ymag MUST NOT be zero (SHOULD NOT be
             * negative: their size is used), zfar > znear >= 0 */
            const tinygltf::OrthographicCamera &o = g.orthographic;
            if (!std::isfinite(o.xmag) || !std::isfinite(o.ymag) || o.xmag == 0.0 || o.ymag == 0.0 ||
                !(o.znear >= 0.0) || !std::isfinite(o.znear) || !(o.zfar > o.znear) || !std::isfinite(o.zfar) ||
                !(std::fabs(o.ymag) < 1e30) || !(std::fabs(o.xmag) < 1e30))
                fail(LIE_ERR_FORMAT, "camera %zu: orthographic xmag and ymag must be finite and nonzero, "
                                     "zfar > znear >= 0", i);
            c.yfov = 0.0f;
            c.aspect = 0.0f;
            c.xmag = float(std::fabs(o.xmag));
            c.ymag = float(std::fabs(o.ymag));
            c.znear = float(o.znear);
            c.zfar = float(o.zfar);
        } else {
            fail(LIE_ERR_FORMAT, "camera %zu: unknown type '%s'", i, clean(g.type).c_str());
        }
    }
}

void import_lights(const tinygltf::Model &m, lie_scene *s)
{
    s->light_defs = alloc_array<lie_light_def>(m.lights.size());
    s->n_light_defs = int(m.lights.size());
    for (size_t i = 0; i < m.lights.size(); i++) {
        const tinygltf::Light &g = m.lights[i];
        lie_light_def &l = s->light_defs[i];
        std::string w = "light " + std::to_string(i);
        l.name = dup_name(g.name);
        if (g.type == "point")
            l.type = LIE_LIGHT_POINT;
        else if (g.type == "spot")
            l.type = LIE_LIGHT_SPOT;
        else if (g.type == "directional")
            l.type = LIE_LIGHT_DIRECTIONAL;
        else
            fail(LIE_ERR_FORMAT, "%s: unknown type '%s'", w.c_str(), clean(g.type).c_str());
        if (!g.color.empty() && g.color.size() != 3)
            fail(LIE_ERR_FORMAT, "%s: color needs 3 numbers", w.c_str());
        for (size_t c = 0; c < 3; c++) {
            double v = g.color.empty() ? 1.0 : g.color[c];
            if (!std::isfinite(v) || v < 0.0)
                fail(LIE_ERR_FORMAT, "%s: color must be numbers >= 0", w.c_str());
            l.color[c] = float(v);
        }
        if (!std::isfinite(g.intensity) || g.intensity < 0.0)
            fail(LIE_ERR_FORMAT, "%s: intensity must be a number >= 0", w.c_str());
        if (!std::isfinite(g.range) || g.range < 0.0)
            fail(LIE_ERR_FORMAT, "%s: range must be a number >= 0", w.c_str());
        l.intensity = float(g.intensity);
        l.range = float(g.range);
        l.inner_cone = 0.0f;
        l.outer_cone = float(M_PI / 4.0);
        if (l.type == LIE_LIGHT_SPOT) {
            double in = g.spot.innerConeAngle, out = g.spot.outerConeAngle;
            if (!(in >= 0.0 && in < out && out <= M_PI / 2.0 + 1e-6))
                fail(LIE_ERR_FORMAT, "%s: spot cones need 0 <= inner < outer <= pi/2", w.c_str());
            l.inner_cone = float(in);
            l.outer_cone = float(fmin(out, M_PI / 2.0));
        }
    }
}

/* ---- the whole document ----------------------------------------------------- */

/* The document: its version and required extensions, every primitive
 * planned and the totals checked against the limits before anything is
 * read, then nodes and roots, the instancing limit, and the primitives read
 * and morphed per node weights.  One piece: the plans made first are what
 * every later step reads. */
void import_document(const tinygltf::Model &m, lie_scene *s, const lie_scene_options &opt)
{
    if (m.asset.version.compare(0, 2, "2.") != 0 && m.asset.version != "2")
        fail(LIE_ERR_UNSUPPORTED, "glTF version '%s' (only 2.x is supported)", clean(m.asset.version).c_str());
    for (const std::string &e : m.extensionsRequired) {
        bool ok = false;
        for (const char *sup : SUPPORTED_REQUIRED)
            ok = ok || e == sup;
        if (!ok)
            fail(LIE_ERR_UNSUPPORTED, "requires extension %s", clean(e).c_str());
    }
    if (m.meshes.size() > size_t(INT_MAX) || m.cameras.size() > size_t(INT_MAX) ||
        m.lights.size() > size_t(INT_MAX))
        fail(LIE_ERR_LIMIT, "too many meshes, cameras or lights");

    uint64_t limit = opt.max_triangles ? opt.max_triangles : LIE_SCENE_MAX_TRIANGLES_DEFAULT;
    if (limit > UINT32_MAX) /* triangle and vertex indices are 32-bit */
        limit = UINT32_MAX;

    /* check every primitive and count before allocating geometry */
    std::vector<std::vector<PrimPlan>> plans(m.meshes.size());
    std::vector<uint64_t> mesh_tris(m.meshes.size(), 0);
    uint64_t verts = 0, tris = 0;
    for (size_t mi = 0; mi < m.meshes.size(); mi++) {
        const tinygltf::Mesh &g = m.meshes[mi];
        if (g.primitives.size() > size_t(INT_MAX))
            fail(LIE_ERR_LIMIT, "mesh %zu: too many primitives", mi);
        for (size_t pi = 0; pi < g.primitives.size(); pi++) {
            plans[mi].push_back(plan_primitive(m, int(mi), int(pi), s));
            const PrimPlan &pl = plans[mi].back();
            if (pl.n_verts > limit || pl.n_tris > limit)
                fail(LIE_ERR_LIMIT, "mesh %zu primitive %zu: %zu vertices, %zu triangles, beyond the limit of %llu",
                     mi, pi, pl.n_verts, pl.n_tris, (unsigned long long)limit);
            verts += pl.n_verts;
            tris += pl.n_tris;
            mesh_tris[mi] += pl.n_tris;
        }
    }
    if (verts > limit || tris > limit)
        fail(LIE_ERR_LIMIT, "%llu vertices and %llu triangles, beyond the limit of %llu",
             (unsigned long long)verts, (unsigned long long)tris, (unsigned long long)limit);

    import_nodes(m, s);
    import_roots(m, s);
    /* Instancing multiplies triangles: count what flatten will make.  The
     * nodes form a forest (checked above), so each is reached at most once. */
    uint64_t world_tris = 0;
    std::vector<int> stack(s->roots, s->roots + s->n_roots);
    while (!stack.empty()) {
        const lie_node &n = s->nodes[stack.back()];
        stack.pop_back();
        if (n.mesh >= 0)
            world_tris += mesh_tris[size_t(n.mesh)];
        if (world_tris > limit)
            fail(LIE_ERR_LIMIT, "instancing makes more than %llu triangles", (unsigned long long)limit);
        stack.insert(stack.end(), n.children, n.children + n.n_children);
    }

    /* A node whose morph weights differ from its mesh's gets its own copy
     * of the mesh, morphed with them; the copies follow the file's meshes. */
    std::vector<std::pair<int, int>> copies; /* (node, file mesh) */
    std::vector<std::vector<double>> mesh_w(m.meshes.size());
    for (size_t mi = 0; mi < m.meshes.size(); mi++)
        mesh_w[mi] = morph_weights(m, mi, NULL, "mesh " + std::to_string(mi));
    for (int i = 0; i < s->n_nodes; i++) {
        const tinygltf::Node &g = m.nodes[size_t(i)];
        int mi = s->nodes[i].mesh;
        if (mi < 0 || g.weights.empty())
            continue;
        if (morph_weights(m, size_t(mi), &g.weights, "node " + std::to_string(i)) == mesh_w[size_t(mi)])
            continue;
        copies.push_back({i, mi});
        for (const PrimPlan &pl : plans[size_t(mi)])
            verts += pl.n_verts;
        if (verts > limit)
            fail(LIE_ERR_LIMIT, "morph weights per node make more than %llu vertices", (unsigned long long)limit);
    }

    size_t n_meshes = m.meshes.size() + copies.size();
    if (n_meshes > size_t(INT_MAX))
        fail(LIE_ERR_LIMIT, "too many meshes");
    s->meshes = alloc_array<lie_mesh>(n_meshes);
    s->n_meshes = int(n_meshes);
    for (size_t k = 0; k < n_meshes; k++) {
        size_t mi = k < m.meshes.size() ? k : size_t(copies[k - m.meshes.size()].second);
        std::vector<double> w = k < m.meshes.size()
                                    ? mesh_w[mi]
                                    : m.nodes[size_t(copies[k - m.meshes.size()].first)].weights;
        lie_mesh &mesh = s->meshes[k];
        mesh.name = dup_name(m.meshes[mi].name);
        mesh.prims = alloc_array<lie_primitive>(plans[mi].size());
        mesh.n_prims = int(plans[mi].size());
        for (size_t pi = 0; pi < plans[mi].size(); pi++) {
            const PrimPlan &pl = plans[mi][pi];
            lie_primitive &p = mesh.prims[pi];
            int mat = m.meshes[mi].primitives[pi].material;
            p.material = mat < 0 ? -1 : mat;
            if (!pl.skip) { /* points and lines stay as empty primitives: indices keep the file's */
                read_primitive(pl, int(mi), int(pi), &p);
                apply_morph(pl, w, int(mi), int(pi), &p);
            }
        }
        if (k >= m.meshes.size())
            s->nodes[copies[k - m.meshes.size()].first].mesh = int(k);
    }
    /* every node drawing a mesh with targets knows its weights (for animations and edits) */
    for (int i = 0; i < s->n_nodes; i++) {
        int fm = m.nodes[size_t(i)].mesh;
        if (fm < 0 || mesh_w[size_t(fm)].empty())
            continue;
        const std::vector<double> &g = m.nodes[size_t(i)].weights;
        const std::vector<double> &w = g.empty() ? mesh_w[size_t(fm)] : g;
        s->nodes[i].weights = alloc_array<double>(w.size());
        memcpy(s->nodes[i].weights, w.data(), w.size() * sizeof(double));
        s->nodes[i].n_weights = int(w.size());
    }
}

} // namespace lie_gltf

using namespace lie_gltf;

/* The rest of what the file holds and the import does not read, warned of
 * once each (docs/gltf.md lists what is read): extensions only used,
 * attributes past the sets read, morph targets' TANGENT, points and lines. */
void warn_not_read(const tinygltf::Model &m, lie_scene *s)
{
    static const char *const read[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                       "KHR_materials_transmission", "KHR_mesh_quantization",
                                       "KHR_texture_transform"};
    for (const std::string &e : m.extensionsUsed) {
        bool known = false;
        for (const char *r : read)
            known = known || e == r;
        if (!known)
            not_read(s, "extension " + clean(e), e == "KHR_materials_volume" ? "transmissive surfaces are thin"
                                                                            : "the file is read without it");
    }
    for (const tinygltf::Mesh &g : m.meshes)
        for (const tinygltf::Primitive &p : g.primitives) {
            for (const auto &a : p.attributes) {
                const std::string &n = a.first;
                bool read_it = n == "POSITION" || n == "NORMAL" || n == "TANGENT" || n == "TEXCOORD_0" ||
                               n == "TEXCOORD_1" || n == "COLOR_0" || n == "JOINTS_0" || n == "WEIGHTS_0";
                if (!read_it)
                    not_read(s, "attribute " + clean(n), "the sets read are TEXCOORD_0/1, COLOR_0, JOINTS_0, WEIGHTS_0");
            }
            for (const auto &t : p.targets)
                if (t.count("TANGENT"))
                    not_read(s, "morph target TANGENT", "tangents are not morphed");
        }
    if (s->stats.points_skipped || s->stats.lines_skipped)
        not_read(s, "points and lines", "only triangles are drawn");
}

extern "C" lie_status lie_gltf_import(lie_scene *s, const char *path, const lie_scene_options *opt,
                                      lie_error *err)
{
    if (!s || !path)
        return lie_error_set(err, LIE_ERR_ARG, path, "lie_gltf_import: NULL scene or path");
    if (s->nodes || s->meshes || s->materials || s->textures || s->camera_defs || s->light_defs || s->roots)
        return lie_error_set(err, LIE_ERR_ARG, path, "lie_gltf_import: the scene's document is not empty");
    lie_scene_options o = opt ? *opt : lie_scene_options_default();
    try {
        tinygltf::Model model;
        std::map<int, std::string> image_errors;
        std::map<int, std::vector<unsigned char>> encoded;
        load_model(model, path, o, image_errors, encoded);
        s->stats.points_skipped = s->stats.lines_skipped = s->stats.prims_without_material = 0;
        import_document(model, s, o);
        s->n_warnings = 0;
        Import im{model, s, image_errors, encoded, {}, {}, {}, {}, {}, {}};
        /* the images the materials use, decoded at once on every core
         * (stb's decoders are most of loading a textured scene), then the
         * materials, whose textures take the decoded codes */
        decode_images(model, encoded, material_images(model), im.decoded, o.threads);
        import_materials(im);
        im.decoded.clear();
        import_cameras(model, s);
        import_lights(model, s);
        import_skins(model, s);
        import_animations(model, s);
        warn_not_read(model, s);
        return LIE_OK;
    } catch (const ImportError &e) {
        if (e.line > 0)
            return lie_error_set_at(err, e.status, path, e.line, e.col, "%s", e.msg.c_str());
        return lie_error_set(err, e.status, path, "%s", e.msg.c_str());
    } catch (const std::bad_alloc &) {
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    } catch (const std::exception &e) {
        return lie_error_set(err, LIE_ERR_FORMAT, path, "%s", first_line(e.what()).c_str());
    } catch (...) {
        return lie_error_set(err, LIE_ERR_FORMAT, path, "unexpected error while importing");
    }
}

