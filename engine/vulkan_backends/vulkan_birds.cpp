// The Vulkan bird backend: one dispatch of shaders/birds_flap.comp evaluates every bird
// for a run of frames, keeping each bird's state in registers between frames (lavapipe
// executes storage-buffer access lane by lane, so state is loaded and stored once per
// dispatch; see shared/PERF-NOTES.md). Poses go to a ring of frame slots that is read
// back after each dispatch when the caller wants them.
#include <algorithm>
#include <array>
#include <cstring>
#include <optional>

#include "backends/backends.hpp"
#include "vulkan_backends/device_backends.hpp"
#include "gpu/compute_vulkan.hpp"
#include "kodawari/birds/flight.hpp"

namespace kodawari {
namespace {

using compute::Buffer;

// Upper bound of the pose + diagnostics ring: many frames per dispatch for small
// flocks, one frame per dispatch for a million birds.
constexpr std::uint64_t kRingBytes = 256ull << 20;

// The kernel stores the left wing only (shared/birds.h, BirdPoseGpu); the right wing is
// its mirror.
void expand(const gpu::BirdPoseGpu* in, std::size_t count, gpu::BirdPose* out) {
    auto mirror = [](const gpu::vec4& q) { return gpu::vec4{q.x, -q.y, -q.z, q.w}; };
    for (std::size_t i = 0; i < count; ++i) {
        const gpu::BirdPoseGpu& g = in[i];
        gpu::BirdPose& p = out[i];
        p.position = g.position;
        p.rotation[KW_PART_BODY] = g.body;
        p.rotation[KW_PART_HEAD] = g.head;
        p.rotation[KW_PART_TAIL] = g.tail;
        p.rotation[KW_PART_LEFT_ARM1] = g.left_arm1;
        p.rotation[KW_PART_LEFT_ARM2] = g.left_arm2;
        p.rotation[KW_PART_RIGHT_ARM1] = mirror(g.left_arm1);
        p.rotation[KW_PART_RIGHT_ARM2] = mirror(g.left_arm2);
    }
}

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& v) {
    return std::as_bytes(std::span<const T>(v));
}

class VulkanBirdBackend final : public BirdBackend, public DeviceBirdBackend, public DeviceData {
public:
    VulkanBirdBackend(std::shared_ptr<compute::Device> ctx, std::uint32_t workgroup, bool pose_fields)
        : ctx_(std::move(ctx)), workgroup_(workgroup), pose_fields_(pose_fields) {}

    /// The kernel specialized for this world's rules, with or without diagnostics; built
    /// on first use (lavapipe compiles it at its first dispatch) and kept.
    Result<const compute::Kernel*> pipeline(bool diagnostics) {
        const std::array<std::uint32_t, KW_BIRDS_SPEC_COUNT> spec = {rules_.x, rules_.y, diagnostics ? 1u : 0u, driven_ > 0 ? 1u : 0u,
                                                                         workgroup_, pose_fields_ ? 1u : 0u};
        for (const auto& [key, p] : pipelines_) {
            if (key == spec) return &p;
        }
        std::vector<compute::Binding> types(KW_BIRDS_BINDING_COUNT, compute::Binding::Storage);
        // Read by every invocation many times: a uniform buffer, which lavapipe loads once
        // for all lanes instead of lane by lane.
        types[KW_BIRDS_BINDING_UNIFORMS] = compute::Binding::Uniform;
        auto created = compute::Kernel::create(*ctx_, "birds_flap", types, sizeof(gpu::BirdPush), spec);
        if (!created) return created.error();
        pipelines_.emplace_back(spec, std::move(created).value());
        if (!buffers_.empty()) pipelines_.back().second.bind(bound_buffers());
        return &pipelines_.back().second;
    }

