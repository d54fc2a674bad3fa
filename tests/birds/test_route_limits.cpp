// Routes a bird can fly (issue 14): route demands per segment, the scene-level check
// with its messages, and the timing fit (docs/wing-types.md "Route limits").
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "kodawari/birds/route_limits.hpp"
#include "kodawari/scene/route_check.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

// One gull on `route` (JSON control points) at `speed`, timing `timing`.
Scene flock_scene(const std::string& points, const std::string& timing = "arc-length", double speed = 12.0,
                  const std::string& extra = "", const std::string& scene_extra = "") {
    const std::string text = R"({"format": "kodawari-scene", "version": 1, "name": "t", "fps": 30, "duration": 1)" +
                             scene_extra + R"(,
        "flocks": [{"name": "gulls", "wing_type": "gull", "count": 3, "seed": 5, "speed": )" +
                             std::to_string(speed) + R"(, "speed_jitter": 0.05, "timing": ")" + timing + R"(",
                     "route": {"points": )" + points + extra + R"(}}]})";
    auto scene = parse_scene(text, "scenes/x.json");
    EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
    return scene.value();
}

// A straight, level first segment, then a hairpin of about 5 m radius (segment 1).
const std::string kTightTurn = "[[0,20,0],[0,20,20],[0,20,40],[0,20,60],[0,20,68],[10,20,68],[10,20,60],"
                               "[10,20,40],[10,20,20],[10,20,0]]";
// Level, then a straight 40 degree climb in segment 1 (a kink at the junction: a corner
// of 40 degrees too).
const std::string kSteepClimb = "[[0,20,0],[0,20,20],[0,20,40],[0,20,60],[0,36.8,80],[0,53.6,100],[0,70.4,120]]";

}  // namespace

TEST(RouteLimits, DemandsOfAKnownCircle) {
    // A quarter circle of radius 50 m by the usual cubic (handle 0.5523 r). Its curvature
    // is not quite constant: 1/50.8 to 1/49.60 m (worked independently at the same 257
    // samples), so at 10 m/s the largest turn load is 100 / 49.60 = 2.016 m/s^2. The
    // tolerance, 1e-3 relative, is the float rounding of the control points and nothing
    // more; level, so no climb or dive; constant speed.
    birds::BirdWorld world;
    birds::RouteSpec route;
    const float h = 0.55228475f * 50.0f;
    route.points = {{50, 10, 0}, {50, 10, h}, {h, 10, 50}, {0, 10, 50}};
    ASSERT_TRUE(world.add_route(route, "t").ok());
    const auto d = birds::route_demands(world, 0, 10.0f);
    ASSERT_EQ(d.size(), 1u);
    EXPECT_NEAR(d[0].turn_acceleration, 2.016, 2e-3);
    EXPECT_NEAR(d[0].turn_radius, 49.60, 0.05);
    EXPECT_NEAR(d[0].climb, 0.0, 1e-6);
    EXPECT_LT(d[0].speed_change, 1e-9);
}

TEST(RouteLimits, ParametricTimingSeesTheSpeedChange) {
    // A straight line with handles at 1/10 and 9/10 of a 100 m segment, D = 10 s:
    // P'(u) = 3 [10 (1-u)^2 + 160 u (1-u) + 10 u^2], so the speed runs 3 -> 13.5 -> 3 m/s,
    // and P''(u) = 420 (1 - 2u): dv/dt = P'' / D^2 is largest at the ends, 4.2 m/s^2. The
    // first finite difference averages P'' over u in [0, 1/256]: 4.2 (1 - 1/256) = 4.184,
    // hence the tolerance 0.02.
    birds::BirdWorld world;
    birds::RouteSpec route;
    route.points = {{0, 0, 0}, {0, 0, 10}, {0, 0, 90}, {0, 0, 100}};
    route.timing = birds::RouteTiming::Parametric;
    route.segment_duration = 10.0f;
    ASSERT_TRUE(world.add_route(route, "t").ok());
    const auto d = birds::route_demands(world, 0, 0.0f);
    EXPECT_NEAR(d[0].speed_change, 4.2, 0.02);
    // The same route at arc-length timing: constant speed.
    birds::BirdWorld arc;
    route.timing = birds::RouteTiming::ArcLength;
    ASSERT_TRUE(arc.add_route(route, "t").ok());
    EXPECT_LT(birds::route_demands(arc, 0, 10.0f)[0].speed_change, 1e-9);
}

