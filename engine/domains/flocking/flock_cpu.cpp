// The flocking step on the CPU: the grid (flock_grid.comp's passes as one counting sort in
// bird order) and shaders/lib/flock_body.glsl compiled as C++ (flock_kernel.hpp), bird
// after bird on one thread (cpu-reference) or over the cpu backend's threads (cpu: the
// same body per bird, so the same bits).
#include "domains/flocking/flock_kernel.hpp"

#include <algorithm>
#include <bit>

namespace kodawari::flocking {

std::uint32_t bucket_count(std::uint32_t birds) {
    const std::uint32_t wanted = std::max<std::uint32_t>(2u * birds, KW_FLOCK_SCAN_SIZE);
    return std::bit_ceil(wanted);
}

void build_grid(std::span<const gpu::FlockStateGpu> states, float inv_radius, std::uint32_t mask, std::vector<std::uint32_t>& cells,
                std::vector<std::uint32_t>& buckets, std::vector<std::uint32_t>& sorted) {
    const std::size_t n = states.size();
    cells.resize(n);
    buckets.assign(2 * (std::size_t{mask} + 1), 0u);
    sorted.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        cells[i] = glsl::flock_bucket(glsl::kw_xyz(states[i].position), inv_radius, mask);
        buckets[2 * cells[i] + 1] += 1;
    }
    std::uint32_t start = 0;
    for (std::size_t b = 0; b <= mask; ++b) {
        buckets[2 * b] = start;
        start += buckets[2 * b + 1];
        buckets[2 * b + 1] = 0;
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t b = cells[i];
        sorted[buckets[2 * b] + buckets[2 * b + 1]++] = static_cast<std::uint32_t>(i);
    }
}

}  // namespace kodawari::flocking

#include <string>

#include "core/parallel.hpp"
#include "domains/flocking/flock_backend.hpp"

namespace kodawari::flocking {

namespace {

class CpuFlockBackend final : public FlockBackend {
public:
    explicit CpuFlockBackend(unsigned threads) : threads_(threads) {}

    Result<void> load(const FlockWorld& world) override {
        world_ = &world;
        state_ = world.initial;
        next_.resize(state_.size());
        return {};
    }

    Result<void> advance(std::uint32_t frames, std::span<const gpu::FlockParamsGpu> flocks, std::span<const gpu::FlockAgentGpu> agents,
                         std::span<gpu::BirdMotionGpu> out) override {
        const FlockWorld& w = *world_;
        const std::size_t n = state_.size(), f_count = w.flocks.size(), a_count = frames > 0 ? agents.size() / frames : 0;
        const std::uint32_t mask = w.buckets - 1u;
        const float inv_radius = 1.0f / w.search_radius;
        for (std::uint32_t k = 0; k < frames; ++k) {
            for (std::uint32_t s = 0; s < w.substeps; ++s) {
                build_grid(state_, inv_radius, mask, cells_, buckets_, sorted_);
                glsl::Kernel kernel{flocks.subspan(k * f_count, f_count), w.birds, state_, buckets_, sorted_,
                                          agents.subspan(k * a_count, a_count)};
                const bool last = s + 1 == w.substeps;
                gpu::BirdMotionGpu* motion = out.data() + std::size_t{k} * n;
                parallel_for(n, threads_, [&](std::size_t begin, std::size_t end) {
                    for (std::size_t i = begin; i < end; ++i) {
                        const auto b = static_cast<std::uint32_t>(i);
                        const glsl::Kernel::FlockStep step =
                            kernel.flock_step_bird(b, mask, static_cast<std::uint32_t>(a_count), w.dt, inv_radius);
                        next_[i].position = {step.position.x, step.position.y, step.position.z, 0.0f};
                        next_[i].velocity = {step.velocity.x, step.velocity.y, step.velocity.z, 0.0f};
                        if (last) {
                            motion[i].position = next_[i].position;
                            motion[i].velocity = next_[i].velocity;
                            motion[i].acceleration = {step.acceleration.x, step.acceleration.y, step.acceleration.z, 0.0f};
                        }
                    }
                });
                state_.swap(next_);
            }
        }
        return {};
    }

    std::string device() const override { return std::to_string(threads_) + (threads_ == 1 ? " thread" : " threads"); }

private:
    unsigned threads_;
    const FlockWorld* world_ = nullptr;
    std::vector<gpu::FlockStateGpu> state_, next_;
    std::vector<std::uint32_t> cells_, buckets_, sorted_;
};

}  // namespace

std::unique_ptr<FlockBackend> make_cpu_flock_backend(unsigned threads) { return std::make_unique<CpuFlockBackend>(threads); }

}  // namespace kodawari::flocking
