// The version-2 scene keys (docs/scene-format.md, "Characters", "Crowds"; the moving
// camera is read in camera_loader.cpp, the chains in chain_loader.cpp): every value is checked here, with its JSON path, so that a scene that loads
// is one build_rod_scene can turn into a RodWorld. Names are resolved to indices and
// mirrored chains are expanded here; shapes are checked by building their chain
// template once (make_chain_template), so a bad shape is reported where it is written.

#include "scene/character_loader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <kodawari/rods/world.hpp>

namespace kodawari::scene_detail {

using Vec3 = glm::vec3;

Vec3 to_vec(const std::array<float, 3>& a) { return Vec3(a[0], a[1], a[2]); }

Result<Vec3> read_point(const JsonReader& r, const JsonNode& node, double limit) {
    std::array<float, 3> a{};
    KW_SCENE_ASSIGN(a, r.vec3(node, NumberRange::closed(-limit, limit)));
    return to_vec(a);
}

// A direction: any finite non-zero vector, normalized.
Result<Vec3> read_direction(const JsonReader& r, const JsonNode& node) {
    Vec3 v{};
    KW_SCENE_ASSIGN(v, read_point(r, node, kMaxCoordinate));
    const float length = glm::length(v);
    if (!(length > 1e-6f)) return r.expected(node, "a non-zero vector [x, y, z]");
    return v / length;
}

Result<float> read_degrees(const JsonReader& r, const JsonNode& node, const NumberRange& range) {
    double degrees = 0.0;
    KW_SCENE_ASSIGN(degrees, r.number(node, range));
    return static_cast<float>(degrees * kDegToRad);
}

Result<float> read_time(const JsonReader& r, const JsonNode& node) {
    return r.real(node, NumberRange::closed(0.0, kMaxTime));
}

// Names become parts of "bunny#12/ear_l", so they may not contain the separators.
Result<std::string> read_name(const JsonReader& r, const JsonNode& node) {
    std::string name;
    KW_SCENE_ASSIGN(name, r.string(node));
    if (name.find_first_of("#/") != std::string::npos) {
        return r.expected(node, "a non-empty name without '#' or '/'");
    }
    return name;
}

std::string quoted_list(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) {
        if (!out.empty()) out += ", ";
        out += "\"" + n + "\"";
    }
    return out;
}

Result<std::uint32_t> find_name(const JsonReader& r, const JsonNode& node, const std::vector<std::string>& names,
                                const std::string& what) {
    std::string name;
    KW_SCENE_ASSIGN(name, r.string(node));
    const auto found = std::find(names.begin(), names.end(), name);
    if (found != names.end()) return static_cast<std::uint32_t>(found - names.begin());
    return r.expected(node, what + " (" + quoted_list(names) + ")");
}

// An array of at most `max` elements; `what` describes a valid one.
Result<std::size_t> read_array(const JsonReader& r, const JsonNode& node, std::size_t min, std::size_t max,
                               const std::string& what) {
    std::size_t size = 0;
    KW_SCENE_ASSIGN(size, r.array(node, what));
    if (size < min || size > max) return r.expected(node, what);
    return size;
}

Result<glm::quat> read_rotation(const JsonReader& r, const JsonNode& node) {
    KW_TRY(r.object(node, {"axis", "angle_deg"}));
    Vec3 axis{};
    KW_SCENE_ASSIGN(axis, read_direction(r, r.member(node, "axis")));
    float angle = 0.0f;
    KW_SCENE_ASSIGN(angle, read_degrees(r, r.member(node, "angle_deg"), NumberRange::closed(-3600.0, 3600.0)));
    return glm::angleAxis(angle, axis);
}

