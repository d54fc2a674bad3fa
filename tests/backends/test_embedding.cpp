// Kodawari on an application's own Vulkan device and command buffers (issue 11,
// kodawari/vulkan/vulkan_embed.hpp), black-box: the test plays the application, with its own
// instance, device, command pool and fences (validation with synchronization validation on
// when ctest asks for it), and checks that
//   - steps recorded into its command buffers give the very bits step() gives on a device
//     of the module's own, with several frames in flight;
//   - every entry point rejects bad arguments with a message naming them, and a rejected
//     call leaves the backend as it was;
//   - the module destroys nothing of the application's.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <array>
#include <cstring>
#include <vector>

#include <limits>

#include <vulkan/vulkan.h>

#include <kodawari/shared/rods.h>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "small_flock.hpp"
#include "test_support.hpp"
#include "vulkan_app_support.hpp"

using namespace kodawari;
using kodawari::testing_support::Application;
using kodawari::testing_support::messages;

namespace {

class Embedding : public ::testing::Test {
protected:
    void SetUp() override {
        if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
        app_ = std::make_unique<Application>();
        ASSERT_TRUE(app_->ok()) << "the test's own Vulkan device could not be created";
        messages = 0;
    }
    std::unique_ptr<Application> app_;
};

// 101 chains (not a multiple of the kernel's 64), 9 joints, views and a collider.
rods::SyntheticScene scene() {
    auto made = rods::SyntheticScene::make({.chains = 101, .joints = 9, .iterations = 3, .chains_per_character = 6, .views = 3});
    EXPECT_TRUE(made.ok());
    return std::move(made).value();
}

void expect_same_bits(const std::vector<rods::ChainState>& a, const std::vector<rods::ChainState>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t c = 0; c < a.size(); ++c) {
        ASSERT_EQ(std::memcmp(&a[c].x, &b[c].x, sizeof(a[c].x)), 0) << "chain " << c << " positions";
        ASSERT_EQ(std::memcmp(&a[c].q, &b[c].q, sizeof(a[c].q)), 0) << "chain " << c << " orientations";
        ASSERT_EQ(std::memcmp(&a[c].v, &b[c].v, sizeof(a[c].v)), 0) << "chain " << c << " velocities";
    }
}

TEST_F(Embedding, RecordedStepsInFlightGiveTheBitsOfStep) {
    const rods::SyntheticScene synthetic = scene();
    constexpr float dt = 1.0f / 60.0f;
    rods::RodFrame frame;
    synthetic.frame(0, dt, frame);

    auto device = adopt_vulkan_device(app_->handles());
    ASSERT_TRUE(device.ok()) << device.error().message;
    BackendOptions embedded;
    embedded.context = device.value();
    auto rods = make_rod_backend(BackendKind::Vulkan, embedded);
    ASSERT_TRUE(rods.ok()) << rods.error().message;
    ASSERT_TRUE(rods.value()->load(synthetic.world(), frame).ok());
    auto own = make_rod_backend(BackendKind::Vulkan, testing_support::gpu_options());
    ASSERT_TRUE(own.ok()) << own.error().message;
    ASSERT_TRUE(own.value()->load(synthetic.world(), frame).ok());

    // 10 frames recorded three in flight, against 10 steps; a dt change at frame 6 (the
    // templates' step sizes go through the ring too).
    constexpr std::uint32_t kFrames = 10;
    for (std::uint32_t k = 1; k <= kFrames; ++k) {
        synthetic.frame(k, dt, frame);
        if (k >= 6) frame.dt = 1.0f / 30.0f;
        VkCommandBuffer cmd = app_->begin(k);
        const auto recorded = record_step(*rods.value(), cmd, frame);
        ASSERT_TRUE(recorded.ok()) << recorded.error().message;
        app_->submit(k);
        ASSERT_TRUE(own.value()->step(frame).ok());
    }
    app_->wait_all();
    std::vector<rods::ChainState> a, b;
    ASSERT_TRUE(rods.value()->read_states(a).ok());
    ASSERT_TRUE(own.value()->read_states(b).ok());
    expect_same_bits(a, b);

    // The output ranges name the module's buffers with the shared structs' strides.
    const auto motion = vulkan_buffer(*rods.value()->device_data(), rod_buffers::motion);
    ASSERT_TRUE(motion.ok()) << motion.error().message;
    EXPECT_NE(motion.value().buffer, VK_NULL_HANDLE);
    EXPECT_EQ(motion.value().count, synthetic.world().joint_count);
    EXPECT_EQ(motion.value().stride, sizeof(gpu::RodJointMotionGpu));
    EXPECT_EQ(motion.value().range, VkDeviceSize{motion.value().count} * motion.value().stride);
    EXPECT_FALSE(vulkan_buffer(*rods.value()->device_data(), bird_buffers::poses).ok());
    EXPECT_EQ(messages, 0u);
}

