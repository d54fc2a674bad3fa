// A user's rigged bird (issue 14, docs/bird-models.md): the bones mapped onto the 7-part
// rig, the wing measured, the part rotations carried into the bones' frames, a flock of
// it simulated on cpu-reference and exported, and bad input. The birds come from
// scripts/make_test_bird.py (bones along +Y as Blender exports them, names "spine",
// "wing.L", "forearm.L", ...; its KNOWN planform: span 1.12 m, area 0.1248 m^2).

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/simulation/bake.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/gltf/bird_model_import.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using testing_support::run_command;
using testing_support::shell_quote;
using testing_support::TempDir;

// The generator's bird of `variant` in `dir`.
std::string make_bird(const TempDir& dir, const std::string& variant = "good", const std::string& name = "bird.glb") {
    const std::string path = dir.file(name);
    std::string output;
    const std::string command = "python3 " + shell_quote(std::string(KODAWARI_SOURCE_DIR) + "/scripts/make_test_bird.py") + " " +
                                shell_quote(path) + " --variant " + variant;
    EXPECT_EQ(run_command(command, output), 0) << output;
    return path;
}

std::string bone(const birds::BirdModel& m, std::size_t part) {
    return m.character.nodes[static_cast<std::size_t>(m.bones[part])].name;
}

glm::vec3 turn(const glm::quat& q, glm::vec3 v) { return q * v; }

// The measured figures are the generator's planform up to float rounding: the skinned
// positions pass through a world matrix and an inverse bind matrix in float (relative
// error ~1e-7 per product), so 1e-5 relative is loose and still catches any real
// mistake (a face counted twice is 100 %, a wrong axis tens of %).
constexpr double kRelative = 1e-5;

TEST(BirdModel, MapsBlenderNamesAndMeasuresTheWing) {
    TempDir dir;
    auto loaded = gltf::load_bird_model(make_bird(dir));
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const birds::BirdModel& m = loaded.value();
    EXPECT_EQ(m.name, "bird");
    EXPECT_EQ(m.mapped_by, "name patterns");
    EXPECT_EQ(bone(m, KW_PART_BODY), "spine");
    EXPECT_EQ(bone(m, KW_PART_HEAD), "head");
    EXPECT_EQ(bone(m, KW_PART_TAIL), "tail");
    EXPECT_EQ(bone(m, KW_PART_LEFT_ARM1), "wing.L");
    EXPECT_EQ(bone(m, KW_PART_LEFT_ARM2), "forearm.L");
    EXPECT_EQ(bone(m, KW_PART_RIGHT_ARM1), "wing.R");
    EXPECT_EQ(bone(m, KW_PART_RIGHT_ARM2), "forearm.R");

    const double span = 1.12, area = 2 * 0.52 * 0.12;
    EXPECT_NEAR(m.measure.wingspan, span, span * kRelative);
    EXPECT_NEAR(m.measure.wing_area, area, area * kRelative);
    EXPECT_NEAR(m.mean_chord, area / span, area / span * kRelative);
    EXPECT_NEAR(m.flight.aspect_ratio, span * span / area, span * span / area * kRelative);
    EXPECT_NEAR(m.measure.body_length, 0.46, 0.46 * kRelative);
    EXPECT_GT(m.measure.mass, 0.0f);  // estimated
    EXPECT_GT(m.flight.flap_frequency, 0.0f);
    EXPECT_GT(m.flight.cruise_speed, 0.0f);

    // The axes: a bone's own +Y (along the bone, Blender's way) is the rig part's forward
    // for the body and head, its backward for the tail, its span (+X) for the left wing
    // and -X for the right one.
    const glm::vec3 y(0, 1, 0);
    const auto expect_dir = [&](std::size_t part, glm::vec3 expected) {
        const glm::vec3 got = turn(m.axes[part], y);
        EXPECT_LT(glm::length(got - expected), 1e-6f) << birds::kPartNames[part] << ": (" << got.x << ", " << got.y << ", " << got.z << ")";
    };
    expect_dir(KW_PART_BODY, {0, 0, 1});
    expect_dir(KW_PART_HEAD, {0, 0, 1});
    expect_dir(KW_PART_TAIL, {0, 0, -1});
    expect_dir(KW_PART_LEFT_ARM1, {1, 0, 0});
    expect_dir(KW_PART_LEFT_ARM2, {1, 0, 0});
    expect_dir(KW_PART_RIGHT_ARM1, {-1, 0, 0});
    expect_dir(KW_PART_RIGHT_ARM2, {-1, 0, 0});
    // Offsets: the shoulder from the spine's root, the elbow along the wing's span.
    const auto expect_offset = [&](std::size_t part, glm::vec3 expected) {
        const auto& o = m.offsets[part];
        EXPECT_LT(glm::length(glm::vec3(o[0], o[1], o[2]) - expected), 1e-6f) << birds::kPartNames[part];
    };
    expect_offset(KW_PART_LEFT_ARM1, {0.04f, 0.02f, 0.1f});
    expect_offset(KW_PART_LEFT_ARM2, {0.26f, 0.0f, 0.0f});
    expect_offset(KW_PART_RIGHT_ARM2, {-0.26f, 0.0f, 0.0f});
    expect_offset(KW_PART_HEAD, {0.0f, 0.03f, 0.25f});
}

