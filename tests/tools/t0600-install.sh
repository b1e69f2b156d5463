#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make install / uninstall into a private DESTDIR: tools, liblie.so (SONAME, symlinks,
# only lie_ symbols exported), liblie.a, headers, pkg-config, man pages, bash completion;
# every declared function exported; C and C++ programs through pkg-config; lie.pc per install.
. "$(dirname "$0")/lib.sh"
unset MAKEFLAGS MFLAGS MAKELEVEL
DEST="$TMP/dest"
PFX=/usr/local
R="$DEST$PFX"

run make -s -C "$ROOT" install DESTDIR="$DEST" PREFIX="$PFX"
expect_rc 0 "make install into a DESTDIR"

missing=""
for f in bin/lie-build bin/lie-render bin/rst-update bin/lie-inspect lib/liblie.a \
         lib/liblie.so.0.1.0 lib/liblie.so.0 lib/liblie.so lib/pkgconfig/lie.pc include/lie/lie.h \
         include/lie/core/core.h include/lie/scene/scene.h share/man/man1/lie-render.1 \
         share/man/man5/lie-cache.5 share/man/man5/lie-edit.5 share/man/man5/lie-camera-path.5 \
         share/bash-completion/completions/lie-render; do
    [ -e "$R/$f" ] || missing="$missing $f"
done
[ -z "$missing" ] && ok "every part is installed" || not_ok "missing:$missing"

[ "$(readlink "$R/lib/liblie.so")" = liblie.so.0 ] && [ "$(readlink "$R/lib/liblie.so.0")" = liblie.so.0.1.0 ] \
    && ok "liblie.so -> liblie.so.0 -> liblie.so.0.1.0" || not_ok "symlinks: $(ls -l "$R/lib")"
soname=$(readelf -d "$R/lib/liblie.so.0.1.0" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')
[ "$soname" = liblie.so.0 ] && ok "SONAME liblie.so.0" || not_ok "SONAME '$soname'"
others=$(nm -D --defined-only "$R/lib/liblie.so.0.1.0" | awk '{print $3}' | grep -v -e '^lie_' -e '^LIE_0$')
n_lie=$(nm -D --defined-only "$R/lib/liblie.so.0.1.0" | awk '{print $3}' | grep -c '^lie_')
if [ -z "$others" ] && [ "$n_lie" -gt 50 ]; then ok "only lie_ symbols exported ($n_lie), versioned LIE_0"
else not_ok "exports besides lie_: $(echo $others | head -c 300) ($n_lie lie_)"; fi
nm -D --defined-only --with-symbol-versions "$R/lib/liblie.so.0.1.0" 2>/dev/null | grep -q 'lie_scene_load@@LIE_0' \
    && ok "symbols carry the LIE_0 version" || not_ok "no LIE_0 version on lie_scene_load"

# Every function the installed headers declare is exported from liblie.so: GCC's -aux-info
# lists the prototypes the installed lie.h brings in, by the header that declares them (static
# inline functions are not symbols); nm -D lists what the library defines.
# pkg-config of the install (not exported: the makes below must see the system's modules)
pc() { PKG_CONFIG_PATH="$R/lib/pkgconfig" PKG_CONFIG_SYSROOT_DIR="$DEST" pkg-config "$@"; }
echo '#include <lie.h>' >"$TMP/decls.c"
# shellcheck disable=SC2046
run gcc -std=c11 -D_GNU_SOURCE $(pc --cflags lie) -fsyntax-only -aux-info "$TMP/aux.txt" "$TMP/decls.c"
expect_rc 0 "the installed lie.h compiles alone"
grep -F "/* $R/include/lie/" "$TMP/aux.txt" | grep -F '*/ extern ' |
    sed 's/^.*\*\/ extern //; s/ (.*$//; s/^.*[ *]//' | sort -u >"$TMP/declared"
nm -D --defined-only "$R/lib/liblie.so.0.1.0" | awk '$2 == "T" || $2 == "i" {print $3}' | sed 's/@.*//' | sort -u >"$TMP/exported"
n_decl=$(wc -l <"$TMP/declared")
unexported=$(comm -23 "$TMP/declared" "$TMP/exported")
[ "$n_decl" -gt 200 ] && [ -z "$unexported" ] && ok "all $n_decl functions the installed headers declare are exported" \
    || not_ok "declared ($n_decl) but not exported: $(echo $unexported)"
for cache in lie_cache_read lie_cache_decode lie_cache_encode lie_cache_write lie_cache_write_with_scene \
             lie_cache_destroy lie_cache_sections lie_version_string; do
    grep -qx "$cache" "$TMP/exported" || not_ok "$cache is not exported"
done
nodecl=""
for h in $(cd "$R/include/lie" && find . -name '*.h'); do
    grep -q '^lie_\|^[a-z].* \**lie_[a-z0-9_]*(' "$R/include/lie/$h" || continue # declares no function
    grep -q 'extern "C"' "$R/include/lie/$h" || nodecl="$nodecl $h"
done
[ -z "$nodecl" ] && ok "every installed header that declares functions has extern \"C\"" || not_ok "no extern \"C\" in:$nodecl"

# lie.pc: the Debian modules as Requires.private, OpenEXR among them; bare -l flags only
# for what Debian ships no module for.
req=$(pc --print-requires-private lie | awk '{print $1}' | tr '\n' ' ')
case "$req" in *OpenEXR*yaml-0.1*libpng*zlib*libxxhash*tinygltf*) ok "Requires.private: $req";;
    *) not_ok "Requires.private: '$req'";; esac
