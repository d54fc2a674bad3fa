// The cpu-reference bird backend: engine/birds/flight.cpp bird after bird on one thread,
// the validation oracle. (The cpu backend is simd_birds.cpp.)
#include "backends/backends.hpp"

#include <string>
#include <vector>

#include "kodawari/birds/flight.hpp"

namespace kodawari {
namespace {

class CpuBirdBackend final : public BirdBackend {
public:
    std::string_view name() const override { return "cpu-reference"; }
    std::string device() const override { return "1 thread"; }

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
        KW_TRY(check_motion(*world_, frames));
        for (std::size_t i = 0; i < count; ++i) {
            const gpu::BirdParams& bird = world_->birds[i];
            gpu::BirdState& state = states_[i];
            for (std::uint32_t k = 0; k < frames; ++k) {
                const gpu::BirdMotionGpu* motion =
                    bird.ids.w == KW_BIRD_DRIVEN ? &motion_[std::size_t{k} * world_->driven + bird.ids.z] : nullptr;
                const birds::BirdFrame f = birds::step_bird(*world_, uniforms_, bird, state, frame_ + k, motion);
                const std::size_t slot = k * count + i;
                // Without an output the pose still goes to memory, as on the GPU.
                (out.poses.empty() ? scratch_[i] : out.poses[slot]) = f.pose;
                if (!out.diag.empty()) out.diag[slot] = f.diag;
            }
        }
        frame_ += frames;
        return {};
    }

private:
    const birds::BirdWorld* world_ = nullptr;
    gpu::FlightUniforms uniforms_{};
    std::vector<gpu::BirdState> states_;
    std::vector<gpu::BirdPose> scratch_;
    std::uint32_t frame_ = 0;
};

}  // namespace

std::unique_ptr<BirdBackend> new_reference_bird_backend() { return std::make_unique<CpuBirdBackend>(); }

}  // namespace kodawari
