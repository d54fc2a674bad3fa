// SPEC B.4-B.6: attitude, flight modes with hysteresis, transitions, the part rotations.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "kodawari/birds/flight.hpp"
#include "kodawari/backends/compare.hpp"
#include "quat_math.hpp"

using namespace kodawari;
using namespace kodawari::birds;

namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

using test_math::rotate;

RouteSample moving(Vec3 velocity, Vec3 acceleration = {}) {
    RouteSample s;
    s.velocity = velocity;
    s.attitude_velocity = velocity;
    s.acceleration = acceleration;
    s.direction = velocity;
    s.lift = acceleration.y;
    return s;
}

// A level straight, then a 30-degree climb: the mode change is well past the
// hysteresis thresholds.
BirdWorld climb_world(float fps) {
    BirdWorld world;
    world.fps = fps;
    RouteSpec r;
    const float c = std::cos(30 * kDeg), s = std::sin(30 * kDeg);
    r.points = {{0, 0, 0}, {0, 0, 20}, {0, 0, 40}, {0, 0, 60},
                {0, 20 * s, 60 + 20 * c}, {0, 40 * s, 60 + 40 * c}, {0, 60 * s, 60 + 60 * c}};
    EXPECT_TRUE(world.add_route(r, "x").ok());
    gpu::BirdParams bird{};
    bird.motion = {10.0f, 4.0f, 1.0f, 0.25f};
    world.birds.push_back(bird);
    return world;
}

}  // namespace

TEST(Flight, HeadingAndClimbFollowTheVelocity) {
    const gpu::FlightUniforms u = BirdWorld{}.uniforms();
    EXPECT_NEAR(attitude(u, moving({0, 0, 5})).yaw, 0.0f, 1e-6f);
    EXPECT_NEAR(attitude(u, moving({5, 0, 0})).yaw, 90 * kDeg, 1e-6f);
    EXPECT_NEAR(attitude(u, moving({0, 0, -5})).yaw, 180 * kDeg, 1e-6f);
    EXPECT_NEAR(attitude(u, moving({0, 5, 5 * std::sqrt(3.0f)})).pitch, 30 * kDeg, 1e-6f);
}

TEST(Flight, CoordinatedTurnBanksIntoTheTurnAndClamps) {
    BirdWorld world;
    gpu::FlightUniforms u = world.uniforms();
    // Flying +Z, turning right (toward -X) at 5 m/s^2: tan(bank) = 5 / g, right wing down.
    const Attitude right = attitude(u, moving({0, 0, 10}, {-5, 0, 0}));
    EXPECT_NEAR(right.bank, std::atan2(5.0f, 9.81f), 1e-6f);
    EXPECT_NEAR(attitude(u, moving({0, 0, 10}, {5, 0, 0})).bank, -right.bank, 1e-6f);
    EXPECT_NEAR(attitude(u, moving({0, 0, 10}, {-500, 0, 0})).bank, 60 * kDeg, 1e-6f);  // the default max bank
    // Acceleration along the path does not bank.
    EXPECT_NEAR(attitude(u, moving({0, 0, 10}, {0, 0, 3})).bank, 0.0f, 1e-6f);
}

TEST(Flight, SeedBankRuleIsEquation4_9) {
    BirdWorld world;
    world.settings.bank_rule = BankRule::Seed;
    const gpu::FlightUniforms u = world.uniforms();
    // a at 60 degrees from v: theta = acos(0.5) - pi/2 = -30 degrees; v x a points down
    // for a toward -X when flying +Z, so the sign stays.
    const Attitude a = attitude(u, moving({0, 0, 10}, {-std::sin(60 * kDeg), 0, std::cos(60 * kDeg)}));
    EXPECT_NEAR(a.bank, -30 * kDeg, 1e-5f);
    const Attitude b = attitude(u, moving({0, 0, 10}, {std::sin(60 * kDeg), 0, std::cos(60 * kDeg)}));
    EXPECT_NEAR(b.bank, 30 * kDeg, 1e-5f);
}

