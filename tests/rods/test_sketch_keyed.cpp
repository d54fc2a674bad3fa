// Keyed sketches (docs/sketch.md, "Keyed sketches"): a stroke becomes a keyed example
// (docs/keyed-examples.md) keyed by the character's motion or pose at the sketched frame.
// The key is what the simulation itself measures there, the example loads back with the
// sketched shape, undo gives the file back byte for byte, and the limits of K.1 are refused
// naming the file and the chain.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "kodawari/scene/scene.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "kodawari/scene/sketch_key.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using Json = nlohmann::ordered_json;

std::string scene_file(const std::string& name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

RodScene rod_scene_of(const std::string& text, const std::string& path) {
    auto scene = parse_scene(text, path);
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    auto rs = build_rod_scene(scene.value());
    EXPECT_TRUE(rs.ok()) << rs.error().message;
    return std::move(rs).value();
}

std::uint32_t template_index(const RodScene& rs, const std::string& name) {
    for (std::uint32_t t = 0; t < rs.world.templates.size(); ++t) {
        if (rs.world.templates[t].name == name) return t;
    }
    ADD_FAILURE() << "no chain " << name;
    return 0;
}

// The first chain instance of template `name`.
std::uint32_t first_chain(const RodScene& rs, const std::string& name) {
    const std::uint32_t t = template_index(rs, name);
    for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
        if (rs.world.chains[c].template_index == t) return c;
    }
    ADD_FAILURE() << "no instance of " << name;
    return 0;
}

// The smoothed keys (K.2's m_j) and raw weights of chain `c`'s keyed examples at `frame`,
// as a backend measures them: the key state from frame 0, measure_keys at 1 .. frame.
struct Measured {
    rods::KeyState state;
    rods::KeyedWeights u{};
};
Measured simulate_keys(const RodScene& rs, std::uint32_t c, std::uint32_t frame) {
    rods::RodFrame f;
    rs.frame(0, f);
    Measured m;
    m.state = rods::initial_key_state(rs.world, c, f);
    for (std::uint32_t i = 1; i <= frame; ++i) {
        rs.frame(i, f);
        m.u = rods::measure_keys(rs.world, c, f, m.state);
    }
    return m;
}

// The chain's shape drawn from the scene's camera at `frame`: a stroke from the root,
// out to the right and down, as a user would sketch a streaming strand.
rods::ChainShape sketched_shape(const RodScene& rs, std::uint32_t chain, std::uint32_t frame) {
    const rods::RodFrame f = rs.frame(frame);
    rods::SketchInput in;
    in.camera = rods::ImageCamera::from_pose(rs.camera_pose(frame), rs.fov_deg, 1280, 720);
    in.root = f.roots[chain];
    in.reference = f.reference[rs.world.chains[chain].character];
    in.lengths = rs.world.templ(rs.world.chains[chain]).basis.lengths;
    for (int i = 0; i < 12; ++i) in.stroke.push_back(glm::dvec2(600.0 + 25.0 * i, 300.0 + 4.0 * i * i / 3.0));
    auto r = rods::sketch_view_example(in);
    EXPECT_TRUE(r.ok()) << r.error().message;
    return r.value().shape;
}

void expect_same_shape(const rods::ChainShape& loaded, const rods::ChainShape& sketched) {
    ASSERT_EQ(loaded.positions.size(), sketched.positions.size());
    for (std::size_t i = 0; i < loaded.positions.size(); ++i) {
        // Written with 6 significant digits: well under a micrometre for millimetre joints.
        EXPECT_LT(glm::length(loaded.positions[i] - sketched.positions[i]), 1e-6f) << "joint " << i;
    }
}

const ChainSpec& chain_spec(const Scene& scene, const std::string& character, const std::string& chain) {
    for (const CharacterSpec& c : scene.characters) {
        if (c.name != character) continue;
        for (const ChainSpec& s : c.chains) {
            if (s.name == chain) return s;
        }
    }
    ADD_FAILURE() << "no chain " << character << "/" << chain;
    return scene.characters.at(0).chains.at(0);
}

