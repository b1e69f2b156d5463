#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Every source file says its licence in its first two lines (an SPDX-License-Identifier,
# as LICENSE: Apache-2.0), LICENSE names its copyright holder, NEWS names this version.
. "$(dirname "$0")/lib.sh"
cd "$ROOT" || exit 1
missing=""
nf=0
for f in $(find lib tools tests bench scripts examples mk completion Makefile -type f \
        \( -name '*.c' -o -name '*.h' -o -name '*.cpp' -o -name '*.sh' -o -name '*.py' -o -name '*.awk' \
           -o -name '*.mk' -o -name '*.bash' -o -name Makefile \) \
        ! -path 'tests/fuzz/regressions/*' ! -path 'build/*' 2>/dev/null | sort); do
    nf=$((nf + 1))
    head -2 "$f" | grep -q 'SPDX-License-Identifier: Apache-2.0' || missing="$missing $f"
done
[ "$nf" -gt 200 ] && [ -z "$missing" ] && ok "all $nf source files carry SPDX-License-Identifier: Apache-2.0" \
    || not_ok "without an SPDX line ($nf files read):$missing"
grep -q '^   Copyright [0-9]\{4\} The LIE toolchain authors$' LICENSE && ! grep -q '\[name of copyright owner\]' LICENSE \
    && ok "LICENSE names its copyright holder" || not_ok "LICENSE: $(grep -n Copyright LICENSE)"
v=$(sed -n 's/^#define LIE_VERSION "\(.*\)"$/\1/p' lib/lie.h)
grep -q "^## $v " NEWS.md && ok "NEWS.md has an entry for $v" || not_ok "no '## $v' entry in NEWS.md"
grep -q "^LIBVERSION := $v$" Makefile && ok "the Makefile's LIBVERSION is $v too" || not_ok "LIBVERSION: $(grep '^LIBVERSION' Makefile)"
finish
