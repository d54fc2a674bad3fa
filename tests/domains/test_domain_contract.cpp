// The domain contract (kodawari/simulation/domain.hpp, issue 31): a domain defined here alone,
// particles on circles with a kernel and buffers of its own, runs through Simulation on
// every backend kind beside the scene's own domains, a second domain that reads its output
// steps after it whatever order they are given in, and definitions the Simulation cannot
// run (two of one name, one buffer name twice, an input nothing produces, a cycle) are
// refused when it is made, naming the domain. Nothing under engine/ knows these domains.
//
// The kernel is compiled by the tests' CMake (tests/domains/circles.comp) and run through
// the public compute layer (kodawari/vulkan/compute.hpp); the test sees public headers only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>
#include <tiny_gltf.h>

#include <kodawari/shared/birds.h>
#include <kodawari/shared/rods.h>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "domains/app_device.hpp"
#include "test_support.hpp"

using namespace kodawari;

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr std::string_view kPositions = "circles.positions";

std::vector<std::uint32_t> circles_spirv() {
    std::ifstream in(KODAWARI_CIRCLES_SPV, std::ios::binary);
    std::vector<char> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    std::vector<std::uint32_t> words(bytes.size() / 4);
    std::memcpy(words.data(), bytes.data(), words.size() * 4);
    return words;
}

// Particle i: on a circle round (cx, cz) of radius r at angular speed w, starting at
// angle phase. Deterministic from i alone, so that a shard's particles are the whole's.
struct Particle {
    glm::vec4 params;  // cx, cz, r, w
    float phase;
};

Particle particle(std::uint32_t i) {
    const float k = static_cast<float>(i);
    return {{std::fmod(k * 0.37f, 5.0f) - 2.5f, std::fmod(k * 0.61f, 5.0f) - 2.5f, 0.2f + std::fmod(k * 0.013f, 1.8f),
             0.5f + std::fmod(k * 0.029f, 3.0f)},
            std::fmod(k * 0.71f, 2.0f * kPi) - kPi};
}

// The one step of a particle (circles.comp's body), for the CPU kinds.
glm::vec4 advance(const glm::vec4& p, float dt, float& angle) {
    float a = angle + p.w * dt;
    if (a >= kPi) a -= 2.0f * kPi;
    angle = a;
    return {p.x + p.z * std::cos(a), 1.0f, p.y + p.z * std::sin(a), 1.0f};
}

class CirclesDomain final : public Domain {
public:
    CirclesDomain(std::string name, std::uint32_t count, float fps) : name_(std::move(name)), count_(count), dt_(1.0f / fps) {}

    std::string_view name() const override { return name_; }
    std::string_view instance_noun() const override { return "particles"; }
    std::uint32_t scene_instances() const override { return count_; }
    void keep_instances(InstanceRange range) override { range_ = range; }
    std::vector<std::string> outputs() const override { return {name_}; }
    std::vector<std::string> buffers() const override { return {name_ + ".params", name_ + ".angles", name_ + ".positions"}; }
    // The positions, for an application's shaders (vec4 per particle); the others are the
    // domain's own.
    Result<VulkanBufferRange> buffer(std::string_view name) const override {
        if (name != name_ + ".positions" || kind_ != BackendKind::Vulkan || gpu_.size() < 3) {
            return make_error(Error::Kind::InvalidInput, "circles: hands out only its positions, on vulkan");
        }
        return vulkan_range(gpu_[2], static_cast<std::uint32_t>(positions_.size()), sizeof(glm::vec4));
    }