// A part rotation q in the rig's axes, carried into the bone's frame (conj(C) q C on the
// rest rotation), turns the bone in the world as q turns the rig's part: the wing's span
// goes where q takes the rig's +X, whatever axis the bone points along itself.
TEST(BirdModel, PartRotationsTurnTheBonesAsTheRigsParts) {
    TempDir dir;
    auto loaded = gltf::load_bird_model(make_bird(dir));
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const birds::BirdModel& m = loaded.value();
    const animation::Pose rest = animation::rest_pose(m.character);
    // A wingbeat-like turn about the forward axis, and a sweep about the up axis.
    const glm::quat q = glm::angleAxis(0.6f, glm::vec3(0, 0, 1)) * glm::angleAxis(0.3f, glm::vec3(0, 1, 0));
    for (const std::size_t part : {std::size_t{KW_PART_LEFT_ARM1}, std::size_t{KW_PART_RIGHT_ARM1}, std::size_t{KW_PART_HEAD}}) {
        const animation::Node& node = m.character.nodes[static_cast<std::size_t>(m.bones[part])];
        const glm::quat parent = animation::rigid_part(rest.world[static_cast<std::size_t>(node.parent)]).rotation;
        const glm::quat world = parent * birds::model_bone_rotation(m, part, q);
        // The bone's +Y in the world, against q applied to the rig part's direction.
        const glm::vec3 rig_dir = turn(m.axes[part], glm::vec3(0, 1, 0));
        const glm::vec3 expected = turn(q, rig_dir);
        const glm::vec3 got = turn(world, glm::vec3(0, 1, 0));
        EXPECT_LT(glm::length(got - expected), 1e-5f) << birds::kPartNames[part];
    }
}

TEST(BirdModel, MappingFileNamesUnusualBones) {
    TempDir dir;
    const std::string bird = make_bird(dir, "oddnames");
    // Without a mapping, the names say nothing.
    auto unmapped = gltf::load_bird_model(bird);
    ASSERT_FALSE(unmapped.ok());
    EXPECT_EQ(unmapped.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(unmapped.error().message.find(bird + ": skins[0].joints: no bone for the body"), std::string::npos)
        << unmapped.error().message;
    const std::string map = dir.file("map.json");
    std::ofstream(map) << R"({"body": "B0", "head": "B1", "tail": "B2", "left_upper_wing": "B3", "left_lower_wing": "B4",
                             "right_upper_wing": "B5", "right_lower_wing": "B6"})";
    auto mapped = gltf::load_bird_model(bird, map);
    ASSERT_TRUE(mapped.ok()) << mapped.error().message;
    EXPECT_EQ(mapped.value().mapped_by, map);
    EXPECT_EQ(bone(mapped.value(), KW_PART_LEFT_ARM2), "B4");
    EXPECT_NEAR(mapped.value().measure.wingspan, 1.12, 1.12 * kRelative);

    // A mapping file naming a bone the skin lacks: the mapping file's path and key.
    std::ofstream(map) << R"({"body": "B0", "head": "Nope"})";
    auto missing = gltf::load_bird_model(bird, map);
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find(map + ": $.head: no bone \"Nope\""), std::string::npos) << missing.error().message;
    std::ofstream(map) << R"({"wing": "B3"})";
    auto unknown = gltf::load_bird_model(bird, map);
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.error().message.find(map + ": $.wing: unknown part"), std::string::npos) << unknown.error().message;
}

