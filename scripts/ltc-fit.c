/* SPDX-License-Identifier: Apache-2.0 */
/* scripts/ltc-fit.c: fits the linearly transformed cosine tables of
 * lib/shade/ltc.h and writes them as data (lib/shade/ltc_table.dat, by
 * `make ltc-tables`), which scripts/ltc-table.awk turns into C at build
 * time.
 *
 * The method is the LTC paper's (Heitz, Dupuy, Hill, Neubelt 2016, §4.1):
 * for each bin of (roughness, view angle), minimise an error between the
 * normalised lobe f cos / N and the LTC distribution D = D_o(M^-1 w / |M^-1 w|)
 * |det M^-1| / |M^-1 w|^3 (D_o = cos / pi) with Nelder-Mead, starting from
 * the neighbouring bin's solution, roughest first.  Our choices:
 *  - the lobe is lib/shade's BRDF (surface.c: GGX D, height-correlated
 *    Smith V, Schlick F; alpha = roughness^2 clamped to >= 1e-3), evaluated
 *    here in double;
 *  - M = R S, R the rotation about y by phi, S = [[a, 0, b], [0, c, 0],
 *    [0, 0, 1]]: every matrix symmetric about the plane of incidence, up to
 *    scale; parameters (log a, log c, b, phi - phi_avg), phi_avg the angle
 *    of the lobe's average direction; one parameter (a = c, b = 0, phi = 0)
 *    at normal incidence, where the lobe is isotropic;
 *  - the error is the L3 norm of the difference between the lobe and the
 *    distribution as it is evaluated: clipped to the shading hemisphere
 *    and divided by its mass h there (ltc.c folds 1/h into the norm),
 *    estimated by multiple importance sampling (balance heuristic) of the
 *    lobe's sampler (GGX normals; cosine for the diffuse lobe) and the
 *    LTC's, on fixed Hammersley points, so the objective is smooth and
 *    deterministic;
 *  - the Schlick-weighted part of the specular lobe, D V (1 - v.h)^5 cos,
 *    gets its own LTC per bin (fitted from the bin's D V cos solution): at
 *    grazing views its shape differs from the lobe's (ltc.h);
 *  - the diffuse part (1 - F) c_diff / pi gets its own roughness-independent
 *    LTC of (1 - (1 - v.h)^5) cos.
 * Output is a function of nothing but this file: double arithmetic, fixed
 * sample sets, floats printed with %.9g (exact round trip).  The header
 * comment of the output holds the fit's quality: per roughness, the L1
 * distance between lobe and fitted distribution (0 = identical, 2 =
 * disjoint), in per cent of the lobe's mass, mean and worst over view
 * angles.
 *
 * Usage: ltc-fit [-o FILE]   (default stdout) */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N_ROUGH 64
#define N_COS 64
#define FIT_SAMPLES 384      /* per sampler, per objective evaluation */
#define NORM_SAMPLES 16384   /* for the norms and average direction */
#define CHECK_SAMPLES 8192   /* per sampler, for the L1 quality figure */
#define MIN_ALPHA 1e-3       /* surface.c's clamp */
#define MIN_NV 1e-4          /* direct.c's clamp */

typedef struct v3 {
    double x, y, z;
} v3;