    Result<void> open(const DomainSetup& setup, std::span<Domain* const>) override {
        kind_ = setup.kind;
        params_.clear();
        start_angles_.clear();
        for (std::uint32_t i = range_.begin; i < range_.end; ++i) {
            params_.push_back(particle(i).params);
            start_angles_.push_back(particle(i).phase);
        }
        positions_.assign(params_.size(), glm::vec4(0.0f));
        if (kind_ != BackendKind::Vulkan) return rewind();
        device_ = setup.options.context;
        compute::Device& device = *device_;
        const std::uint64_t n = std::max<std::size_t>(params_.size(), 1);
        for (std::uint64_t bytes : {n * sizeof(glm::vec4), n * sizeof(float), n * sizeof(glm::vec4)}) {
            auto buffer = compute::Buffer::create(device, bytes, compute::Usage::Storage);
            if (!buffer) return buffer.error();
            gpu_.push_back(std::move(buffer).value());
        }
        KW_TRY(compute::upload(device, gpu_[0], std::as_bytes(std::span(params_))));
        const std::vector<std::uint32_t> spirv = circles_spirv();
        const compute::Binding storage[] = {compute::Binding::Storage, compute::Binding::Storage, compute::Binding::Storage};
        auto kernel = compute::Kernel::create(device, "circles.comp", spirv, storage, 8);
        if (!kernel) return kernel.error();
        kernel_.emplace(std::move(kernel).value());
        const compute::Buffer* bound[] = {&gpu_[0], &gpu_[1], &gpu_[2]};
        kernel_->bind(bound);
        return rewind();
    }
    void close() override {
        kernel_.reset();
        gpu_.clear();
        device_.reset();
    }
    Result<void> rewind() override {
        angles_ = start_angles_;
        current_.reset();
        if (kind_ == BackendKind::Vulkan) KW_TRY(compute::upload(*device_, gpu_[1], std::as_bytes(std::span(angles_))));
        return {};
    }

    std::vector<ChannelInfo> channels() const override {
        return {{std::string(kPositions), sizeof(glm::vec4), params_.size()}};
    }

    Result<void> step(std::uint32_t first, std::uint32_t frames, std::span<const ChannelOutput> out) override {
        std::span<std::byte> channel;
        for (const ChannelOutput& o : out) {
            if (o.name == kPositions) channel = o.bytes;
        }
        for (std::uint32_t f = first; f < first + frames; ++f) {
            const float dt = f == 0 ? 0.0f : dt_;
            if (kind_ == BackendKind::Vulkan) {
                KW_TRY(dispatch(dt));
            } else {
                for (std::size_t i = 0; i < params_.size(); ++i) positions_[i] = advance(params_[i], dt, angles_[i]);
            }
            if (!channel.empty()) {
                std::memcpy(channel.data() + (f - first) * positions_.size() * sizeof(glm::vec4), positions_.data(),
                            positions_.size() * sizeof(glm::vec4));
            }
            current_ = f;
        }
        return {};
    }

    // The kernel into the recording it is handed (the application's command buffer),
    // between barriers against the application's work before and after.
    Result<void> record(std::uint32_t frame, compute::Recording& recording) override {
        if (kind_ != BackendKind::Vulkan) return make_error(Error::Kind::Unsupported, "circles: record needs vulkan");
        compute::barrier(recording, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
        struct Push {
            std::uint32_t count;
            float dt;
        } push{static_cast<std::uint32_t>(params_.size()), frame == 0 ? 0.0f : dt_};
        kernel_->dispatch(recording, std::as_bytes(std::span(&push, 1)), (push.count + 63) / 64);
        compute::barrier(recording, compute::Stage::Compute, compute::Stage::Compute | compute::Stage::Transfer);
        current_ = frame;
        return {};
    }
    // The positions on the device, after the application's submission completed.
    Result<void> read_back() { return compute::download(*device_, gpu_[2], std::as_writable_bytes(std::span(positions_))); }

    std::string device() const override { return device_ ? device_->info().name : std::string("1 thread"); }
    std::uint32_t validation_messages() const override { return device_ ? device_->validation_messages() : 0; }
    Result<void> show_on(render::Renderer&, bool) override { return {}; }
    // Through the neutral drawing interface: a disc per particle, where it is now.
    Result<void> draw_on(render::Renderer& renderer, DrawSource, bool) override {
        std::vector<glm::vec3> centers;
        for (const glm::vec4& p : positions_) centers.emplace_back(p);
        render::Draw& draw = renderer;
        draw.discs(centers, 0.04f, kDiscColor, 3.0f);
        return {};
    }

    static constexpr render::Rgba8 kDiscColor{250, 40, 200};

    [[nodiscard]] std::optional<std::uint32_t> current() const { return current_; }
    [[nodiscard]] const std::vector<glm::vec4>& positions() const { return positions_; }

private:
    Result<void> dispatch(float dt) {
        compute::Device& device = *device_;
        const compute::Queue queue(device);
        auto recording = queue.begin();
        if (!recording) return recording.error();
        struct Push {
            std::uint32_t count;
            float dt;
        } push{static_cast<std::uint32_t>(params_.size()), dt};
        kernel_->dispatch(recording.value(), std::as_bytes(std::span(&push, 1)),
                          (push.count + 63) / 64);
        auto submission = queue.submit(std::move(recording).value());
        if (!submission) return submission.error();
        KW_TRY(submission.value().wait());
        return compute::download(device, gpu_[2], std::as_writable_bytes(std::span(positions_)));
    }

    std::string name_;
    std::uint32_t count_;
    float dt_;
    InstanceRange range_;
    BackendKind kind_ = BackendKind::Cpu;
    std::vector<glm::vec4> params_;
    std::vector<float> start_angles_, angles_;
    std::vector<glm::vec4> positions_;
    std::optional<std::uint32_t> current_;
    std::shared_ptr<compute::Device> device_;
    std::vector<compute::Buffer> gpu_;
    std::optional<compute::Kernel> kernel_;
};

// Reads the circles' output: each frame, the circles' frame must already be this one.
class WatcherDomain final : public Domain {
public:
    WatcherDomain(std::string name, std::vector<std::string> inputs, std::vector<std::string> outputs = {},
                  std::vector<std::string> buffers = {})
        : name_(std::move(name)), inputs_(std::move(inputs)), outputs_(std::move(outputs)), buffers_(std::move(buffers)) {}

