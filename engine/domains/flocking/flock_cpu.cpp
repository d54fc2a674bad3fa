// The flocking step on the CPU: the grid (flock_grid.comp's passes as one counting sort in
// bird order) and shaders/lib/flock_body.glsl compiled as C++ (flock_kernel.hpp), bird
// after bird on one thread (cpu-reference) or over the cpu backend's threads, where the
// neighbour search is the hand-tuned one of flock_search_simd.cpp (the same lists, so the
// same bits) and the rules the shared body's, hand-tuned (flock_rules_simd.cpp).
//
// The cpu backend keeps each bird's state at its slot of the last grid (SlotStates), not
// by index: a thread steps the same share of slots substep after substep, and writes,
// sorts and reads the states of those birds in its own cache, where by index two
// threads' birds share cache lines (10 000 birds on 2 threads: the grid's copy took 95 us
// a substep by index, 21 by slot with the pool's workers awake, docs/performance.md).
#include "domains/flocking/flock_kernel.hpp"

#include <algorithm>
#include <atomic>
#include <bit>

#include "core/parallel.hpp"

namespace kodawari::flocking {

std::uint32_t bucket_count(std::uint32_t birds) {
    const std::uint32_t wanted = std::max<std::uint32_t>(2u * birds, KW_FLOCK_SCAN_SIZE);
    return std::bit_ceil(wanted);
}

namespace {

// The counting sort of build_grid() and build_grid_slots(): `buckets` (start, count) for
// the birds' `cells`, each one's place handed to place(at, bird) in the order given
// (stable). The birds' buckets lie anywhere in the table (16 MB at a million birds): each
// one's entry asked for kAhead birds before it is counted or placed.
template <typename Place>
void counting_sort(std::span<const std::uint32_t> cells, std::uint32_t mask, std::vector<std::uint32_t>& buckets, Place&& place) {
    const std::size_t n = cells.size();
    buckets.assign(2 * (std::size_t{mask} + 1), 0u);
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
        place(buckets[2 * b] + buckets[2 * b + 1]++, static_cast<std::uint32_t>(i));
    }
}

}  // namespace

void build_grid(std::span<const gpu::FlockStateGpu> states, float inv_radius, std::uint32_t mask, std::vector<std::uint32_t>& cells,
                std::vector<std::uint32_t>& buckets, std::vector<std::uint32_t>& sorted) {
    const std::size_t n = states.size();
    cells.resize(n);
    sorted.resize(n);
    for (std::size_t i = 0; i < n; ++i) cells[i] = glsl::flock_bucket(glsl::kw_xyz(states[i].position), inv_radius, mask);
    // A stable order by bird index within a bucket.
    counting_sort(cells, mask, buckets, [&](std::uint32_t at, std::uint32_t i) { sorted[at] = i; });
}

