// The cpu backend's neighbour search for every instruction set (flock_search.hpp): per
// bird, the 27 cells round its own (a bucket visited once, as flock_neighbours() does),
// each bucket's contiguous candidates compared a vector at a time, the ones the bird sees
// compressed into a short list and its k nearest picked by rank (nearest()), or offered to
// the bird's sorted list by the shared flock_offer() where the rank cannot decide.
//
// Exactness: the distance is (dx dx + dy dy) + dz dz and the field-of-view test
// (dx fx + dy fy) + dz fz < cos sqrt(d2), GLM's dot() operation for operation, without
// fused multiply-add (the library is built with -ffp-contract=off; Highway's Mul and Add
// never fuse); the tests are the reference's negated (a NaN fails both the same way).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "domains/flocking/flock_search_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "domains/flocking/flock_search.hpp"

HWY_BEFORE_NAMESPACE();
namespace kodawari::flocking {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using DU = hn::RebindToUnsigned<D>;
static_assert(HWY_MAX_BYTES / sizeof(float) <= SortedBirds::kSortedPad, "a vector's load from a bucket stays in the padding");
static_assert(kSearchRankedMost <= 64, "a rank is a bit of a 64-bit word");

// Each of the n candidates' rank (how many come before it) a vector of candidates at a
// time: every candidate o adds one to the rank of each candidate it comes before (a
// lane's mask is all ones, -1, so Sub adds one); the candidates of rank below k are
// stored at their rank, the others at slot k. By distance alone (kTies false) or by
// (distance, index), flock_before(). Returns the ranks seen, a bit each (n <= 64).
template <bool kTies>
std::uint64_t rank_into(std::uint32_t k, const float* d2, const std::uint32_t* j, std::size_t n, float* out_d2,
                        std::uint32_t* out_j) {
    const D d;
    const DU du;
    const std::size_t lanes = hn::Lanes(d);
    HWY_ALIGN std::uint32_t ranks[HWY_MAX_BYTES / sizeof(float)];
    std::uint64_t seen = 0;
    for (std::size_t s = 0; s < n; s += lanes) {
        const auto md2 = hn::LoadU(d, d2 + s);
        auto rank = hn::Zero(du);
        if constexpr (kTies) {
            const auto mj = hn::LoadU(du, j + s);
            for (std::size_t o = 0; o < n; ++o) {
                const auto od2 = hn::Set(d, d2[o]);
                const auto tie = hn::And(hn::Eq(od2, md2), hn::RebindMask(d, hn::Lt(hn::Set(du, j[o]), mj)));
                rank = hn::Sub(rank, hn::VecFromMask(du, hn::RebindMask(du, hn::Or(hn::Lt(od2, md2), tie))));
            }
        } else {
            for (std::size_t o = 0; o < n; ++o) {
                rank = hn::Sub(rank, hn::VecFromMask(du, hn::RebindMask(du, hn::Lt(hn::Set(d, d2[o]), md2))));
            }
        }
        hn::Store(rank, du, ranks);
        const std::size_t live = std::min(lanes, n - s);
        for (std::size_t l = 0; l < live; ++l) {
            seen |= std::uint64_t{1} << ranks[l];
            const std::size_t at = std::min<std::size_t>(ranks[l], k);
            out_d2[at] = d2[s + l];
            out_j[at] = j[s + l];
        }
    }
    return seen;
}

// The ranks of n candidates in a total order: 0 to n - 1, a bit each.
constexpr std::uint64_t all_ranks(std::size_t n) { return n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1u; }

// The k nearest of the n candidates seen (d2, j), nearest first, into nb: what offering
// each to the body's flock_offer() in the visiting order gives. The k nearest by
// (distance, index) are a total order's first k, so each candidate's place is its rank,
// the count of candidates before it (flock_before()), counted for 16 candidates at once
// on AVX-512 with no branch per candidate, where the insertion's data-dependent branches
// mispredicted (about 140 ns a bird of the 555 ns search at 10 000 birds). A NaN
// distance has no rank (flock_before() is then no total order), so a bird that sees one
// takes the insertion, in the visiting order, as the reference.
// `nan`: whether any of the n distances is NaN (scan() says).
void nearest(glsl::Kernel& kernel, glsl::Kernel::FlockNeighbours& nb, std::uint32_t k, const float* d2, const std::uint32_t* j,
             std::size_t n, bool nan) {
    if (nan || n > kSearchRankedMost) {
        for (std::size_t m = 0; m < n; ++m) kernel.flock_offer(nb, k, d2[m], j[m]);
        return;
    }
    // Slot k takes every candidate past the first k: a store with no branch.
    float out_d2[KW_FLOCK_MAX_NEIGHBOURS + 1] = {};
    std::uint32_t out_j[KW_FLOCK_MAX_NEIGHBOURS + 1] = {};
    // By distance alone first (a third of the operations): the ranks are the total
    // order's when no two distances are equal, which the ranks then show by being 0 to
    // n - 1, each once; two equal distances share a rank, and the ranks are counted
    // again with the index deciding ties (flock_before()).
    if (rank_into<false>(k, d2, j, n, out_d2, out_j) != all_ranks(n)) rank_into<true>(k, d2, j, n, out_d2, out_j);
    nb.found = static_cast<std::uint32_t>(std::min<std::size_t>(n, k));
    // Every slot, a copy of fixed size (the ones past `found` are not read).
    std::memcpy(nb.d2, out_d2, sizeof nb.d2);
    std::memcpy(nb.j, out_j, sizeof nb.j);
}

// What one bird's scan compares candidates with.
struct Probe {
    hn::Vec<D> px, py, pz, fx, fy, fz, blind, own_flock;
    hn::Vec<DU> self;
};

// The candidates of the list (x, y, z, flock, index; `count` of them, padded past it)
// that the probe's bird sees within `bound` (a distance^2, at most the search radius's),
// appended to out_* (distance^2, index) in the list's order: flock_neighbours()'s tests,
// a vector at a time. Returns how many; `nan` whether any of their distances is NaN
// (found here, where the bounded path and nearest() each read the list back for it
// before: one check instead of two, 0.985x in 5 runs, within the noise). (The field of
// view's square root taken only for the candidates within the bound, in a second pass,
// gained nothing: 0.98x.)
HWY_INLINE std::size_t scan(const Probe& b, float bound, const float* x, const float* y, const float* z, const float* f,
                            const std::uint32_t* index, std::size_t count, float* out_d2, std::uint32_t* out_j, bool& nan) {
    const D d;
    const DU du;
    const std::size_t lanes = hn::Lanes(d);
    const auto bound_v = hn::Set(d, bound);
    auto nan_seen = hn::Zero(d);  // a mask's lanes as a vector: the masks' Or
    std::size_t seen = 0;
    for (std::size_t t = 0; t < count; t += lanes) {
        const auto ex = hn::Sub(hn::LoadU(d, x + t), b.px);
        const auto ey = hn::Sub(hn::LoadU(d, y + t), b.py);
        const auto ez = hn::Sub(hn::LoadU(d, z + t), b.pz);
        const auto d2 = hn::Add(hn::Add(hn::Mul(ex, ex), hn::Mul(ey, ey)), hn::Mul(ez, ez));
        const auto ahead = hn::Add(hn::Add(hn::Mul(ex, b.fx), hn::Mul(ey, b.fy)), hn::Mul(ez, b.fz));
        auto pass = hn::Eq(hn::LoadU(d, f + t), b.own_flock);
        pass = hn::AndNot(hn::Gt(d2, bound_v), pass);
        const auto j = hn::LoadU(du, index + t);
        pass = hn::AndNot(hn::RebindMask(d, hn::Eq(j, b.self)), pass);
        pass = hn::AndNot(hn::Lt(ahead, hn::Mul(b.blind, hn::Sqrt(d2))), pass);
        const auto keep = hn::RebindMask(du, pass);
        hn::StoreU(hn::Compress(j, keep), du, out_j + seen);
        hn::StoreU(hn::Compress(d2, pass), d, out_d2 + seen);
        seen += hn::CountTrue(du, keep);
        nan_seen = hn::Or(nan_seen, hn::VecFromMask(d, hn::And(pass, hn::IsNaN(d2))));
    }
    nan = !hn::AllFalse(d, hn::MaskFromVec(nan_seen));
    return seen;
}

void search(const SearchArgs& args, std::uint32_t first_slot, std::uint32_t count, glsl::Kernel::FlockNeighbours* out) {
    const D d;
    const DU du;
    const std::size_t lanes = hn::Lanes(d);
    glsl::Kernel kernel = *args.kernel;  // the body's functions are not const
    const SortedBirds& sorted = *args.sorted;
    // The candidates of the 27 cells round the last bird's cell (each bucket once),
    // gathered into contiguous arrays: birds come in the grid's order, so the next bird is
    // usually in the same cell and scans the same list, whole vectors at a time. Kept by
    // the thread from call to call (a call is one block of birds).
    thread_local std::vector<float> cx, cy, cz, cf;
    thread_local std::vector<std::uint32_t> cb;
    // Per bird, the candidates it sees (distance^2, index), each array at least cx's
    // size plus a vector.
    thread_local std::vector<float> seen_d2;
    thread_local std::vector<std::uint32_t> seen_j;
    std::size_t used = 0;  // candidates in the arrays
    glm::ivec3 list_home(0);
    bool have_list = false;
    for (std::uint32_t n = 0; n < count; ++n) {
        // The bird in grid slot first_slot + n, read from the sorted arrays (in order,
        // where its own parameters and state by index would be a cache miss each).
        const std::uint32_t slot = first_slot + n;
        glsl::Kernel::FlockNeighbours& nb = out[n];
        nb.found = 0u;
        const std::uint32_t i = kernel.kw_sorted(slot);
        float* next_bound = args.bounds != nullptr ? args.bounds + slot : nullptr;
        // A bird on its perch or landing is not stepped (flock_cpu.cpp): no search.
        if (sorted.flock[slot] < 0.0f) {
            if (next_bound != nullptr) *next_bound = std::numeric_limits<float>::infinity();
            continue;
        }
        const auto own = static_cast<std::uint32_t>(sorted.flock[slot]);
        const gpu::FlockParamsGpu flock = kernel.kw_flock(own);
        const glm::vec3 p(sorted.x[slot], sorted.y[slot], sorted.z[slot]);
        const glm::vec3 forward = kernel.flock_forward(glm::vec3(sorted.vx[slot], sorted.vy[slot], sorted.vz[slot]));
        const float radius2 = flock.radii.x * flock.radii.x;
        const std::uint32_t k = kernel.flock_k(flock);
        const glm::ivec3 home = glsl::flock_cell(p, args.inv_radius);
        if (!have_list || home != list_home) {
            std::uint32_t buckets[27];
            flock_cell_buckets27(home, args.mask, buckets);
            std::uint32_t visited[27];
            std::uint32_t visited_count = 0;
            // A 64-bit filter of the buckets seen so far: the list is scanned only when two
            // buckets share a bit (rare: the 27 cells' Morton codes differ in their low 6
            // bits, two an axis, unless the cells straddle a block).
            std::uint64_t filter = 0;
            used = 0;
            // Buckets next to each other in the visiting order and in the table (cells
            // x and x + 1 of an even x, in Morton order) are one range of the grid's
            // arrays: copied as one (the same candidates in the same order).
            std::uint32_t run_first = 0, run_last = 0, run_bucket = 0;
            const auto copy_run = [&] {
                const std::uint32_t length = run_last - run_first;
                if (used + length + lanes > cx.size()) {
                    const std::size_t grown = 2 * (used + length + lanes);
                    cx.resize(grown), cy.resize(grown), cz.resize(grown), cf.resize(grown), cb.resize(grown);
                }
                // A handful of birds per run: a whole vector at a time from the padded
                // arrays, the first one always (one, mostly: no branch to mispredict on an
                // empty run); the lanes past the run's end are overwritten by the next
                // run's or marked as no flock's below.
                for (std::uint32_t t = run_first; t == run_first || t < run_last; t += static_cast<std::uint32_t>(lanes)) {
                    const std::size_t at = used + (t - run_first);
                    hn::StoreU(hn::LoadU(d, sorted.x.data() + t), d, cx.data() + at);
                    hn::StoreU(hn::LoadU(d, sorted.y.data() + t), d, cy.data() + at);
                    hn::StoreU(hn::LoadU(d, sorted.z.data() + t), d, cz.data() + at);
                    hn::StoreU(hn::LoadU(d, sorted.flock.data() + t), d, cf.data() + at);
                    hn::StoreU(hn::LoadU(du, sorted.index.data() + t), du, cb.data() + at);
                }
                used += length;
            };
            bool have_run = false;
            for (const std::uint32_t b : buckets) {
                const std::uint64_t bit = std::uint64_t{1} << (b & 63u);
                if ((filter & bit) != 0 && std::find(visited, visited + visited_count, b) != visited + visited_count) continue;
                filter |= bit;
                visited[visited_count++] = b;
                const std::uint32_t first = kernel.kw_bucket_start(b);
                const std::uint32_t last = first + kernel.kw_bucket_count(b);
                if (have_run && b == run_bucket + 1u) {
                    run_last = last;  // the previous bucket's range ends where this one's starts
                } else {
                    if (have_run) copy_run();
                    run_first = first, run_last = last, have_run = true;
                }
                run_bucket = b;
            }
            if (have_run) copy_run();
            // The lanes past the last bucket's end (copies of the next birds in the grid)
            // belong to no flock, so the scan below needs no mask for its last vector.
            if (used + lanes > cf.size()) cx.resize(used + lanes), cy.resize(used + lanes), cz.resize(used + lanes), cf.resize(used + lanes), cb.resize(used + lanes);
            hn::StoreU(hn::Set(d, -1.0f), d, cf.data() + used);
            if (seen_d2.size() < cx.size() + lanes) {
                seen_d2.resize(cx.size() + lanes), seen_j.resize(cx.size() + lanes);
            }
            list_home = home;
            have_list = true;
        }
        const Probe probe{hn::Set(d, p.x), hn::Set(d, p.y), hn::Set(d, p.z), hn::Set(d, forward.x), hn::Set(d, forward.y),
                          hn::Set(d, forward.z), hn::Set(d, flock.radii.z), hn::Set(d, sorted.flock[slot]),
                          hn::Set(du, i)};  // the bird itself passes every test but the index (d = 0)
        // First within a bound from the bird's k-th distance of last time, grown by
        // kBoundGrowth: where k candidates pass every test within it, every candidate
        // beyond it ranks k or later, so the k nearest are the same and the rank sorts
        // about half as many (a flock's neighbours change little in a substep). A NaN
        // distance (a NaN or infinite position) passes every bound (`d2 > bound` is
        // false) and has no rank: where one is among them, the bird's insertion follows
        // the visiting order of every candidate, so the search takes the whole radius, as
        // it does where fewer than k pass within the bound or there is none.
        const float bound = next_bound != nullptr ? std::min(radius2, sorted.bound[slot] * kBoundGrowth) : radius2;
        std::size_t seen = 0;
        bool whole = true, nan = false;
        if (bound < radius2) {
            seen = scan(probe, bound, cx.data(), cy.data(), cz.data(), cf.data(), cb.data(), used, seen_d2.data(), seen_j.data(), nan);
            whole = seen < k || nan;
        }
        if (whole) {
            seen = scan(probe, radius2, cx.data(), cy.data(), cz.data(), cf.data(), cb.data(), used, seen_d2.data(), seen_j.data(), nan);
        }
        nearest(kernel, nb, k, seen_d2.data(), seen_j.data(), seen, nan);
        if (next_bound != nullptr) *next_bound = nb.found == k ? nb.d2[k - 1] : std::numeric_limits<float>::infinity();
    }
}

}  // namespace