TEST(BirdModel, BadBirdsAreRefusedNamingTheGltfPath) {
    TempDir dir;
    struct Case {
        const char* variant;
        const char* where;
    };
    for (const Case& c : {Case{"noskin", ": skins: the file has no skin"},
                          Case{"nomesh", ": meshes: no mesh is skinned to skins[0]"},
                          Case{"zerospan", ": meshes[0]: the left wing spans 0 m"}}) {
        SCOPED_TRACE(c.variant);
        const std::string bird = make_bird(dir, c.variant, std::string(c.variant) + ".glb");
        auto loaded = gltf::load_bird_model(bird);
        ASSERT_FALSE(loaded.ok());
        EXPECT_EQ(loaded.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(loaded.error().message.find(bird + c.where), std::string::npos) << loaded.error().message;
    }
}

// `rig --bird` prints the mapping and the measurements and writes a scene whose flock
// uses the model; bad input exits 2 and writes nothing.
TEST(BirdModel, RigCommandWritesASceneThatRuns) {
    TempDir dir;
    const std::string bird = make_bird(dir);
    const std::string kodawari = KODAWARI_CLI;
    std::string output;
    const std::string scene = dir.file("bird.json");
    ASSERT_EQ(run_command(shell_quote(kodawari) + " rig " + shell_quote(bird) + " --bird --out " + shell_quote(scene), output), 0)
        << output;
    std::cout << output;
    EXPECT_NE(output.find("left_lower_wing    forearm.L"), std::string::npos) << output;
    EXPECT_NE(output.find("wingspan 1.120 m, wing area 0.1248 m^2"), std::string::npos) << output;
    const std::string text = testing_support::file_bytes(scene);
    EXPECT_NE(text.find("\"model\": \"bird.glb\""), std::string::npos) << text;
    // It runs: every bird is of the model, so the model's file is the output itself.
    output.clear();
    const std::string baked = dir.file("baked.glb");
    ASSERT_EQ(run_command(shell_quote(kodawari) + " run " + shell_quote(scene) + " --backend cpu-reference --frames 10 --out " +
                              shell_quote(baked),
                          output),
              0)
        << output;
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, baked)) << error;
    EXPECT_EQ(model.skins.size(), 20u);
    EXPECT_EQ(model.meshes.size(), 1u);
    EXPECT_FALSE(std::filesystem::exists(dir.file("baked-bird.glb")));

    for (const char* variant : {"noskin", "nomesh", "zerospan", "oddnames"}) {
        SCOPED_TRACE(variant);
        const std::string bad = make_bird(dir, variant, std::string(variant) + ".glb");
        const std::string out = dir.file(std::string(variant) + ".json");
        output.clear();
        EXPECT_EQ(run_command(shell_quote(kodawari) + " rig " + shell_quote(bad) + " --bird --out " + shell_quote(out), output), 2)
            << output;
        EXPECT_NE(output.find(bad + ": "), std::string::npos) << output;
        EXPECT_FALSE(std::filesystem::exists(out));
    }
}

