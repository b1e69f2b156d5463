/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the glTF importer's accessors and meshes (lib/scene/gltf.h).
 * An accessor is checked whole before any element is read; a primitive is
 * planned (checked, its triangles counted) before anything is allocated. */
#include "scene/gltf.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace lie_gltf {

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

/* Check a primitive and count its triangles; nothing is allocated yet.
 * One piece: the checks of every attribute (glTF 2.0 §3.7.2.1) and of its
 * morph targets fill one plan, which read_primitive then trusts. */
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
    int atan = attribute(p, "TANGENT");
    if ((pl.has_tan = atan >= 0)) {
        /* glTF 2.0 §3.7.2.1: VEC4, xyz a unit tangent, w +-1 the bitangent's sign */
        pl.tan = check_accessor(m, atan, what + " TANGENT");
        bool ok = pl.tan.ncomp == 4 &&
                  (pl.tan.ctype == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                   (quant && pl.tan.normalized &&
                    (pl.tan.ctype == TINYGLTF_COMPONENT_TYPE_BYTE || pl.tan.ctype == TINYGLTF_COMPONENT_TYPE_SHORT)));
        if (!ok)
            fail(LIE_ERR_FORMAT, "%s: TANGENT must be VEC4 FLOAT%s", what.c_str(),
                 quant ? " or (KHR_mesh_quantization) normalized BYTE/SHORT" : "");
        if (pl.tan.count != pl.n_verts)
            fail(LIE_ERR_FORMAT, "%s: TANGENT has %zu elements, POSITION %zu", what.c_str(), pl.tan.count,
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
    if (pl.has_tan) {
        out->tan = alloc_array<float>(pl.n_verts * 4);
        read_floats(pl.tan, out->tan, what + " TANGENT");
        for (size_t v = 0; v < pl.n_verts; v++) /* w is +-1; a 0 (quantised rounding) reads as +1 */
            out->tan[4 * v + 3] = out->tan[4 * v + 3] < 0.0f ? -1.0f : 1.0f;
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

} // namespace lie_gltf
