#pragma once
/// @file
/// Everything the bird backends consume, laid out exactly as the GPU reads it
/// (shaders/shared/birds.h): flight settings, a pool of routes with their arc-length
/// tables, and per-bird constants. Built from a scene (scene.hpp) or by hand.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/birds/bird_model.hpp"
#include "kodawari/birds/rig.hpp"

namespace kodawari::birds {

/// How the bank angle follows the route (SPEC B.4).
enum class BankRule : std::uint32_t { Coordinated = KW_BANK_COORDINATED, Seed = KW_BANK_SEED };
/// How the flight mode is chosen (SPEC B.5).
enum class ModeRule : std::uint32_t { Climb = KW_MODE_RULE_CLIMB, Seed = KW_MODE_RULE_SEED };
/// How time maps to the route parameter (SPEC B.3).
enum class RouteTiming : std::uint32_t { ArcLength = 0, Parametric = 1 };

/// Flight settings shared by all birds of a world. Angles in radians.
struct FlightSettings {
    float gravity = 9.81f;                  ///< for the coordinated-turn bank (m/s^2)
    float max_bank = 1.0471976f;            ///< 60 degrees
    /// Time constant of the roll filter (s): the bank and the head's look follow the
    /// route's through a first-order low-pass (docs/flight-modes.md F.6). 0: instantly.
    float bank_time = 0.3f;
    BankRule bank_rule = BankRule::Coordinated;
    ModeRule mode_rule = ModeRule::Climb;
    float ascend_enter = 0.17453292f;       ///< 10 degrees of climb
    float ascend_exit = 0.08726646f;        ///< 5 degrees
    float descend_enter = -0.17453292f;     ///< -10 degrees
    float descend_exit = -0.08726646f;      ///< -5 degrees
    float seed_accel_threshold = 0.05f;     ///< the seed's |a_y| threshold (route units/s^2)
    std::array<float, 3> blend_rates = {0.016f, 0.036f, 0.032f};  ///< alpha per 1/60 s into level, ascend, descend
    /// alpha per 1/60 s into glide, take-off, landing and hover (docs/flight-modes.md F.4):
    /// a take-off is a burst, so it is entered in about 10 frames; the others in half a second.
    std::array<float, 4> blend_rates2 = {0.032f, 0.1f, 0.05f, 0.05f};
};

/// A route segment's flight mode: chosen by the climb rule (SPEC B.5, with the flap-glide
/// rhythm), or given (docs/flight-modes.md F.1).
enum class SegmentMode : std::int32_t {
    Auto = -1,
    Glide = KW_MODE_GLIDE,
    TakeOff = KW_MODE_TAKEOFF,
    Landing = KW_MODE_LANDING,
    Hover = KW_MODE_HOVER,
};

/// "auto", "glide", "takeoff", "landing", "hover".
[[nodiscard]] KODAWARI_API const char* segment_mode_name(SegmentMode mode);

/// A route as given: 3n+1 control points of n cubic Bezier segments (consecutive
/// segments share an end point).
struct RouteSpec {
    std::vector<std::array<float, 3>> points;
    bool loop = false;                      ///< wrap around at the end (else fly on straight)
    RouteTiming timing = RouteTiming::ArcLength;
    float segment_duration = 2.0f;          ///< seconds per segment, parametric timing only
    /// One mode per segment, or empty (all Auto). A take-off may only be the first segment and
    /// a landing only the last, of an open route with arc-length timing (they set its speed).
    std::vector<SegmentMode> modes;
};

/// Arc-length intervals per Bezier segment in the table. u(s) is interpolated by cubic
/// Hermite polynomials with exact derivatives, whose error is O(h^4): at 32 intervals the
/// position error is far below the 1e-5 parity tolerance for any route we accept.
inline constexpr std::uint32_t kArcIntervalsPerSegment = 32;

/// The bird data of a scene, GPU layout.
struct KODAWARI_API BirdWorld {
    float fps = 60.0f;
    std::uint32_t frames = 0;
    FlightSettings settings;
    std::vector<gpu::RouteHeader> routes;
    std::vector<gpu::vec4> control_points;
    std::vector<gpu::ArcSample> arc_samples;
    std::vector<gpu::BirdParams> birds;
    /// The users' bird models the birds use (docs/bird-models.md): a bird whose
    /// BirdParams::ids.y is kWingTypeCount + k is of models[k]. Shared, not copied, by
    /// the worlds made from one scene (shards, the exporter, the renderer).
    std::vector<std::shared_ptr<const BirdModel>> models;
    /// Birds flown by another domain (a flocking flock's, issue 32): BirdParams::ids.w is
    /// KW_BIRD_DRIVEN and ids.z their slot in the motion each frame brings
    /// (BirdBackend::drive()); there are this many slots.
    std::uint32_t driven = 0;

    /// Adds a route (validated: finite, no coincident consecutive control points, no
    /// cusp) and returns its index. `what` names it in errors ("scene.json: $.flocks[0].route").
    [[nodiscard]] Result<std::uint32_t> add_route(const RouteSpec& route, const std::string& what);

    /// The uniforms for a dispatch.
    [[nodiscard]] gpu::FlightUniforms uniforms() const;

    /// Length of the longest route (m): the scale of position tolerances.
    [[nodiscard]] float max_route_length() const;
};

}  // namespace kodawari::birds
