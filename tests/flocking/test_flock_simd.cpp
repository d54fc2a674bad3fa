// White-box: the cpu backend's hand-tuned flocking kernels, at every instruction set,
// against the body (shaders/lib/flock_body.glsl, which cpu-reference and vulkan run), bit
// for bit, on worlds made to reach each of their paths; the motion-level test
// (FlockingBackends.StepLikeTheReference) sees only what a flying flock reaches.
// - The neighbour search (flock_search_simd.cpp) against flock_neighbours(): the selection
//   by rank (a typical flock, a metric radius, a sparse one whose birds see fewer than k),
//   the insertion past kSearchRankedMost candidates seen (a dense cluster), and exact
//   ties in distance, which the total order (distance, index) decides (a lattice).
// - The rules (flock_rules_simd.cpp) against flock_rules(): every agent kind, each of
//   their branches, the ground, the speed and pitch limits, separation's front factor.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "domains/flocking/flock_rules.hpp"
#include "domains/flocking/flock_search.hpp"
#include "kodawari/backends/simd.hpp"
#include "simd/isa.hpp"

namespace kodawari::flocking {
namespace {

gpu::FlockParamsGpu rules(std::uint32_t k, bool metric, float radius, float blind_deg) {
    gpu::FlockParamsGpu p{};
    p.counts = {k, metric ? 1u : 0u, 0u, 0u};
    const double half_view = (360.0 - double{blind_deg}) * 0.5 * 3.141592653589793 / 180.0;
    p.radii = {radius, 1.0f, static_cast<float>(std::cos(half_view)), 10.0f};
    return p;
}

struct World {
    std::vector<gpu::FlockParamsGpu> flocks;
    std::vector<gpu::FlockBirdGpu> birds;
    std::vector<gpu::FlockStateGpu> states;
    float radius = 3.0f;  // the grid's cell: the largest search radius

