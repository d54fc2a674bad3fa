#include "domains/flocking/flock_world.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "domains/flocking/flock_kernel.hpp"
#include "kodawari/birds/bird_model.hpp"
#include "kodawari/birds/flight.hpp"
#include "kodawari/birds/rig.hpp"

namespace kodawari::flocking {

namespace {

// A scene obstacle as the kernels take it (shared/flocking.h's KW_FLOCK_AGENT_*).
gpu::FlockAgentGpu obstacle_agent(const FlockObstacleSpec& o) {
    gpu::FlockAgentGpu agent{};
    const float kind = o.type == FlockObstacleSpec::Type::Plane     ? KW_FLOCK_AGENT_PLANE
                       : o.type == FlockObstacleSpec::Type::Capsule ? KW_FLOCK_AGENT_CAPSULE
                                                                    : KW_FLOCK_AGENT_SPHERE;
    agent.position = {o.a.x, o.a.y, o.a.z, o.type == FlockObstacleSpec::Type::Plane ? 0.0f : o.radius};
    agent.kind_weight = {kind, o.weight, o.margin, 0.0f};
    agent.velocity = {o.b.x, o.b.y, o.b.z, 0.0f};
    return agent;
}

gpu::vec4 v4(const birds::Vec3& v) { return {v.x, v.y, v.z, 0.0f}; }

constexpr std::uint32_t kNever = 0xFFFFFFFFu;  // FlockBirdGpu.ids.z: no landing

// A flock's perches (docs/flocking.md, "Perches"): whether its leader's route takes off
// and lands (a route's take-off and landing segments are its variants' too), and the
// frames between which its birds land: from the one at which the leader is `ahead` metres
// before its landing segment's start (a bird lands once past its own start, and none
// should be that far ahead of the leader: `ahead` is three times the formation's reach and
// at least 30 m), to the one of the leader's touchdown, by which every bird lands. The
// route's arc length s at time t (docs/flight-modes.md F.2): s = d - L0 for d = v (t -
// crouch) >= 2 L0 past a take-off, s = v t without one; the landing from s = L - Ln to
// touchdown at d = L + Ln (+ L0).
struct Perches {
    bool takeoff = false, landing = false;
    std::uint32_t earliest = kNever, latest = kNever;
};

Perches flock_perches(const birds::BirdWorld& world, const FlockWorld::Leader& leader, double reach) {
    const gpu::RouteHeader& route = world.routes[leader.route];
    Perches p;
    p.takeoff = (route.flags.x & KW_ROUTE_TAKEOFF) != 0;
    p.landing = (route.flags.x & KW_ROUTE_LANDING) != 0;
    if (p.landing) {
        const double v = leader.speed, total = route.info.x, l0 = p.takeoff ? double{route.perch.x} : 0.0;
        const double crouch = p.takeoff ? KW_CROUCH_SECONDS : 0.0;
        const auto time_at = [&](double arc) { return crouch + (arc + l0) / v; };
        const double starts = total - double{route.perch.z};
        const double from = std::max(starts - std::max(30.0, 3.0 * reach), l0);
        const double fps = world.fps;
        p.earliest = static_cast<std::uint32_t>(std::floor(time_at(from) * fps));
        p.latest = static_cast<std::uint32_t>(std::ceil(time_at(total + double{route.perch.z}) * fps));
    }
    return p;
}

// Where a bird that takes off leaves the route for the flock: the first frame at which its
// take-off segment is behind it (d = v (t + offset - crouch) >= 2 L0), and its route's
// place and velocity there (flight.cpp's sample, the bird domain's on that frame, whose
// time is frame * frame_dt: step_bird()).
struct Release {
    std::uint32_t frame = 0;
    gpu::FlockStateGpu state{};
};

Release release(const birds::BirdWorld& world, const gpu::BirdParams& bird, float frame_dt) {
    const gpu::RouteHeader& route = world.routes[bird.ids.x];
    const double ends = KW_CROUCH_SECONDS + 2.0 * double{route.perch.x} / double{bird.motion.x} - double{bird.offset.w};
    Release r;
    r.frame = static_cast<std::uint32_t>(std::ceil(ends * static_cast<double>(world.fps)));
    const auto sample = [&] { return birds::sample_route(world, bird.ids.x, static_cast<float>(r.frame) * frame_dt + bird.offset.w, bird.motion.x); };
    birds::RouteSample s = sample();
    // The frame's time rounded as the bird domain rounds it may still fall short of the
    // end by an ulp: the next frame then.
    for (int more = 0; more < 2 && s.progress.speed_fraction < 1.0f; ++more) {
        ++r.frame;
        s = sample();
    }
    r.state = {{s.position.x + bird.offset.x, s.position.y + bird.offset.y, s.position.z + bird.offset.z, 0.0f}, v4(s.velocity)};
    return r;
}

// A bird's landing (FlockPerchGpu): its route at its own speed from the landing
// segment's start (s = L - Ln), where it leaves the flock, to its touchdown 2 Ln / v0 later
// (the end of the landing's deceleration, F.2).
void landing(const birds::BirdWorld& world, bool takeoff, const gpu::BirdParams& bird, gpu::FlockPerchGpu& out) {
    const gpu::RouteHeader& route = world.routes[bird.ids.x];
    const double v = bird.motion.x, l0 = takeoff ? double{route.perch.x} : 0.0;
    const double starts = double{route.info.x} - double{route.perch.z};
    const auto at = static_cast<float>((takeoff ? KW_CROUCH_SECONDS : 0.0) + (starts + l0) / v);
    const birds::RouteSample s = birds::sample_route(world, bird.ids.x, at, bird.motion.x);
    const auto inv_t = static_cast<float>(v / (2.0 * double{route.perch.z}));
    out.land_position = {s.position.x + bird.offset.x, s.position.y + bird.offset.y, s.position.z + bird.offset.z, at};
    out.land_velocity = {s.velocity.x, s.velocity.y, s.velocity.z, inv_t};
}

}  // namespace

Result<FlockWorld> build_flock_world(const Scene& scene, const birds::BirdWorld& world) {
    FlockWorld out;
    const double frame_dt = 1.0 / static_cast<double>(world.fps);
    // Substeps of at most 1/60 s: the rules' stiffest term (separation at full weight
    // within its distance) stays stable at 60 Hz with the shipped weights.
    out.substeps = static_cast<std::uint32_t>(std::ceil(frame_dt * 60.0 - 1e-9));
    out.substeps = std::max(out.substeps, 1u);
    out.dt = static_cast<float>(frame_dt / out.substeps);
    out.frame_dt = world.uniforms().physics.z;  // the bird domain's frame time step, the same float
    out.gravity = world.settings.gravity;
    out.routes.fps = world.fps;
    out.routes.routes = world.routes;
    out.routes.control_points = world.control_points;
    out.routes.arc_samples = world.arc_samples;
    out.birds.resize(world.driven);
    out.perches_of.resize(world.driven);
    out.initial.resize(world.driven);
    out.first.resize(world.driven);

    // The flocks' indices among the flocking ones, and their first bird in the world.
    std::size_t first_bird = 0;
    std::vector<std::uint32_t> flock_of_bird(world.birds.size(), 0);
    for (std::size_t f = 0; f < scene.flocks.size(); ++f) {
        const FlockSpec& spec = scene.flocks[f];
        const std::size_t end = first_bird + spec.count;
        if (spec.flocking) {
            const FlockingSpec& rules = *spec.flocking;
            if (out.flocks.size() == KW_FLOCK_MAX_FLOCKS) {
                return make_error(Error::Kind::InvalidInput, scene.path + ": $.flocks[" + std::to_string(f) + "].flocking: more than " +
                                                                 std::to_string(KW_FLOCK_MAX_FLOCKS) + " flocking flocks in one scene");
            }
            const auto index = static_cast<std::uint32_t>(out.flocks.size());
            gpu::FlockParamsGpu p{};
            p.counts = {rules.neighbours, rules.metric ? 1u : 0u, 0u, 0u};
            const double half_view = (360.0 - static_cast<double>(rules.blind_angle_deg)) * 0.5 * std::numbers::pi / 180.0;
            p.radii = {rules.search_radius, rules.separation_distance, static_cast<float>(std::cos(half_view)), rules.route_radius};
            p.weights = {rules.separation, rules.alignment, rules.cohesion, rules.route};
            p.ground = {rules.ground_clearance, rules.ground, rules.speed_time, rules.separation_front};
            p.collision = {rules.collision_distance, rules.collision_lookahead, 0.0f, 0.0f};
            out.flocks.push_back(p);
            out.search_radius = std::max(out.search_radius, rules.search_radius);
            out.predators.insert(out.predators.end(), rules.predators.begin(), rules.predators.end());
            for (const FlockObstacleSpec& o : rules.obstacles) out.fixed_agents.push_back(obstacle_agent(o));
            for (const FlockAttractorSpec& a : rules.attractors) {
                gpu::FlockAgentGpu agent{};
                agent.position = {a.position.x, a.position.y, a.position.z, a.radius};
                agent.kind_weight = {KW_FLOCK_AGENT_ATTRACTOR, a.weight, 0.0f, 0.0f};
                out.fixed_agents.push_back(agent);
            }
            // The leader: the flock's first route (its variants are jittered copies) at the
            // flock's speed.
            const birds::WingTypeSpec& wing = birds::wing_type_spec(spec.wing_type);
            float cruise = wing.cruise_speed, climb = wing.max_climb, dive = wing.max_dive, change = wing.max_speed_change;
            if (spec.model) {
                cruise = spec.model->flight.cruise_speed;
                climb = spec.model->flight.max_climb;
                dive = spec.model->flight.max_dive;
                change = spec.model->flight.max_speed_change;
            }
            out.leaders.push_back({world.birds[first_bird].ids.x, spec.speed.value_or(cruise)});
            double reach = 0.0;  // the formation's: its farthest offset
            for (std::size_t b = first_bird; b < end; ++b) {
                const gpu::vec4& o = world.birds[b].offset;
                reach = std::max(reach, std::sqrt(double{o.x} * double{o.x} + double{o.y} * double{o.y} + double{o.z} * double{o.z}));
            }
            const Perches perches = flock_perches(world, out.leaders.back(), reach);
            out.perches = out.perches || perches.takeoff || perches.landing;
            std::uint32_t last_release = 0;  // the last bird's first flocking frame
            const auto lateral = static_cast<float>(static_cast<double>(world.settings.gravity) * std::tan(double{world.settings.max_bank}));
            for (std::size_t b = first_bird; b < end; ++b) {
                const gpu::BirdParams& bird = world.birds[b];
                if (bird.ids.w != KW_BIRD_DRIVEN || bird.ids.z >= world.driven) {
                    return make_error(Error::Kind::InvalidInput, scene.path + ": $.flocks[" + std::to_string(f) +
                                                                     "]: its birds are not the bird world's driven birds");
                }
                const float v0 = bird.motion.x;
                gpu::FlockBirdGpu& fb = out.birds[bird.ids.z];
                fb.ids = {index, 0u, perches.earliest, perches.latest};
                fb.offset = {bird.offset.x, bird.offset.y, bird.offset.z, bird.offset.w};
                // Speeds: a starling's flight ranges over about half to one and a half
                // times its cruise speed (docs/flocking.md).
                fb.speed = {v0, 0.5f * v0, 1.5f * v0, change};
                fb.turn = {lateral, static_cast<float>(std::sin(double{climb})), static_cast<float>(std::sin(double{dive})), 0.0f};
                if (perches.takeoff) {
                    // On its perch until its take-off segment ends: the route (the bird
                    // domain flies it, KW_MOTION_ROUTE) to the frame that has it flying at
                    // its speed, where its flocking state starts (flock_body.glsl).
                    const Release r = release(world, bird, out.frame_dt);
                    fb.ids.y = r.frame + 1u;
                    last_release = std::max(last_release, fb.ids.y);
                    out.initial[bird.ids.z] = r.state;
                    out.first[bird.ids.z] = {{0.0f, 0.0f, 0.0f, static_cast<float>(KW_MOTION_ROUTE)}, {0.0f, 0.0f, 0.0f, bird.offset.w}, {0.0f, 0.0f, v0, 0.0f}};
                } else {
                    // Frame 0: where its route puts it, as a route bird's frame 0.
                    const birds::RouteSample s = birds::sample_route(world, bird.ids.x, bird.offset.w, v0);
                    const birds::Vec3 p0{s.position.x + bird.offset.x, s.position.y + bird.offset.y, s.position.z + bird.offset.z};
                    out.initial[bird.ids.z] = {v4(p0), v4(s.velocity)};
                    out.first[bird.ids.z] = {v4(p0), v4(s.velocity), v4(s.acceleration)};
                }
                if (perches.landing) landing(world, perches.takeoff, bird, out.perches_of[bird.ids.z]);
            }
            // A bird that leaves its perch after the leader's landing window opened simply
            // flocks until it passes its own landing's start (on a short route, none at all:
            // its take-off runs into its landing); one still on its perch when the leader
            // touches down would be pulled from there onto its landing: refused.
            if (perches.landing && last_release >= perches.latest) {
                return make_error(Error::Kind::InvalidInput,
                                  scene.path + ": $.flocks[" + std::to_string(f) + "]: its last bird leaves its perch at frame " +
                                      std::to_string(last_release) + ", and its leader touches down at frame " +
                                      std::to_string(perches.latest) +
                                      ": expected every bird to take off before the flock lands (a longer route, a shorter "
                                      "formation.trail or a faster flock)");
            }
        }
        first_bird = end;
    }
    // Predators that are another flock's birds: that flock's first bird.
    out.predator_birds.assign(out.predators.size(), gpu::BirdParams{});
    for (std::size_t a = 0; a < out.predators.size(); ++a) {
        const std::string& name = out.predators[a].flock;
        if (name.empty()) continue;
        std::size_t bird = 0;
        const FlockSpec* found = nullptr;
        for (const FlockSpec& spec : scene.flocks) {
            if (spec.name == name) {
                found = &spec;
                break;
            }
            bird += spec.count;
        }
        if (found == nullptr || found->flocking) {
            return make_error(Error::Kind::InvalidInput,
                              scene.path + ": a predator's \"flock\" is \"" + name + "\": expected the name of a flock without \"flocking\"" +
                                  (found == nullptr ? ", and the scene has no flock of that name" : ", and that one flocks"));
        }
        out.predator_birds[a] = world.birds[bird];
    }
    out.buckets = bucket_count(world.driven);
    return out;
}

void FlockWorld::frame_inputs(std::uint32_t frame, std::span<gpu::FlockParamsGpu> flocks_out,
                              std::span<gpu::FlockAgentGpu> agents_out) const {
    const float t = static_cast<float>(static_cast<double>(frame) / static_cast<double>(routes.fps));
    for (std::size_t f = 0; f < flocks.size(); ++f) {
        flocks_out[f] = flocks[f];
        const birds::RouteSample s = birds::sample_route(routes, leaders[f].route, t, leaders[f].speed);
        flocks_out[f].target = {s.position.x, s.position.y, s.position.z, 0.0f};
        flocks_out[f].counts.z = frame;  // perches: which birds fly (flock_flies())
    }
    for (std::size_t a = 0; a < predators.size(); ++a) {
        const PredatorSpec& p = predators[a];
        gpu::FlockAgentGpu agent{};
        agent.kind_weight = {KW_FLOCK_AGENT_REPELLER, 0.0f, 0.0f, 0.0f};
        agent.position = {p.from.x, p.from.y, p.from.z, p.radius};
        float since = t - p.start;
        if (!p.flock.empty()) {
            // Where that flock's first bird is (flight.cpp: its route and offset).
            const gpu::BirdParams& b = predator_birds[a];
            const birds::RouteSample s = birds::sample_route(routes, b.ids.x, t + b.offset.w, b.motion.x);
            agent.position = {s.position.x + b.offset.x, s.position.y + b.offset.y, s.position.z + b.offset.z, p.radius};
            agent.velocity = {s.velocity.x, s.velocity.y, s.velocity.z, 0.0f};
            if (since >= 0.0f) agent.kind_weight.y = p.weight;
        } else if (since >= 0.0f) {
            if (p.every > 0.0f) since -= p.every * std::floor(since / p.every);
            const glm::vec3 path = p.to - p.from;
            const float length = glm::length(path);
            const float along = p.speed * since;
            if (along <= length) {
                const glm::vec3 at = p.from + (along / length) * path;
                const glm::vec3 velocity = (p.speed / length) * path;
                agent.position = {at.x, at.y, at.z, p.radius};
                agent.velocity = {velocity.x, velocity.y, velocity.z, 0.0f};
                agent.kind_weight.y = p.weight;
            }
        }
        agents_out[a] = agent;
    }
    std::copy(fixed_agents.begin(), fixed_agents.end(), agents_out.begin() + static_cast<std::ptrdiff_t>(predators.size()));
}

}  // namespace kodawari::flocking
