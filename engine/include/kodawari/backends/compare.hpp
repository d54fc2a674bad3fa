#pragma once
/// @file
/// Side-by-side comparison of two backends' bird outputs (kodawari validate, parity
/// tests): maximum and mean deviation per quantity against stated tolerances.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/world.hpp"

namespace kodawari {

/// Deviation statistics of one quantity.
struct Deviation {
    std::string quantity;  ///< "position", "rotation LeftArm1", ...
    std::string unit;      ///< "m", "rad", "", ...
    double max = 0.0;
    double mean = 0.0;
    double tolerance = 0.0;
    std::uint64_t samples = 0;
    std::uint32_t worst_bird = 0;
    std::uint32_t worst_frame = 0;
    [[nodiscard]] bool within() const { return max <= tolerance; }
};

/// The parity tolerances of the bird engine: part rotations within 1e-4 rad; positions
/// within 1e-5 of the longest route's length (float rounding of a route sampled at up
/// to ~1e4 m is ~1e-3 m, well inside); phase and blend within 1e-4 (same arithmetic,
/// different transcendental implementations); modes must agree exactly.
struct BirdTolerances {
    double rotation_rad = 1e-4;
    double position_fraction_of_route = 1e-5;
    double phase_rad = 1e-4;
    double blend = 1e-4;
    double tail_spread = 1e-4;  ///< BirdPose::position.w, a width scale of the order of 1
};

/// Accumulates deviations frame chunk after chunk.
class KODAWARI_API BirdComparison {
public:
    explicit BirdComparison(const birds::BirdWorld& world, BirdTolerances tolerances = {});

    /// Adds `frames` frames starting at `first_frame`: poses (and diag when both given)
    /// of the reference and of the backend under test, frames x birds, frame-major.
    void add(std::uint32_t first_frame, std::uint32_t frames, std::span<const gpu::BirdPose> reference,
             std::span<const gpu::BirdPose> tested, std::span<const gpu::BirdDiag> reference_diag = {},
             std::span<const gpu::BirdDiag> tested_diag = {});

    /// One entry per quantity.
    [[nodiscard]] std::vector<Deviation> results() const;

    /// True when every quantity is within its tolerance.
    [[nodiscard]] bool within() const;

private:
    struct Acc {
        double max = 0.0, sum = 0.0;
        std::uint64_t n = 0;
        std::uint32_t bird = 0, frame = 0;
        void add(double value, std::uint32_t b, std::uint32_t f);
    };
    std::uint32_t birds_ = 0;
    double route_length_ = 1.0;
    BirdTolerances tol_;
    Acc position_, spread_, rotation_[KW_PART_COUNT], phase_, blend_, mode_;
};

/// Angle (rad) of the rotation between two unit quaternions, either sign.
[[nodiscard]] KODAWARI_API double quaternion_angle(const gpu::vec4& a, const gpu::vec4& b);

}  // namespace kodawari