// {"position": [x, y, z], "rotation": {"axis": [...], "angle_deg": a}}, both optional.
Result<rods::Transform> read_transform(const JsonReader& r, const JsonNode& node) {
    KW_TRY(r.object(node, {"position", "rotation"}));
    rods::Transform t;
    KW_TRY(optional_member(r, node, "position", t.position, [&](const JsonNode& n) { return read_point(r, n, kMaxLocal); }));
    KW_TRY(optional_member(r, node, "rotation", t.rotation, [&](const JsonNode& n) { return read_rotation(r, n); }));
    return t;
}

// The index of the joint called `name`, or an error at `node` listing the joints.
Result<std::uint32_t> find_joint(const JsonReader& r, const JsonNode& node, const rods::Skeleton& skeleton) {
    std::vector<std::string> names;
    for (const auto& joint : skeleton.joints) names.push_back(joint.name);
    return find_name(r, node, names, "the name of a joint of this character's skeleton");
}

// The skeleton: joints in any order, each naming its parent; exactly one root. Stored
// parents first (file order where that already holds), as pose_skeleton needs.
Result<rods::Skeleton> read_skeleton(const JsonReader& r, const JsonNode& node) {
    const std::string what = "an array of 1 to " + std::to_string(kMaxPerCharacter) + " joints";
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, node, 1, kMaxPerCharacter, what));
    std::vector<rods::SkeletonJoint> joints(n);
    std::vector<std::string> parents(n);
    for (std::size_t j = 0; j < n; ++j) {
        const JsonNode joint = r.element(node, j);
        KW_TRY(r.object(joint, {"name", "parent", "position", "rotation"}));
        const JsonNode name = r.member(joint, "name");
        KW_SCENE_ASSIGN(joints[j].name, read_name(r, name));
        for (std::size_t k = 0; k < j; ++k) {
            if (joints[k].name == joints[j].name) {
                return r.expected(name, "a name no other joint has (joint " + std::to_string(k) + " is also \"" +
                                            joints[j].name + "\")");
            }
        }
        KW_TRY(optional_member(r, joint, "parent", parents[j], [&](const JsonNode& p) { return r.string(p); }));
        KW_TRY(optional_member(r, joint, "position", joints[j].rest.position,
                               [&](const JsonNode& p) { return read_point(r, p, kMaxLocal); }));
        KW_TRY(optional_member(r, joint, "rotation", joints[j].rest.rotation,
                               [&](const JsonNode& p) { return read_rotation(r, p); }));
    }
    // Resolve parent names to file indices.
    std::vector<std::int32_t> parent(n, -1);
    std::size_t root = n;
    for (std::size_t j = 0; j < n; ++j) {
        const JsonNode joint = r.element(node, j);
        if (parents[j].empty()) {
            if (root != n) {
                return r.expected(r.member(joint, "parent"),
                                  "the name of the parent joint (a skeleton has one root, and joint " + std::to_string(root) +
                                      " \"" + joints[root].name + "\" already is it)");
            }
            root = j;
            continue;
        }
        bool found = false;
        for (std::size_t k = 0; k < n && !found; ++k) {
            if (joints[k].name == parents[j]) {
                parent[j] = static_cast<std::int32_t>(k);
                found = true;
            }
        }
        if (!found) {
            std::vector<std::string> others;
            for (std::size_t k = 0; k < n; ++k) {
                if (k != j) others.push_back(joints[k].name);
            }
            return r.expected(r.member(joint, "parent"), "the name of another joint of this skeleton (" + quoted_list(others) + ")");
        }
    }
    if (root == n) {
        return r.fail(node.path, "expected one joint without a \"parent\" (the root), got none: the parents form a cycle");
    }
    // Parents first: the root, then breadth first by file order.
    std::vector<std::size_t> order = {root};
    std::vector<bool> placed(n, false);
    placed[root] = true;
    for (std::size_t i = 0; i < order.size(); ++i) {
        for (std::size_t k = 0; k < n; ++k) {
            if (!placed[k] && parent[k] == static_cast<std::int32_t>(order[i])) {
                placed[k] = true;
                order.push_back(k);
            }
        }
    }
    if (order.size() != n) {
        // A joint not reached from the root lies on (or below) a cycle: name the cycle.
        std::size_t j = 0;
        while (placed[j]) ++j;
        std::vector<bool> seen(n, false);
        while (!seen[j]) {
            seen[j] = true;
            j = static_cast<std::size_t>(parent[j]);
        }
        std::string cycle = "\"" + joints[j].name + "\"";
        for (std::size_t k = static_cast<std::size_t>(parent[j]); k != j; k = static_cast<std::size_t>(parent[k])) {
            cycle += " -> \"" + joints[k].name + "\"";
        }
        return r.fail(r.member(r.element(node, j), "parent").path,
                      "expected a parent chain that reaches the root joint, got a cycle: " + cycle + " -> \"" + joints[j].name + "\"");
    }
    std::vector<std::int32_t> new_index(n, -1);
    for (std::size_t i = 0; i < n; ++i) new_index[order[i]] = static_cast<std::int32_t>(i);
    rods::Skeleton skeleton;
    for (const std::size_t j : order) {
        rods::SkeletonJoint joint = joints[j];
        joint.parent = parent[j] < 0 ? -1 : new_index[static_cast<std::size_t>(parent[j])];
        skeleton.joints.push_back(std::move(joint));
    }
    return skeleton;
}

