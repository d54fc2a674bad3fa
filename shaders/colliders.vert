#version 450
// The collider layer: the rod input's colliders drawn from a device buffer (the vulkan rod
// backend's input, written there on the device for rigged characters, or the same layout
// uploaded from a frame) as solid, smooth-shaded capsules in one body colour, lit by
// lit.frag: a low-poly capsule built here per vertex, instanced per collider, no vertex
// buffer. Each end is a hemisphere of KW_COLLIDER_RINGS bands round the capsule's axis,
// joined by a cylinder band; a sphere (ends closer than 1e-6 m) is the same mesh with a
// cylinder of no length. shared/render.h has the layout.
#extension GL_GOOGLE_include_directive : require
#include "shared/chain_draw.h"
#include "shared/rods.h"
#include "lib/matrix.glsl"

layout(push_constant, std430) uniform Push { RenderPush push; };
layout(std430, set = 0, binding = KW_COLLIDERS_BINDING_COLLIDERS) readonly buffer Colliders { RodColliderGpu colliders[]; };

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec3 out_across;  // lit.frag: the vertex normal
layout(location = 2) out vec3 out_facing;  // lit.frag: unused by meshes (zero)

void main() {
    RodColliderGpu c = colliders[gl_InstanceIndex];
    // Outside colliders only: an inside one would hide the strands it holds, and a plane
    // has no extent to draw. The others' vertices are all clipped (w = 0).
    if (c.b.w != float(KW_RODS_COLLIDER_OUTSIDE)) {
        gl_Position = vec4(0.0);
        out_color = vec4(0.0);
        out_across = vec3(0.0, 1.0, 0.0);
        out_facing = vec3(0.0);
        return;
    }
    vec3 a = c.a.xyz, b = c.b.xyz;
    float radius = c.a.w;
    vec3 along = b - a;
    vec3 axis = length(along) > 1e-6 ? normalize(along) : vec3(0.0, 1.0, 0.0);
    // Two unit vectors across the axis.
    vec3 helper = abs(axis.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 e1 = normalize(cross(axis, helper)), e2 = cross(axis, e1);

    // Vertex v: corner v % 6 of the quad (band, side) = (v / 6 / SIDES, v / 6 % SIDES),
    // triangles (k, s) (k, s+1) (k+1, s+1) and (k, s) (k+1, s+1) (k+1, s).
    uint v = gl_VertexIndex, quad = v / 6u, corner = v % 6u;
    uint band = quad / uint(KW_COLLIDER_SIDES), side = quad % uint(KW_COLLIDER_SIDES);
    const uint ring_step[6] = uint[](0u, 0u, 1u, 0u, 1u, 1u);
    const uint side_step[6] = uint[](0u, 1u, 1u, 0u, 1u, 0u);
    uint ring = band + ring_step[corner], around = side + side_step[corner];
    // Rings 0..RINGS: from a's pole to its equator; RINGS+1..2 RINGS+1: b's equator to its pole.
    const uint rings = uint(KW_COLLIDER_RINGS);
    bool at_b = ring > rings;
    float latitude = 1.57079632679 * (at_b ? float(ring - rings - 1u) / float(rings) : float(ring) / float(rings) - 1.0);
    float longitude = 6.28318530718 * float(around) / float(KW_COLLIDER_SIDES);
    vec3 n = cos(latitude) * (cos(longitude) * e1 + sin(longitude) * e2) + sin(latitude) * axis;
    vec3 p = (at_b ? b : a) + radius * n;
    gl_Position = mat4_columns(push.view_proj) * vec4(p, 1.0);
    out_color = vec4(unpackUnorm4x8(push.draw.x).rgb, 1.0);  // lit
    out_across = n;
    out_facing = vec3(0.0);
}