static v3 mk(double x, double y, double z) { v3 r = {x, y, z}; return r; }
static double dot(v3 a, v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static v3 add(v3 a, v3 b) { return mk(a.x + b.x, a.y + b.y, a.z + b.z); }
static v3 scale(v3 a, double s) { return mk(a.x * s, a.y * s, a.z * s); }
static v3 norm(v3 a)
{
    double l = sqrt(dot(a, a));
    return l > 0.0 ? scale(a, 1.0 / l) : mk(0, 0, 1);
}

static double radical_inverse2(unsigned i)
{
    double r = 0.0, f = 0.5;
    for (; i; i >>= 1, f *= 0.5)
        if (i & 1)
            r += f;
    return r;
}

/* ---- lobes ------------------------------------------------------------ */

enum {
    LOBE_DIFFUSE,      /* (1 - (1 - v.h)^5) cos */
    LOBE_GGX,          /* D V cos (F split off) */
    LOBE_GGX_FRESNEL   /* D V (1 - v.h)^5 cos: the part F's Schlick term weights */
};

typedef struct lobe {
    int kind;
    double alpha;
    v3 wo;       /* (sin, 0, cos) */
    double nv;
} lobe;

static double schlick5(v3 wo, v3 wi)
{
    v3 h = norm(add(wi, wo));
    double vh = dot(wo, h);
    double x = 1.0 - (vh > 0.0 ? vh : 0.0);
    return x * x * x * x * x;
}

/* The lobe's value f cos at wi (0 below the horizon); *s5 the Schlick
 * factor (1 - v.h)^5 there. */
static double lobe_eval(const lobe *L, v3 wi, double *s5)
{
    double nl = wi.z;
    *s5 = 0.0;
    if (nl <= 0.0)
        return 0.0;
    *s5 = schlick5(L->wo, wi);
    if (L->kind == LOBE_DIFFUSE)
        return (1.0 - *s5) * nl;
    v3 h = norm(add(wi, L->wo));
    double nh = h.z > 0.0 ? h.z : 0.0;
    double a2 = L->alpha * L->alpha, nv = L->nv;
    double dd = nh * nh * (a2 - 1.0) + 1.0;
    double D = a2 / (M_PI * dd * dd);
    double V = 0.5 / (nl * sqrt(nv * nv * (1.0 - a2) + a2) + nv * sqrt(nl * nl * (1.0 - a2) + a2));
    return D * V * nl * (L->kind == LOBE_GGX_FRESNEL ? *s5 : 1.0);
}

/* Density of the lobe's sampler at wi: GGX normals h ~ D(h) (n.h) reflected
 * about h (a density over the whole sphere, h taken on the upper side), or
 * the cosine. */
static double lobe_pdf(const lobe *L, v3 wi)
{
    if (L->kind == LOBE_DIFFUSE)
        return wi.z > 0.0 ? wi.z / M_PI : 0.0;
    v3 h = norm(add(wi, L->wo));
    if (h.z < 0.0)
        h = scale(h, -1.0);
    double a2 = L->alpha * L->alpha;
    double dd = h.z * h.z * (a2 - 1.0) + 1.0;
    double D = a2 / (M_PI * dd * dd);
    double vh = fabs(dot(L->wo, h));
    return vh > 0.0 ? D * h.z / (4.0 * vh) : 0.0;
}

static v3 cosine_dir(double u1, double u2)
{
    double r = sqrt(u1), phi = 2.0 * M_PI * u2;
    return mk(r * cos(phi), r * sin(phi), sqrt(1.0 - u1 > 0.0 ? 1.0 - u1 : 0.0));
}

static v3 lobe_sample(const lobe *L, double u1, double u2)
{
    if (L->kind == LOBE_DIFFUSE)
        return cosine_dir(u1, u2);
    double a2 = L->alpha * L->alpha;
    double t2 = a2 * u1 / (1.0 - u1); /* tan^2 of h's polar angle */
    double ch = 1.0 / sqrt(1.0 + t2), sh = sqrt(1.0 - ch * ch), phi = 2.0 * M_PI * u2;
    v3 h = mk(sh * cos(phi), sh * sin(phi), ch);
    return add(scale(h, 2.0 * dot(L->wo, h)), scale(L->wo, -1.0));
}

/* ---- the LTC ---------------------------------------------------------- */

typedef struct ltc {
    double m[9], minv[9]; /* row-major */
    double det_inv;       /* |det M^-1| */
    double horizon;       /* mass of D above the shading horizon */
} ltc;

static v3 mul(const double *m, v3 v)
{
    return mk(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
              m[6] * v.x + m[7] * v.y + m[8] * v.z);
}

static void mat3_mul(const double *a, const double *b, double *out)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0.0;
            for (int k = 0; k < 3; k++)
                s += a[3 * i + k] * b[3 * k + j];
            out[3 * i + j] = s;
        }
}

