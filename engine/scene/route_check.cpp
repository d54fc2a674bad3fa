// Routes a bird can fly: the demands of every flock's routes (birds/route_limits.hpp)
// against its wing type's limits (docs/wing-types.md "Route limits"), and the timing fit
// of `--fit-routes`.
#include <kodawari/scene/route_check.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <kodawari/birds/flight.hpp>
#include <kodawari/birds/route_limits.hpp>

namespace kodawari {
namespace {

constexpr double kRadToDeg = 57.29577951308232;

// Three significant digits: a warning is read by a person, and the limits themselves
// are not known to more.
std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", v);
    return text;
}

// The routes one flock's birds fly: each used variant with the fastest speed on it.
struct FlownRoute {
    std::uint32_t route = 0;
    std::uint32_t variant = 0;
    double speed = 0.0;  // the fastest bird on it (m/s; arc-length timing)
};

// Routes per flock, in flock order. build_bird_world appends each flock's birds in
// order and gives bird b variant b % variants.
std::vector<std::vector<FlownRoute>> flown_routes(const Scene& scene, const birds::BirdWorld& world) {
    std::vector<std::vector<FlownRoute>> out(scene.flocks.size());
    std::size_t first = 0;
    for (std::size_t f = 0; f < scene.flocks.size(); ++f) {
        const FlockSpec& flock = scene.flocks[f];
        const std::uint32_t variants = std::max(flock.formation.route_variants, 1u);
        const std::uint32_t used = std::min(variants, flock.count);
        out[f].resize(used);
        for (std::uint32_t b = 0; b < flock.count && first + b < world.birds.size(); ++b) {
            const gpu::BirdParams& p = world.birds[first + b];
            FlownRoute& r = out[f][b % variants];
            r.route = p.ids.x;
            r.variant = b % variants;
            r.speed = std::max(r.speed, double{p.motion.x});
        }
        first += flock.count;
    }
    return out;
}

// g tan(max bank): the largest centripetal acceleration a coordinated turn gives
// (r_min = v^2 / (g tan(max_bank)), docs/wing-types.md). 0 turns the check off.
double turn_capacity(const Scene& scene) {
    return double{scene.flight.gravity} * std::tan(double{scene.flight.max_bank});
}

// v rounded down (or up) to three significant digits: the fitted figure is then the one
// printed, which the author can copy into the scene, and still on the safe side.
double round_3_digits(double v, bool up) {
    const double scale = std::pow(10.0, 2.0 - std::floor(std::log10(v)));
    return (up ? std::ceil(v * scale) : std::floor(v * scale)) / scale;
}

struct Worst {
    RouteWarning warning;
    double excess = 0.0;  // value / limit, > 1 when violated
};

constexpr std::size_t kLimits = 6;  // RouteLimit's values up to BankJump: a route's own limits

// What a flock's birds can fly: its wing type's limits, or for a user's bird (`"model"`)
// those derived from its wing (birds::derive_flight), under the bird's own name.
struct FlockLimits {
    std::string name;
    double cruise_speed = 0.0;
    double max_climb = 0.0;
    double max_dive = 0.0;
    double max_speed_change = 0.0;
};

FlockLimits flock_limits(const FlockSpec& flock) {
    if (flock.model) {
        const birds::DerivedFlight& f = flock.model->flight;
        return {flock.model->name.empty() ? "bird of " + flock.model_file : flock.model->name, double{f.cruise_speed},
                double{f.max_climb}, double{f.max_dive}, double{f.max_speed_change}};
    }
    const birds::WingTypeSpec& wing = birds::wing_type_spec(flock.wing_type);
    return {std::string(wing.name), double{wing.cruise_speed}, double{wing.max_climb}, double{wing.max_dive},
            double{wing.max_speed_change}};
}

// The bank the coordinated rule asks for at a lateral acceleration (flight.cpp
// body_frame()): atan2(a_lat, g) within the scene's max bank.
double bank_for(const Scene& scene, double lateral) {
    const double max_bank = double{scene.flight.max_bank};
    return std::clamp(std::atan2(lateral, double{scene.flight.gravity}), -max_bank, max_bank);
}

// The share of a bank jump the roll filter rolls in the first frame after it, its
// fastest (docs/flight-modes.md F.6): 1 - e^(-dt/tau), 1 without a filter.
double first_frame_share(const Scene& scene) {
    const double tau = double{scene.flight.bank_time};
    return tau > 0.0 ? 1.0 - std::exp(-1.0 / (double{scene.fps} * tau)) : 1.0;
}

// The roll in the first frame after the junction where segment `d` starts (degrees).
double junction_roll_deg(const Scene& scene, const birds::SegmentDemand& d) {
    return std::fabs(bank_for(scene, d.lateral_after) - bank_for(scene, d.lateral_before)) * first_frame_share(scene) * kRadToDeg;
}

// Whether p is inside obstacle o (not its margin: the solid itself).
bool inside(const FlockObstacleSpec& o, const birds::Vec3& p) {
    const glm::vec3 q(p.x, p.y, p.z);
    switch (o.type) {
        case FlockObstacleSpec::Type::Sphere: return glm::length(q - o.a) < o.radius;
        case FlockObstacleSpec::Type::Capsule: {
            const glm::vec3 ab = o.b - o.a;
            const float ab2 = glm::dot(ab, ab);
            const float t = ab2 > 0.0f ? std::clamp(glm::dot(q - o.a, ab) / ab2, 0.0f, 1.0f) : 0.0f;
            return glm::length(q - (o.a + t * ab)) < o.radius;
        }
        case FlockObstacleSpec::Type::Plane: return glm::dot(q - o.a, o.b) < 0.0f;
    }
    return false;
}

// The birds of flocking flock f (world.birds from `first`) that frame 0 puts inside one of
// its obstacles: where its route and formation place them, as the flocking world's frame 0
// (domains/flocking/flock_world.cpp). One warning per obstacle.
void start_inside(const Scene& scene, const birds::BirdWorld& world, std::size_t f, std::size_t first,
                  std::vector<RouteWarning>& out) {
    const FlockSpec& flock = scene.flocks[f];
    const std::vector<FlockObstacleSpec>& obstacles = flock.flocking->obstacles;
    if (obstacles.empty()) return;
    std::vector<std::uint32_t> count(obstacles.size(), 0);
    for (std::size_t b = first; b < first + flock.count && b < world.birds.size(); ++b) {
        const gpu::BirdParams& bird = world.birds[b];
        const birds::RouteSample s = birds::sample_route(world, bird.ids.x, bird.offset.w, bird.motion.x);
        const birds::Vec3 p{s.position.x + bird.offset.x, s.position.y + bird.offset.y, s.position.z + bird.offset.z};
        for (std::size_t k = 0; k < obstacles.size(); ++k) count[k] += inside(obstacles[k], p) ? 1u : 0u;
    }
    static constexpr const char* kKinds[] = {"a sphere", "a capsule", "a plane"};
    for (std::size_t k = 0; k < obstacles.size(); ++k) {
        if (count[k] == 0) continue;
        RouteWarning w{f, static_cast<std::uint32_t>(k), RouteLimit::StartInside, 0, 0.0, double(count[k]), 0.0, 0.0, {}};
        w.message = scene.path + ": $.flocks[" + std::to_string(f) + "] \"" + flock.name + "\": " + std::to_string(count[k]) +
                    " of " + std::to_string(flock.count) + " birds start inside flocking.obstacles[" + std::to_string(k) + "] (" +
                    kKinds[static_cast<std::size_t>(obstacles[k].type)] +
                    "), where the route and formation put them at frame 0: they are pushed out through it (move the "
                    "obstacle, the route's start or formation.spread)";
        out.push_back(std::move(w));
    }
}

}  // namespace

