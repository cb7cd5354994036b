// Function multi-versioning for the vector loops of the hot passes: a function marked with one of
// these is compiled for each target listed and the widest the CPU has is picked at load time (GCC's
// target_clones), so the portable build (x86-64-v2: 4 float lanes) runs 8 or 16 lanes a step on the
// machines that have AVX2 or AVX-512F. Only GCC on x86-64 builds below AVX2 clones; elsewhere the
// marks are empty.
//
// The cloned loops must round alike on every target: the files that hold them are compiled with
// -ffp-contract=off (CMakeLists.txt), so that no multiply and add are fused where AVX2 and AVX-512F
// offer FMA; division and square root are correctly rounded at any width.
//
// GCC trusts `restrict` on a function's pointer parameters, not on a struct's pointer members: a
// cloned function is called, not inlined, so its loop's outputs come in as restrict parameters or its
// loop does not vectorize.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__AVX2__)
#define PENUMBRA_CLONES_AVX2 __attribute__((target_clones("avx2", "default")))
#define PENUMBRA_CLONES_AVX512 __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define PENUMBRA_CLONES_AVX2
#define PENUMBRA_CLONES_AVX512
#endif
