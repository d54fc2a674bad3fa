// Keyed examples (docs/keyed-examples.md): the weights' properties (K.2-K.4), the checks of
// add_keyed_examples, the scene format's errors, and the two scenes that show the seed's
// wishes: a ponytail that streams in a sprint (motion) and bangs that fall over the eyes
// when she looks down (pose).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <kodawari/vulkan/backend_factory.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/keyed.hpp>
#include <kodawari/rods/world.hpp>

#include "character_support.hpp"

using namespace kodawari::testing_support::characters;

namespace {

rods::Transform at(glm::vec3 p, glm::quat q = glm::quat(1, 0, 0, 0)) { return rods::Transform{p, q}; }

rods::KeyedExample speed_key(float value, float influence, float smoothing = 0.0f) {
    rods::KeyedExample e;
    e.kind = rods::KeyKind::Motion;
    e.measure = rods::MotionMeasure::Speed;
    e.value = glm::vec3(value, 0, 0);
    e.influence = influence;
    e.smoothing = smoothing;
    e.saturation = value;
    return e;
}

// The weights of one frame in which the source moved `speed` m/s (from rest, unsmoothed).
rods::KeyedWeights weights_at_speed(std::span<const rods::KeyedExample> examples, float speed) {
    const rods::KeySourceKind kinds[] = {rods::KeySourceKind::Motion};
    const rods::Transform start[] = {at(glm::vec3(0.0f))};
    rods::KeyState state = rods::initial_key_state(start);
    const float dt = 0.1f;
    const rods::Transform now[] = {at(glm::vec3(0.0f, 0.0f, speed * dt))};
    return rods::keyed_weights(examples, kinds, now, dt, state);
}

}  // namespace

// K.2: at its key an example has weight 1, away from it exp(-(d/sigma)^2/2); a magnitude
// key reads a larger measure as the largest key (the sprint example keeps its shape in a
// faster sprint). Tolerance: float exp and the division by dt, a few ulp.
TEST(Keyed, MotionWeightIsAGaussianOfTheSpeedSaturatedAtTheLargestKey) {
    std::vector<rods::KeyedExample> e{speed_key(4.0f, 1.0f)};
    EXPECT_NEAR(weights_at_speed(e, 4.0f)[0], 1.0f, 1e-5f);
    EXPECT_NEAR(weights_at_speed(e, 3.0f)[0], std::exp(-0.5f), 1e-5f);
    EXPECT_NEAR(weights_at_speed(e, 2.0f)[0], std::exp(-2.0f), 1e-5f);
    EXPECT_LT(weights_at_speed(e, 0.0f)[0], 4e-4f);  // exp(-8)
    EXPECT_NEAR(weights_at_speed(e, 9.0f)[0], 1.0f, 1e-5f);  // saturated
}

// K.2's smoothing: a first-order low-pass filter, so a sudden speed reaches 1 - e^-1 of
// itself after one time constant whatever the frame rate, and one frame's spike moves
// the read key only by dt / tau of it.
TEST(Keyed, SmoothingIsAFirstOrderFilterIndependentOfTheFrameRate) {
    for (const float dt : {1.0f / 30.0f, 1.0f / 60.0f, 1.0f / 240.0f}) {
        rods::KeyedExample e = speed_key(1000.0f, 1000.0f, 0.5f);  // wide: the weight barely matters here
        e.saturation = 1000.0f;
        const rods::KeySourceKind kinds[] = {rods::KeySourceKind::Motion};
        rods::Transform source = at(glm::vec3(0.0f));
        rods::KeyState state = rods::initial_key_state(std::span<const rods::Transform>(&source, 1));
        const int frames = static_cast<int>(std::lround(0.5f / dt));
        for (int f = 0; f < frames; ++f) {
            source.position.z += 2.0f * dt;  // 2 m/s from t = 0
            (void)rods::keyed_weights(std::span<const rods::KeyedExample>(&e, 1), kinds,
                                      std::span<const rods::Transform>(&source, 1), dt, state);
        }
        // Tolerance: the sum of `frames` float steps, 1e-4 relative.
        EXPECT_NEAR(state.smoothed[0].x, 2.0f * (1.0f - std::exp(-1.0f)), 2e-4f) << "dt " << dt;
    }
}

