// The scene's own domains through the embedding contract (kodawari/simulation/domain.hpp,
// issue 31): chains and flocking flocks recorded frame by frame into an application's
// command buffers (its own instance and device, adopted) are what step() gives on the same
// device, bit for bit. test_domain_contract.cpp runs a domain of the test's own the same
// way. Public headers only, as there.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include <kodawari/shared/birds.h>
#include <kodawari/shared/rods.h>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "domains/app_device.hpp"
#include "test_support.hpp"

using namespace kodawari;

namespace {

// The scene's own domains record too: the chains of a scene recorded frame by frame into
// the application's command buffers are the chains step() gives on the same device.
TEST(DomainContract, TheScenesDomainsRecordAsTheyStep) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    testing_support::AppDevice app;
    ASSERT_TRUE(app.ok());
    auto device = adopt_vulkan_device(app.handles());
    ASSERT_TRUE(device.ok()) << device.error().message;
    SimulationOptions options;
    options.backend = BackendKind::Vulkan;
    options.options.context = device.value();
    options.frames = 8;
    const std::string scene = std::string(KODAWARI_SOURCE_DIR) + "/scenes/ponytail.json";
    auto recorded = Simulation::open(scene, options);
    auto stepped = Simulation::open(scene, options);
    ASSERT_TRUE(recorded.ok() && stepped.ok());
    for (std::uint32_t k = 0; k < 8; ++k) {
        VkCommandBuffer cmd = app.begin(k);
        ASSERT_TRUE(recorded.value()->record(cmd).ok());
        app.submit(k);
    }
    app.wait_all();
    ASSERT_TRUE(stepped.value()->step(8).ok());
    // No application device at all: a Simulation on a device of the module's own
    // (open_shared_device) records each frame into a recording of the module's queue,
    // submitted and waited for by the caller: the same chains.
    auto own_device = open_shared_device(testing_support::gpu_options());
    ASSERT_TRUE(own_device.ok()) << own_device.error().message;
    SimulationOptions own = options;
    own.options = testing_support::gpu_options();
    own.options.context = own_device.value();
    auto queued = Simulation::open(scene, own);
    ASSERT_TRUE(queued.ok()) << queued.error().message;
    const compute::Queue queue(*own_device.value());
    for (std::uint32_t k = 0; k < 8; ++k) {
        auto recording = queue.begin();
        ASSERT_TRUE(recording.ok()) << recording.error().message;
        const auto made = queued.value()->record(recording.value());
        ASSERT_TRUE(made.ok()) << made.error().message;
        auto submission = queue.submit(std::move(recording).value());
        ASSERT_TRUE(submission.ok()) << submission.error().message;
        ASSERT_TRUE(submission.value().wait().ok());
    }
    ChainSnapshot a, b, c;
    ASSERT_TRUE(read_chains(*recorded.value(), a).ok());
    ASSERT_TRUE(read_chains(*stepped.value(), b).ok());
    ASSERT_TRUE(read_chains(*queued.value(), c).ok());
    ASSERT_FALSE(a.positions.empty());
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(c.positions.size(), b.positions.size());
    EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(glm::vec3)), 0);
    EXPECT_EQ(std::memcmp(c.positions.data(), b.positions.data(), c.positions.size() * sizeof(glm::vec3)), 0);
    EXPECT_EQ(queued.value()->validation_messages(), 0u);
    // Where the application binds them: the joints' motion, one RodJointMotionGpu each.
    auto motion = recorded.value()->buffer(rod_buffers::motion);
    ASSERT_TRUE(motion.ok()) << motion.error().message;
    EXPECT_EQ(motion.value().count, a.positions.size());
    EXPECT_EQ(motion.value().stride, sizeof(gpu::RodJointMotionGpu));
    auto states = recorded.value()->buffer(rod_buffers::chain_states);
    ASSERT_TRUE(states.ok()) << states.error().message;
    EXPECT_EQ(states.value().stride, sizeof(gpu::RodChainStateGpu));
    EXPECT_FALSE(recorded.value()->buffer(rod_buffers::colliders).ok());  // an input, not handed out
    EXPECT_FALSE(recorded.value()->buffer(bird_buffers::poses).ok());    // no birds
    EXPECT_EQ(app.messages(), 0u);
}

