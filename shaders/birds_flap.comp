#version 450
// Bird flapping (SPEC part B): one invocation per bird evaluates `frames.y` consecutive
// frames, keeping the bird's state in registers between them, and writes the 7 part
// rotations (and optional diagnostics) of every frame. Mirrors engine/birds/flight.cpp
// step for step; see there for the equations' sources.
#extension GL_GOOGLE_include_directive : require

#include "shared/birds.h"
#include "lib/quat.glsl"

layout(local_size_x = KW_BIRDS_WORKGROUP_SIZE) in;

// The rules and the diagnostics switch are specialization constants, not uniforms:
// lavapipe executes both sides of every branch, uniform ones included, so code that a
// run does not need must not be in its pipeline at all.
layout(constant_id = KW_BIRDS_SPEC_BANK_RULE) const uint BANK_RULE = KW_BANK_COORDINATED;
layout(constant_id = KW_BIRDS_SPEC_MODE_RULE) const uint MODE_RULE = KW_MODE_RULE_CLIMB;
layout(constant_id = KW_BIRDS_SPEC_DIAGNOSTICS) const bool WRITE_DIAGNOSTICS = false;

layout(std140, binding = KW_BIRDS_BINDING_UNIFORMS) uniform Uniforms { FlightUniforms u; };
layout(std430, binding = KW_BIRDS_BINDING_ROUTES) readonly buffer Routes { RouteHeader routes[]; };
layout(std430, binding = KW_BIRDS_BINDING_CONTROL_POINTS) readonly buffer ControlPoints { vec4 control_points[]; };
layout(std430, binding = KW_BIRDS_BINDING_ARC_SAMPLES) readonly buffer ArcSamples { ArcSample arc_samples[]; };
layout(std430, binding = KW_BIRDS_BINDING_PARAMS) readonly buffer Params { BirdParams params[]; };
layout(std430, binding = KW_BIRDS_BINDING_STATES) buffer States { BirdState states[]; };
layout(std430, binding = KW_BIRDS_BINDING_POSES) writeonly buffer Poses { BirdPoseGpu poses[]; };
layout(std430, binding = KW_BIRDS_BINDING_DIAGNOSTICS) writeonly buffer Diagnostics { BirdDiag diags[]; };

layout(push_constant) uniform Push { BirdPush push; };

const float PI = 3.14159265358979;
const float TWO_PI = 6.28318530717959;
const float HALF_PI = 1.57079632679490;

vec4 quat_y(float a) { return vec4(0.0, sin(0.5 * a), 0.0, cos(0.5 * a)); }
vec4 quat_z(float a) { return vec4(0.0, 0.0, sin(0.5 * a), cos(0.5 * a)); }

// `precise` below: the exact decisions of shared/birds.h (no contraction, source order).
struct Bezier { vec3 p; vec3 d1; vec3 d2; };

// Storage loads are the expensive part on lavapipe, and a bird moves a little along its
// route each frame: the current Bezier segment and arc-length interval stay in registers
// and are reloaded only when the bird leaves them. The values used are the same as
// without the cache, so results do not change.
struct RouteCache {
    uint segment;  // cached segment, 0xFFFFFFFF = none
    vec3 b0, b1, b2, b3;
    uint lo;       // cached arc-length interval [lo, lo + 1], 0xFFFFFFFF = none
    vec4 a, b;     // its two samples
    float inv_h;
};

RouteCache empty_cache() {
    RouteCache c;
    c.segment = 0xFFFFFFFFu;
    c.lo = 0xFFFFFFFFu;
    c.b0 = c.b1 = c.b2 = c.b3 = vec3(0.0);
    c.a = c.b = vec4(0.0);
    c.inv_h = 0.0;
    return c;
}

