// The flocking step on a Vulkan device: per substep, the grid in six dispatches of
// shaders/flock_grid.comp (clear, count, the scan in three, scatter) and the step of every bird
// (shaders/flock_step.comp, lib/flock_body.glsl), recorded for many frames into one
// submission with each frame's motion read back for the bird domain, or one frame into an
// application's command buffer with the motion left on the device for the birds' kernel.
#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "vulkan_backends/device_backends.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "domains/flocking/flock_backend.hpp"
#include "kodawari/domains/flocking.hpp"

namespace kodawari::flocking {

namespace {

template <typename T>
std::span<const std::byte> bytes_of(std::span<const T> v) {
    return std::as_bytes(v);
}

class VulkanFlockBackend final : public FlockBackend {
public:
    VulkanFlockBackend(std::shared_ptr<compute::Device> device, std::uint32_t workgroup)
        : device_(std::move(device)), workgroup_(workgroup) {}

    Result<void> create_kernels() {
        const std::vector<compute::Binding> types(KW_FLOCK_BINDING_COUNT, compute::Binding::Storage);
        auto grid = compute::Kernel::create(*device_, "flock_grid", types, sizeof(gpu::FlockPush));
        if (!grid) return grid.error();
        grid_.emplace(std::move(grid).value());
        const std::uint32_t spec[] = {workgroup_};  // KW_FLOCK_SPEC_WORKGROUP_SIZE
        auto step = compute::Kernel::create(*device_, "flock_step", types, sizeof(gpu::FlockPush), spec);
        if (!step) return step.error();
        step_.emplace(std::move(step).value());
        auto search = compute::Kernel::create(*device_, "flock_search_only", types, sizeof(gpu::FlockPush), spec);
        if (!search) return search.error();
        search_only_.emplace(std::move(search).value());
        return {};
    }

