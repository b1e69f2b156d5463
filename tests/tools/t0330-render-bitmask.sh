#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# All light samples at once (lib/shade/bitmask.h): a LIE image whose
# partial pairs are answered as bitmasks, at 16k fixed samples, against
# full visibility at 1k and 16k rotated samples.  The reference's noise
# falls as 1/sqrt(N), so the difference must shrink with it (at least 2x
# from 1k to 16k).  Also: the pairs took the path, the same image for 1
# and 2 threads, the same samples as --exact off within rounding, and the
# CLI's modes.  Bitmasks answer the per-emitter sampler's fixed pattern.
. "$ROOT/tests/tools/lib.sh"
PE="--light-sampler per-emitter"


for scene in cornell museum1; do
    run "$B/lie-build" "$S/$scene.gltf" -q --blockers conservative -o "$TMP/$scene.lie"
    expect_rc 0 "$scene: conservative build"
    run "$B/lie-render" $PE "$TMP/$scene.lie" -q --size 32x32 --light-samples 16384 --bitmask only --stats=json \
        -o "$TMP/$scene-b.exr"
    expect_rc 0 "$scene: bitmask render at 16k samples"
    nb=$(field pairs_bitmask <"$TMP/err")
    if [ "${nb:-0}" -gt 0 ]; then ok "$scene: $nb partial pairs answered as bitmasks"
    else not_ok "$scene: no pair took the bitmask path: $(cat "$TMP/err")"; fi
    expect_converges bitmask "$scene" "$TMP/$scene-b.exr"
done

# the same samples as the per-sample path: only the estimator's rounding
# and its control variate differ
run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 48x40 --light-samples 1024 --bitmask only -o "$TMP/b.exr"
run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 48x40 --light-samples 1024 --exact off -o "$TMP/s.exr"
"$H/exr-compare" --error "$TMP/s.exr" "$TMP/b.exr" >"$TMP/bs.json"
p=$(field p99 <"$TMP/bs.json")
if awk -v p="$p" 'BEGIN { exit !(p <= 0.005) }'; then ok "bitmask vs per-sample at 1024 samples: p99 $p (<= 0.5%)"
else not_ok "bitmask vs per-sample at 1024 samples: p99 $p"; fi

run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 48x40 --light-samples 1024 --bitmask only --threads 1 -o "$TMP/t1.exr"
run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 48x40 --light-samples 1024 --bitmask only --threads 2 -o "$TMP/t2.exr"
expect_same "$TMP/t1.exr" "$TMP/t2.exr" "bitmask frames identical for 1 and 2 threads"

run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 32x32 --light-samples 1024 --bitmask off --stats=json -o "$TMP/o.exr"
if [ "$(field pairs_bitmask <"$TMP/err")" = 0 ]; then ok "--bitmask off: no bitmask pairs"
else not_ok "--bitmask off: $(cat "$TMP/err")"; fi
run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 32x32 --light-samples 1024 --exact off --stats=json -o "$TMP/o.exr"
if [ "$(field pairs_bitmask <"$TMP/err")" = 0 ]; then ok "--exact off (the oracle's mode): no bitmask pairs"
else not_ok "--exact off: $(cat "$TMP/err")"; fi
run "$B/lie-render" $PE "$TMP/museum1.lie" -q --size 8x8 --bitmask sometimes -o "$TMP/u.exr"
expect_rc 2 "--bitmask with an unknown mode"
run "$B/lie-render" "$TMP/museum1.lie" -q --size 8x8 --bitmask only -o "$TMP/u.exr"
expect_rc 2 "--bitmask only needs the per-emitter sampler"
finish
