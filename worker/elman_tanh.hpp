// The Elman network's activation (docs/model.md §4.3): tanh of a binary32 value, computed with
// IEEE binary32 +, -, *, / only, so that it gives the same bits on every CPU and C library.
//
// Why not std::tanh: the C library's tanhf is not the same function everywhere. glibc 2.36's
// AArch64 build differs from its x86-64 build by 1-2 ulp for some arguments (its polynomial is
// compiled with fused multiply-adds there), and later glibc versions replaced it by a correctly
// rounded one. Either would move controller outputs, and through the chaotic gaits the fitness.
//
// This function is bit-identical to glibc 2.36's tanhf on x86-64 for every one of the 2^32
// binary32 inputs (checked exhaustively when it was written; tests/worker/test_elman_tanh.cpp
// keeps a sampled check and pinned hashes), so results from before it keep their bits.
#pragma once

namespace softevo::worker {

// e^x - 1 in binary32 (docs/model.md §4.7), accurate near 0 where e^x - 1 cancels.
float expm1_binary32(float x);

// tanh x in binary32 (docs/model.md §4.7): odd, ±1 beyond |x| = 22, x itself for |x| < 2^-55.
float tanh_binary32(float x);

}  // namespace softevo::worker
