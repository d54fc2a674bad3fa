// The budget mode of the levels of detail (kodawari/rods/lod_budget.hpp): the distance
// that keeps a frame within its budget, nearest characters first; the budget's checks;
// and, through Simulation on the crowd of scenes/crowd-10k.json, that a budget makes
// fewer characters full, bit for bit the same run after run, and that a budget every
// character fits in changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "kodawari/domains/chains.hpp"
#include "kodawari/rods/lod_budget.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

rods::LodView view_down_minus_z() {
    rods::LodSettings lod;
    lod.enabled = true;
    rods::Camera camera;
    camera.position = glm::vec3(0.0f);
    camera.forward = glm::vec3(0.0f, 0.0f, -1.0f);
    return rods::lod_view(lod, camera);  // full within 48.3 m (24 px of 1080 at 50 degrees)
}

// Round costs: a character's frame is 1 us posed, 1 + 10 x chains us full.
rods::LodCosts unit_costs() { return {.full_chain_us = 10.0f, .posed_chain_us = 0.0f, .full_clip_us = 1.0f, .posed_clip_us = 1.0f}; }

}  // namespace

TEST(LodBudget, PromotesTheNearestCharactersWhileTheFrameFits) {
    const rods::LodView view = view_down_minus_z();
    // Depths 30, 10, 20, 40 m on the view, one far (100 m: posed by its size) and one
    // behind the camera (hidden): 2 chains each.
    const std::vector<glm::vec3> refs = {{0, 0, -30}, {0, 0, -10}, {0, 0, -20}, {0, 0, -40}, {0, 0, -100}, {0, 0, 50}};
    const std::vector<std::uint32_t> chains(refs.size(), 2);
    const rods::LodCosts costs = unit_costs();
    // Base 6 us; each full character adds 20 us.
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.006f), -std::numeric_limits<float>::infinity());
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.026f), 10.0f);  // the nearest
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.065f), 20.0f);  // two, not yet three
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.0661f), 30.0f);
    // All four the view makes full fit: no cap (the far one and the hidden one are never promoted).
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.0861f), rods::kNoDistanceCap);
    // The model prices the frame at the levels the capped view gives (lod_view bounds the
    // reduced level's distances by a cap too; off, they are the full ones).
    rods::LodView capped = view;
    capped.full_distance = capped.reduced_distance = 20.0f;
    EXPECT_DOUBLE_EQ(rods::modelled_ms(capped, refs, chains, costs), 0.046);
    // A character as deep as the first one left out is left out too: the cap stops
    // before their depth.
    const std::vector<glm::vec3> tied = {{0, 0, -10}, {1, 0, -20}, {-1, 0, -20}};
    EXPECT_EQ(rods::budget_distance(view, tied, std::vector<std::uint32_t>(3, 2), costs, 0.045f), 10.0f);
    // The cap bounds the view's distances; the hysteresis band ends there too.
    rods::LodSettings on;
    on.enabled = true;
    const rods::LodView bounded = rods::lod_view(on, rods::Camera{}, 20.0f);
    EXPECT_EQ(bounded.full_distance, 20.0f);
    EXPECT_EQ(bounded.stay_distance, 20.0f);
    EXPECT_EQ(bounded.reduced_distance, 20.0f);
}

// With the reduced level on, characters the view makes reduced are candidates too, priced
// at reduced_chain_us: nearest first, whatever their level.
TEST(LodBudget, PricesReducedCharactersAtTheirOwnCost) {
    rods::LodSettings lod;
    lod.enabled = true;
    lod.reduced_pixels = 12.0f;  // full within 48.3 m, reduced within 96.5 m
    rods::Camera camera;
    camera.position = glm::vec3(0.0f);
    camera.forward = glm::vec3(0.0f, 0.0f, -1.0f);
    const rods::LodView view = rods::lod_view(lod, camera);
    ASSERT_NEAR(view.reduced_distance, 96.5f, 0.1f);
    const std::vector<glm::vec3> refs = {{0, 0, -30}, {0, 0, -60}, {0, 0, -80}, {0, 0, -200}};
    const std::vector<std::uint32_t> chains(refs.size(), 2);
    rods::LodCosts costs = unit_costs();
    costs.reduced_chain_us = 2.0f;
    // Base 4 us; the full one adds 20 us, each reduced one 4 us.
    EXPECT_DOUBLE_EQ(rods::modelled_ms(view, refs, chains, costs), 0.032);
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.024f), 30.0f);   // the full one only
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.028f), 60.0f);   // and the nearer reduced one
    EXPECT_EQ(rods::budget_distance(view, refs, chains, costs, 0.032f), rods::kNoDistanceCap);
    const rods::LodView capped = rods::lod_view(lod, camera, 60.0f);
    EXPECT_EQ(rods::chain_level(capped, refs[1], rods::Level::Posed), rods::Level::Reduced);
    EXPECT_EQ(rods::chain_level(capped, refs[2], rods::Level::Posed), rods::Level::Posed);
    EXPECT_DOUBLE_EQ(rods::modelled_ms(capped, refs, chains, costs), 0.028);
}

