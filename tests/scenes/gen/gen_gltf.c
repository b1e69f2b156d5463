/* SPDX-License-Identifier: Apache-2.0 */
/* A small glTF 2.0 writer: geometry helpers, the builder, and the JSON,
 * binary and PNG output.  See gen_gltf.h for the contract. */
#include "gen_gltf.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define GLTF_FLOAT 5126
#define GLTF_USHORT 5123
#define GLTF_UINT 5125
#define GLTF_ARRAY_BUFFER 34962
#define GLTF_ELEMENT_ARRAY_BUFFER 34963

/* Grow *p (elements of `size`) to hold at least `need`; 0 or -1. */
static int grow(void **p, uint32_t *cap, uint32_t need, size_t size)
{
    if (need <= *cap)
        return 0;
    uint32_t c = *cap ? *cap : 16;
    while (c < need)
        c *= 2;
    void *q = realloc(*p, (size_t)c * size);
    if (!q)
        return -1;
    *p = q;
    *cap = c;
    return 0;
}

/* ---- geometry --------------------------------------------------------- */

void gen_geom_init(gen_geom *m)
{
    memset(m, 0, sizeof *m);
}

void gen_geom_free(gen_geom *m)
{
    if (!m)
        return;
    free(m->pos);
    free(m->nrm);
    free(m->uv);
    free(m->idx);
    gen_geom_init(m);
}

uint32_t gen_geom_vertex(gen_geom *m, const float p[3], const float n[3],
                         const float uv[2])
{
    if (m->failed)
        return 0;
    uint32_t need = m->n_verts + 1, c = m->cap_verts;
    if (need > c) {
        uint32_t c1 = c, c2 = c, c3 = c;
        if (grow((void **)&m->pos, &c1, need, 3 * sizeof(float)) ||
            grow((void **)&m->nrm, &c2, need, 3 * sizeof(float)) ||
            grow((void **)&m->uv, &c3, need, 2 * sizeof(float))) {
            m->failed = 1;
            return 0;
        }
        m->cap_verts = c1;
    }
    uint32_t i = m->n_verts++;
    memcpy(m->pos + 3 * i, p, 3 * sizeof(float));
    memcpy(m->nrm + 3 * i, n, 3 * sizeof(float));
    m->uv[2 * i] = uv ? uv[0] : 0.0f;
    m->uv[2 * i + 1] = uv ? uv[1] : 0.0f;
    if (uv)
        m->has_uv = 1;
    return i;
}

void gen_geom_tri(gen_geom *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (m->failed)
        return;
    if (grow((void **)&m->idx, &m->cap_idx, m->n_idx + 3, sizeof(uint32_t))) {
        m->failed = 1;
        return;
    }
    m->idx[m->n_idx++] = a;
    m->idx[m->n_idx++] = b;
    m->idx[m->n_idx++] = c;
}

/* Newell's normal of a polygon, not normalised. */
static void newell(const float p[4][3], double n[3])
{
    n[0] = n[1] = n[2] = 0.0;
    for (int i = 0; i < 4; i++) {
        const float *a = p[i], *b = p[(i + 1) % 4];
        n[0] += ((double)a[1] - b[1]) * ((double)a[2] + b[2]);
        n[1] += ((double)a[2] - b[2]) * ((double)a[0] + b[0]);
        n[2] += ((double)a[0] - b[0]) * ((double)a[1] + b[1]);
    }
}

void gen_geom_quad(gen_geom *m, const float p[4][3], const float uv[4][2])
{
    double d[3];
    newell(p, d);
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    float n[3] = {(float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len)};
    uint32_t v[4];
    for (int i = 0; i < 4; i++)
        v[i] = gen_geom_vertex(m, p[i], n, uv ? uv[i] : NULL);
    gen_geom_tri(m, v[0], v[1], v[2]);
    gen_geom_tri(m, v[0], v[2], v[3]);
}

void gen_geom_quad_facing(gen_geom *m, const float p[4][3], const float want[3])
{
    double d[3];
    newell(p, d);
    if (d[0] * want[0] + d[1] * want[1] + d[2] * want[2] >= 0.0) {
        gen_geom_quad(m, p, NULL);
        return;
    }
    float r[4][3];
    for (int i = 0; i < 4; i++)
        memcpy(r[i], p[3 - i], sizeof r[i]);
    gen_geom_quad(m, (const float (*)[3])r, NULL);
}

