#pragma once
/// @file
/// The instruction sets of the vectorized `cpu` backends (BackendKind::Cpu; kodawari::sim).
///
/// One binary carries the cpu backends' kernels for every x86 SIMD instruction set
/// (Google Highway's dynamic dispatch); each backend takes the widest this machine runs,
/// or the one BackendOptions::isa names. Names: "avx512" (16 floats per vector), "avx2"
/// (8), "sse4" (4) and "scalar" (Highway's portable one-lane fallback, always available).
/// The cpu backends give the same results on every one of them where they are exact
/// (chains and poses: the bits of cpu-reference); see docs/backends.md.

#include <string>
#include <string_view>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari {

/// The instruction sets the cpu backends can use on this machine, widest first; "scalar"
/// is always the last.
[[nodiscard]] KODAWARI_API std::vector<std::string> available_simd_isas();

/// The instruction set a cpu backend made with BackendOptions::isa == `requested` uses:
/// the widest available for "", else `requested` itself. An unknown name, or one this
/// machine cannot run, is an InvalidInput error that names it and the available ones.
[[nodiscard]] KODAWARI_API Result<std::string> simd_isa(std::string_view requested = {});

/// Floats per vector of an instruction set named as above (16, 8, 4, 1); 0 for another name.
[[nodiscard]] KODAWARI_API unsigned simd_lanes(std::string_view isa);

}  // namespace kodawari
