#include "kodawari/birds/world.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace kodawari::birds {
namespace {

struct D3 {
    double x, y, z;
};
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(double s, D3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(D3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// P'(u) of a cubic Bezier segment, SPEC B.3 (with the factor 3).
D3 bezier_d1(const D3* b, double u) {
    const double v = 1.0 - u;
    return 3.0 * (v * v * (b[1] - b[0]) + 2.0 * u * v * (b[2] - b[1]) + u * u * (b[3] - b[2]));
}

// Arc length of [u0, u1] by 8-point Gauss-Legendre quadrature. |P'| of a cubic is smooth,
// so on 1/32 of a segment this is exact to far below float precision.
double arc_length(const D3* b, double u0, double u1) {
    static constexpr double kNodes[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static constexpr double kWeights[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    const double half = 0.5 * (u1 - u0);
    const double mid = 0.5 * (u1 + u0);
    double sum = 0.0;
    for (int i = 0; i < 4; ++i) {
        sum += kWeights[i] * (norm(bezier_d1(b, mid - half * kNodes[i])) + norm(bezier_d1(b, mid + half * kNodes[i])));
    }
    return half * sum;
}

Result<void> check_modes(const RouteSpec& route, const std::string& what) {
    const std::size_t segments = (route.points.size() - 1) / 3;
    if (route.modes.size() != segments) {
        return make_error(Error::Kind::InvalidInput, what + ".modes: expected one mode per segment (" + std::to_string(segments) +
                                                         "), got " + std::to_string(route.modes.size()));
    }
    for (std::size_t k = 0; k < segments; ++k) {
        const SegmentMode m = route.modes[k];
        const std::string at = what + ".modes[" + std::to_string(k) + "]: ";
        const bool perch = m == SegmentMode::TakeOff || m == SegmentMode::Landing;
        if (m == SegmentMode::TakeOff && k != 0) {
            return make_error(Error::Kind::InvalidInput, at + "\"takeoff\" may only be the first segment (a take-off starts from a perch)");
        }
        // A landing needs a flight before it: a route may not start with one.
        if (m == SegmentMode::Landing && (k == 0 || k + 1 != segments)) {
            return make_error(Error::Kind::InvalidInput,
                              at + (k == 0 ? "a route cannot start with \"landing\"" : "\"landing\" may only be the last segment") +
                                  " (a landing ends the route on a perch)");
        }
        if (perch && route.loop) {
            return make_error(Error::Kind::InvalidInput, at + "\"" + segment_mode_name(m) + "\" needs an open route; this one loops");
        }
        if (perch && route.timing == RouteTiming::Parametric) {
            return make_error(Error::Kind::InvalidInput,
                              at + "\"" + segment_mode_name(m) + "\" sets the speed along the route; expected \"timing\": \"arc-length\"");
        }
    }
    return {};
}

std::string point_text(const std::array<float, 3>& p) {
    return "[" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " + std::to_string(p[2]) + "]";
}

}  // namespace

const char* segment_mode_name(SegmentMode mode) {
    switch (mode) {
        case SegmentMode::Auto: return "auto";
        case SegmentMode::Glide: return "glide";
        case SegmentMode::TakeOff: return "takeoff";
        case SegmentMode::Landing: return "landing";
        case SegmentMode::Hover: return "hover";
    }
    return "auto";
}

Result<std::uint32_t> BirdWorld::add_route(const RouteSpec& route, const std::string& what) {
    const auto& pts = route.points;
    if (pts.size() < 4 || (pts.size() - 1) % 3 != 0) {
        return make_error(Error::Kind::InvalidInput,
                          what + ".points: expected 3n+1 control points (n >= 1 cubic Bezier segments), got " +
                              std::to_string(pts.size()));
    }
    for (std::size_t i = 0; i < pts.size(); ++i) {
        for (float c : pts[i]) {
            if (!std::isfinite(c) || std::fabs(c) > 1e6f) {
                return make_error(Error::Kind::InvalidInput, what + ".points[" + std::to_string(i) +
                                                                 "]: expected finite coordinates within 1e6 m");
            }
        }
    }
    if (route.timing == RouteTiming::Parametric && !(route.segment_duration > 0.0f && std::isfinite(route.segment_duration))) {
        return make_error(Error::Kind::InvalidInput, what + ".segment_duration: expected a positive number of seconds");
    }
    if (!route.modes.empty()) KW_TRY(check_modes(route, what));
    if (route.loop && pts.front() != pts.back()) {
        return make_error(Error::Kind::InvalidInput,
                          what + ".loop: a looping route must end where it starts; points[" + std::to_string(pts.size() - 1) +
                              "] " + point_text(pts.back()) + " differs from points[0] " + point_text(pts.front()));
    }
    const std::uint32_t segments = static_cast<std::uint32_t>((pts.size() - 1) / 3);
    std::vector<D3> p(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) p[i] = {pts[i][0], pts[i][1], pts[i][2]};

    // Coincident consecutive control points make P' vanish at a segment end, where the
    // heading is then undefined.
    double extent = 0.0;
    for (std::size_t i = 0; i + 1 < p.size(); ++i) extent = std::max(extent, norm(p[i + 1] - p[0]));
    for (std::size_t i = 0; i + 1 < p.size(); ++i) {
        if (norm(p[i + 1] - p[i]) <= 1e-6 * std::max(extent, 1.0)) {
            return make_error(Error::Kind::InvalidInput,
                              what + ".points[" + std::to_string(i + 1) + "]: coincides with points[" + std::to_string(i) +
                                  "] " + point_text(pts[i]) + "; expected distinct consecutive control points");
        }
    }

    gpu::RouteHeader header{};
    header.extent = {static_cast<std::uint32_t>(control_points.size()), segments,
                     static_cast<std::uint32_t>(arc_samples.size()), segments * kArcIntervalsPerSegment + 1};
    header.flags = {(route.loop ? KW_ROUTE_LOOP : 0u) | (route.timing == RouteTiming::Parametric ? KW_ROUTE_PARAMETRIC : 0u), 0,
                    0, 0};

    std::vector<gpu::ArcSample> samples;
    samples.reserve(header.extent.w);
    double s = 0.0;
    for (std::uint32_t k = 0; k < segments; ++k) {
        const D3* b = &p[3 * k];
        const double seg_chord = norm(b[3] - b[0]) + norm(b[1] - b[0]) + norm(b[2] - b[1]) + norm(b[3] - b[2]);
        D3 previous_d1{};
        for (std::uint32_t j = 0; j <= kArcIntervalsPerSegment; ++j) {
            const double u = static_cast<double>(j) / kArcIntervalsPerSegment;
            const D3 d1 = bezier_d1(b, u);
            const double speed = norm(d1);
            // A cusp (P' = 0 inside a segment) leaves the heading undefined there; the
            // tangent then turns back within one table interval.
            const bool turns_back = j > 0 && dot(d1, previous_d1) <= 0.0;
            previous_d1 = d1;
            if (speed <= 1e-4 * seg_chord || turns_back) {
                return make_error(Error::Kind::InvalidInput,
                                  what + ": segment " + std::to_string(k) +
                                      " has a cusp (the curve stops and turns back); expected a smooth route");
            }
            if (j > 0) s += arc_length(b, static_cast<double>(j - 1) / kArcIntervalsPerSegment, u);
            const auto duds = static_cast<float>(1.0 / speed);
            if (j == 0 && k > 0) {
                samples.back().s_u_duds.w = duds;  // junction: the right-hand derivative
                continue;
            }
            samples.push_back({{static_cast<float>(s), static_cast<float>(k + u), duds, duds}, {0.0f, 0.0f, 0.0f, 0.0f}});
        }
    }
    // Reciprocals from the stored floats, so every backend multiplies by the same values.
    for (std::size_t j = 0; j + 1 < samples.size(); ++j) {
        samples[j].next.x = 1.0f / (samples[j + 1].s_u_duds.x - samples[j].s_u_duds.x);
    }
    const auto length = static_cast<float>(s);
    header.info = {length, route.segment_duration, 1.0f / length, 1.0f / route.segment_duration};

    // The segment's mode rides in the w of its first control point (shared/birds.h).
    for (std::size_t i = 0; i < p.size(); ++i) {
        const std::size_t k = i / 3;
        const float mode = i % 3 == 0 && k < segments && !route.modes.empty() ? static_cast<float>(route.modes[k])
                           : i % 3 == 0 && k < segments                       ? static_cast<float>(KW_SEGMENT_AUTO)
                                                                              : 0.0f;
        control_points.push_back({static_cast<float>(p[i].x), static_cast<float>(p[i].y), static_cast<float>(p[i].z), mode});
    }
    // Take-off and landing segments (docs/flight-modes.md F.2): their lengths and
    // reciprocals, from the table's floats so that every backend uses the same values.
    if (!route.modes.empty() && route.modes.front() == SegmentMode::TakeOff) {
        header.flags.x |= KW_ROUTE_TAKEOFF;
        header.perch.x = samples[kArcIntervalsPerSegment].s_u_duds.x;
        header.perch.y = 1.0f / header.perch.x;
    }
    if (!route.modes.empty() && route.modes.back() == SegmentMode::Landing) {
        header.flags.x |= KW_ROUTE_LANDING;
        header.perch.z = length - samples[samples.size() - 1 - kArcIntervalsPerSegment].s_u_duds.x;
        header.perch.w = 1.0f / header.perch.z;
    }
    arc_samples.insert(arc_samples.end(), samples.begin(), samples.end());
    routes.push_back(header);
    return static_cast<std::uint32_t>(routes.size() - 1);
}

gpu::FlightUniforms BirdWorld::uniforms() const {
    const FlightSettings& f = settings;
    const auto dt = static_cast<float>(1.0 / static_cast<double>(fps));
    gpu::FlightUniforms u{};
    u.physics = {f.gravity, f.max_bank, dt, static_cast<float>(60.0 / static_cast<double>(fps))};
    // Thresholds on the climb angle g become thresholds on sin(g)|sin(g)|, compared
    // with P'_y |P'_y| / |P'|^2 without square roots or divisions.
    auto signed_square_sine = [](float angle) {
        const double s = std::sin(static_cast<double>(angle));
        return static_cast<float>(s * std::fabs(s));
    };
    u.climb = {signed_square_sine(f.ascend_enter), signed_square_sine(f.ascend_exit), signed_square_sine(f.descend_enter),
               signed_square_sine(f.descend_exit)};
    u.blend_rates = {f.blend_rates[0], f.blend_rates[1], f.blend_rates[2], f.seed_accel_threshold};
    u.rules = {static_cast<std::uint32_t>(f.bank_rule), static_cast<std::uint32_t>(f.mode_rule),
               static_cast<std::uint32_t>(birds.size()), 0};
    // The roll filter keeps e^(-dt/tau) of what is left to roll each frame (F.6), computed
    // here once, in double: the kernels then need no exp.
    const double keep = f.bank_time > 0.0f ? std::exp(-static_cast<double>(dt) / double{f.bank_time}) : 0.0;
    u.bank_limit = {static_cast<float>(std::cos(double{f.max_bank})), static_cast<float>(std::sin(double{f.max_bank})),
                    static_cast<float>(keep), 0.0f};
    u.blend_rates2 = {f.blend_rates2[0], f.blend_rates2[1], f.blend_rates2[2], f.blend_rates2[3]};
    return u;
}

float BirdWorld::max_route_length() const {
    float length = 0.0f;
    for (const auto& r : routes) length = std::max(length, r.info.x);
    return length;
}

}  // namespace kodawari::birds