TEST(RouteLimits, TakeOffAndLandingAreChargedTheirAcceleration) {
    // docs/flight-modes.md F.2: from rest to 10 m/s over a 20 m take-off segment is
    // v^2 / (2 L) = 2.5 m/s^2, and to rest over a 40 m landing 1.25 m/s^2; the cruise
    // segment between them keeps its speed.
    birds::BirdWorld world;
    birds::RouteSpec route;
    route.points = {{0, 0, 0}, {0, 0, 5}, {0, 0, 15}, {0, 0, 20}, {0, 0, 25}, {0, 0, 35}, {0, 0, 40},
                    {0, 0, 50}, {0, 0, 70}, {0, 0, 80}};
    route.modes = {birds::SegmentMode::TakeOff, birds::SegmentMode::Auto, birds::SegmentMode::Landing};
    ASSERT_TRUE(world.add_route(route, "t").ok());
    const auto d = birds::route_demands(world, 0, 10.0f);
    EXPECT_NEAR(d[0].speed_change, 2.5, 1e-4);  // the float arc length of a straight segment
    EXPECT_LT(d[1].speed_change, 1e-9);
    EXPECT_NEAR(d[2].speed_change, 1.25, 1e-4);
}

TEST(RouteLimits, TightTurnWarnsNamingSegmentAndLimit) {
    const Scene scene = flock_scene(kTightTurn);
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    // The turn, and the bank jumps from straight flight into the hairpin and out of it
    // (junctions 1 and 2, sorted by segment then limit).
    ASSERT_EQ(warnings.value().size(), 3u);
    EXPECT_EQ(warnings.value()[1].limit, RouteLimit::BankJump);
    EXPECT_EQ(warnings.value()[1].segment, 1u);
    EXPECT_EQ(warnings.value()[2].limit, RouteLimit::BankJump);
    EXPECT_EQ(warnings.value()[2].segment, 2u);
    const RouteWarning& w = warnings.value()[0];
    EXPECT_EQ(w.segment, 1u);
    EXPECT_EQ(w.limit, RouteLimit::TurnRadius);
    // The gull's minimum at its fastest bird's speed (12 m/s +- 5 %) and 60 deg of bank:
    // v^2 / (9.81 tan 60) = 8.47 to 9.34 m.
    EXPECT_GT(w.bound, 8.4);
    EXPECT_LT(w.bound, 9.4);
    EXPECT_LT(w.value, 8.0);
    EXPECT_EQ(w.message.rfind("scenes/x.json: $.flocks[0] \"gulls\": segment 1 (u = ", 0), 0u) << w.message;
    EXPECT_NE(w.message.find("turn radius"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("is below the gull's minimum"), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("(max bank 60 deg)"), std::string::npos) << w.message;
}

TEST(RouteLimits, SteepClimbWarns) {
    const Scene scene = flock_scene(kSteepClimb);
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    ASSERT_EQ(warnings.value().size(), 2u);  // the climb, and the corner where it starts
    EXPECT_EQ(warnings.value()[1].limit, RouteLimit::Corner);
    const RouteWarning& w = warnings.value()[0];
    EXPECT_EQ(w.segment, 1u);
    EXPECT_EQ(w.limit, RouteLimit::Climb);
    // Segment 1 is a straight line climbing atan(16.8 / 20) = 40.03 deg throughout.
    EXPECT_NEAR(w.value, 40.03, 0.01);
    EXPECT_NE(w.message.find("segment 1 (u = "), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("): climb 40 deg is above the gull's maximum 14.8 deg"), std::string::npos) << w.message;
}

TEST(RouteLimits, GentleRoutePasses) {
    // A 200 m wide level loop at the gull's 12 m/s: radius ~100 m >> 9 m.
    const Scene scene = flock_scene("[[100,20,0],[100,20,55],[55,20,100],[0,20,100],[-55,20,100],[-100,20,55],"
                                    "[-100,20,0],[-100,20,-55],[-55,20,-100],[0,20,-100],[55,20,-100],[100,20,-55],"
                                    "[100,20,0]]", "arc-length", 12.0, R"(, "loop": true)");
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    EXPECT_TRUE(warnings.value().empty()) << warnings.value().front().message;
}

TEST(RouteLimits, FitLowersOnlyTheSpeed) {
    Scene scene = flock_scene(kTightTurn);
    const Scene before = scene;
    auto changes = fit_routes(scene);
    ASSERT_TRUE(changes.ok());
    ASSERT_EQ(changes.value().size(), 1u);
    EXPECT_NE(changes.value()[0].find("$.flocks[0] \"gulls\": speed 12 -> "), std::string::npos) << changes.value()[0];
    ASSERT_TRUE(scene.flocks[0].speed.has_value());
    EXPECT_LT(*scene.flocks[0].speed, 12.0f);
    // Nothing else moved: the route and the other flock fields are as they were.
    EXPECT_EQ(scene.flocks[0].route->points, before.flocks[0].route->points);
    EXPECT_EQ(scene.flocks[0].speed_jitter, before.flocks[0].speed_jitter);
    EXPECT_EQ(scene.flocks[0].timing, before.flocks[0].timing);
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    EXPECT_TRUE(warnings.value().empty()) << warnings.value().front().message;
    // The largest speed that passes: 1 % faster fails again (the fit's margin is 0.1 %).
    Scene faster = scene;
    *faster.flocks[0].speed *= 1.01f;
    auto again = check_routes(faster);
    ASSERT_TRUE(again.ok());
    EXPECT_FALSE(again.value().empty());
}

TEST(RouteLimits, FitLengthensParametricSegments) {
    // Parametric timing at D = 0.5 s per 60-68 m segment: ~100 m/s in a 5 m hairpin.
    Scene scene = flock_scene(kTightTurn, "parametric", 12.0, R"(, "segment_duration": 0.5)");
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    EXPECT_FALSE(warnings.value().empty());
    auto changes = fit_routes(scene);
    ASSERT_TRUE(changes.ok());
    ASSERT_EQ(changes.value().size(), 1u);
    EXPECT_NE(changes.value()[0].find("segment_duration 0.5 -> "), std::string::npos) << changes.value()[0];
    EXPECT_GT(scene.flocks[0].route->segment_duration, 0.5f);
    EXPECT_EQ(*scene.flocks[0].speed, 12.0f);
    auto after = check_routes(scene);
    ASSERT_TRUE(after.ok());
    EXPECT_TRUE(after.value().empty()) << after.value().front().message;
}

TEST(RouteLimits, ShippedScenesAreFlyable) {
    for (const char* name : {"birds-closeup.json", "flock.json", "murmuration.json", "perch.json", "starlings.json", "tower.json"}) {
        auto scene = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name);
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        auto warnings = check_routes(scene.value());
        ASSERT_TRUE(warnings.ok()) << warnings.error().message;
        for (const RouteWarning& w : warnings.value()) ADD_FAILURE() << w.message;
    }
}

