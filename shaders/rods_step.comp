#version 450
// One frame of the view-dependent rods (SPEC part A) for every chain: one invocation per
// chain computes the view direction and weights (A.3), combines them with its keyed
// examples' raw weights (docs/keyed-examples.md K.4; rod_keys.comp measured them just
// before), blends the rest shape (A.2),
// applies momentum suppression (A.5) and runs every substep and projection iteration of
// the oriented-particles solver (A.4) in registers. Mirrors engine/rods/world.cpp,
// shape.cpp and solver.cpp step for step; the equations' sources are cited there.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

#include "shared/rods.h"
#include "lib/quat.glsl"
#include "lib/wind.glsl"
#include "lib/spring_limit.glsl"
#include "lib/rod_lod.glsl"

// The size is a specialization constant (default KW_RODS_WORKGROUP_SIZE, see birds_flap.comp).
layout(local_size_x = KW_RODS_WORKGROUP_SIZE, local_size_x_id = KW_RODS_SPEC_WORKGROUP_SIZE) in;

// Sizes the per-chain register arrays: the longest chain of the dispatch, not
// KW_RODS_MAX_JOINTS, so short chains do not pay for 32-joint arrays. Every loop over
// joints (and view examples) is unrolled to this bound with `if (i < n)` guards, so every
// array index is a constant and the arrays live in registers: with a loop index, lavapipe
// keeps them in scratch memory and accesses it lane by lane (several times slower).
layout(constant_id = KW_RODS_SPEC_MAX_JOINTS) const uint MAX_J = 16;
// The most view examples of any chain of the dispatch, and how the world's chains
// suppress momentum (KW_RODS_SUPPRESSION_*): lavapipe executes both sides of every
// branch, even uniform ones, so only a constant removes the blending of unused examples
// or A.5's turns.
layout(constant_id = KW_RODS_SPEC_MAX_VIEWS) const uint MAX_VIEWS = KW_RODS_MAX_VIEWS;
layout(constant_id = KW_RODS_SPEC_SUPPRESSION) const uint SUPPRESSION = KW_RODS_SUPPRESSION_PARTIAL;
// One dispatch per template (KW_RODS_SPEC_GROUPED) reads the template's constants at indices
// that come from push constants only: lavapipe turns such a load into one scalar load for
// all lanes, but only outside every branch, so they are loaded before the guard below.
// Otherwise (worlds of many templates) each chain finds its template itself.
layout(constant_id = KW_RODS_SPEC_GROUPED) const bool GROUPED = true;
// Chains of exactly MAX_J joints, MAX_VIEWS views and MAX_KEYED keyed examples: the counts
// become constants and the `if (i < n)` masks of every unrolled loop fold away (lavapipe
// evaluates them per lane).
layout(constant_id = KW_RODS_SPEC_EXACT) const bool EXACT = false;
// The most keyed examples of any chain of the dispatch (K.4). 0, the default and every
// world without keyed examples: their load, the combination and their shapes' blending
// are compiled out, so such worlds run the kernel they ran before keyed examples existed.
layout(constant_id = KW_RODS_SPEC_MAX_KEYED) const uint MAX_KEYED = 0;
// The world's KW_RODS_FEATURE_*: centers and inside and plane colliders are compiled out
// of worlds that have none (lavapipe would run their code masked for every chain).
layout(constant_id = KW_RODS_SPEC_FEATURES) const uint FEATURES = KW_RODS_FEATURE_ALL;
// The most colliders of any chain of the world (at most KW_RODS_MAX_CHAIN_COLLIDERS): the
// collider loops are unrolled to it with `if (k < col_count)` guards, so the collider
// arrays are indexed by constants and live in registers. With a loop bound known only at
// run time they lived in scratch memory, read lane by lane on lavapipe, in the collisions
// every joint makes every iteration: `bench chains` (one head collider a chain) ran 3.7
// times slower. 0 compiles collisions out.
layout(constant_id = KW_RODS_SPEC_MAX_COLLIDERS) const uint MAX_COLLIDERS = KW_RODS_MAX_CHAIN_COLLIDERS;
// The examples the blend sums past the base: views, then keyed ones (shapes 1 .. m + J).
// A chain has at most KW_RODS_MAX_VIEWS in all (rods::add_keyed_examples), which caps the
// sum of two dispatch-wide maxima that may come from different templates.
const uint MAX_EXAMPLES = MAX_VIEWS + MAX_KEYED > KW_RODS_MAX_VIEWS ? KW_RODS_MAX_VIEWS : MAX_VIEWS + MAX_KEYED;

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
layout(std430, binding = KW_RODS_BINDING_KEYED) readonly buffer Keyed { vec4 keyed[]; };
layout(std430, binding = KW_RODS_BINDING_CENTERS) readonly buffer Centers { RodTransformGpu centers[]; };
layout(std430, binding = KW_RODS_BINDING_CENTER_STATE) buffer CenterStates { RodTransformGpu center_states[]; };
layout(std430, binding = KW_RODS_BINDING_WINDS) readonly buffer Winds { RodWindGpu winds[]; };

