#pragma once
/// @file
/// The bird rig (SPEC B.1): seven parts and the wing types with dimensions, flap
/// frequency and cruise speed from real birds (sources in docs/wing-types.md).

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"

namespace kodawari::birds {

/// The wing types: the seed's three, by aspect ratio, a hovering type, and the starling
/// that the flocking scenes fly. New types go last: the numbers are the C API's
/// (kodawari_wing_type) and a user's bird models are numbered after them
/// (kWingTypeCount + model index, never stored in an export).
enum class WingType : std::uint32_t { Pigeon = 0, Gull = 1, Hawk = 2, Hummingbird = 3, Starling = 4 };
inline constexpr std::size_t kWingTypeCount = 5;

/// The rig's parts in BirdPose order.
enum class Part : std::uint32_t {
    Body = KW_PART_BODY,
    Head = KW_PART_HEAD,
    Tail = KW_PART_TAIL,
    LeftArm1 = KW_PART_LEFT_ARM1,
    LeftArm2 = KW_PART_LEFT_ARM2,
    RightArm1 = KW_PART_RIGHT_ARM1,
    RightArm2 = KW_PART_RIGHT_ARM2,
};
inline constexpr std::size_t kPartCount = KW_PART_COUNT;

/// glTF node names of the parts, in Part order.
inline constexpr std::array<std::string_view, kPartCount> kPartNames = {
    "Body", "Head", "Tail", "LeftArm1", "LeftArm2", "RightArm1", "RightArm2"};

/// Parent of each part (-1 for Body).
inline constexpr std::array<int, kPartCount> kPartParents = {-1, 0, 0, 0, 3, 0, 5};

/// Size and motion defaults of a wing type. Axes (glTF): +Y up, +Z forward, +X the
/// bird's left. Lengths in metres, mass in kg.
struct WingTypeSpec {
    std::string_view name;         ///< "pigeon", "gull", "hawk", "hummingbird", "starling"
    float wingspan;                ///< tip to tip, wings spread
    float body_length;             ///< beak to tail tip
    float mass;                    ///< body mass
    float mean_chord;              ///< wing area / span
    float flap_frequency;          ///< wingbeat frequency in level flight (Hz)
    float cruise_speed;            ///< typical flight speed (m/s)
    float amplitude;               ///< default scale of the wingbeat angles (1 = the seed's)
    float arm1_fraction;           ///< share of the half-span taken by arm1 (inner wing)
    float glide_ratio;             ///< best lift-to-drag ratio in a glide (docs/wing-types.md)
    float flap_glide_beats;        ///< wingbeats per flap-glide cycle in level flight (0: flaps continuously)
    float flap_glide_seconds;      ///< glide time per flap-glide cycle (s)
    bool can_hover;                ///< hovers with figure-eight strokes (docs/flight-modes.md)
    float max_climb;               ///< steepest sustained climb (rad)
    float max_dive;                ///< steepest dive (rad, positive)
    float max_speed_change;        ///< largest tangential acceleration or deceleration (m/s^2)
};

/// The spec of a wing type.
[[nodiscard]] KODAWARI_API const WingTypeSpec& wing_type_spec(WingType type);

/// Parses "pigeon", "gull", "hawk", "hummingbird" or "starling".
[[nodiscard]] KODAWARI_API std::optional<WingType> parse_wing_type(std::string_view name);

/// BirdParams::flight of a bird with this spec (glide ratio, flap-glide rhythm, hover).
[[nodiscard]] KODAWARI_API gpu::vec4 flight_params(const WingTypeSpec& spec);
/// BirdParams::shape of a bird with this spec (body length, wingspan).
[[nodiscard]] KODAWARI_API gpu::vec4 shape_params(const WingTypeSpec& spec);

/// Rest translation of every part relative to its parent (Body: zero), metres.
[[nodiscard]] KODAWARI_API std::array<std::array<float, 3>, kPartCount> part_offsets(WingType type);

}  // namespace kodawari::birds
