/* lib/scene: the glTF 2.0 importer (.gltf and .glb), built on tinygltf.
 *
 * Fills the *document* half of a lie_scene (scene.h); lie_scene_flatten
 * builds the world from it.  This is the trust boundary for scene files
 * (CONTRIBUTING.md, Files): every index, offset, size and count from the file is checked
 * here before it is used, so flatten and the renderer can trust the
 * document.  tinygltf parses the JSON and reads buffers and images through
 * our file-system callbacks, which refuse URIs leaving the scene's folder
 * before anything is opened.
 *
 * Errors travel inside this file as a C++ exception (ImportError) and leave
 * lie_gltf_import as a lie_status; no exception escapes.  Every C array is
 * hung on the scene, with its count, as soon as it is allocated, so
 * lie_scene_destroy frees a half-built document too. */
#include "scene/scene.h"

#include <nlohmann/json.hpp> /* the exporter adds its buffer to tinygltf's JSON */
#include <stb_image.h> /* libstb: the decoder tinygltf uses; its header reader sizes every format */
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <climits>
#include <cfloat>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

namespace {

/* Largest decoded image, in pixels (8192 x 8192); it becomes 16 bytes a
 * pixel as linear float RGBA. */
const uint64_t MAX_IMAGE_PIXELS = uint64_t(1) << 26;

/* extensionsRequired we honour; any other required extension is refused. */
const char *const SUPPORTED_REQUIRED[] = {"KHR_lights_punctual", "KHR_materials_emissive_strength",
                                         "KHR_mesh_quantization", "KHR_texture_transform"};

struct ImportError {
    lie_status status;
    std::string msg;
    int line, col;
};

[[noreturn]] __attribute__((format(printf, 2, 3))) void fail(lie_status status, const char *fmt, ...)
{
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    throw ImportError{status, buf, 0, 0};
}

/* A string from the file, fit for a one-line message. */
std::string clean(const std::string &s, size_t max = 160)
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

/* The first non-empty line of a (possibly multi-line) tinygltf message. */
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

/* ---- file-system callbacks: the URI policy ------------------------------
 * tinygltf joins each (percent-decoded) URI to the folder it was given and
 * then to ".", expands the path, asks FileExists and reads it.  We see the
 * joined path in ExpandFilePath, recover the URI and decide there, so a
 * refused URI is never opened.  The "." fallback (the working directory) is
 * never used: a relative URI means the scene's folder. */

struct FsState {
    std::string prefix; /* the scene's folder as tinygltf joins it, ending in '/' */
    std::string root;   /* the same folder resolved (realpath), ending in '/' */
    bool allow_external;
    std::string refused, refused_why;            /* first URI refused by policy */
    std::map<std::string, std::string> missing;  /* URI -> why it could not be opened */
    std::string last_uri;
    lie_file_set *files; /* lie_scene_options.files: consulted first (lib/core) */
};

/* Does a relative path climb above its starting folder ("a/../../b")? */
bool path_escapes(const std::string &p)
{
    long depth = 0;
    size_t at = 0;
    while (at <= p.size()) {
        size_t end = p.find('/', at);
        if (end == std::string::npos)
            end = p.size();
        std::string seg = p.substr(at, end - at);
        if (seg == "..") {
            if (--depth < 0)
                return true;
        } else if (!seg.empty() && seg != ".") {
            depth++;
        }
        at = end + 1;
    }
    return false;
}

void fs_refuse(FsState &fs, const std::string &uri, const char *why)
{
    if (fs.refused.empty()) {
        fs.refused = uri.empty() ? std::string("(empty)") : uri;
        fs.refused_why = why;
    }
}

std::string fs_expand(const std::string &joined, void *user)
{
    FsState &fs = *static_cast<FsState *>(user);
    fs.last_uri.clear();
    if (joined.compare(0, fs.prefix.size(), fs.prefix) != 0)
        return std::string(); /* tinygltf's second search path, the working directory */
    std::string uri = joined.substr(fs.prefix.size());
    fs.last_uri = uri;
    const char *outside = "leaves the scene's folder (--allow-external-uris permits it)";

    size_t colon = uri.find(':');
    if (colon != std::string::npos && colon > 0 && isalpha((unsigned char)uri[0]) &&
        uri.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+-.") ==
            colon) {
        std::string scheme = uri.substr(0, colon);
        for (char &c : scheme)
            c = (char)tolower((unsigned char)c);
        if (scheme != "file") {
            fs_refuse(fs, uri, "has an unsupported scheme (only data: and relative paths)");
            return std::string();
        }
        if (!fs.allow_external) {
            fs_refuse(fs, uri, outside);
            return std::string();
        }
        std::string p = uri.substr(colon + 1);
        if (p.compare(0, 2, "//") == 0) { /* file://host/path: only an empty host or localhost */
            size_t slash = p.find('/', 2);
            std::string host = p.substr(2, slash == std::string::npos ? std::string::npos : slash - 2);
            if (slash == std::string::npos || !(host.empty() || host == "localhost")) {
                fs_refuse(fs, uri, "names a remote host");
                return std::string();
            }
            p = p.substr(slash);
        }
        return !p.empty() && p[0] == '/' ? p : fs.prefix + p;
    }
    if (!uri.empty() && uri[0] == '/') {
        if (!fs.allow_external) {
            fs_refuse(fs, uri, outside);
            return std::string();
        }
        return uri;
    }
    if (path_escapes(uri) && !fs.allow_external) {
        fs_refuse(fs, uri, outside);
        return std::string();
    }
    return joined;
}

bool fs_exists(const std::string &path, void *user)
{
    FsState &fs = *static_cast<FsState *>(user);
    if (path.empty())
        return false;
    size_t held;
    if (lie_file_set_find(fs.files, path.c_str(), &held))
        return true;
    struct stat st;
    const char *why = nullptr;
    if (fs.files && lie_file_set_get_mode(fs.files) == LIE_FILES_ONLY)
        why = LIE_FILE_SET_MISSING;
    else if (stat(path.c_str(), &st) != 0)
        why = strerror(errno);
    else if (!S_ISREG(st.st_mode))
        why = "not a regular file";
    if (why) {
        if (!fs.last_uri.empty() && !fs.missing.count(fs.last_uri))
            fs.missing[fs.last_uri] = why;
        return false;
    }
    return true;
}

/* The file an open descriptor reads, with every symlink resolved. */
std::string fd_realpath(int fd, const std::string &path)
{
    char link[64], buf[PATH_MAX + 1];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    ssize_t n = readlink(link, buf, sizeof buf - 1);
    if (n > 0 && buf[0] == '/') {
        buf[n] = 0;
        return buf;
    }
    char *r = realpath(path.c_str(), nullptr); /* no /proc: resolve the name instead */
    std::string out = r ? r : "";
    free(r);
    return out;
}

/* Buffers and images: opened non-blocking and fstat-checked (a FIFO cannot
 * hang, a device cannot stream forever), and, unless external URIs are
 * allowed, the file actually opened must lie inside the scene's folder:
 * the URI's text may stay inside while a symlink leads out. */
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user)
{
    FsState &fs = *static_cast<FsState *>(user);
    size_t held;
    if (const unsigned char *d = lie_file_set_find(fs.files, path.c_str(), &held)) {
        /* read on another process, through the checks below */
        out->assign(d, d + held);
        return true;
    }
    int fd;
    uint64_t size;
    lie_error e{};
    if (fs.files && lie_file_set_get_mode(fs.files) == LIE_FILES_ONLY) {
        if (err)
            *err = LIE_FILE_SET_MISSING;
        if (!fs.last_uri.empty() && !fs.missing.count(fs.last_uri))
            fs.missing[fs.last_uri] = LIE_FILE_SET_MISSING;
        return false;
    }
    if (lie_input_open(path.c_str(), LIE_READ_MAX_GLTF, &fd, &size, &e) != LIE_OK) {
        if (err)
            *err = e.msg;
        if (!fs.last_uri.empty() && !fs.missing.count(fs.last_uri))
            fs.missing[fs.last_uri] = e.msg;
        return false;
    }
    if (!fs.allow_external) {
        std::string real = fd_realpath(fd, path);
        if (fs.root.empty() || real.compare(0, fs.root.size(), fs.root) != 0) {
            close(fd);
            fs_refuse(fs, fs.last_uri.empty() ? path : fs.last_uri,
                      "resolves (through a symlink) outside the scene's folder (--allow-external-uris permits it)");
            if (err)
                *err = "outside the scene's folder";
            return false;
        }
    }
    unsigned char *data = nullptr;
    size_t n = 0;
    lie_status st = lie_read_fd(fd, path.c_str(), LIE_READ_MAX_GLTF, size, &data, &n, &e);
    close(fd);
    if (st != LIE_OK) {
        if (err)
            *err = e.msg;
        return false;
    }
    try {
        out->assign(data, data + n);
    } catch (...) {
        free(data);
        throw;
    }
    free(data);
    if (fs.files && lie_file_set_add(fs.files, path.c_str(), out->data(), out->size(), &e) != LIE_OK) {
        if (err)
            *err = e.msg;
        return false;
    }
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
    if (err)
        *err = "the importer never writes";
    return false;
}

/* ---- images ---------------------------------------------------------------
 * tinygltf hands an image stored in a bufferView to the decoder without
 * checking the view's range against its buffer, so this loader checks it
 * first.  It decodes nothing: it keeps the encoded bytes, and an image is
 * decoded only when a material uses it (texture_for), after its header
 * (stb_image's stbi_info_from_memory, which reads the header of every
 * format stb decodes: PNG, JPEG, BMP, GIF, PSD, PIC, PNM, TGA, HDR) showed
 * it within MAX_IMAGE_PIXELS.  A 70-byte BMP claiming 40000 x 13000 pixels
 * then costs nothing unused, and one line of error used. */

struct ImageState {
    const tinygltf::Model *model;
    std::map<int, std::vector<unsigned char>> encoded; /* image -> its bytes, undecoded */
};

