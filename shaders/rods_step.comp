#version 450
// One frame of the view-dependent rods (SPEC part A) for every chain: one invocation per
// chain computes the view direction and weights (A.3), blends the rest shape (A.2),
// applies momentum suppression (A.5) and runs every substep and projection iteration of
// the oriented-particles solver (A.4) in registers. Mirrors engine/rods/world.cpp,
// shape.cpp and solver.cpp step for step; the equations' sources are cited there.
#extension GL_GOOGLE_include_directive : require

#include "shared/rods.h"

layout(local_size_x = KW_RODS_WORKGROUP_SIZE) in;

// Sizes the per-chain register arrays: the longest chain of the world, not
// KW_RODS_MAX_JOINTS, so short chains do not pay for 32-joint arrays.
layout(constant_id = KW_RODS_SPEC_MAX_JOINTS) const uint MAX_J = 16;

layout(std430, binding = KW_RODS_BINDING_TEMPLATES) readonly buffer Templates { RodTemplateGpu templates[]; };
layout(std430, binding = KW_RODS_BINDING_TEMPLATE_JOINTS) readonly buffer TemplateJoints { RodTemplateJointGpu tjoints[]; };
layout(std430, binding = KW_RODS_BINDING_SHAPES) readonly buffer Shapes { RodShapeJointGpu shapes[]; };
layout(std430, binding = KW_RODS_BINDING_CHAINS) readonly buffer Chains { RodChainGpu chains[]; };
layout(std430, binding = KW_RODS_BINDING_REFERENCE) readonly buffer Reference { RodTransformGpu reference[]; };
layout(std430, binding = KW_RODS_BINDING_ROOTS) readonly buffer Roots { RodTransformGpu roots[]; };
layout(std430, binding = KW_RODS_BINDING_COLLIDERS) readonly buffer Colliders { RodColliderGpu colliders[]; };
layout(std430, binding = KW_RODS_BINDING_MOTION) buffer Motion { RodJointMotionGpu motion[]; };
layout(std430, binding = KW_RODS_BINDING_SPIN) buffer Spin { RodJointSpinGpu spin[]; };
layout(std430, binding = KW_RODS_BINDING_REST) buffer Rest { RodJointRestGpu rest[]; };
layout(std430, binding = KW_RODS_BINDING_CHAIN_STATE) buffer ChainStates { RodChainStateGpu chain_states[]; };

layout(push_constant) uniform Push { RodPush push; };

const vec4 IDENTITY = vec4(0.0, 0.0, 0.0, 1.0);
const float ROOT_SHAPE_WEIGHT = 10.0;  // solver.cpp kRootShapeWeight
const int EXTRACT_ITERATIONS = 10;     // solver.cpp kExtractIterations

// ---- quaternions, as glm computes them -------------------------------------------------

