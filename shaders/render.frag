#version 450
// Flat colours: unlit vertices keep their colour exactly (tests look for it), lit faces
// get ambient + two-sided Lambert from one directional light.
#extension GL_GOOGLE_include_directive : require
#include "shared/render.h"

layout(location = 0) in vec4 in_color;
layout(location = 1) flat in vec3 in_normal;

layout(push_constant, std430) uniform Push { RenderPush push; };

layout(location = 0) out vec4 out_color;

void main() {
    vec3 color = in_color.rgb;
    if (in_color.a > 0.5) {
        const float len = length(in_normal);
        const float diffuse = len > 0.0 ? abs(dot(in_normal / len, push.light.xyz)) : 1.0;
        color *= push.light.w + (1.0 - push.light.w) * diffuse;
    }
    out_color = vec4(color, 1.0);
}