    std::string_view name() const override { return name_; }
    std::uint32_t scene_instances() const override { return 0; }
    void keep_instances(InstanceRange) override {}
    std::vector<std::string> inputs() const override { return inputs_; }
    std::vector<std::string> outputs() const override { return outputs_; }
    std::vector<std::string> buffers() const override { return buffers_; }
    Result<void> open(const DomainSetup&, std::span<Domain* const> producers) override {
        producer_ = producers.empty() ? nullptr : dynamic_cast<CirclesDomain*>(producers.front());
        return {};
    }
    void close() override { producer_ = nullptr; }
    Result<void> rewind() override { return {}; }
    Result<void> step(std::uint32_t first, std::uint32_t frames, std::span<const ChannelOutput>) override {
        if (producer_ == nullptr) return {};
        // Stepped after its producer: the circles are at this call's last frame already.
        if (producer_->current() != first + frames - 1) {
            return make_error(Error::Kind::Internal, name_ + " stepped before the circles");
        }
        for (const glm::vec4& p : producer_->positions()) farthest_ = std::max(farthest_, std::hypot(p.x, p.z));
        seen_ += frames;
        return {};
    }
    std::string device() const override { return {}; }
    Result<void> show_on(render::Renderer&, bool) override { return {}; }
    Result<void> draw_on(render::Renderer&, DrawSource, bool) override { return {}; }