void gen_geom_box(gen_geom *m, const float lo[3], const float hi[3])
{
    for (int axis = 0; axis < 3; axis++) {
        int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int side = 0; side < 2; side++) {
            float p[4][3], want[3] = {0, 0, 0};
            want[axis] = side ? 1.0f : -1.0f;
            for (int i = 0; i < 4; i++) {
                p[i][axis] = side ? hi[axis] : lo[axis];
                p[i][u] = (i == 1 || i == 2) ? hi[u] : lo[u];
                p[i][v] = (i >= 2) ? hi[v] : lo[v];
            }
            gen_geom_quad_facing(m, (const float (*)[3])p, want);
        }
    }
}

void gen_geom_lathe(gen_geom *m, const float (*prof)[4], int n, int segs)
{
    const double two_pi = 6.283185307179586;
    for (int i = 0; i + 1 < n; i++) {
        const float *a = prof[i], *b = prof[i + 1];
        if (a[0] == b[0] && a[1] == b[1])
            continue;
        /* Two rings of `segs` vertices: point (r sin phi, y, r cos phi). */
        uint32_t ring[2];
        for (int k = 0; k < 2; k++) {
            const float *q = k ? b : a;
            double nl = sqrt((double)q[2] * q[2] + (double)q[3] * q[3]);
            for (int j = 0; j < segs; j++) {
                double phi = two_pi * j / segs, s = sin(phi), c = cos(phi);
                float p[3] = {(float)(q[0] * s), q[1], (float)(q[0] * c)};
                float nn[3] = {(float)(q[2] / nl * s), (float)(q[3] / nl),
                               (float)(q[2] / nl * c)};
                uint32_t v = gen_geom_vertex(m, p, nn, NULL);
                if (j == 0)
                    ring[k] = v;
            }
        }
        for (int j = 0; j < segs; j++) {
            int j1 = (j + 1) % segs;
            uint32_t va = ring[0] + (uint32_t)j, vb = ring[0] + (uint32_t)j1;
            uint32_t vc = ring[1] + (uint32_t)j1, vd = ring[1] + (uint32_t)j;
            if (a[0] != 0.0f)
                gen_geom_tri(m, va, vb, vc);
            if (b[0] != 0.0f)
                gen_geom_tri(m, va, vc, vd);
        }
    }
}

uint32_t gen_geom_triangles(const gen_geom *m)
{
    return m->n_idx / 3;
}

/* ---- builder ---------------------------------------------------------- */

typedef struct gltf_view {
    uint32_t offset, length, target;
} gltf_view;

typedef struct gltf_accessor {
    uint32_t view, comp, count;
    const char *type;           /* "SCALAR", "VEC2", "VEC3" */
    int has_minmax;
    float min[3], max[3];
} gltf_accessor;

typedef struct gltf_prim {
    int pos, nrm, uv, idx;      /* accessor indices; uv -1 when absent */
    int material;
} gltf_prim;

typedef struct gltf_mesh {
    char *name;
    gltf_prim *prims;
    int n_prims;
    uint32_t n_tris;
} gltf_mesh;

typedef struct gltf_camera {
    char *name;
    float yfov, aspect, znear, zfar;
} gltf_camera;

struct gen_gltf {
    uint8_t *bin;
    uint32_t bin_len, bin_cap;
    gltf_view *views;           uint32_t n_views, cap_views;
    gltf_accessor *accs;        uint32_t n_accs, cap_accs;
    gen_material *mats;         uint32_t n_mats, cap_mats;
    char **tex_uris;            uint32_t n_texs, cap_texs;
    gltf_mesh *meshes;          uint32_t n_meshes, cap_meshes;
    gltf_camera *cams;          uint32_t n_cams, cap_cams;
    gen_node *nodes;            uint32_t n_nodes, cap_nodes;
    int failed;
    const char *why;            /* the first error, when failed */
};