TEST(RouteLimits, GeneratedRoutesKeepToTheBirdWhereTheyCan) {
    // The same generated loop for hawks at 10 m/s (tightest turn 5.9 m: the generator
    // finds a route within it, and within the hawk's climb and dive) and at 40 m/s
    // (94 m, more than the 20 m box allows): the scene still builds, on the generator's
    // own limits, and the check says where the birds cannot follow.
    const auto scene_at = [](double speed) {
        const std::string text = R"({"format": "kodawari-scene", "version": 1, "name": "t", "fps": 30, "duration": 1,
            "flocks": [{"name": "hawks", "wing_type": "hawk", "count": 2, "seed": 3, "speed": )" +
                                 std::to_string(speed) + R"(, "generated_route": {"seed": 4, "segments": 5,
                         "center": [0, 40, 0], "extent": [20, 5, 20], "loop": true},
                         "formation": {"route_variants": 2, "jitter": 0.5}}]})";
        auto scene = parse_scene(text, "scenes/g.json");
        EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
        return scene.value();
    };
    auto slow = check_routes(scene_at(10.0));
    ASSERT_TRUE(slow.ok()) << slow.error().message;
    EXPECT_TRUE(slow.value().empty()) << slow.value().front().message;
    auto fast = check_routes(scene_at(40.0));
    ASSERT_TRUE(fast.ok()) << fast.error().message;
    ASSERT_FALSE(fast.value().empty());
    EXPECT_EQ(fast.value().front().limit, RouteLimit::TurnRadius) << fast.value().front().message;
    // The advice is the generated route's own keys (its waypoints are not the user's to move).
    for (const RouteWarning& w : fast.value()) {
        EXPECT_NE(w.message.find("; generated_route's turns are gentler with a larger extent or fewer segments"),
                  std::string::npos)
            << w.message;
        EXPECT_EQ(w.message.find("match the curvature"), std::string::npos) << w.message;
    }
}