    std::uint32_t seen_ = 0;
    float farthest_ = 0.0f;

private:
    std::string name_;
    std::vector<std::string> inputs_, outputs_, buffers_;
    CirclesDomain* producer_ = nullptr;
};

Scene empty_scene(float seconds) {
    Scene scene;
    scene.name = "domain contract";
    scene.fps = 60.0f;
    scene.duration = seconds;
    return scene;
}

constexpr std::uint32_t kParticles = 1001;  // not a multiple of the workgroup (64)

std::vector<BackendKind> kinds() {
    std::vector<BackendKind> out{BackendKind::CpuReference, BackendKind::Cpu};
    if (testing_support::no_vulkan_device_reason().empty()) out.push_back(BackendKind::Vulkan);
    return out;
}

// Where particle i is at frame f, in double precision from the angle's recurrence in
// float (as the kinds compute it), for the expected positions.
glm::vec4 expected(std::uint32_t i, std::uint32_t frame) {
    const Particle p = particle(i);
    float angle = p.phase;
    glm::vec4 at{};
    for (std::uint32_t f = 0; f <= frame; ++f) at = advance(p.params, f == 0 ? 0.0f : 1.0f / 60.0f, angle);
    return at;
}

Result<std::unique_ptr<Simulation>> make(BackendKind kind, std::vector<std::unique_ptr<Domain>> domains, Shard shard = {}) {
    SimulationOptions options;
    options.backend = kind;
    options.options = testing_support::gpu_options();
    options.shard = shard;
    return Simulation::create(empty_scene(0.5f), options, std::move(domains));
}

TEST(DomainContract, ATestDomainRunsThroughSimulationOnEveryBackendKind) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) {
        std::printf("vulkan not run: %s\n", why.c_str());
    }
    std::vector<std::vector<glm::vec4>> finals;
    for (const BackendKind kind : kinds()) {
        SCOPED_TRACE(std::string(backend_name(kind)));
        // The reader first: the Simulation orders it after its producer.
        std::vector<std::unique_ptr<Domain>> domains;
        domains.push_back(std::make_unique<WatcherDomain>("watcher", std::vector<std::string>{"circles"}));
        domains.push_back(std::make_unique<CirclesDomain>("circles", kParticles, 60.0f));
        auto made = make(kind, std::move(domains));
        ASSERT_TRUE(made.ok()) << made.error().message;
        Simulation& sim = *made.value();
        ASSERT_EQ(sim.frame_count(), 30u);
        // The scene's domains (empty here) first, in the order given, then the circles
        // before their reader.
        std::vector<std::string> order;
        for (const Domain* d : sim.domains()) order.emplace_back(d->name());
        EXPECT_EQ(order, (std::vector<std::string>{"birds", "chains", "circles", "watcher"}));
        EXPECT_EQ(sim.backend(), kind);
        if (kind == BackendKind::Vulkan) {
            EXPECT_NE(sim.device().find(' '), std::string::npos) << sim.device();
        }

        // 7 frames with their positions, then the rest in steps of 1 and 22.
        std::vector<glm::vec4> positions(std::size_t{7} * kParticles);
        const ChannelOutput out[] = {{kPositions, std::as_writable_bytes(std::span(positions))}};
        ASSERT_TRUE(sim.step(7, out).ok());
        for (std::uint32_t f : {0u, 6u}) {
            for (std::uint32_t i : {0u, 500u, kParticles - 1}) {
                const glm::vec4 e = expected(i, f);
                const glm::vec4 a = positions[std::size_t{f} * kParticles + i];
                // Vulkan: sin and cos within 2^-11 absolute (the Vulkan spec's bound on
                // [-pi, pi]) times the radius (< 2 m), twice: 2e-3 m. The CPU kinds run
                // this very function: exact.
                const float tolerance = kind == BackendKind::Vulkan ? 2e-3f : 0.0f;
                EXPECT_NEAR(a.x, e.x, tolerance) << "particle " << i << " frame " << f;
                EXPECT_NEAR(a.z, e.z, tolerance) << "particle " << i << " frame " << f;
            }
        }
        ASSERT_TRUE(sim.step(1).ok());
        std::vector<glm::vec4> last(std::size_t{22} * kParticles);
        const ChannelOutput tail[] = {{kPositions, std::as_writable_bytes(std::span(last))}};
        ASSERT_TRUE(sim.step(22, tail).ok());
        EXPECT_EQ(sim.frame(), 29u);
        auto* watcher = dynamic_cast<WatcherDomain*>(sim.domain("watcher"));
        ASSERT_NE(watcher, nullptr);
        EXPECT_EQ(watcher->seen_, 30u);
        EXPECT_GT(watcher->farthest_, 1.0f);
        finals.emplace_back(last.end() - kParticles, last.end());

        // Seek back replays the same frames.
        ASSERT_TRUE(sim.seek(3).ok());
        ASSERT_TRUE(sim.step(1).ok());
        std::vector<glm::vec4> again(kParticles);
        const ChannelOutput one[] = {{kPositions, std::as_writable_bytes(std::span(again))}};
        ASSERT_TRUE(sim.step(1, one).ok());
        EXPECT_EQ(std::memcmp(again.data(), positions.data() + std::size_t{5} * kParticles, again.size() * sizeof(glm::vec4)), 0);

        // A channel no domain has, or of the wrong size, is refused naming it.
        std::vector<glm::vec4> wrong(3);
        const ChannelOutput bad[] = {{kPositions, std::as_writable_bytes(std::span(wrong))}};
        const auto sized = sim.step(1, bad);
        ASSERT_FALSE(sized.ok());
        EXPECT_NE(sized.error().message.find("\"circles.positions\" must hold frames x elements = 1001"), std::string::npos)
            << sized.error().message;
        const ChannelOutput unknown[] = {{"circles.velocities", std::as_writable_bytes(std::span(wrong))}};
        const auto named = sim.step(1, unknown);
        ASSERT_FALSE(named.ok());
        EXPECT_NE(named.error().message.find("no domain has a channel \"circles.velocities\""), std::string::npos)
            << named.error().message;
        EXPECT_EQ(sim.validation_messages(), 0u);
    }
    // cpu-reference and cpu: the same bits (the same host code); vulkan within the bound above.
    ASSERT_GE(finals.size(), 2u);
    EXPECT_EQ(std::memcmp(finals[0].data(), finals[1].data(), finals[0].size() * sizeof(glm::vec4)), 0);
    for (std::size_t k = 2; k < finals.size(); ++k) {
        float worst = 0.0f;
        for (std::size_t i = 0; i < finals[0].size(); ++i) worst = std::max(worst, glm::length(finals[k][i] - finals[0][i]));
        EXPECT_LT(worst, 2e-3f);
        std::printf("vulkan against cpu-reference after 30 frames: largest distance %.3g m\n", static_cast<double>(worst));
    }
}

