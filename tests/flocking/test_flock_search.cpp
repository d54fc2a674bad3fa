// White-box: the cpu backend's hand-tuned neighbour search
// (engine/domains/flocking/flock_search_simd.cpp) finds what the body's flock_neighbours()
// finds (cpu-reference's and vulkan's search), bit for bit, at every instruction set, on
// worlds made to reach each of its paths: the selection by rank (a typical flock, a
// metric radius, a sparse one whose birds see fewer than k), the insertion past
// kSearchRankedMost candidates seen (a dense cluster), and exact ties in distance, which
// the total order (distance, index) decides (a lattice). The motion-level test
// (FlockingBackends.StepLikeTheReference) sees only what a flying flock reaches.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

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
        b.ids = {flock, 0u, 0u, 0u};
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

Reach compare(const World& w, const char* name) {
    const auto n = static_cast<std::uint32_t>(w.birds.size());
    const std::uint32_t mask = bucket_count(n) - 1u;
    const float inv_radius = 1.0f / w.radius;
    std::vector<std::uint32_t> cells, buckets, sorted;
    build_grid(w.states, inv_radius, mask, cells, buckets, sorted);
    SortedBirds sorted_birds;
    sorted_birds.fill(w.states, w.birds, sorted);
    glsl::Kernel kernel{w.flocks, w.birds, w.states, buckets, sorted, {}};
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
    for (const std::string& isa_name : available_simd_isas()) {
        auto isa = simd::choose_isa(isa_name);
        EXPECT_TRUE(isa.ok()) << isa_name;
        if (!isa.ok()) continue;
        const SearchFn search = flock_search_kernel(isa.value().target);
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

// Starlings' density (about 0.2 birds per cubic metre: 150 candidates in a bird's 27
// cells), two flocks interleaved with their own k and blind angle, and a third with a
// metric radius (k = every bird within it, at most KW_FLOCK_MAX_NEIGHBOURS).
TEST(FlockSearch, TypicalFlocksAreTheReferencesLists) {
    World w;
    w.flocks = {rules(7, false, 3.0f, 60.0f), rules(5, false, 2.5f, 90.0f), rules(16, true, 3.0f, 0.0f)};
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> box(-8.5f, 8.5f);  // each flock at 0.2 birds/m^3
    for (int b = 0; b < 3001; ++b) w.add({box(rng), box(rng) + 40.0f, box(rng)}, heading(rng), static_cast<std::uint32_t>(b % 3));
    const Reach r = compare(w, "typical");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_EQ(r.over_ranked, 0u) << "the typical world is meant to stay on the rank's path";
    EXPECT_LT(r.short_lists, r.birds / 3) << "most birds of a typical world find k";
}

// A sparse flock: most birds see fewer than k (and some none).
TEST(FlockSearch, SparseFlocksAreTheReferencesLists) {
    World w;
    w.flocks = {rules(7, false, 3.0f, 60.0f)};
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> box(-40.0f, 40.0f);
    for (int b = 0; b < 1001; ++b) w.add({box(rng), box(rng), box(rng)}, heading(rng), 0u);
    const Reach r = compare(w, "sparse");
    EXPECT_EQ(r.mismatches, 0u);
    EXPECT_GT(r.short_lists, r.birds / 2);
}

// A dense cluster, every bird within 1.5 m of every other: each sees hundreds, past
// kSearchRankedMost, and takes the insertion.
TEST(FlockSearch, DenseClustersAreTheReferencesLists) {
    World w;
    w.flocks = {rules(7, false, 3.0f, 60.0f), rules(16, true, 3.0f, 30.0f)};
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> box(0.0f, 1.5f);
    for (int b = 0; b < 701; ++b) w.add({box(rng), box(rng), box(rng)}, heading(rng), static_cast<std::uint32_t>(b % 2));
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

}  // namespace
}  // namespace kodawari::flocking