/* M = R(phi) S(a, c, b). */
static void ltc_make(ltc *t, double phi, double a, double c, double b)
{
    double cp = cos(phi), sp = sin(phi);
    double R[9] = {cp, 0, sp, 0, 1, 0, -sp, 0, cp};
    double S[9] = {a, 0, b, 0, c, 0, 0, 0, 1};
    mat3_mul(R, S, t->m);
    /* S^-1 R^T */
    double Si[9] = {1.0 / a, 0, -b / a, 0, 1.0 / c, 0, 0, 0, 1};
    double Rt[9] = {cp, 0, -sp, 0, 1, 0, sp, 0, cp};
    mat3_mul(Si, Rt, t->minv);
    t->det_inv = 1.0 / (a * c);
    /* (M w_o).z > 0 is a half-space of the cosine's domain with pole the
     * third row of M; a clamped cosine has mass (1 + cos) / 2 there. */
    v3 r3 = norm(mk(t->m[6], t->m[7], t->m[8]));
    t->horizon = 0.5 * (1.0 + r3.z);
}

static double ltc_pdf(const ltc *t, v3 w)
{
    v3 o = mul(t->minv, w);
    double l2 = dot(o, o);
    if (o.z <= 0.0 || l2 <= 0.0)
        return 0.0;
    double l = sqrt(l2);
    return (o.z / l) / M_PI * t->det_inv / (l2 * l);
}

/* A sample of the LTC and its density. */
static v3 ltc_sample(const ltc *t, double u1, double u2, double *pdf)
{
    v3 o = cosine_dir(u1, u2);
    v3 w = mul(t->m, o);
    double l = sqrt(dot(w, w));
    /* M^-1 w_normalised = o / l, so |M^-1 w| = 1 / l */
    *pdf = o.z / M_PI * t->det_inv * l * l * l;
    return scale(w, 1.0 / l);
}

/* ---- one bin ---------------------------------------------------------- */

typedef struct bin_fit {
    lobe L;
    double N, K, phi;                    /* norm, Fresnel fraction, average direction */
    int ns;
    v3 *bw;                              /* lobe samples */
    double *bq, *bp;                     /* their sampler density, normalised lobe value */
    double *u1, *u2;                     /* the LTC sampler's points */
} bin_fit;

/* N = int f cos, K = int f cos s5 / N, and the average direction, by the
 * lobe's sampler on NORM_SAMPLES Hammersley points. */
static void lobe_moments(bin_fit *B)
{
    double n = 0.0, k = 0.0;
    v3 avg = mk(0, 0, 0);
    for (int i = 0; i < NORM_SAMPLES; i++) {
        v3 w = lobe_sample(&B->L, (i + 0.5) / NORM_SAMPLES, radical_inverse2((unsigned)i));
        double q = lobe_pdf(&B->L, w), s5;
        double f = lobe_eval(&B->L, w, &s5);
        if (q <= 0.0 || f <= 0.0)
            continue;
        n += f / q;
        k += f * s5 / q;
        avg = add(avg, scale(w, f / q));
    }
    B->N = n / NORM_SAMPLES;
    B->K = n > 0.0 ? k / n : 0.0;
    B->phi = atan2(avg.x, avg.z);
}

static void bin_samples(bin_fit *B, int ns)
{
    B->ns = ns;
    for (int i = 0; i < ns; i++) {
        double u1 = (i + 0.5) / ns, u2 = radical_inverse2((unsigned)i), s5;
        B->u1[i] = u1;
        B->u2[i] = u2;
        B->bw[i] = lobe_sample(&B->L, u1, u2);
        B->bq[i] = lobe_pdf(&B->L, B->bw[i]);
        B->bp[i] = lobe_eval(&B->L, B->bw[i], &s5) / B->N;
    }
}

/* int |lobe - D_clipped / h|^p over the sphere, by MIS of both samplers. */
static double bin_error(const bin_fit *B, const ltc *t, int power)
{
    double e = 0.0;
    for (int i = 0; i < B->ns; i++) {
        /* from the lobe's sampler */
        v3 w = B->bw[i];
        double pl = ltc_pdf(t, w);
        double ql = pl;
        if (w.z <= 0.0)
            pl = 0.0;
        double d = fabs(B->bp[i] - pl / t->horizon);
        double den = B->bq[i] + ql;
        if (den > 0.0)
            e += (power == 3 ? d * d * d : d) / den;
        /* from the LTC's sampler */
        double q2;
        v3 w2 = ltc_sample(t, B->u1[i], B->u2[i], &q2);
        double s5;
        double pb = lobe_eval(&B->L, w2, &s5) / B->N;
        double pl2 = w2.z > 0.0 ? q2 : 0.0;
        double d2 = fabs(pb - pl2 / t->horizon);
        double den2 = lobe_pdf(&B->L, w2) + q2;
        if (den2 > 0.0)
            e += (power == 3 ? d2 * d2 * d2 : d2) / den2;
    }
    return e / B->ns;
}

