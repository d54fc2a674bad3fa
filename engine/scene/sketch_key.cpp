// The key of a keyed sketch (sketch_key.hpp): what the character does at the sketched
// frame, measured the way the backends measure it (docs/keyed-examples.md K.2, K.3).

#include "kodawari/scene/sketch_key.hpp"

#include <cassert>
#include <cmath>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

namespace kodawari {
namespace {

Error invalid(const std::string& message) { return make_error(Error::Kind::InvalidInput, message); }

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    return text;
}

}  // namespace

const char* measure_name(rods::MotionMeasure measure) {
    switch (measure) {
        case rods::MotionMeasure::Speed: return "speed";
        case rods::MotionMeasure::Acceleration: return "acceleration";
        case rods::MotionMeasure::AngularSpeed: return "angular_speed";
    }
    return "speed";
}

const char* measure_unit(rods::MotionMeasure measure) {
    switch (measure) {
        case rods::MotionMeasure::Speed: return "m/s";
        case rods::MotionMeasure::Acceleration: return "m/s^2";
        case rods::MotionMeasure::AngularSpeed: return "rad/s";
    }
    return "m/s";
}

Result<KeyedSketch> measure_sketch_key(const RodScene& scene, std::uint32_t instance, std::uint32_t frame,
                                       const SketchKeyOptions& options) {
    assert(instance < scene.instances.size() && frame < scene.frames);
    const CharacterKinematics& character = scene.characters[scene.instances[instance].character];
    const std::vector<std::string>& names = scene.joint_names(instance);
    const std::vector<std::int32_t>& parents = scene.joint_parents(instance);
    KeyedSketch out;
    out.kind = options.kind;
    out.reference_joint = names.at(character.skeleton.reference);
    out.joint = options.joint.empty() ? out.reference_joint : options.joint;
    std::uint32_t joint = 0;
    while (joint < names.size() && names[joint] != out.joint) ++joint;
    if (joint == names.size()) {
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "\"" : ", \"") + n + "\"";
        return invalid("joint \"" + out.joint + "\": character \"" + character.name + "\" has no such joint (joints: " +
                       list + ")");
    }

    if (options.kind == rods::KeyKind::Pose) {
        const float influence = options.influence.value_or(kSketchPoseInfluenceDeg);
        if (!(std::isfinite(influence) && influence > 0.0f && influence <= 360.0f)) {
            return invalid("influence: expected degrees in (0, 360], got " + number(influence));
        }
        out.influence = influence;
        // K.1: q_parent^T q_joint of the world rotations, scale removed; a root is measured
        // against the world (rod_scene.cpp's key_entry).
        const std::vector<rods::Transform> poses = scene.joint_poses(instance, frame);
        const std::int32_t parent = parents[joint];
        out.rotation = parent >= 0 ? glm::normalize(glm::conjugate(poses[static_cast<std::size_t>(parent)].rotation) *
                                                    poses[joint].rotation)
                                   : poses[joint].rotation;
        return out;
    }

    if (!(std::isfinite(options.smoothing) && options.smoothing >= 0.0f && options.smoothing <= rods::kMaxSmoothing)) {
        return invalid("smoothing: expected seconds in [0, " + number(rods::kMaxSmoothing) + "], got " +
                       number(options.smoothing));
    }
    if (options.influence && !(std::isfinite(*options.influence) && *options.influence > 0.0f)) {
        return invalid("influence: expected a number > 0 (" + std::string(measure_unit(options.measure)) + "), got " +
                       number(*options.influence));
    }
    out.measure = options.measure;
    out.smoothing = options.smoothing;
    // K.2 over frames 0 .. frame, as a backend steps them (frame 0 is the initial state,
    // frames 1, 2, ... are measured): one motion source, one magnitude example, whose
    // smoothed key the key state keeps. Its key and influence only shape the weight, which
    // is not used; saturation stays infinite, so the smoothed value is the unclamped m_j.
    rods::KeyedExample probe;
    probe.kind = rods::KeyKind::Motion;
    probe.source = 0;
    probe.measure = options.measure;
    probe.frame = rods::MotionFrame::Magnitude;
    probe.smoothing = options.smoothing;
    const rods::KeySourceKind kinds[] = {rods::KeySourceKind::Motion};
    std::vector<rods::Transform> poses;
    scene.joint_poses(instance, 0, poses);
    rods::Transform key[] = {poses[joint]};
    rods::KeyState state = rods::initial_key_state(key);
    const float dt = static_cast<float>(1.0 / static_cast<double>(scene.fps));  // RodScene::frame's dt
    for (std::uint32_t f = 1; f <= frame; ++f) {
        scene.joint_poses(instance, f, poses);
        key[0] = poses[joint];
        (void)rods::keyed_weights(std::span<const rods::KeyedExample>(&probe, 1), kinds, key, dt, state);
    }
    out.value = state.smoothed[0].x;
    if (!(out.value >= kSketchStillMotion)) {
        return invalid("character \"" + character.name + "\" does not move at frame " + std::to_string(frame) + ": its " +
                       out.joint + "'s " + measure_name(options.measure) + " is " + number(out.value) + " " +
                       measure_unit(options.measure) + " (smoothed over " + number(options.smoothing) +
                       " s); sketch a motion example at a frame where it moves, or a pose example");
    }
    out.influence = options.influence.value_or(kSketchMotionInfluence * out.value);
    if (!(out.influence <= 1e4f)) return invalid("influence: expected a number in (0, 1e4], got " + number(out.influence));
    return out;
}

}  // namespace kodawari
