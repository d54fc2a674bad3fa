// What a route asks of a bird: turn load, climb, dive and speed change per segment, and
// the corner and bank jump at each junction (docs/wing-types.md "Route limits"). Double precision from the stored float control
// points: this is a check, not part of the simulated bits.
#include "kodawari/birds/route_limits.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

namespace kodawari::birds {
namespace {

struct D3 {
    double x = 0, y = 0, z = 0;
};
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(double s, D3 a) { return {s * a.x, s * a.y, s * a.z}; }
double norm(D3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// One sample: P'(u), P''(u) of a segment (SPEC B.3).
struct Derivatives {
    D3 d1, d2;
};
Derivatives derivatives(const std::array<D3, 4>& b, double u) {
    const double v = 1.0 - u;
    return {3.0 * ((v * v) * (b[1] - b[0]) + (2.0 * u * v) * (b[2] - b[1]) + (u * u) * (b[3] - b[2])),
            6.0 * (v * (b[2] - 2.0 * b[1] + b[0]) + u * (b[3] - 2.0 * b[2] + b[1]))};
}

}  // namespace

std::vector<SegmentDemand> route_demands(const BirdWorld& world, std::uint32_t route_index, float cruise) {
    assert(route_index < world.routes.size());
    const gpu::RouteHeader& route = world.routes[route_index];
    const bool parametric = (route.flags.x & KW_ROUTE_PARAMETRIC) != 0;
    const bool loop = (route.flags.x & KW_ROUTE_LOOP) != 0;
    const double duration = route.info.y;
    const std::uint32_t segments = route.extent.y;
    constexpr std::uint32_t K = kRouteCheckSamples;

    std::vector<SegmentDemand> out(segments);
    // Speed along the route: the route's timing decides it (SPEC B.3). Arc-length timing
    // flies at the bird's speed throughout; a timing that accelerates (take-off, landing)
    // changes this one function, and the finite differences below then see it.
    const auto speed_at = [&](const Derivatives& d) { return parametric ? norm(d.d1) / duration : double{cruise}; };
    const auto controls = [&](std::uint32_t k) {
        const gpu::vec4* c = &world.control_points[route.extent.x + 3 * k];
        std::array<D3, 4> b;
        for (std::size_t i = 0; i < 4; ++i) b[i] = {c[i].x, c[i].y, c[i].z};
        return b;
    };
    // Time to fly from parameter u0 to u1 of a segment (trapezoid on |P'|, O(h^2) at
    // h = 1/256 of a segment: far below the few per cent that decide a speed limit).
    const auto step_time = [&](const Derivatives& a, const Derivatives& b, double du) {
        if (parametric) return duration * du;
        return 0.5 * (norm(a.d1) + norm(b.d1)) * du / double{cruise};
    };
    const auto note_speed_change = [](SegmentDemand& s, double dv, double dt, double u, double speed) {
        const double rate = std::fabs(dv) / dt;
        if (rate > s.speed_change) {
            s.speed_change = rate;
            s.speed_change_u = u;
            s.speed_change_speed = speed;
        }
    };

    for (std::uint32_t k = 0; k < segments; ++k) {
        const std::array<D3, 4> b = controls(k);
        SegmentDemand& s = out[k];
        s.climb = -10.0;  // any sample's angle is above
        s.dive = -10.0;
        Derivatives previous{};
        for (std::uint32_t j = 0; j <= K; ++j) {
            const double u = static_cast<double>(j) / K;
            const Derivatives d = derivatives(b, u);
            const double length = norm(d.d1);
            const double speed = speed_at(d);
            // Curvature |P' x P''| / |P'|^3; the wings' centripetal load is v^2 kappa.
            const double curvature = norm(cross(d.d1, d.d2)) / (length * length * length);
            const double load = speed * speed * curvature;
            if (load > s.turn_acceleration || j == 0) {
                s.turn_acceleration = load;
                s.turn_radius = curvature > 0.0 ? 1.0 / curvature : std::numeric_limits<double>::infinity();
                s.turn_speed = speed;
                s.turn_u = u;
            }
            const double angle = std::asin(std::clamp(d.d1.y / length, -1.0, 1.0));
            if (angle > s.climb) {
                s.climb = angle;
                s.climb_u = u;
            }
            if (-angle > s.dive) {
                s.dive = -angle;
                s.dive_u = u;
            }
            if (j > 0) {
                const double dt = step_time(previous, d, 1.0 / K);
                note_speed_change(s, speed - speed_at(previous), dt, u, speed);
            }
            previous = d;
        }
    }
    // Junctions: the speed on either side of a shared point may differ (parametric timing
    // through handles of unequal length). Compare the samples one step either side, two
    // steps apart in time, and charge the change to the segment that starts there.
    for (std::uint32_t k = 0; k < segments; ++k) {
        if (k == 0 && !loop) continue;
        const std::uint32_t before = k == 0 ? segments - 1 : k - 1;
        const std::array<D3, 4> a = controls(before);
        const std::array<D3, 4> c = controls(k);
        const double h = 1.0 / K;
        const Derivatives a0 = derivatives(a, 1.0 - h), a1 = derivatives(a, 1.0);
        const Derivatives c0 = derivatives(c, 0.0), c1 = derivatives(c, h);
        const double dt = step_time(a0, a1, h) + step_time(c0, c1, h);
        note_speed_change(out[k], speed_at(c1) - speed_at(a0), dt, 0.0, speed_at(c0));
        // Direction and curvature either side: the corner angle atan2(|P'- x P'+|, P'-.P'+),
        // and the lateral acceleration of flight.cpp step_bird() with v = speed T and
        // a = speed^2 P'' / |P'|^2 (under either timing; a's part along T has no lateral
        // component, so the normal part of docs' a = v^2 (P'' - (P''.T)T) / |P'|^2 gives the same).
        out[k].junction = true;
        out[k].corner = std::atan2(norm(cross(a1.d1, c0.d1)), a1.d1.x * c0.d1.x + a1.d1.y * c0.d1.y + a1.d1.z * c0.d1.z);
        const auto lateral = [&](const Derivatives& d) {
            const double length = norm(d.d1), speed = speed_at(d);
            const D3 v = (speed / length) * d.d1, acc = (speed * speed / (length * length)) * d.d2;
            const double horizontal = std::sqrt(v.x * v.x + v.z * v.z);
            return horizontal > 1e-3 ? (acc.x * -v.z + acc.z * v.x) / horizontal : 0.0;
        };
        out[k].lateral_before = lateral(a1);
        out[k].lateral_after = lateral(c0);
    }
    // Take-off and landing segments change the speed uniformly between rest and the
    // cruise speed (docs/flight-modes.md F.2): v^2 / (2 L) throughout. Their turns are
    // charged at the cruise speed above, the fastest they are flown.
    if (!parametric && (route.flags.x & KW_ROUTE_TAKEOFF) != 0) {
        note_speed_change(out.front(), double{cruise} * double{cruise} * 0.5 * double{route.perch.y}, 1.0, 1.0, double{cruise});
    }
    if (!parametric && (route.flags.x & KW_ROUTE_LANDING) != 0) {
        note_speed_change(out.back(), double{cruise} * double{cruise} * 0.5 * double{route.perch.w}, 1.0, 0.0, double{cruise});
    }
    return out;
}

}  // namespace kodawari::birds
