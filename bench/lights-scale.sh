#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench: what a frame costs at a fixed budget as the emitters grow.
# museum1 lit by one small panel (bench/museum1-1light.yaml) against 20
# such panels (bench/museum1-20lights.yaml), at N light samples per point
# (the budget, shared among the emitters), full visibility and the LIE,
# side by side in one run, best of REPEAT: with a light tree a frame's cost
# should grow with log(emitters), not with their number.  The per-emitter
# sampler (the paper's N of every emitter) is the row it replaces.  A point's
# picks (pairs/point: at most N) grow with the emitters until the budget caps
# them, and each costs a lookup and a closed form or a few samples: the LIE's
# ratio follows them (docs/measurements.md, "Equal quality on the real
# scenes, quiet machine").
# Writes out/bench-lights-scale.json.
set -e
cd "$(dirname "$0")/.."
N=${N:-64}
SIZE=${SIZE:-256x256}
REPEAT=${REPEAT:-3}
THREADS=${THREADS:-2}
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
mkdir -p out
field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p" | head -1; }
best() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b < a) print b; else print a }'; }

bin/lie-build tests/scenes/museum1.gltf -q --threads "$THREADS" --edit bench/museum1-1light.yaml -o "$TMP/l1.lie"
bin/lie-build tests/scenes/museum1.gltf -q --threads "$THREADS" --edit bench/museum1-20lights.yaml -o "$TMP/l20.lie"

# time CACHE ARGS...: best seconds_render of REPEAT; shadow rays per shading
# point in $TMP/rays, and (emitter, point) pairs answered per shading point in
# $TMP/pairs: a frame's cost follows its pairs (each a class lookup, a closed
# form or samples), which grow with the emitters until the budget caps them
time_of() {
    c=$1; shift
    t=""; i=0
    while [ $i -lt "$REPEAT" ]; do
        bin/lie-render "$c" -q --size "$SIZE" --threads "$THREADS" --stats=json -o "$TMP/x.exr" "$@" 2>"$TMP/s.json"
        t=$(best "$t" "$(field seconds_render <"$TMP/s.json")")
        i=$((i + 1))
    done
    awk -v r="$(field shadow_rays <"$TMP/s.json")" -v p="$(field shading_points <"$TMP/s.json")" \
        'BEGIN { printf "%.1f", (p > 0 ? r / p : 0) }' >"$TMP/rays"
    pairs=0
    for k in occluded analytic exact blockers embree unshadowed bitmask; do
        pairs=$((pairs + $(field "pairs_$k" <"$TMP/s.json")))
    done
    awk -v r="$pairs" -v p="$(field shading_points <"$TMP/s.json")" \
        'BEGIN { printf "%.1f", (p > 0 ? r / p : 0) }' >"$TMP/pairs"
    echo "$t"
}

echo "bench-lights-scale: museum1, 1 panel against 20, $SIZE, $N light samples, $THREADS threads, best of $REPEAT (load $(uptime | sed 's/.*load average: //'))"
printf '  %-28s %10s %10s %8s %14s %14s\n' method "1 light s" "20 lights s" ratio "rays/point" "pairs/point"
json="{\"samples\":$N,\"size\":\"$SIZE\",\"rows\":["
first=1
for m in "full tree|--visibility=full" "LIE tree|" "full per-emitter|--visibility=full --light-sampler per-emitter" \
         "LIE per-emitter|--light-sampler per-emitter"; do
    name=${m%%|*}; args=${m#*|}
    # shellcheck disable=SC2086
    t1=$(time_of "$TMP/l1.lie" --light-samples "$N" $args); r1=$(cat "$TMP/rays"); p1=$(cat "$TMP/pairs")
    # shellcheck disable=SC2086
    t20=$(time_of "$TMP/l20.lie" --light-samples "$N" $args); r20=$(cat "$TMP/rays"); p20=$(cat "$TMP/pairs")
    ratio=$(awk -v a="$t20" -v b="$t1" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }')
    printf '  %-28s %10.3f %10.3f %8s %6s -> %5s %6s -> %5s\n' "$name" "$t1" "$t20" "$ratio" "$r1" "$r20" "$p1" "$p20"
    [ $first -eq 1 ] || json="$json,"
    first=0
    json="$json{\"method\":\"$name\",\"seconds_1\":$t1,\"seconds_20\":$t20,\"ratio\":$ratio,\"rays_per_point_1\":$r1,\"rays_per_point_20\":$r20,\"pairs_per_point_1\":$p1,\"pairs_per_point_20\":$p20}"
done
echo "  (log2(20) = 4.3: a cost that grows with the logarithm of the emitters stays well under it)"
echo "$json]}" >out/bench-lights-scale.json
echo "bench-lights-scale: wrote out/bench-lights-scale.json"
