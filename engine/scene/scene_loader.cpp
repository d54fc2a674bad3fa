// The scene file format (docs/scene-format.md): reads and checks every key, so a
// scene that loads is one the builder can turn into a BirdWorld. Checks that need the
// route's geometry (coincident control points, cusps) stay in BirdWorld::add_route,
// which reports them with the route's JSON path.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include <kodawari/core/atomic_file.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/shared/flocking.h>

#include "kodawari/gltf/bird_model_import.hpp"
#include "scene/character_loader.hpp"

#include "scene/json_reader.hpp"

namespace kodawari {
namespace {

using scene_detail::JsonNode;
using scene_detail::JsonReader;
using scene_detail::NumberRange;
using scene_detail::optional_member;
using scene_detail::read_direction;
using scene_detail::read_point;

constexpr std::uint64_t kMaxBirds = 10'000'000;   // per flock and per scene
constexpr double kMaxCoordinate = 1e6;            // BirdWorld::add_route's limit (m)
constexpr double kDegToRad = std::numbers::pi / 180.0;

// Keys that only version 2 knows: in a version-1 file they are reported as such rather
// than as unknown, so the fix (the version) is in the message.
Result<void> require_version_2(const JsonReader& r, const JsonNode& node, std::uint32_t version,
                               std::initializer_list<std::string_view> keys) {
    if (version >= 2) return {};
    for (const std::string_view key : keys) {
        const JsonNode n = r.member(node, key);
        if (n.present()) return r.fail(n.path, "needs \"version\": 2 (version 1 scenes describe birds only)");
    }
    return {};
}

Result<void> read_camera(const JsonReader& r, const JsonNode& node, std::uint32_t version, CameraSpec& camera) {
    KW_TRY(require_version_2(r, node, version, {"projection", "orbit", "path", "keyframes"}));
    KW_TRY(r.object(node, {"position", "target", "fov_deg", "projection", "orbit", "path", "keyframes"}));
    const NumberRange coordinate = NumberRange::closed(-kMaxCoordinate, kMaxCoordinate);
    const auto vec = [&](const JsonNode& n) { return r.vec3(n, coordinate); };
    KW_TRY(optional_member(r, node, "position", camera.position, vec));
    KW_TRY(optional_member(r, node, "target", camera.target, vec));
    if (camera.target == camera.position) {
        return r.expected(r.member(node, "target"), "a point other than the camera position (the camera needs a direction)");
    }
    KW_TRY(optional_member(r, node, "fov_deg", camera.fov_deg,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::open(0.0, 180.0)); }));
    return scene_detail::read_camera_motion(r, node, camera);
}

// The climb thresholds are read in degrees and must nest so the hysteresis works:
// descend_enter < descend_exit <= ascend_exit < ascend_enter.
Result<void> read_climb_thresholds(const JsonReader& r, const JsonNode& node, birds::FlightSettings& flight) {
    struct Threshold {
        const char* key;
        float* target;
        double degrees;
        bool given;
    };
    std::array<Threshold, 4> t = {{
        {"ascend_enter_deg", &flight.ascend_enter, 0.0, false},
        {"ascend_exit_deg", &flight.ascend_exit, 0.0, false},
        {"descend_enter_deg", &flight.descend_enter, 0.0, false},
        {"descend_exit_deg", &flight.descend_exit, 0.0, false},
    }};
    for (Threshold& th : t) {
        // Defaults are stored in radians; round them back to the degrees a person wrote.
        th.degrees = std::round(static_cast<double>(*th.target) / kDegToRad * 1e6) / 1e6;
        const JsonNode n = r.member(node, th.key);
        if (n.present()) {
            KW_SCENE_ASSIGN(th.degrees, r.number(n, NumberRange::open(-90.0, 90.0)));
            th.given = true;
        }
    }
    // Blame the left-hand key of the relation when the file gave it, else the other.
    const auto check = [&](const Threshold& low, const Threshold& high, bool strict) -> Result<void> {
        if (strict ? low.degrees < high.degrees : low.degrees <= high.degrees) return {};
        if (low.given || !high.given) {
            return r.expected(r.member(node, low.key), std::string("a number ") + (strict ? "below " : "at or below ") +
                                                           high.key + " (" + scene_detail::format_number(high.degrees) + ")");
        }
        return r.expected(r.member(node, high.key), std::string("a number ") + (strict ? "above " : "at or above ") +
                                                        low.key + " (" + scene_detail::format_number(low.degrees) + ")");
    };
    KW_TRY(check(t[1], t[0], true));   // ascend_exit < ascend_enter
    KW_TRY(check(t[2], t[3], true));   // descend_enter < descend_exit
    KW_TRY(check(t[3], t[1], false));  // descend_exit <= ascend_exit
    for (const Threshold& th : t) *th.target = static_cast<float>(th.degrees * kDegToRad);
    return {};
}