Bezier bezier(RouteHeader route, uint seg, float u, inout RouteCache cache) {
    if (cache.segment != seg) {
        uint c = route.extent.x + 3u * seg;
        cache.segment = seg;
        cache.b0 = control_points[c].xyz;
        cache.b1 = control_points[c + 1u].xyz;
        cache.b2 = control_points[c + 2u].xyz;
        cache.b3 = control_points[c + 3u].xyz;
    }
    vec3 b0 = cache.b0, b1 = cache.b1, b2 = cache.b2, b3 = cache.b3;
    precise float v = 1.0 - u;
    vec3 p = (v * v * v) * b0 + (3.0 * u * v * v) * b1 + (3.0 * u * u * v) * b2 + (u * u * u) * b3;
    precise vec3 d1 = 3.0 * ((v * v) * (b1 - b0) + (2.0 * u * v) * (b2 - b1) + (u * u) * (b3 - b2));
    precise vec3 d2 = 6.0 * (v * (b2 - 2.0 * b1 + b0) + u * (b3 - 2.0 * b2 + b1));
    Bezier r;
    r.p = p;
    r.d1 = d1;
    r.d2 = d2;
    return r;
}

Bezier bezier_global(RouteHeader route, float u, inout RouteCache cache) {
    uint seg = min(uint(max(u, 0.0)), route.extent.y - 1u);
    precise float local_u = u - float(seg);
    return bezier(route, seg, local_u, cache);
}

// The interval a binary search over the samples would find: the last lo with
// s_lo <= s, at most count - 2.
float route_parameter_at(RouteHeader route, float s, inout RouteCache cache) {
    uint base = route.extent.z;
    uint last = route.extent.w - 1u;
    bool valid = cache.lo != 0xFFFFFFFFu && cache.a.x <= s && (s < cache.b.x || cache.lo + 1u == last);
    if (!valid) {
        uint lo = 0u, hi = last;
        // Forward flight: the next interval is the usual answer.
        if (cache.lo != 0xFFFFFFFFu && cache.lo + 2u <= last && cache.b.x <= s &&
            (s < arc_samples[base + cache.lo + 2u].s_u_duds.x || cache.lo + 2u == last)) {
            lo = cache.lo + 1u;
        } else {
            while (hi - lo > 1u) {
                uint mid = (lo + hi) / 2u;
                if (arc_samples[base + mid].s_u_duds.x <= s) lo = mid; else hi = mid;
            }
        }
        cache.lo = lo;
        cache.a = arc_samples[base + lo].s_u_duds;
        cache.b = arc_samples[base + lo + 1u].s_u_duds;
        cache.inv_h = arc_samples[base + lo].next.x;
    }
    vec4 a = cache.a, b = cache.b;
    precise float h = b.x - a.x;
    precise float t = clamp((s - a.x) * cache.inv_h, 0.0, 1.0);
    precise float t2 = t * t;
    precise float t3 = t2 * t;
    precise float u_at_s = (2.0 * t3 - 3.0 * t2 + 1.0) * a.y + (t3 - 2.0 * t2 + t) * h * a.w + (-2.0 * t3 + 3.0 * t2) * b.y +
                           (t3 - t2) * h * b.z;
    return u_at_s;
}

struct RouteSample {
    vec3 position;
    vec3 velocity;
    vec3 acceleration;
    vec3 direction;  // P', a positive multiple of the velocity (exact)
    float lift;      // acceleration.y = lift / lift_scale (exact)
    float lift_scale;
};

