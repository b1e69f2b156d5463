#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make fuzz: build every reader's libFuzzer target with clang and run each
# for a bounded time, reporting executions and crashes.
#
#   FUZZ_SECONDS   seconds per target (default 60)
#   FUZZ_RUNS      stop a target after this many executions instead (the
#                  time limit still applies)
#   FUZZ_TARGETS   which targets (default: every tests/fuzz/fuzz_*.c)
#   CLANG, CLANGXX the compilers (default clang, clang++)
#
# The library is built with -fsanitize=fuzzer-no-link,address,undefined into
# build/fuzz/ (make VARIANT=fuzz), the targets link with -fsanitize=fuzzer.
# Corpora grow in build/fuzz/corpus/TARGET/, seeded from the bundled scenes
# and test files, tests/fuzz/seeds/TARGET/ and caches built by bin/lie-build
# at fuzz time; crashes land in build/fuzz/crashes/TARGET/.  A crash found
# becomes a file under tests/fuzz/regressions/TARGET/ (replayed by
# `make test` through tests/unit/test_fuzz_regressions.c) and a fix.
# Exit 0 when no target crashed, 1 otherwise.
set -u
cd "$(dirname "$0")/../.." || exit 2
ROOT=$(pwd)
SECONDS_EACH=${FUZZ_SECONDS:-60}
CLANG=${CLANG:-clang}
CLANGXX=${CLANGXX:-clang++}
OUT=build/fuzz
SAN="-fsanitize=address,undefined -fno-sanitize-recover=all"

command -v "$CLANG" >/dev/null 2>&1 || { echo "fuzz: $CLANG not found (libFuzzer needs clang)" >&2; exit 2; }

echo "fuzz: building the library with $CLANG (libFuzzer, ASan, UBSan) into $OUT/"
make -s VARIANT=fuzz CC="$CLANG" CXX="$CLANGXX" WERROR= \
    "OPT_fuzz=-O1 -g -fno-omit-frame-pointer -Wno-pass-failed -fsanitize=fuzzer-no-link $SAN" "$OUT/liblie.a" || exit 2
LDLIBS=$(make -s print-libs)
CFLAGS="-std=c11 -O1 -g -fno-omit-frame-pointer -D_GNU_SOURCE -Ilib -DTEST_SCENES=\"$ROOT/tests/scenes\""

targets=${FUZZ_TARGETS:-$(for f in tests/fuzz/fuzz_*.c; do basename "$f" .c | sed 's/^fuzz_//'; done)}
for t in $targets; do
    mkdir -p "$OUT/bin"
    # shellcheck disable=SC2086
    "$CLANG" $CFLAGS -fsanitize=fuzzer $SAN -c "tests/fuzz/fuzz_$t.c" -o "$OUT/fuzz_$t.o" &&
        "$CLANGXX" -fsanitize=fuzzer $SAN "$OUT/fuzz_$t.o" "$OUT/liblie.a" $LDLIBS -o "$OUT/bin/fuzz_$t" ||
        { echo "fuzz: cannot build fuzz_$t" >&2; exit 2; }
done

# Seeds: files in the repository, and caches made now (their format may change).
seed() { # TARGET FILE...
    dir="$OUT/seeds/$1"
    shift
    mkdir -p "$dir"
    for f in "$@"; do [ -f "$f" ] && cp "$f" "$dir/"; done
}
seed gltf tests/scenes/*.gltf tests/data/gltf/*.gltf tests/data/gltf/*.glb tests/data/gltf/escape/*.gltf
seed edit tests/fuzz/seeds/edit/* examples/edits/*.yaml
seed campath tests/fuzz/seeds/campath/*
seed fileset tests/fuzz/seeds/fileset/*
seed cache tests/fuzz/seeds/cache/* # older format versions, which the reader still takes
mkdir -p "$OUT/seeds/cache"
if make -s all >/dev/null 2>&1; then
    c="$OUT/seeds/cache"
    bin/lie-build tests/scenes/cornell.gltf -q --samples 8 --max-samples 16 --min-patch 0.01 -o "$c/cornell.lie"
    bin/lie-build tests/scenes/cornell.gltf -q --samples 4 --max-samples 4 --min-patch 0.3 --blockers conservative -o "$c/cornell-c.lie"
    bin/lie-build tests/scenes/museum3.gltf -q --samples 2 --max-samples 2 --min-patch 1 -o "$c/museum3.lie"
    bin/lie-build tests/data/gltf/lights_cameras.gltf -q --samples 4 --min-patch 0.1 -o "$c/lights.lie"
    # a view build: its unseen units are ROOTS tags (formats/lie-cache.md, version 6)
    bin/lie-build tests/scenes/cornell.gltf -q --samples 4 --max-samples 4 --min-patch 0.1 --view 0 \
        --view-size 32x32 -o "$c/cornell-view.lie"
    printf '%s\n' '- rotate: {node: TallBlock, axis: [0, 1, 0], degrees: -20}' >"$OUT/tall.yaml"
    bin/rst-update "$c/cornell.lie" "$OUT/tall.yaml" -q -o "$c/cornell-edited.lie"
else
    echo "fuzz: could not build bin/ for cache seeds; fuzzing caches from regressions only" >&2
fi

status=0
for t in $targets; do
    corpus="$OUT/corpus/$t" crashes="$OUT/crashes/$t"
    mkdir -p "$corpus" "$crashes" "tests/fuzz/regressions/$t"
    dict=""
    [ -f "tests/fuzz/$t.dict" ] && dict="-dict=tests/fuzz/$t.dict"
    before=$(ls "$crashes" | wc -l)
    # shellcheck disable=SC2086
    "$OUT/bin/fuzz_$t" -max_total_time="$SECONDS_EACH" ${FUZZ_RUNS:+-runs=$FUZZ_RUNS} -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -print_final_stats=1 -artifact_prefix="$crashes/" $dict \
        "$corpus" "$OUT/seeds/$t" "tests/fuzz/regressions/$t" >"$OUT/$t.log" 2>&1
    rc=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$OUT/$t.log" | tail -1)
    after=$(ls "$crashes" | wc -l)
    found=$((after - before))
    secs=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$OUT/$t.log" | tail -1)
    echo "fuzz: $t: ${runs:-?} executions in ${secs:-$SECONDS_EACH} s, corpus $(ls "$corpus" | wc -l) inputs, $found new crash$( [ $found -eq 1 ] || echo es)"
    if [ $rc -ne 0 ] || [ $found -ne 0 ]; then
        status=1
        grep -m1 -E 'ERROR|runtime error|deadly signal' "$OUT/$t.log" | sed "s/^/fuzz: $t: /"
        echo "fuzz: $t: see $OUT/$t.log and $crashes/"
    fi
done
exit $status
