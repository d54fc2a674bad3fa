// The moving camera of a rod scene: orbit, path and keyframes.

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

TEST(CharacterCamera, OrbitRadiusHeightAndPeriod) {
    const RodScene rs = build(load("scenes/bunny.json"));
    ASSERT_EQ(rs.camera.kind, rods::CameraMotion::Kind::Orbit);
    const glm::vec3 target(0.0f, 1.65f, 0.0f);
    const float period = 12.0f;
    for (std::uint32_t f = 0; f < rs.frames; f += 7) {
        const rods::CameraPose pose = rs.camera_pose(f);
        const glm::vec3 offset = pose.position - target;
        EXPECT_NEAR(std::hypot(offset.x, offset.z), 1.6f, 1e-5f);
        EXPECT_NEAR(offset.y, 0.15f, 1e-5f);
        EXPECT_LT(glm::length(pose.forward - glm::normalize(target - pose.position)), 1e-6f);
        // Anticlockwise from the front: azimuth = 360 t / period.
        float azimuth = std::atan2(offset.x, offset.z) * 180.0f / kPi;
        if (azimuth < 0.0f) azimuth += 360.0f;
        const float expected = std::fmod(360.0f * rs.time(f) / period, 360.0f);
        EXPECT_NEAR(std::remainder(azimuth - expected, 360.0f), 0.0f, 1e-3f) << "frame " << f;
    }
    // One period later it is back where it started.
    EXPECT_LT(glm::length(rods::camera_pose(rs.camera, 12.0f).position - rods::camera_pose(rs.camera, 0.0f).position), 1e-5f);
    EXPECT_LT(glm::length(rods::camera_pose(rs.camera, 3.0f).position - (target + glm::vec3(1.6f, 0.15f, 0.0f))), 1e-5f);
}

TEST(CharacterCamera, PathAndKeyframes) {
    rods::CameraMotion m;
    m.kind = rods::CameraMotion::Kind::Keyframes;
    m.interpolation = rods::Interpolation::Linear;
    m.keys = {{0.0f, glm::vec3(0, 1, 4), glm::vec3(0, 1, 0)}, {1.0f, glm::vec3(4, 1, 0), glm::vec3(0, 1, 0)},
              {3.0f, glm::vec3(0, 3, -4), glm::vec3(0, 2, 0)}};
    EXPECT_EQ(rods::camera_pose(m, 0.5f).position, glm::vec3(2, 1, 2));
    EXPECT_EQ(rods::camera_pose(m, 2.0f).position, glm::vec3(2, 2, -2));
    EXPECT_EQ(rods::camera_pose(m, 2.0f).target, glm::vec3(0, 1.5f, 0));
    EXPECT_EQ(rods::camera_pose(m, -1.0f).position, glm::vec3(0, 1, 4));  // holds before the first key
    EXPECT_EQ(rods::camera_pose(m, 9.0f).position, glm::vec3(0, 3, -4));  // and after the last
    // Catmull-Rom: through every key, and C1 across key 1 (one-sided differences over
    // 1e-3 s agree to the curvature term, ~1e-3 of the speed).
    m.interpolation = rods::Interpolation::CatmullRom;
    for (const rods::CameraKey& k : m.keys) EXPECT_LT(glm::length(rods::camera_pose(m, k.time).position - k.position), 1e-5f);
    const float h = 1e-3f;
    const glm::vec3 left = (rods::camera_pose(m, 1.0f).position - rods::camera_pose(m, 1.0f - h).position) / h;
    const glm::vec3 right = (rods::camera_pose(m, 1.0f + h).position - rods::camera_pose(m, 1.0f).position) / h;
    EXPECT_LT(glm::length(left - right), 0.05f * glm::length(left));
    // A looping path from the scene format: a key per point, segment_duration apart, and
    // round again after the last point.
    json doc = valid_character_scene();
    doc["camera"] = json::parse(R"({"projection": "orthographic", "path": {"points": [[0, 1, 3], [3, 1, 0], [0, 1, -3], [-3, 1, 0]],
        "target": [0, 1, 0], "segment_duration": 2, "loop": true}})");
    const auto loaded = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const rods::CameraMotion& path = loaded.value().camera.motion;
    ASSERT_EQ(path.keys.size(), 5u);
    EXPECT_EQ(path.keys[4].time, 8.0f);
    EXPECT_LT(glm::length(rods::camera_pose(path, 4.0f).position - glm::vec3(0, 1, -3)), 1e-5f);
    EXPECT_LT(glm::length(rods::camera_pose(path, 9.3f).position - rods::camera_pose(path, 1.3f).position), 1e-5f);
    const rods::CameraPose pose = rods::camera_pose(path, 2.0f);
    EXPECT_EQ(pose.projection, rods::Camera::Projection::Orthographic);
    EXPECT_LT(glm::length(pose.forward - glm::vec3(-1, 0, 0)), 1e-6f);
}
