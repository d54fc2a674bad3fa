#pragma once
/// @file
/// The scalar reference of the bird engine (SPEC B.3-B.6): route sampling, attitude,
/// flight mode, transitions and the seven part rotations of one bird for one frame.
/// shaders/birds_flap.comp implements the same steps; the CPU backends call these.

#include <array>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/wingbeat.hpp"
#include "kodawari/birds/world.hpp"

namespace kodawari::birds {

struct Vec3 {
    float x = 0, y = 0, z = 0;
};

/// A point of a route with its time derivatives.
struct RouteSample {
    Vec3 position;      ///< m
    Vec3 velocity;      ///< m/s
    Vec3 acceleration;  ///< m/s^2
    /// The mode decisions' inputs, exact on every backend (shaders/shared/birds.h):
    /// a positive multiple of the velocity (P'), and acceleration.y = lift / lift_scale
    /// with lift_scale > 0.
    Vec3 direction;
    float lift = 0.0f;
    float lift_scale = 1.0f;
    /// The velocity the Body is aligned with: `velocity`, except on a take-off or landing
    /// segment, where its climb is scaled by the speed fraction and its length is the
    /// cruise speed, so that a perched bird sits level and faces along the route.
    Vec3 attitude_velocity;
    /// The mode of the segment the bird is on (KW_SEGMENT_AUTO or a KW_MODE_*), exact.
    float segment_mode = KW_SEGMENT_AUTO;
    /// Take-off and landing progress (docs/flight-modes.md F.2); speed_fraction is exact.
    PerchProgress progress;
};

/// Position, velocity and acceleration of a bird flying `route` at `speed` for
/// `time` seconds (arc-length timing), or at the route's parametric timing.
[[nodiscard]] KODAWARI_API RouteSample sample_route(const BirdWorld& world, std::uint32_t route, float time, float speed);

/// Route parameter u (segment index + local parameter) at arc length s in [0, length].
[[nodiscard]] KODAWARI_API float route_parameter_at(const BirdWorld& world, std::uint32_t route, float s);

/// Body attitude (SPEC B.4): yaw from the horizontal velocity, pitch = climb angle,
/// bank by the chosen rule. Radians; bank > 0 = right wing down.
struct Attitude {
    float yaw = 0, pitch = 0, bank = 0;
};
[[nodiscard]] KODAWARI_API Attitude attitude(const gpu::FlightUniforms& uniforms, const RouteSample& sample);

/// The factors of body_rotation(): yaw, climb pitch and bank (identity when not moving).
struct BodyFrame {
    gpu::vec4 yaw{0, 0, 0, 1}, pitch{0, 0, 0, 1}, bank{0, 0, 0, 1};
    bool moving = false;
};
[[nodiscard]] KODAWARI_API BodyFrame body_frame(const gpu::FlightUniforms& uniforms, const RouteSample& sample);

/// The Body's world rotation for `attitude()`: yaw about +Y, then nose up by the climb
/// angle (about -X), then bank about +Z (positive = right wing down).
[[nodiscard]] KODAWARI_API gpu::vec4 body_rotation(const gpu::FlightUniforms& uniforms, const RouteSample& sample);

/// The next flight mode of the climb rule (SPEC B.5) given the previous one (KW_MODE_UNSET
/// on frame 0): level, ascend or descend.
[[nodiscard]] KODAWARI_API std::uint32_t next_mode(const gpu::FlightUniforms& uniforms, std::uint32_t previous,
                                                   const RouteSample& sample);

/// Below this cruise speed (m/s) a bird that can hover hovers (docs/flight-modes.md F.1).
inline constexpr float kHoverBelowSpeed = 3.0f;

/// The mode a bird flies (docs/flight-modes.md F.1): the segment's own mode if it has one,
/// else the climb rule's `climb_mode`, turned into hover for a slow hovering bird and into
/// glide by the flap-glide rhythm. `state` is the bird's state before this frame.
[[nodiscard]] KODAWARI_API std::uint32_t flight_mode(const gpu::BirdParams& bird, const gpu::BirdState& state,
                                                     const RouteSample& sample, std::uint32_t climb_mode);

/// Everything about one bird in one frame.
struct BirdFrame {
    gpu::BirdPose pose;
    gpu::BirdDiag diag;
};

/// Advances `state` to frame `frame` and evaluates the bird. Frames must be visited in
/// order from 0 (the state carries hysteresis, transition, phase and the roll filter).
/// `uniforms` = world.uniforms(), passed in so a loop over birds computes it once. A
/// driven bird (ids.w == KW_BIRD_DRIVEN) flies `motion`, its frame's, instead of its route;
/// or, when motion->position.w is KW_MOTION_ROUTE, its route (route_motion_sample()).
[[nodiscard]] KODAWARI_API BirdFrame step_bird(const BirdWorld& world, const gpu::FlightUniforms& uniforms,
                                               const gpu::BirdParams& bird, gpu::BirdState& state, std::uint32_t frame,
                                               const gpu::BirdMotionGpu* motion = nullptr);

/// The route sample of a bird flown along `motion` (a driven bird): its position, velocity
/// and acceleration, the direction its velocity's, the lift its vertical acceleration, at
/// cruise speed (no take-off or landing).
[[nodiscard]] KODAWARI_API RouteSample motion_sample(const gpu::BirdMotionGpu& motion);

/// The route sample of a driven bird whose `motion` says KW_MOTION_ROUTE (the contract in
/// shared/birds.h, above BirdMotionGpu): its route (bird.ids.x) sampled as a route bird's,
/// at time frame * dt + motion.velocity.w and speed motion.acceleration.z, plus the cubic
/// Hermite correction from (motion.position.xyz, motion.velocity.xyz) at
/// t0 = motion.acceleration.x to 0 at t0 + T (1/T = motion.acceleration.y; 0: none) in
/// the position, velocity, attitude velocity and acceleration. Every exact quantity is the
/// route's. Without the bird's offset, which step_bird() adds as for a route bird.
[[nodiscard]] KODAWARI_API RouteSample route_motion_sample(const BirdWorld& world, const gpu::BirdParams& bird,
                                                          std::uint32_t frame, float dt, const gpu::BirdMotionGpu& motion);

/// A state before frame 0.
[[nodiscard]] KODAWARI_API gpu::BirdState initial_state();

}  // namespace kodawari::birds
