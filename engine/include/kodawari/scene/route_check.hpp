#pragma once
/// @file
/// Routes a bird can fly (issue 14, docs/wing-types.md "Route limits"): every route of
/// every flock (all its variants) against its wing type's limits and the scene's bank
/// limit, and a fit that changes the flock's timing until the turns and speed changes
/// pass. `kodawari run` and `kodawari validate` warn with these messages.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari {

/// Which limit a route exceeds.
/// Corner and BankJump are of the junction where the segment starts (u = 0).
/// StartInside: a flocking flock's birds start inside one of its obstacles, where its
/// route and formation put them at frame 0 (`segment` is the obstacle's index in
/// `flocking.obstacles`, `value` how many birds): they are pushed out through it.
enum class RouteLimit : std::uint32_t { TurnRadius = 0, Climb = 1, Dive = 2, SpeedChange = 3, Corner = 4, BankJump = 5, StartInside = 6 };

/// Largest corner between the tangents either side of a junction (degrees): the bird's
/// heading follows the route's direction, so a corner is a turn in one frame (the roll
/// filter smooths the bank, not the heading). 2 degrees allows for control points typed
/// to one decimal.
inline constexpr double kMaxCornerDeg = 2.0;
/// Largest roll of the Body in the frame after a junction (degrees): the bank the route
/// asks for jumps there by d, and the roll filter (docs/flight-modes.md F.6) rolls
/// d (1 - e^(-dt/tau)) of it in the first frame, its fastest. 4 degrees leaves 2 of the
/// 6 degrees a frame a Body may turn (tests/birds/test_bank_filter.cpp) to the
/// wingbeat's pitch oscillation and the turn itself.
inline constexpr double kMaxRollPerFrameDeg = 4.0;

/// The worst point of one (flock, segment, limit) over the flock's route variants.
struct RouteWarning {
    std::size_t flock = 0;
    std::uint32_t segment = 0;
    RouteLimit limit = RouteLimit::TurnRadius;
    std::uint32_t variant = 0;  ///< 0: the leader route
    double u = 0.0;             ///< local parameter of the segment
    double value = 0.0;         ///< turn radius (m), angle (deg; bank jump: the roll in the first frame) or speed change (m/s^2)
    double bound = 0.0;         ///< the limit in the same unit (turn: the minimum radius at `speed`)
    double speed = 0.0;         ///< m/s at that point
    /// "scenes/x.json: $.flocks[1] \"gulls\": segment 3 (u = 0.42): turn radius 4.1 m at
    /// 12 m/s is below the gull's minimum 8.3 m (max bank 60 deg)".
    std::string message;
};

/// Checks the routes of `scene` (built into `world` by build_bird_world). Sorted by
/// flock, segment, limit. Never fails on a built world.
[[nodiscard]] KODAWARI_API std::vector<RouteWarning> check_routes(const Scene& scene, const birds::BirdWorld& world);

/// Builds the scene's bird world and checks it.
[[nodiscard]] KODAWARI_API Result<std::vector<RouteWarning>> check_routes(const Scene& scene);

/// Fits the routes and timing of every flock whose corners, turns, bank jumps or speed
/// changes exceed the limits: first a corner of an explicit route is smoothed (the two
/// handles at the junction turned onto the bisector of their directions, their lengths
/// kept: the route becomes C1 there); then arc-length timing lowers the flock's speed
/// (its `speed`, jitter kept) to the largest that passes, and parametric timing
/// lengthens the route's segment_duration (a generated route is then stored as the
/// explicit route it generates): a slower bird asks for less bank either side of a
/// junction. Climbs and dives do not depend on the timing and are left to the author;
/// so is a corner of a generated route (the generator makes none). Returns one line per change
/// ("$.flocks[1] \"gulls\": speed 16 -> 11.9 m/s (turn in segment 3)").
[[nodiscard]] KODAWARI_API Result<std::vector<std::string>> fit_routes(Scene& scene);

}  // namespace kodawari
