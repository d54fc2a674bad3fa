// The scalar reference of the bird engine. Single precision throughout, in the same
// order of operations as shaders/birds_flap.comp, so the two agree to rounding.
#include "kodawari/birds/flight.hpp"

#include <cassert>
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

Bezier bezier_global(const BirdWorld& world, const gpu::RouteHeader& route, float u, float* segment_mode = nullptr) {
    const std::uint32_t n = route.extent.y;
    const std::uint32_t seg = std::min(static_cast<std::uint32_t>(std::max(u, 0.0f)), n - 1);
    if (segment_mode != nullptr) *segment_mode = world.control_points[route.extent.x + 3 * seg].w;
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
            const Bezier e = bezier_global(world, route, end, &out.segment_mode);
            out.position = e.p + (u - end) * e.d1;
            out.velocity = route.info.w * e.d1;
            out.attitude_velocity = out.velocity;
            out.direction = e.d1;
            return out;
        }
        const Bezier e = bezier_global(world, route, u, &out.segment_mode);
        out.position = e.p;
        out.velocity = route.info.w * e.d1;
        out.attitude_velocity = out.velocity;
        out.acceleration = (route.info.w * route.info.w) * e.d2;
        out.direction = e.d1;
        out.lift = e.d2.y;  // a_y = P''_y / D^2
        out.lift_scale = duration * duration;
        return out;
    }
    // Arc-length timing (SPEC B.3): distance = speed * time, or, on a route that takes
    // off or lands, the speed profile of docs/flight-modes.md F.2 (constant acceleration
    // from rest over the take-off segment, to rest over the landing segment). The
    // distance and the speed fraction decide modes, so only +, -, * here (shared/birds.h).
    const float total = route.info.x;
    const bool takeoff = (route.flags.x & KW_ROUTE_TAKEOFF) != 0, landing = (route.flags.x & KW_ROUTE_LANDING) != 0;
    float s = 0.0f;
    float fraction = 1.0f;  // speed / cruise speed
    float along = 0.0f;     // tangential acceleration (m/s^2)
    if (takeoff || landing) {
        const float tau = takeoff ? time - kCrouchSeconds : time;
        const float d = speed * tau;
        if (takeoff) out.progress.since_crouch = tau;
        if (takeoff && d < 2.0f * route.perch.x) {
            if (d >= 0.0f) {
                s = d * d * (0.25f * route.perch.y);
                fraction = d * (0.5f * route.perch.y);
                along = speed * speed * (0.5f * route.perch.y);
            } else {
                fraction = 0.0f;  // crouching on the perch
            }
        } else {
            s = takeoff ? d - route.perch.x : d;
        }
        if (landing) {
            const float start = total - route.perch.z;
            if (s > start) {
                const float dl = s - start;
                const float two_ln = 2.0f * route.perch.z;
                if (dl < two_ln) {
                    s = start + dl - dl * dl * (0.25f * route.perch.w);
                    fraction = 1.0f - dl * (0.5f * route.perch.w);
                    along = -(speed * speed * (0.5f * route.perch.w));
                } else {  // on the perch
                    s = total;
                    fraction = 0.0f;
                    out.progress.since_touchdown = (dl - two_ln) / speed;
                }
            }
        }
    } else {
        s = speed * time;
        if (loop) s = s - total * std::floor(s * route.info.z);
    }
    out.progress.speed_fraction = fraction;
    const float now = fraction * speed;
    if (s < 0.0f || s > total) {
        const float end_s = s < 0.0f ? 0.0f : total;
        const Bezier e = bezier_global(world, route, s < 0.0f ? 0.0f : n, &out.segment_mode);
        const Vec3 tangent = (1.0f / length(e.d1)) * e.d1;
        out.position = e.p + (s - end_s) * tangent;
        out.velocity = speed * tangent;
        out.attitude_velocity = out.velocity;
        out.direction = e.d1;
        return out;
    }
    const Bezier e = bezier_global(world, route, route_parameter_at(world, route_index, s), &out.segment_mode);
    const float d1_len = length(e.d1);
    const Vec3 tangent = (1.0f / d1_len) * e.d1;
    out.position = e.p;
    out.velocity = now * tangent;
    out.attitude_velocity = {speed * tangent.x, now * tangent.y, speed * tangent.z};
    // At constant speed only the normal part of P'' remains: a = v^2 (P'' - (P''.T)T) / |P'|^2.
    out.acceleration = ((now * now) / (d1_len * d1_len)) * (e.d2 - dot(e.d2, tangent) * tangent);
    if (along != 0.0f) out.acceleration = out.acceleration + along * tangent;
    out.direction = e.d1;
    // The same a_y without square roots: v^2 (P''_y |P'|^2 - (P''.P') P'_y) / |P'|^4.
    const float dd = e.d1.x * e.d1.x + e.d1.y * e.d1.y + e.d1.z * e.d1.z;
    const float d2d1 = e.d2.x * e.d1.x + e.d2.y * e.d1.y + e.d2.z * e.d1.z;
    out.lift = (now * now) * (e.d2.y * dd - d2d1 * e.d1.y);
    out.lift_scale = dd * dd;
    return out;
}

