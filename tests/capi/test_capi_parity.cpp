// The C API against the C++ path (issue 11, section 3): the shipped scenes' chains and
// flocks, turned into kodawari.h's plain arrays, simulated through libkodawari.so and
// through the C++ backends (RodBackend, BirdBackend) on the same world and the same
// frames, for every backend kind. Tolerance: none. Both paths run the same code on the
// same inputs (the .so holds its own copy of the engine, built with the same flags), so
// every joint, weight and bird part must have the same bits; a wrong field, index or
// conversion in the binding shows as a difference. The vulkan kind runs where a Vulkan
// device exists (lavapipe on a machine without a GPU) with validation on, and skips,
// saying why, only where there is none.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <cstdlib>
#include <optional>
#include <thread>
#include <vector>

#include <kodawari/kodawari.h>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_support.hpp"
#include "vulkan_app_support.hpp"

using namespace kodawari;

namespace {

kodawari_backend c_backend(BackendKind kind) {
    switch (kind) {
        case BackendKind::CpuReference: return KODAWARI_BACKEND_CPU_REFERENCE;
        case BackendKind::Cpu: return KODAWARI_BACKEND_CPU;
        case BackendKind::Vulkan: break;
    }
    return KODAWARI_BACKEND_VULKAN;
}

// `c`'s isa must outlive the options (a test parameter's does).
kodawari_backend_options c_options(const testing_support::BackendCase& c) {
    kodawari_backend_options o{};
    o.backend = c_backend(c.kind);
    o.isa = c.isa.empty() ? nullptr : c.isa.c_str();
    o.validation = testing_support::validation_requested() ? 1u : 0u;
    o.threads = 3;
    return o;
}

void put3(float* out, glm::vec3 v) {
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
}
void put4(float* out, glm::quat q) {
    out[0] = q.x;
    out[1] = q.y;
    out[2] = q.z;
    out[3] = q.w;
}

// A scene's characters as kodawari.h's description: one template per chain of each
// character (build_rod_scene's order), the RodScene's chains, colliders given per frame.
struct CWorld {
    // Every shape's arrays and views, kept alive. The descriptions point into the inner
    // vectors, whose buffers stay where they are when the outer vector grows.
    std::vector<std::vector<float>> floats;
    std::vector<std::vector<kodawari_view_example>> views;
    std::vector<std::vector<kodawari_angle_limit>> limits;
    std::vector<kodawari_chain_template_desc> templates;
    std::vector<kodawari_chain_desc> chains;
    kodawari_chain_world_desc desc{};

    kodawari_chain_shape shape(const rods::ChainShape& s) {
        floats.emplace_back(s.positions.size() * 3);
        floats.emplace_back(s.orientations.size() * 4);
        std::vector<float>& p = floats[floats.size() - 2];
        std::vector<float>& o = floats.back();
        for (std::size_t i = 0; i < s.positions.size(); ++i) put3(&p[3 * i], s.positions[i]);
        for (std::size_t i = 0; i < s.orientations.size(); ++i) put4(&o[4 * i], s.orientations[i]);
        return {p.data(), o.data()};
    }

    CWorld(const Scene& scene, const RodScene& rods, testing_support::BackendCase kind) : backend_case(std::move(kind)) {
        for (const CharacterSpec& ch : scene.characters) {
            for (const ChainSpec& c : ch.chains) {
                kodawari_chain_template_desc t{};
                t.joint_count = static_cast<std::uint32_t>(c.base.positions.size());
                t.base = shape(c.base);
                std::vector<kodawari_view_example>& v = views.emplace_back();
                for (const ViewSpec& view : c.views) {
                    kodawari_view_example e{};
                    put3(e.direction, view.view.direction);
                    e.influence = view.view.influence;
                    e.shape = shape(view.shape);
                    v.push_back(e);
                }
                t.views = v.data();
                t.view_count = static_cast<std::uint32_t>(v.size());
                t.thickness = c.thickness;
                t.mass = c.mass;
                t.solver.max_substep = c.params.max_substep;
                t.solver.iterations = c.params.iterations;
                t.solver.stiffness = c.params.stiffness;
                t.solver.rest_stiffness = c.params.rest_stiffness;
                t.solver.damping = c.params.damping;
                put3(t.solver.gravity, c.params.gravity);
                put3(t.solver.wind, c.params.wind);
                t.solver.momentum_suppression = c.params.momentum_suppression;
                t.solver.settle_start = c.params.settle_start ? 1u : 0u;
                t.solver.teleport_distance = c.params.teleport_distance;
                t.solver.normal_drag = c.params.normal_drag;
                t.solver.tangent_drag = c.params.tangent_drag;
                std::vector<kodawari_angle_limit>& l = limits.emplace_back();
                for (const rods::AngleLimit& a : c.limits) {
                    kodawari_angle_limit e{static_cast<std::uint32_t>(a.kind), a.angle, a.yaw, {}};
                    put4(e.rotation, a.rotation);
                    l.push_back(e);
                }
                t.limits = l.empty() ? nullptr : l.data();
                t.limit_count = static_cast<std::uint32_t>(l.size());
                templates.push_back(t);
            }
        }
        for (const rods::ChainInstance& c : rods.world.chains) {
            chains.push_back({c.template_index, c.character, c.collider_begin, c.collider_count});
        }
        desc.templates = templates.data();
        desc.template_count = static_cast<std::uint32_t>(templates.size());
        desc.chains = chains.data();
        desc.chain_count = static_cast<std::uint32_t>(chains.size());
        desc.character_count = rods.world.character_count;
        desc.collider_count = rods.world.collider_count;
        desc.colliders = nullptr;
        desc.backend = c_options(backend_case);
    }
    CWorld(const Scene& scene, const RodScene& rods, BackendKind kind)
        : CWorld(scene, rods, testing_support::BackendCase{kind, ""}) {}
    CWorld(const CWorld&) = delete;
    CWorld& operator=(const CWorld&) = delete;