TEST(Flight, ClimbModesUseHysteresis) {
    const gpu::FlightUniforms u = BirdWorld{}.uniforms();  // enter 10, exit 5 degrees
    auto climb = [](float deg) { return moving({0, 10 * std::sin(deg * kDeg), 10 * std::cos(deg * kDeg)}); };
    std::uint32_t mode = KW_MODE_UNSET;
    const std::pair<float, std::uint32_t> steps[] = {{0, KW_MODE_LEVEL},    {8, KW_MODE_LEVEL},    {12, KW_MODE_ASCEND},
                                                     {7, KW_MODE_ASCEND},   {4, KW_MODE_LEVEL},    {-8, KW_MODE_LEVEL},
                                                     {-12, KW_MODE_DESCEND}, {-6, KW_MODE_DESCEND}, {-4, KW_MODE_LEVEL},
                                                     {-20, KW_MODE_DESCEND}, {20, KW_MODE_ASCEND}};
    for (const auto& [deg, expected] : steps) {
        mode = next_mode(u, mode, climb(deg));
        EXPECT_EQ(mode, expected) << "climb " << deg << " degrees";
    }
}

TEST(Flight, SeedModeRuleUsesVerticalAcceleration) {
    BirdWorld world;
    world.settings.mode_rule = ModeRule::Seed;
    const gpu::FlightUniforms u = world.uniforms();
    EXPECT_EQ(next_mode(u, KW_MODE_LEVEL, moving({0, 0, 10}, {0, 0.06f, 0})), KW_MODE_ASCEND);
    EXPECT_EQ(next_mode(u, KW_MODE_ASCEND, moving({0, 0, 10}, {0, 0.04f, 0})), KW_MODE_LEVEL);
    EXPECT_EQ(next_mode(u, KW_MODE_LEVEL, moving({0, 0, 10}, {0, -0.06f, 0})), KW_MODE_DESCEND);
}

TEST(Flight, PartsPointWhereTheConventionsSay) {
    BirdWorld world = climb_world(60.0f);
    const gpu::FlightUniforms u = world.uniforms();
    gpu::BirdState state = initial_state();
    // Phase 0.25 + frames: find a frame in the downstroke, where arm1 pitch < 0.
    for (std::uint32_t frame = 0; frame < 40; ++frame) {
        const BirdFrame f = step_bird(world, u, world.birds[0], state, frame);
        // The nose points along the velocity once the mode's extra pitch (diag.flight.y,
        // docs/flight-modes.md F.4, a turn about the body's own lateral axis) is undone.
        const float e = f.diag.flight.y;
        const gpu::vec4& q = f.pose.rotation[KW_PART_BODY];
        const gpu::vec4 undo{std::sin(0.5f * e), 0.0f, 0.0f, std::cos(0.5f * e)};
        const gpu::vec4 level{q.w * undo.x + q.x * undo.w, q.y * undo.w + q.z * undo.x, q.z * undo.w - q.y * undo.x,
                              q.w * undo.w - q.x * undo.x};
        const Vec3 nose = rotate(level, {0, 0, 1});
        const Vec3 v{f.diag.velocity.x, f.diag.velocity.y, f.diag.velocity.z};
        const float speed = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
        EXPECT_NEAR(nose.x, v.x / speed, 1e-5f);
        EXPECT_NEAR(nose.y, v.y / speed, 1e-5f);
        EXPECT_NEAR(nose.z, v.z / speed, 1e-5f);
        // Positive pitch = wingtip up; the right wing mirrors the left.
        const Vec3 left_tip = rotate(f.pose.rotation[KW_PART_LEFT_ARM1], {1, 0, 0});
        const Vec3 right_tip = rotate(f.pose.rotation[KW_PART_RIGHT_ARM1], {-1, 0, 0});
        EXPECT_NEAR(left_tip.y, std::sin(f.diag.angles.x), 1e-5f);
        EXPECT_NEAR(right_tip.y, left_tip.y, 1e-6f);
        EXPECT_NEAR(right_tip.x, -left_tip.x, 1e-6f);
    }
    // Banking right puts the right wing (-X) down.
    const gpu::vec4 body = [] {
        gpu::vec4 q{0, 0, std::sin(0.5f * 0.4f), std::cos(0.5f * 0.4f)};
        return q;
    }();
    EXPECT_LT(rotate(body, {-1, 0, 0}).y, 0.0f);
}

