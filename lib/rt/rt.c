/* SPDX-License-Identifier: Apache-2.0 */
/* Embree 3 device and scene, and the queries the renderer and lie-build ask. */
#include "rt/rt.h"
#include "rt/boxq.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

struct lie_rt {
    RTCDevice device;
    RTCScene scene;
    const lie_scene *s;
    uint8_t *tri_two_sided; /* per triangle: material is double-sided */
    uint8_t *tri_masked;    /* per triangle: alphaMode MASK (NULL: none is) */
    uint8_t *tri_clear;     /* per triangle: transmissive, no occluder (NULL: none is) */
    /* The transmissive triangles alone, for lie_rt_transmittance: their
     * own Embree scene, its primitive k being triangle glass_tri[k]. */
    RTCScene glass;
    uint32_t *glass_tri;
    float scale;
    lie_error *pending;     /* where the error callback writes during create */
    /* box queries' hierarchy, built by the first query (the renderer never
     * asks one): a cache behind a lock, not a change of what rt answers */
    pthread_mutex_t boxq_lock;
    _Atomic(lie_boxq *) boxq;
    atomic_int boxq_failed; /* out of memory: Embree's point query answers */
};

/* Embree reports errors through a callback; we store the first message. */
static void on_embree_error(void *user, enum RTCError code, const char *str)
{
    lie_rt *rt = user;
    if (rt->pending && rt->pending->status == LIE_OK)
        lie_error_set(rt->pending, LIE_ERR_RT, NULL, "Embree error %d: %s", (int)code,
                      str ? str : "unknown");
}

/* Query modes carried in an extended intersect context (first member is
 * Embree's, so the filter can cast back). */
enum { QUERY_CLOSEST = 0, QUERY_CULL = 1, QUERY_ALL = 2, QUERY_ANY = 3, QUERY_ALL8 = 4 };

typedef struct query_ctx {
    struct RTCIntersectContext ctx;
    int mode;
    const lie_rt *rt;
    const uint32_t *exclude;
    int n_exclude;
    uint32_t **out;
    size_t *n, *cap;
    int nomem;
    int found;           /* QUERY_ANY: a hit not excluded was accepted */
    const uint32_t (*exclude8)[2]; /* QUERY_ALL8: per ray (its id), what not to report */
    const int *n_exclude8;
    unsigned blocked8;   /* QUERY_ALL8: bit id set when ray id hit something */
} query_ctx;

/* Embree's RTCRayN/RTCHitN accessors are C++ only; in C the layouts are
 * structures of arrays of N lanes (rtcore_ray.h): ray = org_x, org_y, org_z,
 * tnear, dir_x, dir_y, dir_z, ...; hit = Ng_x, Ng_y, Ng_z, u, v, primID. */
#define RAYN_DIR(ray, N, i, k) (((const float *)(ray))[(4 + (k)) * (N) + (i)])
#define RAYN_ID(ray, N, i) (((const unsigned *)(ray))[10 * (N) + (i)])
#define HITN_PRIM(hit, N, i) (((const unsigned *)(hit))[5 * (N) + (i)])
#define HITN_U(hit, N, i) (((const float *)(hit))[3 * (N) + (i)])
#define HITN_V(hit, N, i) (((const float *)(hit))[4 * (N) + (i)])

/* A hit on an alpha-masked triangle where its alpha is below the cutoff
 * is no hit at all (for every kind of query). */
static int hit_is_hole(const lie_rt *rt, const struct RTCFilterFunctionNArguments *args, unsigned i,
                       unsigned prim)
{
    return rt->tri_masked && rt->tri_masked[prim] &&
           !lie_scene_solid_at(rt->s, prim, HITN_U(args->hit, args->N, i), HITN_V(args->hit, args->N, i));
}

/* A transmissive triangle occludes nothing (lie_material_transmits): no
 * shadow query, of the renderer or of lie-build, stops at it. */