vec4 qmul(vec4 p, vec4 q) {
    return vec4(p.w * q.x + p.x * q.w + p.y * q.z - p.z * q.y, p.w * q.y + p.y * q.w + p.z * q.x - p.x * q.z,
                p.w * q.z + p.z * q.w + p.x * q.y - p.y * q.x, p.w * q.w - p.x * q.x - p.y * q.y - p.z * q.z);
}
vec4 qconj(vec4 q) { return vec4(-q.xyz, q.w); }
vec3 qrot(vec4 q, vec3 v) {
    const vec3 uv = cross(q.xyz, v);
    const vec3 uuv = cross(q.xyz, uv);
    return v + ((uv * q.w) + uuv) * 2.0;
}
vec4 qnormalize(vec4 q) {
    const float len = length(q);
    if (len <= 0.0) return IDENTITY;
    return q * (1.0 / len);
}
vec4 positive_w(vec4 q) { return q.w < 0.0 ? -q : q; }
mat3 mat3_cast(vec4 q) {
    const float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const float xz = q.x * q.z, xy = q.x * q.y, yz = q.y * q.z;
    const float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    return mat3(vec3(1.0 - 2.0 * (yy + zz), 2.0 * (xy + wz), 2.0 * (xz - wy)),
                vec3(2.0 * (xy - wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz + wx)),
                vec3(2.0 * (xz + wy), 2.0 * (yz - wx), 1.0 - 2.0 * (xx + yy)));
}
vec4 angle_axis(float angle, vec3 axis) { return vec4(axis * sin(angle * 0.5), cos(angle * 0.5)); }
// solver.cpp partial(): the rotation by `fraction` of q's angle, the short way.
vec4 partial_turn(vec4 q, float fraction) {
    if (fraction >= 1.0) return q;
    if (fraction <= 0.0) return IDENTITY;
    q = positive_w(q);
    const float sn = length(q.xyz);
    if (!(sn > 0.0)) return IDENTITY;
    const float half_angle = fraction * atan(sn, q.w);
    return qnormalize(vec4(sin(half_angle) * (q.xyz / sn), cos(half_angle)));
}
// solver.cpp interpolate().
vec4 interpolate(vec4 a, vec4 b, float t) { return qnormalize(qmul(a, partial_turn(qmul(qconj(a), b), t))); }
// shape.cpp shortest_arc().
vec4 shortest_arc(vec3 from, vec3 to) {
    const vec3 h = from + to;
    const float h_len = length(h);
    if (h_len < 1e-6) {
        const vec3 a = abs(from);
        const vec3 other = (a.x <= a.y && a.x <= a.z) ? vec3(1, 0, 0) : (a.y <= a.z) ? vec3(0, 1, 0) : vec3(0, 0, 1);
        return vec4(normalize(cross(from, other)), 0.0);
    }
    const vec3 hn = h / h_len;
    return qnormalize(vec4(cross(from, hn), dot(from, hn)));
}
// solver.cpp extract_rotation(): Mueller et al. 2016, Algorithm 1, warm-started.
vec4 extract_rotation(mat3 a, vec4 q) {
    for (int iter = 0; iter < EXTRACT_ITERATIONS; ++iter) {
        const mat3 r = mat3_cast(q);
        const vec3 torque = cross(r[0], a[0]) + cross(r[1], a[1]) + cross(r[2], a[2]);
        const float alignment = abs(dot(r[0], a[0]) + dot(r[1], a[1]) + dot(r[2], a[2]));
        const vec3 omega = torque / (alignment + 1e-9);
        const float angle = length(omega);
        if (!(angle > 1e-6)) break;
        q = qnormalize(qmul(angle_axis(angle, omega / angle), q));
    }
    return q;
}
void push_out(inout vec3 p, vec3 center, float radius) {
    const vec3 d = p - center;
    const float len2 = dot(d, d);
    if (len2 >= radius * radius) return;
    const float len = sqrt(len2);
    const vec3 n = len > 1e-9 ? d / len : vec3(0.0, 1.0, 0.0);
    p = center + radius * n;
}
vec3 closest_on_segment(vec3 p, vec3 a, vec3 b) {
    const vec3 ab = b - a;
    const float len2 = dot(ab, ab);
    if (len2 <= 0.0) return a;
    const float t = clamp(dot(p - a, ab) / len2, 0.0, 1.0);
    return a + t * ab;
}

