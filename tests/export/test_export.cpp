// Tests of the bird export (SPEC C): the .glb read back with tinygltf and checked by the
// Khronos glTF-Validator, its meshes, and bad output paths. The bird worlds and poses are
// made by hand. Traces: test_trace.cpp; characters' chains: test_chain_export.cpp.

#include <gtest/gtest.h>

#include <fstream>

#include "export_support.hpp"

namespace kodawari {
namespace {

using namespace export_test;

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

    // Bird 18 is a hawk (18 % 4 == 2): its Body node, its parts, their rest offsets.
    constexpr std::size_t kBird = 18;
    const int body = model.nodes[0].children[kBird];
    const tinygltf::Node& body_node = model.nodes.at(static_cast<std::size_t>(body));
    EXPECT_EQ(body_node.name, "hawk_18");
    ASSERT_EQ(body_node.children.size(), 4u);  // Head, Tail, LeftArm1, RightArm1
    const auto offsets = birds::part_offsets(birds::WingType::Hawk);
    for (const int child : body_node.children) {
        const tinygltf::Node& part = model.nodes.at(static_cast<std::size_t>(child));
        const auto index = static_cast<std::size_t>(child - body);
        ASSERT_LT(index, birds::kPartCount);
        EXPECT_EQ(part.name, std::string(birds::kPartNames[index]) + "_18");
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

TEST(Export, StreamedFramesGiveTheBytesOfOneCall) {
    // Frames arriving one at a time or in uneven chunks (a bake's steps) end in the same
    // file; the keys wait in a temporary file that is never seen in the directory.
    TempDir dir;
    const auto world = make_world();
    constexpr std::uint32_t kStreamed = 7;
    auto poses = make_poses(world, kStreamed);
    const std::string whole = dir.file("whole.glb");
    ASSERT_TRUE(write_birds_glb(whole, world, poses, kStreamed).ok());
    const std::string streamed = dir.file("streamed.glb");
    auto writer = BirdGlbWriter::create(streamed, world, kStreamed);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    const std::size_t birds = world.birds.size();
    for (const std::uint32_t frames : {1u, 3u, 1u, 2u}) {
        ASSERT_TRUE(writer.value().add_frames(std::span(poses).first(frames * birds)).ok());
        poses.erase(poses.begin(), poses.begin() + static_cast<std::ptrdiff_t>(frames * birds));
        EXPECT_EQ(dir.entries(), std::vector<std::string>{"whole.glb"});
    }
    ASSERT_TRUE(writer.value().finish().ok());
    const auto bytes = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary | std::ios::ate);
        std::string data(static_cast<std::size_t>(in.tellg()), '\0');
        in.seekg(0);
        in.read(data.data(), static_cast<std::streamsize>(data.size()));
        return data;
    };
    EXPECT_EQ(bytes(whole), bytes(streamed));
}

TEST(Export, StreamEndedEarlyWritesNothing) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 3);
    const std::string path = dir.file("flock.glb");
    {
        auto writer = BirdGlbWriter::create(path, world, 3);
        ASSERT_TRUE(writer.ok());
        ASSERT_TRUE(writer.value().add_frames(std::span(poses).first(world.birds.size())).ok());
        const auto early = writer.value().finish();
        ASSERT_FALSE(early.ok());
        EXPECT_EQ(early.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(early.error().message.find("1 of 3 frames"), std::string::npos) << early.error().message;
        EXPECT_FALSE(writer.value().add_frames(std::span(poses).first(world.birds.size() + 1)).ok());
    }
    EXPECT_TRUE(dir.entries().empty());
}

/// Diagnostics with a value per field that tells the fields apart.
}  // namespace
}  // namespace kodawari