// One Bezier evaluation per frame: lavapipe runs both sides of a divergent branch, so
// the timing and end cases only choose the parameter and how the result is used.
RouteSample sample_route(RouteHeader route, float time, float speed, inout RouteCache cache) {
    bool loop = (route.flags.x & KW_ROUTE_LOOP) != 0u;
    bool parametric = (route.flags.x & KW_ROUTE_PARAMETRIC) != 0u;
    float n = float(route.extent.y);
    // Where on the route (u), and how far past an end of an open route (`beyond`: in u
    // for parametric timing, in metres for arc-length timing).
    precise float u;
    precise float beyond = 0.0;
    bool outside;
    if (parametric) {
        u = time * route.info.w;  // the seed's timing: one segment per duration D
        if (loop) {  // u mod n without a division
            float whole = floor(u);
            int wrapped = int(whole) % int(route.extent.y);
            if (wrapped < 0) wrapped += int(route.extent.y);
            u = float(wrapped) + (u - whole);
        }
        outside = u < 0.0 || u > n;
        float end = u < 0.0 ? 0.0 : n;
        if (outside) {
            beyond = u - end;
            u = end;
        }
    } else {
        float total = route.info.x;
        precise float s = speed * time;  // arc-length timing (SPEC B.3)
        if (loop) s = s - total * floor(s * route.info.z);
        outside = s < 0.0 || s > total;
        float end_s = s < 0.0 ? 0.0 : total;
        u = route_parameter_at(route, clamp(s, 0.0, total), cache);
        if (outside) {
            beyond = s - end_s;
            u = s < 0.0 ? 0.0 : n;
        }
    }
    Bezier e = bezier_global(route, u, cache);
    RouteSample r;
    r.direction = e.d1;
    r.acceleration = vec3(0.0);
    r.lift = 0.0;
    r.lift_scale = 1.0;
    if (parametric) {
        r.position = outside ? e.p + beyond * e.d1 : e.p;
        r.velocity = route.info.w * e.d1;
        if (!outside) {
            r.acceleration = (route.info.w * route.info.w) * e.d2;
            r.lift = e.d2.y;  // a_y = P''_y / D^2
            precise float scale = route.info.y * route.info.y;
            r.lift_scale = scale;
        }
    } else {
        float d1_len = length(e.d1);
        vec3 tangent = (1.0 / d1_len) * e.d1;
        r.position = outside ? e.p + beyond * tangent : e.p;
        r.velocity = speed * tangent;
        if (!outside) {
            // a = v^2 (P'' - (P''.T)T) / |P'|^2; a_y exactly as lift / lift_scale.
            r.acceleration = ((speed * speed) / (d1_len * d1_len)) * (e.d2 - dot(e.d2, tangent) * tangent);
            precise float dd = e.d1.x * e.d1.x + e.d1.y * e.d1.y + e.d1.z * e.d1.z;
            precise float d2d1 = e.d2.x * e.d1.x + e.d2.y * e.d1.y + e.d2.z * e.d1.z;
            precise float lift = (speed * speed) * (e.d2.y * dd - d2d1 * e.d1.y);
            precise float lift_scale = dd * dd;
            r.lift = lift;
            r.lift_scale = lift_scale;
        }
    }
    return r;
}

vec3 attitude(vec3 v, vec3 a) {
    float horizontal = sqrt(v.x * v.x + v.z * v.z);
    if (horizontal <= 0.0 && v.y == 0.0) return vec3(0.0);
    vec3 att = vec3(atan(v.x, v.z), atan(v.y, horizontal), 0.0);
    float max_bank = u.physics.y;
    if (BANK_RULE == KW_BANK_SEED) {
        vec3 c = cross(v, a);
        if (length(a) <= 0.0) return att;
        float bank = atan(length(c), dot(v, a)) - HALF_PI;
        if (c.y > 0.0) bank = -bank;
        att.z = clamp(bank, -max_bank, max_bank);
        return att;
    }
    if (horizontal <= 1e-6 * abs(v.y)) return att;
    vec3 right = (1.0 / horizontal) * vec3(-v.z, 0.0, v.x);
    att.z = clamp(atan(dot(a, right), u.physics.x), -max_bank, max_bank);
    return att;
}

// (cos(x/2), sin(x/2)) from (cos x, sin x), cos x >= 0.
vec2 half_angle(float c, float s) {
    float hc = sqrt(0.5 * (1.0 + c));
    return vec2(hc, s / (2.0 * hc));
}

