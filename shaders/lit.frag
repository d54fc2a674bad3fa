#version 450
// Smooth-shaded surfaces of the layers drawn from device buffers (chains.vert,
// colliders.vert): the normal is rebuilt per fragment, so a camera-facing ribbon reads as
// a round tube and a low-poly capsule as a smooth one. Lit by the renderer's light:
// ambient + one-sided Lambert (the far side of a tube is in shade). Unlit vertices
// (colour a = 0: joint dots) keep their colour exactly.
#extension GL_GOOGLE_include_directive : require
#include "shared/render.h"

layout(location = 0) in vec4 in_color;
// The normal's part across the surface, interpolated: for a tube u * side with u in
// [-1, 1] across the ribbon; for a mesh its (interpolated) vertex normal.
layout(location = 1) in vec3 in_across;
// A tube's unit normal at its middle line (towards the viewer); zero for a mesh.
layout(location = 2) in vec3 in_facing;

layout(push_constant, std430) uniform Push { RenderPush push; };

layout(location = 0) out vec4 out_color;

void main() {
    vec3 color = in_color.rgb;
    if (in_color.a > 0.5) {
        // A cylinder's normal at u across: u * side + sqrt(1 - u^2) * facing.
        vec3 n = in_across + sqrt(max(1.0 - dot(in_across, in_across), 0.0)) * in_facing;
        float len = length(n);
        float diffuse = len > 0.0 ? max(dot(n / len, push.light.xyz), 0.0) : 1.0;
        color *= push.light.w + (1.0 - push.light.w) * diffuse;
    }
    out_color = vec4(color, 1.0);
}
