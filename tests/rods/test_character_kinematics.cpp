// The characters' kinematics: skeleton forward kinematics and the procedural motions.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <kodawari/vulkan/gpu_info.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>

#include "character_support.hpp"

using namespace kodawari::testing_support::characters;  // the character suites' shared helpers

// ---------------------------------------------------------------------------------------
// Kinematics: skeleton, motions, camera

TEST(CharacterKinematics, SkeletonForwardKinematics) {
    rods::Skeleton sk;
    sk.joints.push_back({"body", -1, {glm::vec3(0.0f, 1.0f, 0.0f), glm::angleAxis(0.5f * kPi, glm::vec3(0, 1, 0))}});
    sk.joints.push_back({"neck", 0, {glm::vec3(0.0f, 0.5f, 0.1f), glm::angleAxis(kPi / 6.0f, glm::vec3(1, 0, 0))}});
    sk.joints.push_back({"head", 1, {glm::vec3(0.0f, 0.0f, 0.2f), glm::quat(1, 0, 0, 0)}});
    sk.reference = 2;
    const rods::Transform placement{glm::vec3(5.0f, 0.0f, -2.0f), glm::angleAxis(-0.25f * kPi, glm::vec3(0, 1, 0))};
    std::array<rods::Transform, 3> out;
    rods::pose_skeleton(sk, {}, placement, 0.0f, out);
    // The same chain of transforms as 4x4 matrices, built independently.
    glm::mat4 m = glm::translate(glm::mat4(1.0f), placement.position) * glm::mat4_cast(placement.rotation);
    for (std::size_t j = 0; j < 3; ++j) {
        m = m * glm::translate(glm::mat4(1.0f), sk.joints[j].rest.position) * glm::mat4_cast(sk.joints[j].rest.rotation);
        EXPECT_LT(glm::length(out[j].position - glm::vec3(m[3])), 1e-5f) << sk.joints[j].name;
        EXPECT_LT(glm::length(out[j].rotation * glm::vec3(0, 0, 1) - glm::vec3(m * glm::vec4(0, 0, 1, 0))), 1e-5f);
    }
    // By hand: the body at (5, 1, -2); the neck 0.5 up and 0.1 along the body's +Z, which
    // the body's quarter turn and the placement's -45 degrees (45 degrees in all about +Y)
    // take to 0.1 (sin 45, 0, cos 45).
    const float c = std::sqrt(0.5f);
    EXPECT_LT(glm::length(out[1].position - glm::vec3(5.0f + 0.1f * c, 1.5f, -2.0f + 0.1f * c)), 1e-5f);
}

TEST(CharacterKinematics, OscillationFollowsItsFormula) {
    rods::Oscillation o;
    o.amplitude = 0.4f;
    o.frequency = 0.5f;
    o.start = 1.0f;
    o.end = 9.0f;
    EXPECT_EQ(rods::oscillation_angle(o, 0.99f), 0.0f);  // not started
    EXPECT_EQ(rods::oscillation_angle(o, 9.0f), 0.0f);   // over
    for (const float t : {1.0f, 1.3f, 2.7f, 4.1f, 8.9f}) {
        const float expected = 0.4f * std::sin(2.0f * kPi * 0.5f * (t - 1.0f));
        EXPECT_NEAR(rods::oscillation_angle(o, t), expected, 1e-6f) << t;
    }
    EXPECT_NEAR(rods::oscillation_angle(o, 1.5f), 0.4f, 1e-6f);  // a quarter period: the full amplitude
    o.phase = 0.5f * kPi;
    EXPECT_NEAR(rods::oscillation_angle(o, 1.0f), 0.4f, 1e-6f);
    // Fade: a smoothstep over 1 s at both ends (1/2 at the middle of the ramp).
    o.phase = 0.0f;
    o.fade = 1.0f;
    EXPECT_NEAR(rods::oscillation_angle(o, 1.5f), 0.5f * 0.4f, 1e-6f);
    EXPECT_NEAR(rods::oscillation_angle(o, 8.5f), 0.5f * 0.4f * std::sin(2.0f * kPi * 0.5f * 7.5f), 1e-6f);
    // Sharpness: a glance that holds. Where the sine is 1/2 the angle is already
    // tanh(1.5) / tanh(3) = 0.909 of the amplitude.
    o.fade = 0.0f;
    o.sharpness = 3.0f;
    const float t = 1.0f + 1.0f / 6.0f;  // sin(pi/6) = 1/2
    EXPECT_NEAR(rods::oscillation_angle(o, t), 0.4f * std::tanh(1.5f) / std::tanh(3.0f), 1e-5f);
}

// A head turn yaws the head (the reference joint) and nothing below it.
TEST(CharacterKinematics, HeadTurnYawsTheReferenceJoint) {
    json doc = valid_character_scene();
    doc["characters"][0]["motions"] = json::parse(R"([{"type": "head_turn", "amplitude_deg": 40, "frequency": 0.25}])");
    doc["fps"] = 4;
    const auto loaded = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const RodScene rs = build(loaded.value());
    for (std::uint32_t f = 0; f < 16; ++f) {
        const std::vector<rods::Transform> poses = rs.joint_poses(0, f);
        const glm::vec3 head_forward = poses[1].rotation * glm::vec3(0, 0, 1);
        const glm::vec3 body_forward = poses[0].rotation * glm::vec3(0, 0, 1);
        const float yaw = std::atan2(head_forward.x, head_forward.z);
        const float expected = 40.0f * kPi / 180.0f * std::sin(2.0f * kPi * 0.25f * rs.time(f));
        EXPECT_NEAR(yaw, expected, 1e-5f) << "frame " << f;
        EXPECT_NEAR(head_forward.y, 0.0f, 1e-6f);
        EXPECT_LT(glm::length(body_forward - glm::vec3(0, 0, 1)), 1e-6f);
        // The frame's reference pose is the head's.
        const rods::RodFrame frame = rs.frame(f);
        EXPECT_EQ(frame.reference[0].position, poses[1].position);
    }
    // At 1 s (a quarter period) the head looks 40 degrees to its left.
    const glm::vec3 at_one = rs.joint_poses(0, 4)[1].rotation * glm::vec3(0, 0, 1);
    EXPECT_NEAR(std::atan2(at_one.x, at_one.z) * 180.0f / kPi, 40.0f, 1e-3f);
}

