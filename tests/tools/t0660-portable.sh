#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Baseline x86-64: the tools run on a CPU without AVX (qemu-user emulating a Nehalem, SSE4.2
# at most), and give there the same bytes as here, where the hot kernels run their AVX2
# copies (lib/core/hot.h) and Embree its AVX2 kernels: a cache built on each, and renders
# through the cache, with full visibility and with sampled shadows.  FMA instructions appear
# only where the source asks for fmaf: -ffp-contract=off contracts nothing.
. "$(dirname "$0")/lib.sh"
Q="qemu-x86_64 -cpu Nehalem"
# AddressSanitizer's shadow memory cannot be mapped under qemu-user: `make test`'s ASan pass
# checks the release binaries it built first, the ones that ship
if [ "${VARIANT:-release}" = asan ]; then
    B="$ROOT/bin"
    [ -x "$B/lie-render" ] || { not_ok "the ASan pass needs the release build in bin/ (make test builds it first)"; finish; }
fi
command -v qemu-x86_64 >/dev/null 2>&1 || { not_ok "qemu-x86_64 is missing (make deps: qemu-user)"; finish; }

run $Q "$B/lie-render" --version
expect_rc 0 "lie-render --version on an emulated Nehalem"
if grep -q avx2 /proc/cpuinfo; then
    # the library's resolvers pick the AVX2 copies here (one symbol for each copy)
    nm "$B/lie-render" | grep -q 'prepare_2d\.arch_x86_64_v3' && ok "the AVX2 copies are in the binary" \
        || not_ok "no arch_x86_64_v3 copy of prepare_2d in lie-render"
else
    not_ok "this test needs an AVX2 machine to compare the two copies (no avx2 in /proc/cpuinfo)"
fi

run $Q "$B/lie-build" -q "$S/cornell.gltf" -o "$TMP/q.lie"
expect_rc 0 "lie-build under Nehalem"
run "$B/lie-build" -q "$S/cornell.gltf" -o "$TMP/n.lie"
expect_same "$TMP/q.lie" "$TMP/n.lie" "the caches are the same bytes"
for opt in "" "--visibility=full" "--exact=off" "--light-sampler=per-emitter --bitmask=only"; do
    run $Q "$B/lie-render" "$TMP/n.lie" -q --size 24x20 --light-samples 24 $opt -o "$TMP/q.exr"
    expect_rc 0 "lie-render $opt under Nehalem"
    run "$B/lie-render" "$TMP/n.lie" -q --size 24x20 --light-samples 24 $opt -o "$TMP/n.exr"
    expect_same "$TMP/q.exr" "$TMP/n.exr" "lie-render $opt: the same image bytes on Nehalem and here"
done

# every FMA instruction of lie-render comes from a source line that calls fmaf (or the FMA
# intrinsics' header): none was contracted from a multiply and an add
lines=$(objdump -d -l --no-show-raw-insn "$B/lie-render" 2>/dev/null |
    awk '/^\/.*:[0-9]+/ {loc = $1} /\tvf(n)?m(add|sub)/ {print loc}' | sort -u)
n_fma=$(echo "$lines" | grep -c .)
bad=""
for l in $lines; do
    f=${l%%:*}; k=${l##*:}; k=${k%% *}
    case "$f" in */fmaintrin.h) continue;; esac
    sed -n "${k}p" "$f" 2>/dev/null | grep -q 'fma' || bad="$bad $l"
done
[ "$n_fma" -gt 0 ] && [ -z "$bad" ] && ok "all $n_fma source lines with FMA instructions call fmaf" \
    || not_ok "FMA instructions from lines without fmaf:$bad"
finish