static int is_clear(const lie_rt *rt, unsigned prim) { return rt->tri_clear && rt->tri_clear[prim]; }

/* Occlusion queries carry Embree's plain context; the rt comes with the
 * geometry (set only when some triangle is masked or transmissive). */
static void occluded_filter(const struct RTCFilterFunctionNArguments *args)
{
    const lie_rt *rt = args->geometryUserPtr;
    for (unsigned i = 0; i < args->N; i++) {
        unsigned prim = HITN_PRIM(args->hit, args->N, i);
        if (args->valid[i] == -1 && (is_clear(rt, prim) || hit_is_hole(rt, args, i, prim)))
            args->valid[i] = 0;
    }
}

static void intersect_filter(const struct RTCFilterFunctionNArguments *args)
{
    query_ctx *q = (query_ctx *)args->context;
    if (q->mode == QUERY_CLOSEST && !q->rt->tri_masked)
        return;
    /* closest hits (camera and mirror rays) see transmissive surfaces;
     * segment queries (lie-build's blockers) do not */
    const int see_clear = q->mode == QUERY_CLOSEST || q->mode == QUERY_CULL;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1)
            continue;
        unsigned prim = HITN_PRIM(args->hit, args->N, i);
        if (hit_is_hole(q->rt, args, i, prim) || (!see_clear && is_clear(q->rt, prim))) {
            args->valid[i] = 0; /* through a hole of an alpha-masked surface, or glass */
            continue;
        }
        if (q->mode == QUERY_CLOSEST)
            continue;
        if (q->mode == QUERY_CULL) {
            if (q->rt->tri_two_sided[prim])
                continue;
            lie_vec3 ng = q->rt->s->tri_ng[prim];
            float dx = RAYN_DIR(args->ray, args->N, i, 0);
            float dy = RAYN_DIR(args->ray, args->N, i, 1);
            float dz = RAYN_DIR(args->ray, args->N, i, 2);
            if (ng.x * dx + ng.y * dy + ng.z * dz > 0.0f)
                args->valid[i] = 0; /* back face of a single-sided surface */
            continue;
        }
        int skip = 0;
        if (q->mode == QUERY_ALL8) {
            unsigned id = RAYN_ID(args->ray, args->N, i) & 7u;
            for (int k = 0; k < q->n_exclude8[id]; k++)
                if (q->exclude8[id][k] == prim)
                    skip = 1;
            args->valid[i] = 0; /* record and reject, as QUERY_ALL */
            if (skip || q->nomem)
                continue;
            q->blocked8 |= 1u << id;
            if (!LIE_PUSH(*q->out, *q->n, *q->cap, prim))
                q->nomem = 1;
            continue;
        }
        for (int k = 0; k < q->n_exclude; k++)
            if (q->exclude[k] == prim)
                skip = 1;
        if (q->mode == QUERY_ANY) {
            /* accept the first hit not excluded: the segment is blocked,
             * and the shortened ray ends traversal soon */
            if (skip)
                args->valid[i] = 0;
            else
                q->found = 1;
            continue;
        }
        /* QUERY_ALL: record and reject, so traversal continues past it. */
        args->valid[i] = 0;
        if (skip || q->nomem)
            continue;
        if (!LIE_PUSH(*q->out, *q->n, *q->cap, prim))
            q->nomem = 1;
    }
}

/* lie_rt_transmittance's query: the transmissive triangles a segment
 * crosses, recorded (at most GLASS_HITS distinct ones) and rejected so that
 * traversal goes on. */
#define GLASS_HITS 64
typedef struct glass_ctx {
    struct RTCIntersectContext ctx;
    const lie_rt *rt;
    uint32_t tri[GLASS_HITS];
    int n, overflow;
} glass_ctx;

