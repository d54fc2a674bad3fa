#version 450
// The bird layer: each bird's seven part meshes posed from its BirdPoseGpu in a device
// buffer (the vulkan bird backend's pose ring, or the same layout uploaded), instanced
// per bird. The part hierarchy and the pose expansion are those of the glTF export and
// the Vulkan backend's read back: world(part) = world(parent) * T(offset) * R(rotation),
// the Body placed at the pose's position and scaled up to a minimum size on screen;
// the Tail widened by its spread (position.w); the right wing the mirror of the left,
// (x, -y, -z, w) (SPEC B.2).
#extension GL_GOOGLE_include_directive : require
#include "shared/birds.h"
#include "shared/bird_draw.h"
#include "lib/camera.glsl"
#include "lib/matrix.glsl"
#include "lib/quat.glsl"

layout(location = 0) in vec4 in_position;
layout(location = 1) in vec4 in_normal;

layout(push_constant, std430) uniform Push { RenderPush push; };
layout(std430, set = 0, binding = KW_BIRDS_DRAW_BINDING_TYPES) readonly buffer Types { BirdDrawType types[]; };
layout(std430, set = 0, binding = KW_BIRDS_DRAW_BINDING_ORDER) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = KW_BIRDS_DRAW_BINDING_POSES) readonly buffer Poses { BirdPoseGpu poses[]; };

layout(location = 0) out vec4 out_color;
layout(location = 1) flat out vec3 out_normal;

vec4 unit_quat(vec4 q) {
    float n = length(q);
    return n > 0.0 ? q / n : vec4(0.0, 0.0, 0.0, 1.0);
}

vec4 part_rotation(BirdPoseGpu pose, int part) {
    if (part == KW_PART_BODY) return pose.body;
    if (part == KW_PART_HEAD) return pose.head;
    if (part == KW_PART_TAIL) return pose.tail;
    if (part == KW_PART_LEFT_ARM1) return pose.left_arm1;
    if (part == KW_PART_LEFT_ARM2) return pose.left_arm2;
    if (part == KW_PART_RIGHT_ARM1) return vec4(pose.left_arm1.x, -pose.left_arm1.yz, pose.left_arm1.w);
    if (part == KW_PART_RIGHT_ARM2) return vec4(pose.left_arm2.x, -pose.left_arm2.yz, pose.left_arm2.w);
    return vec4(0.0, 0.0, 0.0, 1.0);
}

void main() {
    uint bird = order[gl_InstanceIndex];
    BirdPoseGpu pose = poses[push.draw.y + bird];
    BirdDrawType type = types[push.draw.x];
    // Up the hierarchy to the Body: into each parent's frame.
    vec3 p = in_position.xyz, n = in_normal.xyz;
    int part = int(in_position.w);
    if (part == KW_PART_TAIL) {  // the spread widens the tail across (its X)
        p.x *= 1.0 + pose.position.w;
        n.x /= 1.0 + pose.position.w;
    }
    for (int guard = 0; part != KW_PART_BODY && guard < KW_PART_COUNT; ++guard) {
        vec4 q = unit_quat(part_rotation(pose, part));
        p = rotate(q, p) + type.parts[part].xyz;
        n = rotate(q, n);
        part = int(type.parts[part].w);
    }
    vec4 body = unit_quat(pose.body);
    vec3 position = pose.position.xyz;
    // A far flock stays visible: birds smaller than the minimum wingspan in pixels are
    // drawn scaled up to it (their positions stay exact).
    float pixel = pixel_size_at(push, position);
    float scale = pixel > 0.0 ? max(1.0, uintBitsToFloat(push.draw.z) * pixel / type.color.w) : 1.0;
    vec3 world = position + scale * rotate(body, p);
    gl_Position = mat4_columns(push.view_proj) * vec4(world, 1.0);
    out_color = vec4(type.color.rgb, 1.0);  // lit
    out_normal = rotate(body, n);
}
