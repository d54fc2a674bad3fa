#include "kodawari/gltf/chains.hpp"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace kodawari::gltf {
namespace {

// Segments shorter than this are rejected; the same threshold as rods::make_basis, checked
// here first so that the message can name the nodes.
constexpr float kMinSegment = 1e-6f;
constexpr float kMinThickness = 1e-4f;

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// Shell-style wildcards over the whole (lowered) name: '*' any run, '?' one character.
// Iterative with one backtrack point, so a pattern of many stars stays linear per star.
bool wildcard_match(const std::string& name, const std::string& pattern) {
    std::size_t n = 0, p = 0, star = std::string::npos, resume = 0;
    while (n < name.size()) {
        if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == name[n])) {
            ++n, ++p;
        } else if (p < pattern.size() && pattern[p] == '*') {
            star = p++;
            resume = n;
        } else if (star != std::string::npos) {
            p = star + 1;
            n = ++resume;
        } else {
            return false;
        }
    }
    while (p < pattern.size() && pattern[p] == '*') ++p;
    return p == pattern.size();
}

// A needle with '*' or '?' is a wildcard pattern over the whole name ("tail*"); any other
// is a substring ("ear" matches "J_Sec_Ear_L").
bool contains_any(const std::string& lowered_name, const std::vector<std::string>& needles) {
    return std::any_of(needles.begin(), needles.end(), [&](const std::string& needle) {
        if (needle.empty()) return false;
        if (needle.find_first_of("*?") != std::string::npos) return wildcard_match(lowered_name, lower(needle));
        return lowered_name.find(lower(needle)) != std::string::npos;
    });
}

std::string node_label(const animation::Character& character, int index) {
    const std::string& name = character.nodes[static_cast<std::size_t>(index)].name;
    return name.empty() ? "node " + std::to_string(index)
                        : "node \"" + name + "\" (" + std::to_string(index) + ")";
}

std::string chain_name(const animation::Character& character, int root) {
    const std::string& name = character.nodes[static_cast<std::size_t>(root)].name;
    return name.empty() ? "node " + std::to_string(root) : name;
}

Error invalid(const animation::Character& character, const std::string& what) {
    return make_error(Error::Kind::InvalidInput, character.source + ": chain setup: " + what);
}

// The base shape of `nodes` in the rest pose `pose` (see FoundChain::base).
Result<rods::ChainShape> base_shape(const animation::Character& character, const animation::Pose& pose, const std::vector<int>& nodes) {
    const rods::Transform root = animation::rigid_part(pose.world[static_cast<std::size_t>(nodes.front())]);
    const glm::quat to_root = glm::conjugate(root.rotation);
    rods::ChainShape shape;
    for (std::size_t k = 0; k < nodes.size(); ++k) {
        const rods::Transform t = animation::rigid_part(pose.world[static_cast<std::size_t>(nodes[k])]);
        // Joint 0 exactly at the origin with the identity: computing it would leave
        // rounding residue, and SPEC A.1 defines the frame by it.
        shape.positions.push_back(k == 0 ? glm::vec3(0.0f) : to_root * (t.position - root.position));
        shape.orientations.push_back(k == 0 ? glm::quat(1.0f, 0.0f, 0.0f, 0.0f)
                                            : glm::normalize(to_root * t.rotation));
        if (k > 0) {
            const float segment = glm::length(shape.positions[k] - shape.positions[k - 1]);
            if (!(segment >= kMinSegment)) {
                return invalid(character, node_label(character, nodes[k]) + " is " + std::to_string(segment) +
                                              " m from its parent " + node_label(character, nodes[k - 1]) +
                                              " in the rest pose; a chain segment needs at least 1e-6 m");
            }
        }
    }
    return shape;
}

}  // namespace

