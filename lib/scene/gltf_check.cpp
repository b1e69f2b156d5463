/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: reading a glTF file and the checks around tinygltf (lib/scene/gltf.h).
 *
 * tinygltf trusts more than the trust boundary may: its GLB check lets a
 * BIN chunk run past the data, its JSON parser recurses once per level of
 * nesting, and it drops an optional property of the wrong type or sign for
 * its default.  The raw file is checked here first (the container, the
 * nesting, the schema's integer rules), then tinygltf parses it through the
 * sandbox (gltf_sandbox.cpp), and its failures become one line. */
#include "scene/gltf.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace lie_gltf {

[[noreturn]] __attribute__((format(printf, 2, 3))) void fail(lie_status status, const char *fmt, ...)
{
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    throw ImportError{status, buf, 0, 0};
}

std::string clean(const std::string &s, size_t max)
{
    std::string r;
    for (char c : s) {
        if (r.size() >= max) {
            r += "...";
            break;
        }
        r += (unsigned char)c < 0x20 || c == 0x7f ? '?' : c;
    }
    return r;
}

std::string first_line(const std::string &s)
{
    size_t at = 0;
    while (at < s.size()) {
        size_t end = s.find('\n', at);
        if (end == std::string::npos)
            end = s.size();
        std::string line = s.substr(at, end - at);
        size_t b = line.find_first_not_of(" \t\r"), e = line.find_last_not_of(" \t\r.");
        if (b != std::string::npos && e != std::string::npos && e >= b)
            return clean(line.substr(b, e - b + 1), 300);
        at = end + 1;
    }
    return std::string();
}

std::string percent_decode(const std::string &s)
{
    std::string r;
    for (size_t i = 0; i < s.size(); i++) {
        if (s[i] == '%' && i + 2 < s.size() && isxdigit((unsigned char)s[i + 1]) &&
            isxdigit((unsigned char)s[i + 2])) {
            r += (char)strtol(s.substr(i + 1, 2).c_str(), nullptr, 16);
            i += 2;
        } else {
            r += s[i];
        }
    }
    return r;
}


char *dup_name(const std::string &s)
{
    if (s.empty())
        return nullptr;
    char *p = strdup(s.c_str());
    if (!p)
        throw std::bad_alloc();
    return p;
}

size_t mul_size(size_t a, size_t b, const char *what)
{
    size_t r;
    if (__builtin_mul_overflow(a, b, &r))
        fail(LIE_ERR_LIMIT, "%s: size overflows", what);
    return r;
}

/* ---- loading the file -------------------------------------------------- */

/* The glTF itself: through the file set when there is one ("-" is stdin). */
std::vector<unsigned char> read_input(const char *path, lie_file_set *files)
{
    lie_error e{};
    unsigned char *buf = nullptr;
    size_t n = 0;
    lie_status st = lie_file_set_read(files, path, LIE_READ_MAX_GLTF, &buf, &n, &e);
    if (st != LIE_OK)
        throw ImportError{e.status, e.msg, 0, 0};
    std::vector<unsigned char> data;
    try {
        data.assign(buf, buf + n);
    } catch (...) {
        free(buf);
        throw;
    }
    free(buf);
    if (data.empty())
        fail(LIE_ERR_FORMAT, "empty file");
    return data;
}

/* The GLB container (glTF 2.0 §4.4), checked before tinygltf sees it: its own
 * check lets a BIN chunk run 8 bytes past the end of the data. */
uint32_t glb_check(const std::vector<unsigned char> &d)
{
    auto le32 = [&](size_t at) {
        return uint32_t(d[at]) | uint32_t(d[at + 1]) << 8 | uint32_t(d[at + 2]) << 16 | uint32_t(d[at + 3]) << 24;
    };
    if (d.size() < 20)
        fail(LIE_ERR_FORMAT, "truncated GLB: %zu bytes, the header alone needs 20", d.size());
    uint32_t version = le32(4), length = le32(8), json_len = le32(12), json_type = le32(16);
    if (version != 2)
        fail(LIE_ERR_UNSUPPORTED, "GLB version %u (only 2 is supported)", version);
    if (length > d.size())
        fail(LIE_ERR_FORMAT, "truncated GLB: header says %u bytes, file has %zu", length, d.size());
    if (json_type != 0x4E4F534Au || json_len == 0)
        fail(LIE_ERR_FORMAT, "GLB: first chunk is not JSON");
    uint64_t at = 20 + uint64_t(json_len);
    if (at > length)
        fail(LIE_ERR_FORMAT, "truncated GLB: JSON chunk of %u bytes runs past the end", json_len);
    if (at < length) {
        if (at + 8 > length)
            fail(LIE_ERR_FORMAT, "truncated GLB: incomplete chunk header after JSON");
        uint32_t bin_len = le32(size_t(at)), bin_type = le32(size_t(at) + 4);
        if (bin_type == 0x004E4942u && at + 8 + bin_len > length)
            fail(LIE_ERR_FORMAT, "truncated GLB: BIN chunk of %u bytes runs past the end", bin_len);
    }
    return length;
}

/* A tinygltf failure as one line; nlohmann parse errors carry a position. */
[[noreturn]] void fail_parse(const std::string &msg, const FsState &fs)
{
    std::string line = first_line(msg);
    if (line.empty())
        line = "tinygltf rejected the file";
    const char *nf = "File not found : ";
    if (line.compare(0, strlen(nf), nf) == 0) {
        std::string uri = line.substr(strlen(nf));
        auto it = fs.missing.find(uri);
        fail(LIE_ERR_IO, "cannot open '%s': %s", uri.c_str(),
             it != fs.missing.end() ? it->second.c_str() : "not found");
    }
    if (line.compare(0, 17, "File read error :") == 0)
        fail(LIE_ERR_IO, "%s", line.c_str());
    ImportError e{LIE_ERR_FORMAT, line, 0, 0};
    size_t at = line.find(" at line ");
    if (at != std::string::npos && sscanf(line.c_str() + at, " at line %d, column %d", &e.line, &e.col) != 2)
        e.line = e.col = 0;
    throw e;
}

/* When tinygltf refuses a file, a required extension we do not support
 * (Draco or meshopt compression, say) is the better reason to give: their
 * accessors have no data of their own.  The JSON (of a .gltf, or a GLB's
 * first chunk) is read once more, leniently, for extensionsRequired. */
void fail_if_unsupported_required(const std::vector<unsigned char> &d)
{
    const unsigned char *json = d.data();
    size_t len = d.size();
    if (len >= 20 && memcmp(json, "glTF", 4) == 0) {
        uint32_t jl = uint32_t(d[12]) | uint32_t(d[13]) << 8 | uint32_t(d[14]) << 16 | uint32_t(d[15]) << 24;
        len = std::min<size_t>(jl, len - 20);
        json += 20;
    }
    nlohmann::json j = nlohmann::json::parse(json, json + len, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("extensionsRequired") ||
        !j["extensionsRequired"].is_array())
        return;
    for (const auto &e : j["extensionsRequired"]) {
        if (!e.is_string())
            continue;
        std::string name = e.get<std::string>();
        bool ok = false;
        for (const char *s : SUPPORTED_REQUIRED)
            ok |= name == s;
        if (!ok)
            fail(LIE_ERR_UNSUPPORTED, "requires extension %s", clean(name).c_str());
    }
}

/* ---- JSON checks before tinygltf ----------------------------------------
 * tinygltf and nlohmann recurse once per level of JSON nesting, so a file
 * nested 20,000 deep (in extras, say) overflows the stack.  The raw text is
 * scanned first: no parser sees nesting past MAX_JSON_DEPTH. */

const int MAX_JSON_DEPTH = 128;

void check_json_depth(const unsigned char *p, size_t n)
{
    int depth = 0, line = 1, col = 0;
    bool in_string = false, escaped = false;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = p[i];
        col++;
        if (c == '\n') {
            line++;
            col = 0;
        }
        if (in_string) {
            if (escaped)
                escaped = false;
            else if (c == '\\')
                escaped = true;
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > MAX_JSON_DEPTH)
                throw ImportError{LIE_ERR_LIMIT,
                                  "JSON nested deeper than " + std::to_string(MAX_JSON_DEPTH) + " levels", line, col};
        } else if (c == ']' || c == '}') {
            depth--;
        }
    }
}

