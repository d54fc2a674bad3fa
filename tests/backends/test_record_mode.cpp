// The vulkan backends' record mode (engine/vulkan_backends/device_backends.hpp, issue 19): a rod
// step and a bird frame recorded into the caller's one recording submit nothing and wait
// for nothing until the caller submits, and give the very state step() and simulate()
// give. White-box: the engine's internal headers, as an embedding layer inside the
// engine uses them. Lavapipe where there is no GPU, validation on (ctest).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "vulkan_backends/device_backends.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "gpu/compute_vulkan.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/scene/scene.hpp"
#include "keyed_scene.hpp"
#include "small_flock.hpp"
#include "test_support.hpp"

using namespace kodawari;

namespace {

TEST(RecordMode, RodsAndBirdsRecordIntoOneSubmission) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto opened = open_shared_device(testing_support::gpu_options());
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    compute::Device& device = *opened.value();
    BackendOptions options = testing_support::gpu_options();
    options.context = opened.value();

    // 203 chains of 13 joints: not a multiple of the workgroup size.
    rods::SyntheticOptions o;
    o.chains = 203;
    o.joints = 13;
    o.views = 2;
    auto made = rods::SyntheticScene::make(o);
    ASSERT_TRUE(made.ok()) << made.error().message;
    const rods::SyntheticScene& scene = made.value();
    const birds::BirdWorld birds = testing_support::small_flock();

    auto recorded_rods = make_rod_backend(BackendKind::Vulkan, options);
    auto stepped_rods = make_rod_backend(BackendKind::Vulkan, options);
    auto recorded_birds = make_bird_backend(BackendKind::Vulkan, options);
    auto simulated_birds = make_bird_backend(BackendKind::Vulkan, options);
    ASSERT_TRUE(recorded_rods.ok() && stepped_rods.ok() && recorded_birds.ok() && simulated_birds.ok());
    auto* rods_recorder = dynamic_cast<DeviceRodBackend*>(recorded_rods.value().get());
    auto* birds_recorder = dynamic_cast<DeviceBirdBackend*>(recorded_birds.value().get());
    ASSERT_NE(rods_recorder, nullptr);
    ASSERT_NE(birds_recorder, nullptr);

    constexpr float kDt = 1.0f / 60.0f;
    rods::RodFrame frame;
    scene.frame(0, kDt, frame);
    ASSERT_TRUE(recorded_rods.value()->load(scene.world(), frame).ok());
    ASSERT_TRUE(stepped_rods.value()->load(scene.world(), frame).ok());
    ASSERT_TRUE(recorded_birds.value()->load(birds).ok());
    ASSERT_TRUE(simulated_birds.value()->load(birds).ok());

    const compute::Queue queue(device);
    ChainSnapshot expected, actual;
    for (std::uint32_t f = 1; f <= 6; ++f) {
        scene.frame(f, kDt, frame);
        ASSERT_TRUE(stepped_rods.value()->step(frame).ok());
        ASSERT_TRUE(simulated_birds.value()->simulate(1, {}).ok());

        const std::uint64_t before = device.submissions();
        auto recording = queue.begin();
        ASSERT_TRUE(recording.ok()) << recording.error().message;
        ASSERT_TRUE(rods_recorder->record_step(recording.value(), frame).ok());
        ASSERT_TRUE(birds_recorder->record_simulate(recording.value(), 1).ok());
        EXPECT_EQ(device.submissions(), before) << "recording submitted work (frame " << f << ")";
        auto submission = queue.submit(std::move(recording).value());
        ASSERT_TRUE(submission.ok()) << submission.error().message;
        EXPECT_EQ(device.submissions(), before + 1) << "one submission for both domains";
        ASSERT_TRUE(submission.value().wait().ok());

        ASSERT_TRUE(stepped_rods.value()->read(expected).ok());
        ASSERT_TRUE(recorded_rods.value()->read(actual).ok());
        ASSERT_EQ(expected.positions.size(), actual.positions.size());
        EXPECT_EQ(std::memcmp(expected.positions.data(), actual.positions.data(), expected.positions.size() * sizeof(glm::vec3)), 0)
            << "frame " << f;
    }
    // The birds' states agree too: their next frame is the same poses.
    std::vector<gpu::BirdPose> a(birds.birds.size()), b(birds.birds.size());
    ASSERT_TRUE(recorded_birds.value()->simulate(1, {a, {}}).ok());
    ASSERT_TRUE(simulated_birds.value()->simulate(1, {b, {}}).ok());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(gpu::BirdPose)), 0);
    EXPECT_EQ(device.validation_messages(), 0u);
}

