#version 450
// Bird flapping (SPEC part B): one invocation per bird evaluates `frames.y` consecutive
// frames, keeping the bird's state in registers between them, and writes the 7 part
// rotations (and optional diagnostics) of every frame. Mirrors engine/birds/flight.cpp
// step for step; see there for the equations' sources.
#extension GL_GOOGLE_include_directive : require

#include "shared/birds.h"
#include "lib/quat.glsl"

// The size is a specialization constant (default KW_BIRDS_WORKGROUP_SIZE): a variant to
// time on each GPU (BackendOptions::workgroup_size); one bird per invocation, no shared
// memory, so the results do not depend on it.
layout(local_size_x = KW_BIRDS_WORKGROUP_SIZE, local_size_x_id = KW_BIRDS_SPEC_WORKGROUP_SIZE) in;

// The rules and the diagnostics switch are specialization constants, not uniforms:
// lavapipe executes both sides of every branch, uniform ones included, so code that a
// run does not need must not be in its pipeline at all.
layout(constant_id = KW_BIRDS_SPEC_BANK_RULE) const uint BANK_RULE = KW_BANK_COORDINATED;
layout(constant_id = KW_BIRDS_SPEC_MODE_RULE) const uint MODE_RULE = KW_MODE_RULE_CLIMB;
layout(constant_id = KW_BIRDS_SPEC_DIAGNOSTICS) const bool WRITE_DIAGNOSTICS = false;
layout(constant_id = KW_BIRDS_SPEC_DRIVEN) const bool HAS_DRIVEN = false;
// The pose layout, a variant to time on a GPU (docs/performance.md, "Bird poses: records
// or fields"): false, a BirdPoseGpu record per bird; true, the same bytes as six arrays of
// vec4, one per field, so that a subgroup's store of one field is one run of consecutive
// vec4s rather than vec4s 96 bytes apart.
layout(constant_id = KW_BIRDS_SPEC_POSE_FIELDS) const bool POSE_FIELDS = false;

layout(std140, binding = KW_BIRDS_BINDING_UNIFORMS) uniform Uniforms { FlightUniforms u; };
layout(std430, binding = KW_BIRDS_BINDING_ROUTES) readonly buffer Routes { RouteHeader routes[]; };
layout(std430, binding = KW_BIRDS_BINDING_CONTROL_POINTS) readonly buffer ControlPoints { vec4 control_points[]; };
layout(std430, binding = KW_BIRDS_BINDING_ARC_SAMPLES) readonly buffer ArcSamples { ArcSample arc_samples[]; };
layout(std430, binding = KW_BIRDS_BINDING_PARAMS) readonly buffer Params { BirdParams params[]; };
layout(std430, binding = KW_BIRDS_BINDING_STATES) buffer States { BirdState states[]; };
layout(std430, binding = KW_BIRDS_BINDING_POSES) writeonly buffer Poses { BirdPoseGpu poses[]; };
// The same binding as fields (POSE_FIELDS): field f of ring slot s at (s * 6 + f) * count + i.
layout(std430, binding = KW_BIRDS_BINDING_POSES) writeonly buffer PoseFields { vec4 pose_fields[]; };
layout(std430, binding = KW_BIRDS_BINDING_DIAGNOSTICS) writeonly buffer Diagnostics { BirdDiag diags[]; };
layout(std430, binding = KW_BIRDS_BINDING_MOTION) readonly buffer Motions { BirdMotionGpu motions[]; };

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
    float segment_mode;  // its mode (shared/birds.h KW_SEGMENT_AUTO or a KW_MODE_*)
    uint lo;       // cached arc-length interval [lo, lo + 1], 0xFFFFFFFF = none
    vec4 a, b;     // its two samples
    float inv_h;
};

RouteCache empty_cache() {
    RouteCache c;
    c.segment = 0xFFFFFFFFu;
    c.lo = 0xFFFFFFFFu;
    c.b0 = c.b1 = c.b2 = c.b3 = vec3(0.0);
    c.segment_mode = KW_SEGMENT_AUTO;
    c.a = c.b = vec4(0.0);
    c.inv_h = 0.0;
    return c;
}

