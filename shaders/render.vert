#version 450
// The renderer's one vertex shader: world positions through the camera, or clip-space
// positions (the background) as they are.
#extension GL_GOOGLE_include_directive : require
#include "shared/render.h"
#include "lib/matrix.glsl"

layout(location = 0) in vec4 in_position;
layout(location = 1) in vec4 in_color;
layout(location = 2) in vec4 in_normal;

layout(push_constant, std430) uniform Push { RenderPush push; };

layout(location = 0) out vec4 out_color;
layout(location = 1) flat out vec3 out_normal;

void main() {
    if (in_normal.w > 0.5) {
        gl_Position = vec4(in_position.xy, 0.0, 1.0);
    } else {
        gl_Position = mat4_columns(push.view_proj) * vec4(in_position.xyz, 1.0);
    }
    out_color = in_color;
    out_normal = in_normal.xyz;
}
