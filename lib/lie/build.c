/* Building local illumination environments (§4.1, §4.1.1, §4.3.2).
 *
 * One unit = (triangle, emitter).  A unit is built by a depth-first walk of
 * its patch tree: classify the patch–emitter pair, and split a partial patch
 * whose list is longer than max_blockers while the patch is larger than
 * min_patch.  Units are built in parallel into per-triangle buffers and
 * concatenated in unit order, so the result never depends on the schedule. */
#include "lie/lie.h"
#include "lie/shaft.h"

#include <stdlib.h>
#include <string.h>

const char *lie_class_name(lie_class c)
{
    static const char *const names[LIE_CLASS_COUNT] = {"unlit",   "visible", "occluded", "partial",
                                                       "complex", "split",   "none"};
    return (unsigned)c < LIE_CLASS_COUNT ? names[c] : "invalid";
}

lie_build_params lie_build_params_default(void)
{
    lie_build_params p;
    memset(&p, 0, sizeof p);
    p.samples = LIE_SAMPLES_DEFAULT;
    p.max_samples = LIE_MAX_SAMPLES_DEFAULT;
    p.max_blockers = LIE_MAX_BLOCKERS_DEFAULT;
    p.complex_cap = LIE_COMPLEX_CAP_DEFAULT;
    p.min_patch = LIE_MIN_PATCH_DEFAULT;
    p.mode = LIE_BLOCKERS_SAMPLED;
    return p;
}

lie_status lie_build_params_check(const lie_build_params *p, lie_error *err)
{
    if (p->samples < 1 || p->samples > (1u << 20))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "samples must be in 1..%u", 1u << 20);
    if (p->max_samples < p->samples || p->max_samples > (1u << 24))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "max-samples must be in samples..%u", 1u << 24);
    if (p->max_blockers > (1u << 20) || p->complex_cap > (1u << 24))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "max-blockers or complex-cap too large");
    if (!(p->min_patch > 0.0f) || !(p->min_patch <= 1.0f))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "min-patch must be in (0, 1]");
    if (p->mode != LIE_BLOCKERS_SAMPLED && p->mode != LIE_BLOCKERS_CONSERVATIVE)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "unknown blocker mode");
    return LIE_OK;
}

/* ---- per-unit output and per-worker scratch ----------------------------- */

typedef struct unit_buf {
    uint32_t *roots;      /* per emitter: the unit's root, local index */
    lie_pnode *nodes;
    uint32_t n_nodes, cap_nodes;
    uint32_t *pool;
    uint32_t n_pool, cap_pool;
    int copied;           /* update: every unit is copied whole from the old env at
                             assembly; nothing is held here but the sizes */
} unit_buf;

typedef struct worker {
    uint32_t *hits;      /* all-hits results of a pair, each triangle once */
    size_t n_hits, cap_hits;
    uint32_t *stamp;     /* per triangle: the pair that last added it to hits */
    uint32_t stamp_id;
    uint32_t *cand;      /* conservative candidates */
    size_t n_cand, cap_cand;
    lie_vec3 *hull;      /* conservative hull points */
    int cap_hull;
    lie_build_stats st;
    int nomem;
} worker;

typedef struct build_ctx {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_build_params *p;
    float min_area;       /* absolute smallest patch area that may still split */
    float ray_far;        /* towards directional emitters */
    const lie_env *old;   /* rebuild: units not in the mask are copied from here */
    const int32_t *old_unit;  /* update: per unit, the old unit to copy or update, or -1 to
                                 build afresh (NULL: build everything) */
    const uint8_t *node_flags; /* update: per old node, 1 = recompute (NULL: none) */
    const uint8_t *tri_mask;   /* build only these triangles (NULL: all) */
    uint64_t unit_lo, unit_hi; /* build only units [unit_lo, unit_hi) ... */
    uint32_t tri_lo;           /* ... of triangles tri_lo + item (out[item]) */
    unit_buf *out;        /* per triangle: its units, in emitter order, each contiguous */
    worker *workers;
    /* update: flagged old nodes already recomputed in parallel (see
     * precompute_flagged); memo_of[old node] indexes memo, or -1 */
    int32_t *memo_of;
    struct memo_entry *memo;
    int32_t *memo_new;    /* open-addressing table of the memo entries of new nodes */
    size_t memo_new_mask;
    double *halton;       /* radical inverses in bases 2, 3, 5, 7 of 0..n_halton-1 */
    uint32_t n_halton;
} build_ctx;

/* A recomputed pair, waiting for build_node to take it. */
#define MEMO_NO_OLD UINT32_MAX

typedef struct memo_entry {
    uint32_t old;         /* the old node, or MEMO_NO_OLD for a node new in this update */
    uint32_t tri;
    lie_patch_path path;
    int e;
    lie_class cls;
    uint32_t quality;
    uint32_t n_list;
    uint32_t *list;
} memo_entry;

static uint64_t memo_key(uint32_t tri, lie_patch_path path, int e)
{
    return lie_hash_u64x4(tri, path.digits, (uint64_t)path.depth, (uint64_t)e);
}

/* The memo entry of a node new in this update (no old node), or -1. */
static int32_t memo_find_new(const build_ctx *c, uint32_t tri, lie_patch_path path, int e)
{
    if (!c->memo_new)
        return -1;
    for (size_t h = memo_key(tri, path, e) & c->memo_new_mask;; h = (h + 1) & c->memo_new_mask) {
        int32_t i = c->memo_new[h];
        if (i < 0)
            return -1;
        const memo_entry *m = &c->memo[i];
        if (m->tri == tri && m->e == e && m->path.digits == path.digits && m->path.depth == path.depth)
            return i;
    }
}

static int push_node(unit_buf *u, worker *w)
{
    if (u->n_nodes == u->cap_nodes) {
        uint32_t nc = u->cap_nodes ? 2 * u->cap_nodes : 8;
        lie_pnode *nn = realloc(u->nodes, sizeof *nn * nc);
        if (!nn) {
            w->nomem = 1;
            return -1;
        }
        u->nodes = nn;
        u->cap_nodes = nc;
    }
    memset(&u->nodes[u->n_nodes], 0, sizeof *u->nodes);
    return (int)u->n_nodes++;
}

