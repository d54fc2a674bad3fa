#pragma once
/// @file
/// What a route asks of a bird (issue 14, docs/wing-types.md "Route limits"): the
/// tightest turn, the steepest climb and dive and the largest speed change along each
/// Bezier segment of a route, at the speed the bird flies it. The scene-level check
/// (kodawari/scene/route_check.hpp) compares them with the bird's limits.

#include <cstdint>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/world.hpp"

namespace kodawari::birds {

/// Samples per Bezier segment, uniform in the segment's parameter u. A limit exceeded
/// over more than 1/256 of a segment's parameter range contains a sample, so it cannot
/// be missed; for a route whose |P'| varies by a factor q along a segment, that is at
/// most q/256 of the segment's length. Shorter excesses are not physical at the scale
/// of a bird (a 100 m segment's step is 0.4 m, well under a wingspan of travel).
inline constexpr std::uint32_t kRouteCheckSamples = 256;

/// The worst point of one segment for each quantity. Angles in radians, lengths in m.
struct SegmentDemand {
    /// The largest turn load: speed^2 * curvature (m/s^2), the centripetal acceleration
    /// the wings must give; its point's radius of curvature, speed and parameter.
    double turn_acceleration = 0.0;
    double turn_radius = 0.0;
    double turn_speed = 0.0;
    double turn_u = 0.0;
    double climb = 0.0, climb_u = 0.0;  ///< steepest climb angle (>= 0 or the least dive)
    double dive = 0.0, dive_u = 0.0;    ///< steepest dive angle, positive down
    double speed_change = 0.0, speed_change_u = 0.0;  ///< largest |dv/dt| (m/s^2)
    double speed_change_speed = 0.0;                  ///< speed there (m/s)
    /// The junction where this segment starts (none on the first segment of an open
    /// route): the angle between the tangents either side (rad; a corner turns the bird
    /// that much in an instant), and the lateral acceleration just before and just after
    /// it (m/s^2, toward the bird's right, as the kernel computes it for the bank: a jump
    /// of curvature is a jump of the bank the route asks for).
    bool junction = false;
    double corner = 0.0;
    double lateral_before = 0.0, lateral_after = 0.0;
};

/// The demands of every segment of `route` (segment order) flown at `speed` (m/s,
/// arc-length timing) or at the route's own parametric timing (speed unused). Speed
/// changes are finite differences of the speed sampled along the route, so a jump of
/// speed at a junction (parametric timing through unequal handles) counts too.
[[nodiscard]] KODAWARI_API std::vector<SegmentDemand> route_demands(const BirdWorld& world, std::uint32_t route, float speed);

}  // namespace kodawari::birds
