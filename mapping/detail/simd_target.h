// simd_target.h: which code the map's vector kernels (publish_word.h, occupied_mask.h) compile to.
// SSE2 where the compiler targets it (every x86-64 build; publish_word.h adds an AVX2 kernel that
// it chooses at run time on CPUs with AVX2); otherwise (ARM, e.g. NVIDIA Jetson) or
// with CENOTE_FORCE_SCALAR defined (the CMake option of that name, to run the scalar kernels on
// x86 in tests) the scalar kernels, which give the same results bit for bit.
// CENOTE_FORCE_SCALAR is a PUBLIC definition of cenote_mapping: every translation unit that
// includes these headers must make the same choice (the kernels are inline functions).
#pragma once

#if defined(__SSE2__) && !defined(CENOTE_FORCE_SCALAR)
#define CENOTE_MAPPING_SSE2 1
#include <emmintrin.h>
#else
#define CENOTE_MAPPING_SSE2 0
#endif
