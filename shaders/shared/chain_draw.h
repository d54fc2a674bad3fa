// The chain domain's render layers (engine/domains/chain_layers.cpp): chains and colliders
// drawn from rod state in device buffers.
// Shared by GLSL and C++ (static_asserts in engine/gpu/shared_layout.cpp).
#ifndef KODAWARI_SHADERS_SHARED_CHAIN_DRAW_H
#define KODAWARI_SHADERS_SHARED_CHAIN_DRAW_H

#include "glsl_types.h"
#include "render.h"

KW_NAMESPACE_BEGIN

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

KW_NAMESPACE_END

#endif