void main() {
    const uint c = gl_GlobalInvocationID.x;
    if (c >= push.counts.x) return;

    const RodChainGpu chain = chains[c];
    const RodTemplateGpu t = templates[chain.ids.x];
    const uint n = t.counts.x;
    const uint m = t.counts.y;
    const uint tj = t.counts.z;
    const uint shape0 = t.counts.w;
    const uint j0 = chain.joints.x;

    // ---- A.3: view direction and weights (world.cpp rest_shape, view.cpp) ----
    const RodTransformGpu ref = reference[chain.ids.y];
    const vec4 to_reference = qconj(ref.rotation);
    vec3 d;
    {
        const vec3 offset = push.camera_position.xyz - ref.position.xyz;
        const float len = length(offset);
        if (push.camera_position.w == 0.0 && len >= 1e-6) {
            d = qrot(to_reference, offset / len);
        } else {
            d = normalize(qrot(to_reference, -push.camera_forward.xyz));
        }
    }
    float w[KW_RODS_MAX_VIEWS + 1];
    {
        float sum = 0.0;
        for (uint k = 0; k < m; ++k) {
            const vec4 view = t.views[k];
            const float s = clamp((dot(view.xyz, d) + 1.0) * 0.5, 0.0, 1.0);
            w[k + 1] = pow(s, view.w);
            sum += w[k + 1];
        }
        if (sum >= 1.0) {
            for (uint k = 1; k <= m; ++k) w[k] /= sum;
            sum = 1.0;
        }
        w[0] = 1.0 - sum;
    }

    // ---- A.2: blend, then forward kinematics (shape.cpp blend, to_positions) ----
    vec3 rest_p[MAX_J];
    vec4 rest_o[MAX_J];
    {
        vec3 dir = t.first_dir.xyz;
        rest_p[0] = vec3(0.0);
        for (uint i = 0; i < n; ++i) {
            const RodShapeJointGpu base = shapes[shape0 + i];
            vec4 r_sum = vec4(0.0), o_sum = vec4(0.0);
            for (uint k = 0; k <= m; ++k) {
                const RodShapeJointGpu s = shapes[shape0 + k * n + i];
                r_sum += ((dot(s.rotation, base.rotation) < 0.0 ? -1.0 : 1.0) * w[k]) * s.rotation;
                o_sum += ((dot(s.orientation, base.orientation) < 0.0 ? -1.0 : 1.0) * w[k]) * s.orientation;
            }
            const float r_len = length(r_sum), o_len = length(o_sum);
            rest_o[i] = o_len > 1e-12 ? o_sum / o_len : base.orientation;
            if (i + 1 < n) {
                const vec4 r = r_len > 1e-12 ? r_sum / r_len : base.rotation;
                dir = normalize(qrot(r, dir));
                rest_p[i + 1] = rest_p[i] + tjoints[tj + i].lengths.x * dir;
            }
        }
    }

    // ---- load the state ----
    vec3 x[MAX_J], v[MAX_J], omega[MAX_J];
    vec4 q[MAX_J], group[MAX_J];
    for (uint i = 0; i < n; ++i) {
        const RodJointMotionGpu mo = motion[j0 + i];
        const RodJointSpinGpu sp = spin[j0 + i];
        x[i] = mo.x.xyz;
        v[i] = mo.v.xyz;
        q[i] = sp.q;
        omega[i] = sp.omega.xyz;
        group[i] = sp.group;
    }
    const RodTransformGpu from = chain_states[c].root;
    const RodTransformGpu to = roots[c];

    // ---- A.5: momentum suppression (solver.cpp suppress_momentum) ----
    const float suppression = t.step.w;
    if (suppression > 0.0) {
        const vec4 root = from.rotation;
        const vec4 root_inv = qconj(root);
        vec3 previous_old = x[0];
        vec3 old_rest = rest[j0].position.xyz;
        for (uint i = 0; i + 1 < n; ++i) {
            const vec3 old_next = rest[j0 + i + 1].position.xyz;
            const vec3 old_dir = normalize(old_next - old_rest);
            const vec3 new_dir = normalize(rest_p[i + 1] - rest_p[i]);
            old_rest = old_next;
            const vec4 turn = partial_turn(qmul(qmul(root, shortest_arc(old_dir, new_dir)), root_inv), suppression);
            const vec3 segment = x[i + 1] - previous_old;
            previous_old = x[i + 1];
            x[i + 1] = x[i] + qrot(turn, segment);
        }
        for (uint i = 1; i < n; ++i) {
            const vec4 change = positive_w(qmul(rest_o[i], qconj(rest[j0 + i].orientation)));
            q[i] = qnormalize(qmul(partial_turn(qmul(qmul(root, change), root_inv), suppression), q[i]));
        }
    }
    for (uint i = 0; i < n; ++i) rest[j0 + i] = RodJointRestGpu(vec4(rest_p[i], 0.0), rest_o[i]);

    // ---- A.4: the substeps (solver.cpp step) ----
    const uint substeps = t.solver.y;
    const uint iterations = t.solver.x;
    const float h = t.step.x;
    const float decay = t.step.y;
    const float k_iter = t.step.z;
    const float k_rest = t.physics.y;
    const float b2 = t.physics.x * t.physics.x;
    const vec3 acceleration = t.accel.xyz;
    const float thickness = t.physics.x;
    const uint cbegin = chain.ids.z;
    const uint cend = chain.ids.z + chain.ids.w;

    // Solved relative to the previous root position, as the state is (solver.cpp).
    const vec3 travel = to.position.xyz - from.position.xyz;
    vec3 p[MAX_J], xbar[MAX_J], goal_sum[MAX_J];
    vec4 qs[MAX_J], obar[MAX_J], q_new[MAX_J];
    for (uint sub = 1; sub <= substeps; ++sub) {
        const float f = float(sub) / float(substeps);
        const vec3 r_pos = f * travel;
        const vec4 r_rot = interpolate(from.rotation, to.rotation, f);

        for (uint i = 0; i < n; ++i) {
            xbar[i] = r_pos + qrot(r_rot, rest_p[i]);
            obar[i] = qnormalize(qmul(r_rot, rest_o[i]));
        }
        p[0] = xbar[0];
        qs[0] = obar[0];

        for (uint i = 1; i < n; ++i) {
            v[i] = decay * (v[i] + h * acceleration);
            omega[i] = decay * omega[i];
            p[i] = x[i] + h * v[i];
            const float wl = length(omega[i]);
            if (wl > 0.0) {
                const float half_angle = 0.5 * wl * h;
                const vec3 axis = omega[i] / wl;
                qs[i] = qnormalize(qmul(vec4(sin(half_angle) * axis, cos(half_angle)), q[i]));
            } else {
                qs[i] = q[i];
            }
        }

        for (uint it = 0; it < iterations; ++it) {
            // The ellipsoid terms A_j (solver.cpp), once per particle per iteration.
            mat3 a_j[MAX_J];
            for (uint j = 0; j < n; ++j) {
                const vec4 am = tjoints[tj + j].axis_mass;
                const float mass = j == 0 ? ROOT_SHAPE_WEIGHT * am.w : am.w;
                const float half_length = tjoints[tj + j].lengths.y;
                const float a2 = half_length * half_length;
                const mat3 rj = mat3_cast(qs[j]);
                const mat3 rbarj = mat3_cast(obar[j]);
                const vec3 u = am.xyz;
                a_j[j] = (mass / 5.0) * (b2 * (rj * transpose(rbarj)) + (a2 - b2) * outerProduct(rj * u, rbarj * u));
                goal_sum[j] = vec3(0.0);
            }
            for (uint i = 0; i < n; ++i) {
                const uint lo = i == 0 ? 0 : i - 1;
                const uint hi = min(i + 1, n - 1);
                float group_mass = 0.0;
                vec3 cm = vec3(0.0), cbar = vec3(0.0);
                for (uint j = lo; j <= hi; ++j) {
                    const float mass = j == 0 ? ROOT_SHAPE_WEIGHT * tjoints[tj].axis_mass.w : tjoints[tj + j].axis_mass.w;
                    group_mass += mass;
                    cm += mass * p[j];
                    cbar += mass * xbar[j];
                }
                cm /= group_mass;
                cbar /= group_mass;
                mat3 a = mat3(0.0);
                for (uint j = lo; j <= hi; ++j) {
                    const float mass = j == 0 ? ROOT_SHAPE_WEIGHT * tjoints[tj].axis_mass.w : tjoints[tj + j].axis_mass.w;
                    a += mass * outerProduct(p[j] - cm, xbar[j] - cbar);
                    a += a_j[j];
                }
                const vec4 rot = extract_rotation(a, group[i]);
                group[i] = rot;
                for (uint j = lo; j <= hi; ++j) goal_sum[j] += cm + qrot(rot, xbar[j] - cbar);
                q_new[i] = qnormalize(qmul(rot, obar[i]));
            }
            for (uint i = 1; i < n; ++i) {
                // Groups containing joint i: 2 at either end, 3 inside.
                const float count = (i + 1 == n) ? 2.0 : 3.0;
                p[i] += k_iter * (goal_sum[i] / count - p[i]);
                qs[i] = q_new[i];
            }

            // Rest-pose attraction (solver.cpp; Han & Harada 2012, global shape constraint).
            for (uint i = 1; i < n; ++i) p[i] += k_rest * (xbar[i] - p[i]);

            for (uint i = 0; i + 1 < n; ++i) {
                const vec3 dd = p[i + 1] - p[i];
                const float len = length(dd);
                if (!(len > 1e-9)) continue;
                p[i + 1] = p[i] + (tjoints[tj + i].lengths.x / len) * dd;
            }

            // Collisions, in the CPU's order: each particle against every collider.
            for (uint i = 1; i < n; ++i) {
                for (uint ci = cbegin; ci < cend; ++ci) {
                    const RodColliderGpu col = colliders[ci];
                    const vec3 a = col.a.xyz - from.position.xyz, b = col.b.xyz - from.position.xyz;
                    push_out(p[i], closest_on_segment(p[i], a, b), col.a.w + thickness);
                }
            }
        }

        for (uint i = 0; i < n; ++i) {
            v[i] = (p[i] - x[i]) / h;
            const vec4 dq = positive_w(qmul(qs[i], qconj(q[i])));
            const float sn = length(dq.xyz);
            omega[i] = sn > 0.0 ? dq.xyz * (2.0 * atan(sn, dq.w) / (sn * h)) : vec3(0.0);
            x[i] = p[i];
            q[i] = qs[i];
        }
    }

    // ---- store ----
    for (uint i = 0; i < n; ++i) {
        x[i] -= travel;
        motion[j0 + i] = RodJointMotionGpu(vec4(x[i], 0.0), vec4(v[i], 0.0));
        spin[j0 + i] = RodJointSpinGpu(q[i], vec4(omega[i], 0.0), group[i]);
    }
    for (uint k = m + 1; k <= KW_RODS_MAX_VIEWS; ++k) w[k] = 0.0;
    chain_states[c] = RodChainStateGpu(to, vec4(d, 0.0), vec4[2](vec4(w[0], w[1], w[2], w[3]), vec4(w[4], w[5], w[6], w[7])));
}
