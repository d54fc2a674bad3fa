#version 450
// The chain layer: chains drawn straight from rod state in device buffers (the vulkan rod
// backend's, or the same layout uploaded from a snapshot), with no vertex buffer. Each
// segment between consecutive joints is a camera-facing ribbon shaded as a round tube
// (lit.frag rebuilds a cylinder's normal from the position across the ribbon): as wide
// as the chain's physics thickness at the root, tapering to KW_CHAIN_TIP_WIDTH of it at
// the last joint, but at least a minimum number of pixels wide so that far strands stay
// visible. Joint dots (unlit, the exact chain colour) only when asked for
// (ChainStyle::joints), and only where the chain is long enough on screen for them to
// stay apart (scene_draw.cpp explains the rule).
#extension GL_GOOGLE_include_directive : require
#include "shared/chain_draw.h"
#include "shared/rods.h"
#include "lib/camera.glsl"
#include "lib/matrix.glsl"

layout(push_constant, std430) uniform Push { RenderPush push; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_INFO) readonly buffer Info { ChainDrawInfo info[]; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_JOINT_CHAIN) readonly buffer JointChain { uint joint_chain[]; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_CHAIN_STATES) readonly buffer States { RodChainStateGpu states[]; };
layout(std430, set = 0, binding = KW_CHAINS_BINDING_MOTION) readonly buffer Motion { RodJointMotionGpu motion[]; };

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec3 out_across;  // lit.frag: u * side, u in [-1, 1] across the ribbon
layout(location = 2) out vec3 out_facing;  // lit.frag: the tube's normal at its middle line

// World position of joint j of chain c: the backend stores it relative to the root.
vec3 joint_position(uint c, uint j) { return states[c].root.position.xyz + motion[j].x.xyz; }

// From p towards the viewer (DrawList::towards_viewer).
vec3 towards_viewer(vec3 p) { return push.draw.w == KW_RENDER_ORTHOGRAPHIC ? -push.forward.xyz : push.eye.xyz - p; }

// Nothing to draw: every vertex of the primitive at one point makes it degenerate.
void emit_nothing() {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // behind the far plane as well
    out_color = vec4(0.0);
    out_across = vec3(0.0);
    out_facing = vec3(0.0);
}

// The tube's width at joint j of a chain of n joints from `first`: 2 x thickness at the
// root, linearly down to KW_CHAIN_TIP_WIDTH of that at the tip.
float tube_width(ChainDrawInfo chain, uint j) {
    float t = chain.joints.y > 1u ? float(j - chain.joints.x) / float(chain.joints.y - 1u) : 0.0;
    return 2.0 * chain.size.x * mix(1.0, KW_CHAIN_TIP_WIDTH, t);
}

void main() {
    uint j = gl_InstanceIndex;
    uint c = joint_chain[j];
    ChainDrawInfo chain = info[c];
    uint first = chain.joints.x, n = chain.joints.y;
    vec3 p = joint_position(c, j);
    mat4 view_proj = mat4_columns(push.view_proj);
    out_across = vec3(0.0);
    out_facing = vec3(0.0);
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
        if (!(side_length > 0.0)) {  // seen end-on (a one-segment gap) or degenerate
            emit_nothing();
            return;
        }
        vec3 unit = side / side_length;
        float min_px = uintBitsToFloat(push.draw.y);
        vec3 ha = 0.5 * max(tube_width(chain, j), min_px * pixel_size_at(push, p)) * unit;
        vec3 hb = 0.5 * max(tube_width(chain, j + 1u), min_px * pixel_size_at(push, b)) * unit;
        // Triangles (a - ha, a + ha, b + hb) and (a - ha, b + hb, b - hb); u: -1 on the
        // minus side, +1 on the plus side.
        vec3 corners[KW_CHAIN_SEGMENT_VERTICES] = vec3[](p - ha, p + ha, b + hb, p - ha, b + hb, b - hb);
        const float across[KW_CHAIN_SEGMENT_VERTICES] = float[](-1.0, 1.0, 1.0, -1.0, 1.0, -1.0);
        gl_Position = view_proj * vec4(corners[v], 1.0);
        out_color = vec4(unpackUnorm4x8(chain.joints.z).rgb, 1.0);  // a = 1: lit
        out_across = across[v] * unit;
        // Perpendicular to the axis, in the ribbon's normal plane, towards the viewer
        // (side = axis x towards, so side x axis leans towards the viewer).
        out_facing = normalize(cross(unit, b - p));
        return;
    }

    // Dots (unlit: a = 0, the exact colour), only where they stay apart: a far chain would be one blob of them.
    float min_px = uintBitsToFloat(push.draw.z);
    float length_sum = 0.0;
    for (uint k = first; k + 1 < first + n; ++k) length_sum += length(joint_position(c, k + 1) - joint_position(c, k));
    float pixel = pixel_size_at(push, joint_position(c, first));
    if (pixel > 0.0 && length_sum / pixel < 3.0 * min_px * float(n)) {
        emit_nothing();
        return;
    }
    out_color = vec4(unpackUnorm4x8(chain.joints.z).rgb, 0.0);
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