    testing_support::BackendCase backend_case;  // desc.backend.isa points into it
};

// A RodFrame as kodawari.h's frame (world-space colliders).
struct CFrame {
    std::vector<kodawari_transform> references, roots;
    std::vector<kodawari_capsule> colliders;
    kodawari_chain_frame frame{};

    explicit CFrame(const rods::RodFrame& f) {
        const auto transform = [](const rods::Transform& t) {
            kodawari_transform out{};
            put3(out.position, t.position);
            put4(out.rotation, t.rotation);
            return out;
        };
        for (const rods::Transform& t : f.reference) references.push_back(transform(t));
        for (const rods::Transform& t : f.roots) roots.push_back(transform(t));
        for (const rods::Collider& c : f.colliders) {
            kodawari_capsule out{};
            put3(out.a, c.a);
            put3(out.b, c.b);
            out.radius = c.radius;
            colliders.push_back(out);
        }
        frame.dt = f.dt;
        frame.camera.orthographic = f.camera.projection == rods::Camera::Projection::Orthographic ? 1u : 0u;
        put3(frame.camera.position, f.camera.position);
        put3(frame.camera.forward, f.camera.forward);
        frame.references = references.data();
        frame.reference_count = static_cast<std::uint32_t>(references.size());
        frame.roots = roots.data();
        frame.root_count = static_cast<std::uint32_t>(roots.size());
        frame.colliders = colliders.empty() ? nullptr : colliders.data();
        frame.collider_count = static_cast<std::uint32_t>(colliders.size());
    }
};

// What kodawari_chain_world_read gives, every array.
struct CRead {
    std::vector<float> positions, orientations, rest, view, weights;
    CRead(std::size_t joints, std::size_t chains)
        : positions(joints * 3), orientations(joints * 4), rest(joints * 3), view(chains * 3),
          weights(chains * KODAWARI_WEIGHTS_PER_CHAIN) {}
    kodawari_status read(kodawari_chain_world* world) {
        kodawari_chain_output out{};
        out.positions = positions.data();
        out.positions_capacity = positions.size();
        out.orientations = orientations.data();
        out.orientations_capacity = orientations.size();
        out.rest_positions = rest.data();
        out.rest_positions_capacity = rest.size();
        out.view_directions = view.data();
        out.view_directions_capacity = view.size();
        out.weights = weights.data();
        out.weights_capacity = weights.size();
        return kodawari_chain_world_read(world, &out);
    }
};

// The first element where the C read and the C++ snapshot differ in their bits, or "".
std::string first_difference(const CRead& c, const ChainSnapshot& s) {
    std::vector<float> p(s.positions.size() * 3), o(s.orientations.size() * 4), r(s.rest.size() * 3), v(s.view_directions.size() * 3);
    for (std::size_t i = 0; i < s.positions.size(); ++i) put3(&p[3 * i], s.positions[i]);
    for (std::size_t i = 0; i < s.orientations.size(); ++i) put4(&o[4 * i], s.orientations[i]);
    for (std::size_t i = 0; i < s.rest.size(); ++i) put3(&r[3 * i], s.rest[i]);
    for (std::size_t i = 0; i < s.view_directions.size(); ++i) put3(&v[3 * i], s.view_directions[i]);
    const auto compare = [](const char* name, const std::vector<float>& a, const std::vector<float>& b) -> std::string {
        if (a.size() != b.size()) return std::string(name) + ": " + std::to_string(a.size()) + " vs " + std::to_string(b.size()) + " floats";
        for (std::size_t i = 0; i < a.size(); ++i) {
            if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) {
                return std::string(name) + "[" + std::to_string(i) + "]: C " + std::to_string(a[i]) + ", C++ " + std::to_string(b[i]);
            }
        }
        return "";
    };
    for (const std::string& d : {compare("positions", c.positions, p), compare("orientations", c.orientations, o),
                                 compare("rest", c.rest, r), compare("view_directions", c.view, v),
                                 compare("weights", c.weights, s.weights)}) {
        if (!d.empty()) return d;
    }
    return "";
}

Scene load(const std::string& name) {
    auto scene = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name);
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    return scene.ok() ? std::move(scene).value() : Scene{};
}

