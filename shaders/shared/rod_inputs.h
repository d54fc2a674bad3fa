// GPU-shared data of the rod-input kernel (shaders/rod_inputs.comp): the kinematic input of
// the rod kernel (shared/rods.h: reference joints, chain roots, colliders; shared/rod_keys.h:
// the key sources of keyed examples, docs/keyed-examples.md K.1) written on the
// device from a pose backend's world matrices (shared/poses.h), so that a crowd of rigged
// characters animated on the GPU feeds its chains without its poses coming back to the
// host (CrowdAnimator::write_inputs_on, engine/vulkan_backends/crowd_animator.cpp). Layout:
// std430, only vec4/uvec4 members (see glsl_types.h); sizes and offsets are checked in
// engine/gpu/shared_layout.cpp.
#ifndef KODAWARI_SHADERS_SHARED_ROD_INPUTS_H
#define KODAWARI_SHADERS_SHARED_ROD_INPUTS_H

#include "glsl_types.h"

#define KW_ROD_INPUTS_WORKGROUP_SIZE 64

#define KW_ROD_INPUTS_BINDING_WORLD 0        // PoseMatrixGpu: the pose backend's, instances x nodes
#define KW_ROD_INPUTS_BINDING_INSTANCES 1    // RodInputInstanceGpu, per posed instance
#define KW_ROD_INPUTS_BINDING_ATTACHMENTS 2  // RodInputAttachmentGpu: the character's chain roots, then its colliders
#define KW_ROD_INPUTS_BINDING_REFERENCE 3    // RodTransformGpu, per character instance: the rod backend's
#define KW_ROD_INPUTS_BINDING_ROOTS 4        // RodTransformGpu, per chain: the rod backend's
#define KW_ROD_INPUTS_BINDING_COLLIDERS 5    // RodColliderGpu: the rod backend's
#define KW_ROD_INPUTS_BINDING_KEYS 6         // RodTransformGpu, per key source: the rod backend's (RodFrame::keys)
#define KW_ROD_INPUTS_BINDING_CENTERS 7      // RodTransformGpu, per center frame: the rod backend's (RodFrame::centers)
#define KW_ROD_INPUTS_BINDING_COUNT 8

// RodInputAttachmentGpu.node.y of a pose key source measured against the world (KeyJoint::parent -1).
#define KW_ROD_INPUTS_NO_PARENT 0xFFFFFFFFu

KW_NAMESPACE_BEGIN

// Where one posed instance's input goes in the rod world.
struct RodInputInstanceGpu {
    uvec4 ids;  // x: its RodScene instance (its reference joint's entry), y: its first chain, z: its first collider,
                // w: its first key source (its chains' key sources are consecutive, chain by chain)
    uvec4 more; // x: its first center frame (its chains' centers are consecutive, chain by chain), yzw: unused
};

// A node the rod input comes from: a chain's root joint, a collider's joint with the
// collider in that joint's frame, a key source's joint (K.1), or a chain's center node.
struct RodInputAttachmentGpu {
    uvec4 node;  // x: the node (Character::nodes index); key source: y: the pose source's parent node
                 // (KW_ROD_INPUTS_NO_PARENT: the world), z: rods::KeySourceKind; w: unused
    vec4 a;      // collider: xyz end a in the joint's frame (m), w: radius (m)
    vec4 b;      // collider: xyz end b, w: its kind (KW_RODS_COLLIDER_*)
};

struct RodInputPush {
    uvec4 counts;  // x: posed instances, y: nodes per instance, z: the reference node, w: chains per instance
    uvec4 more;    // x: colliders per instance, y: key sources per instance (after the colliders' attachments),
                   // z: center frames per instance (after the key sources' attachments), w: unused
};

KW_NAMESPACE_END

#endif
