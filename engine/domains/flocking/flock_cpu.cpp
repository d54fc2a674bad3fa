// The flocking step on the CPU: the grid (flock_grid.comp's passes as one counting sort in
// bird order) and shaders/lib/flock_body.glsl compiled as C++ (flock_kernel.hpp), bird
// after bird on one thread (cpu-reference) or over the cpu backend's threads, where the
// neighbour search is the hand-tuned one of flock_search_simd.cpp (the same lists, so the
// same bits) and the rules the shared body.
#include "domains/flocking/flock_kernel.hpp"

#include <algorithm>
#include <bit>

#include "core/parallel.hpp"

namespace kodawari::flocking {

std::uint32_t bucket_count(std::uint32_t birds) {
    const std::uint32_t wanted = std::max<std::uint32_t>(2u * birds, KW_FLOCK_SCAN_SIZE);
    return std::bit_ceil(wanted);
}

void build_grid(std::span<const gpu::FlockStateGpu> states, float inv_radius, std::uint32_t mask, std::vector<std::uint32_t>& cells,
                std::vector<std::uint32_t>& buckets, std::vector<std::uint32_t>& sorted, unsigned threads, BucketsFn find) {
    const std::size_t n = states.size();
    cells.resize(n);
    buckets.assign(2 * (std::size_t{mask} + 1), 0u);
    sorted.resize(n);
    constexpr std::size_t kThreadedFrom = 65536;
    parallel_for(n, n < kThreadedFrom ? 1u : threads, [&](std::size_t begin, std::size_t end) {
        if (find != nullptr) {
            find(states.subspan(begin, end - begin), inv_radius, mask, cells.data() + begin);
            return;
        }
        for (std::size_t i = begin; i < end; ++i) cells[i] = glsl::flock_bucket(glsl::kw_xyz(states[i].position), inv_radius, mask);
    });
    // The counting sort on one thread: a stable order by bird index within a bucket. (The
    // same sort with each thread over its own range of the table, reading every bird's
    // bucket, gained 1% at a million birds on 2 threads: not kept.)
    // The birds' buckets lie anywhere in the table (16 MB at a million birds): each one's
    // entry asked for kAhead birds before it is counted or placed.
    constexpr std::size_t kAhead = 16;
    for (std::size_t i = 0; i < n; ++i) {
        if (i + kAhead < n) __builtin_prefetch(&buckets[2 * std::size_t{cells[i + kAhead]}], 1);
        buckets[2 * cells[i] + 1] += 1;
    }
    std::uint32_t start = 0;
    for (std::size_t b = 0; b <= mask; ++b) {
        buckets[2 * b] = start;
        start += buckets[2 * b + 1];
        buckets[2 * b + 1] = 0;
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (i + kAhead < n) __builtin_prefetch(&buckets[2 * std::size_t{cells[i + kAhead]}], 1);
        const std::uint32_t b = cells[i];
        sorted[buckets[2 * b] + buckets[2 * b + 1]++] = static_cast<std::uint32_t>(i);
    }
}

}  // namespace kodawari::flocking

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "domains/flocking/flock_backend.hpp"
#include "domains/flocking/flock_rules.hpp"
#include "domains/flocking/flock_search.hpp"
#include "simd/isa.hpp"

namespace kodawari::flocking {

namespace {

class CpuFlockBackend final : public FlockBackend {
public:
    /// `isa`: the cpu backend's instruction set, whose hand-tuned search it runs; none:
    /// cpu-reference, flock_body.glsl's search.
    CpuFlockBackend(unsigned threads, std::optional<simd::Isa> isa)
        : threads_(threads),
          isa_(std::move(isa)),
          search_(isa_ ? flock_search_kernel(isa_->target) : nullptr),
          rules_(isa_ ? flock_rules_kernel(isa_->target) : nullptr),
          buckets_fn_(isa_ ? flock_buckets_kernel(isa_->target) : nullptr) {}

