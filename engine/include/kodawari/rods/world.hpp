#pragma once
/// @file
/// Everything the rod backends consume (SPEC A, C): chain templates (a chain's constant
/// description, its view examples and solver settings), chain instances (a template on
/// one character instance), and the small per-frame input (camera, reference joints,
/// chain roots, colliders) that the kinematic characters produce. Built from a scene
/// (scene.hpp, build_rod_scene) or by hand.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "kodawari/api.hpp"
#include "../result.hpp"
#include "shape.hpp"
#include "solver.hpp"
#include "view.hpp"

namespace kodawari::rods {

/// The most view examples one chain may have (m, SPEC A.1). Fixed so that the GPU keeps
/// the weights in registers.
inline constexpr std::uint32_t kMaxViewExamples = 7;

/// A chain's constant description: shape basis, base and example shapes in the blending
/// representation (SPEC A.2), the examples' views (SPEC A.3), and its physics.
struct ChainTemplate {
    std::string name;
    Chain chain;
    ShapeBasis basis;
    std::vector<RotationShape> shapes;  ///< shapes[0] = base C_0, shapes[k] = example k
    std::vector<ViewExample> views;     ///< views[k-1] belongs to shapes[k]
    SolverParams params;
};

/// Builds a template from shapes in the chain root's frame. Fails (InvalidInput, naming
/// `name`) when a shape does not fit the base (joint count, a segment shorter than
/// 1e-6 m), an influence is not > 0, a direction is not finite and non-zero (it is
/// normalized), there are more than kMaxViewExamples examples, or the parameters or the
/// chain's thickness and mass are out of range.
[[nodiscard]] KODAWARI_API Result<ChainTemplate> make_chain_template(std::string name, const ChainShape& base,
                                                                     std::span<const ChainShape> example_shapes,
                                                                     std::span<const ViewExample> views, float thickness,
                                                                     float mass, const SolverParams& params);

/// One simulated chain: a template attached to one character instance.
struct ChainInstance {
    std::uint32_t template_index = 0;
    std::uint32_t character = 0;       ///< the character instance whose reference joint gives the view
    std::uint32_t collider_begin = 0;  ///< its colliders: RodFrame::colliders[begin, begin + count)
    std::uint32_t collider_count = 0;
    std::uint32_t joint_begin = 0;     ///< its joints in flat per-joint arrays (set by RodWorld::finalize)
};

/// The chains of a scene.
struct KODAWARI_API RodWorld {
    std::vector<ChainTemplate> templates;
    std::vector<ChainInstance> chains;
    std::uint32_t character_count = 0;  ///< character instances (RodFrame::reference entries)
    std::uint32_t collider_count = 0;   ///< RodFrame::colliders entries
    std::uint32_t joint_count = 0;      ///< sum of the chains' joints (set by finalize)

    /// Checks every index and range and sets joint_begin and joint_count.
    [[nodiscard]] Result<void> finalize();
    [[nodiscard]] const ChainTemplate& templ(const ChainInstance& c) const { return templates[c.template_index]; }
};

/// One frame's kinematic input, world space. Produced by the characters' animation.
struct RodFrame {
    float time = 0.0f;  ///< s, at the end of the frame
    float dt = 1.0f / 60.0f;  ///< s, > 0
    Camera camera;
    std::vector<Transform> reference;  ///< per character instance: the reference joint's pose (SPEC A.3)
    std::vector<Transform> roots;      ///< per chain: the chain root's frame (joint 0 follows it)
    /// Kinematic colliders; a sphere is a capsule with a == b.
    std::vector<Capsule> colliders;
};

/// Checks that `frame` fits `world` (sizes, dt > 0, finite values).
[[nodiscard]] KODAWARI_API Result<void> check_frame(const RodWorld& world, const RodFrame& frame);

/// The view direction, weights and blended rest shape of one chain (SPEC A.3, A.2).
struct RestShape {
    glm::vec3 view_direction{0.0f, 0.0f, 1.0f};  ///< d, the reference joint's frame
    std::vector<float> weights;                  ///< w_0 .. w_m
    ChainShape shape;                            ///< root frame
};

/// SPEC A.3 then A.2 for `chain` under `frame`: d from the camera and the chain's
/// character's reference joint, the weights, the blend and forward kinematics.
[[nodiscard]] KODAWARI_API RestShape rest_shape(const RodWorld& world, std::uint32_t chain, const RodFrame& frame);

}  // namespace kodawari::rods