    void add(glm::vec3 p, glm::vec3 v, std::uint32_t flock) {
        gpu::FlockBirdGpu b{};
        b.ids = {flock, 0u, 0xFFFFFFFFu, 0u};  // flying at every frame (no perches)
        birds.push_back(b);
        states.push_back({{p.x, p.y, p.z, 0.0f}, {v.x, v.y, v.z, 0.0f}});
    }
};

// What the worlds reach, counted on cpu-reference's lists.
struct Reach {
    std::size_t birds = 0;
    std::size_t over_ranked = 0;  // birds that see more than kSearchRankedMost candidates
    std::size_t ties = 0;         // birds whose list holds two neighbours at one distance
    std::size_t short_lists = 0;  // birds that found fewer than k
    std::size_t mismatches = 0;   // (isa, pass, bird) pairs whose search differs from the reference
    std::size_t bounded = 0;      // birds whose bound from the search's own k-th distance holds k candidates
    std::size_t bounded_short = 0;  // the bounds shrunk 0.6x: birds whose bound holds fewer than k (searched again, whole)
    std::size_t out_of_order = 0;   // slots of the cpu backend's grid holding another bird than the reference's
};

// How many candidates bird i sees within distance^2 `bound` (its search radius's when
// not given): flock_neighbours()'s tests over every bird.
std::size_t seen_by(const World& w, std::size_t i, float bound = std::numeric_limits<float>::infinity()) {
    const gpu::FlockParamsGpu& f = w.flocks[w.birds[i].ids.x];
    const glm::vec3 p = glsl::kw_xyz(w.states[i].position), v = glsl::kw_xyz(w.states[i].velocity);
    const float speed = glm::length(v);
    const glm::vec3 forward = speed > 1e-6f ? v / speed : glm::vec3(0.0f, 0.0f, 1.0f);
    std::size_t seen = 0;
    for (std::size_t j = 0; j < w.birds.size(); ++j) {
        if (j == i || w.birds[j].ids.x != w.birds[i].ids.x) continue;
        const glm::vec3 d = glsl::kw_xyz(w.states[j].position) - p;
        const float d2 = glm::dot(d, d);
        if (d2 > f.radii.x * f.radii.x || d2 > bound || glm::dot(d, forward) < f.radii.z * std::sqrt(d2)) continue;
        ++seen;
    }
    return seen;
}

// Every instruction set this machine runs: its name and Highway target.
std::vector<std::pair<std::string, std::int64_t>> instruction_sets() {
    std::vector<std::pair<std::string, std::int64_t>> out;
    for (const std::string& name : available_simd_isas()) {
        auto isa = simd::choose_isa(name);
        EXPECT_TRUE(isa.ok()) << name;
        if (isa.ok()) out.emplace_back(name, isa.value().target);
    }
    EXPECT_FALSE(out.empty()) << "no instruction set to test";
    return out;
}

// The birds' states by slot, slot t holding bird index[t].
SlotStates slot_states(const World& w, std::span<const std::uint32_t> index) {
    SlotStates out;
    out.resize(index.size());
    for (std::size_t t = 0; t < index.size(); ++t) out.set(t, w.states[index[t]]);
    return out;
}

// The grid's copy as the cpu backend makes it: build_grid_slots() (the grid, `sorted`)
// and SortedBirds::fill(), from the birds held by slot, slot t holding bird t (the first
// substep's) or, with a seed, the birds in a shuffled order (a later substep's: a bucket's
// birds then come in that order, not by index, unless a position is NaN).
SortedBirds sorted_copy(const World& w, std::vector<std::uint32_t>& sorted, unsigned threads = 1, unsigned shuffle_seed = 0) {
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    std::vector<std::uint32_t> identity(n), cells, buckets, perm;
    for (std::uint32_t i = 0; i < n; ++i) identity[i] = i;
    if (shuffle_seed != 0) std::shuffle(identity.begin(), identity.end(), std::mt19937(shuffle_seed));
    const SlotStates states = slot_states(w, identity);
    SortedBirds out;
    build_grid_slots(states.x.data(), states.y.data(), states.z.data(), identity, 1.0f / w.radius, bucket_count(n) - 1u,
                     flock_buckets_kernel(simd::choose_isa("").value().target), threads, cells, buckets, sorted, perm, out.slot_of);
    out.fill(states, identity, perm, w.birds, w.flocks, threads, {});
    return out;
}

Reach compare(const World& w, const char* name) {
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    const std::uint32_t mask = bucket_count(n) - 1u;
    const float inv_radius = 1.0f / w.radius;
    std::vector<std::uint32_t> cells, buckets, sorted;
    build_grid(w.states, inv_radius, mask, cells, buckets, sorted);
    glsl::Kernel kernel{w.flocks, w.birds, w.states, buckets, sorted, {}, {}};
    std::vector<glsl::Kernel::FlockNeighbours> expected(n);  // by bird
    Reach reach;
    reach.birds = n;
    for (std::uint32_t s = 0; s < n; ++s) {
        const std::uint32_t i = sorted[s];
        expected[i] = kernel.flock_neighbours(i, mask, inv_radius);
        const glsl::Kernel::FlockNeighbours& e = expected[i];
        if (e.found < kernel.flock_k(w.flocks[w.birds[i].ids.x])) ++reach.short_lists;
        for (std::uint32_t m = 1; m < e.found; ++m) {
            if (e.d2[m] == e.d2[m - 1]) {
                ++reach.ties;
                break;
            }
        }
        if (seen_by(w, i) > kSearchRankedMost) ++reach.over_ranked;
    }
    // The bounds the search reads as hints (SortedBirds::bound, which its SearchArgs::bounds
    // of last time give), pass after pass: none
    // (infinity, a world's first substep), the k-th distances it wrote itself (what the
    // next substep reads: the first bound holds k for most birds), those shrunk (too tight
    // for some: the whole radius again), and nonsense. Every pass the reference's lists.
    struct Pass {
        const char* what;
        float scale;  // of the bounds written by the pass before (NaN: set to `value`)
        float value;
    };
    const Pass passes[] = {{"no bounds", std::nanf(""), std::numeric_limits<float>::infinity()},
                           {"its own", 1.0f, 0.0f},
                           {"its own, 0.6x", 0.6f, 0.0f},
                           {"0", std::nanf(""), 0.0f},
                           {"-1", std::nanf(""), -1.0f},
                           {"NaN", std::nanf(""), std::nanf("")},
                           {"none", -1.0f, 0.0f}};
    // The cpu backend's copy of the grid from the birds held in a shuffled order: its grid
    // (`slots`: the bird at each slot) has a bucket's birds in that order unless a
    // position is NaN; the search is to find the same lists.
    std::vector<std::uint32_t> slots;
    SortedBirds sorted_birds = sorted_copy(w, slots, 1, 977);
    for (std::uint32_t s = 0; s < n; ++s) reach.out_of_order += slots[s] != sorted[s] ? 1 : 0;
    const glsl::Kernel cpu_kernel{w.flocks, w.birds, {}, buckets, slots, {}, {}};
    for (const auto& [isa_name, target] : instruction_sets()) {
        const SearchFn search = flock_search_kernel(target);
        std::vector<float> bounds(n);
        for (const Pass& pass : passes) {
            std::vector<float> given = bounds;
            for (std::uint32_t i = 0; i < n; ++i) given[i] = std::isnan(pass.scale) ? pass.value : bounds[i] * pass.scale;
            // Birds whose first bound holds k candidates the reference's tests pass, and
            // those whose bound is tighter than their radius but holds fewer.
            std::size_t held = 0, short_of_k = 0;
            for (std::uint32_t i = 0; i < n && !(pass.scale < 0.0f); ++i) {
                const std::uint32_t k = kernel.flock_k(w.flocks[w.birds[i].ids.x]);
                const float radius2 = w.flocks[w.birds[i].ids.x].radii.x * w.flocks[w.birds[i].ids.x].radii.x;
                const float bound = std::min(radius2, given[i] * kBoundGrowth);
                const std::size_t within = bound < radius2 ? seen_by(w, i, bound) : 0;
                held += bound < radius2 && within >= k ? 1 : 0;
                short_of_k += bound < radius2 && within < k ? 1 : 0;
            }
            // By slot, as the fill hands them over (the world does not move: the slots stay).
            std::vector<float> written(n);
            for (std::uint32_t s = 0; s < n; ++s) sorted_birds.bound[s] = given[slots[s]];
            const SearchArgs args{&cpu_kernel, &sorted_birds, mask, inv_radius, pass.scale < 0.0f ? nullptr : written.data()};
            std::vector<glsl::Kernel::FlockNeighbours> found(n);
            // In calls of 37 birds (not a multiple of any vector): a call starts its list afresh.
            for (std::uint32_t first = 0; first < n; first += 37) search(args, first, std::min(37u, n - first), found.data() + first);
            std::size_t differ = 0;
            for (std::uint32_t s = 0; s < n; ++s) {
                const glsl::Kernel::FlockNeighbours &a = found[s], &e = expected[slots[s]];
                bool same = a.found == e.found;
                for (std::uint32_t m = 0; same && m < e.found; ++m) {
                    same = std::bit_cast<std::uint32_t>(a.d2[m]) == std::bit_cast<std::uint32_t>(e.d2[m]) && a.j[m] == e.j[m];
                }
                if (!same && differ++ < 3) {
                    ADD_FAILURE() << name << ", " << isa_name << ", bounds " << pass.what << ": bird " << slots[s] << " found "
                                  << a.found << " (first j " << (a.found > 0 ? a.j[0] : 0u) << "), the reference " << e.found
                                  << " (first j " << (e.found > 0 ? e.j[0] : 0u) << ")";
                }
            }
            if (pass.scale == 1.0f) reach.bounded = std::max(reach.bounded, held);
            if (pass.scale == 0.6f) reach.bounded_short = std::max(reach.bounded_short, short_of_k);
            reach.mismatches += differ;
            for (std::uint32_t s = 0; s < n && !(pass.scale < 0.0f); ++s) bounds[slots[s]] = written[s];  // what this pass wrote
        }
    }
    std::printf("%s: %zu birds, %zu seeing more than %zu, %zu with a tie in their list, %zu with fewer than k, %zu whose own bound "
                "holds k (shrunk 0.6x, %zu hold fewer), %zu slots holding another bird than the reference's grid; %zu differ\n",
                name, reach.birds, reach.over_ranked, kSearchRankedMost, reach.ties, reach.short_lists, reach.bounded,
                reach.bounded_short, reach.out_of_order, reach.mismatches);
    return reach;
}

glm::vec3 heading(std::mt19937& rng) {
    // Mostly along +x, as a flock flies, with every direction among them.
    std::normal_distribution<float> spread(0.0f, 0.6f);
    return glm::vec3(10.0f + 10.0f * spread(rng), 10.0f * spread(rng), 10.0f * spread(rng));
}

// `count` birds uniformly in the cube [lo, hi]^3 lifted by `lift` in y, heading as a
// flock does, bird b in flock b % flocks.
World random_world(std::vector<gpu::FlockParamsGpu> flocks, unsigned seed, float lo, float hi, int count, float lift = 0.0f) {
    World w;
    w.flocks = std::move(flocks);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> box(lo, hi);
    const auto kinds = static_cast<int>(w.flocks.size());
    for (int b = 0; b < count; ++b) w.add({box(rng), box(rng) + lift, box(rng)}, heading(rng), static_cast<std::uint32_t>(b % kinds));
    return w;
}

// `count` birds of flock 0 uniformly in the 27 cells round cell `home` (of the world's
// radius), heading as a flock does.
void add_round(World& w, glm::ivec3 home, int count, std::mt19937& rng) {
    std::uniform_real_distribution<float> box(-1.0f, 2.0f);  // cells home - 1 to home + 1
    for (int b = 0; b < count; ++b) {
        const glm::vec3 cell(static_cast<float>(home.x) + box(rng), static_cast<float>(home.y) + box(rng),
                             static_cast<float>(home.z) + box(rng));
        w.add(cell * w.radius, heading(rng), 0u);
    }
}

// Starlings' density (about 0.2 birds per cubic metre: 150 candidates in a bird's 27
// cells), two flocks interleaved with their own k and blind angle, and a third with a
// metric radius (k = every bird within it, at most KW_FLOCK_MAX_NEIGHBOURS).
TEST(FlockSearch, TypicalFlocksAreTheReferencesLists) {
    // Each flock at 0.2 birds/m^3.
    const World w = random_world({rules(7, false, 3.0f, 60.0f), rules(5, false, 2.5f, 90.0f), rules(16, true, 3.0f, 0.0f)}, 7,
                                 -8.5f, 8.5f, 3001, 40.0f);
    const Reach r = compare(w, "typical");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_EQ(r.over_ranked, 0u) << "the typical world is meant to stay on the rank's path";
    EXPECT_LT(r.short_lists, r.birds / 3) << "most birds of a typical world find k";
    EXPECT_GT(r.bounded, r.birds / 2) << "most birds' own k-th distance is meant to bound their search";
    EXPECT_GT(r.bounded_short, r.birds / 2) << "the shrunk bounds are meant to leave most birds short of k, to their whole radius";
}

// Perches (flock_hash.glsl's flock_flies()): the typical world at frame 5 with every
// seventh bird not flying, on its perch before its first flocking frame (6) or landing
// (its state's velocity.w). Nobody sees those birds and they search for nobody, on every
// instruction set as in the reference; the reference's own lists leave them out.
TEST(FlockSearch, BirdsOnTheirPerchesAreInNobodysList) {
    World w = random_world({rules(7, false, 3.0f, 60.0f), rules(5, false, 2.5f, 90.0f)}, 7, -8.5f, 8.5f, 2001, 40.0f);
    for (gpu::FlockParamsGpu& f : w.flocks) f.counts.z = 5u;
    std::size_t perched = 0;
    for (std::size_t i = 0; i < w.birds.size(); i += 7, ++perched) {
        if (i % 2 == 0) {
            w.birds[i].ids.y = 6u;
        } else {
            w.states[i].position.w = 0.05f;  // t0, landing since frame 4
            w.states[i].velocity.w = 1.0f;
        }
    }
    const Reach r = compare(w, "perched");
    EXPECT_EQ(r.mismatches, 0u);
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    std::vector<std::uint32_t> cells, buckets, sorted;
    build_grid(w.states, 1.0f / w.radius, bucket_count(n) - 1u, cells, buckets, sorted);
    glsl::Kernel kernel{w.flocks, w.birds, w.states, buckets, sorted, {}, {}};
    std::size_t listed = 0, searching = 0, not_flying = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        const auto nb = kernel.flock_neighbours(i, bucket_count(n) - 1u, 1.0f / w.radius);
        const bool flying = glsl::flock_flies(w.birds[i], w.flocks[w.birds[i].ids.x], w.states[i]);
        for (std::uint32_t m = 0; m < nb.found; ++m) listed += nb.j[m] % 7 == 0 ? 1 : 0;
        searching += !flying && nb.found > 0 ? 1 : 0;
        not_flying += !flying ? 1 : 0;
    }
    EXPECT_EQ(listed, 0u) << "a perched or landing bird in a flying bird's list";
    EXPECT_EQ(searching, 0u) << "a perched or landing bird with neighbours of its own";
    EXPECT_EQ(not_flying, perched) << "every seventh bird is not flying at frame 5";
}

// A sparse flock: most birds see fewer than k (and some none).
TEST(FlockSearch, SparseFlocksAreTheReferencesLists) {
    const World w = random_world({rules(7, false, 3.0f, 60.0f)}, 11, -40.0f, 40.0f, 1001);
    const Reach r = compare(w, "sparse");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_GT(r.short_lists, r.birds / 2);
}

// A dense cluster, every bird within 1.5 m of every other: each sees hundreds, past
// kSearchRankedMost, and takes the insertion.
TEST(FlockSearch, DenseClustersAreTheReferencesLists) {
    const World w = random_world({rules(7, false, 3.0f, 60.0f), rules(16, true, 3.0f, 30.0f)}, 13, 0.0f, 1.5f, 701);
    const Reach r = compare(w, "dense");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_GT(r.over_ranked, r.birds / 2);
}

// Birds on a 1 m lattice, all flying along +x: their neighbours lie at exactly equal
// distances (1, 2, 3 m^2, ...), so the index decides most places of every list.
TEST(FlockSearch, TiesInDistanceGoByIndexAsTheReference) {
    World w;
    w.flocks = {rules(7, false, 2.5f, 60.0f), rules(16, true, 2.5f, 0.0f)};
    for (int z = 0; z < 12; ++z) {
        for (int y = 0; y < 12; ++y) {
            for (int x = 0; x < 12; ++x) {
                w.add({float(x), float(y) + 30.0f, float(z)}, {10.0f, 0.0f, 0.0f}, static_cast<std::uint32_t>((x + y + z) % 2 == 0 ? 0 : 1));
            }
        }
    }
    const Reach r = compare(w, "lattice");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_GT(r.ties, r.birds / 2);
}

// Two of a bird's 27 cells in one bucket: both backends visit the bucket once (a
// candidate offered twice would take two places of the list). The grid's Morton order
// (shaders/lib/flock_hash.glsl) keeps the 27 cells apart except where they straddle the
// table's span or a block of 1 024 cells, where the mixed-in high bits place a cell
// anywhere: the test finds such a cell by the grid's own function and fills its
// neighbourhood, 9 m a side, with birds.
TEST(FlockSearch, CellsSharingABucketAreVisitedOnce) {
    constexpr int kBirds = 400;
    const std::uint32_t mask = bucket_count(kBirds) - 1u;
    const auto shared_bucket = [&](glm::ivec3 home) {
        std::vector<std::uint32_t> seen;
        for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) seen.push_back(glsl::flock_cell_bucket(glsl::flock_cell_near(home, glm::ivec3(dx, dy, dz)), mask));
            }
        }
        std::sort(seen.begin(), seen.end());
        return std::adjacent_find(seen.begin(), seen.end()) != seen.end();
    };
    // Cells whose x-neighbours straddle the block boundary at cell 512 (offset 1 024).
    glm::ivec3 home(0);
    bool found = false;
    for (int y = -40; y <= 40 && !found; ++y) {
        for (int z = -40; z <= 40 && !found; ++z) {
            home = glm::ivec3(511, y, z);
            found = shared_bucket(home);
        }
    }
    ASSERT_TRUE(found) << "no cell round x = 511 (cells) has two of its 27 cells in one bucket of " << mask + 1u;
    World w;
    w.flocks = {rules(7, false, 3.0f, 60.0f)};
    std::mt19937 rng(17);
    add_round(w, home, kBirds, rng);
    std::size_t sharing = 0;  // birds whose own 27 cells share a bucket
    for (const gpu::FlockStateGpu& st : w.states) sharing += shared_bucket(glsl::flock_cell(glsl::kw_xyz(st.position), 1.0f / w.radius)) ? 1 : 0;
    std::printf("cell (%d, %d, %d): %zu of %d birds have two of their 27 cells in one bucket\n", home.x, home.y, home.z, sharing, kBirds);
    EXPECT_GT(sharing, std::size_t{kBirds / 50}) << "the world is meant to reach the bucket shared by two cells";
    const Reach r = compare(w, "shared bucket");
    EXPECT_EQ(r.mismatches, 0u);
}

