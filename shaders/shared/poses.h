// GPU-shared data of the pose kernel (glTF animation of crowds): every struct, binding
// index and the workgroup size, defined once for shaders/pose_eval.comp and the C++
// backend (engine/backends/vulkan_poses.cpp). Layout: std430, only vec4/uvec4 members
// (see glsl_types.h); sizes and offsets are checked in engine/gpu/shared_layout.cpp.
//
// Why this layout. One invocation evaluates one whole instance: it walks the character's
// nodes parents first, samples the clip's channels of each node and writes the node's
// world matrix, re-reading its parent's from the output it wrote itself. The character
// is flattened once at load: nodes in parents-first order (Character::order), and per
// clip its channels sorted by that order, so the invocation consumes them with one
// cursor as it walks (no per-node channel table of clips x nodes). Key times are plain
// floats (the binary search touches a few of them), key values vec4s (lavapipe executes
// each storage access lane by lane, shared/PERF-NOTES.md: one vec4 costs what one float
// does). Everything but the output is written at load; evaluate() pushes only the time.
// Quaternions are vec4(x, y, z, w); matrices are four column vec4s, like glm::mat4.
#ifndef KODAWARI_SHADERS_SHARED_POSES_H
#define KODAWARI_SHADERS_SHARED_POSES_H

#include "glsl_types.h"

#define KW_POSES_WORKGROUP_SIZE 64

#define KW_POSES_BINDING_NODES 0      // PoseNodeGpu, per node, parents first
#define KW_POSES_BINDING_CLIPS 1      // PoseClipGpu, per animation
#define KW_POSES_BINDING_CHANNELS 2   // PoseChannelGpu, per channel, each clip's sorted by node position
#define KW_POSES_BINDING_TIMES 3      // float, key times of every channel
#define KW_POSES_BINDING_VALUES 4     // vec4, key values of every channel (CUBICSPLINE: in-tangent, value, out-tangent per key)
#define KW_POSES_BINDING_INSTANCES 5  // PoseInstanceGpu, per instance
#define KW_POSES_BINDING_WORLD 6      // PoseMatrixGpu, instances x nodes, instance-major, node index of Character::nodes
#define KW_POSES_BINDING_COUNT 7

#define KW_POSES_NONE 0xFFFFFFFFu     // no parent; no clip (rest pose)

#define KW_POSES_NODE_TRS 0u          // local = T * R * S from the rest TRS and the channels
#define KW_POSES_NODE_MATRIX 1u       // local = the node's matrix (never animated, §3.5.3)

#define KW_POSES_PATH_TRANSLATION 0u  // gltf::Path
#define KW_POSES_PATH_ROTATION 1u
#define KW_POSES_PATH_SCALE 2u

#define KW_POSES_INTERP_LINEAR 0u     // gltf::Interpolation
#define KW_POSES_INTERP_STEP 1u
#define KW_POSES_INTERP_CUBICSPLINE 2u

KW_NAMESPACE_BEGIN

// One node, at its position in the parents-first order.
struct PoseNodeGpu {
    uvec4 ids;       // x: node index (Character::nodes), y: parent's node index or KW_POSES_NONE,
                     // z: KW_POSES_NODE_*, w: unused
    vec4 local[4];   // TRS: [0] translation (xyz), [1] rotation, [2] scale (xyz), [3] unused;
                     // MATRIX: the columns of the node's matrix
};

struct PoseClipGpu {
    uvec4 channels;  // x: first PoseChannelGpu, y: channel count, z, w: unused
    vec4 range;      // x: start, y: end (s, the earliest and latest key), z, w: unused
};

// One channel: what it animates (`target`, loaded for every node the walk passes while
// the channel is next) and where its keys are (`keys`, loaded when it is sampled).
struct PoseChannelGpu {
    uvec4 target;    // x: node position in the parents-first order, y: KW_POSES_PATH_*,
                     // z: KW_POSES_INTERP_*, w: key count (>= 1)
    uvec4 keys;      // x: first key time (index into times), y: first key value (index into values), z, w: unused
};

struct PoseInstanceGpu {
    vec4 placement[4];  // columns of placement_matrix(placement)
    vec4 timing;        // x: time offset (s), y, z, w: unused
    uvec4 clip;         // x: animation index or KW_POSES_NONE, y: 1 = loop, z, w: unused
};

struct PoseMatrixGpu {
    vec4 columns[4];
};

struct PosePush {
    vec4 time;       // x: scene time (s), y, z, w: unused
    uvec4 counts;    // x: instance count, y: node count, z, w: unused
};

KW_NAMESPACE_END

#endif
