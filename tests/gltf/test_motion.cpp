// Animation from elsewhere (issue 18): VRM Animation import and humanoid retargeting
// (gltf/motion.hpp), checked on skeletons built here whose rest frames differ: a source
// in T-pose with identity rotations, targets whose every bone has its own rest rotation,
// a VRM 0.x target facing -Z, and a non-VRM skeleton through name maps. Expected values
// come from the definitions (docs/motions.md): a bone's world direction turns by the
// source bone's world delta, the hips move by the source's displacement times the
// leg-height ratio; they are computed here from the skeletons' world positions, not
// from the code under test.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "gltf/gltf_import_support.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/gltf/motion.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari {
namespace {

using gltf_import_test::Builder;
using gltf_import_test::write_text;
using nlohmann::json;
using testing_support::TempDir;

// Tolerances: positions are sums of a few float products of metre-sized values, and
// directions 0.25 m long; 1e-5 m is about 50 float ulps of 1 m.
constexpr float kPositionTol = 1e-5f;

glm::quat about(float degrees, glm::vec3 axis) { return glm::angleAxis(glm::radians(degrees), glm::normalize(axis)); }

// One joint of a test skeleton, given in world terms: its T-pose position (+Y up,
// facing +Z, +X the character's left) and its world rest rotation.
struct Joint {
    std::string name;
    std::string bone;  // the VRM humanoid bone, "" for none
    int parent = -1;
    glm::vec3 position{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
};

// A humanoid with every required bone, chest, neck, left toes and a 3-joint hair strand
// under the head, `height` times the size of a 1.6 m figure. `rested`: every joint gets
// a rest rotation of its own (as a VRM 1.0 avatar may); `minus_z`: the model faces -Z
// (VRM 0.x); `prefix`: node names are prefix + bone name ("mixamorig:hips").
std::vector<Joint> humanoid(float height, bool rested, bool minus_z, const std::string& prefix = "") {
    std::vector<Joint> j = {
        {"root", "", -1, {0, 0, 0}},
        {"hips", "hips", 0, {0, 1.0f, 0}},
        {"spine", "spine", 1, {0, 1.2f, 0}},
        {"chest", "chest", 2, {0, 1.35f, 0}},
        {"neck", "neck", 3, {0, 1.5f, 0}},
        {"head", "head", 4, {0, 1.6f, 0}},
        {"hair_0", "", 5, {0, 1.75f, -0.05f}},
        {"hair_1", "", 6, {0, 1.65f, -0.12f}},
        {"hair_2", "", 7, {0, 1.55f, -0.15f}},
        {"leftUpperArm", "leftUpperArm", 3, {0.2f, 1.45f, 0}},
        {"leftLowerArm", "leftLowerArm", 9, {0.45f, 1.45f, 0}},
        {"leftHand", "leftHand", 10, {0.7f, 1.45f, 0}},
        {"rightUpperArm", "rightUpperArm", 3, {-0.2f, 1.45f, 0}},
        {"rightLowerArm", "rightLowerArm", 12, {-0.45f, 1.45f, 0}},
        {"rightHand", "rightHand", 13, {-0.7f, 1.45f, 0}},
        {"leftUpperLeg", "leftUpperLeg", 1, {0.1f, 0.95f, 0}},
        {"leftLowerLeg", "leftLowerLeg", 15, {0.1f, 0.5f, 0}},
        {"leftFoot", "leftFoot", 16, {0.1f, 0.08f, 0}},
        {"rightUpperLeg", "rightUpperLeg", 1, {-0.1f, 0.95f, 0}},
        {"rightLowerLeg", "rightLowerLeg", 18, {-0.1f, 0.5f, 0}},
        {"rightFoot", "rightFoot", 19, {-0.1f, 0.08f, 0}},
        {"leftToes", "leftToes", 17, {0.1f, 0.02f, 0.1f}},
    };
    for (std::size_t i = 0; i < j.size(); ++i) {
        j[i].position *= height / 1.6f;
        if (minus_z) j[i].position = {-j[i].position.x, j[i].position.y, -j[i].position.z};
        if (rested) {
            const float k = static_cast<float>(i);
            j[i].rotation = about(20.0f + 13.0f * k, {1.0f, 2.0f + std::fmod(k, 3.0f), k - 7.0f});
        }
        if (!prefix.empty() && !j[i].bone.empty()) j[i].name = prefix + j[i].bone;
    }
    return j;
}

int index_of(const std::vector<Joint>& joints, const std::string& bone) {
    for (std::size_t i = 0; i < joints.size(); ++i) {
        if (joints[i].bone == bone) return static_cast<int>(i);
    }
    return -1;
}

// The rest local TRS of joint i, from the world terms.
glm::quat local_rotation(const std::vector<Joint>& j, std::size_t i) {
    return j[i].parent < 0 ? j[i].rotation : glm::inverse(j[static_cast<std::size_t>(j[i].parent)].rotation) * j[i].rotation;
}
glm::vec3 local_translation(const std::vector<Joint>& j, std::size_t i) {
    if (j[i].parent < 0) return j[i].position;
    const Joint& p = j[static_cast<std::size_t>(j[i].parent)];
    return glm::inverse(p.rotation) * (j[i].position - p.position);
}

// A keyed property of one joint for a clip.
struct Track {
    std::string bone;
    std::string path;  // "rotation" or "translation"
    std::vector<float> times;
    std::vector<glm::vec4> values;  // xyzw, or xyz
};

// What kind of humanoid the file declares.
enum class Declares { Vrma, Vrm1, Vrm0, Nothing };

struct Doc {
    Builder b;
    json extensions = json::object();
};

Doc skeleton_doc(const std::vector<Joint>& joints, Declares declares, const std::vector<std::string>& leave_out = {}) {
    Doc d;
    json nodes = json::array();
    for (std::size_t i = 0; i < joints.size(); ++i) {
        const glm::quat q = local_rotation(joints, i);
        const glm::vec3 t = local_translation(joints, i);
        json n = {{"name", joints[i].name}, {"translation", {t.x, t.y, t.z}}, {"rotation", {q.x, q.y, q.z, q.w}}};
        json children = json::array();
        for (std::size_t c = 0; c < joints.size(); ++c) {
            if (joints[c].parent == static_cast<int>(i)) children.push_back(c);
        }
        if (!children.empty()) n["children"] = children;
        nodes.push_back(n);
    }
    d.b.doc["nodes"] = nodes;
    d.b.doc["scene"] = 0;
    d.b.doc["scenes"] = json::array({{{"nodes", {0}}}});
    json bones1 = json::object();
    json bones0 = json::array();
    for (std::size_t i = 0; i < joints.size(); ++i) {
        const std::string& bone = joints[i].bone;
        if (bone.empty() || std::find(leave_out.begin(), leave_out.end(), bone) != leave_out.end()) continue;
        bones1[bone] = {{"node", i}};
        bones0.push_back({{"bone", bone}, {"node", i}});
    }
    switch (declares) {
        case Declares::Vrma:
            d.extensions["VRMC_vrm_animation"] = {{"specVersion", "1.0"}, {"humanoid", {{"humanBones", bones1}}}};
            break;
        case Declares::Vrm1: d.extensions["VRMC_vrm"] = {{"specVersion", "1.0"}, {"humanoid", {{"humanBones", bones1}}}}; break;
        case Declares::Vrm0: d.extensions["VRM"] = {{"humanoid", {{"humanBones", bones0}}}}; break;
        case Declares::Nothing: break;
    }
    return d;
}

void add_clip(Doc& d, const std::vector<Joint>& joints, const std::string& name, const std::vector<Track>& tracks) {
    json samplers = json::array();
    json channels = json::array();
    for (const Track& t : tracks) {
        const int node = index_of(joints, t.bone);
        ASSERT_GE(node, 0) << t.bone;
        std::vector<float> flat;
        for (const glm::vec4& v : t.values) {
            for (int c = 0; c < (t.path == "rotation" ? 4 : 3); ++c) flat.push_back(v[c]);
        }
        const int input = d.b.add(t.times, "SCALAR");
        const int output = d.b.add(flat, t.path == "rotation" ? "VEC4" : "VEC3");
        channels.push_back({{"sampler", samplers.size()}, {"target", {{"node", node}, {"path", t.path}}}});
        samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
    }
    if (!d.b.doc.contains("animations")) d.b.doc["animations"] = json::array();
    d.b.doc["animations"].push_back({{"name", name}, {"samplers", samplers}, {"channels", channels}});
}

std::string write_doc(const TempDir& dir, const std::string& file, const Doc& d) {
    json doc = d.b.gltf();
    if (d.b.bytes.empty()) {  // no clip: no buffer (an empty data URI does not decode)
        for (const char* key : {"buffers", "bufferViews", "accessors"}) doc.erase(key);
    }
    if (!d.extensions.empty()) {
        doc["extensions"] = d.extensions;
        json used = json::array();
        for (const auto& [key, value] : d.extensions.items()) used.push_back(key);
        doc["extensionsUsed"] = used;
    }
    const std::string path = dir.file(file);
    write_text(path, doc.dump());
    return path;
}

glm::vec4 xyzw(glm::quat q) { return {q.x, q.y, q.z, q.w}; }

// The source clip of the checks: the hips move by (0.1, -0.1, 0.3) m at t = 1 and back
// at t = 2; the left upper arm turns 45 degrees about world Z at t = 1 (its rest frame is
// the world's: the rotation is the same in local terms); the spine turns 30 degrees about
// +Y at t = 2.
std::vector<Track> walk_tracks(const std::vector<Joint>& j) {
    const glm::vec3 hips = local_translation(j, static_cast<std::size_t>(index_of(j, "hips")));
    const glm::quat id(1.0f, 0.0f, 0.0f, 0.0f);
    return {
        {"hips", "translation", {0, 1, 2}, {glm::vec4(hips, 0), glm::vec4(hips + glm::vec3(0.1f, -0.1f, 0.3f), 0), glm::vec4(hips, 0)}},
        {"leftUpperArm", "rotation", {0, 1, 2}, {xyzw(id), xyzw(about(45, {0, 0, 1})), xyzw(about(45, {0, 0, 1}))}},
        {"spine", "rotation", {0, 1, 2}, {xyzw(id), xyzw(id), xyzw(about(30, {0, 1, 0}))}},
    };
}

animation::Character load(const std::string& path) {
    auto c = gltf::load_character(path);
    EXPECT_TRUE(c.ok()) << (c.ok() ? "" : c.error().message);
    return c.ok() ? std::move(c).value() : animation::Character{};
}

gltf::Retargeted motion_ok(const gltf::MotionRequest& request, const animation::Character& target) {
    auto m = gltf::load_motion(request, target);
    EXPECT_TRUE(m.ok()) << (m.ok() ? "" : m.error().message);
    return m.ok() ? std::move(m).value() : gltf::Retargeted{};
}

// The target with the retargeted clip appended, posed at `time`.
animation::Pose pose_at(animation::Character target, const animation::Animation& clip, float time) {
    target.animations.push_back(clip);
    animation::Pose pose;
    animation::evaluate(target, target.animations.size() - 1, time, pose);
    return pose;
}

glm::vec3 world_position(const animation::Pose& pose, int node) { return glm::vec3(pose.world[static_cast<std::size_t>(node)][3]); }

// The upper arm's bone: from the upper arm's joint to the lower arm's, in world space.
glm::vec3 arm_direction(const animation::Pose& pose, const std::vector<Joint>& j, const std::string& side = "left") {
    return world_position(pose, index_of(j, side + "LowerArm")) - world_position(pose, index_of(j, side + "UpperArm"));
}

void expect_near(glm::vec3 a, glm::vec3 b, float tol, const std::string& what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}

// The leg heights of the test skeletons: hips above the feet.
float leg(float height) { return (1.0f - 0.08f) * height / 1.6f; }

struct Files {
    TempDir dir;
    std::vector<Joint> source = humanoid(1.6f, false, false);
    std::vector<Joint> target = humanoid(1.28f, true, false);  // 0.8 times as tall, every rest rotation its own
    std::string vrma;
    std::string avatar;