// Keyed examples in record mode (docs/keyed-examples.md K.6): the recorded step measures
// the keys (rod_keys.comp) before the rod step in the caller's recording, as step() does
// in its own, so both give the same bits (positions and the combined weights W) over a
// sprint, a stop, a turn and a nod. 67 chains: not a multiple of the workgroup size.
TEST(RecordMode, KeyedExamplesRecordAsTheyStep) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto opened = open_shared_device(testing_support::gpu_options());
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    compute::Device& device = *opened.value();
    BackendOptions options = testing_support::gpu_options();
    options.context = opened.value();
    const testing_support::KeyedScene scene = testing_support::KeyedScene::make(67, 3);
    auto recorded = make_rod_backend(BackendKind::Vulkan, options);
    auto stepped = make_rod_backend(BackendKind::Vulkan, options);
    ASSERT_TRUE(recorded.ok() && stepped.ok());
    auto* recorder = dynamic_cast<DeviceRodBackend*>(recorded.value().get());
    ASSERT_NE(recorder, nullptr);
    rods::RodFrame frame;
    scene.frame(0, frame);
    ASSERT_TRUE(recorded.value()->load(scene.world(), frame).ok());
    ASSERT_TRUE(stepped.value()->load(scene.world(), frame).ok());
    const compute::Queue queue(device);
    ChainSnapshot expected, actual;
    float most_keyed = 0.0f;
    for (std::uint32_t f = 1; f <= testing_support::KeyedScene::kFrames; f += 1) {
        scene.frame(f, frame);
        ASSERT_TRUE(stepped.value()->step(frame).ok());
        auto recording = queue.begin();
        ASSERT_TRUE(recording.ok()) << recording.error().message;
        ASSERT_TRUE(recorder->record_step(recording.value(), frame).ok());
        auto submission = queue.submit(std::move(recording).value());
        ASSERT_TRUE(submission.ok()) << submission.error().message;
        ASSERT_TRUE(submission.value().wait().ok());
        if (f % 15 != 0) continue;
        ASSERT_TRUE(stepped.value()->read(expected).ok());
        ASSERT_TRUE(recorded.value()->read(actual).ok());
        EXPECT_EQ(std::memcmp(expected.positions.data(), actual.positions.data(), expected.positions.size() * sizeof(glm::vec3)), 0)
            << "frame " << f;
        EXPECT_EQ(expected.weights, actual.weights) << "frame " << f;
        const rods::RodWorld& world = scene.world();
        for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
            const rods::ChainTemplate& t = world.templ(world.chains[c]);
            for (std::size_t j = 1; j <= t.keyed.size(); ++j) {
                most_keyed = std::max(most_keyed, actual.weights[c * (rods::kMaxViewExamples + 1) + t.views.size() + j]);
            }
        }
    }
    EXPECT_GT(most_keyed, 0.5f) << "the keyed examples took part";
    EXPECT_EQ(device.validation_messages(), 0u);
}

}  // namespace

// Issue 38: the bird backend pins no read-back memory until something is read back (at
// 10 M birds the buffer is 1.76 GB of host memory a benchmark never reads), on the
// discrete-GPU path (staging forced: storage buffers unmapped, copies to a read-back
// buffer); the first simulate() with poses makes it, and its poses are those the host
// path gives.
TEST(DevicePaths, BirdsPinNoReadbackMemoryUntilAsked) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    BackendOptions staged = testing_support::gpu_options();
    staged.force_staging = true;
    auto opened = open_shared_device(staged);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    const gpu::VulkanContext& device = gpu::vulkan(*opened.value());
    ASSERT_FALSE(device.unified_memory());
    staged.context = opened.value();
    const birds::BirdWorld birds = testing_support::small_flock();
    auto tested = make_bird_backend(BackendKind::Vulkan, staged);
    auto mapped = make_bird_backend(BackendKind::Vulkan, testing_support::gpu_options());
    ASSERT_TRUE(tested.ok() && mapped.ok());
    const std::uint64_t before = device.readback_buffer_bytes();
    ASSERT_TRUE(tested.value()->load(birds).ok());
    ASSERT_TRUE(tested.value()->simulate(5, {}).ok());
    EXPECT_EQ(device.readback_buffer_bytes(), before) << "a read-back buffer made for nothing read back";
    ASSERT_TRUE(mapped.value()->load(birds).ok());
    ASSERT_TRUE(mapped.value()->simulate(5, {}).ok());
    std::vector<gpu::BirdPose> a(birds.birds.size()), b(birds.birds.size());
    ASSERT_TRUE(tested.value()->simulate(1, {a, {}}).ok());
    ASSERT_TRUE(mapped.value()->simulate(1, {b, {}}).ok());
    EXPECT_GT(device.readback_buffer_bytes(), before);
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(gpu::BirdPose)), 0);
    EXPECT_EQ(device.validation_messages(), 0u);
}