std::vector<RouteWarning> check_routes(const Scene& scene, const birds::BirdWorld& world) {
    std::vector<RouteWarning> out;
    const std::vector<std::vector<FlownRoute>> flown = flown_routes(scene, world);
    const double capacity = turn_capacity(scene);
    const double bank_deg = double{scene.flight.max_bank} * kRadToDeg;
    std::size_t first_bird = 0;
    for (std::size_t f = 0; f < scene.flocks.size(); ++f) {
        const FlockSpec& flock = scene.flocks[f];
        const std::size_t flock_first = first_bird;
        first_bird += flock.count;
        // A flocking flock's birds do not fly its route: it only draws them
        // (docs/flocking.md), and their own flight keeps within their wing's limits. What
        // can be wrong is where they start.
        if (flock.flocking) {
            start_inside(scene, world, f, flock_first, out);
            continue;
        }
        const FlockLimits wing = flock_limits(flock);
        const std::string who = wing.name;
        const std::string prefix = scene.path + ": $.flocks[" + std::to_string(f) + "] \"" + flock.name + "\": ";
        std::vector<std::array<Worst, kLimits>> worst;
        for (const FlownRoute& r : flown[f]) {
            const std::vector<birds::SegmentDemand> demands = birds::route_demands(world, r.route, static_cast<float>(r.speed));
            worst.resize(std::max(worst.size(), demands.size()));
            for (std::uint32_t k = 0; k < demands.size(); ++k) {
                const birds::SegmentDemand& d = demands[k];
                const auto consider = [&](RouteLimit limit, double excess, double u, double value, double bound, double speed) {
                    Worst& w = worst[k][static_cast<std::size_t>(limit)];
                    if (!(excess > 1.0) || excess <= w.excess) return;
                    w.excess = excess;
                    w.warning = {f, k, limit, r.variant, u, value, bound, speed, {}};
                };
                if (capacity > 0.0) {
                    const double minimum = d.turn_speed * d.turn_speed / capacity;
                    consider(RouteLimit::TurnRadius, d.turn_acceleration / capacity, d.turn_u, d.turn_radius, minimum,
                             d.turn_speed);
                }
                consider(RouteLimit::Climb, d.climb / wing.max_climb, d.climb_u, d.climb * kRadToDeg,
                         wing.max_climb * kRadToDeg, 0.0);
                consider(RouteLimit::Dive, d.dive / wing.max_dive, d.dive_u, d.dive * kRadToDeg, wing.max_dive * kRadToDeg,
                         0.0);
                consider(RouteLimit::SpeedChange, d.speed_change / wing.max_speed_change, d.speed_change_u, d.speed_change,
                         wing.max_speed_change, d.speed_change_speed);
                if (d.junction) {
                    const double corner = d.corner * kRadToDeg;
                    consider(RouteLimit::Corner, corner / kMaxCornerDeg, 0.0, corner, kMaxCornerDeg, r.speed);
                    const double roll = junction_roll_deg(scene, d);
                    consider(RouteLimit::BankJump, roll / kMaxRollPerFrameDeg, 0.0, roll, kMaxRollPerFrameDeg, r.speed);
                }
            }
        }
        const std::uint32_t variants = std::max(flock.formation.route_variants, 1u);
        for (const auto& segment : worst) {
            for (const Worst& w : segment) {
                if (w.excess <= 1.0) continue;
                RouteWarning warning = w.warning;
                std::string text = prefix + "segment " + std::to_string(warning.segment) + " (u = " + number(warning.u) + "): ";
                switch (warning.limit) {
                    case RouteLimit::TurnRadius:
                        text += "turn radius " + number(warning.value) + " m at " + number(warning.speed) +
                                " m/s is below the " + who + "'s minimum " + number(warning.bound) + " m (max bank " +
                                number(bank_deg) + " deg)";
                        break;
                    case RouteLimit::Climb:
                        text += "climb " + number(warning.value) + " deg is above the " + who + "'s maximum " +
                                number(warning.bound) + " deg";
                        break;
                    case RouteLimit::Dive:
                        text += "dive " + number(warning.value) + " deg is above the " + who + "'s maximum " +
                                number(warning.bound) + " deg";
                        break;
                    case RouteLimit::SpeedChange:
                        text += "speed change " + number(warning.value) + " m/s^2 at " + number(warning.speed) +
                                " m/s is above the " + who + "'s maximum " + number(warning.bound) + " m/s^2";
                        break;
                    case RouteLimit::Corner:
                        text += "the route turns " + number(warning.value) + " deg at the junction with segment " +
                                std::to_string(warning.segment == 0 ? worst.size() - 1 : warning.segment - 1) +
                                " (a corner: the bird's heading turns that much in one frame; the largest is " +
                                number(warning.bound) + " deg: make the handles either side of the junction collinear)";
                        break;
                    case RouteLimit::BankJump:
                        text += "the bank the route asks for jumps at the junction with segment " +
                                std::to_string(warning.segment == 0 ? worst.size() - 1 : warning.segment - 1) + " at " +
                                number(warning.speed) + " m/s: the " + who + " rolls " + number(warning.value) +
                                " deg in one frame, above " + number(warning.bound) + " (" +
                                (flock.generated_route ? std::string("fly slower")
                                                       : std::string("match the curvature either side, or fly slower")) +
                                "; flight.bank_time_constant " + number(double{scene.flight.bank_time}) + " s)";
                        break;
                    case RouteLimit::StartInside: break;  // a flocking flock's, start_inside()
                }
                // A generated route's waypoints are the seed's, not the user's to move: what
                // makes its turns gentler is more room between them.
                if (flock.generated_route) {
                    text += "; generated_route's turns are gentler with a larger extent or fewer segments";
                }
                if (warning.variant > 0) {
                    text += " (in route variant " + std::to_string(warning.variant) + " of " + std::to_string(variants) + ")";
                }
                warning.message = std::move(text);
                out.push_back(std::move(warning));
            }
        }
    }
    return out;
}