Result<void> read_flight(const JsonReader& r, const JsonNode& node, birds::FlightSettings& flight) {
    KW_TRY(r.object(node, {"bank_rule", "max_bank_deg", "bank_time_constant", "mode_rule", "ascend_enter_deg", "ascend_exit_deg",
                           "descend_enter_deg", "descend_exit_deg", "seed_accel_threshold", "blend_rates", "gravity"}));
    const JsonNode bank_rule = r.member(node, "bank_rule");
    if (bank_rule.present()) {
        std::size_t index = 0;
        KW_SCENE_ASSIGN(index, r.choice(bank_rule, {"coordinated", "seed"}));
        flight.bank_rule = index == 0 ? birds::BankRule::Coordinated : birds::BankRule::Seed;
    }
    const JsonNode max_bank = r.member(node, "max_bank_deg");
    if (max_bank.present()) {
        double degrees = 0.0;
        KW_SCENE_ASSIGN(degrees, r.number(max_bank, NumberRange::closed(0.0, 89.0)));
        flight.max_bank = static_cast<float>(degrees * kDegToRad);
    }
    // Seconds; 0 rolls instantly (docs/flight-modes.md F.6). 10 s: a bird that takes
    // longer than that to roll into a turn has flown out of it.
    KW_TRY(optional_member(r, node, "bank_time_constant", flight.bank_time,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 10.0)); }));
    const JsonNode mode_rule = r.member(node, "mode_rule");
    if (mode_rule.present()) {
        std::size_t index = 0;
        KW_SCENE_ASSIGN(index, r.choice(mode_rule, {"climb", "seed"}));
        flight.mode_rule = index == 0 ? birds::ModeRule::Climb : birds::ModeRule::Seed;
    }
    KW_TRY(read_climb_thresholds(r, node, flight));
    KW_TRY(optional_member(r, node, "seed_accel_threshold", flight.seed_accel_threshold,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    const JsonNode rates = r.member(node, "blend_rates");
    if (rates.present()) {
        KW_TRY(r.object(rates, {"level", "ascend", "descend"}));
        const auto rate = [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1.0)); };
        KW_TRY(optional_member(r, rates, "level", flight.blend_rates[0], rate));
        KW_TRY(optional_member(r, rates, "ascend", flight.blend_rates[1], rate));
        KW_TRY(optional_member(r, rates, "descend", flight.blend_rates[2], rate));
    }
    KW_TRY(optional_member(r, node, "gravity", flight.gravity,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    return {};
}

Result<void> read_route(const JsonReader& r, const JsonNode& node, birds::RouteSpec& route) {
    KW_TRY(r.object(node, {"points", "loop", "segment_duration", "modes"}));
    const JsonNode points = r.member(node, "points");
    constexpr std::string_view kPointsWhat =
        "an array of 3n+1 control points [x, y, z] (n >= 1 cubic Bezier segments: 4, 7, 10, ... points)";
    std::size_t count = 0;
    KW_SCENE_ASSIGN(count, r.array(points, kPointsWhat));
    if (count < 4 || (count - 1) % 3 != 0) return r.expected(points, kPointsWhat);
    constexpr std::size_t kMaxPoints = 3 * 4096 + 1;
    if (count > kMaxPoints) return r.expected(points, "at most " + std::to_string(kMaxPoints) + " control points (4096 segments)");
    route.points.resize(count);
    const NumberRange coordinate = NumberRange::closed(-kMaxCoordinate, kMaxCoordinate);
    for (std::size_t i = 0; i < count; ++i) KW_SCENE_ASSIGN(route.points[i], r.vec3(r.element(points, i), coordinate));
    KW_TRY(optional_member(r, node, "loop", route.loop, [&](const JsonNode& n) { return r.boolean(n); }));
    if (route.loop && route.points.back() != route.points.front()) {
        return r.expected(r.element(points, count - 1),
                          "the same point as points[0] (a looping route ends where it starts)");
    }
    // At least a millisecond: time / segment_duration stays finite (found by fuzzing).
    KW_TRY(optional_member(r, node, "segment_duration", route.segment_duration,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.001, 3600.0)); }));
    // One mode per segment (docs/flight-modes.md F.1); where each may stand is checked by
    // BirdWorld::add_route, which knows the timing.
    const JsonNode modes = r.member(node, "modes");
    if (modes.present()) {
        const std::size_t segments = (count - 1) / 3;
        std::size_t n = 0;
        KW_SCENE_ASSIGN(n, r.array(modes, "an array of one mode per segment"));
        if (n != segments) {
            return r.fail(modes.path, "expected one mode per segment (" + std::to_string(segments) + "), got " + std::to_string(n));
        }
        route.modes.resize(n);
        static constexpr birds::SegmentMode kModes[] = {birds::SegmentMode::Auto, birds::SegmentMode::Glide,
                                                        birds::SegmentMode::TakeOff, birds::SegmentMode::Landing,
                                                        birds::SegmentMode::Hover};
        for (std::size_t k = 0; k < n; ++k) {
            std::size_t which = 0;
            KW_SCENE_ASSIGN(which, r.choice(r.element(modes, k), {"auto", "glide", "takeoff", "landing", "hover"}));
            route.modes[k] = kModes[which];
        }
    }
    return {};
}

