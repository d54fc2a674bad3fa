#pragma once
// The vectorized rods kernel (SPEC A.2-A.5) and the structure-of-arrays layout it shares
// with the cpu rod backend (backends/simd_rods.cpp).
//
// Layout. Chains are grouped by template into batches of kBatchLanes (16) chains; every
// chain of a batch has the same joint count, view examples and solver settings, so the
// kernel's loops and constants are uniform and one vector instruction advances 16
// (AVX-512), 8 (AVX2) or 4 (SSE4) chains; the backend runs a batch with few chains in use
// on the width that costs least (a lone chain on the scalar target). A batch's state is
// one block of rows of 16 floats, a row = one quantity of one joint for the 16 chains (64
// bytes, a cache line): per joint x, v, q, omega and last frame's rest shape (kJointRows
// rows), then per chain the root, view direction and weights (kChainRows rows). Padding
// lanes of a template's last batch repeat its first chain, so they compute finite values
// nobody reads.
//
// Exactness. The kernel evaluates every expression of engine/rods (solver.cpp, shape.cpp,
// view.cpp, world.cpp) with the same operations in the same order (glm's association
// included: see vecmath-inl.h), without contraction (-ffp-contract=off) or fused
// multiply-add, and takes the few transcendental functions (pow for the view weights,
// the root interpolation's atan2/sin/cos) from scalar_math.cpp lane by lane. +, -, *, /
// and sqrt are correctly rounded in every instruction set, so each chain's result is
// cpu-reference's bits, on every instruction set (tests/backends/test_rod_backends.cpp).

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kodawari/rods/world.hpp"
#include "simd/isa.hpp"

