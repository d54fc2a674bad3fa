#version 450
// The node world matrices of rigged characters for the skinned-mesh layer, from the
// pose backend's clip world matrices and the rod backend's chain state, on the device
// (nothing read back): one invocation per instance walks the character's nodes parents
// first and composes exactly what RodScene::rigged_world() (engine/scene/rod_scene.cpp)
// composes on the CPU. shared/skin.h has the layout and why.
#extension GL_GOOGLE_include_directive : require

#include "shared/poses.h"
#include "shared/rods.h"
#include "shared/skin.h"
#include "lib/matrix.glsl"
#include "lib/quat.glsl"

layout(local_size_x = KW_SKIN_WORKGROUP_SIZE) in;

layout(std430, binding = KW_SKIN_BINDING_NODES) readonly buffer Nodes { SkinNodeGpu nodes[]; };
layout(std430, binding = KW_SKIN_BINDING_CHAINS) readonly buffer Chains { SkinChainGpu chains[]; };
layout(std430, binding = KW_SKIN_BINDING_CLIP_WORLD) readonly buffer ClipWorld { PoseMatrixGpu clip_world[]; };
layout(std430, binding = KW_SKIN_BINDING_CHAIN_STATES) readonly buffer ChainStates { RodChainStateGpu chain_states[]; };
layout(std430, binding = KW_SKIN_BINDING_MOTION) readonly buffer Motion { RodJointMotionGpu motion[]; };
layout(std430, binding = KW_SKIN_BINDING_SPIN) readonly buffer Spin { RodJointSpinGpu spin[]; };
layout(std430, binding = KW_SKIN_BINDING_WORLD) buffer World { PoseMatrixGpu world[]; };

layout(push_constant) uniform Push { SkinPush push; };

// The clip's local transform of a node, inverse(parent) * node for affine matrices, with
// the translations subtracted first: a crowd's placements put both far from the origin,
// and their difference keeps its precision where the product of a full inverse would not.
mat4 local_of(mat4 parent, mat4 node) {
    const mat3 inv = inverse(mat3(parent));
    return mat4(vec4(inv * node[0].xyz, 0.0), vec4(inv * node[1].xyz, 0.0), vec4(inv * node[2].xyz, 0.0),
                vec4(inv * (node[3].xyz - parent[3].xyz), 1.0));
}

void main() {
    const uint instance = gl_GlobalInvocationID.x;
    if (instance >= push.counts.x) return;
    const uint node_count = push.counts.y;
    const uint base = instance * node_count;
    for (uint k = 0; k < node_count; ++k) {
        const SkinNodeGpu node = nodes[k];
        const uint n = node.ids.x, parent = node.ids.y, kind = node.ids.z;
        const mat4 clip = mat4_columns(clip_world[base + n].columns);
        if (kind == KW_SKIN_NODE_CLIP) {
            world[base + n].columns = clip_world[base + n].columns;
            continue;
        }
        // The clip's local transform (a root's: its world, the placement being rigid).
        const mat4 local = parent == KW_SKIN_NONE ? clip : local_of(mat4_columns(clip_world[base + parent].columns), clip);
        if (kind == KW_SKIN_NODE_BELOW) {
            const mat4 w = mat4_columns(world[base + parent].columns) * local;
            world[base + n].columns = vec4[4](w[0], w[1], w[2], w[3]);
            continue;
        }
        // A simulated joint (rigged_world): at its particle's position, with the
        // particle's orientation turned by the shortest arc that points its bone at the
        // next joint (the last joint keeps the particle's), and the clip's local scale
        // (the column lengths of the local matrix: exact for positive scales).
        const SkinChainGpu chain = chains[instance * push.counts.z + node.ids.w];
        const uint i = node.joint.x, joint = chain.ids.y + i;
        const vec3 x = motion[joint].x.xyz;
        vec4 q = qnormalize(spin[joint].q);
        if (i + 1 < node.joint.y) {
            // positions[j + 1] - positions[j]: both are root + x, the root cancels.
            const vec3 d = motion[joint + 1].x.xyz - x;
            const float len = length(d);
            if (len > 1e-9) q = qnormalize(qmul(shortest_arc(normalize(qrot(q, node.axis.xyz)), d / len), q));
        }
        const mat3 r = mat3_cast(q);
        const vec3 s = vec3(length(local[0].xyz), length(local[1].xyz), length(local[2].xyz));
        const vec3 p = chain_states[chain.ids.x].root.position.xyz + x;
        world[base + n].columns = vec4[4](vec4(r[0] * s.x, 0.0), vec4(r[1] * s.y, 0.0), vec4(r[2] * s.z, 0.0), vec4(p, 1.0));
    }
}