class CApiParity : public ::testing::TestWithParam<testing_support::BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == BackendKind::Vulkan) {
            if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
        }
    }

    // `frames` frames of `scene`'s characters through the C++ backend and through the C
    // API, compared bit for bit after every frame.
    static void same_bits(const Scene& scene, std::uint32_t frames) {
        auto built = build_rod_scene(scene);
        ASSERT_TRUE(built.ok()) << built.error().message;
        const RodScene& rods = built.value();
        auto made = make_rod_backend(GetParam(), testing_support::backend_options(GetParam()));
        ASSERT_TRUE(made.ok()) << made.error().message;
        RodBackend& cpp = *made.value();

        CWorld c(scene, rods, GetParam());
        ASSERT_EQ(c.templates.size(), rods.world.templates.size());
        rods::RodFrame frame = rods.frame(0);
        ASSERT_TRUE(cpp.load(rods.world, frame).ok());
        kodawari_chain_world* world = nullptr;
        const CFrame initial(frame);
        ASSERT_EQ(kodawari_chain_world_create(&c.desc, &initial.frame, &world), KODAWARI_OK) << kodawari_last_error();
        const std::unique_ptr<kodawari_chain_world, void (*)(kodawari_chain_world*)> owner(world, kodawari_chain_world_destroy);

        kodawari_chain_world_info info{};
        ASSERT_EQ(kodawari_chain_world_get_info(world, &info), KODAWARI_OK);
        ASSERT_EQ(info.joint_count, rods.world.joint_count);
        ASSERT_EQ(info.backend, c_backend(GetParam()));
        for (std::uint32_t k = 0; k < info.chain_count; ++k) {
            std::uint32_t begin = 0, count = 0;
            ASSERT_EQ(kodawari_chain_world_chain_joints(world, k, &begin, &count), KODAWARI_OK);
            ASSERT_EQ(begin, rods.world.chains[k].joint_begin);
            ASSERT_EQ(count, rods.world.templ(rods.world.chains[k]).chain.joint_count);
        }
        CRead read(rods.world.joint_count, rods.world.chains.size());
        ChainSnapshot snapshot;
        for (std::uint32_t f = 0; f <= frames; ++f) {
            if (f > 0) {
                rods.frame(f, frame);
                ASSERT_TRUE(cpp.step(frame).ok());
                const CFrame input(frame);
                ASSERT_EQ(kodawari_chain_world_step(world, &input.frame), KODAWARI_OK) << kodawari_last_error();
            }
            ASSERT_TRUE(cpp.read(snapshot).ok());
            ASSERT_EQ(read.read(world), KODAWARI_OK) << kodawari_last_error();
            const std::string difference = first_difference(read, snapshot);
            ASSERT_EQ(difference, "") << scene.name << " frame " << f;
        }
        ASSERT_EQ(kodawari_chain_world_get_info(world, &info), KODAWARI_OK);
        EXPECT_EQ(info.validation_messages, 0u) << "Vulkan validation reported problems through the C API (see stderr)";
        EXPECT_EQ(cpp.validation_messages(), 0u);
        std::printf("[ measured ] %s on %s: %u chains, %u joints, %u frames, the same bits\n", scene.name.c_str(), info.device,
                    info.chain_count, info.joint_count, frames);
    }
};

}  // namespace

// The ahoge scene (1 chain of 12 joints, 2 colliders, the orbiting camera): 4 s.
TEST_P(CApiParity, AhogeHasTheCppPathsBits) { same_bits(load("ahoge.json"), 240); }

// bangs: 3 chains with mirrored copies and explicit orientations.
TEST_P(CApiParity, BangsHaveTheCppPathsBits) { same_bits(load("bangs.json"), 120); }

// limits: 7 bunnies whose chains carry every angle limit kind (kodawari_angle_limit).
TEST_P(CApiParity, LimitsHaveTheCppPathsBits) { same_bits(load("limits.json"), 90); }

// A crowd of 13 critters of 8 chains each (5 in the file, 3 of them mirrored) = 104 chains:
// one full vulkan workgroup of 64 and a partial one, many characters and collider ranges.
TEST_P(CApiParity, CrowdHasTheCppPathsBits) {
    Scene scene = load("crowd.json");
    ASSERT_EQ(scene.crowds.size(), 1u);
    scene.crowds[0].count = 13;
    same_bits(scene, 60);
}

