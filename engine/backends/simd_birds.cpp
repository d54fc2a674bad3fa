// The cpu bird backend: engine/simd/birds_simd.cpp's kernel on every core. It keeps the
// birds in its own structure-of-arrays layout (simd/birds_simd.hpp: batches of 16 birds
// of one route) with their state, and writes each frame's poses straight into the
// caller's frames x birds array. Threads take contiguous ranges of whole batches; each
// bird's state and output rows belong to one thread.
#include <algorithm>
#include <string>
#include <vector>

#include <hwy/aligned_allocator.h>

#include "backends/backends.hpp"
#include "core/parallel.hpp"
#include "kodawari/birds/flight.hpp"
#include "simd/birds_simd.hpp"

namespace kodawari {
namespace {

using simd::kBatchLanes;

class SimdBirdBackend final : public BirdBackend {
public:
    SimdBirdBackend(simd::Isa isa, unsigned threads)
        : isa_(std::move(isa)), threads_(threads), kernels_(simd::bird_kernels(isa_.target)) {}

    std::string_view name() const override { return "cpu"; }
    std::string device() const override {
        return std::to_string(threads_) + (threads_ == 1 ? " thread, " : " threads, ") + isa_.name;
    }

    Result<void> load(const birds::BirdWorld& world) override {
        world_ = &world;
        uniforms_ = world.uniforms();
        frame_ = 0;
        // Batches: each route's birds in world order, 16 at a time.
        batches_.clear();
        std::vector<std::vector<std::uint32_t>> by_route(world.routes.size());
        for (std::uint32_t i = 0; i < world.birds.size(); ++i) by_route[world.birds[i].ids.x].push_back(i);
        for (std::uint32_t r = 0; r < by_route.size(); ++r) {
            for (std::size_t first = 0; first < by_route[r].size(); first += kBatchLanes) {
                simd::BirdBatch b;
                b.route = r;
                b.count = static_cast<std::uint32_t>(std::min(kBatchLanes, by_route[r].size() - first));
                for (std::size_t l = 0; l < kBatchLanes; ++l) b.bird[l] = by_route[r][first + (l < b.count ? l : 0)];
                batches_.push_back(b);
            }
        }
        storage_ = hwy::AllocateAligned<float>(std::max<std::size_t>(1, batches_.size() * simd::kBirdRows * kBatchLanes));
        const gpu::BirdState initial = birds::initial_state();
        for (std::size_t b = 0; b < batches_.size(); ++b) {
            float* rows = storage_.get() + b * simd::kBirdRows * kBatchLanes;
            for (std::size_t l = 0; l < kBatchLanes; ++l) {
                const gpu::BirdParams& p = world.birds[batches_[b].bird[l]];
                const float values[simd::kBirdPose] = {
                    p.offset.x,       p.offset.y,       p.offset.z,       p.offset.w,       p.motion.x,      p.motion.y,
                    p.motion.z,       p.motion.w,       p.flight.x,       p.flight.y,       p.flight.z,      p.flight.w,
                    p.shape.x,        initial.blend.x,  initial.blend.y,  initial.blend.z,  initial.blend.w, initial.blend2.x,
                    initial.blend2.y, initial.blend2.z, initial.blend2.w, initial.phase.x,  initial.phase.y, initial.phase.z,
                    -1.0f /* KW_MODE_UNSET */,
                    initial.roll.x,   initial.roll.y,   initial.roll.z};
                for (std::size_t r = 0; r < simd::kBirdPose; ++r) rows[r * kBatchLanes + l] = values[r];
                for (std::size_t r = simd::kBirdPose; r < simd::kBirdRows; ++r) rows[r * kBatchLanes + l] = 0.0f;
            }
        }
        return {};
    }

    Result<void> simulate(std::uint32_t frames, FrameOutput out) override {
        assert(world_ != nullptr && "load() first");
        const std::size_t count = world_->birds.size();
        assert(out.poses.empty() || out.poses.size() == frames * count);
        assert(out.diag.empty() || out.diag.size() == frames * count);
        simd::BirdStepArgs args;
        args.uniforms = uniforms_;
        args.routes = world_->routes.data();
        args.control_points = world_->control_points.data();
        args.arc_samples = world_->arc_samples.data();
        args.batches = batches_.data();
        args.storage = storage_.get();
        args.poses = out.poses.empty() ? nullptr : out.poses.data();
        args.diag = out.diag.empty() ? nullptr : out.diag.data();
        args.birds = count;
        KW_TRY(check_motion(*world_, frames));
        args.params = world_->birds.data();
        args.motion = motion_.data();
        args.driven = world_->driven;
        args.first_frame = frame_;
        args.frames = frames;
        parallel_for(batches_.size(), threads_, [&](std::size_t begin, std::size_t end) { kernels_.simulate(args, begin, end); });
        frame_ += frames;
        return {};
    }

private:
    simd::Isa isa_;
    unsigned threads_;
    simd::BirdKernels kernels_;
    const birds::BirdWorld* world_ = nullptr;
    gpu::FlightUniforms uniforms_{};
    std::vector<simd::BirdBatch> batches_;
    hwy::AlignedFreeUniquePtr<float[]> storage_;
    std::uint32_t frame_ = 0;
};

}  // namespace

std::unique_ptr<BirdBackend> new_simd_bird_backend(simd::Isa isa, unsigned threads) {
    return std::make_unique<SimdBirdBackend>(std::move(isa), threads);
}

}  // namespace kodawari
