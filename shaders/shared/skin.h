// GPU-shared data of the skinned-mesh layer (engine/render/skinned_layer.cpp): the
// kernel that composes rigged characters' node matrices from the pose and rod backends'
// buffers (shaders/skin_nodes.comp) and the vertex shader that skins their meshes with
// them (shaders/skinned.vert). Every struct, binding index and the workgroup size are
// defined once here; std430, only vec4/uvec4 members (see glsl_types.h); sizes and
// offsets are checked in engine/gpu/shared_layout.cpp.
//
// Why this layout. One invocation composes one whole instance, as pose_eval.comp does:
// it walks the character's nodes parents first and re-reads a parent's matrix from the
// output it wrote itself. What it composes is RodScene::rigged_world(): the clip's pose
// with the simulated chain joints put in from the rod state and their descendants
// composed below them. The clip's local transforms are not on the device, only its world
// matrices (the pose backend's, placement included), so a node below a simulated joint
// takes local = inverse(clip world(parent)) * clip world(node); a node with nothing
// simulated above it keeps the clip's world as it is. The output (node world matrices,
// instances x nodes) has the layout the host path uploads (rigged_world's matrices), so
// one vertex shader draws both. Matrices are four column vec4s, like glm::mat4 and
// PoseMatrixGpu; quaternions vec4(x, y, z, w).
#ifndef KODAWARI_SHADERS_SHARED_SKIN_H
#define KODAWARI_SHADERS_SHARED_SKIN_H

#include "glsl_types.h"

#define KW_SKIN_WORKGROUP_SIZE 64

// skin_nodes.comp
#define KW_SKIN_BINDING_NODES 0         // SkinNodeGpu, per node, parents first (static)
#define KW_SKIN_BINDING_CHAINS 1        // SkinChainGpu, instances x the character's chains (static)
#define KW_SKIN_BINDING_CLIP_WORLD 2    // PoseMatrixGpu, the pose backend's world (instances x nodes)
#define KW_SKIN_BINDING_CHAIN_STATES 3  // RodChainStateGpu, the rod backend's, per chain of the world
#define KW_SKIN_BINDING_MOTION 4        // RodJointMotionGpu, the rod backend's, per joint of the world
#define KW_SKIN_BINDING_SPIN 5          // RodJointSpinGpu, the rod backend's, per joint of the world
#define KW_SKIN_BINDING_WORLD 6         // PoseMatrixGpu, the output: node world matrices (instances x nodes)
#define KW_SKIN_BINDING_COUNT 7

#define KW_SKIN_NONE 0xFFFFFFFFu  // no parent

// SkinNodeGpu.ids.z: how the node's world matrix is made.
#define KW_SKIN_NODE_CLIP 0u       // nothing above it is simulated: the clip's world
#define KW_SKIN_NODE_BELOW 1u      // below a simulated joint: world(parent) * the clip's local
#define KW_SKIN_NODE_SIMULATED 2u  // a simulated chain joint (joint index >= 1)

// skinned.vert
#define KW_SKINNED_BINDING_JOINTS 0  // SkinJointGpu, every skin's joints of the character (static)
#define KW_SKINNED_BINDING_WORLD 1   // PoseMatrixGpu, node world matrices (instances x nodes)
#define KW_SKINNED_BINDING_COUNT 2
// RenderPush.draw for skinned meshes: x: the character's node count (the stride of the
// world matrices per instance), y, z: unused.

KW_NAMESPACE_BEGIN

// One node, at its position in the parents-first order (Character::order).
struct SkinNodeGpu {
    uvec4 ids;    // x: node index (Character::nodes), y: parent's node index or KW_SKIN_NONE,
                  // z: KW_SKIN_NODE_*, w: SIMULATED: the character's chain (chain_nodes index)
    uvec4 joint;  // SIMULATED: x: the joint's index in its chain, y: the chain's joint count, z, w: unused
    vec4 axis;    // SIMULATED: xyz: the bone axis u_i (Chain::bone_axis, the joint's frame), w: unused
};

// A chain of an instance: where its state is in the rod backend's buffers.
struct SkinChainGpu {
    uvec4 ids;  // x: the chain in RodWorld::chains (RodChainStateGpu index), y: its first joint
                // (ChainInstance::joint_begin), z, w: unused
};

struct SkinPush {
    uvec4 counts;  // x: instance count, y: node count, z: chains per instance, w: unused
};

// One joint of a skin (glTF §3.7.3): a vertex's JOINTS_0 entry k of skin s is entry
// first(s) + k of the character's table.
struct SkinJointGpu {
    uvec4 ids;                // x: the joint's node index, y, z, w: unused
    vec4 inverse_bind[4];     // columns of its inverse bind matrix
};

// One vertex of a character's meshes (drawn indexed: the fragment shader finds each
// face's normal itself); attributes are floats (GraphicsPipeline).
struct SkinnedVertexGpu {
    vec4 position;  // xyz: the bind-pose position (mesh space), w: the mesh's node index
    vec4 joints;    // four SkinJointGpu indices (exact integers as floats)
    vec4 weights;   // their weights; 0 where unused or invalid; all 0: not skinned (follows its node)
    vec4 color;     // rgb: the material's base colour, a: unused
};

KW_NAMESPACE_END

#endif