// The flock scene's 270 birds (4 workgroups of 64 and 14), one C flock per bird (the
// scene's birds each have their own jittered speed, frequency and amplitude): the parts'
// local transforms have the C++ poses' bits, and the world transforms are the locals
// composed down the rig.
TEST_P(CApiParity, FlockHasTheCppPathsBits) {
    const Scene scene = load("flock.json");
    auto built = build_bird_world(scene);
    ASSERT_TRUE(built.ok()) << built.error().message;
    birds::BirdWorld world = built.value();
    // Not the default (0.3 s), so that a C field left unread would show.
    world.settings.bank_time = 0.55f;
    const std::size_t birds = world.birds.size();
    ASSERT_NE(birds % KW_BIRDS_WORKGROUP_SIZE, 0u) << "must exercise a partial workgroup";

    std::vector<std::vector<float>> points;
    std::vector<kodawari_route_desc> routes;
    for (const gpu::RouteHeader& r : world.routes) {
        std::vector<float>& p = points.emplace_back();
        for (std::uint32_t i = 0; i < 3 * r.extent.y + 1; ++i) {
            const gpu::vec4& q = world.control_points[r.extent.x + i];
            p.insert(p.end(), {q.x, q.y, q.z});
        }
        kodawari_route_desc d{};
        d.points = p.data();
        d.point_count = 3 * r.extent.y + 1;
        d.loop = (r.flags.x & KW_ROUTE_LOOP) != 0 ? 1u : 0u;
        d.parametric = (r.flags.x & KW_ROUTE_PARAMETRIC) != 0 ? 1u : 0u;
        d.segment_duration = r.info.y;
        routes.push_back(d);
    }
    std::vector<kodawari_flock_desc> flocks(birds);
    for (std::size_t b = 0; b < birds; ++b) {
        const gpu::BirdParams& p = world.birds[b];
        kodawari_flock_desc& f = flocks[b];
        f.route = p.ids.x;
        f.wing_type = static_cast<kodawari_wing_type>(p.ids.y);
        f.count = 1;
        f.speed = p.motion.x;
        f.frequency = p.motion.y;
        f.amplitude = p.motion.z;
        f.offsets = &world.birds[b].offset.x;
        f.phases = &world.birds[b].motion.w;
    }
    kodawari_bird_world_desc desc{};
    desc.routes = routes.data();
    desc.route_count = static_cast<std::uint32_t>(routes.size());
    desc.flocks = flocks.data();
    desc.flock_count = static_cast<std::uint32_t>(flocks.size());
    desc.fps = world.fps;
    const birds::FlightSettings& s = world.settings;
    desc.flight = {s.gravity, s.max_bank, s.bank_rule == birds::BankRule::Seed ? 1u : 0u,
                   s.mode_rule == birds::ModeRule::Seed ? 1u : 0u, s.ascend_enter, s.ascend_exit, s.descend_enter,
                   s.descend_exit, s.seed_accel_threshold, {s.blend_rates[0], s.blend_rates[1], s.blend_rates[2]},
                   s.bank_time};
    desc.backend = c_options(GetParam());
    kodawari_bird_world* c = nullptr;
    ASSERT_EQ(kodawari_bird_world_create(&desc, &c), KODAWARI_OK) << kodawari_last_error();
    const std::unique_ptr<kodawari_bird_world, void (*)(kodawari_bird_world*)> owner(c, kodawari_bird_world_destroy);

    auto made = make_bird_backend(GetParam(), testing_support::backend_options(GetParam()));
    ASSERT_TRUE(made.ok()) << made.error().message;
    BirdBackend& cpp = *made.value();
    ASSERT_TRUE(cpp.load(world).ok());

    // 3 calls of 41 frames each: the frame counter carries across calls on both sides.
    constexpr std::uint32_t kFrames = 41;
    std::vector<gpu::BirdPose> poses(kFrames * birds);
    std::vector<float> local(kFrames * birds * 49), global(kFrames * birds * 49);
    const auto offsets = [](std::uint32_t wing) { return birds::part_offsets(static_cast<birds::WingType>(wing)); };
    for (int call = 0; call < 3; ++call) {
        ASSERT_TRUE(cpp.simulate(kFrames, {poses, {}}).ok());
        kodawari_bird_output out{local.data(), local.size(), global.data(), global.size()};
        ASSERT_EQ(kodawari_bird_world_simulate(c, kFrames, &out), KODAWARI_OK) << kodawari_last_error();
        for (std::size_t i = 0; i < poses.size(); ++i) {
            const gpu::BirdPose& pose = poses[i];
            const auto part = offsets(world.birds[i % birds].ids.y);
            for (std::size_t k = 0; k < birds::kPartCount; ++k) {
                const float* l = &local[i * 49 + k * 7];
                const float expected[7] = {k == 0 ? pose.position.x : part[k][0], k == 0 ? pose.position.y : part[k][1],
                                           k == 0 ? pose.position.z : part[k][2], pose.rotation[k].x,
                                           pose.rotation[k].y, pose.rotation[k].z, pose.rotation[k].w};
                ASSERT_EQ(std::memcmp(l, expected, sizeof expected), 0)
                    << "call " << call << ", frame " << i / birds << ", bird " << i % birds << ", part " << k;
                // World: parent's world turned by the local (checked to float rounding).
                if (const int parent = birds::kPartParents[k]; parent >= 0) {
                    const float* pw = &global[i * 49 + static_cast<std::size_t>(parent) * 7];
                    const glm::quat q(pw[6], pw[3], pw[4], pw[5]);
                    const glm::vec3 p = glm::vec3(pw[0], pw[1], pw[2]) + q * glm::vec3(l[0], l[1], l[2]);
                    const float* w = &global[i * 49 + k * 7];
                    ASSERT_LT(glm::length(p - glm::vec3(w[0], w[1], w[2])), 1e-4f) << "bird " << i % birds << " part " << k;
                }
            }
        }
    }
    kodawari_bird_world_info info{};
    ASSERT_EQ(kodawari_bird_world_get_info(c, &info), KODAWARI_OK);
    EXPECT_EQ(info.next_frame, 3 * kFrames);
    EXPECT_EQ(info.validation_messages, 0u);
    std::printf("[ measured ] flock on %s: %zu birds x %u frames, the same bits\n", info.device, birds, 3 * kFrames);
}

INSTANTIATE_TEST_SUITE_P(All, CApiParity, testing_support::all_backend_kinds(), testing_support::backend_test_name);

// kodawari.h: different handles may be used concurrently. Two worlds per kind stepped on
// two threads at once give the bits of one stepped alone.
TEST(CApiThreads, WorldsOnTwoThreadsGiveTheBitsOfOneAlone) {
    const Scene scene = load("bangs.json");
    auto built = build_rod_scene(scene);
    ASSERT_TRUE(built.ok());
    const RodScene& rods = built.value();
    std::vector<BackendKind> kinds = {BackendKind::CpuReference, BackendKind::Cpu};
    if (testing_support::no_vulkan_device_reason().empty()) kinds.push_back(BackendKind::Vulkan);
    for (const BackendKind kind : kinds) {
        const CWorld c(scene, rods, kind);
        const auto run = [&](std::vector<float>& out) {
            kodawari_chain_world* world = nullptr;
            const CFrame initial(rods.frame(0));
            if (kodawari_chain_world_create(&c.desc, &initial.frame, &world) != KODAWARI_OK) return;
            for (std::uint32_t f = 1; f <= 60; ++f) {
                const CFrame input(rods.frame(f));
                if (kodawari_chain_world_step(world, &input.frame) != KODAWARI_OK) break;
            }
            out.resize(rods.world.joint_count * 3);
            kodawari_chain_output o{};
            o.positions = out.data();
            o.positions_capacity = out.size();
            if (kodawari_chain_world_read(world, &o) != KODAWARI_OK) out.clear();
            kodawari_chain_world_destroy(world);
        };
        std::vector<float> alone, a, b;
        run(alone);
        ASSERT_FALSE(alone.empty()) << kodawari_last_error();
        std::thread ta([&] { run(a); });
        std::thread tb([&] { run(b); });
        ta.join();
        tb.join();
        EXPECT_EQ(a, alone) << backend_name(kind);
        EXPECT_EQ(b, alone) << backend_name(kind);
    }
}

