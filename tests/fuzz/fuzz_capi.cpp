// Fuzz target: the C API's world-building calls (kodawari.h), as a binding in another
// language would drive them: the input decodes into a chain world's description (its
// templates, view examples, chains, colliders) and three frames, and into a bird world's
// (routes, flocks, flight settings), with values that are often out of range, non-finite
// or inconsistent (an index past its array, a route with a cusp). Array lengths always
// match what the description says: a caller who lies about a pointer's size is outside
// any C API's reach. The cpu backend with one thread runs what is created. A third kind
// of input drives a scene simulation (kodawari_simulation_*) of a small flocking flock as
// an application does between steps: agents placed (predators, attractors, obstacles,
// capsules, planes, out-of-range kinds and counts), agents on the device asked for and
// encoded, the wind set, frames stepped.
//
// Invariants: every call returns a status from the header's list, with a message when it
// is not KODAWARI_OK; a world that is created steps, and its outputs are finite; agents
// refused are refused naming agents[i] and the member (or the count), and a simulation
// steps on after any refusal with finite poses.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "kodawari/kodawari.h"

namespace {

using kodawari::fuzz::ByteReader;
using kodawari::fuzz::finding;

void check(kodawari_status s, const char* call, const char* message) {
    if (s < KODAWARI_OK || s > KODAWARI_INTERNAL) finding(std::string(call) + " returned an unknown status");
    if (s == KODAWARI_INTERNAL) finding(std::string(call) + " reported an internal error: " + message);
    if (s != KODAWARI_OK && (message == nullptr || message[0] == '\0')) {
        finding(std::string(call) + " failed without a message");
    }
}

void transform(ByteReader& in, kodawari_transform& t) {
    for (float& p : t.position) p = in.number(5.0f);
    for (float& q : t.rotation) q = in.number(1.0f);
    if (in.flag()) t.rotation[0] = t.rotation[1] = t.rotation[2] = 0.0f, t.rotation[3] = 1.0f;
}

void camera(ByteReader& in, kodawari_camera& c) {
    c.orthographic = in.upto(1);
    for (float& p : c.position) p = in.number(10.0f);
    for (float& f : c.forward) f = in.number(1.0f);
}

struct ShapeData {
    std::vector<float> positions;
    std::vector<float> orientations;
};

void shape(ByteReader& in, std::uint32_t joints, ShapeData& out, kodawari_chain_shape& s) {
    out.positions.assign(std::size_t{joints} * 3, 0.0f);
    for (std::uint32_t j = 1; j < joints; ++j) {
        out.positions[j * 3 + 0] = out.positions[(j - 1) * 3 + 0] + in.number(0.05f);
        out.positions[j * 3 + 1] = out.positions[(j - 1) * 3 + 1] + 0.05f + in.number(0.05f);
        out.positions[j * 3 + 2] = out.positions[(j - 1) * 3 + 2] + in.number(0.05f);
    }
    s.positions = out.positions.data();
    s.orientations = nullptr;
    if (in.flag()) {
        out.orientations.assign(std::size_t{joints} * 4, 0.0f);
        for (float& q : out.orientations) q = in.number(1.0f);
        s.orientations = out.orientations.data();
    }
}

void chain_world(ByteReader& in) {
    const std::uint32_t template_count = 1 + in.upto(2);
    const std::uint32_t character_count = 1 + in.upto(2);
    const std::uint32_t chain_count = 1 + in.upto(5);
    const std::uint32_t collider_count = in.upto(3);

    std::vector<kodawari_chain_template_desc> templates(template_count);
    std::vector<ShapeData> shapes;
    std::vector<std::vector<kodawari_view_example>> views(template_count);
    std::vector<std::vector<kodawari_angle_limit>> limits(template_count);
    shapes.reserve(template_count * (1 + KODAWARI_MAX_VIEW_EXAMPLES));
    for (std::uint32_t t = 0; t < template_count; ++t) {
        kodawari_chain_template_desc& d = templates[t];
        d.joint_count = in.upto(9);  // 0 and 1 are errors
        const std::uint32_t joints = d.joint_count < 2 ? 2 : d.joint_count;
        shape(in, joints, shapes.emplace_back(), d.base);
        views[t].resize(in.upto(3));
        for (kodawari_view_example& v : views[t]) {
            for (float& c : v.direction) c = in.number(1.0f);
            v.influence = in.number(10.0f);
            shape(in, joints, shapes.emplace_back(), v.shape);
        }
        d.views = views[t].empty() ? nullptr : views[t].data();
        d.view_count = static_cast<std::uint32_t>(views[t].size());
        d.thickness = in.number(0.05f);
        d.mass = in.number(0.01f);
        // Angle limits: usually one per segment, sometimes a wrong count; kinds past the
        // last, angles past pi and pi/2, and rotations far from unit are errors.
        if (in.flag()) {
            limits[t].resize(in.flag() ? joints - 1 : in.upto(4));
            for (kodawari_angle_limit& l : limits[t]) {
                l.kind = in.upto(5);
                l.angle = in.number(4.0f);
                l.yaw = in.number(2.0f);
                l.rotation[3] = 1.0f;
                if (in.flag()) {
                    for (float& c : l.rotation) c = in.number(1.0f);
                }
            }
            d.limits = limits[t].empty() ? nullptr : limits[t].data();
            d.limit_count = static_cast<std::uint32_t>(limits[t].size());
        }
        kodawari_solver_params_default(&d.solver);
        if (in.flag()) {
            d.solver.max_substep = in.number(0.05f);
            d.solver.iterations = in.upto(70);
            d.solver.stiffness = in.number(1.0f);
            d.solver.rest_stiffness = in.number(1.0f);
            d.solver.damping = in.number(50.0f);
            d.solver.gravity[1] = in.number(50.0f);
            d.solver.wind[0] = in.number(50.0f);
            d.solver.momentum_suppression = in.number(1.0f);
            d.solver.settle_start = in.upto(2);  // 2 is an error
            d.solver.teleport_distance = in.number(5.0f);
            d.solver.normal_drag = in.number(1200.0f);  // past 1000 is an error
            d.solver.tangent_drag = in.number(1200.0f);
        }
    }
    std::vector<kodawari_chain_desc> chains(chain_count);
    for (kodawari_chain_desc& c : chains) {
        c.template_index = in.upto(template_count);  // one past the end is an error
        c.character = in.upto(character_count);
        c.collider_begin = in.upto(collider_count);
        c.collider_count = in.upto(collider_count);
    }
    std::vector<kodawari_collider_desc> attached(collider_count);
    for (kodawari_collider_desc& c : attached) {
        c.character = in.upto(character_count);
        for (float& v : c.local.a) v = in.number(0.5f);
        for (float& v : c.local.b) v = in.number(0.5f);
        c.local.radius = in.number(0.2f);
    }

    kodawari_chain_world_desc desc{};
    desc.templates = templates.data();
    desc.template_count = template_count;
    desc.chains = chains.data();
    desc.chain_count = chain_count;
    desc.character_count = character_count;
    desc.collider_count = collider_count;
    desc.colliders = collider_count > 0 && in.flag() ? attached.data() : nullptr;
    desc.backend.backend = KODAWARI_BACKEND_CPU;
    desc.backend.threads = 1;

    std::vector<kodawari_transform> references(character_count);
    std::vector<kodawari_transform> roots(chain_count);
    std::vector<kodawari_capsule> world_colliders(collider_count);
    const auto next_frame = [&](kodawari_chain_frame& f) {
        f = {};
        f.dt = in.flag() ? 1.0f / 60.0f : in.number(1.0f);
        camera(in, f.camera);
        for (auto& r : references) transform(in, r);
        for (auto& r : roots) transform(in, r);
        for (auto& c : world_colliders) {
            for (float& v : c.a) v = in.number(5.0f);
            for (float& v : c.b) v = in.number(5.0f);
            c.radius = in.number(0.3f);
        }
        f.references = references.data();
        f.reference_count = character_count;
        f.roots = roots.data();
        f.root_count = chain_count;
        if (desc.colliders == nullptr && collider_count > 0) {
            f.colliders = world_colliders.data();
            f.collider_count = collider_count;
        }
    };

    const bool verbose = std::getenv("KODAWARI_FUZZ_VERBOSE") != nullptr;  // what a finding's input decodes to
    const auto dump_frame = [&](const kodawari_chain_frame& f) {
        if (!verbose) return;
        std::fprintf(stderr, "frame: dt %g, camera %u (%g %g %g) fwd (%g %g %g)\n", double{f.dt}, f.camera.orthographic,
                     double{f.camera.position[0]}, double{f.camera.position[1]}, double{f.camera.position[2]},
                     double{f.camera.forward[0]}, double{f.camera.forward[1]}, double{f.camera.forward[2]});
        for (std::uint32_t k = 0; k < f.reference_count + f.root_count; ++k) {
            const kodawari_transform& t = k < f.reference_count ? f.references[k] : f.roots[k - f.reference_count];
            std::fprintf(stderr, "  %s %u: (%g %g %g) q (%g %g %g %g)\n", k < f.reference_count ? "reference" : "root",
                         k < f.reference_count ? k : k - f.reference_count, double{t.position[0]}, double{t.position[1]},
                         double{t.position[2]}, double{t.rotation[0]}, double{t.rotation[1]}, double{t.rotation[2]},
                         double{t.rotation[3]});
        }
        for (std::uint32_t k = 0; k < f.collider_count; ++k) {
            std::fprintf(stderr, "  collider %u: (%g %g %g)-(%g %g %g) r %g\n", k, double{f.colliders[k].a[0]},
                         double{f.colliders[k].a[1]}, double{f.colliders[k].a[2]}, double{f.colliders[k].b[0]},
                         double{f.colliders[k].b[1]}, double{f.colliders[k].b[2]}, double{f.colliders[k].radius});
        }
    };
    if (verbose) {
        for (const kodawari_chain_template_desc& d : templates) {
            const kodawari_solver_params& p = d.solver;
            std::fprintf(stderr, "template: %u joints, %u views, thickness %g, mass %g, substep %g, %u iterations, stiffness %g,"
                         " rest %g, damping %g, gravity %g, wind %g, suppression %g\n", d.joint_count, d.view_count,
                         double{d.thickness}, double{d.mass}, double{p.max_substep}, p.iterations, double{p.stiffness},
                         double{p.rest_stiffness}, double{p.damping}, double{p.gravity[1]}, double{p.wind[0]},
                         double{p.momentum_suppression});
            const std::uint32_t n = d.joint_count < 2 ? 2 : d.joint_count;
            for (std::uint32_t j = 0; j < n; ++j) {
                std::fprintf(stderr, "  base %u: (%g %g %g)%s\n", j, double{d.base.positions[j * 3]},
                             double{d.base.positions[j * 3 + 1]}, double{d.base.positions[j * 3 + 2]},
                             d.base.orientations ? " (orientations given)" : "");
            }
            for (std::uint32_t v = 0; v < d.view_count; ++v) {
                std::fprintf(stderr, "  view %u: (%g %g %g) influence %g\n", v, double{d.views[v].direction[0]},
                             double{d.views[v].direction[1]}, double{d.views[v].direction[2]}, double{d.views[v].influence});
            }
        }
        for (const kodawari_chain_desc& c : chains) {
            std::fprintf(stderr, "chain: template %u, character %u, colliders [%u, +%u)\n", c.template_index, c.character,
                         c.collider_begin, c.collider_count);
        }
        std::fprintf(stderr, "%u characters, %u colliders%s\n", character_count, collider_count,
                     desc.colliders ? " (attached)" : "");
    }
    kodawari_chain_frame frame;
    next_frame(frame);
    dump_frame(frame);
    kodawari_chain_world* world = nullptr;
    const kodawari_status created = kodawari_chain_world_create(&desc, &frame, &world);
    check(created, "kodawari_chain_world_create", kodawari_last_error());
    if (created != KODAWARI_OK) {
        if (world != nullptr) finding("a failed create set *out");
        return;
    }
    kodawari_chain_world_info info{};
    check(kodawari_chain_world_get_info(world, &info), "kodawari_chain_world_get_info", kodawari_chain_world_last_error(world));
    std::vector<float> positions(std::size_t{info.joint_count} * 3);
    std::vector<float> weights(std::size_t{chain_count} * KODAWARI_WEIGHTS_PER_CHAIN);
    kodawari_chain_output out{};
    out.positions = positions.data();
    out.positions_capacity = positions.size();
    out.weights = weights.data();
    out.weights_capacity = weights.size();
    if (in.flag()) {
        // A wind, in range or not (each bound exceeded by a fifth at most), or calm air.
        kodawari_wind wind;
        kodawari_wind_default(&wind);
        for (float& v : wind.velocity) v = in.number(120.0f);
        wind.gust = in.number(5.0f);
        wind.gust_period = in.number(4.0f);
        wind.gust_size = in.number(20.0f);
        wind.seed = in.u32();
        const kodawari_status s = kodawari_chain_world_set_wind(world, in.flag() ? &wind : nullptr);
        check(s, "kodawari_chain_world_set_wind", kodawari_chain_world_last_error(world));
    }
    for (int f = 0; f < 3; ++f) {
        next_frame(frame);
        dump_frame(frame);
        const kodawari_status s = kodawari_chain_world_step(world, &frame);
        check(s, "kodawari_chain_world_step", kodawari_chain_world_last_error(world));
        if (s != KODAWARI_OK) continue;  // a frame with bad values is refused; the world stays
        const kodawari_status r = kodawari_chain_world_read(world, &out);
        check(r, "kodawari_chain_world_read", kodawari_chain_world_last_error(world));
        if (r != KODAWARI_OK) finding("reading a world that stepped failed");
        for (float p : positions) kodawari::fuzz::require_finite(p, "a chain joint position");
        for (float w : weights) kodawari::fuzz::require_finite(w, "a view weight");
    }
    kodawari_chain_world_destroy(world);
}

void bird_world(ByteReader& in) {
    const std::uint32_t route_count = 1 + in.upto(1);
    std::vector<std::vector<float>> points(route_count);
    std::vector<kodawari_route_desc> routes(route_count);
    for (std::uint32_t r = 0; r < route_count; ++r) {
        const std::uint32_t segments = 1 + in.upto(3);
        points[r].resize((3 * segments + 1) * 3);
        for (std::size_t k = 0; k < points[r].size(); ++k) points[r][k] = static_cast<float>(k) * 3.0f + in.number(20.0f);
        routes[r].points = points[r].data();
        routes[r].point_count = static_cast<std::uint32_t>(points[r].size() / 3) - in.upto(1);  // 3n+1, or not
        routes[r].loop = in.upto(1);
        routes[r].parametric = in.upto(1);
        routes[r].segment_duration = in.number(5.0f);
    }
    const std::uint32_t flock_count = 1 + in.upto(1);
    std::vector<kodawari_flock_desc> flocks(flock_count);
    std::vector<std::vector<float>> offsets(flock_count), phases(flock_count);
    std::uint32_t birds = 0;
    for (std::uint32_t k = 0; k < flock_count; ++k) {
        kodawari_flock_desc& f = flocks[k];
        const auto wing = static_cast<kodawari_wing_type>(in.upto(3));  // 3 is not a wing type
        const std::uint32_t count = 1 + in.upto(20);
        check(kodawari_flock_desc_default(wing, count, &f), "kodawari_flock_desc_default", kodawari_last_error());
        f.route = in.upto(route_count);
        if (in.flag()) {
            f.speed = in.number(40.0f);
            f.frequency = in.number(10.0f);
            f.amplitude = in.number(3.0f);
        }
        if (in.flag()) {
            offsets[k].resize(std::size_t{count} * 4);
            for (float& v : offsets[k]) v = in.number(10.0f);
            f.offsets = offsets[k].data();
        }
        if (in.flag()) {
            phases[k].resize(count);
            for (float& v : phases[k]) v = in.number(1.0f);
            f.phases = phases[k].data();
        }
        f.count = count;
        birds += count;
    }
    kodawari_bird_world_desc desc{};
    desc.routes = routes.data();
    desc.route_count = route_count;
    desc.flocks = flocks.data();
    desc.flock_count = flock_count;
    desc.fps = in.flag() ? 60.0f : in.number(240.0f);
    kodawari_flight_settings_default(&desc.flight);
    if (in.flag()) {
        desc.flight.gravity = in.number(20.0f);
        desc.flight.max_bank = in.number(1.6f);
        desc.flight.seed_bank_rule = in.upto(1);
        desc.flight.seed_mode_rule = in.upto(1);
        desc.flight.ascend_enter = in.number(1.6f);
        desc.flight.ascend_exit = in.number(1.6f);
        desc.flight.descend_enter = in.number(1.6f);
        desc.flight.descend_exit = in.number(1.6f);
        for (float& r : desc.flight.blend_rates) r = in.number(1.0f);
    }
    desc.backend.backend = KODAWARI_BACKEND_CPU;
    desc.backend.threads = 1;
    if (std::getenv("KODAWARI_FUZZ_VERBOSE") != nullptr) {  // what a finding's input decodes to
        for (std::uint32_t r = 0; r < route_count; ++r) {
            std::fprintf(stderr, "route %u: %u points, loop %u, parametric %u, %g s per segment:", r, routes[r].point_count,
                         routes[r].loop, routes[r].parametric, double{routes[r].segment_duration});
            for (std::uint32_t k = 0; k < routes[r].point_count * 3; ++k) std::fprintf(stderr, " %g", double{points[r][k]});
            std::fprintf(stderr, "\n");
        }
        for (const kodawari_flock_desc& f : flocks) {
            std::fprintf(stderr, "flock: route %u, wing %d, %u birds, speed %g, frequency %g, amplitude %g, offsets %s, phases %s\n",
                         f.route, static_cast<int>(f.wing_type), f.count, double{f.speed}, double{f.frequency},
                         double{f.amplitude}, f.offsets ? "yes" : "no", f.phases ? "yes" : "no");
        }
        std::fprintf(stderr, "fps %g, gravity %g, max_bank %g, rules %u %u, climb %g %g %g %g, blend %g %g %g\n",
                     double{desc.fps}, double{desc.flight.gravity}, double{desc.flight.max_bank}, desc.flight.seed_bank_rule,
                     desc.flight.seed_mode_rule, double{desc.flight.ascend_enter}, double{desc.flight.ascend_exit},
                     double{desc.flight.descend_enter}, double{desc.flight.descend_exit}, double{desc.flight.blend_rates[0]},
                     double{desc.flight.blend_rates[1]}, double{desc.flight.blend_rates[2]});
    }
    kodawari_bird_world* world = nullptr;
    const kodawari_status created = kodawari_bird_world_create(&desc, &world);
    check(created, "kodawari_bird_world_create", kodawari_last_error());
    if (created != KODAWARI_OK) return;
    constexpr std::uint32_t kFrames = 3;
    std::vector<float> world_transforms(std::size_t{kFrames} * birds * KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS);
    kodawari_bird_output out{};
    out.world_transforms = world_transforms.data();
    out.world_transforms_capacity = world_transforms.size();
    const kodawari_status s = kodawari_bird_world_simulate(world, kFrames, &out);
    check(s, "kodawari_bird_world_simulate", kodawari_bird_world_last_error(world));
    if (s != KODAWARI_OK) finding("a bird world that was created failed to simulate");
    for (float v : world_transforms) kodawari::fuzz::require_finite(v, "a bird transform");
    kodawari_bird_world_destroy(world);
}

// A flocking flock of 37 birds (not a multiple of any workgroup) on a circle of four
// Bezier segments, written once per process beside the other scratch files. (A generated
// route took 0.3 s to open, the flyability checks of its candidates: 10 executions a
// second under ASan.)
const std::string& flocking_scene() {
    static const std::string path = [] {
        const std::string file = (kodawari::fuzz::scratch_dir() / "capi-flocking.json").string();
        const std::string text = R"({"format": "kodawari-scene", "version": 2, "name": "capi-fuzz", "fps": 60, "duration": 1,
  "camera": {"position": [0, 60, -160], "target": [0, 45, 0], "fov_deg": 60},
  "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 37, "seed": 5, "speed": 15,
    "route": {"points": [[40, 45, 0], [40, 45, 22.09], [22.09, 45, 40], [0, 45, 40], [-22.09, 45, 40], [-40, 45, 22.09],
      [-40, 45, 0], [-40, 45, -22.09], [-22.09, 45, -40], [0, 45, -40], [22.09, 45, -40], [40, 45, -22.09], [40, 45, 0]],
      "loop": true},
    "formation": {"spread": [8, 3, 8]}, "flocking": {}}]})";
        kodawari::fuzz::write_file(file, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
        return file;
    }();
    return path;
}

