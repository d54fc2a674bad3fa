#version 450
// The collider layer: the rod input's colliders drawn from a device buffer (the vulkan rod
// backend's input, written there on the device for rigged characters, or the same layout
// uploaded from a frame) as 1-pixel lines in one colour: a circle facing the camera
// (render::camera_basis) round each end of a capsule and the segment between them; a
// sphere (ends closer than 1e-6 m) gets one circle. shared/render.h has the layout.
#extension GL_GOOGLE_include_directive : require
#include "shared/render.h"
#include "shared/rods.h"
#include "lib/camera.glsl"
#include "lib/matrix.glsl"

layout(push_constant, std430) uniform Push { RenderPush push; };
layout(std430, set = 0, binding = KW_COLLIDERS_BINDING_COLLIDERS) readonly buffer Colliders { RodColliderGpu colliders[]; };

layout(location = 0) out vec4 out_color;
layout(location = 1) flat out vec3 out_normal;

void main() {
    RodColliderGpu c = colliders[gl_InstanceIndex];
    out_color = vec4(unpackUnorm4x8(push.draw.x).rgb, 0.0);  // a = 0: unlit, the exact colour
    out_normal = vec3(0.0);
    vec3 a = c.a.xyz, b = c.b.xyz;
    float radius = c.a.w;
    bool capsule = length(b - a) > 1e-6;
    uint v = gl_VertexIndex;
    const uint circle = 2u * KW_COLLIDER_SIDES;
    if (!capsule && v >= circle) {
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // behind the far plane: not drawn
        return;
    }
    vec3 p;
    if (v >= 2u * circle) {
        p = v == 2u * circle ? a : b;
    } else {
        vec3 right, up;
        camera_basis(push.forward.xyz, right, up);
        uint k = v % circle;  // line k / 2 of the circle, from corner k / 2 to the next
        const float step = 6.28318530718 / float(KW_COLLIDER_SIDES);
        float angle = step * float(k / 2u + k % 2u);
        p = (v < circle ? a : b) + radius * (cos(angle) * right + sin(angle) * up);
    }
    gl_Position = mat4_columns(push.view_proj) * vec4(p, 1.0);
}