// Issue 39: junctions. A level straight along +Z, then one turned 30 degrees toward +X
// at the junction (a corner: the heading turns 30 degrees in one frame); and an S of two
// 20 m quarter circles that meet with one direction but opposite curvature.
const std::string kCorner = "[[0,20,0],[0,20,20],[0,20,40],[0,20,60],[10,20,77.3205],[20,20,94.641],[30,20,111.962]]";
std::string all_messages(const std::vector<RouteWarning>& warnings) {
    std::string text;
    for (const RouteWarning& w : warnings) text += w.message + "\n";
    return text;
}
const std::string kSBend = "[[0,20,0],[0,20,11.05],[-8.95,20,20],[-20,20,20],[-31.05,20,20],[-40,20,28.95],[-40,20,40]]";

TEST(RouteLimits, AJunctionCornerWarns) {
    const Scene scene = flock_scene(kCorner);
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    ASSERT_EQ(warnings.value().size(), 1u) << all_messages(warnings.value());  // straight either side: no bank jump
    const RouteWarning& w = warnings.value()[0];
    EXPECT_EQ(w.limit, RouteLimit::Corner);
    EXPECT_EQ(w.segment, 1u);
    EXPECT_NEAR(w.value, 30.0, 1e-3);  // atan2(10, 17.3205): the control points' rounding only
    EXPECT_EQ(w.bound, kMaxCornerDeg);
    EXPECT_NE(w.message.find("segment 1 (u = 0): the route turns 30 deg at the junction with segment 0 (a corner"),
              std::string::npos)
        << w.message;
}

TEST(RouteLimits, FitSmoothsACornerOntoTheBisector) {
    Scene scene = flock_scene(kCorner);
    auto changes = fit_routes(scene);
    ASSERT_TRUE(changes.ok());
    ASSERT_FALSE(changes.value().empty());
    EXPECT_NE(changes.value()[0].find("route points 2 and 4 turned onto one line through point 3 (a 30 deg corner)"),
              std::string::npos)
        << changes.value()[0];
    // The junction stays; its handles keep their lengths (20 m) on the bisector, 15
    // degrees from +Z toward +X. A bend that is now a curve may then ask for a slower bird
    // (a bank jump at the junctions either side), which the same fit gives.
    const auto& p = scene.flocks[0].route->points;
    EXPECT_EQ(p[3], (std::array<float, 3>{0, 20, 60}));
    EXPECT_NEAR(p[2][0], -20.0 * std::sin(15.0 * 0.017453292519943295), 1e-4);
    EXPECT_NEAR(p[4][2], 60.0 + 20.0 * std::cos(15.0 * 0.017453292519943295), 1e-4);
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    EXPECT_TRUE(warnings.value().empty()) << warnings.value().front().message;
}