    std::string_view name() const override { return "vulkan"; }
    std::string device() const override { return ctx_->info().name; }
    double last_gpu_ms() const override { return gpu_ms_; }
    std::uint32_t validation_messages() const override { return ctx_->validation_messages(); }
    // Poses laid out as fields are for timing only: no reader of bird_buffers::poses knows them.
    const DeviceData* device_data() const override { return frame_ > 0 && !pose_fields_ ? this : nullptr; }
    const compute::Device& context() const override { return *ctx_; }
    compute::Device& compute_device() const override { return *ctx_; }
    DeviceSpan buffer(std::string_view name) const override {
        if (name != bird_buffers::poses || frame_ == 0) return {};
        return {.buffer = &buffers_[KW_BIRDS_BINDING_POSES],
                .first = std::uint64_t{last_slot_} * count_,
                .items = count_,
                .element_bytes = sizeof(gpu::BirdPoseGpu)};
    }

    const compute::Buffer& pose_ring() const override {
        assert(!buffers_.empty() && "load() first");
        return buffers_[KW_BIRDS_BINDING_POSES];
    }

    Result<void> record_simulate(compute::Recording& recording, std::uint32_t frames) override {
        assert(count_ > 0 && "load() first");
        if (pose_fields_) return fields_unsupported();
        if (driven_ > 0) {
            return make_error(Error::Kind::Unsupported, std::to_string(driven_) +
                                                            " birds are flown by another domain (flocking), whose motion is given per "
                                                            "simulate() or, recorded, by that domain's buffer (Simulation::record)");
        }
        return record_next(recording, frames);
    }

    Result<void> record_external(compute::Recording& recording, std::uint32_t frames, const compute::Buffer* motion) override {
        if (count_ == 0) return make_error(Error::Kind::InvalidInput, "record_simulate: the backend has no flock; load() one first");
        if (pose_fields_) return fields_unsupported();
        if (frames == 0 || frames > slots_) {
            return make_error(Error::Kind::InvalidInput, "record_simulate: frames is " + std::to_string(frames) + "; expected 1 to " +
                                                             std::to_string(slots_) + " (the pose ring's slots for this flock)");
        }
        if (driven_ > 0 && (motion == nullptr || frames != 1)) {
            return make_error(Error::Kind::Unsupported,
                              std::to_string(driven_) + " birds are flown by another domain (flocking): they record one frame at a time "
                                                        "with that domain's motion on the device (Simulation::record)");
        }
        const std::uint64_t motion_bytes = std::uint64_t{driven_} * sizeof(gpu::BirdMotionGpu);
        if (driven_ > 0 && motion->size() < motion_bytes) {
            return make_error(Error::Kind::InvalidInput, "record_simulate: the driven birds' motion buffer holds " +
                                                             std::to_string(motion->size()) + " bytes; " +
                                                             std::to_string(motion_bytes) + " needed");
        }
        // No per-frame input from the host: nothing to stage.
        compute::barrier(recording, embedding_consumers(*ctx_), compute::Stage::Compute | compute::Stage::Transfer);
        // The frame's motion, written by the flocking domain's kernels before this call,
        // copied into slot 0 of the motion ring (record_frames' barrier orders the copy
        // before the dispatch).
        if (driven_ > 0) compute::copy(recording, *motion, 0, buffers_[KW_BIRDS_BINDING_MOTION], 0, motion_bytes);
        KW_TRY(record_next(recording, frames));
        compute::barrier(recording, compute::Stage::Compute, embedding_consumers(*ctx_));
        return {};
    }