/* tinygltf drops an optional property of the wrong type or sign and uses
 * its default: a negative byteOffset becomes 0, "bufferView": -1 a view of
 * zeros, "material": -2 the default material.  The glTF 2.0 schema makes
 * every index (glTFid) and every offset, length and count an integer >= 0
 * (byteStride: 4 to 252, a multiple of 4), and a URI an IRI, which holds no
 * NUL.  These are checked on the JSON itself, outside extras and outside
 * extensions this importer does not read. */
struct StrictCheck {
    std::string path;

    [[noreturn]] void refuse(const std::string &key, const std::string &what)
    {
        fail(LIE_ERR_FORMAT, "%s%s%s: %s", path.c_str(), path.empty() ? "" : ".", clean(key).c_str(), what.c_str());
    }

    /* an integer in [lo, hi], or refuse */
    void integer(const nlohmann::json &v, const std::string &key, double lo, double hi)
    {
        double d;
        if (v.is_number_unsigned())
            d = double(v.get<uint64_t>());
        else if (v.is_number_integer())
            d = double(v.get<int64_t>());
        else if (v.is_number_float())
            d = v.get<double>();
        else
            refuse(key, std::string("expected an integer, found ") + v.type_name());
        char num[64];
        if (v.is_number_float())
            snprintf(num, sizeof num, "%.17g", d);
        else
            snprintf(num, sizeof num, "%s", v.dump().c_str());
        if (!(d == floor(d)))
            refuse(key, std::string(num) + " is not an integer");
        if (d < lo || d > hi) {
            char range[96];
            snprintf(range, sizeof range, "%s is not in [%.0f, %.0f]", num, lo, hi);
            refuse(key, range);
        }
    }

