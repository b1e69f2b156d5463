#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench: what a frame costs at a fixed budget as the emitters grow.
# museum1 lit by one small panel (bench/museum1-1light.yaml) against 20
# such panels (bench/museum1-20lights.yaml) and 200 smaller ones (written
# here), at N light samples per point
# (the budget, shared among the emitters), full visibility and the LIE,
# side by side in one run, best of REPEAT: with a light tree a frame's cost
# should grow with log(emitters), not with their number.  The per-emitter
# sampler (the paper's N of every emitter) is the row it replaces.  A point's
# picks (pairs/point: at most N) grow with the emitters until the budget caps
# them, and each costs a lookup and a closed form or a few samples: the LIE's
# ratio follows them (docs/measurements.md, "Equal quality on the real
# scenes, quiet machine").
# Writes out/bench-lights-scale.json.
# The caches hold every unit (--frames 0), as for the paper's tables
# (bench/run.sh): the cost of a pick, not the cost model's choices.
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

bin/lie-build tests/scenes/museum1.gltf --frames 0 -q --threads "$THREADS" --edit bench/museum1-1light.yaml -o "$TMP/l1.lie"
bin/lie-build tests/scenes/museum1.gltf --frames 0 -q --threads "$THREADS" --edit bench/museum1-20lights.yaml -o "$TMP/l20.lie"
# 200 smaller panels on a 20 x 10 grid under the same ceiling: past the
# budget, the pairs a point answers stop growing with the emitters
awk -v f="$PWD/tests/scenes/museum1.gltf" 'BEGIN {
    print "- scale: {node: Light, by: [0.1, 1, 0.1]}"
    print "- move: {node: Light, to: [-4, 3.495, -3]}"
    for (i = 0; i < 20; i++) for (j = 0; j < 10; j++) {
        if (i == 0 && j == 0) continue
        printf "- add: {file: %s, node: Light, as: L%d_%d, transform: {translation: [%.4f, 3.495, %.4f], scale: [0.1, 1, 0.1]}}\n", f, i, j, -4 + 8 * i / 19, -3 + 6 * j / 9
    }
}' >"$TMP/200.yaml"
bin/lie-build tests/scenes/museum1.gltf --frames 0 -q --threads "$THREADS" --edit "$TMP/200.yaml" -o "$TMP/l200.lie"

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

echo "bench-lights-scale: museum1, 1 panel against 20 and 200, $SIZE, $N light samples, $THREADS threads, best of $REPEAT (load $(uptime | sed 's/.*load average: //'))"
printf '  %-20s %9s %9s %9s %7s %7s %21s %21s  %s\n' method "1 light" "20" "200" "20/1" "200/20" "rays/point" "pairs/point" "s per pair/point"
json="{\"samples\":$N,\"size\":\"$SIZE\",\"rows\":["
first=1
for m in "full tree|--visibility=full" "LIE tree|" "full per-emitter|--visibility=full --light-sampler per-emitter" \
         "LIE per-emitter|--light-sampler per-emitter"; do
    name=${m%%|*}; args=${m#*|}
    # shellcheck disable=SC2086
    t1=$(time_of "$TMP/l1.lie" --light-samples "$N" $args); r1=$(cat "$TMP/rays"); p1=$(cat "$TMP/pairs")
    # shellcheck disable=SC2086
    t20=$(time_of "$TMP/l20.lie" --light-samples "$N" $args); r20=$(cat "$TMP/rays"); p20=$(cat "$TMP/pairs")
    # the per-emitter rows at 200 lights would take N samples of each of
    # them: 3,200 times the budget's work, for nothing the table needs
    t200=0 r200=0 p200=0
    case $name in *per-emitter) ;; *)
        # shellcheck disable=SC2086
        t200=$(time_of "$TMP/l200.lie" --light-samples "$N" $args); r200=$(cat "$TMP/rays"); p200=$(cat "$TMP/pairs") ;;
    esac
    ratio=$(awk -v a="$t20" -v b="$t1" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }')
    ratio200=$(awk -v a="$t200" -v b="$t20" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }')
    # seconds per pair answered per point: what each pick costs
    pick=$(awk -v t1="$t1" -v p1="$p1" -v t2="$t200" -v p2="$p200" -v t20="$t20" -v p20="$p20" 'BEGIN {
        printf "%.3f", (p1 > 0 ? t1 / p1 : 0); printf " %.3f", (p20 > 0 ? t20 / p20 : 0); if (p2 > 0) printf " %.3f", t2 / p2 }')
    printf '  %-20s %9.3f %9.3f %9.3f %7s %7s %5s->%5s->%6s %5s->%5s->%6s  %s\n' "$name" "$t1" "$t20" "$t200" "$ratio" "$ratio200" \
        "$r1" "$r20" "$r200" "$p1" "$p20" "$p200" "$pick"
    [ $first -eq 1 ] || json="$json,"
    first=0
    json="$json{\"method\":\"$name\",\"seconds_1\":$t1,\"seconds_20\":$t20,\"ratio\":$ratio,\"seconds_200\":$t200,\"ratio_200_20\":$ratio200,\"rays_per_point_200\":$r200,\"pairs_per_point_200\":$p200,\"rays_per_point_1\":$r1,\"rays_per_point_20\":$r20,\"pairs_per_point_1\":$p1,\"pairs_per_point_20\":$p20}"
done
echo "  (log2(20) = 4.3, log2(200) / log2(20) = 1.8: a point's pairs grow with the emitters up to the budget N,"
echo "   and each pair's descent through the tree with log2(emitters); 0 seconds: not measured)"
echo "$json]}" >out/bench-lights-scale.json
echo "bench-lights-scale: wrote out/bench-lights-scale.json"
