// VRM spring bones as rods chains (SPEC A.7, issue 4). The JSON is read here, not by
// tinygltf, because tinygltf keeps extensions as loosely typed values; every field read
// is checked, and problems name the file and the JSON path. The mapping of parameters is
// documented in vrm.hpp.

#include "kodawari/gltf/vrm.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf/vrm_reader.hpp"

namespace kodawari::gltf {
namespace vrm_detail {

constexpr float kMinThickness = 1e-4f;  // as scaled_physics()
constexpr float kMaxGravity = 1000.0f;  // m/s^2, the scene format's bound on an acceleration component

Result<VrmSprings> Reader::read() {
    if (c_.extensions.empty()) return std::move(out_);
    json root;
    try {
        root = json::parse(c_.extensions);
    } catch (const std::exception& e) {
        return invalid("$.extensions", std::string("invalid JSON: ") + e.what());
    }
    if (!root.is_object()) return std::move(out_);
    if (const auto it = root.find("VRMC_springBone"); it != root.end()) {
        out_.version = 2;
        KW_TRY(read_1(*it, "$.extensions.VRMC_springBone"));
    } else if (const auto vrm = root.find("VRM"); vrm != root.end() && vrm->is_object() &&
                                                   vrm->contains("secondaryAnimation")) {
        out_.version = 1;
        KW_TRY(read_0((*vrm)["secondaryAnimation"], "$.extensions.VRM.secondaryAnimation"));
    }
    return std::move(out_);
}

// The chain of `nodes` with `bones` (the settings of each bone: every joint but the
// tail), truncated and checked, added to out_. `path` names the spring.
Result<void> Reader::add_chain(std::vector<int> nodes, std::vector<Settings> bones, std::vector<std::size_t> colliders, int center,
                               const std::string& path) {
    if (nodes.size() < 2) {
        warn(path, "a spring of " + std::to_string(nodes.size()) + " joint(s) has no bone; skipped");
        return {};
    }
    if (nodes.size() > rods::kMaxChainJoints) {
        warn(path, std::to_string(nodes.size()) + " joints; kept the first " + std::to_string(rods::kMaxChainJoints) +
                       ", node " + std::to_string(nodes[rods::kMaxChainJoints]) + " and below stay kinematic");
        nodes.resize(rods::kMaxChainJoints);
        bones.resize(rods::kMaxChainJoints - 1);
    }
    auto chain = make_found_chain(c_, rest_, std::move(nodes));
    if (!chain) return chain.error();

    VrmSpring spring;
    spring.chain = std::move(chain).value();
    // Angle limits, one per bone (VRMC_springBone_limit), where any bone has one.
    if (std::any_of(bones.begin(), bones.end(), [](const Settings& b) { return b.limit.kind != rods::LimitKind::None; })) {
        for (const Settings& b : bones) spring.limits.push_back(b.limit);
    }
    Settings mean;
    mean.gravity_dir = glm::vec3(0.0f);  // accumulates gravityPower * gravityDir
    mean.hit_radius = mean.stiffness = mean.drag = 0.0f;
    for (const Settings& s : bones) {
        mean.hit_radius += s.hit_radius;
        mean.stiffness += s.stiffness;
        mean.drag += s.drag;
        mean.gravity_dir += s.gravity_power * s.gravity_dir;
    }
    const auto n = static_cast<float>(bones.size());
    const float segment = spring.chain.length / static_cast<float>(spring.chain.nodes.size() - 1);
    // The stiffnesses are fractions per rods::kReferenceSubstep, whatever the substep
    // (rods::substep_stiffness), so the calibration holds at every frame rate.
    const float h = rods::kReferenceSubstep;
    const float a = kVrmFrameRate * h * h * (mean.stiffness / n);
    spring.params.rest_stiffness = a / (a + segment);
    spring.params.stiffness = 0.0f;  // VRM has no shape matching (vrm.hpp)
    const float drag = std::clamp(mean.drag / n, 0.0f, kMaxDragForce);
    spring.params.damping = -std::log(1.0f - drag) * kVrmFrameRate;
    // The solver damps the velocity before adding gravity, as VRM's verlet step damps
    // the inertia term and not the gravity term, so the equilibrium sags agree without
    // a correction (vrm.hpp).
    spring.params.gravity = kVrmFrameRate * mean.gravity_dir / n;
    // The scene format takes accelerations up to kMaxGravity (100 g) a component; VRM's
    // gravityPower has no bound, so a strong one is held there rather than refused.
    if (const float g = glm::length(spring.params.gravity); g > kMaxGravity) {
        spring.params.gravity *= kMaxGravity / g;
        warn(path, "gravity " + std::to_string(g) + " m/s^2 (gravityPower, mapped) held at " + std::to_string(kMaxGravity) +
                       " m/s^2, the scene format's bound");
    }
    spring.hit_radius = mean.hit_radius / n;

    spring.physics = scaled_physics(c_, spring.chain);
    if (spring.hit_radius > 0.0f) {
        const glm::mat4& world = rest_.world[static_cast<std::size_t>(spring.chain.nodes.front())];
        const float scale = std::max({glm::length(glm::vec3(world[0])), glm::length(glm::vec3(world[1])),
                                      glm::length(glm::vec3(world[2]))});
        float shortest = spring.chain.length;
        for (std::size_t i = 1; i < spring.chain.base.positions.size(); ++i) {
            shortest = std::min(shortest, glm::length(spring.chain.base.positions[i] - spring.chain.base.positions[i - 1]));
        }
        const float thickness = std::min(std::max(spring.hit_radius * scale, kMinThickness), 0.5f * shortest);
        // Same cylinder mass as scaled_physics(), at the new thickness.
        spring.physics.mass *= (thickness * thickness) / (spring.physics.thickness * spring.physics.thickness);
        spring.physics.thickness = thickness;
        spring.physics = clamped(spring.physics);
    }
    std::sort(colliders.begin(), colliders.end());
    colliders.erase(std::unique(colliders.begin(), colliders.end()), colliders.end());
    spring.colliders = std::move(colliders);
    spring.center = center;
    out_.springs.push_back(std::move(spring));
    return {};
}

// VRMC_springBone 1.0.
Result<void> Reader::read_1(const json& ext, const std::string& path) {
    if (!ext.is_object()) return invalid(path, "expected an object");
    auto colliders = array(ext, "colliders", path, false);
    if (!colliders) return colliders.error();
    if (colliders.value() != nullptr) {
        for (std::size_t i = 0; i < colliders.value()->size(); ++i) {
            KW_TRY(read_collider_1((*colliders.value())[i], at(path + ".colliders", i)));
        }
    }
    // Collider groups: lists of collider indices.
    std::vector<std::vector<std::size_t>> groups;
    auto group_list = array(ext, "colliderGroups", path, false);
    if (!group_list) return group_list.error();
    if (group_list.value() != nullptr) {
        for (std::size_t g = 0; g < group_list.value()->size(); ++g) {
            const json& group = (*group_list.value())[g];
            const std::string gp = at(path + ".colliderGroups", g);
            if (!group.is_object()) return invalid(gp, "expected an object");
            auto members = array(group, "colliders", gp, true);
            if (!members) return members.error();
            std::vector<std::size_t> list;
            for (std::size_t k = 0; k < members.value()->size(); ++k) {
                auto i = index_value((*members.value())[k], at(gp + ".colliders", k), out_.colliders.size(), "collider");
                if (!i) return i.error();
                list.push_back(i.value());
            }
            groups.push_back(std::move(list));
        }
    }
    auto springs = array(ext, "springs", path, false);
    if (!springs) return springs.error();
    if (springs.value() == nullptr) return {};
    const Settings defaults;  // VRMC_springBone 1.0: hitRadius 0, stiffness 1, gravity 0 along -Y, drag 0.5
    for (std::size_t s = 0; s < springs.value()->size(); ++s) {
        const json& spring = (*springs.value())[s];
        const std::string sp = at(path + ".springs", s);
        if (!spring.is_object()) return invalid(sp, "expected an object");
        auto joints = array(spring, "joints", sp, true);
        if (!joints) return joints.error();
        std::vector<int> nodes;
        std::vector<Settings> bones;
        for (std::size_t j = 0; j < joints.value()->size(); ++j) {
            const json& joint = (*joints.value())[j];
            const std::string jp = at(sp + ".joints", j);
            if (!joint.is_object()) return invalid(jp, "expected an object");
            auto node = index(joint, "node", jp, c_.nodes.size(), "node");
            if (!node) return node.error();
            const int n = static_cast<int>(node.value());
            if (!nodes.empty() && c_.nodes[node.value()].parent != nodes.back()) {
                return invalid(jp, "node " + std::to_string(n) + " is not a child of node " +
                                       std::to_string(nodes.back()) + " (the joint before it); a spring's joints must form a parent-to-child path");
            }
            auto settings_j = settings(joint, jp, defaults, false);
            if (!settings_j) return settings_j.error();
            // The last joint's limit is ignored, as the draft says it MUST be (the tail
            // has no child to limit); its settings are dropped below.
            auto limit_j = limit(joint, jp);
            if (!limit_j) return limit_j.error();
            settings_j.value().limit = limit_j.value();
            nodes.push_back(n);
            bones.push_back(settings_j.value());
        }
        if (!bones.empty()) bones.pop_back();  // the tail's settings move nothing in VRM 1.0
        std::vector<std::size_t> members;
        auto spring_groups = array(spring, "colliderGroups", sp, false);
        if (!spring_groups) return spring_groups.error();
        if (spring_groups.value() != nullptr) {
            for (std::size_t k = 0; k < spring_groups.value()->size(); ++k) {
                auto g = index_value((*spring_groups.value())[k], at(sp + ".colliderGroups", k), groups.size(), "collider group");
                if (!g) return g.error();
                members.insert(members.end(), groups[g.value()].begin(), groups[g.value()].end());
            }
        }
        int center = -1;
        if (spring.contains("center")) {
            auto c = index(spring, "center", sp, c_.nodes.size(), "node");
            if (!c) return c.error();
            center = static_cast<int>(c.value());
        }
        KW_TRY(add_chain(std::move(nodes), std::move(bones), std::move(members), center, sp));
    }
    return {};
}

// VRM 0.x secondaryAnimation.
Result<void> Reader::read_0(const json& secondary, const std::string& path) {
    if (!secondary.is_object()) return invalid(path, "expected an object");
    std::vector<std::vector<std::size_t>> groups;
    auto group_list = array(secondary, "colliderGroups", path, false);
    if (!group_list) return group_list.error();
    if (group_list.value() != nullptr) {
        for (std::size_t g = 0; g < group_list.value()->size(); ++g) {
            const json& group = (*group_list.value())[g];
            const std::string gp = at(path + ".colliderGroups", g);
            if (!group.is_object()) return invalid(gp, "expected an object");
            auto node = index(group, "node", gp, c_.nodes.size(), "node");
            if (!node) return node.error();
            auto members = array(group, "colliders", gp, false);
            if (!members) return members.error();
            std::vector<std::size_t> list;
            for (std::size_t k = 0; members.value() != nullptr && k < members.value()->size(); ++k) {
                const json& collider = (*members.value())[k];
                const std::string cp = at(gp + ".colliders", k);
                if (!collider.is_object()) return invalid(cp, "expected an object");
                auto offset = vec3_object(collider, "offset", cp, glm::vec3(0.0f));
                auto r = radius(collider, cp, 0.0f);
                if (!offset) return offset.error();
                if (!r) return r.error();
                VrmCollider out;
                out.node = static_cast<int>(node.value());
                out.offset = out.tail = offset.value() * glm::vec3(1.0f, 1.0f, -1.0f);  // stored z-negated (UniVRM 0.x)
                out.radius = r.value();
                list.push_back(out_.colliders.size());
                out_.colliders.push_back(out);
            }
            groups.push_back(std::move(list));
        }
    }
    auto bone_groups = array(secondary, "boneGroups", path, false);
    if (!bone_groups) return bone_groups.error();
    if (bone_groups.value() == nullptr) return {};
    Settings defaults;  // UniVRM 0.x VRMSpringBone defaults
    defaults.hit_radius = 0.02f;
    defaults.drag = 0.4f;
    std::vector<bool> claimed(c_.nodes.size(), false);
    for (std::size_t b = 0; b < bone_groups.value()->size(); ++b) {
        const json& group = (*bone_groups.value())[b];
        const std::string bp = at(path + ".boneGroups", b);
        if (!group.is_object()) return invalid(bp, "expected an object");
        auto s = settings(group, bp, defaults, true);
        if (!s) return s.error();
        std::vector<std::size_t> members;
        auto group_refs = array(group, "colliderGroups", bp, false);
        if (!group_refs) return group_refs.error();
        for (std::size_t k = 0; group_refs.value() != nullptr && k < group_refs.value()->size(); ++k) {
            auto g = index_value((*group_refs.value())[k], at(bp + ".colliderGroups", k), groups.size(), "collider group");
            if (!g) return g.error();
            members.insert(members.end(), groups[g.value()].begin(), groups[g.value()].end());
        }
        // UniVRM 0.x writes -1 for "no center".
        int center = -1;
        if (const auto it = group.find("center"); it != group.end() && !(it->is_number_integer() && it->get<long long>() == -1)) {
            auto c = index_value(*it, bp + ".center", c_.nodes.size(), "node");
            if (!c) return c.error();
            center = static_cast<int>(c.value());
        }
        auto bones = array(group, "bones", bp, false);
        if (!bones) return bones.error();
        for (std::size_t k = 0; bones.value() != nullptr && k < bones.value()->size(); ++k) {
            const std::string rp = at(bp + ".bones", k);
            auto root = index_value((*bones.value())[k], rp, c_.nodes.size(), "node");
            if (!root) return root.error();
            // The subtree below the root: single-child runs are chains; a branch ends
            // one and starts one per child.
            std::vector<int> starts{static_cast<int>(root.value())};
            while (!starts.empty()) {
                const int start = starts.back();
                starts.pop_back();
                if (claimed[static_cast<std::size_t>(start)]) {
                    warn(rp, "node " + std::to_string(start) + " is already in a chain; skipped");
                    continue;
                }
                std::vector<int> nodes{start};
                while (c_.nodes[static_cast<std::size_t>(nodes.back())].children.size() == 1) {
                    nodes.push_back(c_.nodes[static_cast<std::size_t>(nodes.back())].children.front());
                }
                const std::vector<int>& branch = c_.nodes[static_cast<std::size_t>(nodes.back())].children;
                starts.insert(starts.end(), branch.rbegin(), branch.rend());  // file order, first child first
                for (const int node : nodes) claimed[static_cast<std::size_t>(node)] = true;
                std::vector<Settings> per_bone(nodes.size() > 1 ? nodes.size() - 1 : 0, s.value());
                KW_TRY(add_chain(std::move(nodes), std::move(per_bone), members, center,
                                 rp + " (chain from node " + std::to_string(start) + ")"));
            }
        }
    }
    return {};
}

}  // namespace vrm_detail

using vrm_detail::json;
using vrm_detail::Reader;

Result<VrmSprings> read_vrm_springs(const animation::Character& character) {
    try {
        return Reader(character).read();
    } catch (const std::exception& e) {
        // nlohmann throws on what the checks above missed; report it, never throw.
        return make_error(Error::Kind::InvalidInput, character.source + ": $.extensions: " + e.what());
    }
}

}  // namespace kodawari::gltf

