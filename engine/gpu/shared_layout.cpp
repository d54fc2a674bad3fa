// The C++ side of every GPU-shared struct must match GLSL's std430 layout exactly.
// Only vec4/uvec4 members are used, so size = 16 x member count and offsets follow.
#include <cstddef>

#include <shared/birds.h>

namespace kodawari::gpu {

static_assert(sizeof(FlightUniforms) == 80);
static_assert(offsetof(FlightUniforms, physics) == 0 && offsetof(FlightUniforms, climb) == 16 &&
              offsetof(FlightUniforms, blend_rates) == 32 && offsetof(FlightUniforms, rules) == 48 &&
              offsetof(FlightUniforms, bank_limit) == 64);
static_assert(sizeof(RouteHeader) == 48);
static_assert(offsetof(RouteHeader, extent) == 0 && offsetof(RouteHeader, flags) == 16 && offsetof(RouteHeader, info) == 32);
static_assert(sizeof(ArcSample) == 32 && offsetof(ArcSample, next) == 16);
static_assert(sizeof(BirdParams) == 48);
static_assert(offsetof(BirdParams, offset) == 0 && offsetof(BirdParams, motion) == 16 && offsetof(BirdParams, ids) == 32);
static_assert(sizeof(BirdState) == 48);
static_assert(offsetof(BirdState, blend) == 0 && offsetof(BirdState, phase) == 16 && offsetof(BirdState, mode) == 32);
static_assert(sizeof(BirdPose) == 128);
static_assert(offsetof(BirdPose, position) == 0 && offsetof(BirdPose, rotation) == 16);
static_assert(sizeof(BirdPoseGpu) == 64);
static_assert(offsetof(BirdPoseGpu, position) == 0 && offsetof(BirdPoseGpu, body) == 16 && offsetof(BirdPoseGpu, left_arm1) == 32 &&
              offsetof(BirdPoseGpu, left_arm2) == 48);
static_assert(sizeof(BirdDiag) == 64);
static_assert(offsetof(BirdDiag, velocity) == 0 && offsetof(BirdDiag, acceleration) == 16 &&
              offsetof(BirdDiag, angles) == 32 && offsetof(BirdDiag, attitude) == 48);
static_assert(sizeof(BirdPush) == 16);
static_assert(KW_BIRDS_WORKGROUP_SIZE % 32 == 0, "a multiple of common subgroup sizes");

}  // namespace kodawari::gpu