layout(push_constant) uniform Push { RodPush push; };

#include "lib/rod_solver.glsl"

// A template's constants, each loaded once: template joint i of tj + i, and its shapes
// (shape0 + k * n + i, examples pre-signed into the base's hemisphere at upload, SPEC A.2).
// Indices are clamped instead of guarded so that no load sits in a branch (see GROUPED);
// entries past n and m (the examples: views and keyed) are never read by the solver.
struct Constants {
    float mass[MAX_J], weight[MAX_J], seg_len[MAX_J], half_len[MAX_J];
    vec3 axis[MAX_J];
    vec4 rotation[MAX_EXAMPLES + 1][MAX_J], orientation[MAX_EXAMPLES + 1][MAX_J];
    // Angle limits (KW_RODS_FEATURE_LIMITS only): segment i's kind, trig and frame.
    uint limit_kind[MAX_J];
    vec4 limit_trig[MAX_J], limit_frame[MAX_J];
};
void load_constants(uint n, uint examples, uint tj, uint shape0, out Constants tc) {
    [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
        const uint ic = min(i, n - 1);
        const RodTemplateJointGpu tjoint = tjoints[tj + ic];
        tc.axis[i] = tjoint.axis_mass.xyz;
        tc.mass[i] = tjoint.axis_mass.w;
        tc.weight[i] = i == 0 ? ROOT_SHAPE_WEIGHT * tc.mass[i] : tc.mass[i];
        tc.seg_len[i] = tjoint.lengths.x;
        tc.half_len[i] = tjoint.lengths.y;
        if ((FEATURES & KW_RODS_FEATURE_LIMITS) != 0u) {
            tc.limit_kind[i] = uint(tjoint.lengths.z);
            tc.limit_trig[i] = tjoint.limit_trig;
            tc.limit_frame[i] = tjoint.limit_frame;
        }
        [[unroll]] for (uint v = 0; v <= MAX_EXAMPLES; ++v) {
            const RodShapeJointGpu s = shapes[shape0 + min(v, examples) * n + ic];
            tc.rotation[v][i] = s.rotation;
            tc.orientation[v][i] = s.orientation;
        }
    }
}

// Steps of one projection iteration (solver.cpp), as macros so that every array index
// stays a constant of the unrolled loop.
// The ellipsoid term A_j of particle j.
#define KW_ELLIPSOID(j)                                                                                       \
    {                                                                                                         \
        const float a2 = tc.half_len[j] * tc.half_len[j];                                                     \
        const mat3 relative = mat3_cast(qmul(qs[j], qconj(obar[j])));                                         \
        a_j[j] = (tc.weight[j] / 5.0) *                                                                       \
                 (b2 * relative + (a2 - b2) * outerProduct(qrot(qs[j], tc.axis[j]), obar_axis[j]));           \
        goal_sum[j] = vec3(0.0);                                                                              \
    }
// Particle j (>= 1) placed on its parent's segment length, follow-the-leader, its
// correction kept for DFTL (solver.cpp).
#define KW_PLACE(j)                                                                                           \
    {                                                                                                         \
        const vec3 dd = p[j] - p[(j) - 1];                                                                    \
        const float len = length(dd);                                                                         \
        if (len > 1e-9) {                                                                                     \
            const vec3 placed = p[(j) - 1] + (tc.seg_len[(j) - 1] / len) * dd;                                \
            pulled[j] += placed - p[j];                                                                       \
            p[j] = placed;                                                                                    \
        }                                                                                                     \
    }
// Particle j (>= 1) pushed out of the colliders, the push kept (solver.cpp).
#define KW_COLLIDE(j)                                                                                         \
    {                                                                                                         \
        const vec3 before = p[j];                                                                             \
        collide_all(p[j]);                                                                                    \
        pushed[j] += p[j] - before;                                                                           \
    }
// Particle j + 1 turned about particle j, at the same distance, to the nearest direction
// segment j's angle limit allows, then the parent bones' swing carried past it
// (solver.cpp limit_child; the limit itself is shaders/lib/spring_limit.glsl).
#define KW_LIMIT(j)                                                                                           \
    {                                                                                                         \
        const vec3 dd = p[(j) + 1] - p[j];                                                                    \
        const float len = length(dd);                                                                         \
        if (len > 1e-9) {                                                                                     \
            vec3 dir = dd / len;                                                                              \
            const uint kind = tc.limit_kind[j];                                                               \
            if (kind != KW_RODS_LIMIT_NONE) {                                                                 \
                const vec4 frame = qmul(qmul(swing, obar[j]), tc.limit_frame[j]);                             \
                const vec3 local = qrot(qconj(frame), dir);                                                   \
                const vec3 allowed = limit_direction(kind, tc.limit_trig[j], local);                          \
                if (any(notEqual(allowed, local))) {                                                          \
                    dir = qrot(frame, allowed);                                                               \
                    p[(j) + 1] = p[j] + len * dir;                                                            \
                }                                                                                             \
            }                                                                                                 \
            swing = qnormalize(qmul(shortest_arc(qrot(swing, obar_axis[j]), dir), swing));                    \
        }                                                                                                     \
    }
