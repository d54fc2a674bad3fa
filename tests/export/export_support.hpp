#pragma once
// What the export suites share: a hand-made bird world and poses whose rotations are
// known, and readers of the glTF files they write (tinygltf).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <glm/gtc/matrix_transform.hpp>
#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/core/version.hpp"
#include "test_support.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_paths.hpp"


namespace kodawari::export_test {

namespace fs = std::filesystem;

constexpr std::size_t kBirds = 67;  // every wing type, and not a multiple of the workgroup size
constexpr std::uint32_t kFrames = 12;
constexpr float kFps = 24.0f;

using testing_support::gltf_validator_command;
using testing_support::run_command;
using testing_support::shell_quote;
using testing_support::TempDir;

inline birds::BirdWorld make_world() {
    birds::BirdWorld world;
    world.fps = kFps;
    world.frames = kFrames;
    world.birds.resize(kBirds);
    for (std::size_t b = 0; b < kBirds; ++b) {
        gpu::BirdParams& params = world.birds[b];
        params.offset = {static_cast<float>(b), 0.0f, 0.0f, 0.0f};
        params.motion = {12.0f, 4.0f, 1.0f, 0.0f};
        params.ids = {0, static_cast<std::uint32_t>(b % birds::kWingTypeCount), 0, 0};
    }
    return world;
}

/// Unit quaternion (x, y, z, w) of `angle` about a unit axis.
inline gpu::vec4 axis_angle(float x, float y, float z, float angle) {
    const float n = std::sqrt(x * x + y * y + z * z);
    const float s = std::sin(0.5f * angle) / n;
    return {x * s, y * s, z * s, std::cos(0.5f * angle)};
}

/// A distinct, smoothly turning rotation per bird, part and frame.
inline gpu::vec4 input_rotation(std::size_t b, std::size_t part, std::uint32_t f) {
    const float angle = 0.15f * static_cast<float>(f) + 0.4f * static_cast<float>(part) + 0.01f * static_cast<float>(b);
    return axis_angle(1.0f + static_cast<float>(part), 0.5f * static_cast<float>(b % 5), 1.0f, angle);
}

/// Frames x birds, frame-major. Bird 4's tail has its sign flipped on odd frames (the
/// same rotations as q, in the opposite hemisphere), as a backend may legally produce.
inline std::vector<gpu::BirdPose> make_poses(const birds::BirdWorld& world, std::uint32_t frames) {
    const std::size_t count = world.birds.size();
    std::vector<gpu::BirdPose> poses(frames * count);
    for (std::uint32_t f = 0; f < frames; ++f) {
        for (std::size_t b = 0; b < count; ++b) {
            gpu::BirdPose& pose = poses[f * count + b];
            const float t = static_cast<float>(f) / world.fps;
            pose.position = {2.0f * static_cast<float>(b), 10.0f + std::sin(t), 12.0f * t, 0.0f};
            for (std::size_t part = 0; part < birds::kPartCount; ++part) {
                pose.rotation[part] = input_rotation(b, part, f);
            }
            if (b == 4 && f % 2 == 1) {
                gpu::vec4& q = pose.rotation[KW_PART_TAIL];
                q = {-q.x, -q.y, -q.z, -q.w};
            }
        }
    }
    return poses;
}

/// The float components of an accessor (tightly packed float data, as we write it).
inline std::vector<float> read_floats(const tinygltf::Model& model, int index) {
    const tinygltf::Accessor& accessor = model.accessors.at(static_cast<std::size_t>(index));
    EXPECT_EQ(accessor.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
    const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(accessor.bufferView));
    const tinygltf::Buffer& buffer = model.buffers.at(static_cast<std::size_t>(view.buffer));
    const auto components = static_cast<std::size_t>(tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(accessor.type)));
    std::vector<float> values(accessor.count * components);
    const std::size_t offset = view.byteOffset + accessor.byteOffset;
    EXPECT_LE(offset + values.size() * sizeof(float), buffer.data.size());
    std::memcpy(values.data(), buffer.data.data() + offset, values.size() * sizeof(float));
    return values;
}

[[nodiscard]] inline bool load_glb(const std::string& path, tinygltf::Model& model) {
    tinygltf::TinyGLTF loader;
    std::string error;
    std::string warning;
    const bool ok = loader.LoadBinaryFromFile(&model, &error, &warning, path);
    EXPECT_TRUE(ok) << error;
    EXPECT_TRUE(error.empty()) << error;
    return ok;
}

/// The channel of `node` animating `path`, or null.
inline const tinygltf::AnimationChannel* find_channel(const tinygltf::Animation& animation, int node,
                                               const std::string& path) {
    for (const auto& channel : animation.channels) {
        if (channel.target_node == node && channel.target_path == path) return &channel;
    }
    return nullptr;
}


/// A rod scene simulated on the CPU reference: every frame's snapshot, frame-major.
struct RodRun {
    RodScene scene;
    std::uint32_t frames = 0;
    std::vector<glm::vec3> positions;
    std::vector<glm::quat> orientations;
};

/// A rod scene file, `frames` frames on the CPU reference.
inline RodRun run_rod_scene(const std::string& path, std::uint32_t frames) {
    RodRun run;
    auto scene = load_scene(path);
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    auto built = build_rod_scene(scene.value());
    EXPECT_TRUE(built.ok());
    run.scene = std::move(built).value();
    run.frames = frames;
    auto backend = std::move(make_rod_backend(BackendKind::CpuReference, {})).value();
    rods::RodFrame frame;
    ChainSnapshot snap;
    for (std::uint32_t f = 0; f < frames; ++f) {
        run.scene.frame(f, frame);
        EXPECT_TRUE((f == 0 ? backend->load(run.scene.world, frame) : backend->step(frame)).ok());
        EXPECT_TRUE(backend->read(snap).ok());
        run.positions.insert(run.positions.end(), snap.positions.begin(), snap.positions.end());
        run.orientations.insert(run.orientations.end(), snap.orientations.begin(), snap.orientations.end());
    }
    return run;
}

/// The bunny scene, `frames` frames on the CPU reference.
inline RodRun run_bunny(std::uint32_t frames) { return run_rod_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/bunny.json", frames); }

/// A copy in `dir` of the shipped scene `name` (scenes/<name>.json) whose crowds have
/// `count` characters each, its character files named by absolute path.
inline std::string scene_with_count(const TempDir& dir, const std::string& name, int count) {
    const std::string source_dir = std::string(KODAWARI_SOURCE_DIR) + "/scenes/";
    std::ifstream in(source_dir + name + ".json");
    nlohmann::json scene = nlohmann::json::parse(in);
    for (auto& crowd : scene["crowds"]) crowd["count"] = count;
    for (auto& character : scene["characters"]) {
        if (character.contains("gltf")) character["gltf"] = source_dir + character["gltf"].get<std::string>();
    }
    const std::string path = dir.file(name + ".json");
    std::ofstream(path) << scene.dump(1);
    return path;
}

}  // namespace kodawari::export_test