// start and end of a motion: end (or stop_time) after start.
Result<void> read_interval(const JsonReader& r, const JsonNode& node, const char* end_key, bool end_required, float& start,
                           float& end) {
    KW_TRY(optional_member(r, node, "start", start, [&](const JsonNode& n) { return read_time(r, n); }));
    const JsonNode end_node = r.member(node, end_key);
    if (!end_node.present() && !end_required) return {};
    double value = 0.0;
    // A start at kMaxTime leaves no time after it: say so rather than print (1e5, 1e5].
    if (!(static_cast<double>(start) < kMaxTime)) {
        return r.fail(r.member(node, "start").path, "expected a time before " + format_number(kMaxTime) + " s, so that \"" +
                                                        end_key + "\" can come after it, got " + format_number(start));
    }
    KW_SCENE_ASSIGN(value, r.number(end_node, NumberRange::left_open(static_cast<double>(start), kMaxTime)));
    end = static_cast<float>(value);
    if (!(end > start)) return r.expected(end_node, "a time after \"start\" (" + format_number(start) + " s)");
    return {};
}

// One procedural motion; the keys depend on its type.
Result<void> read_motion(const JsonReader& r, const JsonNode& node, const rods::Skeleton& skeleton, rods::CharacterMotion& motion) {
    if (!node.present() || !node.value->is_object()) {
        return r.expected(node, "an object with \"type\": \"sway\", \"head_turn\", \"walk\" or \"stop\"");
    }
    std::size_t type = 0;
    KW_SCENE_ASSIGN(type, r.choice(r.member(node, "type"), {"sway", "head_turn", "walk", "stop"}));
    const auto amplitude = [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(0.0, 180.0)); };
    const auto frequency = [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 100.0)); };
    if (type <= 1) {
        const bool sway = type == 0;
        if (sway) {
            KW_TRY(r.object(node, {"type", "joint", "axis", "amplitude_deg", "frequency", "phase_deg", "sharpness", "start",
                                   "end", "fade"}));
        } else {
            KW_TRY(r.object(node, {"type", "joint", "amplitude_deg", "frequency", "phase_deg", "sharpness", "start", "end",
                                   "fade"}));
        }
        rods::Oscillation o;
        // Sway: the root rocks sideways about its forward axis; head turn: the reference
        // joint yaws about its up axis.
        o.joint = sway ? 0 : skeleton.reference;
        o.axis = sway ? Vec3(0.0f, 0.0f, 1.0f) : Vec3(0.0f, 1.0f, 0.0f);
        o.amplitude = static_cast<float>((sway ? 5.0 : 40.0) * kDegToRad);
        o.frequency = sway ? 0.5f : 0.2f;
        KW_TRY(optional_member(r, node, "joint", o.joint, [&](const JsonNode& n) { return find_joint(r, n, skeleton); }));
        KW_TRY(optional_member(r, node, "axis", o.axis, [&](const JsonNode& n) { return read_direction(r, n); }));
        KW_TRY(optional_member(r, node, "amplitude_deg", o.amplitude, amplitude));
        KW_TRY(optional_member(r, node, "frequency", o.frequency, frequency));
        KW_TRY(optional_member(r, node, "phase_deg", o.phase,
                               [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-3600.0, 3600.0)); }));
        KW_TRY(optional_member(r, node, "sharpness", o.sharpness,
                               [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 20.0)); }));
        KW_TRY(read_interval(r, node, "end", false, o.start, o.end));
        KW_TRY(optional_member(r, node, "fade", o.fade, [&](const JsonNode& n) { return read_time(r, n); }));
        motion.oscillations.push_back(o);
        return {};
    }
    const bool walk = type == 2;
    if (walk) {
        KW_TRY(r.object(node, {"type", "speed", "turn_rate_deg", "start", "end", "ramp_in", "ramp_out", "bob", "step_frequency",
                               "roll_deg"}));
    } else {
        KW_TRY(r.object(node, {"type", "speed", "turn_rate_deg", "start", "stop_time", "ramp_in", "bob", "step_frequency",
                               "roll_deg"}));
    }
    rods::Locomotion m;
    m.speed = walk ? 1.0f : 2.5f;
    m.ramp_in = 0.3f;
    m.ramp_out = walk ? 0.3f : 0.0f;  // a stop halts dead: that is its point
    m.bob = walk ? 0.03f : 0.0f;
    m.roll = walk ? static_cast<float>(2.0 * kDegToRad) : 0.0f;
    KW_TRY(optional_member(r, node, "speed", m.speed, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 100.0)); }));
    KW_TRY(optional_member(r, node, "turn_rate_deg", m.turn_rate,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-3600.0, 3600.0)); }));
    KW_TRY(read_interval(r, node, walk ? "end" : "stop_time", !walk, m.start, m.end));
    const auto ramp = [&](const JsonNode& n) { return read_time(r, n); };
    KW_TRY(optional_member(r, node, "ramp_in", m.ramp_in, ramp));
    if (walk) KW_TRY(optional_member(r, node, "ramp_out", m.ramp_out, ramp));
    const double length = static_cast<double>(m.end) - static_cast<double>(m.start);
    if (std::isfinite(m.end) && static_cast<double>(m.ramp_in) + static_cast<double>(m.ramp_out) > length) {
        const JsonNode blame = r.member(node, r.member(node, "ramp_in").present() || !walk ? "ramp_in" : "ramp_out");
        return r.expected(blame, std::string(walk ? "ramps with ramp_in + ramp_out <= end - start" : "a ramp_in <= stop_time - start") +
                                     " (" + format_number(length) + " s)");
    }
    KW_TRY(optional_member(r, node, "bob", m.bob, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 10.0)); }));
    KW_TRY(optional_member(r, node, "step_frequency", m.step_frequency,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100.0)); }));
    KW_TRY(optional_member(r, node, "roll_deg", m.roll,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(0.0, 90.0)); }));
    motion.locomotions.push_back(m);
    return {};
}