// Backend choice: vulkan on a device that does not exist is KODAWARI_UNAVAILABLE with the
// reason; auto then runs on the cpu and says why.
TEST(CApiBackends, AMissingDeviceIsAnInvalidArgumentWithAutoTooAndAutoAloneFallsBack) {
    const Scene scene = load("ahoge.json");
    auto built = build_rod_scene(scene);
    ASSERT_TRUE(built.ok());
    CWorld c(scene, built.value(), BackendKind::Vulkan);
    c.desc.backend.device = "no such device anywhere";
    const CFrame initial(built.value().frame(0));
    kodawari_chain_world* world = nullptr;
    EXPECT_EQ(kodawari_chain_world_create(&c.desc, &initial.frame, &world), KODAWARI_INVALID_ARGUMENT);
    EXPECT_EQ(world, nullptr);
    const std::string message = kodawari_last_error();
    EXPECT_NE(message.find("kodawari_chain_world_create: "), std::string::npos) << message;
    std::printf("[ measured ] vulkan on a missing device: %s\n", message.c_str());

    // AUTO does not fall back from a device asked for (issue 37: `--device 7` ran on the CPU).
    c.desc.backend.backend = KODAWARI_BACKEND_AUTO;
    EXPECT_EQ(kodawari_chain_world_create(&c.desc, &initial.frame, &world), KODAWARI_INVALID_ARGUMENT);
    EXPECT_EQ(world, nullptr);

    // Without a device asked for, AUTO falls back when no device opens (no Vulkan driver).
    c.desc.backend.device = nullptr;
    std::vector<std::pair<const char*, std::optional<std::string>>> saved;
    for (const char* name : {"VK_ICD_FILENAMES", "VK_DRIVER_FILES"}) {
        const char* value = std::getenv(name);
        saved.emplace_back(name, value ? std::optional<std::string>(value) : std::nullopt);
        setenv(name, "/nonexistent.json", 1);
    }
    const kodawari_status fallback = kodawari_chain_world_create(&c.desc, &initial.frame, &world);
    for (const auto& [name, value] : saved) value ? setenv(name, value->c_str(), 1) : unsetenv(name);
    ASSERT_EQ(fallback, KODAWARI_OK) << kodawari_last_error();
    kodawari_chain_world_info info{};
    ASSERT_EQ(kodawari_chain_world_get_info(world, &info), KODAWARI_OK);
    EXPECT_EQ(info.backend, KODAWARI_BACKEND_CPU);
    EXPECT_NE(std::string(info.fallback_reason), "");
    kodawari_chain_world_destroy(world);
}

// AUTO (issue 38): on a CPU-type Vulkan device (lavapipe) the cpu backend, several times
// faster there, with the reason in the world's info; on a GPU vulkan; and a device named
// by index is obeyed whatever its type.
TEST(CApiBackends, AutoTakesTheCpuBackendOnACpuDeviceUnlessItIsNamed) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    GpuDeviceInfo best;
    if (const std::string none = testing_support::chosen_device(best); !none.empty()) FAIL() << none;
    const Scene scene = load("ahoge.json");
    auto built = build_rod_scene(scene);
    ASSERT_TRUE(built.ok());
    CWorld c(scene, built.value(), BackendKind::Vulkan);
    c.desc.backend.backend = KODAWARI_BACKEND_AUTO;
    const CFrame initial(built.value().frame(0));
    kodawari_chain_world* world = nullptr;
    ASSERT_EQ(kodawari_chain_world_create(&c.desc, &initial.frame, &world), KODAWARI_OK) << kodawari_last_error();
    kodawari_chain_world_info info{};
    ASSERT_EQ(kodawari_chain_world_get_info(world, &info), KODAWARI_OK);
    kodawari_chain_world_destroy(world);
    std::printf("[ measured ] AUTO on %s (type %s): backend %d, \"%s\"\n", best.name.c_str(), best.type.c_str(),
                static_cast<int>(info.backend), info.fallback_reason);
    if (best.type == "cpu") {
        EXPECT_EQ(info.backend, KODAWARI_BACKEND_CPU);
        EXPECT_NE(std::string(info.fallback_reason).find("is a CPU, not a GPU"), std::string::npos) << info.fallback_reason;
    } else {
        EXPECT_EQ(info.backend, KODAWARI_BACKEND_VULKAN);
        EXPECT_EQ(std::string(info.fallback_reason), "");
    }
    const std::string index = std::to_string(best.index);
    c.desc.backend.device = index.c_str();
    ASSERT_EQ(kodawari_chain_world_create(&c.desc, &initial.frame, &world), KODAWARI_OK) << kodawari_last_error();
    ASSERT_EQ(kodawari_chain_world_get_info(world, &info), KODAWARI_OK);
    kodawari_chain_world_destroy(world);
    EXPECT_EQ(info.backend, KODAWARI_BACKEND_VULKAN);
    EXPECT_EQ(std::string(info.fallback_reason), "");
}

