#pragma once
/// @file
/// The kinematic side of a character (SPEC A.1, C): a small skeleton posed by
/// procedural motions (idle sway, head turn, walk, sudden stop) and the moving camera
/// that decides the view direction (SPEC A.3). Nothing here is simulated: every pose is
/// a closed-form function of time, so any frame can be evaluated on its own, in any
/// order, and the same time gives the same bits.

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/view.hpp"

namespace kodawari::rods {

/// The most joints one skeleton may have. Poses are evaluated in a fixed-size buffer of
/// this many transforms, so that posing a character allocates nothing.
inline constexpr std::uint32_t kMaxSkeletonJoints = 64;

/// A time that never comes: the end of a motion that lasts for ever.
inline constexpr float kForever = std::numeric_limits<float>::infinity();

/// One kinematic joint (SPEC A.1: animated, never simulated).
struct SkeletonJoint {
    std::string name;
    std::int32_t parent = -1;  ///< index of the parent joint; -1 for the root
    Transform rest;            ///< the joint's frame in its parent's (the root's: in the character's frame)
};

/// A skeleton whose joints are ordered parents first; joint 0 is the only root.
struct Skeleton {
    std::vector<SkeletonJoint> joints;
    std::uint32_t reference = 0;  ///< the reference joint of SPEC A.1/A.3 (default: the head)
};

/// A periodic rotation of one joint about an axis of its own rest frame: idle sway,
/// head turn (look left/right), nodding. The angle at time t is
/// `amplitude * shape(sin(2 pi frequency (t - start) + phase)) * envelope(t)`, where
/// shape(s) = s for sharpness 0 and tanh(k s) / tanh(k) for sharpness k > 0 (the larger
/// k, the more the motion turns quickly and then holds, like a glance), and the
/// envelope is 0 outside [start, end) and rises and falls by a smoothstep over `fade`
/// seconds at both ends (fade 0: a hard start and stop).
struct Oscillation {
    std::uint32_t joint = 0;
    glm::vec3 axis{0.0f, 0.0f, 1.0f};  ///< unit
    float amplitude = 0.0f;            ///< rad
    float frequency = 0.5f;            ///< Hz, >= 0
    float phase = 0.0f;                ///< rad
    float sharpness = 0.0f;            ///< >= 0
    float start = 0.0f;                ///< s
    float end = kForever;              ///< s, > start
    float fade = 0.0f;                 ///< s, >= 0
};

/// The character moving as a whole: forward (+Z of its frame) at `speed`, turning about
/// +Y at `turn_rate`, both scaled by one trapezoid envelope e(t) that ramps from 0 to 1
/// over `ramp_in` seconds after `start` and back to 0 over `ramp_out` seconds before
/// `end`. Because speed and turn share the envelope, the path is a circle of radius
/// speed / turn_rate (a straight line without turning), in closed form at any t.
/// `ramp_out` = 0 is the sudden stop: at `end` the character halts dead, which is the
/// classic test of hair overshoot. While moving, the root joint bobs up by
/// `bob (1 - cos(2 pi step_frequency tau)) / 2` and rolls by
/// `roll sin(pi step_frequency tau)` (tau = t - start), both scaled by e(t).
struct Locomotion {
    float speed = 1.0f;           ///< m/s, >= 0
    float turn_rate = 0.0f;       ///< rad/s, + = to the character's left (about +Y)
    float start = 0.0f;           ///< s
    float end = kForever;         ///< s, > start
    float ramp_in = 0.0f;         ///< s, >= 0
    float ramp_out = 0.0f;        ///< s, >= 0, ramp_in + ramp_out <= end - start
    float bob = 0.0f;             ///< m
    float step_frequency = 2.0f;  ///< steps per second, > 0
    float roll = 0.0f;            ///< rad
};

/// Every procedural motion of a character. Oscillations of one joint compose in list
/// order after the joint's rest rotation. Locomotions compose in list order too (each
/// moves in the frame the previous ones have reached), so list them in the order they
/// happen.
struct CharacterMotion {
    std::vector<Oscillation> oscillations;
    std::vector<Locomotion> locomotions;
};

/// The envelope e(t) of a locomotion, in [0, 1].
[[nodiscard]] KODAWARI_API float locomotion_envelope(const Locomotion& motion, float time);

/// Where the locomotions have taken the character at time t, relative to its placement.
struct LocomotionPose {
    Transform frame;   ///< the moving character frame in the placement's frame
    float bob = 0.0f;  ///< m, up, added to the root joint's position
    float roll = 0.0f; ///< rad, about the character's forward axis, turns the root joint
};

/// All locomotions of a character at time t (composed in list order).
[[nodiscard]] KODAWARI_API LocomotionPose evaluate_locomotion(std::span<const Locomotion> motions, float time);

/// The angle of an oscillation at time t, rad.
[[nodiscard]] KODAWARI_API float oscillation_angle(const Oscillation& motion, float time);

/// `parent` then `local`: world = parent.position + parent.rotation * local.position.
[[nodiscard]] KODAWARI_API Transform compose(const Transform& parent, const Transform& local);

/// The world pose of every joint of `skeleton` at `time`, for a character placed at
/// `placement` (its instance transform) and moved by `motion`. `out` must hold at least
/// skeleton.joints.size() entries (at most kMaxSkeletonJoints). Allocates nothing.
KODAWARI_API void pose_skeleton(const Skeleton& skeleton, const CharacterMotion& motion, const Transform& placement,
                                float time,
                                std::span<Transform> out);

/// How a keyframed camera moves between its keys.
enum class Interpolation {
    Linear,     ///< straight lines, constant speed between keys
    CatmullRom  ///< a C1 curve through the keys (Hermite with finite-difference tangents)
};

/// One camera key: where the camera is and what it looks at, at a time.
struct CameraKey {
    float time = 0.0f;  ///< s, strictly increasing along the keys
    glm::vec3 position{0.0f};
    glm::vec3 target{0.0f};
};

/// A camera moving with time (SPEC A.3: the camera decides the view direction of every
/// chain, so a moving camera is what shows the view-dependent shapes).
struct CameraMotion {
    enum class Kind {
        Fixed,     ///< `position`, looking at `target`
        Orbit,     ///< round `target` at `radius`, `height` above it, `rate` rad/s from `start_angle`
        Keyframes  ///< through `keys`; before the first key and after the last the camera holds
    };
    Kind kind = Kind::Fixed;
    Camera::Projection projection = Camera::Projection::Perspective;
    glm::vec3 position{0.0f, 1.5f, 3.0f};
    glm::vec3 target{0.0f, 1.5f, 0.0f};
    /// Orbit: the camera sits at target + (radius sin a, height, radius cos a) with
    /// a = start_angle + rate t, so a = 0 is in front of a character facing +Z, and a
    /// positive rate goes round anticlockwise seen from above (front, then the
    /// character's left side at a = 90 degrees, the back, its right side).
    float radius = 3.0f;
    float height = 0.0f;
    float rate = 0.5f;         ///< rad/s
    float start_angle = 0.0f;  ///< rad
    std::vector<CameraKey> keys;
    Interpolation interpolation = Interpolation::CatmullRom;
    /// Keyframes: after the last key start again from the first (the last key must then
    /// equal the first; a looping path adds that key itself).
    bool loop = false;
};

/// Where the camera is at one time.
struct CameraPose {
    glm::vec3 position{0.0f};
    glm::vec3 target{0.0f};
    glm::vec3 forward{0.0f, 0.0f, -1.0f};  ///< unit; (0, 0, -1) where target and position coincide
    Camera::Projection projection = Camera::Projection::Perspective;

    /// The camera as the view weights (SPEC A.3) need it.
    [[nodiscard]] Camera camera() const { return Camera{projection, position, forward}; }
};

/// The camera at `time` seconds.
[[nodiscard]] KODAWARI_API CameraPose camera_pose(const CameraMotion& motion, float time);

}  // namespace kodawari::rods