static int push_list(unit_buf *u, worker *w, const uint32_t *list, uint32_t n)
{
    if (u->n_pool + n > u->cap_pool) {
        uint32_t nc = u->cap_pool ? u->cap_pool : 16;
        while (nc < u->n_pool + n)
            nc *= 2;
        uint32_t *np = realloc(u->pool, sizeof *np * nc);
        if (!np) {
            w->nomem = 1;
            return 0;
        }
        u->pool = np;
        u->cap_pool = nc;
    }
    memcpy(u->pool + u->n_pool, list, sizeof *list * n);
    u->n_pool += n;
    return 1;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

static size_t sort_unique(uint32_t *v, size_t n)
{
    if (n < 2)
        return n;
    if (n <= 32) { /* the usual blocker list: insertion sort beats qsort's calls */
        for (size_t i = 1; i < n; i++) {
            uint32_t x = v[i];
            size_t j = i;
            for (; j > 0 && v[j - 1] > x; j--)
                v[j] = v[j - 1];
            v[j] = x;
        }
    } else {
        /* candidate lists run to thousands: byte-wise radix passes,
         * skipping a byte every key shares (the top ones, mostly) */
        uint32_t *tmp = malloc(n * sizeof *tmp);
        if (!tmp) {
            qsort(v, n, sizeof *v, cmp_u32);
        } else {
            uint32_t *src = v, *dst = tmp;
            for (int shift = 0; shift < 32; shift += 8) {
                size_t count[257] = {0};
                for (size_t i = 0; i < n; i++)
                    count[((src[i] >> shift) & 0xFFu) + 1]++;
                if (count[((src[0] >> shift) & 0xFFu) + 1] == n)
                    continue; /* one bucket: already in order by this byte */
                for (int b = 0; b < 256; b++)
                    count[b + 1] += count[b];
                for (size_t i = 0; i < n; i++)
                    dst[count[(src[i] >> shift) & 0xFFu]++] = src[i];
                uint32_t *x = src;
                src = dst;
                dst = x;
            }
            if (src != v)
                memcpy(v, src, n * sizeof *v);
            free(tmp);
        }
    }
    size_t m = 1;
    for (size_t i = 1; i < n; i++)
        if (v[i] != v[m - 1])
            v[m++] = v[i];
    return m;
}

static double radical_inverse(uint32_t base, uint32_t i)
{
    double inv = 1.0 / base, f = inv, r = 0.0;
    while (i) {
        r += (double)(i % base) * f;
        i /= base;
        f *= inv;
    }
    return r;
}

/* Sample i's coordinate `dim` (bases 2, 3, 5, 7), from the table when it
 * holds it (the same values: the table is filled by radical_inverse). */
static const uint32_t HALTON_BASE[4] = {2, 3, 5, 7};
#define HALTON_TABLE_MAX 4096u

static double halton(const build_ctx *c, int dim, uint32_t i)
{
    return i < c->n_halton ? c->halton[(size_t)dim * c->n_halton + i] : radical_inverse(HALTON_BASE[dim], i);
}

static float frac_shift(double x, float shift)
{
    double v = x + shift;
    v -= floor(v);
    return (float)(v < 1.0 ? v : 0.0);
}

/* ---- which pairs cannot interact -------------------------------------- */

/* A pair is unlit when no point of the patch can receive light from any
 * point of the emitter with a non-zero geometric term — exactly the pairs
 * whose every shadow sample the renderer would weight 0. */
static int pair_unlit(const build_ctx *c, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    const lie_scene *s = c->s;
    const lie_emitter *em = &s->emitters[e];
    lie_vec3 ng = s->tri_ng[tri];
    if (s->tri_area[tri] <= 0.0f)
        return 1;
    if (em->type == LIE_EMITTER_AREA) {
        if (tri >= em->first_tri && tri < em->first_tri + em->n_tris)
            return 1; /* an emitter does not light itself */
        /* emitter wholly behind (or in) the patch's plane */
        int front = 0, back = 0;
        for (uint32_t k = 0; k < em->n_tris && !(front && back); k++) {
            const lie_vec3 *E = &s->tri_p[3 * (size_t)(em->first_tri + k)];
            for (int j = 0; j < 3; j++) {
                float d = lie_v3_dot(ng, lie_v3_sub(E[j], V[0]));
                front |= d > 0.0f;
                back |= d < 0.0f;
            }
        }
        if (!front && (!two_sided || !back))
            return 1;
        /* patch wholly behind every triangle of a one-sided emitter */
        if (!em->double_sided) {
            for (uint32_t k = 0; k < em->n_tris; k++) {
                uint32_t g = em->first_tri + k;
                const lie_vec3 *E = &s->tri_p[3 * (size_t)g];
                lie_vec3 ne = s->tri_ng[g];
                float margin = 4e-4f * lie_maxf(lie_v3_maxabs(V[0]), 1.0f);
                for (int j = 0; j < 3; j++)
                    if (lie_v3_dot(ne, lie_v3_sub(V[j], E[0])) > -margin)
                        return 0;
            }
            return 1;
        }
        return 0;
    }
    if (em->type == LIE_EMITTER_POINT) {
        float d = lie_v3_dot(ng, lie_v3_sub(em->position, V[0]));
        return two_sided ? d == 0.0f : d <= 0.0f;
    }
    float d = -lie_v3_dot(ng, em->direction);
    return two_sided ? d == 0.0f : d <= 0.0f;
}

/* ---- conservative blocker lists (§4.1.2, shaft culling) ------------------ */

static void collect_candidate(void *ctx, uint32_t tri)
{
    worker *w = ctx;
    if (w->n_cand == w->cap_cand) {
        size_t nc = w->cap_cand ? 2 * w->cap_cand : 64;
        uint32_t *nb = realloc(w->cand, nc * sizeof *nb);
        if (!nb) {
            w->nomem = 1;
            return;
        }
        w->cand = nb;
        w->cap_cand = nc;
    }
    w->cand[w->n_cand++] = tri;
}

static float v3_axis(lie_vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

/* Candidates for the triangles that meet the convex hull of hull[0..nh)
 * (grown by tol when tol > 0) into w->cand, sorted and unique: Embree box
 * queries over the hull cut into slabs along its longest axis.  A slab's
 * box bounds the hull's part in it: the hull's points inside, and where
 * the segments between two points cross the slab's planes (the vertices of
 * a convex hull cut by a plane lie on such segments).  A long oblique
 * shaft so stops dragging in everything under its bounding box: a
 * terrain patch's shaft to a ceiling light touched thousands of ground
 * triangles.  Every triangle meeting the hull is among the candidates. */
#define SHAFT_SLABS 4

static void shaft_candidates(const build_ctx *c, worker *w, const lie_vec3 *hull, int nh, float tol)
{
    lie_box3 all = lie_box3_empty();
    for (int i = 0; i < nh; i++)
        lie_box3_grow(&all, hull[i]);
    float grow = lie_maxf(tol, 0.0f) + 1e-6f * lie_rt_scale(c->rt);
    w->n_cand = 0;
    int a = 0;
    lie_vec3 ext = lie_v3_sub(all.hi, all.lo);
    if (ext.y > v3_axis(ext, a))
        a = 1;
    if (ext.z > v3_axis(ext, a))
        a = 2;
    float lo = v3_axis(all.lo, a), hi = v3_axis(all.hi, a), width = (hi - lo) / (float)SHAFT_SLABS;
    lie_box3 slab[SHAFT_SLABS];
    int n_slabs = 1;
    if (nh <= 64 && width > 0.0f && isfinite(width)) {
        n_slabs = SHAFT_SLABS;
        for (int k = 0; k < n_slabs; k++)
            slab[k] = lie_box3_empty();
        for (int i = 0; i < nh; i++) {
            float f = (v3_axis(hull[i], a) - lo) / width; /* NaN falls in slab 0, never through a cast */
            int k = f >= 1.0f ? (f < (float)n_slabs ? (int)f : n_slabs - 1) : 0;
            lie_box3_grow(&slab[k], hull[i]);
        }
        for (int i = 0; i < nh; i++)
            for (int j = i + 1; j < nh; j++) {
                float pa = v3_axis(hull[i], a), pb = v3_axis(hull[j], a);
                if (pa == pb)
                    continue;
                for (int k = 1; k < n_slabs; k++) {
                    float y = lo + (float)k * width;
                    if ((y - pa) * (y - pb) > 0.0f)
                        continue;
                    float t = (y - pa) / (pb - pa);
                    lie_vec3 x = lie_v3_add(hull[i], lie_v3_scale(lie_v3_sub(hull[j], hull[i]), t));
                    lie_box3_grow(&slab[k - 1], x);
                    lie_box3_grow(&slab[k], x);
                }
            }
        /* rounding of the crossing points: widen by their size's epsilon */
        grow += 1e-5f * lie_maxf(lie_v3_maxabs(all.lo), lie_v3_maxabs(all.hi));
    } else {
        slab[0] = all;
    }
    for (int k = 0; k < n_slabs; k++) {
        if (lie_box3_is_empty(&slab[k]))
            continue;
        lie_box3 b = slab[k];
        b.lo = lie_v3_sub(b.lo, lie_v3(grow, grow, grow));
        b.hi = lie_v3_add(b.hi, lie_v3(grow, grow, grow));
        lie_rt_box_query(c->rt, b, collect_candidate, w);
    }
    w->n_cand = sort_unique(w->cand, w->n_cand);
}

float lie_ray_far(const lie_scene *s)
{
    lie_vec3 ext = lie_box3_is_empty(&s->bounds) ? lie_v3(1, 1, 1) : lie_v3_sub(s->bounds.hi, s->bounds.lo);
    float scale = fmaxf(1.0f, fmaxf(ext.x, fmaxf(ext.y, ext.z)));
    return 4.0f * scale + 4.0f * lie_v3_len(ext);
}

float lie_pair_eps(const lie_scene *s, uint32_t tri)
{
    const lie_vec3 *P = &s->tri_p[3 * (size_t)tri];
    float mag = 0.0f;
    for (int k = 0; k < 3; k++)
        mag = fmaxf(mag, fmaxf(fabsf(P[k].x), fmaxf(fabsf(P[k].y), fabsf(P[k].z))));
    /* the renderer lifts shadow rays by 1e-4 * max(1, |p|); this bounds it on the triangle */
    return 1.0001e-4f * fmaxf(1.0f, mag);
}

int lie_pair_hull_cap(const lie_scene *s, int e)
{
    const lie_emitter *em = &s->emitters[e];
    return 9 + (em->type == LIE_EMITTER_AREA ? (em->n_hull ? em->n_hull : 3 * (int)em->n_tris) : 3);
}

int lie_pair_hull_points(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int e, lie_vec3 *out)
{
    const lie_emitter *em = &s->emitters[e];
    int two_sided = lie_scene_material(s, s->tri_material[tri])->double_sided != 0;
    float eps = lie_pair_eps(s, tri);
    lie_vec3 ng = s->tri_ng[tri];
    int n = 0;
    for (int k = 0; k < 3; k++) {
        out[n++] = V[k];
        out[n++] = lie_v3_add(V[k], lie_v3_scale(ng, eps));
        if (two_sided)
            out[n++] = lie_v3_sub(V[k], lie_v3_scale(ng, eps));
    }
    if (em->type == LIE_EMITTER_AREA && em->n_hull) {
        memcpy(&out[n], em->hull, sizeof(lie_vec3) * (size_t)em->n_hull); /* a box around many triangles */
        n += em->n_hull;
    } else if (em->type == LIE_EMITTER_AREA) {
        memcpy(&out[n], &s->tri_p[3 * (size_t)em->first_tri], sizeof(lie_vec3) * 3 * em->n_tris);
        n += 3 * (int)em->n_tris;
    } else if (em->type == LIE_EMITTER_POINT) {
        out[n++] = em->position;
    } else {
        float far = lie_ray_far(s);
        for (int k = 0; k < 3; k++)
            out[n++] = lie_v3_add(V[k], lie_v3_scale(em->direction, -far));
    }
    return n;
}

/* The separating-axis prefilter for the hull in w->hull. */
static void pair_sat(const build_ctx *c, const worker *w, int nh, uint32_t tri, int two_sided, int e, float tol,
                     lie_sat *sat)
{
    const lie_emitter *em = &c->s->emitters[e];
    const lie_vec3 *ne = em->type == LIE_EMITTER_AREA ? &c->s->tri_ng[em->first_tri] : NULL;
    lie_sat_init(sat, w->hull, nh, two_sided ? 9 : 6, c->s->tri_ng[tri], ne, tol);
}

/* The pair's hull into w->hull (see lie_pair_hull_points). */
static int pair_hull(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                     float eps)
{
    (void)two_sided;
    (void)eps;
    int need = lie_pair_hull_cap(c->s, e);
    if (need > w->cap_hull) {
        lie_vec3 *nh = realloc(w->hull, sizeof *nh * (size_t)need);
        if (!nh) {
            w->nomem = 1;
            return 0;
        }
        w->hull = nh;
        w->cap_hull = need;
    }
    return lie_pair_hull_points(c->s, tri, V, e, w->hull);
}

/* Every triangle other than the patch's own and the emitter's that enters
 * the pair's shaft, into w->cand (sorted, unique); returns how many.  Only
 * these can block a segment of the pair.  Triangles that merely touch the
 * shaft's boundary — a wall meeting the floor at the patch's edge, the
 * floor's neighbouring triangle — are left out: the hull's corners are
 * pulled in by a thousandth and contact does not count. */
static size_t shaft_triangles(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided,
                              int e, float eps)
{
    const lie_scene *s = c->s;
    lie_vec3 ctr = lie_v3_scale(lie_v3_add(V[0], lie_v3_add(V[1], V[2])), 1.0f / 3.0f);
    lie_vec3 W[3];
    for (int k = 0; k < 3; k++)
        W[k] = lie_v3_add(ctr, lie_v3_scale(lie_v3_sub(V[k], ctr), 0.999f));
    int nh = pair_hull(c, w, tri, W, two_sided, e, eps);
    if (!nh)
        return 0;
    int n_patch = two_sided ? 9 : 6;
    lie_vec3 ectr = lie_v3(0, 0, 0);
    for (int i = n_patch; i < nh; i++)
        ectr = lie_v3_add(ectr, w->hull[i]);
    ectr = lie_v3_scale(ectr, 1.0f / (float)(nh - n_patch));
    for (int i = n_patch; i < nh; i++)
        w->hull[i] = lie_v3_add(ectr, lie_v3_scale(lie_v3_sub(w->hull[i], ectr), 0.999f));
    float tol = -1e-7f * lie_rt_scale(c->rt); /* negative: contact is not entry */
    shaft_candidates(c, w, w->hull, nh, tol);
    lie_sat sat;
    pair_sat(c, w, nh, tri, two_sided, e, 0.0f, &sat);
    size_t m = 0;
    for (size_t i = 0; i < w->n_cand; i++) {
        uint32_t t = w->cand[i];
        if (t == tri || s->tri_emitter[t] == e || !(s->tri_area[t] > 0.0f))
            continue;
        if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]))
            continue;
        if (lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol))
            w->cand[m++] = t;
    }
    w->n_cand = sort_unique(w->cand, m);
    return w->n_cand;
}

