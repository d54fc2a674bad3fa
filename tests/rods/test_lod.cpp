// Levels of detail (kodawari/rods/lod.hpp): the decision from a character's projected size
// and place in the frustum, with hysteresis and bias; the settings' checks; and the posed
// frame (rods::step_posed) on the CPU reference.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/rods/synthetic.hpp"

using namespace kodawari;
using rods::Level;

namespace {

// A camera at the origin looking down -Z.
rods::Camera camera() {
    rods::Camera c;
    c.position = glm::vec3(0.0f);
    c.forward = glm::vec3(0.0f, 0.0f, -1.0f);
    return c;
}

rods::LodSettings settings() {
    rods::LodSettings lod;
    lod.enabled = true;
    lod.full_pixels = 100.0f;
    return lod;
}

// A 1 m character at depth z projects to 1080 / (2 tan 25 deg) / z pixels: 100 px at
// 11.58 m; 75 px (the hysteresis' 100 x (1 - 0.25)) at 15.44 m.
float depth_at_pixels(float pixels) { return 1080.0f / (2.0f * std::tan(glm::radians(25.0f))) / pixels; }

}  // namespace

TEST(Lod, FullWithinItsProjectedSizeWithHysteresis) {
    const rods::LodView v = rods::lod_view(settings(), camera());
    ASSERT_TRUE(v.enabled);
    EXPECT_NEAR(v.full_distance, depth_at_pixels(100.0f), 1e-3f);
    EXPECT_NEAR(v.stay_distance, depth_at_pixels(75.0f), 1e-3f);
    const auto at = [&](float z, Level previous) { return rods::chain_level(v, glm::vec3(0.0f, 0.0f, -z), previous); };
    EXPECT_EQ(at(10.0f, Level::Posed), Level::Full);
    EXPECT_EQ(at(10.0f, Level::Hidden), Level::Full);
    // Between the two distances a character keeps what it was.
    EXPECT_EQ(at(13.0f, Level::Posed), Level::Posed);
    EXPECT_EQ(at(13.0f, Level::Full), Level::Full);
    EXPECT_EQ(at(16.0f, Level::Full), Level::Posed);
    // Nearer than its size, on the axis: full whatever it was.
    EXPECT_EQ(at(0.5f, Level::Posed), Level::Full);
}

