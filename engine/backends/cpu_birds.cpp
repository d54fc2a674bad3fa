// The CPU backends: "cpu-reference" runs engine/birds/flight.cpp bird after bird on one
// thread (the validation oracle); "cpu" runs the same code on several threads, each
// over a fixed range of birds, so both produce the same bits.
#include "backends/backends.hpp"

#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "kodawari/birds/flight.hpp"

namespace kodawari {
namespace {

class CpuBirdBackend final : public BirdBackend {
public:
    CpuBirdBackend(bool reference, unsigned threads) : reference_(reference), threads_(reference ? 1 : resolve_threads(threads)) {}

    std::string_view name() const override { return reference_ ? "cpu-reference" : "cpu"; }
    std::string device() const override { return std::to_string(threads_) + (threads_ == 1 ? " thread" : " threads"); }

    Result<void> load(const birds::BirdWorld& world) override {
        world_ = &world;
        uniforms_ = world.uniforms();
        states_.assign(world.birds.size(), birds::initial_state());
        scratch_.resize(world.birds.size());
        frame_ = 0;
        return {};
    }

    Result<void> simulate(std::uint32_t frames, FrameOutput out) override {
        assert(world_ != nullptr && "load() first");
        const std::size_t count = world_->birds.size();
        assert(out.poses.empty() || out.poses.size() == frames * count);
        assert(out.diag.empty() || out.diag.size() == frames * count);
        auto run = [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                const gpu::BirdParams& bird = world_->birds[i];
                gpu::BirdState& state = states_[i];
                for (std::uint32_t k = 0; k < frames; ++k) {
                    const birds::BirdFrame f = birds::step_bird(*world_, uniforms_, bird, state, frame_ + k);
                    const std::size_t slot = k * count + i;
                    // Without an output the pose still goes to memory, as on the GPU.
                    (out.poses.empty() ? scratch_[i] : out.poses[slot]) = f.pose;
                    if (!out.diag.empty()) out.diag[slot] = f.diag;
                }
            }
        };
        if (reference_) {
            run(0, count);
        } else {
            parallel_for(count, threads_, run);
        }
        frame_ += frames;
        return {};
    }

private:
    bool reference_;
    unsigned threads_;
    const birds::BirdWorld* world_ = nullptr;
    gpu::FlightUniforms uniforms_{};
    std::vector<gpu::BirdState> states_;
    std::vector<gpu::BirdPose> scratch_;
    std::uint32_t frame_ = 0;
};

}  // namespace

std::unique_ptr<BirdBackend> new_cpu_bird_backend(bool reference, unsigned threads) {
    return std::make_unique<CpuBirdBackend>(reference, threads);
}

}  // namespace kodawari