// K.3: a pose key's distance is the angle between the measured and the key rotations.
TEST(Keyed, PoseWeightIsAGaussianOfTheAngleToTheKey) {
    rods::KeyedExample e;
    e.kind = rods::KeyKind::Pose;
    e.source_mask = 1;
    e.rotations[0] = glm::angleAxis(glm::radians(30.0f), glm::vec3(1, 0, 0));
    e.influence = glm::radians(10.0f);
    const rods::KeySourceKind kinds[] = {rods::KeySourceKind::Pose};
    rods::KeyState state;
    for (const float deg : {30.0f, 20.0f, 10.0f, 0.0f, -30.0f}) {
        const rods::Transform now[] = {at(glm::vec3(0.0f), glm::angleAxis(glm::radians(deg), glm::vec3(1, 0, 0)))};
        const float u = rods::keyed_weights(std::span<const rods::KeyedExample>(&e, 1), kinds, now, 1.0f / 60.0f, state)[0];
        const float off = (30.0f - deg) / 10.0f;
        // Tolerance: acos near 1 loses half the digits (1e-3 rad at 0), so 2e-3 absolute.
        EXPECT_NEAR(u, std::exp(-0.5f * off * off), 2e-3f) << deg << " degrees";
    }
}

// K.4's properties: no keyed weight gives the view weights bit for bit; the combined
// weights sum to 1 and lie in [0, 1]; a keyed weight of 1 takes the whole blend; the
// result is continuous where U crosses 1.
TEST(Keyed, CombinedWeightsKeepTheViewBlendAndSumToOne) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int trial = 0; trial < 2000; ++trial) {
        const std::size_t m = trial % 4;
        const std::size_t j = 1 + trial % 3;
        std::vector<float> view(m + 1);
        float rest = 1.0f;
        for (std::size_t k = 1; k <= m; ++k) {
            view[k] = rest * unit(rng);
            rest -= view[k];
        }
        view[0] = rest;
        std::vector<float> keyed(j);
        for (float& u : keyed) u = unit(rng) * (trial % 2 ? 1.0f : 0.3f);
        std::vector<float> out(m + 1 + j);
        rods::combine_weights(view, keyed, out);
        float sum = 0.0f;
        for (const float w : out) {
            EXPECT_GE(w, 0.0f);
            EXPECT_LE(w, 1.0f);
            sum += w;
        }
        EXPECT_NEAR(sum, 1.0f, 1e-5f);  // float sums of up to 8 terms
    }
    const std::vector<float> view{0.25f, 0.5f, 0.25f};
    std::vector<float> out(5);
    rods::combine_weights(view, std::vector<float>{0.0f, 0.0f}, out);
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(out[k], view[k]);
    rods::combine_weights(view, std::vector<float>{1.0f, 0.0f}, out);
    EXPECT_EQ(out[3], 1.0f);
    EXPECT_EQ(out[0] + out[1] + out[2], 0.0f);
    std::vector<float> below(5), above(5);
    rods::combine_weights(view, std::vector<float>{0.5f, 0.5f - 1e-6f}, below);
    rods::combine_weights(view, std::vector<float>{0.5f, 0.5f + 1e-6f}, above);
    for (std::size_t k = 0; k < 5; ++k) EXPECT_NEAR(below[k], above[k], 1e-5f);
}

// A chain without keyed examples blends exactly as before (the view weights untouched).
TEST(Keyed, ATemplateWithoutKeyedExamplesIsUnchanged) {
    Scene scene = load("scenes/bangs.json");
    const RodScene rs = build(scene);
    const rods::RodFrame frame = rs.frame(30);
    const rods::RestShape a = rods::rest_shape(rs.world, 0, frame);
    const rods::RestShape b = rods::rest_shape(rs.world, 0, frame, rods::KeyedWeights{0.7f, 0.2f, 0.0f, 0.0f});
    EXPECT_EQ(a.weights, b.weights);
    EXPECT_EQ(a.shape.positions, b.shape.positions);
}