// The reduced level between full and posed (LodSettings::reduced_pixels): 50 px reaches
// 23.16 m, and a full or reduced character stays simulated within 30.88 m (37.5 px). Off,
// the band is empty and the decision is the two-level one.
TEST(Lod, ReducedBetweenFullAndPosedWithHysteresis) {
    rods::LodSettings lod = settings();
    lod.reduced_pixels = 50.0f;
    const rods::LodView v = rods::lod_view(lod, camera());
    EXPECT_NEAR(v.reduced_distance, depth_at_pixels(50.0f), 1e-3f);
    EXPECT_NEAR(v.reduced_stay, depth_at_pixels(37.5f), 1e-3f);
    const auto at = [&](float z, Level previous) { return rods::chain_level(v, glm::vec3(0.0f, 0.0f, -z), previous); };
    EXPECT_EQ(at(10.0f, Level::Reduced), Level::Full);
    EXPECT_EQ(at(13.0f, Level::Full), Level::Full);       // full's own hysteresis band
    EXPECT_EQ(at(13.0f, Level::Reduced), Level::Reduced);
    EXPECT_EQ(at(13.0f, Level::Posed), Level::Reduced);
    EXPECT_EQ(at(20.0f, Level::Full), Level::Reduced);
    EXPECT_EQ(at(20.0f, Level::Posed), Level::Reduced);
    EXPECT_EQ(at(20.0f, Level::Hidden), Level::Reduced);
    // The reduced band's hysteresis: between 23.16 and 30.88 m it keeps what it was.
    EXPECT_EQ(at(27.0f, Level::Reduced), Level::Reduced);
    EXPECT_EQ(at(27.0f, Level::Full), Level::Reduced);
    EXPECT_EQ(at(27.0f, Level::Posed), Level::Posed);
    EXPECT_EQ(at(32.0f, Level::Reduced), Level::Posed);
    // Off the frustum: hidden whatever the distance.
    EXPECT_EQ(rods::chain_level(v, glm::vec3(0.0f, 0.0f, 20.0f), Level::Reduced), Level::Hidden);
    // Reduced chains step every frame, as full ones; posed ones rest only beyond twice the
    // reduced distance (46.3 m) now.
    for (std::uint32_t turn = 0; turn < 4; ++turn) {
        EXPECT_FALSE(rods::chain_rests(v, glm::vec3(0.0f, 0.0f, -60.0f), Level::Reduced, Level::Reduced, turn));
        EXPECT_FALSE(rods::chain_rests(v, glm::vec3(0.0f, 0.0f, -40.0f), Level::Posed, Level::Posed, turn));
    }
    EXPECT_TRUE(rods::chain_rests(v, glm::vec3(0.0f, 0.0f, -50.0f), Level::Posed, Level::Posed, 1));
    // Off: the reduced distances are the full ones, and no character is reduced.
    const rods::LodView off = rods::lod_view(settings(), camera());
    EXPECT_EQ(off.reduced_distance, off.full_distance);
    EXPECT_EQ(off.reduced_stay, off.stay_distance);
    for (const float z : {5.0f, 13.0f, 20.0f, 40.0f}) {
        for (const Level previous : {Level::Full, Level::Posed, Level::Hidden}) {
            EXPECT_NE(rods::chain_level(off, glm::vec3(0.0f, 0.0f, -z), previous), Level::Reduced) << z;
        }
    }
    // A budget's cap bounds the reduced band too: at 15 m nothing deeper is simulated.
    const rods::LodView capped = rods::lod_view(lod, camera(), 15.0f);
    EXPECT_EQ(capped.full_distance, v.full_distance);
    EXPECT_EQ(capped.reduced_distance, 15.0f);
    EXPECT_EQ(capped.reduced_stay, 15.0f);
    EXPECT_EQ(rods::chain_level(capped, glm::vec3(0.0f, 0.0f, -16.0f), Level::Reduced), Level::Posed);
    // The blend into simulation runs for reduced chains as for full ones.
    EXPECT_GT(rods::blend_in(lod, Level::Reduced, 0.0f, 1.0f / 60.0f), 0.0f);
    EXPECT_EQ(rods::blend_in(lod, Level::Posed, 0.5f, 1.0f / 60.0f), 0.0f);
}

// rods::reduced_params: twice the longest substep (at most 0.05 s), half the iterations
// rounded up, every other setting the same.
TEST(Lod, ReducedParamsHalveTheSubstepsAndIterations) {
    rods::SolverParams p;
    p.max_substep = 1.0f / 120.0f;
    p.iterations = 4;
    const rods::SolverParams r = rods::reduced_params(p);
    EXPECT_EQ(r.max_substep, 2.0f / 120.0f);
    EXPECT_EQ(r.iterations, 2u);
    EXPECT_EQ(r.stiffness, p.stiffness);
    EXPECT_EQ(r.damping, p.damping);
    p.max_substep = 0.04f;
    p.iterations = 1;
    EXPECT_EQ(rods::reduced_params(p).max_substep, 0.05f);
    EXPECT_EQ(rods::reduced_params(p).iterations, 1u);
    p.iterations = 5;
    EXPECT_EQ(rods::reduced_params(p).iterations, 3u);
    EXPECT_TRUE(rods::validate(rods::reduced_params(p)).ok());
}