bool image_load(tinygltf::Image *image, const int index, std::string *err, std::string *warn, int req_w,
                int req_h, const unsigned char *bytes, int size, void *user)
{
    ImageState &st = *static_cast<ImageState *>(user);
    if (image->bufferView >= 0) {
        const tinygltf::Model &m = *st.model;
        bool ok = size_t(image->bufferView) < m.bufferViews.size();
        if (ok) {
            const tinygltf::BufferView &bv = m.bufferViews[size_t(image->bufferView)];
            ok = bv.buffer >= 0 && size_t(bv.buffer) < m.buffers.size() &&
                 bv.byteOffset <= m.buffers[size_t(bv.buffer)].data.size() &&
                 bv.byteLength <= m.buffers[size_t(bv.buffer)].data.size() - bv.byteOffset &&
                 bv.byteLength <= size_t(INT_MAX);
        }
        if (!ok) {
            if (err)
                *err += "image " + std::to_string(index) + ": bufferView lies outside its buffer\n";
            return false;
        }
    }
    if (size <= 0) {
        if (err)
            *err += "image " + std::to_string(index) + " is empty\n";
        return false;
    }
    st.encoded[index].assign(bytes, bytes + size);
    image->image.clear();
    image->width = image->height = 0;
    return true;
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
 * tinygltf skipped (with a warning) could not be opened, `encoded` every
 * image's bytes, undecoded (image_load). */
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

/* ---- accessors ------------------------------------------------------------
 * An accessor is checked completely (views, buffers, ranges, sparse parts)
 * before any element is read; reading then trusts it. */

size_t component_size(int ctype)
{
    switch (ctype) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

size_t type_components(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT4: return 16; /* float only where used (inverse bind matrices): no column padding */
    default: return 0;
    }
}

struct Accessor {
    size_t count, ncomp, csize, stride;
    int ctype;
    bool normalized;
    const unsigned char *data;  /* element 0, or NULL: all zeros (no bufferView) */
    size_t sparse_count;
    int sparse_itype;
    const unsigned char *sparse_idx, *sparse_val;
};

/* The bytes of a buffer view, range-checked against its buffer. */
const unsigned char *view_bytes(const tinygltf::Model &m, int view, size_t *length, const std::string &what)
{
    if (view < 0 || size_t(view) >= m.bufferViews.size())
        fail(LIE_ERR_FORMAT, "%s: bufferView %d out of range", what.c_str(), view);
    const tinygltf::BufferView &bv = m.bufferViews[size_t(view)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= m.buffers.size())
        fail(LIE_ERR_FORMAT, "%s: bufferView %d: buffer %d out of range", what.c_str(), view, bv.buffer);
    const std::vector<unsigned char> &b = m.buffers[size_t(bv.buffer)].data;
    if (bv.byteOffset > b.size() || bv.byteLength > b.size() - bv.byteOffset)
        fail(LIE_ERR_FORMAT, "%s: bufferView %d (offset %zu, length %zu) lies outside buffer %d of %zu bytes",
             what.c_str(), view, bv.byteOffset, bv.byteLength, bv.buffer, b.size());
    *length = bv.byteLength;
    return b.data() + bv.byteOffset;
}

/* Is [offset, offset + stride * (count - 1) + elem) inside [0, length)? */
bool range_fits(size_t offset, size_t stride, size_t count, size_t elem, size_t length)
{
    if (count == 0)
        return offset <= length;
    size_t span, end;
    if (__builtin_mul_overflow(stride, count - 1, &span) || __builtin_add_overflow(span, elem, &span) ||
        __builtin_add_overflow(offset, span, &end))
        return false;
    return end <= length;
}

Accessor check_accessor(const tinygltf::Model &m, int index, const std::string &what)
{
    if (index < 0 || size_t(index) >= m.accessors.size())
        fail(LIE_ERR_FORMAT, "%s: accessor %d out of range", what.c_str(), index);
    const tinygltf::Accessor &a = m.accessors[size_t(index)];
    std::string w = what + ": accessor " + std::to_string(index);
    Accessor r{};
    r.count = a.count;
    r.ctype = a.componentType;
    r.normalized = a.normalized;
    r.csize = component_size(a.componentType);
    r.ncomp = type_components(a.type);
    if (!r.csize || !r.ncomp)
        fail(LIE_ERR_FORMAT, "%s has an unsupported type or componentType", w.c_str());
    size_t elem = r.csize * r.ncomp;
    r.stride = elem;
    if (a.bufferView >= 0) {
        size_t length;
        const unsigned char *base = view_bytes(m, a.bufferView, &length, w);
        size_t bs = m.bufferViews[size_t(a.bufferView)].byteStride;
        if (bs != 0) {
            if (bs < elem)
                fail(LIE_ERR_FORMAT, "%s: byteStride %zu is less than its element size %zu", w.c_str(), bs, elem);
            r.stride = bs;
        }
        if (!range_fits(a.byteOffset, r.stride, r.count, elem, length))
            fail(LIE_ERR_FORMAT, "%s: %zu elements from offset %zu run past its bufferView of %zu bytes",
                 w.c_str(), r.count, a.byteOffset, length);
        r.data = base + a.byteOffset;
    } else if (a.byteOffset != 0) {
        fail(LIE_ERR_FORMAT, "%s has a byteOffset but no bufferView", w.c_str());
    }
    if (a.sparse.isSparse) {
        const auto &sp = a.sparse;
        if (sp.count < 1 || size_t(sp.count) > r.count)
            fail(LIE_ERR_FORMAT, "%s: sparse count %d not in [1, %zu]", w.c_str(), sp.count, r.count);
        r.sparse_count = size_t(sp.count);
        r.sparse_itype = sp.indices.componentType;
        size_t isize = component_size(r.sparse_itype);
        if (r.sparse_itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            r.sparse_itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            r.sparse_itype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(LIE_ERR_FORMAT, "%s: sparse indices must be unsigned integers", w.c_str());
        size_t ilen, vlen;
        const unsigned char *ib = view_bytes(m, sp.indices.bufferView, &ilen, w + " sparse indices");
        const unsigned char *vb = view_bytes(m, sp.values.bufferView, &vlen, w + " sparse values");
        if (sp.indices.byteOffset < 0 || !range_fits(size_t(sp.indices.byteOffset), isize, r.sparse_count, isize, ilen))
            fail(LIE_ERR_FORMAT, "%s: sparse indices run past their bufferView", w.c_str());
        if (sp.values.byteOffset < 0 || !range_fits(size_t(sp.values.byteOffset), elem, r.sparse_count, elem, vlen))
            fail(LIE_ERR_FORMAT, "%s: sparse values run past their bufferView", w.c_str());
        r.sparse_idx = ib + sp.indices.byteOffset;
        r.sparse_val = vb + sp.values.byteOffset;
        for (size_t k = 0; k < r.sparse_count; k++) {
            const unsigned char *p = r.sparse_idx + k * isize;
            uint32_t i = isize == 1 ? p[0] : isize == 2 ? uint32_t(p[0]) | uint32_t(p[1]) << 8
                                                         : uint32_t(p[0]) | uint32_t(p[1]) << 8 |
                                                               uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
            if (i >= r.count)
                fail(LIE_ERR_FORMAT, "%s: sparse index %u beyond its count %zu", w.c_str(), i, r.count);
        }
    }
    return r;
}

/* One component as a number (glTF is little-endian, as is every target we
 * build for; memcpy keeps unaligned reads defined). */
double component(const unsigned char *p, int ctype, bool normalized)
{
    switch (ctype) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float f;
        memcpy(&f, p, 4);
        return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        memcpy(&v, p, 1);
        return normalized ? fmax(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        memcpy(&v, p, 2);
        return normalized ? fmax(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        memcpy(&v, p, 4);
        return v;
    }
    default: return 0.0;
    }
}

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

void read_floats(const Accessor &a, float *dst, const std::string &what)
{
    bool finite = true;
    accessor_each(a, [&](size_t i, size_t c, double v) {
        dst[i * a.ncomp + c] = float(v);
        finite = finite && std::isfinite(float(v));
    });
    if (!finite)
        fail(LIE_ERR_FORMAT, "%s has a value that is not a finite number", what.c_str());
}

/* ---- meshes ---------------------------------------------------------------- */

struct PrimPlan {
    bool skip;                   /* points or lines */
    int mode;
    Accessor pos, nrm, uv, uv1, col, idx;
    bool has_nrm, has_uv, has_uv1, has_col, has_idx;
    size_t n_verts, n_idx, n_tris;
    /* morph targets: position and normal displacements (index -1: none) */
    std::vector<Accessor> tpos, tnrm;
    std::vector<int> tpos_at, tnrm_at;
    Accessor joints, wts;        /* JOINTS_0, WEIGHTS_0 (skins) */
    bool has_skin;
};

int attribute(const tinygltf::Primitive &p, const char *name)
{
    auto it = p.attributes.find(name);
    return it == p.attributes.end() ? -1 : it->second;
}

bool uses_extension(const tinygltf::Model &m, const char *name)
{
    for (const std::string &e : m.extensionsUsed)
        if (e == name)
            return true;
    for (const std::string &e : m.extensionsRequired)
        if (e == name)
            return true;
    return false;
}

/* The integer component types KHR_mesh_quantization allows for positions
 * and texture coordinates (normalized or not). */
bool small_int(int ctype)
{
    return ctype == TINYGLTF_COMPONENT_TYPE_BYTE || ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
           ctype == TINYGLTF_COMPONENT_TYPE_SHORT || ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
}

/* JOINTS_0 and WEIGHTS_0 (glTF 2.0 §3.7.3.1): both or neither; sets
 * beyond the first are not read. */
void plan_skin_attributes(const tinygltf::Model &m, const tinygltf::Primitive &p, const std::string &what,
                          PrimPlan &pl)
{
    int aj = attribute(p, "JOINTS_0"), aw = attribute(p, "WEIGHTS_0");
    if (aj < 0 && aw < 0)
        return;
    if (aj < 0 || aw < 0)
        fail(LIE_ERR_FORMAT, "%s: JOINTS_0 and WEIGHTS_0 come together", what.c_str());
    pl.joints = check_accessor(m, aj, what + " JOINTS_0");
    pl.wts = check_accessor(m, aw, what + " WEIGHTS_0");
    if (pl.joints.ncomp != 4 || (pl.joints.ctype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                 pl.joints.ctype != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
        fail(LIE_ERR_FORMAT, "%s: JOINTS_0 must be VEC4 UNSIGNED_BYTE or UNSIGNED_SHORT", what.c_str());
    if (pl.wts.ncomp != 4 ||
        !(pl.wts.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT ||
          (pl.wts.normalized && (pl.wts.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                 pl.wts.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))))
        fail(LIE_ERR_FORMAT, "%s: WEIGHTS_0 must be VEC4 FLOAT or normalized UNSIGNED_BYTE/SHORT", what.c_str());
    if (pl.joints.count != pl.pos.count || pl.wts.count != pl.pos.count)
        fail(LIE_ERR_FORMAT, "%s: JOINTS_0 and WEIGHTS_0 need one element per vertex (%zu)", what.c_str(),
             pl.pos.count);
    pl.has_skin = true;
}

/* Check a primitive and count its triangles; nothing is allocated yet. */
PrimPlan plan_primitive(const tinygltf::Model &m, int mi, int pi, lie_scene *s)
{
    const tinygltf::Primitive &p = m.meshes[size_t(mi)].primitives[size_t(pi)];
    std::string what = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
    PrimPlan pl{};
    if (p.material >= 0 && size_t(p.material) >= m.materials.size())
        fail(LIE_ERR_FORMAT, "%s: material %d out of range", what.c_str(), p.material);
    pl.mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
    switch (pl.mode) {
    case TINYGLTF_MODE_POINTS:
        s->stats.points_skipped++;
        pl.skip = true;
        return pl;
    case TINYGLTF_MODE_LINE:
    case TINYGLTF_MODE_LINE_LOOP:
    case TINYGLTF_MODE_LINE_STRIP:
        s->stats.lines_skipped++;
        pl.skip = true;
        return pl;
    case TINYGLTF_MODE_TRIANGLES:
    case TINYGLTF_MODE_TRIANGLE_STRIP:
    case TINYGLTF_MODE_TRIANGLE_FAN: break;
    default: fail(LIE_ERR_FORMAT, "%s: unknown mode %d", what.c_str(), p.mode);
    }
    if (p.material < 0)
        s->stats.prims_without_material++;

    int ap = attribute(p, "POSITION");
    if (ap < 0)
        fail(LIE_ERR_FORMAT, "%s has no POSITION", what.c_str());
    /* KHR_mesh_quantization widens the attribute types (gltfpack and other
     * optimisers write it); the node transforms carry the dequantisation. */
    const bool quant = uses_extension(m, "KHR_mesh_quantization");
    pl.pos = check_accessor(m, ap, what + " POSITION");
    if (pl.pos.ncomp != 3 || !(pl.pos.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT || (quant && small_int(pl.pos.ctype))))
        fail(LIE_ERR_FORMAT, "%s: POSITION must be VEC3 FLOAT%s", what.c_str(),
             quant ? " or (KHR_mesh_quantization) BYTE/SHORT, signed or unsigned" : "");
    pl.n_verts = pl.pos.count;

    int an = attribute(p, "NORMAL");
    if ((pl.has_nrm = an >= 0)) {
        pl.nrm = check_accessor(m, an, what + " NORMAL");
        bool ok = pl.nrm.ncomp == 3 &&
                  (pl.nrm.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                   (quant && pl.nrm.normalized &&
                    (pl.nrm.ctype == TINYGLTF_COMPONENT_TYPE_BYTE || pl.nrm.ctype == TINYGLTF_COMPONENT_TYPE_SHORT)));
        if (!ok)
            fail(LIE_ERR_FORMAT, "%s: NORMAL must be VEC3 FLOAT%s", what.c_str(),
                 quant ? " or (KHR_mesh_quantization) normalized BYTE/SHORT" : "");
        if (pl.nrm.count != pl.n_verts)
            fail(LIE_ERR_FORMAT, "%s: NORMAL has %zu elements, POSITION %zu", what.c_str(), pl.nrm.count,
                 pl.n_verts);
    }
    for (int set = 0; set < 2; set++) {
        const char *name = set ? "TEXCOORD_1" : "TEXCOORD_0";
        int at = attribute(p, name);
        bool &has = set ? pl.has_uv1 : pl.has_uv;
        Accessor &uv = set ? pl.uv1 : pl.uv;
        if (!(has = at >= 0))
            continue;
        uv = check_accessor(m, at, what + " " + name);
        bool ok = uv.ncomp == 2 &&
                  (uv.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT || (quant && small_int(uv.ctype)) ||
                   (uv.normalized && (uv.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                      uv.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)));
        if (!ok)
            fail(LIE_ERR_FORMAT, "%s: %s must be VEC2 FLOAT or normalized UNSIGNED_BYTE/SHORT%s", what.c_str(),
                 name, quant ? " (or, KHR_mesh_quantization, any BYTE/SHORT)" : "");
        if (uv.count != pl.n_verts)
            fail(LIE_ERR_FORMAT, "%s: %s has %zu elements, POSITION %zu", what.c_str(), name, uv.count,
                 pl.n_verts);
    }
    int ac = attribute(p, "COLOR_0");
    if ((pl.has_col = ac >= 0)) {
        pl.col = check_accessor(m, ac, what + " COLOR_0");
        bool ok = (pl.col.ncomp == 3 || pl.col.ncomp == 4) &&
                  (pl.col.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                   (pl.col.normalized && (pl.col.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                          pl.col.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)));
        if (!ok)
            fail(LIE_ERR_FORMAT, "%s: COLOR_0 must be VEC3 or VEC4, FLOAT or normalized UNSIGNED_BYTE/SHORT",
                 what.c_str());
        if (pl.col.count != pl.n_verts)
            fail(LIE_ERR_FORMAT, "%s: COLOR_0 has %zu elements, POSITION %zu", what.c_str(), pl.col.count,
                 pl.n_verts);
    }
    plan_skin_attributes(m, p, what, pl);
    /* Morph targets (glTF 2.0 §3.7.2.2): POSITION and NORMAL displacements
     * are applied with the default weights; TANGENT and others are not used. */
    for (size_t t = 0; t < p.targets.size(); t++) {
        std::string tw = what + " target " + std::to_string(t);
        Accessor none{};
        pl.tpos.push_back(none);
        pl.tnrm.push_back(none);
        pl.tpos_at.push_back(-1);
        pl.tnrm_at.push_back(-1);
        auto ip = p.targets[t].find("POSITION");
        if (ip != p.targets[t].end()) {
            Accessor a = check_accessor(m, ip->second, tw + " POSITION");
            if (a.ncomp != 3 || !(a.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT || (quant && small_int(a.ctype))))
                fail(LIE_ERR_FORMAT, "%s POSITION must be VEC3 FLOAT%s", tw.c_str(),
                     quant ? " or (KHR_mesh_quantization) BYTE/SHORT" : "");
            if (a.count != pl.n_verts)
                fail(LIE_ERR_FORMAT, "%s POSITION has %zu elements, POSITION %zu", tw.c_str(), a.count,
                     pl.n_verts);
            pl.tpos.back() = a;
            pl.tpos_at.back() = ip->second;
        }
        auto in = p.targets[t].find("NORMAL");
        if (in != p.targets[t].end()) {
            Accessor a = check_accessor(m, in->second, tw + " NORMAL");
            if (a.ncomp != 3 || !(a.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                                  (quant && a.normalized &&
                                   (a.ctype == TINYGLTF_COMPONENT_TYPE_BYTE || a.ctype == TINYGLTF_COMPONENT_TYPE_SHORT))))
                fail(LIE_ERR_FORMAT, "%s NORMAL must be VEC3 FLOAT%s", tw.c_str(),
                     quant ? " or (KHR_mesh_quantization) normalized BYTE/SHORT" : "");
            if (a.count != pl.n_verts)
                fail(LIE_ERR_FORMAT, "%s NORMAL has %zu elements, POSITION %zu", tw.c_str(), a.count, pl.n_verts);
            pl.tnrm.back() = a;
            pl.tnrm_at.back() = in->second;
        }
    }
    if ((pl.has_idx = p.indices >= 0)) {
        pl.idx = check_accessor(m, p.indices, what + " indices");
        bool ok = pl.idx.ncomp == 1 && (pl.idx.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                        pl.idx.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                                        pl.idx.ctype == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
        if (!ok)
            fail(LIE_ERR_FORMAT, "%s: indices must be SCALAR UNSIGNED_BYTE/SHORT/INT", what.c_str());
        pl.n_idx = pl.idx.count;
    } else {
        pl.n_idx = pl.n_verts;
    }
    if (pl.mode == TINYGLTF_MODE_TRIANGLES) {
        if (pl.n_idx % 3 != 0)
            fail(LIE_ERR_FORMAT, "%s: %zu vertices do not make whole triangles", what.c_str(), pl.n_idx);
        pl.n_tris = pl.n_idx / 3;
    } else {
        pl.n_tris = pl.n_idx >= 3 ? pl.n_idx - 2 : 0;
    }
    return pl;
}

/* Read a planned primitive into `out` (attached to the scene already). */
void read_primitive(const PrimPlan &pl, int mi, int pi, lie_primitive *out)
{
    std::string what = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
    out->n_verts = uint32_t(pl.n_verts);
    out->pos = alloc_array<float>(mul_size(pl.n_verts, 3, what.c_str()));
    read_floats(pl.pos, out->pos, what + " POSITION");
    if (pl.has_nrm) {
        out->nrm = alloc_array<float>(pl.n_verts * 3);
        read_floats(pl.nrm, out->nrm, what + " NORMAL");
    }
    if (pl.has_uv) {
        out->uv = alloc_array<float>(pl.n_verts * 2);
        read_floats(pl.uv, out->uv, what + " TEXCOORD_0");
    }
    if (pl.has_uv1) {
        out->uv1 = alloc_array<float>(pl.n_verts * 2);
        read_floats(pl.uv1, out->uv1, what + " TEXCOORD_1");
    }
    if (pl.has_col) {
        /* RGBA per vertex, alpha 1 for RGB; linear already (glTF 2.0
         * §3.7.2.1), and a multiplier, so kept in [0, 1] */
        std::vector<float> raw(pl.n_verts * pl.col.ncomp);
        read_floats(pl.col, raw.data(), what + " COLOR_0");
        out->color = alloc_array<float>(pl.n_verts * 4);
        for (size_t v = 0; v < pl.n_verts; v++)
            for (size_t c = 0; c < 4; c++) {
                float x = c < pl.col.ncomp ? raw[v * pl.col.ncomp + c] : 1.0f;
                out->color[v * 4 + c] = x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
            }
    }

    if (pl.has_skin) {
        out->joints = alloc_array<uint16_t>(pl.n_verts * 4);
        out->weights = alloc_array<float>(pl.n_verts * 4);
        accessor_each(pl.joints, [&](size_t i, size_t c, double x) { out->joints[i * 4 + c] = uint16_t(x); });
        read_floats(pl.wts, out->weights, what + " WEIGHTS_0");
    }

    std::vector<uint32_t> v(pl.n_idx);
    if (pl.has_idx) {
        accessor_each(pl.idx, [&](size_t i, size_t, double x) { v[i] = uint32_t(x); });
        for (uint32_t i : v)
            if (i >= pl.n_verts)
                fail(LIE_ERR_FORMAT, "%s: index %u beyond vertex count %zu", what.c_str(), i, pl.n_verts);
    } else {
        for (size_t i = 0; i < pl.n_idx; i++)
            v[i] = uint32_t(i);
    }

    out->idx = alloc_array<uint32_t>(mul_size(pl.n_tris, 3, what.c_str()));
    uint32_t *t = out->idx;
    for (size_t k = 0; k < pl.n_tris; k++, t += 3) {
        /* glTF 2.0 §3.7.2.1: strip p_k = {v_k, v_k+1+k%2, v_k+2-k%2} keeps
         * every triangle's winding; fan p_k = {v_k+1, v_k+2, v_0} */
        if (pl.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            t[0] = v[k];
            t[1] = v[k + 1 + k % 2];
            t[2] = v[k + 2 - k % 2];
        } else if (pl.mode == TINYGLTF_MODE_TRIANGLE_FAN) {
            t[0] = v[k + 1];
            t[1] = v[k + 2];
            t[2] = v[0];
        } else {
            t[0] = v[3 * k];
            t[1] = v[3 * k + 1];
            t[2] = v[3 * k + 2];
        }
    }
    out->n_tris = uint32_t(pl.n_tris);
}

/* Keep a read primitive's targets (for edits of its weights) and morph it
 * with weights w (lie_primitive_morph). */
void apply_morph(const PrimPlan &pl, const std::vector<double> &w, int mi, int pi, lie_primitive *out)
{
    size_t nt = pl.tpos.size();
    if (nt == 0)
        return;
    std::string what = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
    size_t n = mul_size(pl.n_verts, 3, what.c_str());
    out->n_targets = int(nt);
    out->base_pos = alloc_array<float>(n);
    memcpy(out->base_pos, out->pos, sizeof(float) * n);
    out->tpos = alloc_array<float>(mul_size(n, nt, what.c_str()));
    if (out->nrm) {
        out->base_nrm = alloc_array<float>(n);
        memcpy(out->base_nrm, out->nrm, sizeof(float) * n);
        out->tnrm = alloc_array<float>(n * nt);
    }
    for (size_t t = 0; t < nt; t++) {
        std::string tw = what + " target " + std::to_string(t);
        if (pl.tpos_at[t] >= 0)
            read_floats(pl.tpos[t], out->tpos + t * n, tw + " POSITION");
        if (pl.tnrm_at[t] >= 0 && out->tnrm)
            read_floats(pl.tnrm[t], out->tnrm + t * n, tw + " NORMAL");
    }
    if (lie_primitive_morph(out, w.data(), int(w.size())) != LIE_OK)
        fail(LIE_ERR_FORMAT, "%s: a morphed position is not a finite number", what.c_str());
}

/* The weights a node's instance of mesh mi is drawn with: the node's, else
 * the mesh's, else zeros (§3.7.2.2); checked against the target count. */
std::vector<double> morph_weights(const tinygltf::Model &m, size_t mi, const std::vector<double> *node_w,
                                  const std::string &w)
{
    const tinygltf::Mesh &g = m.meshes[mi];
    size_t nt = g.primitives.empty() ? 0 : g.primitives[0].targets.size();
    for (size_t pi = 1; pi < g.primitives.size(); pi++)
        if (g.primitives[pi].targets.size() != nt)
            fail(LIE_ERR_FORMAT, "mesh %zu: primitives have %zu and %zu morph targets (they must agree)", mi, nt,
                 g.primitives[pi].targets.size());
    if (nt == 0)
        return std::vector<double>(); /* weights without targets change nothing */
    const std::vector<double> &src = node_w && !node_w->empty() ? *node_w : g.weights;
    if (!src.empty() && src.size() != nt)
        fail(LIE_ERR_FORMAT, "%s: %zu morph weights for %zu targets", w.c_str(), src.size(), nt);
    for (double x : src)
        if (!std::isfinite(x))
            fail(LIE_ERR_FORMAT, "%s: a morph weight is not a finite number", w.c_str());
    return src.empty() ? std::vector<double>(nt, 0.0) : src;
}

/* ---- textures and materials -------------------------------------------- */

struct Import {
    const tinygltf::Model &m;
    lie_scene *s;
    const std::map<int, std::string> &image_errors;               /* from load_model */
    const std::map<int, std::vector<unsigned char>> &encoded;     /* from load_model: images' bytes */
    std::map<int, tinygltf::Image> decoded;                       /* images decoded so far */
    std::map<int, int> texture_of; /* glTF texture * 2 + srgb -> s->textures index */
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

lie_wrap wrap_mode(int mode, const std::string &what)
{
    switch (mode) {
    case TINYGLTF_TEXTURE_WRAP_REPEAT: return LIE_WRAP_REPEAT;
    case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return LIE_WRAP_CLAMP;
    case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return LIE_WRAP_MIRROR;
    default: fail(LIE_ERR_FORMAT, "%s: unknown wrap mode %d", what.c_str(), mode);
    }
}

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }

/* The value of code i of an image with `levels` code values; the exporter
 * inverts exactly this. */
float code_value(size_t i, size_t levels, bool srgb)
{
    double c = double(i) / double(levels - 1);
    return float(srgb ? srgb_to_linear(c) : c);
}

/* Image `index` decoded, once: its size from the header first (any format
 * stb reads), refused past MAX_IMAGE_PIXELS before anything is allocated;
 * then stb's decoding, expanded to 8- or 16-bit RGBA (tinygltf's default
 * options).  An image the decoder cannot read sets *why and comes back
 * without pixels; one that was never loaded comes back without pixels. */
const tinygltf::Image &decode_image(Import &im, int index, std::string *why)
{
    auto done = im.decoded.find(index);
    if (done != im.decoded.end())
        return done->second;
    tinygltf::Image &img = im.decoded[index] = im.m.images[size_t(index)];
    auto enc = im.encoded.find(index);
    if (enc == im.encoded.end())
        return img;
    const std::vector<unsigned char> &b = enc->second;
    std::string name = !img.uri.empty() && img.uri.compare(0, 5, "data:") != 0 ? " '" + clean(img.uri) + "'"
                       : !img.name.empty()                                   ? " '" + clean(img.name) + "'"
                                                                             : std::string();
    std::string iw = "image " + std::to_string(index) + name;
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(b.data(), int(b.size()), &w, &h, &comp)) {
        *why = iw + ": cannot decode (not an image format the decoder reads)";
        return img;
    }
    if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > MAX_IMAGE_PIXELS)
        fail(LIE_ERR_LIMIT, "image %d is %dx%d, beyond the limit of %llu pixels", index, w, h,
             (unsigned long long)MAX_IMAGE_PIXELS);
    std::string derr, warn;
    if (!tinygltf::LoadImageData(&img, index, &derr, &warn, 0, 0, b.data(), int(b.size()), nullptr)) {
        img.image.clear();
        img.width = img.height = 0;
        *why = iw + ": cannot decode (the decoder refused it)";
    }
    return img;
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
    std::string why; /* why the decoder cannot read it */
    const tinygltf::Image &img = decode_image(im, tex.source, &why);
    if (!why.empty()) {
        /* An image the decoder cannot read (a corrupt PNG, a KTX2 or WebP
         * named as a plain source) is not the whole scene's failure: the
         * slots using it fall back to their factors, as Blender and three.js
         * do, with a warning.  Required extensions are refused earlier. */
        if (im.warned.insert(tex.source).second)
            scene_warn(im.s, why + "; its textures fall back to their factors");
        return -1;
    }
    if (img.image.empty() || img.width <= 0 || img.height <= 0) {
        auto e = im.image_errors.find(tex.source);
        if (e != im.image_errors.end())
            fail(LIE_ERR_IO, "%s %s", iw.c_str(), e->second.c_str());
        fail(LIE_ERR_FORMAT, "%s has no decoded pixels", iw.c_str());
    }
    size_t bytes = img.bits == 8 ? 1 : img.bits == 16 ? 2 : 0;
    if (!bytes || img.component < 1 || img.component > 4)
        fail(LIE_ERR_UNSUPPORTED, "%s: %d-bit, %d-channel images are not supported", iw.c_str(), img.bits,
             img.component);
    size_t w = size_t(img.width), h = size_t(img.height), nc = size_t(img.component);
    if (uint64_t(w) * h > MAX_IMAGE_PIXELS)
        fail(LIE_ERR_LIMIT, "%s is %zux%zu, beyond the limit of %llu pixels", iw.c_str(), w, h,
             (unsigned long long)MAX_IMAGE_PIXELS);
    if (img.image.size() != w * h * nc * bytes)
        fail(LIE_ERR_FORMAT, "%s: decoded size does not match %zux%zu", iw.c_str(), w, h);

    lie_wrap ws = LIE_WRAP_REPEAT, wt = LIE_WRAP_REPEAT;
    if (tex.sampler >= 0) {
        if (size_t(tex.sampler) >= m.samplers.size())
            fail(LIE_ERR_FORMAT, "%s: sampler %d out of range", tw.c_str(), tex.sampler);
        const tinygltf::Sampler &sm = m.samplers[size_t(tex.sampler)];
        std::string sw = "sampler " + std::to_string(tex.sampler);
        ws = wrap_mode(sm.wrapS, sw);
        wt = wrap_mode(sm.wrapT, sw);
    }

    /* colour channels through the sRGB transfer function when asked, alpha
     * always linear; a table over every code value */
    size_t levels = bytes == 1 ? 256 : 65536;
    std::vector<float> lin(levels), enc(levels);
    for (size_t i = 0; i < levels; i++) {
        lin[i] = code_value(i, levels, false);
        enc[i] = code_value(i, levels, srgb);
    }
    float *rgba = alloc_array<float>(w * h * 4); /* w * h <= MAX_IMAGE_PIXELS */
    lie_texture &t = im.s->textures[im.s->n_textures];
    t.width = int(w);
    t.height = int(h);
    t.rgba = rgba;
    t.wrap_s = ws;
    t.wrap_t = wt;
    int index = im.s->n_textures++;
    im.texture_of[ti * 2 + srgb] = index;

    const unsigned char *src = img.image.data();
    for (size_t i = 0; i < w * h; i++, src += nc * bytes) {
        size_t code[4];
        for (size_t c = 0; c < nc; c++)
            code[c] = bytes == 1 ? src[c] : (size_t(src[2 * c]) | size_t(src[2 * c + 1]) << 8);
        float *d = rgba + 4 * i;
        switch (nc) { /* grey, grey + alpha, RGB, RGBA */
        case 1: d[0] = d[1] = d[2] = enc[code[0]]; d[3] = 1.0f; break;
        case 2: d[0] = d[1] = d[2] = enc[code[0]]; d[3] = lin[code[1]]; break;
        case 3: d[0] = enc[code[0]]; d[1] = enc[code[1]]; d[2] = enc[code[2]]; d[3] = 1.0f; break;
        default: d[0] = enc[code[0]]; d[1] = enc[code[1]]; d[2] = enc[code[2]]; d[3] = lin[code[3]]; break;
        }
    }
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
int texture_info(Import &im, const tinygltf::TextureInfo &ti, bool srgb, const std::string &what, float param[5],
                 int *set)
{
    *set = 0;
    if (ti.index < 0)
        return -1;
    if (ti.texCoord < 0)
        fail(LIE_ERR_FORMAT, "%s: texCoord must be >= 0", what.c_str());
    *set = ti.texCoord == 1 ? 1 : 0;
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

void import_materials(Import &im)
{
    const tinygltf::Model &m = im.m;
    lie_scene *s = im.s;
    if (m.textures.size() > size_t(INT_MAX / 2) || m.materials.size() > size_t(INT_MAX))
        fail(LIE_ERR_LIMIT, "too many materials or textures");
    s->textures = alloc_array<lie_texture>(m.textures.size() * 2); /* at most one per colour space */
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

/* ---- skins and animations ------------------------------------------------ */

/* glTF 2.0 §3.7.3: joints, inverse bind matrices (MAT4 FLOAT, one per
 * joint; identities when absent), and the skinned nodes' vertex joints
 * within range. */
void import_skins(const tinygltf::Model &m, lie_scene *s)
{
    s->skins = alloc_list<lie_skin>(m.skins, &s->n_skins, "skins");
    for (size_t i = 0; i < m.skins.size(); i++) {
        const tinygltf::Skin &g = m.skins[i];
        lie_skin &k = s->skins[i];
        std::string w = "skin " + std::to_string(i);
        k.name = dup_name(g.name);
        if (g.joints.empty() || g.joints.size() > 65536)
            fail(LIE_ERR_FORMAT, "%s: needs 1 to 65536 joints", w.c_str());
        k.joints = alloc_array<int>(g.joints.size());
        k.inverse_bind = alloc_array<lie_mat4>(g.joints.size());
        k.n_joints = int(g.joints.size());
        for (size_t j = 0; j < g.joints.size(); j++) {
            if (g.joints[j] < 0 || size_t(g.joints[j]) >= m.nodes.size())
                fail(LIE_ERR_FORMAT, "%s: joint %zu names node %d, out of range", w.c_str(), j, g.joints[j]);
            k.joints[j] = g.joints[j];
            k.inverse_bind[j] = lie_mat4_identity();
        }
        if (g.inverseBindMatrices >= 0) {
            Accessor a = check_accessor(m, g.inverseBindMatrices, w + " inverseBindMatrices");
            if (a.ncomp != 16 || a.ctype != TINYGLTF_COMPONENT_TYPE_FLOAT || a.count != g.joints.size())
                fail(LIE_ERR_FORMAT, "%s: inverseBindMatrices must be %zu MAT4 FLOAT", w.c_str(), g.joints.size());
            std::vector<float> v(a.count * 16);
            read_floats(a, v.data(), w + " inverseBindMatrices");
            for (size_t j = 0; j < a.count; j++)
                for (int c = 0; c < 16; c++)
                    k.inverse_bind[j].m[c] = v[j * 16 + size_t(c)];
        }
    }
    for (size_t i = 0; i < m.nodes.size(); i++) {
        int sk = m.nodes[i].skin;
        if (sk < 0)
            continue;
        std::string w = "node " + std::to_string(i);
        if (size_t(sk) >= m.skins.size())
            fail(LIE_ERR_FORMAT, "%s: skin %d out of range", w.c_str(), sk);
        int mi = s->nodes[i].mesh;
        if (mi < 0)
            fail(LIE_ERR_FORMAT, "%s has a skin but no mesh", w.c_str());
        s->nodes[i].skin = sk;
        const lie_mesh &mesh = s->meshes[mi];
        for (int pi = 0; pi < mesh.n_prims; pi++) {
            const lie_primitive &p = mesh.prims[pi];
            if (p.n_tris && !p.joints)
                fail(LIE_ERR_FORMAT, "%s: skinned mesh %d primitive %d has no JOINTS_0 and WEIGHTS_0", w.c_str(),
                     mi, pi);
            for (size_t v = 0; p.joints && v < 4 * size_t(p.n_verts); v++)
                if (p.joints[v] >= s->skins[sk].n_joints && p.weights[v] != 0.0f)
                    fail(LIE_ERR_FORMAT, "%s: mesh %d primitive %d: vertex %zu uses joint %u of skin %d's %d",
                         w.c_str(), mi, pi, v / 4, unsigned(p.joints[v]), sk, s->skins[sk].n_joints);
        }
    }
}

/* glTF 2.0 §3.11: samplers (input times strictly increasing, output
 * element counts matching the interpolation and the target) and channels
 * (a node of the file, a path of translation, rotation, scale or weights).
 * A channel without a target node (left to extensions) is not read. */
void import_animations(const tinygltf::Model &m, lie_scene *s)
{
    s->animations = alloc_list<lie_animation>(m.animations, &s->n_animations, "animations");
    for (size_t ai = 0; ai < m.animations.size(); ai++) {
        const tinygltf::Animation &g = m.animations[ai];
        lie_animation &a = s->animations[ai];
        std::string aw = "animation " + std::to_string(ai);
        if (!g.name.empty())
            aw += " '" + clean(g.name) + "'";
        a.name = dup_name(g.name);
        if (g.samplers.size() > size_t(INT_MAX) || g.channels.size() > size_t(INT_MAX))
            fail(LIE_ERR_LIMIT, "%s: too many samplers or channels", aw.c_str());
        a.samplers = alloc_array<lie_anim_sampler>(g.samplers.size());
        a.n_samplers = int(g.samplers.size());
        a.channels = alloc_array<lie_anim_channel>(g.channels.size());
        std::vector<int> comp(g.samplers.size(), 0); /* floats per key, from the channels using it */
        for (size_t ci = 0; ci < g.channels.size(); ci++) {
            const tinygltf::AnimationChannel &c = g.channels[ci];
            std::string cw = aw + " channel " + std::to_string(ci);
            if (c.target_node < 0)
                continue;
            if (size_t(c.target_node) >= m.nodes.size())
                fail(LIE_ERR_FORMAT, "%s: target node %d does not exist (the file has %zu nodes)", cw.c_str(),
                     c.target_node, m.nodes.size());
            if (c.sampler < 0 || size_t(c.sampler) >= g.samplers.size())
                fail(LIE_ERR_FORMAT, "%s: sampler %d does not exist", cw.c_str(), c.sampler);
            lie_anim_channel &ch = a.channels[a.n_channels++];
            ch.node = c.target_node;
            ch.sampler = c.sampler;
            const lie_node &n = s->nodes[c.target_node];
            int nc;
            if (c.target_path == "translation")
                ch.path = LIE_ANIM_TRANSLATION, nc = 3;
            else if (c.target_path == "rotation")
                ch.path = LIE_ANIM_ROTATION, nc = 4;
            else if (c.target_path == "scale")
                ch.path = LIE_ANIM_SCALE, nc = 3;
            else if (c.target_path == "weights")
                ch.path = LIE_ANIM_WEIGHTS, nc = n.n_weights;
            else
                fail(LIE_ERR_FORMAT, "%s: target path '%s' does not exist (translation, rotation, scale or weights)",
                     cw.c_str(), clean(c.target_path).c_str());
            if (ch.path != LIE_ANIM_WEIGHTS && !n.has_trs)
                fail(LIE_ERR_FORMAT, "%s: node %d has a matrix, and an animated node must use TRS", cw.c_str(),
                     c.target_node);
            if (ch.path == LIE_ANIM_WEIGHTS && nc == 0)
                fail(LIE_ERR_FORMAT, "%s: node %d has no morph targets to weigh", cw.c_str(), c.target_node);
            if (comp[size_t(c.sampler)] && comp[size_t(c.sampler)] != nc)
                fail(LIE_ERR_FORMAT, "%s: sampler %d also drives a target of another size", cw.c_str(), c.sampler);
            comp[size_t(c.sampler)] = nc;
            for (int k = 0; k + 1 < a.n_channels; k++)
                if (a.channels[k].node == ch.node && a.channels[k].path == ch.path)
                    fail(LIE_ERR_FORMAT, "%s: node %d's %s is already animated by channel %d", cw.c_str(),
                         c.target_node, c.target_path.c_str(), k);
        }
        bool first = true;
        for (size_t si = 0; si < g.samplers.size(); si++) {
            const tinygltf::AnimationSampler &gs = g.samplers[si];
            lie_anim_sampler &sp = a.samplers[si];
            std::string sw = aw + " sampler " + std::to_string(si);
            if (gs.interpolation == "LINEAR")
                sp.interp = LIE_INTERP_LINEAR;
            else if (gs.interpolation == "STEP")
                sp.interp = LIE_INTERP_STEP;
            else if (gs.interpolation == "CUBICSPLINE")
                sp.interp = LIE_INTERP_CUBICSPLINE;
            else
                fail(LIE_ERR_FORMAT, "%s: interpolation '%s' is not LINEAR, STEP or CUBICSPLINE", sw.c_str(),
                     clean(gs.interpolation).c_str());
            Accessor in = check_accessor(m, gs.input, sw + " input");
            if (in.ncomp != 1 || in.ctype != TINYGLTF_COMPONENT_TYPE_FLOAT || in.count == 0)
                fail(LIE_ERR_FORMAT, "%s: input must be SCALAR FLOAT with at least one key", sw.c_str());
            if (in.count > 100000000)
                fail(LIE_ERR_LIMIT, "%s: %zu keys", sw.c_str(), in.count);
            sp.n_keys = uint32_t(in.count);
            sp.times = alloc_array<float>(in.count);
            read_floats(in, sp.times, sw + " input");
            for (size_t k = 1; k < in.count; k++)
                if (!(sp.times[k] > sp.times[k - 1]))
                    fail(LIE_ERR_FORMAT, "%s: input times are not strictly increasing (key %zu: %g after %g)",
                         sw.c_str(), k, double(sp.times[k]), double(sp.times[k - 1]));
            if (sp.times[0] < 0.0f)
                fail(LIE_ERR_FORMAT, "%s: input time %g is negative", sw.c_str(), double(sp.times[0]));
            if (first || sp.times[0] < a.start)
                a.start = sp.times[0];
            if (first || sp.times[in.count - 1] > a.end)
                a.end = sp.times[in.count - 1];
            first = false;
            int nc = comp[si];
            if (nc == 0)
                continue; /* no channel uses it */
            Accessor out = check_accessor(m, gs.output, sw + " output");
            size_t per_key = size_t(nc) * (sp.interp == LIE_INTERP_CUBICSPLINE ? 3 : 1);
            size_t want = in.count * per_key; /* floats */
            bool type_ok = nc == 3 || nc == 4 ? out.ncomp == size_t(nc) : out.ncomp == 1;
            bool ctype_ok = out.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT || (out.normalized && nc != 3);
            if (!type_ok || !ctype_ok)
                fail(LIE_ERR_FORMAT, "%s: output must be %s FLOAT%s", sw.c_str(),
                     nc == 3 ? "VEC3" : nc == 4 ? "VEC4" : "SCALAR", nc != 3 ? " or normalized integers" : "");
            if (out.count * out.ncomp != want)
                fail(LIE_ERR_FORMAT, "%s: output has %zu elements, %zu input keys need %zu%s", sw.c_str(), out.count,
                     in.count, want / out.ncomp, sp.interp == LIE_INTERP_CUBICSPLINE ? " (3 per key, CUBICSPLINE)" : "");
            sp.n_comp = nc;
            sp.values = alloc_array<float>(want);
            read_floats(out, sp.values, sw + " output");
        }
    }
}

} // namespace

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
        Import im{model, s, image_errors, encoded, {}, {}, {}};
        import_materials(im);
        import_cameras(model, s);
        import_lights(model, s);
        import_skins(model, s);
        import_animations(model, s);
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

/* ==== the exporter ============================================================
 * lie_gltf_export builds a tinygltf::Model from the document, lets tinygltf
 * serialise it, and adds the one external buffer itself (tinygltf's stream
 * writer embeds buffers as data URIs).  Everything the world hash covers
 * travels exactly: vertex data as the same floats; matrices as the same
 * doubles (nlohmann prints a double so that it reads back bit for bit);
 * float fields as the shortest decimal the importer turns back into the
 * same float; texture pixels as the code values they were decoded from. */

namespace {

/* asset.extras member of a .gltf listing its side files (see check_side_file) */
const char *const SIDE_FILES = "lie.files";

struct ExistsError {
    std::string path; /* a side file that is not ours */
};

struct Png {
    std::string path, uri; /* where it goes (.gltf), as the .gltf names it */
    int width, height, bits, channels;
    std::vector<uint8_t> b8;
    std::vector<uint16_t> b16;
    std::vector<unsigned char> bytes; /* the PNG file */
};

/* The importer's code values (code_value) for 8 and 16 bits, linear and sRGB. */
struct CodeTables {
    std::vector<float> t[2][2]; /* [16-bit][srgb] */
    const std::vector<float> &get(bool sixteen, bool srgb)
    {
        std::vector<float> &v = t[sixteen][srgb];
        if (v.empty()) {
            size_t levels = sixteen ? 65536 : 256;
            v.resize(levels);
            for (size_t i = 0; i < levels; i++)
                v[i] = code_value(i, levels, srgb);
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
    for (size_t i = 0; i < n; i++)
        opaque = opaque && t.rgba[4 * i + 3] == 1.0f;
    out.channels = opaque ? 3 : 4;
    size_t nc = size_t(out.channels);
    for (int sixteen = 0; sixteen < 2; sixteen++) {
        const std::vector<float> &col = tables.get(sixteen, srgb), &alpha = tables.get(sixteen, false);
        std::vector<uint16_t> codes(n * nc);
        bool all_exact = true;
        for (size_t i = 0; i < n; i++)
            for (size_t c = 0; c < nc; c++) {
                bool exact;
                codes[i * nc + c] = uint16_t(nearest_code(c < 3 ? col : alpha, t.rgba[4 * i + c], &exact));
                all_exact = all_exact && exact;
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

/* A file name as a URI path segment (RFC 3986 unreserved characters kept). */
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
double short_float(float f)
{
    return shortest(double(f), [f](double d) { return float(d) == f; });
}

int gl_wrap(lie_wrap w)
{
    switch (w) {
    case LIE_WRAP_CLAMP: return TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    case LIE_WRAP_MIRROR: return TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT;
    default: return TINYGLTF_TEXTURE_WRAP_REPEAT;
    }
}

struct Export {
    const lie_scene &s;
    std::string dir, stem; /* "DIR/" (or ""), NAME */
    bool glb;              /* one .glb: images are bufferViews of the one buffer */
    tinygltf::Model m;
    std::vector<unsigned char> bin;
    std::vector<Png> pngs;
};

/* Append bytes as a new bufferView (4-byte aligned); returns its index. */
int add_view(Export &ex, const void *data, size_t bytes, int target)
{
    while (ex.bin.size() % 4)
        ex.bin.push_back(0);
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteOffset = ex.bin.size();
    bv.byteLength = bytes;
    bv.target = target;
    const unsigned char *p = static_cast<const unsigned char *>(data);
    ex.bin.insert(ex.bin.end(), p, p + bytes);
    ex.m.bufferViews.push_back(bv);
    return int(ex.m.bufferViews.size() - 1);
}

int add_accessor(Export &ex, const void *data, size_t count, int type, int ctype, int target)
{
    size_t ncomp = type_components(type), bytes = mul_size(count, ncomp * component_size(ctype), "accessor");
    tinygltf::Accessor a;
    a.bufferView = add_view(ex, data, bytes, target);
    a.byteOffset = 0;
    a.componentType = ctype;
    a.type = type;
    a.count = count;
    ex.m.accessors.push_back(a);
    return int(ex.m.accessors.size() - 1);
}

tinygltf::Primitive export_primitive(Export &ex, const lie_primitive &p)
{
    tinygltf::Primitive g;
    g.mode = TINYGLTF_MODE_TRIANGLES;
    g.material = p.material >= 0 && p.material < ex.s.n_materials ? p.material : -1;
    int ap = add_accessor(ex, p.pos, p.n_verts, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT,
                          TINYGLTF_TARGET_ARRAY_BUFFER);
    /* glTF 2.0 §3.7.2.1: POSITION needs min and max */
    tinygltf::Accessor &a = ex.m.accessors[size_t(ap)];
    a.minValues.assign(3, 0.0);
    a.maxValues.assign(3, 0.0);
    for (uint32_t v = 0; v < p.n_verts; v++)
        for (size_t c = 0; c < 3; c++) {
            double x = short_float(p.pos[3 * size_t(v) + c]);
            if (v == 0 || x < a.minValues[c])
                a.minValues[c] = x;
            if (v == 0 || x > a.maxValues[c])
                a.maxValues[c] = x;
        }
    g.attributes["POSITION"] = ap;
    if (p.nrm)
        g.attributes["NORMAL"] = add_accessor(ex, p.nrm, p.n_verts, TINYGLTF_TYPE_VEC3,
                                              TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (p.uv)
        g.attributes["TEXCOORD_0"] = add_accessor(ex, p.uv, p.n_verts, TINYGLTF_TYPE_VEC2,
                                                  TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (p.uv1)
        g.attributes["TEXCOORD_1"] = add_accessor(ex, p.uv1, p.n_verts, TINYGLTF_TYPE_VEC2,
                                                  TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (p.color)
        g.attributes["COLOR_0"] = add_accessor(ex, p.color, p.n_verts, TINYGLTF_TYPE_VEC4,
                                               TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (p.joints && p.weights) { /* skins (§3.7.3): the joints and weights as read */
        g.attributes["JOINTS_0"] = add_accessor(ex, p.joints, p.n_verts, TINYGLTF_TYPE_VEC4,
                                                TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TARGET_ARRAY_BUFFER);
        g.attributes["WEIGHTS_0"] = add_accessor(ex, p.weights, p.n_verts, TINYGLTF_TYPE_VEC4,
                                                 TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TARGET_ARRAY_BUFFER);
    }
    g.indices = add_accessor(ex, p.idx, size_t(p.n_tris) * 3, TINYGLTF_TYPE_SCALAR,
                             TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    return g;
}

bool mesh_has_triangles(const lie_mesh &mesh)
{
    for (int i = 0; i < mesh.n_prims; i++)
        if (mesh.prims[i].n_tris > 0 && mesh.prims[i].pos && mesh.prims[i].idx)
            return true;
    return false;
}

/* Textures: one glTF texture (and PNG) per (lie_texture, colour space) that
 * a material uses, in texture order, sRGB before linear.  Returns the map
 * texture * 2 + srgb -> glTF texture. */
/* The PNG file of png's codes, in png.bytes (the codes are freed). */
void png_bytes(Png &png, const std::string &name)
{
    char *buf = nullptr;
    size_t n = 0;
    FILE *fp = open_memstream(&buf, &n);
    if (!fp)
        throw std::bad_alloc();
    lie_error e{};
    const void *codes = png.bits == 16 ? static_cast<const void *>(png.b16.data())
                                       : static_cast<const void *>(png.b8.data());
    lie_status st = lie_scene_png_write(fp, name.c_str(), png.width, png.height, png.bits, png.channels, codes, &e);
    bool closed = fclose(fp) == 0;
    if (st == LIE_OK && closed) {
        try {
            png.bytes.assign(buf, buf + n);
        } catch (...) {
            free(buf);
            throw;
        }
    }
    free(buf);
    if (st != LIE_OK)
        throw ImportError{st, e.msg, 0, 0};
    if (!closed)
        throw std::bad_alloc();
    std::vector<uint8_t>().swap(png.b8);
    std::vector<uint16_t>().swap(png.b16);
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
    }
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
            int image = int(ex.m.images.size());
            std::string name = ex.stem + "_tex" + std::to_string(image) + ".png";
            Png png;
            encode_texture(lt, srgb != 0, tables, png);
            png_bytes(png, name);
            tinygltf::Image im;
            im.mimeType = "image/png";
            if (ex.glb) { /* glTF 2.0 §3.9.1: an image in a bufferView names its mimeType */
                im.bufferView = add_view(ex, png.bytes.data(), png.bytes.size(), 0);
            } else {
                im.uri = png.uri = uri_escape(name);
                png.path = ex.dir + name;
                ex.pngs.push_back(std::move(png));
            }
            ex.m.images.push_back(im);
            tinygltf::Texture tx;
            tx.sampler = found->second;
            tx.source = image;
            ex.m.textures.push_back(tx);
            gl_texture[t * 2 + srgb] = int(ex.m.textures.size() - 1);
        }
    return gl_texture;
}

void export_materials(Export &ex, const std::map<int, int> &gl_texture)
{
    auto tex = [&](int t, bool srgb) {
        auto it = gl_texture.find(t * 2 + srgb);
        return it == gl_texture.end() ? -1 : it->second;
    };
    bool strength_used = false, transform_used = false;
    for (int i = 0; i < ex.s.n_materials; i++) {
        const lie_material &mt = ex.s.materials[i];
        tinygltf::Material g;
        if (mt.name)
            g.name = mt.name;
        tinygltf::PbrMetallicRoughness &pbr = g.pbrMetallicRoughness;
        pbr.baseColorFactor.assign(4, 0.0);
        for (int c = 0; c < 4; c++)
            pbr.baseColorFactor[size_t(c)] = short_float(mt.base_color[c]);
        pbr.baseColorTexture.index = tex(mt.base_color_tex, true);
        pbr.metallicFactor = short_float(mt.metallic);
        pbr.roughnessFactor = short_float(mt.roughness);
        pbr.metallicRoughnessTexture.index = tex(mt.mr_tex, false);
        /* emissive = emissiveFactor x emissiveStrength (what the importer
         * computes, in double, then rounds to float): when the emission is
         * brighter than 1, the strength is its peak and the factor's largest
         * component 1.  A factor e / strength in double comes back as e (the
         * product is within 2^-52 of e); a shorter decimal is used when it
         * comes back as e too. */
        float peak = fmaxf(mt.emissive[0], fmaxf(mt.emissive[1], mt.emissive[2]));
        double strength = short_float(peak);
        g.emissiveFactor.assign(3, 0.0);
        for (int c = 0; c < 3; c++) {
            float e = mt.emissive[c];
            double f = short_float(e);
            if (peak > 1.0f)
                f = e == peak ? 1.0 : shortest(double(e) / strength, [e, strength](double d) {
                    return d <= 1.0 && float(d * strength) == e;
                });
            g.emissiveFactor[size_t(c)] = f;
        }
        if (peak > 1.0f) {
            tinygltf::Value::Object o;
            o["emissiveStrength"] = tinygltf::Value(strength);
            g.extensions["KHR_materials_emissive_strength"] = tinygltf::Value(o);
            strength_used = true;
        }
        g.emissiveTexture.index = tex(mt.emissive_tex, true);
        g.doubleSided = mt.double_sided != 0;
        if (mt.alpha_mask) {
            g.alphaMode = "MASK";
            g.alphaCutoff = short_float(mt.alpha_cutoff);
        }
        tinygltf::TextureInfo *slots[3] = {&pbr.baseColorTexture, &pbr.metallicRoughnessTexture,
                                           &g.emissiveTexture};
        for (int k = 0; k < 3; k++)
            if (slots[k]->index >= 0)
                slots[k]->texCoord = mt.tex_set[k];
        for (int k = 0; k < 3; k++) {
            if (slots[k]->index < 0 || lie_material_tex_xf_is_identity(&mt, k))
                continue;
            const float *p = mt.tex_param[k];
            tinygltf::Value::Object o;
            o["offset"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(short_float(p[0])),
                                                                 tinygltf::Value(short_float(p[1]))});
            o["rotation"] = tinygltf::Value(short_float(p[2]));
            o["scale"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(short_float(p[3])),
                                                                tinygltf::Value(short_float(p[4]))});
            slots[k]->extensions["KHR_texture_transform"] = tinygltf::Value(o);
            transform_used = true;
        }
        ex.m.materials.push_back(g);
    }
    if (strength_used)
        ex.m.extensionsUsed.push_back("KHR_materials_emissive_strength");
    if (transform_used)
        ex.m.extensionsUsed.push_back("KHR_texture_transform");
}

void export_document(Export &ex)
{
    const lie_scene &s = ex.s;
    tinygltf::Model &m = ex.m;
    m.asset.version = "2.0";
    m.asset.generator = "lie";

    /* kept nodes in depth-first pre-order from the default scene's roots, as
     * lie_scene_flatten walks them; a removed node takes its subtree along */
    std::vector<int> order, new_index(size_t(s.n_nodes), -1), stack;
    for (int r = s.n_roots - 1; r >= 0; r--)
        stack.push_back(s.roots[r]);
    while (!stack.empty()) {
        int nd = stack.back();
        stack.pop_back();
        if (nd < 0 || nd >= s.n_nodes || s.nodes[nd].removed || new_index[size_t(nd)] >= 0)
            continue;
        new_index[size_t(nd)] = int(order.size());
        order.push_back(nd);
        for (int c = s.nodes[nd].n_children - 1; c >= 0; c--)
            stack.push_back(s.nodes[nd].children[c]);
    }

    /* meshes, cameras and lights the kept nodes use, in their own order */
    std::vector<int> mesh_map(size_t(s.n_meshes), -1), camera_map(size_t(s.n_camera_defs), -1),
        light_map(size_t(s.n_light_defs), -1);
    for (int nd : order) {
        const lie_node &n = s.nodes[nd];
        if (n.mesh >= 0 && n.mesh < s.n_meshes && mesh_has_triangles(s.meshes[n.mesh]))
            mesh_map[size_t(n.mesh)] = 0;
        if (n.camera >= 0 && n.camera < s.n_camera_defs &&
            (s.camera_defs[n.camera].yfov > 0.0f || s.camera_defs[n.camera].ymag > 0.0f))
            camera_map[size_t(n.camera)] = 0;
        if (n.light >= 0 && n.light < s.n_light_defs)
            light_map[size_t(n.light)] = 0;
    }

    std::map<int, int> gl_texture = export_textures(ex);
    export_materials(ex, gl_texture);

    for (int i = 0; i < s.n_meshes; i++) {
        if (mesh_map[size_t(i)] < 0)
            continue;
        const lie_mesh &mesh = s.meshes[i];
        tinygltf::Mesh g;
        if (mesh.name)
            g.name = mesh.name;
        for (int p = 0; p < mesh.n_prims; p++) /* points and lines were kept as empty primitives */
            if (mesh.prims[p].n_tris > 0 && mesh.prims[p].pos && mesh.prims[p].idx)
                g.primitives.push_back(export_primitive(ex, mesh.prims[p]));
        mesh_map[size_t(i)] = int(m.meshes.size());
        m.meshes.push_back(g);
    }
    for (int i = 0; i < s.n_camera_defs; i++) {
        if (camera_map[size_t(i)] < 0)
            continue;
        const lie_camera_def &c = s.camera_defs[i];
        tinygltf::Camera g;
        if (c.name)
            g.name = c.name;
        if (c.ymag > 0.0f) {
            g.type = "orthographic";
            g.orthographic.xmag = short_float(c.xmag);
            g.orthographic.ymag = short_float(c.ymag);
            g.orthographic.znear = short_float(c.znear);
            g.orthographic.zfar = short_float(c.zfar);
        } else {
            g.type = "perspective";
            g.perspective.yfov = short_float(c.yfov);
            g.perspective.aspectRatio = short_float(c.aspect);
            g.perspective.znear = short_float(c.znear);
            g.perspective.zfar = 0.0; /* infinite: taken out of the JSON below */
        }
        camera_map[size_t(i)] = int(m.cameras.size());
        m.cameras.push_back(g);
    }
    for (int i = 0; i < s.n_light_defs; i++) {
        if (light_map[size_t(i)] < 0)
            continue;
        const lie_light_def &l = s.light_defs[i];
        tinygltf::Light g;
        if (l.name)
            g.name = l.name;
        g.type = l.type == LIE_LIGHT_SPOT ? "spot" : l.type == LIE_LIGHT_DIRECTIONAL ? "directional" : "point";
        g.color.assign(3, 0.0);
        for (int c = 0; c < 3; c++)
            g.color[size_t(c)] = short_float(l.color[c]);
        g.intensity = short_float(l.intensity);
        g.range = short_float(l.range);
        if (l.type == LIE_LIGHT_SPOT) {
            g.spot.innerConeAngle = short_float(l.inner_cone);
            g.spot.outerConeAngle = short_float(l.outer_cone);
        }
        light_map[size_t(i)] = int(m.lights.size());
        m.lights.push_back(g);
    }

    const lie_mat4 identity = lie_mat4_identity();
    for (int nd : order) {
        const lie_node &n = s.nodes[nd];
        tinygltf::Node g;
        if (n.name)
            g.name = n.name;
        /* bit for bit: an identity with a -0 is written, to come back as it is */
        if (memcmp(&n.local, &identity, sizeof identity) != 0)
            g.matrix.assign(n.local.m, n.local.m + 16);
        if (n.mesh >= 0 && n.mesh < s.n_meshes)
            g.mesh = mesh_map[size_t(n.mesh)];
        if (n.camera >= 0 && n.camera < s.n_camera_defs)
            g.camera = camera_map[size_t(n.camera)];
        if (n.light >= 0 && n.light < s.n_light_defs) {
            tinygltf::Value::Object o;
            o["light"] = tinygltf::Value(light_map[size_t(n.light)]);
            g.extensions["KHR_lights_punctual"] = tinygltf::Value(o);
        }
        for (int c = 0; c < n.n_children; c++) {
            int ch = n.children[c];
            if (ch >= 0 && ch < s.n_nodes && new_index[size_t(ch)] >= 0)
                g.children.push_back(new_index[size_t(ch)]);
        }
        m.nodes.push_back(g);
    }
    /* skins of kept skinned nodes; every joint must be kept too */
    std::vector<int> skin_map(size_t(s.n_skins), -1);
    for (size_t k = 0; k < order.size(); k++) {
        const lie_node &n = s.nodes[order[k]];
        if (n.skin < 0 || n.skin >= s.n_skins || m.nodes[k].mesh < 0)
            continue;
        if (skin_map[size_t(n.skin)] < 0) {
            const lie_skin &sk = s.skins[n.skin];
            tinygltf::Skin g;
            if (sk.name)
                g.name = sk.name;
            std::vector<float> ibm(size_t(sk.n_joints) * 16);
            for (int j = 0; j < sk.n_joints; j++) {
                int nj = sk.joints[j] >= 0 && sk.joints[j] < s.n_nodes ? new_index[size_t(sk.joints[j])] : -1;
                if (nj < 0)
                    fail(LIE_ERR_UNSUPPORTED, "skin %d: joint node %d is not in the written scene", n.skin,
                         sk.joints[j]);
                g.joints.push_back(nj);
                for (int c = 0; c < 16; c++) /* read as floats: exact */
                    ibm[size_t(j) * 16 + size_t(c)] = float(sk.inverse_bind[j].m[c]);
            }
            g.inverseBindMatrices = add_accessor(ex, ibm.data(), size_t(sk.n_joints), TINYGLTF_TYPE_MAT4,
                                                 TINYGLTF_COMPONENT_TYPE_FLOAT, 0);
            skin_map[size_t(n.skin)] = int(m.skins.size());
            m.skins.push_back(g);
        }
        m.nodes[k].skin = skin_map[size_t(n.skin)];
    }
    tinygltf::Scene scene;
    for (int r = 0; r < s.n_roots; r++)
        if (s.roots[r] >= 0 && s.roots[r] < s.n_nodes && new_index[size_t(s.roots[r])] >= 0)
            scene.nodes.push_back(new_index[size_t(s.roots[r])]);
    m.scenes.push_back(scene);
    m.defaultScene = 0;
}

std::string hash_hex(const void *data, size_t n)
{
    char buf[24];
    snprintf(buf, sizeof buf, "%016llx", (unsigned long long)lie_hash_bytes(data, n, 0));
    return buf;
}

/* The glTF JSON: tinygltf's serialisation plus the buffer, external (.gltf)
 * or the GLB's BIN chunk (glTF 2.0 §4.4.3.3: buffer 0 without a uri).  A
 * .gltf lists its side files with the hash of their bytes (asset.extras,
 * SIDE_FILES): what a later export of the same name may replace. */
std::string export_json(Export &ex)
{
    tinygltf::TinyGLTF writer;
    writer.SetImageWriter(nullptr, nullptr); /* images keep their uri; we write the PNGs */
    std::ostringstream os;
    if (!writer.WriteGltfSceneToStream(&ex.m, os, false, false))
        fail(LIE_ERR_FORMAT, "tinygltf could not serialise the scene");
    nlohmann::json j = nlohmann::json::parse(os.str());
    if (!ex.bin.empty()) {
        nlohmann::json buffer;
        buffer["byteLength"] = uint64_t(ex.bin.size());
        if (!ex.glb)
            buffer["uri"] = uri_escape(ex.stem + ".bin");
        j["buffers"] = nlohmann::json::array({buffer});
    }
    if (!ex.glb) {
        nlohmann::json files = nlohmann::json::object();
        if (!ex.bin.empty())
            files[uri_escape(ex.stem + ".bin")] = hash_hex(ex.bin.data(), ex.bin.size());
        for (const Png &png : ex.pngs)
            files[png.uri] = hash_hex(png.bytes.data(), png.bytes.size());
        if (!files.empty())
            j["asset"]["extras"][SIDE_FILES] = files;
    }
    /* tinygltf writes an object with nothing but defaults (a node with
     * identity transform and no mesh, a scene without nodes) as null */
    for (auto &top : j.items())
        if (top.value().is_array())
            for (auto &e : top.value())
                if (e.is_null())
                    e = nlohmann::json::object();
    if (j.contains("cameras"))
        for (auto &c : j["cameras"])
            if (c.contains("perspective"))
                c["perspective"].erase("zfar");
    return ex.glb ? j.dump() : j.dump(2) + "\n";
}

void put32(std::string &out, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        out += char((v >> (8 * i)) & 0xff);
}

/* glTF 2.0 §4.4: the 12-byte header, the JSON chunk padded with spaces and
 * the BIN chunk padded with zeros, each to 4 bytes; lengths little-endian. */
std::string glb_container(const std::string &json, const std::vector<unsigned char> &bin)
{
    size_t json_len = (json.size() + 3) & ~size_t(3), bin_len = (bin.size() + 3) & ~size_t(3);
    uint64_t total = 12 + 8 + uint64_t(json_len) + (bin.empty() ? 0 : 8 + uint64_t(bin_len));
    if (total > UINT32_MAX)
        fail(LIE_ERR_LIMIT, "a GLB holds at most 4 GiB, this scene needs %llu bytes: write .gltf",
             (unsigned long long)total);
    std::string out;
    out.reserve(size_t(total));
    out += "glTF";
    put32(out, 2);
    put32(out, uint32_t(total));
    put32(out, uint32_t(json_len));
    put32(out, 0x4E4F534Au); /* "JSON" */
    out += json;
    out.append(json_len - json.size(), ' ');
    if (!bin.empty()) {
        put32(out, uint32_t(bin_len));
        put32(out, 0x004E4942u); /* "BIN\0" */
        out.append(reinterpret_cast<const char *>(bin.data()), bin.size());
        out.append(bin_len - bin.size(), '\0');
    }
    return out;
}

/* ---- side files of a .gltf: replaced only when ours ----------------------
 * A side file (DIR/NAME.bin, DIR/NAME_texK.png) that exists is "ours", and
 * may be replaced, when the .gltf being replaced (DIR/NAME.gltf) is this
 * exporter's (asset.generator "lie") and lists the file under
 * asset.extras.SIDE_FILES with the XXH3-64 hash of exactly the bytes it
 * holds now.  Anything else (no previous .gltf, another generator, a file it
 * does not list, a file changed since) is someone else's: refused unless
 * the caller forces it. */

std::map<std::string, std::string> previous_side_files(const std::string &gltf_path)
{
    std::map<std::string, std::string> out;
    unsigned char *d = nullptr;
    size_t n = 0;
    lie_error e{};
    if (lie_read_file_max(gltf_path.c_str(), LIE_READ_MAX_TEXT, &d, &n, &e) != LIE_OK)
        return out;
    try {
        nlohmann::json j = nlohmann::json::parse(d, d + n);
        const nlohmann::json &a = j.at("asset");
        if (a.at("generator") == "lie")
            for (auto &f : a.at("extras").at(SIDE_FILES).items())
                if (f.value().is_string())
                    out[f.key()] = f.value().get<std::string>();
    } catch (const nlohmann::json::exception &) {
        out.clear(); /* not JSON, or not ours */
    } catch (...) {
        free(d);
        throw;
    }
    free(d);
    return out;
}

/* Returns the open flags of its write: a file absent now is created with
 * LIE_ATOMIC_NO_REPLACE, so one that appears before the rename is not
 * replaced either (the test and the write are one step, lib/core). */
unsigned check_side_file(const std::string &path, const std::string &uri,
                         const std::map<std::string, std::string> &ours)
{
    struct stat st;
    if (lstat(path.c_str(), &st) != 0 && errno == ENOENT)
        return LIE_ATOMIC_NO_REPLACE;
    auto it = ours.find(uri);
    unsigned char *d = nullptr;
    size_t n = 0;
    lie_error e{};
    bool same = it != ours.end() && lie_read_file_max(path.c_str(), LIE_READ_MAX_GLTF, &d, &n, &e) == LIE_OK &&
                hash_hex(d, n) == it->second;
    free(d);
    if (!same)
        throw ExistsError{path};
    return 0;
}

/* Write one output through a temporary file of `group`; `body` fills it. */
template <class F>
lie_status write_atomic(const std::string &path, lie_atomic_group *group, lie_error *err, F body, unsigned flags = 0)
{
    lie_atomic_file af;
    lie_status st = lie_atomic_open_flags(&af, path.c_str(), group, flags, err);
    if (st != LIE_OK)
        return st;
    st = body(af.fp);
    if (st != LIE_OK) {
        lie_atomic_abort(&af);
        return st;
    }
    return lie_atomic_commit(&af, err);
}

lie_status write_bytes(FILE *fp, const std::string &path, const void *data, size_t n, lie_error *err)
{
    if (n && fwrite(data, 1, n, fp) != n)
        return lie_error_set(err, LIE_ERR_IO, path.c_str(), "write failed: %s", strerror(errno));
    return LIE_OK;
}

} // namespace

extern "C" lie_gltf_export_options lie_gltf_export_options_default(void)
{
    lie_gltf_export_options o;
    memset(&o, 0, sizeof o);
    return o;
}

extern "C" lie_status lie_gltf_export(const lie_scene *s, const char *path, lie_error *err)
{
    lie_atomic_group *group = lie_atomic_group_create();
    if (!group)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    lie_status st = lie_gltf_export_group(s, path, NULL, group, err);
    if (st == LIE_OK)
        st = lie_atomic_group_commit(group, err);
    lie_atomic_group_destroy(group);
    return st;
}

static bool ends_with_glb(const std::string &base)
{
    return base.size() > 4 && strcasecmp(base.c_str() + base.size() - 4, ".glb") == 0;
}

extern "C" lie_status lie_gltf_export_group(const lie_scene *s, const char *path, const lie_gltf_export_options *opt,
                                            lie_atomic_group *group, lie_error *err)
{
    if (!s || !path || !*path)
        return lie_error_set(err, LIE_ERR_ARG, path, "lie_gltf_export: NULL scene or empty path");
    lie_gltf_export_options o = opt ? *opt : lie_gltf_export_options_default();
    if (strcmp(path, "-") == 0)
        return lie_error_set(err, LIE_ERR_ARG, path,
                             "a glTF export is a named file (.glb, or .gltf with its .bin and textures): it cannot go to stdout");
    std::string p(path);
    size_t slash = p.rfind('/');
    std::string dir = slash == std::string::npos ? std::string() : p.substr(0, slash + 1);
    std::string base = p.substr(dir.size());
    size_t dot = base.rfind('.');
    std::string stem = dot == std::string::npos || dot == 0 ? base : base.substr(0, dot);
    bool glb = ends_with_glb(base);
    if (base.empty() || base == "." || base == "..")
        return lie_error_set(err, LIE_ERR_ARG, path, "not a file name");
    if (!glb && (base == stem + ".bin" || (base.compare(0, stem.size() + 4, stem + "_tex") == 0 &&
                                           base.size() > 4 && base.compare(base.size() - 4, 4, ".png") == 0)))
        return lie_error_set(err, LIE_ERR_ARG, path, "the glTF would share its name with its .bin or a texture");

    lie_status st = LIE_OK;
    try {
        Export ex{*s, dir, stem, glb, tinygltf::Model(), {}, {}};
        export_document(ex);
        std::string json = export_json(ex);
        if (glb) {
            std::string bytes = glb_container(json, ex.bin);
            return write_atomic(p, group, err, [&](FILE *fp) { return write_bytes(fp, p, bytes.data(), bytes.size(), err); });
        }
        std::string bin_path = dir + stem + ".bin";
        /* a side file must be neither an input nor another output of the run */
        if (!ex.bin.empty() && (st = lie_file_set_claim(o.files, bin_path.c_str(), nullptr, err)) != LIE_OK)
            return st;
        for (const Png &png : ex.pngs)
            if ((st = lie_file_set_claim(o.files, png.path.c_str(), nullptr, err)) != LIE_OK)
                return st;
        std::map<std::string, unsigned> flags; /* per side file (check_side_file) */
        if (!o.force) { /* before anything is written */
            std::map<std::string, std::string> ours = previous_side_files(p);
            if (!ex.bin.empty())
                flags[bin_path] = check_side_file(bin_path, uri_escape(stem + ".bin"), ours);
            for (const Png &png : ex.pngs)
                flags[png.path] = check_side_file(png.path, png.uri, ours);
        }
        /* the side files first, the .gltf last: a .gltf never names a missing file */
        for (const Png &png : ex.pngs) {
            st = write_atomic(
                png.path, group, err,
                [&](FILE *fp) { return write_bytes(fp, png.path, png.bytes.data(), png.bytes.size(), err); },
                flags[png.path]);
            if (st != LIE_OK)
                break;
        }
        if (st == LIE_OK && !ex.bin.empty()) {
            st = write_atomic(
                bin_path, group, err,
                [&](FILE *fp) { return write_bytes(fp, bin_path, ex.bin.data(), ex.bin.size(), err); },
                flags[bin_path]);
        }
        if (st == LIE_OK)
            st = write_atomic(p, group, err, [&](FILE *fp) { return write_bytes(fp, p, json.data(), json.size(), err); });
    } catch (const ExistsError &e) {
        st = lie_error_set(err, LIE_ERR_IO, e.path.c_str(), "exists (use --force to overwrite)");
    } catch (const ImportError &e) {
        st = lie_error_set(err, e.status, path, "%s", e.msg.c_str());
    } catch (const std::bad_alloc &) {
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    } catch (const std::exception &e) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "%s", first_line(e.what()).c_str());
    } catch (...) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "unexpected error while exporting");
    }
    return st; /* on failure the caller's group destroy removes the temporaries */
}
