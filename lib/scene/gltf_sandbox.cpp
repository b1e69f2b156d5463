/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: what tinygltf may open and decode (lib/scene/gltf.h): the URI
 * policy, as tinygltf's file-system callbacks, and the image loader that
 * checks an image's range and size before stb decodes it. */
#include "scene/gltf.h"

#include <stb_image.h> /* libstb: the decoder tinygltf uses; its header reader sizes every format */

#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>

#include <sys/stat.h>
#include <unistd.h>

namespace lie_gltf {

/* ---- file-system callbacks: the URI policy ------------------------------
 * tinygltf joins each (percent-decoded) URI to the folder it was given and
 * then to ".", expands the path, asks FileExists and reads it.  We see the
 * joined path in ExpandFilePath, recover the URI and decide there, so a
 * refused URI is never opened.  The "." fallback (the working directory) is
 * never used: a relative URI means the scene's folder. */


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
 * decoded only when a material uses it (decode_image), after its header
 * showed it within MAX_IMAGE_PIXELS: stb_image's stbi_info_from_memory reads
 * the header of every format stb decodes (PNG, JPEG, BMP, GIF, PSD, PIC,
 * PNM, TGA, HDR).  A 70-byte BMP claiming 40000 x 13000 pixels then costs
 * nothing unused, and one line of error used. */

uint32_t be16(const unsigned char *p) { return uint32_t(p[0]) << 8 | p[1]; }
uint32_t be32(const unsigned char *p) { return be16(p) << 16 | be16(p + 2); }

/* Width and height from a PNG or JPEG header; false when not found.  For
 * the headers stb's own reader refuses (stb refuses a PNG of more than 2^30
 * bytes decoded even to size it), so the limit is still reported. */
bool image_header_size(const unsigned char *b, size_t n, uint32_t *w, uint32_t *h)
{
    if (n >= 24 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0 && memcmp(b + 12, "IHDR", 4) == 0) {
        *w = be32(b + 16);
        *h = be32(b + 20);
        return true;
    }
    if (n >= 4 && b[0] == 0xff && b[1] == 0xd8) {
        size_t at = 2;
        while (at + 9 <= n) {
            if (b[at] != 0xff)
                return false;
            unsigned m = b[at + 1];
            if (m == 0xff) { /* fill byte */
                at++;
                continue;
            }
            if (m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc) { /* SOFn */
                *h = be16(b + at + 5);
                *w = be16(b + at + 7);
                return true;
            }
            at += 2 + be16(b + at + 2);
        }
    }
    return false;
}

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

void StbFree::operator()(unsigned char *p) const { stbi_image_free(p); }

void decode_image(const tinygltf::Image &meta, int index, const std::vector<unsigned char> &b, Decoded *out)
{
    std::string name = !meta.uri.empty() && meta.uri.compare(0, 5, "data:") != 0 ? " '" + clean(meta.uri) + "'"
                       : !meta.name.empty()                                    ? " '" + clean(meta.name) + "'"
                                                                               : std::string();
    std::string iw = "image " + std::to_string(index) + name;
    int w = 0, h = 0, comp = 0;
    uint32_t hw = 0, hh = 0;
    bool sized = stbi_info_from_memory(b.data(), int(b.size()), &w, &h, &comp) != 0;
    if (!sized && image_header_size(b.data(), b.size(), &hw, &hh)) {
        sized = true;
        w = int(hw > INT_MAX ? INT_MAX : hw);
        h = int(hh > INT_MAX ? INT_MAX : hh);
    }
    if (!sized) {
        out->why = iw + ": cannot decode (not an image the decoder reads)";
        return;
    }
    if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > MAX_IMAGE_PIXELS)
        fail(LIE_ERR_LIMIT, "image %d is %dx%d, beyond the limit of %llu pixels", index, w, h,
             (unsigned long long)MAX_IMAGE_PIXELS);
    /* stb decoding expanded to RGBA, 16 bits a channel where the file has
     * them, else 8, as tinygltf's LoadImageData decodes with its default
     * options; kept in stb's buffer (LoadImageData copies it once more) */
    int bits = 8;
    unsigned char *px = nullptr;
    w = h = comp = 0;
    if (stbi_is_16_bit_from_memory(b.data(), int(b.size()))) {
        px = reinterpret_cast<unsigned char *>(stbi_load_16_from_memory(b.data(), int(b.size()), &w, &h, &comp, 4));
        bits = 16;
    }
    if (!px) {
        px = stbi_load_from_memory(b.data(), int(b.size()), &w, &h, &comp, 4);
        bits = 8;
    }
    out->pixels.reset(px);
    if (!px || w < 1 || h < 1) {
        out->pixels.reset();
        out->why = iw + ": cannot decode (the decoder refused it)";
        return;
    }
    out->width = w;
    out->height = h;
    out->component = 4;
    out->bits = bits;
}

} // namespace lie_gltf
