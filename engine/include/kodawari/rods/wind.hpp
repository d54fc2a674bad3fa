#pragma once
/// @file
/// Wind (docs/models.md "Wind"): a field of moving air that the chains feel through drag.
/// The field is a mean velocity with gusts, smooth noise in horizontal position and time
/// carried along with the mean wind; each chain feels the air's velocity at its root
/// (rods::air_velocity, once per frame) through its SolverParams::damping (isotropic)
/// and its normal_drag and tangent_drag (across and along each segment).

#include <cstdint>

#include <glm/glm.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::rods {

/// A wind field. The default is calm (no air moves): a chain then feels exactly what it
/// feels without wind.
struct WindField {
    /// The mean air velocity, m/s (direction times speed); each component in [-100, 100].
    glm::vec3 velocity{0.0f};
    /// Gust strength in [0, 4]: the gusts' velocity is up to gust x |velocity| (three
    /// smooth noises in [-1, 1] scale it; the vertical one is halved). 0: a steady wind.
    float gust = 0.0f;
    /// Gust period, s, in [0.05, 1000]: the time over which a gust rises and falls.
    float gust_period = 3.0f;
    /// Gust size, m, in [0.05, 10000]: the width of one gust across the ground.
    float gust_size = 6.0f;
    /// Noise seed: the same seed, the same gusts.
    std::uint32_t seed = 0;
};

/// Checks every WindField range above; `what` names the field in the message ("wind").
[[nodiscard]] KODAWARI_API Result<void> validate(const WindField& wind, const char* what = "wind");

/// The air's velocity (m/s) of `wind` at world position `position` and time `time` (s):
/// shaders/lib/wind.glsl's wind_air_velocity, the one definition every backend uses.
[[nodiscard]] KODAWARI_API glm::vec3 air_velocity(const WindField& wind, const glm::vec3& position, float time);

}  // namespace kodawari::rods