void build_grid_slots(const float* x, const float* y, const float* z, std::span<const std::uint32_t> index, float inv_radius,
                      std::uint32_t mask, BucketsFn find, unsigned threads, std::vector<std::uint32_t>& cells,
                      std::vector<std::uint32_t>& buckets, std::vector<std::uint32_t>& sorted, std::vector<std::uint32_t>& perm,
                      std::vector<std::uint32_t>& slot_of) {
    const std::size_t n = index.size();
    cells.resize(n);
    sorted.resize(n);
    perm.resize(n);
    slot_of.resize(n);
    // Each thread the share of slots it stepped (flock_cpu.cpp's blocks): their positions
    // are in its cache.
    std::atomic<bool> not_finite{false};
    parallel_for(n, threads, [&](std::size_t begin, std::size_t end) {
        if (find(x + begin, y + begin, z + begin, end - begin, inv_radius, mask, cells.data() + begin)) not_finite.store(true);
    });
    counting_sort(cells, mask, buckets, [&](std::uint32_t at, std::uint32_t t) { perm[at] = t; });
    // A bucket's birds come in their old slots' order, which is the last grid's. The
    // search's result does not depend on it where every distance is a number (the k
    // nearest by distance, then index: a total order, flock_search.hpp), which every
    // distance between finite positions is (a square is at least 0, so an overflow gives
    // infinity, and infinities of one sign add up to one). A NaN distance's insertion
    // follows the visiting order, so where a position is NaN or infinite (rare) the grid
    // takes the reference's order, each bucket's run of slots sorted by bird index
    // (unique: one order). (Sorting every substep cost 49 us of a 10 000-bird substep's
    // 900 on one thread.)
    if (not_finite.load()) {
        for (std::size_t s = 0; s < n;) {
            const std::uint32_t cell = cells[perm[s]];
            std::size_t end = s + 1;
            while (end < n && cells[perm[end]] == cell) ++end;
            std::sort(perm.begin() + static_cast<std::ptrdiff_t>(s), perm.begin() + static_cast<std::ptrdiff_t>(end),
                      [&](std::uint32_t a, std::uint32_t b) { return index[a] < index[b]; });
            s = end;
        }
    }
    constexpr std::size_t kAhead = 16;
    for (std::size_t s = 0; s < n; ++s) {
        // slot_of by index, anywhere in it: its line asked for a few birds ahead.
        if (s + kAhead < n) __builtin_prefetch(&slot_of[index[perm[s + kAhead]]], 1);
        const std::uint32_t i = index[perm[s]];
        sorted[s] = i;
        slot_of[i] = static_cast<std::uint32_t>(s);
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
        const std::size_t n = world.initial.size();
        if (search_ == nullptr) {
            state_ = world.initial;
            next_.resize(n);
            return {};
        }
        // Before the first grid, slot t holds bird t; no bounds yet: the first substep's
        // searches take every bird's whole radius.
        stepped_.resize(n);
        for (std::size_t t = 0; t < n; ++t) stepped_.set(t, world.initial[t]);
        from_index_.resize(n);
        for (std::size_t t = 0; t < n; ++t) from_index_[t] = static_cast<std::uint32_t>(t);
        bounds_.clear();
        return {};
    }

    Result<void> advance(std::uint32_t frames, std::span<const gpu::FlockParamsGpu> flocks, std::span<const gpu::FlockAgentGpu> agents,
                         std::span<gpu::BirdMotionGpu> out) override {
        const FlockWorld& w = *world_;
        const std::size_t n = w.birds.size(), f_count = w.flocks.size(), a_count = frames > 0 ? agents.size() / frames : 0;
        for (std::uint32_t k = 0; k < frames; ++k) {
            const Frame frame{flocks.subspan(k * f_count, f_count), agents.subspan(k * a_count, a_count),
                              out.data() + std::size_t{k} * n};
            for (std::uint32_t s = 0; s < w.substeps; ++s) {
                if (search_ != nullptr) {
                    substep(frame, s);
                } else {
                    substep_reference(frame, s);
                }
                timing_.bird_steps += n;
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

    // One frame's inputs and where its motion goes (bird by index).
    struct Frame {
        std::span<const gpu::FlockParamsGpu> flocks;
        std::span<const gpu::FlockAgentGpu> agents;
        gpu::BirdMotionGpu* motion;
    };

    // What each block of birds hands back: its neighbours, then its steps.
    struct BlockScratch {
        std::vector<glsl::Kernel::FlockNeighbours> found = std::vector<glsl::Kernel::FlockNeighbours>(kBlock);
        std::vector<glsl::Kernel::FlockStep> steps = std::vector<glsl::Kernel::FlockStep>(kBlock);
    };

    // Calls body(b0, b1, scratch) for every block of kBlock birds [b0, b1) of n, with the
    // search's and the rules' time (body returns the split point's clock reading). Each
    // thread takes the blocks of its own equal share in order, then the ones left in the
    // others' shares: a bird's cost follows the flock's density round it, so equal shares
    // may end apart (a million birds on 2 threads: 1.06x with taking others' blocks;
    // 10 000: 1.00x), while a thread that keeps its share steps the birds whose states
    // it wrote last substep, in its own cache. A bird's result does not depend on which
    // thread steps it, nor on the blocks' order: the same bits.
    template <typename Body>
    void run_blocks(std::size_t n, Body&& body) {
        const std::size_t blocks = (n + kBlock - 1) / kBlock;
        const std::size_t parts = std::min<std::size_t>(threads_, blocks);
        std::vector<std::atomic<std::size_t>> next(parts);
        for (std::size_t p = 0; p < parts; ++p) next[p].store(blocks * p / parts);
        parallel_for(parts, threads_, [&](std::size_t me, std::size_t) {
            BlockScratch scratch;
            double search = 0.0, rules = 0.0;
            for (std::size_t share = 0; share < parts; ++share) {
                const std::size_t p = (me + share) % parts, end = blocks * (p + 1) / parts;
                for (std::size_t block = next[p].fetch_add(1, std::memory_order_relaxed); block < end;
                     block = next[p].fetch_add(1, std::memory_order_relaxed)) {
                    const std::size_t b0 = block * kBlock, b1 = std::min(n, b0 + kBlock);
                    const auto t0 = Clock::now();
                    const auto t1 = body(b0, b1, scratch);
                    const auto t2 = Clock::now();
                    search += seconds(t0, t1);
                    rules += seconds(t1, t2);
                }
            }
            const std::lock_guard lock(timing_mutex_);
            timing_.search_seconds += search;
            timing_.rules_seconds += rules;
        });
    }

    // cpu-reference: the grid by index and flock_body.glsl bird after bird.
    void substep_reference(const Frame& frame, std::uint32_t s) {
        const FlockWorld& w = *world_;
        const std::uint32_t mask = w.buckets - 1u;
        const float inv_radius = 1.0f / w.search_radius;
        const auto agent_count = static_cast<std::uint32_t>(frame.agents.size());
        const bool last = s + 1 == w.substeps;
        const auto grid_start = Clock::now();
        build_grid(state_, inv_radius, mask, cells_, buckets_, sorted_);
        timing_.grid_seconds += seconds(grid_start, Clock::now());
        glsl::Kernel kernel{frame.flocks, w.birds, state_, buckets_, sorted_, frame.agents, w.perches_of};
        run_blocks(state_.size(), [&](std::size_t b0, std::size_t b1, BlockScratch& scratch) {
            for (std::size_t i = b0; i < b1; ++i) {
                scratch.found[i - b0] = kernel.flock_neighbours(static_cast<std::uint32_t>(i), mask, inv_radius);
            }
            const auto split = Clock::now();
            for (std::size_t i = b0; i < b1; ++i) {
                const auto bird = static_cast<std::uint32_t>(i);
                gpu::FlockStateGpu kept = state_[i];
                if (!stepped(kernel, bird, kept, s)) {
                    next_[i] = kept;
                    if (last) frame.motion[i] = route_motion(kernel, bird, kept);
                    continue;
                }
                const glsl::Kernel::FlockStep step = kernel.flock_rules(bird, scratch.found[i - b0], agent_count, w.dt);
                next_[i] = {{step.position.x, step.position.y, step.position.z, 0.0f}, {step.velocity.x, step.velocity.y, step.velocity.z, 0.0f}};
                if (last) frame.motion[i] = motion_of(step);
            }
            return split;
        });
        state_.swap(next_);
    }

    // The cpu backend: birds held by slot (stepped_), the grid built from them, the
    // hand-tuned search and rules in the grid's order (flock_search.hpp), where birds of a
    // cell come together, and each bird's new state written at its slot.
    void substep(const Frame& frame, std::uint32_t s) {
        const FlockWorld& w = *world_;
        const std::size_t n = w.birds.size();
        const std::uint32_t mask = w.buckets - 1u;
        const float inv_radius = 1.0f / w.search_radius;
        const bool last = s + 1 == w.substeps;
        const auto grid_start = Clock::now();
        // Old slot t's bird: from_index_[t] (the last fill's index, or t before the first).
        if (!bounds_.empty()) std::swap(from_index_, sorted_birds_.index);
        const std::span<const std::uint32_t> from_index(from_index_.data(), n);
        build_grid_slots(stepped_.x.data(), stepped_.y.data(), stepped_.z.data(), from_index, inv_radius, mask, buckets_fn_, threads_,
                         cells_, buckets_, sorted_, perm_, sorted_birds_.slot_of);
        sorted_birds_.fill(stepped_, from_index, perm_, w.birds, frame.flocks, threads_, bounds_);
        bounds_.resize(n);  // every slot written by the search
        timing_.grid_seconds += seconds(grid_start, Clock::now());
        glsl::Kernel kernel{frame.flocks, w.birds, {}, buckets_, sorted_, frame.agents, w.perches_of};
        const SortedBirds& sorted = sorted_birds_;
        const SearchArgs search_args{&kernel, &sorted, mask, inv_radius, bounds_.data()};
        const RulesArgs rules_args{&kernel, &sorted, static_cast<std::uint32_t>(frame.agents.size()), w.dt};
        run_blocks(n, [&](std::size_t b0, std::size_t b1, BlockScratch& scratch) {
            const auto first = static_cast<std::uint32_t>(b0), count = static_cast<std::uint32_t>(b1 - b0);
            search_(search_args, first, count, scratch.found.data());
            const auto split = Clock::now();
            rules_(rules_args, first, count, scratch.found.data(), scratch.steps.data());
            for (std::size_t t = b0; t < b1; ++t) {
                // The motion goes by index (anywhere in the array): its lines asked for a
                // few birds ahead.
                if (last && t + 8 < b1) __builtin_prefetch(&frame.motion[sorted.index[t + 8]], 1);
                const std::uint32_t i = sorted.index[t];
                gpu::FlockStateGpu kept{{sorted.x[t], sorted.y[t], sorted.z[t], sorted.pw[t]},
                                        {sorted.vx[t], sorted.vy[t], sorted.vz[t], sorted.vw[t]}};
                if (!stepped(kernel, i, kept, s)) {
                    stepped_.set(t, kept);
                    if (last) frame.motion[i] = route_motion(kernel, i, kept);
                    continue;
                }
                const glsl::Kernel::FlockStep& step = scratch.steps[t - b0];
                stepped_.set(t, {{step.position.x, step.position.y, step.position.z, 0.0f}, {step.velocity.x, step.velocity.y, step.velocity.z, 0.0f}});
                if (last) frame.motion[i] = motion_of(step);
            }
            return split;
        });
    }

    // Perches (flock_body.glsl): a bird on its perch or landing is not stepped (`kept`
    // its state, which flock_stepped() may update), and a flying one leaves the flock to
    // land on a frame's first substep. Asked only in a world with perches.
    bool stepped(glsl::Kernel& kernel, std::uint32_t i, gpu::FlockStateGpu& kept, std::uint32_t s) const {
        const FlockWorld& w = *world_;
        if (!w.perches) return true;
        const gpu::FlockBirdGpu& bird = w.birds[i];
        return kernel.flock_stepped(bird, w.perches_of[i], kernel.flocks[bird.ids.x], kept, s, w.frame_dt);
    }
    // A bird not stepped flies its route's motion (the search and rules are not used).
    gpu::BirdMotionGpu route_motion(glsl::Kernel& kernel, std::uint32_t i, const gpu::FlockStateGpu& kept) const {
        const auto m = kernel.flock_route_motion(world_->birds[i], world_->perches_of[i], kept);
        return {gpu4(m.position), gpu4(m.velocity), gpu4(m.acceleration)};
    }
    static gpu::BirdMotionGpu motion_of(const glsl::Kernel::FlockStep& step) {
        return {{step.position.x, step.position.y, step.position.z, 0.0f},
                {step.velocity.x, step.velocity.y, step.velocity.z, 0.0f},
                {step.acceleration.x, step.acceleration.y, step.acceleration.z, 0.0f}};
    }

    unsigned threads_;
    std::optional<simd::Isa> isa_;
    SearchFn search_;  // the cpu backend's hand-tuned search; cpu-reference runs the body's
    RulesFn rules_;    // the cpu backend's hand-tuned rules; cpu-reference runs the body's
    BucketsFn buckets_fn_;  // the cpu backend's birds' buckets, a vector at a time
    const FlockWorld* world_ = nullptr;
    std::vector<std::uint32_t> cells_, buckets_, sorted_;  // the grid
    // cpu-reference: the birds' states by index, this substep's and the next.
    std::vector<gpu::FlockStateGpu> state_, next_;
    // The cpu backend: the birds' states by slot of the last grid (stepped_, old slot t
    // holding bird from_index_[t]), the grid's copy for the search and rules
    // (sorted_birds_), the new grid's old slots (perm_) and the search's k-th distances
    // of last time by slot (SearchArgs::bounds).
    SlotStates stepped_;
    std::vector<std::uint32_t> from_index_, perm_;
    SortedBirds sorted_birds_;
    std::vector<float> bounds_;
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
