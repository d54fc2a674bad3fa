// `kodawari rig` (SPEC A.7: the seed's one menu command that builds the whole physics
// structure of an imported character): chains and colliders found in a glTF / VRM file,
// written as a scene that the scene loader reads back with the same rules.

#include "kodawari/gltf/import.hpp"
#include "kodawari/gltf/rig_scene.hpp"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "kodawari/gltf/motion.hpp"
#include "kodawari/gltf/vrm.hpp"
#include "kodawari/rods/world.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari::gltf {
namespace {

using Json = nlohmann::ordered_json;

// The scene format's bound on collider coordinates in their joint's frame and on radii
// (docs/scene-format.md, "Colliders"), m.
constexpr float kMaxColliderReach = 1000.0f;

// The scene format's bound on the camera's orbit target and radius (camera_loader.cpp:
// half the 1e6 m world bound), m: the rig aims its camera at a joint and backs it off by
// the character's size, so every rest-pose joint must lie inside it.
constexpr float kMaxJointReach = 5.0e5f;

// Six significant digits: what a person reads and edits, and well inside every
// tolerance the loader applies (float keeps about seven).
double num(float v) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", static_cast<double>(v));
    return std::strtod(text, nullptr);
}
Json vec(glm::vec3 v) { return Json::array({num(v.x), num(v.y), num(v.z)}); }

// The same six digits, never above `v` once read back as a float: for a value the loader
// bounds from above by something it recomputes from the glTF (a thickness of half the
// shortest segment), where rounding to the nearest could put it 1e-6 over and `run` would
// refuse the scene `rig` wrote (fuzz_gltf, CI stop 46).
double num_at_most(float v) {
    double d = num(v);
    if (static_cast<float>(d) <= v) return d;
    // One unit in the sixth digit below: the largest six-digit decimal under v.
    const double step = std::pow(10.0, std::floor(std::log10(std::abs(static_cast<double>(v)))) - 5.0);
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", d - step);
    d = std::strtod(text, nullptr);
    assert(static_cast<float>(d) <= v);
    return d;
}

// nlohmann puts every array element on a line of its own; [x, y, z] on one line reads
// better. Only arrays of plain numbers are joined (names could hold brackets).
std::string compact_number_arrays(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] == '[') {
            const std::size_t close = text.find(']', i);
            const std::string inner = close == std::string::npos ? std::string() : text.substr(i + 1, close - i - 1);
            if (!inner.empty() && inner.find_first_not_of("0123456789.eE+-, \n") == std::string::npos) {
                std::string joined = "[";
                std::size_t start = 0;
                for (std::size_t k = 0; k <= inner.size(); ++k) {
                    if (k == inner.size() || inner[k] == ',') {
                        std::string item = inner.substr(start, k - start);
                        item.erase(0, item.find_first_not_of(" \n"));
                        item.erase(item.find_last_not_of(" \n") + 1);
                        joined += (joined.size() > 1 ? ", " : "") + item;
                        start = k + 1;
                    }
                }
                out += joined + "]";
                i = close;
                continue;
            }
        }
        out += text[i];
    }
    return out;
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

// A chain or character name the scene format accepts: non-empty, no '#' or '/'.
std::string scene_name(std::string s) {
    std::replace(s.begin(), s.end(), '#', '_');
    std::replace(s.begin(), s.end(), '/', '_');
    return s.empty() ? std::string("chain") : s;
}