    static bool is_index_key(const std::string &k)
    {
        static const char *const keys[] = {"buffer",  "bufferView", "camera", "index",  "indices",
                                           "input",   "inverseBindMatrices",  "light",  "material",
                                           "mesh",    "node",       "output", "sampler", "scene",
                                           "skeleton", "skin",      "source", "texCoord"};
        for (const char *x : keys)
            if (k == x)
                return true;
        return false;
    }

    void object(const nlohmann::json &o, bool top)
    {
        for (auto it = o.begin(); it != o.end(); ++it) {
            const std::string &k = it.key();
            const nlohmann::json &v = it.value();
            if (k == "extras")
                continue;
            if (k == "extensions" && v.is_object()) {
                for (auto e = v.begin(); e != v.end(); ++e) {
                    bool known = false;
                    for (const char *x : SUPPORTED_REQUIRED)
                        known |= e.key() == x;
                    if (known)
                        descend(e.value(), "extensions." + e.key());
                }
                continue;
            }
            if (k == "uri" && v.is_string() && v.get_ref<const std::string &>().find('\0') != std::string::npos)
                refuse(k, "contains a NUL byte");
            if (is_index_key(k) && !(k == "indices" && v.is_object())) {
                integer(v, k, 0, INT32_MAX);
            } else if (k == "byteOffset" || k == "byteLength" || k == "count") {
                integer(v, k, 0, 9007199254740991.0); /* 2^53 - 1, JSON's exact integers */
            } else if (k == "byteStride") {
                integer(v, k, 4, 252);
                if (v.get<double>() != 4 * floor(v.get<double>() / 4))
                    refuse(k, v.dump() + " is not a multiple of 4");
            } else if ((k == "children" || k == "joints" || (k == "nodes" && !top)) && v.is_array()) {
                for (size_t i = 0; i < v.size(); i++)
                    integer(v[i], k + "[" + std::to_string(i) + "]", 0, INT32_MAX);
            } else if (k == "attributes" && v.is_object()) {
                for (auto a = v.begin(); a != v.end(); ++a)
                    integer(a.value(), k + "." + a.key(), 0, INT32_MAX);
            } else if (k == "targets" && v.is_array()) {
                for (size_t i = 0; i < v.size(); i++)
                    if (v[i].is_object())
                        for (auto a = v[i].begin(); a != v[i].end(); ++a)
                            integer(a.value(), k + "[" + std::to_string(i) + "]." + a.key(), 0, INT32_MAX);
            } else {
                descend(v, k);
            }
        }
    }