    Result<void> load(const birds::BirdWorld& world) override {
        const std::size_t count = world.birds.size();
        if (count == 0) return make_error(Error::Kind::InvalidInput, "the world has no birds");
        if (compute::groups_for(count, workgroup_) > ctx_->info().max_workgroup_count[0]) {
            return make_error(Error::Kind::Unsupported, std::to_string(count) + " birds exceed what one dispatch on " +
                                                            ctx_->info().name + " can cover (" +
                                                            std::to_string(std::uint64_t{ctx_->info().max_workgroup_count[0]} * workgroup_) +
                                                            ")");
        }
        count_ = static_cast<std::uint32_t>(count);
        frame_ = 0;
        const std::uint64_t per_frame = std::uint64_t{count} * (sizeof(gpu::BirdPoseGpu) + sizeof(gpu::BirdDiag));
        slots_ = static_cast<std::uint32_t>(std::clamp<std::uint64_t>(kRingBytes / per_frame, 1, std::max(world.frames, 1u)));
        const std::uint64_t max_range = ctx_->info().max_storage_buffer_range;
        // A storage buffer larger than maxStorageBufferRange cannot be bound (undefined
        // behaviour, a crash or a lost device on some drivers): each is checked here, and
        // the error names the buffer and both sizes (Unsupported: backend "auto" then runs
        // the scene on the CPU). The pose ring holds fewer frames rather than fail; one
        // frame of poses is its floor.
        const auto too_large = [&](const char* buffer, std::uint64_t bytes, const std::string& why) {
            return make_error(Error::Kind::Unsupported, ctx_->info().name + " cannot hold " + std::to_string(count) + " birds: the " +
                                                            buffer + " need a storage buffer of " + std::to_string(bytes) + " bytes (" +
                                                            why + "); the device allows " + std::to_string(max_range) +
                                                            " (maxStorageBufferRange)");
        };
        while (slots_ > 1 && std::uint64_t{slots_} * count * sizeof(gpu::BirdPoseGpu) > max_range) --slots_;
        if (std::uint64_t{count} * sizeof(gpu::BirdPoseGpu) > max_range) {
            return too_large("poses", std::uint64_t{count} * sizeof(gpu::BirdPoseGpu),
                             std::to_string(sizeof(gpu::BirdPoseGpu)) + " bytes per bird, one frame");
        }

        const gpu::FlightUniforms uniforms = world.uniforms();
        const std::vector<gpu::BirdState> states(count, birds::initial_state());
        buffers_.clear();
        const std::span<const std::byte> contents[KW_BIRDS_BINDING_COUNT] = {
            std::as_bytes(std::span(&uniforms, 1)), bytes_of(world.routes), bytes_of(world.control_points),
            bytes_of(world.arc_samples), bytes_of(world.birds), bytes_of(states), {}, {}, {}};
        const std::uint64_t sizes[KW_BIRDS_BINDING_COUNT] = {
            sizeof(uniforms), contents[1].size(), contents[2].size(), contents[3].size(), contents[4].size(),
            contents[5].size(), std::uint64_t{slots_} * count * sizeof(gpu::BirdPoseGpu),
            std::uint64_t{slots_} * count * sizeof(gpu::BirdDiag), std::uint64_t{slots_} * world.driven * sizeof(gpu::BirdMotionGpu)};
        static constexpr const char* kBindingNames[KW_BIRDS_BINDING_COUNT] = {
            "uniforms", "routes", "route control points", "route arc samples", "bird parameters", "bird states",
            "poses", "diagnostics", "driven birds' motion"};
        for (std::uint32_t b = 0; b < KW_BIRDS_BINDING_COUNT; ++b) {
            if (sizes[b] > max_range) return too_large(kBindingNames[b], sizes[b], "binding " + std::to_string(b));
        }
        for (std::uint32_t b = 0; b < KW_BIRDS_BINDING_COUNT; ++b) {
            auto buffer = Buffer::create(*ctx_, std::max<std::uint64_t>(sizes[b], 16), Buffer::Kind::Storage);
            if (!buffer) return buffer.error();
            KW_TRY(compute::upload(*ctx_, buffer.value(), contents[b]));
            buffers_.push_back(std::move(buffer).value());
        }
        // The read-back buffer is made by the first simulate() that reads back (issue 38: at
        // 10 M birds it pins 1.76 GB of host memory that benchmarks never read).
        readback_.reset();
        rules_ = uniforms.rules;
        driven_ = world.driven;
        world_ = &world;
        for (auto& [key, p] : pipelines_) p.bind(bound_buffers());
        return {};
    }

