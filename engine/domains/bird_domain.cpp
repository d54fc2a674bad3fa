// The bird domain (kodawari/domains/birds.hpp): a scene's flocks on a BirdBackend, behind
// the domain contract (kodawari/simulation/domain.hpp).
#include "kodawari/domains/birds.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "vulkan_backends/device_backends.hpp"
#include "domains/flocking/flock_backend.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/domains/bird_draw.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

namespace kodawari {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A channel's bytes as the elements they hold (sizes checked by Simulation::step against
// channels()).
template <class T>
std::span<T> as(std::span<std::byte> bytes) {
    return {reinterpret_cast<T*>(bytes.data()), bytes.size() / sizeof(T)};
}

class BirdDomain final : public Domain {
public:
    explicit BirdDomain(birds::BirdWorld world)
        : world_(std::move(world)), scene_birds_(static_cast<std::uint32_t>(world_.birds.size())) {}

    std::string_view name() const override { return kBirdDomain; }
    std::uint32_t scene_instances() const override { return scene_birds_; }
    void keep_instances(InstanceRange range) override {
        auto& birds = world_.birds;
        if (range.begin == 0 && range.end == birds.size()) return;
        birds.erase(birds.begin() + range.end, birds.end());
        birds.erase(birds.begin(), birds.begin() + range.begin);
    }
    std::vector<std::string> outputs() const override { return {std::string(kBirdDomain)}; }
    std::vector<std::string> buffers() const override {
        if (world_.birds.empty()) return {};
        return {std::string(bird_buffers::poses)};
    }
    Result<VulkanBufferRange> buffer(std::string_view name) const override {
        // Simulation::buffer asks only for buffers(); vulkan_buffer names any other.
        const DeviceData* data = device_data();
        if (data == nullptr) {
            return make_error(Error::Kind::InvalidInput, "domain \"birds\": \"" + std::string(name) +
                                                             "\" is not on a Vulkan device (a cpu backend, or no frame yet)");
        }
        return vulkan_buffer(*data, name);
    }
    // Driven birds fly what the flocking domain gives them each frame.
    std::vector<std::string> inputs() const override {
        if (world_.driven == 0) return {};
        return {std::string(kFlockingDomain)};
    }

    Result<void> open(const DomainSetup& setup, std::span<Domain* const> producers) override {
        driver_ = producers.empty() ? nullptr : producers.front();
        if (world_.birds.empty()) return {};
        auto made = make_bird_backend(setup.kind, setup.options);
        if (!made) return made.error();
        backend_ = std::move(made).value();
        return backend_->load(world_);
    }
    void close() override { backend_.reset(); }
    Result<void> rewind() override {
        if (backend_) KW_TRY(backend_->load(world_));
        return {};
    }

    std::vector<ChannelInfo> channels() const override {
        const std::uint64_t n = world_.birds.size();
        return {{std::string(kBirdPosesChannel), sizeof(gpu::BirdPose), n, false},
                {std::string(kBirdDiagChannel), sizeof(gpu::BirdDiag), n, true}};
    }
    // Bird poses read back per step when birds go in chunks: bounds the chunk buffers
    // (2^18 x 128 bytes = 32 MiB of poses, as much of diagnostics) while amortizing the
    // step calls.
    std::uint32_t max_bake_frames() const override {
        constexpr std::uint32_t kChunkPoses = 1u << 18;
        return std::clamp<std::uint32_t>(kChunkPoses / std::max(scene_birds_, 1u), 1, kMaxBakeFrames);
    }

    Result<void> step(std::uint32_t, std::uint32_t n, std::span<const ChannelOutput> out) override {
        if (!backend_) return {};
        FrameOutput frame_out;
        for (const ChannelOutput& channel : out) {
            if (channel.name == kBirdPosesChannel) frame_out.poses = as<gpu::BirdPose>(channel.bytes);
            if (channel.name == kBirdDiagChannel) frame_out.diag = as<gpu::BirdDiag>(channel.bytes);
        }
        const bool keep = keep_poses_ && frame_out.poses.empty();
        if (keep) {
            scratch_.resize(std::size_t{n} * world_.birds.size());
            frame_out.poses = scratch_;
        }
        const auto start = std::chrono::steady_clock::now();
        if (world_.driven > 0) {
            const auto motion = driver_ != nullptr ? flocking_motion(*driver_) : std::span<const gpu::BirdMotionGpu>{};
            KW_TRY(backend_->drive(motion.first(std::min<std::size_t>(motion.size(), std::size_t{n} * world_.driven))));
        }
        KW_TRY(backend_->simulate(n, frame_out));
        if (timing_.first_frames == 0) {
            timing_.first_seconds = seconds_since(start);
            timing_.first_frames = n;
            timing_.first_gpu_ms = backend_->last_gpu_ms();
        } else {
            timing_.seconds += seconds_since(start);
            timing_.frames += n;
            if (backend_->last_gpu_ms() >= 0.0) {
                timing_.gpu_ms += backend_->last_gpu_ms();
            } else {
                timing_.gpu_timed = false;
            }
        }
        if (keep_poses_) {
            const std::size_t count = world_.birds.size();
            const auto last = frame_out.poses.subspan((std::size_t{n} - 1) * count, count);
            last_poses_.assign(last.begin(), last.end());
        }
        return {};
    }