Result<void> read_generated_route(const JsonReader& r, const JsonNode& node, GeneratedRouteSpec& gen) {
    KW_TRY(r.object(node, {"seed", "segments", "center", "extent", "loop"}));
    KW_TRY(optional_member(r, node, "seed", gen.seed, [&](const JsonNode& n) {
        return r.integer(n, 0, std::numeric_limits<std::uint64_t>::max());
    }));
    KW_TRY(optional_member(r, node, "loop", gen.loop, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode segments = r.member(node, "segments");
    if (segments.present()) {
        // A loop turns through 360 degrees at its waypoints; with at most 120 degrees
        // per waypoint (flock_builder.cpp) it needs at least 4 of them.
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(segments, gen.loop ? 4 : 1, 64));
        gen.segments = static_cast<std::uint32_t>(value);
    } else if (gen.loop && gen.segments < 4) {
        gen.segments = 4;
    }
    // Half the coordinate limit each, so center +- extent stays within it.
    KW_TRY(optional_member(r, node, "center", gen.center, [&](const JsonNode& n) {
        return r.vec3(n, NumberRange::closed(-kMaxCoordinate / 2, kMaxCoordinate / 2));
    }));
    KW_TRY(optional_member(r, node, "extent", gen.extent, [&](const JsonNode& n) {
        return r.vec3(n, NumberRange::left_open(0.0, kMaxCoordinate / 2));
    }));
    return {};
}

// A reader of a number in (0, max], for optional_member.
auto positive_up_to(const JsonReader& r, double max) {
    return [&r, max](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, max)); };
}

Result<void> read_formation(const JsonReader& r, const JsonNode& node, FormationSpec& formation) {
    KW_TRY(r.object(node, {"spread", "shape", "route_variants", "jitter", "trail"}));
    KW_TRY(optional_member(r, node, "spread", formation.spread,
                           [&](const JsonNode& n) { return r.vec3(n, NumberRange::closed(0.0, 10000.0)); }));
    const JsonNode shape = r.member(node, "shape");
    if (shape.present()) {
        std::size_t index = 0;
        KW_SCENE_ASSIGN(index, r.choice(shape, {"box", "ellipsoid"}));
        formation.shape = index == 0 ? FormationSpec::Shape::Box : FormationSpec::Shape::Ellipsoid;
    }
    const JsonNode variants = r.member(node, "route_variants");
    if (variants.present()) {
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(variants, 1, 256));
        formation.route_variants = static_cast<std::uint32_t>(value);
    }
    KW_TRY(optional_member(r, node, "jitter", formation.jitter,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 10000.0)); }));
    KW_TRY(optional_member(r, node, "trail", formation.trail,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 3600.0)); }));
    return {};
}

Result<void> read_predator(const JsonReader& r, const JsonNode& node, PredatorSpec& predator) {
    KW_TRY(r.object(node, {"flock", "from", "to", "start", "every", "speed", "radius", "weight"}));
    const auto point = [&](const JsonNode& n) -> Result<glm::vec3> {
        std::array<float, 3> v{};
        KW_SCENE_ASSIGN(v, r.vec3(n, NumberRange::closed(-kMaxCoordinate, kMaxCoordinate)));
        return glm::vec3(v[0], v[1], v[2]);
    };
    const JsonNode flock = r.member(node, "flock");
    if (flock.present()) {
        // A route flock's first bird (checked against the scene's flocks when built).
        for (const char* key : {"from", "to", "every", "speed"}) {
            if (r.member(node, key).present()) {
                return r.fail(r.member(node, key).path, "a predator that is a flock's bird flies that flock's route: expected no \"" +
                                                            std::string(key) + "\" beside \"flock\"");
            }
        }
        KW_SCENE_ASSIGN(predator.flock, r.string(flock));
        if (predator.flock.empty()) return r.expected(flock, "the name of a flock without \"flocking\"");
    } else {
        KW_SCENE_ASSIGN(predator.from, point(r.member(node, "from")));
        KW_SCENE_ASSIGN(predator.to, point(r.member(node, "to")));
        if (predator.from == predator.to) return r.fail(node.path, "expected \"from\" and \"to\" apart, got the same point");
    }
    KW_TRY(optional_member(r, node, "start", predator.start,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1e6)); }));
    KW_TRY(optional_member(r, node, "every", predator.every,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1e6)); }));
    KW_TRY(optional_member(r, node, "speed", predator.speed,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 200.0)); }));
    KW_TRY(optional_member(r, node, "radius", predator.radius,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "weight", predator.weight,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); }));
    return {};
}

