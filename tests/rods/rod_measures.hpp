#pragma once
// Measures of a chain's state that several rod test files check.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "kodawari/rods/solver.hpp"

namespace kodawari::testing_support {

/// The largest relative change of a segment's length from its rest length (stretch or
/// compression), over the chain.
inline float max_stretch(const rods::Chain& chain, const rods::ChainState& s) {
    float e = 0.0f;
    for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) {
        const float l = glm::length(s.x[i + 1] - s.x[i]);
        e = std::max(e, std::abs(l - chain.segment_length[i]) / chain.segment_length[i]);
    }
    return e;
}

}  // namespace kodawari::testing_support
