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

}  // namespace

Result<FlockWorld> build_flock_world(const Scene& scene, const birds::BirdWorld& world) {
    FlockWorld out;
    const double frame_dt = 1.0 / static_cast<double>(world.fps);
    // Substeps of at most 1/60 s: the rules' stiffest term (separation at full weight
    // within its distance) stays stable at 60 Hz with the shipped weights.
    out.substeps = static_cast<std::uint32_t>(std::ceil(frame_dt * 60.0 - 1e-9));
    out.substeps = std::max(out.substeps, 1u);
    out.dt = static_cast<float>(frame_dt / out.substeps);
    out.gravity = world.settings.gravity;
    out.routes.fps = world.fps;
    out.routes.routes = world.routes;
    out.routes.control_points = world.control_points;
    out.routes.arc_samples = world.arc_samples;
    out.birds.resize(world.driven);
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
            const auto lateral = static_cast<float>(static_cast<double>(world.settings.gravity) * std::tan(double{world.settings.max_bank}));
            for (std::size_t b = first_bird; b < end; ++b) {
                const gpu::BirdParams& bird = world.birds[b];
                if (bird.ids.w != KW_BIRD_DRIVEN || bird.ids.z >= world.driven) {
                    return make_error(Error::Kind::InvalidInput, scene.path + ": $.flocks[" + std::to_string(f) +
                                                                     "]: its birds are not the bird world's driven birds");
                }
                const float v0 = bird.motion.x;
                gpu::FlockBirdGpu& fb = out.birds[bird.ids.z];
                fb.ids = {index, 0u, 0u, 0u};
                fb.offset = {bird.offset.x, bird.offset.y, bird.offset.z, 0.0f};
                // Speeds: a starling's flight ranges over about half to one and a half
                // times its cruise speed (docs/flocking.md).
                fb.speed = {v0, 0.5f * v0, 1.5f * v0, change};
                fb.turn = {lateral, static_cast<float>(std::sin(double{climb})), static_cast<float>(std::sin(double{dive})), 0.0f};
                // Frame 0: where its route puts it, as a route bird's frame 0.
                const birds::RouteSample s = birds::sample_route(world, bird.ids.x, bird.offset.w, v0);
                const birds::Vec3 p0{s.position.x + bird.offset.x, s.position.y + bird.offset.y, s.position.z + bird.offset.z};
                out.initial[bird.ids.z] = {v4(p0), v4(s.velocity)};
                out.first[bird.ids.z] = {v4(p0), v4(s.velocity), v4(s.acceleration)};
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
