#pragma once
/// @file
/// Wingbeat functions (SPEC B.2, the seed's equations 4.1-4.5) and the pose of a wing
/// for a flight mode.

#include <cstdint>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"

namespace kodawari::birds {

/// Flight modes: the seed's three (SPEC B.5) and glide, take-off, landing and hover
/// (docs/flight-modes.md).
enum class FlightMode : std::uint32_t {
    Level = KW_MODE_LEVEL,
    Ascend = KW_MODE_ASCEND,
    Descend = KW_MODE_DESCEND,
    Glide = KW_MODE_GLIDE,
    TakeOff = KW_MODE_TAKEOFF,
    Landing = KW_MODE_LANDING,
    Hover = KW_MODE_HOVER,
};
inline constexpr std::uint32_t kFlightModeCount = KW_MODE_COUNT;

/// "level", "ascend", "descend", "glide", "takeoff", "landing", "hover".
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

/// The wing pose of one of the seed's modes (level, ascend, descend) at phase `t`
/// (radians, [0, 2*pi)), every angle scaled by `amplitude`.
[[nodiscard]] KODAWARI_API WingAngles wing_angles(FlightMode mode, float t, float amplitude);

/// Where a bird is in a take-off or a landing (docs/flight-modes.md F.2).
struct PerchProgress {
    float speed_fraction = 1.0f;    ///< speed / the bird's cruise speed
    float since_crouch = 1e9f;      ///< seconds since the crouch ended (< 0 while crouching)
    float since_touchdown = -1.0f;  ///< seconds since touchdown (< 0 before)
};

/// Key poses (docs/flight-modes.md F.3).
inline constexpr WingAngles kFoldedWings{-0.2f, 0.1f, 1.35f, 0.25f};
inline constexpr WingAngles kGlideWings{0.06f, -0.04f, 0.08f, 0.12f};
inline constexpr WingAngles kFlareWings{0.45f, -0.35f, -0.55f, 0.25f};
/// Take-off timing (s): crouch on the perch, then the leap that opens the wings.
inline constexpr float kCrouchSeconds = static_cast<float>(KW_CROUCH_SECONDS);
inline constexpr float kLeapSeconds = static_cast<float>(KW_LEAP_SECONDS);
/// Seconds to fold the wings after touchdown.
inline constexpr float kFoldSeconds = static_cast<float>(KW_FOLD_SECONDS);
/// Body bob, head and tail (docs/flight-modes.md F.5; shared/birds.h).
inline constexpr float kBobHeight = static_cast<float>(KW_BOB_HEIGHT);
inline constexpr float kBobPitch = static_cast<float>(KW_BOB_PITCH);
inline constexpr float kLookAhead = static_cast<float>(KW_LOOK_AHEAD);
inline constexpr float kMaxLook = static_cast<float>(KW_MAX_LOOK);
inline constexpr float kHeadPitchHold = static_cast<float>(KW_HEAD_PITCH_HOLD);
inline constexpr float kHeadBobHold = static_cast<float>(KW_HEAD_BOB_HOLD);
inline constexpr float kHeadBankHold = static_cast<float>(KW_HEAD_BANK_HOLD);
inline constexpr float kHeadClimbHold = static_cast<float>(KW_HEAD_CLIMB_HOLD);
inline constexpr float kTailClimb = static_cast<float>(KW_TAIL_CLIMB);
inline constexpr float kTailPitch = static_cast<float>(KW_TAIL_PITCH);
inline constexpr float kTailBank = static_cast<float>(KW_TAIL_BANK);
inline constexpr float kTailBankSpread = static_cast<float>(KW_TAIL_BANK_SPREAD);

/// Everything a mode adds to a bird's pose besides the route (docs/flight-modes.md F.3, F.5).
struct ModeLook {
    WingAngles wings;    ///< the left wing
    float pitch = 0.0f;  ///< extra body pitch, nose up (rad)
    float spread = 0.0f; ///< tail spread s (the Tail's width scale is 1 + s)
    float bob = 0.0f;    ///< weight of the wingbeat's body bob and pitch oscillation
};

/// The look of any mode at phase `t` with `amplitude` (the seed's modes' wings are
/// wing_angles()).
[[nodiscard]] KODAWARI_API ModeLook mode_look(FlightMode mode, float t, float amplitude, const PerchProgress& progress);

/// Wingbeat frequency factor of a mode: 0 while the wings are held (glide, crouch, perched).
[[nodiscard]] KODAWARI_API float beat_factor(FlightMode mode, const PerchProgress& progress);

}  // namespace kodawari::birds