static void params_ltc(const bin_fit *B, const double *p, int dim, ltc *t)
{
    double a = exp(p[0]), c = dim == 1 ? a : exp(p[1]), b = dim == 1 ? 0.0 : p[2];
    ltc_make(t, dim == 1 ? 0.0 : B->phi + p[3], a, c, b);
}

static double objective(const bin_fit *B, const double *p, int dim)
{
    ltc t;
    params_ltc(B, p, dim, &t);
    return bin_error(B, &t, 3);
}

/* Nelder-Mead (reflection 1, expansion 2, contraction 1/2, shrink 1/2). */
static void nelder_mead(const bin_fit *B, double *p, int dim, double step, int max_eval)
{
    double x[5][4], f[5];
    for (int i = 0; i <= dim; i++) {
        memcpy(x[i], p, sizeof(double) * (size_t)dim);
        if (i > 0)
            x[i][i - 1] += step;
        f[i] = objective(B, x[i], dim);
    }
    int evals = dim + 1;
    while (evals < max_eval) {
        /* order: best first */
        for (int i = 1; i <= dim; i++)
            for (int j = i; j > 0 && f[j] < f[j - 1]; j--) {
                double tf = f[j];
                f[j] = f[j - 1];
                f[j - 1] = tf;
                for (int k = 0; k < dim; k++) {
                    double tx = x[j][k];
                    x[j][k] = x[j - 1][k];
                    x[j - 1][k] = tx;
                }
            }
        if (f[dim] - f[0] <= 1e-9 * fabs(f[0]) + 1e-14)
            break;
        double cen[4] = {0, 0, 0, 0}, xr[4], xe[4], xc[4];
        for (int i = 0; i < dim; i++)
            for (int k = 0; k < dim; k++)
                cen[k] += x[i][k] / dim;
        for (int k = 0; k < dim; k++)
            xr[k] = cen[k] + (cen[k] - x[dim][k]);
        double fr = objective(B, xr, dim);
        evals++;
        if (fr < f[0]) {
            for (int k = 0; k < dim; k++)
                xe[k] = cen[k] + 2.0 * (cen[k] - x[dim][k]);
            double fe = objective(B, xe, dim);
            evals++;
            if (fe < fr) {
                memcpy(x[dim], xe, sizeof xe);
                f[dim] = fe;
            } else {
                memcpy(x[dim], xr, sizeof xr);
                f[dim] = fr;
            }
            continue;
        }
        if (fr < f[dim - 1]) {
            memcpy(x[dim], xr, sizeof xr);
            f[dim] = fr;
            continue;
        }
        int outside = fr < f[dim];
        for (int k = 0; k < dim; k++)
            xc[k] = outside ? cen[k] + 0.5 * (xr[k] - cen[k]) : cen[k] + 0.5 * (x[dim][k] - cen[k]);
        double fc = objective(B, xc, dim);
        evals++;
        if (fc < (outside ? fr : f[dim])) {
            memcpy(x[dim], xc, sizeof xc);
            f[dim] = fc;
            continue;
        }
        for (int i = 1; i <= dim; i++) {
            for (int k = 0; k < dim; k++)
                x[i][k] = x[0][k] + 0.5 * (x[i][k] - x[0][k]);
            f[i] = objective(B, x[i], dim);
            evals++;
        }
    }
    int best = 0;
    for (int i = 1; i <= dim; i++)
        if (f[i] < f[best])
            best = i;
    memcpy(p, x[best], sizeof(double) * (size_t)dim);
}

/* ---- tables ----------------------------------------------------------- */

typedef struct out_bin {
    float m00, m02, m20, m22, norm, fresnel;
    double l1; /* quality: L1 distance, lobe vs fitted distribution */
} out_bin;

