// A chain's `keyed` array (docs/scene-format.md, "Keyed examples"; the model is
// docs/keyed-examples.md): motion and pose keys, and the key sources (joints) they read.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include <kodawari/rods/world.hpp>

#include "scene/character_loader.hpp"

namespace kodawari::scene_detail {
namespace {

// The measures' largest keys: far past anything a character does (a sprint is 10 m/s, a
// head snap 40 rad/s), small enough that squares stay finite in float.
constexpr double kMaxMotionKey = 1e4;

// The chain's key source for (joint, kind), added when new; an error at `at` past the limit.
Result<std::uint32_t> source(const JsonReader& r, const JsonNode& at, ChainSpec& c, rods::KeyJoint key) {
    const auto found = std::find(c.key_sources.begin(), c.key_sources.end(), key);
    if (found != c.key_sources.end()) return static_cast<std::uint32_t>(found - c.key_sources.begin());
    if (c.key_sources.size() >= rods::kMaxKeySources) {
        return r.fail(at.path, "a chain's keyed examples read at most " + std::to_string(rods::kMaxKeySources) +
                                   " key sources (a joint as motion or as pose counts once)");
    }
    c.key_sources.push_back(key);
    return static_cast<std::uint32_t>(c.key_sources.size() - 1);
}

Result<void> read_motion_key(const JsonReader& r, const JsonNode& node, const JointLookup& joints, ChainSpec& c,
                             rods::KeyedExample& e) {
    const JsonNode pose = r.member(node, "pose");
    if (pose.present()) return r.fail(pose.path, "only used with \"key\": \"pose\"");
    rods::KeyJoint key{joints.reference, -1, rods::KeySourceKind::Motion};
    const JsonNode joint = r.member(node, "joint");
    if (joint.present()) KW_SCENE_ASSIGN(key.joint, joints.find(joint));
    KW_SCENE_ASSIGN(e.source, source(r, joint.present() ? joint : node, c, key));

    const JsonNode measure = r.member(node, "measure");
    if (measure.present()) {
        std::uint32_t m = 0;
        KW_SCENE_ASSIGN(m, find_name(r, measure, {"speed", "acceleration", "angular_speed"}, "a motion measure"));
        e.measure = static_cast<rods::MotionMeasure>(m);
    }
    const JsonNode frame = r.member(node, "frame");
    if (frame.present()) {
        std::uint32_t f = 0;
        KW_SCENE_ASSIGN(f, find_name(r, frame, {"magnitude", "joint"},
                                     "how the measure is read: its magnitude, or a vector in the joint's frame"));
        e.frame = static_cast<rods::MotionFrame>(f);
    }
    const JsonNode value = r.member(node, "value");
    if (e.frame == rods::MotionFrame::Magnitude) {
        KW_SCENE_ASSIGN(e.value.x, r.real(value, NumberRange::closed(0.0, kMaxMotionKey)));
    } else {
        KW_SCENE_ASSIGN(e.value, read_point(r, value, kMaxMotionKey));
    }
    e.influence = 1.0f;
    KW_TRY(optional_member(r, node, "influence", e.influence,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, kMaxMotionKey)); }));
    e.smoothing = 0.25f;
    KW_TRY(optional_member(r, node, "smoothing", e.smoothing,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, rods::kMaxSmoothing)); }));
    return {};
}