// add_keyed_examples refuses what no backend could run, naming the chain and the example.
TEST(Keyed, BadKeyedExamplesAreRefused) {
    rods::ChainShape base;
    base.positions = {glm::vec3(0), glm::vec3(0, -0.1f, 0), glm::vec3(0, -0.2f, 0)};
    rods::default_orientations(base);
    auto t = rods::make_chain_template("tail", base, {}, {}, 0.01f, 0.01f, rods::SolverParams{});
    ASSERT_TRUE(t.ok());
    const rods::KeySourceKind motion[] = {rods::KeySourceKind::Motion};
    const rods::KeySourceKind pose[] = {rods::KeySourceKind::Pose};
    auto refused = [&](std::span<const rods::KeySourceKind> sources, rods::KeyedExample e, const std::string& part) {
        rods::ChainTemplate copy = t.value();
        const rods::ChainShape shapes[] = {base};
        auto r = rods::add_keyed_examples(copy, sources, shapes, std::span<const rods::KeyedExample>(&e, 1));
        ASSERT_FALSE(r.ok()) << part;
        EXPECT_TRUE(contains(r.error().message, "chain 'tail'")) << r.error().message;
        EXPECT_TRUE(contains(r.error().message, part)) << r.error().message;
    };
    rods::KeyedExample e = speed_key(3.0f, 1.0f);
    e.influence = std::nanf("");
    refused(motion, e, "influence must be > 0");
    e = speed_key(3.0f, -1.0f);
    refused(motion, e, "influence must be > 0");
    e = speed_key(3.0f, 1.0f, -0.1f);
    refused(motion, e, "smoothing");
    e = speed_key(3.0f, 1.0f);
    refused(pose, e, "source must be a motion key source");
    rods::KeyedExample p;
    p.kind = rods::KeyKind::Pose;
    p.source_mask = 1;
    p.rotations[0] = glm::quat(2, 0, 0, 0);
    refused(pose, p, "unit quaternions");
    p.rotations[0] = glm::quat(1, 0, 0, 0);
    refused(motion, p, "pose key sources");
    p.source_mask = 0;
    refused(pose, p, "at least one pose key source");
    // More examples than the limit.
    rods::ChainTemplate copy = t.value();
    std::vector<rods::KeyedExample> five(5, speed_key(1.0f, 1.0f));
    std::vector<rods::ChainShape> shapes(5, base);
    auto r = rods::add_keyed_examples(copy, motion, shapes, five);
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(contains(r.error().message, "at most 4 keyed examples")) << r.error().message;
}

// ---------------------------------------------------------------------------------------
// The scenes.

namespace {

// The ponytail tip in the head's frame, averaged over [from, to) s of scenes/ponytail.json.
glm::vec3 tip_in_head(const Scene& scene, float from, float to) {
    const RodScene rs = build(scene);
    Simulation sim(rs);
    const rods::Chain& chain = rs.world.templates[0].chain;
    glm::vec3 sum(0.0f);
    int n = 0;
    for (std::uint32_t f = 1; f < rs.frames && rs.time(f) < to; ++f) {
        sim.step(f);
        if (rs.time(f) < from) continue;
        const rods::Transform& head = sim.frame().reference[0];
        sum += glm::conjugate(head.rotation) * (sim.x(0, chain.joint_count - 1) - head.position);
        ++n;
    }
    return sum / static_cast<float>(n);
}

}  // namespace

