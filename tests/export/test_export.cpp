// Tests of the outputs (SPEC C): the .glb export (read back with tinygltf, checked by
// the Khronos glTF-Validator) and the JSON Lines trace. The bird worlds and poses are
// made by hand; the chain exports come from the CPU reference on scenes/bunny.json.

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

#include "kodawari/backend_factory.hpp"
#include "kodawari/version.hpp"
#include "test_support.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/export.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/rod_scene.hpp"

namespace kodawari {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kBirds = 67;  // three wing types, and not a multiple of the workgroup size
constexpr std::uint32_t kFrames = 12;
constexpr float kFps = 24.0f;

using testing_support::gltf_validator_command;
using testing_support::run_command;
using testing_support::shell_quote;
using testing_support::TempDir;

birds::BirdWorld make_world() {
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
gpu::vec4 axis_angle(float x, float y, float z, float angle) {
    const float n = std::sqrt(x * x + y * y + z * z);
    const float s = std::sin(0.5f * angle) / n;
    return {x * s, y * s, z * s, std::cos(0.5f * angle)};
}

/// A distinct, smoothly turning rotation per bird, part and frame.
gpu::vec4 input_rotation(std::size_t b, std::size_t part, std::uint32_t f) {
    const float angle = 0.15f * static_cast<float>(f) + 0.4f * static_cast<float>(part) + 0.01f * static_cast<float>(b);
    return axis_angle(1.0f + static_cast<float>(part), 0.5f * static_cast<float>(b % 5), 1.0f, angle);
}

/// Frames x birds, frame-major. Bird 4's tail has its sign flipped on odd frames (the
/// same rotations as q, in the opposite hemisphere), as a backend may legally produce.
std::vector<gpu::BirdPose> make_poses(const birds::BirdWorld& world, std::uint32_t frames) {
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
std::vector<float> read_floats(const tinygltf::Model& model, int index) {
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

[[nodiscard]] bool load_glb(const std::string& path, tinygltf::Model& model) {
    tinygltf::TinyGLTF loader;
    std::string error;
    std::string warning;
    const bool ok = loader.LoadBinaryFromFile(&model, &error, &warning, path);
    EXPECT_TRUE(ok) << error;
    EXPECT_TRUE(error.empty()) << error;
    return ok;
}

/// The channel of `node` animating `path`, or null.
const tinygltf::AnimationChannel* find_channel(const tinygltf::Animation& animation, int node,
                                               const std::string& path) {
    for (const auto& channel : animation.channels) {
        if (channel.target_node == node && channel.target_path == path) return &channel;
    }
    return nullptr;
}

TEST(Export, GlbRoundTrip) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, kFrames);
    const std::string path = dir.file("flock.glb");
    const auto written = write_birds_glb(path, world, poses, kFrames);
    ASSERT_TRUE(written.ok()) << written.error().message;

    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    EXPECT_EQ(model.asset.version, "2.0");
    EXPECT_EQ(model.asset.generator, "kodawari " + std::string(version()));
    EXPECT_EQ(model.buffers.size(), 1u);
    ASSERT_EQ(model.nodes.size(), 1 + birds::kPartCount * kBirds);
    EXPECT_EQ(model.nodes[0].name, "Birds");
    ASSERT_EQ(model.nodes[0].children.size(), kBirds);
    EXPECT_EQ(model.materials.size(), birds::kWingTypeCount);
    EXPECT_EQ(model.meshes.size(), birds::kWingTypeCount * birds::kPartCount);
    ASSERT_EQ(model.animations.size(), 1u);
    const tinygltf::Animation& animation = model.animations[0];
    EXPECT_EQ(animation.name, "flight");
    ASSERT_EQ(animation.channels.size(), (birds::kPartCount + 1) * kBirds);

    // Bird 17 is a hawk (17 % 3 == 2): its Body node, its parts, their rest offsets.
    constexpr std::size_t kBird = 17;
    const int body = model.nodes[0].children[kBird];
    const tinygltf::Node& body_node = model.nodes.at(static_cast<std::size_t>(body));
    EXPECT_EQ(body_node.name, "hawk_17");
    ASSERT_EQ(body_node.children.size(), 4u);  // Head, Tail, LeftArm1, RightArm1
    const auto offsets = birds::part_offsets(birds::WingType::Hawk);
    for (const int child : body_node.children) {
        const tinygltf::Node& part = model.nodes.at(static_cast<std::size_t>(child));
        const auto index = static_cast<std::size_t>(child - body);
        ASSERT_LT(index, birds::kPartCount);
        EXPECT_EQ(part.name, std::string(birds::kPartNames[index]) + "_17");
        ASSERT_EQ(part.translation.size(), 3u);
        for (std::size_t i = 0; i < 3; ++i) {
            EXPECT_FLOAT_EQ(static_cast<float>(part.translation[i]), offsets[index][i]) << part.name;
        }
    }
    const int left_arm1 = body + KW_PART_LEFT_ARM1;
    ASSERT_EQ(model.nodes.at(static_cast<std::size_t>(left_arm1)).children.size(), 1u);
    EXPECT_EQ(model.nodes.at(static_cast<std::size_t>(left_arm1)).children[0], body + KW_PART_LEFT_ARM2);

    // Key times: frame / fps.
    const tinygltf::AnimationChannel* rotation = find_channel(animation, body + KW_PART_LEFT_ARM2, "rotation");
    ASSERT_NE(rotation, nullptr);
    const tinygltf::AnimationSampler& sampler = animation.samplers.at(static_cast<std::size_t>(rotation->sampler));
    EXPECT_EQ(sampler.interpolation, "LINEAR");
    const tinygltf::Accessor& times = model.accessors.at(static_cast<std::size_t>(sampler.input));
    ASSERT_EQ(times.count, kFrames);
    ASSERT_EQ(times.maxValues.size(), 1u);
    ASSERT_EQ(times.minValues.size(), 1u);
    EXPECT_NEAR(times.maxValues[0], (kFrames - 1) / static_cast<double>(kFps), 1e-6);
    EXPECT_EQ(times.minValues[0], 0.0);
    const auto time_values = read_floats(model, sampler.input);
    EXPECT_NEAR(time_values[5], 5.0 / static_cast<double>(kFps), 1e-6);

    // A sampled rotation equals the input.
    constexpr std::uint32_t kFrame = 7;
    const auto keys = read_floats(model, sampler.output);
    ASSERT_EQ(keys.size(), 4u * kFrames);
    const gpu::vec4 expected = input_rotation(kBird, KW_PART_LEFT_ARM2, kFrame);
    EXPECT_NEAR(keys[4 * kFrame + 0], expected.x, 1e-6);
    EXPECT_NEAR(keys[4 * kFrame + 1], expected.y, 1e-6);
    EXPECT_NEAR(keys[4 * kFrame + 2], expected.z, 1e-6);
    EXPECT_NEAR(keys[4 * kFrame + 3], expected.w, 1e-6);

    // The Body translation follows the input positions.
    const tinygltf::AnimationChannel* translation = find_channel(animation, body, "translation");
    ASSERT_NE(translation, nullptr);
    const auto positions =
        read_floats(model, animation.samplers.at(static_cast<std::size_t>(translation->sampler)).output);
    ASSERT_EQ(positions.size(), 3u * kFrames);
    const gpu::BirdPose& pose = poses[kFrame * kBirds + kBird];
    EXPECT_EQ(positions[3 * kFrame + 0], pose.position.x);
    EXPECT_EQ(positions[3 * kFrame + 1], pose.position.y);
    EXPECT_EQ(positions[3 * kFrame + 2], pose.position.z);
}

TEST(Export, RotationKeysStayInOneHemisphere) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, kFrames);
    const std::string path = dir.file("flock.glb");
    ASSERT_TRUE(write_birds_glb(path, world, poses, kFrames).ok());
    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    ASSERT_EQ(model.animations.size(), 1u);