namespace kodawari::gltf {

int vrm_humanoid_bone(const animation::Character& character, std::string_view bone) {
    if (character.extensions.empty()) return -1;
    const json ext = json::parse(character.extensions, nullptr, /*allow_exceptions=*/false);
    if (!ext.is_object()) return -1;
    const auto in_range = [&](const json& v) {
        return v.is_number_integer() && v.get<std::int64_t>() >= 0 &&
               v.get<std::int64_t>() < static_cast<std::int64_t>(character.nodes.size());
    };
    const std::string key(bone);
    if (const auto vrm1 = ext.find("VRMC_vrm"); vrm1 != ext.end() && vrm1->is_object()) {
        const json* bones = nullptr;
        if (const auto h = vrm1->find("humanoid"); h != vrm1->end() && h->is_object()) {
            if (const auto b = h->find("humanBones"); b != h->end() && b->is_object()) bones = &*b;
        }
        if (bones != nullptr) {
            if (const auto entry = bones->find(key); entry != bones->end() && entry->is_object()) {
                if (const auto node = entry->find("node"); node != entry->end() && in_range(*node)) return node->get<int>();
            }
        }
    }
    if (const auto vrm0 = ext.find("VRM"); vrm0 != ext.end() && vrm0->is_object()) {
        if (const auto h = vrm0->find("humanoid"); h != vrm0->end() && h->is_object()) {
            if (const auto b = h->find("humanBones"); b != h->end() && b->is_array()) {
                for (const json& entry : *b) {
                    if (!entry.is_object()) continue;
                    const auto name = entry.find("bone");
                    const auto node = entry.find("node");
                    if (name != entry.end() && name->is_string() && name->get<std::string>() == key && node != entry.end() &&
                        in_range(*node)) {
                        return node->get<int>();
                    }
                }
            }
        }
    }
    return -1;
}

}  // namespace kodawari::gltf