// A bird at a NaN position among a flock: its distance from every bird is NaN, which
// passes every test and has no rank, so the birds that visit its bucket take the
// insertion, whose result follows the order of every candidate they visit: a bound from
// last time must not leave the nearer candidates alone (the search takes the whole radius
// where it finds a NaN within the bound). Its cell lies at the int range's end (its
// neighbours' cells wrap, flock_cell_near()); the flock is placed round a cell of its
// bucket, found by the grid's own function, so that most birds visit it. A bird with an
// infinite velocity (a NaN heading: it sees every bird round it) beside them.
TEST(FlockSearch, ABirdAtANaNPositionIsSeenInTheVisitingOrder) {
    constexpr int kBirds = 600;
    const std::uint32_t mask = bucket_count(kBirds) - 1u;
    World w;
    w.flocks = {rules(7, false, 3.0f, 60.0f)};
    const glm::vec3 lost(std::nanf(""), 4.0f, 4.0f);
    const std::uint32_t lost_bucket = glsl::flock_bucket(lost, 1.0f / w.radius, mask);
    glm::ivec3 home(0);
    bool found = false;
    for (int z = -20; z <= 20 && !found; ++z) {
        for (int y = -20; y <= 20 && !found; ++y) {
            for (int x = -20; x <= 20 && !found; ++x) {
                home = glm::ivec3(x, y, z);
                found = glsl::flock_cell_bucket(home, mask) == lost_bucket;
            }
        }
    }
    ASSERT_TRUE(found) << "no cell within 20 of the origin shares the NaN bird's bucket " << lost_bucket;
    std::mt19937 rng(37);
    add_round(w, home, kBirds, rng);
    w.add(lost, heading(rng), 0u);
    w.states[7].velocity.y = std::numeric_limits<float>::infinity();
    const Reach r = compare(w, "NaN position");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_GT(r.bounded, std::size_t{kBirds / 2}) << "the birds' own bounds are meant to hold k (but for the NaN)";
}