// An obstacle: a sphere, capsule or plane in world space, as a chain collider is written
// in a joint's frame (character_loader.cpp's read_collider), with a margin and a weight.
Result<void> read_obstacle(const JsonReader& r, const JsonNode& node, FlockObstacleSpec& o) {
    if (!node.present() || !node.value->is_object()) return r.expected(node, "an object with \"type\": \"sphere\", \"capsule\" or \"plane\"");
    std::size_t type = 0;
    KW_SCENE_ASSIGN(type, r.choice(r.member(node, "type"), {"sphere", "capsule", "plane"}));
    if (type == 2) {
        KW_TRY(r.object(node, {"type", "point", "normal", "margin", "weight"}));
        o.type = FlockObstacleSpec::Type::Plane;
        KW_TRY(optional_member(r, node, "point", o.a, [&](const JsonNode& n) { return read_point(r, n, kMaxCoordinate); }));
        KW_SCENE_ASSIGN(o.b, read_direction(r, r.member(node, "normal")));
    } else {
        if (type == 0) {
            KW_TRY(r.object(node, {"type", "center", "radius", "margin", "weight"}));
            o.type = FlockObstacleSpec::Type::Sphere;
            KW_TRY(optional_member(r, node, "center", o.a, [&](const JsonNode& n) { return read_point(r, n, kMaxCoordinate); }));
            o.b = o.a;
        } else {
            KW_TRY(r.object(node, {"type", "a", "b", "radius", "margin", "weight"}));
            o.type = FlockObstacleSpec::Type::Capsule;
            KW_SCENE_ASSIGN(o.a, read_point(r, r.member(node, "a"), kMaxCoordinate));
            KW_SCENE_ASSIGN(o.b, read_point(r, r.member(node, "b"), kMaxCoordinate));
        }
        KW_SCENE_ASSIGN(o.radius, r.real(r.member(node, "radius"), NumberRange::left_open(0.0, 1e4)));
    }
    KW_TRY(optional_member(r, node, "margin", o.margin, [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "weight", o.weight, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); }));
    return {};
}

Result<void> read_attractor(const JsonReader& r, const JsonNode& node, FlockAttractorSpec& a) {
    KW_TRY(r.object(node, {"position", "radius", "weight"}));
    KW_SCENE_ASSIGN(a.position, read_point(r, r.member(node, "position"), kMaxCoordinate));
    KW_TRY(optional_member(r, node, "radius", a.radius, [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1e4)); }));
    KW_TRY(optional_member(r, node, "weight", a.weight, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); }));
    return {};
}

// An array of at most 64 `what`s at `node` (when present), each read by `read`.
template <typename T, typename Read>
Result<void> read_agents(const JsonReader& r, const JsonNode& node, const char* what, std::vector<T>& out, Read read) {
    if (!node.present()) return {};
    std::size_t count = 0;
    KW_SCENE_ASSIGN(count, r.array(node, std::string("an array of ") + what));
    if (count > 64) return r.fail(node.path, "expected at most 64 " + std::string(what) + ", got " + std::to_string(count));
    out.resize(count);
    for (std::size_t i = 0; i < count; ++i) KW_TRY(read(r, r.element(node, i), out[i]));
    return {};
}

Result<void> read_flocking(const JsonReader& r, const JsonNode& node, FlockingSpec& f) {
    KW_TRY(r.object(node, {"neighbours", "metric", "search_radius", "blind_angle_deg", "separation_distance", "separation", "separation_front",
                           "alignment", "cohesion", "route", "route_radius", "ground_clearance", "ground", "speed_time",
                           "predators", "obstacles", "attractors"}));
    const JsonNode neighbours = r.member(node, "neighbours");
    if (neighbours.present()) {
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(neighbours, 1, KW_FLOCK_MAX_NEIGHBOURS));
        f.neighbours = static_cast<std::uint32_t>(value);
    }
    KW_TRY(optional_member(r, node, "metric", f.metric, [&](const JsonNode& n) { return r.boolean(n); }));
    const auto length = [&r](double max) { return positive_up_to(r, max); };
    const auto weight = [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); };
    KW_TRY(optional_member(r, node, "search_radius", f.search_radius, length(100.0)));
    KW_TRY(optional_member(r, node, "blind_angle_deg", f.blind_angle_deg,
                           [&](const JsonNode& n) { return r.real(n, NumberRange{0.0, 180.0, false, true}); }));
    KW_TRY(optional_member(r, node, "separation_distance", f.separation_distance, length(100.0)));
    if (f.separation_distance > f.search_radius) {
        return r.fail(r.member(node, "separation_distance").present() ? r.member(node, "separation_distance").path : node.path,
                      "expected at most search_radius (" + scene_detail::format_number(f.search_radius) + " m), got " +
                          scene_detail::format_number(f.separation_distance));
    }
    KW_TRY(optional_member(r, node, "separation", f.separation, weight));
    KW_TRY(optional_member(r, node, "separation_front", f.separation_front,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 10.0)); }));
    KW_TRY(optional_member(r, node, "alignment", f.alignment, weight));
    KW_TRY(optional_member(r, node, "cohesion", f.cohesion, weight));
    KW_TRY(optional_member(r, node, "route", f.route, weight));
    KW_TRY(optional_member(r, node, "route_radius", f.route_radius, length(10000.0)));
    KW_TRY(optional_member(r, node, "ground_clearance", f.ground_clearance, length(1000.0)));
    KW_TRY(optional_member(r, node, "ground", f.ground, weight));
    KW_TRY(optional_member(r, node, "speed_time", f.speed_time, length(60.0)));
    KW_TRY(read_agents(r, r.member(node, "predators"), "predators", f.predators, read_predator));
    KW_TRY(read_agents(r, r.member(node, "obstacles"), "obstacles", f.obstacles, read_obstacle));
    KW_TRY(read_agents(r, r.member(node, "attractors"), "attractors", f.attractors, read_attractor));
    return {};
}