static void glass_filter(const struct RTCFilterFunctionNArguments *args)
{
    glass_ctx *q = (glass_ctx *)args->context;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1)
            continue;
        args->valid[i] = 0;
        uint32_t t = q->rt->glass_tri[HITN_PRIM(args->hit, args->N, i)];
        int seen = 0;
        for (int k = 0; k < q->n && !seen; k++)
            seen = q->tri[k] == t; /* Embree may report a triangle twice (spatial splits) */
        if (seen)
            continue;
        if (q->n == GLASS_HITS)
            q->overflow = 1;
        else
            q->tri[q->n++] = t;
    }
}

/* The scene of the transmissive triangles; NULL on an Embree error. */
static RTCScene glass_scene(const lie_rt *rt, uint32_t n)
{
    RTCScene sc = rtcNewScene(rt->device);
    if (!sc)
        return NULL;
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) {
        rtcReleaseScene(sc);
        return NULL;
    }
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * (size_t)n);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n);
    if (vb && ib) {
        for (uint32_t k = 0; k < n; k++)
            memcpy(vb + 9 * (size_t)k, &rt->s->tri_p[3 * (size_t)rt->glass_tri[k]], 9 * sizeof(float));
        for (size_t i = 0; i < 3 * (size_t)n; i++)
            ib[i] = (unsigned)i;
    }
    rtcSetGeometryIntersectFilterFunction(g, glass_filter);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, 0);
    rtcReleaseGeometry(g);
    rtcCommitScene(sc);
    return sc;
}

lie_status lie_rt_create(const lie_scene *s, lie_rt **out, lie_error *err)
{
    *out = NULL;
    lie_rt *rt = calloc(1, sizeof *rt);
    if (!rt)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    lie_error local;
    lie_error_clear(&local);
    rt->pending = &local;
    rt->s = s;
    pthread_mutex_init(&rt->boxq_lock, NULL);
    rt->device = rtcNewDevice("verbose=0,threads=1");
    if (!rt->device) {
        enum RTCError code = rtcGetDeviceError(NULL);
        free(rt);
        return lie_error_set(err, LIE_ERR_RT, s->path, "cannot create Embree device (error %d)", (int)code);
    }
    rtcSetDeviceErrorFunction(rt->device, on_embree_error, rt);
    rt->tri_two_sided = malloc((size_t)s->n_tris + 1);
    if (!rt->tri_two_sided) {
        lie_rt_destroy(rt);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    int any_masked = 0;
    uint32_t n_clear = 0;
    for (uint32_t i = 0; i < s->n_tris; i++) {
        const lie_material *m = lie_scene_material(s, s->tri_material[i]);
        rt->tri_two_sided[i] = (uint8_t)(m->double_sided != 0);
        any_masked |= m->alpha_mask;
        n_clear += (uint32_t)(lie_material_transmits(m) && !s->tri_removed[i]);
    }
    if (n_clear > 0) {
        rt->tri_clear = calloc((size_t)s->n_tris + 1, 1);
        rt->glass_tri = malloc(sizeof *rt->glass_tri * n_clear);
        if (!rt->tri_clear || !rt->glass_tri) {
            lie_rt_destroy(rt);
            return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
        }
        for (uint32_t i = 0, k = 0; i < s->n_tris; i++)
            if (lie_material_transmits(lie_scene_material(s, s->tri_material[i])) && !s->tri_removed[i]) {
                rt->tri_clear[i] = 1;
                rt->glass_tri[k++] = i;
            }
    }
    if (any_masked) {
        rt->tri_masked = malloc((size_t)s->n_tris + 1);
        if (!rt->tri_masked) {
            lie_rt_destroy(rt);
            return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
        }
        for (uint32_t i = 0; i < s->n_tris; i++)
            rt->tri_masked[i] = (uint8_t)(lie_scene_material(s, s->tri_material[i])->alpha_mask != 0);
    }
    lie_vec3 ext = lie_box3_is_empty(&s->bounds) ? lie_v3(1, 1, 1) : lie_v3_sub(s->bounds.hi, s->bounds.lo);
    rt->scale = fmaxf(1.0f, fmaxf(ext.x, fmaxf(ext.y, ext.z)));
    /* Robust traversal: watertight triangle tests, so shadows do not leak
     * through shared edges. */
    rt->scene = rtcNewScene(rt->device);
    if (rt->scene) {
        rtcSetSceneFlags(rt->scene, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(rt->scene, RTC_BUILD_QUALITY_HIGH);
    }
    if (rt->scene && s->n_tris > 0) {
        RTCGeometry g = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (g) {
            float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                3 * sizeof(float), 3 * (size_t)s->n_tris);
            unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                   3 * sizeof(unsigned), s->n_tris);
            if (vb && ib) {
                memcpy(vb, s->tri_p, sizeof(float) * 9 * (size_t)s->n_tris);
                for (size_t i = 0; i < 3 * (size_t)s->n_tris; i++)
                    ib[i] = (unsigned)i;
            }
            rtcSetGeometryIntersectFilterFunction(g, intersect_filter);
            if (rt->tri_masked || rt->tri_clear) {
                rtcSetGeometryUserData(g, rt);
                rtcSetGeometryOccludedFilterFunction(g, occluded_filter);
            }
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(rt->scene, g, 0);
            rtcReleaseGeometry(g);
        }
    }
    if (rt->scene)
        rtcCommitScene(rt->scene);
    if (rt->scene && n_clear > 0)
        rt->glass = glass_scene(rt, n_clear);
    rt->pending = NULL;
    if (!rt->scene || (n_clear > 0 && !rt->glass) || local.status != LIE_OK) {
        lie_status st = local.status != LIE_OK ? local.status : LIE_ERR_RT;
        lie_error_set(err, st, s->path, "%s", local.msg[0] ? local.msg : "cannot build the Embree scene");
        lie_rt_destroy(rt);
        return st;
    }
    *out = rt;
    return LIE_OK;
}