void agent(ByteReader& in, kodawari_flock_agent& a) {
    kodawari_flock_agent_default(&a);
    a.kind = in.upto(6);  // 5 and 6 are no kind
    for (float& v : a.position) v = in.flag() ? in.number(60.0f) : in.number(2.0e6f);
    for (float& v : a.velocity) v = in.number(in.flag() ? 40.0f : 2000.0f);
    if (in.flag()) a.radius = in.number(in.flag() ? 30.0f : 2.0e4f);
    if (in.flag()) a.weight = in.number(in.flag() ? 80.0f : 2000.0f);
    if (in.flag()) a.margin = in.number(in.flag() ? 5.0f : 2000.0f);
    if (in.flag()) {
        for (float& v : a.end) v = in.number(60.0f);
    }
    if (in.flag()) {
        for (float& v : a.normal) v = in.number(in.flag() ? 1.0f : 1.0e-5f);
    }
}

void scene_simulation(ByteReader& in) {
    kodawari_backend_options backend{};
    backend.backend = in.flag() ? KODAWARI_BACKEND_CPU_REFERENCE : KODAWARI_BACKEND_CPU;
    backend.threads = 1;
    kodawari_simulation* sim = nullptr;
    const kodawari_status opened = kodawari_simulation_open(flocking_scene().c_str(), &backend, 4, &sim);
    check(opened, "kodawari_simulation_open", kodawari_last_error());
    if (opened != KODAWARI_OK) finding("the fuzz scene did not open: " + std::string(kodawari_last_error()));
    kodawari_simulation_info info{};
    check(kodawari_simulation_get_info(sim, &info), "kodawari_simulation_get_info", kodawari_simulation_last_error(sim));
    std::vector<float> poses(std::size_t{info.bird_count} * KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS);
    std::vector<kodawari_flock_agent> agents;
    for (std::uint32_t op = 0; op < 6 && info.next_frame < info.frame_count; ++op) {
        switch (in.upto(4)) {
        case 0: {
            // Mostly a few agents; sometimes past the 64 allowed.
            const std::uint32_t count = in.flag() ? in.upto(4) : 60 + in.upto(8);
            agents.resize(count);
            for (kodawari_flock_agent& a : agents) agent(in, a);
            const bool null_array = count == 0 && in.flag();
            const kodawari_status s = kodawari_simulation_set_flock_agents(sim, null_array ? nullptr : agents.data(), count);
            const std::string message = kodawari_simulation_last_error(sim);
            check(s, "kodawari_simulation_set_flock_agents", message.c_str());
            if (s == KODAWARI_INVALID_ARGUMENT && count <= 64 && message.find("agents[") == std::string::npos) {
                finding("agents refused without naming agents[i]: " + message);
            }
            break;
        }
        case 3: {
            // Agents on the device: the count (a CPU backend refuses any above 0, as does
            // a count above 64) and one agent's encoding.
            const std::uint32_t count = in.upto(70);
            const kodawari_status s = kodawari_simulation_set_flock_device_agents(sim, count);
            const std::string message = kodawari_simulation_last_error(sim);
            check(s, "kodawari_simulation_set_flock_device_agents", message.c_str());
            if (count > 0 && s == KODAWARI_OK) finding("a cpu simulation took agents on the device");
            kodawari_flock_agent a;
            agent(in, a);
            float encoded[12];
            const kodawari_status e = kodawari_encode_flock_agent(&a, encoded);
            check(e, "kodawari_encode_flock_agent", kodawari_last_error());
            if (e == KODAWARI_OK) {
                for (float v : encoded) kodawari::fuzz::require_finite(v, "an encoded agent");
            }
            break;
        }
        case 1: {
            kodawari_wind wind;
            kodawari_wind_default(&wind);
            for (float& v : wind.velocity) v = in.number(in.flag() ? 20.0f : 200.0f);
            wind.gust = in.number(5.0f);
            wind.gust_period = in.number(2000.0f);
            wind.gust_size = in.number(2.0e4f);
            wind.seed = in.u32();
            const kodawari_status s = kodawari_simulation_set_wind(sim, in.flag() ? nullptr : &wind);
            check(s, "kodawari_simulation_set_wind", kodawari_simulation_last_error(sim));
            break;
        }
        default: {
            const std::uint32_t frames = 1 + in.upto(1);
            const kodawari_status s = kodawari_simulation_step(sim, frames);
            check(s, "kodawari_simulation_step", kodawari_simulation_last_error(sim));
            if (s != KODAWARI_OK) {
                if (info.next_frame + frames <= info.frame_count) {
                    finding("a step within the frames left failed: " + std::string(kodawari_simulation_last_error(sim)));
                }
                break;
            }
            kodawari_bird_output out{};
            out.world_transforms = poses.data();
            out.world_transforms_capacity = poses.size();
            const kodawari_status read = kodawari_simulation_bird_poses(sim, &out);
            check(read, "kodawari_simulation_bird_poses", kodawari_simulation_last_error(sim));
            if (read != KODAWARI_OK) finding("the poses of a stepped simulation were refused");
            for (float v : poses) kodawari::fuzz::require_finite(v, "a flocking bird's transform");
            break;
        }
        }
        check(kodawari_simulation_get_info(sim, &info), "kodawari_simulation_get_info", kodawari_simulation_last_error(sim));
    }
    kodawari_simulation_destroy(sim);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ByteReader in(data, size);
    switch (in.byte() % 3) {
    case 0:
        chain_world(in);
        break;
    case 1:
        bird_world(in);
        break;
    default:
        scene_simulation(in);
        break;
    }
    return 0;
}