gen_gltf *gen_gltf_create(void)
{
    return calloc(1, sizeof(gen_gltf));
}

void gen_gltf_destroy(gen_gltf *g)
{
    if (!g)
        return;
    free(g->bin);
    free(g->views);
    free(g->accs);
    for (uint32_t i = 0; i < g->n_mats; i++)
        free((char *)g->mats[i].name);
    free(g->mats);
    for (uint32_t i = 0; i < g->n_texs; i++)
        free(g->tex_uris[i]);
    free(g->tex_uris);
    for (uint32_t i = 0; i < g->n_meshes; i++) {
        free(g->meshes[i].name);
        free(g->meshes[i].prims);
    }
    free(g->meshes);
    for (uint32_t i = 0; i < g->n_cams; i++)
        free(g->cams[i].name);
    free(g->cams);
    for (uint32_t i = 0; i < g->n_nodes; i++)
        free((char *)g->nodes[i].name);
    free(g->nodes);
    free(g);
}

static char *dup_str(gen_gltf *g, const char *s)
{
    if (!s)
        return NULL;
    char *d = strdup(s);
    if (!d)
        g->failed = 1;
    return d;
}

/* Reserve one more element of an array; its index, or -1. */
#define PUSH(g, arr, n, cap)                                                 \
    ((g)->failed || grow((void **)&(g)->arr, &(g)->cap, (g)->n + 1,          \
                         sizeof *(g)->arr)                                   \
         ? ((g)->failed = 1, -1)                                             \
         : (int)(g)->n++)

static void put_u32(uint8_t *d, uint32_t v)
{
    d[0] = (uint8_t)v;
    d[1] = (uint8_t)(v >> 8);
    d[2] = (uint8_t)(v >> 16);
    d[3] = (uint8_t)(v >> 24);
}

/* Append a buffer view of `count` elements of `comp` type (floats or
 * indices) read from src (float* or uint32_t*), 4-byte aligned. */
static int add_view(gen_gltf *g, const void *src, uint32_t count, uint32_t comp,
                    uint32_t target)
{
    uint32_t esize = comp == GLTF_USHORT ? 2 : 4;
    uint32_t off = (g->bin_len + 3u) & ~3u, len = count * esize;
    if (g->failed || grow((void **)&g->bin, &g->bin_cap, off + len + 4, 1)) {
        g->failed = 1;
        return -1;
    }
    memset(g->bin + g->bin_len, 0, off - g->bin_len);
    uint8_t *d = g->bin + off;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t v;
        if (comp == GLTF_FLOAT)
            memcpy(&v, (const float *)src + i, 4);
        else
            v = ((const uint32_t *)src)[i];
        if (esize == 2) {
            d[2 * i] = (uint8_t)v;
            d[2 * i + 1] = (uint8_t)(v >> 8);
        } else {
            put_u32(d + 4 * i, v);
        }
    }
    g->bin_len = off + len;
    int vi = PUSH(g, views, n_views, cap_views);
    if (vi < 0)
        return -1;
    g->views[vi] = (gltf_view){off, len, target};
    return vi;
}

static int add_accessor(gen_gltf *g, const void *src, uint32_t count, int ncomp,
                        uint32_t comp, uint32_t target, int minmax)
{
    int view = add_view(g, src, count * (uint32_t)ncomp, comp, target);
    if (view < 0)
        return -1;
    int ai = PUSH(g, accs, n_accs, cap_accs);
    if (ai < 0)
        return -1;
    gltf_accessor *a = &g->accs[ai];
    memset(a, 0, sizeof *a);
    a->view = (uint32_t)view;
    a->comp = comp;
    a->count = count;
    a->type = ncomp == 1 ? "SCALAR" : ncomp == 2 ? "VEC2" : "VEC3";
    a->has_minmax = minmax;
    if (minmax) {
        const float *f = src;
        for (int k = 0; k < ncomp; k++)
            a->min[k] = a->max[k] = f[k];
        for (uint32_t i = 1; i < count; i++)
            for (int k = 0; k < ncomp; k++) {
                float x = f[i * (uint32_t)ncomp + (uint32_t)k];
                a->min[k] = x < a->min[k] ? x : a->min[k];
                a->max[k] = x > a->max[k] ? x : a->max[k];
            }
    }
    return ai;
}