namespace kodawari::simd {

/// Rows per joint in a batch block: x(3) v(3) q(4) omega(3) rest position(3) rest orientation(4).
enum JointRow : std::uint32_t { kX = 0, kV = 3, kQ = 6, kOmega = 10, kRestP = 13, kRestO = 16, kJointRows = 20 };
/// Rows per chain after the joints: root position(3) and rotation(4), view direction(3), weights(8),
/// level of detail (rods::Level as a float) and the share of full simulation in the result
/// (rods::ChainState::blend_in), both decided by the backend before each step, and the
/// frames the chain kept its state since its last step (rods::ChainState::idle: counted by
/// the backend, 0 again after a step).
enum ChainRow : std::uint32_t {
    kRootP = 0, kRootQ = 3, kView = 7, kWeights = 10, kLevel = 18, kBlendIn = 19, kIdle = 20, kChainRows = 21
};

/// A frame's step sizes for one set of solver settings, computed by the backend with
/// rods::step's own expressions (backends/simd_rods.cpp set_step).
struct RodStepConsts {
    std::uint32_t substeps = 1, iterations = 0;
    float h = 0.0f, decay = 0.0f, k_iter = 0.0f, k_rest = 0.0f;
    float half_h = 0.0f, two_over_h = 0.0f;
    float ftl_over_h = 0.0f;                // rods::kFollowTheLeaderDamping / h
    std::array<float, 3> h_acceleration{};  // h * (gravity + wind)
    // Each part of the drag's decay, exp(-drag h) (SolverParams::normal_drag, tangent_drag).
    float normal_decay = 1.0f, tangent_decay = 1.0f;
};

/// A template's constants in the kernel's terms, and this frame's step sizes, computed
/// by the backend with rods::step's own expressions.
struct RodTemplateConsts {
    std::uint32_t joints = 0, views = 0;
    std::uint32_t keyed = 0;         // keyed examples J (docs/keyed-examples.md), shapes m+1 .. m+J
    float thickness = 0.0f;
    float b2 = 0.0f;                 // thickness^2
    float suppression = 0.0f;        // SPEC A.5 coefficient
    std::array<float, 3> first_direction{};
    std::array<float, rods::kMaxChainJoints> weight{};      // shape-matching weight (root: kRootShapeWeight x mass)
    std::array<float, rods::kMaxChainJoints> weight5{};     // weight / 5
    std::array<float, rods::kMaxChainJoints> ab{};          // half_length^2 - b2
    std::array<float, rods::kMaxChainJoints> segment{};     // segment length l_i
    std::array<float, rods::kMaxChainJoints> lengths{};     // the basis' lengths (SPEC A.2)
    std::array<std::array<float, 3>, rods::kMaxChainJoints> bone_axis{};
    std::array<float, rods::kMaxChainJoints> group_mass{};  // per group G_i
    std::array<std::array<float, 3>, rods::kMaxViewExamples> view_direction{};
    std::array<float, rods::kMaxViewExamples> influence{};
    // Shapes (SPEC A.2), [k][i][xyzw], k = 0 the base: rotations r_i (identity for the
    // last joint) and orientations o_i, and the sign that flips each into the base's
    // hemisphere (+1 or -1; exact, as shape.cpp's dot test).
    std::vector<std::array<float, 4>> rotation, orientation;
    std::vector<float> rotation_sign, orientation_sign;
    // With no examples the rest shape is the same every frame: blended once at load
    // by engine/rods itself (n positions, n orientations).
    std::vector<std::array<float, 3>> fixed_rest_position;
    std::vector<std::array<float, 4>> fixed_rest_orientation;
    // Angle limits (rods::set_limits): per segment its kind (rods::LimitKind), its
    // rods::limit_trig and its rods::limit_frame (x, y, z, w); `limited` when any has one.
    bool limited = false;
    std::array<std::uint32_t, rods::kMaxChainJoints> limit_kind{};
    std::array<std::array<float, 4>, rods::kMaxChainJoints> limit_trig{};
    std::array<std::array<float, 4>, rods::kMaxChainJoints> limit_frame{};
    // Drag across and along the segments (SolverParams::normal_drag, tangent_drag) on.
    bool drag = false;
    // This frame's step sizes: the template's settings (full lanes) and rods::reduced_params
    // of them (lanes at the reduced level).
    RodStepConsts step, reduced;
};

/// A batch of up to kBatchLanes chains of one template.
struct RodBatch {
    std::uint32_t templ = 0;
    std::uint32_t count = 0;                        // valid lanes, 1 .. kBatchLanes
    std::array<std::uint32_t, kBatchLanes> chain{};  // chain index per lane (padding: lane 0's)
    std::size_t offset = 0;                         // first float of its block in the storage
    std::uint32_t colliders = 0;                    // most colliders of one of its chains
    std::size_t sag_offset = 0;                     // first float of its sag rows (RodStepArgs::sag)
};

/// Floats of a batch block of chains of `joints` joints.
[[nodiscard]] constexpr std::size_t rod_block_floats(std::uint32_t joints) {
    return (std::size_t{joints} * kJointRows + kChainRows) * kBatchLanes;
}

/// What one step reads and writes.
struct RodStepArgs {
    const RodTemplateConsts* templates = nullptr;
    const RodBatch* batches = nullptr;
    float* storage = nullptr;
    const rods::RodFrame* frame = nullptr;
    const rods::ChainInstance* chains = nullptr;
    /// Per chain, its raw keyed weights this frame (rods::measure_keys, kMaxKeyedExamples
    /// each): measured by the backend, since they are a few scalars per chain.
    const float* keyed = nullptr;
    /// Per chain, the air's velocity this frame (rods::chain_air, 3 floats each),
    /// computed by the backend with engine/rods' own function; null in a world without
    /// wind, whose kernels then take damping on the world velocities as before.
    const float* air = nullptr;
    /// Levels of detail on (RodWorld::lod): lanes whose kLevel row is posed or hidden take
    /// rods::step_posed with this blend (rods::posed_blend), reduced lanes step with their
    /// template's `reduced` constants; full and reduced lanes whose kBlendIn row is below 1
    /// take rods::hand_over of the step and the posed frame.
    bool lod = false;
    /// rods::posed_blend over 1 .. kHiddenPeriod frames: a posed step covers its lane's
    /// kIdle row + 1 frames.
    std::array<float, rods::kHiddenPeriod> blend{};
    /// Per batch, the lanes (bit l) that keep their state this frame (rods::chain_rests),
    /// null where none does: a batch whose every lane keeps is not stepped, the others keep
    /// those lanes' rows as they were.
    const std::uint32_t* resting = nullptr;
    /// Per batch, from RodBatch::sag_offset: each joint's rods::ChainState::sag, 3 rows
    /// of kBatchLanes (read by posed lanes only, so kept out of the blocks the step streams).
    const float* sag = nullptr;
};

/// Advances batches [begin, end) by one frame (SPEC A.3, A.2, A.5, A.4).
using RodStepFn = void (*)(const RodStepArgs& args, std::size_t begin, std::size_t end);

struct RodKernels {
    RodStepFn step = nullptr;
};

/// The kernels of a Highway target (isa.hpp).
[[nodiscard]] RodKernels rod_kernels(std::int64_t target);

}  // namespace kodawari::simd