    Files() {
        Doc s = skeleton_doc(source, Declares::Vrma);
        add_clip(s, source, "walk", walk_tracks(source));
        vrma = write_doc(dir, "walk.vrma", s);
        avatar = write_doc(dir, "avatar.gltf", skeleton_doc(target, Declares::Vrm1));
    }
};

TEST(Motion, VrmaRetargetsOntoAvatarWithOtherRestFrames) {
    Files f;
    const animation::Character target = load(f.avatar);
    const gltf::Retargeted m = motion_ok({"walk", f.vrma, "", "", ""}, target);
    ASSERT_FALSE(m.animation.channels.empty());
    EXPECT_EQ(m.animation.name, "walk");
    EXPECT_FLOAT_EQ(m.animation.start, 0.0f);
    EXPECT_FLOAT_EQ(m.animation.end, 2.0f);
    // Keys at the source's keys, gaps split to at most 1/30 s: 0, 1/30, ..., 2.
    EXPECT_EQ(m.keys, 61u);
    EXPECT_NEAR(m.leg_ratio, leg(1.28f) / leg(1.6f), 1e-6f);
    for (const animation::Sampler& s : m.animation.samplers) {
        EXPECT_EQ(s.interpolation, animation::Interpolation::Linear);
        EXPECT_EQ(s.times.size(), m.keys);
    }
    // Only humanoid bones are animated: the hair strand and the root keep their rest pose.
    for (const animation::Channel& c : m.animation.channels) {
        EXPECT_FALSE(f.target[static_cast<std::size_t>(c.node)].bone.empty()) << f.target[static_cast<std::size_t>(c.node)].name;
    }

    const animation::Pose rest = animation::rest_pose(target);
    const glm::vec3 arm0 = arm_direction(rest, f.target);
    // t = 1: the upper arm's bone has turned by exactly 45 degrees about +Z.
    const animation::Pose p1 = pose_at(target, m.animation, 1.0f);
    const glm::vec3 arm1 = arm_direction(p1, f.target);
    expect_near(arm1, about(45, {0, 0, 1}) * arm0, kPositionTol, "upper arm at t = 1");
    EXPECT_NEAR(glm::degrees(std::acos(glm::dot(glm::normalize(arm0), glm::normalize(arm1)))), 45.0f, 1e-3f);
    EXPECT_GT(glm::cross(arm0, arm1).z, 0.0f);  // about +Z, counter-clockwise: the arm rises
    // ... and its child follows: the forearm turned with it.
    const int lower = index_of(f.target, "leftLowerArm");
    const int hand = index_of(f.target, "leftHand");
    expect_near(world_position(p1, hand) - world_position(p1, lower),
                about(45, {0, 0, 1}) * (world_position(rest, hand) - world_position(rest, lower)), kPositionTol, "forearm");
    // The other arm did not move relative to the hips.
    const int hips = index_of(f.target, "hips");
    expect_near(arm_direction(p1, f.target, "right"), arm_direction(rest, f.target, "right"), kPositionTol, "right arm");
    // The hips moved by the source's displacement times the leg ratio.
    const float k = leg(1.28f) / leg(1.6f);
    expect_near(world_position(p1, hips) - world_position(rest, hips), k * glm::vec3(0.1f, -0.1f, 0.3f), kPositionTol,
                "hips at t = 1");
    // t = 0.5, between keys: 22.5 degrees.
    const glm::vec3 arm_half = arm_direction(pose_at(target, m.animation, 0.5f), f.target);
    expect_near(arm_half, about(22.5f, {0, 0, 1}) * arm0, kPositionTol, "upper arm at t = 0.5");
    // t = 2: the spine's 30 degrees about +Y carry the arm (still raised 45 degrees) with it.
    const animation::Pose p2 = pose_at(target, m.animation, 2.0f);
    expect_near(arm_direction(p2, f.target), about(30, {0, 1, 0}) * about(45, {0, 0, 1}) * arm0, kPositionTol, "upper arm at t = 2");
    expect_near(world_position(p2, hips), world_position(rest, hips), kPositionTol, "hips back at t = 2");
    // The hair strand stays at rest relative to the head.
    const int head = index_of(f.target, "head");
    const int hair = static_cast<int>(std::find_if(f.target.begin(), f.target.end(), [](const Joint& j) { return j.name == "hair_2"; }) -
                                      f.target.begin());
    const glm::mat4 hair_in_head_rest = glm::inverse(rest.world[static_cast<std::size_t>(head)]) * rest.world[static_cast<std::size_t>(hair)];
    const glm::mat4 hair_in_head = glm::inverse(p2.world[static_cast<std::size_t>(head)]) * p2.world[static_cast<std::size_t>(hair)];
    expect_near(glm::vec3(hair_in_head[3]), glm::vec3(hair_in_head_rest[3]), kPositionTol, "hair in the head's frame");
}

// The local rotation the code writes is VRMC_vrm_animation's formula (how_to_transform_
// human_pose): q_tgt = P_tgt^-1 (P_src q_src W_src^-1) P_tgt L_tgt, with P the parent's
// world rest rotation, W the bone's, L its local rest rotation.
TEST(Motion, LocalRotationIsTheSpecFormula) {
    Files f;
    const animation::Character target = load(f.avatar);
    const gltf::Retargeted m = motion_ok({"walk", f.vrma, "", "", ""}, target);
    const int arm = index_of(f.target, "leftUpperArm");
    const auto channel = std::find_if(m.animation.channels.begin(), m.animation.channels.end(), [&](const animation::Channel& c) {
        return c.node == arm && c.path == animation::Path::Rotation;
    });
    ASSERT_NE(channel, m.animation.channels.end());
    const glm::vec4 v = animation::sample(m.animation.samplers[channel->sampler], animation::Path::Rotation, 1.0f);
    const glm::quat written(v.w, v.x, v.y, v.z);
    // The source's rests are identity: P_src = W_src = 1, so D = q_src = Rz(45).
    const glm::quat d = about(45, {0, 0, 1});
    const std::size_t a = static_cast<std::size_t>(arm);
    const glm::quat p_tgt = f.target[static_cast<std::size_t>(f.target[a].parent)].rotation;
    const glm::quat expected = glm::inverse(p_tgt) * d * p_tgt * local_rotation(f.target, a);
    // The angle between the two rotations, 2 asin |vector part of written^-1 expected|
    // (acos of a dot near 1 would lose half the digits): 1e-5 rad is float rounding of the
    // few products above (a few 1e-7 each); a wrong order of the products is off by tens
    // of degrees. (|dot| within 1e-6 of 1, the bound before, allowed 2.8 mrad.)
    const glm::quat delta = glm::conjugate(written) * expected;
    const float angle = 2.0f * std::asin(std::min(1.0f, glm::length(glm::vec3(delta.x, delta.y, delta.z))));
    EXPECT_LT(angle, 1e-5f) << "rad";
}

TEST(Motion, Vrm0TargetFacingMinusZ) {
    Files f;
    const std::vector<Joint> vrm0 = humanoid(1.28f, false, true);
    const animation::Character target = load(write_doc(f.dir, "avatar0.gltf", skeleton_doc(vrm0, Declares::Vrm0)));
    const gltf::Retargeted m = motion_ok({"walk", f.vrma, "", "", ""}, target);
    const animation::Pose rest = animation::rest_pose(target);
    const glm::vec3 arm0 = arm_direction(rest, vrm0);
    ASSERT_LT(arm0.x, 0.0f);  // facing -Z, the character's left is -X
    const animation::Pose p1 = pose_at(target, m.animation, 1.0f);
    // The motion is turned half round +Y with the model: 45 degrees about -Z, and the arm rises.
    const glm::vec3 arm1 = arm_direction(p1, vrm0);
    expect_near(arm1, about(-45, {0, 0, 1}) * arm0, kPositionTol, "upper arm at t = 1");
    EXPECT_GT(arm1.y, arm0.y + 0.1f);
    const int hips = index_of(vrm0, "hips");
    const float k = leg(1.28f) / leg(1.6f);
    expect_near(world_position(p1, hips) - world_position(rest, hips), k * glm::vec3(-0.1f, -0.1f, -0.3f), kPositionTol,
                "hips at t = 1 (forward is -Z)");
}

// A non-VRM source and a non-VRM target through name maps; the source's rest frames are
// not the world's either, and its clip is not its first.
TEST(Motion, NameMapsOnBothSides) {
    TempDir dir;
    const std::vector<Joint> source = humanoid(1.6f, true, false, "mixamorig:");
    const std::vector<Joint> target = humanoid(1.28f, true, false, "Bone_");
    Doc s = skeleton_doc(source, Declares::Nothing);
    add_clip(s, source, "Idle", {{"hips", "rotation", {0}, {xyzw(local_rotation(source, 1))}}});
    // The left upper arm's local rotations that turn it 45 degrees about world Z while its
    // parent rests: q = P^-1 Rz(45) P L.
    const auto arm = static_cast<std::size_t>(index_of(source, "leftUpperArm"));
    const glm::quat p = source[static_cast<std::size_t>(source[arm].parent)].rotation;
    const glm::quat l = local_rotation(source, arm);
    std::vector<Track> run = {{"leftUpperArm", "rotation", {0, 1}, {xyzw(l), xyzw(glm::inverse(p) * about(45, {0, 0, 1}) * p * l)}}};
    const auto hips = static_cast<std::size_t>(index_of(source, "hips"));
    run.push_back({"hips", "translation", {0, 1}, {glm::vec4(local_translation(source, hips), 0),
                                                    glm::vec4(local_translation(source, hips) + glm::inverse(source[0].rotation) *
                                                                                                     glm::vec3(0.1f, -0.1f, 0.3f), 0)}});
    add_clip(s, source, "Run", run);
    const std::string glb = write_doc(dir, "run.gltf", s);
    json map = json::object();
    json target_map = json::object();
    for (const Joint& j : source) {
        if (!j.bone.empty()) map[j.bone] = j.name;
    }
    for (const Joint& j : target) {
        if (!j.bone.empty()) target_map[j.bone] = j.name;
    }
    write_text(dir.file("mixamo-map.json"), map.dump());
    write_text(dir.file("target-map.json"), target_map.dump());
    const animation::Character tgt = load(write_doc(dir, "target.gltf", skeleton_doc(target, Declares::Nothing)));

    const gltf::Retargeted m =
        motion_ok({"run", glb, "Run", dir.file("mixamo-map.json"), dir.file("target-map.json")}, tgt);
    const animation::Pose rest = animation::rest_pose(tgt);
    const animation::Pose p1 = pose_at(tgt, m.animation, 1.0f);
    expect_near(arm_direction(p1, target), about(45, {0, 0, 1}) * arm_direction(rest, target), kPositionTol, "upper arm");
    const int th = index_of(target, "hips");
    expect_near(world_position(p1, th) - world_position(rest, th), (leg(1.28f) / leg(1.6f)) * glm::vec3(0.1f, -0.1f, 0.3f),
                kPositionTol, "hips");

    // Without the target map, a character that is not VRM says what to give.
    gltf::MotionKey key = gltf::MotionKey::File;
    auto no_map = gltf::load_motion({"run", glb, "Run", dir.file("mixamo-map.json"), ""}, tgt, &key);
    ASSERT_FALSE(no_map.ok());
    EXPECT_EQ(key, gltf::MotionKey::TargetMap);
    EXPECT_NE(no_map.error().message.find("target_map"), std::string::npos) << no_map.error().message;
    // Without the source map, a glTF that is not a VRM Animation says so.
    auto no_source_map = gltf::load_motion({"run", glb, "Run", "", dir.file("target-map.json")}, tgt, &key);
    ASSERT_FALSE(no_source_map.ok());
    EXPECT_EQ(no_source_map.error().message.rfind(glb + ": $.extensions.VRMC_vrm_animation: missing", 0), 0u)
        << no_source_map.error().message;
    // A clip name that does not exist.
    auto no_clip = gltf::load_motion({"run", glb, "Sprint", dir.file("mixamo-map.json"), dir.file("target-map.json")}, tgt, &key);
    ASSERT_FALSE(no_clip.ok());
    EXPECT_EQ(key, gltf::MotionKey::Clip);
    EXPECT_NE(no_clip.error().message.find("\"Sprint\""), std::string::npos) << no_clip.error().message;
}

TEST(Motion, SameInputSameBits) {
    Files f;
    const animation::Character target = load(f.avatar);
    const gltf::Retargeted a = motion_ok({"walk", f.vrma, "", "", ""}, target);
    const gltf::Retargeted b = motion_ok({"walk", f.vrma, "", "", ""}, target);
    ASSERT_EQ(a.animation.samplers.size(), b.animation.samplers.size());
    for (std::size_t s = 0; s < a.animation.samplers.size(); ++s) {
        ASSERT_EQ(a.animation.samplers[s].values.size(), b.animation.samplers[s].values.size());
        EXPECT_EQ(std::memcmp(a.animation.samplers[s].values.data(), b.animation.samplers[s].values.data(),
                              a.animation.samplers[s].values.size() * sizeof(glm::vec4)),
                  0);
    }
}

TEST(Motion, ExpressionsLookAtAndOptionalBonesAreWarnings) {
    Files f;
    Doc s = skeleton_doc(f.source, Declares::Vrma);
    s.extensions["VRMC_vrm_animation"]["expressions"] = {{"preset", {{"happy", {{"node", 0}}}}}};
    s.extensions["VRMC_vrm_animation"]["lookAt"] = {{"node", 0}};
    std::vector<Track> tracks = walk_tracks(f.source);
    tracks.push_back({"leftToes", "rotation", {0, 1}, {xyzw(glm::quat(1, 0, 0, 0)), xyzw(about(20, {1, 0, 0}))}});
    add_clip(s, f.source, "walk", tracks);
    const std::string vrma = write_doc(f.dir, "notes.vrma", s);
    // The avatar has no toes (optional): skipped with a warning.
    const animation::Character target = load(write_doc(f.dir, "toeless.gltf", skeleton_doc(f.target, Declares::Vrm1, {"leftToes"})));
    const gltf::Retargeted m = motion_ok({"walk", vrma, "", "", ""}, target);
    const auto warned = [&](const std::string& words) {
        return std::any_of(m.warnings.begin(), m.warnings.end(), [&](const std::string& w) { return w.find(words) != std::string::npos; });
    };
    EXPECT_TRUE(warned(vrma + ": $.extensions.VRMC_vrm_animation.expressions: not used"));
    EXPECT_TRUE(warned(vrma + ": $.extensions.VRMC_vrm_animation.lookAt: not used"));
    EXPECT_TRUE(warned("humanBones.leftToes.node: the clip animates leftToes"));
}

// Bad input: each error names the file and the glTF / JSON path.
void expect_error(const Result<gltf::Retargeted>& r, const std::string& starts, const std::string& words) {
    ASSERT_FALSE(r.ok()) << "retargeted";
    EXPECT_EQ(r.error().kind, Error::Kind::InvalidInput) << r.error().message;
    EXPECT_EQ(r.error().message.rfind(starts, 0), 0u) << r.error().message;
    EXPECT_NE(r.error().message.find(words), std::string::npos) << r.error().message;
}

TEST(Motion, VrmaWithoutHumanoidBones) {
    Files f;
    const animation::Character target = load(f.avatar);
    Doc s = skeleton_doc(f.source, Declares::Vrma);
    s.extensions["VRMC_vrm_animation"].erase("humanoid");
    add_clip(s, f.source, "walk", walk_tracks(f.source));
    const std::string bad = write_doc(f.dir, "bones.vrma", s);
    expect_error(gltf::load_motion({"walk", bad, "", "", ""}, target),
                 bad + ": $.extensions.VRMC_vrm_animation.humanoid.humanBones: missing", "humanoid bones");
    s.extensions["VRMC_vrm_animation"]["humanoid"] = {{"humanBones", json::object()}};
    write_doc(f.dir, "bones.vrma", s);
    expect_error(gltf::load_motion({"walk", bad, "", "", ""}, target),
                 bad + ": $.extensions.VRMC_vrm_animation.humanoid.humanBones: ", "no humanoid bone");
}

// Key times far from zero (review of issue 18): at 1e12 s a float step is about 1e5 s,
// so a split that counted only the keys it could place spun for hours; the keys a clip
// needs are counted first, and too many is an error naming the file and the clip.
TEST(Motion, KeyTimesTooFarApartAreAnErrorNotAHang) {
    Files f;
    const animation::Character target = load(f.avatar);
    Doc s = skeleton_doc(f.source, Declares::Vrma);
    add_clip(s, f.source, "walk", {{"leftUpperArm", "rotation", {1e12f, 1.001e12f}, {xyzw(glm::quat(1, 0, 0, 0)), xyzw(about(10, {1, 0, 0}))}}});
    const std::string vrma = write_doc(f.dir, "far.vrma", s);
    // (A hang fails by the test's timeout; the error must come at once.)
    expect_error(gltf::load_motion({"walk", vrma, "", "", ""}, target), vrma + ": $.animations[0]", "keys per channel");
}

TEST(Motion, RequiredBoneTheAvatarLacks) {
    Files f;
    Doc s = skeleton_doc(f.source, Declares::Vrma);
    std::vector<Track> tracks = walk_tracks(f.source);
    tracks.push_back({"leftHand", "rotation", {0, 1}, {xyzw(glm::quat(1, 0, 0, 0)), xyzw(about(10, {1, 0, 0}))}});
    add_clip(s, f.source, "wave", tracks);
    const std::string vrma = write_doc(f.dir, "wave.vrma", s);
    const animation::Character handless = load(write_doc(f.dir, "handless.gltf", skeleton_doc(f.target, Declares::Vrm1, {"leftHand"})));
    expect_error(gltf::load_motion({"wave", vrma, "", "", ""}, handless),
                 vrma + ": $.extensions.VRMC_vrm_animation.humanoid.humanBones.leftHand.node: ", "required VRM humanoid bone");
}

TEST(Motion, NoCommonBones) {
    Files f;
    // The source names only its toes; the target's map only its hips.
    Doc s = skeleton_doc(f.source, Declares::Nothing);
    s.extensions["VRMC_vrm_animation"] = {{"specVersion", "1.0"},
                                          {"humanoid", {{"humanBones", {{"leftToes", {{"node", index_of(f.source, "leftToes")}}}}}}}};
    add_clip(s, f.source, "wiggle", {{"leftToes", "rotation", {0, 1}, {xyzw(glm::quat(1, 0, 0, 0)), xyzw(about(20, {1, 0, 0}))}}});
    const std::string vrma = write_doc(f.dir, "toes.vrma", s);
    write_text(f.dir.file("hips-only.json"), json{{"hips", "hips"}}.dump());
    const animation::Character target = load(write_doc(f.dir, "plain.gltf", skeleton_doc(f.target, Declares::Nothing)));
    expect_error(gltf::load_motion({"wiggle", vrma, "", "", f.dir.file("hips-only.json")}, target),
                 vrma + ": $.extensions.VRMC_vrm_animation.humanoid.humanBones: ", "no humanoid bone in common");
}

TEST(Motion, MapNamingANodeThatDoesNotExist) {
    Files f;
    const animation::Character target = load(f.avatar);
    write_text(f.dir.file("map.json"), json{{"hips", "hips"}, {"leftHand", "mixamorig:LeftHand"}}.dump());
    gltf::MotionKey key = gltf::MotionKey::File;
    const auto r = gltf::load_motion({"walk", f.vrma, "", f.dir.file("map.json"), ""}, target, &key);
    expect_error(r, f.dir.file("map.json") + ": $.leftHand: ", "no node of " + f.vrma + " is called \"mixamorig:LeftHand\"");
    EXPECT_EQ(key, gltf::MotionKey::Map);
    write_text(f.dir.file("map.json"), json{{"hipz", "hips"}}.dump());
    expect_error(gltf::load_motion({"walk", f.vrma, "", f.dir.file("map.json"), ""}, target), f.dir.file("map.json") + ": $.hipz: ",
                 "not a VRM humanoid bone name");
}

// The scene: motions become clips by name, usable by `animation` and crowds; a name
// clash and a missing file are errors at their keys.
struct SceneFiles : Files {
    std::string scene(const json& motions, const std::string& animation = "walk") {
        json character = {{"name", "avatar"}, {"gltf", "avatar.gltf"}, {"animation", animation}, {"motions", motions},
                          {"chains", {{{"name", "hair"}, {"root", "hair_0"}}}}};
        json doc = {{"format", "kodawari-scene"}, {"version", 2}, {"name", "motions"}, {"fps", 30}, {"duration", 1},
                    {"characters", {character}},
                    {"crowds", {{{"character", "avatar"}, {"count", 2}, {"animations", {"walk", "idle"}}}}}};
        const std::string path = dir.file("scene.json");
        write_text(path, doc.dump());
        return path;
    }
};

TEST(Motion, SceneMotionsAreClips) {
    SceneFiles f;
    Doc idle = skeleton_doc(f.source, Declares::Vrma);
    add_clip(idle, f.source, "idle", {{"spine", "rotation", {0, 2}, {xyzw(glm::quat(1, 0, 0, 0)), xyzw(about(5, {0, 0, 1}))}}});
    write_doc(f.dir, "idle.vrma", idle);
    auto scene = load_scene(f.scene(json::array({{{"name", "walk"}, {"file", "walk.vrma"}}, {{"name", "idle"}, {"file", "idle.vrma"}}})));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const RigSpec& rig = *scene.value().characters.at(0).rig;
    ASSERT_EQ(rig.character->animations.size(), 2u);
    EXPECT_EQ(rig.character->animations[0].name, "walk");
    EXPECT_EQ(rig.character->animations[1].name, "idle");
    EXPECT_EQ(rig.clip, 0);
    EXPECT_EQ(scene.value().crowds.at(0).clips, (std::vector<std::int32_t>{0, 1}));
}

TEST(Motion, SceneMotionNameClashesWithAClip) {
    SceneFiles f;
    // The avatar has a clip of its own called "walk".
    Doc avatar = skeleton_doc(f.target, Declares::Vrm1);
    add_clip(avatar, f.target, "walk", {{"head", "rotation", {0}, {xyzw(local_rotation(f.target, 5))}}});
    write_doc(f.dir, "avatar.gltf", avatar);
    const std::string path = f.scene(json::array({{{"name", "walk"}, {"file", "walk.vrma"}}}));
    auto scene = load_scene(path);
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.error().kind, Error::Kind::InvalidInput);
    EXPECT_EQ(scene.error().message.rfind(path + ": $.characters[0].motions[0].name: ", 0), 0u) << scene.error().message;
    EXPECT_NE(scene.error().message.find("already a clip"), std::string::npos) << scene.error().message;
}

TEST(Motion, SceneMissingMotionFile) {
    SceneFiles f;
    const std::string path = f.scene(json::array({{{"name", "walk"}, {"file", "gone.vrma"}}}));
    auto scene = load_scene(path);
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.error().kind, Error::Kind::InvalidInput);
    EXPECT_EQ(scene.error().message.rfind(path + ": $.characters[0].motions[0].file: ", 0), 0u) << scene.error().message;
    EXPECT_NE(scene.error().message.find("gone.vrma: no such file"), std::string::npos) << scene.error().message;
}

TEST(Motion, SceneErrorInsideTheMotionNamesBothFiles) {
    SceneFiles f;
    Doc s = skeleton_doc(f.source, Declares::Vrma);
    s.extensions["VRMC_vrm_animation"].erase("humanoid");
    add_clip(s, f.source, "walk", walk_tracks(f.source));
    write_doc(f.dir, "walk.vrma", s);
    const std::string path = f.scene(json::array({{{"name", "walk"}, {"file", "walk.vrma"}}}));
    auto scene = load_scene(path);
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.error().message.rfind(path + ": $.characters[0].motions[0].file: ", 0), 0u) << scene.error().message;
    EXPECT_NE(scene.error().message.find("walk.vrma: $.extensions.VRMC_vrm_animation.humanoid.humanBones: missing"), std::string::npos)
        << scene.error().message;
}

}  // namespace
}  // namespace kodawari