// A flock of the model on cpu-reference, baked: the built-in birds' file and the model's
// own (its mesh once, one armature per bird), glTF-Validator 0 errors.
TEST(BirdModel, FlockSimulatesAndExports) {
    TempDir dir;
    make_bird(dir);
    const std::string scene = dir.file("scene.json");
    std::ofstream(scene) << R"({"format": "kodawari-scene", "version": 1, "fps": 30, "duration": 1,
        "flocks": [{"name": "mine", "model": "bird.glb", "count": 5,
                    "generated_route": {"seed": 3, "segments": 4, "center": [0, 40, 0], "extent": [45, 8, 45], "loop": true}},
                   {"name": "pigeons", "wing_type": "pigeon", "count": 3,
                    "generated_route": {"seed": 4, "segments": 4, "center": [0, 40, 0], "extent": [45, 8, 45], "loop": true}}]})";
    auto sim = Simulation::open(scene, {.backend = BackendKind::CpuReference, .frames = 12});
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const birds::BirdWorld& world = bird_world(*sim.value());
    ASSERT_EQ(world.models.size(), 1u);
    EXPECT_EQ(world.birds[0].ids.y, birds::kWingTypeCount);
    EXPECT_EQ(world.birds[4].ids.y, birds::kWingTypeCount);
    EXPECT_EQ(world.birds[5].ids.y, 0u);
    EXPECT_EQ(world.birds[0].motion.y > 0.0f, true);
    auto sink = make_birds_glb_sink(dir.file("out.glb"));
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*sim.value(), sinks);
    ASSERT_TRUE(written.ok()) << written.error().message;
    ASSERT_EQ(written.value().size(), 2u);
    EXPECT_EQ(written.value()[1].path, dir.file("out-bird.glb"));

    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, dir.file("out-bird.glb"))) << error;
    EXPECT_EQ(model.meshes.size(), 1u);  // the model's mesh, shared
    EXPECT_EQ(model.skins.size(), 5u);   // one armature per bird
    EXPECT_EQ(model.materials.size(), 1u);
    ASSERT_EQ(model.animations.size(), 1u);
    // 7 bones, translation and rotation, and the tail bone's scale: the simulation spreads
    // the tail (flight-modes.md F.5).
    EXPECT_EQ(model.animations[0].channels.size(), 5u * (7u * 2u + 1u));
    // Bird 0's spine (the Body's bone; its parent "Armature" sits at the origin) is keyed
    // where the simulation put the bird, frame by frame (float keys: 1e-5 m at 40 m).
    auto stepped = Simulation::open(scene, {.backend = BackendKind::CpuReference, .frames = 12});
    ASSERT_TRUE(stepped.ok()) << stepped.error().message;
    std::vector<gpu::BirdPose> poses(12 * world.birds.size());
    ASSERT_TRUE(step_birds(*stepped.value(), 12, poses).ok());
    int spine = -1;
    for (std::size_t n = 0; n < model.nodes.size(); ++n) {
        if (model.nodes[n].name == "bird_0/spine") spine = static_cast<int>(n);
    }
    ASSERT_GE(spine, 0);
    const tinygltf::Animation& flight = model.animations[0];
    const tinygltf::AnimationChannel* moved = nullptr;
    for (const auto& channel : flight.channels) {
        if (channel.target_node == spine && channel.target_path == "translation") moved = &channel;
    }
    ASSERT_NE(moved, nullptr);
    const tinygltf::Accessor& keys = model.accessors.at(static_cast<std::size_t>(flight.samplers.at(static_cast<std::size_t>(moved->sampler)).output));
    ASSERT_EQ(keys.count, 12u);
    const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(keys.bufferView));
    std::vector<float> values(3 * keys.count);
    std::memcpy(values.data(), model.buffers[0].data.data() + view.byteOffset + keys.byteOffset, values.size() * sizeof(float));
    for (std::uint32_t f = 0; f < 12; ++f) {
        const gpu::BirdPose& pose = poses[f * world.birds.size()];
        EXPECT_NEAR(values[3 * f], pose.position.x, 1e-5) << "frame " << f;
        EXPECT_NEAR(values[3 * f + 1], pose.position.y, 1e-5) << "frame " << f;
        EXPECT_NEAR(values[3 * f + 2], pose.position.z, 1e-5) << "frame " << f;
    }

    tinygltf::Model birds_file;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&birds_file, &error, &warning, dir.file("out.glb"))) << error;
    EXPECT_EQ(birds_file.skins.size(), 3u);  // the pigeons only
    EXPECT_EQ(birds_file.nodes.at(1).name, "pigeon_5");

    for (const char* file : {"out.glb", "out-bird.glb"}) {
        std::string output;
        EXPECT_EQ(run_command(testing_support::gltf_validator_command(dir.file(file)), output), 0) << output;
        EXPECT_NE(output.find("glTF-Validator: 0 errors"), std::string::npos) << output;
    }
}

