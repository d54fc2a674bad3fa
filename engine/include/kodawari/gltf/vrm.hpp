#pragma once
/// @file
/// VRM spring bones as rods chains (SPEC A.7, issue 4): the springs and colliders of a
/// VRM character (VRMC_springBone 1.0 with VRMC_springBone_extended_collider 1.0, or
/// VRM 0.x `extensions.VRM.secondaryAnimation`) read from a loaded Character, each
/// spring a FoundChain with solver parameters mapped from VRM's.
///
/// Which nodes become chains:
/// - VRM 1.0: each spring's `joints` in order, root first; each joint must be the child
///   of the one before (an error otherwise). The last joint is the spring's tail.
/// - VRM 0.x: each bone group's `bones` are roots; from a root the chain walks down
///   single-child nodes as find_chains() does, and at a node with two or more children
///   the chain ends there and each child starts a chain of its own (VRM 0.x simulates
///   the whole subtree). UniVRM adds a virtual 7 cm tail beyond every leaf; we have no
///   node to put it on, so a chain's last simulated bone ends at the leaf.
/// - Springs of fewer than 2 joints are skipped, of more than rods::kMaxChainJoints
///   truncated, each with a warning.
///
/// The parameter mapping. VRM's model is not ours: VRM moves each joint's tail by a
/// verlet step, nextTail = tail + (tail - prevTail)(1 - dragForce) + dt stiffness
/// (rest bone direction) + dt gravityPower gravityDir, then puts the tail back at the
/// bone's length; "rest direction" is in the parent's *current* frame, so bones bend
/// independently. Ours is shape matching plus a rest-pose attraction of every particle
/// towards its rest position in the root frame (rods/solver.hpp). So the mapping matches
/// the feel of one bone (its sag under gravity and its swing frequency at VRM's 60 Hz
/// reference), not the trajectory. The formulas (h = rods::kReferenceSubstep, the
/// substep the solver's stiffnesses are given for, L = the chain's mean segment length in
/// metres, kVrmFrameRate = 60):
/// - gravity = kVrmFrameRate * mean over the chain's bones of gravityPower * gravityDir,
///   m/s^2. VRM's terms are displacements per frame scaled by dt, and the inertia term
///   carries them over frames, so a constant term p acts as an acceleration p / dt = 60 p
///   at 60 Hz: gravityPower 1 is about 6 g, not 1 g. (VRM's response therefore depends on
///   the frame rate; ours does not: the stiffnesses are compliances, rods::
///   substep_stiffness, and damping is a rate, so the mapped chain rests at the same sag
///   and swings alike at any frame rate.) Our solver damps the velocity before adding
///   gravity, as VRM damps its inertia term and not its gravity term, so the equilibrium
///   sags agree with no correction for damping. Held at 1000 m/s^2 (the scene format's
///   bound), with a warning.
/// - rest_stiffness = a s / (a s + L) with a = kVrmFrameRate h^2 and s = mean stiffness.
///   For a horizontal rest bone, VRM's equilibrium sag angle is atan(gravityPower /
///   stiffness), independent of the bone; a particle held by our rest attraction k (per
///   h) sags by g h^2 (1 - k) / k at equilibrium, whatever the substep. Equating the
///   small-angle sag of one segment of length L gives this k, which is in [0, 1) for any
///   s >= 0. It also matches the swing frequency: VRM's restoring term is a spring of
///   omega^2 = 60 s / L, ours of K = k / ((1 - k) h^2), equal by the same equation. Limits: VRM's sag accumulates bone by bone along a
///   chain and ours does not, so long VRM chains droop more than ours; and the same VRM
///   stiffness gives a weaker rest attraction on longer segments, as it does in VRM.
/// - stiffness (shape matching) = 0: VRM has no such term, and at SolverParams' default
///   (0.5) it acts like a rest attraction some 27 times the mapped one, so a bone rang 5x
///   faster and sagged 1/40 as much as three-vrm's (docs/rigged-characters.md, "Measured
///   against three-vrm"). The rest-pose attraction alone holds the chain's shape.
/// - damping = -ln(1 - dragForce) * kVrmFrameRate, 1/s: dragForce is the fraction of
///   velocity lost per 60 Hz frame. dragForce is clamped to [0, kMaxDragForce] first, as
///   1 would be an infinite rate.
/// - hitRadius -> VrmSpring::hit_radius (file units) and the chain's thickness: hitRadius
///   times the root node's world scale (largest axis, as UniVRM), at least 0.1 mm (our
///   solver needs a thickness > 0; VRM's default hitRadius is 0) and at most half the
///   chain's shortest segment (see scaled_physics()). A joint's hitRadius 0 falls back to
///   scaled_physics()'s thickness.
/// - VRM 1.0 parameters are per joint; a chain has one set, so they are averaged over
///   the chain's bones (every joint but the tail, whose parameters VRM 1.0 does not use).
///   VRM 0.x parameters are per bone group.
/// - VRM 1.0 `center` and VRM 0.x `center` (a node whose space the spring's inertia is
///   measured in; UniVRM and three-vrm keep the previous and current tail positions in
///   it) become VrmSpring::center, which the scene's chain `center` makes the solver
///   honour by carrying the chain rigidly with that node's motion before each step
///   (rods::follow_center). VRM 0.x's -1 means none.
///
/// Colliders. Sphere and capsule become VrmCollider in their node's local frame, each
/// spring keeping its own collider groups (VrmSpring::colliders). The extended collider
/// (VRMC_springBone_extended_collider 1.0) replaces the base shape when present, as the
/// extension defines it (the base shape is the fallback of readers without it): its
/// spheres and capsules, outside or `inside` (the joint is kept inside the shape), and its
/// planes (offset on the plane, unit normal; the joint is kept on the normal's side), each
/// a rods::ColliderKind. VRM 0.x collider offsets are stored with z negated (UniVRM 0.x
/// wrote Unity's frame), so z is negated back here; its gravityDir is not.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/gltf/chains.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/solver.hpp"