// Issue 13's ponytail: in the sprint (5 to 6 s) the tip streams behind the head (its -Z)
// and rises; standing (8.5 to 9.5 s) it hangs as the base shape does. Bounds (the strand
// is 0.32 m): sprinting, the tip is at least 0.1 m further behind and 0.1 m higher than in
// the base-shape-only run; standing, the two runs are within 2 cm.
TEST(KeyedScenes, PonytailStreamsInTheSprintAndHangsAtRest) {
    Scene scene = load("scenes/ponytail.json");
    ASSERT_EQ(scene.characters[0].chains[0].keyed.size(), 1u);
    const glm::vec3 sprint = tip_in_head(scene, 5.0f, 6.0f);
    const glm::vec3 rest = tip_in_head(scene, 8.5f, 9.5f);
    for (kodawari::ChainSpec& chain : scene.characters[0].chains) {
        chain.keyed.clear();
        chain.key_sources.clear();
    }
    const glm::vec3 sprint_base = tip_in_head(scene, 5.0f, 6.0f);
    const glm::vec3 rest_base = tip_in_head(scene, 8.5f, 9.5f);
    std::printf("[ measured ] ponytail tip in the head frame (m): sprint (%.3f, %.3f, %.3f), base only (%.3f, %.3f, %.3f); "
                "standing (%.3f, %.3f, %.3f), base only (%.3f, %.3f, %.3f)\n",
                double(sprint.x), double(sprint.y), double(sprint.z), double(sprint_base.x), double(sprint_base.y),
                double(sprint_base.z), double(rest.x), double(rest.y), double(rest.z), double(rest_base.x),
                double(rest_base.y), double(rest_base.z));
    EXPECT_LE(sprint.z, sprint_base.z - 0.1f);
    EXPECT_GE(sprint.y, sprint_base.y + 0.1f);
    EXPECT_LE(glm::length(rest - rest_base), 0.02f);
}

namespace {

// Seen from the scene's camera, the smallest on-screen distance from either eye to any
// bang (in head radii) while the head is held looking down (pitch > 25 degrees) and
// while it is held looking up (< -25 degrees), over the first 8 s of scenes/nod.json.
struct Coverage {
    float down = 1e9f, up = 1e9f;
};
Coverage eye_coverage(const Scene& scene) {
    const RodScene rs = build(scene);
    Simulation sim(rs);
    Coverage out;
    for (std::uint32_t f = 1; f < rs.frames && rs.time(f) < 9.0f; ++f) {
        sim.step(f);
        // The head's pitch against the neck (joints body, neck, head): the pose key's measure.
        const std::vector<rods::Transform> joints = rs.joint_poses(0, f);
        const glm::quat relative = glm::conjugate(joints[1].rotation) * joints[2].rotation;
        const float pitch = glm::degrees(2.0f * std::atan2(relative.x, relative.w));
        if (std::abs(pitch) < 25.0f) continue;
        float& worst = pitch > 0.0f ? out.down : out.up;
        worst = std::min(worst, eye_to_strands(rs, sim, Projector(rs.camera_pose(f), rs.fov_deg)));
    }
    return out;
}

}  // namespace

// Issue 13's nod: looking down, the pose example lays the bangs over the eyes (a strand
// within 0.1 head radii of an eye on screen); looking up, the front view example parts
// them (every strand at least 0.2 head radii off both eyes). Without the pose example the
// view example keeps them parted looking down too (at least 0.2): the pose made the
// difference, not the camera.
TEST(KeyedScenes, BangsFallOverTheEyesLookingDownAndPartLookingUp) {
    Scene scene = load("scenes/nod.json");
    const Coverage with = eye_coverage(scene);
    for (kodawari::ChainSpec& chain : scene.characters[0].chains) chain.keyed.clear();
    const Coverage without = eye_coverage(scene);
    std::printf("[ measured ] eye clearance (head radii): looking down %.3f with the pose example, %.3f without; "
                "looking up %.3f with, %.3f without\n",
                double(with.down), double(without.down), double(with.up), double(without.up));
    EXPECT_LE(with.down, 0.1f);
    EXPECT_GE(without.down, 0.2f);
    EXPECT_GE(with.up, 0.2f);
}