    // The frame's flapping and flight (the vulkan backend's barriers); driven birds fly
    // the motion the flocking domain recorded just before, on the device.
    Result<void> record(std::uint32_t, compute::Recording& recording) override {
        if (!backend_) return {};
        // (Simulation::record refused the cpu kinds already; a caller of the domain itself
        // is told.)
        auto* device = dynamic_cast<DeviceBirdBackend*>(backend_.get());
        if (device == nullptr) {
            return make_error(Error::Kind::Unsupported, "domain \"birds\" records into a command buffer on the vulkan backend only");
        }
        const compute::Buffer* motion = world_.driven > 0 && driver_ != nullptr ? flocking::flocking_motion_buffer(*driver_) : nullptr;
        return device->record_external(recording, 1, motion);
    }

    std::string device() const override { return backend_ ? backend_->device() : std::string(); }
    const DeviceData* device_data() const { return backend_ ? backend_->device_data() : nullptr; }
    std::uint32_t validation_messages() const override { return backend_ ? backend_->validation_messages() : 0; }

    Result<void> show_on(render::Renderer& renderer, bool shared_device) override {
        KW_TRY(show_birds(renderer, backend_ ? &world_ : nullptr));
        // Poses on the host only where the renderer cannot draw them where they are.
        if (backend_ && !shared_device) keep_poses_ = true;
        return {};
    }

    Result<void> draw_on(render::Renderer& renderer, DrawSource source, bool shared_device) override {
        if (!backend_) return {};
        if (source == DrawSource::Device && shared_device) return draw_birds(renderer, *backend_);
        if (last_poses_.size() != world_.birds.size()) {
            return make_error(Error::Kind::InvalidInput,
                              "Simulation::draw_on: the bird poses are not on the renderer's device and were not kept "
                              "(show_on() before step(), or keep_bird_poses(true))");
        }
        return draw_birds(renderer, last_poses_);
    }

    const birds::BirdWorld& world() const { return world_; }
    void keep_poses(bool keep) { keep_poses_ = keep; }
    const BirdTiming& timing() const { return timing_; }

private:
    birds::BirdWorld world_;
    std::uint32_t scene_birds_;  // before keep_instances()
    std::unique_ptr<BirdBackend> backend_;
    const Domain* driver_ = nullptr;  // the flocking domain, when birds are driven
    // The last frame's poses on the host, for drawing from a CPU backend.
    bool keep_poses_ = false;
    std::vector<gpu::BirdPose> last_poses_;
    std::vector<gpu::BirdPose> scratch_;
    BirdTiming timing_;
};

BirdDomain* find(const Simulation& sim) { return dynamic_cast<BirdDomain*>(sim.domain(kBirdDomain)); }

}  // namespace

std::unique_ptr<Domain> make_bird_domain(birds::BirdWorld world) { return std::make_unique<BirdDomain>(std::move(world)); }

const birds::BirdWorld* bird_world_of(const Domain& domain) {
    const auto* birds = dynamic_cast<const BirdDomain*>(&domain);
    return birds ? &birds->world() : nullptr;
}

const birds::BirdWorld& bird_world(const Simulation& sim) {
    static const birds::BirdWorld none;
    const BirdDomain* domain = find(sim);
    return domain ? domain->world() : none;
}

Result<void> step_birds(Simulation& sim, std::uint32_t frames, std::span<gpu::BirdPose> poses, std::span<gpu::BirdDiag> diag) {
    std::vector<ChannelOutput> out;
    if (!poses.empty()) out.push_back({kBirdPosesChannel, std::as_writable_bytes(poses)});
    if (!diag.empty()) out.push_back({kBirdDiagChannel, std::as_writable_bytes(diag)});
    return sim.step(frames, out);
}

void keep_bird_poses(Simulation& sim, bool keep) {
    if (BirdDomain* domain = find(sim)) domain->keep_poses(keep);
}

const BirdTiming& bird_timing(const Simulation& sim) {
    static const BirdTiming none;
    const BirdDomain* domain = find(sim);
    return domain ? domain->timing() : none;
}

}  // namespace kodawari
