// docs/flight-modes.md: glide and the flap-glide rhythm, take-off and landing (F.2 timing,
// F.3 poses), hover, the body bob and the head and tail (F.4, F.5), and the scene
// format's route modes with their errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "kodawari/birds/flight.hpp"
#include "kodawari/scene/scene.hpp"
#include "quat_math.hpp"

using namespace kodawari;
using namespace kodawari::birds;

namespace {

constexpr float kDeg = 0.017453292f;

using test_math::mul;
using test_math::rotate;

gpu::BirdParams bird_of(WingType type, float speed) {
    const WingTypeSpec& spec = wing_type_spec(type);
    gpu::BirdParams bird{};
    bird.motion = {speed, spec.flap_frequency, spec.amplitude, 0.0f};
    bird.flight = flight_params(spec);
    bird.shape = shape_params(spec);
    bird.ids = {0, static_cast<std::uint32_t>(type), 0, 0};
    return bird;
}

// A straight level route along +Z of three 30 m segments: take-off, cruise, landing.
BirdWorld perch_world(WingType type = WingType::Pigeon) {
    BirdWorld world;
    RouteSpec r;
    for (int i = 0; i <= 9; ++i) r.points.push_back({0.0f, 0.0f, 10.0f * static_cast<float>(i)});
    r.modes = {SegmentMode::TakeOff, SegmentMode::Auto, SegmentMode::Landing};
    EXPECT_TRUE(world.add_route(r, "perch").ok());
    world.birds.push_back(bird_of(type, 10.0f));
    return world;
}

std::vector<BirdFrame> fly(const BirdWorld& world, float seconds, std::size_t bird = 0) {
    const gpu::FlightUniforms u = world.uniforms();
    gpu::BirdState state = initial_state();
    std::vector<BirdFrame> frames;
    const auto count = static_cast<std::uint32_t>(seconds * world.fps);
    for (std::uint32_t k = 0; k < count; ++k) frames.push_back(step_bird(world, u, world.birds[bird], state, k));
    return frames;
}

std::uint32_t mode_of(const BirdFrame& f) { return static_cast<std::uint32_t>(f.diag.acceleration.w); }

}  // namespace

TEST(FlightModes, TakeOffStartsAtRestAndReachesTheCruiseSpeed) {
    const BirdWorld world = perch_world();
    const std::vector<BirdFrame> frames = fly(world, 8.0f);
    const float dt = 1.0f / world.fps;
    // F.2: 0.3 s crouching on the perch, then uniform acceleration over L0 = 30 m at
    // 10 m/s: 2 L0 / v = 6 s. The arc-length table's error is far below the 1e-3 m
    // allowed here (SPEC B.3: 32 Hermite intervals per segment).
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const float t = static_cast<float>(k) * dt;
        const BirdFrame& f = frames[k];
        const float tau = t - kCrouchSeconds;
        const float expected_s = tau < 0.0f ? 0.0f : tau < 6.0f ? 10.0f * tau * 10.0f * tau / 120.0f : 10.0f * tau - 30.0f;
        EXPECT_NEAR(f.pose.position.z, expected_s, 1e-3f + 1e-5f * expected_s) << "t " << t;
        const float expected_fraction = tau < 0.0f ? 0.0f : std::min(10.0f * tau / 60.0f, 1.0f);
        EXPECT_NEAR(f.diag.flight.x, expected_fraction, 1e-5f) << "t " << t;
        if (tau < 6.0f) {
            EXPECT_EQ(mode_of(f), KW_MODE_TAKEOFF) << "t " << t;
        }
    }
    // While crouching the wings are folded and still (the phase stops), the bird sits.
    EXPECT_EQ(frames[0].diag.attitude.w, frames[10].diag.attitude.w);
    EXPECT_NEAR(frames[10].diag.angles.z, kFoldedWings.arm1_heading, 1e-6f);
    // Beats 1.25 times as fast during the take-off (F.3).
    float phase_step = frames[61].diag.attitude.w - frames[60].diag.attitude.w;
    if (phase_step < 0.0f) phase_step += 2.0f * 3.14159265f;  // wrapped
    EXPECT_NEAR(phase_step, 2.0f * 3.14159265f * 1.25f * wing_type_spec(WingType::Pigeon).flap_frequency * dt, 1e-4f);
    // Leaves the take-off for level flight at the end of the segment.
    EXPECT_EQ(mode_of(frames.back()), KW_MODE_LEVEL);
}

