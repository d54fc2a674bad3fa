#pragma once
/// @file
/// The scalar reference of the rods physics (SPEC A.4, A.5): oriented particles
/// (Mueller & Chentanez, "Solid Simulation with Oriented Particles", SCA 2011) with a
/// PBD distance constraint per segment, one particle per joint. shaders/rods_step.comp
/// mirrors these steps line by line; the data is fixed-size per chain for that reason.
///
/// Conventions. World units are metres and seconds. Quaternions are glm::quat.
/// The *root transform* is the world pose of the chain root's frame, the frame the
/// chain's shapes are given in (SPEC A.1); joint 0 follows it exactly. The *bone axis*
/// of joint i is the unit vector u_i, in joint i's own frame, that points along segment
/// i (towards joint i+1) in the base shape: u_i = o_i^-1 dir_i (the last joint uses the
/// last segment). For a rig whose bones point down local +Y, u_i = +Y for every joint.
/// The particle ellipsoid's long axis is u_i.
///
/// Why the solver has a rest-pose attraction besides SPEC A.4's shape matching. Shape
/// matching over overlapping groups {i-1, i, i+1} cannot resist a uniform bend: for a
/// chain bent into an arc (curvature k, straight rest), group i's best rigid fit moves its
/// centre particle by -2s/3 towards the chord and its two end particles by +s/3 away from
/// it (s = the sagitta, k l^2 / 2), so the three groups that contain a particle pull it by
/// -2s/3 + s/3 + s/3 = 0. This holds for any group width (the residuals of a straight fit
/// to a parabola sum to zero over a symmetric window) and the orientation term does not
/// change it (every particle's orientation follows its own group). Only the clipped groups
/// at the root resist, so a strand sags under gravity into an arc of its own length
/// whatever the stiffness (measured: a curled 13-joint strand ended 0.9-1.1 chain lengths
/// from its rest shape at stiffness 0.5 and 1). Measured fixes, on the same strand:
/// larger or self-weighted groups went unstable (Jacobi overshoot); Gauss-Seidel groups
/// stayed soft; bend-twist constraints on the orientations (Kugelstadt & Schoemer 2016)
/// and local shape constraints in the parent's frame either stayed soft or pumped energy
/// next to the groups. The global shape constraint (rest_stiffness) fixes it: 3% of the
/// length of sag at 0.1, convergence to the rest shape to 1e-5 of the length without
/// gravity, and a 1e-7 m perturbation of 200 strands stays below 1e-5 m over 300 frames
/// (without it, the same perturbation grew to 0.2 m: the soft mode made the system
/// chaotic).

#include <array>
#include <cstdint>
#include <span>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/limits.hpp"
#include "kodawari/rods/shape.hpp"

