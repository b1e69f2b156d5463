/* SPDX-License-Identifier: Apache-2.0 */
/* Silhouette counting: a pair's blocked samples as a bitmask from the
 * silhouette edges of its blockers (after Laine, Aila, Assarsson, Lehtinen,
 * Akenine-Moeller 2005, "Soft shadow volumes for ray tracing"), so that the
 * edges inside a connected mesh cost nothing.
 *
 * Toward a planar emitter, a blocker wholly in front of the shading point
 * projects to a triangle in the emitter plane's (s, t).  A sample's depth
 * complexity (how many of these triangles hold it) is a sum over their
 * edges: cast a ray from the sample toward +t; a triangle holds the sample
 * iff the ray leaves it through its upper edge, so each edge adds sigma
 * (+1 for an edge with the triangle below it, -1 above it) to the samples
 * below it whose s lies in the edge's half-open range [a, b).  Two
 * triangles sharing an edge, one on each side of it (the edge is interior
 * to a mesh whose triangles face the point alike), add exactly opposite
 * terms: both edges are dropped.  What remains are the silhouette edges
 * (the two triangles face differently from the point, or one of them is
 * not among the blockers) and the mesh's boundary.  Laine et al. count
 * relative to one reference sample; the ray toward +t makes the reference
 * the sample above every blocker, whose count is 0 with no test.
 *
 * The walk reuses the hierarchical sample groups of bitmask.h: an edge
 * wholly above a group adds nothing to it, one wholly below it (and across
 * its whole s range) adds sigma to the group's count at once, and only the
 * groups an edge's line or the vertical line through one of its ends
 * crosses go a level down.  A group whose count is known is set or
 * skipped whole.
 *
 * Exactness.  The edge's side is decided by the blocker's own edge form,
 * evaluated as the per-sample test does (fmaf), so a sample's sign is the
 * per-sample test's sign.  A sample within the form's rounding margin of
 * a silhouette edge (|G| <= tol, the margin of bitmask.c), or of the
 * vertical line through an edge's end (s within delta of it), is decided
 * by the per-sample test over the triangles (in_cone), so near every
 * silhouette edge and vertex the answer is the per-sample test's.  Away
 * from them the count is the number of triangles holding the sample, so
 * it is blocked iff the per-sample test blocks it, up to what the
 * per-sample test itself rounds differently from exact arithmetic: a
 * sample within rounding of a vertex inside a mesh (where the fan's edge
 * forms may disagree) or inside a sliver thinner than the margin.
 * tests/unit/test_silhouette.c counts such samples on meshes with shared
 * vertices: none were found. */
#ifndef LIE_SHADE_SILHOUETTE_H
#define LIE_SHADE_SILHOUETTE_H

#include "shade/bitmask.h"

/* One edge: the sample x = (s, t) is below it iff g0 + s gs + t gt > 0
 * (fmaf as the per-sample test); it adds sigma there when s is in [a, b).
 * A vertex inside the meshes (all its edges interior) is a record too,
 * with sigma 0, an empty range at its s, and G = t - its t: it adds
 * nothing, but samples within its margins (s within delta, |G| <= tol) are
 * decided by the per-sample test, whose edge forms all vanish there and
 * may leave a crack between the fan's triangles. */
typedef struct lie_sil_edge {
    float a, b;          /* s range of the edge's projection, half-open */
    float ae, be;        /* the same widened by the rounding margin delta */
    float g0, gs, gt;    /* sigma times the blocker's edge form */
    float tol;           /* the form's rounding margin */
    int sigma;
} lie_sil_edge;

/* Per-worker workspace, sized for a number of blockers. */
typedef struct lie_sil_work {
    int cap;             /* triangles */
    int n_tris, n_edges;
    int counted;         /* the last pair was counted (else walked per triangle) */
    float *forms;        /* 9 per triangle: its three edge forms (the per-sample test) */
    lie_sil_edge *edges; /* up to 6 cap: silhouette edges, then interior vertices */
    int32_t *act;        /* active edge lists: per level, per group of 8 two lists of 3 cap */
    int32_t *slot;       /* hash of triangle -> index, 4 cap (power of two) */
    uint32_t *slot_tri;
    int n_slots;
    float *ps, *pt;      /* projected vertices, 3 per triangle */
    uint64_t *vkey;      /* hash of projected vertices (s, t bits): n_vslots (a power of two) */
    int n_vslots, n_vused; /* slots allocated, and those the pair uses */
    int32_t *cand;       /* interior edges' ends, 6 cap: 3 i + corner */
} lie_sil_work;

lie_status lie_sil_work_init(lie_sil_work *w, int cap);
void lie_sil_work_free(lie_sil_work *w);

/* OR into mask the samples of b inside any of w's n_tris triangles (their
 * forms in w->forms), counting over w's n_edges silhouette edges.  Returns
 * the number of samples decided by the per-sample fallback. */
int lie_sil_mask(const lie_bitmask *b, lie_sil_work *w, uint64_t *mask);

/* Whether counting a pair's n_edges silhouette edges costs less than
 * walking its n_tris triangles one by one (bitmask.h).  Measured with
 * --timers at 1024 samples, one thread, best of 3 (the threshold k in
 * n_edges < k n_tris): museum1 at --detail 4 (sculptures of 4 x 4 times
 * the triangles) 0.065 s walking every triangle, 0.067 / 0.055 / 0.096 s
 * for k = 0.5 / 1 / always; on museum1, museum3 and cornell the walk of
 * every triangle won at any k (silhouette.h: few triangles per point are
 * wholly in front of it, and they share few edges). */
static inline int lie_sil_pays(int n_tris, int n_edges) { return n_edges < n_tris; }

/* The margin of a form evaluated over samples within |s| <= s_abs,
 * |t| <= t_abs (the bitmask's). */
static inline float lie_sil_tol(float f0, float fs, float ft, float s_abs, float t_abs)
{
    return 1e-5f * (fabsf(f0) + fabsf(fs) * s_abs + fabsf(ft) * t_abs);
}

#endif