// The record calls into a compute::Recording of the module's own queue (no Vulkan code in
// the caller): a chains' frame and a flock's frame recorded together submit once and give
// step()'s and simulate()'s bits; a recording of another device is refused by name, the
// backend unchanged. 37 birds, 101 chains: neither a multiple of the workgroup size.
TEST_F(Embedding, BackendsRecordIntoOneRecordingOfTheModulesQueue) {
    const rods::SyntheticScene synthetic = scene();
    constexpr float dt = 1.0f / 60.0f;
    rods::RodFrame frame;
    synthetic.frame(0, dt, frame);
    const birds::BirdWorld flock = testing_support::small_flock();

    auto opened = open_shared_device(testing_support::gpu_options());
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    compute::Device& device = *opened.value();
    BackendOptions shared = testing_support::gpu_options();
    shared.context = opened.value();
    auto rods = std::move(make_rod_backend(BackendKind::Vulkan, shared)).value();
    auto birds = std::move(make_bird_backend(BackendKind::Vulkan, shared)).value();
    auto stepped = std::move(make_rod_backend(BackendKind::Vulkan, testing_support::gpu_options())).value();
    auto simulated = std::move(make_bird_backend(BackendKind::Vulkan, testing_support::gpu_options())).value();
    ASSERT_TRUE(rods->load(synthetic.world(), frame).ok());
    ASSERT_TRUE(stepped->load(synthetic.world(), frame).ok());
    ASSERT_TRUE(birds->load(flock).ok());
    ASSERT_TRUE(simulated->load(flock).ok());

    const compute::Queue queue(device);
    for (std::uint32_t k = 1; k <= 5; ++k) {
        synthetic.frame(k, dt, frame);
        ASSERT_TRUE(stepped->step(frame).ok());
        ASSERT_TRUE(simulated->simulate(1, {}).ok());
        const std::uint64_t before = device.submissions();
        auto recording = queue.begin();
        ASSERT_TRUE(recording.ok()) << recording.error().message;
        const auto chains = record_step(*rods, recording.value(), frame);
        ASSERT_TRUE(chains.ok()) << chains.error().message;
        const auto flew = record_simulate(*birds, recording.value(), 1);
        ASSERT_TRUE(flew.ok()) << flew.error().message;
        EXPECT_EQ(device.submissions(), before) << "recording submitted work (frame " << k << ")";
        auto submission = queue.submit(std::move(recording).value());
        ASSERT_TRUE(submission.ok()) << submission.error().message;
        ASSERT_TRUE(submission.value().wait().ok());
        EXPECT_EQ(device.submissions(), before + 1) << "one submission for both backends (frame " << k << ")";
    }
    std::vector<rods::ChainState> a, b;
    ASSERT_TRUE(rods->read_states(a).ok());
    ASSERT_TRUE(stepped->read_states(b).ok());
    expect_same_bits(a, b);
    // The flocks' states agree too: their next frame is the same poses.
    std::vector<gpu::BirdPose> recorded_poses(flock.birds.size()), simulated_poses(flock.birds.size());
    ASSERT_TRUE(birds->simulate(1, {recorded_poses, {}}).ok());
    ASSERT_TRUE(simulated->simulate(1, {simulated_poses, {}}).ok());
    EXPECT_EQ(std::memcmp(recorded_poses.data(), simulated_poses.data(), recorded_poses.size() * sizeof(gpu::BirdPose)), 0);

    // A recording of the application's device is not the backends': refused, naming it,
    // and nothing recorded (the state is the last frame's).
    auto adopted = adopt_vulkan_device(app_->handles());
    ASSERT_TRUE(adopted.ok()) << adopted.error().message;
    VkCommandBuffer cmd = app_->begin(1);
    auto foreign = borrow_command_buffer(*adopted.value(), cmd);
    ASSERT_TRUE(foreign.ok()) << foreign.error().message;
    synthetic.frame(6, dt, frame);
    const auto refused = record_step(*rods, foreign.value(), frame);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("record_step: recording is on another device"), std::string::npos)
        << refused.error().message;
    const auto refused_birds = record_simulate(*birds, foreign.value(), 1);
    ASSERT_FALSE(refused_birds.ok());
    EXPECT_NE(refused_birds.error().message.find("record_simulate: recording"), std::string::npos) << refused_birds.error().message;
    app_->submit(1);
    app_->wait_all();
    ASSERT_TRUE(rods->read_states(b).ok());
    expect_same_bits(a, b);
    EXPECT_EQ(device.validation_messages(), 0u);
    EXPECT_EQ(messages, 0u);
}