    Result<void> load(const FlockWorld& world) override {
        world_ = &world;
        count_ = static_cast<std::uint32_t>(world.birds.size());
        slot_ = 0;
        timing_ = {};
        timing_.device_seconds = device_->info().timestamps ? 0.0 : -1.0;
        ring_.reset();
        buffers_.clear();
        const std::uint64_t n = count_;
        // Flocks, agents and motion grow with the frames of a call (advance()).
        const std::uint64_t sizes[KW_FLOCK_BINDING_COUNT] = {
            sizeof(gpu::FlockParamsGpu) * std::max<std::size_t>(world.flocks.size(), 1), sizeof(gpu::FlockBirdGpu) * n,
            2 * sizeof(gpu::FlockStateGpu) * n, sizeof(std::uint32_t) * n, sizeof(std::uint32_t) * (2 * std::uint64_t{world.buckets} + scan_tiles(world)),
            sizeof(std::uint32_t) * n, sizeof(gpu::FlockAgentGpu) * (world.scene_agents() + kMaxFlockAgents),
            sizeof(gpu::BirdMotionGpu) * n, sizeof(gpu::vec4) * n, sizeof(gpu::FlockPerchGpu) * n};
        for (std::uint64_t bytes : sizes) {
            if (bytes > device_->info().max_storage_buffer_range) {
                return make_error(Error::Kind::Unsupported, device_->info().name + " cannot hold " + std::to_string(count_) +
                                                                " flocking birds: a buffer of " + std::to_string(bytes) +
                                                                " bytes exceeds maxStorageBufferRange");
            }
            auto buffer = compute::Buffer::create(*device_, std::max<std::uint64_t>(bytes, 16), compute::Usage::Storage);
            if (!buffer) return buffer.error();
            buffers_.push_back(std::move(buffer).value());
        }
        KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_BIRDS], bytes_of(std::span(world.birds))));
        KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_PERCHES], bytes_of(std::span(world.perches_of))));
        KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_STATES], bytes_of(std::span(world.initial))));
        bind();
        return {};
    }

    Result<void> advance(std::uint32_t frames, std::span<const gpu::FlockParamsGpu> flocks, std::span<const gpu::FlockAgentGpu> agents,
                         std::span<gpu::BirdMotionGpu> out) override {
        const FlockWorld& w = *world_;
        const std::size_t n = count_, f = w.flocks.size(), a = frames > 0 ? agents.size() / frames : 0;
        // A chunk's motion at most 64 MiB, its inputs with it.
        const std::uint32_t chunk = std::clamp<std::uint32_t>(
            static_cast<std::uint32_t>((64u << 20) / std::max<std::size_t>(n * sizeof(gpu::BirdMotionGpu), 1)), 1, frames);
        KW_TRY(grow(KW_FLOCK_BINDING_FLOCKS, std::uint64_t{chunk} * f * sizeof(gpu::FlockParamsGpu)));
        KW_TRY(grow(KW_FLOCK_BINDING_AGENTS, std::uint64_t{chunk} * a * sizeof(gpu::FlockAgentGpu)));
        KW_TRY(grow(KW_FLOCK_BINDING_MOTION, std::uint64_t{chunk} * n * sizeof(gpu::BirdMotionGpu)));
        const compute::Queue queue(*device_);
        for (std::uint32_t done = 0; done < frames;) {
            const std::uint32_t m = std::min(chunk, frames - done);
            if (f > 0) KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_FLOCKS], bytes_of(flocks.subspan(done * f, m * f))));
            if (a > 0) KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_AGENTS], bytes_of(agents.subspan(done * a, m * a))));
            auto recording = queue.begin();
            if (!recording) return recording.error();
            compute::Recording& rec = recording.value();
            rec.timestamp(compute::Timestamp::Begin);
            for (std::uint32_t k = 0; k < m; ++k) record_frame(rec, k, static_cast<std::uint32_t>(f), static_cast<std::uint32_t>(a));
            rec.timestamp(compute::Timestamp::End);
            compute::barrier(rec, compute::Stage::Compute, compute::Stage::Transfer | compute::Stage::Host);
            auto submission = queue.submit(std::move(recording).value());
            if (!submission) return submission.error();
            double ms = -1.0;
            KW_TRY(submission.value().wait(&ms));
            if (ms >= 0.0 && timing_.device_seconds >= 0.0) timing_.device_seconds += ms / 1000.0;
            timing_.bird_steps += std::uint64_t{count_} * w.substeps * m;
            const auto target = out.subspan(std::size_t{done} * n, std::size_t{m} * n);
            KW_TRY(compute::download(*device_, buffers_[KW_FLOCK_BINDING_MOTION], std::as_writable_bytes(target)));
            done += m;
        }
        return {};
    }

    Result<void> record(compute::Recording& recording, bool first, std::span<const gpu::FlockParamsGpu> flocks,
                        std::span<const gpu::FlockAgentGpu> agents, std::uint32_t device_agents) override {
        const FlockWorld& w = *world_;
        if (agents.size() + device_agents > agent_capacity()) {
            return make_error(Error::Kind::InvalidInput, "the flocking step: " + std::to_string(agents.size() + device_agents) +
                                                             " agents in a frame; at most " + std::to_string(agent_capacity()));
        }
        if (first) {
            // Frame 0 is where the routes fly the birds (advance() never computes it): the
            // world loads, as every domain's does at frame 0.
            return compute::upload(*device_, buffers_[KW_FLOCK_BINDING_MOTION], bytes_of(std::span(w.first)));
        }
        assert(flocks.size() == w.flocks.size() && "one frame's flock parameters");
        if (!ring_) {
            // The most one frame uploads: its flocks' parameters and every agent it may have.
            const auto rounded = [](std::uint64_t bytes) { return (bytes + 15) / 16 * 16; };
            const std::uint64_t bytes =
                rounded(w.flocks.size() * sizeof(gpu::FlockParamsGpu)) + rounded(agent_capacity() * sizeof(gpu::FlockAgentGpu));
            auto ring = compute::StagingRing::create(*device_, bytes, device_->frames_in_flight());
            if (!ring) return ring.error();
            ring_.emplace(std::move(ring).value());
        }
        ring_->next_frame();
        auto rec = recording.share(&*ring_);
        // The application's reads of the previous frame's motion (the birds' copy, its own
        // draws or kernels) before this frame's copies and dispatches overwrite it; and its
        // writes of the agents it places on the device (a copy or a kernel of its own)
        // before the step reads them.
        compute::barrier(rec, embedding_consumers(*device_), compute::Stage::Transfer | compute::Stage::Compute);
        KW_TRY(compute::upload(rec, buffers_[KW_FLOCK_BINDING_FLOCKS], bytes_of(flocks)));
        // Only the agents given here: the application's device agents after them are its own.
        KW_TRY(compute::upload(rec, buffers_[KW_FLOCK_BINDING_AGENTS], bytes_of(agents)));
        record_frame(rec, 0, static_cast<std::uint32_t>(flocks.size()), static_cast<std::uint32_t>(agents.size()) + device_agents);
        compute::barrier(rec, compute::Stage::Compute, embedding_consumers(*device_));
        return {};
    }

    const compute::Buffer* motion_buffer() const override { return &buffers_[KW_FLOCK_BINDING_MOTION]; }
    DeviceSpan device_agents() const override {
        if (buffers_.empty()) return {};
        return DeviceSpan{.buffer = &buffers_[KW_FLOCK_BINDING_AGENTS],
                          .first = world_->scene_agents(),
                          .items = kMaxFlockAgents,
                          .element_bytes = sizeof(gpu::FlockAgentGpu)};
    }

    Result<FlockingTiming> profile(std::uint32_t frames, std::span<const gpu::FlockParamsGpu> flocks,
                                   std::span<const gpu::FlockAgentGpu> agents) override {
        const FlockWorld& w = *world_;
        if (agents.size() > agent_capacity()) {
            return make_error(Error::Kind::InvalidInput, "profile_flocking: " + std::to_string(agents.size()) + " agents; at most " +
                                                             std::to_string(agent_capacity()));
        }
        // One frame's inputs at slot 0 of their bindings (each holds a frame at least).
        if (!flocks.empty()) KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_FLOCKS], bytes_of(flocks)));
        if (!agents.empty()) KW_TRY(compute::upload(*device_, buffers_[KW_FLOCK_BINDING_AGENTS], bytes_of(agents)));
        // The state and the motion of the last frame (record()'s, which the application and
        // the birds' kernel read) set aside and put back after: the flock is left as it was.
        const compute::Buffer& states = buffers_[KW_FLOCK_BINDING_STATES];
        const compute::Buffer& motion = buffers_[KW_FLOCK_BINDING_MOTION];
        const std::uint64_t motion_bytes = std::uint64_t{count_} * sizeof(gpu::BirdMotionGpu);
        auto saved = compute::Buffer::create(*device_, states.size() + motion_bytes, compute::Usage::Storage);
        if (!saved) return saved.error();
        const std::uint32_t slot = slot_;
        const compute::Queue queue(*device_);
        const auto copy = [&](bool back) -> Result<void> {
            auto recording = queue.begin();
            if (!recording) return recording.error();
            compute::Recording& rec = recording.value();
            compute::barrier(rec, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Transfer);
            if (back) {
                compute::copy(rec, saved.value(), 0, states, 0, states.size());
                compute::copy(rec, saved.value(), states.size(), motion, 0, motion_bytes);
            } else {
                compute::copy(rec, states, 0, saved.value(), 0, states.size());
                compute::copy(rec, motion, 0, saved.value(), states.size(), motion_bytes);
            }
            compute::barrier(rec, compute::Stage::Transfer, compute::Stage::Compute | compute::Stage::Transfer);
            auto submission = queue.submit(std::move(recording).value());
            if (!submission) return submission.error();
            return submission.value().wait();
        };
        KW_TRY(copy(false));
        double seconds[3] = {};
        const Part parts[3] = {Part::Grid, Part::Search, Part::Step};
        for (int p = 0; p < 3; ++p) {
            auto recording = queue.begin();
            if (!recording) return recording.error();
            compute::Recording& rec = recording.value();
            rec.timestamp(compute::Timestamp::Begin);
            for (std::uint32_t k = 0; k < frames; ++k) {
                record_frame(rec, 0, static_cast<std::uint32_t>(flocks.size()), static_cast<std::uint32_t>(agents.size()), parts[p]);
            }
            rec.timestamp(compute::Timestamp::End);
            const auto start = std::chrono::steady_clock::now();
            auto submission = queue.submit(std::move(recording).value());
            if (!submission) return submission.error();
            double ms = -1.0;
            KW_TRY(submission.value().wait(&ms));
            seconds[p] = ms >= 0.0 ? ms / 1000.0 : std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
        KW_TRY(copy(true));
        slot_ = slot;  // (each pass that steps flips it frames x substeps times: back where it was)
        FlockingTiming t;
        t.grid_seconds = seconds[0];
        t.search_seconds = std::max(seconds[1] - seconds[0], 0.0);
        t.rules_seconds = std::max(seconds[2] - seconds[1], 0.0);
        t.bird_steps = std::uint64_t{count_} * w.substeps * frames;
        t.device_seconds = device_->info().timestamps ? seconds[2] : -1.0;
        return t;
    }
    FlockingTiming timing() const override { return timing_; }

    std::string device() const override { return device_->info().name; }
    std::uint32_t validation_messages() const override { return device_->validation_messages(); }

