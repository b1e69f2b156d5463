/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: the glTF importer's skins and animations (lib/scene/gltf.h). */
#include "scene/gltf.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace lie_gltf {

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


} // namespace lie_gltf