// flock_cell_buckets27() against flock_cell_bucket() cell by cell: round the origin, at
// the edges of a block of 1 024 cells (where the mixed-in high bits change), at the
// table's span, far out, at negative cells and at the int range's ends (where the cells
// wrap, flock_cell_near()), for tables of several sizes.
TEST(FlockGrid, The27BucketsAreTheGridsOwn) {
    std::mt19937 rng(31);
    std::uniform_int_distribution<int> near(-3000, 3000), far(-200000000, 200000000);
    std::size_t compared = 0, differ = 0;
    for (const std::uint32_t mask : {1023u, 32767u, (1u << 21) - 1u}) {
        std::vector<glm::ivec3> homes;
        constexpr int kLow = std::numeric_limits<int>::min(), kHigh = std::numeric_limits<int>::max();
        for (const int edge : {kLow, kLow + 1, -1536, -513, -512, -511, 0, 511, 512, 513, 1535, 1536, kHigh - 1, kHigh}) {
            homes.emplace_back(edge, 0, 0), homes.emplace_back(0, edge, 0), homes.emplace_back(0, 0, edge);
            homes.emplace_back(edge, edge, edge == kLow ? kHigh : -edge);
        }
        for (int t = 0; t < 300; ++t) homes.emplace_back(near(rng), near(rng), near(rng));
        for (int t = 0; t < 100; ++t) homes.emplace_back(far(rng), far(rng), far(rng));
        for (const glm::ivec3 home : homes) {
            std::uint32_t got[27];
            flock_cell_buckets27(home, mask, got);
            int c = 0;
            for (int dz = -1; dz <= 1; ++dz) {
                for (int dy = -1; dy <= 1; ++dy) {
                    for (int dx = -1; dx <= 1; ++dx, ++c) {
                        const glm::ivec3 cell = glsl::flock_cell_near(home, glm::ivec3(dx, dy, dz));
                        const std::uint32_t want = glsl::flock_cell_bucket(cell, mask);
                        ++compared;
                        if (got[c] != want && differ++ < 3) {
                            ADD_FAILURE() << "cell (" << cell.x << ", " << cell.y << ", " << cell.z << "), mask " << mask << ": "
                                          << got[c] << ", the grid's " << want;
                        }
                    }
                }
            }
        }
    }
    std::printf("27 buckets: %zu cells compared, %zu differ\n", compared, differ);
    EXPECT_EQ(differ, 0u);
}