TEST(RouteLimits, ABankJumpWarnsUnlessTheRollFilterSpreadsIt) {
    // At up to 12.6 m/s (the fastest gull) on 20 m: a_lat = 7.9 m/s^2, a bank of 38.9 degrees
    // each way, a jump of 77.8 (the cubic's curvature at its ends is within 1 % of the
    // circle's). At 30 fps and tau = 0.3 s the filter rolls 1 - e^(-1/9) = 10.5 % of it in
    // the first frame, 8.2 degrees, above 4; tau = 1 s rolls 3.3 % (2.6 degrees), within.
    const Scene scene = flock_scene(kSBend);
    auto warnings = check_routes(scene);
    ASSERT_TRUE(warnings.ok());
    ASSERT_EQ(warnings.value().size(), 1u) << all_messages(warnings.value());
    const RouteWarning& w = warnings.value()[0];
    EXPECT_EQ(w.limit, RouteLimit::BankJump);
    EXPECT_EQ(w.segment, 1u);
    EXPECT_GT(w.value, 7.0);  // the fastest bird's speed is 12 m/s +- 5 %: 7.2 to 8.2 degrees
    EXPECT_LT(w.value, 8.4);
    EXPECT_NE(w.message.find("segment 1 (u = 0): the bank the route asks for jumps at the junction with segment 0 at "),
              std::string::npos)
        << w.message;
    EXPECT_NE(w.message.find(" m/s: the gull rolls "), std::string::npos) << w.message;
    EXPECT_NE(w.message.find("(match the curvature either side, or fly slower; flight.bank_time_constant 0.3 s)"),
              std::string::npos)
        << w.message;
    EXPECT_EQ(w.message.find("generated_route"), std::string::npos) << w.message;
    const Scene slow = flock_scene(kSBend, "arc-length", 12.0, "", R"(, "flight": {"bank_time_constant": 1})");
    auto spread = check_routes(slow);
    ASSERT_TRUE(spread.ok());
    EXPECT_TRUE(spread.value().empty()) << spread.value().front().message;
    // --fit-routes flies it slower instead.
    Scene fitted = scene;
    auto changes = fit_routes(fitted);
    ASSERT_TRUE(changes.ok());
    ASSERT_EQ(changes.value().size(), 1u);
    EXPECT_NE(changes.value()[0].find("speed 12 -> "), std::string::npos) << changes.value()[0];
    auto after = check_routes(fitted);
    ASSERT_TRUE(after.ok());
    EXPECT_TRUE(after.value().empty()) << after.value().front().message;
}

// A flocking flock whose frame 0 puts birds inside one of its obstacles is told so (they
// would be pushed out through it over the first seconds), per obstacle, counting the birds
// inside the solid (not its margin); obstacles clear of the start say nothing.
TEST(RouteLimits, FlockingBirdsStartingInsideAnObstacleWarn) {
    const auto check = [](const std::string& obstacles) {
        const std::string text = R"({"format": "kodawari-scene", "version": 1, "name": "t", "fps": 30, "duration": 1,
            "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 301, "seed": 3, "speed": 12,
                        "generated_route": {"seed": 3, "segments": 6, "center": [0, 40, 0], "extent": [60, 5, 60], "loop": true},
                        "formation": {"spread": [8, 3, 8]}, "flocking": {"obstacles": [)" + obstacles + "]}}]}";
        auto scene = parse_scene(text, "scenes/o.json");
        EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
        auto warnings = check_routes(scene.value());
        EXPECT_TRUE(warnings.ok());
        return warnings.value();
    };
    // A sphere round the whole route, a plane with every bird behind it, a sphere far off.
    const auto all = check(R"({"type": "sphere", "center": [0, 40, 0], "radius": 300},
                              {"type": "sphere", "center": [0, 500, 0], "radius": 10},
                              {"type": "plane", "point": [0, 100, 0], "normal": [0, 1, 0]})");
    ASSERT_EQ(all.size(), 2u) << all_messages(all);
    EXPECT_EQ(all[0].limit, RouteLimit::StartInside);
    EXPECT_EQ(all[0].segment, 0u);
    EXPECT_EQ(all[0].value, 301.0);
    EXPECT_EQ(all[0].message, "scenes/o.json: $.flocks[0] \"starlings\": 301 of 301 birds start inside flocking.obstacles[0] "
                              "(a sphere), where the route and formation put them at frame 0: they are pushed out through it "
                              "(move the obstacle, the route's start or formation.spread)");
    EXPECT_EQ(all[1].segment, 2u);
    EXPECT_EQ(all[1].value, 301.0);
    // The same plane facing down: every bird on its open side.
    const auto start = check(R"({"type": "plane", "point": [0, 100, 0], "normal": [0, -1, 0]})");
    EXPECT_TRUE(start.empty()) << all_messages(start);
}
