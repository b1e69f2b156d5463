/* SPDX-License-Identifier: Apache-2.0 */
/* lib/export: the textures a material uses, as PNG files of the code values
 * the importer decoded them from (lib/export/internal.h). */
#include "export/internal.h"

#include "image/image.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace lie_export {

/* The importer's code values (lie_texture_code_value) for 8 and 16 bits, linear and sRGB. */
struct CodeTables {
    std::vector<float> t[2][2]; /* [16-bit][srgb] */
    const std::vector<float> &get(bool sixteen, bool srgb)
    {
        std::vector<float> &v = t[sixteen][srgb];
        if (v.empty()) {
            size_t levels = sixteen ? 65536 : 256;
            v.resize(levels);
            for (size_t i = 0; i < levels; i++)
                v[i] = lie_texture_code_value(i, levels, srgb);
        }
        return v;
    }
};

/* The code whose value is nearest to v (tables rise strictly); *exact when
 * it is v itself. */
size_t nearest_code(const std::vector<float> &t, float v, bool *exact)
{
    size_t i = size_t(std::lower_bound(t.begin(), t.end(), v) - t.begin());
    if (i == t.size())
        i = t.size() - 1;
    else if (i > 0 && v - t[i - 1] <= t[i] - v)
        i--;
    *exact = t[i] == v;
    return i;
}

/* Texture t as PNG codes for a slot decoded in `srgb`: 8-bit when every
 * value is an 8-bit code's value (so the importer gives back the same
 * floats), else 16-bit, the nearest codes.  Colour through the table of the
 * colour space, alpha always linear; RGB when alpha is 1 everywhere. */
void encode_texture(const lie_texture &t, bool srgb, CodeTables &tables, Png &out)
{
    size_t n = size_t(t.width) * size_t(t.height);
    out.width = t.width;
    out.height = t.height;
    bool opaque = true;
    float px[4];
    for (size_t i = 0; i < n; i++) {
        lie_texture_texel(&t, i, px);
        opaque = opaque && px[3] == 1.0f;
    }
    out.channels = opaque ? 3 : 4;
    size_t nc = size_t(out.channels);
    for (int sixteen = 0; sixteen < 2; sixteen++) {
        const std::vector<float> &col = tables.get(sixteen, srgb), &alpha = tables.get(sixteen, false);
        std::vector<uint16_t> codes(n * nc);
        bool all_exact = true;
        for (size_t i = 0; i < n; i++) {
            lie_texture_texel(&t, i, px);
            for (size_t c = 0; c < nc; c++) {
                bool exact;
                codes[i * nc + c] = uint16_t(nearest_code(c < 3 ? col : alpha, px[c], &exact));
                all_exact = all_exact && exact;
            }
        }
        if (!sixteen && !all_exact)
            continue;
        out.bits = sixteen ? 16 : 8;
        if (sixteen)
            out.b16.swap(codes);
        else
            out.b8.assign(codes.begin(), codes.end());
        return;
    }
}


std::string uri_escape(const std::string &name)
{
    static const char hex[] = "0123456789ABCDEF";
    std::string r;
    for (unsigned char c : name) {
        if (isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
            r += char(c);
        } else {
            r += '%';
            r += hex[c >> 4];
            r += hex[c & 15];
        }
    }
    return r;
}

int gl_wrap(lie_wrap w)
{
    switch (w) {
    case LIE_WRAP_CLAMP: return TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    case LIE_WRAP_MIRROR: return TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT;
    default: return TINYGLTF_TEXTURE_WRAP_REPEAT;
    }
}

/* The PNG file of png's codes, in png.bytes (the codes are freed); no
 * colour chunk: the .gltf's slot says how the codes are decoded. */
void png_bytes(Png &png, const std::string &name)
{
    lie_png_pixels px = {png.width, png.height, png.bits, png.channels,
                         png.bits == 16 ? static_cast<const void *>(png.b16.data())
                                        : static_cast<const void *>(png.b8.data()),
                         0, nullptr, 0};
    unsigned char *buf = nullptr;
    size_t n = 0;
    lie_error e{};
    lie_status st = lie_png_encode(&px, name.c_str(), &buf, &n, &e);
    if (st != LIE_OK)
        throw ExportError{st, e.msg};
    try {
        png.bytes.assign(buf, buf + n);
    } catch (...) {
        free(buf);
        throw;
    }
    free(buf);
    std::vector<uint8_t>().swap(png.b8);
    std::vector<uint16_t>().swap(png.b16);
}