static double bin_cos(int j)
{
    double u = (double)j / (N_COS - 1), c = 1.0 - u * u;
    return c > MIN_NV ? c : MIN_NV;
}

/* Fit one bin from p (dim parameters; updated), store its table entry. */
static void fit_bin(bin_fit *B, double *p, int dim, out_bin *o)
{
    lobe_moments(B);
    bin_samples(B, FIT_SAMPLES);
    nelder_mead(B, p, dim, 0.05, 600);
    ltc t;
    params_ltc(B, p, dim, &t);
    /* M^-1 scaled so that its (1,1) entry is 1 */
    double s = 1.0 / t.minv[4];
    o->m00 = (float)(t.minv[0] * s);
    o->m02 = (float)(t.minv[2] * s);
    o->m20 = (float)(t.minv[6] * s);
    o->m22 = (float)(t.minv[8] * s);
    o->norm = (float)(B->N / t.horizon);
    o->fresnel = B->L.kind == LOBE_GGX ? (float)B->K : 0.0f;
    bin_samples(B, CHECK_SAMPLES);
    o->l1 = bin_error(B, &t, 1);
}

static void print_bin(FILE *f, const out_bin *b)
{
    fprintf(f, "%.9g %.9g %.9g %.9g %.9g %.9g\n", b->m00, b->m02, b->m20, b->m22, b->norm, b->fresnel);
}

/* The fit's stages in order: options, the grid of roughness and view
 * angle, each cell's fit from its neighbour's, the table written.  One
 * piece: each stage is a loop over the same grid. */
