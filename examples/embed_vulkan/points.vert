#version 450
// Draws the module's output where it is: chain joints from the rod backend's buffers
// (root + joint offset, the layout of kodawari/shared/rods.h) or bird bodies from the
// bird backend's (kodawari/shared/birds.h), as points. The application's own shader: the
// module defines the structs, the application binds its buffers.
#extension GL_GOOGLE_include_directive : require
#include "kodawari/shared/birds.h"
#include "kodawari/shared/rods.h"

layout(push_constant, std430) uniform Push {
    mat4 view_proj;
    uvec4 info;  // x: 0 chains, 1 birds; y: joints per chain; z: the first bird's element
    vec4 color;
} push;

layout(std430, set = 0, binding = 0) readonly buffer States { RodChainStateGpu states[]; };
layout(std430, set = 0, binding = 1) readonly buffer Motion { RodJointMotionGpu motion[]; };
layout(std430, set = 0, binding = 2) readonly buffer Poses { BirdPoseGpu poses[]; };

layout(location = 0) out vec4 out_color;

void main() {
    vec3 p;
    if (push.info.x == 0u) {
        uint j = uint(gl_VertexIndex);
        p = states[j / push.info.y].root.position.xyz + motion[j].x.xyz;
    } else {
        p = poses[push.info.z + uint(gl_VertexIndex)].position.xyz;
    }
    gl_Position = push.view_proj * vec4(p, 1.0);
    gl_PointSize = 1.0;
    out_color = push.color;
}