// A bird world whose poses of one frame (64 bytes a bird) exceed the device's
// maxStorageBufferRange (lavapipe: 128 MiB, 2.1 million birds, about 0.1 GB host-side):
// VULKAN is refused as unavailable, naming the buffer and both sizes; AUTO runs it on the
// CPU and says why, as `kodawari run` does (faults_test.sh).
TEST(CApiBackends, AWorldTooLargeForTheDeviceIsUnavailableAndAutoFallsBack) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    GpuDeviceInfo best;
    if (const std::string none = testing_support::chosen_device(best); !none.empty()) FAIL() << none;
    const std::uint64_t range = best.max_storage_buffer_range;
    const std::uint64_t birds = range / sizeof(gpu::BirdPoseGpu) + 1;
    if (birds > 10'000'000) {
        GTEST_SKIP() << "this device's storage buffer range (" << range << " bytes) holds the largest world (10 million birds)";
    }
    const float points[] = {0, 20, 0, 30, 20, 0, 60, 25, 0, 90, 20, 0};
    kodawari_route_desc route{};
    route.points = points;
    route.point_count = 4;
    kodawari_flock_desc flock{};
    flock.count = static_cast<std::uint32_t>(birds);
    flock.speed = 10.0f;
    flock.frequency = 4.0f;
    flock.amplitude = 0.5f;
    kodawari_bird_world_desc desc{};
    desc.routes = &route;
    desc.route_count = 1;
    desc.flocks = &flock;
    desc.flock_count = 1;
    desc.fps = 30.0f;
    ASSERT_EQ(kodawari_flight_settings_default(&desc.flight), KODAWARI_OK) << kodawari_last_error();
    desc.backend.backend = KODAWARI_BACKEND_VULKAN;
    // The device named, so that AUTO below runs on it although it may be a CPU (issue 38).
    const std::string chosen = std::to_string(best.index);
    desc.backend.device = chosen.c_str();

    kodawari_bird_world* world = nullptr;
    EXPECT_EQ(kodawari_bird_world_create(&desc, &world), KODAWARI_UNAVAILABLE);
    EXPECT_EQ(world, nullptr);
    const std::string message = kodawari_last_error();
    const std::string sizes = "cannot hold " + std::to_string(birds) + " birds: the poses need a storage buffer of " +
                              std::to_string(birds * sizeof(gpu::BirdPoseGpu)) + " bytes";
    EXPECT_NE(message.find("kodawari_bird_world_create: "), std::string::npos) << message;
    EXPECT_NE(message.find(sizes), std::string::npos) << message;
    EXPECT_NE(message.find("the device allows " + std::to_string(range)), std::string::npos) << message;

    desc.backend.backend = KODAWARI_BACKEND_AUTO;
    ASSERT_EQ(kodawari_bird_world_create(&desc, &world), KODAWARI_OK) << kodawari_last_error();
    const std::unique_ptr<kodawari_bird_world, void (*)(kodawari_bird_world*)> owner(world, kodawari_bird_world_destroy);
    kodawari_bird_world_info info{};
    ASSERT_EQ(kodawari_bird_world_get_info(world, &info), KODAWARI_OK);
    EXPECT_EQ(info.backend, KODAWARI_BACKEND_CPU);
    EXPECT_NE(std::string(info.fallback_reason).find(sizes), std::string::npos) << info.fallback_reason;
    std::printf("[ measured ] auto, %llu birds: %s\n", static_cast<unsigned long long>(birds), info.fallback_reason);
}

namespace {

// The C description of the test application's device.
kodawari_vulkan_device_desc device_desc(const testing_support::Application& app) {
    const VulkanDeviceHandles h = app.handles();
    return {h.instance, h.physical_device, h.device, h.queue_family, h.queue_index,
            reinterpret_cast<void*>(h.get_instance_proc_addr), nullptr, h.api_version, h.frames_in_flight};
}

}  // namespace

