// A domain of the application's own, simulated by Kodawari beside a scene's domains
// (docs/architecture.md, "Adding a domain"): fireflies that circle and bob, with a compute
// kernel the application compiled itself (fireflies.comp), written against the public
// compute layer (kodawari/vulkan/compute.hpp: Device, Buffer, Kernel, Queue, Recording) and the
// domain contract (kodawari/simulation/domain.hpp). Nothing of Kodawari changes for it.
//
//   own_domain SCENE.json [--frames N] [--validation]
//
// --validation: the Khronos validation layer with synchronization validation on the
// vulkan run; any message fails it.
//
// It runs the scene with the fireflies on the cpu backend and, where a Vulkan device
// exists, on the vulkan backend (the kernel on the Simulation's device), reads the
// fireflies' positions of every frame through the Simulation's channels, and checks that
// the two backends agree within the bound of Vulkan's sin and cos. Exit status 0 when
// every check passes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <kodawari/vulkan/compute.hpp>
#include <kodawari/simulation/domain.hpp>
#include <kodawari/render/renderer.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/simulation/simulation.hpp>
#include <kodawari/vulkan/vulkan_embed.hpp>

#include "fireflies.comp.spv.h"

namespace {

using namespace kodawari;

constexpr float kPi = 3.14159265358979f;
constexpr const char* kPositions = "fireflies.positions";

// Firefly i: its centre, radius, angular speed and starting angle, from i alone (so that
// a shard's fireflies are the whole run's).
struct Firefly {
    glm::vec4 params;  // centre x, centre z, radius, angular speed (rad/s)
    float phase;
};

Firefly firefly(std::uint32_t i) {
    const float k = static_cast<float>(i);
    return {{std::fmod(k * 0.37f, 6.0f) - 3.0f, std::fmod(k * 0.61f, 6.0f) - 3.0f, 0.3f + std::fmod(k * 0.013f, 1.7f),
             0.8f + std::fmod(k * 0.029f, 2.5f)},
            std::fmod(k * 0.71f, 2.0f * kPi) - kPi};
}

// fireflies.comp's body, for the CPU backends.
glm::vec4 advance(const glm::vec4& p, float dt, float& angle) {
    float a = angle + p.w * dt;
    if (a >= kPi) a -= 2.0f * kPi;
    angle = a;
    return {p.x + p.z * std::cos(a), 1.5f + 0.3f * std::sin(a) * std::cos(a), p.y + p.z * std::sin(a), 1.0f};
}

class FirefliesDomain final : public Domain {
public:
    FirefliesDomain(std::uint32_t count, float fps) : count_(count), dt_(1.0f / fps) {}

    std::string_view name() const override { return "fireflies"; }
    std::uint32_t scene_instances() const override { return count_; }
    void keep_instances(InstanceRange range) override { range_ = range; }
    std::vector<std::string> buffers() const override { return {kPositions}; }
    // The positions where the kernel wrote them, for the application's shaders.
    Result<VulkanBufferRange> buffer(std::string_view) const override {
        if (gpu_.empty()) return make_error(Error::Kind::InvalidInput, "fireflies: on a device only on the vulkan backend");
        return vulkan_range(gpu_[2], static_cast<std::uint32_t>(positions_.size()), sizeof(glm::vec4));
    }
    std::vector<ChannelInfo> channels() const override { return {{kPositions, sizeof(glm::vec4), positions_.size()}}; }

