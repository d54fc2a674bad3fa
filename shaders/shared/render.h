// The renderer's vertex layout and push constants (engine/render/, shaders/render.*),
// which every layer's shaders use too,
// shared by GLSL and C++ (static_asserts in engine/gpu/shared_layout.cpp).
#ifndef KODAWARI_SHADERS_SHARED_RENDER_H
#define KODAWARI_SHADERS_SHARED_RENDER_H

#include "glsl_types.h"

// RenderVertex.normal.w: how the vertex shader treats the position.
#define KW_RENDER_WORLD 0.0f  // world space, transformed by RenderPush.view_proj
#define KW_RENDER_CLIP 1.0f   // already in clip space (the background)

KW_NAMESPACE_BEGIN

// One vertex of a draw list: triangles and lines alike. The draw lists are built on the
// CPU, so every vertex carries its own colour and normal (no indices, no materials).
struct RenderVertex {
    vec4 position;  // xyz: world position (or clip xy with KW_RENDER_CLIP), w: 1
    vec4 color;     // rgb: base colour in [0, 1]; a: 1 = lit by RenderPush.light, 0 = unlit (exact colour)
    vec4 normal;    // xyz: world normal of a lit face (need not be unit), w: KW_RENDER_WORLD or KW_RENDER_CLIP
};

// Per draw: the camera and the light, and for the layers a domain draws from its device
// buffers (engine/render/layer.hpp) what the draw is.
struct RenderPush {
    vec4 view_proj[4];  // columns of projection * view (Vulkan clip space: y down, depth 0..1)
    vec4 light;         // xyz: unit direction towards the light (world), w: ambient fraction
    vec4 eye;           // xyz: camera position (world), w: near plane distance
    vec4 forward;       // xyz: unit view direction, w: world size of a pixel at depth 1 (orthographic: everywhere)
    uvec4 draw;         // xyz: the layer's own (its shared header says); w: the projection
};

// RenderPush.draw.w, for every layer.
#define KW_RENDER_PERSPECTIVE 0u
#define KW_RENDER_ORTHOGRAPHIC 1u

KW_NAMESPACE_END

#endif
