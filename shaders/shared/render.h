// The renderer's vertex layout and push constants (engine/render/, shaders/render.*),
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

// Per draw: the camera and the light, and for the layers drawn from device buffers
// (chains.vert, birds.vert) what the draw is.
struct RenderPush {
    vec4 view_proj[4];  // columns of projection * view (Vulkan clip space: y down, depth 0..1)
    vec4 light;         // xyz: unit direction towards the light (world), w: ambient fraction
    vec4 eye;           // xyz: camera position (world), w: near plane distance
    vec4 forward;       // xyz: unit view direction, w: world size of a pixel at depth 1 (orthographic: everywhere)
    uvec4 draw;         // xyz: layer-specific, see KW_CHAINS_DRAW_* and KW_BIRDS_DRAW_*; w: the projection
};

// RenderPush.draw.w, for every layer.
#define KW_RENDER_PERSPECTIVE 0u
#define KW_RENDER_ORTHOGRAPHIC 1u

// ---------------------------------------------------------------------------------------
// The chain layer (chains.vert): chains drawn from rod state in device buffers, either
// the vulkan rod backend's own (shaders/shared/rods.h) or the same layout uploaded from a
// ChainSnapshot. No vertex buffer: segments are instanced per joint (6 vertices, two
// triangles of a camera-facing ribbon to the next joint, shaded as a tube by lit.frag;
// none after a chain's last joint), dots per joint (KW_CHAIN_DOT_SIDES triangles) when
// asked for.
#define KW_CHAINS_BINDING_INFO 0          // ChainDrawInfo, one per chain (static)
#define KW_CHAINS_BINDING_JOINT_CHAIN 1   // uint per joint: its chain (static)
#define KW_CHAINS_BINDING_CHAIN_STATES 2  // RodChainStateGpu per chain: root.position
#define KW_CHAINS_BINDING_MOTION 3        // RodJointMotionGpu per joint: x (relative to the root)
#define KW_CHAINS_BINDING_COUNT 4
#define KW_CHAIN_SEGMENT_VERTICES 6
#define KW_CHAIN_DOT_SIDES 8
#define KW_CHAIN_DOT_VERTICES 24  // 3 x KW_CHAIN_DOT_SIDES
// RenderPush.draw for chains: x: KW_CHAINS_DRAW_SEGMENTS or _DOTS, y: minimum segment
// width in pixels, z: minimum dot radius in pixels (float bits).
#define KW_CHAINS_DRAW_SEGMENTS 0u
#define KW_CHAINS_DRAW_DOTS 1u
// A tube's width at the chain's last joint, as a fraction of its width at the root.
#define KW_CHAIN_TIP_WIDTH 0.4

struct ChainDrawInfo {
    uvec4 joints;  // x: first joint, y: joint count, z: colour (RGBA8, packUnorm4x8), w: unused
    vec4 size;     // x: thickness (m): tubes 2x as wide at the root (tapering), dots 1.5x as large in radius; yzw: unused
};

// ---------------------------------------------------------------------------------------
// The collider layer (colliders.vert): the colliders of the rod input (RodColliderGpu,
// shared/rods.h), the vulkan rod backend's input buffer or the same layout uploaded from a
// frame, as solid lit capsules (lit.frag): per collider a low-poly capsule of
// KW_COLLIDER_SIDES sides round its axis, each end a hemisphere of KW_COLLIDER_RINGS
// bands, joined by one cylinder band (of no length for a sphere). Instanced per collider,
// no vertex buffer, triangle lists; RenderPush.draw.x: the colour (packUnorm4x8).
#define KW_COLLIDERS_BINDING_COLLIDERS 0
#define KW_COLLIDERS_BINDING_COUNT 1
#define KW_COLLIDER_SIDES 24
#define KW_COLLIDER_RINGS 6
#define KW_COLLIDER_VERTICES 1872  // (2 x KW_COLLIDER_RINGS + 1) bands x KW_COLLIDER_SIDES quads x 6 vertices

// ---------------------------------------------------------------------------------------
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