// Particle j (>= 1) after its last group: toward the mean of its goals, then rest-pose
// attraction (Han & Harada 2012, global shape constraint), then the distance constraint to
// its (already final) parent, follow-the-leader, its correction kept for DFTL, then the
// colliders (solver.cpp).
#define KW_SETTLE(j, groups)                                                                                  \
    {                                                                                                         \
        p[j] += k_iter * (goal_sum[j] / (groups) - p[j]);                                                     \
        qs[j] = q_new[j];                                                                                     \
        p[j] += k_rest * (xbar[j] - p[j]);                                                                    \
        KW_PLACE(j);                                                                                          \
        if (MAX_COLLIDERS > 0u && col_count > 0u) KW_COLLIDE(j);                                                                \
        if (LIMITS) KW_LIMIT((j) - 1);                                                                        \
    }

#ifdef KW_RODS_SHARED_CONSTANTS
// Kernel rods_step_shared (BackendOptions::rod_kernel, issue 38 item 2): the template's
// constants loaded once per workgroup into shared memory and read there at each use,
// instead of held in every invocation's registers (some 600 floats at 16 joints and 3
// views), for a GPU run to time against the kernel that holds them. GROUPED dispatches
// only (one template per dispatch; the backend builds it for no other). The same values
// in the same operations.
shared Constants tc_shared;
#endif

