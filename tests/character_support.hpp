#pragma once
// Helpers shared by the character test suites (tests/scene/test_character_*.cpp,
// tests/rods/test_character_*.cpp, tests/backends/test_character_backends.cpp): loading
// scenes, a CPU reference run of a RodScene, a picture projector, a small valid
// character scene to break, and bitwise frame comparisons.

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

#include <kodawari/vulkan/backend_factory.hpp>
#include <kodawari/vulkan/gpu_info.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>

#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari::testing_support::characters {

using kodawari::Error;
using kodawari::Result;
using kodawari::RodScene;
using kodawari::Scene;
using nlohmann::json;
namespace rods = kodawari::rods;

inline constexpr float kPi = std::numbers::pi_v<float>;

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

inline std::string source_path(const std::string& relative) { return std::string(KODAWARI_SOURCE_DIR) + "/" + relative; }

inline Scene load_file(const std::string& path) {
    auto scene = kodawari::load_scene(path);
    EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
    return scene.ok() ? scene.value() : Scene{};
}

inline Scene load(const std::string& relative) { return load_file(source_path(relative)); }

inline RodScene build(const Scene& scene) {
    auto built = kodawari::build_rod_scene(scene);
    EXPECT_TRUE(built.ok()) << (built.ok() ? "" : built.error().message);
    return built.ok() ? std::move(built).value() : RodScene{};
}

// The CPU reference run of a RodScene, frame by frame, exactly as a backend would: the
// frame's kinematic input, each chain's view-blended rest shape, one solver step.
class Simulation {
public:
    /// Simulates the first `limit` chains (all by default).
    explicit Simulation(const RodScene& scene, std::uint32_t limit = ~0u)
        : scene_(scene), count_(std::min<std::uint32_t>(limit, static_cast<std::uint32_t>(scene.world.chains.size()))) {
        scene_.frame(0, frame_);
        for (std::uint32_t c = 0; c < count_; ++c) {
            states_.push_back(rods::initial_chain_state(scene_.world, c, frame_));
            keys_.push_back(rods::initial_key_state(scene_.world, c, frame_));
        }
    }

    /// Advances every chain to frame `index` (call with 1, 2, 3, ...): the frame's
    /// kinematic input, then each chain's view-blended rest shape (SPEC A.3, A.2) and one
    /// solver step (A.4), as every rod backend does.
    void step(std::uint32_t index) {
        scene_.frame(index, frame_);
        for (std::uint32_t c = 0; c < count_; ++c) kodawari::step_chain_reference(scene_.world, c, frame_, states_[c], keys_[c]);
    }

    /// World position of joint `i` of chain `c`.
    [[nodiscard]] glm::vec3 x(std::uint32_t c, std::uint32_t i) const { return rods::position(states_[c], i); }
    [[nodiscard]] const rods::ChainState& state(std::uint32_t chain) const { return states_[chain]; }
    [[nodiscard]] const rods::RodFrame& frame() const { return frame_; }

private:
    const RodScene& scene_;
    std::uint32_t count_;
    rods::RodFrame frame_;
    std::vector<rods::ChainState> states_;
    std::vector<rods::KeyState> keys_;
};

// A look-at + perspective camera on a 1920 x 1080 picture, +Y up: what a viewer shows.
struct Projector {
    glm::mat4 view;
    glm::mat4 projection;
    float focal_px;  // pixels per metre at 1 m depth
    static constexpr float kWidth = 1920.0f;
    static constexpr float kHeight = 1080.0f;

    Projector(const rods::CameraPose& pose, float fov_deg)
        : view(glm::lookAt(pose.position, pose.target, glm::vec3(0.0f, 1.0f, 0.0f))),
          projection(glm::perspective(glm::radians(fov_deg), kWidth / kHeight, 0.01f, 1000.0f)),
          focal_px(0.5f * kHeight / std::tan(0.5f * glm::radians(fov_deg))) {}

    // Pixel coordinates, x to the right, y down.
    [[nodiscard]] glm::vec2 pixel(glm::vec3 p) const {
        const glm::vec4 clip = projection * view * glm::vec4(p, 1.0f);
        const glm::vec2 ndc(clip.x / clip.w, clip.y / clip.w);
        return glm::vec2(0.5f * (ndc.x + 1.0f) * kWidth, 0.5f * (1.0f - ndc.y) * kHeight);
    }
    // Pixels per metre at the depth of `p`.
    [[nodiscard]] float scale(glm::vec3 p) const { return focal_px / -(view * glm::vec4(p, 1.0f)).z; }
};

