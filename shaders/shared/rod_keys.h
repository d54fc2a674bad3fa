// GPU-shared data of the key kernel (shaders/rod_keys.comp, docs/keyed-examples.md K.2,
// K.3): per chain with keyed examples, this frame's key sources (RodFrame::keys) and its
// key state in, its raw keyed weights u_1 .. u_4 out, which shaders/rods_step.comp
// combines with the view weights (K.4) at binding KW_RODS_BINDING_KEYED. Defined once
// for the kernel and the C++ backend (engine/vulkan_backends/vulkan_rods.cpp). Layout: std430,
// only vec4/uvec4 members (see glsl_types.h); sizes and offsets are checked in
// engine/gpu/shared_layout.cpp.
//
// Why a kernel of its own rather than more of rods_step.comp: the key state is per chain
// and small (one load, one store, as PERF-NOTES asks), and only chains with keyed examples
// need it, so a separate dispatch over just those chains (listed densely) costs the rest
// of the world nothing, while rods_step reads one vec4 per chain, and only in the
// variants specialized for keyed templates (KW_RODS_SPEC_MAX_KEYED > 0).
#ifndef KODAWARI_SHADERS_SHARED_ROD_KEYS_H
#define KODAWARI_SHADERS_SHARED_ROD_KEYS_H

#include "glsl_types.h"

#define KW_ROD_KEYS_WORKGROUP_SIZE 64
#define KW_ROD_KEYS_MAX_SOURCES 4   // rods::kMaxKeySources
#define KW_ROD_KEYS_MAX_EXAMPLES 4  // rods::kMaxKeyedExamples

#define KW_ROD_KEYS_BINDING_TEMPLATES 0  // RodKeyTemplateGpu, per chain template (templates without keyed examples too)
#define KW_ROD_KEYS_BINDING_CHAINS 1     // RodKeyChainGpu, per chain with keyed examples
#define KW_ROD_KEYS_BINDING_KEYS 2       // RodTransformGpu (shared/rods.h), per key source: RodFrame::keys (this frame)
#define KW_ROD_KEYS_BINDING_STATE 3      // RodKeyStateGpu, per chain with keyed examples (state)
#define KW_ROD_KEYS_BINDING_WEIGHTS 4    // vec4 per chain of the world: u_1 .. u_4 (the rods kernel's KW_RODS_BINDING_KEYED)
#define KW_ROD_KEYS_BINDING_REFERENCE 5  // RodTransformGpu per character (the rods kernel's KW_RODS_BINDING_REFERENCE)
#define KW_ROD_KEYS_BINDING_CHAIN_STATE 6  // RodChainStateGpu per chain (the rods kernel's KW_RODS_BINDING_CHAIN_STATE), read
#define KW_ROD_KEYS_BINDING_COUNT 7
// RodKeyChainGpu.ids.w of a chain with a center frame: it steps every frame (no level read).
#define KW_ROD_KEYS_EVERY_FRAME 0xFFFFFFFFu

// rods::KeyKind, rods::MotionMeasure, rods::MotionFrame (checked in vulkan_rods.cpp).
#define KW_ROD_KEYS_KIND_MOTION 0u
#define KW_ROD_KEYS_KIND_POSE 1u
#define KW_ROD_KEYS_MEASURE_SPEED 0u
#define KW_ROD_KEYS_MEASURE_ACCELERATION 1u
#define KW_ROD_KEYS_MEASURE_ANGULAR_SPEED 2u
#define KW_ROD_KEYS_FRAME_MAGNITUDE 0u
#define KW_ROD_KEYS_FRAME_JOINT 1u

KW_NAMESPACE_BEGIN

// A chain template's keyed examples (rods::ChainTemplate::key_sources, keyed). The
// smoothing factor alpha is computed on the host for each frame length, with the CPU
// reference's expression, so both sides smooth with the same bits (as set_step does for
// the solver's step sizes).
struct RodKeyTemplateGpu {
    uvec4 counts;  // x: key sources S, y: keyed examples J, z: bit s set for every Motion source s, w: the teleport distance's float bits (m)
    uvec4 examples[KW_ROD_KEYS_MAX_EXAMPLES];  // x: KW_ROD_KEYS_KIND_*, y: motion: source, pose: source mask,
                                               // z: KW_ROD_KEYS_MEASURE_*, w: KW_ROD_KEYS_FRAME_*
    vec4 keys[KW_ROD_KEYS_MAX_EXAMPLES];       // xyz: motion key kappa_j, w: influence sigma_j
    vec4 smoothing[KW_ROD_KEYS_MAX_EXAMPLES];  // x: tau_j (s), y: saturation kappa_max (K.2; +inf unless magnitude),
                                               // z: alpha_j this frame (1 - exp(-dt / tau_j), 1 for tau_j = 0), w: unused
    vec4 rotations[KW_ROD_KEYS_MAX_EXAMPLES * KW_ROD_KEYS_MAX_SOURCES];  // pose: [j * 4 + s] kappa_{j,s} (quaternion)
};

// A chain with keyed examples.
struct RodKeyChainGpu {
    uvec4 ids;  // x: template, y: the chain's index in the per-chain buffers, z: its first key source,
                // w: its character (the reference joint's index), KW_ROD_KEYS_EVERY_FRAME for a chain with a center
};

// rods::KeyState of one chain.
struct RodKeyStateGpu {
    vec4 position[KW_ROD_KEYS_MAX_SOURCES];  // xyz: last frame's position p'_s, w: 1 once a velocity exists (has_velocity)
    vec4 rotation[KW_ROD_KEYS_MAX_SOURCES];  // last frame's rotation q'_s
    vec4 velocity[KW_ROD_KEYS_MAX_SOURCES];  // xyz: last frame's velocity v'_s (m/s, world), w: unused
    vec4 smoothed[KW_ROD_KEYS_MAX_EXAMPLES]; // xyz: m_j, the smoothed read key (K.2), w: unused
};

// A chain that keeps its state this frame (the posed and hidden levels' rate,
// shaders/lib/rod_lod.glsl rod_rests) is not measured: its next step measures over the
// frames it kept. The level is decided as rods_step.comp decides it, from the same push
// values (RodPush's camera and LOD fields).
struct RodKeyPush {
    uvec4 counts;          // x: chains with keyed examples, y: 1 = levels of detail (KW_RODS_STEP_LOD),
                           // z: the rate (RodPush.flags.w), w: unused
    vec4 frame;            // x: dt (s), y: LOD margin, z: LOD full distance, w: LOD stay distance (m)
    vec4 camera_position;  // xyz, w: LOD reduced distance (m)
    vec4 camera_forward;   // xyz, w: LOD reduced stay distance (m)
    vec4 camera_right;     // xyz, w: tan of half the horizontal field of view
    vec4 camera_up;        // xyz, w: tan of half the vertical field of view
};

KW_NAMESPACE_END

#endif