    Result<void> open(const DomainSetup& setup, std::span<Domain* const>) override {
        kind_ = setup.kind;
        params_.clear();
        start_.clear();
        for (std::uint32_t i = range_.begin; i < range_.end; ++i) {
            params_.push_back(firefly(i).params);
            start_.push_back(firefly(i).phase);
        }
        positions_.assign(params_.size(), glm::vec4(0.0f));
        if (kind_ != BackendKind::Vulkan) return rewind();
        // The device every domain of the Simulation shares.
        device_ = setup.options.context;
        const std::uint64_t n = std::max<std::size_t>(params_.size(), 1);
        for (std::uint64_t bytes : {n * sizeof(glm::vec4), n * sizeof(float), n * sizeof(glm::vec4)}) {
            auto buffer = compute::Buffer::create(*device_, bytes, compute::Usage::Storage);
            if (!buffer) return buffer.error();
            gpu_.push_back(std::move(buffer).value());
        }
        KW_TRY(compute::upload(*device_, gpu_[0], std::as_bytes(std::span(params_))));
        const compute::Binding storage[] = {compute::Binding::Storage, compute::Binding::Storage, compute::Binding::Storage};
        auto kernel = compute::Kernel::create(*device_, "fireflies.comp", fireflies_comp, storage, sizeof(Push));
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
        angles_ = start_;
        if (kind_ == BackendKind::Vulkan) KW_TRY(compute::upload(*device_, gpu_[1], std::as_bytes(std::span(angles_))));
        return {};
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
                std::memcpy(channel.data() + std::size_t{f - first} * positions_.size() * sizeof(glm::vec4), positions_.data(),
                            positions_.size() * sizeof(glm::vec4));
            }
        }
        return {};
    }

    std::string device() const override { return device_ ? device_->info().name : std::string("1 thread"); }
    std::uint32_t validation_messages() const override { return device_ ? device_->validation_messages() : 0; }
    Result<void> show_on(render::Renderer&, bool) override { return {}; }
    // Through the renderer's neutral drawing interface: a yellow disc per firefly.
    Result<void> draw_on(render::Renderer& renderer, DrawSource, bool) override {
        std::vector<glm::vec3> centres(positions_.begin(), positions_.end());
        render::Draw& draw = renderer;
        draw.discs(centres, 0.03f, {255, 230, 60}, 2.0f);
        return {};
    }

private:
    struct Push {
        std::uint32_t count;
        float dt;
    };

    // One frame on the device: record, submit, wait, read the positions back.
    Result<void> dispatch(float dt) {
        const compute::Queue queue(*device_);
        auto recording = queue.begin();
        if (!recording) return recording.error();
        const Push push{static_cast<std::uint32_t>(params_.size()), dt};
        kernel_->dispatch(recording.value(), std::as_bytes(std::span(&push, 1)), (push.count + 63) / 64);
        compute::barrier(recording.value(), compute::Stage::Compute, compute::Stage::Transfer | compute::Stage::Host);
        auto submission = queue.submit(std::move(recording).value());
        if (!submission) return submission.error();
        KW_TRY(submission.value().wait());
        return compute::download(*device_, gpu_[2], std::as_writable_bytes(std::span(positions_)));
    }

    std::uint32_t count_;
    float dt_;
    InstanceRange range_;
    BackendKind kind_ = BackendKind::Cpu;
    std::vector<glm::vec4> params_, positions_;
    std::vector<float> start_, angles_;
    std::shared_ptr<compute::Device> device_;
    std::vector<compute::Buffer> gpu_;
    std::optional<compute::Kernel> kernel_;
};

constexpr std::uint32_t kFireflies = 777;  // not a multiple of the kernel's workgroup (64)