// The shared character's eyes (scripts/make_rod_scenes.py: the head sphere of radius
// 0.11 m, centre 0.1 m above the head joint; eyes 20 degrees either side of the face, 5
// above): the smallest on-screen distance from either eye to any chain segment of `sim`
// this frame, in head radii as `cam` shows the head.
inline float eye_to_strands(const RodScene& rs, const Simulation& sim, const Projector& cam) {
    const glm::vec3 centre(0.0f, 0.1f, 0.0f);
    const float radius = 0.11f;
    const rods::Transform& head = sim.frame().reference[0];
    const float head_px = radius * cam.scale(head.position + head.rotation * centre);
    float closest = 1e9f;
    for (const float side : {-1.0f, 1.0f}) {
        const float az = side * 20.0f * kPi / 180.0f;
        const float el = 5.0f * kPi / 180.0f;
        const glm::vec3 eye_local = centre + radius * glm::vec3(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
        const glm::vec2 eye = cam.pixel(head.position + head.rotation * eye_local);
        for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
            const std::uint32_t n = rs.world.templ(rs.world.chains[c]).chain.joint_count;
            for (std::uint32_t i = 0; i + 1 < n; ++i) {
                const glm::vec2 a = cam.pixel(sim.x(c, i)), ab = cam.pixel(sim.x(c, i + 1)) - a;
                const float len2 = glm::dot(ab, ab);
                const float t = len2 > 0.0f ? std::clamp(glm::dot(eye - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
                closest = std::min(closest, glm::length(eye - (a + t * ab)) / head_px);
            }
        }
    }
    return closest;
}

// A small valid character scene that the error tests break one key at a time.
inline json valid_character_scene() {
    return json::parse(R"({
      "format": "kodawari-scene",
      "version": 2,
      "characters": [
        {
          "name": "bunny",
          "skeleton": [
            {"name": "body", "position": [0, 0.9, 0]},
            {"name": "head", "parent": "body", "position": [0, 0.6, 0]}
          ],
          "motions": [{"type": "sway"}, {"type": "head_turn"}, {"type": "walk", "end": 2}, {"type": "stop", "start": 3, "stop_time": 4}],
          "colliders": [{"type": "sphere", "joint": "head", "radius": 0.1}],
          "chains": [
            {
              "name": "ear", "joint": "head", "mirror": "ear_r", "offset": {"position": [0, 0.1, 0]},
              "shape": {"arc": {"joints": 8, "length": 0.2}},
              "views": [{"direction": [0, 0, 1], "shape": {"arc": {"joints": 8, "length": 0.2, "curl_deg": 30}}}]
            }
          ]
        }
      ]
    })");
}

inline std::string error_of(const Result<Scene>& result) {
    if (result.ok()) return "(no error)";
    EXPECT_EQ(result.error().kind, Error::Kind::InvalidInput);
    return result.error().message;
}

inline std::string parse_error(const json& scene) { return error_of(kodawari::parse_scene(scene.dump(), "test.json")); }

inline json& chain0(json& doc) { return doc["characters"][0]["chains"][0]; }

template <typename T>
inline bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

inline bool same_frame(const rods::RodFrame& a, const rods::RodFrame& b) {
    return std::memcmp(&a.time, &b.time, sizeof(float)) == 0 && std::memcmp(&a.dt, &b.dt, sizeof(float)) == 0 &&
           std::memcmp(&a.camera, &b.camera, sizeof(rods::Camera)) == 0 && same_bytes(a.reference, b.reference) &&
           same_bytes(a.roots, b.roots) && same_bytes(a.colliders, b.colliders);
}

// The kinematic part of two frames (not their time): the same bits.
inline bool same_frame_kinematics(const rods::RodFrame& a, const rods::RodFrame& b) {
    return std::memcmp(&a.camera, &b.camera, sizeof(rods::Camera)) == 0 && same_bytes(a.reference, b.reference) &&
           same_bytes(a.roots, b.roots) && same_bytes(a.colliders, b.colliders);
}

// Runs `rs`'s chains on `kind` for `frames` frames, frame f from `frame_at(f, frame)` (frame 0
// loads the world), failing the test on any error or Vulkan validation message; returns
// the snapshot after the last (empty after a failure).
template <typename FrameAt>
ChainSnapshot run_rod_frames(const BackendCase& kind, const RodScene& rs, std::uint32_t frames, FrameAt&& frame_at) {
    auto made = make_rod_backend(kind, backend_options(kind));
    EXPECT_TRUE(made.ok()) << made.error().message;
    if (!made.ok()) return {};
    RodBackend& backend = *made.value();
    rods::RodFrame frame;
    frame_at(0u, frame);
    EXPECT_TRUE(backend.load(rs.world, frame).ok());
    for (std::uint32_t f = 1; f < frames; ++f) {
        frame_at(f, frame);
        const auto stepped = backend.step(frame);
        EXPECT_TRUE(stepped.ok()) << (stepped.ok() ? "" : stepped.error().message);
        if (!stepped.ok()) return {};
    }
    EXPECT_EQ(backend.validation_messages(), 0u) << "Vulkan validation reported problems (see stderr)";
    ChainSnapshot snap;
    EXPECT_TRUE(backend.read(snap).ok());
    return snap;
}

// The largest distance between a joint of `ours` and of `reference` (per joint, rs's
// layout), in units of its chain's length: the parity tests' measure.
inline float worst_in_chain_lengths(const RodScene& rs, const std::vector<glm::vec3>& ours,
                                    const std::vector<glm::vec3>& reference) {
    float worst = 0.0f;
    for (const rods::ChainInstance& c : rs.world.chains) {
        const rods::Chain& chain = rs.world.templ(c).chain;
        float length = 0.0f;
        for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) length += chain.segment_length[i];
        for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
            worst = std::max(worst, glm::length(ours[c.joint_begin + i] - reference[c.joint_begin + i]) / length);
        }
    }
    return worst;
}

}  // namespace kodawari::testing_support::characters