// The cpu backend's buckets, a vector of birds at a time (flock_buckets_kernel()), against
// flock_bucket() bird by bird, at every instruction set: positions near the origin and
// on cells' edges (exact multiples of the cell), far out, beyond the int range (a cell
// at the range's end), NaN, infinite and -0; 1 001 birds (not a multiple of a vector).
TEST(FlockGrid, TheBucketsOfAVectorOfBirdsAreTheGridsOwn) {
    std::mt19937 rng(43);
    std::uniform_real_distribution<float> near(-50.0f, 50.0f), far(-7e9f, 7e9f);
    std::uniform_int_distribution<int> edge(-20, 20);
    const float special[] = {std::nanf(""), std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(), -0.0f,
                             6442450560.0f, -6442450944.0f, 6442451200.0f, 3e38f, 1e-30f};
    std::vector<gpu::FlockStateGpu> states(1001);
    for (std::size_t i = 0; i < states.size(); ++i) {
        float c[3];
        for (float& v : c) {
            switch (i % 5) {
                case 0: v = near(rng); break;
                case 1: v = 3.0f * static_cast<float>(edge(rng)); break;
                case 2: v = far(rng); break;
                case 3: v = special[(i / 5) % std::size(special)]; break;
                default: v = near(rng) * 1e-3f; break;
            }
        }
        states[i].position = {c[0], c[1], c[2], 0.0f};
    }
    std::vector<float> x, y, z;  // the cpu backend's arrays by slot
    for (const gpu::FlockStateGpu& st : states) x.push_back(st.position.x), y.push_back(st.position.y), z.push_back(st.position.z);
    std::size_t compared = 0, differ = 0;
    for (const std::uint32_t mask : {1023u, 32767u}) {
        for (const auto& [isa_name, target] : instruction_sets()) {
            std::vector<std::uint32_t> got(states.size());
            flock_buckets_kernel(target)(x.data(), y.data(), z.data(), states.size(), 1.0f / 3.0f, mask, got.data());
            for (std::size_t i = 0; i < states.size(); ++i, ++compared) {
                const std::uint32_t want = glsl::flock_bucket(glsl::kw_xyz(states[i].position), 1.0f / 3.0f, mask);
                if (got[i] != want && differ++ < 3) {
                    ADD_FAILURE() << isa_name << ": (" << states[i].position.x << ", " << states[i].position.y << ", "
                                  << states[i].position.z << "), mask " << mask << ": " << got[i] << ", the grid's " << want;
                }
            }
        }
    }
    std::printf("buckets: %zu compared, %zu differ\n", compared, differ);
    EXPECT_EQ(differ, 0u);
}

// The bounds the search wrote by slot reach each bird at its new slot after the grid
// is sorted again (the birds moved): a bird's own k-th distance, not its slot's former
// bird's (the lists would be the same, but the bound a stranger's: slower, not wrong, so
// only this test sees it). On 1 and 3 threads.
TEST(FlockSearch, EachBirdsBoundFollowsItToItsNewSlot) {
    World w = random_world({rules(7, false, 3.0f, 60.0f)}, 41, -8.5f, 8.5f, 2001);
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    const std::uint32_t mask = bucket_count(n) - 1u;
    const BucketsFn find = flock_buckets_kernel(instruction_sets().front().second);
    for (const unsigned threads : {1u, 3u}) {
        std::vector<std::uint32_t> cells, buckets, sorted, perm;
        SortedBirds birds = sorted_copy(w, sorted, threads);
        std::vector<float> written(n);  // by slot: a value that names the bird
        for (std::uint32_t s = 0; s < n; ++s) written[s] = static_cast<float>(sorted[s]);
        // Every bird 4 m along x, held at its slot (as the cpu backend's step writes it):
        // most change cell, and slot.
        World moved = w;
        for (gpu::FlockStateGpu& st : moved.states) st.position.x += 4.0f;
        const std::vector<std::uint32_t> from_index(birds.index.begin(), birds.index.begin() + n);
        const SlotStates stepped = slot_states(moved, from_index);
        std::vector<std::uint32_t> sorted2;
        build_grid_slots(stepped.x.data(), stepped.y.data(), stepped.z.data(), from_index, 1.0f / w.radius, mask, find, threads, cells,
                         buckets, sorted2, perm, birds.slot_of);
        std::size_t changed = 0, wrong = 0;
        for (std::uint32_t s = 0; s < n; ++s) changed += sorted2[s] != sorted[s] ? 1 : 0;
        birds.fill(stepped, from_index, perm, moved.birds, moved.flocks, threads, written);
        for (std::uint32_t s = 0; s < n; ++s) {
            wrong += birds.bound[s] != static_cast<float>(sorted2[s]) ? 1 : 0;
            wrong += birds.index[s] != sorted2[s] || birds.x[s] != moved.states[sorted2[s]].position.x ? 1 : 0;
        }
        EXPECT_GT(changed, std::size_t{n / 2}) << "most birds are meant to change slot";
        EXPECT_EQ(wrong, 0u) << threads << " threads";
        birds.fill(stepped, from_index, perm, moved.birds, moved.flocks, threads, {});  // none given: infinity
        for (std::uint32_t s = 0; s < n; ++s) wrong += std::isinf(birds.bound[s]) ? 0 : 1;
        EXPECT_EQ(wrong, 0u) << threads << " threads, no bounds given";
    }
}