// A whole scene recorded through the C API (kodawari_simulation_record): a flocking flock
// with a predator the application moves each frame, recorded three frames in flight on
// the application's device, is where a simulation stepped on the same device is: the next
// frame stepped from both gives the same poses, bit for bit. The pose buffer's range is
// the birds'; poses are not read from the host after a recorded frame; bad calls are
// refused naming the argument.
TEST(CApiEmbedding, RecordedScenesGiveTheStepsBits) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    testing_support::Application app;
    ASSERT_TRUE(app.ok());
    testing_support::messages = 0;
    const kodawari_vulkan_device_desc desc = device_desc(app);
    kodawari_vulkan_device* device = nullptr;
    ASSERT_EQ(kodawari_vulkan_device_adopt(&desc, &device), KODAWARI_OK) << kodawari_last_error();
    constexpr std::uint32_t kBirds = 203;
    const testing_support::TempDir dir;
    const std::string path = dir.file("capi-record-flocking.json");
    {
        std::FILE* file = std::fopen(path.c_str(), "wb");
        ASSERT_NE(file, nullptr);
        const std::string text = R"({"format": "kodawari-scene", "version": 1, "name": "capi-record", "fps": 30, "duration": 1,
            "camera": {"position": [0, 60, -160], "target": [0, 45, 0], "fov_deg": 60},
            "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 203, "seed": 5, "speed": 15,
                        "generated_route": {"seed": 7, "segments": 8, "center": [0, 45, 0], "extent": [45, 8, 45], "loop": true},
                        "formation": {"spread": [10, 5, 10]}, "flocking": {}}]})";
        std::fwrite(text.data(), 1, text.size(), file);
        std::fclose(file);
    }
    kodawari_backend_options on_app{};
    on_app.vulkan_device = device;
    kodawari_simulation* recorded = nullptr;
    kodawari_simulation* stepped = nullptr;
    ASSERT_EQ(kodawari_simulation_open(path.c_str(), &on_app, 0, &recorded), KODAWARI_OK) << kodawari_last_error();
    ASSERT_EQ(kodawari_simulation_open(path.c_str(), &on_app, 0, &stepped), KODAWARI_OK) << kodawari_last_error();
    kodawari_vulkan_device_release(device);  // the simulations hold it
    for (std::uint32_t k = 0; k < 8; ++k) {
        kodawari_flock_agent hawk{};
        ASSERT_EQ(kodawari_flock_agent_default(&hawk), KODAWARI_OK);
        hawk.position[0] = -20.0f + 5.0f * static_cast<float>(k);
        hawk.position[1] = 45.0f;
        hawk.velocity[0] = 150.0f;
        for (kodawari_simulation* sim : {recorded, stepped}) {
            ASSERT_EQ(kodawari_simulation_set_flock_agents(sim, &hawk, 1), KODAWARI_OK) << kodawari_simulation_last_error(sim);
        }
        VkCommandBuffer cmd = app.begin(k);
        ASSERT_EQ(kodawari_simulation_record(recorded, cmd), KODAWARI_OK) << kodawari_simulation_last_error(recorded);
        app.submit(k);
        ASSERT_EQ(kodawari_simulation_step(stepped, 1), KODAWARI_OK) << kodawari_simulation_last_error(stepped);
    }
    app.wait_all();
    kodawari_buffer_range range{};
    ASSERT_EQ(kodawari_simulation_buffer(recorded, KODAWARI_BUFFER_BIRD_POSES, &range), KODAWARI_OK)
        << kodawari_simulation_last_error(recorded);
    EXPECT_NE(range.buffer, 0u);
    EXPECT_EQ(range.count, kBirds);
    EXPECT_EQ(range.range, std::uint64_t{range.count} * range.stride);
    std::vector<float> local(std::size_t{kBirds} * KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS);
    const kodawari_bird_output out{local.data(), local.size(), nullptr, 0};
    EXPECT_EQ(kodawari_simulation_bird_poses(recorded, &out), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_simulation_last_error(recorded)).find("recorded"), std::string::npos);
    EXPECT_EQ(kodawari_simulation_buffer(recorded, KODAWARI_BUFFER_JOINT_MOTION, &range), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_simulation_last_error(recorded)).find("no domain has a buffer named \"chains.motion\" (they have flocking.agents, birds.poses)"),
              std::string::npos)
        << kodawari_simulation_last_error(recorded);
    EXPECT_EQ(kodawari_simulation_record(recorded, nullptr), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_simulation_last_error(recorded)).find("command_buffer"), std::string::npos);

    std::vector<float> other(local.size());
    const kodawari_bird_output out_other{other.data(), other.size(), nullptr, 0};
    ASSERT_EQ(kodawari_simulation_step(recorded, 1), KODAWARI_OK) << kodawari_simulation_last_error(recorded);
    ASSERT_EQ(kodawari_simulation_step(stepped, 1), KODAWARI_OK) << kodawari_simulation_last_error(stepped);
    ASSERT_EQ(kodawari_simulation_bird_poses(recorded, &out), KODAWARI_OK) << kodawari_simulation_last_error(recorded);
    ASSERT_EQ(kodawari_simulation_bird_poses(stepped, &out_other), KODAWARI_OK);
    EXPECT_EQ(std::memcmp(local.data(), other.data(), local.size() * sizeof(float)), 0) << "recorded and stepped part";
    kodawari_simulation_info info{};
    ASSERT_EQ(kodawari_simulation_get_info(recorded, &info), KODAWARI_OK);
    EXPECT_EQ(info.next_frame, 9u);
    EXPECT_EQ(info.validation_messages, 0u);

    // A simulation on a device of the module's own cannot record.
    kodawari_backend_options own{};
    own.backend = KODAWARI_BACKEND_VULKAN;
    kodawari_simulation* alone = nullptr;
    ASSERT_EQ(kodawari_simulation_open(path.c_str(), &own, 0, &alone), KODAWARI_OK) << kodawari_last_error();
    VkCommandBuffer cmd = app.begin(9);
    EXPECT_EQ(kodawari_simulation_record(alone, cmd), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_simulation_last_error(alone)).find("vulkan_device"), std::string::npos);
    // Nor take agents on the device, which record() alone reads (step() refuses them).
    EXPECT_EQ(kodawari_simulation_set_flock_device_agents(alone, 3), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_simulation_last_error(alone)).find("vulkan_device"), std::string::npos)
        << kodawari_simulation_last_error(alone);
    EXPECT_EQ(kodawari_simulation_set_flock_device_agents(alone, 0), KODAWARI_OK);
    app.submit(9);
    app.wait_all();
    kodawari_simulation_destroy(alone);
    kodawari_simulation_destroy(stepped);
    kodawari_simulation_destroy(recorded);
    EXPECT_EQ(testing_support::messages, 0u);
}