    // Bird 4's tail input alternates between q and -q; the keys must not.
    const int tail = model.nodes[0].children.at(4) + KW_PART_TAIL;
    const auto* channel = find_channel(model.animations[0], tail, "rotation");
    ASSERT_NE(channel, nullptr);
    const auto keys =
        read_floats(model, model.animations[0].samplers.at(static_cast<std::size_t>(channel->sampler)).output);
    ASSERT_EQ(keys.size(), 4u * kFrames);
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        const gpu::vec4 q = input_rotation(4, KW_PART_TAIL, f);
        EXPECT_NEAR(keys[4 * f + 0], q.x, 1e-6) << "frame " << f;
        EXPECT_NEAR(keys[4 * f + 3], q.w, 1e-6) << "frame " << f;
        if (f > 0) {
            float dot = 0.0f;
            for (std::size_t i = 0; i < 4; ++i) dot += keys[4 * f + i] * keys[4 * (f - 1) + i];
            EXPECT_GT(dot, 0.0f) << "frame " << f;
        }
    }
}

TEST(Export, MeshesAreClosedAndFaceOutward) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 2);
    const std::string path = dir.file("flock.glb");
    ASSERT_TRUE(write_birds_glb(path, world, poses, 2).ok());
    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    ASSERT_FALSE(model.meshes.empty());

    using Point = std::array<float, 3>;
    for (const tinygltf::Mesh& mesh : model.meshes) {
        ASSERT_EQ(mesh.primitives.size(), 1u);
        const tinygltf::Primitive& primitive = mesh.primitives[0];
        const auto positions = read_floats(model, primitive.attributes.at("POSITION"));
        const auto normals = read_floats(model, primitive.attributes.at("NORMAL"));
        const tinygltf::Accessor& index_accessor = model.accessors.at(static_cast<std::size_t>(primitive.indices));
        ASSERT_EQ(index_accessor.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(index_accessor.bufferView));
        std::vector<std::uint16_t> indices(index_accessor.count);
        std::memcpy(indices.data(), model.buffers[0].data.data() + view.byteOffset + index_accessor.byteOffset,
                    indices.size() * sizeof(std::uint16_t));
        ASSERT_EQ(indices.size() % 3, 0u);

        auto point = [&](std::uint16_t i) {
            return Point{positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]};
        };
        Point centre{0, 0, 0};
        for (std::size_t i = 0; i < positions.size(); ++i) centre[i % 3] += positions[i];
        for (float& c : centre) c /= static_cast<float>(positions.size() / 3);

        // Closed: every directed edge is matched by the reverse edge of a neighbour.
        std::multiset<std::pair<Point, Point>> edges;
        for (std::size_t t = 0; t < indices.size(); t += 3) {
            const Point a = point(indices[t]), b = point(indices[t + 1]), c = point(indices[t + 2]);
            edges.insert({a, b});
            edges.insert({b, c});
            edges.insert({c, a});
            const Point e1{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            const Point e2{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const Point cross{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                              e1[0] * e2[1] - e1[1] * e2[0]};
            const std::size_t n = 3 * indices[t];
            const float along_normal = cross[0] * normals[n] + cross[1] * normals[n + 1] + cross[2] * normals[n + 2];
            EXPECT_GT(along_normal, 0.0f) << mesh.name << ": winding disagrees with the normal";
            // The parts are convex, so an outward face points away from the centre.
            const float outward = (a[0] + b[0] + c[0] - 3 * centre[0]) * normals[n] +
                                  (a[1] + b[1] + c[1] - 3 * centre[1]) * normals[n + 1] +
                                  (a[2] + b[2] + c[2] - 3 * centre[2]) * normals[n + 2];
            EXPECT_GT(outward, 0.0f) << mesh.name << ": face points inward";
        }
        for (const auto& [from, to] : edges) {
            EXPECT_EQ(edges.count({to, from}), edges.count({from, to})) << mesh.name << ": open edge";
        }
    }

    // The left wings reach along +X, the right ones along -X.
    const int left = model.nodes[0].children[0] + KW_PART_LEFT_ARM1;
    const int right = model.nodes[0].children[0] + KW_PART_RIGHT_ARM1;
    auto extent = [&](int node) {
        const int mesh = model.nodes.at(static_cast<std::size_t>(node)).mesh;
        const auto& accessor = model.accessors.at(static_cast<std::size_t>(
            model.meshes.at(static_cast<std::size_t>(mesh)).primitives[0].attributes.at("POSITION")));
        return std::pair{accessor.minValues.at(0), accessor.maxValues.at(0)};
    };
    EXPECT_GT(extent(left).second, 0.1);
    EXPECT_GE(extent(left).first, 0.0);
    EXPECT_LT(extent(right).first, -0.1);
    EXPECT_LE(extent(right).second, 0.0);
}