// The bake pipeline hands the test domain's channel to a sink as it does the scene's
// domains'; the points sink writes it as a glTF that glTF-Validator passes, every node
// where the domain put its particle.
TEST(DomainContract, TheTestDomainBakesToGltf) {
    testing_support::TempDir dir;
    std::vector<std::unique_ptr<Domain>> domains;
    domains.push_back(std::make_unique<CirclesDomain>("circles", 37, 60.0f));
    auto made = make(BackendKind::Cpu, std::move(domains));
    ASSERT_TRUE(made.ok()) << made.error().message;
    const std::string path = dir.file("circles.glb");
    auto sink = make_points_glb_sink(path, std::string(kPositions), "circles", 60.0f);
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*made.value(), sinks);
    ASSERT_TRUE(written.ok()) << written.error().message;
    ASSERT_EQ(written.value().size(), 1u);

    std::string output;
    const int status = testing_support::run_command(testing_support::gltf_validator_command(path), output);
    EXPECT_EQ(status, 0) << output;
    EXPECT_NE(output.find("0 errors, 0 warnings"), std::string::npos) << output;

    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
    ASSERT_EQ(model.nodes.size(), 38u);  // the root and 37 points
    ASSERT_EQ(model.animations.size(), 1u);
    // Particle 20's last key is where the domain put it at frame 29.
    const tinygltf::AnimationChannel& channel = model.animations[0].channels[20];
    EXPECT_EQ(channel.target_node, 21);
    const tinygltf::Accessor& keys = model.accessors[static_cast<std::size_t>(model.animations[0].samplers[static_cast<std::size_t>(channel.sampler)].output)];
    ASSERT_EQ(keys.count, 30u);
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(keys.bufferView)];
    glm::vec3 last;
    std::memcpy(&last, model.buffers[0].data.data() + view.byteOffset + keys.byteOffset + 29 * sizeof(glm::vec3), sizeof last);
    const glm::vec4 e = expected(20, 29);
    EXPECT_EQ(last.x, e.x);
    EXPECT_EQ(last.z, e.z);

    // A channel the scene does not have is refused naming it, and nothing is written.
    auto again = make(BackendKind::Cpu, {});
    ASSERT_TRUE(again.ok());
    auto missing = make_points_glb_sink(dir.file("none.glb"), "circles.velocities", "v", 60.0f);
    BakeSink* missing_sinks[] = {missing.get()};
    auto refused = bake(*again.value(), missing_sinks);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("no domain of the scene has a channel \"circles.velocities\""), std::string::npos)
        << refused.error().message;
    EXPECT_FALSE(std::filesystem::exists(dir.file("none.glb")));
}