/* Sampling finds a blocker's triangles where segments happened to hit it;
 * the rest of the same object inside the shaft blocks other rays.  Add every
 * triangle of an instance already in the list that meets the shaft. */
#define EXPAND_SCAN_MAX 256 /* instances up to this many triangles are scanned whole */

static void expand_instances(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided,
                             int e, float eps)
{
    const lie_scene *s = c->s;
    size_t n0 = w->n_hits;
    if (n0 == 0)
        return;
    int nh = pair_hull(c, w, tri, V, two_sided, e, eps);
    if (!nh)
        return;
    float tol = 1e-6f * lie_rt_scale(c->rt);
    lie_sat sat;
    pair_sat(c, w, nh, tri, two_sided, e, tol, &sat);
    /* A large instance (a terrain, a building exported as one mesh) is not
     * scanned whole: its candidates come from one Embree box query over the
     * shaft's bounds, shared by every large instance of the list. */
    int have_box = 0;
    uint32_t last = UINT32_MAX;
    for (size_t i = 0; i < n0; i++) {
        uint32_t inst = s->tri_instance[w->hits[i]];
        if (inst == last)
            continue; /* hits are sorted, so an instance's triangles are together */
        last = inst;
        const lie_instance *in = &s->instances[inst];
        int scan = in->n_tris <= EXPAND_SCAN_MAX;
        if (!scan && !have_box) {
            shaft_candidates(c, w, w->hull, nh, tol);
            if (w->nomem)
                return;
            have_box = 1;
        }
        size_t n_try = scan ? in->n_tris : w->n_cand;
        for (size_t k = 0; k < n_try; k++) {
            uint32_t t = scan ? in->first_tri + (uint32_t)k : w->cand[k];
            if (!scan && s->tri_instance[t] != inst)
                continue;
            if (t == tri || s->tri_emitter[t] == e || !(s->tri_area[t] > 0.0f))
                continue;
            if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]) ||
                !lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol))
                continue;
            if (w->n_hits == w->cap_hits) {
                size_t ncap = 2 * w->cap_hits + 16;
                uint32_t *nb = realloc(w->hits, ncap * sizeof *nb);
                if (!nb) {
                    w->nomem = 1;
                    return;
                }
                w->hits = nb;
                w->cap_hits = ncap;
            }
            w->hits[w->n_hits++] = t;
        }
    }
    w->n_hits = sort_unique(w->hits, w->n_hits);
}

/* ---- sampled blocker lists (§4.1, §4.3.2) ------------------------------ */

/* A patch large enough to split (§4.1.1): the one size test of splits()
 * and of sample_pair's early stop, which must agree. */
static int patch_may_split(const build_ctx *c, uint32_t tri, lie_patch_path path)
{
    float area = c->s->tri_area[tri] / (float)(1u << (2 * (path.depth < 15 ? path.depth : 15)));
    return area > c->min_area && path.depth < LIE_PATCH_MAX_DEPTH;
}

/* The pair's sampling: segment i runs from a patch point (Halton bases 2,
 * 3) to an emitter point (bases 5, 7), each shifted by a hash of the pair. */
