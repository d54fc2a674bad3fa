#pragma once
/// @file
/// Wingbeat functions (SPEC B.2, the seed's equations 4.1-4.5) and the pose of a wing
/// for a flight mode.

#include <cstdint>

#include <kodawari/shared/birds.h>

#include "kodawari/api.hpp"

namespace kodawari::birds {

/// Flight modes (SPEC B.5).
enum class FlightMode : std::uint32_t { Level = KW_MODE_LEVEL, Ascend = KW_MODE_ASCEND, Descend = KW_MODE_DESCEND };

/// "level", "ascend", "descend".
[[nodiscard]] KODAWARI_API const char* mode_name(FlightMode mode);

/// Angles of the left wing (radians). Pitch: rotation about the body's forward axis
/// (+Z), positive = wingtip up. Heading: rotation about the body's up axis (+Y),
/// positive = left wingtip swept backward. arm2's angles are relative to arm1. The right
/// wing mirrors the left.
struct WingAngles {
    float arm1_pitch = 0;
    float arm2_pitch = 0;
    float arm1_heading = 0;
    float arm2_heading = 0;
};

/// Eq. 4.1: level flight, arm1 pitch (a trapezoid; SPEC B.2 resolves the sign of the
/// last piece). t in [0, 2*pi).
[[nodiscard]] KODAWARI_API float level_arm1_pitch(float t);
/// Eq. 4.2: level-flight arm2 pitch, also the ascending arm1 pitch.
[[nodiscard]] KODAWARI_API float level_arm2_pitch(float t);
/// Eq. 4.3: ascending arm2 pitch.
[[nodiscard]] KODAWARI_API float ascend_arm2_pitch(float t);
/// Eq. 4.4: descending arm1 heading.
[[nodiscard]] KODAWARI_API float descend_arm1_heading(float t);
/// Eq. 4.5: descending arm2 heading.
[[nodiscard]] KODAWARI_API float descend_arm2_heading(float t);

/// The wing pose of `mode` at phase `t` (radians, [0, 2*pi)), every angle scaled by
/// `amplitude`.
[[nodiscard]] KODAWARI_API WingAngles wing_angles(FlightMode mode, float t, float amplitude);

}  // namespace kodawari::birds
