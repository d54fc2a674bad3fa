// Crowds of characters: their layout, yaw and time offsets.

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

TEST(CharacterCrowd, LayoutAndTimeOffsets) {
    const Scene scene = load("scenes/crowd.json");
    const RodScene rs = build(scene);
    const kodawari::CrowdSpec& crowd = scene.crowds[0];
    ASSERT_EQ(rs.instances.size(), 1024u);
    float min_offset = 1e9f, max_offset = -1e9f, sum = 0.0f, max_yaw = 0.0f;
    for (std::size_t i = 0; i < rs.instances.size(); ++i) {
        const kodawari::CharacterInstance& inst = rs.instances[i];
        min_offset = std::min(min_offset, inst.time_offset);
        max_offset = std::max(max_offset, inst.time_offset);
        sum += inst.time_offset;
        const glm::vec3 forward = inst.placement.rotation * glm::vec3(0, 0, 1);
        max_yaw = std::max(max_yaw, std::abs(std::atan2(forward.x, forward.z)));
        // Grid: 32 columns 1.6 m apart, centred, each moved by at most the jitter.
        const float x = (static_cast<float>(i % 32) - 15.5f) * 1.6f;
        const float z = (static_cast<float>(i / 32) - 15.5f) * 1.6f;
        EXPECT_LE(std::abs(inst.placement.position.x - x), crowd.position_jitter + 1e-5f) << i;
        EXPECT_LE(std::abs(inst.placement.position.z - z), crowd.position_jitter + 1e-5f) << i;
    }
    EXPECT_GE(min_offset, 0.0f);
    EXPECT_LT(max_offset, 1.5f);
    EXPECT_GT(max_offset - min_offset, 1.4f);  // spread over the whole range...
    EXPECT_NEAR(sum / 1024.0f, 0.75f, 0.1f);  // ...evenly (1024 uniform draws: sd of the mean 0.014)
    EXPECT_LE(max_yaw, crowd.yaw_jitter + 1e-5f);
    EXPECT_GT(max_yaw, 0.9f * crowd.yaw_jitter);
    // Another seed, other offsets.
    Scene reseeded = scene;
    reseeded.crowds[0].seed = 8;
    const RodScene other = build(reseeded);
    EXPECT_NE(other.instances[0].time_offset, rs.instances[0].time_offset);
    // A ring faces outwards, `spacing` apart by default.
    json doc = valid_character_scene();
    doc["crowds"] = json::parse(R"([{"character": "bunny", "count": 40, "layout": "ring", "spacing": 1.0, "center": [10, 0, 0]},
                                    {"character": "bunny", "instances": [{"position": [1, 2, 3], "yaw_deg": 90, "time_offset": 0.5}]}])");
    const auto loaded = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const RodScene ring = build(loaded.value());
    ASSERT_EQ(ring.instances.size(), 41u);
    const float radius = 40.0f / (2.0f * kPi);
    for (std::size_t i = 0; i < 40; ++i) {
        const glm::vec3 out = ring.instances[i].placement.position - glm::vec3(10, 0, 0);
        EXPECT_NEAR(glm::length(out), radius, 1e-4f);
        EXPECT_LT(glm::length(ring.instances[i].placement.rotation * glm::vec3(0, 0, 1) - out / glm::length(out)), 1e-5f);
    }
    EXPECT_EQ(ring.instances[40].placement.position, glm::vec3(1, 2, 3));
    EXPECT_EQ(ring.instances[40].time_offset, 0.5f);
    EXPECT_EQ(ring.character_names[40], "bunny#40");
}
