#pragma once
// The vectorized pose kernel (glTF clips of a crowd: §3.5.3 Transformations of the glTF
// 2.0.1 specification) and the layout it shares with the cpu pose backend
// (backends/simd_poses.cpp).
//
// Layout. Instances are grouped by clip (the rest pose is a clip of its own) into batches
// of kBatchLanes (16), in instance order within a clip, so that every lane of a batch
// walks the same node hierarchy with the same animated nodes; one vector instruction
// composes a node's matrices for 16 (AVX-512), 8 (AVX2) or 4 (SSE4) instances. A clip's
// plan says which nodes' world matrices are the same for every instance (nothing animated
// on their path from the root: the rest pose's, computed once) and which local matrices
// are (no channel targets the node), so only the rest is composed per lane.
//
// Exactness. The matrix products are glm's (0.9.9, scalar: each column
// ((A0 b0 + A1 b1) + A2 b2) + A3 b3, its literal zeros and ones included), as are
// translate, mat4_cast and scale; the channels' values (animation::sample: the key search and
// the interpolation, in double) and the clip times (clip_time) come from the reference's
// functions lane by lane, a small share of the work. So every matrix is cpu-reference's
// bits, on every instruction set.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "simd/isa.hpp"

namespace kodawari::simd {

/// What a batch of one clip composes, node by node (Character::order: parents first).
struct PoseClipPlan {
    std::vector<std::int32_t> order;             // nodes, each after its parent
    std::vector<std::int32_t> parent;            // per node, -1 for a root
    std::vector<std::uint8_t> uniform_world;     // per node: 1 = `world` holds its world matrix for every instance
    std::vector<std::array<float, 16>> world;    // per node: the rest pose's world matrix (column-major)
    std::vector<std::array<float, 16>> local;    // per node: the rest local matrix (used when not animated)
    // Per node: the channel whose value it takes for translation, rotation, scale (the
    // last of the clip's channels that targets it: they are applied in order), or -1.
    std::vector<std::int32_t> t_channel, r_channel, s_channel;
    std::vector<std::array<float, 4>> rest_t, rest_r, rest_s;  // the node's rest TRS (xyz(w))
    std::uint32_t channels = 0;
};

/// A batch of up to kBatchLanes instances of one clip.
struct PoseBatch {
    std::uint32_t plan = 0;
    std::uint32_t count = 0;
    std::array<std::uint32_t, kBatchLanes> instance{};  // per lane (padding: lane 0's)
};

/// What one evaluation reads and writes.
struct PoseStepArgs {
    const PoseClipPlan* plans = nullptr;
    const PoseBatch* batches = nullptr;
    const float* placements = nullptr;  // per batch: 16 rows (the placement matrix, column-major) of kBatchLanes
    const float* values = nullptr;      // per batch: channels x 4 rows of kBatchLanes (the sampled values)
    const std::size_t* value_offset = nullptr;  // per batch: its first float in `values`
    float* world = nullptr;             // instances x nodes matrices, instance-major (the backend's output)
    std::size_t nodes = 0;
    float* scratch = nullptr;           // nodes x 16 rows of kBatchLanes floats, for one caller's batches
};

/// Composes batches [begin, end).
using PoseStepFn = void (*)(const PoseStepArgs& args, std::size_t begin, std::size_t end);

struct PoseKernels {
    PoseStepFn evaluate = nullptr;
};

/// The kernels of a Highway target (isa.hpp).
[[nodiscard]] PoseKernels pose_kernels(std::int64_t target);

}  // namespace kodawari::simd
