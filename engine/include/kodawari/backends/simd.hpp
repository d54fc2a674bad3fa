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

#include <cstddef>
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

/// The machine's ceilings as one measurement found them (`kodawari bench ceilings`,
/// docs/performance.md): what a kernel's rate is set against.
struct MachineCeilings {
    std::string isa;            ///< the instruction set of the fp32 loop
    unsigned threads = 1;       ///< threads, each running the loop and its share of the triad
    /// fp32 operations a second, a fused multiply-add counted as 2: 12 independent chains
    /// of one vector each per thread (past the latency of every FMA pipe), no memory.
    double fp32_flops = 0.0;
    /// STREAM's triad a[i] = b[i] + s c[i] over three float arrays of `triad_bytes` / 3,
    /// counted as STREAM does (12 bytes an element: two reads and a write; the write's
    /// allocation read is not counted), the best of three passes.
    double triad_bytes_per_second = 0.0;
    std::size_t triad_bytes = 0;  ///< the three arrays together
};

/// Measures the ceilings on `threads` threads (1 to 1024) with the fp32 loop on `isa`
/// ("" for the widest, as simd_isa()), the triad over `triad_bytes` (at least 3 MiB,
/// at most 64 GiB). About half a second. An unknown `isa`, a thread count or size out of
/// range is an InvalidInput error naming the argument; arrays that cannot be allocated
/// are an Internal error saying how many bytes.
[[nodiscard]] KODAWARI_API Result<MachineCeilings> measure_ceilings(std::string_view isa = {}, unsigned threads = 1,
                                                                    std::size_t triad_bytes = std::size_t{384} << 20);

}  // namespace kodawari
