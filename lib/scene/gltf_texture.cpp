/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the images materials use, decoded on every core
 * (lib/scene/gltf.h).
 *
 * Decoding a textured scene's images is most of its loading: bedroom_corner
 * (docs/measurements.md, "The viewer's first frame") has six 2048 x 2048
 * images, which stb decodes on one core each.  Each image is decoded by one worker from its own bytes, so
 * the pixels do not depend on the thread count (CONTRIBUTING.md,
 * Determinism); the textures keep the codes (lie_texture_texel). */
#include "scene/gltf.h"

#include <algorithm>

namespace lie_gltf {

std::vector<int> material_images(const tinygltf::Model &m)
{
    std::vector<int> out;
    auto add = [&](int ti) {
        if (ti < 0 || size_t(ti) >= m.textures.size())
            return;
        int src = m.textures[size_t(ti)].source;
        if (src >= 0 && size_t(src) < m.images.size())
            out.push_back(src);
    };
    for (const tinygltf::Material &g : m.materials) {
        add(g.pbrMetallicRoughness.baseColorTexture.index);
        add(g.pbrMetallicRoughness.metallicRoughnessTexture.index);
        add(g.emissiveTexture.index);
        add(g.normalTexture.index);
        /* KHR_materials_transmission's texture, as import_transmission
         * reads it (a malformed one is refused there, not here) */
        auto ext = g.extensions.find("KHR_materials_transmission");
        if (ext != g.extensions.end() && ext->second.IsObject() && ext->second.Has("transmissionTexture")) {
            const tinygltf::Value &t = ext->second.Get("transmissionTexture");
            if (t.IsObject() && t.Has("index") && t.Get("index").IsNumber()) {
                double d = t.Get("index").GetNumberAsDouble();
                if (d >= 0.0 && d <= double(INT_MAX) && d == double(int(d)))
                    add(int(d));
            }
        }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

namespace {

struct DecodeJob {
    const tinygltf::Model *m;
    std::vector<const std::vector<unsigned char> *> bytes; /* NULL: no bytes (an image tinygltf could not open) */
    std::vector<int> images;
    std::vector<Decoded *> out;
};

extern "C" void decode_run(void *ctx, size_t item, int worker)
{
    (void)worker;
    DecodeJob &j = *static_cast<DecodeJob *>(ctx);
    if (!j.bytes[item])
        return;
    try {
        decode_image(j.m->images[size_t(j.images[item])], j.images[item], *j.bytes[item], j.out[item]);
    } catch (...) {
        j.out[item]->pixels.reset();
        j.out[item]->error = std::current_exception();
    }
}

} // namespace

void decode_images(const tinygltf::Model &m, const std::map<int, std::vector<unsigned char>> &encoded,
                   const std::vector<int> &images, std::map<int, Decoded> &decoded, int threads)
{
    DecodeJob j;
    j.m = &m;
    for (int img : images) {
        if (decoded.count(img))
            continue;
        auto enc = encoded.find(img);
        j.images.push_back(img);
        j.bytes.push_back(enc != encoded.end() ? &enc->second : nullptr);
        j.out.push_back(&decoded.emplace(img, Decoded()).first->second);
    }
    if (j.images.empty())
        return;
    /* the largest files first: the last to start is a small one */
    std::vector<uint32_t> order(j.images.size());
    for (size_t i = 0; i < order.size(); i++)
        order[i] = uint32_t(i);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        size_t sa = j.bytes[a] ? j.bytes[a]->size() : 0, sb = j.bytes[b] ? j.bytes[b]->size() : 0;
        return sa > sb;
    });
    if (lie_parallel_for_ordered(j.images.size(), threads, decode_run, &j, order.data(), nullptr, nullptr, nullptr,
                                 nullptr) != LIE_OK)
        throw std::bad_alloc(); /* the workers could not start */
}

} // namespace lie_gltf