namespace {

// A sphere, capsule or plane on the joint whose index `joint` returns for the `joint`
// member (rods::ColliderKind says what each keeps).
Result<ColliderSpec> read_collider(const JsonReader& r, const JsonNode& node,
                                  const std::function<Result<std::uint32_t>(const JsonNode&)>& joint) {
    if (!node.present() || !node.value->is_object()) {
        return r.expected(node, "an object with \"type\": \"sphere\", \"capsule\" or \"plane\"");
    }
    std::size_t type = 0;
    KW_SCENE_ASSIGN(type, r.choice(r.member(node, "type"), {"sphere", "capsule", "plane"}));
    ColliderSpec c;
    KW_SCENE_ASSIGN(c.joint, joint(r.member(node, "joint")));
    if (type == 2) {
        KW_TRY(r.object(node, {"name", "type", "joint", "point", "normal"}));
        KW_TRY(optional_member(r, node, "point", c.a, [&](const JsonNode& n) { return read_point(r, n, kMaxLocal); }));
        glm::vec3 normal{0.0f};
        KW_SCENE_ASSIGN(normal, read_direction(r, r.member(node, "normal")));
        c.b = normal;
        c.kind = rods::ColliderKind::Plane;
    } else {
        if (type == 0) {
            KW_TRY(r.object(node, {"name", "type", "joint", "center", "radius", "inside"}));
            KW_TRY(optional_member(r, node, "center", c.a, [&](const JsonNode& n) { return read_point(r, n, kMaxLocal); }));
            c.b = c.a;
        } else {
            KW_TRY(r.object(node, {"name", "type", "joint", "a", "b", "radius", "inside"}));
            KW_SCENE_ASSIGN(c.a, read_point(r, r.member(node, "a"), kMaxLocal));
            KW_SCENE_ASSIGN(c.b, read_point(r, r.member(node, "b"), kMaxLocal));
        }
        KW_SCENE_ASSIGN(c.radius, r.real(r.member(node, "radius"), NumberRange::left_open(0.0, kMaxLocal)));
        bool inside = false;
        KW_TRY(optional_member(r, node, "inside", inside, [&](const JsonNode& n) { return r.boolean(n); }));
        if (inside) c.kind = rods::ColliderKind::Inside;
    }
    KW_TRY(optional_member(r, node, "name", c.name, [&](const JsonNode& n) { return read_name(r, n); }));
    return c;
}

}  // namespace