// How the scene names each node (the scene loader's find_node): its name where no other
// node has it; else its path of names from a root ("Armature/Hips/Hair") where each step
// is unique among its siblings and holds no '/'; else its index.
std::vector<Json> node_refs(const animation::Character& ch) {
    const auto unique_name = [&](std::size_t i) {
        return !ch.nodes[i].name.empty() &&
               std::count_if(ch.nodes.begin(), ch.nodes.end(), [&](const animation::Node& n) { return n.name == ch.nodes[i].name; }) == 1;
    };
    std::vector<Json> out(ch.nodes.size());
    for (std::size_t i = 0; i < ch.nodes.size(); ++i) {
        if (unique_name(i) && ch.nodes[i].name.find('/') == std::string::npos) {
            out[i] = ch.nodes[i].name;
            continue;
        }
        std::string path;
        bool ok = true;
        for (int n = static_cast<int>(i); n >= 0 && ok; n = ch.nodes[static_cast<std::size_t>(n)].parent) {
            const animation::Node& node = ch.nodes[static_cast<std::size_t>(n)];
            const int parent = node.parent;
            const auto same = [&](int other) { return other != n && ch.nodes[static_cast<std::size_t>(other)].name == node.name; };
            bool clash = false;
            if (parent >= 0) {
                const std::vector<int>& siblings = ch.nodes[static_cast<std::size_t>(parent)].children;
                clash = std::any_of(siblings.begin(), siblings.end(), same);
            } else {
                for (std::size_t r = 0; r < ch.nodes.size() && !clash; ++r) {
                    clash = ch.nodes[r].parent < 0 && same(static_cast<int>(r));
                }
            }
            ok = !node.name.empty() && node.name.find('/') == std::string::npos && !clash;
            path = path.empty() ? node.name : node.name + "/" + path;
        }
        // A path that is itself some node's name would be read as that name.
        ok = ok && std::none_of(ch.nodes.begin(), ch.nodes.end(), [&](const animation::Node& n) { return n.name == path; });
        out[i] = ok ? Json(path) : Json(i);
    }
    return out;
}

// A node's name for messages: its name, or "node <index>".
std::string node_label(const animation::Character& ch, int n) {
    const std::string& name = ch.nodes[static_cast<std::size_t>(n)].name;
    return name.empty() ? "node " + std::to_string(n) : "\"" + name + "\"";
}

struct Candidate {
    FoundChain chain;
    PhysicsScale physics;
    std::optional<rods::SolverParams> params;  // VRM's mapped parameters
    std::vector<std::size_t> colliders;        // VRM: the spring's colliders (VrmSprings::colliders indices)
    int center = -1;                           // VRM: its center node
    std::vector<rods::AngleLimit> limits;      // VRM: its joints' angle limits (or none)
};

// A limit's rotation as the scene writes rotations ({"axis", "angle_deg"}), the short way.
Json rotation_json(const glm::quat& q) {
    const glm::quat shortest = q.w < 0.0f ? -q : q;
    Json r;
    r["axis"] = vec(glm::axis(shortest));
    r["angle_deg"] = num(glm::degrees(glm::angle(shortest)));
    return r;
}

// One joint's limit as the scene format writes it (docs/scene-format.md, "limit"), or
// null for none. Degrees at six digits; a limit at pi or pi/2 stays within the loader's
// [0, 180] and [0, 90] (num_at_most).
Json limit_json(const rods::AngleLimit& l) {
    if (l.kind == rods::LimitKind::None) return nullptr;
    Json shape;
    if (l.kind == rods::LimitKind::Spherical) {
        shape["pitch_deg"] = num_at_most(glm::degrees(l.angle));
        shape["yaw_deg"] = num_at_most(glm::degrees(l.yaw));
    } else {
        shape["angle_deg"] = num_at_most(glm::degrees(l.angle));
    }
    if (l.rotation != glm::quat(1.0f, 0.0f, 0.0f, 0.0f)) shape["rotation"] = rotation_json(l.rotation);
    Json j;
    j[l.kind == rods::LimitKind::Cone ? "cone" : l.kind == rods::LimitKind::Hinge ? "hinge" : "spherical"] = shape;
    return j;
}

float max_scale(const glm::mat4& m) {
    return std::max({glm::length(glm::vec3(m[0])), glm::length(glm::vec3(m[1])), glm::length(glm::vec3(m[2]))});
}

}  // namespace

