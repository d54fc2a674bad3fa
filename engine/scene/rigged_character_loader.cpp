// Rigged characters in a scene (docs/scene-format.md, "Rigged characters"; issue 4,
// SPEC A.7): a character given by a glTF 2.0 / VRM file instead of a hand-written
// skeleton. The file is loaded here, relative to the scene's folder, so that every name
// in the scene (reference joint, chain roots, collider joints, clips) is checked against
// it and reported at its JSON path. Chains take their base shapes from the file's rest
// pose (gltf::make_found_chain), and their thickness and mass, unless given, from the
// character's size (gltf::scaled_physics).

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <kodawari/gltf/chains.hpp>
#include <kodawari/gltf/import.hpp>
#include <kodawari/gltf/motion.hpp>
#include <kodawari/gltf/vrm.hpp>
#include <kodawari/rods/world.hpp>

#include "scene/character_loader.hpp"

namespace kodawari::scene_detail {
namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

// A node as the scene names it: its index in the file (an integer), the name that exactly
// one node has, or, where names repeat, its path of names from a root node of the file
// ("Armature/Hips/Hair_01": each name a child of the one before, unique among its
// siblings).
Result<int> find_node(const JsonReader& r, const JsonNode& node, const animation::Character& ch) {
    if (node.present() && node.value->is_number_integer()) {
        std::uint64_t index = 0;
        KW_SCENE_ASSIGN(index, r.integer(node, 0, ch.nodes.size() - 1));
        return static_cast<int>(index);
    }
    std::string name;
    KW_SCENE_ASSIGN(name, r.string(node));
    std::vector<int> found;
    for (std::size_t i = 0; i < ch.nodes.size(); ++i) {
        if (ch.nodes[i].name == name) found.push_back(static_cast<int>(i));
    }
    if (found.size() == 1) return found.front();
    if (found.size() > 1) {
        return r.fail(node.path, "\"" + name + "\" names " + std::to_string(found.size()) + " nodes of " + ch.source + " (" +
                                     std::to_string(found[0]) + " and " + std::to_string(found[1]) +
                                     "); name the node by its index or by its path from a root (\"Root/Hips/" + name + "\")");
    }
    if (name.find('/') == std::string::npos) return r.expected(node, "the name, path or index of a node of " + ch.source);
    // A path: one step a name.
    int at = -1;
    std::size_t begin = 0;
    while (begin <= name.size()) {
        const std::size_t end = std::min(name.find('/', begin), name.size());
        const std::string step = name.substr(begin, end - begin);
        std::vector<int> candidates;
        if (at < 0) {
            for (std::size_t i = 0; i < ch.nodes.size(); ++i) {
                if (ch.nodes[i].parent < 0) candidates.push_back(static_cast<int>(i));
            }
        } else {
            candidates = ch.nodes[static_cast<std::size_t>(at)].children;
        }
        int next = -1;
        for (const int c : candidates) {
            if (ch.nodes[static_cast<std::size_t>(c)].name != step) continue;
            if (next >= 0) {
                return r.fail(node.path, "path \"" + name + "\": two " + (at < 0 ? std::string("root nodes") : "children of \"" + ch.nodes[static_cast<std::size_t>(at)].name + "\"") +
                                             " of " + ch.source + " are called \"" + step + "\" (" + std::to_string(next) +
                                             " and " + std::to_string(c) + "); name the node by its index");
            }
            next = c;
        }
        if (next < 0) {
            return r.expected(node, "the name, path or index of a node of " + ch.source + " (path step \"" + step + "\" is not " +
                                        (at < 0 ? std::string("a root node") : "a child of \"" + ch.nodes[static_cast<std::size_t>(at)].name + "\"") + ")");
        }
        at = next;
        begin = end + 1;
    }
    return at;
}

// The reference joint when the scene names none: a node called "head" (any case), else
// the humanoid head bone of a VRM file.
Result<int> default_reference(const JsonReader& r, const JsonNode& at, const animation::Character& ch) {
    int found = -1;
    for (std::size_t i = 0; i < ch.nodes.size(); ++i) {
        if (lower(ch.nodes[i].name) != "head") continue;
        if (found >= 0) {
            return r.fail(at.path, "two nodes of " + ch.source + " are called \"head\"; name the reference joint");
        }
        found = static_cast<int>(i);
    }
    if (found >= 0) return found;
    if (const int head = gltf::vrm_humanoid_bone(ch, "head"); head >= 0) return head;
    return r.fail(at.path, "no node of " + ch.source +
                               " is called \"head\" and it has no VRM humanoid head; name the node that view directions "
                               "are measured in (\"reference_joint\")");
}

// A chain's nodes: "nodes" (each the child of the one before) or "root" walked down
// single children (docs: at most "joints" of them).
Result<std::vector<int>> read_chain_nodes(const JsonReader& r, const JsonNode& node, const animation::Character& ch) {
    const JsonNode root = r.member(node, "root");
    const JsonNode list = r.member(node, "nodes");
    const JsonNode joints = r.member(node, "joints");
    if (root.present() == list.present()) {
        return r.fail(node.path, std::string("expected exactly one of \"root\" and \"nodes\", got ") +
                                     (root.present() ? "both" : "neither"));
    }
    const std::string range = "[2, " + std::to_string(rods::kMaxChainJoints) + "]";
    std::vector<int> nodes;
    if (list.present()) {
        if (joints.present()) return r.fail(joints.path, "only used with \"root\" (\"nodes\" lists every joint)");
        std::size_t n = 0;
        KW_SCENE_ASSIGN(n, read_array(r, list, 2, rods::kMaxChainJoints, "an array of " + range + " node names"));
        for (std::size_t i = 0; i < n; ++i) {
            const JsonNode element = r.element(list, i);
            int index = 0;
            KW_SCENE_ASSIGN(index, find_node(r, element, ch));
            if (i > 0 && ch.nodes[static_cast<std::size_t>(index)].parent != nodes.back()) {
                return r.expected(element, "a child of the node before it (\"" +
                                               ch.nodes[static_cast<std::size_t>(nodes.back())].name + "\")");
            }
            nodes.push_back(index);
        }
        return nodes;
    }
    int start = 0;
    KW_SCENE_ASSIGN(start, find_node(r, root, ch));
    std::uint64_t wanted = 0;
    if (joints.present()) KW_SCENE_ASSIGN(wanted, r.integer(joints, 2, rods::kMaxChainJoints));
    nodes.push_back(start);
    while (ch.nodes[static_cast<std::size_t>(nodes.back())].children.size() == 1 &&
           (wanted == 0 || nodes.size() < wanted)) {
        nodes.push_back(ch.nodes[static_cast<std::size_t>(nodes.back())].children.front());
        if (wanted == 0 && nodes.size() > rods::kMaxChainJoints) {
            return r.fail(root.path, "the strand from \"" + ch.nodes[static_cast<std::size_t>(start)].name + "\" has more than " +
                                         std::to_string(rods::kMaxChainJoints) +
                                         " single-child joints; give \"joints\" (at most " +
                                         std::to_string(rods::kMaxChainJoints) + ") to simulate the first ones");
        }
    }
    if (nodes.size() < 2 || (wanted != 0 && nodes.size() < wanted)) {
        return r.fail(root.path, "the strand from \"" + ch.nodes[static_cast<std::size_t>(start)].name + "\" has " +
                                     std::to_string(nodes.size()) + " single-child joint(s) before a branch or a leaf; " +
                                     (wanted != 0 ? std::to_string(wanted) : std::string("2")) + " needed (or list \"nodes\")");
    }
    return nodes;
}

Result<void> read_rigged_chain(const JsonReader& r, const JsonNode& node, const animation::Character& ch, const animation::Pose& rest,
                               std::uint32_t reference, const std::vector<ColliderSpec>& colliders,
                               const rods::SolverParams& defaults, std::vector<ChainSpec>& chains) {
    KW_TRY(r.object(node, {"name", "root", "nodes", "joints", "thickness", "mass", "physics", "collide", "colliders", "center",
                           "views", "keyed", "limit"}));
    ChainSpec c;
    c.path = node.path;
    c.params = defaults;
    const JsonNode name = r.member(node, "name");
    KW_SCENE_ASSIGN(c.name, read_name(r, name));
    for (const ChainSpec& other : chains) {
        if (other.name == c.name) return r.expected(name, "a chain name this character does not use yet (\"" + c.name + "\" is taken)");
    }
    KW_SCENE_ASSIGN(c.nodes, read_chain_nodes(r, node, ch));
    for (const ChainSpec& other : chains) {
        for (const int n : c.nodes) {
            if (std::find(other.nodes.begin(), other.nodes.end(), n) != other.nodes.end()) {
                return r.fail(node.path, "node \"" + ch.nodes[static_cast<std::size_t>(n)].name + "\" is already simulated by chain \"" +
                                             other.name + "\" (a joint belongs to one chain)");
            }
        }
    }
    auto found = gltf::make_found_chain(ch, rest, c.nodes);
    if (!found) return r.fail(node.path, found.error().message);
    c.joint = static_cast<std::uint32_t>(c.nodes.front());
    c.base = found.value().base;
    const gltf::PhysicsScale scaled = gltf::scaled_physics(ch, found.value());
    c.thickness = scaled.thickness;
    c.mass = scaled.mass;
    JointLookup joints;
    joints.find = [&](const JsonNode& n) -> Result<std::uint32_t> {
        int index = 0;
        KW_SCENE_ASSIGN(index, find_node(r, n, ch));
        return static_cast<std::uint32_t>(index);
    };
    joints.parent = [&](std::uint32_t n) { return static_cast<std::int32_t>(ch.nodes[n].parent); };
    // As RodScene::rigged_frame measures it: from the rest pose's world matrices, scale removed.
    joints.rest_rotation = [&](std::uint32_t n) {
        const glm::quat world = animation::rigid_part(rest.world[n]).rotation;
        const int parent = ch.nodes[n].parent;
        if (parent < 0) return world;
        return glm::normalize(glm::conjugate(animation::rigid_part(rest.world[static_cast<std::size_t>(parent)]).rotation) * world);
    };
    joints.reference = reference;
    joints.colliders = collider_names(colliders);
    KW_TRY(read_chain_settings(r, node, joints, c));
    chains.push_back(std::move(c));
    return {};
}

// A path in the scene, relative to the scene file's folder unless absolute.
std::string scene_relative(const JsonReader& r, const std::string& given) {
    const std::filesystem::path p(given);
    return p.is_absolute() ? given : (std::filesystem::path(r.file()).parent_path() / p).string();
}

// The `motions` of a rigged character (docs/scene-format.md, "Motions"): each a clip made
// for another skeleton, retargeted onto `ch` (gltf/motion.hpp) and appended to its clips.
Result<void> read_motions(const JsonReader& r, const JsonNode& motions, animation::Character& ch, std::vector<std::string>& warnings,
                          std::vector<std::string>& files) {
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, motions, 1, kMaxPerCharacter,
                                  "a non-empty array of motions (at most " + std::to_string(kMaxPerCharacter) + ")"));
    const std::size_t file_clips = ch.animations.size();
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode m = r.element(motions, i);
        KW_TRY(r.object(m, {"name", "file", "clip", "map", "target_map"}));
        gltf::MotionRequest request;
        const JsonNode name = r.member(m, "name");
        KW_SCENE_ASSIGN(request.name, r.string(name));
        for (std::size_t c = 0; c < ch.animations.size(); ++c) {
            if (ch.animations[c].name != request.name) continue;
            return r.fail(name.path, "\"" + request.name + "\" is already " +
                                         (c < file_clips ? "a clip of " + ch.source : std::string("the name of an earlier motion")) +
                                         "; give the motion another name");
        }
        const JsonNode file = r.member(m, "file");
        KW_SCENE_ASSIGN(request.file, r.string(file));
        request.file = scene_relative(r, request.file);
        files.push_back(request.file);
        const JsonNode clip = r.member(m, "clip");
        if (clip.present()) KW_SCENE_ASSIGN(request.clip, r.string(clip));
        const JsonNode map = r.member(m, "map");
        if (map.present()) {
            KW_SCENE_ASSIGN(request.map, r.string(map));
            request.map = scene_relative(r, request.map);
            files.push_back(request.map);
        }
        const JsonNode target_map = r.member(m, "target_map");
        if (target_map.present()) {
            KW_SCENE_ASSIGN(request.target_map, r.string(target_map));
            request.target_map = scene_relative(r, request.target_map);
            files.push_back(request.target_map);
        }
        gltf::MotionKey key = gltf::MotionKey::File;
        auto motion = gltf::load_motion(request, ch, &key);
        if (!motion) {
            const JsonNode& at = key == gltf::MotionKey::Clip ? clip
                                 : key == gltf::MotionKey::Map ? map
                                 : key == gltf::MotionKey::TargetMap ? (target_map.present() ? target_map : m)
                                                                     : file;
            return make_error(motion.error().kind, r.file() + ": " + at.path + ": " + motion.error().message);
        }
        for (const std::string& w : motion.value().warnings) warnings.push_back(r.file() + ": " + m.path + ": " + w);
        ch.animations.push_back(std::move(motion.value().animation));
    }
    return {};
}

}  // namespace

