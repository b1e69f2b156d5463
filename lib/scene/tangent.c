/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: per-vertex tangents for normal maps whose primitive gives no
 * TANGENT attribute.
 *
 * glTF 2.0 §3.7.2.1 asks for MikkTSpace tangents (Mikkelsen 2008) where a
 * file gives none.  Debian ships no MikkTSpace library (Blender and others
 * bundle the reference C file), so this computes them the way MikkTSpace
 * does in its common case, written here: per triangle the direction of
 * increasing u (Lengyel 2001, "Computing Tangent Space Basis Vectors for an
 * Arbitrary Mesh"), projected into the vertex normal's plane, normalised and
 * weighted by the triangle's angle at the vertex, summed over the triangles
 * around each vertex, then made orthogonal to the normal (Gram-Schmidt).
 * The handedness w follows glTF's texture space, whose v axis points down
 * the image: w = +1 when cross(normal, tangent) points toward decreasing v.
 * It differs from MikkTSpace where MikkTSpace splits a vertex whose
 * triangles disagree in handedness (mirrored UV islands sharing vertices):
 * here the vertex keeps the sign of the larger weight.  Bakers write files
 * whose seams are split vertices, where the two agree. */
#include "scene/scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A unit vector orthogonal to unit n. */
static lie_vec3 any_orthogonal(lie_vec3 n)
{
    lie_vec3 a = fabsf(n.x) < 0.9f ? lie_v3(1.0f, 0.0f, 0.0f) : lie_v3(0.0f, 1.0f, 0.0f);
    return lie_v3_norm(lie_v3_sub(a, lie_v3_scale(n, lie_v3_dot(a, n))));
}

static lie_vec3 vert(const float *a, uint32_t i)
{
    return lie_v3(a[3 * (size_t)i], a[3 * (size_t)i + 1], a[3 * (size_t)i + 2]);
}

int lie_primitive_tangents(const lie_primitive *p, int set, float *out)
{
    const float *uv = set == 1 && p->uv1 ? p->uv1 : p->uv;
    size_t n = p->n_verts;
    /* per vertex: the summed tangent, the summed signed weight of handedness,
     * and the normal the tangent is made orthogonal to (the file's, else the
     * area-weighted face normals) */
    lie_vec3 *t = calloc(n + 1, sizeof *t), *nn = calloc(n + 1, sizeof *nn);
    double *hand = calloc(n + 1, sizeof *hand);
    if (!t || !nn || !hand) {
        free(t);
        free(nn);
        free(hand);
        return 0;
    }
    for (uint32_t f = 0; f < p->n_tris; f++) {
        const uint32_t *v = &p->idx[3 * (size_t)f];
        lie_vec3 fn = lie_v3_cross(lie_v3_sub(vert(p->pos, v[1]), vert(p->pos, v[0])),
                                   lie_v3_sub(vert(p->pos, v[2]), vert(p->pos, v[0])));
        if (!p->nrm && isfinite(lie_v3_dot(fn, fn)))
            for (int k = 0; k < 3; k++)
                nn[v[k]] = lie_v3_add(nn[v[k]], fn);
    }
    for (size_t i = 0; i < n; i++) {
        lie_vec3 a = p->nrm ? vert(p->nrm, (uint32_t)i) : nn[i];
        nn[i] = lie_v3_norm(a);
        if (!(lie_v3_dot(nn[i], nn[i]) > 0.5f))
            nn[i] = lie_v3(0.0f, 0.0f, 1.0f);
    }
    for (uint32_t f = 0; uv && f < p->n_tris; f++) {
        const uint32_t *v = &p->idx[3 * (size_t)f];
        for (int k = 0; k < 3; k++) {
            /* corner k: its two edges, in space and in texture space */
            uint32_t a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
            lie_vec3 e1 = lie_v3_sub(vert(p->pos, b), vert(p->pos, a));
            lie_vec3 e2 = lie_v3_sub(vert(p->pos, c), vert(p->pos, a));
            float du1 = uv[2 * (size_t)b] - uv[2 * (size_t)a], dv1 = uv[2 * (size_t)b + 1] - uv[2 * (size_t)a + 1];
            float du2 = uv[2 * (size_t)c] - uv[2 * (size_t)a], dv2 = uv[2 * (size_t)c + 1] - uv[2 * (size_t)a + 1];
            float r = du1 * dv2 - du2 * dv1;
            if (!(fabsf(r) > 0.0f) || !isfinite(r))
                continue; /* no texture-space area: no direction to take */
            lie_vec3 sdir = lie_v3_scale(lie_v3_sub(lie_v3_scale(e1, dv2), lie_v3_scale(e2, dv1)), 1.0f / r);
            lie_vec3 tdir = lie_v3_scale(lie_v3_sub(lie_v3_scale(e2, du1), lie_v3_scale(e1, du2)), 1.0f / r);
            lie_vec3 na = nn[a];
            lie_vec3 sp = lie_v3_norm(lie_v3_sub(sdir, lie_v3_scale(na, lie_v3_dot(na, sdir))));
            float l1 = lie_v3_len(e1), l2 = lie_v3_len(e2);
            if (!(lie_v3_dot(sp, sp) > 0.5f) || !(l1 > 0.0f) || !(l2 > 0.0f))
                continue;
            float cosang = lie_v3_dot(e1, e2) / (l1 * l2);
            float angle = acosf(fminf(fmaxf(cosang, -1.0f), 1.0f));
            if (!isfinite(angle))
                continue;
            t[a] = lie_v3_add(t[a], lie_v3_scale(sp, angle));
            /* glTF's v grows down the image: a right-handed frame has its
             * bitangent cross(n, t) along -dP/dv */
            hand[a] += lie_v3_dot(lie_v3_cross(na, sp), tdir) < 0.0f ? angle : -angle;
        }
    }
    for (size_t i = 0; i < n; i++) {
        lie_vec3 ni = nn[i];
        lie_vec3 ti = lie_v3_norm(lie_v3_sub(t[i], lie_v3_scale(ni, lie_v3_dot(ni, t[i]))));
        if (!(lie_v3_dot(ti, ti) > 0.5f))
            ti = any_orthogonal(ni); /* no texture-space direction here: any frame will do */
        out[4 * i] = ti.x;
        out[4 * i + 1] = ti.y;
        out[4 * i + 2] = ti.z;
        out[4 * i + 3] = hand[i] < 0.0 ? -1.0f : 1.0f;
    }
    free(t);
    free(nn);
    free(hand);
    return 1;
}