Result<std::vector<ColliderSpec>> read_colliders(const JsonReader& r, const JsonNode& node,
                                                 const std::function<Result<std::uint32_t>(const JsonNode&)>& joint) {
    std::vector<ColliderSpec> out;
    const JsonNode colliders = r.member(node, "colliders");
    if (!colliders.present()) return out;
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, colliders, 0, kMaxCharacterColliders,
                                  "an array of colliders (at most " + std::to_string(kMaxCharacterColliders) + ")"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode element = r.element(colliders, i);
        ColliderSpec c;
        KW_SCENE_ASSIGN(c, read_collider(r, element, joint));
        for (const ColliderSpec& other : out) {
            if (!c.name.empty() && other.name == c.name) {
                return r.expected(r.member(element, "name"), "a collider name this character does not use yet (\"" + c.name + "\" is taken)");
            }
        }
        out.push_back(c);
    }
    return out;
}

namespace {

// Issue 39: no chain's root inside one of its colliders, in the rest pose. The root is
// kinematic and the collision pass pushes every other particle out, so the first
// segments would fight the collider every substep. A root on the collider's surface (a
// hair on the scalp: its particle overlaps the collider by the chain's thickness, as
// every shipped scene's roots and VRM's do) is allowed; a root whose centre is inside
// the shape (farther than `thickness` into the collider's reach, with 10 um for rounding)
// is refused.
// Procedural characters only (a rigged character's chains and colliders come from its
// glTF file and are not checked here).
Result<void> check_roots_outside_colliders(const JsonReader& r, const CharacterSpec& ch) {
    if (ch.colliders.empty()) return {};
    std::vector<rods::Transform> world(ch.skeleton.joints.size());
    for (std::size_t j = 0; j < world.size(); ++j) {  // parents first (read_skeleton)
        const rods::SkeletonJoint& joint = ch.skeleton.joints[j];
        world[j] = joint.parent < 0 ? joint.rest : rods::compose(world[static_cast<std::size_t>(joint.parent)], joint.rest);
    }
    for (const ChainSpec& chain : ch.chains) {
        if (!chain.collide) continue;
        const glm::vec3 root = rods::compose(world[chain.joint], chain.offset).position;
        for (std::size_t k = 0; k < ch.colliders.size(); ++k) {
            if (!chain.all_colliders &&
                std::find(chain.colliders.begin(), chain.colliders.end(), static_cast<std::uint32_t>(k)) == chain.colliders.end()) {
                continue;
            }
            const ColliderSpec& c = ch.colliders[k];
            const rods::Transform& at = world[c.joint];
            const glm::vec3 b = c.kind == rods::ColliderKind::Plane ? at.rotation * c.b : at.position + at.rotation * c.b;
            const rods::Collider placed{at.position + at.rotation * c.a, b, c.radius, c.kind};
            // How far the root's centre is inside the shape itself (collider_gap measures
            // the particle's surface; a clamped inside reach only makes it stricter).
            const float depth = -(rods::collider_gap(placed, root, chain.thickness) + chain.thickness);
            if (depth > 1e-5f) {
                const std::string name = c.name.empty() ? "collider " + std::to_string(k) : "collider \"" + c.name + "\"";
                return r.fail(chain.path, "the chain's root is " + std::to_string(depth) + " m inside " + name +
                                              " in the rest pose; move the root onto or outside its surface");
            }
        }
    }
    return {};
}

}  // namespace