TEST(Lod, HiddenOffTheFrustumByMoreThanItsSize) {
    const rods::LodView v = rods::lod_view(settings(), camera());
    const float tan_y = std::tan(glm::radians(25.0f));
    const float tan_x = tan_y * 16.0f / 9.0f;
    EXPECT_EQ(rods::chain_level(v, glm::vec3(0.0f, 0.0f, 2.0f), Level::Full), Level::Hidden);  // 2 m behind
    EXPECT_EQ(rods::chain_level(v, glm::vec3(0.0f, 0.0f, 0.5f), Level::Full), Level::Full);    // within its size
    // 10 m ahead: the frustum's edge is 10 tan_x to the side and 10 tan_y up.
    EXPECT_EQ(rods::chain_level(v, glm::vec3(10.0f * tan_x + 0.9f, 0.0f, -10.0f), Level::Full), Level::Full);
    EXPECT_EQ(rods::chain_level(v, glm::vec3(10.0f * tan_x + 1.1f, 0.0f, -10.0f), Level::Full), Level::Hidden);
    EXPECT_EQ(rods::chain_level(v, glm::vec3(-10.0f * tan_x - 1.1f, 0.0f, -10.0f), Level::Posed), Level::Hidden);
    EXPECT_EQ(rods::chain_level(v, glm::vec3(0.0f, 10.0f * tan_y + 0.9f, -10.0f), Level::Full), Level::Full);
    EXPECT_EQ(rods::chain_level(v, glm::vec3(0.0f, -10.0f * tan_y - 1.1f, -10.0f), Level::Full), Level::Hidden);
    // A camera looking straight down takes +X as its right.
    rods::Camera down = camera();
    down.forward = glm::vec3(0.0f, -1.0f, 0.0f);
    const rods::LodView d = rods::lod_view(settings(), down);
    EXPECT_EQ(rods::chain_level(d, glm::vec3(0.0f, -10.0f, 0.0f), Level::Posed), Level::Full);
    EXPECT_EQ(rods::chain_level(d, glm::vec3(0.0f, 10.0f, 0.0f), Level::Full), Level::Hidden);
}

TEST(Lod, BiasScalesTheProjectedSize) {
    rods::LodSettings lod = settings();
    const float base = rods::lod_view(lod, camera()).full_distance;
    lod.bias = 1.0f;
    EXPECT_FLOAT_EQ(rods::lod_view(lod, camera()).full_distance, 2.0f * base);
    lod.bias = -2.0f;
    EXPECT_FLOAT_EQ(rods::lod_view(lod, camera()).full_distance, 0.25f * base);
}

TEST(Lod, OffOrOrthographicIsAlwaysFull) {
    rods::LodSettings off = settings();
    off.enabled = false;
    const glm::vec3 far(0.0f, 0.0f, -1000.0f);
    EXPECT_EQ(rods::chain_level(rods::lod_view(off, camera()), far, Level::Posed), Level::Full);
    rods::Camera ortho = camera();
    ortho.projection = rods::Camera::Projection::Orthographic;
    EXPECT_EQ(rods::chain_level(rods::lod_view(settings(), ortho), far, Level::Posed), Level::Full);
    EXPECT_EQ(rods::chain_level(rods::lod_view(settings(), camera()), far, Level::Full), Level::Posed);
}

