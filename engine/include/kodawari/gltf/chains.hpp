#pragma once
/// @file
/// Chain setup from a rigged glTF character (SPEC A.7, issue 4): which node strands of a
/// loaded Character become simulated rods chains, their base shapes from the rest pose,
/// and physical parameters scaled by the character's size.
///
/// The rules, in one place:
/// - A *chain* is a run of nodes, root first, each the only child of the one before. The
///   walk down from a chain's root continues while the current node has exactly one
///   child; a node with no child or with two or more children is the chain's last joint
///   (at a branch the chain ends *at* the branching node, whose children are not part of
///   it). Node names below the root do not matter for the walk.
/// - Chains have at most rods::kMaxChainJoints (32) joints. A longer strand is truncated:
///   the chain keeps its first 32 joints, a warning names the first node left out, and
///   the nodes left out stay kinematic (they follow their parent's rest transform; they
///   never start chains of their own).
/// - Chains with fewer than ChainSearch::min_joints joints are skipped with a warning.
/// - With ChainSearch::roots given, exactly those nodes start chains. Otherwise, in the
///   character's parents-first node order, every node whose name matches a pattern (and
///   matches no exclusion) and is not already part of a chain (or left out by truncation)
///   starts one. So a matching node under a matching parent continues the parent's chain
///   when the parent has one child, and starts its own chain when the parent is a branch
///   (e.g. "hair_root" with children "hair_L", "hair_R": each child strand is a chain).

#include <cstdint>
#include <string>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/shape.hpp"

namespace kodawari::gltf {

/// How to find the chains of a character.
struct ChainSearch {
    /// Exact node names (case-sensitive) of chain roots. When non-empty, `patterns` and
    /// `excludes` are not used. Each name must name exactly one node.
    std::vector<std::string> roots;
    /// Case-insensitive (ASCII) patterns of node names that mark a chain root, used when
    /// `roots` is empty. A pattern without wildcards is a substring, so "ear" also matches
    /// "Ear_L" and "J_Sec_Ear"; one with `*` (any run) or `?` (one character) matches the
    /// whole name, as a shell does ("tail*" matches "Tail_1", not "Cocktail"). "spring" is
    /// there for VRM spring-bone rigs, whose nodes are often so named.
    std::vector<std::string> patterns = {"hair", "bang", "ahoge", "ear", "tail", "ribbon", "skirt", "antenna", "spring"};
    /// Case-insensitive substrings that veto a pattern match: "ear" is a substring of
    /// "ForeArm" (Mixamo's "mixamorig:LeftForeArm"), which must not become a chain.
    std::vector<std::string> excludes = {"forearm"};
    /// Chains with fewer joints are skipped (with a warning). Values below 2 act as 2:
    /// a chain needs at least one segment (rods::make_basis).
    std::uint32_t min_joints = 2;
};

/// One chain found in a character.
struct FoundChain {
    std::string name;        ///< the root node's name ("node <index>" when it has none)
    std::vector<int> nodes;  ///< joint node indices, root first, 2..32 of them
    /// The node the chain hangs from: the root's parent, -1 when the root is a scene
    /// root. It is kinematic for this chain, though it may itself be the last joint of
    /// another chain (a strand below a branch); the caller places the root by it.
    int parent = -1;
    /// The base shape (SPEC A.1) from the rest pose, in the frame of the chain root's
    /// world transform with its scale removed (rigid_part()): positions in metres as they
    /// are in the world, joint 0 at the origin with the identity orientation; every
    /// orientation is the node's world rotation (scale removed) in that frame.
    rods::ChainShape base;
    float length = 0.0f;  ///< sum of the base shape's segment lengths, m
};

/// What find_chains() found.
struct ChainSetup {
    std::vector<FoundChain> chains;  ///< in the order their roots were found
    /// Chains skipped (too few joints) or truncated (too many), each a readable line
    /// naming the file and the node.
    std::vector<std::string> warnings;
};

/// Finds the chains of `character` by `search` (see the file comment for the rules) and
/// computes their base shapes from rest_pose(). Errors (InvalidInput, naming
/// Character::source and the node): a named root that no node has, or that two nodes
/// have; a named root inside a chain found before; two consecutive joints closer than
/// 1e-6 m in the rest pose (the chain would have a zero-length segment); a base shape
/// rods::make_basis() rejects for any other reason.
[[nodiscard]] KODAWARI_API Result<ChainSetup> find_chains(const animation::Character& character, const ChainSearch& search);

/// The chain of the joints `nodes` (root first, each the child of the one before, 2..32
/// of them; the caller checks that) with its base shape from `rest` (rest_pose()), as
/// find_chains() builds each of its chains. Errors as find_chains(): two consecutive
/// joints closer than 1e-6 m, or a base shape rods::make_basis() rejects.
[[nodiscard]] KODAWARI_API Result<FoundChain> make_found_chain(const animation::Character& character, const animation::Pose& rest,
                                                               std::vector<int> nodes);

/// Physical parameters of one chain for rods::make_chain().
struct PhysicsScale {
    float thickness = 0.0f;  ///< m, > 0
    float mass = 0.0f;       ///< per joint, kg, > 0
};

/// The character's size: the length of the diagonal of the axis-aligned box around all
/// node world positions in the rest pose, m (0 for a single node). It includes meshes'
/// nodes and the root nodes, so it is the rig's extent rather than the mesh's; for a
/// humanoid rig it is about its height.
[[nodiscard]] KODAWARI_API float character_size(const animation::Character& character);

/// Thickness and mass of `chain`, scaled by character_size():
/// - thickness = kThicknessPerSize * size (1 cm for a 1.7 m character: a hair lock's
///   radius), at least 0.1 mm, and at most half the chain's shortest segment, so that the
///   collision spheres of neighbouring joints do not swallow a segment (the upper bound
///   wins over the lower);
/// - mass per joint = kLockDensity * pi * thickness^2 * (length / segments): a cylinder
///   of the chain's thickness and the mean segment length, at the density of a loose
///   hair lock. So mass grows as size^3, as real mass does. Within one chain every joint
///   has the same mass and the solver uses masses only as ratios, so this value matters
///   only where chains interact with forces in newtons later.
///
/// Both are then clamped() to what the solver takes, so a chain of micrometre or
/// kilometre segments still loads.
[[nodiscard]] KODAWARI_API PhysicsScale scaled_physics(const animation::Character& character, const FoundChain& chain);

/// `physics` with thickness in [rods::kMinThickness, rods::kMaxThickness] and mass in
/// [rods::kMinMass, rods::kMaxMass].
[[nodiscard]] KODAWARI_API PhysicsScale clamped(PhysicsScale physics);

/// Thickness per metre of character size (see scaled_physics()).
inline constexpr float kThicknessPerSize = 0.006f;
/// Density of a hair lock, kg/m^3: keratin (about 1300) at a quarter fill, the rest air.
inline constexpr float kLockDensity = 300.0f;

}  // namespace kodawari::gltf
