// The characters' chain export (SPEC C): the CPU reference on scenes/bunny.json baked to
// .glb, read back and checked by the glTF-Validator.

#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <span>

#include "export_support.hpp"

namespace kodawari {
namespace {

using namespace export_test;

// ---------------------------------------------------------------------------------------
// Rod scenes: the chains' export.

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

// Frames one at a time (a bake's sink) end in write_chains_glb's file (whose bytes
// export_identity pins to those of the writer that held every frame); the keys wait in
// a temporary file that is never seen in the directory.
TEST(Export, ChainsStreamedGiveTheBytesOfOneCall) {
    const RodRun run = run_bunny(9);
    const std::size_t joints = run.scene.world.joint_count;
    TempDir dir;
    ASSERT_TRUE(write_chains_glb(dir.file("whole.glb"), run.scene, run.frames, run.positions, run.orientations).ok());
    auto writer = ChainsGlbWriter::create(dir.file("streamed.glb"), run.scene, run.frames);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    for (std::uint32_t f = 0; f < run.frames; ++f) {
        ASSERT_TRUE(writer.value()
                        .add_frame(std::span(run.positions).subspan(f * joints, joints),
                                   std::span(run.orientations).subspan(f * joints, joints))
                        .ok());
        EXPECT_EQ(dir.entries(), std::vector<std::string>{"whole.glb"});
    }
    ASSERT_TRUE(writer.value().finish().ok());
    EXPECT_EQ(testing_support::file_bytes(dir.file("whole.glb")), testing_support::file_bytes(dir.file("streamed.glb")));
}

TEST(Export, ChainsStreamFailuresLeaveNoFile) {
    RodRun run = run_bunny(3);
    const std::size_t joints = run.scene.world.joint_count;
    TempDir dir;
    const std::string path = dir.file("x.glb");
    {
        auto writer = ChainsGlbWriter::create(path, run.scene, 3);
        ASSERT_TRUE(writer.ok());
        ASSERT_TRUE(writer.value().add_frame(std::span(run.positions).first(joints), std::span(run.orientations).first(joints)).ok());
        const auto early = writer.value().finish();
        ASSERT_FALSE(early.ok());
        EXPECT_EQ(early.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(early.error().message.find("1 of 3 frames"), std::string::npos) << early.error().message;
        EXPECT_FALSE(writer.value().add_frame(std::span(run.positions).first(joints - 1), std::span(run.orientations).first(joints)).ok());
    }
    EXPECT_TRUE(dir.entries().empty());
    // A joint the solver lost: the frame is refused, nothing is written.
    run.positions[joints + 1] = glm::vec3(std::numeric_limits<float>::quiet_NaN());
    const auto lost = write_chains_glb(path, run.scene, run.frames, run.positions, run.orientations);
    ASSERT_FALSE(lost.ok());
    EXPECT_EQ(lost.error().kind, Error::Kind::Internal);
    EXPECT_NE(lost.error().message.find("frame 1"), std::string::npos) << lost.error().message;
    EXPECT_TRUE(dir.entries().empty());
}

// Past glb's 32-bit length, refused before any frame is simulated, naming file and size.
TEST(Export, ChainsPastFourGibAreRefusedAtOnce) {
    const RodRun run = run_bunny(1);
    TempDir dir;
    const std::string path = dir.file("x.glb");
    const auto writer = ChainsGlbWriter::create(path, run.scene, 1u << 30);
    ASSERT_FALSE(writer.ok());
    EXPECT_EQ(writer.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(writer.error().message.find(path), std::string::npos) << writer.error().message;
    EXPECT_NE(writer.error().message.find("4 GiB"), std::string::npos) << writer.error().message;
    EXPECT_TRUE(dir.entries().empty());
}

}  // namespace
}  // namespace kodawari