int gen_gltf_add_material(gen_gltf *g, const gen_material *mat)
{
    int i = PUSH(g, mats, n_mats, cap_mats);
    if (i < 0)
        return -1;
    g->mats[i] = *mat;
    g->mats[i].name = dup_str(g, mat->name);
    return g->failed ? -1 : i;
}

int gen_gltf_add_texture(gen_gltf *g, const char *uri)
{
    int i = PUSH(g, tex_uris, n_texs, cap_texs);
    if (i < 0)
        return -1;
    g->tex_uris[i] = dup_str(g, uri);
    return g->failed ? -1 : i;
}

int gen_gltf_add_mesh(gen_gltf *g, const char *name, const gen_prim *prims,
                      int n_prims)
{
    int mi = PUSH(g, meshes, n_meshes, cap_meshes);
    if (mi < 0)
        return -1;
    gltf_mesh *m = &g->meshes[mi];
    memset(m, 0, sizeof *m);
    m->name = dup_str(g, name);
    m->prims = calloc((size_t)n_prims, sizeof *m->prims);
    if (!m->prims || g->failed) {
        g->failed = 1;
        return -1;
    }
    m->n_prims = n_prims;
    for (int i = 0; i < n_prims; i++) {
        const gen_geom *s = prims[i].geom;
        gltf_prim *p = &m->prims[i];
        if (s->failed) {
            g->failed = 1;
            return -1;
        }
        uint32_t icomp = s->n_verts <= 65535 ? GLTF_USHORT : GLTF_UINT;
        p->pos = add_accessor(g, s->pos, s->n_verts, 3, GLTF_FLOAT,
                              GLTF_ARRAY_BUFFER, 1);
        p->nrm = add_accessor(g, s->nrm, s->n_verts, 3, GLTF_FLOAT,
                              GLTF_ARRAY_BUFFER, 0);
        p->uv = s->has_uv ? add_accessor(g, s->uv, s->n_verts, 2, GLTF_FLOAT,
                                         GLTF_ARRAY_BUFFER, 0)
                          : -1;
        p->idx = add_accessor(g, s->idx, s->n_idx, 1, icomp,
                              GLTF_ELEMENT_ARRAY_BUFFER, 0);
        p->material = prims[i].material;
        m->n_tris += s->n_idx / 3;
    }
    return g->failed ? -1 : mi;
}

int gen_gltf_add_camera(gen_gltf *g, const char *name, float yfov,
                        float aspect, float znear, float zfar)
{
    int i = PUSH(g, cams, n_cams, cap_cams);
    if (i < 0)
        return -1;
    g->cams[i] = (gltf_camera){dup_str(g, name), yfov, aspect, znear, zfar};
    return g->failed ? -1 : i;
}

int gen_gltf_add_node(gen_gltf *g, const gen_node *node)
{
    if (node->parent >= (int)g->n_nodes && !g->failed) {
        g->failed = 1;
        g->why = "a node's parent was not added before it";
    }
    int i = PUSH(g, nodes, n_nodes, cap_nodes);
    if (i < 0)
        return -1;
    g->nodes[i] = *node;
    g->nodes[i].name = dup_str(g, node->name);
    return g->failed ? -1 : i;
}

uint32_t gen_gltf_triangles(const gen_gltf *g)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < g->n_nodes; i++)
        if (g->nodes[i].mesh >= 0)
            n += g->meshes[g->nodes[i].mesh].n_tris;
    return n;
}

int gen_gltf_node_count(const gen_gltf *g)
{
    return (int)g->n_nodes;
}

/* ---- output ----------------------------------------------------------- */

static void set_err(char *err, size_t size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void set_err(char *err, size_t size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, size, fmt, ap);
    va_end(ap);
}

/* Atomic output (CONTRIBUTING.md, Files): a temporary file beside the target. */
typedef struct atomic_file {
    FILE *f;
    char tmp[4096];
    char path[4096];
} atomic_file;