// Issue 13's rigged crowd: scenes/crowd-gltf.json's tail has a motion example keyed by the
// hips' speed (smoothed over 0.4 s). The walk clip bobs the hips at about 0.06 m/s and
// more; idle and turn move them at 0.03 m/s at most. After 2 s every walker's tail has
// the example at weight above 0.8 and every other instance's below 0.2 (measured: 1.0 and
// under 0.05), on the cpu backend (the same bits as cpu-reference, validate checks that).
TEST(KeyedScenes, TheRiggedCrowdsWalkRaisesItsTails) {
    const Scene scene = load("scenes/crowd-gltf.json");
    const RodScene rs = build(scene);
    auto made = kodawari::make_rod_backend(kodawari::BackendKind::Cpu, kodawari::BackendOptions{});
    ASSERT_TRUE(made.ok());
    kodawari::RodBackend& backend = *made.value();
    rods::RodFrame frame;
    rs.frame(0, frame);
    ASSERT_TRUE(backend.load(rs.world, frame).ok());
    const std::uint32_t frames = static_cast<std::uint32_t>(2.5f * rs.fps);
    std::vector<float> lowest(rs.instances.size(), 1.0f), highest(rs.instances.size(), 0.0f);
    kodawari::ChainSnapshot snap;
    for (std::uint32_t f = 1; f < frames; ++f) {
        rs.frame(f, frame);
        ASSERT_TRUE(backend.step(frame).ok());
        if (rs.time(f) < 2.0f) continue;
        ASSERT_TRUE(backend.read(snap).ok());
        for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
            const rods::ChainTemplate& t = rs.world.templ(rs.world.chains[c]);
            if (t.keyed.empty()) continue;
            const float w = snap.weights[c * (rods::kMaxViewExamples + 1) + t.views.size() + 1];
            const std::uint32_t i = rs.world.chains[c].character;
            lowest[i] = std::min(lowest[i], w);
            highest[i] = std::max(highest[i], w);
        }
    }
    const auto& clips = rs.characters[0].rig->animations;
    int walkers = 0;
    for (std::size_t i = 0; i < rs.instances.size(); ++i) {
        const bool walks = clips[static_cast<std::size_t>(rs.instances[i].clip)].name == "walk";
        walkers += walks;
        if (walks) {
            EXPECT_GT(lowest[i], 0.8f) << rs.character_names[i];
        } else {
            EXPECT_LT(highest[i], 0.2f) << rs.character_names[i] << " plays " << clips[static_cast<std::size_t>(rs.instances[i].clip)].name;
        }
    }
    std::printf("[ measured ] %d walkers of %zu instances\n", walkers, rs.instances.size());
    EXPECT_GT(walkers, 0);
}

namespace {

json keyed_scene(const json& keyed) {
    json doc = valid_character_scene();
    doc["characters"][0]["chains"][0]["keyed"] = keyed;
    return doc;
}

const json kSprint = json::parse(R"({"name": "sprint", "key": "motion", "value": 3, "influence": 1,
                                      "shape": {"arc": {"joints": 8, "length": 0.2, "curl_deg": -40}}})");

}  // namespace