typedef struct pair_sampler {
    const build_ctx *c;
    uint32_t tri;
    const lie_vec3 *V;
    int two_sided, e;
    float sp1, sp2, se1, se2;
} pair_sampler;

/* Segment i, if it counts (it leaves the patch's lit side and, for a
 * one-sided emitter, reaches its front); ex[] gets the triangles it must
 * not report (the patch's own and the emitter point's), *n_ex their count. */
static int pair_segment(const pair_sampler *ps, uint32_t i, lie_vec3 *org, lie_vec3 *dir, float *tnear, float *tfar,
                        uint32_t ex[2], int *n_ex)
{
    const build_ctx *c = ps->c;
    const lie_scene *s = c->s;
    const lie_emitter *em = &s->emitters[ps->e];
    const lie_vec3 *V = ps->V;
    float b1, b2;
    lie_sample_triangle(frac_shift(halton(c, 0, i), ps->sp1), frac_shift(halton(c, 1, i), ps->sp2), &b1, &b2);
    float b0 = 1.0f - b1 - b2;
    lie_vec3 p = lie_v3_add(lie_v3_add(lie_v3_scale(V[0], b0), lie_v3_scale(V[1], b1)), lie_v3_scale(V[2], b2));
    lie_vec3 q, ne = lie_v3(0, 0, 0);
    uint32_t target = LIE_NO_HIT;
    if (em->type == LIE_EMITTER_AREA) {
        float eb1, eb2;
        target = lie_emitter_point(s, ps->e, frac_shift(halton(c, 2, i), ps->se1),
                                   frac_shift(halton(c, 3, i), ps->se2), &q, &ne, &eb1, &eb2);
    } else if (em->type == LIE_EMITTER_POINT) {
        q = em->position;
    } else {
        q = lie_v3_add(p, lie_v3_scale(em->direction, -c->ray_far));
    }
    lie_vec3 d = lie_v3_sub(q, p);
    lie_vec3 ng = s->tri_ng[ps->tri];
    float cg = lie_v3_dot(ng, d);
    if (!(cg > 0.0f) && !(ps->two_sided && cg < 0.0f))
        return 0;
    if (em->type == LIE_EMITTER_AREA && !em->double_sided && !(lie_v3_dot(ne, d) < 0.0f))
        return 0;
    lie_vec3 side = cg > 0.0f ? ng : lie_v3_scale(ng, -1.0f);
    if (!lie_shadow_segment(p, side, q, org, dir, tnear, tfar))
        return 0;
    ex[0] = ps->tri;
    ex[1] = target;
    *n_ex = target == LIE_NO_HIT ? 1 : 2;
    return 1;
}

/* After the first round found every segment blocked: are all the segments
 * up to max_samples blocked too?  Any-hit queries, stopping at the first
 * segment that is not. */
static int all_blocked_to_max(const pair_sampler *ps, uint32_t from, worker *w)
{
    const build_ctx *c = ps->c;
    for (uint32_t i = from; i < c->p->max_samples; i++) {
        lie_vec3 org, dir;
        float tnear, tfar;
        uint32_t ex[2];
        int n_ex;
        if (!pair_segment(ps, i, &org, &dir, &tnear, &tfar, ex, &n_ex))
            continue;
        w->st.segments++;
        if (!lie_rt_any_hit(c->rt, org, dir, tnear, tfar, ex, n_ex))
            return 0;
    }
    return 1;
}

/* Classify one patch–emitter pair by sampling segments.  Leaves the sorted
 * unique blocker list in w->hits[0..*n_list).
 *
 * Rounds of segments, doubling while a round finds a blocker the earlier
 * ones missed (§4.3.2), up to max_samples.  Sampling stops early when the
 * outcome can no longer change; only the informational quality and count
 * of such nodes then differ from sampling on (formats/lie-cache.md):
 * - the first round blocked every segment: any-hit queries for the rest
 *   either find them all blocked (occluded, quality = max_samples) or
 *   meet a free one, and the rounds go on as if the probe had not been;
 * - the pair is partial (some segment blocked, some not) and its list is
 *   already past what decides the node: past max_blockers where it will
 *   split (the emitter cannot put more than complex_cap of its own
 *   triangles in a list), past complex_cap where it cannot split; the
 *   list is not stored then, so it is not expanded to whole instances. */
static lie_class sample_pair(const build_ctx *c, worker *w, uint32_t tri, lie_patch_path path,
                             const lie_vec3 V[3], int two_sided, int e, float eps, uint32_t *quality,
                             size_t *n_list)
{
    const lie_scene *s = c->s;
    const lie_emitter *em = &s->emitters[e];
    uint64_t h = lie_hash_u64x4(tri, path.digits, (uint64_t)path.depth, (uint64_t)e);
    uint64_t h2 = lie_hash_u64x4(h, 0x656d6974ull, 0, 0);
    const pair_sampler ps = {c,
                             tri,
                             V,
                             two_sided,
                             e,
                             lie_hash_to_unit(h),
                             lie_hash_to_unit(h << 24),
                             lie_hash_to_unit(h2),
                             lie_hash_to_unit(h2 << 24)};
    const int can_split = patch_may_split(c, tri, path);
    /* the list length past which this node's class is settled, once partial */
    const size_t settled = can_split ? (em->n_tris <= c->p->complex_cap ? c->p->max_blockers : SIZE_MAX)
                                     : c->p->complex_cap;
    uint32_t total = 0, round_n = c->p->samples;
    uint64_t valid = 0, blocked = 0;
    size_t known = 0; /* distinct blockers after the previous round */
    int forced = 0;
    w->n_hits = 0;
    /* hits are kept unique as they come (a segment through an occluder
     * hits it hundreds of times a pair), by stamping triangles */
    if (!w->stamp) {
        w->stamp = calloc((size_t)s->n_tris + 1, sizeof *w->stamp);
        if (!w->stamp) {
            w->nomem = 1;
            return LIE_CLASS_VISIBLE;
        }
    }
    if (++w->stamp_id == 0) {
        memset(w->stamp, 0, sizeof *w->stamp * ((size_t)s->n_tris + 1));
        w->stamp_id = 1;
    }
    const uint32_t id = w->stamp_id;
    for (;;) {
        for (uint32_t i = total; i < total + round_n; i++) {
            lie_vec3 org, dir;
            float tnear, tfar;
            uint32_t ex[2];
            int n_ex;
            if (!pair_segment(&ps, i, &org, &dir, &tnear, &tfar, ex, &n_ex))
                continue;
            size_t before = w->n_hits;
            if (lie_rt_all_hits(c->rt, org, dir, tnear, tfar, ex, n_ex, &w->hits, &w->n_hits, &w->cap_hits) !=
                LIE_OK) {
                w->nomem = 1;
                return LIE_CLASS_VISIBLE;
            }
            valid++;
            blocked += w->n_hits > before;
            size_t k = before;
            for (size_t j = before; j < w->n_hits; j++) {
                uint32_t t = w->hits[j];
                if (t < s->n_tris && w->stamp[t] == id)
                    continue;
                if (t < s->n_tris)
                    w->stamp[t] = id;
                w->hits[k++] = t;
            }
            w->n_hits = k;
        }
        w->st.segments += round_n;
        total += round_n;
        w->n_hits = sort_unique(w->hits, w->n_hits);
        int found_new = w->n_hits > known;
        known = w->n_hits;
        if (total >= c->p->max_samples)
            break;
        if (blocked > 0 && blocked < valid && w->n_hits > settled) {
            *quality = total; /* partial, and the list already decides the node */
            *n_list = w->n_hits;
            return LIE_CLASS_PARTIAL;
        }
        if (total == c->p->samples && valid > 0 && blocked == valid && all_blocked_to_max(&ps, total, w)) {
            *quality = c->p->max_samples;
            *n_list = w->n_hits;
            return LIE_CLASS_OCCLUDED;
        }
        /* §4.3.2: keep doubling while a round finds a blocker the earlier
         * rounds missed */
        if (!found_new && w->n_hits > 0)
            break;
        if (!found_new && !forced) {
            /* Nothing found.  Only triangles in the shaft can block: none
             * means visible, proven; a few become the list, exact; many
             * mean sampling on to max_samples before calling it visible. */
            size_t n_shaft = shaft_triangles(c, w, tri, V, two_sided, e, eps);
            if (n_shaft == 0)
                break;
            if (n_shaft <= c->p->max_blockers) {
                *quality = total;
                *n_list = n_shaft;
                if (n_shaft > w->cap_hits) {
                    uint32_t *nb = realloc(w->hits, n_shaft * sizeof *nb);
                    if (!nb) {
                        w->nomem = 1;
                        return LIE_CLASS_VISIBLE;
                    }
                    w->hits = nb;
                    w->cap_hits = n_shaft;
                }
                memcpy(w->hits, w->cand, n_shaft * sizeof *w->hits);
                w->n_hits = n_shaft;
                return LIE_CLASS_PARTIAL;
            }
            forced = 1;
        }
        round_n = total;
        if (total + round_n > c->p->max_samples)
            round_n = c->p->max_samples - total;
    }
    if (blocked > 0 && blocked < valid)
        expand_instances(c, w, tri, V, two_sided, e, eps);
    *quality = total;
    *n_list = w->n_hits;
    if (valid == 0 || blocked == 0)
        return LIE_CLASS_VISIBLE;
    if (blocked == valid)
        return LIE_CLASS_OCCLUDED;
    return LIE_CLASS_PARTIAL;
}

