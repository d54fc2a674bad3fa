// The vulkan kernels' workgroup size (BackendOptions::workgroup_size, issue 38 item 2): a
// variant a GPU run times side by side (`bench --workgroup-sizes`), never a change of
// result. Every kernel that runs one instance per invocation (chains, birds, characters'
// clips, flocking birds) gives the same bits at 32, 64 (the default) and 256 invocations
// per workgroup, on instance counts that fill none of them; a size that is no power of
// two, or past the device's limit, is refused naming the option. Lavapipe where there is
// no GPU, with validation on (ctest sets KODAWARI_VALIDATION=1).
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/backends/pose_backend.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

constexpr unsigned kSizes[] = {32, 64, 256};

std::string scene_path(const char* name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

BackendOptions at_size(unsigned size) {
    BackendOptions o = testing_support::gpu_options();
    o.workgroup_size = size;
    return o;
}

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

class WorkgroupSizes : public ::testing::Test {
protected:
    void SetUp() override {
        if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    }
};

// A flocking flock of 1 001 birds (a multiple of no workgroup size), as
// tests/flocking/test_flocking.cpp flies them.
std::string flocking_scene() {
    return R"({"format": "kodawari-scene", "version": 1, "name": "workgroups", "fps": 60, "duration": 1,
               "camera": {"position": [0, 60, -160], "target": [0, 45, 0], "fov_deg": 60},
               "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 1001, "seed": 2024, "speed": 15,
                           "generated_route": {"seed": 7, "segments": 8, "center": [0, 45, 0], "extent": [45, 8, 45], "loop": true},
                           "formation": {"spread": [14, 6, 14]}, "flocking": {}}]})";
}

}  // namespace

// 203 synthetic chains of 6 joints with colliders: the rod kernel (rods_step.comp). Short
// chains and one view keep the three pipelines quick for lavapipe to compile.
TEST_F(WorkgroupSizes, ChainsAreTheSameBitsAtEverySize) {
    rods::SyntheticOptions options;
    options.chains = 203;
    options.joints = 6;
    // Two templates of about 100 chains: each of the rod kernel's dispatches (one per
    // template) spans several workgroups at every size but 256.
    options.chains_per_character = 2;
    options.views = 1;
    options.colliders = true;
    auto scene = rods::SyntheticScene::make(options);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    std::vector<std::vector<glm::vec3>> positions;
    for (const unsigned size : kSizes) {
        auto backend = make_rod_backend(BackendKind::Vulkan, at_size(size));
        ASSERT_TRUE(backend.ok()) << backend.error().message;
        rods::RodFrame frame;
        scene.value().frame(0, 1.0f / 60.0f, frame);
        ASSERT_TRUE(backend.value()->load(scene.value().world(), frame).ok());
        for (std::uint32_t f = 1; f <= 10; ++f) {
            scene.value().frame(f, 1.0f / 60.0f, frame);
            ASSERT_TRUE(backend.value()->step(frame).ok());
        }
        ChainSnapshot snap;
        ASSERT_TRUE(backend.value()->read(snap).ok());
        positions.push_back(snap.positions);
        EXPECT_EQ(backend.value()->validation_messages(), 0u);
    }
    ASSERT_FALSE(positions[0].empty());
    EXPECT_TRUE(same_bits(positions[0], positions[1])) << "32 against 64 invocations";
    EXPECT_TRUE(same_bits(positions[2], positions[1])) << "256 against 64 invocations";
}

// flock.json's 270 birds: the wingbeat kernel (birds_flap.comp).
TEST_F(WorkgroupSizes, BirdsAreTheSameBitsAtEverySize) {
    std::vector<std::vector<gpu::BirdPose>> poses;
    for (const unsigned size : kSizes) {
        auto sim = Simulation::open(scene_path("flock.json"), {.backend = BackendKind::Vulkan, .options = at_size(size), .frames = 6});
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        const std::size_t birds = bird_world(*sim.value()).birds.size();
        ASSERT_NE(birds % 32, 0u) << "the flock must leave a workgroup partly empty";
        std::vector<gpu::BirdPose> out(6 * birds);
        ASSERT_TRUE(step_birds(*sim.value(), 6, out).ok());
        poses.push_back(std::move(out));
        EXPECT_EQ(sim.value()->validation_messages(), 0u);
    }
    EXPECT_TRUE(same_bits(poses[0], poses[1])) << "32 against 64 invocations";
    EXPECT_TRUE(same_bits(poses[2], poses[1])) << "256 against 64 invocations";
}