TEST(Export, PassesGltfValidator) {
    std::string output;
    // node is a required test tool (scripts/setup installs it): missing is a failure.
    ASSERT_EQ(run_command("command -v node", output), 0) << "node is not on PATH; run scripts/setup";

    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, kFrames);
    const std::string path = dir.file("flock.glb");
    ASSERT_TRUE(write_birds_glb(path, world, poses, kFrames).ok());

    output.clear();
    EXPECT_EQ(run_command(gltf_validator_command(path), output), 0) << output;
    EXPECT_NE(output.find("glTF-Validator: 0 errors, 0 warnings"), std::string::npos) << output;
}

TEST(Export, ValidatorRejectsABrokenFile) {
    // Guards the test above: the script must really report errors.
    TempDir dir;
    const std::string path = dir.file("broken.glb");
    {
        std::ofstream out(path, std::ios::binary);
        out << "glTF not really";
    }
    std::string output;
    const std::string command = "KODAWARI_NODE_TOOLS=" + shell_quote(KODAWARI_NODE_TOOLS) + " node " +
                                shell_quote(std::string(KODAWARI_SOURCE_DIR) + "/tests/tools/validate_gltf.mjs") +
                                " " + shell_quote(path);
    EXPECT_EQ(run_command(command, output), 1) << output;
}

