// SPARSEBODY_ONE_COPY: a function compiled once, never inlined, so that two call paths which must
// agree bit for bit (a batch of users against each user's own pipeline) run the same machine code.
// Inlined into different callers, the same source may compile to different rounding even with
// -ffp-contract=off: Eigen picks its explicit-FMA packet paths (pmadd) or scalar a*b + c per
// context. Measured on an Intel Xeon (AVX-512, x86-64-v3 and native builds, 2026-12-07): the LoBSTr
// batch's hips rotation differed in the last bit from the single pipeline's on identical inputs.
// Costs one call per frame.
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define SPARSEBODY_ONE_COPY __attribute__((noinline))
#elif defined(_MSC_VER)
#define SPARSEBODY_ONE_COPY __declspec(noinline)
#else
#define SPARSEBODY_ONE_COPY
#endif
