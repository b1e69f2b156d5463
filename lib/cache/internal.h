/* SPDX-License-Identifier: Apache-2.0 */
/* lib/cache internals shared by the encoder and the decoder: section ids,
 * little-endian field access, the layout arithmetic of formats/lie-cache.md
 * and the structural check of an env. */
#ifndef LIE_CACHE_INTERNAL_H
#define LIE_CACHE_INTERNAL_H

#include "cache/cache.h"

#include <string.h>

#define LIE_CACHE_MAGIC "LIECACHE"
#define LIE_CACHE_HEADER_SIZE 32u
#define LIE_CACHE_ENTRY_SIZE 32u
#define LIE_CACHE_META_FIXED 48u
#define LIE_CACHE_PARAMS_SIZE 56u    /* version 7; 6: 52 (no whole_pixels); 3 to 5: 48 (no complex_predict); 2: 28 (no cost model); 1: 24 */
#define LIE_CACHE_PARAMS_SIZE_V6 52u
#define LIE_CACHE_PARAMS_SIZE_V5 48u
#define LIE_CACHE_PARAMS_SIZE_V2 28u
#define LIE_CACHE_PARAMS_SIZE_V1 24u
#define LIE_CACHE_VIEWS_FIXED 16u
#define LIE_CACHE_VIEW_SIZE 48u
#define LIE_CACHE_EMITTER_SIZE 24u    /* version 4; versions 1 to 3: 16 (one cluster each) */
#define LIE_CACHE_EMITTER_SIZE_V3 16u
#define LIE_CACHE_NODE_SIZE 20u

/* A section id: its four ASCII bytes read as a little-endian u32. */
#define LIE_CACHE_ID(a, b, c, d) \
    ((uint32_t)(a) | ((uint32_t)(b) << 8) | ((uint32_t)(c) << 16) | ((uint32_t)(d) << 24))
#define LIE_CACHE_ID_META LIE_CACHE_ID('M', 'E', 'T', 'A')
#define LIE_CACHE_ID_PARAMS LIE_CACHE_ID('P', 'A', 'R', 'M')
#define LIE_CACHE_ID_EDITS LIE_CACHE_ID('E', 'D', 'I', 'T')
#define LIE_CACHE_ID_EMITTERS LIE_CACHE_ID('E', 'M', 'I', 'T')
#define LIE_CACHE_ID_ROOTS LIE_CACHE_ID('R', 'O', 'O', 'T')
#define LIE_CACHE_ID_NODES LIE_CACHE_ID('N', 'O', 'D', 'E')
#define LIE_CACHE_ID_POOL LIE_CACHE_ID('P', 'O', 'O', 'L')
#define LIE_CACHE_ID_RST LIE_CACHE_ID('R', 'S', 'T', 'S') /* reserved for rst-update */
#define LIE_CACHE_ID_VIEWS LIE_CACHE_ID('V', 'I', 'E', 'W')

static inline void lie_cache_put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

static inline void lie_cache_put_u64(unsigned char *p, uint64_t v)
{
    lie_cache_put_u32(p, (uint32_t)v);
    lie_cache_put_u32(p + 4, (uint32_t)(v >> 32));
}

static inline uint32_t lie_cache_get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline uint64_t lie_cache_get_u64(const unsigned char *p)
{
    return (uint64_t)lie_cache_get_u32(p) | ((uint64_t)lie_cache_get_u32(p + 4) << 32);
}

static inline uint32_t lie_cache_f32_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static inline float lie_cache_bits_f32(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Round up to the next multiple of 8 (x well below 2^64). */
static inline uint64_t lie_cache_align8(uint64_t x) { return (x + 7u) & ~(uint64_t)7u; }

/* The display name of a section id ("NODES"; unknown ids as their four
 * characters or in hex). */
void lie_cache_section_name(uint32_t id, char name[16]);

/* Check env's patch trees against the structural rules of
 * formats/lie-cache.md ("What a reader must reject", 15).  env->n_tris,
 * n_emitters, n_nodes, n_pool must describe the arrays.  Failures are
 * reported with `status`, file `name` and `prefix` before the message. */
lie_status lie_cache_check_env(const lie_env *env, lie_status status, const char *name, const char *prefix,
                               lie_error *err);

/* Check one emitter record against a scene of n_tris triangles; returns a
 * static description of the problem, or NULL when the record is valid. */
const char *lie_cache_check_emitter(const lie_cache_emitter *e, uint32_t n_tris);
/* NULL, or what is wrong with the views (formats/lie-cache.md, VIEWS). */
#define LIE_CACHE_VIEW_MAX 16384
const char *lie_cache_check_views(const lie_cache_views *v);


/* ---- the writer's parts, shared by the encoder (cache.c) and the stream
 * (stream.c) ---------------------------------------------------------------- */

/* The sections in the order a writer writes them. */
enum { S_META, S_PARAMS, S_EDITS, S_EMITTERS, S_ROOTS, S_NODES, S_POOL, S_VIEWS, S_COUNT };

extern const uint32_t lie_cache_section_ids[S_COUNT]; /* their ids */

/* The trees laid out in the file's canonical order (formats/lie-cache.md):
 * each unit's tree from `src`, its lists from `src_pool`. */
typedef struct lie_cache_tree_writer {
    const lie_pnode *src;        /* the trees' nodes ... */
    const uint32_t *src_pool;    /* ... and lists */
    unsigned char *nodes, *pool; /* where node node_base and POOL entry pool_base go */
    uint32_t node_base, pool_base;
    uint32_t next_node, next_pool;
} lie_cache_tree_writer;
void lie_cache_write_tree(lie_cache_tree_writer *w, uint32_t from, uint32_t idx);
/* The nodes and list entries of the tree from node `from`. */
void lie_cache_tree_size(const lie_pnode *nodes, uint32_t from, uint64_t *n_nodes, uint64_t *n_pool);
/* The ROOTS tag of a unit whose tree is one lone leaf, or 0. */
uint32_t lie_cache_lone_tag(const lie_pnode *nodes, uint32_t root);
/* Where each section goes (Layout), for trees of file_nodes nodes and
 * file_pool list entries. */
typedef struct lie_cache_layout {
    uint64_t sz[S_COUNT], off[S_COUNT], total;
    int n_sections;
} lie_cache_layout;
void lie_cache_lay_out(const lie_cache *c, uint64_t file_nodes, uint64_t file_pool, lie_cache_layout *L);
/* The header and the section table, with the sections' checksums, at buf. */
void lie_cache_put_header(unsigned char *buf, const lie_cache_layout *L, int partial, const uint64_t hash[S_COUNT]);
/* The sections but ROOTS, NODES and POOL, at buf + L->off[k] (VIEWS at views). */
void lie_cache_put_small(unsigned char *buf, unsigned char *views, const lie_cache *c, const lie_cache_layout *L,
                         uint64_t file_nodes, uint64_t file_pool);
/* What a reader would reject in the fields around the env's trees. */
lie_status lie_cache_check_head(const lie_cache *c, const char *name, lie_error *err);

#endif
