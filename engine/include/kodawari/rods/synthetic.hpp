#pragma once
/// @file
/// A procedural rod world for benchmarks and backend tests: characters laid out on a
/// grid, each a swaying, turning head carrying strands with view examples, and an
/// orbiting camera. Independent of the scene format, so the benchmark measures the
/// solver alone.

#include <cstdint>

#include "kodawari/core/api.hpp"
#include "kodawari/rods/world.hpp"

namespace kodawari::rods {

struct SyntheticOptions {
    std::uint32_t chains = 1000;             ///< total chains, >= 1
    std::uint32_t joints = 16;               ///< per chain, 2 .. kMaxChainJoints
    std::uint32_t iterations = 4;            ///< projection iterations per substep, 1 .. 64
    std::uint32_t chains_per_character = 8;  ///< the last character may have fewer
    std::uint32_t views = 3;                 ///< view examples per chain, 0 .. kMaxViewExamples
    bool colliders = true;                   ///< a head sphere per character
    float motion = 1.0f;                     ///< scales the head's sway and turn (0 = still)
    /// Chains start settled on their rest shape (SolverParams::settle_start). Off: they
    /// start on the rest shape itself, unsettled. Settling takes 60 to 660 solver
    /// substeps a chain at load (about 0.65 ms a chain on cpu-reference, so minutes for a
    /// million), which a benchmark of the step does not measure.
    bool settle = true;
};

/// The world and its kinematics.
class KODAWARI_API SyntheticScene {
public:
    [[nodiscard]] static Result<SyntheticScene> make(const SyntheticOptions& options);

    [[nodiscard]] const RodWorld& world() const { return world_; }
    /// The kinematic input at the end of frame `index` (time index * dt); frame 0 is the
    /// initial pose. Reuses `out`'s storage.
    void frame(std::uint32_t index, float dt, RodFrame& out) const;
    /// The chain length (m) of every chain.
    [[nodiscard]] float chain_length() const { return length_; }

private:
    RodWorld world_;
    SyntheticOptions options_;
    float length_ = 0.0f;
    std::vector<Transform> chain_offsets_;  // per template: root frame in the head's frame
};

}  // namespace kodawari::rods