TEST(Flight, TransitionsAreTimeBasedAndContinuous) {
    // The same route at 60 and 120 fps: the blend reaches the same alpha at the same
    // time (rates per 1/60 s, SPEC B.6), and no frame jumps at a mode change.
    std::vector<float> alpha60, alpha120;
    for (float fps : {60.0f, 120.0f}) {
        BirdWorld world = climb_world(fps);
        const gpu::FlightUniforms u = world.uniforms();
        gpu::BirdState state = initial_state();
        std::vector<float>& alpha = fps == 60.0f ? alpha60 : alpha120;
        gpu::vec4 previous{};
        float worst_jump = 0.0f, worst_jump_steady = 0.0f;
        std::uint32_t previous_mode = KW_MODE_UNSET;
        for (std::uint32_t frame = 0; frame < static_cast<std::uint32_t>(12 * fps); ++frame) {
            const BirdFrame f = step_bird(world, u, world.birds[0], state, frame);
            alpha.push_back(f.diag.velocity.w);
            const auto mode = static_cast<std::uint32_t>(f.diag.acceleration.w);
            if (frame > 0) {
                const float jump = static_cast<float>(quaternion_angle(previous, f.pose.rotation[KW_PART_LEFT_ARM2]));
                if (mode != previous_mode) worst_jump = std::max(worst_jump, jump);
                else worst_jump_steady = std::max(worst_jump_steady, jump);
            }
            previous = f.pose.rotation[KW_PART_LEFT_ARM2];
            previous_mode = mode;
        }
        EXPECT_GT(worst_jump_steady, 0.0f);
        EXPECT_LE(worst_jump, worst_jump_steady) << "a mode change must not jump more than an ordinary frame does";
    }
    // The climb starts at 6 s. Frame f at 60 fps and 2f at 120 fps are the same time.
    int blending = 0;
    for (std::size_t f = 0; f < alpha60.size(); ++f) {
        if (alpha60[f] < 1.0f) ++blending;
        // One frame at 60 fps can shift when the change is seen by up to 1/60 s.
        EXPECT_NEAR(alpha60[f], alpha120[2 * f], 0.036f + 1e-5f) << "frame " << f;
    }
    EXPECT_GT(blending, 20) << "the route must produce transitions";
}

TEST(Flight, BodyRotationIsTheAttitudesRotation) {
    // body_rotation() builds the quaternion without trig; it must equal
    // yaw(Y) * climb(-X) * bank(Z) of attitude() for every direction, including flight
    // backwards (yaw near 180 degrees), steep climbs and clamped banks.
    for (BankRule rule : {BankRule::Coordinated, BankRule::Seed}) {
        BirdWorld world;
        world.settings.bank_rule = rule;
        const gpu::FlightUniforms u = world.uniforms();
        std::uint32_t seed = 12345;
        auto next = [&] {
            seed = seed * 1664525u + 1013904223u;
            return static_cast<float>(seed >> 8) / 16777216.0f * 2.0f - 1.0f;
        };
        for (int i = 0; i < 2000; ++i) {
            const Vec3 v{20 * next(), 15 * next(), 20 * next()};
            const Vec3 a{30 * next(), 5 * next(), 30 * next()};
            const RouteSample sample = moving(v, a);
            const Attitude att = attitude(u, sample);
            auto axis = [](float x, float y, float z, float angle) {
                return gpu::vec4{x * std::sin(0.5f * angle), y * std::sin(0.5f * angle), z * std::sin(0.5f * angle), std::cos(0.5f * angle)};
            };
            auto mul = [](const gpu::vec4& p, const gpu::vec4& q) {
                return gpu::vec4{p.w * q.x + p.x * q.w + p.y * q.z - p.z * q.y, p.w * q.y - p.x * q.z + p.y * q.w + p.z * q.x,
                                 p.w * q.z + p.x * q.y - p.y * q.x + p.z * q.w, p.w * q.w - p.x * q.x - p.y * q.y - p.z * q.z};
            };
            const gpu::vec4 expected = mul(mul(axis(0, 1, 0, att.yaw), axis(1, 0, 0, -att.pitch)), axis(0, 0, 1, att.bank));
            // Float trig against square roots: a few 1e-7 rad.
            EXPECT_LT(quaternion_angle(body_rotation(u, sample), expected), 2e-6) << "v " << v.x << " " << v.y << " " << v.z;
        }
    }
}