TEST(FlightModes, LandingTouchesDownOnTheEndPointAtZeroSpeedAndStays) {
    const BirdWorld world = perch_world();
    const std::vector<BirdFrame> frames = fly(world, 20.0f);
    const float dt = 1.0f / world.fps;
    // Touchdown at 0.3 + 6 (take-off) + 3 (cruise) + 6 (landing) = 15.3 s.
    float largest_step = 0.0f;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const float t = static_cast<float>(k) * dt;
        // Along the route (z); y also carries the wingbeat's bob.
        if (k > 0) largest_step = std::max(largest_step, frames[k].pose.position.z - frames[k - 1].pose.position.z);
        if (t > 9.4f) {
            EXPECT_EQ(mode_of(frames[k]), KW_MODE_LANDING) << "t " << t;
        }
        if (t > 15.31f) {
            EXPECT_NEAR(frames[k].pose.position.z, 90.0f, 1e-3f) << "t " << t;
            EXPECT_EQ(frames[k].diag.flight.x, 0.0f);
        }
    }
    // The speed never exceeds the cruise speed: no jump at any junction.
    EXPECT_LE(largest_step, 10.0f * dt * 1.001f);
    // In the last metre the bird is slower than a fifth of the cruise speed: speed falls
    // as sqrt(distance left) (uniform deceleration), sqrt(2 * 1 / 60) * 10 = 1.8 m/s.
    const auto index_at = [&](float seconds) { return static_cast<std::size_t>(seconds / dt); };
    EXPECT_LT(frames[index_at(15.0f) + 1].pose.position.z - frames[index_at(15.0f)].pose.position.z, 0.2f * 10.0f * dt);
    // Flared before touchdown (body pitched up, tail spread), wings folded 0.5 s after.
    const BirdFrame& flare = frames[index_at(15.0f)];
    EXPECT_GT(flare.diag.flight.y, 0.5f);
    EXPECT_GT(flare.pose.position.w, 0.7f);
    const BirdFrame& perched = frames.back();
    EXPECT_NEAR(perched.diag.angles.z, kFoldedWings.arm1_heading, 1e-6f);
    EXPECT_NEAR(perched.diag.flight.y, 0.0f, 1e-6f);
}

TEST(FlightModes, APerchedBirdSitsLevelFacingAlongTheRoute) {
    // A take-off that climbs at 45 degrees toward +X: on the perch the bird is level.
    BirdWorld world;
    RouteSpec r;
    r.points = {{0, 0, 0}, {5, 5, 0}, {10, 10, 0}, {15, 15, 0}, {25, 15, 0}, {35, 15, 0}, {45, 15, 0}};
    r.modes = {SegmentMode::TakeOff, SegmentMode::Auto};
    ASSERT_TRUE(world.add_route(r, "climb").ok());
    world.birds.push_back(bird_of(WingType::Gull, 12.0f));
    const BirdFrame f = fly(world, 0.1f).front();
    const float e = f.diag.flight.y;  // the crouch's extra pitch, undone (F.4)
    const gpu::vec4 level = mul(f.pose.rotation[KW_PART_BODY], gpu::vec4{std::sin(0.5f * e), 0, 0, std::cos(0.5f * e)});
    const Vec3 nose = rotate(level, {0, 0, 1});
    EXPECT_NEAR(nose.x, 1.0f, 1e-5f);
    EXPECT_NEAR(nose.y, 0.0f, 1e-5f);
    EXPECT_NEAR(e, -0.2f, 1e-5f);  // crouching: nose down
}

TEST(FlightModes, GullsFlapAndGlideInTurnOnLevelStretchesOnly) {
    const WingTypeSpec& gull = wing_type_spec(WingType::Gull);
    ASSERT_GT(gull.flap_glide_beats, 0.0f);
    for (const float climb_deg : {0.0f, -4.0f, 6.0f}) {
        BirdWorld world;
        RouteSpec r;
        const float c = std::cos(climb_deg * kDeg), s = std::sin(climb_deg * kDeg);
        for (int i = 0; i <= 30; ++i) r.points.push_back({0.0f, 20.0f * s * static_cast<float>(i), 20.0f * c * static_cast<float>(i)});
        ASSERT_TRUE(world.add_route(r, "straight").ok());
        world.birds.push_back(bird_of(WingType::Gull, 12.0f));
        const std::vector<BirdFrame> frames = fly(world, 40.0f);
        // Run lengths (frames) of gliding and flapping; the first and last are partial.
        std::vector<std::pair<bool, int>> runs;
        for (const BirdFrame& f : frames) {
            const bool glide = mode_of(f) == KW_MODE_GLIDE;
            if (runs.empty() || runs.back().first != glide) runs.push_back({glide, 0});
            ++runs.back().second;
        }
        if (climb_deg > 0.0f) {
            EXPECT_EQ(runs.size(), 1u) << "a glide on a climb loses speed";
            EXPECT_FALSE(runs.front().first);
            continue;
        }
        ASSERT_GE(runs.size(), 6u);
        // Each glide lasts g seconds and each flapping stretch b beats at f Hz (the phase
        // stops in a glide, so b beats take b / f seconds), to a frame.
        const float frame_seconds = 1.0f / world.fps;
        for (std::size_t i = 1; i + 1 < runs.size(); ++i) {
            const float seconds = static_cast<float>(runs[i].second) * frame_seconds;
            const float expected = runs[i].first ? gull.flap_glide_seconds : gull.flap_glide_beats / gull.flap_frequency;
            EXPECT_NEAR(seconds, expected, frame_seconds + 1e-4f) << "run " << i << (runs[i].first ? " (glide)" : " (flapping)");
        }
    }
}