// A flock's name is one flock: predators name the flock whose first bird they are
// (`flocking.predators[].flock`), which must be a flock without flocking. Checked here,
// where the JSON paths are known, once every flock is read (a predator may name a later
// flock); FlockWorld checks scenes built in code again.
Result<void> check_flock_names(const JsonReader& r, const JsonNode& flocks, const std::vector<FlockSpec>& specs) {
    const auto name_path = [&](std::size_t i) {
        const JsonNode name = r.member(r.element(flocks, i), "name");
        return name.present() ? name.path : r.element(flocks, i).path;
    };
    for (std::size_t i = 0; i < specs.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j) {
            if (specs[j].name != specs[i].name) continue;
            return r.fail(name_path(i), "\"" + specs[i].name + "\" is already the name of flock " + std::to_string(j) +
                                            " (" + name_path(j) + "); expected a name of its own");
        }
    }
    for (std::size_t f = 0; f < specs.size(); ++f) {
        if (!specs[f].flocking) continue;
        const JsonNode predators = r.member(r.member(r.element(flocks, f), "flocking"), "predators");
        for (std::size_t p = 0; p < specs[f].flocking->predators.size(); ++p) {
            const std::string& wanted = specs[f].flocking->predators[p].flock;
            if (wanted.empty()) continue;
            const JsonNode at = r.member(r.element(predators, p), "flock");
            const auto found = std::find_if(specs.begin(), specs.end(), [&](const FlockSpec& s) { return s.name == wanted; });
            if (found == specs.end()) {
                std::string names;
                for (const FlockSpec& s : specs) names += (names.empty() ? "\"" : ", \"") + s.name + "\"";
                return r.fail(at.path, "\"" + wanted + "\": the scene has no flock of that name (its flocks: " + names +
                                           "); expected the name of a flock without \"flocking\"");
            }
            if (found->flocking) {
                return r.fail(at.path, "\"" + wanted + "\" flocks itself; expected the name of a flock without \"flocking\" "
                                       "(the predator is that flock's first bird, flying its route)");
            }
        }
    }
    return {};
}