// The posed and hidden levels' rate (rods::chain_rests): far posed chains step on even
// turns only, hidden ones every 4th; never a full chain, one that changed level, one within
// twice its full distance (23.2 m here) unless hidden far off the view, or with lower_rate
// off.
TEST(Lod, FarPosedAndHiddenChainsRestBetweenTheirTurns) {
    const rods::LodView v = rods::lod_view(settings(), camera());
    const glm::vec3 far(0.0f, 0.0f, -30.0f), near(0.0f, 0.0f, -20.0f), behind(0.0f, 0.0f, 30.0f);
    std::uint32_t posed_steps = 0, hidden_steps = 0;
    for (std::uint32_t turn = 0; turn < 8; ++turn) {
        posed_steps += rods::chain_rests(v, far, Level::Posed, Level::Posed, turn) ? 0u : 1u;
        hidden_steps += rods::chain_rests(v, behind, Level::Hidden, Level::Hidden, turn) ? 0u : 1u;
        EXPECT_FALSE(rods::chain_rests(v, far, Level::Full, Level::Full, turn));
        EXPECT_FALSE(rods::chain_rests(v, far, Level::Posed, Level::Full, turn));
        EXPECT_FALSE(rods::chain_rests(v, far, Level::Hidden, Level::Posed, turn));
        EXPECT_FALSE(rods::chain_rests(v, near, Level::Posed, Level::Posed, turn));
    }
    EXPECT_EQ(posed_steps, 4u);
    EXPECT_EQ(hidden_steps, 2u);
    // Within twice the full distance a hidden chain beside the view steps every frame (the
    // camera may turn to it), one far off the view rests: off the frustum widened by 20
    // degrees (vertically 25 + 20 = 45: at 10 m deep the widened edge is 10 m up, plus the
    // character's 1 m), or behind the camera.
    const glm::vec3 above(0.0f, 6.7f, -10.0f), far_above(0.0f, 11.5f, -10.0f), close_behind(0.0f, 0.0f, 10.0f);
    ASSERT_EQ(rods::chain_level(v, above, Level::Hidden), Level::Hidden);
    ASSERT_EQ(rods::chain_level(v, far_above, Level::Hidden), Level::Hidden);
    std::uint32_t above_steps = 0, far_above_steps = 0, behind_steps = 0;
    for (std::uint32_t turn = 0; turn < 8; ++turn) {
        above_steps += rods::chain_rests(v, above, Level::Hidden, Level::Hidden, turn) ? 0u : 1u;
        far_above_steps += rods::chain_rests(v, far_above, Level::Hidden, Level::Hidden, turn) ? 0u : 1u;
        behind_steps += rods::chain_rests(v, close_behind, Level::Hidden, Level::Hidden, turn) ? 0u : 1u;
        // Posed there (the level the view would give): posed chains never rest near.
        EXPECT_FALSE(rods::chain_rests(v, far_above, Level::Posed, Level::Posed, turn));
    }
    EXPECT_EQ(above_steps, 8u);
    EXPECT_EQ(far_above_steps, 2u);
    EXPECT_EQ(behind_steps, 2u);
    // A field of view that 20 degrees more takes past 90 has no far side: 150 degrees (its
    // full distance 1.45 m, so 1.5 m behind is within twice it).
    rods::LodSettings wide = settings();
    wide.vertical_fov_deg = 150.0f;
    wide.aspect = 1.0f;
    const rods::LodView wide_view = rods::lod_view(wide, camera());
    const glm::vec3 just_behind(0.0f, 0.0f, 1.5f);
    ASSERT_EQ(rods::chain_level(wide_view, just_behind, Level::Hidden), Level::Hidden);
    ASSERT_LT(1.5f, 2.0f * wide_view.full_distance);
    EXPECT_FALSE(rods::chain_rests(wide_view, just_behind, Level::Hidden, Level::Hidden, 1));
    EXPECT_TRUE(rods::chain_rests(v, far, Level::Posed, Level::Posed, 1));
    EXPECT_FALSE(rods::chain_rests(v, far, Level::Posed, Level::Posed, 2));
    // Groups of 16 characters take turns: the 16th is a turn after the 15th.
    EXPECT_EQ(rods::rate_turn(7, 15), 7u);
    EXPECT_EQ(rods::rate_turn(7, 16), 8u);
    rods::LodSettings every = settings();
    every.lower_rate = false;
    EXPECT_FALSE(rods::chain_rests(rods::lod_view(every, camera()), far, Level::Posed, Level::Posed, 1));
    EXPECT_FALSE(rods::chain_rests(rods::lod_view(rods::LodSettings{}, camera()), far, Level::Posed, Level::Posed, 1));
}

TEST(Lod, RefusesSettingsOutOfRange) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    struct Case {
        const char* field;
        void (*set)(rods::LodSettings&, float);
        float value;
    };
    const Case cases[] = {
        {"size", [](rods::LodSettings& l, float x) { l.size = x; }, 0.0f},
        {"size", [](rods::LodSettings& l, float x) { l.size = x; }, nan},
        {"full_pixels", [](rods::LodSettings& l, float x) { l.full_pixels = x; }, -1.0f},
        {"full_pixels", [](rods::LodSettings& l, float x) { l.full_pixels = x; }, inf},
        {"reduced_pixels", [](rods::LodSettings& l, float x) { l.reduced_pixels = x; }, -1.0f},
        {"reduced_pixels", [](rods::LodSettings& l, float x) { l.reduced_pixels = x; }, 100.0f},  // full_pixels'
        {"reduced_pixels", [](rods::LodSettings& l, float x) { l.reduced_pixels = x; }, nan},
        {"hysteresis", [](rods::LodSettings& l, float x) { l.hysteresis = x; }, 0.95f},
        {"bias", [](rods::LodSettings& l, float x) { l.bias = x; }, nan},
        {"settle_rate", [](rods::LodSettings& l, float x) { l.settle_rate = x; }, 0.0f},
        {"vertical_fov_deg", [](rods::LodSettings& l, float x) { l.vertical_fov_deg = x; }, 180.0f},
        {"aspect", [](rods::LodSettings& l, float x) { l.aspect = x; }, 0.0f},
        {"viewport_height", [](rods::LodSettings& l, float x) { l.viewport_height = x; }, 0.5f},
    };
    ASSERT_TRUE(rods::validate(settings()).ok());
    for (const Case& c : cases) {
        rods::LodSettings lod = settings();
        c.set(lod, c.value);
        const Result<void> r = rods::validate(lod, "scene.lod");
        ASSERT_FALSE(r.ok()) << c.field << " = " << c.value;
        EXPECT_NE(r.error().message.find(std::string("scene.lod.") + c.field + ": expected"), std::string::npos)
            << r.error().message;
    }
    // A world refuses them too.
    auto scene = rods::SyntheticScene::make({.chains = 3, .joints = 4});
    ASSERT_TRUE(scene.ok());
    rods::RodWorld world = scene.value().world();
    world.lod.hysteresis = -0.1f;
    EXPECT_FALSE(world.finalize().ok());
}