static lie_class conservative_pair(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3],
                                   int two_sided, int e, float eps, const uint32_t *parent, size_t n_parent,
                                   size_t *n_list)
{
    const lie_scene *s = c->s;
    int nh = pair_hull(c, w, tri, V, two_sided, e, eps);
    w->n_hits = 0;
    *n_list = 0;
    if (!nh)
        return LIE_CLASS_VISIBLE;
    float tol = 1e-6f * lie_rt_scale(c->rt);
    const uint32_t *cand;
    size_t n_cand;
    if (parent) {
        /* a child's hull lies inside its parent's: only the parent's list can meet it */
        cand = parent;
        n_cand = n_parent;
    } else {
        shaft_candidates(c, w, w->hull, nh, tol);
        cand = w->cand;
        n_cand = w->n_cand;
    }
    lie_sat sat;
    pair_sat(c, w, nh, tri, two_sided, e, tol, &sat);
    for (size_t i = 0; i < n_cand; i++) {
        uint32_t t = cand[i];
        if (t == tri || !(s->tri_area[t] > 0.0f)) /* empty triangles block nothing */
            continue;
        if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]))
            continue;
        if (lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol)) {
            if (w->n_hits == w->cap_hits) {
                size_t ncap = w->cap_hits ? 2 * w->cap_hits : 64;
                uint32_t *nb = realloc(w->hits, ncap * sizeof *nb);
                if (!nb) {
                    w->nomem = 1;
                    return LIE_CLASS_VISIBLE;
                }
                w->hits = nb;
                w->cap_hits = ncap;
            }
            w->hits[w->n_hits++] = t;
        }
    }
    *n_list = w->n_hits;
    /* occlusion is never claimed: proving it needs more than a list */
    return w->n_hits ? LIE_CLASS_PARTIAL : LIE_CLASS_VISIBLE;
}

static lie_status assemble(lie_env *env, unit_buf *bufs, uint32_t tri_lo, uint32_t n_tris, int n_emitters,
                           const int32_t *old_unit, uint64_t unit_lo, uint64_t unit_hi);

/* ---- the patch tree of one unit ----------------------------------------- */

static void hist_add(lie_build_stats *st, uint32_t n)
{
    int b = 0;
    while (b < 17 && n > (1u << b))
        b++;
    st->list_hist[b]++;
}

/* §4.1.1: a patch whose list is too long is split while it is large.  But
 * a closed, double-sided emitter hides its far side behind its near side:
 * those blockers are the emitter's own triangles, and smaller patches keep
 * seeing about as many; when they alone pass the complex cap, splitting
 * cannot help and the pair is complex at once. */
static int splits(const build_ctx *c, uint32_t tri, lie_patch_path path, int e, lie_class cls, const uint32_t *list,
                  size_t n_list)
{
    const lie_scene *s = c->s;
    if (!(cls == LIE_CLASS_PARTIAL && n_list > c->p->max_blockers && patch_may_split(c, tri, path)))
        return 0;
    const lie_emitter *em = &s->emitters[e];
    size_t own = 0;
    for (size_t k = 0; em->type == LIE_EMITTER_AREA && k < n_list; k++)
        own += list[k] - em->first_tri < em->n_tris;
    return own <= c->p->complex_cap;
}

/* Build node `idx` (already pushed) for patch `path` of unit (tri, e). */
static void copy_node(const lie_env *old, uint32_t from, worker *w, unit_buf *u, uint32_t idx);

/* Build node `idx` for patch `path` of unit (tri, e).  In an update, `old`
 * is the old env's node for the same patch (or -1): when both old and new
 * split, children whose regions no edit touched are copied. */
static void build_node(const build_ctx *c, worker *w, unit_buf *u, uint32_t idx, uint32_t tri,
                       lie_patch_path path, int e, int two_sided, float eps, const uint32_t *parent,
                       size_t n_parent, int64_t old)
{
    if (old >= 0 && !(c->node_flags && c->node_flags[old])) {
        copy_node(c->old, (uint32_t)old, w, u, idx); /* no edit reached this patch's shaft */
        return;
    }
    const lie_scene *s = c->s;
    lie_vec3 V[3];
    lie_patch_world(path, &s->tri_p[3 * (size_t)tri], V);
    w->st.patches_per_depth[path.depth]++;
    lie_class cls;
    uint32_t quality = 0;
    size_t n_list = 0;
    int32_t mi = old >= 0 && c->memo_of ? c->memo_of[old] : memo_find_new(c, tri, path, e);
    if (mi >= 0) {
        /* computed already, in parallel with the other flagged nodes */
        const memo_entry *m = &c->memo[mi];
        cls = m->cls;
        quality = m->quality;
        n_list = m->n_list;
        if (n_list > w->cap_hits) {
            uint32_t *nb = realloc(w->hits, n_list * sizeof *nb);
            if (!nb) {
                w->nomem = 1;
                return;
            }
            w->hits = nb;
            w->cap_hits = n_list;
        }
        if (n_list)
            memcpy(w->hits, m->list, n_list * sizeof *w->hits);
    } else if (pair_unlit(c, tri, V, two_sided, e)) {
        cls = LIE_CLASS_UNLIT;
    } else if (c->p->mode == LIE_BLOCKERS_SAMPLED) {
        cls = sample_pair(c, w, tri, path, V, two_sided, e, eps, &quality, &n_list);
    } else {
        cls = conservative_pair(c, w, tri, V, two_sided, e, eps, parent, n_parent, &n_list);
    }
    if (w->nomem)
        return;
    if (splits(c, tri, path, e, cls, w->hits, n_list)) {
        /* §4.1.1: split a patch whose list is too long while it is large */
        uint32_t *keep = NULL;
        if (c->p->mode == LIE_BLOCKERS_CONSERVATIVE) {
            keep = malloc(sizeof *keep * n_list);
            if (!keep) {
                w->nomem = 1;
                return;
            }
            memcpy(keep, w->hits, sizeof *keep * n_list);
        }
        int first = push_node(u, w);
        for (int k = 1; k < 4 && first >= 0; k++)
            if (push_node(u, w) < 0)
                first = -1;
        if (first < 0) {
            free(keep);
            return;
        }
        u->nodes[idx].child = (uint32_t)first; /* unit-local; rebased on assembly */
        u->nodes[idx].cls = LIE_CLASS_SPLIT;
        u->nodes[idx].quality = quality;
        u->nodes[idx].count = (uint32_t)n_list;
        uint32_t old_child = old >= 0 ? c->old->nodes[old].child : 0;
        for (int k = 0; k < 4; k++)
            build_node(c, w, u, (uint32_t)first + (uint32_t)k, tri, lie_patch_child(path, k), e, two_sided, eps,
                       keep, n_list, old_child ? (int64_t)old_child + k : -1);
        free(keep);
        return;
    }
    lie_pnode *nd = &u->nodes[idx];
    nd->quality = quality;
    nd->count = (uint32_t)n_list;
    /* A list with an alpha-masked triangle goes to Embree as well: the
     * renderer's segment test knows nothing of holes. */
    int masked = 0;
    for (size_t k = 0; cls == LIE_CLASS_PARTIAL && k < n_list && !masked; k++)
        masked = lie_scene_material(s, s->tri_material[w->hits[k]])->alpha_mask;
    int complex = cls == LIE_CLASS_PARTIAL && (n_list > c->p->complex_cap || masked);
    w->st.pairs[complex ? LIE_CLASS_COMPLEX : cls]++;
    if (complex) {
        nd->cls = LIE_CLASS_COMPLEX; /* the renderer asks the whole scene */
        return;
    }
    nd->cls = cls;
    if (cls == LIE_CLASS_PARTIAL) {
        nd->list = u->n_pool;
        push_list(u, w, w->hits, (uint32_t)n_list);
        w->st.blocker_total += n_list;
        hist_add(&w->st, (uint32_t)n_list);
    }
}