TEST_F(Embedding, AdoptRejectsBadHandlesNamingTheField) {
    struct Case {
        const char* field;
        VulkanDeviceHandles handles;
    };
    VulkanDeviceHandles good = app_->handles();
    std::vector<Case> cases;
    cases.push_back({"instance", good});
    cases.back().handles.instance = VK_NULL_HANDLE;
    cases.push_back({"physical_device", good});
    cases.back().handles.physical_device = VK_NULL_HANDLE;
    cases.push_back({"device", good});
    cases.back().handles.device = VK_NULL_HANDLE;
    cases.push_back({"get_instance_proc_addr", good});
    cases.back().handles.get_instance_proc_addr = nullptr;
    cases.push_back({"api_version", good});
    cases.back().handles.api_version = VK_API_VERSION_1_0;
    cases.push_back({"frames_in_flight", good});
    cases.back().handles.frames_in_flight = 0;
    cases.push_back({"queue_family", good});
    cases.back().handles.queue_family = 99;
    cases.push_back({"queue_index", good});
    cases.back().handles.queue_index = 7;
    for (const Case& c : cases) {
        const auto adopted = adopt_vulkan_device(c.handles);
        ASSERT_FALSE(adopted.ok()) << c.field;
        EXPECT_NE(adopted.error().message.find(std::string("VulkanDeviceHandles::") + c.field), std::string::npos)
            << adopted.error().message;
    }
    EXPECT_TRUE(adopt_vulkan_device(good).ok());
}

TEST_F(Embedding, RecordRejectsBadCallsAndLeavesTheStateAsItWas) {
    const rods::SyntheticScene synthetic = scene();
    rods::RodFrame frame;
    synthetic.frame(0, 1.0f / 60.0f, frame);
    auto device = adopt_vulkan_device(app_->handles());
    ASSERT_TRUE(device.ok()) << device.error().message;
    BackendOptions embedded;
    embedded.context = device.value();
    auto rods = std::move(make_rod_backend(BackendKind::Vulkan, embedded)).value();
    VkCommandBuffer cmd = app_->begin(1);

    // Before load(): nothing to record.
    auto before = record_step(*rods, cmd, frame);
    ASSERT_FALSE(before.ok());
    EXPECT_NE(before.error().message.find("load()"), std::string::npos) << before.error().message;

    ASSERT_TRUE(rods->load(synthetic.world(), frame).ok());
    std::vector<rods::ChainState> loaded, after;
    ASSERT_TRUE(rods->read_states(loaded).ok());

    auto null_cmd = record_step(*rods, VK_NULL_HANDLE, frame);
    ASSERT_FALSE(null_cmd.ok());
    EXPECT_NE(null_cmd.error().message.find("cmd is null"), std::string::npos) << null_cmd.error().message;

    rods::RodFrame short_frame = frame;
    short_frame.roots.pop_back();
    auto wrong = record_step(*rods, cmd, short_frame);
    ASSERT_FALSE(wrong.ok());
    EXPECT_NE(wrong.error().message.find("roots"), std::string::npos) << wrong.error().message;

    rods::RodFrame nan_frame = frame;
    nan_frame.dt = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FALSE(record_step(*rods, cmd, nan_frame).ok());

    auto cpu = std::move(make_rod_backend(BackendKind::Cpu, {})).value();
    auto not_vulkan = record_step(*cpu, cmd, frame);
    ASSERT_FALSE(not_vulkan.ok());
    EXPECT_NE(not_vulkan.error().message.find("vulkan"), std::string::npos) << not_vulkan.error().message;

    auto birds = std::move(make_bird_backend(BackendKind::Vulkan, embedded)).value();
    auto unloaded = record_simulate(*birds, cmd, 1);
    ASSERT_FALSE(unloaded.ok());
    EXPECT_NE(unloaded.error().message.find("load()"), std::string::npos) << unloaded.error().message;

    // Nothing was recorded: the command buffer submits empty and the state is load()'s.
    app_->submit(1);
    app_->wait_all();
    ASSERT_TRUE(rods->read_states(after).ok());
    expect_same_bits(loaded, after);
    EXPECT_EQ(messages, 0u);
}