constexpr std::uint32_t kSprintFrame = 330;  // 5.5 s of scenes/ponytail.json: the sprint (3.8 to 6.5 s)

}  // namespace

// The motion key is the head speed the simulation measures at the frame: with the sprint
// example's own smoothing (0.3 s), the same number as the backend's key state for that
// example. Tolerance: the same float operations on the same poses, so 1e-6 relative.
TEST(SketchKeyed, MotionKeyIsTheSpeedTheSimulationMeasures) {
    const std::string path = scene_file("ponytail.json");
    const RodScene rs = rod_scene_of(testing_support::file_bytes(path), path);
    const std::uint32_t chain = first_chain(rs, "runner/ponytail");
    SketchKeyOptions o;
    o.smoothing = 0.3f;
    auto key = measure_sketch_key(rs, rs.world.chains[chain].character, kSprintFrame, o);
    ASSERT_TRUE(key.ok()) << key.error().message;
    const Measured sim = simulate_keys(rs, chain, kSprintFrame);
    std::printf("[ measured ] head speed at frame %u: sketch %.6f m/s, simulation %.6f m/s\n", kSprintFrame,
                double(key.value().value), double(sim.state.smoothed[0].x));
    EXPECT_EQ(key.value().joint, "head");
    EXPECT_NEAR(key.value().value, sim.state.smoothed[0].x, 1e-6f * sim.state.smoothed[0].x);
    EXPECT_GT(key.value().value, 4.0f);  // a sprint (the walk is 1.4 m/s, the run 4.6 m/s more)
    EXPECT_FLOAT_EQ(key.value().influence, kSketchMotionInfluence * key.value().value);
}

