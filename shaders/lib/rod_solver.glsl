// The oriented-particles solver's helpers that both rod kernels compile (rods_step.comp: a
// chain per invocation; rods_lanes.comp: a chain per group of lanes, a joint per lane), so
// that the two run the same operations on the same values. Each mirrors engine/rods/solver.cpp;
// the equations' sources are cited there. Before including, a kernel declares FEATURES
// (KW_RODS_SPEC_FEATURES), MAX_VIEWS (KW_RODS_SPEC_MAX_VIEWS), MAX_COLLIDERS
// (KW_RODS_SPEC_MAX_COLLIDERS), the colliders buffer and the push constants `push`.
#ifndef KODAWARI_SHADERS_LIB_ROD_SOLVER_GLSL
#define KODAWARI_SHADERS_LIB_ROD_SOLVER_GLSL

const uint COLLIDER_SLOTS = MAX_COLLIDERS > 0u ? MAX_COLLIDERS : 1u;  // (an array has one element at least)
// Up to KW_RODS_UNROLLED_COLLIDERS colliders a chain the collisions of every joint are
// unrolled as above; past it they stay a loop. The unrolled code is joints x passes x
// colliders copies of a collision, at every place a joint collides: for the VRM avatars
// (16 colliders a chain) lavapipe took about 2 minutes to compile that pipeline (the
// scene itself runs 3 frames in a second). The same operations in the same order either
// way: the same bits.
const bool UNROLL_COLLIDERS = MAX_COLLIDERS <= KW_RODS_UNROLLED_COLLIDERS;

const vec4 IDENTITY = vec4(0.0, 0.0, 0.0, 1.0);
const float ROOT_SHAPE_WEIGHT = 10.0;  // solver.cpp kRootShapeWeight
const int EXTRACT_ITERATIONS = 1;      // solver.cpp kExtractIterations