Result<void> read_flock(const JsonReader& r, const JsonNode& node, std::size_t index, std::uint64_t& total_birds,
                        FlockSpec& flock) {
    KW_TRY(r.object(node, {"name", "wing_type", "model", "map", "count", "seed", "speed", "speed_jitter", "frequency",
                           "frequency_jitter", "amplitude", "amplitude_jitter", "phase_jitter", "timing", "route",
                           "generated_route", "formation", "flocking"}));
    flock.name = "flock" + std::to_string(index);
    KW_TRY(optional_member(r, node, "name", flock.name, [&](const JsonNode& n) { return r.string(n); }));

    // A built-in wing type, or a user's bird (docs/bird-models.md), loaded here relative
    // to the scene's folder as a rigged character's file is.
    const JsonNode model = r.member(node, "model");
    const JsonNode map = r.member(node, "map");
    if (model.present()) {
        if (r.member(node, "wing_type").present()) {
            return r.fail(model.path, "expected one of \"wing_type\" and \"model\", got both");
        }
        KW_SCENE_ASSIGN(flock.model_file, r.string(model));
        if (flock.model_file.empty()) return r.expected(model, "the path of a rigged bird's .gltf or .glb file");
        if (map.present()) KW_SCENE_ASSIGN(flock.map_file, r.string(map));
        const auto resolve = [&](const std::string& file) {
            const std::filesystem::path given(file);
            return given.is_absolute() ? file : (std::filesystem::path(r.file()).parent_path() / given).string();
        };
        auto loaded = gltf::load_bird_model(resolve(flock.model_file), flock.map_file.empty() ? "" : resolve(flock.map_file));
        if (!loaded) return make_error(loaded.error().kind, r.file() + ": " + model.path + ": " + loaded.error().message);
        flock.model = std::make_shared<const birds::BirdModel>(std::move(loaded).value());
    } else {
        if (map.present()) return r.fail(map.path, "a mapping file belongs to a \"model\", and this flock has none");
        std::size_t wing = 0;
        KW_SCENE_ASSIGN(wing, r.choice(r.member(node, "wing_type"), {"pigeon", "gull", "hawk", "hummingbird"}));
        flock.wing_type = static_cast<birds::WingType>(wing);
    }

    const JsonNode count = r.member(node, "count");
    std::uint64_t birds_in_flock = 0;
    KW_SCENE_ASSIGN(birds_in_flock, r.integer(count, 1, kMaxBirds));
    if (total_birds + birds_in_flock > kMaxBirds) {
        return r.expected(count, "an integer in [1, " + std::to_string(kMaxBirds - total_birds) +
                                     "] (a scene holds at most " + std::to_string(kMaxBirds) + " birds in all)");
    }
    total_birds += birds_in_flock;
    flock.count = static_cast<std::uint32_t>(birds_in_flock);

    KW_TRY(optional_member(r, node, "seed", flock.seed, [&](const JsonNode& n) {
        return r.integer(n, 0, std::numeric_limits<std::uint64_t>::max());
    }));
    // Upper bounds keep base * (1 + jitter) finite and the numbers physical.
    const auto positive = [&r](double max) { return positive_up_to(r, max); };
    const auto jitter = [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 0.9)); };
    KW_TRY(optional_member(r, node, "speed", flock.speed, positive(1000.0)));
    KW_TRY(optional_member(r, node, "speed_jitter", flock.speed_jitter, jitter));
    KW_TRY(optional_member(r, node, "frequency", flock.frequency, positive(1000.0)));
    KW_TRY(optional_member(r, node, "frequency_jitter", flock.frequency_jitter, jitter));
    KW_TRY(optional_member(r, node, "amplitude", flock.amplitude, positive(3.0)));
    KW_TRY(optional_member(r, node, "amplitude_jitter", flock.amplitude_jitter, jitter));
    KW_TRY(optional_member(r, node, "phase_jitter", flock.phase_jitter,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0)); }));
    const JsonNode timing = r.member(node, "timing");
    if (timing.present()) {
        std::size_t value = 0;
        KW_SCENE_ASSIGN(value, r.choice(timing, {"arc-length", "parametric"}));
        flock.timing = value == 0 ? birds::RouteTiming::ArcLength : birds::RouteTiming::Parametric;
    }

    const JsonNode route = r.member(node, "route");
    const JsonNode generated = r.member(node, "generated_route");
    if (route.present() && generated.present()) {
        return r.fail(generated.path, "expected exactly one of \"route\" and \"generated_route\", got both");
    }
    if (route.present()) {
        birds::RouteSpec spec;
        KW_TRY(read_route(r, route, spec));
        spec.timing = flock.timing;
        flock.route = std::move(spec);
    } else if (generated.present()) {
        GeneratedRouteSpec spec;
        KW_TRY(read_generated_route(r, generated, spec));
        flock.generated_route = spec;
    } else {
        return r.fail(node.path, "expected exactly one of \"route\" and \"generated_route\", got neither");
    }

    const JsonNode formation = r.member(node, "formation");
    if (formation.present()) KW_TRY(read_formation(r, formation, flock.formation));
    const JsonNode flocking = r.member(node, "flocking");
    if (flocking.present()) {
        if (flock.timing == birds::RouteTiming::Parametric) {
            return r.fail(flocking.path, "a flocking flock's route gives its leader at its speed: expected \"timing\": \"arc-length\", got \"parametric\"");
        }
        FlockingSpec spec;
        KW_TRY(read_flocking(r, flocking, spec));
        flock.flocking = std::move(spec);
    }
    return {};
}

