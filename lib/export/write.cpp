/* SPDX-License-Identifier: Apache-2.0 */
/* lib/export: the glTF JSON and the GLB container, the side files of a
 * .gltf, atomic output, and the public functions (lib/export/internal.h). */
#include "export/internal.h"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include <strings.h>
#include <sys/stat.h>

namespace lie_export {

/* asset.extras member of a .gltf listing its side files (see check_side_file) */
const char *const SIDE_FILES = "lie.files";

struct ExistsError {
    std::string path; /* a side file that is not ours */
};

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
        throw ExportError{LIE_ERR_FORMAT, "tinygltf could not serialise the scene"};
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
        throw ExportError{LIE_ERR_LIMIT, "a GLB holds at most 4 GiB, this scene needs " +
                                              std::to_string((unsigned long long)total) + " bytes: write .gltf"};
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

} // namespace lie_export

using namespace lie_export;

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
    if (!glb && (base == stem + ".bin" || base.compare(0, stem.size() + 4, stem + "_tex") == 0 ||
                 base.compare(0, stem.size() + 4, stem + "_img") == 0))
        return lie_error_set(err, LIE_ERR_ARG, path, "the glTF would share its name with its .bin or a texture");

    lie_status st = LIE_OK;
    try {
        Export ex{*s, dir, stem, glb, tinygltf::Model(), {}, {}};
        export_document(ex);
        if (o.warn) {
            for (int i = 0; i < s->n_not_read; i++)
                o.warn(o.warn_ctx, (std::string("not written: ") + s->not_read[i] + " (not read)").c_str());
            if (s->n_animations > 0)
                o.warn(o.warn_ctx, ("not written: " + std::to_string(s->n_animations) +
                                    " animation(s) (lie-animate turns them into edit files)")
                                       .c_str());
            bool morph = false;
            for (int i = 0; i < s->n_meshes; i++)
                for (int k = 0; k < s->meshes[i].n_prims; k++)
                    morph = morph || s->meshes[i].prims[k].n_targets > 0;
            if (morph)
                o.warn(o.warn_ctx, "not written: morph targets (meshes are written morphed, with their weights)");
        }
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
    } catch (const ExportError &e) {
        st = lie_error_set(err, e.status, path, "%s", e.msg.c_str());
    } catch (const std::bad_alloc &) {
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    } catch (const std::exception &e) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "%.*s", int(strcspn(e.what(), "\n")), e.what());
    } catch (...) {
        st = lie_error_set(err, LIE_ERR_FORMAT, path, "unexpected error while exporting");
    }
    return st; /* on failure the caller's group destroy removes the temporaries */
}
