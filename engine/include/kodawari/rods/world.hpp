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

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/keyed.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/rods/shape.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/view.hpp"
#include "kodawari/rods/wind.hpp"

namespace kodawari::rods {

/// The most view examples one chain may have (m, SPEC A.1), and the most examples of
/// every kind together (view and keyed, docs/keyed-examples.md K.1). Fixed so that the GPU
/// keeps the weights in registers.
inline constexpr std::uint32_t kMaxViewExamples = 7;

/// A chain's constant description: shape basis, base and example shapes in the blending
/// representation (SPEC A.2), the examples' views (SPEC A.3), and its physics.
struct ChainTemplate {
    std::string name;
    Chain chain;
    ShapeBasis basis;
    /// shapes[0] = base C_0, shapes[k] = view example k (1 .. m), then the keyed examples
    /// (shapes[m + j] = keyed example j, docs/keyed-examples.md).
    std::vector<RotationShape> shapes;
    std::vector<ViewExample> views;     ///< views[k-1] belongs to shapes[k]
    std::vector<KeySourceKind> key_sources;  ///< what each key source of its chains is (K.1)
    std::vector<KeyedExample> keyed;         ///< keyed[j-1] belongs to shapes[m + j]
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

/// Adds keyed examples (docs/keyed-examples.md K.1) to `t`, after its view examples:
/// `sources` are the kinds of the key sources its chains read (RodFrame::keys), `shapes`
/// one shape per example in the chain root's frame. Fails (InvalidInput, naming the
/// template and the example) when the counts do not match, there are more than
/// kMaxKeySources sources or kMaxKeyedExamples keyed examples or kMaxViewExamples
/// examples in all, an influence is not finite and > 0, a smoothing time is not in
/// [0, kMaxSmoothing], a motion example's source is not a motion source, a pose example
/// names no source or a source that is not a pose source, a key is not finite or a key
/// rotation is not a unit quaternion, or a shape does not fit the base. Sets each
/// magnitude example's saturation (K.2). Called at most once per template.
[[nodiscard]] KODAWARI_API Result<void> add_keyed_examples(ChainTemplate& t, std::span<const KeySourceKind> sources,
                                                           std::span<const ChainShape> shapes,
                                                           std::span<const KeyedExample> keyed);

/// ChainInstance::center of a chain without a center frame.
inline constexpr std::uint32_t kNoCenter = 0xFFFFFFFFu;

/// One simulated chain: a template attached to one character instance.
struct ChainInstance {
    std::uint32_t template_index = 0;
    std::uint32_t character = 0;       ///< the character instance whose reference joint gives the view
    std::uint32_t collider_begin = 0;  ///< its colliders: RodFrame::colliders[begin, begin + count)
    std::uint32_t collider_count = 0;
    std::uint32_t joint_begin = 0;     ///< its joints in flat per-joint arrays (set by RodWorld::finalize)
    /// Its key sources: RodFrame::keys[key_begin, key_begin + the template's key_sources
    /// count) (set by RodWorld::finalize).
    std::uint32_t key_begin = 0;
    /// Its center frame (follow_center()): an index into RodFrame::centers that no other
    /// chain uses, or kNoCenter for a chain whose inertia is measured in the world.
    std::uint32_t center = kNoCenter;
    /// The wind field it feels: an index into RodFrame::winds (ignored in a world without
    /// wind fields, RodWorld::wind_count 0).
    std::uint32_t wind = 0;
};

/// The chains of a scene.
struct KODAWARI_API RodWorld {
    std::vector<ChainTemplate> templates;
    std::vector<ChainInstance> chains;
    std::uint32_t character_count = 0;  ///< character instances (RodFrame::reference entries)
    std::uint32_t collider_count = 0;   ///< RodFrame::colliders entries
    std::uint32_t center_count = 0;     ///< RodFrame::centers entries
    /// RodFrame::winds entries: 0, no wind (the chains' damping acts on their world
    /// velocities), or the fields that ChainInstance::wind picks from.
    std::uint32_t wind_count = 0;
    std::uint32_t joint_count = 0;      ///< sum of the chains' joints (set by finalize)
    std::uint32_t key_count = 0;        ///< sum of the chains' key sources (set by finalize)
    /// Levels of detail (lod.hpp): off unless enabled; then every backend decides each
    /// chain's level per frame from RodFrame::camera and its character's reference joint.
    LodSettings lod;