// A host-visible storage buffer of the application's.
struct AppBuffer {
    VkDevice device = VK_NULL_HANDLE;
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
    AppBuffer(const Application& app, VkDeviceSize size) : device(app.device) {
        const VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, nullptr, 0, size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                      VK_SHARING_MODE_EXCLUSIVE, 0, nullptr};
        vkCreateBuffer(device, &info, nullptr, &buffer);
        VkMemoryRequirements needs;
        vkGetBufferMemoryRequirements(device, buffer, &needs);
        VkPhysicalDeviceMemoryProperties props;
        vkGetPhysicalDeviceMemoryProperties(app.physical, &props);
        const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        std::uint32_t type = 0;
        while (type < props.memoryTypeCount && !((needs.memoryTypeBits >> type & 1u) && (props.memoryTypes[type].propertyFlags & want) == want)) ++type;
        const VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, needs.size, type};
        vkAllocateMemory(device, &alloc, nullptr, &memory);
        vkBindBufferMemory(device, buffer, memory, 0);
        vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &mapped);
    }
    AppBuffer(const AppBuffer&) = delete;
    AppBuffer& operator=(const AppBuffer&) = delete;
    ~AppBuffer() {
        vkDestroyBuffer(device, buffer, nullptr);
        vkFreeMemory(device, memory, nullptr);
    }
};

glm::mat4 matrix_of(const rods::Transform& t) { return glm::translate(glm::mat4(1.0f), t.position) * glm::mat4_cast(t.rotation); }

