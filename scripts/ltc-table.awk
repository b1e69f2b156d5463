# SPDX-License-Identifier: Apache-2.0
# scripts/ltc-table.awk: the LTC tables' data (lib/shade/ltc_table.dat,
# written by scripts/ltc-fit.c) as the C source the library compiles
# (the Makefile runs it into build/VARIANT/gen/ltc_table.c).  The format
# is described at the top of the data file.
function close_table() {
    if (open_table)
        printf "};\n\n"
    open_table = 0
}
/^##/ { next }
/^#/ {
    text = substr($0, 2)
    if (!in_comment)
        printf "/*%s\n", text
    else
        printf " *%s\n", text
    in_comment = 1
    next
}
in_comment {
    printf " */\n#include \"shade/ltc.h\"\n\n"
    in_comment = 0
}
/^[a-z_]+ / {
    close_table()
    name = $1
    if (name == "ggx") {
        n_rough = $2
        n_cos = $3
        printf "/* [roughness i / %d][u = sqrt(1 - n.wo) = j / %d]: m00, m02, m20, m22, norm, fresnel */\n",
               n_rough - 1, n_cos - 1
    } else if (name == "ggx_fresnel") {
        printf "/* the same bins for D V (1 - v.h)^5 cos (fresnel unused) */\n"
    }
    size = NF > 2 ? $2 * $3 : $2
    printf "static const lie_ltc_bin %s[%d] = {\n", name, size
    open_table = 1
    next
}
NF == 6 {
    printf "    {%s, %s, %s, %s, %s, %s},\n", $1, $2, $3, $4, $5, $6
    next
}
{
    printf "ltc-table.awk: line %d: expected a bin of 6 numbers\n", NR > "/dev/stderr"
    bad = 1
    exit 1
}
END {
    if (bad)
        exit 1
    close_table()
    printf "static const lie_ltc_table table = {%d, %d, ggx, diffuse, ggx_fresnel};\n\n", n_rough, n_cos
    printf "const lie_ltc_table *lie_ltc_table_default(void) { return &table; }\n"
}