Bezier bezier(RouteHeader route, uint seg, float u, inout RouteCache cache) {
    if (cache.segment != seg) {
        uint c = route.extent.x + 3u * seg;
        cache.segment = seg;
        vec4 first = control_points[c];
        cache.b0 = first.xyz;
        cache.segment_mode = first.w;
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
    vec3 attitude_velocity;  // flight.hpp RouteSample::attitude_velocity
    float segment_mode;      // exact
    float speed_fraction;    // exact (docs/flight-modes.md F.2)
    float since_crouch;
    float since_touchdown;
};

// flight.cpp motion_sample(): a driven bird's frame, from the motion another domain gave.
RouteSample motion_sample(BirdMotionGpu m) {
    RouteSample r;
    r.position = m.position.xyz;
    r.velocity = m.velocity.xyz;
    r.acceleration = m.acceleration.xyz;
    r.direction = r.velocity;
    r.lift = m.acceleration.y;
    r.lift_scale = 1.0;
    r.attitude_velocity = r.velocity;
    r.segment_mode = KW_SEGMENT_AUTO;
    r.speed_fraction = 1.0;
    r.since_crouch = 1e9;
    r.since_touchdown = -1.0;
    return r;
}

// flight.cpp route_motion_sample(): the cubic Hermite correction of a driven bird on its
// route (KW_MOTION_ROUTE, shared/birds.h) at the frame's time `now`, in flight.cpp's order
// of operations (`precise`: no contraction), so that positions agree with the cpu backends
// to rounding. Nothing exact changes: the correction moves the bird only.
void route_correction(inout RouteSample r, BirdMotionGpu m, float now) {
    float inv_t = m.acceleration.y;
    precise float s = clamp((now - m.acceleration.x) * inv_t, 0.0, 1.0);
    if (inv_t == 0.0 || !(s < 1.0)) return;  // no correction, or past t0 + T: the route's own bits
    precise float span = 1.0 / inv_t;
    precise float h00 = (2.0 * s - 3.0) * (s * s) + 1.0;
    precise float h10 = ((s - 2.0) * s + 1.0) * s;
    precise float d00 = (6.0 * s - 6.0) * s;
    precise float d10 = (3.0 * s - 4.0) * s + 1.0;
    precise float dd00 = 12.0 * s - 6.0;
    precise float dd10 = 6.0 * s - 4.0;
    vec3 ep = m.position.xyz, ev = m.velocity.xyz;
    precise vec3 c = h00 * ep + (span * h10) * ev;
    precise vec3 c1 = (d00 * inv_t) * ep + d10 * ev;
    precise vec3 c2 = ((dd00 * inv_t) * inv_t) * ep + (dd10 * inv_t) * ev;
    precise vec3 position = r.position + c;
    precise vec3 velocity = r.velocity + c1;
    precise vec3 attitude_velocity = r.attitude_velocity + c1;
    precise vec3 acceleration = r.acceleration + c2;
    r.position = position;
    r.velocity = velocity;
    r.attitude_velocity = attitude_velocity;
    r.acceleration = acceleration;
}

// One Bezier evaluation per frame: lavapipe runs both sides of a divergent branch, so
// the timing and end cases only choose the parameter and how the result is used.
RouteSample sample_route(RouteHeader route, float time, float speed, inout RouteCache cache) {
    bool loop = (route.flags.x & KW_ROUTE_LOOP) != 0u;
    precise float fraction = 1.0;
    float along = 0.0;
    float since_crouch = 1e9, since_touchdown = -1.0;
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
        precise float s;
        bool takeoff = (route.flags.x & KW_ROUTE_TAKEOFF) != 0u, landing = (route.flags.x & KW_ROUTE_LANDING) != 0u;
        if (takeoff || landing) {  // flight.cpp sample_route(): docs/flight-modes.md F.2
            precise float tau = takeoff ? time - float(KW_CROUCH_SECONDS) : time;
            precise float d = speed * tau;
            if (takeoff) since_crouch = tau;
            precise float two_l0 = 2.0 * route.perch.x;
            if (takeoff && d < two_l0) {
                if (d >= 0.0) {
                    precise float k0 = 0.25 * route.perch.y;
                    precise float k1 = 0.5 * route.perch.y;
                    s = d * d * k0;
                    fraction = d * k1;
                    along = speed * speed * k1;
                } else {
                    s = 0.0;
                    fraction = 0.0;
                }
            } else {
                s = takeoff ? d - route.perch.x : d;
            }
            if (landing) {
                precise float start = total - route.perch.z;
                if (s > start) {
                    precise float dl = s - start;
                    precise float two_ln = 2.0 * route.perch.z;
                    if (dl < two_ln) {
                        precise float kn0 = 0.25 * route.perch.w;
                        precise float kn1 = 0.5 * route.perch.w;
                        s = start + dl - dl * dl * kn0;
                        fraction = 1.0 - dl * kn1;
                        along = -(speed * speed * kn1);
                    } else {
                        s = total;
                        fraction = 0.0;
                        since_touchdown = (dl - two_ln) / speed;
                    }
                }
            }
        } else {
            s = speed * time;  // arc-length timing (SPEC B.3)
            if (loop) s = s - total * floor(s * route.info.z);
        }
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
    r.segment_mode = cache.segment_mode;
    r.speed_fraction = fraction;
    r.since_crouch = since_crouch;
    r.since_touchdown = since_touchdown;
    if (parametric) {
        r.position = outside ? e.p + beyond * e.d1 : e.p;
        r.velocity = route.info.w * e.d1;
        r.attitude_velocity = r.velocity;
        if (!outside) {
            r.acceleration = (route.info.w * route.info.w) * e.d2;
            r.lift = e.d2.y;  // a_y = P''_y / D^2
            precise float scale = route.info.y * route.info.y;
            r.lift_scale = scale;
        }
    } else {
        float d1_len = length(e.d1);
        vec3 tangent = (1.0 / d1_len) * e.d1;
        precise float now = fraction * speed;
        r.position = outside ? e.p + beyond * tangent : e.p;
        r.velocity = (outside ? speed : now) * tangent;
        r.attitude_velocity = outside ? r.velocity : vec3(speed * tangent.x, now * tangent.y, speed * tangent.z);
        if (!outside) {
            // a = v^2 (P'' - (P''.T)T) / |P'|^2; a_y exactly as lift / lift_scale.
            r.acceleration = ((now * now) / (d1_len * d1_len)) * (e.d2 - dot(e.d2, tangent) * tangent) + along * tangent;
            precise float dd = e.d1.x * e.d1.x + e.d1.y * e.d1.y + e.d1.z * e.d1.z;
            precise float d2d1 = e.d2.x * e.d1.x + e.d2.y * e.d1.y + e.d2.z * e.d1.z;
            precise float lift = (now * now) * (e.d2.y * dd - d2d1 * e.d1.y);
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

// engine/birds/flight.cpp body_frame(): the attitude's rotation without trig, as its
// yaw, climb pitch and bank factors.
struct BodyFrame { vec4 yaw; vec4 pitch; vec4 bank; bool moving; };

BodyFrame body_frame(vec3 v, vec3 a) {
    BodyFrame f;
    f.yaw = f.pitch = f.bank = vec4(0.0, 0.0, 0.0, 1.0);
    f.moving = false;
    float horizontal = sqrt(v.x * v.x + v.z * v.z);
    float speed = sqrt(horizontal * horizontal + v.y * v.y);
    if (speed <= 0.0) return f;
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
    f.yaw = yaw;
    f.pitch = pitch;
    f.bank = vec4(0.0, 0.0, b.y, b.x);
    f.moving = true;
    return f;
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

// engine/birds/flight.cpp flight_mode(): docs/flight-modes.md F.1, from exact inputs.
uint flight_mode(BirdParams bird, BirdState state, RouteSample r, uint climb_mode) {
    if (r.segment_mode >= 0.0) return uint(r.segment_mode);
    uint mode = climb_mode;
    if (bird.flight.w > 0.0 && bird.motion.x < 3.0) return KW_MODE_HOVER;  // flight.hpp kHoverBelowSpeed
    if (mode == KW_MODE_LEVEL && bird.flight.y > 0.0 && r.direction.y <= 0.0) {
        bool glide = state.mode.x == KW_MODE_GLIDE ? state.phase.y < bird.flight.z : state.phase.z >= bird.flight.y;
        if (glide) mode = KW_MODE_GLIDE;
    }
    return mode;
}

// engine/birds/wingbeat.cpp: the looks of the modes (docs/flight-modes.md F.3, F.5).
struct Look { vec4 wings; float pitch; float spread; float bob; };

const vec4 FOLDED_WINGS = vec4(-0.2, 0.1, 1.35, 0.25);
const vec4 GLIDE_WINGS = vec4(0.06, -0.04, 0.08, 0.12);
const vec4 FLARE_WINGS = vec4(0.45, -0.35, -0.55, 0.25);

float level_arm1(float t) {
    return t < 0.5 * PI ? 0.0 : t < PI ? -(2.0 / 3.0) * t + PI / 3.0 : t < 1.5 * PI ? -PI / 3.0 : (2.0 / 3.0) * t - (4.0 / 3.0) * PI;
}
float level_arm2(float t, float s) { return t < PI ? -(PI / 3.0) * s : -(3.0 / 18.0) * PI * s; }

Look mode_look(uint mode, float t, float sin_t, float cos_t, float amplitude, RouteSample r) {
    Look l;
    l.pitch = 0.0;
    l.spread = 0.0;
    l.bob = 0.0;
    if (mode <= KW_MODE_DESCEND) {
        l.wings = wing_angles(mode, t, sin_t, amplitude);
        l.spread = mode == KW_MODE_LEVEL ? 0.15 : mode == KW_MODE_ASCEND ? 0.35 : 0.1;
        l.bob = mode == KW_MODE_DESCEND ? 0.3 : 1.0;
    } else if (mode == KW_MODE_GLIDE) {
        l.wings = GLIDE_WINGS;
        l.spread = 0.25;
    } else if (mode == KW_MODE_TAKEOFF) {
        float open = smoothstep(0.0, float(KW_LEAP_SECONDS), r.since_crouch);
        vec4 beats = vec4(1.3 * amplitude * level_arm1(t), 1.3 * amplitude * level_arm2(t, sin_t), 0.3 * amplitude * cos_t, 0.0);
        l.wings = mix(FOLDED_WINGS, beats, open);
        l.pitch = mix(-0.2, 0.45 * (1.0 - r.speed_fraction), open);
        l.spread = 0.8 * open;
        l.bob = open;
    } else if (mode == KW_MODE_LANDING) {
        float flare = smoothstep(0.4, 1.0, 1.0 - r.speed_fraction);
        float fold = smoothstep(0.0, float(KW_FOLD_SECONDS), r.since_touchdown);
        vec4 beats = vec4(0.6 * amplitude * level_arm1(t), 0.6 * amplitude * level_arm2(t, sin_t), -0.25 + 0.25 * amplitude * cos_t, 0.0);
        l.wings = mix(mix(beats, FLARE_WINGS, flare), FOLDED_WINGS, fold);
        l.pitch = 0.8 * flare * (1.0 - fold);
        l.spread = (0.3 + 0.6 * flare) * (1.0 - fold);
        l.bob = (1.0 - flare) * (1.0 - fold);
    } else {  // hover: figure-eight strokes
        l.wings = vec4(0.2 * amplitude * sin(2.0 * t), -0.1 * amplitude * sin_t, 0.95 * amplitude * cos_t, 0.0);
        l.pitch = 0.6;
        l.spread = 0.5;
        l.bob = 0.5;
    }
    return l;
}

// wingbeat.cpp beat_factor(): exact.
float beat_factor(uint mode, RouteSample r) {
    if (mode == KW_MODE_GLIDE) return 0.0;
    if (mode == KW_MODE_TAKEOFF) return r.since_crouch < 0.0 ? 0.0 : 1.25;
    if (mode == KW_MODE_LANDING) return r.since_touchdown >= 0.0 ? 0.0 : 1.25;
    return 1.0;
}

// flight.cpp arm_rotation(): heading about the body's up axis, then pitch about its forward axis.
vec4 arm_rotation(float pitch, float heading) { return qmul_flight(quat_z(pitch), quat_y(heading)); }

// flight.cpp nlerp_turn(): a fraction k of q's turn, by nlerp, without trig.
vec4 nlerp_turn(vec4 q, float k) {
    vec4 p = vec4(k * q.xyz, (1.0 - k) + k * q.w);
    return p * (1.0 / sqrt(dot(p, p)));
}
vec4 nose_up(float angle) { return vec4(-sin(0.5 * angle), 0.0, 0.0, cos(0.5 * angle)); }

float blend_rate(uint mode) {
    return mode == KW_MODE_LEVEL ? u.blend_rates.x : mode == KW_MODE_ASCEND ? u.blend_rates.y : mode == KW_MODE_DESCEND ? u.blend_rates.z
         : mode == KW_MODE_GLIDE ? u.blend_rates2.x : mode == KW_MODE_TAKEOFF ? u.blend_rates2.y : mode == KW_MODE_LANDING ? u.blend_rates2.z
         : u.blend_rates2.w;
}

float weight_of(vec4 w0, vec3 w1, uint m) {
    return m < 4u ? w0[m] : w1[m - 4u];
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
        uint previous = state.mode.x;
        bool first = previous == KW_MODE_UNSET;

        // HAS_DRIVEN is a specialization constant: without driven birds this is the
        // route alone (lavapipe runs both sides of a branch). A driven bird flies its
        // motion (flown) or its own route at the motion's time offset and speed, eased by
        // route_correction() (KW_MOTION_ROUTE, shared/birds.h).
        const bool driven = HAS_DRIVEN && bird.ids.w == KW_BIRD_DRIVEN;
        BirdMotionGpu m = BirdMotionGpu(vec4(0.0), vec4(0.0), vec4(0.0));
        bool on_route = false;
        if (driven) {
            m = motions[k * push.frames.w + bird.ids.z];
            on_route = m.position.w == KW_MOTION_ROUTE;
        }
        const bool flown = driven && !on_route;
        precise float now = float(frame) * dt;
        precise float time = now + (on_route ? m.velocity.w : bird.offset.w);
        RouteSample r;
        if (flown) {
            r = motion_sample(m);
        } else {
            r = sample_route(route, time, on_route ? m.acceleration.z : bird.motion.x, cache);
            if (on_route) route_correction(r, m, now);
        }

        uint climb_previous = previous <= KW_MODE_DESCEND ? previous : previous == KW_MODE_GLIDE ? KW_MODE_LEVEL : KW_MODE_UNSET;
        uint mode = flight_mode(bird, state, r, next_mode(climb_previous, r));

        // Transition (SPEC B.6), seven weights: blend.xyzw and blend2.xyz; alpha in blend2.w.
        vec4 w0 = state.blend;
        vec3 w1 = state.blend2.xyz;
        precise float alpha = state.blend2.w;
        if (first) {
            w0 = vec4(mode == 0u ? 1.0 : 0.0, mode == 1u ? 1.0 : 0.0, mode == 2u ? 1.0 : 0.0, mode == 3u ? 1.0 : 0.0);
            w1 = vec3(mode == 4u ? 1.0 : 0.0, mode == 5u ? 1.0 : 0.0, mode == 6u ? 1.0 : 0.0);
            alpha = 1.0;
        } else if (mode != previous) {
            precise vec4 n0 = (1.0 - alpha) * w0 + alpha * vec4(previous == 0u ? 1.0 : 0.0, previous == 1u ? 1.0 : 0.0,
                                                                  previous == 2u ? 1.0 : 0.0, previous == 3u ? 1.0 : 0.0);
            precise vec3 n1 = (1.0 - alpha) * w1 + alpha * vec3(previous == 4u ? 1.0 : 0.0, previous == 5u ? 1.0 : 0.0,
                                                                  previous == 6u ? 1.0 : 0.0);
            w0 = n0;
            w1 = n1;
            alpha = 0.0;
        } else if (alpha < 1.0) {
            alpha = alpha + blend_rate(mode) * u.physics.w;
            if (alpha >= 1.0) {
                w0 = vec4(mode == 0u ? 1.0 : 0.0, mode == 1u ? 1.0 : 0.0, mode == 2u ? 1.0 : 0.0, mode == 3u ? 1.0 : 0.0);
                w1 = vec3(mode == 4u ? 1.0 : 0.0, mode == 5u ? 1.0 : 0.0, mode == 6u ? 1.0 : 0.0);
                alpha = 1.0;
            }
        }
        state.blend = w0;
        state.blend2 = vec4(w1, alpha);

        // Phase, by the mode's beat factor; completed beats drive the flap-glide rhythm.
        precise float increment = (bird.motion.y * dt) * beat_factor(mode, r);
        precise float phase = first ? bird.motion.w : state.phase.x + increment;
        float whole = floor(phase);
        phase = phase - whole;
        state.phase.x = phase;
        if (mode == KW_MODE_GLIDE) {
            precise float glided = (previous == KW_MODE_GLIDE ? state.phase.y : 0.0) + dt;
            state.phase.y = glided;
            state.phase.z = 0.0;
        } else {
            state.phase.y = 0.0;
            if (!first) {
                precise float beats = state.phase.z + whole;
                state.phase.z = beats;
            }
        }
        state.mode.x = mode;

        float t = phase * TWO_PI;
        if (t >= TWO_PI) t = 0.0;
        float amplitude = bird.motion.z;
        float sin_t = sin(t), cos_t = cos(t);
        Look target_look = mode_look(mode, t, sin_t, cos_t, amplitude, r);
        vec4 left1 = arm_rotation(target_look.wings.x, target_look.wings.z);
        vec4 left2 = arm_rotation(target_look.wings.y, target_look.wings.w);
        float pitch = target_look.pitch, spread = target_look.spread, bob = target_look.bob;
        if (alpha < 1.0) {  // a transition (SPEC B.6): the modes of the blend source
            vec4 sum1 = alpha * left1, sum2 = alpha * left2;
            pitch *= alpha;
            spread *= alpha;
            bob *= alpha;
            for (uint m = 0u; m < KW_MODE_COUNT; ++m) {
                float w = weight_of(w0, w1, m);
                if (w == 0.0) continue;
                Look l = mode_look(m, t, sin_t, cos_t, amplitude, r);
                vec4 q1 = arm_rotation(l.wings.x, l.wings.z), q2 = arm_rotation(l.wings.y, l.wings.w);
                float kw = (1.0 - alpha) * w;
                sum1 += (kw * (dot(q1, left1) < 0.0 ? -1.0 : 1.0)) * q1;
                sum2 += (kw * (dot(q2, left2) < 0.0 ? -1.0 : 1.0)) * q2;
                pitch += kw * l.pitch;
                spread += kw * l.spread;
                bob += kw * l.bob;
            }
            left1 = sum1 * (1.0 / sqrt(dot(sum1, sum1)));
            left2 = sum2 * (1.0 / sqrt(dot(sum2, sum2)));
        }

        // Body, head and tail: flight.cpp step_bird(), docs/flight-modes.md F.5.
        vec3 v = r.attitude_velocity, a = r.acceleration;
        BodyFrame f = body_frame(v, a);
        // The roll filter (flight.cpp step_bird(), docs/flight-modes.md F.6): a first-order
        // low-pass of the bank quaternion's (w, z) and of the lateral acceleration.
        float horizontal = sqrt(v.x * v.x + v.z * v.z);
        float lateral = horizontal > 1e-3 ? (a.x * -v.z + a.z * v.x) / horizontal : 0.0;
        vec3 target = vec3(f.bank.w, f.bank.z, lateral);
        vec3 roll = first ? target : target + u.bank_limit.z * (state.roll.xyz - target);
        state.roll = vec4(roll, 0.0);
        if (f.moving) f.bank = vec4(0.0, 0.0, roll.y, roll.x) * (1.0 / sqrt(roll.x * roll.x + roll.y * roll.y));
        vec4 body_base = qmul_flight(qmul_flight(f.yaw, f.pitch), f.bank);  // identity factors when not moving
        float oscillation = float(KW_BOB_PITCH) * amplitude * sin_t * bob;
        float extra = pitch + oscillation;
        vec4 body = qmul_flight(body_base, nose_up(extra));
        float bob_height = -float(KW_BOB_HEIGHT) * bird.shape.x * amplitude * cos_t * bob;
        float sin_bank = 2.0 * f.bank.z * f.bank.w;
        float look = 0.0;
        if (horizontal > 1e-3) look = clamp(-float(KW_LOOK_AHEAD) * roll.z / horizontal, -float(KW_MAX_LOOK), float(KW_MAX_LOOK));
        vec4 head = qmul_flight(qmul_flight(qmul_flight(nose_up(-(float(KW_HEAD_PITCH_HOLD) * pitch + float(KW_HEAD_BOB_HOLD) * oscillation)),
                                                        nlerp_turn(qconj(f.bank), float(KW_HEAD_BANK_HOLD))),
                                            nlerp_turn(qconj(f.pitch), float(KW_HEAD_CLIMB_HOLD))),
                                quat_y(look));
        vec4 tail = qmul_flight(qmul_flight(nlerp_turn(f.pitch, float(KW_TAIL_CLIMB)), nose_up(float(KW_TAIL_PITCH) * pitch)),
                                nlerp_turn(f.bank, float(KW_TAIL_BANK)));
        float tail_spread = spread + float(KW_TAIL_BANK_SPREAD) * abs(sin_bank);

        uint slot = (k % push.frames.z) * count + i;
        vec3 position = flown ? r.position : r.position + bird.offset.xyz;
        const vec4 placed = vec4(position.x, position.y + bob_height, position.z, tail_spread);
        if (POSE_FIELDS) {
            uint field = (k % push.frames.z) * 6u * count + i;
            pose_fields[field] = placed;
            pose_fields[field + count] = body;
            pose_fields[field + 2u * count] = head;
            pose_fields[field + 3u * count] = tail;
            pose_fields[field + 4u * count] = left1;
            pose_fields[field + 5u * count] = left2;
        } else {
            poses[slot].position = placed;
            poses[slot].body = body;
            poses[slot].head = head;
            poses[slot].tail = tail;
            poses[slot].left_arm1 = left1;
            poses[slot].left_arm2 = left2;
        }
        if (WRITE_DIAGNOSTICS) {
            diags[slot].velocity = vec4(r.velocity, alpha);
            diags[slot].acceleration = vec4(r.acceleration, float(mode));
            diags[slot].angles = target_look.wings;
            vec3 angles = attitude(v, a);
            angles.z = 2.0 * atan(f.bank.z, f.bank.w);  // the Body's (filtered) bank
            diags[slot].attitude = vec4(angles, t);
            diags[slot].flight = vec4(r.speed_fraction, extra, tail_spread, state.phase.y);
        }
    }
    states[i] = state;
}