grep -q '^Libs.private: -lembree3 -lpthread -lm -lstdc++$' "$R/lib/pkgconfig/lie.pc" \
    && ok "Libs.private holds only what has no pkg-config module" || not_ok "$(grep Libs.private "$R/lib/pkgconfig/lie.pc")"
pc --static --libs lie | grep -q -- '-lOpenEXRCore-3_1' && ok "--static --libs brings OpenEXR's libraries from its module" \
    || not_ok "--static --libs: $(pc --static --libs lie)"

# Programs built against the installed headers and liblie.so through pkg-config, in C and
# in C++ (tests/data/api/prog.c): they read a cache, render it and write image and cache.
flags=$(pc --cflags --libs lie)
# `make VARIANT=asan test-tools` installs the sanitized library: a program
# using it must carry the sanitizer runtime first.
SAN=""
[ "${VARIANT:-release}" = asan ] && SAN="-fsanitize=address,undefined"
run "$BINDIR/lie-build" -q "$S/cornell.gltf" -o "$TMP/in.lie"
expect_rc 0 "lie-build cornell.gltf"
cp "$ROOT/tests/data/api/prog.c" "$TMP/prog.c"
cp "$ROOT/tests/data/api/prog.c" "$TMP/prog.cpp"
# shellcheck disable=SC2086
run cc -std=c11 -Wall -Wextra -Werror $SAN "$TMP/prog.c" $flags -o "$TMP/prog"
expect_rc 0 "a C11 program compiles and links with pkg-config --cflags --libs lie ($flags)"
# shellcheck disable=SC2086
run c++ -std=c++17 -Wall -Wextra -Werror $SAN "$TMP/prog.cpp" $flags -o "$TMP/prog_cpp"
expect_rc 0 "the same program compiles and links as C++17"
for p in prog prog_cpp; do
    LD_LIBRARY_PATH="$R/lib" ldd "$TMP/$p" | grep -q "$R/lib/liblie.so.0" \
        && ok "$p loads liblie.so.0 from the install" || not_ok "$p: ldd: $(LD_LIBRARY_PATH="$R/lib" ldd "$TMP/$p" | grep lie)"
    own=$(nm --defined-only "$TMP/$p" | awk '$2 == "T" && $3 ~ /^lie_/' | head -3)
    [ -z "$own" ] && ok "$p carries no lie_ code of its own (not linked with liblie.a)" || not_ok "$p defines: $own"
    run env LD_LIBRARY_PATH="$R/lib" "$TMP/$p" "$TMP/in.lie" "$TMP/$p.exr" "$TMP/$p.lie"
    expect_rc 0 "$p reads the cache, renders and writes"
    grep -q '^0\.1\.0 [1-9][0-9]* triangles, [1-9][0-9]* shading points$' "$TMP/out" && ok "$p: $(cat "$TMP/out")" \
        || not_ok "$p output: $(cat "$TMP/out")"
    cmp -s "$TMP/in.lie" "$TMP/$p.lie" && ok "$p wrote the cache it read, byte for byte" || not_ok "$p: the cache differs"
done
cmp -s "$TMP/prog.exr" "$TMP/prog_cpp.exr" && ok "the C and C++ programs write the same image" || not_ok "C and C++ images differ"

