// GPU-shared data of the pose kernel (glTF animation of crowds): every struct, binding
// index and the workgroup size, defined once for shaders/pose_eval.comp and the C++
// backend (engine/vulkan_backends/vulkan_poses.cpp). Layout: std430 (the node records also as a
// std140 uniform block, the same bytes for vec4-only structs), only vec4/uvec4 members
// (see glsl_types.h); sizes and offsets are checked in engine/gpu/shared_layout.cpp.
//
// Why this layout. One invocation evaluates one whole instance. Most of a character
// never moves relative to its nearest animated ancestor (the chibi: 40 hair nodes under
// the head), so the character is split once at load: its anchors are the nodes that any
// clip animates (parents first), and every node's world matrix is its anchor's times a
// constant, the node's rest transform relative to that anchor (the product of the rest
// local matrices below the anchor, §3.5.3), or relative to the instance's placement when
// no ancestor is animated. Per instance the kernel first poses the few anchors, keeping
// their placed world matrices in a local array (slot 0 is the placement, slot a + 1
// anchor a), then writes every node as slot x constant: one record and no parent
// read-back per node. Each clip's channels are sorted by anchor, so the invocation
// consumes them with one cursor as it walks the anchors. Key times are plain floats (a
// guess from the keys per second, and a binary search where it misses, touch two or a
// few), key values vec4s. On lavapipe every storage-buffer load and store is a loop over
// the lanes with a branch per float (shared/PERF-NOTES.md), so the kernel loads as few
// floats as it can and, for affine characters, stores only the upper three rows of each
// matrix: the output stores are still about 70% of its time (0.56 of 0.74 ms for 1000
// chibi instances). Everything but the output is written at load; evaluate() pushes only
// the time. Quaternions are vec4(x, y, z, w); matrices are four column vec4s, like
// glm::mat4.
//
// On a discrete GPU: the slots (16 floats each, 7 for the chibi) are indexed by a slot
// number read from memory, so the compiler keeps them in per-thread local memory (L1
// cached) rather than registers; the rest needs a few dozen registers, so occupancy is
// not what limits it. Every invocation of a warp reads the same node record at the same
// time, which the uniform buffer serves as one constant-cache broadcast. What bounds it
// is the output, instances x nodes x 64 bytes: instance-major, the lanes of a warp store
// 12- or 16-byte pieces nodes x 64 bytes apart, one cache line per lane and instruction
// (each line is completed by the same lane's next stores, so L2 still writes whole
// lines); a node-major output would coalesce the stores, a change of the consumers'
// layout that lavapipe, which stores lane by lane, would not repay.
#ifndef KODAWARI_SHADERS_SHARED_POSES_H
#define KODAWARI_SHADERS_SHARED_POSES_H

#include "glsl_types.h"

#define KW_POSES_WORKGROUP_SIZE 64

#define KW_POSES_BINDING_NODES 0      // PoseNodeGpu, the first KW_POSES_UNIFORM_NODES nodes (index of Character::nodes), uniform
#define KW_POSES_BINDING_CLIPS 1      // PoseClipGpu, per animation
#define KW_POSES_BINDING_CHANNELS 2   // PoseChannelGpu, per channel, each clip's sorted by anchor
#define KW_POSES_BINDING_TIMES 3      // float, key times of every channel
#define KW_POSES_BINDING_VALUES 4     // vec4, key values of every channel (CUBICSPLINE: in-tangent, value, out-tangent per key)
#define KW_POSES_BINDING_INSTANCES 5  // PoseInstanceGpu, per instance
#define KW_POSES_BINDING_WORLD 6      // PoseMatrixGpu, instances x nodes, instance-major, node index of Character::nodes
#define KW_POSES_BINDING_ANCHORS 7    // PoseAnchorGpu, per anchor, parents first
#define KW_POSES_BINDING_MORE_NODES 8 // PoseNodeGpu, the nodes from KW_POSES_UNIFORM_NODES on
#define KW_POSES_BINDING_COUNT 9

