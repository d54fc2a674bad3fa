#pragma once
// KW_SIMD_SELECT(target, fn): fn() of the Highway target `target` (a HWY_* bit), for the
// HWY_ONCE part of a kernel file compiled with foreach_target.h, where the per-target
// namespaces N_AVX3, N_AVX2, ... exist. Only the targets this build compiles have a case;
// anything else gets the static (baseline) target's, which isa.cpp never asks for.

#include <hwy/highway.h>

#if HWY_TARGETS & HWY_AVX3
#define KW_SIMD_CASE_AVX3(fn) \
    case HWY_AVX3:            \
        return N_AVX3::fn();
#else
#define KW_SIMD_CASE_AVX3(fn)
#endif
#if HWY_TARGETS & HWY_AVX2
#define KW_SIMD_CASE_AVX2(fn) \
    case HWY_AVX2:            \
        return N_AVX2::fn();
#else
#define KW_SIMD_CASE_AVX2(fn)
#endif
#if HWY_TARGETS & HWY_SSE4
#define KW_SIMD_CASE_SSE4(fn) \
    case HWY_SSE4:            \
        return N_SSE4::fn();
#else
#define KW_SIMD_CASE_SSE4(fn)
#endif
#if HWY_TARGETS & HWY_EMU128
#define KW_SIMD_CASE_EMU128(fn) \
    case HWY_EMU128:            \
        return N_EMU128::fn();
#else
#define KW_SIMD_CASE_EMU128(fn)
#endif
#if HWY_TARGETS & HWY_SCALAR
#define KW_SIMD_CASE_SCALAR(fn) \
    case HWY_SCALAR:            \
        return N_SCALAR::fn();
#else
#define KW_SIMD_CASE_SCALAR(fn)
#endif

#define KW_SIMD_SELECT(target, fn)                                                                          \
    switch (target) {                                                                                       \
        KW_SIMD_CASE_AVX3(fn) KW_SIMD_CASE_AVX2(fn) KW_SIMD_CASE_SSE4(fn) KW_SIMD_CASE_EMU128(fn)           \
            KW_SIMD_CASE_SCALAR(fn) default : return HWY_STATIC_DISPATCH(fn)();                              \
    }