void main() {
#ifdef KW_RODS_SHARED_CONSTANTS
#define tc tc_shared
#else
    Constants tc;
#endif
    RodTemplateGpu t;
    if (GROUPED) {
        t = templates[push.group.x];
#ifdef KW_RODS_SHARED_CONSTANTS
        if (gl_LocalInvocationIndex == 0u)
#endif
            load_constants(EXACT ? MAX_J : push.group.y, EXACT ? MAX_VIEWS + MAX_KEYED : push.group.z + push.group.w, push.counts.z,
                           push.counts.w, tc);
#ifdef KW_RODS_SHARED_CONSTANTS
        barrier();
#endif
    }
    const uint e = gl_GlobalInvocationID.x;
    if (e >= push.counts.x) return;

    const RodChainGpu chain = chains[push.counts.y + e];
    // The chain's index in the per-chain buffers (the chains are listed by template).
    const uint c = chain.joints.y;
    if (!GROUPED) t = templates[chain.ids.x];
    const uint n = EXACT ? MAX_J : t.counts.x;
    const uint m = EXACT ? MAX_VIEWS : t.counts.y;
    // Keyed examples J (K.4), 0 where compiled out.
    const uint nk = MAX_KEYED == 0 ? 0 : EXACT ? MAX_KEYED : t.solver.z;
    if (!GROUPED) load_constants(n, m + nk, t.counts.z, t.counts.w, tc);
    const uint j0 = chain.joints.x;

    // ---- A.3: view direction and weights (world.cpp rest_shape, view.cpp) ----
    const RodTransformGpu ref = reference[chain.ids.y];
    const vec3 d = view_direction(ref);
    // ---- the level of detail (shaders/lib/rod_lod.glsl, rods::chain_level), from the
    // character's reference joint and the level of the chain's last step ----
    const bool LOD = (FEATURES & KW_RODS_FEATURE_LOD) != 0u;
    uint level = KW_RODS_LEVEL_FULL;
    // The share of full simulation in the result (rods::blend_in; kept in the state's
    // root.position.w): 1 without levels of detail.
    float share = 1.0;
    // The frames the chain kept its state since its last step (rods::ChainState::idle).
    uint idle = 0u;
    if (LOD && (push.flags.x & KW_RODS_STEP_LOD) != 0u) {
        const RodChainStateGpu last = chain_states[c];
        const uint packed = uint(last.view.w);  // level + KW_RODS_IDLE_UNIT x idle
        const uint previous = packed % KW_RODS_IDLE_UNIT;
        idle = packed / KW_RODS_IDLE_UNIT;
        const vec3 offset = ref.position.xyz - push.camera_position.xyz;
        const float depth = dot(offset, push.camera_forward.xyz);
        const float right = dot(offset, push.camera_right.xyz);
        const float up = dot(offset, push.camera_up.xyz);
        const float reduced_distance = uintBitsToFloat(push.flags.y);
        level = rod_level(depth, right, up, push.camera_right.w, push.camera_up.w, push.time.y, push.time.z, push.time.w,
                          reduced_distance, uintBitsToFloat(push.flags.z), previous);
        // The posed and hidden levels' rate (rods::chain_rests): between its turns the chain
        // keeps its state (a chain with a center frame steps every frame, as on the CPU).
        const uint rate = push.flags.w;
        if ((rate & KW_RODS_RATE_ON) != 0u && chain.joints.z == KW_RODS_NO_CENTER) {
            const bool far_off = level == KW_RODS_LEVEL_HIDDEN &&
                                 rod_far_off_view(depth, right, up, push.camera_right.w, push.camera_up.w, push.time.y);
            if (rod_rests(level, previous, depth, reduced_distance, far_off, rod_rate_turn(rate, chain.ids.y))) {
                chain_states[c].view.w = float(previous + KW_RODS_IDLE_UNIT * (idle + 1u));
                return;
            }
        }
        share = level == KW_RODS_LEVEL_FULL || level == KW_RODS_LEVEL_REDUCED ? min(1.0, last.root.position.w + t.drag.w) : 0.0;
    }
    // A posed step covers the frames the chain kept (solver_posed.cpp step_posed with dt x (idle + 1)).
    const float steps = float(idle + 1u);
    // Full and reduced chains run the dynamics; posed and hidden ones step_posed.
    const bool DYNAMIC = level == KW_RODS_LEVEL_FULL || level == KW_RODS_LEVEL_REDUCED;
    const bool HANDING = LOD && DYNAMIC && share < 1.0;
    float w[KW_RODS_MAX_VIEWS + 1];
    view_weights(t, m, d, w);
    if (MAX_KEYED > 0) {
        // K.4 (keyed.cpp combine_weights): the keyed examples take their share U of the view
        // weights, W_k = (1 - U) w_k, W_{m+j} = u_j, normalized when U >= 1. Entries of u
        // past J are 0 (rod_keys.comp, or never written for a chain without keyed
        // examples), so summing all four adds exact zeros to the CPU's sum of J.
        const vec4 u = keyed[c];
        const float sum = u.x + u.y + u.z + u.w;
        const bool whole = sum >= 1.0;
        const float rest = 1.0 - (whole ? 1.0 : sum);
        [[unroll]] for (uint k = 0; k <= MAX_EXAMPLES; ++k) {
            const uint j = k - m - 1;  // keyed example j + 1 has shape m + 1 + j
            const float uj = j == 0 ? u.x : j == 1 ? u.y : j == 2 ? u.z : u.w;
            if (k <= m) {
                w[k] = rest * w[k];
            } else if (k <= m + nk) {
                w[k] = whole ? uj / sum : uj;
            }
        }
    }

    // ---- A.2: blend, then forward kinematics (shape.cpp blend, to_positions), for this
    // frame's weights and, for A.5, last frame's (the same arithmetic gives back the
    // rest shape the last frame used, as the CPU keeps it) ----
    float w_old[KW_RODS_MAX_VIEWS + 1];
    {
        const RodChainStateGpu last = chain_states[c];
        w_old[0] = last.weights[0].x;
        w_old[1] = last.weights[0].y;
        w_old[2] = last.weights[0].z;
        w_old[3] = last.weights[0].w;
        w_old[4] = last.weights[1].x;
        w_old[5] = last.weights[1].y;
        w_old[6] = last.weights[1].z;
        w_old[7] = last.weights[1].w;
    }
    vec3 rest_p[MAX_J], old_rest_p[MAX_J];
    vec4 rest_o[MAX_J], old_rest_o[MAX_J];
    {
        vec3 dir = t.first_dir.xyz, old_dir = t.first_dir.xyz;
        rest_p[0] = vec3(0.0);
        old_rest_p[0] = vec3(0.0);
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
            if (i < n) {
                // Shape 0 is the base; the examples were flipped into its hemisphere at upload.
                vec4 r_sum = w[0] * tc.rotation[0][i], o_sum = w[0] * tc.orientation[0][i];
                vec4 r_old = w_old[0] * tc.rotation[0][i], o_old = w_old[0] * tc.orientation[0][i];
                [[unroll]] for (uint v = 1; v <= MAX_EXAMPLES; ++v) {
                    if (v <= m + nk) {
                        r_sum += w[v] * tc.rotation[v][i];
                        o_sum += w[v] * tc.orientation[v][i];
                        r_old += w_old[v] * tc.rotation[v][i];
                        o_old += w_old[v] * tc.orientation[v][i];
                    }
                }
                rest_o[i] = length(o_sum) > 1e-12 ? o_sum / length(o_sum) : tc.orientation[0][i];
                old_rest_o[i] = length(o_old) > 1e-12 ? o_old / length(o_old) : tc.orientation[0][i];
                if (i + 1 < MAX_J && i + 1 < n) {
                    const vec4 r = length(r_sum) > 1e-12 ? r_sum / length(r_sum) : tc.rotation[0][i];
                    const vec4 ro = length(r_old) > 1e-12 ? r_old / length(r_old) : tc.rotation[0][i];
                    dir = normalize(qrot(r, dir));
                    old_dir = normalize(qrot(ro, old_dir));
                    rest_p[i + 1] = rest_p[i] + tc.seg_len[i] * dir;
                    old_rest_p[i + 1] = old_rest_p[i] + tc.seg_len[i] * old_dir;
                }
            }
        }
    }

    // ---- load the state ----
    vec3 x[MAX_J], v[MAX_J], omega[MAX_J];
    vec4 q[MAX_J];
    [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
        if (i < n) {
            const RodJointMotionGpu mo = motion[j0 + i];
            const RodJointSpinGpu sp = spin[j0 + i];
            x[i] = mo.x.xyz;
            v[i] = mo.v.xyz;
            q[i] = sp.q;
            omega[i] = sp.omega.xyz;
        }
    }
    RodTransformGpu from = chain_states[c].root;
    const RodTransformGpu to = roots[c];

    // ---- the chain carried by its center frame's motion (solver_root_motion.cpp follow_center) ----
    const uint center = chain.joints.z;
    // ---- and by a teleport, the root's jump (solver_root_motion.cpp follow_teleport) ----
    // Three carries at most, by the same code: the center's motion; a root that jumped
    // farther than the teleport distance from where that left it, carried to the new root
    // and then back by one frame of joint 0's (the root's) own motion (frame_before).
    bool teleported = false;
    [[unroll]] for (uint pass = 0; pass < 3; ++pass) {
        RodTransformGpu was = from, now = to;
        if (pass == 0) {
            if ((FEATURES & KW_RODS_FEATURE_CENTERS) == 0u || center == KW_RODS_NO_CENTER) continue;
            was = center_states[center];
            now = centers[center];
            center_states[center] = now;
        } else if (pass == 1) {
            const vec3 jump = to.position.xyz - from.position.xyz;
            teleported = dot(jump, jump) > t.physics.z * t.physics.z;
            if (!teleported) continue;
        } else {
            if (!teleported) continue;
            // A posed step's carry is over the frames it covers (rods::follow_teleport in step_posed).
            const float dt = DYNAMIC ? push.camera_forward.w : push.camera_forward.w * steps;
            const vec3 turn = omega[0] * dt;
            const float angle = length(turn);
            const vec3 axis = angle > 0.0 ? turn / angle : vec3(0.0);
            const vec4 back = vec4(-sin(0.5 * angle) * axis, cos(0.5 * angle));
            was = to;
            now.position = vec4(to.position.xyz - v[0] * dt, 0.0);
            now.rotation = qnormalize(qmul(back, to.rotation));
        }
        const vec4 r = qnormalize(qmul(now.rotation, qconj(was.rotation)));
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
            if (i < n) {
                x[i] = qrot(r, x[i]);
                v[i] = qrot(r, v[i]);
                q[i] = qnormalize(qmul(r, q[i]));
                omega[i] = qrot(r, omega[i]);
            }
        }
        from.position = vec4(now.position.xyz + qrot(r, from.position.xyz - was.position.xyz), 0.0);
        from.rotation = qnormalize(qmul(r, from.rotation));
    }

    // ---- the first step starts moving with the root (solver_root_motion.cpp start_moving) ----
    if ((push.flags.x & KW_RODS_STEP_FIRST) != 0u && t.physics.w != 0.0) {
        const float dt = push.camera_forward.w;
        const vec4 turn = positive_w(qnormalize(qmul(to.rotation, qconj(from.rotation))));
        const vec3 travel = to.position.xyz - from.position.xyz;
        const vec3 spin = (2.0 / dt) * turn.xyz;
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
            if (i < n) {
                v[i] += (travel + (qrot(turn, x[i]) - x[i])) / dt;
                omega[i] += spin;
            }
        }
    }

    // ---- the posed level of detail (solver_posed.cpp step_posed): no dynamics, the chain carried
    // by its root and eased onto its rest shape ----
    vec3 posed_x[MAX_J], x_before[MAX_J];
    vec4 posed_q[MAX_J], q_before[MAX_J];
    if (LOD && (!DYNAMIC || HANDING)) {
        // rods::posed_blend over the frames covered: 1 - (1 - blend)^steps (the CPU takes
        // exp once of their length: the same to rounding); one frame's as given.
        float blend = t.accel.w;
        if (idle > 0u && !HANDING) {
            float kept = 1.0 - t.accel.w;
            const float one = kept;
            for (uint k = 0u; k < idle; ++k) kept *= one;
            blend = 1.0 - kept;
        }
        const float dt = HANDING ? push.camera_forward.w : push.camera_forward.w * steps;
        const vec3 moved = to.position.xyz - from.position.xyz;
        const vec4 turn_by = qnormalize(qmul(to.rotation, qconj(from.rotation)));
        // The colliders at their end-of-frame poses relative to the last root position.
        col_count = min(chain.ids.w, MAX_COLLIDERS);
        [[unroll]] for (uint k = 0; k < MAX_COLLIDERS; ++k) if (k < col_count) {
            const RodColliderGpu col = colliders[chain.ids.z + k];
            const uint kind = uint(col.b.w);
            col_kind[k] = kind;
            col_ca[k] = col.a.xyz - from.position.xyz;
            col_cb[k] = kind == KW_RODS_COLLIDER_PLANE ? col.b.xyz : col.b.xyz - from.position.xyz;
            col_reach[k] = kind == KW_RODS_COLLIDER_PLANE    ? t.physics.x
                           : kind == KW_RODS_COLLIDER_INSIDE ? max(col.a.w - t.physics.x, 0.0)
                                                             : col.a.w + t.physics.x;
        }
        vec3 parent = vec3(0.0);
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
            if (i < n) {
                const vec3 target = moved + qrot(to.rotation, rest_p[i]);
                vec4 goal = qnormalize(qmul(to.rotation, rest_o[i]));
                vec3 px = target;
                vec4 pq = goal;
                if (i > 0) {
                    const vec3 sag = vec3(motion[j0 + i].x.w, motion[j0 + i].v.w, spin[j0 + i].omega.w);
                    const vec3 sagged = moved + qrot(to.rotation, rest_p[i] + sag);
                    const vec3 carried = moved + qrot(turn_by, x[i]);
                    px = carried + blend * (sagged - carried);
                    // On its parent's segment length and out of the colliders (solver_posed.cpp step_posed).
                    {
                        const vec3 dd = px - parent;
                        const float len = length(dd);
                        if (len > 1e-9) px = parent + (tc.seg_len[i - 1] / len) * dd;
                    }
                    if (MAX_COLLIDERS > 0u && col_count > 0u) collide_all(px);
                    const vec4 held = qnormalize(qmul(turn_by, q[i]));
                    if (dot(held, goal) < 0.0) goal = -goal;
                    pq = qnormalize(held + blend * (goal - held));
                }
                parent = px;
                if (HANDING) {  // kept for hand_over() below
                    posed_x[i] = px;
                    posed_q[i] = pq;
                    x_before[i] = x[i];
                    q_before[i] = q[i];
                } else {
                    const vec4 dq = positive_w(qmul(pq, qconj(q[i])));
                    motion[j0 + i].x.xyz = px - moved;
                    motion[j0 + i].v.xyz = (px - x[i]) / dt;
                    spin[j0 + i].q = pq;
                    spin[j0 + i].omega.xyz = (2.0 / dt) * dq.xyz;
                }
            }
        }
        if (!HANDING) {
            chain_states[c] = RodChainStateGpu(RodTransformGpu(vec4(to.position.xyz, share), to.rotation), vec4(d, float(level)),
                                               vec4[2](vec4(w[0], w[1], w[2], w[3]), vec4(w[4], w[5], w[6], w[7])));
            return;
        }
    }

    // ---- A.5: momentum suppression (solver.cpp suppress_momentum) ----
    const float suppression = SUPPRESSION == KW_RODS_SUPPRESSION_FULL ? 1.0 : t.step.w;
    if (SUPPRESSION != KW_RODS_SUPPRESSION_NONE && suppression > 0.0) {
        const vec4 root = from.rotation;
        const vec4 root_inv = qconj(root);
        vec3 previous_old = x[0];
        [[unroll]] for (uint i = 0; i + 1 < MAX_J; ++i) {
            if (i + 1 < n) {
                const vec3 old_dir = normalize(old_rest_p[i + 1] - old_rest_p[i]);
                const vec3 new_dir = normalize(rest_p[i + 1] - rest_p[i]);
                const vec4 turn = partial_turn(qmul(qmul(root, shortest_arc(old_dir, new_dir)), root_inv), suppression);
                const vec3 segment = x[i + 1] - previous_old;
                previous_old = x[i + 1];
                x[i + 1] = x[i] + qrot(turn, segment);
            }
        }
        [[unroll]] for (uint i = 1; i < MAX_J; ++i) {
            if (i < n) {
                const vec4 change = positive_w(qmul(rest_o[i], qconj(old_rest_o[i])));
                q[i] = qnormalize(qmul(partial_turn(qmul(qmul(root, change), root_inv), suppression), q[i]));
            }
        }
    }

    // ---- A.4: the substeps (solver.cpp step), a reduced chain's with rods::reduced_params' ----
    const bool REDUCED = LOD && level == KW_RODS_LEVEL_REDUCED;
    const uint substeps = REDUCED ? uint(t.reduced_solver.w) : t.solver.y;
    const uint iterations = REDUCED ? uint(t.reduced_solver.z) : t.solver.x;
    const float h = REDUCED ? t.reduced_step.x : t.step.x;
    const float decay = REDUCED ? t.reduced_step.y : t.step.y;
    const float k_iter = REDUCED ? t.reduced_step.z : t.step.z;
    const float k_rest = REDUCED ? t.reduced_step.w : t.physics.y;
    const vec2 drag_decay = REDUCED ? t.reduced_solver.xy : t.drag.xy;
    const float thickness = t.physics.x;
    const float b2 = thickness * thickness;
    const vec3 acceleration = t.accel.xyz;
    // The air around the chain this frame (rods::chain_air: its field at its end root),
    // and the drag across and along its segments (solver.cpp step).
    const bool AIR = (FEATURES & KW_RODS_FEATURE_AIR) != 0u;
    vec3 air = vec3(0.0);
    if (AIR && (push.flags.x & KW_RODS_STEP_WIND) != 0u) {
        const RodWindGpu w = winds[chain.joints.w];
        air = wind_air_velocity(w.velocity.xyz, w.velocity.w, w.scales.x, w.scales.y, w.seed.x, to.position.xyz, push.time.x);
    }
    const bool drag = AIR && t.drag.z != 0.0;
    // Angle limits: the parent bones' swing from their rest, carried down each sweep (solver.cpp).
    const bool LIMITS = (FEATURES & KW_RODS_FEATURE_LIMITS) != 0u && t.solver.w != 0u;
    vec4 swing = vec4(0.0, 0.0, 0.0, 1.0);
    const uint cbegin = chain.ids.z;
    const uint cend = chain.ids.z + chain.ids.w;
    // Solved relative to the previous root position, as the state is (solver.cpp).
    const vec3 travel = to.position.xyz - from.position.xyz;

    // The colliders in the end root's frame (solver.cpp step).
    col_count = min(cend - cbegin, MAX_COLLIDERS);  // (the host sets MAX_COLLIDERS to the world's most)
    colliders_in_root_frame(cbegin, to, thickness);

    vec3 p[MAX_J], xbar[MAX_J], goal_sum[MAX_J], obar_axis[MAX_J], pulled[MAX_J], pushed[MAX_J];
    vec4 qs[MAX_J], obar[MAX_J], q_new[MAX_J];
    mat3 a_j[MAX_J];
    for (uint sub = 1; sub <= substeps; ++sub) {
        const float f = float(sub) / float(substeps);
        const vec3 r_pos = f * travel;
        const vec4 r_rot = interpolate(from.rotation, to.rotation, f);

        [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
            if (i < n) {
                xbar[i] = r_pos + qrot(r_rot, rest_p[i]);
                obar[i] = qnormalize(qmul(r_rot, rest_o[i]));
                obar_axis[i] = qrot(obar[i], tc.axis[i]);
            }
        }
        p[0] = xbar[0];
        qs[0] = obar[0];
        // The colliders placed by the substep's root.
        place_colliders(r_pos, r_rot);
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) pulled[i] = vec3(0.0);
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) pushed[i] = vec3(0.0);

        [[unroll]] for (uint i = 1; i < MAX_J; ++i) {
            if (i < n) {
                if (AIR) {
                    // Damping and drag relative to the air, then gravity (solver.cpp).
                    vec3 relative = decay * (v[i] - air);
                    if (drag) {
                        const vec3 segment = x[i] - x[i - 1];
                        const float len = length(segment);
                        if (len > 1e-9) {
                            const vec3 axis = segment / len;
                            const vec3 along = dot(relative, axis) * axis;
                            relative = drag_decay.x * (relative - along) + drag_decay.y * along;
                        }
                    }
                    v[i] = air + relative + h * acceleration;
                } else {
                    v[i] = decay * v[i] + h * acceleration;  // damping, then gravity (solver.cpp)
                }
                omega[i] = decay * omega[i];
                p[i] = x[i] + h * v[i];
                // First-order orientation update (solver.cpp).
                qs[i] = qnormalize(q[i] + qmul(vec4((0.5 * h) * omega[i], 0.0), q[i]));
            }
        }

        for (uint it = 0; it < iterations; ++it) {
            swing = vec4(0.0, 0.0, 0.0, 1.0);
            // One pass over the groups that also finishes each joint as soon as its last
            // group is done: A_j right before its first group, a joint's goal average,
            // rest-pose attraction and distance constraint right after its last. The same
            // operations on the same values as the phase-by-phase order of solver.cpp (so the
            // same bits), with far fewer values alive at once (lavapipe spills the rest).
            [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
                if (i < n) {
                    // The ellipsoid terms A_j (solver.cpp), once per particle per iteration.
                    if (i == 0) {
                        KW_ELLIPSOID(0);
                        KW_ELLIPSOID(1);
                    } else if (i + 1 < MAX_J && i + 1 < n) {
                        KW_ELLIPSOID(i + 1);
                    }
                    // Shape matching over G_i = {i-1, i, i+1}, clipped at the ends.
                    const uint lo = i == 0 ? 0 : i - 1;
                    const bool has_next = i + 1 < MAX_J && i + 1 < n && i != 0;
                    // Group 0 is {0, 1}: its "previous" member is joint 0 itself.
                    const uint hi = i == 0 ? 1 : i + 1;
                    float group_mass = tc.weight[lo];
                    vec3 cm = tc.weight[lo] * p[lo];
                    vec3 cbar = tc.weight[lo] * xbar[lo];
                    if (i != 0) {
                        group_mass += tc.weight[i];
                        cm += tc.weight[i] * p[i];
                        cbar += tc.weight[i] * xbar[i];
                    }
                    if (i == 0 || has_next) {
                        group_mass += tc.weight[hi];
                        cm += tc.weight[hi] * p[hi];
                        cbar += tc.weight[hi] * xbar[hi];
                    }
                    cm /= group_mass;
                    cbar /= group_mass;
                    mat3 a = mat3(0.0);
                    a += tc.weight[lo] * outerProduct(p[lo] - cm, xbar[lo] - cbar);
                    a += a_j[lo];
                    if (i != 0) {
                        a += tc.weight[i] * outerProduct(p[i] - cm, xbar[i] - cbar);
                        a += a_j[i];
                    }
                    if (i == 0 || has_next) {
                        a += tc.weight[hi] * outerProduct(p[hi] - cm, xbar[hi] - cbar);
                        a += a_j[hi];
                    }
                    // Warm start from the centre's orientation (solver.cpp).
                    const vec4 rot = extract_rotation(a, qmul(qs[i], qconj(obar[i])));
                    goal_sum[lo] += cm + qrot(rot, xbar[lo] - cbar);
                    if (i != 0) goal_sum[i] += cm + qrot(rot, xbar[i] - cbar);
                    if (i == 0 || has_next) goal_sum[hi] += cm + qrot(rot, xbar[hi] - cbar);
                    q_new[i] = qnormalize(qmul(rot, obar[i]));
                    // Joint i-1's last group was this one (2 groups hold either end, 3 the others).
                    if (i >= 2) KW_SETTLE(i - 1, 3.0);
                    if (i >= 1 && i + 1 == n) KW_SETTLE(i, 2.0);
                }
            }

        }
        // The last sweep: placed and pushed out, twice, then limited (solver.cpp).
        swing = vec4(0.0, 0.0, 0.0, 1.0);
        [[unroll]] for (uint i = 1; i < MAX_J; ++i) {
            if (i < n) {
                KW_PLACE(i);
                if (MAX_COLLIDERS > 0u && col_count > 0u) {
                    KW_COLLIDE(i);
                    KW_PLACE(i);
                    KW_COLLIDE(i);
                    KW_PLACE(i);
                    KW_COLLIDE(i);
                }
                if (LIMITS) KW_LIMIT(i - 1);
            }
        }

        // What the colliders undid is not the parent's to give back (solver.cpp).
        if (MAX_COLLIDERS > 0u && col_count > 0u) {
            [[unroll]] for (uint i = 1; i < MAX_J; ++i) {
                const float pl = length(pushed[i]);
                if (i < n && pl > 0.0) {
                    const vec3 nn = pushed[i] / pl;
                    const float along = dot(pulled[i], nn);
                    if (along < 0.0) pulled[i] -= max(along, -pl) * nn;
                }
            }
        }
        [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
            if (i < n) {
                v[i] = (p[i] - x[i]) / h;
                // Dynamic follow-the-leader (solver.cpp; Mueller et al. 2012, eq. 9).
                if (i > 0 && i + 1 < MAX_J && i + 1 < n) v[i] -= (KW_RODS_FTL_DAMPING / h) * pulled[i + 1];
                const vec4 dq = positive_w(qmul(qs[i], qconj(q[i])));
                omega[i] = (2.0 / h) * dq.xyz;
                x[i] = p[i];
                q[i] = qs[i];
            }
        }
    }

    // ---- store ----
    [[unroll]] for (uint i = 0; i < MAX_J; ++i) {
        if (i < n) {
            vec3 stored = x[i] - travel;
            if (HANDING) {
                // Turning full again (solver_posed.cpp hand_over): the step's result mixed with the posed one.
                const float dt = push.camera_forward.w;
                const vec3 a = posed_x[i] - travel;
                const vec3 mixed = a + share * (stored - a);
                vec4 full = q[i];
                if (dot(posed_q[i], full) < 0.0) full = -full;
                q[i] = qnormalize(posed_q[i] + share * (full - posed_q[i]));
                v[i] = (mixed - (x_before[i] - travel)) / dt;
                const vec4 dq = positive_w(qmul(q[i], qconj(q_before[i])));
                omega[i] = (2.0 / dt) * dq.xyz;
                stored = mixed;
            }
            // xyz only: w holds the sag (RodJointMotionGpu).
            motion[j0 + i].x.xyz = stored;
            motion[j0 + i].v.xyz = v[i];
            spin[j0 + i].q = q[i];
            spin[j0 + i].omega.xyz = omega[i];
        }
    }
    chain_states[c] = RodChainStateGpu(RodTransformGpu(vec4(to.position.xyz, share), to.rotation), vec4(d, float(level)), vec4[2](vec4(w[0], w[1], w[2], w[3]), vec4(w[4], w[5], w[6], w[7])));
}