TEST(CharacterKinematics, WalkMovesForwardAndBobs) {
    rods::Locomotion walk;
    walk.speed = 1.2f;
    walk.start = 0.5f;
    walk.end = 3.5f;
    walk.ramp_in = 0.4f;
    walk.ramp_out = 0.4f;
    walk.bob = 0.05f;
    walk.step_frequency = 2.0f;
    const std::array<rods::Locomotion, 1> motions{walk};
    const auto at = [&](float t) { return rods::evaluate_locomotion(motions, t); };
    EXPECT_EQ(at(0.4f).frame.position, glm::vec3(0.0f));
    // In the steady part: z = v (t - start - ramp_in / 2), straight ahead.
    for (const float t : {1.0f, 2.0f, 3.0f}) {
        EXPECT_NEAR(at(t).frame.position.z, 1.2f * (t - 0.5f - 0.2f), 1e-5f) << t;
        EXPECT_EQ(at(t).frame.position.x, 0.0f);
        EXPECT_NEAR(rods::locomotion_envelope(walk, t), 1.0f, 1e-6f);
    }
    // Ramps: half speed half-way through each.
    EXPECT_NEAR(rods::locomotion_envelope(walk, 0.7f), 0.5f, 1e-5f);
    EXPECT_NEAR(rods::locomotion_envelope(walk, 3.3f), 0.5f, 1e-5f);
    // After the end it stands where the walk took it: v (duration - (ramp_in + ramp_out) / 2).
    EXPECT_NEAR(at(3.5f).frame.position.z, 1.2f * (3.0f - 0.4f), 1e-5f);
    EXPECT_EQ(at(4.0f).frame.position, at(10.0f).frame.position);
    // The bob: 0 at each footfall, the full height between, once per step.
    EXPECT_NEAR(at(1.5f).bob, 0.0f, 1e-6f);
    EXPECT_NEAR(at(1.75f).bob, 0.05f, 1e-6f);
    EXPECT_NEAR(at(2.25f).bob, 0.05f, 1e-6f);
    EXPECT_EQ(at(4.0f).bob, 0.0f);
}

// The classic hair-overshoot test: run, turning, then halt dead. Before the stop the
// character moves at `speed` on a circle of radius speed / turn_rate; from the stop on,
// every joint, chain root and collider keeps exactly the same bits.
TEST(CharacterKinematics, SuddenStopReallyStops) {
    json doc = valid_character_scene();
    doc["characters"][0]["motions"] = json::parse(
        R"([{"type": "stop", "speed": 2.5, "turn_rate_deg": 60, "start": 0.5, "stop_time": 2.0, "ramp_in": 0.3}])");
    doc["fps"] = 60;
    doc["duration"] = 3;
    const auto loaded = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const RodScene rs = build(loaded.value());
    const float omega = 60.0f * kPi / 180.0f;
    const float radius = 2.5f / omega;
    // The body starts at (0, 0.9, 0) facing +Z; a left turn (+Y) curves towards +X, so
    // the circle's centre is at (radius, 0.9, 0).
    const glm::vec3 centre(radius, 0.9f, 0.0f);
    float speed_error = 0.0f;
    float circle_error = 0.0f;
    for (std::uint32_t f = 1; f <= 120; ++f) {
        const glm::vec3 p = rs.joint_poses(0, f)[0].position;
        circle_error = std::max(circle_error, std::abs(glm::length(p - centre) - radius));
        const float t = rs.time(f);
        if (t > 0.85f && t <= 2.0f) {  // after the ramp, up to the stop
            const float speed = glm::length(p - rs.joint_poses(0, f - 1)[0].position) * rs.fps;
            speed_error = std::max(speed_error, std::abs(speed - 2.5f));
        }
    }
    // Tolerances: the speed is a chord over 1/60 s of a 2.4 m circle (0.01% shorter than
    // the arc) in float; the circle is exact up to float rounding of ~1e-6 m.
    EXPECT_LT(speed_error, 2e-3f);
    EXPECT_LT(circle_error, 1e-5f);
    const rods::RodFrame at_stop = rs.frame(120);  // t = 2.0 s, the stop
    for (std::uint32_t f = 121; f < rs.frames; ++f) {
        EXPECT_TRUE(same_frame_kinematics(at_stop, rs.frame(f))) << "frame " << f << " moved after the stop";
    }
    // It really was moving the frame before.
    const rods::RodFrame before = rs.frame(119);
    EXPECT_GT(glm::length(at_stop.roots[0].position - before.roots[0].position), 0.03f);
    // Heading at the stop: turn_rate times the distance integral, (1.5 - 0.3 / 2) s.
    const glm::vec3 forward = rs.joint_poses(0, 120)[0].rotation * glm::vec3(0, 0, 1);
    EXPECT_NEAR(std::atan2(forward.x, forward.z), omega * 1.35f, 1e-4f);
    std::printf("[ measured ] sudden stop: speed error %.2g m/s before, circle error %.2g m, motion after the stop: none\n",
                static_cast<double>(speed_error), static_cast<double>(circle_error));
}