static int atomic_open(atomic_file *af, const char *path, char *err, size_t esz)
{
    af->f = NULL;
    if (snprintf(af->path, sizeof af->path, "%s", path) >= (int)sizeof af->path ||
        snprintf(af->tmp, sizeof af->tmp, "%s.tmpXXXXXX", path) >= (int)sizeof af->tmp) {
        set_err(err, esz, "%s: path too long", path);
        return -1;
    }
    int fd = mkstemp(af->tmp);
    if (fd < 0) {
        set_err(err, esz, "%s: %s", path, strerror(errno));
        return -1;
    }
    fchmod(fd, 0644);
    af->f = fdopen(fd, "wb");
    if (!af->f) {
        set_err(err, esz, "%s: %s", path, strerror(errno));
        close(fd);
        unlink(af->tmp);
        return -1;
    }
    return 0;
}

/* Finish (ok != 0) or abandon the file; 0 or -1. */
static int atomic_close(atomic_file *af, int ok, char *err, size_t esz)
{
    if (ok && (fflush(af->f) != 0 || ferror(af->f) || fsync(fileno(af->f)) != 0)) {
        set_err(err, esz, "%s: %s", af->path, strerror(errno));
        ok = 0;
    }
    if (fclose(af->f) != 0 && ok) {
        set_err(err, esz, "%s: %s", af->path, strerror(errno));
        ok = 0;
    }
    if (ok && rename(af->tmp, af->path) != 0) {
        set_err(err, esz, "%s: %s", af->path, strerror(errno));
        ok = 0;
    }
    if (!ok)
        unlink(af->tmp);
    return ok ? 0 : -1;
}

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

static void json_floats(FILE *f, const float *v, int n)
{
    fputc('[', f);
    for (int i = 0; i < n; i++) /* -0 is written as 0 */
        fprintf(f, "%s%.9g", i ? ", " : "", v[i] == 0.0f ? 0.0 : (double)v[i]);
    fputc(']', f);
}

/* "sep" before every element but the first of a list. */
static const char *sep(uint32_t i)
{
    return i ? ",\n" : "\n";
}

static void write_nodes(FILE *f, const gen_gltf *g)
{
    fprintf(f, "  \"nodes\": [");
    for (uint32_t i = 0; i < g->n_nodes; i++) {
        const gen_node *n = &g->nodes[i];
        fprintf(f, "%s    {\"name\": ", sep(i));
        json_str(f, n->name);
        if (n->mesh >= 0)
            fprintf(f, ", \"mesh\": %d", n->mesh);
        if (n->camera >= 0)
            fprintf(f, ", \"camera\": %d", n->camera);
        if (n->use_matrix) {
            fprintf(f, ", \"matrix\": ");
            json_floats(f, n->matrix, 16);
        } else {
            const float *t = n->translation, *r = n->rotation, *s = n->scale;
            if (t[0] != 0 || t[1] != 0 || t[2] != 0) {
                fprintf(f, ", \"translation\": ");
                json_floats(f, t, 3);
            }
            if (r[0] != 0 || r[1] != 0 || r[2] != 0 || r[3] != 1) {
                fprintf(f, ", \"rotation\": ");
                json_floats(f, r, 4);
            }
            if (s[0] != 1 || s[1] != 1 || s[2] != 1) {
                fprintf(f, ", \"scale\": ");
                json_floats(f, s, 3);
            }
        }
        int first = 1;
        for (uint32_t c = i + 1; c < g->n_nodes; c++)
            if (g->nodes[c].parent == (int)i) {
                fprintf(f, "%s%u", first ? ", \"children\": [" : ", ", c);
                first = 0;
            }
        fprintf(f, "%s}", first ? "" : "]");
    }
    fprintf(f, "\n  ],\n");
}

