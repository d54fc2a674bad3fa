#version 450
// One frame of the view-dependent rods (SPEC part A), a chain per group of LANES
// invocations and a joint per invocation: the GPU-first mapping that shared/rods.h's "On a
// discrete GPU" describes, built as a variant for the first GPU run to time against
// rods_step.comp's chain per invocation (issue 38, item 2; BackendOptions::rod_kernel,
// RodKernel::PerJoint).
//
// Each lane keeps its own joint's state and template constants (a few dozen registers
// instead of a whole chain's), and the chain's joints are consecutive lanes, so the
// state's loads and stores are consecutive addresses across a subgroup. Neighbours are
// exchanged through shared memory: shape matching (SPEC A.4) reads joints i-1 and i+1 as
// they were at the start of the iteration, so every group is solved at once, one lane
// each; what is sequential along the chain (the rest shape's forward kinematics, A.5's
// carried segments, follow-the-leader placement and the colliders, which start from the
// parent's final position) is run by the chain's first lane while the others wait at the
// barrier. The operations and their order are rods_step.comp's (and engine/rods/solver.cpp's,
// where the equations' sources are cited): a world it runs gets the same bits.
//
// It covers the worlds of a GROUPED dispatch (one template per dispatch, so the substep and
// iteration counts that bound the loops around the barriers are the same for every lane of
// a workgroup) without levels of detail, keyed examples, center frames or angle limits;
// the backend refuses the others (vulkan_rods_load.cpp, kernel_variant_for).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

#include "shared/rods.h"
#include "lib/quat.glsl"
#include "lib/wind.glsl"

layout(local_size_x = KW_RODS_WORKGROUP_SIZE, local_size_x_id = KW_RODS_SPEC_WORKGROUP_SIZE) in;

// Lanes per chain: a power of two (2 to 32), at least the template's joints and at most
// the workgroup's size, so that a workgroup holds whole chains.
layout(constant_id = KW_RODS_SPEC_LANES) const uint LANES = 16;
layout(constant_id = KW_RODS_SPEC_MAX_VIEWS) const uint MAX_VIEWS = KW_RODS_MAX_VIEWS;
layout(constant_id = KW_RODS_SPEC_SUPPRESSION) const uint SUPPRESSION = KW_RODS_SUPPRESSION_PARTIAL;
layout(constant_id = KW_RODS_SPEC_FEATURES) const uint FEATURES = 0u;
layout(constant_id = KW_RODS_SPEC_MAX_COLLIDERS) const uint MAX_COLLIDERS = KW_RODS_MAX_CHAIN_COLLIDERS;

layout(std430, binding = KW_RODS_BINDING_TEMPLATES) readonly buffer Templates { RodTemplateGpu templates[]; };
layout(std430, binding = KW_RODS_BINDING_TEMPLATE_JOINTS) readonly buffer TemplateJoints { RodTemplateJointGpu tjoints[]; };
layout(std430, binding = KW_RODS_BINDING_SHAPES) readonly buffer Shapes { RodShapeJointGpu shapes[]; };
layout(std430, binding = KW_RODS_BINDING_CHAINS) readonly buffer Chains { RodChainGpu chains[]; };
layout(std430, binding = KW_RODS_BINDING_REFERENCE) readonly buffer Reference { RodTransformGpu reference[]; };
layout(std430, binding = KW_RODS_BINDING_ROOTS) readonly buffer Roots { RodTransformGpu roots[]; };
layout(std430, binding = KW_RODS_BINDING_COLLIDERS) readonly buffer Colliders { RodColliderGpu colliders[]; };
layout(std430, binding = KW_RODS_BINDING_MOTION) buffer Motion { RodJointMotionGpu motion[]; };
layout(std430, binding = KW_RODS_BINDING_SPIN) buffer Spin { RodJointSpinGpu spin[]; };
layout(std430, binding = KW_RODS_BINDING_CHAIN_STATE) buffer ChainStates { RodChainStateGpu chain_states[]; };
layout(std430, binding = KW_RODS_BINDING_WINDS) readonly buffer Winds { RodWindGpu winds[]; };