SearchFn flock_search_kernel() { return &search; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::flocking
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <array>

#include "core/parallel.hpp"
#include "simd/dispatch.hpp"

namespace kodawari::flocking {

SearchFn flock_search_kernel(std::int64_t target) { KW_SIMD_SELECT(target, flock_search_kernel) }

namespace {

// glsl::flock_spread3() of every 10-bit value (it reads only the low 10 bits): a load
// instead of its ten operations. (Made when the library loads: nothing calls the search
// before main.)
const auto kSpread3 = [] {
    std::array<std::uint32_t, 1024> table{};
    for (std::uint32_t v = 0; v < 1024; ++v) table[v] = glsl::flock_spread3(v);
    return table;
}();

}  // namespace

void flock_cell_buckets27(glm::ivec3 home, std::uint32_t mask, std::uint32_t out[27]) {
    // glsl::flock_cell_bucket()'s terms, an axis at a time: the Morton code is the or of
    // each axis's spread bits (disjoint, so its bits above the table's are the xor of each
    // axis's), and the block's hash the xor of each axis's product; so the wrapped bits
    // are the xor of a term an axis, and the mix is computed again only where they change
    // (at a block's or the table's edge: rarely among one cell's 27).
    std::uint32_t m[3][3], w[3][3];
    constexpr std::uint32_t kPrime[3] = {KW_FLOCK_PRIME_X, KW_FLOCK_PRIME_Y, KW_FLOCK_PRIME_Z};
    for (int a = 0; a < 3; ++a) {
        const glm::uvec3 u = glm::uvec3(glsl::flock_cell_near(home, glm::ivec3(a - 1))) + glm::uvec3(KW_FLOCK_HALF_BLOCK);
        for (int axis = 0; axis < 3; ++axis) {
            m[axis][a] = kSpread3[u[axis] & 0x3FFu] << axis;
            w[axis][a] = (m[axis][a] & ~mask) ^ ((u[axis] >> KW_FLOCK_BLOCK_BITS) * kPrime[axis]);
        }
    }
    std::uint32_t wrap_of_mix = 0, mixed = glsl::flock_mix(0u);
    int c = 0;
    for (int z = 0; z < 3; ++z) {
        for (int y = 0; y < 3; ++y) {
            for (int x = 0; x < 3; ++x) {
                const std::uint32_t wrap = w[0][x] ^ w[1][y] ^ w[2][z];
                if (wrap != wrap_of_mix) wrap_of_mix = wrap, mixed = glsl::flock_mix(wrap);
                out[c++] = ((m[0][x] | m[1][y] | m[2][z]) ^ mixed) & mask;
            }
        }
    }
}

void SlotStates::resize(std::size_t n) {
    for (std::vector<float>* v : {&x, &y, &z, &w, &vx, &vy, &vz, &vw}) v->resize(n);
}

void SortedBirds::fill(const SlotStates& from, std::span<const std::uint32_t> from_index, std::span<const std::uint32_t> perm,
                         std::span<const gpu::FlockBirdGpu> birds, std::span<const gpu::FlockParamsGpu> flocks, unsigned threads,
                         std::span<const float> last_bounds) {
    const std::size_t n = perm.size(), padded = n + kSortedPad;
    const bool bounded = last_bounds.size() == n;
    for (std::vector<float>* v : {&x, &y, &z, &vx, &vy, &vz, &pw, &vw, &flock}) v->resize(padded);
    index.resize(padded);
    bound.resize(n);
    for (std::size_t s = n; s < padded; ++s) flock[s] = -1.0f;  // no bird's flock
    // perm is mostly in order (a bird keeps its slot while it keeps its cell), so the old
    // slots' arrays are read nearly in order, by the thread that wrote them; each bird's
    // constants are read by index (64 MB at a million birds), asked for kPrefetch birds
    // ahead.
    constexpr std::size_t kPrefetch = 16;
    parallel_for(n, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t s = begin; s < end; ++s) {
            if (s + kPrefetch < end) __builtin_prefetch(&birds[from_index[perm[s + kPrefetch]]]);
            const std::uint32_t t = perm[s];
            const std::uint32_t i = from_index[t];
            x[s] = from.x[t];
            y[s] = from.y[t];
            z[s] = from.z[t];
            pw[s] = from.w[t];
            vx[s] = from.vx[t];
            vy[s] = from.vy[t];
            vz[s] = from.vz[t];
            vw[s] = from.vw[t];
            const gpu::FlockBirdGpu& bird = birds[i];
            // glsl::flock_seen_as() of the state (its velocity.w) and the bird's constants.
            flock[s] = glsl::flock_seen_as(bird, flocks[bird.ids.x], from.at(t));
            index[s] = i;
            bound[s] = bounded ? last_bounds[t] : std::numeric_limits<float>::infinity();
        }
    });
}

}  // namespace kodawari::flocking
#endif
