/* SPDX-License-Identifier: Apache-2.0 */
/* Small linear algebra: bases, 4x4 transforms in glTF's column-major order. */
#include "core/core.h"

#include <string.h>

void lie_onb(lie_vec3 n, lie_vec3 *t, lie_vec3 *b)
{
    /* Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017). */
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = lie_v3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = lie_v3(c, sign + n.y * n.y * a, -n.y);
}

lie_mat4 lie_mat4_identity(void)
{
    lie_mat4 r;
    memset(&r, 0, sizeof r);
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0;
    return r;
}

lie_mat4 lie_mat4_mul(const lie_mat4 *a, const lie_mat4 *b)
{
    lie_mat4 r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++)
                s += a->m[k * 4 + row] * b->m[c * 4 + k];
            r.m[c * 4 + row] = s;
        }
    return r;
}

lie_mat4 lie_mat4_from_trs(const double t[3], const double q[4], const double s[3])
{
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double n = sqrt(x * x + y * y + z * z + w * w);
    if (n > 0.0) {
        x /= n; y /= n; z /= n; w /= n;
    } else {
        x = y = z = 0.0; w = 1.0;
    }
    lie_mat4 r = lie_mat4_identity();
    /* columns of R scaled by S */
    r.m[0] = (1 - 2 * (y * y + z * z)) * s[0];
    r.m[1] = (2 * (x * y + z * w)) * s[0];
    r.m[2] = (2 * (x * z - y * w)) * s[0];
    r.m[4] = (2 * (x * y - z * w)) * s[1];
    r.m[5] = (1 - 2 * (x * x + z * z)) * s[1];
    r.m[6] = (2 * (y * z + x * w)) * s[1];
    r.m[8] = (2 * (x * z + y * w)) * s[2];
    r.m[9] = (2 * (y * z - x * w)) * s[2];
    r.m[10] = (1 - 2 * (x * x + y * y)) * s[2];
    r.m[12] = t[0];
    r.m[13] = t[1];
    r.m[14] = t[2];
    return r;
}

lie_vec3 lie_mat4_point(const lie_mat4 *m, lie_vec3 p)
{
    const double *a = m->m;
    return lie_v3((float)(a[0] * p.x + a[4] * p.y + a[8] * p.z + a[12]),
                  (float)(a[1] * p.x + a[5] * p.y + a[9] * p.z + a[13]),
                  (float)(a[2] * p.x + a[6] * p.y + a[10] * p.z + a[14]));
}

lie_vec3 lie_mat4_vector(const lie_mat4 *m, lie_vec3 v)
{
    const double *a = m->m;
    return lie_v3((float)(a[0] * v.x + a[4] * v.y + a[8] * v.z),
                  (float)(a[1] * v.x + a[5] * v.y + a[9] * v.z),
                  (float)(a[2] * v.x + a[6] * v.y + a[10] * v.z));
}

double lie_mat4_det3(const lie_mat4 *m)
{
    const double *a = m->m;
    return a[0] * (a[5] * a[10] - a[9] * a[6]) - a[4] * (a[1] * a[10] - a[9] * a[2]) +
           a[8] * (a[1] * a[6] - a[5] * a[2]);
}

lie_vec3 lie_mat4_normal(const lie_mat4 *m, lie_vec3 n)
{
    /* The cofactor matrix is det * inverse-transpose; its sign is fixed up
     * so that normals keep their side when the transform mirrors. */
    const double *a = m->m; /* A[r][c] = a[c*4+r]; C = cofactor matrix */
    double c00 = a[5] * a[10] - a[9] * a[6], c01 = a[9] * a[2] - a[1] * a[10], c02 = a[1] * a[6] - a[5] * a[2];
    double c10 = a[8] * a[6] - a[4] * a[10], c11 = a[0] * a[10] - a[8] * a[2], c12 = a[4] * a[2] - a[0] * a[6];
    double c20 = a[4] * a[9] - a[8] * a[5], c21 = a[8] * a[1] - a[0] * a[9], c22 = a[0] * a[5] - a[4] * a[1];
    double d = lie_mat4_det3(m) < 0.0 ? -1.0 : 1.0;
    return lie_v3((float)(d * (c00 * n.x + c01 * n.y + c02 * n.z)),
                  (float)(d * (c10 * n.x + c11 * n.y + c12 * n.z)),
                  (float)(d * (c20 * n.x + c21 * n.y + c22 * n.z)));
}

int lie_mat4_inverse(const lie_mat4 *m, lie_mat4 *out)
{
    const double *a = m->m;
    double det = lie_mat4_det3(m);
    *out = lie_mat4_identity();
    if (!(fabs(det) > 1e-300) || !isfinite(det))
        return 0;
    double id = 1.0 / det;
    double *r = out->m;
    /* inverse of the 3x3 = adjugate / det; r[c*4+row] */
    r[0] = (a[5] * a[10] - a[9] * a[6]) * id;
    r[4] = (a[8] * a[6] - a[4] * a[10]) * id;
    r[8] = (a[4] * a[9] - a[8] * a[5]) * id;
    r[1] = (a[9] * a[2] - a[1] * a[10]) * id;
    r[5] = (a[0] * a[10] - a[8] * a[2]) * id;
    r[9] = (a[8] * a[1] - a[0] * a[9]) * id;
    r[2] = (a[1] * a[6] - a[5] * a[2]) * id;
    r[6] = (a[4] * a[2] - a[0] * a[6]) * id;
    r[10] = (a[0] * a[5] - a[4] * a[1]) * id;
    for (int row = 0; row < 3; row++)
        r[12 + row] = -(r[row] * a[12] + r[4 + row] * a[13] + r[8 + row] * a[14]);
    return 1;
}

lie_mat4 lie_mat4_rotation(const double axis[3], double radians)
{
    double x = axis[0], y = axis[1], z = axis[2];
    double n = sqrt(x * x + y * y + z * z);
    lie_mat4 r = lie_mat4_identity();
    if (!(n > 0.0))
        return r;
    x /= n;
    y /= n;
    z /= n;
    double c = cos(radians), s = sin(radians), t = 1.0 - c;
    r.m[0] = t * x * x + c;
    r.m[1] = t * x * y + s * z;
    r.m[2] = t * x * z - s * y;
    r.m[4] = t * x * y - s * z;
    r.m[5] = t * y * y + c;
    r.m[6] = t * y * z + s * x;
    r.m[8] = t * x * z + s * y;
    r.m[9] = t * y * z - s * x;
    r.m[10] = t * z * z + c;
    return r;
}

lie_mat4 lie_mat4_translation(double x, double y, double z)
{
    lie_mat4 r = lie_mat4_identity();
    r.m[12] = x;
    r.m[13] = y;
    r.m[14] = z;
    return r;
}

void lie_bound_sphere(const lie_vec3 *p, uint32_t n, float sphere[4])
{
    lie_box3 b = lie_box3_empty();
    for (uint32_t i = 0; i < n; i++)
        lie_box3_grow(&b, p[i]);
    lie_vec3 c = lie_v3_scale(lie_v3_add(b.lo, b.hi), 0.5f);
    float r = 0.0f;
    for (uint32_t i = 0; i < n; i++)
        r = fmaxf(r, lie_v3_len(lie_v3_sub(p[i], c)));
    float mag = fmaxf(fabsf(c.x), fmaxf(fabsf(c.y), fabsf(c.z)));
    sphere[0] = c.x;
    sphere[1] = c.y;
    sphere[2] = c.z;
    sphere[3] = r * 1.001f + 1e-5f * fmaxf(1.0f, mag);
}
