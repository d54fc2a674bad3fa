// The scalar reference of the bird engine. Single precision throughout, in the same
// order of operations as shaders/birds_flap.comp, so the two agree to rounding.
#include "kodawari/birds/flight.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace kodawari::birds {
namespace {

constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;
constexpr float kHalfPi = 0.5f * std::numbers::pi_v<float>;

Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator*(float s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
float length(Vec3 a) { return std::sqrt(dot(a, a)); }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec3 xyz(const gpu::vec4& v) { return {v.x, v.y, v.z}; }

// Quaternions as gpu::vec4 (x, y, z, w), glTF order.
gpu::vec4 quat_mul(const gpu::vec4& a, const gpu::vec4& b) {
    return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
gpu::vec4 quat_y(float angle) { return {0.0f, std::sin(0.5f * angle), 0.0f, std::cos(0.5f * angle)}; }
gpu::vec4 quat_z(float angle) { return {0.0f, 0.0f, std::sin(0.5f * angle), std::cos(0.5f * angle)}; }
float quat_dot(const gpu::vec4& a, const gpu::vec4& b) { return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w; }
gpu::vec4 quat_normalize(const gpu::vec4& q) {
    const float inv = 1.0f / std::sqrt(quat_dot(q, q));
    return {q.x * inv, q.y * inv, q.z * inv, q.w * inv};
}
// Reflection of the rig through the body's YZ plane: the right wing mirrors the left.
gpu::vec4 quat_mirror_x(const gpu::vec4& q) { return {q.x, -q.y, -q.z, q.w}; }

// Arm rotation: heading about the body's up axis, then pitch about its forward axis
// (SPEC B.2 axes).
gpu::vec4 arm_rotation(float pitch, float heading) { return quat_mul(quat_z(pitch), quat_y(heading)); }

// Bezier segment `seg` of `route` at local parameter u: point and the two derivatives
// (SPEC B.3, eqs. P, P', P'').
struct Bezier {
    Vec3 p, d1, d2;
};
Bezier bezier(const BirdWorld& world, const gpu::RouteHeader& route, std::uint32_t seg, float u) {
    const gpu::vec4* c = &world.control_points[route.extent.x + 3 * seg];
    const Vec3 b0 = xyz(c[0]), b1 = xyz(c[1]), b2 = xyz(c[2]), b3 = xyz(c[3]);
    const float v = 1.0f - u;
    Bezier r;
    r.p = (v * v * v) * b0 + (3.0f * u * v * v) * b1 + (3.0f * u * u * v) * b2 + (u * u * u) * b3;
    r.d1 = 3.0f * ((v * v) * (b1 - b0) + (2.0f * u * v) * (b2 - b1) + (u * u) * (b3 - b2));
    r.d2 = 6.0f * (v * (b2 - 2.0f * b1 + b0) + u * (b3 - 2.0f * b2 + b1));
    return r;
}

Bezier bezier_global(const BirdWorld& world, const gpu::RouteHeader& route, float u) {
    const std::uint32_t n = route.extent.y;
    const std::uint32_t seg = std::min(static_cast<std::uint32_t>(std::max(u, 0.0f)), n - 1);
    return bezier(world, route, seg, u - static_cast<float>(seg));
}

}  // namespace

float route_parameter_at(const BirdWorld& world, std::uint32_t route_index, float s) {
    const gpu::RouteHeader& route = world.routes[route_index];
    const gpu::ArcSample* table = &world.arc_samples[route.extent.z];
    std::uint32_t lo = 0, hi = route.extent.w - 1;
    while (hi - lo > 1) {
        const std::uint32_t mid = (lo + hi) / 2;
        if (table[mid].s_u_duds.x <= s) lo = mid; else hi = mid;
    }
    // Cubic Hermite interpolation of u(s) with exact end derivatives du/ds = 1/|P'(u)|.
    const gpu::vec4 a = table[lo].s_u_duds, b = table[hi].s_u_duds;
    const float h = b.x - a.x;
    const float t = std::clamp((s - a.x) * table[lo].next.x, 0.0f, 1.0f);
    const float t2 = t * t, t3 = t2 * t;
    return (2.0f * t3 - 3.0f * t2 + 1.0f) * a.y + (t3 - 2.0f * t2 + t) * h * a.w + (-2.0f * t3 + 3.0f * t2) * b.y +
           (t3 - t2) * h * b.z;
}

RouteSample sample_route(const BirdWorld& world, std::uint32_t route_index, float time, float speed) {
    const gpu::RouteHeader& route = world.routes[route_index];
    const bool loop = (route.flags.x & KW_ROUTE_LOOP) != 0;
    const float n = static_cast<float>(route.extent.y);
    RouteSample out;
    if ((route.flags.x & KW_ROUTE_PARAMETRIC) != 0) {
        // The seed's timing: u advances uniformly with time, one segment per duration D.
        const float duration = route.info.y;
        float u = time * route.info.w;
        if (loop) {  // u mod n without a division
            const float whole = std::floor(u);
            int wrapped = static_cast<int>(whole) % static_cast<int>(route.extent.y);
            if (wrapped < 0) wrapped += static_cast<int>(route.extent.y);
            u = static_cast<float>(wrapped) + (u - whole);
        }
        if (u < 0.0f || u > n) {  // past the ends: fly on straight at the end velocity
            const float end = u < 0.0f ? 0.0f : n;
            const Bezier e = bezier_global(world, route, end);
            out.position = e.p + (u - end) * e.d1;
            out.velocity = route.info.w * e.d1;
            out.direction = e.d1;
            return out;
        }
        const Bezier e = bezier_global(world, route, u);
        out.position = e.p;
        out.velocity = route.info.w * e.d1;
        out.acceleration = (route.info.w * route.info.w) * e.d2;
        out.direction = e.d1;
        out.lift = e.d2.y;  // a_y = P''_y / D^2
        out.lift_scale = duration * duration;
        return out;
    }
    // Arc-length timing (SPEC B.3): distance = speed * time.
    const float total = route.info.x;
    float s = speed * time;
    if (loop) s = s - total * std::floor(s * route.info.z);
    if (s < 0.0f || s > total) {
        const float end_s = s < 0.0f ? 0.0f : total;
        const Bezier e = bezier_global(world, route, s < 0.0f ? 0.0f : n);
        const Vec3 tangent = (1.0f / length(e.d1)) * e.d1;
        out.position = e.p + (s - end_s) * tangent;
        out.velocity = speed * tangent;
        out.direction = e.d1;
        return out;
    }
    const Bezier e = bezier_global(world, route, route_parameter_at(world, route_index, s));
    const float d1_len = length(e.d1);
    const Vec3 tangent = (1.0f / d1_len) * e.d1;
    out.position = e.p;
    out.velocity = speed * tangent;
    // At constant speed only the normal part of P'' remains: a = v^2 (P'' - (P''.T)T) / |P'|^2.
    out.acceleration = ((speed * speed) / (d1_len * d1_len)) * (e.d2 - dot(e.d2, tangent) * tangent);
    out.direction = e.d1;
    // The same a_y without square roots: v^2 (P''_y |P'|^2 - (P''.P') P'_y) / |P'|^4.
    const float dd = e.d1.x * e.d1.x + e.d1.y * e.d1.y + e.d1.z * e.d1.z;
    const float d2d1 = e.d2.x * e.d1.x + e.d2.y * e.d1.y + e.d2.z * e.d1.z;
    out.lift = (speed * speed) * (e.d2.y * dd - d2d1 * e.d1.y);
    out.lift_scale = dd * dd;
    return out;
}

Attitude attitude(const gpu::FlightUniforms& uniforms, const RouteSample& sample) {
    const Vec3 v = sample.velocity, a = sample.acceleration;
    Attitude att;
    const float horizontal = std::sqrt(v.x * v.x + v.z * v.z);
    if (horizontal <= 0.0f && v.y == 0.0f) return att;
    // SPEC B.4: heading from the horizontal velocity (+Z forward, +Y up); the climb angle
    // asin(v_y / |v|), as atan2, which stays accurate near vertical flight.
    att.yaw = std::atan2(v.x, v.z);
    att.pitch = std::atan2(v.y, horizontal);
    const float max_bank = uniforms.physics.y;
    if (uniforms.rules.x == KW_BANK_SEED) {
        // The seed's eq. 4.9: theta = acos(a.v / |a||v|) - pi/2, as atan2(|v x a|, v.a),
        // sign flipped when the up component of v x a is positive.
        const Vec3 c = cross(v, a);
        if (length(a) <= 0.0f) return att;
        float bank = std::atan2(length(c), dot(v, a)) - kHalfPi;
        if (c.y > 0.0f) bank = -bank;
        att.bank = std::clamp(bank, -max_bank, max_bank);
        return att;
    }
    // Coordinated turn: tan(bank) = a_lat / g, a_lat toward the bird's right (-X body).
    if (horizontal <= 1e-6f * std::fabs(v.y)) return att;
    const Vec3 right = (1.0f / horizontal) * Vec3{-v.z, 0.0f, v.x};
    att.bank = std::clamp(std::atan2(dot(a, right), uniforms.physics.x), -max_bank, max_bank);
    return att;
}

namespace {

// (cos(x/2), sin(x/2)) from (cos x, sin x) of an angle with cos x >= 0, without trig.
void half_angle(float c, float s, float& half_c, float& half_s) {
    half_c = std::sqrt(0.5f * (1.0f + c));
    half_s = s / (2.0f * half_c);
}

}  // namespace

gpu::vec4 body_rotation(const gpu::FlightUniforms& uniforms, const RouteSample& sample) {
    // The rotation of attitude(): yaw about +Y, climb about -X, bank about +Z, built from
    // the sines and cosines the velocity and acceleration give directly (no atan2, sin or
    // cos: the largest arithmetic cost of the kernel).
    const Vec3 v = sample.velocity, a = sample.acceleration;
    const float horizontal = std::sqrt(v.x * v.x + v.z * v.z);
    const float speed = std::sqrt(horizontal * horizontal + v.y * v.y);
    if (speed <= 0.0f) return {0.0f, 0.0f, 0.0f, 1.0f};
    gpu::vec4 yaw{0.0f, 0.0f, 0.0f, 1.0f};
    if (horizontal > 0.0f) {
        const float c = v.z / horizontal, s = v.x / horizontal;
        if (c >= 0.0f) {
            half_angle(c, s, yaw.w, yaw.y);
        } else {  // near 180 degrees the half sine is the stable one
            yaw.y = std::copysign(std::sqrt(0.5f * (1.0f - c)), s);
            yaw.w = s / (2.0f * yaw.y);
        }
    }
    gpu::vec4 pitch{0.0f, 0.0f, 0.0f, 1.0f};
    half_angle(horizontal / speed, -v.y / speed, pitch.w, pitch.x);
    gpu::vec4 bank{0.0f, 0.0f, 0.0f, 1.0f};
    float bc = 1.0f, bs = 0.0f;
    if (uniforms.rules.x == KW_BANK_SEED) {
        const Attitude att = attitude(uniforms, sample);
        bc = std::cos(att.bank);
        bs = std::sin(att.bank);
    } else if (horizontal > 1e-6f * std::fabs(v.y)) {
        // tan(bank) = a_lat / g, clamped to the maximum bank.
        const float lateral = (a.x * -v.z + a.z * v.x) / horizontal;
        const float g = uniforms.physics.x;
        const float norm = std::sqrt(lateral * lateral + g * g);
        bc = g / norm;
        bs = lateral / norm;
        if (bc < uniforms.bank_limit.x) {
            bc = uniforms.bank_limit.x;
            bs = std::copysign(uniforms.bank_limit.y, lateral);
        }
    }
    half_angle(bc, bs, bank.w, bank.z);
    return quat_mul(quat_mul(yaw, pitch), bank);
}

std::uint32_t next_mode(const gpu::FlightUniforms& uniforms, std::uint32_t previous, const RouteSample& sample) {
    if (uniforms.rules.y == KW_MODE_RULE_SEED) {
        // The seed's rule: vertical acceleration against a fixed threshold, no memory.
        const float threshold = uniforms.blend_rates.w * sample.lift_scale;
        if (sample.lift > threshold) return KW_MODE_ASCEND;
        if (sample.lift < -threshold) return KW_MODE_DESCEND;
        return KW_MODE_LEVEL;
    }
    // Climb angle g with hysteresis (SPEC B.5): enter a mode past its enter threshold,
    // leave it only past its exit threshold. g > g0 <=> sin(g)|sin(g)| > sin(g0)|sin(g0)|,
    // and sin(g)|sin(g)| = P'_y |P'_y| / |P'|^2: compared without dividing.
    const Vec3 d = sample.direction;
    const float dd = d.x * d.x + d.y * d.y + d.z * d.z;
    const float climb = d.y * std::fabs(d.y);
    auto above = [&](float k) { return climb > k * dd; };
    auto below = [&](float k) { return climb < k * dd; };
    const float ascend_enter = uniforms.climb.x, ascend_exit = uniforms.climb.y;
    const float descend_enter = uniforms.climb.z, descend_exit = uniforms.climb.w;
    std::uint32_t mode = previous;
    if (mode == KW_MODE_ASCEND && below(ascend_exit)) mode = KW_MODE_LEVEL;
    if (mode == KW_MODE_DESCEND && above(descend_exit)) mode = KW_MODE_LEVEL;
    if (mode == KW_MODE_LEVEL || mode == KW_MODE_UNSET) {
        mode = above(ascend_enter) ? KW_MODE_ASCEND : below(descend_enter) ? KW_MODE_DESCEND : KW_MODE_LEVEL;
    }
    return mode;
}

gpu::BirdState initial_state() {
    gpu::BirdState state{};
    state.blend = {1.0f, 0.0f, 0.0f, 1.0f};
    state.mode = {KW_MODE_UNSET, 0, 0, 0};
    return state;
}

BirdFrame step_bird(const BirdWorld& world, const gpu::FlightUniforms& uniforms, const gpu::BirdParams& bird,
                    gpu::BirdState& state, std::uint32_t frame) {
    const float dt = uniforms.physics.z;
    const bool first = state.mode.x == KW_MODE_UNSET;

    // Wingbeat phase in cycles, advanced per frame at the bird's constant frequency
    // (SPEC B.2); kept in [0, 1) so its precision does not decay over long runs.
    float phase = first ? bird.motion.w : state.phase.x + bird.motion.y * dt;
    phase = phase - std::floor(phase);
    state.phase.x = phase;

    const float time = static_cast<float>(frame) * dt + bird.offset.w;
    RouteSample sample = sample_route(world, bird.ids.x, time, bird.motion.x);
    const Attitude att = attitude(uniforms, sample);

    // Mode and transition (SPEC B.5, B.6). The blend source is a weighted sum of the
    // three mode poses, so a change during a transition starts exactly from the
    // current blended pose.
    const std::uint32_t mode = next_mode(uniforms, state.mode.x, sample);
    if (first) {
        state.blend = {mode == KW_MODE_LEVEL ? 1.0f : 0.0f, mode == KW_MODE_ASCEND ? 1.0f : 0.0f,
                       mode == KW_MODE_DESCEND ? 1.0f : 0.0f, 1.0f};
    } else if (mode != state.mode.x) {
        const float alpha = state.blend.w;
        const std::uint32_t old = state.mode.x;
        state.blend = {(1.0f - alpha) * state.blend.x + (old == KW_MODE_LEVEL ? alpha : 0.0f),
                       (1.0f - alpha) * state.blend.y + (old == KW_MODE_ASCEND ? alpha : 0.0f),
                       (1.0f - alpha) * state.blend.z + (old == KW_MODE_DESCEND ? alpha : 0.0f), 0.0f};
    } else if (state.blend.w < 1.0f) {
        // The seed's per-frame rates, applied per 1/60 s of simulated time.
        const float rate = mode == KW_MODE_LEVEL ? uniforms.blend_rates.x
                           : mode == KW_MODE_ASCEND ? uniforms.blend_rates.y
                                                    : uniforms.blend_rates.z;
        state.blend.w += rate * uniforms.physics.w;
        if (state.blend.w >= 1.0f) {
            state.blend = {mode == KW_MODE_LEVEL ? 1.0f : 0.0f, mode == KW_MODE_ASCEND ? 1.0f : 0.0f,
                           mode == KW_MODE_DESCEND ? 1.0f : 0.0f, 1.0f};
        }
    }
    state.mode.x = mode;

    float t = phase * kTwoPi;
    if (t >= kTwoPi) t = 0.0f;
    const float amplitude = bird.motion.z;
    WingAngles poses[3];
    gpu::vec4 arm1[3], arm2[3];
    for (std::uint32_t m = 0; m < 3; ++m) {
        poses[m] = wing_angles(static_cast<FlightMode>(m), t, amplitude);
        arm1[m] = arm_rotation(poses[m].arm1_pitch, poses[m].arm1_heading);
        arm2[m] = arm_rotation(poses[m].arm2_pitch, poses[m].arm2_heading);
    }
    // SPEC B.6: Q = ((1-a) Qa + a Qb) / |...|, Qa the blend source, each term flipped
    // into the target's hemisphere. Outside a transition (a = 1) Q is the target pose.
    const float weights[3] = {state.blend.x, state.blend.y, state.blend.z};
    const float alpha = state.blend.w;
    auto blend = [&](const gpu::vec4* q) {
        const gpu::vec4& target = q[mode];
        if (alpha >= 1.0f) return target;
        gpu::vec4 sum{alpha * target.x, alpha * target.y, alpha * target.z, alpha * target.w};
        for (std::uint32_t m = 0; m < 3; ++m) {
            const float w = (1.0f - alpha) * weights[m] * (quat_dot(q[m], target) < 0.0f ? -1.0f : 1.0f);
            sum = {sum.x + w * q[m].x, sum.y + w * q[m].y, sum.z + w * q[m].z, sum.w + w * q[m].w};
        }
        return quat_normalize(sum);
    };
    const gpu::vec4 left1 = blend(arm1), left2 = blend(arm2);

    BirdFrame out{};
    const Vec3 position = sample.position + xyz(bird.offset);
    out.pose.position = {position.x, position.y, position.z, 0.0f};
    out.pose.rotation[KW_PART_BODY] = body_rotation(uniforms, sample);
    out.pose.rotation[KW_PART_HEAD] = {0.0f, 0.0f, 0.0f, 1.0f};
    out.pose.rotation[KW_PART_TAIL] = {0.0f, 0.0f, 0.0f, 1.0f};
    out.pose.rotation[KW_PART_LEFT_ARM1] = left1;
    out.pose.rotation[KW_PART_LEFT_ARM2] = left2;
    out.pose.rotation[KW_PART_RIGHT_ARM1] = quat_mirror_x(left1);
    out.pose.rotation[KW_PART_RIGHT_ARM2] = quat_mirror_x(left2);

    const WingAngles& target = poses[mode];
    out.diag.velocity = {sample.velocity.x, sample.velocity.y, sample.velocity.z, alpha};
    out.diag.acceleration = {sample.acceleration.x, sample.acceleration.y, sample.acceleration.z, static_cast<float>(mode)};
    out.diag.angles = {target.arm1_pitch, target.arm2_pitch, target.arm1_heading, target.arm2_heading};
    out.diag.attitude = {att.yaw, att.pitch, att.bank, t};
    return out;
}

}  // namespace kodawari::birds