static void write_meshes(FILE *f, const gen_gltf *g)
{
    fprintf(f, "  \"meshes\": [");
    for (uint32_t i = 0; i < g->n_meshes; i++) {
        const gltf_mesh *m = &g->meshes[i];
        fprintf(f, "%s    {\"name\": ", sep(i));
        json_str(f, m->name);
        fprintf(f, ", \"primitives\": [");
        for (int k = 0; k < m->n_prims; k++) {
            const gltf_prim *p = &m->prims[k];
            fprintf(f, "%s{\"attributes\": {\"POSITION\": %d, \"NORMAL\": %d",
                    k ? ", " : "", p->pos, p->nrm);
            if (p->uv >= 0)
                fprintf(f, ", \"TEXCOORD_0\": %d", p->uv);
            fprintf(f, "}, \"indices\": %d", p->idx);
            if (p->material >= 0)
                fprintf(f, ", \"material\": %d", p->material);
            fprintf(f, ", \"mode\": 4}");
        }
        fprintf(f, "]}");
    }
    fprintf(f, "\n  ],\n");
}

static void write_materials(FILE *f, const gen_gltf *g)
{
    fprintf(f, "  \"materials\": [");
    for (uint32_t i = 0; i < g->n_mats; i++) {
        const gen_material *m = &g->mats[i];
        fprintf(f, "%s    {\"name\": ", sep(i));
        json_str(f, m->name ? m->name : "");
        fprintf(f, ", \"pbrMetallicRoughness\": {\"baseColorFactor\": ");
        json_floats(f, m->base_color, 4);
        if (m->base_color_texture >= 0)
            fprintf(f, ", \"baseColorTexture\": {\"index\": %d}",
                    m->base_color_texture);
        fprintf(f, ", \"metallicFactor\": %.9g, \"roughnessFactor\": %.9g}",
                (double)m->metallic, (double)m->roughness);
        if (m->emissive[0] != 0 || m->emissive[1] != 0 || m->emissive[2] != 0) {
            fprintf(f, ", \"emissiveFactor\": ");
            json_floats(f, m->emissive, 3);
        }
        if (m->emissive_strength > 0)
            fprintf(f, ", \"extensions\": {\"KHR_materials_emissive_strength\": "
                       "{\"emissiveStrength\": %.9g}}",
                    (double)m->emissive_strength);
        fprintf(f, ", \"doubleSided\": %s}", m->double_sided ? "true" : "false");
    }
    fprintf(f, "\n  ],\n");
}

static void write_textures(FILE *f, const gen_gltf *g)
{
    if (!g->n_texs)
        return;
    fprintf(f, "  \"textures\": [");
    for (uint32_t i = 0; i < g->n_texs; i++)
        fprintf(f, "%s    {\"sampler\": 0, \"source\": %u}", sep(i), i);
    fprintf(f, "\n  ],\n  \"images\": [");
    for (uint32_t i = 0; i < g->n_texs; i++) {
        fprintf(f, "%s    {\"uri\": ", sep(i));
        json_str(f, g->tex_uris[i]);
        fprintf(f, "}");
    }
    /* LINEAR, LINEAR_MIPMAP_LINEAR, REPEAT, REPEAT */
    fprintf(f, "\n  ],\n  \"samplers\": [\n    {\"magFilter\": 9729, "
               "\"minFilter\": 9987, \"wrapS\": 10497, \"wrapT\": 10497}\n  ],\n");
}

static void write_cameras(FILE *f, const gen_gltf *g)
{
    if (!g->n_cams)
        return;
    fprintf(f, "  \"cameras\": [");
    for (uint32_t i = 0; i < g->n_cams; i++) {
        const gltf_camera *c = &g->cams[i];
        fprintf(f, "%s    {\"name\": ", sep(i));
        json_str(f, c->name ? c->name : "");
        fprintf(f, ", \"type\": \"perspective\", \"perspective\": {");
        if (c->aspect > 0)
            fprintf(f, "\"aspectRatio\": %.9g, ", (double)c->aspect);
        fprintf(f, "\"yfov\": %.9g, \"znear\": %.9g, \"zfar\": %.9g}}",
                (double)c->yfov, (double)c->znear, (double)c->zfar);
    }
    fprintf(f, "\n  ],\n");
}