// The characters' levels of detail (docs/level-of-detail.md): on unless "enabled" is false.
// The vertical field of view is the camera's, set where the rod world is built
// (build_rod_scene), as for a scene built in code.
Result<void> read_lod(const JsonReader& r, const JsonNode& node, rods::LodSettings& lod) {
    KW_TRY(r.object(node, {"enabled", "size", "full_pixels", "reduced_pixels", "hysteresis", "bias", "settle_rate", "blend_time", "lower_rate",
                         "viewport", "budget_ms", "costs"}));
    lod.enabled = true;
    if (const JsonNode enabled = r.member(node, "enabled"); enabled.present()) KW_SCENE_ASSIGN(lod.enabled, r.boolean(enabled));
    KW_TRY(optional_member(r, node, "size", lod.size, [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "full_pixels", lod.full_pixels,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100000.0)); }));
    KW_TRY(optional_member(r, node, "reduced_pixels", lod.reduced_pixels,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100000.0)); }));
    if (const JsonNode reduced = r.member(node, "reduced_pixels"); reduced.present() && !(lod.reduced_pixels < lod.full_pixels)) {
        return r.expected(reduced, "a number of pixels below full_pixels");
    }
    KW_TRY(optional_member(r, node, "hysteresis", lod.hysteresis,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 0.9)); }));
    KW_TRY(optional_member(r, node, "bias", lod.bias, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(-8.0, 8.0)); }));
    KW_TRY(optional_member(r, node, "settle_rate", lod.settle_rate,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "blend_time", lod.blend_time,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100.0)); }));
    if (const JsonNode rate = r.member(node, "lower_rate"); rate.present()) KW_SCENE_ASSIGN(lod.lower_rate, r.boolean(rate));
    KW_TRY(optional_member(r, node, "budget_ms", lod.budget_ms,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100000.0)); }));
    if (const JsonNode costs = r.member(node, "costs"); costs.present()) {
        KW_TRY(r.object(costs, {"full_chain_us", "reduced_chain_us", "posed_chain_us", "full_clip_us", "posed_clip_us"}));
        rods::LodCosts& c = lod.costs;
        for (auto [name, field] : {std::pair{"full_chain_us", &c.full_chain_us}, std::pair{"reduced_chain_us", &c.reduced_chain_us},
                                   std::pair{"posed_chain_us", &c.posed_chain_us},
                                   std::pair{"full_clip_us", &c.full_clip_us}, std::pair{"posed_clip_us", &c.posed_clip_us}}) {
            KW_TRY(optional_member(r, costs, name, *field,
                                   [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0e6)); }));
        }
        if (c.full_chain_us < c.posed_chain_us) {
            return r.expected(r.member(costs, "full_chain_us").present() ? r.member(costs, "full_chain_us") : costs,
                              "full_chain_us at least posed_chain_us (a full chain costs more than a posed one)");
        }
        if (c.full_clip_us < c.posed_clip_us) {
            return r.expected(r.member(costs, "full_clip_us").present() ? r.member(costs, "full_clip_us") : costs,
                              "full_clip_us at least posed_clip_us");
        }
    }
    if (const JsonNode viewport = r.member(node, "viewport"); viewport.present()) {
        std::size_t count = 0;
        KW_SCENE_ASSIGN(count, r.array(viewport, "[width, height] in pixels"));
        if (count != 2) return r.expected(viewport, "[width, height] in pixels");
        double size[2] = {};
        for (std::size_t i = 0; i < 2; ++i) KW_SCENE_ASSIGN(size[i], r.number(r.element(viewport, i), NumberRange::closed(1.0, 100000.0)));
        lod.viewport_height = static_cast<float>(size[1]);
        lod.aspect = static_cast<float>(size[0] / size[1]);
    }
    return {};
}