// The flocking tests' scene: 301 birds (not a multiple of the 64- or 256-wide
// workgroups), 2 substeps a frame at 30 fps, and a scene predator; opened on `kind`, on
// the application's device `device` for vulkan.
namespace {

constexpr std::uint32_t kFlockingBirds = 301;
Result<std::unique_ptr<Simulation>> open_flocking(BackendKind kind, const std::shared_ptr<compute::Device>& device) {
    const std::string text = R"({"format": "kodawari-scene", "version": 1, "name": "flocking-record", "fps": 30, "duration": 1,
        "camera": {"position": [0, 60, -160], "target": [0, 45, 0], "fov_deg": 60},
        "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 301, "seed": 2024, "speed": 15,
                    "generated_route": {"seed": 7, "segments": 8, "center": [0, 45, 0], "extent": [45, 8, 45], "loop": true},
                    "formation": {"spread": [14, 6, 14]},
                    "flocking": {"predators": [{"from": [-40, 45, 0], "to": [40, 45, 0], "start": 0.1, "speed": 20,
                                                "radius": 20, "weight": 60}]}}]})";
    SimulationOptions options;
    options.backend = kind;
    if (kind == BackendKind::Vulkan) options.options.context = device;
    auto scene = parse_scene(text, "flocking-record.json");
    if (!scene) return scene.error();
    return Simulation::create(std::move(scene).value(), options);
}

// A moving predator of the application's, frame k's.
FlockAgent hawk_at(std::uint32_t k) {
    FlockAgent hawk;
    hawk.position = {-30.0f + 6.0f * static_cast<float>(k), 45.0f, 4.0f};
    hawk.velocity = {180.0f, 0.0f, 0.0f};
    hawk.radius = 25.0f;
    return hawk;
}

}  // namespace