bad=""
for m in "$R"/share/man/man1/*.1 "$R"/share/man/man5/*.5; do
    out=$(MANWIDTH=80 man -l "$m" 2>/dev/null) && [ -n "$out" ] || bad="$bad $(basename "$m")"
done
n_man=$(ls "$R"/share/man/man1/*.1 "$R"/share/man/man5/*.5 | wc -l)
[ -z "$bad" ] && ok "man -l renders all $n_man pages" || not_ok "man -l fails on:$bad"
MANWIDTH=80 man -l "$R/share/man/man1/lie-render.1" 2>/dev/null | grep -q -- '--visibility' \
    && ok "lie-render(1) holds the options of --help" || not_ok "lie-render(1) lacks --visibility"
nosyn=""; badtitle=""; nosee=""
for m in "$R"/share/man/man1/*.1; do
    txt=$(MANWIDTH=80 man -l "$m" 2>/dev/null)
    t=$(basename "$m" .1)
    echo "$txt" | grep -q '^SYNOPSIS' && echo "$txt" | sed -n '/^SYNOPSIS/,/^[A-Z]/p' | grep -q "$t" || nosyn="$nosyn $t"
    echo "$txt" | grep -q 'manual page for' && badtitle="$badtitle $t"
    for other in lie-build lie-render rst-update lie-inspect lie-animate lie-view lie-cache lie-edit lie-camera-path; do
        [ "$other" = "$t" ] || echo "$txt" | sed -n '/^SEE ALSO/,$p' | grep -q "$other" || nosee="$nosee $t:$other"
    done
done
[ -z "$nosyn" ] && ok "every section-1 page has a SYNOPSIS with its command" || not_ok "no SYNOPSIS:$nosyn"
[ -z "$badtitle" ] && ok "no page is titled 'manual page for'" || not_ok "untitled:$badtitle"
[ -z "$nosee" ] && ok "SEE ALSO names every other page" || not_ok "SEE ALSO lacks:$nosee"
badname=""
for m in "$R"/share/man/man5/*.5; do
    t=$(basename "$m" .5)
    lexgrog "$m" 2>/dev/null | grep -q "\"$t - [A-Z]" || badname="$badname $t($(lexgrog "$m" 2>&1))"
done
[ -z "$badname" ] && ok "lexgrog reads the NAME of every section-5 page" || not_ok "lexgrog:$badname"

run bash -n "$R/share/bash-completion/completions/lie-render"
expect_rc 0 "bash -n on the completion script"
comp=$(PATH="$R/bin:$PATH" bash -c ". '$R/share/bash-completion/completions/lie-render';
    COMP_WORDS=(lie-render --visi); COMP_CWORD=1; _lie_tool; echo \"\${COMPREPLY[*]}\"")
case "$comp" in *--visibility*) ok "completion offers --visibility for --visi";;
    *) not_ok "completion gave '$comp'";; esac

run "$R/bin/lie-render" --version
expect_rc 0 "the installed lie-render --version"
grep -q 'Embree' "$TMP/out" && grep -q 'commit' "$TMP/out" && ok "--version names the commit and Embree: $(head -1 "$TMP/out")" \
    || not_ok "--version: $(cat "$TMP/out")"

run make -s -C "$ROOT" uninstall DESTDIR="$DEST" PREFIX="$PFX"
expect_rc 0 "make uninstall"
left=$(find "$DEST" ! -type d)
[ -z "$left" ] && ok "uninstall removes every installed file" || not_ok "left behind: $left"
# lie.pc is written for each install's directories (Debian's multiarch libdir, say).
D2="$TMP/dest2"
run make -s -C "$ROOT" install DESTDIR="$D2" PREFIX=/usr LIBDIR=/usr/lib/x86_64-linux-gnu
expect_rc 0 "make install PREFIX=/usr LIBDIR=/usr/lib/x86_64-linux-gnu"
pc="$D2/usr/lib/x86_64-linux-gnu/pkgconfig/lie.pc"
grep -qx 'prefix=/usr' "$pc" && grep -qx 'libdir=${prefix}/lib/x86_64-linux-gnu' "$pc" && grep -qx 'includedir=${prefix}/include' "$pc" \
    && [ -e "$D2/usr/lib/x86_64-linux-gnu/liblie.so.0" ] && ok "lie.pc and the library follow PREFIX and LIBDIR" \
    || not_ok "lie.pc: $(head -4 "$pc" 2>/dev/null | tr '\n' ' ')"
run make -s -C "$ROOT" uninstall DESTDIR="$D2" PREFIX=/usr LIBDIR=/usr/lib/x86_64-linux-gnu
left=$(find "$D2" ! -type d)
[ -z "$left" ] && ok "and uninstall removes it all" || not_ok "left behind: $left"

# User CFLAGS add to the project's flags (GNU make's command-line variables would replace them).
obj=build/${VARIANT:-release}/lib/core/math.o
line=$(make -s -C "$ROOT" -n -B CFLAGS=-O2 "$obj" 2>/dev/null | grep -- ' -c lib/core/math.c')
case "$line" in *-std=c11*-Ilib*-O2\ *) ok "make CFLAGS=-O2 keeps -std=c11 -Ilib and adds -O2 last";;
    *) not_ok "make CFLAGS=-O2 compiles with: $line";; esac
exit $failures