Result<CharacterSpec> read_character(const JsonReader& r, const JsonNode& node) {
    if (node.present() && node.value->is_object() && r.member(node, "gltf").present()) return read_rigged_character(r, node);
    KW_TRY(r.object(node, {"name", "skeleton", "reference_joint", "motions", "colliders", "physics", "chains", "wind"}));
    CharacterSpec ch;
    ch.path = node.path;
    KW_SCENE_ASSIGN(ch.name, read_name(r, r.member(node, "name")));
    KW_SCENE_ASSIGN(ch.skeleton, read_skeleton(r, r.member(node, "skeleton")));
    const JsonNode reference = r.member(node, "reference_joint");
    if (reference.present()) {
        KW_SCENE_ASSIGN(ch.skeleton.reference, find_joint(r, reference, ch.skeleton));
    } else {
        bool found = false;
        for (std::size_t j = 0; j < ch.skeleton.joints.size() && !found; ++j) {
            if (ch.skeleton.joints[j].name == "head") {
                ch.skeleton.reference = static_cast<std::uint32_t>(j);
                found = true;
            }
        }
        if (!found) {
            return r.fail(reference.path, "no joint is called \"head\" (the default reference joint); name the joint that "
                                          "view directions are measured in");
        }
    }
    const std::string per = " (at most " + std::to_string(kMaxPerCharacter) + ")";
    const JsonNode motions = r.member(node, "motions");
    if (motions.present()) {
        std::size_t n = 0;
        KW_SCENE_ASSIGN(n, read_array(r, motions, 0, kMaxPerCharacter, "an array of motions" + per));
        for (std::size_t i = 0; i < n; ++i) KW_TRY(read_motion(r, r.element(motions, i), ch.skeleton, ch.motion));
    }
    KW_SCENE_ASSIGN(ch.colliders, read_colliders(r, node, [&](const JsonNode& j) { return find_joint(r, j, ch.skeleton); }));
    rods::SolverParams defaults;
    const JsonNode physics = r.member(node, "physics");
    if (physics.present()) KW_TRY(read_physics(r, physics, defaults));
    const JsonNode chains = r.member(node, "chains");
    std::size_t n = 0;
    const std::string chains_what = "a non-empty array of chains" + per;
    KW_SCENE_ASSIGN(n, read_array(r, chains, 1, kMaxPerCharacter, chains_what));
    for (std::size_t i = 0; i < n; ++i) KW_TRY(read_chain(r, r.element(chains, i), ch.skeleton, ch.colliders, defaults, ch.chains));
    if (ch.chains.size() > kMaxPerCharacter) {
        return r.expected(chains, chains_what + ", counting mirrored copies; got " + std::to_string(ch.chains.size()));
    }
    KW_TRY(check_roots_outside_colliders(r, ch));
    return ch;
}