// The test domain draws itself through render::Draw from Simulation::draw_on(): seen from
// above, each particle's disc is in its colour at the pixel it projects to, and the next
// frame's discs replace the last ones.
TEST(DomainContract, TheTestDomainRenders) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    render::RendererOptions ropts;
    ropts.width = 320;
    ropts.height = 240;
    ropts.validation = testing_support::validation_requested();
    auto renderer = render::Renderer::create(ropts);
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;
    constexpr std::uint32_t kCount = 50;
    std::vector<std::unique_ptr<Domain>> domains;
    domains.push_back(std::make_unique<CirclesDomain>("circles", kCount, 60.0f));
    auto made = make(BackendKind::Cpu, std::move(domains));
    ASSERT_TRUE(made.ok()) << made.error().message;
    Simulation& sim = *made.value();
    ASSERT_TRUE(sim.show_on(*renderer.value()).ok());

    render::CameraView camera;
    camera.position = {0.0f, 10.0f, 0.0f};
    camera.target = {0.0f, 0.0f, 0.0f};
    camera.orthographic = true;
    camera.ortho_height = 12.0f;
    const glm::mat4 vp = render::view_projection(camera, 320.0f / 240.0f);
    const auto pixel = [&](const glm::vec4& p) {
        const glm::vec4 clip = vp * glm::vec4(glm::vec3(p), 1.0f);
        return glm::ivec2(static_cast<int>((clip.x / clip.w * 0.5f + 0.5f) * 320.0f),
                          static_cast<int>((clip.y / clip.w * 0.5f + 0.5f) * 240.0f));
    };
    std::size_t coloured_before = 0;
    for (std::uint32_t frame = 0; frame < 2; ++frame) {
        ASSERT_TRUE(sim.step(1).ok());
        ASSERT_TRUE(sim.draw_on(*renderer.value()).ok());
        auto image = renderer.value()->render(render::DrawList(camera, 320, 240));
        ASSERT_TRUE(image.ok()) << image.error().message;
        for (std::uint32_t i : {0u, 17u, 42u}) {
            const glm::ivec2 at = pixel(expected(i, frame));
            ASSERT_TRUE(at.x > 0 && at.x < 320 && at.y > 0 && at.y < 240) << at.x << ", " << at.y;
            EXPECT_EQ(image.value().at(static_cast<std::uint32_t>(at.x), static_cast<std::uint32_t>(at.y)),
                      CirclesDomain::kDiscColor)
                << "particle " << i << " at frame " << frame << ", pixel " << at.x << ", " << at.y;
        }
        EXPECT_NE(image.value().at(2, 2), CirclesDomain::kDiscColor);  // outside every circle
        std::size_t coloured = 0;
        for (std::uint32_t y = 0; y < 240; ++y) {
            for (std::uint32_t x = 0; x < 320; ++x) coloured += image.value().at(x, y) == CirclesDomain::kDiscColor;
        }
        if (frame == 1) {
            // The same discs moved, not more of them: within a fifth of frame 0's pixels
            // (overlaps change as they move).
            EXPECT_LT(static_cast<double>(coloured), 1.2 * static_cast<double>(coloured_before));
        }
        coloured_before = coloured;
        // 50 discs of at least 1.5 pixels' radius (3 at 720 rows, 240 here): about 6 pixels
        // each, 2 or more of them covered whole (exactly the colour) where none overlap.
        EXPECT_GE(coloured, 100u);
    }
    EXPECT_EQ(renderer.value()->validation_messages(), 0u);
}