Result<std::vector<RouteWarning>> check_routes(const Scene& scene) {
    auto world = build_bird_world(scene);
    if (!world) return world.error();
    return check_routes(scene, world.value());
}

namespace {

// Turns the two handles at each cornered junction of an explicit route onto the bisector
// of their directions, their lengths kept: the tangent is then continuous there (the
// route C1) and the path moves by less than the handles' lengths. One line per junction.
void smooth_corners(Scene& scene, std::size_t f, std::vector<std::string>& changes) {
    FlockSpec& flock = scene.flocks[f];
    if (!flock.route) return;
    std::vector<std::array<float, 3>>& points = flock.route->points;
    const std::size_t segments = (points.size() - 1) / 3;
    using P = std::array<double, 3>;
    const auto at = [&](std::size_t i) { return P{points[i][0], points[i][1], points[i][2]}; };
    const auto length = [](const P& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); };
    for (std::size_t k = 0; k < segments; ++k) {
        if (k == 0 && !flock.route->loop) continue;
        const std::size_t junction = 3 * k, before = k == 0 ? 3 * segments - 1 : 3 * k - 1, after = 3 * k + 1;
        const P j = at(junction), b = at(before), a = at(after);
        const P in{j[0] - b[0], j[1] - b[1], j[2] - b[2]}, out{a[0] - j[0], a[1] - j[1], a[2] - j[2]};
        const double li = length(in), lo = length(out);
        if (!(li > 0.0) || !(lo > 0.0)) continue;
        const double cosine = (in[0] * out[0] + in[1] * out[1] + in[2] * out[2]) / (li * lo);
        const double corner = std::acos(std::clamp(cosine, -1.0, 1.0)) * kRadToDeg;
        if (corner <= kMaxCornerDeg) continue;
        P mid{in[0] / li + out[0] / lo, in[1] / li + out[1] / lo, in[2] / li + out[2] / lo};
        const double lm = length(mid);
        if (!(lm > 1e-6)) continue;  // a reversal: no direction to smooth onto
        for (double& c : mid) c /= lm;
        for (std::size_t i = 0; i < 3; ++i) {
            points[before][i] = static_cast<float>(j[i] - li * mid[i]);
            points[after][i] = static_cast<float>(j[i] + lo * mid[i]);
        }
        // A loop's last point is its first: it does not move, only the handles do.
        changes.push_back(scene.path + ": $.flocks[" + std::to_string(f) + "] \"" + flock.name + "\": route points " +
                          std::to_string(before) + " and " + std::to_string(after) + " turned onto one line through point " +
                          std::to_string(junction) + " (a " + number(corner) + " deg corner)");
    }
}

}  // namespace

