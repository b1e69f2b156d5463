#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Atomic outputs: a writer killed with SIGKILL leaves the previous output
# byte for byte (and creates nothing where there was nothing); a full disk
# is an error (exit 1, one line), not a short file.
#
# What a kill leaves behind: the temporary file (".NAME.tmpXXXXXX" next to
# the target) stays if the kill comes after it was created and before the
# rename; nothing can remove it then.  That is accepted: the target is
# intact, and the temporary is plainly named.
. "$ROOT/tests/tools/lib.sh"
SMALL="--samples 8 --max-samples 16 --min-patch 0.01 -q"

# shellcheck disable=SC2086
"$B/lie-build" "$S/cornell.gltf" $SMALL -o "$TMP/old.lie" || not_ok "build cornell"
printf '%s\n' '- rotate: {node: TallBlock, axis: [0, 1, 0], degrees: -20}' >"$TMP/tall.yaml"
mkdir -p "$TMP/k"

# 1. Killed while building (a long build of museum3, killed after a moment).
cp "$TMP/old.lie" "$TMP/k/out.lie"
"$B/lie-build" "$S/museum3.gltf" -q -o "$TMP/k/out.lie" 2>/dev/null &
pid=$!
sleep 1
kill -9 $pid 2>/dev/null
wait $pid 2>/dev/null
rc=$?
if [ "$rc" -eq 137 ]; then ok "lie-build museum3 killed with SIGKILL after 1 s"; else
    not_ok "lie-build was not killed (exit $rc): it finished in under a second?"; fi
expect_same "$TMP/old.lie" "$TMP/k/out.lie" "killed while building: the old cache is intact"
expect_no_temp "$TMP/k" "killed while building: no temporary file (none was created yet)"

# 2. Killed in the middle of writing: an LD_PRELOAD shim turns fsync, which
# the writers call after the last byte and before the rename, into SIGKILL.
CC=${CC:-cc}
cat >"$TMP/killsync.c" <<'EOF'
#include <signal.h>
#include <unistd.h>
int fsync(int fd) { (void)fd; raise(SIGKILL); return -1; }
int fdatasync(int fd) { (void)fd; raise(SIGKILL); return -1; }
EOF
if "$CC" -shared -fPIC -o "$TMP/killsync.so" "$TMP/killsync.c" 2>/dev/null; then
    # killed WHAT TARGET CMD...: CMD (writing TARGET) dies in fsync; TARGET
    # keeps its old bytes, or stays absent if it was absent.
    killed() {
        what=$1; target=$2; shift 2
        had=0
        [ -e "$target" ] && had=1 && cp "$target" "$TMP/before"
        LD_PRELOAD="$TMP/killsync.so" ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0" \
            "$@" >/dev/null 2>"$TMP/err"
        rc=$?
        if [ "$rc" -eq 137 ]; then ok "$what: killed in fsync"; else not_ok "$what: expected death by SIGKILL, exit $rc"; sed 's/^/# /' "$TMP/err" | head -3; fi
        if [ $had -eq 1 ]; then expect_same "$TMP/before" "$target" "$what: the old output is intact"; else
            expect_no_file "$target" "$what: no output where there was none"; fi
        dir=$(dirname "$target"); base=$(basename "$target")
        left=$(ls -a "$dir" | grep -c "^\.$base\.tmp")
        if [ "$left" -eq 1 ]; then ok "$what: its temporary .$base.tmpXXXXXX is left beside the target (expected after SIGKILL)"; else
            not_ok "$what: $left temporary files"; fi
        rm -f "$dir"/."$base".tmp*
    }
    # shellcheck disable=SC2086
    killed "lie-build over a cache" "$TMP/k/out.lie" "$B/lie-build" "$S/museum1.gltf" $SMALL -o "$TMP/k/out.lie"
    # shellcheck disable=SC2086
    killed "lie-build to a new file" "$TMP/k/new.lie" "$B/lie-build" "$S/cornell.gltf" $SMALL -o "$TMP/k/new.lie"
    killed "rst-update over its own input" "$TMP/k/out.lie" "$B/rst-update" "$TMP/k/out.lie" "$TMP/tall.yaml" -q -o "$TMP/k/out.lie"
    "$B/lie-render" "$TMP/old.lie" -q --size 16x16 --light-samples 1 -o "$TMP/k/img.exr" || not_ok "render"
    "$B/lie-render" "$TMP/old.lie" -q --size 16x16 --light-samples 1 -o "$TMP/k/img.png" || not_ok "render PNG"
    killed "lie-render EXR over an image" "$TMP/k/img.exr" "$B/lie-render" "$TMP/old.lie" -q --size 24x24 --light-samples 1 -o "$TMP/k/img.exr"
    killed "lie-render PNG over an image" "$TMP/k/img.png" "$B/lie-render" "$TMP/old.lie" -q --size 24x24 --light-samples 1 -o "$TMP/k/img.png"
    killed "lie-inspect image over an image" "$TMP/k/img.png" "$B/lie-inspect" image "$TMP/old.lie" -q --size 24x24 -o "$TMP/k/img.png"
    run "$B/lie-inspect" verify "$TMP/k/out.lie"
    expect_rc 0 "the surviving cache is still valid"
else
    ok "# SKIP no C compiler for the fsync shim"
fi

# 3. A full disk: -o - with stdout on /dev/full.
if [ -w /dev/full ]; then
    full() { # WHAT CMD...: exit 1 (diff: 2, trouble)
        what=$1; shift
        "$@" >/dev/full 2>"$TMP/err"; rc=$?
        expect_rc "$(case $what in *diff) echo 2 ;; *) echo 1 ;; esac)" "$what to a full disk"
        expect_one_error_line "$(basename "$1"): -: " "$what to a full disk: one line naming -"
    }
    # shellcheck disable=SC2086
    full "lie-build -o -" "$B/lie-build" "$S/cornell.gltf" $SMALL -o -
    full "rst-update -o -" "$B/rst-update" "$TMP/old.lie" "$TMP/tall.yaml" -q -o -
    full "lie-render EXR -o -" "$B/lie-render" "$TMP/old.lie" -q --size 16x16 --light-samples 1 -o -
    full "lie-inspect image -o -" "$B/lie-inspect" image "$TMP/old.lie" -q --size 16x16 -o -
    full "lie-inspect dump" "$B/lie-inspect" dump "$TMP/old.lie"
    full "lie-inspect summary" "$B/lie-inspect" summary "$TMP/old.lie"
    full "lie-inspect diff" "$B/lie-inspect" diff "$TMP/old.lie" "$TMP/old.lie"
    full "lie-inspect patch" "$B/lie-inspect" patch "$TMP/old.lie" 3
    full "lie-inspect verify" "$B/lie-inspect" verify "$TMP/old.lie"
else
    ok "# SKIP /dev/full is not writable"
fi
finish