namespace kodawari::rods {

/// A rigid transform: world = position + rotation * local.
struct Transform {
    glm::vec3 position{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
};

/// The most colliders one chain may touch (the GPU keeps them in fixed arrays), and the
/// most one character template may have (its chains touch subsets of them).
inline constexpr std::uint32_t kMaxChainColliders = 16;
inline constexpr std::uint32_t kMaxCharacterColliders = 256;
/// The smallest particle thickness (m), particle mass (kg) and frame length (s) a chain
/// takes: above zero by margins that keep inertias, inverse masses and velocities
/// (displacement / dt) finite in float; below a hair's width, a segment's mass, a
/// 100 kHz step.
inline constexpr float kMinThickness = 1e-5f;
inline constexpr float kMinMass = 1e-9f;
inline constexpr float kMinFrameDt = 1e-5f;
/// The largest particle thickness (m) and mass (kg) a chain takes: a metre-thick,
/// tonne-heavy particle is already no hair, ear or antenna; the bounds keep inertias
/// (m t^2) far from float's range.
inline constexpr float kMaxThickness = 1.0f;
inline constexpr float kMaxMass = 1000.0f;

/// The substep the stiffnesses are given for, s: SolverParams::stiffness and
/// rest_stiffness are the fractions covered per substep of this length, and other
/// substeps take the same compliance (substep_stiffness()), so that results do not depend
/// on the frame rate (SPEC A.4). 1/120 s, the default max_substep, so a 60 fps frame's
/// two substeps take the stiffnesses as given.
inline constexpr float kReferenceSubstep = 1.0f / 120.0f;
/// Passes over a chain's collider set per particle (step()): a particle pushed out of one
/// collider into another is pushed out again by the second pass, so the result no longer
/// depends on the colliders' order except by what two passes leave (shaders/shared/rods.h
/// KW_RODS_COLLIDER_PASSES).
inline constexpr std::uint32_t kColliderPasses = 2;
/// s_damping of the dynamic follow-the-leader velocity correction (Mueller, Kim,
/// Chentanez 2012, eq. 9; s in [0, 1], they suggest 0.9): the share of a child's distance
/// correction its parent's velocity gives back (shaders/shared/rods.h KW_RODS_FTL_DAMPING).
/// 1: a slack 16-joint chain released horizontal then never moves with more energy than
/// it started with at 1 ms, 1/120 s or 1/20 s substeps (tests/rods/test_rod_physics.cpp);
/// at 0.9 it gained 18% at 1 ms (and 0.8 gained 73%, 0.5 17x), the under-corrected FTL
/// energy the correction is there to remove. The velocity term is not all motion: a
/// chain hanging at rest keeps velocities along its segments that the next sweep takes
/// back (the paper's artefact), so kinetic_energy() of a resting chain is not 0 where
/// gravity pulls along it; damping bounds them.
inline constexpr float kFollowTheLeaderDamping = 1.0f;

/// A stiffness fraction k per kReferenceSubstep as the fraction for a substep of `h` s,
/// with the same compliance K = k / ((1 - k) h_ref^2): k_h = K h^2 / (1 + K h^2). A
/// particle held by it against an acceleration g rests g / K away, whatever h. Every
/// backend takes this value, so that they agree to the bit.
[[nodiscard]] KODAWARI_API float substep_stiffness(float k, float h);
/// The fraction per projection iteration that `iterations` iterations compound to
/// `k_substep`: 1 - (1 - k_substep)^(1 / iterations).
[[nodiscard]] KODAWARI_API float iteration_stiffness(float k_substep, std::uint32_t iterations);

/// What a collider keeps a chain's particles from (VRMC_springBone 1.0 and its
/// VRMC_springBone_extended_collider 1.0 define the three).
enum class ColliderKind : std::uint32_t {
    /// Outside the capsule (a sphere when a == b): the distance of a particle's centre to
    /// the segment ab is kept >= radius + thickness.
    Outside = 0,
    /// Inside the capsule or sphere: the distance is kept <= max(radius - thickness, 0).
    Inside = 1,
    /// On the positive side of a plane through a with unit normal b: the signed distance
    /// dot(p - a, b) is kept >= thickness. `radius` is unused.
    Plane = 2,
};

/// A kinematic collider, world space. A plane's b is its unit normal, a direction: a rigid
/// transform turns it without moving it (and keeps it a unit vector far from the origin,
/// where a second point's rounding would tilt it).
struct Collider {
    glm::vec3 a{0.0f}, b{0.0f};
    float radius = 0.0f;  ///< m, >= 0
    ColliderKind kind = ColliderKind::Outside;
};

/// The distance a collider keeps for a particle of `thickness`: radius + thickness
/// outside, max(radius - thickness, 0) inside, thickness from a plane. Every backend
/// takes this value, so that their collisions agree to the bit.
[[nodiscard]] KODAWARI_API float collider_reach(const Collider& collider, float thickness);

/// How far a particle of `thickness` at `p` is from what `collider` forbids, m: positive
/// when it is free, 0 on the boundary, negative by the depth it violates it (outside: the
/// distance to the segment ab minus radius + thickness; inside: max(radius - thickness,
/// 0) minus that distance; plane: the signed distance along the normal minus thickness).
[[nodiscard]] KODAWARI_API float collider_gap(const Collider& collider, glm::vec3 p, float thickness);

/// Solver settings, shared by all chains of a character. Ranges are checked by
/// validate(); step() asserts them.
struct SolverParams {
    /// Longest substep, s, in (0, 0.05]. A frame of length dt runs ceil(dt / max_substep)
    /// equal substeps. The stiffnesses are converted to the substep's length as
    /// compliances (kReferenceSubstep) and damping is a rate, so the substep count changes
    /// the result only by the integration's own error: a horizontal strand's resting sag
    /// is the same within 1% from 24 to 144 fps (tests/rods/test_rods.cpp). 1/120 s keeps a
    /// 60 fps frame at two substeps.
    float max_substep = 1.0f / 120.0f;
    /// Projection iterations per substep, 1 .. 64.
    std::uint32_t iterations = 4;
    /// Shape-matching stiffness k in [0, 1]: the fraction of the way to the shape-matching
    /// goals covered per kReferenceSubstep, whatever `iterations` is; a substep of h covers
    /// k_h = substep_stiffness(k, h), and each iteration k' = 1 - (1 - k_h)^(1/iterations),
    /// so that `iterations` moves compound to k_h.
    float stiffness = 0.5f;
    /// Rest-pose attraction k_rest in [0, 1]: the fraction of the way each particle moves
    /// towards its rest position (the blended rest shape placed by the root) per
    /// kReferenceSubstep, whatever `iterations` is (same conversions as `stiffness`). It
    /// holds the artist's shape against gravity; 0 leaves only shape matching, which
    /// cannot (see above). Sag of a horizontal-ish strand scales as
    /// g h_ref^2 (1 - k_rest) / k_rest, whatever the substep.
    float rest_stiffness = 0.1f;
    /// Linear and angular velocity damping rate, 1/s, >= 0: velocities are multiplied by
    /// exp(-damping h) per substep h, which is independent of the substep length. It acts
    /// on world velocities, as VRM's drag does: a character moving at speed u pushes its
    /// strands back by damping x u (12 m/s^2 at 2/s and 6 m/s); a chain's `center`
    /// (follow_center()) measures velocities relative to a moving node instead.
    /// In a wind (rods::WindField) it acts on velocities relative to the air, so that
    /// the default 1/s is also a chain's isotropic drag: still air brakes a moving
    /// strand, moving air carries a still one.
    float damping = 1.0f;
    /// Drag across and along each segment, 1/s, each in [0, 1000]: on top of `damping`,
    /// the part of a particle's velocity relative to the air that is across its segment
    /// (joint i-1 to i) decays by exp(-normal_drag h) per substep h, the part along it by
    /// exp(-tangent_drag h), as a thin cylinder's drag is mostly across it (Houdini
    /// Vellum's normal and tangent drag). A strand then turns across a wind, not only
    /// with it. 0 and 0: isotropic damping only.
    float normal_drag = 0.0f;
    float tangent_drag = 0.0f;
    glm::vec3 gravity{0.0f, -9.81f, 0.0f};  ///< m/s^2
    /// An extra constant acceleration, m/s^2 (a push that ignores the chain's motion;
    /// a moving air is a rods::WindField).
    glm::vec3 wind{0.0f};
    /// Momentum suppression (SPEC A.5) in [0, 1]: 0 = plain shape matching, 1 = a change
    /// of rest shape moves the particles kinematically and injects no velocity.
    float momentum_suppression = 1.0f;
    /// How a chain starts: true, at rest in equilibrium under gravity, wind and its
    /// colliders (settle()), and in its first step moving with its root (start_moving()),
    /// as if it had been carried along before the first frame; false, on its rest shape
    /// and still, so that its first frames sag towards that equilibrium and lag behind a
    /// moving root (what UniVRM and three-vrm do; the comparisons with three-vrm start
    /// both sides this way).
    bool settle_start = true;
    /// A root that moves farther than this in one frame, m (> 0), has teleported (a cut,
    /// a respawn): its chain is carried rigidly by the root's jump, keeping its shape and
    /// velocities relative to the root (follow_center() by the old and new root), instead
    /// of being dragged across the gap. 1 m a frame is 60 m/s at 60 fps, past any
    /// character's run; a jump shorter than this is simulated as motion.
    float teleport_distance = 1.0f;
};

/// Checks every SolverParams range above.
[[nodiscard]] KODAWARI_API Result<void> validate(const SolverParams& params);

/// One chain's constant description, built from its base shape by make_chain().
struct Chain {
    std::uint32_t joint_count = 0;
    float thickness = 0.0f;                                ///< m: ellipsoid radii b = c, collision radius
    std::array<float, kMaxChainJoints> mass{};             ///< kg, > 0 (joint 0's too: it counts in shape matching)
    std::array<float, kMaxChainJoints> segment_length{};   ///< l_i, m, joint i to i+1
    std::array<float, kMaxChainJoints> half_length{};      ///< ellipsoid radius a along u_i, m
    std::array<glm::vec3, kMaxChainJoints> bone_axis{};    ///< u_i, unit, in joint i's frame
    /// Angle limits (set_limits()): limit[i] constrains the direction of segment i, from
    /// joint i to joint i+1; `limited` when any joint has one.
    bool limited = false;
    std::array<AngleLimit, kMaxChainJoints> limit{};
    std::array<glm::vec4, kMaxChainJoints> limit_trig{};   ///< limit_trig() of each
    std::array<glm::quat, kMaxChainJoints> limit_frame{};  ///< limit_frame(u_i, rotation) of each
};

/// A chain from its base shape (SPEC A.1), with `thickness` > 0 m and every particle of
/// `mass` > 0 kg. Fails on a base shape make_basis() rejects or a bad thickness or mass.
[[nodiscard]] KODAWARI_API Result<Chain> make_chain(const ChainShape& base, float thickness, float mass);

/// Gives `chain` angle limits: `limits` has one per segment (joint_count - 1, the last
/// joint has no child to limit) or none (no limits). Fails (InvalidInput, naming
/// `what`[i] and the field) on a limit out of range (validate(AngleLimit)) or a count that
/// does not fit.
///
/// step() applies a joint's limit wherever it places its child (each projection
/// iteration's follow-the-leader sweep and the last sweep), after the colliders' push, as
/// the draft orders it ("immediately after each collision"): the child is turned about its
/// parent, at the same distance, to the nearest direction the limit allows (limits.hpp),
/// in the limit's frame carried by the parent bone's current turn from its rest
/// (docs/models.md "Angle limits").
[[nodiscard]] KODAWARI_API Result<void> set_limits(Chain& chain, std::span<const AngleLimit> limits,
                                                   const std::string& what);

/// Everything a chain carries from one step to the next. Joint 0 is kinematic.
struct ChainState {
    /// Positions relative to root.position (world axes), m: position() gives the world
    /// position. Relative, so that precision follows the strand's size, not its distance
    /// from the world origin.
    std::array<glm::vec3, kMaxChainJoints> x{};
    std::array<glm::vec3, kMaxChainJoints> v{};      ///< velocities, m/s
    std::array<glm::quat, kMaxChainJoints> q{};      ///< orientations, world
    std::array<glm::vec3, kMaxChainJoints> omega{};  ///< angular velocities, rad/s, world
    Transform root;                                          ///< the last step's root transform
    /// The last step's center frame (follow_center()), for a chain that has one.
    Transform center;
    std::array<glm::vec3, kMaxChainJoints> rest_position{};  ///< the last step's rest shape, root frame
    std::array<glm::quat, kMaxChainJoints> rest_orientation{};
    /// Whether it has stepped since initial_state() (step() starts it moving first).
    bool started = false;
    /// Where the chain settled at load relative to its rest shape, in the root's frame (m):
    /// R^-1 (x_i - R rest_i) of the settled state (rods::initial_chain_state; 0 for a
    /// chain that does not settle). step_posed() eases a chain onto its rest shape plus
    /// this sag, the shape full simulation holds it in, so that one that turns full again
    /// does not fall.
    std::array<glm::vec3, kMaxChainJoints> sag{};
    /// Its level of detail at the last step (rods::Level in kodawari/rods/lod.hpp: 0 full,
    /// 1 posed, 2 hidden), which the next step's decision starts from (hysteresis).
    std::uint32_t level = 0;
    /// The share of full simulation in its last result (rods::blend_in): 1 while it is
    /// simulated, 0 while posed, and in between while it turns full again.
    float blend_in = 1.0f;
    /// The frames it has kept its state since its last step (rods::chain_rests: a posed or
    /// hidden chain stepped at the levels' rate, at most kHiddenPeriod - 1); its next step
    /// covers idle + 1 frames.
    std::uint32_t idle = 0;
};

/// A chain at rest: the rest shape `rest` (root frame, e.g. a blend from A.2) placed by
/// `root`, zero velocities.
[[nodiscard]] KODAWARI_API ChainState initial_state(const Chain& chain, const Transform& root, const ChainShape& rest);

/// The most quasi-static substeps settle() takes, their length (s: the longest
/// max_substep that validate() accepts) and the largest move of a particle in one of them
/// below which it stops, m per m of the root's distance from the origin plus 1 (about 8
/// float spacings: below that a substep's rounding moves particles). A quasi-static
/// substep moves every particle by its remaining distance times (1 - k_h), k_h the
/// stiffness of a 0.05 s substep (0.8 for the default rest_stiffness), so 1e-6 m comes
/// within 15 substeps of a 0.3 m sag; the cap is for soft chains.
inline constexpr std::uint32_t kMaxSettleSubsteps = 600;
inline constexpr float kSettleSubstep = 0.05f;
inline constexpr float kSettleTolerance = 1e-6f;
/// The dynamic substeps of params.max_substep that follow. Measured on scenes/ahoge.json
/// with the root held: the fastest particle moves at 0.02 m/s after 30, 1e-4 m/s after
/// 120; the dynamic phase decays at the damping's rate, not to a tolerance in any bounded
/// time, so it has a fixed length, which a crowd's load pays per chain (scenes/crowd.json,
/// 8 192 chains).
inline constexpr std::uint32_t kSettleDynamicSubsteps = 60;

/// Brings `state` to rest in equilibrium at `root` under the chain's gravity, the air
/// moving at `air` (m/s) and `colliders`, with `rest` its rest shape, by step()s of params.max_substep with the
/// root held: quasi-static first (substeps of kSettleSubstep, every velocity set to 0
/// after each, so nothing overshoots) until no particle moves by kSettleTolerance (x (1 +
/// |root.position|)) in a substep or kMaxSettleSubsteps have run, then kSettleDynamicSubsteps as step() runs (its rest
/// state keeps the small velocities of its follow-the-leader correction). Returns the
/// substeps taken.
KODAWARI_API std::uint32_t settle(const Chain& chain, const SolverParams& params, const Transform& root,
                                  const ChainShape& rest, std::span<const Collider> colliders, ChainState& state,
                                  const glm::vec3& air = glm::vec3(0.0f));

/// Adds to every velocity of `state` the rigid motion that carries its last root
/// (state.root) to `root` in `dt` s: v_i += (travel + turn x_i - x_i) / dt, omega_i += that of
/// the turn (first order, as step() takes angular velocities), so that a chain that
/// starts still does not lag behind a root that is already moving. step() calls it on a
/// chain's first step when params.settle_start (after a teleport's carry).
KODAWARI_API void start_moving(const Transform& root, float dt, ChainState& state);

/// Advances `state` by a frame of `dt` > 0 seconds (SPEC A.4). `root` is the root
/// transform at the end of the frame; within the frame the substeps interpolate it from
/// the previous one (linearly, and by slerp), so a fast root does not jump. `rest` is
/// this frame's rest shape in the root frame (positions and orientations, joint_count
/// each); the solver places it by the interpolated root in every substep. `colliders`
/// (at most kMaxChainColliders) are their poses at the end of the frame; within the frame
/// they move rigidly with the interpolated root, as the rest shape does (a collider on the
/// head stays where the head is in every substep). Each projection iteration ends with one
/// follow-the-leader distance sweep in which every particle, right after it is placed on
/// its parent's segment length, is pushed out of the whole collider set kColliderPasses
/// times; a last distance sweep after the iterations leaves no segment stretched, and the
/// velocities take the dynamic follow-the-leader correction (kFollowTheLeaderDamping), so
/// the inextensibility adds no energy. A root that jumped farther than
/// params.teleport_distance first carries the chain (follow_teleport()); a chain's first
/// step then starts it moving with its root (start_moving(), when params.settle_start).
/// `air` is the air's velocity around the chain this frame (m/s, rods::air_velocity()
/// at its root): damping and drag act on velocities relative to it.
KODAWARI_API void step(const Chain& chain, const SolverParams& params, const Transform& root, const ChainShape& rest,
                       std::span<const Collider> colliders, float dt, ChainState& state,
                       const glm::vec3& air = glm::vec3(0.0f));

/// The posed level of detail's frame (kodawari/rods/lod.hpp, docs/level-of-detail.md): no
/// dynamics. Like step(), a teleport's carry and a first step's start come first. Then,
/// from the root outwards, every joint is carried rigidly by the root's motion over the
/// frame (state.root to `root`: the travel and the turn R = root.rotation
/// state.root.rotation^-1), moved `blend` (in [0, 1]: posed_blend()) of the way from there
/// to its rest position plus its sag (ChainState::sag) placed by `root`, and put back on its parent's segment length and
/// out of `colliders` (their end-of-frame poses) as step()'s last sweep does (one round:
/// placed, then pushed out); its orientation goes `blend` of the way to its rest orientation
/// (a normalized lerp in one hemisphere). Joint 0 takes its rest placement exactly, as in
/// step(). Velocities are the frame's move over dt and the angular velocities its turn
/// (2/dt times the vector part of q_new q_old^-1 in the positive hemisphere), as step()'s
/// last substep derives them, so that a chain that turns full again moves on without a
/// jump from a shape its constraints already keep; the rest shape is kept for the next
/// frame's momentum suppression (SPEC A.5) as step() keeps it. No joint moves in a frame
/// by more than the root's motion plus `blend` of its distance from its rest shape (and
/// what the constraints take back). Every backend computes these operations in this order.
KODAWARI_API void step_posed(const Chain& chain, const SolverParams& params, const Transform& root, const ChainShape& rest,
                             std::span<const Collider> colliders, float dt, float blend, ChainState& state);

/// A chain turning full again (LodSettings::blend_time): `state` holds the frame step()
/// made from `before` (after its teleport carry and start), `posed` the one step_posed()
/// made from it; their mix `share` (in [0, 1]) of the way from `posed` to `state` goes
/// into `state`: positions linearly, orientations by a normalized lerp in one hemisphere,
/// velocities and angular velocities from the move since `before` as step() derives
/// them. Every backend computes these operations in this order.
KODAWARI_API void hand_over(const Chain& chain, const ChainState& before, const ChainState& posed, float share, float dt,
                            ChainState& state);

/// Carries `state` rigidly by the motion of a *center* frame from `from` to `to` (the
/// spring's `center` of VRMC_springBone 1.0 and VRM 0.x): UniVRM and three-vrm keep a
/// spring's previous and current tail positions in the center node's space, so its
/// inertia is measured relative to that node. With M = to * from^-1 (rotation R), every
/// particle's world position P becomes M P, its velocity R v, orientation R q and angular
/// velocity R omega, and the last root transform (state.root) moves by M as well, so the
/// next step() interpolates the root from where the carried chain hangs. Call it before
/// step() with the center's transforms at the previous and this frame.
KODAWARI_API void follow_center(const Transform& from, const Transform& to, ChainState& state);

/// The root's pose a frame of `dt` before `root` had it moved as joint 0 last moved:
/// back by its velocity state.v[0] and its turn state.omega[0] (joint 0 follows the root).
[[nodiscard]] KODAWARI_API Transform frame_before(const Transform& root, const ChainState& state, float dt);

/// Whether a root (or a motion key source) that moved from `from` to `to` in one frame
/// teleported: farther than `distance` (SolverParams::teleport_distance).
[[nodiscard]] inline bool teleported(const glm::vec3& from, const glm::vec3& to, float distance) {
    const glm::vec3 jump = to - from;
    return glm::dot(jump, jump) > distance * distance;
}

/// A teleport: when `root` is farther than params.teleport_distance from the last step's
/// root (state.root), carries `state` rigidly to `root` (follow_center(state.root, root)),
/// then back to frame_before(root, state, dt), so that the chain keeps its shape and
/// velocities relative to its root and the frame of `dt` that step() then takes sees the
/// root move on as it moved (the velocities carry that motion; a chain carried to the
/// frame's end would take it twice). step() calls it first; a backend that carries chains
/// itself calls it before its own step. Returns whether it carried.
KODAWARI_API bool follow_teleport(const SolverParams& params, const Transform& root, float dt, ChainState& state);

/// What a renderer or a skinned mesh needs from a chain.
struct ChainPose {
    std::array<glm::vec3, kMaxChainJoints> position{};     ///< world
    std::array<glm::quat, kMaxChainJoints> orientation{};  ///< world, the particles' own
    /// The skinning rotation of each bone relative to its parent: joint 0's relative to
    /// the root transform, joint i's relative to joint i-1's bone. A bone's world rotation
    /// is the particle orientation turned by the shortest arc that makes its bone axis
    /// u_i point exactly at particle i+1 (the last joint keeps its particle orientation).
    std::array<glm::quat, kMaxChainJoints> local_rotation{};
};

/// The pose of `state` (SPEC A.4, output).
[[nodiscard]] KODAWARI_API ChainPose pose(const Chain& chain, const ChainState& state);

/// World position of a joint: root.position + x[joint].
[[nodiscard]] KODAWARI_API glm::vec3 position(const ChainState& state, std::uint32_t joint);

/// Kinetic energy of the simulated particles (all but joint 0), J. For tests and tools.
[[nodiscard]] KODAWARI_API float kinetic_energy(const Chain& chain, const ChainState& state);

}  // namespace kodawari::rods