Attitude attitude(const gpu::FlightUniforms& uniforms, const RouteSample& sample) {
    const Vec3 v = sample.attitude_velocity, a = sample.acceleration;
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

BodyFrame body_frame(const gpu::FlightUniforms& uniforms, const RouteSample& sample) {
    // The rotation of attitude(): yaw about +Y, climb about -X, bank about +Z, built from
    // the sines and cosines the velocity and acceleration give directly (no atan2, sin or
    // cos: the largest arithmetic cost of the kernel).
    const Vec3 v = sample.attitude_velocity, a = sample.acceleration;
    const float horizontal = std::sqrt(v.x * v.x + v.z * v.z);
    const float speed = std::sqrt(horizontal * horizontal + v.y * v.y);
    if (speed <= 0.0f) return {{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f, 1.0f}, false};
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
    return {yaw, pitch, bank, true};
}

gpu::vec4 body_rotation(const gpu::FlightUniforms& uniforms, const RouteSample& sample) {
    const BodyFrame f = body_frame(uniforms, sample);
    if (!f.moving) return {0.0f, 0.0f, 0.0f, 1.0f};
    return quat_mul(quat_mul(f.yaw, f.pitch), f.bank);
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

std::uint32_t flight_mode(const gpu::BirdParams& bird, const gpu::BirdState& state, const RouteSample& sample,
                          std::uint32_t climb_mode) {
    // docs/flight-modes.md F.1. Every input is exact: the segment's mode (a stored float),
    // the bird's constants, P'_y, and the rhythm's counters carried in the state.
    if (sample.segment_mode >= 0.0f) return static_cast<std::uint32_t>(sample.segment_mode);
    std::uint32_t mode = climb_mode;
    if (bird.flight.w > 0.0f && bird.motion.x < kHoverBelowSpeed) return KW_MODE_HOVER;
    // The flap-glide rhythm: after `beats` wingbeats, glide for `seconds` on a level or
    // descending stretch (a glide on a climb would lose speed).
    if (mode == KW_MODE_LEVEL && bird.flight.y > 0.0f && sample.direction.y <= 0.0f) {
        const bool glide = state.mode.x == KW_MODE_GLIDE ? state.phase.y < bird.flight.z : state.phase.z >= bird.flight.y;
        if (glide) mode = KW_MODE_GLIDE;
    }
    return mode;
}

gpu::BirdState initial_state() {
    gpu::BirdState state{};
    state.blend = {1.0f, 0.0f, 0.0f, 0.0f};
    state.blend2 = {0.0f, 0.0f, 0.0f, 1.0f};
    state.mode = {KW_MODE_UNSET, 0, 0, 0};
    return state;
}

namespace {

gpu::vec4 conj(const gpu::vec4& q) { return {-q.x, -q.y, -q.z, q.w}; }
// nlerp(identity, q, k) for a unit q with q.w >= 0: a fraction k of q's turn, without trig.
gpu::vec4 nlerp_turn(const gpu::vec4& q, float k) {
    return quat_normalize({k * q.x, k * q.y, k * q.z, (1.0f - k) + k * q.w});
}
// A turn raising the nose (or lowering the tail) by `angle`: about -X.
gpu::vec4 nose_up(float angle) { return {-std::sin(0.5f * angle), 0.0f, 0.0f, std::cos(0.5f * angle)}; }

float blend_rate(const gpu::FlightUniforms& u, std::uint32_t mode) {
    const float rates[KW_MODE_COUNT] = {u.blend_rates.x,  u.blend_rates.y,  u.blend_rates.z, u.blend_rates2.x,
                                        u.blend_rates2.y, u.blend_rates2.z, u.blend_rates2.w};
    return rates[mode];
}

}  // namespace

RouteSample motion_sample(const gpu::BirdMotionGpu& motion) {
    RouteSample out;
    out.position = xyz(motion.position);
    out.velocity = xyz(motion.velocity);
    out.acceleration = xyz(motion.acceleration);
    out.direction = out.velocity;
    out.attitude_velocity = out.velocity;
    out.lift = motion.acceleration.y;
    out.lift_scale = 1.0f;
    return out;
}

RouteSample route_motion_sample(const BirdWorld& world, const gpu::BirdParams& bird, std::uint32_t frame, float dt,
                                const gpu::BirdMotionGpu& motion) {
    // shared/birds.h, the comment above BirdMotionGpu (KW_MOTION_ROUTE): the bird's own
    // route as a route bird flies it, at the motion's time offset and speed...
    const float now = static_cast<float>(frame) * dt;
    RouteSample out = sample_route(world, bird.ids.x, now + motion.velocity.w, motion.acceleration.z);
    // ...plus the cubic Hermite correction c(t) from (e_p, e_v) at t0 to 0 at t0 + T. The
    // exact decisions (segment mode, direction, lift, progress) stay the route's: c only
    // moves the bird. From t0 + T on (s = 1) c, c' and c'' are 0 and the sample is the
    // route's own bits; 1/T = 0 means no correction. The SIMD and Vulkan kernels repeat
    // these operations in this order, so the position is the same bits on the cpu backend.
    const float inv_t = motion.acceleration.y;
    const float s = std::clamp((now - motion.acceleration.x) * inv_t, 0.0f, 1.0f);
    if (inv_t == 0.0f || !(s < 1.0f)) return out;
    const float span = 1.0f / inv_t;  // T
    const float h00 = (2.0f * s - 3.0f) * (s * s) + 1.0f;
    const float h10 = ((s - 2.0f) * s + 1.0f) * s;
    const float d00 = (6.0f * s - 6.0f) * s;  // h00'(s)
    const float d10 = (3.0f * s - 4.0f) * s + 1.0f;
    const float dd00 = 12.0f * s - 6.0f;  // h00''(s)
    const float dd10 = 6.0f * s - 4.0f;
    const Vec3 ep = xyz(motion.position), ev = xyz(motion.velocity);
    const Vec3 c = h00 * ep + (span * h10) * ev;
    const Vec3 c1 = (d00 * inv_t) * ep + d10 * ev;
    const Vec3 c2 = ((dd00 * inv_t) * inv_t) * ep + (dd10 * inv_t) * ev;
    out.position = out.position + c;
    out.velocity = out.velocity + c1;
    out.attitude_velocity = out.attitude_velocity + c1;
    out.acceleration = out.acceleration + c2;
    return out;
}

BirdFrame step_bird(const BirdWorld& world, const gpu::FlightUniforms& uniforms, const gpu::BirdParams& bird,
                    gpu::BirdState& state, std::uint32_t frame, const gpu::BirdMotionGpu* motion) {
    const float dt = uniforms.physics.z;
    const std::uint32_t previous = state.mode.x;
    const bool first = previous == KW_MODE_UNSET;

    const float time = static_cast<float>(frame) * dt + bird.offset.w;
    const bool driven = bird.ids.w == KW_BIRD_DRIVEN;
    assert(!driven || motion != nullptr);
    // A driven bird flies its motion (flown: no offset added) or, KW_MOTION_ROUTE, its
    // own route (shared/birds.h), which takes the offset as a route bird's does.
    const bool flown = driven && motion->position.w != static_cast<float>(KW_MOTION_ROUTE);
    const RouteSample sample = flown    ? motion_sample(*motion)
                               : driven ? route_motion_sample(world, bird, frame, dt, *motion)
                                        : sample_route(world, bird.ids.x, time, bird.motion.x);
    const Attitude att = attitude(uniforms, sample);

    // Mode (SPEC B.5, docs/flight-modes.md F.1). The climb rule keeps its hysteresis
    // through a glide (a glide is level flight without beats); after the other modes it
    // decides afresh.
    const std::uint32_t climb_previous = previous <= KW_MODE_DESCEND ? previous
                                         : previous == KW_MODE_GLIDE  ? KW_MODE_LEVEL
                                                                      : KW_MODE_UNSET;
    const std::uint32_t mode = flight_mode(bird, state, sample, next_mode(uniforms, climb_previous, sample));

    // Transition (SPEC B.6): the blend source is a weighted sum of the mode poses, so a
    // change during a transition starts exactly from the current blended pose.
    float weights[KW_MODE_COUNT] = {state.blend.x,  state.blend.y,  state.blend.z, state.blend.w,
                                    state.blend2.x, state.blend2.y, state.blend2.z};
    float alpha = state.blend2.w;
    if (first) {
        for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) weights[m] = m == mode ? 1.0f : 0.0f;
        alpha = 1.0f;
    } else if (mode != previous) {
        for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) weights[m] = (1.0f - alpha) * weights[m] + (m == previous ? alpha : 0.0f);
        alpha = 0.0f;
    } else if (alpha < 1.0f) {
        // The seed's per-frame rates, applied per 1/60 s of simulated time.
        alpha += blend_rate(uniforms, mode) * uniforms.physics.w;
        if (alpha >= 1.0f) {
            for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) weights[m] = m == mode ? 1.0f : 0.0f;
            alpha = 1.0f;
        }
    }
    state.blend = {weights[0], weights[1], weights[2], weights[3]};
    state.blend2 = {weights[4], weights[5], weights[6], alpha};

    // Wingbeat phase in cycles, advanced per frame at the bird's frequency times the
    // mode's factor (SPEC B.2; F.3: held wings do not beat); kept in [0, 1) so its
    // precision does not decay over long runs. Completed beats drive the flap-glide rhythm.
    const PerchProgress& progress = sample.progress;
    float phase = first ? bird.motion.w
                        : state.phase.x + (bird.motion.y * dt) * beat_factor(static_cast<FlightMode>(mode), progress);
    const float whole = std::floor(phase);
    phase = phase - whole;
    state.phase.x = phase;
    if (mode == KW_MODE_GLIDE) {
        state.phase.y = (previous == KW_MODE_GLIDE ? state.phase.y : 0.0f) + dt;
        state.phase.z = 0.0f;
    } else {
        state.phase.y = 0.0f;
        if (!first) state.phase.z = state.phase.z + whole;
    }
    state.mode.x = mode;

    float t = phase * kTwoPi;
    if (t >= kTwoPi) t = 0.0f;
    const float amplitude = bird.motion.z;
    // The looks of the modes that take part: the target, and in a transition every mode
    // with a weight in the blend source.
    ModeLook looks[KW_MODE_COUNT];
    gpu::vec4 arm1[KW_MODE_COUNT], arm2[KW_MODE_COUNT];
    for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) {
        if (m != mode && (alpha >= 1.0f || weights[m] == 0.0f)) continue;
        looks[m] = mode_look(static_cast<FlightMode>(m), t, amplitude, progress);
        arm1[m] = arm_rotation(looks[m].wings.arm1_pitch, looks[m].wings.arm1_heading);
        arm2[m] = arm_rotation(looks[m].wings.arm2_pitch, looks[m].wings.arm2_heading);
    }
    // SPEC B.6: Q = ((1-a) Qa + a Qb) / |...|, Qa the blend source, each term flipped
    // into the target's hemisphere. Outside a transition (a = 1) Q is the target pose.
    auto blend = [&](const gpu::vec4* q) {
        const gpu::vec4& target = q[mode];
        if (alpha >= 1.0f) return target;
        gpu::vec4 sum{alpha * target.x, alpha * target.y, alpha * target.z, alpha * target.w};
        for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) {
            if (weights[m] == 0.0f) continue;
            const float w = (1.0f - alpha) * weights[m] * (quat_dot(q[m], target) < 0.0f ? -1.0f : 1.0f);
            sum = {sum.x + w * q[m].x, sum.y + w * q[m].y, sum.z + w * q[m].z, sum.w + w * q[m].w};
        }
        return quat_normalize(sum);
    };
    const gpu::vec4 left1 = blend(arm1), left2 = blend(arm2);
    // The continuous parts of the look, weighted like the poses (F.5).
    float pitch = 0.0f, spread = 0.0f, bob = 0.0f;
    for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) {
        const float w = (m == mode ? alpha : 0.0f) + (alpha >= 1.0f ? 0.0f : (1.0f - alpha) * weights[m]);
        if (w == 0.0f) continue;
        pitch += w * looks[m].pitch;
        spread += w * looks[m].spread;
        bob += w * looks[m].bob;
    }

    // Roll (docs/flight-modes.md F.6): the bank body_frame() asks for and the lateral
    // acceleration the head looks into the turn by pass through a first-order low-pass,
    // x += (1 - e^(-dt/tau)) (target - x), the exact step of dx/dt = (target - x) / tau
    // with the target held over the frame (the roll subsidence mode of flight dynamics,
    // Etkin & Reid, "Dynamics of Flight", 3rd ed., 1996: the roll subsidence mode, a
    // roll rate proportional to the roll still to go). The bank is filtered as its quaternion about
    // the forward axis, (z, w) = (sin, cos) of half the angle, then normalised: no trig,
    // and since |bank| < 90 deg both half angles are within 45 deg, where this nlerp's
    // rate is within a factor 2 tan(d/4) / d <= 1 of the angle's own filter.
    // uniforms.bank_limit.z holds e^(-dt/tau), 0 without a filter (then x = target
    // exactly). Frame 0 starts on its target. Not moving, the Body has no bank (identity)
    // and the filter runs on toward that.
    BodyFrame frame_parts = body_frame(uniforms, sample);
    const Vec3 v = sample.attitude_velocity, a = sample.acceleration;
    const float horizontal = std::sqrt(v.x * v.x + v.z * v.z);
    const float lateral = horizontal > 1e-3f ? (a.x * -v.z + a.z * v.x) / horizontal : 0.0f;  // toward the bird's right
    const float keep = uniforms.bank_limit.z;
    const gpu::vec4 bank_target = frame_parts.bank;
    const float roll_w = first ? bank_target.w : bank_target.w + keep * (state.roll.x - bank_target.w);
    const float roll_z = first ? bank_target.z : bank_target.z + keep * (state.roll.y - bank_target.z);
    const float roll_lateral = first ? lateral : lateral + keep * (state.roll.z - lateral);
    state.roll = {roll_w, roll_z, roll_lateral, 0.0f};
    const float roll_inv = 1.0f / std::sqrt(roll_w * roll_w + roll_z * roll_z);
    if (frame_parts.moving) frame_parts.bank = {0.0f, 0.0f, roll_z * roll_inv, roll_w * roll_inv};

    // Body (SPEC B.4) with the mode's extra pitch and the wingbeat's pitch oscillation
    // about its own lateral axis, and the body's bob (F.5).
    const float oscillation = kBobPitch * amplitude * std::sin(t) * bob;
    const float extra = pitch + oscillation;
    // body_rotation()'s product, from the factors the head and tail also use.
    const gpu::vec4 base = frame_parts.moving ? quat_mul(quat_mul(frame_parts.yaw, frame_parts.pitch), frame_parts.bank)
                                              : gpu::vec4{0.0f, 0.0f, 0.0f, 1.0f};
    const gpu::vec4 body = quat_mul(base, nose_up(extra));
    const float bob_height = -kBobHeight * bird.shape.x * amplitude * std::cos(t) * bob;
    const float sin_bank = 2.0f * frame_parts.bank.z * frame_parts.bank.w;

    // Head (F.5): levels itself against part of the climb, the bank, the extra pitch and
    // the oscillation, and looks into the turn by the turn rate (the filtered lateral
    // acceleration over the speed, F.6) times a look-ahead time.
    float look = 0.0f;
    if (horizontal > 1e-3f) look = std::clamp(-kLookAhead * roll_lateral / horizontal, -kMaxLook, kMaxLook);
    const gpu::vec4 head = quat_mul(quat_mul(quat_mul(nose_up(-(kHeadPitchHold * pitch + kHeadBobHold * oscillation)),
                                                      nlerp_turn(conj(frame_parts.bank), kHeadBankHold)),
                                             nlerp_turn(conj(frame_parts.pitch), kHeadClimbHold)),
                                    quat_y(look));
    // Tail (F.5): lowered with the extra pitch and part of the climb, twisted with part of
    // the bank; spread by the mode and the bank.
    const gpu::vec4 tail =
        quat_mul(quat_mul(nlerp_turn(frame_parts.pitch, kTailClimb), nose_up(kTailPitch * pitch)), nlerp_turn(frame_parts.bank, kTailBank));
    const float tail_spread = spread + kTailBankSpread * std::fabs(sin_bank);

    BirdFrame out{};
    const Vec3 position = flown ? sample.position : sample.position + xyz(bird.offset);
    out.pose.position = {position.x, position.y + bob_height, position.z, tail_spread};
    out.pose.rotation[KW_PART_BODY] = body;
    out.pose.rotation[KW_PART_HEAD] = head;
    out.pose.rotation[KW_PART_TAIL] = tail;
    out.pose.rotation[KW_PART_LEFT_ARM1] = left1;
    out.pose.rotation[KW_PART_LEFT_ARM2] = left2;
    out.pose.rotation[KW_PART_RIGHT_ARM1] = quat_mirror_x(left1);
    out.pose.rotation[KW_PART_RIGHT_ARM2] = quat_mirror_x(left2);

    const WingAngles& target = looks[mode].wings;
    out.diag.velocity = {sample.velocity.x, sample.velocity.y, sample.velocity.z, alpha};
    out.diag.acceleration = {sample.acceleration.x, sample.acceleration.y, sample.acceleration.z, static_cast<float>(mode)};
    out.diag.angles = {target.arm1_pitch, target.arm2_pitch, target.arm1_heading, target.arm2_heading};
    // The bank the Body has (filtered), not the route's instantaneous one.
    out.diag.attitude = {att.yaw, att.pitch, 2.0f * std::atan2(frame_parts.bank.z, frame_parts.bank.w), t};
    out.diag.flight = {progress.speed_fraction, extra, tail_spread, state.phase.y};
    return out;
}

}  // namespace kodawari::birds
