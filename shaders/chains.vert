#version 450
// The chain layer: chains drawn straight from rod state in device buffers (the vulkan rod
// backend's, or the same layout uploaded from a snapshot), with no vertex buffer. The
// geometry is the draw list's (DrawList::add_segment / add_dot, engine/render/
// renderer.cpp) computed here per vertex: camera-facing quads between consecutive joints
// at least a minimum number of pixels wide, and dots at the joints when the chain is long
// enough on screen for them to stay apart (scene_draw.cpp explains the rule).
#extension GL_GOOGLE_include_directive : require
#include "shared/render.h"
#include "shared/rods.h"
#include "lib/camera.glsl"
#include "lib/matrix.glsl"

layout(push_constant, std430) uniform Push { RenderPush push; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_INFO) readonly buffer Info { ChainDrawInfo info[]; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_JOINT_CHAIN) readonly buffer JointChain { uint joint_chain[]; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_CHAIN_STATES) readonly buffer States { RodChainStateGpu states[]; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_MOTION) readonly buffer Motion { RodJointMotionGpu motion[]; };

layout(location = 0) out vec4 out_color;
layout(location = 1) flat out vec3 out_normal;

// World position of joint j of chain c: the backend stores it relative to the root.
vec3 joint_position(uint c, uint j) { return states[c].root.position.xyz + motion[j].x.xyz; }

// From p towards the viewer (DrawList::towards_viewer).
vec3 towards_viewer(vec3 p) { return push.draw.w == KW_RENDER_ORTHOGRAPHIC ? -push.forward.xyz : push.eye.xyz - p; }

// Nothing to draw: every vertex of the primitive at one point makes it degenerate.
void emit_nothing() {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // behind the far plane as well
    out_color = vec4(0.0);
    out_normal = vec3(0.0);
}

void main() {
    uint j = gl_InstanceIndex;
    uint c = joint_chain[j];
    ChainDrawInfo chain = info[c];
    uint first = chain.joints.x, n = chain.joints.y;
    vec3 p = joint_position(c, j);
    mat4 view_proj = mat4_columns(push.view_proj);
    out_color = vec4(unpackUnorm4x8(chain.joints.z).rgb, 0.0);  // a = 0: unlit, the exact colour
    out_normal = vec3(0.0);
    uint v = gl_VertexIndex;

    if (push.draw.x == KW_CHAINS_DRAW_SEGMENTS) {
        if (j + 1 >= first + n) {  // the last joint starts no segment
            emit_nothing();
            return;
        }
        vec3 b = joint_position(c, j + 1);
        // The quad lies in the plane of the segment and the line of sight to its middle.
        vec3 side = cross(b - p, towards_viewer(0.5 * (p + b)));
        float side_length = length(side);
        if (!(side_length > 0.0)) {  // seen end-on (its dots still show it) or degenerate
            emit_nothing();
            return;
        }
        vec3 unit = side / side_length;
        float width = 2.0 * chain.size.x, min_px = uintBitsToFloat(push.draw.y);
        vec3 ha = 0.5 * max(width, min_px * pixel_size_at(push, p)) * unit;
        vec3 hb = 0.5 * max(width, min_px * pixel_size_at(push, b)) * unit;
        // Triangles (a - ha, a + ha, b + hb) and (a - ha, b + hb, b - hb).
        vec3 corners[KW_CHAIN_SEGMENT_VERTICES] = vec3[](p - ha, p + ha, b + hb, p - ha, b + hb, b - hb);
        gl_Position = view_proj * vec4(corners[v], 1.0);
        return;
    }

    // Dots, only where they stay apart: a far chain would be one blob of them.
    float min_px = uintBitsToFloat(push.draw.z);
    float length_sum = 0.0;
    for (uint k = first; k + 1 < first + n; ++k) length_sum += length(joint_position(c, k + 1) - joint_position(c, k));
    float pixel = pixel_size_at(push, joint_position(c, first));
    if (pixel > 0.0 && length_sum / pixel < 3.0 * min_px * float(n)) {
        emit_nothing();
        return;
    }
    float r = max(1.5 * chain.size.x, min_px * pixel_size_at(push, p));
    vec3 right, up;
    camera_basis(push.forward.xyz, right, up);
    uint corner = v % 3u, side_index = v / 3u;
    if (corner == 0u) {
        gl_Position = view_proj * vec4(p, 1.0);
        return;
    }
    const float step = 6.28318530718 / float(KW_CHAIN_DOT_SIDES);
    float angle = step * float(side_index + corner - 1u);
    gl_Position = view_proj * vec4(p + r * (cos(angle) * right + sin(angle) * up), 1.0);
}
