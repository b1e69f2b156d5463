#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench: how much faster than full visibility the LIE can be on the
# third-party scenes, bounded from above by two measurements side by side:
#
#  - the shading floor: a frame at N light samples with full visibility
#    against the same frame with no shadows at all (--visibility none).
#    No way of answering shadows makes a frame at equal samples cheaper
#    than the second;
#  - the samples the best LIE could save at equal quality
#    (bench/light-classes.c, an oracle that needs no cache): units of whole
#    emitters (the paper's), of clusters, of single emitter triangles, on a
#    patch of 8 pixels and at the point itself.
#
# Same scenes and cameras as bench/quality-real.sh (its Lambertian copies
# in out/bench-scenes, made there).  Writes out/bench-light-bound.json.
set -e
cd "$(dirname "$0")/.."
N=${N:-256}
SIZE=${SIZE:-256x256}
THREADS=${THREADS:-2}
K=${K:-16}
STEP=${STEP:-4}
CLASSES=build/release/bench-light-classes
LAMBERT=build/release/bench-lambert
make -s "$CLASSES" "$LAMBERT" >/dev/null
mkdir -p out/bench-scenes
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p" | head -1; }

# NAME|SCENE|EYE|TARGET|N, as bench/quality-real.sh; N: the light samples
# of the floor's frames (the lamp's five point lights converge at 16, where
# its images reach p99 <= 2% in bench/quality-real.sh; else $N)
SCENES=${BOUND_SCENES:-"scifi_hallway|../shared/scenes/scifi_hallway/space_ship_hallway.glb|20.1,0.5,2|20.1,0.3,-20|
ccity_buildings|../shared/scenes/ccity_buildings/scene.gltf|400,200,-5800|850,380,-6400|
bedroom_corner|../shared/scenes/bedroom_corner/scene.gltf|-12,36,42|-45,20,8|
lights_punctual_lamp|../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf|1.3,1.3,1.5|0.25,0.9,0|16"}

echo "bench-light-bound: $SIZE, $THREADS threads; oracle: $K rays per emitter triangle, every ${STEP}th pixel (load $(cut -d' ' -f1 /proc/loadavg))"
printf '  %-22s %5s %8s %8s %7s | %s\n' scene N "full s" "none s" bound "samples the best LIE saves at equal p99 (share of light in partial units)"
json=""
echo "$SCENES" | while IFS='|' read -r name scene eye target n; do
    [ -n "$name" ] || continue
    if [ ! -f "$scene" ]; then
        printf '  %-22s (no %s)\n' "$name" "$scene"
        continue
    fi
    glb=out/bench-scenes/$name.glb
    [ -f "$glb" ] && [ "$glb" -nt "$scene" ] && [ "$glb" -nt "$LAMBERT" ] || "$LAMBERT" "$scene" "$glb"
    cam="eye=$eye,target=$target,fov=45"
    for vis in full none; do
        bin/lie-render "$glb" --camera "$cam" --size "$SIZE" --threads "$THREADS" --light-samples "${n:-$N}" \
            --visibility "$vis" -q --stats=json -o "$TMP/x.exr" 2>"$TMP/$vis.json"
    done
    tf=$(field seconds_render <"$TMP/full.json")
    tn=$(field seconds_render <"$TMP/none.json")
    "$CLASSES" "$glb" "$cam" "$K" "$STEP" 8 >"$TMP/o.json"
    saved=$(tail -n 1 "$TMP/o.json")
    bound=$(awk -v f="$tf" -v n="$tn" 'BEGIN { if (n > 0) printf "%.2f", f / n; else print "-" }')
    printf '  %-22s %5s %8.2f %8.2f %7s | %s\n' "$name" "${n:-$N}" "$tf" "$tn" "$bound" "$saved"
    printf '"%s":{"light_samples":%s,"full_seconds":%s,"none_seconds":%s,"oracle":%s}\n' "$name" "${n:-$N}" "$tf" "$tn" "$(head -n 1 "$TMP/o.json")" >>"$TMP/all"
done
[ -f "$TMP/all" ] && { printf '{'; paste -sd, "$TMP/all"; printf '}\n'; } >out/bench-light-bound.json
echo "  (bound: full / none, the most any visibility method gains at equal samples; the oracle's"
echo "   figures ignore what answers cost: docs/measurements.md, \"What the LIE can save on real scenes\")"
