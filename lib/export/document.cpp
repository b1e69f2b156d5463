/* SPDX-License-Identifier: Apache-2.0 */
/* lib/export: a scene's document as a tinygltf::Model (lib/export/internal.h):
 * meshes, materials, cameras, lights, nodes in the order lie_scene_flatten
 * walks them, and skins. */
#include "export/internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lie_export {

double short_float(float f)
{
    return shortest(double(f), [f](double d) { return float(d) == f; });
}

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
    size_t elem = size_t(tinygltf::GetNumComponentsInType(uint32_t(type))) *
                  size_t(tinygltf::GetComponentSizeInBytes(uint32_t(ctype))),
           bytes;
    if (__builtin_mul_overflow(count, elem, &bytes))
        throw ExportError{LIE_ERR_LIMIT, "accessor: size overflows"};
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
    if (p.tan)
        g.attributes["TANGENT"] = add_accessor(ex, p.tan, p.n_verts, TINYGLTF_TYPE_VEC4, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                               TINYGLTF_TARGET_ARRAY_BUFFER);
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

void export_materials(Export &ex, const std::map<int, int> &gl_texture)
{
    auto tex = [&](int t, bool srgb) {
        auto it = gl_texture.find(t * 2 + srgb);
        return it == gl_texture.end() ? -1 : it->second;
    };
    bool strength_used = false, transform_used = false, transmission_used = false;
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
        /* each slot's set and KHR_texture_transform, the core slots, the
         * normal map and the transmission texture alike */
        auto transform = [&](int k, tinygltf::ExtensionMap &ext) {
            if (lie_material_tex_xf_is_identity(&mt, k))
                return;
            const float *p = mt.tex_param[k];
            tinygltf::Value::Object o;
            o["offset"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(short_float(p[0])),
                                                                 tinygltf::Value(short_float(p[1]))});
            o["rotation"] = tinygltf::Value(short_float(p[2]));
            o["scale"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(short_float(p[3])),
                                                                tinygltf::Value(short_float(p[4]))});
            ext["KHR_texture_transform"] = tinygltf::Value(o);
            transform_used = true;
        };
        tinygltf::TextureInfo *slots[3] = {&pbr.baseColorTexture, &pbr.metallicRoughnessTexture,
                                           &g.emissiveTexture};
        for (int k = 0; k < 3; k++)
            if (slots[k]->index >= 0) {
                slots[k]->texCoord = mt.tex_set[k];
                transform(k, slots[k]->extensions);
            }
        g.normalTexture.index = tex(mt.normal_tex, false);
        if (g.normalTexture.index >= 0) {
            g.normalTexture.texCoord = mt.tex_set[LIE_TEX_NORMAL];
            g.normalTexture.scale = short_float(mt.normal_scale);
            transform(LIE_TEX_NORMAL, g.normalTexture.extensions);
        }
        if (lie_material_transmits(&mt)) {
            tinygltf::Value::Object o;
            o["transmissionFactor"] = tinygltf::Value(short_float(mt.transmission));
            int ti = tex(mt.transmission_tex, false);
            if (ti >= 0) {
                tinygltf::Value::Object info;
                info["index"] = tinygltf::Value(ti);
                info["texCoord"] = tinygltf::Value(mt.tex_set[LIE_TEX_TRANSMISSION]);
                tinygltf::ExtensionMap ext;
                transform(LIE_TEX_TRANSMISSION, ext);
                if (!ext.empty()) {
                    tinygltf::Value::Object e;
                    e["KHR_texture_transform"] = ext["KHR_texture_transform"];
                    info["extensions"] = tinygltf::Value(e);
                }
                o["transmissionTexture"] = tinygltf::Value(info);
            }
            g.extensions["KHR_materials_transmission"] = tinygltf::Value(o);
            transmission_used = true;
        }
        ex.m.materials.push_back(g);
    }
    if (strength_used)
        ex.m.extensionsUsed.push_back("KHR_materials_emissive_strength");
    if (transform_used)
        ex.m.extensionsUsed.push_back("KHR_texture_transform");
    if (transmission_used)
        ex.m.extensionsUsed.push_back("KHR_materials_transmission");
}

/* The cameras kept nodes use (camera_map[i] >= 0), in their order;
 * camera_map[i] becomes the glTF index. */
static void export_cameras(Export &ex, std::vector<int> &camera_map)
{
    const lie_scene &s = ex.s;
    tinygltf::Model &m = ex.m;
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
}

/* The KHR_lights_punctual lights kept nodes use, as export_cameras. */
static void export_lights(Export &ex, std::vector<int> &light_map)
{
    const lie_scene &s = ex.s;
    tinygltf::Model &m = ex.m;
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
}

/* Skins of kept skinned nodes (order: the kept nodes, new_index: their
 * glTF indices, dead: removed, kept only as a joint); every joint must be
 * kept too. */