/* Copy node `from` of the old env (and its subtree) into node `idx` of u,
 * in the order a build would have produced it. */
static void copy_node(const lie_env *old, uint32_t from, worker *w, unit_buf *u, uint32_t idx)
{
    lie_pnode x = old->nodes[from];
    if (x.child) {
        int first = push_node(u, w);
        for (int k = 1; k < 4 && first >= 0; k++)
            if (push_node(u, w) < 0)
                first = -1;
        if (first < 0)
            return;
        u->nodes[idx] = x;
        u->nodes[idx].child = (uint32_t)first;
        for (int k = 0; k < 4; k++)
            copy_node(old, x.child + (uint32_t)k, w, u, (uint32_t)first + (uint32_t)k);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        uint32_t list = u->n_pool;
        if (!push_list(u, w, old->pool + x.list, x.count))
            return;
        x.list = list;
    }
    u->nodes[idx] = x;
}

/* The nodes and pool entries of old node `from` and its subtree. */
static void subtree_size(const lie_env *old, uint32_t from, uint32_t *n_nodes, uint32_t *n_pool)
{
    const lie_pnode *x = &old->nodes[from];
    ++*n_nodes;
    if (x->child)
        for (uint32_t k = 0; k < 4; k++)
            subtree_size(old, x->child + k, n_nodes, n_pool);
    else if (x->cls == LIE_CLASS_PARTIAL)
        *n_pool += x->count;
}

/* An update's triangle whose every unit continues an old one that no edit
 * reached: it is copied at assembly, straight into the new arrays. */
static int copied_whole(const build_ctx *c, uint32_t tri, unit_buf *u)
{
    size_t ne = (size_t)c->s->n_emitters;
    if (!c->old_unit || c->tri_mask)
        return 0;
    for (size_t e = 0; e < ne; e++) {
        int32_t ou = c->old_unit[(size_t)tri * ne + e];
        if (ou < 0 || (c->node_flags && c->node_flags[c->old->root[ou]]))
            return 0;
    }
    for (size_t e = 0; e < ne; e++)
        subtree_size(c->old, c->old->root[c->old_unit[(size_t)tri * ne + e]], &u->n_nodes, &u->n_pool);
    u->copied = 1;
    return 1;
}

static void build_triangle(void *ctx, size_t item, int worker_id)
{
    build_ctx *c = ctx;
    worker *w = &c->workers[worker_id];
    uint32_t tri = c->tri_lo + (uint32_t)item;
    unit_buf *u = &c->out[item];
    const lie_scene *s = c->s;
    size_t ne = (size_t)s->n_emitters;
    if (copied_whole(c, tri, u))
        return;
    u->roots = malloc(sizeof *u->roots * (ne + 1));
    if (!u->roots) {
        w->nomem = 1;
        return;
    }
    int two_sided = lie_scene_material(s, s->tri_material[tri])->double_sided != 0;
    float eps = lie_pair_eps(s, tri);
    for (size_t e = 0; e < ne; e++) {
        size_t unit = (size_t)tri * ne + e;
        if (unit < c->unit_lo || unit >= c->unit_hi)
            continue; /* lie_env_build_range: another part's */
        int root = push_node(u, w);
        if (root < 0)
            return;
        u->roots[e] = (uint32_t)root;
        int64_t old = c->old_unit && c->old_unit[unit] >= 0 ? (int64_t)c->old->root[c->old_unit[unit]] : -1;
        if (c->tri_mask && !c->tri_mask[tri]) {
            u->nodes[root].cls = LIE_CLASS_NONE; /* outside the views: not built */
            w->st.pairs[LIE_CLASS_NONE]++;
            continue;
        }
        build_node(c, w, u, (uint32_t)root, tri, lie_patch_root(), (int)e, two_sided, eps, NULL, 0, old);
    }
}

static void workers_free(worker *ws, int n)
{
    for (int i = 0; ws && i < n; i++) {
        free(ws[i].hits);
        free(ws[i].stamp);
        free(ws[i].cand);
        free(ws[i].hull);
    }
    free(ws);
}

static void stats_merge(lie_build_stats *dst, const lie_build_stats *src)
{
    for (int k = 0; k < LIE_CLASS_COUNT; k++)
        dst->pairs[k] += src->pairs[k];
    for (int k = 0; k <= LIE_PATCH_MAX_DEPTH; k++)
        dst->patches_per_depth[k] += src->patches_per_depth[k];
    for (int k = 0; k < 18; k++)
        dst->list_hist[k] += src->list_hist[k];
    dst->segments += src->segments;
    dst->blocker_total += src->blocker_total;
}

void lie_build_stats_add(lie_build_stats *a, const lie_build_stats *b) { stats_merge(a, b); }

/* ---- update: flagged nodes recomputed in parallel ------------------------ */

/* An update's work sits in few units (a floor triangle's patch tree under a
 * moved object holds most of it), so parallelism over triangles leaves the
 * cores idle.  Before the build proper, the nodes build_node will compute
 * are computed in parallel, in waves by depth: wave 0 the flagged roots and
 * the roots of units built afresh, wave d+1 the children of wave d's nodes
 * that split (their flagged old children, or all four where there were
 * none).  These are exactly the nodes build_node computes (a sampled pair
 * depends only on its patch and emitter), so the result and the statistics
 * do not change; build_node takes each from the memo. */
typedef struct memo_state {
    build_ctx *c;
    size_t first, n;      /* this wave: memo[first, first + n) */
} memo_state;

static void memo_compute(void *ctx, size_t item, int worker_id)
{
    memo_state *ms = ctx;
    const build_ctx *c = ms->c;
    worker *w = &c->workers[worker_id];
    memo_entry *m = &c->memo[ms->first + item];
    const lie_scene *s = c->s;
    lie_vec3 V[3];
    lie_patch_world(m->path, &s->tri_p[3 * (size_t)m->tri], V);
    int two_sided = lie_scene_material(s, s->tri_material[m->tri])->double_sided != 0;
    size_t n_list = 0;
    m->quality = 0;
    if (pair_unlit(c, m->tri, V, two_sided, m->e))
        m->cls = LIE_CLASS_UNLIT;
    else
        m->cls = sample_pair(c, w, m->tri, m->path, V, two_sided, m->e, lie_pair_eps(s, m->tri), &m->quality,
                             &n_list);
    m->n_list = (uint32_t)n_list;
    m->list = NULL;
    if (n_list && !w->nomem) {
        m->list = malloc(n_list * sizeof *m->list);
        if (!m->list)
            w->nomem = 1;
        else
            memcpy(m->list, w->hits, n_list * sizeof *m->list);
    }
}

static int memo_push(build_ctx *c, size_t *n, size_t *cap, uint32_t old, uint32_t tri, lie_patch_path path, int e)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 256;
        memo_entry *nm = realloc(c->memo, nc * sizeof *nm);
        if (!nm)
            return 0;
        c->memo = nm;
        *cap = nc;
    }
    memo_entry *m = &c->memo[(*n)++];
    memset(m, 0, sizeof *m);
    m->old = old;
    m->tri = tri;
    m->path = path;
    m->e = e;
    if (old != MEMO_NO_OLD)
        c->memo_of[old] = (int32_t)(*n - 1);
    return 1;
}

