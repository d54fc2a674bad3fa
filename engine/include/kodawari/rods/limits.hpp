#pragma once
/// @file
/// Angle limits of a chain's joints: the cone, hinge and spherical limits of the
/// `VRMC_springBone_limit` 1.0 draft (vrm-c/vrm-specification), which constrain the
/// direction from a joint to its child. docs/models.md "Angle limits" says how they are
/// placed on a chain and which choices were made where the draft is silent.

#include <cstdint>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::rods {

/// Which limit a joint has (shaders/shared/rods.h KW_RODS_LIMIT_*).
enum class LimitKind : std::uint32_t {
    None = 0,
    /// At most `angle` from the limit's axis: a cone.
    Cone = 1,
    /// Turning only about the limit's X axis, at most `angle` from its axis: a hinge.
    Hinge = 2,
    /// At most `angle` of pitch (about X) and `yaw` of yaw (towards X) from its axis.
    Spherical = 3,
};

/// One joint's limit. Its frame: +Y along the joint's rest direction to its child (the
/// draft's shortest turn from +Y, a half turn about X when that direction is -Y), then
/// turned by `rotation`, all carried by the parent bone's current orientation (as the
/// draft's parent.worldRotation * localRotation).
struct AngleLimit {
    LimitKind kind = LimitKind::None;
    /// Cone and hinge: the angle, rad, in [0, pi]. Spherical: the pitch, rad, in [0, pi].
    float angle = 0.0f;
    /// Spherical: the yaw, rad, in [0, pi/2]. Unused by the others (0).
    float yaw = 0.0f;
    /// The limit's turn from its default frame, a unit quaternion.
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
};

/// The largest angle and yaw a limit takes, rad (the draft's clamps: pi and pi/2).
inline constexpr float kMaxLimitAngle = 3.14159265f;
inline constexpr float kMaxLimitYaw = 1.57079633f;

/// Checks `limit`'s ranges; errors name `what` and the field.
[[nodiscard]] KODAWARI_API Result<void> validate(const AngleLimit& limit, const std::string& what);

/// The nearest direction `limit` allows to unit `direction`, both in the limit's frame
/// (shaders/lib/spring_limit.glsl, the one definition every backend uses).
[[nodiscard]] KODAWARI_API glm::vec3 limit_direction(const AngleLimit& limit, glm::vec3 direction);

/// The same for a limit of `kind` given as limit_trig() (the solver's form).
[[nodiscard]] KODAWARI_API glm::vec3 limit_direction(LimitKind kind, const glm::vec4& trig, glm::vec3 direction);

/// `limit`'s angles as the kernels take them: (cos angle, sin angle, cos yaw, sin yaw).
[[nodiscard]] KODAWARI_API glm::vec4 limit_trig(const AngleLimit& limit);

/// The turn from +Y to a joint's limit frame in the joint's own frame: the shortest turn
/// from +Y to `bone_axis` (a half turn about X when it is -Y, as the draft says), then
/// the limit's `rotation`.
[[nodiscard]] KODAWARI_API glm::quat limit_frame(glm::vec3 bone_axis, const glm::quat& rotation);

}  // namespace kodawari::rods
