#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# A whole build's cost model (docs/algorithms.md, "Whole builds"): without
# --view, the units whose emitter's share of the light cannot pay over
# frames of --view-size pixels spread over the surface are left unbuilt,
# and --stats says how many and what a frame saves; larger frames build
# more, --frames 0 builds every unit; an edit of the light updates into a
# rebuild's bytes; the image agrees with full visibility.
. "$ROOT/tests/tools/lib.sh"
{
    echo "- scale: {node: Light, by: [0.3, 1, 0.3]}"
    echo "- move: {node: Light, to: [-3, 3.495, -2]}"
    echo "- add: {file: $S/museum1.gltf, node: Light, as: Light2, transform: {translation: [3, 3.495, 2], scale: [0.3, 1, 0.3]}}"
} >"$TMP/two.yaml"
ARGS="--min-patch 1e-2 --edit $TMP/two.yaml"
# shellcheck disable=SC2086
run "$B/lie-build" "$S/museum1.gltf" $ARGS -q --stats=json -o "$TMP/w.lie"
expect_rc 0 "whole build with the model"
unpaid=$(field units_unpaid <"$TMP/err"); px=$(field whole_pixels <"$TMP/err")
saving=$(field saving_s_per_frame_predicted <"$TMP/err")
if [ "${unpaid:-0}" -gt 0 ] && [ "$px" = 262144 ] && awk -v s="$saving" 'BEGIN { exit !(s > 0) }'; then
    ok "--stats: $unpaid units left unpaid in frames of $px pixels, a frame saves $saving s"
else not_ok "--stats: units_unpaid '$unpaid', whole_pixels '$px', saving '$saving'"; fi
# shellcheck disable=SC2086
run "$B/lie-build" "$S/museum1.gltf" $ARGS --view-size 2048x2048 -q --stats=json -o "$TMP/big.lie"
big=$(field units_unpaid <"$TMP/err")
if [ "${big:-0}" -lt "$unpaid" ]; then ok "larger frames leave fewer units unpaid ($big < $unpaid)"; else
    not_ok "larger frames: $big units unpaid, not fewer than $unpaid"; fi
# shellcheck disable=SC2086
run "$B/lie-build" "$S/museum1.gltf" $ARGS --frames 0 -q --stats=json -o "$TMP/all.lie"
none=$(sed -n 's/.*"none":\([0-9]*\).*/\1/p' <"$TMP/err")
[ "$none" = 0 ] && ok "--frames 0 builds every unit" || not_ok "--frames 0 left $none units unbuilt"

# an edit of the light: the model decides the units again, as a rebuild does
echo "- set-emission: {node: Light2, strength: 0.2}" >"$TMP/dim.yaml"
run "$B/rst-update" "$TMP/w.lie" "$TMP/dim.yaml" -q -o "$TMP/upd.lie"
expect_rc 0 "rst-update of the light"
# shellcheck disable=SC2086
run "$B/lie-build" "$S/museum1.gltf" $ARGS --edit "$TMP/dim.yaml" -q -o "$TMP/reb.lie"
run "$B/lie-inspect" diff "$TMP/upd.lie" "$TMP/reb.lie"
expect_rc 0 "rst-update of the light = lie-build --edit (lie-inspect diff)"

run "$B/lie-render" "$TMP/w.lie" -q --size 64x64 --visibility=full -o "$TMP/full.exr"
run "$B/lie-render" "$TMP/w.lie" -q --size 64x64 --exact off -o "$TMP/lie.exr"
expect_near_full "$TMP/full.exr" "$TMP/lie.exr" "whole build with the model"
finish