/* Index the entries of new nodes for memo_find_new. */
static int memo_index_new(build_ctx *c, size_t n)
{
    size_t cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    c->memo_new = malloc(sizeof *c->memo_new * cap);
    if (!c->memo_new)
        return 0;
    for (size_t i = 0; i < cap; i++)
        c->memo_new[i] = -1;
    c->memo_new_mask = cap - 1;
    for (size_t i = 0; i < n; i++) {
        const memo_entry *m = &c->memo[i];
        if (m->old != MEMO_NO_OLD)
            continue;
        size_t h = memo_key(m->tri, m->path, m->e) & c->memo_new_mask;
        while (c->memo_new[h] >= 0)
            h = (h + 1) & c->memo_new_mask;
        c->memo_new[h] = (int32_t)i;
    }
    return 1;
}

static void memo_free(build_ctx *c, size_t n)
{
    for (size_t i = 0; c->memo && i < n; i++)
        free(c->memo[i].list);
    free(c->memo);
    free(c->memo_of);
    free(c->memo_new);
    c->memo = NULL;
    c->memo_of = NULL;
    c->memo_new = NULL;
}

static lie_status precompute_flagged(build_ctx *c, int threads, size_t *n_memo)
{
    const lie_env *old = c->old;
    const lie_scene *s = c->s;
    *n_memo = 0;
    c->memo_of = malloc(sizeof *c->memo_of * ((size_t)old->n_nodes + 1));
    if (!c->memo_of)
        return LIE_ERR_NOMEM;
    for (uint32_t i = 0; i < old->n_nodes; i++)
        c->memo_of[i] = -1;
    size_t n = 0, cap = 0;
    size_t ne = (size_t)s->n_emitters;
    for (uint32_t t = 0; t < s->n_tris; t++)
        for (size_t e = 0; e < ne; e++) {
            int32_t ou = c->old_unit[(size_t)t * ne + e];
            uint32_t r = ou < 0 ? MEMO_NO_OLD : old->root[ou];
            if ((r == MEMO_NO_OLD || c->node_flags[r]) && !memo_push(c, &n, &cap, r, t, lie_patch_root(), (int)e)) {
                *n_memo = n;
                return LIE_ERR_NOMEM;
            }
        }
    size_t first = 0;
    lie_status st = LIE_OK;
    while (st == LIE_OK && first < n) {
        memo_state ms = {c, first, n - first};
        st = lie_parallel_for(ms.n, threads, memo_compute, &ms, NULL, NULL);
        for (int i = 0; i < threads; i++)
            if (c->workers[i].nomem)
                st = LIE_ERR_NOMEM;
        size_t end = n;
        for (size_t i = first; st == LIE_OK && i < end; i++) {
            const memo_entry m = c->memo[i];
            uint32_t child = m.old == MEMO_NO_OLD ? 0 : old->nodes[m.old].child;
            if (!splits(c, m.tri, m.path, m.e, m.cls, m.list, m.n_list))
                continue;
            /* the children build_node will compute: flagged old ones, or
             * all four when the node had none (unflagged ones are copied) */
            for (uint32_t k = 0; k < 4; k++)
                if ((!child || c->node_flags[child + k]) &&
                    !memo_push(c, &n, &cap, child ? child + k : MEMO_NO_OLD, m.tri,
                               lie_patch_child(m.path, (int)k), m.e))
                    st = LIE_ERR_NOMEM;
        }
        first = end;
    }
    *n_memo = n;
    if (st == LIE_OK && !memo_index_new(c, n))
        st = LIE_ERR_NOMEM;
    return st;
}

/* Build (or, with a mask, rebuild some units of) every triangle, then
 * concatenate the per-triangle buffers in unit order. */
static lie_status run_build(lie_env *env, const lie_scene *s, const lie_rt *rt, const int32_t *old_unit,
                           const uint8_t *node_flags, const uint8_t *tri_mask, uint64_t unit_lo, uint64_t unit_hi,
                           int threads, lie_progress *progress, lie_build_stats *stats)
{
    build_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.rt = rt;
    c.p = &env->params;
    c.min_area = env->params.min_patch * s->max_tri_area;
    c.ray_far = lie_ray_far(s);
    c.old = env;
    c.old_unit = old_unit;
    c.node_flags = node_flags;
    c.tri_mask = tri_mask;
    /* the triangles holding units [unit_lo, unit_hi) */
    size_t ne = s->n_emitters > 0 ? (size_t)s->n_emitters : 1;
    c.unit_lo = unit_lo;
    c.unit_hi = unit_hi;
    c.tri_lo = (uint32_t)(unit_lo / ne);
    uint32_t n_items = unit_hi > unit_lo ? (uint32_t)((unit_hi - 1) / ne + 1 - c.tri_lo) : 0;
    if (s->n_emitters == 0) {
        c.tri_lo = 0;
        n_items = s->n_tris;
    }
    if (threads <= 0)
        threads = lie_cpu_count();
    c.workers = calloc((size_t)threads, sizeof *c.workers);
    c.out = calloc((size_t)n_items + 1, sizeof *c.out);
    c.n_halton = c.p->max_samples < HALTON_TABLE_MAX ? c.p->max_samples : HALTON_TABLE_MAX;
    c.halton = malloc(sizeof *c.halton * 4 * (size_t)c.n_halton + 1);
    for (int d = 0; c.halton && d < 4; d++)
        for (uint32_t i = 0; i < c.n_halton; i++)
            c.halton[(size_t)d * c.n_halton + i] = radical_inverse(HALTON_BASE[d], i);
    lie_status st = c.workers && c.out && c.halton ? LIE_OK : LIE_ERR_NOMEM;
    size_t n_memo = 0;
    if (st == LIE_OK && node_flags && old_unit && c.p->mode == LIE_BLOCKERS_SAMPLED)
        st = precompute_flagged(&c, threads, &n_memo);
    if (st == LIE_OK)
        st = lie_parallel_for(n_items, threads, build_triangle, &c, progress ? lie_progress_cb : NULL, progress);
    memo_free(&c, n_memo);
    for (int i = 0; c.workers && i < threads; i++) {
        if (c.workers[i].nomem)
            st = LIE_ERR_NOMEM;
        if (stats)
            stats_merge(stats, &c.workers[i].st);
    }
    if (st == LIE_OK)
        st = assemble(env, c.out, c.tri_lo, n_items, s->n_emitters, old_unit, unit_lo, unit_hi);
    for (uint32_t t = 0; c.out && t < n_items; t++) {
        free(c.out[t].roots);
        free(c.out[t].nodes);
        free(c.out[t].pool);
    }
    free(c.out);
    free(c.halton);
    workers_free(c.workers, threads);
    return st;
}

void lie_env_destroy(lie_env *env)
{
    if (!env)
        return;
    free(env->root);
    free(env->nodes);
    free(env->pool);
    free(env);
}

/* Copy old node `from` and its subtree to node idx of the new arrays, in
 * the order copy_node gives (children appended at next_node, lists at
 * next_pool, as their nodes are visited). */
static void copy_direct(const lie_env *old, uint32_t from, lie_pnode *nd, uint32_t *pl, uint32_t idx,
                        uint32_t *next_node, uint32_t *next_pool)
{
    lie_pnode x = old->nodes[from];
    if (x.child) {
        uint32_t first = *next_node, oc = x.child;
        *next_node += 4;
        x.child = first;
        nd[idx] = x;
        for (uint32_t k = 0; k < 4; k++)
            copy_direct(old, oc + k, nd, pl, first + k, next_node, next_pool);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        memcpy(pl + *next_pool, old->pool + x.list, sizeof *pl * x.count);
        x.list = *next_pool;
        *next_pool += x.count;
    }
    nd[idx] = x;
}

/* Concatenate per-triangle unit buffers (of triangles tri_lo + t) into
 * env's flat arrays (copied triangles straight from env's old arrays, which
 * are freed last); env->root[unit - unit_lo] for the units in
 * [unit_lo, unit_hi). */
