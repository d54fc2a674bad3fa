#pragma once
/// @file
/// One instance of a rigged character in a crowd, and the two formulas every consumer of
/// instances shares (the pose backends, the rod scene): the clip time an instance samples
/// and the matrix of its placement. They live below the backends so that the scene can
/// use them without depending on a backend.

#include <cstdint>

#include <glm/glm.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/rods/solver.hpp"

namespace kodawari {

/// One instance of a rigged character in a crowd.
struct PoseInstance {
    rods::Transform placement;   ///< the instance's transform (world = placement * node world)
    std::int32_t clip = -1;      ///< index into Character::animations; -1 = rest pose
    float time_offset = 0.0f;    ///< s, added to the scene time
    bool loop = true;            ///< wrap the clip time into [start, end] (see clip_time)
};

/// The time an instance samples its clip at for scene time `time`: t = time + time_offset;
/// looping: start + (t - start) - d * floor((t - start) / d) with d = end - start
/// (d == 0: start); not looping: t (animation::sample() clamps). Exactly this float formula
/// (IEEE single precision, correctly rounded, evaluated left to right without
/// contraction) on every backend, so every backend wraps at the same scene times.
[[nodiscard]] KODAWARI_API float clip_time(const animation::Animation& clip, const PoseInstance& instance, float time);

/// The matrix of an instance's placement: translate(position) * mat4_cast(rotation).
/// Every backend applies this very matrix.
[[nodiscard]] KODAWARI_API glm::mat4 placement_matrix(const rods::Transform& placement);

}  // namespace kodawari