void lie_rt_destroy(lie_rt *rt)
{
    if (!rt)
        return;
    if (rt->scene)
        rtcReleaseScene(rt->scene);
    if (rt->glass)
        rtcReleaseScene(rt->glass);
    if (rt->device)
        rtcReleaseDevice(rt->device);
    free(rt->tri_two_sided);
    free(rt->tri_masked);
    free(rt->tri_clear);
    free(rt->glass_tri);
    lie_boxq_destroy(atomic_load(&rt->boxq));
    pthread_mutex_destroy(&rt->boxq_lock);
    free(rt);
}

float lie_rt_scale(const lie_rt *rt) { return rt->scale; }

static void init_ray(struct RTCRay *r, lie_vec3 org, lie_vec3 dir, float tnear, float tfar)
{
    r->org_x = org.x;
    r->org_y = org.y;
    r->org_z = org.z;
    r->tnear = tnear;
    r->dir_x = dir.x;
    r->dir_y = dir.y;
    r->dir_z = dir.z;
    r->time = 0.0f;
    r->tfar = tfar;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

/* The hit's distance and barycentrics, computed here from the triangle Embree found rather
 * than taken from Embree: Embree picks its kernels by the CPU (SSE2, SSE4.2, AVX, AVX2 with
 * FMA, AVX-512) and their roundings differ, so its t, u and v differ in the last bits from one
 * CPU to another and every image with them.  This is the Moller-Trumbore solution (Moller and
 * Trumbore 1997) in double precision, compiled once for every CPU (lib/core/hot.h), clamped to
 * the triangle as Embree's watertight test keeps it.  A ray nearly parallel to the plane
 * keeps Embree's values. */
static int solve_exact(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, uint32_t tri, double tuv[3])
{
    const lie_vec3 *P = &rt->s->tri_p[3 * (size_t)tri];
    const double e1[3] = {(double)P[1].x - P[0].x, (double)P[1].y - P[0].y, (double)P[1].z - P[0].z};
    const double e2[3] = {(double)P[2].x - P[0].x, (double)P[2].y - P[0].y, (double)P[2].z - P[0].z};
    const double d[3] = {dir.x, dir.y, dir.z};
    const double w[3] = {(double)org.x - P[0].x, (double)org.y - P[0].y, (double)org.z - P[0].z};
    const double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    const double len = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]) *
                       sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]) *
                       sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(fabs(det) > 1e-12 * len))
        return 0;
    const double q[3] = {w[1] * e1[2] - w[2] * e1[1], w[2] * e1[0] - w[0] * e1[2], w[0] * e1[1] - w[1] * e1[0]};
    const double inv = 1.0 / det;
    double u = (w[0] * p[0] + w[1] * p[1] + w[2] * p[2]) * inv;
    double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
    v = v < 0.0 ? 0.0 : v > 1.0 - u ? 1.0 - u : v;
    tuv[0] = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    tuv[1] = u;
    tuv[2] = v;
    return 1;
}