layout(push_constant) uniform Push { RodPush push; };

#include "lib/rod_solver.glsl"

// What lanes exchange, one entry per lane (the chain's joint i at base + i). Before the
// substeps s_g0 and s_g1 hold the rest shapes' positions and s_q0, s_q1 the blended
// rotations, then A.5's turns; during them s_g0..2 hold each group's goals for its lo,
// middle and hi members.
shared vec3 s_p[gl_WorkGroupSize.x], s_xbar[gl_WorkGroupSize.x], s_x[gl_WorkGroupSize.x];
shared vec3 s_pulled[gl_WorkGroupSize.x], s_pushed[gl_WorkGroupSize.x];
shared vec3 s_g0[gl_WorkGroupSize.x], s_g1[gl_WorkGroupSize.x], s_g2[gl_WorkGroupSize.x];
shared mat3 s_a[gl_WorkGroupSize.x];
shared vec4 s_q0[gl_WorkGroupSize.x], s_q1[gl_WorkGroupSize.x];
shared float s_weight[gl_WorkGroupSize.x], s_seg[gl_WorkGroupSize.x];

// Particle j (>= 1) of the chain at `base` placed on its parent's segment length,
// follow-the-leader, its correction kept for DFTL (rods_step.comp KW_PLACE).
void place(uint base, uint j) {
    const vec3 pj = s_p[base + j];
    const vec3 parent = s_p[base + j - 1];
    const vec3 dd = pj - parent;
    const float len = length(dd);
    if (len > 1e-9) {
        const vec3 placed = parent + (s_seg[base + j - 1] / len) * dd;
        s_pulled[base + j] += placed - pj;
        s_p[base + j] = placed;
    }
}
// Particle j (>= 1) pushed out of the colliders, the push kept (rods_step.comp KW_COLLIDE).
void collide(uint base, uint j) {
    vec3 pj = s_p[base + j];
    const vec3 before = pj;
    collide_all(pj);
    s_pushed[base + j] += pj - before;
    s_p[base + j] = pj;
}

