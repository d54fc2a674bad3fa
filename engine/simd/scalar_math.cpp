// See scalar_math.hpp: the reference's own expressions, lane by lane.
#include "simd/scalar_math.hpp"

#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/birds/flight.hpp"

namespace kodawari::simd {

void pow_lanes(const float* base, float exponent, float* out, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) out[i] = std::pow(base[i], exponent);
}

namespace {

// engine/rods/solver.cpp partial(), verbatim: the rotation by `fraction` of q's angle.
glm::quat partial(glm::quat q, float fraction) {
    constexpr glm::quat kIdentity{1.0f, 0.0f, 0.0f, 0.0f};
    if (fraction >= 1.0f) return q;
    if (fraction <= 0.0f) return kIdentity;
    q = q.w < 0.0f ? -q : q;
    const glm::vec3 v(q.x, q.y, q.z);
    const float sn = glm::length(v);
    if (!(sn > 0.0f)) return kIdentity;
    const float half = fraction * std::atan2(sn, q.w);
    const glm::vec3 axis = v / sn;
    return glm::normalize(glm::quat(std::cos(half), std::sin(half) * axis.x, std::sin(half) * axis.y, std::sin(half) * axis.z));
}

birds::RouteSample sample_of(const float* motion, std::size_t stride, std::size_t i) {
    birds::RouteSample s;
    s.velocity = {motion[0 * stride + i], motion[1 * stride + i], motion[2 * stride + i]};
    s.acceleration = {motion[3 * stride + i], motion[4 * stride + i], motion[5 * stride + i]};
    s.attitude_velocity = s.velocity;  // the caller passes the attitude velocity
    return s;
}

}  // namespace

void partial_lanes(float* q, std::size_t stride, float fraction, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
        const glm::quat r = partial(glm::quat(q[3 * stride + i], q[i], q[stride + i], q[2 * stride + i]), fraction);
        q[i] = r.x;
        q[stride + i] = r.y;
        q[2 * stride + i] = r.z;
        q[3 * stride + i] = r.w;
    }
}

void seed_bank_lanes(const gpu::FlightUniforms& uniforms, const float* motion, std::size_t stride, float* rotation,
                     std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
        const gpu::vec4 r = birds::body_frame(uniforms, sample_of(motion, stride, i)).bank;
        rotation[i] = r.x;
        rotation[stride + i] = r.y;
        rotation[2 * stride + i] = r.z;
        rotation[3 * stride + i] = r.w;
    }
}

void half_angle_lanes(const float* z, const float* w, float* angle, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) angle[i] = 2.0f * std::atan2(z[i], w[i]);
}

void attitude_lanes(const gpu::FlightUniforms& uniforms, const float* motion, std::size_t stride, float* angles,
                    std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
        const birds::Attitude a = birds::attitude(uniforms, sample_of(motion, stride, i));
        angles[i] = a.yaw;
        angles[stride + i] = a.pitch;
        angles[2 * stride + i] = a.bank;
    }
}

}  // namespace kodawari::simd
