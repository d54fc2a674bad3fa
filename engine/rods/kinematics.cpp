// Procedural character motion and camera motion (SPEC A.1, A.3, C): closed-form
// functions of time, so a frame never depends on the frames before it.
#include "kodawari/rods/kinematics.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <numbers>

namespace kodawari::rods {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double smoothstep(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// The time integral of a locomotion's envelope from its start to `tau` seconds after
// it: how far (in units of `speed`) the character has gone. Piecewise: a quadratic
// ramp in, a line, a quadratic ramp out, then constant.
double envelope_integral(const Locomotion& m, double tau) {
    if (!(tau > 0.0)) return 0.0;
    const double a = m.ramp_in;
    const double b = m.ramp_out;
    const double d = static_cast<double>(m.end) - static_cast<double>(m.start);  // may be +inf
    if (tau < a) return tau * tau / (2.0 * a);
    if (tau <= d - b) return 0.5 * a + (tau - a);
    if (tau < d) {
        const double left = d - tau;
        return 0.5 * a + (d - b - a) + (b * b - left * left) / (2.0 * b);
    }
    return d - 0.5 * (a + b);
}

double envelope(const Locomotion& m, double tau) {
    const double d = static_cast<double>(m.end) - static_cast<double>(m.start);
    const double a = m.ramp_in;
    const double b = m.ramp_out;
    if (!(tau >= 0.0) || !(tau < d)) return 0.0;
    if (tau < a) return tau / a;
    if (tau > d - b) return (d - tau) / b;
    return 1.0;
}

glm::quat yaw(float angle) { return glm::angleAxis(angle, glm::vec3(0.0f, 1.0f, 0.0f)); }

// Catmull-Rom tangent of a key (per second), from its neighbours' values: one-sided at
// the ends of an open sequence, wrapped for a loop (whose last key repeats the first).
template <typename Get>
glm::vec3 key_tangent(std::span<const CameraKey> keys, std::size_t k, bool loop, Get get) {
    const std::size_t n = keys.size();
    const double period = static_cast<double>(keys[n - 1].time) - static_cast<double>(keys[0].time);
    glm::vec3 before = get(keys[k]);
    glm::vec3 after = before;
    double t_before = keys[k].time;
    double t_after = keys[k].time;
    if (k > 0) {
        before = get(keys[k - 1]);
        t_before = keys[k - 1].time;
    } else if (loop && n > 2) {
        before = get(keys[n - 2]);
        t_before = static_cast<double>(keys[n - 2].time) - period;
    }
    if (k + 1 < n) {
        after = get(keys[k + 1]);
        t_after = keys[k + 1].time;
    } else if (loop && n > 2) {
        after = get(keys[1]);
        t_after = static_cast<double>(keys[1].time) + period;
    }
    const double span = t_after - t_before;
    if (!(span > 0.0)) return glm::vec3(0.0f);
    return (after - before) / static_cast<float>(span);
}

template <typename Get>
glm::vec3 interpolate_keys(std::span<const CameraKey> keys, double t, std::size_t segment, Interpolation mode, bool loop,
                           Get get) {
    const CameraKey& k0 = keys[segment];
    const CameraKey& k1 = keys[segment + 1];
    const double h = static_cast<double>(k1.time) - static_cast<double>(k0.time);
    const float u = static_cast<float>(std::clamp((t - static_cast<double>(k0.time)) / h, 0.0, 1.0));
    const glm::vec3 p0 = get(k0);
    const glm::vec3 p1 = get(k1);
    if (mode == Interpolation::Linear) return p0 + u * (p1 - p0);
    // Cubic Hermite with Catmull-Rom tangents scaled to the segment's duration.
    const glm::vec3 m0 = key_tangent(keys, segment, loop, get) * static_cast<float>(h);
    const glm::vec3 m1 = key_tangent(keys, segment + 1, loop, get) * static_cast<float>(h);
    const float u2 = u * u;
    const float u3 = u2 * u;
    return (2.0f * u3 - 3.0f * u2 + 1.0f) * p0 + (u3 - 2.0f * u2 + u) * m0 + (-2.0f * u3 + 3.0f * u2) * p1 +
           (u3 - u2) * m1;
}

}  // namespace

float locomotion_envelope(const Locomotion& motion, float time) {
    return static_cast<float>(envelope(motion, static_cast<double>(time) - static_cast<double>(motion.start)));
}

LocomotionPose evaluate_locomotion(std::span<const Locomotion> motions, float time) {
    LocomotionPose out;
    for (const Locomotion& m : motions) {
        const double tau = static_cast<double>(time) - static_cast<double>(m.start);
        const double distance = envelope_integral(m, tau);  // s, times speed = metres
        const double psi = static_cast<double>(m.turn_rate) * distance;
        Transform step;
        if (m.turn_rate == 0.0f) {
            step.position = glm::vec3(0.0f, 0.0f, static_cast<float>(static_cast<double>(m.speed) * distance));
        } else {
            // The circle of radius speed / turn_rate: the integral of e(t) (sin psi, 0, cos psi)
            // with psi = turn_rate * E(t) is (1 - cos psi, 0, sin psi) / turn_rate whatever
            // the envelope's shape; 2 sin^2(psi/2) keeps small turns precise.
            const double r = static_cast<double>(m.speed) / static_cast<double>(m.turn_rate);
            const double half = std::sin(0.5 * psi);
            step.position = glm::vec3(static_cast<float>(r * 2.0 * half * half), 0.0f, static_cast<float>(r * std::sin(psi)));
        }
        step.rotation = yaw(static_cast<float>(psi));
        out.frame = compose(out.frame, step);
        const double e = envelope(m, tau);
        if (e > 0.0) {
            const double phase = std::numbers::pi * static_cast<double>(m.step_frequency) * tau;
            out.bob += static_cast<float>(static_cast<double>(m.bob) * 0.5 * (1.0 - std::cos(2.0 * phase)) * e);
            out.roll += static_cast<float>(static_cast<double>(m.roll) * std::sin(phase) * e);
        }
    }
    return out;
}

float oscillation_angle(const Oscillation& m, float time) {
    const double t = time;
    if (!(t >= static_cast<double>(m.start) && t < static_cast<double>(m.end))) return 0.0f;
    double env = 1.0;
    if (m.fade > 0.0f) {
        env = smoothstep((t - static_cast<double>(m.start)) / static_cast<double>(m.fade));
        if (std::isfinite(m.end)) env = std::min(env, smoothstep((static_cast<double>(m.end) - t) / static_cast<double>(m.fade)));
    }
    // Double precision: after an hour at a few hertz a float phase would be coarse.
    double s = std::sin(kTwoPi * static_cast<double>(m.frequency) * (t - static_cast<double>(m.start)) +
                        static_cast<double>(m.phase));
    if (m.sharpness > 0.0f) {
        const double k = m.sharpness;
        s = std::tanh(k * s) / std::tanh(k);
    }
    return static_cast<float>(static_cast<double>(m.amplitude) * s * env);
}

Transform compose(const Transform& parent, const Transform& local) {
    return Transform{parent.position + parent.rotation * local.position, parent.rotation * local.rotation};
}

void pose_skeleton(const Skeleton& skeleton, const CharacterMotion& motion, const Transform& placement, float time,
                   std::span<Transform> out) {
    const std::size_t n = skeleton.joints.size();
    assert(n >= 1 && n <= kMaxSkeletonJoints && out.size() >= n);
    const LocomotionPose moved = evaluate_locomotion(motion.locomotions, time);
    const Transform character = compose(placement, moved.frame);
    std::array<glm::quat, kMaxSkeletonJoints> turn;
    std::fill_n(turn.begin(), n, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    for (const Oscillation& o : motion.oscillations) {
        assert(o.joint < n);
        turn[o.joint] = turn[o.joint] * glm::angleAxis(oscillation_angle(o, time), o.axis);
    }
    for (std::size_t j = 0; j < n; ++j) {
        const SkeletonJoint& joint = skeleton.joints[j];
        Transform local = joint.rest;
        local.rotation = local.rotation * turn[j];
        const Transform* parent = &character;
        if (joint.parent < 0) {
            // The gait moves the root joint in the character frame: up, and rolled about
            // the walking direction (+Z).
            local.position.y += moved.bob;
            local.rotation = glm::angleAxis(moved.roll, glm::vec3(0.0f, 0.0f, 1.0f)) * local.rotation;
        } else {
            assert(static_cast<std::size_t>(joint.parent) < j);
            parent = &out[static_cast<std::size_t>(joint.parent)];
        }
        out[j] = compose(*parent, local);
        // Products of many rotations drift off unit length; the rod frame checks it.
        out[j].rotation = glm::normalize(out[j].rotation);
    }
}

CameraPose camera_pose(const CameraMotion& motion, float time) {
    CameraPose pose;
    pose.projection = motion.projection;
    switch (motion.kind) {
        case CameraMotion::Kind::Fixed:
            pose.position = motion.position;
            pose.target = motion.target;
            break;
        case CameraMotion::Kind::Orbit: {
            const double a = static_cast<double>(motion.start_angle) + static_cast<double>(motion.rate) * static_cast<double>(time);
            pose.target = motion.target;
            pose.position = motion.target + glm::vec3(static_cast<float>(static_cast<double>(motion.radius) * std::sin(a)),
                                                      motion.height,
                                                      static_cast<float>(static_cast<double>(motion.radius) * std::cos(a)));
            break;
        }
        case CameraMotion::Kind::Keyframes: {
            const std::span<const CameraKey> keys(motion.keys);
            assert(!keys.empty());
            double t = time;
            const double first = keys.front().time;
            const double last = keys.back().time;
            if (motion.loop && last > first) {
                t = first + std::fmod(t - first, last - first);
                if (t < first) t += last - first;
            }
            if (keys.size() == 1 || t <= first) {
                pose.position = keys.front().position;
                pose.target = keys.front().target;
            } else if (t >= last) {
                pose.position = keys.back().position;
                pose.target = keys.back().target;
            } else {
                // The segment whose start is the last key time <= t.
                const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                                    [](double value, const CameraKey& k) { return value < static_cast<double>(k.time); });
                const auto segment = static_cast<std::size_t>(after - keys.begin()) - 1;
                pose.position = interpolate_keys(keys, t, segment, motion.interpolation, motion.loop,
                                                 [](const CameraKey& k) { return k.position; });
                pose.target = interpolate_keys(keys, t, segment, motion.interpolation, motion.loop,
                                               [](const CameraKey& k) { return k.target; });
            }
            break;
        }
    }
    const glm::vec3 look = pose.target - pose.position;
    const float length = glm::length(look);
    if (length > 1e-6f && std::isfinite(length)) pose.forward = look / length;
    return pose;
}

}  // namespace kodawari::rods
