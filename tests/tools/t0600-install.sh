#!/bin/sh
# make install / uninstall into a private DESTDIR: tools, liblie.so (SONAME, symlinks,
# only lie_ symbols exported), liblie.a, headers, pkg-config, man pages, bash completion.
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

# A program built against the installed headers and liblie.so through pkg-config.
cat >"$TMP/prog.c" <<'EOC'
#include <lie.h>
#include <stdio.h>
int main(int argc, char **argv)
{
    lie_scene_options o = lie_scene_options_default();
    lie_scene *s = NULL;
    lie_error err = {LIE_OK};
    if (lie_scene_load(argv[1], &o, &s, &err) != LIE_OK) {
        fprintf(stderr, "prog: %s\n", err.msg);
        return 1;
    }
    printf("%s %u\n", lie_version_string(), (unsigned)s->n_tris);
    lie_scene_destroy(s);
    return argc == 2 ? 0 : 1;
}
EOC
export PKG_CONFIG_PATH="$R/lib/pkgconfig" PKG_CONFIG_SYSROOT_DIR="$DEST"
flags=$(pkg-config --cflags --libs lie)
# `make VARIANT=asan test-tools` installs the sanitized library: a program
# using it must carry the sanitizer runtime first.
SAN=""
[ "${VARIANT:-release}" = asan ] && SAN="-fsanitize=address,undefined"
# shellcheck disable=SC2086
run cc -std=c11 -Wall -Werror $SAN "$TMP/prog.c" $flags -o "$TMP/prog"
expect_rc 0 "a C11 program compiles and links with pkg-config --cflags --libs lie ($flags)"
run env LD_LIBRARY_PATH="$R/lib" "$TMP/prog" "$S/cornell.gltf"
expect_rc 0 "it runs against the installed liblie.so"
grep -q '^0\.1\.0 [1-9]' "$TMP/out" && ok "and loads a scene: $(cat "$TMP/out")" || not_ok "output: $(cat "$TMP/out")"
LD_LIBRARY_PATH="$R/lib" ldd "$TMP/prog" | grep -q "$R/lib/liblie.so.0" \
    && ok "the program loads liblie.so.0 from the install" || not_ok "ldd: $(LD_LIBRARY_PATH="$R/lib" ldd "$TMP/prog" | grep lie)"
cp "$TMP/prog.c" "$TMP/prog.cpp"
run c++ -std=c++17 -Wall -Werror -c "$TMP/prog.cpp" $(pkg-config --cflags lie) -o "$TMP/prog_cpp.o"
expect_rc 0 "the installed headers compile as C++17"

bad=""
for m in "$R"/share/man/man1/*.1 "$R"/share/man/man5/*.5; do
    out=$(MANWIDTH=80 man -l "$m" 2>/dev/null) && [ -n "$out" ] || bad="$bad $(basename "$m")"
done
n_man=$(ls "$R"/share/man/man1/*.1 "$R"/share/man/man5/*.5 | wc -l)
[ -z "$bad" ] && ok "man -l renders all $n_man pages" || not_ok "man -l fails on:$bad"
MANWIDTH=80 man -l "$R/share/man/man1/lie-render.1" 2>/dev/null | grep -q -- '--visibility' \
    && ok "lie-render(1) holds the options of --help" || not_ok "lie-render(1) lacks --visibility"

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
exit $failures
