/* SPDX-License-Identifier: Apache-2.0 */
/* bench-lambert IN.gltf|IN.glb OUT.glb: the scene with every material made
 * Lambertian (metallic 0, roughness 1, no metallic-roughness texture; base
 * colour, its texture, emission and alpha kept), written as one binary glTF
 * for the equal-quality bench (bench/quality.sh).  lie-render shades
 * metallic 0 and roughness 1 as pure Lambert (lib/shade/surface.c), and
 * bench/cycles.py gives Cycles a Diffuse BSDF of the same colour, so the
 * two renderers integrate the same BRDF.  Messages as the tools'. */
#include <stdio.h>
#include <string.h>

#include "lie.h"

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: bench-lambert IN.gltf|IN.glb OUT.glb\n");
        return 2;
    }
    lie_scene *s = NULL;
    lie_error err;
    memset(&err, 0, sizeof err);
    if (lie_scene_load(argv[1], NULL, &s, &err) != LIE_OK) {
        fprintf(stderr, "bench-lambert: %s: %s\n", err.file[0] ? err.file : argv[1], err.msg);
        return 1;
    }
    for (int i = 0; i < s->n_materials; i++) {
        lie_material *m = &s->materials[i];
        m->metallic = 0.0f;
        m->roughness = 1.0f;
        m->mr_tex = -1;
    }
    lie_status st = lie_scene_flatten(s, &err);
    if (st == LIE_OK)
        st = lie_gltf_export(s, argv[2], &err);
    if (st != LIE_OK)
        fprintf(stderr, "bench-lambert: %s: %s\n", err.file[0] ? err.file : argv[2], err.msg);
    lie_scene_destroy(s);
    return st == LIE_OK ? 0 : 1;
}
