// Angle limits (kodawari/rods/limits.hpp): their checks, the kernels' constants, and the
// limited direction from the one definition rods_step.comp compiles too
// (shaders/lib/spring_limit.glsl), here over GLM.
#include "kodawari/rods/limits.hpp"

#include <cmath>
#include <string>

namespace kodawari::rods {

namespace glsl {
// GLSL's names for shaders/lib/spring_limit.glsl (inside this namespace only).
using namespace glm;
using uint = std::uint32_t;
#define KW_LIMIT_FN inline
#include "lib/spring_limit.glsl"
#undef KW_LIMIT_FN
}  // namespace glsl

Result<void> validate(const AngleLimit& limit, const std::string& what) {
    auto bad = [&](const std::string& field, const std::string& expected) {
        return make_error(Error::Kind::InvalidInput, what + "." + field + ": expected " + expected);
    };
    switch (limit.kind) {
        case LimitKind::None: return {};
        case LimitKind::Cone:
        case LimitKind::Hinge:
            if (!(limit.angle >= 0.0f && limit.angle <= kMaxLimitAngle)) return bad("angle", "an angle in [0, pi] rad");
            break;
        case LimitKind::Spherical:
            if (!(limit.angle >= 0.0f && limit.angle <= kMaxLimitAngle)) return bad("pitch", "an angle in [0, pi] rad");
            if (!(limit.yaw >= 0.0f && limit.yaw <= kMaxLimitYaw)) return bad("yaw", "an angle in [0, pi/2] rad");
            break;
        default: return bad("kind", "cone, hinge or spherical");
    }
    const glm::quat& q = limit.rotation;
    const float n2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
    // A unit quaternion as a file gives it (six digits): within 1e-4 of length 1.
    if (!(std::abs(n2 - 1.0f) <= 2e-4f)) return bad("rotation", "a unit quaternion [x, y, z, w]");
    return {};
}

glm::vec4 limit_trig(const AngleLimit& limit) {
    return {std::cos(limit.angle), std::sin(limit.angle), std::cos(limit.yaw), std::sin(limit.yaw)};
}

glm::vec3 limit_direction(const AngleLimit& limit, glm::vec3 direction) {
    return glsl::limit_direction(static_cast<std::uint32_t>(limit.kind), limit_trig(limit), direction);
}

glm::vec3 limit_direction(LimitKind kind, const glm::vec4& trig, glm::vec3 direction) {
    return glsl::limit_direction(static_cast<std::uint32_t>(kind), trig, direction);
}

glm::quat limit_frame(glm::vec3 bone_axis, const glm::quat& rotation) {
    // The draft's axisRotation: quaternion(cross(+Y, u); dot(+Y, u) + 1), normalized, and
    // a half turn about X where u is -Y (within float's resolution of a unit vector).
    const float w = bone_axis.y + 1.0f;
    const glm::quat axis_rotation = w <= 1e-6f ? glm::quat(0.0f, 1.0f, 0.0f, 0.0f)
                                               : glm::normalize(glm::quat(w, bone_axis.z, 0.0f, -bone_axis.x));
    return glm::normalize(axis_rotation * glm::normalize(rotation));
}

}  // namespace kodawari::rods