// The whole path at a sprint frame with the defaults (speed, 0.25 s): the written example
// loads with the measured key and the sketched shape, and in the written scene the
// simulation at that frame reads the example's key (weight 1 within 1e-4: the key is
// written with 6 significant digits); undo gives back the file byte for byte.
TEST(SketchKeyed, MotionSketchOnThePonytailLoadsAndUndoes) {
    const std::string path = scene_file("ponytail.json");
    const std::string text = testing_support::file_bytes(path);
    const RodScene rs = rod_scene_of(text, path);
    const std::uint32_t chain = first_chain(rs, "runner/ponytail");
    auto key = measure_sketch_key(rs, rs.world.chains[chain].character, kSprintFrame, SketchKeyOptions{});
    ASSERT_TRUE(key.ok()) << key.error().message;
    KeyedSketch k = key.value();
    k.shape = sketched_shape(rs, chain, kSprintFrame);
    auto edit = add_keyed_example(text, path, "runner/ponytail", k);
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_TRUE(edit.value().keyed);
    EXPECT_EQ(edit.value().index, 1u);
    EXPECT_EQ(edit.value().name, "sketch 1");

    auto scene = parse_scene(edit.value().text, path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const ChainSpec& c = chain_spec(scene.value(), "runner", "ponytail");
    ASSERT_EQ(c.keyed.size(), 2u);
    const KeyedSpec& added = c.keyed[1];
    EXPECT_EQ(added.name, "sketch 1");
    EXPECT_EQ(added.example.kind, rods::KeyKind::Motion);
    EXPECT_EQ(added.example.measure, rods::MotionMeasure::Speed);
    EXPECT_EQ(added.example.frame, rods::MotionFrame::Magnitude);
    EXPECT_NEAR(added.example.value.x, k.value, 1e-5f * k.value);
    EXPECT_NEAR(added.example.influence, k.influence, 1e-5f * k.influence);
    EXPECT_FLOAT_EQ(added.example.smoothing, 0.25f);
    // The sprint example and the sketch read the same source: the head, as motion.
    EXPECT_EQ(added.example.source, c.keyed[0].example.source);
    ASSERT_EQ(c.key_sources.size(), 1u);
    expect_same_shape(added.shape, k.shape);

    const RodScene written = rod_scene_of(edit.value().text, path);
    const Measured sim = simulate_keys(written, first_chain(written, "runner/ponytail"), kSprintFrame);
    std::printf("[ measured ] written key %.6f m/s; the written scene's simulation reads %.6f m/s there (weight %.6f)\n",
                double(added.example.value.x), double(sim.state.smoothed[1].x), double(sim.u[1]));
    EXPECT_GT(sim.u[1], 1.0f - 1e-4f);

    auto undo = remove_last_sketch(edit.value().text, path, "runner/ponytail");
    ASSERT_TRUE(undo.ok()) << undo.error().message;
    EXPECT_TRUE(undo.value().keyed);
    EXPECT_EQ(undo.value().name, "sketch 1");
    EXPECT_EQ(undo.value().text, text);  // byte for byte
}

// A pose sketch on scenes/nod.json while she looks down (the frame of the largest head
// pitch in the first 8 s): the key is the head's rotation relative to the neck, which the
// written example holds (6 digits: within 1e-5) and which the simulation reads there at
// weight 1.
TEST(SketchKeyed, PoseSketchOnTheBangsLookingDown) {
    const std::string path = scene_file("nod.json");
    const std::string text = testing_support::file_bytes(path);
    const RodScene rs = rod_scene_of(text, path);
    const std::uint32_t chain = first_chain(rs, "girl/bang_l1");
    const std::uint32_t character = rs.world.chains[chain].character;
    std::uint32_t down = 0;
    float pitch = -1e9f;
    for (std::uint32_t f = 0; f < rs.frames && rs.time(f) < 8.0f; ++f) {
        const std::vector<rods::Transform> j = rs.joint_poses(character, f);
        const glm::quat relative = glm::conjugate(j[1].rotation) * j[2].rotation;  // body, neck, head
        const float p = glm::degrees(2.0f * std::atan2(relative.x, relative.w));
        if (p > pitch) {
            pitch = p;
            down = f;
        }
    }
    ASSERT_GT(pitch, 25.0f);
    SketchKeyOptions o;
    o.kind = rods::KeyKind::Pose;
    auto key = measure_sketch_key(rs, character, down, o);
    ASSERT_TRUE(key.ok()) << key.error().message;
    KeyedSketch k = key.value();
    const std::vector<rods::Transform> j = rs.joint_poses(character, down);
    const glm::quat expected = glm::normalize(glm::conjugate(j[1].rotation) * j[2].rotation);
    std::printf("[ measured ] looking down at frame %u: head pitch %.2f degrees, key [%.5f, %.5f, %.5f, %.5f]\n", down,
                double(pitch), double(k.rotation.x), double(k.rotation.y), double(k.rotation.z), double(k.rotation.w));
    EXPECT_EQ(k.joint, "head");
    EXPECT_LT(std::abs(std::abs(glm::dot(k.rotation, expected)) - 1.0f), 1e-6f);
    EXPECT_FLOAT_EQ(k.influence, 20.0f);
    k.shape = sketched_shape(rs, chain, down);

    auto edit = add_keyed_example(text, path, "girl/bang_l1", k);
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_EQ(edit.value().index, 1u);
    auto scene = parse_scene(edit.value().text, path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const ChainSpec& c = chain_spec(scene.value(), "girl", "bang_l1");
    ASSERT_EQ(c.keyed.size(), 2u);
    const KeyedSpec& added = c.keyed[1];
    EXPECT_EQ(added.example.kind, rods::KeyKind::Pose);
    EXPECT_NEAR(added.example.influence, glm::radians(20.0f), 1e-6f);
    // The look_down example keys the head too: one pose source for both.
    EXPECT_EQ(added.example.source_mask, c.keyed[0].example.source_mask);
    const std::uint32_t s = static_cast<std::uint32_t>(std::countr_zero(added.example.source_mask));
    EXPECT_LT(std::abs(std::abs(glm::dot(added.example.rotations[s], expected)) - 1.0f), 1e-5f);
    expect_same_shape(added.shape, k.shape);

    const RodScene written = rod_scene_of(edit.value().text, path);
    const Measured sim = simulate_keys(written, first_chain(written, "girl/bang_l1"), down);
    EXPECT_GT(sim.u[1], 1.0f - 1e-4f);

    auto undo = remove_last_sketch(edit.value().text, path, "girl/bang_l1");
    ASSERT_TRUE(undo.ok()) << undo.error().message;
    EXPECT_EQ(undo.value().text, text);
}

// Rigged characters key glTF nodes: crowd-gltf's tail with the hips' speed over 0.4 s,
// as its own "walk" example measures it (the same bits).
TEST(SketchKeyed, RiggedCharactersKeyTheirNodes) {
    const std::string path = scene_file("crowd-gltf.json");
    const RodScene rs = rod_scene_of(testing_support::file_bytes(path), path);
    const std::uint32_t chain = first_chain(rs, "chibi/tail");
    SketchKeyOptions o;
    o.joint = "hips";
    o.smoothing = 0.4f;
    const std::uint32_t frame = 150;
    auto key = measure_sketch_key(rs, rs.world.chains[chain].character, frame, o);
    ASSERT_TRUE(key.ok()) << key.error().message;
    const Measured sim = simulate_keys(rs, chain, frame);
    std::printf("[ measured ] crowd-gltf instance %u hips speed at frame %u: sketch %.6f m/s, simulation %.6f m/s\n",
                rs.world.chains[chain].character, frame, double(key.value().value), double(sim.state.smoothed[0].x));
    EXPECT_NEAR(key.value().value, sim.state.smoothed[0].x, 1e-6f * sim.state.smoothed[0].x);
    EXPECT_EQ(key.value().reference_joint, "head");

    o.kind = rods::KeyKind::Pose;
    auto pose = measure_sketch_key(rs, rs.world.chains[chain].character, frame, o);
    ASSERT_TRUE(pose.ok()) << pose.error().message;
    EXPECT_NEAR(glm::length(pose.value().rotation), 1.0f, 1e-5f);
}

// A chain without `keyed` gets the array, and an undo takes it away again; view and keyed
// sketches are numbered together, and undo takes them last first.
TEST(SketchKeyed, UndoTakesTheLastSketchViewOrKeyed) {
    const std::string path = scene_file("ahoge.json");
    // ahoge with 3 of its 5 view examples, so that three sketches stay within the 7.
    Json ahoge = Json::parse(testing_support::file_bytes(path));
    ahoge["characters"][0]["chains"][0]["views"].erase(4);
    ahoge["characters"][0]["chains"][0]["views"].erase(3);
    const std::string text = ahoge.dump(2) + "\n";
    const RodScene rs = rod_scene_of(text, path);
    const std::uint32_t chain = first_chain(rs, "girl/ahoge");
    const rods::ChainShape shape = sketched_shape(rs, chain, 0);
    ViewSpec view;
    view.view.direction = glm::normalize(glm::vec3(1.0f, 1.0f, 1.0f));
    view.view.influence = 4.0f;
    view.shape = shape;
    auto first = add_view_example(text, path, "girl/ahoge", view);
    ASSERT_TRUE(first.ok()) << first.error().message;
    KeyedSketch pose;
    pose.kind = rods::KeyKind::Pose;
    pose.joint = "head";
    pose.reference_joint = "head";
    pose.influence = 15.0f;
    pose.rotation = glm::angleAxis(0.3f, glm::vec3(1.0f, 0.0f, 0.0f));
    pose.shape = shape;
    auto second = add_keyed_example(first.value().text, path, "girl/ahoge", pose);
    ASSERT_TRUE(second.ok()) << second.error().message;
    EXPECT_EQ(second.value().name, "sketch 2");
    EXPECT_EQ(second.value().index, 0u);
    auto loaded = parse_scene(second.value().text, path);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message << "\n" << second.value().text;
    EXPECT_EQ(chain_spec(loaded.value(), "girl", "ahoge").keyed.size(), 1u);
    // A third, a view, is "sketch 3" (the numbers count over both arrays).
    view.view.direction = glm::normalize(glm::vec3(-1.0f, 1.0f, 1.0f));
    auto third = add_view_example(second.value().text, path, "girl/ahoge", view);
    ASSERT_TRUE(third.ok()) << third.error().message;
    EXPECT_EQ(third.value().name, "sketch 3");

    auto undo3 = remove_last_sketch(third.value().text, path, "girl/ahoge");
    ASSERT_TRUE(undo3.ok());
    EXPECT_FALSE(undo3.value().keyed);
    EXPECT_EQ(undo3.value().text, second.value().text);
    auto undo2 = remove_last_sketch(undo3.value().text, path, "girl/ahoge");
    ASSERT_TRUE(undo2.ok());
    EXPECT_TRUE(undo2.value().keyed);
    EXPECT_EQ(undo2.value().text, first.value().text);
    auto undo1 = remove_last_sketch(undo2.value().text, path, "girl/ahoge");
    ASSERT_TRUE(undo1.ok());
    EXPECT_EQ(undo1.value().text, text);  // byte for byte, the `keyed` member gone with its example
}

// K.1's limits: at most 4 keyed examples, 7 examples in all, 4 key sources; each refused
// naming the file, the chain's JSON path and the chain, with what was expected.
TEST(SketchKeyed, TheLimitsAreRefusedNamingTheChain) {
    const std::string path = scene_file("ahoge.json");
    const std::string text = testing_support::file_bytes(path);
    const RodScene rs = rod_scene_of(text, path);
    KeyedSketch k;
    k.kind = rods::KeyKind::Motion;
    k.joint = "head";
    k.reference_joint = "head";
    k.value = 1.0f;
    k.influence = 0.5f;
    k.shape = sketched_shape(rs, first_chain(rs, "girl/ahoge"), 0);
    // ahoge has 5 view examples: two keyed ones fill it.
    auto one = add_keyed_example(text, path, "girl/ahoge", k);
    ASSERT_TRUE(one.ok()) << one.error().message;
    auto two = add_keyed_example(one.value().text, path, "girl/ahoge", k);
    ASSERT_TRUE(two.ok()) << two.error().message;
    ASSERT_TRUE(parse_scene(two.value().text, path).ok());
    auto three = add_keyed_example(two.value().text, path, "girl/ahoge", k);
    ASSERT_FALSE(three.ok());
    EXPECT_NE(three.error().message.find(path + ": $.characters[0].chains[0].keyed: chain \"girl/ahoge\" already has 5 view "
                                                "examples and 2 keyed examples, the most a chain may have (7 in all)"),
              std::string::npos)
        << three.error().message;
    // And a view sketch counts the keyed ones too.
    ViewSpec view;
    view.view.direction = glm::normalize(glm::vec3(1.0f, 1.0f, 1.0f));
    view.shape = k.shape;
    auto full = add_view_example(two.value().text, path, "girl/ahoge", view);
    ASSERT_FALSE(full.ok());
    EXPECT_NE(full.error().message.find("already has 5 view examples and 2 keyed examples"), std::string::npos)
        << full.error().message;

    // Four keyed examples on a chain without views, then the fifth is refused.
    Json scene = Json::parse(text);
    scene["characters"][0]["chains"][0].erase("views");
    std::string t = scene.dump(2) + "\n";
    for (int i = 0; i < 4; ++i) {
        auto e = add_keyed_example(t, path, "girl/ahoge", k);
        ASSERT_TRUE(e.ok()) << e.error().message;
        t = e.value().text;
    }
    ASSERT_TRUE(parse_scene(t, path).ok());
    auto fifth = add_keyed_example(t, path, "girl/ahoge", k);
    ASSERT_FALSE(fifth.ok());
    EXPECT_NE(fifth.error().message.find(path + ": $.characters[0].chains[0].keyed: chain \"girl/ahoge\" already has 4 "
                                                "keyed examples, the most a chain may have (4)"),
              std::string::npos)
        << fifth.error().message;

    // Key sources: a hand-written pose example of three joints and a motion one of a
    // fourth fill the four; a motion key of the head would be a fifth.
    scene = Json::parse(text);
    scene["characters"][0]["chains"][0].erase("views");
    scene["characters"][0]["chains"][0]["keyed"] = Json::parse(R"([{"key": "pose", "pose": [
        {"joint": "head", "rotation": [0, 0, 0, 1]}, {"joint": "neck", "rotation": [0, 0, 0, 1]},
        {"joint": "body", "rotation": [0, 0, 0, 1]}]}])");
    scene["characters"][0]["chains"][0]["keyed"][0]["shape"] = scene["characters"][0]["chains"][0]["shape"];
    t = scene.dump(2) + "\n";
    {
        // ahoge.json's girl has a body, a neck and a head; a scene that lost one fails here.
        const auto loaded = parse_scene(t, path);
        ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    }
    KeyedSketch neck = k;
    neck.joint = "neck";
    auto fourth = add_keyed_example(t, path, "girl/ahoge", neck);
    ASSERT_TRUE(fourth.ok()) << fourth.error().message;
    ASSERT_TRUE(parse_scene(fourth.value().text, path).ok());
    auto over = add_keyed_example(fourth.value().text, path, "girl/ahoge", k);
    ASSERT_FALSE(over.ok());
    EXPECT_NE(over.error().message.find(path + ": $.characters[0].chains[0].keyed: chain \"girl/ahoge\": a motion key of "
                                               "joint \"head\" would make its keyed examples read 5 key sources; expected "
                                               "at most 4"),
              std::string::npos)
        << over.error().message;
    // A source they read already is fine.
    auto again = add_keyed_example(fourth.value().text, path, "girl/ahoge", neck);
    EXPECT_TRUE(again.ok()) << again.error().message;
}