// A clip of a rigged character by name; procedural characters have none.
Result<std::int32_t> read_clip(const JsonReader& r, const JsonNode& node, const CharacterSpec& character) {
    KW_TRY(r.string(node));
    if (!character.rig) {
        return r.fail(node.path, "only rigged characters (with \"gltf\") play animation clips; \"" + character.name +
                                     "\" moves by its \"motions\"");
    }
    return find_clip(r, node, *character.rig->character);
}

Result<InstanceSpec> read_instance(const JsonReader& r, const JsonNode& node, const CharacterSpec& character) {
    KW_TRY(r.object(node, {"position", "yaw_deg", "time_offset", "animation"}));
    InstanceSpec s;
    KW_SCENE_ASSIGN(s.position, read_point(r, r.member(node, "position"), kMaxCoordinate));
    KW_TRY(optional_member(r, node, "yaw_deg", s.yaw,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-3600.0, 3600.0)); }));
    KW_TRY(optional_member(r, node, "time_offset", s.time_offset,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 3600.0)); }));
    const JsonNode animation = r.member(node, "animation");
    if (animation.present()) KW_SCENE_ASSIGN(s.clip, read_clip(r, animation, character));
    return s;
}

Result<CrowdSpec> read_crowd(const JsonReader& r, const JsonNode& node, std::size_t index, const Scene& scene,
                             std::uint64_t& characters, std::uint64_t& chains) {
    KW_TRY(r.object(node, {"name", "character", "count", "layout", "spacing", "columns", "radius", "center", "yaw_deg",
                           "yaw_jitter_deg", "position_jitter", "time_offset", "seed", "animations", "instances"}));
    CrowdSpec c;
    c.name = "crowd" + std::to_string(index);
    KW_TRY(optional_member(r, node, "name", c.name, [&](const JsonNode& n) { return read_name(r, n); }));
    std::vector<std::string> names;
    for (const CharacterSpec& k : scene.characters) names.push_back(k.name);
    KW_SCENE_ASSIGN(c.character, find_name(r, r.member(node, "character"), names, "the name of a character of this scene"));

    const JsonNode count = r.member(node, "count");
    if (count.present()) {
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(count, 0, kMaxCharacterInstances));
        c.count = static_cast<std::uint32_t>(value);
    }
    const JsonNode layout = r.member(node, "layout");
    if (layout.present()) {
        std::size_t value = 0;
        KW_SCENE_ASSIGN(value, r.choice(layout, {"grid", "ring"}));
        c.layout = value == 0 ? CrowdLayout::Grid : CrowdLayout::Ring;
    }
    KW_TRY(optional_member(r, node, "spacing", c.spacing,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 10000.0)); }));
    const JsonNode columns = r.member(node, "columns");
    if (columns.present()) {
        if (c.layout != CrowdLayout::Grid) return r.fail(columns.path, "only used by \"layout\": \"grid\"");
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(columns, 1, kMaxCharacterInstances));
        c.columns = static_cast<std::uint32_t>(value);
    }
    const JsonNode radius = r.member(node, "radius");
    if (radius.present()) {
        if (c.layout != CrowdLayout::Ring) return r.fail(radius.path, "only used by \"layout\": \"ring\"");
        KW_SCENE_ASSIGN(c.radius, r.real(radius, NumberRange::left_open(0.0, kMaxCoordinate / 2)));
    }
    KW_TRY(optional_member(r, node, "center", c.center, [&](const JsonNode& n) { return read_point(r, n, kMaxCoordinate / 2); }));
    KW_TRY(optional_member(r, node, "yaw_deg", c.yaw,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-3600.0, 3600.0)); }));
    KW_TRY(optional_member(r, node, "yaw_jitter_deg", c.yaw_jitter,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(0.0, 180.0)); }));
    KW_TRY(optional_member(r, node, "position_jitter", c.position_jitter,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 10000.0)); }));
    KW_TRY(optional_member(r, node, "time_offset", c.time_offset,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 3600.0)); }));
    KW_TRY(optional_member(r, node, "seed", c.seed, [&](const JsonNode& n) {
        return r.integer(n, 0, std::numeric_limits<std::uint64_t>::max());
    }));
    const CharacterSpec& spec = scene.characters[c.character];
    const JsonNode animations = r.member(node, "animations");
    if (animations.present()) {
        std::size_t n = 0;
        KW_SCENE_ASSIGN(n, read_array(r, animations, 1, 1024, "a non-empty array of animation names"));
        for (std::size_t i = 0; i < n; ++i) {
            std::int32_t clip = 0;
            KW_SCENE_ASSIGN(clip, read_clip(r, r.element(animations, i), spec));
            c.clips.push_back(clip);
        }
    }
    const JsonNode instances = r.member(node, "instances");
    if (instances.present()) {
        std::size_t n = 0;
        KW_SCENE_ASSIGN(n, read_array(r, instances, 0, kMaxCharacterInstances, "an array of instances"));
        for (std::size_t i = 0; i < n; ++i) {
            InstanceSpec s;
            KW_SCENE_ASSIGN(s, read_instance(r, r.element(instances, i), spec));
            c.instances.push_back(s);
        }
    }
    const std::uint64_t total = c.count + c.instances.size();
    if (total == 0) return r.fail(node.path, "expected \"count\" >= 1 or a non-empty \"instances\", got no instances");
    const std::uint64_t per_chains = scene.characters[c.character].chains.size();
    if (characters + total > kMaxCharacterInstances || chains + total * per_chains > kMaxChainInstances) {
        return r.fail(node.path, "too many instances: a scene holds at most " + std::to_string(kMaxCharacterInstances) +
                                     " characters and " + std::to_string(kMaxChainInstances) + " chains in all");
    }
    characters += total;
    chains += total * per_chains;
    return c;
}