static void hit_exact(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, lie_hit *hit)
{
    double tuv[3];
    if (!solve_exact(rt, org, dir, hit->tri, tuv))
        return;
    hit->t = (float)tuv[0];
    hit->u = (float)tuv[1];
    hit->v = (float)tuv[2];
}

int lie_rt_intersect(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar,
                     int cull_backfaces, lie_hit *hit)
{
    query_ctx q;
    memset(&q, 0, sizeof q);
    rtcInitIntersectContext(&q.ctx);
    q.mode = cull_backfaces ? QUERY_CULL : QUERY_CLOSEST;
    q.rt = rt;
    struct RTCRayHit rh;
    init_ray(&rh.ray, org, dir, tnear, tfar);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rt->scene, &q.ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        hit->tri = LIE_NO_HIT;
        return 0;
    }
    hit->tri = rh.hit.primID;
    hit->t = rh.ray.tfar;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit_exact(rt, org, dir, hit);
    return 1;
}

/* A packet of n <= 8 rays (lanes past n invalid), ray k with id k, over
 * [tnear[k], tfar[k]] (NULL: [0, inf)), and no hit yet. */
static void init_ray8(struct RTCRayHit8 *rh, int valid[8], int n, const lie_vec3 *org, const lie_vec3 *dir,
                      const float *tnear, const float *tfar)
{
    for (int k = 0; k < 8; k++) {
        int ok = k < n;
        valid[k] = ok ? -1 : 0;
        rh->ray.org_x[k] = ok ? org[k].x : 0.0f;
        rh->ray.org_y[k] = ok ? org[k].y : 0.0f;
        rh->ray.org_z[k] = ok ? org[k].z : 0.0f;
        rh->ray.tnear[k] = ok && tnear ? tnear[k] : 0.0f;
        rh->ray.dir_x[k] = ok ? dir[k].x : 0.0f;
        rh->ray.dir_y[k] = ok ? dir[k].y : 0.0f;
        rh->ray.dir_z[k] = ok ? dir[k].z : 1.0f;
        rh->ray.time[k] = 0.0f;
        rh->ray.tfar[k] = !tfar ? INFINITY : ok ? tfar[k] : 0.0f;
        rh->ray.mask[k] = 0xFFFFFFFFu;
        rh->ray.id[k] = (unsigned)k;
        rh->ray.flags[k] = 0;
        rh->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh->hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        rh->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
}

void lie_rt_intersect8(const lie_rt *rt, const lie_vec3 *org, const lie_vec3 *dir, int n, int cull_backfaces,
                       lie_hit *hits)
{
    query_ctx q;
    memset(&q, 0, sizeof q);
    rtcInitIntersectContext(&q.ctx);
    q.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    q.mode = cull_backfaces ? QUERY_CULL : QUERY_CLOSEST;
    q.rt = rt;
    struct RTCRayHit8 rh __attribute__((aligned(32)));
    int valid[8] __attribute__((aligned(32)));
    init_ray8(&rh, valid, n, org, dir, NULL, NULL);
    rtcIntersect8(valid, rt->scene, &q.ctx, &rh);
    for (int k = 0; k < n; k++) {
        if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
            hits[k].tri = LIE_NO_HIT;
            continue;
        }
        hits[k].tri = rh.hit.primID[k];
        hits[k].t = rh.ray.tfar[k];
        hits[k].u = rh.hit.u[k];
        hits[k].v = rh.hit.v[k];
        hit_exact(rt, org[k], dir[k], &hits[k]);
    }
}

