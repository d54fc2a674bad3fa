#version 450
// The rod kernel's kinematic input of rigged characters, written on the device: for each
// posed instance (one invocation), its reference joint, its chain roots, its colliders,
// its chains' key sources and center frames (docs/keyed-examples.md K.1; engine/rods/rod_scene.cpp key_entry)
// from the pose backend's world matrices, exactly as RodScene::rigged_frame computes them
// on the host (engine/scene/rod_scene.cpp) with animation::rigid_part (engine/animation/character.cpp:
// the translation, and the rotation of the matrix's columns normalized, a mirror turned
// proper, converted to a quaternion as glm::quat_cast does). shared/rod_inputs.h has the
// layout.
#extension GL_GOOGLE_include_directive : require

#include "shared/poses.h"
#include "shared/rod_inputs.h"
#include "shared/rods.h"
#include "lib/quat.glsl"

layout(local_size_x = KW_ROD_INPUTS_WORKGROUP_SIZE) in;

layout(std430, binding = KW_ROD_INPUTS_BINDING_WORLD) readonly buffer World { PoseMatrixGpu world[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_INSTANCES) readonly buffer Instances { RodInputInstanceGpu instances[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_ATTACHMENTS) readonly buffer Attachments { RodInputAttachmentGpu attachments[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_REFERENCE) writeonly buffer Reference { RodTransformGpu reference[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_ROOTS) writeonly buffer Roots { RodTransformGpu roots[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_COLLIDERS) writeonly buffer Colliders { RodColliderGpu colliders[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_KEYS) writeonly buffer Keys { RodTransformGpu keys[]; };
layout(std430, binding = KW_ROD_INPUTS_BINDING_CENTERS) writeonly buffer Centers { RodTransformGpu centers[]; };

layout(push_constant) uniform Push { RodInputPush push; };

// glm::quat_cast of a rotation matrix (m[column][row]): the largest of 4w^2-1, 4x^2-1,
// 4y^2-1, 4z^2-1 (in that order of preference) gives the best-conditioned component.
vec4 quat_cast(mat3 m) {
    float four_x = m[0][0] - m[1][1] - m[2][2];
    float four_y = m[1][1] - m[0][0] - m[2][2];
    float four_z = m[2][2] - m[0][0] - m[1][1];
    float four_w = m[0][0] + m[1][1] + m[2][2];
    int biggest_index = 0;
    float biggest = four_w;
    if (four_x > biggest) { biggest = four_x; biggest_index = 1; }
    if (four_y > biggest) { biggest = four_y; biggest_index = 2; }
    if (four_z > biggest) { biggest = four_z; biggest_index = 3; }
    float value = sqrt(biggest + 1.0) * 0.5;
    float mult = 0.25 / value;
    if (biggest_index == 0) return vec4((m[1][2] - m[2][1]) * mult, (m[2][0] - m[0][2]) * mult, (m[0][1] - m[1][0]) * mult, value);
    if (biggest_index == 1) return vec4(value, (m[0][1] + m[1][0]) * mult, (m[2][0] + m[0][2]) * mult, (m[1][2] - m[2][1]) * mult);
    if (biggest_index == 2) return vec4((m[0][1] + m[1][0]) * mult, value, (m[1][2] + m[2][1]) * mult, (m[2][0] - m[0][2]) * mult);
    return vec4((m[2][0] + m[0][2]) * mult, (m[1][2] + m[2][1]) * mult, value, (m[0][1] - m[1][0]) * mult);
}

// animation::rigid_part of node n of posed instance i.
RodTransformGpu rigid_part(uint i, uint n) {
    PoseMatrixGpu w = world[i * push.counts.y + n];
    mat3 r = mat3(w.columns[0].xyz, w.columns[1].xyz, w.columns[2].xyz);
    for (int c = 0; c < 3; ++c) {
        float len = length(r[c]);
        if (len > 0.0) r[c] /= len;
    }
    if (determinant(r) < 0.0) r[0] = -r[0];  // a mirror: keep a proper rotation
    RodTransformGpu t;
    t.position = vec4(w.columns[3].xyz, 0.0);
    t.rotation = normalize(quat_cast(r));
    return t;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.counts.x) return;
    uvec4 ids = instances[i].ids;
    reference[ids.x] = rigid_part(i, push.counts.z);
    for (uint c = 0u; c < push.counts.w; ++c) roots[ids.y + c] = rigid_part(i, attachments[c].node.x);
    for (uint k = 0u; k < push.more.x; ++k) {
        RodInputAttachmentGpu a = attachments[push.counts.w + k];
        RodTransformGpu joint = rigid_part(i, a.node.x);
        colliders[ids.z + k].a = vec4(joint.position.xyz + rotate(joint.rotation, a.a.xyz), a.a.w);
        // A plane's b is its normal: turned, not moved (rod_scene.cpp place()).
        const vec3 b = rotate(joint.rotation, a.b.xyz);
        colliders[ids.z + k].b = vec4(a.b.w == float(KW_RODS_COLLIDER_PLANE) ? b : joint.position.xyz + b, a.b.w);
    }
    // rod_scene.cpp key_entry: a motion source's world pose; a pose source's rotation
    // relative to its parent's (the world's when it has none), position 0.
    for (uint k = 0u; k < push.more.y; ++k) {
        RodInputAttachmentGpu a = attachments[push.counts.w + push.more.x + k];
        RodTransformGpu joint = rigid_part(i, a.node.x);
        if (a.node.z == 0u) {  // rods::KeySourceKind::Motion
            keys[ids.w + k] = joint;
        } else {
            vec4 rotation = joint.rotation;
            if (a.node.y != KW_ROD_INPUTS_NO_PARENT) rotation = qnormalize(qmul(qconj(rigid_part(i, a.node.y).rotation), joint.rotation));
            keys[ids.w + k] = RodTransformGpu(vec4(0.0), rotation);
        }
    }
    // rod_scene.cpp rigged_frame: a center frame is its node's rigid part.
    const uint first_center = push.counts.w + push.more.x + push.more.y;
    for (uint k = 0u; k < push.more.z; ++k) centers[instances[i].more.x + k] = rigid_part(i, attachments[first_center + k].node.x);
}
