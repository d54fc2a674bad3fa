#version 450
// Ground contact shadows (DrawList::add_ground_shadow): black, blended over what is
// drawn. The colour's r is the disc's opacity, its a how far in from the rim (1 in the
// middle, 0 at the rim, interpolated across the fan); smoothstep makes the edge soft.
layout(location = 0) in vec4 in_color;
layout(location = 1) flat in vec3 in_normal;

layout(location = 0) out vec4 out_color;

void main() { out_color = vec4(0.0, 0.0, 0.0, in_color.r * smoothstep(0.0, 1.0, in_color.a)); }