// engine/birds/flight.cpp body_rotation(): the attitude's rotation without trig.
vec4 body_rotation(vec3 v, vec3 a) {
    float horizontal = sqrt(v.x * v.x + v.z * v.z);
    float speed = sqrt(horizontal * horizontal + v.y * v.y);
    if (speed <= 0.0) return vec4(0.0, 0.0, 0.0, 1.0);
    vec4 yaw = vec4(0.0, 0.0, 0.0, 1.0);
    if (horizontal > 0.0) {
        float c = v.z / horizontal, s = v.x / horizontal;
        if (c >= 0.0) {
            vec2 h = half_angle(c, s);
            yaw.w = h.x;
            yaw.y = h.y;
        } else {
            yaw.y = (s < 0.0 ? -1.0 : 1.0) * sqrt(0.5 * (1.0 - c));
            yaw.w = s / (2.0 * yaw.y);
        }
    }
    vec2 p = half_angle(horizontal / speed, -v.y / speed);
    vec4 pitch = vec4(p.y, 0.0, 0.0, p.x);
    float bc = 1.0, bs = 0.0;
    if (BANK_RULE == KW_BANK_SEED) {
        float bank = attitude(v, a).z;
        bc = cos(bank);
        bs = sin(bank);
    } else if (horizontal > 1e-6 * abs(v.y)) {
        float lateral = (a.x * -v.z + a.z * v.x) / horizontal;
        float g = u.physics.x;
        float norm = sqrt(lateral * lateral + g * g);
        bc = g / norm;
        bs = lateral / norm;
        if (bc < u.bank_limit.x) {
            bc = u.bank_limit.x;
            bs = (lateral < 0.0 ? -1.0 : 1.0) * u.bank_limit.y;
        }
    }
    vec2 b = half_angle(bc, bs);
    return qmul_flight(qmul_flight(yaw, pitch), vec4(0.0, 0.0, b.y, b.x));
}

uint next_mode(uint previous, RouteSample r) {
    if (MODE_RULE == KW_MODE_RULE_SEED) {
        precise float threshold = u.blend_rates.w * r.lift_scale;
        if (r.lift > threshold) return KW_MODE_ASCEND;
        if (r.lift < -threshold) return KW_MODE_DESCEND;
        return KW_MODE_LEVEL;
    }
    vec3 d = r.direction;
    precise float dd = d.x * d.x + d.y * d.y + d.z * d.z;
    precise float climb = d.y * abs(d.y);
    precise float ascend_enter = u.climb.x * dd;
    precise float ascend_exit = u.climb.y * dd;
    precise float descend_enter = u.climb.z * dd;
    precise float descend_exit = u.climb.w * dd;
    uint mode = previous;
    if (mode == KW_MODE_ASCEND && climb < ascend_exit) mode = KW_MODE_LEVEL;
    if (mode == KW_MODE_DESCEND && climb > descend_exit) mode = KW_MODE_LEVEL;
    if (mode == KW_MODE_LEVEL || mode == KW_MODE_UNSET) {
        mode = climb > ascend_enter ? KW_MODE_ASCEND : climb < descend_enter ? KW_MODE_DESCEND : KW_MODE_LEVEL;
    }
    return mode;
}

// Wingbeat functions, SPEC B.2 eqs. 4.1-4.5: (arm1 pitch, arm2 pitch, arm1 heading, arm2 heading).
vec4 wing_angles(uint mode, float t, float s, float amplitude) {
    bool first_half = t < PI;
    vec4 a = vec4(0.0);
    if (mode == KW_MODE_LEVEL) {
        a.x = t < 0.5 * PI ? 0.0 : t < PI ? -(2.0 / 3.0) * t + PI / 3.0 : t < 1.5 * PI ? -PI / 3.0 : (2.0 / 3.0) * t - (4.0 / 3.0) * PI;
        a.y = first_half ? -(PI / 3.0) * s : -(3.0 / 18.0) * PI * s;
    } else if (mode == KW_MODE_ASCEND) {
        a.x = first_half ? -(PI / 3.0) * s : -(3.0 / 18.0) * PI * s;
        a.y = first_half ? -(4.0 / 9.0) * PI * s : -(5.0 / 18.0) * PI * s;
    } else {
        a.z = (PI / 180.0) * s;
        a.w = first_half ? -(PI / 36.0) * s : -(PI / 90.0) * s;
    }
    return a * amplitude;
}

vec4 blend_quats(vec4 q0, vec4 q1, vec4 q2, vec3 weights, float alpha, uint mode) {
    vec4 target = mode == KW_MODE_LEVEL ? q0 : mode == KW_MODE_ASCEND ? q1 : q2;
    vec4 sum = alpha * target;
    sum += ((1.0 - alpha) * weights.x * (dot(q0, target) < 0.0 ? -1.0 : 1.0)) * q0;
    sum += ((1.0 - alpha) * weights.y * (dot(q1, target) < 0.0 ? -1.0 : 1.0)) * q1;
    sum += ((1.0 - alpha) * weights.z * (dot(q2, target) < 0.0 ? -1.0 : 1.0)) * q2;
    return sum * (1.0 / sqrt(dot(sum, sum)));
}

