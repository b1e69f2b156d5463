/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect patch CACHE TRI[/PATH]: one patch's local illumination
 * environment.  Per emitter, the unit's tree is followed along the path:
 * if it ends at a node, that node and its subtree are shown; if a leaf is
 * reached first, that leaf covers the whole patch and is shown alone. */
#include "inspect.h"

#include <string.h>

static void tree_text(const lie_env *env, uint32_t node, uint32_t tri, lie_patch_path path, int indent)
{
    const lie_pnode *n = &env->nodes[node];
    char name[64];
    lie_patch_format(tri, path, name, sizeof name);
    printf("%*s%s ", indent, "", name);
    inspect_print_node(stdout, env, n);
    putchar('\n');
    if (n->child)
        for (int d = 0; d < 4; d++)
            tree_text(env, n->child + (uint32_t)d, tri, lie_patch_child(path, d), indent + 2);
}

static void tree_json(const lie_env *env, uint32_t node, uint32_t tri, lie_patch_path path)
{
    const lie_pnode *n = &env->nodes[node];
    char name[64];
    lie_patch_format(tri, path, name, sizeof name);
    printf("{\"patch\":\"%s\",", name);
    inspect_json_node(stdout, env, n);
    if (n->child) {
        printf(",\"children\":[");
        for (int d = 0; d < 4; d++) {
            if (d)
                putchar(',');
            tree_json(env, n->child + (uint32_t)d, tri, lie_patch_child(path, d));
        }
        putchar(']');
    }
    putchar('}');
}

int inspect_patch(const char *path, const char *patch, const inspect_options *o)
{
    uint32_t tri;
    lie_patch_path want;
    if (!lie_patch_parse(patch, &tri, &want)) {
        fprintf(stderr, "%s: patch: expected TRI or TRI/PATH (digits 0-3, at most %d), got '%s' (see --help)\n",
                inspect_prog, LIE_PATCH_MAX_DEPTH, patch);
        return 2;
    }
    inspect_cache l;
    lie_error err;
    if (inspect_load(path, &l, &err) != LIE_OK) {
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    const lie_cache *c = l.cache;
    const lie_env *env = c->env;
    if (tri >= env->n_tris) {
        lie_error_set(&err, LIE_ERR_NOT_FOUND, path, "patch %s: the cache has %u triangles", patch, env->n_tris);
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    char want_name[64];
    lie_patch_format(tri, want, want_name, sizeof want_name);
    if (o->json) {
        printf("{\"cache\":");
        inspect_json_string(stdout, path);
        printf(",\"patch\":\"%s\",\"triangle\":%u,\"emitters\":[", want_name, tri);
    } else {
        printf("patch %s: %d emitter%s\n", want_name, env->n_clusters, env->n_clusters == 1 ? "" : "s");
    }
    for (int e = 0; e < env->n_clusters; e++) {
        /* down the tree along the path, stopping at a leaf */
        uint32_t node = env->root[(size_t)tri * (size_t)env->n_clusters + (size_t)e];
        lie_patch_path at = lie_patch_root();
        while (at.depth < want.depth && env->nodes[node].child) {
            int d = lie_patch_digit(want, at.depth);
            node = env->nodes[node].child + (uint32_t)d;
            at = lie_patch_child(at, d);
        }
        int exact = at.depth == want.depth;
        const lie_cache_emitter *m = &c->emitters[e];
        char at_name[64];
        lie_patch_format(tri, at, at_name, sizeof at_name);
        if (o->json) {
            printf("%s{\"emitter\":%d,\"type\":\"%s\",\"node\":%d,\"match\":\"%s\",\"tree\":", e ? "," : "", e,
                   inspect_emitter_type_name(m->type), m->node, exact ? "node" : "leaf");
            tree_json(env, node, tri, at);
            putchar('}');
        } else {
            printf("emitter %d (%s, node %d): ", e, inspect_emitter_type_name(m->type), m->node);
            if (exact)
                printf("%s %s\n", env->nodes[node].child ? "the subtree at" : "the leaf at", at_name);
            else
                printf("leaf %s covers %s\n", at_name, want_name);
            tree_text(env, node, tri, at, 2);
        }
    }
    if (o->json)
        printf("]}\n");
    inspect_unload(&l);
    return inspect_stdout_check();
}