Result<void> read_pose_key(const JsonReader& r, const JsonNode& node, const JointLookup& joints, ChainSpec& c,
                           rods::KeyedExample& e) {
    for (const char* motion_only : {"joint", "measure", "frame", "value", "smoothing"}) {
        const JsonNode m = r.member(node, motion_only);
        if (m.present()) return r.fail(m.path, "only used with \"key\": \"motion\" (a pose key names its joints in \"pose\")");
    }
    const JsonNode pose = r.member(node, "pose");
    const std::string what = "an array of 1 to " + std::to_string(rods::kMaxKeySources) +
                             " joint poses {\"joint\": name, \"axis\": [x, y, z], \"angle_deg\": a} or "
                             "{\"joint\": name, \"rotation\": [x, y, z, w]}";
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, pose, 1, rods::kMaxKeySources, what));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode p = r.element(pose, i);
        KW_TRY(r.object(p, {"joint", "axis", "angle_deg", "rotation"}));
        const JsonNode joint = r.member(p, "joint");
        rods::KeyJoint key{0, -1, rods::KeySourceKind::Pose};
        KW_SCENE_ASSIGN(key.joint, joints.find(joint));
        key.parent = joints.parent(key.joint);
        std::uint32_t s = 0;
        KW_SCENE_ASSIGN(s, source(r, joint, c, key));
        if ((e.source_mask & (1u << s)) != 0) return r.expected(joint, "a joint this pose key does not name yet");
        e.source_mask |= 1u << s;
        const JsonNode rotation = r.member(p, "rotation");
        const JsonNode axis = r.member(p, "axis");
        const JsonNode angle = r.member(p, "angle_deg");
        if (rotation.present()) {
            if (axis.present() || angle.present()) {
                return r.fail(p.path, "expected either \"rotation\" or \"axis\" and \"angle_deg\", not both");
            }
            KW_SCENE_ASSIGN(e.rotations[s], read_unit_quat(r, rotation));
        } else {
            // A turn of the joint about an axis of its own rest frame, from its rest pose.
            glm::vec3 a{};
            KW_SCENE_ASSIGN(a, read_direction(r, axis));
            float radians = 0.0f;
            KW_SCENE_ASSIGN(radians, read_degrees(r, angle, NumberRange::closed(-180.0, 180.0)));
            e.rotations[s] = glm::normalize(joints.rest_rotation(key.joint) * glm::angleAxis(radians, a));
        }
    }
    float influence = 20.0f * static_cast<float>(kDegToRad);
    KW_TRY(optional_member(r, node, "influence", influence,
                           [&](const JsonNode& x) { return read_degrees(r, x, NumberRange::left_open(0.0, 360.0)); }));
    e.influence = influence;
    return {};
}

}  // namespace

Result<void> read_keyed(const JsonReader& r, const JsonNode& node, const JointLookup& joints, ChainSpec& c) {
    const std::size_t room = std::min<std::size_t>(rods::kMaxKeyedExamples, rods::kMaxViewExamples - c.views.size());
    const std::string what = "an array of at most " + std::to_string(room) + " keyed examples (at most " +
                             std::to_string(rods::kMaxKeyedExamples) + ", and at most " +
                             std::to_string(rods::kMaxViewExamples) + " examples with the views)";
    std::size_t n = 0;
    if (room == 0 && node.present() && node.value->is_array() && !node.value->empty()) {
        return r.fail(node.path, "the chain's " + std::to_string(c.views.size()) + " view examples leave no room for a keyed "
                                 "one (at most " + std::to_string(rods::kMaxViewExamples) +
                                 " examples in all): expected an empty array, got " + std::to_string(node.value->size()));
    }
    KW_SCENE_ASSIGN(n, read_array(r, node, 0, room, what));
    for (std::size_t j = 0; j < n; ++j) {
        const JsonNode element = r.element(node, j);
        KW_TRY(r.object(element, {"name", "key", "joint", "measure", "frame", "value", "influence", "smoothing", "pose",
                                  "shape"}));
        KeyedSpec k;
        KW_TRY(optional_member(r, element, "name", k.name, [&](const JsonNode& x) { return r.string(x); }));
        std::uint32_t kind = 0;
        KW_SCENE_ASSIGN(kind, find_name(r, r.member(element, "key"), {"motion", "pose"}, "a key kind"));
        k.example.kind = static_cast<rods::KeyKind>(kind);
        if (k.example.kind == rods::KeyKind::Motion) {
            KW_TRY(read_motion_key(r, element, joints, c, k.example));
        } else {
            KW_TRY(read_pose_key(r, element, joints, c, k.example));
        }
        KW_SCENE_ASSIGN(k.shape, read_shape(r, r.member(element, "shape"), c.base.positions.size()));
        c.keyed.push_back(std::move(k));
    }
    return {};
}

}  // namespace kodawari::scene_detail