    void descend(const nlohmann::json &v, const std::string &key)
    {
        if (!v.is_object() && !v.is_array())
            return;
        size_t keep = path.size();
        path += (path.empty() ? "" : ".") + clean(key, 60);
        if (v.is_object()) {
            object(v, false);
        } else {
            std::string base = path;
            for (size_t i = 0; i < v.size(); i++) {
                path = base + "[" + std::to_string(i) + "]";
                if (v[i].is_object())
                    object(v[i], false);
            }
        }
        path.resize(keep);
    }
};

/* The JSON text of a .gltf, or of a GLB's first chunk (checked by glb_check). */
void check_json(const std::vector<unsigned char> &d, bool glb)
{
    const unsigned char *json = d.data();
    size_t len = d.size();
    if (glb) {
        uint32_t jl = uint32_t(d[12]) | uint32_t(d[13]) << 8 | uint32_t(d[14]) << 16 | uint32_t(d[15]) << 24;
        len = std::min<size_t>(jl, len - 20);
        json += 20;
    }
    check_json_depth(json, len);
    nlohmann::json j = nlohmann::json::parse(json, json + len, nullptr, false);
    if (j.is_discarded() || !j.is_object())
        return; /* tinygltf reports the syntax error, with its position */
    StrictCheck c;
    c.object(j, true);
}

/* Parse the file into `model`; `image_errors` gets why external images that
 * tinygltf skipped (with a warning) could not be opened. */
void load_model(tinygltf::Model &model, const char *path, const lie_scene_options &opt,
                std::map<int, std::string> &image_errors, std::map<int, std::vector<unsigned char>> &encoded)
{
    std::vector<unsigned char> data = read_input(path, opt.files);

    FsState fs;
    fs.files = opt.files;
    std::string p(path);
    size_t slash = p.rfind('/');
    /* the folder as tinygltf will join URIs to it ("dir/" + uri, "/" + uri) */
    std::string base = slash == std::string::npos ? std::string(".") : p.substr(0, slash == 0 ? 1 : slash);
    fs.prefix = base.back() == '/' ? base : base + "/";
    fs.allow_external = opt.allow_external_uris != 0;
    if (char *r = realpath(base.c_str(), nullptr)) {
        fs.root = r;
        free(r);
        if (fs.root.back() != '/')
            fs.root += '/';
    }

    ImageState images{&model, {}};
    tinygltf::TinyGLTF loader;
    tinygltf::FsCallbacks cb;
    cb.FileExists = fs_exists;
    cb.ExpandFilePath = fs_expand;
    cb.ReadWholeFile = fs_read;
    cb.WriteWholeFile = fs_write;
    cb.user_data = &fs;
    loader.SetFsCallbacks(cb);
    loader.SetImageLoader(image_load, &images);

    std::string err, warn;
    bool ok;
    if (data.size() >= 4 && memcmp(data.data(), "glTF", 4) == 0) {
        uint32_t length = glb_check(data);
        check_json(data, true);
        ok = loader.LoadBinaryFromMemory(&model, &err, &warn, data.data(), length, base);
    } else {
        check_json(data, false);
        ok = loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char *>(data.data()),
                                        (unsigned)data.size(), base);
    }
    if (!fs.refused.empty())
        fail(LIE_ERR_UNSUPPORTED, "URI '%s' %s", clean(fs.refused).c_str(), fs.refused_why.c_str());
    /* tinygltf's result decides; it also puts notes on problems it tolerated
     * in err.  An external image it could not open is only a warning: that is
     * an error where the image is used (texture_for). */
    if (!ok) {
        fail_if_unsupported_required(data);
        fail_parse(err.empty() ? warn : err, fs);
    }

    for (size_t i = 0; i < model.images.size(); i++) {
        const tinygltf::Image &im = model.images[i];
        if (!images.encoded.count(int(i)) && !im.uri.empty()) {
            auto it = fs.missing.find(percent_decode(im.uri));
            image_errors[int(i)] = "'" + clean(im.uri) + "': cannot open: " +
                                   (it != fs.missing.end() ? it->second : std::string("not loaded"));
        }
    }
    encoded.swap(images.encoded);
}

} // namespace lie_gltf