Result<std::int32_t> find_clip(const JsonReader& r, const JsonNode& node, const animation::Character& ch) {
    if (ch.animations.empty()) {
        // Still a string, or that is the error.
        KW_TRY(r.string(node));
        return r.expected(node, "no animation: " + ch.source + " has no animation clips");
    }
    std::vector<std::string> names;
    for (const animation::Animation& clip : ch.animations) names.push_back(clip.name);
    std::uint32_t clip = 0;
    KW_SCENE_ASSIGN(clip, find_name(r, node, names, "the name of an animation of " + ch.source));
    return static_cast<std::int32_t>(clip);
}

Result<CharacterSpec> read_rigged_character(const JsonReader& r, const JsonNode& node) {
    KW_TRY(r.object(node, {"name", "gltf", "reference_joint", "animation", "animate", "motions", "colliders", "physics", "chains",
                           "wind"}));
    CharacterSpec out;
    out.path = node.path;
    KW_SCENE_ASSIGN(out.name, read_name(r, r.member(node, "name")));

    RigSpec rig;
    const JsonNode file = r.member(node, "gltf");
    KW_SCENE_ASSIGN(rig.file, r.string(file));
    if (rig.file.empty()) return r.expected(file, "the path of a .gltf, .glb or .vrm file");
    const std::filesystem::path given(rig.file);
    rig.resolved = given.is_absolute() ? rig.file : (std::filesystem::path(r.file()).parent_path() / given).string();
    auto loaded = gltf::load_character(rig.resolved);
    if (!loaded) {
        return make_error(loaded.error().kind, r.file() + ": " + file.path + ": " + loaded.error().message);
    }
    if (const JsonNode motions = r.member(node, "motions"); motions.present()) {
        KW_TRY(read_motions(r, motions, loaded.value(), rig.warnings, rig.motion_files));
    }
    auto character = std::make_shared<const animation::Character>(std::move(loaded.value()));
    const animation::Character& ch = *character;

    const JsonNode reference = r.member(node, "reference_joint");
    int reference_node = 0;
    if (reference.present()) {
        KW_SCENE_ASSIGN(reference_node, find_node(r, reference, ch));
    } else {
        KW_SCENE_ASSIGN(reference_node, default_reference(r, reference, ch));
    }
    out.skeleton.reference = static_cast<std::uint32_t>(reference_node);

    bool animate = true;
    KW_TRY(optional_member(r, node, "animate", animate, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode animation = r.member(node, "animation");
    if (animation.present()) {
        if (!animate) return r.fail(animation.path, "not used with \"animate\": false (the rest pose)");
        KW_SCENE_ASSIGN(rig.clip, find_clip(r, animation, ch));
    } else {
        rig.clip = animate && !ch.animations.empty() ? 0 : -1;
    }

    const auto node_index = [&](const JsonNode& n) -> Result<std::uint32_t> {
        int index = 0;
        KW_SCENE_ASSIGN(index, find_node(r, n, ch));
        return static_cast<std::uint32_t>(index);
    };
    KW_SCENE_ASSIGN(out.colliders, read_colliders(r, node, node_index));

    rods::SolverParams defaults;
    const JsonNode physics = r.member(node, "physics");
    if (physics.present()) KW_TRY(read_physics(r, physics, defaults));
    const animation::Pose rest = animation::rest_pose(ch);
    const JsonNode chains = r.member(node, "chains");
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, chains, 1, kMaxPerCharacter,
                                  "a non-empty array of chains (at most " + std::to_string(kMaxPerCharacter) + ")"));
    for (std::size_t i = 0; i < n; ++i) KW_TRY(read_rigged_chain(r, r.element(chains, i), ch, rest, out.skeleton.reference, out.colliders, defaults, out.chains));

    rig.character = std::move(character);
    out.rig = std::move(rig);
    return out;
}

}  // namespace kodawari::scene_detail