int lie_rt_occluded(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    init_ray(&r, org, dir, tnear, tfar);
    rtcOccluded1(rt->scene, &ctx, &r);
    return r.tfar < 0.0f;
}

void lie_rt_occluded_batch(const lie_rt *rt, lie_ray_batch *b, lie_ray_mode mode)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (mode == LIE_RAYS_SINGLE) {
        for (int i = 0; i < b->n; i++) {
            struct RTCRay r;
            init_ray(&r, lie_v3(b->ox[i], b->oy[i], b->oz[i]), lie_v3(b->dx[i], b->dy[i], b->dz[i]),
                     b->tnear[i], b->tfar[i]);
            rtcOccluded1(rt->scene, &ctx, &r);
            b->occluded[i] = r.tfar < 0.0f;
        }
        return;
    }
    if (mode == LIE_RAYS_PACKET) {
        for (int base = 0; base < b->n; base += 8) {
            struct RTCRay8 r __attribute__((aligned(32)));
            int valid[8] __attribute__((aligned(32)));
            for (int k = 0; k < 8; k++) {
                int i = base + k;
                int ok = i < b->n;
                valid[k] = ok ? -1 : 0;
                r.org_x[k] = ok ? b->ox[i] : 0.0f;
                r.org_y[k] = ok ? b->oy[i] : 0.0f;
                r.org_z[k] = ok ? b->oz[i] : 0.0f;
                r.dir_x[k] = ok ? b->dx[i] : 0.0f;
                r.dir_y[k] = ok ? b->dy[i] : 0.0f;
                r.dir_z[k] = ok ? b->dz[i] : 1.0f;
                r.tnear[k] = ok ? b->tnear[i] : 0.0f;
                r.tfar[k] = ok ? b->tfar[i] : 0.0f;
                r.time[k] = 0.0f;
                r.mask[k] = 0xFFFFFFFFu;
                r.id[k] = (unsigned)k;
                r.flags[k] = 0;
            }
            rtcOccluded8(valid, rt->scene, &ctx, &r);
            for (int k = 0; k < 8 && base + k < b->n; k++)
                b->occluded[base + k] = r.tfar[k] < 0.0f;
        }
        return;
    }
    /* Stream: AoS rays in chunks on the stack. */
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    enum { CHUNK = 64 };
    struct RTCRay rays[CHUNK] __attribute__((aligned(16)));
    for (int base = 0; base < b->n; base += CHUNK) {
        int m = b->n - base < CHUNK ? b->n - base : CHUNK;
        for (int k = 0; k < m; k++) {
            int i = base + k;
            init_ray(&rays[k], lie_v3(b->ox[i], b->oy[i], b->oz[i]),
                     lie_v3(b->dx[i], b->dy[i], b->dz[i]), b->tnear[i], b->tfar[i]);
        }
        rtcOccluded1M(rt->scene, &ctx, rays, (unsigned)m, sizeof(struct RTCRay));
        for (int k = 0; k < m; k++)
            b->occluded[base + k] = rays[k].tfar < 0.0f;
    }
}

