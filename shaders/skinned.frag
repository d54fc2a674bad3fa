#version 450
// Skinned meshes, flat shaded as the draw list's lit triangles are (render.frag: ambient
// + two-sided Lambert from one directional light). A vertex cannot know its face's normal
// after skinning, so the fragment takes it from the screen-space derivatives of the
// interpolated position: every sample of a triangle lies in its plane, so their
// differences span it and their cross product is the face normal (its sign does not
// matter, the light is two-sided).
#extension GL_GOOGLE_include_directive : require
#include "shared/render.h"

layout(location = 0) in vec4 in_color;
layout(location = 1) in vec3 in_from_eye;

layout(push_constant, std430) uniform Push { RenderPush push; };

layout(location = 0) out vec4 out_color;

void main() {
    const vec3 normal = cross(dFdx(in_from_eye), dFdy(in_from_eye));
    const float len = length(normal);
    const float diffuse = len > 0.0 ? abs(dot(normal / len, push.light.xyz)) : 1.0;
    out_color = vec4(in_color.rgb * (push.light.w + (1.0 - push.light.w) * diffuse), 1.0);
}
