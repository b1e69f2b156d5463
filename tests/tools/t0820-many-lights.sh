#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Many lights (docs/algorithms.md, "Many lights"): museum1 lit by six small panels an edit file adds.
# The build is the same for any thread count, its image agrees with full
# visibility, and rst-update of a moved light equals a rebuild.  The pairs of the six panels are each proven visible by a
# probe of their shafts where nothing enters them (lib/lie/sample.c).
. "$ROOT/tests/tools/lib.sh"
SIZE=96x96
{
    echo "- scale: {node: Light, by: [0.3, 1, 0.3]}"
    echo "- move: {node: Light, to: [-3, 3.495, -2]}"
    i=1
    for p in "-3 2" "0 -2" "0 2" "3 -2" "3 2"; do
        i=$((i + 1)); set -- $p
        echo "- add: {file: $S/museum1.gltf, node: Light, as: Light$i, transform: {translation: [$1, 3.495, $2], scale: [0.3, 1, 0.3]}}"
    done
} >"$TMP/six.yaml"
ARGS="--min-patch 1e-2"
run "$B/lie-build" "$S/museum1.gltf" --edit "$TMP/six.yaml" $ARGS -q --threads 1 --stats=json -o "$TMP/t1.lie"
expect_rc 0 "six lights: build on 1 thread"
emitters=$(field emitters <"$TMP/err")
[ "$emitters" = 6 ] && ok "six lights: 6 emitters" || not_ok "six lights: $emitters emitters, not 6"
run "$B/lie-build" "$S/museum1.gltf" --edit "$TMP/six.yaml" $ARGS -q --threads 2 -o "$TMP/t2.lie"
expect_rc 0 "six lights: build on 2 threads"
expect_same "$TMP/t1.lie" "$TMP/t2.lie" "six lights: identical caches for 1 and 2 threads"

run "$B/lie-render" "$TMP/t1.lie" -q --size $SIZE --visibility=full -o "$TMP/full.exr"
expect_rc 0 "six lights: reference render"
run "$B/lie-render" "$TMP/t1.lie" -q --size $SIZE --exact off -o "$TMP/lie.exr"
expect_rc 0 "six lights: LIE render"
expect_near_full "$TMP/full.exr" "$TMP/lie.exr" "six lights"

# update = rebuild, byte for byte, for a moved light (a moved object:
# t0400); an update gives the same bytes for 1 and 2 threads
printf -- '- move: {node: Light4, by: [0.6, 0, 0.4]}\n' >"$TMP/light.yaml"
run "$B/rst-update" "$TMP/t1.lie" "$TMP/light.yaml" -q --threads 2 -o "$TMP/u2.lie"
expect_rc 0 "six lights: rst-update (a light moved)"
run "$B/rst-update" "$TMP/t1.lie" "$TMP/light.yaml" -q --full -o "$TMP/f.lie"
expect_same "$TMP/u2.lie" "$TMP/f.lie" "six lights: update = rebuild (a light moved)"
run "$B/rst-update" "$TMP/t1.lie" "$TMP/light.yaml" -q --threads 1 -o "$TMP/u1.lie"
expect_same "$TMP/u1.lie" "$TMP/u2.lie" "six lights: identical updates for 1 and 2 threads"
finish