void main() {
    const uint lane = gl_LocalInvocationID.x % LANES;
    const uint base = gl_LocalInvocationID.x - lane;  // the chain's first lane
    const uint e = gl_WorkGroupID.x * (gl_WorkGroupSize.x / LANES) + gl_LocalInvocationID.x / LANES;
    // Lanes past the dispatch's chains or past the chain's joints compute on clamped
    // indices (their loads stay in bounds) and store nothing, but reach every barrier.
    const bool in_range = e < push.counts.x;
    const RodChainGpu chain = chains[push.counts.y + min(e, push.counts.x - 1u)];
    const uint c = chain.joints.y;
    const RodTemplateGpu t = templates[push.group.x];
    const uint n = push.group.y;
    const uint m = push.group.z;
    const uint i = lane;
    const bool live = in_range && i < n;
    const uint ic = min(i, n - 1u);
    const uint j0 = chain.joints.x;

    // This joint's template constants (rods_step.comp load_constants, one joint's).
    const RodTemplateJointGpu tjoint = tjoints[push.counts.z + ic];
    const vec3 axis = tjoint.axis_mass.xyz;
    const float weight = i == 0 ? ROOT_SHAPE_WEIGHT * tjoint.axis_mass.w : tjoint.axis_mass.w;
    const float seg_len = tjoint.lengths.x;
    const float half_len = tjoint.lengths.y;
    vec4 rotation[MAX_VIEWS + 1], orientation[MAX_VIEWS + 1];
    [[unroll]] for (uint v = 0; v <= MAX_VIEWS; ++v) {
        const RodShapeJointGpu s = shapes[push.counts.w + min(v, m) * n + ic];
        rotation[v] = s.rotation;
        orientation[v] = s.orientation;
    }
    s_weight[gl_LocalInvocationID.x] = weight;
    s_seg[gl_LocalInvocationID.x] = seg_len;

    // ---- A.3: view direction and weights (every lane of the chain the same) ----
    const RodTransformGpu ref = reference[chain.ids.y];
    const vec3 d = view_direction(ref);
    float w[KW_RODS_MAX_VIEWS + 1];
    view_weights(t, m, d, w);

    // ---- A.2: blend (this joint's rotations), then forward kinematics (sequential) ----
    const RodChainStateGpu last = chain_states[c];
    const float w_old[KW_RODS_MAX_VIEWS + 1] = float[](last.weights[0].x, last.weights[0].y, last.weights[0].z, last.weights[0].w,
                                                       last.weights[1].x, last.weights[1].y, last.weights[1].z, last.weights[1].w);
    vec4 rest_o, old_rest_o;
    {
        vec4 r_sum = w[0] * rotation[0], o_sum = w[0] * orientation[0];
        vec4 r_old = w_old[0] * rotation[0], o_old = w_old[0] * orientation[0];
        [[unroll]] for (uint v = 1; v <= MAX_VIEWS; ++v) {
            if (v <= m) {
                r_sum += w[v] * rotation[v];
                o_sum += w[v] * orientation[v];
                r_old += w_old[v] * rotation[v];
                o_old += w_old[v] * orientation[v];
            }
        }
        rest_o = length(o_sum) > 1e-12 ? o_sum / length(o_sum) : orientation[0];
        old_rest_o = length(o_old) > 1e-12 ? o_old / length(o_old) : orientation[0];
        s_q0[gl_LocalInvocationID.x] = length(r_sum) > 1e-12 ? r_sum / length(r_sum) : rotation[0];
        s_q1[gl_LocalInvocationID.x] = length(r_old) > 1e-12 ? r_old / length(r_old) : rotation[0];
    }
    barrier();
    if (lane == 0u) {
        vec3 dir = t.first_dir.xyz, old_dir = t.first_dir.xyz;
        vec3 rest = vec3(0.0), old_rest = vec3(0.0);
        s_g0[base] = rest;
        s_g1[base] = old_rest;
        for (uint k = 0; k + 1 < n; ++k) {
            dir = normalize(qrot(s_q0[base + k], dir));
            old_dir = normalize(qrot(s_q1[base + k], old_dir));
            rest = rest + s_seg[base + k] * dir;
            old_rest = old_rest + s_seg[base + k] * old_dir;
            s_g0[base + k + 1] = rest;
            s_g1[base + k + 1] = old_rest;
        }
    }
    barrier();
    // (lanes past the chain's joints have no rest position: the origin, never stored)
    const vec3 rest_p = i < n ? s_g0[gl_LocalInvocationID.x] : vec3(0.0);

    // ---- load the state ----
    vec3 x = vec3(0.0), v = vec3(0.0), omega = vec3(0.0);
    vec4 q = IDENTITY;
    if (live) {
        const RodJointMotionGpu mo = motion[j0 + i];
        const RodJointSpinGpu sp = spin[j0 + i];
        x = mo.x.xyz;
        v = mo.v.xyz;
        q = sp.q;
        omega = sp.omega.xyz;
    }
    RodTransformGpu from = last.root;
    const RodTransformGpu to = roots[c];

    // ---- the chain carried by a teleport, the root's jump (solver_root_motion.cpp follow_teleport):
    // to the new root, then back by one frame of joint 0's own motion ----
    const vec3 jump = to.position.xyz - from.position.xyz;
    const bool teleported = dot(jump, jump) > t.physics.z * t.physics.z;
    s_p[gl_LocalInvocationID.x] = v;  // joint 0's motion, for every lane
    s_x[gl_LocalInvocationID.x] = omega;
    barrier();
    vec3 v0 = s_p[base], omega0 = s_x[base];
    barrier();
    if (teleported) {
        [[unroll]] for (uint pass = 1; pass < 3; ++pass) {
            RodTransformGpu was = from, now = to;
            if (pass == 2) {
                const float dt = push.camera_forward.w;
                const vec3 turn = omega0 * dt;
                const float angle = length(turn);
                const vec3 turn_axis = angle > 0.0 ? turn / angle : vec3(0.0);
                const vec4 back = vec4(-sin(0.5 * angle) * turn_axis, cos(0.5 * angle));
                was = to;
                now.position = vec4(to.position.xyz - v0 * dt, 0.0);
                now.rotation = qnormalize(qmul(back, to.rotation));
            }
            const vec4 r = qnormalize(qmul(now.rotation, qconj(was.rotation)));
            x = qrot(r, x);
            v = qrot(r, v);
            q = qnormalize(qmul(r, q));
            omega = qrot(r, omega);
            // Joint 0's, as lane 0 turns its own (the same operation: the same bits).
            v0 = qrot(r, v0);
            omega0 = qrot(r, omega0);
            from.position = vec4(now.position.xyz + qrot(r, from.position.xyz - was.position.xyz), 0.0);
            from.rotation = qnormalize(qmul(r, from.rotation));
        }
    }

    // ---- the first step starts moving with the root (solver_root_motion.cpp start_moving) ----
    if ((push.flags.x & KW_RODS_STEP_FIRST) != 0u && t.physics.w != 0.0) {
        const float dt = push.camera_forward.w;
        const vec4 turn = positive_w(qnormalize(qmul(to.rotation, qconj(from.rotation))));
        const vec3 moved = to.position.xyz - from.position.xyz;
        const vec3 spun = (2.0 / dt) * turn.xyz;
        v += (moved + (qrot(turn, x) - x)) / dt;
        omega += spun;
    }

    // ---- A.5: momentum suppression (solver.cpp suppress_momentum): each segment's turn
    // here, the segments carried down the chain by its first lane ----
    const float suppression = SUPPRESSION == KW_RODS_SUPPRESSION_FULL ? 1.0 : t.step.w;
    if (SUPPRESSION != KW_RODS_SUPPRESSION_NONE && suppression > 0.0) {
        const vec4 root = from.rotation;
        const vec4 root_inv = qconj(root);
        if (i + 1u < n) {
            const vec3 old_dir = normalize(s_g1[gl_LocalInvocationID.x + 1u] - s_g1[gl_LocalInvocationID.x]);
            const vec3 new_dir = normalize(s_g0[gl_LocalInvocationID.x + 1u] - s_g0[gl_LocalInvocationID.x]);
            s_q0[gl_LocalInvocationID.x] = partial_turn(qmul(qmul(root, shortest_arc(old_dir, new_dir)), root_inv), suppression);
        }
        s_x[gl_LocalInvocationID.x] = x;
        barrier();
        if (lane == 0u) {
            vec3 previous_old = s_x[base];
            for (uint k = 0; k + 1 < n; ++k) {
                const vec3 segment = s_x[base + k + 1] - previous_old;
                previous_old = s_x[base + k + 1];
                s_x[base + k + 1] = s_x[base + k] + qrot(s_q0[base + k], segment);
            }
        }
        barrier();
        x = s_x[gl_LocalInvocationID.x];
        if (i >= 1u) {
            const vec4 change = positive_w(qmul(rest_o, qconj(old_rest_o)));
            q = qnormalize(qmul(partial_turn(qmul(qmul(root, change), root_inv), suppression), q));
        }
    }

    // ---- A.4: the substeps (solver.cpp step) ----
    const uint substeps = t.solver.y;
    const uint iterations = t.solver.x;
    const float h = t.step.x;
    const float decay = t.step.y;
    const float k_iter = t.step.z;
    const float k_rest = t.physics.y;
    const vec2 drag_decay = t.drag.xy;
    const float thickness = t.physics.x;
    const float b2 = thickness * thickness;
    const vec3 acceleration = t.accel.xyz;
    const bool AIR = (FEATURES & KW_RODS_FEATURE_AIR) != 0u;
    vec3 air = vec3(0.0);
    if (AIR && (push.flags.x & KW_RODS_STEP_WIND) != 0u) {
        const RodWindGpu wf = winds[chain.joints.w];
        air = wind_air_velocity(wf.velocity.xyz, wf.velocity.w, wf.scales.x, wf.scales.y, wf.seed.x, to.position.xyz, push.time.x);
    }
    const bool drag = AIR && t.drag.z != 0.0;
    const vec3 travel = to.position.xyz - from.position.xyz;
    // The colliders in the end root's frame (only the first lane collides, but every lane
    // loads them: the same addresses, one transaction).
    const uint cbegin = chain.ids.z;
    col_count = min(chain.ids.w, MAX_COLLIDERS);
    colliders_in_root_frame(cbegin, to, thickness);
    const bool COLLIDES = MAX_COLLIDERS > 0u && col_count > 0u;
    const uint me = gl_LocalInvocationID.x;
    // The group of joint i (shape matching over G_i = {i-1, i, i+1}, clipped at the ends;
    // group 0 is {0, 1}).
    const uint lo = i == 0u ? 0u : i - 1u;
    const bool has_next = i + 1u < n && i != 0u;
    const uint hi = i == 0u ? 1u : i + 1u;
    for (uint sub = 1; sub <= substeps; ++sub) {
        const float f = float(sub) / float(substeps);
        const vec3 r_pos = f * travel;
        const vec4 r_rot = interpolate(from.rotation, to.rotation, f);
        const vec3 xbar = r_pos + qrot(r_rot, rest_p);
        const vec4 obar = qnormalize(qmul(r_rot, rest_o));
        const vec3 obar_axis = qrot(obar, axis);
        place_colliders(r_pos, r_rot);
        s_x[me] = x;  // the segments' directions for drag
        s_xbar[me] = xbar;
        s_pulled[me] = vec3(0.0);
        s_pushed[me] = vec3(0.0);
        barrier();
        vec3 p = xbar;
        vec4 qs = obar;
        if (i >= 1u) {
            if (AIR) {
                // Damping and drag relative to the air, then gravity (solver.cpp).
                vec3 relative = decay * (v - air);
                if (drag) {
                    const vec3 segment = x - s_x[me - 1u];
                    const float len = length(segment);
                    if (len > 1e-9) {
                        const vec3 seg_axis = segment / len;
                        const vec3 along = dot(relative, seg_axis) * seg_axis;
                        relative = drag_decay.x * (relative - along) + drag_decay.y * along;
                    }
                }
                v = air + relative + h * acceleration;
            } else {
                v = decay * v + h * acceleration;  // damping, then gravity (solver.cpp)
            }
            omega = decay * omega;
            p = x + h * v;
            qs = qnormalize(q + qmul(vec4((0.5 * h) * omega, 0.0), q));
        }

        for (uint it = 0; it < iterations; ++it) {
            // The ellipsoid term A_i (solver.cpp) of every particle, and the positions, as
            // the iteration starts.
            {
                const float a2 = half_len * half_len;
                const mat3 relative = mat3_cast(qmul(qs, qconj(obar)));
                s_a[me] = (weight / 5.0) * (b2 * relative + (a2 - b2) * outerProduct(qrot(qs, axis), obar_axis));
            }
            s_p[me] = p;
            barrier();
            // Shape matching over G_i, every group at once (rods_step.comp's sweep: each
            // group reads its members before any of them settles).
            vec4 q_new = qs;
            if (live) {
                // (hi is n for the last joint, whose group has no next member: its loads are
                // clamped to stay inside the chain's slots, and never used)
                const uint hi_in = min(hi, n - 1u);
                const float w_lo = s_weight[base + lo], w_hi = s_weight[base + hi_in];
                const vec3 p_lo = s_p[base + lo], p_hi = s_p[base + hi_in];
                const vec3 xbar_lo = s_xbar[base + lo], xbar_hi = s_xbar[base + hi_in];
                float group_mass = w_lo;
                vec3 cm = w_lo * p_lo;
                vec3 cbar = w_lo * xbar_lo;
                if (i != 0u) {
                    group_mass += weight;
                    cm += weight * p;
                    cbar += weight * xbar;
                }
                if (i == 0u || has_next) {
                    group_mass += w_hi;
                    cm += w_hi * p_hi;
                    cbar += w_hi * xbar_hi;
                }
                cm /= group_mass;
                cbar /= group_mass;
                mat3 a = mat3(0.0);
                a += w_lo * outerProduct(p_lo - cm, xbar_lo - cbar);
                a += s_a[base + lo];
                if (i != 0u) {
                    a += weight * outerProduct(p - cm, xbar - cbar);
                    a += s_a[me];
                }
                if (i == 0u || has_next) {
                    a += w_hi * outerProduct(p_hi - cm, xbar_hi - cbar);
                    a += s_a[base + hi];
                }
                // Warm start from the centre's orientation (solver.cpp).
                const vec4 rot = extract_rotation(a, qmul(qs, qconj(obar)));
                s_g0[me] = cm + qrot(rot, xbar_lo - cbar);
                if (i != 0u) s_g1[me] = cm + qrot(rot, xbar - cbar);
                if (i == 0u || has_next) s_g2[me] = cm + qrot(rot, xbar_hi - cbar);
                q_new = qnormalize(qmul(rot, obar));
            }
            barrier();
            // Particle i (>= 1) toward the mean of its goals (from groups i-1, i, i+1, added
            // in that order, as the sweep adds them), then rest-pose attraction (Han &
            // Harada 2012, global shape constraint).
            if (live && i >= 1u) {
                vec3 goal_sum = vec3(0.0);
                goal_sum += s_g2[me - 1u];
                goal_sum += s_g1[me];
                const bool last_joint = i + 1u == n;
                if (!last_joint) goal_sum += s_g0[me + 1u];
                p += k_iter * (goal_sum / (last_joint ? 2.0 : 3.0) - p);
                qs = q_new;
                p += k_rest * (xbar - p);
                s_p[me] = p;
            }
            barrier();
            // Then the distance constraint to its (already final) parent, follow-the-leader,
            // and the colliders, down the chain.
            if (lane == 0u && in_range) {
                for (uint j = 1; j < n; ++j) {
                    place(base, j);
                    if (COLLIDES) collide(base, j);
                }
            }
            barrier();
            p = s_p[me];
        }
        // The last sweep: placed and pushed out, twice (solver.cpp).
        if (lane == 0u && in_range) {
            for (uint j = 1; j < n; ++j) {
                place(base, j);
                if (COLLIDES) {
                    collide(base, j);
                    place(base, j);
                    collide(base, j);
                    place(base, j);
                    collide(base, j);
                }
            }
        }
        barrier();
        p = s_p[me];
        // What the colliders undid is not the parent's to give back (solver.cpp).
        vec3 pulled = s_pulled[me];
        if (COLLIDES) {
            const vec3 pushed = s_pushed[me];
            const float pl = length(pushed);
            if (i >= 1u && i < n && pl > 0.0) {
                const vec3 nn = pushed / pl;
                const float along = dot(pulled, nn);
                if (along < 0.0) pulled -= max(along, -pl) * nn;
            }
        }
        barrier();  // (everyone has read s_pulled)
        s_pulled[me] = pulled;
        barrier();
        v = (p - x) / h;
        // Dynamic follow-the-leader (solver.cpp; Mueller et al. 2012, eq. 9).
        if (i > 0u && i + 1u < n) v -= (KW_RODS_FTL_DAMPING / h) * s_pulled[me + 1u];
        const vec4 dq = positive_w(qmul(qs, qconj(q)));
        omega = (2.0 / h) * dq.xyz;
        x = p;
        q = qs;
        barrier();  // (s_x, s_pulled and s_pushed are rewritten by the next substep)
    }

    // ---- store ----
    // Every lane read the chain's state (chain_states[c]) before lane 0 overwrites it: the
    // barriers above order shared memory only, so this one orders the storage buffer too.
    memoryBarrierBuffer();
    barrier();
    if (!live) return;
    // xyz only: w holds the sag (RodJointMotionGpu).
    motion[j0 + i].x.xyz = x - travel;
    motion[j0 + i].v.xyz = v;
    spin[j0 + i].q = q;
    spin[j0 + i].omega.xyz = omega;
    if (i == 0u) {
        chain_states[c] = RodChainStateGpu(RodTransformGpu(vec4(to.position.xyz, 1.0), to.rotation), vec4(d, float(KW_RODS_LEVEL_FULL)),
                                           vec4[2](vec4(w[0], w[1], w[2], w[3]), vec4(w[4], w[5], w[6], w[7])));
    }
}