namespace kodawari::gltf {

/// VRM's reference frame rate: its per-frame parameters are read at this rate, Hz.
inline constexpr float kVrmFrameRate = 60.0f;
/// The largest dragForce used in the damping formula (gives 276/s).
inline constexpr float kMaxDragForce = 0.99f;

/// One VRM spring as a chain.
struct VrmSpring {
    FoundChain chain;
    /// The mapped parameters (see the file comment); the rest are SolverParams' defaults.
    rods::SolverParams params;
    /// VRM's hitRadius (mean over the chain's bones), in the joints' local units as in
    /// the file (VRM scales it by the joint's world scale).
    float hit_radius = 0.0f;
    /// Thickness (from hit_radius, see the file comment) and mass for rods::make_chain().
    PhysicsScale physics;
    /// The colliders this spring collides with (its collider groups' colliders), indices
    /// into VrmSprings::colliders, ascending, without repeats.
    std::vector<std::size_t> colliders;
    /// The node whose space its inertia is measured in (`center`), -1 for none.
    int center = -1;
    /// Its joints' angle limits (VRMC_springBone_limit 1.0-draft), one per bone (joint
    /// count - 1), or none when no joint has one.
    std::vector<rods::AngleLimit> limits;
};

/// A sphere, capsule or plane collider, in the frame of its node: the node's world matrix
/// maps offset and tail to the world, and radius is in the node's local units (multiply
/// by the node's world scale, the largest axis, for metres).
struct VrmCollider {
    int node = -1;
    bool capsule = false;
    glm::vec3 offset{0.0f};  ///< the sphere's centre, the capsule's first end, a point of the plane
    glm::vec3 tail{0.0f};    ///< the capsule's second end (offset for a sphere, offset + normal for a plane)
    glm::vec3 normal{0.0f};  ///< a plane's unit normal (node frame)
    float radius = 0.0f;     ///< >= 0 (0 for a plane)
    /// What it keeps the spring's joints from: outside it, inside it (extended collider
    /// `inside`), or behind the plane.
    rods::ColliderKind kind = rods::ColliderKind::Outside;
};

/// What read_vrm_springs() found.
struct VrmSprings {
    std::vector<VrmSpring> springs;  ///< in the file's order
    /// VRM 1.0: indexed like the file's `colliders`. VRM 0.x: the colliders of every
    /// collider group, flattened in group order.
    std::vector<VrmCollider> colliders;
    /// Things read but not mapped (see the file comment), each naming the file and the
    /// JSON path.
    std::vector<std::string> warnings;
    int version = 0;  ///< 0 = no spring bones, 1 = VRM 0.x, 2 = VRMC_springBone 1.0
};

/// Reads the spring bones of `character` from Character::extensions: VRMC_springBone
/// when present, else VRM 0.x secondaryAnimation, else version 0 and nothing (not an
/// error). Errors (InvalidInput, naming Character::source and the JSON path, e.g.
/// "$.extensions.VRMC_springBone.springs[1].joints[2]"): a missing or mistyped required
/// field, a node or collider (group) index out of range, a 1.0 joint that is not the
/// child of the joint before it, a negative radius, a plane whose normal is zero, and the
/// errors of make_found_chain().
[[nodiscard]] KODAWARI_API Result<VrmSprings> read_vrm_springs(const animation::Character& character);

/// The node of a VRM humanoid bone ("head", "hips", ...): VRMC_vrm 1.0's
/// `humanoid.humanBones.<bone>.node`, else VRM 0.x's `humanoid.humanBones[i]` whose
/// `bone` is `bone`. -1 when the file has neither or does not map that bone (or maps it
/// to a node out of range).
[[nodiscard]] KODAWARI_API int vrm_humanoid_bone(const animation::Character& character, std::string_view bone);

}  // namespace kodawari::gltf