TEST(Export, MissingDirectoryIsAnError) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 2);
    const std::string path = dir.file("no-such-dir/flock.glb");
    const auto written = write_birds_glb(path, world, poses, 2);
    ASSERT_FALSE(written.ok());
    EXPECT_EQ(written.error().kind, Error::Kind::Io);
    EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Export, UnwritableTargetLeavesNoTemporaryFile) {
    // The target is a directory: the temporary file can be written, the rename fails,
    // and the temporary file must go.
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 2);
    const std::string path = dir.file("taken");
    fs::create_directories(fs::path(path) / "inside");
    const auto written = write_birds_glb(path, world, poses, 2);
    ASSERT_FALSE(written.ok());
    EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"taken"});
    EXPECT_TRUE(fs::is_directory(path));
}

TEST(Export, PoseCountMismatchIsAnError) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 3);
    const std::string path = dir.file("flock.glb");
    const auto written = write_birds_glb(path, world, std::span(poses).first(poses.size() - 1), 3);
    ASSERT_FALSE(written.ok());
    EXPECT_EQ(written.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(written.error().message.find("poses"), std::string::npos) << written.error().message;
    EXPECT_TRUE(dir.entries().empty());

    const auto too_many = write_birds_glb(path, world, poses, 2);
    EXPECT_FALSE(too_many.ok());
    EXPECT_TRUE(dir.entries().empty());
}

/// Diagnostics with a value per field that tells the fields apart.
std::vector<gpu::BirdDiag> make_diag(std::size_t count, std::uint32_t frame) {
    std::vector<gpu::BirdDiag> diag(count);
    for (std::size_t b = 0; b < count; ++b) {
        const float k = static_cast<float>(b) + 0.5f * static_cast<float>(frame);
        diag[b].velocity = {k, 2.0f, 3.0f, 0.25f};
        diag[b].acceleration = {0.5f, -0.5f, 0.125f, static_cast<float>(b % 3)};
        diag[b].angles = {0.1f, 0.2f, 0.3f, 0.4f};
        diag[b].attitude = {1.0f, -0.25f, 0.75f, 1.5f + k};
    }
    return diag;
}