/* A segment query whose filter (intersect_filter) does the work. */
static void run_query(const lie_rt *rt, query_ctx *q, lie_vec3 org, lie_vec3 dir, float tnear, float tfar)
{
    rtcInitIntersectContext(&q->ctx);
    q->rt = rt;
    struct RTCRayHit rh;
    init_ray(&rh.ray, org, dir, tnear, tfar);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rt->scene, &q->ctx, &rh);
}

lie_status lie_rt_all_hits(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar,
                           const uint32_t *exclude, int n_exclude, uint32_t **out, size_t *n,
                           size_t *cap)
{
    query_ctx q = {.mode = QUERY_ALL, .exclude = exclude, .n_exclude = n_exclude, .out = out, .n = n, .cap = cap};
    run_query(rt, &q, org, dir, tnear, tfar);
    return q.nomem ? LIE_ERR_NOMEM : LIE_OK;
}

lie_status lie_rt_all_hits8(const lie_rt *rt, const lie_vec3 *org, const lie_vec3 *dir, const float *tnear,
                            const float *tfar, const uint32_t (*exclude)[2], const int *n_exclude, int n,
                            uint32_t **out, size_t *n_out, size_t *cap, unsigned *blocked)
{
    query_ctx q;
    memset(&q, 0, sizeof q);
    rtcInitIntersectContext(&q.ctx);
    q.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    q.mode = QUERY_ALL8;
    q.rt = rt;
    q.exclude8 = exclude;
    q.n_exclude8 = n_exclude;
    q.out = out;
    q.n = n_out;
    q.cap = cap;
    struct RTCRayHit8 rh __attribute__((aligned(32)));
    int valid[8] __attribute__((aligned(32)));
    init_ray8(&rh, valid, n, org, dir, tnear, tfar);
    rtcIntersect8(valid, rt->scene, &q.ctx, &rh);
    *blocked = q.blocked8;
    return q.nomem ? LIE_ERR_NOMEM : LIE_OK;
}

int lie_rt_any_hit(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar, const uint32_t *exclude,
                   int n_exclude)
{
    query_ctx q = {.mode = QUERY_ANY, .exclude = exclude, .n_exclude = n_exclude};
    run_query(rt, &q, org, dir, tnear, tfar);
    return q.found;
}

int lie_rt_transmits(const lie_rt *rt) { return rt->glass != NULL; }

int lie_rt_transmittance(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 1.0f;
    if (!rt->glass)
        return 0;
    glass_ctx q;
    rtcInitIntersectContext(&q.ctx);
    q.rt = rt;
    q.n = 0;
    q.overflow = 0;
    struct RTCRayHit rh;
    init_ray(&rh.ray, org, dir, tnear, tfar);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rt->glass, &q.ctx, &rh);
    if (q.overflow) { /* more layers than GLASS_HITS: as good as opaque */
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return 1;
    }
    /* in triangle order, whatever order traversal found them in, so that
     * the product has the same bits on every CPU */
    for (int i = 1; i < q.n; i++)
        for (int k = i; k > 0 && q.tri[k - 1] > q.tri[k]; k--) {
            uint32_t x = q.tri[k];
            q.tri[k] = q.tri[k - 1];
            q.tri[k - 1] = x;
        }
    for (int i = 0; i < q.n; i++) {
        double tuv[3] = {0.0, 1.0 / 3.0, 1.0 / 3.0}; /* a segment in the plane: the centre */
        solve_exact(rt, org, dir, q.tri[i], tuv);
        float t[3];
        lie_scene_transmittance(rt->s, q.tri[i], (float)tuv[1], (float)tuv[2], t);
        for (int k = 0; k < 3; k++)
            rgb[k] *= t[k];
    }
    return q.n > 0;
}

/* Box queries find shaft candidates (lib/lie/cull.c): transmissive
 * triangles are never blockers, so they are never candidates. */
typedef struct box_opaque {
    const lie_rt *rt;
    lie_rt_box_fn fn;
    void *ctx;
} box_opaque;