Result<Scene> read_scene(const JsonReader& r, const nlohmann::json& document, const std::string& path) {
    const JsonNode root{&document, "$"};
    KW_TRY(r.object(root, {"format", "version", "name", "fps", "duration", "camera", "flight", "flocks", "characters", "crowds",
                           "wind", "lod", "$schema"}));
    // Editors find the JSON Schema (docs/scene.schema.json) through "$schema"; the loader
    // checks the same rules itself, so only the key's type matters here.
    const JsonNode schema = r.member(root, "$schema");
    if (schema.present()) KW_TRY(r.string(schema));

    const JsonNode format = r.member(root, "format");
    if (!format.present() || !format.value->is_string() || *format.value != "kodawari-scene") {
        return r.expected(format, "\"kodawari-scene\"");
    }
    const JsonNode version = r.member(root, "version");
    if (!version.present() || !version.value->is_number() ||
        (version.value->get<double>() != 1.0 && version.value->get<double>() != 2.0)) {
        return r.expected(version, "1 or 2 (the versions this build reads; 2 adds characters)");
    }

    Scene scene;
    scene.version = version.value->get<double>() == 2.0 ? 2u : 1u;
    KW_TRY(require_version_2(r, root, scene.version, {"characters", "crowds", "wind", "lod"}));
    scene.path = path;
    scene.name = as_scene_name(std::filesystem::path(path).stem().string(), "scene");
    const JsonNode name = r.member(root, "name");
    if (name.present()) {
        KW_SCENE_ASSIGN(scene.name, r.string(name));
        if (const std::string problem = scene_name_problem(scene.name); !problem.empty()) return r.expected(name, problem);
    }
    // At least 0.01 (a frame per 100 s): frame times f / fps stay finite for any frame
    // count (a denormal rate made them infinite, found by fuzzing).
    KW_TRY(optional_member(r, root, "fps", scene.fps,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.01, 1000.0)); }));
    KW_TRY(optional_member(r, root, "duration", scene.duration,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 3600.0)); }));
    const JsonNode camera = r.member(root, "camera");
    if (camera.present()) {
        KW_TRY(read_camera(r, camera, scene.version, scene.camera));
    } else {
        scene.camera.motion.position = glm::vec3(scene.camera.position[0], scene.camera.position[1], scene.camera.position[2]);
        scene.camera.motion.target = glm::vec3(scene.camera.target[0], scene.camera.target[1], scene.camera.target[2]);
    }
    const JsonNode flight = r.member(root, "flight");
    if (flight.present()) KW_TRY(read_flight(r, flight, scene.flight));

    const JsonNode flocks = r.member(root, "flocks");
    const JsonNode characters = r.member(root, "characters");
    const JsonNode crowds = r.member(root, "crowds");
    // From version 2 a scene may hold characters only.
    if (flocks.present() || scene.version < 2) {
        constexpr std::string_view kFlocksWhat = "a non-empty array of flocks";
        std::size_t count = 0;
        KW_SCENE_ASSIGN(count, r.array(flocks, kFlocksWhat));
        if (count == 0) return r.expected(flocks, kFlocksWhat);
        scene.flocks.resize(count);
        std::uint64_t total_birds = 0;
        for (std::size_t i = 0; i < count; ++i) KW_TRY(read_flock(r, r.element(flocks, i), i, total_birds, scene.flocks[i]));
        KW_TRY(check_flock_names(r, flocks, scene.flocks));
    } else if (!characters.present()) {
        return r.fail(root.path, "expected \"flocks\", \"characters\" or both, got neither");
    }
    // Before the characters: theirs are the scene's where they are silent.
    if (const JsonNode wind = r.member(root, "wind"); wind.present()) {
        rods::WindField field;
        KW_TRY(scene_detail::read_wind(r, wind, field));
        scene.wind = field;
    }
    if (const JsonNode lod = r.member(root, "lod"); lod.present()) KW_TRY(read_lod(r, lod, scene.lod));
    if (characters.present()) {
        KW_TRY(scene_detail::read_characters(r, characters, crowds, scene));
    } else if (crowds.present()) {
        return r.fail(crowds.path, "needs \"characters\" (a crowd is made of a scene's characters)");
    }
    // The other files it read, resolved as the readers above resolved them.
    const auto resolved = [&](const std::string& file) {
        const std::filesystem::path given(file);
        return given.is_absolute() ? file : (std::filesystem::path(r.file()).parent_path() / given).string();
    };
    for (std::size_t f = 0; f < scene.flocks.size(); ++f) {
        const FlockSpec& flock = scene.flocks[f];
        if (!flock.model_file.empty()) scene.inputs.push_back({resolved(flock.model_file), "the model of flock " + std::to_string(f)});
        if (!flock.map_file.empty()) scene.inputs.push_back({resolved(flock.map_file), "the bone map of flock " + std::to_string(f)});
    }
    for (const CharacterSpec& character : scene.characters) {
        if (!character.rig) continue;
        const std::string named = "character \"" + character.name + "\"";
        scene.inputs.push_back({character.rig->resolved, "the model of " + named});
        for (const std::string& file : character.rig->motion_files) scene.inputs.push_back({file, "a motion file of " + named});
    }
    return scene;
}

}  // namespace

std::string scene_name_problem(const std::string& name) {
    const bool bad_character = std::any_of(name.begin(), name.end(), [](char c) {
        return c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
    });
    if (name.empty() || name == "." || name == ".." || bad_character) {
        return "a file name, as it names the scene's outputs (out/<name>.glb): not empty, \".\" or \"..\", without '/', "
               "'\\' or control characters";
    }
    return {};
}

std::string as_scene_name(std::string name, const std::string& fallback) {
    for (char& c : name) {
        if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '_';
    }
    return name.empty() || name == "." || name == ".." ? fallback : name;
}

std::string Scene::reads(const std::string& file) const {
    if (same_file(file, path)) return "the scene file";
    for (const SceneInput& input : inputs) {
        if (same_file(file, input.path)) return input.what;
    }
    return {};
}

std::uint32_t Scene::frame_count() const {
    const double frames = std::round(static_cast<double>(duration) * static_cast<double>(fps));
    // The loader bounds both factors (3600 s, 1000 fps); clamp anyway for hand-made scenes.
    if (!(frames >= 1.0)) return 1;
    if (frames > 4294967295.0) return 4294967295u;
    return static_cast<std::uint32_t>(frames);
}

Result<Scene> parse_scene(const std::string& text, const std::string& path) {
    nlohmann::json document;
    KW_SCENE_ASSIGN(document, scene_detail::parse_json(text, path));
    const JsonReader reader(path);
    return read_scene(reader, document, path);
}

Result<Scene> load_scene(const std::string& path) {
    std::string text;
    KW_SCENE_ASSIGN(text, scene_detail::read_text_file(path));
    return parse_scene(text, path);
}

}  // namespace kodawari