    Result<void> load(const FlockWorld& world) override {
        world_ = &world;
        timing_ = {};
        state_ = world.initial;
        next_.resize(state_.size());
        // No bounds yet: the first substep's searches take every bird's whole radius.
        bounds_.clear();
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
                const auto grid_start = Clock::now();
                const auto frame_flocks = flocks.subspan(k * f_count, f_count);
                build_grid(state_, inv_radius, mask, cells_, buckets_, sorted_, threads_, buckets_fn_);
                if (search_ != nullptr) {
                    sorted_birds_.fill(state_, w.birds, frame_flocks, sorted_, threads_, bounds_);
                    bounds_.resize(n);  // every slot written by the search
                }
                timing_.grid_seconds += seconds(grid_start, Clock::now());
                glsl::Kernel kernel{frame_flocks, w.birds, state_, buckets_, sorted_, agents.subspan(k * a_count, a_count), w.perches_of};
                const SearchArgs search_args{&kernel, &sorted_birds_, mask, inv_radius, bounds_.data()};
                const RulesArgs rules_args{&kernel, &sorted_birds_, static_cast<std::uint32_t>(a_count), w.dt};
                const bool last = s + 1 == w.substeps;
                gpu::BirdMotionGpu* motion = out.data() + std::size_t{k} * n;
                const auto agent_count = static_cast<std::uint32_t>(a_count);
                // cpu-reference goes bird after bird; the cpu backend in the grid's order,
                // where birds of a cell come together (flock_search.hpp).
                if (search_ == nullptr && order_.size() != n) {
                    order_.resize(n);
                    for (std::size_t i = 0; i < n; ++i) order_[i] = static_cast<std::uint32_t>(i);
                }
                const std::uint32_t* order = search_ != nullptr ? sorted_.data() : order_.data();
                // Blocks of kBlock birds, each thread taking the next block not taken:
                // a bird's cost follows the flock's density round it (its candidates),
                // so equal shares of the grid's order may end apart (a million birds on
                // 2 threads: 1.06x with this; 10 000: 1.00x). A bird's result does not
                // depend on which thread steps it, nor on the blocks' order: the same bits.
                const std::size_t blocks = (n + kBlock - 1) / kBlock;
                std::atomic<std::size_t> next_block{0};
                parallel_for(std::min<std::size_t>(threads_, blocks), threads_, [&](std::size_t, std::size_t) {
                    // Per block: every bird's neighbours, then every bird's rules, each
                    // phase timed (two clock reads a block of 256 birds).
                    std::vector<glsl::Kernel::FlockNeighbours> found(kBlock);
                    std::vector<glsl::Kernel::FlockStep> steps(kBlock);
                    double search = 0.0, rules = 0.0;
                    for (std::size_t block = next_block.fetch_add(1, std::memory_order_relaxed); block < blocks;
                         block = next_block.fetch_add(1, std::memory_order_relaxed)) {
                        const std::size_t b0 = block * kBlock, b1 = std::min(n, b0 + kBlock);
                        const auto t0 = Clock::now();
                        if (search_ != nullptr) {
                            search_(search_args, static_cast<std::uint32_t>(b0), static_cast<std::uint32_t>(b1 - b0), found.data());
                        } else {
                            for (std::size_t o = b0; o < b1; ++o) found[o - b0] = kernel.flock_neighbours(order[o], mask, inv_radius);
                        }
                        const auto t1 = Clock::now();
                        if (rules_ != nullptr) {
                            rules_(rules_args, static_cast<std::uint32_t>(b0), static_cast<std::uint32_t>(b1 - b0), found.data(), steps.data());
                        } else {
                            for (std::size_t o = b0; o < b1; ++o) steps[o - b0] = kernel.flock_rules(order[o], found[o - b0], agent_count, w.dt);
                        }
                        for (std::size_t o = b0; o < b1; ++o) {
                            // The writes below go by index (anywhere in the arrays): their
                            // lines asked for a few birds ahead.
                            if (o + 8 < b1) {
                                __builtin_prefetch(&next_[order[o + 8]], 1);
                                if (last) __builtin_prefetch(&motion[order[o + 8]], 1);
                            }
                            const std::uint32_t i = order[o];
                            // Perches (flock_body.glsl): a bird on its perch or landing is not
                            // stepped, and a flying one leaves the flock to land on a frame's
                            // first substep. Asked only in a world with perches (each bird's
                            // constants and state read by index again).
                            const gpu::FlockBirdGpu& bird = w.birds[i];
                            gpu::FlockStateGpu kept = w.perches ? state_[i] : gpu::FlockStateGpu{};
                            if (w.perches && !kernel.flock_stepped(bird, w.perches_of[i], kernel.flocks[bird.ids.x], kept, s, w.frame_dt)) {
                                // On its perch or landing: its state kept, its route's motion
                                // (the search and rules above are not used).
                                next_[i] = kept;
                                if (last) {
                                    const auto m = kernel.flock_route_motion(bird, w.perches_of[i], kept);
                                    motion[i] = {gpu4(m.position), gpu4(m.velocity), gpu4(m.acceleration)};
                                }
                                continue;
                            }
                            const glsl::Kernel::FlockStep& step = steps[o - b0];
                            next_[i].position = {step.position.x, step.position.y, step.position.z, 0.0f};
                            next_[i].velocity = {step.velocity.x, step.velocity.y, step.velocity.z, 0.0f};
                            if (last) {
                                motion[i].position = next_[i].position;
                                motion[i].velocity = next_[i].velocity;
                                motion[i].acceleration = {step.acceleration.x, step.acceleration.y, step.acceleration.z, 0.0f};
                            }
                        }
                        const auto t2 = Clock::now();
                        search += seconds(t0, t1);
                        rules += seconds(t1, t2);
                    }
                    const std::lock_guard lock(timing_mutex_);
                    timing_.search_seconds += search;
                    timing_.rules_seconds += rules;
                });
                timing_.bird_steps += n;
                state_.swap(next_);
            }
        }
        return {};
    }

