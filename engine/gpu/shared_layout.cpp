// The C++ side of every GPU-shared struct must match GLSL's std430 layout exactly.
// (The domains' own constants that must match these are checked where the domain is:
// e.g. KW_RODS_MAX_JOINTS in vulkan_backends/vulkan_rods.cpp.)
// Only vec4/uvec4 members are used, so size = 16 x member count and offsets follow.
#include <cstddef>
#include <cstdint>

#include <kodawari/shared/bird_draw.h>
#include <kodawari/shared/birds.h>
#include <kodawari/shared/chain_draw.h>
#include <kodawari/shared/flocking.h>
#include <kodawari/shared/poses.h>
#include <kodawari/shared/render.h>
#include <kodawari/shared/rod_inputs.h>
#include <kodawari/shared/rod_keys.h>
#include <kodawari/shared/rods.h>
#include <kodawari/shared/skin.h>


namespace kodawari::gpu {

static_assert(sizeof(FlightUniforms) == 96);
static_assert(offsetof(FlightUniforms, physics) == 0 && offsetof(FlightUniforms, climb) == 16 &&
              offsetof(FlightUniforms, blend_rates) == 32 && offsetof(FlightUniforms, rules) == 48 &&
              offsetof(FlightUniforms, bank_limit) == 64 && offsetof(FlightUniforms, blend_rates2) == 80);
static_assert(sizeof(RouteHeader) == 64);
static_assert(offsetof(RouteHeader, extent) == 0 && offsetof(RouteHeader, flags) == 16 && offsetof(RouteHeader, info) == 32 &&
              offsetof(RouteHeader, perch) == 48);
static_assert(sizeof(ArcSample) == 32 && offsetof(ArcSample, next) == 16);
static_assert(sizeof(BirdParams) == 80);
static_assert(offsetof(BirdParams, offset) == 0 && offsetof(BirdParams, motion) == 16 && offsetof(BirdParams, ids) == 32 &&
              offsetof(BirdParams, flight) == 48 && offsetof(BirdParams, shape) == 64);
static_assert(sizeof(BirdState) == 80);
static_assert(offsetof(BirdState, blend) == 0 && offsetof(BirdState, blend2) == 16 && offsetof(BirdState, phase) == 32 &&
              offsetof(BirdState, mode) == 48 && offsetof(BirdState, roll) == 64);
static_assert(sizeof(BirdPose) == 128);
static_assert(offsetof(BirdPose, position) == 0 && offsetof(BirdPose, rotation) == 16);
static_assert(sizeof(BirdPoseGpu) == 96);
static_assert(offsetof(BirdPoseGpu, position) == 0 && offsetof(BirdPoseGpu, body) == 16 && offsetof(BirdPoseGpu, head) == 32 &&
              offsetof(BirdPoseGpu, tail) == 48 && offsetof(BirdPoseGpu, left_arm1) == 64 && offsetof(BirdPoseGpu, left_arm2) == 80);
static_assert(sizeof(BirdDiag) == 80);
static_assert(offsetof(BirdDiag, velocity) == 0 && offsetof(BirdDiag, acceleration) == 16 &&
              offsetof(BirdDiag, angles) == 32 && offsetof(BirdDiag, attitude) == 48 && offsetof(BirdDiag, flight) == 64);
static_assert(sizeof(BirdPush) == 16);
static_assert(KW_BIRDS_WORKGROUP_SIZE % 32 == 0, "a multiple of common subgroup sizes");

// shared/rods.h
static_assert(sizeof(RodTemplateGpu) == 16 * (9 + KW_RODS_MAX_VIEWS));
static_assert(offsetof(RodTemplateGpu, counts) == 0 && offsetof(RodTemplateGpu, solver) == 16 &&
              offsetof(RodTemplateGpu, step) == 32 && offsetof(RodTemplateGpu, physics) == 48 &&
              offsetof(RodTemplateGpu, accel) == 64 && offsetof(RodTemplateGpu, first_dir) == 80 &&
              offsetof(RodTemplateGpu, drag) == 96 && offsetof(RodTemplateGpu, reduced_step) == 112 &&
              offsetof(RodTemplateGpu, reduced_solver) == 128 && offsetof(RodTemplateGpu, views) == 144);
static_assert(sizeof(RodWindGpu) == 48 && offsetof(RodWindGpu, scales) == 16 && offsetof(RodWindGpu, seed) == 32);
static_assert(sizeof(RodTemplateJointGpu) == 64 && offsetof(RodTemplateJointGpu, lengths) == 16 &&
              offsetof(RodTemplateJointGpu, limit_trig) == 32 && offsetof(RodTemplateJointGpu, limit_frame) == 48);
static_assert(sizeof(RodShapeJointGpu) == 32 && offsetof(RodShapeJointGpu, orientation) == 16);
static_assert(sizeof(RodChainGpu) == 32 && offsetof(RodChainGpu, joints) == 16);
static_assert(sizeof(RodTransformGpu) == 32 && offsetof(RodTransformGpu, rotation) == 16);
static_assert(sizeof(RodColliderGpu) == 32 && offsetof(RodColliderGpu, b) == 16);
static_assert(sizeof(RodJointMotionGpu) == 32 && offsetof(RodJointMotionGpu, v) == 16);
static_assert(sizeof(RodJointSpinGpu) == 32 && offsetof(RodJointSpinGpu, omega) == 16);
static_assert(sizeof(RodChainStateGpu) == 80);
static_assert(offsetof(RodChainStateGpu, root) == 0 && offsetof(RodChainStateGpu, view) == 32 &&
              offsetof(RodChainStateGpu, weights) == 48);
static_assert(sizeof(RodPush) == 128 && offsetof(RodPush, group) == 16 && offsetof(RodPush, camera_position) == 32 &&
              offsetof(RodPush, camera_forward) == 48 && offsetof(RodPush, flags) == 64 && offsetof(RodPush, time) == 80 &&
              offsetof(RodPush, camera_right) == 96 && offsetof(RodPush, camera_up) == 112);
static_assert(sizeof(RodPush) <= 128, "Vulkan guarantees 128 bytes of push constants");
static_assert(KW_RODS_WORKGROUP_SIZE % 32 == 0, "a multiple of common subgroup sizes");

// shared/rod_keys.h
static_assert(sizeof(RodKeyTemplateGpu) == 16 * (1 + 3 * KW_ROD_KEYS_MAX_EXAMPLES + KW_ROD_KEYS_MAX_EXAMPLES * KW_ROD_KEYS_MAX_SOURCES));
static_assert(offsetof(RodKeyTemplateGpu, counts) == 0 && offsetof(RodKeyTemplateGpu, examples) == 16 &&
              offsetof(RodKeyTemplateGpu, keys) == 16 + 16 * KW_ROD_KEYS_MAX_EXAMPLES &&
              offsetof(RodKeyTemplateGpu, smoothing) == 16 + 32 * KW_ROD_KEYS_MAX_EXAMPLES &&
              offsetof(RodKeyTemplateGpu, rotations) == 16 + 48 * KW_ROD_KEYS_MAX_EXAMPLES);
static_assert(sizeof(RodKeyChainGpu) == 16);
static_assert(sizeof(RodKeyStateGpu) == 16 * (3 * KW_ROD_KEYS_MAX_SOURCES + KW_ROD_KEYS_MAX_EXAMPLES));
static_assert(offsetof(RodKeyStateGpu, position) == 0 && offsetof(RodKeyStateGpu, rotation) == 16 * KW_ROD_KEYS_MAX_SOURCES &&
              offsetof(RodKeyStateGpu, velocity) == 32 * KW_ROD_KEYS_MAX_SOURCES &&
              offsetof(RodKeyStateGpu, smoothed) == 48 * KW_ROD_KEYS_MAX_SOURCES);
static_assert(sizeof(RodKeyPush) == 96 && offsetof(RodKeyPush, frame) == 16 && offsetof(RodKeyPush, camera_up) == 80);
static_assert(KW_ROD_KEYS_WORKGROUP_SIZE % 32 == 0, "a multiple of common subgroup sizes");

// shared/poses.h
static_assert(sizeof(PoseNodeGpu) == 80 && offsetof(PoseNodeGpu, relative) == 16);
static_assert(sizeof(PoseAnchorGpu) == 128 && offsetof(PoseAnchorGpu, rest) == 16 && offsetof(PoseAnchorGpu, link) == 64);
static_assert(KW_POSES_UNIFORM_NODES * sizeof(PoseNodeGpu) <= 16384, "the uniform buffer range every Vulkan device allows");
static_assert(sizeof(PoseClipGpu) == 32 && offsetof(PoseClipGpu, range) == 16);
static_assert(sizeof(PoseChannelGpu) == 32 && offsetof(PoseChannelGpu, keys) == 16);
static_assert(sizeof(PoseInstanceGpu) == 96);
static_assert(offsetof(PoseInstanceGpu, placement) == 0 && offsetof(PoseInstanceGpu, timing) == 64 &&
              offsetof(PoseInstanceGpu, clip) == 80);
static_assert(sizeof(PoseMatrixGpu) == 64 && alignof(PoseMatrixGpu) == 16);
static_assert(sizeof(PosePush) == 32 && offsetof(PosePush, counts) == 16);
static_assert(KW_POSES_WORKGROUP_SIZE % 32 == 0, "a multiple of common subgroup sizes");

// shared/render.h: the vertex layout is also the vertex input state (engine/render/).
static_assert(sizeof(RenderVertex) == 48);
static_assert(offsetof(RenderVertex, position) == 0 && offsetof(RenderVertex, color) == 16 &&
              offsetof(RenderVertex, normal) == 32);
static_assert(sizeof(RenderPush) == 128 && offsetof(RenderPush, light) == 64 && offsetof(RenderPush, eye) == 80 &&
              offsetof(RenderPush, forward) == 96 && offsetof(RenderPush, draw) == 112);
static_assert(sizeof(ChainDrawInfo) == 32 && offsetof(ChainDrawInfo, size) == 16);
static_assert(sizeof(BirdDrawVertex) == 32 && offsetof(BirdDrawVertex, normal) == 16);
static_assert(sizeof(BirdDrawType) == 128 && offsetof(BirdDrawType, color) == 112);
static_assert(KW_CHAIN_DOT_VERTICES == 3 * KW_CHAIN_DOT_SIDES);
static_assert(KW_PART_COUNT == 7, "BirdDrawType::parts has one entry per bird part");
static_assert(KW_COLLIDER_VERTICES == (2 * KW_COLLIDER_RINGS + 1) * KW_COLLIDER_SIDES * 6);
static_assert(sizeof(RodInputInstanceGpu) == 32 && offsetof(RodInputInstanceGpu, more) == 16);
static_assert(sizeof(RodInputAttachmentGpu) == 48 && offsetof(RodInputAttachmentGpu, a) == 16 &&
              offsetof(RodInputAttachmentGpu, b) == 32);
static_assert(sizeof(RodInputPush) == 32 && offsetof(RodInputPush, more) == 16);
static_assert(sizeof(RenderPush) <= 128, "Vulkan guarantees 128 bytes of push constants");

// shared/flocking.h and the driven birds' motion (shared/birds.h)
static_assert(sizeof(BirdMotionGpu) == 48 && offsetof(BirdMotionGpu, velocity) == 16 && offsetof(BirdMotionGpu, acceleration) == 32);
static_assert(sizeof(FlockParamsGpu) == 96 && offsetof(FlockParamsGpu, radii) == 16 && offsetof(FlockParamsGpu, weights) == 32 &&
              offsetof(FlockParamsGpu, ground) == 48 && offsetof(FlockParamsGpu, target) == 64 && offsetof(FlockParamsGpu, collision) == 80);
static_assert(sizeof(FlockBirdGpu) == 64 && offsetof(FlockBirdGpu, offset) == 16 && offsetof(FlockBirdGpu, speed) == 32 &&
              offsetof(FlockBirdGpu, turn) == 48);
static_assert(sizeof(FlockPerchGpu) == 32 && offsetof(FlockPerchGpu, land_velocity) == 16);
static_assert(sizeof(FlockStateGpu) == 32 && offsetof(FlockStateGpu, velocity) == 16);
static_assert(sizeof(FlockAgentGpu) == 48 && offsetof(FlockAgentGpu, kind_weight) == 16 && offsetof(FlockAgentGpu, velocity) == 32);
static_assert(sizeof(FlockPush) == 64 && offsetof(FlockPush, slots) == 16 && offsetof(FlockPush, bases) == 32 &&
              offsetof(FlockPush, step) == 48);
static_assert(KW_FLOCK_WORKGROUP_SIZE % 32 == 0 && KW_FLOCK_SCAN_SIZE % 32 == 0, "multiples of common subgroup sizes");

// shared/skin.h
static_assert(sizeof(SkinNodeGpu) == 48 && offsetof(SkinNodeGpu, joint) == 16 && offsetof(SkinNodeGpu, axis) == 32);
static_assert(sizeof(SkinChainGpu) == 16);
static_assert(sizeof(SkinPush) == 16);
static_assert(sizeof(SkinJointGpu) == 80 && offsetof(SkinJointGpu, inverse_bind) == 16);
static_assert(sizeof(SkinnedVertexGpu) == 64 && offsetof(SkinnedVertexGpu, joints) == 16 &&
              offsetof(SkinnedVertexGpu, weights) == 32 && offsetof(SkinnedVertexGpu, color) == 48);
static_assert(KW_SKIN_WORKGROUP_SIZE % 32 == 0, "a multiple of common subgroup sizes");

}  // namespace kodawari::gpu
