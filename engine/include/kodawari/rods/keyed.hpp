#pragma once
/// @file
/// Keyed examples (docs/keyed-examples.md): example rest shapes keyed, besides the view of
/// SPEC A.3, by how violently the character moves (motion) or by the pose of named joints
/// (pose), the two uses seed A names first. A chain's keyed examples read its key
/// sources: joints of its character, measured every frame (RodFrame::keys). Their weights
/// (K.2, K.3) come from the distance between the measured key and each example's key;
/// they take their share of the blend from the view weights (K.4), and the one blend of
/// SPEC A.2 makes the rest shape, so momentum suppression (A.5) covers every change.
#include <array>
#include <cstdint>
#include <limits>
#include <span>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/rods/solver.hpp"

namespace kodawari::rods {

/// The most key sources (joints) one chain reads.
inline constexpr std::uint32_t kMaxKeySources = 4;
/// The most keyed examples one chain may have; with its view examples at most
/// kMaxViewExamples (world.hpp) in all, so that every backend keeps the weights of one
/// chain in 8 registers.
inline constexpr std::uint32_t kMaxKeyedExamples = 4;
/// The largest smoothing time constant scenes and sketches take, s.
inline constexpr float kMaxSmoothing = 60.0f;

/// What a key source is measured as; decides what the producer of a frame writes into
/// RodFrame::keys for it.
enum class KeySourceKind : std::uint32_t {
    Motion = 0,  ///< the joint's world pose; its motion is measured frame to frame (K.2)
    Pose = 1,    ///< the joint's rotation relative to its parent's (position unused) (K.3)
};

/// A key source of a scene's chain: a joint of its character, read every frame as its
/// world pose (Motion) or as its rotation relative to `parent` (Pose); RodScene fills
/// RodFrame::keys from it.
struct KeyJoint {
    std::uint32_t joint = 0;    ///< skeleton joint (rigged characters: node)
    std::int32_t parent = -1;   ///< Pose: the joint (node) it is measured against; -1: the world
    KeySourceKind kind = KeySourceKind::Motion;
    bool operator==(const KeyJoint&) const = default;
};

/// A keyed example's kind.
enum class KeyKind : std::uint32_t { Motion = 0, Pose = 1 };
/// What a motion key measures of its source joint (K.2).
enum class MotionMeasure : std::uint32_t {
    Speed = 0,         ///< linear velocity, m/s
    Acceleration = 1,  ///< linear acceleration, m/s^2
    AngularSpeed = 2,  ///< angular velocity, rad/s
};
/// How a motion key is read (K.2).
enum class MotionFrame : std::uint32_t {
    Magnitude = 0,  ///< the measure's length: a number (value.x)
    Joint = 1,      ///< the measure as a vector in the joint's own frame (value)
};

/// One keyed example's key, influence and smoothing; its shape is kept alongside (the
/// template's shapes, after the view examples').
struct KeyedExample {
    KeyKind kind = KeyKind::Motion;
    /// Motion: the key source measured (an index into ChainTemplate::key_sources, of kind
    /// Motion). Pose: unused.
    std::uint32_t source = 0;
    /// Pose: bit s set for every key source s (of kind Pose) whose rotation is keyed.
    std::uint32_t source_mask = 0;
    MotionMeasure measure = MotionMeasure::Speed;
    MotionFrame frame = MotionFrame::Magnitude;
    /// Motion: the key, (magnitude, 0, 0) or a vector in the joint's frame, in the
    /// measure's units.
    glm::vec3 value{0.0f};
    /// Pose: per key source in source_mask, its rotation relative to its parent (unit).
    std::array<glm::quat, kMaxKeySources> rotations{};
    /// sigma > 0, the width of the example's region: motion in the measure's units, pose in
    /// radians. Small: the example acts only near its key, and the nearest example dominates.
    float influence = 1.0f;
    /// tau >= 0, s: motion keys read the measure smoothed over this time constant (K.2),
    /// so one noisy frame does not flip the shape; 0 reads it raw.
    float smoothing = 0.0f;
    /// Set by add_keyed_examples: a magnitude key reads the measure clamped to at most
    /// the largest key of the examples of its source and measure (K.2).
    float saturation = std::numeric_limits<float>::infinity();
};

/// What the key measurement keeps from frame to frame, per chain.
struct KeyState {
    struct Source {
        Transform last;                ///< last frame's pose (Motion sources)
        glm::vec3 velocity{0.0f};      ///< last frame's velocity, m/s (world)
        bool has_velocity = false;     ///< false until a velocity has been measured
    };
    std::array<Source, kMaxKeySources> sources{};
    std::array<glm::vec3, kMaxKeyedExamples> smoothed{};  ///< per keyed example, its read key (K.2)
};

/// The raw weights u_1 .. u_J of a chain's keyed examples (K.2, K.3), before K.4's
/// normalization; entries past J are 0.
using KeyedWeights = std::array<float, kMaxKeyedExamples>;

/// The key state at the start of a simulation: every source's last pose is its pose in
/// `keys` (the first frame's), no velocity yet, every smoothed key 0 (the character
/// starts at rest, so a motion example starts without weight).
[[nodiscard]] KODAWARI_API KeyState initial_key_state(std::span<const Transform> keys);

/// Measures the keys of one frame of `dt` s (K.2, K.3) and updates `state`: the weights
/// u_j = exp(-(Delta_j / sigma_j)^2 / 2) of `examples`, from `keys` (this frame's, one per
/// key source, as RodFrame::keys holds them). `sources` are the kinds of the key sources.
/// A motion source that moved farther than `teleport_distance` (m; SolverParams's) in the
/// frame teleported: its motion goes on as it was (last velocity, no acceleration), so a
/// cut does not read as a burst of speed.
[[nodiscard]] KODAWARI_API KeyedWeights keyed_weights(std::span<const KeyedExample> examples,
                                                      std::span<const KeySourceKind> sources,
                                                      std::span<const Transform> keys, float dt, KeyState& state,
                                                      float teleport_distance = SolverParams{}.teleport_distance);

/// Combines view weights w_0 .. w_m (SPEC A.3) with raw keyed weights u_1 .. u_J (K.4):
/// U = sum u_j; if U >= 1 every u_j /= U and U = 1; then the view weights scale by 1 - U.
/// Writes m + 1 + J weights into `out` (w_0 first, the keyed examples last), which must
/// hold that many. They sum to 1 and lie in [0, 1].
KODAWARI_API void combine_weights(std::span<const float> view, std::span<const float> keyed, std::span<float> out);

}  // namespace kodawari::rods