    std::string device() const override {
        return std::to_string(threads_) + (threads_ == 1 ? " thread" : " threads") + (isa_ ? ", " + isa_->name : std::string());
    }
    FlockingTiming timing() const override { return timing_; }

private:
    using Clock = std::chrono::steady_clock;
    static double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }
    static gpu::vec4 gpu4(const glm::vec4& v) { return {v.x, v.y, v.z, v.w}; }
    static constexpr std::size_t kBlock = 256;

    unsigned threads_;
    std::optional<simd::Isa> isa_;
    SearchFn search_;
    RulesFn rules_;  // the cpu backend's hand-tuned rules; cpu-reference runs the body's
    BucketsFn buckets_fn_;  // the cpu backend's birds' buckets, a vector at a time; cpu-reference: flock_bucket()
    SortedBirds sorted_birds_;  // the hand-tuned search's copy of the grid
    std::vector<float> bounds_;  // the hand-tuned search's k-th distances of last time, by slot (SearchArgs::bounds)
    const FlockWorld* world_ = nullptr;
    std::vector<gpu::FlockStateGpu> state_, next_;
    std::vector<std::uint32_t> cells_, buckets_, sorted_;
    std::vector<std::uint32_t> order_;  // cpu-reference's: 0, 1, 2, ...
    FlockingTiming timing_;
    std::mutex timing_mutex_;
};

}  // namespace

std::unique_ptr<FlockBackend> make_reference_flock_backend() { return std::make_unique<CpuFlockBackend>(1, std::nullopt); }

Result<std::unique_ptr<FlockBackend>> make_cpu_flock_backend(const BackendOptions& options) {
    auto isa = simd::choose_isa(options.isa);
    if (!isa) return isa.error();
    return std::unique_ptr<FlockBackend>(std::make_unique<CpuFlockBackend>(cpu_backend_threads(options), std::move(isa).value()));
}

}  // namespace kodawari::flocking