// The scene with the fireflies on `kind` for `frames` frames: every frame's positions.
Result<std::vector<glm::vec4>> run(const std::string& path, BackendKind kind, std::uint32_t frames, bool validation) {
    auto scene = load_scene(path);
    if (!scene) return scene.error();
    const float fps = scene.value().fps;
    std::vector<std::unique_ptr<Domain>> own;
    own.push_back(std::make_unique<FirefliesDomain>(kFireflies, fps));
    SimulationOptions options;
    options.backend = kind;
    options.frames = frames;
    options.options.validation = validation && kind == BackendKind::Vulkan;
    auto sim = Simulation::create(std::move(scene).value(), options, std::move(own));
    if (!sim) return sim.error();
    std::vector<glm::vec4> positions(std::size_t{frames} * kFireflies);
    const ChannelOutput out[] = {{kPositions, std::as_writable_bytes(std::span(positions))}};
    KW_TRY(sim.value()->step(frames, out));
    std::string order;
    for (const Domain* d : sim.value()->domains()) order += (order.empty() ? "" : ", ") + std::string(d->name());
    std::printf("own_domain: %s on %s (%s): %u frames of %s\n", sim.value()->scene().name.c_str(),
                std::string(backend_name(kind)).c_str(), sim.value()->device().c_str(), frames, order.c_str());
    if (kind == BackendKind::Vulkan) {
        auto range = sim.value()->buffer(kPositions);
        if (!range) return range.error();
        std::printf("own_domain: %s on the device: %u elements of %u bytes\n", kPositions, range.value().count,
                    range.value().stride);
        if (sim.value()->validation_messages() != 0) {
            return make_error(Error::Kind::Internal, std::to_string(sim.value()->validation_messages()) + " validation messages");
        }
    }
    return positions;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: own_domain SCENE.json [--frames N]\n");
        return 2;
    }
    const std::string path = argv[1];
    std::uint32_t frames = 120;
    bool validation = false;
    for (int i = 2; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--frames" && i + 1 < argc) {
            frames = static_cast<std::uint32_t>(std::strtoul(argv[++i], nullptr, 10));
        } else if (arg == "--validation") {
            validation = true;
        } else {
            std::fprintf(stderr, "own_domain: unknown argument \"%s\" (expected --frames N or --validation)\n", arg.c_str());
            return 2;
        }
    }
    if (frames == 0) {
        std::fprintf(stderr, "own_domain: --frames must be a whole number of at least 1\n");
        return 2;
    }
    auto cpu = run(path, BackendKind::Cpu, frames, false);
    if (!cpu) {
        std::fprintf(stderr, "own_domain: cpu: %s\n", cpu.error().message.c_str());
        return 1;
    }
    // Each firefly's distance from its circle's centre is its radius at every frame.
    float worst_radius = 0.0f;
    for (std::size_t k = 0; k < cpu.value().size(); ++k) {
        const glm::vec4 p = firefly(static_cast<std::uint32_t>(k % kFireflies)).params;
        const glm::vec4 q = cpu.value()[k];
        worst_radius = std::max(worst_radius, std::abs(std::hypot(q.x - p.x, q.z - p.y) - p.z));
    }
    if (worst_radius > 1e-5f) {
        std::fprintf(stderr, "own_domain: a firefly left its circle by %g m\n", static_cast<double>(worst_radius));
        return 1;
    }
    auto vulkan = run(path, BackendKind::Vulkan, frames, validation);
    if (!vulkan) {
        if (vulkan.error().kind == Error::Kind::Vulkan || vulkan.error().kind == Error::Kind::Unsupported) {
            std::printf("own_domain: no vulkan run (%s)\nown_domain: ok (cpu only)\n", vulkan.error().message.c_str());
            return 0;
        }
        std::fprintf(stderr, "own_domain: vulkan: %s\n", vulkan.error().message.c_str());
        return 1;
    }
    // Vulkan bounds sin and cos in [-pi, pi] to 2^-11 absolute error: x and z are off by at
    // most radius (2 m at most) x 2^-11 = 9.8e-4 m each, y by 0.3 x 2 x 2^-11 = 2.9e-4 m,
    // a distance of at most 1.41e-3 m (the angles' own rounding adds ~1e-5 m over 1 000
    // frames).
    float worst = 0.0f;
    for (std::size_t k = 0; k < cpu.value().size(); ++k) worst = std::max(worst, glm::length(cpu.value()[k] - vulkan.value()[k]));
    std::printf("own_domain: cpu and vulkan differ by at most %.3g m over %u frames of %u fireflies (bound 1.5e-3 m)\n",
                static_cast<double>(worst), frames, kFireflies);
    if (!(worst <= 1.5e-3f)) return 1;
    std::printf("own_domain: ok\n");
    return 0;
}