// Simulation::record: the test domain's frames recorded into an application's command
// buffers (its own instance and device, adopted; three frames in flight) are the frames
// step() gives on the same device, bit for bit; the scene's domains record with it.
TEST(DomainContract, TheTestDomainRecordsIntoTheApplicationsCommandBuffers) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    testing_support::AppDevice app;
    ASSERT_TRUE(app.ok());
    auto device = adopt_vulkan_device(app.handles());
    ASSERT_TRUE(device.ok()) << device.error().message;
    const auto on_app_device = [&]() {
        std::vector<std::unique_ptr<Domain>> domains;
        domains.push_back(std::make_unique<CirclesDomain>("circles", kParticles, 60.0f));
        SimulationOptions options;
        options.backend = BackendKind::Vulkan;
        options.options.context = device.value();
        return Simulation::create(empty_scene(0.5f), options, std::move(domains));
    };
    auto recorded = on_app_device();
    auto stepped = on_app_device();
    ASSERT_TRUE(recorded.ok() && stepped.ok()) << (recorded.ok() ? stepped.error().message : recorded.error().message);
    for (std::uint32_t k = 0; k < 12; ++k) {
        VkCommandBuffer cmd = app.begin(k);
        if (k % 2 == 0) {
            // The compute layer's recording of the application's command buffer
            // (kodawari/vulkan/compute.hpp through vulkan_embed.hpp), on odd frames the command
            // buffer itself: both the same frames.
            auto recording = borrow_command_buffer(*device.value(), cmd);
            ASSERT_TRUE(recording.ok()) << recording.error().message;
            ASSERT_TRUE(recorded.value()->record(recording.value()).ok());
        } else {
            ASSERT_TRUE(recorded.value()->record(cmd).ok());
        }
        app.submit(k);
    }
    app.wait_all();
    EXPECT_EQ(recorded.value()->frame(), 11u);
    ASSERT_TRUE(stepped.value()->step(12).ok());
    auto* a = dynamic_cast<CirclesDomain*>(recorded.value()->domain("circles"));
    auto* b = dynamic_cast<CirclesDomain*>(stepped.value()->domain("circles"));
    ASSERT_TRUE(a->read_back().ok());
    ASSERT_EQ(a->positions().size(), b->positions().size());
    EXPECT_EQ(std::memcmp(a->positions().data(), b->positions().data(), a->positions().size() * sizeof(glm::vec4)), 0);
    const glm::vec4 e = expected(7, 11);
    EXPECT_NEAR(a->positions()[7].x, e.x, 2e-3f);  // the bound of the first test
    EXPECT_NEAR(a->positions()[7].z, e.z, 2e-3f);
    // The buffer it names, found by the Simulation among its domains' (the engine names
    // no circles): the application binds the positions it just recorded.
    auto positions = recorded.value()->buffer("circles.positions");
    ASSERT_TRUE(positions.ok()) << positions.error().message;
    EXPECT_NE(positions.value().buffer, VK_NULL_HANDLE);
    EXPECT_EQ(positions.value().count, kParticles);
    EXPECT_EQ(positions.value().stride, sizeof(glm::vec4));
    const auto unknown = recorded.value()->buffer("circles.velocities");
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.error().message.find("no domain has a buffer named \"circles.velocities\" (they have circles.params, "
                                           "circles.angles, circles.positions)"),
              std::string::npos)
        << unknown.error().message;
    EXPECT_FALSE(recorded.value()->buffer("circles.angles").ok());  // named, not handed out
    // Misuse: a null command buffer; a recording on another device; the cpu backends
    // record nothing.
    EXPECT_FALSE(recorded.value()->record(VK_NULL_HANDLE).ok());
    EXPECT_FALSE(borrow_command_buffer(*device.value(), VK_NULL_HANDLE).ok());
    {
        auto other = open_shared_device(testing_support::gpu_options());
        ASSERT_TRUE(other.ok()) << other.error().message;
        const compute::Queue queue(*other.value());
        auto elsewhere = queue.begin();
        ASSERT_TRUE(elsewhere.ok());
        const auto wrong = recorded.value()->record(elsewhere.value());
        ASSERT_FALSE(wrong.ok());
        EXPECT_NE(wrong.error().message.find("on another device than the simulation's"), std::string::npos) << wrong.error().message;
        EXPECT_EQ(recorded.value()->frame(), 11u) << "a refused record advanced the frame";
    }
    auto cpu = make(BackendKind::Cpu, {});
    ASSERT_TRUE(cpu.ok());
    const auto refused = cpu.value()->record(app.begin(12));
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("runs on the cpu backend"), std::string::npos) << refused.error().message;
    app.submit(12);
    app.wait_all();
    EXPECT_EQ(app.messages(), 0u);
    EXPECT_EQ(recorded.value()->validation_messages(), 0u);
}