TEST(LodBudget, RefusesABudgetThatIsNotAPositiveFiniteNumber) {
    for (const float bad : {0.0f, -1.0f, std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()}) {
        auto made = rods::LodBudget::create(bad, false);
        ASSERT_FALSE(made) << bad;
        EXPECT_EQ(made.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(made.error().message.find("budget_ms: expected a positive finite number"), std::string::npos)
            << made.error().message;
    }
    rods::LodCosts costs;
    costs.posed_chain_us = 2.0f;  // more than a full chain
    auto made = rods::LodBudget::create(16.0f, false, costs);
    ASSERT_FALSE(made);
    EXPECT_NE(made.error().message.find("lod.costs.full_chain_us: expected at least posed_chain_us"), std::string::npos)
        << made.error().message;
    rods::LodSettings lod;
    lod.budget_ms = -3.0f;
    auto checked = rods::validate(lod);
    ASSERT_FALSE(checked);
    EXPECT_NE(checked.error().message.find("lod.budget_ms"), std::string::npos) << checked.error().message;
}

TEST(LodBudget, AMeasuredBudgetScalesTheModelByWhatFramesTook) {
    const rods::LodView view = view_down_minus_z();
    const std::vector<glm::vec3> refs = {{0, 0, -10}, {0, 0, -20}};
    const std::vector<std::uint32_t> chains = {2, 2};
    auto model = rods::LodBudget::create(1.0f, /*measured=*/false, unit_costs()).value();
    auto measured = rods::LodBudget::create(1.0f, /*measured=*/true, unit_costs()).value();
    (void)model.cap(view, refs, chains);
    (void)measured.cap(view, refs, chains);
    // The frame took ten times what the model priced it at (0.042 ms).
    model.observe(0.42);
    measured.observe(0.42);
    EXPECT_EQ(model.scale(), 1.0f);  // a bake's budget never reads the clock
    EXPECT_NEAR(measured.scale(), 0.9 + 0.1 * 10.0, 1e-6);
    measured.observe(std::numeric_limits<double>::quiet_NaN());  // ignored
    EXPECT_NEAR(measured.scale(), 1.9, 1e-6);
}

namespace {

// scenes/crowd-10k.json's crowd cut to `count` characters, levels of detail on (the
// scene's 48 px), `frames` frames of its camera's flight from 90 m in.
Scene crowd(std::uint32_t count) {
    auto loaded = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/crowd-10k.json");
    EXPECT_TRUE(loaded) << loaded.error().message;
    Scene scene = std::move(loaded).value();
    scene.crowds[0].count = count;
    scene.lod.enabled = true;
    scene.lod.bias = 2.0f;  // four times nearer: a few dozen characters full on this small crowd
    return scene;
}

struct BudgetRun {
    std::vector<std::byte> positions;  // every frame's joints
    std::uint64_t full = 0;           // chain-frames at the full level
    std::optional<LodBudgetState> budget;  // after the last frame
};

BudgetRun run(Scene scene, std::uint32_t frames) {
    BudgetRun out;
    auto made = Simulation::create(std::move(scene), {.backend = BackendKind::Cpu, .frames = frames});
    EXPECT_TRUE(made) << made.error().message;
    if (!made) return out;
    Simulation& sim = *made.value();
    std::vector<rods::Level> levels;
    ChainSnapshot snapshot;
    for (std::uint32_t f = 0; f < frames; ++f) {
        EXPECT_TRUE(sim.step(1));
        EXPECT_TRUE(read_chain_levels(sim, levels));
        for (const rods::Level l : levels) out.full += l == rods::Level::Full ? 1u : 0u;
        EXPECT_TRUE(read_chains(sim, snapshot));
        const auto* bytes = reinterpret_cast<const std::byte*>(snapshot.positions.data());
        out.positions.insert(out.positions.end(), bytes, bytes + snapshot.positions.size() * sizeof(glm::vec3));
    }
    out.budget = lod_budget(sim);
    return out;
}

}  // namespace

TEST(LodBudget, ABudgetMakesFewerCharactersFullTheSameWayEveryRun) {
    constexpr std::uint32_t kCount = 400, kFrames = 24;
    const BudgetRun free = run(crowd(kCount), kFrames);
    Scene tight = crowd(kCount);
    // The defaults' model prices this crowd's frame at 400 x (1.2 + 7 x 0.23) us = 1.12 ms
    // with every character posed; 1.3 ms leaves room for a dozen or so of them full.
    tight.lod.budget_ms = 1.3f;
    const BudgetRun capped = run(tight, kFrames);
    const BudgetRun again = run(tight, kFrames);
    std::printf("chain-frames full: %llu without a budget, %llu within 1.3 ms\n", static_cast<unsigned long long>(free.full),
                static_cast<unsigned long long>(capped.full));
    EXPECT_GT(free.full, 0u);
    EXPECT_GT(capped.full, 0u);
    EXPECT_LT(capped.full, free.full);
    // Deterministic: the cost model alone decides, never the clock.
    EXPECT_TRUE(capped.positions == again.positions);
    EXPECT_EQ(capped.full, again.full);
    // The state says what the budget did at the last frame: full within a finite depth, the
    // frame priced within the budget and above every character posed (1.12 ms).
    ASSERT_FALSE(free.budget.has_value());
    ASSERT_TRUE(capped.budget.has_value());
    std::printf("the last frame: full within %.2f m, modelled %.3f ms\n", static_cast<double>(capped.budget->full_distance),
                capped.budget->modelled_ms);
    EXPECT_TRUE(std::isfinite(capped.budget->full_distance) && capped.budget->full_distance > 0.0f);
    EXPECT_LE(capped.budget->modelled_ms, 1.3);
    EXPECT_GT(capped.budget->modelled_ms, 1.12);
    EXPECT_FALSE(capped.budget->measured);
    EXPECT_EQ(capped.budget->scale, 1.0f);
    // A budget every character fits in caps nothing: the bits of no budget.
    Scene roomy = crowd(kCount);
    roomy.lod.budget_ms = 1000.0f;
    const BudgetRun loose = run(roomy, kFrames);
    EXPECT_TRUE(loose.positions == free.positions);
    ASSERT_TRUE(loose.budget.has_value());
    EXPECT_EQ(loose.budget->full_distance, std::numeric_limits<float>::infinity());
}

TEST(LodBudget, SimulationRefusesABadBudgetNamingIt) {
    Scene off = crowd(20);
    off.lod.enabled = false;
    auto made = Simulation::create(std::move(off), {.backend = BackendKind::Cpu, .frames = 4});
    ASSERT_TRUE(made) << made.error().message;
    auto refused = set_lod_budget(*made.value(), 16.0f, false);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("levels of detail are off"), std::string::npos) << refused.error().message;
    auto on = Simulation::create(crowd(20), {.backend = BackendKind::Cpu, .frames = 4});
    ASSERT_TRUE(on) << on.error().message;
    auto zero = set_lod_budget(*on.value(), 0.0f, true);
    ASSERT_FALSE(zero);
    EXPECT_NE(zero.error().message.find("set_lod_budget: budget_ms: expected a positive finite number"), std::string::npos)
        << zero.error().message;
    ASSERT_TRUE(set_lod_budget(*on.value(), 16.0f, true));
    ASSERT_TRUE(lod_budget(*on.value()).has_value());
    EXPECT_TRUE(lod_budget(*on.value())->measured);
    EXPECT_TRUE(on.value()->step(4));
}

TEST(LodBudget, AShardWithABudgetIsRefusedNamingIt) {
    // A shard would rank its own characters alone: its chains would not be the whole run's.
    Scene scene = crowd(20);
    scene.lod.budget_ms = 16.0f;
    auto made = Simulation::create(std::move(scene), {.backend = BackendKind::Cpu, .frames = 2, .shard = {1, 2}});
    ASSERT_FALSE(made);
    EXPECT_EQ(made.error().kind, Error::Kind::Unsupported);
    EXPECT_NE(made.error().message.find("lod.budget_ms: a budget ranks every character of the scene, and this shard holds 10 of its 20"),
              std::string::npos)
        << made.error().message;
}
