// The flocks of the scene format (flock_loader.hpp, docs/scene-format.md "Flocks"): a
// flock's birds, its route or generated route, its formation and its flocking (predators,
// obstacles, attractors). Checks that need the route's geometry (coincident control
// points, cusps) stay in BirdWorld::add_route, which reports them with the route's JSON
// path.

#include "scene/flock_loader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>

#include <kodawari/shared/flocking.h>

#include "kodawari/gltf/bird_model_import.hpp"
#include "scene/character_loader.hpp"

namespace kodawari::scene_detail {
namespace {

constexpr std::uint64_t kMaxBirds = 10'000'000;  // per flock and per scene

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
                           "collision_distance", "collision_lookahead", "alignment", "cohesion", "route", "route_radius", "ground_clearance", "ground", "speed_time",
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
    KW_TRY(optional_member(r, node, "collision_distance", f.collision_distance,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 100.0)); }));
    KW_TRY(optional_member(r, node, "collision_lookahead", f.collision_lookahead,
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
    // By name, once: a scene may hold up to 10 000 000 one-bird flocks.
    std::unordered_map<std::string, std::size_t> by_name;
    for (std::size_t i = 0; i < specs.size(); ++i) {
        const auto [first, added] = by_name.emplace(specs[i].name, i);
        if (added) continue;
        return r.fail(name_path(i), "\"" + specs[i].name + "\" is already the name of flock " + std::to_string(first->second) +
                                        " (" + name_path(first->second) + "); expected a name of its own");
    }
    for (std::size_t f = 0; f < specs.size(); ++f) {
        if (!specs[f].flocking) continue;
        const JsonNode predators = r.member(r.member(r.element(flocks, f), "flocking"), "predators");
        for (std::size_t p = 0; p < specs[f].flocking->predators.size(); ++p) {
            const std::string& wanted = specs[f].flocking->predators[p].flock;
            if (wanted.empty()) continue;
            const JsonNode at = r.member(r.element(predators, p), "flock");
            const auto named = by_name.find(wanted);
            if (named == by_name.end()) {
                std::vector<std::string> names;  // the first few: enough to see a misspelling
                for (std::size_t i = 0; i < specs.size() && i < 16; ++i) names.push_back(specs[i].name);
                return r.fail(at.path, "\"" + wanted + "\": the scene has no flock of that name (its flocks: " + quoted_list(names) +
                                           (specs.size() > 16 ? ", ..." : "") + "); expected the name of a flock without \"flocking\"");
            }
            const FlockSpec* found = &specs[named->second];
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
        KW_SCENE_ASSIGN(wing, r.choice(r.member(node, "wing_type"), {"pigeon", "gull", "hawk", "hummingbird", "starling"}));
        flock.wing_type = static_cast<birds::WingType>(wing);
    }

    const JsonNode count = r.member(node, "count");
    std::uint64_t birds_in_flock = 0;
    KW_SCENE_ASSIGN(birds_in_flock, r.integer(count, 1, kMaxBirds));
    if (total_birds + birds_in_flock > kMaxBirds) {
        if (total_birds == kMaxBirds) {
            return r.fail(count.path, "the flocks before it hold " + std::to_string(kMaxBirds) +
                                          " birds, the most a scene holds: expected no further flock, got " +
                                          std::to_string(birds_in_flock) + " birds");
        }
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
        // A flocking bird's mode comes from its own flight (docs/flocking.md): a segment's
        // glide or hover would be ignored. A take-off and a landing are its perches: it
        // flies those segments by its route (docs/flocking.md, "Perches").
        if (flock.route) {
            for (std::size_t k = 0; k < flock.route->modes.size(); ++k) {
                const birds::SegmentMode mode = flock.route->modes[k];
                if (mode == birds::SegmentMode::Auto || mode == birds::SegmentMode::TakeOff || mode == birds::SegmentMode::Landing) continue;
                return r.fail(r.element(r.member(route, "modes"), k).path,
                              std::string("\"") + birds::segment_mode_name(mode) +
                                  "\" is not flown by a flocking flock (its birds choose their modes from their own "
                                  "flight): expected \"auto\", or \"takeoff\" and \"landing\" for its perches");
            }
        }
        FlockingSpec spec;
        KW_TRY(read_flocking(r, flocking, spec));
        flock.flocking = std::move(spec);
    }
    return {};
}

}  // namespace

Result<void> read_flocks(const JsonReader& r, const JsonNode& flocks, std::vector<FlockSpec>& out) {
    constexpr std::string_view kFlocksWhat = "a non-empty array of flocks";
    std::size_t count = 0;
    KW_SCENE_ASSIGN(count, r.array(flocks, kFlocksWhat));
    if (count == 0) return r.expected(flocks, kFlocksWhat);
    out.resize(count);
    std::uint64_t total_birds = 0;
    for (std::size_t i = 0; i < count; ++i) KW_TRY(read_flock(r, r.element(flocks, i), i, total_birds, out[i]));
    return check_flock_names(r, flocks, out);
}

}  // namespace kodawari::scene_detail
