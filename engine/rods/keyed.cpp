// Keyed examples' weights (docs/keyed-examples.md K.2-K.4), the reference every backend
// follows: shaders/rod_keys.comp and rods_step.comp mirror it expression for expression.
#include "kodawari/rods/keyed.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace kodawari::rods {
namespace {

glm::quat positive_w(glm::quat q) { return q.w < 0.0f ? -q : q; }

// The angular velocity that turns `last` into `now` over dt (K.2), world.
glm::vec3 angular_velocity(glm::quat last, glm::quat now, float dt) {
    const glm::quat dq = positive_w(now * glm::conjugate(last));
    const glm::vec3 axis(dq.x, dq.y, dq.z);
    const float sn = glm::length(axis);
    if (!(sn > 0.0f)) return glm::vec3(0.0f);
    return axis * (2.0f * std::atan2(sn, dq.w) / (sn * dt));
}

// exp(-(d / sigma)^2 / 2) with d^2 given: K.2 and K.3's weight.
float gaussian(float distance2, float sigma) { return std::exp(-0.5f * distance2 / (sigma * sigma)); }

}  // namespace

KeyState initial_key_state(std::span<const Transform> keys) {
    assert(keys.size() <= kMaxKeySources);
    KeyState s;
    for (std::size_t i = 0; i < keys.size(); ++i) s.sources[i].last = keys[i];
    return s;
}

KeyedWeights keyed_weights(std::span<const KeyedExample> examples, std::span<const KeySourceKind> sources,
                           std::span<const Transform> keys, float dt, KeyState& state, float teleport_distance) {
    assert(examples.size() <= kMaxKeyedExamples && sources.size() <= kMaxKeySources && keys.size() == sources.size());
    assert(dt > 0.0f);
    // K.2: the measures of every motion source; then the last poses move on.
    std::array<glm::vec3, kMaxKeySources> velocity{}, acceleration{}, spin{};
    for (std::size_t s = 0; s < sources.size(); ++s) {
        if (sources[s] != KeySourceKind::Motion) continue;
        KeyState::Source& src = state.sources[s];
        const glm::vec3 jump = keys[s].position - src.last.position;
        const bool teleport = teleported(src.last.position, keys[s].position, teleport_distance);
        spin[s] = angular_velocity(src.last.rotation, keys[s].rotation, dt);
        src.last = keys[s];
        if (teleport) {
            velocity[s] = src.velocity;  // 0 before any velocity
            continue;
        }
        velocity[s] = jump / dt;
        acceleration[s] = src.has_velocity ? (velocity[s] - src.velocity) / dt : glm::vec3(0.0f);
        src.velocity = velocity[s];
        src.has_velocity = true;
    }
    KeyedWeights u{};
    for (std::size_t j = 0; j < examples.size(); ++j) {
        const KeyedExample& e = examples[j];
        float distance2 = 0.0f;
        if (e.kind == KeyKind::Motion) {
            const std::uint32_t s = e.source;
            const glm::vec3 raw = e.measure == MotionMeasure::Speed          ? velocity[s]
                                  : e.measure == MotionMeasure::Acceleration ? acceleration[s]
                                                                             : spin[s];
            const glm::vec3 read =
                e.frame == MotionFrame::Joint ? glm::conjugate(keys[s].rotation) * raw : glm::vec3(glm::length(raw), 0.0f, 0.0f);
            const float alpha = e.smoothing > 0.0f ? 1.0f - std::exp(-dt / e.smoothing) : 1.0f;
            glm::vec3& m = state.smoothed[j];
            m += alpha * (read - m);
            const glm::vec3 key = e.frame == MotionFrame::Joint ? m : glm::vec3(std::min(m.x, e.saturation), 0.0f, 0.0f);
            const glm::vec3 d = key - e.value;
            distance2 = glm::dot(d, d);
        } else {
            for (std::uint32_t s = 0; s < sources.size(); ++s) {
                if ((e.source_mask & (1u << s)) == 0) continue;
                const float c = std::min(1.0f, std::abs(glm::dot(keys[s].rotation, e.rotations[s])));
                const float theta = 2.0f * std::acos(c);
                distance2 += theta * theta;
            }
        }
        u[j] = gaussian(distance2, e.influence);
    }
    return u;
}

void combine_weights(std::span<const float> view, std::span<const float> keyed, std::span<float> out) {
    assert(!view.empty() && out.size() >= view.size() + keyed.size());
    // K.4.
    float sum = 0.0f;
    for (const float u : keyed) sum += u;
    const bool whole = sum >= 1.0f;
    const float rest = 1.0f - (whole ? 1.0f : sum);
    for (std::size_t k = 0; k < view.size(); ++k) out[k] = rest * view[k];
    for (std::size_t j = 0; j < keyed.size(); ++j) out[view.size() + j] = whole ? keyed[j] / sum : keyed[j];
}

}  // namespace kodawari::rods