int main(int argc, char **argv)
{
    const char *path = NULL;
    if (argc == 3 && strcmp(argv[1], "-o") == 0)
        path = argv[2];
    else if (argc != 1) {
        fprintf(stderr, "usage: ltc-fit [-o FILE]\n");
        return 2;
    }
    static out_bin ggx[N_ROUGH][N_COS], fre[N_ROUGH][N_COS], dif[N_COS];
    bin_fit B;
    size_t ns = CHECK_SAMPLES > FIT_SAMPLES ? CHECK_SAMPLES : FIT_SAMPLES;
    B.bw = malloc(ns * sizeof *B.bw);
    B.bq = malloc(ns * sizeof *B.bq);
    B.bp = malloc(ns * sizeof *B.bp);
    B.u1 = malloc(ns * sizeof *B.u1);
    B.u2 = malloc(ns * sizeof *B.u2);
    if (!B.bw || !B.bq || !B.bp || !B.u1 || !B.u2) {
        fprintf(stderr, "ltc-fit: out of memory\n");
        return 1;
    }

    /* GGX: roughest row first; along a row, from normal incidence out,
     * each bin starting from its neighbour's solution. */
    double row_start[4] = {0.0, 0.0, 0.0, 0.0};
    for (int i = N_ROUGH - 1; i >= 0; i--) {
        double r = (double)i / (N_ROUGH - 1);
        double alpha = r * r > MIN_ALPHA ? r * r : MIN_ALPHA;
        double p[4];
        for (int j = 0; j < N_COS; j++) {
            double c = bin_cos(j);
            B.L.kind = LOBE_GGX;
            B.L.alpha = alpha;
            B.L.nv = c;
            B.L.wo = mk(sqrt(1.0 - c * c), 0.0, c);
            int dim = j == 0 ? 1 : 4;
            if (j == 0)
                p[0] = row_start[0];
            fit_bin(&B, p, dim, &ggx[i][j]);
            /* the Fresnel-weighted lobe, from this bin's solution */
            double q[4];
            memcpy(q, p, sizeof q);
            B.L.kind = LOBE_GGX_FRESNEL;
            fit_bin(&B, q, dim, &fre[i][j]);
            if (j == 0) {
                row_start[0] = p[0];
                p[1] = p[0];
                p[2] = p[3] = 0.0;
            }
        }
        fprintf(stderr, "ltc-fit: roughness %.3f done\n", r);
    }
    /* the diffuse lobe, from the cosine (M = I) at normal incidence */
    double p[4] = {0.0, 0.0, 0.0, 0.0};
    for (int j = 0; j < N_COS; j++) {
        double c = bin_cos(j);
        B.L.kind = LOBE_DIFFUSE;
        B.L.alpha = 1.0;
        B.L.nv = c;
        B.L.wo = mk(sqrt(1.0 - c * c), 0.0, c);
        if (j == 0) {
            fit_bin(&B, p, 1, &dif[j]);
            p[1] = p[0];
            p[2] = p[3] = 0.0;
        } else {
            fit_bin(&B, p, 4, &dif[j]);
        }
    }

    FILE *f = path ? fopen(path, "w") : stdout;
    if (!f) {
        fprintf(stderr, "ltc-fit: %s: cannot write\n", path);
        return 1;
    }
    fprintf(f, "## LTC tables (lib/shade/ltc.h) as data: written by scripts/ltc-fit.c (`make ltc-tables`),\n"
               "## turned into C at build time by scripts/ltc-table.awk.  Lines \"# ...\" are the C file's\n"
               "## header comment; \"NAME ROWS COLS\" starts a table of ROWS x COLS bins (diffuse: COLS),\n"
               "## one bin a line: m00 m02 m20 m22 norm fresnel, as %%.9g.\n"
               "# Generated by scripts/ltc-fit.c (`make ltc-tables`): do not edit.\n"
               "# LTC tables for lib/shade/ltc.h, fitted to lib/shade's BRDF.\n"
               "#\n"
               "# Fit quality: L1 distance between the normalised lobe and the fitted\n"
               "# distribution as evaluated (clipped, renormalised), in %% of the\n"
               "# lobe's mass (0 identical, 200 disjoint), over the %d view angles:\n"
               "#\n"
               "# The Schlick-weighted part D V (1 - v.h)^5 cos: its L1 times its share K\n"
               "# of the lobe (its error in units of the whole specular lobe).\n"
               "#\n"
               "#               D V cos                       D V (1 - v.h)^5 cos\n"
               "#   roughness   mean L1   worst L1   at n.wo   mean L1   worst L1\n",
            N_COS);
    for (int i = 0; i < N_ROUGH; i += 3) {
        double sum = 0.0, worst = 0.0, fsum = 0.0, fworst = 0.0;
        int wj = 0;
        for (int j = 0; j < N_COS; j++) {
            sum += ggx[i][j].l1;
            if (ggx[i][j].l1 > worst) {
                worst = ggx[i][j].l1;
                wj = j;
            }
            /* in units of the whole specular lobe: the part's own L1 times its share K */
            double fl = fre[i][j].l1 * ggx[i][j].fresnel;
            fsum += fl;
            fworst = fl > fworst ? fl : fworst;
        }
        fprintf(f, "#   %9.3f   %6.2f%%   %7.2f%%   %7.4f   %6.2f%%   %7.2f%%\n", (double)i / (N_ROUGH - 1),
                100.0 * sum / N_COS, 100.0 * worst, bin_cos(wj), 100.0 * fsum / N_COS, 100.0 * fworst);
    }
    {
        double sum = 0.0, worst = 0.0;
        for (int j = 0; j < N_COS; j++) {
            sum += dif[j].l1;
            worst = dif[j].l1 > worst ? dif[j].l1 : worst;
        }
        fprintf(f, "#   diffuse     %6.2f%%   %7.2f%%\n", 100.0 * sum / N_COS, 100.0 * worst);
    }
    fprintf(f, "ggx %d %d\n", N_ROUGH, N_COS);
    for (int i = 0; i < N_ROUGH; i++)
        for (int j = 0; j < N_COS; j++)
            print_bin(f, &ggx[i][j]);
    fprintf(f, "ggx_fresnel %d %d\n", N_ROUGH, N_COS);
    for (int i = 0; i < N_ROUGH; i++)
        for (int j = 0; j < N_COS; j++)
            print_bin(f, &fre[i][j]);
    fprintf(f, "diffuse %d\n", N_COS);
    for (int j = 0; j < N_COS; j++)
        print_bin(f, &dif[j]);
    int bad = ferror(f);
    if (path)
        bad |= fclose(f) != 0;
    if (bad) {
        fprintf(stderr, "ltc-fit: %s: write failed\n", path ? path : "stdout");
        return 1;
    }
    free(B.bw);
    free(B.bq);
    free(B.bp);
    free(B.u1);
    free(B.u2);
    return 0;
}