Result<ChainSetup> find_chains(const animation::Character& character, const ChainSearch& search) {
    const std::size_t n = character.nodes.size();
    const std::uint32_t min_joints = std::max<std::uint32_t>(search.min_joints, 2);
    const animation::Pose pose = rest_pose(character);

    // Roots, in the order they start chains.
    std::vector<int> named_roots;
    for (const std::string& name : search.roots) {
        int found = -1;
        for (std::size_t i = 0; i < n; ++i) {
            if (character.nodes[i].name != name) continue;
            if (found >= 0) {
                return invalid(character, "chain root \"" + name + "\" names two nodes (" + std::to_string(found) +
                                              " and " + std::to_string(i) + ")");
            }
            found = static_cast<int>(i);
        }
        if (found < 0) return invalid(character, "chain root \"" + name + "\": no node has this name");
        named_roots.push_back(found);
    }
    std::vector<std::string> lowered_names;
    lowered_names.reserve(n);
    for (const animation::Node& node : character.nodes) lowered_names.push_back(lower(node.name));
    // Parents first, so that a strand is claimed by its top matching node.
    const std::vector<int>& candidates = search.roots.empty() ? character.order : named_roots;

    ChainSetup setup;
    std::vector<bool> claimed(n, false);  // part of a chain, or left out of one by truncation
    for (const int root : candidates) {
        const auto r = static_cast<std::size_t>(root);
        if (search.roots.empty()) {
            if (claimed[r] || !contains_any(lowered_names[r], search.patterns) ||
                contains_any(lowered_names[r], search.excludes)) {
                continue;
            }
        } else if (claimed[r]) {
            return invalid(character, "chain root " + node_label(character, root) +
                                          " is already a joint of an earlier chain");
        }

        // Walk down single-child nodes; the node that ends the walk is the last joint.
        std::vector<int> strand{root};
        while (character.nodes[static_cast<std::size_t>(strand.back())].children.size() == 1) {
            strand.push_back(character.nodes[static_cast<std::size_t>(strand.back())].children.front());
        }
        for (const int node : strand) claimed[static_cast<std::size_t>(node)] = true;
        if (strand.size() > rods::kMaxChainJoints) {
            setup.warnings.push_back(character.source + ": chain \"" + chain_name(character, root) + "\" has " +
                                     std::to_string(strand.size()) + " joints; kept the first " +
                                     std::to_string(rods::kMaxChainJoints) + ", " +
                                     node_label(character, strand[rods::kMaxChainJoints]) +
                                     " and below stay kinematic");
            strand.resize(rods::kMaxChainJoints);
        }
        if (strand.size() < min_joints) {
            setup.warnings.push_back(character.source + ": chain \"" + chain_name(character, root) + "\" has " +
                                     std::to_string(strand.size()) + " joint(s), fewer than " +
                                     std::to_string(min_joints) + "; skipped");
            continue;
        }

        auto chain = make_found_chain(character, pose, std::move(strand));
        if (!chain) return chain.error();
        setup.chains.push_back(std::move(chain).value());
    }
    return setup;
}

Result<FoundChain> make_found_chain(const animation::Character& character, const animation::Pose& rest, std::vector<int> nodes) {
    assert(nodes.size() >= 2 && nodes.size() <= rods::kMaxChainJoints);
    const int root = nodes.front();
    auto shape = base_shape(character, rest, nodes);
    if (!shape) return shape.error();
    const auto basis = rods::make_basis(shape.value());
    if (!basis) return invalid(character, "chain \"" + chain_name(character, root) + "\": " + basis.error().message);
    FoundChain chain;
    chain.name = chain_name(character, root);
    chain.nodes = std::move(nodes);
    chain.parent = character.nodes[static_cast<std::size_t>(root)].parent;
    chain.base = std::move(shape).value();
    for (const float l : basis.value().lengths) chain.length += l;
    return chain;
}

float character_size(const animation::Character& character) {
    if (character.nodes.empty()) return 0.0f;
    const animation::Pose pose = rest_pose(character);
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const glm::mat4& world : pose.world) {
        const glm::vec3 p(world[3]);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    return glm::length(hi - lo);
}

PhysicsScale scaled_physics(const animation::Character& character, const FoundChain& chain) {
    assert(chain.base.positions.size() >= 2);
    float shortest = std::numeric_limits<float>::max();
    for (std::size_t i = 1; i < chain.base.positions.size(); ++i) {
        shortest = std::min(shortest, glm::length(chain.base.positions[i] - chain.base.positions[i - 1]));
    }
    PhysicsScale physics;
    physics.thickness = std::min(std::max(kThicknessPerSize * character_size(character), kMinThickness), 0.5f * shortest);
    const float mean_segment = chain.length / static_cast<float>(chain.base.positions.size() - 1);
    physics.mass = kLockDensity * std::numbers::pi_v<float> * physics.thickness * physics.thickness * mean_segment;
    return clamped(physics);
}

PhysicsScale clamped(PhysicsScale physics) {
    // A chain of micrometre or kilometre segments still gets what the loader accepts (its
    // rig scene must load: fuzz_gltf's invariant).
    physics.thickness = std::clamp(physics.thickness, rods::kMinThickness, rods::kMaxThickness);
    physics.mass = std::clamp(physics.mass, rods::kMinMass, rods::kMaxMass);
    return physics;
}

}  // namespace kodawari::gltf