vec3 one_hot(uint mode) {
    return vec3(mode == KW_MODE_LEVEL ? 1.0 : 0.0, mode == KW_MODE_ASCEND ? 1.0 : 0.0, mode == KW_MODE_DESCEND ? 1.0 : 0.0);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint count = u.rules.z;
    if (i >= count) return;

    BirdParams bird = params[i];
    BirdState state = states[i];
    RouteHeader route = routes[bird.ids.x];
    RouteCache cache = empty_cache();
    float dt = u.physics.z;

    for (uint k = 0u; k < push.frames.y; ++k) {
        uint frame = push.frames.x + k;
        bool first = state.mode.x == KW_MODE_UNSET;
        precise float phase = first ? bird.motion.w : state.phase.x + bird.motion.y * dt;
        phase = phase - floor(phase);
        state.phase.x = phase;

        precise float time = float(frame) * dt + bird.offset.w;
        RouteSample r = sample_route(route, time, bird.motion.x, cache);
        vec3 position = r.position, velocity = r.velocity, acceleration = r.acceleration;

        uint mode = next_mode(state.mode.x, r);
        if (first) {
            state.blend = vec4(one_hot(mode), 1.0);
        } else if (mode != state.mode.x) {
            float alpha = state.blend.w;
            precise vec3 weights = (1.0 - alpha) * state.blend.xyz + alpha * one_hot(state.mode.x);
            state.blend = vec4(weights, 0.0);
        } else if (state.blend.w < 1.0) {
            float rate = mode == KW_MODE_LEVEL ? u.blend_rates.x : mode == KW_MODE_ASCEND ? u.blend_rates.y : u.blend_rates.z;
            precise float alpha = state.blend.w + rate * u.physics.w;
            state.blend.w = alpha;
            if (state.blend.w >= 1.0) state.blend = vec4(one_hot(mode), 1.0);
        }
        state.mode.x = mode;

        float t = phase * TWO_PI;
        if (t >= TWO_PI) t = 0.0;
        float amplitude = bird.motion.z;
        float sin_t = sin(t);
        // All three mode poses (the transition blends them; outside one the target is
        // picked): computed once, as lavapipe would run a divergent branch anyway.
        vec4 a0 = wing_angles(KW_MODE_LEVEL, t, sin_t, amplitude);
        vec4 a1 = wing_angles(KW_MODE_ASCEND, t, sin_t, amplitude);
        vec4 a2 = wing_angles(KW_MODE_DESCEND, t, sin_t, amplitude);
        vec4 level1 = quat_z(a0.x), level2 = quat_z(a0.y);
        vec4 ascend1 = quat_z(a1.x), ascend2 = quat_z(a1.y);
        vec4 descend1 = quat_y(a2.z), descend2 = quat_y(a2.w);
        vec4 target = mode == KW_MODE_LEVEL ? a0 : mode == KW_MODE_ASCEND ? a1 : a2;
        vec4 left1 = mode == KW_MODE_LEVEL ? level1 : mode == KW_MODE_ASCEND ? ascend1 : descend1;
        vec4 left2 = mode == KW_MODE_LEVEL ? level2 : mode == KW_MODE_ASCEND ? ascend2 : descend2;
        if (state.blend.w < 1.0) {  // a transition (SPEC B.6)
            left1 = blend_quats(level1, ascend1, descend1, state.blend.xyz, state.blend.w, mode);
            left2 = blend_quats(level2, ascend2, descend2, state.blend.xyz, state.blend.w, mode);
        }

        uint slot = (k % push.frames.z) * count + i;
        poses[slot].position = vec4(position + bird.offset.xyz, 0.0);
        poses[slot].body = body_rotation(velocity, acceleration);
        poses[slot].left_arm1 = left1;
        poses[slot].left_arm2 = left2;
        if (WRITE_DIAGNOSTICS) {
            diags[slot].velocity = vec4(velocity, state.blend.w);
            diags[slot].acceleration = vec4(acceleration, float(mode));
            diags[slot].angles = target;
            diags[slot].attitude = vec4(attitude(velocity, acceleration), t);
        }
    }
    states[i] = state;
}