// The scene format's keyed examples: a motion and a pose key load into the template with
// their key sources; the mirrored chain gets mirrored pose keys.
TEST(KeyedScenes, TheSceneFormatReadsMotionAndPoseKeys) {
    json pose = kSprint;
    pose.erase("value");
    pose["key"] = "pose";
    pose["pose"] = json::parse(R"([{"joint": "head", "axis": [0, 1, 0], "angle_deg": 30}])");
    pose["influence"] = 15;
    const auto loaded = kodawari::parse_scene(keyed_scene(json::array({kSprint, pose})).dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const RodScene rs = build(loaded.value());
    const rods::ChainTemplate& t = rs.world.templates[0];
    ASSERT_EQ(t.keyed.size(), 2u);
    ASSERT_EQ(t.key_sources.size(), 2u);
    EXPECT_EQ(t.shapes.size(), 1u + t.views.size() + 2u);
    EXPECT_EQ(t.keyed[0].value.x, 3.0f);
    EXPECT_EQ(t.keyed[0].smoothing, 0.25f);  // the documented default
    EXPECT_NEAR(t.keyed[1].influence, glm::radians(15.0f), 1e-7f);
    // The head turned 30 degrees about its own +Y; the mirror chain's key turns the other way.
    const glm::quat key = t.keyed[1].rotations[1];
    EXPECT_NEAR(glm::degrees(glm::angle(key)), 30.0f, 1e-3f);
    const glm::quat mirrored = rs.world.templates[1].keyed[1].rotations[1];
    EXPECT_NEAR(glm::dot(glm::axis(key), glm::axis(mirrored)), -1.0f, 1e-5f);
    EXPECT_EQ(rs.world.key_count, 4u);  // 2 sources x 2 chains
    EXPECT_TRUE(rods::check_frame(rs.world, rs.frame(0)).ok());
}

// Bad keyed examples name the file, the JSON path and what was expected.
TEST(KeyedScenes, BadKeyedExamplesNameThePathAndWhatWasExpected) {
    struct Case {
        json keyed;
        std::string path, part;
    };
    auto with = [](const char* key, json value) {
        json k = kSprint;
        if (value.is_null()) {
            k.erase(key);
        } else {
            k[key] = std::move(value);
        }
        return json::array({k});
    };
    json pose = kSprint;
    pose.erase("value");
    pose["key"] = "pose";
    pose["pose"] = json::parse(R"([{"joint": "tail", "axis": [1, 0, 0], "angle_deg": 10}])");
    const std::vector<Case> cases = {
        {with("key", "wiggle"), "keyed[0].key", "a key kind (\"motion\", \"pose\")"},
        {with("influence", -1), "keyed[0].influence", ""},
        {with("influence", 0), "keyed[0].influence", ""},
        {with("smoothing", -0.5), "keyed[0].smoothing", ""},
        {with("smoothing", 1000), "keyed[0].smoothing", ""},
        {with("measure", "jerk"), "keyed[0].measure", "a motion measure"},
        {with("joint", "tail"), "keyed[0].joint", "the name of a joint"},
        {with("value", nullptr), "keyed[0].value", ""},
        {json::array({pose}), "keyed[0].pose[0].joint", "the name of a joint"},
        {json::array({kSprint, kSprint, kSprint, kSprint, kSprint}), "keyed", "at most"},
    };
    for (const Case& c : cases) {
        const auto loaded = kodawari::parse_scene(keyed_scene(c.keyed).dump(), "test.json");
        ASSERT_FALSE(loaded.ok()) << c.keyed.dump();
        const std::string& m = loaded.error().message;
        EXPECT_TRUE(contains(m, "test.json")) << m;
        EXPECT_TRUE(contains(m, c.path)) << m;
        EXPECT_TRUE(contains(m, c.part)) << m;
    }
}

namespace {

// The peak over [from, to) s of the ponytail's kinetic energy relative to its root (J per
// kg of each joint): the solver's velocities (ChainState::v, which A.5 keeps the rest
// shape's change out of) less the root joint's, squared, halved, summed.
float peak_relative_energy(const Scene& scene, float from, float to) {
    const RodScene rs = build(scene);
    Simulation sim(rs);
    const std::uint32_t n = rs.world.templates[0].chain.joint_count;
    float peak = 0.0f;
    for (std::uint32_t f = 1; f < rs.frames && rs.time(f) < to; ++f) {
        sim.step(f);
        if (rs.time(f) < from) continue;
        const rods::ChainState& s = sim.state(0);
        float energy = 0.0f;
        for (std::uint32_t i = 1; i < n; ++i) {
            const glm::vec3 v = s.v[i] - s.v[0];
            energy += 0.5f * glm::dot(v, v);
        }
        peak = std::max(peak, energy);
    }
    return peak;
}

}  // namespace

// K.5: momentum suppression (SPEC A.5) covers a rest shape changed by a keyed example as
// it covers one changed by the view. The sprint example with a narrow influence (0.05
// m/s) and no smoothing switches on within a few frames as the speed passes 6 m/s; the
// peak kinetic energy of the ponytail relative to the head while it switches is at most
// a quarter with suppression on of what it is with suppression off (SPEC A.5's bound for
// an instant switch of rest shape).
TEST(KeyedScenes, ASuddenSprintDoesNotKickTheStrand) {
    Scene scene = load("scenes/ponytail.json");
    rods::KeyedExample& sprint = scene.characters[0].chains[0].keyed[0].example;
    sprint.influence = 0.05f;
    sprint.smoothing = 0.0f;
    scene.characters[0].chains[0].params.momentum_suppression = 1.0f;
    const float on = peak_relative_energy(scene, 3.0f, 5.0f);
    scene.characters[0].chains[0].params.momentum_suppression = 0.0f;
    const float off = peak_relative_energy(scene, 3.0f, 5.0f);
    std::printf("[ measured ] peak kinetic energy relative to the root while the sprint example switches on: %.4f J/kg "
                "with suppression, %.4f without\n", double(on), double(off));
    EXPECT_LE(on, 0.25f * off);
}