TEST(FlightModes, OnlyHoveringTypesHoverWithFigureEightStrokes) {
    BirdWorld world;
    RouteSpec r;
    r.points = {{0, 2, 0}, {0, 2, 1}, {0, 2, 2}, {0, 2, 3}};
    ASSERT_TRUE(world.add_route(r, "slow").ok());
    world.birds = {bird_of(WingType::Hummingbird, 1.0f), bird_of(WingType::Hummingbird, 8.0f), bird_of(WingType::Pigeon, 1.0f)};
    const std::vector<BirdFrame> slow = fly(world, 1.0f, 0), fast = fly(world, 1.0f, 1), pigeon = fly(world, 1.0f, 2);
    EXPECT_EQ(mode_of(slow.back()), KW_MODE_HOVER);
    EXPECT_EQ(mode_of(fast.back()), KW_MODE_LEVEL);
    EXPECT_EQ(mode_of(pigeon.back()), KW_MODE_LEVEL);
    // The stroke sweeps fore and aft (arm1 heading 0.95 A cos t) with a figure eight
    // (arm1 pitch 0.2 A sin 2t), with the body pitched up (F.3, F.4).
    float sweep_min = 1.0f, sweep_max = -1.0f;
    for (const BirdFrame& f : slow) {
        sweep_min = std::min(sweep_min, f.diag.angles.z);
        sweep_max = std::max(sweep_max, f.diag.angles.z);
        EXPECT_NEAR(f.diag.angles.x, 0.2f * std::sin(2.0f * f.diag.attitude.w), 1e-5f);
    }
    EXPECT_LT(sweep_min, -0.9f);
    EXPECT_GT(sweep_max, 0.9f);
    EXPECT_NEAR(slow.back().diag.flight.y, 0.6f, 0.03f);  // plus the pitch oscillation's 0.04 * 0.5
}

TEST(FlightModes, TheHeadHoldsTheHorizonAndLooksIntoTheTurn) {
    // A level right turn (toward -X) at 15 m/s on a radius of about 20 m: banked near 49
    // degrees.
    BirdWorld world;
    RouteSpec r;
    const float k = 0.5523f * 20.0f;
    r.points = {{0, 10, 0}, {0, 10, k}, {-20 + k, 10, 20}, {-20, 10, 20}, {-20 - k, 10, 20}, {-40, 10, k}, {-40, 10, 0}};
    ASSERT_TRUE(world.add_route(r, "turn").ok());
    world.birds.push_back(bird_of(WingType::Pigeon, 15.0f));
    const std::vector<BirdFrame> frames = fly(world, 2.0f);
    const BirdFrame& f = frames[60];  // 1 s in, mid-turn
    ASSERT_GT(f.diag.attitude.z, 40 * kDeg);
    const gpu::vec4 body = f.pose.rotation[KW_PART_BODY];
    const gpu::vec4 head = mul(body, f.pose.rotation[KW_PART_HEAD]);
    const Vec3 body_up = rotate(body, {0, 1, 0}), head_up = rotate(head, {0, 1, 0});
    // The head takes back 70% of the bank (F.5): its up axis is much nearer vertical.
    EXPECT_LT(std::acos(head_up.y), 0.45f * std::acos(body_up.y));
    // It looks into the turn: its nose turned right of the body's (toward the body's -X).
    const Vec3 head_nose_in_body = rotate(f.pose.rotation[KW_PART_HEAD], {0, 0, 1});
    EXPECT_LT(head_nose_in_body.x, -0.2f);
    // The tail spreads with the bank: level flight's 0.15 plus 0.4 |sin bank| (F.5).
    EXPECT_NEAR(f.pose.position.w, 0.15f + kTailBankSpread * std::sin(f.diag.attitude.z), 1e-4f);
}

