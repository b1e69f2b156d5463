/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the textures' pixels on every core (lib/scene/gltf.h).
 *
 * Decoding a textured scene's images is most of its loading: bedroom_corner
 * (../shared/scenes) has six 2048 x 2048 images, and stb decodes each on
 * one core, after which every texel becomes four floats (64 MB an image,
 * written page by page).  Both are independent per image and per row, so
 * they run on every core; each result is computed by one worker from its
 * own inputs, so the pixels do not depend on the thread count
 * (CONTRIBUTING.md, Determinism). */
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

/* A band of rows of one texture. */
struct Band {
    const Conversion *c;
    size_t y0, y1;
};

struct ConvertJob {
    std::vector<Band> bands;
    /* code value -> linear value: [bits 8 | 16][srgb] */
    std::vector<float> table[2][2];
};

extern "C" void convert_run(void *ctx, size_t item, int worker)
{
    (void)worker;
    const ConvertJob &j = *static_cast<const ConvertJob *>(ctx);
    const Band &b = j.bands[item];
    const Decoded &img = *b.c->img;
    const int wide = img.bits == 16;
    const float *lin = j.table[wide][0].data(), *enc = j.table[wide][b.c->srgb].data();
    const size_t w = size_t(img.width), nc = size_t(img.component), bytes = wide ? 2 : 1;
    const unsigned char *src = img.pixels.get() + b.y0 * w * nc * bytes;
    for (size_t i = b.y0 * w; i < b.y1 * w; i++, src += nc * bytes) {
        size_t code[4];
        for (size_t c = 0; c < nc; c++)
            code[c] = wide ? (size_t(src[2 * c]) | size_t(src[2 * c + 1]) << 8) : src[c];
        float *d = b.c->rgba + 4 * i;
        switch (nc) { /* grey, grey + alpha, RGB, RGBA */
        case 1: d[0] = d[1] = d[2] = enc[code[0]]; d[3] = 1.0f; break;
        case 2: d[0] = d[1] = d[2] = enc[code[0]]; d[3] = lin[code[1]]; break;
        case 3: d[0] = enc[code[0]]; d[1] = enc[code[1]]; d[2] = enc[code[2]]; d[3] = 1.0f; break;
        default: d[0] = enc[code[0]]; d[1] = enc[code[1]]; d[2] = enc[code[2]]; d[3] = lin[code[3]]; break;
        }
    }
}

/* Rows a band: a few hundred thousand texels, enough to share a texture
 * between the workers and few enough to cost nothing to hand out. */
const size_t BAND_TEXELS = size_t(1) << 17;

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

void convert_textures(const std::vector<Conversion> &jobs, int threads)
{
    ConvertJob j;
    for (const Conversion &c : jobs) {
        const size_t w = size_t(c.img->width), h = size_t(c.img->height);
        const size_t rows = std::max<size_t>(1, BAND_TEXELS / w);
        for (size_t y = 0; y < h; y += rows)
            j.bands.push_back(Band{&c, y, std::min(h, y + rows)});
        const int wide = c.img->bits == 16;
        const size_t levels = wide ? 65536 : 256;
        for (int srgb = 0; srgb < 2; srgb++)
            if (j.table[wide][srgb].empty()) {
                j.table[wide][srgb].resize(levels);
                for (size_t i = 0; i < levels; i++)
                    j.table[wide][srgb][i] = lie_texture_code_value(i, levels, srgb);
            }
    }
    if (!j.bands.empty() && lie_parallel_for(j.bands.size(), threads, convert_run, &j, nullptr, nullptr) != LIE_OK)
        throw std::bad_alloc();
}

} // namespace lie_gltf