    /// Checks every index and range (a center belongs to one chain) and `lod`, and sets joint_begin,
    /// key_begin, joint_count and key_count.
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
    /// Kinematic colliders (ChainInstance::collider_begin / collider_count pick each
    /// chain's); a sphere is a capsule with a == b.
    std::vector<Collider> colliders;
    /// The center frames (ChainInstance::center): the pose of the node whose space a
    /// chain's inertia is measured in.
    std::vector<Transform> centers;
    /// Per chain, its key sources (ChainInstance::key_begin): a Motion source's world
    /// pose, a Pose source's rotation relative to its parent (position 0).
    std::vector<Transform> keys;
    /// The wind fields (RodWorld::wind_count of them), at `time`: each chain feels the air
    /// of its field at its root (chain_air()), for the whole frame.
    std::vector<WindField> winds;
    /// The frame's number in its scene (RodScene: the frame's index), by which posed and
    /// hidden chains take turns to step (rate_turn(), chain_rests(); docs/level-of-detail.md
    /// "The rate"). kNoFrameNumber, a frame made by hand, steps every chain every frame.
    std::uint32_t number = kNoFrameNumber;
    /// The scene's index of this world's character 0 (a shard's first instance,
    /// RodScene::first_instance): the characters that take turns together are the whole
    /// scene's.
    std::uint32_t first_character = 0;
    /// The budget's cap on the full distance this frame (lod_budget.hpp, LodBudget::cap()):
    /// a character deeper than it is not full whatever its projected size. kNoDistanceCap
    /// (infinity) without a budget.
    float full_distance_cap = kNoDistanceCap;
};

/// Checks that `frame` fits `world` (sizes, dt > 0, finite values).
[[nodiscard]] KODAWARI_API Result<void> check_frame(const RodWorld& world, const RodFrame& frame);

/// The air's velocity around `chain` this frame: rods::air_velocity() of its wind field
/// at its root and frame.time; 0 in a world without wind.
[[nodiscard]] KODAWARI_API glm::vec3 chain_air(const RodWorld& world, std::uint32_t chain, const RodFrame& frame);
/// `chain` at rest at `frame` (its first): initial_state() on the rest shape of
/// rest_shape(world, chain, frame), settled there (settle(), with the chain's colliders
/// and air at `frame`) unless its params say settle_start false, with its center frame
/// (ChainState::center) from frame.centers when it has one, and where it settled relative to
/// its rest shape (ChainState::sag). Every backend starts from
/// these bits.
[[nodiscard]] KODAWARI_API ChainState initial_chain_state(const RodWorld& world, std::uint32_t chain, const RodFrame& frame);

/// The view direction, weights and blended rest shape of one chain (SPEC A.3, A.2).
struct RestShape {
    glm::vec3 view_direction{0.0f, 0.0f, 1.0f};  ///< d, the reference joint's frame
    std::vector<float> weights;                  ///< W_0 .. W_{m+J} (keyed-examples.md K.4)
    ChainShape shape;                            ///< root frame
};

/// SPEC A.3 then A.2 for `chain` under `frame`: d from the camera and the chain's
/// character's reference joint, the weights, the blend and forward kinematics. `keyed`
/// are the chain's raw keyed weights this frame (measure_keys(); all 0 for a chain
/// without keyed examples), combined with the view weights by keyed-examples.md K.4.
[[nodiscard]] KODAWARI_API RestShape rest_shape(const RodWorld& world, std::uint32_t chain, const RodFrame& frame,
                                                const KeyedWeights& keyed = {});

/// This frame's key sources of `chain`: frame.keys[key_begin, key_begin + count).
[[nodiscard]] KODAWARI_API std::span<const Transform> chain_keys(const RodWorld& world, std::uint32_t chain,
                                                                 const RodFrame& frame);

/// `chain`'s key state at the start, from the first frame (initial_key_state).
[[nodiscard]] KODAWARI_API KeyState initial_key_state(const RodWorld& world, std::uint32_t chain,
                                                      const RodFrame& frame);

/// `chain`'s raw keyed weights this frame (keyed_weights), advancing `keys`; all 0 for a
/// chain without keyed examples. `frames`: the frames since its last measure (a chain that
/// kept its state between its turns, rods::chain_rests, is measured at its step over them).
[[nodiscard]] KODAWARI_API KeyedWeights measure_keys(const RodWorld& world, std::uint32_t chain, const RodFrame& frame,
                                                     KeyState& keys, std::uint32_t frames = 1);

}  // namespace kodawari::rods