private:
    // What record_frame() records per substep: the grid's passes, and the search alone
    // or the whole step (profile()).
    enum class Part { Grid, Search, Step };

    // The substeps of the k-th frame of a recording: per substep the grid's six passes
    // and the birds' step; the frame's motion goes to motion slot k, its flocks and
    // agents are at k x flocks and k x agents.
    void record_frame(compute::Recording& rec, std::uint32_t k, std::uint32_t flocks, std::uint32_t agents, Part part = Part::Step) {
        const FlockWorld& w = *world_;
        const std::uint32_t groups_birds = compute::groups_for(count_, workgroup_);
        const std::uint32_t groups_grid = (count_ + KW_FLOCK_SCAN_SIZE - 1) / KW_FLOCK_SCAN_SIZE;
        const std::uint32_t groups_buckets = (w.buckets + KW_FLOCK_SCAN_SIZE - 1) / KW_FLOCK_SCAN_SIZE;
        const std::uint32_t tiles = scan_tiles(w);
        for (std::uint32_t s = 0; s < w.substeps; ++s) {
            gpu::FlockPush push{};
            push.counts = {count_, w.buckets - 1u, agents, KW_FLOCK_PASS_CLEAR};
            push.slots = {slot_, k, w.substeps, s};
            push.bases = {k * flocks, k * agents, 0u, 0u};
            push.step = {w.dt, 1.0f / w.search_radius, w.gravity, w.frame_dt};
            const auto dispatch = [&](const compute::Kernel& kernel, std::uint32_t pass, std::uint32_t groups) {
                // Each pass reads what the previous one (or the last submission's copy,
                // upload or step) wrote.
                compute::barrier(rec, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
                push.counts.w = pass;
                kernel.dispatch(rec, std::as_bytes(std::span(&push, 1)), groups);
            };
            dispatch(*grid_, KW_FLOCK_PASS_CLEAR, groups_buckets);
            dispatch(*grid_, KW_FLOCK_PASS_COUNT, groups_grid);
            dispatch(*grid_, KW_FLOCK_PASS_SCAN_TILES, tiles);
            dispatch(*grid_, KW_FLOCK_PASS_SCAN_TOP, 1);
            dispatch(*grid_, KW_FLOCK_PASS_SCAN_DOWN, tiles);
            dispatch(*grid_, KW_FLOCK_PASS_SCATTER, groups_grid);
            if (part == Part::Grid) continue;  // the state unchanged: the same grid next time
            dispatch(part == Part::Search ? *search_only_ : *step_, 0u, groups_birds);
            slot_ = 1u - slot_;
        }
    }

    // The grid scan's tiles (flock_grid.comp): a workgroup each.
    static std::uint32_t scan_tiles(const FlockWorld& w) { return (w.buckets + KW_FLOCK_SCAN_TILE - 1) / KW_FLOCK_SCAN_TILE; }

    // The most agents a frame has: the scene's and the application's.
    std::size_t agent_capacity() const { return world_->scene_agents() + kMaxFlockAgents; }

    // Binding `b` at least `bytes` long (no submission is pending: each is waited for).
    Result<void> grow(std::uint32_t b, std::uint64_t bytes) {
        if (buffers_[b].size() >= bytes) return {};
        if (bytes > device_->info().max_storage_buffer_range) {
            return make_error(Error::Kind::Unsupported, device_->info().name + ": the flocking binding " + std::to_string(b) + " needs " +
                                                            std::to_string(bytes) + " bytes, more than maxStorageBufferRange");
        }
        auto buffer = compute::Buffer::create(*device_, bytes, compute::Usage::Storage);
        if (!buffer) return buffer.error();
        buffers_[b] = std::move(buffer).value();
        bind();
        return {};
    }
    void bind() {
        std::vector<const compute::Buffer*> bound;
        for (const auto& b : buffers_) bound.push_back(&b);
        grid_->bind(bound);
        step_->bind(bound);
        search_only_->bind(bound);
    }

    std::shared_ptr<compute::Device> device_;
    std::optional<compute::Kernel> grid_, step_, search_only_;
    FlockingTiming timing_;  // advance()'s device time
    std::vector<compute::Buffer> buffers_;
    std::optional<compute::StagingRing> ring_;  // record()'s per-frame uploads
    const FlockWorld* world_ = nullptr;
    std::uint32_t count_ = 0;
    std::uint32_t slot_ = 0;  // the state slot the next substep reads
    std::uint32_t workgroup_ = KW_FLOCK_WORKGROUP_SIZE;  // flock_step's invocations per workgroup
};

}  // namespace

Result<std::unique_ptr<FlockBackend>> make_vulkan_flock_backend(const BackendOptions& options) {
    auto device = backend_context(options);
    if (!device) return device.error();
    auto workgroup = compute::workgroup_size(*device.value(), options.workgroup_size, KW_FLOCK_WORKGROUP_SIZE);
    if (!workgroup) return workgroup.error();
    auto backend = std::make_unique<VulkanFlockBackend>(std::move(device).value(), workgroup.value());
    KW_TRY(backend->create_kernels());
    return std::unique_ptr<FlockBackend>(std::move(backend));
}

}  // namespace kodawari::flocking