std::vector<nlohmann::json> read_lines(const std::string& path) {
    std::vector<nlohmann::json> lines;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        // Every line on its own must be a complete JSON document.
        lines.push_back(nlohmann::json::parse(line));
    }
    return lines;
}

std::array<float, 3> as_vec3(const nlohmann::json& value) {
    EXPECT_TRUE(value.is_array());
    EXPECT_EQ(value.size(), 3u);
    return {value.at(0).get<float>(), value.at(1).get<float>(), value.at(2).get<float>()};
}

TEST(Trace, RoundTrip) {
    TempDir dir;
    const auto world = make_world();
    constexpr std::uint32_t kTraceFrames = 2;
    const auto poses = make_poses(world, kTraceFrames);
    const std::string path = dir.file("trace.jsonl");

    auto writer = TraceWriter::open(path, TraceHeader{"two \"frames\"\n", kFps, kTraceFrames, "cpu-reference"});
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    for (std::uint32_t f = 0; f < kTraceFrames; ++f) {
        const auto diag = make_diag(kBirds, f);
        writer.value().write_frame(f, world, std::span(poses).subspan(f * kBirds, kBirds), diag);
    }
    const auto finished = writer.value().finish();
    ASSERT_TRUE(finished.ok()) << finished.error().message;
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"trace.jsonl"});

    const auto lines = read_lines(path);
    ASSERT_EQ(lines.size(), 1 + kTraceFrames * kBirds);
    const auto& header = lines[0];
    EXPECT_EQ(header.at("kind"), "header");
    EXPECT_EQ(header.at("scene"), "two \"frames\"\n");
    EXPECT_EQ(header.at("fps").get<double>(), 24.0);
    EXPECT_EQ(header.at("frames"), kTraceFrames);
    EXPECT_EQ(header.at("backend"), "cpu-reference");

    // Records are frame-major, birds in index order.
    for (std::size_t i = 1; i < lines.size(); ++i) {
        EXPECT_EQ(lines[i].at("kind"), "bird");
        EXPECT_EQ(lines[i].at("frame"), (i - 1) / kBirds);
        EXPECT_EQ(lines[i].at("id"), (i - 1) % kBirds);
    }

    // Bird 40 (a gull, mode 40 % 3 = 1: ascend) in frame 1.
    constexpr std::size_t kBird = 40;
    const auto& record = lines[1 + kBirds + kBird];
    const std::set<std::string> expected_keys = {"kind",     "frame",    "time",         "id",  "wing_type",
                                                 "mode",     "phase",    "blend",        "position", "velocity",
                                                 "acceleration", "yaw",  "pitch",        "bank", "angles",
                                                 "parts"};
    std::set<std::string> keys;
    for (const auto& item : record.items()) keys.insert(item.key());
    EXPECT_EQ(keys, expected_keys);

    const gpu::BirdPose& pose = poses[kBirds + kBird];
    const gpu::BirdDiag diag = make_diag(kBirds, 1)[kBird];
    EXPECT_EQ(record.at("frame"), 1);
    EXPECT_DOUBLE_EQ(record.at("time").get<double>(), 1.0 / 24.0);
    EXPECT_EQ(record.at("wing_type"), "gull");
    EXPECT_EQ(record.at("mode"), "ascend");
    EXPECT_EQ(record.at("phase").get<float>(), diag.attitude.w);
    EXPECT_EQ(record.at("blend").get<float>(), 0.25f);
    EXPECT_EQ(as_vec3(record.at("position")), (std::array<float, 3>{pose.position.x, pose.position.y, pose.position.z}));
    EXPECT_EQ(as_vec3(record.at("velocity")), (std::array<float, 3>{diag.velocity.x, 2.0f, 3.0f}));
    EXPECT_EQ(as_vec3(record.at("acceleration")), (std::array<float, 3>{0.5f, -0.5f, 0.125f}));
    EXPECT_EQ(record.at("yaw").get<float>(), 1.0f);
    EXPECT_EQ(record.at("pitch").get<float>(), -0.25f);
    EXPECT_EQ(record.at("bank").get<float>(), 0.75f);
    const auto& angles = record.at("angles");
    EXPECT_EQ(angles.size(), 4u);
    EXPECT_EQ(angles.at("arm1_pitch").get<float>(), 0.1f);
    EXPECT_EQ(angles.at("arm2_pitch").get<float>(), 0.2f);
    EXPECT_EQ(angles.at("arm1_heading").get<float>(), 0.3f);
    EXPECT_EQ(angles.at("arm2_heading").get<float>(), 0.4f);

    const auto& parts = record.at("parts");
    ASSERT_EQ(parts.size(), birds::kPartCount);
    const auto offsets = birds::part_offsets(birds::WingType::Gull);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        const std::string name(birds::kPartNames[part]);
        ASSERT_TRUE(parts.contains(name)) << name;
        const auto& entry = parts.at(name);
        const auto t = as_vec3(entry.at("t"));
        if (part == KW_PART_BODY) {
            EXPECT_EQ(t, (std::array<float, 3>{pose.position.x, pose.position.y, pose.position.z}));
        } else {
            EXPECT_EQ(t, offsets[part]) << name;
        }
        const auto& r = entry.at("r");
        ASSERT_EQ(r.size(), 4u);
        const gpu::vec4& q = pose.rotation[part];
        // Shortest round-trip formatting: the floats come back bit for bit.
        EXPECT_EQ(r.at(0).get<float>(), q.x) << name;
        EXPECT_EQ(r.at(1).get<float>(), q.y) << name;
        EXPECT_EQ(r.at(2).get<float>(), q.z) << name;
        EXPECT_EQ(r.at(3).get<float>(), q.w) << name;
    }
}

