// The instruction sets of the cpu backends (kodawari/backends/simd.hpp): what this build compiled
// (HWY_TARGETS) and this machine runs (hwy::SupportedTargets(), which also checks that the
// operating system saves the wide registers).
#include "simd/isa.hpp"

#include <hwy/highway.h>
#include <hwy/targets.h>

#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/simd.hpp"

namespace kodawari::simd {
namespace {

struct Known {
    const char* name;
    std::int64_t target;
    unsigned lanes;
};

// Widest first; the fallback last. Only the targets this build compiles.
constexpr Known kKnown[] = {
#if HWY_TARGETS & HWY_AVX3
    {"avx512", HWY_AVX3, 16},
#endif
#if HWY_TARGETS & HWY_AVX2
    {"avx2", HWY_AVX2, 8},
#endif
#if HWY_TARGETS & HWY_SSE4
    {"sse4", HWY_SSE4, 4},
#endif
#if HWY_TARGETS & HWY_EMU128
    {"emu128", HWY_EMU128, 4},
#endif
#if HWY_TARGETS & HWY_SCALAR
    {"scalar", HWY_SCALAR, 1},
#endif
};

bool runs_here(const Known& k) {
    // The portable fallback runs anywhere; hwy::SupportedTargets() lists it too, but
    // saying so here keeps "always available" independent of that detail.
    return k.target == HWY_SCALAR || k.target == HWY_EMU128 || (hwy::SupportedTargets() & k.target) != 0;
}

}  // namespace

Result<Isa> choose_isa(std::string_view requested) {
    for (const Known& k : kKnown) {
        if (!runs_here(k)) continue;
        if (requested.empty() || requested == k.name) return Isa{k.target, k.name, k.lanes};
    }
    std::string available;
    for (const std::string& name : available_simd_isas()) available += (available.empty() ? "" : ", ") + name;
    std::string known;
    for (const Known& k : kKnown) known += (known.empty() ? "" : ", ") + std::string(k.name);
    bool is_known = false;
    for (const Known& k : kKnown) is_known = is_known || requested == k.name;
    return make_error(Error::Kind::InvalidInput,
                      "SIMD instruction set \"" + std::string(requested) + "\" " +
                          (is_known ? "is not supported by this CPU" : "is unknown (known: " + known + ")") +
                          "; available here: " + available);
}

std::vector<Isa> isas_up_to(const Isa& widest) {
    std::vector<Isa> out;
    for (const Known& k : kKnown) {
        if (!runs_here(k) || k.lanes > widest.lanes) continue;
        if (k.lanes == widest.lanes && k.target != widest.target) continue;  // the widest is the one asked for
        if (!out.empty() && out.back().lanes == k.lanes) continue;           // emu128 after sse4
        out.push_back(Isa{k.target, k.name, k.lanes});
    }
    return out;
}

std::size_t cheapest_width(const std::vector<Isa>& widths, std::uint32_t count, const VectorCosts& costs) {
    std::size_t best = 0;
    double best_cost = 0.0;
    for (std::size_t w = 0; w < widths.size(); ++w) {
        const unsigned lanes = widths[w].lanes;
        const double cost = static_cast<double>((count + lanes - 1) / lanes) * costs.of(lanes);
        if (w == 0 || cost < best_cost) best = w, best_cost = cost;
    }
    return best;
}

}  // namespace kodawari::simd

namespace kodawari {

std::vector<std::string> available_simd_isas() {
    std::vector<std::string> out;
    for (const simd::Known& k : simd::kKnown) {
        if (simd::runs_here(k)) out.emplace_back(k.name);
    }
    return out;
}

Result<std::string> simd_isa(std::string_view requested) {
    auto isa = simd::choose_isa(requested);
    if (!isa) return isa.error();
    return isa.value().name;
}

unsigned simd_lanes(std::string_view isa) {
    for (const simd::Known& k : simd::kKnown) {
        if (isa == k.name) return k.lanes;
    }
    return 0;
}

}  // namespace kodawari
