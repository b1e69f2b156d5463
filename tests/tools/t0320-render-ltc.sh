#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# GGX receivers in closed form (lib/shade/ltc.h) under --light-samples exact:
# a Cornell box whose floor, back wall and short block are made glossy
# (rst-update set-material) rendered from its cache with exact shadows and
# LTC shading, against full visibility with sampled shading at 1k and 16k
# rotated samples.  An LTC is a fit of the BRDF, so the difference stops
# shrinking at the fit's bias (measured on 32x32: rmse 1.1%, p99 6.1% at
# 16k samples, 1.3% at 1k: the reference's noise is already near the
# bias); the bounds leave room for noise only.  Also: every pair took a
# closed form, full visibility with LTC shading (the ratio estimator) against
# exact shadows, and thread-count determinism.
. "$ROOT/tests/tools/lib.sh"


cat >"$TMP/ggx.yaml" <<'EOF'
- set-material: {node: Floor, metallic: 0, roughness: 0.35}
- set-material: {node: BackWall, metallic: 0.5, roughness: 0.2}
- set-material: {node: ShortBlock, metallic: 0.2, roughness: 0.6}
EOF
run "$B/lie-build" "$S/cornell.gltf" -q --blockers conservative -o "$TMP/c.lie"
expect_rc 0 "conservative build"
run "$B/rst-update" "$TMP/c.lie" "$TMP/ggx.yaml" -q -o "$TMP/g.lie" --write-scene "$TMP/g.gltf"
expect_rc 0 "glossy materials by rst-update"
run "$B/lie-render" "$TMP/g.lie" -q --size 32x32 --light-samples exact --stats=json -o "$TMP/x.exr"
expect_rc 0 "exact render with GGX receivers"
sampled=$(( $(field pairs_blockers <"$TMP/err") + $(field pairs_embree <"$TMP/err") + $(field pairs_unshadowed <"$TMP/err") ))
closed=$(( $(field pairs_analytic <"$TMP/err") + $(field pairs_exact <"$TMP/err") ))
if [ "$sampled" -eq 0 ] && [ "$closed" -gt 0 ]; then ok "every lit pair in closed form ($closed pairs)"
else not_ok "pairs left to samples: $(cat "$TMP/err")"; fi

for ns in 1024 16384; do
    "$B/lie-render" "$TMP/g.gltf" -q --size 32x32 --visibility=full --pattern rotated \
        --light-samples $ns -o "$TMP/f$ns.exr"
    "$H/exr-compare" --error "$TMP/f$ns.exr" "$TMP/x.exr" >"$TMP/e$ns.json"
done
r16=$(field rmse <"$TMP/e16384.json"); p16=$(field p99 <"$TMP/e16384.json"); r1=$(field rmse <"$TMP/e1024.json")
if awk -v r="$r16" -v p="$p16" 'BEGIN { exit !(r <= 0.02 && p <= 0.09) }'; then
    ok "LTC + exact shadows vs full at 16k samples: rmse $r16, p99 $p16 (1k: rmse $r1)"
else not_ok "LTC + exact shadows vs full at 16k samples: rmse $r16 (> 0.02) or p99 $p16 (> 0.09)"; fi

# full visibility with LTC shading: the ratio estimator over its 100 samples
"$B/lie-render" "$TMP/g.gltf" -q --size 32x32 --visibility=full --pattern rotated --light-samples exact \
    -o "$TMP/fx.exr"
"$H/exr-compare" --error "$TMP/fx.exr" "$TMP/x.exr" >"$TMP/ex.json"
rx=$(field rmse <"$TMP/ex.json")
if awk -v r="$rx" 'BEGIN { exit !(r <= 0.04) }'; then ok "full visibility, LTC shading, ratio estimator: rmse $rx against exact"
else not_ok "full visibility with LTC shading: rmse $rx against exact (> 0.04)"; fi

run "$B/lie-render" "$TMP/g.lie" -q --size 24x20 --light-samples exact --threads 1 -o "$TMP/t1.exr"
run "$B/lie-render" "$TMP/g.lie" -q --size 24x20 --light-samples exact --threads 2 -o "$TMP/t2.exr"
expect_same "$TMP/t1.exr" "$TMP/t2.exr" "LTC frames identical for 1 and 2 threads"
finish
