#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Progress (issue 18): on a terminal (script -qc gives the tool one) a bar
# with elapsed time, rate and ETA, "frame N/M" on camera paths, progress in
# lie-build and rst-update; nothing when stderr is not a terminal; -v prints
# each phase's time (lie-render, lie-build, rst-update).
. "$(dirname "$0")/lib.sh"
if ! command -v script >/dev/null 2>&1; then not_ok "script(1) missing (util-linux)"; finish; fi
cd "$TMP" || exit 1
SC="$S/cornell.gltf"
# tty CMD...: run CMD on a pseudo-terminal; its output, \r as new lines, in tty.out
tty() { script -qc "$*" /dev/null </dev/null | tr '\r' '\n' | sed 's/\x1b\[K//g' >tty.out 2>&1; }
has() { # PATTERN WHAT
    if grep -qE -- "$1" tty.out; then ok "$2"; else not_ok "$2: no /$1/ in:"; sed 's/^/# /' tty.out | tail -5; fi
}

tty "$B/lie-render" "$SC" -o r.exr --size 160x160 --light-samples 8 --threads 2
has '^render \[#+\] 100% [0-9.]+ s, [0-9.e+]+ tiles/s, ETA [0-9.]+ s' "lie-render: bar with elapsed, rate, ETA"
cat >path.yaml <<'YAML'
interpolation: linear
keys:
  - eye: [0.278, 0.273, -0.8]
    target: [0.278, 0.273, 0.5]
    frames: 2
  - eye: [0.3, 0.3, -0.7]
    target: [0.278, 0.273, 0.5]
YAML
tty "$B/lie-render" "$SC" --path path.yaml -o "f_%02d.exr" --size 64x64 --light-samples 4
has '^frame 1/3 \[' "camera path: frame 1/3"
has '^frame 3/3 \[#+\] 100%' "camera path: frame 3/3 to the end"

tty "$B/lie-build" "$SC" -o c.lie --threads 2
has '^lie-build \[#+\] 100% [0-9.]+ s, [0-9.e+]+%/s, ETA' "lie-build: bar with elapsed, rate, ETA"
printf '%s\n' '- move: {node: TallBlock, by: [0.05, 0, 0]}' >e.yaml
tty "$B/rst-update" c.lie e.yaml -o u.lie
has '^rst-update \[#+\] 100%' "rst-update: bar"

# not a terminal: silent
run "$B/lie-render" "$SC" -o r2.exr --size 64x64 --light-samples 4
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "lie-render: silent when stderr is not a terminal"; else
    not_ok "lie-render printed: $(head -c 200 "$TMP/err")"; fi
run "$B/lie-build" "$SC" -o c2.lie
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "lie-build: silent when not a terminal"; else
    not_ok "lie-build printed: $(head -c 200 "$TMP/err")"; fi
# -q on a terminal: no bar
tty "$B/lie-render" "$SC" -o r3.exr --size 64x64 --light-samples 4 -q
if [ ! -s tty.out ]; then ok "-q: no bar on a terminal"; else not_ok "-q printed: $(head -c 200 tty.out)"; fi

# -v: one line per phase, also when not a terminal
run "$B/lie-render" "$SC" -o r4.exr --size 32x32 --light-samples 2 -v
if [ "$(grep -cE '^lie-render: (load|bvh|render|write): [0-9]+\.[0-9]{3} s$' "$TMP/err")" -eq 4 ] &&
    [ "$(wc -l <"$TMP/err")" -eq 4 ]; then ok "lie-render -v: load, bvh, render, write"; else
    not_ok "lie-render -v:"; sed 's/^/# /' "$TMP/err"; fi
run "$B/lie-render" "$SC" --path path.yaml -o "v_%02d.exr" --size 32x32 --light-samples 2 -v
if grep -qE '^lie-render: frame 2: render: ' "$TMP/err" && grep -qE '^lie-render: frame 2: write: ' "$TMP/err"; then
    ok "lie-render -v on a path: per-frame phases"; else not_ok "path -v:"; sed 's/^/# /' "$TMP/err"; fi
run "$B/lie-build" "$SC" -o c3.lie -v
if [ "$(grep -cE '^lie-build: (load|bvh|build|write): [0-9]+\.[0-9]{3} s$' "$TMP/err")" -eq 4 ]; then
    ok "lie-build -v: load, bvh, build, write"; else not_ok "lie-build -v:"; sed 's/^/# /' "$TMP/err"; fi
expect_same c.lie c3.lie "-v and a terminal change no byte of the cache"
run "$B/rst-update" c.lie e.yaml -o u2.lie -v
if [ "$(grep -cE '^rst-update: (load|trees|edits|update|write): [0-9]+\.[0-9]{3} s$' "$TMP/err")" -eq 5 ] &&
    [ "$(wc -l <"$TMP/err")" -eq 5 ]; then ok "rst-update -v: load, trees, edits, update, write"; else
    not_ok "rst-update -v:"; sed 's/^/# /' "$TMP/err"; fi
expect_same u.lie u2.lie "rst-update: -v and a terminal change no byte of the cache"
finish
