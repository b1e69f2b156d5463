# SPDX-License-Identifier: Apache-2.0
# Helpers for tool tests (sourced).  Each check prints "ok N - what" or
# "not ok N - what" with the evidence; the script exits 1 if any failed.
set -u
n=0
failures=0
TMP=$(mktemp -d "${TMPDIR:-/tmp}/lie-test.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
B="$BINDIR_ABS"
H="$HELPERS_ABS"
S="$ROOT/tests/scenes"
D="$ROOT/tests/data"

ok() { n=$((n + 1)); echo "ok $n - $1"; }
not_ok() { n=$((n + 1)); failures=$((failures + 1)); echo "not ok $n - $1"; }

# run CMD...: runs with stdout/stderr captured to $TMP/out, $TMP/err; sets rc
run() { "$@" >"$TMP/out" 2>"$TMP/err"; rc=$?; }

# xvfb_run CMD...: CMD under a private Xvfb.  The server picks a free display
# itself and says which (-displayfd), so test runs side by side cannot take
# the same display, as two `xvfb-run -a` can (both pick the first unlocked one).
xvfb_run() {
    _xn="$TMP/xvfb.display.$$"
    rm -f "$_xn"
    Xvfb -displayfd 3 -screen 0 1024x768x24 -nolisten tcp 3>"$_xn" 2>/dev/null &
    _xp=$!
    _xi=0
    while [ ! -s "$_xn" ] && [ $_xi -lt 200 ] && kill -0 $_xp 2>/dev/null; do sleep 0.05; _xi=$((_xi + 1)); done
    if [ ! -s "$_xn" ]; then
        kill $_xp 2>/dev/null; wait $_xp 2>/dev/null
        echo "xvfb_run: Xvfb did not start" >&2; return 127
    fi
    DISPLAY=":$(cat "$_xn")" "$@"; _xr=$?
    kill $_xp 2>/dev/null; wait $_xp 2>/dev/null
    return $_xr
}

# need_viewer: what a lie-view test under Xvfb needs first.  X and SDL's
# libraries keep a few allocations to the end of the process (not ours), so
# LeakSanitizer is off for them; without Xvfb the test fails and ends.
need_viewer() {
    export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
    if ! command -v Xvfb >/dev/null 2>&1; then
        not_ok "Xvfb is missing (make deps installs xvfb)"
        finish
    fi
}

# expect_rc CODE WHAT
expect_rc() {
    if [ "$rc" -eq "$1" ]; then ok "$2 (exit $rc)"; else
        not_ok "$2: expected exit $1, got $rc"; sed 's/^/# /' "$TMP/err" | head -5; fi
}

# expect_one_error_line PREFIX WHAT: stderr is exactly one line starting with PREFIX
expect_one_error_line() {
    lines=$(wc -l <"$TMP/err")
    if [ "$lines" -eq 1 ] && head -1 "$TMP/err" | grep -qF -- "$1"; then ok "$2: $(cat "$TMP/err")"; else
        not_ok "$2: expected one line starting '$1', got $lines:"; sed 's/^/# /' "$TMP/err" | head -5; fi
}

expect_file() { if [ -s "$1" ]; then ok "$2"; else not_ok "$2: $1 missing or empty"; fi; }
expect_no_file() { if [ ! -e "$1" ]; then ok "$2"; else not_ok "$2: $1 exists"; fi; }
# no temporary files left in a directory
expect_no_temp() {
    if ls -a "$1" | grep -q '\.tmp'; then not_ok "$2: temporary file left in $1"; else ok "$2"; fi
}
expect_same() { if cmp -s "$1" "$2"; then ok "$3"; else not_ok "$3: $1 and $2 differ"; fi; }

# expect_near_full FULL.exr LIE.exr WHAT: the LIE image within 2% of full
# visibility on at least 99.9% of its pixels (exr-compare's report as evidence)
expect_near_full() {
    if "$H/exr-compare" "$1" "$2" 1 0.001 >"$TMP/cmp" 2>&1; then
        ok "$3: LIE image within 2% of full on >= 99.9% of pixels: $(cat "$TMP/cmp")"
    else not_ok "$3: LIE image against full: $(cat "$TMP/cmp")"; fi
}
finish() { [ "$failures" -eq 0 ]; exit $?; }

# a number member of one-line JSON on stdin: field NAME
field() { sed -n "s/.*\"$1\":\([0-9.e+-]*\).*/\1/p"; }

# expect_converges WHAT SCENE IMAGE: IMAGE (32x32, of tests/scenes/SCENE)
# against full visibility at 1k and 16k rotated samples: the RMSE must at
# least halve (the difference shrinks like the reference's noise) and the
# p99 error at 16k be <= 2%.
expect_converges() {
    for ns in 1024 16384; do
        "$B/lie-render" "$S/$2.gltf" -q --size 32x32 --visibility=full --pattern rotated \
            --light-samples $ns -o "$TMP/$2-f$ns.exr"
        "$H/exr-compare" --error "$TMP/$2-f$ns.exr" "$3" >"$TMP/$2-e$ns.json"
    done
    e1=$(field rmse <"$TMP/$2-e1024.json"); e16=$(field rmse <"$TMP/$2-e16384.json")
    p16=$(field p99 <"$TMP/$2-e16384.json")
    if awk -v a="$e1" -v b="$e16" 'BEGIN { exit !(b <= a / 2) }'; then
        ok "$2: $1 vs full, rmse $e1 at 1k samples, $e16 at 16k (shrinks with the reference's noise)"
    else not_ok "$2: $1 vs full did not converge: rmse $e1 at 1k samples, $e16 at 16k"; fi
    if awk -v p="$p16" 'BEGIN { exit !(p <= 0.02) }'; then ok "$2: p99 error against full at 16k is $p16 (<= 2%)"
    else not_ok "$2: p99 error against full at 16k is $p16 (> 2%)"; fi
}