// ---- quaternions (lib/quat.glsl holds the ones shared with other kernels) --------------

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
// solver.cpp extract_rotation(): Mueller et al. 2016, Algorithm 1, warm-started, with
// the first-order turn.
vec4 extract_rotation(mat3 a, vec4 q) {
    [[unroll]] for (int iter = 0; iter < EXTRACT_ITERATIONS; ++iter) {
        const mat3 r = mat3_cast(q);
        const vec3 torque = cross(r[0], a[0]) + cross(r[1], a[1]) + cross(r[2], a[2]);
        const float alignment = abs(dot(r[0], a[0]) + dot(r[1], a[1]) + dot(r[2], a[2]));
        const vec3 half_omega = torque * (0.5 / (alignment + 1e-9));
        q = qnormalize(q + qmul(vec4(half_omega, 0.0), q));
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
void pull_in(inout vec3 p, vec3 center, float radius) {
    const vec3 d = p - center;
    const float len2 = dot(d, d);
    if (len2 <= radius * radius) return;
    p = center + radius * (d / sqrt(len2));
}
vec3 closest_on_segment(vec3 p, vec3 a, vec3 b) {
    const vec3 ab = b - a;
    const float len2 = dot(ab, ab);
    if (len2 <= 0.0) return a;
    const float t = clamp(dot(p - a, ab) / len2, 0.0, 1.0);
    return a + t * ab;
}

// The chain's colliders (solver.cpp step): in the end root's frame (la, lb; a plane's lb
// its turned normal), where the substep's root places them (ca, cb), the distance each
// keeps (rods::collider_reach) and its kind. Sized and indexed by constants (MAX_COLLIDERS).
vec3 col_la[COLLIDER_SLOTS], col_lb[COLLIDER_SLOTS];
vec3 col_ca[COLLIDER_SLOTS], col_cb[COLLIDER_SLOTS];
float col_reach[COLLIDER_SLOTS];
uint col_kind[COLLIDER_SLOTS];
uint col_count;

// solver_collide.cpp collide_all(): one particle against collider k.
void collide_with(inout vec3 p, uint k) {
    if ((FEATURES & KW_RODS_FEATURE_PLANE) != 0u && col_kind[k] == KW_RODS_COLLIDER_PLANE) {
        const float s = dot(p - col_ca[k], col_cb[k]);
        if (s < col_reach[k]) p += (col_reach[k] - s) * col_cb[k];
    } else if ((FEATURES & KW_RODS_FEATURE_INSIDE) != 0u && col_kind[k] == KW_RODS_COLLIDER_INSIDE) {
        pull_in(p, closest_on_segment(p, col_ca[k], col_cb[k]), col_reach[k]);
    } else {
        push_out(p, closest_on_segment(p, col_ca[k], col_cb[k]), col_reach[k]);
    }
}

// solver_collide.cpp collide_all(): one particle against every collider, the set
// KW_RODS_COLLIDER_PASSES times (unrolled for few colliders: UNROLL_COLLIDERS).
void collide_all(inout vec3 p) {
    [[unroll]] for (uint pass = 0; pass < KW_RODS_COLLIDER_PASSES; ++pass) {
        if (UNROLL_COLLIDERS) {
            [[unroll]] for (uint k = 0; k < MAX_COLLIDERS; ++k) if (k < col_count) collide_with(p, k);
        } else {
            [[dont_unroll]] for (uint k = 0; k < col_count; ++k) collide_with(p, k);
        }
    }
}

// SPEC A.3 (world.cpp rest_shape, view.cpp): the direction to the camera (or against its
// view for an orthographic one) in the frame of the character's reference joint `ref`.
vec3 view_direction(RodTransformGpu ref) {
    const vec4 to_reference = qconj(ref.rotation);
    const vec3 offset = push.camera_position.xyz - ref.position.xyz;
    const float len = length(offset);
    if (push.camera_position.w == 0.0 && len >= 1e-6) return qrot(to_reference, offset / len);
    return normalize(qrot(to_reference, -push.camera_forward.xyz));
}

// SPEC A.3: the weights of template t's m view examples for direction d (w[1..m], 0 past
// m), normalized when they sum to 1 or more, and the base's w[0], the rest.
void view_weights(RodTemplateGpu t, uint m, vec3 d, out float w[KW_RODS_MAX_VIEWS + 1]) {
    float sum = 0.0;
    [[unroll]] for (uint k = 0; k < KW_RODS_MAX_VIEWS; ++k) w[k + 1] = 0.0;
    [[unroll]] for (uint k = 0; k < MAX_VIEWS; ++k) {
        if (k < m) {
            const vec4 view = t.views[k];
            const float s = clamp((dot(view.xyz, d) + 1.0) * 0.5, 0.0, 1.0);
            w[k + 1] = pow(s, view.w);
            sum += w[k + 1];
        }
    }
    if (sum >= 1.0) {
        [[unroll]] for (uint k = 1; k <= MAX_VIEWS; ++k) w[k] /= sum;
        sum = 1.0;
    }
    w[0] = 1.0 - sum;
}

// The chain's col_count colliders from `begin` in the end root's frame `to` (solver.cpp
// step), each with the distance it keeps from a particle of the chain's `thickness`
// (rods::collider_reach()).
void colliders_in_root_frame(uint begin, RodTransformGpu to, float thickness) {
    const vec4 to_root = qconj(to.rotation);
    [[unroll]] for (uint k = 0; k < MAX_COLLIDERS; ++k) if (k < col_count) {
        const RodColliderGpu col = colliders[begin + k];
        const uint kind = uint(col.b.w);
        col_kind[k] = kind;
        col_la[k] = qrot(to_root, col.a.xyz - to.position.xyz);
        col_lb[k] = kind == KW_RODS_COLLIDER_PLANE ? qrot(to_root, col.b.xyz) : qrot(to_root, col.b.xyz - to.position.xyz);
        col_reach[k] = kind == KW_RODS_COLLIDER_PLANE    ? thickness
                       : kind == KW_RODS_COLLIDER_INSIDE ? max(col.a.w - thickness, 0.0)
                                                         : col.a.w + thickness;
    }
}

// The colliders placed by a substep's root (r_pos, r_rot), solver.cpp step.
void place_colliders(vec3 r_pos, vec4 r_rot) {
    [[unroll]] for (uint k = 0; k < MAX_COLLIDERS; ++k) if (k < col_count) {
        col_ca[k] = r_pos + qrot(r_rot, col_la[k]);
        col_cb[k] = col_kind[k] == KW_RODS_COLLIDER_PLANE ? qrot(r_rot, col_lb[k]) : r_pos + qrot(r_rot, col_lb[k]);
    }
}

#endif