    Result<void> simulate(std::uint32_t frames, FrameOutput out) override {
        assert(count_ > 0 && "load() first");
        assert(out.poses.empty() || out.poses.size() == std::size_t{frames} * count_);
        assert(out.diag.empty() || out.diag.size() == std::size_t{frames} * count_);
        const bool want_poses = !out.poses.empty();
        const bool want_diag = !out.diag.empty();
        if (pose_fields_ && (want_poses || want_diag || driven_ > 0)) return fields_unsupported();
        auto kernel = pipeline(want_diag);
        if (!kernel) return kernel.error();
        gpu_ms_ = 0.0;
        KW_TRY(check_motion(*world_, frames));

        const compute::Queue queue(*ctx_);
        if (!want_poses && !want_diag && driven_ == 0) {
            // Nothing read back (benchmarks): one dispatch runs every frame; each frame's
            // poses still go to the ring, whose slots are reused.
            auto recording = queue.begin();
            if (!recording) return recording.error();
            recording.value().timestamp(compute::Timestamp::Begin);
            KW_TRY(record_next(recording.value(), frames));
            recording.value().timestamp(compute::Timestamp::End);
            auto submission = queue.submit(std::move(recording).value());
            if (!submission) return submission.error();
            double ms = -1.0;
            KW_TRY(submission.value().wait(&ms));
            gpu_ms_ = ms;
            return {};
        }

        if (!ctx_->unified_memory() && !readback_ && (want_poses || want_diag)) {
            auto readback = Buffer::create(*ctx_, buffers_[KW_BIRDS_BINDING_POSES].size() + buffers_[KW_BIRDS_BINDING_DIAGNOSTICS].size(),
                                           Buffer::Kind::Readback);
            if (!readback) return readback.error();
            readback_.emplace(std::move(readback).value());
        }
        for (std::uint32_t done = 0; done < frames;) {
            const std::uint32_t n = std::min(slots_, frames - done);
            if (driven_ > 0) {
                // This chunk's motion, before the dispatch that reads it (the last one has
                // finished: every submission is waited for).
                const auto chunk = motion_.subspan(std::size_t{done} * driven_, std::size_t{n} * driven_);
                KW_TRY(compute::upload(*ctx_, buffers_[KW_BIRDS_BINDING_MOTION], std::as_bytes(chunk)));
            }
            auto recording = queue.begin();
            if (!recording) return recording.error();
            compute::Recording& rec = recording.value();
            rec.timestamp(compute::Timestamp::Begin);
            record_frames(rec, *kernel.value(), frame_ + done, n);
            rec.timestamp(compute::Timestamp::End);
            if (want_poses || want_diag) {
                record_readback(rec, n, want_diag);
            } else {
                compute::barrier(rec, compute::Stage::Compute, compute::Stage::Host);
            }
            auto submission = queue.submit(std::move(recording).value());
            if (!submission) return submission.error();
            double ms = -1.0;
            KW_TRY(submission.value().wait(&ms));
            if (ms >= 0.0) gpu_ms_ += ms;
            const std::size_t pose_count = std::size_t{n} * count_;
            if (!want_poses && !want_diag) {
                done += n;
                continue;
            }
            gpu::vulkan(*ctx_).count_read_back(pose_count * ((want_poses ? sizeof(gpu::BirdPoseGpu) : 0) + (want_diag ? sizeof(gpu::BirdDiag) : 0)));
            const std::byte* poses = readback_ ? readback_->mapped() : buffers_[KW_BIRDS_BINDING_POSES].mapped();
            const std::byte* diags = readback_ ? readback_->mapped() + buffers_[KW_BIRDS_BINDING_POSES].size()
                                               : buffers_[KW_BIRDS_BINDING_DIAGNOSTICS].mapped();
            if (readback_) KW_TRY(readback_->invalidate(*ctx_));
            if (want_poses) {
                expand(reinterpret_cast<const gpu::BirdPoseGpu*>(poses), pose_count, out.poses.data() + std::size_t{done} * count_);
            }
            if (want_diag) {
                std::memcpy(out.diag.data() + std::size_t{done} * count_, diags, pose_count * sizeof(gpu::BirdDiag));
            }
            done += n;
        }
        frame_ += frames;
        last_slot_ = (frames - 1) % slots_;  // the last chunk started at slot 0
        return {};
    }

private:
    static Error fields_unsupported() {
        return make_error(Error::Kind::Unsupported,
                          "BackendOptions::bird_pose_fields lays the poses out for timing only (bench birds --pose-layouts): "
                          "nothing reads them back, records them for an application or draws them");
    }

