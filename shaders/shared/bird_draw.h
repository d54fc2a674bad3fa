// The bird domain's render layer (engine/domains/bird_layer.cpp): birds drawn from their
// poses in device buffers.
// Shared by GLSL and C++ (static_asserts in engine/gpu/shared_layout.cpp).
#ifndef KODAWARI_SHADERS_SHARED_BIRD_DRAW_H
#define KODAWARI_SHADERS_SHARED_BIRD_DRAW_H

#include "glsl_types.h"
#include "render.h"

KW_NAMESPACE_BEGIN

// The bird layer (birds.vert): the seven part meshes of each wing type in one vertex
// buffer (BirdDrawVertex, triangle lists), instanced per bird from BirdPoseGpu poses in
// device buffers: the vulkan bird backend's pose ring or the same layout uploaded.
#define KW_BIRDS_DRAW_BINDING_TYPES 0  // BirdDrawType per wing type (static)
#define KW_BIRDS_DRAW_BINDING_ORDER 1  // uint per bird: bird indices grouped by wing type (static)
#define KW_BIRDS_DRAW_BINDING_POSES 2  // BirdPoseGpu per bird (from RenderPush.draw.y on)
#define KW_BIRDS_DRAW_BINDING_COUNT 3
// RenderPush.draw for birds: x: wing type, y: index of the first bird's pose in the
// poses buffer (a frame slot of the backend's ring), z: minimum wingspan in pixels
// (float bits).

struct BirdDrawVertex {
    vec4 position;  // xyz: in its part's frame, w: the part (KW_PART_*)
    vec4 normal;    // xyz: the face's normal in its part's frame (flat shading), w: unused
};

struct BirdDrawType {
    vec4 parts[7];  // per part (KW_PART_*): xyz its offset in its parent's frame, w: the parent (-1: none)
    vec4 color;     // rgb: base colour, w: wingspan (m)
};

KW_NAMESPACE_END

#endif