// The node records every invocation reads in the same order sit in a uniform buffer:
// lavapipe reads one for 8 lanes with a plain gather, where a storage buffer costs a loop
// over the lanes with a branch and a bounds check per float (0.90 against 1.06 ms for the
// chibi's 1000 instances). 204 x 80 bytes fit the 16 KiB every Vulkan device allows a
// uniform buffer; a larger character's further nodes come from a storage buffer.
#define KW_POSES_UNIFORM_NODES 204

// Specialization constant: the number of slots (anchors + 1), the size of the kernel's
// array of placed anchor matrices.
#define KW_POSES_SPEC_SLOTS 0
// Specialization constant: 1 when every node's relative transform and anchor link has the
// bottom row (0, 0, 0, 1), as TRS nodes always do: then every output matrix has it too,
// load() writes it once and the kernel stores only the upper three rows.
#define KW_POSES_SPEC_AFFINE 1
// Specialization constant: invocations per workgroup (BackendOptions::workgroup_size).
#define KW_POSES_SPEC_WORKGROUP_SIZE 2
#define KW_POSES_SPEC_COUNT 3

#define KW_POSES_NONE 0xFFFFFFFFu     // no parent; no clip (rest pose)

#define KW_POSES_PATH_TRANSLATION 0u  // animation::Path
#define KW_POSES_PATH_ROTATION 1u
#define KW_POSES_PATH_SCALE 2u

#define KW_POSES_INTERP_LINEAR 0u     // animation::Interpolation
#define KW_POSES_INTERP_STEP 1u
#define KW_POSES_INTERP_CUBICSPLINE 2u

KW_NAMESPACE_BEGIN

// One node: its world matrix is slots[ids.x] * relative.
struct PoseNodeGpu {
    uvec4 ids;            // x: slot of the node's anchor (itself when animated; 0: the placement), y, z, w: unused
    vec4 relative[4];     // columns of the rest transform from that anchor to the node (identity for an anchor)
};

// One anchor, a node that some clip animates (only TRS nodes are, §3.5.3), parents first:
// slots[a + 1] = slots[ids.x] * link * T * R * S.
struct PoseAnchorGpu {
    uvec4 ids;            // x: slot of the parent's anchor (0: the placement), y, z, w: unused
    vec4 rest[3];         // the rest TRS: [0] translation (xyz), [1] rotation, [2] scale (xyz)
    vec4 link[4];         // columns of the rest transform from the parent's anchor to the parent
                          // (identity when the parent is an anchor or there is no parent)
};

struct PoseClipGpu {
    uvec4 channels;  // x: first PoseChannelGpu, y: channel count, z, w: unused
    vec4 range;      // x: start, y: end (s, the earliest and latest key), z, w: unused
};

// One channel: what it animates (`target`, loaded for every anchor the walk passes while
// the channel is next) and where its keys are (`keys`, loaded when it is sampled).
struct PoseChannelGpu {
    uvec4 target;    // x: anchor index, y: KW_POSES_PATH_*,
                     // z: KW_POSES_INTERP_*, w: key count (>= 1)
    uvec4 keys;      // x: first key time (index into times), y: first key value (index into values),
                     // z: float bits of (count - 1) / (last time - first time), 0 for one key; w: unused
};

struct PoseInstanceGpu {
    vec4 placement[4];  // columns of placement_matrix(placement)
    vec4 timing;        // x: time offset (s), y, z, w: unused
    uvec4 clip;         // x: animation index or KW_POSES_NONE, y: 1 = loop, z, w: unused
};

struct PoseMatrixGpu {
    vec4 columns[4];
};

#ifndef __cplusplus
// The kernel's view of one column of a PoseMatrixGpu when it stores only xyz
// (KW_POSES_SPEC_AFFINE): in std430 a vec3 and a float are the same 16 bytes as a vec4.
// GLSL only: C++ sees the columns as PoseMatrixGpu's vec4s.
struct PoseColumnGpu {
    vec3 xyz;
    float w;
};
#endif

struct PosePush {
    vec4 time;       // x: scene time (s), y, z, w: unused
    uvec4 counts;    // x: instance count, y: node count, z: anchor count, w: unused
};

KW_NAMESPACE_END

#endif