static void write_accessors(FILE *f, const gen_gltf *g)
{
    fprintf(f, "  \"accessors\": [");
    for (uint32_t i = 0; i < g->n_accs; i++) {
        const gltf_accessor *a = &g->accs[i];
        fprintf(f, "%s    {\"bufferView\": %u, \"componentType\": %u, "
                   "\"count\": %u, \"type\": \"%s\"",
                sep(i), a->view, a->comp, a->count, a->type);
        if (a->has_minmax) {
            int n = a->type[0] == 'S' ? 1 : a->type[3] - '0';
            fprintf(f, ", \"min\": ");
            json_floats(f, a->min, n);
            fprintf(f, ", \"max\": ");
            json_floats(f, a->max, n);
        }
        fprintf(f, "}");
    }
    fprintf(f, "\n  ],\n  \"bufferViews\": [");
    for (uint32_t i = 0; i < g->n_views; i++)
        fprintf(f, "%s    {\"buffer\": 0, \"byteOffset\": %u, \"byteLength\": %u, "
                   "\"target\": %u}",
                sep(i), g->views[i].offset, g->views[i].length, g->views[i].target);
    fprintf(f, "\n  ],\n");
}

static void write_json(FILE *f, const gen_gltf *g, const char *name)
{
    int emissive_ext = 0;
    for (uint32_t i = 0; i < g->n_mats; i++)
        emissive_ext |= g->mats[i].emissive_strength > 0;
    fprintf(f, "{\n  \"asset\": {\"version\": \"2.0\", "
               "\"generator\": \"LIE tests/scenes/gen/gen_scenes\"},\n");
    if (emissive_ext)
        fprintf(f, "  \"extensionsUsed\": [\"KHR_materials_emissive_strength\"],\n");
    fprintf(f, "  \"scene\": 0,\n  \"scenes\": [{\"name\": ");
    json_str(f, name);
    fprintf(f, ", \"nodes\": [");
    int first = 1;
    for (uint32_t i = 0; i < g->n_nodes; i++)
        if (g->nodes[i].parent < 0) {
            fprintf(f, "%s%u", first ? "" : ", ", i);
            first = 0;
        }
    fprintf(f, "]}],\n");
    write_nodes(f, g);
    write_meshes(f, g);
    write_materials(f, g);
    write_textures(f, g);
    write_cameras(f, g);
    write_accessors(f, g);
    fprintf(f, "  \"buffers\": [{\"uri\": ");
    char bin[1024];
    snprintf(bin, sizeof bin, "%s.bin", name);
    json_str(f, bin);
    fprintf(f, ", \"byteLength\": %u}]\n}\n", g->bin_len);
}

int gen_gltf_write(const gen_gltf *g, const char *dir, const char *name,
                   char *err, size_t err_size)
{
    if (g->failed) {
        set_err(err, err_size, "%s: %s", name, g->why ? g->why : "out of memory");
        return -1;
    }
    for (uint32_t i = 0; i < g->n_nodes; i++) {
        if (!g->nodes[i].name) {
            set_err(err, err_size, "%s: node %u has no name", name, i);
            return -1;
        }
        for (uint32_t j = 0; j < i; j++)
            if (!strcmp(g->nodes[i].name, g->nodes[j].name)) {
                set_err(err, err_size, "%s: node name '%s' used twice", name,
                        g->nodes[i].name);
                return -1;
            }
    }
    char path[4096];
    atomic_file af;
    snprintf(path, sizeof path, "%s/%s.bin", dir, name);
    if (atomic_open(&af, path, err, err_size))
        return -1;
    int ok = fwrite(g->bin, 1, g->bin_len, af.f) == g->bin_len;
    if (atomic_close(&af, ok, err, err_size))
        return -1;
    snprintf(path, sizeof path, "%s/%s.gltf", dir, name);
    if (atomic_open(&af, path, err, err_size))
        return -1;
    write_json(af.f, g, name);
    return atomic_close(&af, 1, err, err_size);
}

int gen_png_write(const char *path, int width, int height,
                  const uint8_t *rgb, char *err, size_t err_size)
{
    atomic_file af;
    if (atomic_open(&af, path, err, err_size))
        return -1;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        set_err(err, err_size, "%s: PNG encoding failed", path);
        atomic_close(&af, 0, err, err_size);
        return -1;
    }
    png_init_io(png, af.f);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    for (int y = 0; y < height; y++)
        png_write_row(png, rgb + (size_t)y * (size_t)width * 3);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return atomic_close(&af, 1, err, err_size);
}