Result<RigScene> make_rig_scene(const std::string& character_path, const std::string& scene_path, const RigOptions& options) {
    auto loaded = load_character(character_path);
    if (!loaded) return loaded.error();
    animation::Character& ch = loaded.value();
    RigScene out;
    namespace fs = std::filesystem;
    const fs::path scene_dir = fs::absolute(fs::path(scene_path)).parent_path();
    const auto scene_relative = [&](const std::string& path) {
        return fs::absolute(fs::path(path)).lexically_normal().lexically_relative(scene_dir.lexically_normal()).generic_string();
    };

    // Motions first, so that --animation may name one: each retargeted here (its errors
    // are the user's, exit 2) and appended to the clips the way the scene loader will.
    Json motions = Json::array();
    for (const std::string& file : options.motions) {
        MotionRequest request;
        request.file = file;
        std::string name = fs::path(file).stem().string();
        if (name.empty()) name = "motion";
        const auto taken = [&](const std::string& n) {
            return std::any_of(ch.animations.begin(), ch.animations.end(), [&](const animation::Animation& a) { return a.name == n; });
        };
        request.name = name;
        for (int suffix = 2; taken(request.name); ++suffix) request.name = name + "_" + std::to_string(suffix);
        bool mapped = false;
        if (!options.motion_map.empty()) {
            // The map is for the motions that are not VRM Animations.
            auto source = load_character(file);
            if (!source) return source.error();
            mapped = source.value().extensions.empty() ||
                     !nlohmann::json::parse(source.value().extensions, nullptr, false).contains("VRMC_vrm_animation");
            if (mapped) request.map = options.motion_map;
        }
        auto motion = load_motion(request, ch);
        if (!motion) return motion.error();
        Retargeted& m = motion.value();
        out.warnings.insert(out.warnings.end(), m.warnings.begin(), m.warnings.end());
        const bool hips = std::any_of(m.animation.channels.begin(), m.animation.channels.end(),
                                      [](const animation::Channel& c) { return c.path == animation::Path::Translation; });
        out.motions.push_back(
            RigMotion{request.name, file, m.bones, m.keys, m.animation.end - m.animation.start, hips, m.leg_ratio, mapped});
        Json j;
        j["name"] = request.name;
        j["file"] = scene_relative(file);
        if (mapped) j["map"] = scene_relative(options.motion_map);
        motions.push_back(j);
        ch.animations.push_back(std::move(m.animation));
    }
    const std::vector<Json> refs = node_refs(ch);
    const animation::Pose rest = rest_pose(ch);
    // A node far out (or its transforms' product overflowing) would write a camera the
    // loader refuses (fuzz_gltf, CI stop 49): name the node and its place instead.
    for (std::size_t i = 0; i < rest.world.size(); ++i) {
        const glm::vec3 p(rest.world[i][3]);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
            std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxJointReach) {
            char where[96];
            std::snprintf(where, sizeof(where), "(%g, %g, %g)", static_cast<double>(p.x), static_cast<double>(p.y),
                          static_cast<double>(p.z));
            return make_error(Error::Kind::InvalidInput,
                              ch.source + ": nodes[" + std::to_string(i) + "] (\"" + ch.nodes[i].name +
                                  "\") is at " + where + " in the rest pose: expected every node within 500 km of " +
                                  "the origin (a scene's camera range); are the file's units or transforms wrong?");
        }
    }
    out.size = character_size(ch);

    // The chains, by the first rule that applies (see the header).
    std::vector<Candidate> candidates;
    std::vector<VrmCollider> vrm_colliders;
    const auto from_search = [&](const ChainSearch& search) -> Result<void> {
        auto found = find_chains(ch, search);
        if (!found) return found.error();
        for (FoundChain& c : found.value().chains) {
            Candidate k;
            k.physics = scaled_physics(ch, c);
            k.chain = std::move(c);
            candidates.push_back(std::move(k));
        }
        out.warnings.insert(out.warnings.end(), found.value().warnings.begin(), found.value().warnings.end());
        return {};
    };
    if (options.search) {
        out.source = options.search->roots.empty() ? "name patterns" : "named roots";
        KW_TRY(from_search(*options.search));
    } else {
        auto springs = read_vrm_springs(ch);
        if (!springs) return springs.error();
        VrmSprings& vrm = springs.value();
        out.warnings.insert(out.warnings.end(), vrm.warnings.begin(), vrm.warnings.end());
        if (!vrm.springs.empty()) {
            out.source = vrm.version == 2 ? "VRM 1.0 spring bones" : "VRM 0.x secondaryAnimation";
            for (VrmSpring& s : vrm.springs) {
                Candidate k;
                k.chain = std::move(s.chain);
                k.physics = s.physics;
                k.params = s.params;
                k.colliders = s.colliders;
                k.center = s.center;
                k.limits = s.limits;
                candidates.push_back(std::move(k));
            }
            vrm_colliders = std::move(vrm.colliders);
        } else {
            out.source = "name patterns";
            KW_TRY(from_search(ChainSearch{}));
        }
    }

    // Chains the scene can express: nameable nodes, one chain per joint, at most 64.
    Json chains = Json::array();
    std::set<int> used_nodes;
    std::set<std::string> used_names;
    std::vector<const Candidate*> written;  // per chain of `chains`
    for (const Candidate& k : candidates) {
        const FoundChain& c = k.chain;
        const auto shared = std::find_if(c.nodes.begin(), c.nodes.end(), [&](int n) { return used_nodes.count(n) != 0; });
        if (shared != c.nodes.end()) {
            out.warnings.push_back(ch.source + ": chain \"" + c.name + "\" skipped: node " + node_label(ch, *shared) +
                                   " is in a chain already");
            continue;
        }
        if (chains.size() == 64) {
            out.warnings.push_back(ch.source + ": chain \"" + c.name + "\" and later ones skipped: a character has at most 64 chains");
            break;
        }
        std::string name = scene_name(c.name);
        for (int suffix = 2; used_names.count(name) != 0; ++suffix) name = scene_name(c.name) + "_" + std::to_string(suffix);
        used_names.insert(name);
        used_nodes.insert(c.nodes.begin(), c.nodes.end());

        Json j;
        j["name"] = name;
        // "root" + "joints" when the walk down single children gives these nodes, else the list.
        bool walk = true;
        for (std::size_t i = 0; i + 1 < c.nodes.size(); ++i) {
            const animation::Node& n = ch.nodes[static_cast<std::size_t>(c.nodes[i])];
            walk = walk && n.children.size() == 1 && n.children.front() == c.nodes[i + 1];
        }
        if (walk) {
            j["root"] = refs[static_cast<std::size_t>(c.nodes.front())];
            j["joints"] = c.nodes.size();
        } else {
            Json list = Json::array();
            for (const int n : c.nodes) list.push_back(refs[static_cast<std::size_t>(n)]);
            j["nodes"] = list;
        }
        j["thickness"] = num_at_most(k.physics.thickness);
        j["mass"] = num(k.physics.mass);
        if (k.params) {
            Json physics;
            physics["gravity"] = vec(k.params->gravity);
            // Every parameter the mapping sets: a member left out reads as SolverParams'
            // default, and stiffness's (0.5) is shape matching VRM does not have (vrm.hpp).
            physics["stiffness"] = num(k.params->stiffness);
            physics["rest_stiffness"] = num(k.params->rest_stiffness);
            physics["damping"] = num(k.params->damping);
            j["physics"] = physics;
        }
        if (k.center >= 0) j["center"] = refs[static_cast<std::size_t>(k.center)];
        if (!k.limits.empty()) {
            Json limits = Json::array();
            for (const rods::AngleLimit& l : k.limits) limits.push_back(limit_json(l));
            j["limit"] = limits;
        }
        chains.push_back(j);
        written.push_back(&k);
        out.chains.push_back(RigChain{name, ch.nodes[static_cast<std::size_t>(c.nodes.front())].name.empty()
                                                ? "node " + std::to_string(c.nodes.front())
                                                : ch.nodes[static_cast<std::size_t>(c.nodes.front())].name,
                                      static_cast<std::uint32_t>(c.nodes.size()), c.length, k.physics.thickness});
    }
    if (chains.empty()) {
        return make_error(Error::Kind::InvalidInput,
                          ch.source + ": no chain found (" + out.source +
                              "); name the chains' roots or name patterns (`kodawari rig --roots` or `--chains`; "
                              "RigOptions::search in C++)");
    }

    // Colliders, in their node's rigid frame at rest (docs/scene-format.md), metres, named
    // by their index in the file ("collider3") for the chains' lists.
    Json colliders = Json::array();
    std::vector<std::string> collider_name(vrm_colliders.size());  // "" for one skipped
    for (std::size_t i = 0; i < vrm_colliders.size(); ++i) {
        const VrmCollider& c = vrm_colliders[i];
        const std::string what = ch.source + ": collider " + std::to_string(i);
        const glm::mat4& world = rest.world[static_cast<std::size_t>(c.node)];
        const float radius = c.radius * max_scale(world);
        if (c.kind != rods::ColliderKind::Plane && !(radius > 0.0f)) {
            out.warnings.push_back(what + " skipped: radius 0");
            continue;
        }
        // A plane's normal turns by the inverse transpose of the node's linear part (exact
        // under non-uniform scale); a node scaled to 0 along an axis has none, and its
        // plane no direction.
        const glm::mat3 linear(world);
        const glm::vec3 turned = glm::transpose(glm::inverse(linear)) * c.normal;
        if (c.kind == rods::ColliderKind::Plane &&
            !(std::abs(glm::determinant(linear)) > 0.0f && std::isfinite(glm::length(turned)) && glm::length(turned) > 0.0f)) {
            out.warnings.push_back(what + " skipped: a plane on a node scaled to 0 along an axis has no normal");
            continue;
        }
        if (colliders.size() == rods::kMaxCharacterColliders) {
            out.warnings.push_back(what + " and later ones skipped: a character has at most " +
                                   std::to_string(rods::kMaxCharacterColliders) + " colliders");
            break;
        }
        const rods::Transform frame = animation::rigid_part(world);
        const glm::quat inverse = glm::inverse(frame.rotation);
        const auto local = [&](glm::vec3 p) { return inverse * (glm::vec3(world * glm::vec4(p, 1.0f)) - frame.position); };
        const glm::vec3 a = local(c.offset);
        const glm::vec3 b = local(c.tail);
        const float reach = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z), std::abs(b.x), std::abs(b.y), std::abs(b.z)});
        if (!(reach <= kMaxColliderReach && radius <= kMaxColliderReach)) {
            out.warnings.push_back(what + " skipped: it lies " + std::to_string(std::max(reach, radius)) +
                                   " m from its node; scenes allow " + std::to_string(static_cast<int>(kMaxColliderReach)) + " m");
            continue;
        }
        Json j;
        collider_name[i] = "collider" + std::to_string(i);
        j["name"] = collider_name[i];
        j["joint"] = refs[static_cast<std::size_t>(c.node)];
        if (c.kind == rods::ColliderKind::Plane) {
            // The normal turned above, then into the rigid frame.
            const glm::vec3 n = glm::normalize(turned);
            j["type"] = "plane";
            j["point"] = vec(a);
            j["normal"] = vec(glm::normalize(inverse * n));
        } else {
            j["type"] = c.capsule ? "capsule" : "sphere";
            if (c.capsule) {
                j["a"] = vec(a);
                j["b"] = vec(b);
            } else {
                j["center"] = vec(a);
            }
            j["radius"] = num(radius);
            if (c.kind == rods::ColliderKind::Inside) j["inside"] = true;
        }
        colliders.push_back(j);
    }
    out.colliders = static_cast<std::uint32_t>(colliders.size());
    // Each VRM spring collides with its own collider groups; a chain lists its colliders
    // unless it has all of them (and that many fit one chain).
    for (std::size_t i = 0; i < written.size(); ++i) {
        const Candidate& k = *written[i];
        if (!k.params) continue;  // found by name patterns: all colliders, as before
        Json list = Json::array();
        for (const std::size_t c : k.colliders) {
            if (collider_name[c].empty()) continue;
            if (list.size() == rods::kMaxChainColliders) {
                out.warnings.push_back(ch.source + ": chain \"" + chains[i]["name"].get<std::string>() + "\" keeps the first " +
                                       std::to_string(rods::kMaxChainColliders) + " of its " + std::to_string(k.colliders.size()) +
                                       " colliders (one chain touches at most that many)");
                break;
            }
            list.push_back(collider_name[c]);
        }
        if (list.size() != colliders.size() || colliders.size() > rods::kMaxChainColliders) {
            if (list.empty()) {
                chains[i]["collide"] = false;
            } else {
                chains[i]["colliders"] = list;
            }
        }
    }

    // The reference joint: "head", the VRM humanoid head, else what the first chain hangs from.
    int reference = -1;
    for (std::size_t i = 0; i < ch.nodes.size() && reference < 0; ++i) {
        if (lower(ch.nodes[i].name) == "head" && refs[i].is_string()) reference = static_cast<int>(i);
    }
    if (reference < 0) {
        const int head = vrm_humanoid_bone(ch, "head");
        if (head >= 0) reference = head;
    }
    if (reference < 0) {
        const FoundChain& first = candidates.front().chain;
        reference = first.parent >= 0 ? first.parent : first.nodes.front();
        out.warnings.push_back(ch.source + ": no \"head\" node and no VRM humanoid head: view directions are measured in " +
                               node_label(ch, reference) + " (change \"reference_joint\" in the scene if that is wrong)");
    }
    out.reference = ch.nodes[static_cast<std::size_t>(reference)].name;

    if (!options.clip.empty()) {
        const auto it = std::find_if(ch.animations.begin(), ch.animations.end(), [&](const animation::Animation& a) { return a.name == options.clip; });
        if (it == ch.animations.end()) {
            std::string names;
            for (const animation::Animation& a : ch.animations) names += (names.empty() ? "\"" : ", \"") + a.name + "\"";
            return make_error(Error::Kind::InvalidInput, ch.source + ": no animation is called \"" + options.clip + "\" (" +
                                                             (names.empty() ? std::string("the file has none") : names) + ")");
        }
        out.clip = options.clip;
    } else if (!out.motions.empty()) {
        out.clip = out.motions.front().name;
    } else if (!ch.animations.empty()) {
        out.clip = ch.animations.front().name;
    }

    // The scene: the character once at the origin, the camera orbiting its head.
    const std::string file = fs::absolute(fs::path(character_path)).lexically_relative(scene_dir).generic_string();
    const std::string stem = fs::path(character_path).stem().string();
    // The character's and the scene's name, which names the bake's files too.
    const std::string name = as_scene_name(scene_name(options.name.empty() ? stem : options.name), "character");
    const glm::vec3 head = glm::vec3(rest.world[static_cast<std::size_t>(reference)][3]);
    Json character;
    character["name"] = name;
    character["gltf"] = file;
    character["reference_joint"] = refs[static_cast<std::size_t>(reference)];
    if (!out.clip.empty()) {
        character["animation"] = out.clip;
    } else {
        character["animate"] = false;
    }
    if (!motions.empty()) character["motions"] = motions;
    if (!colliders.empty()) character["colliders"] = colliders;
    character["chains"] = chains;
    Json scene;
    scene["format"] = "kodawari-scene";
    scene["version"] = 2;
    scene["name"] = name;
    scene["fps"] = 60;
    scene["duration"] = num(options.duration);
    Json orbit;
    orbit["target"] = vec(head);
    orbit["radius"] = num(std::clamp(1.5f * out.size, 0.5f, kMaxJointReach));
    orbit["height"] = 0;
    orbit["degrees_per_second"] = 30;
    scene["camera"] = Json{{"orbit", orbit}};
    scene["characters"] = Json::array({character});
    out.json = compact_number_arrays(scene.dump(2)) + "\n";
    return out;
}

}  // namespace kodawari::gltf