Result<std::vector<std::string>> fit_routes(Scene& scene) {
    std::vector<std::string> changes;
    for (std::size_t f = 0; f < scene.flocks.size(); ++f) smooth_corners(scene, f, changes);
    const double capacity = turn_capacity(scene);
    // Both the turn load v^2 kappa and a speed change over a fixed stretch of route scale
    // with the square of the speed (with 1 / D^2 under parametric timing), so one factor
    // sqrt(worst excess) fits both; the margin absorbs the rounding of the birds' float
    // speeds, and the loop below confirms the result. A bank jump shrinks more slowly
    // than v^2 (the bank is atan(v^2 kappa / g), within the max bank), so it may take a
    // few passes.
    constexpr double kMargin = 1e-3;
    // One line per flock refitted, from its first value to its last, however many passes.
    std::vector<std::size_t> line(scene.flocks.size(), SIZE_MAX);
    std::vector<double> first(scene.flocks.size(), 0.0);
    const auto note = [&](std::size_t f, double before, double after, const std::string& what, const char* unit) {
        if (line[f] == SIZE_MAX) {
            line[f] = changes.size();
            first[f] = before;
            changes.emplace_back();
        }
        const FlockSpec& flock = scene.flocks[f];
        changes[line[f]] = scene.path + ": $.flocks[" + std::to_string(f) + "] \"" + flock.name + "\": " + what + " " +
                           number(first[f]) + " -> " + number(after) + unit +
                           " so its turns, bank jumps and speed changes are within the " +
                           flock_limits(flock).name + "'s limits";
    };
    for (int pass = 0; pass < 16; ++pass) {
        auto built = build_bird_world(scene);
        if (!built) return built.error();
        const birds::BirdWorld& world = built.value();
        const std::vector<std::vector<FlownRoute>> flown = flown_routes(scene, world);
        bool changed = false;
        for (std::size_t f = 0; f < scene.flocks.size(); ++f) {
            FlockSpec& flock = scene.flocks[f];
            const FlockLimits wing = flock_limits(flock);
            double excess = 0.0;
            for (const FlownRoute& r : flown[f]) {
                for (const birds::SegmentDemand& d : birds::route_demands(world, r.route, static_cast<float>(r.speed))) {
                    if (capacity > 0.0) excess = std::max(excess, d.turn_acceleration / capacity);
                    excess = std::max(excess, d.speed_change / wing.max_speed_change);
                    if (d.junction) excess = std::max(excess, junction_roll_deg(scene, d) / kMaxRollPerFrameDeg);
                }
            }
            if (!(excess > 1.0)) continue;
            const double factor = std::sqrt(excess) * (1.0 + kMargin);
            if (flock.timing == birds::RouteTiming::ArcLength) {
                const double before = flock.speed ? double{*flock.speed} : wing.cruise_speed;
                flock.speed = static_cast<float>(round_3_digits(before / factor, false));
                note(f, before, double{*flock.speed}, "speed", " m/s");
            } else {
                if (!flock.route) {
                    // The generated leader, as the explicit route it is: the variants are
                    // made from it with the same seed, so the flock is unchanged but for D.
                    const gpu::RouteHeader& header = world.routes[flown[f].front().route];
                    birds::RouteSpec route;
                    route.loop = (header.flags.x & KW_ROUTE_LOOP) != 0;
                    route.timing = birds::RouteTiming::Parametric;
                    for (std::uint32_t i = 0; i <= 3 * header.extent.y; ++i) {
                        const gpu::vec4& c = world.control_points[header.extent.x + i];
                        route.points.push_back({c.x, c.y, c.z});
                    }
                    flock.route = std::move(route);
                    flock.generated_route.reset();
                }
                const double before = flock.route->segment_duration;
                flock.route->segment_duration = static_cast<float>(round_3_digits(before * factor, true));
                note(f, before, double{flock.route->segment_duration}, "segment_duration", " s");
            }
            changed = true;
        }
        if (!changed) return changes;
    }
    return changes;
}

}  // namespace kodawari