// 203 instances of the chibi, most playing its clips at staggered times: the clip
// evaluator (pose_eval.comp).
TEST_F(WorkgroupSizes, CharactersAreTheSameBitsAtEverySize) {
    auto character = gltf::load_character(scene_path("characters/chibi.glb"));
    ASSERT_TRUE(character.ok()) << character.error().message;
    const animation::Character& c = character.value();
    ASSERT_FALSE(c.animations.empty());
    std::vector<PoseInstance> instances(203);
    for (std::size_t i = 0; i < instances.size(); ++i) {
        instances[i].placement.position = glm::vec3(static_cast<float>(i % 17), 0.0f, static_cast<float>(i / 17));
        instances[i].clip = i % 11 == 0 ? -1 : static_cast<std::int32_t>(i % c.animations.size());
        instances[i].time_offset = 0.037f * static_cast<float>(i);
    }
    std::vector<std::vector<glm::mat4>> world;
    for (const unsigned size : kSizes) {
        auto backend = make_pose_backend(BackendKind::Vulkan, at_size(size));
        ASSERT_TRUE(backend.ok()) << backend.error().message;
        ASSERT_TRUE(backend.value()->load(c, instances).ok());
        std::vector<glm::mat4> all, at;
        for (const float t : {0.0f, 0.41f, 1.73f}) {
            ASSERT_TRUE(backend.value()->evaluate(t).ok());
            ASSERT_TRUE(backend.value()->read(at).ok());
            all.insert(all.end(), at.begin(), at.end());
        }
        world.push_back(std::move(all));
        EXPECT_EQ(backend.value()->validation_messages(), 0u);
    }
    ASSERT_FALSE(world[0].empty());
    EXPECT_TRUE(same_bits(world[0], world[1])) << "32 against 64 invocations";
    EXPECT_TRUE(same_bits(world[2], world[1])) << "256 against 64 invocations";
}

// 1 001 flocking birds: the flocking step (flock_step.comp), whose motion the wingbeats fly.
TEST_F(WorkgroupSizes, FlockingIsTheSameBitsAtEverySize) {
    std::vector<std::vector<gpu::BirdPose>> poses;
    for (const unsigned size : kSizes) {
        auto scene = parse_scene(flocking_scene(), "workgroups.json");
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        auto sim = Simulation::create(std::move(scene).value(), {.backend = BackendKind::Vulkan, .options = at_size(size)});
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        std::vector<gpu::BirdPose> out(4 * 1001);
        ASSERT_TRUE(step_birds(*sim.value(), 4, out).ok());
        poses.push_back(std::move(out));
        EXPECT_EQ(sim.value()->validation_messages(), 0u);
    }
    EXPECT_TRUE(same_bits(poses[0], poses[1])) << "32 against 64 invocations";
    EXPECT_TRUE(same_bits(poses[2], poses[1])) << "256 against 64 invocations";
}

// A size that is no power of two, below 32, or past 1024 is refused by every vulkan
// factory and by Simulation, naming the option and the size.
TEST_F(WorkgroupSizes, AnyOtherSizeIsRefusedNamingTheOption) {
    for (const unsigned size : {16u, 48u, 96u, 2048u}) {
        SCOPED_TRACE("workgroup_size " + std::to_string(size));
        auto rods = make_rod_backend(BackendKind::Vulkan, at_size(size));
        ASSERT_FALSE(rods.ok());
        EXPECT_EQ(rods.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(rods.error().message.find("BackendOptions::workgroup_size: " + std::to_string(size)), std::string::npos)
            << rods.error().message;
        auto birds = make_bird_backend(BackendKind::Vulkan, at_size(size));
        ASSERT_FALSE(birds.ok());
        EXPECT_EQ(birds.error().kind, Error::Kind::InvalidInput);
        auto poses = make_pose_backend(BackendKind::Vulkan, at_size(size));
        ASSERT_FALSE(poses.ok());
        EXPECT_EQ(poses.error().kind, Error::Kind::InvalidInput);
        auto sim = Simulation::open(scene_path("flock.json"), {.backend = BackendKind::Vulkan, .options = at_size(size), .frames = 2});
        ASSERT_FALSE(sim.ok());
        EXPECT_NE(sim.error().message.find("workgroup_size"), std::string::npos) << sim.error().message;
    }
    // The cpu kinds have no workgroups: the option is theirs to ignore.
    auto cpu = make_rod_backend(BackendKind::Cpu, at_size(48));
    EXPECT_TRUE(cpu.ok());
}