Result<void> read_characters(const JsonReader& r, const JsonNode& characters, const JsonNode& crowds, Scene& scene) {
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, characters, 1, 1024, "a non-empty array of characters (at most 1024)"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode node = r.element(characters, i);
        CharacterSpec c;
        KW_SCENE_ASSIGN(c, read_character(r, node));
        // Its own wind field: the scene's where it is silent.
        if (const JsonNode wind = r.member(node, "wind"); wind.present()) {
            rods::WindField field = scene.wind.value_or(rods::WindField{});
            KW_TRY(read_wind(r, wind, field));
            c.wind = field;
        }
        for (const CharacterSpec& other : scene.characters) {
            if (other.name == c.name) {
                return r.expected(r.member(node, "name"), "a character name no other character has (\"" + c.name + "\" is taken)");
            }
        }
        scene.characters.push_back(std::move(c));
    }
    std::uint64_t total_characters = 0;
    std::uint64_t total_chains = 0;
    if (!crowds.present()) {
        for (std::size_t i = 0; i < scene.characters.size(); ++i) {
            CrowdSpec c;
            c.name = scene.characters[i].name;
            c.character = static_cast<std::uint32_t>(i);
            c.instances.push_back(InstanceSpec{});
            scene.crowds.push_back(std::move(c));
        }
        return {};
    }
    std::size_t m = 0;
    KW_SCENE_ASSIGN(m, read_array(r, crowds, 1, 1024, "a non-empty array of crowds (at most 1024)"));
    for (std::size_t i = 0; i < m; ++i) {
        CrowdSpec c;
        KW_SCENE_ASSIGN(c, read_crowd(r, r.element(crowds, i), i, scene, total_characters, total_chains));
        scene.crowds.push_back(std::move(c));
    }
    return {};
}

}  // namespace kodawari::scene_detail
