#version 450
// The skinned-mesh layer: a rigged character's indexed triangles instanced
// per character instance, each vertex skinned with its instance's node world matrices
// (skin_nodes.comp's output, or rigged_world()'s uploaded): glTF §3.7.3, the weighted
// sum of world(joint) * inverseBindMatrix * position, divided by the sum of the weights
// used (the CPU path's normalization); a vertex without weights follows its mesh node.
#extension GL_GOOGLE_include_directive : require
#include "shared/poses.h"
#include "shared/render.h"
#include "shared/skin.h"
#include "lib/matrix.glsl"

layout(location = 0) in vec4 in_position;
layout(location = 1) in vec4 in_joints;
layout(location = 2) in vec4 in_weights;
layout(location = 3) in vec4 in_color;

layout(push_constant, std430) uniform Push { RenderPush push; };
layout(std430, set = 0, binding = KW_SKINNED_BINDING_JOINTS) readonly buffer Joints { SkinJointGpu joints[]; };
layout(std430, set = 0, binding = KW_SKINNED_BINDING_WORLD) readonly buffer World { PoseMatrixGpu world[]; };

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec3 out_from_eye;

mat4 world_matrix(uint node) {
    return mat4_columns(world[gl_InstanceIndex * push.draw.x + node].columns);
}

void main() {
    const vec4 p = vec4(in_position.xyz, 1.0);
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int k = 0; k < 4; ++k) {
        const float w = in_weights[k];
        if (w <= 0.0) continue;
        const SkinJointGpu joint = joints[uint(in_joints[k])];
        const mat4 inverse_bind = mat4_columns(joint.inverse_bind);
        // world * (inverse bind * p): two matrix-vector products instead of a matrix product.
        sum += w * (world_matrix(joint.ids.x) * (inverse_bind * p)).xyz;
        total += w;
    }
    const vec3 skinned = total > 0.0 ? sum / total : (world_matrix(uint(in_position.w)) * p).xyz;
    gl_Position = mat4_columns(push.view_proj) * vec4(skinned, 1.0);
    out_color = vec4(in_color.rgb, 1.0);
    // Relative to the eye: the fragment shader's derivatives of it then keep their
    // precision far from the origin.
    out_from_eye = skinned - push.eye.xyz;
}
