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
    std::size_t mismatches = 0;   // (isa, bird) pairs whose search differs from the reference
};

// How many candidates bird i sees: flock_neighbours()'s tests over every bird.
std::size_t seen_by(const World& w, std::size_t i) {
    const gpu::FlockParamsGpu& f = w.flocks[w.birds[i].ids.x];
    const glm::vec3 p = glsl::kw_xyz(w.states[i].position), v = glsl::kw_xyz(w.states[i].velocity);
    const float speed = glm::length(v);
    const glm::vec3 forward = speed > 1e-6f ? v / speed : glm::vec3(0.0f, 0.0f, 1.0f);
    std::size_t seen = 0;
    for (std::size_t j = 0; j < w.birds.size(); ++j) {
        if (j == i || w.birds[j].ids.x != w.birds[i].ids.x) continue;
        const glm::vec3 d = glsl::kw_xyz(w.states[j].position) - p;
        const float d2 = glm::dot(d, d);
        if (d2 > f.radii.x * f.radii.x || glm::dot(d, forward) < f.radii.z * std::sqrt(d2)) continue;
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

Reach compare(const World& w, const char* name) {
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    const std::uint32_t mask = bucket_count(n) - 1u;
    const float inv_radius = 1.0f / w.radius;
    std::vector<std::uint32_t> cells, buckets, sorted;
    build_grid(w.states, inv_radius, mask, cells, buckets, sorted);
    SortedBirds sorted_birds;
    sorted_birds.fill(w.states, w.birds, w.flocks, sorted);
    glsl::Kernel kernel{w.flocks, w.birds, w.states, buckets, sorted, {}, {}};
    std::vector<glsl::Kernel::FlockNeighbours> expected(n);
    Reach reach;
    reach.birds = n;
    for (std::uint32_t s = 0; s < n; ++s) {
        const std::uint32_t i = sorted[s];
        expected[s] = kernel.flock_neighbours(i, mask, inv_radius);
        const glsl::Kernel::FlockNeighbours& e = expected[s];
        if (e.found < kernel.flock_k(w.flocks[w.birds[i].ids.x])) ++reach.short_lists;
        for (std::uint32_t m = 1; m < e.found; ++m) {
            if (e.d2[m] == e.d2[m - 1]) {
                ++reach.ties;
                break;
            }
        }
        if (seen_by(w, i) > kSearchRankedMost) ++reach.over_ranked;
    }
    const SearchArgs args{&kernel, &sorted_birds, mask, inv_radius};
    for (const auto& [isa_name, target] : instruction_sets()) {
        const SearchFn search = flock_search_kernel(target);
        std::vector<glsl::Kernel::FlockNeighbours> found(n);
        // In calls of 37 birds (not a multiple of any vector): a call starts its list afresh.
        for (std::uint32_t first = 0; first < n; first += 37) search(args, first, std::min(37u, n - first), found.data() + first);
        std::size_t differ = 0;
        for (std::uint32_t s = 0; s < n; ++s) {
            const glsl::Kernel::FlockNeighbours &a = found[s], &e = expected[s];
            bool same = a.found == e.found;
            for (std::uint32_t m = 0; same && m < e.found; ++m) {
                same = std::bit_cast<std::uint32_t>(a.d2[m]) == std::bit_cast<std::uint32_t>(e.d2[m]) && a.j[m] == e.j[m];
            }
            if (!same && differ++ < 3) {
                ADD_FAILURE() << name << ", " << isa_name << ": bird " << sorted[s] << " found " << a.found << " (first j "
                              << (a.found > 0 ? a.j[0] : 0u) << "), the reference " << e.found << " (first j "
                              << (e.found > 0 ? e.j[0] : 0u) << ")";
            }
        }
        reach.mismatches += differ;
    }
    std::printf("%s: %zu birds, %zu seeing more than %zu, %zu with a tie in their list, %zu with fewer than k; %zu differ\n", name,
                reach.birds, reach.over_ranked, kSearchRankedMost, reach.ties, reach.short_lists, reach.mismatches);
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
                for (int dx = -1; dx <= 1; ++dx) seen.push_back(glsl::flock_cell_bucket(home + glm::ivec3(dx, dy, dz), mask));
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
    std::uniform_real_distribution<float> box(-1.0f, 2.0f);  // cells home - 1 to home + 1
    for (int b = 0; b < kBirds; ++b) {
        const glm::vec3 cell(static_cast<float>(home.x) + box(rng), static_cast<float>(home.y) + box(rng),
                             static_cast<float>(home.z) + box(rng));
        w.add(cell * w.radius, heading(rng), 0u);
    }
    std::size_t sharing = 0;  // birds whose own 27 cells share a bucket
    for (const gpu::FlockStateGpu& st : w.states) sharing += shared_bucket(glsl::flock_cell(glsl::kw_xyz(st.position), 1.0f / w.radius)) ? 1 : 0;
    std::printf("cell (%d, %d, %d): %zu of %d birds have two of their 27 cells in one bucket\n", home.x, home.y, home.z, sharing, kBirds);
    EXPECT_GT(sharing, std::size_t{kBirds / 50}) << "the world is meant to reach the bucket shared by two cells";
    const Reach r = compare(w, "shared bucket");
    EXPECT_EQ(r.mismatches, 0u);
}

// The grid built on several threads (the birds' buckets found on them) gives the serial
// build's table and order (a bucket's birds by index): for fewer birds than threads, a
// flock at starlings' density (several birds a bucket) and one spread over several
// blocks of cells (a bucket each, mostly).
TEST(FlockGrid, EveryThreadCountGivesTheSerialSort) {
    struct Case {
        int count;
        float lo, hi;
    };
    for (const Case c : {Case{3, -40.0f, 4000.0f}, Case{3001, -8.5f, 8.5f}, Case{20011, -40.0f, 4000.0f}}) {
        const World w = random_world({rules(7, false, 3.0f, 60.0f)}, 23, c.lo, c.hi, c.count);
        const auto n = static_cast<std::uint32_t>(w.birds.size());
        const std::uint32_t mask = bucket_count(n) - 1u;
        std::vector<std::uint32_t> cells, buckets, sorted;
        build_grid(w.states, 1.0f / w.radius, mask, cells, buckets, sorted, 1);
        std::uint32_t fullest = 0;
        for (std::size_t b = 0; b <= mask; ++b) fullest = std::max(fullest, buckets[2 * b + 1]);
        std::printf("%d birds in [%g, %g]^3: at most %u a bucket\n", c.count, double{c.lo}, double{c.hi}, fullest);
        if (c.hi - c.lo < 20.0f) {
            EXPECT_GT(fullest, 4u) << "the dense flock is meant to put several birds in a bucket";
        }
        for (const unsigned threads : {2u, 3u, 7u, 64u}) {
            std::vector<std::uint32_t> cells_t, buckets_t(7, 99u), sorted_t(3, 99u);  // stale contents, resized
            build_grid(w.states, 1.0f / w.radius, mask, cells_t, buckets_t, sorted_t, threads);
            EXPECT_EQ(cells_t, cells) << c.count << " birds, " << threads << " threads";
            EXPECT_EQ(buckets_t, buckets) << c.count << " birds, " << threads << " threads";
            EXPECT_EQ(sorted_t, sorted) << c.count << " birds, " << threads << " threads";
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
TEST(FlockRules, AreTheBodysRulesBitForBit) {
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
        w.add(p, rest ? glm::vec3(0.0f) : speed(rng) * dir, static_cast<std::uint32_t>(b % 2));
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
    SortedBirds sorted_birds;
    sorted_birds.fill(w.states, w.birds, w.flocks, sorted);
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

}  // namespace
}  // namespace kodawari::flocking