// Two flocks of one model file: each flock loads the file, so the bake has two models of
// one name, and each gets a file of its own (out-bird.glb, out-bird-2.glb); they shared
// one path and the second replaced the first, its birds lost.
TEST(BirdModel, TwoFlocksOfOneModelBakeToTwoFiles) {
    TempDir dir;
    make_bird(dir);
    const std::string scene = dir.file("scene.json");
    std::ofstream(scene) << R"({"format": "kodawari-scene", "version": 1, "fps": 30, "duration": 1,
        "flocks": [{"name": "a", "model": "bird.glb", "count": 3,
                    "generated_route": {"seed": 3, "segments": 4, "center": [0, 40, 0], "extent": [45, 8, 45], "loop": true}},
                   {"name": "b", "model": "bird.glb", "count": 4,
                    "generated_route": {"seed": 4, "segments": 4, "center": [0, 40, 0], "extent": [45, 8, 45], "loop": true}}]})";
    auto sim = Simulation::open(scene, {.backend = BackendKind::CpuReference, .frames = 4});
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    auto sink = make_birds_glb_sink(dir.file("out.glb"));
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*sim.value(), sinks);
    ASSERT_TRUE(written.ok()) << written.error().message;
    ASSERT_EQ(written.value().size(), 2u);
    EXPECT_EQ(written.value()[0].path, dir.file("out-bird.glb"));
    EXPECT_EQ(written.value()[1].path, dir.file("out-bird-2.glb"));
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    std::size_t skins = 0;
    for (const char* file : {"out-bird.glb", "out-bird-2.glb"}) {
        tinygltf::Model model;
        ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, dir.file(file))) << file << ": " << error;
        skins += model.skins.size();
    }
    EXPECT_EQ(skins, 7u);  // every bird of both flocks, one armature each

    // Named after --out without its .glb in any case (they were "OUT.GLB-bird.glb" where
    // the characters' file was already "OUT-characters.glb").
    EXPECT_EQ(glb_stem("a/b.GLB"), "a/b");
    EXPECT_EQ(glb_stem("a/b.gltf"), "a/b.gltf");
    auto again = Simulation::open(scene, {.backend = BackendKind::CpuReference, .frames = 4});
    ASSERT_TRUE(again.ok()) << again.error().message;
    auto upper = make_birds_glb_sink(dir.file("UP.GLB"));
    BakeSink* upper_sinks[] = {upper.get()};
    auto rewritten = bake(*again.value(), upper_sinks);
    ASSERT_TRUE(rewritten.ok()) << rewritten.error().message;
    ASSERT_EQ(rewritten.value().size(), 2u);
    EXPECT_EQ(rewritten.value()[0].path, dir.file("UP-bird.glb"));
}

// The Tail's spread s scales the model's tail bone by 1 + s along its own axis nearest
// the rig's width (the generator's tail bone keeps X: its scale is (1 + s, 1, 1)), keyed
// only where the scale moves.
TEST(BirdModel, TailSpreadScalesTheTailBone) {
    TempDir dir;
    make_bird(dir);
    const std::string scene = dir.file("scene.json");
    std::ofstream(scene) << R"({"format": "kodawari-scene", "version": 1, "fps": 30, "duration": 1,
        "flocks": [{"model": "bird.glb", "count": 2,
                    "generated_route": {"seed": 3, "segments": 4, "center": [0, 40, 0], "extent": [45, 8, 45], "loop": true}}]})";
    auto sim = Simulation::open(scene, {.backend = BackendKind::CpuReference, .frames = 4});
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const birds::BirdWorld& world = bird_world(*sim.value());
    std::vector<gpu::BirdPose> poses(4 * world.birds.size());
    ASSERT_TRUE(step_birds(*sim.value(), 4, poses).ok());
    // The simulation spreads every tail a little (flight-modes.md F.5); here bird 0 keeps
    // its tail furled and bird 1 spreads it by a known amount.
    for (std::uint32_t f = 0; f < 4; ++f) {
        poses[f * 2].position.w = 0.0f;
        poses[f * 2 + 1].position.w = 0.1f * static_cast<float>(f);
    }
    const std::string path = dir.file("spread.glb");
    auto out = BirdModelExport::create(world, 0, path);
    ASSERT_TRUE(out.ok()) << out.error().message;
    ASSERT_TRUE(out.value().add_frames(poses).ok());
    ASSERT_TRUE(out.value().finish().ok());
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
    const auto scale_keys = [&](const std::string& name) {
        std::vector<float> values;
        for (const auto& channel : model.animations.at(0).channels) {
            if (channel.target_path != "scale" || model.nodes.at(static_cast<std::size_t>(channel.target_node)).name != name) continue;
            const auto& accessor = model.accessors.at(static_cast<std::size_t>(
                model.animations[0].samplers.at(static_cast<std::size_t>(channel.sampler)).output));
            const auto& view = model.bufferViews.at(static_cast<std::size_t>(accessor.bufferView));
            values.resize(3 * accessor.count);
            std::memcpy(values.data(), model.buffers[0].data.data() + view.byteOffset + accessor.byteOffset, values.size() * 4);
        }
        return values;
    };
    EXPECT_TRUE(scale_keys("bird_0/tail").empty());  // bird 0 never spreads
    const std::vector<float> spread = scale_keys("bird_1/tail");
    ASSERT_EQ(spread.size(), 12u);
    for (std::uint32_t f = 0; f < 4; ++f) {
        EXPECT_FLOAT_EQ(spread[3 * f], 1.0f + 0.1f * static_cast<float>(f)) << "frame " << f;
        EXPECT_FLOAT_EQ(spread[3 * f + 1], 1.0f);
        EXPECT_FLOAT_EQ(spread[3 * f + 2], 1.0f);
    }
}

}  // namespace
}  // namespace kodawari