// The characters' input from the application's world matrices on the device gives what the
// same transforms passed in the RodFrame give, though the frame given with it is wrong in
// every entry the matrices name (so they must be overwritten).
TEST_F(Embedding, MatrixInputFeedsRootsReferencesAndColliders) {
    constexpr std::uint32_t kPerCharacter = 6, kCharacters = 17;
    auto made = rods::SyntheticScene::make({.chains = kPerCharacter * kCharacters, .joints = 9, .iterations = 3,
                                            .chains_per_character = kPerCharacter, .views = 3});
    ASSERT_TRUE(made.ok());
    const rods::SyntheticScene& synthetic = made.value();
    const rods::RodWorld& world = synthetic.world();
    ASSERT_EQ(world.character_count, kCharacters);
    ASSERT_EQ(world.collider_count, kCharacters);  // a head sphere each
    constexpr float dt = 1.0f / 60.0f;
    rods::RodFrame frame;
    synthetic.frame(0, dt, frame);

    auto device = adopt_vulkan_device(app_->handles());
    ASSERT_TRUE(device.ok()) << device.error().message;
    BackendOptions embedded;
    embedded.context = device.value();
    auto by_matrix = std::move(make_rod_backend(BackendKind::Vulkan, embedded)).value();
    auto by_frame = std::move(make_rod_backend(BackendKind::Vulkan, embedded)).value();
    ASSERT_TRUE(by_matrix->load(world, frame).ok());
    ASSERT_TRUE(by_frame->load(world, frame).ok());

    // Node 0: the head (reference joint, carrying the collider); nodes 1..6: the chain roots.
    constexpr std::uint32_t kNodes = 1 + kPerCharacter;
    AppBuffer matrices(*app_, VkDeviceSize{kCharacters} * kNodes * sizeof(glm::mat4));
    MatrixInput input;
    input.buffer = matrices.buffer;
    input.instances = kCharacters;
    input.nodes = kNodes;
    input.reference_node = 0;
    for (std::uint32_t j = 0; j < kPerCharacter; ++j) input.chain_nodes.push_back(1 + j);
    const rods::Collider head = frame.colliders[0];
    const rods::Transform ref = frame.reference[0];
    const glm::vec3 a = glm::inverse(ref.rotation) * (head.a - ref.position), b = glm::inverse(ref.rotation) * (head.b - ref.position);
    input.colliders.push_back({.node = 0, .a = {a.x, a.y, a.z}, .b = {b.x, b.y, b.z}, .radius = head.radius});
    for (std::uint32_t i = 0; i < kCharacters; ++i) {
        ASSERT_EQ(world.chains[i * kPerCharacter].character, i);
        input.targets.push_back({.character = i, .first_chain = i * kPerCharacter, .first_collider = world.chains[i * kPerCharacter].collider_begin});
    }
    const auto set = set_matrix_input(*by_matrix, input);
    ASSERT_TRUE(set.ok()) << set.error().message;

    for (std::uint32_t k = 1; k <= 8; ++k) {
        synthetic.frame(k, dt, frame);
        app_->wait_all();  // the matrices are rewritten by the host: no frame may still read them
        auto* m = static_cast<glm::mat4*>(matrices.mapped);
        for (std::uint32_t i = 0; i < kCharacters; ++i) {
            m[i * kNodes] = matrix_of(frame.reference[i]);
            for (std::uint32_t j = 0; j < kPerCharacter; ++j) m[i * kNodes + 1 + j] = matrix_of(frame.roots[i * kPerCharacter + j]);
        }
        rods::RodFrame wrong = frame;
        for (rods::Transform& t : wrong.reference) t.position += glm::vec3(1.0f);
        for (rods::Transform& t : wrong.roots) t.position += glm::vec3(1.0f);
        for (rods::Collider& c : wrong.colliders) c.radius *= 2.0f;
        VkCommandBuffer cmd = app_->begin(k);
        ASSERT_TRUE(record_step(*by_matrix, cmd, wrong).ok());
        ASSERT_TRUE(record_step(*by_frame, cmd, frame).ok());
        app_->submit(k);
    }
    app_->wait_all();
    ChainSnapshot got, want;
    ASSERT_TRUE(by_matrix->read(got).ok());
    ASSERT_TRUE(by_frame->read(want).ok());
    // The rotation comes back from a matrix (quat_cast of float columns): within 1e-5 of the
    // chain length, the backends' parity tolerance.
    const float tolerance = 1e-5f * synthetic.chain_length();
    ASSERT_EQ(got.positions.size(), want.positions.size());
    float worst = 0.0f;
    for (std::size_t j = 0; j < got.positions.size(); ++j) worst = std::max(worst, glm::length(got.positions[j] - want.positions[j]));
    EXPECT_LE(worst, tolerance);

    // Bad input: named, and the backend keeps its writer.
    MatrixInput bad = input;
    bad.chain_nodes[2] = kNodes;
    auto rejected = set_matrix_input(*by_matrix, bad);
    ASSERT_FALSE(rejected.ok());
    EXPECT_NE(rejected.error().message.find("chain_nodes[2]"), std::string::npos) << rejected.error().message;
    bad = input;
    bad.targets[16].first_chain = kPerCharacter * kCharacters - 1;
    rejected = set_matrix_input(*by_matrix, bad);
    ASSERT_FALSE(rejected.ok());
    EXPECT_NE(rejected.error().message.find("targets[16].first_chain"), std::string::npos) << rejected.error().message;
    bad = input;
    bad.targets.pop_back();
    EXPECT_FALSE(set_matrix_input(*by_matrix, bad).ok());
    bad = input;
    bad.buffer = VK_NULL_HANDLE;
    EXPECT_FALSE(set_matrix_input(*by_matrix, bad).ok());
    auto cpu = std::move(make_rod_backend(BackendKind::Cpu, {})).value();
    EXPECT_FALSE(set_matrix_input(*cpu, input).ok());
    EXPECT_EQ(messages, 0u);
}

}  // namespace
