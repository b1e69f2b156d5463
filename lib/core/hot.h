/* SPDX-License-Identifier: Apache-2.0 */
/* Hot kernels: the library is compiled for baseline x86-64 (SSE2, every CPU Debian supports),
 * and the few loops where the shading time goes carry a second copy for x86-64-v3 (AVX2, FMA),
 * chosen once when the library is loaded by the CPU it runs on (GCC's function multi-versioning,
 * `target_clones`: an ifunc resolved by the dynamic loader).  The measurements that chose
 * these functions, and what the baseline copies cost against a whole -march=x86-64-v3 build,
 * are in bench/arch.sh.
 *
 * Both copies give the same bits: the project compiles with -ffp-contract=off, so an FMA
 * instruction appears only where the source asks for fmaf (exact in both copies: the baseline
 * calls libm's correctly rounded fmaf), and sums keep a fixed order of eight lanes whatever the
 * vector width (lie_sum8 in lib/shade/internal.h).  tests/tools/t0660-portable.sh renders the
 * same image natively and under `qemu-x86_64 -cpu Nehalem` and compares the bytes.
 *
 * Clang (the fuzz build) and a build that already targets AVX2 (ARCHFLAGS=-march=native,
 * `make VARIANT=v3`) get one copy. */
#ifndef LIE_CORE_HOT_H
#define LIE_CORE_HOT_H

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__AVX2__) && \
    !defined(LIE_NO_CLONES)
#define LIE_HOT __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define LIE_HOT
#endif

#endif
