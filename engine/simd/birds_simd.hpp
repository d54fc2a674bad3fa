#pragma once
// The vectorized bird kernel (SPEC B.2-B.6) and the structure-of-arrays layout it shares
// with the cpu bird backend (backends/simd_birds.cpp).
//
// Layout. Birds are grouped by route into batches of kBatchLanes (16), in world order
// within a route, so that a batch's route (timing, looping, segment count, tables) is
// uniform and one vector instruction advances 16 (AVX-512), 8 (AVX2) or 4 (SSE4) birds.
// A batch's block holds rows of 16 floats: the birds' constants, their state (blend,
// phase, mode, roll) and, for frames simulated without an output, the moving parts' pose (the
// GPU's BirdPoseGpu: position, Body, Head, Tail, LeftArm1, LeftArm2), which still goes to memory, as
// on the GPU. Padding lanes repeat the batch's first bird and are never written out.
//
// Exactness. Everything the flight modes, transitions and the phase depend on, the
// position and the Body rotation are flight.cpp's expressions, operation for operation
// (+, -, *, /, sqrt, floor: correctly rounded on every instruction set, no contraction),
// so those are cpu-reference's bits; the seed's bank rule and the diagnostics' angles
// (atan2, sin, cos of the attitude) come from flight.cpp itself lane by lane
// (scalar_math.hpp). Only the wing rotations use a vector sin and cos of their own (a few
// ulp from the C library's, far inside compare.hpp's 1e-4 rad), without fused
// multiply-add, so that they too are the same bits on every instruction set.

#include <array>
#include <cstddef>
#include <cstdint>

#include <kodawari/shared/birds.h>

#include "simd/isa.hpp"

namespace kodawari::simd {

/// Rows of a batch block.
enum BirdRow : std::uint32_t {
    kBirdOffset = 0,   // BirdParams::offset (xyz: m, w: time offset)
    kBirdMotion = 4,   // BirdParams::motion (speed, frequency, amplitude, initial phase)
    kBirdFlight = 8,   // BirdParams::flight (glide ratio, flap-glide beats and seconds, hover)
    kBirdShape = 12,   // BirdParams::shape.x (body length)
    kBirdBlend = 13,   // BirdState::blend and blend2.xyz: the seven modes' weights
    kBirdAlpha = 20,   // BirdState::blend2.w
    kBirdPhase = 21,   // BirdState::phase.x
    kBirdGlided = 22,  // BirdState::phase.y
    kBirdBeats = 23,   // BirdState::phase.z
    kBirdMode = 24,    // BirdState::mode.x as a float; -1 = KW_MODE_UNSET
    kBirdRoll = 25,    // BirdState::roll.xyz: the roll filter (filtered bank quaternion w, z; lateral acceleration)
    kBirdPose = 28,    // BirdPoseGpu (24 floats): the last frame without an output
    kBirdRows = 52,
};

/// A batch of up to kBatchLanes birds on one route.
struct BirdBatch {
    std::uint32_t route = 0;
    std::uint32_t count = 0;                       // valid lanes
    std::array<std::uint32_t, kBatchLanes> bird{};  // bird index per lane (padding: lane 0's)
};

/// What one simulate() call reads and writes.
struct BirdStepArgs {
    gpu::FlightUniforms uniforms{};
    const gpu::RouteHeader* routes = nullptr;
    const gpu::vec4* control_points = nullptr;
    const gpu::ArcSample* arc_samples = nullptr;
    const BirdBatch* batches = nullptr;
    float* storage = nullptr;        // kBirdRows x kBatchLanes floats per batch
    gpu::BirdPose* poses = nullptr;  // frames x birds, frame-major, or null
    gpu::BirdDiag* diag = nullptr;   // likewise
    // Driven birds (BirdWorld::driven, a route's birds all are or none is): their motion,
    // frames x driven, and every bird's params (ids.z: the slot).
    const gpu::BirdParams* params = nullptr;
    const gpu::BirdMotionGpu* motion = nullptr;
    std::uint32_t driven = 0;
    std::size_t birds = 0;
    std::uint32_t first_frame = 0, frames = 0;
};

/// Simulates `frames` frames of batches [begin, end).
using BirdStepFn = void (*)(const BirdStepArgs& args, std::size_t begin, std::size_t end);

struct BirdKernels {
    BirdStepFn simulate = nullptr;
};

/// The kernels of a Highway target (isa.hpp).
[[nodiscard]] BirdKernels bird_kernels(std::int64_t target);

}  // namespace kodawari::simd