// A shard of the Simulation cuts every domain, the test's too, by the same formula.
TEST(DomainContract, ShardsCutTheTestDomain) {
    std::vector<std::unique_ptr<Domain>> domains;
    domains.push_back(std::make_unique<CirclesDomain>("circles", kParticles, 60.0f));
    auto made = make(BackendKind::Cpu, std::move(domains), {1, 3});
    ASSERT_TRUE(made.ok()) << made.error().message;
    Simulation& sim = *made.value();
    const ShardPart part = sim.shard().part("particles");
    EXPECT_EQ(part.scene_count, kParticles);
    EXPECT_EQ(part.range.begin, 333u);
    EXPECT_EQ(part.range.end, 667u);
    std::vector<glm::vec4> positions(part.range.size());
    const ChannelOutput out[] = {{kPositions, std::as_writable_bytes(std::span(positions))}};
    ASSERT_TRUE(sim.step(1, out).ok());
    const glm::vec4 e = expected(333, 0);
    EXPECT_EQ(positions.front().x, e.x);
    EXPECT_EQ(positions.front().z, e.z);
}

struct Refusal {
    const char* what;
    std::function<std::vector<std::unique_ptr<Domain>>()> domains;
    const char* message;
};

// What the Simulation cannot run is refused when it is made, naming the domain.
TEST(DomainContract, BadDefinitionsAreRefusedNamingTheDomain) {
    using Names = std::vector<std::string>;
    const auto circles = [] { return std::make_unique<CirclesDomain>("circles", 10, 60.0f); };
    const std::vector<Refusal> refusals = {
        {"two of one name",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(circles());
             d.push_back(circles());
             return d;
         },
         "domain \"circles\": two domains have this name (domains 2 and 3)"},
        {"a buffer name twice",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(circles());
             d.push_back(std::make_unique<WatcherDomain>("copycat", Names{}, Names{}, Names{"circles.angles"}));
             return d;
         },
         "domain \"copycat\": buffer \"circles.angles\" is also a buffer of domain \"circles\""},
        {"a channel name twice",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(circles());
             d.push_back(std::make_unique<CirclesDomain>("squares", 10, 60.0f));
             return d;
         },
         "domain \"squares\": channel \"circles.positions\" is also a channel of domain \"circles\""},
        {"an input nothing produces",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(std::make_unique<WatcherDomain>("watcher", Names{"squares"}));
             return d;
         },
         "domain \"watcher\": input \"squares\" is produced by no domain"},
        {"an output twice",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(circles());
             d.push_back(std::make_unique<WatcherDomain>("impostor", Names{}, Names{"circles"}));
             return d;
         },
         "domain \"impostor\": output \"circles\" is also produced by domain \"circles\""},
        {"a cycle",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(std::make_unique<WatcherDomain>("x", Names{"y"}, Names{"x"}));
             d.push_back(std::make_unique<WatcherDomain>("y", Names{"z"}, Names{"y"}));
             d.push_back(std::make_unique<WatcherDomain>("z", Names{"x"}, Names{"z"}));
             return d;
         },
         "its inputs depend on its own outputs, a cycle: \"x\" reads \"y\" reads \"z\" reads \"x\""},
        {"a null domain",
         [&] {
             std::vector<std::unique_ptr<Domain>> d;
             d.push_back(nullptr);
             return d;
         },
         "Simulation::create: domains[0] is null"},
    };
    for (const Refusal& r : refusals) {
        SCOPED_TRACE(r.what);
        auto made = make(BackendKind::CpuReference, r.domains());
        ASSERT_FALSE(made.ok());
        EXPECT_EQ(made.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(made.error().message.find(r.message), std::string::npos) << made.error().message;
    }
}

}  // namespace