// The cpu backend's grid of birds held by slot (build_grid_slots(): the birds in any
// order, their buckets found on several threads) is the grid of the same birds by index:
// the same table, and the same order where a position is NaN (a bucket's birds by index),
// elsewhere a bucket's birds in their old slots' order; each new slot's old slot.
// For fewer birds than threads, a flock at starlings' density (several birds a bucket),
// one spread over several blocks of cells (a bucket each, mostly), and a knot of birds in
// one cell with NaN positions among them (a bucket of almost all of them); the
// old slots in bird order, reversed and shuffled.
TEST(FlockGrid, TheSlotsGridIsTheGridOfTheBirdsByIndex) {
    struct Case {
        int count;
        float lo, hi;
    };
    for (const Case c : {Case{3, -40.0f, 4000.0f}, Case{3001, -8.5f, 8.5f}, Case{20011, -40.0f, 4000.0f}, Case{2003, 0.5f, 2.5f}}) {
        World w = random_world({rules(7, false, 3.0f, 60.0f)}, 23, c.lo, c.hi, c.count);
        const bool knot = c.hi - c.lo < 3.0f;
        if (knot) {
            for (std::size_t i = 0; i < w.states.size(); i += 97) w.states[i].position.y = std::nanf("");
        }
        const auto n = static_cast<std::uint32_t>(w.birds.size());
        const std::uint32_t mask = bucket_count(n) - 1u;
        std::vector<std::uint32_t> cells, buckets, sorted;
        build_grid(w.states, 1.0f / w.radius, mask, cells, buckets, sorted);
        std::uint32_t fullest = 0;
        for (std::size_t b = 0; b <= mask; ++b) fullest = std::max(fullest, buckets[2 * b + 1]);
        std::printf("%d birds in [%g, %g]^3: at most %u a bucket\n", c.count, double{c.lo}, double{c.hi}, fullest);
        if (c.hi - c.lo < 20.0f) {
            EXPECT_GT(fullest, c.hi - c.lo < 3.0f ? 32u : 4u) << "the dense flock is meant to put several birds in a bucket";
        }
        std::vector<std::uint32_t> index(n);
        for (std::uint32_t i = 0; i < n; ++i) index[i] = i;
        const BucketsFn find = flock_buckets_kernel(instruction_sets().front().second);
        for (int order = 0; order < 3; ++order) {
            if (order == 1) std::reverse(index.begin(), index.end());
            if (order == 2) std::shuffle(index.begin(), index.end(), std::mt19937(5));
            std::vector<float> x, y, z;
            for (const std::uint32_t i : index) {
                x.push_back(w.states[i].position.x), y.push_back(w.states[i].position.y), z.push_back(w.states[i].position.z);
            }
            for (const unsigned threads : {1u, 2u, 3u, 7u, 64u}) {
                std::vector<std::uint32_t> cells_t, buckets_t(7, 99u), sorted_t(3, 99u), perm, slot_of;  // stale contents, resized
                build_grid_slots(x.data(), y.data(), z.data(), index, 1.0f / w.radius, mask, find, threads, cells_t, buckets_t,
                                 sorted_t, perm, slot_of);
                const std::string what = std::to_string(c.count) + " birds, order " + std::to_string(order) + ", " +
                                         std::to_string(threads) + " threads";
                EXPECT_EQ(buckets_t, buckets) << what;
                // With a NaN position, the reference's order (by index in a bucket);
                // without, each bucket's birds in their old slots' order.
                std::vector<std::uint32_t> want = sorted;
                if (!knot) {
                    for (std::uint32_t t = 0; t < n; ++t) want[t] = index[t];
                    std::stable_sort(want.begin(), want.end(), [&](std::uint32_t a, std::uint32_t b) { return cells[a] < cells[b]; });
                    // stable_sort by bucket puts the buckets in the table's order, the birds of
                    // one in the order given: the old slots'.
                }
                EXPECT_EQ(sorted_t, want) << what;
                std::size_t wrong = 0;
                for (std::uint32_t t = 0; t < n; ++t) {
                    wrong += index[perm[t]] != sorted_t[t] ? 1 : 0;
                    wrong += slot_of[sorted_t[t]] != t ? 1 : 0;
                    wrong += cells_t[t] != cells[index[t]] ? 1 : 0;
                }
                EXPECT_EQ(wrong, 0u) << what;
            }
        }
    }
}

gpu::FlockAgentGpu agent(float kind, glm::vec4 position, float weight, float margin, glm::vec3 velocity) {
    gpu::FlockAgentGpu a{};
    a.position = {position.x, position.y, position.z, position.w};
    a.kind_weight = {kind, weight, margin, 0.0f};
    a.velocity = {velocity.x, velocity.y, velocity.z, 0.0f};
    return a;
}