    // The next `frames` frames recorded (the motion of driven birds already in place).
    Result<void> record_next(compute::Recording& recording, std::uint32_t frames) {
        assert(&recording.device() == ctx_.get() && "a recording of the backend's device");
        auto kernel = pipeline(false);
        if (!kernel) return kernel.error();
        record_frames(recording, *kernel.value(), frame_, frames);
        frame_ += frames;
        last_slot_ = (frames - 1) % slots_;
        return {};
    }

    // The dispatch of frames [first, first + n) (at most slots_ when read back).
    void record_frames(compute::Recording& recording, const compute::Kernel& kernel, std::uint32_t first, std::uint32_t n) const {
        // The previous dispatch (this or an earlier submission) wrote the states and the
        // ring, and a copy may have read the ring; this one reads and overwrites them.
        compute::barrier(recording, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
        const gpu::BirdPush push{{first, n, slots_, driven_}};
        kernel.dispatch(recording, std::as_bytes(std::span(&push, 1)), compute::groups_for(count_, workgroup_));
    }

    // The poses (and diagnostics) of the dispatch's n frames to where the host reads them.
    void record_readback(compute::Recording& recording, std::uint32_t n, bool want_diag) const {
        if (!readback_) {
            compute::barrier(recording, compute::Stage::Compute, compute::Stage::Host);
            return;
        }
        compute::barrier(recording, compute::Stage::Compute, compute::Stage::Transfer);
        const std::uint64_t pose_bytes = std::uint64_t{n} * count_ * sizeof(gpu::BirdPoseGpu);
        const std::uint64_t diag_bytes = std::uint64_t{n} * count_ * sizeof(gpu::BirdDiag);
        compute::copy(recording, buffers_[KW_BIRDS_BINDING_POSES], 0, *readback_, 0, pose_bytes);
        if (want_diag) {
            compute::copy(recording, buffers_[KW_BIRDS_BINDING_DIAGNOSTICS], 0, *readback_, buffers_[KW_BIRDS_BINDING_POSES].size(),
                          diag_bytes);
        }
        compute::barrier(recording, compute::Stage::Transfer, compute::Stage::Host);
    }

    // The k-th frame of a dispatch goes to ring slot k % slots_ (shaders/birds_flap.comp).
    std::shared_ptr<compute::Device> ctx_;
    std::vector<const Buffer*> bound_buffers() const {
        std::vector<const Buffer*> bound;
        for (const auto& b : buffers_) bound.push_back(&b);
        return bound;
    }

    // A handful of variants at most (rules x diagnostics): a vector is the simplest map.
    std::vector<std::pair<std::array<std::uint32_t, KW_BIRDS_SPEC_COUNT>, compute::Kernel>> pipelines_;
    std::uint32_t workgroup_ = KW_BIRDS_WORKGROUP_SIZE;  // invocations per workgroup (KW_BIRDS_SPEC_WORKGROUP_SIZE)
    bool pose_fields_ = false;  // KW_BIRDS_SPEC_POSE_FIELDS: the fields layout, a variant to time
    gpu::uvec4 rules_{};
    std::vector<Buffer> buffers_;
    std::optional<Buffer> readback_;
    std::uint32_t count_ = 0;
    std::uint32_t slots_ = 1;
    std::uint32_t frame_ = 0;
    std::uint32_t last_slot_ = 0;  // the ring slot of the last simulated frame
    std::uint32_t driven_ = 0;     // BirdWorld::driven
    const birds::BirdWorld* world_ = nullptr;
    double gpu_ms_ = -1.0;
};

}  // namespace

Result<std::unique_ptr<BirdBackend>> make_vulkan_bird_backend(const BackendOptions& options) {
    auto ctx = backend_context(options);
    if (!ctx) return ctx.error();
    auto workgroup = compute::workgroup_size(*ctx.value(), options.workgroup_size, KW_BIRDS_WORKGROUP_SIZE);
    if (!workgroup) return workgroup.error();
    auto backend = std::make_unique<VulkanBirdBackend>(std::move(ctx).value(), workgroup.value(), options.bird_pose_fields);
    // The default variant now, so a broken shader or driver shows up at creation.
    if (auto p = backend->pipeline(false); !p) return p.error();
    return std::unique_ptr<BirdBackend>(std::move(backend));
}

}  // namespace kodawari
