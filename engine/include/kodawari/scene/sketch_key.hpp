#pragma once
/// @file
/// The key of a keyed sketch (docs/sketch.md, "Keyed sketches"): a stroke drawn over a
/// frame becomes a keyed example (docs/keyed-examples.md) keyed by what the character does
/// at that frame, its motion as the simulation measures it there (K.2) or a joint's pose
/// (K.3). The shape comes from the stroke as for a view example (rods::sketch_view_example);
/// add_keyed_example (scene_edit.hpp) writes the two into the scene.

#include <cstdint>
#include <optional>
#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/keyed.hpp"
#include "kodawari/rods/rod_scene.hpp"
#include "kodawari/scene/scene_edit.hpp"

namespace kodawari {

/// A motion key's smoothing when none is given: the scene format's default, s.
inline constexpr float kSketchSmoothing = 0.25f;
/// A motion key's influence when none is given, as a fraction of the measured key: the
/// example acts from about half to one and a half times the motion it was drawn at (at
/// +-2 sigma its weight is exp(-2) = 0.14), as scenes/ponytail.json's sprint (6 m/s,
/// influence 1.5) does.
inline constexpr float kSketchMotionInfluence = 0.25f;
/// A pose key's influence when none is given, degrees: the scene format's default.
inline constexpr float kSketchPoseInfluenceDeg = 20.0f;
/// A measured motion below this (m/s, m/s^2 or rad/s) is no motion: a key there would
/// be the character standing still, and its default influence nothing.
inline constexpr float kSketchStillMotion = 1e-3f;

/// What a keyed sketch is keyed by.
struct SketchKeyOptions {
    rods::KeyKind kind = rods::KeyKind::Motion;
    /// The key source's name (a skeleton joint, a glTF node); empty: the character's
    /// reference joint.
    std::string joint;
    rods::MotionMeasure measure = rods::MotionMeasure::Speed;  ///< motion
    float smoothing = kSketchSmoothing;                        ///< motion: tau, s
    /// Motion: in the measure's units (default kSketchMotionInfluence times the key);
    /// pose: degrees (default kSketchPoseInfluenceDeg).
    std::optional<float> influence;
};

/// The key of character instance `instance` of `scene` at frame `frame`, as a KeyedSketch
/// without its shape (the caller sets it):
/// - motion: the magnitude of `options.measure` of the joint, smoothed over
///   `options.smoothing`, exactly as the simulation reads it at `frame` (K.2: the joint's
///   world pose of frames 0 .. frame through rods::keyed_weights, which keeps the smoothed
///   key in its KeyState);
/// - pose: the joint's rotation relative to its parent at `frame` (K.1, as RodFrame::keys
///   holds it).
/// Fails (InvalidInput) naming the joint when the character has no joint of that name
/// (listing its joints), the influence when it is not finite and > 0, the smoothing when
/// it is not in [0, rods::kMaxSmoothing], and when a motion key measures less than
/// kSketchStillMotion: the character does not move at that frame. Asserts `instance` and
/// `frame` are in range.
[[nodiscard]] KODAWARI_API Result<KeyedSketch> measure_sketch_key(const RodScene& scene, std::uint32_t instance,
                                                                   std::uint32_t frame, const SketchKeyOptions& options);

/// "speed", "acceleration", "angular_speed": the scene format's names of the measures.
[[nodiscard]] KODAWARI_API const char* measure_name(rods::MotionMeasure measure);
/// The measure's unit, "m/s", "m/s^2" or "rad/s".
[[nodiscard]] KODAWARI_API const char* measure_unit(rods::MotionMeasure measure);

}  // namespace kodawari
