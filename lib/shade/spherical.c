/* SPDX-License-Identifier: Apache-2.0 */
/* Arvo's sampling of spherical triangles (spherical.h). */
#include "shade/spherical.h"

#include <math.h>

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static int normalize3(double *a)
{
    double l = sqrt(dot3(a, a));
    if (!(l > 0.0) || !isfinite(l))
        return 0;
    a[0] /= l, a[1] /= l, a[2] /= l;
    return 1;
}

/* The angle between unit vectors, accurate near 0 and pi (acos is not). */
static double angle3(const double *a, const double *b)
{
    double c[3];
    cross3(a, b, c);
    return atan2(sqrt(dot3(c, c)), dot3(a, b));
}

/* The part of b orthogonal to unit a, normalized, into out. */
static int ortho3(const double *a, const double *b, double *out)
{
    double d = dot3(a, b);
    for (int k = 0; k < 3; k++)
        out[k] = b[k] - d * a[k];
    return normalize3(out);
}

double lie_sph_tri_solid_angle(lie_vec3 o, const lie_vec3 p[3])
{
    double a[3] = {(double)p[0].x - o.x, (double)p[0].y - o.y, (double)p[0].z - o.z};
    double b[3] = {(double)p[1].x - o.x, (double)p[1].y - o.y, (double)p[1].z - o.z};
    double c[3] = {(double)p[2].x - o.x, (double)p[2].y - o.y, (double)p[2].z - o.z};
    double la = sqrt(dot3(a, a)), lb = sqrt(dot3(b, b)), lc = sqrt(dot3(c, c)), bc[3];
    cross3(b, c, bc);
    double num = fabs(dot3(a, bc));
    double den = la * lb * lc + dot3(a, b) * lc + dot3(a, c) * lb + dot3(b, c) * la;
    double w = 2.0 * atan2(num, den);
    return w < 0.0 ? w + 2.0 * M_PI : w;
}

int lie_sph_tri_setup(lie_vec3 o, const lie_vec3 p[3], lie_sph_tri *t)
{
    t->o[0] = o.x, t->o[1] = o.y, t->o[2] = o.z;
    double *dirs[3] = {t->a, t->b, t->c};
    for (int k = 0; k < 3; k++) {
        dirs[k][0] = (double)p[k].x - o.x;
        dirs[k][1] = (double)p[k].y - o.y;
        dirs[k][2] = (double)p[k].z - o.z;
    }
    t->p0[0] = p[0].x, t->p0[1] = p[0].y, t->p0[2] = p[0].z;
    for (int k = 0; k < 3; k++) {
        t->e1[k] = t->b[k] - t->a[k];
        t->e2[k] = t->c[k] - t->a[k];
    }
    cross3(t->e1, t->e2, t->n);
    if (!normalize3(t->n))
        return 0;
    if (!(fabs(dot3(t->n, t->a)) > 1e-9 * sqrt(dot3(t->a, t->a))))
        return 0; /* o in the plane: the triangle is an arc */
    for (int k = 0; k < 3; k++)
        if (!normalize3(dirs[k]))
            return 0;
    /* the great circles' normals, and the angles between them */
    double nab[3], nbc[3], nca[3];
    cross3(t->a, t->b, nab);
    cross3(t->b, t->c, nbc);
    cross3(t->c, t->a, nca);
    if (!normalize3(nab) || !normalize3(nbc) || !normalize3(nca))
        return 0;
    const double mca[3] = {-nca[0], -nca[1], -nca[2]}, mab[3] = {-nab[0], -nab[1], -nab[2]},
                 mbc[3] = {-nbc[0], -nbc[1], -nbc[2]};
    const double alpha = angle3(nab, mca), beta = angle3(nbc, mab), gamma = angle3(nca, mbc);
    /* Girard's theorem; the map below is built on the same angles, so
     * u1 = 1 lands on c exactly */
    t->area = alpha + beta + gamma - M_PI;
    if (!(t->area >= LIE_SPH_MIN_SOLID_ANGLE && t->area <= LIE_SPH_MAX_SOLID_ANGLE))
        return 0;
    t->alpha = alpha;
    t->sin_alpha = sin(alpha);
    t->cos_alpha = cos(alpha);
    t->cos_c = dot3(t->a, t->b);
    return 1;
}

int lie_sph_tri_sample(const lie_sph_tri *t, double u1, double u2, lie_sph_sample *out)
{
    /* Arvo 1995, Figure 2: the sub-triangle (a, b, c') of area u1 A fixes
     * c' on the arc ac; then the point on the arc bc' at the height that
     * makes its share of (a, b, c') u2. */
    const double area_hat = u1 * t->area;
    const double s = sin(area_hat - t->alpha), c = cos(area_hat - t->alpha);
    const double u = c - t->cos_alpha;
    const double v = s + t->sin_alpha * t->cos_c;
    double den = (v * s + u * c) * t->sin_alpha;
    double q = den != 0.0 ? ((v * c - u * s) * t->cos_alpha - v) / den : 1.0;
    q = q > 1.0 ? 1.0 : q < -1.0 ? -1.0 : q;
    double ca[3], cp[3], cb[3], w[3];
    if (!ortho3(t->a, t->c, ca))
        return 0;
    const double sq = sqrt(1.0 - q * q);
    for (int k = 0; k < 3; k++)
        cp[k] = q * t->a[k] + sq * ca[k];
    double z = 1.0 - u2 * (1.0 - dot3(cp, t->b));
    z = z > 1.0 ? 1.0 : z < -1.0 ? -1.0 : z;
    if (ortho3(t->b, cp, cb)) {
        const double sz = sqrt(1.0 - z * z);
        for (int k = 0; k < 3; k++)
            w[k] = z * t->b[k] + sz * cb[k];
    } else {
        for (int k = 0; k < 3; k++)
            w[k] = t->b[k]; /* c' = b: the arc is a point */
    }
    /* where the direction meets the plane */
    const double po[3] = {t->p0[0] - t->o[0], t->p0[1] - t->o[1], t->p0[2] - t->o[2]};
    const double cw = dot3(t->n, w), h = dot3(t->n, po);
    if (!(fabs(cw) > 0.0))
        return 0;
    const double dist = h / cw;
    if (!(dist > 0.0))
        return 0;
    double rel[3];
    for (int k = 0; k < 3; k++) {
        out->dir[k] = w[k];
        out->p[k] = t->o[k] + dist * w[k];
        rel[k] = dist * w[k] - po[k];
    }
    /* barycentrics by the areas of the sub-triangles */
    double x1[3], x2[3];
    cross3(rel, t->e2, x1);
    cross3(t->e1, rel, x2);
    double nn[3];
    cross3(t->e1, t->e2, nn);
    const double a2 = dot3(nn, nn);
    out->b1 = dot3(x1, nn) / a2;
    out->b2 = dot3(x2, nn) / a2;
    out->inv_pdf_area = t->area * dist * dist / fabs(cw);
    return 1;
}