TEST(Lod, PosedBlendIsAFrameRateIndependentRate) {
    rods::LodSettings lod = settings();
    lod.settle_rate = 8.0f;
    EXPECT_NEAR(rods::posed_blend(lod, 1.0f / 60.0f), 1.0f - std::exp(-8.0f / 60.0f), 1e-7f);
    // Two frames of dt leave what one frame of 2 dt leaves: (1 - b(dt))^2 = 1 - b(2 dt).
    const float one = 1.0f - rods::posed_blend(lod, 1.0f / 120.0f);
    EXPECT_NEAR(one * one, 1.0f - rods::posed_blend(lod, 1.0f / 60.0f), 1e-6f);
}

// Posed chains of still characters hold the shape they settled in at load (their rest
// shape plus their sag, ChainState::sag): a posed frame that moved them would be one that
// full simulation does not make. Within float rounding: 1e-5 of the chain length.
TEST(Lod, PosedChainsOfStillCharactersHoldTheirSettledShape) {
    auto scene = rods::SyntheticScene::make({.chains = 40, .joints = 9, .motion = 0.0f});
    ASSERT_TRUE(scene.ok());
    rods::RodWorld world = scene.value().world();
    world.lod = settings();
    world.lod.full_pixels = 1e5f;  // posed at any distance
    ASSERT_TRUE(world.finalize().ok());
    auto backend = make_rod_backend(BackendKind::CpuReference, {});
    ASSERT_TRUE(backend.ok());
    rods::RodFrame frame;
    auto at = [&](std::uint32_t f) {
        scene.value().frame(f, 1.0f / 60.0f, frame);
        frame.camera.position = glm::vec3(3.0f, 2.0f, 20.0f);  // still, looking at the grid
        frame.camera.forward = glm::vec3(0.0f, 0.0f, -1.0f);
    };
    at(0);
    ASSERT_TRUE(backend.value()->load(world, frame).ok());
    for (std::uint32_t f = 1; f <= 150; ++f) {
        at(f);
        ASSERT_TRUE(backend.value()->step(frame).ok());
    }
    ChainSnapshot snap;
    ASSERT_TRUE(backend.value()->read(snap).ok());
    std::vector<rods::ChainState> states;
    ASSERT_TRUE(backend.value()->read_states(states).ok());
    float worst = 0.0f, sag = 0.0f;
    for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
        const rods::ChainState& s = states[c];
        EXPECT_EQ(s.level, static_cast<std::uint32_t>(Level::Posed));
        EXPECT_EQ(s.blend_in, 0.0f);
        for (std::uint32_t i = 0; i < world.templ(world.chains[c]).chain.joint_count; ++i) {
            const glm::vec3 settled = s.root.position + s.root.rotation * (s.rest_position[i] + s.sag[i]);
            worst = std::max(worst, glm::length(snap.positions[world.chains[c].joint_begin + i] - settled));
            sag = std::max(sag, glm::length(s.sag[i]));
        }
        // Joint 0 sits on its root exactly, as in full simulation.
        EXPECT_EQ(snap.positions[world.chains[c].joint_begin], frame.roots[c].position);
    }
    EXPECT_LT(worst, 1e-5f * scene.value().chain_length());
    EXPECT_GT(sag, 1e-3f) << "the strands sag under gravity when they settle";
}