static void export_skins(Export &ex, const std::vector<int> &order, const std::vector<int> &new_index,
                         const std::vector<char> &dead)
{
    const lie_scene &s = ex.s;
    tinygltf::Model &m = ex.m;
    std::vector<int> skin_map(size_t(s.n_skins), -1);
    for (size_t k = 0; k < order.size(); k++) {
        const lie_node &n = s.nodes[order[k]];
        if (n.skin < 0 || n.skin >= s.n_skins || m.nodes[k].mesh < 0 || dead[size_t(order[k])])
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
                    throw ExportError{LIE_ERR_UNSUPPORTED, "skin " + std::to_string(n.skin) + ": joint node " +
                                                               std::to_string(sk.joints[j]) +
                                                               " is not in the written scene"};
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
}

void export_document(Export &ex)
{
    const lie_scene &s = ex.s;
    tinygltf::Model &m = ex.m;
    m.asset.version = "2.0";
    m.asset.generator = "lie";

    /* kept nodes in depth-first pre-order from the default scene's roots, as
     * lie_scene_flatten walks them; a removed node takes its subtree along.
     * Except the joints a kept skinned mesh still needs, and their
     * ancestors: a removed joint still poses the mesh (lie_scene_flatten
     * skins from every node's transform), so it is written bare, its
     * transform alone, without mesh, camera or light (their triangles and
     * lights are gone, as removed). */
    std::vector<int> order, new_index(size_t(s.n_nodes), -1), stack;
    std::vector<char> dead(size_t(s.n_nodes), 0), needed(size_t(s.n_nodes), 0), seen(size_t(s.n_nodes), 0);
    for (int pass = 0; pass < 2; pass++) {
        order.clear();
        std::fill(seen.begin(), seen.end(), 0);
        for (int r = s.n_roots - 1; r >= 0; r--)
            stack.push_back(s.roots[r]);
        std::vector<char> under(size_t(s.n_nodes), 0); /* below a removed node */
        while (!stack.empty()) {
            int nd = stack.back();
            stack.pop_back();
            if (nd < 0 || nd >= s.n_nodes || seen[size_t(nd)])
                continue;
            seen[size_t(nd)] = 1;
            dead[size_t(nd)] = s.nodes[nd].removed || under[size_t(nd)];
            if (dead[size_t(nd)] && !needed[size_t(nd)] && pass == 0)
                continue;
            if (!dead[size_t(nd)] || needed[size_t(nd)]) {
                if (pass == 1)
                    new_index[size_t(nd)] = int(order.size());
                order.push_back(nd);
            }
            for (int c = s.nodes[nd].n_children - 1; c >= 0; c--) {
                int ch = s.nodes[nd].children[c];
                if (ch >= 0 && ch < s.n_nodes)
                    under[size_t(ch)] = dead[size_t(nd)];
                stack.push_back(ch);
            }
        }
        if (pass == 1)
            break;
        /* the joints (and their ancestors) of the skins kept meshes use */
        for (int nd : order) {
            const lie_node &n = s.nodes[nd];
            if (n.skin < 0 || n.skin >= s.n_skins || n.mesh < 0 || n.mesh >= s.n_meshes ||
                !mesh_has_triangles(s.meshes[n.mesh]))
                continue;
            const lie_skin &sk = s.skins[n.skin];
            for (int j = 0; j < sk.n_joints; j++)
                for (int a = sk.joints[j], hops = 0; a >= 0 && a < s.n_nodes && hops <= s.n_nodes;
                     a = s.nodes[a].parent, hops++)
                    needed[size_t(a)] = 1;
        }
    }

    /* meshes, cameras and lights the kept nodes use, in their own order */
    std::vector<int> mesh_map(size_t(s.n_meshes), -1), camera_map(size_t(s.n_camera_defs), -1),
        light_map(size_t(s.n_light_defs), -1);
    for (int nd : order) {
        const lie_node &n = s.nodes[nd];
        if (dead[size_t(nd)])
            continue; /* a bare joint */
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
    export_cameras(ex, camera_map);
    export_lights(ex, light_map);

    const lie_mat4 identity = lie_mat4_identity();
    for (int nd : order) {
        const lie_node &n = s.nodes[nd];
        tinygltf::Node g;
        if (n.name)
            g.name = n.name;
        /* bit for bit: an identity with a -0 is written, to come back as it is */
        if (memcmp(&n.local, &identity, sizeof identity) != 0)
            g.matrix.assign(n.local.m, n.local.m + 16);
        bool bare = dead[size_t(nd)] != 0;
        if (!bare && n.mesh >= 0 && n.mesh < s.n_meshes)
            g.mesh = mesh_map[size_t(n.mesh)];
        if (!bare && n.camera >= 0 && n.camera < s.n_camera_defs)
            g.camera = camera_map[size_t(n.camera)];
        if (!bare && n.light >= 0 && n.light < s.n_light_defs) {
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
    export_skins(ex, order, new_index, dead);
    tinygltf::Scene scene;
    for (int r = 0; r < s.n_roots; r++)
        if (s.roots[r] >= 0 && s.roots[r] < s.n_nodes && new_index[size_t(s.roots[r])] >= 0)
            scene.nodes.push_back(new_index[size_t(s.roots[r])]);
    m.scenes.push_back(scene);
    m.defaultScene = 0;
}

} // namespace lie_export