// The C API on the application's own device (kodawari.h, "Device embedding"): the crowd's
// chains recorded into the application's command buffers three frames in flight give the
// bits of kodawari_chain_world_step on a world of the module's own device; the buffer
// ranges name the module's buffers; bad calls are refused naming the argument.
TEST(CApiEmbedding, RecordedStepsOnTheApplicationsDeviceGiveTheStepsBits) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    testing_support::Application app;
    ASSERT_TRUE(app.ok());
    testing_support::messages = 0;
    const kodawari_vulkan_device_desc desc = device_desc(app);
    kodawari_vulkan_device* device = nullptr;
    ASSERT_EQ(kodawari_vulkan_device_adopt(&desc, &device), KODAWARI_OK) << kodawari_last_error();

    Scene scene = load("crowd.json");
    scene.crowds[0].count = 13;  // 104 chains: a full workgroup of 64 and a partial one
    auto built = build_rod_scene(scene);
    ASSERT_TRUE(built.ok()) << built.error().message;
    const RodScene& rods = built.value();
    CWorld embedded(scene, rods, BackendKind::Vulkan);
    embedded.desc.backend.validation = 0;
    embedded.desc.backend.vulkan_device = device;
    CWorld own(scene, rods, BackendKind::Vulkan);
    rods::RodFrame frame = rods.frame(0);
    const CFrame initial(frame);
    kodawari_chain_world* a = nullptr;
    kodawari_chain_world* b = nullptr;
    ASSERT_EQ(kodawari_chain_world_create(&embedded.desc, &initial.frame, &a), KODAWARI_OK) << kodawari_last_error();
    ASSERT_EQ(kodawari_chain_world_create(&own.desc, &initial.frame, &b), KODAWARI_OK) << kodawari_last_error();
    // The worlds hold the device: the wrapper can go now.
    kodawari_vulkan_device_release(device);

    for (std::uint32_t k = 1; k <= 9; ++k) {
        rods.frame(k, frame);
        const CFrame input(frame);
        VkCommandBuffer cmd = app.begin(k);
        ASSERT_EQ(kodawari_chain_world_record_step(a, cmd, &input.frame), KODAWARI_OK) << kodawari_last_error();
        app.submit(k);
        ASSERT_EQ(kodawari_chain_world_step(b, &input.frame), KODAWARI_OK) << kodawari_last_error();
    }
    app.wait_all();
    CRead ra(rods.world.joint_count, rods.world.chains.size()), rb(rods.world.joint_count, rods.world.chains.size());
    ASSERT_EQ(ra.read(a), KODAWARI_OK) << kodawari_last_error();
    ASSERT_EQ(rb.read(b), KODAWARI_OK) << kodawari_last_error();
    EXPECT_EQ(std::memcmp(ra.positions.data(), rb.positions.data(), ra.positions.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(ra.orientations.data(), rb.orientations.data(), ra.orientations.size() * sizeof(float)), 0);

    kodawari_buffer_range range{};
    ASSERT_EQ(kodawari_chain_world_buffer(a, KODAWARI_BUFFER_JOINT_MOTION, &range), KODAWARI_OK) << kodawari_last_error();
    EXPECT_NE(range.buffer, 0u);
    EXPECT_EQ(range.count, rods.world.joint_count);
    EXPECT_EQ(range.stride, 32u);  // RodJointMotionGpu: x, v
    EXPECT_EQ(range.range, std::uint64_t{range.count} * range.stride);
    EXPECT_EQ(kodawari_chain_world_buffer(a, KODAWARI_BUFFER_BIRD_POSES, &range), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_last_error()).find("which"), std::string::npos) << kodawari_last_error();

    // Bad calls: named, nothing recorded, the world unchanged.
    const CFrame input(frame);
    EXPECT_EQ(kodawari_chain_world_record_step(a, nullptr, &input.frame), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_last_error()).find("command_buffer"), std::string::npos) << kodawari_last_error();
    CWorld cpu(scene, rods, BackendKind::Cpu);
    kodawari_chain_world* c = nullptr;
    ASSERT_EQ(kodawari_chain_world_create(&cpu.desc, &initial.frame, &c), KODAWARI_OK) << kodawari_last_error();
    VkCommandBuffer cmd = app.begin(10);
    EXPECT_EQ(kodawari_chain_world_record_step(c, cmd, &input.frame), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_last_error()).find("vulkan"), std::string::npos) << kodawari_last_error();
    EXPECT_EQ(kodawari_chain_world_buffer(c, KODAWARI_BUFFER_JOINT_MOTION, &range), KODAWARI_INVALID_ARGUMENT);
    app.submit(10);
    app.wait_all();
    CRead after(rods.world.joint_count, rods.world.chains.size());
    ASSERT_EQ(after.read(a), KODAWARI_OK);
    EXPECT_EQ(std::memcmp(after.positions.data(), ra.positions.data(), ra.positions.size() * sizeof(float)), 0);

    kodawari_vulkan_device_desc bad = desc;
    bad.device = nullptr;
    kodawari_vulkan_device* none = nullptr;
    EXPECT_EQ(kodawari_vulkan_device_adopt(&bad, &none), KODAWARI_INVALID_ARGUMENT);
    EXPECT_EQ(none, nullptr);
    EXPECT_NE(std::string(kodawari_last_error()).find("desc->device is null"), std::string::npos) << kodawari_last_error();
    kodawari_backend_options cpu_on_device = own.desc.backend;
    cpu_on_device.backend = KODAWARI_BACKEND_CPU;
    cpu_on_device.validation = 0;
    cpu_on_device.vulkan_device = reinterpret_cast<kodawari_vulkan_device*>(&bad);  // never dereferenced: refused first
    kodawari_chain_world_desc cpu_desc = own.desc;
    cpu_desc.backend = cpu_on_device;
    kodawari_chain_world* refused = nullptr;
    EXPECT_EQ(kodawari_chain_world_create(&cpu_desc, &initial.frame, &refused), KODAWARI_INVALID_ARGUMENT);
    EXPECT_NE(std::string(kodawari_last_error()).find("vulkan_device"), std::string::npos) << kodawari_last_error();

    kodawari_chain_world_destroy(c);
    kodawari_chain_world_destroy(b);
    kodawari_chain_world_destroy(a);  // the last holder of the adopted device
    EXPECT_EQ(testing_support::messages, 0u);
}