// Bad keys: an unknown joint (the joints listed), a character standing still, a NaN or
// negative influence or smoothing, each refused naming what is wrong.
TEST(SketchKeyed, BadKeysAreRefused) {
    const std::string path = scene_file("ponytail.json");
    const RodScene rs = rod_scene_of(testing_support::file_bytes(path), path);
    const auto message = [&](const SketchKeyOptions& o, std::uint32_t frame) {
        auto r = measure_sketch_key(rs, 0, frame, o);
        return r.ok() ? std::string("ok") : r.error().message;
    };
    SketchKeyOptions o;
    o.joint = "tail";
    EXPECT_EQ(message(o, kSprintFrame).rfind("joint \"tail\": character \"runner\" has no such joint (joints: \"body\", "
                                             "\"neck\", \"head\")",
                                             0),
              0u)
        << message(o, kSprintFrame);
    o = {};
    EXPECT_NE(message(o, 0).find("character \"runner\" does not move at frame 0: its head's speed is 0 m/s"),
              std::string::npos)
        << message(o, 0);
    o.smoothing = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(message(o, kSprintFrame).rfind("smoothing: expected seconds in [0, 60]", 0), 0u) << message(o, kSprintFrame);
    o.smoothing = -1.0f;
    EXPECT_EQ(message(o, kSprintFrame).rfind("smoothing: ", 0), 0u);
    o = {};
    o.influence = -2.0f;
    EXPECT_EQ(message(o, kSprintFrame).rfind("influence: expected a number > 0 (m/s)", 0), 0u) << message(o, kSprintFrame);
    o.influence = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(message(o, kSprintFrame).rfind("influence: ", 0), 0u);
    o.kind = rods::KeyKind::Pose;
    EXPECT_EQ(message(o, kSprintFrame).rfind("influence: expected degrees in (0, 360]", 0), 0u) << message(o, kSprintFrame);

    // What the loader would not take back is refused before the text is touched.
    const std::string text = testing_support::file_bytes(path);
    KeyedSketch k;
    k.joint = "head";
    k.value = 1.0f;
    k.influence = std::numeric_limits<float>::quiet_NaN();
    k.shape = sketched_shape(rs, 0, kSprintFrame);
    auto bad = add_keyed_example(text, "p.json", "runner/ponytail", k);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("p.json: the keyed sketch for chain \"runner/ponytail\": influence: expected a number "
                                       "in (0, 10000]"),
              std::string::npos)
        << bad.error().message;
    k.influence = 1.0f;
    k.smoothing = 61.0f;
    bad = add_keyed_example(text, "p.json", "runner/ponytail", k);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("smoothing: expected a number in [0, 60] s, got 61"), std::string::npos)
        << bad.error().message;
}

}  // namespace kodawari
