// Evaluating glTF animations on the CPU (§3.11 Animations, Appendix C Interpolation of
// the glTF 2.0.1 specification) and composing world matrices (§3.5.3 Transformations).

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>

#include <glm/gtc/matrix_transform.hpp>

#include "kodawari/animation/character.hpp"

namespace kodawari::animation {
namespace {

// The key value of key k (CUBICSPLINE stores in-tangent, value, out-tangent per key).
glm::vec4 key_value(const Sampler& sampler, std::size_t k) {
    return sampler.interpolation == Interpolation::CubicSpline ? sampler.values[3 * k + 1] : sampler.values[k];
}

// Appendix C, spherical linear interpolation: along the shorter arc (the sign of one
// quaternion flipped when their dot product is negative). Computed in double so that
// the result is correctly rounded to float at midpoints.
glm::vec4 slerp(glm::vec4 a_in, glm::vec4 b_in, float u) {
    glm::dvec4 a(a_in);
    glm::dvec4 b(b_in);
    double d = glm::dot(a, b);
    if (d < 0.0) {
        b = -b;
        d = -d;
    }
    const double t = u;
    glm::dvec4 r;
    if (d > 1.0 - 1e-9) {
        // Nearly the same rotation: sin(theta) ~ 0, the arc is a straight line.
        r = glm::normalize(a * (1.0 - t) + b * t);
    } else {
        const double theta = std::acos(d);
        const double s = std::sin(theta);
        r = a * (std::sin((1.0 - t) * theta) / s) + b * (std::sin(t * theta) / s);
    }
    return glm::vec4(r);
}

}  // namespace

glm::vec4 sample(const Sampler& sampler, Path path, float time) {
    assert(!sampler.times.empty());
    const std::vector<float>& times = sampler.times;
    const std::size_t n = times.size();
    // Outside the keys the first / last value holds (§3.11: clamped, no extrapolation).
    // `!(time > first)` also sends NaN to the first key.
    if (!(time > times.front())) return key_value(sampler, 0);
    if (time >= times.back()) return key_value(sampler, n - 1);
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), time) - times.begin()) - 1;
    if (time == times[k] || sampler.interpolation == Interpolation::Step) return key_value(sampler, k);
    const double td = static_cast<double>(times[k + 1]) - static_cast<double>(times[k]);
    const double u = (static_cast<double>(time) - static_cast<double>(times[k])) / td;
    if (sampler.interpolation == Interpolation::Linear) {
        if (path == Path::Rotation) return slerp(key_value(sampler, k), key_value(sampler, k + 1), static_cast<float>(u));
        const glm::dvec4 a(key_value(sampler, k));
        const glm::dvec4 b(key_value(sampler, k + 1));
        return glm::vec4(a + (b - a) * u);
    }
    // Appendix C, cubic spline: Hermite on [t_k, t_k+1] with the key values v_k, v_k+1,
    // the out-tangent b_k of key k and the in-tangent a_k+1 of key k+1, tangents scaled
    // by the keyframe delta t_d.
    const glm::dvec4 p0(sampler.values[3 * k + 1]);
    const glm::dvec4 m0 = glm::dvec4(sampler.values[3 * k + 2]) * td;
    const glm::dvec4 p1(sampler.values[3 * (k + 1) + 1]);
    const glm::dvec4 m1 = glm::dvec4(sampler.values[3 * (k + 1)]) * td;
    const double u2 = u * u;
    const double u3 = u2 * u;
    glm::dvec4 v = (2.0 * u3 - 3.0 * u2 + 1.0) * p0 + (u3 - 2.0 * u2 + u) * m0 + (-2.0 * u3 + 3.0 * u2) * p1 +
                   (u3 - u2) * m1;
    // The spline of unit quaternions leaves the unit sphere; Appendix C normalizes.
    if (path == Path::Rotation) {
        const double len = glm::length(v);
        if (len > 0.0) v /= len;
    }
    return glm::vec4(v);
}

void compute_world(const Character& character, Pose& pose) {
    const std::size_t n = character.nodes.size();
    pose.world.resize(n);
    for (const int index : character.order) {
        const auto i = static_cast<std::size_t>(index);
        const Node& node = character.nodes[i];
        // §3.5.3: local = T * R * S, or the node's matrix.
        const glm::mat4 local = node.matrix ? *node.matrix
                                            : glm::translate(glm::mat4(1.0f), pose.translation[i]) *
                                                  glm::mat4_cast(pose.rotation[i]) *
                                                  glm::scale(glm::mat4(1.0f), pose.scale[i]);
        pose.world[i] = node.parent >= 0 ? pose.world[static_cast<std::size_t>(node.parent)] * local : local;
    }
}

Pose rest_pose(const Character& character) {
    Pose pose;
    for (const Node& node : character.nodes) {
        pose.translation.push_back(node.translation);
        pose.rotation.push_back(node.rotation);
        pose.scale.push_back(node.scale);
    }
    compute_world(character, pose);
    return pose;
}

void evaluate(const Character& character, std::size_t animation, float time, Pose& pose) {
    assert(animation < character.animations.size());
    const std::size_t n = character.nodes.size();
    pose.translation.resize(n);
    pose.rotation.resize(n);
    pose.scale.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        pose.translation[i] = character.nodes[i].translation;
        pose.rotation[i] = character.nodes[i].rotation;
        pose.scale[i] = character.nodes[i].scale;
    }
    const Animation& clip = character.animations[animation];
    for (const Channel& channel : clip.channels) {
        const glm::vec4 v = sample(clip.samplers[channel.sampler], channel.path, time);
        const auto i = static_cast<std::size_t>(channel.node);
        switch (channel.path) {
            case Path::Translation: pose.translation[i] = glm::vec3(v); break;
            case Path::Rotation: pose.rotation[i] = glm::quat(v.w, v.x, v.y, v.z); break;
            case Path::Scale: pose.scale[i] = glm::vec3(v); break;
        }
    }
    compute_world(character, pose);
}

rods::Transform rigid_part(const glm::mat4& world) {
    rods::Transform t;
    t.position = glm::vec3(world[3]);
    glm::mat3 r(world);
    for (int c = 0; c < 3; ++c) {
        const float len = glm::length(r[c]);
        if (len > 0.0f) r[c] /= len;
    }
    if (glm::determinant(r) < 0.0f) r[0] = -r[0];  // a mirror: keep a proper rotation
    t.rotation = glm::normalize(glm::quat_cast(r));
    return t;
}

}  // namespace kodawari::animation