static lie_status assemble(lie_env *env, unit_buf *bufs, uint32_t tri_lo, uint32_t n_tris, int n_emitters,
                           const int32_t *old_unit, uint64_t unit_lo, uint64_t unit_hi)
{
    uint64_t nodes = 0, pool = 0;
    for (uint32_t t = 0; t < n_tris; t++) {
        nodes += bufs[t].n_nodes;
        pool += bufs[t].n_pool;
    }
    if (nodes >= 0xFFFFFFF0u || pool >= 0xFFFFFFF0u)
        return LIE_ERR_LIMIT;
    uint32_t *root = malloc(sizeof *root * ((size_t)(unit_hi - unit_lo) + 1));
    lie_pnode *nd = malloc(sizeof *nd * (size_t)(nodes + 1));
    uint32_t *pl = malloc(sizeof *pl * (size_t)(pool + 1));
    if (!root || !nd || !pl) {
        free(root);
        free(nd);
        free(pl);
        return LIE_ERR_NOMEM;
    }
    uint32_t nb = 0, pb = 0;
    for (uint32_t t = 0; t < n_tris; t++) {
        const unit_buf *u = &bufs[t];
        if (u->copied) {
            uint32_t next_node = nb, next_pool = pb;
            for (int e = 0; e < n_emitters; e++) {
                size_t unit = (size_t)(tri_lo + t) * (size_t)n_emitters + (size_t)e;
                uint32_t idx = next_node++;
                root[unit - unit_lo] = idx;
                copy_direct(env, env->root[old_unit[unit]], nd, pl, idx, &next_node, &next_pool);
            }
            nb += u->n_nodes;
            pb += u->n_pool;
            continue;
        }
        for (int e = 0; e < n_emitters; e++) {
            uint64_t unit = (uint64_t)(tri_lo + t) * (uint64_t)n_emitters + (uint64_t)e;
            if (unit >= unit_lo && unit < unit_hi)
                root[unit - unit_lo] = nb + u->roots[e];
        }
        for (uint32_t i = 0; i < u->n_nodes; i++) {
            lie_pnode x = u->nodes[i];
            if (x.child)
                x.child += nb;
            if (x.cls == LIE_CLASS_PARTIAL)
                x.list += pb;
            nd[nb + i] = x;
        }
        if (u->n_pool)
            memcpy(pl + pb, u->pool, sizeof *pl * u->n_pool);
        nb += u->n_nodes;
        pb += u->n_pool;
    }
    free(env->root);
    free(env->nodes);
    free(env->pool);
    env->root = root;
    env->nodes = nd;
    env->pool = pl;
    env->n_nodes = nb;
    env->n_pool = pb;
    return LIE_OK;
}

lie_status lie_env_build(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                         lie_progress *progress, lie_env **out, lie_build_stats *stats, lie_error *err)
{
    return lie_env_build_masked(s, rt, p, NULL, progress, out, stats, err);
}

lie_status lie_env_build_masked(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                                const uint8_t *tri_mask, lie_progress *progress, lie_env **out,
                                lie_build_stats *stats, lie_error *err)
{
    *out = NULL;
    if (lie_build_params_check(p, err) != LIE_OK)
        return LIE_ERR_ARG;
    double t0 = lie_time_now();
    lie_env *env = calloc(1, sizeof *env);
    if (!env)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    env->n_tris = s->n_tris;
    env->n_emitters = s->n_emitters;
    env->params = *p;
    env->params.threads = 0;
    env->scene_hash = s->hash;
    if (stats)
        memset(stats, 0, sizeof *stats);
    uint64_t n_units = (uint64_t)s->n_tris * (uint64_t)s->n_emitters;
    lie_status st = run_build(env, s, rt, NULL, NULL, tri_mask, 0, n_units, p->threads, progress, stats);
    if (st != LIE_OK) {
        lie_env_destroy(env);
        return lie_error_set(err, st, s->path, "building local illumination environments: %s",
                             lie_status_str(st));
    }
    if (stats)
        stats->seconds = lie_time_now() - t0;
    *out = env;
    return LIE_OK;
}

lie_status lie_env_build_range(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const uint8_t *tri_mask, uint64_t first_unit, uint64_t n_units, lie_env_part *out,
                               lie_build_stats *stats, lie_error *err)
{
    memset(out, 0, sizeof *out);
    if (lie_build_params_check(p, err) != LIE_OK)
        return LIE_ERR_ARG;
    uint64_t total = (uint64_t)s->n_tris * (uint64_t)s->n_emitters;
    if (first_unit > total || n_units > total - first_unit)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "units %llu..%llu out of range (%llu)",
                             (unsigned long long)first_unit, (unsigned long long)(first_unit + n_units),
                             (unsigned long long)total);
    double t0 = lie_time_now();
    lie_env part;
    memset(&part, 0, sizeof part);
    part.params = *p;
    if (stats)
        memset(stats, 0, sizeof *stats);
    lie_status st = LIE_OK;
    if (n_units)
        st = run_build(&part, s, rt, NULL, NULL, tri_mask, first_unit, first_unit + n_units, p->threads, NULL, stats);
    if (st != LIE_OK) {
        free(part.root);
        free(part.nodes);
        free(part.pool);
        return lie_error_set(err, st, s->path, "building local illumination environments: %s", lie_status_str(st));
    }
    if (stats)
        stats->seconds = lie_time_now() - t0;
    out->first_unit = first_unit;
    out->n_units = n_units;
    out->root = part.root;
    out->nodes = part.nodes;
    out->n_nodes = part.n_nodes;
    out->pool = part.pool;
    out->n_pool = part.n_pool;
    return LIE_OK;
}

lie_status lie_env_rebuild_units(lie_env *env, const lie_scene *s, const lie_rt *rt,
                                 const uint32_t *units, size_t n_units, int threads,
                                 lie_build_stats *stats, lie_error *err)
{
    if (env->n_tris != s->n_tris || env->n_emitters != s->n_emitters)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "the scene's triangles or emitters changed in number");
    size_t n = (size_t)s->n_tris * (size_t)s->n_emitters;
    int32_t *old_unit = malloc(sizeof *old_unit * (n + 1));
    if (!old_unit)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    for (size_t u = 0; u < n; u++)
        old_unit[u] = (int32_t)u;
    for (size_t i = 0; i < n_units; i++)
        if (units[i] < n)
            old_unit[units[i]] = -1;
    lie_status st = lie_env_update(env, s, rt, old_unit, NULL, threads, stats, err);
    free(old_unit);
    return st;
}

lie_status lie_env_update(lie_env *env, const lie_scene *s, const lie_rt *rt, const int32_t *old_unit,
                          const uint8_t *node_flags, int threads, lie_build_stats *stats, lie_error *err)
{
    double t0 = lie_time_now();
    if (stats)
        memset(stats, 0, sizeof *stats);
    lie_status st = run_build(env, s, rt, old_unit, node_flags, NULL, 0, (uint64_t)s->n_tris * (uint64_t)s->n_emitters,
                              threads, NULL, stats);
    if (stats)
        stats->seconds = lie_time_now() - t0;
    if (st != LIE_OK)
        return lie_error_set(err, st, s->path, "updating local illumination environments: %s",
                             lie_status_str(st));
    env->n_tris = s->n_tris;
    env->n_emitters = s->n_emitters;
    env->scene_hash = s->hash;
    return LIE_OK;
}

static void stats_walk(const lie_env *env, uint32_t idx, int depth, lie_build_stats *st)
{
    const lie_pnode *x = &env->nodes[idx];
    st->patches_per_depth[depth < LIE_PATCH_MAX_DEPTH ? depth : LIE_PATCH_MAX_DEPTH]++;
    if (x->child) {
        for (uint32_t k = 0; k < 4; k++)
            stats_walk(env, x->child + k, depth + 1, st);
        return;
    }
    st->pairs[x->cls < LIE_CLASS_COUNT ? x->cls : LIE_CLASS_COMPLEX]++;
    st->segments += x->quality;
    if (x->cls == LIE_CLASS_PARTIAL) {
        st->blocker_total += x->count;
        hist_add(st, x->count);
    }
}

void lie_env_stats(const lie_env *env, lie_build_stats *stats)
{
    memset(stats, 0, sizeof *stats);
    size_t n = (size_t)env->n_tris * (size_t)env->n_emitters;
    for (size_t u = 0; u < n; u++)
        stats_walk(env, env->root[u], 0, stats);
}