// A scene with a flocking flock records too: the flocking step (its grid and rules) and
// the birds it drives go into the application's command buffers frame by frame, the
// frame's inputs (the flock's route leader, the scene's predator, a predator the
// application moves every frame) through staging rings, the motion never read back.
// From the state recorded that way the next frame step()s to the same bits as a run
// stepped all along on the same device: flocks and birds recorded exactly as stepped.
// A third run has the application write its predator on its device
// (set_flock_device_agents): each frame it copies the encoded predator into the range
// flock_buffers::agents hands out, in its own command buffer before record(), as a kernel
// of its would write it; that flock flies the bits of the host arrays' too, with the
// validation layer and synchronization validation silent. step() is refused while the
// agents are on the device.
TEST(DomainContract, FlockingRecordsAsItSteps) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    testing_support::AppDevice app;
    ASSERT_TRUE(app.ok());
    auto device = adopt_vulkan_device(app.handles());
    ASSERT_TRUE(device.ok()) << device.error().message;
    constexpr std::uint32_t kBirds = kFlockingBirds, kFrames = 10;
    auto recorded = open_flocking(BackendKind::Vulkan, device.value());
    auto stepped = open_flocking(BackendKind::Vulkan, device.value());
    auto on_device = open_flocking(BackendKind::Vulkan, device.value());
    for (auto* made : {&recorded, &stepped, &on_device}) ASSERT_TRUE(made->ok()) << made->error().message;
    ASSERT_TRUE(set_flock_device_agents(*on_device.value(), 1).ok());
    auto range = on_device.value()->buffer(flock_buffers::agents);
    ASSERT_TRUE(range.ok()) << range.error().message;
    EXPECT_EQ(range.value().count, kMaxFlockAgents);
    EXPECT_EQ(range.value().stride, sizeof(gpu::FlockAgentGpu));
    EXPECT_EQ(range.value().offset, sizeof(gpu::FlockAgentGpu));  // after the scene's one predator
    for (std::uint32_t k = 0; k < kFrames; ++k) {
        const FlockAgent hawk = hawk_at(k);
        ASSERT_TRUE(set_flock_agents(*recorded.value(), std::span(&hawk, 1)).ok());
        ASSERT_TRUE(set_flock_agents(*stepped.value(), std::span(&hawk, 1)).ok());
        auto encoded = encode_flock_agent(hawk);
        ASSERT_TRUE(encoded.ok()) << encoded.error().message;
        VkCommandBuffer cmd = app.begin(k);
        const auto made = recorded.value()->record(cmd);
        ASSERT_TRUE(made.ok()) << made.error().message;
        // After the previous frame's step read the buffer, the application writes it.
        app.write_buffer(cmd, range.value().buffer, range.value().offset, &encoded.value(), sizeof(gpu::FlockAgentGpu));
        const auto made_on_device = on_device.value()->record(cmd);
        ASSERT_TRUE(made_on_device.ok()) << made_on_device.error().message;
        app.submit(k);
        ASSERT_TRUE(stepped.value()->step(1).ok());
    }
    app.wait_all();
    EXPECT_EQ(recorded.value()->frame(), kFrames - 1);
    auto pose_range = recorded.value()->buffer(bird_buffers::poses);
    ASSERT_TRUE(pose_range.ok()) << pose_range.error().message;
    EXPECT_EQ(pose_range.value().count, kBirds);
    EXPECT_EQ(pose_range.value().stride, sizeof(gpu::BirdPoseGpu));
    // step() cannot see the device's agents: refused until they are removed.
    const auto refused = on_device.value()->step(1);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("set_flock_device_agents(sim, 0)"), std::string::npos) << refused.error().message;
    ASSERT_TRUE(set_flock_device_agents(*on_device.value(), 0).ok());
    std::vector<gpu::BirdPose> a(kBirds), b(kBirds), c(kBirds);
    std::vector<gpu::BirdMotionGpu> ma(kBirds), mb(kBirds), mc(kBirds);
    for (auto [sim, poses, motion] : {std::tuple(recorded.value().get(), &a, &ma), std::tuple(stepped.value().get(), &b, &mb),
                                      std::tuple(on_device.value().get(), &c, &mc)}) {
        const ChannelOutput out[] = {{kBirdPosesChannel, std::as_writable_bytes(std::span(*poses))},
                                     {kFlockingMotionChannel, std::as_writable_bytes(std::span(*motion))}};
        ASSERT_TRUE(sim->step(1, out).ok());
    }
    EXPECT_EQ(std::memcmp(ma.data(), mb.data(), ma.size() * sizeof(gpu::BirdMotionGpu)), 0) << "the flocks' state";
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(gpu::BirdPose)), 0) << "the birds' poses";
    EXPECT_EQ(std::memcmp(mc.data(), mb.data(), mc.size() * sizeof(gpu::BirdMotionGpu)), 0) << "the flock of agents on the device";
    EXPECT_EQ(std::memcmp(c.data(), b.data(), c.size() * sizeof(gpu::BirdPose)), 0) << "the birds of agents on the device";
    EXPECT_EQ(app.messages(), 0u);
    EXPECT_EQ(recorded.value()->validation_messages(), 0u);
}

// Agents on the device, refused naming what is wrong: past 64, on a CPU backend (which
// hands out no buffer), and an agent out of range given to encode_flock_agent.
TEST(DomainContract, FlockingDeviceAgentsAreRefusedWhereTheyCannotBe) {
    auto cpu = open_flocking(BackendKind::Cpu, nullptr);
    ASSERT_TRUE(cpu.ok()) << cpu.error().message;
    const auto many = set_flock_device_agents(*cpu.value(), kMaxFlockAgents + 1);
    ASSERT_FALSE(many.ok());
    EXPECT_NE(many.error().message.find("count: 65 agents; at most 64"), std::string::npos) << many.error().message;
    const auto on_cpu = set_flock_device_agents(*cpu.value(), 1);
    ASSERT_FALSE(on_cpu.ok());
    EXPECT_NE(on_cpu.error().message.find("need the vulkan backend"), std::string::npos) << on_cpu.error().message;
    EXPECT_TRUE(set_flock_device_agents(*cpu.value(), 0).ok());
    EXPECT_FALSE(cpu.value()->buffer(flock_buffers::agents).ok());
    FlockAgent bad;
    bad.radius = -1.0f;
    const auto unencoded = encode_flock_agent(bad);
    ASSERT_FALSE(unencoded.ok());
    EXPECT_NE(unencoded.error().message.find("encode_flock_agent: agent.radius"), std::string::npos) << unencoded.error().message;
}

}  // namespace