/* An image file of the export: a bufferView of the .glb, else a side file
 * named `name`. */
void add_image(Export &ex, Png &file, const std::string &name, const std::string &mime)
{
    tinygltf::Image im;
    im.mimeType = mime;
    if (ex.glb) { /* glTF 2.0 §3.9.1: an image in a bufferView names its mimeType */
        im.bufferView = add_view(ex, file.bytes.data(), file.bytes.size(), 0);
    } else {
        im.uri = file.uri = uri_escape(name);
        file.path = ex.dir + name;
        ex.pngs.push_back(std::move(file));
    }
    ex.m.images.push_back(im);
}

/* The glTF image of scene image k: its file's bytes as they were (a JPEG
 * stays that JPEG), once however many textures use it. */
int kept_image(Export &ex, int k, std::map<int, int> &image_of)
{
    auto found = image_of.find(k);
    if (found != image_of.end())
        return found->second;
    const lie_image &src = ex.s.images[k];
    std::string mime = src.mime ? src.mime : "";
    std::string ext = mime == "image/png" ? ".png" : mime == "image/jpeg" ? ".jpg" : mime == "image/webp" ? ".webp"
                                                                                   : mime == "image/ktx2" ? ".ktx2"
                                                                                                          : ".bin";
    int image = int(ex.m.images.size());
    std::string name = ex.stem + "_img" + std::to_string(image) + ext;
    Png file;
    file.bytes.assign(src.bytes, src.bytes + src.size);
    add_image(ex, file, name, mime);
    if (src.name)
        ex.m.images.back().name = src.name;
    image_of[k] = image;
    return image;
}

std::map<int, int> export_textures(Export &ex)
{
    const lie_scene &s = ex.s;
    std::vector<char> used(size_t(s.n_textures) * 2, 0);
    auto mark = [&](int t, bool srgb) {
        if (t >= 0 && t < s.n_textures)
            used[size_t(t) * 2 + srgb] = 1;
    };
    for (int i = 0; i < s.n_materials; i++) {
        mark(s.materials[i].base_color_tex, true);
        mark(s.materials[i].mr_tex, false);
        mark(s.materials[i].emissive_tex, true);
        mark(s.materials[i].normal_tex, false);
        mark(s.materials[i].transmission_tex, false);
    }
    std::map<int, int> image_of; /* s.images -> glTF image: a file's image written once, as it was */
    std::map<int, int> gl_texture;
    std::map<std::pair<int, int>, int> sampler_of;
    CodeTables tables;
    for (int t = 0; t < s.n_textures; t++)
        for (int srgb = 1; srgb >= 0; srgb--) {
            if (!used[size_t(t) * 2 + size_t(srgb)])
                continue;
            const lie_texture &lt = s.textures[t];
            std::pair<int, int> wrap(gl_wrap(lt.wrap_s), gl_wrap(lt.wrap_t));
            auto found = sampler_of.find(wrap);
            if (found == sampler_of.end()) {
                tinygltf::Sampler sm;
                sm.wrapS = wrap.first;
                sm.wrapT = wrap.second;
                ex.m.samplers.push_back(sm);
                found = sampler_of.emplace(wrap, int(ex.m.samplers.size() - 1)).first;
            }
            int image = lt.image >= 0 && lt.image < s.n_images ? kept_image(ex, lt.image, image_of) : -1;
            if (image < 0) { /* made in memory: its code values as a PNG */
                image = int(ex.m.images.size());
                std::string name = ex.stem + "_tex" + std::to_string(image) + ".png";
                Png png;
                encode_texture(lt, srgb != 0, tables, png);
                png_bytes(png, name);
                add_image(ex, png, name, "image/png");
            }
            tinygltf::Texture tx;
            tx.sampler = found->second;
            tx.source = image;
            ex.m.textures.push_back(tx);
            gl_texture[t * 2 + srgb] = int(ex.m.textures.size() - 1);
        }
    return gl_texture;
}

} // namespace lie_export