// The birds' pose layouts (BackendOptions::bird_pose_fields, a variant `bench birds
// --pose-layouts` times on a GPU): the fields layout holds the very bytes of the records
// layout, field by field, for every bird of every frame of a dispatch; and since nothing
// reads fields, asking for poses, diagnostics or a recording with it is refused by name.
// 301 birds: several workgroups, the last one partial.
TEST(DevicePaths, BirdPoseFieldsHoldTheRecordsBytes) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    constexpr std::uint32_t kBirds = 301, kFrames = 3;
    const birds::BirdWorld birds = testing_support::small_flock(kBirds);
    BackendOptions as_fields = testing_support::gpu_options();
    as_fields.bird_pose_fields = true;
    auto records = make_bird_backend(BackendKind::Vulkan, testing_support::gpu_options());
    auto fields = make_bird_backend(BackendKind::Vulkan, as_fields);
    ASSERT_TRUE(records.ok() && fields.ok());
    ASSERT_TRUE(records.value()->load(birds).ok());
    ASSERT_TRUE(fields.value()->load(birds).ok());
    ASSERT_TRUE(records.value()->simulate(kFrames, {}).ok());
    const auto simulated = fields.value()->simulate(kFrames, {});
    ASSERT_TRUE(simulated.ok()) << simulated.error().message;

    auto* records_device = dynamic_cast<DeviceBirdBackend*>(records.value().get());
    auto* fields_device = dynamic_cast<DeviceBirdBackend*>(fields.value().get());
    ASSERT_TRUE(records_device != nullptr && fields_device != nullptr);
    constexpr std::size_t kFields = sizeof(gpu::BirdPoseGpu) / sizeof(glm::vec4);
    static_assert(kFields == 6);
    // The dispatch's frame k went to ring slot k (the rest of the ring holds whatever the
    // memory held: not compared).
    constexpr std::size_t kSlots = kFrames;
    const std::size_t count = kSlots * kBirds * kFields;
    std::vector<glm::vec4> a(records_device->pose_ring().size() / sizeof(glm::vec4));
    std::vector<glm::vec4> b(fields_device->pose_ring().size() / sizeof(glm::vec4));
    ASSERT_GE(a.size(), count);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_TRUE(compute::download(records_device->compute_device(), records_device->pose_ring(), std::as_writable_bytes(std::span(a))).ok());
    ASSERT_TRUE(compute::download(fields_device->compute_device(), fields_device->pose_ring(), std::as_writable_bytes(std::span(b))).ok());
    std::size_t differ = 0;
    for (std::size_t s = 0; s < kSlots; ++s) {
        for (std::size_t i = 0; i < kBirds; ++i) {
            for (std::size_t f = 0; f < kFields; ++f) {
                const glm::vec4& record = a[(s * kBirds + i) * kFields + f];
                const glm::vec4& field = b[(s * kFields + f) * kBirds + i];
                differ += std::memcmp(&record, &field, sizeof(glm::vec4)) != 0;
            }
        }
    }
    EXPECT_EQ(differ, 0u) << "of " << count << " vec4s";
    EXPECT_NE(std::memcmp(a.data(), b.data(), count * sizeof(glm::vec4)), 0) << "the two layouts are the same bytes in the same order";

    std::vector<gpu::BirdPose> poses(kBirds);
    const auto read = fields.value()->simulate(1, {poses, {}});
    ASSERT_FALSE(read.ok());
    EXPECT_EQ(read.error().kind, Error::Kind::Unsupported);
    EXPECT_NE(read.error().message.find("bird_pose_fields"), std::string::npos) << read.error().message;
    EXPECT_EQ(fields.value()->device_data(), nullptr) << "fields handed out as bird_buffers::poses";
    const compute::Queue queue(fields_device->compute_device());
    auto recording = queue.begin();
    ASSERT_TRUE(recording.ok());
    EXPECT_FALSE(fields_device->record_simulate(recording.value(), 1).ok());
    EXPECT_EQ(fields_device->compute_device().validation_messages(), 0u);
}
