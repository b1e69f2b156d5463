#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench: what the portable build costs.  The tools are built for baseline x86-64 with
# AVX2 copies of the hot kernels chosen at run time (lib/core/hot.h); this builds the same
# sources the way they were built before, whole at -march=x86-64-v3 (`make VARIANT=v3`, tools
# in build/v3/bin), and renders the same frames with both, side by side, alternating, best
# of REPEAT render times (load and BVH excluded), one thread.  The images must be the same
# bytes.  Scenes: the bundled museums and, when present, ../shared/scenes (the lamp, the
# bedroom corner).  Writes out/bench-arch.json.
set -e
cd "$(dirname "$0")/.."
SIZE=${SIZE:-256x256}
REPEAT=${REPEAT:-3}
mkdir -p out
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
make -s -j"$(nproc)" VARIANT=v3 build/v3/bin/lie-render build/v3/bin/lie-build >/dev/null
field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p"; }

# best BIN CACHE OUT ARGS...: the best seconds_render of REPEAT renders
best() {
    b=$1; c=$2; o=$3; shift 3
    t=""
    for _ in $(seq "$REPEAT"); do
        "$b/lie-render" "$c" --size "$SIZE" --threads 1 -q --stats-file "$TMP/s.json" -o "$o" "$@"
        x=$(field seconds_render <"$TMP/s.json")
        t=$(awk -v a="$t" -v b="$x" 'BEGIN { if (a == "" || b < a) print b; else print a }')
    done
    echo "$t"
}

echo "bench/arch: baseline x86-64 + AVX2 clones (bin/) against -march=x86-64-v3 (build/v3/bin/), $SIZE, 1 thread, best of $REPEAT; load: $(uptime | sed 's/.*load/load/')"
printf '%-28s %-22s %10s %10s %7s %s\n' scene mode v3_s portable_s ratio bytes
json="["
for scene in tests/scenes/museum2.gltf tests/scenes/museum3.gltf ../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf \
             ../shared/scenes/bedroom_corner/scene.gltf; do
    [ -f "$scene" ] || continue
    name=$(basename "$(dirname "$scene")")/$(basename "$scene")
    bin/lie-build "$scene" -q -o "$TMP/c.lie"
    for mode in "lie" "full"; do
        set -- ; [ "$mode" = full ] && set -- --visibility=full
        tv=$(best build/v3/bin "$TMP/c.lie" "$TMP/v3.exr" "$@")
        tp=$(best bin "$TMP/c.lie" "$TMP/p.exr" "$@")
        same=same; cmp -s "$TMP/v3.exr" "$TMP/p.exr" || same=DIFFER
        r=$(awk -v a="$tp" -v b="$tv" 'BEGIN { printf "%.3f", a / b }')
        printf '%-28s %-22s %10s %10s %7s %s\n' "$name" "$mode" "$tv" "$tp" "$r" "$same"
        json="$json{\"scene\":\"$name\",\"mode\":\"$mode\",\"v3_s\":$tv,\"portable_s\":$tp,\"ratio\":$r,\"bytes\":\"$same\"},"
    done
done
echo "${json%,}]" >out/bench-arch.json
echo "bench/arch: ratio = portable / v3 render time (above 1: the portable build is slower); out/bench-arch.json"