TEST(Trace, UnfinishedWriterLeavesNoFile) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 1);
    const auto diag = make_diag(kBirds, 0);
    const std::string path = dir.file("trace.jsonl");
    {
        auto writer = TraceWriter::open(path, TraceHeader{"abandoned", kFps, 1, "cpu"});
        ASSERT_TRUE(writer.ok()) << writer.error().message;
        writer.value().write_frame(0, world, poses, diag);
        EXPECT_FALSE(dir.entries().empty());  // the temporary file exists meanwhile
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Trace, MissingDirectoryIsAnError) {
    TempDir dir;
    const std::string path = dir.file("no-such-dir/trace.jsonl");
    const auto writer = TraceWriter::open(path, TraceHeader{"s", kFps, 1, "cpu"});
    ASSERT_FALSE(writer.ok());
    EXPECT_EQ(writer.error().kind, Error::Kind::Io);
    EXPECT_NE(writer.error().message.find(path), std::string::npos) << writer.error().message;
}

// ---------------------------------------------------------------------------------------
// Rod scenes: the chains' export.

struct RodRun {
    RodScene scene;
    std::uint32_t frames = 0;
    std::vector<glm::vec3> positions;
    std::vector<glm::quat> orientations;
};

// The bunny scene, `frames` frames on the CPU reference.
RodRun run_bunny(std::uint32_t frames) {
    RodRun run;
    auto scene = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/bunny.json");
    EXPECT_TRUE(scene.ok());
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

glm::mat4 node_matrix(const tinygltf::Node& n) {
    glm::mat4 m(1.0f);
    if (n.translation.size() == 3) {
        m = glm::translate(m, glm::vec3(static_cast<float>(n.translation[0]), static_cast<float>(n.translation[1]),
                                        static_cast<float>(n.translation[2])));
    }
    if (n.rotation.size() == 4) {
        m = m * glm::mat4_cast(glm::quat(static_cast<float>(n.rotation[3]), static_cast<float>(n.rotation[0]),
                                         static_cast<float>(n.rotation[1]), static_cast<float>(n.rotation[2])));
    }
    return m;
}

// Re-importing the export gives back the simulated joints: every chain joint node's
// world position (its rest TRS is frame 0, composed down the hierarchy) is the
// simulated position within 1e-5 m (float rounding of 12 composed transforms on a 0.3 m
// ear), and every node has translation and rotation channels with one key per frame.
TEST(Export, ChainsRoundTrip) {
    const RodRun run = run_bunny(20);
    TempDir dir;
    const std::string path = dir.file("bunny.glb");
    const auto written = write_chains_glb(path, run.scene, run.frames, run.positions, run.orientations);
    ASSERT_TRUE(written.ok()) << written.error().message;
    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    const rods::RodWorld& world = run.scene.world;
    std::size_t skeleton_nodes = 0;
    for (std::uint32_t c = 0; c < world.character_count; ++c) skeleton_nodes += run.scene.joint_names(c).size();
    ASSERT_EQ(model.nodes.size(), 1 + skeleton_nodes + world.joint_count);
    ASSERT_EQ(model.animations.size(), 1u);
    EXPECT_EQ(model.animations[0].channels.size(), 2 * (skeleton_nodes + world.joint_count));
    for (const auto& sampler : model.animations[0].samplers) {
        ASSERT_EQ(model.accessors.at(static_cast<std::size_t>(sampler.output)).count, run.frames);
    }
    // World matrices by walking the tree from the root node.
    std::vector<glm::mat4> world_of(model.nodes.size());
    std::vector<std::pair<int, glm::mat4>> stack = {{0, node_matrix(model.nodes[0])}};
    while (!stack.empty()) {
        auto [node, m] = stack.back();
        stack.pop_back();
        world_of[static_cast<std::size_t>(node)] = m;
        for (int child : model.nodes[static_cast<std::size_t>(node)].children) {
            stack.push_back({child, m * node_matrix(model.nodes[static_cast<std::size_t>(child)])});
        }
    }
    float worst = 0.0f;
    std::size_t checked = 0;
    for (std::size_t c = 0; c < world.chains.size(); ++c) {
        const rods::ChainInstance& ch = world.chains[c];
        for (std::uint32_t i = 0; i < world.templ(ch).chain.joint_count; ++i) {
            const std::string name = run.scene.chain_names[c] + "/" + std::to_string(i);
            for (std::size_t n = 0; n < model.nodes.size(); ++n) {
                if (model.nodes[n].name != name) continue;
                const glm::vec3 p(world_of[n][3]);
                worst = std::max(worst, glm::length(p - run.positions[ch.joint_begin + i]));
                ++checked;
            }
        }
    }
    EXPECT_EQ(checked, world.joint_count);
    EXPECT_LT(worst, 1e-5f);
}

TEST(Export, ChainsPassGltfValidator) {
    const RodRun run = run_bunny(10);
    TempDir dir;
    const std::string path = dir.file("bunny.glb");
    ASSERT_TRUE(write_chains_glb(path, run.scene, run.frames, run.positions, run.orientations).ok());
    std::string output;
    EXPECT_EQ(run_command(gltf_validator_command(path), output), 0) << output;
    EXPECT_NE(output.find("glTF-Validator: 0 errors, 0 warnings"), std::string::npos) << output;
}

TEST(Export, ChainsRejectMismatchedSizes) {
    RodRun run = run_bunny(3);
    run.positions.pop_back();
    TempDir dir;
    const auto written = write_chains_glb(dir.file("x.glb"), run.scene, run.frames, run.positions, run.orientations);
    ASSERT_FALSE(written.ok());
    EXPECT_EQ(written.error().kind, Error::Kind::InvalidInput);
    EXPECT_FALSE(fs::exists(dir.file("x.glb")));
}

}  // namespace
}  // namespace kodawari