TEST(FlightModes, TheBodyBobsWithTheWingbeatAndNotInAGlide) {
    BirdWorld world;
    RouteSpec r;
    for (int i = 0; i <= 6; ++i) r.points.push_back({0.0f, 10.0f, 10.0f * static_cast<float>(i)});
    r.modes = {SegmentMode::Auto, SegmentMode::Glide};
    ASSERT_TRUE(world.add_route(r, "bob").ok());
    world.birds.push_back(bird_of(WingType::Pigeon, 10.0f));
    const std::vector<BirdFrame> frames = fly(world, 5.0f);
    float flap_low = 1e9f, flap_high = -1e9f, glide_low = 1e9f, glide_high = -1e9f;
    for (const BirdFrame& f : frames) {
        const bool flapping = f.pose.position.z < 25.0f, gliding = f.pose.position.z > 45.0f;
        if (flapping) {
            flap_low = std::min(flap_low, f.pose.position.y);
            flap_high = std::max(flap_high, f.pose.position.y);
        }
        if (gliding) {
            glide_low = std::min(glide_low, f.pose.position.y);
            glide_high = std::max(glide_high, f.pose.position.y);
        }
    }
    // KW_BOB_HEIGHT 0.05 body lengths up and down: 2 * 0.05 * 0.33 m for a pigeon.
    EXPECT_NEAR(flap_high - flap_low, 2.0f * kBobHeight * wing_type_spec(WingType::Pigeon).body_length, 2e-3f);
    EXPECT_LT(glide_high - glide_low, 1e-4f);
}

TEST(FlightModes, RouteModesInTheSceneFormatAreChecked) {
    using nlohmann::json;
    auto scene_with = [](const json& route, const std::string& wing = "pigeon") {
        json doc = {{"format", "kodawari-scene"}, {"version", 1}};
        doc["flocks"] = json::array({{{"wing_type", wing}, {"count", 2}, {"route", route}}});
        return doc;
    };
    const json points = json::array({json::array({0, 5, 0}), json::array({0, 5, 10}), json::array({0, 6, 20}), json::array({0, 6, 30}),
                                     json::array({0, 6, 40}), json::array({0, 5, 50}), json::array({0, 5, 60})});
    auto error_of = [](const json& doc) -> std::string {
        auto scene = parse_scene(doc.dump(), "test.json");
        if (!scene.ok()) return scene.error().message;
        auto world = build_bird_world(scene.value());
        return world.ok() ? "(no error)" : world.error().message;
    };
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"takeoff", "landing"}}})), "(no error)");
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"landing", "auto"}}})),
              "test.json: $.flocks[0].route.modes[0]: a route cannot start with \"landing\" (a landing ends the route on a perch)");
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"auto", "takeoff"}}})),
              "test.json: $.flocks[0].route.modes[1]: \"takeoff\" may only be the first segment (a take-off starts from a perch)");
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"auto", "soar"}}})),
              "test.json: $.flocks[0].route.modes[1]: expected one of \"auto\", \"glide\", \"takeoff\", \"landing\", \"hover\", got \"soar\"");
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"auto"}}})),
              "test.json: $.flocks[0].route.modes: expected one mode per segment (2), got 1");
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"hover", "auto"}}})),
              "test.json: $.flocks[0].route.modes[0]: \"hover\" needs a bird that can hover (\"hummingbird\"); a pigeon cannot");
    EXPECT_EQ(error_of(scene_with({{"points", points}, {"modes", {"hover", "auto"}}}, "hummingbird")), "(no error)");
    json loop = json::array({json::array({0, 5, 0}), json::array({10, 5, 0}), json::array({10, 5, 10}), json::array({0, 5, 10}),
                             json::array({-10, 5, 10}), json::array({-10, 5, 0}), json::array({0, 5, 0})});
    EXPECT_EQ(error_of(scene_with({{"points", loop}, {"loop", true}, {"modes", {"takeoff", "auto"}}})),
              "test.json: $.flocks[0].route.modes[0]: \"takeoff\" needs an open route; this one loops");
    json parametric = scene_with({{"points", points}, {"modes", {"auto", "landing"}}});
    parametric["flocks"][0]["timing"] = "parametric";
    EXPECT_EQ(error_of(parametric),
              "test.json: $.flocks[0].route.modes[1]: \"landing\" sets the speed along the route; expected \"timing\": \"arc-length\"");
}