// The rules of 1 512 birds in two flocks, at every instruction set, against the body's:
// separation's front factor 0.7 and 2.5 (at 0 or 1 the order of its products cannot
// show), collision avoidance with and without its look-ahead and both its fallbacks, birds straddling the ground clearance, speeds from rest (where the body's
// forward is +z) to twice the largest with steep climbs and dives (the speed and pitch
// limits), and every agent kind among them: a floor and a wall, a sphere, an upright capsule, a
// level one and one of no length, five birds flying dead at them, predators crossing the
// flock and diving straight down (their two ways to flee), one of negative weight (no
// panic), an attractor. In calls of 37 birds.
// `one_flock`: every bird of the first flock, so that the vectors of birds share it (the
// rules set its parameters once), where otherwise the two flocks alternate in every vector.
void rules_bit_for_bit(bool one_flock) {
    World w;
    gpu::FlockParamsGpu first = rules(7, false, 3.0f, 60.0f), second = rules(16, true, 2.5f, 0.0f);
    first.radii.y = 1.1f;
    first.weights = {2.0f, 1.5f, 1.0f, 0.5f};
    first.ground = {3.0f, 20.0f, 0.8f, 0.7f};
    first.target = {5.0f, 4.0f, -3.0f, 0.0f};
    second.weights = {1.0f, 2.0f, 0.5f, 0.3f};
    second.ground = {2.0f, 10.0f, 1.2f, 2.5f};
    second.target = {-4.0f, 2.0f, 6.0f, 0.0f};
    // Collision avoidance: predicted 0.3 s ahead in one flock, as the birds are in the other.
    first.collision = {0.6f, 0.3f, 0.0f, 0.0f};
    second.collision = {0.45f, 0.0f, 0.0f, 0.0f};
    w.flocks = {first, second};
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> across(-9.0f, 9.0f), height(0.0f, 8.0f), unit(-1.0f, 1.0f), speed(0.0f, 30.0f);
    std::size_t at_rest = 0, low = 0;
    for (int b = 0; b < 1501; ++b) {
        const glm::vec3 p(across(rng), height(rng), across(rng));
        glm::vec3 dir(unit(rng), unit(rng), unit(rng));
        const float len = glm::length(dir);
        dir = len > 1e-3f ? dir / len : glm::vec3(1.0f, 0.0f, 0.0f);
        const bool rest = b % 10 == 0;
        at_rest += rest ? 1 : 0;
        low += p.y < 3.0f ? 1 : 0;
        w.add(p, rest ? glm::vec3(0.0f) : speed(rng) * dir, one_flock ? 0u : static_cast<std::uint32_t>(b % 2));
        gpu::FlockBirdGpu& bird = w.birds.back();
        bird.offset = {unit(rng), unit(rng), unit(rng), 0.0f};
        bird.speed = {10.0f, 5.0f, 15.0f, 8.0f};
        bird.turn = {12.0f, 0.5f, 0.6f, 0.0f};
    }
    // Five birds flying dead on an obstacle's centre line or normal, where the steer across
    // it has no direction and the body turns to its side (forward x up; the horizontal
    // capsule's up is its axis) or, flying along up, to +x: at the sphere, the level
    // capsule, the sphere from above, the wall, and the floor from above.
    const glm::vec3 aimed[][2] = {{{3.0f, 4.0f, -3.5f}, {0.0f, 0.0f, 10.0f}},
                                  {{-4.0f, 6.0f, 5.5f}, {0.0f, 0.0f, 10.0f}},
                                  {{3.0f, 7.5f, 0.0f}, {0.0f, -10.0f, 0.0f}},
                                  {{-6.0f, 4.0f, 2.0f}, {-10.0f, 0.0f, 0.0f}},
                                  {{7.0f, 2.5f, -7.0f}, {0.0f, -10.0f, 0.0f}}};
    for (const auto& a : aimed) {
        w.add(a[0], a[1], 0u);
        w.birds.back().speed = {10.0f, 5.0f, 15.0f, 8.0f};
        w.birds.back().turn = {12.0f, 0.5f, 0.6f, 0.0f};
    }
    // Collision avoidance's fallbacks: two birds at one place flying apart (no direction
    // to steer from: nothing), and two flying head-on whose predicted nearest is exactly
    // 0 apart (from where the neighbour is).
    for (const auto& [at, v] : {std::pair{glm::vec3(3.0f, 5.0f, 3.0f), glm::vec3(0.0f, 0.0f, 10.0f)},
                                std::pair{glm::vec3(3.0f, 5.0f, 3.0f), glm::vec3(10.0f, 0.0f, 0.0f)},
                                std::pair{glm::vec3(-3.0f, 5.0f, -3.0f), glm::vec3(0.0f, 0.0f, 10.0f)},
                                std::pair{glm::vec3(-3.0f, 5.0f, -2.0f), glm::vec3(0.0f, 0.0f, -10.0f)}}) {
        w.add(at, v, 0u);
        w.birds.back().speed = {10.0f, 5.0f, 15.0f, 8.0f};
        w.birds.back().turn = {12.0f, 0.5f, 0.6f, 0.0f};
    }
    // Two birds at rest whose wing allows no speed (0 / 0 in the pitch limit: NaN, which
    // the body's `!=` takes for a change), one of them on its route's target: NaN
    // results, the body's branches taken on NaN.
    for (const glm::vec3 at : {glm::vec3(5.0f, 4.0f, -3.0f), glm::vec3(-7.0f, 2.0f, 7.0f)}) {
        w.add(at, glm::vec3(0.0f), 0u);
        w.birds.back().speed = {0.0f, 0.0f, 0.0f, 8.0f};
        w.birds.back().turn = {12.0f, 0.5f, 0.6f, 0.0f};
    }
    const std::vector<gpu::FlockAgentGpu> agents = {
        agent(KW_FLOCK_AGENT_PLANE, {0.0f, 1.0f, 0.0f, 0.0f}, 15.0f, 2.0f, {0.0f, 1.0f, 0.0f}),
        agent(KW_FLOCK_AGENT_PLANE, {-8.0f, 0.0f, 0.0f, 0.0f}, 15.0f, 3.0f, {1.0f, 0.0f, 0.0f}),
        agent(KW_FLOCK_AGENT_SPHERE, {3.0f, 4.0f, 0.0f, 1.5f}, 20.0f, 3.0f, {}),
        agent(KW_FLOCK_AGENT_CAPSULE, {-4.0f, 0.0f, -4.0f, 1.0f}, 20.0f, 3.0f, {-4.0f, 8.0f, -4.0f}),
        agent(KW_FLOCK_AGENT_CAPSULE, {6.0f, 5.0f, 6.0f, 1.2f}, 15.0f, 2.0f, {6.0f, 5.0f, 6.0f}),
        agent(KW_FLOCK_AGENT_CAPSULE, {-8.0f, 6.0f, 8.0f, 1.0f}, 20.0f, 3.0f, {0.0f, 6.0f, 8.0f}),
        agent(KW_FLOCK_AGENT_REPELLER, {0.0f, 4.0f, 2.0f, 6.0f}, 40.0f, 0.0f, {12.0f, 0.0f, 0.0f}),
        agent(KW_FLOCK_AGENT_REPELLER, {-2.0f, 6.0f, -1.0f, 5.0f}, 30.0f, 0.0f, {0.0f, -15.0f, 0.0f}),
        agent(KW_FLOCK_AGENT_REPELLER, {5.0f, 2.0f, -6.0f, 4.0f}, -5.0f, 0.0f, {0.0f, 0.0f, 3.0f}),
        agent(KW_FLOCK_AGENT_ATTRACTOR, {2.0f, 3.0f, -5.0f, 8.0f}, 10.0f, 0.0f, {}),
    };
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    const std::uint32_t mask = bucket_count(n) - 1u;
    const float inv_radius = 1.0f / w.radius, dt = 1.0f / 60.0f;
    std::vector<std::uint32_t> cells, buckets, sorted;
    build_grid(w.states, inv_radius, mask, cells, buckets, sorted);
    std::vector<std::uint32_t> sorted_by_slots;
    SortedBirds sorted_birds = sorted_copy(w, sorted_by_slots);
    EXPECT_EQ(sorted_by_slots, sorted) << "the cpu backend's grid is the reference's";
    glsl::Kernel kernel{w.flocks, w.birds, w.states, buckets, sorted, agents, {}};
    const auto agent_count = static_cast<std::uint32_t>(agents.size());
    std::vector<glsl::Kernel::FlockNeighbours> found(n);
    std::vector<glsl::Kernel::FlockStep> expected(n);
    std::size_t pitched = 0, clamped = 0, colliding = 0;
    for (std::uint32_t s = 0; s < n; ++s) {
        found[s] = kernel.flock_neighbours(sorted[s], mask, inv_radius);
        // Birds with a neighbour predicted within the collision distance (the body's sum).
        const gpu::FlockStateGpu& me = w.states[sorted[s]];
        const gpu::FlockParamsGpu& f = w.flocks[w.birds[sorted[s]].ids.x];
        bool collides = false;
        for (std::uint32_t k = 0; k < found[s].found; ++k) {
            const gpu::FlockStateGpu& other = w.states[found[s].j[k]];
            const glm::vec3 d = glsl::kw_xyz(other.position) - glsl::kw_xyz(me.position);
            const glm::vec3 rel = glsl::kw_xyz(other.velocity) - glsl::kw_xyz(me.velocity);
            const float rel2 = glm::dot(rel, rel);
            const float t = rel2 > 0.0f ? glm::clamp(-glm::dot(d, rel) / rel2, 0.0f, f.collision.y) : 0.0f;
            collides = collides || glm::length(d + t * rel) < f.collision.x;
        }
        colliding += collides ? 1 : 0;
        expected[s] = kernel.flock_rules(sorted[s], found[s], agent_count, dt);
        const float v = glm::length(expected[s].velocity);
        clamped += (v <= 5.0f + 1e-4f || v >= 15.0f - 1e-4f) ? 1 : 0;
        pitched += std::abs(expected[s].velocity.y / v - 0.5f) < 1e-4f || std::abs(expected[s].velocity.y / v + 0.6f) < 1e-4f ? 1 : 0;
    }
    std::size_t nan = 0;
    for (const glsl::Kernel::FlockStep& e : expected) nan += std::isnan(e.velocity.x) ? 1 : 0;
    std::printf("rules: %u birds, %zu at rest, %zu below the clearance, %zu at a speed limit, %zu at a climb or dive limit, "
                "%zu with a NaN velocity, %zu steering from a collision\n",
                n, at_rest, low, clamped, pitched, nan, colliding);
    EXPECT_GT(colliding, 50u) << "the world is meant to reach the collision avoidance";
    EXPECT_GE(nan, 2u) << "the birds without speed are meant to reach the pitch limit's NaN";
    EXPECT_GT(clamped, 100u);
    EXPECT_GT(pitched, 100u);
    const RulesArgs args{&kernel, &sorted_birds, agent_count, dt};
    for (const auto& [isa_name, target] : instruction_sets()) {
        const RulesFn run = flock_rules_kernel(target);
        std::vector<glsl::Kernel::FlockStep> steps(n);
        for (std::uint32_t first_slot = 0; first_slot < n; first_slot += 37) {
            run(args, first_slot, std::min(37u, n - first_slot), found.data() + first_slot, steps.data() + first_slot);
        }
        std::size_t differ = 0;
        for (std::uint32_t s = 0; s < n; ++s) {
            const glsl::Kernel::FlockStep &a = steps[s], &e = expected[s];
            const float got[9] = {a.position.x, a.position.y, a.position.z, a.velocity.x, a.velocity.y, a.velocity.z,
                                  a.acceleration.x, a.acceleration.y, a.acceleration.z};
            const float want[9] = {e.position.x, e.position.y, e.position.z, e.velocity.x, e.velocity.y, e.velocity.z,
                                   e.acceleration.x, e.acceleration.y, e.acceleration.z};
            // Bit for bit, but a NaN for a NaN of any sign (flock_rules.hpp says why).
            bool same = true;
            for (int c = 0; c < 9; ++c) {
                same = same && (std::bit_cast<std::uint32_t>(got[c]) == std::bit_cast<std::uint32_t>(want[c]) ||
                                (std::isnan(got[c]) && std::isnan(want[c])));
            }
            if (!same && differ++ < 3) {
                ADD_FAILURE() << isa_name << ": bird " << sorted[s] << " velocity (" << a.velocity.x << ", " << a.velocity.y << ", "
                              << a.velocity.z << "), the body's (" << e.velocity.x << ", " << e.velocity.y << ", " << e.velocity.z << ")";
            }
        }
        std::printf("rules, %s: %zu of %u birds differ\n", isa_name.c_str(), differ, n);
    }
}

TEST(FlockRules, AreTheBodysRulesBitForBit) { rules_bit_for_bit(false); }

TEST(FlockRules, AreTheBodysRulesBitForBitInOneFlock) { rules_bit_for_bit(true); }

}  // namespace
}  // namespace kodawari::flocking
