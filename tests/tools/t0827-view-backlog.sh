#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-view under a real X server (Xvfb): a screenshot, quitting and --save
# never wait for the constructor's backlog, and SIGINT and SIGTERM are
# honoured while one is pending.  `pause` before a drag holds its
# backlog for good, so a program that waited for it would never end (each
# run is bounded by `timeout`): on a whole cache (lib/update's steps) and on
# a scene (the asynchronous constructor), the screenshot is written, the
# session ends with exit 0, and --save writes a partial cache that is valid.
. "$ROOT/tests/tools/lib.sh"

need_viewer
M1="$S/museum1.gltf"
VIEW="-q --size 64x64 --light-samples 4 --view-size 96x96"
"$B/lie-build" "$M1" -q --min-patch 1e-2 -o "$TMP/m1.lie" || not_ok "build museum1"

partial_and_valid() { # CACHE WHAT
    if "$B/lie-inspect" summary "$1" 2>/dev/null | grep -q '^partial  *yes' && "$B/lie-inspect" verify "$1" >/dev/null 2>&1
    then ok "$2: --save wrote a valid partial cache (the backlog left pending)"
    else not_ok "$2: --save: $("$B/lie-inspect" summary "$1" 2>&1 | grep -i partial)"; fi
}

for input in m1.lie scene; do
    case $input in
    m1.lie) in="$TMP/m1.lie" what="a whole cache" warm="" ;;
    *) in="$M1" what="a scene" warm="wait-units 10" ;;
    esac
    cat >"$TMP/held.txt" <<EOF
frames 1
$warm
select Cube
pause
drag 0.4 0 -0.3
screenshot $TMP/held.png
quit
EOF
    run xvfb_run timeout 120 "$B/lie-view" "$in" $VIEW --script "$TMP/held.txt" --save "$TMP/held.lie" --stats=json
    expect_rc 0 "$what: a screenshot and quit with the drag's backlog held"
    if grep -q '"pending_max":[1-9]' "$TMP/err" || [ "$input" = scene ]; then ok "$what: the drag left units pending"
    else not_ok "$what: the drag left nothing pending: $(cat "$TMP/err")"; fi
    expect_file "$TMP/held.png" "$what: the screenshot is written"
    partial_and_valid "$TMP/held.lie" "$what"
    rm -f "$TMP/held.png" "$TMP/held.lie"

    # a signal while the backlog is held
    for sig in INT TERM; do
        cat >"$TMP/sig.txt" <<EOF
frames 1
$warm
select Cube
pause
drag 0.4 0 -0.3
screenshot $TMP/ready.png
frames 1000000
EOF
        cat >"$TMP/sig.sh" <<EOF
timeout --foreground 120 "$B/lie-view" "$in" $VIEW --script "$TMP/sig.txt" --save "$TMP/sig.lie" 2>"$TMP/sig.err" &
pid=\$!
i=0
while [ ! -s "$TMP/ready.png" ] && [ \$i -lt 600 ]; do sleep 0.1; i=\$((i + 1)); done
kill -$sig \$pid
wait \$pid
echo \$? >"$TMP/sig.rc"
EOF
        xvfb_run sh "$TMP/sig.sh" >/dev/null 2>&1
        rc=$(cat "$TMP/sig.rc" 2>/dev/null || echo none)
        if [ "$rc" = 0 ]; then ok "$what: SIG$sig with the backlog held ends the session (exit 0)"; else
            not_ok "$what: SIG$sig: exit $rc"; sed 's/^/# /' "$TMP/sig.err" | head -5; fi
        partial_and_valid "$TMP/sig.lie" "$what, SIG$sig"
        rm -f "$TMP/sig.lie" "$TMP/sig.rc" "$TMP/ready.png"
    done
done
finish