static void box_opaque_fn(void *p, uint32_t tri)
{
    const box_opaque *b = p;
    if (!is_clear(b->rt, tri))
        b->fn(b->ctx, tri);
}

typedef struct box_query {
    const lie_rt *rt;
    lie_box3 box;
    lie_rt_box_fn fn;
    void *ctx;
} box_query;

static bool on_point_query(struct RTCPointQueryFunctionArguments *args)
{
    box_query *q = args->userPtr;
    uint32_t t = args->primID;
    const lie_vec3 *P = &q->rt->s->tri_p[3 * (size_t)t];
    lie_vec3 lo = lie_v3_min(P[0], lie_v3_min(P[1], P[2]));
    lie_vec3 hi = lie_v3_max(P[0], lie_v3_max(P[1], P[2]));
    if (lo.x <= q->box.hi.x && hi.x >= q->box.lo.x && lo.y <= q->box.hi.y && hi.y >= q->box.lo.y &&
        lo.z <= q->box.hi.z && hi.z >= q->box.lo.z)
        q->fn(q->ctx, t);
    return false; /* the query radius never shrinks */
}

/* The hierarchy, built on first use by whichever worker asks first. */
static const lie_boxq *boxq_get(const lie_rt *crt)
{
    lie_rt *rt = (lie_rt *)crt; /* only the cache members change */
    lie_boxq *q = atomic_load_explicit(&rt->boxq, memory_order_acquire);
    if (q || atomic_load(&rt->boxq_failed))
        return q;
    pthread_mutex_lock(&rt->boxq_lock);
    q = atomic_load(&rt->boxq);
    if (!q && !atomic_load(&rt->boxq_failed)) {
        if (lie_boxq_build(rt->s->tri_p, rt->s->n_tris, &q) == LIE_OK)
            atomic_store_explicit(&rt->boxq, q, memory_order_release);
        else
            atomic_store(&rt->boxq_failed, 1);
    }
    pthread_mutex_unlock(&rt->boxq_lock);
    return q;
}

void lie_rt_box_query(const lie_rt *rt, lie_box3 box, lie_rt_box_fn fn, void *ctx)
{
    box_opaque op = {rt, fn, ctx};
    if (rt->tri_clear) {
        fn = box_opaque_fn;
        ctx = &op;
    }
    const lie_boxq *bq = boxq_get(rt);
    if (bq) {
        lie_boxq_query(bq, box, fn, ctx);
        return;
    }
    /* Embree's point query visits every primitive whose bounds meet a
     * sphere; the sphere around the box is a superset, the callback keeps
     * the triangles whose bounds meet the box itself. */
    box_query q = {rt, box, fn, ctx};
    lie_vec3 c = lie_v3_scale(lie_v3_add(box.lo, box.hi), 0.5f);
    struct RTCPointQuery pq __attribute__((aligned(16)));
    pq.x = c.x;
    pq.y = c.y;
    pq.z = c.z;
    pq.time = 0.0f;
    pq.radius = 0.5f * lie_v3_len(lie_v3_sub(box.hi, box.lo)) * 1.0001f + 1e-6f;
    struct RTCPointQueryContext pctx;
    rtcInitPointQueryContext(&pctx);
    rtcPointQuery(rt->scene, &pq, &pctx, on_point_query, &q);
}

int lie_shadow_segment(lie_vec3 p, lie_vec3 ng, lie_vec3 q, lie_vec3 *org, lie_vec3 *dir,
                       float *tnear, float *tfar)
{
    float eps = lie_ray_eps(p);
    lie_vec3 o = lie_ray_origin(p, ng, eps);
    lie_vec3 d = lie_v3_sub(q, o);
    float len = lie_v3_len(d);
    if (!(len > 2.0f * eps))
        return 0;
    *org = o;
    *dir = lie_v3_scale(d, 1.0f / len);
    *tnear = 0.0f;
    *tfar = lie_ray_end(len, eps);
    return 1;
}
